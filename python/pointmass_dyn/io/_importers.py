"""Models from other libraries' models (docs/robots.md): :func:`from_mujoco` (a compiled
``mujoco.MjModel``) and :func:`from_pinocchio` (a ``pinocchio.Model``), both optional
dependencies, and :class:`InertiaRepair`, the ``repair=`` option of ``Model.from_urdf``.

Joint order and names are kept; each joint is one of our bodies (a MuJoCo body with several
joints becomes a chain of massless bodies, named ``body/joint`` but the last, which carries
the body's name and inertia)."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._core import Joint, Model
from .._helpers import rotation_of_wxyz
from ..errors import InvalidInputError, ModelImportWarning
from ._mujoco_visuals import geom_visuals, mesh_dirs_of, model_name


@dataclass(frozen=True)
class InertiaRepair:
    """What ``Model.from_urdf(path, repair=...)`` may change (``repair=True``: the defaults).

    Applied to each link's own ``<inertial>`` before fixed joints merge links, in MuJoCo's
    order (``mjCBody::Compile``): ``bound_mass`` (MuJoCo ``boundmass``: mass raised to at
    least this), ``bound_inertia`` (``boundinertia``: principal moments raised to at least
    this; with 0, negative moments become 0), ``balance_inertia`` (``balanceinertia``:
    principal moments violating ``A + B >= C`` all become their mean). Then
    ``weld_massless``: a moving joint whose child link and all links below it have no mass
    moves nothing and is made fixed (MuJoCo instead needs ``bound_mass`` and
    ``bound_inertia`` > 0 for it, which keeps a nearly massless degree of freedom).
    """

    balance_inertia: bool = True
    bound_mass: float = 0.0
    bound_inertia: float = 0.0
    weld_massless: bool = True


# ---------------------------------------------------------------------------------- MuJoCo


def _axis_angle(axis, angle: float) -> np.ndarray:
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def _name(mj, objtype, i: int, fallback: str) -> str:
    import mujoco

    n = mujoco.mj_id2name(mj, objtype, i)
    return n if n else fallback


def from_mujoco(mj_model: Any, *, mesh_dirs=None) -> Model:
    """Our model of a compiled ``mujoco.MjModel``: its bodies (mass, COM, inertia from
    ``body_inertia``/``body_iquat``), hinge, slide, ball and free joints in MuJoCo's order and
    with its names (unnamed: ``jnt<i>``).

    Coordinates: hinge and slide q equal ``qpos`` (a joint ``ref`` is built into the joint
    frame); ball q is ``qpos`` reordered to ``(x, y, z, w)``; a free joint's q is ``(pos,
    quat xyzw)`` and its linear speed is in the body frame where MuJoCo's ``qvel`` has it in
    the world frame (:func:`mujoco_state` converts). Only the mass matrix and bias forces are
    MuJoCo's, plus ``dof_armature`` (rotor inertia, :meth:`Model.set_armature`); passive
    forces, contacts, actuators and equality constraints are not imported (a
    :class:`ModelImportWarning` names those present), but for ``<equality connect>`` and
    ``<equality weld>`` between bodies, which become loops (``Spherical`` and ``Fixed`` cut
    joints, docs/loops.md), and ``<equality joint>`` with a linear ``polycoef``, which
    becomes a coupling (docs/couplings.md). The ``range`` of a limited hinge or slide becomes
    the joint's limit (``Model.joint_limits()``, what ``pmd.JointLimit`` without bounds
    enforces).

    Each ``<site>`` becomes a frame of its name (``model.frame_names``). The geoms of the
    bodies (groups 0-2) become ``model.visuals`` (mesh files looked for as
    MuJoCo recorded them and in ``mesh_dirs``), and the model is named after
    ``<mujoco model>``."""
    try:
        import mujoco
    except ImportError as e:  # pragma: no cover - optional dependency
        raise ImportError(
            "from_mujoco needs the optional dependency mujoco (pip install 'pointmass_dyn[mujoco]')"
        ) from e
    if not isinstance(mj_model, mujoco.MjModel):
        raise InvalidInputError(
            f"mj_model: expected a mujoco.MjModel, got {type(mj_model).__name__}"
        )
    m = mj_model
    J = mujoco.mjtJoint
    parts: list[tuple] = []
    ranges: list[tuple[float, float] | None] = []  # per part, its joint's range
    part_of_joint: dict[int, int] = {}  # MuJoCo joint id -> our body index
    last_of_body = {0: -1}  # MuJoCo body id -> our index of its last part (world: -1)
    anchor_of_body = {0: np.zeros(3)}  # the last part's frame origin in the MuJoCo body frame
    for b in range(1, m.nbody):
        pb = int(m.body_parentid[b])
        parent = last_of_body[pb]
        # The body frame in the parent's last part's frame.
        t_body = np.asarray(m.body_pos[b], float) - anchor_of_body[pb]
        r_body = rotation_of_wxyz(m.body_quat[b])
        bname = _name(m, mujoco.mjtObj.mjOBJ_BODY, b, f"body{b}")
        jids = list(range(int(m.body_jntadr[b]), int(m.body_jntadr[b]) + int(m.body_jntnum[b])))
        mass = float(m.body_mass[b])
        ri = rotation_of_wxyz(m.body_iquat[b])
        inertia = ri @ np.diag(m.body_inertia[b]) @ ri.T
        ipos = np.asarray(m.body_ipos[b], float)
        if not jids:
            parts.append((bname, parent, Joint.fixed(), t_body, r_body, bname, mass, ipos, inertia))
            ranges.append(None)
            last_of_body[b], anchor_of_body[b] = len(parts) - 1, np.zeros(3)
            continue
        prev_anchor = np.zeros(3)
        trans, rot = t_body, r_body
        for k, j in enumerate(jids):
            jname = _name(m, mujoco.mjtObj.mjOBJ_JOINT, j, f"jnt{j}")
            jtype = int(m.jnt_type[j])
            anchor = np.asarray(m.jnt_pos[j], float)
            axis = np.asarray(m.jnt_axis[j], float)
            ref = float(m.qpos0[m.jnt_qposadr[j]])
            if jtype == J.mjJNT_FREE:
                if len(jids) != 1 or pb != 0:
                    raise InvalidInputError(
                        f"mj_model: free joint '{jname}' must be the only joint of a child of the world"
                    )
                joint, anchor = Joint.free_flyer(), np.zeros(3)
                # qpos is the body's world pose: the joint frame is the world frame.
                trans, rot = np.zeros(3), np.eye(3)
            elif jtype == J.mjJNT_BALL:
                joint = Joint.spherical()
            elif jtype == J.mjJNT_HINGE:
                joint = Joint.revolute(axis)
            elif jtype == J.mjJNT_SLIDE:
                joint = Joint.prismatic(axis)
            else:  # pragma: no cover - MuJoCo has no other joint type today
                raise InvalidInputError(f"mj_model: joint '{jname}' has unsupported type {jtype}")
            # This joint's frame: at its anchor, body axes, in the previous frame.
            t = trans + rot @ (anchor - prev_anchor)
            r = rot
            if jtype == J.mjJNT_HINGE and ref != 0.0:
                r = r @ _axis_angle(axis, -ref)  # MuJoCo rotates by qpos - ref
            elif jtype == J.mjJNT_SLIDE and ref != 0.0:
                t = t - r @ (axis / np.linalg.norm(axis)) * ref
            last = k == len(jids) - 1
            name = bname if last else f"{bname}/{jname}"
            body = (mass, ipos - anchor, inertia) if last else (0.0, np.zeros(3), np.zeros((3, 3)))
            parts.append((name, parent, joint, t, r, jname, *body))
            limited = jtype in (J.mjJNT_HINGE, J.mjJNT_SLIDE) and bool(m.jnt_limited[j])
            ranges.append((float(m.jnt_range[j][0]), float(m.jnt_range[j][1])) if limited else None)
            parent = len(parts) - 1
            part_of_joint[j] = parent
            prev_anchor, trans, rot = anchor, np.zeros(3), np.eye(3)
        last_of_body[b], anchor_of_body[b] = parent, prev_anchor
    model = Model._from_parts(parts, ranges)
    visuals, missing = geom_visuals(m, last_of_body, anchor_of_body, mesh_dirs_of(mesh_dirs))
    model.set_visuals(visuals, name=model_name(m))
    ignored = []
    if missing:
        ignored.append(f"{len(missing)} mesh file(s) not found (their bodies are drawn as "
                       f"inertia boxes; pass mesh_dirs=[...]): " + ", ".join(missing[:8]))
    ignored += _mujoco_armature(m, model, part_of_joint)
    ignored += _mujoco_loops(m, model, parts, last_of_body, anchor_of_body, part_of_joint)
    ignored += _mujoco_sites(m, model, last_of_body, anchor_of_body)
    if ignored:
        warnings.warn(
            "from_mujoco: not imported: " + "; ".join(ignored),
            ModelImportWarning,
            stacklevel=2,
        )
    return model


def _mujoco_sites(m, model, last_of_body, anchor_of_body) -> list[str]:
    """Each ``<site>`` on a body as a frame (``Model.add_frame``, docs/kinematics.md) named
    after it (unnamed: ``site<i>``): the body's last part's frame is the MuJoCo body frame
    moved to that part's anchor. Returns what was not imported (sites on the world body, or
    whose name a body already has)."""
    import mujoco

    skipped = []
    taken = set(model.frame_names)
    for s in range(m.nsite):
        name = _name(m, mujoco.mjtObj.mjOBJ_SITE, s, f"site{s}")
        b = int(m.site_bodyid[s])
        if b == 0 or name in taken:
            skipped.append(f"site '{name}' ({'on the world body' if b == 0 else 'name taken'})")
            continue
        pos = np.asarray(m.site_pos[s], float) - anchor_of_body[b]
        model.add_frame(name, last_of_body[b], pos, rotation_of_wxyz(m.site_quat[s]))
        taken.add(name)
    return skipped


def _mujoco_armature(m, model, part_of_joint) -> list[str]:
    """Each joint's ``dof_armature`` as its rotor inertia; returns what was not imported (a
    free joint's: a free body has no rotor)."""
    import mujoco

    arm = np.asarray(m.dof_armature, float)
    skipped = []
    for j, body in part_of_joint.items():
        d = int(m.jnt_dofadr[j])
        nv = {0: 6, 1: 3}.get(int(m.jnt_type[j]), 1)
        values = arm[d : d + nv]
        if not np.any(values != 0):
            continue
        if int(m.jnt_type[j]) == mujoco.mjtJoint.mjJNT_FREE:
            skipped.append(f"dof_armature of free joint '{parts_name(m, j)}'")
            continue
        model.set_armature(body, values)
    return skipped


def parts_name(m, j: int) -> str:
    import mujoco

    return _name(m, mujoco.mjtObj.mjOBJ_JOINT, j, f"jnt{j}")


def _mujoco_joint_coupling(m, model, e: int, name: str, part_of_joint) -> str | None:
    """An active ``<equality joint>`` as a coupling: MuJoCo's ``q1 − q1₀ = Σ cₖ (q2 −
    q2₀)ᵏ`` with ``c2 = c3 = c4 = 0`` is ``q1 = c1 q2 + (q1₀ + c0 − c1 q2₀)`` (``q₀`` =
    ``qpos0``). Returns why it was not imported, or None."""
    j1, j2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
    poly = np.asarray(m.eq_data[e][:5], float)
    if j2 < 0:
        return "joint equality constraint(s) locking one joint"
    if np.any(poly[2:] != 0):
        return "joint equality constraint(s) with a nonlinear polycoef (only c0 + c1 x is a coupling)"
    q10 = float(m.qpos0[m.jnt_qposadr[j1]])
    q20 = float(m.qpos0[m.jnt_qposadr[j2]])
    model.add_coupling(
        part_of_joint[j1],
        part_of_joint[j2],
        ratio=float(poly[1]),
        offset=q10 + float(poly[0]) - float(poly[1]) * q20,
        name=name,
    )
    return None


def _mujoco_loops(m, model, parts, last_of_body, anchor_of_body, part_of_joint) -> list[str]:
    """Active body-to-body ``<equality connect>`` and ``<equality weld>`` as cut joints
    (docs/loops.md): connect → ``Spherical`` between its two anchors, weld → ``Fixed``
    between a frame at MuJoCo's ``relpose`` on body 1 and body 2's anchor; active linear
    ``<equality joint>`` as couplings. Returns what was not imported."""
    import mujoco

    skipped: dict[str, int] = {}
    for e in range(m.neq):
        kind = int(m.eq_type[e])
        name = _name(m, mujoco.mjtObj.mjOBJ_EQUALITY, e, f"equality{e}")
        if kind == mujoco.mjtEq.mjEQ_JOINT and m.eq_active0[e]:
            why = _mujoco_joint_coupling(m, model, e, name, part_of_joint)
            if why is not None:
                skipped[why] = skipped.get(why, 0) + 1
            continue
        spatial = kind in (mujoco.mjtEq.mjEQ_CONNECT, mujoco.mjtEq.mjEQ_WELD)
        by_body = int(m.eq_objtype[e]) == mujoco.mjtObj.mjOBJ_BODY
        if not (spatial and by_body):
            what = mujoco.mjtEq(kind).name.removeprefix("mjEQ_").lower()
            key = f"{what} equality constraint(s)" + (" between sites" if spatial else "")
            skipped[key] = skipped.get(key, 0) + 1
            continue
        if not m.eq_active0[e]:
            skipped["inactive equality constraint(s)"] = (
                skipped.get("inactive equality constraint(s)", 0) + 1
            )
            continue
        b1, b2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
        data = np.asarray(m.eq_data[e], float)
        ours = [None if b == 0 else last_of_body[b] for b in (b1, b2)]
        shift = [anchor_of_body[b1], anchor_of_body[b2]]
        if kind == mujoco.mjtEq.mjEQ_CONNECT:
            joint, rot_a = Joint.spherical(), np.eye(3)
            t_a, t_b = data[0:3] - shift[0], data[3:6] - shift[1]
        else:
            rot_a = rotation_of_wxyz(data[6:10])
            joint = Joint.fixed()
            # MuJoCo's rows: body 2's anchor at body 1's relpos point, and body 2's
            # orientation body 1's times relquat (engine_core_constraint.c).
            t_a = data[3:6] - shift[0]
            t_b = data[0:3] - shift[1]
        model.add_loop(
            -1 if ours[0] is None else ours[0],
            -1 if ours[1] is None else ours[1],
            joint,
            translation_a=t_a,
            translation_b=t_b,
            rotation_a=rot_a,
            rotation_b=np.eye(3),
            name=name,
        )
    return [f"{n} {k}" for k, n in skipped.items()]


def mujoco_state(mj_model: Any, qpos, qvel) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo ``(qpos, qvel)`` as our ``(q, v)`` for :func:`from_mujoco`'s model: quaternions
    ``(w, x, y, z)`` → ``(x, y, z, w)``; a free joint's linear velocity from world to body
    axes."""
    import mujoco

    m = mj_model
    qpos = np.asarray(qpos, float)
    qvel = np.asarray(qvel, float)
    q, v = qpos.copy(), qvel.copy()
    for j in range(m.njnt):
        a, d, t = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j]), int(m.jnt_type[j])
        if t == mujoco.mjtJoint.mjJNT_FREE:
            w = qpos[a + 3 : a + 7]
            q[a + 3 : a + 7] = [w[1], w[2], w[3], w[0]]
            v[d : d + 3] = rotation_of_wxyz(w).T @ qvel[d : d + 3]
        elif t == mujoco.mjtJoint.mjJNT_BALL:
            w = qpos[a : a + 4]
            q[a : a + 4] = [w[1], w[2], w[3], w[0]]
    return q, v


# ------------------------------------------------------------------------------- Pinocchio

_PIN_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


def _pin_joint(jm) -> tuple[Joint, bool]:
    """Our joint for a Pinocchio joint model, and whether its q is (cos, sin)."""
    s = jm.shortname()
    if s in ("JointModelRX", "JointModelRY", "JointModelRZ"):
        return Joint.revolute(_PIN_AXES[s[-1]]), False
    if s in ("JointModelRUBX", "JointModelRUBY", "JointModelRUBZ"):
        return Joint.revolute(_PIN_AXES[s[-1]]), True
    if s == "JointModelRevoluteUnaligned":
        return Joint.revolute(np.asarray(jm.extract().axis)), False
    if s == "JointModelRevoluteUnboundedUnaligned":
        return Joint.revolute(np.asarray(jm.extract().axis)), True
    if s in ("JointModelPX", "JointModelPY", "JointModelPZ"):
        return Joint.prismatic(_PIN_AXES[s[-1]]), False
    if s == "JointModelPrismaticUnaligned":
        return Joint.prismatic(np.asarray(jm.extract().axis)), False
    if s == "JointModelSpherical":
        return Joint.spherical(), False
    if s == "JointModelFreeFlyer":
        return Joint.free_flyer(), False
    raise InvalidInputError(
        f"pin_model: joint type {s} is not supported (supported: RX/RY/RZ, RUBX/RUBY/RUBZ, "
        "RevoluteUnaligned, RevoluteUnboundedUnaligned, PX/PY/PZ, PrismaticUnaligned, "
        "Spherical, FreeFlyer)"
    )


def from_pinocchio(pin_model: Any) -> Model:
    """Our model of a ``pinocchio.Model``: one body per joint (named after the joint's first
    BODY frame at its origin, else the joint), its placement and inertia, joint names and
    order kept, and ``model.armature`` as each joint's rotor inertia. q equals Pinocchio's
    but for unbounded revolute joints (``RUBX``..., q = (cos, sin) there, the angle here:
    :func:`pinocchio_q` converts); v equals Pinocchio's."""
    try:
        import pinocchio as pin
    except ImportError as e:  # pragma: no cover - optional dependency
        raise ImportError(
            "from_pinocchio needs the optional dependency pinocchio (pip install pin)"
        ) from e
    if not isinstance(pin_model, pin.Model):
        raise InvalidInputError(
            f"pin_model: expected a pinocchio.Model, got {type(pin_model).__name__}"
        )
    pm = pin_model
    body_name = {}
    for f in pm.frames:
        if (
            f.type == pin.FrameType.BODY
            and f.parentJoint not in body_name
            and f.placement.isIdentity()
        ):
            body_name[f.parentJoint] = f.name
    parts = []
    for j in range(1, pm.njoints):
        joint, _ = _pin_joint(pm.joints[j])
        pl = pm.jointPlacements[j]
        y = pm.inertias[j]
        parts.append(
            (
                body_name.get(j, pm.names[j]),
                int(pm.parents[j]) - 1,
                joint,
                np.asarray(pl.translation),
                np.asarray(pl.rotation),
                pm.names[j],
                float(y.mass),
                np.asarray(y.lever),
                np.asarray(y.inertia),
            )
        )
    model = Model._from_parts(parts)
    armature = np.asarray(getattr(pm, "armature", np.zeros(pm.nv)), float)
    for j in range(1, pm.njoints):
        jm = pm.joints[j]
        values = armature[jm.idx_v : jm.idx_v + jm.nv]
        if np.any(values != 0):
            model.set_armature(j - 1, values)
    return model


def pinocchio_q(pin_model: Any, q) -> np.ndarray:
    """Our q (angles for unbounded revolute joints) as Pinocchio's (``(cos, sin)`` there)."""
    pm = pin_model
    q = np.asarray(q, float)
    out = np.empty(pm.nq)
    k = 0
    for j in range(1, pm.njoints):
        jm = pm.joints[j]
        _, cs = _pin_joint(jm)
        if cs:
            out[jm.idx_q : jm.idx_q + 2] = [math.cos(q[k]), math.sin(q[k])]
            k += 1
        else:
            out[jm.idx_q : jm.idx_q + jm.nq] = q[k : k + jm.nq]
            k += jm.nq
    return out


# The importers are Model's constructors too, beside the core's Model.from_urdf: attached
# here, so the extension never calls back into Python.
Model.from_mujoco = staticmethod(from_mujoco)  # type: ignore[method-assign]
Model.from_pinocchio = staticmethod(from_pinocchio)  # type: ignore[method-assign]
