"""Dynamics invariants that need no other library: the GIM is symmetric positive definite,
İ − 2C is skew-symmetric, energy changes at the rate of the joint power, the explicit DeNOC
matrices fit together (N = D Nl Nd, I = Nᵀ M N, point velocities = d/dt point positions),
the point-mass centre is irrelevant to the dynamics, and the paper's pendulum starts as a
compound pendulum should."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import (
    PAPER_A,
    PAPER_D,
    PAPER_M,
    BodySpec,
    G,
    TreeSpec,
    build_model,
    moving_kinds,
    normalize_q,
    paper_pendulum_tree,
    random_state,
    random_tree,
    record,
    rel_err,
    rod_body,
)

SEEDS = list(range(8))
METHODS = ["recursive", "denoc"]


def tree_and_state(seed, n=10, **kw):
    tree = random_tree(seed, n, **kw)
    model = build_model(tree)
    q, v = random_state(model, np.random.default_rng(1000 + seed))
    return tree, model, q, v


def qdot_step(model, q, v, h):
    """q moved by h along q̇ = velocity_to_qdot(q, v), quaternions renormalised."""
    return normalize_q(model, q + h * model.velocity_to_qdot(q, v))


# ---------------------------------------------------------------------------------------------
# GIM
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
def test_gim_symmetric_positive_definite_and_methods_agree(seed):
    _, model, q, _ = tree_and_state(seed)
    m_rec = model.mass_matrix(q)
    m_den = model.mass_matrix(q, method="denoc")
    assert m_rec.shape == (model.nv, model.nv)
    np.testing.assert_allclose(m_rec, m_rec.T, rtol=0, atol=1e-14 * np.abs(m_rec).max())
    eig = np.linalg.eigvalsh(0.5 * (m_rec + m_rec.T))
    assert eig.min() > 0, eig
    np.linalg.cholesky(m_den)
    record("GIM recursive vs denoc", rel_err(m_rec, m_den))
    assert rel_err(m_rec, m_den) <= 1e-12


@pytest.mark.parametrize("seed", SEEDS)
def test_kinetic_energy_is_half_vT_I_v_and_sum_over_points(seed):
    _, model, q, v = tree_and_state(seed)
    t = model.kinetic_energy(q, v)
    assert t == pytest.approx(0.5 * v @ model.mass_matrix(q) @ v, rel=1e-13)
    den = model.denoc(q)
    pv = (den["N"] @ v).reshape(-1, 3)
    assert t == pytest.approx(0.5 * np.sum(den["masses"] * np.sum(pv * pv, axis=1)), rel=1e-13)


@pytest.mark.parametrize("seed", SEEDS)
def test_potential_energy_from_point_positions(seed):
    _, model, q, _ = tree_and_state(seed)
    masses, pos = model.point_masses(q)
    expect = -np.sum(masses[..., None] * pos * G)
    assert model.potential_energy(q, G) == pytest.approx(expect, rel=1e-13, abs=1e-13)
    # The point masses carry each link's mass (Σ m_ij = m_i).
    assert masses.sum() == pytest.approx(model.total_mass, rel=1e-14)


# ---------------------------------------------------------------------------------------------
# Convective matrix: İ − 2C skew-symmetric, C v consistent with the bias forces
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
def test_idot_minus_2c_is_skew_symmetric(seed):
    _, model, q, v = tree_and_state(seed)
    c = model.convective_matrix(q, v)
    assert c.shape == (model.nv, model.nv)
    h = 1e-5
    idot = (
        model.mass_matrix(qdot_step(model, q, v, h)) - model.mass_matrix(qdot_step(model, q, v, -h))
    ) / (2 * h)
    s = idot - 2 * c
    err = np.abs(s + s.T).max() / np.abs(idot).max()
    record("skew(İ − 2C) (central FD, h=1e-5)", err)
    assert err <= 1e-8, err
    # The check can fail: C alone is not skew-symmetric here.
    assert np.abs(c + c.T).max() > 1e-3 * np.abs(idot).max()


@pytest.mark.parametrize("seed", SEEDS)
def test_convective_and_gravity_give_bias_forces(seed):
    _, model, q, v = tree_and_state(seed)
    bias = model.bias_forces(q, v, G)
    expect = model.convective_matrix(q, v) @ v - model.gravity_forces(q, G)
    assert rel_err(bias, expect) <= 1e-12
    # gravity=None means no gravity.
    assert rel_err(model.bias_forces(q, v), model.convective_matrix(q, v) @ v) <= 1e-12
    assert rel_err(model.bias_forces(q, v, None), model.bias_forces(q, v, [0, 0, 0])) == 0


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("method", METHODS)
def test_forward_inverse_round_trip(seed, method):
    _, model, q, v = tree_and_state(seed)
    rng = np.random.default_rng(seed)
    a = rng.normal(size=model.nv)
    tau = model.inverse_dynamics(q, v, a, G, method=method)
    back = model.forward_dynamics(q, v, tau, G, method=method)
    assert rel_err(back, a) <= 1e-10
    # I a + C v − τ_g = τ, from the separately exposed pieces.
    expect = (
        model.mass_matrix(q) @ a + model.convective_matrix(q, v) @ v - model.gravity_forces(q, G)
    )
    assert rel_err(tau, expect) <= 1e-12


# ---------------------------------------------------------------------------------------------
# Energy balance along a trajectory
# ---------------------------------------------------------------------------------------------


def rk4_trajectory(model, q, v, tau, h, steps):
    def f(q, v):
        return model.velocity_to_qdot(q, v), model.forward_dynamics(q, v, tau, G)

    qs, vs = [q], [v]
    for _ in range(steps):
        k1q, k1v = f(q, v)
        k2q, k2v = f(q + h / 2 * k1q, v + h / 2 * k1v)
        k3q, k3v = f(q + h / 2 * k2q, v + h / 2 * k2v)
        k4q, k4v = f(q + h * k3q, v + h * k3v)
        q = normalize_q(model, q + h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q))
        v = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        qs.append(q)
        vs.append(v)
    return qs, vs


@pytest.mark.parametrize("seed", SEEDS[:5])
def test_energy_rate_equals_joint_power(seed):
    """d(T + V)/dt = τ·v along a short trajectory (RK4, h = 1 ms; five-point differences)."""
    _, model, q, v = tree_and_state(seed)
    tau = np.random.default_rng(seed).normal(size=model.nv)
    h, steps = 1e-3, 24
    qs, vs = rk4_trajectory(model, q, v, tau, h, steps)
    e = np.array(
        [model.kinetic_energy(qk, vk) + model.potential_energy(qk, G) for qk, vk in zip(qs, vs)]
    )
    power = np.array([tau @ vk for vk in vs])
    grav_power = np.array([model.gravity_forces(qk, G) @ vk for qk, vk in zip(qs, vs)])
    de = (-e[4:] + 8 * e[3:-1] - 8 * e[1:-3] + e[:-4]) / (12 * h)
    scale = np.abs(power).max() + np.abs(grav_power).max()
    err = np.abs(de - power[2:-2]).max() / scale
    record("energy balance d(T+V)/dt vs tau.v", err)
    assert err <= 1e-7, err
    # Can fail: without the potential energy the balance is off by the gravity power.
    t = np.array([model.kinetic_energy(qk, vk) for qk, vk in zip(qs, vs)])
    dt_ = (-t[4:] + 8 * t[3:-1] - 8 * t[1:-3] + t[:-4]) / (12 * h)
    assert np.abs(dt_ - power[2:-2]).max() > 1e3 * err * scale


def test_energy_conserved_paper_pendulum_without_torque():
    model = build_model(paper_pendulum_tree())
    q = np.radians([90.0, 45.0, 45.0])
    v = np.array([0.0, 1.0, 0.0])
    qs, vs = rk4_trajectory(model, q, v, np.zeros(3), 1e-3, 200)
    e = np.array(
        [model.kinetic_energy(qk, vk) + model.potential_energy(qk, G) for qk, vk in zip(qs, vs)]
    )
    scale = PAPER_M * 9.81 * PAPER_A
    assert np.ptp(e) / scale <= 1e-9


# ---------------------------------------------------------------------------------------------
# Independence from the point-mass centre
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
def test_dynamics_independent_of_point_mass_center(seed):
    tree = random_tree(seed, 10, centers=True)
    with_centers = build_model(tree)
    default = build_model(tree, centers=False)
    q, v = random_state(default, np.random.default_rng(seed))
    tau = np.random.default_rng(seed + 1).normal(size=default.nv)
    # The centres do change the point masses...
    m1, _ = with_centers.point_masses(q)
    m0, _ = default.point_masses(q)
    assert np.abs(m1 - m0).max() > 1e-3
    # ... but not the dynamics.
    errs = [
        rel_err(with_centers.mass_matrix(q), default.mass_matrix(q)),
        rel_err(
            with_centers.mass_matrix(q, method="denoc"), default.mass_matrix(q, method="denoc")
        ),
        rel_err(
            with_centers.forward_dynamics(q, v, tau, G), default.forward_dynamics(q, v, tau, G)
        ),
        rel_err(
            with_centers.forward_dynamics(q, v, tau, G, method="denoc"),
            default.forward_dynamics(q, v, tau, G, method="denoc"),
        ),
        rel_err(with_centers.bias_forces(q, v, G), default.bias_forces(q, v, G)),
        rel_err(with_centers.convective_matrix(q, v), default.convective_matrix(q, v)),
    ]
    record("point-mass centre independence", max(errs))
    assert max(errs) <= 1e-12, errs


def test_paper_rod_far_end_and_com_centres_same_pendulum():
    """The paper's choice (box at the far end) and the tetrahedron (box at the COM)."""
    q = np.radians([90.0, 45.0, 45.0])
    v = np.array([0.3, 1.0, -0.2])
    models = []
    for center in (None, [PAPER_A, 0, 0], [0, 0, 0]):
        t = TreeSpec(
            [
                BodySpec(
                    rod_body(), "SphericalZYZ", -1, np.eye(3), np.zeros(3), point_mass_center=center
                )
            ]
        )
        models.append(build_model(t))
    ref = models[0]
    for m in models[1:]:
        assert rel_err(m.mass_matrix(q), ref.mass_matrix(q)) <= 1e-12
        assert (
            rel_err(
                m.forward_dynamics(q, v, np.zeros(3), G), ref.forward_dynamics(q, v, np.zeros(3), G)
            )
            <= 1e-11
        )


# ---------------------------------------------------------------------------------------------
# Explicit DeNOC matrices
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
def test_denoc_matrices_fit_together(seed):
    _, model, q, _ = tree_and_state(seed)
    n, nv = model.nlinks, model.nv
    den = model.denoc(q)
    d, nl, nd, nmat, masses = den["D"], den["Nl"], den["Nd"], den["N"], den["masses"]
    assert d.shape == (21 * n, 6 * n) and nl.shape == (6 * n, 6 * n)
    assert nd.shape == (6 * n, nv) and nmat.shape == (21 * n, nv) and masses.shape == (7 * n,)
    assert rel_err(nmat, d @ nl @ nd) <= 1e-14
    m = np.diag(np.repeat(masses, 3))
    gim = nmat.T @ m @ nmat
    assert rel_err(model.mass_matrix(q), gim) <= 1e-12
    assert rel_err(model.mass_matrix(q, method="denoc"), 0.5 * (gim + gim.T)) <= 1e-13
    # Gravity: τ_g = Nᵀ f, f_ij = m_ij g.
    f = np.outer(masses, G).ravel()
    assert rel_err(model.gravity_forces(q, G), nmat.T @ f) <= 1e-13
    # Blocks: A_ij = [[1, 0], [ã, 1]] with identity diagonal blocks; D_i rows [−d̃, 1].
    for i in range(n):
        np.testing.assert_array_equal(nl[6 * i : 6 * i + 6, 6 * i : 6 * i + 6], np.eye(6))
        for j in range(7):
            np.testing.assert_array_equal(
                d[21 * i + 3 * j : 21 * i + 3 * j + 3, 6 * i + 3 : 6 * i + 6], np.eye(3)
            )


@pytest.mark.parametrize("seed", SEEDS)
def test_denoc_point_masses_are_the_bodies_point_masses(seed):
    """masses of link i = the seven masses of its body (trees without welded bodies)."""
    kinds = ("Revolute", "Prismatic", "Spherical", "SphericalZYZ")
    tree = random_tree(seed, 10, kinds=kinds, centers=True)
    model = build_model(tree)
    q, _ = random_state(model, np.random.default_rng(seed))
    den = model.denoc(q)
    rots, origins = model.placements(q)
    for i, b in enumerate(tree.bodies):
        local = b.body.point_masses(b.point_mass_center)
        np.testing.assert_allclose(
            den["masses"][7 * i : 7 * i + 7], local.masses, rtol=0, atol=1e-13 * b.body.mass
        )
        world = origins[i] + local.positions @ rots[i].T
        np.testing.assert_allclose(den["points"][7 * i : 7 * i + 7], world, rtol=0, atol=1e-13)


@pytest.mark.parametrize("seed", SEEDS)
def test_point_velocities_are_rates_of_point_positions(seed):
    _, model, q, v = tree_and_state(seed)
    den = model.denoc(q)
    vel = (den["D"] @ den["Nl"] @ den["Nd"] @ v).reshape(-1, 3)
    h = 1e-6
    _, pp = model.point_masses(qdot_step(model, q, v, h))
    _, pm = model.point_masses(qdot_step(model, q, v, -h))
    fd = (pp - pm).reshape(-1, 3) / (2 * h)
    err = rel_err(vel, fd)
    record("point velocities N v vs FD of positions", err)
    assert err <= 1e-8, err
    np.testing.assert_allclose(
        model.point_masses(q)[1].reshape(-1, 3), den["points"], rtol=0, atol=1e-15
    )


@pytest.mark.parametrize("seed", SEEDS[:4])
def test_denoc_rates_are_time_derivatives(seed):
    _, model, q, v = tree_and_state(seed)
    rates = model.denoc_rates(q, v)
    h = 1e-6
    dp, dm = model.denoc(qdot_step(model, q, v, h)), model.denoc(qdot_step(model, q, v, -h))
    for key in ("D", "Nl", "Nd", "N"):
        fd = (dp[key] - dm[key]) / (2 * h)
        assert rel_err(rates[key], fd) <= 1e-7, key


# ---------------------------------------------------------------------------------------------
# Analytic: the paper's pendulum at the planar start (φ = θ = ψ = 90°)
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", METHODS)
def test_paper_planar_start_is_compound_pendulum(method):
    """At φ = θ = ψ = 90° the rod lies along −x; ω = (−θ̇, ψ̇, φ̇) (L of eq 38b), and gravity's
    moment about the joint, (−m g a/2) e_y, drives ψ alone: ψ̈ = −m g (a/2) / I_O with
    I_O = m a²/3 + m d²/16."""
    model = build_model(paper_pendulum_tree())
    q = np.radians([90.0, 90.0, 90.0])
    m, a, d = PAPER_M, PAPER_A, PAPER_D
    i_o = m * a * a / 3 + m * d * d / 16
    acc = model.forward_dynamics(q, np.zeros(3), np.zeros(3), G, method=method)
    np.testing.assert_allclose(acc, [0, 0, -m * 9.81 * (a / 2) / i_o], rtol=0, atol=1e-12)
    np.testing.assert_allclose(
        model.gravity_forces(q, G), [0, 0, -m * 9.81 * a / 2], rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(model.mass_matrix(q, method=method)[2, 2], i_o, rtol=1e-14)


def test_prismatic_free_fall_and_revolute_pendulum():
    """One body on a vertical prismatic joint falls at g; on a revolute joint about y it is a
    compound pendulum about the joint."""
    body = pmd.RigidBody(2.0, [0.4, 0.0, 0.0], np.diag([0.01, 0.05, 0.05]))
    slider = pmd.Model()
    slider.add_body(body, pmd.Prismatic([0, 0, 2.0]))
    assert slider.forward_dynamics([0.3], [1.0], [0.0], G)[0] == pytest.approx(-9.81, rel=1e-14)
    assert slider.forward_dynamics([0.3], [1.0], [2.0], G)[0] == pytest.approx(
        -9.81 + 1.0, rel=1e-14
    )
    pend = pmd.Model()
    pend.add_body(body, pmd.Revolute([0, 1, 0]))
    th = 0.3
    i_o = 0.05 + 2.0 * 0.4**2
    # Turning about +y moves the COM to 0.4 (cos θ, 0, −sin θ); gravity's moment about +y is
    # r × (0, 0, −m g) · e_y = m g 0.4 cos θ.
    expect = 2.0 * 9.81 * 0.4 * np.cos(th) / i_o
    for method in METHODS:
        assert pend.forward_dynamics([th], [0.7], [0.0], G, method=method)[0] == pytest.approx(
            expect, rel=1e-13
        )
        assert pend.mass_matrix([th], method=method)[0, 0] == pytest.approx(i_o, rel=1e-14)


@pytest.mark.parametrize("ratio", [1e-2, 1e-4, 1e-5, 1e-6])
def test_slender_rod_on_spherical_joint_exact(ratio):
    """One rod on a quaternion Spherical joint at its end: the GIM is the inertia about the
    joint in the body frame, I_O = diag(m d²/8, m d²/16 + m a²/3, ·), so the exact answer is
    a = I_O⁻¹ (τ + r_c × Rᵀ m g − ω × I_O ω), computed here in the body frame (no rounding of
    the small axial moment). cond(I_O) = (a/d)²·8/3: the denoc path keeps full accuracy; the
    recursive path (world-frame articulated inertias) is held to a backward-stable solver's
    bound, 100·eps·cond."""
    m, a = PAPER_M, 1.0
    d = ratio * a
    model = pmd.Model()
    model.add_body(rod_body(m, a, d), pmd.Spherical())
    q = np.array([0.1, 0.2, 0.3, 0.9]) / np.linalg.norm([0.1, 0.2, 0.3, 0.9])
    v = np.array([0.1, 0.5, -0.3])
    tau = np.array([0.01, 0.02, 0.03])
    x, y, z, w = q
    r = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    i_o = np.diag([m * d * d / 8, m * d * d / 16 + m * a * a / 3, m * d * d / 16 + m * a * a / 3])
    exact = np.linalg.solve(
        i_o, tau + np.cross([a / 2, 0, 0], r.T @ (m * G)) - np.cross(v, i_o @ v)
    )
    cond = np.linalg.cond(i_o)
    e_den = rel_err(model.forward_dynamics(q, v, tau, G, method="denoc"), exact)
    e_rec = rel_err(model.forward_dynamics(q, v, tau, G), exact)
    record(f"slender rod on Spherical, d/a={ratio:g}: denoc FD vs exact", e_den)
    record(f"slender rod on Spherical, d/a={ratio:g}: recursive FD vs exact", e_rec)
    assert e_den <= 1e-9, e_den
    assert e_rec <= 100 * np.finfo(float).eps * cond, (e_rec, cond)
    assert rel_err(model.mass_matrix(q, method="denoc"), i_o) <= 1e-14


def test_fixed_body_is_welded_into_parent():
    """A body on a Fixed joint adds its mass, COM and inertia to its parent's link."""
    base = pmd.RigidBody(1.0, [0.2, 0, 0], np.diag([0.01, 0.02, 0.02]))
    tip = pmd.RigidBody(0.5, [0.05, 0.0, 0.0], np.diag([0.001, 0.002, 0.002]))
    welded = pmd.Model()
    welded.add_body(base, pmd.Revolute([0, 0, 1]))
    welded.add_body(tip, pmd.Fixed(), parent=0, translation=[0.4, 0.1, 0.0])
    assert welded.nv == 1 and welded.nlinks == 1 and welded.nbodies == 2
    # By hand: inertia about the joint axis z of both bodies.
    i_zz = 0.02 + 1.0 * 0.2**2 + 0.002 + 0.5 * ((0.4 + 0.05) ** 2 + 0.1**2)
    assert welded.mass_matrix([0.4])[0, 0] == pytest.approx(i_zz, rel=1e-14)
    assert welded.total_mass == pytest.approx(1.5)


def test_kinds_listed_in_q_order():
    tree = random_tree(3, 10)
    model = build_model(tree)
    kinds = moving_kinds(model)
    nq = {"Revolute": 1, "Prismatic": 1, "Spherical": 4, "SphericalZYZ": 3}
    nv = {"Revolute": 1, "Prismatic": 1, "Spherical": 3, "SphericalZYZ": 3}
    assert model.nq == sum(nq[k] for k in kinds) and model.nv == sum(nv[k] for k in kinds)
    q = model.neutral()
    for kind, (iq, _, n_q, _) in zip(kinds, model.joint_slices()):
        assert n_q == nq[kind]
        if kind == "Spherical":
            np.testing.assert_array_equal(q[iq : iq + 4], [0, 0, 0, 1])
