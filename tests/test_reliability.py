"""Reliability (issue 11): no lost work, no stalls, no aborts.

Each test reproduces one defect a probe of the installed package found; each asserts
against the behaviour the standard asks for (our own exception, the partial result, the
same numbers as a single-threaded reference), not against recorded output.
"""

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


def chain_scene(n: int, effects=None) -> pmd.Scene:
    m = chain(n)
    q0 = np.linspace(0.1, 0.5, n)
    return pmd.Scene(m, q0, np.zeros(n), effects=[pmd.Gravity(G)] + list(effects or []))


class _Boom(Exception):
    pass


# --------------------------------------------------------------------------------------------
# 2. A failed or interrupted run keeps what it computed.
# --------------------------------------------------------------------------------------------
def test_torque_function_exception_carries_the_partial_result():
    def torque(t, q, v):
        if t > 0.4:
            raise _Boom(f"at t = {t}")
        return np.zeros(3)

    scene = chain_scene(3, [pmd.TorqueFunction(torque)])
    with pytest.raises(_Boom) as info:
        pmd.simulate(scene, (0.0, 2.0))
    r = info.value.result
    assert isinstance(r, pmd.SimulationResult) and not r.success
    assert 0.0 < r.t_reached <= 0.4 and r.t[-1] == r.t_reached
    assert r.q.shape == (len(r.t), 3) and np.all(np.isfinite(r.q))
    # The partial trajectory is the run's own: it equals a run stopped there by t_span.
    ref = pmd.simulate(chain_scene(3), (0.0, 2.0))
    k = len(r.t)
    np.testing.assert_array_equal(r.t, ref.t[:k])
    np.testing.assert_array_equal(r.q, ref.q[:k])


def test_event_exception_carries_the_partial_result():
    def event(t, q, v):
        if t > 0.3:
            raise _Boom("event")
        return 1.0

    with pytest.raises(_Boom) as info:
        pmd.simulate(chain_scene(2), (0.0, 1.0), events=[event])
    r = info.value.result
    assert not r.success and 0.0 < r.t_reached <= 0.3 + 1e-12 and len(r.t) > 1


def test_ctrl_c_during_simulate_raises_keyboard_interrupt_with_the_partial_result():
    # Pressed once progress has seen the run under way, heard by the run's own poll.
    scene = chain_scene(30)
    ctrl_c = CtrlC(inside="simulate_scene", armed=False)

    def progress(t):
        if t > 0:
            ctrl_c.arm()

    r = ctrl_c.run(lambda: pmd.simulate(scene, (0.0, 1e4), rtol=1e-12, atol=1e-12,
                                        progress=progress)).result
    assert not r.success and 0.0 < r.t_reached < 1e4 and r.t[-1] == r.t_reached
    assert np.all(np.isfinite(r.q)) and "interrupt" in r.message


def test_rk45_exception_from_fun_carries_the_partial_result():
    def fun(t, y):
        if t > 0.5:
            raise _Boom("fun")
        return -y

    with pytest.raises(_Boom) as info:
        pmd.rk45(fun, (0.0, 2.0), [1.0, 2.0])
    r = info.value.result
    assert r.status == -1 and 0.0 < r.t_reached <= 0.5
    np.testing.assert_allclose(r.y[:, -1], np.array([1.0, 2.0]) * np.exp(-r.t_reached), rtol=1e-3)


# --------------------------------------------------------------------------------------------
# 6. A dense output without a step is an error of ours, not a PanicException.
# --------------------------------------------------------------------------------------------
def test_dense_output_of_a_run_that_failed_at_once():
    r = pmd.rk45(lambda t, y: y * np.nan, (0, 1), [1.0], dense_output=True)
    assert r.status == -1 and r.t_reached == 0.0
    with pytest.raises(pmd.SimulationError, match="before its first step"):
        r.sol(0.0)


# --------------------------------------------------------------------------------------------
# 5. One Model serves many threads.
# --------------------------------------------------------------------------------------------
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


# --------------------------------------------------------------------------------------------
# 4. Shared, copy-on-write models: scene.model is not a copy, and editing it changes no scene.
# --------------------------------------------------------------------------------------------
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


# --------------------------------------------------------------------------------------------
# 3. Memory: a refused allocation is an error, not an abort; long dense calls hear Ctrl-C.
# --------------------------------------------------------------------------------------------
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
