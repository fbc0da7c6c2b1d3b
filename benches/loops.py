"""Closed loops beside SciPy: forward dynamics per call of the four-bar and of Andrews'
squeezing mechanism, and a whole run of Andrews' mechanism to t = 0.03 s against
`scipy.integrate.solve_ivp(method="Radau")` on the published index-1 form (tests/andrews.py:
[M Gᵀ; G 0][q̈; λ] = [f; −g_qq], NumPy per evaluation), both to the published reference.

    python benches/loops.py

Ratios come from one run on one machine; the absolute times vary with load."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import andrews as ref
import pointmass_dyn as pmd

PERM = np.array([0, 1, 2, 4, 3, 6, 5])
INV = np.argsort(PERM)


def per_call(f, n=20000):
    f()
    best = np.inf
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(n):
            f()
        best = min(best, (time.perf_counter() - t0) / n)
    return best


def four_bar():
    z = [0, 0, 1]

    def bar(length):
        i = length**2 / 12 + 1e-4
        return pmd.RigidBody(1.0, [length / 2, 0, 0], np.diag([1e-4, i, i]))

    m = pmd.Model()
    m.add_body(bar(0.1), pmd.Revolute(z), name="crank")
    m.add_body(bar(0.35), pmd.Revolute(z), parent=0, translation=[0.1, 0, 0], name="coupler")
    m.add_body(bar(0.3), pmd.Revolute(z), translation=[0.4, 0, 0], name="rocker")
    tree = pmd.Model()
    for k, (length, parent, x) in enumerate([(0.1, -1, 0.0), (0.35, 0, 0.1), (0.3, -1, 0.4)]):
        tree.add_body(bar(length), pmd.Revolute(z), parent=parent, translation=[x, 0, 0], name=f"b{k}")
    m.add_loop("coupler", "rocker", pmd.Revolute(z), translation_a=[0.35, 0, 0], translation_b=[0.3, 0, 0])
    q = m.assemble([0.5, 0.5, 1.5], fixed=[0])
    v = m.assemble_velocity(q, [2.0, 0, 0], fixed=[0])
    return m, tree, q, v


def andrews_run(rtol):
    s = pmd.load_scene("andrews")  # its own drive and spring
    t0 = time.perf_counter()
    res = pmd.simulate(s, (0, ref.T_END), rtol=rtol, atol=rtol)
    wall = time.perf_counter() - t0
    err = np.max(np.abs(res.q[-1][INV] - ref.Q_END) / np.abs(ref.Q_END))
    return wall, err, res.nfev, res.n_accepted


def radau_run(rtol):
    def rhs(t, y):
        q, qd = y[:7], y[7:]
        a, _ = ref.index1_rhs(q, qd)
        return np.concatenate([qd, a])

    y0 = np.concatenate([ref.Q0, np.zeros(7)])
    t0 = time.perf_counter()
    sol = solve_ivp(rhs, (0, ref.T_END), y0, method="Radau", rtol=rtol, atol=rtol)
    wall = time.perf_counter() - t0
    err = np.max(np.abs(sol.y[:7, -1] - ref.Q_END) / np.abs(ref.Q_END))
    return wall, err, sol.nfev, sol.t.size - 1


def main():
    print(f"pointmass_dyn {pmd.__version__}, numpy {np.__version__}")
    m, tree, q, v = four_bar()
    tau = np.zeros(3)
    g = np.array([0, -9.81, 0])
    t_loops = per_call(lambda: m.forward_dynamics(q, v, tau, gravity=g))
    t_tree = per_call(lambda: tree.forward_dynamics(q, v, tau, gravity=g))
    print("\nforward dynamics per Python call")
    print(f"  four-bar with its loop   {t_loops * 1e6:8.2f} µs   (tree alone {t_tree * 1e6:.2f} µs)")
    s = pmd.load_scene("andrews")
    tau7 = ref.applied_forces(ref.Q0)[PERM]
    qa, va, ma = s.q0, np.zeros(7), s.model
    t_and = per_call(lambda: ma.forward_dynamics(qa, va, tau7))
    t_ref = per_call(lambda: ref.index1_rhs(ref.Q0, np.zeros(7)), n=2000)
    print(f"  Andrews (3 loops)        {t_and * 1e6:8.2f} µs   (published index-1 form in NumPy {t_ref * 1e6:.1f} µs, {t_ref / t_and:.0f}x)")
    print("\nAndrews' mechanism to t = 0.03 s: max relative error of the 7 angles vs the reference")
    print(f"  {'tol':>7} | {'ours (RK45 + projection)':>34} | {'SciPy Radau, index-1 NumPy':>34} | time ratio")
    for tol in (1e-6, 1e-8, 1e-10):
        w1, e1, n1, s1 = andrews_run(tol)
        w2, e2, n2, s2 = radau_run(tol)
        print(
            f"  {tol:7.0e} | {w1 * 1e3:8.1f} ms {e1:8.1e} {n1:6d} ev {s1:5d} st | "
            f"{w2 * 1e3:8.1f} ms {e2:8.1e} {n2:6d} ev {s2:5d} st | {w2 / w1:6.0f}x"
        )


if __name__ == "__main__":
    main()
