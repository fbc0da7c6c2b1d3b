"""Building a model under bad input: quaternions far from unit norm, names that are empty or
blank, a second mimic, joints, coupling ratios and armature of the wrong type, iteration
counts and velocities of ``assemble`` — each either the right answer (against the rotation it
stands for) or a ``pmd.errors`` exception naming the argument."""

from __future__ import annotations

import re

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import G
from pointmass_dyn.errors import (
    InvalidInputError,
    UrdfError,
)


def _free_box():
    m = pmd.Model()
    m.add_body(pmd.RigidBody(2.0, [0, 0, 0], np.diag([0.1, 0.2, 0.3])), pmd.FreeFlyer(),
               parent=-1, name="box")
    return m


LONG_NUMBER = re.compile(r"\d{25,}")


@pytest.fixture(scope="module")
def fourbar():
    return pmd.load_scene("fourbar")


Z = [0.0, 0.0, 1.0]


def _arm() -> pmd.Model:
    arm = pmd.Model()
    arm.add_body(pmd.RigidBody(1.2, [0.2, 0, 0], np.diag([1e-3, 0.02, 0.02])), pmd.Revolute(Z), name="upper")
    arm.add_body(pmd.RigidBody(0.8, [0.15, 0, 0], np.diag([1e-3, 0.01, 0.01])), pmd.Revolute(Z),
                 parent="upper", translation=[0.4, 0, 0], name="fore")
    return arm


@pytest.mark.parametrize("scale", [1e155, 1e300, 3.0, 1e-7])
def test_huge_quaternion_is_the_rotation_it_points_at(scale):
    m = _free_box()
    q = np.array([0.0, 0.0, 0.0, scale, 0.0, 0.0, 0.0])  # (x, y, z, w): half-turn about x
    rot = m.body_poses(q)["rotations"][0]
    np.testing.assert_allclose(rot, np.diag([1.0, -1.0, -1.0]), atol=1e-15)
    scene = pmd.Scene(m, q, np.zeros(6))
    np.testing.assert_allclose(scene.q0, [0, 0, 0, 1, 0, 0, 0], atol=1e-15)
    a = m.forward_dynamics(q, np.zeros(6), np.zeros(6), gravity=G)
    np.testing.assert_allclose(a[:3], [0.0, 0.0, 9.81], atol=1e-12)  # body axes: upside down


def test_tiny_quaternion_is_refused_with_the_bound():
    m = _free_box()
    with pytest.raises(InvalidInputError, match=r"norm at least 1e-8.*got.*norm 1\.000e-9"):
        m.body_poses([0, 0, 0, 1e-9, 0, 0, 0])


def test_from_urdf_repair_bound_refuses_bools():
    urdf = pmd.scenes.resolve_scene_path("panda").with_suffix(".urdf")
    for key in ("bound_mass", "bound_inertia"):
        with pytest.raises(InvalidInputError, match=f"repair.{key}: expected a finite number"):
            pmd.Model.from_urdf(urdf, repair={key: True})
        with pytest.raises(InvalidInputError, match=f"repair.{key}"):
            pmd.Model.from_urdf(urdf, repair=pmd.InertiaRepair(**{key: True}))


def test_assemble_refuses_iteration_counts_below_one():
    scene = pmd.load_scene("fourbar")
    for bad in (-1, 0, True, 10**30):
        with pytest.raises(InvalidInputError, match="max_iterations: expected a whole number"):
            scene.model.assemble(scene.q0, max_iterations=bad)
    q = scene.model.assemble(scene.q0 + 0.05, fixed=[0])
    assert np.abs(scene.model.constraint_residual(q)).max() < 1e-12
    assert q[0] == scene.q0[0] + 0.05


def test_assemble_velocity_overflow_is_a_numerical_error():
    from pointmass_dyn.errors import NumericalError

    scene = pmd.load_scene("fourbar")
    model = scene.model
    with pytest.raises(NumericalError, match="assemble_velocity: the result is not finite"):
        model.assemble_velocity(scene.q0, np.full(model.nv, 1e308))
    # Linear in the guess: 1e200 × the projection of ones, to rounding.
    unit = model.assemble_velocity(scene.q0, np.ones(model.nv))
    big = model.assemble_velocity(scene.q0, np.full(model.nv, 1e200))
    np.testing.assert_allclose(big / 1e200, unit, rtol=1e-12)
    assert np.abs(model.constraint_jacobian(scene.q0) @ unit).max() < 1e-12


def test_a_second_mimic_in_one_urdf_joint_is_refused(tmp_path):
    urdf = """<robot name="r">
      <link name="base"/>
      <link name="a"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="b"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="ja" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="jb" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/>
        <mimic joint="ja" multiplier="2"/><mimic joint="ja" multiplier="3"/></joint>
    </robot>"""
    path = tmp_path / "two_mimics.urdf"
    path.write_text(urdf)
    with pytest.raises(UrdfError, match="a second <mimic>: a joint mimics at most one joint"):
        pmd.Model.from_urdf(str(path), mimic=True)
    path.write_text(urdf.replace('<mimic joint="ja" multiplier="3"/>', ""))
    m = pmd.Model.from_urdf(str(path), mimic=True)
    assert len(m.couplings) == 1


def test_an_empty_loop_name_is_refused(fourbar):
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 0.01), pmd.Revolute([0, 0, 1]), name="a")
    m.add_body(pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 0.01), pmd.Revolute([0, 0, 1]),
               parent="a", translation=[1, 0, 0], name="b")
    for name in ("", "  "):
        with pytest.raises(InvalidInputError, match="name: expected a non-empty loop name"):
            m.add_loop("b", -1, pmd.Revolute([0, 0, 1]), translation_a=[1, 0, 0],
                       translation_b=[1, 0, 0], name=name)
    assert m.nloops == 0
    m.add_loop("b", -1, pmd.Revolute([0, 0, 1]), translation_a=[1, 0, 0], translation_b=[1, 0, 0])
    assert m.nloops == 1 and m.loop_names[0]


def test_empty_body_and_coupling_names_are_refused():
    # Found by this round's probes: a body and a coupling named "" (unnamed in every listing).
    m = pmd.Model()
    body = pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 0.01)
    with pytest.raises(InvalidInputError, match="name: expected a non-empty body name"):
        m.add_body(body, pmd.Revolute([0, 0, 1]), name="")
    m.add_body(body, pmd.Revolute([0, 0, 1]), name="a")
    m.add_body(body, pmd.Revolute([0, 0, 1]), parent="a", translation=[1, 0, 0], name="b")
    with pytest.raises(InvalidInputError, match="name: expected a non-empty coupling name"):
        m.add_coupling("b", "a", ratio=2.0, name=" ")
    assert m.couplings == []
    m.add_coupling("b", "a", ratio=2.0)
    assert m.couplings[0][0]


def test_blank_effect_names_are_refused_by_the_scene():
    # An effect's name is its output key: "" and "  " would be unnamed columns.
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 0.01), pmd.Revolute([0, 0, 1]),
               name="a")
    for name in ("", "  "):
        with pytest.raises(InvalidInputError, match=r"effects\[1\]\.name: expected a non-empty"):
            pmd.Scene(m, effects=[pmd.Gravity([0, 0, -9.81]), pmd.Spring("a", 1.0, name=name)])
    spring = pmd.Spring("a", 1.0, name="k")
    pmd.Scene(m, effects=[spring])
    assert "name='k'" in repr(spring)


@pytest.mark.parametrize("x", [1e-300, -1e-300, 1e300, -1e300, 1e-320])
def test_error_messages_write_extreme_numbers_in_exponent_form(x):
    # Rust's "{}" wrote 1e-300 as 0.000…0001 with 300 zeros.
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0, 0, 0], np.eye(3) * 0.01), pmd.Revolute([0, 0, 1]), name="a")
    gc = dict(stiffness=1e4, damping=10.0, friction=0.5)
    calls = [
        lambda: pmd.RigidBody(-abs(x), [0, 0, 0], np.eye(3)),
        lambda: pmd.simulate(pmd.Scene(m), (0, 1), rtol=-abs(x)),
        lambda: pmd.simulate(pmd.Scene(m), (0, 1), first_step=-abs(x)),
        lambda: pmd.simulate(pmd.Scene(m), (0, 1), t_eval=[-abs(x) - 1e-3]),
        lambda: pmd.Scene(m, effects=[pmd.GroundContact([("a", [0, 0, 0], 0.1)],
                                                        **{**gc, "damping": -abs(x)})]),
        lambda: pmd.JointLimit(lower=1.0, upper=1.0 - abs(x) if abs(x) > 1 else -abs(x),
                               stiffness=1.0, damping=1.0),
        lambda: m.set_armature("a", -abs(x)),
    ]
    for call in calls:
        with pytest.raises(pmd.errors.PointMassDynError) as info:
            call()
        assert not LONG_NUMBER.search(str(info.value)), str(info.value)[:200]


@pytest.mark.parametrize("joint", [1.0, None, [1]])
def test_a_joint_of_the_wrong_type_is_a_type_error_naming_the_argument(joint):
    # Was "'float' object cannot be interpreted as an integer": no argument named.
    with pytest.raises(TypeError, match="joint: expected a body index, a joint name or a body name"):
        _arm().add_coupling(joint, "upper")
    with pytest.raises(TypeError, match="joint: expected"):
        _arm().set_armature(joint, 0.1)


@pytest.mark.parametrize("arg", ["ratio", "offset"])
@pytest.mark.parametrize("value", [True, "x", [1.0, 2.0]])
def test_a_coupling_ratio_or_offset_that_is_not_a_number_is_refused(arg, value):
    # True was taken as 1.0 (bools are refused as numbers elsewhere); "x" and a list were a
    # TypeError without the argument's name.
    with pytest.raises(InvalidInputError, match=f"{arg}: expected"):
        _arm().add_coupling("fore", "upper", **{arg: value})


def test_armature_refuses_a_bool():
    with pytest.raises(InvalidInputError, match="value: expected .* got the bool True"):
        _arm().set_armature("fore", True)
