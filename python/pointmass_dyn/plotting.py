"""Plots (matplotlib, imported only when a plot is asked for): trajectories, shaking and
balancing (:mod:`pointmass_dyn.design`), sweeps."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._helpers import pyplot, rms


def coordinate_labels(model) -> tuple[list[str], list[str], list[bool]]:
    """Labels for q and v, and which q entries are angles (shown in degrees)."""
    qlab, vlab, angular = [], [], []
    for name in model.link_names:
        kind = model.body_info(model.body_names.index(name))[1]
        if kind == "SphericalZYZ":
            qlab += [f"{name} φ", f"{name} θ", f"{name} ψ"]
            vlab += [f"{name} dφ/dt", f"{name} dθ/dt", f"{name} dψ/dt"]
            angular += [True] * 3
        elif kind == "Spherical":
            qlab += [f"{name} q{c}" for c in "xyzw"]
            vlab += [f"{name} ω{c}" for c in "xyz"]
            angular += [False] * 4
        elif kind == "FreeFlyer":
            qlab += [f"{name} {c}" for c in "xyz"] + [f"{name} q{c}" for c in "xyzw"]
            vlab += [f"{name} v{c}" for c in "xyz"] + [f"{name} ω{c}" for c in "xyz"]
            angular += [False] * 7
        else:
            qlab.append(f"{name} q")
            vlab.append(f"{name} dq/dt")
            angular.append(kind == "Revolute")
    return qlab, vlab, angular


def coordinate_units(model) -> tuple[list[str], list[str]]:
    """The quantity of each q entry (``"angle"``, ``"length"``, ``"quaternion"``) and of each v
    entry (``"angular rate"``, ``"linear rate"``), in the order of q and v."""
    qu, vu = [], []
    for name in model.link_names:
        kind = model.body_info(model.body_names.index(name))[1]
        if kind == "SphericalZYZ":
            qu += ["angle"] * 3
            vu += ["angular rate"] * 3
        elif kind == "Spherical":
            qu += ["quaternion"] * 4
            vu += ["angular rate"] * 3
        elif kind == "FreeFlyer":
            qu += ["length"] * 3 + ["quaternion"] * 4
            vu += ["linear rate"] * 3 + ["angular rate"] * 3
        elif kind == "Revolute":
            qu.append("angle")
            vu.append("angular rate")
        else:
            qu.append("length")
            vu.append("linear rate")
    return qu, vu


# One unit system per figure: degrees for every angle and angular rate (SI otherwise); each
# panel holds one quantity, its label says which and in what unit.
_PANELS = {
    "angle": ("joint angle (deg)", np.degrees(1.0)),
    "length": ("joint position (m)", 1.0),
    "quaternion": ("orientation quaternion (–)", 1.0),
    "angular rate": ("angular rate (deg/s)", np.degrees(1.0)),
    "linear rate": ("linear rate (m/s)", 1.0),
}


def plot_trajectory(result, model, path: str | Path | None = None, title: str = ""):
    """Joint coordinates and rates against time, one panel per quantity (angles and angular
    rates in degrees), like the paper's Figs. 4 and 5, plus the energy drift when it was
    recorded. The title names the scene (``title`` or ``result.scene``), the method and, for a
    failed run, why it stopped. Saves to ``path`` if given."""
    plt = pyplot()
    qlab, vlab, _ = coordinate_labels(model)
    qu, vu = coordinate_units(model)
    q = np.array(result.q, dtype=float)
    v = np.array(result.v, dtype=float)
    series = [(u, q, qu, qlab) for u in ("angle", "length", "quaternion") if u in qu]
    series += [(u, v, vu, vlab) for u in ("angular rate", "linear rate") if u in vu]
    rows = len(series) + (result.energy is not None)
    fig, axes = plt.subplots(rows, 1, figsize=(9, 2.2 * rows + 0.8), sharex=True, squeeze=False)
    axes = axes[:, 0]
    for ax, (unit, data, units, labels) in zip(axes, series):
        label, scale = _PANELS[unit]
        cols = [k for k, u in enumerate(units) if u == unit]
        for k in cols:
            ax.plot(result.t, scale * data[:, k], label=labels[k], lw=1.2)
        ax.set_ylabel(label, fontsize=8)
        ax.grid(alpha=0.3)
        if len(cols) <= 12:  # beside the panel, never over the curves
            ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    if result.energy is not None:
        e = np.asarray(result.energy)
        axes[-1].plot(result.t, e - e[0], color="k", lw=1.0)
        axes[-1].set_ylabel("energy drift\nE − E(0) (J)", fontsize=8)
        axes[-1].grid(alpha=0.3)
    axes[-1].set_xlabel("time t (s)")
    name = title or result.scene or "simulation"
    t_end = float(result.t[-1]) if len(result.t) else 0.0
    head = f"{name}: {result.method}, {len(result.t)} samples to t = {t_end:g} s"
    if not result.success:
        head += f"\nstopped: {result.message}"
    fig.suptitle(head, fontsize=10)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


# --------------------------------------------------------------------------------------------
# Shaking forces and balancing (pointmass_dyn.design)
# --------------------------------------------------------------------------------------------
_AXES = "xyz"
_BEFORE, _AFTER = "#1f5fa8", "#d1495b"


def _planar_axis(*vectors) -> int | None:
    """The one world axis along which all the (N, 3) series have something (a moment of a
    planar mechanism), or None if more than one axis carries a share above 1e-9."""
    rms = np.sqrt(sum(np.mean(np.asarray(v, float) ** 2, axis=0) for v in vectors))
    big = rms.max()
    if big == 0.0:
        return 2
    active = np.flatnonzero(rms > 1e-9 * big)
    return int(active[0]) if len(active) == 1 else None


def _force_plane(*vectors) -> tuple[int, int, int | None]:
    """The two world axes the shaking-force locus is drawn in and the axis left out, if it
    carries anything (a spatial mechanism): x–y unless the force lies in x–z or y–z."""
    rms = np.sqrt(sum(np.mean(np.asarray(v, float) ** 2, axis=0) for v in vectors))
    big = rms.max()
    quiet = [k for k in range(3) if rms[k] <= 1e-9 * big] if big > 0 else [2]
    if quiet and quiet[-1] != 2 and 2 not in quiet:
        off = quiet[-1]
        i, j = (k for k in range(3) if k != off)
        return i, j, None
    return 0, 1, (None if 2 in quiet else 2)


def _driver_axis(analysis):
    """x values, axis label and the unit of the driving force for an analysis: the input
    angle in degrees (a revolute driver), its position (prismatic) or, for an input that
    goes back and forth or none, the time."""
    model = analysis.model
    x = None if analysis.input is None else np.asarray(analysis.input, dtype=float)
    steps = np.diff(x) if x is not None else np.zeros(0)
    monotonic = x is not None and (np.all(steps > 0) or np.all(steps < 0))
    if monotonic and analysis.input_name is not None:
        kind = model.body_info(model.body_names.index(analysis.input_name))[1]
        if kind == "Revolute":
            return (np.degrees(analysis.input), f"{analysis.input_name} angle (deg)", "N·m")
        return np.asarray(analysis.input), f"{analysis.input_name} position (m)", "N"
    unit = "N or N·m"
    if analysis.input_name is not None:
        kind = model.body_info(model.body_names.index(analysis.input_name))[1]
        unit = "N·m" if kind == "Revolute" else "N"
    return np.asarray(analysis.t), "t (s)", unit


def _driven_columns(analysis) -> list[tuple[int, str]]:
    """(v index, label) of each driving force shown: the actuated coordinates, else all."""
    model = analysis.model
    cols = analysis.actuated if analysis.actuated is not None else range(analysis.tau.shape[1])
    names = {}
    for link, (_, iv, _, nv) in enumerate(model.joint_slices()):
        for k in range(nv):
            names[iv + k] = model.link_names[link] + (f" [{k}]" if nv > 1 else "")
    return [(int(c), names.get(int(c), f"v[{c}]")) for c in cols]


def _joint_labels(model) -> list[str]:
    """One label per moving link's joint (parent–link) and then per cut joint."""
    out = []
    for name in model.link_names:
        parent = model.body_info(model.body_names.index(name))[2]
        out.append(f"{'ground' if parent < 0 else model.body_names[parent]}–{name}")
    return out + [f"{n} (cut)" for n in model.loop_names]


def _bearing_series(analysis) -> np.ndarray:
    """|force| of each joint per instant, (N, nlinks + nloops)."""
    f = [np.linalg.norm(analysis.bearing[:, i, :3], axis=1) for i in range(analysis.bearing.shape[1])]
    f += [np.linalg.norm(analysis.cut[:, k, :3], axis=1) for k in range(analysis.cut.shape[1])]
    return np.array(f).T.reshape(len(analysis.t), -1)


def _g(x: float) -> str:
    return f"{x:.3g}"


def _mass_text(m: float) -> str:
    return f"{m:.4g} kg" if abs(m) >= 1.0 else f"{1e3 * m:.4g} g"


def _point_text(p, scale: float | None = None) -> str:
    p = np.asarray(p, dtype=float)
    if scale is None:
        scale = 1e3 if np.abs(p).max(initial=0.0) < 1.0 else 1.0
    unit = "mm" if scale == 1e3 else "m"
    vals = [0.0 if abs(x * scale) < 5e-10 else x * scale for x in p]
    return "(" + ", ".join(f"{v:.4g}" for v in vals) + f") {unit}"


def balance_caption(balance) -> str:
    """The counterweights placed and the redesigned bodies, one line each (body frame)."""
    lines = []
    for body, pos, mass in balance.counterweights:
        lines.append(
            f"counterweight on {body}: {_mass_text(mass)} at {_point_text(pos)} ({body} frame)"
        )
    redesigned = {b for b in balance.bodies} - {c[0] for c in balance.counterweights}
    for name in sorted(redesigned):
        rb = balance.bodies[name]
        lines.append(
            f"{name} redesigned: {_mass_text(rb.mass)}, COM {_point_text(rb.com)} ({name} frame)"
        )
    if not lines:
        lines.append("no mass added")
    return "\n".join(lines)


def _polar_panel(ax, series, x_deg, plane, revolute: bool, closed: bool):
    """The locus of the shaking force vector's tip (F_j against F_i) over the motion, closed
    over a whole cycle."""
    i, j, off = plane
    for f, color, style, label in series:
        fi = np.append(f[:, i], f[:1, i]) if closed else f[:, i]
        fj = np.append(f[:, j], f[:1, j]) if closed else f[:, j]
        ax.plot(fi, fj, style, color=color, lw=1.6, label=label)
    f0, color = series[0][0], series[0][1]
    size0 = max(np.ptp(f0[:, i]), np.ptp(f0[:, j]))
    for f, c, _, _ in series[1:]:
        # A locus balanced away shrinks to a point: show where it is.
        if max(np.ptp(f[:, i]), np.ptp(f[:, j])) <= 1e-3 * size0:
            ax.plot(f[:, i].mean(), f[:, j].mean(), "o", ms=7, color=c, zorder=5)
    if revolute and len(f0) >= 8:
        # The input angle along the first locus at each multiple of 90° it passes (open
        # circles) and at the start of the cycle (filled), which shows the sense of travel.
        ax.plot(f0[0, i], f0[0, j], "o", ms=5, color=color, zorder=3)
        lo, hi = x_deg.min(), x_deg.max()
        step = np.median(np.abs(np.diff(x_deg)))
        for mark in np.arange(90 * np.ceil(lo / 90), hi + 0.5 * step, 90):
            idx = int(np.argmin(np.abs(x_deg - mark)))
            if abs(x_deg[idx] - mark) > 0.5 * step + 1e-9:
                continue
            ax.plot(f0[idx, i], f0[idx, j], "o", ms=5, color=color, mfc="white", zorder=3)
            ax.annotate(f"{mark % 360:.0f}°", (f0[idx, i], f0[idx, j]), xytext=(5, 4),
                        textcoords="offset points", fontsize=7, color=color)
    ax.axhline(0.0, color="0.75", lw=0.8, zorder=0)
    ax.axvline(0.0, color="0.75", lw=0.8, zorder=0)
    ax.plot([0], [0], "k+", ms=12, mew=1.5, zorder=4)
    ax.set_aspect("equal", adjustable="datalim")
    # Keep the origin in view, with a margin.
    xs = np.concatenate([s[0][:, i] for s in series] + [[0.0]])
    ys = np.concatenate([s[0][:, j] for s in series] + [[0.0]])
    pad = 0.08 * max(np.ptp(xs), np.ptp(ys), 1e-300)
    ax.update_datalim([[xs.min() - pad, ys.min() - pad], [xs.max() + pad, ys.max() + pad]])
    ax.set_xlabel(f"shaking force F{_AXES[i]} (N)")
    ax.set_ylabel(f"shaking force F{_AXES[j]} (N)")
    note = "" if off is None else f"  (F{_AXES[off]} not drawn)"
    ax.set_title("(a) shaking force polar diagram" + note, fontsize=9, loc="left")
    ax.legend(fontsize=7, loc="best")
    ax.grid(alpha=0.3)


def _balance_figure(analyses, labels, colors, title, caption, path):
    """The four panels for one or two analyses of one motion (before, after)."""
    plt = pyplot()
    first = analyses[0]
    x, xlabel, tau_unit = _driver_axis(first)
    revolute = xlabel.endswith("(deg)")
    # A whole number of turns sampled with the end left out: the locus closes.
    step = float(np.median(np.abs(np.diff(x)))) if revolute and len(x) > 1 else 0.0
    turns = (np.ptp(x) + step) / 360.0 if revolute else 0.0
    closed = revolute and turns >= 0.999 and abs(turns - round(turns)) < 1e-6
    forces = [a.shaking.force for a in analyses]
    moments = [a.shaking.moment for a in analyses]
    styles = ["-", "--"]
    fig, axes = plt.subplots(2, 2, figsize=(11.5, 8.6))
    (ax_a, ax_b), (ax_c, ax_d) = axes

    # (a) polar diagram of the shaking force.
    series = [
        (f, c, s, f"{lab} (RMS {_g(rms(f))} N)")
        for f, c, s, lab in zip(forces, colors, styles, labels)
    ]
    _polar_panel(ax_a, series, x, _force_plane(*forces), revolute, closed)

    # (b) shaking moment: its one component for a planar mechanism, else its magnitude.
    axis = _planar_axis(*moments)
    for m, c, s, lab in zip(moments, colors, styles, labels):
        y = m[:, axis] if axis is not None else np.linalg.norm(m, axis=1)
        ax_b.plot(x, y, s, color=c, lw=1.6, label=f"{lab} (RMS {_g(rms(m))} N·m)")
    about = np.asarray(first.shaking.about, dtype=float)
    where = "the origin" if not np.any(about) else _point_text(about)
    name = f"M{_AXES[axis]}" if axis is not None else "|M|"
    ax_b.set_ylabel(f"shaking moment {name} (N·m)")
    ax_b.set_title(f"(b) shaking moment about {where}", fontsize=9, loc="left")

    # (c) driving force(s).
    cols = _driven_columns(first)
    for a_, c, s, lab in zip(analyses, colors, styles, labels):
        for n, (col, cname) in enumerate(cols):
            y = a_.tau[:, col]
            text = f"{lab} (RMS {_g(rms(y))} {tau_unit})"
            if len(cols) > 1:
                text = f"{cname}, {text}"
            ax_c.plot(x, y, s, color=c if len(cols) == 1 else f"C{n % 10}", lw=1.6, label=text)
    ax_c.axhline(0.0, color="0.75", lw=0.8, zorder=0)
    what = "torque" if tau_unit == "N·m" else "force"
    ax_c.set_ylabel(f"driving {what} ({tau_unit})")
    driver = ", ".join(n for _, n in cols) if len(cols) <= 3 else f"{len(cols)} coordinates"
    ax_c.set_title(f"(c) driving {what} ({driver})", fontsize=9, loc="left")

    # (d) bearing force magnitudes, one colour per joint, before solid, after dashed.
    jl = _joint_labels(first.model)
    for a_, s in zip(analyses, styles):
        b = _bearing_series(a_)
        for k in range(b.shape[1]):
            ax_d.plot(x, b[:, k], s, color=f"C{k % 10}", lw=1.4,
                      label=jl[k] if a_ is first else None)
    ax_d.set_ylabel("bearing force magnitude (N)")
    ax_d.set_title("(d) joint (bearing) forces, gravity included", fontsize=9, loc="left")
    handles, hl = ax_d.get_legend_handles_labels()
    if len(analyses) > 1:
        from matplotlib.lines import Line2D

        handles += [Line2D([], [], color="0.3", ls=s) for s in styles[: len(analyses)]]
        hl += labels
    ax_d.legend(handles, hl, fontsize=7, ncol=2 if len(hl) > 6 else 1, loc="best")
    ax_d.set_ylim(bottom=0.0)

    for ax in (ax_b, ax_c, ax_d):
        ax.set_xlabel(xlabel)
        ax.grid(alpha=0.3)
        if revolute:
            lo, hi = float(np.min(x)), float(np.max(x))
            ax.set_xlim(lo, max(hi, lo + 1e-9))
            if hi - lo > 180:
                ax.set_xticks(np.arange(90 * np.ceil(lo / 90), hi + 1e-9, 90))
    for ax in (ax_a, ax_b, ax_c, ax_d):
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 4))
    ax_a.ticklabel_format(axis="x", style="sci", scilimits=(-3, 4))
    for ax in (ax_b, ax_c):
        ax.axhline(0.0, color="0.75", lw=0.8, zorder=0)
        ax.legend(fontsize=7, loc="best")

    fig.suptitle(title, fontsize=11)
    bottom = 0.0
    if caption:
        nlines = caption.count("\n") + 1
        bottom = min(0.03 + 0.022 * nlines, 0.3)
        fig.text(0.01, 0.008, caption, fontsize=8, va="bottom", ha="left", family="monospace")
    fig.tight_layout(rect=(0.0, bottom, 1.0, 0.97))
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


def plot_motion(analysis, path: str | Path | None = None, title: str = ""):
    """Shaking and reactions along one :class:`~pointmass_dyn.MotionAnalysis`: (a) the polar
    diagram of the shaking force (the locus of its tip, equal axes, origin marked), (b) the
    shaking moment (its one component for a planar mechanism, else its magnitude), (c) the
    driving force, (d) each joint's bearing force magnitude, against the input angle in
    degrees (or the driver's position, or time). Saves to ``path`` if given."""
    return _balance_figure(
        [analysis], ["unbalanced"], [_BEFORE],
        title or "Shaking force, moment, driving torque and bearing forces", "", path,
    )


def plot_balance(balance, path: str | Path | None = None, title: str = ""):
    """The panels of :func:`plot_motion` for a :class:`~pointmass_dyn.Balance`, before
    (solid) and after (dashed), with the counterweights placed (body, mass, position in the
    body frame) and the redesigned bodies in the caption. Saves to ``path`` if given."""
    return _balance_figure(
        [balance.before, balance.after], ["before", "after"], [_BEFORE, _AFTER],
        title or "Balancing: before and after", balance_caption(balance), path,
    )


_UNITS = {"force": "N", "moment": "N·m", "torque": "N·m"}


def objective_rms(analysis, what: str) -> float:
    """RMS over the cycle of the shaking force, the shaking moment or the driving force(s)."""
    if what == "force":
        return rms(analysis.shaking.force)
    if what == "moment":
        return rms(analysis.shaking.moment)
    cols = [c for c, _ in _driven_columns(analysis)]
    return rms(analysis.tau[:, cols])


def plot_pareto(front, objectives=("force", "moment"), path: str | Path | None = None,
                title: str = ""):
    """The RMS pairs of a :func:`~pointmass_dyn.pareto_front` (one point per weighting), with
    the unbalanced mechanism's pair. Saves to ``path`` if given."""
    plt = pyplot()
    first, second = objectives
    xs = np.array([objective_rms(b.after, first) for b in front])
    ys = np.array([objective_rms(b.after, second) for b in front])
    fig, ax = plt.subplots(figsize=(6.4, 5.0))
    ax.plot(xs, ys, "o-", color=_AFTER, lw=1.4, ms=5, label="balanced (weights swept)")
    if front:
        x0, y0 = objective_rms(front[0].before, first), objective_rms(front[0].before, second)
        ax.plot([x0], [y0], "*", color=_BEFORE, ms=13, label="unbalanced")
        # Each point's weight of the second objective, where the labels do not crowd.
        span = np.array([max(np.ptp(np.append(xs, x0)), 1e-300),
                         max(np.ptp(np.append(ys, y0)), 1e-300)])
        last = None
        for b, x, y in zip(front, xs, ys):
            here = np.array([x, y]) / span
            if last is not None and np.linalg.norm(here - last) < 0.06:
                continue
            last = here
            w = b.objective.get(second, 0.0) / max(sum(b.objective.values()), 1e-300)
            ax.annotate(f"{w:.2f}", (x, y), xytext=(5, 3), textcoords="offset points",
                        fontsize=7, color="0.3")
    ax.set_xlabel(f"RMS shaking {first} ({_UNITS[first]})" if first != "torque"
                  else f"RMS driving torque ({_UNITS[first]})")
    ax.set_ylabel(f"RMS shaking {second} ({_UNITS[second]})" if second != "torque"
                  else f"RMS driving torque ({_UNITS[second]})")
    ax.set_xlim(left=0.0)
    ax.set_ylim(bottom=0.0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title or f"Pareto front: {first} against {second} "
                 f"(labels: weight of {second})", fontsize=9)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig


# --------------------------------------------------------------------------------------------
# Sweeps (pointmass-dyn sweep)
# --------------------------------------------------------------------------------------------
def plot_sweep(t, q, success, q_labels, angular, param_names, param_values, coord: int,
               path: str | Path | None = None, title: str = ""):
    """A sweep's runs: coordinate ``coord`` against time over the successful runs (median,
    25–75 % and 5–95 % bands, a few runs drawn), its final value against the first swept
    parameter (coloured by the second, if any; a histogram when nothing was swept), and
    the spread of every coordinate's final value. Angles in degrees. Saves to ``path``."""
    plt = pyplot()
    q = np.asarray(q, dtype=float)[np.asarray(success, dtype=bool)]
    values = np.asarray(param_values, dtype=float).reshape(len(success), -1)
    values = values[np.asarray(success, dtype=bool)]
    scale = np.where(np.asarray(angular, dtype=bool), 180.0 / np.pi, 1.0)
    q = q * scale
    last = q_labels[coord].split()[-1]
    unit = "deg" if angular[coord] else ("-" if last in ("qx", "qy", "qz", "qw") else "m")
    fig = plt.figure(figsize=(11, 7.2))
    grid = fig.add_gridspec(2, 2, height_ratios=(1.15, 1.0))
    fan = fig.add_subplot(grid[0, :])
    final_ax = fig.add_subplot(grid[1, 0])
    box = fig.add_subplot(grid[1, 1])
    y = q[:, :, coord]
    if len(y):
        lo5, lo25, med, hi75, hi95 = np.percentile(y, [5, 25, 50, 75, 95], axis=0)
        fan.fill_between(t, lo5, hi95, color=_BEFORE, alpha=0.18, lw=0, label="5–95 %")
        fan.fill_between(t, lo25, hi75, color=_BEFORE, alpha=0.38, lw=0, label="25–75 %")
        pick = np.linspace(0, len(y) - 1, min(len(y), 12)).astype(int)
        pick = np.unique(pick)
        for n, k in enumerate(pick):
            fan.plot(t, y[k], color="0.35", lw=0.5, alpha=0.6,
                     label=f"{len(pick)} of the runs" if n == 0 else None)
        fan.plot(t, med, color=_AFTER, lw=1.8, label="median")
        fan.legend(loc="upper left", fontsize=8, ncol=4)
    else:
        fan.text(0.5, 0.5, "no successful run", ha="center", va="center",
                 transform=fan.transAxes)
    fan.set_xlabel("t (s)")
    fan.set_ylabel(f"q[{coord}] {q_labels[coord]} ({unit})")
    fan.set_xlim(t[0], t[-1])
    fan.grid(alpha=0.3)
    fan.set_title(f"q[{coord}] ({q_labels[coord]}) over {len(y)} successful runs", fontsize=9)

    final = y[:, -1] if len(y) else np.zeros(0)
    if param_names and len(final):
        x = values[:, 0]
        second = np.unique(values[:, 1]) if len(param_names) > 1 else None
        if second is not None and len(second) <= 8:
            # One line (the median over the runs at each value) per value of the second.
            colors = plt.get_cmap("viridis")(np.linspace(0.0, 0.85, len(second)))
            for u, c in zip(second, colors):
                on = values[:, 1] == u
                xs = np.unique(x[on])
                final_ax.plot(x[on], final[on], "o", color=c, ms=4, alpha=0.6)
                final_ax.plot(xs, [np.median(final[on][x[on] == w]) for w in xs], "-",
                              color=c, lw=1.4, label=f"{param_names[1]} = {u:g}")
            final_ax.legend(fontsize=7)
        elif second is not None:
            sc = final_ax.scatter(x, final, c=values[:, 1], cmap="viridis", s=18,
                                  edgecolors="none")
            fig.colorbar(sc, ax=final_ax, label=param_names[1])
        else:
            final_ax.plot(x, final, "o", color=_BEFORE, ms=4, alpha=0.7)
            xs = np.unique(x)
            if len(xs) > 1:
                meds = [np.median(final[x == u]) for u in xs]
                final_ax.plot(xs, meds, "-", color=_AFTER, lw=1.4, label="median")
                final_ax.legend(fontsize=8)
        final_ax.set_xlabel(param_names[0])
        final_ax.set_ylabel(f"final q[{coord}] ({unit})")
        final_ax.set_title(f"q[{coord}] at t = {t[-1]:g} s against {param_names[0]}",
                           fontsize=9)
    elif len(final):
        final_ax.hist(final, bins=min(30, max(5, len(final) // 4)), color=_BEFORE, alpha=0.8)
        final_ax.set_xlabel(f"final q[{coord}] ({unit})")
        final_ax.set_ylabel("runs")
        final_ax.set_title(f"q[{coord}] at t = {t[-1]:g} s", fontsize=9)
    final_ax.grid(alpha=0.3)

    if len(q):
        nq = q.shape[2]
        box.boxplot([q[:, -1, k] for k in range(nq)], whis=(5, 95), showfliers=True,
                    flierprops={"markersize": 2}, medianprops={"color": _AFTER})
        box.set_xticks(range(1, nq + 1))
        box.set_xticklabels([f"{k}" for k in range(nq)], fontsize=8)
        if nq <= 10:
            box.set_xticklabels([lab.removesuffix(" q").replace(" ", "\n") for lab in q_labels],
                                fontsize=7)
    box.set_ylabel("final q (deg for angles)")
    box.set_title(f"every coordinate at t = {t[-1]:g} s (box 25–75 %, whiskers 5–95 %)",
                  fontsize=9)
    box.grid(alpha=0.3, axis="y")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig
