"""Validation by simulation: the identified model driven by the measured joint forces, its
motion beside the measured one (docs/identification.md §6)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._core import Scene
from .._helpers import pyplot
from .._simulation import Damper, Gravity, JointFriction, TabulatedTorque, simulate
from ..errors import InvalidInputError
from ._filter import savgol
from ._identify import Identification


@dataclass(frozen=True)
class Replay:
    """``t`` (N,), the measured ``q_measured`` and the simulated ``q_simulated`` (N, nq) and
    ``v_simulated``; ``error`` = simulated − measured and its ``rms`` per coordinate;
    ``success``/``message`` of the run (a run that stopped early has its samples so far: the
    simulated arrays are then shorter than ``t``)."""

    t: np.ndarray
    q_measured: np.ndarray
    q_simulated: np.ndarray
    v_simulated: np.ndarray
    success: bool
    message: str

    @property
    def error(self) -> np.ndarray:
        return self.q_simulated - self.q_measured[: len(self.q_simulated)]

    @property
    def rms(self) -> np.ndarray:
        return np.sqrt(np.mean(self.error**2, axis=0))

    def plot(self, path=None, labels=None, title: str = "identified model under the measured torques"):
        """Measured (solid) and simulated (dashed) coordinates against time, one panel per
        coordinate (matplotlib). Saves to ``path`` if given; returns the figure."""
        return plot_replay(self, path, labels, title)


def _driven(model, result: Identification):
    """Link names of the driven joints and the v indices their torque columns are."""
    links = list(model.link_names)
    slices = model.joint_slices()
    cols = list(result.actuated) if result.actuated else [vi for (_, vi, _, nv) in slices if nv == 1]
    if not result.actuated and any(nv != 1 for (_, _, _, nv) in slices):
        raise InvalidInputError("result: replay drives 1-dof joints only; this model has multi-dof joints")
    by_v = {vi: links[k] for k, (_, vi, _, _) in enumerate(slices)}
    return [by_v[c] for c in cols], cols


def replay(
    result: Identification,
    t,
    q,
    tau,
    v0=None,
    gravity=None,
    window: int | None = None,
    rtol: float = 1e-9,
    atol: float = 1e-11,
    method: str = "DOP853",
) -> Replay:
    """Simulates ``result.model`` (the identified inertias and armature) from the measured
    first state under the measured joint forces ``tau`` (N, nv, or N, na for an
    identification from actuated forces; tabulated in ``t``, linear between samples), minus
    the identified offsets, with the identified friction as effects (viscous: a damper;
    Coulomb: a regularised friction) and ``gravity``; returns it beside the measured ``q``.
    ``v0``: the first speeds (default: a Savitzky–Golay derivative of ``q``). With loops the
    first state is closed onto them (assembled) before the run. Open-loop: an unstable or
    chaotic motion drifts away from the measurement however good the model, so compare over a
    horizon the motion can be predicted on."""
    model = result.model
    if model is None:
        raise InvalidInputError(f"result: an identification with a model to simulate, got none ({result.model_error})")
    t = np.asarray(t, float)
    width = len(result.actuated) or model.nv
    q, tau = _given(model, t, q, tau, width)
    joints, cols = _driven(model, result)
    tau = tau - np.array([result.offsets.get(j, 0.0) for j in joints]) if result.offsets else tau
    q0 = np.asarray(q[0], float)
    v0 = savgol(t, q, window)[1][0] if v0 is None else np.asarray(v0, float)
    if model.nconstraints:
        q0 = model.assemble(q0, fixed=joints)
        v0 = model.assemble_velocity(q0, v0, fixed=joints)
    effects = [TabulatedTorque(joints, t, tau)]
    if gravity is not None:
        effects.append(Gravity(gravity))
    fv = {j: f["viscous"] for j, f in result.friction.items() if f["viscous"] > 0}
    fc = {j: f["coulomb"] for j, f in result.friction.items() if f["coulomb"] > 0}
    if fv:
        effects.append(Damper(list(fv), list(fv.values())))
    if fc:
        effects.append(JointFriction(list(fc), list(fc.values())))
    scene = Scene(model, q0=q0, v0=v0, effects=effects)
    res = simulate(scene, (float(t[0]), float(t[-1])), t_eval=t, rtol=rtol, atol=atol, method=method)
    return Replay(t, np.asarray(q, float), np.asarray(res.q), np.asarray(res.v), bool(res.success), str(res.message))


def _given(model, t, q, tau, width):
    """``q`` and ``tau`` as measured (N, nq) and (N, width): the raw samples (the torque
    table is the measurement itself, not a smoothed one)."""
    q = np.asarray(q, float)
    tau = np.asarray(tau, float)
    if q.shape != (len(t), model.nq) or tau.shape != (len(t), width):
        raise InvalidInputError(f"q, tau: expected ({len(t)}, {model.nq}) and ({len(t)}, {width}), got {q.shape} and {tau.shape}")
    bad = ~(np.isfinite(q).all() and np.isfinite(tau).all())
    if bad:
        raise InvalidInputError("q, tau: expected finite numbers, got NaN or infinity")
    return q, tau


def plot_replay(rep: Replay, path=None, labels=None, title: str = ""):
    """Measured against simulated coordinates (see :meth:`Replay.plot`)."""
    plt = pyplot()
    n = rep.q_measured.shape[1]
    labels = labels or [f"q{k}" for k in range(n)]
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.8 * n + 0.8), sharex=True, squeeze=False)
    m = len(rep.q_simulated)
    for k, ax in enumerate(axes[:, 0]):
        ax.plot(rep.t, rep.q_measured[:, k], color="k", lw=1.2, label="measured")
        ax.plot(rep.t[:m], rep.q_simulated[:, k], color="#d1495b", lw=1.2, ls="--", label="identified model")
        ax.set_ylabel(labels[k], fontsize=8)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    axes[-1, 0].set_xlabel("time t (s)")
    fig.suptitle(title + ("" if rep.success else f"\nstopped: {rep.message}"), fontsize=10)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig
