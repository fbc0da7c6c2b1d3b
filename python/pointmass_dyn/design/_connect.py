"""Connected links (docs/design.md §3, "Connected links"): the face graph of a link's cells,
its bosses, the flows the conic program holds (``rust/design/connectivity.rs``), and after
the cells are chosen the flood fill that checks the written part and the repair that joins
what thresholding separated."""

from __future__ import annotations

import heapq
from typing import Any

import numpy as np

from ..errors import InvalidInputError

#: Cells' worth of fill a face may carry in the hanging flow, by default (``LinkShape.hang``).
HANG = 16.0


def grid(centers: np.ndarray, cell: float) -> np.ndarray:
    """Integer grid indices (K, 3) of cell ``centers`` (all on one grid of side ``cell``)."""
    return np.round((centers - centers.min(axis=0)) / cell).astype(np.int64)


def _keys(idx: np.ndarray) -> np.ndarray:
    span = idx.max(axis=0) + 3
    return ((idx[:, 0] + 1) * span[1] + idx[:, 1] + 1) * span[2] + idx[:, 2] + 1, span


def faces(idx: np.ndarray) -> np.ndarray:
    """(E, 2) index pairs of cells sharing a face (each pair once, lower index first)."""
    keys, span = _keys(idx)
    order = np.argsort(keys)
    sk = keys[order]
    out = []
    for step in (span[1] * span[2], span[2], 1):  # +x, +y, +z neighbours
        pos = np.searchsorted(sk, keys + step)
        ok = pos < len(sk)
        ok[ok] = sk[pos[ok]] == keys[ok] + step
        a = np.nonzero(ok)[0]
        out.append(np.column_stack([a, order[pos[ok]]]))
    e = np.concatenate(out) if out else np.zeros((0, 2), np.int64)
    return np.sort(e, axis=1)


def neighbours(n: int, edges: np.ndarray) -> list[list[int]]:
    adj: list[list[int]] = [[] for _ in range(n)]
    for a, b in edges:
        adj[a].append(int(b))
        adj[b].append(int(a))
    return adj


def components(mask: np.ndarray, adj: list[list[int]]) -> np.ndarray:
    """Label (K,) of each cell in ``mask`` by its face-connected component (-1 outside)."""
    label = np.full(len(mask), -1, np.int64)
    count = 0
    for s in np.nonzero(mask)[0]:
        if label[s] >= 0:
            continue
        label[s] = count
        stack = [int(s)]
        while stack:
            v = stack.pop()
            for w in adj[v]:
                if mask[w] and label[w] < 0:
                    label[w] = count
                    stack.append(w)
        count += 1
    return label


def bosses(shape: Any, model: Any, centers: np.ndarray) -> list[np.ndarray]:
    """Cell indices of each pin's boss (``LinkShape.pin_cells``), overlapping ones merged,
    then each ``keep`` box's cells: the parts a connected link joins."""
    groups = [g for g in shape.pin_cells(model, centers)]
    for k, g in enumerate(groups):
        if len(g) == 0:
            raise InvalidInputError(
                f"LinkShape '{shape.body}': joint {k} on the link has no cell within its boss "
                "(the envelope does not reach it); a connected link must hold every joint "
                "(widen the envelope or give connected=False)"
            )
    groups += [g for g in shape.keep_cells(centers) if len(g)]
    merged: list[set] = []
    for g in groups:
        s = set(int(v) for v in g)
        for m in [m for m in merged if m & s]:
            s |= m
            merged.remove(m)
        merged.append(s)
    return [np.array(sorted(m), np.int64) for m in merged]


def connected(shape: Any) -> bool:
    """``LinkShape.connected``, checked to be a bool."""
    if not isinstance(shape.connected, (bool, np.bool_)):
        raise InvalidInputError(
            f"connected: expected True or False for LinkShape '{shape.body}', got {shape.connected!r}"
        )
    return bool(shape.connected)


def flow(shape: Any, model: Any, centers: np.ndarray, start: int) -> dict:
    """The flows a connected link's cells hold in the program (design variables from
    ``start``), after checking that its envelope joins its bosses at all."""
    for arg, v, low in (("section", shape.section, 0.0), ("hang", shape.hang, None)):
        if arg == "hang" and v is None:
            continue
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) \
                or not np.isfinite(v) or not (v >= 0 if low == 0.0 else v > 0):
            raise InvalidInputError(
                f"{arg}: expected a finite number {'>= 0 (cell faces)' if low == 0.0 else '> 0 or None'} "
                f"for LinkShape '{shape.body}', got {v!r}"
            )
    idx = grid(centers, shape.cell)
    edges = faces(idx)
    groups = bosses(shape, model, centers)
    label = components(np.ones(len(centers), bool), neighbours(len(centers), edges))
    parts = {int(label[g[0]]) for g in groups}
    if len(parts) > 1:
        raise InvalidInputError(
            f"LinkShape '{shape.body}': its envelope (less keep_out) falls apart into pieces "
            "that separate its joints; a connected link needs cells joining them (or give "
            "connected=False)"
        )
    return {
        "nodes": list(range(start, start + len(centers))),
        "edges": [tuple(e) for e in edges.tolist()],
        "bosses": [g.tolist() for g in groups],
        "web": float(shape.section),
        "hang": float(HANG if shape.hang is None else shape.hang),
    }


def join(solid: np.ndarray, fill: np.ndarray, adj: list[list[int]], groups: list[np.ndarray]) -> np.ndarray:
    """``solid`` (K,) with cells added so that it is one face-connected part holding every
    boss: from the part holding the first boss, the cheapest path (a void cell costs
    ``1 − fill`` plus a little, a solid one nothing) to each other piece, until one is left.
    Deterministic; the added cells are the ones the design filled most."""
    solid = solid.copy()
    for g in groups:
        solid[g] = True
    while True:
        label = components(solid, adj)
        main = label[groups[0][0]]
        others = np.unique(label[solid & (label != main)])
        if len(others) == 0:
            return solid
        path = _cheapest_path(solid, fill, adj, label == main, label == others[0])
        solid[path] = True


def _cheapest_path(solid, fill, adj, source, target) -> list[int]:
    cost = np.where(solid, 0.0, 1.0 - np.clip(fill, 0.0, 1.0) + 1e-3)
    dist = np.full(len(solid), np.inf)
    prev = np.full(len(solid), -1, np.int64)
    heap = []
    for s in np.nonzero(source)[0]:
        dist[s] = 0.0
        heap.append((0.0, int(s)))
    heapq.heapify(heap)
    while heap:
        d, v = heapq.heappop(heap)
        if d > dist[v]:
            continue
        if target[v]:
            path = []
            while prev[v] >= 0 and not source[v]:
                path.append(v)
                v = int(prev[v])
            return path
        for w in adj[v]:
            nd = d + cost[w]
            if nd < dist[w]:
                dist[w], prev[w] = nd, v
                heapq.heappush(heap, (nd, w))
    raise InvalidInputError("links: a connected link's envelope does not join its parts")  # pragma: no cover
