"""pmd.robots / pmd.example_robot (docs/robots.md §0): example-robot-data's URDFs found
through the package metadata, against the files themselves and Pinocchio's parser."""

from __future__ import annotations

import importlib.metadata
import warnings

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn.errors import InvalidInputError

try:
    ROOT = pmd.robots.directory()
except InvalidInputError:
    ROOT = None
needs_robots = pytest.mark.skipif(ROOT is None, reason="example-robot-data not installed")


@needs_robots
def test_every_short_name_is_a_urdf_in_the_folder():
    assert ROOT.name == "robots" and (ROOT / "panda_description").is_dir()
    for name, rel in pmd.robots.NAMES.items():
        path = pmd.robots.urdf_path(name)
        assert path == ROOT / rel and path.is_file(), name
        assert "<robot" in path.read_text(errors="replace")[:5000], name
    # Any file of the folder by its relative path.
    rel = "ur_description/urdf/ur10_robot.urdf"
    assert pmd.robots.urdf_path(rel) == ROOT / rel


@needs_robots
def test_example_robot_is_from_urdf_of_its_file():
    pin = pytest.importorskip("pinocchio")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pmd.errors.UrdfWarning)
        panda = pmd.example_robot("panda")
        direct = pmd.Model.from_urdf(str(ROOT / "panda_description/urdf/panda.urdf"))
        solo = pmd.example_robot("solo12", root_joint="free")  # keywords reach from_urdf
    pm = pin.buildModelFromUrdf(str(pmd.robots.urdf_path("panda")))
    assert panda.joint_names == list(pm.names)[1:]
    q = np.random.default_rng(1).uniform(-1, 1, panda.nq)
    np.testing.assert_array_equal(panda.mass_matrix(q), direct.mass_matrix(q))
    data = pm.createData()
    ref = pin.crba(pm, data, q)
    ref = np.triu(ref) + np.triu(ref, 1).T
    np.testing.assert_allclose(panda.mass_matrix(q), ref, rtol=1e-10, atol=1e-12)
    assert solo.joint_names[0] == "root_joint" and solo.nq == solo.nv + 1 == 19


@needs_robots
def test_unknown_names_are_our_error_listing_the_names():
    with pytest.raises(InvalidInputError, match=r"name: expected one of \[.*'panda'.*got 'pnada'"):
        pmd.robots.urdf_path("pnada")
    with pytest.raises(InvalidInputError, match="name: expected one of"):
        pmd.robots.urdf_path("panda_description")  # a folder, not a .urdf file
    with pytest.raises(InvalidInputError, match=r"name: expected a robot name \(str\), got int"):
        pmd.example_robot(3)


def test_missing_package_says_how_to_install_it(monkeypatch):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(importlib.metadata, "distribution", missing)
    with pytest.raises(InvalidInputError, match="not installed: pip install example-robot-data"):
        pmd.robots.directory()
    with pytest.raises(InvalidInputError, match="not installed"):
        pmd.example_robot("panda")


@pytest.mark.parametrize("name, free", [("go1_description/urdf/go1.urdf", True),
                                        ("solo12", True), ("panda", False), ("talos", True)])
def test_reference_poses_of_the_shipped_srdf_equal_pinocchios(name, free):
    """`pmd.robots.reference_poses` reads the SRDF's group states ("standing",
    "half_sitting", …) as Pinocchio's `loadReferenceConfigurations` does, to the bit."""
    import warnings

    pin = pytest.importorskip("pinocchio")
    from pointmass_dyn.robots import reference_poses, srdf_path, urdf_path

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pmd.errors.UrdfRepairWarning)
        warnings.simplefilter("ignore", pmd.errors.UrdfWarning)
        model, poses = reference_poses(name, repair=True, **({"root_joint": "free"} if free else {}))
    path = str(urdf_path(name))
    ref = (pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()) if free
           else pin.buildModelFromUrdf(path))
    pin.loadReferenceConfigurations(ref, str(srdf_path(name)), False)
    assert poses and len(poses) == len(ref.referenceConfigurations)
    for k, q in poses.items():
        np.testing.assert_array_equal(q, ref.referenceConfigurations[k])


def test_a_bad_srdf_value_names_the_pose_and_the_joint(tmp_path):
    model = pmd.load_scene("panda").model
    srdf = tmp_path / "p.srdf"
    srdf.write_text('<robot name="p"><group_state name="up" group="arm">'
                    '<joint name="panda_joint2" value="0.1 0.2"/></group_state></robot>')
    with pytest.raises(pmd.errors.UrdfError, match=r"group_state 'up' joint 'panda_joint2'.*"
                                                   r"expected 1 finite number"):
        model.reference_poses(str(srdf))
    srdf.write_text('<robot name="p"><group_state name="up" group="arm">'
                    '<joint name="panda_joint2" value="0.5"/><joint name="no_such" value="1"/>'
                    '</group_state></robot>')
    with pytest.warns(pmd.errors.UrdfWarning, match="no_such"):
        q = model.reference_poses(str(srdf))["up"]
    expected = model.neutral()
    expected[1] = 0.5
    np.testing.assert_array_equal(q, expected)
