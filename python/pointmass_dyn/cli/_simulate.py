"""``pointmass-dyn simulate``: simulate a scene, report steps, evaluations and energy drift;
write the trajectory (.csv, .npz), a plot or an animation."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from .._simulation import energies, simulate
from ..errors import PointMassDynError
from ..plotting import coordinate_labels, plot_trajectory
from ..scenes import load_scene
from ._animate import add_options as add_animate_options
from ._animate import check_outputs
from ._animate import write as write_animation


def add_parser(sub):
    """The ``simulate`` subcommand."""
    s = sub.add_parser("simulate", help="simulate a scene (a file or a bundled name)")
    s.add_argument("scene")
    s.add_argument("--t-end", type=float, default=None, help="end time (s); default: the scene's")
    s.add_argument("--rtol", type=float, default=None)
    s.add_argument("--atol", type=float, default=None)
    s.add_argument("--method", default=None,
                   help="RK45 (default), DOP853, Radau, RK4, Euler or auto; default: the scene's")
    s.add_argument("--dt", type=float, default=None, help="fixed step (s) of RK4 and Euler")
    s.add_argument("--out", default=None, help="write the trajectory to a .csv or .npz file")
    s.add_argument("--plot", default=None, help="write a plot of q and v against time (PNG)")
    s.add_argument("--animate", default=None, metavar="PATH",
                   help="write a 3-D animation (.html, .gif or .mp4; options as 'animate')")
    add_animate_options(s)
    s.set_defaults(func=cmd_simulate)
    return s


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


def _work_of_other_effects(scene, result) -> tuple[np.ndarray, list[str]]:
    """The work W(t) (J) done since t0 by the effects whose energy is not in
    ``result.energy`` (dampers, friction, torques, contact: everything but gravity and
    springs), by the trapezoid rule over the result's samples, and their names. The energy
    balance ``E(t) - E(0) = W(t)`` then holds to the accuracy of the run and of that rule."""
    stored = set(energies(scene, result.q[0], result.v[0]))
    doers = [k for k in result.power if k not in stored]
    if not doers:
        return np.zeros(len(result.t)), []
    p = np.sum([np.asarray(result.power[k]) for k in doers], axis=0)
    dt = np.diff(result.t)
    return np.concatenate([[0.0], np.cumsum(0.5 * dt * (p[1:] + p[:-1]))]), doers


def cmd_simulate(args) -> int:
    scene = load_scene(args.scene)
    if args.out and Path(args.out).suffix not in (".csv", ".npz"):
        raise PointMassDynError(f"--out: expected a .csv or .npz file name, got '{args.out}'")
    check_outputs(scene.model, [("--out", args.out), ("--plot", args.plot),
                                ("--animate", args.animate)],
                  args.trail if args.animate else None, args.size if args.animate else None)
    t_span = scene.t_span or (0.0, 10.0)
    if args.t_end is not None:
        t_span = (t_span[0], args.t_end)
    report, finish = _progress_printer(t_span[0], t_span[1], sys.stderr)
    start = time.perf_counter()
    result = simulate(scene, t_span, rtol=args.rtol, atol=args.atol, energy=True, power=True,
                      progress=report, method=args.method, dt=args.dt)
    wall = time.perf_counter() - start
    finish()
    model = scene.model
    e = np.asarray(result.energy)
    # Relative to the largest kinetic energy reached: the total may be ~0 (zero potential at
    # the pivot), which would make a ratio to |E| meaningless.
    kinetic = max(model.kinetic_energy(q, v) for q, v in zip(result.q, result.v))
    work, doers = _work_of_other_effects(scene, result)
    drift = np.max(np.abs(e - e[0] - work))
    print(f"{scene.name}: {result.message}")
    print(f"  method {result.method}"
          + (f" (switched to {result.switched_to} at t = {result.t_switch:g} s)" if result.switched_to else ""))
    print(f"  {result.n_accepted} steps ({result.n_rejected} rejected), {result.nfev} evaluations, "
          f"{wall * 1e3:.1f} ms")
    relative = f"({drift / max(kinetic, 1e-300):.2e} of the largest kinetic energy)"
    if doers:
        print(f"  energy balance: E(0) = {e[0]:.12g} J, E(end) - E(0) = {e[-1] - e[0]:.6g} J, "
              f"work of {', '.join(doers)} = {work[-1]:.6g} J; max |E - E(0) - W| = "
              f"{drift:.3e} J {relative} (W by the trapezoid rule over the steps)")
    else:
        print(f"  energy: E(0) = {e[0]:.12g} J, max |E - E(0)| = {drift:.3e} J {relative}")
    if result.constraint_residual is not None and len(result.constraint_residual):
        print(f"  loops: {model.nloops} closed, largest residual {result.constraint_residual.max():.3e} "
              f"(drift before projection at most {result.constraint_drift:.3e})")
    if args.out:
        _write_trajectory(Path(args.out), result, model)
        print(f"  trajectory written to {args.out}")
    if args.plot:
        plot_trajectory(result, model, args.plot, title=scene.name)
        print(f"  plot written to {args.plot}")
    if args.animate:
        write_animation(args, result, scene, args.animate)
    return 0 if result.success else 1
