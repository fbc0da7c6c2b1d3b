"""Models from MuJoCo and Pinocchio (python/pointmass_dyn/importers.py), and floating-base
URDF loads: mass matrix and bias forces against MuJoCo's own (`mj_fullM`, `qfrc_bias`) and
Pinocchio's (`crba`, `nonLinearEffects`) at random states, to <= 1e-9 relative."""

from __future__ import annotations

import importlib.util
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import record, rel_err, robots_dir
from pointmass_dyn._helpers import rotation_of_wxyz
from pointmass_dyn.io import mujoco_state, pinocchio_q

TOL = 1e-9
mujoco = pytest.importorskip("mujoco")


def mj_compile(xml: str | None = None, path: Path | None = None):
    """MuJoCo's model of `xml` (or the file `path`); its compiler warnings (deprecated
    attributes, URDF mimic joints it makes equalities) are dropped instead of appended to
    MUJOCO_LOG.TXT in the working directory."""
    old = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda _msg: None)
    try:
        if path is not None:
            return mujoco.MjModel.from_xml_path(str(path))
        return mujoco.MjModel.from_xml_string(xml)
    finally:
        mujoco.set_mju_user_warning(old)


def mj_random_state(m, rng):
    qpos = m.qpos0.copy()
    for j in range(m.njnt):
        a, t = int(m.jnt_qposadr[j]), int(m.jnt_type[j])
        if t == mujoco.mjtJoint.mjJNT_FREE:
            qpos[a : a + 3] = rng.normal(size=3)
            w = rng.normal(size=4)
            qpos[a + 3 : a + 7] = w / np.linalg.norm(w)
        elif t == mujoco.mjtJoint.mjJNT_BALL:
            w = rng.normal(size=4)
            qpos[a : a + 4] = w / np.linalg.norm(w)
        else:
            qpos[a] = rng.uniform(-1.0, 1.0)
    return qpos, rng.normal(size=m.nv)


def mj_dynamics(m, qpos, qvel):
    """MuJoCo's mass matrix (armature included: imported as rotor inertia) and bias forces."""
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = qpos, qvel
    mujoco.mj_forward(m, d)
    full = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, full)
    return full, d.qfrc_bias.copy()


def ours_in_mujoco_coordinates(model, m, qpos, qvel, gravity):
    """Our M and bias in MuJoCo's speeds: v_ours = T v_mj (a free joint's linear velocity
    world → body axes), so M_mj = Tᵀ M T and bias_mj = Tᵀ (bias(q, T v) + M Ṫ v)."""
    q, v = mujoco_state(m, qpos, qvel)
    t = np.eye(m.nv)
    tdot_v = np.zeros(m.nv)
    for j in range(m.njnt):
        if int(m.jnt_type[j]) == mujoco.mjtJoint.mjJNT_FREE:
            a, d = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
            r = rotation_of_wxyz(qpos[a + 3 : a + 7])
            t[d : d + 3, d : d + 3] = r.T
            # d/dt (Rᵀ v_w) at fixed v_w = −ω_body × (Rᵀ v_w)
            tdot_v[d : d + 3] = -np.cross(qvel[d + 3 : d + 6], r.T @ qvel[d : d + 3])
    mm = model.mass_matrix(q)
    return t.T @ mm @ t, t.T @ (model.bias_forces(q, v, gravity) + mm @ tdot_v)


def mj_gravity(m):
    off = m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_GRAVITY
    return np.zeros(3) if off else np.asarray(m.opt.gravity, float)


def check_against_mujoco(name, model, m, seeds=(0, 1)):
    for seed in seeds:
        qpos, qvel = mj_random_state(m, np.random.default_rng(seed))
        m_ref, b_ref = mj_dynamics(m, qpos, qvel)
        m_got, b_got = ours_in_mujoco_coordinates(model, m, qpos, qvel, mj_gravity(m))
        e_m, e_b = rel_err(m_got, m_ref), rel_err(b_got, b_ref)
        record(f"mujoco {name}: mass_matrix", e_m)
        record(f"mujoco {name}: bias_forces", e_b)
        assert max(e_m, e_b) <= TOL, (name, seed, e_m, e_b)


# ---------------------------------------------------------------------------- from_mujoco


def mjcf_files():
    out = [Path(mujoco.__file__).parent / "testdata" / "model.xml"]
    spec = importlib.util.find_spec("dm_control")
    if spec is not None and spec.origin:
        suite = Path(spec.origin).parent / "suite"
        out += [
            suite / f"{n}.xml"
            for n in (
                "acrobot",
                "cheetah",
                "finger",
                "fish",
                "humanoid",
                "humanoid_CMU",
                "manipulator",
                "quadruped",
                "stacker",
                "swimmer",
                "walker",
            )
        ]
    return [p for p in out if p.is_file()]


@pytest.mark.parametrize("path", mjcf_files(), ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_from_mujoco_equals_mujoco(path):
    m = mj_compile(path=path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pmd.errors.ModelImportWarning)
        model = pmd.Model.from_mujoco(m)  # the same importer as pmd.from_mujoco
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) or f"jnt{j}" for j in range(m.njnt)]
    assert model.joint_names == names  # order and names kept
    assert model.nv == m.nv and model.nq == m.nq
    check_against_mujoco(path.stem, model, m)


def test_from_mujoco_joint_kinds_ref_and_warning():
    """Hinge and slide with `ref`, off-centre anchors, a ball, several joints in one body, a
    free body, a connect constraint (a loop) and armature (imported: in MuJoCo's mass
    matrix and ours)."""
    xml = """<mujoco><option gravity="0.3 -0.2 -9.81"/>
      <worldbody>
        <body name="a" pos="0.1 0.2 0.3" quat="0.9 0.1 0.3 0.2">
          <joint name="h1" type="hinge" axis="1 2 0" pos="0.05 0 0.1" ref="0.4" armature="0.1"/>
          <joint name="s1" type="slide" axis="0 1 1" pos="0 0.1 0" ref="-0.2"/>
          <geom type="capsule" size="0.05" fromto="0 0 0 0.3 0.1 0"/>
          <body name="b" pos="0.3 0.1 0" euler="10 20 30">
            <joint name="ball" type="ball" pos="0.02 0.01 0"/>
            <geom type="box" size="0.1 0.05 0.02" pos="0.1 0 0"/>
            <body name="c" pos="0.2 0 0">
              <joint name="h2" type="hinge" axis="0 0 1"/>
              <geom type="sphere" size="0.04" pos="0.05 0.02 0"/>
            </body>
          </body>
        </body>
        <body name="free" pos="1 0 1"><freejoint name="root"/>
          <geom type="ellipsoid" size="0.1 0.2 0.3" pos="0.02 0 0"/>
          <body name="arm" pos="0.1 0 0"><joint name="h3" axis="0 1 0"/>
            <geom type="box" size="0.1 0.02 0.02" pos="0.1 0 0"/></body>
        </body>
      </worldbody>
      <equality><connect body1="c" body2="world" anchor="0 0 0"/></equality>
    </mujoco>"""
    m = mj_compile(xml)
    with warnings.catch_warnings():
        warnings.simplefilter("error", pmd.errors.ModelImportWarning)
        model = pmd.from_mujoco(m)
    assert model.nloops == 1
    assert model.armature[0] == 0.1 and not np.any(model.armature[1:])
    assert model.joint_names == ["h1", "s1", "ball", "h2", "root", "h3"]
    assert "a" in model.body_names and "a/h1" in model.body_names
    check_against_mujoco("kinds", model, m, seeds=(0, 1, 2))


LOOPS_XML = """<mujoco><worldbody>
  <body name="a" pos="0 0 1"><joint name="h1" axis="0 1 0" pos="0 0 0.1"/>
    <geom type="box" size=".1 .02 .02" pos=".1 0 0"/>
    <body name="b" pos="0.2 0 0"><joint name="h2" axis="0 1 0" pos="0.05 0 0"/>
      <joint name="h2b" axis="1 0 0" pos="0.02 0.01 0"/>
      <geom type="box" size=".1 .02 .02" pos=".1 0 0"/></body></body>
  <body name="c" pos="0.4 0 1" euler="0 30 0"><joint name="h3" axis="0 1 0" pos="0.01 0 0.02"/>
    <geom type="box" size=".1 .02 .02" pos=".1 0 0"/></body>
  </worldbody>
  <equality><connect body1="b" body2="c" anchor="0.2 0 0"/>
    <weld body1="a" body2="c" anchor="0.1 0.05 0" relpose="0.1 0.2 0.3 0.9 0.1 0.2 0.3"/>
    <weld body1="b" body2="world"/><joint joint1="h1" joint2="h3"/></equality>
</mujoco>"""


def test_from_mujoco_equalities_become_loops():
    """connect → Spherical cut joint, weld → Fixed cut joint: the position rows have the
    norm of MuJoCo's (efc_pos, world axes where ours are in frame a's) and the same Gram
    matrix JᵀJ; the orientation rows vanish where MuJoCo's do; the joint equality becomes
    a coupling (its row last)."""
    m = mj_compile(LOOPS_XML)
    with warnings.catch_warnings():
        warnings.simplefilter("error", pmd.errors.ModelImportWarning)
        model = pmd.from_mujoco(m)
    assert model.nloops == 3 and model.ncouplings == 1 and model.nconstraints == 16
    assert model.couplings == [("equality3", "a", "c", 1.0, 0.0)]
    d = mujoco.MjData(m)
    rows = {"connect": slice(0, 3), "weld a-c": slice(3, 6), "weld b-world": slice(9, 12)}
    for k, qpos in enumerate([m.qpos0.copy(), np.random.default_rng(0).uniform(-1, 1, m.nq)]):
        d.qpos[:] = qpos
        mujoco.mj_forward(m, d)
        q, _ = mujoco_state(m, qpos, np.zeros(m.nv))
        res, jac = model.constraint_residual(q), model.constraint_jacobian(q)
        jac_mj = d.efc_J.reshape(d.nefc, m.nv)
        for what, r in rows.items():
            e = abs(np.linalg.norm(res[r]) - np.linalg.norm(d.efc_pos[r]))
            record(f"mujoco loops: {what} residual norm", e)
            assert e <= 1e-12, (what, res[r], d.efc_pos[r])
            if np.linalg.norm(res[r]) <= 1e-12:
                # At closure the rows differ by a rotation only (frame a vs world axes);
                # apart, ours also carry the rotation of frame a's axes.
                gram, gram_mj = jac[r].T @ jac[r], jac_mj[r].T @ jac_mj[r]
                assert rel_err(gram, gram_mj) <= TOL, what
        if k == 0:  # at qpos0 the welds MuJoCo computed relpose for are closed
            assert np.abs(res[12:15]).max() <= 1e-12 and np.abs(d.efc_pos[12:15]).max() <= 1e-12


def test_from_mujoco_refuses_other_objects():
    with pytest.raises(pmd.errors.InvalidInputError, match="mj_model: expected a mujoco.MjModel"):
        pmd.from_mujoco("model.xml")


# ------------------------------------------------------------------------- from_pinocchio

pin = pytest.importorskip("pinocchio")


def pin_reference(pm, qp, v):
    d = pm.createData()
    full = pin.crba(pm, d, qp)
    full = np.triu(full) + np.triu(full, 1).T
    return full, pin.nonLinearEffects(pm, d, qp, v).copy()


def our_q_from_pin(pm, qp):
    out = []
    for j in range(1, pm.njoints):
        jm = pm.joints[j]
        if jm.shortname().startswith("JointModelRUB"):
            out.append(math.atan2(qp[jm.idx_q + 1], qp[jm.idx_q]))
        else:
            out.extend(qp[jm.idx_q : jm.idx_q + jm.nq])
    return np.array(out)


def check_against_pinocchio(name, model, pm, seeds=(0, 1)):
    for seed in seeds:
        np.random.seed(seed)  # pin.randomConfiguration draws from NumPy's global state
        rng = np.random.default_rng(seed)
        lo, hi = -np.ones(pm.nq), np.ones(pm.nq)
        qp = pin.randomConfiguration(pm, lo, hi)
        q = our_q_from_pin(pm, qp)
        assert np.allclose(pinocchio_q(pm, q), qp, atol=1e-15)
        v = rng.normal(size=pm.nv)
        m_ref, b_ref = pin_reference(pm, qp, v)
        e_m = rel_err(model.mass_matrix(q), m_ref)
        e_b = rel_err(model.bias_forces(q, v, pm.gravity.linear), b_ref)
        record(f"pinocchio {name}: mass_matrix", e_m)
        record(f"pinocchio {name}: bias_forces", e_b)
        assert max(e_m, e_b) <= TOL, (name, seed, e_m, e_b)


def custom_pin_model():
    pm = pin.Model()
    parent = 0
    joints = [
        pin.JointModelFreeFlyer(),
        pin.JointModelSpherical(),
        pin.JointModelRevoluteUnaligned(np.array([1.0, 2.0, 3.0]) / math.sqrt(14.0)),
        pin.JointModelPrismaticUnaligned(np.array([0.0, 1.0, 1.0]) / math.sqrt(2.0)),
        pin.JointModelRUBY(),
        pin.JointModelPX(),
        pin.JointModelRZ(),
    ]
    rng = np.random.default_rng(3)
    for k, jm in enumerate(joints):
        placement = pin.SE3(pin.rpy.rpyToMatrix(*rng.uniform(-1, 1, 3)), rng.uniform(-0.3, 0.3, 3))
        parent = pm.addJoint(parent, jm, placement, f"j{k}")
        y = pin.Inertia.FromBox(1.0 + k, 0.1, 0.2, 0.3 + 0.1 * k)
        y.lever = np.array([0.05, -0.02, 0.1])
        pm.appendBodyToJoint(parent, y, pin.SE3.Identity())
    return pm


def pin_models():
    out = {"manipulator": pin.buildSampleModelManipulator(), "custom": custom_pin_model()}
    root = robots_dir()
    if root is not None:
        out["kinova"] = pin.buildModelFromUrdf(str(root / "kinova_description/robots/kinova.urdf"))
        out["talos_free"] = pin.buildModelFromUrdf(
            str(root / "talos_data/robots/talos_reduced.urdf"), pin.JointModelFreeFlyer()
        )
    return out


PIN_MODELS = pin_models()


@pytest.mark.parametrize("name", sorted(PIN_MODELS))
def test_from_pinocchio_equals_pinocchio(name):
    pm = PIN_MODELS[name]
    model = pmd.Model.from_pinocchio(pm)  # the same importer as pmd.from_pinocchio
    assert model.joint_names == list(pm.names)[1:]
    check_against_pinocchio(name, model, pm)


def test_from_pinocchio_refuses_unsupported_joints():
    pm = pin.Model()
    pm.addJoint(0, pin.JointModelPlanar(), pin.SE3.Identity(), "p")
    with pytest.raises(pmd.errors.InvalidInputError, match="JointModelPlanar is not supported"):
        pmd.from_pinocchio(pm)
    with pytest.raises(pmd.errors.InvalidInputError, match="pin_model"):
        pmd.from_pinocchio(None)
    with pytest.raises(pmd.errors.InvalidInputError, match="pin_model"):
        pmd.Model.from_pinocchio(None)


# -------------------------------------------------------------- floating-base URDF loads


def mujoco_urdf(text: str, compiler: str = "", free: bool = False) -> str:
    """The URDF for MuJoCo: no geometry (meshes are not shipped with the dynamics), a
    <mujoco><compiler/> element, and for a floating base a `floating` joint from a `world`
    link (MuJoCo's URDF reader makes it a free joint)."""
    text = re.sub(r"<(visual|collision)\b.*?</\1\s*>", "", text, flags=re.S)
    text = re.sub(r"<(visual|collision)\b[^>]*/>", "", text)
    extra = f"<mujoco><compiler {compiler}/></mujoco>"
    if free:
        root = root_link(text)
        extra += (
            '<link name="world"/><joint name="root_joint" type="floating">'
            f'<parent link="world"/><child link="{root}"/></joint>'
        )
    return re.sub(r"(<robot\b[^>]*>)", lambda mt: mt.group(1) + extra, text, count=1)


def root_link(text: str) -> str:
    links = re.findall(r'<link\s+name="([^"]+)"', text)
    children = set(re.findall(r'<child\s+link="([^"]+)"', text))
    (root,) = [name for name in links if name not in children]
    return root


FLOATING = {
    "solo12": "solo_description/robots/solo12.urdf",
    "a1": "a1_description/urdf/a1.urdf",
    "talos": "talos_data/robots/talos_reduced.urdf",
}


@pytest.mark.parametrize("name", sorted(FLOATING))
def test_free_root_equals_mujoco_free_joint_and_pinocchio_free_flyer(name):
    root = robots_dir()
    if root is None:
        pytest.skip("example-robot-data not installed")
    path = root / FLOATING[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pmd.errors.UrdfWarning)
        model = pmd.Model.from_urdf(path, root_joint="free")
    pm = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    pm.gravity.linear = np.array([0.0, 0.0, -9.81])
    check_against_pinocchio(f"{name} free", model, pm)
    m = mj_compile(mujoco_urdf(path.read_text(), free=True))
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(m.njnt)]
    # MuJoCo orders the joints its own way: compare through a permutation by name.
    check_free_against_mujoco(name, model, m, names)


def check_free_against_mujoco(name, model, m, names):
    slices = dict(zip(model.joint_names, model.joint_slices()))
    perm_q, perm_v = [], []
    for n in names:
        q0, v0, nq, nv = slices[n]
        perm_q += list(range(q0, q0 + nq))
        perm_v += list(range(v0, v0 + nv))
    assert names[0] == "root_joint" and int(m.jnt_type[0]) == mujoco.mjtJoint.mjJNT_FREE
    pq, pv = np.array(perm_q, dtype=int), np.array(perm_v, dtype=int)
    for seed in (0, 1):
        qpos, qvel = mj_random_state(m, np.random.default_rng(seed))
        m_ref, b_ref = mj_dynamics(m, qpos, qvel)
        q_mj, v_mj = mujoco_state(m, qpos, qvel)
        q = np.empty(model.nq)
        v = np.empty(model.nv)
        q[pq], v[pv] = q_mj, v_mj
        t = np.eye(m.nv)
        r = rotation_of_wxyz(qpos[3:7])
        t[:3, :3] = r.T
        tdot_v = np.zeros(m.nv)
        tdot_v[:3] = -np.cross(qvel[3:6], r.T @ qvel[:3])
        mm = model.mass_matrix(q)[np.ix_(pv, pv)]
        b = model.bias_forces(q, v, mj_gravity(m))[pv]
        e_m = rel_err(t.T @ mm @ t, m_ref)
        e_b = rel_err(t.T @ (b + mm @ tdot_v), b_ref)
        record(f"mujoco {name} free: mass_matrix", e_m)
        record(f"mujoco {name} free: bias_forces", e_b)
        assert max(e_m, e_b) <= TOL, (name, seed, e_m, e_b)
