"""Ground contact, joint limits and torque limits under bad input: lengths and bounds beyond any
mechanism, non-finite or unreadable states, malformed URDF contact points — each refused with a
``pmd.errors`` exception naming the argument (or the link), never a panic or a silent NaN."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn.errors import InvalidInputError


def _contact_ball():
    m = pmd.Model()
    m.add_body(pmd.RigidBody(2.0, [0, 0, 0], np.eye(3) * 0.002), pmd.Prismatic([0, 0, 1]),
               name="ball")
    contact = pmd.GroundContact([("ball", [0, 0, 0], 0.05)], stiffness=2e5, damping=5e5,
                                friction=0.0)
    return pmd.Scene(m, q0=[0.1], v0=[0.0], effects=[contact, pmd.Gravity([0, 0, -9.81])])


def test_torque_limit_message_says_inf_is_allowed():
    pmd.JointTorque(None, 1.0, limit=np.inf)  # accepted: no limit
    for bad in (np.nan, -1.0, [1.0, np.nan]):
        with pytest.raises(InvalidInputError, match=r"limit: expected numbers > 0.*inf: no limit"):
            pmd.JointTorque(None, 1.0, limit=bad)


def test_joint_limit_on_a_model_without_1dof_joints_says_so():
    # Was "lower: expected 0 values".
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0, 0, 0], np.eye(3) * 0.01), pmd.Spherical(), name="ball")
    with pytest.raises(InvalidInputError, match="a model that has no 1-dof joints"):
        pmd.Scene(m, effects=[pmd.JointLimit(lower=-1.0, upper=1.0, stiffness=1.0, damping=0.1)])


@pytest.mark.parametrize("bound", [1e308, -1e300, 2e9])
def test_joint_limit_bounds_beyond_any_mechanism_are_refused_up_front(bound):
    with pytest.raises(InvalidInputError, match=r"lower: expected numbers within ±1e9 \(rad or m\), or ±inf"):
        pmd.JointLimit(lower=bound, upper=np.inf, stiffness=1e3, damping=1.0)
    pmd.JointLimit(lower=-np.inf, upper=1e9, stiffness=1e3, damping=1.0)  # the bound itself


@pytest.mark.parametrize("where", ["offset", "radius", "height"])
def test_contact_lengths_beyond_any_mechanism_are_refused_up_front(where):
    point, kw = ("ball", [0, 0, 0], 0.05), dict(stiffness=2e5, damping=5e5, friction=0.0)
    if where == "offset":
        point = ("ball", [1e300, 0, 0], 0.05)
    elif where == "radius":
        point = ("ball", [0, 0, 0], 1e300)
    else:
        kw["height"] = -1e300
    with pytest.raises(InvalidInputError, match=r"within ±1e6 m|in \[0, 1e6\] m"):
        pmd.GroundContact([point], **kw)


def test_contact_forces_at_a_non_finite_state_are_refused():
    scene = _contact_ball()

    class Result:
        q = np.array([[0.1], [np.nan]])
        v = np.array([[0.0], [0.0]])

    with pytest.raises(InvalidInputError, match=r"q: expected finite states, got NaN in state 1"):
        pmd.contact_forces(scene, Result)


@pytest.mark.filterwarnings("error::numpy.exceptions.ComplexWarning")
def test_contact_forces_refuses_states_it_cannot_read():
    scene = _contact_ball()
    bad = [
        (np.array([[""]]), np.zeros((1, 1)), "result: expected a result with numeric q"),
        (np.array([[0.1 + 1j]]), np.zeros((1, 1)), "result: expected real q and v"),
    ]
    for q, v, message in bad:
        with pytest.raises(InvalidInputError, match=message):
            pmd.contact_forces(scene, type("R", (), {"q": q, "v": v}))


def test_contact_forces_at_a_zero_quaternion_or_an_overflowing_law_are_refused():
    # NaN positions for a zero quaternion; inf forces for a damping of 3e307 (both silent).
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0, 0, 0], np.eye(3) * 0.01), pmd.Spherical(), name="ball")
    contact = pmd.GroundContact([("ball", [0, 0, -0.1], 0.05)], stiffness=1e3, damping=3e307,
                                friction=0.0)
    scene = pmd.Scene(m, effects=[contact])

    class State:
        q = np.zeros((1, 4))
        v = np.zeros((1, 3))

    with pytest.raises(InvalidInputError, match=r"q \(state 0\): expected a quaternion"):
        pmd.contact_forces(scene, State)
    # A point 1.05 m deep moving into the ground at 10 m/s: c δ^e v overflows.
    State.q = np.array([[0.0, 0.0, 0.0, 1.0]])
    State.v = np.array([[0.0, 100.0, 0.0]])
    contact_low = pmd.GroundContact([("ball", [0.1, 0, 0], 0.05)], stiffness=1e3, damping=3e307,
                                    friction=0.0, height=1.0)
    with pytest.raises(pmd.errors.NumericalError, match=r"contact_state\['.*'\]: the result is not finite"):
        pmd.contact_forces(pmd.Scene(m, effects=[contact_low]), State)


def test_urdf_contact_spheres_of_nan_or_inf_are_refused(tmp_path):
    # float("inf") read a sphere of infinite radius, returned as it was.
    for radius, xyz in (("inf", "0 0 0"), ("nan", "0 0 0"), ("-0.1", "0 0 0"), ("0.1", "nan 0 0")):
        path = tmp_path / "r.urdf"
        path.write_text(
            f'<robot name="r"><link name="a"><collision><origin xyz="{xyz}"/><geometry>'
            f'<sphere radius="{radius}"/></geometry></collision></link></robot>')
        with pytest.raises(InvalidInputError, match="expected a finite <origin xyz> and a finite"):
            pmd.urdf_contact_points(path, ["a"])


@pytest.mark.parametrize("xyz, radius", [("0 x 0", "0.01"), ("0 0 0", "abc"), ("0 0", "0.01")])
def test_urdf_contact_points_with_malformed_numbers_name_the_link(tmp_path, xyz, radius):
    # Was a builtin ValueError ("could not convert string to float"), or a 2-vector point.
    path = tmp_path / "r.urdf"
    path.write_text(
        f'<robot name="r"><link name="foot"><collision><origin xyz="{xyz}"/>'
        f'<geometry><sphere radius="{radius}"/></geometry></collision></link></robot>'
    )
    with pytest.raises(InvalidInputError, match="link 'foot'"):
        pmd.urdf_contact_points(path, ["foot"])
