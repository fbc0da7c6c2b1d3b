"""pointmass_dyn: multibody dynamics with equimomental point masses and DeNOC matrices.

Every rigid body is represented by seven point masses with the same mass, centre of mass and
inertia; the equations of motion come from the Decoupled Natural Orthogonal Complement (DeNOC)
matrices. The core is Rust; this package is its NumPy front.
"""

from __future__ import annotations

from . import _pickle, design, errors, identification, io, kinematics, robots, viewer  # noqa: F401  (_pickle: copyreg)
from ._batch import BatchResult, simulate_batch
from ._contact import (
    ContactForces,
    GroundContact,
    JointLimit,
    contact_forces,
    torque_saturation,
    urdf_contact_points,
)
from ._control import IMU, Simulator, simulate
from ._core import (
    Effect,
    Joint,
    Model,
    PointMasses,
    RigidBody,
    RunConfig,
    RunStatus,
    Scene,
    StateEvent,
    __version__,
)
from ._simulation import (
    Damper,
    ExternalForce,
    Gravity,
    JointFriction,
    JointTorque,
    OdeResult,
    PDTorque,
    PointSpring,
    SimulationResult,
    Spring,
    TabulatedTorque,
    TorqueFunction,
    effect_forces,
    effect_power,
    energies,
    rk45,
    solve_ivp,
)
from ._sweep import sweep
from .design import (
    Balance,
    Counterweight,
    LinkShape,
    Material,
    MotionAnalysis,
    Shaking,
    Shape,
    analyze_motion,
    balance,
    pareto_front,
    prescribed_motion,
    shaking,
)
from .errors import (
    InertiaError,
    InvalidInputError,
    LoopClosureError,
    ModelStructureError,
    NumericalError,
    PointMassDynError,
    SceneError,
    SimulationError,
    SingularityError,
)
from .identification import Identification, excitation_trajectory, identify
from .io import InertiaRepair, from_mujoco, from_pinocchio, to_mjcf
from .kinematics import IKResult, inverse_kinematics
from .robots import example_robot
from .scenes import builtin_scenes, load_scene
from .viewer import AnimationInfo, animate
from .viewer import show as show_meshcat

#: Names served by a subpackage imported on first use: the benchmarking tools (work-precision
#: runs against SciPy and MuJoCo) are not needed to simulate, so ``import pointmass_dyn``
#: does not load them.
LAZY = {"benchmarking": None, "WorkPrecision": "WorkPrecision", "work_precision": "work_precision"}


def __getattr__(name: str):
    if name in LAZY:
        import importlib

        module = importlib.import_module(f"{__name__}.benchmarking")
        return module if LAZY[name] is None else getattr(module, LAZY[name])
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def Revolute(axis) -> Joint:
    """Revolute joint about ``axis`` (joint frame); q is the angle in radians."""
    return Joint.revolute(axis)


def Prismatic(axis) -> Joint:
    """Prismatic joint along ``axis`` (joint frame); q is the displacement."""
    return Joint.prismatic(axis)


def SphericalZYZ() -> Joint:
    """The paper's spherical joint: ZYZ Euler angles (phi, theta, psi), Euler rates as speeds.

    Singular where sin(theta) = 0; use :func:`Spherical` for motions through it."""
    return Joint.spherical_zyz()


def Spherical() -> Joint:
    """Quaternion spherical joint: q = (x, y, z, w), speeds = angular velocity relative to the
    parent in the body frame (as Pinocchio's JointModelSpherical)."""
    return Joint.spherical()


def Fixed() -> Joint:
    """Rigid attachment: the body is welded into its parent for dynamics."""
    return Joint.fixed()


def FreeFlyer() -> Joint:
    """Six-dof joint (Pinocchio's JointModelFreeFlyer): q = (x, y, z, qx, qy, qz, qw), the body
    origin in the joint frame then a unit quaternion; v = linear then angular velocity of the
    body relative to the joint frame, both in the body frame. nq = 7, nv = 6."""
    return Joint.free_flyer()


__all__ = [
    "kinematics",
    "IKResult",
    "inverse_kinematics",
    "benchmarking",
    "robots",
    "design",
    "identification",
    "Identification",
    "excitation_trajectory",
    "identify",
    "io",
    "viewer",
    "AnimationInfo",
    "animate",
    "example_robot",
    "Balance",
    "BatchResult",
    "ContactForces",
    "Counterweight",
    "LinkShape",
    "Material",
    "Shape",
    "Damper",
    "Effect",
    "IMU",
    "Simulator",
    "ExternalForce",
    "Fixed",
    "FreeFlyer",
    "Gravity",
    "GroundContact",
    "InertiaError",
    "InertiaRepair",
    "InvalidInputError",
    "Joint",
    "JointFriction",
    "JointLimit",
    "JointTorque",
    "LoopClosureError",
    "Model",
    "ModelStructureError",
    "MotionAnalysis",
    "NumericalError",
    "OdeResult",
    "PDTorque",
    "PointMassDynError",
    "PointSpring",
    "PointMasses",
    "Prismatic",
    "Revolute",
    "RigidBody",
    "RunConfig",
    "RunStatus",
    "Scene",
    "SceneError",
    "Shaking",
    "SimulationError",
    "SimulationResult",
    "SingularityError",
    "Spherical",
    "SphericalZYZ",
    "Spring",
    "StateEvent",
    "TabulatedTorque",
    "TorqueFunction",
    "WorkPrecision",
    "__version__",
    "analyze_motion",
    "balance",
    "builtin_scenes",
    "contact_forces",
    "effect_forces",
    "effect_power",
    "from_mujoco",
    "from_pinocchio",
    "energies",
    "errors",
    "load_scene",
    "pareto_front",
    "prescribed_motion",
    "rk45",
    "shaking",
    "show_meshcat",
    "simulate",
    "simulate_batch",
    "solve_ivp",
    "sweep",
    "to_mjcf",
    "torque_saturation",
    "urdf_contact_points",
    "work_precision",
]
