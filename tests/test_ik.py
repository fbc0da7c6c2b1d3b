"""Inverse kinematics: Panda, UR5 and a Talos arm reach random reachable targets (the poses
of random configurations within the limits) from the neutral configuration to 1e-10 in at
least 99 % of the tries, within their joint limits; an unreachable target ends with the
closest reach and converged=False; the README four-bar's coupler point reaches a point of its
coupler curve (closed form) with the loop closed."""

from __future__ import annotations

import math

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import record
from test_frames import FIXED, load, random_q

pin = pytest.importorskip("pinocchio")

TRIES = 200


def arm(name: str):
    from conftest import robots_dir

    root = robots_dir()
    if root is None:
        pytest.skip("example-robot-data not installed")
    files = dict(FIXED, talos="talos_data/robots/talos_left_arm.urdf")
    model, _ = load(str(root / files[name]), False)
    return model


def limits(model):
    lim = np.array([(lo, hi) for lo, hi, _, _ in model.joint_limits().values()])
    return lim[:, 0], lim[:, 1]


@pytest.mark.parametrize("name,frame", [("panda", "panda_hand"), ("ur5", "tool0"), ("talos", "gripper_left_base_link")])
def test_random_reachable_poses_are_reached(name, frame):
    model = arm(name)
    if frame not in model.frame_names:
        frame = model.frame_names[-1]
    rng = np.random.default_rng(41)
    lo, hi = limits(model)
    reached = 0
    worst_iterations = 0
    for _ in range(TRIES):
        q_goal = random_q(model, rng)
        rot, pos = model.frame_placement(frame, q_goal)
        res = pmd.inverse_kinematics(model, {frame: (rot, pos)})
        r, t = model.frame_placement(frame, res.q)
        err = max(np.abs(t - pos).max(), np.abs(r - rot).max())
        assert np.all(res.q >= lo - 1e-12) and np.all(res.q <= hi + 1e-12), "limits"
        if res.converged:
            # The reported residual is what the configuration reaches.
            assert err < 1e-9 and res.residual <= 1e-10
            reached += 1
        worst_iterations = max(worst_iterations, res.iterations)
    record(f"ik misses {name} (of {TRIES})", TRIES - reached)
    assert reached >= 0.99 * TRIES, f"{name}: reached {reached} of {TRIES}"


def test_several_targets_and_weights():
    model = arm("panda")
    q_goal = random_q(model, np.random.default_rng(8))
    hand = model.frame_placement("panda_hand", q_goal)
    elbow = model.frame_placement("panda_link4", q_goal)[1]
    res = pmd.inverse_kinematics(model, {"panda_hand": hand, "panda_link4": elbow},
                                 weights={"panda_link4": 0.5})
    assert res.converged, res.message
    np.testing.assert_allclose(model.frame_placement("panda_link4", res.q)[1], elbow, atol=1e-9)
    assert set(res.errors) == {"panda_hand", "panda_link4"}


def test_unreachable_target_gives_the_closest_reach():
    model = arm("panda")
    target = np.array([3.0, 0.0, 0.5])
    res = pmd.inverse_kinematics(model, {"panda_hand": target}, restarts=2, max_iterations=50)
    assert not res.converged and "not converged" in res.message
    reach = model.frame_placement("panda_hand", res.q)[1]
    # Stretched towards the target: the hand is about a reach (~1 m) from the base,
    # on the target's side.
    assert reach[0] > 0.7 and abs(reach[1]) < 0.05
    assert res.iterations <= 3 * 50
    with pytest.raises(pmd.errors.NumericalError, match="not converged"):
        res.raise_for_status()


def test_bad_targets_name_the_argument():
    model = arm("panda")
    with pytest.raises(pmd.errors.InvalidInputError, match="no frame named 'hand'.*panda_link0"):
        pmd.inverse_kinematics(model, {"hand": [0.3, 0, 0.5]})
    with pytest.raises(pmd.errors.InvalidInputError, match="targets"):
        pmd.inverse_kinematics(model, {"panda_hand": [0.3, 0]})
    with pytest.raises(pmd.errors.InvalidInputError, match="weights"):
        pmd.inverse_kinematics(model, {"panda_hand": [0.3, 0, 0.5]}, weights=[1, 2])
    with pytest.raises(pmd.errors.InvalidInputError, match="q0"):
        pmd.inverse_kinematics(model, {"panda_hand": [0.3, 0, 0.5]}, q0=np.zeros(3))


# The README four-bar: crank a, coupler b, rocker c, ground d; a coupler point at (px, py)
# in the coupler's frame.
A, B, C, D = 0.035, 0.09, 0.07, 0.1
PX, PY = 0.045, 0.02


def coupler_point(theta: float) -> np.ndarray:
    """Closed form: the crank's end, the rocker's end as the intersection of two circles
    (the open assembly, left of the line from the crank's end to the rocker's pivot)."""
    pa = A * np.array([math.cos(theta), math.sin(theta)])
    dv = np.array([D, 0.0]) - pa
    dist = np.linalg.norm(dv)
    u = dv / dist
    along = (B * B - C * C + dist * dist) / (2 * dist)
    pb = pa + along * u + math.sqrt(B * B - along * along) * np.array([-u[1], u[0]])
    e = (pb - pa) / B
    return pa + PX * e + PY * np.array([-e[1], e[0]])


def test_fourbar_coupler_curve_is_the_closed_form():
    scene = pmd.load_scene("fourbar")
    res = pmd.simulate(scene, (0.0, 0.2), t_eval=np.linspace(0.0, 0.2, 41))
    path = res.point_path("coupler", (PX, PY, 0.0))
    want = np.array([coupler_point(th) for th in res.q[:, 0]])
    err = np.abs(path[:, :2] - want).max()
    assert record("coupler curve vs closed form", err) < 1e-9
    assert np.abs(path[:, 2]).max() < 1e-15


def test_fourbar_coupler_point_reaches_its_curve_with_the_loop_closed():
    scene = pmd.load_scene("fourbar")
    model = scene.model
    model.add_frame("coupler_point", "coupler", (PX, PY, 0.0))
    target = np.append(coupler_point(2.0), 0.0)
    res = pmd.inverse_kinematics(model, {"coupler_point": target}, q0=scene.q0)
    assert res.converged, res.message
    np.testing.assert_allclose(model.frame_placement("coupler_point", res.q)[1], target, atol=1e-10)
    assert np.abs(model.constraint_residual(res.q)).max() < 1e-10
