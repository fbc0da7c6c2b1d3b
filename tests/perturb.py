"""Pytest plugin that finds comparisons fragile to rounding: every call of SciPy's
``solve_ivp`` gets its initial state and tolerances multiplied by (1 + δ), δ ~ 1e-15, as
another CPU's BLAS/LAPACK kernel would move SciPy's last bits. A comparison whose verdict
flips under this is fragile and must assert margins plus accuracy instead of equality.

    PYTHONPATH=tests POINTMASS_DYN_PERTURB=1e-15 python -m pytest -p perturb tests/...

``POINTMASS_DYN_PERTURB`` is δ (negative allowed); ``POINTMASS_DYN_PERTURB_WHAT`` is
``y0``, ``tol``, ``both`` (the default) or ``fun``: every value ``fun`` returns to SciPy
multiplied by (1 ± δ), random signs (seed 0), as another kernel rounds each evaluation.
Off unless the variable is set.

Record (issue 26; δ = ±1e-15, ±3e-15 on y0 and tolerances, and 1e-15 noise on f), over
test_radau, test_rk45, test_methods, test_work_precision, test_hard_cases, test_simulate and
test_free_flyer. Flipped, now margins plus accuracy against a reference: test_radau's van der
Pol μ = 1e3 with finite-difference Jacobians, van der Pol μ = 1e5 (error ratio), Robertson
with finite differences, the constant-Jacobian test's finite-difference run; test_hard_cases'
stiff Prothero–Robinson under RK45; test_rk45's Krogh error comparison at tol 1e-12 (only at
3e-15). Never flipped, kept step for step: every RK45 and DOP853 comparison (Krogh, chain7,
events, dense output, work-precision rows), Radau with analytic or constant Jacobians.
"""

from __future__ import annotations

import functools
import os

import numpy as np


def _noisy(fun, delta, rng):
    def noisy(t, y, *args):
        f = np.asarray(fun(t, y, *args), dtype=float)
        return f * (1.0 + delta * rng.choice([-1.0, 1.0], size=f.shape))

    return noisy


def _perturbed(solve_ivp, delta, what):
    rng = np.random.default_rng(0)

    @functools.wraps(solve_ivp)
    def wrapper(fun, t_span, y0, *args, **kw):
        if what == "fun":
            fun = _noisy(fun, delta, rng)
        if what in ("y0", "both"):
            y0 = np.asarray(y0, dtype=float) * (1.0 + delta)
        if what in ("tol", "both"):
            for name, default in (("rtol", 1e-3), ("atol", 1e-6)):
                kw[name] = np.asarray(kw.get(name, default), dtype=float) * (1.0 + delta)
                if kw[name].ndim == 0:
                    kw[name] = float(kw[name])
        return solve_ivp(fun, t_span, y0, *args, **kw)

    return wrapper


def pytest_configure(config):
    delta = os.environ.get("POINTMASS_DYN_PERTURB")
    if not delta:
        return
    import scipy.integrate

    what = os.environ.get("POINTMASS_DYN_PERTURB_WHAT", "both")
    scipy.integrate.solve_ivp = _perturbed(scipy.integrate.solve_ivp, float(delta), what)
