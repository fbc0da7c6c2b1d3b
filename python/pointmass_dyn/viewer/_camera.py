"""The camera and the ground of an animation (docs/visualisation.md §4): where the page looks
from, the same matrix in Python and in ``viewer.js`` (so tests project world points to
pixels), framing the subject, following a floating base, and "up" against gravity.

A camera is a dict: ``target`` (a point), ``distance``, ``azimuth`` and ``elevation``
(degrees, about ``up``), ``fov`` (vertical, degrees), ``up`` (unit vector, −gravity), and
``track`` (F, 3) or None: the target at each frame when the camera follows the subject
(:func:`camera_at` gives frame k's camera).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InvalidInputError

#: (azimuth, elevation) in degrees for z up: the general view (matplotlib's default 3-D view),
#: and for a motion flat across x, y or z a view about 30° off that axis, so its plane is seen
#: nearly face on rather than at a grazing angle.
VIEWS = {None: (-60.0, 25.0), 0: (-20.0, 20.0), 1: (-70.0, 20.0), 2: (-60.0, 60.0)}
FOV = 35.0
#: A floating base is followed when its path is longer than this many subject sizes.
FOLLOW_RATIO = 1.0


def up_basis(up) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(e1, e2, up)``: a right-handed frame whose third axis is ``up``; ``e1`` is world x
    made orthogonal to ``up`` (world y if ``up`` is along x). z up gives x, y, z."""
    u = np.asarray(up, dtype=float)
    u = u / np.linalg.norm(u)
    ref = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = ref - (ref @ u) * u
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(u, e1), u


def up_from_gravity(g) -> np.ndarray:
    """−g normalised; z when there is no gravity."""
    g = np.zeros(3) if g is None else np.asarray(g, dtype=float)
    n = float(np.linalg.norm(g))
    return -g / n if n > 0 else np.array([0.0, 0.0, 1.0])


def _angles(extent: np.ndarray, up: np.ndarray) -> tuple[float, float]:
    flat = int(np.argmin(extent)) if extent.min() < 0.15 * extent.max() else None
    if np.allclose(up, [0, 0, 1]):
        return VIEWS[flat]
    if flat is None:
        return VIEWS[None]
    e1, e2, u = up_basis(up)
    n = np.eye(3)[flat]
    if abs(n @ u) > 0.9:  # flat across up: look down at it
        return VIEWS[2]
    # About 20° off the plane's normal, a little from above.
    return math.degrees(math.atan2(n @ e2, n @ e1)) - 20.0, 20.0


def fit(lo, hi, up=(0.0, 0.0, 1.0)) -> dict:
    """A view of the box ``[lo, hi]``: angles from :data:`VIEWS` (flat: an extent under 15 %
    of the largest), far enough that the bounding sphere fits."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    up = np.asarray(up, dtype=float)
    radius = max(float(np.linalg.norm(hi - lo)) / 2, 1e-3)
    azimuth, elevation = _angles(hi - lo, up)
    return {
        "target": ((lo + hi) / 2).tolist(),
        "distance": radius / math.sin(math.radians(FOV / 2)) * 1.05,
        "azimuth": azimuth,
        "elevation": elevation,
        "fov": FOV,
        "up": up.tolist(),
        "track": None,
    }


def choose(camera, lo_f: np.ndarray, hi_f: np.ndarray, base: np.ndarray | None,
           up: np.ndarray) -> dict:
    """The camera for per-frame boxes ``lo_f``, ``hi_f`` (F, 3) of the subject. ``camera``:
    "auto" (follow ``base`` (F, 3), a floating base's path, when it moves more than the
    subject's size, else frame the whole motion), "fixed", "follow", or a dict overriding
    any of ``target``, ``distance``, ``azimuth``, ``elevation``, ``fov``."""
    lo, hi = lo_f.min(axis=0), hi_f.max(axis=0)
    whole = fit(lo, hi, up)
    if isinstance(camera, dict):
        known = {"target", "distance", "azimuth", "elevation", "fov"}
        if not set(camera) <= known:
            raise InvalidInputError(
                f"camera: expected keys among {sorted(known)}, got {sorted(camera)}")
        out = dict(whole)
        for k, val in camera.items():
            arr = np.asarray(val, dtype=float)
            ok = arr.shape == ((3,) if k == "target" else ()) and np.all(np.isfinite(arr))
            if not ok or (k in ("distance", "fov") and not 0 < float(arr) < (
                    180 if k == "fov" else math.inf)):
                raise InvalidInputError(f"camera['{k}']: expected a finite "
                                        f"{'point (3,)' if k == 'target' else 'number'}"
                                        f"{' > 0' if k == 'distance' else ''}, got {val!r}")
            out[k] = arr.tolist() if k == "target" else float(arr)
        return out
    if camera not in ("auto", "fixed", "follow"):
        raise InvalidInputError(
            f"camera: expected 'auto', 'fixed', 'follow' or a dict, got {camera!r}")
    if camera == "fixed" or base is None:
        return whole
    size = float(np.max(np.linalg.norm(hi_f - lo_f, axis=1)))
    travel = float(np.linalg.norm(base.max(axis=0) - base.min(axis=0)))
    if camera == "auto" and travel <= FOLLOW_RATIO * max(size, 1e-9):
        return whole
    # Follow: frame 0's box, the largest box of any frame, moved with the base.
    k = int(np.argmax(np.linalg.norm(hi_f - lo_f, axis=1)))
    cam = fit(lo_f[k] - base[k], hi_f[k] - base[k], up)
    cam["track"] = (base + np.asarray(cam["target"])).tolist()
    cam["target"] = cam["track"][0]
    return cam


def camera_at(camera: dict, frame: int) -> dict:
    """The camera at ``frame`` (its ``track`` target when it follows)."""
    if camera.get("track") is None:
        return camera
    return {**camera, "target": camera["track"][frame]}


def view_projection(camera: dict, aspect: float) -> np.ndarray:
    """The page's 4×4 world → clip matrix (column vectors): a perspective of vertical field
    of view ``fov`` looking at ``target`` from ``distance`` along azimuth/elevation (degrees,
    about ``up``, z if absent). The page computes the same matrix (``viewProj`` in
    viewer.js)."""
    az, el = math.radians(camera["azimuth"]), math.radians(camera["elevation"])
    d = camera["distance"]
    e1, e2, up = up_basis(camera.get("up", (0.0, 0.0, 1.0)))
    target = np.asarray(camera["target"], dtype=float)
    eye = target + d * (math.cos(el) * math.cos(az) * e1 + math.cos(el) * math.sin(az) * e2
                        + math.sin(el) * up)
    f = target - eye
    f /= np.linalg.norm(f)
    s = np.cross(f, up)
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


def project(camera: dict, width: int, height: int, points, frame: int = 0) -> np.ndarray:
    """Pixel coordinates (x right, y down) of world ``points`` (..., 3) in a page of
    ``width × height`` CSS pixels at the camera of ``frame``."""
    p = np.asarray(points, dtype=float)
    h = np.concatenate([p, np.ones(p.shape[:-1] + (1,))], axis=-1)
    c = h @ view_projection(camera_at(camera, frame), width / height).T
    ndc = c[..., :3] / c[..., 3:4]
    return np.stack([(ndc[..., 0] + 1) / 2 * width, (1 - ndc[..., 1]) / 2 * height], axis=-1)


def ground(lo, hi, up) -> dict:
    """A square grid in the plane ⟂ ``up`` just below the box ``[lo, hi]``, centred under it,
    spacing 1, 2 or 5 × 10^k: ``origin`` (its centre), axes ``u``, ``v``, ``half``, ``step``."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    size = max(float(np.linalg.norm(hi - lo)), 1e-3)
    e1, e2, u = up_basis(up)
    corners = np.array([[(hi if c >> k & 1 else lo)[k] for k in range(3)] for c in range(8)])
    low = float((corners @ u).min()) - 0.02 * size
    raw = size / 8
    step = min((f * 10 ** math.floor(math.log10(raw)) for f in (1, 2, 5, 10)),
               key=lambda x: abs(math.log(x / raw)))
    half = step * math.ceil(size / step / 2)
    centre = (lo + hi) / 2
    a, b = (round(float(centre @ e) / step) * step for e in (e1, e2))
    return {"origin": (a * e1 + b * e2 + low * u).tolist(), "u": e1.tolist(), "v": e2.tolist(),
            "half": half, "step": step}


#: The most grid lines a plane's square has each way (a long walk widens the square, not the
#: line count).
MAX_GRID_LINES = 200


def plane_grid(lo, hi, normal, height: float, size: float) -> dict:
    """A square grid on the plane ``normal · x = height`` (``normal`` unit) under the box
    ``[lo, hi]``: centred at the box centre's projection onto the plane, covering the box's
    shadow along the normal with a margin; spacing 1, 2 or 5 × 10^k of about ``size`` / 8
    (the subject's size), coarser when the square would need more than
    :data:`MAX_GRID_LINES` lines. Same keys as :func:`ground`, with ``point`` (the plane's
    point nearest the world origin, ``height · normal``) and ``normal``."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    e1, e2, n = up_basis(normal)
    corners = np.array([[(hi if c >> k & 1 else lo)[k] for k in range(3)] for c in range(8)])
    shadow = np.stack([corners @ e1, corners @ e2], axis=1)
    raw = max(float(size), 1e-3) / 8
    step = min((f * 10 ** math.floor(math.log10(raw)) for f in (1, 2, 5, 10)),
               key=lambda x: abs(math.log(x / raw)))
    reach = float(np.max(shadow.max(axis=0) - shadow.min(axis=0))) / 2 + 2 * raw
    while 2 * reach / step > MAX_GRID_LINES:
        step *= 10
    half = step * math.ceil(reach / step)
    a, b = (round(float(c) / step) * step for c in (shadow.max(axis=0) + shadow.min(axis=0)) / 2)
    return {"origin": (a * e1 + b * e2 + height * n).tolist(), "u": e1.tolist(),
            "v": e2.tolist(), "half": half, "step": step, "point": (height * n).tolist(),
            "normal": n.tolist()}
