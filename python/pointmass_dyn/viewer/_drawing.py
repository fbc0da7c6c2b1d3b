"""What an animation draws, in the world frame, frame by frame (docs/visualisation.md): the
:class:`Drawing` every writer (page, video, Meshcat) reads, its colours, and the camera.

Links between joint origins, joint axes, the seven point masses of every link (radius ∝
|m|^(1/3), colour by sign) and the box they are corners of, cut joints, trails, the
shaking-force arrow, contact-force arrows, the world frame, and each contact plane with a
grid on it (a ground grid under the motion when there is none).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InvalidInputError
from . import _camera, _meshes

#: Colours (RGB in 0..1), shared by both writers so a page and a GIF look alike.
COLOURS = {
    "positive": (0.16, 0.42, 0.85),  # point masses m > 0
    "negative": (0.90, 0.25, 0.10),  # point masses m < 0 (the equimomental set allows them)
    "zero": (0.55, 0.55, 0.55),  # m = 0: drawn small, so the box's seven points stay visible
    "link": (0.30, 0.30, 0.34),
    "axis": (0.95, 0.70, 0.05),  # revolute / prismatic joint axes
    "cut": (0.80, 0.10, 0.80),  # cut joints closing loops
    "shaking": (0.85, 0.05, 0.45),
    "contact": (0.0, 0.62, 0.58),  # ground-contact forces, one arrow per point in contact
    "grid": (0.78, 0.78, 0.80),
    "box": (0.55, 0.62, 0.78),  # edges of each link's point-mass box
}
#: Trail colours in order (a trail may also name its own).
TRAIL_COLOURS = [(0.0, 0.75, 0.25), (0.10, 0.60, 0.95), (0.95, 0.50, 0.0), (0.55, 0.20, 0.85)]


@dataclass
class Drawing:
    """Everything both writers draw, world frame, per frame ``F`` (arrays float64).

    ``spheres``: point masses, (F, P, 3) centres with ``sphere_radius`` (P,) and
    ``sphere_colour`` (P, 3). ``links``: (F, L, 2, 3) segments, ``boxes``: (F, 12·nlinks,
    2, 3) edges of each link's point-mass box (also as ``box_pose`` (F, nlinks, 12) and
    ``box_corners`` (nlinks, 2, 3), lowest and highest corner in the link frame), ``axes``: (F, A, 2, 3) joint
    axis segments, ``cuts``: (F, C, 2, 3) the two ends of each cut joint (plus its axis as
    an ``axes`` segment). ``trails``: (F, T, 3) with ``trail_colour`` (T, 3). ``arrow``:
    (F, 2, 3) shaking-force arrow (tail, head) or None. ``contact``: (F, K, 2, 3) contact-force
    arrows (tail at the contact point, head at point + ``contact_scale`` · force; tail = head
    where a point carries no force, which draws nothing) or None, ``contact_scale`` in m/N.
    ``planes``: each ground contact's plane (:func:`._camera.plane_grid`: ``point``,
    ``normal``, the square grid drawn on it, and its ``name``); ``grid``: the ground, the
    first plane's grid or, without planes, one under the motion. ``camera``: the initial
    view."""

    times: np.ndarray
    spheres: np.ndarray
    sphere_radius: np.ndarray
    sphere_colour: np.ndarray
    sphere_mass: np.ndarray
    links: np.ndarray
    boxes: np.ndarray
    box_pose: np.ndarray
    box_corners: np.ndarray
    link_radius: float
    axes: np.ndarray
    cuts: np.ndarray
    trails: np.ndarray
    trail_colour: np.ndarray
    arrow: np.ndarray | None
    grid: dict
    camera: dict
    size: float
    #: Largest side of the box holding the motion.
    extent: float = 0.0
    title: str = ""
    labels: dict = field(default_factory=dict)
    #: The robot's shapes (``_visuals``) or None: meshes, instances, body poses.
    visuals: dict | None = None
    #: Layers shown when the page opens (:data:`LAYERS`).
    show: tuple = ()
    #: Contact-force arrows (F, K, 2, 3) or None, and their scale (metres per newton).
    contact: np.ndarray | None = None
    contact_scale: float = 0.0
    #: The contact planes, each a grid dict (:func:`._camera.plane_grid`) with its ``name``.
    planes: list = field(default_factory=list)

    @property
    def triangles(self) -> int:
        return 0 if self.visuals is None else self.visuals["scene"].triangles

    @property
    def nframes(self) -> int:
        return len(self.times)


# ---------------------------------------------------------------- camera
# (in ._camera; these names stay here, where users and tests found them)

VIEWS = _camera.VIEWS
view_projection = _camera.view_projection
project = _camera.project
camera_at = _camera.camera_at


def default_camera(lo: np.ndarray, hi: np.ndarray) -> dict:
    """A view of the box ``[lo, hi]``, z up (:func:`._camera.fit`)."""
    return _camera.fit(lo, hi)


# ---------------------------------------------------------------- the drawing


def _body_index(model, body, what: str) -> int:
    names = model.body_names
    if isinstance(body, str):
        if body not in names:
            raise InvalidInputError(f"{what}: expected a body name of {names}, got '{body}'")
        return names.index(body)
    if isinstance(body, (int, np.integer)) and 0 <= int(body) < len(names):
        return int(body)
    raise InvalidInputError(
        f"{what}: expected a body name or an index 0..{len(names) - 1}, got {body!r}"
    )


def _trail_specs(model, trails) -> list[tuple[int, np.ndarray, tuple]]:
    """``trails``: body names/indices (their origin), or ``(body, point)`` pairs (point in
    the body frame), or ``(body, point, colour)``."""
    out = []
    for k, spec in enumerate(trails or ()):
        colour = TRAIL_COLOURS[k % len(TRAIL_COLOURS)]
        point = np.zeros(3)
        if isinstance(spec, (tuple, list)):
            if not 1 <= len(spec) <= 3:
                raise InvalidInputError(
                    f"trails[{k}]: expected a body, (body, point) or (body, point, colour), "
                    f"got {spec!r}"
                )
            body = spec[0]
            if len(spec) > 1:
                point = np.asarray(spec[1], dtype=float)
                if point.shape != (3,) or not np.all(np.isfinite(point)):
                    raise InvalidInputError(
                        f"trails[{k}]: expected a finite point of shape (3,), got {spec[1]!r}"
                    )
            if len(spec) > 2:
                colour = _colour(spec[2], f"trails[{k}] colour")
        else:
            body = spec
        out.append((_body_index(model, body, f"trails[{k}]"), point, colour))
    return out


def _colour(c, what: str) -> tuple:
    if isinstance(c, str) and c.startswith("#") and len(c) == 7:
        try:
            return tuple(int(c[i:i + 2], 16) / 255 for i in (1, 3, 5))
        except ValueError:
            pass
    else:
        arr = np.asarray(c, dtype=float) if not isinstance(c, str) else np.array([])
        if arr.shape == (3,) and np.all((arr >= 0) & (arr <= 1)):
            return tuple(arr.tolist())
    raise InvalidInputError(f"{what}: expected '#rrggbb' or 3 numbers in [0, 1], got {c!r}")


#: The 12 edges of a box, as pairs of corners numbered by their (x, y, z) sign bits.
BOX_EDGES = [(a, a | bit) for bit in (1, 2, 4) for a in range(8) if not a & bit]


def box_corners(lo, hi) -> np.ndarray:
    """The eight corners (8, 3) of the box ``[lo, hi]``, corner ``c`` taking ``hi`` along
    axis ``k`` where bit ``k`` of ``c`` is set (the numbering of :data:`BOX_EDGES`)."""
    return np.array([[(hi if c >> k & 1 else lo)[k] for k in range(3)] for c in range(8)])


def _boxes(model, poses) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each link's point-mass box (the seven points are seven of its eight corners,
    docs/method.md §1): its 12 edges (F, 12·nlinks, 2, 3), and compactly the link poses
    (F, nlinks, 12: rotation row-major, origin) with the box's corners ``lo``, ``hi``
    (nlinks, 3) in the link frame."""
    nf = poses["points"].shape[0]
    edges, pose, los, his = [], [], [], []
    for i, name in enumerate(model.link_names):
        b = model.body_names.index(name)
        rot, org = poses["rotations"][:, b], poses["origins"][:, b]
        # The points in the link's frame (constant in time: read at frame 0).
        local = (poses["points"][0, i] - org[0]) @ rot[0]
        lo, hi = local.min(axis=0), local.max(axis=0)
        corners = box_corners(lo, hi)
        world = org[:, None, :] + np.einsum("fij,cj->fci", rot, corners)
        edges += [np.stack([world[:, a], world[:, c]], axis=1) for a, c in BOX_EDGES]
        pose.append(np.concatenate([rot.reshape(nf, 9), org], axis=1))
        los.append(lo)
        his.append(hi)
    if not edges:
        return np.zeros((nf, 0, 2, 3)), np.zeros((nf, 0, 12)), np.zeros((0, 3))
    return (np.stack(edges, axis=1), np.stack(pose, axis=1),
            np.stack([np.array(los), np.array(his)], axis=1))


#: The page's layers (toggles): the robot's shapes, the seven point masses of each link with
#: their boxes, the links as segments, the joint axes, body frames, force arrows.
LAYERS = ("robot", "masses", "links", "axes", "frames", "forces")


def _layers(show, robot: bool) -> tuple:
    """Layers shown at first: ``show`` if given, else the robot and forces for a model with
    visuals, and everything but the robot and frames otherwise."""
    if show is None:
        return ("robot", "forces") if robot else ("masses", "links", "axes", "forces")
    names = (show,) if isinstance(show, str) else tuple(show)
    bad = [n for n in names if n not in LAYERS]
    if bad:
        raise InvalidInputError(f"show: expected names among {LAYERS}, got {bad!r}")
    return names


def _visuals(model, rot, origins, triangles) -> dict | None:
    """The model's visuals as triangles (:mod:`._meshes`), with the poses (F, nb, 12:
    rotation row-major, origin) of the bodies that carry them and the world corners
    (F, 8·instances, 3) of their boxes; None for a model without visuals."""
    if not model.visuals:
        return None
    scene = _meshes.visual_scene(
        model, _meshes.DEFAULT_TRIANGLES if triangles is None else triangles)
    if not scene.instances:
        return None
    bodies = sorted({i.body for i in scene.instances})
    nf = rot.shape[0]
    pose = np.concatenate([rot[:, bodies].reshape(nf, len(bodies), 9), origins[:, bodies]],
                          axis=2)
    local = _meshes.bounds(scene)  # (k, 8, 3) in body frames
    which = [i.body for i in scene.instances]
    corners = origins[:, which, None, :] + np.einsum("fkij,kcj->fkci", rot[:, which], local)
    return {"scene": scene, "bodies": bodies, "pose": pose,
            "corners": corners.reshape(nf, -1, 3), "model": model}


def _links(model, origins, jo, rot, info, floating) -> np.ndarray:
    """The links as segments (F, L, 2, 3)."""
    nf, nb = origins.shape[0], len(info)
    children = {b: [c for c in range(nb) if info[c][2] == b] for b in range(nb)}
    # Links: parent origin → joint origin → body origin; a body without children extends
    # to twice its centre of mass (a uniform rod's far end), so a leaf is not invisible. A
    # floating base is joined to nothing.
    segs = []
    for b in range(nb):
        parent = info[b][2]
        if b not in floating:
            start = origins[:, parent] if parent >= 0 else np.zeros((nf, 3))
            segs.append((start, jo[:, b]))
            segs.append((jo[:, b], origins[:, b]))
        if not children[b]:
            com = np.asarray(model.body(b).com, dtype=float)
            segs.append((origins[:, b], origins[:, b] + 2 * rot[:, b] @ com))
    segs = segs or [(origins[:, 0], origins[:, 0])]
    links = np.stack([np.stack(s, axis=1) for s in segs], axis=1)
    # Degenerate segments (length 0 in every frame) are dropped.
    keep = np.linalg.norm(links[:, :, 1] - links[:, :, 0], axis=-1).max(axis=0) > 1e-12
    return links[:, keep]


def _axes(poses, axis_len: float) -> tuple[np.ndarray, np.ndarray]:
    """The joint and cut-joint axes as segments (F, A, 2, 3) and the cut joints' two
    points (F, C, 2, 3)."""
    jo, ja = poses["joint_origins"], poses["joint_axes"]
    nf, nb = ja.shape[0], ja.shape[1]
    axes = []
    for b in range(nb):
        if np.any(ja[0, b] != 0):
            axes.append(np.stack([jo[:, b] - axis_len * ja[:, b],
                                  jo[:, b] + axis_len * ja[:, b]], axis=1))
    la, lb, lax = poses["loop_a"], poses["loop_b"], poses["loop_axes"]
    cuts = np.stack([la, lb], axis=2) if la.shape[1] else np.zeros((nf, 0, 2, 3))
    for c in range(la.shape[1]):
        if np.any(lax[0, c] != 0):
            axes.append(np.stack([la[:, c] - axis_len * lax[:, c],
                                  la[:, c] + axis_len * lax[:, c]], axis=1))
    axes = np.stack(axes, axis=1) if axes else np.zeros((nf, 0, 2, 3))
    return axes, cuts


def build_drawing(
    model,
    times: np.ndarray,
    q: np.ndarray,
    *,
    trails=None,
    shaking: np.ndarray | None = None,
    title: str = "",
    gravity=None,
    camera: Any = "auto",
    show=None,
    triangles: int | None = None,
    contact: tuple[np.ndarray, np.ndarray] | None = None,
    contact_scale: float | None = None,
    planes=None,
) -> Drawing:
    """The :class:`Drawing` of ``model`` at configurations ``q`` (F, nq) and ``times`` (F,).
    ``shaking``: the shaking force (F, 3) to draw as an arrow, or None. ``contact``: the
    contact points and their forces, ``(position, force)`` each (F, K, 3), drawn as arrows
    scaled by ``contact_scale`` (m/N; None: the largest force is 25 % of the scene's size),
    or None. ``planes``: ``(name, normal, height)`` of each contact plane ``normal · x =
    height`` (``normal`` unit), drawn with a grid on it; without planes a ground grid lies
    under the motion. ``gravity``: sets
    "up" (−g) for the camera and the ground. ``camera``, ``show``, ``triangles``: as in
    :func:`~pointmass_dyn.viewer.animate`."""
    poses = model.body_poses(q)
    nf, nb = len(times), model.nbodies
    origins, jo = poses["origins"], poses["joint_origins"]
    rot = poses["rotations"]
    info = [model.body_info(b) for b in range(nb)]
    floating = [b for b in range(nb) if info[b][2] < 0 and info[b][1] == "FreeFlyer"]

    links = _links(model, origins, jo, rot, info, floating)

    masses, _ = model.point_masses(q[0])
    pts = poses["points"].reshape(nf, -1, 3)
    m = np.asarray(masses, dtype=float).reshape(-1)
    boxes, box_pose, box_corners = _boxes(model, poses)

    specs = _trail_specs(model, trails)
    trail = np.zeros((nf, len(specs), 3))
    for k, (b, p, _c) in enumerate(specs):
        trail[:, k] = origins[:, b] + rot[:, b] @ p
    trail_colour = np.array([c for _b, _p, c in specs]).reshape(-1, 3)

    visuals = _visuals(model, rot, origins, triangles)
    # The subject, frame by frame: a robot's meshes and point masses, else everything drawn
    # and the world origin.
    if visuals is not None:
        subject = [pts, visuals["corners"], trail]
    else:
        subject = [pts, links.reshape(nf, -1, 3), trail, np.zeros((nf, 1, 3))]
    per_frame = np.concatenate(subject, axis=1)
    lo_f, hi_f = per_frame.min(axis=1), per_frame.max(axis=1)
    lo, hi = lo_f.min(axis=0), hi_f.max(axis=0)
    size = max(float(np.linalg.norm(hi - lo)), 1e-3)
    up = _camera.up_from_gravity(gravity)
    base = origins[:, floating[0]] if floating else None
    cam = _camera.choose(camera, lo_f, hi_f, base, up)
    if cam.get("track") is not None:  # sizes follow the subject, not its whole path
        size = max(float(np.max(np.linalg.norm(hi_f - lo_f, axis=1))), 1e-3)

    # Radius ∝ |m|^(1/3) (a sphere of uniform density), the heaviest 2.5 % of the scene size.
    mmax = max(float(np.max(np.abs(m))), 1e-300)
    radius = 0.025 * size * np.cbrt(np.abs(m) / mmax)
    radius = np.maximum(radius, 0.006 * size)
    colour = np.array([
        COLOURS["positive"] if x > 0 else COLOURS["negative"] if x < 0 else COLOURS["zero"]
        for x in m
    ]).reshape(-1, 3)

    axes, cuts = _axes(poses, 0.06 * size)

    arrow = None
    if shaking is not None:
        f = np.asarray(shaking, dtype=float)
        fmax = float(np.max(np.linalg.norm(f, axis=1)))
        scale = 0.35 * size / fmax if fmax > 0 else 0.0
        base = np.zeros((nf, 3))
        arrow = np.stack([base, base + scale * f], axis=1)
    arrows, cscale = _contact_arrows(contact, contact_scale, size)
    grids = [{**_camera.plane_grid(lo, hi, n, h, size), "name": name}
             for name, n, h in planes or ()]

    return Drawing(
        times=np.asarray(times, dtype=float),
        spheres=pts,
        sphere_radius=radius,
        sphere_colour=colour,
        sphere_mass=m,
        links=links,
        boxes=boxes,
        box_pose=box_pose,
        box_corners=box_corners,
        link_radius=0.008 * size,
        axes=axes,
        cuts=cuts,
        trails=trail,
        trail_colour=trail_colour,
        arrow=arrow,
        grid=grids[0] if grids else _camera.ground(lo, hi, up),
        camera=cam,
        size=size,
        extent=max(float(np.max(hi - lo)), 1e-3),
        title=title,
        labels={"links": model.link_names, "loops": model.loop_names},
        visuals=visuals,
        show=_layers(show, visuals is not None),
        contact=arrows,
        contact_scale=cscale,
        planes=grids,
    )


#: Share of the scene's size the largest contact force is drawn at by default.
CONTACT_SHARE = 0.25


def _contact_arrows(contact, scale, size: float) -> tuple[np.ndarray | None, float]:
    """Contact-force arrows (F, K, 2, 3): tail at each point, head at point + scale · force
    (a point without force: tail = head). ``scale`` None: :data:`CONTACT_SHARE` of ``size``
    for the largest force (1 when every force is zero)."""
    if contact is None:
        return None, 0.0
    pos, force = (np.asarray(a, dtype=float) for a in contact)
    if scale is None:
        fmax = float(np.max(np.linalg.norm(force, axis=-1), initial=0.0))
        scale = CONTACT_SHARE * size / fmax if fmax > 0 else 1.0
    return np.stack([pos, pos + scale * force], axis=2), float(scale)
