"""Prescribed-motion analysis and balancing with point masses (pointmass_dyn.design)
against the Berkof–Lowen conditions for the complete force balance of a four-bar, against
re-analysis and simulation of the balanced mechanism, and against the invariants of a
weighted-sum Pareto front."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest

G = np.array([0.0, -9.81, 0.0])
SPEED = 10.0


@pytest.fixture(scope="module")
def fourbar():
    scene = pmd.load_scene("fourbar")
    motion = pmd.prescribed_motion(
        scene.model, "crank", speed=SPEED, samples=180, q_guess=scene.q0, gravity=G
    )
    return scene, motion


def first_moment(body):
    return body.mass * np.asarray(body.com)


def with_point_mass(body, mass, point):
    """The body plus a point mass at ``point`` (body frame), from its seven point masses."""
    pm = body.point_masses()
    return pmd.RigidBody.from_point_masses(
        np.concatenate([pm.masses, [mass]]), np.vstack([pm.positions, [point]])
    )


def berkof_lowen_targets(model):
    """Berkof & Lowen (1969): the total centre of mass of a four-bar stays put iff, with the
    coupler's centre of mass at (ξ, η) from the crank pin in its frame (length a₂ along x),
    the crank's and rocker's first moments about their pivots are
    ``h₁ = −m₂ a₁ (1 − (ξ + iη)/a₂)`` and ``h₃ = −m₂ a₃ (ξ + iη)/a₂`` (complex numbers in
    each link's frame, x along the link)."""
    crank, coupler, rocker = (model.body(n) for n in ("crank", "coupler", "rocker"))
    a1, a2, a3 = 0.035, 0.09, 0.07  # the bundled scene's link lengths (see its description)
    m2 = coupler.mass
    z = complex(*coupler.com[:2])
    h1 = -m2 * a1 * (1 - z / a2)
    h3 = -m2 * a3 * z / a2
    del crank, rocker
    return np.array([h1.real, h1.imag, 0.0]), np.array([h3.real, h3.imag, 0.0])


def test_berkof_lowen_counterweights_cancel_the_shaking_force(fourbar):
    scene, motion = fourbar
    model = scene.model
    h1, h3 = berkof_lowen_targets(model)
    balanced = model
    for name, target in (("crank", h1), ("rocker", h3)):
        body = model.body(name)
        missing = target - first_moment(body)
        r = 0.02  # counterweight on a 2 cm arm, along the missing first moment
        mass = np.linalg.norm(missing) / r
        point = missing / np.linalg.norm(missing) * r
        balanced = balanced.with_body(name, with_point_mass(body, mass, point))
        assert first_moment(balanced.body(name)) == pytest.approx(target, abs=1e-15)
    after = pmd.analyze_motion(
        balanced, motion.t, motion.q, motion.v, motion.a, actuated=["crank"], gravity=G
    )
    before_rms = motion.shaking.rms["force"]
    assert before_rms > 0.1
    assert after.shaking.rms["force"] <= 1e-10 * before_rms
    # Not a balance of everything: the moment remains.
    assert after.shaking.rms["moment"] > 1e-3 * motion.shaking.rms["moment"]


def test_the_optimiser_finds_the_berkof_lowen_balance_by_itself(fourbar):
    scene, motion = fourbar
    rings = [
        pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 24),
        pmd.Counterweight.ring("rocker", [0, 0, 0], 0.02, 24),
    ]
    for kw in ({"zero": ("force",), "objective": {}}, {"objective": {"force": 1.0}}):
        b = pmd.balance(motion, counterweights=rings, **kw)
        # To the conic solver's tolerances (feasibility and gap 1e-10, relative).
        assert b.solver["status"] == "Solved" and b.solver["gap_rel"] <= 1e-8
        assert b.after.shaking.rms["force"] <= 1e-8 * motion.shaking.rms["force"], kw
        h1, h3 = berkof_lowen_targets(scene.model)
        tol = 1e-8 * np.linalg.norm(h1)
        np.testing.assert_allclose(first_moment(b.bodies["crank"]), h1, atol=tol)
        np.testing.assert_allclose(first_moment(b.bodies["rocker"]), h3, atol=tol)
        # The least added mass: one counterweight per link, on the ring point opposite.
        assert [c[0] for c in b.counterweights] == ["crank", "rocker"]
        for name, point, _ in b.counterweights:
            target = h1 if name == "crank" else h3
            np.testing.assert_allclose(
                point / np.linalg.norm(point), target / np.linalg.norm(target), atol=1e-8
            )


def test_predictions_equal_the_reanalysed_balanced_model(fourbar):
    """A mixed design (the coupler redesigned, counterweights on crank and rocker) and every
    objective: what the linear model predicts is what the rebuilt model does."""
    _, motion = fourbar
    b = pmd.balance(
        motion,
        counterweights=[
            pmd.Counterweight.ring("crank", [0, 0, 0], 0.015, 12, max_mass=0.05),
            pmd.Counterweight.ring("rocker", [0, 0, 0], 0.015, 12),
        ],
        links=["coupler"],
        objective={"force": 1.0, "moment": 0.3, "torque": 0.2},
    )
    after = b.after
    for what, got in (
        ("force", after.shaking.force),
        ("moment", after.shaking.moment),
        ("torque", after.tau[:, after.actuated]),
    ):
        scale = np.abs(b.predicted[what]).max() + 1e-300
        assert np.abs(b.predicted[what] - got).max() <= 1e-9 * scale, what
    # Bounds held, and every new body is physical (the constructor validates it).
    assert np.all(b.masses >= 0)
    assert all(m <= 0.05 + 1e-15 for name, _, m in b.counterweights if name == "crank")
    for body in b.bodies.values():
        pmd.RigidBody(body.mass, com=body.com, inertia=body.inertia)
        eig = np.linalg.eigvalsh(body.inertia)
        # Positive semi-definite with the triangle inequality (a point mass, all at the
        # centre, is the limit: the optimiser may lump a link's mass there).
        assert body.mass > 0 and eig.min() >= -1e-18
        assert eig.max() <= eig.sum() - eig.max() + 1e-15
    # The weighted objective did not get worse than doing nothing.
    cost = sum(
        w * (b.after.summary()[k]["rms"] / motion.summary()[k]["rms"]) ** 2
        for k, w in (("shaking force", 1.0), ("shaking moment", 0.3))
    )
    assert cost < 1.3


def test_the_balanced_mechanism_simulated_reproduces_the_prediction(fourbar):
    """Drive the balanced four-bar by its predicted crank torque and simulate: it follows the
    prescribed crank motion and its shaking (computed along the simulated result from the
    scene's own accelerations) is the predicted one."""
    scene, motion = fourbar
    b = pmd.balance(
        motion,
        counterweights=[
            pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 24),
            pmd.Counterweight.ring("rocker", [0, 0, 0], 0.02, 24),
        ],
        zero=("force",),
        objective={"moment": 1.0},
    )
    model = b.model
    theta0 = motion.q[0, 0]

    def crank_torque(t, q, v):
        # The prescribed state at time t (closed from the nearest sample, so on the same
        # assembly branch), and the balanced model's driving torque there.
        guess = motion.q[np.argmin(np.abs(motion.t - t))].copy()
        guess[0] = theta0 + SPEED * t
        qp = model.assemble(guess, fixed=["crank"])
        vp = model.assemble_velocity(qp, [SPEED, 0, 0], fixed=["crank"])
        ap = model.assemble_acceleration(qp, vp, [0.0, 0, 0], fixed=["crank"])
        return model.inverse_dynamics(qp, vp, ap, gravity=G, actuated=["crank"])

    scene2 = pmd.Scene(
        model,
        motion.q[0],
        motion.v[0],
        effects=[pmd.Gravity(G), pmd.TorqueFunction(crank_torque)],
    )
    ts = motion.t[motion.t <= 0.3]
    res = pmd.simulate(scene2, (0.0, ts[-1]), t_eval=ts, rtol=1e-11, atol=1e-13)
    assert res.success, res.message
    np.testing.assert_allclose(res.q[:, 0], theta0 + SPEED * ts, atol=1e-7)
    along = pmd.shaking(scene2, res)
    k = len(ts)
    force_scale = motion.shaking.rms["force"]
    assert np.abs(along.force).max() <= 1e-7 * force_scale
    np.testing.assert_allclose(
        along.moment, b.predicted["moment"][:k], atol=1e-6 * np.abs(b.predicted["moment"]).max()
    )
    np.testing.assert_allclose(along.weight, model.total_mass * G)


def test_pareto_front_trades_one_objective_for_the_other(fourbar):
    _, motion = fourbar
    rings = [
        pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 12),
        pmd.Counterweight.ring("rocker", [0, 0, 0], 0.02, 12),
    ]
    front = pmd.pareto_front(motion, ("force", "moment"), count=6, counterweights=rings)
    force = np.array([b.after.shaking.rms["force"] for b in front])
    moment = np.array([b.after.shaking.rms["moment"] for b in front])
    # Weighted-sum scalarisation: raising the moment's weight never raises the moment.
    tol = 1e-9
    assert np.all(np.diff(moment) <= tol * moment.max())
    assert np.all(np.diff(force) >= -tol * force.max() - 1e-15)
    # The force end weights the moment TIE_WEIGHT (ties broken by it, issue 39): an RMS
    # program weights mean squares, so the relative force's square rises by at most
    # TIE_WEIGHT times the relative moment's square there.
    rf, rm = motion.shaking.rms["force"], motion.shaking.rms["moment"]
    assert (force[0] / rf) ** 2 <= pmd.design.TIE_WEIGHT * (moment[0] / rm) ** 2 + 1e-12
    assert moment[-1] < moment[0]


def test_shaking_along_arrays_equals_per_state(fourbar):
    _, motion = fourbar
    s = pmd.shaking(motion.model, motion.q, motion.v, motion.a, about=[0.05, 0.0, 0.0])
    for k in (0, 17, 90):
        f, m = motion.model.shaking(motion.q[k], motion.v[k], motion.a[k], about=[0.05, 0, 0])
        np.testing.assert_array_equal(s.force[k], f)
        np.testing.assert_array_equal(s.moment[k], m)
    # The moment about another point: M_O' = M_O + (O − O') × F.
    s0 = pmd.shaking(motion.model, motion.q, motion.v, motion.a)
    shifted = s0.moment + np.cross(np.zeros(3) - [0.05, 0, 0], s0.force)
    np.testing.assert_allclose(s.moment, shifted, atol=1e-15 * np.abs(s0.moment).max() + 1e-18)


def test_bad_balancing_input_is_a_clear_error(fourbar):
    scene, motion = fourbar
    ring = pmd.Counterweight.ring("coupler", [0.045, 0, 0], 0.01, 8)
    with pytest.raises(pmd.errors.InvalidInputError, match="zero"):
        pmd.balance(motion, counterweights=[ring], zero=("force",))
    with pytest.raises(pmd.errors.InvalidInputError, match="objective"):
        pmd.balance(motion, counterweights=[ring], objective={"energy": 1.0})
    with pytest.raises(pmd.errors.InvalidInputError, match="design"):
        pmd.balance(motion)
    with pytest.raises(pmd.errors.InvalidInputError, match="driver"):
        pmd.prescribed_motion(scene.model, "nothing", speed=1.0)
    with pytest.raises(pmd.errors.InvalidInputError, match="speed"):
        pmd.prescribed_motion(scene.model, "crank", speed=0.0)
    chain = pmd.load_scene("chain7").model
    with pytest.raises(pmd.errors.InvalidInputError, match="one degree of freedom"):
        pmd.prescribed_motion(chain, 0, speed=1.0)
    with pytest.raises(pmd.errors.InvalidInputError, match="Scene"):
        pmd.shaking(scene.model, pmd.simulate(scene, (0, 0.01)))


def test_a_tabulated_input_equals_the_constant_speed_one(fourbar):
    scene, motion = fourbar
    n = len(motion.t)
    tab = pmd.prescribed_motion(
        scene.model,
        "crank",
        input=(motion.t, motion.input, np.full(n, SPEED), np.zeros(n)),
        q_guess=scene.q0,
        gravity=G,
    )
    np.testing.assert_array_equal(tab.q, motion.q)
    np.testing.assert_array_equal(tab.tau, motion.tau)
    np.testing.assert_array_equal(tab.shaking.force, motion.shaking.force)
    # An accelerating crank: the driving torque differs by the reflected inertia, I(θ) θ̈.
    acc = np.full(n, 3.0)
    fast = pmd.prescribed_motion(
        scene.model,
        "crank",
        input=(motion.t, motion.input, np.full(n, SPEED), acc),
        q_guess=scene.q0,
        gravity=G,
    )
    for k in (0, 40, 100):
        q, v = fast.q[k], fast.v[k]
        # The mechanism's inertia seen by the crank: vᵀ M v / θ̇² along the loop's motion.
        m = scene.model.mass_matrix(q)
        inertia = v @ m @ v / SPEED**2
        np.testing.assert_allclose(fast.tau[k, 0] - motion.tau[k, 0], inertia * 3.0, rtol=1e-9)
