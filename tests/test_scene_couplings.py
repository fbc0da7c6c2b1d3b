"""Couplings and armature in scene files (docs/couplings.md "In a scene file"): a scene's
``[[coupling]]`` tables and ``armature`` keys give the dynamics of the same model built in
Python with ``add_coupling``/``set_armature``; ``write_scene`` keeps them; bad values are
``SceneError``s naming the key."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn.errors import SceneError

Z = [0.0, 0.0, 1.0]
G = np.array([0.0, -9.81, 0.0])

ARM = """
name = "arm"
angles = "{angles}"

[[body]]
name = "upper"
joint = {{ type = "Revolute", axis = [0, 0, 1] }}
mass = 1.2
com = [0.2, 0, 0]
inertia_diag = [1e-3, 0.02, 0.02]
armature = 0.05

[[body]]
name = "fore"
parent = "upper"
translation = [0.4, 0, 0]
joint = {{ type = "Revolute", axis = [0, 0, 1] }}
mass = 0.8
com = [0.15, 0, 0]
inertia_diag = [1e-3, 0.01, 0.01]

[[body]]
name = "slider"
parent = "fore"
translation = [0.3, 0, 0]
joint = {{ type = "Prismatic", axis = [1, 0, 0] }}
mass = 0.3
com = [0.05, 0, 0]
inertia_diag = [1e-4, 1e-3, 1e-3]

[[coupling]]
joint = "fore"
reference = "upper"
ratio = 0.5
offset = {offset}

[[coupling]]
name = "screw"
joint = "slider"
reference = "fore"
ratio = {screw}

[armature]
fore = 0.02
slider = [0.3]

[[effect]]
type = "gravity"
g = [0.0, -9.81, 0.0]
"""


def _python_arm() -> pmd.Model:
    arm = pmd.Model()
    arm.add_body(pmd.RigidBody(1.2, [0.2, 0, 0], np.diag([1e-3, 0.02, 0.02])), pmd.Revolute(Z),
                 name="upper")
    arm.add_body(pmd.RigidBody(0.8, [0.15, 0, 0], np.diag([1e-3, 0.01, 0.01])),
                 pmd.Revolute(Z), parent="upper", translation=[0.4, 0, 0], name="fore")
    arm.add_body(pmd.RigidBody(0.3, [0.05, 0, 0], np.diag([1e-4, 1e-3, 1e-3])),
                 pmd.Prismatic([1, 0, 0]), parent="fore", translation=[0.3, 0, 0],
                 name="slider")
    arm.add_coupling("fore", "upper", ratio=0.5, offset=0.2)
    arm.add_coupling("slider", "fore", ratio=0.02, name="screw")  # 2 cm per radian
    arm.set_armature("upper", 0.05)
    arm.set_armature("fore", 0.02)
    arm.set_armature("slider", 0.3)
    return arm


def _text(angles="radians") -> str:
    if angles == "degrees":  # 0.2 rad; 0.02 m/rad = 0.02·π/180 m/degree
        return ARM.format(angles=angles, offset=repr(float(np.degrees(0.2))),
                          screw=repr(float(0.02 * np.pi / 180)))
    return ARM.format(angles=angles, offset="0.2", screw="0.02")


def _same_dynamics(a: pmd.Model, b: pmd.Model) -> None:
    assert [c[:3] for c in a.couplings] == [c[:3] for c in b.couplings]
    np.testing.assert_allclose([c[3:] for c in a.couplings], [c[3:] for c in b.couplings],
                               rtol=1e-15, atol=1e-16)
    np.testing.assert_array_equal(a.armature, b.armature)
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = a.assemble(rng.uniform(-1, 1, a.nq))
        v = a.assemble_velocity(q, rng.uniform(-1, 1, a.nv))
        tau = rng.uniform(-1, 1, a.nv)
        np.testing.assert_allclose(a.mass_matrix(q), b.mass_matrix(q), rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(a.forward_dynamics(q, v, tau, G),
                                   b.forward_dynamics(q, v, tau, G), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("angles", ["radians", "degrees"])
def test_scene_keys_give_the_python_models_dynamics(angles):
    scene = pmd.Scene.from_toml(_text(angles), "arm.toml")
    ref = _python_arm()
    _same_dynamics(scene.model, ref)
    assert scene.model.couplings[1][0] == "screw"
    # Armature: the mass matrix's diagonal grows by exactly the values.
    bare = pmd.Scene.from_toml(_text(angles).split("[armature]")[0]
                               .replace("armature = 0.05\n", ""), "bare.toml").model
    q = scene.q0
    np.testing.assert_allclose(np.diag(scene.model.mass_matrix(q) - bare.mass_matrix(q)),
                               [0.05, 0.02, 0.3], rtol=1e-12)
    # The initial state is put on the couplings.
    np.testing.assert_allclose(ref.constraint_residual(scene.q0), 0.0, atol=1e-12)


def test_write_scene_keeps_couplings_and_armature(tmp_path):
    source = tmp_path / "arm.toml"
    source.write_text(_text(), encoding="utf-8")
    heavier = pmd.RigidBody(1.1, [0.12, 0.01, 0], np.diag([2e-3, 0.012, 0.011]))
    out = pmd.design.write_scene({"fore": heavier}, source, tmp_path / "designed.toml")
    loaded = pmd.load_scene(out)
    _same_dynamics(loaded.model, _python_arm().with_body("fore", heavier))
    # And the run: the same trajectory as the Python model's scene.
    ref = pmd.Scene(_python_arm().with_body("fore", heavier), effects=[pmd.Gravity(G)],
                    q0=loaded.q0)
    a = pmd.simulate(loaded, (0, 0.3), rtol=1e-10, atol=1e-12, t_eval=[0.3])
    b = pmd.simulate(ref, (0, 0.3), rtol=1e-10, atol=1e-12, t_eval=[0.3])
    np.testing.assert_allclose(a.q, b.q, atol=1e-12)


def test_urdf_joint_names_in_a_scene():
    urdf = Path(pmd.__file__).parent / "scenes" / "panda.urdf"
    text = f"""
urdf = "{urdf.as_posix()}"
[[coupling]]
joint = "panda_joint7"
reference = "panda_joint6"
ratio = -1.5
[armature]
panda_joint1 = 0.1
panda_link4 = 0.2
"""
    scene = pmd.Scene.from_toml(text, "panda_coupled.toml")
    ref = pmd.Model.from_urdf(urdf)
    ref.add_coupling("panda_joint7", "panda_joint6", ratio=-1.5)
    ref.set_armature("panda_joint1", 0.1)
    ref.set_armature("panda_link4", 0.2)
    _same_dynamics(scene.model, ref)


@pytest.mark.parametrize("change, key", [
    (('ratio = 0.5', 'ratio = "half"'), r"coupling\[0\]\.ratio: expected a number"),
    (('offset = 0.2', 'offset = nan'), r"coupling\[0\]\.offset: expected a finite number"),
    (('joint = "fore"', 'joint = "elbow"'), r"coupling\[0\]\.joint: expected a joint name.*'elbow'"),
    (('joint = "fore"', 'gain = 2\njoint = "fore"'), r"coupling\[0\]\.gain: unknown key"),
    (('reference = "upper"', 'reference = "fore"'), r"coupling\[0\]\.reference: expected a joint other"),
    (('joint = "fore"\n', ''), r"coupling\[0\]\.joint: missing"),
    (('fore = 0.02', 'fore = -0.02'), r"armature\.fore: .*>= 0"),
    (('fore = 0.02', 'fore = "heavy"'), r"armature\.fore: expected a number >= 0"),
    (('fore = 0.02', 'elbow = 0.02'), r"armature\.elbow: expected a joint name"),
    (('slider = [0.3]', 'slider = [0.3, 0.1]'), r"armature\.slider: .*one number, or 1"),
    (('armature = 0.05', 'armature = [true]'), r"body\[0\] \('upper'\)\.armature: expected a number"),
])
def test_bad_values_name_the_key(change, key):
    text = _text().replace(*change, 1)
    with pytest.raises(SceneError, match=key):
        pmd.Scene.from_toml(text, "arm.toml")
