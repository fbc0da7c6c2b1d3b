"""``identify``: inertial parameters (and joint friction, armature, offsets) from measured
motion and joint forces; ``method="cells"`` keeps every body physically consistent by
construction (non-negative masses on cells inside its envelope), ``"ols"`` is plain least
squares for comparison (docs/identification.md)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import _core
from ..errors import InertiaError, InvalidInputError
from ._envelope import box_cells, envelope_boxes
from ._filter import savgol
from ._regressor import (
    BaseParameters,
    actuated_indices,
    base_parameters_from,
    friction_flags,
    one_dof_joints,
)

METHODS = ("cells", "ols")


@dataclass(frozen=True)
class IdentifiedBody:
    """One link's estimate: mass, centre of mass and inertia about it (link frame), the
    smallest eigenvalue of its pseudo-inertia ``[[Σ, h], [hᵀ, m]]`` (``Σ = ½ tr(I) 1 − I``
    about the link origin; ≥ 0 for a body that can exist), and whether its centre of mass
    lies in its envelope (None without one)."""

    name: str
    mass: float
    com: np.ndarray
    inertia: np.ndarray
    parameters: np.ndarray
    pseudo_inertia_min: float
    inside_envelope: bool | None

    @property
    def physical(self) -> bool:
        """Positive mass and a positive semidefinite pseudo-inertia (to rounding)."""
        scale = max(abs(self.mass), float(np.abs(self.parameters[4:]).max()), 1e-300)
        return self.mass > 0 and self.pseudo_inertia_min >= -1e-9 * scale


def pseudo_inertia(parameters) -> np.ndarray:
    """The 4×4 pseudo-inertia of ten parameters (Pinocchio's order)."""
    p = np.asarray(parameters, float)
    m, h = p[0], p[1:4]
    i = np.array([[p[4], p[5], p[7]], [p[5], p[6], p[8]], [p[7], p[8], p[9]]])
    sigma = 0.5 * np.trace(i) * np.eye(3) - i
    out = np.zeros((4, 4))
    out[:3, :3], out[:3, 3], out[3, :3], out[3, 3] = sigma, h, h, m
    return out


def body_of(name: str, parameters, box=None) -> IdentifiedBody:
    """An :class:`IdentifiedBody` from ten parameters."""
    p = np.asarray(parameters, float)
    m = p[0]
    com = p[1:4] / m if m != 0 else np.zeros(3)
    io = np.array([[p[4], p[5], p[7]], [p[5], p[6], p[8]], [p[7], p[8], p[9]]])
    ic = io - m * (com @ com * np.eye(3) - np.outer(com, com))
    inside = None
    if hasattr(box, "contains"):  # a prism or a mesh (identification._shapes)
        inside = bool(box.contains(com[None])[0])
    elif box is not None:
        slack = 1e-9 * float(np.ptp(box, axis=0).max())
        inside = bool(np.all(com >= box[0] - slack) and np.all(com <= box[1] + slack))
    return IdentifiedBody(name, float(m), com, ic, p, float(np.linalg.eigvalsh(pseudo_inertia(p)).min()), inside)


@dataclass
class Identification:
    """What :func:`identify` found. ``parameters``: every regressor column's value
    (``names``; unidentified links keep the prior's); ``base``: the identifiable combinations,
    ``base_values`` and ``base_std`` (σ̂ from the residuals, of the least-squares problem);
    ``condition``: the base regressor's condition number with unit-norm columns;
    ``residuals`` (N, nv) measured minus predicted torques and ``rms`` per joint;
    ``bodies``, ``friction`` (``{joint: {"viscous": fv, "coulomb": fc}}``), ``armature``,
    ``offsets``; ``model``: the model with the identified inertias and armature (None, with
    ``model_error``, when a body is not physical, as least squares can give)."""

    method: str
    names: list[str]
    parameters: np.ndarray
    base: BaseParameters
    base_values: np.ndarray
    base_std: np.ndarray
    condition: float
    residuals: np.ndarray
    rms: np.ndarray
    bodies: dict[str, IdentifiedBody]
    friction: dict[str, dict[str, float]]
    armature: dict[str, float]
    offsets: dict[str, float]
    model: object | None
    model_error: str | None = None
    cells: dict[str, tuple[np.ndarray, np.ndarray, float]] = field(default_factory=dict)
    structural_rank: int = 0
    actuated: tuple[int, ...] = ()

    @property
    def physical(self) -> bool:
        """Every identified body physically consistent."""
        return all(b.physical for b in self.bodies.values())


def _array(value, arg: str, width: int | None) -> np.ndarray:
    try:
        x = np.asarray(value, float)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{arg}: expected an array of numbers, got {type(value).__name__}") from None
    if width is None:
        if x.ndim != 1:
            raise InvalidInputError(f"{arg}: expected a 1-d array of times, got shape {x.shape}")
    elif x.ndim != 2 or x.shape[1] != width:
        raise InvalidInputError(f"{arg}: expected an (N, {width}) array, got shape {x.shape}")
    bad = np.argwhere(~np.isfinite(x))
    if len(bad):
        raise InvalidInputError(f"{arg}: expected finite numbers, got {x[tuple(bad[0])]} at index {tuple(int(i) for i in bad[0])}")
    return x


def measured_states(model, data, window: int | None = None, order: int = 3, width: int | None = None):
    """``(q, v, a, tau)`` from ``data``: ``(q, v, a, tau)`` as given, or ``(t, q, tau)`` with
    ``v`` and ``a`` from a Savitzky–Golay fit (see ``_filter``) and ``tau`` smoothed by the
    same zero-phase filter. A dict with keys ``t, q, tau`` or ``q, v, a, tau`` works too.
    ``tau`` is (N, ``width``): nv by default, the number of actuated joints with them."""
    tw = model.nv if width is None else width
    if isinstance(data, dict):
        keys = ("q", "v", "a", "tau") if "v" in data else ("t", "q", "tau")
        missing = [k for k in keys if k not in data]
        if missing:
            raise InvalidInputError(f"data: expected keys {keys}, got {sorted(data)}")
        data = tuple(data[k] for k in keys)
    if not isinstance(data, (tuple, list)) or len(data) not in (3, 4):
        raise InvalidInputError("data: expected (t, q, tau) or (q, v, a, tau), got " + type(data).__name__)
    if len(data) == 4:
        q = _array(data[0], "q", model.nq)
        v, a = (_array(x, k, model.nv) for x, k in zip(data[1:3], ("v", "a")))
        tau = _array(data[3], "tau", tw)
    else:
        t = _array(data[0], "t", None)
        q = _array(data[1], "q", model.nq)
        tau = _array(data[2], "tau", tw)
        if model.nq != model.nv:
            raise InvalidInputError("data: (t, q, tau) needs nq == nv (no quaternion joints); give (q, v, a, tau)")
        if not (len(t) == len(q) == len(tau)):
            raise InvalidInputError(f"data: expected t, q and tau of the same length, got {len(t)}, {len(q)}, {len(tau)}")
        q, v, a = savgol(t, q, window, order)
        tau = savgol(t, tau, window, order)[0]
    lengths = {"q": len(q), "v": len(v), "a": len(a), "tau": len(tau)}
    if len(set(lengths.values())) != 1:
        raise InvalidInputError(f"data: expected q, v, a and tau of the same length, got {lengths}")
    return q, v, a, tau


def _columns(model, bodies, friction, armature, offset):
    viscous, coulomb = friction_flags(friction)
    names, values = _core.identification_parameters(model, (viscous, coulomb, armature, offset))
    links = list(model.link_names)
    if bodies is None:
        chosen = links
    else:
        chosen = [bodies] if isinstance(bodies, str) else list(bodies)
        unknown = [b for b in chosen if b not in links]
        if unknown:
            raise InvalidInputError(f"bodies: expected names of moving links {links}, got {unknown}")
    free = np.zeros(len(names), bool)
    for k in range(len(links)):
        free[10 * k : 10 * k + 10] = links[k] in chosen
    free[10 * len(links) :] = True
    if armature:
        idx = [i for i, n in enumerate(names) if n.endswith(".armature")]
        values[idx] = np.asarray(model.armature)[one_dof_joints(model)]
    return (viscous, coulomb), names, values, free, chosen


def identify(
    model,
    data,
    method: str = "cells",
    bodies=None,
    friction=None,
    armature: bool = False,
    offset: bool = False,
    prior=None,
    prior_weight: float = 0.0,
    noise=None,
    envelopes=None,
    cells: int = 200,
    gravity=None,
    window: int | None = None,
    rank_tol: float = 1e-8,
    actuated=None,
) -> Identification:
    """Identifies the inertial parameters of ``bodies`` (link names; all by default) and,
    when asked, ``friction`` (True, "viscous", "coulomb") per 1-dof joint, ``armature`` and
    torque ``offset`` from ``data`` (see :func:`measured_states`). ``method``: "cells"
    (about ``cells`` non-negative cell masses per link inside ``envelopes[link]``, a (2, 3)
    box, else the bounds of its visual geometry) or "ols". ``prior``: a Model or a full
    parameter vector (default: ``model``'s own values) for the links not identified and, with
    ``prior_weight`` > 0, as a pull (cells). ``noise``: each joint's torque noise σ (one
    number or nv), weighting the rows by 1/σ. A motion that cannot identify all the model's
    base parameters raises, naming the ones it misses. ``actuated`` (v indices or link names;
    required with loops): ``tau`` holds those joints' driving forces alone, (N, na), and
    ``noise`` is one σ per actuated joint."""
    if method not in METHODS:
        raise InvalidInputError(f"method: expected one of {METHODS}, got {method!r}")
    act = actuated_indices(model, actuated)
    rows = len(act) if act else model.nv
    q, v, a, tau = measured_states(model, data, window, width=rows)
    flags, names, values, free, chosen = _columns(model, bodies, friction, armature, offset)
    if prior is not None:
        values = _prior(prior, names, flags, armature, offset)
    weights = _weights(noise, rows)
    links = list(model.link_names)
    boxes, cell_args, cell_grids = {}, [], {}
    if method == "cells":
        boxes = envelope_boxes(model, chosen, envelopes)
        for name in chosen:
            env = boxes[name]
            centres, side = env.cells(int(cells)) if hasattr(env, "cells") else box_cells(env, int(cells))
            cell_grids[name] = (centres, side)
            cell_args.append((links.index(name), centres, side))
    elif envelopes is not None:
        boxes = envelope_boxes(model, chosen, envelopes)
    out = _core.identification_fit(
        model, q, v, a, tau.reshape(-1), gravity=gravity, method=method, free=list(map(bool, free)),
        prior=list(map(float, values)), prior_weight=float(prior_weight), weights=list(weights),
        cells=cell_args, viscous=bool(flags[0]), coulomb=bool(flags[1]), armature=bool(armature),
        offset=bool(offset), rank_tol=float(rank_tol), actuated=act,
    )
    free_names = [names[i] for i in out.free]
    base = base_parameters_from(out.base, free_names, len(free_names))
    pi = out.pi
    residuals = out.residuals.reshape(-1, rows)
    bodies_out = {n: body_of(n, pi[10 * links.index(n) : 10 * links.index(n) + 10], boxes.get(n)) for n in chosen}
    joints = [links[_link_of(model, j)] for j in one_dof_joints(model)]
    extra = {k: {} for k in ("fv", "fc", "armature", "offset")}
    for n, x in zip(names, pi):
        owner, _, kind = n.rpartition(".")
        if kind in extra and owner in joints and n.count(".") >= 1 and not _is_link_param(kind):
            extra[kind][owner] = float(x)
    friction_out = {j: {"viscous": extra["fv"].get(j, 0.0), "coulomb": extra["fc"].get(j, 0.0)} for j in joints} if any(flags) else {}
    ident_model, err = _identified_model(model, pi, [links.index(n) for n in chosen], extra["armature"], joints, armature)
    masses = {n: (cell_grids[n][0], np.asarray(m), cell_grids[n][1]) for n, m in zip(chosen, out.masses)}
    return Identification(
        method, names, pi, base, out.beta, out.std, float(out.condition),
        residuals, np.sqrt(np.mean(residuals**2, axis=0)), bodies_out, friction_out, extra["armature"],
        extra["offset"], ident_model, err, masses, int(out.structural_rank), tuple(act),
    )


def _is_link_param(kind: str) -> bool:
    return kind in ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")


def _link_of(model, v_index: int) -> int:
    for k, (_, vi, _, _) in enumerate(model.joint_slices()):
        if vi == v_index:
            return k
    raise InvalidInputError(f"joint: no link with v index {v_index}")


def _identified_model(model, pi, links, arm: dict, joints, armature: bool):
    values = [arm.get(j, 0.0) for j in joints] if armature else None
    try:
        return _core.identification_model(model, list(map(float, pi)), links, values), None
    except InertiaError as exc:
        return None, str(exc)


def _prior(prior, names, flags, armature, offset) -> np.ndarray:
    if hasattr(prior, "link_names"):
        pn, pv = _core.identification_parameters(prior, (flags[0], flags[1], armature, offset))
        if pn != names:
            raise InvalidInputError("prior: expected a model with the same links and joints as model")
        return np.asarray(pv, float)
    x = np.asarray(prior, float)
    if x.shape != (len(names),) or not np.all(np.isfinite(x)):
        raise InvalidInputError(f"prior: expected a Model or {len(names)} finite numbers (one per column), got shape {x.shape}")
    return x


def _weights(noise, nv: int) -> np.ndarray:
    if noise is None:
        return np.zeros(0)
    s = np.broadcast_to(np.asarray(noise, float), (nv,)) if np.ndim(noise) == 0 else np.asarray(noise, float)
    if s.shape != (nv,) or not np.all(np.isfinite(s)) or not np.all(s > 0):
        raise InvalidInputError(f"noise: expected one positive σ or {nv} (one per joint), got {np.asarray(noise).tolist()}")
    return 1.0 / s
