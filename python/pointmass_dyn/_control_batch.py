""":func:`simulate_batch`'s runs with a controller (docs/control.md §3).

Each run is its own :class:`Simulator` loop. A Python controller holds the GIL while it
runs, but ``Simulator.step`` integrates with the GIL released: on ``threads`` threads (one
unless asked), one run integrates while another's controller runs, and runs integrate side
by side on separate cores. Runs share no state of ours (each its own simulator and noise
generator), so a run's result is the same bits whatever the thread count, as long as the
controllers keep none across runs either (one callable for every run that counts its calls,
say, sees the runs' calls interleaved on several threads)."""

from __future__ import annotations

import threading
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor, wait
from typing import Any

import numpy as np

from ._control import check_options, controlled_run
from ._simulation import SimulationResult
from .errors import InvalidInputError

__all__ = ["controlled_runs"]


def _per_run(scenes: Sequence[Any], controllers: Any, sensing: dict, q0: Any, v0: Any) -> list:
    """``(scene, controller, sensing)`` of each run, the per-run arguments checked."""
    count = len(scenes)
    for x in (q0, v0):
        if x is not None and np.ndim(x) == 2:
            count = max(count, int(np.shape(x)[0]))
    if callable(controllers):
        controllers = [controllers] * count
    else:
        controllers = list(controllers)
        if not controllers or not all(callable(f) for f in controllers):
            raise InvalidInputError(
                "controller: expected a callable f(t, q, v, sensors) or a list of them (one per run)"
            )
        count = max(count, len(controllers))
        if len(controllers) == 1:
            controllers = controllers * count
    seeds = sensing.get("seed")
    per_seed = isinstance(seeds, (list, tuple))
    sizes = {"controller": len(controllers), "scene": len(scenes) if len(scenes) > 1 else count,
             "seed": len(seeds) if per_seed else count}  # fmt: skip
    for x, name in ((q0, "q0"), (v0, "v0")):
        if x is not None and np.ndim(x) == 2:
            sizes[name] = int(np.shape(x)[0])
    wrong = {k: n for k, n in sizes.items() if n != count}
    if wrong:
        raise InvalidInputError(f"controller: expected {count} runs from every per-run argument, got {wrong}")
    runs = []
    for b in range(count):
        scene = scenes[b] if len(scenes) > 1 else scenes[0]
        changes = {}
        for x, name in ((q0, "q0"), (v0, "v0")):
            if x is not None:
                changes[name] = np.asarray(x, float)[b] if np.ndim(x) == 2 else x
        if changes:
            scene = scene.replace(**changes)
        runs.append((scene, controllers[b], dict(sensing, seed=seeds[b] if per_seed else seeds)))
    return runs


def _not_run(scene: Any, t0: float, message: str) -> SimulationResult:
    """A run with nothing computed: an empty trajectory and the reason."""
    m = scene.model
    return SimulationResult(
        t=np.empty(0), q=np.empty((0, m.nq)), v=np.empty((0, m.nv)), energy=None,
        t_events=[], q_events=[], v_events=[], nfev=0, n_accepted=0, n_rejected=0,
        status=-1, message=message, success=False, t_reached=t0, scene=scene.name,
    )  # fmt: skip


def _t0(scene: Any, t_span: Any) -> float:
    span = t_span if t_span is not None else scene.t_span
    try:
        return float(span[0])
    except (TypeError, ValueError, IndexError):
        return float("nan")


def controlled_runs(
    scenes: Sequence[Any],
    t_span: Any,
    controllers: Any,
    period: float,
    sensing: dict,
    options: dict,
    q0: Any = None,
    v0: Any = None,
    threads: int | None = None,
) -> tuple[list[SimulationResult], BaseException | None]:
    """The runs' results, and the exception that stopped the batch (Ctrl-C), if any.

    Run ``b`` is exactly ``simulate(scene_b, t_span, controller=f_b, ...)``. ``controllers``:
    one callable for every run or a sequence of one per run; ``q0``/``v0`` rows and a
    sequence of ``seed`` values are per run too. A run whose controller raises, whose control
    is refused (wrong length, not finite) or that cannot start ends alone: ``success``
    False, ``status`` -1, the reason in ``message``, its trajectory so far (empty if it
    could not start; bad input refused before a run starts raises, as in any call). Ctrl-C stops the batch: runs under way end at their next period, runs
    not started stay empty, and the ``KeyboardInterrupt`` is returned beside the results."""
    runs = _per_run(scenes, controllers, sensing, q0, v0)
    check_options(runs[0][0], t_span, options)  # the batch's own arguments: refused at once
    # One thread unless asked: with a cheap integration the GIL's hand-offs cost more than
    # the overlap gains (docs/control.md §3).
    threads = max(1, min(threads or 1, len(runs)))
    stopped = threading.Event()

    def one(b: int) -> SimulationResult:
        scene, f, run_sensing = runs[b]
        if stopped.is_set():
            return _not_run(scene, _t0(scene, t_span), "the batch was stopped before this run started")
        try:
            return controlled_run(scene, t_span, f, period, run_sensing, options, stop=stopped.is_set)
        except Exception as error:  # this run's only
            res = getattr(error, "result", None)
            why = f"{type(error).__name__}: {error}"
            if res is None:
                if isinstance(error, InvalidInputError):  # bad input, refused as in any call
                    raise
                return _not_run(scene, _t0(scene, t_span), f"the run could not start: {why}")
            res.success, res.status = False, -1
            res.message = f"the run stopped at t = {res.t_reached}: {why}"
            return res

    out: list[SimulationResult | None] = [None] * len(runs)
    interrupt = None
    if threads == 1:
        for b in range(len(runs)):
            try:
                out[b] = one(b)
            except KeyboardInterrupt as error:  # the batch stops, with what it has
                interrupt = error
                stopped.set()
                part = getattr(error, "result", None)
                out[b] = part if part is not None else one(b)
                out[b].success, out[b].status = False, -1
                out[b].message = f"the batch was stopped; this run reached t = {out[b].t_reached}"
                break
    else:
        with ThreadPoolExecutor(max_workers=threads) as pool:
            futures = [pool.submit(one, b) for b in range(len(runs))]
            pending = set(futures)
            while pending:
                try:
                    # The calling thread waits in short slices, so Ctrl-C reaches it.
                    _, pending = wait(pending, timeout=0.05)
                except KeyboardInterrupt as error:
                    interrupt = error
                    stopped.set()
            for b, fut in enumerate(futures):
                out[b] = fut.result()
    for b, res in enumerate(out):
        if res is None:  # not reached after Ctrl-C
            scene = runs[b][0]
            out[b] = _not_run(scene, _t0(scene, t_span), "the batch was stopped before this run started")
    return out, interrupt
