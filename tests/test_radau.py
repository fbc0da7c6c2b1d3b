"""Radau IIA (order 5), ``solve_ivp(method="Radau")``, against SciPy's Radau (same steps and
counts where the rounding of the linear algebra does not tip a decision), published
reference solutions (Hairer's test set) and exact solutions; the stiff chain against RK45."""

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn.errors import InvalidInputError
from pointmass_dyn.scenes import builtin_scenes, load_scene
from scipy.integrate import solve_ivp as scipy_solve_ivp


def van_der_pol(mu):
    """Hairer's scaled form: y1' = y2, y2' = ((1 - y1²) y2 - y1)/ε, ε = 1/μ²; t in (0, 2)."""
    eps = 1.0 / mu**2

    def fun(t, y):
        return [y[1], ((1 - y[0] ** 2) * y[1] - y[0]) / eps]

    def jac(t, y):
        return [[0.0, 1.0], [(-2 * y[0] * y[1] - 1) / eps, (1 - y[0] ** 2) / eps]]

    return fun, jac


# y(2) from (2, 0). μ = 1e3: Hairer's test set (VDPOL, ε = 1e-6). The others: SciPy 1.17 Radau
# at rtol = atol = 1e-10 with the analytic Jacobian (agreeing with rtol = 1e-9 and 1e-11 runs
# to ~1e-12).
VDP_REFERENCE = {
    1e3: [1.706167732170483, -0.8928097010247975],
    1e4: [1.7055751811815651, -0.893445288431278],
    1e5: [1.7055475043212927, -0.8934749821192012],
    1e6: [1.7055462175352276, -0.89347636254669],
}


def robertson():
    def fun(t, y):
        return [
            -0.04 * y[0] + 1e4 * y[1] * y[2],
            0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] ** 2,
            3e7 * y[1] ** 2,
        ]

    def jac(t, y):
        return [
            [-0.04, 1e4 * y[2], 1e4 * y[1]],
            [0.04, -1e4 * y[2] - 6e7 * y[1], -1e4 * y[1]],
            [0.0, 6e7 * y[1], 0.0],
        ]

    return fun, jac


# Hairer's test set (ROBER), y(1e11).
ROBERTSON_REFERENCE = [0.2083340149701255e-07, 0.8333360770334713e-13, 0.9999999791665050]


def both(fun, t_span, y0, **kw):
    return (
        scipy_solve_ivp(fun, t_span, y0, method="Radau", **kw),
        pmd.solve_ivp(fun, t_span, y0, method="Radau", **kw),
    )


def counts(r):
    return (len(r.t), r.nfev, r.njev, r.nlu)


def assert_counts_near(ours, ref, steps=0.05, nfev=0.05, nlu=0.05, njev=0.05):
    """Counts within relative margins of SciPy's (each at least one unit)."""
    for name, got, want, margin in (("steps", len(ours.t), len(ref.t), steps),
                                    ("nfev", ours.nfev, ref.nfev, nfev),
                                    ("nlu", ours.nlu, ref.nlu, nlu),
                                    ("njev", ours.njev, ref.njev, njev)):
        assert abs(got - want) <= max(1, margin * want), (name, got, want)


# Step for step only where rounding cannot tip a decision. Found by perturbing SciPy's inputs
# by 1e-15 .. 3e-15 relative (initial state, tolerances, each f value: tests/perturb.py), as
# another CPU's LAPACK/BLAS kernels would: with the analytic Jacobian every count and step
# stayed SciPy's in every variant; with finite-difference Jacobians (their rounding ~1e-8 is
# amplified by ε = 1e-6) the counts moved by up to 2.9 % and the final error by up to 1.24×
# (an Intel Xeon's OpenBLAS moved one late step time by 3.4 %). Those compare with margins,
# and their accuracy against Hairer's reference solution.
@pytest.mark.parametrize("tol", [1e-3, 1e-6])
def test_van_der_pol_mu_1e3_analytic_jacobian_is_scipys_step_for_step(tol):
    fun, jac = van_der_pol(1e3)
    ref, ours = both(fun, (0, 2), [2, 0], rtol=tol, atol=tol, jac=jac)
    assert ours.success and ours.method == "Radau"
    assert counts(ours) == counts(ref)
    # The same steps; rounding moves them slightly in the fast jump near t = 1.6.
    np.testing.assert_allclose(ours.t, ref.t, rtol=1e-2)
    err_ref = np.abs(ref.y[:, -1] - VDP_REFERENCE[1e3]).max()
    err = np.abs(ours.y[:, -1] - VDP_REFERENCE[1e3]).max()
    assert err <= 1.5 * err_ref + 1e-12
    assert err < 100 * tol


@pytest.mark.parametrize("tol", [1e-3, 1e-6])
def test_van_der_pol_mu_1e3_difference_jacobian_costs_and_errs_as_scipy(tol):
    fun, _ = van_der_pol(1e3)
    ref, ours = both(fun, (0, 2), [2, 0], rtol=tol, atol=tol)
    assert ours.success and ours.method == "Radau"
    assert_counts_near(ours, ref, steps=0.06, nfev=0.06, nlu=0.06, njev=0.06)
    err_ref = np.abs(ref.y[:, -1] - VDP_REFERENCE[1e3]).max()
    err = np.abs(ours.y[:, -1] - VDP_REFERENCE[1e3]).max()
    assert err <= 3 * err_ref + 1e-12
    assert err < 100 * tol


@pytest.mark.parametrize("mu", [1e4, 1e5, 1e6])
def test_van_der_pol_very_stiff_costs_and_errs_as_scipy(mu):
    # The Newton matrices have entries up to μ² ~ 1e12: last-bit differences between LAPACK's
    # LU and ours part the step sequences after some steps (as SciPy's own would between
    # BLAS builds); the work and the accuracy stay SciPy's. Perturbing SciPy's inputs by
    # 1e-15 moved its counts by up to 3.4 % and its final error by up to 4× at μ = 1e5 (two
    # valid step sequences), hence the margins; accuracy is against Hairer's reference.
    fun, jac = van_der_pol(mu)
    tol = 1e-4
    ref, ours = both(fun, (0, 2), [2, 0], rtol=tol, atol=tol, jac=jac)
    assert ours.success
    assert ours.nfev <= 1.1 * ref.nfev
    assert abs(len(ours.t) - len(ref.t)) <= 0.1 * len(ref.t)
    err_ref = np.abs(ref.y[:, -1] - VDP_REFERENCE[mu]).max()
    err = np.abs(ours.y[:, -1] - VDP_REFERENCE[mu]).max()
    assert err <= 10 * err_ref + 1e-12
    assert err < 100 * tol


@pytest.mark.parametrize("analytic", [False, True])
def test_robertson_to_1e11_is_scipys(analytic):
    # With the analytic Jacobian, step for step in every perturbed variant (see above); with
    # finite differences, 1e-15 noise on f moved SciPy's counts by up to 1.3 % and its error
    # by up to 100× (ours stays at the unperturbed run's): margins, and accuracy against
    # Hairer's reference.
    fun, jac = robertson()
    kw = dict(rtol=1e-6, atol=1e-9, jac=jac if analytic else None)
    ref, ours = both(fun, (0, 1e11), [1, 0, 0], **kw)
    assert ours.success
    scale = np.abs(ROBERTSON_REFERENCE)
    err = np.abs(ours.y[:, -1] - ROBERTSON_REFERENCE) / scale
    err_ref = np.abs(ref.y[:, -1] - ROBERTSON_REFERENCE) / scale
    if analytic:
        assert counts(ours) == counts(ref)
        assert np.all(err <= 1.1 * err_ref + 1e-9)
    else:
        assert_counts_near(ours, ref)
    assert err.max() < 1e-3
    # Mass is conserved by the equations (the rows of f sum to zero).
    np.testing.assert_allclose(ours.y.sum(axis=0), 1.0, atol=1e-12)


def test_constant_jacobian_is_never_re_evaluated():
    # y' = A y, eigenvalues -1 and -1e4; exact solution known.
    a = np.array([[-5000.5, 4999.5], [4999.5, -5000.5]])

    def fun(t, y):
        return a @ y

    for jac in (a, lambda t, y: a):
        ref, ours = both(fun, (0, 3), [1, 0], rtol=1e-6, atol=1e-9, jac=jac)
        assert counts(ours) == counts(ref)
    # Finite differences: 1e-15 perturbations of SciPy's inputs moved its nfev by up to
    # 5.6 %, nlu by 12 % and njev by one (when to re-evaluate the Jacobian is a decision
    # on a rounding-sized convergence rate).
    ref, ours = both(fun, (0, 3), [1, 0], rtol=1e-6, atol=1e-9, jac=None)
    assert_counts_near(ours, ref, steps=0.05, nfev=0.1, nlu=0.2, njev=0.34)
    np.testing.assert_allclose(ours.y[:, -1], ref.y[:, -1], rtol=1e-5)
    assert ours.njev == 3  # our own count: the Jacobian is re-evaluated rarely
    ref, ours = both(fun, (0, 3), [1, 0], rtol=1e-6, atol=1e-9, jac=a)
    assert ours.njev == 0
    u, v = 0.5 * np.exp(-3.0), 0.5 * np.exp(-3e4)
    np.testing.assert_allclose(ours.y[:, -1], [u + v, u - v], rtol=1e-5)


def test_dense_output_and_events_follow_scipys():
    fun, jac = van_der_pol(1e3)

    def crossing(t, y):
        return y[0]

    crossing.terminal = True
    kw = dict(rtol=1e-6, atol=1e-6, jac=jac, dense_output=True, events=crossing)
    ref, ours = both(fun, (0, 2), [2, 0], **kw)
    assert ours.status == 1 and ref.status == 1
    # Same steps, so the same interpolants: the event times and dense values agree to the
    # rounding of the Newton solves.
    np.testing.assert_allclose(ours.t_events[0], ref.t_events[0], rtol=1e-9)
    assert abs(ours.y_events[0][0][0]) < 1e-9
    ts = np.linspace(0, ref.t_events[0][0], 200)
    np.testing.assert_allclose(ours.sol(ts), ref.sol(ts), rtol=1e-6, atol=1e-8)
    # And the interpolant is accurate against a tight solution between the steps.
    tight = scipy_solve_ivp(fun, (0, 0.5), [2, 0], method="Radau", rtol=1e-10, atol=1e-10,
                            jac=jac, t_eval=ts[ts < 0.5])
    np.testing.assert_allclose(ours.sol(tight.t)[0], tight.y[0], atol=1e-5)


def test_t_eval_matches_the_dense_output():
    fun, jac = van_der_pol(1e3)
    t_eval = np.linspace(0, 2, 41)
    r = pmd.solve_ivp(fun, (0, 2), [2, 0], method="Radau", rtol=1e-6, atol=1e-6, jac=jac,
                      t_eval=t_eval, dense_output=True)
    np.testing.assert_array_equal(r.t, t_eval)
    np.testing.assert_allclose(r.y, r.sol(t_eval), rtol=1e-14, atol=1e-14)


def test_blow_up_fails_with_the_time_reached():
    # y' = y², y(0) = 1: y = 1/(1 - t) blows up at t = 1.
    def fun(t, y):
        return y**2

    ref, ours = both(fun, (0, 2), [1.0], rtol=1e-6, atol=1e-6)
    assert ours.status == -1 and not ours.success
    assert ref.status == -1
    assert abs(ours.t_reached - 1.0) < 1e-3
    assert abs(ours.t[-1] - ref.t[-1]) < 1e-3
    assert "step size fell below the minimum" in ours.message
    assert f"t = {ours.t_reached}" in ours.message


def test_wrong_jacobian_makes_newton_fail_and_the_step_shrink():
    # A zero Jacobian: simplified Newton is then a fixed-point iteration, which converges only
    # for |h λ| small; the failures halve the step, and the result is still right.
    a = np.array([[-5000.5, 4999.5], [4999.5, -5000.5]])

    def fun(t, y):
        return a @ y

    ref, r = both(fun, (0, 0.01), [1, 0], rtol=1e-6, atol=1e-9, jac=np.zeros((2, 2)))
    good = pmd.solve_ivp(fun, (0, 0.01), [1, 0], method="Radau", rtol=1e-6, atol=1e-9, jac=a)
    assert r.success
    assert counts(r) == counts(ref)
    assert len(r.t) > 2 * len(good.t)
    u, v = 0.5 * np.exp(-0.01), 0.5 * np.exp(-100.0)
    np.testing.assert_allclose(r.y[:, -1], [u + v, u - v], rtol=1e-6)


def test_jac_is_checked():
    def fun(t, y):
        return -y

    with pytest.raises(InvalidInputError, match=r"jac: expected shape \(2, 2\), got shape \(3, 3\)"):
        pmd.solve_ivp(fun, (0, 1), [1, 1], method="Radau", jac=np.eye(3))
    with pytest.raises(InvalidInputError, match="jac.*only 'Radau' and 'auto'"):
        pmd.solve_ivp(fun, (0, 1), [1, 1], method="RK45", jac=np.eye(2))
    with pytest.raises(InvalidInputError, match="jac: expected finite entries"):
        pmd.solve_ivp(fun, (0, 1), [1, 1], method="Radau", jac=[[1, np.nan], [0, 1]])
    # A callable returning the wrong shape, or raising: the run stops, the error propagates
    # with the partial result.
    with pytest.raises(InvalidInputError, match=r"jac\(t, y\): expected shape \(2, 2\)") as e:
        pmd.solve_ivp(fun, (0, 1), [1, 1], method="Radau", jac=lambda t, y: np.eye(3))
    assert e.value.result.status == -1

    def failing(t, y):
        raise ZeroDivisionError("no Jacobian")

    with pytest.raises(ZeroDivisionError, match="no Jacobian") as e:
        pmd.solve_ivp(fun, (0, 1), [1, 1], method="Radau", jac=failing)
    assert "jacobian" in e.value.result.message


def test_sparse_jacobian_is_accepted():
    sparse = pytest.importorskip("scipy.sparse")
    fun, jac = robertson()
    dense = pmd.solve_ivp(fun, (0, 40), [1, 0, 0], method="Radau", rtol=1e-6, atol=1e-10,
                          jac=jac)
    sp = pmd.solve_ivp(fun, (0, 40), [1, 0, 0], method="Radau", rtol=1e-6, atol=1e-10,
                       jac=lambda t, y: sparse.csr_matrix(jac(t, y)))
    np.testing.assert_array_equal(sp.t, dense.t)
    # Published y(40) (Hairer & Wanner II, Robertson's problem).
    np.testing.assert_allclose(sp.y[:, -1], [0.7158270687193, 0.9185534764529e-5,
                                             0.2841637457460], rtol=1e-4)


def stiff_chain():
    """chain_stiff if bundled, else chain7 with stiff, heavily damped joints 1-6."""
    if "chain_stiff" in builtin_scenes():
        return load_scene("chain_stiff")
    base = load_scene("chain7")
    joints = [f"link{i}" for i in range(1, 7)]
    effects = list(base.effects) + [
        pmd.Spring(joints, 600.0, 0.0),
        pmd.Damper(joints, 300.0),
    ]
    return base.replace(effects=effects)


def test_stiff_chain_radau_needs_ten_times_fewer_evaluations_than_rk45():
    scene = stiff_chain()
    span = (0.0, 1.0)
    ref = pmd.simulate(scene, span, method="DOP853", rtol=1e-12, atol=1e-12)
    y_ref = np.concatenate([ref.q[-1], ref.v[-1]])
    dim = y_ref.size

    def run(method, tol):
        r = pmd.simulate(scene, span, method=method, rtol=tol, atol=tol)
        assert r.success, r.message
        err = np.abs(np.concatenate([r.q[-1], r.v[-1]]) - y_ref).max()
        # Finite-difference Jacobians (not in nfev, as in SciPy) counted at their most:
        # one evaluation per column plus one retry.
        return err, r.nfev + 2 * dim * r.njev

    radau = [run("Radau", tol) for tol in (1e-4, 1e-6, 1e-8, 1e-10)]
    for tol in (1e-4, 1e-6, 1e-8):
        err, cost = run("RK45", tol)
        cheapest = min(c for e, c in radau if e <= err)
        assert 10 * cheapest <= cost, (tol, err, cost, radau)
