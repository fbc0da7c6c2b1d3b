"""Shaking force and moment, point-mass motion and bearing forces (issue 14) against results
that do not come from our code:

* shaking force and moment = minus the rate of the centroidal momentum computed by
  Pinocchio (``computeCentroidalMomentumTimeVariation``, ``centerOfMass``), on random trees
  (every joint kind, free-flyer roots) and floating-base URDF robots; the point masses' sums
  against Pinocchio's mass, COM and momenta, their velocities and accelerations against
  finite differences along Pinocchio's ``integrate``;
* bearing forces = Pinocchio's joint wrenches ``data.f`` after ``rnea`` (gravity, external
  wrenches);
* loops (the bundled fourbar, slider_crank, rssr scenes and a four-bar cut at a ground
  pivot): invariants — no wrench along a passive joint's motion, Newton–Euler of every link
  by its own point masses, the shaking force and moment from the ground bearings;
* the slider-crank's shaking force and moment in closed form (exact offset kinematics
  differentiated by SymPy) and its Fourier series against the textbook primary and
  secondary forces of the reciprocating mass;
* bad input.

Shaking (gravity excluded): F = −Σ m a, M_O = −Σ m (r − O) × a over every point mass."""

from __future__ import annotations

import functools

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import (
    BodySpec,
    G,
    build_model,
    build_pinocchio,
    random_body,
    random_rotation,
    random_state,
    random_tree,
    record,
    rel_err,
)

pin = pytest.importorskip("pinocchio")
sp = pytest.importorskip("sympy")

from test_loops_mechanisms import (  # noqa: E402
    THETA,
    SliderCrank,
    prescribed_states,
    scene_file,
)
from test_pinocchio import carriers  # noqa: E402

TOL = 1e-9


def check(name, got, ref, tol=TOL):
    err = record(f"shaking/bearing: {name}", rel_err(got, ref))
    assert err <= tol, (name, err)


# --------------------------------------------------------------------------------------------
# Random trees built in both libraries
# --------------------------------------------------------------------------------------------
def tree_case(seed, free_root):
    """A random tree of 12 bodies (every joint kind; 13 with a FreeFlyer root if
    `free_root`), the same tree in Pinocchio with gravity G, and a generator for states."""
    tree = random_tree(seed, 12)
    if free_root:
        # A new first body on a free flyer carries the old root (depth-first order kept).
        rng = np.random.default_rng(seed)
        for b in tree.bodies:
            b.parent = b.parent + 1 if b.parent >= 0 else b.parent
        tree.bodies[0].parent = 0
        tree.bodies.insert(0, BodySpec(random_body(rng), "FreeFlyer", -1, random_rotation(rng),
                                       rng.uniform(-0.5, 0.5, size=3)))
    model = build_model(tree)
    pm, pd = build_pinocchio(tree, G)
    assert (pm.nq, pm.nv) == (model.nq, model.nv)
    return tree, model, pm, pd, np.random.default_rng(seed + 1000)


def link_joint_ids(tree, pm):
    """Pinocchio's joint id for each of our links (the joint carrying the link's body, whose
    frame is the body frame: build_pinocchio appends each moving body at the identity)."""
    out = []
    for spec, (jid, frame) in zip(tree.bodies, carriers(tree, pm)):
        if spec.kind != "Fixed":
            assert frame.isIdentity()
            out.append(jid)
    return out


def pin_shaking(pm, pd, q, v, a):
    """Minus Pinocchio's centroidal momentum rate: (F, M about the COM, COM, total mass,
    COM acceleration)."""
    dhg = pin.computeCentroidalMomentumTimeVariation(pm, pd, q, v, a)
    f, m_g = -dhg.linear.copy(), -dhg.angular.copy()
    com = pin.centerOfMass(pm, pd, q, v, a).copy()
    return f, m_g, com, pin.computeTotalMass(pm), pd.acom[0].copy()


def compare_shaking(model, pm, pd, q, v, a, rng, label):
    f_ref, m_g, com, mass, acom = pin_shaking(pm, pd, q, v, a)
    f, m = model.shaking(q, v, a, about=com)
    check(f"{label} force = −ḣ_G (Pinocchio)", f, f_ref)
    check(f"{label} force = −M a_com (Pinocchio)", f, -mass * acom)
    check(f"{label} moment about the COM = −ḣ_G (Pinocchio)", m, m_g)
    # Any other point: M_O = M_G + (G − O) × F; the default is the world origin.
    o = rng.uniform(-1.0, 1.0, size=3)
    check(f"{label} moment about O", model.shaking(q, v, a, about=o)[1],
          m_g + np.cross(com - o, f_ref))
    check(f"{label} moment about the origin", model.shaking(q, v, a)[1],
          m_g + np.cross(com, f_ref))


@pytest.mark.parametrize("free_root", [False, True])
@pytest.mark.parametrize("seed", range(5))
def test_shaking_is_minus_pinocchios_centroidal_momentum_rate(seed, free_root):
    tree, model, pm, pd, rng = tree_case(seed, free_root)
    kinds = set(tree.kinds())
    assert {"Revolute", "Prismatic", "Spherical", "SphericalZYZ"} <= kinds
    assert ("FreeFlyer" in kinds) == free_root
    for _ in range(3):
        q, v = random_state(model, rng)
        a = rng.normal(size=model.nv)
        compare_shaking(model, pm, pd, q, v, a, rng, "random trees")
    # Gravity excluded: a mechanism at rest does not shake its ground.
    f, m = model.shaking(q, np.zeros(model.nv), np.zeros(model.nv), about=rng.normal(size=3))
    assert not f.any() and not m.any()


def test_batched_shaking_equals_single_calls_bit_for_bit():
    _, model, _, _, rng = tree_case(3, True)
    states = [random_state(model, rng) for _ in range(6)]
    qs = np.array([q for q, _ in states])
    vs = np.array([v for _, v in states])
    acc = rng.normal(size=(6, model.nv))
    for about in (None, rng.normal(size=3)):
        f, m = model.shaking(qs, vs, acc, about=about)
        assert f.shape == m.shape == (6, 3)
        for k in range(6):
            fk, mk = model.shaking(qs[k], vs[k], acc[k], about=about)
            assert fk.shape == mk.shape == (3,)
            np.testing.assert_array_equal(f[k], fk)
            np.testing.assert_array_equal(m[k], mk)
    f1, m1 = model.shaking(qs[:1], vs[:1], acc[:1])
    assert f1.shape == m1.shape == (1, 3)
    np.testing.assert_array_equal(f1[0], model.shaking(qs[0], vs[0], acc[0])[0])


def check_point_motion(model, pm, pd, q, v, a, label):
    """The point masses' sums against Pinocchio's total mass, COM, COM velocity and
    acceleration, centroidal momentum; positions against model.point_masses."""
    pmo = model.point_motion(q, v, a)
    n = model.nlinks
    assert pmo["masses"].shape == (n, 7)
    for k in ("positions", "velocities", "accelerations"):
        assert pmo[k].shape == (n, 7, 3), k
    m = pmo["masses"].reshape(-1)
    r, vel, acc = (pmo[k].reshape(-1, 3) for k in ("positions", "velocities", "accelerations"))
    mass = pin.computeTotalMass(pm)
    com = pin.centerOfMass(pm, pd, q, v, a).copy()
    vcom, acom = pd.vcom[0].copy(), pd.acom[0].copy()
    hg = pin.computeCentroidalMomentum(pm, pd, q, v)
    check(f"{label} Σ m = total mass", m.sum(), mass, 1e-12)
    check(f"{label} Σ m r = M c", m @ r, mass * com)
    check(f"{label} Σ m v = momentum", m @ vel, hg.linear)
    check(f"{label} Σ m v = M v_com", m @ vel, mass * vcom)
    check(f"{label} Σ m a = M a_com", m @ acc, mass * acom)
    check(f"{label} Σ m (r − c) × v = h_G", np.cross(r - com, vel).T @ m, hg.angular)
    masses, points = model.point_masses(q)
    np.testing.assert_array_equal(pmo["masses"], masses)
    np.testing.assert_allclose(pmo["positions"], points, rtol=0, atol=1e-14)
    return pmo


@pytest.mark.parametrize("free_root", [False, True])
@pytest.mark.parametrize("seed", range(3))
def test_point_motion_sums_are_pinocchios_mass_com_and_momenta(seed, free_root):
    tree, model, pm, pd, rng = tree_case(10 + seed, free_root)
    q, v = random_state(model, rng)
    a = rng.normal(size=model.nv)
    pmo = check_point_motion(model, pm, pd, q, v, a, "random trees")
    # Each point's velocity and acceleration: central differences of the positions along
    # q(±h) = integrate(q, ±h v + h²/2 a) (Pinocchio's exponential on every joint; the
    # commutator terms of the true flow are O(h³) and odd, so both differences are O(h²)).
    h = 1e-4

    def pos(dq):
        return model.point_masses(pin.integrate(pm, q, dq))[1]

    p_plus, p_minus = pos(h * v + h * h / 2 * a), pos(-h * v + h * h / 2 * a)
    vel_fd = (p_plus - p_minus) / (2 * h)
    acc_fd = (p_plus - 2 * pmo["positions"] + p_minus) / (h * h)
    check("point velocities vs finite differences", pmo["velocities"], vel_fd, 1e-7)
    check("point accelerations vs finite differences", pmo["accelerations"], acc_fd, 1e-5)


# --------------------------------------------------------------------------------------------
# Bearing forces against Pinocchio's RNEA joint wrenches
# --------------------------------------------------------------------------------------------
def pin_joint_wrenches(pm, pd, q, v, a, jids, external=None):
    """Pinocchio's data.f after rnea (gravity in pm) for the joints `jids`, [linear;
    angular] in each joint's frame, and τ. `external`: one wrench per link [moment about
    the link origin; force], world axes, converted to Pinocchio's per-joint local forces."""
    pin.forwardKinematics(pm, pd, q)
    if external is None:
        tau = pin.rnea(pm, pd, q, v, a).copy()
    else:
        fext = pin.StdVec_Force()
        for _ in range(pm.njoints):
            fext.append(pin.Force.Zero())
        for jid, w in zip(jids, external):
            rt = pd.oMi[jid].rotation.T
            fext[jid] = pin.Force(rt @ w[3:], rt @ w[:3])
        tau = pin.rnea(pm, pd, q, v, a, fext).copy()
    joints = np.array([np.r_[pd.f[j].linear, pd.f[j].angular] for j in jids])
    return joints, tau, [pd.oMi[j].rotation.copy() for j in jids]


def compare_bearing(model, pm, pd, q, v, a, jids, external, label):
    ref, tau_ref, rots = pin_joint_wrenches(pm, pd, q, v, a, jids, external)
    out = model.bearing_forces(q, v, a, gravity=G, external=external)
    assert out["joints"].shape == (model.nlinks, 6) and out["loops"].shape == (0, 6)
    check(f"{label} joint wrenches = Pinocchio's rnea data.f", out["joints"], ref)
    check(f"{label} tau = Pinocchio's rnea", out["tau"], tau_ref)
    check(f"{label} tau = inverse_dynamics", out["tau"],
          model.inverse_dynamics(q, v, a, gravity=G, external=external), 1e-12)
    world = model.bearing_forces(q, v, a, gravity=G, external=external, frame="world")
    rotated = [np.r_[r @ w[:3], r @ w[3:]] for r, w in zip(rots, out["joints"])]
    check(f"{label} frame='world' = rotated frame='joint'", world["joints"], np.array(rotated),
          1e-13)
    np.testing.assert_array_equal(world["tau"], out["tau"])


@pytest.mark.parametrize("free_root", [False, True])
@pytest.mark.parametrize("seed", range(5))
def test_bearing_forces_are_pinocchios_rnea_joint_wrenches(seed, free_root):
    tree, model, pm, pd, rng = tree_case(20 + seed, free_root)
    jids = link_joint_ids(tree, pm)
    assert len(jids) == model.nlinks
    for external in (None, rng.normal(size=(model.nlinks, 6))):
        q, v = random_state(model, rng)
        a = rng.normal(size=model.nv)
        compare_bearing(model, pm, pd, q, v, a, jids, external, "random trees")


def test_floating_robot_shaking_and_bearing_forces_equal_pinocchios(floating_robot):
    """URDF link frames are the joint frames in both libraries, links in Pinocchio's joint
    order (joint id = link + 1; fixed links welded into their parents on both sides)."""
    name, model, pm = floating_robot
    pd = pm.createData()
    rng = np.random.default_rng(5)
    jids = list(range(1, pm.njoints))
    for external in (None, rng.normal(size=(model.nlinks, 6))):
        q = pin.randomConfiguration(pm, -np.ones(pm.nq), np.ones(pm.nq))
        v, a = rng.normal(size=pm.nv), rng.normal(size=pm.nv)
        label = f"floating robots ({name})"
        compare_shaking(model, pm, pd, q, v, a, rng, label)
        check_point_motion(model, pm, pd, q, v, a, label)
        compare_bearing(model, pm, pd, q, v, a, jids, external, label)


# --------------------------------------------------------------------------------------------
# Loops: invariants of the bearing forces
# --------------------------------------------------------------------------------------------
def links_of(model):
    """Each link's body index and parent link (-1: the world); the loop scenes have no Fixed
    bodies, so bodies and links are one."""
    info = [model.body_info(b) for b in range(model.nbodies)]
    assert all(kind != "Fixed" for _, kind, _, _ in info)
    bodies = [model.body_names.index(n) for n in model.link_names]
    return bodies, [-1 if info[b][2] < 0 else info[info[b][2]][3] for b in bodies]


def constant_speed_state(model, q_guess, theta, omega, g, external=None):
    """A closed state with the crank (q[0], v[0]) at θ turning at ω with no acceleration,
    every other acceleration what the dynamics give (forward dynamics with the crank torque
    that keeps ω constant: a(τ) is affine in τ), so the rssr coupler's idle spin is
    consistent too."""
    guess = np.array(q_guess, float)
    guess[0] = theta
    q = model.assemble(guess, fixed=["crank"])
    v = model.assemble_velocity(q, np.r_[omega, np.zeros(model.nv - 1)], fixed=["crank"])
    unit = np.zeros(model.nv)
    unit[0] = 1.0
    a0 = model.forward_dynamics(q, v, np.zeros(model.nv), gravity=g, external=external)
    da = model.forward_dynamics(q, v, unit, gravity=g, external=external) - a0
    a = a0 - a0[0] / da[0] * da
    assert q[0] == theta and v[0] == omega and abs(a[0]) < 1e-9 * np.abs(a).max()
    a[0] = 0.0
    return q, v, a


def check_loop_invariants(model, loops, q, v, a, g, external, label):
    """Every invariant of the bearing forces of a loop model driven at the crank.

    `loops`: the cut joints as the scene files give them (body names or "world",
    translations; no rotations). Returns the worst relative residual per invariant."""
    out = model.bearing_forces(q, v, a, gravity=g, external=external, actuated=["crank"])
    world = model.bearing_forces(q, v, a, gravity=g, external=external, actuated=["crank"],
                                 frame="world")
    tau = model.inverse_dynamics(q, v, a, gravity=g, external=external, actuated=["crank"])
    bodies, parent = links_of(model)
    rot, org = model.placements(q)
    n = model.nlinks
    assert out["joints"].shape == (n, 6) and out["loops"].shape == (len(loops), 6)
    check(f"{label}: tau = inverse_dynamics(actuated)", out["tau"], tau, 1e-12)
    assert not out["tau"][1:].any()  # passive: exactly zero, as inverse_dynamics says
    check(f"{label}: loops = constraint_forces",
          out["loops"], model.constraint_forces(q, v, tau, gravity=g, external=external))
    check(f"{label}: frame='world' = rotated frame='joint'", world["joints"],
          np.array([np.r_[rot[b] @ w[:3], rot[b] @ w[3:]] for b, w in zip(bodies, out["joints"])]),
          1e-13)
    f, mom = world["joints"][:, :3], world["joints"][:, 3:]
    origin = org[bodies]
    force_scale = np.abs(f).max()
    moment_scale = np.abs(mom).max()

    # (1) Frictionless joints: the wrench's work-conjugate components (Nd_iᵀ [n; f], the
    # joint's motion at the link origin in world axes) are zero for the passive joints and
    # the actuator's force for the crank.
    nd = model.denoc(q)["Nd"]
    along = np.concatenate(
        [nd[6 * i : 6 * i + 6, iv : iv + k].T @ np.r_[mom[i], f[i]]
         for i, (_, iv, _, k) in enumerate(model.joint_slices())]
    )
    check(f"{label}: wrench along each joint's motion = tau (0 if passive)", along, tau)
    assert np.abs(along[1:]).max() <= TOL * force_scale

    # The cut joints' wrenches in world axes, at frame b's origin (where both act).
    def body(name):
        return None if name == "world" else model.body_names.index(name)

    cuts = []
    for lp, w in zip(loops, out["loops"]):
        ia, ib = body(lp["body_a"]), body(lp["body_b"])
        ra = np.eye(3) if ia is None else rot[ia]
        tb = np.asarray(lp["translation_b"], float)
        at = tb if ib is None else org[ib] + rot[ib] @ tb
        cuts.append((ia, ib, ra @ w[:3], ra @ w[3:], at))

    # (2) Newton–Euler of every link from its own point masses: Σ m a = f_in − Σ f_children
    # + weight + cut forces + external; moments about the link origin likewise.
    pmo = model.point_motion(q, v, a)
    ext = np.zeros((n, 6)) if external is None else np.asarray(external)
    for i in range(n):
        m, r, acc = pmo["masses"][i], pmo["positions"][i], pmo["accelerations"][i]
        lever = r - origin[i]
        lhs_f, lhs_n = m @ acc, np.cross(lever, acc).T @ m
        rhs_f = f[i] + m.sum() * g + ext[i, 3:]
        rhs_n = mom[i] + np.cross(lever, g).T @ m + ext[i, :3]
        for c in (c for c in range(n) if parent[c] == i):
            rhs_f -= f[c]
            rhs_n -= mom[c] + np.cross(origin[c] - origin[i], f[c])
        for ia, ib, fc, nc, at in cuts:
            for b, sign in ((ib, 1.0), (ia, -1.0)):
                if b == bodies[i]:
                    rhs_f += sign * fc
                    rhs_n += sign * (nc + np.cross(at - origin[i], fc))
        assert np.abs(lhs_f - rhs_f).max() <= TOL * force_scale, (i, lhs_f, rhs_f)
        assert np.abs(lhs_n - rhs_n).max() <= TOL * moment_scale, (i, lhs_n, rhs_n)
        record(f"shaking/bearing: {label}: Newton–Euler per link (force, moment scale)",
               max(np.abs(lhs_f - rhs_f).max() / force_scale,
                   np.abs(lhs_n - rhs_n).max() / moment_scale))

    # (3) The whole mechanism: the internal cut wrenches cancel (equal and opposite at one
    # point), so Σ m a = Σ (ground → mechanism) + M g + Σ external. With R the total force
    # the mechanism puts on its ground (the tree joints to the world and the cut joints to
    # the world, reversed): F_shaking = −Σ m a = R − M g − Σ f_ext, and about any O,
    # M_O = N_O − (c − O) × M g − Σ (n_ext + (O_i − O) × f_ext), N_O R's moment about O.
    total = pmo["masses"].sum()
    com = np.einsum("ij,ijk->k", pmo["masses"], pmo["positions"]) / total
    for o in (np.zeros(3), np.array([0.3, -0.2, 0.1])):
        on_ground = np.zeros(3)
        on_ground_moment = np.zeros(3)
        for i in (i for i in range(n) if parent[i] < 0):
            on_ground -= f[i]
            on_ground_moment -= mom[i] + np.cross(origin[i] - o, f[i])
        for ia, ib, fc, nc, at in cuts:
            sign = 1.0 if ib is None else -1.0 if ia is None else 0.0  # on the world
            on_ground += sign * fc
            on_ground_moment += sign * (nc + np.cross(at - o, fc))
        ext_f = ext[:, 3:].sum(axis=0)
        ext_n = ext[:, :3].sum(axis=0) + np.cross(origin - o, ext[:, 3:]).sum(axis=0)
        ref_f = on_ground - total * g - ext_f
        ref_n = on_ground_moment - np.cross(com - o, total * g) - ext_n
        got_f, got_n = model.shaking(q, v, a, about=o)
        check(f"{label}: shaking force = ground bearings − weight", got_f, ref_f)
        check(f"{label}: shaking moment = ground bearings' − weight's", got_n, ref_n)
    return out


LOOP_SCENES = {"fourbar": 30.0, "slider_crank": 30.0, "rssr": 40.0}


@pytest.mark.parametrize("with_external", [False, True])
@pytest.mark.parametrize("name", sorted(LOOP_SCENES))
def test_loop_scene_bearing_forces_satisfy_the_balances(name, with_external):
    data = scene_file(name)
    assert all(set(lp) == {"name", "body_a", "body_b", "joint", "translation_a",
                           "translation_b"} for lp in data["loop"])
    scene = pmd.load_scene(name)
    model, g = scene.model, data["g"]
    rng = np.random.default_rng(len(name))
    ext = None
    if with_external:
        ext = np.c_[rng.normal(scale=0.02, size=(model.nlinks, 3)),
                    rng.normal(scale=0.5, size=(model.nlinks, 3))]
    q = scene.q0
    angles = np.linspace(0.0, 2 * np.pi, 9)[:-1]
    for th in angles:
        q, v, a = constant_speed_state(model, q, th, LOOP_SCENES[name], g, ext)
        if name != "rssr":  # one degree of freedom: the kinematics alone fix a
            (_, _, a_kin), = prescribed_states(model, q, [th], LOOP_SCENES[name], 0.0)
            np.testing.assert_allclose(a, a_kin, rtol=0, atol=1e-9 * np.abs(a_kin).max())
        check_loop_invariants(model, data["loop"], q, v, a, g, ext, f"loop scenes ({name})")


@pytest.mark.parametrize("world_is", ["body_a", "body_b"])
def test_fourbar_cut_at_a_ground_pivot(world_is):
    """The fourbar's links as one chain crank–coupler–rocker, the loop closed by a revolute
    cut joint between the rocker's end and the ground pivot at (d, 0, 0): the ground
    bearings are then a tree joint and a cut joint, in either order of the cut's bodies."""
    data = scene_file("fourbar")
    b = data["bodies"]
    lp = data["loops"]["coupler-rocker"]
    a_len, b_len = b["coupler"]["translation"][0], lp["translation_a"][0]
    c_len, d_len = lp["translation_b"][0], b["rocker"]["translation"][0]
    model = pmd.Model()
    z = pmd.Revolute([0.0, 0.0, 1.0])
    for name, parent, x in (("crank", -1, 0.0), ("coupler", 0, a_len), ("rocker", 1, b_len)):
        body = pmd.RigidBody(b[name]["mass"], b[name]["com"], np.diag(b[name]["inertia_diag"]))
        model.add_body(body, z, parent=parent, translation=[x, 0.0, 0.0], name=name)
    ends = {"rocker": [c_len, 0.0, 0.0], "world": [d_len, 0.0, 0.0]}
    pair = ("world", "rocker") if world_is == "body_a" else ("rocker", "world")
    model.add_loop(pair[0], pair[1], z, translation_a=ends[pair[0]], translation_b=ends[pair[1]])
    loops = [{"body_a": pair[0], "body_b": pair[1], "translation_b": ends[pair[1]]}]
    # The scene's open assembly: the rocker (absolute angle θ4 + π from B towards D).
    th3, th4 = 0.8832855795, 1.683673226
    q = np.array([0.0, th3, th4 + np.pi - th3])
    rng = np.random.default_rng(1)
    ext = np.c_[rng.normal(scale=0.02, size=(3, 3)), rng.normal(scale=0.5, size=(3, 3))]
    for th in np.linspace(0.0, 2 * np.pi, 7)[:-1]:
        q, v, a = constant_speed_state(model, q, th, 30.0, data["g"], ext)
        out = check_loop_invariants(model, loops, q, v, a, data["g"], ext,
                                    "fourbar cut at a ground pivot")
        assert np.abs(out["loops"][0, :2]).max() > 0.1  # the cut joint does bear load


# --------------------------------------------------------------------------------------------
# Slider-crank: closed form and Fourier series
# --------------------------------------------------------------------------------------------
@functools.cache
def slider_crank_closed_form():
    """The scene's slider-crank at constant crank speed ω: the shaking force (x, y) and
    moment (z, about the origin) divided by ω², as NumPy functions of θ, from the exact
    COM positions (offset included) differentiated twice by SymPy (d²/dt² = ω² d²/dθ²)."""
    sc = SliderCrank()
    th, r, e = THETA, sc.r, sc.e
    s = sc.stroke(th, symbolic=True)
    # The rod from the crank pin (r cos θ, r sin θ) to the wrist pin (s, e), length l.
    cos_phi, sin_phi = (s - r * sp.cos(th)) / sc.l, (e - r * sp.sin(th)) / sc.l
    phi = sp.atan2(e - r * sp.sin(th), s - r * sp.cos(th))
    cx = {n: sc.bodies[n]["com"][0] for n in sc.bodies}
    links = {
        "crank": (cx["crank"] * sp.cos(th), cx["crank"] * sp.sin(th), th),
        "rod": (r * sp.cos(th) + cx["rod"] * cos_phi, r * sp.sin(th) + cx["rod"] * sin_phi,
                phi),
        "slider": (s + cx["slider"], sp.Float(e), sp.Integer(0)),
    }
    fx = fy = mz = sp.Integer(0)
    for name, (x, y, angle) in links.items():
        mass, izz = sc.bodies[name]["mass"], sc.bodies[name]["inertia_diag"][2]
        ax, ay = x.diff(th, 2), y.diff(th, 2)
        fx -= mass * ax
        fy -= mass * ay
        mz -= mass * (x * ay - y * ax) + izz * angle.diff(th, 2)
    return sc, [sp.lambdify(th, expr, "numpy", cse=True) for expr in (fx, fy, mz)]


def fourier(samples, k):
    """(a_k, b_k) of samples at θ_j = 2π j / N: f ≈ Σ a_k cos kθ + b_k sin kθ."""
    n = len(samples)
    th = 2 * np.pi * np.arange(n) / n
    return 2 / n * samples @ np.cos(k * th), 2 / n * samples @ np.sin(k * th)


def test_slider_crank_shaking_equals_the_closed_form_and_the_textbook_harmonics():
    sc, (fx, fy, mz) = slider_crank_closed_form()
    scene = pmd.load_scene("slider_crank")
    model, omega = scene.model, 30.0
    n = 48
    angles = 2 * np.pi * np.arange(n) / n
    states = prescribed_states(model, scene.q0, angles, omega, 0.0)
    qs, vs, acc = (np.array([s[k] for s in states]) for k in range(3))
    force, moment = model.shaking(qs, vs, acc)  # one batched call, about the origin
    ref_f = omega**2 * np.c_[fx(angles), fy(angles), np.zeros(n)]
    ref_m = omega**2 * np.c_[np.zeros((n, 2)), mz(angles)]
    check("slider-crank shaking force vs SymPy closed form", force, ref_f)
    check("slider-crank shaking moment vs SymPy closed form", moment, ref_m)

    # The textbook split: the rod's COM lies on the line between its pins, at k = c/l from
    # the crank pin, so its x is (1 − k) r cos θ + k s: exactly a rotating mass moment
    # m_c c_c + m_rod (1 − k) r on the crank and a reciprocating mass m_rec = m_slider +
    # k m_rod moving with the slider:
    #     F_x = ω² (m_c c_c + m_rod (1 − k) r) cos θ − m_rec s̈,
    #     F_y = ω² (m_c c_c + m_rod (1 − k) r) sin θ             (no secondary at all).
    # With s = r cos θ + √(l² − (r sin θ − e)²) ≈ r cos θ + l − (r sin θ − e)²/(2l),
    #     −s̈ ≈ ω² (r cos θ + (r²/l) cos 2θ + (e r/l) sin θ):
    # the primary (r ω² cos θ), secondary (r²/l ω² cos 2θ) and, from the offset, a primary
    # sine term. The square root is a function of sin θ alone, whose Fourier series has
    # cos 2jθ and sin (2j+1)θ only: the cos θ coefficient is exactly the textbook one; the
    # secondary's and the offset term's carry O((r/l)², (e/l)²) corrections.
    b = sc.bodies
    k = b["rod"]["com"][0] / sc.l
    rotating = b["crank"]["mass"] * b["crank"]["com"][0] + b["rod"]["mass"] * (1 - k) * sc.r
    m_rec = b["slider"]["mass"] + k * b["rod"]["mass"]
    w2 = omega**2
    a1, b1 = fourier(force[:, 0], 1)
    a2, _ = fourier(force[:, 0], 2)
    primary, secondary = m_rec * w2 * sc.r, m_rec * w2 * sc.r**2 / sc.l
    offset_primary = m_rec * w2 * sc.e * sc.r / sc.l
    assert abs(a1 - (w2 * rotating + primary)) <= 1e-9 * abs(a1)
    ay1, by1 = fourier(force[:, 1], 1)
    assert abs(ay1) <= 1e-9 * abs(by1) and abs(by1 - w2 * rotating) <= 1e-9 * abs(by1)
    assert max(abs(fourier(force[:, 1], j)[i]) for j in (2, 3, 4) for i in (0, 1)) <= 1e-9 * by1
    # The truncation: the textbook coefficients' relative errors are below (r/l)²; the
    # series of √ in (r, e) to the next order (SymPy) leaves errors below (r/l)⁴.
    lam = sc.r / sc.l
    eps = sp.Symbol("epsilon")
    s = sc.r * sp.cos(THETA) + sp.sqrt(sc.l**2 - eps**2 * (sc.r * sp.sin(THETA) - sc.e) ** 2)
    series = sp.series(s, eps, 0, 6).removeO().subs(eps, 1)
    s_next = sp.lambdify(THETA, series, "numpy")(angles)
    # −m_rec s̈ for the terms cos 2θ and sin θ: 4 ω² and ω² times s's coefficients.
    secondary_next = 4 * w2 * m_rec * fourier(s_next, 2)[0]
    offset_next = w2 * m_rec * fourier(s_next, 1)[1]
    errors = {
        "secondary (textbook)": (abs(a2 / secondary - 1), lam**2),
        "offset primary (textbook)": (abs(b1 / offset_primary - 1), lam**2),
        "secondary (next order)": (abs(a2 / secondary_next - 1), lam**4),
        "offset primary (next order)": (abs(b1 / offset_next - 1), lam**4),
    }
    for key, (err, _) in errors.items():
        record(f"shaking/bearing: slider-crank Fourier {key} (relative)", err)
    assert all(err <= bound for err, bound in errors.values()), errors
    # …and they are truncation errors indeed, shrinking by about (r/l)² per order.
    assert errors["secondary (textbook)"][0] > 10 * errors["secondary (next order)"][0]


# --------------------------------------------------------------------------------------------
# Bad input
# --------------------------------------------------------------------------------------------
def raises_naming(arg):
    """pytest.raises(InvalidInputError) whose message starts with the argument's name."""
    return pytest.raises(pmd.errors.InvalidInputError, match=rf"^{arg}: ")


@pytest.fixture(scope="module")
def tree_and_loop():
    _, model, _, _, rng = tree_case(0, False)
    q, v = random_state(model, rng)
    scene = pmd.load_scene("fourbar")
    return model, q, v, rng.normal(size=model.nv), scene.model, scene.q0


def test_bad_shapes_name_the_argument(tree_and_loop):
    model, q, v, a, _, _ = tree_and_loop
    stack = [np.tile(x, (3, 1)) for x in (q, v, a)]
    for call in (model.shaking, model.point_motion, model.bearing_forces):
        with raises_naming("q"):
            call(np.r_[q, 0.0], v, a)
        with raises_naming("q"):
            call(q[None, None], v, a)
        with raises_naming("v"):
            call(q, v[:-1], a)
        with raises_naming("a"):
            call(q, v, np.r_[a, 0.0])
        with raises_naming("v"):  # a stack of q with a single v
            call(stack[0], v, a)
    # Stacks: the same N for all three (shaking only; the others take one state).
    with raises_naming("v"):
        model.shaking(stack[0], stack[1][:2], stack[2])
    with raises_naming("a"):
        model.shaking(stack[0], stack[1], stack[2][:2])
    with raises_naming("a"):
        model.shaking(stack[0], stack[1], stack[2].T)
    for call in (model.point_motion, model.bearing_forces):
        with raises_naming("q"):
            call(*stack)
    with raises_naming("about"):
        model.shaking(q, v, a, about=[0.0, 0.0])
    with raises_naming("external"):
        model.bearing_forces(q, v, a, external=np.zeros((model.nlinks - 1, 6)))
    with raises_naming("gravity"):
        model.bearing_forces(q, v, a, gravity=[0.0, -9.81])
    # The messages say what was expected once (no "shape shape").
    with pytest.raises(pmd.errors.InvalidInputError) as info:
        model.shaking(q, v[:-1], a)
    assert "shape shape" not in str(info.value) and f"({model.nv},)" in str(info.value)


def test_non_finite_input_names_the_argument(tree_and_loop):
    model, q, v, a, _, _ = tree_and_loop
    for bad in (np.nan, np.inf, -np.inf):
        a_bad = a.copy()
        a_bad[-1] = bad
        for call in (model.shaking, model.point_motion, model.bearing_forces):
            with raises_naming("a"):
                call(q, v, a_bad)
            with raises_naming("v"):
                call(q, a_bad, a)
        rows = np.tile(a, (3, 1))
        rows[1, 0] = bad
        with raises_naming(r"a\[1\]"):
            model.shaking(np.tile(q, (3, 1)), np.tile(v, (3, 1)), rows)
        with raises_naming("about"):
            model.shaking(q, v, a, about=[0.0, bad, 0.0])
        with raises_naming("external"):
            model.bearing_forces(q, v, a, external=np.full((model.nlinks, 6), bad))


def test_bad_frame_and_actuated_name_the_argument(tree_and_loop):
    model, q, v, a, loop_model, q_loop = tree_and_loop
    for frame in ("body", "World", ""):
        with raises_naming("frame"):
            model.bearing_forces(q, v, a, frame=frame)
    with pytest.raises(TypeError):  # a wrong Python type, as for method= elsewhere
        model.bearing_forces(q, v, a, frame=None)
    with raises_naming("actuated"):
        model.bearing_forces(q, v, a, actuated=[0])
    zero = np.zeros(loop_model.nv)
    with raises_naming("actuated"):
        loop_model.bearing_forces(q_loop, zero, zero)
    with raises_naming("actuated"):
        loop_model.bearing_forces(q_loop, zero, zero, actuated=["no such body"])
    # and with it the call works (a state at rest: the crank holds the mechanism up).
    out = loop_model.bearing_forces(q_loop, zero, zero, gravity=G, actuated=["crank"])
    assert out["loops"].shape == (1, 6) and np.isfinite(out["joints"]).all()
