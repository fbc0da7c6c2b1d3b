"""`pmd.Simulator` (step, sense, act) and `simulate(controller=...)`.

References: the same zero-order-hold torques as a `JointTorque` effect in chained `simulate`
calls (RK4: bit for bit, the method carries nothing across a step; adaptive methods: within
their tolerance), finite differences of a body frame's pose (the IMU), MuJoCo running the same
Python PD controller on the exported model, the Go2's weight on its feet (standing)."""

from __future__ import annotations

import inspect

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import record
from pointmass_dyn.errors import InvalidInputError

PERIOD = 0.002


def chain3():
    scene = pmd.load_scene("chain7")
    return pmd.Scene(scene.model, q0=scene.q0, effects=[pmd.Gravity((0, 0, -9.81))])


def controls(nv, n, seed=3):
    return np.random.default_rng(seed).normal(scale=2.0, size=(n, nv))


def loop(scene, u, **kw):
    sim = pmd.Simulator(scene, control_period=PERIOD, **kw)
    for uk in u:
        sim.step(control=uk)
    return sim


METHODS = [dict(method="RK45", rtol=1e-8, atol=1e-10), dict(method="DOP853", rtol=1e-9, atol=1e-12),
           dict(method="Radau", rtol=1e-7, atol=1e-10), dict(method="RK4", dt=PERIOD / 4)]


@pytest.mark.parametrize("opts", METHODS, ids=lambda o: o["method"])
def test_simulator_loop_is_simulate_with_the_controller_bit_for_bit(opts):
    scene = chain3()
    u = controls(scene.model.nv, 50)
    sim = loop(scene, u, **opts)
    a = sim.result()
    b = pmd.simulate(scene, (0, 50 * PERIOD), control_period=PERIOD,
                     controller=lambda t, q, v, s: u[round(t / PERIOD)], **opts)
    assert a.success and b.success
    assert np.array_equal(a.t, b.t) and np.array_equal(a.q, b.q) and np.array_equal(a.v, b.v)
    assert a.t[-1] == pytest.approx(50 * PERIOD, abs=1e-15)


def chained(scene, u, **opts):
    """The ZOH torques as a JointTorque effect, one `simulate` call per period."""
    q, v = np.array(scene.q0), np.array(scene.v0)
    for k, uk in enumerate(u):
        s = pmd.Scene(scene.model, q0=q, v0=v,
                      effects=list(scene.effects) + [pmd.JointTorque(None, tau=uk)])
        r = pmd.simulate(s, (k * PERIOD, (k + 1) * PERIOD), **opts)
        q, v = r.q[-1], r.v[-1]
    return q, v


def test_rk4_simulator_is_chained_simulate_with_constant_torques_bit_for_bit():
    scene = chain3()
    u = controls(scene.model.nv, 30)
    sim = loop(scene, u, method="RK4", dt=PERIOD / 4)
    q, v = chained(scene, u, method="RK4", dt=PERIOD / 4)
    assert np.array_equal(sim.q, q) and np.array_equal(sim.v, v)


@pytest.mark.parametrize("opts", METHODS[:3], ids=lambda o: o["method"])
def test_adaptive_simulator_agrees_with_restarted_runs_within_tolerance(opts):
    scene = chain3()
    u = controls(scene.model.nv, 30)
    sim = loop(scene, u, **opts)
    q, v = chained(scene, u, **opts)
    gap = record(f"simulator vs restarted {opts['method']}", float(np.abs(sim.q - q).max()))
    assert gap < 100 * opts["rtol"]
    # Kept its step across the boundaries: far fewer evaluations than restarting each period.
    restarted = sum(pmd.simulate(chain3(), (0, PERIOD), **opts).nfev for _ in range(1))
    assert sim.result().nfev < 30 * restarted


def test_control_and_state_inputs_are_checked_naming_the_step():
    sim = pmd.Simulator(chain3(), control_period=PERIOD)
    sim.step(control=np.zeros(7))
    with pytest.raises(InvalidInputError, match=r"control.*step 1"):
        sim.step(control=np.zeros(6))
    with pytest.raises(InvalidInputError, match=r"control.*NaN at index 2"):
        sim.step(control=[0, 0, np.nan, 0, 0, 0, 0])
    with pytest.raises(InvalidInputError, match="duration"):
        sim.step(duration=-1.0)
    with pytest.raises(InvalidInputError, match="state"):
        sim.state = np.zeros(14)
    with pytest.raises(InvalidInputError, match="q"):
        sim.state = (np.zeros(3), np.zeros(7))
    with pytest.raises(InvalidInputError, match="method"):
        pmd.Simulator(chain3(), method="auto")
    with pytest.raises(InvalidInputError, match="control_period"):
        pmd.Simulator(chain3(), control_period=0.0)
    with pytest.raises(InvalidInputError, match="'pd'"):
        pmd.Simulator(chain3(), control="pd")


def test_state_reset_and_result():
    scene = chain3()
    sim = pmd.Simulator(scene, control_period=PERIOD, method="RK45", rtol=1e-9, atol=1e-12)
    for _ in range(10):
        sim.step()
    sim.state = (scene.q0, scene.v0)
    assert sim.t == pytest.approx(10 * PERIOD)
    for _ in range(10):
        sim.step()
    fresh = pmd.Simulator(scene, control_period=PERIOD, method="RK45", rtol=1e-9, atol=1e-12)
    for _ in range(10):
        fresh.step()
    # The same motion from the same state (the method restarted at the reset).
    np.testing.assert_allclose(sim.q, fresh.q, rtol=0, atol=1e-9)
    res = sim.result()
    assert np.count_nonzero(np.diff(res.t) == 0) == 1  # the reset's second row


def test_controller_exception_stops_with_the_trajectory_so_far():
    def f(t, q, v, s):
        if t > 5 * PERIOD:
            raise ZeroDivisionError("boom")
        return np.zeros(7)

    with pytest.raises(ZeroDivisionError) as info:
        pmd.simulate(chain3(), (0, 0.1), controller=f, control_period=PERIOD)
    assert info.value.result.t[-1] == pytest.approx(6 * PERIOD)
    with pytest.raises(InvalidInputError, match="control"):
        pmd.simulate(chain3(), (0, 0.1), controller=lambda *a: np.zeros(2))


def test_pd_targets_hold_the_scene_pd_torques():
    base = chain3()
    names = [base.model.body_info(i)[0] for i in range(base.model.nbodies)]
    q0 = np.array(base.q0)
    target = q0 + 0.1
    pd = pmd.PDTorque(names, kp=50.0, kd=5.0, time=[0, 1], reference=[q0, q0])
    scene = pmd.Scene(base.model, q0=q0, effects=list(base.effects) + [pd])
    sim = pmd.Simulator(scene, control="pd", control_period=PERIOD, method="RK45", rtol=1e-9,
                        atol=1e-12)
    sim.step(control=target)
    # The same law written as a torque control from the state is the reference.
    ref = pmd.Simulator(chain3(), control_period=PERIOD / 200, method="RK4", dt=PERIOD / 200)
    for _ in range(200):
        q, v = ref.q, ref.v
        ref.step(control=50.0 * (target - q) - 5.0 * v)
    np.testing.assert_allclose(sim.q, ref.q, rtol=0, atol=1e-6)
    np.testing.assert_allclose(sim.sensors()["tau"], 50.0 * (target - sim.q) - 5.0 * sim.v,
                               rtol=1e-12, atol=1e-12)


def test_imu_against_finite_differences_of_the_frame():
    scene = chain3()
    model = scene.model
    body, p = 4, np.array([0.1, 0.02, -0.03])
    rot = np.linalg.qr(np.random.default_rng(1).normal(size=(3, 3)))[0]
    imu = {"imu": pmd.IMU(body, p, rot)}
    h = 1e-3
    sim = pmd.Simulator(scene, control_period=h, method="DOP853", rtol=1e-13, atol=1e-14,
                        imu=imu)
    u = np.linspace(-1, 1, 7)
    frames, reads = [], []
    for _ in range(5):
        poses = model.body_poses(sim.q)
        frames.append((poses["rotations"][body], poses["origins"][body]))
        reads.append(sim.sensors())
        sim.step(control=u)
    g = np.array([0, 0, -9.81])
    for k in (1, 2, 3):
        (r0, o0), (r1, o1), (r2, o2) = frames[k - 1], frames[k], frames[k + 1]
        pt = [r @ p + o for r, o in ((r0, o0), (r1, o1), (r2, o2))]
        a = (pt[0] - 2 * pt[1] + pt[2]) / h**2
        axes = r1 @ rot
        np.testing.assert_allclose(reads[k]["imu.accel"], axes.T @ (a - g), rtol=0, atol=2e-4)
        w = (r2 - r0) / (2 * h) @ r1.T
        omega = np.array([w[2, 1] - w[1, 2], w[0, 2] - w[2, 0], w[1, 0] - w[0, 1]]) / 2
        np.testing.assert_allclose(reads[k]["imu.gyro"], axes.T @ omega, rtol=0, atol=2e-5)


def test_sensor_noise_is_seeded():
    imu = {"imu": pmd.IMU(2)}
    kw = dict(imu=imu, noise={"imu.gyro": 0.01, "q": 1e-3}, bias={"imu.accel": [0, 0, 1.0]})
    a = pmd.Simulator(chain3(), seed=4, **kw).sensors()
    b = pmd.Simulator(chain3(), seed=4, **kw).sensors()
    c = pmd.Simulator(chain3(), **{k: v for k, v in kw.items() if k != "noise"}).sensors()
    d = pmd.Simulator(chain3(), imu=imu).sensors()
    for key in a:
        assert np.array_equal(a[key], b[key])
    assert not np.array_equal(a["q"], c["q"]) and np.array_equal(c["q"], d["q"])
    np.testing.assert_allclose(c["imu.accel"] - d["imu.accel"], [0, 0, 1.0], rtol=0, atol=1e-12)


def test_python_pd_holding_panda_matches_mujoco_running_the_same_controller():
    mujoco = pytest.importorskip("mujoco")
    from pointmass_dyn import io as mjcf

    scene = pmd.load_scene("panda")
    model = scene.model
    goal = np.array(scene.q0)
    start = goal + 0.2
    kp, kd, period, n = 100.0, 10.0, 1e-3, 40  # mid-transient (it settles by 0.3 s)

    def pd(q, v):
        return kp * (goal - q) - kd * v

    sim = pmd.Simulator(pmd.Scene(model, q0=start, effects=scene.effects), method="DOP853",
                        rtol=1e-10, atol=1e-12, control_period=period)
    for _ in range(n):
        sim.step(control=pd(sim.q, sim.v))
    m = mujoco.MjModel.from_xml_string(pmd.to_mjcf(scene))
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    sub = 20
    m.opt.timestep = period / sub
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = mjcf.to_mujoco_state(model, start, np.zeros(model.nv))
    for _ in range(n):
        q, v = mjcf.from_mujoco_state(model, d.qpos, d.qvel)
        d.qfrc_applied[:] = pd(q, v)  # revolute joints: MuJoCo's dofs are ours
        for _ in range(sub):
            mujoco.mj_step(m, d)
    q_mj, _ = mjcf.from_mujoco_state(model, d.qpos, d.qvel)
    gap = record("panda PD: max |q - q_mujoco| after 40 ms", float(np.abs(sim.q - q_mj).max()))
    moved = float(np.abs(sim.q - start).max())
    assert gap < 1e-6 and moved > 0.05  # RK4 at 50 µs: ~1e-9; the controller moved the arm


def test_go2_stands_under_a_python_pd_controller_on_ground_contact():
    urdf = pytest.importorskip("pointmass_dyn.robots").urdf_path
    try:
        path = urdf("go2_description/urdf/go2.urdf")
    except Exception:  # example-robot-data without the Go2
        pytest.skip("no Go2 in example-robot-data")
    go2 = pmd.example_robot("go2_description/urdf/go2.urdf", root_joint="free")
    feet = pmd.urdf_contact_points(path, ["FL_foot", "FR_foot", "RL_foot", "RR_foot"])
    pose = np.array([0.0, 0.9, -1.8] * 4)
    q0 = go2.neutral()
    q0[7:] = pose
    rot, org = go2.placements(q0)
    names = [go2.body_info(i)[0] for i in range(go2.nbodies)]
    bottoms = [(org[names.index(f)] + rot[names.index(f)] @ c)[2] - r for f, c, r in feet]
    q0[2] = -min(bottoms) + 0.005  # dropped from 5 mm
    scene = pmd.Scene(go2, q0=q0, effects=[pmd.Gravity(), pmd.GroundContact(feet, friction=1.0)])

    def stand(t, q, v, sensors):
        u = np.zeros(go2.nv)
        u[6:] = 100.0 * (pose - q[7:]) - 5.0 * v[6:]
        return u

    # 5 s (about 6 s of test): dropped from 5 mm, it settles and stays.
    res = pmd.simulate(scene, (0, 5.0), controller=stand, control_period=1e-3, method="Radau",
                       rtol=1e-5, atol=1e-8, contact=True)
    res.raise_for_status()
    last = pmd.Simulator(scene, contact=True)
    last.state = (res.q[-1], res.v[-1])
    forces = last.sensors()["contact.contact"]
    mass = go2.total_mass
    record("go2 standing under Python PD: max |v| at 5 s", float(np.abs(res.v[-1]).max()))
    assert np.abs(res.v[-1]).max() < 0.05
    assert forces[:, 2].sum() == pytest.approx(mass * 9.81, rel=0.05)  # its weight on its feet
    assert res.q[:, 2].min() > q0[2] - 0.05  # did not collapse


@pytest.mark.parametrize("opts", METHODS, ids=lambda o: o["method"])
def test_simulator_t_eval_samples_the_steps_interpolants(opts):
    """``t_eval``: the same steps as without it; at a step's end its state exactly, between
    steps within the tolerance of a tight run; times are checked."""
    scene = chain3()
    u = controls(scene.model.nv, 10)
    t_eval = np.linspace(0.0, 10 * PERIOD, 41)  # period ends and quarter periods
    sampled = loop(scene, u, t_eval=t_eval, **opts).result()
    steps = loop(scene, u, **opts).result()
    assert np.array_equal(sampled.t, t_eval) and sampled.nfev >= steps.nfev
    at = np.isin(t_eval, steps.t)
    assert at.sum() >= 11 and np.array_equal(sampled.q[at], steps.q[np.isin(steps.t, t_eval)])
    tight = loop(scene, u, t_eval=t_eval, method="DOP853", rtol=1e-12, atol=1e-14).result()
    np.testing.assert_allclose(sampled.q, tight.q, rtol=0, atol=1e-6)
    for bad, match in (([0.0, 0.01, 0.005], "increasing"), ([-1.0, 0.0], "current time"),
                       ([0.0, np.nan], "finite")):
        with pytest.raises(InvalidInputError, match=f"t_eval.*{match}"):
            pmd.Simulator(scene, control_period=PERIOD, t_eval=bad, **opts)


def test_a_refused_state_keeps_the_state_without_recording():
    """A state that breaks the four-bar's loop is refused and the run goes on from where it
    was, whether or not it records its steps."""
    scene = pmd.load_scene("fourbar")
    for record_steps in (True, False):
        sim = pmd.Simulator(scene, control_period=PERIOD, method="RK45", record=record_steps)
        for _ in range(3):
            sim.step()
        q, v = sim.state
        with pytest.raises(InvalidInputError):
            sim.state = (q + 0.3, v)
        assert np.array_equal(sim.q, q) and np.array_equal(sim.v, v)
        sim.step()
        assert sim.t == pytest.approx(4 * PERIOD)


def test_core_simulator_reads_its_whole_call():
    """`_Simulator(scene, **settings)` is read in the core: a keyword it does not take is
    refused by name rather than ignored, and one not given takes `pmd.Simulator`'s default."""
    with pytest.raises(TypeError, match="max_steps: expected a keyword of Simulator"):
        pmd._core._Simulator(chain3(), max_steps=10)
    with pytest.raises(InvalidInputError, match="control"):
        pmd._core._Simulator(chain3(), control="position")
    default = inspect.signature(pmd.Simulator).parameters["control_period"].default
    assert pmd._core._Simulator(chain3()).control_period == default
    assert pmd._core._Simulator(chain3(), t0=0.25).t == 0.25


_CHILD_PRELUDE = """
import threading, time
import numpy as np, pointmass_dyn as pmd

base = pmd.load_scene("chain7")

def simulator(torque):
    effects = [pmd.Gravity((0, 0, -9.81)), pmd.TorqueFunction(torque)]
    scene = pmd.Scene(base.model, q0=base.q0, effects=effects)
    return pmd.Simulator(scene, method="RK4", dt=0.002, control_period=0.002)
"""


def _in_child(script, what):
    """``script`` after the prelude in a child process, its stdout; a hang (a deadlock) fails
    the test by the timeout instead of hanging the suite."""
    import subprocess
    import sys

    try:
        out = subprocess.run([sys.executable, "-c", _CHILD_PRELUDE + script], capture_output=True,
                             text=True, timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail(f"deadlock: {what} hung")
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def test_a_simulator_read_from_another_thread_while_it_steps_waits_instead_of_deadlocking():
    """One thread steps a Simulator whose torque law is Python; another reads its time
    meanwhile. The reader must wait for the step without holding the interpreter (which the
    torque law needs), not block the stepping thread forever."""
    script = """
def torque(t, q, v):
    time.sleep(1e-4)  # releases the interpreter, as a slow law would
    return np.zeros_like(v)

sim = simulator(torque)
read = []
threads = [threading.Thread(target=lambda: [sim.step() for _ in range(20)]),
           threading.Thread(target=lambda: [read.append(sim.t) for _ in range(200)])]
for th in threads:
    th.start()
for th in threads:
    th.join()
assert len(read) == 200 and read == sorted(read), read
print(sim.t)
"""
    out = _in_child(script, "two threads sharing a Simulator with a Python torque law")
    assert float(out) == pytest.approx(20 * 0.002)


def test_a_simulators_own_callback_using_it_is_refused_naming_the_reentry():
    """A torque law that reads the Simulator it is driving (same thread, mid-step) gets a clear
    error instead of a hang."""
    script = """
holder = {}

def torque(t, q, v):
    holder["sim"].t  # the simulator being stepped
    return np.zeros_like(v)

sim = holder["sim"] = simulator(torque)
try:
    sim.step()
except pmd.errors.InvalidInputError as e:
    print(type(e).__name__, e)
"""
    out = _in_child(script, "a torque law reading its own Simulator")
    assert out.startswith("InvalidInputError Simulator:") and "already in a call" in out, out
