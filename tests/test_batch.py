"""simulate_batch: each run bit for bit the simulate call it stands for, on 1, 2 and 4
threads; per-run parameters against the scenes they describe and against closed forms; a
failing run reported on its own; progress, interruption and bad input."""

from __future__ import annotations

import math

import numpy as np
import pointmass_dyn as pmd
import pytest

T_EVAL = np.linspace(0.0, 1.0, 11)


@pytest.fixture(scope="module")
def chain7():
    return pmd.load_scene("chain7")


def per_run_states(scene, count, seed=0):
    rng = np.random.default_rng(seed)
    q0 = scene.q0 + 0.2 * rng.normal(size=(count, scene.model.nq))
    v0 = scene.v0 + 0.5 * rng.normal(size=(count, scene.model.nv))
    return q0, v0


def assert_same_run(got, expect):
    assert got.success == expect.success
    np.testing.assert_array_equal(got.t, expect.t)
    np.testing.assert_array_equal(got.q, expect.q)
    np.testing.assert_array_equal(got.v, expect.v)
    assert (got.nfev, got.n_accepted, got.n_rejected) == (
        expect.nfev,
        expect.n_accepted,
        expect.n_rejected,
    )


@pytest.mark.parametrize("threads", [1, 2, 4])
def test_every_run_is_the_simulate_call_bit_for_bit(chain7, threads):
    q0, v0 = per_run_states(chain7, 12)
    kw = dict(t_eval=T_EVAL, rtol=1e-8, atol=1e-10)
    batch = pmd.simulate_batch(chain7, (0.0, 1.0), q0=q0, v0=v0, threads=threads, **kw)
    assert batch.success.all() and batch.q.shape == (12, len(T_EVAL), chain7.model.nq)
    for k in (0, 5, 11):
        one = pmd.simulate(
            pmd.Scene(chain7.model, q0[k], v0[k], effects=chain7.effects), (0.0, 1.0), **kw
        )
        assert_same_run(batch.results[k], one)
        np.testing.assert_array_equal(batch.q[k], one.q)
    assert list(batch.nfev) == [r.nfev for r in batch.results]


def test_params_are_the_scenes_they_describe(chain7):
    """gravity, an effect's parameter and a body's mass per run: each run equals simulate on
    the scene built by hand with that value."""
    base = chain7.replace(effects=[*chain7.effects, pmd.Damper(None, 0.01, name="damping")])
    g = np.array([[0.0, 0.0, -9.81], [0.0, -3.0, -1.0], [1.0, 0.0, -20.0]])
    c = np.array([0.0, 0.05, 0.2])
    mass = np.array([1.0, 2.5, 0.4])
    batch = pmd.simulate_batch(
        base,
        (0.0, 0.5),
        params={"gravity": g, "damping.damping": c, "link3.mass": mass},
        t_eval=T_EVAL / 2,
        rtol=1e-9,
        atol=1e-11,
    )
    name = base.model.body_names[3]
    assert name == "link3"
    for k in range(3):
        effects = [
            e.with_parameter("g", g[k])
            if e.g is not None
            else e.with_parameter("damping", [c[k]])
            if e.kind == "dampers"
            else e
            for e in base.effects
        ]
        body = base.model.body(name)
        model = base.model.with_body(
            name, pmd.RigidBody(mass[k], com=body.com, inertia=body.inertia)
        )
        one = pmd.simulate(
            base.replace(model=model, effects=effects),
            (0.0, 0.5),
            t_eval=T_EVAL / 2,
            rtol=1e-9,
            atol=1e-11,
        )
        assert_same_run(batch.results[k], one)
    # Different parameters, different motions.
    assert not np.array_equal(batch.q[0], batch.q[1])


def test_a_stiffness_sweep_follows_the_closed_form_oscillation():
    """A mass on a prismatic joint with a spring: x(t) = x0 cos(√(k/m) t) for each k."""
    m = 2.0
    model = pmd.Model()
    model.add_body(
        pmd.RigidBody(m, com=[0, 0, 0], inertia=np.eye(3) * 0.01),
        pmd.Prismatic([1, 0, 0]),
        name="cart",
    )
    scene = pmd.Scene(model, [0.1], [0.0], effects=[pmd.Spring(None, 1.0, name="spring")])
    k = np.array([1.0, 4.0, 9.0, 50.0])
    t = np.linspace(0, 2, 9)
    batch = pmd.simulate_batch(
        scene, (0, 2), params={"spring.stiffness": k}, t_eval=t, rtol=1e-11, atol=1e-13
    )
    assert batch.success.all()
    expect = 0.1 * np.cos(np.sqrt(k / m)[:, None] * t[None])
    np.testing.assert_allclose(batch.q[:, :, 0], expect, atol=1e-9)


def test_a_failing_run_is_reported_while_the_others_finish(chain7):
    def nan_torque(t, q, v):
        return np.full(7, math.nan) if t > 0.2 else np.zeros(7)

    bad = chain7.replace(effects=[*chain7.effects, pmd.TorqueFunction(nan_torque)])
    scenes = [chain7, bad, chain7]
    batch = pmd.simulate_batch(scenes, (0.0, 1.0), t_eval=T_EVAL, rtol=1e-7, threads=2)
    assert list(batch.success) == [True, False, True]
    assert 0.15 < batch.t_reached[1] < 0.3  # the last accepted step before the NaN
    assert "t = " in batch.message[1] or "non-finite" in batch.message[1].lower()
    assert np.isnan(batch.q[1, -1]).all() and not np.isnan(batch.q[1, 0]).any()
    one = pmd.simulate(chain7, (0.0, 1.0), t_eval=T_EVAL, rtol=1e-7)
    assert_same_run(batch.results[0], one)
    assert_same_run(batch.results[2], one)


def test_progress_is_called_and_its_exception_stops_the_batch(chain7):
    q0, v0 = per_run_states(chain7, 64, seed=3)
    seen = []
    batch = pmd.simulate_batch(
        chain7,
        (0.0, 4.0),
        q0=q0,
        v0=v0,
        rtol=1e-10,
        atol=1e-12,
        threads=2,
        progress=lambda done, total: seen.append((done, total)),
    )
    assert batch.success.all()
    assert seen and all(total == 64 and 0 <= done <= 64 for done, total in seen)
    assert seen[-1] == (64, 64)  # the last report is the end

    def stop(done, total):
        raise RuntimeError("cancelled")

    with pytest.raises(RuntimeError, match="cancelled"):
        pmd.simulate_batch(chain7, (0.0, 4.0), q0=q0, v0=v0, rtol=1e-10, atol=1e-12, progress=stop)


def test_bad_batch_input_is_a_clear_error(chain7):
    q0, v0 = per_run_states(chain7, 4)
    err = pmd.errors.InvalidInputError
    with pytest.raises(err, match="q0"):
        pmd.simulate_batch(chain7, (0, 1), q0=q0[:, :3])
    with pytest.raises(err, match="v0"):
        pmd.simulate_batch(chain7, (0, 1), q0=q0, v0=v0[:3])
    with pytest.raises(err, match="params"):
        pmd.simulate_batch(chain7, (0, 1), params={"nothing.stiffness": [1.0, 2.0]})
    with pytest.raises(err, match="params"):
        pmd.simulate_batch(
            chain7, (0, 1), params={"gravity": [[0, 0, -9.81]], "link1.mass": [1, 2]}
        )
    with pytest.raises(err, match="parameter"):
        pmd.simulate_batch(chain7, (0, 1), params={"gravity.stiffness": [1.0]})
    with pytest.raises(err, match="events"):
        pmd.simulate_batch(chain7, (0, 1), events=[lambda t, q, v: q[0]])
    with pytest.raises(err, match="scene"):
        pmd.simulate_batch([], (0, 1))
    with pytest.raises(err, match="threads"):
        pmd.simulate_batch(chain7, (0, 1), threads=-1)
    # A run whose own input is refused (an open loop) fails alone.
    fourbar = pmd.load_scene("fourbar")
    open_q0 = np.array([fourbar.q0, fourbar.q0 + [0.0, 0.3, 0.0]])
    batch = pmd.simulate_batch(fourbar, (0, 0.01), q0=open_q0, v0=np.zeros((2, 3)))
    assert list(batch.success) == [True, False]
    assert "loop" in batch.message[1]


def test_torque_parameters_per_run_are_the_scenes_they_describe():
    """A tabulated drive's values and a constant torque per run, against hand-built scenes."""
    scene = pmd.load_scene("pendulum_planar")
    nv = scene.model.nv
    times = [0.0, 0.5, 1.0]
    drive = pmd.TabulatedTorque(None, times, np.zeros((3, nv)), name="drive")
    bias = pmd.JointTorque(None, 0.0, name="bias")
    base = scene.replace(effects=[*scene.effects, drive, bias])
    values = np.array(
        [np.zeros((3, nv)), np.full((3, nv), 0.3), np.linspace(-1, 1, 3 * nv).reshape(3, nv)]
    )
    tau = np.array([0.0, -0.2, 0.5])
    batch = pmd.simulate_batch(
        base,
        (0, 1),
        params={"drive.values": values.reshape(3, -1), "bias.tau": tau},
        t_eval=T_EVAL,
        rtol=1e-9,
        atol=1e-11,
    )
    for k in range(3):
        effects = [
            *scene.effects,
            pmd.TabulatedTorque(None, times, values[k], name="drive"),
            pmd.JointTorque(None, tau[k], name="bias"),
        ]
        one = pmd.simulate(
            scene.replace(effects=effects), (0, 1), t_eval=T_EVAL, rtol=1e-9, atol=1e-11
        )
        assert_same_run(batch.results[k], one)
    assert not np.array_equal(batch.q[0], batch.q[2])
    with pytest.raises(pmd.errors.InvalidInputError, match="values"):
        pmd.simulate_batch(base, (0, 1), params={"drive.values": np.zeros((2, 5))})
