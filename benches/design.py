"""Design benchmarks (docs/design.md, issue 30's targets): the bundled four-bar at 30 rad/s,
360 samples, crank, coupler and rocker as steel cells of 5 mm (~300 per link).

    python benches/design.py            # all cases, one line each
    python benches/design.py --quick    # fewer repeats
    python benches/design.py --strength # only the strength-limited case (issue 39)
    python benches/design.py --connected  # only issue 39's target: connected, realised links

Each line: the case, wall time of the whole `pmd.balance` call (maps, solve(s), re-analysis)
median of the repeats, the solver's own time and iterations (summed over the programs
solved: both stages and, for peak designs, every cutting-plane round), its status and
relative gap.
"""

from __future__ import annotations

import statistics
import sys
import time

import numpy as np
import pointmass_dyn as pmd

QUICK = "--quick" in sys.argv
REPEATS = 1 if QUICK else 3
G = np.array([0.0, -9.81, 0.0])


def links(cell=0.005):
    box = lambda x0, x1, y: ([x0, -y, -0.006], [x1, y, 0.006])  # noqa: E731
    return [
        pmd.LinkShape("crank", box=box(-0.05, 0.045, 0.02), cell=cell),
        pmd.LinkShape("coupler", box=box(-0.01, 0.10, 0.01), cell=cell),
        pmd.LinkShape("rocker", box=box(-0.05, 0.08, 0.02), cell=cell),
    ]


def timed(fn):
    times, out = [], None
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def line(label, seconds, b):
    s = b.solver
    rounds = f", {s['rounds']} rounds" if "rounds" in s else ""
    print(
        f"{label:<46} {seconds:8.3f} s   solver {s['solve_time']:7.3f} s, {s['iterations']:3d} it{rounds}, "
        f"{s['status']}, gap {s['gap_rel']:.1e}"
    )


def connected():
    """Issue 39's target: four-bar, 3 links, ~1,750 cells, 360 samples, connected links, least
    peak bearing force with the peak shaking force at most 10 % (the whole call: maps, program
    with the connectivity flows, cutting-plane rounds, least mass, realisation and polish,
    both analyses) <= 5 s."""
    scene = pmd.load_scene("fourbar")
    motion = pmd.prescribed_motion(scene.model, "crank", speed=30.0, samples=360, q_guess=scene.q0, gravity=G)
    shapes = links(cell=0.0042)
    cells = [len(s.cells(scene.model)[0]) for s in shapes]
    peak_force = motion.summary()["shaking force"]["peak"]
    cpu = time.process_time()
    t, b = timed(lambda: pmd.balance(motion, links=shapes, objective={"bearing": 1.0}, norm="peak",
                                     limits={"force": 0.1 * peak_force}))
    cpu = (time.process_time() - cpu) / REPEATS  # the machine is shared: CPU time besides wall time
    line(f"connected, peak bearing ({sum(cells)} cells {cells})", t, b)
    print(f"{'':<46} CPU time of the call {cpu:.3f} s")
    r = b.realised
    print(f"{'':<46} realised: polish {r.polish['status']}, {r.polish['columns']} columns, deviation "
          f"force {100 * r.deviation['force']['relative']:.4f} %, bearing "
          f"{100 * r.deviation['bearing']['relative']:.4f} % of the predicted peaks")


def main():
    if "--connected" in sys.argv:
        return connected()
    scene = pmd.load_scene("fourbar")
    motion = pmd.prescribed_motion(scene.model, "crank", speed=30.0, samples=360, q_guess=scene.q0, gravity=G)
    cells = [len(s.cells(scene.model)[0]) for s in links()]
    print(f"four-bar, 360 samples, cells per link {cells}")
    peak_force = motion.summary()["shaking force"]["peak"]

    t, b = timed(lambda: pmd.balance(motion, links=links(), zero=("force",), objective={"mass": 1.0}))
    line("force balance by shape", t, b)
    t, b = timed(
        lambda: pmd.balance(
            motion, links=links(), objective={"bearing": 1.0}, norm="peak", limits={"force": 0.1 * peak_force}
        )
    )
    line("peak bearing, peak force <= 10 % (SOCP)", t, b)
    t0 = time.perf_counter()
    front = pmd.pareto_front(motion, ("force", "moment"), count=11, links=links())
    t = time.perf_counter() - t0
    print(f"{'11-point Pareto front force-moment (RMS)':<46} {t:8.3f} s   "
          f"({sum(f.solver['solve_time'] for f in front):.3f} s in the solver)")
    t0 = time.perf_counter()
    front = pmd.pareto_front(motion, ("bearing", "force"), count=11, links=links(), norm="peak")
    t = time.perf_counter() - t0
    print(f"{'11-point Pareto front bearing-force (peak)':<46} {t:8.3f} s   "
          f"({sum(f.solver['solve_time'] for f in front):.3f} s in the solver)")
    if "method" in pmd.pareto_front.__code__.co_varnames:  # the ε-constraint front (issue 30)
        t0 = time.perf_counter()
        front = pmd.pareto_front(motion, ("bearing", "force"), count=11, links=links(), norm="peak",
                                 method="epsilon")
        t = time.perf_counter() - t0
        print(f"{'11-point ε-constraint front bearing-force (peak)':<46} {t:8.3f} s   "
              f"({sum(f.solver['solve_time'] for f in front):.3f} s in the solver)")
    rings = [
        pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 1000),
        pmd.Counterweight.ring("rocker", [0, 0, 0], 0.02, 1000),
    ]
    t, b = timed(lambda: pmd.balance(motion, counterweights=rings, zero=("force",)))
    line("2 x 1000 counterweight candidates, zero force", t, b)
    t, b = timed(lambda: pmd.balance(motion, counterweights=rings, objective={"force": 1.0, "moment": 1.0}))
    line("2 x 1000 candidates, force + moment (RMS)", t, b)
    de_comparison(motion)


def strength_case():
    """Issue 39's target: strength-limited least peak bearing force of the four-bar, 360
    samples, crank, coupler and rocker as 12 mm steel plates of 4 mm cells with their webs
    (members strength-checked at every sample), at 300 rad/s where steel's safety factors are a
    few: every member at a safety factor of 2.85 at least (binding: the least-bearing design
    has 2.83 in the crank without it, 2.87 is the most any design reaches)."""
    scene = pmd.load_scene("fourbar")
    motion = pmd.prescribed_motion(scene.model, "crank", speed=300.0, samples=360, q_guess=scene.q0,
                                   gravity=G)
    steel = pmd.Material.steel()
    box = lambda x0, x1, y: ([x0, -y, -0.006], [x1, y, 0.006])  # noqa: E731
    plates = [
        pmd.LinkShape("crank", box=box(-0.05, 0.045, 0.02), cell=0.004, material=steel),
        pmd.LinkShape("coupler", box=box(-0.01, 0.10, 0.01), cell=0.004, material=steel),
        pmd.LinkShape("rocker", box=box(-0.05, 0.08, 0.02), cell=0.004, material=steel),
    ]
    cells = [len(p.cells(scene.model)[0]) for p in plates]
    t, b = timed(lambda: pmd.balance(motion, links=plates, objective={"bearing": 1.0}, norm="peak",
                                     limits={"safety": 2.85}))
    print(f"four-bar at 300 rad/s, 360 samples, cells per link {cells} ({sum(cells)})")
    line("peak bearing, safety >= 2.85 (SOCP)", t, b)
    t0, b0 = timed(lambda: pmd.balance(motion, links=plates, objective={"bearing": 1.0}, norm="peak"))
    line("the same without the safety limit", t0, b0)
    print("  least safety factors " + ", ".join(f"{n} {s.safety:.3f}" for n, s in b.strength.items()))


def de_comparison(motion):
    """SciPy's differential evolution on a small instance (2 rings of 4 candidates), each
    design scored from point_regressor's linear model."""
    from scipy.optimize import differential_evolution

    cws = [
        pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 4, max_mass=0.03),
        pmd.Counterweight.ring("rocker", [0, 0, 0], 0.02, 4, max_mass=0.03),
    ]
    pts = [(c.body, p) for c in cws for p in c.points]
    reg = motion.model.point_regressor(motion.q, motion.v, motion.a, points=pts, gravity=G)
    acc, pos = reg["accelerations"], reg["positions"]
    # Per unit mass at each point: its shaking force and moment (N, P, 3), flattened.
    per_force = -np.transpose(acc, (1, 0, 2)).reshape(len(pts), -1)
    per_moment = -np.transpose(np.cross(pos, acc), (1, 0, 2)).reshape(len(pts), -1)
    f0, m0 = motion.shaking.force, motion.shaking.moment
    for norm in ("rms", "peak"):
        def value(y, norm=norm):
            mag = np.linalg.norm(y, axis=1)
            return np.sqrt(np.mean(mag**2)) if norm == "rms" else mag.max()

        ref_f, ref_m = value(f0), value(m0)

        def score(x, norm=norm):
            f = f0 + (x @ per_force).reshape(f0.shape)
            m = m0 + (x @ per_moment).reshape(m0.shape)
            if norm == "rms":
                return (value(f) / ref_f) ** 2 + (value(m) / ref_m) ** 2
            return value(f) / ref_f + value(m) / ref_m

        t, b = timed(lambda: pmd.balance(motion, counterweights=cws, objective={"force": 1.0, "moment": 1.0}, norm=norm))
        t0 = time.perf_counter()
        de = differential_evolution(score, [(0.0, 0.03)] * len(pts), seed=3, tol=1e-12, maxiter=3000)
        t_de = time.perf_counter() - t0
        print(f"{'vs differential evolution (' + norm + ', 8 masses)':<46} conic {t:.3f} s (objective "
              f"{score(b.masses):.10g}), DE {t_de:.2f} s, {de.nfev} evaluations (objective {de.fun:.10g}): "
              f"{t_de / t:.0f}x")


if __name__ == "__main__":
    if "--strength" in sys.argv:
        strength_case()
    else:
        main()
        strength_case()
