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
