"""Triangles of a model's visual geometry (``Model.visuals``) for the viewers
(docs/visualisation.md §1).

Mesh files are read with trimesh (STL, OBJ, PLY, ...; COLLADA ``.dae`` through pycollada),
the optional extra ``pip install "pointmass-dyn[mesh]"``, and simplified with
fast-simplification to a triangle budget shared by the model's meshes, so a page stays a few
MB. Boxes, cylinders, spheres, capsules and ellipsoids are triangulated here. A file that is
missing, unreadable, of an unknown format or too large is left out with one
:class:`~pointmass_dyn.errors.VisualWarning` naming every such file, and its body is drawn as
the box of its inertia (same mass and principal moments, uniform density).

Simplified meshes are kept in memory and on disk (``~/.cache/pointmass_dyn/meshes``, or
``$PMD_MESH_CACHE``; ``PMD_MESH_CACHE=0`` turns that off), keyed by path, modification time,
size, scale and budget, so animating the same robot again does not read its files again.
"""

from __future__ import annotations

import hashlib
import os
import stat
import warnings
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import VisualWarning

#: Files larger than this are not read (a mesh for display is rarely over a few MB).
MAX_MESH_BYTES = 256 * 1024 * 1024
#: Meshes above this many triangles before simplification are refused (memory).
MAX_MESH_TRIANGLES = 20_000_000
#: Default triangle budget of a model's shapes: every triangle drawn, each instance of a mesh
#: counted (Go2's four legs share their files), primitives and inertia boxes included.
DEFAULT_TRIANGLES = 60_000
#: A simplified mesh keeps at least this many triangles (or all it has) while the budget
#: allows (a smaller budget shares itself in proportion, down to a few triangles each).
MIN_TRIANGLES = 120
#: Colour of shapes without one (URDF without <material>, STL files).
DEFAULT_RGBA = (0.72, 0.74, 0.78, 1.0)
#: Colour of the inertia boxes that stand in for meshes that could not be drawn.
FALLBACK_RGBA = (0.85, 0.60, 0.35, 1.0)


class MeshReadError(Exception):
    """A mesh file that cannot be drawn; the message says why (internal: turned into a
    :class:`VisualWarning`)."""


@dataclass
class Mesh:
    """Triangles in the shape's frame: ``vertices`` (n, 3) float32, ``faces`` (m, 3) int
    indices, and ``parts``: (first face, face count, rgb or None) in face order."""

    vertices: np.ndarray
    faces: np.ndarray
    parts: list = field(default_factory=list)

    @property
    def ntriangles(self) -> int:
        return len(self.faces)


@dataclass
class Instance:
    """One drawn shape: ``mesh`` (index into :attr:`VisualScene.meshes`) on ``body``, placed
    by ``pose`` (3, 4: rotation | translation, in the body frame), coloured ``rgba`` (None:
    the mesh's part colours) ; ``fallback`` marks an inertia box standing in for a mesh."""

    body: int
    mesh: int
    pose: np.ndarray
    rgba: tuple | None
    fallback: bool = False


@dataclass
class VisualScene:
    """The model's visuals as triangles: unique meshes and their instances."""

    meshes: list
    instances: list
    #: Files that could not be drawn, with the reason (already warned about).
    failed: dict

    @property
    def triangles(self) -> int:
        return sum(self.meshes[i.mesh].ntriangles for i in self.instances)


# ---------------------------------------------------------------- primitives


def _cylinder(radius: float, length: float, n: int = 24) -> Mesh:
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.stack([radius * np.cos(a), radius * np.sin(a), np.zeros(n)], axis=1)
    lo, hi = ring - [0, 0, length / 2], ring + [0, 0, length / 2]
    verts = np.concatenate([lo, hi, [[0, 0, -length / 2], [0, 0, length / 2]]])
    i = np.arange(n)
    j = (i + 1) % n
    side = np.concatenate([np.stack([i, j, n + j], 1), np.stack([i, n + j, n + i], 1)])
    caps = np.concatenate([np.stack([np.full(n, 2 * n), j, i], 1),
                           np.stack([np.full(n, 2 * n + 1), n + i, n + j], 1)])
    return Mesh(verts.astype(np.float32), np.concatenate([side, caps]))


def _sphere(radii, nu: int = 24, nv: int = 12, stretch: float = 0.0) -> Mesh:
    """An ellipsoid of semi-axes ``radii``; ``stretch`` moves the two halves apart along z
    (a capsule's cylinder length)."""
    th = np.linspace(0, np.pi, nv + 1)
    ph = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    t, p = np.meshgrid(th, ph, indexing="ij")
    v = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1).reshape(-1, 3)
    v = v * np.asarray(radii, dtype=float)
    v[:, 2] += np.where(v[:, 2] >= 0, stretch / 2, -stretch / 2)
    k = np.arange(nv)[:, None] * nu
    i = np.arange(nu)[None, :]
    j = (i + 1) % nu
    a, b, c, d = k + i, k + j, k + nu + j, k + nu + i
    faces = np.concatenate([np.stack([a, d, c], -1).reshape(-1, 3),
                            np.stack([a, c, b], -1).reshape(-1, 3)])
    # Drop the degenerate triangles at the poles.
    area = np.linalg.norm(np.cross(v[faces[:, 1]] - v[faces[:, 0]],
                                   v[faces[:, 2]] - v[faces[:, 0]]), axis=1)
    return Mesh(v.astype(np.float32), faces[area > 1e-12 * max(radii) ** 2])


def _box(size) -> Mesh:
    h = np.asarray(size, dtype=float) / 2
    corners = np.array([[(-1) ** (1 + (c >> k & 1)) for k in range(3)] for c in range(8)]) * h
    quads = [(0, 2, 6, 4), (1, 5, 7, 3), (0, 4, 5, 1), (2, 3, 7, 6), (0, 1, 3, 2), (4, 6, 7, 5)]
    faces = [f for q in quads for f in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))]
    return Mesh(corners.astype(np.float32), np.array(faces))


def primitive(visual: dict) -> Mesh:
    """Triangles of a box, cylinder, sphere, capsule or ellipsoid visual (dict as in
    ``Model.visuals``)."""
    kind = visual["kind"]
    if kind == "box":
        return _box(visual["size"])
    if kind == "cylinder":
        return _cylinder(visual["radius"], visual["length"])
    if kind == "sphere":
        r = visual["radius"]
        return _sphere((r, r, r))
    if kind == "capsule":
        r = visual["radius"]
        return _sphere((r, r, r), stretch=visual["length"])
    if kind == "ellipsoid":
        return _sphere(visual["radii"])
    raise ValueError(f"not a primitive: {kind}")


def inertia_box(body) -> tuple[Mesh, np.ndarray] | None:
    """The uniform box of the body's mass and principal moments, and its pose (3, 4) in the
    body frame (at the COM, principal axes); None for a massless body."""
    m = float(body.mass)
    if not m > 0:
        return None
    ic = np.asarray(body.inertia, dtype=float)  # about the COM
    com = np.asarray(body.com, dtype=float)
    moments, axes = np.linalg.eigh((ic + ic.T) / 2)
    # Box of sides a: I_x = m (a_y² + a_z²) / 12.
    sq = 6.0 / m * (moments.sum() - 2 * moments)
    sides = np.sqrt(np.maximum(sq, 0.0))
    sides = np.maximum(sides, 0.05 * max(sides.max(), 1e-3))
    if np.linalg.det(axes) < 0:
        axes[:, 2] *= -1
    return _box(sides), np.concatenate([axes, com[:, None]], axis=1)


# ---------------------------------------------------------------- files


def _has_trimesh() -> bool:
    import importlib.util

    return importlib.util.find_spec("trimesh") is not None


def _trimesh():
    try:
        import trimesh
    except ImportError as exc:
        raise MeshReadError(
            'the mesh readers are not installed (pip install "pointmass-dyn[mesh]")'
        ) from exc
    return trimesh


def _part_colour(geom) -> tuple | None:
    """One colour for a trimesh mesh: its material's main colour or its face colours' most
    common one; None when it has none of its own."""
    vis = getattr(geom, "visual", None)
    try:
        if vis is None or not vis.defined:
            return None
        if vis.kind == "texture":
            c = vis.material.main_color
        else:
            fc = np.asarray(vis.face_colors)
            rows, counts = np.unique(fc, axis=0, return_counts=True)
            c = rows[np.argmax(counts)]
        return tuple(float(x) / 255 for x in np.asarray(c)[:3])
    except Exception:  # a colour is optional: any reader quirk means none
        return None


def _welded(v: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One vertex per position (files repeat them at texture and normal seams, which keeps
    the simplifier from collapsing across them and the page from smoothing across them),
    without non-finite vertices and degenerate faces."""
    f = f[np.all(np.isfinite(v[f].reshape(len(f), -1)), axis=1)]
    if not len(f):
        return v[:0], f
    used = v[f.reshape(-1)]
    lo = used.min(axis=0)
    # Vertices no face uses any more (non-finite ones) merge into the corner `lo`.
    v = np.where(np.isfinite(v).all(axis=1)[:, None], v, lo)
    span = float(np.max(used.max(axis=0) - lo)) or 1.0
    # Positions on a grid of span/2^20 (finer than any screen), as one 60-bit integer each:
    # a 1-D unique, far faster than unique rows.
    grid = np.clip(np.round((v - lo) * ((2**20 - 1) / span)), 0, 2**20 - 1).astype(np.int64)
    key = (grid[:, 0] << 40) | (grid[:, 1] << 20) | grid[:, 2]
    _keys, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    f = inverse.reshape(-1)[f]
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
    return v[first], f


@lru_cache(maxsize=256)
def _read_cached(path: str, mtime: int, size: int) -> list:
    del mtime, size  # cache key only: a changed file is read again
    return _read(path)


def _read_stl(path: str, size: int) -> list:
    """A binary STL (80-byte header, count, 50 bytes per triangle) with NumPy alone: the
    commonest robot mesh format, read without the extra and without trimesh's 1-2 s import.
    ASCII STL goes to trimesh."""
    with open(path, "rb") as fh:
        head = fh.read(84)
        n = int(np.frombuffer(head, dtype="<u4", count=1, offset=80)[0]) if len(head) == 84 else 0
        if head[:5].lower() == b"solid" and 84 + 50 * n != size:
            return []  # ASCII
        if len(head) < 84:
            raise MeshReadError(f"truncated: {size} bytes, less than an STL header")
        if 84 + 50 * n > size:
            raise MeshReadError(f"truncated: {n} triangles announced, {size} bytes")
        rec = np.fromfile(fh, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)),
                                              ("a", "<u2")]), count=n)
    v = rec["v"].reshape(-1, 3).astype(float)
    v, f = _welded(v, np.arange(len(v)).reshape(-1, 3))
    if not len(f):
        raise MeshReadError("no triangles in it")
    return [(v, f, None)]


def _read(path: str) -> list:
    """(vertices, faces, rgb or None) of each part of the file, in the file's frame."""
    try:
        st = os.stat(path)
    except OSError as exc:
        raise MeshReadError(f"cannot be read ({exc.strerror})") from exc
    if not stat.S_ISREG(st.st_mode):  # a FIFO or device would block or never end
        raise MeshReadError("not a regular file")
    size = st.st_size
    if size > MAX_MESH_BYTES:
        raise MeshReadError(f"{size} bytes, more than the {MAX_MESH_BYTES} read for display")
    ext = os.path.splitext(path)[1].lower().lstrip(".")
    if ext == "stl":
        parts = _read_stl(path, size)
        if parts:
            return parts
    trimesh = _trimesh()
    if ext not in trimesh.available_formats():
        raise MeshReadError(f"unknown mesh format '.{ext}'")
    try:
        loaded = trimesh.load(path, force=None)
    except Exception as exc:  # readers raise anything on a corrupt file
        raise MeshReadError(f"unreadable ({type(exc).__name__}: {exc})"[:300]) from exc
    if isinstance(loaded, trimesh.Scene):
        geoms = loaded.dump() if len(loaded.geometry) else []
    else:
        geoms = [loaded]
    parts = []
    for g in geoms:
        if not isinstance(g, trimesh.Trimesh) or len(g.faces) == 0:
            continue
        v, f = _welded(np.asarray(g.vertices, dtype=float), np.asarray(g.faces, dtype=np.int64))
        if len(f):
            parts.append((v, f, _part_colour(g)))
    if not parts:
        raise MeshReadError("no triangles in it")
    if sum(len(p[1]) for p in parts) > MAX_MESH_TRIANGLES:
        raise MeshReadError(f"more than {MAX_MESH_TRIANGLES} triangles")
    return parts


def _has_simplifier() -> bool:
    import importlib.util

    return importlib.util.find_spec("fast_simplification") is not None


def _simplify(v: np.ndarray, f: np.ndarray, target: int) -> tuple[np.ndarray, np.ndarray]:
    if len(f) <= target:
        return v, f
    try:
        import fast_simplification
    except ImportError:
        return v, f  # drawn whole: bigger page, same picture
    # A tiny target may collapse a part to nothing: ask again for more before keeping it all.
    for t in (target, 4 * target + 12, 16 * target + 60):
        v2, f2 = fast_simplification.simplify(v.astype(np.float64), f.astype(np.int32),
                                              target_count=int(min(t, len(f))))
        if len(f2):
            return v2, f2
    return v, f


# ---------------------------------------------------------------- the disk cache
# Reading a COLLADA file takes pycollada ~0.5 s; the simplified meshes (a few hundred kB per
# robot) are kept in ~/.cache/pointmass_dyn/meshes (or $PMD_MESH_CACHE; "0" turns it off), keyed
# by path, modification time, size, scale and budget, so a new process need not read them.

_CACHE_FORMAT = 1


def _cache_dir() -> Path | None:
    env = os.environ.get("PMD_MESH_CACHE")
    if env is not None and env.strip().lower() in ("", "0", "off", "no", "false"):
        return None
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "pointmass_dyn" / "meshes"


def _cache_file(*key) -> Path | None:
    d = _cache_dir()
    if d is None:
        return None
    digest = hashlib.sha256(repr((_CACHE_FORMAT, *key)).encode()).hexdigest()[:32]
    return d / f"{digest}.npz"


def _cache_load(f: Path | None) -> dict | None:
    if f is None:
        return None
    try:
        with np.load(f) as z:
            return {k: z[k] for k in z.files}
    except Exception:  # absent, or damaged: computed again (and rewritten)
        return None


def _cache_save(f: Path | None, **arrays) -> None:
    if f is None:
        return
    try:
        f.parent.mkdir(parents=True, exist_ok=True)
        tmp = f.with_suffix(f".{os.getpid()}.tmp.npz")
        np.savez(tmp, **arrays)
        os.replace(tmp, f)  # whole or not at all, also with processes writing at once
    except OSError:
        pass  # a read-only home: no cache, same result


@lru_cache(maxsize=512)
def _file_mesh(path: str, mtime: int, size: int, scale: tuple, target: int) -> Mesh:
    cache = _cache_file("mesh", path, mtime, size, scale, target)
    z = _cache_load(cache)
    if z is not None:
        rgb = [None if np.isnan(c[0]) else tuple(float(x) for x in c) for c in z["rgb"]]
        return Mesh(z["vertices"], z["faces"],
                    [(int(a), int(n), c) for a, n, c in zip(z["start"], z["count"], rgb)])
    parts = _read_cached(path, mtime, size)
    shares = budget_shares([len(p[1]) for p in parts], [1] * len(parts), target)
    verts, faces, spans = [], [], []
    nv = nf = 0
    for (v, f, rgb), share in zip(parts, shares):
        v, f = _simplify(v, f, share)
        verts.append(v * np.asarray(scale))
        faces.append(f + nv)
        spans.append((nf, len(f), rgb))
        nv += len(v)
        nf += len(f)
    mesh = Mesh(np.concatenate(verts).astype(np.float32), np.concatenate(faces), spans)
    if not np.isfinite(mesh.vertices).all():
        raise MeshReadError(f"coordinates beyond the page's float32 range (scale {scale})")
    if np.prod(np.sign(scale)) < 0:  # a mirroring scale turns the faces inside out
        mesh.faces = mesh.faces[:, ::-1].copy()
    _cache_save(cache, vertices=mesh.vertices, faces=mesh.faces.astype(np.int64),
                start=np.array([a for a, _n, _c in spans]),
                count=np.array([n for _a, n, _c in spans]),
                rgb=np.array([c if c is not None else (np.nan,) * 3 for _a, _n, c in spans],
                             dtype=float).reshape(-1, 3))
    return mesh


@lru_cache(maxsize=512)
def _triangle_count(path: str, mtime: int, size: int) -> int:
    cache = _cache_file("count", path, mtime, size)
    z = _cache_load(cache)
    if z is not None:
        return int(z["n"])
    n = sum(len(p[1]) for p in _read_cached(path, mtime, size))
    _cache_save(cache, n=np.array(n))
    return n


def _stat(path: str) -> tuple[int, int]:
    try:
        st = os.stat(path)
    except ValueError as exc:  # an embedded NUL: no file has that name
        raise MeshReadError(f"not a file name ({exc})") from exc
    return st.st_mtime_ns, st.st_size


# ---------------------------------------------------------------- a model's scene


def budget_shares(counts, uses, budget: int) -> list[int]:
    """Triangles each mesh is simplified to so that ``Σ uses · share ≤ budget`` (``uses``:
    how many times each is drawn): all of them when that fits, else in proportion to its own
    count, a mesh that would get less than :data:`MIN_TRIANGLES` keeping that many (or all
    it has) while the others can pay for it; a budget too small even for that is shared in
    proportion, at least four triangles each (the caller says if the budget is exceeded)."""
    counts, uses = [int(c) for c in counts], [int(u) for u in uses]
    if sum(c * u for c, u in zip(counts, uses)) <= budget:
        return counts
    floor = [min(c, MIN_TRIANGLES) for c in counts]
    if sum(f * u for f, u in zip(floor, uses)) > budget:
        floor = [min(c, 4) for c in counts]
    pinned: dict[int, int] = {}
    while True:
        free = [k for k in range(len(counts)) if k not in pinned]
        left = budget - sum(pinned[k] * uses[k] for k in pinned)
        weight = sum(counts[k] * uses[k] for k in free)
        rate = left / weight if weight > 0 else 0.0
        low = [k for k in free if counts[k] * rate < floor[k]]
        if not low:
            break
        pinned.update({k: floor[k] for k in low})
    return [pinned.get(k, min(counts[k], int(counts[k] * rate))) for k in range(len(counts))]


def _budgeted_meshes(uses: dict, counts: dict, budget: int) -> dict:
    """Each file's mesh (or the error reading it) by ``(path, scale)`` key, simplified so
    that ``Σ uses · triangles ≤ budget`` where the simplifier can: a mesh it leaves above its
    share (a part that will not collapse further) keeps what it got, and the others share the
    rest again (a few rounds)."""
    out: dict[tuple, Any] = {}
    kept: dict[tuple, int] = {}  # triangles of the meshes settled above their share
    for _round in range(4):
        free = [k for k in uses if k not in kept]
        left = budget - sum(kept[k] * uses[k] for k in kept)
        shares = budget_shares([counts[k[0]] for k in free], [uses[k] for k in free], left)
        over = False
        for key, share in zip(free, shares):
            try:
                out[key] = _file_mesh(key[0], *_stat(key[0]), key[1], share)
            except (MeshReadError, OSError) as exc:
                out[key], kept[key] = exc, 0
                continue
            if out[key].ntriangles > share:
                kept[key], over = out[key].ntriangles, True
        if not over:
            break
    return out


def visual_scene(model, triangles: int = DEFAULT_TRIANGLES, warn: bool = True) -> VisualScene:
    """The triangles of ``model.visuals``: each mesh file read once (shared by the visuals
    that use it at one scale) and simplified so that everything drawn has at most
    ``triangles`` triangles: each instance of a mesh counts (a file on four legs four
    times), and so do the primitives and inertia boxes, which are not simplified; the meshes
    share what is left in proportion to their own counts (:func:`budget_shares`). A budget
    that cannot be kept (smaller than the primitives, or fast-simplification missing) is a
    :class:`VisualWarning` saying how many triangles are drawn. Bodies whose meshes could
    not be drawn get their inertia box; one :class:`VisualWarning` names the files that
    could not be read (those not found were named when the model was loaded)."""
    visuals = model.visuals
    meshes, instances, failed = [], [], {}
    counts: dict[str, int] = {}
    for v in visuals:
        if v["kind"] == "mesh" and v["path"] and v["path"] not in counts:
            try:
                counts[v["path"]] = _triangle_count(v["path"], *_stat(v["path"]))
            except (MeshReadError, OSError) as exc:
                failed[v["path"]] = str(exc) if isinstance(exc, MeshReadError) else (
                    f"cannot be read ({exc.strerror})")
    # What each visual draws: a primitive's triangles now, a file's (path, scale) key.
    drawn: list = []
    uses: dict[tuple, int] = {}
    broken_bodies = set()
    for v in visuals:
        pose = np.concatenate([np.asarray(v["rotation"], dtype=float),
                               np.asarray(v["translation"], dtype=float)[:, None]], axis=1)
        rgba = tuple(v["rgba"]) if v["rgba"] is not None else None
        if v["kind"] != "mesh":
            with np.errstate(over="ignore"):
                shape = primitive(v)
            if not np.isfinite(shape.vertices).all():  # sizes beyond float32 (1e308 m)
                failed[f"{v['kind']} of body '{v['body_name']}'"] = "sizes beyond float32"
                broken_bodies.add(v["body"])
                continue
            drawn.append((v, pose, rgba, shape))
        elif not v["path"] or v["path"] in failed:
            # Not found when the model was loaded (which warned), or unreadable.
            broken_bodies.add(v["body"])
        else:
            key = (v["path"], tuple(float(s) for s in v["scale"]))
            uses[key] = uses.get(key, 0) + 1
            drawn.append((v, pose, rgba, key))
    fixed = sum(d[3].ntriangles for d in drawn if isinstance(d[3], Mesh))
    fixed += 12 * len(broken_bodies)  # an inertia box each
    loaded = _budgeted_meshes(uses, counts, triangles - fixed)
    index: dict[tuple, int] = {}
    for v, pose, rgba, what in drawn:
        if isinstance(what, Mesh):
            meshes.append(what)
            instances.append(Instance(v["body"], len(meshes) - 1, pose, rgba or DEFAULT_RGBA))
            continue
        path = what[0]
        if path in failed:
            broken_bodies.add(v["body"])
            continue
        if what not in index:
            mesh = loaded[what]
            if not isinstance(mesh, Mesh):
                failed[path] = str(mesh) if isinstance(mesh, MeshReadError) else (
                    f"cannot be read ({mesh.strerror})")
                broken_bodies.add(v["body"])
                continue
            meshes.append(mesh)
            index[what] = len(meshes) - 1
        mesh = meshes[index[what]]
        own = any(rgb is not None for _s, _n, rgb in mesh.parts)
        # A file's own colours (COLLADA, OBJ materials) win over the URDF's, as in RViz.
        instances.append(Instance(v["body"], index[what], pose,
                                  None if own else (rgba or DEFAULT_RGBA)))
    for b in sorted(broken_bodies):
        box = inertia_box(model.body(b))
        if box is not None:
            meshes.append(box[0])
            instances.append(Instance(b, len(meshes) - 1, box[1], FALLBACK_RGBA, True))
    scene = VisualScene(meshes, instances, failed)
    if failed and warn:
        shown = [f"{k} ({why})" for k, why in list(failed.items())[:8]]
        more = f" and {len(failed) - 8} more" if len(failed) > 8 else ""
        warnings.warn(
            f"{len(failed)} mesh file(s) or shape(s) not drawn, their bodies are shown as inertia boxes: "
            + "; ".join(shown) + more,
            VisualWarning,
            stacklevel=3,
        )
    if scene.triangles > triangles and warn:
        why = ("fast-simplification is not installed (pip install \"pointmass-dyn[mesh]\")"
               if not _has_simplifier() else
               f"the shapes that are not simplified (primitives, inertia boxes) alone have "
               f"{fixed}" if fixed > triangles else "the meshes cannot be simplified further")
        warnings.warn(
            f"triangles: expected at most {triangles} triangles drawn, the model's shapes have "
            f"{scene.triangles}: {why}", VisualWarning, stacklevel=3)
    return scene


def bounds(scene: VisualScene) -> np.ndarray:
    """Per instance, the 8 corners (k, 8, 3) of its mesh's bounding box in the body frame."""
    out = np.zeros((len(scene.instances), 8, 3))
    for k, inst in enumerate(scene.instances):
        v = scene.meshes[inst.mesh].vertices
        lo, hi = v.min(axis=0), v.max(axis=0)
        c = np.array([[(hi if j >> a & 1 else lo)[a] for a in range(3)] for j in range(8)])
        out[k] = c @ inst.pose[:, :3].T + inst.pose[:, 3]
    return out

