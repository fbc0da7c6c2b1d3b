"""`pmd.to_mjcf` and the state conversions of `pointmass_dyn.io`, checked against MuJoCo
itself: MuJoCo's `mj_forward` acceleration of the exported model equals our forward dynamics
(with the scene's effects) on every bundled tree scene and on random trees of every joint
type, and MuJoCo's own kinematics (body poses, velocities) agree with ours through the state
conversion."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import build_model, random_state, random_tree, record
from pointmass_dyn import io as mjcf
from pointmass_dyn.benchmarking import scene_rhs
from pointmass_dyn.errors import InvalidInputError, ModelStructureError

mujoco = pytest.importorskip("mujoco")

TREE_SCENES = ["chain7", "panda", "pendulum_spatial", "pendulum_planar", "satellite",
               "chain_stiff"]


def load(xml: str):
    m = mujoco.MjModel.from_xml_string(xml)
    return m, mujoco.MjData(m)


def qacc_gap(scene, rng, n=6, scale=0.4, initial=True):
    """Worst relative gap between MuJoCo's qacc and ours over random states (and the scene's
    initial state if ``initial``)."""
    m, d = load(pmd.to_mjcf(scene))
    model = scene.model
    rhs = scene_rhs(scene)
    worst = 0.0
    for k in range(n):
        q, v = np.array(scene.q0), np.array(scene.v0)
        if k or not initial:
            q, v = random_state(model, rng)
            v *= 2 * scale
        a = rhs(0.0, np.concatenate([q, v]))[model.nq:]
        qpos, qvel = mjcf.to_mujoco_state(model, q, v)
        d.qpos[:], d.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, d)
        want = mjcf.to_mujoco_acceleration(model, q, v, a)
        worst = max(worst, np.max(np.abs(d.qacc - want)) / max(np.max(np.abs(want)), 1e-300))
    return worst


@pytest.mark.parametrize("name", TREE_SCENES)
def test_bundled_scene_qacc_equals_mujoco(name):
    rng = np.random.default_rng(7)
    gap = record(f"mjcf {name}: max |qacc_mj - ours| / max|ours|",
                 qacc_gap(pmd.load_scene(name), rng))
    assert gap <= 1e-10


def random_scene(seed: int, effects: bool = True) -> pmd.Scene:
    """A random tree with every joint type (FreeFlyer bodies hung from the world, as MuJoCo
    requires), not added depth first, with gravity, springs and dampers where MuJoCo has
    them."""
    tree = random_tree(seed, n=10, kinds=("Revolute", "Prismatic", "Spherical", "SphericalZYZ",
                                          "FreeFlyer", "Fixed"), dfs=False)
    for b in tree.bodies:
        if b.kind == "FreeFlyer":
            b.parent = -1
    model = build_model(tree)
    rng = np.random.default_rng(seed + 1000)
    names = [f"b{k}" for k, b in enumerate(tree.bodies)]
    sprung = [n for n, b in zip(names, tree.bodies) if b.kind in ("Revolute", "Prismatic")]
    balls = [n for n, b in zip(names, tree.bodies) if b.kind == "Spherical"]
    damped = [n for n, b in zip(names, tree.bodies) if b.kind not in ("Fixed", "SphericalZYZ")]
    eff = [pmd.Gravity(rng.normal(size=3) * 5)]
    if effects:
        eff.append(pmd.Spring(sprung, stiffness=rng.uniform(1, 50, len(sprung)),
                              rest=rng.uniform(-1, 1, len(sprung))))
        if balls:
            eff.append(pmd.Spring(balls, stiffness=rng.uniform(1, 50, len(balls))))
        eff.append(pmd.Damper(damped, damping=rng.uniform(0.1, 3, len(damped))))
    return pmd.Scene(model, effects=eff, name=f"random{seed}")


@pytest.mark.parametrize("seed", range(6))
def test_random_trees_qacc_equal_mujoco(seed):
    scene = random_scene(seed)
    kinds = {scene.model.body_info(i)[1] for i in range(scene.model.nbodies)}
    assert kinds == {"Revolute", "Prismatic", "Spherical", "SphericalZYZ", "FreeFlyer", "Fixed"}
    gap = qacc_gap(scene, np.random.default_rng(seed), initial=False)
    record("mjcf random trees: max |qacc_mj - ours| / max|ours|", gap)
    assert gap <= 1e-10


@pytest.mark.parametrize("seed", range(3))
def test_random_tree_kinematics_equal_mujoco(seed):
    """Body poses and velocities: MuJoCo's xpos/xmat and cvel against ours (placements and a
    finite difference of them), through the state conversion."""
    scene = random_scene(seed, effects=False)
    model = scene.model
    m, d = load(pmd.to_mjcf(scene))
    rng = np.random.default_rng(seed)
    q, v = random_state(model, rng)
    d.qpos[:], d.qvel[:] = mjcf.to_mujoco_state(model, q, v)
    mujoco.mj_forward(m, d)
    rots, origins = model.placements(q)
    order = mjcf.layout(model).order          # MuJoCo body k + 1 is our body order[k]
    for k, b in enumerate(order):
        np.testing.assert_allclose(d.xpos[k + 1], origins[b], atol=1e-12)
        np.testing.assert_allclose(d.xmat[k + 1].reshape(3, 3), rots[b], atol=1e-12)
    # Velocity of each body origin: ours by a central difference along (q, v).
    h = 1e-6
    qd = model.velocity_to_qdot(q, v)
    _, op = model.placements(q + h * qd)
    _, om = model.placements(q - h * qd)
    lin = np.empty((model.nbodies, 6))
    for k, b in enumerate(order):
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_XBODY, k + 1, lin[b], 0)
    np.testing.assert_allclose(lin[:, 3:], (op - om) / (2 * h), atol=1e-7)


@pytest.mark.parametrize("seed", range(3))
def test_state_round_trip(seed):
    scene = random_scene(seed, effects=False)
    model = scene.model
    rng = np.random.default_rng(seed)
    states = [random_state(model, rng) for _ in range(5)]
    q = np.array([s[0] for s in states])
    v = np.array([s[1] for s in states])
    qpos, qvel = mjcf.to_mujoco_state(model, q, v)
    assert qpos.shape == (5, mjcf.layout(model).nq)
    q2, v2 = mjcf.from_mujoco_state(model, qpos, qvel, q_like=q)
    np.testing.assert_allclose(q2, q, atol=1e-12)
    np.testing.assert_allclose(v2, v, atol=1e-10)
    # One state at a time gives the same as the batch.
    p0, v0 = mjcf.to_mujoco_state(model, q[0], v[0])
    np.testing.assert_allclose(p0, qpos[0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(v0, qvel[0], rtol=0, atol=1e-14)


def test_zyz_branch_and_quaternion_sign_follow_q_like():
    model = pmd.Model()
    model.add_body(pmd.RigidBody(1.0, [0.3, 0, 0], np.diag([0.01, 0.02, 0.02])),
                   pmd.SphericalZYZ(), name="rod")
    q = np.array([2.5, -0.7, -3.0])     # θ < 0: the other branch of the same rotation
    v = np.array([0.3, -0.2, 0.5])
    qpos, qvel = mjcf.to_mujoco_state(model, q, v)
    qa, va = mjcf.from_mujoco_state(model, qpos, qvel)
    assert 0 <= qa[1] <= np.pi           # default branch
    ra, _ = model.placements(qa)
    rb, _ = model.placements(q)
    np.testing.assert_allclose(ra, rb, atol=1e-14)
    np.testing.assert_allclose(mjcf.to_mujoco_state(model, qa, va)[1], qvel, atol=1e-14)
    qb, vb = mjcf.from_mujoco_state(model, qpos, qvel, q_like=q + 2 * np.pi)
    np.testing.assert_allclose(qb, q + 2 * np.pi, atol=1e-12)
    np.testing.assert_allclose(vb, v, atol=1e-12)


def test_mujoco_rk4_follows_our_trajectory():
    """Integrating the exported pendulum_spatial with MuJoCo's RK4 at a small step lands on
    our simulate's state (a ZYZ joint as a ball joint, Euler rates as angular velocity)."""
    scene = pmd.load_scene("pendulum_spatial")
    model = scene.model
    m, d = load(pmd.to_mjcf(scene, timestep=1e-3, integrator="RK4"))
    d.qpos[:], d.qvel[:] = mjcf.to_mujoco_state(model, scene.q0, scene.v0)
    for _ in range(500):
        mujoco.mj_step(m, d)
    ours = pmd.simulate(scene, (0.0, 0.5), rtol=1e-12, atol=1e-12)
    q, v = mjcf.from_mujoco_state(model, d.qpos, d.qvel, q_like=ours.q[-1])
    assert abs(d.time - 0.5) < 1e-12
    np.testing.assert_allclose(q, ours.q[-1], atol=1e-9)
    np.testing.assert_allclose(v, ours.v[-1], atol=1e-8)


def test_mjcf_text():
    scene = pmd.load_scene("chain_stiff")
    xml = pmd.to_mjcf(scene, timestep=5e-4, integrator="implicitfast")
    assert 'integrator="implicitfast"' in xml and 'timestep="0.0005"' in xml
    assert '<flag contact="disable"/>' in xml
    assert xml.count('stiffness="600.0"') == 4 and xml.count('damping="300.0"') == 4
    m, _ = load(xml)
    assert m.nq == 5 and m.nv == 5
    np.testing.assert_array_equal(m.opt.gravity, [0, 0, -9.81])
    np.testing.assert_array_equal(m.jnt_stiffness, [0, 600, 600, 600, 600])
    np.testing.assert_array_equal(m.dof_damping, [0, 300, 300, 300, 300])
    # A bare model: gravity as given, no effects.
    bare = pmd.to_mjcf(scene.model, gravity=[0, 0, -1.0])
    assert "stiffness" not in bare and 'gravity="0.0 0.0 -1.0"' in bare


def test_refusals_name_the_problem():
    with pytest.raises(ModelStructureError, match="loop"):
        pmd.to_mjcf(pmd.load_scene("fourbar"))
    chain = pmd.load_scene("chain7")
    for eff, words in [
        (pmd.JointFriction("link0", friction=0.2, v_eps=1e-3), "JointFriction"),
        (pmd.ExternalForce("link0", [0, 0, 1.0]), "External"),  # a JointTorque is a motor now
    ]:
        with pytest.raises(InvalidInputError, match=words):
            pmd.to_mjcf(chain.replace(effects=[*chain.effects, eff]))
    # ...unless disabled, then it is left out.
    with_friction = pmd.Scene(chain.model, effects=[*chain.effects,
                                                    pmd.JointFriction("link0", 0.2)],
                              disable="friction")
    assert "friction" not in pmd.to_mjcf(with_friction)
    # A damper on a ZYZ joint damps Euler rates: no MuJoCo counterpart.
    zyz = pmd.load_scene("pendulum_spatial")
    with pytest.raises(InvalidInputError, match="Euler rates"):
        pmd.to_mjcf(zyz.replace(effects=[pmd.Damper(None, 0.1)]))
    # A quaternion spring resting away from the identity.
    ball = pmd.Model()
    ball.add_body(pmd.RigidBody(1.0, [0.3, 0, 0], np.diag([0.01, 0.02, 0.02])),
                  pmd.Spherical(), name="b")
    off = pmd.Scene(ball, effects=[pmd.Spring("b", 5.0, rest=[0, 0, np.sin(0.3), np.cos(0.3)])])
    with pytest.raises(InvalidInputError, match="identity"):
        pmd.to_mjcf(off)
    # A free joint below a moving body.
    fm = pmd.Model()
    fm.add_body(pmd.RigidBody(1.0, [0, 0, 0], np.eye(3) * 0.1), pmd.Revolute([0, 0, 1]), name="a")
    fm.add_body(pmd.RigidBody(1.0, [0, 0, 0], np.eye(3) * 0.1), pmd.FreeFlyer(), parent=0,
                name="f")
    with pytest.raises(ModelStructureError, match="top level|world"):
        pmd.to_mjcf(fm)
    with pytest.raises(InvalidInputError, match="integrator"):
        pmd.to_mjcf(chain, integrator="RK45")
    with pytest.raises(InvalidInputError, match="timestep"):
        pmd.to_mjcf(chain, timestep=0)
    with pytest.raises(InvalidInputError, match="gravity"):
        pmd.to_mjcf(chain, gravity=[0, 0, -1])
    with pytest.raises(InvalidInputError, match="model_or_scene"):
        pmd.to_mjcf("chain7")
    with pytest.raises(InvalidInputError, match=r"q, v"):
        mjcf.to_mujoco_state(chain.model, np.zeros(3), np.zeros(7))


@pytest.mark.parametrize("name", ["chain7", "panda", "chain_stiff"])
def test_round_trip_through_from_mujoco(name):
    """Ours → MJCF → MuJoCo's compiler → ``pmd.from_mujoco`` (the importer, written
    independently) gives back the same dynamics (hinge models: the same coordinates)."""
    scene = pmd.load_scene(name)
    model = scene.model
    m = mujoco.MjModel.from_xml_string(pmd.to_mjcf(model))
    back = pmd.from_mujoco(m)
    assert (back.nq, back.nv) == (model.nq, model.nv)
    rng = np.random.default_rng(11)
    g = np.array([0.0, 0.0, -9.81])
    for _ in range(3):
        q, v = random_state(model, rng)
        tau = rng.normal(size=model.nv)
        a = model.forward_dynamics(q, v, tau, gravity=g)
        np.testing.assert_allclose(back.forward_dynamics(q, v, tau, gravity=g), a,
                                   rtol=1e-10, atol=1e-10 * np.max(np.abs(a)))
        np.testing.assert_allclose(back.mass_matrix(q), model.mass_matrix(q), rtol=1e-10,
                                   atol=1e-12)


def test_cached_state_maps_follow_each_model_against_mujoco():
    """The conversions keep per-model index maps: models called in turn (and a new model
    built after one was dropped) each get their own, checked against MuJoCo's kinematics of
    the exported model (body positions of ``mj_kinematics`` from qpos, and qpos back)."""
    rng = np.random.default_rng(7)
    for _ in range(2):
        scenes = [random_scene(s, effects=False) for s in (3, 11)] + [pmd.load_scene("panda")]
        for scene in scenes * 2:
            model = scene.model
            m, d = load(pmd.to_mjcf(scene))
            q, v = random_state(model, rng)
            d.qpos[:], d.qvel[:] = mjcf.to_mujoco_state(model, q, v)
            mujoco.mj_kinematics(m, d)
            q2, v2 = mjcf.from_mujoco_state(model, d.qpos, d.qvel, q_like=q)
            _, org = model.placements(q2)
            names = [model.body_info(i)[0] for i in range(model.nbodies)]
            for i, name in enumerate(names):
                bid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
                if bid >= 0:
                    np.testing.assert_allclose(org[i], d.xpos[bid], rtol=0, atol=1e-12)
            np.testing.assert_allclose(q2, q, rtol=0, atol=1e-12)
            np.testing.assert_allclose(v2, v, rtol=0, atol=1e-10)
        del scenes
