"""Ground contact against closed forms: the static Hunt–Crossley penetration, the first
impact's energy bound, the Hunt–Crossley restitution relation, a box sliding down an incline
at g (sin θ − μ cos θ) and sticking below atan μ, energy that never grows, and the bundled
quadruped standing with its weight on its feet."""

from __future__ import annotations

import math

import numpy as np
import pointmass_dyn as pmd
import pytest
from scipy.optimize import brentq

G = 9.81


def ball(mass: float = 2.0, radius: float = 0.05) -> pmd.Model:
    """A sphere on a vertical slider (q = height of its centre)."""
    m = pmd.Model()
    m.add_body(
        pmd.RigidBody(mass, [0, 0, 0], np.eye(3) * 0.4 * mass * radius**2),
        pmd.Prismatic([0, 0, 1]),
        name="ball",
    )
    return m


def ball_scene(k, n, c, z0, v0=0.0, g=G, radius=0.05, mass=2.0):
    m = ball(mass, radius)
    effects = [pmd.GroundContact([("ball", [0, 0, 0], radius)], stiffness=k, exponent=n,
                                 damping=c, friction=0.0)]
    if g:
        effects.append(pmd.Gravity([0, 0, -g]))
    return pmd.Scene(m, q0=[z0], v0=[v0], effects=effects)


def test_ball_comes_to_rest_at_the_static_hunt_crossley_penetration():
    k, n, c, mass, r = 2e5, 1.5, 5e5, 2.0, 0.05
    res = pmd.simulate(ball_scene(k, n, c, 0.1), (0, 3), method="Radau", rtol=1e-8, atol=1e-10)
    res.raise_for_status()
    delta = r - res.q[-1, 0]
    expected = (mass * G / k) ** (1 / n)
    assert abs(res.v[-1, 0]) < 1e-6
    assert delta == pytest.approx(expected, rel=1e-5)


@pytest.mark.parametrize("c", [0.0, 3e5])
def test_first_impact_never_compresses_beyond_the_undamped_energy_bound(c):
    k, n, mass, r, drop = 2e5, 1.5, 2.0, 0.05, 0.05
    t = np.linspace(0, 0.15, 30001)
    res = pmd.simulate(ball_scene(k, n, c, r + drop), (0, 0.15), t_eval=t, method="Radau",
                       rtol=1e-10, atol=1e-12)
    res.raise_for_status()
    deepest = r - res.q[:, 0].min()
    # Undamped: k δ^(n+1)/(n+1) = m g (drop + δ).
    bound = brentq(lambda d: k * d ** (n + 1) / (n + 1) - mass * G * (drop + d), 1e-9, 0.1)
    assert deepest <= bound * (1 + 1e-6)
    if c == 0.0:
        assert deepest == pytest.approx(bound, rel=1e-4)  # sampled every 5 µs
    else:
        assert deepest < 0.95 * bound


@pytest.mark.parametrize("v_in", [0.5, 2.0])
def test_rebound_follows_the_hunt_crossley_restitution_relation(v_in):
    # Without gravity, m u du/dδ = −k δⁿ (1 + a u), a = c/k, integrates over a whole impact to
    # a v_in − ln(1 + a v_in) = −a v_out − ln(1 − a v_out): exact for this law.
    k, n, c, r = 1e5, 1.5, 2e4, 0.05
    a = c / k
    res = pmd.simulate(ball_scene(k, n, c, r + 1e-3, v0=-v_in, g=0.0), (0, 0.2),
                       method="Radau", rtol=1e-10, atol=1e-12)
    res.raise_for_status()
    v_out = res.v[-1, 0]
    assert res.q[-1, 0] > r  # separated
    lhs = a * v_in - math.log1p(a * v_in)
    expected = brentq(lambda w: -a * w - math.log1p(-a * w) - lhs, 1e-12, (1 - 1e-12) / a)
    assert v_out == pytest.approx(expected, rel=1e-6)
    assert v_out < v_in


def incline(theta_deg: float, mu: float = 0.3) -> pmd.Scene:
    """The bundled box on an incline of ``theta_deg`` (the scene file is at 30°)."""
    base = pmd.load_scene("box_incline")
    th = math.radians(theta_deg)
    k = 1e5
    depth = (G * math.cos(th) / 4 / k) ** (1 / 1.5)
    h = 0.05 - depth
    q0 = [h * math.sin(th), 0.0, h * math.cos(th), 0.0, math.sin(th / 2), 0.0, math.cos(th / 2)]
    corners = [("box", [sx * 0.1, sy * 0.05, -0.05]) for sx in (1, -1) for sy in (1, -1)]
    effects = [
        pmd.Gravity([0, 0, -G]),
        pmd.GroundContact(corners, normal=[math.sin(th), 0, math.cos(th)], stiffness=k,
                          damping=1e6, friction=mu, v_eps=5e-4),
    ]
    return pmd.Scene(base.model, q0=q0, effects=effects)


def test_bundled_incline_is_the_30_degree_scene():
    scene = pmd.load_scene("box_incline")
    ref = incline(30.0)
    np.testing.assert_allclose(scene.q0, ref.q0, rtol=0, atol=1e-15)


def test_box_slides_down_a_30_degree_incline_at_g_sin_minus_mu_cos():
    res = pmd.simulate(pmd.load_scene("box_incline"), t_eval=[0.5, 1.0])
    res.raise_for_status()
    # Body x is the downhill direction; v is in the body frame.
    accel = (res.v[1, 0] - res.v[0, 0]) / 0.5
    th = math.radians(30)
    expected = G * (math.sin(th) - 0.3 * math.cos(th))
    assert accel == pytest.approx(expected, rel=0.01)


def test_box_sticks_on_a_10_degree_incline():
    scene = incline(10.0)
    res = pmd.simulate(scene, (0, 1.0), method="Radau", rtol=1e-8, atol=1e-10, t_eval=[0, 1.0])
    res.raise_for_status()
    creep = np.linalg.norm(res.q[-1, :3] - res.q[0, :3])
    assert creep < 1e-3


@pytest.mark.parametrize("theta", [10.0, 30.0])
def test_friction_and_damping_never_add_energy(theta):
    # Total energy (kinetic + gravity + the contact's elastic potential) never grows.
    res = pmd.simulate(incline(theta), (0, 1.0), method="Radau", rtol=1e-9, atol=1e-11,
                       t_eval=np.linspace(0, 1, 401), energy=True)
    res.raise_for_status()
    growth = np.diff(res.energy)
    assert growth.max() <= 1e-7 * abs(res.energy).max()
    assert res.energy[-1] < res.energy[0]


def test_quadruped_stands_with_its_weight_on_its_feet():
    scene = pmd.load_scene("solo12_standing")
    res = pmd.simulate(scene, t_eval=[1.5, 2.0], contact=True)
    res.raise_for_status()
    feet = res.contact["contact"]
    model = scene.model
    mass = sum(model.body(i).mass for i in range(model.nbodies))
    weight = mass * G
    # Every foot on the ground, a few mm deep at most; the base at rest.
    assert np.all(feet.penetration[-1] > 0) and np.all(feet.penetration[-1] < 5e-3)
    assert np.abs(res.v[-1, :6]).max() < 1e-3
    assert feet.normal_force[-1].sum() == pytest.approx(weight, rel=5e-3)
    np.testing.assert_allclose(feet.total_force[-1], [0, 0, weight], rtol=0, atol=5e-3 * weight)


def test_contact_forces_are_reported_per_point():
    scene = ball_scene(2e5, 1.5, 1e5, 0.049)
    res = pmd.simulate(scene, (0, 0.01), t_eval=[0.0], contact=True)
    c = res.contact["contact"]
    assert c.position.shape == (1, 1, 3) and c.force.shape == (1, 1, 3)
    assert c.penetration[0, 0] == pytest.approx(1e-3)
    assert c.normal_force[0, 0] == pytest.approx(2e5 * 1e-3**1.5)
    assert pmd.simulate(scene, (0, 0.01)).contact is None


def test_contact_refusals_name_the_argument():
    pts = [("ball", [0, 0, 0])]
    for kwargs, arg in [
        (dict(stiffness=-1.0, damping=0.0, friction=0.0), "stiffness"),
        (dict(stiffness=1.0, damping=-1.0, friction=0.0), "damping"),
        (dict(stiffness=1.0, damping=0.0, friction=-0.1), "friction"),
        (dict(stiffness=1.0, damping=0.0, friction=0.1, v_eps=0.0), "v_eps"),
        (dict(stiffness=1.0, damping=0.0, friction=0.1, normal=[0, 0, 0]), "normal"),
    ]:
        with pytest.raises(pmd.InvalidInputError, match=arg):
            pmd.GroundContact(pts, **kwargs)
    e = pmd.GroundContact([("toe", [0, 0, 0])], stiffness=1.0, damping=0.0, friction=0.0)
    with pytest.raises(pmd.InvalidInputError, match=r"points\[0\].*toe"):
        pmd.Scene(ball(), effects=[e])
    with pytest.raises(pmd.InvalidInputError, match=r"points"):
        pmd.GroundContact("ball", stiffness=1.0, damping=0.0, friction=0.0)


def test_urdf_contact_points_take_spheres_and_link_origins(tmp_path):
    urdf = tmp_path / "r.urdf"
    urdf.write_text(
        """<robot name="r"><link name="base"/>
        <link name="foot"><collision><origin xyz="0 0 -0.1"/><geometry><sphere radius="0.02"/></geometry></collision></link>
        <joint name="j" type="fixed"><parent link="base"/><child link="foot"/></joint></robot>"""
    )
    assert pmd.urdf_contact_points(urdf, ["foot", "base"]) == [
        ("foot", [0.0, 0.0, -0.1], 0.02),
        ("base", [0.0, 0.0, 0.0], 0.0),
    ]
    with pytest.raises(pmd.InvalidInputError, match=r"links\[0\]"):
        pmd.urdf_contact_points(urdf, ["hand"])


def _quat_mul(a, b):
    (ax, ay, az, aw), (bx, by, bz, bw) = a, b
    return np.array([aw * bx + bw * ax + ay * bz - az * by, aw * by + bw * ay + az * bx - ax * bz,
                     aw * bz + bw * az + ax * by - ay * bx, aw * bw - ax * bx - ay * by - az * bz])


def _step(q, d):
    """q ⊕ d for a free-flyer root then 1-dof joints (solo12): body-frame right perturbation."""
    out = np.array(q, float)
    x, y, z, w = q[3:7]
    rot = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                    [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                    [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    out[:3] += rot @ d[:3]
    angle = np.linalg.norm(d[3:6])
    axis = d[3:6] / angle if angle > 0 else np.zeros(3)
    out[3:7] = _quat_mul(q[3:7], np.r_[axis * math.sin(angle / 2), math.cos(angle / 2)])
    out[7:] += d[6:]
    return out


def test_quadruped_derivatives_in_contact_are_analytic_and_match_central_differences():
    scene = pmd.load_scene("solo12_standing")
    model = scene.model
    res = pmd.simulate(scene, t_eval=[0.12])  # just after landing: sliding a little, damped
    q, v = res.q[0], res.v[0] + 0.01  # every foot moving, so friction is off its symmetric point
    feet = pmd.contact_forces(scene, type("R", (), {"q": q[None], "v": v[None]})())["contact"]
    assert np.all(feet.normal_force > 0)
    r = scene.forward_dynamics_derivatives(q, v, t=0.12)
    assert r["numerical"] == []

    def qdd(x, vv):
        return model.forward_dynamics(x, vv, sum(pmd.effect_forces(scene, 0.12, x, vv).values()))

    h = 1e-7
    eye = np.eye(model.nv)
    num_q = np.column_stack([(qdd(_step(q, h * e), v) - qdd(_step(q, -h * e), v)) / (2 * h)
                             for e in eye])
    num_v = np.column_stack([(qdd(q, v + h * e) - qdd(q, v - h * e)) / (2 * h) for e in eye])
    scale_q, scale_v = np.abs(num_q).max(), np.abs(num_v).max()
    assert np.abs(r["dq"] - num_q).max() < 1e-5 * scale_q
    assert np.abs(r["dv"] - num_v).max() < 1e-5 * scale_v


def test_contact_describes_itself_and_takes_per_run_stiffness():
    e = pmd.GroundContact([("ball", [0, 0, 0], 0.05)], stiffness=2e5, damping=5e5, friction=0.0)
    assert (e.kind, e.name) == ("contact", "contact")
    assert repr(e).startswith("GroundContact(1 points, normal=[0, 0, 1], height=0, stiffness=200000,")
    limit = pmd.JointLimit("arm", -1.0, 1.0, stiffness=10.0, damping=0.0, name="stop")
    assert (limit.kind, repr(limit)) == ("limits", "JointLimit(joints=['arm'], bounds=given, name='stop')")
    assert repr(pmd.JointLimit(stiffness=1.0, damping=0.0)) == "JointLimit(joints=all, bounds=the model's)"
    # Per-run stiffness in a batch: each run rests at its own (m g / k)^(1/n).
    ks = np.array([1e5, 4e5])
    out = pmd.simulate_batch(ball_scene(2e5, 1.5, 5e5, 0.1), (0, 3), params={"contact.stiffness": ks},
                             method="Radau", rtol=1e-8, atol=1e-10)
    for k, res in zip(ks, out.results):
        res.raise_for_status()
        assert 0.05 - res.q[-1, 0] == pytest.approx((2.0 * G / k) ** (1 / 1.5), rel=1e-5)
    with pytest.raises(pmd.InvalidInputError, match="stiffness"):
        e.with_parameter("stiffness", -1.0)
