"""Dask's overhead (issue 16): a 10,000-run chain7 sweep (0.5 s each, rtol 1e-6, per-run q0
noise and gravity) by `pmd.sweep` on a LocalCluster of one single-threaded worker process
per core, against `pmd.simulate_batch` with one thread per core in this process. The
cluster is started before the clock (a long-lived cluster is the use case); the sweep's time
includes sending the chunks, running them and gathering and stacking the results. The two
results are checked equal bit for bit first. Target: sweep / batch within 1.3.

    python benches/sweep.py [--runs 10000] [--repeat 5]

Ratios come from one run on one machine; the absolute times vary with load."""

from __future__ import annotations

import argparse
import time

import numpy as np
import pointmass_dyn as pmd
from dask.system import CPU_COUNT
from distributed import Client, LocalCluster
from pointmass_dyn._sweep import CHUNKS_PER_SLOT  # the default chunking, to report it


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=10_000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--t-end", type=float, default=0.5)
    args = ap.parse_args()

    scene = pmd.load_scene("chain7")
    rng = np.random.default_rng(0)
    b = args.runs
    kw = dict(
        q0=scene.q0 + 0.05 * rng.standard_normal((b, scene.model.nq)),
        params={"gravity": np.array([0, 0, -9.81]) + 0.1 * rng.standard_normal((b, 3))},
        t_eval=np.linspace(0, args.t_end, 11),
        rtol=1e-6,
        atol=1e-6,
    )
    span = (0.0, args.t_end)
    cores = CPU_COUNT
    with LocalCluster(
        n_workers=cores, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster, Client(cluster) as client:
        ref = pmd.simulate_batch(scene, span, threads=cores, **kw)
        got = pmd.sweep(scene, span, client=client, **kw)
        assert np.array_equal(got.q, ref.q) and np.array_equal(got.nfev, ref.nfev)

        # Interleaved, best of each: the machines here are shared and the load moves.
        t_batch = t_sweep = np.inf
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            pmd.simulate_batch(scene, span, threads=cores, **kw)
            t1 = time.perf_counter()
            pmd.sweep(scene, span, client=client, **kw)
            t2 = time.perf_counter()
            t_batch, t_sweep = min(t_batch, t1 - t0), min(t_sweep, t2 - t1)
        chunks = -(-b // (CHUNKS_PER_SLOT * cores))
    print(f"{b} chain7 runs to t = {args.t_end} s, {cores} cores "
          f"(mean nfev {ref.nfev.mean():.0f}); best of {args.repeat}")
    print(f"simulate_batch(threads={cores}):             {t_batch:8.3f} s")
    print(f"sweep on LocalCluster({cores} x 1 thread), chunks of {chunks}: {t_sweep:8.3f} s")
    print(f"ratio sweep / simulate_batch: {t_sweep / t_batch:.2f}  (target <= 1.3)")


if __name__ == "__main__":
    main()
