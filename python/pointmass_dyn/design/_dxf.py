"""A plate link's 2-D outline for laser or water-jet cutting (docs/design.md §4b).

Written by hand as AutoCAD R12 ASCII DXF (group-code/value line pairs; every CAD and CAM tool
reads R12): the boundary of the cells at least ``threshold`` full, seen along the plate's
normal (the body's z axis), as closed POLYLINEs (the outer contour and any inner ones), and
one CIRCLE per pin hole. Units: millimetres (``$INSUNITS`` 4), the body frame's x and y."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InvalidInputError


def _loops(cells: set[tuple[int, int]]) -> list[list[tuple[int, int]]]:
    """Closed boundary loops of a union of unit squares (lower-left corners ``cells``), each
    counter-clockwise around the material, collinear vertices merged."""
    edges: dict[tuple[int, int], list[tuple[int, int]]] = {}
    for i, j in cells:
        # Each square's edges counter-clockwise; an edge shared with a neighbour is interior.
        for (a, b), nb in (
            (((i, j), (i + 1, j)), (i, j - 1)),
            (((i + 1, j), (i + 1, j + 1)), (i + 1, j)),
            (((i + 1, j + 1), (i, j + 1)), (i, j + 1)),
            (((i, j + 1), (i, j)), (i - 1, j)),
        ):
            if nb not in cells:
                edges.setdefault(a, []).append(b)
    loops = []
    while edges:
        start = next(iter(edges))
        loop, here, heading = [start], start, None
        while True:
            outs = edges[here]
            if len(outs) > 1 and heading is not None:
                # A pinch point (two squares touching at a corner): turn left first, so
                # each loop stays one simple polygon.
                def left(b, here=here, heading=heading):
                    d = (b[0] - here[0], b[1] - here[1])
                    return -(heading[0] * d[1] - heading[1] * d[0])
                outs.sort(key=left)
            nxt = outs.pop(0)
            if not outs:
                del edges[here]
            heading = (nxt[0] - here[0], nxt[1] - here[1])
            if nxt == start:
                break
            loop.append(nxt)
            here = nxt
        loops.append(_merge(loop))
    return loops


def _merge(loop: list[tuple[int, int]]) -> list[tuple[int, int]]:
    n = len(loop)
    keep = []
    for k in range(n):
        a, b, c = loop[k - 1], loop[k], loop[(k + 1) % n]
        if (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]) != 0:
            keep.append(b)
    return keep


def outline(centers: np.ndarray, filled: np.ndarray, cell: float) -> list[np.ndarray]:
    """The outline loops (each (P, 2), metres, body frame) of the cells ``filled``, seen
    along z (a column is material where any of its cells is)."""
    c = centers[filled]
    if len(c) == 0:
        return []
    base = centers[:, :2].min(axis=0) - 0.5 * cell
    idx = np.round((c[:, :2] - base) / cell - 0.5).astype(np.int64)
    squares = {(int(i), int(j)) for i, j in idx}
    return [base + cell * np.asarray(loop, float) for loop in _loops(squares)]


def thinned(boxes: np.ndarray, centers: np.ndarray, cell: float) -> list[tuple[np.ndarray, float]]:
    """The realised part's columns holding less material than their stack of cells (polished
    thinner, or joined by single cells): each as its square (4, 2) and its material's
    thickness (m), the sum of its boxes' heights."""
    base = centers[:, :2].min(axis=0)
    key = lambda xy: tuple(int(v) for v in np.round((xy - base) / cell))  # noqa: E731
    stack: dict[tuple, int] = {}
    for c in centers:
        stack[key(c[:2])] = stack.get(key(c[:2]), 0) + 1
    columns: dict[tuple, list] = {}
    for lo, hi in boxes:
        col = columns.setdefault(key(0.5 * (lo[:2] + hi[:2])), [lo[:2], hi[:2], 0.0])
        col[2] += float(hi[2] - lo[2])
    out = []
    for k, (lo, hi, t) in sorted(columns.items()):
        if t < stack.get(k, 0) * cell * (1 - 1e-6):
            out.append((np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]]), t))
    return out


def write_dxf(path: Any, loops: list[np.ndarray], holes: list[tuple[np.ndarray, float]],
              pockets: list[tuple[np.ndarray, float]] = ()) -> Path:
    """Writes ``loops`` (closed polylines) and ``holes`` (centre (2,), radius) in metres as
    an R12 DXF in millimetres; ``pockets`` (square (4, 2), thickness): each on a layer
    ``THICK_<µm>UM``."""
    out = ["0", "SECTION", "2", "HEADER", "9", "$ACADVER", "1", "AC1009",
           "9", "$INSUNITS", "70", "4", "0", "ENDSEC", "0", "SECTION", "2", "ENTITIES"]
    mm = 1000.0
    layered = [(loop, "OUTLINE") for loop in loops]
    layered += [(sq, f"THICK_{round(t * 1e6)}UM") for sq, t in pockets]
    for loop, layer in layered:
        out += ["0", "POLYLINE", "8", layer, "66", "1", "10", "0.0", "20", "0.0",
                "30", "0.0", "70", "1"]
        for x, y in loop:
            out += ["0", "VERTEX", "8", layer, "10", f"{x * mm:.6f}", "20", f"{y * mm:.6f}",
                    "30", "0.0"]
        out += ["0", "SEQEND", "8", layer]
    for centre, radius in holes:
        out += ["0", "CIRCLE", "8", "HOLES", "10", f"{centre[0] * mm:.6f}",
                "20", f"{centre[1] * mm:.6f}", "30", "0.0", "40", f"{radius * mm:.6f}"]
    out += ["0", "ENDSEC", "0", "EOF"]
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text("\n".join(out) + "\n", encoding="ascii")
    return p


def plate_holes(pins: list, hole: float) -> list[tuple[np.ndarray, float]]:
    """The pins' holes in the plate's plane: refused unless every pin axis is along z (a plate
    link cut from sheet)."""
    holes = []
    for point, axis in pins:
        a = np.asarray(axis, float)
        n = np.linalg.norm(a)
        if n > 0 and np.linalg.norm(np.cross(a / n, [0.0, 0.0, 1.0])) > 1e-9:
            raise InvalidInputError(
                f"write_dxf: expected a plate link (every pin axis along the body's z), got an "
                f"axis {a.tolist()}"
            )
        holes.append((np.asarray(point, float)[:2], float(hole)))
    return holes
