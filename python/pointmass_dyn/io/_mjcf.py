"""Our models and scenes as MuJoCo MJCF, and states between the two coordinate conventions.

    xml = pmd.to_mjcf(scene, timestep=1e-3, integrator="RK4")
    m = mujoco.MjModel.from_xml_string(xml)          # optional peer: pip install 'pointmass-dyn[mujoco]'
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = pmd.io.to_mujoco_state(scene.model, q, v)
    mujoco.mj_forward(m, d)
    d.qacc == pmd.io.to_mujoco_acceleration(scene.model, q, v, a)   # a: our forward dynamics

Writing the MJCF needs no MuJoCo; only loading it does. The conversion, joint by joint:

============== ============================ =========================================
ours           MJCF                          state (ours → MuJoCo)
============== ============================ =========================================
Revolute       ``hinge``, same axis          same q, v
Prismatic      ``slide``, same axis          same q, v
Spherical      ``ball``                      quaternion (x, y, z, w) → (w, x, y, z); v same
                                             (angular velocity in the body frame)
SphericalZYZ   ``ball``                      q → the quaternion of Rz(φ) Ry(θ) Rz(ψ);
                                             Euler rates → body angular velocity Rᵀ L q̇
FreeFlyer      ``free`` (below the world     position and orientation in the world;
               only)                         linear velocity in world axes (ours: body
                                             axes), angular in body axes (same)
Fixed          a body without a joint        —
============== ============================ =========================================

MuJoCo refuses massless moving bodies, so a ZYZ joint becomes one ball joint (not three
hinges with massless bodies between them) and the state conversion carries the Euler rates.
Bodies keep their placements (``pos``/``quat`` from the model's joint frames), mass, COM and
full inertia tensor (``fullinertia``, same sign convention). MuJoCo orders joints by a
depth-first walk of the tree; the helpers here permute accordingly.

Scene effects: gravity (summed), joint springs on revolute/prismatic joints (``stiffness``,
``springref``) and on quaternion joints resting at the identity (MuJoCo's ball spring), and
dampers (``damping``) on every joint but ZYZ ones (ours damp Euler rates, MuJoCo the angular
velocity), read back by probing :func:`pointmass_dyn.effect_forces`; rotor inertia as
``armature``. PD, constant and tabulated torques as actuators (their limits as
``forcerange``), joint limits as limited ranges and ground contact as a plane with spheres:
``_mjcf_effects.py``, which says how the soft laws are matched. Other effects (friction,
external forces, point springs, torque functions), loops, couplings and FreeFlyer joints
below a moving body are refused (``InvalidInputError``). Without ground contact, contact is
disabled.

Accuracy: MuJoCo's ``mj_forward`` ``qacc`` equals our forward dynamics (with the scene's
springs and dampers) to ~1e-14 relative on chain7, Panda and random trees of every joint
type, 3e-12 on the paper's slender rod (``tests/test_mjcf.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _core
from .._helpers import rotation_of_wxyz, scene_gravity
from ..errors import InvalidInputError, ModelStructureError
from ._mjcf_effects import mjcf_effects
from ._mjcf_rotations import (
    axis_of,
    qmul,
    quat_wxyz_of,
    zyz_of_rot,
    zyz_quat,
    zyz_rate,
    zyz_rate_dot,
)

#: MuJoCo's integrators, as ``<option integrator=...>`` names them.
MUJOCO_INTEGRATORS = ("Euler", "RK4", "implicit", "implicitfast")

_MOVING = ("Revolute", "Prismatic", "Spherical", "SphericalZYZ", "FreeFlyer")


@dataclass(frozen=True)
class _Joint:
    body: int
    kind: str
    q: int          # our q index
    v: int          # our v index
    qpos: int       # MuJoCo qpos address
    dof: int        # MuJoCo dof address
    rot0: np.ndarray  # joint frame in the parent's frame (for FreeFlyer: in the world)
    pos0: np.ndarray


@dataclass(frozen=True)
class MujocoLayout:
    """Where each of our joints lives in MuJoCo's ``qpos``/``qvel``; see :func:`layout`."""

    nq: int
    nv: int
    joints: tuple[_Joint, ...]
    #: bodies in the order the MJCF lists them (depth first, children by our index)
    order: tuple[int, ...]


# ----------------------------------------------------------------------------- structure


def _model_of(model_or_scene: Any) -> tuple[Any, Any]:
    if isinstance(model_or_scene, _core.Scene):
        return model_or_scene.model, model_or_scene
    if isinstance(model_or_scene, _core.Model):
        return model_or_scene, None
    raise InvalidInputError(
        f"model_or_scene: expected a pointmass_dyn Model or Scene, got "
        f"{type(model_or_scene).__name__}")


def _tree(model) -> tuple[list[tuple[str, str, int, int]], list[list[int]], list[int]]:
    """Body infos, children lists and the depth-first order the MJCF writes the bodies in."""
    if model.nloops or model.ncouplings:
        raise ModelStructureError(
            f"model: MJCF export handles kinematic trees; this model has {model.nloops} loop(s) "
            f"({', '.join(model.loop_names)}) and {model.ncouplings} coupling(s): not supported")
    infos = [model.body_info(i) for i in range(model.nbodies)]
    children: list[list[int]] = [[] for _ in infos]
    roots = []
    for i, (_, _, parent, _) in enumerate(infos):
        (roots if parent < 0 else children[parent]).append(i)
    order: list[int] = []
    stack = list(reversed(roots))
    while stack:
        i = stack.pop()
        order.append(i)
        stack.extend(reversed(children[i]))
    return infos, children, order


def layout(model) -> MujocoLayout:
    """Addresses of our joints in the qpos/qvel of :func:`to_mjcf`'s MuJoCo model (MuJoCo
    orders joints depth first through the tree), with each joint frame's placement."""
    model, _ = _model_of(model)
    infos, _, order = _tree(model)
    rots, origins = model.placements(model.neutral())
    slices = model.joint_slices()
    joints = []
    qpos = dof = 0
    for b in order:
        _, kind, parent, link = infos[b]
        if kind == "Fixed":
            continue
        if kind not in _MOVING:
            raise ModelStructureError(f"model: body {infos[b][0]!r} has a joint of kind {kind!r}, "
                                      f"which the MJCF export does not know")
        rp, op = (np.eye(3), np.zeros(3)) if parent < 0 else (rots[parent], origins[parent])
        qi, vi, _, _ = slices[link]
        joints.append(_Joint(b, kind, qi, vi, qpos, dof, rp.T @ rots[b], rp.T @ (origins[b] - op)))
        nq, nv = {"Revolute": (1, 1), "Prismatic": (1, 1), "Spherical": (4, 3),
                  "SphericalZYZ": (4, 3), "FreeFlyer": (7, 6)}[kind]
        qpos += nq
        dof += nv
    return MujocoLayout(nq=qpos, nv=dof, joints=tuple(joints), order=tuple(order))


def _fmt(v) -> str:
    return " ".join(repr(float(x)) for x in np.ravel(v))


def probe_effects(scene, model, lay: MujocoLayout):
    """Gravity, per-dof spring stiffness/rest and damping of the scene's enabled effects,
    read back through ``effect_forces`` and checked to be laws MuJoCo has."""
    disabled = set(scene.disable or ())
    g = scene_gravity(scene)
    gravity = np.zeros(3) if g is None else g
    springs, dampers = [], []
    for e in scene.effects:
        if e.kind in disabled:
            continue
        r = repr(e)
        if r.startswith("Gravity(") or e.kind in ("torques", "contact", "limits"):
            continue  # torques, contact and limits: _mjcf_effects.py
        elif r.startswith("Spring("):
            springs.append(e)
        elif r.startswith("Damper("):
            dampers.append(e)
        else:
            raise InvalidInputError(
                f"scene: effect {r} ({e.name!r}) has no MuJoCo counterpart in the MJCF export "
                f"(supported: Gravity, Spring, Damper, PD/constant/tabulated torques, "
                f"GroundContact, JointLimit); leave it out or disable its family "
                f"({e.kind!r}) to convert the rest")
    nv = model.nv
    stiff, rest, damp = np.zeros(nv), np.zeros(nv), np.zeros(nv)

    def forces(effects, q, v):
        sub = _core.Scene(model, effects=effects)
        out = _core.effect_forces(sub, 0.0, np.asarray(q, float), np.asarray(v, float), None)
        return np.sum(list(out.values()), axis=0) if out else np.zeros(nv)

    def bad(what, j, detail):
        name = model.body_info(j.body)[0]
        return InvalidInputError(
            f"scene: the {what} on {j.kind} joint {name!r} has no MuJoCo counterpart ({detail})")

    if springs:
        qn = model.neutral()
        q1, q2 = qn.copy(), qn.copy()
        for j in lay.joints:
            if j.kind in ("Revolute", "Prismatic"):
                q1[j.q], q2[j.q] = 1.0, -0.7
            elif j.kind == "Spherical":    # 0.5 rad about x, then about y
                q1[j.q:j.q + 4] = [math.sin(0.25), 0, 0, math.cos(0.25)]
                q2[j.q:j.q + 4] = [0, math.sin(0.25), 0, math.cos(0.25)]
        zero = np.zeros(nv)
        t0, t1, t2 = (forces(springs, q, zero) for q in (qn, q1, q2))
        scale = 1e-9 * (1.0 + np.max(np.abs([t0, t1, t2])))
        for j in lay.joints:
            if j.kind in ("Revolute", "Prismatic"):
                k = t0[j.v] - t1[j.v]
                r0 = t0[j.v] / k if k != 0 else 0.0
                if abs(t2[j.v] + k * (-0.7 - r0)) > scale:
                    raise bad("spring", j, "its force is not linear in q")
                stiff[j.v], rest[j.v] = k, r0
            elif j.kind == "Spherical":
                k = -t1[j.v] / 0.5
                want1 = np.array([-0.5 * k, 0, 0])
                want2 = np.array([0, -0.5 * k, 0])
                if np.max(np.abs(t0[j.v:j.v + 3])) > scale:
                    raise bad("spring", j, "MuJoCo's ball spring rests at the identity; this "
                                           "one rests elsewhere")
                if (np.max(np.abs(t1[j.v:j.v + 3] - want1)) > scale
                        or np.max(np.abs(t2[j.v:j.v + 3] - want2)) > scale):
                    raise bad("spring", j, "not an isotropic rotation-vector spring")
                stiff[j.v:j.v + 3] = k
            elif np.max(np.abs(np.r_[t0, t1, t2][[j.v, nv + j.v, 2 * nv + j.v]])) > scale:
                raise bad("spring", j, "not supported on this joint")
    if dampers:
        rng = np.random.default_rng(0)
        q = model.neutral()
        ones, vr = np.ones(nv), rng.uniform(-1, 1, nv)
        c = -forces(dampers, q, ones)
        tr = forces(dampers, q, vr)
        if np.max(np.abs(tr + c * vr)) > 1e-9 * (1 + np.max(np.abs(c))):
            raise InvalidInputError("scene: a damper whose force is not -c v per speed has no "
                                    "MuJoCo counterpart")
        for j in lay.joints:
            cj = c[j.v:j.v + (6 if j.kind == "FreeFlyer" else 3 if "Spher" in j.kind else 1)]
            if j.kind == "SphericalZYZ" and np.any(cj != 0):
                raise bad("damper", j, "ours damps the Euler rates, MuJoCo's ball joint the "
                                       "angular velocity; use the quaternion joint Spherical")
            if np.ptp(cj) > 1e-12 * (1 + np.max(np.abs(cj))):
                raise bad("damper", j, "MuJoCo damps all speeds of a joint alike")
        damp = c
    return gravity, stiff, rest, damp


def to_mjcf(
    model_or_scene: Any,
    *,
    timestep: float = 0.002,
    integrator: str = "RK4",
    gravity: Any = None,
    name: str | None = None,
) -> str:
    """MJCF text of a :class:`Model` or :class:`Scene` (see the module docstring for the
    mapping). ``timestep`` and ``integrator`` (``"Euler"``, ``"RK4"``, ``"implicit"``,
    ``"implicitfast"``) go into ``<option>``; ``gravity`` (3,) only for a bare model (a
    scene's comes from its effects). Joints carry ``model.joint_names`` and 1-dof joints
    their ranges (``limited="false"``: not enforced); bodies carry the model's names."""
    model, scene = _model_of(model_or_scene)
    if integrator not in MUJOCO_INTEGRATORS:
        raise InvalidInputError(f"integrator: expected one of {MUJOCO_INTEGRATORS}, got "
                                f"{integrator!r}")
    if isinstance(timestep, (bool, str)) or not (float(timestep) > 0
                                                 and math.isfinite(float(timestep))):
        raise InvalidInputError(f"timestep: expected a finite number > 0, got {timestep!r}")
    lay = layout(model)
    infos, children, _ = _tree(model)
    nv = model.nv
    if scene is not None:
        if gravity is not None:
            raise InvalidInputError("gravity: give it only with a Model; a Scene's gravity is "
                                    "its Gravity effect")
        g, stiff, rest, damp = probe_effects(scene, model, lay)
        extra = mjcf_effects(scene)
        name = name or scene.name
    else:
        g = np.zeros(3) if gravity is None else np.asarray(gravity, dtype=float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise InvalidInputError(f"gravity: expected 3 finite numbers, got {gravity!r}")
        stiff, rest, damp = np.zeros(nv), np.zeros(nv), np.zeros(nv)
        extra = mjcf_effects(None)
    by_body = {j.body: j for j in lay.joints}
    rots, origins = model.placements(model.neutral())

    # Joint axes, read back from the placements with every 1-dof joint at q = π/2.
    q_turn = model.neutral()
    for j in lay.joints:
        if j.kind in ("Revolute", "Prismatic"):
            q_turn[j.q] = math.pi / 2
    rt, ot = model.placements(q_turn)

    for j in lay.joints:
        if j.kind == "FreeFlyer" and infos[j.body][2] >= 0:
            raise ModelStructureError(
                f"model: the FreeFlyer joint of body {infos[j.body][0]!r} is below body "
                f"{infos[infos[j.body][2]][0]!r}; MuJoCo allows free joints only on bodies of "
                f"the world")

    # Here, not at module level: xml.sax pulls in urllib, http and email (~20 ms of import).
    from xml.sax.saxutils import quoteattr

    xml = [f"<mujoco model={quoteattr(name or 'pointmass_dyn')}>",
           '  <compiler angle="radian" autolimits="true"/>',
           f'  <option gravity="{_fmt(g)}" integrator="{integrator}" '
           f'timestep="{float(timestep)!r}">',
           *([] if extra.contact else ['    <flag contact="disable"/>']),
           "  </option>",
           "  <worldbody>",
           *(f"    {g}" for g in extra.world_geoms)]

    joint_names, limits = model.joint_names, model.joint_limits()
    def joint_xml(b: int, frame: int) -> str:
        """Body b's joint, axis and anchor in the neutral frame of body ``frame``."""
        bname, kind, parent, link = infos[b]
        jname = joint_names[link]
        j, rf = by_body[b], rots[frame]
        attrs = "" if frame == b else f' pos="{_fmt(rf.T @ (origins[b] - origins[frame]))}"'
        if kind in ("Revolute", "Prismatic"):
            rp, op = (np.eye(3), np.zeros(3)) if parent < 0 else (rots[parent], origins[parent])
            rpt = np.eye(3) if parent < 0 else rt[parent]
            opt = np.zeros(3) if parent < 0 else ot[parent]
            r0, p0 = rp.T @ rots[b], rp.T @ (origins[b] - op)
            if kind == "Revolute":
                axis = axis_of(r0.T @ (rpt.T @ rt[b]), math.pi / 2)
            else:
                axis = r0.T @ (rpt.T @ (ot[b] - opt) - p0) / (math.pi / 2)
                axis = axis / np.linalg.norm(axis)
            axis = rf.T @ rots[b] @ axis
            mj = "hinge" if kind == "Revolute" else "slide"
            attrs += f' type="{mj}" axis="{_fmt(axis)}"'
            lo, up = limits[jname][:2]  # enforced only by a JointLimit effect (extra)
            if link in extra.joint_attrs:
                attrs += extra.joint_attrs[link]
            elif abs(lo) + abs(up) < math.inf:
                attrs += f' range="{lo!r} {up!r}" limited="false"'
            if stiff[j.v]:
                attrs += f' stiffness="{float(stiff[j.v])!r}" springref="{float(rest[j.v])!r}"'
        elif kind in ("Spherical", "SphericalZYZ"):
            attrs += ' type="ball"'
            if stiff[j.v]:
                attrs += f' stiffness="{float(stiff[j.v])!r}"'
        else:
            attrs += ' type="free"'
        if damp[j.v]:
            attrs += f' damping="{float(damp[j.v])!r}"'
        arm = model.armature[j.v : j.v + (3 if kind.startswith("Spherical") else 1)]
        if np.any(arm != arm[0]):  # MuJoCo has one value per joint
            raise ModelStructureError(f"model: body {bname!r}: armature {arm} differs by axis")
        attrs += f' armature="{float(arm[0])!r}"' if arm[0] else ""
        return f"<joint name={quoteattr(jname)}{attrs}/>"

    def carried_into(b: int) -> int | None:
        """The body a massless moving body's joint goes into, or None. MuJoCo refuses moving
        bodies without mass, but takes several joints in one body: a massless body with one
        child (what ``from_mujoco`` makes of a multi-joint body) lends its joint to the
        child's MJCF body. A ball joint only where the two share axes (it turns the body's
        own axes)."""
        kind, c = infos[b][1], children[b][0] if len(children[b]) == 1 else None
        if (b not in by_body or kind == "FreeFlyer" or float(model.body(b).mass) > 0
                or c is None or infos[c][1] == "FreeFlyer"):
            return None
        if kind in ("Spherical", "SphericalZYZ") and not np.allclose(
                rots[b].T @ rots[c], np.eye(3), rtol=0, atol=1e-12):
            return None
        return c

    def write(b: int, depth: int, carried: list[int]) -> None:
        into = carried_into(b)
        if into is not None:
            return write(into, depth, carried + [b])
        pad, bname, parent = "  " * depth, infos[b][0], infos[(carried or [b])[0]][2]
        rp, op = (np.eye(3), np.zeros(3)) if parent < 0 else (rots[parent], origins[parent])
        r0 = rp.T @ rots[b]
        p0 = rp.T @ (origins[b] - op)
        xml.append(f"{pad}<body name={quoteattr(bname)} pos=\"{_fmt(p0)}\" "
                   f"quat=\"{_fmt(quat_wxyz_of(r0))}\">")
        for k in carried + ([b] if b in by_body else []):
            xml.append(f"{pad}  {joint_xml(k, b)}")
        body = model.body(b)
        mass = float(body.mass)
        inertia = np.asarray(body.inertia)
        if mass > 0:
            if np.count_nonzero(inertia - np.diag(np.diag(inertia))) == 0:
                iner = f'diaginertia="{_fmt(np.diag(inertia))}"'
            else:
                iner = (f'fullinertia="{_fmt([inertia[0, 0], inertia[1, 1], inertia[2, 2]])} '
                        f'{_fmt([inertia[0, 1], inertia[0, 2], inertia[1, 2]])}"')
            xml.append(f"{pad}  <inertial mass=\"{mass!r}\" pos=\"{_fmt(body.com)}\" {iner}/>")
        elif b in by_body or carried:
            raise ModelStructureError(
                f"model: body {bname!r} moves but has no mass; MuJoCo refuses massless moving "
                f"bodies (give it a mass, or fix it to a body that has one)")
        for geom in extra.body_geoms.get(b, ()):
            xml.append(f"{pad}  {geom}")
        for c in children[b]:
            write(c, depth + 1, [])
        xml.append(f"{pad}</body>")

    for b in range(model.nbodies):
        if infos[b][2] < 0:
            write(b, 2, [])
    xml.append("  </worldbody>")
    if extra.actuators:
        xml += ["  <actuator>", *(f"    {a}" for a in extra.actuators), "  </actuator>"]
    if scene is not None:  # the start state (and controls): mj_resetDataKeyframe(m, d, 0)
        qpos, qvel = to_mujoco_state(model, scene.q0, scene.v0)
        ctrl = f' ctrl="{_fmt(extra.ctrl0)}"' if extra.actuators else ""
        xml += ["  <keyframe>",
                f'    <key name="scene" qpos="{_fmt(qpos)}" qvel="{_fmt(qvel)}"{ctrl}/>',
                "  </keyframe>"]
    xml.append("</mujoco>")
    return "\n".join(xml) + "\n"


# ----------------------------------------------------------------------------- states


def _states(model, q, v, what=("q", "v")):
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    if q.shape[-1:] != (model.nq,) or v.shape[-1:] != (model.nv,) or q.shape[:-1] != v.shape[:-1]:
        raise InvalidInputError(
            f"{what[0]}, {what[1]}: expected shapes (..., {model.nq}) and (..., {model.nv}) "
            f"with the same leading shape, got {q.shape} and {v.shape}")
    return q, v


#: Models (frozen, so a layout stays true) and their layouts and 1-dof index maps, most
#: recent last: a state conversion per control step reads them instead of rebuilding them.
_MAPS: dict[int, tuple[Any, MujocoLayout, tuple, list]] = {}


def _state_map(model) -> tuple[MujocoLayout, tuple, list]:
    """``model``'s layout, the index arrays ``(q, v, qpos, dof)`` of its revolute and
    prismatic joints (one copy each way), and its other joints."""
    hit = _MAPS.get(id(model))
    if hit is not None and hit[0] is model:
        return hit[1:]
    lay = layout(model)
    one = [j for j in lay.joints if j.kind in ("Revolute", "Prismatic")]
    index = tuple(np.array([getattr(j, k) for j in one], dtype=np.intp)
                  for k in ("q", "v", "qpos", "dof"))
    others = [j for j in lay.joints if j.kind not in ("Revolute", "Prismatic")]
    if len(_MAPS) >= 32:  # a few models at a time: drop the oldest
        del _MAPS[next(iter(_MAPS))]
    _MAPS[id(model)] = (model, lay, index, others)  # the model kept: its id stays its own
    return lay, index, others


def to_mujoco_state(model, q, v) -> tuple[np.ndarray, np.ndarray]:
    """(qpos, qvel) of :func:`to_mjcf`'s model for our (q, v); one state (nq,), (nv,) or many
    (N, nq), (N, nv)."""
    model, _ = _model_of(model)
    lay, (qi, vi, pi, di), others = _state_map(model)
    q, v = _states(model, q, v)
    lead = q.shape[:-1]
    qpos, qvel = np.empty(lead + (lay.nq,)), np.empty(lead + (lay.nv,))
    qpos[..., pi], qvel[..., di] = q[..., qi], v[..., vi]
    for j in others:
        a, b, p, d = j.q, j.v, j.qpos, j.dof
        if j.kind == "Spherical":
            qpos[..., p:p + 4] = q[..., [a + 3, a, a + 1, a + 2]]
            qvel[..., d:d + 3] = v[..., b:b + 3]
        elif j.kind == "SphericalZYZ":
            e, ed = q[..., a:a + 3], v[..., b:b + 3]
            qpos[..., p:p + 4] = zyz_quat(e)
            w_joint = np.einsum("...ij,...j->...i", zyz_rate(e), ed)
            qvel[..., d:d + 3] = np.einsum("...ji,...j->...i", rotation_of_wxyz(zyz_quat(e)),
                                           w_joint)
        else:  # FreeFlyer below the world
            quat = qmul(quat_wxyz_of(j.rot0), q[..., [a + 6, a + 3, a + 4, a + 5]])
            qpos[..., p:p + 3] = j.pos0 + q[..., a:a + 3] @ j.rot0.T
            qpos[..., p + 3:p + 7] = quat
            qvel[..., d:d + 3] = np.einsum("...ij,...j->...i", rotation_of_wxyz(quat),
                                           v[..., b:b + 3])
            qvel[..., d + 3:d + 6] = v[..., b + 3:b + 6]
    return qpos, qvel


def from_mujoco_state(model, qpos, qvel, q_like=None) -> tuple[np.ndarray, np.ndarray]:
    """Our (q, v) from MuJoCo's (qpos, qvel), the inverse of :func:`to_mujoco_state`. A
    rotation has two quaternions and (ZYZ) two Euler branches and 2π-shifts: ``q_like``
    (same shape as q, e.g. a reference trajectory) picks the nearest; by default quaternions
    keep MuJoCo's sign and Euler angles take θ ∈ [0, π], φ, ψ ∈ (−π, π]."""
    model, _ = _model_of(model)
    lay, (qi, vi, pi, di), others = _state_map(model)
    qpos = np.asarray(qpos, dtype=float)
    qvel = np.asarray(qvel, dtype=float)
    if (qpos.shape[-1:] != (lay.nq,) or qvel.shape[-1:] != (lay.nv,)
            or qpos.shape[:-1] != qvel.shape[:-1]):
        raise InvalidInputError(
            f"qpos, qvel: expected shapes (..., {lay.nq}) and (..., {lay.nv}), got "
            f"{qpos.shape} and {qvel.shape}")
    lead = qpos.shape[:-1]
    like = None if q_like is None else np.broadcast_to(np.asarray(q_like, float),
                                                       lead + (model.nq,))
    q, v = np.empty(lead + (model.nq,)), np.empty(lead + (model.nv,))

    def near_sign(quat_xyzw, a):
        if like is None:
            return quat_xyzw
        flip = np.sum(quat_xyzw * like[..., a:a + 4], -1) < 0
        return np.where(flip[..., None], -quat_xyzw, quat_xyzw)

    q[..., qi], v[..., vi] = qpos[..., pi], qvel[..., di]
    for j in others:
        a, b, p, d = j.q, j.v, j.qpos, j.dof
        if j.kind == "Spherical":
            q[..., a:a + 4] = near_sign(qpos[..., [p + 1, p + 2, p + 3, p]], a)
            v[..., b:b + 3] = qvel[..., d:d + 3]
        elif j.kind == "SphericalZYZ":
            r = rotation_of_wxyz(qpos[..., p:p + 4])
            e = zyz_of_rot(r, None if like is None else like[..., a:a + 3])
            w_joint = np.einsum("...ij,...j->...i", r, qvel[..., d:d + 3])
            q[..., a:a + 3] = e
            v[..., b:b + 3] = np.linalg.solve(zyz_rate(e), w_joint[..., None])[..., 0]
        else:
            r_w = rotation_of_wxyz(qpos[..., p + 3:p + 7])
            rel = qmul(quat_wxyz_of(j.rot0.T), qpos[..., p + 3:p + 7])
            q[..., a:a + 3] = (qpos[..., p:p + 3] - j.pos0) @ j.rot0
            q[..., a + 3:a + 7] = near_sign(rel[..., [1, 2, 3, 0]], a + 3)
            v[..., b:b + 3] = np.einsum("...ji,...j->...i", r_w, qvel[..., d:d + 3])
            v[..., b + 3:b + 6] = qvel[..., d + 3:d + 6]
    return q, v


def to_mujoco_acceleration(model, q, v, a) -> np.ndarray:
    """MuJoCo's ``qacc`` for our state (q, v) and acceleration ``a`` (as
    ``forward_dynamics`` returns it): the rate of :func:`to_mujoco_state`'s ``qvel``."""
    model, _ = _model_of(model)
    lay = layout(model)
    q, v = _states(model, q, v)
    a = np.asarray(a, dtype=float)
    if a.shape != v.shape:
        raise InvalidInputError(f"a: expected the shape of v, {v.shape}, got {a.shape}")
    qacc = np.empty(q.shape[:-1] + (lay.nv,))
    for j in lay.joints:
        i, b, d = j.q, j.v, j.dof
        if j.kind in ("Revolute", "Prismatic"):
            qacc[..., d] = a[..., b]
        elif j.kind == "Spherical":
            qacc[..., d:d + 3] = a[..., b:b + 3]
        elif j.kind == "SphericalZYZ":
            # ω_b = Rᵀ L ė, and d(Rᵀ)/dt ω_joint = 0, so ω̇_b = Rᵀ (L ë + L̇ ė).
            e, ed, edd = q[..., i:i + 3], v[..., b:b + 3], a[..., b:b + 3]
            wdot = (np.einsum("...ij,...j->...i", zyz_rate(e), edd)
                    + np.einsum("...ij,...j->...i", zyz_rate_dot(e, ed), ed))
            qacc[..., d:d + 3] = np.einsum("...ji,...j->...i", rotation_of_wxyz(zyz_quat(e)), wdot)
        else:
            # world linear velocity R v_lin: its rate is R (a_lin + ω × v_lin)
            quat = qmul(quat_wxyz_of(j.rot0), q[..., [i + 6, i + 3, i + 4, i + 5]])
            lin = a[..., b:b + 3] + np.cross(v[..., b + 3:b + 6], v[..., b:b + 3])
            qacc[..., d:d + 3] = np.einsum("...ij,...j->...i", rotation_of_wxyz(quat), lin)
            qacc[..., d + 3:d + 6] = a[..., b + 3:b + 6]
    return qacc


__all__ = [
    "MUJOCO_INTEGRATORS",
    "MujocoLayout",
    "from_mujoco_state",
    "layout",
    "to_mjcf",
    "to_mujoco_acceleration",
    "to_mujoco_state",
]
