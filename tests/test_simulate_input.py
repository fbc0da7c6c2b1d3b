"""Simulation under bad input and near singular positions: tolerances fixed-step and implicit
methods cannot use, batch parameters that mean nothing, NaN from a user's function or Jacobian,
a ZYZ joint passing near its singularity (a ``SingularityError`` naming it) or far from it (run
to the end, against the exact motion) — and batches of mixed scenes kept run by run."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import G, rod_body
from pointmass_dyn.errors import (
    InvalidInputError,
    SingularityError,
)


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rod_pair(q0, v0):
    """The same rod on SphericalZYZ (from q0, v0) and on Spherical (the same rotation and
    angular velocity: body rates = Rᵀ L(φ, θ) q̇, paper eq 38b)."""
    zyz = pmd.Model()
    zyz.add_body(rod_body(), pmd.SphericalZYZ(), parent=-1, name="rod")
    ball = pmd.Model()
    ball.add_body(rod_body(), pmd.Spherical(), parent=-1, name="rod")
    phi, th, psi = q0
    r = _rz(phi) @ _ry(th) @ _rz(psi)
    lmat = np.array([[0, -np.sin(phi), np.cos(phi) * np.sin(th)],
                     [0, np.cos(phi), np.sin(phi) * np.sin(th)], [1, 0, np.cos(th)]])
    w = 0.5 * np.sqrt(1 + np.trace(r))
    quat = [(r[2, 1] - r[1, 2]) / (4 * w), (r[0, 2] - r[2, 0]) / (4 * w),
            (r[1, 0] - r[0, 1]) / (4 * w), w]
    return (pmd.Scene(zyz, q0, v0, effects=[pmd.Gravity(G)]),
            pmd.Scene(ball, quat, r.T @ lmat @ np.asarray(v0), effects=[pmd.Gravity(G)]))


G_PLANE = np.array([0.0, -9.81, 0.0])


@pytest.fixture(scope="module")
def fourbar():
    return pmd.load_scene("fourbar")


@pytest.fixture(scope="module")
def motion(fourbar):
    return pmd.prescribed_motion(fourbar.model, "crank", speed=30.0, samples=24,
                                 q_guess=fourbar.q0, gravity=G_PLANE)


def test_scene_derivatives_at_the_zyz_singularity_are_singularity_errors():
    m = pmd.Model()
    m.add_body(rod_body(), pmd.SphericalZYZ(), parent=-1, name="rod")
    scene = pmd.Scene(m, [0.1, 0.5, 0.2], np.zeros(3), effects=[pmd.Gravity(G)])
    q = np.array([0.1, 0.0, 0.2])
    with pytest.raises(SingularityError):
        m.forward_dynamics_derivatives(q, np.zeros(3), np.zeros(3))
    with pytest.raises(SingularityError, match="forward_dynamics_derivatives"):
        scene.forward_dynamics_derivatives(q, np.zeros(3))


def test_auto_checks_jac_even_without_switching():
    def fun(t, y):
        return -y

    with pytest.raises(InvalidInputError, match=r"jac\(t, y\)"):
        pmd.solve_ivp(fun, (0, 1), [1.0, 2.0], method="auto", jac=lambda t, y: np.eye(3))
    with pytest.raises(InvalidInputError, match=r"jac\(t0, y0\).*finite"):
        pmd.solve_ivp(fun, (0, 1), [1.0, 2.0], method="auto",
                      jac=lambda t, y: np.full((2, 2), np.nan))
    ok = pmd.solve_ivp(fun, (0, 1), [1.0, 2.0], method="auto", jac=lambda t, y: -np.eye(2))
    assert ok.success and ok.switched_to is None
    np.testing.assert_allclose(ok.y[:, -1], np.exp(-1) * np.array([1.0, 2.0]), rtol=3e-3)


@pytest.mark.parametrize("rtol", [1e-9, 1e-6])
def test_zyz_passing_near_its_singularity_fails_naming_it(rtol):
    zyz, ball = _rod_pair([0.3, 2e-3, 0.2], [0.5, -1.0, 0.3])
    r = pmd.simulate(zyz, (0, 1), rtol=rtol, atol=rtol * 1e-3)
    # On main: success, the rotation 2.4e-3 (rtol 1e-9) or 7.8e-4 (rtol 1e-6) off.
    assert not r.success and "Euler singularity" in r.message and "'rod'" in r.message
    assert 0 < r.t_reached < 1 and r.t[-1] == r.t_reached
    # What it kept is right: the same rotation as the quaternion joint's at that time.
    ref = pmd.simulate(ball, (0, r.t_reached), rtol=1e-12, atol=1e-14)
    got = zyz.model.placements(r.q[-1])[0][0]
    want = ball.model.placements(ref.q[-1])[0][0]
    assert np.abs(got - want).max() < 100 * rtol


def test_zyz_far_from_its_singularity_runs_to_the_end_accurately():
    zyz, ball = _rod_pair([0.3, 0.3, 0.2], [0.5, -1.0, 0.3])
    r = pmd.simulate(zyz, (0, 1), rtol=1e-9, atol=1e-12)
    ref = pmd.simulate(ball, (0, 1), rtol=1e-12, atol=1e-14)
    assert r.success
    got = zyz.model.placements(r.q[-1])[0][0]
    want = ball.model.placements(ref.q[-1])[0][0]
    assert np.abs(got - want).max() < 1e-7


def test_simulate_batch_refuses_non_numeric_params_and_zero_threads():
    scene = pmd.load_scene("pendulum_planar")
    with pytest.raises(InvalidInputError, match=r"params\['gravity'\]: expected numbers"):
        pmd.simulate_batch(scene, (0, 0.1), t_eval=[0, 0.1], params={"gravity": "x"})
    with pytest.raises(InvalidInputError, match="threads: expected a thread count >= 1"):
        pmd.simulate_batch(scene, (0, 0.1), t_eval=[0, 0.1], q0=np.tile(scene.q0, (2, 1)),
                           threads=0)


@pytest.mark.parametrize("method", ["RK4", "Euler"])
def test_fixed_step_methods_refuse_bad_tolerances(method):
    scene = pmd.load_scene("pendulum_planar")
    with pytest.raises(InvalidInputError, match="rtol"):
        pmd.simulate(scene, (0, 0.1), method=method, dt=1e-3, rtol=np.nan)
    with pytest.raises(InvalidInputError, match="atol"):
        pmd.simulate(scene, (0, 0.1), method=method, dt=1e-3, atol=-1)
    ok = pmd.simulate(scene, (0, 0.1), method=method, dt=1e-3)
    assert ok.success and np.all(np.isfinite(ok.q))


def test_simulate_batch_of_mixed_scenes_keeps_each_trajectory():
    pp, chain7 = pmd.load_scene("pendulum_planar"), pmd.load_scene("chain7")
    t_eval = [0.0, 0.25, 0.5]
    batch = pmd.simulate_batch([pp, chain7], (0, 0.5), t_eval=t_eval)
    assert batch.success.all() and batch.q.shape == (2, 3, 7) and batch.v.shape == (2, 3, 7)
    for k, scene in enumerate([pp, chain7]):
        ref = pmd.simulate(scene, (0, 0.5), t_eval=t_eval)
        nq, nv = scene.model.nq, scene.model.nv
        np.testing.assert_allclose(batch.q[k, :, :nq], ref.q, rtol=0, atol=1e-12)
        np.testing.assert_allclose(batch.v[k, :, :nv], ref.v, rtol=0, atol=1e-12)
        assert np.isnan(batch.q[k, :, nq:]).all() and np.isnan(batch.v[k, :, nv:]).all()


def test_simulate_batch_gravity_param_is_the_total_gravity():
    pp = pmd.load_scene("pendulum_planar")
    half = pmd.Effect.gravity(0.5 * G)
    doubled = pp.replace(effects=[half, half])
    g = np.array([[0.0, 0.0, -3.0], [0.0, 0.0, -20.0]])
    batch = pmd.simulate_batch(doubled, (0, 0.5), t_eval=[0.5], params={"gravity": g})
    for k in range(2):
        ref = pmd.simulate(pp.replace(effects=[pmd.Effect.gravity(g[k])]), (0, 0.5),
                           t_eval=[0.5])
        np.testing.assert_allclose(batch.q[k], ref.q, rtol=0, atol=1e-12)


def test_radau_refuses_zero_atol_and_runs_with_zero_rtol():
    pp = pmd.load_scene("pendulum_planar")
    for method in ("Radau", "auto"):
        for rtol, atol in ((0, 0), (1e-6, 0), (1e-6, [1e-8, 1e-8, 0, 1e-8, 1e-8, 1e-8])):
            with pytest.raises(InvalidInputError, match=r"atol: component \d must be > 0 .*got 0"):
                pmd.simulate(pp, (0, 1), method=method, rtol=rtol, atol=atol)
    r = pmd.simulate(pp, (0, 1), method="Radau", rtol=0, atol=1e-10)
    ref = pmd.simulate(pp, (0, 1), method="DOP853", rtol=1e-13, atol=1e-13)
    assert r.success
    np.testing.assert_allclose(r.q[-1], ref.q[-1], rtol=0, atol=1e-7)


def test_radau_names_nan_from_fun_nan_from_jac_and_newton():
    def fun(t, y):  # harmonic oscillator, NaN from t = 0.5 on
        return np.array([y[1], -y[0] if t < 0.5 else np.nan])

    r = pmd.solve_ivp(fun, (0, 1), [1.0, 0.0], method="Radau")
    assert not r.success and "right-hand side returned a non-finite value" in r.message
    assert 0.49 < r.t_reached <= 0.5 and "step size" not in r.message
    np.testing.assert_allclose(r.y[:, -1], [np.cos(r.t_reached), -np.sin(r.t_reached)],
                               atol=1e-3)

    def jac(t, y):
        return np.array([[0.0, 1.0], [-1.0, np.nan if t > 0.5 else 0.0]])

    r = pmd.solve_ivp(lambda t, y: np.array([y[1], -y[0]]), (0, 1), [1.0, 0.0],
                      method="Radau", jac=jac)
    assert not r.success and "the Jacobian returned a non-finite value" in r.message
    assert r.t_reached > 0.5
    # f = 1e20 sin y with a zero Jacobian: Newton contracts only for h below ~1e-20, under
    # the minimum step 10 ulp(1) = 2.2e-15 of a run starting at t = 1.
    r = pmd.solve_ivp(lambda t, y: 1e20 * np.sin(y), (1, 2), [1.0], method="Radau",
                      jac=np.zeros((1, 1)))
    assert not r.success and "Newton iteration did not converge" in r.message
    assert r.t_reached == 1.0


def test_batch_params_errors_name_the_run():
    scene = pmd.load_scene("pendulum_planar")
    with pytest.raises(pmd.errors.InertiaError, match=r"params \(run 2\): mass: .*got -1"):
        pmd.simulate_batch(scene, (0, 0.1), params={"rod.mass": [1.0, 2.0, -1.0]})
    with pytest.raises(InvalidInputError, match=r"params \(run 1\): gravity: .*NaN"):
        pmd.simulate_batch(scene, (0, 0.1), params={"gravity": [[0, 0, -9.8], [0, 0, np.nan]]})
