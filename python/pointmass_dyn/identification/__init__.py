"""Inertial parameter identification (docs/identification.md): the joint torque regressor in
Pinocchio's ten-parameter form, base parameters, :func:`identify` (physically consistent
cells, or least squares), excitation trajectories and validation on held-out data."""

from ._excitation import Excitation, excitation_trajectory, fourier
from ._filter import savgol
from ._identify import (
    Identification,
    IdentifiedBody,
    body_of,
    identify,
    measured_states,
    pseudo_inertia,
)
from ._regressor import BaseParameters, Regressor, base_parameters, one_dof_joints, torque_regressor
from ._replay import Replay, plot_replay, replay
from ._validate import Validation, predict_torques, validate

__all__ = [
    "BaseParameters",
    "Excitation",
    "Identification",
    "IdentifiedBody",
    "Regressor",
    "Replay",
    "Validation",
    "base_parameters",
    "body_of",
    "excitation_trajectory",
    "fourier",
    "identify",
    "measured_states",
    "one_dof_joints",
    "plot_replay",
    "predict_torques",
    "pseudo_inertia",
    "replay",
    "savgol",
    "torque_regressor",
    "validate",
]
