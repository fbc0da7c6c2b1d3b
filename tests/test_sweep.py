"""pmd.sweep on a real dask.distributed LocalCluster (two worker processes): the gathered
result is simulate_batch's on the whole batch, bit for bit, and a worker killed mid-sweep
loses nothing (its chunk is run again on a live worker)."""

from __future__ import annotations

import os
import signal
import sys
import threading
import time

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn.errors import InvalidInputError


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0"
    )
    try:
        yield cluster
    finally:
        cluster.close()


@pytest.fixture(scope="module")
def client(cluster):
    import distributed

    client = distributed.Client(cluster)
    try:
        yield client
    finally:
        client.close()


def _batch(b: int, t_end: float, seed: int):
    scene = pmd.load_scene("chain7")
    rng = np.random.default_rng(seed)
    q0 = scene.q0 + 0.05 * rng.standard_normal((b, scene.model.nq))
    params = {
        "gravity": np.array([0.0, 0.0, -9.81]) + 0.1 * rng.standard_normal((b, 3)),
        "link3.mass": 1.0 + 0.2 * rng.random(b),
    }
    return scene, (0.0, t_end), dict(q0=q0, params=params, t_eval=np.linspace(0, t_end, 11))


@pytest.fixture(scope="module")
def short():
    """400 short chain7 runs at a loose tolerance, and their serial simulate_batch."""
    scene, span, kw = _batch(400, 0.5, 1)
    kw.update(rtol=1e-6, atol=1e-6)
    return scene, span, kw, pmd.simulate_batch(scene, span, threads=1, **kw)


def _assert_same(got: pmd.BatchResult, ref: pmd.BatchResult):
    assert len(got) == len(ref)
    assert np.array_equal(got.t, ref.t)
    assert np.array_equal(got.q, ref.q)
    assert np.array_equal(got.v, ref.v)
    assert np.array_equal(got.nfev, ref.nfev)
    assert np.array_equal(got.success, ref.success) and ref.success.all()
    assert np.array_equal(got.status, ref.status)
    assert np.array_equal(got.t_reached, ref.t_reached)
    assert got.message == ref.message
    for a, b in zip(got.results, ref.results):
        assert np.array_equal(a.q, b.q) and a.n_accepted == b.n_accepted and a.scene == b.scene


def test_sweep_is_simulate_batch_bit_for_bit(client, short):
    scene, span, kw, ref = short
    seen = []
    got = pmd.sweep(scene, span, client=client, progress=lambda d, b: seen.append((d, b)), **kw)
    _assert_same(got, ref)
    # The default chunk size: four chunks per worker thread.
    assert len(seen) == 8 and seen[-1] == (400, 400)


def test_sweep_by_scheduler_address_uneven_chunks(cluster, short):
    scene, span, kw, ref = short
    got = pmd.sweep(scene, span, scheduler=cluster.scheduler_address, chunk_size=37, **kw)
    _assert_same(got, ref)


def test_sweep_broadcasts_one_row_and_lists_of_scenes(client, short):
    scene, span, kw, _ = short
    kw = dict(kw, q0=kw["q0"][0], params={"gravity": kw["params"]["gravity"][:1]},
              v0=np.zeros((400, 7)))
    ref = pmd.simulate_batch(scene, span, threads=1, **kw)
    _assert_same(pmd.sweep(scene, span, client=client, chunk_size=150, **kw), ref)
    scenes = [scene.replace(effects=[pmd.Effect.gravity([0, 0, -9 - k])]) for k in range(5)]
    kw = dict(t_eval=kw["t_eval"], rtol=1e-6, atol=1e-6)
    ref = pmd.simulate_batch(scenes, span, threads=1, **kw)
    _assert_same(pmd.sweep(scenes, span, client=client, chunk_size=2, **kw), ref)


def test_sweep_input_errors(client, short):
    scene, span, kw, _ = short
    with pytest.raises(InvalidInputError, match="t_eval is required"):
        pmd.sweep(scene, span, client=client, q0=kw["q0"])
    with pytest.raises(InvalidInputError, match="q0: expected 1 or 400 runs"):
        pmd.sweep(scene, span, client=client, q0=kw["q0"][:3], v0=np.zeros((400, 7)),
                  t_eval=kw["t_eval"])
    # Refused on the worker (an unknown effect): raised as itself, not retried (no chunk of
    # this sweep went to a worker twice: the scheduler's log, not a clock).
    before = {k for k, _, _ in client.run_on_scheduler(_sweep_transitions)}
    with pytest.raises(InvalidInputError, match="no effect named 'nosuch'"):
        pmd.sweep(scene, span, client=client, q0=kw["q0"], params={"nosuch.k": np.ones(400)},
                  t_eval=kw["t_eval"])
    log = [t for t in client.run_on_scheduler(_sweep_transitions) if t[0] not in before]
    runs: dict = {}
    for key, _, to in log:
        runs[key] = runs.get(key, 0) + (to == "processing")
    assert runs and max(runs.values()) == 1, log


def test_sweep_without_dask_names_the_extra(monkeypatch, short):
    scene, span, kw, _ = short
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(ImportError, match=r"pointmass-dyn\[dask\]"):
        pmd.sweep(scene, span, **kw)


def test_sweep_default_local_cluster(short):
    pytest.importorskip("distributed")
    scene, span, kw, ref = short
    kw = dict(kw, q0=kw["q0"][:20], params={k: v[:20] for k, v in kw["params"].items()})
    ref = pmd.simulate_batch(scene, span, threads=1, **kw)
    _assert_same(pmd.sweep(scene, span, **kw), ref)


def _sweep_transitions(dask_scheduler):
    """The scheduler's transitions of sweep chunks: (key, from, to) (run on the scheduler)."""
    return [
        (str(key), start, finish)
        for key, start, finish, *_ in dask_scheduler.transition_log
        if str(key).startswith("pmd-sweep-")
    ]


def test_worker_killed_mid_sweep_loses_nothing(cluster, client):
    """Last in the file: the cluster's nanny restarts the killed worker, at a new address."""
    # 240 runs of 5 s at rtol 1e-10 (≈ 6 ms each): three chunks of ≈ 0.5 s.
    scene, span, kw = _batch(240, 5.0, 2)
    kw.update(rtol=1e-10, atol=1e-10)
    ref = pmd.simulate_batch(scene, span, threads=1, **kw)

    before = {k for k, _, _ in client.run_on_scheduler(_sweep_transitions)}
    pids = client.run(os.getpid)
    victim = sorted(pids)[0]
    out: dict = {}

    def run():
        try:
            out["result"] = pmd.sweep(scene, span, client=client, chunk_size=80, **kw)
        except BaseException as e:  # reported below
            out["error"] = e

    worker = threading.Thread(target=run)
    worker.start()
    try:
        # Until a chunk is on the victim (events, no deadline): a sweep that ends first fails.
        while not client.processing(workers=[victim]).get(victim):
            assert worker.is_alive(), "no chunk on the victim"
            time.sleep(0.005)
        os.kill(pids[victim], signal.SIGKILL)
        killed_mid_sweep = worker.is_alive()
    finally:
        worker.join()
    assert "error" not in out, out.get("error")
    assert killed_mid_sweep
    _assert_same(out["result"], ref)
    # The chunk the victim was running was taken back from it and run again.
    log = [t for t in client.run_on_scheduler(_sweep_transitions) if t[0] not in before]
    lost = {k for k, a, b in log if (a, b) == ("processing", "released")}
    assert lost and all(
        sum(1 for k2, _, b in log if k2 == k and b == "processing") >= 2 for k in lost
    ), log
    assert victim not in client.nthreads()
