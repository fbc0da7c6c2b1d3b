"""`Simulator.step` per call against MuJoCo's `mj_step` called from Python, chain7 at a fixed
step (RK4, 1 ms), one process, side by side. Run: python benches/control.py"""

from __future__ import annotations

import time

import mujoco
import numpy as np
import pointmass_dyn as pmd


def per_call(fn, n):
    fn()
    t0 = time.perf_counter()
    for _ in range(n):
        fn()
    return (time.perf_counter() - t0) / n


def main(n: int = 20000) -> None:
    scene = pmd.load_scene("chain7")
    sim = pmd.Simulator(scene, method="RK4", dt=1e-3, control_period=1e-3, record=False)
    u = np.zeros(scene.model.nv)
    ours = per_call(lambda: sim.step(), n)
    ours_u = per_call(lambda: sim.step(control=u), n)
    m = mujoco.MjModel.from_xml_string(pmd.to_mjcf(scene))
    m.opt.timestep = 1e-3
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    d = mujoco.MjData(m)
    mj = per_call(lambda: mujoco.mj_step(m, d), n)

    def mj_ctrl():
        d.qfrc_applied[:] = u
        mujoco.mj_step(m, d)

    mj_u = per_call(mj_ctrl, n)
    print(f"chain7, RK4 at 1 ms, per call ({n} calls):")
    print(f"  Simulator.step()            {ours * 1e6:7.2f} us")
    print(f"  Simulator.step(control=u)   {ours_u * 1e6:7.2f} us")
    print(f"  mujoco.mj_step              {mj * 1e6:7.2f} us")
    print(f"  qfrc_applied[:] = u; mj_step {mj_u * 1e6:7.2f} us")


if __name__ == "__main__":
    main()
