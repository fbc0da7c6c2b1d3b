"""A run or analysis that stops — Ctrl-C, a progress callback that raises, an exception in a
user callback, a failure — keeps what it did: the partial result on the exception (or the
result with ``success=False``), the reason and the time reached, each checked against the same
run uninterrupted or against what the stop must be."""

from __future__ import annotations

import pickle

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import G
from conftest import revolute_chain as chain
from ctrl_c import CtrlC


def chain_scene(n: int, effects=None) -> pmd.Scene:
    m = chain(n)
    q0 = np.linspace(0.1, 0.5, n)
    return pmd.Scene(m, q0, np.zeros(n), effects=[pmd.Gravity(G)] + list(effects or []))


class _Boom(Exception):
    pass


@pytest.fixture(scope="module")
def fourbar_motion():
    scene = pmd.load_scene("fourbar")
    motion = pmd.prescribed_motion(
        scene.model, "crank", speed=2 * np.pi, samples=36, q_guess=scene.q0, gravity=G
    )
    return scene, motion


def _stoppable_batch_args():
    scene = pmd.load_scene("pendulum_planar")
    q0 = scene.q0 + np.linspace(0.0, 1.0, 400)[:, None]
    return scene, q0, {"t_span": (0, 50), "rtol": 1e-11, "atol": 1e-12, "threads": 2}


def _check_partial_batch(scene, q0, kw, batch):
    assert isinstance(batch, pmd.BatchResult) and len(batch) == len(q0)
    done = np.flatnonzero(batch.success)
    assert 0 < len(done) < len(q0)
    # A finished run is the simulate call it stands for (an independent single run).
    k = done[-1]
    single = pmd.Scene(scene.model, q0[k], scene.v0, scene.effects)
    ref = pmd.simulate(single, kw["t_span"], rtol=kw["rtol"], atol=kw["atol"])
    np.testing.assert_allclose(batch.results[k].q[-1], ref.q[-1], rtol=0, atol=1e-12)
    # Every other run says why it stopped and how far it got.
    for k in np.flatnonzero(~batch.success):
        r = batch.results[k]
        assert batch.status[k] == -1
        assert "interrupted" in r.message or "stopped before this run started" in r.message
        # The typed status says the same: stopped midway (time reached, where) or never run.
        if isinstance(r.outcome, pmd.RunStatus.Interrupted):
            assert r.outcome.t == r.t_reached and r.outcome.at >= r.outcome.t
        else:
            assert isinstance(r.outcome, pmd.RunStatus.NotStarted) and len(r.t) == 0
            assert r.outcome.reason == r.message
        if len(r.t):
            assert r.t[-1] == pytest.approx(r.t_reached) and r.t_reached < 50


G_PLANE = np.array([0.0, -9.81, 0.0])


@pytest.fixture(scope="module")
def fourbar():
    return pmd.load_scene("fourbar")


@pytest.fixture(scope="module")
def motion(fourbar):
    return pmd.prescribed_motion(fourbar.model, "crank", speed=30.0, samples=24,
                                 q_guess=fourbar.q0, gravity=G_PLANE)


def _same_instants(part, full):
    """The partial analysis is the full one's first instants, array by array."""
    n = len(part.t)
    for name in ("t", "q", "v", "a", "tau", "bearing", "cut"):
        np.testing.assert_allclose(getattr(part, name), getattr(full, name)[:n], rtol=0,
                                   atol=1e-9, err_msg=name)
    np.testing.assert_allclose(part.shaking.force, full.shaking.force[:n], rtol=0, atol=1e-9)
    np.testing.assert_allclose(part.shaking.moment, full.shaking.moment[:n], rtol=0, atol=1e-9)


def _stopped_after_some_states(name, call):
    """The partial result of ``call`` stopped by Ctrl-C after some states. The press is
    heard by the call's own polls of the signal handlers, at most one per state, and raises
    at the n-th; the up-front check of the states polls too (and has nothing to keep), so n
    doubles until the press lands in the computation after a state done (no delays: a
    loaded machine changes n, not the outcome)."""
    part = None
    for polls in (1, 2, 4, 8, 16, 32):
        error = CtrlC(inside=name, polls=polls).attempt(call)
        if error is None:
            pytest.fail(f"{name} ended before its poll {polls} heard Ctrl-C (last: {part})")
        part = getattr(error, "result", None)
        if part is not None and part["states"] > 0:
            return part
    pytest.fail(f"{name}: no Ctrl-C kept a state done (last: {part})")


def _contact_ball():
    m = pmd.Model()
    m.add_body(pmd.RigidBody(2.0, [0, 0, 0], np.eye(3) * 0.002), pmd.Prismatic([0, 0, 1]),
               name="ball")
    contact = pmd.GroundContact([("ball", [0, 0, 0], 0.05)], stiffness=2e5, damping=5e5,
                                friction=0.0)
    return pmd.Scene(m, q0=[0.1], v0=[0.0], effects=[contact, pmd.Gravity([0, 0, -9.81])])


def test_torque_function_exception_carries_the_partial_result():
    def torque(t, q, v):
        if t > 0.4:
            raise _Boom(f"at t = {t}")
        return np.zeros(3)

    scene = chain_scene(3, [pmd.TorqueFunction(torque)])
    with pytest.raises(_Boom) as info:
        pmd.simulate(scene, (0.0, 2.0))
    r = info.value.result
    assert isinstance(r, pmd.SimulationResult) and not r.success
    assert 0.0 < r.t_reached <= 0.4 and r.t[-1] == r.t_reached
    assert r.q.shape == (len(r.t), 3) and np.all(np.isfinite(r.q))
    # The partial trajectory is the run's own: it equals a run stopped there by t_span.
    ref = pmd.simulate(chain_scene(3), (0.0, 2.0))
    k = len(r.t)
    np.testing.assert_array_equal(r.t, ref.t[:k])
    np.testing.assert_array_equal(r.q, ref.q[:k])


def test_event_exception_carries_the_partial_result():
    def event(t, q, v):
        if t > 0.3:
            raise _Boom("event")
        return 1.0

    with pytest.raises(_Boom) as info:
        pmd.simulate(chain_scene(2), (0.0, 1.0), events=[event])
    r = info.value.result
    assert not r.success and 0.0 < r.t_reached <= 0.3 + 1e-12 and len(r.t) > 1


def test_ctrl_c_during_simulate_raises_keyboard_interrupt_with_the_partial_result():
    # Pressed once progress has seen the run under way, heard by the run's own poll.
    scene = chain_scene(30)
    ctrl_c = CtrlC(inside="simulate_scene", armed=False)

    def progress(t):
        if t > 0:
            ctrl_c.arm()

    r = ctrl_c.run(lambda: pmd.simulate(scene, (0.0, 1e4), rtol=1e-12, atol=1e-12,
                                        progress=progress)).result
    assert not r.success and 0.0 < r.t_reached < 1e4 and r.t[-1] == r.t_reached
    assert np.all(np.isfinite(r.q)) and "interrupt" in r.message


def test_rk45_exception_from_fun_carries_the_partial_result():
    def fun(t, y):
        if t > 0.5:
            raise _Boom("fun")
        return -y

    with pytest.raises(_Boom) as info:
        pmd.rk45(fun, (0.0, 2.0), [1.0, 2.0])
    r = info.value.result
    assert r.status == -1 and 0.0 < r.t_reached <= 0.5
    np.testing.assert_allclose(r.y[:, -1], np.array([1.0, 2.0]) * np.exp(-r.t_reached), rtol=1e-3)


def test_dense_output_of_a_run_that_failed_at_once():
    r = pmd.rk45(lambda t, y: y * np.nan, (0, 1), [1.0], dense_output=True)
    assert r.status == -1 and r.t_reached == 0.0
    with pytest.raises(pmd.SimulationError, match="before its first step"):
        r.sol(0.0)


def test_simulate_batch_stopped_by_progress_keeps_every_run():
    scene, q0, kw = _stoppable_batch_args()
    seen = []

    def progress(done, total):
        seen.append(done)
        if done >= 3:
            raise RuntimeError("cancelled by the caller")

    with pytest.raises(RuntimeError, match="cancelled by the caller") as info:
        pmd.simulate_batch(scene, q0=q0, progress=progress, **kw)
    batch = info.value.result
    assert batch.success.sum() >= seen[-1]  # nothing finished is lost
    assert "in this exception's .result" in info.value.__notes__[-1]
    _check_partial_batch(scene, q0, kw, batch)


def test_simulate_batch_stopped_by_ctrl_c_keeps_every_run():
    # Pressed once a run is done, heard by the batch's own poll (tests/ctrl_c.py).
    from ctrl_c import CtrlC

    scene, q0, kw = _stoppable_batch_args()
    ctrl_c = CtrlC(inside="simulate_batch", armed=False)

    def progress(done, total):
        if done >= 1:
            ctrl_c.arm()

    error = ctrl_c.run(lambda: pmd.simulate_batch(scene, q0=q0, progress=progress, **kw))
    _check_partial_batch(scene, q0, kw, error.result)


def test_prescribed_motion_reports_progress_to_the_end(fourbar_motion):
    scene, mo = fourbar_motion
    seen = []
    again = pmd.prescribed_motion(scene.model, "crank", speed=2 * np.pi, samples=200,
                                  q_guess=scene.q0, gravity=G,
                                  progress=lambda d, n: seen.append((d, n)))
    assert seen[-1] == (400, 400) and all(n == 400 for _, n in seen)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen) and len(seen) >= 4
    assert again.q.shape == (200, 3)


def test_prescribed_motion_stopped_by_progress_keeps_the_instants_done(fourbar):
    kw = dict(speed=30.0, samples=300, q_guess=fourbar.q0, gravity=G_PLANE)
    full = pmd.prescribed_motion(fourbar.model, "crank", **kw)
    calls = []

    def progress(done, total):
        calls.append(done)
        if len(calls) == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as info:
        pmd.prescribed_motion(fourbar.model, "crank", progress=progress, **kw)
    part = info.value.result
    assert isinstance(part, pmd.MotionAnalysis) and not part.success
    assert 0 < len(part.t) < 300 and 2 * len(part.t) == calls[-1]
    assert part.t_reached == part.t[-1]
    assert f"stopped after {len(part.t)} of 300 instants" in part.message
    assert "interrupted" in part.message and "in this exception's .result" in info.value.__notes__[-1]
    _same_instants(part, full)
    np.testing.assert_array_equal(part.input, full.input[: len(part.t)])
    assert full.success and full.message == "complete" and full.t_reached == full.t[-1]


def test_prescribed_motion_stopped_by_ctrl_c_keeps_the_instants_done(fourbar):
    ctrl_c = CtrlC(armed=False)

    def progress(done, total):
        if done >= 2 * 64:  # the second report (every 64th instant): 64 instants done
            ctrl_c.arm()

    part = ctrl_c.run(lambda: pmd.prescribed_motion(
        fourbar.model, "crank", speed=30.0, samples=10**6, q_guess=fourbar.q0, gravity=G_PLANE,
        progress=progress)).result
    assert not part.success and 64 <= len(part.t) < 10**6
    # An independent check of the instants kept: every one is closed, and the driving torque
    # reproduces its accelerations through forward dynamics.
    m = fourbar.model
    for k in range(0, len(part.t), max(1, len(part.t) // 5)):
        assert np.max(np.abs(m.constraint_residual(part.q[k]))) < 1e-9
        a = m.forward_dynamics(part.q[k], part.v[k], part.tau[k], gravity=G_PLANE)
        np.testing.assert_allclose(a, part.a[k], rtol=1e-8, atol=1e-8 * np.abs(part.a[k]).max())
    assert part.message.startswith(f"stopped after {len(part.t)} of 1000000 instants")


def test_analyze_motion_stopped_by_progress_keeps_the_states_done(fourbar, motion):
    seen = []

    def progress(done, total):
        seen.append(done)
        raise RuntimeError("cancelled by the caller")

    many = [np.tile(x, (10, 1)) for x in (motion.q, motion.v, motion.a)]
    t = np.arange(len(many[0])) * 0.01
    with pytest.raises(RuntimeError, match="cancelled by the caller") as info:
        pmd.analyze_motion(fourbar.model, t, *many, actuated=["crank"], gravity=G_PLANE,
                           progress=progress)
    part = info.value.result
    assert not part.success and len(part.t) == 0 and part.t_reached is None
    assert "RuntimeError: cancelled by the caller" in part.message


def test_point_regressor_and_shaking_stopped_by_ctrl_c_keep_the_states_done():
    # A model without loops: a loop model's check of the states closes each one's loops, as
    # long as the computation itself. Enough states for any CPU to poll (every 50 ms).
    m = pmd.load_scene("chain7").model
    rng = np.random.default_rng(7)
    q, v, a = (np.tile(rng.uniform(-1, 1, (100, n)), (4000, 1)) for n in (m.nq, m.nv, m.nv))
    points = [(m.body_names[-1], [0.01, 0.0, 0.0])]
    for name, call in (
        ("point_regressor", lambda: m.point_regressor(q, v, a, points=points, gravity=G_PLANE)),
        ("shaking", lambda: m.shaking(q, v, a)),
    ):
        part = _stopped_after_some_states(name, call)
        k = part["states"]
        assert 0 < k < len(q) and f"{name} stopped after {k} of {len(q)} states" in part["message"]
        if name == "point_regressor":
            assert part["generalized"].shape == (k, 1, m.nv)
            # The rows kept are what the same states give alone.
            ref = m.point_regressor(q[:k], v[:k], a[:k], points=points, gravity=G_PLANE)
            np.testing.assert_allclose(part["generalized"], ref["generalized"], rtol=0, atol=0)
        else:
            assert part["force"].shape == (k, 3)
            # −Σ m a of the point masses, as the one-state call gives it.
            f, _ = m.shaking(q[k - 1], v[k - 1], a[k - 1])
            np.testing.assert_allclose(part["force"][-1], f, rtol=0, atol=0)


def test_work_precision_stopped_by_progress_keeps_the_rows_measured():
    calls = []

    def progress(msg):
        calls.append(msg)
        if "at 1e-05" in msg:
            raise KeyboardInterrupt

    kw = dict(t_end=0.5, repeats=1, scipy=False, rk4=False, n_dense=11)
    with pytest.raises(KeyboardInterrupt) as info:
        pmd.work_precision("pendulum_planar", [1e-3, 1e-4, 1e-5, 1e-6], progress=progress, **kw)
    part = info.value.result
    assert not part.success and [r["tol"] for r in part.rows] == [1e-3, 1e-4]
    assert "simulate at 1e-05" in part.message and "after 2 rows" in part.message
    # The rows kept are the ones a run of those tolerances alone measures (errors against the
    # DOP853 reference do not depend on the timing).
    alone = pmd.work_precision("pendulum_planar", [1e-3, 1e-4], **kw)
    for r, s in zip(part.rows, alone.rows):
        assert r["nfev"] == s["nfev"] and r["err_final"] == pytest.approx(s["err_final"], rel=1e-9)


def test_work_precision_stopped_by_ctrl_c_keeps_the_reference_check():
    # Ctrl-C pressed once the second tolerance's measurement has begun: the reference, its
    # check and the first row are done, and are what an uninterrupted run measures.
    ctrl_c = CtrlC(armed=False)

    def progress(msg):
        if "simulate at 0.0001" in msg:
            ctrl_c.arm()

    kw = dict(t_end=0.5, repeats=1, scipy=False, rk4=False, n_dense=11)
    part = ctrl_c.run(lambda: pmd.work_precision(
        "pendulum_planar", [1e-3, 1e-4, 1e-5], progress=progress, **kw)).result
    assert not part.success and "interrupted" in part.message
    assert part.scene == "pendulum_planar" and "simulate at 0.0001" in part.message
    full = pmd.work_precision("pendulum_planar", [1e-3, 1e-4, 1e-5], **kw)
    assert set(part.reference_check) == set(full.reference_check) and "err_final" in full.reference_check
    for key, value in full.reference_check.items():
        if key.startswith("err") or key == "energy_scale":
            assert part.reference_check[key] == pytest.approx(value, rel=1e-9), key
        else:
            assert part.reference_check[key] == value, key
    assert [r["tol"] for r in part.rows] == [1e-3]
    first, again = part.rows[0], full.rows[0]
    assert first["nfev"] == again["nfev"] and first["steps"] == again["steps"]
    for key in ("err_final", "err_dense", "err_energy"):
        assert first[key] == pytest.approx(again[key], rel=1e-9), key


@pytest.mark.parametrize("method", ["RK45", "Radau"])
def test_a_contact_run_stopped_by_progress_says_interrupted_not_failed(method):
    # Was "the right-hand side failed at t = …: interrupted".
    calls = []

    def progress(t):
        calls.append(t)
        if len(calls) > 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as info:
        pmd.simulate(_contact_ball(), (0, 30), method=method, rtol=1e-10, atol=1e-12,
                     progress=progress, progress_interval=0.0)
    r = info.value.result
    assert r.message.startswith("interrupted at t = ") and "failed" not in r.message
    assert "Ctrl-C (or a KeyboardInterrupt raised by progress)" in r.message
    assert 0 < r.t_reached < 30
    # Typed end to end: the variant, the time reached (the trajectory's last), the place the
    # progress hook stopped the run (at or after it) and the reason, no message to parse.
    status = r.outcome
    assert isinstance(status, pmd.RunStatus.Interrupted) and r.status == -1
    assert status.t == r.t_reached == r.t[-1] and status.at >= status.t
    assert status.reason == "Ctrl-C (or a KeyboardInterrupt raised by progress)"
    assert f"{status.at:.6g}" in r.message or str(status.at) in r.message
    # It travels with the result (pickle, copies): the same variant and fields.
    back = pickle.loads(pickle.dumps(r))
    assert type(back.outcome) is type(status) and repr(back.outcome) == repr(status)
    assert (back.outcome.t, back.outcome.at, back.outcome.reason) == (
        status.t, status.at, status.reason)
    assert repr(status).startswith("RunStatus.Interrupted(t=")


def test_a_nan_torque_is_a_typed_failure_at_its_time():
    # Finite up to t = 0.2, NaN past it: the run fails at the first evaluation past 0.2,
    # reaching at most that time.
    scene = chain_scene(3, [pmd.TorqueFunction(
        lambda t, q, v: np.full(3, np.nan) if t > 0.2 else np.zeros(3))])
    r = pmd.simulate(scene, (0.0, 1.0))
    assert not r.success and r.status == -1
    status = r.outcome
    assert isinstance(status, (pmd.RunStatus.NonFinite, pmd.RunStatus.RhsError)), status
    assert status.at > 0.2 and status.t == r.t_reached == r.t[-1] <= status.at
    assert not isinstance(pmd.simulate(chain_scene(3), (0.0, 1.0)).outcome,
                          (pmd.RunStatus.NonFinite, pmd.RunStatus.RhsError))
    assert isinstance(pmd.simulate(chain_scene(3), (0.0, 1.0)).outcome, pmd.RunStatus.Success)


def test_a_batch_stopped_by_progress_names_the_real_reason():
    # The runs said "KeyboardInterrupt: the batch was stopped …" for a RuntimeError.
    scene = pmd.load_scene("chain7")

    def progress(done, total):
        if done >= 1:
            raise RuntimeError("cancelled")

    with pytest.raises(RuntimeError, match="cancelled") as info:
        pmd.simulate_batch(scene, (0, 30), q0=np.tile(scene.q0, (6, 1)), rtol=1e-11,
                           atol=1e-11, progress=progress, threads=2)
    messages = info.value.result.message
    cut = [m for m in messages if not m.startswith("reached the end")]
    assert cut and all("RuntimeError: cancelled, raised by progress" in m for m in cut)
    assert not any("KeyboardInterrupt" in m for m in messages)


@pytest.mark.parametrize("method", ["weighted", "epsilon"])
def test_an_interrupted_pareto_front_keeps_the_points_solved(motion, method):
    # Ctrl-C (or a failing point) at the third point lost the two already solved.
    ring = [pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 8, max_mass=0.05)]

    def stop_at_third(text):
        if text.startswith("Pareto point 3/"):
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as info:
        pmd.pareto_front(motion, ("force", "moment"), count=4, counterweights=ring,
                         progress=stop_at_third, method=method)
    done = info.value.result
    assert len(done) == 2  # epsilon: the first end and the first level (the far end is dropped)
    assert all(isinstance(b, pmd.design.Balance) for b in done)
    # The first point is the force optimum: the same as solving it alone.
    alone = pmd.balance(motion, counterweights=ring, objective={"force": 1.0})
    assert pmd.design.objective_value(done[0], "force") == pytest.approx(
        pmd.design.objective_value(alone, "force"), rel=1e-6, abs=1e-9)
