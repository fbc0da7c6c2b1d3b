"""Sweeps: :func:`simulate_batch` split into chunks over a ``dask.distributed`` cluster
(docs/batch.md §2). The same call runs on a laptop (a ``LocalCluster`` of processes made for
the call) and on a multi-node cluster (``scheduler="tcp://host:8786"`` or a ``client``).

Each chunk is one task calling :func:`simulate_batch` on its runs (the scene pickles, the
per-run ``q0``/``v0``/``params`` rows are sliced per chunk), so the result is bit for bit
:func:`simulate_batch` on the whole batch, whatever the cluster. Results are fetched as the
chunks finish, so a worker that dies costs only the chunks it was running: the scheduler
runs them again elsewhere (up to Dask's ``distributed.scheduler.allowed-failures`` worker
deaths per chunk); ``retries`` reruns a chunk whose task raised (a ``MemoryError`` on a busy
node), except for input errors, which are raised at once.

Needs the ``dask`` extra: ``pip install "pointmass-dyn[dask]"``.
"""

from __future__ import annotations

import math
import socket
import uuid
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ._batch import BatchResult, simulate_batch
from ._core import Scene, __version__
from .errors import ClusterError, InvalidInputError

#: Chunks per concurrent task slot when ``chunk_size`` is not given (see :func:`sweep`).
CHUNKS_PER_SLOT = 4


def _distributed():
    try:
        import distributed
    except ImportError as e:
        raise ImportError(
            "pmd.sweep needs Dask's distributed scheduler: pip install "
            "'pointmass-dyn[dask]' (or 'dask[distributed]')"
        ) from e
    return distributed


class _Refused:
    """A chunk's input error, returned rather than raised so that Dask does not retry it."""

    def __init__(self, error: BaseException):
        self.error = error


def _run_chunk(version, scene, t_span, q0, v0, params, t_eval, kwargs):
    """One task: ``simulate_batch`` on one chunk's runs (module level, so that workers find
    it by name)."""
    if version != __version__:
        return _Refused(
            InvalidInputError(
                f"sweep: the worker has pointmass_dyn {__version__}, the client {version}; "
                f"install the same version on every node"
            )
        )
    try:
        return simulate_batch(
            scene, t_span, q0=q0, v0=v0, params=params, t_eval=t_eval, **kwargs
        )
    except InvalidInputError as e:
        return _Refused(e)


def _count(name: str, value: Any, lead_ndim: int) -> int | None:
    """Runs given by a per-run argument (its leading length), None if it is one for all."""
    if value is None:
        return None
    arr = np.asarray(value)
    if arr.ndim < lead_ndim:
        return None
    if arr.shape[0] == 0:
        raise InvalidInputError(f"{name}: expected at least one run, got shape {arr.shape}")
    return arr.shape[0]


def _runs(scene, q0, v0, params) -> tuple[int, dict[str, bool]]:
    """The batch size B and, per argument, whether it has one row per run (to be sliced)."""
    counts = {
        "q0": _count("q0", q0, 2),
        "v0": _count("v0", v0, 2),
        "scenes": None if isinstance(scene, Scene) else len(scene),
    }
    for key, value in (params or {}).items():
        arr = np.asarray(value)
        if arr.ndim == 0:
            raise InvalidInputError(f"params['{key}']: expected one value per run, got a scalar")
        counts[f"params['{key}']"] = _count(f"params['{key}']", arr, 1)
    b = max([n for n in counts.values() if n is not None], default=1)
    for name, n in counts.items():
        if n is not None and n not in (1, b) and not name.startswith("params"):
            raise InvalidInputError(f"{name}: expected 1 or {b} runs (as the other batch "
                                    f"arguments), got {n}")
    ps = [n for name, n in counts.items() if name.startswith("params")]
    if ps and (len(set(ps)) != 1 or ps[0] not in (1, b)):
        raise InvalidInputError(f"params: expected {b} runs in every key, got {ps}")
    return b, {name: n == b and b > 1 for name, n in counts.items()}


def _connect(distributed, scheduler, timeout: float):
    """``Client(scheduler)``, with Dask's own errors as ours: a malformed address (Dask
    raises ValueError, or for an unknown protocol an AssertionError after its timeout) is an
    input error, a scheduler that does not answer within ``timeout`` a :class:`ClusterError`."""
    expected = "an address such as 'tcp://host:8786'"
    if not isinstance(scheduler, str):
        raise InvalidInputError(f"scheduler: expected {expected}, got {scheduler!r}")
    from distributed.comm import parse_address
    from distributed.comm.registry import backends

    protocol = parse_address(scheduler)[0]
    if protocol not in backends:
        raise InvalidInputError(
            f"scheduler: expected {expected} (protocols {', '.join(backends)}), got "
            f"{scheduler!r}"
        )
    try:
        if protocol == "tcp":
            # A plain socket first: a Client whose __init__ fails can deadlock in its own
            # __del__ (seen with distributed 2025 under load), so do not build one for a
            # scheduler that cannot be reached at all.
            from distributed.comm import get_address_host_port

            socket.create_connection(get_address_host_port(scheduler), timeout=timeout).close()
        return distributed.Client(scheduler, timeout=timeout)
    except ValueError as exc:
        raise InvalidInputError(f"scheduler: expected {expected}, got {scheduler!r} ({exc})") from exc
    except Exception as exc:  # Dask's connect timeout is an OSError; its own loop may fail too
        raise ClusterError(
            f"scheduler: no Dask scheduler answered at {scheduler!r} within "
            f"connect_timeout={timeout} s ({type(exc).__name__}: {exc})"
        ) from exc


def _client(client, scheduler, threads_per_task: int, connect_timeout: float):
    """The client to use and what to close afterwards."""
    distributed = _distributed()
    if client is not None:
        if scheduler is not None:
            raise InvalidInputError("sweep: give a client or a scheduler address, not both")
        return client, []
    if scheduler is not None:
        c = _connect(distributed, scheduler, connect_timeout)
        return c, [c]
    from dask.system import CPU_COUNT

    cluster = distributed.LocalCluster(
        n_workers=max(1, CPU_COUNT // threads_per_task),
        threads_per_worker=1,
        processes=True,
        dashboard_address=":0",
    )
    try:
        c = distributed.Client(cluster)
    except BaseException:
        cluster.close()
        raise
    return c, [c, cluster]


def _concat(parts: list[BatchResult]) -> BatchResult:
    return BatchResult(
        results=[r for p in parts for r in p.results],
        t=parts[0].t,
        q=np.concatenate([p.q for p in parts]),
        v=np.concatenate([p.v for p in parts]),
        success=np.concatenate([p.success for p in parts]),
        status=np.concatenate([p.status for p in parts]),
        message=[m for p in parts for m in p.message],
        t_reached=np.concatenate([p.t_reached for p in parts]),
        nfev=np.concatenate([p.nfev for p in parts]),
    )


def sweep(
    scene: Scene | Sequence[Scene],
    t_span: Sequence[float],
    *,
    q0: Any = None,
    v0: Any = None,
    params: dict[str, Any] | None = None,
    t_eval: Any = None,
    chunk_size: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    connect_timeout: float = 10.0,
    retries: int = 2,
    threads_per_task: int = 1,
    progress: Callable[[int, int], Any] | None = None,
    **simulate_kwargs: Any,
) -> BatchResult:
    """:func:`simulate_batch` on a ``dask.distributed`` cluster: the B runs in chunks of
    ``chunk_size``, one task per chunk, gathered in order into the :class:`BatchResult` that
    ``simulate_batch`` gives on the whole batch (bit for bit).

    The cluster: ``client`` (a ``distributed.Client``, left open), else ``Client(scheduler)``
    for a scheduler address (closed afterwards; one that does not answer within
    ``connect_timeout`` seconds is a :class:`~pointmass_dyn.errors.ClusterError`), else a new ``LocalCluster`` of one process
    per ``threads_per_task`` cores (closed afterwards). Each task runs ``simulate_batch`` with
    ``threads=threads_per_task``: give workers that many cores per thread.

    ``q0``, ``v0``, ``params``, ``t_eval`` (required, so that the runs stack) and the other
    keywords (``rtol``, ``atol``, ``events``, ``max_step``, ...) are ``simulate_batch``'s.
    ``chunk_size`` defaults to ``ceil(B / (4 * slots))``, ``slots`` the cluster's worker
    threads: four chunks per slot balance runs of unequal cost and keep the work lost with a
    worker small, while a chunk of even 100 short runs costs far more than a task's few
    milliseconds of overhead. ``retries``: reruns of a chunk whose task raised (other than an
    input error); a chunk lost with its worker is rerun by the scheduler in any case.
    ``progress(done, B)`` is called in this process as chunks arrive."""
    if t_eval is None:
        raise InvalidInputError("sweep: t_eval is required (the chunks' runs are stacked)")
    for key in ("threads", "progress"):
        if key in simulate_kwargs:
            raise InvalidInputError(f"sweep: '{key}' is not a simulate_batch argument here "
                                    f"(use threads_per_task)")
    if isinstance(scene, Scene):
        scenes = scene
    else:
        scenes = list(scene)
        if not scenes or not all(isinstance(s, Scene) for s in scenes):
            raise InvalidInputError("scene: expected a Scene or a non-empty list of Scenes")
        if params:
            raise InvalidInputError("params: give one scene with params, or a list of scenes")
    if int(threads_per_task) < 1:
        raise InvalidInputError(f"threads_per_task: expected >= 1, got {threads_per_task}")
    threads_per_task = int(threads_per_task)
    if chunk_size is not None and int(chunk_size) < 1:
        raise InvalidInputError(f"chunk_size: expected >= 1, got {chunk_size}")
    b, sliced = _runs(scenes, q0, v0, params)
    q0 = None if q0 is None else np.asarray(q0)
    v0 = None if v0 is None else np.asarray(v0)
    params = None if not params else {k: np.asarray(v) for k, v in params.items()}
    kwargs = dict(simulate_kwargs, threads=threads_per_task)

    distributed = _distributed()
    if isinstance(connect_timeout, bool) or not (
        isinstance(connect_timeout, (int, float)) and 0 < connect_timeout < math.inf
    ):
        raise InvalidInputError(
            f"connect_timeout: expected a positive number of seconds, got {connect_timeout!r}"
        )
    client, close = _client(client, scheduler, threads_per_task, float(connect_timeout))
    futures: dict[Any, int] = {}
    try:
        if chunk_size is None:
            slots = sum(client.nthreads().values()) or 1
            chunk_size = math.ceil(b / (CHUNKS_PER_SLOT * slots))
        chunk_size = int(chunk_size)
        bounds = [(a, min(a + chunk_size, b)) for a in range(0, b, chunk_size)]
        tag = uuid.uuid4().hex[:12]

        def rows(name, x, lo, hi):
            return x[lo:hi] if sliced.get(name) else x

        for k, (lo, hi) in enumerate(bounds):
            part = params and {
                key: rows(f"params['{key}']", value, lo, hi) for key, value in params.items()
            }
            fut = client.submit(
                _run_chunk,
                __version__,
                scenes[lo:hi] if sliced["scenes"] else scenes,
                t_span,
                rows("q0", q0, lo, hi),
                rows("v0", v0, lo, hi),
                part,
                t_eval,
                kwargs,
                key=f"pmd-sweep-{tag}-{k}",
                retries=retries,
                pure=False,
            )
            futures[fut] = k
        parts: list[BatchResult | None] = [None] * len(bounds)
        done = 0
        for fut, part in distributed.as_completed(list(futures), with_results=True):
            if isinstance(part, _Refused):
                raise part.error
            k = futures.pop(fut)
            parts[k] = part
            fut.release()
            done += bounds[k][1] - bounds[k][0]
            if progress is not None:
                progress(done, b)
        return _concat(parts)  # type: ignore[arg-type]
    finally:
        if futures:
            client.cancel(list(futures))
        for c in close:
            c.close()
