"""`auto`'s two stiffness tests on the bundled loop-free scenes (docs/integrators.md, *auto*):
for each rtol = atol from 1e-3 to 1e-8, `auto`'s evaluations and switch time beside RK45's
alone, and the largest `h·ρ` seen at the checks `auto` would make (every 20 accepted steps
from step 100; ρ the Jacobian's spectral radius by three power-iteration steps in NumPy on
SciPy's RK45 steps of our right-hand side, independent of the Rust code; at most 40 checks,
over the scene's span, solo12_standing over 0.3 s). Hairer's estimate alone misses
solo12_standing at 1e-3 and 1e-4; the new test's limit is 0.75 × 3.25 = 2.44 for RK45.

    python benches/stiffness_spectral.py          # ~2 min
"""

from __future__ import annotations

import math
import time

import numpy as np
import pointmass_dyn as pmd
from pointmass_dyn.benchmarking._rhs import scene_rhs
from scipy.integrate import solve_ivp
from scipy.integrate._ivp.rk import RK45

SCENES = ("chain7", "panda", "pendulum_spatial", "pendulum_planar", "satellite",
          "iftomm_a01_pendulum", "box_incline", "chain_stiff", "solo12_standing")
TOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
FIRST, EVERY, MAX_CHECKS = 100, 20, 40


def spectral_radius(f, t, y, fy, v, iterations=3):
    eps = math.sqrt(np.finfo(float).eps) * max(1.0, np.linalg.norm(y))
    rho = math.nan
    for _ in range(iterations):
        nv = np.linalg.norm(v)
        if not nv > 0:
            break
        w = (f(t, y + (eps / nv) * v) - fy) / eps
        rho, v = np.linalg.norm(w), w
    return rho


def largest_h_rho(f, span, y0, tol):
    """The largest h·ρ over the checks, along SciPy's RK45 steps (NaN: no check)."""
    sol = solve_ivp(f, span, y0, method="RK45", rtol=tol, atol=tol)
    ts, ys = sol.t, sol.y.T
    c, a, b = RK45.C, RK45.A, RK45.B
    out = []
    for i in range(FIRST - 1, len(ts) - 1, EVERY):
        h, y = ts[i + 1] - ts[i], ys[i]
        k = np.zeros((7, y.size))
        k[0] = f(ts[i], y)
        for j in range(1, 6):
            k[j] = f(ts[i] + c[j] * h, y + h * (a[j, :j] @ k[:j]))
        y6 = y + h * (a[5, :5] @ k[:5])
        y_new = y + h * (b @ k[:6])
        out.append(h * spectral_radius(f, ts[i] + h, y_new, f(ts[i] + h, y_new), y_new - y6))
        if len(out) == MAX_CHECKS:
            break
    return max(out) if out else math.nan


def main():
    t_all = time.perf_counter()
    print(f"{'scene':20}{'rtol':>7}{'auto nfev':>11}{'switch t':>10}{'RK45 nfev':>11}"
          f"{'max h*rho':>11}")
    for name in SCENES:
        sc = pmd.load_scene(name)
        span = (0.0, min(sc.t_span[1], 10.0))
        f = scene_rhs(sc)
        y0 = np.concatenate([sc.q0, sc.v0])
        for tol in TOLS:
            auto = pmd.simulate(sc, span, method="auto", rtol=tol, atol=tol)
            rk = pmd.simulate(sc, span, method="RK45", rtol=tol, atol=tol)
            replay = (0.0, 0.3) if name == "solo12_standing" else span
            hr = largest_h_rho(f, replay, y0, tol)
            sw = f"{auto.t_switch:.3g}" if auto.t_switch is not None else "-"
            print(f"{name:20}{tol:>7.0e}{auto.nfev:>11}{sw:>10}{rk.nfev:>11}{hr:>11.2f}",
                  flush=True)
    print(f"({time.perf_counter() - t_all:.0f} s)")


if __name__ == "__main__":
    main()
