"""Type stubs for the compiled core (``rust/python``): bodies and their seven equimomental
point masses, joints, kinematic trees with both dynamics paths (explicit DeNOC products and
the O(n) recursion), scenes, ``simulate_scene`` and the generic ``rk45``.

Array arguments accept anything NumPy can turn into float64 (lists, integer arrays); a wrong
shape raises :class:`pointmass_dyn.errors.InvalidInputError` naming the argument. Arrays
returned are fresh float64 NumPy arrays.
"""

import os
from collections.abc import Callable, Sequence
from typing import Any, ClassVar, Literal, TypeAlias, final

import numpy as np
from numpy.typing import ArrayLike, NDArray

__version__: str
#: The widest copy of the multiversioned loops that runs: "avx512" (the batched frame kernels;
#: the rest in AVX2), "avx2" or "baseline" (POINTMASS_DYN_BASELINE=1).
cpu_dispatch: str

_Array: TypeAlias = NDArray[np.float64]
#: ``"recursive"`` (O(n) recursion) or ``"denoc"`` (explicit DeNOC matrix products).
_Method = str
#: Integration method: ``"RK45"``, ``"DOP853"``, ``"Vern9"``, ``"Adams"``, ``"Radau"``,
#: ``"RK4"``, ``"Euler"``, ``"auto"`` (case-insensitive).
_Integrator = str
#: ``"standard"`` (SciPy's step-size controller, also ``"scipy"``) or ``"pi"`` (Hairer's PI).
_Controller = str
#: A Python event: ``f(t, q, v) -> float`` (``simulate_scene``) or ``f(t, y) -> float``
#: (``rk45``), with optional ``terminal`` (bool or count) and ``direction`` attributes.
_EventFunc: TypeAlias = Callable[..., float]

class _Record:
    """A typed result (rust/python/record.rs): frozen; its fields read as attributes or as
    ``r["field"]``, and ``keys()``, ``items()`` and ``len()`` read it as the dict it replaced
    (it pickles as that dict). Declared here only: each record class has these methods."""

    def keys(self) -> list[str]: ...
    def items(self) -> list[tuple[str, Any]]: ...
    def __len__(self) -> int: ...
    def __getitem__(self, key: str) -> Any: ...

@final
class UrdfRepair(_Record):
    """A typed result (rust/python/record.rs): frozen; fields as attributes or ``r["field"]``."""

    link: str
    joint: str | None
    rules: list[str]
    mass: tuple[float, float]
    principal_moments: tuple[tuple[float, float, float], tuple[float, float, float]]
    joint_type: tuple[str, str] | None

@final
class PointMotion(_Record):
    """A typed result (rust/python/record.rs): frozen; fields as attributes or ``r["field"]``."""

    masses: _Array
    positions: _Array
    velocities: _Array
    accelerations: _Array

@final
class BearingForces(_Record):
    """A typed result (rust/python/record.rs): frozen; fields as attributes or ``r["field"]``."""

    joints: _Array
    loops: _Array
    tau: _Array

@final
class Denoc(_Record):
    """A typed result (rust/python/record.rs): frozen; fields as attributes or ``r["field"]``."""

    D: _Array
    Nl: _Array
    Nd: _Array
    N: _Array
    masses: _Array
    points: _Array

@final
class DenocRates(_Record):
    """A typed result (rust/python/record.rs): frozen; fields as attributes or ``r["field"]``."""

    D: _Array
    Nl: _Array
    Nd: _Array
    N: _Array

@final
class LoopSolverInfo(_Record):
    """A typed result (rust/python/record.rs): frozen; fields as attributes or ``r["field"]``."""

    banded: bool
    order: list[int]
    profile: int
    model_profile: int

@final
class IkSolution(_Record):
    """A typed result (rust/python/record.rs): frozen; fields as attributes or ``r["field"]``."""

    q: _Array
    residual: float
    errors: list[_Array]
    iterations: int
    restarts: int
    converged: bool
    message: str

@final
class IdentificationBase(_Record):
    """A typed result (rust/python/record.rs): frozen; fields as attributes or ``r["field"]``."""

    rank: int
    independent: list[int]
    dependent: list[int]
    coefficients: _Array
    pivots: _Array

@final
class Identified(_Record):
    """A typed result (rust/python/record.rs): frozen; fields as attributes or ``r["field"]``."""

    names: list[str]
    free: list[int]
    base: IdentificationBase
    base_names: list[str]
    beta: _Array
    std: _Array
    pi: _Array
    rss: float
    condition: float
    structural_rank: int
    residuals: _Array
    masses: list[_Array]

@final
class RigidBody:
    """A rigid body: mass (kg), centre of mass (body frame) and inertia tensor about the COM
    (body frame, standard sign convention ``I_xy = -Σ m x y``). Invalid values raise
    :class:`pointmass_dyn.errors.InertiaError`."""

    def __new__(cls, mass: float, com: ArrayLike, inertia: ArrayLike) -> RigidBody: ...
    @staticmethod
    def from_point_masses(masses: ArrayLike, positions: ArrayLike) -> RigidBody:
        """Mass, COM and inertia about the COM of point masses (``positions`` shape (n, 3))."""
    @property
    def mass(self) -> float:
        """Mass (kg)."""
    @property
    def com(self) -> _Array:
        """Centre of mass in the body frame, shape (3,)."""
    @property
    def inertia(self) -> _Array:
        """Inertia tensor about the COM, body frame, shape (3, 3)."""
    def inertia_about(self, point: ArrayLike) -> _Array:
        """Inertia about ``point`` (body frame) by the parallel-axis theorem, shape (3, 3)."""
    def point_masses(self, center: ArrayLike | None = None) -> PointMasses:
        """The seven equimomental point masses, box centred at ``center`` (default: the COM)."""

@final
class PointMasses:
    """Seven point masses with the mass, COM and inertia of a body (paper Table I layout)."""

    @property
    def masses(self) -> _Array:
        """The seven masses (kg), shape (7,); some may be negative."""
    @property
    def positions(self) -> _Array:
        """Positions in the body frame, shape (7, 3)."""
    @property
    def half_sides(self) -> _Array:
        """Half-sides ``(hx, hy, hz)`` of the box, shape (3,)."""
    @property
    def center(self) -> _Array:
        """Centre of the box in the body frame, shape (3,)."""
    def to_body(self) -> RigidBody:
        """The rigid body these points represent (mass, COM and inertia rebuilt from them)."""

@final
class Joint:
    """A joint; build with the factories (or ``pmd.Revolute(axis)`` etc.)."""

    @staticmethod
    def revolute(axis: ArrayLike) -> Joint:
        """Rotation about ``axis`` (joint frame); q is the angle (rad)."""
    @staticmethod
    def prismatic(axis: ArrayLike) -> Joint:
        """Translation along ``axis`` (joint frame); q is the displacement (m)."""
    @staticmethod
    def spherical_zyz() -> Joint:
        """ZYZ Euler angles ``(φ, θ, ψ)`` with Euler rates as speeds; singular at sin θ = 0."""
    @staticmethod
    def spherical() -> Joint:
        """Unit quaternion ``(x, y, z, w)``; speeds: angular velocity in the body frame."""
    @staticmethod
    def fixed() -> Joint:
        """Rigid attachment: the body is welded into its parent."""
    @staticmethod
    def free_flyer() -> Joint:
        """Six dof: q = (x, y, z, qx, qy, qz, qw), v = (linear, angular) in the body frame."""
    @property
    def kind(self) -> str:
        """``'Revolute'``, ``'Prismatic'``, ``'SphericalZYZ'``, ``'Spherical'``, ``'Fixed'`` or
        ``'FreeFlyer'``."""
    @property
    def nq(self) -> int:
        """Number of configuration coordinates."""
    @property
    def nv(self) -> int:
        """Number of speeds."""
    @property
    def axis(self) -> _Array | None:
        """Unit axis, shape (3,), of a revolute or prismatic joint; ``None`` otherwise."""

@final
class Model:
    """A kinematic tree of rigid bodies, each represented by seven point masses.

    ``q`` and ``v`` list the joints in the order the bodies were added; gravity is applied
    only when given (``gravity=None`` means none). Safe to use from many threads at once
    (each call takes its own workspace; long calls release the GIL)."""

    def __new__(cls) -> Model: ...
    def add_body(
        self,
        body: RigidBody,
        joint: Joint,
        parent: int | str | None = -1,
        translation: ArrayLike | None = None,
        rotation: ArrayLike | None = None,
        name: str | None = None,
        point_mass_center: ArrayLike | None = None,
    ) -> int:
        """Adds ``body`` on ``joint`` below ``parent``; returns its index.

        ``parent`` is the parent body's name or index (-1, ``"world"`` or None: the world; an
        unknown name is a ``ModelStructureError`` listing the names). ``translation`` and
        ``rotation`` place the joint frame in the parent's body frame; ``name`` is the body's
        unique name (default ``"body<index>"``); ``point_mass_center`` is where the box of
        the seven point masses is centred, body frame (default: the COM).

        ``rotation`` must be a rotation to 1e-9; it is re-orthonormalised, and one within 4ε of
        a quarter or half turn about coordinate axes is taken as exactly that turn."""
    @property
    def nq(self) -> int:
        """Length of ``q``."""
    @property
    def nv(self) -> int:
        """Length of ``v``."""
    @property
    def nbodies(self) -> int:
        """Number of bodies, Fixed ones included."""
    @property
    def nlinks(self) -> int:
        """Moving links (bodies on Fixed joints are welded into their parent's link)."""
    @property
    def body_names(self) -> list[str]:
        """Names of all bodies, in the order added."""
    @property
    def link_names(self) -> list[str]:
        """Names of the bodies that define each moving link, in q/v order."""
    @property
    def total_mass(self) -> float:
        """Sum of the body masses (kg)."""
    def body_info(self, index: int) -> tuple[str, str, int, int]:
        """(name, joint kind, parent index or -1, link index or -1) of body ``index``."""
    def joint_slices(self) -> list[tuple[int, int, int, int]]:
        """(q index, v index, nq, nv) of each moving link's joint."""
    def neutral(self) -> _Array:
        """The neutral configuration (zeros, identity quaternions), shape (nq,)."""
    def placements(self, q: ArrayLike) -> tuple[_Array, _Array]:
        """World placements of every body: rotations (nbodies, 3, 3), origins (nbodies, 3)."""
    def point_masses(self, q: ArrayLike) -> tuple[_Array, _Array]:
        """Masses (nlinks, 7) and world positions (nlinks, 7, 3) of every link's points."""
    def body_poses(self, q: ArrayLike) -> dict[str, _Array]:
        """World poses of everything a viewer draws, at one configuration (q (nq,)) or N
        (q (N, nq), a leading N axis on every array): ``rotations`` (nbodies, 3, 3),
        ``origins``, ``joint_origins`` (each joint frame's origin), ``joint_axes`` (unit axis of
        revolute and prismatic joints, zero otherwise) (nbodies, 3), ``points`` (nlinks, 7, 3)
        and per cut joint ``loop_a``, ``loop_b`` (its two frames' origins), ``loop_axes``
        (nloops, 3)."""
    # Frames, Jacobians, centre of mass (docs/kinematics.md); six-vectors angular first.
    @property
    def frame_names(self) -> list[str]:
        """Every body's name (URDF links welded by fixed joints included), then the frames
        added with ``add_frame``."""
    def add_frame(
        self, name: str, body: str | int, translation: ArrayLike | None = None,
        rotation: ArrayLike | None = None,
    ) -> int:
        """Adds a frame fixed on ``body``; returns its index among the added frames."""
    def frame_placement(self, frame: str | int, q: ArrayLike) -> tuple[_Array, _Array]:
        """(rotation (3, 3), translation (3,)) of ``frame`` in the world, or (N, 3, 3), (N, 3)
        for q (N, nq)."""
    def point_path(
        self, frame: str | int, point: ArrayLike, q: ArrayLike, v: ArrayLike | None = None
    ) -> tuple[_Array, _Array | None]:
        """World positions (N, 3) of ``point`` (in ``frame``) at q (N, nq); with v (N, nv),
        its velocities (N, 3)."""
    def frame_jacobian(
        self, frame: str | int, q: ArrayLike, reference: str = "local"
    ) -> _Array:
        """(6, nv) Jacobian, or (N, 6, nv) for q (N, nq); ``reference``: "local",
        "world" or "local_world_aligned" (Pinocchio's). ``frame``: a name or an index in
        ``frame_names`` (as everywhere a frame is asked for)."""
    def frame_jacobian_dot(
        self, frame: str | int, q: ArrayLike, v: ArrayLike, reference: str = "local"
    ) -> _Array:
        """(6, nv) time derivative of ``frame_jacobian`` in the same reference."""
    def frame_motion(
        self, frame: str | int, q: ArrayLike, v: ArrayLike, a: ArrayLike | None = None,
        reference: str = "local",
    ) -> tuple[_Array, _Array]:
        """(J v, J a + J̇ v) of ``frame`` in ``reference``, (6,) each, angular first;
        ``a=None`` is zero (the acceleration is then ``J̇ v``)."""
    def center_of_mass(self, q: ArrayLike, jacobian: bool = False) -> Any:
        """COM of the moving bodies (3,) or (N, 3); with ``jacobian=True`` also the COM
        Jacobian (3, nv) or (N, 3, nv)."""
    def center_of_mass_motion(
        self, q: ArrayLike, v: ArrayLike, a: ArrayLike | None = None
    ) -> tuple[_Array, _Array, _Array]:
        """COM position, velocity and acceleration; ``a=None`` is zero."""
    def centroidal(
        self, q: ArrayLike, v: ArrayLike | None = None, a: ArrayLike | None = None
    ) -> dict[str, _Array]:
        """``A`` (A_g, 6 × nv, [k_G; p], about the centre of mass, world axes) and with ``v``
        ``momentum`` (A_g v) and ``rate`` (A_g a + Ȧ_g v; with a=None the bias Ȧ_g v)."""
    def independent_map(
        self, q: ArrayLike, independent: Any = None
    ) -> tuple[_Array, list[int]]:
        """G (nv, k) with v = G v_I for the independent speeds ``independent`` (v indices or
        body names; None: chosen from the constraint Jacobian), and their v indices."""
    def _inverse_kinematics(
        self, tasks: list, q0: ArrayLike, limits: bool, tol: float, max_iterations: int,
        restarts: int, seed: int,
    ) -> IkSolution: ...
    def denoc(self, q: ArrayLike) -> Denoc:
        """The DeNOC matrices at ``q``: keys ``D``, ``Nl``, ``Nd``, ``N``, ``masses`` (7n,)
        and ``points`` (7n, 3)."""
    def denoc_rates(self, q: ArrayLike, v: ArrayLike) -> DenocRates:
        """Time derivatives of the DeNOC matrices: keys ``D``, ``Nl``, ``Nd``, ``N``."""
    def mass_matrix(self, q: ArrayLike, method: _Method = "recursive") -> _Array:
        """Generalized inertia matrix (GIM) ``Nᵀ M N``, shape (nv, nv)."""
    def convective_matrix(self, q: ArrayLike, v: ArrayLike) -> _Array:
        """Convective matrix ``C = Nᵀ M Ṅ``, shape (nv, nv)."""
    def gravity_forces(self, q: ArrayLike, gravity: ArrayLike) -> _Array:
        """Generalized gravity force ``Nᵀ f^G`` (right-hand side; Pinocchio's
        ``computeGeneralizedGravity`` is its negative), shape (nv,)."""
    def generalized_forces(self, q: ArrayLike, forces: ArrayLike) -> _Array:
        """``Nᵀ f`` for world forces on the point masses, shape (nlinks, 7, 3) or
        (7·nlinks, 3); returns shape (nv,)."""
    def bias_forces(self, q: ArrayLike, v: ArrayLike, gravity: ArrayLike | None = None) -> _Array:
        """``C v − τ_g`` (Pinocchio's ``nonLinearEffects``), shape (nv,)."""
    def forward_dynamics(
        self,
        q: ArrayLike,
        v: ArrayLike,
        tau: ArrayLike,
        gravity: ArrayLike | None = None,
        external: ArrayLike | None = None,
        method: _Method = "recursive",
    ) -> _Array:
        """Accelerations from ``I a + C v = τ + τ_g + τ_ext``, shape (nv,). ``external``:
        one wrench [moment about the link origin; force] per moving link, shape (nlinks, 6).
        With loops, ``I a + C v = τ + τ_g + τ_ext + Jᵀλ`` and ``J a + J̇ v = 0``: the
        accelerations keep the loops closed (redundant constraints allowed); raises
        ``SingularityError`` for a locked mechanism (no freedom of motion)."""
    def inverse_dynamics(
        self,
        q: ArrayLike,
        v: ArrayLike,
        a: ArrayLike,
        gravity: ArrayLike | None = None,
        external: ArrayLike | None = None,
        method: _Method = "recursive",
        actuated: Sequence[int | str] | None = None,
    ) -> _Array:
        """Joint forces ``τ = I a + C v − τ_g − τ_ext``, shape (nv,). With loops, ``actuated``
        (v indices or body names) is required: the forces of those coordinates alone (zero
        elsewhere) that, with the cut joints' forces, produce ``a`` (which must satisfy the
        loops: see :meth:`assemble_acceleration`)."""
    def inverse_dynamics_derivatives(
        self, q: ArrayLike, v: ArrayLike, a: ArrayLike, gravity: ArrayLike | None = None
    ) -> tuple[_Array, _Array, _Array]:
        """``(∂τ/∂q, ∂τ/∂v, ∂τ/∂a = M)``, each (nv, nv); q perturbed in the tangent space
        (``q ⊕ δ``, as Pinocchio's ``computeRNEADerivatives``; docs/derivatives.md). Trees
        only. New C-ordered arrays; from nv = 64 on, views of one (3, nv, nv) array."""
    def forward_dynamics_derivatives(
        self, q: ArrayLike, v: ArrayLike, tau: ArrayLike, gravity: ArrayLike | None = None
    ) -> tuple[_Array, _Array, _Array]:
        """``(∂q̈/∂q, ∂q̈/∂v, ∂q̈/∂τ = M⁻¹)``, each (nv, nv), as Pinocchio's
        ``computeABADerivatives`` (docs/derivatives.md). Trees only. New C-ordered arrays;
        from nv = 64 on, views of one (3, nv, nv) array."""
    def kinetic_energy(self, q: ArrayLike, v: ArrayLike) -> float:
        """Kinetic energy ``½ vᵀ I v`` (J), rotor inertia included."""
    def potential_energy(self, q: ArrayLike, gravity: ArrayLike) -> float:
        """Gravitational potential energy ``−Σ m_ij g·x_ij`` (J), zero at the world origin."""
    def velocity_to_qdot(self, q: ArrayLike, v: ArrayLike) -> _Array:
        """``q̇`` from ``v`` (differs from ``v`` only for quaternion joints), shape (nq,)."""
    def add_loop(
        self,
        body_a: int | str | None,
        body_b: int | str | None,
        joint: Joint,
        translation_a: ArrayLike | None = None,
        translation_b: ArrayLike | None = None,
        rotation_a: ArrayLike | None = None,
        rotation_b: ArrayLike | None = None,
        name: str | None = None,
    ) -> int:
        """Closes a kinematic loop with a cut joint (``Revolute``, ``Prismatic``, ``Spherical``
        or ``Fixed``) between a frame on ``body_a`` and one on ``body_b`` (index or name; -1,
        None or ``"world"`` for the ground). Each frame is ``(rotation, translation)`` in its
        body's frame; the axis is in frame a. Returns the loop's index. Raises
        ``ModelStructureError`` for unknown bodies or a loop joining a body to itself (or to
        a body welded to it)."""
    @property
    def nloops(self) -> int:
        """Number of cut joints (closed loops)."""
    @property
    def nconstraints(self) -> int:
        """Scalar loop constraints: 3 per spherical, 5 per revolute or prismatic, 6 per fixed
        cut joint (rows of :meth:`constraint_jacobian`)."""
    @property
    def loop_names(self) -> list[str]:
        """The cut joints' names in order."""
    def constraint_residual(self, q: ArrayLike) -> _Array:
        """Position-level residual of every cut joint, shape (nconstraints,), in frame a's
        axes: position rows (m), then orientation rows (rad); zero when the loops are closed."""
    def constraint_jacobian(self, q: ArrayLike) -> _Array:
        """Velocity-level constraint Jacobian ``J``, shape (nconstraints, nv): ``J v = 0``
        keeps the loops closed. Rows of redundant constraints (a planar loop closed by a
        spatial joint) are zero or dependent."""
    def loop_solver_info(self) -> LoopSolverInfo:
        """How the loop solver factors this model (docs/loops.md §3): ``banded`` (the banded
        QRs of long mechanisms, or the dense ones), ``order`` (the v indices in the order the
        factorisations take them: the model's own unless the banded solver reorders),
        ``profile`` (the structural work of that order: per cut-joint row, the spans of its
        ``Jᵀ`` and ``L⁻¹Jᵀ`` columns) and ``model_profile`` (the same for the model's order)."""
    def assemble(
        self,
        q_guess: ArrayLike,
        fixed: Sequence[int | str] | int | str | None = None,
        tol: float = 1e-12,
        max_iterations: int = 50,
    ) -> _Array:
        """The closed configuration nearest ``q_guess`` (Gauss–Newton, minimum-norm steps)
        with the coordinates in ``fixed`` held (q indices, or body names for all of a body's
        joint coordinates). Raises ``LoopClosureError`` naming the loop that cannot close."""
    def assemble_velocity(
        self,
        q: ArrayLike,
        v_guess: ArrayLike,
        fixed: Sequence[int | str] | int | str | None = None,
    ) -> _Array:
        """``v_guess`` projected onto ``J v = 0``, nearest to it with the ``fixed`` speeds held."""
    def assemble_acceleration(
        self,
        q: ArrayLike,
        v: ArrayLike,
        a_guess: ArrayLike,
        fixed: Sequence[int | str] | int | str | None = None,
    ) -> _Array:
        """``a_guess`` projected onto ``J a + J̇ v = 0``, nearest to it with the ``fixed``
        entries held (e.g. a prescribed crank acceleration)."""
    def constraint_forces(
        self,
        q: ArrayLike,
        v: ArrayLike,
        tau: ArrayLike,
        gravity: ArrayLike | None = None,
        external: ArrayLike | None = None,
    ) -> _Array:
        """Per loop ``[fx, fy, fz, mx, my, mz]`` (shape (nloops, 6)): the force and moment
        the cut joint applies to body b (minus those on body a) at frame b's origin, in frame
        a's axes, under ``tau``. Components along the joint's free motion are zero; where
        constraints are redundant the minimum-norm set (only their resultant is defined)."""
    def add_coupling(
        self,
        joint: int | str,
        reference: int | str,
        ratio: float = 1.0,
        offset: float = 0.0,
        name: str | None = None,
    ) -> int:
        """Couples two revolute/prismatic joints, ``q_joint = ratio · q_reference + offset``
        (a mimic joint, a gear), as one holonomic constraint row after the loops' (the loop
        solver holds it: docs/couplings.md). Joints by body index, body name or URDF joint
        name. Returns the coupling's index. Raises ``InvalidInputError`` naming the argument
        for a joint coupled to itself or already coupled, a cycle of couplings, an unknown
        joint, a joint that is not 1-dof and a non-finite ratio or offset."""
    @property
    def ncouplings(self) -> int:
        """Number of joint couplings."""
    @property
    def couplings(self) -> list[tuple[str, str, str, float, float]]:
        """``(name, joint body, reference body, ratio, offset)`` of each coupling."""
    def coupling_forces(
        self, q: ArrayLike, v: ArrayLike, tau: ArrayLike, gravity: ArrayLike | None = None
    ) -> _Array:
        """Each coupling's generalized force on its joint under ``tau`` (shape
        (ncouplings,)); the reference joint feels ``−ratio`` times it."""
    def set_armature(self, joint: int | str, value: float | ArrayLike) -> None:
        """Sets a joint's rotor inertia (armature, kg m² or kg): one number, or one per speed
        (3 for a spherical joint), finite and ≥ 0; added to the mass matrix's diagonal in
        every algorithm. Refused on a free flyer and a fixed joint."""
    @property
    def armature(self) -> _Array:
        """Rotor inertia of every speed, shape (nv,) (zeros where none is set)."""
    def body(self, body: int | str) -> RigidBody:
        """Body ``body``'s own rigid body (mass, COM, inertia in its frame), as added."""
    def with_body(self, body: int | str, rigid_body: RigidBody) -> Model:
        """A copy with body ``body``'s rigid body replaced (joint, placement, loops, names
        kept); this model is unchanged."""
    def point_motion(self, q: ArrayLike, v: ArrayLike, a: ArrayLike) -> PointMotion:
        """Every link's seven point masses in motion at one state: keys ``masses`` (nlinks,
        7), ``positions``, ``velocities``, ``accelerations`` (nlinks, 7, 3), world axes, no
        gravity."""
    def shaking(
        self, q: ArrayLike, v: ArrayLike, a: ArrayLike, about: ArrayLike | None = None
    ) -> tuple[_Array, _Array]:
        """Shaking force and moment ``(−Σ m a, −Σ m (r − O) × a)`` over every point mass,
        gravity excluded, about ``about`` (world; default the origin): at one state (q (nq,),
        v, a (nv,)) each (3,), or at N (q (N, nq), v, a (N, nv)) each (N, 3). Ctrl-C stops
        it: the ``KeyboardInterrupt`` carries the states done as ``.result``, a dict with
        ``force``, ``moment`` (states done, 3), ``states`` (how many of N) and ``message``."""
    def bearing_forces(
        self,
        q: ArrayLike,
        v: ArrayLike,
        a: ArrayLike,
        gravity: ArrayLike | None = None,
        external: ArrayLike | None = None,
        actuated: Sequence[int | str] | None = None,
        frame: Literal["joint", "world"] = "joint",
    ) -> BearingForces:
        """The wrench every joint transmits at one state: keys ``joints`` (nlinks, 6),
        ``[force; moment]`` the parent applies to the link's subtree at the link origin, in
        the link's axes (``frame="joint"``) or the world's; ``loops`` (nloops, 6), the cut
        joints' wrenches as :meth:`constraint_forces` gives them; ``tau`` (nv,), the joint
        forces (with loops the ``actuated`` ones, required as for
        :meth:`inverse_dynamics`, zero elsewhere)."""
    def point_regressor(
        self,
        q: ArrayLike,
        v: ArrayLike,
        a: ArrayLike,
        points: Sequence[tuple[int | str, ArrayLike]] | None = None,
        gravity: ArrayLike | None = None,
    ) -> dict[str, _Array]:
        """Per state and point: ``positions``, ``accelerations`` ((N,) P, 3) and
        ``generalized`` ((N,) P, nv) ``= J_pᵀ (a_p − g)``. ``points``: None for all point
        masses, or (body, point in its frame) pairs. Ctrl-C stops it: the
        ``KeyboardInterrupt`` carries the states done as ``.result``, this dict cut to them,
        with ``states`` (how many of N) and ``message``."""
    @staticmethod
    def from_urdf(
        path: Any,
        *,
        root_joint: Literal["fixed", "free"] | None = None,
        repair: bool | dict[str, Any] | Any | None = None,
        package_dirs: Any | None = None,
        mimic: bool = True,
    ) -> Model:
        """A robot from a URDF file (``path``: str or os.PathLike): revolute, continuous
        (q = angle), prismatic and fixed joints; joint order and body (link) names as
        Pinocchio's ``buildModelFromUrdf``. The root link is welded to the world
        (``root_joint=None`` or ``"fixed"``) or moves on a :func:`FreeFlyer` joint named
        ``"root_joint"``, first in q and v (``"free"``, as
        ``buildModelFromUrdf(path, JointModelFreeFlyer())``). Raises
        :class:`pointmass_dyn.errors.UrdfError` naming the file and the element; warns with
        :class:`pointmass_dyn.errors.UrdfWarning` (ignored elements, undeclared namespace
        prefixes). ``<mimic>`` joints are couplings (:meth:`add_coupling`, as Pinocchio's
        ``mimic=True``); ``mimic=False`` loads them as independent joints, with a warning.

        ``repair`` (``True``, a dict or :class:`pointmass_dyn.InertiaRepair`) allows
        MuJoCo-style repairs of non-physical inertials (``balance_inertia``, ``bound_mass``,
        ``bound_inertia``) and welds moving joints that move no mass (``weld_massless``);
        every change is listed in one :class:`pointmass_dyn.errors.UrdfRepairWarning` and in
        :attr:`repairs` (docs/robots.md).

        ``<visual>`` elements become :attr:`visuals`; mesh URIs (``package://...``) are looked
        for in ``package_dirs`` (a path or a list), ``ROS_PACKAGE_PATH`` and the file's
        ancestors, as Pinocchio does; one ``UrdfWarning`` names those not found
        (docs/visualisation.md §2)."""
    @property
    def visuals(self) -> list[dict[str, Any]]:
        """The visual geometry (URDF ``<visual>``, MJCF geoms): one dict per shape with
        ``body``, ``body_name``, ``kind`` ("box", "cylinder", "sphere", "capsule",
        "ellipsoid", "mesh"), ``rotation`` (3×3) and ``translation`` in the body frame, its
        sizes (``size``; ``radius``, ``length``; ``radii``; ``uri``, ``path``, ``scale``) and
        ``rgba`` or None (docs/visualisation.md §2)."""
    @property
    def name(self) -> str:
        """The model's name (URDF ``<robot name>``, MJCF ``<mujoco model>``; "" if none)."""
    def set_visuals(self, visuals: list[dict[str, Any]], *, name: str | None = None) -> None:
        """Replaces :attr:`visuals` (dicts as it gives them; checked, errors name
        ``visuals[k]``) and, if given, the name. The dynamics is unchanged."""
    @staticmethod
    def from_mujoco(mj_model: Any) -> Model:
        """Our model of a compiled ``mujoco.MjModel``: same as
        :func:`pointmass_dyn.from_mujoco` (docs/robots.md)."""
    @staticmethod
    def from_pinocchio(pin_model: Any) -> Model:
        """Our model of a ``pinocchio.Model``: same as :func:`pointmass_dyn.from_pinocchio`
        (docs/robots.md)."""
    def reference_poses(self, srdf: str | os.PathLike[str]) -> dict[str, _Array]:
        """``{pose name: q}`` of the SRDF's ``<group_state>`` elements ("standing", …), as
        Pinocchio's ``loadReferenceConfigurations``: from the neutral configuration, the named
        joints set (URDF names); joints the model does not move are skipped with one
        ``UrdfWarning``. Raises ``UrdfError`` naming the file, pose and joint."""
    @property
    def repairs(self) -> list[UrdfRepair]:
        """What ``from_urdf(..., repair=...)`` changed: one record per link or welded joint
        (``link``, ``joint``, ``rules``, ``mass`` and ``principal_moments`` as (before,
        after), ``joint_type`` (before, after) for welds). Empty otherwise."""
    @staticmethod
    def _from_parts(
        parts: list[tuple[Any, ...]], ranges: Sequence[tuple[float, float] | None] | None = None
    ) -> Model:
        """For :mod:`pointmass_dyn.importers`: bodies in tree order, each ``(name, parent,
        joint, translation, rotation, joint_name, mass, com, inertia)``; ``ranges``: per part,
        its joint's ``(lower, upper)`` or None."""
    @property
    def joint_names(self) -> list[str]:
        """Names of the moving joints in q/v order (URDF joint names; for models built with
        ``add_body``, the names of the bodies that define each link)."""
    def joint_limits(self) -> dict[str, tuple[float, float, float, float]]:
        """``{joint: (lower, upper, effort, velocity)}`` in q/v order; ±inf where the URDF
        gives no bound (continuous joints have no position bounds)."""
    def joint_dynamics(self) -> dict[str, tuple[float, float]]:
        """``{joint: (damping, friction)}`` from URDF ``<dynamics>``, in q/v order (0 where
        absent); recorded, not applied by the model."""

#: Effect families, as ``disable`` names them.
_Family: TypeAlias = Literal[
    "gravity", "springs", "dampers", "friction", "torques", "external", "contact", "limits"
]

@final
class Effect:
    """Something a scene applies to its model; build with the factories (``pmd.Gravity``,
    ``pmd.Spring``, ...). Each is computed only when declared; SI units, radians."""

    def __init__(self, type: str, /, **keys: Any) -> None:
        """The effect of scene-file ``type`` (``"spring"``, ``"torque"``, ``"external"``, ...)
        with that type's keys as keyword arguments (README "Effects"; the table in
        rust/effects/mod.rs), arrays as NumPy arrays or sequences; what every factory calls.
        Errors name the key."""

    def with_parameter(self, name: str, value: ArrayLike) -> Effect:
        """A copy with one parameter replaced and checked: gravity ``g``; a spring's
        ``stiffness``, ``rest``; a damper's ``damping``; friction's ``friction``, ``v_eps``;
        a point spring's ``stiffness``, ``rest_length``, ``damping``; a constant torque's
        ``tau``, a tabulated torque's ``values`` (same times), a PD torque's ``kp``, ``kd``."""
    @property
    def g(self) -> _Array | None:
        """A gravity effect's ``g`` (3,); None for other effects."""
    @property
    def plane(self) -> tuple[_Array, float] | None:
        """A ground contact's plane ``n · x = height`` as ``(n, height)``, ``n`` (3,) its unit
        normal out of the ground; None for other effects."""

    __hash__: ClassVar[None]  # type: ignore[assignment]
    @staticmethod
    def gravity(g: ArrayLike | None = None) -> Effect:
        """Uniform gravity ``g`` (m/s², world frame); default ``(0, 0, -9.81)``."""
    @staticmethod
    def torque_function(f: Callable[[float, _Array, _Array], ArrayLike], name: str | None = None) -> Effect:
        """Generalized forces ``f(t, q, v) -> (nv,)`` from Python (one Python call per evaluation)."""
    def with_torque_limit(self, limit: ArrayLike | str | None) -> Effect:
        """A torque effect clamped per speed at ``±limit`` (``"effort"``: the URDF's)."""
    @property
    def torque_limit(self) -> NDArray[np.float64] | float | str | None:
        """A torque effect's limit (``"effort"`` until a scene fills it in), else None."""
    def torque_limit_per_speed(self, model: Model) -> NDArray[np.float64]:
        """The limit on each of ``model``'s speeds (inf where unlimited or not driven)."""
    @property
    def contact_parameters(self) -> ContactParameters | None:
        """A ground contact's law parameters (``stiffness``/``damping`` None until a scene
        fills in their defaults); None for other effects."""
    def contact_state(
        self, model: Model, q: ArrayLike, v: ArrayLike
    ) -> ContactStates:
        """A ground contact's ``position`` (N, P, 3), ``penetration`` (N, P),
        ``normal_force`` (N, P) and ``force`` (N, P, 3) along states ``q`` (N, nq), ``v``."""
    @property
    def name(self) -> str:
        """The effect's name: the one given, else its family's, e.g. ``'gravity'``."""
    @property
    def kind(self) -> _Family:
        """The effect's family (what ``disable`` switches off)."""
    def to_dict(self) -> dict[str, Any]:
        """The effect's scene-file ``[[effect]]`` table (``type``, ``name`` and its keys, SI
        units, radians). A torque function raises ``InvalidInputError``."""
    def __eq__(self, other: object, /) -> bool: ...

@final
class StateEvent:
    """``q[index]`` (``variable='q'``) or ``v[index]`` (``'v'``) crossing ``value``;
    ``direction`` +1/-1 keeps only rising/falling crossings; ``terminal`` (bool or count)
    stops the run at that occurrence. Evaluated in Rust."""

    def __new__(
        cls,
        variable: Literal["q", "v"],
        index: int,
        value: float = 0.0,
        direction: int = 0,
        terminal: bool | int | None = None,
    ) -> StateEvent: ...
    @property
    def terminal(self) -> int:
        """Occurrence that stops the run (0: never)."""
    @property
    def direction(self) -> int:
        """-1, 0 or +1."""

@final
class RunConfig:
    """One run's settings (``simulate``, ``simulate_batch``, ``solve_ivp``), ``None`` where
    nothing is said: a run takes the keywords of its call, else this, else the scene's
    ``[simulate]`` table, else the default (docs/architecture.md). Frozen: vary it with
    :meth:`replace`; equal when every setting is."""

    def __new__(
        cls,
        t_span: ArrayLike | None = None,
        *,
        rtol: ArrayLike | None = None,
        atol: ArrayLike | None = None,
        t_eval: ArrayLike | None = None,
        first_step: float | None = None,
        max_step: float | None = None,
        max_steps: int | None = None,
        method: _Integrator | None = None,
        dt: float | None = None,
        controller: _Controller | None = None,
        stiffness: Literal["warn", "stop", "off"] | None = None,
        disable: _Family | Sequence[_Family] | None = None,
        energy: bool | None = None,
        power: bool | None = None,
        dense_output: bool | None = None,
    ) -> RunConfig: ...
    @property
    def t_span(self) -> tuple[float, float] | None: ...
    @property
    def rtol(self) -> float | _Array | None:
        """A number, or one per state component."""
    @property
    def atol(self) -> float | _Array | None: ...
    @property
    def t_eval(self) -> _Array | None: ...
    @property
    def first_step(self) -> float | None: ...
    @property
    def max_step(self) -> float | None: ...
    @property
    def max_steps(self) -> int | None: ...
    @property
    def method(self) -> str | None:
        """SciPy's spelling: ``"RK45"``, ``"DOP853"``, ``"Radau"``, ``"RK4"``, ``"Euler"``, ``"auto"``."""
    @property
    def dt(self) -> float | None: ...
    @property
    def controller(self) -> Literal["standard", "pi"] | None: ...
    @property
    def stiffness(self) -> Literal["warn", "stop", "off"] | None: ...
    @property
    def disable(self) -> tuple[str, ...] | None:
        """The effect families switched off (``()``: none)."""
    @property
    def energy(self) -> bool | None: ...
    @property
    def power(self) -> bool | None: ...
    @property
    def dense_output(self) -> bool | None: ...
    def as_dict(self) -> dict[str, Any]:
        """The settings given, by keyword (``RunConfig(**d)`` rebuilds it)."""
    def replace(self, **changes: Any) -> RunConfig:
        """A copy with the given settings replaced (``None`` unsets one)."""

@final
class Scene:
    """A model, the effects it declares, its initial state and integrator settings."""

    def __new__(
        cls,
        model: Model,
        q0: ArrayLike | None = None,
        v0: ArrayLike | None = None,
        effects: Sequence[Effect] | None = None,
        t_span: ArrayLike | None = None,
        rtol: float | None = None,
        atol: float | None = None,
        name: str | None = None,
        description: str | None = None,
        disable: _Family | Sequence[_Family] | None = None,
        *,
        method: str | None = None,
        dt: float | None = None,
        max_step: float | None = None,
        max_steps: int | None = None,
        first_step: float | None = None,
    ) -> Scene:
        """``q0`` defaults to the neutral configuration, ``v0`` to zero; only the declared
        ``effects`` act (none: no gravity); joint and body names and table widths are checked
        against the model here. ``disable``: families switched off by default.

        A new scene has only the run settings given here (``t_span``, ``rtol``, ``atol``,
        ``method``, ``dt``, ``max_step``, ``max_steps``, ``first_step``, ``disable``); the
        others are ``None`` and ``simulate`` uses its defaults for them. A scene built from a
        loaded scene's ``model`` therefore does not take that scene's settings: vary a
        loaded scene with :meth:`replace`, which keeps every setting not given."""
    def forward_dynamics_derivatives(
        self,
        q: ArrayLike,
        v: ArrayLike,
        tau: ArrayLike | None = None,
        t: float = 0.0,
        disable: _Family | Sequence[_Family] | None = None,
    ) -> Any:
        """``{"dq": ∂q̈/∂q, "dv": ∂q̈/∂v, "dtau": M⁻¹, "numerical": [names]}`` (a record,
        indexable by these names) of the scene's
        accelerations with its enabled effects (plus ``tau``); ``numerical`` names the effects
        differentiated by central differences (torque callbacks, external loads). With closed
        loops, those of the constrained dynamics (``dtau`` the constrained compliance;
        docs/mechanisms.md)."""
    def inverse_dynamics_derivatives(
        self,
        q: ArrayLike,
        v: ArrayLike,
        a: ArrayLike,
        t: float = 0.0,
        disable: _Family | Sequence[_Family] | None = None,
    ) -> Any:
        """``{"dq", "dv", "da", "numerical"}`` (a record, indexable by these names) of
        ``τ = ID(q, v, a) − τ_effects(t, q, v)``.
        Scenes without closed loops."""
    def state_jacobian(
        self, y: ArrayLike, t: float = 0.0, disable: _Family | Sequence[_Family] | None = None
    ) -> _Array | None:
        """``∂ẏ/∂y`` of ``y = [q; v]`` (q's own coordinates), shape (nq+nv, nq+nv), as the
        implicit integrators use it (with closed loops, of the constrained dynamics)."""
    def replace(
        self,
        model: Model | None = None,
        effects: Sequence[Effect] | None = None,
        *,
        q0: ArrayLike | None = None,
        v0: ArrayLike | None = None,
        t_span: ArrayLike | None = None,
        rtol: float | None = None,
        atol: float | None = None,
        name: str | None = None,
        description: str | None = None,
        disable: _Family | Sequence[_Family] | None = None,
        method: str | None = None,
        dt: float | None = None,
        max_step: float | None = None,
        max_steps: int | None = None,
        first_step: float | None = None,
    ) -> Scene:
        """A copy with what is given replaced and everything else kept: the model (of the
        same sizes), the effects (checked against it), the start state (``q0`` normalised),
        name, description and any run setting. Raises ``InvalidInputError`` naming the
        argument."""
    def to_toml(self) -> str:
        """The scene as scene-file text that ``Scene.from_toml`` reads back as an equal scene:
        the model inline (bodies, joints, placements, point-mass centres, loops, couplings,
        armature; joint names, limits, repairs and visuals under ``[records]``), every effect,
        the start state and every run setting. A torque function raises
        ``InvalidInputError`` naming the effect."""
    def write(self, path: str | os.PathLike[str]) -> None:
        """Writes :meth:`to_toml` to ``path`` (``load_scene(path)`` reads it back)."""
    @staticmethod
    def from_toml(text: str, file: str = "<string>") -> Scene:
        """Parses a scene from TOML text; raises :class:`pointmass_dyn.errors.SceneError`
        naming ``file`` and the key."""
    @staticmethod
    def from_file(path: str | os.PathLike[str]) -> Scene:
        """Reads a scene file: only a regular file of at most 128 MiB (a FIFO, a device or a
        directory is refused before it is opened); raises
        :class:`pointmass_dyn.errors.SceneError` naming the file."""
    @property
    def model(self) -> Model:
        """A copy of the scene's model."""
    @property
    def q0(self) -> _Array:
        """Initial configuration, shape (nq,), in radians (quaternions normalised)."""
    @property
    def v0(self) -> _Array:
        """Initial speeds, shape (nv,)."""
    @property
    def effects(self) -> list[Effect]:
        """The declared effects."""
    @property
    def name(self) -> str: ...
    @property
    def description(self) -> str: ...
    @property
    def t_span(self) -> tuple[float, float] | None:
        """Default integration interval, if the scene sets one."""
    @property
    def rtol(self) -> float | None: ...
    @property
    def atol(self) -> float | None: ...
    @property
    def max_step(self) -> float | None: ...
    @property
    def max_steps(self) -> int | None: ...
    @property
    def first_step(self) -> float | None: ...
    @property
    def method(self) -> str | None:
        """Integration method of the scene's ``[simulate]`` table, or ``None``."""
    @property
    def dt(self) -> float | None:
        """Fixed step (``[simulate] dt``) of RK4 and Euler, or ``None``."""
    @property
    def disable(self) -> list[str] | None:
        """Effect families the scene switches off (``[simulate] disable``), or ``None``."""

@final
class DenseSolution:
    """Dense output of an ``rk45`` run, as SciPy's ``OdeSolution``."""

    def __call__(self, t: ArrayLike) -> _Array:
        """The state at ``t``: shape (n,) for a scalar, (n, len(t)) for a 1-D array."""
    @property
    def ts(self) -> _Array:
        """Step boundaries."""

@final
class _Simulator:
    """The stepping simulator (``pointmass_dyn.Simulator`` wraps it; docs/control.md)."""

    def __init__(self, scene: Scene, **settings: Any) -> None:
        """``settings``: ``method``, ``rtol``, ``atol``, ``dt``, ``disable``, ``first_step``,
        ``max_step``, ``t_eval``, ``control_period`` (0.001), ``control`` (``"torque"`` or
        ``"pd"``), ``record`` (True), ``t0`` (0.0): those of ``pointmass_dyn.Simulator``."""
    t: float
    nq: int
    control_period: float
    method: str
    control_len: int
    y: _Array
    control: _Array | None
    def set_control(self, u: ArrayLike) -> None: ...
    def set_state(self, q: ArrayLike, v: ArrayLike) -> None: ...
    def advance(self, target: float) -> str | None:
        """Advances to ``target``; None, or the message of the failure that ended the run."""
    def trajectory(self) -> RunResult: ...
    def joint_torques(self) -> _Array: ...
    def imu(self, imus: Sequence[tuple[int, ArrayLike, ArrayLike]]) -> _Array: ...

class RunStatus:
    """How a run ended, one variant per cause (``isinstance(s, RunStatus.Interrupted)``):
    ``t`` the time reached, ``at`` where the failure or interruption happened. Shown as
    ``RunStatus.Interrupted(t=..., at=..., reason=...)``; pickles."""

    __match_args__: ClassVar[tuple[str, ...]]

    class Success(RunStatus): ...
    class TerminalEvent(RunStatus):
        event: int
        t: float
    class StepTooSmall(RunStatus):
        t: float
        min_step: float
    class NewtonFailed(RunStatus):
        t: float
        min_step: float
        singular: bool
    class MaxSteps(RunStatus):
        t: float
        max_steps: int
    class NonFinite(RunStatus):
        t: float
        at: float
        what: Literal["derivative", "state", "jacobian"]
    class RhsError(RunStatus):
        t: float
        at: float
        message: str
    class EventNaN(RunStatus):
        t: float
        at: float
        event: int
    class Stiff(RunStatus):
        t: float
        h_lambda: float
        h: float
    class Interrupted(RunStatus):
        t: float
        at: float
        reason: str | None
    class NotStarted(RunStatus):
        reason: str

@final
class ContactParameters(_Record):
    """A ground contact's law parameters (SI); ``p["stiffness"]`` indexes them as well (a
    typed record, rust/python/record.rs)."""
    height: float
    stiffness: float | None
    exponent: float
    damping: float | None
    friction: float
    v_eps: float
    def __getitem__(self, key: str) -> float | None: ...

@final
class ContactStates(_Record):
    """A ground contact's points along N states (``Effect.contact_state``): a typed record,
    fields as attributes or ``r["field"]``."""

    position: _Array
    penetration: _Array
    normal_force: _Array
    force: _Array

@final
class OdeSolution(_Record):
    """What :func:`rk45` returns (``pointmass_dyn.OdeResult`` is built from it): ``y`` as
    (dim, N); ``stiff``: ``{"t", "h_lambda", "h", "lambda"}`` of the first stiffness
    detection, if any. A record: indexable by its attribute names, as the dict it replaced,
    pickled as that dict."""
    t: NDArray[np.float64]
    y: NDArray[np.float64]
    t_events: list[NDArray[np.float64]] | None
    y_events: list[NDArray[np.float64]] | None
    nfev: int
    njev: int
    nlu: int
    method: str
    switched_to: str | None
    t_switch: float | None
    n_accepted: int
    n_rejected: int
    status: int
    message: str
    success: bool
    t_reached: float
    stiff: dict[str, float] | None
    sol: DenseSolution | None
    error: BaseException | None

@final
class RunResult(_Record):
    """One run's trajectory and outcome: the fields of ``pointmass_dyn.SimulationResult``
    of the same names (``outcome`` the typed status, ``status`` its SciPy code), and
    ``error``: the exception that stopped the run from Python, or None. A record: indexable
    by its attribute names, pickled as the dict of them."""

    t: _Array
    q: _Array
    v: _Array
    energy: _Array | None
    constraint_residual: _Array | None
    constraint_drift: float | None
    singular_passage: tuple[float, float] | None
    singular_crossings: tuple[int, float | None] | None
    power: dict[str, _Array] | None
    t_events: list[_Array]
    q_events: list[_Array]
    v_events: list[_Array]
    nfev: int
    njev: int
    nlu: int
    n_accepted: int
    n_rejected: int
    method: str
    switched_to: str | None
    t_switch: float | None
    status: int
    outcome: RunStatus
    message: str
    success: bool
    t_reached: float
    error: BaseException | None

def simulate_scene(
    scene: Scene,
    t_span: ArrayLike | None = None,
    rtol: ArrayLike | None = None,
    atol: ArrayLike | None = None,
    *,
    config: RunConfig | None = None,
    events: Sequence[StateEvent | _EventFunc] | None = None,
    progress: Callable[[float], Any] | None = None,
    progress_interval: float | None = None,
    **settings: Any,
) -> RunResult:
    """Integrates a scene in Rust (GIL released); its :class:`RunResult`, whose ``error``
    is ``None`` or the exception a Python callback raised (Ctrl-C included), for the caller
    to re-raise. ``settings``: :class:`RunConfig`'s keywords, which beat ``config``'s."""

def simulate_batch(
    scenes: Sequence[Scene],
    q0: ArrayLike | None = None,
    v0: ArrayLike | None = None,
    t_span: ArrayLike | None = None,
    rtol: ArrayLike | None = None,
    atol: ArrayLike | None = None,
    *,
    config: RunConfig | None = None,
    events: Sequence[StateEvent] | None = None,
    threads: int | None = None,
    progress: Callable[[int, int], Any] | None = None,
    **settings: Any,
) -> tuple[list[RunResult], BaseException | None]:
    """Runs B scenes (or one scene from B initial states ``q0`` (B, nq), ``v0`` (B, nv)) on
    ``threads`` threads, the GIL released once; one :class:`RunResult` per run as
    ``simulate_scene`` returns it (``RunStatus.NotStarted`` with the exception in ``error``
    for a run whose input was refused or that did not start); with the exception (Ctrl-C,
    or one ``progress`` raised) that stopped the batch, else None."""

def effect_forces(
    scene: Scene,
    t: float,
    q: ArrayLike,
    v: ArrayLike,
    disable: _Family | Sequence[_Family] | None = None,
) -> dict[str, _Array]:
    """Generalized force (nv,) of each enabled effect at ``(t, q, v)``, by effect name."""

def scene_along(
    scene: Scene,
    t: ArrayLike,
    q: ArrayLike,
    v: ArrayLike,
    disable: _Family | Sequence[_Family] | None = None,
    accelerations: bool = True,
    forces: bool = False,
    threads: int | None = None,
) -> tuple[_Array | None, dict[str, _Array]]:
    """``(a, forces)`` at the N states ``(t[k], q[k], v[k])``: with ``accelerations`` the
    accelerations (N, nv) the scene's effects give (else None), and with ``forces`` each
    enabled effect's generalized force (N, nv) by name (else an empty dict). In one call, the
    interpreter released, the samples in chunks on ``threads`` threads (None: one per core;
    a scene with a Python torque function: one), the same bits whatever their number. A
    sample that fails or gives a non-finite value is an error naming it."""

def scene_shaking(
    scene: Scene,
    t: ArrayLike,
    q: ArrayLike,
    v: ArrayLike,
    about: ArrayLike | None = None,
    threads: int | None = None,
) -> tuple[_Array, _Array]:
    """``(force, moment)``, each (N, 3): the shaking force and moment about ``about`` (world,
    default the origin) at the N states ``(t[k], q[k], v[k])`` and the accelerations the
    scene gives there (as ``Model.shaking``), computed in the same pass over the samples as
    :func:`scene_along`'s accelerations: one call, on ``threads`` threads, the same bits
    whatever their number."""

def energies(
    scene: Scene,
    q: ArrayLike,
    v: ArrayLike,
    disable: _Family | Sequence[_Family] | None = None,
) -> dict[str, float]:
    """``kinetic``, each conservative effect's potential energy by name, and ``total``."""

def resolve_mesh(
    uri: str,
    base_dir: str | os.PathLike[str] | None = None,
    package_dirs: str | os.PathLike[str] | Sequence[str | os.PathLike[str]] | None = None,
) -> os.PathLike[str] | None:
    """Where a mesh ``uri`` of a model file in ``base_dir`` is (a ``pathlib.Path``), as
    ``from_urdf`` finds its meshes; None when no candidate is a file."""

def rk45(
    fun: Callable[[float, _Array], ArrayLike],
    t_span: ArrayLike,
    y0: ArrayLike,
    rtol: ArrayLike | None = None,
    atol: ArrayLike | None = None,
    *,
    config: RunConfig | None = None,
    events: _EventFunc | Sequence[_EventFunc] | None = None,
    jac: Callable[[float, _Array], Any] | ArrayLike | None = None,
    **settings: Any,
) -> OdeSolution:
    """Our integrators on ``fun(t, y)`` (``method``: RK45 by default; RK45 and DOP853 step for
    step SciPy's ``solve_ivp``, RK4/Euler at the fixed step ``dt``);
    returns an :class:`OdeSolution`: ``t``, ``y`` (n, N), ``sol`` (:class:`DenseSolution` or ``None``),
    ``t_events``, ``y_events``, ``nfev``, ``njev``, ``nlu``, ``n_accepted``,
    ``n_rejected``, ``status``, ``message``, ``success``, ``t_reached``, ``method``,
    ``switched_to``, ``t_switch``, ``stiff``:
    ``None`` or the first stiffness detection ``{"t", "h_lambda", "h", "lambda"}``, and
    ``error``: ``None`` or the exception ``fun`` or an event raised, to re-raise.
    ``stiffness``: ``"warn"`` detects and reports (steps unchanged), ``"stop"`` ends the
    run at the detection (status -1; it also checks the Jacobian's spectral radius every
    20 steps from step 100, three evaluations a check, as ``auto`` does), ``"off"`` skips
    the test. ``jac`` (Radau, auto):
    ``jac(t, y) -> (n, n)`` or a constant (n, n) array; ``None``: finite differences."""

# Pickling (``pointmass_dyn/_pickle.py`` registers these with ``copyreg``).
_Pickled: TypeAlias = (
    RigidBody | PointMasses | Joint | Model | Effect | StateEvent | Scene | DenseSolution
)

def _dumps(obj: _Pickled) -> tuple[bytes, tuple[Callable[..., Any], ...]]:
    """``(data, callables)``: a versioned, checksummed binary encoding of ``obj`` (every float
    bit for bit) and the Python callables of its ``TorqueFunction`` effects, in order."""

def _loads(data: bytes, callables: tuple[Callable[..., Any], ...] | None = None) -> _Pickled:
    """The object ``_dumps`` encoded; raises :class:`pointmass_dyn.errors.UnpicklingError`
    for data that is truncated, altered or of another format version."""

def design_cells(
    cell: float,
    box: ArrayLike | None = None,
    polygon: ArrayLike | None = None,
    z: tuple[float, float] | None = None,
    triangles: ArrayLike | None = None,
) -> _Array:
    """Centres (K, 3) of the cubes of side ``cell`` inside an envelope: a ``box`` (2, 3), a
    ``polygon`` (P, 2) extruded over ``z``, or a closed mesh of ``triangles`` (T, 3, 3)."""

def design_regressor(
    model: Model,
    q: ArrayLike,
    v: ArrayLike,
    a: ArrayLike,
    gravity: ArrayLike | None,
    about: ArrayLike,
    actuated: list[int],
) -> Any:
    """The design maps along N states (a record, indexable by its names): ``data`` (N · rows, 10 · nlinks) (shaking force,
    moment, driving forces, bearing forces per link and cut joint, per unit inertial
    parameter), ``rows``, ``nactuated``, ``nlinks``, ``nloops``, ``parameters``."""

def identification_regressor(
    model: Model,
    q: ArrayLike,
    v: ArrayLike,
    a: ArrayLike,
    gravity: ArrayLike | None = None,
    extras: tuple[bool, bool, bool, bool] = (False, False, False, False),
    actuated: list[int] = ...,
) -> _Array:
    """The joint torque regressor along N states, (N · nv, p), sample-major rows: per link
    Pinocchio's ten parameters, then per 1-dof joint the asked joint-space columns
    (``extras``: viscous, coulomb, armature, offset; docs/identification.md); with ``actuated`` (v indices; required with loops) the driven
    joints' forces, (N · na, p)."""

def identification_parameters(
    model: Model, extras: tuple[bool, bool, bool, bool] = (False, False, False, False)
) -> tuple[list[str], _Array]:
    """Column names and the model's values (friction and offsets 0, armature 0 here)."""

def identification_base(y: ArrayLike, rank_tol: float = 1e-8) -> IdentificationBase:
    """Base parameters of a regressor: ``rank``, ``independent``, ``dependent``,
    ``coefficients`` (rank, p − rank), ``pivots``."""

def identification_fit(
    model: Model,
    q: ArrayLike,
    v: ArrayLike,
    a: ArrayLike,
    tau: ArrayLike,
    **options: Any,
) -> Identified:
    """The identification (pointmass_dyn.identification.identify builds the arguments; the
    core parses ``options``, refusing unknown keys): ``gravity`` (3,), ``method`` ("ols",
    "cells", ...), ``free``, ``prior``, ``prior_weight``, ``weights``, ``cells`` (a list of
    ``(link index, centres (K, 3), side)`` for method "cells"), ``viscous``, ``coulomb``,
    ``armature``, ``offset``, ``rank_tol``, ``actuated``. Returns ``names``, ``free``,
    ``base``, ``base_names``, ``beta``, ``std``, ``pi``, ``rss``, ``condition``,
    ``structural_rank``, ``residuals``, ``masses``."""

def identification_model(
    model: Model, pi: list[float], links: list[int], armature: list[float] | None = None
) -> Model:
    """A copy of ``model`` with links ``links`` given the parameters ``pi`` (10 per link);
    ``InertiaError`` naming the body when one is not a rigid body."""

def design_pins(model: Model, body: int | str) -> list[tuple[_Array, _Array]]:
    """``(point, axis)`` of each revolute or ball joint on ``body``, in its frame."""

def design_pin_loads(model: Model, body: int | str) -> list[Any]:
    """The pins of :func:`design_pins` (same order) with the source of each one's force, each a
    record indexable by its names:
    ``point``, ``axis`` (body frame), ``kind`` (``"joint"``: a tree joint's bearing rows, world
    axes; ``"cut"``: a cut joint's, frame a's axes), ``index`` (link or cut joint), ``sign``
    (+1 the force on this body, -1 its reaction), ``frame_body`` (the body whose rotation
    times ``frame_rotation`` turns the rows to world axes; -1: none) and ``frame_rotation``
    (3, 3)."""

def design_solve(spec: dict[str, Any]) -> Any:
    """Solves a design program (pointmass_dyn.design._problem builds ``spec``) with Clarabel; a
    record indexable by its names (an infeasible program: a record of ``status`` "Infeasible",
    ``message`` and ``relaxation``):
    ``x``, ``delta``, ``values``, ``status``, ``objective``, ``gap_abs``, ``gap_rel`` (the last
    stage's), ``stages`` (each stage's ``(status, gap_abs, gap_rel, objective)``, the first
    stage's objective at that stage's design: the optimum, then the least mass), ``notes`` (what did not go as asked without failing: a least-mass stage not
    found), ``iterations``, ``rounds``, ``solve_time``. Optional ``spec["flows"]``: connected
    links, dicts with ``nodes``, ``edges`` ((a, b) tuples), ``bosses``, ``web``, ``hang``
    (rust/design/connectivity.rs)."""
