"""URDF import: robots from example-robot-data against Pinocchio's own URDF parser
(`buildModelFromUrdf`, no root joint): joint names and order, body names, limits, damping and
friction, and at random states the mass matrix, bias forces and forward dynamics to ≤ 1e-9
relative. Then every kind of malformed file, as small URDF strings written to tmp files."""

from __future__ import annotations

import importlib.metadata
import math
import warnings
from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import G, record, rel_err

pin = pytest.importorskip("pinocchio")

TOL = 1e-9


def robots_dir() -> Path | None:
    """example-robot-data's robots folder (the cmeel wheel has no Python module to ask)."""
    candidates = []
    try:
        dist = importlib.metadata.distribution("example-robot-data")
        candidates.append(Path(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    except importlib.metadata.PackageNotFoundError:
        pass
    # pinocchio lives in cmeel.prefix/lib/pythonX.Y/site-packages/pinocchio.
    candidates.append(Path(pin.__file__).parents[4] / "share" / "example-robot-data" / "robots")
    for c in candidates:
        if c.is_dir():
            return c
    return None


ROBOTS_DIR = robots_dir()

# name: (file, states to test). Each is fixed-base with supported joint types.
ROBOTS = {
    # 7 revolute + 2 prismatic fingers (one a mimic joint), massless hand-tcp frames.
    "panda": "panda_description/urdf/panda.urdf",
    # Root link 'world', fixed joints to base and tool frames, massless links.
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    # Continuous joints (Pinocchio: cos/sin pairs).
    "kinova": "kinova_description/robots/kinova.urdf",
    "double_pendulum_continuous": "double_pendulum_description/urdf/double_pendulum_continuous.urdf",
    # Prismatic joints and mimic joints.
    "baxter": "baxter_description/urdf/baxter.urdf",
    # Humanoid, 44 joints, mimic gripper joints.
    "talos": "talos_data/robots/talos_full_v2.urdf",
    # Humanoid with massless intermediate links on moving joints (multi-axis hips, ...).
    "human": "human_description/robots/human.urdf",
    # Humanoid with hands, 43 joints.
    "g1_with_hands": "g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf",
    # Humanoid, 32 joints, unaligned axes, rounding noise in inertias.
    "icub": "icub_description/robots/icub.urdf",
    # Mobile manipulator, 48 joints: continuous wheels, prismatic torso, hand; an invalid
    # dummy inertia on a link welded to the world (a warning).
    "tiago": "tiago_description/robots/tiago.urdf",
}

needs_robots = pytest.mark.skipif(ROBOTS_DIR is None, reason="example-robot-data not installed")


def load(path, mimic=False) -> tuple[pmd.Model, list[str]]:
    """Our model and the UrdfWarning messages it gave; mimic joints independent by default,
    as in Pinocchio's `buildModelFromUrdf` that these tests compare with."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = pmd.Model.from_urdf(path, mimic=mimic)
    msgs = [str(w.message) for w in caught if issubclass(w.category, pmd.errors.UrdfWarning)]
    return model, msgs


def pin_q(pm, model: pmd.Model, q: np.ndarray) -> np.ndarray:
    """Our q (angles) as Pinocchio's (continuous joints as cos, sin)."""
    slot = {n: s[0] for n, s in zip(model.joint_names, model.joint_slices())}
    out = np.empty(pm.nq)
    for j in range(1, pm.njoints):
        jm = pm.joints[j]
        x = q[slot[pm.names[j]]]
        if jm.nq == 2:
            out[jm.idx_q : jm.idx_q + 2] = [math.cos(x), math.sin(x)]
        else:
            assert jm.nq == 1
            out[jm.idx_q] = x
    return out


def random_q(model: pmd.Model, rng) -> np.ndarray:
    q = np.empty(model.nq)
    for k, (lo, hi, _, _) in enumerate(model.joint_limits().values()):
        if math.isfinite(lo) and math.isfinite(hi) and lo < hi:
            q[k] = rng.uniform(lo, hi)
        else:
            q[k] = rng.uniform(-math.pi, math.pi)
    return q


def sym(m):
    return np.triu(m) + np.triu(m, 1).T


@pytest.fixture(scope="module", params=sorted(ROBOTS))
def robot(request):
    if ROBOTS_DIR is None:
        pytest.skip("example-robot-data not installed")
    path = ROBOTS_DIR / ROBOTS[request.param]
    model, msgs = load(path)
    pm = pin.buildModelFromUrdf(str(path))
    return request.param, path, model, msgs, pm


def test_names_and_order_match_pinocchio(robot):
    name, _, model, _, pm = robot
    assert model.joint_names == list(pm.names)[1:], name
    bodies = [f.name for f in pm.frames if f.type == pin.FrameType.BODY]
    assert model.body_names == bodies, name
    assert model.nv == pm.nv and model.nq == pm.nv
    assert model.nlinks == pm.njoints - 1
    # Pinocchio's total mass leaves out what is welded to the world, as our links do.
    assert model.total_mass == pytest.approx(pin.computeTotalMass(pm), rel=1e-12)


def test_limits_and_dynamics_match_pinocchio(robot):
    name, _, model, _, pm = robot
    limits = model.joint_limits()
    dyn = model.joint_dynamics()
    assert list(limits) == model.joint_names == list(dyn)
    for j in range(1, pm.njoints):
        jm = pm.joints[j]
        lo, hi, effort, velocity = limits[pm.names[j]]
        if jm.nq == 1:  # continuous joints: Pinocchio bounds cos/sin, we give ±inf
            assert (lo, hi) == (pm.lowerPositionLimit[jm.idx_q], pm.upperPositionLimit[jm.idx_q])
        else:
            assert (lo, hi) == (-math.inf, math.inf)
        assert effort == pm.effortLimit[jm.idx_v], (name, pm.names[j])
        assert velocity == pm.velocityLimit[jm.idx_v], (name, pm.names[j])
        assert dyn[pm.names[j]] == (pm.damping[jm.idx_v], pm.friction[jm.idx_v])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_dynamics_match_pinocchio(robot, seed):
    name, _, model, _, pm = robot
    pd = pm.createData()
    rng = np.random.default_rng(seed)
    q = random_q(model, rng)
    v = rng.normal(size=model.nv)
    tau = rng.normal(size=model.nv)
    qp = pin_q(pm, model, q)
    pm.gravity.linear = G
    m_ref = sym(pin.crba(pm, pd, qp).copy())
    nle_ref = pin.nle(pm, pd, qp, v).copy()
    aba_ref = pin.aba(pm, pd, qp, v, tau).copy()
    errs = {
        "mass_matrix": rel_err(model.mass_matrix(q), m_ref),
        "bias_forces": rel_err(model.bias_forces(q, v, G), nle_ref),
        "forward_dynamics": rel_err(model.forward_dynamics(q, v, tau, G), aba_ref),
    }
    for k, e in errs.items():
        record(f"urdf {name}: {k}", e)
    assert max(errs.values()) <= TOL, (name, errs)


@needs_robots
@pytest.mark.parametrize("robot_name", ["panda", "kinova"])
def test_denoc_path_matches_pinocchio(robot_name):
    path = ROBOTS_DIR / ROBOTS[robot_name]
    model, _ = load(path)
    pm = pin.buildModelFromUrdf(str(path))
    pd = pm.createData()
    rng = np.random.default_rng(7)
    for _ in range(3):
        q = random_q(model, rng)
        v = rng.normal(size=model.nv)
        tau = rng.normal(size=model.nv)
        qp = pin_q(pm, model, q)
        e_m = rel_err(model.mass_matrix(q, method="denoc"), sym(pin.crba(pm, pd, qp).copy()))
        e_a = rel_err(
            model.forward_dynamics(q, v, tau, G, method="denoc"), pin.aba(pm, pd, qp, v, tau)
        )
        record(f"urdf {robot_name}: mass_matrix[denoc]", e_m)
        record(f"urdf {robot_name}: forward_dynamics[denoc]", e_a)
        assert max(e_m, e_a) <= TOL


@needs_robots
def test_mimic_joints_are_couplings_or_independent_with_mimic_false():
    model, msgs = load(ROBOTS_DIR / ROBOTS["panda"], mimic=True)
    assert not any("mimic" in m for m in msgs), msgs
    assert model.couplings == [
        ("panda_finger_joint2", "panda_rightfinger", "panda_leftfinger", 1.0, 0.0)
    ]
    model, msgs = load(ROBOTS_DIR / ROBOTS["panda"])
    assert any("mimic=False" in m and "'panda_finger_joint2'" in m for m in msgs), msgs
    assert "panda_finger_joint2" in model.joint_names and model.ncouplings == 0
    _, msgs = load(ROBOTS_DIR / ROBOTS["talos"])
    assert sum("mimic" in m for m in msgs) == 1, msgs  # one warning lists them all


def test_mimic_warning_category(tmp_path):
    path = write(
        tmp_path,
        link("base"),
        link("a"),
        link("b"),
        joint("j1", "revolute", "base", "a"),
        joint("j2", "revolute", "a", "b",
              '<limit effort="1" velocity="1"/><mimic joint="j1" multiplier="-1" offset="0.1"/>'),
    )
    with pytest.warns(pmd.errors.UrdfWarning, match=r"robot\.urdf: mimic=False: 1 mimic joint.*'j2'"):
        model = pmd.Model.from_urdf(path, mimic=False)
    assert model.nv == 2 and model.ncouplings == 0
    model = pmd.Model.from_urdf(path)
    assert model.couplings == [("j2", "b", "a", -1.0, 0.1)]


@needs_robots
def test_pathlike_and_ignored_elements_summary():
    model, msgs = load(ROBOTS_DIR / ROBOTS["ur5"])  # a pathlib.Path
    # No mimic joints: one summary of what was ignored (geometry is ignored silently).
    assert len(msgs) == 1 and "elements ignored" in msgs[0], msgs
    assert "<transmission>" in msgs[0] and "visual" not in msgs[0]
    assert model.body_names[0] == "world"
    assert model.joint_names == [
        "shoulder_pan_joint",
        "shoulder_lift_joint",
        "elbow_joint",
        "wrist_1_joint",
        "wrist_2_joint",
        "wrist_3_joint",
    ]


@needs_robots
def test_add_body_keeps_urdf_joint_data():
    model, _ = load(ROBOTS_DIR / ROBOTS["ur5"])
    limits = model.joint_limits()
    tool = model.body_names.index("tool0")
    model.add_body(pmd.RigidBody(0.5, [0, 0, 0.05], np.eye(3) * 1e-3), pmd.Fixed(), tool)
    model.add_body(pmd.RigidBody(0.2, [0, 0, 0.05], np.eye(3) * 1e-4), pmd.Revolute([0, 0, 1]), tool, name="extra")
    assert model.joint_names[:6] == list(limits)
    assert model.joint_names[6] == "extra"
    assert list(model.joint_limits().values())[:6] == list(limits.values())
    assert model.joint_limits()["extra"] == (-math.inf, math.inf, math.inf, math.inf)
    assert model.joint_dynamics()["extra"] == (0.0, 0.0)


def test_models_built_by_hand_name_joints_after_bodies():
    model = pmd.Model()
    model.add_body(pmd.RigidBody(1.0, [0.1, 0, 0], np.eye(3) * 1e-2), pmd.Revolute([0, 0, 1]), name="arm")
    assert model.joint_names == ["arm"]
    assert model.joint_dynamics() == {"arm": (0.0, 0.0)}


# --------------------------------------------------------------------------------------------
# Small URDFs written to tmp files
# --------------------------------------------------------------------------------------------
def inertial(mass=1.0, diag=(0.01, 0.02, 0.02), xyz="0.1 0 0", rpy="0 0 0"):
    return (
        f'<inertial><origin xyz="{xyz}" rpy="{rpy}"/><mass value="{mass}"/>'
        f'<inertia ixx="{diag[0]}" ixy="0" ixz="0" iyy="{diag[1]}" iyz="0" izz="{diag[2]}"/>'
        "</inertial>"
    )


def link(name, body=None):
    return f'<link name="{name}">{inertial() if body is None else body}</link>'


def joint(name, kind, parent, child, extra='<limit effort="10" velocity="2" lower="-1" upper="1"/>'):
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f"{extra}</joint>"
    )


def write(tmp_path, *parts, name="robot.urdf") -> Path:
    path = tmp_path / name
    path.write_text('<?xml version="1.0"?>\n<robot name="r">\n' + "\n".join(parts) + "\n</robot>\n")
    return path


def chain(tmp_path):
    """base → a (revolute) → b (continuous, with dynamics) → tool (fixed, massless)."""
    return write(
        tmp_path,
        link("base"),
        link("a", inertial(2.0, xyz="0 0 0.2", rpy="0.3 -0.4 1.2")),
        link("b"),
        '<link name="tool"/>',
        joint("j1", "revolute", "base", "a", '<origin xyz="0 0 0.1" rpy="0 0.5 0"/><axis xyz="0 1 1"/>'
              '<limit lower="-2" upper="2.5" effort="30" velocity="3"/>'),
        joint("j2", "continuous", "a", "b", '<origin xyz="0.3 0 0" rpy="1 0 0"/><axis xyz="0 0 1"/>'
              '<limit effort="5" velocity="4"/><dynamics damping="0.7" friction="0.2"/>'),
        joint("tool_joint", "fixed", "b", "tool", '<origin xyz="0.1 0 0"/>'),
    )


def test_small_chain_limits_dynamics_and_pinocchio(tmp_path):
    path = chain(tmp_path)
    model, msgs = load(path)
    assert msgs == []
    assert model.joint_names == ["j1", "j2"]
    assert model.body_names == ["base", "a", "b", "tool"]
    assert model.joint_limits() == {
        "j1": (-2.0, 2.5, 30.0, 3.0),
        "j2": (-math.inf, math.inf, 5.0, 4.0),
    }
    assert model.joint_dynamics() == {"j1": (0.0, 0.0), "j2": (0.7, 0.2)}
    pm = pin.buildModelFromUrdf(str(path))
    pd = pm.createData()
    rng = np.random.default_rng(3)
    for _ in range(5):
        q = rng.uniform(-2, 2, size=2)
        v = rng.normal(size=2)
        tau = rng.normal(size=2)
        qp = pin_q(pm, model, q)
        for method in ("recursive", "denoc"):
            assert rel_err(model.mass_matrix(q, method=method), sym(pin.crba(pm, pd, qp).copy())) < TOL
            assert rel_err(
                model.forward_dynamics(q, v, tau, G, method=method), pin.aba(pm, pd, qp, v, tau)
            ) < TOL
        assert rel_err(model.bias_forces(q, v, G), pin.nle(pm, pd, qp, v)) < TOL


def test_massless_intermediate_link_matches_pinocchio(tmp_path):
    """A two-axis hip: the link between the axes has no mass (a zero body)."""
    path = write(
        tmp_path,
        link("base"),
        '<link name="hip_virtual"/>',
        link("leg"),
        joint("hip_x", "revolute", "base", "hip_virtual", '<axis xyz="1 0 0"/><limit effort="1" velocity="1"/>'),
        joint("hip_y", "revolute", "hip_virtual", "leg", '<axis xyz="0 1 0"/><limit effort="1" velocity="1"/>'),
    )
    model, _ = load(path)
    pm = pin.buildModelFromUrdf(str(path))
    pd = pm.createData()
    q, v, tau = np.array([0.4, -0.9]), np.array([0.3, 1.1]), np.array([0.2, -0.1])
    assert rel_err(model.forward_dynamics(q, v, tau, G), pin.aba(pm, pd, q, v, tau)) < TOL


def test_massless_leaf_on_moving_joint_is_an_error(tmp_path):
    """Pinocchio loads this but its mass matrix has a zero row and aba returns NaN."""
    path = write(
        tmp_path,
        link("base"),
        link("palm"),
        '<link name="finger"/>',
        joint("wrist", "revolute", "base", "palm"),
        joint("finger_joint", "revolute", "palm", "finger"),
    )
    pm = pin.buildModelFromUrdf(str(path))
    with np.errstate(all="ignore"):
        a = pin.aba(pm, pm.createData(), np.zeros(2), np.zeros(2), np.zeros(2))
    assert not np.all(np.isfinite(a))
    with pytest.raises(pmd.errors.UrdfError, match=r"robot\.urdf: joint 'finger_joint': child link 'finger' has no mass"):
        pmd.Model.from_urdf(path)


def test_ignored_elements_give_one_summary_warning(tmp_path):
    path = write(
        tmp_path,
        link("base"),
        link("a"),
        joint("j", "revolute", "base", "a",
              '<limit effort="1" velocity="1"/><safety_controller k_velocity="1"/><calibration rising="0"/>'),
        '<transmission name="t"><joint name="j"/></transmission><gazebo reference="a"/>',
        '<material name="grey"/>',
    )
    model, msgs = load(path)
    assert model.nv == 1
    assert len(msgs) == 1, msgs
    for kind in ("<transmission>", "<gazebo>", "<joint><safety_controller>", "<joint><calibration>"):
        assert kind in msgs[0]
    assert "material" not in msgs[0]


BASE = [link("base"), link("a"), joint("j", "revolute", "base", "a")]


@pytest.mark.parametrize(
    "parts, pattern",
    [
        # Malformed XML: the line.
        (['<link name="base">', link("a")], r"robot\.urdf: malformed XML at line \d+"),
        (
            ['<link name="base"><inertial><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>'],
            r"robot\.urdf: link 'base': <inertial> has no <mass",
        ),
        (
            ['<link name="base"><inertial><mass value="1"/><inertia ixx="1" ixy="0" iyy="1" iyz="0" izz="1"/></inertial></link>'],
            r"robot\.urdf: link 'base': <inertia> is missing the 'ixz' attribute",
        ),
        (
            ['<link name="base"><inertial><mass value="1"/></inertial></link>'],
            r"robot\.urdf: link 'base': <inertial> has no <inertia",
        ),
        (
            [link("base"), link("a", inertial(diag=(-0.01, 0.02, 0.02))), joint("j", "revolute", "base", "a")],
            r"robot\.urdf: link 'a': <inertial>: inertia: expected a positive semidefinite",
        ),
        (
            [link("base"), link("a", inertial(diag=(0.01, 0.01, 0.03))), joint("j", "revolute", "base", "a")],
            r"robot\.urdf: link 'a': .*triangle inequality",
        ),
        (
            # Welded to a moving link: still part of the dynamics.
            BASE + [link("b", inertial(mass=-1.0)), joint("k", "fixed", "a", "b")],
            r"robot\.urdf: link 'b': <inertial><mass value>",
        ),
        ([link("base", inertial(mass="abc"))], r"link 'base': <mass value>: expected a finite number, got 'abc'"),
        (
            [link("base"), joint("j", "revolute", "base", "nowhere")],
            r"robot\.urdf: joint 'j': child link 'nowhere' is not defined",
        ),
        (
            [link("base"), link("a"), joint("j", "revolute", "nowhere", "a")],
            r"robot\.urdf: joint 'j': parent link 'nowhere' is not defined",
        ),
        (
            BASE + [link("b"), joint("k", "fixed", "b", "a")],
            r"robot\.urdf: joint 'k': link 'a' already has a parent through joint 'j'",
        ),
        (
            [link("a"), link("b"), joint("ab", "fixed", "a", "b"), joint("ba", "fixed", "b", "a")],
            r"robot\.urdf: robot: no root link: .*cycle .*'ab'",
        ),
        (
            BASE + [link("c"), link("d"), joint("cd", "fixed", "c", "d"), joint("dc", "fixed", "d", "c")],
            r"robot\.urdf: robot: the joints .* form a cycle",
        ),
        (BASE + [link("b")], r"robot\.urdf: robot: several root links \('base', 'b'\)"),
        ([], r"robot\.urdf: robot: no <link> elements"),
        (
            [link("base"), link("a"), joint("j", "floating", "base", "a")],
            r"robot\.urdf: joint 'j': floating joints are not supported yet; got joint 'j' of type floating",
        ),
        (
            [link("base"), link("a"), joint("j", "planar", "base", "a")],
            r"joint 'j': planar joints are not supported yet",
        ),
        (
            [link("base"), link("a"), joint("j", "spherical", "base", "a")],
            r"joint 'j': unknown joint type 'spherical'",
        ),
        (
            [link("base"), link("a"), joint("j", "revolute", "base", "a", '<axis xyz="0 0 0"/>')],
            r"joint 'j': <axis xyz>: expected a non-zero vector",
        ),
        (
            [link("base"), link("a"), joint("j", "revolute", "base", "a", '<origin rpy="0 1"/>')],
            r"joint 'j': <origin rpy>: expected three finite numbers, got '0 1'",
        ),
        (
            [link("base"), link("a"), joint("j", "revolute", "base", "a", '<limit lower="0" upper="1"/>')],
            r"joint 'j': <limit> is missing the 'effort' attribute",
        ),
        (
            [link("base"), link("a"), joint("j", "revolute", "base", "a", '<limit effort="1" velocity="1"/><dynamics damping="-1"/>')],
            r"joint 'j': <dynamics damping>: expected a number >= 0",
        ),
        (
            [link("base"), link("base")],
            r"robot\.urdf: link 'base': defined twice",
        ),
        (
            BASE + [link("b"), joint("j", "revolute", "a", "b")],
            r"robot\.urdf: joint 'j': defined twice",
        ),
    ],
)
def test_malformed_urdf_errors(tmp_path, parts, pattern):
    path = write(tmp_path, *parts)
    with pytest.raises(pmd.errors.UrdfError, match=pattern) as info:
        pmd.Model.from_urdf(str(path))
    assert isinstance(info.value, pmd.errors.InvalidInputError)
    assert isinstance(info.value, ValueError)
    assert str(path) in str(info.value)


def test_invalid_inertia_welded_to_the_world_only_warns(tmp_path):
    """A dummy root inertia (ANYmal's base: izz only) does not enter the dynamics."""
    path = write(
        tmp_path,
        link("base", inertial(mass=0.001, diag=(0.0, 0.0, 3e-6))),
        link("a"),
        joint("j", "revolute", "base", "a"),
    )
    with pytest.warns(pmd.errors.UrdfWarning, match=r"robot\.urdf: invalid inertia ignored on links welded to the world.*link 'base': .*triangle"):
        model = pmd.Model.from_urdf(path)
    assert model.nv == 1
    assert model.total_mass == pytest.approx(1.0)


def test_malformed_xml_names_the_line(tmp_path):
    path = tmp_path / "bad.urdf"
    path.write_text('<robot name="r">\n  <link name="a">\n    <inertial>\n  </link>\n</robot>\n')
    with pytest.raises(pmd.errors.UrdfError, match=r"bad\.urdf: malformed XML at line 4"):
        pmd.Model.from_urdf(path)


def test_unreadable_file(tmp_path):
    with pytest.raises(pmd.errors.UrdfError, match="cannot read the URDF file"):
        pmd.Model.from_urdf(tmp_path / "missing.urdf")


# --------------------------------------------------------------------------------------------
# Scenes: `urdf = "..."`, relative to the scene file
# --------------------------------------------------------------------------------------------
def test_scene_with_urdf(tmp_path):
    sub = tmp_path / "robots"
    sub.mkdir()
    chain(sub)
    scene_file = tmp_path / "scene.toml"
    scene_file.write_text(
        'name = "arm"\nurdf = "robots/robot.urdf"\n'
        '[[body]]\nname = "payload"\nparent = "tool"\njoint = { type = "Fixed" }\n'
        "mass = 0.5\ninertia_diag = [1e-3, 1e-3, 1e-3]\n"
        '[[effect]]\ntype = "gravity"\ng = [0, 0, -9.81]\n'
    )
    scene = pmd.load_scene(scene_file)
    model = scene.model
    direct, _ = load(sub / "robot.urdf")
    assert model.nv == 2
    assert model.body_names == direct.body_names + ["payload"]
    assert model.total_mass == pytest.approx(direct.total_mass + 0.5)
    assert np.all(scene.q0 == 0) and np.all(scene.v0 == 0)
    bad = tmp_path / "bad.toml"
    bad.write_text('urdf = "robots/nope.urdf"\n')
    with pytest.raises(pmd.errors.SceneError, match=r"bad\.toml: urdf: .*nope\.urdf: cannot read"):
        pmd.load_scene(bad)


def test_scene_maps_urdf_dynamics_to_effects_and_sets_initial_state(tmp_path):
    """`urdf_dynamics` turns the URDF's <dynamics damping friction> into our effects, and
    `[initial]` sets the whole state; checked against the URDF's own numbers."""
    import shutil

    bundled = Path(pmd.__file__).with_name("scenes") / "panda.urdf"
    shutil.copy(bundled, tmp_path / "panda.urdf")
    q0 = [10, -20, 30, -90, 15, 60, -5]
    (tmp_path / "s.toml").write_text(
        'urdf = "panda.urdf"\nurdf_dynamics = ["damping", "friction"]\nangles = "degrees"\n'
        f"[initial]\nq0 = {q0}\nv0 = [0.1, -0.2, 0.3, 0.4, -0.5, 0.6, 0.7]\n"
    )
    scene = pmd.load_scene(tmp_path / "s.toml")
    model = scene.model
    np.testing.assert_allclose(scene.q0, np.radians(q0), rtol=0, atol=1e-15)
    forces = pmd.effect_forces(scene, 0.0, scene.q0, scene.v0)
    assert "urdf_damping" in forces  # panda.urdf: damping 0.003 on every arm joint
    assert "urdf_friction" not in forces  # all friction values are 0: nothing computed
    dyn = pmd.Model.from_urdf(tmp_path / "panda.urdf").joint_dynamics()
    damping = np.array([dyn[name][0] for name in pmd.Model.from_urdf(tmp_path / "panda.urdf").joint_names])
    np.testing.assert_allclose(forces["urdf_damping"], -damping * scene.v0, rtol=1e-15)
    assert model.nq == 7


def test_scene_urdf_dynamics_errors(tmp_path):
    import shutil

    bundled = Path(pmd.__file__).with_name("scenes") / "panda.urdf"
    shutil.copy(bundled, tmp_path / "panda.urdf")
    bad = tmp_path / "bad.toml"
    bad.write_text('urdf = "panda.urdf"\nurdf_dynamics = ["stiction"]\n')
    with pytest.raises(pmd.SceneError, match=r"bad.toml: urdf_dynamics: .*stiction"):
        pmd.load_scene(bad)
    bad.write_text('urdf = "panda.urdf"\n[initial]\nq0 = [0, 0]\n')
    with pytest.raises(pmd.SceneError, match=r"initial.q0: expected 7 values, got 2"):
        pmd.load_scene(bad)
