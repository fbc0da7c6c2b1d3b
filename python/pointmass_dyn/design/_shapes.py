"""Link shapes as material cells (docs/design.md §1).

A :class:`LinkShape` describes where a link's material may be: an envelope in the body frame
(a box, a planar polygon extruded along z, or a closed STL mesh) cut into cubic cells of side
``cell``, each holding between 0 and ``density × cell³`` of material. The design chooses
every cell's mass; the link's mass, first and second moments are linear in them (each cell
a small solid cube), which is what makes the design a convex program. The result per link
is a :class:`Shape` (cells, masses, bounds; ``write_stl`` for a CAD tool)."""

from __future__ import annotations

import struct
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import _core
from ..errors import InvalidInputError
from ._material import Material
from ._strength import link_pins, members, web_mask


def _numbers(value: Any, arg: str, expected: str) -> np.ndarray:
    """``value`` as a float array, or our error naming ``arg`` (NumPy's is a ValueError)."""
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{arg}: expected {expected}, got {value!r:.80}") from None


def _box(value: Any, arg: str) -> np.ndarray:
    b = _numbers(value, arg, "(lower, upper) corners, two (x, y, z)")
    if b.shape != (2, 3) or not np.all(np.isfinite(b)):
        raise InvalidInputError(f"{arg}: expected (lower, upper) corners, two (x, y, z), got {value!r}")
    if np.any(b[1] <= b[0]):
        raise InvalidInputError(f"{arg}: expected lower < upper along x, y and z, got {b.tolist()}")
    return b


def read_stl(path: str | Path) -> np.ndarray:
    """The triangles (T, 3, 3) of a binary or ASCII STL file."""
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise InvalidInputError(f"stl: expected a readable STL file, got '{path}' ({exc})") from None
    if len(data) >= 84:
        count = struct.unpack("<I", data[80:84])[0]
        if 84 + 50 * count == len(data):
            rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]), offset=84)
            return rec["v"].astype(float)
    text = data.decode("ascii", errors="replace").split()
    try:
        verts = [[float(text[i + 1]), float(text[i + 2]), float(text[i + 3])] for i, w in enumerate(text) if w == "vertex"]
    except (IndexError, ValueError):
        raise InvalidInputError(
            f"stl: expected 'vertex x y z' lines of numbers, got '{path}' with a malformed vertex"
        ) from None
    if not verts or len(verts) % 3:
        raise InvalidInputError(f"stl: expected a binary or ASCII STL file, got '{path}' without triangles")
    return np.asarray(verts).reshape(-1, 3, 3)


@dataclass(frozen=True)
class LinkShape:
    """A link whose material the design places, as cells of side ``cell`` (m) inside an
    envelope in the body frame: ``box=(lower, upper)``, or ``polygon=[(x, y), …]`` extruded
    over ``z=(low, high)``, or ``stl=`` a closed mesh (path or (T, 3, 3) triangles).

    Each cell holds between 0 and ``density × cell³`` kg. ``mass``: None (free) or
    ``(low, high)`` in kg. The cells within ``boss`` (default: one cell) of the axis of every
    joint on the link (its own, its children's, the cut joints') stay full, so the link
    still carries its pins; ``keep`` (boxes) adds cells that must stay full, ``keep_out``
    (boxes) removes cells. ``symmetric=True`` keeps the link symmetric about the mid-plane
    of its envelope's z range (a planar link stays in its plane).

    ``connected=True`` (default): the link is one face-connected part holding its bosses
    (docs/design.md §3): every cross-section between two joints holds at least ``section``
    cell faces of material, and material hangs from the bosses through faces at least ``1/hang``
    as full as what they carry (``hang`` None: ``pmd.design.HANG``); the written part is
    checked by a flood fill and joined where thresholding separated it."""

    body: Any
    box: Any = None
    polygon: Any = None
    z: Any = None
    stl: Any = None
    density: float = 7850.0
    cell: float = 0.002
    mass: Any = None
    keep: Any = ()
    keep_out: Any = ()
    boss: float | None = None
    symmetric: bool = False
    #: A :class:`~pointmass_dyn.Material` (density and allowable stress): the link's members
    #: are strength-checked (docs/design.md §4a); its density replaces ``density``.
    material: Any = None
    #: With a material: the width (m) of the web kept full along each member (default: two
    #: bosses' radius).
    web: float | None = None

    @property
    def rho(self) -> float:
        """The density the cells are made of: the material's, else ``density``."""
        return float(self.material.density if self.material is not None else self.density)

    def web_width(self) -> float:
        """The web's width (m): ``web``, else the bosses' diameter."""
        return float(self.web) if self.web is not None else 2.0 * self.boss_radius()

    def boss_radius(self) -> float:
        return self.cell if self.boss is None else float(self.boss)
    #: One connected solid holding its pins (docs/design.md §3); ``False``: the unconnected
    #: optimum.
    connected: bool = True
    #: Connected: the least cross-section, in cell faces, between two of its joints.
    section: float = 1.0
    #: Connected: how full (``1/hang``) the faces a region of cells hangs from must be, for
    #: what it carries (``None``: :data:`~pointmass_dyn.design.HANG`).
    hang: float | None = None

    def _envelope(self) -> dict:
        given = [k for k in ("box", "polygon", "stl") if getattr(self, k) is not None]
        if len(given) != 1:
            raise InvalidInputError(
                f"LinkShape '{self.body}': expected exactly one envelope (box, polygon or stl), got "
                f"{given or 'none'}"
            )
        if self.box is not None:
            return {"box": _box(self.box, "box")}
        if self.polygon is not None:
            poly = _numbers(self.polygon, "polygon", "(P, 2) vertices")
            z = _numbers(self.z if self.z is not None else (), "z", "(low, high)")
            if poly.ndim != 2 or poly.shape[1] != 2 or z.shape != (2,):
                raise InvalidInputError(
                    "polygon, z: expected (P, 2) vertices and z=(low, high), got "
                    f"{poly.shape} and {self.z!r}"
                )
            return {"polygon": poly, "z": (float(z[0]), float(z[1]))}
        tri = self.stl if not isinstance(self.stl, (str, Path)) else read_stl(self.stl)
        return {"triangles": np.asarray(tri, dtype=float)}

    def cells(self, model: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Centres (K, 3), lower and upper bounds (K,) of the cells, body frame."""
        for arg in ("density", "cell"):
            v = getattr(self, arg)
            if isinstance(v, bool) or not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
                raise InvalidInputError(f"{arg}: expected a positive number, got {v!r}")
        b = self.boss
        if b is not None and (
            isinstance(b, bool) or not (isinstance(b, (int, float)) and np.isfinite(b) and b >= 0)
        ):
            raise InvalidInputError(f"boss: expected None or a finite radius >= 0 (m), got {b!r}")
        _check_material(self)
        env = self._envelope()
        centers = np.asarray(_core.design_cells(float(self.cell), **env), dtype=float).reshape(-1, 3)
        for b in _boxes(self.keep_out, "keep_out"):
            centers = centers[~_inside(centers, b)]
        if len(centers) == 0:
            raise InvalidInputError(
                f"LinkShape '{self.body}': no cell of side {self.cell} fits in the envelope (less keep_out)"
            )
        cap = np.full(len(centers), self.rho * self.cell**3)
        full = np.zeros(len(centers), dtype=bool)
        for g in self.keep_cells(centers) + self.pin_cells(model, centers):
            full[g] = True
        if self.material is not None:  # the members' webs stay full: they carry the loads
            full |= web_mask(members(link_pins(model, self.body), self.boss_radius()), centers,
                             self.web_width())
        return centers, np.where(full, cap, 0.0), cap

    def pin_cells(self, model: Any, centers: np.ndarray) -> list[np.ndarray]:
        """Indices of the cells within ``boss`` of each joint on the link (its boss)."""
        radius = self.boss_radius()
        out = []
        for point, axis in _core.design_pins(model, self.body):
            d = centers - point
            n = np.linalg.norm(axis)
            if n > 0:
                d = d - np.outer(d @ (axis / n), axis / n)
            out.append(np.nonzero(np.linalg.norm(d, axis=1) <= radius * (1 + 1e-9))[0])
        return out

    def keep_cells(self, centers: np.ndarray) -> list[np.ndarray]:
        """Indices of the cells inside each ``keep`` box."""
        return [np.nonzero(_inside(centers, b))[0] for b in _boxes(self.keep, "keep")]

    def mirror_pairs(self, centers: np.ndarray) -> list[tuple[int, int]]:
        """Index pairs of cells mirrored about the envelope's z mid-plane."""
        if not self.symmetric:
            return []
        lo, hi = (centers[:, 2].min(), centers[:, 2].max())
        mid = 0.5 * (lo + hi)
        key = {tuple(np.round(c / self.cell * 2).astype(int)): i for i, c in enumerate(centers)}
        pairs = []
        for i, c in enumerate(centers):
            m = c.copy()
            m[2] = 2 * mid - c[2]
            j = key.get(tuple(np.round(m / self.cell * 2).astype(int)))
            if j is None:
                raise InvalidInputError(
                    f"symmetric: the cells of '{self.body}' are not symmetric about z = {mid:g} "
                    "(give an envelope symmetric about its mid-plane)"
                )
            if i < j:
                pairs.append((i, j))
        return pairs


def _check_material(shape: LinkShape) -> None:
    if shape.material is not None and not isinstance(shape.material, Material):
        raise InvalidInputError(
            f"material: expected a pmd.Material (e.g. pmd.Material.steel()), got {shape.material!r}"
        )
    if shape.material is not None and shape.density != LinkShape.density \
            and shape.density != shape.material.density:
        raise InvalidInputError(
            f"density: expected the material's ({shape.material.density} kg/m³) or none with "
            f"material=, got {shape.density!r}"
        )
    w = shape.web
    if w is not None and (isinstance(w, bool) or not isinstance(w, (int, float, np.integer, np.floating))
                          or not (np.isfinite(w) and w > 0)):
        raise InvalidInputError(f"web: expected None or a width > 0 (m), got {w!r}")


def _boxes(value: Any, arg: str) -> list[np.ndarray]:
    if value is None or len(value) == 0:
        return []
    arr = np.asarray(value, dtype=float)
    if arr.shape == (2, 3):
        return [_box(arr, arg)]
    return [_box(b, f"{arg}[{k}]") for k, b in enumerate(value)]


def _inside(centers: np.ndarray, box: np.ndarray) -> np.ndarray:
    return np.all((centers >= box[0]) & (centers <= box[1]), axis=1)


@dataclass(frozen=True)
class Shape:
    """A designed link's material: cell ``centers`` (K, 3) in the body frame, their
    ``masses`` (K,) and ``capacity`` (K,) (density × cell³), the cell side ``cell``;
    ``realised``: the part as written (``Balance.realised[body]``, a ``RealisedPart``), set
    by ``balance``."""

    body: str
    centers: np.ndarray
    masses: np.ndarray
    capacity: np.ndarray
    cell: float
    realised: Any = field(default=None, repr=False, compare=False)

    @property
    def mass(self) -> float:
        return float(np.sum(self.masses))

    @property
    def fill(self) -> np.ndarray:
        """Each cell's mass as a fraction of its capacity."""
        return self.masses / self.capacity

    def mass_properties(self) -> dict:
        """The material's mass (kg), COM (m, body frame) and inertia about the COM (kg m²),
        ``"designed"`` (the cells' masses, each a cube) and ``"written"`` (the realised
        part's boxes, exactly; None without one)."""
        m, c = self.masses, self.centers
        mass = float(m.sum())
        com = (m @ c) / max(mass, 1e-300)
        r = c - com
        inertia = (np.eye(3) * (np.einsum("k,ki,ki->", m, r, r) + mass * self.cell**2 / 6.0)
                   - np.einsum("k,ki,kj->ij", m, r, r))
        out = {"designed": {"mass": mass, "com": com, "inertia": inertia}, "written": None}
        if self.realised is not None:
            b = self.realised.body
            out["written"] = {"mass": float(b.mass), "com": np.asarray(b.com, float),
                              "inertia": np.asarray(b.inertia, float)}
        return out

    def table(self) -> str:
        """The material's mass, COM and Izz, designed and written, one line each."""
        rows = [f"{self.body:<10}{'':>9}{'mass (kg)':>13}{'COM (mm)':>30}{'Izz (kg m²)':>14}"]
        for label, p in self.mass_properties().items():
            if p is not None:
                c = p["com"] * 1e3
                rows.append(f"{'':<10}{label:>9}{p['mass']:>13.6g}{c[0]:>10.4f}{c[1]:>10.4f}"
                            f"{c[2]:>10.4f}{p['inertia'][2, 2]:>14.6g}")
        return "\n".join(rows)

    def write_stl(self, path: str | Path, threshold: float | None = None) -> int:
        """Writes the part as realised (``self.realised``, what ``Balance.realised`` analyses:
        decided, joined and polished; ``mass_properties()`` gives it beside the design) as a
        closed binary STL (metres, body frame). With ``threshold`` (or for a shape without a
        realised part: 0.5), the cells filled to at least that fraction of their capacity
        instead, with a ``RuntimeWarning`` giving how far their mass and COM are from the
        design's. Returns the number of triangles."""
        if threshold is None and self.realised is not None:
            return self.realised.write_stl(path)
        threshold = 0.5 if threshold is None else threshold
        if not 0.0 <= threshold <= 1.0:
            raise InvalidInputError(f"threshold: expected a fraction in [0, 1], got {threshold}")
        mask = self.fill >= threshold
        kept = self.centers[mask]
        warn_rounded(self, mask, threshold)
        base = self.centers.min(axis=0)
        idx = np.round((kept - base) / self.cell).astype(np.int64)
        occupied = {tuple(i) for i in idx}
        h = 0.5 * self.cell
        tris = []
        for axis in range(3):
            for sign in (-1, 1):
                step = np.zeros(3, dtype=np.int64)
                step[axis] = sign
                u, v = (axis + 1) % 3, (axis + 2) % 3
                for c, i in zip(kept, idx):
                    if tuple(i + step) in occupied:
                        continue
                    center = c.copy()
                    center[axis] += sign * h
                    du, dv = np.zeros(3), np.zeros(3)
                    du[u], dv[v] = h, h
                    q = [center - du - dv, center + du - dv, center + du + dv, center - du + dv]
                    if sign < 0:
                        q = q[::-1]
                    tris += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        with open(path, "wb") as f:
            f.write(b"pointmass_dyn design".ljust(80, b" "))
            f.write(struct.pack("<I", len(tris)))
            for t in tris:
                a, b, c = (np.asarray(p, dtype=np.float32) for p in t)
                n = np.cross(b - a, c - a)
                n = n / (np.linalg.norm(n) or 1.0)
                f.write(struct.pack("<12fH", *n, *a, *b, *c, 0))
        return len(tris)


def warn_rounded(shape: Shape, mask: np.ndarray, threshold: float, what: str = "write_stl") -> None:
    """Thresholded cells are not the design: say by how much (mass, and the COM against the
    envelope's size)."""
    designed = shape.mass_properties()["designed"]
    full = shape.capacity[mask]
    mass = float(full.sum())
    com = (full @ shape.centers[mask]) / max(mass, 1e-300)
    size = float(np.ptp(shape.centers, axis=0).max() + shape.cell)
    dm = abs(mass - designed["mass"]) / max(designed["mass"], 1e-300)
    dc = float(np.linalg.norm(com - designed["com"])) / size
    warnings.warn(
        f"{what}: the cells at least {threshold:g} full are not the design: mass "
        f"{100 * dm:.2f} % off, COM {100 * dc:.2f} % of the part's size off (write the realised "
        "part: threshold=None)", RuntimeWarning, stacklevel=3)
