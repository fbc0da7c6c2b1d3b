"""Point-to-point spring–dampers (``pmd.PointSpring``) against things the law does not compute
itself: the potential ½ k (l − l0)² from the bodies' world placements, its gradient by central
differences (generalized force = −∂V/∂q) on random trees with ends on random bodies and the
world, l̇ by central differences along the motion, energy conservation without damping and the
loss ∫ c l̇² dt with it; plus the errors."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import KINDS, build_model, random_state, random_tree, record
from scipy.integrate import cumulative_simpson

TIGHT = dict(rtol=1e-12, atol=1e-12)


def retract(m, q, dv):
    """q moved by the speeds dv for unit time (first order), quaternions renormalised (a
    Spherical's q, a FreeFlyer's last four): enough for central differences, whose error
    stays O(h²)."""
    out = q + m.velocity_to_qdot(q, dv)
    for iq, _iv, nq, _nv in m.joint_slices():
        if nq in (4, 7):
            quat = slice(iq + nq - 4, iq + nq)
            out[quat] /= np.linalg.norm(out[quat])
    return out


def world_point(m, q, body, point):
    """The world position of ``point`` (body frame) of ``body`` (-1: the world)."""
    if body < 0:
        return np.asarray(point, float)
    rot, origin = m.placements(q)
    return rot[body] @ point + origin[body]


def length(m, q, spring):
    body_a, pa, body_b, pb = spring[:4]
    return np.linalg.norm(world_point(m, q, body_b, pb) - world_point(m, q, body_a, pa))


def potential(m, q, spring):
    k, l0 = spring[4], spring[5]
    return 0.5 * k * (length(m, q, spring) - l0) ** 2


def gradient(m, q, f, h=1e-6):
    """∂f/∂v_k by central differences along each speed."""
    e = np.eye(m.nv)
    return np.array([(f(retract(m, q, h * e[k])) - f(retract(m, q, -h * e[k]))) / (2 * h)
                     for k in range(m.nv)])


def random_springs(m, rng, n=4, damping=0.0):
    """``n`` springs (body_a, point_a, body_b, point_b, k, l0, c) between random bodies on
    different links, the world (-1) among them; the first always has a world end."""
    link = [m.body_info(b)[3] for b in range(m.nbodies)]  # -1: welded to the world
    out = []
    while len(out) < n:
        a = -1 if not out else int(rng.integers(-1, m.nbodies))
        b = int(rng.integers(0, m.nbodies))
        if (link[a] if a >= 0 else -1) == link[b]:
            continue
        k, l0 = rng.uniform(5.0, 50.0), rng.choice([0.0, rng.uniform(0.05, 0.5)])
        out.append((a, rng.uniform(-0.3, 0.3, 3), b, rng.uniform(-0.3, 0.3, 3), k, l0, damping))
    return out


def effects_of(springs):
    return [pmd.PointSpring(a, pa, b, pb, k, rest_length=l0, damping=c, name=f"ps{i}")
            for i, (a, pa, b, pb, k, l0, c) in enumerate(springs)]


# --------------------------------------------------------------------------------------------
# The law
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(6))
def test_force_is_minus_the_gradient_of_the_potential_on_random_trees(seed):
    rng = np.random.default_rng(100 + seed)
    m = build_model(random_tree(seed, n=9, kinds=(*KINDS, "FreeFlyer")))
    springs = random_springs(m, rng)
    scene = pmd.Scene(m, effects=effects_of(springs))
    q, v = random_state(m, rng)
    forces = pmd.effect_forces(scene, 0.0, q, v)
    energies = pmd.energies(scene, q, v)
    worst = 0.0
    for i, s in enumerate(springs):
        name = f"ps{i}"
        assert energies[name] == pytest.approx(potential(m, q, s), rel=1e-12, abs=1e-15)
        want = -gradient(m, q, lambda x, s=s: potential(m, x, s))
        scale = np.abs(want).max()
        assert scale > 1e-3, (s, want)
        err = np.abs(forces[name] - want).max() / scale
        worst = max(worst, err)
        assert err <= 1e-7, (seed, i, forces[name], want)
    record("point spring: |τ + ∂V/∂q| / |∂V/∂q| (random trees)", worst)


def test_force_is_minus_the_gradient_on_a_free_flyer():
    # A free body at the root (translation and quaternion coordinates) with an arm on a revolute joint:
    # springs from the world to each, and between them across the joint.
    m = pmd.Model()
    body = pmd.RigidBody(2.0, [0.05, -0.02, 0.1], np.diag([0.02, 0.03, 0.04]))
    m.add_body(body, pmd.FreeFlyer(), name="hull")
    m.add_body(body, pmd.Revolute([0, 1, 1]), parent=0, translation=[0.3, 0, 0], name="arm")
    springs = [
        (-1, np.array([0.5, 0.2, -0.3]), 0, np.array([0.1, 0.2, 0.0]), 30.0, 0.2, 0.0),
        (0, np.array([-0.2, 0.1, 0.1]), 1, np.array([0.2, 0.0, 0.1]), 12.0, 0.0, 0.0),
        (1, np.array([0.3, 0.0, 0.0]), -1, np.array([0.0, 0.0, 1.0]), 20.0, 0.4, 0.0),
    ]
    scene = pmd.Scene(m, effects=effects_of(springs))
    rng = np.random.default_rng(5)
    q = np.concatenate([rng.normal(scale=0.3, size=3), [0.1, -0.3, 0.2, 0.9], [0.7]])
    q[3:7] /= np.linalg.norm(q[3:7])
    forces = pmd.effect_forces(scene, 0.0, q, rng.normal(size=m.nv))
    for i, s in enumerate(springs):
        want = -gradient(m, q, lambda x, s=s: potential(m, x, s))
        assert np.abs(want).max() > 1e-2
        np.testing.assert_allclose(forces[f"ps{i}"], want, rtol=0, atol=1e-7 * np.abs(want).max())


@pytest.mark.parametrize("seed", range(3))
def test_damping_adds_c_ldot_along_the_line(seed):
    rng = np.random.default_rng(200 + seed)
    m = build_model(random_tree(seed, n=7))
    (spring,) = random_springs(m, rng, n=1)
    c = 0.7
    damped = (*spring[:6], c)
    q, v = random_state(m, rng)
    tau0 = pmd.effect_forces(pmd.Scene(m, effects=effects_of([spring])), 0.0, q, v)["ps0"]
    scene = pmd.Scene(m, effects=effects_of([damped]))
    tau = pmd.effect_forces(scene, 0.0, q, v)["ps0"]
    h = 1e-6
    l_dot = (length(m, retract(m, q, h * v), spring) - length(m, retract(m, q, -h * v), spring)) / (2 * h)
    grad_l = gradient(m, q, lambda x: length(m, x, spring))
    np.testing.assert_allclose(tau - tau0, -c * l_dot * grad_l, rtol=0,
                               atol=1e-7 * c * abs(l_dot) * np.abs(grad_l).max())
    # Its power: −(k (l − l0) + c l̇) l̇.
    k, l0 = spring[4], spring[5]
    stretch = length(m, q, spring) - l0
    power = pmd.effect_power(scene, 0.0, q, v)["ps0"]
    assert power == pytest.approx(-(k * stretch + c * l_dot) * l_dot, rel=1e-7)


# --------------------------------------------------------------------------------------------
# Energy
# --------------------------------------------------------------------------------------------
def swinging_scene(seed, damping):
    """A random tree without Euler-angle joints (no singularity stops the run), under
    gravity, with point springs between random bodies and the world."""
    rng = np.random.default_rng(300 + seed)
    kinds = ("Revolute", "Prismatic", "Spherical", "Fixed", "FreeFlyer")
    m = build_model(random_tree(seed, n=6, kinds=kinds))
    springs = random_springs(m, rng, n=3, damping=damping)
    q, v = random_state(m, rng, vscale=0.5)
    effects = [pmd.Gravity((0.0, 0.0, -9.81)), *effects_of(springs)]
    return pmd.Scene(m, q, v, effects=effects), springs


@pytest.mark.parametrize("seed", range(3))
def test_undamped_energy_is_conserved(seed):
    scene, _ = swinging_scene(seed, damping=0.0)
    r = pmd.simulate(scene, (0.0, 1.0), energy=True, **TIGHT)
    assert r.success, r.message
    parts = pmd.energies(scene, r.q[0], r.v[0])
    assert set(parts) == {"kinetic", "gravity", "ps0", "ps1", "ps2", "total"}
    scale = parts["kinetic"] + sum(abs(parts[f"ps{i}"]) for i in range(3))
    drift = np.abs(r.energy - r.energy[0]).max() / scale
    record("point spring: relative energy drift, undamped, 1 s at 1e-12", drift)
    assert drift <= 1e-9, drift
    # It is a real exchange: the springs' share changes by much more than the drift.
    v_end = sum(pmd.energies(scene, r.q[-1], r.v[-1])[f"ps{i}"] for i in range(3))
    v_start = sum(parts[f"ps{i}"] for i in range(3))
    assert abs(v_end - v_start) > 1e3 * drift * scale


@pytest.mark.parametrize("seed", range(2))
def test_damped_energy_loss_is_the_integral_of_c_ldot_squared(seed):
    scene, springs = swinging_scene(seed, damping=0.4)
    m = scene.model
    t = np.linspace(0.0, 1.0, 2001)
    r = pmd.simulate(scene, (0.0, 1.0), t_eval=t, energy=True, power=True, **TIGHT)
    assert r.success, r.message
    # −c l̇² at every output state, l̇ by central differences along the motion.
    h = 1e-6
    rate = np.zeros(len(t))
    for s in springs:
        c = s[6]
        for i, (q, v) in enumerate(zip(r.q, r.v)):
            l_dot = (length(m, retract(m, q, h * v), s) - length(m, retract(m, q, -h * v), s)) / (2 * h)
            rate[i] -= c * l_dot**2
    loss = cumulative_simpson(rate, x=r.t, initial=0.0)
    err = np.abs((r.energy - r.energy[0]) - loss).max()
    record("point spring: |E(t) - E(0) - ∫ -c l̇² dt| (J)", err)
    assert loss[-1] < -1e-3  # the dampers really take energy out
    assert err <= 1e-7 * abs(loss[-1]), (err, loss[-1])
    # The same from the recorded power: P_e + dV_e/dt summed over the point springs.
    v_springs = np.array([sum(pmd.energies(scene, q, v)[f"ps{i}"] for i in range(3))
                          for q, v in zip(r.q, r.v)])
    work = cumulative_simpson(sum(r.power[f"ps{i}"] for i in range(3)), x=r.t, initial=0.0)
    np.testing.assert_allclose(work + (v_springs - v_springs[0]), loss, rtol=0,
                               atol=1e-7 * abs(loss[-1]))


# --------------------------------------------------------------------------------------------
# Special cases and errors
# --------------------------------------------------------------------------------------------
def arm() -> pmd.Model:
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0.2, 0, 0], np.diag([0.01, 0.02, 0.02])), pmd.Revolute([0, 0, 1]),
               name="arm")
    return m


@pytest.mark.parametrize("rest_length, damping", [(0.1, 0.0), (0.0, 0.3)])
def test_a_run_stops_where_the_points_coincide(rest_length, damping):
    # A point on the arm's axis sits exactly on the world point: l = 0 from the start.
    spring = pmd.PointSpring("arm", [0, 0, 0.2], "world", [0, 0, 0.2], 10.0, rest_length, damping)
    scene = pmd.Scene(arm(), [0.3], [1.0], effects=[spring])
    r = pmd.simulate(scene, (0.0, 1.0))
    assert not r.success
    assert "coincide" in r.message and "'arm'" in r.message and "t = 0" in r.message, r.message
    assert np.all(np.isfinite(r.q)) and np.all(np.isfinite(r.v))
    with pytest.raises(pmd.PointMassDynError, match="coincide"):
        pmd.effect_forces(scene, 0.0, [0.3], [1.0])


def test_zero_rest_length_without_damping_is_minus_k_d_everywhere():
    # −k d is defined where the points meet: the arm's tip sweeps through the world point.
    tip = [0.5, 0.0, 0.0]
    spring = pmd.PointSpring("arm", tip, -1, [0.0, 0.5, 0.0], 10.0)
    scene = pmd.Scene(arm(), [np.pi / 2], [0.0], effects=[spring])
    assert pmd.effect_forces(scene, 0.0, [np.pi / 2], [0.0])["springs"] == pytest.approx([0.0], abs=1e-14)
    r = pmd.simulate(pmd.Scene(arm(), [0.0], [3.0], effects=[spring]), (0.0, 1.0), energy=True, **TIGHT)
    assert r.success and r.q[:, 0].max() > np.pi / 2
    assert np.abs(r.energy - r.energy[0]).max() <= 1e-9 * r.energy[0]


def test_python_errors_name_the_argument():
    ok = dict(point_a=[0, 0, 0], body_b="world", point_b=[1, 0, 0], stiffness=1.0)
    for kwargs, pattern in [
        (dict(stiffness=-1.0), r"^stiffness: expected a finite number >= 0, got -1$"),
        (dict(stiffness=np.nan), r"^stiffness: .*NaN"),
        (dict(rest_length=-0.1), r"^rest_length: expected a finite number >= 0"),
        (dict(damping=np.inf), r"^damping: expected a finite number >= 0, got inf"),
        (dict(point_a=[0, 0]), r"^point_a: expected shape \(3,\)"),
        (dict(point_b=[0, np.nan, 0]), r"^point_b: expected finite numbers"),
        (dict(body_b=-2), r"^body_b: expected .*-1 .* got -2"),
        (dict(body_b=True), r"^body_b: expected .* got True"),
        (dict(body_b=1.5), r"^body_b: expected .* got 1.5"),
        (dict(body_b="arm"), r"^body_b: expected a body other than body_a.*'arm' for both"),
    ]:
        with pytest.raises(pmd.InvalidInputError, match=pattern):
            pmd.PointSpring("arm", **{**ok, **kwargs})
    with pytest.raises(pmd.InvalidInputError, match=r"^body_b: .*the world for both"):
        pmd.PointSpring(None, [0, 0, 0], -1, [1, 0, 0], 1.0)
    with pytest.raises(pmd.InvalidInputError, match=r"^stiffness: expected real numbers, got a str"):
        pmd.PointSpring("arm", [0, 0, 0], "world", [1, 0, 0], "stiff")
    m = arm()
    m.add_body(pmd.RigidBody(0.1, [0, 0, 0], np.eye(3) * 1e-3), pmd.Fixed(), parent=0, name="tip")
    with pytest.raises(pmd.InvalidInputError, match=r"^effects\[0\]\.body_a: .*'arm', 'tip'.*got 'hand'"):
        pmd.Scene(m, effects=[pmd.PointSpring("hand", [0, 0, 0], -1, [1, 0, 0], 1.0)])
    with pytest.raises(pmd.InvalidInputError, match=r"^effects\[0\]\.body_b: .*body index 0\.\.2.*got 5"):
        pmd.Scene(m, effects=[pmd.PointSpring(-1, [0, 0, 0], 5, [1, 0, 0], 1.0)])
    with pytest.raises(pmd.InvalidInputError, match=r"^effects\[0\]\.body_b: .*'arm'.*'tip'.*welded"):
        pmd.Scene(m, effects=[pmd.PointSpring("arm", [0, 0, 0], "tip", [1, 0, 0], 1.0)])


def test_the_world_may_be_named_three_ways_and_either_end():
    m = arm()
    q, v = [0.4], [0.7]
    forces = [
        pmd.effect_forces(pmd.Scene(m, effects=[pmd.PointSpring(a, pa, b, pb, 20.0, 0.1, 0.3)]), 0.0, q, v)
        for a, pa, b, pb in [
            ("arm", [0.3, 0, 0], "world", [0.1, 0.4, 0]),
            (0, [0.3, 0, 0], -1, [0.1, 0.4, 0]),
            (None, [0.1, 0.4, 0], "arm", [0.3, 0, 0]),
        ]
    ]
    assert forces[0]["springs"][0] != 0.0
    for f in forces[1:]:
        assert f["springs"] == pytest.approx(forces[0]["springs"], rel=1e-14)


def test_scene_file_point_spring_equals_the_python_one(tmp_path):
    text = """
name = "arm"
[[body]]
name = "arm"
joint = { type = "Revolute", axis = [0, 0, 1] }
mass = 1.0
com = [0.2, 0, 0]
inertia_diag = [0.01, 0.02, 0.02]
q0 = [0.4]
v0 = [0.7]

[[effect]]
type = "point_spring"
body_a = "arm"
point_a = [0.3, 0, 0]
body_b = -1
point_b = [0.1, 0.4, 0]
stiffness = 20
rest_length = 0.1
damping = 0.3
name = "tendon"
"""
    path = tmp_path / "arm.toml"
    path.write_text(text, encoding="utf-8")
    scene = pmd.load_scene(path)
    want = pmd.PointSpring("arm", [0.3, 0, 0], "world", [0.1, 0.4, 0], 20.0, 0.1, 0.3, name="tendon")
    assert scene.effects == [want]
    assert repr(want) == (
        "PointSpring(body_a='arm', point_a=[0.3, 0, 0], body_b='world', point_b=[0.1, 0.4, 0], "
        "stiffness=20, rest_length=0.1, damping=0.3, name='tendon')"
    )
    assert want.kind == "springs" and want != pmd.PointSpring("arm", [0.3, 0, 0], "world", [0.1, 0.4, 0], 20.0)
    path.write_text(text.replace("damping = 0.3", "damping = -0.3"), encoding="utf-8")
    with pytest.raises(pmd.SceneError, match=r"effect\[0\]\.damping: expected a finite number >= 0, got -0.3"):
        pmd.load_scene(path)
    path.write_text(text.replace("rest_length", "rest"), encoding="utf-8")
    with pytest.raises(pmd.SceneError, match=r"effect\[0\]\.rest: .*rest_length, damping\), got an unknown key"):
        pmd.load_scene(path)
