"""``pointmass-dyn balance``: shaking forces of a one-input mechanism driven over a revolution
(docs/balancing.md), and counterweights or redesigned links that balance it."""

from __future__ import annotations

import argparse
import csv
import math
import sys
from pathlib import Path

import numpy as np

from .._helpers import scene_gravity
from ..design import OBJECTIVES, Counterweight, balance, pareto_front, prescribed_motion
from ..errors import InertiaError, InvalidInputError, PointMassDynError
from ..plotting import objective_rms, plot_balance, plot_motion, plot_pareto
from ..scenes import load_scene, resolve_scene_path
from ._progress import progress_bar

BALANCE_EPILOG = """\
The mechanism is driven by one 1-dof joint at constant speed over one revolution (its own
loops closed at every instant), and the shaking force and moment (about the world origin),
the driving torque and every joint's bearing force are computed along it. With no
--counterweight and no --redesign only this analysis is printed (RMS and peak of each).

Design variables (point masses at fixed body points, chosen exactly by a convex QP):
  --counterweight BODY:RADIUS[:COUNT][@X,Y,Z]
        COUNT candidate masses (default 24, each >= 0, at most --max-mass) on a circle of
        RADIUS metres about X,Y,Z (BODY's frame, default its origin) in the plane normal to
        BODY's joint axis (z for a joint that is not revolute); neighbouring candidates share
        a counterweight, so it can sit at any angle. Repeat for several bodies.
  --redesign BODY
        BODY's own seven point masses become free (kept >= 0): its mass, COM and inertia are
        redesigned. Repeat for several bodies.
Goals (quantities: force = shaking force, moment = shaking moment, torque = driving torque):
  --zero Q        Q must vanish at every instant (e.g. --zero force: complete force balance)
  --weight Q=W    weight of Q's RMS, relative to its unbalanced RMS (default force=1)
  --pareto Q1,Q2[:COUNT]
                  COUNT balances (default 11) sweeping the weights of Q1 and Q2 from (1, 0) to
                  (0, 1): prints the RMS pairs; --plot draws the front, --out writes it

examples:
  pointmass-dyn balance fourbar
  pointmass-dyn balance fourbar --counterweight crank:0.02 --counterweight rocker:0.02 \\
      --zero force --plot fourbar.png --out fourbar.csv
  pointmass-dyn balance fourbar --counterweight crank:0.02 --counterweight rocker:0.02 \\
      --pareto force,moment:9 --plot front.png
"""


def add_parser(sub):
    """The ``balance`` subcommand."""
    bl = sub.add_parser(
        "balance",
        help="shaking force and moment, driving torque and bearing forces of a mechanism "
             "driven over a revolution; counterweights or redesigned links that balance it",
        description="Shaking forces and balancing of a one-input mechanism: a scene file or\n"
                    "a bundled name (fourbar, slider_crank, andrews).",
        epilog=BALANCE_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    bl.add_argument("scene", help="a scene file or a bundled name")
    bl.add_argument("--driver", default=None, metavar="BODY",
                    help="the driving body, on a revolute or prismatic joint (default: the "
                         "scene's one [initial] fixed body)")
    bl.add_argument("--speed", type=float, default=None, metavar="W",
                    help="driver speed, rad/s or m/s (default: the scene's initial speed of the "
                         "driver, or 2π)")
    bl.add_argument("--samples", type=int, default=360, metavar="N",
                    help="instants over the revolution (default 360)")
    bl.add_argument("--counterweight", action="append", metavar=COUNTERWEIGHT_SPEC,
                    help="candidate counterweights on a ring (see below); repeatable")
    bl.add_argument("--max-mass", type=float, default=None, metavar="KG",
                    help="upper bound of each counterweight candidate's mass (default none)")
    bl.add_argument("--redesign", action="append", metavar="BODY",
                    help="redesign BODY's own mass distribution; repeatable")
    bl.add_argument("--zero", action="append", choices=("force", "moment", "torque"),
                    help="make this quantity vanish at every instant; repeatable")
    bl.add_argument("--weight", action="append", metavar="Q=W",
                    help="weight of a quantity's relative RMS (force, moment, torque); "
                         "repeatable; default force=1")
    bl.add_argument("--pareto", default=None, metavar="Q1,Q2[:COUNT]",
                    help="sweep the weights of two quantities and print the front")
    bl.add_argument("--plot", default=None,
                    help="write the plot (PNG): polar shaking force, moment, driving torque, "
                         "bearing forces; or the Pareto front")
    bl.add_argument("--out", default=None, help="write the table to a .csv file")
    bl.set_defaults(func=cmd_balance)
    return bl


def _scene_fixed(path: Path) -> list[str] | None:
    """A scene file's ``[initial] fixed`` (None where the file cannot be read as TOML here:
    Python < 3.11 without tomli)."""
    try:
        import tomllib
    except ImportError:  # pragma: no cover - Python < 3.11
        try:
            import tomli as tomllib
        except ImportError:
            return None
    try:
        with open(path, "rb") as f:
            data = tomllib.load(f)
    except (OSError, ValueError):
        return None
    fixed = data.get("initial", {}).get("fixed", [])
    return [str(x) for x in fixed] if isinstance(fixed, list) else None


def _one_dof_links(model) -> list[str]:
    return [name for name, (_, _, nq, nv) in zip(model.link_names, model.joint_slices())
            if nq == nv == 1]


def driver_of(args, scene) -> str:
    """The driving body: --driver, else the scene's one ``[initial] fixed`` body, else the
    only joint of a one-dof model without loops."""
    model = scene.model
    candidates = _one_dof_links(model)
    if args.driver is not None:
        if args.driver not in model.body_names:
            raise InvalidInputError(
                f"--driver: no body named '{args.driver}' in {scene.name} (bodies on 1-dof "
                f"joints: {', '.join(candidates) or 'none'})"
            )
        if args.driver not in candidates:
            raise InvalidInputError(
                f"--driver: '{args.driver}' is not on a 1-dof (revolute or prismatic) joint; "
                f"bodies on 1-dof joints: {', '.join(candidates) or 'none'}"
            )
        return args.driver
    fixed = _scene_fixed(resolve_scene_path(args.scene))
    if fixed is not None and len(fixed) == 1 and fixed[0] in candidates:
        return fixed[0]
    if model.nloops == 0 and model.nv == 1 and len(candidates) == 1:
        return candidates[0]
    shown = "not read" if fixed is None else f"[{', '.join(fixed)}]"
    raise InvalidInputError(
        f"--driver: {scene.name} does not name one driving body (its [initial] fixed is "
        f"{shown}); give --driver BODY, one of: {', '.join(candidates) or 'none'}"
    )


def _floats(text: str, n: int, option: str, spec: str) -> list[float]:
    parts = text.split(",")
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        vals = []
    if len(vals) != n or not all(math.isfinite(v) for v in vals):
        raise InvalidInputError(
            f"{option}: expected {n} finite numbers separated by commas in '{spec}', got "
            f"'{text}'"
        )
    return vals


def _joint_axis(model, body: str, q) -> np.ndarray:
    """A revolute body's joint axis in its own frame (z for any other joint), from the
    rotation its joint makes: R(q)ᵀ R(q + δ) = Rot(axis, δ)."""
    index = model.body_names.index(body)
    _, kind, _, link = model.body_info(index)
    if kind != "Revolute" or link < 0 or model.link_names[link] != body:
        return np.array([0.0, 0.0, 1.0])
    iq = model.joint_slices()[link][0]
    q1 = np.array(q, dtype=float)
    q1[iq] += 0.5
    r0 = model.placements(q)[0][index]
    r1 = model.placements(q1)[0][index]
    d = r0.T @ r1
    axis = np.array([d[2, 1] - d[1, 2], d[0, 2] - d[2, 0], d[1, 0] - d[0, 1]])
    return axis / np.linalg.norm(axis)


COUNTERWEIGHT_SPEC = "BODY:RADIUS[:COUNT][@X,Y,Z]"


def _counterweights(args, scene) -> list:
    model = scene.model
    out = []
    for spec in args.counterweight or []:
        head, _, center_text = spec.partition("@")
        parts = head.split(":")
        if len(parts) not in (2, 3) or not parts[0]:
            raise InvalidInputError(
                f"--counterweight: expected {COUNTERWEIGHT_SPEC}, got '{spec}'"
            )
        body = parts[0]
        if body not in model.body_names:
            raise InvalidInputError(
                f"--counterweight: no body named '{body}' in {scene.name} (bodies: "
                f"{', '.join(model.body_names)}), in '{spec}'"
            )
        radius = _floats(parts[1], 1, "--counterweight", spec)[0] if parts[1] else -1.0
        if not radius > 0.0:
            raise InvalidInputError(
                f"--counterweight: expected a radius > 0 (metres) in '{spec}', got '{parts[1]}'"
            )
        count = 24
        if len(parts) == 3:
            try:
                count = int(parts[2])
            except ValueError:
                count = 0
            if count < 1:
                raise InvalidInputError(
                    f"--counterweight: expected a whole COUNT >= 1 in '{spec}', got "
                    f"'{parts[2]}'"
                )
        center = (
            _floats(center_text, 3, "--counterweight", spec) if center_text else [0.0, 0.0, 0.0]
        )
        normal = _joint_axis(model, body, scene.q0)
        out.append(Counterweight.ring(body, center, radius, count, normal=normal,
                                      max_mass=args.max_mass))
    return out


def _weights(args) -> dict[str, float] | None:
    if not args.weight:
        return None
    out = {}
    for spec in args.weight:
        name, eq, value = spec.partition("=")
        name = name.strip()
        try:
            w = float(value)
        except ValueError:
            w = math.nan
        if name not in OBJECTIVES or not eq or not (math.isfinite(w) and w >= 0.0):
            raise InvalidInputError(
                f"--weight: expected QUANTITY=WEIGHT with QUANTITY one of "
                f"{', '.join(OBJECTIVES)} and a finite WEIGHT >= 0, got '{spec}'"
            )
        out[name] = w
    return out


def _pareto_spec(text: str) -> tuple[tuple[str, str], int]:
    pair, _, count_text = text.partition(":")
    names = tuple(p.strip() for p in pair.split(","))
    try:
        count = int(count_text) if count_text else 11
    except ValueError:
        count = 0
    if len(names) != 2 or names[0] == names[1] or not set(names) <= set(OBJECTIVES) or count < 2:
        raise InvalidInputError(
            f"--pareto: expected Q1,Q2[:COUNT] with two different quantities among "
            f"{', '.join(OBJECTIVES)} and a whole COUNT >= 2, got '{text}'"
        )
    return names, count


def _write_rows(path: Path, header: list[str], rows: list[list]) -> None:
    if path.suffix != ".csv":
        raise PointMassDynError(f"--out: expected a .csv file name, got '{path}'")
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(header)
        for row in rows:
            w.writerow([f"{x:.17g}" if isinstance(x, float) else x for x in row])


def _vec(x) -> str:
    return "(" + ", ".join(f"{0.0 if abs(v) < 1e-300 else v:.6g}" for v in x) + ")"


def _print_balance(b, model) -> None:
    """The before/after table, the counterweights placed and the new bodies of a balance."""
    print(b.table())
    if b.counterweights:
        print("\ncounterweights placed (positions in the body's frame)")
        print(f"  {'body':<16}{'mass (kg)':>13}{'x (m)':>13}{'y (m)':>13}{'z (m)':>13}")
        for body, pos, mass in b.counterweights:
            p = [0.0 if abs(x) < 1e-15 else x for x in pos]
            print(f"  {body:<16}{mass:>13.6g}{p[0]:>13.6g}{p[1]:>13.6g}{p[2]:>13.6g}")
    else:
        print("\nno counterweight placed")
    print("\nnew bodies (COM in the body's frame; inertia about the COM, diagonal)")
    print(f"  {'body':<16}{'mass (kg)':>13}{'COM x (m)':>12}{'COM y (m)':>12}{'COM z (m)':>12}"
          f"{'Ixx (kg·m²)':>14}{'Iyy (kg·m²)':>14}{'Izz (kg·m²)':>14}")
    for name, rb in b.bodies.items():
        c = [0.0 if abs(x) < 1e-15 else x for x in rb.com]
        d = np.diag(rb.inertia)
        print(f"  {name:<16}{rb.mass:>13.6g}{c[0]:>12.5g}{c[1]:>12.5g}{c[2]:>12.5g}"
              f"{d[0]:>14.5g}{d[1]:>14.5g}{d[2]:>14.5g}")
    print(f"  mass added: {b.model.total_mass - model.total_mass:.6g} kg")


def cmd_balance(args) -> int:
    scene = load_scene(args.scene)
    model = scene.model
    driver = driver_of(args, scene)
    _, iv, _, _ = model.joint_slices()[model.link_names.index(driver)]
    revolute = model.body_info(model.body_names.index(driver))[1] == "Revolute"
    unit = "rad/s" if revolute else "m/s"
    if args.speed is None:
        speed = float(scene.v0[iv]) if scene.v0[iv] != 0.0 else 2.0 * math.pi
    else:
        speed = args.speed
    if not (math.isfinite(speed) and speed != 0.0):
        raise InvalidInputError(f"--speed: expected a finite non-zero speed, got {speed}")
    if args.samples < 2:
        raise InvalidInputError(f"--samples: expected at least 2, got {args.samples}")
    if args.max_mass is not None and not (math.isfinite(args.max_mass) and args.max_mass > 0):
        raise InvalidInputError(f"--max-mass: expected a mass > 0 (kg), got {args.max_mass}")
    for body in args.redesign or []:
        if body not in model.link_names:
            raise InvalidInputError(
                f"--redesign: no moving body named '{body}' in {scene.name} (moving bodies: "
                f"{', '.join(model.link_names)})"
            )
    cws = _counterweights(args, scene)
    weights = _weights(args)
    pareto = _pareto_spec(args.pareto) if args.pareto else None
    designing = bool(cws or args.redesign)
    if (args.zero or weights or pareto) and not designing:
        option = "--pareto" if pareto else "--zero" if args.zero else "--weight"
        raise InvalidInputError(
            f"{option}: needs something to choose: give --counterweight or --redesign"
        )
    if pareto and weights:
        raise InvalidInputError("--pareto: sweeps the weights itself; drop --weight")

    gravity = scene_gravity(scene)
    # Many samples take a while: a bar on stderr after half a second (Ctrl-C stops them).
    report, finish = progress_bar(2 * args.samples, sys.stderr, always=False, unit="steps")
    try:
        motion = prescribed_motion(model, driver, speed=speed, samples=args.samples,
                                   q_guess=scene.q0, gravity=gravity, progress=report)
    finally:
        finish()
    g_text = "no gravity" if gravity is None else f"gravity {_vec(gravity)} m/s²"
    print(f"{scene.name}: '{driver}' driven at {speed:.6g} {unit} over one "
          f"{'revolution' if revolute else 'cycle of 2π m'}, {args.samples} samples; {g_text}")
    title = f"{scene.name}: '{driver}' at {speed:.4g} {unit}"

    if not designing:
        summary, units = motion.summary(), motion.units()
        print(f"{'quantity':<40}{'RMS':>13}{'peak':>13}")
        for k, v in summary.items():
            print(f"{f'{k} ({units[k]})':<40}{v['rms']:>13.5g}{v['peak']:>13.5g}")
        if args.out:
            _write_rows(Path(args.out), ["quantity", "rms", "peak"],
                        [[k, v["rms"], v["peak"]] for k, v in summary.items()])
            print(f"table written to {args.out}")
        if args.plot:
            plot_motion(motion, args.plot, title=title)
            print(f"plot written to {args.plot}")
        return 0

    kwargs = dict(counterweights=cws, links=list(args.redesign or []), zero=tuple(args.zero or ()))
    if pareto:
        (first, second), count = pareto
        front = pareto_front(motion, (first, second), count, **kwargs)
        rows = []
        for b in front:
            total = sum(b.objective.values())
            rows.append([b.objective[first] / total, b.objective[second] / total,
                         objective_rms(b.after, first), objective_rms(b.after, second),
                         b.model.total_mass - model.total_mass])
        # The driving force is a torque (N·m) for a revolute driver, a force (N) for a slider.
        u = {"force": "N", "moment": "N·m", "torque": "N·m" if revolute else "N",
             "bearing": "N", "mass": "kg"}
        print(f"Pareto front, {len(front)} balances of {count} (RMS over the cycle; unbalanced: {first} "
              f"{objective_rms(motion, first):.5g} {u[first]}, {second} "
              f"{objective_rms(motion, second):.5g} {u[second]})")
        print(f"{'w ' + first:>10}{'w ' + second:>10}{f'RMS {first} ({u[first]})':>20}"
              f"{f'RMS {second} ({u[second]})':>20}{'mass added (kg)':>17}")
        for r in rows:
            print(f"{r[0]:>10.3f}{r[1]:>10.3f}{r[2]:>20.5g}{r[3]:>20.5g}{r[4]:>17.5g}")
        if args.out:
            _write_rows(Path(args.out), [f"weight_{first}", f"weight_{second}", f"rms_{first}",
                                         f"rms_{second}", "mass_added"], rows)
            print(f"table written to {args.out}")
        if args.plot:
            plot_pareto(front, (first, second), args.plot, title=f"{title}: Pareto front")
            print(f"plot written to {args.plot}")
        return 0

    try:
        b = balance(motion, objective=weights, **kwargs)
    except InertiaError as exc:
        if not args.redesign:
            raise
        raise InvalidInputError(
            f"--redesign: a redesigned body cannot be rebuilt from the point masses the "
            f"balance chose ({exc}): the optimum empties it; add counterweights, or ask less "
            f"(fewer --zero, other --weight)"
        ) from exc
    weighed = [f"{k}×{w:g}" for k, w in b.objective.items() if k not in b.zero and w > 0]
    goal = ", ".join([f"zero {z}" for z in b.zero] + weighed)
    print(f"balanced: {', '.join(f'zero {z}' for z in b.zero) or 'nothing made zero'}"
          + (f"; minimising the weighted RMS {', '.join(weighed)} (each relative to its "
             f"unbalanced RMS)" if weighed else "; least mass added"))
    _print_balance(b, model)
    if args.out:
        before, after = b.before.summary(), b.after.summary()
        _write_rows(
            Path(args.out), ["quantity", "rms_before", "rms_after", "peak_before", "peak_after"],
            [[k, before[k]["rms"], after[k]["rms"], before[k]["peak"], after[k]["peak"]]
             for k in before],
        )
        print(f"table written to {args.out}")
    if args.plot:
        plot_balance(b, args.plot, title=f"{title}: {goal}")
        print(f"plot written to {args.plot}")
    return 0
