"""A controller in the loop: :class:`Simulator` (step, sense, act) and ``simulate`` with a
controller sampled at a fixed period (docs/control.md)."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _core
from ._contact import contact_forces
from ._simulation import SimulationResult, result_from_run
from ._simulation import simulate as _simulate
from .errors import InvalidInputError, SimulationError

__all__ = ["IMU", "Simulator", "simulate"]


@dataclass(frozen=True)
class IMU:
    """A frame fixed on ``body`` (name or index) at ``position`` with axes ``rotation``
    (3 × 3, columns the sensor's axes), both in the body's frame. It reads the specific force
    ``Rᵀ (a − g)`` (what an accelerometer reads: ``−Rᵀ g`` at rest) and the angular velocity
    ``Rᵀ ω``, both in its own axes."""

    body: Any
    position: Any = (0.0, 0.0, 0.0)
    rotation: Any = None


def _body_index(model: Any, body: Any, where: str) -> int:
    names = list(model.body_names)
    if isinstance(body, str):
        if body not in names:
            raise InvalidInputError(f"{where}: expected a body name of the model, got {body!r}")
        return names.index(body)
    if isinstance(body, (int, np.integer)) and 0 <= int(body) < len(names):
        return int(body)
    raise InvalidInputError(
        f"{where}: expected a body name or an index below {len(names)}, got {body!r}"
    )


class _Noise:
    """Gaussian noise (standard deviation per sensor name) and a constant bias per name,
    from one seeded generator."""

    def __init__(self, noise: Mapping | None, bias: Mapping | None, seed: Any):
        self.noise = dict(noise or {})
        self.bias = {k: np.asarray(b, dtype=float) for k, b in (bias or {}).items()}
        for name, x in self.noise.items():
            if not np.all(np.isfinite(x)) or np.any(np.asarray(x) < 0):
                raise InvalidInputError(
                    f"noise[{name!r}]: expected standard deviations >= 0, got {x!r}"
                )
        self.rng = np.random.default_rng(seed)

    def apply(self, readings: dict) -> dict:
        for name, value in readings.items():
            if name in self.bias:
                readings[name] = value + self.bias[name]
            if name in self.noise:
                sd = np.asarray(self.noise[name], dtype=float)
                readings[name] = readings[name] + sd * self.rng.standard_normal(np.shape(value))
        return readings


class Simulator:
    """A scene stepped one control period at a time, the control held over each step.

    ``Simulator(scene, method=..., rtol=..., atol=... | dt=..., control_period=0.001,
    control="torque" | "pd")``: ``control="torque"`` holds joint torques (nv, added to the
    scene's effects); ``"pd"`` holds the targets of the scene's PD torques (one per joint they
    drive, zero target rate; their tables are not read while a target is held). ``method``:
    ``"RK45"``, ``"DOP853"``, ``"Radau"``, ``"RK4"`` or ``"Euler"`` (``dt`` for the last two);
    ``None`` takes the scene's, else RK45, or Radau for a scene with contact or joint limits.

    An adaptive method keeps its state across :meth:`step` calls: the step that would pass a
    period boundary is clipped to it, the next starts from the step size proposed before the
    clipping, and a changed control costs one evaluation at the boundary (RK45, DOP853 and
    Radau re-evaluate their first stage; RK4 and Euler carry nothing). Setting :attr:`state`
    restarts the method from the new state.

    Sensors (:meth:`sensors`): ``q``, ``v``, ``tau`` (the actuators' joint torques: the torque
    control plus the scene's torque effects), per :class:`IMU` ``"<name>.accel"`` and
    ``"<name>.gyro"``, and with ``contact=True`` each ground contact's forces per point
    (``"contact.<effect>"``, (P, 3), world axes). ``noise`` (standard deviation by reading name)
    and ``bias`` (added by name) are drawn from ``numpy.random.default_rng(seed)``.

    ``t_eval`` (increasing times from ``t0`` on): :meth:`result` holds the states at these
    times only, each from the interpolant of the step that reaches it (as ``simulate``'s
    ``t_eval``), instead of every accepted step; the stepping is the same either way.
    """

    def __init__(
        self,
        scene: Any,
        *,
        method: str | None = None,
        rtol: Any = None,
        atol: Any = None,
        dt: float | None = None,
        control_period: float = 0.001,
        control: str = "torque",
        imu: Mapping[str, IMU] | None = None,
        contact: bool = False,
        noise: Mapping | None = None,
        bias: Mapping | None = None,
        seed: Any = None,
        record: bool = True,
        disable: Any = None,
        first_step: float | None = None,
        max_step: float | None = None,
        t0: float = 0.0,
        t_eval: Any = None,
    ):
        self.scene = scene
        self._core = _core._Simulator(
            scene, method=method, rtol=rtol, atol=atol, dt=dt, control_period=control_period,
            control=control, record=record, disable=disable, first_step=first_step,
            max_step=max_step, t0=t0, t_eval=t_eval,
        )  # fmt: skip
        model = scene.model
        self._imu_names = list((imu or {}).keys())
        self._imus = []
        for name, s in (imu or {}).items():
            if not isinstance(s, IMU):
                raise InvalidInputError(f"imu[{name!r}]: expected a pmd.IMU, got {s!r}")
            rot = np.eye(3) if s.rotation is None else s.rotation
            self._imus.append((_body_index(model, s.body, f"imu[{name!r}].body"), s.position, rot))
        self._contact = bool(contact)
        self._noise = _Noise(noise, bias, seed)
        # Default steps end at anchor + k·period (no accumulated sum), from t0 or the last
        # explicit duration or state change.
        self._anchor, self._k = self.t, 0

    @property
    def t(self) -> float:
        return self._core.t

    @property
    def q(self) -> np.ndarray:
        return self._core.y[: self._core.nq]

    @property
    def v(self) -> np.ndarray:
        return self._core.y[self._core.nq :]

    @property
    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q, v)`` now (copies). Set it to reset or perturb the run at the current time:
        quaternions are normalised; with loops ``q`` must close them to 1e-8 and ``v`` keep
        them closed (the rest is projected away), else :class:`InvalidInputError` and the
        state is unchanged. The method restarts from the new state; :meth:`result` gets a
        second row at this time."""
        return self.q, self.v

    @state.setter
    def state(self, value: Any) -> None:
        try:
            q, v = value
        except (TypeError, ValueError):
            raise InvalidInputError(f"state: expected a pair (q, v), got {value!r:.80}") from None
        self._core.set_state(q, v)
        self._anchor, self._k = self.t, 0

    @property
    def control(self) -> np.ndarray | None:
        """The control held (None before the first): torques (nv) or PD targets."""
        return self._core.control

    @control.setter
    def control(self, u: Any) -> None:
        self._core.set_control(u)

    @property
    def control_period(self) -> float:
        return self._core.control_period

    @property
    def method(self) -> str:
        return self._core.method

    def step(self, duration: float | None = None, control: Any = None) -> Simulator:
        """Advances exactly ``duration`` (default: the control period) holding ``control``
        (default: the one held). A control of the wrong length or with a non-finite value is
        refused naming the step; a run that fails raises :class:`SimulationError` with
        ``.result`` (everything so far)."""
        if control is not None:
            self._core.set_control(control)
        if duration is None:
            target = self._anchor + (self._k + 1) * self.control_period
        else:
            target = self.t + float(duration)
        message = self._core.advance(target)
        if duration is None:
            self._k += 1
        else:
            self._anchor, self._k = self.t, 0
        if message is not None:
            raise SimulationError(message, self.t, self.result())
        return self

    def sensors(self) -> dict:
        """The readings now (with noise and bias if configured), by name."""
        out = {"q": self.q, "v": self.v, "tau": self._core.joint_torques()}
        if self._imus:
            readings = self._core.imu(self._imus)
            for name, r in zip(self._imu_names, readings):
                out[f"{name}.accel"] = r[:3]
                out[f"{name}.gyro"] = r[3:]
        if self._contact:
            now = SimulationResult(
                t=np.array([self.t]), q=self.q[None], v=self.v[None], energy=None,
                t_events=[], q_events=[], v_events=[], nfev=0, n_accepted=0, n_rejected=0,
                status=0, message="", success=True, t_reached=self.t,
            )  # fmt: skip
            for name, c in contact_forces(self.scene, now).items():
                out[f"contact.{name}"] = c.force[0]
        return self._noise.apply(out)

    def result(self) -> SimulationResult:
        """Everything so far (every accepted step, with ``record=True``) as ``simulate``
        returns it."""
        return result_from_run(self._core.trajectory(), self.scene.name)


def simulate(
    scene: Any,
    t_span: Sequence[float] | None = None,
    *,
    controller: Any = "standard",
    control_period: float = 0.001,
    control: str = "torque",
    imu: Mapping[str, IMU] | None = None,
    contact: bool = False,
    noise: Mapping | None = None,
    bias: Mapping | None = None,
    seed: Any = None,
    **options: Any,
) -> SimulationResult:
    if not callable(controller):
        return _simulate(scene, t_span, controller=controller, contact=contact, **options)
    return controlled_run(
        scene, t_span, controller, control_period,
        dict(control=control, imu=imu, contact=contact, noise=noise, bias=bias, seed=seed),
        options,
    )  # fmt: skip


simulate.__doc__ = (_simulate.__doc__ or "") + """
    ``controller=f`` (a callable; a string is the step-size controller above): ``f(t, q, v,
    sensors) -> control`` is called every ``control_period`` seconds from ``t0`` and its
    control held until the next call (zero-order hold; ``control="torque"`` or ``"pd"``, and
    ``imu``, ``contact``, ``noise``, ``bias``, ``seed`` as :class:`Simulator`'s). The run is
    the :class:`Simulator` loop ``sim.step(control=f(sim.t, sim.q, sim.v, sim.sensors()))``,
    bit for bit; the last period is shortened to end at ``t_end``. An exception raised by
    ``f`` stops the run and propagates with the trajectory so far as ``.result``.
    A control the :class:`Simulator` refuses (wrong length, not finite) raises
    :class:`InvalidInputError` naming the step, with the trajectory so far as ``.result``.
    ``method``, ``rtol``, ``atol``, ``dt``, ``first_step``, ``max_step``, ``disable`` and
    ``t_eval`` (the output times, up to ``t_end``) apply; events, ``energy``, ``power`` and
    ``progress`` are not taken with a controller.
"""

_LOOP_OPTIONS = {"method", "rtol", "atol", "dt", "first_step", "max_step", "disable", "t_eval"}


def check_options(scene: Any, t_span: Any, options: dict) -> tuple[float, float]:
    """``(t0, t_end)``, after refusing what a run with a controller does not take."""
    extra = sorted(k for k, v in options.items() if k not in _LOOP_OPTIONS and v is not None)
    if extra:
        raise InvalidInputError(
            f"{extra[0]}: not taken with a controller (it takes {sorted(_LOOP_OPTIONS)}), "
            f"got {options[extra[0]]!r}"
        )
    if t_span is None:
        t_span = scene.t_span
    if t_span is None:
        raise InvalidInputError("t_span: expected (t0, t_end): the scene sets none, got None")
    t0, t_end = (float(x) for x in t_span)
    if not (np.isfinite(t0) and np.isfinite(t_end) and t_end > t0):
        raise InvalidInputError(
            f"t_span: expected finite (t0, t_end) with t_end > t0 for a controller, got {t_span!r}"
        )
    t_eval = options.get("t_eval")
    if t_eval is not None and np.size(t_eval) and np.max(t_eval) > t_end:
        raise InvalidInputError(
            f"t_eval: expected times within t_span ({t0}, {t_end}), got {np.max(t_eval)!r}"
        )
    return t0, t_end


def controlled_run(
    scene: Any,
    t_span: Any,
    f: Callable,
    period: float,
    sensing: dict,
    options: dict,
    stop: Callable[[], bool] | None = None,
) -> SimulationResult:
    """``simulate(scene, t_span, controller=f, ...)``. ``stop()`` is asked before each
    period (a batch being stopped): True ends the run there, its result so far with
    ``success`` False and ``status`` -1."""
    t0, t_end = check_options(scene, t_span, options)
    opts = {k: options.get(k) for k in _LOOP_OPTIONS}
    sim = Simulator(scene, control_period=period, t0=t0, **sensing, **opts)
    k = 0
    while sim.t < t_end:
        if stop is not None and stop():
            result = sim.result()
            result.success, result.status = False, -1
            result.message = f"the batch was stopped; this run reached t = {sim.t}"
            return _with_contact(scene, result, sensing["contact"])
        k += 1
        # Periods end at t0 + k·period, as Simulator.step's; the last one at t_end.
        last = t0 + k * period >= t_end
        try:
            u = f(sim.t, sim.q, sim.v, sim.sensors())
            sim.step(duration=t_end - sim.t if last else None, control=u)
        except SimulationError as error:
            return _with_contact(scene, error.result, sensing["contact"])
        except BaseException as error:  # the controller's, a refused control, Ctrl-C
            _attach(error, sim.result())
            raise
    return _with_contact(scene, sim.result(), sensing["contact"])


def _with_contact(scene: Any, result: SimulationResult, contact: bool) -> SimulationResult:
    if contact:
        result.contact = contact_forces(scene, result)
    return result


def _attach(error: BaseException, result: SimulationResult) -> None:
    try:
        error.result = result
        error.add_note(f"pointmass_dyn: the run stopped at t = {result.t_reached}; "
                       "what was computed is in this exception's .result")  # fmt: skip
    except (AttributeError, TypeError):
        pass
