"""Threads and memory: one model used from many threads gives the same numbers; a request
beyond the memory is our ``OutOfMemoryError`` (or ``MemoryError``) up front, naming the size,
and the process lives (checked under an address-space cap); a scheduler that cannot be reached
is our error within its timeout."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import threading

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import G, rod_body
from conftest import revolute_chain as chain
from ctrl_c import CtrlC
from pointmass_dyn.errors import (
    ClusterError,
    InvalidInputError,
)


def chain_scene(n: int, effects=None) -> pmd.Scene:
    m = chain(n)
    q0 = np.linspace(0.1, 0.5, n)
    return pmd.Scene(m, q0, np.zeros(n), effects=[pmd.Gravity(G)] + list(effects or []))


def _run_limited(code: str, limit_bytes: int) -> subprocess.CompletedProcess:
    """Runs `code` in a fresh interpreter whose address space is capped after the imports."""
    prog = textwrap.dedent(
        f"""
        import resource, sys
        import numpy as np
        import pointmass_dyn as pmd
        sys.path.insert(0, {os.path.dirname(__file__)!r})
        from conftest import revolute_chain as chain
        """
    ) + textwrap.dedent(code).replace("__CAP__", str(limit_bytes))
    return subprocess.run(
        [sys.executable, "-c", prog], capture_output=True, text=True, timeout=300
    )


needs_rlimit = pytest.mark.skipif(
    not sys.platform.startswith("linux"), reason="RLIMIT_AS as Linux applies it"
)


@pytest.fixture(scope="module")
def fourbar_motion():
    scene = pmd.load_scene("fourbar")
    motion = pmd.prescribed_motion(
        scene.model, "crank", speed=2 * np.pi, samples=36, q_guess=scene.q0, gravity=G
    )
    return scene, motion


def _run_capped(code: str, limit_bytes: int) -> subprocess.CompletedProcess:
    """``code`` in a fresh interpreter whose address space is capped at ``limit_bytes``."""
    prelude = textwrap.dedent(
        f"""
        import resource
        resource.setrlimit(resource.RLIMIT_AS, ({limit_bytes}, {limit_bytes}))
        """
    )
    return subprocess.run(
        [sys.executable, "-c", prelude + textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_one_model_many_threads_same_numbers():
    model = chain(300)  # above the size from which the calls release the GIL
    rng = np.random.default_rng(5)
    states = [(rng.normal(size=300), rng.normal(size=300)) for _ in range(8)]
    ref_m = [model.mass_matrix(q) for q, _ in states]
    ref_a = [model.forward_dynamics(q, v, np.zeros(300), gravity=G) for q, v in states]
    errors: list[BaseException] = []
    mismatches = []

    def work(offset: int):
        try:
            for i in range(100):
                k = (i + offset) % len(states)
                q, v = states[k]
                if not np.array_equal(model.mass_matrix(q), ref_m[k]):
                    mismatches.append(("M", k))
                a = model.forward_dynamics(q, v, np.zeros(300), gravity=G)
                if not np.array_equal(a, ref_a[k]):
                    mismatches.append(("a", k))
        except BaseException as exc:
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(j,)) for j in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors[:3]
    assert not mismatches, mismatches[:5]


def test_adding_bodies_while_other_threads_compute():
    model = chain(100)
    stop = threading.Event()
    errors: list[BaseException] = []

    def compute():
        try:
            while not stop.is_set():
                n = model.nv  # the model may grow between these two reads
                q = np.zeros(n)
                try:
                    model.mass_matrix(q)
                except pmd.InvalidInputError:
                    pass  # q was sized for an older version: a clear error, not a crash
        except BaseException as exc:
            errors.append(exc)

    t = threading.Thread(target=compute)
    t.start()
    try:
        for _ in range(50):
            model.add_body(rod_body(1.0, 0.3, 0.02), pmd.Revolute([0, 1, 0]), parent=model.nbodies - 1)
    finally:
        stop.set()
        t.join()
    assert not errors, errors[:3]
    assert model.nv == 150
    # The grown model is the one built in one go.
    q = np.linspace(-1, 1, 150)
    ref = chain(100)
    for _ in range(50):
        ref.add_body(rod_body(1.0, 0.3, 0.02), pmd.Revolute([0, 1, 0]), parent=ref.nbodies - 1)
    np.testing.assert_array_equal(model.mass_matrix(q), ref.mass_matrix(q))


def test_scene_model_is_shared_and_copy_on_write():
    scene = chain_scene(4)
    before = pmd.simulate(scene, (0.0, 0.5))
    m = scene.model
    assert m.nv == 4
    m.add_body(rod_body(), pmd.Revolute([0, 1, 0]), parent=3)
    assert m.nv == 5 and scene.model.nv == 4
    after = pmd.simulate(scene, (0.0, 0.5))
    np.testing.assert_array_equal(before.q, after.q)
    # A model edited after a scene was made from it leaves the scene alone too.
    base = chain(3)
    s2 = pmd.Scene(base, effects=[pmd.Gravity(G)])
    base.add_body(rod_body(), pmd.Revolute([0, 1, 0]), parent=2)
    assert s2.model.nv == 3 and base.nv == 4


@needs_rlimit
def test_dense_denoc_too_large_is_out_of_memory_error_naming_the_size():
    r = _run_limited(
        """
        m = chain(2000)     # D alone is 42000 x 12000 doubles: 4 GB
        resource.setrlimit(resource.RLIMIT_AS, (__CAP__, __CAP__))
        try:
            m.mass_matrix(np.zeros(2000), method="denoc")
        except pmd.errors.OutOfMemoryError as e:
            assert isinstance(e, MemoryError), type(e).__mro__
            print("REFUSED:", e)
        """,
        3 * 2**30,
    )
    assert r.returncode == 0, (r.returncode, r.stderr[-2000:])
    assert "REFUSED:" in r.stdout and "mass_matrix" in r.stdout and "GB" in r.stdout, r.stdout


@needs_rlimit
def test_recursive_mass_matrix_under_memory_pressure_raises_memory_error():
    r = _run_limited(
        """
        import resource
        m = chain(3000)
        m.mass_matrix(np.zeros(3000))           # workspace in place: only the result is new
        usage = int(open("/proc/self/statm").read().split()[0]) * resource.getpagesize()
        limit = usage + 16 * 2**20               # the 72 MB result cannot fit
        resource.setrlimit(resource.RLIMIT_AS, (limit, resource.RLIM_INFINITY))
        try:
            m.mass_matrix(np.zeros(3000))
        except MemoryError as e:
            print("REFUSED:", type(e).__name__, e)
        """,
        0,
    )
    assert r.returncode == 0, (r.returncode, r.stderr[-2000:])
    assert "REFUSED: OutOfMemoryError" in r.stdout and "3000 × 3000" in r.stdout, r.stdout


def test_long_dense_denoc_call_hears_ctrl_c():
    # Pressed while the call runs: its own poll of the signal handlers must hear it, and the
    # call end with the KeyboardInterrupt, not run to its end.
    model = chain(500)
    q = np.linspace(-1, 1, 500)
    ctrl_c = CtrlC(inside="convective_matrix")
    assert ctrl_c.attempt(lambda: model.convective_matrix(q, np.ones(500))) is not None
    assert ctrl_c.heard == 1 and ctrl_c.ended == "c_exception"


@needs_rlimit
def test_t_eval_too_large_for_memory_is_refused_before_the_run():
    # 10^6 output times of a 4000-component state: 32 GB of output, refused at once with our
    # error, not an abort once the run has filled the memory.
    r = _run_limited(
        """
        m = chain(2000)
        s = pmd.Scene(m, effects=[pmd.Gravity()])
        resource.setrlimit(resource.RLIMIT_AS, (__CAP__, __CAP__))
        try:
            pmd.simulate(s, (0.0, 1e-3), t_eval=np.linspace(0.0, 1e-3, 10**6))
        except pmd.errors.OutOfMemoryError as e:
            print("REFUSED:", e)
        """,
        4 * 2**30,
    )
    assert r.returncode == 0, (r.returncode, r.stderr[-2000:])
    assert "REFUSED:" in r.stdout and "t_eval" in r.stdout, r.stdout


def test_point_regressor_beyond_memory_is_out_of_memory_error():
    code = """
        import numpy as np, pointmass_dyn as pmd
        scene = pmd.load_scene("fourbar")
        mo = pmd.prescribed_motion(scene.model, "crank", speed=6.0, samples=36, q_guess=scene.q0)
        try:
            scene.model.point_regressor(mo.q, mo.v, mo.a, points=[("crank", [0.1, 0, 0])] * 10**6)
        except pmd.errors.OutOfMemoryError as e:
            print("OOM", "point_regressor" in str(e))
        """
    out = _run_capped(code, 2 << 30)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.split() == ["OOM", "True"]


def test_point_regressor_still_agrees_with_point_motion(fourbar_motion):
    """The regressor moved into the core: its positions and accelerations are the point
    masses' own (point_motion, an independent path through the same kinematics)."""
    scene, mo = fourbar_motion
    model = scene.model
    k = 5
    pm = model.point_motion(mo.q[k], mo.v[k], mo.a[k])
    reg = model.point_regressor(mo.q[k], mo.v[k], mo.a[k])
    np.testing.assert_allclose(reg["positions"], pm["positions"].reshape(-1, 3), atol=1e-12)
    np.testing.assert_allclose(
        reg["accelerations"], pm["accelerations"].reshape(-1, 3), atol=1e-9
    )
    # generalized = J_pᵀ (a_p − g): a unit mass at every point needs these joint forces; over
    # all point masses weighted by their masses it is the inverse dynamics of the tree.
    w = pm["masses"].reshape(-1)
    tau_tree = np.einsum("p,pk->k", w, reg["generalized"])
    assert np.all(np.isfinite(tau_tree))


def test_simulate_batch_beyond_memory_is_refused_up_front(monkeypatch):
    from pointmass_dyn import _batch
    from pointmass_dyn.errors import OutOfMemoryError

    scene = pmd.load_scene("pendulum_planar")
    # A machine of 1 GiB: 10^6 runs need 4.4 GB (the bound measured per run).
    monkeypatch.setattr(_batch, "_physical_memory", lambda: 2**30)
    with pytest.raises(OutOfMemoryError, match=r"1000000 runs need at least 4\.1 GiB"):
        pmd.simulate_batch(scene, (0, 0.1), params={"rod.mass": np.ones(10**6)})
    with pytest.raises(OutOfMemoryError, match=r"1000 runs .* 10000 output times of 6"):
        pmd.simulate_batch(scene, (0, 0.1), q0=np.tile(scene.q0, (1000, 1)),
                           t_eval=np.linspace(0, 0.1, 10**4))
    monkeypatch.undo()
    ok = pmd.simulate_batch(scene, (0, 0.1), q0=np.tile(scene.q0, (3, 1)))
    assert ok.success.all()


def test_sweep_unreachable_scheduler_is_our_error_within_the_timeout(monkeypatch):
    distributed = pytest.importorskip("distributed")
    import socket

    # What bounds the wait, not a clock: the one connection attempt is given the timeout,
    # and a malformed address is refused before any (no socket, no Client).
    attempts = []
    connect = socket.create_connection

    def create_connection(address, timeout=None, *args, **kwargs):
        attempts.append((address, timeout))
        return connect(address, timeout, *args, **kwargs)

    def no_client(*args, **kwargs):
        raise AssertionError("a Client was built for an address refused up front")

    monkeypatch.setattr(socket, "create_connection", create_connection)
    monkeypatch.setattr(distributed, "Client", no_client)
    scene = pmd.load_scene("pendulum_planar")
    with pytest.raises(ClusterError, match=r"127\.0\.0\.1:1.*connect_timeout=1\.0"):
        pmd.sweep(scene, (0, 0.1), t_eval=[0, 0.1], scheduler="tcp://127.0.0.1:1",
                  connect_timeout=1.0)
    assert attempts == [(("127.0.0.1", 1), 1.0)]
    for bad in ("notanaddress", "foo://x:1", "tcp://host:abc"):
        with pytest.raises(InvalidInputError, match="scheduler"):
            pmd.sweep(scene, (0, 0.1), t_eval=[0, 0.1], scheduler=bad, connect_timeout=1.0)
    assert len(attempts) == 1
    with pytest.raises(InvalidInputError, match="connect_timeout"):
        pmd.sweep(scene, (0, 0.1), t_eval=[0, 0.1], scheduler="tcp://127.0.0.1:1",
                  connect_timeout=0)
