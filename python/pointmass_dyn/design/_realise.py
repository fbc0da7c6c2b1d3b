"""What is written is what was designed (docs/design.md §4, "Realised parts").

After the conic program, each designed link's cells are decided: a cell at least half full
(or held full) is solid, the rest void, and a connected link is joined where that
separated it (``_connect.join``). Rounding moves the link's mass and moments by a few per
cent, so a polishing program follows: the decided cells stay as they are except the
**boundary layer** — the columns of cells along z (a plate's through-thickness stacks) on
the part's in-plane edge — whose thickness becomes continuous: a solid edge column may
thin to ``T_MIN`` of its thickness, a void column beside a solid one may grow up to the
full thickness, always centred on the column's mid-plane (so it keeps its faces with its
neighbours). A column of thickness ``t`` has mass, first moments and in-plane second
moments exactly linear in ``t``; the polish (Clarabel, through the same program as the
design) minimises the RMS mismatch between the realised and the designed quantities along
the whole motion (every regressor row: shaking force and moment, driving and bearing
forces; the shaking and bearing forces relative to their scale in the 1 % check, their
predicted peaks floored at ``FLOOR`` of their values before, the others to their values
before), then among the optima the least material
changed. The written geometry is a set of boxes whose corners are rounded to float32 (the
STL's numbers); the realised bodies are their exact mass properties, and the realised
model is analysed again along the motion."""

from __future__ import annotations

import struct
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import _core
from ..errors import InvalidInputError
from . import _connect
from ._shaking import analyze_motion

#: The thinnest a solid edge column may be polished to (fraction of its thickness).
T_MIN = 0.5
#: Realised forces within this fraction of the design's predicted peaks.
TOLERANCE = 0.01
#: Below this fraction of its value before, a designed quantity counts as cancelled: the
#: realised one is then held to the tolerance of this floor (the float32 STL's resolution).
FLOOR = 1e-3
NPARAM = 10


def box_moments(lower: np.ndarray, upper: np.ndarray, density: float) -> np.ndarray:
    """(B, 10) mass, first and second moments (xx, yy, zz, xy, xz, yz) of solid boxes."""
    e = upper - lower
    c = 0.5 * (upper + lower)
    m = density * np.prod(e, axis=1)
    s = c[:, :, None] * c[:, None, :] + np.einsum("bi,ij->bij", e**2 / 12.0, np.eye(3))
    return np.column_stack(
        [m, m[:, None] * c, m * s[:, 0, 0], m * s[:, 1, 1], m * s[:, 2, 2], m * s[:, 0, 1],
         m * s[:, 0, 2], m * s[:, 1, 2]]
    )


@dataclass
class RealisedPart:
    """A link as written: solid ``boxes`` (B, 2, 3) (lower, upper corners, body frame, float32
    values) of ``density``; ``body``: their exact mass, COM and inertia; ``thickness``: the
    polished columns' fraction of their thickness; ``cells``: which cells are (partly)
    solid."""

    body_name: str
    boxes: np.ndarray
    density: float
    body: Any
    cells: np.ndarray
    thickness: np.ndarray
    connected: bool

    @property
    def mass(self) -> float:
        return float(box_moments(self.boxes[:, 0], self.boxes[:, 1], self.density)[:, 0].sum())

    def write_stl(self, path: str | Path) -> int:
        """The part's surface as a binary STL (metres, body frame): the faces between solid
        and empty on the grid of every box corner, so every edge is shared by two triangles
        and no vertex lies on another triangle's edge. Returns the number of triangles."""
        tris = surface(self.boxes)
        try:
            Path(path).parent.mkdir(parents=True, exist_ok=True)
            with open(path, "wb") as f:
                f.write(b"pointmass_dyn realised part".ljust(80, b" "))
                f.write(struct.pack("<I", len(tris)))
                for t in tris.astype(np.float32):
                    n = np.cross(t[1] - t[0], t[2] - t[0])
                    n = n / (np.linalg.norm(n) or 1.0)
                    f.write(struct.pack("<12fH", *n, *t.reshape(-1), 0))
        except OSError as exc:
            raise InvalidInputError(f"path: expected a writable file path, got '{path}' ({exc})") from None
        return len(tris)


def surface(boxes: np.ndarray) -> np.ndarray:
    """(T, 3, 3) outward triangles of the union of ``boxes``: the elementary cells of the grid
    through every corner, the faces between an occupied and an empty one."""
    lines = [np.unique(boxes[:, :, k]) for k in range(3)]
    occ = np.zeros([len(g) - 1 for g in lines], dtype=bool)
    for lo, hi in boxes:
        i0 = [np.searchsorted(lines[k], lo[k]) for k in range(3)]
        i1 = [np.searchsorted(lines[k], hi[k]) for k in range(3)]
        occ[i0[0]:i1[0], i0[1]:i1[1], i0[2]:i1[2]] = True
    pad = np.pad(occ, 1)
    out = []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        for sign in (1, -1):
            shifted = np.roll(pad, -sign, axis=axis)
            face = (pad & ~shifted)[1:-1, 1:-1, 1:-1]
            idx = np.argwhere(face)
            if len(idx) == 0:
                continue
            p = np.zeros((len(idx), 4, 3))
            at = idx[:, axis] + (1 if sign > 0 else 0)
            p[:, :, axis] = lines[axis][at][:, None]
            iu, iv = idx[:, u], idx[:, v]
            corners = [(iu, iv), (iu + 1, iv), (iu + 1, iv + 1), (iu, iv + 1)]
            for k, (a, b) in enumerate(corners):
                p[:, k, u] = lines[u][a]
                p[:, k, v] = lines[v][b]
            if sign < 0:
                p = p[:, ::-1]
            out += [p[:, [0, 1, 2]], p[:, [0, 2, 3]]]
    return np.concatenate(out) if out else np.zeros((0, 3, 3))


@dataclass
class Realisation:
    """The written parts (:class:`RealisedPart` by body name; ``realised["crank"]``), the
    realised ``bodies`` and ``model`` (designed bodies with their written geometry),
    ``after``: that model analysed along the motion, ``deviation``: per quantity the largest
    difference from the design's prediction over the motion (``"max"``), the predicted and
    before peaks, and ``"relative"`` (to the predicted peak, floored at ``FLOOR`` of the
    peak before); ``within``: all of shaking force and bearing forces within ``TOLERANCE``;
    ``polish``: the polishing program's report."""

    parts: dict
    bodies: dict
    model: Any
    after: Any
    deviation: dict
    within: bool
    polish: dict = field(default_factory=dict)
    designed: dict = field(default_factory=dict)

    def __getitem__(self, name: str) -> RealisedPart:
        return self.parts[name]

    def __iter__(self):
        return iter(self.parts)

    def __len__(self) -> int:
        return len(self.parts)

    def table(self) -> str:
        """Each designed body's mass, COM and inertia (about the COM) as designed and as
        written, with the realised quantities' deviation from the prediction."""
        rows = [f"{'body':<10}{'':>9}{'mass (kg)':>13}{'COM (mm)':>30}{'Izz (kg m²)':>14}"]
        for name, real in self.bodies.items():
            for label, b in (("designed", self.designed.get(name)), ("written", real)):
                if b is None:
                    continue
                c = np.asarray(b.com) * 1e3
                rows.append(f"{name:<10}{label:>9}{b.mass:>13.6g}{c[0]:>10.4f}{c[1]:>10.4f}{c[2]:>10.4f}"
                            f"{np.asarray(b.inertia)[2, 2]:>14.6g}")
        for q, d in self.deviation.items():
            rows.append(f"{q:<19} realised − predicted: {d['max']:.3e} (peak {d['predicted']:.4g}, "
                        f"{100 * d['relative']:.3f} %)")
        return "\n".join(rows)


def world_quantities(a: Any) -> dict:
    """Shaking force and moment, driving forces and bearing forces (N, joints, 3; tree joints
    in world axes, cut joints in their frame a) of an analysis, as the prediction gives them."""
    model = a.model
    names = list(model.body_names)
    rot = [[model.placements(q)[0][names.index(n)] for n in model.link_names] for q in a.q]
    tree = np.einsum("nlij,nlj->nli", np.asarray(rot)[..., :3, :3], a.bearing[:, :, :3])
    bearing = np.concatenate([tree, a.cut[:, :, :3]], axis=1) if a.cut.size else tree
    tau = a.tau[:, a.actuated] if a.actuated is not None else a.tau
    return {"force": a.shaking.force, "moment": a.shaking.moment, "torque": tau, "bearing": bearing}


def deviation(got: dict, predicted: dict, before: dict) -> dict:
    out = {}
    for q in ("force", "moment", "torque", "bearing"):
        g, p, b = (np.asarray(d[q]) for d in (got, predicted, before))
        norm = (lambda y: np.abs(y)) if q == "torque" else (lambda y: np.linalg.norm(y, axis=-1))
        diff, peak, peak0 = norm(g - p).max(), norm(p).max(), norm(b).max()
        out[q] = {"max": float(diff), "predicted": float(peak), "before": float(peak0),
                  "relative": float(diff / max(peak, FLOOR * peak0, 1e-300))}
    return out


def _decide(spec: Any, model: Any, masses: np.ndarray) -> dict:
    """Solid and void cells of one link: at least half full or held full, then (connected
    links) joined into one part holding its bosses."""
    centers, lower, cap = spec.cells(model)
    fill = masses / cap
    idx = _connect.grid(centers, spec.cell)
    adj = _connect.neighbours(len(centers), _connect.faces(idx))
    # Decided by column along z (a plate's through-thickness stack, when its cells are
    # contiguous): the mean fill, so that columns are whole and the polish can thin them.
    level = _threshold(fill, cap, masses)
    solid = fill >= level
    stacks: dict = {}
    for j, (i0, i1, _) in enumerate(idx):
        stacks.setdefault((int(i0), int(i1)), []).append(j)
    for cells in stacks.values():
        ks = np.sort(idx[cells, 2])
        if np.all(np.diff(ks) == 1):
            solid[cells] = fill[cells].mean() >= level or bool(np.any(lower[cells] > 0))
    solid |= lower > 0
    if spec.connected:
        solid = _connect.join(solid, fill, adj, _connect.bosses(spec, model, centers))
    base = centers.min(axis=0)
    return {"centers": centers, "cap": cap, "idx": idx, "adj": adj, "solid": solid, "kept": lower > 0,
            "cell": float(spec.cell), "density": spec.rho, "base": base, "fill": fill}


def _threshold(fill: np.ndarray, cap: np.ndarray, masses: np.ndarray) -> float:
    """The fill above which cells are solid: the fullest cells until they hold the design's
    mass, between 0.25 and 0.5 (a design of mostly full and empty cells rounds at a half;
    one that spreads material thinly keeps its fullest cells rather than losing them all)."""
    order = np.argsort(-fill)
    reached = np.searchsorted(np.cumsum(cap[order]), masses.sum())
    level = fill[order[min(reached, len(order) - 1)]]
    return float(np.clip(level, 0.25, 0.5))


def _columns(d: dict, depth: int) -> list[tuple[np.ndarray, str]]:
    """The boundary layer: (cells, "S" or "V") of each column along z whose thickness the
    polish may change — solid ones within ``depth`` columns of the part's in-plane edge (none
    held full), void ones beside a solid column; each with every in-plane neighbour column
    spanning the same contiguous cells along z (so a column thinned about its mid-plane keeps
    its faces with them)."""
    idx, solid, kept = d["idx"], d["solid"], d["kept"]
    cols: dict[tuple[int, int], list[int]] = {}
    for j, (i0, i1, _) in enumerate(idx):
        cols.setdefault((int(i0), int(i1)), []).append(j)
    info = {}
    for key, cells in cols.items():
        cells = np.array(sorted(cells, key=lambda j: idx[j, 2]))
        ks = idx[cells, 2]
        contiguous = bool(np.all(np.diff(ks) == 1))
        state = "S" if solid[cells].all() else ("V" if not solid[cells].any() else "")
        info[key] = (cells, (int(ks[0]), int(ks[-1])) if contiguous else None, state, bool(kept[cells].any()))
    near = ((1, 0), (-1, 0), (0, 1), (0, -1))

    def around(key):
        return [info.get((key[0] + a, key[1] + b)) for a, b in near]

    def even(key):
        span = info[key][1]
        return span is not None and all(n is None or n[1] == span for n in around(key))

    free: dict[tuple[int, int], str] = {}
    edge = [k for k, (_, _, s, held) in info.items() if s == "S" and not held and even(k)
            and any(n is None or n[2] != "S" for n in around(k))]
    frontier = set(edge)
    free.update({k: "S" for k in edge})
    if depth == 0:  # every column
        free.update({k: "S" for k, (_, _, st, held) in info.items() if st == "S" and not held and even(k)})
    for _ in range(depth - 1):
        frontier = {(k[0] + a, k[1] + b) for k in frontier for a, b in near} - set(free)
        frontier = {k for k in frontier if k in info and info[k][2] == "S" and not info[k][3] and even(k)}
        free.update({k: "S" for k in frontier})
    for k, (_, _, s, _) in info.items():
        if s == "V" and even(k) and any(n is not None and n[2] == "S" for n in around(k)):
            free[k] = "V"
    return [(info[k][0], kind) for k, kind in sorted(free.items())]


def _unit(d: dict, cells: np.ndarray, g: float) -> tuple[np.ndarray, float]:
    """Moments of a unit mass spread over a column as a box centred on its mid-plane, the
    own second moment along z as ``g`` times the full column's (linearised thickness);
    and the column's full mass."""
    c = d["centers"][cells].mean(axis=0)
    s, h = d["cell"], d["cell"] * len(cells)
    own = np.array([s * s, s * s, g * h * h]) / 12.0
    u = np.array([1.0, *c, c[0] ** 2 + own[0], c[1] ** 2 + own[1], c[2] ** 2 + own[2],
                  c[0] * c[1], c[0] * c[2], c[1] * c[2]])
    return u, float(d["cap"][cells].sum())


def _cube_moments(d: dict, mask: np.ndarray) -> np.ndarray:
    p, s = d["centers"][mask], d["cell"]
    own = s * s / 12.0
    u = np.column_stack([np.ones(len(p)), p, p[:, 0] ** 2 + own, p[:, 1] ** 2 + own, p[:, 2] ** 2 + own,
                         p[:, 0] * p[:, 1], p[:, 0] * p[:, 2], p[:, 1] * p[:, 2]])
    return u.T @ d["cap"][mask]


def _boxes(d: dict, columns, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The written boxes (float32 corners) and the thickness of each column: solid cells
    outside the polished columns as cubes, each polished column as one box."""
    s, base, idx = d["cell"], d["base"], d["idx"]
    line = lambda k, i: base[k] + (i - 0.5) * s  # noqa: E731  (shared faces: the same numbers)
    in_col = np.zeros(len(idx), bool)
    out = []
    for (cells, _kind), tk in zip(columns, t):
        in_col[cells] = True
        if tk <= 1e-9:
            continue
        i, j = idx[cells[0], 0], idx[cells[0], 1]
        zmid = d["centers"][cells, 2].mean()
        half = 0.5 * tk * s * len(cells)
        out.append([[line(0, i), line(1, j), zmid - half], [line(0, i + 1), line(1, j + 1), zmid + half]])
    rest = np.nonzero(d["solid"] & ~in_col)[0]
    lo = np.column_stack([line(k, idx[rest, k]) for k in range(3)])
    hi = np.column_stack([line(k, idx[rest, k] + 1) for k in range(3)])
    boxes = np.concatenate([np.stack([lo, hi], axis=1), np.asarray(out, float).reshape(-1, 2, 3)])
    return boxes.astype(np.float32).astype(float)


def _polish(links: list, data: np.ndarray, phi: np.ndarray, scale: np.ndarray,
            depth: int) -> tuple[list, list, dict]:
    """One polishing program over every shape link's boundary layer (see the module's text).
    ``links``: (link index, decided dict, design's shape moments (10,)); returns each link's
    columns, their thicknesses and the solver's report."""
    n, rows, _ = data.shape
    start = phi.copy()
    cols, lower, upper, mr, mc, mv, columns, kinds, full = [], [], [], [], [], [], [], [], []
    count = 0
    for pos, (link, d, designed) in enumerate(links):
        cl = _columns(d, depth)
        columns.append(cl)
        start[NPARAM * link: NPARAM * (link + 1)] += _cube_moments(d, d["solid"]) - designed
        cols.extend(range(NPARAM * link, NPARAM * (link + 1)))
        for cells, kind in cl:
            # The own second moment along z of a column thinned to t is (t h)²/12 per unit
            # mass: linearised about a full column for a solid one (removing r changes it by
            # r h²/12 (1 + t + t²)), about half for a void one; it moves no force of a planar
            # motion about z, and `deviation` reports what it does.
            u, m = _unit(d, cells, 3.0 if kind == "S" else 0.25)
            sign = -1.0 if kind == "S" else 1.0
            kinds.append(kind)
            full.append(m)
            lower.append(0.0)
            upper.append((1.0 - T_MIN) * m if kind == "S" else m)
            mr += [NPARAM * pos + c for c in range(NPARAM)]
            mc += [count] * NPARAM
            mv += list(sign * u)
            count += 1
    w = np.repeat(scale[None, :], n, axis=0).reshape(-1, 1)
    block = data.reshape(n * rows, -1)
    spec = {
        "ndelta": len(cols), "lower": np.array(lower), "upper": np.array(upper),
        "map_rows": mr, "map_cols": mc, "map_vals": np.array(mv, float), "groups": [], "equal": [],
        "quantities": [{"name": "realised − designed", "rows": np.ascontiguousarray(w * block[:, cols]),
                        "constant": (w * (block @ (start - phi))[:, None])[:, 0], "dim": 1, "samples": n,
                        "weight": 1.0, "reference": 1.0, "limit": None, "zero": False}],
        "norm": "rms", "mass_weight": 0.0, "mass_reference": float(sum(upper) or 1.0), "mass_limit": None,
        "least_mass": True,
    }
    if count == 0:
        return columns, [np.zeros(0) for _ in links], {"status": "nothing to polish", "mismatch": float(
            np.sqrt(np.mean((w[:, 0] * (block @ (start - phi))) ** 2)))}
    sol = _core.design_solve(spec)
    x = np.clip(sol["x"], spec["lower"], spec["upper"])
    frac = np.where(np.array(kinds) == "S", 1.0 - x / np.array(full), x / np.array(full))
    t = np.split(frac, np.cumsum([len(cl) for cl in columns])[:-1])
    report = {"status": sol["status"], "gap_rel": float(sol["gap_rel"]), "iterations": int(sol["iterations"]),
              "mismatch": float(sol["values"][0]), "columns": count, "depth": depth}
    return columns, t, report


def realise(motion: Any, shapes: list, phi: np.ndarray, data: np.ndarray, predicted: dict,
            bodies: dict, body_from: Any, say: Any) -> Realisation | None:
    """The written parts of a design (see the module's text). ``shapes``: (name, link index,
    LinkShape, its cells' masses); ``phi``: the design's parameters (10 per link);
    ``data``: the regressor (N, rows, 10 · links); ``predicted``: the design's quantities;
    ``bodies``: the designed bodies; ``body_from``: parameters (10,) → RigidBody."""
    if not shapes:
        return None
    model = motion.model
    decided = [_decide(spec, model, xs) for _, _, spec, xs in shapes]
    designed = [_cube_moments({**d, "cap": xs}, np.ones(len(xs), bool)) for d, (*_, xs) in zip(decided, shapes)]
    links = [(link, d, m) for (_, link, _, _), d, m in zip(shapes, decided, designed)]
    before = world_quantities(motion)
    scale = _row_scale(data.shape[1], predicted, before)
    best = None
    for depth in (1, 2, 0):
        say(f"polishing the written parts (boundary layer {depth or 'all'} column(s) deep)")
        columns, t, report = _polish(links, data, phi, scale, depth)
        out = _written(motion, shapes, decided, columns, t, phi, designed, bodies, body_from)
        out.polish = report
        out.deviation = deviation(world_quantities(out.after), predicted, before)
        out.within = all(out.deviation[q]["relative"] <= TOLERANCE for q in ("force", "bearing"))
        if best is None or _worst(out) < _worst(best):
            best = out
        if out.within:
            break
    if not best.within:
        worst = max(("force", "bearing"), key=lambda q: best.deviation[q]["relative"])
        warnings.warn(
            f"balance: the written parts' {worst} differs from the design's prediction by "
            f"{100 * best.deviation[worst]['relative']:.2f} % of its peak (more than "
            f"{100 * TOLERANCE:g} %) after polishing; use finer cells (Balance.realised)",
            RuntimeWarning, stacklevel=3)
    return best


def _worst(r: Realisation) -> float:
    return max(r.deviation[q]["relative"] for q in ("force", "bearing"))


def _row_scale(rows: int, predicted: dict, before: dict) -> np.ndarray:
    """1 / each regressor row's scale: for the quantities the 1 % check holds (shaking and
    bearing forces) their scale there — the predicted peak, floored at ``FLOOR`` of the peak
    before (a force the design cancels is matched to its floor, not to its value before) —
    and for the others (moment, driving forces) their peak before."""
    na = np.asarray(predicted["torque"]).shape[1]
    peak = {q: np.abs(np.asarray(before[q])).max() for q in ("moment", "torque")}
    peak.update({q: max(np.abs(np.asarray(predicted[q])).max(), FLOOR * np.abs(np.asarray(before[q])).max())
                 for q in ("force", "bearing")})
    s = np.empty(rows)
    s[0:3], s[3:6] = peak["force"], peak["moment"]
    s[6:6 + na], s[6 + na:] = peak["torque"], peak["bearing"]
    return 1.0 / np.where(s > 0, s, 1.0)


def _written(motion, shapes, decided, columns, t, phi, designed, bodies, body_from) -> Realisation:
    model = motion.model
    parts, real_bodies, new_model = {}, {}, model
    # The designed bodies without a shape (counterweights only) are as designed: point masses.
    shaped = {name for name, *_ in shapes}
    for name, body in bodies.items():
        if name not in shaped:
            new_model = new_model.with_body(name, body)
    for (name, link, spec, _), d, cl, tk, m in zip(shapes, decided, columns, t, designed):
        boxes = _boxes(d, cl, tk)
        written = box_moments(boxes[:, 0], boxes[:, 1], d["density"]).sum(axis=0)
        p = phi[NPARAM * link: NPARAM * (link + 1)] - m + written
        body = body_from(p)
        cells = d["solid"].copy()
        for (c, _), tc in zip(cl, tk):
            cells[c] = tc > 1e-9
        parts[name] = RealisedPart(name, boxes, d["density"], body, cells, np.asarray(tk), bool(spec.connected))
        real_bodies[name] = body
        new_model = new_model.with_body(name, body)
    after = analyze_motion(
        new_model, motion.t, motion.q, motion.v, motion.a,
        actuated=motion.actuated if model.nloops or model.ncouplings else None,
        gravity=motion.gravity, about=motion.shaking.about,
    )
    return Realisation(parts, real_bodies, new_model, after, {}, False,
                       designed={n: bodies[n] for n in real_bodies if n in bodies})
