"""Closed loops: cut-joint kinematics against finite differences, the constrained dynamics
against the KKT system solved with NumPy from the model's own tree quantities (M, bias
forces, J, J̇v), invariants (energy, closure along a run), and the errors."""

from __future__ import annotations

import pickle

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn import LoopClosureError, ModelStructureError, SingularityError

Z = [0.0, 0.0, 1.0]
G = np.array([0.0, -9.81, 0.0])
# Four-bar of docs/loops.md: ground, crank, coupler, rocker (Grashof crank-rocker).
L0, L1, L2, L3 = 0.4, 0.1, 0.35, 0.3


def bar(length, mass=1.0):
    i = mass * length**2 / 12 + 1e-4
    return pmd.RigidBody(mass, [length / 2, 0, 0], np.diag([1e-4, i, i]))


def fourbar():
    m = pmd.Model()
    m.add_body(bar(L1), pmd.Revolute(Z), name="crank")
    m.add_body(bar(L2), pmd.Revolute(Z), parent=0, translation=[L1, 0, 0], name="coupler")
    m.add_body(bar(L3), pmd.Revolute(Z), translation=[L0, 0, 0], name="rocker")
    m.add_loop(
        "coupler", "rocker", pmd.Revolute(Z), translation_a=[L2, 0, 0], translation_b=[L3, 0, 0]
    )
    return m


def random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def random_body(rng):
    d = rng.uniform(0.05, 0.3, size=3)
    return pmd.RigidBody(
        rng.uniform(0.5, 2),
        rng.normal(scale=0.1, size=3),
        np.diag([d[1] + d[2], d[0] + d[2], d[0] + d[1]]) * 0.1,
    )


def random_joint(rng, kinds):
    kind = kinds[rng.integers(len(kinds))]
    axis = rng.normal(size=3)
    return {"R": pmd.Revolute(axis), "P": pmd.Prismatic(axis), "S": pmd.Spherical()}[kind]


def random_state(m, rng):
    q = m.neutral()
    for iq, _iv, nq, _nv in m.joint_slices():
        if nq == 4:
            x = rng.normal(size=4)
            q[iq : iq + 4] = x / np.linalg.norm(x)
        else:
            q[iq : iq + nq] = rng.uniform(-1, 1, size=nq)
    return q, rng.normal(size=m.nv)


def world_frame(m, q, body):
    """Body `body`'s world placement (R, p) at q, from the model's placements."""
    r, p = m.placements(q)
    return r[body], p[body]


def closed_random_tree(seed, cut_kinds, n=6):
    """A random tree with loops of the given cut-joint kinds, each closed at the returned q:
    frame b is chosen where frame a is at q (rotated about the free axes for revolute and
    prismatic cuts is unnecessary: coincident frames close every kind)."""
    rng = np.random.default_rng(seed)
    m = pmd.Model()
    for k in range(n):
        parent = -1 if k == 0 else int(rng.integers(-1, k))
        m.add_body(
            random_body(rng),
            random_joint(rng, "RPS"),
            parent=parent,
            translation=rng.normal(scale=0.3, size=3),
            rotation=random_rotation(rng),
        )
    q, v = random_state(m, rng)
    for kind in cut_kinds:
        a, b = rng.choice(np.arange(-1, n), size=2, replace=False)
        ra_w, pa_w = (np.eye(3), np.zeros(3)) if a == -1 else world_frame(m, q, a)
        rb_w, pb_w = (np.eye(3), np.zeros(3)) if b == -1 else world_frame(m, q, b)
        fa_r, fa_t = random_rotation(rng), rng.normal(scale=0.2, size=3)
        # The cut frame in the world, then in body b's frame.
        f_r, f_t = ra_w @ fa_r, pa_w + ra_w @ fa_t
        fb_r, fb_t = rb_w.T @ f_r, rb_w.T @ (f_t - pb_w)
        joint = {
            "R": pmd.Revolute(rng.normal(size=3)),
            "P": pmd.Prismatic(rng.normal(size=3)),
            "S": pmd.Spherical(),
            "F": pmd.Fixed(),
        }[kind]
        m.add_loop(
            int(a),
            int(b),
            joint,
            translation_a=fa_t,
            rotation_a=fa_r,
            translation_b=fb_t,
            rotation_b=fb_r,
        )
    return m, q, v, rng


def retract(m, q, dv):
    """q moved by the speeds dv for unit time (first order), quaternions renormalised."""
    out = q + m.velocity_to_qdot(q, dv)
    for iq, _iv, nq, _nv in m.joint_slices():
        if nq == 4:
            out[iq : iq + 4] /= np.linalg.norm(out[iq : iq + 4])
    return out


def kkt(m, q, v, tau, gravity):
    """The constrained accelerations and multipliers from the dense KKT system (least squares
    for redundant rows), with M, the bias forces and J from the model and J̇v by central
    differences of J along the motion."""
    mm = m.mass_matrix(q)
    h = m.bias_forces(q, v, gravity=gravity)
    j = m.constraint_jacobian(q)
    eps = 1e-6
    jdot_v = (
        (
            m.constraint_jacobian(retract(m, q, eps * v))
            - m.constraint_jacobian(retract(m, q, -eps * v))
        )
        @ v
        / (2 * eps)
    )
    nv, nc = m.nv, j.shape[0]
    k = np.block([[mm, -j.T], [j, np.zeros((nc, nc))]])
    rhs = np.concatenate([tau - h, -jdot_v])
    x = np.linalg.lstsq(k, rhs, rcond=1e-12)[0]
    return x[:nv], x[nv:], jdot_v


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("cuts", ["S", "F", "R", "P", "SR", "FP"])
def test_jacobian_is_the_derivative_of_the_residual(seed, cuts):
    m, q, v, _ = closed_random_tree(seed, cuts)
    assert m.nloops == len(cuts)
    assert m.nconstraints == sum({"S": 3, "R": 5, "P": 5, "F": 6}[c] for c in cuts)
    r0 = m.constraint_residual(q)
    assert np.abs(r0).max() < 1e-12
    j = m.constraint_jacobian(q)
    eps = 1e-6
    fd = (
        m.constraint_residual(retract(m, q, eps * v))
        - m.constraint_residual(retract(m, q, -eps * v))
    ) / (2 * eps)
    np.testing.assert_allclose(j @ v, fd, atol=1e-7 * (1 + np.abs(fd).max()))


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("cuts", ["S", "F", "SF", "R", "P", "RP"])
def test_forward_dynamics_solves_the_kkt_system(seed, cuts):
    m, q, v, rng = closed_random_tree(seed, cuts)
    v = m.assemble_velocity(q, v)
    tau = rng.normal(size=m.nv)
    a = m.forward_dynamics(q, v, tau, gravity=G)
    a_ref, _lam, jdot_v = kkt(m, q, v, tau, G)
    np.testing.assert_allclose(a, a_ref, rtol=1e-6, atol=1e-6 * np.abs(a_ref).max())
    j = m.constraint_jacobian(q)
    np.testing.assert_allclose(j @ a, -jdot_v, atol=1e-6 * (1 + np.abs(jdot_v).max()))
    # The constraint forces and the tree's inverse dynamics balance: M a + h = τ + Jᵀλ.
    forces = m.constraint_forces(q, v, tau, gravity=G)
    assert forces.shape == (m.nloops, 6)
    # Inverse dynamics with every joint actuated gives τ back (no loop force needed beyond λ).
    tau_back = m.inverse_dynamics(q, v, a, gravity=G, actuated=list(range(m.nv)))
    np.testing.assert_allclose(
        m.forward_dynamics(q, v, tau_back, gravity=G), a, atol=1e-8 * (1 + np.abs(a).max())
    )


def test_fourbar_is_redundant_in_space_and_moves_with_one_freedom():
    m = fourbar()
    q = m.assemble([0.5, 0.5, 1.5], fixed=[0])
    assert q[0] == 0.5
    j = m.constraint_jacobian(q)
    # A planar loop closed by a spatial revolute: 5 rows, 2 independent (the in-plane
    # position); z and the two tilt rows vanish identically.
    assert j.shape == (5, 3)
    assert np.linalg.matrix_rank(j, tol=1e-10) == 2
    np.testing.assert_array_equal(j[2:], 0.0)
    v = m.assemble_velocity(q, [2.0, 0.0, 0.0], fixed=["crank"])
    assert v[0] == 2.0
    assert np.abs(j @ v).max() < 1e-14
    a = m.forward_dynamics(q, v, np.zeros(3), gravity=G)
    a_ref, _, _ = kkt(m, q, v, np.zeros(3), G)
    np.testing.assert_allclose(a, a_ref, rtol=1e-7)
    # In-plane reaction only; the statically indeterminate components are zero (minimum norm).
    f = m.constraint_forces(q, v, np.zeros(3), gravity=G)
    assert np.all(f[0, 2:] == 0.0)


def test_fourbar_simulation_conserves_energy_and_stays_closed():
    m = fourbar()
    q = m.assemble([0.5, 0.5, 1.5], fixed=[0])
    v = m.assemble_velocity(q, [12.0, 0.0, 0.0], fixed=[0])
    scene = pmd.Scene(m, q0=q, v0=v, effects=[pmd.Gravity(G)])
    res = pmd.simulate(scene, (0, 2.0), rtol=1e-10, atol=1e-12, energy=True)
    assert res.success, res.message
    e = res.energy
    assert np.ptp(e) < 1e-8 * np.abs(e).max()
    assert res.constraint_residual.max() < 1e-12
    assert 0 < res.constraint_drift < 1e-8
    # The crank turns through full revolutions (crank-rocker), so the run is not trivial.
    assert np.ptp(res.q[:, 0]) > 2 * np.pi


def test_driving_torque_reproduces_the_prescribed_motion():
    m = fourbar()
    q = m.assemble([0.3, 0.5, 1.5], fixed=[0])
    v = m.assemble_velocity(q, [5.0, 0, 0], fixed=[0])
    a = m.assemble_acceleration(q, v, np.zeros(3), fixed=[0])
    assert a[0] == 0.0
    tau = m.inverse_dynamics(q, v, a, gravity=G, actuated=["crank"])
    assert tau[1] == tau[2] == 0.0
    np.testing.assert_allclose(m.forward_dynamics(q, v, tau, gravity=G), a, atol=1e-9)
    # Virtual work: the crank's power equals the rate of change of the mechanism's energy.
    h = 1e-6

    def energy(qq, vv):
        return m.kinetic_energy(qq, vv) + m.potential_energy(qq, G)

    q1, q2 = retract(m, q, h * v), retract(m, q, -h * v)
    v1 = m.assemble_velocity(q1, v + h * a, fixed=[0])
    v2 = m.assemble_velocity(q2, v - h * a, fixed=[0])
    de = (energy(q1, v1) - energy(q2, v2)) / (2 * h)
    assert abs(tau[0] * v[0] - de) < 1e-6 * (1 + abs(de))


def test_assemble_reaches_from_a_far_guess_and_keeps_fixed_coordinates():
    m = fourbar()
    for crank in np.linspace(0, 2 * np.pi, 13):
        q = m.assemble([crank, 0.0, 1.0], fixed=[0])
        assert q[0] == crank
        assert np.abs(m.constraint_residual(q)).max() <= 1e-12


def test_scene_file_with_a_loop_closes_its_initial_state(tmp_path):
    text = f"""
name = "fourbar"
[[body]]
name = "crank"
joint = {{ type = "Revolute", axis = [0, 0, 1] }}
mass = 1.0
com = [{L1 / 2}, 0, 0]
inertia_diag = [1e-4, 1e-3, 1e-3]
q0 = [0.5]
v0 = [2.0]
[[body]]
name = "coupler"
parent = "crank"
joint = {{ type = "Revolute", axis = [0, 0, 1] }}
translation = [{L1}, 0, 0]
mass = 1.0
com = [{L2 / 2}, 0, 0]
inertia_diag = [1e-4, 1e-2, 1e-2]
q0 = [0.4]
[[body]]
name = "rocker"
joint = {{ type = "Revolute", axis = [0, 0, 1] }}
translation = [{L0}, 0, 0]
mass = 1.0
com = [{L3 / 2}, 0, 0]
inertia_diag = [1e-4, 1e-2, 1e-2]
q0 = [1.6]
[[loop]]
name = "coupler-rocker"
body_a = "coupler"
body_b = "rocker"
joint = {{ type = "Revolute", axis = [0, 0, 1] }}
translation_a = [{L2}, 0, 0]
translation_b = [{L3}, 0, 0]
[initial]
fixed = ["crank"]
"""
    path = tmp_path / "fourbar.toml"
    path.write_text(text)
    scene = pmd.load_scene(path)
    m = scene.model
    assert m.nloops == 1 and m.loop_names == ["coupler-rocker"]
    assert scene.q0[0] == 0.5 and scene.v0[0] == 2.0
    assert np.abs(m.constraint_residual(scene.q0)).max() < 1e-12
    assert np.abs(m.constraint_jacobian(scene.q0) @ scene.v0).max() < 1e-12
    bad = text.replace('body_b = "rocker"', 'body_b = "nobody"')
    path.write_text(bad)
    with pytest.raises(pmd.SceneError, match=r"loop\[0\] \('coupler-rocker'\).body_b.*nobody"):
        pmd.load_scene(path)


def test_model_with_loops_pickles():
    m = fourbar()
    m2 = pickle.loads(pickle.dumps(m))
    q = m.assemble([0.5, 0.5, 1.5], fixed=[0])
    assert m2.nloops == 1
    np.testing.assert_array_equal(m2.constraint_jacobian(q), m.constraint_jacobian(q))


# --- bad input --------------------------------------------------------------------------


def test_loop_to_itself_or_a_welded_body_is_refused():
    m = fourbar()
    with pytest.raises(ModelStructureError, match="body_b: a loop must join two different bodies"):
        m.add_loop("coupler", "coupler", pmd.Revolute(Z))
    m.add_body(bar(0.1), pmd.Fixed(), parent=1, name="bracket")
    with pytest.raises(ModelStructureError, match="welded together"):
        m.add_loop("coupler", "bracket", pmd.Spherical())
    m.add_body(bar(0.1), pmd.Fixed(), name="post")
    with pytest.raises(ModelStructureError, match="welded together"):
        m.add_loop("post", "world", pmd.Spherical())


def test_unknown_bodies_and_joint_types_are_refused():
    m = fourbar()
    with pytest.raises(ModelStructureError, match="body_a: no body named 'nope'"):
        m.add_loop("nope", "rocker", pmd.Spherical())
    with pytest.raises(
        ModelStructureError,
        match=r"body_b: expected -1 \(the world\) or a body index 0\.\.3, got 7",
    ):
        m.add_loop(0, 7, pmd.Spherical())
    with pytest.raises(
        pmd.InvalidInputError,
        match="joint: expected a Revolute, Prismatic, Spherical or Fixed cut joint",
    ):
        m.add_loop(0, 2, pmd.SphericalZYZ())
    with pytest.raises(ModelStructureError, match="a loop named 'x' already exists"):
        m.add_loop(0, 2, pmd.Spherical(), name="x")
        m.add_loop(0, 2, pmd.Spherical(), name="x")


def test_a_loop_that_cannot_close_names_itself():
    m = pmd.Model()
    m.add_body(bar(L1), pmd.Revolute(Z), name="crank")
    m.add_body(bar(0.05), pmd.Revolute(Z), parent=0, translation=[L1, 0, 0], name="coupler")
    m.add_body(bar(0.2), pmd.Revolute(Z), translation=[L0, 0, 0], name="rocker")
    # Crank, coupler and rocker together (0.35) are shorter than the ground link (0.4).
    m.add_loop(
        "coupler",
        "rocker",
        pmd.Revolute(Z),
        translation_a=[0.05, 0, 0],
        translation_b=[0.2, 0, 0],
        name="short",
    )
    with pytest.raises(LoopClosureError, match="loop 'short' cannot be closed from this guess"):
        m.assemble([0.0, 0.0, 2.0])
    # Reachable in general, but not with the crank held where the coupler cannot reach.
    m2 = fourbar()
    with pytest.raises(LoopClosureError, match="loop 'loop0' cannot be closed"):
        m2.assemble([0.0, 0.0, 1.0], fixed=["crank", "rocker"])


def test_locked_mechanism_is_a_clear_error():
    # A triangle of two links pinned to the ground at both ends: no freedom of motion.
    m = pmd.Model()
    m.add_body(bar(0.3), pmd.Revolute(Z), name="left")
    m.add_body(bar(0.3), pmd.Revolute(Z), parent=0, translation=[0.3, 0, 0], name="right")
    m.add_loop(
        "right", "world", pmd.Revolute(Z), translation_a=[0.3, 0, 0], translation_b=[0.4, 0, 0]
    )
    q = m.assemble([0.8, -1.6])
    with pytest.raises(SingularityError, match="no freedom of motion"):
        m.forward_dynamics(q, np.zeros(2), np.zeros(2), gravity=G)
    with pytest.raises(SingularityError, match="no freedom of motion"):
        pmd.simulate(pmd.Scene(m, q0=q, effects=[pmd.Gravity(G)]), (0, 1))


def test_inverse_dynamics_with_loops_needs_the_actuated_joints():
    m = fourbar()
    q = m.assemble([0.5, 0.5, 1.5], fixed=[0])
    with pytest.raises(pmd.InvalidInputError, match="actuated: expected the actuated joints"):
        m.inverse_dynamics(q, np.zeros(3), np.zeros(3))
    a_bad = np.array([1.0, 0.0, 0.0])
    with pytest.raises(
        pmd.InvalidInputError, match="a: expected accelerations that keep the loops closed"
    ):
        m.inverse_dynamics(q, np.zeros(3), a_bad, actuated=[0])
    with pytest.raises(
        pmd.InvalidInputError, match="actuated: expected v indices 0..3 or body names"
    ):
        m.inverse_dynamics(q, np.zeros(3), np.zeros(3), actuated=[5])



def test_inverse_dynamics_splits_redundant_actuation_and_refuses_an_impossible_one():
    """Crank and slider both actuated: the forces are the least-norm solution of
    [S_a | Jᵀ] (τ_a, λ) = M a + h, as NumPy's lstsq (SVD) finds it from the model's own M, h
    and J. The slider alone cannot turn the crank at the dead centre (crank and rod in line):
    an error that names the imbalance."""
    scene = pmd.load_scene("slider_crank")
    m = scene.model
    q = m.assemble([1.0, *scene.q0[1:]], fixed=[0])
    v = m.assemble_velocity(q, [30.0, 0.0, 0.0], fixed=[0])
    a = m.assemble_acceleration(q, v, [-200.0, 0.0, 0.0], fixed=[0])
    tau = m.inverse_dynamics(q, v, a, gravity=G, actuated=["crank", "slider"])
    system = np.hstack([np.eye(3)[:, [0, 2]], m.constraint_jacobian(q).T])
    rhs = m.mass_matrix(q) @ a + m.bias_forces(q, v, gravity=G)
    ref = np.linalg.lstsq(system, rhs, rcond=1e-12)[0]
    assert tau[1] == 0.0
    np.testing.assert_allclose(tau[[0, 2]], ref[:2], rtol=0, atol=1e-14 * np.abs(ref).max())
    # Dead centre: the slider's force passes through the crank's pivot.
    crank, rod = 0.04, 0.12
    offset = scene.model.placements(q)[1][m.body_names.index("slider")][1]
    q = m.assemble([np.arcsin(offset / (crank + rod)), 0.0, crank + rod], fixed=[0])
    a = m.assemble_acceleration(q, np.zeros(3), [1.0, 0.0, 0.0], fixed=[0])
    m.inverse_dynamics(q, np.zeros(3), a, gravity=G, actuated=["crank"])
    with pytest.raises(SingularityError, match=r"actuated coordinates \[2\] cannot produce"):
        m.inverse_dynamics(q, np.zeros(3), a, gravity=G, actuated=["slider"])

def test_simulate_refuses_an_open_or_inconsistent_initial_state():
    m = fourbar()
    with pytest.raises(LoopClosureError, match="q0: loop 'loop0' is open"):
        pmd.simulate(pmd.Scene(m, q0=[0.5, 0.5, 1.5]), (0, 1))
    q = m.assemble([0.5, 0.5, 1.5], fixed=[0])
    with pytest.raises(
        pmd.InvalidInputError, match=r"v0: expected speeds that keep the loops closed"
    ):
        pmd.simulate(pmd.Scene(m, q0=q, v0=[1.0, 0, 0]), (0, 1))


def test_events_and_dissipative_effects_work_with_loops():
    m = fourbar()
    q = m.assemble([0.5, 0.5, 1.5], fixed=[0])
    v = m.assemble_velocity(q, [12.0, 0.0, 0.0], fixed=[0])
    damper = pmd.Damper(["crank"], 0.05, name="brake")
    scene = pmd.Scene(m, q0=q, v0=v, effects=[pmd.Gravity(G), damper])
    # The crank swinging back down through 0: located on the dense output, the state there
    # closes the loop to the interpolation error.
    event = pmd.StateEvent("q", 0, 0.0, direction=-1)
    res = pmd.simulate(
        scene, (0, 1.0), rtol=1e-10, atol=1e-12, energy=True, power=True, events=[event]
    )
    assert res.success, res.message
    (te,) = res.t_events
    assert len(te) >= 1
    qe = res.q_events[0][0]
    assert abs(qe[0]) < 1e-9
    assert np.abs(m.constraint_residual(qe)).max() < 1e-8
    # Energy balance with a damper: E(t) − E(0) equals the integral of the damper's power
    # (trapezoid on the dense output samples), and energy only decreases.
    e = res.energy
    p = res.power["brake"]
    assert np.all(np.diff(e) <= 1e-12 * np.abs(e).max())
    t_fine = np.linspace(0, 1.0, 4001)
    fine = pmd.simulate(
        scene, (0, 1.0), rtol=1e-10, atol=1e-12, energy=True, power=True, t_eval=t_fine
    )
    pb = fine.power["brake"]
    work = np.sum(np.diff(fine.t) * (pb[1:] + pb[:-1]) / 2)
    assert abs((fine.energy[-1] - fine.energy[0]) - work) < 1e-6 * abs(work)
    assert p.min() <= 0.0
