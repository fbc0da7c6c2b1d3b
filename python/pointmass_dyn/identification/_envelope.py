"""Each link's envelope (link frame) for the cells: a given box, or the bounding box of the
geometry of the link's bodies (the link's own and those welded to it) from the model's
visuals (URDF ``<visual>``: boxes, cylinders, spheres, meshes)."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .._collision import GeometryUnreadable, mesh_vertices
from ..errors import InvalidInputError
from ._shapes import envelope_of

_UNIT_BOX = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)


@lru_cache(maxsize=128)
def _hull_points(path: str) -> np.ndarray:
    """A mesh file's vertices, read once per process (a robot's meshes are re-read for every
    identification otherwise)."""
    return mesh_vertices(path)


def _shape_points(vis: dict) -> np.ndarray:
    """Points spanning a visual shape's bounds, in its body's frame."""
    kind = vis["kind"]
    if kind == "box":
        pts = _UNIT_BOX * (np.asarray(vis["size"], float) / 2)
    elif kind == "sphere":
        pts = _UNIT_BOX * float(vis["radius"])
    elif kind in ("cylinder", "capsule"):
        r, half = float(vis["radius"]), float(vis["length"]) / 2
        extra = r if kind == "capsule" else 0.0
        pts = _UNIT_BOX * np.array([r, r, half + extra])
    elif kind == "ellipsoid":
        pts = _UNIT_BOX * np.asarray(vis["radii"], float)
    elif kind == "mesh":
        path = vis.get("path")
        if not path:
            raise GeometryUnreadable(f"mesh '{vis.get('uri')}': no file")
        pts = _hull_points(str(path)) * np.asarray(vis.get("scale") or (1.0, 1.0, 1.0), float)
    else:
        raise GeometryUnreadable(f"a '{kind}' shape")
    return pts @ np.asarray(vis["rotation"], float).T + np.asarray(vis["translation"], float)


def visual_boxes(model) -> dict[str, np.ndarray]:
    """``{link name: (2, 3) box}`` for every link with geometry: the bounds of its bodies'
    visuals in the link frame (bodies placed at the neutral configuration)."""
    rot, org = model.placements(model.neutral())
    names = list(model.body_names)
    links = list(model.link_names)
    owner = {}
    for b in range(len(names)):
        info = model.body_info(b)
        if info[3] >= 0:
            owner[b] = links[info[3]]
    pts: dict[str, list[np.ndarray]] = {}
    for vis in model.visuals:
        b = int(vis["body"])
        if b not in owner:
            continue
        link = owner[b]
        lb = names.index(link)
        try:
            local = _shape_points(vis)
        except GeometryUnreadable:
            continue
        world = local @ rot[b].T + org[b]
        pts.setdefault(link, []).append((world - org[lb]) @ rot[lb])
    return {k: np.array([np.min(np.vstack(v), 0), np.max(np.vstack(v), 0)]) for k, v in pts.items()}


def envelope_boxes(model, links: list[str], envelopes) -> dict:
    """The envelope of every link in ``links``: ``envelopes[link]`` where given ((2, 3) lower
    and upper corners; a prism ``{"polygon": (P, 2), "z": (low, high)}`` or a mesh
    ``{"stl": path or (T, 3, 3)}`` / an STL path, as ``_shapes`` objects), else the bounds of
    its visuals; an error naming the link when it has neither."""
    given = dict(envelopes or {})
    unknown = [k for k in given if k not in model.link_names]
    if unknown:
        raise InvalidInputError(f"envelopes: expected link names of the model ({list(model.link_names)}), got {unknown}")
    auto = visual_boxes(model) if any(k not in given for k in links) else {}
    out = {}
    for k in links:
        box = given.get(k, auto.get(k))
        shape = envelope_of(k, box) if k in given else None
        if shape is not None:
            out[k] = shape
            continue
        if box is None:
            raise InvalidInputError(
                f"envelopes: expected a box for link '{k}' (it has no visual geometry to bound), got none"
            )
        box = np.asarray(box, float)
        if box.shape != (2, 3) or not np.all(np.isfinite(box)) or not np.all(box[1] > box[0]):
            raise InvalidInputError(f"envelopes['{k}']: expected (lower, upper) corners with lower < upper, got {box.tolist()}")
        out[k] = box
    return out


def box_cells(box: np.ndarray, count: int) -> tuple[np.ndarray, float]:
    """About ``count`` cubic cells filling ``box``: centres (K, 3) and the side."""
    span = box[1] - box[0]
    side = float((np.prod(span) / max(count, 1)) ** (1 / 3))
    side = min(side, float(span.min()))
    n = np.maximum(np.floor(span / side * (1 + 1e-12)).astype(int), 1)
    axes = [box[0][i] + (np.arange(n[i]) + 0.5) * span[i] / n[i] for i in range(3)]
    # Cells stretched to fill the box exactly: the side of the inscribed cube of each.
    side = float(np.min(span / n))
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    return grid, side
