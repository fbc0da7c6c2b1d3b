"""Issue 11's targets, measured (not asserted: these machines are shared and noisy).

* ``simulate`` beside a busy Python thread costs <= 1.2x the time alone (chain7, 240 s at
  rtol 1e-11, as the probe ran it).
* ``Model.add_body`` of 5000 links in under a second; ``scene.model`` of a 5000-link scene
  without copying it.

    PYTHONPATH=python python3 benches/reliability.py [--quick]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import threading
import time

import numpy as np
import pointmass_dyn as pmd


def best_of(n: int, f) -> float:
    best = float("inf")
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def busy_thread_ratio(t_end: float, pairs: int) -> dict[str, list[float]]:
    """Times alone, beside a busy Python thread and (the control: the same load on the other
    core, but no interpreter to share) beside a busy process, interleaved run by run so that
    the machine's drift hits all three alike."""
    scene = pmd.load_scene("chain7")

    def run() -> float:
        t0 = time.perf_counter()
        r = pmd.simulate(scene, (0.0, t_end), rtol=1e-11, atol=1e-11)
        assert r.success, r.message
        return time.perf_counter() - t0

    def beside_busy() -> float:
        stop = threading.Event()

        def busy():
            x = 0
            while not stop.is_set():
                x += 1

        t = threading.Thread(target=busy, daemon=True)
        t.start()
        try:
            return run()
        finally:
            stop.set()
            t.join()

    def beside_process() -> float:
        p = subprocess.Popen([sys.executable, "-c", "while True: pass"])
        time.sleep(0.05)
        try:
            return run()
        finally:
            p.kill()
            p.wait()

    times: dict[str, list[float]] = {"alone": [], "thread": [], "process": []}
    for _ in range(pairs):
        times["alone"].append(run())
        times["thread"].append(beside_busy())
        times["process"].append(beside_process())
    return times


def build_chain(n: int) -> pmd.Model:
    body = pmd.RigidBody(1.0, com=[0.15, 0, 0], inertia=np.diag([1e-4, 7.5e-3, 7.5e-3]))
    m = pmd.Model()
    parent = -1
    for k in range(n):
        parent = m.add_body(
            body, pmd.Revolute([0, 1, 0] if k % 2 == 0 else [0, 0, 1]), parent=parent,
            translation=[0.3 if k else 0.0, 0, 0],
        )
    return m


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="shorter runs (a smoke test)")
    args = ap.parse_args()
    t_end, pairs = (24.0, 1) if args.quick else (240.0, 7)

    times = busy_thread_ratio(t_end, pairs)
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"simulate chain7 0..{t_end:g} s at rtol 1e-11, {pairs} interleaved runs each, median "
          f"(best): alone {med['alone']:.3f} s ({min(times['alone']):.3f}), beside a busy Python "
          f"thread {med['thread']:.3f} s ({min(times['thread']):.3f}), beside a busy process "
          f"{med['process']:.3f} s ({min(times['process']):.3f})")
    print(f"  busy thread / alone: {med['thread'] / med['alone']:.2f} (target <= 1.2); the "
          f"control, busy process / alone: {med['process'] / med['alone']:.2f}")

    for n in (1000, 5000):
        t = best_of(1 if n > 1000 else 3, lambda n=n: build_chain(n))
        print(f"add_body x {n}: {t:.3f} s ({t / n * 1e6:.1f} us per body; target < 1 s at 5000)")

    model = build_chain(5000)
    scene = pmd.Scene(model, effects=[pmd.Gravity()])
    t = best_of(5, lambda: scene.model)
    print(f"scene.model of a 5000-link scene: {t * 1e6:.1f} us per access (shared, not copied)")
    q = np.zeros(5000)
    t = best_of(3, lambda: model.mass_matrix(q))
    print(f"mass_matrix of the 5000-link chain (recursive, 200 MB result): {t:.3f} s")


if __name__ == "__main__":
    main()
