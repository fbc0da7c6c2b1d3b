"""`simulate_batch(..., controller=f or [f1, f2, ...])`: each run against its own
`simulate(controller=...)` call (bit for bit: the same loop, run by run), one controller per
run or one for all, per-run start states, params and seeds, and a run whose controller raises
ending with its trajectory so far while the others finish."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn.errors import InvalidInputError

PERIOD = 0.002
T = (0.0, 0.04)


def chain():
    scene = pmd.load_scene("chain7")
    return pmd.Scene(scene.model, q0=scene.q0, effects=[pmd.Gravity((0, 0, -9.81))])


def pd(kp, target):
    def f(t, q, v, sensors):
        return kp * (target - q) - 2.0 * v

    return f


def same(a, b):
    return a.success == b.success and all(np.array_equal(x, y) for x, y in ((a.t, b.t), (a.q, b.q), (a.v, b.v)))


@pytest.mark.parametrize("opts", [dict(method="RK45", rtol=1e-8, atol=1e-10), dict(method="RK4", dt=PERIOD / 2)],
                         ids=lambda o: o["method"])
def test_one_controller_per_run_is_each_runs_simulate_bit_for_bit(opts):
    scene = chain()
    nq = scene.model.nq
    rng = np.random.default_rng(0)
    q0 = np.asarray(scene.q0) + 0.1 * rng.normal(size=(3, nq))
    fs = [pd(30.0, np.zeros(nq)), pd(10.0, 0.2 * np.ones(nq)), pd(50.0, -0.1 * np.ones(nq))]
    batch = pmd.simulate_batch(scene, T, q0=q0, controller=fs, control_period=PERIOD, **opts)
    assert len(batch) == 3 and batch.success.all()
    for b in range(3):
        ref = pmd.simulate(scene.replace(q0=q0[b]), T, controller=fs[b], control_period=PERIOD, **opts)
        assert same(batch.results[b], ref), b
    # Different controllers, different runs (the comparison can fail).
    assert not np.array_equal(batch.results[0].q[-1], batch.results[1].q[-1])


def test_one_controller_for_every_run_with_params_and_seeded_noise():
    scene = chain()
    nq = scene.model.nq
    f = pd(20.0, np.zeros(nq))
    g = np.array([[0, 0, -9.81], [0, 0, -3.0]])
    noise = {"q": 1e-3}
    batch = pmd.simulate_batch(scene, T, params={"gravity": g}, controller=f, control_period=PERIOD,
                               noise=noise, seed=[1, 2], method="RK4", dt=PERIOD)
    for b in range(2):
        s = scene.replace(effects=[pmd.Gravity(g[b])])
        ref = pmd.simulate(s, T, controller=f, control_period=PERIOD, noise=noise, seed=[1, 2][b], method="RK4", dt=PERIOD)
        assert same(batch.results[b], ref), b


def test_a_raising_controller_ends_its_run_only():
    scene = chain()
    nq = scene.model.nq
    good = pd(20.0, np.zeros(nq))

    def bad(t, q, v, s):
        if t > 5 * PERIOD:
            raise ZeroDivisionError("boom")
        return good(t, q, v, s)

    batch = pmd.simulate_batch(scene, T, controller=[good, bad, good], control_period=PERIOD, method="RK4", dt=PERIOD)
    assert list(batch.success) == [True, False, True]
    assert "ZeroDivisionError: boom" in batch.message[1]
    partial = batch.results[1]
    assert partial.t[-1] == pytest.approx(6 * PERIOD)
    # Its trajectory so far is the good controller's (the same until it raised).
    ref = batch.results[0]
    n = len(partial.t)
    assert np.array_equal(partial.q, ref.q[:n]) and np.array_equal(partial.t, ref.t[:n])
    assert batch.t_reached[1] == pytest.approx(6 * PERIOD) and batch.t_reached[0] == pytest.approx(T[1])


def test_controller_batch_bad_input():
    scene = chain()
    f = pd(20.0, np.zeros(scene.model.nq))
    with pytest.raises(InvalidInputError, match="controller"):
        pmd.simulate_batch(scene, T, controller=[f, "x"], control_period=PERIOD)
    with pytest.raises(InvalidInputError, match="controller: expected 3 runs"):
        pmd.simulate_batch(scene, T, q0=np.zeros((3, scene.model.nq)), controller=[f, f], control_period=PERIOD)
    with pytest.raises(InvalidInputError, match="t_eval"):
        pmd.simulate_batch(scene, T, controller=f, t_eval=[0.0, 1.0])
    with pytest.raises(InvalidInputError, match="energy"):
        pmd.simulate_batch(scene, T, controller=f, energy=True)


def test_a_refused_control_ends_its_run_only_with_its_partial_result():
    """A control of the wrong length (here from step 4 on): in ``simulate`` an
    InvalidInputError naming the step with the trajectory so far; in a batch that run ends
    there (the reason and t_reached in its result) and the others are their own runs."""
    scene = chain()
    nq = scene.model.nq
    good = pd(20.0, np.zeros(nq))

    def short(t, q, v, s):
        return good(t, q, v, s)[: 3 if t > 3.5 * PERIOD else nq]

    with pytest.raises(InvalidInputError, match=r"control.*step 4") as e:
        pmd.simulate(scene, T, controller=short, control_period=PERIOD, method="RK4", dt=PERIOD)
    assert e.value.result.t[-1] == pytest.approx(4 * PERIOD)
    for threads in (1, 2):
        batch = pmd.simulate_batch(scene, T, controller=[good, short, good], control_period=PERIOD,
                                   method="RK4", dt=PERIOD, threads=threads)
        assert list(batch.success) == [True, False, True]
        assert "step 4" in batch.message[1] and batch.status[1] == -1
        assert batch.t_reached[1] == pytest.approx(4 * PERIOD)
        ref = pmd.simulate(scene, T, controller=good, control_period=PERIOD, method="RK4", dt=PERIOD)
        n = len(batch.results[1].t)
        assert n == 5 and np.array_equal(batch.results[1].q, ref.q[:n])
        assert same(batch.results[0], ref) and same(batch.results[2], ref)


@pytest.mark.parametrize("opts", [dict(method="RK45", rtol=1e-8, atol=1e-10), dict(method="RK4", dt=PERIOD / 2)],
                         ids=lambda o: o["method"])
def test_controller_batch_has_the_batch_arrays_and_the_same_bits_on_threads(opts):
    """With ``t_eval`` a controller batch gives ``t``, ``q``, ``v`` (B, T, ·) as other batches:
    row b is run b's ``simulate(controller=..., t_eval=...)``, whatever the thread count; at
    the steps' own ends the samples are the every-step trajectory's states, between them the
    interpolant agrees with a tight reference run."""
    scene = chain()
    nq = scene.model.nq
    rng = np.random.default_rng(1)
    q0 = np.asarray(scene.q0) + 0.1 * rng.normal(size=(4, nq))
    f = pd(30.0, np.zeros(nq))
    t_eval = np.linspace(T[0], T[1], 21)  # every period, and half-periods between
    batches = [pmd.simulate_batch(scene, T, q0=q0, controller=f, control_period=PERIOD, t_eval=t_eval,
                                  threads=n, **opts) for n in (1, 2, 4)]
    for batch in batches:
        assert batch.q.shape == (4, 21, nq) and batch.v.shape == (4, 21, scene.model.nv)
        assert np.array_equal(batch.t, t_eval) and batch.success.all()
        assert np.array_equal(batch.q, batches[0].q) and np.array_equal(batch.v, batches[0].v)
    for b in range(4):
        run = scene.replace(q0=q0[b])
        ref = pmd.simulate(run, T, controller=f, control_period=PERIOD, t_eval=t_eval, **opts)
        assert np.array_equal(batches[0].q[b], ref.q) and np.array_equal(batches[0].v[b], ref.v)
        steps = pmd.simulate(run, T, controller=f, control_period=PERIOD, **opts)
        at = np.isin(t_eval, steps.t)
        assert at.sum() >= 11  # the period ends are steps' ends
        assert np.array_equal(ref.q[at], steps.q[np.isin(steps.t, t_eval)])
        tight = pmd.simulate(run, T, controller=f, control_period=PERIOD, t_eval=t_eval, method="DOP853",
                             rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(ref.q, tight.q, rtol=0, atol=1e-5 if opts["method"] == "RK4" else 1e-7)
