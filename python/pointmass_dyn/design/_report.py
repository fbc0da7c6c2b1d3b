"""A design report (docs/design.md §4c): one self-contained HTML page, its figures
(matplotlib, Agg) embedded as base64 PNGs — each link's outline and density map, before/after
polar plots of the shaking force and moment, the bearing forces over the cycle, the mass and
safety-factor table, the solver's status and time."""

from __future__ import annotations

import base64
import html
import io
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InvalidInputError
from ._dxf import outline


def _pyplot():
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise InvalidInputError(
            "report: expected matplotlib for the figures (pip install matplotlib), got none"
        ) from None
    return plt


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100, bbox_inches="tight")
    fig.clf()
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _img(data: str, alt: str) -> str:
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{data}">'


def _angle(a) -> tuple[np.ndarray, str]:
    """The motion's input (the crank angle) when it has one, else the phase of the cycle."""
    if a.input is not None:
        return np.asarray(a.input, float), f"{a.input_name or 'input'} (rad)"
    t = np.asarray(a.t, float)
    span = (t[-1] - t[0]) or 1.0
    return 2 * np.pi * (t - t[0]) / span, "phase of the cycle (rad)"


def _with_input(a, before):
    """``a`` with the motion's input (a re-analysis along the same motion has none)."""
    if a.input is None and before.input is not None:
        return replace(a, input=before.input, input_name=before.input_name)
    return a


def _shape_figure(plt, name: str, shape, strength) -> str:
    idx = np.round((shape.centers[:, :2] - shape.centers[:, :2].min(axis=0)) / shape.cell).astype(int)
    grid = np.zeros(idx.max(axis=0) + 1)
    count = np.zeros_like(grid)
    np.add.at(grid, (idx[:, 0], idx[:, 1]), shape.fill)
    np.add.at(count, (idx[:, 0], idx[:, 1]), 1.0)
    image = np.where(count > 0, grid / np.maximum(count, 1), np.nan)
    lo = shape.centers[:, :2].min(axis=0) - shape.cell / 2
    hi = shape.centers[:, :2].max(axis=0) + shape.cell / 2
    fig, ax = plt.subplots(figsize=(6, 3.2))
    im = ax.imshow(image.T, origin="lower", extent=(lo[0], hi[0], lo[1], hi[1]), cmap="viridis",
                   vmin=0.0, vmax=1.0)
    fig.colorbar(im, ax=ax, label="fill, mean through z")
    for loop in outline(shape.centers, shape.fill >= 0.5, shape.cell):
        closed = np.vstack([loop, loop[:1]])
        ax.plot(closed[:, 0], closed[:, 1], color="w", lw=1.2)
    if strength is not None:
        for p in strength.pins:
            ax.plot(p["point"][0], p["point"][1], "r+", ms=10)
    ax.set_xlabel("x (m, body frame)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"{name}: {shape.mass:.4g} kg (outline: cells at least half full)")
    out = _png(fig)
    plt.close(fig)
    return out


def _polar_figure(plt, b) -> str:
    fig = plt.figure(figsize=(10, 4.2))
    ax1 = fig.add_subplot(1, 2, 1, projection="polar")
    ax2 = fig.add_subplot(1, 2, 2, projection="polar")
    for a, label, style in ((b.before, "before", "--"), (b.after, "after", "-")):
        a = _with_input(a, b.before)
        # The cycle closed: its last sample joined to its first.
        f = np.vstack([a.shaking.force, a.shaking.force[:1]])
        ax1.plot(np.arctan2(f[:, 1], f[:, 0]), np.hypot(f[:, 0], f[:, 1]), style, label=label)
        ang, _ = _angle(a)
        m = np.asarray(a.shaking.moment)
        ax2.plot(np.append(ang, ang[0]), np.abs(np.append(m[:, 2], m[0, 2])), style, label=label)
    ax1.set_title("shaking force (N): tip of (Fx, Fy)")
    ax2.set_title("|shaking moment Mz| (N·m) over the input angle")
    ax1.legend(loc="lower left", fontsize=8)
    out = _png(fig)
    plt.close(fig)
    return out


def _bearing_figure(plt, b) -> str:
    model = b.before.model
    names = list(model.link_names) + list(model.loop_names)
    fig, ax = plt.subplots(figsize=(10, 3.8))
    for a, style in ((b.before, "--"), (b.after, "-")):
        ang, xlabel = _angle(_with_input(a, b.before))
        f = np.concatenate([a.bearing[:, :, :3], a.cut[:, :, :3]], axis=1)
        for k, name in enumerate(names):
            ax.plot(ang, np.linalg.norm(f[:, k], axis=1), style, color=f"C{k % 10}",
                    label=name if style == "-" else None)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("bearing force (N)")
    ax.set_title("bearing forces over the cycle (dashed: before, solid: after)")
    ax.legend(fontsize=8, ncol=4)
    out = _png(fig)
    plt.close(fig)
    return out


def _table(header: list[str], rows: list[list[Any]]) -> str:
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>" for r in rows
    )
    return f"<table><tr>{head}</tr>{body}</table>"


def _mass_rows(b) -> list[list[Any]]:
    rows = []
    for name, body in b.bodies.items():
        before = b.before.model.body(name)
        s = b.strength.get(name)
        where = "-"
        safety = "-"
        if s is not None and np.isfinite(s.safety):
            safety = f"{s.safety:.3g} ({s.material.name})"
            ang = "" if s.input is None else f", input {s.input:.3f} rad"
            where = (f"t = {s.t:.4g} s{ang}, member {s.member}, "
                     f"{s.section * 1e3:.1f} mm from its first pin")
        rows.append([name, f"{before.mass:.4g}", f"{body.mass:.4g}",
                     np.array2string(np.asarray(body.com), precision=4), safety, where])
    return rows


def write_report(b, path: Any) -> Path:
    """Writes the report of design ``b`` (a :class:`Balance`) to ``path`` (HTML)."""
    plt = _pyplot()
    s = b.solver
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>pointmass_dyn design "
             "report</title><style>body{font-family:sans-serif;max-width:1100px;margin:auto}"
             "table{border-collapse:collapse}td,th{border:1px solid #999;padding:3px 8px}"
             "img{max-width:100%}</style></head><body><h1>Design report</h1>"]
    parts.append(_table(["solver status", "relative gap", "iterations", "programs",
                         "solver time (s)", "total time (s)", "norm"],
                        [[s.get("status"), f"{s.get('gap_rel', float('nan')):.1e}",
                          s.get("iterations"), s.get("rounds"),
                          f"{s.get('solve_time', float('nan')):.3f}",
                          f"{s.get('time', float('nan')):.3f}", s.get("norm")]]))
    parts.append("<h2>Masses and safety factors</h2>")
    parts.append(_table(["body", "mass before (kg)", "mass after (kg)", "COM after (m)",
                         "least safety factor", "where"], _mass_rows(b)))
    parts.append("<h2>Before and after</h2><pre>" + html.escape(b.table()) + "</pre>")
    parts.append("<h2>Shaking</h2>" + _img(_polar_figure(plt, b), "shaking polar plots"))
    parts.append("<h2>Bearing forces</h2>" + _img(_bearing_figure(plt, b), "bearing forces"))
    parts.append("<h2>Links</h2>")
    for name, shape in b.shapes.items():
        parts.append(_img(_shape_figure(plt, name, shape, b.strength.get(name)), name))
    parts.append("</body></html>")
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text("\n".join(parts), encoding="utf-8")
    return p
