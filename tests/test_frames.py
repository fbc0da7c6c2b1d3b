"""Frames (every URDF link, welded ones included, and frames added by hand) against
Pinocchio's `framesForwardKinematics` on example-robot-data URDFs, fixed and free base, to
1e-10 relative; placements at N configurations; paths along a trajectory; pickling; errors."""

from __future__ import annotations

import math
import pickle
import warnings

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import FLOATING, record, rel_err, robots_dir

pin = pytest.importorskip("pinocchio")

TOL = 1e-10

# Fixed-base robots (continuous joints included: kinova's q is its angle, Pinocchio's cos/sin).
FIXED = {
    "panda": "panda_description/urdf/panda.urdf",
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
    "baxter": "baxter_description/urdf/baxter.urdf",
    "tiago": "tiago_description/robots/tiago.urdf",
}


def load(path: str, free: bool):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pmd.errors.UrdfWarning)
        model = pmd.Model.from_urdf(path, root_joint="free" if free else None, mimic=False)
    pm = (
        pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())
        if free
        else pin.buildModelFromUrdf(path)
    )
    return model, pm


def pin_q(pm, model: pmd.Model, q: np.ndarray) -> np.ndarray:
    """Our q as Pinocchio's (continuous joints as cos, sin; a free flyer as it is)."""
    slot = {n: s for n, s in zip(model.joint_names, model.joint_slices())}
    out = np.empty(pm.nq)
    for j in range(1, pm.njoints):
        jm = pm.joints[j]
        s = slot[pm.names[j]]
        x = q[s[0] : s[0] + jm.nq] if jm.nq != 2 else q[s[0]]
        if jm.nq == 2:
            out[jm.idx_q : jm.idx_q + 2] = [math.cos(x), math.sin(x)]
        else:
            out[jm.idx_q : jm.idx_q + jm.nq] = x
    return out


def random_q(model: pmd.Model, rng) -> np.ndarray:
    q = model.neutral()
    slices = model.joint_slices()
    for (lo, hi, _, _), (s, _, nq, _) in zip(model.joint_limits().values(), slices):
        if nq == 7:  # free flyer: a position and a unit quaternion
            q[s : s + 3] = rng.normal(size=3)
            quat = rng.normal(size=4)
            q[s + 3 : s + 7] = quat / np.linalg.norm(quat)
        elif math.isfinite(lo) and math.isfinite(hi) and lo < hi:
            q[s] = rng.uniform(lo, hi)
        else:
            q[s] = rng.uniform(-math.pi, math.pi)
    return q


def robots():
    root = robots_dir()
    if root is None:
        return []
    out = [(name, str(root / f), False) for name, f in FIXED.items()]
    out += [(name + "-free", str(root / f), True) for name, f in FLOATING.items()]
    return out


@pytest.fixture(scope="module", params=robots() or [None], ids=lambda p: p[0] if p else "none")
def robot(request):
    if request.param is None:
        pytest.skip("example-robot-data not installed")
    name, path, free = request.param
    model, pm = load(path, free)
    return name, model, pm


def test_every_link_is_a_frame_and_placements_match_pinocchio(robot):
    name, model, pm = robot
    data = pm.createData()
    rng = np.random.default_rng(7)
    links = [f.name for f in pm.frames if f.type == pin.FrameType.BODY]
    # Every URDF link is a frame (welded ones too: Pinocchio's BODY frames).
    assert set(links) <= set(model.frame_names)
    qs = np.array([random_q(model, rng) for _ in range(4)])
    for q in qs:
        pin.framesForwardKinematics(pm, data, pin_q(pm, model, q))
        for link in links:
            ref = data.oMf[pm.getFrameId(link, pin.FrameType.BODY)]
            r, t = model.frame_placement(link, q)
            assert record(f"frame placement {name}", rel_err(t, ref.translation) + rel_err(r, ref.rotation)) < TOL, link
    # N configurations in one call: the same as one by one.
    r_all, t_all = model.frame_placement(links[-1], qs)
    assert r_all.shape == (4, 3, 3) and t_all.shape == (4, 3)
    for k in range(4):
        r, t = model.frame_placement(links[-1], qs[k])
        np.testing.assert_array_equal(r_all[k], r)
        np.testing.assert_array_equal(t_all[k], t)


def test_added_frame_is_where_pinocchio_puts_it():
    root = robots_dir()
    if root is None:
        pytest.skip("example-robot-data not installed")
    model, pm = load(str(root / FIXED["panda"]), False)
    rot = pin.utils.rpyToMatrix(0.1, -0.2, 0.3)
    model.add_frame("tool", "panda_hand", (0.0, 0.02, 0.1), rot)
    parent = pm.frames[pm.getFrameId("panda_hand")]
    pm.addFrame(
        pin.Frame("tool", parent.parentJoint, pm.getFrameId("panda_hand"),
                  parent.placement * pin.SE3(rot, np.array([0.0, 0.02, 0.1])), pin.FrameType.OP_FRAME)
    )
    data = pm.createData()
    q = random_q(model, np.random.default_rng(3))
    pin.framesForwardKinematics(pm, data, q)
    r, t = model.frame_placement("tool", q)
    ref = data.oMf[pm.getFrameId("tool")]
    assert rel_err(t, ref.translation) < TOL and rel_err(r, ref.rotation) < TOL
    assert model.frame_names[-1] == "tool"


def pendulum() -> pmd.Model:
    m = pmd.Model()
    body = pmd.RigidBody(1.0, (0.5, 0.0, 0.0), np.diag([0.01, 0.1, 0.1]))
    a = m.add_body(body, pmd.Revolute((0, 0, 1)), name="arm")
    m.add_body(body, pmd.Fixed(), parent=a, translation=(1.0, 0.0, 0.0), name="welded")
    return m


def test_frames_survive_pickle_and_scene():
    m = pendulum()
    m.add_frame("tip", "welded", (0.2, 0.0, 0.0))
    again = pickle.loads(pickle.dumps(m))
    assert again.frame_names == ["arm", "welded", "tip"]
    q = np.array([0.4])
    np.testing.assert_array_equal(again.frame_placement("tip", q)[1], m.frame_placement("tip", q)[1])
    scene = pmd.Scene(m, q, [0.0])
    assert pickle.loads(pickle.dumps(scene)).model.frame_names == m.frame_names
    # Angle 0.4 about z: the tip is 1.2 m along the arm.
    np.testing.assert_allclose(m.frame_placement("tip", q)[1], [1.2 * math.cos(0.4), 1.2 * math.sin(0.4), 0], atol=1e-15)


def test_point_path_along_a_trajectory_is_the_circle():
    m = pendulum()
    scene = pmd.Scene(m, [0.0], [2.0])  # no gravity: uniform rotation at 2 rad/s
    res = pmd.simulate(scene, (0.0, 1.0), t_eval=np.linspace(0, 1, 11), rtol=1e-10, atol=1e-12)
    pos, vel = res.point_path("welded", (0.5, 0.0, 0.0), velocities=True)
    ang = 2.0 * res.t
    np.testing.assert_allclose(pos[:, 0], 1.5 * np.cos(ang), atol=1e-8)
    np.testing.assert_allclose(vel[:, 1], 3.0 * np.cos(ang), atol=1e-8)
    rot, org = res.frame_path("welded")
    np.testing.assert_allclose(org[:, 1], np.sin(ang), atol=1e-8)
    assert rot.shape == (11, 3, 3)


def test_bad_frames_and_shapes_name_the_argument():
    m = pendulum()
    with pytest.raises(pmd.errors.InvalidInputError, match=r"frame.*no frame named 'hand'.*'arm', 'welded'"):
        m.frame_placement("hand", [0.0])
    with pytest.raises(pmd.errors.InvalidInputError, match=r"q: .*shape \(1,\) or \(N, 1\)"):
        m.frame_placement("arm", [0.0, 1.0])
    with pytest.raises(pmd.errors.InvalidInputError, match=r"q\[1\]"):
        m.frame_placement("arm", [[0.0], [float("nan")]])
    with pytest.raises(pmd.errors.InvalidInputError, match="already exists"):
        m.add_frame("arm", 0)
    with pytest.raises(pmd.errors.InvalidInputError, match="reference"):
        m.frame_jacobian("arm", [0.0], reference="global")


def test_mujoco_sites_are_frames_where_mujoco_puts_them():
    mujoco = pytest.importorskip("mujoco")
    xml = """<mujoco><worldbody><body name="a" pos="0 0 1">
      <joint name="j1" type="hinge" axis="0 1 0" pos="0 0 0.1" ref="0.3"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05"/>
      <site name="tip" pos="0.5 0.02 0" quat="0.9 0.1 0.3 0.2"/>
      <body name="b" pos="0.5 0 0"><joint type="slide" axis="1 0 0" ref="0.1"/>
        <geom type="sphere" size="0.05"/><site name="probe" pos="0.1 0.2 0.3"/></body>
    </body></worldbody></mujoco>"""
    mj = mujoco.MjModel.from_xml_string(xml)
    model = pmd.from_mujoco(mj)
    assert {"tip", "probe"} <= set(model.frame_names)
    data = mujoco.MjData(mj)
    data.qpos[:] = [0.7, -0.15]
    mujoco.mj_kinematics(mj, data)
    for k, name in enumerate(["tip", "probe"]):
        r, t = model.frame_placement(name, np.array([0.7, -0.15]))
        np.testing.assert_allclose(t, data.site_xpos[k], atol=1e-12)
        np.testing.assert_allclose(r, data.site_xmat[k].reshape(3, 3), atol=1e-12)


def test_a_frame_index_in_frame_names_is_that_frame():
    m = pendulum()
    m.add_frame("tip", "welded", (0.2, 0.0, 0.0))
    q = np.array([0.4])
    for k, name in enumerate(m.frame_names):
        np.testing.assert_array_equal(m.frame_jacobian(k, q), m.frame_jacobian(name, q))
        np.testing.assert_array_equal(m.frame_placement(k, q)[1], m.frame_placement(name, q)[1])
    # Index 2 is the added frame: 1.2 m along the arm turned by 0.4 about z.
    np.testing.assert_allclose(m.frame_placement(2, q)[1], [1.2 * math.cos(0.4), 1.2 * math.sin(0.4), 0], atol=1e-15)
    with pytest.raises(pmd.errors.InvalidInputError, match=r"frame: expected a frame name or index.*got 3"):
        m.frame_jacobian(3, q)


def test_large_batches_equal_one_call_per_configuration():
    # Big enough to be split over threads where there are several cores: each row is
    # still the single call's, bit for bit; a bad row is named.
    root = robots_dir()
    if root is None:
        pytest.skip("example-robot-data not installed")
    model, _ = load(str(root / FIXED["panda"]), False)
    rng = np.random.default_rng(5)
    qs = np.array([random_q(model, rng) for _ in range(8000)])
    jac = model.frame_jacobian("panda_hand", qs, reference="world")
    com, jcom = model.center_of_mass(qs, jacobian=True)
    for k in range(0, 8000, 13):
        np.testing.assert_array_equal(jac[k], model.frame_jacobian("panda_hand", qs[k], reference="world"))
        c, j = model.center_of_mass(qs[k], jacobian=True)
        np.testing.assert_array_equal(com[k], c)
        np.testing.assert_array_equal(jcom[k], j)
    qs[3001, 2] = np.inf
    with pytest.raises(pmd.errors.InvalidInputError, match=r"q\[3001\]"):
        model.frame_jacobian("panda_hand", qs)
    with pytest.raises(pmd.errors.InvalidInputError, match=r"q\[3001\]"):
        model.center_of_mass(qs, jacobian=True)


def test_batched_jacobians_refuse_a_result_that_overflows():
    # Two slides of 1.5e308 each along x: every input is finite, the second link's origin
    # is not, so the Jacobian's linear rows are NaN (0 · inf). The batched path must say so
    # as the one-configuration call does, not hand back NaN, and a sane row stays accepted.
    m = pmd.Model()
    body = pmd.RigidBody(1.0, (0.0, 0.0, 0.0), np.eye(3) * 0.1)
    a = m.add_body(body, pmd.Prismatic((1, 0, 0)), name="a")
    m.add_body(body, pmd.Prismatic((1, 0, 0)), parent=a, name="b")
    huge = np.array([[0.1, 0.2], [1.5e308, 1.5e308]])
    for ref in ("world", "local", "local_world_aligned"):
        with pytest.raises(pmd.errors.NumericalError):
            m.frame_jacobian("b", huge[1], reference=ref)
        with pytest.raises(pmd.errors.NumericalError, match="overflows"):
            m.frame_jacobian("b", huge, reference=ref)
        assert np.isfinite(m.frame_jacobian("b", huge[:1], reference=ref)).all()
