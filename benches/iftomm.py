"""The IFToMM multibody benchmark problems A01-A05 (docs/mechanisms.md): per problem and
method, the benchmark's error measure (largest error over the output steps, relative where the
reference is >= 1e-3, absolute below), energy error, constraint residual, steps and wall time.
References as in tests/test_iftomm.py (closed forms, exact reductions, the published Andrews
values); A05 has no closed form: its reference is our own DOP853 run at rtol 1e-12, so its
error column measures convergence only.

    python benches/iftomm.py [--quick] [--only A02,A04]
    python benches/iftomm.py --opensim    # the settings OpenSim's pages report times for
    python benches/iftomm.py --shuffled   # A02 with other numberings of its bodies

A02 (N = 40) runs DOP853 only, over a range of tolerances (the error must fall as the
tolerance tightens); RK45 and Radau take minutes there.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
from scipy.integrate import solve_ivp
from scipy.special import ellipj

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import andrews as andrews_ref

G = 9.81
#: Times the benchmark pages report for another code (OpenSim 3.2, i5-4570; the OpenSim
#: implementation's pages, RehabEngGroup/MBSbenchmarksInOpenSim).
OPENSIM = {"A04": "0.258 s"}
#: OpenSim's pages time shorter or smaller runs than the spec's for A01 and A02 (10 s of the
#: pendulum, N = 2 over 10 s): `--opensim` times ours on those settings.
OPENSIM_RUNS = {"A01": (10.0, None, "0.637 s"), "A02": (10.0, 2, "0.455 s"),
                "A04": (10.0, None, "0.258 s")}


def measure(x, ref):
    x, ref = np.asarray(x), np.asarray(ref)
    return float(np.max(np.abs(x - ref) / np.maximum(np.abs(ref), 1e-3)))


def a01():
    sc = pmd.load_scene("iftomm_a01_pendulum")
    t = np.linspace(0, 2000, 4001)
    _, cn, dn, _ = ellipj(np.sqrt(G) * t, 0.5)
    a = 2 * np.arcsin(np.sqrt(0.5) * cn / dn)
    ref = np.stack([np.sin(a), -np.cos(a)], 1)

    def out(q):
        return np.stack([np.cos(q[:, 0]), np.sin(q[:, 0])], 1)

    return sc, t, out, ref


def a02():
    sc = pmd.load_scene("iftomm_a02_nfourbar")
    n = 40
    c = G * ((n + 1) / 2 + n) / ((n + 1) / 3 + n)
    t = np.linspace(0, 20, 401)
    r = solve_ivp(lambda _, y: [y[1], -c * np.cos(y[0])], (0, 20), [np.pi / 2, -1.0],
                  t_eval=t, rtol=1e-13, atol=1e-13, method="DOP853")
    ref = np.stack([np.cos(r.y[0]), np.sin(r.y[0])], 1)

    def out(q):
        return np.stack([np.cos(q[:, 0]), np.sin(q[:, 0])], 1)

    return sc, t, out, ref


def a02_reduction_error(rtol, atol):
    """SciPy's DOP853 on the exact one-degree-of-freedom reduction at the run's tolerances,
    on the same measure: what the integrator alone gives (docs/mechanisms.md §2)."""
    n = 40
    c = G * ((n + 1) / 2 + n) / ((n + 1) / 3 + n)
    t = np.linspace(0, 20, 401)

    def phi(rt, at):
        return solve_ivp(lambda _, y: [y[1], -c * np.cos(y[0])], (0, 20), [np.pi / 2, -1.0],
                         t_eval=t, rtol=rt, atol=at, method="DOP853").y[0]

    ref, x = phi(1e-13, 1e-13), phi(rtol, atol)
    return measure(np.stack([np.cos(x), np.sin(x)], 1), np.stack([np.cos(ref), np.sin(ref)], 1))


def a03():
    sc = pmd.load_scene("andrews")
    t = np.array([0.0, andrews_ref.T_END])
    inv = np.argsort(np.array([0, 1, 2, 4, 3, 6, 5]))
    ref = np.vstack([andrews_ref.Q0, andrews_ref.Q_END])

    def out(q):
        return q[:, inv]

    return sc, t, out, ref


def a04():
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from test_iftomm import bricard_reduction

    sc = pmd.load_scene("iftomm_a04_bricard")
    m = sc.model
    t = np.linspace(0, 10, 201)
    qref = bricard_reduction(m, sc.q0, t)

    def out(q):
        return np.array([m.placements(x)[1][2] for x in q])

    return sc, t, out, out(qref)


def a05():
    sc = pmd.load_scene("iftomm_a05_governor")
    t = np.linspace(0, 10, 201)
    r = pmd.simulate(sc, (0, 10), t_eval=t, method="DOP853", rtol=1e-12, atol=1e-14)
    ref = np.asarray(r.q)[:, 1:2]

    def out(q):
        return q[:, 1:2]

    return sc, t, out, ref


PROBLEMS = {"A01": a01, "A02": a02, "A03": a03, "A04": a04, "A05": a05}
RUNS = [("RK45", 1e-8), ("DOP853", 1e-8), ("DOP853", 1e-10), ("Radau", 1e-8), ("auto", 1e-8)]
RUNS_A02 = [("DOP853", 1e-6), ("DOP853", 1e-8), ("DOP853", 1e-9), ("DOP853", 1e-10), ("DOP853", 1e-11),
            ("DOP853", 1e-12)]


def run(name, method, rtol, setup, budget=60.0):
    sc, t, out, ref = setup
    t0 = time.perf_counter()
    res = pmd.simulate(sc, (t[0], t[-1]), t_eval=t, method=method, rtol=rtol, atol=rtol * 1e-2,
                       energy=True, max_steps=2_000_000)
    wall = time.perf_counter() - t0
    q = np.asarray(res.q)
    err = measure(out(q), ref) if res.success and len(q) == len(t) else float("nan")
    e = np.asarray(res.energy)
    de = float(np.abs(e - e[0]).max() / max(np.abs(e).max(), 1.0))
    resid = float(np.max(res.constraint_residual)) if res.constraint_residual is not None else 0.0
    return err, de, resid, res.n_accepted, res.nfev, wall, res.success


def opensim_setups():
    """A01 over 10 s, A02 with N = 2 over 10 s (B0 at +1 m/s, the exact reduction as the
    reference) and A04: the runs OpenSim's pages time."""
    from test_iftomm import n_fourbar, n_fourbar_rate, parallel_state

    sc, t, out, ref = a01()
    keep = t <= OPENSIM_RUNS["A01"][0]
    yield "A01", (sc, t[keep], out, ref[keep])
    t_end, n = OPENSIM_RUNS["A02"][:2]
    c = n_fourbar_rate(n)
    q0, v0 = parallel_state(n, np.pi / 2, -1.0)
    scene = pmd.Scene(n_fourbar(n), q0, v0, effects=[pmd.Effect.gravity([0, -G, 0])])
    t = np.linspace(0, t_end, 201)
    r = solve_ivp(lambda _, y: [y[1], -c * np.cos(y[0])], (0, t_end), [np.pi / 2, -1.0],
                  t_eval=t, rtol=1e-13, atol=1e-13, method="DOP853")

    def out2(q):
        return np.stack([np.cos(q[:, 0]), np.sin(q[:, 0])], 1)

    yield "A02", (scene, t, out2, out2(r.y[0][:, None]))
    yield "A04", a04()


def opensim_table():
    """Ours (best of 3, CPU) on the settings OpenSim 3.2's pages report times for."""
    print("| problem | setting | method | rtol | error (spec measure) | steps | CPU (best of 3) "
          "| OpenSim 3.2 (i5-4570) |")
    print("|---|---|---|---|---|---|---|---|")
    for name, setup in opensim_setups():
        t_end, n, theirs = OPENSIM_RUNS[name]
        setting = f"{t_end:g} s" + (f", N = {n}" if n else "")
        for method, rtol in [("DOP853", 1e-10), ("auto", 1e-8)]:
            cpu = []
            for _ in range(3):
                c0 = time.process_time()
                err, _, _, steps, _, _, ok = run(name, method, rtol, setup)
                cpu.append(time.process_time() - c0)
            status = "" if ok else " (failed)"
            print(f"| {name} | {setting} | {method} | {rtol:.0e} | {err:.1e}{status} | {steps} | "
                  f"{min(cpu) * 1e3:.1f} ms | {theirs} |", flush=True)


def shuffled_table(seeds=3, repeats=2):
    """A02 (N = 40) with its bodies numbered otherwise than the bundled scene's interleaved
    v0, h0, v1, ...: every vertical bar first, and random orders (each h_k after its v_k, the
    loops shuffled too). The banded solver orders the coordinates itself (docs/loops.md §3):
    CPU time (best of `repeats`) and its ratio to the bundled scene's, DOP853 rtol 1e-10, the
    benchmark's error (against the exact reduction) and the largest difference of v0's angle
    from the bundled run's."""
    from test_loops_ordering import n_fourbar, rods_first, shuffled

    n, rtol = 40, 1e-10
    _, t, out, ref = a02()
    cases = [("bundled (interleaved)", None), ("rods first", (rods_first(n), list(range(n))))]
    cases += [(f"shuffled (seed {s})", shuffled(n, s)) for s in range(seeds)]
    print("| numbering | profile (model's own) | nfev | CPU | per evaluation | ratio | "
          "error (spec measure) | max abs diff of v0's angle |")
    print("|---|---|---|---|---|---|---|---|")
    base_cpu = base_q = None
    for label, numbering in cases:
        if numbering is None:
            scene, v0_index = pmd.load_scene("iftomm_a02_nfourbar"), 0
            m = scene.model
        else:
            bodies, loops = numbering
            m = n_fourbar(n, bodies, loops)
            q0 = [np.pi / 2 if b[0] == "v" else -np.pi / 2 for b in bodies]
            v0 = [-1.0 if b[0] == "v" else 1.0 for b in bodies]
            scene = pmd.Scene(m, q0, v0, effects=[pmd.Effect.gravity([0, -G, 0])])
            v0_index = bodies.index("v0")
        cpu = []
        for _ in range(repeats):
            c0 = time.process_time()
            res = pmd.simulate(scene, (0, 20), t_eval=t, method="DOP853", rtol=rtol,
                               atol=rtol * 1e-2, max_steps=2_000_000)
            cpu.append(time.process_time() - c0)
        q = np.asarray(res.q)[:, v0_index]
        best = min(cpu)
        if base_cpu is None:
            base_cpu, base_q = best, q
        info = m.loop_solver_info()
        print(f"| {label} | {info['profile']} ({info['model_profile']}) | {res.nfev} | "
              f"{best:.2f} s | {best / res.nfev * 1e6:.0f} µs | {best / base_cpu:.2f} | "
              f"{measure(out(q[:, None]), ref):.1e} | {np.abs(q - base_q).max():.1e} |",
              flush=True)


def main():
    if "--opensim" in sys.argv:
        return opensim_table()
    if "--shuffled" in sys.argv:
        return shuffled_table()
    quick = "--quick" in sys.argv
    only = None
    if "--only" in sys.argv:
        only = sys.argv[sys.argv.index("--only") + 1].split(",")
    print("| problem | method | rtol | error (spec measure) | energy error (rel.) | "
          "constraint residual | steps | nfev | wall time | other codes |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, make in PROBLEMS.items():
        if only is not None and name not in only:
            continue
        setup = make()
        for method, rtol in RUNS_A02 if name == "A02" else RUNS:
            if quick and (method != "DOP853" or rtol < 1e-10):
                continue
            err, de, resid, steps, nfev, wall, ok = run(name, method, rtol, setup)
            note = OPENSIM.get(name, "")
            if name == "A02":
                note = f"reduction, SciPy DOP853: {a02_reduction_error(rtol, rtol * 1e-2):.1e}"
            status = "" if ok else " (failed)"
            print(f"| {name} | {method} | {rtol:.0e} | {err:.1e}{status} | {de:.1e} | "
                  f"{resid:.1e} | {steps} | {nfev} | {wall * 1e3:.0f} ms | {note} |", flush=True)


if __name__ == "__main__":
    main()
