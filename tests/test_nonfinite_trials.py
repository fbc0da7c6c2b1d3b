"""A trial step whose stages are not finite is a rejected step (docs/integrators.md, "Exact
SciPy equivalence"): RK45 and DOP853 shrink it by SciPy's MIN_FACTOR, as SciPy's NaN/inf
error norm does, and Radau counts it as a Newton failure, as SciPy does; only a non-finite
value at an accepted state or at the minimum step ends the run.

Against live SciPy `solve_ivp` on the same Python function, with a count of the evaluations
SciPy made on NaN/inf (so that each test provably takes the path): the number of steps and
the step grid (GRID_TOL, as test_methods.py), the end state to rounding, and the exact
solution where there is one. `nfev` of RK45 and DOP853 is at most SciPy's: a trial stops at
its first non-finite stage where SciPy evaluates the rest on NaN/inf.
"""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import record, rel_err
from pointmass_dyn.benchmarking import scene_rhs
from scipy.integrate import solve_ivp

GRID_TOL = 1e-4


def counting(fun):
    """`fun` that counts its non-finite results (in `.bad`)."""

    def f(t, y):
        r = fun(t, y)
        if not np.all(np.isfinite(r)):
            f.bad += 1
        return r

    f.bad = 0
    return f


def both(fun, t_span, y0, **kw):
    """(ours, SciPy's, evaluations SciPy made that were not finite) on the same function."""
    f = counting(fun)
    with np.errstate(all="ignore"):
        ref = solve_ivp(f, t_span, y0, **kw)
        ours = pmd.solve_ivp(fun, t_span, y0, **kw)
    return ours, ref, f.bad


def assert_same_steps(ours, ref, name):
    assert ours.success and ref.success, ours.message
    assert len(ours.t) == len(ref.t)
    assert record(f"{name}: step times vs SciPy", rel_err(ours.t, ref.t)) <= GRID_TOL
    assert ours.t[-1] == ref.t[-1]
    assert record(f"{name}: y(t_end) vs SciPy", rel_err(ours.y[:, -1], ref.y[:, -1])) <= 1e-11


@pytest.mark.parametrize("method", ["RK45", "DOP853"])
def test_a_long_step_that_overflows_is_rejected_step_for_step_like_scipy(method):
    """y' = −y³ from 10 (y = 1/√(2t + 0.01)) with a first step of 1: its stages cube their way
    past 1e308 (−190, 7e6, ...), SciPy's error norm is NaN/inf and the step shrinks by 5."""
    ours, ref, bad = both(lambda t, y: -(y**3), (0.0, 10.0), [10.0], method=method, rtol=1e-8,
                          atol=1e-10, first_step=1.0)
    assert bad > 0
    assert_same_steps(ours, ref, f"{method} y' = -y^3")
    assert ours.nfev <= ref.nfev
    assert rel_err(ours.y[0, -1], 1 / np.sqrt(20.01)) < 1e-6


@pytest.mark.parametrize("method", ["RK45", "DOP853"])
def test_non_finite_at_the_minimum_step_ends_the_run_where_scipy_does(method):
    """NaN beyond t = 0.5: the steps close in on 0.5 as SciPy's do, until the step is the
    minimum one; the message names the non-finite value and the time reached. (Within ~1e-14
    of 0.5 rounding decides which stage times pass it: the count of those last steps may
    differ, the time reached does not.)"""

    def f(t, y):
        return -y if t <= 0.5 else np.full_like(y, np.nan)

    ours, ref, bad = both(f, (0.0, 2.0), [1.0], method=method)
    assert bad > 0 and ref.status == ours.status == -1
    early = ref.t < 0.4999
    assert rel_err(ours.t[: early.sum()], ref.t[early]) <= GRID_TOL
    assert ours.t[early.sum()] >= 0.4999
    assert ours.t_reached == ours.t[-1] and abs(ours.t_reached - ref.t[-1]) < 1e-13
    assert "non-finite" in ours.message
    assert ours.message.endswith(f"integration reached t = {float(ours.t_reached)!r}")


def test_radau_recovers_from_a_non_finite_newton_iterate_like_scipy():
    """A pendulum whose force is NaN beyond |θ| = 2 (a domain, as sqrt's): from θ = 1.5 the
    first Newton iterates of a step of 1 leave it; SciPy halves the step, as do we."""

    def f(t, y):
        return np.array([y[1], -100.0 * np.sin(y[0]) * np.sqrt(1.0 - y[0] ** 2 / 4.0)])

    ours, ref, bad = both(f, (0.0, 1.0), [1.5, 0.0], method="Radau", rtol=1e-8, atol=1e-10,
                          first_step=1.0)
    assert bad > 0
    assert_same_steps(ours, ref, "Radau pendulum with a domain")
    assert ours.nfev == ref.nfev


@pytest.mark.parametrize(
    "bad, method",
    [(np.nan, "RK45"), (np.nan, "DOP853"), (np.nan, "Radau"), (np.inf, "RK45"), (np.inf, "DOP853")],
)
def test_a_non_finite_probe_of_the_initial_step_is_scipys(bad, method):
    """y' = −y from 1 whose value at t = 0.01 (where `select_initial_step` probes, h0 = 0.01
    d0/d1) is NaN or inf: SciPy's NaN `d2` drops out of `max(d1, d2)`, an infinite one makes the
    first step the minimum one (then ×10 per step); no failure in either."""

    def f(t, y):
        return np.full_like(y, bad) if t == 0.01 else -y

    ours, ref, n_bad = both(f, (0.0, 1.0), [1.0], method=method, rtol=1e-8, atol=1e-10)
    assert n_bad == 1
    assert_same_steps(ours, ref, f"{method}, {bad} at the initial step's probe")
    assert ours.nfev == ref.nfev
    assert rel_err(ours.y[0, -1], np.exp(-1.0)) < 1e-6


def fourbar_with_pd():
    """The README's bundled four-bar with the stiff PD crank drive of issue 38."""
    base = pmd.load_scene("fourbar")
    q0 = float(base.q0[0])
    drive = pmd.PDTorque("crank", kp=2e4, kd=200, time=[0, 1], reference=[q0, q0 + 30])
    return pmd.Scene(base.model, base.q0, base.v0, effects=list(base.effects) + [drive])


def test_stiff_four_bar_dop853_recovers_like_scipy():
    """DOP853 at rtol = atol = 1e-9: the first trial step (to t = 5e-4) overflows the state.
    The scene's right-hand side in Python, NaN where forward dynamics refuses an overflowed
    state, step for step as SciPy; `simulate` (which projects onto the loop) finishes too and
    ends where SciPy does, to the tolerance."""
    scene = fourbar_with_pd()
    rhs = scene_rhs(scene)
    n = scene.model.nq + scene.model.nv

    def f(t, y):
        if not np.all(np.isfinite(y)):
            return np.full(n, np.nan)
        try:
            return rhs(t, y)
        except pmd.errors.NumericalError:  # "the state overflows double precision"
            return np.full(n, np.nan)

    y0 = np.concatenate([scene.q0, scene.v0])
    span, tol = (0.0, 5e-4), dict(rtol=1e-9, atol=1e-9)
    ours, ref, bad = both(f, span, y0, method="DOP853", **tol)
    assert bad > 0
    assert_same_steps(ours, ref, "DOP853 four-bar + PD")
    sim = pmd.simulate(scene, span, method="DOP853", **tol)
    assert sim.success, sim.message
    err = rel_err(np.concatenate([sim.q[-1], sim.v[-1]]), ref.y[:, -1])
    assert record("DOP853 four-bar + PD: simulate vs SciPy at t_end", err) < 1e-6
