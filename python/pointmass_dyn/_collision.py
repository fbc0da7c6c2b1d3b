"""Bounding boxes of a URDF link's geometry, for the contact spheres of
:func:`pointmass_dyn.urdf_contact_points` (docs/contact.md §1).

A ``<collision>`` or ``<visual>`` element's ``<box>``, ``<cylinder>`` or ``<mesh>`` is bounded
in its link's frame (its ``<origin>`` and a mesh's ``scale`` applied). Mesh files: STL
(binary and ASCII) and OBJ are read here with NumPy alone; any other format (COLLADA
``.dae``, PLY, ...) needs trimesh, the optional extra ``pip install "pointmass-dyn[mesh]"``,
and without it the element counts as unreadable, saying so.
"""

from __future__ import annotations

import importlib.util
import os
import xml.etree.ElementTree as ET

import numpy as np

from . import _core

#: Mesh files larger than this are not read for their bounds.
MAX_MESH_BYTES = 256 * 1024 * 1024

_EXTRA = 'pip install "pointmass-dyn[mesh]"'


class GeometryUnreadable(Exception):
    """An element whose bounds cannot be had (a mesh file missing, unreadable or needing the
    extra); the message says why (internal: a warning of ``urdf_contact_points``)."""


class MalformedGeometry(Exception):
    """An element whose numbers are not what URDF says (internal: an
    ``InvalidInputError`` of ``urdf_contact_points``, naming the link)."""


def rpy_matrix(rpy) -> np.ndarray:
    """URDF's fixed-axis roll, pitch, yaw: ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ])


def _numbers(text: str | None, n: int, what: str, low: float = -np.inf) -> np.ndarray:
    try:
        x = np.array([float(v) for v in (text or "").split()])
    except ValueError:
        x = np.array([])
    if x.shape != (n,) or not np.all(np.isfinite(x)) or np.any(x < low):
        at_least = f" >= {low:g}" if low > -np.inf else ""
        raise MalformedGeometry(f"{what}: expected {n} finite numbers{at_least}, got {text!r}")
    return x


def _origin(elem: ET.Element) -> tuple[np.ndarray, np.ndarray]:
    origin = elem.find("origin")
    if origin is None:
        return np.eye(3), np.zeros(3)
    xyz = _numbers(origin.get("xyz", "0 0 0"), 3, "<origin xyz>")
    rpy = _numbers(origin.get("rpy", "0 0 0"), 3, "<origin rpy>")
    return rpy_matrix(rpy), xyz


def _stl_vertices(path: str, size: int) -> np.ndarray:
    with open(path, "rb") as fh:
        head = fh.read(84)
        n = int(np.frombuffer(head, dtype="<u4", count=1, offset=80)[0]) if len(head) == 84 else 0
        # Binary files may begin with "solid" too: their size tells them apart.
        if not (head[:5].lower() == b"solid" and 84 + 50 * n != size):
            if len(head) < 84 or 84 + 50 * n > size:
                raise GeometryUnreadable(f"a truncated binary STL ({size} bytes)")
            rec = np.fromfile(fh, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)),
                                                  ("a", "<u2")]), count=n)
            return rec["v"].reshape(-1, 3).astype(float)
    return _text_vertices(path, b"vertex", 1)


def _text_vertices(path: str, key: bytes, skip: int) -> np.ndarray:
    """The three numbers after ``key`` on each line that starts with it (ASCII STL's
    ``vertex x y z``, OBJ's ``v x y z``)."""
    rows = []
    with open(path, "rb") as fh:
        for line in fh:
            words = line.split()
            if words and words[0] == key:
                try:
                    rows.append([float(w) for w in words[skip:skip + 3]])
                except ValueError:
                    raise GeometryUnreadable(f"a malformed line {line[:60]!r}") from None
    if not rows or any(len(r) != 3 for r in rows):
        raise GeometryUnreadable(f"no '{key.decode()} x y z' vertices in it")
    return np.array(rows, dtype=float)


def _trimesh_vertices(path: str, ext: str) -> np.ndarray:
    if importlib.util.find_spec("trimesh") is None:
        raise GeometryUnreadable(
            f"reading '.{ext}' meshes needs trimesh, the optional extra: {_EXTRA} "
            "(STL and OBJ need nothing)"
        )
    import trimesh

    try:
        loaded = trimesh.load(path)
    except Exception as exc:  # readers raise anything on a corrupt file or missing reader
        raise GeometryUnreadable(f"unreadable ({type(exc).__name__}: {exc})"[:300]) from exc
    # A scene's geometries placed by its node transforms (COLLADA's), as they are drawn.
    geoms = loaded.dump() if isinstance(loaded, trimesh.Scene) else [loaded]
    verts = [np.asarray(g.vertices, dtype=float) for g in geoms if hasattr(g, "vertices")]
    if not verts or not sum(len(v) for v in verts):
        raise GeometryUnreadable("no vertices in it")
    return np.concatenate(verts)


def mesh_vertices(path: str) -> np.ndarray:
    """The vertices (n, 3) of a mesh file, in its own frame and units."""
    try:
        size = os.stat(path).st_size
    except OSError as exc:
        raise GeometryUnreadable(f"cannot be read ({exc.strerror})") from exc
    if size > MAX_MESH_BYTES:
        raise GeometryUnreadable(f"{size} bytes, more than the {MAX_MESH_BYTES} read for bounds")
    ext = os.path.splitext(path)[1].lower().lstrip(".")
    try:
        if ext == "stl":
            v = _stl_vertices(path, size)
        elif ext == "obj":
            v = _text_vertices(path, b"v", 1)
        else:
            v = _trimesh_vertices(path, ext)
    except OSError as exc:
        raise GeometryUnreadable(f"cannot be read ({exc.strerror})") from exc
    v = v[np.all(np.isfinite(v), axis=1)]
    if not len(v):
        raise GeometryUnreadable("no finite vertices in it")
    return v


def element_bounds(
    elem: ET.Element, base_dir: str, package_dirs
) -> tuple[np.ndarray, np.ndarray] | None:
    """``(lo, hi)`` of a ``<collision>``/``<visual>`` element's geometry in its link's frame;
    None for an element without geometry; :class:`GeometryUnreadable` (naming the file or
    the shape) when it has one that cannot be bounded, :class:`MalformedGeometry` when its
    numbers are not URDF's."""
    geometry = elem.find("geometry")
    shape = None if geometry is None else next(iter(geometry), None)
    if shape is None:
        return None
    rot, xyz = _origin(elem)
    if shape.tag == "box":
        half = _numbers(shape.get("size"), 3, "<box size>", 0.0) / 2
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        pts = (corners * half) @ rot.T + xyz
        return pts.min(axis=0), pts.max(axis=0)
    if shape.tag in ("cylinder", "sphere"):
        r = float(_numbers(shape.get("radius"), 1, f"<{shape.tag} radius>", 0.0)[0])
        if shape.tag == "sphere":
            return xyz - r, xyz + r
        half = float(_numbers(shape.get("length"), 1, "<cylinder length>", 0.0)[0]) / 2
        axis = rot[:, 2]
        # A disc of radius r about `axis` spans r·sqrt(1 − a_i²) along world axis i.
        ext = abs(half * axis) + r * np.sqrt(np.clip(1 - axis**2, 0.0, 1.0))
        return xyz - ext, xyz + ext
    if shape.tag == "mesh":
        uri = shape.get("filename") or ""
        path = _core.resolve_mesh(uri, base_dir, package_dirs)
        if path is None:
            raise GeometryUnreadable(f"mesh '{uri}': no such file")
        scale = shape.get("scale")
        scale = np.ones(3) if scale is None else _numbers(scale, 3, f"mesh '{uri}' scale")
        try:
            v = mesh_vertices(os.fspath(path))
        except GeometryUnreadable as exc:
            raise GeometryUnreadable(f"mesh {os.fspath(path)}: {exc}") from None
        pts = (v * scale) @ rot.T + xyz
        return pts.min(axis=0), pts.max(axis=0)
    raise GeometryUnreadable(f"<{shape.tag}>: a shape not bounded here")


def link_sphere(
    link: ET.Element, base_dir: str, package_dirs
) -> tuple[list[float], float] | None | str:
    """The contact sphere of a link without collision spheres: centre ``[x, y, z]`` and
    radius from the bounding box of its ``<collision>`` geometry (else its ``<visual>``):
    the box's centre, half its smallest side (the largest sphere inside the box). None when
    the link has no geometry; the reason (a str) when it has some and none can be bounded;
    :class:`MalformedGeometry` for numbers that are not URDF's."""
    reasons = []
    for tag in ("collision", "visual"):
        boxes = []
        try:
            for elem in link.findall(tag):
                b = element_bounds(elem, base_dir, package_dirs)
                if b is not None:
                    boxes.append(b)
        except GeometryUnreadable as exc:
            reasons.append(f"<{tag}> {exc}")
            continue
        if boxes:
            lo = np.min([b[0] for b in boxes], axis=0)
            hi = np.max([b[1] for b in boxes], axis=0)
            return [float(x) for x in (lo + hi) / 2], float(np.min(hi - lo) / 2)
    return "; ".join(reasons) if reasons else None
