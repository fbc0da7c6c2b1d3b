"""Andrews' squeezing mechanism (bundled scene `andrews`) against the published problem
(tests/andrews.py: the Test Set for IVP Solvers' equations, initial values and reference
solution at t = 0.03 s)."""

from __future__ import annotations

import andrews as ref
import numpy as np
import pointmass_dyn as pmd
import pytest

#: Our coordinates (bodies in tree order: β, Θ, γ, δ, Φ, ε, Ω) as indices into the paper's.
PERM = np.array([0, 1, 2, 4, 3, 6, 5])
INV = np.argsort(PERM)


@pytest.fixture(scope="module")
def scene():
    return pmd.load_scene("andrews")


def test_three_revolute_cut_joints_close_seven_bodies(scene):
    m = scene.model
    assert (m.nbodies, m.nv, m.nloops, m.nconstraints) == (7, 7, 3, 15)
    # Six independent constraints (two per planar loop): one degree of freedom.
    assert np.linalg.matrix_rank(m.constraint_jacobian(scene.q0), tol=1e-10) == 6
    # The loader's closing of the published initial state moved nothing.
    np.testing.assert_allclose(scene.q0, ref.Q0[PERM], rtol=0, atol=1e-15)
    assert np.abs(ref.constraints(ref.Q0)).max() < 1e-16 + 1e-15


@pytest.mark.parametrize("seed", range(5))
def test_tree_mass_matrix_and_velocity_forces_equal_the_published_ones(scene, seed):
    rng = np.random.default_rng(seed)
    q, v = rng.uniform(-np.pi, np.pi, 7), rng.normal(scale=300.0, size=7)
    m = scene.model
    mm = ref.mass_matrix(q)[np.ix_(PERM, PERM)]
    np.testing.assert_allclose(m.mass_matrix(q[PERM]), mm, rtol=0, atol=1e-15 * np.abs(mm).max())
    c = -ref.velocity_forces(q, v)[PERM]
    np.testing.assert_allclose(
        m.bias_forces(q[PERM], v[PERM]), c, rtol=0, atol=1e-13 * np.abs(c).max()
    )


def test_constraint_jacobian_spans_the_published_one(scene):
    # Ours has 15 rows (5 per spatial revolute cut), the paper's 6 (x, y per loop): the same
    # row space.
    rng = np.random.default_rng(3)
    q = scene.model.assemble(scene.q0 + rng.normal(scale=0.05, size=7), fixed=["K1"])
    ours = scene.model.constraint_jacobian(q)
    theirs = ref.constraint_jacobian(q[INV])[:, PERM]
    assert np.abs(ref.constraints(q[INV])).max() < 1e-14
    both = np.vstack([ours, theirs])
    assert np.linalg.matrix_rank(both, tol=1e-10) == 6


def test_initial_accelerations_and_multipliers_equal_the_published_ones(scene):
    m = scene.model
    tau = ref.applied_forces(ref.Q0)[PERM]
    a = m.forward_dynamics(scene.q0, np.zeros(7), tau)
    np.testing.assert_allclose(a, ref.A0[PERM], rtol=0, atol=1e-13 * np.abs(ref.A0).max())
    # The cut joint K2–K3 carries the paper's λ₁, λ₂ (force on K3, world axes; ours is in
    # K2's frame); the other two carry nothing at t = 0.
    forces = m.constraint_forces(scene.q0, np.zeros(7), tau)
    c, s = np.cos(ref.Q0[0] + ref.Q0[1]), np.sin(ref.Q0[0] + ref.Q0[1])
    lam_in_k2 = np.array([[c, s], [-s, c]]) @ ref.LAMBDA0[:2]
    np.testing.assert_allclose(
        forces[0, :2], lam_in_k2, rtol=0, atol=1e-12 * np.abs(lam_in_k2).max()
    )
    np.testing.assert_allclose(forces[1:, :2], 0.0, atol=1e-10)


@pytest.mark.parametrize("seed", range(5))
def test_scene_spring_is_the_published_one(scene, seed):
    # The scene's point spring (D on K3 to the ground point C) against the paper's
    # generalized force and its potential ½ c0 (l − l0)², at random configurations.
    rng = np.random.default_rng(seed)
    q, v = rng.uniform(-np.pi, np.pi, 7), rng.normal(scale=300.0, size=7)
    forces = pmd.effect_forces(scene, 0.0, q[PERM], v[PERM])
    assert set(forces) == {"drive", "spring"}
    want = ref.applied_forces(q)
    want[0] = 0.0  # the drive
    np.testing.assert_allclose(
        forces["spring"], want[PERM], rtol=0, atol=1e-13 * np.abs(want).max()
    )
    p = ref.P
    length = np.hypot(*(ref.spring_point(q) - [p["xc"], p["yc"]]))
    energy = pmd.energies(scene, q[PERM], v[PERM])["spring"]
    assert energy == pytest.approx(0.5 * p["c0"] * (length - p["l0"]) ** 2, rel=1e-13)


def test_solution_at_t_003_has_eight_significant_digits(scene):
    # The bundled scene as loaded: its own drive and spring, tolerances and end time.
    assert [e.name for e in scene.effects] == ["drive", "spring"]
    res = pmd.simulate(scene)
    assert res.success, res.message
    assert res.t[-1] == ref.T_END
    q, v = res.q[-1][INV], res.v[-1][INV]
    # The reference itself carries about 1e-9 rad of error: 8 digits is the bar.
    np.testing.assert_allclose(q, ref.Q_END, rtol=1e-8)
    np.testing.assert_allclose(v, ref.V_END, rtol=0, atol=1e-8 * np.abs(ref.V_END).max())
    assert res.constraint_residual.max() <= 1e-10
    assert res.constraint_drift <= 1e-10


def test_radau_keeps_eight_digits_with_the_projected_systems_newton_matrix(scene):
    # Issue 27: Radau's Newton matrices are those of f(P(y)), the right-hand side evaluated at
    # the stage's projection (J_f P'), not J_f alone: before, the contraction was slow across
    # the manifolds and the Jacobian was re-evaluated on 348 of 1214 steps.
    res = pmd.simulate(scene, (0, ref.T_END), method="Radau", rtol=1e-8, atol=1e-10)
    assert res.success, res.message
    np.testing.assert_allclose(res.q[-1][INV], ref.Q_END, rtol=1e-8)
    assert res.njev < 0.1 * res.n_accepted


def test_radau_error_estimate_ignores_what_the_projection_removes(scene):
    # SciPy's Radau on the published index-1 equations (no projection, the same estimate)
    # against ours, whose estimate keeps only its part along the constraint manifolds
    # (P(y + err) - y): the components across them are removed by the step's projection, so
    # they are not errors of the solution. Fewer steps, the same accuracy.
    from scipy.integrate import solve_ivp

    def fun(_, y):
        return np.concatenate([y[7:], ref.index1_rhs(y[:7], y[7:])[0]])

    y0 = np.concatenate([ref.Q0, np.zeros(7)])
    tol = dict(rtol=1e-6, atol=1e-8)
    theirs = solve_ivp(fun, (0, ref.T_END), y0, method="Radau", **tol)
    ours = pmd.simulate(scene, (0, ref.T_END), method="Radau", **tol)
    assert ours.success, ours.message
    assert ours.n_accepted < 0.75 * (len(theirs.t) - 1)
    err_theirs = np.abs(theirs.y[:7, -1] - ref.Q_END).max()
    err_ours = np.abs(ours.q[-1][INV] - ref.Q_END).max()
    assert err_ours < max(3 * err_theirs, 1e-7)
