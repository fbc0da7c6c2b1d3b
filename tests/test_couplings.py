"""Joint couplings (mimic joints) and rotor inertia (armature), against independent
references: the SymPy Lagrangian of a coupled arm's reduced coordinate, Pinocchio's mimic
models and its `model.armature`, MuJoCo's armature and joint equalities, invariants (the
coupling along a run, energy), and the errors (docs/couplings.md)."""

from __future__ import annotations

import pickle
import warnings

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import record, rel_err
from pointmass_dyn.errors import InvalidInputError, ModelImportWarning

Z = [0.0, 0.0, 1.0]
G = np.array([0.0, -9.81, 0.0])
# Planar arm: link lengths, masses, COM distances, inertias about the COM (z).
L1, M1, C1, I1 = 0.4, 1.2, 0.2, 0.02
M2, C2, I2 = 0.8, 0.15, 0.01


def arm(ratio, offset, armature=(0.0, 0.0)):
    m = pmd.Model()
    m.add_body(pmd.RigidBody(M1, [C1, 0, 0], np.diag([1e-3, I1, I1])), pmd.Revolute(Z), name="upper")
    m.add_body(
        pmd.RigidBody(M2, [C2, 0, 0], np.diag([1e-3, I2, I2])),
        pmd.Revolute(Z),
        parent=0,
        translation=[L1, 0, 0],
        name="fore",
    )
    m.add_coupling("fore", "upper", ratio=ratio, offset=offset)
    for body, a in zip(("upper", "fore"), armature):
        m.set_armature(body, a)
    return m


def reduced_lagrangian(ratio, offset, armature):
    """θ̈(θ, θ̇, τ_red) and τ_red(θ, θ̇, θ̈) of the arm in its reduced coordinate θ = q1
    (q2 = ratio θ + offset), from the Lagrangian derived by SymPy."""
    sp = pytest.importorskip("sympy")
    t = sp.symbols("t")
    th = sp.Function("th")(t)
    q1, q2 = th, ratio * th + offset
    g = -G[1]
    p1 = sp.Matrix([C1 * sp.cos(q1), C1 * sp.sin(q1)])
    p2 = sp.Matrix([L1 * sp.cos(q1), L1 * sp.sin(q1)]) + C2 * sp.Matrix(
        [sp.cos(q1 + q2), sp.sin(q1 + q2)]
    )
    v1, v2 = p1.diff(t), p2.diff(t)
    kinetic = (
        M1 * v1.dot(v1) / 2
        + I1 * q1.diff(t) ** 2 / 2
        + M2 * v2.dot(v2) / 2
        + I2 * (q1 + q2).diff(t) ** 2 / 2
        + armature[0] * q1.diff(t) ** 2 / 2
        + armature[1] * q2.diff(t) ** 2 / 2
    )
    lagrangian = kinetic - g * (M1 * p1[1] + M2 * p2[1])
    eq = sp.diff(lagrangian.diff(th.diff(t)), t) - lagrangian.diff(th)
    x, xd, xdd, tau = sp.symbols("x xd xdd tau")
    eq = eq.subs(th.diff(t, 2), xdd).subs(th.diff(t), xd).subs(th, x)
    # The equation is linear in θ̈: θ̈ = (τ − eq|θ̈=0) / (∂eq/∂θ̈).
    accel = (tau - eq.subs(xdd, 0)) / eq.diff(xdd)
    return sp.lambdify((x, xd, tau), accel), sp.lambdify((x, xd, xdd), eq)


@pytest.mark.parametrize("ratio,offset,armature", [(0.5, 0.2, (0.0, 0.0)), (-1.5, -0.3, (0.05, 0.2))])
def test_coupled_arm_equals_reduced_lagrangian(ratio, offset, armature):
    accel, force = reduced_lagrangian(ratio, offset, armature)
    m = arm(ratio, offset, armature)
    rng = np.random.default_rng(3)
    for _ in range(5):
        th, thd = rng.uniform(-2, 2), rng.uniform(-3, 3)
        tau = rng.uniform(-1, 1, size=2)
        q = np.array([th, ratio * th + offset])
        v = np.array([thd, ratio * thd])
        a = m.forward_dynamics(q, v, tau, gravity=G)
        # Virtual work: the reduced force is τ1 + ratio τ2.
        ref = accel(th, thd, tau[0] + ratio * tau[1])
        e = abs(a[0] - ref) / (1 + abs(ref))
        record("coupling: arm q̈ vs reduced Lagrangian", e)
        assert e <= 1e-12, (a, ref)
        assert abs(a[1] - ratio * a[0]) <= 1e-12 * (1 + abs(a[0]))
        # Inverse dynamics driven by the reference joint alone: the reduced force.
        tau_id = m.inverse_dynamics(q, v, a, gravity=G, actuated=["upper"])
        ref_tau = force(th, thd, a[0])
        assert abs(tau_id[0] - ref_tau) <= 1e-11 * (1 + abs(ref_tau)) and tau_id[1] == 0.0


def test_coupling_holds_over_a_run_and_conserves_energy():
    m = arm(0.5, 0.2, armature=(0.0, 0.1))
    q0 = np.array([0.3, 0.5 * 0.3 + 0.2])
    v0 = np.array([1.0, 0.5])
    scene = pmd.Scene(m, q0=q0, v0=v0, effects=[pmd.Gravity(G)])
    res = pmd.simulate(scene, (0, 2.0), rtol=1e-10, atol=1e-12, energy=True)
    assert res.success, res.message
    drift = np.abs(res.q[:, 1] - 0.5 * res.q[:, 0] - 0.2).max()
    speed = np.abs(res.v[:, 1] - 0.5 * res.v[:, 0]).max()
    record("coupling: residual along a 2 s run", drift)
    assert drift <= 1e-9 and speed <= 1e-9
    e = np.asarray(res.energy)
    assert np.abs(e - e[0]).max() <= 1e-7 * (1 + abs(e[0]))


GRIPPER = """<robot name="gripper">
  <link name="base"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="palm"><inertial><mass value="0.8"/><origin xyz="0.05 0.01 0"/><inertia ixx="0.002" iyy="0.003" izz="0.004" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="finger_a"><inertial><mass value="0.2"/><origin xyz="0.03 0 0.01"/><inertia ixx="0.0004" iyy="0.0005" izz="0.0003" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="finger_b"><inertial><mass value="0.25"/><origin xyz="0.03 0.005 0"/><inertia ixx="0.0004" iyy="0.0006" izz="0.0003" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip_a"><inertial><mass value="0.1"/><origin xyz="0.02 0 0"/><inertia ixx="0.0001" iyy="0.0002" izz="0.0002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="a_wrist" type="revolute"><parent link="base"/><child link="palm"/><origin xyz="0 0 0.1" rpy="0.1 0 0"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="10" velocity="5"/></joint>
  <joint name="b_finger_a" type="revolute"><parent link="palm"/><child link="finger_a"/><origin xyz="0.1 0.02 0" rpy="0 0 0.2"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="10" velocity="5"/></joint>
  <joint name="c_finger_b" type="revolute"><parent link="palm"/><child link="finger_b"/><origin xyz="0.1 -0.02 0" rpy="0 0 -0.2"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="10" velocity="5"/><mimic joint="b_finger_a" multiplier="-1" offset="0.05"/></joint>
  <joint name="d_tip_a" type="prismatic"><parent link="finger_a"/><child link="tip_a"/><origin xyz="0.06 0 0"/><axis xyz="1 0 0"/><limit lower="0" upper="0.05" effort="10" velocity="5"/><mimic joint="b_finger_a" multiplier="0.02" offset="0.01"/></joint>
</robot>"""


def gripper_state(qr, vr):
    """Our full state (joints a, b, d, c in q/v order) from the reduced (a, b)."""
    q = np.array([qr[0], qr[1], 0.02 * qr[1] + 0.01, -qr[1] + 0.05])
    v = np.array([vr[0], vr[1], 0.02 * vr[1], -vr[1]])
    return q, v


def test_gripper_mimic_loads_as_couplings_and_matches_pinocchio(tmp_path):
    path = tmp_path / "gripper.urdf"
    path.write_text(GRIPPER)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m = pmd.Model.from_urdf(str(path))
    assert m.joint_names == ["a_wrist", "b_finger_a", "d_tip_a", "c_finger_b"]
    assert m.couplings == [
        ("d_tip_a", "tip_a", "finger_a", 0.02, 0.01),
        ("c_finger_b", "finger_b", "finger_a", -1.0, 0.05),
    ]
    pin = pytest.importorskip("pinocchio")
    try:
        pm = pin.buildModelFromUrdf(str(path), mimic=True)
    except TypeError:  # pragma: no cover - Pinocchio before mimic models
        pytest.skip("this Pinocchio has no mimic models")
    assert pm.nv == 2
    d = pm.createData()
    g = [0.0, 0.0, -9.81]
    rng = np.random.default_rng(0)
    for _ in range(5):
        qr, vr, tau_r = rng.uniform(-1, 1, 2), rng.uniform(-2, 2, 2), rng.uniform(-1, 1, 2)
        mr = pin.crba(pm, d, qr)
        mr = np.triu(mr) + np.triu(mr, 1).T
        b = pin.rnea(pm, d, qr, vr, np.zeros(2))
        ref = np.linalg.solve(mr, tau_r - b)
        q, v = gripper_state(qr, vr)
        assert np.abs(m.constraint_residual(q)).max() <= 1e-15
        a = m.forward_dynamics(q, v, np.r_[tau_r, 0.0, 0.0], gravity=g)
        e = rel_err(a[:2], ref)
        record("coupling: gripper q̈ vs Pinocchio mimic", e)
        assert e <= 1e-10, (a, ref)
        # The reduced mass matrix Gᵀ M G (G: reduced speeds → ours) is Pinocchio's.
        gmap = np.array([[1, 0], [0, 1], [0, 0.02], [0, -1]])
        assert rel_err(gmap.T @ m.mass_matrix(q) @ gmap, mr) <= 1e-12
        tau = m.inverse_dynamics(q, v, a, gravity=g, actuated=["palm", "finger_a"])
        assert rel_err(tau[:2], tau_r) <= 1e-10


def test_talos_mimic_joints_load_as_couplings():
    """Talos' 12 gripper mimic joints become couplings (no warning), and its dynamics keep
    them: J q̈ = 0 at a closed state."""
    path = pmd.robots.urdf_path("talos")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = pmd.Model.from_urdf(str(path))
    assert not [w for w in caught if "mimic" in str(w.message)]
    assert m.ncouplings == 12
    names = set(m.joint_names)
    assert all(c[0] in names for c in m.couplings)
    rng = np.random.default_rng(1)
    q = m.assemble(rng.uniform(-0.3, 0.3, m.nq))
    v = m.assemble_velocity(q, rng.uniform(-1, 1, m.nv))
    a = m.forward_dynamics(q, v, np.zeros(m.nv), gravity=[0, 0, -9.81])
    j = m.constraint_jacobian(q)
    assert np.abs(m.constraint_residual(q)).max() <= 1e-12
    assert np.abs(j @ a).max() <= 1e-9 * (1 + np.abs(a).max())
    # The reduced Talos welds its grippers: their <mimic> has nothing to couple.
    with pytest.warns(pmd.errors.UrdfWarning, match=r"<mimic> elements with nothing to couple.*on or of fixed joints: 'gripper"):
        m = pmd.Model.from_urdf(str(path.parent / "talos_reduced.urdf"))
    assert m.ncouplings == 0


# ------------------------------------------------------------------------------ armature


def test_armature_matches_pinocchio():
    pin = pytest.importorskip("pinocchio")
    pm = pin.buildModelFromUrdf(str(pmd.robots.urdf_path("panda")))
    pm.armature[:] = np.linspace(0.1, 0.5, pm.nv)
    m = pmd.Model.from_pinocchio(pm)
    assert np.array_equal(m.armature, pm.armature)
    d = pm.createData()
    g = [0.0, 0.0, -9.81]
    rng = np.random.default_rng(2)
    for _ in range(3):
        q = pin.randomConfiguration(pm)
        v, tau = rng.normal(size=pm.nv), rng.normal(size=pm.nv)
        a = pin.aba(pm, d, q, v, tau)
        mm = pin.crba(pm, d, q)
        mm = np.triu(mm) + np.triu(mm, 1).T
        for method in ("recursive", "denoc"):
            e = rel_err(m.forward_dynamics(q, v, tau, gravity=g, method=method), a)
            record(f"armature: panda FD ({method}) vs Pinocchio", e)
            assert e <= 1e-10
            assert rel_err(m.inverse_dynamics(q, v, a, gravity=g, method=method), tau) <= 1e-10
            assert rel_err(m.mass_matrix(q, method=method), mm) <= 1e-12
        pin.computeABADerivatives(pm, d, q, v, tau)
        dq, dv, minv = m.forward_dynamics_derivatives(q, v, tau, gravity=g)
        assert rel_err(dq, d.ddq_dq) <= 1e-10 and rel_err(dv, d.ddq_dv) <= 1e-10
        assert rel_err(minv, d.Minv) <= 1e-10
        _, _, mass = m.inverse_dynamics_derivatives(q, v, a, gravity=g)
        assert rel_err(mass, mm) <= 1e-12
        assert abs(m.kinetic_energy(q, v) - 0.5 * v @ mm @ v) <= 1e-12 * (v @ mm @ v)


ARMATURE_XML = """<mujoco><option gravity="0.3 -0.2 -9.81"/>
  <worldbody>
    <body name="a" pos="0.1 0.2 0.3"><joint name="h1" axis="1 2 0" armature="0.3"/>
      <geom type="capsule" size="0.05" fromto="0 0 0 0.3 0.1 0"/>
      <body name="b" pos="0.3 0.1 0"><joint name="s1" type="slide" axis="0 1 1" armature="0.7"/>
        <geom type="box" size="0.1 0.05 0.02" pos="0.1 0 0"/>
        <body name="c" pos="0.2 0 0"><joint name="ball" type="ball" armature="0.05"/>
          <geom type="box" size="0.1 0.03 0.02" pos="0.1 0 0"/>
          <body name="d" pos="0.2 0 0"><joint name="h2" axis="0 0 1" armature="0.02"/>
            <geom type="sphere" size="0.04" pos="0.05 0.02 0"/></body></body></body></body>
  </worldbody></mujoco>"""


def test_armature_matches_mujoco():
    mujoco = pytest.importorskip("mujoco")
    mj = mujoco.MjModel.from_xml_string(ARMATURE_XML)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ModelImportWarning)
        m = pmd.from_mujoco(mj)
    assert np.array_equal(m.armature, mj.dof_armature)
    data = mujoco.MjData(mj)
    rng = np.random.default_rng(4)
    for _ in range(3):
        qpos = mj.qpos0.copy()
        qpos[:2] = rng.uniform(-1, 1, 2)
        w = rng.normal(size=4)
        qpos[2:6] = w / np.linalg.norm(w)
        qpos[6] = rng.uniform(-1, 1)
        qvel, tau = rng.normal(size=mj.nv), rng.normal(size=mj.nv)
        data.qpos[:], data.qvel[:], data.qfrc_applied[:] = qpos, qvel, tau
        mujoco.mj_forward(mj, data)
        q, v = pmd.io.mujoco_state(mj, qpos, qvel)
        a = m.forward_dynamics(q, v, tau, gravity=mj.opt.gravity)
        e = rel_err(a, data.qacc)
        record("armature: FD vs MuJoCo qacc", e)
        assert e <= 1e-10, (a, data.qacc)


def test_mujoco_joint_equality_is_a_coupling():
    mujoco = pytest.importorskip("mujoco")
    xml = """<mujoco><worldbody>
      <body name="a"><joint name="h1" axis="0 1 0" ref="0.2"/><geom size=".05" pos=".1 0 0"/>
        <body name="b" pos=".2 0 0"><joint name="h2" axis="0 1 0" ref="-0.1"/>
          <geom size=".05" pos=".1 0 0"/></body></body></worldbody>
      <equality><joint name="gear" joint1="h2" joint2="h1" polycoef="0.1 -0.5 0 0 0"/></equality>
    </mujoco>"""
    mj = mujoco.MjModel.from_xml_string(xml)
    m = pmd.from_mujoco(mj)
    assert m.ncouplings == 1 and m.couplings[0][:3] == ("gear", "b", "a")
    data = mujoco.MjData(mj)
    for qpos in ([0.2, -0.1], [0.7, 0.4], [-1.0, 2.0]):
        data.qpos[:] = qpos
        mujoco.mj_forward(mj, data)
        q, _ = pmd.io.mujoco_state(mj, np.array(qpos), np.zeros(2))
        assert abs(m.constraint_residual(q)[0] - data.efc_pos[0]) <= 1e-14
    nonlinear = xml.replace("0.1 -0.5 0 0 0", "0.1 -0.5 0.3 0 0")
    with pytest.warns(ModelImportWarning, match="nonlinear polycoef"):
        m = pmd.from_mujoco(mujoco.MjModel.from_xml_string(nonlinear))
    assert m.ncouplings == 0


def test_armature_invariants_on_a_tree_with_a_ball_joint():
    """FD(ID(a)) = a, the mass matrix's diagonal grows by exactly the armature, the explicit
    DeNOC path agrees and the kinetic energy is ½ vᵀ M v."""
    m = pmd.Model()
    body = pmd.RigidBody(1.0, [0.1, 0.02, 0], np.diag([0.01, 0.02, 0.03]))
    m.add_body(body, pmd.Revolute([0, 0, 1]), name="r")
    m.add_body(body, pmd.Spherical(), parent=0, translation=[0.3, 0, 0], name="s")
    m.add_body(body, pmd.Prismatic([1, 0, 0]), parent=1, translation=[0.3, 0, 0], name="p")
    rng = np.random.default_rng(5)
    q = np.r_[0.4, rng.normal(size=4), 0.1]
    q[1:5] /= np.linalg.norm(q[1:5])
    before = m.mass_matrix(q)
    m.set_armature("r", 0.2)
    m.set_armature("s", [0.01, 0.02, 0.03])
    m.set_armature(2, 0.5)
    assert np.array_equal(m.armature, [0.2, 0.01, 0.02, 0.03, 0.5])
    after = m.mass_matrix(q)
    assert np.abs(after - before - np.diag(m.armature)).max() <= 1e-15
    v, a = rng.normal(size=5), rng.normal(size=5)
    tau = m.inverse_dynamics(q, v, a, gravity=G)
    assert rel_err(m.forward_dynamics(q, v, tau, gravity=G), a) <= 1e-12
    assert rel_err(m.forward_dynamics(q, v, tau, gravity=G, method="denoc"), a) <= 1e-12
    assert abs(m.kinetic_energy(q, v) - 0.5 * v @ after @ v) <= 1e-14 * (v @ after @ v)
    m.set_armature("s", 0.0)  # back to none on that joint
    assert np.array_equal(m.armature, [0.2, 0, 0, 0, 0.5])


def test_pickle_keeps_couplings_and_armature():
    m = arm(0.5, 0.2, armature=(0.1, 0.3))
    back = pickle.loads(pickle.dumps(m))
    assert back.couplings == m.couplings and np.array_equal(back.armature, m.armature)
    q, v = np.array([0.3, 0.35]), np.array([1.0, 0.5])
    assert np.array_equal(back.forward_dynamics(q, v, [0.1, 0.2]), m.forward_dynamics(q, v, [0.1, 0.2]))


# ------------------------------------------------------------------------------- errors


def chain3():
    m = pmd.Model()
    body = pmd.RigidBody(1.0, [0.1, 0, 0], np.diag([0.01, 0.01, 0.01]))
    m.add_body(body, pmd.Revolute(Z), name="a")
    m.add_body(body, pmd.Revolute(Z), parent=0, translation=[0.2, 0, 0], name="b")
    m.add_body(body, pmd.Spherical(), parent=1, translation=[0.2, 0, 0], name="ball")
    m.add_body(body, pmd.Fixed(), parent=2, translation=[0.2, 0, 0], name="welded")
    m.add_body(body, pmd.Prismatic([1, 0, 0]), parent=2, name="slider")
    return m


@pytest.mark.parametrize(
    "args,kwargs,match",
    [
        (("a", "a"), {}, r"reference: expected a joint other than `joint`.*'a' for both"),
        (("a", "nope"), {}, r"reference: expected a moving joint's name or its body's name.*got 'nope'"),
        (("a", 17), {}, r"reference: expected a body index 0\.\.5.*got 17"),
        (("a", "b"), {"ratio": float("nan")}, r"ratio: expected a finite number, got NaN"),
        (("a", "b"), {"offset": float("inf")}, r"offset: expected a finite number, got inf"),
        (("ball", "a"), {}, r"joint: expected a revolute or prismatic \(1-dof\) joint.*Spherical"),
        (("a", "welded"), {}, r"reference: expected a revolute or prismatic.*Fixed"),
    ],
)
def test_bad_couplings_are_refused(args, kwargs, match):
    m = chain3()
    with pytest.raises(InvalidInputError, match=match):
        m.add_coupling(*args, **kwargs)
    assert m.ncouplings == 0


def test_cycles_and_double_couplings_are_refused():
    m = chain3()
    m.add_coupling("a", "b", ratio=2.0)
    with pytest.raises(InvalidInputError, match=r"reference: .*cycle of couplings 'b' → 'a' → 'b'"):
        m.add_coupling("b", "a")
    m.add_coupling("slider", "a", ratio=0.1)
    with pytest.raises(InvalidInputError, match=r"cycle of couplings 'b' → 'slider' → 'a' → 'b'"):
        m.add_coupling("b", "slider")
    with pytest.raises(InvalidInputError, match=r"joint: expected a joint not yet coupled.*'a'"):
        m.add_coupling("a", "slider")
    assert m.ncouplings == 2


@pytest.mark.parametrize(
    "joint,value,match",
    [
        ("a", -0.1, r"value: expected finite numbers >= 0, got -0.1 at index 0"),
        ("a", float("nan"), r"value: expected finite numbers >= 0, got NaN"),
        ("ball", [0.1, 0.2], r"value: expected one number, or 3.*got 2 numbers"),
        ("welded", 0.1, r"joint: expected a body on a moving joint.*'welded' on a fixed joint"),
        ("nope", 0.1, r"joint: expected a moving joint's name or its body's name.*'nope'"),
    ],
)
def test_bad_armature_is_refused(joint, value, match):
    m = chain3()
    with pytest.raises(InvalidInputError, match=match):
        m.set_armature(joint, value)
    assert not np.any(m.armature)


def test_armature_on_a_free_flyer_is_refused():
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0, 0, 0], np.eye(3) * 0.01), pmd.FreeFlyer(), name="base")
    with pytest.raises(InvalidInputError, match=r"joint: expected a revolute, prismatic or spherical"):
        m.set_armature("base", 0.1)


def test_derivatives_of_coupled_models_are_refused_by_name():
    m = arm(0.5, 0.2)
    with pytest.raises(InvalidInputError, match=r"model: expected a tree .*1 coupling"):
        m.forward_dynamics_derivatives([0.3, 0.35], [0, 0], [0, 0])


def test_to_mjcf_writes_armature_and_refuses_couplings():
    mujoco = pytest.importorskip("mujoco")
    m = arm(0.5, 0.2)
    with pytest.raises(pmd.errors.ModelStructureError, match=r"1 coupling\(s\): not supported"):
        pmd.to_mjcf(m)
    m = chain3()
    m.set_armature("a", 0.3)
    m.set_armature("ball", 0.02)
    mj = mujoco.MjModel.from_xml_string(pmd.to_mjcf(m, gravity=G))
    rng = np.random.default_rng(6)
    q = np.r_[rng.normal(size=2), [0.1, 0.2, 0.3, 0.9] / np.linalg.norm([0.1, 0.2, 0.3, 0.9]), 0.05]
    v, tau = rng.normal(size=m.nv), rng.normal(size=m.nv)
    d = mujoco.MjData(mj)
    d.qpos[:], d.qvel[:] = pmd.io.to_mujoco_state(m, q, v)
    perm = [j.v for j in pmd.io.layout(m).joints]
    d.qfrc_applied[:] = tau  # every joint here is revolute/ball/slide in our v order
    mujoco.mj_forward(mj, d)
    a = m.forward_dynamics(q, v, tau, gravity=G)
    assert perm == [0, 1, 2, 5] and rel_err(a, d.qacc) <= 1e-10
    m.set_armature("ball", [0.01, 0.02, 0.03])
    with pytest.raises(pmd.errors.ModelStructureError, match=r"armature .* differs by axis"):
        pmd.to_mjcf(m)


def test_urdf_mimic_cycles_are_errors_and_unknown_references_warn(tmp_path):
    cyclic = GRIPPER.replace(
        '<limit lower="-1" upper="1" effort="10" velocity="5"/></joint>',
        '<limit lower="-1" upper="1" effort="10" velocity="5"/>'
        '<mimic joint="c_finger_b" multiplier="2"/></joint>',
        1,
    )
    path = tmp_path / "cyclic.urdf"
    path.write_text(cyclic)
    with pytest.raises(pmd.errors.UrdfError, match=r"joint 'c_finger_b' <mimic>.*cycle of couplings"):
        pmd.Model.from_urdf(str(path))
    path.write_text(GRIPPER.replace('mimic joint="b_finger_a" multiplier="-1"', 'mimic joint="nope" multiplier="-1"'))
    with pytest.warns(pmd.errors.UrdfWarning, match=r"of unknown joints: 'c_finger_b' \(mimics 'nope'\)"):
        m = pmd.Model.from_urdf(str(path))
    assert [c[0] for c in m.couplings] == ["d_tip_a"]
