"""Plots of trajectories (matplotlib, imported only when a plot is asked for)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _pyplot():
    try:
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError(
            "plots need matplotlib: pip install 'pointmass-dyn[plot]'"
        ) from exc
    return plt


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


def plot_trajectory(result, model, path: str | Path | None = None, title: str = ""):
    """Joint coordinates and rates against time (angles in degrees), like the paper's
    Figs. 4 and 5, plus the energy when it was recorded. Saves to ``path`` if given."""
    plt = _pyplot()
    qlab, vlab, angular = coordinate_labels(model)
    rows = 3 if result.energy is not None else 2
    fig, axes = plt.subplots(rows, 1, figsize=(8, 2.6 * rows + 0.6), sharex=True)
    q = np.array(result.q, dtype=float)
    v = np.array(result.v, dtype=float)
    ang = np.array(angular, dtype=bool)
    q_show = q.copy()
    if ang.any():
        q_show[:, ang] = np.degrees(q[:, ang])
    for k in range(q.shape[1]):
        axes[0].plot(result.t, q_show[:, k], label=qlab[k])
    axes[0].set_ylabel("q (deg, m, -)")
    for k in range(v.shape[1]):
        axes[1].plot(result.t, v[:, k], label=vlab[k])
    axes[1].set_ylabel("v (rad/s, m/s)")
    if result.energy is not None:
        e = np.asarray(result.energy)
        axes[2].plot(result.t, e - e[0], color="k")
        axes[2].set_ylabel("E − E(0) (J)")
    axes[-1].set_xlabel("t (s)")
    for ax in axes[:2]:
        if q.shape[1] <= 8:
            ax.legend(loc="upper right", fontsize=7, ncol=2)
        ax.grid(alpha=0.3)
    fig.suptitle(title or f"{result.scene}: {result.message}", fontsize=9)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig
