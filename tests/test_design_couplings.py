"""Design and balancing of a mechanism with joint couplings (docs/design.md, docs/couplings.md):
a forearm geared to its upper arm (q_fore = 0.5 q_upper + 0.2) driven at the upper joint.
The driving torque is the reduced force τ_upper + ratio · τ_fore of the tree's inverse
dynamics (virtual work), before and after a counterweight design."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest

Z = [0.0, 0.0, 1.0]
G = np.array([0.0, -9.81, 0.0])
RATIO = 0.5


def _arm() -> pmd.Model:
    arm = pmd.Model()
    arm.add_body(pmd.RigidBody(1.2, [0.2, 0, 0], np.diag([1e-3, 0.02, 0.02])), pmd.Revolute(Z),
                 name="upper")
    arm.add_body(pmd.RigidBody(0.8, [0.15, 0, 0], np.diag([1e-3, 0.01, 0.01])),
                 pmd.Revolute(Z), parent="upper", translation=[0.4, 0, 0], name="fore")
    arm.add_coupling("fore", "upper", ratio=RATIO, offset=0.2)
    return arm


def _reduced(model, motion) -> np.ndarray:
    """The upper joint's driving force by virtual work from the tree's joint forces."""
    tree = np.array([model.inverse_dynamics(q, v, a, gravity=G)
                     for q, v, a in zip(motion.q, motion.v, motion.a)])
    return tree[:, 0] + RATIO * tree[:, 1]


@pytest.fixture(scope="module")
def motion():
    return pmd.design.prescribed_motion(_arm(), "upper", speed=3.0, samples=48, gravity=G)


def test_a_coupled_arm_moves_on_its_coupling_and_is_driven_by_the_reduced_force(motion):
    np.testing.assert_allclose(motion.q[:, 1], RATIO * motion.q[:, 0] + 0.2, atol=1e-12)
    np.testing.assert_allclose(motion.v[:, 1], RATIO * motion.v[:, 0], atol=1e-12)
    assert motion.actuated == [0]
    want = _reduced(motion.model, motion)
    np.testing.assert_allclose(motion.tau[:, 0], want, rtol=0, atol=1e-12 * np.abs(want).max())
    assert np.all(motion.tau[:, 1] == 0)
    # Without `actuated`, each joint's own force (the tree's), as inverse_dynamics gives.
    own = pmd.design.analyze_motion(motion.model, motion.t, motion.q, motion.v, motion.a,
                                    gravity=G)
    assert own.actuated is None
    np.testing.assert_allclose(own.tau[5], motion.model.inverse_dynamics(
        motion.q[5], motion.v[5], motion.a[5], gravity=G), atol=1e-12)


def test_torque_balancing_a_coupled_arm_predicts_the_redesigned_torque(motion):
    cw = pmd.Counterweight.ring("upper", [0.0, 0.0, 0.0], 0.1, count=12, max_mass=5.0)
    b = pmd.balance(motion, counterweights=[cw], objective={"torque": 1.0})
    assert b.counterweights
    # The prediction, the re-analysis and the virtual-work torque of the designed model agree.
    want = _reduced(b.model, motion)
    scale = np.abs(motion.tau[:, 0]).max()
    np.testing.assert_allclose(b.predicted["torque"][:, 0], want, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(b.after.tau[:, 0], want, rtol=0, atol=1e-9 * scale)
    # A counterweight on the upper arm takes out the gravity torque of the geared pair's
    # first moment about the upper joint: much less torque than before.
    rms = lambda x: float(np.sqrt(np.mean(x ** 2)))  # noqa: E731
    assert rms(b.after.tau[:, 0]) < 0.5 * rms(motion.tau[:, 0])
