"""Identification of a mechanism with a loop from its actuated torque (docs/identification.md
§7): the four-bar scene driven at its crank. The actuated regressor against the loop solver's
inverse dynamics (``inverse_dynamics(..., actuated)``) and against the work-energy balance
``τ ω = d(T + V)/dt`` by finite differences; exact data recovering the base parameters, the
identified model's own actuated inverse dynamics reproducing the true model's torques on a
different motion; the simulation of the identified model under the measured torque beside the
measurement; bad input."""

from __future__ import annotations

import dataclasses

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import record, rel_err
from pointmass_dyn import identification as ident

G = [0.0, -9.81, 0.0]


def box(length):
    return [[-0.01, -0.01, -0.005], [length + 0.01, 0.01, 0.005]]


ENVELOPES = {"crank": box(0.035), "coupler": box(0.09), "rocker": box(0.07)}


def crank_motion(model, q0, t, coeffs):
    """Closed states along a prescribed crank angle θ(t) = c0 t + Σ c_k sin(k ω t + k): each
    state assembled from the previous one with the crank held, then the speeds and
    accelerations projected with the crank's held (so J v = 0, J a + J̇ v = 0 exactly)."""
    w = 2 * np.pi / (t[-1] - t[0])
    th = coeffs[0] * t + sum(c * np.sin(k * w * t + k) for k, c in enumerate(coeffs[1:], 1))
    om = coeffs[0] + sum(c * k * w * np.cos(k * w * t + k) for k, c in enumerate(coeffs[1:], 1))
    al = -sum(c * (k * w) ** 2 * np.sin(k * w * t + k) for k, c in enumerate(coeffs[1:], 1))
    q = np.array(q0, float)
    out = []
    for x, y, z in zip(th, om, al):
        guess = q.copy()
        guess[0] = x
        q = model.assemble(guess, fixed=["crank"])
        v = model.assemble_velocity(q, np.r_[y, 0.0, 0.0], fixed=["crank"])
        a = model.assemble_acceleration(q, v, np.r_[z, 0.0, 0.0], fixed=["crank"])
        out.append((q, v, a))
    return tuple(np.array(s) for s in zip(*out))


def other_fourbar(model):
    """The four-bar with a heavier crank and a lighter rocker (other rigid bodies)."""
    other = model.with_body("crank", pmd.RigidBody(0.03, [0.02, 0.002, 0.0], np.diag([3e-7, 3e-6, 3.2e-6])))
    return other.with_body("rocker", pmd.RigidBody(0.025, [0.03, -0.001, 0.0], np.diag([4e-7, 1.1e-5, 1.14e-5])))


def crank_torque(model, qs, vs, acs):
    return np.array([model.inverse_dynamics(*s, gravity=G, actuated=["crank"])[[0]] for s in zip(qs, vs, acs)])


@pytest.fixture(scope="module")
def fourbar():
    scene = pmd.load_scene("fourbar")
    t = np.linspace(0.0, 2.0, 241)
    states = crank_motion(scene.model, scene.q0, t, [9.0, 0.8, 0.3, 0.2])
    return scene.model, scene.q0, t, states


def test_actuated_regressor_is_the_loop_solvers_crank_torque(fourbar):
    m, _, _, (qs, vs, acs) = fourbar
    reg = ident.torque_regressor(m, qs, vs, acs, G, actuated=["crank"])
    assert reg.data.shape == (len(qs), 30) and reg.actuated == (0,)
    tau = crank_torque(m, qs, vs, acs)
    assert record("identification: four-bar Y_a π vs actuated inverse dynamics", rel_err(reg.torques(), tau)) < 1e-12
    # v index and name select the same rows; the tree's regressor is refused for a loop.
    np.testing.assert_array_equal(ident.torque_regressor(m, qs, vs, acs, G, actuated=[0]).data, reg.data)
    with pytest.raises(pmd.errors.InvalidInputError, match="actuated"):
        ident.torque_regressor(m, qs, vs, acs, G)


def test_actuated_regressor_balances_the_work_of_the_crank(fourbar):
    """τ ω = d(T + V)/dt: the crank's power against central differences of the energy along
    the motion, for the model's parameters and for a second, physically different set (each
    column's torque is the power balance of its own parameter; a wrong column breaks it)."""
    m, q0, _, _ = fourbar
    # States at t and t ± h (each grid closed by continuation from q0), h small enough that
    # the central difference's O(h²) error is far below the tolerance.
    h, t = 2e-5, np.linspace(0.0, 2.0, 121)[1:-1]
    coeffs = [9.0, 0.8, 0.3, 0.2]
    qs, vs, acs = crank_motion(m, q0, t, coeffs)
    ends = [crank_motion(m, q0, t + s, coeffs) for s in (-h, h)]
    reg = ident.torque_regressor(m, qs, vs, acs, G, actuated=["crank"])
    other = other_fourbar(m)
    pi2 = ident.torque_regressor(other, qs[:1], vs[:1], acs[:1], G, actuated=["crank"]).values
    for model, pi in ((m, reg.values), (other, pi2)):
        def energy(states, model=model):
            return np.array([model.kinetic_energy(q, v) + model.potential_energy(q, G) for q, v, _ in zip(*states)])

        de = (energy(ends[1]) - energy(ends[0])) / (2 * h)
        power = (reg.data @ pi) * vs[:, 0]
        assert record("identification: four-bar crank power vs dE/dt (FD)", rel_err(power, de)) < 1e-6
    # And not by accident: the first model's torques break the second's balance.
    assert rel_err(reg.torques()[:, 0] * vs[:, 0], de) > 0.05


@pytest.mark.parametrize("method", ["ols", "cells"])
def test_fourbar_identified_from_its_crank_torque(fourbar, method):
    """Exact crank torques: the base parameters to 1e-9; the identified model (another split
    of the same base parameters, the rest from a wrong prior) drives a different motion with
    the true model's torque."""
    m, q0, t, (qs, vs, acs) = fourbar
    tau = crank_torque(m, qs, vs, acs)
    res = pmd.identify(
        m, (qs, vs, acs, tau), method=method, actuated=["crank"], gravity=G, envelopes=ENVELOPES, cells=60,
        prior=other_fourbar(m),
    )
    reg = ident.torque_regressor(m, qs, vs, acs, G, actuated=["crank"])
    truth = res.base.of(reg.values)
    assert res.structural_rank == res.base.rank == 8
    assert record(f"identification: four-bar base parameters ({method})", rel_err(res.base_values, truth)) < 1e-9
    assert np.abs(res.parameters - reg.values).max() > 1e-3 * np.abs(reg.values).max()  # not the truth itself
    q2, v2, a2 = crank_motion(m, q0, t[:60], [-5.0, 0.5, 0.4])
    tau2 = crank_torque(m, q2, v2, a2)
    held = ident.validate(res, m, (q2, v2, a2, tau2), gravity=G)
    assert held.predicted.shape == (60, 1)
    assert record(f"identification: four-bar held-out Y_a π ({method})", rel_err(held.predicted, tau2)) < 1e-9
    if method == "cells":
        # The identified bodies exist; the identified model's own loop solver reproduces the
        # true model's crank torque on the other motion.
        assert res.model is not None and res.physical
        got = crank_torque(res.model, q2, v2, a2)
        assert record("identification: four-bar held-out crank torque (cells model)", rel_err(got, tau2)) < 1e-9

def test_actuated_bad_input(fourbar):
    m, _, _, (qs, vs, acs) = fourbar
    tau = crank_torque(m, qs, vs, acs)
    with pytest.raises(pmd.errors.InvalidInputError, match="actuated.*'elbow'"):
        ident.torque_regressor(m, qs, vs, acs, G, actuated=["elbow"])
    with pytest.raises(pmd.errors.InvalidInputError, match="actuated"):
        ident.torque_regressor(m, qs, vs, acs, G, actuated=[0, 0])
    tree = pmd.load_scene("chain7").model
    with pytest.raises(pmd.errors.InvalidInputError, match="actuated: expected None for a model without loops"):
        ident.torque_regressor(tree, np.zeros((2, 7)), np.zeros((2, 7)), np.zeros((2, 7)), actuated=[0])
    with pytest.raises(pmd.errors.InvalidInputError, match=r"tau: expected an \(N, 1\) array"):
        pmd.identify(m, (qs, vs, acs, np.c_[tau, tau, tau]), method="ols", actuated=["crank"], gravity=G)
    with pytest.raises(pmd.errors.InvalidInputError, match="actuated"):
        pmd.identify(m, (qs, vs, acs, np.c_[tau, tau, tau]), method="ols", gravity=G)


def test_replay_puts_the_identified_models_motion_beside_the_measurement(fourbar, tmp_path):
    """The identified model under the measured crank torque (1 kHz, 0.5 s: the torque-driven
    four-bar's open-loop motion separates from any perturbation exponentially, ~e-fold in
    0.1 s at this speed) against the true model run by ``simulate`` on the same torque table
    (the same trajectory to the integration tolerance: the same base parameters are the same
    dynamics) and against the measured motion (to the table's interpolation error)."""
    m, q0, _, _ = fourbar
    t = np.linspace(0.0, 0.5, 501)
    qs, vs, acs = crank_motion(m, q0, t, [9.0, 0.8, 0.3, 0.2])
    tau = crank_torque(m, qs, vs, acs)
    res = pmd.identify(m, (qs, vs, acs, tau), actuated=["crank"], gravity=G, envelopes=ENVELOPES, cells=60, prior=other_fourbar(m))
    rep = ident.replay(res, t, qs, tau, v0=vs[0], gravity=G, rtol=1e-11, atol=1e-13)
    assert rep.success and rep.q_simulated.shape == qs.shape
    true = pmd.Scene(m, q0=qs[0], v0=vs[0], effects=[pmd.TabulatedTorque(["crank"], t, tau), pmd.Gravity(G)])
    ref = pmd.simulate(true, (0.0, 0.5), t_eval=t, rtol=1e-11, atol=1e-13, method="DOP853")
    assert record("identification: four-bar replay vs true model's run (rad)", np.abs(rep.q_simulated - ref.q).max()) < 1e-5
    assert record("identification: four-bar replay vs measurement (rad)", rep.rms.max()) < 1e-2
    # A model that is not the mechanism's (the prior) does not follow the measurement.
    wrong = ident.replay(dataclasses.replace(res, model=other_fourbar(m)), t, qs, tau, v0=vs[0], gravity=G)
    assert wrong.rms.max() > 10 * rep.rms.max()
    rep.plot(tmp_path / "replay.png", labels=list(m.link_names))
    assert (tmp_path / "replay.png").stat().st_size > 0


def test_coupled_arm_actuated_regressor_is_the_virtual_work_sum():
    """A coupling q_fore = r q_upper + c driven at the upper joint: by virtual work the
    driving force is τ_upper + r τ_fore of the tree, so Y_a = Y_upper + r Y_fore row by row
    (and the fit recovers the base parameters from it)."""
    z, r = [0.0, 0.0, 1.0], 0.5
    arm = pmd.Model()
    arm.add_body(pmd.RigidBody(1.2, [0.2, 0, 0], np.diag([1e-3, 0.02, 0.02])), pmd.Revolute(z), name="upper")
    arm.add_body(pmd.RigidBody(0.8, [0.15, 0.02, 0], np.diag([1e-3, 0.01, 0.01])), pmd.Revolute(z),
                 parent="upper", translation=[0.4, 0, 0], name="fore")
    arm.add_coupling("fore", "upper", ratio=r, offset=0.2)
    rng = np.random.default_rng(4)
    th, om, al = rng.uniform(-2, 2, (3, 40))
    qs = np.c_[th, r * th + 0.2]
    vs, acs = np.c_[om, r * om], np.c_[al, r * al]
    tree = ident.torque_regressor(arm, qs, vs, acs, G).data.reshape(40, 2, -1)
    act = ident.torque_regressor(arm, qs, vs, acs, G, actuated=["upper"])
    assert record("identification: coupled arm Y_a vs virtual work", rel_err(act.data, tree[:, 0] + r * tree[:, 1])) < 1e-13
    tau = np.array([arm.inverse_dynamics(*s, gravity=G, actuated=["upper"])[:1] for s in zip(qs, vs, acs)])
    assert rel_err(act.torques(), tau) < 1e-13
    res = pmd.identify(arm, (qs, vs, acs, tau), method="ols", actuated=["upper"], gravity=G)
    assert res.structural_rank == res.base.rank and rel_err(res.base_values, res.base.of(act.values)) < 1e-9
