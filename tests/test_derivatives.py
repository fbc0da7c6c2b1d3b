"""Analytic derivatives of the dynamics (docs/derivatives.md) against Pinocchio's
computeRNEADerivatives / computeABADerivatives (random trees with every joint kind, Panda,
floating URDF robots), against central differences of our own dynamics (whose error must
shrink as h²), and, with effects, against central differences of the scene's accelerations;
the state Jacobian against central differences of the right-hand side."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import (
    KINDS,
    G,
    build_model,
    build_pinocchio,
    moving_kinds,
    quat_to_matrix,
    random_state,
    random_tree,
    record,
    rel_err,
)

pin = pytest.importorskip("pinocchio")

TOL = 1e-8
ALL_KINDS = (*KINDS, "FreeFlyer")


def sym(m):
    m = np.array(m)
    return np.triu(m) + np.triu(m, 1).T


def pin_derivatives(pm, pd, q, v, a, tau):
    rq, rv, ra = (x.copy() for x in pin.computeRNEADerivatives(pm, pd, q, v, a))
    fq, fv, ft = (x.copy() for x in pin.computeABADerivatives(pm, pd, q, v, tau))
    return (rq, rv, sym(ra)), (fq, fv, sym(ft))


def compare(model, pm, q, v, a, tau, g, label):
    pd = pm.createData()
    (rq, rv, ra), (fq, fv, ft) = pin_derivatives(pm, pd, q, v, a, tau)
    dq, dv, m = model.inverse_dynamics_derivatives(q, v, a, g)
    fdq, fdv, minv = model.forward_dynamics_derivatives(q, v, tau, g)
    errs = {
        "dtau/dq": rel_err(dq, rq),
        "dtau/dv": rel_err(dv, rv),
        "dtau/da": rel_err(m, ra),
        "dqdd/dq": rel_err(fdq, fq),
        "dqdd/dv": rel_err(fdv, fv),
        "dqdd/dtau": rel_err(minv, ft),
    }
    for k, e in errs.items():
        record(f"derivatives vs pinocchio {label}: {k}", e)
    bad = {k: e for k, e in errs.items() if not e <= TOL}
    assert not bad, bad


@pytest.mark.parametrize("seed", range(8))
def test_random_trees_match_pinocchio(seed):
    tree = random_tree(seed, 12, kinds=ALL_KINDS)
    assert set(tree.kinds()) == set(ALL_KINDS)
    model = build_model(tree)
    pm, _ = build_pinocchio(tree, G)
    rng = np.random.default_rng(seed + 5)
    q, v = random_state(model, rng)
    a, tau = rng.normal(size=model.nv), rng.normal(size=model.nv)
    compare(model, pm, q, v, a, tau, G, "random trees")


@pytest.mark.parametrize(
    "kind", ["Revolute", "Prismatic", "Spherical", "SphericalZYZ", "FreeFlyer"]
)
def test_single_kind_chains_match_pinocchio(kind):
    """Every joint kind on its own (ZYZ: configuration-dependent columns, mirrored as
    revolutes Z, Y, Z), the base joint included."""
    tree = random_tree(3, 6, kinds=(kind,))
    model = build_model(tree)
    pm, _ = build_pinocchio(tree, G)
    rng = np.random.default_rng(11)
    q, v = random_state(model, rng)
    compare(model, pm, q, v, rng.normal(size=model.nv), rng.normal(size=model.nv), G, kind)


def test_panda_matches_pinocchio():
    from test_pinocchio import model_from_pinocchio, panda_urdf

    pm = pin.buildModelFromUrdf(panda_urdf())
    pm.gravity.linear = G
    model = model_from_pinocchio(pm)
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = pin.randomConfiguration(pm)
        v, a, tau = (rng.normal(size=pm.nv) for _ in range(3))
        compare(model, pm, q, v, a, tau, G, "panda")


def test_floating_robots_match_pinocchio(floating_robot):
    """URDF robots on a free-flyer root (talos, g1, solo12, a1 from example-robot-data)."""
    name, model, pm = floating_robot
    rng = np.random.default_rng(5)
    q = pin.randomConfiguration(pm, -np.ones(pm.nq), np.ones(pm.nq))
    v, a, tau = (rng.normal(size=pm.nv) for _ in range(3))
    compare(model, pm, q, v, a, tau, pm.gravity.linear.copy(), name)


# ---------------------------------------------------------------------------------------------
# Against our own dynamics: central differences in the tangent space
# ---------------------------------------------------------------------------------------------


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array(
        [
            aw * bx + bw * ax + ay * bz - az * by,
            aw * by + bw * ay + az * bx - ax * bz,
            aw * bz + bw * az + ax * by - ay * bx,
            aw * bw - ax * bx - ay * by - az * bz,
        ]
    )


def quat_exp(d):
    t = np.linalg.norm(d)
    if t == 0:
        return np.array([0.0, 0.0, 0.0, 1.0])
    return np.concatenate([np.sin(t / 2) * d / t, [np.cos(t / 2)]])


def integrate(model, q, d):
    """q ⊕ δ: quaternion joints q ⊗ exp(δ) (a free flyer's origin moves by R δ_lin)."""
    out = np.array(q, float)
    for kind, (iq, iv, nq, nv) in zip(moving_kinds(model), model.joint_slices()):
        if kind == "Spherical":
            out[iq : iq + 4] = quat_mul(q[iq : iq + 4], quat_exp(d[iv : iv + 3]))
        elif kind == "FreeFlyer":
            out[iq : iq + 3] += quat_to_matrix(q[iq + 3 : iq + 7]) @ d[iv : iv + 3]
            out[iq + 3 : iq + 7] = quat_mul(q[iq + 3 : iq + 7], quat_exp(d[iv + 3 : iv + 6]))
        else:
            out[iq : iq + nq] += d[iv : iv + nv]
    return out


def central_dq(model, f, q, h):
    cols = []
    for e in np.eye(model.nv):
        cols.append((f(integrate(model, q, h * e)) - f(integrate(model, q, -h * e))) / (2 * h))
    return np.column_stack(cols)


def test_central_differences_converge_as_h_squared():
    """The truncation error of central differences of our forward and inverse dynamics
    against the analytic derivatives falls by 4 when h halves (so the analytic value is the
    limit), on a tree with every joint kind."""
    tree = random_tree(2, 10, kinds=ALL_KINDS)
    model = build_model(tree)
    rng = np.random.default_rng(8)
    q, v = random_state(model, rng)
    a, tau = rng.normal(size=model.nv), rng.normal(size=model.nv)
    dq, _, _ = model.inverse_dynamics_derivatives(q, v, a, G)
    fq, _, _ = model.forward_dynamics_derivatives(q, v, tau, G)
    for exact, f in [
        (dq, lambda x: model.inverse_dynamics(x, v, a, G)),
        (fq, lambda x: model.forward_dynamics(x, v, tau, G)),
    ]:
        errs = [np.abs(central_dq(model, f, q, h) - exact).max() for h in (4e-3, 2e-3, 1e-3)]
        ratios = [errs[0] / errs[1], errs[1] / errs[2]]
        record("derivatives: central-difference error ratio per halving (h²: 4)", min(ratios))
        assert all(3.5 < r < 4.5 for r in ratios), (errs, ratios)


def test_velocity_derivatives_and_inverse_mass_matrix():
    """∂/∂v against central differences (exact for the quadratic velocity terms up to
    rounding), and ∂q̈/∂τ = M⁻¹ against the mass matrix."""
    tree = random_tree(6, 10, kinds=ALL_KINDS)
    model = build_model(tree)
    rng = np.random.default_rng(9)
    q, v = random_state(model, rng)
    a, tau = rng.normal(size=model.nv), rng.normal(size=model.nv)
    h = 1e-4
    _, dv, m = model.inverse_dynamics_derivatives(q, v, a, G)
    num = np.column_stack(
        [
            (
                model.inverse_dynamics(q, v + h * e, a, G)
                - model.inverse_dynamics(q, v - h * e, a, G)
            )
            / (2 * h)
            for e in np.eye(model.nv)
        ]
    )
    assert rel_err(dv, num) < 1e-9
    assert rel_err(m, model.mass_matrix(q)) < 1e-12
    _, fv, minv = model.forward_dynamics_derivatives(q, v, tau, G)
    assert rel_err(minv @ model.mass_matrix(q), np.eye(model.nv)) < 1e-10
    num = np.column_stack(
        [
            (
                model.forward_dynamics(q, v + h * e, tau, G)
                - model.forward_dynamics(q, v - h * e, tau, G)
            )
            / (2 * h)
            for e in np.eye(model.nv)
        ]
    )
    assert rel_err(fv, num) < 1e-8


# ---------------------------------------------------------------------------------------------
# Scenes: effects and the state Jacobian
# ---------------------------------------------------------------------------------------------

E = pmd.Effect


def effect_scene(with_numerical=True):
    tree = random_tree(
        3, 8, kinds=("Revolute", "Prismatic", "Spherical", "SphericalZYZ", "FreeFlyer")
    )
    model = build_model(tree)
    names, kinds = model.body_names, tree.kinds()
    sph = [names[i] for i, k in enumerate(kinds) if k == "Spherical"]
    one = [names[i] for i, k in enumerate(kinds) if k in ("Revolute", "Prismatic")]
    assert sph and len(one) >= 2
    effects = [
        E.gravity(),
        pmd.Damper(None, 0.3),
        pmd.JointFriction(one + sph, 0.2, v_eps=0.5),
        pmd.Spring(one, 2.0, 0.1),
        pmd.Spring(sph, 1.5, name="ball"),
        pmd.PDTorque(one[:1], 3.0, 0.5, [0, 1], [[0.2], [0.4]]),
        pmd.JointTorque(one[1:2], 0.7),
    ]
    if with_numerical:
        effects += [
            pmd.ExternalForce(names[-1], force=[1, 2, 3], point=[0.1, 0, 0], frame="body"),
            pmd.PointSpring(names[0], [0.1, 0, 0], names[-1], [0, 0.1, 0], 5.0, 0.2, 0.3),
            pmd.TorqueFunction(lambda t, q, v: -0.1 * v, name="callback"),
        ]
    return model, pmd.Scene(model, effects=effects)


def scene_qdd(model, scene, t, q, v):
    return model.forward_dynamics(q, v, sum(pmd.effect_forces(scene, t, q, v).values()))


@pytest.mark.parametrize("with_numerical", [False, True])
def test_scene_derivatives_match_central_differences(with_numerical):
    model, scene = effect_scene(with_numerical)
    rng = np.random.default_rng(4)
    q, v = random_state(model, rng)
    t = 0.3
    r = scene.forward_dynamics_derivatives(q, v, t=t)
    expected = ["external", "callback"] if with_numerical else []
    assert r["numerical"] == expected
    f = lambda x: scene_qdd(model, scene, t, x, v)  # noqa: E731
    h = 1e-5
    num_q = central_dq(model, f, q, h)
    num_v = np.column_stack(
        [
            (scene_qdd(model, scene, t, q, v + h * e) - scene_qdd(model, scene, t, q, v - h * e))
            / (2 * h)
            for e in np.eye(model.nv)
        ]
    )
    eq, ev = rel_err(r["dq"], num_q), rel_err(r["dv"], num_v)
    record("scene derivatives vs central differences: dq", eq)
    record("scene derivatives vs central differences: dv", ev)
    assert eq < 1e-7 and ev < 1e-7, (eq, ev)
    # Without effects besides gravity the scene's derivatives are the model's.
    bare = pmd.Scene(model, effects=[E.gravity()])
    tau = rng.normal(size=model.nv)
    rb = bare.forward_dynamics_derivatives(q, v, tau)
    fq, fv, minv = model.forward_dynamics_derivatives(q, v, tau, [0, 0, -9.81])
    assert rel_err(rb["dq"], fq) < 1e-12 and rel_err(rb["dv"], fv) < 1e-12
    assert rel_err(rb["dtau"], minv) < 1e-12


def test_scene_inverse_derivatives_subtract_the_effects():
    """τ = ID(q, v, a) − τ_e: its derivatives against central differences."""
    model, scene = effect_scene(False)
    rng = np.random.default_rng(6)
    q, v = random_state(model, rng)
    a = rng.normal(size=model.nv)
    t = 0.2

    def tau(x, vv):
        return model.inverse_dynamics(x, vv, a) - sum(pmd.effect_forces(scene, t, x, vv).values())

    r = scene.inverse_dynamics_derivatives(q, v, a, t=t)
    h = 1e-5
    num_q = central_dq(model, lambda x: tau(x, v), q, h)
    num_v = np.column_stack(
        [(tau(q, v + h * e) - tau(q, v - h * e)) / (2 * h) for e in np.eye(model.nv)]
    )
    assert rel_err(r["dq"], num_q) < 1e-7
    assert rel_err(r["dv"], num_v) < 1e-7
    assert rel_err(r["da"], model.mass_matrix(q)) < 1e-12


def test_friction_derivative_at_rest_is_the_smooth_law_slope():
    """At v = 0 the regularised friction's slope is −F/v_eps (finite: the law is smooth)."""
    m = pmd.Model()
    m.add_body(pmd.RigidBody(2.0, [0.1, 0, 0], np.diag([0.1, 0.2, 0.2])), pmd.Revolute([0, 0, 1]))
    s = pmd.Scene(m, effects=[pmd.JointFriction(None, 0.4, v_eps=0.01)])
    r = s.inverse_dynamics_derivatives([0.3], [0.0], [0.0])
    assert r["dv"][0, 0] == pytest.approx(0.4 / 0.01, rel=1e-12)


def test_state_jacobian_matches_central_differences_of_the_rhs():
    """∂ẏ/∂y in the coordinates of y = [q; v] (quaternions' four), q̇ = f(q, v) included."""
    model, scene = effect_scene(True)
    rng = np.random.default_rng(2)
    q, v = random_state(model, rng)
    y = np.concatenate([q, v])
    t = 0.4
    jac = scene.state_jacobian(y, t=t)
    assert jac.shape == (model.nq + model.nv,) * 2

    def rhs(yy):
        qq, vv = yy[: model.nq], yy[model.nq :]
        return np.concatenate([model.velocity_to_qdot(qq, vv), scene_qdd(model, scene, t, qq, vv)])

    h = 1e-6
    num = np.column_stack([(rhs(y + h * e) - rhs(y - h * e)) / (2 * h) for e in np.eye(len(y))])
    err = rel_err(jac, num)
    record("state Jacobian vs central differences of the RHS", err)
    assert err < 1e-7


def test_loops_and_bad_input_are_refused():
    from test_loops import fourbar

    m = fourbar()
    q, v = np.array([0.3, 0.5, 0.7]), np.zeros(3)
    with pytest.raises(pmd.errors.InvalidInputError, match="loop"):
        m.forward_dynamics_derivatives(q, v, np.zeros(3))
    # Scenes with loops: the constrained dynamics' derivatives (tests/test_iftomm.py); the
    # inverse ones are refused (they depend on the actuated joints).
    s = pmd.Scene(m, effects=[E.gravity()])
    assert s.state_jacobian(np.concatenate([q, v])) is not None
    with pytest.raises(pmd.errors.InvalidInputError, match="loop"):
        s.inverse_dynamics_derivatives(q, v, np.zeros(3))
    tree = random_tree(1, 5, kinds=("Revolute",))
    model = build_model(tree)
    with pytest.raises(pmd.errors.InvalidInputError, match="v"):
        model.inverse_dynamics_derivatives(np.zeros(5), np.zeros(4), np.zeros(5))
    with pytest.raises(pmd.errors.InvalidInputError, match="tau"):
        model.forward_dynamics_derivatives(np.zeros(5), np.zeros(5), [np.nan] * 5)
    # A ZYZ joint at its singularity: the forward dynamics refuse it, and so do these.
    zyz = pmd.Model()
    zyz.add_body(pmd.RigidBody(1.0, [0, 0, 0.2], np.eye(3) * 0.1), pmd.SphericalZYZ())
    with pytest.raises(pmd.errors.SingularityError):
        zyz.forward_dynamics_derivatives([0.1, 0.0, 0.2], np.zeros(3), np.zeros(3))


@pytest.mark.parametrize(
    "ends, rest, damping",
    [
        ((1, 4), 0.2, 0.3),  # both ends on one branch (shared upstream columns)
        ((-1, 5), 0.0, 0.0),  # to the world, the linear law −k d
        ((2, -1), 0.1, 0.5),
    ],
)
def test_point_spring_derivatives_are_analytic_and_match_central_differences(ends, rest, damping):
    tree = random_tree(
        4, 7, kinds=("Revolute", "Prismatic", "Spherical", "SphericalZYZ", "FreeFlyer")
    )
    model = build_model(tree)
    names = model.body_names
    body = [None if e < 0 else names[e] for e in ends]
    scene = pmd.Scene(
        model,
        effects=[
            pmd.PointSpring(
                body[0], [0.1, -0.05, 0.02], body[1], [0.0, 0.1, 0.03], 7.0, rest, damping
            )
        ],
    )
    rng = np.random.default_rng(12)
    q, v = random_state(model, rng)
    r = scene.forward_dynamics_derivatives(q, v)
    assert r["numerical"] == []
    h = 1e-5
    f = lambda x: scene_qdd(model, scene, 0.0, x, v)  # noqa: E731
    num_q = central_dq(model, f, q, h)
    num_v = np.column_stack(
        [
            (
                scene_qdd(model, scene, 0.0, q, v + h * e)
                - scene_qdd(model, scene, 0.0, q, v - h * e)
            )
            / (2 * h)
            for e in np.eye(model.nv)
        ]
    )
    assert rel_err(r["dq"], num_q) < 1e-7
    assert rel_err(r["dv"], num_v) < 1e-7
