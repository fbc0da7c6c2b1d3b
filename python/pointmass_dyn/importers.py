"""Former module path (the flat layout before the subpackages) of the MuJoCo and Pinocchio
importers, kept so that code importing it keeps working; the names live in
:mod:`pointmass_dyn.io`."""

from .io import (
    InertiaRepair,
    from_mujoco,
    from_pinocchio,
    mujoco_state,
    pinocchio_q,
)

__all__ = [
    "InertiaRepair",
    "from_mujoco",
    "from_pinocchio",
    "mujoco_state",
    "pinocchio_q",
]
