"""URDF repairs (`Model.from_urdf(..., repair=...)`, docs/robots.md): every URDF of
example-robot-data loads, loads with repair (each repair listed), or is refused for not being
a robot description; repaired models equal MuJoCo's model of the same file compiled with the
matching compiler options, and Pinocchio's model of the file repaired here independently
(NumPy), to <= 1e-9 relative. Then lenient XML (undeclared namespace prefixes) and errors."""

from __future__ import annotations

import pickle
import re
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import G, record, rel_err, robots_dir

pin = pytest.importorskip("pinocchio")
TOL = 1e-9
ROOT = robots_dir()
pytestmark = pytest.mark.skipif(ROOT is None, reason="example-robot-data not installed")
FILES = sorted(ROOT.rglob("*.urdf")) if ROOT is not None else []


def load(path, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = pmd.Model.from_urdf(path, **kw)
    repairs = [w for w in caught if issubclass(w.category, pmd.errors.UrdfRepairWarning)]
    return model, repairs


def outcomes(root_joint=None):
    """{relative path: ("loaded" | "repaired" | "refused", detail)} for every file. The
    table of docs/robots.md: `cd tests && python -W ignore -c "import test_urdf_repair as t;
    [print(v[0], k, v[1][:80]) for k, v in sorted(t.outcomes('free').items())]"`."""
    table = {}
    for path in FILES:
        rel = str(path.relative_to(ROOT))
        try:
            load(path, root_joint=root_joint)
            table[rel] = ("loaded", "")
        except pmd.errors.UrdfError as plain:
            try:
                model, _ = load(path, root_joint=root_joint, repair=True)
                rules = sorted({r for rec in model.repairs for r in rec["rules"]})
                table[rel] = ("repaired", ", ".join(rules), str(plain))
            except pmd.errors.UrdfError as e:
                table[rel] = ("refused", str(e))
    return table


@pytest.fixture(scope="module")
def table():
    return outcomes()


def test_every_robot_loads_or_loads_with_repair(table):
    refused = {k: v for k, v in table.items() if v[0] == "refused"}
    # ur3.urdf is a xacro wrapper without links (Pinocchio refuses it too).
    assert set(refused) == {"ur_description/urdf/ur3.urdf"}, refused
    assert "no <link> elements" in refused["ur_description/urdf/ur3.urdf"][1]
    with pytest.raises(ValueError):
        pin.buildModelFromUrdf(str(ROOT / "ur_description/urdf/ur3.urdf"))
    repaired = {k for k, v in table.items() if v[0] == "repaired"}
    assert {
        "allegro_hand_description/urdf/allegro_left_hand.urdf",
        "allegro_hand_description/urdf/allegro_right_hand.urdf",
        "alex_description/urdf/alex_psyonic_hands.urdf",
        "hyq_description/robots/hyq_no_sensors.urdf",
        "pr2_description/urdf/pr2.urdf",
        "romeo_description/urdf/romeo.urdf",
        "romeo_description/urdf/romeo_small.urdf",
        "romeo_description/urdf/romeo_laas_small.urdf",
    } == repaired
    for k in repaired:
        # Without repair, the error names the option that loads the file.
        assert "repair=True" in table[k][2], (k, table[k][2])


@pytest.mark.parametrize("root_joint", [None, "free"])
def test_repair_loads_every_robot_with_a_free_root(root_joint):
    for path in FILES:
        if path.name == "ur3.urdf":
            continue
        model, _ = load(path, root_joint=root_joint, repair=True)
        assert model.nv > 0 or root_joint is None


# --------------------------------------------------- the repair, done independently in NumPy


def rpy_matrix(rpy):
    r, p, y = rpy
    cx, sx, cy, sy, cz, sz = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def numpy_repaired(text, bound_mass=0.0, bound_inertia=0.0, balance=True, weld=True) -> str:
    """The URDF with MuJoCo's rules applied to each link's own <inertial> (mjCBody::Compile:
    bounds on mass and principal moments, then balance to the mean when A + B < C), and
    moving joints that move no mass made fixed."""
    robot = ET.fromstring(text)
    mass_of = {}
    for link in robot.findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            m, xyz, tensor = 0.0, "0 0 0", np.zeros((3, 3))
        else:
            origin = inertial.find("origin")
            xyz = origin.get("xyz", "0 0 0") if origin is not None else "0 0 0"
            rpy = [
                float(x)
                for x in (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()
            ]
            m = float(inertial.find("mass").get("value"))
            a = {
                k: float(inertial.find("inertia").get(k))
                for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
            }
            i = np.array(
                [
                    [a["ixx"], a["ixy"], a["ixz"]],
                    [a["ixy"], a["iyy"], a["iyz"]],
                    [a["ixz"], a["iyz"], a["izz"]],
                ]
            )
            r = rpy_matrix(rpy)
            tensor = r @ i @ r.T
        lam, vec = np.linalg.eigh(tensor)
        new_m, new_lam = max(m, bound_mass), np.maximum(lam, bound_inertia)
        a_, b_, c_ = new_lam
        if balance and (a_ + b_ < c_ or a_ + c_ < b_ or b_ + c_ < a_):
            new_lam = np.full(3, new_lam.sum() / 3)
        mass_of[link.get("name")] = new_m
        if new_m == m and np.array_equal(new_lam, lam):
            continue  # unchanged links keep their tensor bit for bit, as ours do
        t = vec @ np.diag(new_lam) @ vec.T
        if inertial is not None:
            link.remove(inertial)
        ET.SubElement(link, "inertial").extend(
            [
                ET.Element("origin", xyz=xyz, rpy="0 0 0"),
                ET.Element("mass", value=repr(float(new_m))),
                ET.Element(
                    "inertia",
                    ixx=repr(float(t[0, 0])),
                    ixy=repr(float(t[0, 1])),
                    ixz=repr(float(t[0, 2])),
                    iyy=repr(float(t[1, 1])),
                    iyz=repr(float(t[1, 2])),
                    izz=repr(float(t[2, 2])),
                ),
            ]
        )
    if weld:
        joints = robot.findall("joint")
        children = {}
        for j in joints:
            children.setdefault(j.find("parent").get("link"), []).append(
                j.find("child").get("link")
            )

        def below(link):
            return mass_of.get(link, 0.0) + sum(below(c) for c in children.get(link, []))

        for j in joints:
            if j.get("type") != "fixed" and below(j.find("child").get("link")) <= 0.0:
                j.set("type", "fixed")
    return ET.tostring(robot, encoding="unicode")


REPAIRED = [
    "allegro_hand_description/urdf/allegro_left_hand.urdf",
    "alex_description/urdf/alex_psyonic_hands.urdf",
    "hyq_description/robots/hyq_no_sensors.urdf",
    "pr2_description/urdf/pr2.urdf",
    "romeo_description/urdf/romeo.urdf",
    "romeo_description/urdf/romeo_small.urdf",
    "romeo_description/urdf/romeo_laas_small.urdf",
    "anymal_b_simple_description/robots/anymal.urdf",
    "go1_description/urdf/go1.urdf",
]


def pin_check(name, model, pm, seeds=(0, 1)):
    from pointmass_dyn.io import pinocchio_q

    pm.gravity.linear = G
    for seed in seeds:
        rng = np.random.default_rng(seed)
        q = model.neutral()
        for _, (q0, _v0, nq, _nv) in zip(model.joint_names, model.joint_slices()):
            if nq == 1:
                q[q0] = rng.uniform(-1.5, 1.5)
            else:  # the free root: position, then a unit quaternion
                q[q0 : q0 + 3] = rng.normal(size=3)
                w = rng.normal(size=4)
                q[q0 + 3 : q0 + 7] = w / np.linalg.norm(w)
        v = rng.normal(size=model.nv)
        qp = pinocchio_q(pm, q)
        d = pm.createData()
        m_ref = pin.crba(pm, d, qp)
        m_ref = np.triu(m_ref) + np.triu(m_ref, 1).T
        b_ref = pin.nonLinearEffects(pm, d, qp, v)
        e_m, e_b = rel_err(model.mass_matrix(q), m_ref), rel_err(model.bias_forces(q, v, G), b_ref)
        record(f"repair {name}: mass_matrix vs Pinocchio", e_m)
        record(f"repair {name}: bias_forces vs Pinocchio", e_b)
        assert max(e_m, e_b) <= TOL, (name, seed, e_m, e_b)


@pytest.mark.parametrize("root_joint", [None, "free"])
@pytest.mark.parametrize("rel", REPAIRED)
def test_repaired_equals_pinocchio_on_the_numpy_repaired_file(rel, root_joint, tmp_path):
    path = ROOT / rel
    model, caught = load(path, root_joint=root_joint, repair=True)
    assert len(caught) == 1 and len(model.repairs) >= 1
    for rec in model.repairs:  # each record named in the one warning
        assert f"'{rec['link']}'" in str(caught[0].message)
    fixed = tmp_path / "repaired.urdf"
    fixed.write_text(numpy_repaired(path.read_text()))
    args = (pin.JointModelFreeFlyer(),) if root_joint == "free" else ()
    pm = pin.buildModelFromUrdf(str(fixed), *args)
    assert model.joint_names == list(pm.names)[1:]
    pin_check(f"{path.stem}{' free' if root_joint else ''}", model, pm)


# ------------------------------------------------------------ against MuJoCo's compiler


def mujoco_model(text, compiler):
    pytest.importorskip("mujoco")
    from test_import import mj_compile, mujoco_urdf

    return mj_compile(mujoco_urdf(text, compiler))


# (file, our repair, MuJoCo's compiler options): files MuJoCo compiles with those options
# (it refuses tensors with an eigenvalue < 1e-14 before any option applies: hyq, anymal,
# romeo_laas_small).
MUJOCO_CASES = [
    ("allegro_hand_description/urdf/allegro_left_hand.urdf", True, 'balanceinertia="true"'),
    ("allegro_hand_description/urdf/allegro_right_hand.urdf", True, 'balanceinertia="true"'),
    ("alex_description/urdf/alex_psyonic_hands.urdf", True, 'balanceinertia="true"'),
    ("pr2_description/urdf/pr2.urdf", True, 'balanceinertia="true"'),
    ("romeo_description/urdf/romeo_small.urdf", True, 'balanceinertia="true"'),
    (
        "romeo_description/urdf/romeo.urdf",
        pmd.InertiaRepair(bound_mass=1e-3, bound_inertia=1e-6, weld_massless=False),
        'boundmass="1e-3" boundinertia="1e-6" balanceinertia="true"',
    ),
]


@pytest.mark.parametrize(
    "rel,repair,compiler", MUJOCO_CASES, ids=[c[0].split("/")[-1] for c in MUJOCO_CASES]
)
def test_repaired_equals_mujoco_compiled_with_the_same_options(rel, repair, compiler):
    mujoco = pytest.importorskip("mujoco")
    path = ROOT / rel
    m = mujoco_model(path.read_text(), compiler)
    model, _ = load(path, repair=repair)
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(m.njnt)]
    slices = dict(zip(model.joint_names, model.joint_slices()))
    perm = np.array([slices[n][0] for n in names], dtype=int)
    assert sorted(names) == sorted(model.joint_names)
    for seed in (0, 1):
        rng = np.random.default_rng(seed)
        qpos, qvel = rng.uniform(-1.5, 1.5, m.nq), rng.normal(size=m.nv)
        d = mujoco.MjData(m)
        d.qpos[:], d.qvel[:] = qpos, qvel
        mujoco.mj_forward(m, d)
        m_ref = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, m_ref)
        q, v = np.empty(model.nq), np.empty(model.nv)
        q[perm], v[perm] = qpos, qvel
        e_m = rel_err(model.mass_matrix(q)[np.ix_(perm, perm)], m_ref)
        e_b = rel_err(model.bias_forces(q, v, m.opt.gravity)[perm], d.qfrc_bias)
        record(f"repair {path.stem}: mass_matrix vs MuJoCo", e_m)
        record(f"repair {path.stem}: bias_forces vs MuJoCo", e_b)
        assert max(e_m, e_b) <= TOL, (rel, seed, e_m, e_b)


# ------------------------------------------------------------------ records and options


def test_weld_records_and_pickle():
    model, _ = load(ROOT / "romeo_description/urdf/romeo.urdf", repair=True)
    welds = [r for r in model.repairs if r["rules"] == ["weld_massless"]]
    assert welds and all(r["joint_type"] == ("revolute", "fixed") for r in welds)
    assert all(r["joint"] not in model.joint_names for r in welds)
    back = pickle.loads(pickle.dumps(model))
    assert back.repairs == model.repairs
    pm = pin.buildModelFromUrdf(str(ROOT / "romeo_description/urdf/romeo.urdf"))
    assert model.nv == pm.nv - len(welds)


def test_balance_record_is_mujoco_mean():
    model, _ = load(ROOT / "pr2_description/urdf/pr2.urdf", repair=True)
    (rec,) = [r for r in model.repairs if r["link"] == "sensor_mount_link"]
    before, after = rec["principal_moments"]
    assert before == pytest.approx((1e-3, 1e-3, 1e-2), rel=1e-12)
    assert after == pytest.approx((4e-3,) * 3, rel=1e-12)
    assert rec["mass"][0] == rec["mass"][1]


@pytest.mark.parametrize(
    "repair,match",
    [
        ({"balance": True}, "repair: expected None, False, True, a dict"),
        ({"bound_mass": -1.0}, "repair.bound_mass: expected a finite number >= 0"),
        ({"weld_massless": 1}, "repair.weld_massless: expected True or False"),
        ("yes", "repair: expected"),
    ],
)
def test_bad_repair_option(repair, match):
    with pytest.raises(pmd.errors.InvalidInputError, match=match):
        pmd.Model.from_urdf(ROOT / "pr2_description/urdf/pr2.urdf", repair=repair)


def test_no_repair_means_no_change():
    path = ROOT / "panda_description/urdf/panda.urdf"
    plain, _ = load(path)
    same, caught = load(path, repair=False)
    assert same.repairs == [] and not caught
    q = plain.neutral() + 0.3
    assert np.array_equal(plain.mass_matrix(q), same.mass_matrix(q))
    repaired, caught = load(path, repair=True)  # a valid file: nothing to repair
    assert repaired.repairs == [] and not caught
    assert np.array_equal(plain.mass_matrix(q), repaired.mass_matrix(q))


# -------------------------------------------------------------------------- lenient XML

DRAKE = """<?xml version="1.0"?>
<robot name="r">
  <link name="base"/>
  <link name="arm" drake:note="x">
    <inertial><origin xyz="0.1 0 0"/><mass value="2"/>
      <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.25"/></inertial>
    <drake:proximity_properties><drake:mu_dynamic value="0.5"/></drake:proximity_properties>
  </link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/>
    <drake:acceleration lower="-1" upper="1"/></joint>
  <drake:joint name="extra" type="planar"><drake:parent link="base"/></drake:joint>
</robot>
"""


def test_undeclared_namespace_prefix_accepted_with_a_warning(tmp_path):
    path = tmp_path / "drake.urdf"
    path.write_text(DRAKE)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = pmd.Model.from_urdf(path)
    msgs = [str(w.message) for w in caught if issubclass(w.category, pmd.errors.UrdfWarning)]
    assert any("undeclared XML namespace prefix(es) 'drake:'" in m for m in msgs), msgs
    assert any("<drake:joint>" in m and "<link><drake:proximity_properties>" in m for m in msgs)
    assert model.joint_names == ["j"]  # <drake:joint> is not a URDF joint
    pm = pin.buildModelFromUrdf(str(path))
    assert model.total_mass == pytest.approx(pin.computeTotalMass(pm), rel=1e-15)
    pin_check("drake", model, pm, seeds=(0,))


def test_unreadable_xml_is_a_clear_error(tmp_path):
    path = tmp_path / "bad.urdf"
    path.write_text('<robot name="r"><link name="a"></robot>')
    with pytest.raises(pmd.errors.UrdfError, match=r"malformed XML at line 1"):
        pmd.Model.from_urdf(path)


def test_namespace_mention_is_not_mistaken(tmp_path):
    # A declared prefix keeps working and is not reported.
    path = tmp_path / "x.urdf"
    path.write_text(
        re.sub('<robot name="r">', '<robot name="r" xmlns:drake="http://drake.mit.edu">', DRAKE)
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pmd.Model.from_urdf(path)
    assert not any("undeclared" in str(w.message) for w in caught)


def test_scene_urdf_repair_key(tmp_path):
    """`urdf_repair = true` in a scene loads the URDF as `from_urdf(..., repair=True)`."""
    path = ROOT / "pr2_description/urdf/pr2.urdf"
    scene_file = tmp_path / "s.toml"
    scene_file.write_text(f'urdf = "{path}"\n')
    with pytest.raises(pmd.errors.SceneError, match="repair=True"):
        pmd.load_scene(scene_file)
    scene_file.write_text(f'urdf = "{path}"\nurdf_repair = true\n')
    scene = pmd.load_scene(scene_file)
    model, _ = load(path, repair=True)
    q = np.random.default_rng(0).uniform(-1, 1, model.nq)
    assert np.array_equal(scene.model.mass_matrix(q), model.mass_matrix(q))
    bad = tmp_path / "bad.toml"
    bundled = scene_file.parent / "pendulum.toml"
    bundled.write_text(
        (Path(pmd.__file__).with_name("scenes") / "pendulum_planar.toml").read_text()
    )
    bad.write_text("urdf_repair = true\n" + bundled.read_text())
    with pytest.raises(pmd.errors.SceneError, match="urdf_repair: needs a urdf key"):
        pmd.load_scene(bad)
