"""Closed loops against Pinocchio's constrained dynamics (``pin.constraintDynamics``, an
independent implementation: its own kinematics, constraint Jacobians, drift terms and KKT
solve). Random trees mixing every joint kind both libraries share (revolute and prismatic
about skew axes, quaternion spherical, ZYZ spherical as three revolutes, fixed), closed by
spherical (``CONTACT_3D``) and fixed (``CONTACT_6D``) cut joints between two body frames, at
states closed by our ``assemble``/``assemble_velocity``: accelerations and multipliers to
1e-8 relative, and Pinocchio's own view of the states (placement and velocity errors zero).

Multipliers. Pinocchio solves ``M q̈ + h = τ + Jᵀλ`` with ``J`` the velocity of the frame on
joint 1 relative to the frame on joint 2, in frame 1's axes (``ReferenceFrame.LOCAL``,
linear part first), so ``λ = [f; n]`` is the wrench the constraint applies to *joint 1's*
body at frame 1's origin, in frame 1's axes; joint 2's body gets the opposite. (Checked by
hand: a point mass held by a ``CONTACT_3D`` to the world under gravity has ``λ = +m g``
upwards with the mass as joint 1, and the opposite with the world as joint 1 — see
``test_pinocchio_multiplier_sign_on_a_hanging_mass``.) Ours (docs/loops.md) is ``[f; n]``
applied to *body b* at frame b's origin in frame a's axes. Here joint 1 is our body a with
frame 1 our frame a, so at a closed state (the two origins coincide) ``λ_pin = −ours``."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import (
    G,
    build_model,
    build_pinocchio,
    random_rotation,
    random_state,
    random_tree,
    record,
    rel_err,
)

pin = pytest.importorskip("pinocchio")

TOL = 1e-8


def carriers(tree):
    """The Pinocchio joint id carrying each of our bodies (0: the world) and the body's frame
    in that joint's frame (build_pinocchio's bookkeeping)."""
    out, jid = [], 0
    for b in tree.bodies:
        parent_joint, parent_frame = (0, pin.SE3.Identity()) if b.parent < 0 else out[b.parent]
        placement = parent_frame * pin.SE3(np.asarray(b.rotation), np.asarray(b.translation))
        if b.kind == "Fixed":
            out.append((parent_joint, placement))
        else:
            jid += 3 if b.kind == "SphericalZYZ" else 1
            out.append((jid, pin.SE3.Identity()))
    return out


def body_pose(model, q, k):
    """World rotation and origin of our body k (the world for k = −1)."""
    if k < 0:
        return np.eye(3), np.zeros(3)
    rot, org = model.placements(q)
    return rot[k], org[k]


def same_link(model, a, b):
    link = [-1 if k < 0 else model.body_info(k)[3] for k in (a, b)]
    return link[0] == link[1]


def closed_tree(seed, cuts, n=10, world_a=False):
    """A random tree (every kind, depth-first for Pinocchio's CRBA) and cut joints of the
    given kinds ("S", "F"), each between two random bodies with frame b placed where frame a
    is at a random q (`world_a`: the first cut's body a is the world). Pairs are drawn until
    the constraints are independent (full row rank, so the multipliers are unique and both
    libraries must agree on them) and leave motion."""
    rng = np.random.default_rng(seed)
    tree = random_tree(seed, n)
    base = build_model(tree)
    q0, _ = random_state(base, rng)
    for _attempt in range(50):
        model = build_model(tree)
        cuts_made = []
        for k, kind in enumerate(cuts):
            a, b = (int(x) for x in rng.choice(np.arange(-1, n), size=2, replace=False))
            if world_a and k == 0:
                a, b = -1, int(rng.integers(n))
            if same_link(model, a, b):
                break
            ra, pa = body_pose(model, q0, a)
            rb, pb = body_pose(model, q0, b)
            fa = (random_rotation(rng), rng.normal(scale=0.2, size=3))
            f_rot, f_org = ra @ fa[0], pa + ra @ fa[1]  # the cut frame in the world
            fb = (rb.T @ f_rot, rb.T @ (f_org - pb))
            joint = pmd.Spherical() if kind == "S" else pmd.Fixed()
            model.add_loop(a, b, joint, translation_a=fa[1], rotation_a=fa[0],
                           translation_b=fb[1], rotation_b=fb[0])
            cuts_made.append((kind, a, b, fa, fb))
        else:
            j = model.constraint_jacobian(q0)
            if np.linalg.matrix_rank(j, tol=1e-8) == j.shape[0] < model.nv:
                return tree, model, cuts_made, q0, rng
    raise AssertionError(f"seed {seed}: no independent cut joints found")


def pinocchio_constraints(tree, pm, cuts):
    """Pinocchio's constraint models for our cut joints: joint 1 = body a, joint 2 = body b,
    the frames as ours, LOCAL."""
    carry = carriers(tree)
    models = pin.StdVec_RigidConstraintModel()
    for kind, a, b, fa, fb in cuts:
        (j1, f1), (j2, f2) = [
            (0, pin.SE3.Identity()) if k < 0 else carry[k] for k in (a, b)
        ]
        models.append(pin.RigidConstraintModel(
            pin.ContactType.CONTACT_3D if kind == "S" else pin.ContactType.CONTACT_6D,
            pm, j1, f1 * pin.SE3(*fa), j2, f2 * pin.SE3(*fb), pin.ReferenceFrame.LOCAL,
        ))
        bg = models[-1].m_baumgarte_parameters
        assert bg.Kp == 0.0 and bg.Kd == 0.0  # no Baumgarte stabilisation: the exact KKT
    datas = pin.StdVec_RigidConstraintData()
    for c in models:
        datas.append(c.createData())
    return models, datas


def pinocchio_solve(pm, pd, q, v, tau, models, datas):
    pin.initConstraintDynamics(pm, pd, models, datas)
    # mu = 0: no proximal regularisation, one factorization of the (full-rank) KKT system.
    settings = pin.ProximalSettings(1e-14, 1e-14, 0.0, 1)
    a = pin.constraintDynamics(pm, pd, q, v, tau, models, datas, settings).copy()
    return a, pd.lambda_c.copy()


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("cuts", ["S", "F", "SF", "SS", "world-S", "world-F"])
def test_constrained_dynamics_matches_pinocchio(seed, cuts):
    world_a = cuts.startswith("world-")
    cuts = cuts.removeprefix("world-")
    tree, model, made, q0, rng = closed_tree(seed, cuts, world_a=world_a)
    if world_a:
        assert made[0][1] == -1  # Pinocchio's joint 1 is the universe (joint 0)
    pm, pd = build_pinocchio(tree, G)
    assert (pm.nq, pm.nv) == (model.nq, model.nv)
    # Another closed state near the construction one, and a consistent velocity, from ours.
    guess = q0 + 0.05 * rng.normal(size=model.nq)
    q = model.assemble(guess)
    v = model.assemble_velocity(q, rng.normal(size=model.nv))
    tau = rng.normal(size=model.nv)
    models, datas = pinocchio_constraints(tree, pm, made)
    a_pin, lam_pin = pinocchio_solve(pm, pd, q, v, tau, models, datas)
    # Pinocchio sees the loops closed and the velocity consistent (its own kinematics).
    for d in datas:
        assert np.abs(d.contact_placement_error.vector).max() < 1e-11
        assert np.abs(d.contact_velocity_error.vector).max() < 1e-11 * (1 + np.abs(v).max())
    a = model.forward_dynamics(q, v, tau, gravity=G)
    ea = record("pinocchio loops: q̈", rel_err(a, a_pin))
    assert ea <= TOL, ea
    forces = model.constraint_forces(q, v, tau, gravity=G)
    ours = []
    for (kind, *_), f in zip(made, forces):
        if kind == "S":
            assert np.all(f[3:] == 0.0)  # a ball joint carries no moment
            ours.append(-f[:3])
        else:
            ours.append(-f)
    el = record("pinocchio loops: λ", rel_err(np.concatenate(ours), lam_pin))
    assert el <= TOL, el


@pytest.mark.parametrize("cut_a_is_world", [False, True])
def test_pinocchio_multiplier_sign_on_a_hanging_mass(cut_a_is_world):
    """The convention by hand: a 2 kg point-like body on three prismatic joints (x, y, z)
    pinned to the world by a spherical cut joint, under gravity: it hangs still and the
    constraint carries its weight. Ours is locked (no freedom), so only Pinocchio's λ is
    checked here, against m g by hand: +m g (up) on joint 1's body when that is the mass."""
    pm = pin.Model()
    pm.gravity.linear = G
    jid = 0
    for axis in ("PX", "PY", "PZ"):
        jid = pm.addJoint(jid, getattr(pin, f"JointModel{axis}")(), pin.SE3.Identity(), axis)
        mass = 2.0 if axis == "PZ" else 0.5
        pm.appendBodyToJoint(jid, pin.Inertia(mass, np.zeros(3), 0.01 * np.eye(3)),
                             pin.SE3.Identity())
    pd = pm.createData()
    frame = pin.SE3(random_rotation(np.random.default_rng(1)), np.zeros(3))
    ends = (0, 3) if cut_a_is_world else (3, 0)
    c = pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, pm, ends[0], frame, ends[1], frame,
                                 pin.ReferenceFrame.LOCAL)
    models, datas = pin.StdVec_RigidConstraintModel(), pin.StdVec_RigidConstraintData()
    models.append(c)
    datas.append(c.createData())
    a, lam = pinocchio_solve(pm, pd, np.zeros(3), np.zeros(3), np.zeros(3), models, datas)
    np.testing.assert_allclose(a, 0.0, atol=1e-12)
    # The last body's weight only (the x and y carriages ride on their own joints).
    support = frame.rotation.T @ (-2.0 * G)  # upward force on the mass, in the cut frame
    np.testing.assert_allclose(lam, -support if cut_a_is_world else support, rtol=1e-12)
