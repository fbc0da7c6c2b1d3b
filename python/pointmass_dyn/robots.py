"""The robots of example-robot-data, found and loaded (docs/robots.md §0).

example-robot-data ≥ 6 is installed as URDF and mesh files only (a cmeel wheel: ``import
example_robot_data`` fails), under ``site-packages/cmeel.prefix/share/example-robot-data``.
This module finds that folder through the package metadata and loads a robot by a short name
(``"panda"``) or by its path inside the folder::

    import pointmass_dyn as pmd
    panda = pmd.example_robot("panda")                     # Model.from_urdf of its URDF
    talos = pmd.example_robot("talos", root_joint="free")  # arguments go to from_urdf
    pmd.robots.urdf_path("panda")                          # the file, e.g. for Pinocchio
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ._core import Model
from .errors import InvalidInputError

__all__ = ["NAMES", "directory", "example_robot", "reference_poses", "srdf_path", "urdf_path"]

# Short names of the robots the tests load (tests/test_urdf.py, tests/test_free_flyer.py),
# relative to the robots folder. Any other file there can be named by its relative path.
NAMES = {
    "a1": "a1_description/urdf/a1.urdf",
    "baxter": "baxter_description/urdf/baxter.urdf",
    "double_pendulum": "double_pendulum_description/urdf/double_pendulum.urdf",
    "g1": "g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf",
    "human": "human_description/robots/human.urdf",
    "icub": "icub_description/robots/icub.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "solo12": "solo_description/robots/solo12.urdf",
    "talos": "talos_data/robots/talos_full_v2.urdf",
    "tiago": "tiago_description/robots/tiago.urdf",
    "ur5": "ur_description/urdf/ur5_robot.urdf",
}

_INSTALL = "pip install example-robot-data (or pip install 'pointmass-dyn[test]')"


def directory() -> Path:
    """example-robot-data's ``robots`` folder; ``InvalidInputError`` saying how to install it
    if it is missing."""
    import importlib.metadata

    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        raise InvalidInputError(f"example-robot-data is not installed: {_INSTALL}") from None
    found = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    if not found.is_dir():
        raise InvalidInputError(
            f"example-robot-data {dist.version} is installed but has no robots folder at "
            f"{found}: {_INSTALL}"
        )
    return found


def urdf_path(name: str) -> Path:
    """The URDF of ``name``: a key of ``NAMES`` or a path relative to :func:`directory`
    (``"ur_description/urdf/ur10_robot.urdf"``)."""
    if not isinstance(name, str):
        raise InvalidInputError(f"name: expected a robot name (str), got {type(name).__name__}")
    root = directory()
    path = root / NAMES.get(name, name)
    if not path.is_file() or not path.name.endswith(".urdf"):
        raise InvalidInputError(
            f"name: expected one of {sorted(NAMES)} or the path of a .urdf file under {root}, "
            f"got {name!r}"
        )
    return path


def example_robot(name: str, **kwargs):
    """``Model.from_urdf`` of the robot ``name`` (see :func:`urdf_path`); keyword arguments
    (``root_joint="free"``, ``repair=True``) go to ``from_urdf``."""
    return Model.from_urdf(str(urdf_path(name)), **kwargs)


def srdf_path(name: str) -> Path:
    """The SRDF that example-robot-data ships beside the URDF of ``name`` (its package's
    ``srdf`` folder): the one named like the URDF, else the one whose name is the longest
    prefix of the URDF's (``solo.srdf`` for ``solo12.urdf``), else the folder's only one.
    ``InvalidInputError`` naming what is there when none fits."""
    urdf = urdf_path(name)
    package = directory() / urdf.relative_to(directory()).parts[0]
    found = sorted((package / "srdf").glob("*.srdf"))
    prefixes = [p for p in found if urdf.stem.startswith(p.stem)]
    if prefixes:
        return max(prefixes, key=lambda p: len(p.stem))
    if len(found) == 1:
        return found[0]
    raise InvalidInputError(
        f"name: {name!r} has no SRDF that fits its URDF '{urdf.name}' in {package / 'srdf'} "
        f"(there: {[p.name for p in found] or 'none'})"
    )


def reference_poses(name: str, **kwargs) -> tuple[Any, dict[str, Any]]:
    """The robot ``name`` (:func:`example_robot`, ``kwargs`` to ``from_urdf``) and its SRDF's
    reference poses ``{"standing": q, ...}`` (``Model.reference_poses``)::

        go1, poses = pmd.robots.reference_poses("go1_description/urdf/go1.urdf", root_joint="free")
        scene = pmd.Scene(go1, poses["standing"])
    """
    model = example_robot(name, **kwargs)
    return model, model.reference_poses(str(srdf_path(name)))
