"""``pointmass-dyn scenes``: the bundled scenes, one line each."""

from __future__ import annotations

from ..scenes import builtin_scenes, load_scene


def add_parser(sub):
    """The ``scenes`` subcommand."""
    sc = sub.add_parser("scenes", help="list the bundled scenes")
    sc.set_defaults(func=cmd_scenes)
    return sc


def cmd_scenes(args) -> int:
    for name, path in builtin_scenes().items():
        scene = load_scene(path)
        first = scene.description.split(". ")[0].strip()
        print(f"{name:<20} nq={scene.model.nq:<3} {first}")
    return 0
