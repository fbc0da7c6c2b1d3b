"""``simulate`` (a whole scene in Rust, GIL released) and ``rk45`` (our Dormand–Prince on
any Python right-hand side, SciPy-like)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Optional, Sequence

import numpy as np

from . import _core
from ._core import Effect, Scene, StateEvent
from .errors import SimulationError


def Gravity(g: Sequence[float] = (0.0, 0.0, -9.81)) -> Effect:  # noqa: N802
    """Uniform gravity ``g`` (m/s², world frame), declared per scene."""
    return Effect.gravity(g)


@dataclass
class SimulationResult:
    """Trajectory of a scene. ``q`` is (N, nq), ``v`` (N, nv); ``energy`` (N,) when asked."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    energy: Optional[np.ndarray]
    t_events: list
    q_events: list
    v_events: list
    nfev: int
    n_accepted: int
    n_rejected: int
    status: int
    message: str
    success: bool
    t_reached: float
    scene: str = ""
    extras: dict = field(default_factory=dict)

    @property
    def nsteps(self) -> int:
        return self.n_accepted

    def raise_for_status(self) -> "SimulationResult":
        """Raises :class:`SimulationError` (with ``.t``) if the run failed; returns self."""
        if not self.success:
            raise SimulationError(self.message, self.t_reached)
        return self


def simulate(
    scene: Scene,
    t_span: Optional[Sequence[float]] = None,
    *,
    rtol: Any = None,
    atol: Any = None,
    t_eval: Any = None,
    events: Optional[Sequence[Any]] = None,
    first_step: Optional[float] = None,
    max_step: Optional[float] = None,
    max_steps: Optional[int] = None,
    energy: bool = False,
    controller: str = "standard",
    progress: Optional[Callable[[float], Any]] = None,
) -> SimulationResult:
    """Integrates a scene with our adaptive RK45, entirely in Rust with the GIL released.

    Settings not given here come from the scene (its ``[simulate]`` table), then SciPy's
    defaults (rtol 1e-3, atol 1e-6). ``events`` holds :class:`StateEvent` objects (a joint
    coordinate or speed crossing a value, evaluated in Rust) or callables
    ``f(t, q, v) -> float`` with optional ``terminal``/``direction`` attributes as in SciPy
    (these re-enter Python at every evaluation and cost accordingly). ``energy=True`` records
    kinetic plus gravitational potential energy at every output time. ``progress(t)`` is
    called every few hundred right-hand-side evaluations (an exception it raises stops the
    run and is re-raised, as is Ctrl-C).

    A run that cannot finish returns ``success=False`` with a message giving the reason and
    the time reached; call ``.raise_for_status()`` to turn that into a
    :class:`SimulationError`. Invalid arguments raise :class:`InvalidInputError`.
    """
    out = _core.simulate_scene(
        scene,
        t_span,
        rtol,
        atol,
        t_eval,
        events,
        first_step,
        max_step,
        max_steps,
        energy,
        controller,
        progress,
    )
    return SimulationResult(scene=scene.name, **out)


class OdeResult(dict):
    """SciPy's ``OdeResult``: a dict with attribute access."""

    def __getattr__(self, name: str) -> Any:
        try:
            return self[name]
        except KeyError as exc:
            raise AttributeError(name) from exc

    def __repr__(self) -> str:
        keys = ", ".join(sorted(self))
        return f"OdeResult({keys})"


def rk45(
    fun: Callable[[float, np.ndarray], Any],
    t_span: Sequence[float],
    y0: Any,
    *,
    rtol: Any = 1e-3,
    atol: Any = 1e-6,
    t_eval: Any = None,
    events: Any = None,
    first_step: Optional[float] = None,
    max_step: float = np.inf,
    max_steps: Optional[int] = None,
    dense_output: bool = False,
    controller: str = "standard",
) -> OdeResult:
    """Our Dormand–Prince 5(4) on ``fun(t, y)``, step for step SciPy's
    ``solve_ivp(fun, t_span, y0, method="RK45")`` with the same options.

    Returns a SciPy-like result: ``t``, ``y`` (n, N), ``sol`` (when ``dense_output``),
    ``t_events``, ``y_events``, ``nfev``, ``njev``, ``nlu``, ``status`` (0 end reached,
    1 terminal event, -1 failure), ``message``, ``success``; plus ``n_accepted``,
    ``n_rejected`` and ``t_reached``.
    """
    out = _core.rk45(
        fun,
        t_span,
        y0,
        rtol,
        atol,
        t_eval,
        events,
        first_step,
        None if max_step is None or np.isinf(max_step) else float(max_step),
        max_steps,
        dense_output,
        controller,
    )
    return OdeResult(out)


__all__ = ["Gravity", "SimulationResult", "simulate", "OdeResult", "rk45", "StateEvent"]
