"""``pointmass-dyn design``: link shapes and counterweights of a one-input mechanism driven
over a revolution, from a design spec (TOML), written as CSV, density maps, STL and the
designed scene (docs/design.md §6)."""

from __future__ import annotations

import argparse
import csv
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from .._helpers import scene_gravity
from ..design import (
    Counterweight,
    LinkShape,
    Material,
    balance,
    pareto_front,
    prescribed_motion,
)
from ..errors import InvalidInputError
from ..scenes import load_scene, resolve_scene_path
from ._balance import driver_of
from ._progress import progress_bar

DESIGN_EPILOG = """\
The spec is a TOML file:

  speed = 30.0                # driver speed (default: the scene's, or 2π); driver = "crank"
  samples = 360               # instants over the revolution
  norm = "peak"               # or "rms"
  objective = { bearing = 1.0 }          # force, moment, torque, bearing, bearing:<joint>, mass
  limits = { force = 0.39 }              # same norm, absolute units (mass: kg);
                                         # safety = 2.0: links with a material
  zero = []                              # quantities that must vanish at every instant

  [[link]]                    # a link's material as cells (pmd.LinkShape's arguments)
  body = "crank"
  box = [[-0.05, -0.02, -0.006], [0.045, 0.02, 0.006]]   # or polygon + z, or stl = "file"
  cell = 0.005
  density = 7850.0            # optional: mass = [low, high], keep, keep_out, symmetric
  material = "steel"          # optional, strength-checked: "steel", "aluminium" or
                              # { density = 2700.0, allowable_stress = 1.2e8 }; web = 0.008

  [[counterweight]]           # candidate point masses (pmd.Counterweight)
  body = "rocker"
  ring = { center = [0, 0, 0], radius = 0.02, count = 24 }   # or points = [[x, y, z], ...]
  max_mass = 0.1

  [pareto]                    # optional: a front instead of one design
  objectives = ["bearing", "force"]
  count = 11
  method = "epsilon"          # or "weighted"

Written to --out (a directory): design.csv (each design mass: cell or candidate, body,
position, mass, bound), bodies.csv (each designed body's ten inertial parameters: mass,
first moments m·c, inertia about the body origin in Pinocchio's order), summary.csv (RMS
and peak of each quantity before and after), <body>.stl (cells filled to half or more),
density_<body>.png (matplotlib), and designed.toml: the scene with the designed bodies
(and designed.urdf where they came from a URDF), <body>.dxf (plate links: the outline and
pin holes for cutting). With [pareto]: pareto.csv, pareto.png. --report PATH: one HTML page
on the design (figures embedded; matplotlib).
Exit status 2 with the reason when no design meets the spec (which limit, by how much).

example:
  pointmass-dyn design fourbar fourbar_design.toml --out fourbar_design
"""

_SPEC_KEYS = {"driver", "speed", "samples", "norm", "objective", "limits", "zero", "least_mass",
              "link", "counterweight", "pareto"}
_LINK_KEYS = {"body", "box", "polygon", "z", "stl", "density", "cell", "mass", "keep", "keep_out",
              "boss", "symmetric", "material", "web", "connected", "section", "hang"}


def add_parser(sub):
    """The ``design`` subcommand."""
    p = sub.add_parser(
        "design",
        help="design link shapes (material cells) and counterweights of a mechanism from a "
             "spec: CSV, density maps, STL and the designed scene",
        description="Design of a one-input mechanism's bodies along one revolution of its\n"
                    "driver: a scene file or bundled name, and a design spec (TOML).",
        epilog=DESIGN_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("scene", help="a scene file or a bundled name")
    p.add_argument("spec", help="the design spec, a TOML file (see below)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="directory for the results (default: <scene>_design)")
    p.add_argument("--report", default=None, metavar="PATH",
                   help="also write one self-contained HTML report of the design there")
    p.set_defaults(func=cmd_design, driver=None)
    return p


def _read_spec(path: Path) -> dict:
    try:
        import tomllib
    except ImportError:  # pragma: no cover - Python < 3.11
        try:
            import tomli as tomllib
        except ImportError as exc:
            raise InvalidInputError("spec: reading TOML needs Python >= 3.11 or tomli") from exc
    try:
        with open(path, "rb") as f:
            spec = tomllib.load(f)
    except OSError as exc:
        raise InvalidInputError(f"spec: expected a readable TOML file, got '{path}' ({exc})") from exc
    except ValueError as exc:
        raise InvalidInputError(f"spec: '{path}' is not TOML ({exc})") from exc
    unknown = sorted(set(spec) - _SPEC_KEYS)
    if unknown:
        raise InvalidInputError(f"spec: unknown keys {unknown} in '{path}' (known: {sorted(_SPEC_KEYS)})")
    return spec


def _links(spec: dict, base: Path) -> list[LinkShape]:
    out = []
    for k, item in enumerate(spec.get("link", [])):
        unknown = sorted(set(item) - _LINK_KEYS)
        if unknown or "body" not in item:
            raise InvalidInputError(
                f"spec: [[link]] {k + 1} needs 'body' and keys among {sorted(_LINK_KEYS)}, got "
                f"{sorted(item)}"
            )
        args = dict(item)
        if "stl" in args:
            args["stl"] = str(base / args["stl"])
        for key in ("mass", "z"):
            if key in args:
                args[key] = tuple(args[key])
        if "material" in args:
            args["material"] = _material(args["material"], k)
        out.append(LinkShape(**args))
    return out


def _material(value, k: int) -> Material:
    """A [[link]]'s material: a preset's name or a table of Material's arguments."""
    presets = {"steel": Material.steel, "aluminium": Material.aluminium}
    if isinstance(value, str) and value in presets:
        return presets[value]()
    if isinstance(value, dict) and set(value) <= {"density", "allowable_stress", "name"}:
        try:
            return Material(**value)
        except TypeError:
            pass
    raise InvalidInputError(
        f"spec: [[link]] {k + 1} material: expected \"steel\", \"aluminium\" or a table with "
        f"density and allowable_stress, got {value!r}"
    )


def _spec_number(table: dict, key: str, default, cast, where: str):
    """``table[key]`` as a number of type ``cast`` (``int``: a whole number), or an error
    naming the key, where it is and what was given."""
    value = table.get(key, default)
    kind = "an integer" if cast is int else "a number"
    if value is None or isinstance(value, bool) or not isinstance(value, (int, float)) or (
        cast is int and isinstance(value, float) and not value.is_integer()
    ):
        raise InvalidInputError(f"spec: '{key}' in {where}: expected {kind}, got {value!r}")
    return cast(value)


def _counterweights(spec: dict) -> list[Counterweight]:
    out = []
    for k, item in enumerate(spec.get("counterweight", [])):
        body, ring, points = item.get("body"), item.get("ring"), item.get("points")
        if body is None or (ring is None) == (points is None):
            raise InvalidInputError(
                f"spec: [[counterweight]] {k + 1} needs 'body' and one of 'ring' or 'points', "
                f"got {sorted(item)}"
            )
        max_mass = item.get("max_mass")
        if ring is not None:
            out.append(Counterweight.ring(body, ring.get("center", (0, 0, 0)), _spec_number(ring, "radius", None, float, f"[[counterweight]] {k + 1} ring"),
                                          _spec_number(ring, "count", 24, int, f"[[counterweight]] {k + 1} ring"),
                                          normal=ring.get("normal", (0, 0, 1)), max_mass=max_mass))
        else:
            out.append(Counterweight(body, np.asarray(points, float), max_mass))
    return out


def _write_csv(path: Path, header: list[str], rows: list[list]) -> None:
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(header)
        for row in rows:
            w.writerow([f"{x:.17g}" if isinstance(x, float) else x for x in row])


def _design_rows(b, links, cws) -> list[list]:
    rows = []
    for name, shape in b.shapes.items():
        for c, m, cap in zip(shape.centers, shape.masses, shape.capacity):
            rows.append(["cell", name, *map(float, c), float(m), float(cap)])
    start = sum(len(s.masses) for s in b.shapes.values())
    # Counterweight candidates follow the cells, in the order given (balance's order).
    for cw in cws:
        pts = np.atleast_2d(np.asarray(cw.points, float))
        bound = math.inf if cw.max_mass is None else float(cw.max_mass)
        for p, m in zip(pts, b.masses[start : start + len(pts)]):
            rows.append(["counterweight", str(cw.body), *map(float, p), float(m), bound])
        start += len(pts)
    return rows


def _parameters(body) -> list[float]:
    """m, m·c, inertia about the body origin (xx, xy, yy, xz, yz, zz): Pinocchio's order."""
    m, c = float(body.mass), np.asarray(body.com, float)
    i = np.asarray(body.inertia, float) + m * (c @ c * np.eye(3) - np.outer(c, c))
    return [m, *(m * c), i[0, 0], i[0, 1], i[1, 1], i[0, 2], i[1, 2], i[2, 2]]


def _density_maps(b, out: Path) -> list[Path]:
    """Each shape's fill (mass / bound) averaged through its thickness (z), as an image."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("density maps skipped: matplotlib is not installed (pip install matplotlib)")
        return []
    written = []
    for name, s in b.shapes.items():
        idx = np.round((s.centers[:, :2] - s.centers[:, :2].min(axis=0)) / s.cell).astype(int)
        grid = np.zeros(idx.max(axis=0) + 1)
        count = np.zeros_like(grid)
        np.add.at(grid, (idx[:, 0], idx[:, 1]), s.fill)
        np.add.at(count, (idx[:, 0], idx[:, 1]), 1.0)
        image = np.where(count > 0, grid / np.maximum(count, 1), np.nan)
        lo = s.centers[:, :2].min(axis=0) - s.cell / 2
        hi = s.centers[:, :2].max(axis=0) + s.cell / 2
        fig, ax = plt.subplots(figsize=(6, 3.5))
        im = ax.imshow(image.T, origin="lower", extent=(lo[0], hi[0], lo[1], hi[1]),
                       cmap="viridis", vmin=0.0, vmax=1.0)
        fig.colorbar(im, ax=ax, label="fill (mass / cell bound), mean through z")
        ax.set_xlabel("x (m, body frame)")
        ax.set_ylabel("y (m)")
        ax.set_title(f"{name}: {s.mass:.4g} kg")
        path = out / f"density_{name}.png"
        fig.savefig(path, dpi=120, bbox_inches="tight")
        plt.close(fig)
        written.append(path)
    return written


def _objective_unit(motion, name: str) -> str:
    """The unit of objective ``name``'s value: kg of design material, N·m for the shaking
    moment and the driving torques (N for a prismatic driver), N for the forces."""
    if name == "mass":
        return "kg"
    if name == "moment":
        return "N·m"
    if name == "torque":
        units = {u for k, u in motion.units().items() if k.startswith("driving force")}
        return units.pop() if len(units) == 1 else "N or N·m"
    return "N"  # the shaking force, the bearing forces


def _front(motion, spec, kwargs, out: Path) -> None:
    pareto = spec["pareto"]
    names = tuple(pareto.get("objectives", ()))
    count = _spec_number(pareto, "count", 11, int, "[pareto]")
    method = pareto.get("method", "weighted")
    front = pareto_front(motion, names, count, method=method, **kwargs)
    # The figures re-analysed along the motion (repeated and dominated points dropped).
    rows = [[float(v[0]), float(v[1]), float(np.sum(b.masses))] for b, v in zip(front, front.values)]
    units = [_objective_unit(motion, n) for n in names]
    print(f"Pareto front ({method}, {kwargs['norm']}): {names[0]} ({units[0]}) / "
          f"{names[1]} ({units[1]}); {len(front.dropped)} of {count} dropped (repeated or dominated)")
    for r in rows:
        print(f"  {r[0]:>13.6g} {units[0]:<6}{r[1]:>13.6g} {units[1]:<6}  "
              f"design mass {r[2]:.6g} kg")
    _write_csv(out / "pareto.csv", [names[0], names[1], "design_mass"], rows)
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("pareto.png skipped: matplotlib is not installed")
        return
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.plot([r[0] for r in rows], [r[1] for r in rows], "o-")
    ax.set_xlabel(f"{names[0]}, {kwargs['norm']} ({units[0]})")
    ax.set_ylabel(f"{names[1]}, {kwargs['norm']} ({units[1]})")
    fig.savefig(out / "pareto.png", dpi=120, bbox_inches="tight")
    plt.close(fig)


def _motion(args, scene, spec):
    model = scene.model
    args.driver = spec.get("driver")
    driver = driver_of(args, scene)
    _, iv, _, _ = model.joint_slices()[model.link_names.index(driver)]
    default = float(scene.v0[iv]) if scene.v0[iv] != 0.0 else 2.0 * math.pi
    speed = _spec_number(spec, "speed", default, float, "the top level")
    samples = _spec_number(spec, "samples", 360, int, "the top level")
    if not (math.isfinite(speed) and speed != 0.0) or samples < 2:
        raise InvalidInputError(
            f"spec: expected a finite non-zero speed and samples >= 2, got {speed}, {samples}"
        )
    report, finish = progress_bar(2 * samples, sys.stderr, always=False, unit="steps")
    try:
        motion = prescribed_motion(model, driver, speed=speed, samples=samples, q_guess=scene.q0,
                                   gravity=scene_gravity(scene), progress=report)
    finally:
        finish()
    revolute = model.body_info(model.body_names.index(driver))[1] == "Revolute"
    print(f"{scene.name}: '{driver}' driven at {speed:.6g} {'rad/s' if revolute else 'm/s'} "
          f"over one {'revolution' if revolute else 'cycle of 2π m'}, {samples} samples")
    return motion


def cmd_design(args) -> int:
    spec_path = Path(args.spec)
    spec = _read_spec(spec_path)
    scene = load_scene(args.scene)
    out = Path(args.out or f"{scene.name}_design")
    links, cws = _links(spec, spec_path.parent), _counterweights(spec)
    motion = _motion(args, scene, spec)
    kwargs: dict[str, Any] = dict(
        links=links, counterweights=cws, norm=spec.get("norm", "rms"),
        limits=spec.get("limits"), zero=tuple(spec.get("zero", ())),
        least_mass=bool(spec.get("least_mass", True)),
    )
    out.mkdir(parents=True, exist_ok=True)
    if "pareto" in spec:
        _front(motion, spec, kwargs, out)
        return 0
    b = balance(motion, objective=spec.get("objective"), **kwargs)
    s = b.solver
    print(f"designed: {s['status']}, relative gap {s['gap_rel']:.1e}, {s['iterations']} iterations, "
          f"{s['time']:.2f} s")
    print(b.table())
    _write_csv(out / "design.csv", ["kind", "body", "x", "y", "z", "mass", "bound"],
               _design_rows(b, links, cws))
    _write_csv(out / "bodies.csv",
               ["body", "mass", "mcx", "mcy", "mcz", "ixx", "ixy", "iyy", "ixz", "iyz", "izz"],
               [[name, *_parameters(body)] for name, body in b.bodies.items()])
    before, after = b.before.summary(), b.after.summary()
    _write_csv(out / "summary.csv", ["quantity", "rms_before", "rms_after", "peak_before", "peak_after"],
               [[k, before[k]["rms"], after[k]["rms"], before[k]["peak"], after[k]["peak"]] for k in before])
    for name in b.shapes:  # the written (realised) parts, whose mass properties b.realised gives
        b.realised[name].write_stl(out / f"{name}.stl")
    _density_maps(b, out)
    for name, st in b.strength.items():
        print(f"{name}: least safety factor {st.safety:.3g} at t = {st.t:.4g} s")
    for name in b.shapes:
        try:
            b.write_dxf(name, out / f"{name}.dxf")
        except InvalidInputError as exc:  # not a plate: no outline to cut
            print(f"{name}.dxf skipped: {exc}")
    b.write_scene(resolve_scene_path(args.scene), out / "designed.toml")
    print(f"written to {out}/: design.csv, bodies.csv, summary.csv, STL, DXF, density maps, "
          "designed.toml")
    if args.report:
        print(f"report: {b.report(args.report)}")
    return 0
