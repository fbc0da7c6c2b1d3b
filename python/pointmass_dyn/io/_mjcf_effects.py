"""The scene effects :func:`pointmass_dyn.to_mjcf` writes as MuJoCo actuators, joint limits
and contacts (gravity, springs and dampers are joint attributes: ``_mjcf.py``).

============================ ==========================================================
ours                         MJCF
============================ ==========================================================
``PDTorque`` (1-dof joints)  ``<position kp kv>`` per joint, ``ctrl = r(t) + kd/kp ṙ(t)``
                             (then ``kp (ctrl − q) − kv v`` is our ``kp (r − q) + kd (ṙ − v)``)
``JointTorque`` (1-dof)      ``<motor>`` per joint, ``ctrl = τ``
``TabulatedTorque`` (1-dof)  ``<motor>`` per joint, ``ctrl = τ(t)``
a torque's ``limit``         the actuator's ``forcerange`` (MuJoCo clamps the force as ours)
``JointLimit``               the joint's ``range``, ``limited="true"``, ``solreflimit`` from
                             ``k``, ``c`` (below)
``GroundContact``            a ``plane`` at ``normal · x = height`` and a ``sphere`` of the
                             point's radius at each contact point (radius 0: 0.1 mm), μ as
                             ``friction``; only spheres and their own plane collide
============================ ==========================================================

Start: ``<keyframe><key name="scene" qpos qvel ctrl>`` holds the scene's start state and the
actuators' controls then (``mujoco.mj_resetDataKeyframe(m, d, 0)``); a reference or table that changes in time is the
caller's to follow: set ``d.ctrl[:] = pmd.io.mujoco_controls(scene, d.time)`` before each step.

Soft constraints: MuJoCo's are not our penalty laws, so they are matched where it makes sense.
A joint limit ``k``, ``c`` on a joint whose diagonal mass-matrix entry at ``q0`` is ``m`` gets
``solreflimit = (−k/m, −c/m)`` (MuJoCo's direct stiffness and damping per unit mass) and
``solimplimit = (0.99, 0.99, 0.001)``. A contact linearised at our static sink
``δ₀ = (M g₀ / (N k))^(1/e)`` (the model's mass ``M`` shared by its ``N`` points) has
``k_lin = e k δ₀^(e−1)``, ``c_lin = c δ₀^e``; the spheres get ``solref = (−k_lin/m, −c_lin/m)``
with ``m = M/N`` and ``solimp = (0.99, 0.99, 0.001)``: the same frequency and damping ratio
about rest, and a static sink of ``(1 − 0.99)/(0.99 e)`` of ours (MuJoCo's soft constraint
keeps that fraction of the weight as penetration). Resting heights therefore agree within our
sink ``δ₀`` (1 mm with the default stiffness); the contact forces of a body at rest sum to its
weight in both (``tests/test_mjcf_effects.py``).

Refused, naming the effect (``InvalidInputError``): joint friction, external forces, point
springs, torque functions, and torques on joints with more than one speed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._core import Scene
from ..errors import InvalidInputError

#: MuJoCo's impedance for our soft limits and contacts: nearly hard (see the module docs).
SOLIMP = "0.99 0.99 0.001"
#: The radius a point contact (radius 0) gets: MuJoCo has no point geoms.
POINT_RADIUS = 1e-4
_G0 = 9.81


@dataclass
class MjcfEffects:
    """What :func:`mjcf_effects` writes: extra joint attributes by link, geoms by body and in
    the world, actuators, their controls at the start, and whether anything collides."""

    joint_attrs: dict[int, str] = field(default_factory=dict)
    body_geoms: dict[int, list[str]] = field(default_factory=dict)
    world_geoms: list[str] = field(default_factory=list)
    actuators: list[str] = field(default_factory=list)
    ctrl0: list[float] = field(default_factory=list)

    @property
    def contact(self) -> bool:
        return bool(self.world_geoms)


def _fmt(v) -> str:
    return " ".join(repr(float(x)) for x in np.ravel(v))


def _refuse(e, why: str) -> InvalidInputError:
    return InvalidInputError(f"scene: effect {e!r} ({e.name!r}) has no MuJoCo counterpart in the "
                             f"MJCF export ({why}); leave it out or disable its family "
                             f"({e.kind!r}) to convert the rest")


def _links(model, e, sel, one_dof: bool) -> list[int]:
    """The links of a joint selection (names of joints or bodies, body indices; None: every
    moving joint, or every 1-dof one with ``one_dof``)."""
    infos = [model.body_info(i) for i in range(model.nbodies)]
    names, bodies = model.joint_names, model.body_names
    owner = {info[3]: i for i, info in enumerate(infos) if info[1] != "Fixed"}
    if sel is None:
        out = sorted(owner)
        if one_dof:
            out = [k for k in out if infos[owner[k]][1] in ("Revolute", "Prismatic")]
        return out
    out = []
    for s in sel:
        if isinstance(s, str) and s in names:
            out.append(names.index(s))
        else:
            b = bodies.index(s) if isinstance(s, str) else int(s)
            out.append(infos[b][3])
    if one_dof and any(infos[owner[k]][1] not in ("Revolute", "Prismatic") for k in out):
        raise _refuse(e, "MuJoCo actuators and limits here act on revolute and prismatic joints")
    return out


def _per(x, n: int) -> np.ndarray:
    return np.full(n, float(x)) if np.isscalar(x) else np.asarray(x, dtype=float)


def _table(d: dict, key: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(d["time"], dtype=float)
    vals = np.asarray(d[key], dtype=float).reshape(len(t), n)
    return t, vals


def _at(t: np.ndarray, vals: np.ndarray, time: float) -> tuple[np.ndarray, np.ndarray]:
    """Linear interpolation (ends held) and its slope (0 outside, the next segment's at a
    knot), as our tables evaluate."""
    r = np.array([np.interp(time, t, vals[:, k]) for k in range(vals.shape[1])])
    if len(t) < 2 or time < t[0] or time >= t[-1]:
        return r, np.zeros_like(r)
    i = int(np.searchsorted(t, time, side="right")) - 1
    return r, (vals[i + 1] - vals[i]) / (t[i + 1] - t[i])


def _torque_controls(d: dict, n: int, time: float) -> np.ndarray:
    """An actuator's controls at ``time`` for the torque effect table ``d`` on ``n`` joints."""
    if d["type"] == "torque":
        return _per(d["tau"], n)
    if d["type"] == "tabulated_torque":
        return _at(*_table(d, "values", n), time)[0]
    kp, kd = _per(d["kp"], n), _per(d["kd"], n)
    r, rd = _at(*_table(d, "reference", n), time)
    return r + kd / kp * rd


def _actuated(scene) -> list[tuple[Any, dict, list[int]]]:
    """(effect, its table, its links) of every enabled torque effect, checked."""
    disabled = set(scene.disable or ())
    out = []
    for e in scene.effects:
        if e.kind != "torques" or "torques" in disabled:
            continue
        if repr(e).startswith("TorqueFunction("):
            raise _refuse(e, "a Python function; write its law as a PDTorque or a table")
        d = e.to_dict()
        links = _links(scene.model, e, d.get("joints"), one_dof=True)
        if d["type"] == "pd_torque" and np.any(_per(d["kp"], len(links)) <= 0):
            raise _refuse(e, "MuJoCo's position actuator needs kp > 0")
        out.append((e, d, links))
    return out


def mujoco_controls(scene, t: float = 0.0) -> np.ndarray:
    """``d.ctrl`` of :func:`to_mjcf`'s model at time ``t``: the actuators' controls, in the
    order the MJCF lists them (see the module docs)."""
    if not isinstance(scene, Scene):
        raise InvalidInputError(f"scene: expected a pointmass_dyn Scene, got "
                                f"{type(scene).__name__}")
    parts = [_torque_controls(d, len(links), float(t)) for _, d, links in _actuated(scene)]
    return np.concatenate(parts) if parts else np.zeros(0)


def _actuators(scene, out: MjcfEffects) -> None:
    names = scene.model.joint_names
    for e, d, links in _actuated(scene):
        n = len(links)
        limit = d.get("limit")
        limit = np.full(n, math.inf) if limit is None else _per(limit, n)
        kp, kd = (_per(d["kp"], n), _per(d["kd"], n)) if d["type"] == "pd_torque" else (
            None, None)
        for k, link in enumerate(links):
            attrs = f'name="{e.name}_{k}" joint="{names[link]}"'
            if kp is not None:
                tag = f'position {attrs} kp="{float(kp[k])!r}" kv="{float(kd[k])!r}"'
            else:
                tag = f'motor {attrs} gear="1"'
            if math.isfinite(limit[k]):
                tag += f' forcelimited="true" forcerange="{_fmt([-limit[k], limit[k]])}"'
            out.actuators.append(f"<{tag}/>")
        out.ctrl0.extend(_torque_controls(d, n, scene.t_span[0] if scene.t_span else 0.0))


def _limits(scene, out: MjcfEffects) -> None:
    model = scene.model
    diag = np.diag(model.mass_matrix(scene.q0))
    slices = model.joint_slices()
    for e in scene.effects:
        if e.kind != "limits" or "limits" in set(scene.disable or ()):
            continue
        d = e.to_dict()
        links = _links(model, e, d.get("joints"), one_dof=True)
        n = len(links)
        if "lower" not in d or "upper" not in d:
            raise _refuse(e, "its bounds are the model's and the model has none")
        lo, up = _per(d["lower"], n), _per(d["upper"], n)
        k, c = _per(d["stiffness"], n), _per(d["damping"], n)
        for j, link in enumerate(links):
            m = diag[slices[link][1]]
            # MuJoCo wants a finite range: an open side becomes far beyond any motion.
            bounds = [max(lo[j], -1e10), min(up[j], 1e10)]
            out.joint_attrs[link] = (
                f' range="{_fmt(bounds)}" limited="true" '
                f'solreflimit="{_fmt([-k[j] / m, -c[j] / m])}" solimplimit="{SOLIMP}"')


def _contacts(scene, out: MjcfEffects) -> None:
    model = scene.model
    bodies = model.body_names
    names = model.joint_names
    infos = [model.body_info(i) for i in range(model.nbodies)]
    owner = {info[3]: i for i, info in enumerate(infos) if info[1] != "Fixed"}
    mass = model.total_mass
    contacts = [e for e in scene.effects if e.kind == "contact"]
    if len(contacts) > 30 or "contact" in set(scene.disable or ()):
        contacts = contacts[:0] if "contact" in set(scene.disable or ()) else contacts
        if len(contacts) > 30:
            raise _refuse(contacts[30], "MuJoCo has 31 collision bits: at most 30 contacts")
    for k, e in enumerate(contacts):
        p = e.contact_parameters
        d = e.to_dict()
        n, h = np.asarray(d["normal"], float), float(d["height"])
        npts = len(d["points"])
        sink = (mass * _G0 / (npts * p["stiffness"])) ** (1.0 / p["exponent"])
        k_lin = p["exponent"] * p["stiffness"] * sink ** (p["exponent"] - 1.0)
        c_lin = p["damping"] * sink ** p["exponent"]
        share = mass / npts
        mu = f'friction="{float(p["friction"])!r} 0.005 0.0001"'
        soft = f'solref="{_fmt([-k_lin / share, -c_lin / share])}" solimp="{SOLIMP}"'
        bit = 2 << k
        out.world_geoms.append(
            f'<geom name="{e.name}_plane" type="plane" size="0 0 1" pos="{_fmt(n * h)}" '
            f'zaxis="{_fmt(n)}" contype="0" conaffinity="{bit}" {mu} {soft}/>')
        for j, (body, point, radius) in enumerate(d["points"]):
            if isinstance(body, str):
                b = bodies.index(body) if body in bodies else owner[names.index(body)]
            else:
                b = int(body)
            r = radius if radius > 0 else POINT_RADIUS
            out.body_geoms.setdefault(b, []).append(
                f'<geom name="{e.name}_{j}" type="sphere" size="{float(r)!r}" '
                f'pos="{_fmt(point)}" contype="{bit}" conaffinity="0" mass="0" {mu} {soft}/>')


def mjcf_effects(scene) -> MjcfEffects:
    """The actuators, joint limits and contacts of ``scene``'s enabled effects (module docs)."""
    out = MjcfEffects()
    if scene is None:  # a bare model
        return out
    _actuators(scene, out)
    _limits(scene, out)
    _contacts(scene, out)
    return out
