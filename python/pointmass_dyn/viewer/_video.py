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
from . import _camera, _meshes
from ._drawing import COLOURS, Drawing


def _pyplot():
    return pyplot("GIF and MP4 animations", AnimationWriterError,
                  instead="or write an .html animation, which needs nothing")


#: Triangles of a robot's meshes in a GIF/MP4 (matplotlib sorts and fills each one).
VIDEO_TRIANGLES = 6000


def _robot(ax, d: Drawing, up: np.ndarray):
    """The robot's meshes as one shaded ``Poly3DCollection`` (mplot3d sorts its faces by
    depth), simplified to :data:`VIDEO_TRIANGLES`; returns ``update(k)`` or None."""
    if d.visuals is None or "robot" not in d.show:
        return None
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    scene = _meshes.visual_scene(d.visuals["model"], VIDEO_TRIANGLES, warn=False)
    slot = {b: k for k, b in enumerate(d.visuals["bodies"])}
    local, colours, which = [], [], []
    for inst in scene.instances:
        if inst.body not in slot:
            continue
        m = scene.meshes[inst.mesh]
        tri = m.vertices[m.faces].astype(float) @ inst.pose[:, :3].T + inst.pose[:, 3]
        rgb = np.empty((len(m.faces), 3))
        for a, n, c in m.parts or [(0, len(m.faces), None)]:
            rgb[a:a + n] = (inst.rgba[:3] if inst.rgba is not None
                            else c if c is not None else _meshes.DEFAULT_RGBA[:3])
        local.append(tri)
        colours.append(rgb)
        which += [slot[inst.body]] * len(tri)
    if not local:
        return None
    local, colours, which = np.concatenate(local), np.concatenate(colours), np.array(which)
    e1, e2, u = _camera.up_basis(up)
    az, el = np.radians(d.camera["azimuth"]), np.radians(d.camera["elevation"])
    eye = np.cos(el) * np.cos(az) * e1 + np.cos(el) * np.sin(az) * e2 + np.sin(el) * u
    coll = Poly3DCollection(np.zeros((0, 3, 3)), edgecolors="none", zorder=1.9)
    ax.add_collection3d(coll)

    def update(k: int):
        pose = d.visuals["pose"][k][which]  # (n, 12) per triangle
        rot = pose[:, :9].reshape(-1, 3, 3)
        world = np.einsum("nij,nvj->nvi", rot, local) + pose[:, None, 9:]
        n = np.cross(world[:, 1] - world[:, 0], world[:, 2] - world[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        coll.set_verts(world)
        coll.set_facecolor(colours * (0.3 + 0.6 * np.abs(n @ eye))[:, None])

    return update


def _point_camera(ax, d: Drawing):
    """Point the axes' camera as ``d.camera`` says: ``(centre, up)``; ``centre(k)``
    re-centres the axes' cube on frame ``k`` (a following camera moves with its subject)."""
    cam = d.camera
    target = np.asarray(cam["target"], dtype=float)
    # A cube around the motion (equal scales), a little larger than its largest extent (a
    # following camera: around the subject, moved with it frame by frame).
    half = 0.55 * (0.8 * d.size if cam.get("track") is not None else d.extent)

    def centre(k: int):
        c = target if cam.get("track") is None else np.asarray(cam["track"][k], dtype=float)
        ax.set_xlim(c[0] - half, c[0] + half)
        ax.set_ylim(c[1] - half, c[1] + half)
        ax.set_zlim(c[2] - half, c[2] + half)

    centre(0)
    ax.set_box_aspect((1, 1, 1), zoom=1.35)
    up = np.asarray(cam.get("up", (0, 0, 1)), dtype=float)
    vertical = {0: "x", 1: "y", 2: "z"}.get(int(np.argmax(np.abs(up))), "z")
    if abs(up[int(np.argmax(np.abs(up)))]) < 0.999 or up.max() < 0.999:
        vertical = "z"  # mplot3d's vertical axis is a positive world axis
    ax.view_init(elev=cam["elevation"], azim=cam["azimuth"], vertical_axis=vertical)
    return centre, up


def _planes(ax, d: Drawing) -> None:
    # Every contact plane's grid where the plane is (else the ground grid), all as one
    # NaN-separated line (one artist: drawing cost is per artist).
    seg = []
    for g in d.planes or [d.grid]:
        ks = np.arange(-g["half"], g["half"] + 1e-9 * g["half"], g["step"])
        o, gu, gv, h = (np.asarray(g[k], dtype=float) for k in ("origin", "u", "v", "half"))
        seg += [[o + k * gu - h * gv, o + k * gu + h * gv] for k in ks]
        seg += [[o - h * gu + k * gv, o + h * gu + k * gv] for k in ks]
    xyz = np.concatenate([np.array(seg), np.full((len(seg), 1, 3), np.nan)],
                         axis=1).reshape(-1, 3)
    ax.plot(xyz[:, 0], xyz[:, 1], xyz[:, 2], color=COLOURS["grid"], lw=0.5, zorder=0.5)


def _legend(ax, d: Drawing, on: dict, contact: bool) -> None:
    """The legend of the layers shown, bottom right."""
    legend = [("● m > 0", COLOURS["positive"])] if on["masses"] else []
    if on["masses"] and np.any(d.sphere_mass < 0):
        legend.append(("● m < 0", COLOURS["negative"]))
    if on["masses"] and np.any(d.sphere_mass == 0):
        legend.append(("● m = 0", COLOURS["zero"]))
    if on["masses"]:
        legend.append(("disc ∝ |m|^(1/3)", (0.35, 0.35, 0.35)))
    if contact:
        legend.append((f"→ contact forces ({1e3 * d.contact_scale:.3g} mm/N)",
                       COLOURS["contact"]))
    for k, (text, colour) in enumerate(reversed(legend)):
        ax.text2D(0.98, 0.03 + 0.05 * k, text, transform=ax.transAxes, color=colour,
                  fontsize=8, ha="right")


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
    centre, up = _point_camera(ax, d)
    _planes(ax, d)
    robot = _robot(ax, d, up)
    w = 0.15 * d.size
    for axis, c in zip(np.eye(3), [(0.85, 0.1, 0.1), (0.1, 0.6, 0.1), (0.1, 0.2, 0.85)]):
        ax.plot([0, w * axis[0]], [0, w * axis[1]], [0, w * axis[2]], color=c, lw=1.2, zorder=1)

    trails = [ax.plot([], [], [], color=c, lw=1.2, zorder=1.5)[0] for c in d.trail_colour]
    # The layers the page shows at first (each artist costs time in every frame).
    on = {k: k in d.show for k in ("masses", "links", "axes", "forces")}
    boxes = [ax.plot([], [], [], color=COLOURS["box"], lw=0.7, zorder=1.8)[0]
             for _ in range(d.boxes.shape[1] // 12 if on["masses"] else 0)]
    links = [ax.plot([], [], [], color=COLOURS["link"], lw=3.5, solid_capstyle="round",
                     zorder=2)[0]
             for _ in range(d.links.shape[1] if on["links"] else 0)]
    axes = [ax.plot([], [], [], color=COLOURS["axis"], lw=2, zorder=2.1)[0]
            for _ in range(d.axes.shape[1] if on["axes"] else 0)]
    arrow = (ax.plot([], [], [], color=COLOURS["shaking"], lw=2.5, zorder=2.2)[0]
             if d.arrow is not None and on["forces"] else None)
    # Contact forces: all arrows as one NaN-separated line, a dot at each point in contact.
    contact = None
    if d.contact is not None and on["forces"]:
        contact = (ax.plot([], [], [], color=COLOURS["contact"], lw=2.2, zorder=2.3)[0],
                   ax.plot([], [], [], color=COLOURS["contact"], ls="none", marker="o",
                           ms=3.5, zorder=2.3)[0])
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
        for i in (order if on["masses"] else ())
    }
    cuts = (ax.scatter(*d.cuts[0, :, 0].T, s=60, c=[COLOURS["cut"]], depthshade=False,
                       marker="o", edgecolors="none", zorder=3.5) if d.cuts.shape[1] else None)
    heads = (ax.scatter(*d.trails[0].T, s=40, c=d.trail_colour, depthshade=False,
                        edgecolors="none", zorder=4) if d.trails.shape[1] else None)
    clock = ax.text2D(0.02, 0.96, "", transform=ax.transAxes, family="monospace", fontsize=11)
    if d.title:
        ax.text2D(0.02, 0.91, d.title, transform=ax.transAxes, color="0.35", fontsize=9)
    _legend(ax, d, on, contact is not None)

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
        if contact is not None:
            a = contact_segments(d, k)
            path = np.concatenate([a, np.full((len(a), 1, 3), np.nan)], axis=1).reshape(-1, 3)
            contact[0].set_data_3d(path[:, 0], path[:, 1], path[:, 2])
            contact[1].set_data_3d(a[:, 0, 0], a[:, 0, 1], a[:, 0, 2])
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
        if robot is not None:
            robot(k)
        if cam.get("track") is not None:
            centre(k)
        return []

    update(0)
    fig.pmd_masses = masses  # the artist of each point mass, for tests
    fig.pmd_contact = contact  # the contact arrows' line and dots, for tests
    return fig, ax, update


def contact_segments(d: Drawing, k: int) -> np.ndarray:
    """The contact arrows drawn at frame ``k``, (K', 2, 3): those of points with a force."""
    a = d.contact[k]
    return a[np.linalg.norm(a[:, 1] - a[:, 0], axis=1) > 1e-9 * d.size]


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
