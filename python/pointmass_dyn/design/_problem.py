"""Design of bodies and counterweights along a prescribed motion (docs/design.md).

Every objective a designer trades — shaking force, shaking moment, driving force(s), the
bearing force of every joint (cut joints included), the mass added — is linear in the masses
of material cells (:class:`~pointmass_dyn.LinkShape`) and counterweight candidates
(:class:`~pointmass_dyn.Counterweight`) for a given motion, through the ten inertial
parameters of each link (the core's ``design_regressor``). RMS objectives make a quadratic
program, peak (minimax over the motion) ones a second-order cone program; ``limits`` are
constraints in the same norm. The core solves it with Clarabel and reports its status and
duality gap; the designed model is then analysed again along the same motion."""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from .. import _core
from ..errors import InvalidInputError
from . import _connect, _safety
from ._balance import Balance, Counterweight, SolverStage
from ._realise import realise
from ._shaking import MotionAnalysis, analyze_motion
from ._shapes import LinkShape, Shape

QUANTITIES = ("force", "moment", "torque", "bearing")
OBJECTIVES = (*QUANTITIES, "mass")
NPARAM = 10
MAX_PARETO_POINTS = 10_000  # each point is one (or two) conic programs: more is a typo


def _check_progress(progress: Any) -> None:
    if progress is not None and not callable(progress):
        raise TypeError(f"progress: expected None or a callable taking a str, got {type(progress).__name__}")


def _moments(points: np.ndarray, side: float = 0.0) -> np.ndarray:
    """(K, 10): mass, first and second moments of unit masses at ``points`` (cubes of side
    ``side``), the order of the core's regressor columns."""
    p = np.atleast_2d(points)
    own = side * side / 12.0
    return np.column_stack(
        [
            np.ones(len(p)),
            p,
            p[:, 0] ** 2 + own,
            p[:, 1] ** 2 + own,
            p[:, 2] ** 2 + own,
            p[:, 0] * p[:, 1],
            p[:, 0] * p[:, 2],
            p[:, 1] * p[:, 2],
        ]
    )


def _body_from_parameters(phi: np.ndarray) -> Any:
    """The rigid body with parameters ``phi`` (10,): mass, COM and inertia about the COM."""
    m, h = phi[0], phi[1:4]
    s = np.array(
        [[phi[4], phi[7], phi[8]], [phi[7], phi[5], phi[9]], [phi[8], phi[9], phi[6]]]
    )
    c = h / m
    inertia_o = np.trace(s) * np.eye(3) - s
    inertia = inertia_o - m * (c @ c * np.eye(3) - np.outer(c, c))
    return _core.RigidBody(float(m), c, 0.5 * (inertia + inertia.T))


def _link_of(model, body: Any, arg: str) -> tuple[str, int]:
    """(name, link index) of a body that defines a moving link."""
    names = model.body_names
    if isinstance(body, str):
        if body not in names:
            raise InvalidInputError(f"{arg}: expected a body name, got '{body}' (bodies: {names})")
        name = body
    elif isinstance(body, (int, np.integer)) and 0 <= int(body) < len(names):
        name = names[int(body)]
    else:
        raise InvalidInputError(
            f"{arg}: expected a body name or an index 0..{len(names) - 1}, got {body!r}"
        )
    if name not in model.link_names:
        raise InvalidInputError(
            f"{arg}: expected a body on a moving joint of its own, got '{name}' (welded or fixed)"
        )
    return name, model.link_names.index(name)


def _mass_range(mass: Any) -> tuple[float, float]:
    """A ``LinkShape``'s ``mass=(low, high)`` as two floats, or an error naming it."""
    try:
        lo_m, hi_m = (float(v) for v in mass)
    except (TypeError, ValueError):
        raise InvalidInputError(f"mass: expected None or (low, high) in kg, got {mass!r}") from None
    return lo_m, hi_m


class _Variables:
    """The design masses: bounds, their map to the designed links' parameters, groups."""

    def __init__(self, model):
        self.model = model
        self.lower: list[np.ndarray] = []
        self.upper: list[np.ndarray] = []
        self.columns: list[tuple[int, np.ndarray]] = []  # (link, (K, 10) moments)
        self.groups: list[tuple[list[int], float, float]] = []
        self.equal: list[tuple[int, int]] = []
        self.replaced: set[int] = set()  # links whose current material the design replaces
        self.parts: list[tuple[str, str, Any, slice]] = []  # (kind, body, spec, slice of x)
        self.count = 0

    def add(self, kind, name, link, spec, moments, lower, upper):
        k = len(lower)
        sl = slice(self.count, self.count + k)
        self.lower.append(np.asarray(lower, float))
        self.upper.append(np.asarray(upper, float))
        self.columns.append((link, moments))
        self.parts.append((kind, name, spec, sl))
        self.count += k
        return sl


def _link_mass_arg(link_mass) -> tuple[float, float]:
    """``(low, high)``, factors ``0 < low <= high`` (``high`` may be inf), checked whether or not a link
    uses them (a wrong value is a mistake either way)."""
    try:
        lo, hi = (float(f) for f in link_mass)
    except (TypeError, ValueError):
        lo = hi = float("nan")
    if not (np.isfinite(lo) and not np.isnan(hi) and 0.0 < lo <= hi):
        raise InvalidInputError(
            f"link_mass: expected factors (low, high), 0 < low <= high, low finite (high may "
            f"be inf), got {link_mass!r}"
        )
    return lo, hi


def _collect(model, links, counterweights, link_mass) -> _Variables:
    var = _Variables(model)
    for item in links:
        if isinstance(item, LinkShape):
            name, link = _link_of(model, item.body, "links")
            if link in var.replaced:
                raise InvalidInputError(f"links: '{name}' given twice")
            centers, lo, cap = item.cells(model)
            sl = var.add("shape", name, link, item, _moments(centers, item.cell), lo, cap)
            var.replaced.add(link)
            if item.mass is not None:
                lo_m, hi_m = _mass_range(item.mass)
                if not 0.0 <= lo_m <= hi_m:
                    raise InvalidInputError(f"mass: expected 0 <= low <= high kg, got {item.mass}")
                if hi_m < lo.sum() or lo_m > cap.sum():
                    raise InvalidInputError(
                        f"mass: '{name}' must weigh {lo.sum():.4g} kg at least (its pins) and at "
                        f"most {cap.sum():.4g} kg (a full envelope), got the range {item.mass}"
                    )
                var.groups.append((list(range(sl.start, sl.stop)), lo_m, hi_m))
            var.equal += [(sl.start + i, sl.start + j) for i, j in item.mirror_pairs(centers)]
        else:
            name, link = _link_of(model, item, "links")
            if link in var.replaced:
                raise InvalidInputError(f"links: '{name}' given twice")
            pm = model.body(name).point_masses()
            pos = np.asarray(pm.positions, float)
            sl = var.add("points", name, link, None, _moments(pos), np.zeros(7), np.full(7, np.inf))
            var.replaced.add(link)
            lo, hi = link_mass
            m0 = model.body(name).mass
            var.groups.append((list(range(sl.start, sl.stop)), lo * m0, hi * m0))
    for k, cw in enumerate(counterweights):
        if not isinstance(cw, Counterweight):
            raise InvalidInputError(
                f"counterweights[{k}]: expected a Counterweight, got {type(cw).__name__}"
            )
        name, link = _link_of(model, cw.body, f"counterweights[{k}]")
        try:
            pts = np.asarray(cw.points, dtype=float)
        except (TypeError, ValueError):
            raise InvalidInputError(
                f"counterweights[{k}]: points of '{name}' must be a finite (K, 3) array of numbers, "
                f"got {cw.points!r}"
            ) from None
        if pts.ndim == 1:
            pts = pts.reshape(1, -1)
        # Beyond 1e100 m the second moments overflow; no mechanism has such a point.
        if (pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0 or not np.all(np.isfinite(pts))
                or np.abs(pts).max() > 1e100):
            raise InvalidInputError(
                f"counterweights[{k}]: points of '{name}' must be a finite (K, 3) array within "
                f"1e100 m of the body origin, got shape {pts.shape}"
                + (f" reaching {np.abs(pts).max():.3g}" if pts.size and np.all(np.isfinite(pts)) else "")
            )
        hi = np.inf if cw.max_mass is None else float(cw.max_mass)
        if not hi > 0:
            raise InvalidInputError(
                f"counterweights[{k}]: max_mass must be positive (or None), got {cw.max_mass!r}"
            )
        var.add("counterweight", name, link, cw, _moments(pts), np.zeros(len(pts)), np.full(len(pts), hi))
    if var.count == 0:
        raise InvalidInputError("counterweights, links: give at least one design point mass or link shape")
    return var


def _quantity_rows(reg: dict, what: str, model) -> tuple[np.ndarray, int]:
    """Row indices (per sample) and the block size of a quantity."""
    rows, na, nl = reg["rows"], reg["nactuated"], reg["nlinks"]
    if what == "force":
        return np.arange(0, 3), 3
    if what == "moment":
        return np.arange(3, 6), 3
    if what == "torque":
        return np.arange(6, 6 + na), na
    if what == "bearing":
        return np.arange(6 + na, rows), 3
    if what.startswith("bearing:"):
        joint = what.split(":", 1)[1]
        if joint in model.link_names:
            s = 6 + na + 3 * model.link_names.index(joint)
        elif joint in model.loop_names:
            s = 6 + na + 3 * (nl + model.loop_names.index(joint))
        else:
            raise InvalidInputError(
                f"objective: '{what}' names no joint (links: {model.link_names}, cut joints: "
                f"{model.loop_names})"
            )
        return np.arange(s, s + 3), 3
    raise InvalidInputError(f"objective: expected keys among {OBJECTIVES} or 'bearing:<joint>', got '{what}'")


def _norm_value(y: np.ndarray, dim: int, samples: int, norm: str) -> float:
    blocks = np.sum(y.reshape(-1, dim) ** 2, axis=1)
    if norm == "rms":
        return float(np.sqrt(blocks.sum() / samples))
    return float(np.sqrt(blocks.max(initial=0.0)))


def _number(value: Any, arg: str, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise InvalidInputError(f"{arg}: expected a number, got {value!r}")
    v = float(value)
    if not np.isfinite(v) or v < 0 or (positive and v == 0):
        raise InvalidInputError(f"{arg}: expected a finite number {'> 0' if positive else '>= 0'}, got {value!r}")
    return v


def _design_arguments(objective, limits, zero, norm, least_mass, link_mass):
    """``balance``'s settings checked: ``(objective, limits, zero, names, safety,
    link_mass)``, ``names`` every quantity they mention, ``safety`` the members' limit."""
    for arg, value in (("objective", objective), ("limits", limits)):
        if value is not None and not isinstance(value, dict):  # dict("0.3") is a ValueError
            raise InvalidInputError(f"{arg}: expected None or a dict by quantity, got {value!r}")
    objective = {"force": 1.0} if objective is None else dict(objective)
    limits = dict(limits or {})
    for k, w in objective.items():
        _number(w, f"objective['{k}']")
    for k, v in limits.items():
        _number(v, f"limits['{k}']")
    safety = _safety.safety_limit(limits)  # bounds the members' stress (design/_safety.py)
    if not any(float(w) > 0 for w in objective.values()) and not limits and not zero:
        raise InvalidInputError(
            f"objective: expected some weight > 0 (or limits= / zero=), got {objective}"
        )
    if norm not in ("rms", "peak"):
        raise InvalidInputError(f"norm: expected 'rms' or 'peak', got {norm!r}")
    zero = tuple([zero] if isinstance(zero, str) else zero)
    names = set(objective) | set(limits) | set(zero)
    if zero and "mass" in zero:
        raise InvalidInputError("zero: the design mass cannot be zero; give a limit instead")
    if not isinstance(least_mass, (bool, np.bool_)):
        raise InvalidInputError(f"least_mass: expected True or False, got {least_mass!r}")
    link_mass = _link_mass_arg(link_mass)
    return objective, limits, zero, names, safety, link_mass


def _design_map(var: _Variables, designed: list[int]) -> dict:
    """``δ = M x``: the designed links' parameters from the design masses, as the sparse
    ``map_rows``, ``map_cols``, ``map_vals`` of the program."""
    pos = {link: k for k, link in enumerate(designed)}
    mr, mc, mv = [], [], []
    for (link, mom), (_, _, _, sl) in zip(var.columns, var.parts):
        j = np.arange(sl.start, sl.stop)
        for c in range(NPARAM):
            mr.append(np.full(len(j), NPARAM * pos[link] + c))
            mc.append(j)
            mv.append(mom[:, c])
    return {"map_rows": [int(v) for v in np.concatenate(mr)],
            "map_cols": [int(v) for v in np.concatenate(mc)],
            "map_vals": np.concatenate(mv)}


def _quantities(model, reg, data, names, objective, limits, zero, norm, phi_now, phi_base,
                cols) -> tuple[list[dict], dict]:
    """The program's quantities (their rows on the design, the rest constant) and each one's
    value before, in ``norm``."""
    n = data.shape[0]
    quantities, before = [], {}
    for what in sorted(names - {"mass"}):
        idx, dim = _quantity_rows(reg, what, model)
        block = data[:, idx, :].reshape(n * len(idx), -1)
        y_now = block @ phi_now
        ref = _norm_value(y_now, dim, n, norm)
        w = float(objective.get(what, 0.0))
        if (w > 0 or what in zero) and ref == 0.0:
            raise InvalidInputError(
                f"objective: the {what} is zero along this motion before any design; nothing to "
                f"reduce (check the motion's speed and the model's masses)"
            )
        before[what] = ref
        quantities.append(
            {
                "name": what,
                "rows": np.ascontiguousarray(block[:, cols]),
                "constant": block @ phi_base,
                "dim": dim,
                "samples": n,
                "weight": w,
                "reference": ref if ref > 0 else 1.0,
                "limit": limits.get(what),
                "zero": what in zero,
            }
        )
    return quantities, before


def _solver_report(sol: dict, quantities: list[dict], before: dict, norm: str, t0: float) -> dict:
    """``Balance.solver``: the certificate of every stage, the counts and times, the values
    the program predicts and those before."""
    return {
        "status": sol["status"],
        "gap_abs": float(sol["gap_abs"]),
        "gap_rel": float(sol["gap_rel"]),
        # Every stage's certificate: the optimum, then (least_mass) the least mass.
        "stages": [
            SolverStage(stage, st, float(ga), float(gr), float(obj))
            for stage, (st, ga, gr, obj) in zip(("optimum", "least mass"), sol["stages"])
        ],
        "iterations": int(sol["iterations"]),
        "rounds": int(sol["rounds"]),
        # What did not go as asked without failing the design (a least-mass stage that did
        # not converge): also a RuntimeWarning.
        "notes": list(sol["notes"]),
        "solve_time": float(sol["solve_time"]),
        "values": dict(zip([q["name"] for q in quantities], sol["values"].tolist())),
        "before": before,
        "norm": norm,
        "time": time.perf_counter() - t0,
    }


def balance(
    motion: MotionAnalysis,
    *,
    counterweights: Sequence[Counterweight] = (),
    links: Sequence[Any] = (),
    objective: dict[str, float] | None = None,
    norm: str = "rms",
    limits: dict[str, float] | None = None,
    zero: Sequence[str] = (),
    link_mass: tuple[float, float] = (1.0, 1.0),
    least_mass: bool = True,
    progress: Callable[[str], Any] | None = None,
) -> Balance:
    """Design counterweights and link shapes along a prescribed ``motion``.

    Design variables: ``counterweights`` (candidate point masses, each in ``[0, max_mass]``)
    and ``links``: :class:`LinkShape` (the link's material as cells) or a body name (its own
    seven point masses redistributed, their total within ``link_mass`` × its mass).
    ``objective`` weights ``"force"``, ``"moment"`` (about the motion's ``about``),
    ``"torque"`` (driving forces), ``"bearing"`` (every joint's bearing force, cut joints
    included; ``"bearing:<joint>"`` one joint) — each relative to its value before — and
    ``"mass"`` (the design's mass relative to the model's); default ``{"force": 1}``.
    ``norm``: ``"rms"`` over the motion (a QP) or ``"peak"`` (the largest magnitude: an
    SOCP). ``limits``: upper bounds in absolute units in the same norm (``"mass"``: kg of
    design material). ``zero``: quantities that must vanish at every instant. Among equal
    optima the least design mass is taken (``least_mass``). ``progress`` is called with a
    short text at each stage."""
    t0 = time.perf_counter()
    _check_progress(progress)
    say = progress or (lambda _s: None)
    model = motion.model
    objective, limits, zero, names, safety, link_mass = _design_arguments(
        objective, limits, zero, norm, least_mass, link_mass)
    var = _collect(model, list(links), list(counterweights), link_mass)
    actuated = motion.actuated if motion.actuated is not None else list(range(model.nv))
    say("maps along the motion")
    reg = _core.design_regressor(
        model, motion.q, motion.v, motion.a, motion.gravity, motion.shaking.about, actuated
    )
    n = len(motion.t)
    rows = reg["rows"]
    data = reg["data"].reshape(n, rows, -1)
    phi_now = reg["parameters"]
    designed = sorted({link for link, _ in var.columns})
    cols = np.concatenate([np.arange(NPARAM * i, NPARAM * (i + 1)) for i in designed])
    phi_base = phi_now.copy()
    for link in var.replaced:
        phi_base[NPARAM * link : NPARAM * (link + 1)] = 0.0
    quantities, before = _quantities(model, reg, data, names, objective, limits, zero, norm,
                                     phi_now, phi_base, cols)
    checked = _safety.checked_links(model, var.parts, safety)
    quantities += _safety.quantities(checked, motion, data, actuated, cols, phi_base,
                                     phi_now, safety)
    lower = np.concatenate(var.lower)
    upper = np.concatenate(var.upper)
    spec = {
        "ndelta": len(cols),
        "lower": lower,
        "upper": upper,
        **_design_map(var, designed),
        "groups": var.groups,
        "equal": var.equal,
        "quantities": quantities,
        "norm": norm,
        "mass_weight": float(objective.get("mass", 0.0)),
        "mass_reference": float(model.total_mass),
        "mass_limit": limits.get("mass"),
        "least_mass": bool(least_mass),
        # Connected links: flows through their cells' faces (docs/design.md §3).
        "flows": [_connect.flow(sp, model, sp.cells(model)[0], sl.start)
                  for kind, _, sp, sl in var.parts if kind == "shape" and _connect.connected(sp)],
    }
    say(f"conic program: {var.count} design masses, {len(quantities)} quantities ({norm})")
    sol = _core.design_solve(spec)
    if sol["status"] == "Infeasible":
        items = sol["relaxation"]
        relaxation = {name: (asked, needed) for name, _z, asked, needed, *_ in items}
        binding = tuple(name for name, _z, _a, _n, _b, on, _alone in items if on)
        alone = {name: value for name, *_, value in items}
        _safety.raise_infeasible(sol["message"], relaxation, binding, alone, checked, safety)
    for note in sol["notes"]:
        warnings.warn(f"balance: {note}", RuntimeWarning, stacklevel=2)
    x = np.clip(sol["x"], lower, upper)
    say(f"solved: {sol['status']}, {sol['iterations']} iterations, gap {sol['gap_rel']:.1e}")
    # The parameters of the masses found (the solver's δ = M x holds to its tolerance only):
    # the bodies, the prediction and the re-analysis all follow from x.
    phi = phi_base.copy()
    for (link, mom), (_, _, _, sl) in zip(var.columns, var.parts):
        phi[NPARAM * link : NPARAM * (link + 1)] += mom.T @ x[sl]
    result = _build(motion, var, x, phi, designed)
    result.strength = _safety.analysed(checked, result.after, motion.input)
    result.solver.update(_solver_report(sol, quantities, before, norm, t0))
    # Each quantity's value at the masses found (the solver's δ = M x holds to its
    # feasibility tolerance only, 1e-8 when a program was solved again, §3).
    dx = (phi - phi_base)[cols]
    result.solver["values"] = {
        q["name"]: _norm_value(q["rows"] @ dx + q["constant"], q["dim"], q["samples"],
                               "peak" if q.get("peak") else norm)
        for q in quantities}
    # Predicted quantities along the motion (what the re-analysis must reproduce).
    full = data @ phi
    result.predicted.update(
        {
            "force": full[:, 0:3],
            "moment": full[:, 3:6],
            "torque": full[:, 6 : 6 + reg["nactuated"]],
            "bearing": full[:, 6 + reg["nactuated"] :].reshape(n, -1, 3),
        }
    )
    result.objective.update(objective)
    result.zero = zero
    # What is written: cells decided, joined, polished; the written parts analysed again.
    shapes = [(name, link, sp, x[sl]) for (kind, name, sp, sl), (link, _) in zip(var.parts, var.columns)
              if kind == "shape"]
    result.realised = realise(motion, shapes, phi, data, result.predicted, result.bodies,
                              _body_from_parameters, say)
    if result.realised is not None:
        # Each Shape writes its realised part (what was designed, not thresholded cells).
        result.shapes = {n: replace(s, realised=result.realised.parts.get(n)) for n, s in result.shapes.items()}
    result.solver["time"] = time.perf_counter() - t0
    return result


def _build(motion, var: _Variables, x, phi, designed) -> Balance:
    model = motion.model
    shapes, cws = {}, []
    by_link: dict[int, list] = {}
    for (kind, name, spec, sl), (link, mom) in zip(var.parts, var.columns):
        by_link.setdefault(link, []).append((kind, name, spec, sl, mom))
        if kind == "shape":
            shapes[name] = (spec, sl)
        if kind == "counterweight":
            pts = np.atleast_2d(np.asarray(spec.points, float))
            # Placed: above 1e-9 of the largest design mass or of the model's mass (the
            # solver's round-off otherwise lists a 1e-26 kg "counterweight").
            big = max(float(np.max(x)), float(model.total_mass), 1e-300)
            cws += [(name, p, float(m)) for p, m in zip(pts, x[sl]) if m > 1e-9 * big]
    out_shapes = {}
    for name, (spec, sl) in shapes.items():
        centers, _, cap = spec.cells(model)
        out_shapes[name] = Shape(name, centers, x[sl], cap, float(spec.cell))
    bodies, new_model = {}, model
    for link in designed:
        name = model.link_names[link]
        parts = by_link[link]
        if all(kind != "shape" for kind, *_ in parts):
            # Point masses only: the body from them (exactly as before: a lump is allowed).
            masses, positions = [], []
            if link not in var.replaced:
                pm = model.body(name).point_masses()
                masses += list(pm.masses)
                positions += list(np.asarray(pm.positions, float))
            for _kind, _, _spec, sl, mom in parts:
                masses += list(x[sl])
                positions += list(mom[:, 1:4])
            body = _core.RigidBody.from_point_masses(np.array(masses), np.array(positions))
        else:
            # Cells carry their own inertia: the body from the parameters they give.
            body = _body_from_parameters(phi[NPARAM * link : NPARAM * (link + 1)])
        bodies[name] = body
        new_model = new_model.with_body(name, body)
    after = analyze_motion(
        new_model,
        motion.t,
        motion.q,
        motion.v,
        motion.a,
        actuated=motion.actuated if model.nloops or model.ncouplings else None,
        gravity=motion.gravity,
        about=motion.shaking.about,
    )
    return Balance(
        masses=x,
        counterweights=cws,
        bodies=bodies,
        model=new_model,
        before=motion,
        after=after,
        predicted={},
        objective={},
        zero=(),
        shapes=out_shapes,
    )


def objective_value(b: Balance, name: str) -> float:
    """A design's value of objective ``name`` in its problem's norm (absolute units; kg of
    design material for ``"mass"``)."""
    if name == "mass":
        return float(np.sum(b.masses))
    if name in b.solver.get("values", {}):
        return float(b.solver["values"][name])
    # Not in its program: from the prediction along the motion (which `after` reproduces).
    if name.startswith("bearing:"):
        model, joint = b.model, name.split(":", 1)[1]
        names = list(model.link_names) + list(model.loop_names)
        if joint not in names:
            raise InvalidInputError(f"name: '{name}' names no joint (joints: {names})")
        y = b.predicted["bearing"][:, names.index(joint)]
    elif name in QUANTITIES:
        y = b.predicted[name].reshape(len(b.predicted[name]), -1, b.predicted[name].shape[-1])
    else:
        raise InvalidInputError(f"name: expected one of {OBJECTIVES} or 'bearing:<joint>', got {name!r}")
    size = y.shape[-1] if name != "torque" else b.predicted["torque"].shape[1]
    return _norm_value(np.asarray(y).reshape(-1), size, len(b.predicted["force"]), b.solver["norm"])
