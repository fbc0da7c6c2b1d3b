"""``pmd.simulate`` on whole scenes, checked against things it does not compute itself:
the compound-pendulum period (complete elliptic integral), conservation laws (energy,
angular momentum about the pivot, the plane of a planar swing), SciPy's integrators driving
the model's own forward dynamics, and the same rod on a quaternion joint."""

from __future__ import annotations

import re

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import PAPER_A, PAPER_D, PAPER_M, record, rel_err, rod_body
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation
from scipy.special import ellipk

G = np.array([0.0, 0.0, -9.81])
# Compound pendulum about its end, released horizontal (amplitude 90°): docs/conventions.md §7.
I_O = PAPER_M * PAPER_A**2 / 3 + PAPER_M * PAPER_D**2 / 16
PERIOD = 4.0 * np.sqrt(I_O / (PAPER_M * 9.81 * PAPER_A / 2)) * ellipk(0.5)
MGA2 = PAPER_M * 9.81 * PAPER_A / 2  # energy scale of the pendulum (J)


def test_analytic_period_is_the_design_value():
    assert abs(PERIOD - 1.9334073530709592) < 1e-14


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------
def rod_directions(model: pmd.Model, qs) -> np.ndarray:
    """World direction of the rod (body x axis) at each row of qs."""
    return np.array([model.placements(q)[0][0][:, 0] for q in qs])


def rotations(model: pmd.Model, qs) -> np.ndarray:
    return np.array([model.placements(q)[0][0] for q in qs])


def euler_rate_matrix(phi: float, theta: float) -> np.ndarray:
    """L(φ, θ) (docs/method.md §2, paper eq 38b): world angular velocity = L · (φ̇, θ̇, ψ̇)."""
    s, c = np.sin, np.cos
    return np.array(
        [[0.0, -s(phi), c(phi) * s(theta)], [0.0, c(phi), s(phi) * s(theta)], [1.0, 0.0, c(theta)]]
    )


def first_order_rhs(model: pmd.Model, gravity=G):
    """[q; v]' for a model whose q̇ = v (no quaternion joints), built on forward_dynamics."""
    nq = model.nq
    tau = np.zeros(model.nv)
    g = np.asarray(gravity, dtype=float)

    def rhs(t, y):
        return np.concatenate([y[nq:], model.forward_dynamics(y[:nq], y[nq:], tau, gravity=g)])

    return rhs


@pytest.fixture(scope="module")
def planar():
    return pmd.load_scene("pendulum_planar")


@pytest.fixture(scope="module")
def spatial():
    return pmd.load_scene("pendulum_spatial")


@pytest.fixture(scope="module")
def spatial_reference(spatial):
    """SciPy DOP853 at rtol = atol = 1e-13 on the same model, 0–10 s, with dense output."""
    y0 = np.concatenate([spatial.q0, spatial.v0])
    ref = solve_ivp(
        first_order_rhs(spatial.model), (0.0, 10.0), y0, method="DOP853", rtol=1e-13, atol=1e-13,
        dense_output=True,
    )
    assert ref.success
    return ref


# --------------------------------------------------------------------------------------------
# The paper's planar pendulum
# --------------------------------------------------------------------------------------------
def test_planar_period_from_events(planar):
    psi0 = planar.q0[2]
    events = [
        pmd.StateEvent("v", 2, 0.0, direction=-1),  # ψ̇ falls through 0: back at the start
        pmd.StateEvent("v", 2, 0.0, direction=+1),  # ψ̇ rises through 0: the far turning point
        pmd.StateEvent("q", 2, psi0 - np.pi / 2, direction=-1),  # rod hanging straight down
    ]
    r = pmd.simulate(planar, (0.0, 10.0), rtol=1e-12, atol=1e-12, events=events)
    assert r.success and r.status == 0, r.message
    back, far, bottom = r.t_events
    back = back[back > PERIOD / 4]  # ψ̇ = 0 at t = 0 may count as a crossing, as in SciPy
    k = np.arange(5)
    assert back.shape == far.shape == bottom.shape == (5,), (back, far, bottom)
    err = max(
        np.max(np.abs(back - (k + 1) * PERIOD)),
        np.max(np.abs(far - (k + 0.5) * PERIOD)),
        np.max(np.abs(bottom - (k + 0.25) * PERIOD)),
    )
    record("planar pendulum: event times vs k·T/4 (s)", err)
    assert err <= 1e-8
    # The period measured between successive returns, as the brief asks.
    assert np.max(np.abs(np.diff(back) - PERIOD)) <= 1e-8
    # Turning points at ψ0 (start) and ψ0 − π (amplitude 90° on the other side), at rest.
    q_back, q_far = r.q_events[0][r.t_events[0] > PERIOD / 4], r.q_events[1]
    assert np.max(np.abs(q_back[:, 2] - psi0)) <= 1e-8
    assert np.max(np.abs(q_far[:, 2] - (psi0 - np.pi))) <= 1e-8
    assert np.max(np.abs(r.v_events[1][:, 2])) <= 1e-12
    assert np.max(np.abs(r.q_events[2][:, 2] - (psi0 - np.pi / 2))) <= 1e-12


def test_planar_swing_stays_in_its_vertical_plane(planar):
    t = np.linspace(0.0, 10.0, 801)
    r = pmd.simulate(planar, (0.0, 10.0), rtol=1e-12, atol=1e-12, t_eval=t, energy=True)
    assert r.success, r.message
    np.testing.assert_array_equal(r.t, t)
    model = planar.model
    d = rod_directions(model, r.q)
    d0 = d[0]
    assert abs(d0 @ G) <= 1e-12  # released horizontal
    # The swing plane contains the initial rod and the vertical.
    normal = np.cross(d0, [0.0, 0.0, 1.0])
    normal /= np.linalg.norm(normal)
    out_of_plane = np.max(np.abs(d @ normal))
    record("planar pendulum: rod out of its plane", out_of_plane)
    assert out_of_plane <= 1e-9
    # ... and it really swings through that plane: straight down and to the other side.
    assert np.min(d[:, 2]) < -0.999
    assert np.min(d @ d0) < -0.999
    # The pivot does not move; φ, θ stay at 90°.
    origins = np.array([model.placements(q)[1][0] for q in r.q])
    assert np.max(np.abs(origins)) == 0.0
    assert np.max(np.abs(r.q[:, :2] - planar.q0[:2])) <= 1e-9
    drift = np.max(np.abs(r.energy - r.energy[0])) / MGA2
    record("planar pendulum: energy drift / (m g a/2) at 1e-12", drift)
    assert drift <= 1e-9


# --------------------------------------------------------------------------------------------
# The paper's spatial pendulum
# --------------------------------------------------------------------------------------------
def angular_momentum_about_pivot(model_zyz: pmd.Model, q, v) -> np.ndarray:
    """World angular momentum about the fixed pivot of the ZYZ rod: R I_O Rᵀ ω."""
    i_o = rod_body().inertia_about([0.0, 0.0, 0.0])
    rot = model_zyz.placements(q)[0][0]
    omega = euler_rate_matrix(q[0], q[1]) @ v
    return rot @ i_o @ rot.T @ omega


def test_spatial_energy_and_vertical_momentum_conserved(spatial):
    r = pmd.simulate(spatial, (0.0, 10.0), rtol=1e-11, atol=1e-11, energy=True)
    assert r.success, r.message
    model = spatial.model
    # Recorded energy is kinetic + gravitational potential of the declared gravity.
    e0 = model.kinetic_energy(spatial.q0, spatial.v0) + model.potential_energy(spatial.q0, G)
    assert abs(r.energy[0] - e0) <= 1e-14 * abs(e0)
    drift = np.max(np.abs(r.energy - r.energy[0])) / np.max(np.abs(r.energy))
    record("spatial pendulum: relative energy drift at 1e-11", drift)
    assert drift <= 1e-9
    # Gravity's moment about the pivot is horizontal: L_z is conserved.
    lz = np.array([angular_momentum_about_pivot(model, q, v)[2] for q, v in zip(r.q, r.v)])
    assert abs(lz[0]) > 0.05  # the test means something
    assert np.max(np.abs(lz - lz[0])) / abs(lz[0]) <= 1e-8
    # It is genuinely spatial: θ moves far from 45°, φ is not constant.
    assert np.ptp(r.q[:, 1]) > 1.0 and np.ptp(r.q[:, 0]) > 0.5


def test_spatial_matches_scipy_dop853(spatial, spatial_reference):
    r = pmd.simulate(spatial, (0.0, 10.0), rtol=1e-12, atol=1e-12)
    assert r.success and r.t[-1] == 10.0
    ref = spatial_reference
    ours = np.concatenate([r.q[-1], r.v[-1]])
    err = rel_err(ours, ref.y[:, -1])
    record("spatial pendulum: final state vs DOP853 1e-13", err)
    assert err <= 1e-8


def test_t_eval_output_matches_reference(spatial, spatial_reference):
    t_eval = np.linspace(0.0, 10.0, 37)
    r = pmd.simulate(spatial, (0.0, 10.0), rtol=1e-12, atol=1e-12, t_eval=t_eval)
    np.testing.assert_array_equal(r.t, t_eval)
    assert r.q.shape == (37, 3) and r.v.shape == (37, 3)
    ref = spatial_reference.sol(t_eval).T
    err = rel_err(np.hstack([r.q, r.v]), ref)
    record("spatial pendulum: t_eval (dense output) vs DOP853", err)
    assert err <= 1e-8
    # t_eval only chooses the output: same steps, same end state as without it.
    full = pmd.simulate(spatial, (0.0, 10.0), rtol=1e-12, atol=1e-12)
    assert full.nfev == r.nfev
    np.testing.assert_array_equal(full.q[-1], r.q[-1])
    with pytest.raises(pmd.InvalidInputError, match="t_eval"):
        pmd.simulate(spatial, (0.0, 2.0), t_eval=[0.0, 3.0])


# --------------------------------------------------------------------------------------------
# The same rod on a quaternion joint
# --------------------------------------------------------------------------------------------
def quaternion_twin(scene_zyz):
    """The ZYZ scene's rod on pmd.Spherical(), same initial orientation and angular
    velocity (converted here, independently of the library)."""
    phi, theta, psi = scene_zyz.q0
    rot = Rotation.from_euler("ZYZ", [phi, theta, psi])  # intrinsic: Rz(φ) Ry(θ) Rz(ψ)
    omega_world = euler_rate_matrix(phi, theta) @ scene_zyz.v0
    omega_body = rot.as_matrix().T @ omega_world
    model = pmd.Model()
    model.add_body(rod_body(), pmd.Spherical(), name="rod", point_mass_center=[PAPER_A, 0.0, 0.0])
    return pmd.Scene(model, rot.as_quat(), omega_body, effects=[pmd.Gravity(G)], name="quat")


def test_quaternion_joint_agrees_with_zyz(spatial):
    quat = quaternion_twin(spatial)
    mq, mz = quat.model, spatial.model
    # The conversion itself: same orientation, same kinetic energy at t = 0.
    assert np.max(np.abs(mq.placements(quat.q0)[0] - mz.placements(spatial.q0)[0])) <= 1e-14
    ke_q, ke_z = mq.kinetic_energy(quat.q0, quat.v0), mz.kinetic_energy(spatial.q0, spatial.v0)
    assert abs(ke_q - ke_z) <= 1e-13 * ke_z
    t = np.linspace(0.0, 10.0, 201)
    rq = pmd.simulate(quat, (0.0, 10.0), rtol=1e-11, atol=1e-11, t_eval=t, energy=True)
    rz = pmd.simulate(spatial, (0.0, 10.0), rtol=1e-11, atol=1e-11, t_eval=t)
    assert rq.success and rz.success
    assert rq.q.shape == (201, 4) and rq.v.shape == (201, 3)
    unit = np.max(np.abs(np.linalg.norm(rq.q, axis=1) - 1.0))
    assert unit <= 1e-13
    drift = np.max(np.abs(rq.energy - rq.energy[0])) / np.max(np.abs(rq.energy))
    record("quaternion pendulum: relative energy drift at 1e-11", drift)
    assert drift <= 1e-8
    dir_err = np.max(np.abs(rod_directions(mq, rq.q) - rod_directions(mz, rz.q)))
    rot_err = np.max(np.abs(rotations(mq, rq.q) - rotations(mz, rz.q)))
    record("quaternion vs ZYZ pendulum: rod direction", dir_err)
    assert dir_err <= 1e-7
    assert rot_err <= 1e-7


# --------------------------------------------------------------------------------------------
# Events
# --------------------------------------------------------------------------------------------
def reference_crossing(ref, index: int, value: float, t_lo: float, t_hi: float) -> float:
    return brentq(lambda t: ref.sol(t)[index] - value, t_lo, t_hi, xtol=1e-15, rtol=1e-15)


def test_terminal_state_event_stops_the_run(spatial, spatial_reference):
    target = np.pi / 2
    ev = pmd.StateEvent("q", 1, target, direction=1, terminal=True)
    assert ev.terminal == 1 and ev.direction == 1
    r = pmd.simulate(spatial, (0.0, 10.0), rtol=1e-12, atol=1e-12, events=[ev])
    assert r.success and r.status == 1, r.message
    assert "event" in r.message
    (te,) = r.t_events
    assert te.shape == (1,)
    assert r.t[-1] == te[0] == r.t_reached
    np.testing.assert_array_equal(r.q[-1], r.q_events[0][0])
    np.testing.assert_array_equal(r.v[-1], r.v_events[0][0])
    assert abs(r.q[-1][1] - target) <= 1e-12
    assert r.v[-1][1] > 0  # a rising crossing
    t_ref = reference_crossing(spatial_reference, 1, target, 0.05, te[0] + 0.05)
    assert abs(te[0] - t_ref) <= 1e-9


def test_python_event_with_terminal_and_direction_attributes(spatial):
    seen = []

    def theta_up(t, q, v):
        seen.append((type(q), q.shape, v.shape))
        return q[1] - np.pi / 2

    theta_up.terminal = True
    theta_up.direction = 1
    r = pmd.simulate(spatial, (0.0, 10.0), rtol=1e-12, atol=1e-12, events=[theta_up])
    assert seen and all(s == (np.ndarray, (3,), (3,)) for s in seen)
    assert r.status == 1 and r.t[-1] == r.t_events[0][0]
    same = pmd.simulate(
        spatial, (0.0, 10.0), rtol=1e-12, atol=1e-12,
        events=[pmd.StateEvent("q", 1, np.pi / 2, direction=1, terminal=True)],
    )
    assert abs(r.t[-1] - same.t[-1]) <= 1e-13

    # direction = -1, not terminal: only falling crossings of θ̇, exactly those of the
    # equivalent StateEvent, and the run goes to the end.
    def theta_dot(t, q, v):
        return v[1]

    theta_dot.direction = -1
    both = pmd.simulate(
        spatial, (0.0, 10.0), rtol=1e-10, atol=1e-12,
        events=[theta_dot, pmd.StateEvent("v", 1, 0.0), pmd.StateEvent("v", 1, 0.0, direction=-1)],
    )
    assert both.status == 0 and both.t[-1] == 10.0
    falling, every, falling_state = both.t_events
    assert len(falling) >= 3 and len(every) > len(falling)
    np.testing.assert_allclose(falling, falling_state, rtol=0, atol=1e-13)
    # Every falling crossing is one of all crossings, and θ is at a maximum there.
    assert all(np.min(np.abs(every - t)) <= 1e-13 for t in falling)
    model = spatial.model
    for q, v in zip(both.q_events[0], both.v_events[0]):
        assert model.forward_dynamics(q, v, np.zeros(3), gravity=G)[1] < 0


def test_events_are_returned_in_the_callers_order(spatial):
    def theta_1(t, q, v):
        return q[1] - 1.0

    def phi_0(t, q, v):
        return q[0]

    specs = [
        theta_1,
        pmd.StateEvent("v", 1, 0.0),
        phi_0,
        pmd.StateEvent("q", 1, 2.0),
    ]
    kw = dict(rtol=1e-10, atol=1e-12)
    mixed = pmd.simulate(spatial, (0.0, 10.0), events=specs, **kw)
    assert len(mixed.t_events) == len(mixed.q_events) == len(mixed.v_events) == 4
    for k, spec in enumerate(specs):
        alone = pmd.simulate(spatial, (0.0, 10.0), events=[spec], **kw)
        assert len(alone.t_events[0]) > 0, k
        np.testing.assert_array_equal(mixed.t_events[k], alone.t_events[0], err_msg=str(k))
        np.testing.assert_array_equal(mixed.q_events[k], alone.q_events[0], err_msg=str(k))
    # The four lists differ, so a permutation could not pass unnoticed.
    sets = [tuple(np.round(t, 9)) for t in mixed.t_events]
    assert len(set(sets)) == 4
    # The recorded states satisfy their own event functions.
    assert np.max(np.abs(mixed.q_events[0][:, 1] - 1.0)) <= 1e-9
    assert np.max(np.abs(mixed.v_events[1][:, 1])) <= 1e-9
    assert np.max(np.abs(mixed.q_events[2][:, 0])) <= 1e-9
    assert np.max(np.abs(mixed.q_events[3][:, 1] - 2.0)) <= 1e-9


# --------------------------------------------------------------------------------------------
# Failures
# --------------------------------------------------------------------------------------------
def test_max_steps_failure_and_raise_for_status(spatial):
    r = pmd.simulate(spatial, (0.0, 10.0), max_steps=20)
    assert r.success is False and r.status == -1
    assert r.n_accepted == 20
    assert re.search(r"max\w*\s.*steps", r.message), r.message
    m = re.search(r"t = ([-+0-9.eE]+)", r.message)
    assert m, r.message
    assert float(m.group(1)) == pytest.approx(r.t_reached, rel=1e-12)
    assert 0.0 < r.t_reached < 10.0 and r.t[-1] == r.t_reached
    with pytest.raises(pmd.SimulationError) as info:
        r.raise_for_status()
    assert isinstance(info.value, RuntimeError)
    assert info.value.t == r.t_reached
    assert "steps" in str(info.value)
    ok = pmd.simulate(spatial, (0.0, 1.0))
    assert ok.raise_for_status() is ok


class _Stop(Exception):
    pass


def test_progress_callback_and_its_exception(spatial):
    times = []
    r = pmd.simulate(spatial, (0.0, 10.0), rtol=1e-10, progress=times.append, progress_interval=0)
    assert r.success and len(times) >= 5
    assert all(0.0 <= t <= 10.0 for t in times) and times == sorted(times)

    def stop(t):
        if t > 1.0:
            raise _Stop(f"stopped at {t}")

    with pytest.raises(_Stop, match="stopped at") as info:
        pmd.simulate(spatial, (0.0, 10.0), rtol=1e-10, progress=stop, progress_interval=0)
    # What was computed before the callback raised comes with the exception (issue 11).
    partial = info.value.result
    assert not partial.success and 1.0 < partial.t_reached < 10.0
    assert partial.t[-1] == partial.t_reached and partial.q.shape == (len(partial.t), 3)


def test_python_event_exception_propagates(spatial):
    def bad(t, q, v):
        raise _Stop("from an event")

    with pytest.raises(_Stop, match="from an event"):
        pmd.simulate(spatial, (0.0, 1.0), events=[bad])


@pytest.mark.parametrize("t_span", [(1.0, 1.0), (0.0, float("nan")), (0.0,), (0.0, float("inf"))])
def test_bad_t_span(spatial, t_span):
    with pytest.raises(pmd.InvalidInputError, match="t_span") as info:
        pmd.simulate(spatial, t_span)
    assert isinstance(info.value, ValueError)


def test_scene_without_t_span_needs_one(spatial):
    scene = pmd.Scene(spatial.model, spatial.q0, spatial.v0)
    assert scene.t_span is None
    with pytest.raises(pmd.InvalidInputError, match="t_span"):
        pmd.simulate(scene)


def test_scene_rejects_wrong_lengths_and_types(spatial):
    model = spatial.model
    with pytest.raises(pmd.InvalidInputError, match="q0") as info:
        pmd.Scene(model, [0.1, 0.2], [0.0, 0.0, 0.0])
    assert isinstance(info.value, ValueError) and "3" in str(info.value)
    with pytest.raises(pmd.InvalidInputError, match="v0"):
        pmd.Scene(model, [0.1, 0.5, 0.2], [0.0, 0.0])
    with pytest.raises(pmd.InvalidInputError, match=r"effects\[0\]"):
        pmd.Scene(model, [0.1, 0.5, 0.2], effects=["gravity"])
    with pytest.raises(pmd.InvalidInputError, match=r"events\[0\]"):
        pmd.simulate(spatial, (0.0, 1.0), events=[3])
    with pytest.raises(pmd.InvalidInputError, match=r"events\[0\]\.index"):
        pmd.simulate(spatial, (0.0, 1.0), events=[pmd.StateEvent("q", 3)])


@pytest.mark.parametrize("not_a_scene", [None, "pendulum_planar", "model"])
def test_simulate_needs_a_scene(spatial, not_a_scene):
    arg = spatial.model if not_a_scene == "model" else not_a_scene
    with pytest.raises(TypeError, match="Scene"):
        pmd.simulate(arg, (0.0, 1.0))


# --------------------------------------------------------------------------------------------
# Scenes built in Python: only the declared effects act
# --------------------------------------------------------------------------------------------
def test_python_scene_with_gravity_equals_the_bundled_scene(spatial):
    model = pmd.Model()
    model.add_body(rod_body(), pmd.SphericalZYZ(), name="rod", point_mass_center=[1.0, 0.0, 0.0])
    scene = pmd.Scene(model, spatial.q0, spatial.v0, effects=[pmd.Gravity((0, 0, -9.81))])
    assert scene.effects == [pmd.Gravity()]
    a = pmd.simulate(scene, (0.0, 3.0), rtol=1e-10, atol=1e-12)
    b = pmd.simulate(spatial, (0.0, 3.0), rtol=1e-10, atol=1e-12)
    assert rel_err(a.q[-1], b.q[-1]) <= 1e-9
    assert rel_err(a.v[-1], b.v[-1]) <= 1e-9


def test_no_effects_means_no_gravity(planar):
    still = pmd.Scene(planar.model, planar.q0, planar.v0)
    assert still.effects == []
    r = pmd.simulate(still, (0.0, 5.0), energy=True)
    assert r.success
    assert np.all(r.q == planar.q0) and np.all(r.v == 0.0) and np.all(r.energy == 0.0)
    # The same state with gravity declared does fall.
    falls = pmd.Scene(planar.model, planar.q0, planar.v0, effects=[pmd.Gravity()])
    r = pmd.simulate(falls, (0.0, 0.5))
    assert np.max(np.abs(r.v[-1])) > 1.0


def test_torque_free_tumbling_body_conserves_energy_and_momentum():
    # An asymmetric body about a fixed point, nothing acting on it: it tumbles (Euler's
    # equations), its kinetic energy and world angular momentum about the point are constant.
    body = pmd.RigidBody(1.3, [0.12, -0.05, 0.03], np.diag([0.02, 0.05, 0.065]))
    model = pmd.Model()
    model.add_body(body, pmd.Spherical(), name="top")
    q0 = Rotation.from_euler("xyz", [0.3, -0.7, 1.1]).as_quat()
    w0 = np.array([3.0, -2.0, 5.0])
    scene = pmd.Scene(model, q0, w0)  # no effects: nothing acts on it
    r = pmd.simulate(scene, (0.0, 5.0), rtol=1e-11, atol=1e-12, energy=True)
    assert r.success, r.message
    ke = np.array([model.kinetic_energy(q, v) for q, v in zip(r.q, r.v)])
    np.testing.assert_allclose(r.energy, ke, rtol=1e-14)  # no potential without gravity
    i_o = body.inertia_about([0.0, 0.0, 0.0])
    assert abs(ke[0] - 0.5 * w0 @ i_o @ w0) <= 1e-14 * ke[0]
    assert np.max(np.abs(ke - ke[0])) / ke[0] <= 1e-9
    # World angular momentum about the fixed point: R I_O ω_body.
    mom = np.array([model.placements(q)[0][0] @ i_o @ w for q, w in zip(r.q, r.v)])
    err = np.max(np.abs(mom - mom[0])) / np.linalg.norm(mom[0])
    record("torque-free body: angular momentum drift", err)
    assert err <= 1e-9
    assert np.max(np.abs(r.v - w0)) > 1.0  # ω really changes in the body frame (it tumbles)
    assert np.max(np.abs(np.linalg.norm(r.q, axis=1) - 1.0)) <= 1e-13


# --------------------------------------------------------------------------------------------
# chain7: our RK45 is SciPy's RK45 step for step
# --------------------------------------------------------------------------------------------
def test_chain7_reproduces_scipy_rk45():
    scene = pmd.load_scene("chain7")
    assert scene.rtol == 1e-6 and scene.atol == 1e-9
    y0 = np.concatenate([scene.q0, scene.v0])
    ours = pmd.simulate(scene, (0.0, 10.0), rtol=1e-6, atol=1e-9)
    ref = solve_ivp(first_order_rhs(scene.model), (0.0, 10.0), y0, method="RK45", rtol=1e-6, atol=1e-9)
    assert ours.success and ref.success
    assert ours.nfev == ref.nfev
    assert len(ours.t) == len(ref.t)
    np.testing.assert_allclose(ours.t, ref.t, rtol=1e-9, atol=1e-12)
    err = rel_err(np.concatenate([ours.q[-1], ours.v[-1]]), ref.y[:, -1])
    record("chain7: final state vs SciPy RK45 at 1e-6 (10 s)", err)
    assert err <= 1e-9
