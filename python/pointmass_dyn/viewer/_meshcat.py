"""A live view in a Meshcat viewer (optional extra ``meshcat``; docs/visualisation.md §6):
the same drawing as the page, sent as Meshcat objects and one animation clip, for notebooks
(``vis.jupyter_cell()``) and scripts (``vis.open()``)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import AnimationWriterError
from ._animation import prepare
from ._drawing import BOX_EDGES, COLOURS, box_corners


def _hex(rgb) -> int:
    r, g, b = (int(round(255 * c)) for c in rgb)
    return (r << 16) | (g << 8) | b


def _translation(x) -> np.ndarray:
    t = np.eye(4)
    t[:3, 3] = x
    return t


def _segment(a, b) -> tuple[np.ndarray, float]:
    """The transform taking Meshcat's unit cylinder (along y, centred) to the segment
    a → b, unscaled, and the segment's length (the y scale)."""
    d = np.asarray(b, dtype=float) - np.asarray(a, dtype=float)
    length = float(np.linalg.norm(d))
    t = _translation((np.asarray(a) + np.asarray(b)) / 2)
    if length < 1e-12:
        return t, 1e-9
    y = d / length
    h = np.array([1.0, 0, 0]) if abs(y[0]) < 0.9 else np.array([0.0, 1, 0])
    x = np.cross(y, h)
    x /= np.linalg.norm(x)
    t[:3, 0], t[:3, 1], t[:3, 2] = x, y, np.cross(x, y)
    return t, length


def show(
    result: Any,
    model_or_scene: Any,
    vis: Any = None,
    *,
    fps: float = 30.0,
    frames: int | None = None,
    duration: float | None = None,
    trails: Any = None,
    shaking: bool = False,
    play: bool = True,
    path: str = "pointmass_dyn",
    contact: Any = None,
    contact_scale: float | None = None,
):
    """Draws ``result`` in a Meshcat ``vis`` (a new ``meshcat.Visualizer()`` if None) under
    ``path`` and sets its animation (frames, ``contact`` and ``contact_scale`` as
    :func:`pointmass_dyn.animate`); returns the visualizer. Raises :class:`~pointmass_dyn.errors.AnimationWriterError` without meshcat."""
    try:
        import meshcat
        import meshcat.animation as mc_anim
        import meshcat.geometry as g
    except ImportError as exc:
        raise AnimationWriterError(
            "the Meshcat view needs meshcat: pip install 'pointmass-dyn[meshcat]' (or write "
            "an .html animation with pmd.animate, which needs nothing)"
        ) from exc
    d = prepare(result, model_or_scene, fps=fps, frames=frames, duration=duration,
                trails=trails, shaking=shaking, contact=contact, contact_scale=contact_scale)
    if vis is None:
        vis = meshcat.Visualizer()
    root = vis[path]
    root.delete()

    def mat(key_or_rgb):
        rgb = COLOURS[key_or_rgb] if isinstance(key_or_rgb, str) else key_or_rgb
        return g.MeshLambertMaterial(color=_hex(rgb))

    for i, r in enumerate(d.sphere_radius):
        root[f"masses/{i}"].set_object(g.Sphere(float(r)), mat(d.sphere_colour[i]))
    for i in range(d.links.shape[1]):
        root[f"links/{i}"].set_object(g.Cylinder(1.0, d.link_radius), mat("link"))
    for i in range(d.axes.shape[1]):
        root[f"axes/{i}"].set_object(g.Cylinder(1.0, 0.45 * d.link_radius), mat("axis"))
    for i in range(d.cuts.shape[1]):
        root[f"cuts/{i}"].set_object(g.Sphere(1.3 * d.link_radius), mat("cut"))
    for j, colour in enumerate(d.trail_colour):
        pts = np.ascontiguousarray(d.trails[:, j].T, dtype=np.float32)
        root[f"trails/{j}/path"].set_object(
            g.Line(g.PointsGeometry(pts), g.LineBasicMaterial(color=_hex(colour))))
        root[f"trails/{j}/head"].set_object(g.Sphere(0.015 * d.size), mat(colour))
    # Point-mass boxes: rigid, set once in the link frame and moved with the link.
    for i, (lo, hi) in enumerate(d.box_corners):
        corners = box_corners(lo, hi)
        seg = np.array([corners[[a, b]] for a, b in BOX_EDGES]).reshape(-1, 3).T
        root[f"boxes/{i}"].set_object(g.LineSegments(
            g.PointsGeometry(np.ascontiguousarray(seg, dtype=np.float32)),
            g.LineBasicMaterial(color=_hex(COLOURS["box"]))))
    if d.arrow is not None:
        root["shaking"].set_object(g.Cylinder(1.0, 1.2 * d.link_radius), mat("shaking"))
    ncontact = 0 if d.contact is None else d.contact.shape[1]
    for i in range(ncontact):  # a point without force: a cylinder of length ~0
        root[f"contact/{i}"].set_object(g.Cylinder(1.0, 0.7 * d.link_radius), mat("contact"))

    def pose(k: int, transform, scale) -> None:
        """Every moving object at frame ``k``: ``transform(name, 4×4)``, ``scale(name, y)``."""
        def segment(name, a, b):
            t, length = _segment(a, b)
            transform(name, t)
            scale(name, length)

        for i in range(d.spheres.shape[1]):
            transform(f"masses/{i}", _translation(d.spheres[k, i]))
        for i in range(d.links.shape[1]):
            segment(f"links/{i}", *d.links[k, i])
        for i in range(d.axes.shape[1]):
            segment(f"axes/{i}", *d.axes[k, i])
        for i in range(d.cuts.shape[1]):
            transform(f"cuts/{i}", _translation(d.cuts[k, i, 0]))
        for j in range(d.trails.shape[1]):
            transform(f"trails/{j}/head", _translation(d.trails[k, j]))
        for i in range(d.box_pose.shape[1]):
            t = np.eye(4)
            t[:3, :3] = d.box_pose[k, i, :9].reshape(3, 3)
            t[:3, 3] = d.box_pose[k, i, 9:]
            transform(f"boxes/{i}", t)
        if d.arrow is not None:
            segment("shaking", *d.arrow[k])
        for i in range(ncontact):
            segment(f"contact/{i}", *d.contact[k, i])

    # Frame 0 as the still scene (before and without playing), then the clip.
    pose(0, lambda n, t: root[n].set_transform(t),
         lambda n, y: root[n].set_property("scale", [1.0, y, 1.0]))
    anim = mc_anim.Animation(default_framerate=fps)
    for k in range(d.nframes):
        with anim.at_frame(root, k) as f:
            pose(k, lambda n, t, f=f: f[n].set_transform(t),
                 lambda n, y, f=f: f[n].set_property("scale", "vector3", [1.0, y, 1.0]))
    vis.set_animation(anim, play=play)
    return vis
