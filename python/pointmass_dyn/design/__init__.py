"""Mechanism design with point masses (docs/balancing.md, docs/design.md): shaking forces and
moments, a mechanism along a prescribed motion (driving and bearing forces), and the design of
link shapes (material cells) and counterweights that trade shaking force, shaking moment,
driving torque, bearing forces and mass — a convex program (QP or SOCP) solved by Clarabel.

    motion = pmd.prescribed_motion(scene.model, "crank", speed=2 * np.pi, q_guess=scene.q0)
    b = pmd.balance(motion, counterweights=[pmd.Counterweight.ring("crank", (0, 0, 0), 0.02)],
                    zero=("force",))
"""

from ._balance import Balance, Counterweight, SolverStage
from ._connect import HANG
from ._front import TIE_WEIGHT, ParetoFront, analysed_value, pareto_front
from ._material import Material
from ._problem import OBJECTIVES, balance, objective_value
from ._realise import FLOOR, T_MIN, TOLERANCE, Realisation, RealisedPart
from ._shaking import MotionAnalysis, Shaking, analyze_motion, prescribed_motion, shaking
from ._shapes import LinkShape, Shape, read_stl
from ._strength import LinkStrength
from ._write import write_scene, write_urdf

__all__ = [
    "FLOOR",
    "HANG",
    "OBJECTIVES",
    "TIE_WEIGHT",
    "TOLERANCE",
    "T_MIN",
    "Balance",
    "Counterweight",
    "LinkShape",
    "LinkStrength",
    "Material",
    "MotionAnalysis",
    "ParetoFront",
    "Realisation",
    "RealisedPart",
    "Shape",
    "Shaking",
    "SolverStage",
    "analyze_motion",
    "analysed_value",
    "balance",
    "objective_value",
    "pareto_front",
    "prescribed_motion",
    "read_stl",
    "shaking",
    "write_scene",
    "write_urdf",
]
