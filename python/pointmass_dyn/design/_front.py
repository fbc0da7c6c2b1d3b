"""Pareto fronts of two design objectives (docs/design.md §5).

Each point is one :func:`~pointmass_dyn.balance` with both objectives weighted strictly
positively (a zero weight gives only a weakly optimal point: a tie in the first objective
is broken by design mass, not by the second objective), and the front keeps only the points
no other point beats: figures recomputed from each design's analysis along the motion,
repeats and dominated points dropped and counted."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..errors import InvalidInputError
from ._balance import Balance
from ._problem import MAX_PARETO_POINTS, balance, objective_value
from ._shaking import MotionAnalysis

#: Weight of the other objective (both relative to their values before the design) that
#: makes an end or an ε-constrained point properly Pareto-optimal instead of only weakly. It
#: can raise the first objective (relative) by at most this times the second's (relative)
#: value there, their squares in an RMS program (which weights mean squares): 6e-5 of the
#: unbalanced RMS force at the four-bar's force-balanced end (tests/test_balancing.py).
TIE_WEIGHT = 1e-5
#: Two figures closer than this fraction of the objective's scale (its value before the
#: design, or the largest on the front) count as equal: the solver's and the re-analysis'
#: accuracy is far finer (gap 1e-10, round-off), a real trade-off far coarser.
FRONT_TOL = 1e-6


class ParetoFront(list):
    """The designs of a front (a list of :class:`Balance`, in the order solved) with
    ``objectives`` (the two names), ``values`` (P, 2): each design's two figures in the
    problem's norm recomputed from its analysis along the motion (also in each point's
    ``solver["analysed"]``), and ``dropped``: the designs solved but left out, each repeated
    or dominated by a kept one (within ``FRONT_TOL`` of the objective's scale)."""

    objectives: tuple[str, str]
    values: np.ndarray
    dropped: list


def analysed_value(b: Balance, name: str) -> float:
    """Objective ``name`` of design ``b`` in its problem's norm, from ``b.after`` (the
    designed model analysed along the motion), not from the solver: what a front compares."""
    if name == "mass":
        return float(np.sum(b.masses))
    a, norm = b.after, b.solver["norm"]
    if name in ("force", "moment"):
        y = getattr(a.shaking, name)
    elif name == "torque":
        cols = b.before.actuated if b.before.actuated is not None else range(a.tau.shape[1])
        y = a.tau[:, list(cols)]
    elif name == "bearing" or name.startswith("bearing:"):
        y = np.concatenate([a.bearing[:, :, :3], a.cut[:, :, :3]], axis=1)
        if name != "bearing":
            joints = list(a.model.link_names) + list(a.model.loop_names)
            joint = name.split(":", 1)[1]
            if joint not in joints:
                raise InvalidInputError(f"name: '{name}' names no joint (joints: {joints})")
            y = y[:, joints.index(joint)]
    else:
        raise InvalidInputError(f"name: expected an objective of the front, got {name!r}")
    y = np.asarray(y, float).reshape(len(a.t), -1, np.shape(y)[-1])
    blocks = np.sum(y**2, axis=2)
    if norm == "rms":
        return float(np.sqrt(blocks.sum() / len(a.t)))
    return float(np.sqrt(blocks.max(initial=0.0)))


def dominated(values: np.ndarray, tol: np.ndarray) -> np.ndarray:
    """(P,) bool: point ``i`` is dominated — another point is no worse in both objectives
    (beyond ``tol``) and better in one (by more than ``tol``) — or repeats (both figures
    within ``tol``) a point not dominated that is lower in the sum of its figures over
    ``tol`` (the earlier one on a tie)."""
    v = np.asarray(values, float)
    no_worse = np.all(v[:, None, :] <= v[None, :, :] + tol, axis=2)  # [j, i]: j no worse than i
    better = np.any(v[:, None, :] < v[None, :, :] - tol, axis=2)
    out = np.any(no_worse & better, axis=0)
    key = np.sum(v / tol, axis=1)
    first = out.copy()
    for i in range(len(v)):
        same = np.all(np.abs(v - v[i]) <= tol, axis=1) & ~first
        ahead = (key < key[i]) | ((key == key[i]) & (np.arange(len(v)) < i))
        out[i] |= bool(np.any(same & ahead))
    return out


def _scale(points: list[Balance], name: str, values: np.ndarray) -> float:
    before = points[0].solver.get("before", {}).get(name)
    if name == "mass":
        before = float(points[0].before.model.total_mass)
    return max(float(before or 0.0), float(np.max(np.abs(values))), 1e-300)


def _front(points: list[Balance], first: str, second: str, say) -> ParetoFront:
    values = np.array([[analysed_value(b, first), analysed_value(b, second)] for b in points])
    for b, (v1, v2) in zip(points, values):
        b.solver["analysed"] = {first: float(v1), second: float(v2)}
    tol = FRONT_TOL * np.array([_scale(points, n, values[:, k]) for k, n in enumerate((first, second))])
    drop = dominated(values, tol)
    front = ParetoFront(b for b, d in zip(points, drop) if not d)
    front.objectives = (first, second)
    front.values = values[~drop]
    front.dropped = [b for b, d in zip(points, drop) if d]
    say(f"front: {len(front)} points kept, {len(front.dropped)} repeated or dominated dropped")
    return front


def pareto_front(
    motion: MotionAnalysis,
    objectives: tuple[str, str] = ("force", "moment"),
    count: int = 11,
    progress: Callable[[str], Any] | None = None,
    method: str = "weighted",
    **kwargs,
) -> ParetoFront:
    """Designs trading two objectives: at most ``count``, none beaten in both by another.

    ``method="weighted"``: weights ``(1 − s, s)`` for ``s`` from 0 to 1 in ``count`` steps
    (each a :func:`balance` with those weights; a zero weight raised to ``TIE_WEIGHT``).
    ``method="epsilon"``: the ε-constraint method — the two objectives' own optima as the
    ends, and ``count − 2`` levels ε of the second evenly between its values there, each
    design minimising the first objective with the second limited to ε (``limits``, in the
    chosen ``norm``; for ``"mass"``, kg of design material), the second weighted
    ``TIE_WEIGHT`` to break ties; it also reaches the non-convex-looking parts of a front
    that weights skip. Each point's two figures are then recomputed from its analysis along
    the motion (``solver["analysed"]``) and the points repeated or dominated on them are
    dropped (:class:`ParetoFront`: ``.values``, ``.dropped``); each point keeps its solve's
    certificate (``solver["status"]``, ``solver["gap_rel"]``). Other arguments are passed
    on to :func:`balance`. Interrupted (Ctrl-C) or failing at a point, the exception carries
    the points already solved as ``.result`` (a list, in order, not filtered)."""
    if "objective" in kwargs:
        raise InvalidInputError(
            "objective: pareto_front sets the weights itself; give the two objectives as "
            "`objectives` (and equalities as `zero`)"
        )
    if (isinstance(count, bool) or not isinstance(count, (int, np.integer))
            or not 2 <= count <= MAX_PARETO_POINTS):
        raise InvalidInputError(
            f"count: expected an integer in [2, {MAX_PARETO_POINTS}] (one program each), got {count!r}"
        )
    if (
        not isinstance(objectives, (tuple, list))
        or len(objectives) != 2
        or objectives[0] == objectives[1]
    ):
        raise InvalidInputError(f"objectives: expected two different objectives, got {objectives!r}")
    if method not in ("weighted", "epsilon"):
        raise InvalidInputError(f"method: expected 'weighted' or 'epsilon', got {method!r}")
    if progress is not None and not callable(progress):
        raise TypeError(f"progress: expected None or a callable taking a str, got {type(progress).__name__}")
    first, second = objectives
    say = progress or (lambda _s: None)
    if method == "epsilon":
        return _front(_epsilon_points(motion, first, second, int(count), say, kwargs), first, second, say)
    out: list[Balance] = []
    try:
        for k, s in enumerate(np.linspace(0.0, 1.0, int(count))):
            say(f"Pareto point {k + 1}/{count}")
            weights = {first: max(1.0 - s, TIE_WEIGHT), second: max(s, TIE_WEIGHT)}
            out.append(balance(motion, objective=weights, **kwargs))
    except BaseException as exc:
        # An interrupt or a failing point keeps the points already solved (in order).
        exc.result = out
        raise
    return _front(out, first, second, say)


def _epsilon_points(motion, first, second, count, say, kwargs) -> list[Balance]:
    limits = dict(kwargs.pop("limits", None) or {})
    if second in limits:
        raise InvalidInputError(f"limits: the ε-constraint front sets the limit of '{second}' itself")
    # The ends: each objective's own optimum (the payoff table), the other weighted
    # TIE_WEIGHT; the levels ε of the second lie evenly between its values there. (Holding
    # the first at its optimum to refine an end is a thin, ill-conditioned cone when that
    # optimum is zero, as in force balance: Clarabel stops for lack of progress.)
    first_w = {first: 1.0, second: TIE_WEIGHT}
    out: list[Balance] = []
    try:
        say(f"Pareto point 1/{count}")
        out.append(balance(motion, objective=first_w, limits=limits or None, **kwargs))
        say(f"Pareto point {count}/{count}")
        end = balance(motion, objective={second: 1.0, first: TIE_WEIGHT}, limits=limits or None, **kwargs)
        hi, lo = objective_value(out[0], second), objective_value(end, second)
        for k, eps in enumerate(np.linspace(hi, lo, count)[1:-1]):
            say(f"Pareto point {k + 2}/{count}")
            out.append(balance(motion, objective=first_w, limits={**limits, second: float(eps)}, **kwargs))
    except BaseException as exc:
        # The points already solved, in order along the front (the far end, if solved, is
        # left out: it is not adjacent to them).
        exc.result = out
        raise
    out.append(end)
    return out
