"""pmd.rk45 (our Dormand–Prince 5(4), Rust) against live SciPy `solve_ivp(method="RK45")`
and against exact solutions.

SciPy is the reference for everything that must match step for step; the exact solution
(Krogh's rigid body: Jacobi elliptic functions from scipy.special.ellipj) checks accuracy.

What "step for step" can mean in floating point: the error estimate h·Σ eᵢkᵢ cancels about
seven digits (more at tight tolerances), so its last digits are round-off in both codes, and
NumPy sums through OpenBLAS kernels (FMA, blocked order, CPU-dependent) while we sum in plain
stage order. So: nfev, the number of steps and every accept/reject decision are identical;
values at *fixed* times (t_end, t_eval, sol(t), event times) agree to ~1e-14; the step times
themselves may differ by up to ~1e-7 relative (GRID_TOL), exactly as SciPy's own step times
differ between CPUs.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import record, rel_err
from scipy.integrate import solve_ivp
from scipy.special import ellipj

M = 0.51
Y0 = [0.0, 1.0, 1.0]
T_END = 12.0
TOLS = [1e-6, 1e-8, 1e-10, 1e-12]


def krogh(t, y):
    """Krogh's rigid-body problem; exact solution (sn, cn, dn)(t | 0.51)."""
    return np.array([y[1] * y[2], -y[0] * y[2], -M * y[0] * y[1]])


def exact(t):
    sn, cn, dn, _ = ellipj(t, M)
    return np.array([sn, cn, dn])


def oscillator(t, y):
    """y1 = cos t, y2 = -sin t from (1, 0)."""
    return np.array([y[1], -y[0]])


def scipy_rk45(fun, t_span, y0, **kw):
    return solve_ivp(fun, t_span, y0, method="RK45", **kw)


def event(fun, terminal=None, direction=None):
    """A fresh callable carrying SciPy's optional attributes."""

    def g(t, y):
        return fun(t, y)

    if terminal is not None:
        g.terminal = terminal
    if direction is not None:
        g.direction = direction
    return g


GRID_TOL = 1e-5  # step times / states on the step grid (see the module docstring)
FIXED_TOL = 1e-12  # values at fixed times


def assert_same_run(got, ref, grid_y=True):
    """Same steps as SciPy: identical status, nfev and number of outputs; the end state and the
    output at fixed times to round-off; the step grid to GRID_TOL."""
    assert got.status == ref.status
    assert got.success == ref.success
    assert got.nfev == ref.nfev
    assert got.njev == ref.njev == 0
    assert got.nlu == ref.nlu == 0
    assert got.t.shape == ref.t.shape
    assert got.y.shape == ref.y.shape
    if ref.t.size == 0:
        return
    assert got.t[0] == ref.t[0]
    assert record("rk45 vs scipy: step times", rel_err(got.t, ref.t)) <= GRID_TOL
    if grid_y:
        assert record("rk45 vs scipy: states on the step grid", rel_err(got.y, ref.y)) <= GRID_TOL
    if ref.status == 0:
        assert got.t[-1] == ref.t[-1]
        err = rel_err(got.y[:, -1], ref.y[:, -1])
        assert record("rk45 vs scipy: state at t_end", err) <= FIXED_TOL


# --------------------------------------------------------------------------------------------
# Krogh's rigid body: step for step SciPy, and the exact solution
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("tol", TOLS)
def test_krogh_matches_scipy_step_for_step(tol):
    ref = scipy_rk45(krogh, (0.0, T_END), Y0, rtol=tol, atol=tol)
    got = pmd.rk45(krogh, (0.0, T_END), Y0, rtol=tol, atol=tol)
    assert ref.status == 0
    assert_same_run(got, ref)
    assert got.t[0] == 0.0 and got.t[-1] == T_END
    assert got.y.shape == (3, len(got.t))
    np.testing.assert_array_equal(got.y[:, 0], Y0)
    assert got.t_events is None and got.y_events is None and got.sol is None
    assert "t = 12" in got.message


def test_krogh_error_against_exact_solution_falls_with_tolerance():
    errs = []
    for tol in TOLS:
        got = pmd.rk45(krogh, (0.0, T_END), Y0, rtol=tol, atol=tol)
        ref = scipy_rk45(krogh, (0.0, T_END), Y0, rtol=tol, atol=tol)
        err = np.max(np.abs(got.y[:, -1] - exact(T_END)))
        ref_err = np.max(np.abs(ref.y[:, -1] - exact(T_END)))
        record(f"rk45 Krogh |y(12) - exact| / tol, tol={tol:g}", err / tol)
        # RK45 on this problem: global error ≈ 10-15 × tol (SciPy's own is 11-14 × tol).
        assert 0.1 * tol < err < 20 * tol
        # Same steps, same error; at tol 1e-12 (error ~1e-11) the last bits of y(12) are
        # rounding, which moved SciPy's by up to 7e-14 when its inputs were perturbed by
        # 1e-15 .. 1e-14 relative (tests/perturb.py): a 2 % margin.
        assert abs(err - ref_err) <= 2e-2 * ref_err + 1e-14
        errs.append(err)
    assert all(b < a / 10 for a, b in zip(errs, errs[1:])), errs


def test_exact_reference_is_sane():
    # sn² + cn² = 1, dn² + m sn² = 1 and sn(K) = 1: the reference itself is right.
    t = np.linspace(-10, 10, 41)
    sn, cn, dn = exact(t)
    np.testing.assert_allclose(sn**2 + cn**2, 1.0, atol=1e-14)
    np.testing.assert_allclose(dn**2 + M * sn**2, 1.0, atol=1e-14)
    from scipy.special import ellipk

    assert abs(exact(ellipk(M))[0] - 1.0) < 1e-14


# --------------------------------------------------------------------------------------------
# Options: tolerances, first/max step, t_eval, dense output, backward integration
# --------------------------------------------------------------------------------------------
def test_per_component_tolerances_match_scipy():
    kw = {"rtol": [1e-7, 1e-8, 1e-6], "atol": np.array([1e-9, 1e-8, 1e-3])}
    assert_same_run(
        pmd.rk45(krogh, (0.0, T_END), Y0, **kw), scipy_rk45(krogh, (0.0, T_END), Y0, **kw)
    )


def test_first_step_and_max_step_match_scipy():
    for kw in ({"first_step": 1e-3}, {"max_step": 0.05}, {"first_step": 0.5, "max_step": 0.7}):
        kw.update(rtol=1e-7, atol=1e-9)
        got = pmd.rk45(krogh, (0.0, T_END), Y0, **kw)
        assert_same_run(got, scipy_rk45(krogh, (0.0, T_END), Y0, **kw))
        if "max_step" in kw:
            # np.diff of the step times rounds by up to an ulp of t.
            assert np.max(np.diff(got.t)) <= kw["max_step"] + 4 * np.finfo(float).eps * T_END


def test_tiny_rtol_is_raised_like_scipy():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # SciPy warns that rtol is raised to 100 eps
        ref = scipy_rk45(oscillator, (0.0, 1.0), [1.0, 0.0], rtol=1e-20, atol=1e-12)
    got = pmd.rk45(oscillator, (0.0, 1.0), [1.0, 0.0], rtol=1e-20, atol=1e-12)
    assert_same_run(got, ref)


def test_t_eval_matches_scipy():
    t_eval = np.linspace(0.0, T_END, 37)
    ref = scipy_rk45(krogh, (0.0, T_END), Y0, rtol=1e-8, atol=1e-8, t_eval=t_eval)
    got = pmd.rk45(krogh, (0.0, T_END), Y0, rtol=1e-8, atol=1e-8, t_eval=t_eval)
    assert_same_run(got, ref)
    np.testing.assert_array_equal(got.t, t_eval)
    assert record("rk45 vs scipy: t_eval values", rel_err(got.y, ref.y)) <= FIXED_TOL
    assert np.max(np.abs(got.y - exact(t_eval))) < 20 * 1e-8


def test_dense_output_matches_scipy_sol():
    ref = scipy_rk45(krogh, (0.0, T_END), Y0, rtol=1e-6, atol=1e-6, dense_output=True)
    got = pmd.rk45(krogh, (0.0, T_END), Y0, rtol=1e-6, atol=1e-6, dense_output=True)
    assert_same_run(got, ref)
    ts = np.concatenate([np.linspace(0.0, T_END, 101), got.t[::-1]])
    assert got.sol(ts).shape == (3, ts.size)
    assert record("rk45 vs scipy: dense output", rel_err(got.sol(ts), ref.sol(ts))) <= FIXED_TOL
    # Outside the span SciPy extrapolates the first/last piece; the slightly different end
    # steps make that agree less tightly.
    out = np.array([-0.5, T_END + 0.5])
    assert rel_err(got.sol(out), ref.sol(out)) <= 1e-9
    assert got.sol(5.5).shape == (3,)
    assert rel_err(got.sol(5.5), ref.sol(5.5)) <= FIXED_TOL
    # At the step ends the interpolant reproduces the steps (to round-off).
    assert rel_err(got.sol(got.t), got.y) <= 1e-14
    # Between steps: a 4th-order interpolant, about as accurate as the steps.
    assert np.max(np.abs(got.sol(ts[:101]) - exact(ts[:101]))) < 30 * 1e-6


def test_dense_output_with_t_eval_matches_scipy():
    t_eval = [0.0, 2.5, 5.0, 7.5, 12.0]
    kw = {"rtol": 1e-6, "atol": 1e-6, "dense_output": True, "t_eval": t_eval}
    ref = scipy_rk45(krogh, (0.0, T_END), Y0, **kw)
    got = pmd.rk45(krogh, (0.0, T_END), Y0, **kw)
    assert_same_run(got, ref)
    assert rel_err(got.y, ref.y) <= FIXED_TOL
    ts = np.linspace(0.0, T_END, 57)
    assert rel_err(got.sol(ts), ref.sol(ts)) <= FIXED_TOL


def test_backward_integration_matches_scipy():
    y12 = exact(T_END)
    t_eval = [12.0, 9.0, 3.5, 0.0]
    for kw in ({}, {"t_eval": t_eval}, {"dense_output": True}):
        kw.update(rtol=1e-9, atol=1e-9)
        ref = scipy_rk45(krogh, (T_END, 0.0), y12, **kw)
        got = pmd.rk45(krogh, (T_END, 0.0), y12, **kw)
        assert_same_run(got, ref)
        assert np.all(np.diff(got.t) < 0)
        assert np.max(np.abs(got.y[:, -1] - Y0)) < 20 * 1e-9
        if "dense_output" in kw:
            ts = np.linspace(T_END, 0.0, 31)
            assert rel_err(got.sol(ts), ref.sol(ts)) <= FIXED_TOL
        if "t_eval" in kw:
            assert rel_err(got.y, ref.y) <= FIXED_TOL


# --------------------------------------------------------------------------------------------
# Events
# --------------------------------------------------------------------------------------------
def assert_same_events(got, ref, tol=FIXED_TOL):
    assert len(got.t_events) == len(ref.t_events)
    for gt, rt, gy, ry in zip(got.t_events, ref.t_events, got.y_events, ref.y_events):
        assert gt.shape == rt.shape
        assert gy.shape == ry.shape
        if rt.size:
            assert record("rk45 vs scipy: event times", rel_err(gt, rt)) <= tol
            assert rel_err(gy, ry) <= tol


def test_events_match_scipy():
    evs = [
        event(lambda t, y: y[0]),
        event(lambda t, y: y[1] - 0.5, direction=1),
        event(lambda t, y: y[1] - 0.5, direction=-1),
    ]
    kw = {"rtol": 1e-9, "atol": 1e-9, "events": evs}
    ref = scipy_rk45(krogh, (0.0, 30.0), Y0, **kw)
    got = pmd.rk45(krogh, (0.0, 30.0), Y0, **kw)
    assert_same_run(got, ref)
    assert_same_events(got, ref)
    assert len(got.t_events[0]) >= 7
    # Direction filtering: rising and falling crossings of y2 = 1/2 alternate.
    assert len(got.t_events[1]) >= 3 and len(got.t_events[2]) >= 3
    assert not set(got.t_events[1]) & set(got.t_events[2])


def test_event_times_are_accurate():
    # cos t vanishes at π/2 + kπ.
    kw = {"rtol": 1e-12, "atol": 1e-12, "events": event(lambda t, y: y[0])}
    got = pmd.rk45(oscillator, (0.0, 10.0), [1.0, 0.0], **kw)
    ref = scipy_rk45(oscillator, (0.0, 10.0), [1.0, 0.0], **kw)
    assert_same_events(got, ref)
    expect = np.pi / 2 + np.pi * np.arange(3)
    assert len(got.t_events[0]) == 3
    assert np.max(np.abs(got.t_events[0] - expect)) < 1e-10
    assert got.y_events[0].shape == (3, 2)


def test_terminal_event_matches_scipy():
    evs = [event(lambda t, y: y[0], terminal=True, direction=-1), event(lambda t, y: y[1])]
    kw = {"rtol": 1e-8, "atol": 1e-8, "events": evs}
    ref = scipy_rk45(krogh, (0.0, T_END), Y0, **kw)
    got = pmd.rk45(krogh, (0.0, T_END), Y0, **kw)
    assert ref.status == 1
    assert_same_run(got, ref)
    assert_same_events(got, ref)
    assert got.success and got.status == 1
    assert got.t[-1] == got.t_events[0][-1]
    assert rel_err(got.t[-1], ref.t[-1]) <= FIXED_TOL
    assert rel_err(got.y[:, -1], ref.y[:, -1]) <= FIXED_TOL
    np.testing.assert_allclose(got.y[:, -1], got.y_events[0][-1], rtol=0, atol=1e-15)
    assert "terminal event" in got.message


def test_terminal_count_stops_at_the_nth_occurrence():
    # SciPy's int `terminal`: stop at the 3rd crossing of y1 = 0 (t = 0 is the first).
    plain = pmd.rk45(krogh, (0.0, T_END), Y0, rtol=1e-8, atol=1e-8, events=event(lambda t, y: y[0]))
    got = pmd.rk45(
        krogh, (0.0, T_END), Y0, rtol=1e-8, atol=1e-8, events=event(lambda t, y: y[0], terminal=3)
    )
    assert got.status == 1
    assert len(got.t_events[0]) == 3
    np.testing.assert_array_equal(got.t_events[0], plain.t_events[0][:3])
    assert got.t[-1] == plain.t_events[0][2]


def test_terminal_event_with_t_eval_matches_scipy():
    kw = {
        "rtol": 1e-8,
        "atol": 1e-8,
        "t_eval": np.linspace(0, T_END, 25),
        "events": event(lambda t, y: y[1], terminal=True),
    }
    ref = scipy_rk45(krogh, (0.0, T_END), Y0, **kw)
    got = pmd.rk45(krogh, (0.0, T_END), Y0, **kw)
    assert_same_run(got, ref)
    assert_same_events(got, ref)
    assert got.t[-1] <= got.t_events[0][-1]
    assert rel_err(got.y, ref.y) <= FIXED_TOL  # t_eval values: fixed times


# --------------------------------------------------------------------------------------------
# Failures: a status and a message that says what happened and where, never a hang
# --------------------------------------------------------------------------------------------
def test_blow_up_fails_with_step_too_small_like_scipy():
    # y' = y², y(0) = 1: y = 1/(1 - t) is singular at t = 1.
    ref = scipy_rk45(lambda t, y: y**2, (0.0, 2.0), [1.0])
    got = pmd.rk45(lambda t, y: y**2, (0.0, 2.0), [1.0])
    assert ref.status == -1
    # Near the pole y ~ 1e14 and y' = y², so grid differences are hugely amplified in y.
    assert_same_run(got, ref, grid_y=False)
    assert rel_err(got.t[-1], ref.t[-1]) <= FIXED_TOL
    assert not got.success
    assert "step size fell below the minimum" in got.message
    assert got.message.endswith(f"at t = {float(got.t_reached)!r}")
    assert got.t_reached == got.t[-1]
    assert 0.999 < got.t_reached < 1.0


def test_nan_in_rhs_gives_failure_with_the_time():
    def f(t, y):
        return -y if t < 0.5 else np.full_like(y, np.nan)

    got = pmd.rk45(f, (0.0, 2.0), [1.0])
    assert got.status == -1 and not got.success
    assert "non-finite" in got.message and "t = " in got.message
    assert got.t[-1] < 0.5 and got.t_reached == got.t[-1]


def test_max_steps_is_honoured():
    got = pmd.rk45(krogh, (0.0, T_END), Y0, rtol=1e-10, atol=1e-10, max_steps=5)
    assert got.status == -1
    assert got.t.shape == (6,) and got.y.shape == (3, 6)
    assert "maximum number of steps (5)" in got.message
    ref = scipy_rk45(krogh, (0.0, T_END), Y0, rtol=1e-10, atol=1e-10)
    assert rel_err(got.t, ref.t[:6]) <= GRID_TOL


def test_exception_in_fun_propagates_like_scipy():
    def f(t, y):
        if t > 1.0:
            raise ZeroDivisionError("boom")
        return -y

    with pytest.raises(ZeroDivisionError, match="boom"):
        scipy_rk45(f, (0.0, 3.0), [1.0])
    with pytest.raises(ZeroDivisionError, match="boom"):
        pmd.rk45(f, (0.0, 3.0), [1.0])


@pytest.mark.parametrize(
    "kw, word",
    [
        ({"t_span": (1.0, 1.0)}, "t_span"),
        ({"t_span": (0.0, math.inf)}, "t_span"),
        ({"y0": [0.0, math.nan, 1.0]}, "y0"),
        ({"rtol": -1e-3}, "rtol"),
        ({"atol": -1.0}, "atol"),
        ({"atol": [1e-6, 1e-6]}, "atol"),
        ({"max_step": 0.0}, "max_step"),
        ({"max_step": -1.0}, "max_step"),
        ({"first_step": 0.0}, "first_step"),
        ({"first_step": -1.0}, "first_step"),
        ({"first_step": 20.0}, "first_step"),
        ({"t_eval": [0.0, 13.0]}, "t_eval"),
        ({"t_eval": [3.0, 2.0]}, "t_eval"),
    ],
)
def test_bad_input_raises_value_error_naming_the_argument(kw, word):
    args = {"t_span": (0.0, T_END), "y0": Y0}
    args.update(kw)
    t_span, y0 = args.pop("t_span"), args.pop("y0")
    with pytest.raises(ValueError, match=word):
        pmd.rk45(krogh, t_span, y0, **args)
