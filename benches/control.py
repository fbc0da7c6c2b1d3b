"""Control loops beside MuJoCo, one process, side by side (benches/README.md):

1. `Simulator.step` per call against MuJoCo's `mj_step` called from Python, chain7 at a fixed
   step (RK4, 1 ms);
2. a 1 kHz Python PD loop on Panda: our adaptive methods against MuJoCo's RK4 (its sub-step
   per period varied) at equal error, both against one reference (our DOP853 at rtol 1e-12,
   checked against MuJoCo's RK4 at 20 µs first);
3. 1,000 steps of a vectorised environment of the Go2 quadruped on ground contact
   (`pmd.envs.VectorSceneEnv`, random torques) beside MuJoCo stepping Gymnasium's Ant model
   (`gymnasium/envs/mujoco/assets/ant.xml`, its frame_skip 5) directly: env steps per second;
4. `simulate_batch(controller=f)` of 8 chain7 runs under a Python PD at 1 kHz (RK45 rtol
   1e-8) on 1 and 2 threads: each run integrates with the GIL released while another's
   controller runs (the same bits either way);
5. `io.from_mujoco_state` per call on Panda.

Run: python benches/control.py [--quick]"""

from __future__ import annotations

import sys
import time
from pathlib import Path

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


def panda_pd_loop(quick: bool) -> None:
    from pointmass_dyn import io as mjcf

    scene = pmd.load_scene("panda")
    model = scene.model
    goal = np.array(scene.q0)
    start = goal + 0.2
    kp, kd, period = 100.0, 10.0, 1e-3
    n = 100 if quick else 300  # 0.1 / 0.3 s of the transient, 1 kHz

    def pd(q, v):
        return kp * (goal - q) - kd * v

    def ours(**opts):
        t0 = time.perf_counter()
        sim = pmd.Simulator(pmd.Scene(model, q0=start, effects=scene.effects), control_period=period,
                            record=False, **opts)
        for _ in range(n):
            sim.step(control=pd(sim.q, sim.v))
        return time.perf_counter() - t0, np.array(sim.q)

    m = mujoco.MjModel.from_xml_string(pmd.to_mjcf(scene))
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    # Our scene has no contact: MuJoCo's collision detection off too.
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT

    # Panda's MuJoCo state is ours coordinate for coordinate (checked here), so the loop reads
    # d.qpos / d.qvel directly (io.from_mujoco_state costs ~0.4 ms a call in Python).
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = np.arange(7.0), -np.arange(7.0)
    assert all(np.array_equal(a, b) for a, b in zip(mjcf.from_mujoco_state(model, d.qpos, d.qvel), (d.qpos, d.qvel)))

    def mj(sub):
        m.opt.timestep = period / sub
        d = mujoco.MjData(m)
        d.qpos[:], d.qvel[:] = mjcf.to_mujoco_state(model, start, np.zeros(model.nv))
        t0 = time.perf_counter()
        for _ in range(n):
            d.qfrc_applied[:] = pd(d.qpos, d.qvel)
            mujoco.mj_step(m, d, nstep=sub)
        return time.perf_counter() - t0, np.array(d.qpos)

    _, ref = ours(method="DOP853", rtol=1e-12, atol=1e-14)
    floor = float(np.abs(mj(50)[1] - ref).max())
    print(f"\nPanda, Python PD at 1 kHz for {n} ms, error = max |q(T) - q_ref(T)| (rad); "
          f"reference vs MuJoCo RK4 at 20 us: {floor:.1e}")
    rows_mj = []
    for sub in (1, 2, 4, 8, 16):
        t, q = min((mj(sub) for _ in range(2)), key=lambda r: r[0])
        rows_mj.append((float(np.abs(q - ref).max()), t))
        print(f"  MuJoCo RK4 {period / sub * 1e6:6.1f} us      error {rows_mj[-1][0]:.2e}   {t * 1e3:8.1f} ms")
    err_mj = np.log([r[0] for r in rows_mj])
    t_mj = np.log([r[1] for r in rows_mj])
    best = 0.0
    for method, tols in (("RK45", (1e-4, 1e-6, 1e-8)), ("DOP853", (1e-6, 1e-8, 1e-10))):
        for rtol in tols:
            t, q = min((ours(method=method, rtol=rtol, atol=rtol * 1e-2) for _ in range(2)), key=lambda r: r[0])
            e = float(np.abs(q - ref).max())
            # MuJoCo's time at this error: log-log interpolation along its sub-step curve
            # (errors fall as the sub-step shrinks), None outside the measured range.
            order = np.argsort(err_mj)
            inside = err_mj[order][0] <= np.log(e) <= err_mj[order][-1]
            tm = float(np.exp(np.interp(np.log(e), err_mj[order], t_mj[order]))) if inside else None
            ratio = f"MuJoCo at this error {tm * 1e3:8.1f} ms: {tm / t:5.1f}x" if tm else "outside MuJoCo's range"
            if tm:
                best = max(best, tm / t)
            print(f"  ours {method:6s} rtol {rtol:.0e}  error {e:.2e}   {t * 1e3:8.1f} ms   {ratio}")
    print(f"  best ratio at equal error: {best:.1f}x (target >= 3x)")


def quadruped_env(quick: bool) -> None:
    from pointmass_dyn.envs import SceneEnv, VectorSceneEnv

    urdf = pmd.robots.urdf_path("go2_description/urdf/go2.urdf")
    go2 = pmd.example_robot("go2_description/urdf/go2.urdf", root_joint="free")
    feet = pmd.urdf_contact_points(urdf, ["FL_foot", "FR_foot", "RL_foot", "RR_foot"])
    q0 = go2.neutral()
    q0[7:] = [0.0, 0.9, -1.8] * 4
    rot, org = go2.placements(q0)
    names = [go2.body_info(i)[0] for i in range(go2.nbodies)]
    q0[2] = -min((org[names.index(f)] + rot[names.index(f)] @ c)[2] - r for f, c, r in feet)
    scene = pmd.Scene(go2, q0=q0, effects=[pmd.Gravity(), pmd.GroundContact(feet, friction=1.0)])
    steps, copies, period = (100 if quick else 1000), 2, 0.01

    def make():
        return SceneEnv(scene, action_limit=5.0, control_period=period, method="Radau", rtol=1e-4, atol=1e-7,
                        max_episode_steps=10**9)

    venv = VectorSceneEnv(make, copies, threads=2)
    venv.reset(seed=0)
    venv.action_space.seed(0)
    actions = [venv.action_space.sample() for _ in range(steps)]
    t0 = time.perf_counter()
    for a in actions:
        venv.step(a)
    ours = time.perf_counter() - t0
    venv.close()

    import gymnasium

    xml = Path(gymnasium.__file__).parent / "envs/mujoco/assets/ant.xml"
    m = mujoco.MjModel.from_xml_path(str(xml))
    d = mujoco.MjData(m)
    rng = np.random.default_rng(0)
    ctrl = rng.uniform(-1, 1, (steps * copies, m.nu))
    t0 = time.perf_counter()
    for a in ctrl:  # Ant-v5: frame_skip 5 of its 10 ms timestep per env step
        d.ctrl[:] = a
        mujoco.mj_step(m, d, nstep=5)
    ant = time.perf_counter() - t0
    print(f"\nGo2 on ground contact, {copies} copies x {steps} steps of {period * 1e3:.0f} ms "
          f"(VectorSceneEnv, 2 threads, Radau rtol 1e-4): {steps * copies / ours:8.0f} env steps/s")
    print(f"MuJoCo Ant (ant.xml, 5 x 10 ms per step, {steps * copies} steps, one thread): "
          f"{steps * copies / ant:8.0f} env steps/s")


def controller_batch(quick: bool) -> None:
    scene = pmd.load_scene("chain7")
    nq = scene.model.nq
    q0 = np.asarray(scene.q0) + 0.1 * np.random.default_rng(0).normal(size=(8, nq))

    def f(t, q, v, sensors):
        return 30.0 * (0.0 - q) - 3.0 * v

    span = (0.0, 0.1 if quick else 0.3)
    times, last = {}, None
    for threads in (1, 2, 1, 2):
        t0 = time.perf_counter()
        batch = pmd.simulate_batch(scene, span, q0=q0, controller=f, control_period=1e-3, method="RK45",
                                   rtol=1e-8, atol=1e-10, threads=threads)
        times[threads] = min(times.get(threads, np.inf), time.perf_counter() - t0)
        q = np.array([r.q[-1] for r in batch.results])
        assert last is None or np.array_equal(q, last)  # the same bits on any thread count
        last = q
    print(f"\nsimulate_batch(controller=f), 8 chain7 runs x {span[1] * 1e3:.0f} periods, RK45 rtol 1e-8: "
          f"1 thread {times[1] * 1e3:.0f} ms, 2 threads {times[2] * 1e3:.0f} ms ({times[1] / times[2]:.2f}x)")


def state_conversion(n: int = 2000) -> None:
    from pointmass_dyn import io

    model = pmd.load_scene("panda").model
    qpos, qvel = io.to_mujoco_state(model, model.neutral(), np.zeros(model.nv))
    t = per_call(lambda: io.from_mujoco_state(model, qpos, qvel), n)
    print(f"\nio.from_mujoco_state on Panda: {t * 1e6:.1f} us a call")


if __name__ == "__main__":
    quick = "--quick" in sys.argv
    main(2000 if quick else 20000)
    panda_pd_loop(quick)
    quadruped_env(quick)
    controller_batch(quick)
    state_conversion()
