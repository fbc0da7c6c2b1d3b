"""One-run side-by-side of batch throughput: our simulate_batch against MuJoCo's rollout on
chain7 (docs/benchmarks.md), at equal error.

    pip install mujoco                     # optional peer, not a dependency of pointmass_dyn
    python benches/mujoco_rollout.py       # B = 64 runs over 10 s, best of 3
    python benches/mujoco_rollout.py --quick

The MJCF is built from the loaded chain7 scene (hinges with the same axes and placements,
<inertial> mass / COM / diaginertia, no damping, armature or limits, contact disabled) and is
checked first: MuJoCo's mj_forward qacc must equal our forward_dynamics to ~1e-10 relative at
random states, or the script aborts.

Error = max over runs of |q(t) - q_ref(t)|_inf at t = 1, 2, 5, 10 s, the reference being our
simulate_batch at rtol 1e-12, atol 1e-14 (its own floor is printed: against rtol 1e-11).
chain7 is chaotic: from 0.05 rad perturbations, errors grow by orders of magnitude per second,
and at 10 s even the reference is not converged (rtol 1e-11 against 1e-12 differ by O(1) rad:
the floor line), so the 10 s column is saturated and says nothing about accuracy. The
equal-error ratio is therefore given at 2 s and 5 s (reference floor ~1e-11 and ~1e-8), and at
10 s only for completeness. Time = wall clock, best of 3, the same thread count
for both (MuJoCo: one MjData per thread). Ratios from one run on a shared machine: compare
ratios, not absolute runs/s.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
import pointmass_dyn as pmd

try:
    import mujoco
    import mujoco.rollout
except ImportError:
    sys.exit("benches/mujoco_rollout.py needs MuJoCo (an optional peer, not a dependency of "
             "pointmass_dyn): pip install mujoco")

T_END = 10.0
HORIZONS = [1.0, 2.0, 5.0, 10.0]   # errors at each; 10 s is the brief's, the others unsaturated
G = np.array([0.0, 0.0, -9.81])


def mjcf_from_scene(scene, timestep: float, integrator: str = "RK4") -> str:
    """MJCF of a revolute chain scene, from the scene's own bodies."""
    bodies = model_bodies(scene)
    xml = [f'<mujoco model="{scene.name}">',
           f'  <option gravity="{G[0]} {G[1]} {G[2]}" integrator="{integrator}" '
           f'timestep="{timestep!r}">',
           '    <flag contact="disable"/>',
           '  </option>',
           '  <worldbody>']
    depth = 0
    for b in bodies:
        pad = "  " * (2 + depth)
        xml.append(f'{pad}<body name="{b["name"]}" pos="{fmt(b["translation"])}">')
        xml.append(f'{pad}  <joint name="j_{b["name"]}" type="hinge" axis="{fmt(b["axis"])}"/>')
        xml.append(f'{pad}  <inertial mass="{b["mass"]!r}" pos="{fmt(b["com"])}" '
                   f'diaginertia="{fmt(b["inertia_diag"])}"/>')
        depth += 1
    for d in reversed(range(depth)):
        xml.append("  " * (2 + d) + "</body>")
    xml += ['  </worldbody>', '</mujoco>']
    return "\n".join(xml)


def fmt(v) -> str:
    return " ".join(repr(float(x)) for x in v)


def model_bodies(scene):
    """chain7's bodies from its TOML (a serial chain: each body's parent is the previous)."""
    from importlib import resources

    import tomllib
    path = resources.files("pointmass_dyn") / "scenes" / f"{scene.name}.toml"
    spec = tomllib.loads(path.read_text())
    bodies = []
    prev = "world"
    for b in spec["body"]:
        assert b["parent"] == prev and b["joint"]["type"] == "Revolute", "serial revolute chain only"
        bodies.append(dict(name=b["name"], translation=b["translation"], axis=b["joint"]["axis"],
                           mass=b["mass"], com=b["com"], inertia_diag=b["inertia_diag"]))
        prev = b["name"]
    return bodies


def check_conversion(scene, mj_model, rng, n=5):
    d = mujoco.MjData(mj_model)
    worst = 0.0
    for _ in range(n):
        q = rng.uniform(-np.pi, np.pi, scene.model.nq)
        v = rng.uniform(-3, 3, scene.model.nv)
        d.qpos[:] = q
        d.qvel[:] = v
        mujoco.mj_forward(mj_model, d)
        ours = np.asarray(scene.model.forward_dynamics(q, v, np.zeros(scene.model.nv), gravity=G))
        rel = np.max(np.abs(d.qacc - ours)) / np.max(np.abs(ours))
        worst = max(worst, rel)
    print(f"conversion check: max |qacc_mujoco - qacc_ours| / max|qacc_ours| over {n} random "
          f"states = {worst:.2e}")
    if not worst < 1e-9:
        sys.exit("MJCF conversion does not match forward_dynamics: aborting")


def best_of(fn, repeat):
    times = []
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="1 repeat, fewer settings")
    ap.add_argument("--runs", type=int, default=64)
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    args = ap.parse_args()
    repeat = 1 if args.quick else 3
    B, threads = args.runs, args.threads

    scene = pmd.load_scene("chain7")
    nq, nv = scene.model.nq, scene.model.nv
    rng = np.random.default_rng(0)
    print(f"mujoco {mujoco.__version__}, pointmass_dyn {getattr(pmd, '__version__', '?')}, "
          f"B = {B} runs of chain7 over {T_END} s, {threads} threads, best of {repeat}")

    check_conversion(scene, mujoco.MjModel.from_xml_string(mjcf_from_scene(scene, 1e-3)), rng)

    Q0 = scene.q0 + 0.05 * rng.standard_normal((B, nq))
    V0 = np.zeros((B, nv)) + 0.05 * rng.standard_normal((B, nv))

    def ours(rtol, atol):
        res = pmd.simulate_batch(scene, (0.0, T_END), q0=Q0, v0=V0, t_eval=HORIZONS,
                                 rtol=rtol, atol=atol, threads=threads)
        assert np.all(res.success)
        return np.asarray(res.q)           # (B, len(HORIZONS), nq)

    t_ref, q_ref = best_of(lambda: ours(1e-12, 1e-14), 1)
    print(f"reference: simulate_batch rtol 1e-12 atol 1e-14, {B / t_ref:.1f} runs/s")

    rows = []  # (method, setting, error, runs/s)

    def err(q):
        return np.max(np.abs(q - q_ref), axis=(0, 2))     # per horizon

    floor = err(ours(1e-11, 1e-13))
    print("reference floor (rtol 1e-11 against 1e-12): "
          + ", ".join(f"{e:.1e} at {h:g} s" for h, e in zip(HORIZONS, floor)))

    tols = [(1e-4, 1e-7), (1e-6, 1e-9), (1e-8, 1e-11)]
    if args.quick:
        tols = [(1e-6, 1e-9)]
    for rtol, atol in tols:
        t, q = best_of(lambda: ours(rtol, atol), repeat)
        rows.append(("ours simulate_batch", f"rtol {rtol:.0e} atol {atol:.0e}", err(q), B / t))

    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    i_qpos = mujoco.mj_stateSize(mujoco.MjModel.from_xml_string(mjcf_from_scene(scene, 1e-3)),
                                 mujoco.mjtState.mjSTATE_TIME)

    def mj(integrator, dt):
        m = mujoco.MjModel.from_xml_string(mjcf_from_scene(scene, dt, integrator))
        nstep = int(round(T_END / dt))
        datas = [mujoco.MjData(m) for _ in range(threads)]
        d = datas[0]
        x0 = np.empty((B, mujoco.mj_stateSize(m, spec)))
        for k in range(B):
            mujoco.mj_resetData(m, d)
            d.qpos[:] = Q0[k]
            d.qvel[:] = V0[k]
            mujoco.mj_getState(m, d, x0[k], spec)
        state = np.empty((B, nstep, x0.shape[1]))   # allocated once, outside the timing
        idx = [int(round(h / dt)) - 1 for h in HORIZONS]   # state[:, k] is after step k+1

        def run():
            mujoco.rollout.rollout(m, datas, x0, nstep=nstep, state=state)
            return state[:, idx, i_qpos:i_qpos + nq].copy()
        t, q = best_of(run, repeat)
        assert abs(state[0, -1, 0] - T_END) < 1e-9 * T_END, state[0, -1, 0]
        return t, q

    rk4_dts = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4]
    if args.quick:
        rk4_dts = [5e-3, 1e-3]
    for dt in rk4_dts:
        t, q = mj("RK4", dt)
        rows.append(("mujoco rollout", f"RK4 dt {dt:g}", err(q), B / t))
    for integ, dt in [("Euler", 1e-3), ("implicitfast", 1e-3)] if not args.quick else []:
        t, q = mj(integ, dt)
        rows.append(("mujoco rollout", f"{integ} dt {dt:g}", err(q), B / t))

    print()
    head = "".join(f"{f'err {h:g}s':>11}" for h in HORIZONS)
    print(f"{'method':<22}{'setting':<28}{head}{'runs/s':>10}")
    for method, setting, e, rate in rows:
        errs = "".join(f"{x:>11.1e}" for x in e)
        print(f"{method:<22}{setting:<28}{errs}{rate:>10.1f}")

    rk4 = [r for r in rows if r[1].startswith("RK4")]
    for h in (2.0, 5.0, T_END):
        j = HORIZONS.index(h)
        print(f"\nequal error at {h:g} s: ours against the MuJoCo RK4 timestep whose error is "
              f"nearest (log scale)"
              + (" -- SATURATED: the reference itself is not converged at 10 s" if h == T_END
                 else ""))
        for method, setting, e, rate in rows:
            if not method.startswith("ours"):
                continue
            near = min(rk4, key=lambda r: abs(np.log10(max(r[2][j], 1e-300))
                                              - np.log10(max(e[j], 1e-300))))
            print(f"  ours {setting} (err {e[j]:.1e}, {rate:.1f} runs/s) vs MuJoCo {near[1]} "
                  f"(err {near[2][j]:.1e}, {near[3]:.1f} runs/s): ours {rate / near[3]:.2f}x")


if __name__ == "__main__":
    main()
