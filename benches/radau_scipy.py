"""Our Radau against SciPy's on the classic stiff problems, and against RK45 on the stiff chain.

    python benches/radau_scipy.py            # the full table (~1 min)
    python benches/radau_scipy.py --quick    # one tolerance per problem

Prints per problem and tolerance: SciPy's and our nfev / njev / nlu / steps and the error at
the end against a reference (Van der Pol μ = 1e3 and Robertson: Hairer's test set; μ ≥ 1e4:
SciPy Radau at 1e-10). nfev is counted as SciPy counts it (finite-difference Jacobian
evaluations excluded). The stiff chain: evaluations of RK45 and of Radau (finite-difference
Jacobians counted at 2·dim each) against DOP853 at 1e-12, all on our Rust right-hand side.
"""

import argparse
import sys
from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
from pointmass_dyn.scenes import builtin_scenes, load_scene
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from test_radau import (  # the problems and references live with the tests
    ROBERTSON_REFERENCE,
    VDP_REFERENCE,
    robertson,
    van_der_pol,
)


def compare(name, fun, span, y0, reference, tols, atol_of, jacs):
    for tol in tols:
        for jac_name, jac in jacs:
            kw = dict(rtol=tol, atol=atol_of(tol), jac=jac)
            a = solve_ivp(fun, span, y0, method="Radau", **kw)
            b = pmd.solve_ivp(fun, span, y0, method="Radau", **kw)
            scale = np.maximum(np.abs(reference), 1e-300) if name == "Robertson" else 1.0
            ea = np.max(np.abs(a.y[:, -1] - reference) / scale)
            eb = np.max(np.abs(b.y[:, -1] - reference) / scale)
            print(f"{name:14s} {tol:7.0e} {jac_name:4s} | {a.nfev:7d} {a.njev:5d} {a.nlu:6d} "
                  f"{len(a.t) - 1:6d} {ea:9.2e} | {b.nfev:7d} {b.njev:5d} {b.nlu:6d} "
                  f"{len(b.t) - 1:6d} {eb:9.2e} | {b.nfev / a.nfev:5.3f}")


def stiff_chain(tols):
    if "chain_stiff" in builtin_scenes():
        scene, label = load_scene("chain_stiff"), "chain_stiff"
    else:
        label = "chain7, joints 1-6 with springs 600 N m/rad and dampers 300 N m s/rad"
        base = load_scene("chain7")
        joints = [f"link{i}" for i in range(1, 7)]
        scene = base.replace(effects=list(base.effects) + [
            pmd.Spring(joints, 600.0, 0.0), pmd.Damper(joints, 300.0)])
    span = (0.0, 3.0)
    ref = pmd.simulate(scene, span, method="DOP853", rtol=1e-12, atol=1e-12)
    y_ref = np.concatenate([ref.q[-1], ref.v[-1]])
    print(f"\nstiff chain ({label}, t in {span}, dim "
          f"{y_ref.size}): error vs DOP853 1e-12")
    print(f"{'method':6s} {'tol':>7s} | {'nfev':>7s} {'njev':>5s} {'nlu':>5s} {'steps':>6s} "
          f"{'nfev+2n·njev':>12s} {'error':>9s}")
    for method in ("RK45", "Radau"):
        for tol in tols:
            r = pmd.simulate(scene, span, method=method, rtol=tol, atol=tol)
            err = np.abs(np.concatenate([r.q[-1], r.v[-1]]) - y_ref).max()
            total = r.nfev + 2 * y_ref.size * r.njev
            print(f"{method:6s} {tol:7.0e} | {r.nfev:7d} {r.njev:5d} {r.nlu:5d} "
                  f"{r.n_accepted:6d} {total:12d} {err:9.2e}")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true")
    args = p.parse_args()
    tols = [1e-4] if args.quick else [1e-3, 1e-4, 1e-6, 1e-8]
    print(f"{'problem':14s} {'tol':>7s} {'jac':4s} | SciPy: {'nfev':>7s} {'njev':>5s} "
          f"{'nlu':>6s} {'steps':>6s} {'error':>9s} | ours: same | nfev ours/SciPy")
    for mu in (1e3, 1e4, 1e5, 1e6):
        fun, jac = van_der_pol(mu)
        compare(f"VdP mu={mu:.0e}", fun, (0, 2), [2.0, 0.0], VDP_REFERENCE[mu], tols,
                lambda t: t, [("fd", None), ("jac", jac)])
    fun, jac = robertson()
    compare("Robertson", fun, (0, 1e11), [1.0, 0.0, 0.0], ROBERTSON_REFERENCE, tols,
            lambda t: 1e-3 * t, [("fd", None), ("jac", jac)])
    stiff_chain([1e-4] if args.quick else [1e-4, 1e-6, 1e-8])


if __name__ == "__main__":
    main()
