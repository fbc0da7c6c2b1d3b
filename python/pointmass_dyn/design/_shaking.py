"""Shaking forces and moments, and a mechanism along a prescribed motion (docs/balancing.md).

A moving mechanism shakes its ground with the resultant of its inertia forces, the shaking
force ``F = −Σ m_ij a_ij`` and moment ``M_O = −Σ m_ij (r_ij − O) × a_ij`` over every point
mass (gravity excluded: the weight is steady and reported apart).

* :func:`shaking` — shaking force and moment per state, over arrays of states or along a
  :class:`~pointmass_dyn.SimulationResult`.
* :func:`prescribed_motion` — a mechanism driven at a prescribed input (a crank at constant
  speed over a revolution, or a tabulated input): per instant the whole state, driving
  torque, bearing forces, shaking force and moment (:class:`MotionAnalysis`);
  :func:`analyze_motion` the same along given states.
"""

from __future__ import annotations

from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _core
from .._helpers import (
    attach_partial,
    float_array,
    peak,
    rms,
    sample_count,
    scene_gravity,
    stop_reason,
)
from ..errors import InvalidInputError
from ..plotting import coordinate_units


@dataclass(frozen=True)
class Shaking:
    """Shaking force and moment (world axes) about ``about``, per state: (N, 3) or (3,).
    ``weight`` is the steady load of the moving links (``total mass × g``; None without
    gravity), which the shaking force leaves out."""

    force: np.ndarray
    moment: np.ndarray
    about: np.ndarray
    weight: np.ndarray | None = None

    @property
    def rms(self) -> dict[str, float]:
        """RMS magnitudes over the states (equal weights: sample the cycle uniformly)."""
        return {"force": rms(self.force), "moment": rms(self.moment)}

    @property
    def peak(self) -> dict[str, float]:
        return {"force": peak(self.force), "moment": peak(self.moment)}



def shaking(
    model_or_scene: Any,
    q: Any,
    v: Any = None,
    a: Any = None,
    *,
    about: Any = (0.0, 0.0, 0.0),
    gravity: Any = None,
) -> Shaking:
    """Shaking force ``−Σ m a`` and moment ``−Σ m (r − O) × a`` (``O = about``) of a model.

    ``q``, ``v``, ``a``: one state ((nq,), (nv,), (nv,)) or N states ((N, nq), (N, nv),
    (N, nv)). Or ``q`` a :class:`SimulationResult` and ``model_or_scene`` the
    :class:`Scene` it came from: the accelerations are then the scene's own (its effects, its
    loops) at each output sample. ``gravity`` only sets the reported ``weight`` (a scene's
    gravity by default)."""
    about = np.asarray(about, dtype=float)
    if hasattr(q, "t") and hasattr(q, "q") and hasattr(q, "v"):
        result = q
        if not isinstance(model_or_scene, _core.Scene):
            raise InvalidInputError(
                "model_or_scene: expected the Scene a SimulationResult came from (its effects "
                "give the accelerations), got " + type(model_or_scene).__name__
            )
        scene = model_or_scene
        model = scene.model
        q, v = np.asarray(result.q, dtype=float), np.asarray(result.v, dtype=float)
        # The accelerations and the shaking in one pass over the samples, in the core.
        force, moment = _core.scene_shaking(scene, result.t, q, v, about=about)
        if gravity is None:
            gravity = scene_gravity(scene)
    else:
        model = model_or_scene.model if isinstance(model_or_scene, _core.Scene) else model_or_scene
        if v is None or a is None:
            raise InvalidInputError("v, a: expected the speeds and accelerations with q, got None")
        force, moment = model.shaking(q, v, a, about=about)
    weight = None if gravity is None else model.total_mass * np.asarray(gravity, dtype=float)
    return Shaking(force, moment, about, weight)


@dataclass
class MotionAnalysis:
    """A mechanism along a prescribed motion, per instant (N of them).

    ``tau`` (N, nv): the driving forces (nonzero at the actuated coordinates only, for a
    mechanism with loops); ``bearing`` (N, nlinks, 6): each joint's ``[force; moment]`` on its
    link at the link origin, link axes; ``cut`` (N, nloops, 6): each cut joint's wrench
    (frame a axes, as ``constraint_forces``); ``shaking``: force and moment.

    A run that stopped (Ctrl-C, a ``progress`` callback that raised, an instant that could
    not be closed) raises with the instants done so far attached to the exception as
    ``.result``: a ``MotionAnalysis`` with ``success=False``, ``t_reached`` (the time of the
    last instant analysed; None for none) and ``message`` (how many instants of how many,
    and why it stopped)."""

    model: Any
    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    tau: np.ndarray
    bearing: np.ndarray
    cut: np.ndarray
    shaking: Shaking
    actuated: list[int] | None
    gravity: np.ndarray | None
    input: np.ndarray | None = None
    input_name: str | None = None
    success: bool = True
    t_reached: float | None = None
    message: str = "complete"

    def summary(self) -> dict[str, dict[str, float]]:
        """RMS and peak of the shaking force and moment, the driving force(s) and each
        joint's bearing force."""
        out = {
            "shaking force": {"rms": rms(self.shaking.force), "peak": peak(self.shaking.force)},
            "shaking moment": {
                "rms": rms(self.shaking.moment),
                "peak": peak(self.shaking.moment),
            },
        }
        cols = self.actuated if self.actuated is not None else range(self.tau.shape[1])
        for c in cols:
            out[f"driving force [{c}]"] = {
                "rms": rms(self.tau[:, c]),
                "peak": peak(self.tau[:, c]),
            }
        for i, name in enumerate(self.model.link_names):
            f = self.bearing[:, i, :3]
            out[f"bearing '{name}'"] = {"rms": rms(f), "peak": peak(f)}
        for k, name in enumerate(self.model.loop_names):
            f = self.cut[:, k, :3]
            out[f"cut joint '{name}'"] = {"rms": rms(f), "peak": peak(f)}
        return out

    def units(self) -> dict[str, str]:
        """The unit of each :meth:`summary` entry: N for forces, N·m for the shaking moment
        and for the driving torque of an angular speed."""
        speed = coordinate_units(self.model)[1]
        cols = self.actuated if self.actuated is not None else range(self.tau.shape[1])
        out = {"shaking force": "N", "shaking moment": "N·m"}
        out.update({f"driving force [{c}]": "N·m" if speed[c] == "angular rate" else "N"
                    for c in cols})
        out.update({f"bearing '{n}'": "N" for n in self.model.link_names})
        out.update({f"cut joint '{n}'": "N" for n in self.model.loop_names})
        return out


def analyze_motion(
    model: Any,
    t: Any,
    q: Any,
    v: Any,
    a: Any,
    *,
    actuated: Any = None,
    gravity: Any = None,
    about: Any = (0.0, 0.0, 0.0),
    progress: Callable[[int, int], Any] | None = None,
) -> MotionAnalysis:
    """Driving forces, bearing forces and shaking along given states (N, nq), (N, nv), (N, nv)
    at times ``t`` (N,). A model with loops needs ``actuated`` (as ``inverse_dynamics``); a
    model with joint couplings only takes it too (the driven joints' forces, the coupled
    joints held by their couplings), else each joint's own force.
    ``progress(done, N)``, if given, is called as the states are analysed. A run that stops
    (Ctrl-C, ``progress`` raising) raises with the states analysed so far as the exception's
    ``.result`` (a :class:`MotionAnalysis` with ``success=False``, ``t_reached``,
    ``message``)."""
    t, q, v, a = _state_rows(model, t, q, v, a)
    report = _reporter(progress, len(t))
    rows = _Rows(model, actuated, gravity, about, len(t))
    with rows.keeping_partial():
        for k, (tk, qk, vk, ak) in enumerate(zip(t, q, v, a)):
            report(k)
            rows.add(tk, qk, vk, ak)
        report(len(t))
    return rows.analysis()


class _Rows:
    """The instants analysed so far (kept when a run stops: :meth:`keeping_partial`)."""

    def __init__(self, model, actuated, gravity, about, total: int, driver=None):
        self.model, self.about, self.total, self.driver = model, about, total, driver
        self.g = None if gravity is None else np.asarray(gravity, dtype=float)
        self.act = actuated if model.nloops or model.ncouplings else None
        self.actuated = None if self.act is None else _actuated_indices(model, self.act)
        self.t, self.q, self.v, self.a, self.tau, self.bearing, self.cut = ([] for _ in range(7))

    def add(self, t, q, v, a) -> None:
        b = self.model.bearing_forces(q, v, a, gravity=self.g, actuated=self.act)
        for out, x in zip((self.t, self.q, self.v, self.a, self.tau, self.bearing, self.cut),
                          (t, q, v, a, b["tau"], b["joints"], b["loops"])):
            out.append(x)

    def analysis(self, stopped: BaseException | None = None) -> MotionAnalysis:
        m, n = self.model, len(self.t)
        t = np.array(self.t, dtype=float).reshape(n)
        q, v, a = (np.array(x, dtype=float).reshape(n, w)
                   for x, w in ((self.q, m.nq), (self.v, m.nv), (self.a, m.nv)))
        out = MotionAnalysis(
            model=m, t=t, q=q, v=v, a=a,
            tau=np.array(self.tau).reshape(n, m.nv),
            bearing=np.array(self.bearing).reshape(n, m.nlinks, 6),
            cut=np.array(self.cut).reshape(n, m.nloops, 6),
            shaking=shaking(m, q, v, a, about=self.about, gravity=self.g),
            actuated=self.actuated, gravity=self.g,
            t_reached=float(t[-1]) if n else None,
        )
        if self.driver is not None:
            out.input, out.input_name = self.driver[0][:n], self.driver[1]
        if stopped is not None:
            out.success = False
            out.message = (f"stopped after {n} of {self.total} instants"
                           + (f" (t = {t[-1]:.6g} s)" if n else "") + f": {stop_reason(stopped)}")
        return out

    @contextmanager
    def keeping_partial(self):
        """Any exception inside (Ctrl-C included) leaves with the instants done as its
        ``.result``."""
        try:
            yield
        except BaseException as exc:
            try:
                partial = self.analysis(stopped=exc)
            except Exception:  # nothing to keep: the original exception says why
                raise exc from None
            attach_partial(exc, partial, f"pointmass_dyn: {partial.message}; the instants "
                           "analysed are in this exception's .result")
            raise


def _reporter(progress, total: int, scale: int = 1):
    """``report(k)``: calls ``progress(scale * k, scale * total)`` every 64th state and at
    the end (a callback per state would cost more than a short model's state)."""
    if progress is None:
        return lambda k: None

    def report(k: int) -> None:
        if k % 64 == 0 or k == total:
            progress(scale * k, scale * total)

    return report


def _state_rows(model, t, q, v, a):
    """``t`` (N,) finite, and ``q``, ``v``, ``a`` as (N, nq), (N, nv), (N, nv): one state per
    time; anything else is an :class:`InvalidInputError` naming the array and both shapes."""
    for name, x in (("t", t), ("q", q), ("v", v), ("a", a)):
        if np.iscomplexobj(x):  # NumPy would drop the imaginary part with only a warning
            raise InvalidInputError(f"{name}: expected real numbers, got complex values")
    t = float_array("t", t)
    if t.ndim != 1 or len(t) == 0 or not np.all(np.isfinite(t)):
        raise InvalidInputError(
            f"t: expected a non-empty 1-D array of finite times, got shape {t.shape}"
            + ("" if t.size == 0 or np.all(np.isfinite(t)) else " with non-finite entries")
        )
    n = len(t)
    out = [t]
    for name, x, width in (("q", q, model.nq), ("v", v, model.nv), ("a", a, model.nv)):
        x = float_array(name, x)
        if x.ndim == 1 and n == 1:
            x = x.reshape(1, -1)
        if x.shape != (n, width):
            raise InvalidInputError(
                f"{name}: expected shape ({n}, {width}) (one row per time in t), got {x.shape}"
            )
        out.append(x)
    return out


def _actuated_indices(model, actuated) -> list[int]:
    """v indices of ``actuated`` (ints: v indices; names: all speeds of that body's joint)."""
    items = [actuated] if isinstance(actuated, (str, int, np.integer)) else list(actuated)
    out = []
    for item in items:
        if isinstance(item, str):
            if item not in model.body_names:
                raise InvalidInputError(f"actuated: no body named '{item}'")
            link = model.body_info(model.body_names.index(item))[3]
            if link < 0:
                raise InvalidInputError(f"actuated: '{item}' has no joint coordinates")
            _, iv, _, nv = model.joint_slices()[link]
            out.extend(range(iv, iv + nv))
        else:
            out.append(_index(item, "actuated"))
    return sorted(set(out))


def _index(x, arg: str) -> int:
    """An int index (a Python or NumPy integer, not a bool), else an error naming ``arg``."""
    if isinstance(x, (int, np.integer)) and not isinstance(x, (bool, np.bool_)):
        return int(x)
    raise InvalidInputError(f"{arg}: expected a body name or an int index, got {x!r}")


def _driver_slot(model, driver) -> tuple[str, int, int]:
    """(body name, q index, v index) of a 1-dof driving joint."""
    names = model.body_names
    if isinstance(driver, str):
        if driver not in names:
            raise InvalidInputError(
                f"driver: expected a body name, got '{driver}' (bodies: {names})"
            )
        body = names.index(driver)
    else:
        body = _index(driver, "driver")
        if not 0 <= body < len(names):
            raise InvalidInputError(
                f"driver: expected a body index 0..{len(names) - 1}, got {body}"
            )
    link = model.body_info(body)[3]
    if link < 0 or model.link_names[link] != names[body]:
        raise InvalidInputError(f"driver: expected a body on a moving joint, got '{names[body]}'")
    iq, iv, nq, nv = model.joint_slices()[link]
    if nq != 1 or nv != 1:
        raise InvalidInputError(
            f"driver: expected a 1-dof joint (revolute or prismatic), got '{names[body]}' with "
            f"nq = {nq}, nv = {nv}"
        )
    return names[body], iq, iv


def prescribed_motion(
    model: Any,
    driver: Any,
    *,
    speed: float | None = None,
    samples: int = 360,
    revolutions: float = 1.0,
    start: float | None = None,
    q_guess: Any = None,
    input: tuple | None = None,
    gravity: Any = None,
    about: Any = (0.0, 0.0, 0.0),
    progress: Callable[[int, int], Any] | None = None,
) -> MotionAnalysis:
    """A one-input mechanism driven by ``driver`` (a 1-dof joint's body): at constant
    ``speed`` (rad/s or m/s) over ``revolutions`` turns sampled at ``samples`` uniformly
    spaced instants (the end excluded, so RMS values are over whole cycles), or along a
    tabulated ``input = (t, position, rate, acceleration)`` (arrays of one length).

    Each instant's state is closed by ``assemble`` with the driver held, continuing from the
    previous instant (from ``q_guess``, default the model's closed guess: a scene's
    ``q0``), so the mechanism stays on one assembly branch. Freedoms the driver leaves
    (the idle spin of an RSSR's coupler) take minimum-norm speeds and the accelerations the
    dynamics gives them. Returns a :class:`MotionAnalysis`. ``progress(done, 2 N)``, if given,
    is called as the N instants are closed and analysed (two steps each; long runs show it).

    Ctrl-C, a ``progress`` callback that raises, or an instant that cannot be closed stops
    the run: the exception propagates as itself with the instants done so far attached as
    ``.result`` (a :class:`MotionAnalysis` with ``success=False``, ``t_reached`` the last
    instant's time and ``message`` saying how many instants of how many and why)."""
    name, iq, iv = _driver_slot(model, driver)
    kind = model.body_info(model.body_names.index(name))[1]
    if input is None and kind != "Revolute":
        raise InvalidInputError(
            f"input: a {kind} driver ('{name}') has no revolution to sample; give its motion "
            f"as input=(t, position, rate, acceleration)"
        )
    q0 = np.asarray(model.neutral() if q_guess is None else q_guess, dtype=float).copy()
    if input is not None:
        t, pos, rate, acc = (np.asarray(x, dtype=float).reshape(-1) for x in input)
        if not len(t) == len(pos) == len(rate) == len(acc) or len(t) == 0:
            raise InvalidInputError(
                "input: expected (t, position, rate, acceleration) of one non-zero length, got "
                f"lengths {[len(x) for x in (t, pos, rate, acc)]}"
            )
        if not all(np.all(np.isfinite(x)) for x in (t, pos, rate, acc)):
            raise InvalidInputError("input: expected finite values, got NaN or infinity")
    else:
        if speed is None or not np.isfinite(speed) or speed == 0.0:
            raise InvalidInputError(f"speed: expected a finite non-zero driver speed, got {speed}")
        samples = sample_count("samples", samples, lowest=2)
        if not (np.isfinite(revolutions) and revolutions > 0):
            raise InvalidInputError(
                f"revolutions: expected a finite positive number of turns, got {revolutions}"
            )
        theta0 = q0[iq] if start is None else float(start)
        span = 2.0 * np.pi * revolutions
        pos = theta0 + np.sign(speed) * span * np.arange(samples) / samples
        t = (pos - theta0) / speed
        rate = np.full(samples, float(speed))
        acc = np.zeros(samples)
    n = len(t)
    guess = q0
    loops = model.nloops > 0 or model.ncouplings > 0  # constrained: closed at each instant
    # Freedoms the driver does not set (an RSSR coupler's spin about its own axis) move as
    # the dynamics says: their speeds are taken at minimum norm, their accelerations from
    # forward dynamics under the driver force that gives the prescribed acceleration.
    idle = (
        loops
        and model.nv
        - np.linalg.matrix_rank(
            model.constraint_jacobian(model.assemble(q0, fixed=[name])), tol=1e-9
        )
        > 1
    )
    g = None if gravity is None else np.asarray(gravity, dtype=float)
    report = _reporter(progress, n, scale=2)
    rows = _Rows(model, [name], gravity, about, n, driver=(pos, name))
    with rows.keeping_partial():
        for k in range(n):
            report(k)
            guess, vk, ak = _closed_instant(model, name, (iq, iv), guess, (pos[k], rate[k], acc[k]),
                                            loops, idle, g)
            rows.add(t[k], guess, vk, ak)
        report(n)
    return rows.analysis()


def _closed_instant(model, name, slot, guess, driven, loops, idle, g):
    """The state ``(q, v, a)`` of one instant with the driver (q and v index ``slot``) at
    ``driven = (position, rate, acceleration)``, closed from ``guess`` (see
    :func:`prescribed_motion`)."""
    (iq, iv), (pos, rate, acc) = slot, driven
    guess = guess.copy()
    guess[iq] = pos
    vk = np.zeros(model.nv)
    vk[iv] = rate
    ak = np.zeros(model.nv)
    ak[iv] = acc
    if loops:
        guess = model.assemble(guess, fixed=[name])
        vk = model.assemble_velocity(guess, vk, fixed=[name])
        if idle:
            zero = np.zeros(model.nv)
            a0 = model.forward_dynamics(guess, vk, zero, gravity=g)
            unit = zero.copy()
            unit[iv] = 1.0
            per_unit = model.forward_dynamics(guess, vk, unit, gravity=g) - a0
            ak = a0 + per_unit * ((acc - a0[iv]) / per_unit[iv])
            ak[iv] = acc
        else:
            ak = model.assemble_acceleration(guess, vk, ak, fixed=[name])
    elif model.nv != 1:
        raise InvalidInputError(
            f"driver: a model without loops or couplings moves with one input only if it "
            f"has one degree of freedom (this one has nv = {model.nv}); give every "
            f"coordinate's motion to analyze_motion instead"
        )
    return guess, vk, ak
