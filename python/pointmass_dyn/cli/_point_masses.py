"""``pointmass-dyn point-masses``: each moving link's seven equimomental point masses at the
scene's initial configuration."""

from __future__ import annotations

from ..scenes import load_scene


def add_parser(sub):
    """The ``point-masses`` subcommand."""
    pm = sub.add_parser("point-masses", help="print each body's seven point masses")
    pm.add_argument("scene")
    pm.set_defaults(func=cmd_point_masses)
    return pm


def cmd_point_masses(args) -> int:
    scene = load_scene(args.scene)
    model = scene.model
    masses, positions = model.point_masses(scene.q0)
    print(f"{scene.name}: seven equimomental point masses per moving link "
          f"(positions in the world frame at q0, metres)")
    for name, m, p in zip(model.link_names, masses, positions):
        print(f"\n{name}  (total {m.sum():.6g} kg)")
        print(f"  {'j':>2} {'mass (kg)':>14} {'x':>12} {'y':>12} {'z':>12}")
        for j in range(7):
            print(f"  {j + 1:>2} {m[j]:>14.6g} {p[j, 0]:>12.6g} {p[j, 1]:>12.6g} {p[j, 2]:>12.6g}")
    return 0
