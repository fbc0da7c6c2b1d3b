"""Prescribed-motion analysis and balancing of the bundled four-bar over 360 crank positions,
timed (issue 14's target: each well under a second). Median of repeated runs, wall clock.

    python benches/balancing.py [--repeat 7]
"""

from __future__ import annotations

import argparse
import statistics
import time

import pointmass_dyn as pmd


def timed(f, repeat):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    scene = pmd.load_scene("fourbar")
    g = [0.0, -9.81, 0.0]
    t_motion, motion = timed(
        lambda: pmd.prescribed_motion(
            scene.model, "crank", speed=10.0, samples=360, q_guess=scene.q0, gravity=g
        ),
        args.repeat,
    )
    rings = [
        pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 24),
        pmd.Counterweight.ring("rocker", [0, 0, 0], 0.02, 24),
    ]
    cases = {
        "force balance (zero force, 48 candidates)": dict(
            counterweights=rings, zero=("force",), objective={}
        ),
        "zero force + least RMS moment": dict(
            counterweights=rings, zero=("force",), objective={"moment": 1.0}
        ),
        "force + moment + torque, coupler redesigned": dict(
            counterweights=rings, links=["coupler"],
            objective={"force": 1.0, "moment": 0.5, "torque": 0.2},
        ),
    }
    print(f"prescribed_motion, 360 crank positions: {1e3 * t_motion:.1f} ms")
    for name, kw in cases.items():
        t_bal, b = timed(lambda kw=kw: pmd.balance(motion, **kw), args.repeat)
        ratio = b.after.shaking.rms["force"] / motion.shaking.rms["force"]
        print(f"balance, {name}: {1e3 * t_bal:.1f} ms (shaking force RMS after/before {ratio:.2e})")
    t_front, _ = timed(
        lambda: pmd.pareto_front(motion, ("force", "moment"), count=11, counterweights=rings), 1
    )
    print(f"pareto_front, 11 points: {1e3 * t_front:.0f} ms")


if __name__ == "__main__":
    main()
