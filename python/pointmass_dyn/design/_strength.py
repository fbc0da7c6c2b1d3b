"""Is a designed link strong enough (docs/design.md §4a): its members, their web sections,
the normal stress along the motion and the safety factor; the stress rows a design program
bounds (``limits={"safety": s}``).

The member model. A link with a :class:`~pointmass_dyn.Material` has one *member* from its
first pin (its own joint, else the first pin found) to each other pin (a star). Along each
member runs a *web*: the cells within ``web / 2`` of the pins' centre line, through the
whole thickness, kept full (like the bosses). A member's *sections* are cuts normal to its
axis, one per cell layer between the bosses; a section is the web's cells crossing the cut
(squares of the cell's side). At each section and sample the normal stress is

    σ(y, z) = N / A + [y z] I⁻¹ [∫σy, ∫σz]ᵀ       (σ = N/A + M c/I for a symmetric one)

with ``N`` and ``M`` the force and moment carried by the cut, from the pin forces on one
side of it (the far pin's, or all the others' — both are taken: they differ by the link's
own inertia force, which this model does not spread along the member), at the four corners
of the section's bounding box. Shear and torsion are not counted. The safety factor is the
material's allowable stress over the largest ``|σ|``. Every term is linear in the pin forces,
hence in the designed links' ten parameters: the program bounds ``|σ|`` at every sample,
section and corner (peak cones of dimension one, added by cutting planes)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _core
from ..errors import InvalidInputError

CORNERS = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)


@dataclass(frozen=True)
class Section:
    """A cut of a member at ``s`` (m from its first pin): its ``centroid`` (body frame),
    ``area`` (m²), ``inertia`` (2×2 about the centroid, member axes y, z) and the
    ``corners`` (4, 2) of its bounding box relative to the centroid."""

    s: float
    centroid: np.ndarray
    area: float
    inertia: np.ndarray
    corners: np.ndarray


@dataclass(frozen=True)
class Member:
    """The part of a link between pin ``a`` and pin ``b`` (indices into the link's pins):
    axes ``ex`` (a to b), ``ey``, ``ez`` (the pin's axis) in the body frame."""

    a: int
    b: int
    origin: np.ndarray
    ex: np.ndarray
    ey: np.ndarray
    ez: np.ndarray
    length: float
    sections: tuple = ()


def link_pins(model, body) -> list[dict]:
    """The pins on ``body`` with the source of each one's force (``_core.design_pin_loads``)."""
    return list(_core.design_pin_loads(model, body))


def _frame(pa: dict, pb: dict) -> tuple:
    d = np.asarray(pb["point"]) - np.asarray(pa["point"])
    length = float(np.linalg.norm(d))
    ex = d / length
    ez = np.asarray(pa["axis"], float)
    ez = ez - (ez @ ex) * ex
    if np.linalg.norm(ez) < 1e-9:  # a ball joint, or an axis along the member
        ez = np.cross(ex, [0.0, 0.0, 1.0])
        if np.linalg.norm(ez) < 1e-9:
            ez = np.cross(ex, [0.0, 1.0, 0.0])
    ez = ez / np.linalg.norm(ez)
    return length, ex, np.cross(ez, ex), ez


def members(pins: list[dict], boss: float) -> list[Member]:
    """The star of members from the first pin to every other one further than two bosses."""
    out = []
    for j in range(1, len(pins)):
        if np.linalg.norm(np.asarray(pins[j]["point"]) - pins[0]["point"]) <= 2 * boss:
            continue  # coincident pins: no member between them
        length, ex, ey, ez = _frame(pins[0], pins[j])
        out.append(Member(0, j, np.asarray(pins[0]["point"], float), ex, ey, ez, length))
    return out


def _local(member: Member, centers: np.ndarray) -> np.ndarray:
    d = centers - member.origin
    return np.column_stack([d @ member.ex, d @ member.ey, d @ member.ez])


def web_mask(member_list: list[Member], centers: np.ndarray, web: float) -> np.ndarray:
    """The cells of the members' webs: within ``web / 2`` of a member's centre line."""
    mask = np.zeros(len(centers), dtype=bool)
    for m in member_list:
        x = _local(m, centers)
        mask |= (x[:, 0] >= 0) & (x[:, 0] <= m.length) & (np.abs(x[:, 1]) <= 0.5 * web * (1 + 1e-9))
    return mask


def with_sections(member: Member, centers: np.ndarray, full: np.ndarray, cell: float,
                  boss: float, web: float) -> Member:
    """``member`` with its sections: the full cells of its web crossing each cut."""
    x = _local(member, centers)
    inside = full & (np.abs(x[:, 1]) <= 0.5 * web * (1 + 1e-9))
    lo, hi = boss + 0.5 * cell, member.length - boss - 0.5 * cell
    stations = np.arange(lo, hi + 1e-12, cell) if hi >= lo else np.array([0.5 * member.length])
    out = []
    for s in stations:
        on = inside & (x[:, 0] >= s - 0.5 * cell) & (x[:, 0] < s + 0.5 * cell)
        if not np.any(on):
            out.append(Section(float(s), member.origin + s * member.ex, 0.0, np.zeros((2, 2)),
                               np.zeros((4, 2))))
            continue
        yz = x[on, 1:]
        c = yz.mean(axis=0)
        r = yz - c
        a = cell * cell
        inertia = a * (r.T @ r) + np.eye(2) * len(yz) * a * a / 12.0  # + each square's own
        half = 0.5 * (r.max(axis=0) - r.min(axis=0)) + 0.5 * cell
        mid = 0.5 * (r.max(axis=0) + r.min(axis=0))
        centroid = member.origin + s * member.ex + c[0] * member.ey + c[1] * member.ez
        out.append(Section(float(s), centroid, a * len(yz), inertia, mid + CORNERS * half))
    return Member(**{**member.__dict__, "sections": tuple(_run_ends(member, out))})


def _run_ends(member: Member, sections: list[Section]) -> list[Section]:
    """The first and last of each run of equal sections: along a run the cut's loads, hence
    every corner's stress, are affine in ``s`` (the pins' arms change linearly), so the
    largest ``|σ|`` of the run is at one of its ends — the others add nothing."""
    def key(sec):
        offset = sec.centroid - member.origin - sec.s * member.ex
        return np.concatenate([[sec.area], sec.inertia.ravel(), sec.corners.ravel(), offset])
    keep = []
    for k, sec in enumerate(sections):
        same_before = k > 0 and np.allclose(key(sections[k - 1]), key(sec), rtol=1e-12, atol=0)
        same_after = k + 1 < len(sections) and np.allclose(key(sections[k + 1]), key(sec),
                                                           rtol=1e-12, atol=0)
        if not (same_before and same_after):
            keep.append(sec)
    return keep


def stress_weights(member: Member, pins: list[dict]) -> np.ndarray:
    """(sections, 2 sides, 4 corners, pins, 6): ``σ = Σ_j w_j · [F_j; M_j]`` with ``F_j``,
    ``M_j`` the force and moment on the link at pin j (body axes). Side 0: from the far pin;
    side 1: from all the others."""
    out = np.zeros((len(member.sections), 2, 4, len(pins), 6))
    for k, sec in enumerate(member.sections):
        if sec.area == 0.0:
            continue
        inv = np.linalg.inv(sec.inertia)
        for side, sign in ((0, 1.0), (1, -1.0)):
            loaded = [member.b] if side == 0 else [j for j in range(len(pins)) if j != member.b]
            for corner in range(4):
                c1, c2 = sec.corners[corner] @ inv
                for j in loaded:
                    # The cut's resultant M_R = −Σ ((p_j − C) × F_j + M_j) (the part's
                    # equilibrium); ∫σy = sign·M_R·ez, ∫σz = −sign·M_R·ey.
                    arm = np.asarray(pins[j]["point"]) - sec.centroid
                    v = c1 * member.ez - c2 * member.ey
                    out[k, side, corner, j, :3] = sign * (member.ex / sec.area + np.cross(arm, v))
                    out[k, side, corner, j, 3:] = -sign * v  # M_R = Σ F_j × (p_j − C) − M_j
    return out


def _axis(p: dict) -> np.ndarray:
    a = np.asarray(p["axis"], float)
    n = np.linalg.norm(a)
    return a / n if n > 0 else a


def pin_forces_rows(model, body: str, pins: list[dict], q: np.ndarray, data: np.ndarray,
                    actuated: list[int]) -> np.ndarray:
    """(N, pins, 6, P): the force and moment on the link at each pin, body axes, as rows over
    all links' parameters (``data`` the design regressor's (N, rows, P)). The moment is the
    driving torque about an actuated joint's axis (the regressor's rows hold no other)."""
    nl, nact = model.nlinks, len(actuated)
    b = model.body_names.index(body)
    out = np.zeros((len(q), len(pins), 6, data.shape[2]))
    v_index = [sl[1] for sl in model.joint_slices()]
    for j, p in enumerate(pins):
        if p["kind"] == "joint" and v_index[p["index"]] in actuated:
            row = 6 + actuated.index(v_index[p["index"]])
            out[:, j, 3:] = p["sign"] * _axis(p)[None, :, None] * data[:, row, None, :]
    for t in range(len(q)):
        rot, _ = model.placements(q[t])
        for j, p in enumerate(pins):
            start = 6 + nact + 3 * (p["index"] if p["kind"] == "joint" else nl + p["index"])
            r = np.asarray(p["frame_rotation"])
            if p["frame_body"] >= 0:
                r = rot[p["frame_body"]] @ r
            out[t, j, :3] = p["sign"] * (rot[b].T @ r) @ data[t, start:start + 3]
    return out


def pin_forces_analysed(analysis, body: str, pins: list[dict]) -> np.ndarray:
    """(N, pins, 6): the force and moment on the link at each pin, body axes, from an analysis
    along the motion (``bearing``: link axes; ``cut``: frame a's axes); the moment is the
    tree joints' about their axis (the driving torque; zero on a passive pin)."""
    model = analysis.model
    b = model.body_names.index(body)
    out = np.zeros((len(analysis.t), len(pins), 6))
    for t in range(len(analysis.t)):
        rot, _ = model.placements(analysis.q[t])
        for j, p in enumerate(pins):
            if p["kind"] == "joint":
                carrier = model.body_names.index(model.link_names[p["index"]])
                f = rot[carrier] @ analysis.bearing[t, p["index"], :3]
                m = rot[b].T @ rot[carrier] @ analysis.bearing[t, p["index"], 3:]
                out[t, j, 3:] = p["sign"] * (m @ _axis(p)) * _axis(p)
            else:
                r = np.asarray(p["frame_rotation"])
                if p["frame_body"] >= 0:
                    r = rot[p["frame_body"]] @ r
                f = r @ analysis.cut[t, p["index"], :3]
            out[t, j, :3] = p["sign"] * (rot[b].T @ f)
    return out


@dataclass
class LinkStrength:
    """A link's strength along the motion: ``material``, its ``members`` and ``pins``,
    ``stress`` (N, members, sections, 2, 4) in Pa, the ``safety`` factor (the allowable
    stress over the largest |σ|), where it occurs (``sample``, ``t``, ``input``: the
    driver's position then (the crank angle; None without one), ``member``, ``section`` (m
    from the member's first pin))."""

    body: str
    material: object
    pins: list
    members: list
    stress: np.ndarray
    safety: float
    sample: int
    t: float
    member: int
    section: float
    input: float | None = None


def analyse(analysis, body: str, material, member_list: list[Member], pins: list[dict],
            inputs=None) -> LinkStrength:
    """The stresses in a link's members from the pin forces of ``analysis`` (an independent
    re-analysis of a design: its bearing and cut joint forces)."""
    forces = pin_forces_analysed(analysis, body, pins)
    n = len(analysis.t)
    if not member_list:
        return LinkStrength(body, material, pins, [], np.zeros((n, 0)), np.inf, 0, 0.0, -1, 0.0)
    ns = max(len(m.sections) for m in member_list)
    stress = np.zeros((n, len(member_list), ns, 2, 4))
    for i, m in enumerate(member_list):
        w = stress_weights(m, pins)
        stress[:, i, : len(m.sections)] = np.einsum("kscjd,tjd->tksc", w, forces)
    peak = np.abs(stress)
    t, i, k, _, _ = np.unravel_index(int(np.argmax(peak)), peak.shape)
    top = float(peak.max(initial=0.0))
    safety = material.allowable_stress / top if top > 0 else np.inf
    inputs = analysis.input if inputs is None else inputs  # the driver's, per sample
    angle = None if inputs is None else float(np.asarray(inputs)[t])
    return LinkStrength(body, material, pins, member_list, stress, float(safety), int(t),
                        float(analysis.t[t]), int(i), float(member_list[i].sections[k].s), angle)


def stress_rows(model, body: str, member_list: list[Member], pins: list[dict], q, data,
                actuated: list[int]) -> np.ndarray:
    """(N · K, P): every section's corner stresses per sample (sample-major, K per sample)
    as rows over all links' parameters."""
    g = pin_forces_rows(model, body, pins, q, data, actuated)
    blocks = []
    for m in member_list:
        w = stress_weights(m, pins)
        blocks.append(np.einsum("kscjd,tjdp->tkscp", w, g).reshape(len(q), -1, g.shape[-1]))
    return np.concatenate(blocks, axis=1).reshape(-1, g.shape[-1])


def check_sections(body: str, member_list: list[Member]) -> None:
    """A member with a section of no material cannot carry anything: our error, naming it."""
    for m in member_list:
        for sec in m.sections:
            if sec.area == 0.0:
                raise InvalidInputError(
                    f"LinkShape '{body}': expected material at every section between pins "
                    f"{m.a} and {m.b}, got none at {sec.s:.4g} m from pin {m.a} "
                    "(widen web= or move the envelope over the pins' centre line)"
                )
