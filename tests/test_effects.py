"""Effects a scene declares (gravity, springs, dampers, friction, joint torques, external
forces; point springs in test_point_spring.py), checked against things the engine does not compute itself: closed-form motions, the
energy balance d(T + V)/dt = Σ non-conservative power, numpy.interp, virtual work of a force
at a point; plus the disable switch, declared-only evaluation and the errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import record
from scipy.integrate import cumulative_simpson
from scipy.spatial.transform import Rotation

G = np.array([0.0, 0.0, -9.81])
TIGHT = dict(rtol=1e-12, atol=1e-12)


# --------------------------------------------------------------------------------------------
# Models
# --------------------------------------------------------------------------------------------
def box(m, com=(0.0, 0.0, 0.0), diag=(0.01, 0.02, 0.03)):
    return pmd.RigidBody(m, com, np.diag(diag))


def slider(m=2.0) -> pmd.Model:
    """One body on a prismatic joint along x."""
    model = pmd.Model()
    model.add_body(box(m), pmd.Prismatic([1, 0, 0]), name="cart")
    return model


def wheel(inertia_zz=0.05, m=1.3, com=(0.0, 0.0, 0.0)) -> pmd.Model:
    """One body on a revolute joint about z."""
    model = pmd.Model()
    model.add_body(box(m, com, (0.02, 0.03, inertia_zz)), pmd.Revolute([0, 0, 1]), name="wheel")
    return model


def tree() -> pmd.Model:
    """Revolute (y) → quaternion ball → welded plate → prismatic slider, plus a revolute
    branch: every joint kind a spring accepts, and a Fixed body."""
    model = pmd.Model()
    base = model.add_body(box(1.0, (0.15, 0, 0), (0.002, 0.008, 0.008)), pmd.Revolute([0, 1, 0]), name="base")
    ball = model.add_body(box(0.8, (0.0, 0.1, -0.1), (0.01, 0.012, 0.006)), pmd.Spherical(),
                          parent=base, translation=(0.3, 0, 0), name="ball")
    plate = model.add_body(box(0.4, (0.05, 0, 0), (0.001, 0.002, 0.002)), pmd.Fixed(), parent=ball,
                           translation=(0.0, 0.2, -0.1), rotation=Rotation.from_euler("z", 0.6).as_matrix(),
                           name="plate")
    model.add_body(box(0.3, (0.02, 0, 0.01), (0.001, 0.001, 0.001)), pmd.Prismatic([1, 0, 0.5]),
                   parent=plate, translation=(0, 0, 0.1), name="slide")
    model.add_body(box(0.6, (0.1, 0, 0), (0.001, 0.004, 0.004)), pmd.Revolute([0, 0, 1]),
                   parent=base, translation=(0.3, 0, 0.1), name="arm")
    return model


def tree_state(model):
    q = model.neutral()
    q[0] = 0.4
    q[1:5] = Rotation.from_rotvec([0.3, -0.5, 0.2]).as_quat()
    q[5] = 0.05
    q[6] = -0.7
    v = np.array([0.5, 1.0, -0.8, 0.6, 0.3, 1.2])
    return q, v


def spring_damper_scene(disable=None) -> pmd.Scene:
    model = tree()
    q0, v0 = tree_state(model)
    rest = [0.1, *Rotation.from_rotvec([0.1, 0.0, -0.2]).as_quat(), 0.02, 0.0]
    effects = [
        pmd.Gravity(G),
        pmd.Spring(None, [3.0, 2.0, 40.0, 1.5], rest=rest),
        pmd.Damper(None, [0.05, 0.02, 0.5, 0.03]),
    ]
    return pmd.Scene(model, q0, v0, effects=effects, name="springs+dampers", disable=disable)


# --------------------------------------------------------------------------------------------
# Energy balance
# --------------------------------------------------------------------------------------------
def test_energy_balance_along_a_trajectory():
    """E(t) − E(0) (E = T + V_gravity + V_springs, as recorded) equals the integral of the
    dampers' recorded power, on a dense output grid at tight tolerance."""
    scene = spring_damper_scene()
    t = np.linspace(0.0, 2.0, 4001)
    r = pmd.simulate(scene, (0.0, 2.0), t_eval=t, energy=True, power=True, **TIGHT)
    assert r.success, r.message
    assert set(r.power) == {"gravity", "springs", "dampers"}
    e = r.energy
    work = cumulative_simpson(r.power["dampers"], x=r.t, initial=0.0)
    err = np.max(np.abs((e - e[0]) - work))
    record("energy balance: |E(t) - E(0) - ∫ P_dampers dt| (J)", err)
    assert err <= 1e-8, err
    assert e[-1] < e[0] - 0.1  # the dampers really take energy out
    # Springs and gravity are conservative: their power is −dV/dt, and the total power is dT/dt.
    kinetic = np.array([scene.model.kinetic_energy(q, v) for q, v in zip(r.q, r.v)])
    total_work = cumulative_simpson(sum(r.power.values()), x=r.t, initial=0.0)
    assert np.max(np.abs((kinetic - kinetic[0]) - total_work)) <= 1e-8
    # The recorded energy is the sum of the parts pmd.energies reports.
    parts = pmd.energies(scene, r.q[-1], r.v[-1])
    assert set(parts) == {"kinetic", "gravity", "springs", "total"}
    assert parts["total"] == pytest.approx(e[-1], rel=1e-13, abs=1e-15)
    assert parts["total"] == pytest.approx(parts["kinetic"] + parts["gravity"] + parts["springs"])


def test_energy_derivative_equals_damper_power_at_sample_points():
    """dE/dt by central differences of the exact state functions along ẋ = f(x) equals the
    dampers' power, at states along a trajectory."""
    scene = spring_damper_scene()
    model = scene.model
    r = pmd.simulate(scene, (0.0, 1.0), t_eval=np.linspace(0, 1, 7), **TIGHT)
    h = 1e-6
    worst = 0.0
    for t, q, v in zip(r.t, r.q, r.v):
        forces = pmd.effect_forces(scene, t, q, v)
        tau = sum(forces.values())  # gravity's included, so no gravity argument below
        a = model.forward_dynamics(q, v, tau)
        qd = model.velocity_to_qdot(q, v)

        def energy(s):
            return pmd.energies(scene, q + s * qd, v + s * a)["total"]

        dedt = (energy(h) - energy(-h)) / (2 * h)
        p = pmd.effect_power(scene, t, q, v)
        assert p["dampers"] < 0
        worst = max(worst, abs(dedt - p["dampers"]))
    record("energy balance: |dE/dt - P_dampers| at sample points (W)", worst)
    assert worst <= 1e-8, worst


def test_recorded_energy_includes_spring_potential():
    model = slider()
    scene = pmd.Scene(model, [0.3], [0.0], effects=[pmd.Spring("cart", 20.0, rest=0.1)])
    r = pmd.simulate(scene, (0.0, 1.0), energy=True, **TIGHT)
    assert r.energy[0] == pytest.approx(0.5 * 20.0 * 0.2**2, rel=1e-14)
    assert np.max(np.abs(r.energy - r.energy[0])) <= 1e-9
    # Disabling the springs removes their potential too.
    r = pmd.simulate(scene, (0.0, 1.0), energy=True, disable="springs")
    assert np.all(r.energy == 0.0) and np.all(r.q == 0.3)


# --------------------------------------------------------------------------------------------
# Closed-form motions
# --------------------------------------------------------------------------------------------
def test_mass_spring_damper_matches_the_damped_oscillator():
    m, k, c, rest, x0, v0 = 2.0, 50.0, 1.5, 0.02, 0.1, -0.3
    scene = pmd.Scene(slider(m), [x0], [v0], effects=[
        pmd.Spring("cart", k, rest=rest), pmd.Damper(0, c)])
    t = np.linspace(0.0, 4.0, 201)
    r = pmd.simulate(scene, (0.0, 4.0), t_eval=t, **TIGHT)
    zeta_w = c / (2 * m)
    wd = np.sqrt(k / m - zeta_w**2)
    a, b = x0 - rest, (v0 + zeta_w * (x0 - rest)) / wd
    x = rest + np.exp(-zeta_w * t) * (a * np.cos(wd * t) + b * np.sin(wd * t))
    xd = np.exp(-zeta_w * t) * ((b * wd - zeta_w * a) * np.cos(wd * t) - (a * wd + zeta_w * b) * np.sin(wd * t))
    err = max(np.max(np.abs(r.q[:, 0] - x)), np.max(np.abs(r.v[:, 0] - xd)) / 10)
    record("mass-spring-damper vs closed form (m)", err)
    assert err <= 1e-9, err


def test_constant_torque_on_a_free_revolute_body():
    inertia, m, d = 0.05, 1.3, 0.2
    model = wheel(inertia, m, com=(d, 0.0, 0.0))  # COM off the axis: I about the joint = I_c + m d²
    i_joint = inertia + m * d * d
    tau = 0.7
    scene = pmd.Scene(model, effects=[pmd.JointTorque("wheel", tau)])  # no gravity
    t = np.linspace(0.0, 3.0, 31)
    r = pmd.simulate(scene, (0.0, 3.0), t_eval=t, **TIGHT)
    np.testing.assert_allclose(r.q[:, 0], tau * t**2 / (2 * i_joint), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(r.v[:, 0], tau * t / i_joint, rtol=1e-10, atol=1e-12)


def test_body_frame_force_at_a_point_is_a_constant_torque():
    """A force fixed in the body, perpendicular to its arm, acts like a constant torque."""
    inertia, m = 0.05, 1.3
    model = wheel(inertia, m)
    f, arm = 2.0, 0.4  # force along body y at body point (arm, 0, 0): τ = arm·f about z
    scene = pmd.Scene(model, effects=[pmd.ExternalForce("wheel", [0.0, f, 0.0], [arm, 0, 0], frame="body")])
    t = np.linspace(0.0, 3.0, 31)
    r = pmd.simulate(scene, (0.0, 3.0), t_eval=t, **TIGHT)
    np.testing.assert_allclose(r.q[:, 0], arm * f * t**2 / (2 * inertia), rtol=1e-10, atol=1e-12)


def test_world_force_at_a_point_is_the_equivalent_torque():
    inertia = 0.05
    model = wheel(inertia)
    force, point = np.array([0.3, 2.0, -1.0]), np.array([0.4, 0.1, 0.2])
    scene = pmd.Scene(model, effects=[pmd.ExternalForce("wheel", force, point)])
    for q in np.linspace(-3, 3, 13):
        rot = Rotation.from_euler("z", q).as_matrix()
        expect = np.cross(rot @ point, force)[2]
        got = pmd.effect_forces(scene, 0.0, [q], [0.0])["external"]
        assert got == pytest.approx([expect], abs=1e-14)

    # Same motion as a Python torque function computing that torque.
    def torque(t, q, v):
        rot = Rotation.from_euler("z", q[0]).as_matrix()
        return [np.cross(rot @ point, force)[2]]

    twin = pmd.Scene(model, effects=[pmd.TorqueFunction(torque)])
    a = pmd.simulate(scene, (0.0, 2.0), t_eval=np.linspace(0, 2, 21), **TIGHT)
    b = pmd.simulate(twin, (0.0, 2.0), t_eval=np.linspace(0, 2, 21), **TIGHT)
    np.testing.assert_allclose(a.q, b.q, rtol=1e-9, atol=1e-12)


def test_force_on_a_welded_body_acts_on_its_link():
    """A force on a Fixed child equals the same force on its parent at the carried point."""
    model = tree()
    q, v = tree_state(model)
    p_plate = np.array([0.05, -0.02, 0.03])
    rot = Rotation.from_euler("z", 0.6).as_matrix()
    p_ball = np.array([0.0, 0.2, -0.1]) + rot @ p_plate
    f = np.array([1.0, -2.0, 0.5])
    on_plate = pmd.Scene(model, q, v, effects=[pmd.ExternalForce("plate", f, p_plate)])
    on_ball = pmd.Scene(model, q, v, effects=[pmd.ExternalForce("ball", f, p_ball)])
    a = pmd.effect_forces(on_plate, 0.0, q, v)["external"]
    b = pmd.effect_forces(on_ball, 0.0, q, v)["external"]
    np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-15)
    # ... and it is the virtual work on the point's world path (finite differences).
    body = model.body_names.index("plate")

    def world_point(qq):
        rots, origins = model.placements(qq)
        return rots[body] @ p_plate + origins[body]

    h = 1e-6
    for k in range(model.nv):
        dv = np.zeros(model.nv)
        dv[k] = 1.0
        qd = model.velocity_to_qdot(q, dv)
        dx = (world_point(q + h * qd) - world_point(q - h * qd)) / (2 * h)
        assert a[k] == pytest.approx(f @ dx, abs=1e-8)


def test_quaternion_spring_oscillates_about_a_fixed_axis():
    """An isotropic body on a ball joint with a rotational spring, released at rest rotated by
    angle a about an axis, turns about that axis with angle a cos(√(k/I) t)."""
    inertia, k, a = 0.02, 0.5, 1.2
    model = pmd.Model()
    model.add_body(box(1.0, diag=(inertia,) * 3), pmd.Spherical(), name="ball")
    axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    q0 = Rotation.from_rotvec(a * axis).as_quat()
    scene = pmd.Scene(model, q0, effects=[pmd.Spring("ball", k)])
    t = np.linspace(0.0, 3.0, 61)
    r = pmd.simulate(scene, (0.0, 3.0), t_eval=t, energy=True, **TIGHT)
    rotvec = Rotation.from_quat(r.q).as_rotvec()
    expect = a * np.cos(np.sqrt(k / inertia) * t)[:, None] * axis
    err = np.max(np.abs(rotvec - expect))
    record("quaternion spring vs a cos(wt) (rad)", err)
    assert err <= 1e-9
    assert r.energy[0] == pytest.approx(0.5 * k * a * a, rel=1e-14)


def test_pd_tracking_converges():
    model = wheel(0.05, 1.3, com=(0.2, 0, 0))
    time = [0.0, 1.0, 2.0]
    ref = [0.0, 0.5, 0.5]  # ramp, then hold
    scene = pmd.Scene(model, effects=[pmd.PDTorque("wheel", 40.0, 6.0, time, ref)])
    t = np.linspace(0.0, 8.0, 81)
    r = pmd.simulate(scene, (0.0, 8.0), t_eval=t, **TIGHT)
    assert np.max(np.abs(r.q[t >= 7.0, 0] - 0.5)) <= 1e-6
    assert np.max(np.abs(r.v[t >= 7.0, 0])) <= 1e-5
    # On the ramp the reference velocity is the table's slope: τ at q = q_ref, v = 0.5 is 0.
    f = pmd.effect_forces(scene, 0.5, [0.25], [0.5])["torques"]
    assert f == pytest.approx([0.0], abs=1e-14)
    f = pmd.effect_forces(scene, 0.5, [0.2], [0.0])["torques"]
    assert f == pytest.approx([40.0 * 0.05 + 6.0 * 0.5], rel=1e-14)
    # Past the table: the last row held, zero slope.
    assert pmd.effect_forces(scene, 9.0, [0.4], [0.1])["torques"] == pytest.approx([40 * 0.1 - 6 * 0.1])


def test_tabulated_torque_is_numpy_interp():
    model = tree()
    q, v = tree_state(model)
    time = np.array([0.0, 0.3, 0.35, 1.0, 2.5])
    values = np.array([[0.0, 1.0, -2.0, 0.5], [1.0, -1.0, 0.0, 0.2], [3.0, 0.0, 1.0, 0.1],
                       [-2.0, 2.0, 0.5, 0.0], [0.5, 0.5, 0.5, 0.5]])
    # Columns: the speeds of base (1) and ball (3), in that order.
    scene = pmd.Scene(model, q, v, effects=[pmd.TabulatedTorque(["base", "ball"], time, values)])
    rng = np.random.default_rng(3)
    ts = np.concatenate([time, rng.uniform(-1.0, 3.5, 200), [-5.0, 10.0]])
    for t in ts:
        f = pmd.effect_forces(scene, t, q, v)["torques"]
        expect = [np.interp(t, time, values[:, c]) for c in range(4)]
        np.testing.assert_allclose(f[:4], expect, rtol=1e-15, atol=1e-15)
        assert np.all(f[4:] == 0.0)
    # A 1-D table for one joint.
    one = pmd.Scene(model, q, v, effects=[pmd.TabulatedTorque("arm", time, values[:, 0])])
    for t in ts[:30]:
        assert pmd.effect_forces(one, t, q, v)["torques"][5] == pytest.approx(np.interp(t, time, values[:, 0]), abs=1e-15)


def test_tabulated_torque_drives_a_free_body():
    """θ̈ = τ(t)/I with τ piecewise linear: θ is the exact double integral."""
    inertia = 0.05
    model = wheel(inertia)
    time, tau = [0.0, 1.0, 2.0], [0.0, 1.0, 1.0]
    scene = pmd.Scene(model, effects=[pmd.TabulatedTorque(0, time, tau)])
    t = np.array([0.5, 1.0, 1.5, 3.0])
    r = pmd.simulate(scene, (0.0, 3.0), t_eval=t, **TIGHT)
    # τ = t on [0, 1], then 1: θ = t³/6I, then 1/6I + (t−1)/2I + (t−1)²/2I.
    expect = np.where(t <= 1, t**3 / 6, 1 / 6 + (t - 1) / 2 + (t - 1) ** 2 / 2) / inertia
    np.testing.assert_allclose(r.q[:, 0], expect, rtol=1e-9)


def test_friction_law_and_power():
    model = tree()
    q, v = tree_state(model)
    scene = pmd.Scene(model, q, v, effects=[pmd.JointFriction(["base", "ball", "arm"], [0.2, 0.3, 0.1], v_eps=0.5)])
    f = pmd.effect_forces(scene, 0.0, q, v)["friction"]
    w = v[1:4]
    assert f[0] == pytest.approx(-0.2 * np.tanh(v[0] / 0.5), rel=1e-15)
    np.testing.assert_allclose(f[1:4], -0.3 * np.tanh(np.linalg.norm(w) / 0.5) * w / np.linalg.norm(w), rtol=1e-14)
    assert f[4] == 0.0 and f[5] == pytest.approx(-0.1 * np.tanh(v[5] / 0.5), rel=1e-15)
    assert pmd.effect_power(scene, 0.0, q, v)["friction"] < 0
    # Friction stops a spinning wheel: the speed decays, sign preserved, to below v_eps scale.
    spin = pmd.Scene(wheel(0.05), [0.0], [3.0], effects=[pmd.JointFriction(0, 0.5, v_eps=1e-3)])
    r = pmd.simulate(spin, (0.0, 1.0), t_eval=[0.1, 1.0], rtol=1e-9, atol=1e-12)
    assert r.v[0, 0] == pytest.approx(3.0 - 0.5 / 0.05 * 0.1, rel=1e-6)  # Coulomb: constant deceleration
    assert 0.0 <= r.v[1, 0] < 1e-3


def test_torque_function_equals_constant_torque_and_reraises():
    model = tree()
    q, v = tree_state(model)
    tau = np.array([0.1, 0.2, -0.3, 0.05, 1.0, -0.4])
    calls = []

    def f(t, qq, vv):
        calls.append(t)
        return tau

    a = pmd.Scene(model, q, v, effects=[pmd.Gravity(G), pmd.TorqueFunction(f, name="motor")])
    b = pmd.Scene(model, q, v, effects=[pmd.Gravity(G), pmd.JointTorque(None, tau)])
    ra = pmd.simulate(a, (0.0, 0.5), rtol=1e-10, atol=1e-10)
    rb = pmd.simulate(b, (0.0, 0.5), rtol=1e-10, atol=1e-10)
    np.testing.assert_array_equal(ra.q, rb.q)
    assert len(calls) == ra.nfev
    assert set(pmd.effect_forces(a, 0.0, q, v)) == {"gravity", "motor"}

    def boom(t, qq, vv):
        if t > 0.1:
            raise KeyError("boom")
        return np.zeros(6)

    with pytest.raises(KeyError, match="boom"):
        pmd.simulate(pmd.Scene(model, q, v, effects=[pmd.TorqueFunction(boom)]), (0.0, 1.0))
    bad = pmd.Scene(model, q, v, effects=[pmd.TorqueFunction(lambda t, q, v: [1.0, 2.0])])
    with pytest.raises(pmd.InvalidInputError, match=r"torque function f\(t, q, v\).*\(6,\)"):
        pmd.simulate(bad, (0.0, 1.0))
    with pytest.raises(pmd.InvalidInputError, match=r"torque function"):
        pmd.effect_forces(bad, 0.0, q, v)


# --------------------------------------------------------------------------------------------
# The disable switch, declared-only evaluation
# --------------------------------------------------------------------------------------------
def test_disable_switch_equals_a_scene_without_those_effects():
    full = spring_damper_scene()
    model = full.model
    only_dampers = pmd.Scene(model, full.q0, full.v0, effects=[full.effects[2]])
    a = pmd.simulate(full, (0.0, 1.0), disable=("gravity", "springs"), energy=True, power=True)
    b = pmd.simulate(only_dampers, (0.0, 1.0), energy=True, power=True)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.energy, b.energy)
    assert set(a.power) == set(b.power) == {"dampers"}
    assert set(pmd.effect_forces(full, 0.0, full.q0, full.v0, disable=["gravity", "spring"])) == {"dampers"}
    # The scene's own switch, and the caller's override of it.
    off = spring_damper_scene(disable=["gravity", "springs"])
    assert off.disable == ["gravity", "springs"]
    c = pmd.simulate(off, (0.0, 1.0))
    np.testing.assert_array_equal(c.q, b.q)
    d = pmd.simulate(off, (0.0, 1.0), disable=())
    np.testing.assert_array_equal(d.q, pmd.simulate(full, (0.0, 1.0)).q)
    with pytest.raises(pmd.InvalidInputError, match=r"disable\[1\].*gravity.*\"sprngs\""):
        pmd.simulate(full, (0.0, 1.0), disable=["dampers", "sprngs"])
    with pytest.raises(pmd.InvalidInputError, match="disable"):
        pmd.simulate(full, (0.0, 1.0), disable=3)


def test_only_declared_effects_are_evaluated():
    model = tree()
    q, v = tree_state(model)
    free = pmd.Scene(model, q, v)
    assert pmd.effect_forces(free, 0.0, q, v) == {}
    assert set(pmd.energies(free, q, v)) == {"kinetic", "total"}
    r = pmd.simulate(free, (0.0, 0.5), power=True, energy=True)
    assert r.power == {}
    # No spring declared: no spring output; declared ones appear under their names.
    scene = pmd.Scene(model, q, v, effects=[
        pmd.Damper("base", 0.1), pmd.Damper("arm", 0.2), pmd.Gravity(G),
        pmd.ExternalForce("slide", [0, 0, 1.0], name="push")])
    forces = pmd.effect_forces(scene, 0.0, q, v)
    assert list(forces) == ["dampers", "dampers_2", "gravity", "push"]
    assert all(f.shape == (model.nv,) for f in forces.values())
    np.testing.assert_allclose(forces["gravity"], model.gravity_forces(q, G), rtol=1e-13, atol=1e-15)
    assert pmd.simulate(scene, (0.0, 0.2), power=True).power.keys() == forces.keys()


def test_no_effects_is_free_motion():
    """With nothing declared the right-hand side is the bare forward dynamics."""
    model = tree()
    q, v = tree_state(model)
    scene = pmd.Scene(model, q, v)
    r = pmd.simulate(scene, (0.0, 1.0), energy=True, **TIGHT)
    assert np.max(np.abs(r.energy - r.energy[0])) <= 1e-9 * r.energy[0]


# --------------------------------------------------------------------------------------------
# Scene files
# --------------------------------------------------------------------------------------------
SCENE = """
name = "effects"
[[body]]
name = "base"
joint = { type = "Revolute", axis = [0, 1, 0] }
mass = 1.0
com = [0.15, 0, 0]
inertia_diag = [0.002, 0.008, 0.008]
q0 = [0.4]
[[body]]
name = "cart"
parent = "base"
joint = { type = "Prismatic", axis = [1, 0, 0] }
translation = [0.3, 0, 0]
mass = 0.5
inertia_diag = [0.001, 0.001, 0.001]
q0 = [0.05]

[[effect]]
type = "gravity"
g = [0, 0, -9.81]

[[effect]]
type = "spring"
joints = ["base", "cart"]
stiffness = [3.0, 40]
rest = [0.1, 0.0]

[[effect]]
type = "damper"
damping = 0.05

[[effect]]
type = "friction"
joints = 1
friction = 0.01
v_eps = 0.01
name = "rail"

[[effect]]
type = "tabulated_torque"
joints = "base"
time = [0, 1, 2]
values = [0, 0.5, 0]

[[effect]]
type = "pd_torque"
joints = "cart"
kp = 10
kd = 1
time = [0, 2]
reference = [[0.0], [0.1]]

[[effect]]
type = "torque"
joints = ["base"]
tau = 0.01

[[effect]]
type = "external"
body = "cart"
point = [0, 0, 0.1]
force = [0, 0, 2.0]

[[effect]]
type = "external"
body = "cart"
frame = "body"
time = [0, 1]
force = [[0, 0, 0], [1, 0, 0]]
moment = [[0, 0, 0], [0, 0.1, 0]]

[[effect]]
type = "point_spring"
body_a = "world"
point_a = [0.5, 0, 0.2]
body_b = "cart"
point_b = [0, 0, 0.1]
stiffness = 20
rest_length = 0.1

[simulate]
t_end = 1.0
disable = ["friction"]
"""


def write(tmp_path: Path, text: str, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_scene_file_declares_every_effect(tmp_path):
    scene = pmd.load_scene(write(tmp_path, SCENE))
    assert [e.kind for e in scene.effects] == [
        "gravity", "springs", "dampers", "friction", "torques", "torques", "torques", "external", "external",
        "springs"]
    assert scene.disable == ["friction"]
    assert scene.effects[3].name == "rail"
    forces = pmd.effect_forces(scene, 0.5, scene.q0, [0.1, -0.2])
    assert list(forces) == ["gravity", "springs", "dampers", "torques", "torques_2", "torques_3",
                            "external", "external_2", "springs_2"]  # friction switched off by the scene
    assert forces["springs"] == pytest.approx([-3.0 * 0.3, -40 * 0.05])
    assert forces["torques"] == pytest.approx([0.25, 0.0])
    assert forces["torques_2"] == pytest.approx([0.0, 10 * (0.025 - 0.05) + 1 * (0.05 + 0.2)])
    assert "rail" in pmd.effect_forces(scene, 0.5, scene.q0, [0.1, -0.2], disable=())
    # The same scene built in Python.
    py = pmd.Scene(scene.model, scene.q0, scene.v0, effects=scene.effects, disable="friction")
    r1 = pmd.simulate(scene, energy=True, power=True, rtol=1e-10, atol=1e-10)
    r2 = pmd.simulate(py, (0.0, 1.0), energy=True, power=True, rtol=1e-10, atol=1e-10)
    assert r1.success and r1.t[-1] == 1.0
    np.testing.assert_array_equal(r1.q, r2.q)
    assert set(r1.power) == set(forces)


def test_effect_takes_a_scene_file_type_and_its_keys(tmp_path):
    # Each effect the scene file declares (read by the scene-file reader), rebuilt from its
    # table by the generic constructor (the keyword reader the factories use), is equal.
    scene = pmd.load_scene(write(tmp_path, SCENE))
    contact = pmd.GroundContact([("cart", [0, 0, 0], 0.1)], friction=0.5, stiffness=1e4)
    limit = pmd.JointLimit("cart", -1.0, 2.0, stiffness=1e3, damping=[5.0])
    for e in [*scene.effects, contact, limit]:
        table = e.to_dict()
        assert pmd.Effect(table.pop("type"), **table) == e, table
    with pytest.raises(pmd.InvalidInputError,
                       match=r'^stifness: expected a key of a "spring" effect \(type, name, joints, stiffness, rest\)'):
        pmd.Effect("spring", stifness=1.0)
    with pytest.raises(pmd.InvalidInputError, match=r'^type: expected one of "gravity", .*got "sprung"'):
        pmd.Effect("sprung", stiffness=1.0)
    with pytest.raises(pmd.InvalidInputError, match=r"^stiffness: expected a value, got nothing"):
        pmd.Effect("spring", joints=0)


@pytest.mark.parametrize(
    "old, new, key, words",
    [
        ('joints = ["base", "cart"]', 'joints = ["base", "elbow"]', "effect[1].joints", ["'elbow'", "'cart'"]),
        ("stiffness = [3.0, 40]", "stiffness = [3.0, -40]", "effect[1].stiffness", [">= 0", "-40"]),
        ("stiffness = [3.0, 40]", "stiffness = [3.0, 40, 5]", "effect[1].stiffness", ["2 values", "3 values"]),
        ("stiffness = [3.0, 40]", "stifness = [3.0, 40]", "effect[1].stifness", ["unknown key", "stiffness"]),
        ('type = "damper"', 'type = "dampr"', "effect[2].type", ['"damper"']),
        ("time = [0, 1, 2]", "time = [0, 2, 1]", "effect[4].time", ["strictly increasing", "time[2] = 1"]),
        ("values = [0, 0.5, 0]", "values = [0, 0.5]", "effect[4].values", ["(3,)", "(2,)"]),
        ("values = [0, 0.5, 0]", "values = [[0, 1], [0.5, 1], [0, 1]]", "effect[4].values", ["(3, 1)", "(3, 2)"]),
        ("reference = [[0.0], [0.1]]", "reference = [[0.0], [0.1], [0.2]]", "effect[5].reference", ["(2,"]),
        ('body = "cart"\npoint', 'body = "nope"\npoint', "effect[7].body", ["'nope'"]),
        ("v_eps = 0.01", "v_eps = -1", "effect[3].v_eps", ["> 0"]),
        ('disable = ["friction"]', 'disable = ["friction", "air"]', "simulate.disable[1]", ['"air"']),
        ('name = "rail"', 'name = "total"', "effect[3].name", ["'total'"]),
        ('body_b = "cart"', 'body_b = "carts"', "effect[9].body_b", ["'carts'", "'base'"]),
        ("rest_length = 0.1", "rest_length = -0.1", "effect[9].rest_length", [">= 0", "-0.1"]),
        ("q0 = [0.4]", "q0 = [nan]", "body[0] ('base').q0", ["finite", "NaN at index 0"]),
    ],
)
def test_scene_file_effect_errors_name_file_and_key(tmp_path, old, new, key, words):
    assert old in SCENE
    path = write(tmp_path, SCENE.replace(old, new, 1), "bad.toml")
    with pytest.raises(pmd.SceneError) as info:
        pmd.load_scene(path)
    msg = str(info.value)
    assert msg.startswith(f"{path}: {key}: "), msg
    for w in words:
        assert w in msg, msg


# --------------------------------------------------------------------------------------------
# Errors from Python
# --------------------------------------------------------------------------------------------
def test_python_errors_name_the_argument():
    model = tree()
    with pytest.raises(pmd.InvalidInputError, match=r"effects\[1\]\.joints: .*'base'.*got 'elbow'"):
        pmd.Scene(model, effects=[pmd.Gravity(), pmd.Spring("elbow", 1.0)])
    with pytest.raises(pmd.InvalidInputError, match=r"effects\[0\]\.joints: .*'plate'.*Fixed"):
        pmd.Scene(model, effects=[pmd.Damper("plate", 1.0)])
    with pytest.raises(pmd.InvalidInputError, match=r"effects\[0\]\.joints: .*body index 0\.\.5.*9"):
        pmd.Scene(model, effects=[pmd.Damper(9, 1.0)])
    with pytest.raises(pmd.InvalidInputError, match=r"stiffness: expected finite numbers >= 0, got -1"):
        pmd.Spring("base", -1.0)
    with pytest.raises(pmd.InvalidInputError, match=r"stiffness: .*NaN at index 1"):
        pmd.Spring("base", [1.0, np.nan])
    with pytest.raises(pmd.InvalidInputError, match=r"damping"):
        pmd.Damper(None, -0.1)
    with pytest.raises(pmd.InvalidInputError, match=r"v_eps"):
        pmd.JointFriction(None, 1.0, v_eps=0.0)
    with pytest.raises(pmd.InvalidInputError, match=r"time: expected strictly increasing times"):
        pmd.TabulatedTorque("base", [0.0, 1.0, 1.0], [1.0, 2.0, 3.0])
    with pytest.raises(pmd.InvalidInputError, match=r"values: .*\(3,\).*shape \(2,\)"):
        pmd.TabulatedTorque("base", [0.0, 1.0, 2.0], [1.0, 2.0])
    with pytest.raises(pmd.InvalidInputError, match=r"effects\[0\]\.values: expected shape \(3, 4\).*'base', 'ball'.*\(3, 2\)"):
        pmd.Scene(model, effects=[pmd.TabulatedTorque(["base", "ball"], [0, 1, 2], np.zeros((3, 2)))])
    with pytest.raises(pmd.InvalidInputError, match=r"effects\[0\]\.joints: .*PD.*Spherical"):
        pmd.Scene(model, effects=[pmd.PDTorque("ball", 1.0, 1.0, [0.0], [[0.0]])])
    with pytest.raises(pmd.InvalidInputError, match=r"effects\[0\]\.tau: .*6 values"):
        pmd.Scene(model, effects=[pmd.JointTorque(None, [1.0, 2.0])])
    with pytest.raises(pmd.InvalidInputError, match=r"effects\[0\]\.rest"):
        pmd.Scene(model, effects=[pmd.Spring(["base", "ball"], 1.0, rest=[0.0, 1.0])])
    with pytest.raises(pmd.InvalidInputError, match=r"effects\[0\]\.joints: .*SphericalZYZ"):
        zyz = pmd.Model()
        zyz.add_body(box(1.0), pmd.SphericalZYZ())
        pmd.Scene(zyz, [0.1, 0.5, 0.2], effects=[pmd.Spring(None, 1.0)])
    with pytest.raises(pmd.InvalidInputError, match=r"force: expected shape \(2, 3\)"):
        pmd.ExternalForce("cart", [1.0, 2.0, 3.0], time=[0.0, 1.0])
    with pytest.raises(pmd.InvalidInputError, match=r"force: expected shape \(3,\)"):
        pmd.ExternalForce("cart", [1.0, 2.0])
    with pytest.raises(pmd.InvalidInputError, match=r"frame: .*\"world\" or \"body\""):
        pmd.ExternalForce("cart", [1.0, 2.0, 3.0], frame="link")
    with pytest.raises(pmd.InvalidInputError, match=r"joints\[1\]: .*name .*or body index"):
        pmd.Damper(["base", -2], 1.0)
    with pytest.raises(pmd.InvalidInputError, match=r"f: expected a callable"):
        pmd.TorqueFunction(3.0)
    with pytest.raises(pmd.InvalidInputError, match=r"effects\[1\]\.name: .*'d' again"):
        pmd.Scene(model, effects=[pmd.Damper(None, 1.0, name="d"), pmd.Damper(None, 1.0, name="d")])
    scene = pmd.Scene(model, effects=[pmd.Damper(None, 1.0)])
    with pytest.raises(pmd.InvalidInputError, match=r"v: expected shape \(6,\)"):
        pmd.effect_forces(scene, 0.0, model.neutral(), [0.0])
    with pytest.raises(pmd.InvalidInputError, match=r"t: expected a finite time"):
        pmd.effect_forces(scene, np.nan, model.neutral(), np.zeros(6))


def test_effect_objects_describe_themselves():
    s = pmd.Spring(["base", 2], 1.0, name="knee")
    assert (s.kind, s.name) == ("springs", "knee")
    assert repr(s) == "Spring(joints=['base', 2], name='knee')"
    assert pmd.Damper(None, 0.1).name == "dampers"
    assert repr(pmd.ExternalForce(1, [0, 0, 1])) == "ExternalForce(body=1, point=[0, 0, 0], frame='world')"
    assert pmd.Spring("a", 1.0) == pmd.Spring("a", 1.0) and pmd.Spring("a", 1.0) != pmd.Spring("a", 2.0)
    p = pmd.PointSpring(2, [0.5, 0, 0], -1, [0, 1, 0], 10.0, damping=0.5)
    assert (p.kind, p.name) == ("springs", "springs")
    assert repr(p) == ("PointSpring(body_a=2, point_a=[0.5, 0, 0], body_b='world', point_b=[0, 1, 0], "
                       "stiffness=10, rest_length=0, damping=0.5)")
    assert p == pmd.PointSpring(2, [0.5, 0, 0], None, [0, 1, 0], 10.0, 0.0, 0.5) and p != pmd.PointSpring(
        2, [0.5, 0, 0], -1, [0, 1, 0], 10.0)
    f = pmd.TorqueFunction(lambda t, q, v: q)
    assert f == f and f != pmd.TorqueFunction(lambda t, q, v: q) and f.kind == "torques"
