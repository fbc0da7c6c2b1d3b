"""A model's joint names, limits, repairs, couplings, armature and visuals survive every way
a model travels: into a Scene and out of it, `Scene.replace`, `with_body`, pickling and deep
copies, a scene file written and loaded (`write_scene`, `Scene.to_toml`), and `to_mjcf`. The reference names come from
Pinocchio's URDF parser and the limits from the URDF text itself."""

from __future__ import annotations

import copy
import pickle
import xml.etree.ElementTree as ET

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn.robots import urdf_path

pin = pytest.importorskip("pinocchio")

GO2 = "go2_description/urdf/go2.urdf"


def urdf_limits(path) -> dict[str, tuple[float, float, float, float]]:
    """{joint name: (lower, upper, effort, velocity)} of the revolute/prismatic joints."""
    out = {}
    for j in ET.parse(path).getroot().iter("joint"):
        lim = j.find("limit")
        if j.get("type") in ("revolute", "prismatic") and lim is not None:
            out[j.get("name")] = tuple(
                float(lim.get(k, "nan")) for k in ("lower", "upper", "effort", "velocity")
            )
    return out


def pinocchio_names(path, free: bool) -> list[str]:
    m = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer()) if free else (
        pin.buildModelFromUrdf(str(path)))
    return list(m.names)[1:]


def copies(model: pmd.Model):
    """(how, model) for every way a model travels."""
    scene = pmd.Scene(model, effects=[pmd.Gravity()], rtol=1e-7)
    q = model.neutral()
    yield "model", model
    yield "Scene(model).model", scene.model
    yield "Scene.replace(q0=…).model", scene.replace(q0=q, rtol=1e-5).model
    yield "pickle(model)", pickle.loads(pickle.dumps(model))
    yield "pickle(scene).model", pickle.loads(pickle.dumps(scene)).model
    yield "Scene.from_toml(scene.to_toml()).model", pmd.Scene.from_toml(scene.to_toml()).model
    yield "deepcopy(model)", copy.deepcopy(model)
    yield "with_body", model.with_body(model.nbodies - 1, model.body(model.nbodies - 1))
    grown = scene.model
    grown.add_body(pmd.RigidBody(1.0, [0, 0, 0], np.eye(3) * 1e-3), pmd.Fixed(),
                   parent=grown.nbodies - 1, name="payload")
    yield "model.add_body", grown


def test_go2_joint_names_and_limits_survive_every_copy():
    path = urdf_path(GO2)
    go2 = pmd.example_robot(GO2, root_joint="free")
    names = pinocchio_names(path, free=True)
    limits = urdf_limits(path)
    assert names[0] == "root_joint" and len(names) == 13
    for how, m in copies(go2):
        assert m.joint_names == names, how
        got = m.joint_limits()
        for n, lim in limits.items():
            assert got[n] == pytest.approx(lim), (how, n)
        assert m.name == go2.name, how
        assert len(m.visuals) == len(go2.visuals) > 0, how


def test_joint_names_are_accepted_wherever_a_joint_is_meant():
    go2 = pmd.example_robot(GO2, root_joint="free")
    by_joint = pmd.Scene(go2, effects=[pmd.Damper(["FL_hip_joint", "FR_thigh_joint"], 2.0)])
    by_body = pmd.Scene(go2, effects=[pmd.Damper(["FL_hip", "FR_thigh"], 2.0)])
    q, v = go2.neutral(), np.linspace(-1, 1, go2.nv)
    f_joint = pmd.effect_forces(by_joint, 0.0, q, v)["dampers"]
    f_body = pmd.effect_forces(by_body, 0.0, q, v)["dampers"]
    np.testing.assert_array_equal(f_joint, f_body)
    # −c v on the named joints' speeds (the free flyer takes speeds 0..5), nothing elsewhere
    expected = np.zeros(go2.nv)
    for n in ("FL_hip_joint", "FR_thigh_joint"):
        k = go2.joint_names.index(n) + 5
        expected[k] = -2.0 * v[k]
    np.testing.assert_allclose(f_joint, expected, rtol=1e-15)
    with pytest.raises(pmd.errors.InvalidInputError) as e:
        pmd.Scene(go2, effects=[pmd.Damper(["FL_hip_jiont"], 1.0)])
    msg = str(e.value)
    assert "'FL_hip_jiont'" in msg and "'FL_hip_joint' (body 'FL_hip')" in msg
    # Only joints that can be chosen are listed: Go2's welded links (feet, imu) are not.
    assert "FL_foot" not in msg and "imu" not in msg


def test_bundled_panda_keeps_its_joint_names_through_files_and_mjcf(tmp_path):
    path = urdf_path("panda")  # the bundled file's source robot has the same joint names
    scene = pmd.load_scene("panda")
    names = pinocchio_names(pmd.scenes.resolve_scene_path("panda").parent / "panda.urdf",
                            free=False)
    assert names == [f"panda_joint{k}" for k in range(1, 8)]
    assert scene.model.joint_names == names
    limits = urdf_limits(pmd.scenes.resolve_scene_path("panda").parent / "panda.urdf")
    assert scene.model.joint_limits()["panda_joint4"] == pytest.approx(limits["panda_joint4"])
    written = pmd.design.write_scene({}, "panda", tmp_path / "panda_copy.toml")
    again = pmd.load_scene(written)
    assert again.model.joint_names == names
    assert again.model.joint_limits() == scene.model.joint_limits()
    del path
    mujoco = pytest.importorskip("mujoco")
    mj = mujoco.MjModel.from_xml_string(pmd.to_mjcf(scene))
    mj_names = [mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_JOINT, k) for k in range(mj.njnt)]
    assert mj_names == names
    for k, n in enumerate(names):
        np.testing.assert_allclose(mj.jnt_range[k], limits[n][:2], rtol=1e-15)
        assert mj.jnt_limited[k] == 0  # written for the reader, enforced only by JointLimit


REPAIRED = """<robot name="mimicked">
  <link name="base"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="a"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.05" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="b"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="ja" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="5" velocity="2"/></joint>
  <joint name="jb" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="3" velocity="4"/><mimic joint="ja" multiplier="-0.5" offset="0.1"/></joint>
</robot>"""


def test_repairs_couplings_and_armature_survive_every_copy(tmp_path):
    path = tmp_path / "mimicked.urdf"
    path.write_text(REPAIRED)
    with pytest.warns(pmd.errors.UrdfRepairWarning):
        model = pmd.Model.from_urdf(str(path), repair=True)
    model.set_armature("jb", 0.25)
    # link a's moments (0.01, 0.01, 0.05) break A + B >= C: the repair makes them equal
    assert [r["link"] for r in model.repairs] == ["a"]
    assert model.couplings[0][3:] == (-0.5, 0.1)
    for how, m in copies(model):
        assert m.joint_names == ["ja", "jb"], how
        assert m.joint_limits() == {"ja": (-1, 1, 5, 2), "jb": (-2, 2, 3, 4)}, how
        assert m.repairs == model.repairs, how
        assert m.couplings == model.couplings, how
        np.testing.assert_array_equal(m.armature[:2], [0.0, 0.25])


def test_replace_changes_what_is_given_and_keeps_the_rest():
    chain = pmd.load_scene("chain7")
    q = np.full(7, 0.1)
    r = chain.replace(q0=q, rtol=1e-9, method="DOP853", name="varied")
    np.testing.assert_array_equal(r.q0, q)
    np.testing.assert_array_equal(r.v0, chain.v0)
    assert (r.rtol, r.method, r.name) == (1e-9, "DOP853", "varied")
    assert (r.atol, r.t_span, r.description) == (chain.atol, chain.t_span, chain.description)
    assert r.model.joint_names == chain.model.joint_names
    # The run follows the replaced start state: the same as a scene built with it.
    built = pmd.Scene(chain.model, q, chain.v0, chain.effects, t_span=(0, 0.2), rtol=1e-9,
                      atol=chain.atol, method="DOP853")
    a = pmd.simulate(r, (0, 0.2))
    b = pmd.simulate(built, (0, 0.2))
    np.testing.assert_array_equal(a.q[-1], b.q[-1])
    with pytest.raises(pmd.errors.InvalidInputError, match=r"q0: expected .*7.*got"):
        chain.replace(q0=np.zeros(3))
    with pytest.raises(pmd.errors.InvalidInputError, match="rtol: expected a finite number > 0"):
        chain.replace(rtol=-1.0)
    with pytest.raises(pmd.errors.InvalidInputError, match="method"):
        chain.replace(method="RK99")


def test_a_typed_result_reads_as_the_dict_it_replaced_and_pickles_as_one():
    """A record (here `point_motion`) answers `r[key]`, `keys()`, `items()`, `len()` and `in`
    as the dict it replaced did, and pickles to that dict with equal values: the attribute read
    and the unpickled entry are the same numbers."""
    model = pmd.load_scene("fourbar").model
    rng = np.random.default_rng(3)
    q = model.neutral()
    v, a = rng.normal(size=model.nv), rng.normal(size=model.nv)
    r = model.point_motion(q, v, a)
    keys = list(r.keys())
    assert keys and len(r) == len(keys) and list(r) == keys
    assert all(k in r for k in keys) and "not a field" not in r
    for k, value in r.items():
        np.testing.assert_array_equal(np.asarray(value), np.asarray(getattr(r, k)))
        np.testing.assert_array_equal(np.asarray(r[k]), np.asarray(getattr(r, k)))
    back = pickle.loads(pickle.dumps(r))
    assert isinstance(back, dict) and list(back) == keys
    for k in keys:
        np.testing.assert_array_equal(np.asarray(back[k]), np.asarray(getattr(r, k)))
    with pytest.raises(KeyError):
        r["not a field"]
