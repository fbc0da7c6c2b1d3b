"""Models in and out (docs/robots.md): importers of MuJoCo and Pinocchio models, the URDF
repair options of ``Model.from_urdf``, the MJCF exporter and the state conversions between
MuJoCo's coordinates and ours.

    model = pmd.from_mujoco(mujoco.MjModel.from_xml_path("arm.xml"))
    q, v = pmd.io.mujoco_state(mj_model, data.qpos, data.qvel)
    xml = pmd.to_mjcf(scene)
    qpos, qvel = pmd.io.to_mujoco_state(scene.model, q, v)
    d.ctrl[:] = pmd.io.mujoco_controls(scene, d.time)   # its actuators' controls at a time
"""

from ._importers import InertiaRepair, from_mujoco, from_pinocchio, mujoco_state, pinocchio_q
from ._mjcf import (
    MUJOCO_INTEGRATORS,
    MujocoLayout,
    from_mujoco_state,
    layout,
    probe_effects,
    to_mjcf,
    to_mujoco_acceleration,
    to_mujoco_state,
)
from ._mjcf_effects import mujoco_controls

__all__ = [
    "MUJOCO_INTEGRATORS",
    "InertiaRepair",
    "MujocoLayout",
    "from_mujoco",
    "from_mujoco_state",
    "from_pinocchio",
    "layout",
    "mujoco_controls",
    "mujoco_state",
    "pinocchio_q",
    "probe_effects",
    "to_mjcf",
    "to_mujoco_acceleration",
    "to_mujoco_state",
]
