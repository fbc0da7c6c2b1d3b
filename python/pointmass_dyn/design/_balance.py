"""Shaking forces, bearing forces and balancing with point masses (docs/balancing.md).

A moving mechanism shakes its ground with the resultant of its inertia forces, the shaking
force ``F = −Σ m_ij a_ij`` and moment ``M_O = −Σ m_ij (r_ij − O) × a_ij`` over every point
mass (gravity excluded: the weight is steady and reported apart). For a prescribed motion the
point masses' positions and accelerations are fixed, so the shaking force, the shaking
moment and the driving torque are **linear in the masses** placed at given body points: a
link's own seven point masses, or counterweights at candidate points. Balancing is then a
least-squares problem with linear equalities (e.g. zero shaking force) and bounds (a
counterweight's mass is not negative), solved exactly here, not by a search.

* :func:`shaking` — shaking force and moment per state, over arrays of states or along a
  :class:`~pointmass_dyn.SimulationResult`.
* :func:`prescribed_motion` — a mechanism driven at a prescribed input (a crank at constant
  speed over a revolution, or a tabulated input): per instant the whole state, driving
  torque, bearing forces, shaking force and moment (:class:`MotionAnalysis`).
* :func:`balance` — counterweights and/or redesigned links that minimise weighted RMS
  shaking force, moment and driving torque, subject to chosen ones being zero
  (:class:`Balance`); :func:`pareto_front` between two objectives.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _core
from .errors import InvalidInputError, NumericalError

OBJECTIVES = ("force", "moment", "torque")


def _rms(x: np.ndarray) -> float:
    """RMS of the magnitude of the rows of x (N, k), or of x (N,)."""
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return 0.0
    sq = x**2 if x.ndim == 1 else np.sum(x**2, axis=-1)
    return float(np.sqrt(np.mean(sq)))


def _peak(x: np.ndarray) -> float:
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return 0.0
    return float(np.max(np.abs(x) if x.ndim == 1 else np.linalg.norm(x, axis=-1)))


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
        return {"force": _rms(self.force), "moment": _rms(self.moment)}

    @property
    def peak(self) -> dict[str, float]:
        return {"force": _peak(self.force), "moment": _peak(self.moment)}


def _gravity_of(scene) -> np.ndarray | None:
    """The sum of a scene's gravity effects (None without one)."""
    if "gravity" in (scene.disable or ()):
        return None
    gs = [np.asarray(e.g) for e in scene.effects if e.g is not None]
    return np.sum(gs, axis=0) if gs else None


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
        a = np.array(
            [
                model.forward_dynamics(qk, vk, sum(_core.effect_forces(scene, t, qk, vk).values()))
                for t, qk, vk in zip(result.t, q, v)
            ]
        ).reshape(len(result.t), model.nv)
        if gravity is None:
            gravity = _gravity_of(scene)
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
    (frame a axes, as ``constraint_forces``); ``shaking``: force and moment."""

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

    def summary(self) -> dict[str, dict[str, float]]:
        """RMS and peak of the shaking force and moment, the driving force(s) and each
        joint's bearing force."""
        out = {
            "shaking force": {"rms": _rms(self.shaking.force), "peak": _peak(self.shaking.force)},
            "shaking moment": {
                "rms": _rms(self.shaking.moment),
                "peak": _peak(self.shaking.moment),
            },
        }
        cols = self.actuated if self.actuated is not None else range(self.tau.shape[1])
        for c in cols:
            out[f"driving force [{c}]"] = {
                "rms": _rms(self.tau[:, c]),
                "peak": _peak(self.tau[:, c]),
            }
        for i, name in enumerate(self.model.link_names):
            f = self.bearing[:, i, :3]
            out[f"bearing '{name}'"] = {"rms": _rms(f), "peak": _peak(f)}
        for k, name in enumerate(self.model.loop_names):
            f = self.cut[:, k, :3]
            out[f"cut joint '{name}'"] = {"rms": _rms(f), "peak": _peak(f)}
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
) -> MotionAnalysis:
    """Driving forces, bearing forces and shaking along given states (N, nq), (N, nv), (N, nv)
    at times ``t`` (N,). A model with loops needs ``actuated`` (as ``inverse_dynamics``)."""
    t = np.asarray(t, dtype=float).reshape(-1)
    q = np.asarray(q, dtype=float).reshape(len(t), model.nq)
    v = np.asarray(v, dtype=float).reshape(len(t), model.nv)
    a = np.asarray(a, dtype=float).reshape(len(t), model.nv)
    g = None if gravity is None else np.asarray(gravity, dtype=float)
    act = None if model.nloops == 0 else actuated
    tau, bearing, cut = [], [], []
    for qk, vk, ak in zip(q, v, a):
        b = model.bearing_forces(qk, vk, ak, gravity=g, actuated=act)
        tau.append(b["tau"])
        bearing.append(b["joints"])
        cut.append(b["loops"])
    sh = shaking(model, q, v, a, about=about, gravity=g)
    actuated_idx = None if act is None else _actuated_indices(model, act)
    return MotionAnalysis(
        model=model,
        t=t,
        q=q,
        v=v,
        a=a,
        tau=np.array(tau).reshape(len(t), model.nv),
        bearing=np.array(bearing).reshape(len(t), model.nlinks, 6),
        cut=np.array(cut).reshape(len(t), model.nloops, 6),
        shaking=sh,
        actuated=actuated_idx,
        gravity=g,
    )


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
            out.append(int(item))
    return sorted(set(out))


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
        body = int(driver)
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
) -> MotionAnalysis:
    """A one-input mechanism driven by ``driver`` (a 1-dof joint's body): at constant
    ``speed`` (rad/s or m/s) over ``revolutions`` turns sampled at ``samples`` uniformly
    spaced instants (the end excluded, so RMS values are over whole cycles), or along a
    tabulated ``input = (t, position, rate, acceleration)`` (arrays of one length).

    Each instant's state is closed by ``assemble`` with the driver held, continuing from the
    previous instant (from ``q_guess``, default the model's closed guess: a scene's
    ``q0``), so the mechanism stays on one assembly branch. Freedoms the driver leaves
    (the idle spin of an RSSR's coupler) take minimum-norm speeds and the accelerations the
    dynamics gives them. Returns a :class:`MotionAnalysis`."""
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
        if not len(t) == len(pos) == len(rate) == len(acc):
            raise InvalidInputError(
                "input: expected (t, position, rate, acceleration) of one length"
            )
    else:
        if speed is None or not np.isfinite(speed) or speed == 0.0:
            raise InvalidInputError(f"speed: expected a finite non-zero driver speed, got {speed}")
        if samples < 2:
            raise InvalidInputError(f"samples: expected at least 2, got {samples}")
        theta0 = q0[iq] if start is None else float(start)
        span = 2.0 * np.pi * revolutions
        pos = theta0 + np.sign(speed) * span * np.arange(samples) / samples
        t = (pos - theta0) / speed
        rate = np.full(samples, float(speed))
        acc = np.zeros(samples)
    n = len(t)
    q = np.empty((n, model.nq))
    v = np.empty((n, model.nv))
    a = np.empty((n, model.nv))
    guess = q0
    loops = model.nloops > 0
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
    for k in range(n):
        guess = guess.copy()
        guess[iq] = pos[k]
        vk = np.zeros(model.nv)
        vk[iv] = rate[k]
        ak = np.zeros(model.nv)
        ak[iv] = acc[k]
        if loops:
            guess = model.assemble(guess, fixed=[name])
            vk = model.assemble_velocity(guess, vk, fixed=[name])
            if idle:
                zero = np.zeros(model.nv)
                a0 = model.forward_dynamics(guess, vk, zero, gravity=g)
                unit = zero.copy()
                unit[iv] = 1.0
                per_unit = model.forward_dynamics(guess, vk, unit, gravity=g) - a0
                ak = a0 + per_unit * ((acc[k] - a0[iv]) / per_unit[iv])
                ak[iv] = acc[k]
            else:
                ak = model.assemble_acceleration(guess, vk, ak, fixed=[name])
        elif model.nv != 1:
            raise InvalidInputError(
                f"driver: a model without loops moves with one input only if it has one degree "
                f"of freedom (this one has nv = {model.nv}); give every coordinate's motion to "
                f"analyze_motion instead"
            )
        q[k], v[k], a[k] = guess, vk, ak
    out = analyze_motion(model, t, q, v, a, actuated=[name], gravity=gravity, about=about)
    out.input, out.input_name = pos, name
    return out


@dataclass(frozen=True)
class Counterweight:
    """Candidate counterweight positions on one body: point masses at ``points`` (K, 3) in the
    body's frame, each of mass in ``[0, max_mass]`` (``None``: unbounded). Balancing chooses
    their masses; a ring of candidates around a pivot lets it place a counterweight at any
    angle (two neighbours share it)."""

    body: Any
    points: Any
    max_mass: float | None = None

    @staticmethod
    def ring(
        body: Any,
        center: Any,
        radius: float,
        count: int = 24,
        normal: Any = (0, 0, 1),
        max_mass: float | None = None,
    ) -> Counterweight:
        """``count`` candidates on a circle of ``radius`` about ``center`` in the plane normal
        to ``normal`` (body frame)."""
        n = np.asarray(normal, dtype=float)
        n = n / np.linalg.norm(n)
        u = np.cross(n, [1.0, 0.0, 0.0])
        if np.linalg.norm(u) < 1e-8:
            u = np.cross(n, [0.0, 1.0, 0.0])
        u /= np.linalg.norm(u)
        w = np.cross(n, u)
        ang = 2 * np.pi * np.arange(count) / count
        pts = np.asarray(center, float) + radius * (
            np.outer(np.cos(ang), u) + np.outer(np.sin(ang), w)
        )
        return Counterweight(body, pts, max_mass)


@dataclass
class Balance:
    """The result of :func:`balance`.

    ``counterweights``: ``(body name, position in the body frame (3,), mass)`` of each
    counterweight placed (mass above ``1e-12`` of the largest); ``bodies``: each changed
    body's new :class:`RigidBody` (mass, COM, inertia, all physically valid); ``model``: the
    balanced model; ``before`` / ``after``: the analysis of the original and of the balanced
    model along the same motion (recomputed, not predicted); ``predicted``: the objective
    quantities the linear model gave, which ``after`` reproduces to round-off."""

    masses: np.ndarray
    counterweights: list[tuple[str, np.ndarray, float]]
    bodies: dict[str, Any]
    model: Any
    before: MotionAnalysis
    after: MotionAnalysis
    predicted: dict[str, np.ndarray]
    objective: dict[str, float]
    zero: tuple[str, ...]
    message: str = ""
    extras: dict = field(default_factory=dict)

    def table(self) -> str:
        """Before/after RMS and peaks, as text."""
        b, a = self.before.summary(), self.after.summary()
        rows = [
            f"{'quantity':<34}{'RMS before':>13}{'RMS after':>13}{'peak before':>13}{'peak after':>13}"
        ]
        for k in b:
            rows.append(
                f"{k:<34}{b[k]['rms']:>13.5g}{a[k]['rms']:>13.5g}{b[k]['peak']:>13.5g}{a[k]['peak']:>13.5g}"
            )
        return "\n".join(rows)


def _objective_rows(motion: MotionAnalysis, reg: dict, what: str, about):
    """The linear model of one objective quantity: its current value y0 (N·k,) and the change
    per unit mass at each design point A (N·k, P)."""
    pos, acc, gen = reg["positions"], reg["accelerations"], reg["generalized"]
    n = len(motion.t)
    if what == "force":
        y0 = motion.shaking.force.reshape(-1)
        a = -np.transpose(acc, (0, 2, 1)).reshape(n * 3, -1)
        return y0, a
    if what == "moment":
        y0 = motion.shaking.moment.reshape(-1)
        m = -np.cross(pos - np.asarray(about, float), acc)  # (N, P, 3)
        return y0, np.transpose(m, (0, 2, 1)).reshape(n * 3, -1)
    if what == "torque":
        cols = motion.actuated if motion.actuated is not None else list(range(motion.model.nv))
        y0 = motion.tau[:, cols].reshape(-1)
        if motion.model.nloops == 0:
            a = gen[:, :, cols]
        else:
            # τ_a and λ solve [S_a | Jᵀ] x = τ_tree (minimum norm): a linear map of τ_tree.
            a = np.empty((n, gen.shape[1], len(cols)))
            nv = motion.model.nv
            for k in range(n):
                s = np.zeros((nv, len(cols)))
                s[cols, range(len(cols))] = 1.0
                sys = np.hstack([s, motion.model.constraint_jacobian(motion.q[k]).T])
                op = np.linalg.pinv(sys, rcond=1e-12)[: len(cols)]
                a[k] = gen[k] @ op.T
        return y0, np.transpose(a, (0, 2, 1)).reshape(n * len(cols), -1)
    raise InvalidInputError(f"objective: expected keys among {OBJECTIVES}, got '{what}'")


def _design_points(model, links, counterweights):
    """The design point masses: [(body name, position in the body frame, current mass, lower,
    upper)], the links' own equimomental points first."""
    names = model.body_names
    out = []
    for body in links:
        name = body if isinstance(body, str) else names[int(body)]
        rb = model.body(name)
        pm = rb.point_masses()
        for m, p in zip(pm.masses, pm.positions):
            out.append((name, np.array(p), float(m), 0.0, np.inf))
    for cw in counterweights:
        name = cw.body if isinstance(cw.body, str) else names[int(cw.body)]
        model.body(name)  # checks it exists
        pts = np.atleast_2d(np.asarray(cw.points, dtype=float))
        if pts.shape[1] != 3:
            raise InvalidInputError(
                f"counterweights: points of '{name}' must be (K, 3), got {pts.shape}"
            )
        hi = np.inf if cw.max_mass is None else float(cw.max_mass)
        for p in pts:
            out.append((name, p, 0.0, 0.0, hi))
    return out


def _solve_qp(h, c, ce, de, lb, ub, x0=None):
    """min ½ xᵀ H x + cᵀ x  s.t.  Cₑ x = dₑ (independent rows), lb ≤ x ≤ ub (lb finite).

    A primal–dual interior-point method (Mehrotra's predictor–corrector), which degenerate
    problems — many masses at zero, more equalities than free masses — do not trouble, then
    a polish: the bounds it finds active are fixed and the equality-constrained problem on
    the others is solved exactly, kept if it is feasible and no worse. Variables with
    equal bounds are substituted first."""
    pinned = lb >= ub
    if pinned.any():
        keep = ~pinned
        xp = np.where(pinned, lb, 0.0)
        sub = _solve_qp(
            h[np.ix_(keep, keep)],
            c[keep] + h[np.ix_(keep, pinned)] @ xp[pinned],
            ce[:, keep],
            de - ce[:, pinned] @ xp[pinned],
            lb[keep],
            ub[keep],
            None if x0 is None else x0[keep],
        )
        xp[keep] = sub
        return xp
    n, m = len(c), ce.shape[0]
    finite_ub = np.isfinite(ub)
    span = np.where(finite_ub, ub - lb, 1.0)
    x = lb + np.where(finite_ub, 0.5 * span, 1.0)
    if x0 is not None:
        x = np.clip(x0, lb + 1e-3 * span, np.where(finite_ub, ub - 1e-3 * span, np.inf))
    y = np.zeros(m)
    zl = np.ones(n)
    zu = np.where(finite_ub, 1.0, 0.0)
    scale = 1.0 + max(np.abs(h).max(initial=0.0), np.abs(c).max(initial=0.0))
    for _ in range(100):
        sl = x - lb
        su = np.where(finite_ub, ub - x, 1.0)
        r_dual = h @ x + c + ce.T @ y - zl + zu
        r_prim = ce @ x - de
        mu = (sl @ zl + (su * zu)[finite_ub].sum()) / (n + finite_ub.sum())
        # The polish below makes the answer exact; the interior point needs only to find
        # the active bounds (its residuals stall near 1e-11 as gaps reach 1e-20).
        if (
            np.abs(r_dual).max(initial=0.0) < 1e-10 * scale
            and np.abs(r_prim).max(initial=0.0) < 1e-11 * (1.0 + np.abs(de).max(initial=0.0))
            and mu < 1e-13 * scale
        ):
            break
        d = zl / sl + np.where(finite_ub, zu / su, 0.0)
        kkt = np.zeros((n + m, n + m))
        kkt[:n, :n] = h + np.diag(d)
        kkt[:n, n:] = ce.T
        kkt[n:, :n] = ce

        def direction(sigma_mu, dx_aff=None, dzl_aff=None, dzu_aff=None):
            # Complementarity targets sl·zl = σμ (− the predictor's second-order term).
            cl = sigma_mu - sl * zl
            cu = np.where(finite_ub, sigma_mu - su * zu, 0.0)
            if dx_aff is not None:
                cl = cl - dx_aff * dzl_aff
                cu = cu + np.where(finite_ub, dx_aff * dzu_aff, 0.0)
            rhs = np.concatenate([-r_dual + cl / sl - np.where(finite_ub, cu / su, 0.0), -r_prim])
            try:
                sol = np.linalg.solve(kkt, rhs)
            except np.linalg.LinAlgError:
                sol = np.linalg.lstsq(kkt, rhs, rcond=1e-14)[0]
            dx = sol[:n]
            dzl = (cl - zl * dx) / sl
            dzu = np.where(finite_ub, (cu + zu * dx) / su, 0.0)
            return dx, sol[n:], dzl, dzu

        def longest(dx, dzl, dzu):
            steps = [1.0]
            for v, dv in ((sl, dx), (zl, dzl)):
                neg = dv < 0
                if neg.any():
                    steps.append(np.min(-v[neg] / dv[neg]))
            for v, dv in ((su, -dx), (zu, dzu)):
                neg = finite_ub & (dv < 0)
                if neg.any():
                    steps.append(np.min(-v[neg] / dv[neg]))
            return min(steps)

        dx, dy, dzl, dzu = direction(0.0)
        a_aff = longest(dx, dzl, dzu)
        sl_a, zl_a = sl + a_aff * dx, zl + a_aff * dzl
        su_a, zu_a = su - a_aff * dx, zu + a_aff * dzu
        mu_aff = (sl_a @ zl_a + (su_a * zu_a)[finite_ub].sum()) / (n + finite_ub.sum())
        sigma = (mu_aff / mu) ** 3 if mu > 0 else 0.0
        dx, dy, dzl, dzu = direction(sigma * mu, dx, dzl, dzu)
        alpha = 0.99 * longest(dx, dzl, dzu)
        x, y = x + alpha * dx, y + alpha * dy
        zl, zu = zl + alpha * dzl, np.where(finite_ub, zu + alpha * dzu, 0.0)
    else:
        raise NumericalError(
            f"balance: the quadratic program did not converge ({n} design masses); the "
            f"problem may be badly scaled"
        )
    return _polish(h, c, ce, de, lb, ub, x, zl, zu)


def _polish(h, c, ce, de, lb, ub, x, zl, zu):
    """The exact solution on the active set the interior point found (bounds whose
    multiplier exceeds their gap), if it is feasible and no worse; else ``x``."""
    at_lb = (x - lb) < zl
    at_ub = np.isfinite(ub) & ((ub - x) < zu)
    fixed = at_lb | at_ub
    free = np.flatnonzero(~fixed)
    xf = np.where(at_lb, lb, np.where(at_ub, ub, 0.0))
    m = ce.shape[0]
    k = len(free)
    kkt = np.zeros((k + m, k + m))
    kkt[:k, :k] = h[np.ix_(free, free)]
    kkt[:k, k:] = ce[:, free].T
    kkt[k:, :k] = ce[:, free]
    rhs = np.concatenate([-(c[free] + h[free] @ xf), de - ce @ xf])
    sol = np.linalg.lstsq(kkt, rhs, rcond=1e-14)[0]
    polished = xf.copy()
    polished[free] = sol[:k]
    feasible = (
        np.all(polished >= lb - 1e-12 * (1 + np.abs(lb)))
        and np.all(polished <= ub + 1e-12 * (1 + np.abs(ub)))
        and np.abs(ce @ polished - de).max(initial=0.0)
        <= max(1e-12 * (1.0 + np.abs(de).max(initial=0.0)), np.abs(ce @ x - de).max(initial=0.0))
    )
    if not feasible:
        return x
    polished = np.clip(polished, lb, ub)

    def cost(v):
        return 0.5 * v @ h @ v + c @ v

    return polished if cost(polished) <= cost(x) + 1e-12 * (1 + abs(cost(x))) else x


def _row_space(ce: np.ndarray, de: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Equalities ``Cₑ x = dₑ`` as an orthonormal basis of their row space (N instants give
    many more rows than design variables), after checking they can be met at all."""
    p = ce.shape[1]
    if ce.shape[0] == 0:
        return np.zeros((0, p)), np.zeros(0)
    # Round-off entries (a planar mechanism's out-of-plane rows, ~1e-300 after scaling) are
    # flushed: subnormal numbers slow LAPACK down a thousandfold.
    big = np.abs(ce).max(initial=0.0)
    ce = np.where(np.abs(ce) < 1e-15 * big, 0.0, ce)
    # Tall systems are first reduced to a square one by QR in blocks of rows: a tall SVD or
    # QR goes to multithreaded LAPACK, which a busy machine slows a thousandfold, small
    # factorisations do not. `lost²` is the part of dₑ that no combination of rows reaches.
    lost2 = 0.0
    if ce.shape[0] > 2 * p:
        rf, tf = np.zeros((0, p)), np.zeros(0)
        for k in range(0, ce.shape[0], 2 * p):
            stack = np.vstack([rf, ce[k : k + 2 * p]])
            rhs = np.concatenate([tf, de[k : k + 2 * p]])
            qb, rf = np.linalg.qr(stack)
            tf = qb.T @ rhs
            lost2 += float(np.sum((rhs - qb @ tf) ** 2))
        ce, de = rf, tf
    u, sv, vt = np.linalg.svd(ce, full_matrices=False)
    r = int(np.sum(sv > 1e-12 * sv.max(initial=0.0)))
    outside = np.sqrt(lost2 + float(np.sum((de - u[:, :r] @ (u[:, :r].T @ de)) ** 2)))
    if outside > 1e-9 * (1.0 + np.linalg.norm(de)):
        raise InvalidInputError(
            f"zero: no masses at the design points make {what} vanish at every instant "
            f"(residual {outside:.3e}); add counterweight candidates on other links"
        )
    return vt[:r], (u[:, :r].T @ de) / sv[:r]


def balance(
    motion: MotionAnalysis,
    *,
    counterweights: Sequence[Counterweight] = (),
    links: Sequence[Any] = (),
    link_mass: tuple[float, float] = (1.0, 1.0),
    objective: dict[str, float] | None = None,
    zero: Sequence[str] = (),
    regularization: float = 1e-3,
) -> Balance:
    """Balance a mechanism along a prescribed ``motion`` (from :func:`prescribed_motion`).

    Design variables are point masses at fixed body points: ``counterweights`` (masses ≥ 0 at
    candidate points) and/or ``links`` (bodies whose own seven equimomental point masses
    are redesigned, kept ≥ 0 so the body stays physical, their total within ``link_mass``
    times the current mass: by default the mass is redistributed, not changed). ``objective`` weights the RMS of
    ``"force"`` (shaking force), ``"moment"`` (shaking moment about the motion's ``about``)
    and ``"torque"`` (driving force), each relative to its unbalanced RMS (default
    ``{"force": 1}``); ``zero`` lists those that must vanish at every instant (linear
    equalities, e.g. ``zero=("force",)`` for complete force balance). Among equal optima the
    least added mass wins (then, by ``regularization``, the smallest masses).

    The quantities are linear in the design masses for the given motion, so the problem is a
    convex quadratic program, solved exactly; the balanced model is then analysed again along
    the same motion (``after``)."""
    model = motion.model
    objective = {"force": 1.0} if objective is None else dict(objective)
    for k in list(objective) + list(zero):
        if k not in OBJECTIVES:
            raise InvalidInputError(f"objective/zero: expected keys among {OBJECTIVES}, got '{k}'")
    design = _design_points(model, list(links), list(counterweights))
    if not design:
        raise InvalidInputError("counterweights, links: give at least one design point mass")
    about = motion.shaking.about
    pts = [(d[0], d[1]) for d in design]
    reg = model.point_regressor(motion.q, motion.v, motion.a, points=pts, gravity=motion.gravity)
    x_now = np.array([d[2] for d in design])
    lb = np.array([d[3] for d in design])
    ub = np.array([d[4] for d in design])
    nd = len(design)
    # A redesigned link's total mass is a bounded slack variable s with Σ x_link − s = 0.
    lo, hi = (float(f) for f in link_mass)
    if not 0.0 < lo <= hi:
        raise InvalidInputError(f"link_mass: expected factors 0 < low <= high, got {link_mass}")
    names = [b if isinstance(b, str) else model.body_names[int(b)] for b in links]
    mass_rows = []
    for k, name in enumerate(names):
        row = np.zeros(nd + len(names))
        row[[j for j, d in enumerate(design[: 7 * len(names)]) if d[0] == name]] = 1.0
        row[nd + k] = -1.0
        mass_rows.append(row)
        m0 = model.body(name).mass
        x_now = np.append(x_now, m0)
        lb, ub = np.append(lb, lo * m0), np.append(ub, hi * m0)
    p = nd + len(names)
    pad = np.zeros((0, len(names)))
    h = np.zeros((p, p))
    c = np.zeros(p)
    ce_rows, de_rows, lin, weighted = list(mass_rows), [np.zeros(len(names))], {}, []
    for what in sorted(set(objective) | set(zero)):
        y0, a = _objective_rows(motion, reg, what, about)
        a = np.hstack([a, np.zeros((a.shape[0], pad.shape[1]))])
        # y(x) = y0 + A (x − x_now): as a function of x, y = (y0 − A x_now) + A x.
        b = y0 - a @ x_now
        lin[what] = (a, b)
        w = objective.get(what, 0.0)
        if what in zero:
            ce_rows.append(a)
            de_rows.append(-b)
        elif w > 0:
            scale = max(_rms(y0.reshape(len(motion.t), -1)), 1e-300) ** 2 * len(motion.t)
            h += (w / scale) * (a.T @ a)
            c += (w / scale) * (a.T @ b)
            weighted.append(np.sqrt(w / scale) * a)
    ce, de = _row_space(
        np.vstack(ce_rows) if ce_rows else np.zeros((0, p)),
        np.concatenate(de_rows),
        what=", ".join(zero) or "the link masses",
    )
    # A feasible start: the bounded point nearest the equalities (phase 1), checked.
    x_start = np.clip(x_now, lb, ub)
    if ce.shape[0]:
        x_start = _solve_qp(ce.T @ ce, -ce.T @ de, np.zeros((0, p)), np.zeros(0), lb, ub, x_start)
        miss = np.abs(ce @ x_start - de).max()
        if miss > 1e-9 * (1.0 + np.abs(de).max()):
            raise InvalidInputError(
                f"zero: the design point masses cannot make {', '.join(zero)} vanish at every "
                f"instant within their bounds (best residual {miss:.3e}); add counterweight "
                f"candidates on other links, or relax the bounds"
            )
    # 1. The weighted objective (strictly convex in the objective's values A x).
    base = np.trace(h) / p if np.trace(h) > 0 else 1.0
    x = _solve_qp(h + 1e-14 * base * np.eye(p), c, ce, de, lb, ub, x_start)
    # 2. Among its optima (all share A x), the least added mass: an L1 term (masses ≥ 0)
    #    well above an L2 one that keeps the subproblems strictly convex.
    #    The optimal values A x are unique; where the bounds do not decide them they are
    #    those of the equality-constrained least squares, exactly (the interior point gives
    #    them to ~1e-10 only): try those first.
    m_scale = model.total_mass / max(model.nlinks, 1)
    l1 = np.concatenate([np.ones(nd), np.zeros(p - nd)]) / m_scale
    h2 = regularization * np.eye(p) / m_scale**2
    if weighted:
        w = np.vstack(weighted)
        k = ce.shape[0]
        kkt = np.block([[h, ce.T], [ce, np.zeros((k, k))]])
        free_opt = np.linalg.lstsq(kkt, np.concatenate([-c, de]), rcond=1e-13)[0][:p]
        tries = [w @ free_opt, w @ x]
        for target in tries:
            try:
                ce2, de2 = _row_space(
                    np.vstack([ce, w]), np.concatenate([de, target]), what="objective"
                )
                x2 = _solve_qp(h2, l1, ce2, de2, lb, ub, x)
            except (InvalidInputError, NumericalError):
                continue
            if np.abs(ce2 @ x2 - de2).max() <= 1e-9 * (1.0 + np.abs(de2).max()):
                x = x2
                break
        x = x[:nd]
    else:
        x = _solve_qp(h2, l1, ce, de, lb, ub, x)[:nd]
    lb, ub = lb[:nd], ub[:nd]
    # Rebuild the changed bodies from their point masses and analyse the balanced model.
    groups: dict[str, list[int]] = {}
    for j, d in enumerate(design):
        groups.setdefault(d[0], []).append(j)
    redesigned = {model.body_names[int(b)] if not isinstance(b, str) else b for b in links}
    bodies, new_model = {}, model
    for name, idx in groups.items():
        masses = [x[j] for j in idx]
        positions = [design[j][1] for j in idx]
        if name not in redesigned:
            pm = model.body(name).point_masses()
            masses = list(pm.masses) + masses
            positions = list(pm.positions) + positions
        body = _core.RigidBody.from_point_masses(np.array(masses), np.array(positions))
        bodies[name] = body
        new_model = new_model.with_body(name, body)
    largest = max(float(np.max(x)), 1e-300)
    cws = [
        (design[j][0], design[j][1], float(x[j]))
        for j in range(nd)
        if design[j][0] not in redesigned and x[j] > 1e-12 * largest
    ]
    after = analyze_motion(
        new_model,
        motion.t,
        motion.q,
        motion.v,
        motion.a,
        actuated=motion.actuated if model.nloops else None,
        gravity=motion.gravity,
        about=about,
    )
    predicted = {
        what: (a[:, :nd] @ x + b).reshape(len(motion.t), -1) for what, (a, b) in lin.items()
    }
    return Balance(
        masses=x,
        counterweights=cws,
        bodies=bodies,
        model=new_model,
        before=motion,
        after=after,
        predicted=predicted,
        objective=objective,
        zero=tuple(zero),
    )


def pareto_front(
    motion: MotionAnalysis,
    objectives: tuple[str, str] = ("force", "moment"),
    count: int = 11,
    **kwargs,
) -> list[Balance]:
    """Balances trading two objectives: weights ``(1 − s, s)`` for ``s`` from 0 to 1 in
    ``count`` steps (each a :func:`balance` with those weights; other arguments passed on)."""
    if "objective" in kwargs:
        raise InvalidInputError(
            "objective: pareto_front sets the weights itself; give the two objectives as "
            "`objectives` (and equalities as `zero`)"
        )
    first, second = objectives
    out = []
    for s in np.linspace(0.0, 1.0, count):
        w = {first: 1.0 - s, second: s}
        out.append(balance(motion, objective=w, **kwargs))
    return out
