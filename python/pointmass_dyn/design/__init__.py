"""Mechanism design with point masses (docs/balancing.md): shaking forces and moments, a
mechanism along a prescribed motion (driving and bearing forces), and balancing by
counterweights or redesigned links, exactly, as a convex quadratic program.

    motion = pmd.prescribed_motion(scene.model, "crank", speed=2 * np.pi, q_guess=scene.q0)
    b = pmd.balance(motion, counterweights=[pmd.Counterweight.ring("crank", (0, 0, 0), 0.02)],
                    zero=("force",))
"""

from ._balance import OBJECTIVES, Balance, Counterweight, balance, pareto_front
from ._shaking import MotionAnalysis, Shaking, analyze_motion, prescribed_motion, shaking

__all__ = [
    "OBJECTIVES",
    "Balance",
    "Counterweight",
    "MotionAnalysis",
    "Shaking",
    "analyze_motion",
    "balance",
    "pareto_front",
    "prescribed_motion",
    "shaking",
]
