"""Excitation trajectories: per joint a finite Fourier series (Swevers et al. 1997)
``q_j(t) = q_j0 + Σ_l a_jl/(l ω) sin(l ω t) − b_jl/(l ω) cos(l ω t)``, periodic over
``duration`` (so a robot can repeat it and the repeats can be averaged), kept inside each
joint's position, velocity and acceleration limits by scaling, and chosen by a random
search (NumPy only) for the smallest condition number of the base regressor along it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _core
from ..errors import InvalidInputError
from ._regressor import friction_flags


@dataclass
class Excitation:
    """``t`` (N,), ``q`` (N, nq), ``v``, ``a`` (N, nv); ``coefficients`` (nv, 2, harmonics)
    (the ``a`` and ``b`` of each joint), ``offsets`` (nv,), ``condition`` of the base
    regressor along it (unit-norm columns), ``joints`` (names)."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    coefficients: np.ndarray
    offsets: np.ndarray
    condition: float
    joints: list[str]

    def to_csv(self, path) -> None:
        """Writes ``t, q_<joint>…, v_<joint>…, a_<joint>…`` (one row per sample, a header
        line) for a controller to play back."""
        header = ["t"] + [f"{k}_{j}" for k in ("q", "v", "a") for j in self.joints]
        table = np.column_stack([self.t, self.q, self.v, self.a])
        np.savetxt(path, table, delimiter=",", header=",".join(header), comments="", fmt="%.10g")


def fourier(coef: np.ndarray, offsets: np.ndarray, t: np.ndarray, omega: float):
    """``(q, v, a)`` (N, nv) of the series at times ``t``."""
    h = coef.shape[2]
    ls = np.arange(1, h + 1) * omega  # (h,)
    s, c = np.sin(np.outer(t, ls)), np.cos(np.outer(t, ls))  # (N, h)
    a_, b_ = coef[:, 0, :], coef[:, 1, :]  # (nv, h)
    q = offsets + s @ (a_ / ls).T - c @ (b_ / ls).T
    v = c @ a_.T + s @ b_.T
    acc = -s @ (a_ * ls).T + c @ (b_ * ls).T
    return q, v, acc


def _limits(model, position, velocity, acceleration):
    joints = [model.link_names[k] for k in range(model.nlinks)]
    lim = list(model.joint_limits().values()) if hasattr(model, "joint_limits") else []
    lo, hi, vmax = np.full(model.nv, -np.pi), np.full(model.nv, np.pi), np.full(model.nv, 2.0)
    for k, item in enumerate(lim[: model.nv]):
        lower, upper, _, vel = item
        if np.isfinite(lower) and np.isfinite(upper) and upper > lower:
            lo[k], hi[k] = lower, upper
        if np.isfinite(vel) and vel > 0:
            vmax[k] = vel
    if position is not None:
        p = np.asarray(position, float)
        if p.shape != (model.nv, 2):
            raise InvalidInputError(f"position: expected (nv, 2) = ({model.nv}, 2) bounds, got shape {p.shape}")
        lo, hi = p[:, 0], p[:, 1]
    if velocity is not None:
        vmax = np.broadcast_to(np.asarray(velocity, float), (model.nv,)).copy()
    amax = np.broadcast_to(np.asarray(acceleration, float), (model.nv,)).copy()
    if not (np.all(hi > lo) and np.all(vmax > 0) and np.all(amax > 0)):
        raise InvalidInputError("limits: expected lower < upper and positive velocity and acceleration limits")
    return joints, lo, hi, vmax, amax


def _fit_into(coef, lo, hi, vmax, amax, t, omega, margin):
    """Scales each joint's coefficients (and centres it) so that it stays within limits."""
    centre = 0.5 * (lo + hi)
    q, v, a = fourier(coef, np.zeros(len(lo)), t, omega)
    q = q - 0.5 * (q.max(0) + q.min(0))
    ratio = np.max(
        [np.ptp(q, 0) / (hi - lo), np.abs(v).max(0) / vmax, np.abs(a).max(0) / amax], axis=0
    ) / margin
    scale = 1.0 / np.maximum(ratio, 1e-300)
    coef = coef * scale[:, None, None]
    q, _, _ = fourier(coef, np.zeros(len(lo)), t, omega)
    offsets = centre - 0.5 * (q.max(0) + q.min(0))
    return coef, offsets


def excitation_trajectory(
    model,
    duration: float,
    harmonics: int = 5,
    rate: float = 100.0,
    position=None,
    velocity=None,
    acceleration: float = 5.0,
    margin: float = 0.9,
    iterations: int = 200,
    seed: int = 0,
    gravity=None,
    friction=None,
    csv=None,
    samples: int = 200,
) -> Excitation:
    """A periodic Fourier-series motion of ``duration`` seconds (``harmonics`` per joint,
    base frequency 1/duration) sampled at ``rate`` Hz, within ``margin`` of the position
    (the model's joint limits, else ±π, or ``position`` (nv, 2)), velocity (the URDF's, else
    2, or ``velocity``) and ``acceleration`` limits, optimised for the condition number of
    the base regressor over ``samples`` evenly spread instants by a random search of
    ``iterations`` steps. Models with ``nq == nv`` only. ``csv``: a path to write it to."""
    if model.nq != model.nv:
        raise InvalidInputError("model: expected nq == nv (no quaternion joints) for a Fourier excitation")
    if not (np.isfinite(duration) and duration > 0):
        raise InvalidInputError(f"duration: expected a positive number of seconds, got {duration}")
    if int(harmonics) < 1:
        raise InvalidInputError(f"harmonics: expected at least 1, got {harmonics}")
    joints, lo, hi, vmax, amax = _limits(model, position, velocity, acceleration)
    omega = 2 * np.pi / duration
    tc = np.linspace(0, duration, samples, endpoint=False)
    viscous, coulomb = friction_flags(friction)
    rng = np.random.default_rng(seed)
    shape = (model.nv, 2, int(harmonics))

    def condition(coef):
        coef, off = _fit_into(coef, lo, hi, vmax, amax, tc, omega, margin)
        q, v, a = fourier(coef, off, tc, omega)
        y = _core.identification_regressor(model, q, v, a, gravity, (bool(viscous), bool(coulomb), False, False))
        if cols is not None:
            y = y[:, cols]
        norms = np.linalg.norm(y, axis=0)
        y = y[:, norms > 0] / norms[norms > 0]
        # The Gram matrix's eigenvalues (small and symmetric: much cheaper than an SVD of
        # the tall regressor), squares of the singular values.
        ev = np.linalg.eigvalsh(y.T @ y)
        return float(np.sqrt(ev[-1] / ev[0])) if ev[0] > 0 else np.inf

    # The identifiable columns of a rich motion, once; the search then conditions those.
    cols = None
    best = rng.normal(size=shape)
    q, v, a = fourier(*_fit_into(best, lo, hi, vmax, amax, tc, omega, margin), tc, omega)
    y = _core.identification_regressor(model, q, v, a, gravity, (bool(viscous), bool(coulomb), False, False))
    cols = _core.identification_base(y, 1e-8).independent
    best_c = condition(best)
    step = 0.5
    for _ in range(int(iterations)):
        trial = best + step * rng.normal(size=shape)
        c = condition(trial)
        if c < best_c:
            best, best_c = trial, c
        else:
            step = max(0.02, step * 0.97)
    coef, off = _fit_into(best, lo, hi, vmax, amax, tc, omega, margin)
    t = np.arange(0.0, duration, 1.0 / rate)
    q, v, a = fourier(coef, off, t, omega)
    out = Excitation(t, q, v, a, coef, off, float(best_c), joints)
    if csv is not None:
        out.to_csv(csv)
    return out


__all__ = ["Excitation", "excitation_trajectory", "fourier"]
