"""``pointmass-dyn sweep``: many runs of one scene through :func:`simulate_batch`, over a grid
of parameter values and/or random perturbations of the initial state (docs/batch.md).

The runs are built here (:func:`sweep_runs`) exactly as a Python user would build them for
``simulate_batch``, so that the ``.npz`` the command writes is the batch's result, bit for
bit."""

from __future__ import annotations

import argparse
import itertools
import math
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._batch import scenes_from_params, simulate_batch
from .._helpers import quaternion_slices, scene_gravity
from ..errors import InvalidInputError
from ..plotting import coordinate_labels, coordinate_units, plot_sweep
from ..scenes import load_scene
from ._animate import check_outputs
from ._progress import progress_bar

PARAM_SPEC = "KEY=START:STOP:COUNT[:log] | KEY=V1,V2,..."

SWEEP_EPILOG = """\
Runs: every combination of the --param values (a grid, the first --param varying slowest),
each repeated --runs times (default 1) with its own random initial state when --q0-noise or
--v0-noise is given (Gaussian, standard deviation SIGMA in the coordinates' units, rad, m or
m/s; drawn from --seed, so that a sweep is repeatable; quaternions are renormalised).

--param KEY=...   one scalar per run; KEY is
    <body>.mass                  a body's mass (kg)
    <body>.com.x|y|z             a component of a body's centre of mass (m, its own frame)
    gravity.x|y|z                a component of gravity (m/s²; the rest is the scene's)
    <effect>.<parameter>         an effect's parameter, the effect by its name or family:
                                 springs.stiffness, springs.rest, dampers.damping,
                                 friction.friction, friction.v_eps, point_spring.stiffness,
                                 point_spring.rest_length, point_spring.damping
  values: START:STOP:COUNT  COUNT values evenly spaced from START to STOP (both included;
                            with :log, evenly spaced in log scale)
          V1,V2,...         the values listed (one value: every run)

Prints how many runs failed (and why), the wall time, runs per second and the spread of the
final state; exit status 1 if any run failed, 2 for bad arguments. --out writes an .npz with
t (T,), q (B, T, nq), v (B, T, nv) (NaN past a failed run's end), success, status, message,
t_reached, nfev, q0, v0, param_names and param_values (B, P). --plot draws one coordinate
over the runs (median and percentile bands), its final value against the swept parameters,
and the final spread of every coordinate.

examples:
  pointmass-dyn sweep chain7 --param link0.mass=0.5:2:4 --param gravity.z=-9.81,-1.62
  pointmass-dyn sweep chain7 --runs 64 --q0-noise 1e-3 --threads 2 --out runs.npz --plot fan.png
  pointmass-dyn sweep pendulum_planar --param rod.mass=1:5:9 --t-end 2 --plot mass.png
"""


def add_parser(sub) -> argparse.ArgumentParser:
    """The ``sweep`` subcommand."""
    sw = sub.add_parser(
        "sweep",
        help="many runs of a scene on a thread pool: a grid of parameters and/or random "
             "initial states",
        description="Many runs of one scene (a file or a bundled name) with "
                    "simulate_batch:\nparameter grids, perturbed initial states, their "
                    "spread.",
        epilog=SWEEP_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sw.add_argument("scene", help="a scene file or a bundled name")
    sw.add_argument("--param", action="append", metavar=PARAM_SPEC,
                    help="a swept parameter (see below); repeat for a grid")
    sw.add_argument("--runs", type=int, default=1, metavar="B",
                    help="runs per grid point, each with its own perturbed initial state "
                         "(default 1)")
    sw.add_argument("--q0-noise", type=float, default=0.0, metavar="SIGMA",
                    help="standard deviation of the Gaussian added to q0 (default 0)")
    sw.add_argument("--v0-noise", type=float, default=0.0, metavar="SIGMA",
                    help="standard deviation of the Gaussian added to v0 (default 0)")
    sw.add_argument("--seed", type=int, default=0, metavar="N",
                    help="seed of the perturbations (default 0)")
    sw.add_argument("--t-end", type=float, default=None, metavar="T",
                    help="end time (s); default: the scene's, else 10")
    sw.add_argument("--samples", type=int, default=201, metavar="N",
                    help="output times from start to end, both included (default 201)")
    sw.add_argument("--rtol", type=float, default=None, metavar="R",
                    help="relative tolerance (default: the scene's)")
    sw.add_argument("--atol", type=float, default=None, metavar="A",
                    help="absolute tolerance (default: the scene's)")
    sw.add_argument("--threads", type=int, default=None, metavar="N",
                    help="worker threads (default: one per core)")
    sw.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                    help="progress bar on stderr (default: when stderr is a terminal)")
    sw.add_argument("--coord", default=None, metavar="K|NAME",
                    help="the coordinate --plot draws: an index into q or a body name "
                         "(default: the one whose final value spreads most)")
    sw.add_argument("--out", default=None, metavar="FILE.npz", help="write the runs (.npz)")
    sw.add_argument("--plot", default=None, metavar="FILE.png",
                    help="write a summary figure (PNG)")
    sw.set_defaults(func=cmd_sweep)
    return sw


# --------------------------------------------------------------------------------------------
# Building the runs
# --------------------------------------------------------------------------------------------
@dataclass
class SweepRuns:
    """What ``simulate_batch`` is given: ``q0`` (B, nq), ``v0`` (B, nv), ``params`` (the
    batch's dict, or None), and the swept scalars ``names`` with their ``values`` (B, P)."""

    q0: np.ndarray
    v0: np.ndarray
    params: dict[str, np.ndarray] | None
    names: list[str]
    values: np.ndarray
    grid: tuple[int, ...]


def parse_values(spec: str) -> tuple[str, np.ndarray]:
    """``KEY=START:STOP:COUNT[:log]`` or ``KEY=V1,V2,...`` -> (KEY, values)."""
    key, eq, text = spec.partition("=")
    key = key.strip()
    bad = f"--param: expected {PARAM_SPEC}, got '{spec}'"
    if not eq or not key or not text.strip():
        raise InvalidInputError(bad)
    if ":" in text:
        parts = [p.strip() for p in text.split(":")]
        log = len(parts) == 4 and parts[3] == "log"
        if len(parts) != 3 and not log:
            raise InvalidInputError(bad)
        try:
            start, stop = float(parts[0]), float(parts[1])
            count = int(parts[2])
        except ValueError:
            raise InvalidInputError(
                f"--param: expected START:STOP:COUNT with numbers START, STOP and a whole "
                f"COUNT, got '{text}' in '{spec}'"
            ) from None
        if count < 1 or not (math.isfinite(start) and math.isfinite(stop)):
            raise InvalidInputError(
                f"--param: expected finite START, STOP and COUNT >= 1, got '{text}' in "
                f"'{spec}'"
            )
        if log:
            if not (start > 0 and stop > 0):
                raise InvalidInputError(
                    f"--param: a :log range needs START > 0 and STOP > 0, got '{text}' in "
                    f"'{spec}'"
                )
            return key, np.geomspace(start, stop, count)
        return key, np.linspace(start, stop, count)
    try:
        vals = np.array([float(p) for p in text.split(",")])
    except ValueError:
        raise InvalidInputError(
            f"--param: expected numbers separated by commas, got '{text}' in '{spec}'"
        ) from None
    if not np.all(np.isfinite(vals)):
        raise InvalidInputError(f"--param: expected finite values, got '{text}' in '{spec}'")
    return key, vals


_AXIS = {"x": 0, "y": 1, "z": 2}


def _key_target(scene, key: str) -> tuple[str, int | None]:
    """The ``simulate_batch`` params key that ``key`` sets, and the component (or None)."""
    model = scene.model
    head, _, tail = key.rpartition(".")
    if head == "gravity" and tail in _AXIS:
        return "gravity", _AXIS[tail]
    if head.endswith(".com") and head[:-4] in model.body_names and tail in _AXIS:
        return head, _AXIS[tail]
    if head in model.body_names and tail == "mass":
        return key, None
    effects = {e.name for e in scene.effects} | {e.kind for e in scene.effects}
    if head in effects and tail:
        return key, None
    raise InvalidInputError(
        f"--param: unknown key '{key}' for {scene.name}: expected <body>.mass, "
        f"<body>.com.x|y|z, gravity.x|y|z or <effect>.<parameter> (bodies: "
        f"{', '.join(model.body_names)}; effects: {', '.join(sorted(effects)) or 'none'})"
    )


def sweep_runs(scene, param_specs=(), runs: int = 1, q0_noise: float = 0.0,
               v0_noise: float = 0.0, seed: int = 0) -> SweepRuns:
    """The runs of a sweep: the grid of ``param_specs`` (strings as ``--param`` takes them,
    the first varying slowest), each point repeated ``runs`` times; q0 and v0 perturbed by
    Gaussians (``q0`` drawn first, then ``v0``, from ``numpy.random.default_rng(seed)``)."""
    model = scene.model
    if runs < 1:
        raise InvalidInputError(f"--runs: expected a whole number >= 1, got {runs}")
    for option, sigma in (("--q0-noise", q0_noise), ("--v0-noise", v0_noise)):
        if not (math.isfinite(sigma) and sigma >= 0.0):
            raise InvalidInputError(f"{option}: expected a standard deviation >= 0, got {sigma}")
    if model.nloops and (q0_noise or v0_noise):
        option = "--q0-noise" if q0_noise else "--v0-noise"
        raise InvalidInputError(
            f"{option}: {scene.name} has closed loops, which a perturbed initial state would "
            f"open; sweep --param instead"
        )
    if runs > 1 and q0_noise == 0.0 and v0_noise == 0.0:
        raise InvalidInputError(
            f"--runs: {runs} runs per grid point would be identical: give --q0-noise or "
            f"--v0-noise"
        )
    names, axes = [], []
    for spec in param_specs:
        key, vals = parse_values(spec)
        if key in names:
            raise InvalidInputError(f"--param: '{key}' is given twice")
        _key_target(scene, key)
        names.append(key)
        axes.append(vals)
    grid = tuple(len(a) for a in axes)
    combos = list(itertools.product(*axes))
    points = np.array(combos, dtype=float).reshape(len(combos), len(axes))
    values = np.repeat(points, runs, axis=0)
    count = len(values)

    params: dict[str, np.ndarray] = {}
    for j, key in enumerate(names):
        target, axis = _key_target(scene, key)
        if axis is None:
            params[target] = values[:, j].copy()
            continue
        if target not in params:
            if target == "gravity":
                g = scene_gravity(scene)
                base = np.zeros(3) if g is None else g
            else:
                base = np.asarray(model.body(target[:-4]).com, dtype=float)
            params[target] = np.tile(base, (count, 1))
        params[target][:, axis] = values[:, j]

    rng = np.random.default_rng(seed)
    q0 = np.tile(np.asarray(scene.q0, dtype=float), (count, 1))
    v0 = np.tile(np.asarray(scene.v0, dtype=float), (count, 1))
    if q0_noise > 0.0:
        q0 = q0 + q0_noise * rng.standard_normal(q0.shape)
        for s in quaternion_slices(model):
            q0[:, s] /= np.linalg.norm(q0[:, s], axis=1, keepdims=True)
    if v0_noise > 0.0:
        v0 = v0 + v0_noise * rng.standard_normal(v0.shape)
    if params:
        # Every run's scene is built before anything runs: a bad value (a negative stiffness,
        # a mass <= 0) is reported here, naming the option.
        try:
            scenes_from_params(scene, params)
        except (InvalidInputError, ValueError) as exc:
            raise InvalidInputError(f"--param: {exc}") from None
    return SweepRuns(q0=q0, v0=v0, params=params or None, names=names, values=values,
                     grid=grid)


# --------------------------------------------------------------------------------------------
# The command
# --------------------------------------------------------------------------------------------
def _failure_lines(message: list[str], success: np.ndarray, limit: int = 8) -> list[str]:
    """Failed runs grouped by message (the time reached is part of most messages, so runs
    are grouped by what precedes ' at t')."""
    groups: dict[str, list[int]] = {}
    for k in np.flatnonzero(~success):
        groups.setdefault(message[k], []).append(int(k))
    lines = []
    for msg, idx in sorted(groups.items(), key=lambda kv: -len(kv[1]))[:limit]:
        shown = ", ".join(map(str, idx[:6])) + (", ..." if len(idx) > 6 else "")
        lines.append(f"    {len(idx)} run{'s' * (len(idx) > 1)} ({shown}): {msg}")
    if len(groups) > limit:
        lines.append(f"    ... and {len(groups) - limit} other messages")
    return lines


def _pick_coord(text: str | None, model, qlab: list[str], final: np.ndarray) -> int:
    nq = model.nq
    if text is None:
        if final.shape[0] == 0:
            return nq - 1
        spread = np.nanstd(final, axis=0)
        return int(np.nanargmax(spread)) if np.any(np.isfinite(spread)) else nq - 1
    try:
        k = int(text)
    except ValueError:
        k = None
    if k is not None:
        if not -nq <= k < nq:
            raise InvalidInputError(f"--coord: expected an index in 0..{nq - 1}, got {k}")
        return k % nq
    if text in model.link_names:
        return model.joint_slices()[model.link_names.index(text)][0]
    if text in qlab:
        return qlab.index(text)
    raise InvalidInputError(
        f"--coord: expected an index into q (0..{nq - 1}) or a moving body "
        f"({', '.join(model.link_names)}), got '{text}'"
    )


def _thread_count(threads: int | None) -> int:
    if threads is not None:
        return threads
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def cmd_sweep(args) -> int:
    if args.samples < 2:
        raise InvalidInputError(f"--samples: expected at least 2, got {args.samples}")
    if args.threads is not None and args.threads < 1:
        raise InvalidInputError(f"--threads: expected at least 1, got {args.threads}")
    for option, value in (("--rtol", args.rtol), ("--atol", args.atol)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise InvalidInputError(f"{option}: expected a tolerance > 0, got {value}")
    if args.out and Path(args.out).suffix != ".npz":
        raise InvalidInputError(f"--out: expected a .npz file name, got '{args.out}'")
    scene = load_scene(args.scene)
    model = scene.model
    check_outputs(model, [("--out", args.out), ("--plot", args.plot)])
    t0, t_end = scene.t_span or (0.0, 10.0)
    if args.t_end is not None:
        t_end = args.t_end
    if not (math.isfinite(t_end) and t_end > t0):
        raise InvalidInputError(f"--t-end: expected an end time > {t0:g} s, got {t_end:g}")
    runs = sweep_runs(scene, args.param or (), args.runs, args.q0_noise, args.v0_noise,
                      args.seed)
    qlab, vlab, angular = coordinate_labels(model)
    if args.coord is not None:  # checked before the runs, not after
        _pick_coord(args.coord, model, qlab, np.zeros((0, model.nq)))
    count = len(runs.q0)
    t_eval = np.linspace(t0, t_end, args.samples)
    rtol = args.rtol if args.rtol is not None else scene.rtol
    atol = args.atol if args.atol is not None else scene.atol
    threads = _thread_count(args.threads)
    what = []
    if runs.names:
        what.append("grid " + " × ".join(map(str, runs.grid)) + " of " + ", ".join(runs.names))
    noise = [f"{n} σ = {s:g}" for n, s in (("q0", args.q0_noise), ("v0", args.v0_noise)) if s]
    if noise:
        what.append(f"{args.runs} perturbed run{'s' * (args.runs > 1)} per point "
                    f"({', '.join(noise)}, seed {args.seed})" if runs.names else
                    f"{', '.join(noise)}, seed {args.seed}")
    print(f"{scene.name}: {count} run{'s' * (count > 1)}"
          + (f" ({'; '.join(what)})" if what else "")
          + f", t = {t0:g} → {t_end:g} s, rtol {rtol if rtol is not None else 1e-3:g}, "
            f"atol {atol if atol is not None else 1e-6:g}, {threads} thread"
            f"{'s' * (threads > 1)}", flush=True)

    show = args.progress if args.progress is not None else sys.stderr.isatty()
    report, finish = progress_bar(count, sys.stderr, always=args.progress is True)
    start = time.perf_counter()
    try:
        res = simulate_batch(
            scene, (t0, t_end), q0=runs.q0, v0=runs.v0, params=runs.params, t_eval=t_eval,
            rtol=args.rtol, atol=args.atol, threads=args.threads,
            progress=report if show else None,
        )
    except KeyboardInterrupt:
        finish()
        print("pointmass-dyn: interrupted", file=sys.stderr)
        return 130
    wall = time.perf_counter() - start
    finish(count)

    ok = res.success
    nfail = int((~ok).sum())
    print(f"  {count - nfail} succeeded, {nfail} failed; wall {wall:.3g} s, "
          f"{count / wall:.4g} runs/s, {int(res.nfev.sum())} evaluations "
          f"({res.nfev.mean():.0f} per run)")
    if nfail:
        print("  failures:")
        for line in _failure_lines(res.message, ok):
            print(line)
    final_q = res.q[ok, -1, :]
    final_v = res.v[ok, -1, :]
    if ok.any():
        print(f"  final state at t = {t_end:g} s over the {int(ok.sum())} successful runs:")
        qu, vu = coordinate_units(model)
        unit = {"angle": "rad", "length": "m", "quaternion": "1", "angular rate": "rad/s",
                "linear rate": "m/s"}
        labels = [f"{lab} ({unit[u]})" for lab, u in zip(qlab + vlab, qu + vu)]
        width = max(12, *(len(s) for s in labels))
        print(f"    {'':<{width}}{'mean':>13}{'std':>12}{'min':>13}{'max':>13}")
        for lab, col in zip(labels, itertools.chain(final_q.T, final_v.T)):
            print(f"    {lab:<{width}}{col.mean():>13.5g}{col.std():>12.4g}{col.min():>13.5g}"
                  f"{col.max():>13.5g}")
    if args.out:
        np.savez(
            args.out, t=res.t, q=res.q, v=res.v, success=res.success, status=res.status,
            message=np.array(res.message, dtype=str), t_reached=res.t_reached, nfev=res.nfev,
            q0=runs.q0, v0=runs.v0, param_names=np.array(runs.names, dtype=str),
            param_values=runs.values, q_names=np.array(qlab), v_names=np.array(vlab),
            scene=np.array(scene.name), seed=np.array(args.seed),
        )
        print(f"  runs written to {args.out}")
    if args.plot:
        k = _pick_coord(args.coord, model, qlab, final_q)
        plot_sweep(res.t, res.q, ok, qlab, angular, runs.names, runs.values, k, args.plot,
                   title=f"{scene.name}: {count} runs, {count - nfail} succeeded "
                         f"({wall:.3g} s on {threads} thread{'s' * (threads > 1)})")
        print(f"  plot written to {args.plot} (coordinate {k}: {qlab[k]})")
    return 0 if nfail == 0 else 1
