"""Evaluations to reach a given error at loose tolerances: Runge–Kutta pairs and step-size
controllers compared on our right-hand side, before any is built into the integrator
(issue 44: can a pair other than Dormand–Prince 5(4) close the gap to MuJoCo's RK4 at 1e-4?).

One generic embedded-pair engine in NumPy (FSAL, SciPy's RMS error norm and initial step,
dense output on the check grid) runs SciPy's RK45 and RK23 tableaux and Tsitouras' 5(4)
(Tsit5, Comput. Math. Appl. 62 (2011) 770, with its 4th-order interpolant), each with SciPy's
controller and (the 5(4) pairs, for which its constants are made) with Hairer's PI controller
(``controller="pi"``: α = 0.17, β = 0.04). Errors are
measured as benches/work_precision_methods.py does (max over 21 check times of |y − y_ref|,
divided by max |y_ref|; the reference is our DOP853 at 1e-13), and the evaluations to reach
1e-3 … 1e-6 are read off each curve by log–log interpolation. Evaluations, not seconds: the
engine is Python. The engine is checked against SciPy's ``solve_ivp`` (same evaluations for
RK45 with SciPy's controller).

    python benches/rk_pairs.py            # ~10 s
"""

from __future__ import annotations

import math

import numpy as np
import pointmass_dyn as pmd
from pointmass_dyn.benchmarking._rhs import scene_rhs
from scipy.integrate import solve_ivp
from scipy.integrate._ivp.rk import RK23, RK45

SPANS = {"chain7": 2.0, "panda": 1.0, "pendulum_spatial": 10.0}
DECADES = (1e-3, 1e-4, 1e-5, 1e-6)

TSIT5_A = np.zeros((6, 6))
TSIT5_A[1, 0] = 0.161
TSIT5_A[2, :2] = [-0.008480655492356989, 0.335480655492357]
TSIT5_A[3, :3] = [2.8971530571054935, -6.359448489975075, 4.3622954328695815]
TSIT5_A[4, :4] = [5.325864828439257, -11.748883564062828, 7.4955393428898365, -0.09249506636175525]
TSIT5_A[5, :5] = [5.86145544294642, -12.92096931784711, 8.159367898576159, -0.071584973281401,
                  -0.028269050394068383]
TSIT5 = dict(
    C=np.array([0, 0.161, 0.327, 0.9, 0.9800255409045097, 1.0]), A=TSIT5_A,
    B=np.array([0.09646076681806523, 0.01, 0.4798896504144996, 1.379008574103742,
                -3.290069515436081, 2.324710524099774]),
    # B − B̂ over the seven FSAL stages (the published b̂ with the last entry's sign as the
    # order conditions need it: these sum to zero).
    E=np.array([0.001780011052226, 0.000816434459657, -0.007880878010262, 0.144711007173263,
                -0.582357165452555, 0.458082105929187, -1 / 66]),
    # The 4th-order interpolant: b_i(θ) = Σ_j P[i, j] θ^(j+1) (checked below).
    P=np.array([[1, -2.763706197274826, 2.9132554618219126, -1.0530884977290216],
                [0, 0.13169999999999998, -0.2234, 0.1017],
                [0, 3.930296236894751, -5.941033872131505, 2.490627285651253],
                [0, -12.411077166933676, 30.338188630282318, -16.548102889244902],
                [0, 37.50931341651104, -88.1789048947664, 47.37952196281928],
                [0, -27.896526289197286, 65.09189467479368, -34.87065786149661],
                [0, 1.5, -4.0, 2.5]]),
    order=5)
PAIRS = {
    "DP5 (RK45)": dict(C=RK45.C, A=RK45.A, B=RK45.B, E=RK45.E, P=RK45.P, order=5),
    "Tsit5": TSIT5,
    "BS3 (RK23)": dict(C=RK23.C, A=RK23.A, B=RK23.B, E=RK23.E, P=RK23.P, order=3),
}
HAIRER_PI = (0.17, 0.04)


def check_tsit5() -> None:
    """Row sums, the solution's and the interpolant's order conditions to 4, B̂'s to 4."""
    a = np.zeros((7, 7))
    a[:6, :6], a[6, :6] = TSIT5["A"], TSIT5["B"]
    c = np.append(TSIT5["C"], 1.0)
    assert np.allclose(a.sum(1), c, atol=1e-14)
    for th in (0.3, 1.0):
        b = TSIT5["P"] @ th ** np.arange(1, 5)
        conds = [b.sum() - th, b @ c - th**2 / 2, b @ c**2 - th**3 / 3, b @ (a @ c) - th**3 / 6,
                 b @ c**3 - th**4 / 4, b @ (c * (a @ c)) - th**4 / 8,
                 b @ (a @ c**2) - th**4 / 12, b @ (a @ a @ c) - th**4 / 24]
        assert max(abs(x) for x in conds) < 1e-13, conds
    bh = np.append(TSIT5["B"], 0) - TSIT5["E"]
    assert max(abs(bh.sum() - 1), abs(bh @ c - 0.5), abs(bh @ (a @ a @ c) - 1 / 24)) < 1e-13


def rms(x):
    return math.sqrt(float(x @ x) / x.size)


def integrate(f, span, y0, pair, tol, grid, pi=None):
    """(states on grid, evaluations) of one run; ``pi``: (α, β) or None for SciPy's."""
    c, a, b, e, p, order = (pair[k] for k in ("C", "A", "B", "E", "P", "order"))
    s = len(c)
    t, t1 = span
    y = np.array(y0, float)
    fy = f(t, y)
    nfev = 1
    scale = tol + np.abs(y) * tol                       # SciPy's select_initial_step
    d0, d1 = rms(y / scale), rms(fy / scale)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    f1 = f(t + h0, y + h0 * fy)
    nfev += 1
    d2 = rms((f1 - fy) / scale) / h0
    h1 = max(1e-6, h0 * 1e-3) if max(d1, d2) <= 1e-15 else (0.01 / max(d1, d2)) ** (1 / order)
    h = min(100 * h0, h1)
    k = np.zeros((s + 1, y.size))
    out, gi, err_prev, rejected = [y.copy()], 1, 1e-4, False
    while t < t1:
        hh = min(h, t1 - t)
        k[0] = fy
        for i in range(1, s):
            k[i] = f(t + c[i] * hh, y + hh * (a[i, :i] @ k[:i]))
        y_new = y + hh * (b @ k[:s])
        k[s] = f(t + hh, y_new)
        nfev += s
        en = rms(hh * (e @ k) / (tol + np.maximum(np.abs(y), np.abs(y_new)) * tol))
        alpha = pi[0] if pi else 1 / order
        if en < 1:
            fac = 10.0 if en == 0 else 0.9 * en ** -alpha * (err_prev ** pi[1] if pi else 1.0)
            fac = min(10.0, max(0.2, fac) if pi else fac)
            if rejected:
                fac = min(1.0, fac)
            while gi < len(grid) and grid[gi] <= t + hh + 1e-14:
                th = (grid[gi] - t) / hh
                out.append(y + hh * (k.T @ p) @ th ** np.arange(1, p.shape[1] + 1))
                gi += 1
            t, y, fy, rejected = t + hh, y_new, k[s].copy(), False
            if pi:
                err_prev = max(en, 1e-4)
        else:
            fac, rejected = max(0.2, 0.9 * en ** -alpha), True
        h = hh * fac
    return np.array(out), nfev


def evaluations_at(rows, e):
    """Log–log interpolation of evaluations at error ``e`` along (evaluations, error) rows."""
    r = sorted(rows, key=lambda x: -x[1])
    for (n0, e0), (n1, e1) in zip(r, r[1:]):
        if e0 >= e >= e1 and e0 > e1:
            w = (math.log(e0) - math.log(e)) / (math.log(e0) - math.log(e1))
            return math.exp((1 - w) * math.log(n0) + w * math.log(n1))
    return math.nan


def main():
    check_tsit5()
    print("evaluations to reach each error (max over 21 check times / max |y|), "
          "tolerances 1e-2 … 1e-8 (25 values, rtol = atol)")
    print(f"{'scene':17} {'pair':11} {'controller':10} " + " ".join(f"{e:>7.0e}" for e in DECADES))
    for name, t_end in SPANS.items():
        sc = pmd.load_scene(name)
        f = scene_rhs(sc)
        y0 = np.concatenate([sc.q0, sc.v0])
        grid = np.linspace(0, t_end, 21)
        ref = pmd.simulate(sc, (0, t_end), t_eval=grid, method="DOP853", rtol=1e-13, atol=1e-13)
        y_ref = np.hstack([ref.q, ref.v])
        if y_ref.shape[1] != y0.size:
            print(f"{name}: q and v sizes differ (quaternions); skipped")
            continue
        scale = np.max(np.abs(y_ref))
        sp = solve_ivp(f, (0, t_end), y0, method="RK45", rtol=1e-4, atol=1e-4, t_eval=grid)
        _, n = integrate(f, (0, t_end), y0, PAIRS["DP5 (RK45)"], 1e-4, grid)
        assert n == sp.nfev, (n, sp.nfev)              # the engine is SciPy's, step for step
        for pair_name, pair in PAIRS.items():
            ctrls = [("SciPy", None)] + ([("Hairer PI", HAIRER_PI)] if pair["order"] == 5 else [])
            for ctrl, pi in ctrls:
                rows = []
                for tol in np.logspace(-2, -8, 25):
                    y, n = integrate(f, (0, t_end), y0, pair, tol, grid, pi)
                    rows.append((n, float(np.max(np.abs(y - y_ref))) / scale))
                at = [evaluations_at(rows, e) for e in DECADES]
                print(f"{name:17} {pair_name:11} {ctrl:10} "
                      + " ".join(f"{x:7.0f}" if np.isfinite(x) else "      -" for x in at))


if __name__ == "__main__":
    main()
