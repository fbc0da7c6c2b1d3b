"""Inverse kinematics and paths of frames and points along trajectories (docs/kinematics.md).

The frame algorithms themselves are ``Model`` methods (``frame_placement``,
``frame_jacobian``, ``frame_jacobian_dot``, ``frame_motion``, ``center_of_mass``,
``centroidal``, ``independent_map``, ``point_path``), all in Rust; this module normalises
the targets of :func:`inverse_kinematics` and gives a trajectory's paths.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _core
from .errors import InvalidInputError, NumericalError


@dataclass
class IKResult:
    """What :func:`inverse_kinematics` found. ``residual`` is the largest error (m, rad) of
    any target row or loop/coupling constraint at ``q``; ``errors`` per target its error rows
    (angular then linear for a pose; target minus reached, world axes)."""

    q: np.ndarray
    residual: float
    converged: bool
    iterations: int
    restarts: int
    message: str
    errors: dict = field(default_factory=dict)

    def raise_for_status(self) -> IKResult:
        """Raises :class:`pointmass_dyn.errors.NumericalError` (with the message) if the
        targets were not reached; returns self."""
        if not self.converged:
            raise NumericalError(self.message)
        return self


def _target(frame: Any, value: Any) -> tuple[Any, Any]:
    """(rotation or None, position) of one target: a position (3,), a pose as a (rotation
    (3, 3), position (3,)) pair or a 4 × 4 homogeneous matrix."""
    if isinstance(value, tuple) and len(value) == 2:
        return np.asarray(value[0], dtype=float), np.asarray(value[1], dtype=float)
    arr = np.asarray(value, dtype=float) if not isinstance(value, (str, bytes)) else None
    if arr is not None and arr.shape == (3,):
        return None, arr
    if arr is not None and arr.shape == (4, 4):
        return arr[:3, :3], arr[:3, 3]
    raise InvalidInputError(
        f"targets: expected, for frame {frame!r}, a position (3,), a (rotation (3, 3), "
        f"position (3,)) pair or a 4x4 homogeneous matrix, got {value!r}"
    )


def _weights(frame: Any, rows: int, weights: Any) -> list[float]:
    w = weights.get(frame, 1.0) if isinstance(weights, Mapping) else weights
    w = 1.0 if w is None else w
    arr = np.broadcast_to(np.asarray(w, dtype=float), (rows,)) if np.ndim(w) == 0 else np.asarray(w, dtype=float)
    if arr.shape != (rows,):
        raise InvalidInputError(
            f"weights: expected, for frame {frame!r}, a number or {rows} numbers "
            f"({'angular then linear' if rows == 6 else 'x, y, z'}), got shape {arr.shape}"
        )
    return [float(x) for x in arr]


def inverse_kinematics(
    model: _core.Model,
    targets: Mapping[Any, Any],
    q0: Any = None,
    *,
    weights: Any = None,
    limits: bool = True,
    tol: float = 1e-10,
    max_iterations: int = 100,
    restarts: int = 20,
    seed: int = 0,
) -> IKResult:
    """Joint coordinates that bring each frame of ``targets`` to its target.

    ``targets``: ``{frame: target}``, a frame a name of ``model.frame_names`` (or a body
    index), a target a world position (3,), a ``(rotation, position)`` pair or a 4 × 4
    matrix. ``q0``: the start (default: the neutral configuration). ``weights``: one number,
    or per frame (a dict) a number or one per row (3 for a position, 6 for a pose: angular
    then linear). ``limits``: keep the joints within the model's position limits (URDF
    ``<limit>``). Loops and couplings stay closed.

    Damped least squares (Levenberg–Marquardt); where a step would leave the limits it is a
    quadratic program (Clarabel). A run that does not reach ``tol`` restarts from up to
    ``restarts`` pseudo-random configurations (``seed``); the result is the best found,
    with ``converged=False`` and a message when even that misses ``tol``: an unreachable
    target gives the closest configuration found, never an endless search.
    """
    if not isinstance(targets, Mapping) or not targets:
        raise InvalidInputError(
            f"targets: expected a non-empty dict {{frame: position or pose}}, got {targets!r}"
        )
    tasks = []
    for frame, value in targets.items():
        rot, pos = _target(frame, value)
        rows = 3 if rot is None else 6
        tasks.append((frame, rot, pos, _weights(frame, rows, weights)))
    q0 = model.neutral() if q0 is None else q0
    for name, x in (("max_iterations", max_iterations), ("restarts", restarts), ("seed", seed)):
        if isinstance(x, bool) or not isinstance(x, (int, np.integer)) or x < 0:
            raise InvalidInputError(f"{name}: expected an integer >= 0, got {x!r}")
    out = model._inverse_kinematics(
        tasks, q0, bool(limits), float(tol), int(max_iterations), int(restarts), int(seed)
    )
    errors = {frame: e for (frame, *_), e in zip(tasks, out.errors)}
    return IKResult(
        q=out.q,
        residual=out.residual,
        converged=out.converged,
        iterations=out.iterations,
        restarts=out.restarts,
        message=out.message,
        errors=errors,
    )


def frame_path(model: _core.Model, q: Any, frame: Any) -> tuple[np.ndarray, np.ndarray]:
    """(rotations (N, 3, 3), positions (N, 3)) of ``frame`` at the configurations ``q``."""
    return model.frame_placement(frame, np.atleast_2d(q))


def point_path(
    model: _core.Model, q: Any, body: Any, point: Any, v: Any = None
) -> tuple[np.ndarray, np.ndarray | None]:
    """World positions (N, 3) of ``point`` (in the frame or body ``body``) at the
    configurations ``q``, and with ``v`` their velocities (N, 3) (else None)."""
    q = np.atleast_2d(q)
    return model.point_path(body, point, q, None if v is None else np.atleast_2d(v))
