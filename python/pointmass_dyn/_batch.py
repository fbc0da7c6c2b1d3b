"""Many simulations of one mechanism: :func:`simulate_batch` runs them on a pool of threads
in Rust with the GIL released once, each run bit for bit the :func:`simulate` call it stands
for, whatever the thread count (docs/batch.md).

Runs differ by their initial states (``q0``, ``v0`` with one row per run) and by
``params``, a dict of per-run values::

    "gravity"                    (B, 3)   every gravity effect's g
    "<effect>.<parameter>"       (B,) or (B, k)   an effect's parameter by its name (or
                                          family): spring stiffness/rest, damper damping,
                                          friction friction/v_eps, point_spring
                                          stiffness/rest_length/damping, torque tau,
                                          tabulated_torque values, pd_torque kp/kd
    "<body>.mass" / ".com" / ".inertia"   (B,), (B, 3), (B, 3, 3)   a body's inertial
                                          (the model's structure is kept)

or by giving a list of scenes (one per run).
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _core
from ._control_batch import controlled_runs
from ._core import RunConfig, Scene
from ._helpers import changed_settings, float_array
from ._simulation import SimulationResult, result_from_run
from .errors import (
    InvalidInputError,
    OutOfMemoryError,
    PointMassDynError,
    SingularPassageWarning,
)

#: Memory a run of a batch holds at least, besides its outputs at ``t_eval``: its result's
#: Python objects (measured: a 100,000-run batch of a small scene took 438 MB).
BYTES_PER_RUN = 4400


@dataclass
class BatchResult:
    """B runs. ``results``: each run's :class:`SimulationResult` (a run that could not start
    has ``success=False``, an empty trajectory and the reason as its message). With
    ``t_eval``: ``t`` (T,), ``q`` (B, T, nq), ``v`` (B, T, nv), NaN past a failed run's
    end; scenes of different sizes fill the first ``nq``/``nv`` columns of their rows (the
    widest scene's width), NaN after them. Per run: ``success``, ``status``, ``message``,
    ``t_reached``, ``nfev``."""

    results: list[SimulationResult]
    t: np.ndarray | None
    q: np.ndarray | None
    v: np.ndarray | None
    success: np.ndarray
    status: np.ndarray
    message: list[str]
    t_reached: np.ndarray
    nfev: np.ndarray

    def __len__(self) -> int:
        return len(self.results)


def _rows(name: str, value: Any, count: int | None, shape: tuple[int, ...]) -> np.ndarray:
    """``value`` as B rows of ``shape`` (B from the first such argument)."""
    arr = float_array(f"params['{name}']", value, "numbers, one value per run")
    if arr.ndim == len(shape):
        arr = arr[None]
    if arr.shape[1:] != shape or (count is not None and arr.shape[0] != count):
        want = f"({'B' if count is None else count}, {', '.join(map(str, shape))})".replace(
            ", )", ")"
        )
        raise InvalidInputError(f"params['{name}']: expected shape {want}, got {arr.shape}")
    return arr


def _effect_param(effects: list, name: str, parameter: str, value: np.ndarray) -> list:
    hits = [k for k, e in enumerate(effects) if name in (e.name, e.kind)]
    if not hits:
        names = sorted({e.name for e in effects} | {e.kind for e in effects})
        raise InvalidInputError(
            f"params: no effect named '{name}' in the scene (effects: {names}); a body "
            f"parameter is '<body>.mass', '.com' or '.inertia'"
        )
    out = list(effects)
    for k in hits:
        out[k] = out[k].with_parameter(parameter, np.atleast_1d(value))
    return out


def _physical_memory() -> int | None:
    try:
        return os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):  # not POSIX: no bound
        return None


def check_batch_memory(count: int, nq: int, nv: int, t_eval: Any = None) -> None:
    """Refuses, before anything is built, a batch whose results alone would exceed the
    machine's physical memory (:class:`OutOfMemoryError` naming the sizes)."""
    try:
        points = 0 if t_eval is None else int(np.size(t_eval))
    except (TypeError, ValueError):  # not an array: the core names the argument
        points = 0
    need = count * (BYTES_PER_RUN + 3 * 8 * (nq + nv) * points)
    have = _physical_memory()
    if have is not None and need > have:
        raise OutOfMemoryError(
            f"simulate_batch: {count} runs need at least {need / 2**30:.1f} GiB for their "
            f"results ({BYTES_PER_RUN} bytes a run plus {points} output times of {nq + nv} "
            f"values), more than this machine's {have / 2**30:.1f} GiB; split the batch (or "
            "use sweep(..., scheduler=...) over a cluster)"
        )


def _run_scene(scene: Scene, per: dict, count: int, b: int, bodies: set) -> Scene:
    """Run ``b``'s scene: ``scene`` with row ``b`` of each per-run parameter."""
    m = scene.model
    effects = list(scene.effects)
    for key, arr in per.items():
        if key == "gravity":
            g = _rows(key, arr, count, (3,))[b]
            grav = [k for k, e in enumerate(effects) if e.g is not None]
            if grav:
                # The gravity the bodies feel is the sum of the gravity effects: the
                # first carries g, any others none (kept, so the effects keep their order).
                for k in grav:
                    effects[k] = effects[k].with_parameter("g", g if k == grav[0] else 0 * g)
            else:
                effects.append(_core.Effect.gravity(g))
            continue
        head, _, tail = key.rpartition(".")
        if head in bodies and tail in ("mass", "com", "inertia"):
            body = m.body(head)
            mass, com, inertia = body.mass, np.asarray(body.com), np.asarray(body.inertia)
            if tail == "mass":
                mass = float(_rows(key, arr, count, ())[b])
            elif tail == "com":
                com = _rows(key, arr, count, (3,))[b]
            else:
                inertia = _rows(key, arr, count, (3, 3))[b]
            m = m.with_body(head, _core.RigidBody(mass, com=com, inertia=inertia))
        elif head:
            effects = _effect_param(effects, head, tail, arr[b])
        else:
            raise InvalidInputError(
                f"params: expected 'gravity', '<effect>.<parameter>' or '<body>.mass'/"
                f"'.com'/'.inertia', got '{key}'"
            )
    return scene.replace(model=m, effects=effects)


def scenes_from_params(scene: Scene, params: dict[str, Any]) -> list[Scene]:
    """One scene per run, from ``scene`` with the per-run ``params``."""
    model = scene.model
    count = None
    per = {}
    for key, value in params.items():
        arr = float_array(f"params['{key}']", value, "numbers, one value per run")
        if arr.ndim == 0:
            raise InvalidInputError(f"params['{key}']: expected one value per run, got a scalar")
        if count is None:
            count = arr.shape[0]
        elif arr.shape[0] != count:
            raise InvalidInputError(
                f"params['{key}']: expected {count} runs (as the other params), got {arr.shape[0]}"
            )
        per[key] = arr
    check_batch_memory(count or 0, model.nq, model.nv)
    bodies = set(model.body_names)
    out = []
    for b in range(count or 0):
        try:
            out.append(_run_scene(scene, per, count, b, bodies))
        except PointMassDynError as e:
            if str(e).startswith("params:"):  # a key no run can take
                raise
            # Name the run: its row of params is the one at fault.
            raise type(e)(f"params (run {b}): {e}") from None
    return out


def simulate_batch(
    scene: Scene | Sequence[Scene],
    t_span: Sequence[float] | None = None,
    *,
    q0: Any = None,
    v0: Any = None,
    params: dict[str, Any] | None = None,
    t_eval: Any = None,
    rtol: Any = None,
    atol: Any = None,
    events: Sequence[Any] | None = None,
    first_step: float | None = None,
    max_step: float | None = None,
    max_steps: int | None = None,
    energy: bool = False,
    disable: Any = None,
    threads: int | None = None,
    progress: Callable[[int, int], Any] | None = None,
    method: str | None = None,
    dt: float | None = None,
    config: RunConfig | None = None,
    controller: Any = None,
    control_period: float = 0.001,
    control: str = "torque",
    imu: Any = None,
    contact: bool = False,
    noise: Any = None,
    bias: Any = None,
    seed: Any = None,
) -> BatchResult:
    """B simulations of one scene (or of a list of scenes), on ``threads`` threads (default:
    one per core), the GIL released once for the whole batch.

    ``q0`` (B, nq) and ``v0`` (B, nv) give per-run initial states (one row: every run);
    ``params`` per-run parameters (see the module docs; ``"gravity"`` is the total gravity
    the bodies feel, however many gravity effects the scene has); the other arguments are
    :func:`simulate`'s, for every run (events: :class:`StateEvent` only). ``progress(done,
    B)`` is called every 50 ms from the calling thread, which also watches for Ctrl-C (a
    ``KeyboardInterrupt`` stops the batch). Ctrl-C or an exception raised by ``progress``
    stops the batch and propagates with the :class:`BatchResult` so far as its ``.result``:
    finished runs whole, runs under way up to where they stopped (``success=False``,
    ``t_reached``), runs not started with ``status=-1`` and the reason. Each run gives
    exactly what the same
    :func:`simulate` call gives; one failing run (a NaN force, a singularity) is reported in
    its own result while the others finish. ``config``: a :class:`RunConfig`, as
    :func:`simulate`'s.

    ``controller``: a callable ``f(t, q, v, sensors)`` for every run, or a list of one per
    run, sampled every ``control_period`` as in ``simulate(controller=...)`` (``control``,
    ``imu``, ``contact``, ``noise``, ``bias``, ``seed`` as there; ``seed`` may be a list of
    one per run). Each run is then exactly its ``simulate(..., controller=f_b)`` call, bit
    for bit, whatever ``threads``: the runs go on ``threads`` threads (default one: a Python
    controller holds the GIL, so controllers never run at the same time; a thread integrates
    with the GIL released while another's controller runs, which gains only where the
    integration dominates; docs/control.md §3). ``t_eval`` gives the
    batch's ``t``, ``q`` and ``v`` arrays as for other batches. An exception raised by one
    run's controller, or a control refused (wrong length, not finite), ends that run with
    its trajectory so far (``success`` False, the reason and ``t_reached``) and the others
    go on; Ctrl-C stops the batch and propagates with the :class:`BatchResult` so far."""
    if controller is not None:
        scenes = [scene] if isinstance(scene, Scene) else list(scene)
        if params:
            if len(scenes) != 1:
                raise InvalidInputError("params: give one scene with params, or a list of scenes")
            scenes = scenes_from_params(scenes[0], dict(params))
        options = dict(method=method, rtol=rtol, atol=atol, dt=dt, first_step=first_step, max_step=max_step,
                       disable=disable, t_eval=t_eval, events=events or None, max_steps=max_steps,
                       energy=energy or None, config=config, progress=progress)  # fmt: skip
        sensing = dict(control=control, imu=imu, contact=contact, noise=noise, bias=bias, seed=seed)
        results, stopped = controlled_runs(scenes, t_span, controller, control_period, sensing, options,
                                           q0, v0, threads)  # fmt: skip
        batch = batch_of_results(results, t_eval)
        if stopped is not None:
            raise _with_batch(stopped, batch)
        return batch
    scenes = [scene] if isinstance(scene, Scene) else list(scene)
    if not scenes or not all(isinstance(s, Scene) for s in scenes):
        raise InvalidInputError("scene: expected a Scene or a non-empty list of Scenes")
    count = len(scenes)
    for x in (q0, v0):
        try:
            if x is not None and np.ndim(x) == 2:
                count = max(count, int(np.shape(x)[0]))
        except (TypeError, ValueError):  # not an array: the core names the argument
            pass
    model = scenes[0].model
    check_batch_memory(count, model.nq, model.nv, t_eval)
    if params:
        if len(scenes) != 1:
            raise InvalidInputError("params: give one scene with params, or a list of scenes")
        scenes = scenes_from_params(scenes[0], dict(params))
    out, stopped = _core.simulate_batch(
        scenes,
        q0,
        v0,
        t_span,
        rtol,
        atol,
        config=config,
        events=events,
        threads=threads,
        progress=progress,
        **changed_settings(
            t_eval=t_eval,
            first_step=first_step,
            max_step=max_step,
            max_steps=max_steps,
            energy=energy,
            disable=disable,
            method=method,
            dt=dt,
        ),
    )
    if t_eval is None and config is not None:
        t_eval = config.t_eval
    batch = _batch_result(scenes, out, t_eval)
    if stopped is not None:
        raise _with_batch(stopped, batch)
    return batch


def _batch_result(scenes: list[Scene], out: list, t_eval: Any) -> BatchResult:
    """The core's per-run ``RunResult``s as a :class:`BatchResult` (the runs a stopped batch
    cut short name what stopped it in their messages: the bindings put it there; a run that
    could not start is ``RunStatus.NotStarted``)."""
    names = [s.name for s in scenes]
    results = [result_from_run(run, names[0] if len(names) == 1 else names[k])
               for k, run in enumerate(out)]
    return batch_of_results(results, t_eval, stacklevel=4)


def batch_of_results(results: list[SimulationResult], t_eval: Any, stacklevel: int = 3) -> BatchResult:
    """The runs as a :class:`BatchResult`; with ``t_eval``, their states at it stacked."""
    passed = [k for k, r in enumerate(results) if r.singular_passage is not None]
    if passed:
        # One warning for the batch, naming the runs (simulate warns per run).
        warnings.warn(SingularPassageWarning(
            f"{len(passed)} of {len(results)} runs ended a step at a singular position of the "
            f"loops (runs {passed[:10]}{' ...' if len(passed) > 10 else ''}; their "
            "results' singular_passage holds the time): past it the motion may continue on "
            "another branch, chosen by rounding (docs/mechanisms.md §5)"), stacklevel=stacklevel)
    success = np.array([r.success for r in results], dtype=bool)
    t = q = v = None
    if t_eval is not None:
        t = np.asarray(t_eval, dtype=float).reshape(-1)
        nq = max(r.q.shape[1] for r in results)
        nv = max(r.v.shape[1] for r in results)
        q = np.full((len(results), len(t), nq), np.nan)
        v = np.full((len(results), len(t), nv), np.nan)
        for k, r in enumerate(results):
            n = len(r.t)
            if n:
                q[k, :n, : r.q.shape[1]], v[k, :n, : r.v.shape[1]] = r.q, r.v
    return BatchResult(
        results=results,
        t=t,
        q=q,
        v=v,
        success=success,
        status=np.array([r.status for r in results]),
        message=[r.message for r in results],
        t_reached=np.array([r.t_reached for r in results], dtype=float),
        nfev=np.array([r.nfev for r in results], dtype=int),
    )


def _with_batch(error: BaseException, batch: BatchResult) -> BaseException:
    """Attaches the runs a stopped batch computed to the exception that stopped it as
    ``.result``, and says so in the traceback."""
    done = int(np.sum(batch.success))
    note = (
        f"pointmass_dyn: the batch stopped with {done} of {len(batch)} runs complete; every "
        "run's result so far (t_reached per run) is in this exception's .result"
    )
    try:
        error.result = batch
        notes = getattr(error, "__notes__", None)
        if notes is None:
            error.__notes__ = [note]
        else:
            notes.append(note)
    except (AttributeError, TypeError):  # an exception type that takes no attributes
        pass
    return error

