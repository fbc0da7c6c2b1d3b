"""Envelopes besides the box for the cells of :func:`identify` (docs/identification.md §3): a
prism (a planar polygon in the link's x–y plane extruded along z) and a closed triangle mesh
(an STL file or (T, 3, 3) triangles), each with its cells and an inside test."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import _core
from ..design import read_stl
from ..errors import InvalidInputError


def winding_numbers(triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The generalised winding number of a closed mesh at each point (Jacobson et al. 2013):
    the solid angles of its triangles summed over 4π, ±1 inside (the sign of the
    orientation), 0 outside. A sum, not a ray's crossings, so a point whose ray would graze
    an edge or a vertex is classified like any other, and a tiny gap changes it by the
    gap's solid angle only."""
    tri = np.asarray(triangles, float)
    out = np.zeros(len(points))
    # Chunks of points keep the (points, triangles) temporaries small.
    step = max(1, 200_000 // max(len(tri), 1))
    for s in range(0, len(points), step):
        p = np.asarray(points[s : s + step], float)[:, None, :]
        a, b, c = tri[None, :, 0] - p, tri[None, :, 1] - p, tri[None, :, 2] - p
        la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
        det = np.einsum("ijk,ijk->ij", a, np.cross(b, c))
        den = la * lb * lc + np.einsum("ijk,ijk->ij", a, b) * lc
        den += np.einsum("ijk,ijk->ij", b, c) * la + np.einsum("ijk,ijk->ij", c, a) * lb
        out[s : s + step] = 2 * np.arctan2(det, den).sum(axis=1) / (4 * np.pi)
    return out


@dataclass(frozen=True)
class Prism:
    """A simple polygon ``(P, 2)`` in the link's x–y plane, extruded from ``z[0]`` to ``z[1]``."""

    polygon: np.ndarray
    z: tuple[float, float]

    @property
    def bounds(self) -> np.ndarray:
        return np.array([[*self.polygon.min(0), self.z[0]], [*self.polygon.max(0), self.z[1]]])

    @property
    def volume(self) -> float:
        x, y = self.polygon.T
        area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
        return area * (self.z[1] - self.z[0])

    def cells(self, count: int) -> tuple[np.ndarray, float]:
        side = _side(self.volume, count, self.bounds)
        centres = np.asarray(_core.design_cells(side, polygon=self.polygon, z=self.z), float).reshape(-1, 3)
        return centres, side

    def contains(self, points) -> np.ndarray:
        p = np.atleast_2d(np.asarray(points, float))
        inside = np.zeros(len(p), bool)
        poly = self.polygon
        for a, b in zip(poly, np.roll(poly, -1, axis=0)):  # even–odd rule
            cross = (a[1] > p[:, 1]) != (b[1] > p[:, 1])
            with np.errstate(divide="ignore", invalid="ignore"):
                x = a[0] + (p[:, 1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0])
            inside ^= cross & (p[:, 0] < x)
        slack = 1e-9 * float(np.ptp(self.bounds, axis=0).max())
        return inside & (p[:, 2] >= self.z[0] - slack) & (p[:, 2] <= self.z[1] + slack)


@dataclass(frozen=True)
class Mesh:
    """A closed triangle mesh ``(T, 3, 3)`` (link frame)."""

    triangles: np.ndarray

    @property
    def bounds(self) -> np.ndarray:
        pts = self.triangles.reshape(-1, 3)
        return np.array([pts.min(0), pts.max(0)])

    @property
    def volume(self) -> float:
        t = self.triangles
        return abs(float(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum()) / 6)

    def contains(self, points) -> np.ndarray:
        return np.abs(winding_numbers(self.triangles, np.atleast_2d(np.asarray(points, float)))) > 0.5

    def cells(self, count: int) -> tuple[np.ndarray, float]:
        """Cubes on a grid over the bounds whose centre and eight corners are all inside (by
        the winding number), about ``count`` of them."""
        box = self.bounds
        side = _side(self.volume, count, box)
        span = box[1] - box[0]
        n = np.maximum(np.floor(span / side * (1 + 1e-12)).astype(int), 1)
        start = box[0] + 0.5 * (span - n * side)
        axes = [start[i] + (np.arange(n[i]) + 0.5) * side for i in range(3)]
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
        h = 0.5 * side * (1 - 1e-9)
        corners = np.array([[sx, sy, sz] for sx in (-h, h) for sy in (-h, h) for sz in (-h, h)])
        ok = self.contains(grid)
        for c in corners:
            ok[ok] &= self.contains(grid[ok] + c)
        if not ok.any():
            raise InvalidInputError(f"envelopes: no cell of side {side:.3g} fits inside the mesh (is it closed?)")
        return grid[ok], side


def _side(volume: float, count: int, box: np.ndarray) -> float:
    side = float((volume / max(count, 1)) ** (1 / 3))
    return min(side, float(np.ptp(box, axis=0).min()))


def envelope_of(link: str, value):
    """A :class:`Prism` or :class:`Mesh` from an ``envelopes`` entry, or None for a box:
    ``{"polygon": (P, 2), "z": (low, high)}``, ``{"stl": path or (T, 3, 3)}``, or an STL path."""
    if isinstance(value, (str, Path)):
        value = {"stl": value}
    if not isinstance(value, dict):
        return None
    arg = f"envelopes['{link}']"
    if set(value) == {"polygon", "z"}:
        poly = np.asarray(value["polygon"], float)
        z = np.asarray(value["z"], float)
        if poly.ndim != 2 or poly.shape[1] != 2 or len(poly) < 3 or z.shape != (2,) or not z[1] > z[0]:
            raise InvalidInputError(f"{arg}: expected polygon (P ≥ 3, 2) and z=(low, high), got {poly.shape} and {z.tolist()}")
        if not (np.isfinite(poly).all() and np.isfinite(z).all()):
            raise InvalidInputError(f"{arg}: expected finite polygon and z, got NaN or infinity")
        return Prism(poly, (float(z[0]), float(z[1])))
    if set(value) == {"stl"}:
        src = value["stl"]
        tri = read_stl(src) if isinstance(src, (str, Path)) else np.asarray(src, float)
        if tri.ndim != 3 or tri.shape[1:] != (3, 3) or len(tri) < 4 or not np.isfinite(tri).all():
            raise InvalidInputError(f"{arg}: expected a closed mesh of (T ≥ 4, 3, 3) finite triangles, got shape {tri.shape}")
        return Mesh(tri)
    raise InvalidInputError(f"{arg}: expected a (2, 3) box, {{'polygon', 'z'}}, {{'stl'}} or an STL path, got keys {sorted(value)}")
