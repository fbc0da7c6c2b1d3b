"""Former module path (the flat layout before the subpackages) of the MJCF exporter and the MuJoCo
state conversions, kept so that code importing it keeps working; the names live in
:mod:`pointmass_dyn.io`."""

from .io import (
    MUJOCO_INTEGRATORS,
    MujocoLayout,
    from_mujoco_state,
    layout,
    to_mjcf,
    to_mujoco_acceleration,
    to_mujoco_state,
)

__all__ = [
    "MUJOCO_INTEGRATORS",
    "MujocoLayout",
    "from_mujoco_state",
    "layout",
    "to_mjcf",
    "to_mujoco_acceleration",
    "to_mujoco_state",
]
