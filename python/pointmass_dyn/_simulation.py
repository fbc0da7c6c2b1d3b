"""``simulate`` (a whole scene in Rust, GIL released), the effects a scene declares, their
per-effect generalized forces, power and energies, and ``solve_ivp`` (``rk45``: our integrators on any
Python right-hand side, SciPy-like).

Effects (each declared per scene, each computed only when declared; SI units, radians):

=====================  ===========  ================================================
factory                family       law
=====================  ===========  ================================================
``Gravity(g)``         gravity      ``f_ij = m_ij g`` (on the base acceleration: free)
``Spring``             springs      ``τ = −k (q − rest)``; quaternion joints:
                                    ``τ = −k θ``, θ the rotation vector of rest⁻¹·q
``Damper``             dampers      ``τ = −c v``
``JointFriction``      friction     ``τ = −F tanh(v / v_eps)`` (isotropic on a ball)
``JointTorque``        torques      constant ``τ``
``TabulatedTorque``    torques      ``τ(t)`` linear between rows, clamped outside
``PDTorque``           torques      ``kp (q_ref(t) − q) + kd (q̇_ref(t) − v)``
``TorqueFunction``     torques      ``f(t, q, v) -> τ`` (a Python call per evaluation)
``ExternalForce``      external     force at a body-fixed point (+ moment), constant
                                    or tabulated, world or body axes
``PointSpring``        springs      ``k (l − l0) + c l̇`` along the line between a
                                    point of body a and one of body b (or the world)
``GroundContact``      contact      Hunt–Crossley contact of body points with a plane
``JointLimit``         limits       one-sided spring–damper outside a joint's range
=====================  ===========  ================================================

The torque factories take ``limit=`` (actuator limits: the output clamped per speed, or
``"effort"``: the URDF's); ``GroundContact`` and ``JointLimit`` are in ``_contact.py``
(docs/contact.md).

``joints`` selects joints by body name or body index (as ``Model.add_body`` returns), one or
a sequence; ``None`` means every moving joint. Per-joint parameters are one number or one per
selected joint. ``disable=("gravity", "springs")`` in :func:`simulate` (or
``[simulate] disable = [...]`` in a scene file) switches families off without editing the
scene.
"""

from __future__ import annotations

import operator
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from . import _core, kinematics
from ._contact import contact_forces, torque_saturation
from ._core import Effect, RunConfig, RunStatus, Scene, StateEvent
from ._helpers import changed_settings
from .errors import InvalidInputError, SimulationError, SingularPassageWarning


def Gravity(g: Sequence[float] = (0.0, 0.0, -9.81)) -> Effect:
    """Uniform gravity ``g`` (m/s², world frame), declared per scene."""
    return Effect.gravity(g)


def Spring(joints: Any, stiffness: Any, rest: Any = None, *, name: str | None = None) -> Effect:
    """Joint springs, family ``springs``.

    Revolute/prismatic joints: ``τ = −k (q − rest)``, potential ``½ k (q − rest)²``.
    Quaternion ``Spherical`` joints: an isotropic rotational spring ``τ = −k θ`` on the
    rotation vector ``θ = log(rest⁻¹ q)`` (|θ| ≤ π), potential ``½ k |θ|²``. Euler-angle
    (``SphericalZYZ``) joints are refused. ``stiffness`` ≥ 0: one number or one per joint;
    ``rest``: one number for the 1-dof joints (quaternion joints then rest at the identity),
    or the selected joints' coordinates in order (4 per quaternion joint, x y z w)."""
    return Effect("spring", joints=joints, stiffness=stiffness, rest=rest, name=name)


def Damper(joints: Any, damping: Any, *, name: str | None = None) -> Effect:
    """Viscous joint dampers ``τ = −c v`` on every speed of the selected joints, family
    ``dampers``; ``damping`` ≥ 0, one number or one per joint."""
    return Effect("damper", joints=joints, damping=damping, name=name)


def JointFriction(
    joints: Any, friction: Any, v_eps: float = 1e-3, *, name: str | None = None
) -> Effect:
    """Regularised Coulomb friction, family ``friction``: ``τ = −F tanh(v / v_eps)`` per
    speed (``τ = −F tanh(|ω|/v_eps) ω/|ω|`` on a quaternion joint). ``F`` (``friction`` ≥ 0,
    N·m or N) is reached when sliding well above ``v_eps`` (rad/s or m/s); below, the law is
    viscous with slope ``F / v_eps``: smooth, no stick-slip switching, no true sticking."""
    return Effect("friction", joints=joints, friction=friction, v_eps=v_eps, name=name)


def JointTorque(joints: Any, tau: Any, *, limit: Any = None, name: str | None = None) -> Effect:
    """Constant joint torques (forces on prismatic joints), family ``torques``: one number
    for every speed of the selected joints, or one per speed (3 for a spherical joint).
    ``limit``: as :func:`PDTorque`'s, per speed."""
    return Effect("torque", joints=joints, tau=tau, limit=limit, name=name)


def TabulatedTorque(
    joints: Any, time: Any, values: Any, *, limit: Any = None, name: str | None = None
) -> Effect:
    """Joint torques tabulated in time, family ``torques``: ``time`` (N,) strictly
    increasing, ``values`` (N, n) with one column per speed of the selected joints ((N,)
    for one). Linear interpolation between rows (as ``numpy.interp``), the end rows held
    outside the table. ``limit``: as :func:`PDTorque`'s, per speed."""
    return Effect(
        "tabulated_torque", joints=joints, time=time, values=values, limit=limit, name=name
    )


def PDTorque(
    joints: Any,
    kp: Any,
    kd: Any,
    time: Any,
    reference: Any,
    *,
    limit: Any = None,
    name: str | None = None,
) -> Effect:
    """A PD law tracking a tabulated reference on revolute/prismatic joints, family
    ``torques``: ``τ = kp (q_ref(t) − q) + kd (q̇_ref(t) − v)``. ``reference`` (N, n) holds one
    column per joint at the times ``time`` (N,); ``q_ref`` is interpolated linearly (held
    outside the table) and ``q̇_ref`` is the slope of the current segment (right-continuous
    at the breakpoints, zero outside the table). ``limit``: actuator limits, the output
    clamped per joint at ``±limit`` (one number, one per joint, or ``"effort"``: each joint's
    URDF ``<limit effort>``, taken when the scene is built); :func:`simulate` then reports
    where it saturated (``.saturated``)."""
    return Effect(
        "pd_torque", joints=joints, kp=kp, kd=kd, time=time, reference=reference, limit=limit,
        name=name,
    )


def TorqueFunction(
    f: Callable[[float, np.ndarray, np.ndarray], Any], *, limit: Any = None, name: str | None = None
) -> Effect:
    """Generalized forces from a Python callable ``f(t, q, v) -> tau`` (nv,), family
    ``torques``. It has a price the Rust effects do not: every right-hand-side evaluation
    re-attaches to the interpreter (takes the GIL), builds two arrays and calls Python —
    about 1 µs per evaluation measured on chain7, some 40 % of its whole right-hand side,
    and more if other threads hold the GIL. Prefer ``JointTorque``/``TabulatedTorque``/
    ``PDTorque`` when they fit. An exception it raises stops the run and is re-raised by
    :func:`simulate`. ``limit``: as :func:`PDTorque`'s, one number or one per speed (all
    ``nv``)."""
    effect = Effect.torque_function(f, name)
    return effect if limit is None else effect.with_torque_limit(limit)


def ExternalForce(
    body: Any,
    force: Any = None,
    point: Any = (0.0, 0.0, 0.0),
    *,
    moment: Any = None,
    time: Any = None,
    frame: str = "world",
    name: str | None = None,
) -> Effect:
    """A force on ``body`` (name or index) applied at ``point`` (body frame), plus an
    optional pure ``moment``; family ``external``. ``frame="world"``: world components;
    ``frame="body"``: components in the body frame, turning with it. Constant (3-vectors),
    or with ``time`` (N,) tables ``force``/``moment`` (N, 3), linear between rows and held
    outside. Bodies on Fixed joints are welded into their link; the force acts there."""
    return Effect(
        "external", body=body, force=force, point=point, moment=moment, time=time, frame=frame,
        name=name,
    )


def PointSpring(
    body_a: Any,
    point_a: Any,
    body_b: Any,
    point_b: Any,
    stiffness: float,
    rest_length: float = 0.0,
    damping: float = 0.0,
    *,
    name: str | None = None,
) -> Effect:
    """A linear spring–damper between ``point_a`` of ``body_a`` and ``point_b`` of ``body_b``
    (each point in its body's frame; a body by name or index, or the ground as ``"world"``,
    ``-1`` or ``None``, whose points are world coordinates); family ``springs``.

    The force ``k (l − l0) + c l̇`` (``l`` the distance between the points) acts along the
    line between them, pulling them together when stretched; ``stiffness`` k, ``rest_length``
    l0 and ``damping`` c are ≥ 0. Potential ``½ k (l − l0)²`` (in ``energies``); the damping
    makes it dissipative: its power is ``−dV/dt − c l̇²``. A run stops with an error where the
    two points coincide (the force's direction is undefined there), except for ``l0 = 0``
    and ``c = 0``, whose force ``−k (p_b − p_a)`` is defined everywhere."""
    return Effect(
        "point_spring", body_a=body_a, point_a=point_a, body_b=body_b, point_b=point_b,
        stiffness=stiffness, rest_length=rest_length, damping=damping, name=name,
    )


@dataclass(repr=False, eq=False)
class SimulationResult:
    """Trajectory of a scene. ``q`` is (N, nq), ``v`` (N, nv); ``energy`` (N,) when asked.

    Compared (and hashed) by identity: two runs' arrays are compared with NumPy, as
    ``np.array_equal(a.q, b.q)``, not with ``==``."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    energy: np.ndarray | None
    t_events: list
    q_events: list
    v_events: list
    nfev: int
    n_accepted: int
    n_rejected: int
    status: int
    message: str
    success: bool
    t_reached: float
    scene: str = ""
    extras: dict = field(default_factory=dict)
    #: Power ``τ_e · v`` (W) of each enabled effect at the output times, by effect name,
    #: when ``simulate(..., power=True)``.
    power: dict | None = None
    #: Models with loops: the largest constraint residual of each output state (N,), after
    #: the states were projected onto the constraint manifolds.
    constraint_residual: np.ndarray | None = None
    #: Models with loops: the largest residual any accepted step had before projection (the
    #: integrator's drift, which the projection removed).
    constraint_drift: float | None = None
    #: Models with loops: ``(t, ratio)`` when an accepted step ended at a singular position
    #: within rounding (its loop rows' pivot ratio ``ratio`` times the run's best, below
    #: 1e-5), or a one-degree-of-freedom motion's tangent turned by more than 60 degrees in
    #: one step (the first such step): past it the motion may continue on another branch,
    #: chosen by rounding. ``simulate`` then warns (:class:`SingularPassageWarning`).
    singular_passage: tuple | None = None
    #: Models with loops and one degree of freedom: ``(count, t)``, how many singular
    #: positions the motion passed between accepted states (the orientation of the kernel of
    #: the loop rows reversed, however long the step) and the time just past the first
    #: (``None`` if none). Passing one is how such motions go; past one the accuracy is
    #: limited (docs/mechanisms.md section 5).
    singular_crossings: tuple | None = None
    #: The integration method that ran ("RK45", "DOP853", "Vern9", "Adams", "Radau", "RK4",
    #: "Euler" or "auto";
    #: the one ``simulate`` chose when none was named). ``"auto"``: see ``switched_to``.
    method: str = "RK45"
    #: Jacobian evaluations and LU decompositions (implicit methods; 0 otherwise).
    njev: int = 0
    nlu: int = 0
    #: ``method="auto"``: the method it switched to once the problem was found stiff, and when.
    switched_to: str | None = None
    t_switch: float | None = None
    #: ``simulate(..., contact=True)``: each ground contact's points, penetrations and forces
    #: at the output times (:class:`pointmass_dyn.ContactForces`), by effect name.
    contact: dict | None = None
    #: Torques with a ``limit``: where each was at its limit, (N, nv) booleans at the output
    #: times by effect name (columns of the speeds it does not drive are False).
    saturated: dict | None = None
    #: The scene's model (``simulate`` sets it): what ``frame_path`` and ``point_path`` use.
    model: Any = field(default=None, repr=False, compare=False)
    #: How the run ended, typed (a :class:`RunStatus` variant: ``RunStatus.Interrupted``
    #: with ``t`` reached, ``at`` where and ``reason``; ``RunStatus.NonFinite``, ...);
    #: ``status`` is its SciPy code.
    outcome: Any = field(default=None, compare=False)

    def frame_path(self, frame: Any, model: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """(rotations (N, 3, 3), positions (N, 3)) of ``frame`` at the output times."""
        return kinematics.frame_path(self._model(model), self.q, frame)

    def point_path(
        self, body: Any, point: Any, model: Any = None, velocities: bool = False
    ) -> Any:
        """World positions (N, 3) of ``point`` (in the body or frame ``body``) at the output
        times (a coupler curve); with ``velocities=True``, (positions, velocities (N, 3))."""
        pos, vel = kinematics.point_path(
            self._model(model), self.q, body, point, self.v if velocities else None
        )
        return (pos, vel) if velocities else pos

    def _model(self, model: Any) -> Any:
        model = self.model if model is None else model
        if model is None:
            raise InvalidInputError(
                "model: this result holds no model (a batch result): pass model=scene.model"
            )
        return model

    @property
    def nsteps(self) -> int:
        return self.n_accepted

    def __repr__(self) -> str:
        # A summary: the arrays can hold millions of numbers.
        t = np.asarray(self.t)
        span = f"[{t[0]:g}, {t[-1]:g}]" if t.size else "[]"
        parts = [
            f"scene={self.scene!r}" if self.scene else None,
            f"method={self.method!r}",
            f"switched_to={self.switched_to!r} at t={self.t_switch:.6g}"
            if self.switched_to is not None and self.t_switch is not None
            else None,
            f"success={self.success}",
            f"t={span} ({t.size} points)",
            f"q: {np.shape(self.q)}, v: {np.shape(self.v)}",
            f"energy: {np.shape(self.energy)}" if self.energy is not None else None,
            f"events: {[len(e) for e in self.t_events]}" if self.t_events else None,
            f"nfev={self.nfev}, n_accepted={self.n_accepted}, n_rejected={self.n_rejected}",
            f"message={self.message!r}",
        ]
        return "SimulationResult(" + ", ".join(p for p in parts if p) + ")"

    def raise_for_status(self) -> SimulationResult:
        """Raises :class:`SimulationError` (with ``.t``) if the run failed; returns self."""
        if not self.success:
            raise SimulationError(self.message, self.t_reached, self)
        return self


def simulate(
    scene: Scene,
    t_span: Sequence[float] | None = None,
    *,
    rtol: Any = None,
    atol: Any = None,
    t_eval: Any = None,
    events: Sequence[Any] | None = None,
    first_step: float | None = None,
    max_step: float | None = None,
    max_steps: int | None = None,
    energy: bool = False,
    controller: str = "standard",
    progress: Callable[[float], Any] | None = None,
    disable: Any = None,
    power: bool = False,
    stiffness: str = "warn",
    progress_interval: float | None = None,
    method: str | None = None,
    dt: float | None = None,
    contact: bool = False,
    config: RunConfig | None = None,
) -> SimulationResult:
    """Integrates a scene, entirely in Rust with the GIL released.

    ``method``: ``"RK45"`` (SciPy's, step for step), ``"DOP853"`` (SciPy's, step for
    step; better at tight tolerances), ``"Vern9"`` or ``"Adams"`` (variable-order Adams PECE,
    two evaluations a step; tight tolerances on smooth problems), ``"RK4"`` or ``"Euler"``
    (semi-implicit, MuJoCo's) at
    the fixed step ``dt`` (required by these two only), ``"Radau"`` (implicit) or ``"auto"``
    (RK45, or Adams at rtol ≤ 1e-8 (DOP853 with closed loops), then Radau from where the
    stiffness test fires;
    ``.switched_to``, ``.t_switch``).
    ``None`` takes the scene's ``[simulate] method``/``dt``; a scene that names none runs
    ``"auto"`` when it has a ground contact or joint limits (enabled; stiff by design, where
    RK45 takes 10–100× the evaluations), else ``"RK45"``. ``.method`` says which ran.
    See docs/integrators.md.

    Settings not given here come from the scene (its ``[simulate]`` table), then SciPy's
    defaults (rtol 1e-3, atol 1e-6). ``events`` holds :class:`StateEvent` objects (a joint
    coordinate or speed crossing a value, evaluated in Rust) or callables
    ``f(t, q, v) -> float`` with optional ``terminal``/``direction`` attributes as in SciPy
    (these re-enter Python at every evaluation and cost accordingly). ``energy=True`` records
    kinetic energy plus the potential energy of the enabled gravity and springs at every
    output time; ``power=True`` records each enabled effect's power ``τ_e · v`` (``.power``,
    a dict by effect name), so that ``dE/dt = Σ`` power of the non-conservative effects can
    be checked. ``contact=True`` records each ground contact's points, penetrations and
    forces at the output times (``.contact``, see :func:`pointmass_dyn.contact_forces`); a
    scene with torque limits reports where they saturated (``.saturated``). ``disable`` names
    effect families to switch off (``"gravity"``, ``"springs"``, ``"dampers"``,
    ``"friction"``, ``"torques"``, ``"external"``, ``"contact"``, ``"limits"``); ``None``
    takes the scene's ``[simulate] disable`` list, ``()`` switches nothing off.
    ``progress(t)`` is called when the run looks for Ctrl-C: by elapsed time, every 50 ms
    (every 250 ms at most while another Python thread keeps the interpreter busy, so that
    such a thread barely slows the run), or every ``progress_interval`` seconds if given (0:
    every 64 evaluations). ``stiffness`` is what Hairer's stiffness test does when it
    fires: ``"warn"`` (default) notes it in the message and changes no step, ``"stop"``
    ends the run (and, as ``auto``, also checks the Jacobian's spectral radius every 20
    steps from step 100: docs/integrators.md), ``"off"`` skips the test.

    A ``SphericalZYZ`` joint reaching its Euler singularity (sin θ = 0) ends the run there
    with ``success=False`` and a message naming the joint and the time; so does one coming
    within ``|sin θ| = 3 √(ε / rtol)`` of it (1.4e-3 at rtol 1e-9; a run starting nearer:
    twice as near as it started), where rounding in the Euler-angle rates would exceed the
    tolerance. Use ``Spherical`` for motions through or near it.

    A run that cannot finish returns ``success=False`` with a message giving the reason and
    the time reached (a non-finite force from any effect, a ``TorqueFunction`` included);
    call ``.raise_for_status()`` to turn that into a :class:`SimulationError`. An exception
    raised by Python code the run calls (a ``TorqueFunction``, an event, ``progress``) and
    Ctrl-C (``KeyboardInterrupt``) stop the run and propagate as themselves, with the
    trajectory computed so far attached as ``.result`` (a ``SimulationResult`` with
    ``success=False`` and ``t_reached``). Invalid arguments raise :class:`InvalidInputError`.

    ``config``: a :class:`RunConfig` holding these settings once for many calls; the
    keywords given here beat it (those left at their defaults do not), and it beats the
    scene's ``[simulate]`` table.
    """
    run = _core.simulate_scene(
        scene,
        t_span,
        rtol,
        atol,
        config=config,
        events=events,
        progress=progress,
        progress_interval=progress_interval,
        **changed_settings(
            t_eval=t_eval,
            first_step=first_step,
            max_step=max_step,
            max_steps=max_steps,
            method=method,
            dt=dt,
            disable=disable,
            energy=energy,
            power=power,
            controller=controller,
            stiffness=stiffness,
        ),
    )
    result = result_from_run(run, scene.name, scene.model)
    result.saturated = torque_saturation(scene, result, disable)
    if result.singular_passage is not None:
        warnings.warn(singular_passage_warning(result), stacklevel=2)
    if contact:
        result.contact = contact_forces(scene, result)
    if run.error is not None:
        raise _with_partial_result(run.error, result)
    return result


#: The fields from the core's ``RunResult``, the caller's, and each field's place in both: a
#: result built positionally from one C call's getters (~2 us less than 30 keywords).
_RUN_FIELDS = tuple(f.name for f in fields(SimulationResult) if hasattr(_core.RunResult, f.name))
_CALLER_FIELDS = ("scene", "extras", "contact", "saturated", "model")
_RUN_VALUES = operator.attrgetter(*_RUN_FIELDS)
_BOTH = _RUN_FIELDS + _CALLER_FIELDS
_IN_ORDER = operator.itemgetter(*(_BOTH.index(f.name) for f in fields(SimulationResult)))


def result_from_run(run: Any, scene: str = "", model: Any = None) -> SimulationResult:
    """The :class:`SimulationResult` of a core ``RunResult`` (``simulate``, a batch's run,
    a ``Simulator``'s trajectory)."""
    return SimulationResult(*_IN_ORDER(_RUN_VALUES(run) + (scene, {}, None, None, model)))


def singular_passage_warning(result: SimulationResult) -> SingularPassageWarning:
    """What ``simulate`` says when a step ended at a singular position of the loops."""
    t, ratio = result.singular_passage
    return SingularPassageWarning(
        f"{result.method} ended a step at a singular position of the loops near t = {t:.9g} "
        f"(their rows' pivot ratio {ratio:.1e} of the run's best): the motion past it may "
        "continue on another branch, chosen by rounding. DOP853 and RK45 step over such "
        "positions; check the run with method='DOP853' (docs/mechanisms.md §5)"
    )


def _with_partial_result(error: BaseException, result: Any) -> BaseException:
    """Attaches what a run computed before a Python callback raised (or Ctrl-C) to the
    exception as ``.result``, and says so in the traceback."""
    try:
        error.result = result
        note = (
            f"pointmass_dyn: the run stopped at t = {result.t_reached}; what it computed is "
            "in this exception's .result"
        )
        notes = getattr(error, "__notes__", None)
        if notes is None:
            error.__notes__ = [note]
        else:
            notes.append(note)
    except (AttributeError, TypeError):  # an exception type that takes no attributes
        pass
    return error


def effect_forces(scene: Scene, t: float, q: Any, v: Any, *, disable: Any = None) -> dict:
    """Generalized force (nv,) of each enabled effect of ``scene`` at ``(t, q, v)``, by
    effect name (the user's ``name``, else the family's: ``gravity``, ``springs``,
    ``springs_2``, ...). Gravity's is ``Nᵀ f^G``; external wrenches are mapped through the
    joints. Only declared, enabled effects appear. ``disable`` as in :func:`simulate`."""
    return _core.effect_forces(scene, t, q, v, disable)


def effect_power(scene: Scene, t: float, q: Any, v: Any, *, disable: Any = None) -> dict:
    """Power ``τ_e · v`` (W) each enabled effect injects at ``(t, q, v)``, by effect name."""
    forces = effect_forces(scene, t, q, v, disable=disable)  # validates v first
    v = np.asarray(v, dtype=float)
    return {k: float(f @ v) for k, f in forces.items()}


def energies(scene: Scene, q: Any, v: Any, *, disable: Any = None) -> dict:
    """``kinetic``, the potential energy of each enabled conservative effect (gravity:
    ``−Σ m_ij g·x_ij``, zero at the world origin; springs) by effect name, and ``total``
    (what ``simulate(..., energy=True)`` records)."""
    return _core.energies(scene, q, v, disable)


class OdeResult(dict):
    """SciPy's ``OdeResult``: a dict with attribute access."""

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError as exc:
            raise AttributeError(name) from exc

    def __repr__(self) -> str:
        keys = ", ".join(sorted(self))
        return f"OdeResult({keys})"


def solve_ivp(
    fun: Callable[[float, np.ndarray], Any],
    t_span: Sequence[float],
    y0: Any,
    *,
    method: str = "RK45",
    dt: float | None = None,
    rtol: Any = 1e-3,
    atol: Any = 1e-6,
    t_eval: Any = None,
    events: Any = None,
    first_step: float | None = None,
    max_step: float = np.inf,
    max_steps: int | None = None,
    dense_output: bool = False,
    controller: str = "standard",
    stiffness: str = "warn",
    jac: Any = None,
) -> OdeResult:
    """Our integrators on ``fun(t, y)``, as SciPy's ``solve_ivp(fun, t_span, y0, method=...)``:
    ``"RK45"`` (default) and ``"DOP853"`` step for step SciPy's with the same options (same
    steps, ``nfev``, dense output); ``"RK4"`` and ``"Euler"`` (explicit Euler here: a plain
    ``fun`` has no ``[q; v]`` split) at the fixed step ``dt``, their dense output the cubic
    Hermite of each step; ``"Radau"`` and ``"auto"`` see docs/integrators.md.

    Returns a SciPy-like result: ``t``, ``y`` (n, N), ``sol`` (when ``dense_output``),
    ``t_events``, ``y_events``, ``nfev``, ``njev``, ``nlu``, ``status`` (0 end reached,
    1 terminal event, -1 failure), ``message``, ``success``; plus ``n_accepted``,
    ``n_rejected``, ``t_reached``, ``method``, ``switched_to`` and ``t_switch``. An exception
    raised by ``fun`` or an event (Ctrl-C included) propagates with the partial result
    attached as ``.result``.

    ``jac`` (``"Radau"`` and ``"auto"`` only, as SciPy's): a callable ``jac(t, y)``
    returning the (n, n) Jacobian ``∂f_i/∂y_j`` (an array-like or a SciPy sparse matrix),
    or a constant (n, n) array; ``None`` (default): finite differences (SciPy's
    ``num_jac``, whose evaluations SciPy does not count in ``nfev``, nor do we).
    """
    out = _core.rk45(
        fun,
        t_span,
        y0,
        rtol,
        atol,
        events=events,
        jac=jac,
        t_eval=t_eval,
        first_step=first_step,
        max_step=max_step,  # inf: no limit (checked in Rust: a real number)
        max_steps=max_steps,
        dense_output=dense_output,
        controller=controller,
        stiffness=stiffness,
        method=method,
        dt=dt,
    )
    result = OdeResult({k: out[k] for k in out.keys() if k != "error"})
    if out.error is not None:
        raise _with_partial_result(out.error, result)
    return result


def rk45(
    fun: Callable[[float, np.ndarray], Any],
    t_span: Sequence[float],
    y0: Any,
    **options: Any,
) -> OdeResult:
    """:func:`solve_ivp` (``method="RK45"`` unless given): our Dormand–Prince 5(4), step for
    step SciPy's ``solve_ivp(fun, t_span, y0, method="RK45")`` with the same options."""
    return solve_ivp(fun, t_span, y0, **options)


__all__ = [
    "Damper",
    "ExternalForce",
    "Gravity",
    "JointFriction",
    "JointTorque",
    "OdeResult",
    "PDTorque",
    "PointSpring",
    "RunStatus",
    "SimulationResult",
    "Spring",
    "StateEvent",
    "TabulatedTorque",
    "TorqueFunction",
    "effect_forces",
    "effect_power",
    "energies",
    "rk45",
    "simulate",
    "solve_ivp",
]
