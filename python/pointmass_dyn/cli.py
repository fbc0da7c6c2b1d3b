"""``pointmass-dyn``: simulate a scene, print its point masses, list the bundled scenes,
measure work–precision."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from .errors import PointMassDynError
from .scenes import builtin_scenes, load_scene
from .simulation import simulate


def _progress_printer(t0: float, t1: float, stream):
    """A one-line progress indicator, shown only for runs that take a while."""
    start = time.perf_counter()
    state = {"shown": False}

    def report(t: float) -> None:
        if time.perf_counter() - start < 0.5:
            return
        frac = (t - t0) / (t1 - t0) if t1 != t0 else 1.0
        bar = "#" * int(30 * frac)
        stream.write(f"\r  t = {t:10.4f} s  [{bar:<30}] {100 * frac:5.1f}%")
        stream.flush()
        state["shown"] = True

    def finish() -> None:
        if state["shown"]:
            stream.write("\n")

    return report, finish


def _write_trajectory(path: Path, result, model) -> None:
    from .plotting import coordinate_labels

    qlab, vlab, _ = coordinate_labels(model)
    if path.suffix == ".npz":
        extra = {} if result.energy is None else {"energy": result.energy}
        np.savez(path, t=result.t, q=result.q, v=result.v, q_names=np.array(qlab),
                 v_names=np.array(vlab), **extra)
    elif path.suffix == ".csv":
        cols = [result.t[:, None], result.q, result.v]
        header = ["t"] + [f"q[{k}] {n}" for k, n in enumerate(qlab)] + [
            f"v[{k}] {n}" for k, n in enumerate(vlab)]
        if result.energy is not None:
            cols.append(np.asarray(result.energy)[:, None])
            header.append("energy")
        np.savetxt(path, np.hstack(cols), delimiter=",", header=",".join(header), comments="",
                   fmt="%.17g")
    else:
        raise PointMassDynError(f"--out: expected a .csv or .npz file name, got '{path}'")


def cmd_simulate(args) -> int:
    scene = load_scene(args.scene)
    t_span = scene.t_span or (0.0, 10.0)
    if args.t_end is not None:
        t_span = (t_span[0], args.t_end)
    report, finish = _progress_printer(t_span[0], t_span[1], sys.stderr)
    start = time.perf_counter()
    result = simulate(scene, t_span, rtol=args.rtol, atol=args.atol, energy=True, progress=report)
    wall = time.perf_counter() - start
    finish()
    model = scene.model
    e = np.asarray(result.energy)
    # Relative to the largest kinetic energy reached: the total may be ~0 (zero potential at
    # the pivot), which would make a ratio to |E| meaningless.
    kinetic = max(model.kinetic_energy(q, v) for q, v in zip(result.q, result.v))
    drift = np.max(np.abs(e - e[0]))
    print(f"{scene.name}: {result.message}")
    print(f"  {result.n_accepted} steps ({result.n_rejected} rejected), {result.nfev} evaluations, "
          f"{wall * 1e3:.1f} ms")
    print(f"  energy: E(0) = {e[0]:.12g} J, max |E - E(0)| = {drift:.3e} J "
          f"({drift / max(kinetic, 1e-300):.2e} of the largest kinetic energy)")
    if result.constraint_residual is not None and len(result.constraint_residual):
        print(f"  loops: {model.nloops} closed, largest residual {result.constraint_residual.max():.3e} "
              f"(drift before projection at most {result.constraint_drift:.3e})")
    if args.out:
        _write_trajectory(Path(args.out), result, model)
        print(f"  trajectory written to {args.out}")
    if args.plot:
        from .plotting import plot_trajectory

        plot_trajectory(result, model, args.plot, title=f"{scene.name}: {result.message}")
        print(f"  plot written to {args.plot}")
    return 0 if result.success else 1


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


def cmd_scenes(args) -> int:
    for name, path in builtin_scenes().items():
        scene = load_scene(path)
        first = scene.description.split(". ")[0].strip()
        print(f"{name:<20} nq={scene.model.nq:<3} {first}")
    return 0


def cmd_work_precision(args) -> int:
    from .work_precision import (
        DEFAULT_TOLERANCES,
        plot_work_precision,
        work_precision,
        write_csv,
    )

    tols = DEFAULT_TOLERANCES if not args.tolerances else tuple(args.tolerances)
    results = []
    for name in args.scene:
        def say(msg: str) -> None:
            if args.verbose:
                print(f"  {msg}", file=sys.stderr, flush=True)

        res = work_precision(
            name, tols, t_end=args.t_end, repeats=args.repeats, scipy=not args.no_scipy,
            scipy_repeats=args.scipy_repeats, rk4=not args.no_rk4, progress=say,
        )
        results.append(res)
        print(res.table())
        print()
    if args.out:
        write_csv(results, args.out)
        print(f"table written to {args.out}")
    if args.plot:
        plot_work_precision(results, args.plot)
        print(f"plot written to {args.plot}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="pointmass-dyn",
        description="Multibody dynamics with equimomental point masses and DeNOC matrices.",
    )
    sub = p.add_subparsers(dest="command", required=True)
    s = sub.add_parser("simulate", help="simulate a scene (a file or a bundled name)")
    s.add_argument("scene")
    s.add_argument("--t-end", type=float, default=None, help="end time (s); default: the scene's")
    s.add_argument("--rtol", type=float, default=None)
    s.add_argument("--atol", type=float, default=None)
    s.add_argument("--out", default=None, help="write the trajectory to a .csv or .npz file")
    s.add_argument("--plot", default=None, help="write a plot of q and v against time (PNG)")
    s.set_defaults(func=cmd_simulate)
    pm = sub.add_parser("point-masses", help="print each body's seven point masses")
    pm.add_argument("scene")
    pm.set_defaults(func=cmd_point_masses)
    sc = sub.add_parser("scenes", help="list the bundled scenes")
    sc.set_defaults(func=cmd_scenes)
    wp = sub.add_parser(
        "work-precision",
        help="error, time and evaluations of simulate against tolerance, beside SciPy RK45 "
             "and fixed-step RK4",
    )
    wp.add_argument("scene", nargs="+", help="one or more scene files or bundled names")
    wp.add_argument("--plot", default=None, help="write the work-precision plot (PNG)")
    wp.add_argument("--out", default=None, help="write the table to a .csv file")
    wp.add_argument("--t-end", type=float, default=None, help="end time (s); default: the scene's")
    wp.add_argument("--tolerances", type=float, nargs="+", default=None,
                    help="rtol = atol values (default 1e-3 ... 1e-12)")
    wp.add_argument("--repeats", type=int, default=5, help="timing runs of simulate (best kept)")
    wp.add_argument("--scipy-repeats", type=int, default=2, help="timing runs of SciPy RK45")
    wp.add_argument("--no-scipy", action="store_true", help="skip SciPy RK45 (the slow part)")
    wp.add_argument("--no-rk4", action="store_true", help="skip the fixed-step RK4 line")
    wp.add_argument("-v", "--verbose", action="store_true", help="report progress on stderr")
    wp.set_defaults(func=cmd_work_precision)
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except PointMassDynError as exc:
        print(f"pointmass-dyn: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # writing --out / --plot (inputs are read with our own errors)
        print(f"pointmass-dyn: error: cannot write the output file: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
