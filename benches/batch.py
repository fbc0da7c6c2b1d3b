"""Throughput of ``simulate_batch`` (issue 16): chain7 over 10 s at rtol 1e-6, B runs that
differ by the tip link's mass, on 1 and 2 threads, against a Python loop of ``simulate``
calls over the same scenes. Target: 2 threads >= 1.8x 1 thread on a 2-core machine.
Measured, not asserted: on a shared, busy machine the ratio comes out lower (the load
average is printed beside the figures).

    PYTHONPATH=python python3 benches/batch.py [--runs 64] [--repeats 5]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
import pointmass_dyn as pmd


def scenes(count: int) -> list:
    """``count`` chain7 scenes, the tip link's mass from 0.9 to 1.1 kg (a Python loop of
    ``simulate`` can run the very same scenes: ``Scene`` has no per-call q0)."""
    base = pmd.load_scene("chain7")
    body = base.model.body("link6")
    out = []
    for m in np.linspace(0.9, 1.1, count):
        rb = pmd.RigidBody(float(m), com=np.asarray(body.com), inertia=np.asarray(body.inertia))
        out.append(base.replace(model=base.model.with_body("link6", rb)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=64, help="runs per batch (default 64)")
    ap.add_argument("--repeats", type=int, default=5, help="timings of each kind, best kept")
    ap.add_argument("--t-end", type=float, default=10.0)
    ap.add_argument("--rtol", type=float, default=1e-6)
    args = ap.parse_args()
    runs = scenes(args.runs)
    t_span = (0.0, args.t_end)
    t_eval = np.linspace(0.0, args.t_end, 101)
    kw = dict(rtol=args.rtol, t_eval=t_eval)

    def loop():
        return [pmd.simulate(s, t_span, **kw) for s in runs]

    def batch(threads):
        return lambda: pmd.simulate_batch(runs, t_span, threads=threads, **kw)

    kinds = {"python loop": loop, "batch, 1 thread": batch(1), "batch, 2 threads": batch(2)}
    # Same runs, same bits, whichever way they are run.
    ref = loop()
    for name in ("batch, 1 thread", "batch, 2 threads"):
        res = kinds[name]()
        assert res.success.all(), res.message
        for r, b in zip(ref, res.results):
            assert np.array_equal(r.q, b.q) and r.nfev == b.nfev, name
    nfev = sum(r.nfev for r in ref)

    load = os.getloadavg()
    times: dict[str, list[float]] = {k: [] for k in kinds}
    for _ in range(args.repeats):  # interleaved, so that the machine's drift hits all alike
        for name, f in kinds.items():
            t0 = time.perf_counter()
            f()
            times[name].append(time.perf_counter() - t0)
    load_after = os.getloadavg()

    print(f"chain7, t = 0 -> {args.t_end:g} s, rtol {args.rtol:g}, {args.runs} runs "
          f"({nfev / args.runs:.0f} evaluations per run), best and median of {args.repeats}; "
          f"load average {load[0]:.2f} before, {load_after[0]:.2f} after, "
          f"{os.cpu_count()} CPUs")
    print(f"{'':<20}{'best (s)':>10}{'median (s)':>12}{'sims/s':>10}{'vs loop':>9}")
    best = {k: min(v) for k, v in times.items()}
    for name, v in times.items():
        print(f"{name:<20}{best[name]:>10.3f}{np.median(v):>12.3f}"
              f"{args.runs / best[name]:>10.1f}{best['python loop'] / best[name]:>8.2f}x")
    ratio = best["batch, 1 thread"] / best["batch, 2 threads"]
    med = np.median(times["batch, 1 thread"]) / np.median(times["batch, 2 threads"])
    print(f"2 threads / 1 thread: {ratio:.2f}x (best), {med:.2f}x (median); target >= 1.8x")


if __name__ == "__main__":
    main()
