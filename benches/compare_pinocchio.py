"""Side-by-side timings, in one process: our Python calls against Pinocchio's on identical
models, and our simulate() against SciPy solve_ivp(RK45) driving pinocchio.aba.

    python benches/compare_pinocchio.py            # full table
    python benches/compare_pinocchio.py --quick    # fewer repeats

Models are docs/benchmarks.md's: chainN (revolute, axes alternating y, z; 0.3 m links; 1 kg, COM
(0.15, 0, 0), inertia diag(1e-3, 7.5e-3, 7.5e-3)), q = 0.3 rad, v = 0, gravity (0, 0, -9.81).
Ratios are measured in one run: this machine is shared and noisy, so compare ratios, not µs.
"""

from __future__ import annotations

import argparse
import platform
import time
import timeit

import numpy as np
import pinocchio as pin
import pointmass_dyn as pmd
from scipy.integrate import solve_ivp

G = np.array([0.0, 0.0, -9.81])
INERTIA = np.diag([1e-3, 7.5e-3, 7.5e-3])
COM = np.array([0.15, 0.0, 0.0])


def chain_ours(n: int) -> pmd.Model:
    model = pmd.Model()
    body = pmd.RigidBody(1.0, COM, INERTIA)
    parent = -1
    for k in range(n):
        axis = (0, 1, 0) if k % 2 == 0 else (0, 0, 1)
        t = (0, 0, 0) if k == 0 else (0.3, 0, 0)
        parent = model.add_body(body, pmd.Revolute(axis), parent=parent, translation=t)
    return model


def chain_pin(n: int) -> pin.Model:
    model = pin.Model()
    parent = 0
    for k in range(n):
        joint = pin.JointModelRY() if k % 2 == 0 else pin.JointModelRZ()
        t = np.zeros(3) if k == 0 else np.array([0.3, 0, 0])
        parent = model.addJoint(parent, joint, pin.SE3(np.eye(3), t), f"j{k}")
        model.appendBodyToJoint(parent, pin.Inertia(1.0, COM, INERTIA), pin.SE3.Identity())
    model.gravity.linear = G
    return model


def best_us(fn, number: int, repeat: int) -> float:
    return min(timeit.repeat(fn, number=number, repeat=repeat)) / number * 1e6


# pinocchio.Model.createData() for a 1000-joint chain needs more than 8 GB (it sizes many
# nv x nv buffers); above this size only our side is timed.
PIN_MAX_JOINTS = 300


def per_call_table(sizes, repeat):
    rows = []
    rng = np.random.default_rng(0)
    for n in sizes:
        ours = chain_ours(n)
        q = np.full(n, 0.3)
        v = rng.uniform(-1, 1, n)
        tau = rng.uniform(-1, 1, n)
        a = rng.uniform(-1, 1, n)
        number = max(20, 20000 // n)
        if n > PIN_MAX_JOINTS:
            for name, f in {
                "forward dynamics": lambda: ours.forward_dynamics(q, v, tau, gravity=G),
                "inverse dynamics": lambda: ours.inverse_dynamics(q, v, a, gravity=G),
                "mass matrix": lambda: ours.mass_matrix(q),
            }.items():
                rows.append((f"chain{n}", name, best_us(f, number, repeat), float("nan"), float("nan")))
            continue
        pm = chain_pin(n)
        data = pm.createData()
        # Same numbers first: a timing of different answers is worthless.
        fd = ours.forward_dynamics(q, v, tau, gravity=G)
        assert np.allclose(fd, pin.aba(pm, data, q, v, tau), rtol=1e-9, atol=1e-9)
        pairs = {
            "forward dynamics": (lambda: ours.forward_dynamics(q, v, tau, gravity=G),
                                 lambda: pin.aba(pm, data, q, v, tau)),
            "inverse dynamics": (lambda: ours.inverse_dynamics(q, v, a, gravity=G),
                                 lambda: pin.rnea(pm, data, q, v, a)),
            "mass matrix": (lambda: ours.mass_matrix(q),
                            lambda: pin.crba(pm, data, q)),
        }
        for name, (f_ours, f_pin) in pairs.items():
            t_ours = best_us(f_ours, number, repeat)
            t_pin = best_us(f_pin, number, repeat)
            rows.append((f"chain{n}", name, t_ours, t_pin, t_pin / t_ours))
    return rows


def simulate_table(tols, repeat):
    rows = []
    scene = pmd.load_scene("chain7")
    pm = chain_pin(7)
    data = pm.createData()
    nq = 7
    y0 = np.concatenate([scene.q0, scene.v0])

    def rhs(t, y):
        return np.concatenate([y[nq:], pin.aba(pm, data, y[:nq], y[nq:], np.zeros(nq))])

    for tol in tols:
        atol = tol * 1e-3
        t_ours = min(timeit.repeat(lambda: pmd.simulate(scene, (0, 10), rtol=tol, atol=atol),
                                   number=1, repeat=repeat))
        reps = 1 if tol < 1e-8 else max(1, repeat // 2)
        start = time.perf_counter()
        for _ in range(reps):
            ref = solve_ivp(rhs, (0, 10), y0, method="RK45", rtol=tol, atol=atol)
        t_scipy = (time.perf_counter() - start) / reps
        ours = pmd.simulate(scene, (0, 10), rtol=tol, atol=atol)
        rows.append((tol, t_ours * 1e3, t_scipy * 1e3, t_scipy / t_ours, ours.nfev, ref.nfev))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    repeat = 3 if args.quick else 7
    print(f"# {platform.processor() or platform.machine()}, Python {platform.python_version()}, "
          f"pin {pin.__version__}, pointmass_dyn {pmd.__version__}")
    print("\n## Per Python call (best of repeats, µs)\n")
    print("| model | function | pointmass_dyn | pinocchio | speed-up |")
    print("|---|---|---:|---:|---:|")
    for name, fn, a, b, r in per_call_table([7, 30, 100, 300, 1000], repeat):
        print(f"| {name} | {fn} | {a:.2f} | {b:.2f} | {r:.2f}× |")
    print("\n## chain7, 10 s: simulate() vs SciPy solve_ivp(RK45) + pinocchio.aba (ms)\n")
    print("| rtol | simulate | SciPy+aba | speed-up | nfev ours | nfev SciPy |")
    print("|---:|---:|---:|---:|---:|---:|")
    for tol, a, b, r, n1, n2 in simulate_table([1e-3, 1e-6, 1e-9, 1e-12], repeat):
        print(f"| {tol:.0e} | {a:.2f} | {b:.1f} | {r:.0f}× | {n1} | {n2} |")


if __name__ == "__main__":
    main()
