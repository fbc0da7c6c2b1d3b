"""Solo12 standing (the bundled ``solo12_standing`` scene: dropped from 3 cm onto the ground,
PD to its standing posture), 2 s: our Radau / auto with the analytic Jacobian against RK45, and
MuJoCo's own simulation of the same robot (``pmd.to_mjcf`` of the model, plus a floor, a small
sphere at each foot and position actuators with the same gains) at several time steps.

    python benches/contact.py            # best of 3 per row
    python benches/contact.py --quick    # best of 1, fewer rows

Each simulator is measured against its own converged solution (ours: Radau at rtol 1e-10;
MuJoCo: its step at 1e-5 s), since the two contact models differ (ours: Hunt–Crossley
penalty; MuJoCo: soft constraints): error = max |q(t) − q_ref(t)| over the coordinates (base
position in m, orientation quaternion, joint angles in rad) and the times t = 0.05, 0.1, 0.2,
0.5, 1 and 2 s (the landing at about 0.08 s, the settling, the rest). Times: the wall clock
of the whole 2 s run on one thread, and the process's CPU time for it (steadier than the wall
clock on a loaded machine: what the run costs when it has a core to itself), each the best of
the repeats. Ratios from one run on a shared machine: compare ratios.
"""

from __future__ import annotations

import argparse
import re
import sys
import time

import numpy as np
import pointmass_dyn as pmd

FOOT_RADIUS = 0.005  # MuJoCo's foot spheres; ours are points at the foot origins
TIMES = [0.05, 0.1, 0.2, 0.5, 1.0, 2.0]


def best_of(n: int, f):
    """``((wall, cpu), f())``: the best wall-clock and CPU seconds of ``n`` calls."""
    out, wall, cpu = None, np.inf, np.inf
    for _ in range(n):
        t0, c0 = time.perf_counter(), time.process_time()
        out = f()
        wall = min(wall, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    return (wall, cpu), out


def ours(scene, reps: int, quick: bool) -> list[tuple]:
    ref = pmd.simulate(scene, method="Radau", rtol=1e-10, atol=1e-12, t_eval=TIMES)
    q_ref = ref.raise_for_status().q
    rows = []
    cases = [("Radau", 1e-4), ("Radau", 1e-6), ("Radau", 1e-8), ("auto", 1e-6)]
    if not quick:
        cases.append(("RK45", 1e-6))
    for method, rtol in cases:
        sec, res = best_of(reps, lambda: pmd.simulate(scene, method=method, rtol=rtol,
                                                      atol=rtol * 1e-2, t_eval=TIMES))
        res.raise_for_status()
        err = np.abs(res.q - q_ref).max()
        rows.append((f"ours {method} rtol {rtol:g}", sec, err, res.nfev, res.njev))
    return rows


def mujoco_xml(scene) -> str:
    """The scene's robot in MJCF with MuJoCo's contact on and the scene's PD as actuators."""
    model = scene.model
    xml = pmd.to_mjcf(model, gravity=[0, 0, -9.81], integrator="implicitfast")
    xml = xml.replace('    <flag contact="disable"/>\n', "")
    xml = xml.replace("  <worldbody>\n", '  <worldbody>\n    <geom name="floor" type="plane" '
                      'size="5 5 0.1" friction="1 0.005 0.0001"/>\n', 1)
    for foot in ("FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"):
        xml = re.sub(rf'(<body name="{foot}"[^>]*>\n)',
                     rf'\1        <geom type="sphere" size="{FOOT_RADIUS}" friction="1 0.005 '
                     r'0.0001"/>' + "\n", xml, count=1)
    joints = re.findall(r'<joint name="(j_[A-Z]{2}_[A-Z_]+)" type="hinge"', xml)
    acts = "".join(f'    <position joint="{j}" kp="5" kv="0.1"/>\n' for j in joints)
    return xml.replace("</mujoco>", f"  <actuator>\n{acts}  </actuator>\n</mujoco>")


def mujoco_rows(scene, reps: int, quick: bool) -> list[tuple]:
    try:
        import mujoco
    except ImportError:
        print("(MuJoCo not installed: its rows are skipped; pip install mujoco)")
        return []
    xml = mujoco_xml(scene)
    qpos0, qvel0 = pmd.io.to_mujoco_state(scene.model, scene.q0, scene.v0)
    posture = np.asarray(scene.q0)[7:]

    def run(dt: float):
        m = mujoco.MjModel.from_xml_string(xml)
        m.opt.timestep = dt
        d = mujoco.MjData(m)
        d.qpos[:], d.qvel[:] = qpos0, qvel0
        d.qpos[2] += FOOT_RADIUS  # the spheres' bottoms where our points are
        d.ctrl[:] = posture
        out, done = [], 0
        for t in TIMES:
            for _ in range(int(round(t / dt)) - done):
                mujoco.mj_step(m, d)
            done = int(round(t / dt))
            out.append(d.qpos.copy())
        return np.array(out)

    q_ref = run(1e-5)
    rows = []
    for dt in ([2e-3, 1e-3] if quick else [2e-3, 1e-3, 5e-4, 2e-4]):
        sec, q = best_of(reps, lambda: run(dt))
        rows.append((f"MuJoCo implicitfast dt {dt:g}", sec, np.abs(q - q_ref).max(),
                     int(round(2.0 / dt)), 0))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    reps = 1 if args.quick else 3
    scene = pmd.load_scene("solo12_standing")
    rows = ours(scene, reps, args.quick) + mujoco_rows(scene, reps, args.quick)
    print(f"{'run':34s} {'wall (ms)':>10s} {'cpu (ms)':>10s} {'error':>10s} {'rhs/steps':>10s} "
          f"{'jac':>5s}")
    for name, (wall, cpu), err, n, nj in rows:
        print(f"{name:34s} {wall * 1e3:10.2f} {cpu * 1e3:10.2f} {err:10.2e} {n:10d} {nj:5d}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
