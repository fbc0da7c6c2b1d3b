"""Animation of a result (docs/visualisation.md): :func:`animate` samples a trajectory at a
frame rate, asks the model for the world poses of everything drawn (``Model.body_poses``,
batched over all frames; :mod:`._drawing`) and hands the :class:`Drawing` to a writer: the
self-contained WebGL page (:mod:`._html`) or matplotlib's animation writers (:mod:`._video`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import _core
from .._contact import contact_forces
from .._helpers import quaternion_slices, scene_gravity
from ..design import shaking as shaking_of
from ..errors import InvalidInputError
from ._drawing import Drawing, build_drawing
from ._html import page
from ._video import write_video


@dataclass(repr=False)
class AnimationInfo:
    """What :func:`animate` made: the file (None: nothing written), its frame count and
    times, the frame size in pixels, the initial camera (see
    :func:`~pointmass_dyn.viewer.view_projection`; ``camera_at`` for a following camera),
    the size in bytes, how many triangles the robot's shapes have, for a page its HTML,
    which a notebook shows inline, and the contact-force arrows' scale (m/N) if drawn."""

    path: Path | None
    frames: int
    times: np.ndarray
    size: tuple[int, int]
    camera: dict
    bytes: int
    triangles: int = 0
    html: str | None = field(default=None, repr=False)
    #: Metres of contact-force arrow per newton; None when no contact force is drawn.
    contact_scale: float | None = None

    def _repr_html_(self) -> str | None:
        """The page in an ``<iframe srcdoc>``: self-contained (no server, no network), so it
        works in Jupyter, JupyterLab, VS Code and Colab, offline; None for a GIF/MP4."""
        if self.html is None:
            return None
        import html as _html

        return (f'<iframe srcdoc="{_html.escape(self.html, quote=True)}" '
                f'style="width:100%;height:{self.size[1]}px;border:0" '
                'sandbox="allow-scripts" title="pointmass_dyn animation"></iframe>')

    def __repr__(self) -> str:
        # A summary: ``times`` holds one entry per frame.
        t = np.asarray(self.times)
        span = f"[{t[0]:g}, {t[-1]:g}] s" if t.size else "[]"
        return (
            f"AnimationInfo(path={str(self.path)!r}, frames={self.frames}, times={span}, "
            f"size={tuple(self.size)}, bytes={self.bytes})"
        )


# ---------------------------------------------------------------- sampling


#: The most frames an animation may have: an hour at 30 fps. Each frame costs every body's
#: pose in the page (or an image in a video), so more is a memory bomb, not a longer film.
MAX_FRAMES = 108_000


def frame_times(t: np.ndarray, fps: float, frames: int | None, duration: float | None):
    """Frame times: ``frames`` of them, or ``round(duration·fps)`` over the result (playback
    as long as the motion unless ``duration`` says otherwise), endpoints included; at most
    :data:`MAX_FRAMES`, else an :class:`InvalidInputError` saying which arguments ask more."""
    t0, t1 = float(t[0]), float(t[-1])
    if frames is None:
        span = (t1 - t0) if duration is None else duration
        wanted = span * fps
        if not wanted <= MAX_FRAMES:
            raise InvalidInputError(
                f"fps, duration: expected at most {MAX_FRAMES} frames (duration × fps), got "
                f"{span:g} s × {fps:g} fps = {wanted:.3g} frames"
            )
        frames = max(1, int(round(wanted)))
    elif frames > MAX_FRAMES:
        raise InvalidInputError(f"frames: expected at most {MAX_FRAMES}, got {frames}")
    return np.linspace(t0, t1, frames) if frames > 1 else np.array([t0])


def sample(t, x, times, quaternions=()) -> np.ndarray:
    """``x`` (N, n) at ``times`` by linear interpolation in each interval; quaternion slices
    are taken on the same hemisphere as their left sample, then renormalised."""
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if len(t) == 1:
        return np.repeat(x[:1], len(times), axis=0)
    i = np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(t) - 2)
    h = t[i + 1] - t[i]
    w = np.where(h > 0, (times - t[i]) / np.where(h > 0, h, 1.0), 0.0)[:, None]
    left, right = x[i], x[i + 1].copy()
    for s in quaternions:
        flip = np.sum(left[:, s] * right[:, s], axis=1) < 0
        right[flip, s] *= -1.0
    out = (1.0 - w) * left + w * right
    for s in quaternions:
        out[:, s] /= np.linalg.norm(out[:, s], axis=1, keepdims=True)
    return out


# ---------------------------------------------------------------- entry point


def _trajectory(result) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    if hasattr(result, "t") and hasattr(result, "q"):
        t, q, v = result.t, result.q, getattr(result, "v", None)
    elif isinstance(result, (tuple, list)) and len(result) in (2, 3):
        t, q = result[0], result[1]
        v = result[2] if len(result) == 3 else None
    else:
        raise InvalidInputError(
            "result: expected a SimulationResult (or anything with .t and .q) or a tuple "
            f"(t, q[, v]), got {type(result).__name__}"
        )
    t = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    if t.ndim != 1 or len(t) == 0 or q.ndim != 2 or q.shape[0] != len(t):
        raise InvalidInputError(
            f"result: expected t (N,) and q (N, nq) with N >= 1, got t {t.shape} and q {q.shape}"
        )
    if not (np.all(np.isfinite(t)) and np.all(np.diff(t) >= 0)):
        raise InvalidInputError("result.t: expected finite, non-decreasing times")
    return t, q, (None if v is None else np.asarray(v, dtype=float))


def prepare(
    result: Any,
    model_or_scene: Any,
    *,
    fps: float = 30.0,
    frames: int | None = None,
    duration: float | None = None,
    trails: Any = None,
    shaking: bool = False,
    title: str | None = None,
    camera: Any = "auto",
    show=None,
    triangles: int | None = None,
    contact: Any = None,
    contact_scale: float | None = None,
) -> Drawing:
    """The :class:`Drawing` :func:`animate` writes (same arguments)."""
    scene = model_or_scene if isinstance(model_or_scene, _core.Scene) else None
    model = scene.model if scene is not None else model_or_scene
    if not isinstance(model, _core.Model):
        # simulate takes the scene first, animate the result first: say so when swapped.
        swapped = (" (the arguments are (result, model_or_scene, path): the result first, "
                   "as it came from simulate)"
                   if isinstance(result, (_core.Scene, _core.Model)) else "")
        raise InvalidInputError(
            f"model_or_scene: expected a Model or a Scene, got "
            f"{type(model_or_scene).__name__}{swapped}"
        )
    for name, val in (("fps", fps), ("duration", duration)):
        if val is not None and not (isinstance(val, (int, float)) and math.isfinite(val)
                                    and val > 0):
            raise InvalidInputError(f"{name}: expected a positive number, got {val!r}")
    if frames is not None and not (isinstance(frames, (int, np.integer)) and frames >= 1):
        raise InvalidInputError(f"frames: expected an integer >= 1, got {frames!r}")
    t, q, v = _trajectory(result)
    if q.shape[1] != model.nq:
        raise InvalidInputError(
            f"result.q: expected (N, {model.nq}) for this model, got {q.shape}"
        )
    times = frame_times(t, fps, frames, duration)
    qf = sample(t, q, times, quaternion_slices(model))
    force = None
    if shaking:
        if scene is None:
            raise InvalidInputError(
                "shaking: needs the Scene the result came from (its effects give the "
                "accelerations), got a Model"
            )
        if v is None:
            raise InvalidInputError("shaking: needs the result's speeds v, got none")
        force = np.asarray(shaking_of(scene, _Sampled(times, qf, sample(t, v, times))).force)
    arrows = _contact(result, scene, contact, t, times, qf, v)
    if contact_scale is not None and not (
            isinstance(contact_scale, (int, float, np.floating)) and not isinstance(
                contact_scale, bool) and math.isfinite(contact_scale) and contact_scale > 0):
        raise InvalidInputError(
            f"contact_scale: expected None or a positive number (metres per newton), "
            f"got {contact_scale!r}")
    if triangles is not None and not (isinstance(triangles, (int, np.integer))
                                      and 0 <= triangles <= 10_000_000):
        raise InvalidInputError(f"triangles: expected an integer 0..10000000, got {triangles!r}")
    if title is None:
        title = default_title(scene, model)
    return build_drawing(model, times, qf, trails=trails, shaking=force, title=title,
                         gravity=None if scene is None else scene_gravity(scene),
                         camera=camera, show=show, triangles=triangles, contact=arrows,
                         contact_scale=contact_scale, planes=contact_planes(scene))


#: The name a Scene built without one gets: it names nothing, so a page says the robot's.
DEFAULT_SCENE_NAME = "scene"


def default_title(scene, model) -> str:
    """The scene's name, or the model's (a URDF's robot name) when the scene has none of its
    own (or there is no scene), else "pointmass_dyn"."""
    if scene is not None and scene.name and scene.name != DEFAULT_SCENE_NAME:
        return scene.name
    return model.name or "pointmass_dyn"


def contact_planes(scene) -> list[tuple[str, np.ndarray, float]]:
    """``(name, unit normal, height)`` of each ground contact ``scene`` (a Scene or None)
    feels: the planes ``normal · x = height`` the page draws."""
    if not has_contact(scene):
        return []
    return [(e.name, *e.plane) for e in scene.effects if e.kind == "contact"]


def has_contact(scene) -> bool:
    """Whether ``scene`` (a Scene or None) has a ground contact its runs feel (not switched
    off by ``[simulate] disable``)."""
    if not isinstance(scene, _core.Scene) or "contact" in (scene.disable or ()):
        return False
    return any(e.kind == "contact" for e in scene.effects)


def _contact(result, scene, contact, t, times, qf, v):
    """The contact points and forces ``(position, force)`` (F, K, 3) at the frame times, or
    None. ``contact``: None draws the result's ``.contact`` (``simulate(..., contact=True)``)
    when it has some; False nothing; True the result's, else the scene's ground contacts
    evaluated at the frames' states; or a dict of :class:`~pointmass_dyn.ContactForces`
    (anything with ``position`` and ``force`` (N, P, 3)) at the result's times."""
    if contact is False:
        return None
    data = contact if isinstance(contact, dict) else getattr(result, "contact", None)
    if contact is not None and not isinstance(contact, (bool, dict)):
        raise InvalidInputError(
            "contact: expected None (draw the result's contact forces if it has any), True, "
            f"False or a dict of ContactForces, got {type(contact).__name__}")
    if data:
        pos, force = [], []
        for name, c in data.items():
            p = np.asarray(getattr(c, "position", None), dtype=float)
            f = np.asarray(getattr(c, "force", None), dtype=float)
            if (p.ndim != 3 or p.shape[0] != len(t) or p.shape[2] != 3 or f.shape != p.shape
                    or not (np.all(np.isfinite(p)) and np.all(np.isfinite(f)))):
                raise InvalidInputError(
                    f"contact['{name}']: expected finite position and force of shape "
                    f"({len(t)}, P, 3) (one row per result time), got {p.shape} and {f.shape}")
            pos.append(p)
            force.append(f)
        pos, force = np.concatenate(pos, axis=1), np.concatenate(force, axis=1)
        n = pos.shape[1]
        both = sample(t, np.concatenate([pos, force], axis=1).reshape(len(t), -1), times)
        both = both.reshape(len(times), 2 * n, 3)
        return both[:, :n], both[:, n:]
    if contact is not True:
        return None
    if not has_contact(scene) or v is None:
        raise InvalidInputError(
            "contact: True needs contact forces on the result (simulate(..., contact=True)) "
            "or the Scene with a ground contact (not disabled) and the result's speeds v, got "
            f"{'a Model' if scene is None else 'a Scene'} and a result without them")
    frames = contact_forces(scene, _Sampled(times, qf, sample(t, v, times)))
    return (np.concatenate([c.position for c in frames.values()], axis=1),
            np.concatenate([c.force for c in frames.values()], axis=1))


def animate(
    result: Any,
    model_or_scene: Any,
    path: str | os.PathLike | None = None,
    *,
    fps: float = 30.0,
    frames: int | None = None,
    duration: float | None = None,
    size: tuple[int, int] = (640, 480),
    trails: Any = None,
    shaking: bool = False,
    title: str | None = None,
    dpi: int = 100,
    camera: Any = "auto",
    show: Any = None,
    triangles: int | None = None,
    contact: Any = None,
    contact_scale: float | None = None,
) -> AnimationInfo:
    """Writes an animation of ``result`` to ``path``: ``.html`` (one self-contained WebGL
    page, works offline: play/pause, scrub, orbit/zoom, layer toggles), ``.gif`` (Pillow) or
    ``.mp4`` (ffmpeg), the last two with matplotlib. ``path=None`` writes nothing: the
    returned object holds the page and shows it inline in a notebook (``_repr_html_``).

    ``result``: a :class:`SimulationResult` or ``(t, q[, v])``. ``model_or_scene``: the
    :class:`Model` or the :class:`Scene` it came from (a scene is needed for ``shaking``,
    and gives gravity, hence "up" and the ground's plane). The trajectory is sampled at
    ``fps``: ``frames`` frames if given, else ``round(duration·fps)``, ``duration`` being
    the result's time span unless given, so a long result costs only its frames. ``size``:
    GIF/MP4 frame size in pixels (width, height); the page fills its window (inline: that
    height). ``trails``: points whose path is drawn — body names/indices (their origin) or
    ``(body, point_in_body[, colour])``. ``shaking``: draw the shaking force ``−Σ m a``
    (docs/balancing.md) as an arrow at the world origin. ``camera``: "auto" (frame the
    subject over the motion; follow a floating base that travels farther than its size),
    "fixed", "follow" or a dict of ``target``, ``distance``, ``azimuth``, ``elevation``,
    ``fov``. ``show``: the layers shown at first (``LAYERS``: "robot", "masses", "links",
    "axes", "frames", "forces"). ``triangles``: the most triangles the robot's shapes are
    drawn with, every instance of a mesh and the unsimplified primitives counted (default
    60,000; a :class:`~pointmass_dyn.errors.VisualWarning` when they cannot be simplified
    that far). ``contact``: ground-contact forces as arrows at their
    points, in the "forces" layer: None (default) draws them when ``result`` carries them
    (``simulate(..., contact=True)``), False never, True also computes them from the
    Scene's ground contacts; a point without force draws nothing. ``contact_scale``: metres
    of arrow per newton (default: the largest force is 25 % of the scene's size; the scale
    used is ``AnimationInfo.contact_scale``). Returns :class:`AnimationInfo`. Raises
    :class:`~pointmass_dyn.errors.AnimationWriterError` for a format this machine cannot
    write (MP4 without ffmpeg); a mesh that cannot be drawn is a
    :class:`~pointmass_dyn.errors.VisualWarning`."""
    kind = ".html" if path is None else Path(path).suffix.lower()
    if kind not in (".html", ".gif", ".mp4"):
        raise InvalidInputError(
            f"path: expected None or a file name ending in .html, .gif or .mp4, got '{path}'"
        )
    if not (isinstance(size, (tuple, list)) and len(size) == 2
            and all(isinstance(s, (int, np.integer)) and 16 <= s <= 8192 for s in size)):
        raise InvalidInputError(
            f"size: expected (width, height) in pixels, integers 16..8192, got {size!r}"
        )
    if not (isinstance(dpi, (int, np.integer)) and 10 <= dpi <= 1000):
        raise InvalidInputError(f"dpi: expected an integer 10..1000, got {dpi!r}")
    if path is not None and not Path(path).parent.is_dir():
        raise InvalidInputError(
            f"path: expected a file in an existing directory, got '{path}' "
            f"('{Path(path).parent}' does not exist or is not a directory)"
        )
    drawing = prepare(result, model_or_scene, fps=fps, frames=frames, duration=duration,
                      trails=trails, shaking=shaking, title=title, camera=camera, show=show,
                      triangles=triangles, contact=contact, contact_scale=contact_scale)
    width, height = int(size[0]), int(size[1])
    html = None
    if kind == ".html":
        html = page(drawing, fps)
        if path is not None:
            Path(path).write_text(html, encoding="utf-8")
    else:
        write_video(drawing, Path(path), fps=fps, size=(width, height), dpi=int(dpi))
    nbytes = len(html.encode()) if path is None else Path(path).stat().st_size
    return AnimationInfo(path=None if path is None else Path(path), frames=drawing.nframes,
                         times=drawing.times, size=(width, height), camera=drawing.camera,
                         bytes=nbytes, triangles=drawing.triangles, html=html,
                         contact_scale=drawing.contact_scale if drawing.contact is not None
                         else None)


@dataclass
class _Sampled:
    """A result resampled at the frame times (what :func:`pointmass_dyn.shaking` reads)."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
