"""Work–precision across methods on the bundled scenes (issue 15): every method of ours, SciPy's
on our right-hand side and MuJoCo's own engine, error against one reference, and the ratios
behind the targets:

* at equal error, our best method ≥ 10× faster than SciPy's best method on our right-hand
  side at every accuracy decade from 1e-4 to 1e-10 on chain7, and
* ≥ 10× faster than MuJoCo's RK4 at 1e-4 on chain7 (issue 44; issue 15 asked 5× and 20×
  at every decade from 1e-3 to 1e-10 on every scene),

(times read off each method's time–error curve by log–log interpolation,
``pointmass_dyn.benchmarking``). ``--markdown`` prints the ratio table of
docs/numerical-stability.md from the run.

    pip install mujoco              # optional peer
    python benches/work_precision_methods.py                      # ~5 min on 2 cores
    python benches/work_precision_methods.py --scenes chain7 --quick
    python benches/work_precision_methods.py --plot docs/work_precision.png \\
        --out docs/work_precision.csv --markdown

Spans: chain7 2 s (chaotic: at 10 s the reference itself is not converged), panda 1 s (its
scene's), pendulum_spatial 10 s (the paper's), chain_stiff 3 s (its scene's). Ratios from one
run on a shared machine: compare ratios, not milliseconds across runs.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np
import pointmass_dyn as pmd
from pointmass_dyn import benchmarking
from pointmass_dyn.benchmarking import DEFAULT_TOLERANCES

SPANS = {"chain7": 2.0, "panda": 1.0, "pendulum_spatial": 10.0, "chain_stiff": 3.0}
TARGET_MUJOCO, TARGET_SCIPY = 10.0, 10.0
TARGET_SCENE = "chain7"
# The decades each target is asked at (issue 44).
MUJOCO_DECADES, SCIPY_DECADES = (1e-4,), (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
LABEL = {"chain7": "chain7", "panda": "Panda", "pendulum_spatial": "spatial pendulum",
         "chain_stiff": "chain_stiff"}


def fmt(x, spec=".1f"):
    return format(x, spec) if np.isfinite(x) else "-"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", nargs="+", default=list(SPANS))
    ap.add_argument("--methods", nargs="+", default=["all"])
    ap.add_argument("--quick", action="store_true", help="4 tolerances, 1 repeat")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--scipy-repeats", type=int, default=2)
    ap.add_argument("--plot", default=None)
    ap.add_argument("--out", default=None)
    ap.add_argument("--markdown", action="store_true",
                    help="print the ratio table of docs/numerical-stability.md")
    args = ap.parse_args()
    tols = (1e-3, 1e-5, 1e-7, 1e-9, 1e-11) if args.quick else DEFAULT_TOLERANCES
    repeats = 1 if args.quick else args.repeats
    scipy_repeats = 1 if args.quick else args.scipy_repeats
    try:
        import mujoco
        mj = mujoco.__version__
    except ImportError:
        mj = "not installed"
    import scipy

    load = os.getloadavg()
    print(f"pointmass_dyn {pmd.__version__}, mujoco {mj}, scipy {scipy.__version__}, "
          f"{os.cpu_count()} cores, load average {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}; "
          f"best of {repeats} (SciPy: {scipy_repeats})")
    results, summary = [], []
    t_all = time.perf_counter()
    for name in args.scenes:
        t0 = time.perf_counter()
        res = pmd.work_precision(name, tols, t_end=SPANS.get(name), repeats=repeats,
                                 scipy_repeats=scipy_repeats, methods=args.methods)
        results.append(res)
        print()
        print(res.methods_table())
        print()
        print(res.cheapest_table())
        print(f"({time.perf_counter() - t0:.0f} s; reference floor: ours at 1e-13 against "
              f"DOP853 {res.reference_check.get('err_dense', math.nan):.1e})")
        for r in benchmarking.ratio_table(res.method_rows):
            summary.append((name, r))
    print(f"\nall scenes: {time.perf_counter() - t_all:.0f} s\n")
    print(f"Targets (issue 44, {TARGET_SCENE}): ours best >= {TARGET_SCIPY:g}x SciPy's best at "
          f"1e-4 ... 1e-10 and >= {TARGET_MUJOCO:g}x MuJoCo's RK4 at 1e-4, at equal error")
    print(f"{'scene':<18}{'err':>7}  {'ours best':<10}{'x MuJoCo RK4':>13}{'x SciPy best':>13}"
          f"  {'SciPy best':<14}{'met?':>6}")
    for name, r in summary:
        asked = name == TARGET_SCENE
        mj = asked and any(math.isclose(r["err"], e) for e in MUJOCO_DECADES)
        sp = asked and any(math.isclose(r["err"], e) for e in SCIPY_DECADES)
        misses = [k for k, on, x, t in (("MJ", mj, r["vs_mujoco_rk4"], TARGET_MUJOCO),
                                         ("SP", sp, r["vs_scipy"], TARGET_SCIPY))
                  if on and not x >= t]
        met = ("-" if not (mj or sp) else "n/a" if not np.isfinite(r["t_ours"])
               else " ".join(misses) or "yes")
        print(f"{name:<18}{r['err']:>7.0e}  {r['ours'] or '-':<10}"
              f"{fmt(r['vs_mujoco_rk4']):>13}{fmt(r['vs_scipy']):>13}  "
              f"{r['scipy'] or '-':<14}{met:>6}")
    print("met?: yes = every target asked at that error; MJ / SP = the MuJoCo / SciPy target "
          "missed; - = none asked there; n/a = no method of ours reaches that error")
    if args.markdown:
        print()
        print(markdown_table(summary))
    if args.out:
        benchmarking.write_methods_csv(results, args.out)
        print(f"rows written to {args.out}")
    if args.plot:
        benchmarking.plot_methods(results, args.plot)
        print(f"figure written to {args.plot}")


def markdown_table(summary) -> str:
    """docs/numerical-stability.md's table: per error, each scene's best method of ours and
    how many times faster it is than MuJoCo's RK4 and than SciPy's best (named)."""
    scenes = list(dict.fromkeys(name for name, _ in summary))
    head = ["error"]
    for name in scenes:
        head += [LABEL.get(name, name), "× MuJoCo RK4", "× SciPy"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    by = {(name, f"{r['err']:.0e}"): r for name, r in summary}
    for err in dict.fromkeys(f"{r['err']:.0e}" for _, r in summary):
        cells = [err]
        for name in scenes:
            r = by.get((name, err))
            if r is None or not np.isfinite(r["t_ours"]):
                cells += ["-", "-", "-"]
                continue
            sp = r["scipy"].split(":")[-1] if r["scipy"] else ""
            cells += [r["ours"], fmt(r["vs_mujoco_rk4"]),
                      f"{fmt(r['vs_scipy'])} ({sp})" if sp else "-"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
