"""Frame Jacobians in Pinocchio's three reference frames and their time variation, against
Pinocchio's `getFrameJacobian` and `getFrameJacobianTimeVariation` on example-robot-data
URDFs (fixed and free base, three frames each: a welded link among them) to 1e-10 relative;
`J̇ v` against central differences of `J(q(t)) v`; the loop-closing map of the four-bar."""

from __future__ import annotations

import pickle

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import record, rel_err
from test_frames import pin_q, random_q, robot  # noqa: F401  (robot: the fixture)

pin = pytest.importorskip("pinocchio")

TOL = 1e-10
REFS = {
    "world": pin.ReferenceFrame.WORLD,
    "local": pin.ReferenceFrame.LOCAL,
    "local_world_aligned": pin.ReferenceFrame.LOCAL_WORLD_ALIGNED,
}
# Pinocchio's six-vectors are linear first, ours angular first.
SWAP = [3, 4, 5, 0, 1, 2]


def three_frames(pm) -> list[str]:
    """The last link, one in the middle and a link welded by a fixed joint (if any)."""
    bodies = [f for f in pm.frames if f.type == pin.FrameType.BODY]
    names = [bodies[-1].name, bodies[len(bodies) // 2].name]
    welded = [f.name for f in bodies if pm.frames[f.parentFrame].type == pin.FrameType.FIXED_JOINT]
    names.append(welded[-1] if welded else bodies[1].name)
    return names


def test_frame_jacobians_match_pinocchio(robot):  # noqa: F811
    name, model, pm = robot
    data = pm.createData()
    rng = np.random.default_rng(11)
    for _ in range(3):
        q = random_q(model, rng)
        v = rng.normal(size=model.nv)
        qp = pin_q(pm, model, q)
        pin.computeJointJacobians(pm, data, qp)
        pin.computeJointJacobiansTimeVariation(pm, data, qp, v)
        pin.updateFramePlacements(pm, data)
        for frame in three_frames(pm):
            fid = pm.getFrameId(frame, pin.FrameType.BODY)
            for ref, rf in REFS.items():
                j = model.frame_jacobian(frame, q, reference=ref)
                want = pin.getFrameJacobian(pm, data, fid, rf)[SWAP]
                assert record(f"frame jacobian {name}", rel_err(j, want)) < TOL, (frame, ref)
                jd = model.frame_jacobian_dot(frame, q, v, reference=ref)
                want = pin.getFrameJacobianTimeVariation(pm, data, fid, rf)[SWAP]
                # Relative to the size of its terms (|J| |v|): where J̇ is zero (a frame on a
                # free-flying base, LOCAL), Pinocchio's is rounding noise.
                scale = max(np.abs(want).max(), np.abs(j).max() * np.abs(v).max())
                err = np.abs(jd - want).max() / scale if scale > 0 else np.abs(jd - want).max()
                assert record(f"frame jacobian dot {name}", err) < TOL, (frame, ref)


def test_batched_frame_jacobians_match_pinocchio_and_one_configuration(robot):  # noqa: F811
    """The (N, nq) path (eight rows at a time, `frames::batch`) row by row against Pinocchio
    and against the one-configuration call (bit for bit): eleven rows (a full block of
    eight and a padded one), an angle beyond the fast sine's range in each block, a welded
    frame, an added frame with a rotation, every reference frame."""
    name, model, pm = robot
    model = pickle.loads(pickle.dumps(model))  # the fixture's model stays without the tool
    data = pm.createData()
    rng = np.random.default_rng(12)
    qs = np.array([random_q(model, rng) for _ in range(11)])
    if model.nq == pm.nq and all(pm.joints[j].nq == 1 for j in range(1, pm.njoints)):
        qs[[3, 9], 0] += 2e5  # angles beyond the branch-free sine's reduction (revolute joints)
    frames = three_frames(pm)
    tool = f"tool_{name}"
    model.add_frame(tool, frames[0], [0.1, -0.2, 0.3], pin.rpy.rpyToMatrix(0.3, -0.5, 0.7))
    for ref, rf in REFS.items():
        for frame in [*frames, tool]:
            jb = model.frame_jacobian(frame, qs, reference=ref)
            assert jb.shape == (11, 6, model.nv)
            for k, q in enumerate(qs):
                # The same operations in the same order: equal, not merely close.
                np.testing.assert_array_equal(jb[k], model.frame_jacobian(frame, q, reference=ref))
                if frame == tool:
                    continue
                qp = pin_q(pm, model, q)
                pin.computeJointJacobians(pm, data, qp)
                pin.updateFramePlacements(pm, data)
                fid = pm.getFrameId(frame, pin.FrameType.BODY)
                want = pin.getFrameJacobian(pm, data, fid, rf)[SWAP]
                assert record(f"batched frame jacobian {name}", rel_err(jb[k], want)) < TOL


def test_batched_jacobians_do_not_depend_on_how_q_is_laid_out():
    """A C-ordered float64 block short enough for one thread is read in place with the
    interpreter held; any other layout (Fortran order, a strided view, a list, a read-only
    array) or a block long enough for several threads is copied first. The same rows give
    the same bits whichever way, and a non-finite entry is refused by name either way."""
    model = pmd.robots.example_robot("panda")
    rng = np.random.default_rng(3)
    qs = np.array([random_q(model, rng) for _ in range(9)])
    frame = model.frame_names[-1]
    ref_j = model.frame_jacobian(frame, qs, reference="world")
    ref_c, ref_cj = model.center_of_mass(qs, jacobian=True)
    frozen = qs.copy()
    frozen.flags.writeable = False
    wide = np.zeros((9, 2 * model.nq))
    wide[:, ::2] = qs
    for q in (np.asfortranarray(qs), wide[:, ::2], qs.tolist(), frozen):
        np.testing.assert_array_equal(model.frame_jacobian(frame, q, reference="world"), ref_j)
        c, cj = model.center_of_mass(q, jacobian=True)
        np.testing.assert_array_equal(c, ref_c)
        np.testing.assert_array_equal(cj, ref_cj)
    # Enough rows for several threads (copied, detached): the first rows unchanged.
    many = np.concatenate([qs] * 4000)
    np.testing.assert_array_equal(model.frame_jacobian(frame, many, reference="world")[:9], ref_j)
    np.testing.assert_array_equal(model.center_of_mass(many, jacobian=True)[1][:9], ref_cj)
    bad = qs.copy()
    bad[4, 2] = np.nan
    for q in (bad, np.asfortranarray(bad)):
        with pytest.raises(pmd.errors.InvalidInputError, match="q"):
            model.frame_jacobian(frame, q)
        with pytest.raises(pmd.errors.InvalidInputError, match="q"):
            model.center_of_mass(q, jacobian=True)


def test_frame_velocity_and_acceleration_match_pinocchio(robot):  # noqa: F811
    name, model, pm = robot
    data = pm.createData()
    rng = np.random.default_rng(5)
    q = random_q(model, rng)
    v, a = rng.normal(size=model.nv), rng.normal(size=model.nv)
    pin.forwardKinematics(pm, data, pin_q(pm, model, q), v, a)
    frame = three_frames(pm)[0]
    fid = pm.getFrameId(frame, pin.FrameType.BODY)
    for ref in ("world", "local"):
        vel, acc = model.frame_motion(frame, q, v, a, reference=ref)
        want_v = pin.getFrameVelocity(pm, data, fid, REFS[ref]).vector[SWAP]
        want_a = pin.getFrameAcceleration(pm, data, fid, REFS[ref]).vector[SWAP]
        assert rel_err(vel, want_v) < TOL and rel_err(acc, want_a) < TOL, ref
    # LOCAL_WORLD_ALIGNED: the linear part is the classical acceleration of the frame origin.
    vel, acc = model.frame_motion(frame, q, v, a, reference="local_world_aligned")
    want = pin.getFrameClassicalAcceleration(pm, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
    assert rel_err(acc[3:], want.linear) < TOL


@pytest.mark.parametrize("name", ["panda", "ur5", "solo12-free"])
def test_jdot_v_is_the_derivative_of_j_v(name, request):
    from conftest import FLOATING, robots_dir
    from test_frames import FIXED, load

    root = robots_dir()
    if root is None:
        pytest.skip("example-robot-data not installed")
    free = name.endswith("-free")
    path = str(root / (FLOATING if free else FIXED)[name.removesuffix("-free")])
    model, pm = load(path, free)
    rng = np.random.default_rng(2)
    q = random_q(model, rng)
    v = rng.normal(size=model.nv)
    frame = three_frames(pm)[0]
    h = 1e-5
    for ref in REFS:
        jdv = model.frame_jacobian_dot(frame, q, v, reference=ref) @ v
        jp = model.frame_jacobian(frame, pin.integrate(pm, q, v * h), reference=ref)
        jm = model.frame_jacobian(frame, pin.integrate(pm, q, -v * h), reference=ref)
        fd = (jp - jm) @ v / (2 * h)
        assert rel_err(jdv, fd) < 1e-7, ref


def fourbar():
    return pmd.load_scene("fourbar")


def test_jacobian_in_independent_coordinates_keeps_the_loop_closed():
    scene = fourbar()
    model, q = scene.model, scene.q0
    g, idx = model.independent_map(q)
    # The four-bar has one degree of freedom: one independent speed, and G's column a
    # velocity the constraints allow (J_c G = 0), scaled so that the independent speed is 1.
    assert len(idx) == 1 and g.shape == (model.nv, 1)
    assert g[idx[0], 0] == 1.0
    jc = model.constraint_jacobian(q)
    assert np.abs(jc @ g).max() < 1e-12 * np.abs(jc).max()
    g_crank, idx_crank = model.independent_map(q, independent=["crank"])
    assert idx_crank == [0]
    # With the crank independent, the frame Jacobian in the crank's speed moves the coupler
    # as the closed mechanism does: compare with a step along the closed motion.
    frame = "coupler"
    jg = model.frame_jacobian(frame, q, reference="local_world_aligned") @ g_crank
    h = 1e-6
    qp = model.assemble(q + h * g_crank[:, 0], fixed=["crank"])
    qm = model.assemble(q - h * g_crank[:, 0], fixed=["crank"])
    fd = (model.frame_placement(frame, qp)[1] - model.frame_placement(frame, qm)[1]) / (2 * h)
    np.testing.assert_allclose(fd, jg[3:, 0], rtol=1e-6, atol=1e-12)
    with pytest.raises(pmd.errors.InvalidInputError, match="independent"):
        model.independent_map(q, independent=["crank", "coupler", "rocker"])
