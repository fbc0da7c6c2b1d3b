"""The video form of an animation: GIF (Pillow) or MP4 (ffmpeg) through matplotlib's
animation writers, drawn with mplot3d (docs/visualisation.md §4).

The view is the page's initial camera (azimuth, elevation) in matplotlib's orthographic-ish
3-D axes with equal scales; point masses are screen-space discs (diameter ∝ |m|^(1/3)), not
shaded spheres, drawn over the links, larger before smaller (``computed_zorder`` off).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._helpers import pyplot
from ..errors import AnimationWriterError
from ._drawing import COLOURS, Drawing


def _pyplot():
    return pyplot("GIF and MP4 animations", AnimationWriterError,
                  instead="or write an .html animation, which needs nothing")


def figure(d: Drawing, size: tuple[int, int], dpi: int = 100):
    """The figure of ``d`` at frame 0: ``(fig, ax, update)``, ``update(k)`` moves every
    artist to frame ``k``. The axes' limits never change, so one projection serves all
    frames."""
    plt = _pyplot()
    width, height = size
    fig = plt.figure(figsize=(width / dpi, height / dpi), dpi=dpi)
    ax = fig.add_axes((0, 0, 1, 1), projection="3d")
    ax.computed_zorder = False
    ax.set_axis_off()
    cam = d.camera
    target = np.asarray(cam["target"], dtype=float)
    # A cube around the motion (equal scales), a little larger than its largest extent.
    half = 0.55 * d.extent
    ax.set_xlim(target[0] - half, target[0] + half)
    ax.set_ylim(target[1] - half, target[1] + half)
    ax.set_zlim(target[2] - half, target[2] + half)
    ax.set_box_aspect((1, 1, 1), zoom=1.35)
    ax.view_init(elev=cam["elevation"], azim=cam["azimuth"])

    g = d.grid
    ks = np.arange(-g["half"], g["half"] + 1e-9 * g["half"], g["step"])
    cx, cy, h = g["center"][0], g["center"][1], g["half"]
    # The whole grid as one NaN-separated line (one artist: drawing cost is per artist).
    seg = [[(cx + k, cy - h), (cx + k, cy + h)] for k in ks]
    seg += [[(cx - h, cy + k), (cx + h, cy + k)] for k in ks]
    xy = np.concatenate([np.array(seg), np.full((len(seg), 1, 2), np.nan)], axis=1).reshape(-1, 2)
    ax.plot(xy[:, 0], xy[:, 1], np.full(len(xy), g["z"]), color=COLOURS["grid"], lw=0.5,
            zorder=0.5)
    w = 0.15 * d.size
    for axis, c in zip(np.eye(3), [(0.85, 0.1, 0.1), (0.1, 0.6, 0.1), (0.1, 0.2, 0.85)]):
        ax.plot([0, w * axis[0]], [0, w * axis[1]], [0, w * axis[2]], color=c, lw=1.2, zorder=1)

    trails = [ax.plot([], [], [], color=c, lw=1.2, zorder=1.5)[0] for c in d.trail_colour]
    boxes = [ax.plot([], [], [], color=COLOURS["box"], lw=0.7, zorder=1.8)[0]
             for _ in range(d.boxes.shape[1] // 12)]
    links = [ax.plot([], [], [], color=COLOURS["link"], lw=3.5, solid_capstyle="round",
                     zorder=2)[0]
             for _ in range(d.links.shape[1])]
    axes = [ax.plot([], [], [], color=COLOURS["axis"], lw=2, zorder=2.1)[0]
            for _ in range(d.axes.shape[1])]
    arrow = (ax.plot([], [], [], color=COLOURS["shaking"], lw=2.5, zorder=2.2)[0]
             if d.arrow is not None else None)
    # Disc diameter in points ∝ sphere radius / scene size.
    diam = 2 * d.sphere_radius / d.size * min(width, height) * 1.2 * 72 / dpi
    # Drawing order by zorder (computed_zorder is off): grid, frame, trails, point-mass
    # boxes, links, axes,
    # point masses, cut joints, trail heads.
    # One artist per point mass, largest first: a smaller disc (often a negative mass
    # beside a larger positive one, 2·half-side away) is never hidden behind a larger one.
    order = np.argsort(-d.sphere_radius, kind="stable")
    masses = {
        int(i): ax.scatter(*d.spheres[0, i, :, None], s=diam[i] ** 2, c=[d.sphere_colour[i]],
                           depthshade=False, edgecolors="none", zorder=3)
        for i in order
    }
    cuts = (ax.scatter(*d.cuts[0, :, 0].T, s=60, c=[COLOURS["cut"]], depthshade=False,
                       marker="o", edgecolors="none", zorder=3.5) if d.cuts.shape[1] else None)
    heads = (ax.scatter(*d.trails[0].T, s=40, c=d.trail_colour, depthshade=False,
                        edgecolors="none", zorder=4) if d.trails.shape[1] else None)
    clock = ax.text2D(0.02, 0.96, "", transform=ax.transAxes, family="monospace", fontsize=11)
    if d.title:
        ax.text2D(0.02, 0.91, d.title, transform=ax.transAxes, color="0.35", fontsize=9)
    legend = [("● m > 0", COLOURS["positive"])]
    if np.any(d.sphere_mass < 0):
        legend.append(("● m < 0", COLOURS["negative"]))
    if np.any(d.sphere_mass == 0):
        legend.append(("● m = 0", COLOURS["zero"]))
    legend.append(("disc ∝ |m|^(1/3)", (0.35, 0.35, 0.35)))
    for k, (text, colour) in enumerate(reversed(legend)):
        ax.text2D(0.98, 0.03 + 0.05 * k, text, transform=ax.transAxes, color=colour,
                  fontsize=8, ha="right")

    def update(k: int):
        for i, line in enumerate(boxes):
            # A link's 12 edges as one line, NaN-separated.
            e = d.boxes[k, 12 * i:12 * (i + 1)]
            path = np.concatenate([e, np.full((12, 1, 3), np.nan)], axis=1).reshape(-1, 3)
            line.set_data_3d(path[:, 0], path[:, 1], path[:, 2])
        for line, seg in zip(links, d.links[k]):
            line.set_data_3d(seg[:, 0], seg[:, 1], seg[:, 2])
        for line, seg in zip(axes, d.axes[k]):
            line.set_data_3d(seg[:, 0], seg[:, 1], seg[:, 2])
        for j, line in enumerate(trails):
            p = d.trails[: k + 1, j]
            line.set_data_3d(p[:, 0], p[:, 1], p[:, 2])
        if arrow is not None:
            a, b = d.arrow[k]
            arrow.set_data_3d([a[0], b[0]], [a[1], b[1]], [a[2], b[2]])
        for i, art in masses.items():
            x = d.spheres[k, i]
            art._offsets3d = ([x[0]], [x[1]], [x[2]])
        if cuts is not None:
            c = d.cuts[k, :, 0]
            cuts._offsets3d = (c[:, 0], c[:, 1], c[:, 2])
        if heads is not None:
            h = d.trails[k]
            heads._offsets3d = (h[:, 0], h[:, 1], h[:, 2])
        clock.set_text(f"t = {d.times[k]:.3f} s")
        return []

    update(0)
    fig.pmd_masses = masses  # the artist of each point mass, for tests
    return fig, ax, update


def write_video(d: Drawing, path: Path, *, fps: float, size: tuple[int, int], dpi: int) -> None:
    """Writes ``d.nframes`` frames of ``size`` pixels to ``path`` (.gif or .mp4)."""
    plt = _pyplot()
    from matplotlib import animation

    if Path(path).suffix.lower() == ".mp4":
        if not animation.writers.is_available("ffmpeg"):
            raise AnimationWriterError(
                f"path: writing '{path}' (MP4) needs ffmpeg, which was not found on PATH; "
                "install it (e.g. apt-get install ffmpeg, conda install ffmpeg) or write a "
                ".gif or .html animation instead"
            )
        writer = animation.FFMpegWriter(fps=fps, codec="libx264",
                                        extra_args=["-pix_fmt", "yuv420p"])
        if size[0] % 2 or size[1] % 2:
            raise AnimationWriterError(
                f"size: MP4 (H.264, yuv420p) needs an even width and height, got {size}"
            )
    else:
        try:
            import PIL  # noqa: F401
        except ImportError as exc:  # pragma: no cover - matplotlib depends on Pillow
            raise AnimationWriterError("GIF animations need Pillow: pip install pillow") from exc
        writer = animation.PillowWriter(fps=fps)
    fig, _ax, update = figure(d, size, dpi)
    try:
        # The writer's own loop (not FuncAnimation.save, which draws every frame twice).
        with writer.saving(fig, str(path), dpi):
            for k in range(d.nframes):
                update(k)
                writer.grab_frame()
    finally:
        plt.close(fig)
