"""`Scene.to_toml()` / `Scene.write(path)`: every scene, bundled or built in Python, written as
a scene file and read back is the same scene. Compared: the effects (declarations equal),
the model (mass matrix and bias forces at random states to 1e-14 relative, names, limits,
couplings, armature, visuals), the start state and every run setting, and a short run of
both scenes gives the same trajectory (the same arithmetic: equal to rounding)."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest

RNG = np.random.default_rng(38)


def random_state(model: pmd.Model):
    q = model.neutral() + RNG.uniform(-0.5, 0.5, model.nq)
    v = RNG.uniform(-1.0, 1.0, model.nv)
    return q, v


def assert_same_model(a: pmd.Model, b: pmd.Model):
    assert (a.nq, a.nv, a.nbodies) == (b.nq, b.nv, b.nbodies)
    assert a.body_names == b.body_names
    assert a.joint_names == b.joint_names
    assert a.joint_limits() == b.joint_limits()
    assert a.couplings == b.couplings
    assert a.loop_names == b.loop_names
    np.testing.assert_array_equal(a.armature, b.armature)
    assert a.name == b.name
    assert a.repairs == b.repairs
    assert len(a.visuals) == len(b.visuals)
    assert a.total_mass == pytest.approx(b.total_mass, rel=1e-15)
    g = np.array([0.0, 0.0, -9.81])
    for _ in range(3):
        q, v = random_state(a)
        q = a.neutral() if a.nloops else q  # loop models: a state on the constraint manifold
        # The seven point masses (where point_mass_center puts them), not only their sums.
        for xa, xb in zip(a.point_masses(q), b.point_masses(q)):
            np.testing.assert_allclose(xb, xa, rtol=0, atol=1e-14 * max(np.abs(xa).max(), 1))
        ma, mb = a.mass_matrix(q), b.mass_matrix(q)
        np.testing.assert_allclose(mb, ma, rtol=0, atol=1e-14 * np.abs(ma).max())
        ba, bb = a.bias_forces(q, v, g), b.bias_forces(q, v, g)
        np.testing.assert_allclose(bb, ba, rtol=0, atol=1e-14 * max(np.abs(ba).max(), 1.0))


SETTINGS = ("t_span", "rtol", "atol", "max_step", "max_steps", "first_step", "method", "dt",
            "disable", "name", "description")


def assert_same_scene(a: pmd.Scene, b: pmd.Scene, t_end: float | None = 0.05):
    assert_same_model(a.model, b.model)
    assert list(b.effects) == list(a.effects)
    for s in SETTINGS:
        assert getattr(b, s) == getattr(a, s), s
    # A closed-loop scene's start state is closed again when read: equal to rounding.
    np.testing.assert_allclose(b.q0, a.q0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(b.v0, a.v0, rtol=0, atol=1e-14 * max(np.abs(a.v0).max(), 1))
    if t_end is None:
        return
    t = np.linspace(0, t_end, 6)
    kw = dict(t_eval=t, max_steps=20000)
    ra, rb = pmd.simulate(a, (0, t_end), **kw), pmd.simulate(b, (0, t_end), **kw)
    assert ra.success == rb.success
    scale = max(np.abs(ra.q).max(), 1.0)
    np.testing.assert_allclose(rb.q, ra.q, rtol=0, atol=1e-12 * scale)


def round_trip(scene: pmd.Scene) -> pmd.Scene:
    return pmd.Scene.from_toml(scene.to_toml())


@pytest.mark.parametrize("name", sorted(pmd.builtin_scenes()))
def test_every_bundled_scene_reads_back_equal(name):
    sc = pmd.load_scene(name)
    assert_same_scene(sc, round_trip(sc), t_end=None if name.startswith("iftomm") else 0.05)


def pendulum_chain() -> pmd.Model:
    m = pmd.Model()
    body = pmd.RigidBody(1.2, [0.3, 0.01, 0], np.diag([0.01, 0.05, 0.06]))
    a = m.add_body(body, pmd.Revolute([0, 1, 0]), name="upper")
    m.add_body(pmd.RigidBody.from_point_masses([0.5, 0.7], [[0.2, 0, 0], [0.45, 0.02, 0.01]]),
               pmd.Revolute([0, 1, 0]), parent=a, translation=[0.6, 0, 0], name="lower",
               rotation=[[0, -1, 0], [1, 0, 0], [0, 0, 1]], point_mass_center=[0.3, 0, 0])
    m.add_body(pmd.RigidBody(0.2, [0, 0, 0], np.eye(3) * 1e-4), pmd.Fixed(), parent="lower",
               translation=[0.6, 0, 0], name="tip")
    m.add_body(pmd.RigidBody(0.4, [0, 0, 0.1], np.eye(3) * 2e-3), pmd.Prismatic([1, 0, 0]),
               parent="lower", name="slider")
    m.set_armature("upper", 0.05)
    return m


def test_a_python_built_scene_with_every_effect_reads_back_equal(tmp_path):
    m = pendulum_chain()
    t = [0.0, 0.5, 1.0]
    effects = [
        pmd.Gravity([0.1, 0, -9.81]),
        pmd.Spring(["upper"], 3.0, 0.2, name="hinge"),
        pmd.Damper([0, "lower"], [0.1, 0.2]),
        pmd.JointFriction("slider", 0.3, v_eps=2e-3),
        pmd.JointTorque(["upper", "lower"], [0.5, -0.25], limit=[1.0, np.inf]),
        pmd.TabulatedTorque("slider", t, [0.0, 1.0, -1.0], name="push"),
        pmd.PDTorque(["lower"], kp=40.0, kd=2.0, time=t, reference=[[0.0], [0.3], [0.1]],
                     limit=5.0),
        pmd.ExternalForce("tip", [0, 0, 1.5], [0.01, 0, 0], moment=[0, 0.1, 0]),
        pmd.ExternalForce("tip", [[0, 0, 1], [0, 1, 0], [1, 0, 0]], time=t, frame="body",
                          name="wind"),
        pmd.PointSpring("world", [0, 0, 1], "tip", [0, 0, 0], 20.0, 0.3, 0.5),
        pmd.GroundContact([("tip", [0, 0, 0], 0.02), ("slider", [0, 0, 0])], height=-2.0,
                          friction=0.8),
        pmd.JointLimit(["upper", "lower"], -1.0, [1.0, 2.0], stiffness=1e3, damping=5.0),
    ]
    sc = pmd.Scene(m, m.neutral() + 0.1, np.linspace(-0.2, 0.3, m.nv), effects,
                   t_span=(0, 2), rtol=1e-8, atol=1e-10, name="built", description="a test",
                   disable=["friction"], method="DOP853", max_step=0.1, max_steps=10**5,
                   first_step=1e-4)
    text = sc.to_toml()
    assert "[[body]]" in text and "point_mass_center" in text
    assert_same_scene(sc, pmd.Scene.from_toml(text))
    path = tmp_path / "built.toml"
    sc.write(path)
    assert_same_scene(sc, pmd.load_scene(path))
    fixed = sc.replace(method="RK4", dt=1e-3, disable=[])
    assert_same_scene(fixed, round_trip(fixed), t_end=0.01)


def test_a_robot_from_example_robot_data_reads_back_with_its_names_limits_and_visuals():
    go2 = pmd.example_robot("go2_description/urdf/go2.urdf", root_joint="free")
    q0 = go2.neutral()
    q0[2] = 0.4
    feet = [(f"{leg}_foot", [0, 0, 0], 0.02) for leg in ("FL", "FR", "RL", "RR")]
    sc = pmd.Scene(go2, q0, effects=[
        pmd.Gravity(), pmd.GroundContact(feet, friction=0.9),
        pmd.JointTorque(["FL_hip_joint"], 1.0, limit="effort"),
        pmd.JointLimit(stiffness=100.0, damping=1.0)], rtol=1e-6)
    back = round_trip(sc)
    assert back.model.joint_limits()["FL_hip_joint"] == go2.joint_limits()["FL_hip_joint"]
    assert back.model.visuals == go2.visuals
    assert_same_scene(sc, back, t_end=0.01)


def test_couplings_loops_and_a_urdf_repair_read_back(tmp_path):
    from test_model_records import REPAIRED  # a URDF with a mimic joint and a repaired link

    path = tmp_path / "mimicked.urdf"
    path.write_text(REPAIRED)
    with pytest.warns(pmd.errors.UrdfRepairWarning):
        model = pmd.Model.from_urdf(str(path), repair=True)
    model.set_armature("jb", 0.25)
    q0 = model.assemble([0.3, 0.0], fixed=["a"])  # a start state that keeps the coupling
    sc = pmd.Scene(model, q0, effects=[pmd.Gravity([0, -9.81, 0])])
    assert_same_scene(sc, round_trip(sc))
    fourbar = pmd.load_scene("fourbar")
    moved = fourbar.replace(v0=fourbar.v0, name="moved")
    assert_same_scene(moved, round_trip(moved))


def test_a_torque_function_is_refused_naming_the_effect():
    m = pendulum_chain()
    sc = pmd.Scene(m, effects=[pmd.Gravity(), pmd.TorqueFunction(lambda t, q, v: 0 * v,
                                                                   name="my_controller")])
    with pytest.raises(pmd.errors.InvalidInputError, match=r"effects\[1\].*my_controller"):
        sc.to_toml()


def test_a_written_massless_body_must_move_something():
    text = """
[[body]]
name = "ghost"
joint = { type = "Revolute", axis = [0, 0, 1] }
mass = 0.0
inertia = [[0, 0, 0], [0, 0, 0], [0, 0, 0]]
"""
    with pytest.raises(pmd.errors.SceneError, match=r"body\[0\] \('ghost'\)\.mass"):
        pmd.Scene.from_toml(text)
    with pytest.raises(pmd.errors.SceneError, match=r"body\[0\] \('ghost'\)\.inertia"):
        pmd.Scene.from_toml(text.replace("[0, 0, 0]]", "[0, 0, 1]]"))


def test_a_design_is_written_from_a_python_built_scene(tmp_path):
    # write_scene needed a scene file as its source; a Scene built in Python is one now.
    sc = pmd.load_scene("fourbar")
    built = pmd.Scene(sc.model, sc.q0, sc.v0, sc.effects, name="built in Python")
    mo = pmd.prescribed_motion(sc.model, "crank", speed=30.0, q_guess=sc.q0,
                               gravity=[0, -9.81, 0])
    rings = [pmd.Counterweight.ring("crank", [0, 0, 0], 0.02),
             pmd.Counterweight.ring("rocker", [0, 0, 0], 0.02)]
    b = pmd.balance(mo, counterweights=rings, zero=("force",))
    path = b.write_scene(built, tmp_path / "balanced.toml")
    again = pmd.load_scene(path)
    for name, body in b.bodies.items():
        got = again.model.body(name)
        assert got.mass == body.mass
        np.testing.assert_array_equal(got.com, body.com)
        np.testing.assert_array_equal(got.inertia, body.inertia)
    # The balanced model's shaking force along the same motion: what the balance promised.
    after = pmd.prescribed_motion(again.model, "crank", speed=30.0, q_guess=sc.q0,
                                  gravity=[0, -9.81, 0])
    assert after.summary()["shaking force"]["rms"] < 1e-6 * mo.summary()["shaking force"]["rms"]
    with pytest.raises(pmd.errors.InvalidInputError, match="bodies"):
        pmd.design.write_scene({"nobody": b.bodies["crank"]}, built, tmp_path / "x.toml")


def test_a_mujoco_import_with_a_massless_intermediate_body_reads_back():
    mujoco = pytest.importorskip("mujoco")
    xml = """<mujoco><worldbody><body name="a" pos="0 0 1">
      <joint name="j1" type="hinge" axis="1 0 0"/><joint name="j2" type="hinge" axis="0 1 0"/>
      <inertial mass="1" pos="0.1 0 0" diaginertia="0.01 0.02 0.03"/>
      <body name="b" pos="0.3 0 0"><joint name="j3" type="slide" axis="1 0 0"/>
        <inertial mass="0.5" pos="0 0 0" diaginertia="0.001 0.001 0.001"/></body>
    </body></worldbody></mujoco>"""
    m = pmd.from_mujoco(mujoco.MjModel.from_xml_string(xml))
    assert m.body(0).mass == 0.0  # the body of joint j1, between the world and j2's
    sc = pmd.Scene(m, effects=[pmd.Gravity()])
    text = sc.to_toml()
    assert "mass = 0.0" in text
    assert_same_scene(sc, pmd.Scene.from_toml(text))
