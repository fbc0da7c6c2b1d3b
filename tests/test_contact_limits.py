"""Joint limits: the bounds a model brings (Panda's URDF <limit>, an MJCF range) are the ones
a JointLimit without numbers enforces, a pendulum swung toward a bound stays inside it (plus
the spring's energy-bounded penetration), and bad input is refused by name."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
import pytest

PANDA = Path(pmd.__file__).parent / "scenes" / "panda.urdf"


def test_panda_limits_are_its_urdf_limit_elements():
    root = ET.parse(PANDA).getroot()
    given = {
        j.get("name"): (float(j.find("limit").get("lower")), float(j.find("limit").get("upper")))
        for j in root.findall("joint")
        if j.get("type") == "revolute"
    }
    model = pmd.Model.from_urdf(PANDA)
    limits = model.joint_limits()
    assert set(limits) == set(given)
    for name, (lo, up) in given.items():
        assert limits[name][:2] == (lo, up)
    # The effect without numbers pushes back exactly past those bounds.
    k = 1000.0
    scene = pmd.Scene(model, effects=[pmd.JointLimit(stiffness=k, damping=0.0)])
    names = model.joint_names
    for side, sign in ((1, -1.0), (0, 1.0)):
        q = np.array([given[n][side] for n in names]) - sign * 0.01
        tau = pmd.effect_forces(scene, 0.0, q, np.zeros(model.nv))["limits"]
        np.testing.assert_allclose(tau, sign * k * 0.01, rtol=1e-12)
        inside = np.array([given[n][side] for n in names]) + sign * 1e-9
        tau = pmd.effect_forces(scene, 0.0, inside, np.zeros(model.nv))["limits"]
        assert np.all(tau == 0.0)


@pytest.mark.parametrize("c", [0.0, 2.0])
def test_pendulum_released_toward_a_limit_stays_inside_it(c):
    # Released horizontal (q = 0), it falls toward −π/2; a bound at −1 rad stops it.
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 1e-3), pmd.Revolute([0, 0, 1]),
               name="arm")
    k, lower = 2000.0, -1.0
    scene = pmd.Scene(m, q0=[0.0], effects=[
        pmd.Gravity([0, -9.81, 0]),
        pmd.JointLimit("arm", lower, math.inf, stiffness=k, damping=c),
    ])
    res = pmd.simulate(scene, (0, 3), method="Radau", rtol=1e-9, atol=1e-11,
                       t_eval=np.linspace(0, 3, 30001))
    res.raise_for_status()
    # Energy bound on the overshoot: ½ k δ² ≤ m g (0.5 sin 1 + 0.5 δ) (the potential released
    # from q = 0 down to the wall and past it), solved for δ.
    mgl = 9.81 * 0.5
    a, b, cc = 0.5 * k, -mgl, -mgl * math.sin(1.0)
    bound = (-b + math.sqrt(b * b - 4 * a * cc)) / (2 * a)
    deepest = lower - res.q[:, 0].min()
    assert 0 < deepest <= bound
    if c == 0.0:
        assert deepest > 0.9 * bound  # the bound is nearly reached without damping
        # Elastic bounce: it comes back up to (nearly) where it started.
        assert res.q[:, 0].max() == pytest.approx(0.0, abs=1e-5)


def test_mujoco_ranges_are_the_models_limits():
    mujoco = pytest.importorskip("mujoco")
    xml = """<mujoco><compiler angle="radian"/><worldbody><body name="a"><joint name="h" type="hinge" axis="0 0 1"
      range="-0.5 0.7" limited="true"/><geom type="capsule" size="0.05" fromto="0 0 0 0.3 0 0"/>
      <body name="b" pos="0.3 0 0"><joint name="s" type="slide" axis="1 0 0"/>
      <geom type="sphere" size="0.05"/></body></body></worldbody></mujoco>"""
    model = pmd.from_mujoco(mujoco.MjModel.from_xml_string(xml))
    limits = model.joint_limits()
    assert limits["h"][:2] == (-0.5, 0.7)
    assert limits["s"][:2] == (-math.inf, math.inf)


def test_joint_limit_refusals_name_the_argument():
    with pytest.raises(pmd.InvalidInputError, match="lower"):
        pmd.JointLimit(None, 1.0, -1.0, stiffness=1.0, damping=0.0)
    with pytest.raises(pmd.InvalidInputError, match="stiffness"):
        pmd.JointLimit(None, -1.0, 1.0, stiffness=-1.0, damping=0.0)
    with pytest.raises(pmd.InvalidInputError, match="damping"):
        pmd.JointLimit(None, -1.0, 1.0, stiffness=1.0, damping=-1.0)
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 1e-3), pmd.Revolute([0, 0, 1]),
               name="arm")
    # A model without limits and no numbers: the missing bound is named.
    with pytest.raises(pmd.InvalidInputError, match="lower"):
        pmd.Scene(m, effects=[pmd.JointLimit(stiffness=1.0, damping=0.0)])
    with pytest.raises(pmd.InvalidInputError, match="joints"):
        pmd.Scene(m, effects=[pmd.JointLimit("nope", -1, 1, stiffness=1.0, damping=0.0)])


def test_torques_saturate_at_their_limit_and_say_so():
    # A PD holding a horizontal arm against gravity (m g l = 4.905 N·m) with 2 N·m at most:
    # the torque stays at the limit while the arm falls, and the result says so.
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 1e-3), pmd.Revolute([0, 0, 1]),
               name="arm")
    pd = pmd.PDTorque("arm", kp=100.0, kd=1.0, time=[0, 1], reference=[0.0, 0.0], limit=2.0)
    scene = pmd.Scene(m, q0=[0.0], effects=[pmd.Gravity([0, -9.81, 0]), pd])
    res = pmd.simulate(scene, (0, 0.3), t_eval=np.linspace(0, 0.3, 31), method="Radau",
                       rtol=1e-8, atol=1e-10)
    res.raise_for_status()
    sat = res.saturated["torques"]
    # At rest at first (τ = 0), then past 2 N·m of PD action within a few tens of ms.
    assert sat.shape == (31, 1) and not sat[0, 0] and sat[5:].all()
    taus = np.array([pmd.effect_forces(scene, t, q, v)["torques"][0]
                     for t, q, v in zip(res.t, res.q, res.v)])
    np.testing.assert_allclose(taus[sat[:, 0]], 2.0, rtol=1e-12)
    assert np.all(np.abs(taus) <= 2.0 * (1 + 1e-12))
    # Free fall with a constant 2 N·m: I θ̈ = 2 − m g l cos θ, so it falls, unlike the
    # unlimited PD.
    assert res.q[-1, 0] < -0.1
    free = pmd.simulate(pmd.Scene(m, q0=[0.0], effects=[
        pmd.Gravity([0, -9.81, 0]),
        pmd.PDTorque("arm", kp=100.0, kd=1.0, time=[0, 1], reference=[0.0, 0.0])]), (0, 0.3))
    assert free.saturated is None and free.q[-1, 0] > -0.1


def test_effort_limits_are_the_urdf_efforts():
    root = ET.parse(PANDA).getroot()
    effort = {j.get("name"): float(j.find("limit").get("effort"))
              for j in root.findall("joint") if j.get("type") == "revolute"}
    model = pmd.Model.from_urdf(PANDA)
    torque = pmd.JointTorque(None, 1000.0, limit="effort")
    assert torque.torque_limit == "effort"
    scene = pmd.Scene(model, effects=[torque])
    filled = scene.effects[0]
    expected = [effort[n] for n in model.joint_names]
    np.testing.assert_array_equal(filled.torque_limit_per_speed(model), expected)
    tau = pmd.effect_forces(scene, 0.0, model.neutral(), np.zeros(model.nv))["torques"]
    np.testing.assert_array_equal(tau, expected)
    with pytest.raises(pmd.InvalidInputError, match="limit"):
        pmd.JointTorque(None, 1.0, limit=-1.0)
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 1e-3), pmd.Revolute([0, 0, 1]),
               name="arm")
    # A model without efforts: 'effort' means no limit (inf), as Model.joint_limits() says.
    scene = pmd.Scene(m, effects=[pmd.JointTorque(None, 5.0, limit="effort")])
    assert pmd.effect_forces(scene, 0.0, [0.0], [0.0])["torques"][0] == 5.0
