"""Validation on held-out data: predicted against measured joint forces."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._identify import Identification, measured_states
from ._regressor import torque_regressor


@dataclass(frozen=True)
class Validation:
    """``predicted`` and ``measured`` (N, nv), ``rms`` of their difference per joint and
    ``rms_measured`` (the measured forces' own RMS, for scale)."""

    predicted: np.ndarray
    measured: np.ndarray
    rms: np.ndarray
    rms_measured: np.ndarray


def predict_torques(result: Identification, model, q, v, a, gravity=None) -> np.ndarray:
    """Joint forces (N, nv) the identification predicts at the states: ``Y π`` with every
    column it identified (friction, armature, offsets included); (N, na), the actuated
    joints' forces, for an identification from actuated forces."""
    flags = {n.rpartition(".")[2] for n in result.names}
    friction = [k for k, f in (("viscous", "fv"), ("coulomb", "fc")) if f in flags]
    act = list(result.actuated) or None
    reg = torque_regressor(model, q, v, a, gravity, friction or None, "armature" in flags, "offset" in flags, act)
    return reg.torques(result.parameters)


def validate(result: Identification, model, data, gravity=None, window=None) -> Validation:
    """Predicted against measured torques on ``data`` (as :func:`identify` takes it)."""
    width = len(result.actuated) or None
    q, v, a, tau = measured_states(model, data, window, width=width)
    pred = predict_torques(result, model, q, v, a, gravity)
    return Validation(pred, tau, np.sqrt(np.mean((pred - tau) ** 2, 0)), np.sqrt(np.mean(tau**2, 0)))
