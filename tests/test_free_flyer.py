"""The FreeFlyer joint (Pinocchio's JointModelFreeFlyer convention) against Pinocchio's
floating-base models of example-robot-data robots, against rigid-body mechanics (Euler's
equations integrated by SciPy, free fall, conserved momenta), and through scenes, effects,
loops, pickling and the CLI."""

from __future__ import annotations

import pickle

import numpy as np
import pinocchio as pin
import pointmass_dyn as pmd
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

TOL = 1e-9
G = np.array([0.0, 0.0, -9.81])


def rel(ours, theirs):
    return np.abs(ours - theirs).max() / max(np.abs(theirs).max(), 1e-300)


def random_state(nq, nv, rng):
    q = np.empty(nq)
    q[:3] = rng.normal(size=3)
    quat = rng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)
    q[7:] = rng.uniform(-1.5, 1.5, nq - 7)
    return q, rng.normal(size=nv), rng.normal(size=nv), rng.normal(size=nv)


def test_floating_robot_names_and_sizes_equal_pinocchios(floating_robot):
    name, model, pm = floating_robot
    assert model.joint_names == list(pm.names)[1:], name
    assert model.joint_names[0] == "root_joint"
    assert (model.nq, model.nv) == (pm.nq, pm.nv) == (model.nv + 1, pm.nv)
    assert model.joint_slices()[0] == (0, 0, 7, 6)
    np.testing.assert_array_equal(model.neutral(), pin.neutral(pm))
    assert model.total_mass == pytest.approx(pin.computeTotalMass(pm), rel=1e-12)


def test_floating_robot_dynamics_equal_pinocchios(floating_robot):
    name, model, pm = floating_robot
    pd = pm.createData()
    rng = np.random.default_rng(7)
    worst = {}
    for _ in range(4):
        q, v, tau, a = random_state(pm.nq, pm.nv, rng)
        mp = pin.crba(pm, pd, q)
        mp = np.triu(mp) + np.triu(mp, 1).T
        pairs = {
            "M": (model.mass_matrix(q), mp),
            "M (denoc)": (model.mass_matrix(q, method="denoc"), mp),
            "bias": (model.bias_forces(q, v, gravity=G), pin.nonLinearEffects(pm, pd, q, v)),
            "ID": (model.inverse_dynamics(q, v, a, gravity=G), pin.rnea(pm, pd, q, v, a)),
            "FD": (model.forward_dynamics(q, v, tau, gravity=G), pin.aba(pm, pd, q, v, tau)),
            "FD (denoc)": (
                model.forward_dynamics(q, v, tau, gravity=G, method="denoc"),
                pin.aba(pm, pd, q, v, tau),
            ),
        }
        for k, (ours, theirs) in pairs.items():
            worst[k] = max(worst.get(k, 0.0), rel(ours, theirs))
    # FD goes through M⁻¹: scale its bar by M's condition number (icub-like robots reach 1e7).
    cond = np.linalg.cond(mp)
    bad = {
        k: e for k, e in worst.items() if not e <= (TOL if "FD" not in k else TOL * max(1, cond))
    }
    assert not bad, (name, bad, cond)


def test_energies_equal_pinocchios(floating_robot):
    _, model, pm = floating_robot
    pd = pm.createData()
    q, v, _, _ = random_state(pm.nq, pm.nv, np.random.default_rng(3))
    assert model.kinetic_energy(q, v) == pytest.approx(
        pin.computeKineticEnergy(pm, pd, q, v), rel=1e-12
    )
    pm.gravity.linear = G
    # Potential energies agree up to a constant: compare differences between two states.
    q2, _, _, _ = random_state(pm.nq, pm.nv, np.random.default_rng(4))
    ours = model.potential_energy(q2, gravity=G) - model.potential_energy(q, gravity=G)
    theirs = pin.computePotentialEnergy(pm, pd, q2) - pin.computePotentialEnergy(pm, pd, q)
    assert ours == pytest.approx(theirs, rel=1e-10, abs=1e-10)


def box(mass=12.0, dims=(0.3, 0.2, 0.1)):
    a, b, c = dims
    inertia = mass / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    return pmd.RigidBody(mass, com=[0, 0, 0], inertia=inertia), inertia


def free_box_model():
    body, inertia = box()
    m = pmd.Model()
    m.add_body(body, pmd.FreeFlyer(), parent=-1, name="box")
    return m, inertia


def test_torque_free_rotation_follows_eulers_equations():
    """Body-frame angular velocity against Euler's equations I ω̇ = −ω × I ω (SciPy, DOP853);
    the world angular momentum R I ω, linear momentum and energy stay constant."""
    model, inertia = free_box_model()
    w0 = np.array([0.01, 2.0, 0.01])  # near the intermediate axis: it flips (Dzhanibekov)
    q0 = np.array([0.1, -0.2, 0.3, 0, 0, 0, 1.0])
    v0 = np.concatenate([[0.05, 0.0, -0.02], w0])
    ts = np.linspace(0, 12, 61)
    res = pmd.simulate(pmd.Scene(model, q0, v0), (0, 12), t_eval=ts, rtol=1e-11, atol=1e-12)
    assert res.success, res.message
    inv = np.linalg.inv(inertia)
    ref = solve_ivp(
        lambda t, w: inv @ (-np.cross(w, inertia @ w)),
        (0, 12),
        w0,
        method="DOP853",
        t_eval=ts,
        rtol=1e-12,
        atol=1e-14,
    )
    w = res.v[:, 3:]
    assert np.abs(w - ref.y.T).max() < 1e-7
    assert np.ptp(w[:, 1]) > 3.0  # it did flip
    rot = Rotation.from_quat(res.q[:, 3:7])  # SciPy's quaternions are (x, y, z, w) too
    momentum = rot.apply(w @ inertia)  # R I ω
    assert np.abs(momentum - momentum[0]).max() < 1e-9 * np.linalg.norm(momentum[0])
    velocity = rot.apply(res.v[:, :3])  # the centre of mass moves uniformly
    assert np.abs(velocity - velocity[0]).max() < 1e-9
    np.testing.assert_allclose(res.q[:, :3], q0[:3] + np.outer(ts, velocity[0]), atol=1e-9)
    energy = [model.kinetic_energy(q, v) for q, v in zip(res.q, res.v)]
    assert np.ptp(energy) < 1e-9 * energy[0]


def test_free_fall_is_a_parabola_whatever_the_spin():
    model, _ = free_box_model()
    q0 = np.array([0.0, 0.0, 10.0, 0.2, 0.1, -0.3, 0.9])
    q0[3:] /= np.linalg.norm(q0[3:])
    v0 = np.array([1.0, 0.5, 2.0, 0.3, -0.7, 1.1])
    ts = np.linspace(0, 1.5, 16)
    scene = pmd.Scene(model, q0, v0, effects=[pmd.Gravity(G)])
    res = pmd.simulate(scene, (0, 1.5), t_eval=ts, rtol=1e-11, atol=1e-12, energy=True)
    assert res.success, res.message
    v_world0 = Rotation.from_quat(q0[3:]).apply(v0[:3])
    expect = q0[:3] + np.outer(ts, v_world0) + 0.5 * np.outer(ts**2, G)
    np.testing.assert_allclose(res.q[:, :3], expect, atol=1e-9)
    assert np.abs(res.energy - res.energy[0]).max() < 1e-9 * abs(res.energy[0])


def test_external_force_and_moment_accelerate_the_body_as_newton_and_euler_say():
    model, inertia = free_box_model()
    q = np.array([0.3, 0.1, -0.2, 0.1, 0.4, -0.2, 0.8])
    q[3:] /= np.linalg.norm(q[3:])
    v = np.zeros(6)
    f, n = np.array([1.0, -2.0, 3.0]), np.array([0.2, 0.1, -0.3])
    scene = pmd.Scene(model, q, v, effects=[pmd.ExternalForce("box", f, moment=n)])
    tau = pmd.effect_forces(scene, 0.0, q, v)
    a = model.forward_dynamics(q, v, sum(tau.values()))
    rot = Rotation.from_quat(q[3:])
    # At rest: body-frame linear acceleration Rᵀ f / m, angular I⁻¹ Rᵀ n.
    np.testing.assert_allclose(a[:3], rot.inv().apply(f) / 12.0, rtol=1e-12)
    np.testing.assert_allclose(a[3:], np.linalg.solve(inertia, rot.inv().apply(n)), rtol=1e-12)


def test_a_free_flyer_below_a_joint_equals_pinocchios():
    """A free flyer that is not the root (a body floating inside a moving cabin)."""
    rng = np.random.default_rng(11)
    body, inertia = box(3.0, (0.4, 0.3, 0.2))
    m = pmd.Model()
    place = Rotation.from_rotvec([0.3, -0.2, 0.5])
    m.add_body(body, pmd.Revolute([0, 0, 1]), parent=-1, name="cabin")
    m.add_body(
        body,
        pmd.FreeFlyer(),
        parent=0,
        translation=[0.5, 0.1, 0.0],
        rotation=place.as_matrix(),
        name="float",
    )
    pm = pin.Model()
    inert = pin.Inertia(3.0, np.zeros(3), inertia)
    j1 = pm.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "cabin")
    pm.appendBodyToJoint(j1, inert, pin.SE3.Identity())
    j2 = pm.addJoint(
        j1,
        pin.JointModelFreeFlyer(),
        pin.SE3(place.as_matrix(), np.array([0.5, 0.1, 0.0])),
        "float",
    )
    pm.appendBodyToJoint(j2, inert, pin.SE3.Identity())
    pm.gravity.linear = G
    pd = pm.createData()
    for _ in range(3):
        q = np.concatenate([[rng.uniform(-3, 3)], rng.normal(size=3), rng.normal(size=4)])
        q[4:] /= np.linalg.norm(q[4:])
        v, tau = rng.normal(size=7), rng.normal(size=7)
        assert rel(m.forward_dynamics(q, v, tau, gravity=G), pin.aba(pm, pd, q, v, tau)) < TOL
        assert rel(m.inverse_dynamics(q, v, tau, gravity=G), pin.rnea(pm, pd, q, v, tau)) < TOL
        mp = pin.crba(pm, pd, q)
        assert rel(m.mass_matrix(q), np.triu(mp) + np.triu(mp, 1).T) < TOL


def test_free_body_held_by_a_spherical_cut_joint_is_a_spherical_pendulum():
    """Loops and the free flyer together: a free box tied to the world at a point by a
    spherical cut joint moves as the same box on a Spherical tree joint at that point."""
    body, _ = box(2.0, (0.5, 0.1, 0.1))
    pivot = np.array([-0.25, 0.0, 0.0])  # in the box frame: one end of the box
    tied = pmd.Model()
    tied.add_body(body, pmd.FreeFlyer(), parent=-1, name="box")
    tied.add_loop("box", "world", pmd.Spherical(), translation_a=pivot)
    ball = pmd.Model()
    ball.add_body(body, pmd.Spherical(), parent=-1, translation=[0, 0, 0], name="box")
    rot = Rotation.from_rotvec([0.4, 0.9, -0.2])
    w = np.array([0.5, -1.0, 2.0])
    # The same state: the box origin at R (−pivot) from the world point (the origin).
    q_tied = np.concatenate([rot.apply(-pivot), rot.as_quat()])
    v_lin = np.cross(w, -pivot)  # body-frame velocity of the box origin
    v_tied = np.concatenate([v_lin, w])
    assert np.abs(tied.constraint_residual(q_tied)).max() < 1e-15
    assert np.abs(tied.constraint_jacobian(q_tied) @ v_tied).max() < 1e-14
    ts = np.linspace(0, 2, 11)
    res_tied = pmd.simulate(
        pmd.Scene(tied, q_tied, v_tied, effects=[pmd.Gravity(G)]),
        (0, 2),
        t_eval=ts,
        rtol=1e-11,
        atol=1e-12,
    )
    # The ball model: body frame at the pivot, so shift the body by −pivot.
    shifted = pmd.RigidBody(2.0, com=-pivot, inertia=body.inertia)
    ball = pmd.Model()
    ball.add_body(shifted, pmd.Spherical(), parent=-1, name="box")
    res_ball = pmd.simulate(
        pmd.Scene(ball, rot.as_quat(), w, effects=[pmd.Gravity(G)]),
        (0, 2),
        t_eval=ts,
        rtol=1e-11,
        atol=1e-12,
    )
    assert res_tied.success and res_ball.success
    np.testing.assert_allclose(res_tied.v[:, 3:], res_ball.v, atol=1e-8)
    same = np.abs(np.sum(res_tied.q[:, 3:] * res_ball.q, axis=1))  # q and −q are one rotation
    np.testing.assert_allclose(same, 1.0, atol=1e-9)
    assert res_tied.constraint_residual.max() <= 1e-10


def test_bundled_satellite_flips_and_conserves_energy():
    scene = pmd.load_scene("satellite")
    assert scene.model.joint_slices()[0][2:] == (7, 6)
    res = pmd.simulate(scene, energy=True)
    assert res.success, res.message
    assert res.v[:, 4].min() < -1.9  # the Dzhanibekov flip
    assert np.abs(res.energy - res.energy[0]).max() < 1e-8 * res.energy[0]


def test_scene_file_root_joint_free(tmp_path):
    urdf = tmp_path / "r.urdf"
    urdf.write_text(
        """<robot name="r">
  <link name="base"><inertial><mass value="2"/><inertia ixx="0.1" iyy="0.2" izz="0.25"
    ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="arm"><inertial><origin xyz="0.2 0 0"/><mass value="1"/><inertia ixx="0.01"
    iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"""
    )
    (tmp_path / "s.toml").write_text('urdf = "r.urdf"\nroot_joint = "free"\n')
    scene = pmd.Scene.from_file(tmp_path / "s.toml")
    assert (scene.model.nq, scene.model.nv) == (8, 7)
    pm = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    q, v, tau, _ = random_state(8, 7, np.random.default_rng(1))
    pd = pm.createData()
    assert rel(scene.model.forward_dynamics(q, v, tau, gravity=G), pin.aba(pm, pd, q, v, tau)) < TOL
    (tmp_path / "bad.toml").write_text('urdf = "r.urdf"\nroot_joint = "floating"\n')
    with pytest.raises(pmd.errors.SceneError, match="root_joint"):
        pmd.Scene.from_file(tmp_path / "bad.toml")


def test_root_joint_argument_errors_and_quaternion_checks():
    with pytest.raises(pmd.errors.InvalidInputError, match="root_joint"):
        pmd.Model.from_urdf("nowhere.urdf", root_joint="floating")
    model, _ = free_box_model()
    with pytest.raises(pmd.errors.InvalidInputError, match="quaternion"):
        model.forward_dynamics(np.zeros(7), np.zeros(6), np.zeros(6))
    assert pmd.FreeFlyer().kind == "FreeFlyer"
    assert (pmd.FreeFlyer().nq, pmd.FreeFlyer().nv) == (7, 6)
    with pytest.raises(pmd.errors.InvalidInputError, match="free flyer"):
        pmd.Scene(model, model.neutral(), np.zeros(6), effects=[pmd.Spring(None, 1.0)])


def test_free_flyer_models_pickle():
    model, _ = free_box_model()
    again = pickle.loads(pickle.dumps(model))
    q = np.array([0.1, 0.2, 0.3, 0.1, 0.2, 0.3, 0.9])
    v = np.arange(6.0)
    np.testing.assert_array_equal(
        again.forward_dynamics(q, v, np.zeros(6), gravity=G),
        model.forward_dynamics(q, v, np.zeros(6), gravity=G),
    )
