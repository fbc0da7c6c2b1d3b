"""`to_mjcf` writes PD and tabulated torques as MuJoCo actuators (their limits as
forcerange), joint limits as limited ranges and ground contact as a floor with contact
spheres (python/pointmass_dyn/io/_mjcf_effects.py); what it cannot write is refused naming
the effect. Checked by loading the MJCF in MuJoCo: trajectories against ours (MuJoCo's RK4
at a small step against our DOP853 at rtol 1e-10), and a body resting on the floor (its
height within our static sink, the contact forces summing to its weight in both)."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest

mujoco = pytest.importorskip("mujoco")

G = 9.81


def chain(n: int = 2) -> pmd.Model:
    m = pmd.Model()
    parent = -1
    for k in range(n):
        body = pmd.RigidBody(1.0 + 0.3 * k, [0.25, 0, 0.01 * k], np.diag([1e-3, 2e-2, 2e-2]))
        parent = m.add_body(body, pmd.Revolute([0, 1, 0]), parent=parent,
                            translation=[0.5 if k else 0.0, 0, 0], name=f"link{k}")
    return m


def mujoco_run(scene: pmd.Scene, t_end: float, dt: float, follow: bool = False):
    mj = mujoco.MjModel.from_xml_string(pmd.to_mjcf(scene, timestep=dt, integrator="RK4"))
    d = mujoco.MjData(mj)
    mujoco.mj_resetDataKeyframe(mj, d, 0)
    for _ in range(round(t_end / dt)):
        if follow:
            d.ctrl[:] = pmd.io.mujoco_controls(scene, d.time)
        mujoco.mj_step(mj, d)
    return mj, d


def ours(scene: pmd.Scene, t_end: float):
    res = pmd.simulate(scene, (0, t_end), method="DOP853", rtol=1e-10, atol=1e-12)
    assert res.success, res.message
    return np.asarray(res.q)[-1], np.asarray(res.v)[-1]


def test_a_pd_chain_with_saturated_torques_moves_as_ours():
    m = chain(2)
    pd = pmd.PDTorque(["link0", "link1"], kp=[60.0, 30.0], kd=[4.0, 2.0], time=[0.0],
                      reference=[[0.8, -0.5]], limit=[8.0, np.inf])
    sc = pmd.Scene(m, [0.1, 0.2], [0.0, 0.5], [pmd.Gravity(), pmd.Damper(None, 0.05), pd])
    # The first link's PD demands more than 8 N m at the start: the limit is in play.
    assert abs(60 * 0.7 + 4 * 0 - 0) > 8
    t_end = 1.5
    q, v = ours(sc, t_end)
    mj, d = mujoco_run(sc, t_end, 2e-4)
    qm, vm = pmd.io.from_mujoco_state(m, d.qpos, d.qvel)
    np.testing.assert_allclose(qm, q, rtol=0, atol=1e-7)
    np.testing.assert_allclose(vm, v, rtol=0, atol=1e-6)
    assert mj.nu == 2 and list(mj.actuator_forcelimited) == [1, 0]


def test_a_tabulated_reference_is_followed_through_mujoco_controls():
    m = chain(1)
    pd = pmd.PDTorque("link0", kp=80.0, kd=6.0, time=[0.0, 0.5, 1.0],
                      reference=[0.0, 0.6, 0.2])
    sc = pmd.Scene(m, effects=[pmd.Gravity(), pd])
    q, _ = ours(sc, 1.2)
    errs = []
    for dt in (4e-4, 2e-4):  # the control is held over each step: first order in dt
        _, d = mujoco_run(sc, 1.2, dt, follow=True)
        errs.append(abs(d.qpos[0] - q[0]))
    assert errs[1] < 2e-3 and errs[1] < 0.7 * errs[0], errs


def test_joint_ranges_are_written_limited_with_our_bounds():
    m = chain(2)
    lim = pmd.JointLimit(["link1"], -0.4, 0.3, stiffness=2e3, damping=20.0)
    sc = pmd.Scene(m, effects=[pmd.Gravity(), lim])
    mj = mujoco.MjModel.from_xml_string(pmd.to_mjcf(sc))
    assert list(mj.jnt_limited) == [0, 1]
    np.testing.assert_array_equal(mj.jnt_range[1], [-0.4, 0.3])
    # One link falling under gravity (towards q = pi/2) onto its upper bound 0.3: both hold
    # it there (ours past it by its static deflection tau/k = 1.2e-3 rad, MuJoCo's soft
    # limit by a small part of that).
    one = chain(1)
    held = pmd.Scene(one, [0.25], effects=[
        pmd.Gravity(), pmd.Damper(None, 2.0),
        pmd.JointLimit(None, -0.4, 0.3, stiffness=2e3, damping=20.0)])
    q, _ = ours(held, 3.0)
    _, d = mujoco_run(held, 3.0, 5e-4)
    deflection = 1.0 * G * 0.25 * np.cos(0.3) / 2e3
    assert q[0] == pytest.approx(0.3 + deflection, rel=1e-3)
    assert 0.3 - 1e-4 < d.qpos[0] < q[0]


def box(mass: float = 2.0, half: float = 0.1) -> pmd.Model:
    m = pmd.Model()
    m.add_body(pmd.RigidBody(mass, [0, 0, 0], np.eye(3) * mass * (2 * half) ** 2 / 6),
               pmd.FreeFlyer(), name="box")
    return m


@pytest.mark.parametrize("radius", [0.0, 0.05])
def test_a_box_resting_on_the_floor_settles_where_ours_does(radius):
    h, mass = 0.1, 2.0
    m = box(mass, h)
    corners = [("box", [sx * h, sy * h, -h], radius) for sx in (-1, 1) for sy in (-1, 1)]
    contact = pmd.GroundContact(corners, friction=0.8)
    q0 = m.neutral()
    q0[2] = h + radius + 0.01
    sc = pmd.Scene(m, q0, effects=[pmd.Gravity(), contact])
    q, v = ours(sc, 1.5)
    mj, d = mujoco_run(sc, 1.5, 5e-4)
    p = sc.effects[1].contact_parameters
    sink = (mass * G / (4 * p["stiffness"])) ** (1 / p["exponent"])
    assert sink == pytest.approx(1e-3)  # the documented default: 1 mm
    z_ours, z_mj = q[2], d.qpos[2]
    assert z_ours == pytest.approx(h + radius - sink, abs=1e-6)
    assert abs(z_mj - z_ours) < sink + 1e-4  # 1e-4: a point's sphere in MuJoCo
    # The forces at rest carry the weight in both.
    ours_fn = sc.effects[1].contact_state(m, q[None], v[None])["normal_force"].sum()
    assert ours_fn == pytest.approx(mass * G, rel=1e-4)
    f6 = np.zeros(6)
    total = 0.0
    for k in range(d.ncon):
        mujoco.mj_contactForce(mj, d, k, f6)
        total += f6[0]
    assert d.ncon == 4 and total == pytest.approx(mass * G, rel=1e-3)


@pytest.mark.parametrize("effect", [
    pmd.JointFriction(None, 0.1),
    pmd.ExternalForce("link0", [0, 0, 1]),
    pmd.PointSpring("world", [0, 0, 0], "link1", [0, 0, 0], 10.0),
    pmd.TorqueFunction(lambda t, q, v: 0 * v, name="ctl"),
])
def test_what_mujoco_cannot_take_is_refused_naming_the_effect(effect):
    sc = pmd.Scene(chain(2), effects=[pmd.Gravity(), effect])
    with pytest.raises(pmd.errors.InvalidInputError, match=repr(effect.name)):
        pmd.to_mjcf(sc)
    with pytest.raises(pmd.errors.InvalidInputError, match="scene: expected a pointmass_dyn"):
        pmd.io.mujoco_controls(sc.model, 0.0)
