"""Balancing with point masses (docs/balancing.md).

For a prescribed motion the point masses' positions and accelerations are fixed, so the
shaking force, the shaking moment and the driving torque are **linear in the masses** placed
at given body points: a link's own seven point masses, or counterweights at candidate points.
Balancing is then a least-squares problem with linear equalities (e.g. zero shaking force) and
bounds (a counterweight's mass is not negative), solved exactly (``_qp``), not by a search.

* :func:`balance` — counterweights and/or redesigned links that minimise weighted RMS
  shaking force, moment and driving torque, subject to chosen ones being zero
  (:class:`Balance`); :func:`pareto_front` between two objectives.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import _core
from .._helpers import rms
from ..errors import InvalidInputError, NumericalError
from ._qp import row_space, solve_qp
from ._shaking import MotionAnalysis, analyze_motion

OBJECTIVES = ("force", "moment", "torque")


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


def _least_mass(model, x, h, c, ce, de, lb, ub, weighted, nd: int, regularization: float):
    """Step 2 of :func:`balance`: among the optima of the weighted objective ``x`` (all share
    the objective's values A x), the one of least added mass; the design masses (nd,)."""
    p = len(x)
    # An L1 term (masses ≥ 0) well above an L2 one that keeps the subproblems strictly convex.
    # The optimal values A x are unique; where the bounds do not decide them they are those
    # of the equality-constrained least squares, exactly (the interior point gives them to
    # ~1e-10 only): try those first.
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
                ce2, de2 = row_space(
                    np.vstack([ce, w]), np.concatenate([de, target]), what="objective"
                )
                x2 = solve_qp(h2, l1, ce2, de2, lb, ub, x)
            except (InvalidInputError, NumericalError):
                continue
            if np.abs(ce2 @ x2 - de2).max() <= 1e-9 * (1.0 + np.abs(de2).max()):
                x = x2
                break
        return x[:nd]
    return solve_qp(h2, l1, ce, de, lb, ub, x)[:nd]


def _rebuild(model, design, x, links):
    """The bodies the design masses ``x`` change, rebuilt from their point masses (a
    counterweight's added to the body's own seven), the model with them, and the
    counterweights placed: ``(bodies, model, [(body, position, mass)])``."""
    nd = len(design)
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
    return bodies, new_model, cws


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
            scale = max(rms(y0.reshape(len(motion.t), -1)), 1e-300) ** 2 * len(motion.t)
            h += (w / scale) * (a.T @ a)
            c += (w / scale) * (a.T @ b)
            weighted.append(np.sqrt(w / scale) * a)
    ce, de = row_space(
        np.vstack(ce_rows) if ce_rows else np.zeros((0, p)),
        np.concatenate(de_rows),
        what=", ".join(zero) or "the link masses",
    )
    # A feasible start: the bounded point nearest the equalities (phase 1), checked.
    x_start = np.clip(x_now, lb, ub)
    if ce.shape[0]:
        x_start = solve_qp(ce.T @ ce, -ce.T @ de, np.zeros((0, p)), np.zeros(0), lb, ub, x_start)
        miss = np.abs(ce @ x_start - de).max()
        if miss > 1e-9 * (1.0 + np.abs(de).max()):
            raise InvalidInputError(
                f"zero: the design point masses cannot make {', '.join(zero)} vanish at every "
                f"instant within their bounds (best residual {miss:.3e}); add counterweight "
                f"candidates on other links, or relax the bounds"
            )
    # 1. The weighted objective (strictly convex in the objective's values A x).
    base = np.trace(h) / p if np.trace(h) > 0 else 1.0
    x = solve_qp(h + 1e-14 * base * np.eye(p), c, ce, de, lb, ub, x_start)
    # 2. Among its optima, the least added mass; then the balanced model, analysed again.
    x = _least_mass(model, x, h, c, ce, de, lb, ub, weighted, nd, regularization)
    bodies, new_model, cws = _rebuild(model, design, x, links)
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
