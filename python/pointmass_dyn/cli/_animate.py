"""``pointmass-dyn animate``: simulate a scene and write its animation (docs/visualisation.md);
also the ``--animate`` option of ``simulate``."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from .._simulation import simulate
from ..errors import InvalidInputError
from ..scenes import load_scene
from ..viewer import animate, has_contact

TRAIL_SPEC = "BODY[:X,Y,Z]"


def add_options(p: argparse.ArgumentParser) -> None:
    """Options shared by ``animate`` and ``simulate --animate``."""
    p.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    p.add_argument("--frames", type=int, default=None,
                   help="number of frames (default: the duration times --fps)")
    p.add_argument("--duration", type=float, default=None, metavar="SECONDS",
                   help="playback length (default: the simulated time span; longer plays "
                        "slower)")
    p.add_argument("--size", default="640x480", metavar="WxH",
                   help="GIF/MP4 frame size in pixels (default 640x480)")
    p.add_argument("--trail", action="append", metavar=TRAIL_SPEC,
                   help="draw the path of a point of a body (its origin, or X,Y,Z in its "
                        "frame); repeatable")
    p.add_argument("--shaking", action="store_true",
                   help="draw the shaking force (−Σ m a) as an arrow at the world origin")
    p.add_argument("--no-contact-forces", action="store_true",
                   help="do not draw the ground-contact forces (drawn by default for a scene "
                        "with a ground contact, as arrows at the points in contact)")
    p.add_argument("--contact-scale", type=float, default=None, metavar="M_PER_N",
                   help="length of a contact-force arrow per newton, in metres (default: the "
                        "largest force is a quarter of the scene's size)")


def add_parser(sub) -> argparse.ArgumentParser:
    """The ``animate`` subcommand."""
    an = sub.add_parser(
        "animate",
        help="simulate a scene and write a 3-D animation (.html, .gif or .mp4)",
        description="Simulate a scene (a file or a bundled name) and write an animation of "
                    "its bodies and point masses: a self-contained WebGL page (.html), a GIF "
                    "or an MP4 (needs ffmpeg).",
    )
    an.add_argument("scene")
    an.add_argument("--out", required=True, help="the animation file: .html, .gif or .mp4")
    an.add_argument("--t-end", type=float, default=None, help="end time (s); default: the scene's")
    an.add_argument("--rtol", type=float, default=None)
    an.add_argument("--atol", type=float, default=None)
    add_options(an)
    an.set_defaults(func=cmd_animate)
    return an


def _size(text: str) -> tuple[int, int]:
    parts = text.lower().split("x")
    try:
        w, h = (int(x) for x in parts)
    except ValueError:
        raise InvalidInputError(
            f"--size: expected WIDTHxHEIGHT in pixels (e.g. 640x480), got '{text}'"
        ) from None
    return w, h


def _trails(specs) -> list:
    out = []
    for spec in specs or ():
        body, _, point = spec.partition(":")
        if not point:
            out.append(body)
            continue
        try:
            xyz = [float(x) for x in point.split(",")]
        except ValueError:
            xyz = []
        if len(xyz) != 3 or not np.all(np.isfinite(xyz)):
            raise InvalidInputError(
                f"--trail: expected {TRAIL_SPEC} (three numbers after the colon), got '{spec}'"
            )
        out.append((body, xyz))
    return out


def check_outputs(model, files, trails=None, size=None) -> None:
    """Refuses, before any run, what would only fail after it: ``files`` ((option, path or
    None) pairs) in directories that do not exist, ``--trail`` bodies the model does not
    have, a ``--size`` that does not parse."""
    for option, path in files:
        if path and not Path(path).resolve().parent.is_dir():
            raise InvalidInputError(
                f"{option}: expected a file in an existing directory, got '{path}'"
            )
    names = list(model.body_names)
    for spec in _trails(trails):
        body = spec[0] if isinstance(spec, tuple) else spec
        if body not in names:
            raise InvalidInputError(f"--trail: expected a body of {names}, got '{body}'")
    if size is not None:
        _size(size)


def write(args, result, scene, path: str) -> None:
    """Writes the animation of ``result`` that ``args`` (``add_options``) describe."""
    # A scene with a ground contact: its forces at the frames' states (False: none).
    contact = False if args.no_contact_forces else has_contact(scene) or None
    info = animate(result, scene, path, fps=args.fps, frames=args.frames,
                   duration=args.duration, size=_size(args.size), trails=_trails(args.trail),
                   shaking=args.shaking, contact=contact, contact_scale=args.contact_scale)
    forces = ("" if info.contact_scale is None
              else f", contact forces at {1e3 * info.contact_scale:.3g} mm/N")
    print(f"  animation written to {path} ({info.frames} frames, {info.bytes / 1e3:.0f} kB"
          f"{forces})")


def cmd_animate(args) -> int:
    scene = load_scene(args.scene)
    check_outputs(scene.model, [("--out", args.out)], args.trail, args.size)
    # Before the run, not after it: a file name animate cannot write.
    if args.out and Path(args.out).suffix.lower() not in (".html", ".gif", ".mp4"):
        raise InvalidInputError(
            f"--out: expected a file name ending in .html, .gif or .mp4, got '{args.out}'")
    t_span = scene.t_span or (0.0, 10.0)
    if args.t_end is not None:
        t_span = (t_span[0], args.t_end)
    result = simulate(scene, t_span, rtol=args.rtol, atol=args.atol)
    print(f"{scene.name}: {result.message}")
    # A failed run is still drawn up to where it stopped.
    write(args, result, scene, args.out)
    return 0 if result.success else 1
