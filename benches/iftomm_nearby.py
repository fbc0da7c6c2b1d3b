"""A02 (the N-four-bar, N = 40) from states near the scene's: v0 scaled by 1 + d, a stand-in
for another CPU's rounding (docs/mechanisms.md §2, "How far this holds" and "Jumping a
crossing"). DOP853, 0-20 s, atol = rtol/100.

    python benches/iftomm_nearby.py finish 1e-9 1e-10 1e-11 1e-12   # 11 fixed states
    python benches/iftomm_nearby.py random 1e-12 --seeds 1 2 3 4     # 20 random states per seed
    python benches/iftomm_nearby.py spec 1e-10 1e-12                 # the spec's error measure

``finish``: whether each run reaches 20 s, its steps and where it stopped. ``random``:
d = ±10^U(-15, -9), ``rng = np.random.default_rng(seed)``, 20 per seed. ``spec``: the
benchmark's error measure against the exact reduction with phi'(0) scaled alike
(benches/iftomm.py's ``run``), with steps and evaluations.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parent))
import iftomm

#: The fixed states of docs/mechanisms.md §2.
STATES = [0, 1e-13, -3e-13, 1e-12, 5e-12, -2e-11, 1e-10, 3e-15, -1e-9, 2e-13, -7e-12]


def nearby(scene, d):
    return pmd.Scene(scene.model, scene.q0, np.asarray(scene.v0) * (1 + d), effects=scene.effects)


def finish(scene, d, rtol):
    r = pmd.simulate(nearby(scene, d), (0, 20), method="DOP853", rtol=rtol, atol=rtol * 1e-2,
                     max_steps=4000)
    return r.success, r.n_accepted, float(r.t[-1])


def spec_error(setup, d, rtol):
    sc0, t, out, _ = setup
    n = 40
    c = iftomm.G * ((n + 1) / 2 + n) / ((n + 1) / 3 + n)
    r = solve_ivp(lambda _, y: [y[1], -c * np.cos(y[0])], (0, 20), [np.pi / 2, -(1 + d)],
                  t_eval=t, rtol=1e-13, atol=1e-13, method="DOP853")
    ref = np.stack([np.cos(r.y[0]), np.sin(r.y[0])], 1)
    err, _, _, steps, nfev, _, ok = iftomm.run("A02", "DOP853", rtol, (nearby(sc0, d), t, out, ref))
    return err, steps, nfev, ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mode", choices=["finish", "random", "spec"])
    ap.add_argument("rtol", type=float, nargs="+")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4])
    args = ap.parse_args()
    scene = pmd.load_scene("iftomm_a02_nfourbar")
    if args.mode == "finish":
        for d in STATES:
            row = [(rtol, *finish(scene, d, rtol)) for rtol in args.rtol]
            print(d, " | ".join(f"{r:g}: {'ok' if ok else 'STALLED'} {n} steps, t = {t:.3f}"
                                for r, ok, n, t in row), flush=True)
    elif args.mode == "random":
        for rtol in args.rtol:
            for seed in args.seeds:
                rng = np.random.default_rng(seed)
                ds = rng.choice([-1, 1], 20) * 10 ** rng.uniform(-15, -9, 20)
                runs = [(d, *finish(scene, d, rtol)) for d in ds]
                failed = [f"{float(d)!r} at t = {t:.3f}" for d, ok, _, t in runs if not ok]
                print(f"rtol {rtol:g}, seed {seed}: {20 - len(failed)} of 20 finish; "
                      f"stalled: {', '.join(failed) or 'none'}", flush=True)
    else:
        setup = iftomm.a02()
        for d in STATES:
            row = [(rtol, *spec_error(setup, d, rtol)) for rtol in args.rtol]
            print(d, " | ".join(f"{r:g}: {e:.1e}{'' if ok else ' (stalled)'} {s} steps {f} nfev"
                                for r, e, s, f, ok in row), flush=True)


if __name__ == "__main__":
    main()
