"""The variable-order Adams method (``method="Adams"``, Shampine–Gordon PECE,
docs/integrators.md) from Python: Krogh's rigid body against its exact solution (Jacobi's
elliptic functions), chain7 and the spatial pendulum against SciPy's DOP853 at 1e-13 on our
right-hand side, ``auto`` at tight tolerances, and its argument errors. Events, ``t_eval``,
dense output and failures run with every method in test_methods.py."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import rel_err
from pointmass_dyn.benchmarking import scene_rhs
from scipy.integrate import solve_ivp
from scipy.special import ellipj

M = 0.51


def krogh(t, y):
    return np.array([y[1] * y[2], -y[0] * y[2], -M * y[0] * y[1]])


@pytest.mark.parametrize("tol", [1e-6, 1e-9, 1e-12])
def test_adams_krogh_against_the_exact_solution(tol):
    r = pmd.solve_ivp(krogh, (0.0, 12.0), [0.0, 1.0, 1.0], method="Adams", rtol=tol, atol=tol)
    assert r.success and r.method == "Adams", r.message
    sn, cn, dn, _ = ellipj(12.0, M)
    err = np.max(np.abs(r.y[:, -1] - [sn, cn, dn]))
    assert err < 100 * tol, err
    assert r.njev == 0 and r.nlu == 0


@pytest.mark.parametrize("name, t_end", [("chain7", 1.0), ("pendulum_spatial", 3.0)])
def test_adams_scenes_against_scipy_dop853(name, t_end):
    """SciPy's DOP853 at 1e-13 on the same forward dynamics is the reference."""
    scene = pmd.load_scene(name)
    y0 = np.concatenate([scene.q0, scene.v0])
    t_eval = np.linspace(0.0, t_end, 6)
    ref = solve_ivp(scene_rhs(scene), (0.0, t_end), y0, method="DOP853", rtol=1e-13,
                    atol=1e-13, t_eval=t_eval)
    for tol, bound in [(1e-6, 1e-3), (1e-10, 1e-7)]:
        r = pmd.simulate(scene, (0.0, t_end), method="Adams", rtol=tol, atol=tol, t_eval=t_eval)
        assert r.success and r.method == "Adams", r.message
        got = np.concatenate([r.q, r.v], axis=1).T
        assert rel_err(got, ref.y) < bound, (tol, rel_err(got, ref.y))


def test_adams_argument_errors():
    with pytest.raises(pmd.errors.InvalidInputError, match="atol"):
        pmd.solve_ivp(krogh, (0.0, 1.0), [0.0, 1.0, 1.0], method="Adams", atol=0.0)
    with pytest.raises(pmd.errors.InvalidInputError, match="controller"):
        pmd.solve_ivp(krogh, (0.0, 1.0), [0.0, 1.0, 1.0], method="adams", controller="pi")


# --------------------------------------------------------------------------------------------
# Scenes where `auto` starts on Adams (rtol ≤ 1e-8) but the effects are stiff by design
# --------------------------------------------------------------------------------------------
def test_auto_on_a_contact_scene_at_tight_tolerance_against_radau():
    """box_incline (Hunt–Crossley corners, Coulomb friction) at rtol 1e-9: `auto` starts on
    Adams (handing over to Radau only if its stiffness test fires: here the resting contact
    is not stiff enough to) and agrees with Radau run alone at 1e-12; once sliding, the box
    accelerates downhill at g (sin 30° − μ cos 30°) (the scene's own analytic value)."""
    scene = pmd.load_scene("box_incline")
    t_eval = np.linspace(0.0, 0.5, 11)
    ref = pmd.simulate(scene, (0.0, 0.5), method="Radau", rtol=1e-12, atol=1e-12,
                       t_eval=t_eval)
    ref.raise_for_status()
    r = pmd.simulate(scene, (0.0, 0.5), method="auto", rtol=1e-9, atol=1e-9, t_eval=t_eval)
    r.raise_for_status()
    assert r.method == "auto" and r.switched_to in (None, "Radau"), (r.method, r.switched_to)
    got = np.concatenate([r.q, r.v], axis=1)
    want = np.concatenate([ref.q, ref.v], axis=1)
    assert rel_err(got, want) < 1e-6, rel_err(got, want)
    # Downhill speed (body-frame x, the box's bottom lies along the incline) over the last
    # 0.2 s against the analytic sliding acceleration.
    accel = (r.v[-1, 0] - r.v[-5, 0]) / (r.t[-1] - r.t[-5])
    analytic = 9.81 * (0.5 - 0.3 * np.sqrt(3.0) / 2.0)
    assert accel == pytest.approx(analytic, rel=1e-5), accel


def limit_pendulum():
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0.5, 0, 0], np.eye(3) * 1e-3), pmd.Revolute([0, 0, 1]),
               name="arm")
    return pmd.Scene(m, q0=[0.0], effects=[
        pmd.Gravity([0, -9.81, 0]),
        pmd.JointLimit("arm", -1.0, np.inf, stiffness=2000.0, damping=2.0),
    ])


def test_auto_on_a_joint_limit_scene_at_tight_tolerance_against_radau():
    """A pendulum falling onto a joint limit at −1 rad, at rtol 1e-9 with a terminal event on
    the way down: `auto` (Adams first) against Radau alone at 1e-12 — the states, the event's
    time, and the bound holding (the spring's energy-bounded penetration)."""
    scene = limit_pendulum()
    t_eval = np.linspace(0.0, 2.0, 21)

    def run(**kw):
        r = pmd.simulate(scene, (0.0, 2.0), t_eval=t_eval,
                         events=[pmd.StateEvent("q", 0, -0.5, direction=-1)], **kw)
        r.raise_for_status()
        return r

    ref = run(method="Radau", rtol=1e-12, atol=1e-12)
    r = run(method="auto", rtol=1e-9, atol=1e-9)
    assert r.method == "auto"
    np.testing.assert_allclose(r.t_events[0], ref.t_events[0], rtol=0, atol=1e-7)
    assert len(r.t_events[0]) >= 1
    got = np.concatenate([r.q, r.v], axis=1)
    want = np.concatenate([ref.q, ref.v], axis=1)
    assert rel_err(got, want) < 1e-6, rel_err(got, want)
    k, mgl = 2000.0, 9.81 * 0.5
    a, b, c = 0.5 * k, -mgl, -mgl * np.sin(1.0)
    bound = (-b + np.sqrt(b * b - 4 * a * c)) / (2 * a)
    assert -1.0 - r.q[:, 0].min() <= bound


def test_adams_on_a_loop_scene_by_name():
    """The four-bar (closed loop, kept on its constraint manifold by projection) with Adams
    asked by name: against DOP853 at 1e-12, as accurate as DOP853 at the same tolerance (within
    a factor 10: at rtol 1e-9 every method's error here is ~1e-7) on fewer evaluations (`auto`
    keeps loops on DOP853, whose error control knows the projection; by name Adams runs)."""
    scene = pmd.load_scene("fourbar")
    t_eval = np.linspace(0.0, 1.0, 6)
    ref = pmd.simulate(scene, (0.0, 1.0), method="DOP853", rtol=1e-12, atol=1e-12,
                       t_eval=t_eval)
    ref.raise_for_status()
    want = np.concatenate([ref.q, ref.v], axis=1)
    runs = {}
    for method in ("Adams", "DOP853"):
        r = pmd.simulate(scene, (0.0, 1.0), method=method, rtol=1e-9, atol=1e-9,
                         t_eval=t_eval)
        r.raise_for_status()
        assert r.method == method
        runs[method] = (rel_err(np.concatenate([r.q, r.v], axis=1), want), r.nfev)
    (err, nfev), (err_dop, nfev_dop) = runs["Adams"], runs["DOP853"]
    assert err < max(10 * err_dop, 1e-8), runs
    assert nfev < nfev_dop, runs


def test_auto_with_the_pi_controller_at_tight_tolerance_starts_on_dop853():
    """`auto` keeps a PI controller asked for on its explicit part; Adams has SciPy's
    controller only, so at rtol ≤ 1e-8 `auto` with `controller="pi"` starts on DOP853 (it
    used to refuse the call naming Adams, a method the caller never asked for): the run is
    DOP853's with the PI controller up to where a stiffness test would stop it, here never,
    and within its tolerance of a tight reference."""
    scene = pmd.load_scene("pendulum_spatial")
    opts = dict(rtol=1e-9, atol=1e-9, controller="pi")
    r = pmd.simulate(scene, (0.0, 2.0), method="auto", **opts)
    d = pmd.simulate(scene, (0.0, 2.0), method="DOP853", stiffness="stop", **opts)
    assert r.success and r.switched_to is None
    assert (r.nfev, r.n_accepted) == (d.nfev, d.n_accepted)
    ref = pmd.simulate(scene, (0.0, 2.0), method="DOP853", rtol=1e-13, atol=1e-13)
    assert rel_err(r.q[-1], ref.q[-1]) < 1e-6
    sol = pmd.solve_ivp(krogh, (0.0, 12.0), [0.0, 1.0, 1.0], method="auto", **opts)
    dop = pmd.solve_ivp(krogh, (0.0, 12.0), [0.0, 1.0, 1.0], method="DOP853", **opts)
    assert sol.success and sol.nfev == dop.nfev
