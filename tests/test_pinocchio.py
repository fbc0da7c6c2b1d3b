"""Agreement with Pinocchio (an independent rigid-body implementation) to ≤ 1e-9 relative:
the paper's spatial pendulum (ZYZ spherical joint = revolute Z, Y, Z with two massless bodies)
and random trees of ≥ 10 bodies mixing every joint kind, for mass matrix, bias forces,
gravity, forward and inverse dynamics, both methods, plus kinematics (placements, twists) and
external wrenches."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import (
    KINDS,
    BodySpec,
    G,
    TreeSpec,
    build_model,
    build_pinocchio,
    paper_pendulum_tree,
    random_body,
    random_rotation,
    random_state,
    random_tree,
    record,
    rel_err,
)
from hypothesis import given, settings
from hypothesis import strategies as st

pin = pytest.importorskip("pinocchio")

TOL = 1e-9
METHODS = ["recursive", "denoc"]


def pin_mass_matrix(pm, pd, q):
    m = pin.crba(pm, pd, q).copy()
    return np.triu(m) + np.triu(m, 1).T


def compare_all(model, pm, pd, q, v, tau, a, label):
    """Every dynamics quantity against Pinocchio; returns {name: relative error}."""
    errs = {}
    m_ref = pin_mass_matrix(pm, pd, q)
    nle_ref = pin.nle(pm, pd, q, v).copy()
    aba_ref = pin.aba(pm, pd, q, v, tau).copy()
    rnea_ref = pin.rnea(pm, pd, q, v, a).copy()
    grav_ref = pin.computeGeneralizedGravity(pm, pd, q).copy()
    g = pm.gravity.linear.copy()
    for method in METHODS:
        errs[f"mass_matrix[{method}]"] = rel_err(model.mass_matrix(q, method=method), m_ref)
        errs[f"forward_dynamics[{method}]"] = rel_err(
            model.forward_dynamics(q, v, tau, g, method=method), aba_ref
        )
        errs[f"inverse_dynamics[{method}]"] = rel_err(
            model.inverse_dynamics(q, v, a, g, method=method), rnea_ref
        )
    errs["bias_forces"] = rel_err(model.bias_forces(q, v, g), nle_ref)
    errs["gravity_forces (= −generalized gravity)"] = rel_err(-model.gravity_forces(q, g), grav_ref)
    errs["C v (= nle without gravity)"] = rel_err(
        model.convective_matrix(q, v) @ v, nle_ref - grav_ref
    )
    for k, e in errs.items():
        record(f"pinocchio {label}: {k}", e)
    return errs


# ---------------------------------------------------------------------------------------------
# The paper's pendulum
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "q_deg, v",
    [
        ([90, 45, 45], [0, 1, 0]),  # the paper's spatial run
        ([90, 90, 90], [0, 0, 0]),  # the paper's planar run
        ([30, 120, -70], [0.4, -1.3, 2.2]),
        ([-150, 10, 200], [3.0, 0.5, -1.0]),
    ],
)
def test_paper_pendulum_matches_pinocchio(q_deg, v):
    tree = paper_pendulum_tree()
    model = build_model(tree)
    pm, pd = build_pinocchio(tree, G)
    assert pm.nq == model.nq == 3 and pm.nv == model.nv == 3
    q = np.radians(q_deg)
    v = np.asarray(v, float)
    rng = np.random.default_rng(0)
    errs = compare_all(
        model, pm, pd, q, v, rng.normal(size=3), rng.normal(size=3), "paper pendulum"
    )
    bad = {k: e for k, e in errs.items() if not e <= TOL}
    assert not bad, bad


def test_pinocchio_accepts_massless_intermediate_bodies():
    """The ZYZ stand-in uses zero inertias between the three revolutes; Pinocchio's ABA
    handles them (checked against its own CRBA) — so the reference itself is sound."""
    tree = paper_pendulum_tree()
    pm, pd = build_pinocchio(tree, G)
    assert pm.inertias[1].mass == 0 and pm.inertias[2].mass == 0
    q = np.radians([20, 70, 10])
    v = np.array([0.3, -0.2, 0.5])
    tau = np.array([0.1, 0.2, -0.3])
    m = pin_mass_matrix(pm, pd, q)
    a = pin.aba(pm, pd, q, v, tau).copy()
    assert rel_err(m @ a + pin.nle(pm, pd, q, v), tau) <= 1e-12


# ---------------------------------------------------------------------------------------------
# Random trees
# ---------------------------------------------------------------------------------------------


def check_tree(seed, n=12, kinds=KINDS, dfs=True):
    tree = random_tree(seed, n, kinds=kinds, dfs=dfs)
    assert len(tree.bodies) >= 10
    model = build_model(tree)
    pm, pd = build_pinocchio(tree, G)
    assert (pm.nq, pm.nv) == (model.nq, model.nv)
    rng = np.random.default_rng(seed + 77)
    q, v = random_state(model, rng)
    tau = rng.normal(size=model.nv)
    a = rng.normal(size=model.nv)
    return tree, model, pm, pd, q, v, tau, a


@pytest.mark.parametrize("seed", range(12))
def test_random_tree_matches_pinocchio(seed):
    tree, model, pm, pd, q, v, tau, a = check_tree(seed)
    assert set(tree.kinds()) == set(KINDS)  # every joint kind in every tree
    errs = compare_all(model, pm, pd, q, v, tau, a, "random trees")
    bad = {k: e for k, e in errs.items() if not e <= TOL}
    assert not bad, bad


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(1000, 2**31), n=st.integers(10, 16))
def test_random_tree_matches_pinocchio_hypothesis(seed, n):
    _, model, pm, pd, q, v, tau, a = check_tree(seed, n)
    errs = compare_all(model, pm, pd, q, v, tau, a, "random trees")
    bad = {k: e for k, e in errs.items() if not e <= TOL}
    assert not bad, bad


@pytest.mark.parametrize("kind", ["Revolute", "Prismatic", "Spherical", "SphericalZYZ"])
def test_single_kind_chains_match_pinocchio(kind):
    _, model, pm, pd, q, v, tau, a = check_tree(5, 10, kinds=(kind,))
    errs = compare_all(model, pm, pd, q, v, tau, a, "single-kind trees")
    bad = {k: e for k, e in errs.items() if not e <= TOL}
    assert not bad, bad


@pytest.mark.parametrize("seed", range(4))
def test_non_depth_first_trees(seed):
    """Bodies added in any order (parents first, but not depth-first). Pinocchio's CRBA is not
    valid for such joint orders, so the reference mass matrix is built column by column from
    RNEA: M e_k = rnea(q, 0, e_k) − rnea(q, 0, 0)."""
    _, model, pm, pd, q, v, tau, a = check_tree(seed, 12, dfs=False)
    zero = np.zeros(model.nv)
    base = pin.rnea(pm, pd, q, zero, zero).copy()
    m_ref = np.column_stack([pin.rnea(pm, pd, q, zero, e).copy() - base for e in np.eye(model.nv)])
    for method in METHODS:
        assert rel_err(model.mass_matrix(q, method=method), m_ref) <= TOL
        assert (
            rel_err(model.forward_dynamics(q, v, tau, G, method=method), pin.aba(pm, pd, q, v, tau))
            <= TOL
        )
        assert (
            rel_err(model.inverse_dynamics(q, v, a, G, method=method), pin.rnea(pm, pd, q, v, a))
            <= TOL
        )
    assert rel_err(model.bias_forces(q, v, G), pin.nle(pm, pd, q, v)) <= TOL


@pytest.mark.parametrize("seed", range(3))
def test_no_gravity_by_default(seed):
    """gravity=None (the default) is zero gravity: Pinocchio with model.gravity = 0."""
    tree = random_tree(seed, 10)
    model = build_model(tree)
    pm, pd = build_pinocchio(tree, gravity=None)
    rng = np.random.default_rng(seed)
    q, v = random_state(model, rng)
    tau = rng.normal(size=model.nv)
    assert rel_err(model.forward_dynamics(q, v, tau), pin.aba(pm, pd, q, v, tau)) <= TOL
    assert rel_err(model.bias_forces(q, v), pin.nle(pm, pd, q, v)) <= TOL
    assert rel_err(model.inverse_dynamics(q, v, tau), pin.rnea(pm, pd, q, v, tau)) <= TOL


# ---------------------------------------------------------------------------------------------
# Kinematics and external wrenches
# ---------------------------------------------------------------------------------------------


def carriers(tree, pm):
    """Pinocchio joint id carrying each of our bodies (0: the world) and the body's frame in
    that joint's frame — the same bookkeeping as build_pinocchio, reread from the tree."""
    out = []
    jid = 0
    for b in tree.bodies:
        parent_joint, parent_frame = (0, pin.SE3.Identity()) if b.parent < 0 else out[b.parent]
        placement = parent_frame * pin.SE3(np.asarray(b.rotation), np.asarray(b.translation))
        if b.kind == "Fixed":
            out.append((parent_joint, placement))
        else:
            jid += 3 if b.kind == "SphericalZYZ" else 1
            out.append((jid, pin.SE3.Identity()))
    return out


@pytest.mark.parametrize("seed", range(6))
def test_placements_and_twists_match_pinocchio(seed):
    tree, model, pm, pd, q, v, _, _ = check_tree(seed)
    pin.forwardKinematics(pm, pd, q, v)
    rots, origins = model.placements(q)
    den = model.denoc(q)
    twists = den["Nl"] @ den["Nd"] @ v  # t_i = [ω_i; velocity of O_i], world axes
    link = 0
    for k, (jid, frame) in enumerate(carriers(tree, pm)):
        world = pd.oMi[jid] * frame
        np.testing.assert_allclose(rots[k], world.rotation, rtol=0, atol=1e-12)
        np.testing.assert_allclose(origins[k], world.translation, rtol=0, atol=1e-12)
        if tree.bodies[k].kind != "Fixed":
            vel = pin.getVelocity(pm, pd, jid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            np.testing.assert_allclose(
                twists[6 * link : 6 * link + 3], vel.angular, rtol=0, atol=1e-11
            )
            np.testing.assert_allclose(
                twists[6 * link + 3 : 6 * link + 6], vel.linear, rtol=0, atol=1e-11
            )
            link += 1
    assert link == model.nlinks


@pytest.mark.parametrize("seed", range(4))
def test_external_wrenches_match_pinocchio(seed):
    """External wrench per link: [moment about the link origin; force], world axes. Pinocchio's
    fext: the same wrench in the link's (last joint's) local frame."""
    tree, model, pm, pd, q, v, tau, a = check_tree(
        seed, kinds=("Revolute", "Prismatic", "Spherical", "SphericalZYZ", "Fixed")
    )
    rng = np.random.default_rng(seed)
    ext = rng.normal(size=(model.nlinks, 6))
    pin.forwardKinematics(pm, pd, q)
    fext = [pin.Force.Zero() for _ in range(pm.njoints)]
    link = 0
    for k, (jid, _) in enumerate(carriers(tree, pm)):
        if tree.bodies[k].kind == "Fixed":
            continue
        r = pd.oMi[jid].rotation
        fext[jid] = pin.Force(r.T @ ext[link, 3:], r.T @ ext[link, :3])
        link += 1
    aba_ref = pin.aba(pm, pd, q, v, tau, fext).copy()
    rnea_ref = pin.rnea(pm, pd, q, v, a, fext).copy()
    e1 = rel_err(model.forward_dynamics(q, v, tau, G, external=ext), aba_ref)
    e2 = rel_err(model.inverse_dynamics(q, v, a, G, external=ext), rnea_ref)
    record("pinocchio external wrenches (FD, ID)", max(e1, e2))
    assert e1 <= TOL and e2 <= TOL, (e1, e2)


def test_rod_inertia_convention_matches_pinocchio():
    """Products of inertia: pinocchio.Inertia takes the standard tensor, as RigidBody does; a
    body with a large product of inertia on a spherical joint gives the same GIM."""
    import pointmass_dyn as pmd

    inertia = np.array([[0.3, -0.1, 0.05], [-0.1, 0.2, 0.02], [0.05, 0.02, 0.25]])
    body = pmd.RigidBody(1.5, [0.1, 0.2, -0.1], inertia)
    model = pmd.Model()
    model.add_body(body, pmd.Spherical())
    pm = pin.Model()
    j = pm.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "s")
    pm.appendBodyToJoint(
        j, pin.Inertia(1.5, np.array([0.1, 0.2, -0.1]), inertia), pin.SE3.Identity()
    )
    q = np.array([0, 0, 0, 1.0])
    assert rel_err(model.mass_matrix(q), pin_mass_matrix(pm, pm.createData(), q)) <= 1e-14


# ---------------------------------------------------------------------------------------------
# Benchmark models: chainN (docs/benchmarks.md) and Panda (example-robot-data)
# ---------------------------------------------------------------------------------------------


def chain_tree(n):
    """docs/benchmarks.md chainN: revolute axes y, z, y, …; joint k at (0.3, 0, 0) in body k−1;
    1 kg, COM (0.15, 0, 0), inertia diag(1e-3, 7.5e-3, 7.5e-3)."""
    import pointmass_dyn as pmd
    from conftest import BodySpec, TreeSpec

    body = pmd.RigidBody(1.0, [0.15, 0, 0], np.diag([1e-3, 7.5e-3, 7.5e-3]))
    tree = TreeSpec()
    for k in range(n):
        axis = np.array([0.0, 1.0, 0.0]) if k % 2 == 0 else np.array([0.0, 0.0, 1.0])
        t = np.zeros(3) if k == 0 else np.array([0.3, 0.0, 0.0])
        tree.bodies.append(BodySpec(body, "Revolute", k - 1, np.eye(3), t, axis=axis))
    return tree


@pytest.mark.parametrize("n", [7, 30])
def test_chain_benchmark_matches_pinocchio(n):
    tree = chain_tree(n)
    model = build_model(tree)
    pm, pd = build_pinocchio(tree, G)
    q = np.full(n, 0.3)
    rng = np.random.default_rng(n)
    v = rng.normal(size=n)
    errs = compare_all(model, pm, pd, q, v, rng.normal(size=n), rng.normal(size=n), "chainN")
    bad = {k: e for k, e in errs.items() if not e <= TOL}
    assert not bad, bad


def panda_urdf():
    import glob
    import os

    try:
        import example_robot_data as erd
    except ImportError:  # only the data files are installed: look in the share directory
        erd = None
    if erd is not None:
        return os.path.join(
            erd.getModelPath("panda_description/urdf/panda.urdf"),
            "panda_description/urdf/panda.urdf",
        )
    root = os.path.dirname(os.path.dirname(pin.__file__))
    for base in (root, os.path.join(root, "..", "..", "..")):
        hits = glob.glob(
            os.path.join(base, "**", "panda_description", "urdf", "panda.urdf"), recursive=True
        )
        if hits:
            return hits[0]
    pytest.skip("example-robot-data's panda.urdf not found")


def model_from_pinocchio(pm):
    """Our model from a Pinocchio model of revolute/prismatic joints (axes from the joint
    types), placements and inertias read from Pinocchio."""
    import pointmass_dyn as pmd

    axes = {"X": [1.0, 0, 0], "Y": [0, 1.0, 0], "Z": [0, 0, 1.0]}
    model = pmd.Model()
    for j in range(1, pm.njoints):
        name = pm.joints[j].shortname()
        if name.startswith("JointModelR") and name[-1] in axes:
            joint = pmd.Revolute(axes[name[-1]])
        elif name.startswith("JointModelP") and name[-1] in axes:
            joint = pmd.Prismatic(axes[name[-1]])
        elif name == "JointModelRevoluteUnaligned":
            joint = pmd.Revolute(pm.joints[j].extract().axis)
        elif name == "JointModelPrismaticUnaligned":
            joint = pmd.Prismatic(pm.joints[j].extract().axis)
        else:
            raise AssertionError(name)
        y = pm.inertias[j]
        # Eigen hands out column-major (Fortran-ordered) arrays; pass C-ordered copies (the
        # Fortran-order bug has its own test in test_errors.py).
        body = pmd.RigidBody(y.mass, y.lever, np.ascontiguousarray(y.inertia))
        x = pm.jointPlacements[j]
        model.add_body(
            body,
            joint,
            parent=pm.parents[j] - 1,
            translation=x.translation,
            rotation=np.ascontiguousarray(x.rotation),
            name=pm.names[j],
        )
    return model


def test_panda_matches_pinocchio():
    pm = pin.buildModelFromUrdf(panda_urdf())
    pd = pm.createData()
    model = model_from_pinocchio(pm)
    assert (model.nq, model.nv) == (pm.nq, pm.nv) == (9, 9)
    rng = np.random.default_rng(7)
    for _ in range(5):
        q = pin.randomConfiguration(pm)
        v = rng.normal(size=pm.nv)
        errs = compare_all(
            model, pm, pd, q, v, rng.normal(size=pm.nv), rng.normal(size=pm.nv), "panda"
        )
        bad = {k: e for k, e in errs.items() if not e <= TOL}
        assert not bad, bad


@pytest.mark.parametrize("seed", range(4))
def test_velocity_to_qdot_matches_pinocchio_integrate(seed):
    """q̇ = velocity_to_qdot(q, v) against central differences of pinocchio.integrate(q, ±h v)
    (quaternion speeds = body-frame angular velocity, as in Pinocchio)."""
    _, model, pm, _, q, v, _, _ = check_tree(seed)
    h = 1e-6
    fd = (pin.integrate(pm, q, h * v) - pin.integrate(pm, q, -h * v)) / (2 * h)
    assert rel_err(model.velocity_to_qdot(q, v), fd) <= 1e-8


def _turn(axis: int, quarters: int) -> np.ndarray:
    """A quarter/half turn about a coordinate axis computed in floating point, as from a
    decimal rpy: cos(π/2) = 6e-17, not 0."""
    a = quarters * (np.pi / 2)
    c, s = np.cos(a), np.sin(a)
    i, j = (axis + 1) % 3, (axis + 2) % 3
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


@pytest.mark.parametrize("seed", range(6))
def test_quarter_turn_placements_match_pinocchio(seed):
    """Revolute joints on ±x, ±y, ±z below quarter and half turns (and products of them),
    offsets zero, along one axis or anywhere, some spherical and prismatic joints: the
    recursions absorb the turns into their link frames (the joint then turns about ±e_K with
    no placement). Pinocchio gets the placements as computed (with their 6e-17 entries)."""
    rng = np.random.default_rng(100 + seed)
    tree = TreeSpec()
    for k in range(12):
        kind = "Spherical" if k % 5 == 4 else ("Prismatic" if k % 7 == 6 else "Revolute")
        axis = None
        if kind == "Revolute":
            axis = np.zeros(3)
            axis[rng.integers(3)] = rng.choice([-1.0, 1.0])
        elif kind == "Prismatic":
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
        choice = rng.integers(4)
        if choice == 0:
            rot = np.eye(3)
        elif choice == 1:
            rot = _turn(int(rng.integers(3)), int(rng.integers(1, 4)))
        elif choice == 2:
            rot = _turn(int(rng.integers(3)), 1) @ _turn(int(rng.integers(3)), -1)
        else:
            rot = random_rotation(rng)
        t = np.zeros(3)
        form = rng.integers(3)
        if form == 1:
            t[rng.integers(3)] = rng.uniform(-0.4, 0.4)
        elif form == 2:
            t = rng.uniform(-0.4, 0.4, size=3)
        # Depth-first order (Pinocchio's CRBA needs it): the last body or one of its ancestors.
        parent = k - 1
        if k > 0 and rng.random() < 0.3:
            path = [k - 1]
            while tree.bodies[path[-1]].parent >= 0:
                path.append(tree.bodies[path[-1]].parent)
            parent = int(path[rng.integers(len(path))])
        tree.bodies.append(
            BodySpec(
                body=random_body(rng), kind=kind, parent=parent, rotation=rot, translation=t,
                axis=axis,
            )
        )
    model = build_model(tree)
    pm, pd = build_pinocchio(tree, G)
    for _ in range(3):
        q, v = random_state(model, rng)
        errs = compare_all(
            model, pm, pd, q, v, rng.normal(size=model.nv), rng.normal(size=model.nv),
            f"quarter turns {seed}",
        )
        bad = {k: e for k, e in errs.items() if not e <= TOL}
        assert not bad, bad


def test_quarter_turns_are_exact_in_the_model():
    model = pmd.Model()
    body = pmd.RigidBody(1.0, [0.1, 0.0, 0.0], np.diag([0.01, 0.02, 0.02]))
    b0 = model.add_body(body, pmd.Revolute([0, 0, 1]), rotation=_turn(0, 1))
    model.add_body(body, pmd.Revolute([0, 0, 1]), parent=b0, rotation=_turn(1, -1),
                   translation=[0.3, 0, 0])
    model.add_body(body, pmd.Revolute([0, 0, 1]), parent=b0, rotation=_turn(2, 1) + 1e-12,
                   translation=[0.3, 0, 0])
    rot, _ = model.placements(model.neutral())
    assert set(np.unique(rot[0])) <= {-1.0, 0.0, 1.0}
    assert set(np.unique(rot[1])) <= {-1.0, 0.0, 1.0}
    # 1e-12 away from a quarter turn is a (re-orthonormalised) rotation of its own.
    assert not set(np.unique(rot[2])) <= {-1.0, 0.0, 1.0}
