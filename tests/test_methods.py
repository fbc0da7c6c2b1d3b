"""The integration methods beyond RK45 (docs/integrators.md).

* DOP853 (`pmd.solve_ivp(..., method="DOP853")`, `pmd.simulate(..., method="DOP853")`) against
  live SciPy `solve_ivp(method="DOP853")`: nfev, njev, the number of steps and the state
  equal on Krogh's rigid body and on the bundled chain7 at rtol 1e-6 ... 1e-12; the dense
  output against SciPy's `sol(t)`; events.
* RK4 and the semi-implicit Euler against a NumPy implementation of the same scheme (the
  formulas and the time grid as docs/integrators.md states them) on chain7 and on the
  free-flying `satellite` (a quaternion joint).
* Argument errors: unknown method names, a missing or stray `dt`, Radau before it exists.

As in test_rk45.py: the error estimate cancels most of its digits (DOP853's ~9 at rtol 1e-12),
so its last digits are round-off, and NumPy sums it through OpenBLAS in its own order (FMA,
blocking) where we sum in stage order. Every accept/reject decision, nfev and the number of
steps are nevertheless identical; the step times differ by up to ~2e-5 relative (GRID_TOL,
measured: 1.9e-8 at rtol 1e-6, 2e-5 at 1e-12 on Krogh), and values at fixed times agree to
~1e-14 relative (the interpolant at a fixed time does not care where the step ended).
"""

from __future__ import annotations

import math

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import record, rel_err
from scipy.integrate import solve_ivp
from scipy.special import ellipj

M = 0.51
Y0 = [0.0, 1.0, 1.0]
TOLS = [1e-6, 1e-8, 1e-10, 1e-12]
GRID_TOL = 1e-4
G = np.array([0.0, 0.0, -9.81])


def krogh(t, y):
    """Krogh's rigid body (Euler's equations, I1:I2:I3 chosen so that the solution is
    (sn, cn, dn)(t | 0.51))."""
    return np.array([y[1] * y[2], -y[0] * y[2], -M * y[0] * y[1]])


def first_order_rhs(model, gravity=G):
    """[q̇; v̇] of a scene's model through the Python API (q̇ from velocity_to_qdot)."""
    nq = model.nq
    tau = np.zeros(model.nv)
    g = np.asarray(gravity, dtype=float)

    def rhs(t, y):
        q, v = y[:nq], y[nq:]
        return np.concatenate([model.velocity_to_qdot(q, v), model.forward_dynamics(q, v, tau, gravity=g)])

    return rhs


# --------------------------------------------------------------------------------------------
# DOP853 is SciPy's, step for step
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("tol", TOLS)
def test_dop853_krogh_equals_scipy(tol):
    ours = pmd.solve_ivp(krogh, (0.0, 12.0), Y0, method="DOP853", rtol=tol, atol=tol)
    ref = solve_ivp(krogh, (0.0, 12.0), Y0, method="DOP853", rtol=tol, atol=tol)
    assert ours.success and ref.success
    assert ours.method == "DOP853"
    assert (ours.nfev, ours.njev, ours.nlu, len(ours.t)) == (ref.nfev, ref.njev, ref.nlu, len(ref.t))
    np.testing.assert_allclose(ours.t, ref.t, rtol=GRID_TOL, atol=0)
    err = rel_err(ours.y[:, -1], ref.y[:, -1])
    record(f"DOP853 Krogh y(12) vs SciPy DOP853 at {tol:g}", err)
    assert err <= 1e-13
    # Accuracy against the exact solution (Jacobi elliptic functions).
    sn, cn, dn, _ = ellipj(12.0, M)
    assert np.max(np.abs(ours.y[:, -1] - [sn, cn, dn])) < 50 * tol


@pytest.fixture(scope="module")
def chain7():
    return pmd.load_scene("chain7")


@pytest.mark.parametrize("tol", TOLS)
def test_dop853_chain7_equals_scipy(chain7, tol):
    y0 = np.concatenate([chain7.q0, chain7.v0])
    t_span = (0.0, 2.0)
    ours = pmd.simulate(chain7, t_span, rtol=tol, atol=tol, method="DOP853")
    ref = solve_ivp(first_order_rhs(chain7.model), t_span, y0, method="DOP853", rtol=tol, atol=tol)
    assert ours.success and ref.success, ours.message
    assert ours.method == "DOP853"
    assert (ours.nfev, ours.njev, ours.nlu, ours.n_accepted) == (ref.nfev, ref.njev, ref.nlu, len(ref.t) - 1)
    np.testing.assert_allclose(ours.t, ref.t, rtol=GRID_TOL, atol=0)
    err = rel_err(np.concatenate([ours.q[-1], ours.v[-1]]), ref.y[:, -1])
    record(f"DOP853 chain7 y(2) vs SciPy DOP853 at {tol:g}", err)
    assert err <= 1e-11


def test_dop853_dense_output_and_t_eval_equal_scipy(chain7):
    """The 7th-order interpolant as SciPy's `sol(t)`, and nfev counted as SciPy counts the
    three extra stages: on every step with dense output, else only on steps holding a
    t_eval value."""
    rhs = first_order_rhs(chain7.model)
    y0 = np.concatenate([chain7.q0, chain7.v0])
    t_eval = np.linspace(0.0, 1.0, 7)
    opts = dict(rtol=1e-8, atol=1e-8)
    ours = pmd.solve_ivp(rhs, (0.0, 1.0), y0, method="DOP853", dense_output=True, **opts)
    ref = solve_ivp(rhs, (0.0, 1.0), y0, method="DOP853", dense_output=True, **opts)
    assert ours.nfev == ref.nfev
    ts = np.linspace(0.0, 1.0, 101)
    err = rel_err(ours.sol(ts), ref.sol(ts))
    record("DOP853 chain7 sol(t) vs SciPy sol(t), 101 times", err)
    assert err <= 1e-13
    for dense in (False, True):
        ours = pmd.solve_ivp(rhs, (0.0, 1.0), y0, method="DOP853", t_eval=t_eval, dense_output=dense, **opts)
        ref = solve_ivp(rhs, (0.0, 1.0), y0, method="DOP853", t_eval=t_eval, dense_output=dense, **opts)
        assert ours.nfev == ref.nfev
        assert rel_err(ours.y, ref.y) <= 1e-13


def test_dop853_events_equal_scipy():
    """Krogh: y0 crosses zero; the second crossing ends the run (terminal count 2)."""

    def crossing(t, y):
        return y[0]

    crossing.terminal = 2
    ours = pmd.solve_ivp(krogh, (0.0, 30.0), Y0, method="DOP853", rtol=1e-10, atol=1e-10, events=crossing)
    ref = solve_ivp(krogh, (0.0, 30.0), Y0, method="DOP853", rtol=1e-10, atol=1e-10, events=crossing)
    assert ours.status == ref.status == 1
    assert ours.nfev == ref.nfev
    np.testing.assert_allclose(ours.t_events[0], ref.t_events[0], rtol=1e-13)
    np.testing.assert_allclose(ours.y_events[0], ref.y_events[0], rtol=1e-12, atol=1e-13)
    # sn has its zeros at multiples of 2K(0.51).
    from scipy.special import ellipk

    np.testing.assert_allclose(ours.t_events[0], [0.0, 2 * ellipk(M)][: len(ours.t_events[0])], atol=1e-9)


def test_dop853_state_events_in_simulate(chain7):
    """q0 rises through 1 rad (terminal): the same time as RK45 finds, to their accuracy."""
    ev = pmd.StateEvent("q", 0, 1.0, direction=1, terminal=True)
    r = pmd.simulate(chain7, (0.0, 2.0), rtol=1e-10, atol=1e-10, method="DOP853", events=[ev])
    assert r.status == 1 and r.method == "DOP853"
    assert abs(r.q_events[0][0][0] - 1.0) < 1e-12 and r.t[-1] == r.t_events[0][0]
    rk = pmd.simulate(chain7, (0.0, 2.0), rtol=1e-12, atol=1e-12, events=[ev])
    assert abs(r.t_events[0][0] - rk.t_events[0][0]) < 1e-8


# --------------------------------------------------------------------------------------------
# RK4 and Euler: NumPy implementations of the same schemes
# --------------------------------------------------------------------------------------------
def grid_step(t0, t_end, dt, k, t):
    """End and size of step k + 1 (docs/integrators.md): h = dt·dir; the last step ends at
    t_end, with h = dt if the grid point is within 1e-9·dt of it, else h = t_end − t."""
    d = 1.0 if t_end > t0 else -1.0
    h = dt * d
    t_grid = t0 + (k + 1) * h
    if abs(t_grid - t_end) <= 1e-9 * dt:
        return t_end, h
    if d * (t_grid - t_end) > 0:
        return t_end, t_end - t
    return t_grid, h


def normalize(model, y):
    """Unit quaternions, as the integrator's projection (a sum of squares in order)."""
    y = y.copy()
    for at in quaternion_slots(model):
        s = y[at : at + 4]
        n = math.sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2] + s[3] * s[3])
        y[at : at + 4] = s / n
    return y


def quaternion_slots(model):
    """Where the quaternion starts in q: the scenes here have none, or one FreeFlyer at the
    root (q = (x, y, z, qx, qy, qz, qw))."""
    return [3] if model.nq != model.nv else []


def rk4_numpy(f, t0, t_end, y0, dt, model):
    t, y, ts, ys, k = t0, np.asarray(y0, float), [t0], [np.asarray(y0, float)], 0
    while t != t_end:
        t_new, h = grid_step(t0, t_end, dt, k, t)
        k1 = f(t, y)
        k2 = f(t + 0.5 * h, y + 0.5 * h * k1)
        k3 = f(t + 0.5 * h, y + 0.5 * h * k2)
        k4 = f(t + h, y + h * k3)
        y = normalize(model, y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4))
        t, k = t_new, k + 1
        ts.append(t)
        ys.append(y)
    return np.array(ts), np.array(ys)


def euler_numpy(model, f, t0, t_end, y0, dt):
    """Semi-implicit Euler: v ← v + h v̇(q, v), then q ← q + h q̇(q, v_new), normalised."""
    nq = model.nq
    t, y, ts, ys, k = t0, np.asarray(y0, float), [t0], [np.asarray(y0, float)], 0
    while t != t_end:
        t_new, h = grid_step(t0, t_end, dt, k, t)
        a = f(t, y)[nq:]
        v = y[nq:] + h * a
        q = y[:nq] + h * model.velocity_to_qdot(y[:nq], v)
        y = normalize(model, np.concatenate([q, v]))
        t, k = t_new, k + 1
        ts.append(t)
        ys.append(y)
    return np.array(ts), np.array(ys)


@pytest.fixture(scope="module")
def satellite():
    return pmd.load_scene("satellite")


@pytest.mark.parametrize("name", ["chain7", "satellite"])
@pytest.mark.parametrize("method", ["RK4", "Euler"])
def test_fixed_step_methods_equal_numpy(name, method):
    scene = pmd.load_scene(name)
    model = scene.model
    g = G if name == "chain7" else np.zeros(3)
    f = first_order_rhs(model, g)
    y0 = np.concatenate([scene.q0, scene.v0])
    t_end, dt = 0.5, 1.3e-3  # 384 full steps and a shortened last one
    r = pmd.simulate(scene, (0.0, t_end), method=method, dt=dt, energy=True)
    assert r.success and r.method == method, r.message
    if method == "RK4":
        ts, ys = rk4_numpy(f, 0.0, t_end, y0, dt, model)
    else:
        ts, ys = euler_numpy(model, f, 0.0, t_end, y0, dt)
    assert len(r.t) == len(ts) == 386 and r.t[-1] == t_end
    np.testing.assert_array_equal(r.t, ts)
    ours = np.hstack([r.q, r.v])
    err = np.max(np.abs(ours - ys) / (1.0 + np.abs(ys)))
    record(f"{method} {name} vs NumPy {method}, 386 steps", err)
    assert err <= 1e-14
    per_step = 4 if method == "RK4" else 1
    assert r.nfev == per_step * (len(ts) - 1)
    assert (r.njev, r.nlu, r.n_rejected) == (0, 0, 0)
    if name == "satellite":
        # No gravity or torque: the energy is conserved to the method's order.
        e = r.energy
        drift = np.max(np.abs(e - e[0])) / e[0]
        assert drift < (1e-9 if method == "RK4" else 1e-2), drift


def test_fixed_step_solve_ivp_dense_output_is_hermite():
    """pmd.solve_ivp(RK4) on a plain function: the states of the NumPy RK4 and, between them,
    the cubic Hermite through the end states and slopes."""

    def f(t, y):
        return np.array([y[1], -y[0]])

    r = pmd.solve_ivp(f, (0.0, 1.0), [0.0, 1.0], method="RK4", dt=0.1, dense_output=True)
    t, y = 0.0, np.array([0.0, 1.0])
    for k in range(10):
        h = 0.1
        k1 = f(t, y)
        k2 = f(t + 0.5 * h, y + 0.5 * h * k1)
        k3 = f(t + 0.5 * h, y + 0.5 * h * k2)
        k4 = f(t + h, y + h * k3)
        y_new = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        assert np.max(np.abs(r.y[:, k + 1] - y_new)) <= 1e-15
        # Hermite at a third of the step.
        x = 1 / 3
        d = y_new - y
        a, b = h * f(t, y), h * f(t + h, y_new)
        herm = y + (a * x + (3 * d - 2 * a - b) * x**2 + (a + b - 2 * d) * x**3)
        np.testing.assert_allclose(r.sol(t + x * h), herm, rtol=0, atol=1e-15)
        t, y = r.t[k + 1], y_new
    assert r.nfev == 41  # 4 per step, and f(1) for the last step's interpolant


# --------------------------------------------------------------------------------------------
# Plumbing and errors
# --------------------------------------------------------------------------------------------
def test_methods_agree_with_each_other_on_chain7(chain7):
    """Every method reaches the same state (to its accuracy) on a short run."""
    ref = pmd.simulate(chain7, (0.0, 0.5), rtol=1e-12, atol=1e-12, method="DOP853")
    for method, kw, tol in [
        ("RK45", dict(rtol=1e-10, atol=1e-10), 1e-7),
        ("rk4", dict(dt=1e-3), 1e-7),
        ("euler", dict(dt=1e-4), 5e-2),
    ]:
        r = pmd.simulate(chain7, (0.0, 0.5), method=method, **kw)
        assert r.success
        assert rel_err(r.q[-1], ref.q[-1]) < tol, method


def test_scene_file_method_and_cli(tmp_path, chain7):
    from pointmass_dyn.cli import main
    from pointmass_dyn.scenes import builtin_scenes

    src = builtin_scenes()["chain7"].read_text()
    path = tmp_path / "c.toml"
    path.write_text(src.replace("[simulate]", '[simulate]\nmethod = "RK4"\ndt = 1e-3'))
    scene = pmd.load_scene(str(path))
    assert (scene.method, scene.dt) == ("RK4", 1e-3)
    r = pmd.simulate(scene, (0.0, 0.1))
    assert r.method == "RK4" and r.n_accepted == 100
    # The caller's argument beats the scene's.
    assert pmd.simulate(scene, (0.0, 0.1), method="DOP853").method == "DOP853"
    assert main(["simulate", str(path), "--t-end", "0.05", "--method", "euler", "--dt", "1e-3"]) == 0


def test_batch_takes_a_method(chain7):
    b = pmd.simulate_batch(chain7, (0.0, 0.2), method="RK4", dt=1e-3, threads=2,
                           q0=np.array([chain7.q0, chain7.q0 * 0.5]))
    single = pmd.simulate(chain7, (0.0, 0.2), method="RK4", dt=1e-3)
    assert all(r.method == "RK4" for r in b.results)
    np.testing.assert_array_equal(b.results[0].q, single.q)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(method="RK5"), r"method: expected one of 'RK45', 'DOP853'.*got 'RK5'"),
        (dict(method="RK4"), r"dt: method 'RK4' takes a fixed step size dt > 0, got none"),
        (dict(method="Euler", dt=0.0), r"dt: must be positive and finite, got 0"),
        (dict(method="DOP853", dt=0.1), r"dt: only the fixed-step methods 'RK4' and 'Euler' take dt"),
        (dict(method="Radau", controller="pi"), r"controller: method 'Radau' has SciPy's controller only"),
    ],
)
def test_bad_method_arguments(chain7, kwargs, match):
    with pytest.raises(pmd.errors.InvalidInputError, match=match):
        pmd.simulate(chain7, (0.0, 1.0), **kwargs)
    with pytest.raises(pmd.errors.InvalidInputError, match=match):
        pmd.solve_ivp(krogh, (0.0, 1.0), Y0, **kwargs)


def test_dop853_has_the_pi_controller_and_the_stiffness_test():
    """DOP853 runs on the explicit Runge–Kutta engine RK45 uses: the PI controller (not
    SciPy's steps, same accuracy against a tight SciPy reference) and Hairer's stiffness
    test (DOP853's threshold h·|λ| > 6.1), which stops y' = −1e4 (y − cos t) early."""
    ref = solve_ivp(krogh, (0.0, 12.0), Y0, method="DOP853", rtol=1e-13, atol=1e-13)
    opts = dict(method="DOP853", rtol=1e-9, atol=1e-9)
    std = pmd.solve_ivp(krogh, (0.0, 12.0), Y0, **opts)
    pi = pmd.solve_ivp(krogh, (0.0, 12.0), Y0, controller="pi", **opts)
    assert std.success and pi.success
    assert pi.nfev != std.nfev
    for r in (std, pi):
        assert np.max(np.abs(r.y[:, -1] - ref.y[:, -1])) < 1e-7

    def f(t, y):
        return np.array([-1e4 * (y[0] - np.cos(t))])

    stop = pmd.solve_ivp(f, (0.0, 2.0), [0.0], method="DOP853", stiffness="stop", rtol=1e-6,
                         atol=1e-9)
    assert stop.status == -1 and "stiff" in stop.message and stop.t_reached < 0.1
    alone = pmd.solve_ivp(f, (0.0, 2.0), [0.0], method="DOP853", rtol=1e-6, atol=1e-9)
    assert alone.success and "looks stiff" in alone.message


def test_rk45_alias_and_default_method():
    a = pmd.rk45(krogh, (0.0, 1.0), Y0, rtol=1e-8, atol=1e-8)
    b = pmd.solve_ivp(krogh, (0.0, 1.0), Y0, rtol=1e-8, atol=1e-8)
    ref = solve_ivp(krogh, (0.0, 1.0), Y0, rtol=1e-8, atol=1e-8)
    assert a.method == b.method == "RK45"
    assert a.nfev == b.nfev == ref.nfev
    np.testing.assert_array_equal(a.y, b.y)


# --------------------------------------------------------------------------------------------
# Outputs, events and statuses with every method
# --------------------------------------------------------------------------------------------
EXPLICIT = [
    dict(method="RK45"),
    dict(method="DOP853"),
    dict(method="Adams"),
    dict(method="RK4", dt=0.01),
    dict(method="Euler", dt=1e-3),
]


@pytest.mark.parametrize("kw", EXPLICIT, ids=lambda kw: kw["method"])
def test_t_eval_events_and_dense_output_with_every_method(kw):
    """The oscillator (sin t, cos t): t_eval values, the falling zero of y0 at π as a terminal
    event, and a pickled dense output that evaluates as before."""
    import pickle

    def f(t, y):
        return np.array([y[1], -y[0]])

    def zero(t, y):
        return y[0]

    zero.terminal = True
    zero.direction = -1
    t_eval = np.linspace(0.0, 3.0, 7)
    acc = 1e-2 if kw["method"] == "Euler" else 1e-5
    r = pmd.solve_ivp(f, (0.0, 10.0), [0.0, 1.0], t_eval=t_eval, events=zero, dense_output=True,
                      rtol=1e-8, atol=1e-8, **kw)
    assert r.status == 1 and r.method == kw["method"], r.message
    np.testing.assert_array_equal(r.t, t_eval)
    np.testing.assert_allclose(r.y[0], np.sin(t_eval), atol=acc)
    assert abs(r.t_events[0][0] - np.pi) < acc
    assert r.t_reached == r.t_events[0][0]
    back = pickle.loads(pickle.dumps(r.sol))
    ts = np.linspace(0.0, 3.0, 13)
    np.testing.assert_array_equal(back(ts), r.sol(ts))
    np.testing.assert_allclose(r.sol(ts)[1], np.cos(ts), atol=acc)


@pytest.mark.parametrize("kw", EXPLICIT, ids=lambda kw: kw["method"])
def test_failures_report_reason_and_time_with_every_method(kw):
    """A right-hand side that turns NaN at t > 0.5, one that raises, and max_steps."""

    def nan_late(t, y):
        return np.array([np.nan if t > 0.5 else 1.0])

    r = pmd.solve_ivp(nan_late, (0.0, 1.0), [0.0], **kw)
    assert r.status == -1 and not r.success
    # The time reached is the last accepted state (Euler evaluates at the start of its step).
    assert "non-finite" in r.message and 0.0 < r.t_reached <= 0.5 + 2e-3, r.message

    class Boom(RuntimeError):
        pass

    def boom(t, y):
        if t > 0.25:
            raise Boom("no")
        return np.array([1.0])

    with pytest.raises(Boom) as exc:
        pmd.solve_ivp(boom, (0.0, 1.0), [0.0], **kw)
    assert 0.0 < exc.value.result.t_reached <= 0.25 + 2e-3

    r = pmd.solve_ivp(lambda t, y: -y, (0.0, 50.0), [1.0], max_steps=3, **kw)
    assert r.status == -1 and "maximum number of steps (3)" in r.message
    assert r.n_accepted == 3


def test_energy_and_power_with_fixed_steps(chain7):
    """Gravity only (conservative): RK4's energy drift falls as dt⁴."""
    drifts = []
    for dt in (4e-3, 2e-3):
        r = pmd.simulate(chain7, (0.0, 0.4), method="RK4", dt=dt, energy=True, power=True)
        assert r.energy.shape == r.t.shape and "gravity" in r.power
        drifts.append(np.max(np.abs(r.energy - r.energy[0])))
    assert 8 < drifts[0] / drifts[1] < 32, drifts


def test_auto_switches_to_radau_where_rk45_finds_the_problem_stiff():
    """y' = −1e4 (y − cos t): RK45 until Hairer's test fires, Radau from there. The switch
    time is where RK45 alone (stiffness="stop") stops; the end state matches SciPy's Radau
    to the tolerance; far fewer evaluations than RK45 alone."""

    def f(t, y):
        return np.array([-1e4 * (y[0] - np.cos(t))])

    opts = dict(rtol=1e-6, atol=1e-9)
    r = pmd.solve_ivp(f, (0.0, 2.0), [0.0], method="auto", dense_output=True, **opts)
    assert r.success and r.method == "auto" and r.switched_to == "Radau", r.message
    stop = pmd.solve_ivp(f, (0.0, 2.0), [0.0], stiffness="stop", **opts)
    assert stop.status == -1 and r.t_switch == stop.t_reached
    assert "switched from RK45 to Radau" in r.message
    np.testing.assert_array_equal(r.t[: len(stop.t)], stop.t)
    ref = solve_ivp(f, (0.0, 2.0), [0.0], method="Radau", rtol=1e-10, atol=1e-12)
    assert abs(r.y[0, -1] - ref.y[0, -1]) < 1e-5
    # The dense output passes through every step's state; between Radau's long steps (~0.9)
    # its cubic collocation polynomial is accurate to O(h⁴), not to the tolerance (as SciPy's).
    np.testing.assert_allclose(r.sol(r.t)[0], r.y[0], rtol=0, atol=1e-12)
    assert abs(r.sol(1.5)[0] - (np.cos(1.5) + 1e-4 * np.sin(1.5))) < 5e-4
    alone = pmd.solve_ivp(f, (0.0, 2.0), [0.0], **opts)
    assert r.nfev < alone.nfev / 5 and r.njev >= 1 and r.nlu >= 1
    # The scene route: simulate(method="auto") on a non-stiff scene never switches.
    s = pmd.simulate(pmd.load_scene("chain7"), (0.0, 0.5), method="auto")
    assert s.success and s.switched_to is None and s.t_switch is None


def test_fixed_steps_on_a_closed_loop_converge_at_their_order():
    """fourbar (a closed loop, projected after every step): halving dt divides the error
    against a DOP853 reference by ~16 for RK4 and ~2 for Euler; the loop stays closed."""
    scene = pmd.load_scene("fourbar")
    ref = pmd.simulate(scene, (0.0, 0.5), rtol=1e-12, atol=1e-12, method="DOP853")
    for method, dts, lo, hi in [("RK4", (2e-3, 1e-3), 12, 80), ("Euler", (2e-4, 1e-4), 1.8, 2.2)]:
        errs = []
        for dt in dts:
            r = pmd.simulate(scene, (0.0, 0.5), method=method, dt=dt)
            assert r.success and r.constraint_residual.max() < 1e-12
            errs.append(np.max(np.abs(r.q[-1] - ref.q[-1])))
        assert lo < errs[0] / errs[1] < hi, (method, errs)
