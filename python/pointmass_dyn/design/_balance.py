"""What balancing takes and gives (docs/balancing.md, docs/design.md): candidate
counterweight points (:class:`Counterweight`) and the result of a design (:class:`Balance`).
The design itself is in ``_problem``."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import _core
from ..errors import InvalidInputError
from ._dxf import outline, plate_holes, thinned, write_dxf
from ._report import write_report
from ._shaking import MotionAnalysis
from ._shapes import warn_rounded as _warn_rounded
from ._write import write_scene, write_urdf

MAX_RING_COUNT = 1_000_000  # as many candidates as a design takes cells (rust/design/cells.rs)


@dataclass(frozen=True)
class Counterweight:
    """Candidate counterweight positions on one body: point masses at ``points`` (K, 3) in the
    body's frame, each of mass in ``[0, max_mass]`` (``None``: unbounded). Balancing chooses
    their masses; a ring of candidates around a pivot lets it place a counterweight at any
    angle (two neighbours share it)."""

    body: Any
    points: Any
    max_mass: float | None = None

    def __post_init__(self):
        # Refused where it is written, not only when a design or balance reads it.
        m = self.max_mass
        if m is not None and (isinstance(m, bool) or not isinstance(m, (int, float, np.integer, np.floating))
                              or not m > 0):
            raise InvalidInputError(
                f"max_mass: expected a number > 0 (kg) or None (unbounded), got {m!r}"
            )

    @staticmethod
    def ring(
        body: Any,
        center: Any,
        radius: float,
        count: int = 24,
        normal: Any = (0, 0, 1),
        max_mass: float | None = None,
    ) -> Counterweight:
        """``count`` candidates on a circle of ``radius`` about ``center`` in the plane normal
        to ``normal`` (body frame)."""
        if (isinstance(count, bool) or not isinstance(count, (int, np.integer))
                or not 1 <= count <= MAX_RING_COUNT):
            raise InvalidInputError(
                f"count: expected an integer number of candidates in [1, {MAX_RING_COUNT}], got {count!r}"
            )
        c = _vector(center, "center")
        if isinstance(radius, bool) or not isinstance(radius, (int, float, np.integer, np.floating)) \
                or not (np.isfinite(radius) and radius > 0):
            raise InvalidInputError(f"radius: expected a finite number > 0 (m), got {radius!r}")
        try:
            n = np.zeros(0) if np.iscomplexobj(normal) else np.asarray(normal, dtype=float)
        except (TypeError, ValueError):  # a string, a ragged list
            n = np.zeros(0)
        if n.shape != (3,) or not np.all(np.isfinite(n)) or not np.any(n != 0):
            raise InvalidInputError(f"normal: expected a finite non-zero (x, y, z), got {normal!r}")
        n = n / np.max(np.abs(n))  # first, so a normal of 1e300 does not overflow the norm
        n = n / np.linalg.norm(n)
        u = np.cross(n, [1.0, 0.0, 0.0])
        if np.linalg.norm(u) < 1e-8:
            u = np.cross(n, [0.0, 1.0, 0.0])
        u /= np.linalg.norm(u)
        w = np.cross(n, u)
        ang = 2 * np.pi * np.arange(count) / count
        pts = c + float(radius) * (
            np.outer(np.cos(ang), u) + np.outer(np.sin(ang), w)
        )
        return Counterweight(body, pts, max_mass)


@dataclass(frozen=True)
class SolverStage:
    """One stage of a design's solve (``Balance.solver["stages"]``): ``stage``
    (``"optimum"``, then ``"least mass"``), Clarabel's ``status``, the absolute and relative
    duality gaps of its last program, and ``objective``: the first stage's weighted objective
    at this stage's design (docs/design.md §3: the least-mass stage keeps it within
    ``LEAST_MASS_HOLD`` of the optimum's). ``stage["status"]`` reads a field too."""

    stage: str
    status: str
    gap_abs: float
    gap_rel: float
    objective: float

    def __getitem__(self, name: str) -> Any:
        if name not in self.__dataclass_fields__:
            raise KeyError(name)
        return getattr(self, name)


def _vector(x, arg: str) -> np.ndarray:
    """``x`` as a finite (x, y, z), or our error naming ``arg``."""
    try:  # (complex values: NumPy would drop the imaginary part with only a warning)
        v = None if np.iscomplexobj(x) else np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        v = None
    if v is None or v.shape != (3,) or not np.all(np.isfinite(v)):
        raise InvalidInputError(f"{arg}: expected a finite (x, y, z) in the body frame, got {x!r}")
    return v


@dataclass
class Balance:
    """The result of :func:`balance`.

    ``counterweights``: ``(body name, position in the body frame (3,), mass)`` of each
    counterweight placed (mass above ``1e-12`` of the largest); ``bodies``: each changed
    body's new :class:`RigidBody` (mass, COM, inertia, all physically valid); ``model``: the
    balanced model; ``before`` / ``after``: the analysis of the original and of the balanced
    model along the same motion (recomputed, not predicted); ``predicted``: the objective
    quantities the linear model gave, which ``after`` reproduces to round-off."""

    masses: np.ndarray
    counterweights: list[tuple[str, np.ndarray, float]]
    bodies: dict[str, Any]
    model: Any
    before: MotionAnalysis
    after: MotionAnalysis
    predicted: dict[str, np.ndarray]
    objective: dict[str, float]
    zero: tuple[str, ...]
    message: str = ""
    extras: dict = field(default_factory=dict)
    #: Designed link shapes by body name (:class:`~pointmass_dyn.Shape`).
    shapes: dict = field(default_factory=dict)
    #: The conic solver's report: status, duality gaps, iterations, times, the values it
    #: predicts in the problem's norm and those before; ``stages``: a :class:`SolverStage`
    #: each (the optimum, then the least mass among the optima); ``notes``: what did not go
    #: as asked without failing the design (a least-mass stage not found; also warned).
    solver: dict = field(default_factory=dict)
    #: Strength-checked links (``LinkShape(material=…)``) by body name: a
    #: :class:`~pointmass_dyn.design.LinkStrength` each — stresses along the motion, the
    #: smallest safety factor and where it occurs (re-analysed from ``after``).
    strength: dict = field(default_factory=dict)
    #: The written parts (:class:`~pointmass_dyn.design.Realisation`, docs/design.md §4):
    #: each link's solid boxes and their exact mass properties, the realised model analysed
    #: along the motion and its deviation from ``predicted``; None without link shapes.
    realised: Any = None

    def write_scene(self, source: Any, path: Any) -> Any:
        """The designed model as a scene file: a copy of ``source`` (the scene the motion's
        model came from: a path, a bundled name or a :class:`Scene`) with the designed
        bodies' mass, COM and inertia; bodies from a URDF go into a copy of it beside ``path``
        (:func:`~pointmass_dyn.design.write_scene`)."""
        return write_scene(self.bodies, source, path)

    def write_urdf(self, source: Any, path: Any) -> Any:
        """A copy of the URDF ``source`` with the designed bodies' ``<inertial>`` elements."""
        return write_urdf(self.bodies, source, path)

    def report(self, path: Any) -> Any:
        """Writes one self-contained HTML page on this design (figures embedded): each link's
        outline and density map, shaking before/after, bearing forces, the mass and
        safety-factor table, the solver's status and time (docs/design.md §4c)."""
        return write_report(self, path)  # (matplotlib imported only here)

    def write_dxf(self, body: str, path: Any, threshold: float | None = None,
                  hole: float | None = None) -> Any:
        """A plate link's outline for cutting (R12 DXF, mm): the realised part (the same as
        ``write_stl``) seen along z on layer ``OUTLINE``, each column the polish thinned as a
        square on a layer ``THICK_<µm>UM`` naming its thickness (a pocket milled from both
        faces), and a hole of radius ``hole`` (default half a cell) at each pin. With
        ``threshold``: the cells at least that full instead (not the design: warned)."""
        if body not in self.shapes:
            raise InvalidInputError(f"body: expected a designed link shape {sorted(self.shapes)}, got {body!r}")
        shape = self.shapes[body]
        if threshold is not None and not 0.0 <= threshold <= 1.0:
            raise InvalidInputError(f"threshold: expected a fraction in [0, 1] or None, got {threshold}")
        r = 0.5 * shape.cell if hole is None else float(hole)
        if not (np.isfinite(r) and r > 0):
            raise InvalidInputError(f"hole: expected a radius > 0 (m), got {hole!r}")
        holes = plate_holes(_core.design_pins(self.before.model, body), r)
        part = shape.realised
        if threshold is None and part is not None:
            return write_dxf(path, outline(shape.centers, part.cells, shape.cell), holes,
                             thinned(part.boxes, shape.centers, shape.cell))
        mask = shape.fill >= (0.5 if threshold is None else threshold)
        _warn_rounded(shape, mask, 0.5 if threshold is None else threshold, "write_dxf")
        return write_dxf(path, outline(shape.centers, mask, shape.cell), holes)

    def table(self) -> str:
        """Before/after RMS and peaks, as text, each quantity with its unit."""
        b, a = self.before.summary(), self.after.summary()
        units = self.before.units()
        rows = [
            f"{'quantity':<40}{'RMS before':>13}{'RMS after':>13}{'peak before':>13}{'peak after':>13}"
        ]
        for k in b:
            rows.append(
                f"{f'{k} ({units[k]})':<40}{b[k]['rms']:>13.5g}{a[k]['rms']:>13.5g}"
                f"{b[k]['peak']:>13.5g}{a[k]['peak']:>13.5g}"
            )
        return "\n".join(rows)
