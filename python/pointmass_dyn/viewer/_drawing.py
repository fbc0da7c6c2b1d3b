"""What an animation draws, in the world frame, frame by frame (docs/visualisation.md): the
:class:`Drawing` every writer (page, video, Meshcat) reads, its colours, and the camera.

Links between joint origins, joint axes, the seven point masses of every link (radius ∝
|m|^(1/3), colour by sign) and the box they are corners of, cut joints, trails, the
shaking-force arrow, the world frame and a ground grid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InvalidInputError

#: Colours (RGB in 0..1), shared by both writers so a page and a GIF look alike.
COLOURS = {
    "positive": (0.16, 0.42, 0.85),  # point masses m > 0
    "negative": (0.90, 0.25, 0.10),  # point masses m < 0 (the equimomental set allows them)
    "zero": (0.55, 0.55, 0.55),  # m = 0: drawn small, so the box's seven points stay visible
    "link": (0.30, 0.30, 0.34),
    "axis": (0.95, 0.70, 0.05),  # revolute / prismatic joint axes
    "cut": (0.80, 0.10, 0.80),  # cut joints closing loops
    "shaking": (0.85, 0.05, 0.45),
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
    (F, 2, 3) shaking-force arrow (tail, head) or None. ``camera``: the initial view."""

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

    @property
    def nframes(self) -> int:
        return len(self.times)


# ---------------------------------------------------------------- camera


#: (azimuth, elevation) in degrees: the general view (matplotlib's default 3-D view), and for
#: a motion flat across x, y or z a view about 30° off that axis, so its plane is seen nearly
#: face on rather than at a grazing angle.
VIEWS = {None: (-60.0, 25.0), 0: (-20.0, 20.0), 1: (-70.0, 20.0), 2: (-60.0, 60.0)}


def default_camera(lo: np.ndarray, hi: np.ndarray) -> dict:
    """A view of the box ``[lo, hi]`` (azimuth and elevation from :data:`VIEWS`; flat: an
    extent under 15 % of the largest), field of view 35°, far enough that the bounding
    sphere fits."""
    centre = (lo + hi) / 2
    extent = hi - lo
    radius = max(float(np.linalg.norm(extent)) / 2, 1e-3)
    flat = int(np.argmin(extent)) if extent.min() < 0.15 * extent.max() else None
    azimuth, elevation = VIEWS[flat]
    fov = 35.0
    return {
        "target": centre.tolist(),
        "distance": radius / math.sin(math.radians(fov / 2)) * 1.05,
        "azimuth": azimuth,
        "elevation": elevation,
        "fov": fov,
    }


def view_projection(camera: dict, aspect: float) -> np.ndarray:
    """The page's 4×4 world → clip matrix (column vectors): a perspective of vertical field
    of view ``fov`` looking at ``target`` from ``distance`` along azimuth/elevation (degrees,
    z up). The page computes the same matrix (``viewProj`` in viewer.js)."""
    az, el = math.radians(camera["azimuth"]), math.radians(camera["elevation"])
    d = camera["distance"]
    target = np.asarray(camera["target"], dtype=float)
    eye = target + d * np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az),
                                 math.sin(el)])
    f = target - eye
    f /= np.linalg.norm(f)
    s = np.cross(f, [0.0, 0.0, 1.0])
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = s, u, -f
    view[:3, 3] = -view[:3, :3] @ eye
    near, far = d / 100.0, d * 100.0
    ft = 1.0 / math.tan(math.radians(camera["fov"]) / 2)
    proj = np.zeros((4, 4))
    proj[0, 0], proj[1, 1] = ft / aspect, ft
    proj[2, 2], proj[2, 3] = (far + near) / (near - far), 2 * far * near / (near - far)
    proj[3, 2] = -1.0
    return proj @ view


def project(camera: dict, width: int, height: int, points) -> np.ndarray:
    """Pixel coordinates (x right, y down) of world ``points`` (..., 3) in a page of
    ``width × height`` CSS pixels at the initial camera."""
    p = np.asarray(points, dtype=float)
    h = np.concatenate([p, np.ones(p.shape[:-1] + (1,))], axis=-1)
    c = h @ view_projection(camera, width / height).T
    ndc = c[..., :3] / c[..., 3:4]
    return np.stack([(ndc[..., 0] + 1) / 2 * width, (1 - ndc[..., 1]) / 2 * height], axis=-1)


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


def build_drawing(
    model,
    times: np.ndarray,
    q: np.ndarray,
    *,
    trails=None,
    shaking: np.ndarray | None = None,
    title: str = "",
) -> Drawing:
    """The :class:`Drawing` of ``model`` at configurations ``q`` (F, nq) and ``times`` (F,).
    ``shaking``: the shaking force (F, 3) to draw as an arrow, or None."""
    poses = model.body_poses(q)
    nf, nb = len(times), model.nbodies
    origins, jo = poses["origins"], poses["joint_origins"]
    rot = poses["rotations"]
    info = [model.body_info(b) for b in range(nb)]
    children = {b: [c for c in range(nb) if info[c][2] == b] for b in range(nb)}

    # Links: parent origin → joint origin → body origin; a body without children extends
    # to twice its centre of mass (a uniform rod's far end), so a leaf is not invisible.
    segs = []
    for b in range(nb):
        parent = info[b][2]
        start = origins[:, parent] if parent >= 0 else np.zeros((nf, 3))
        segs.append((start, jo[:, b]))
        segs.append((jo[:, b], origins[:, b]))
        if not children[b]:
            com = np.asarray(model.body(b).com, dtype=float)
            segs.append((origins[:, b], origins[:, b] + 2 * rot[:, b] @ com))
    links = np.stack([np.stack(s, axis=1) for s in segs], axis=1)
    # Degenerate segments (length 0 in every frame) are dropped.
    keep = np.linalg.norm(links[:, :, 1] - links[:, :, 0], axis=-1).max(axis=0) > 1e-12
    links = links[:, keep]

    masses, _ = model.point_masses(q[0])
    pts = poses["points"].reshape(nf, -1, 3)
    m = np.asarray(masses, dtype=float).reshape(-1)
    boxes, box_pose, box_corners = _boxes(model, poses)

    specs = _trail_specs(model, trails)
    trail = np.zeros((nf, len(specs), 3))
    for k, (b, p, _c) in enumerate(specs):
        trail[:, k] = origins[:, b] + rot[:, b] @ p
    trail_colour = np.array([c for _b, _p, c in specs]).reshape(-1, 3)

    everything = np.concatenate([pts.reshape(-1, 3), links.reshape(-1, 3),
                                 trail.reshape(-1, 3), np.zeros((1, 3))])
    lo, hi = everything.min(axis=0), everything.max(axis=0)
    size = max(float(np.linalg.norm(hi - lo)), 1e-3)

    # Radius ∝ |m|^(1/3) (a sphere of uniform density), the heaviest 2.5 % of the scene size.
    mmax = max(float(np.max(np.abs(m))), 1e-300)
    radius = 0.025 * size * np.cbrt(np.abs(m) / mmax)
    radius = np.maximum(radius, 0.006 * size)
    colour = np.array([
        COLOURS["positive"] if x > 0 else COLOURS["negative"] if x < 0 else COLOURS["zero"]
        for x in m
    ]).reshape(-1, 3)

    axis_len = 0.06 * size
    axes = []
    ja = poses["joint_axes"]
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

    arrow = None
    if shaking is not None:
        f = np.asarray(shaking, dtype=float)
        fmax = float(np.max(np.linalg.norm(f, axis=1)))
        scale = 0.35 * size / fmax if fmax > 0 else 0.0
        base = np.zeros((nf, 3))
        arrow = np.stack([base, base + scale * f], axis=1)

    # Ground grid: a square under everything (world z up), spacing a round number.
    raw = size / 8
    step = min((f * 10 ** math.floor(math.log10(raw)) for f in (1, 2, 5, 10)),
               key=lambda x: abs(math.log(x / raw)))
    half = step * math.ceil(size / step / 2)
    grid = {
        "z": float(lo[2]) - 0.02 * size,
        "center": [round(float(c) / step) * step for c in (lo[:2] + hi[:2]) / 2],
        "half": half,
        "step": step,
    }
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
        grid=grid,
        camera=default_camera(lo, hi),
        size=size,
        extent=max(float(np.max(hi - lo)), 1e-3),
        title=title,
        labels={"links": model.link_names, "loops": model.loop_names},
    )
