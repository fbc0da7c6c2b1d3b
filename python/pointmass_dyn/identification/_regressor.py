"""The joint torque regressor ``τ = Y π`` and its base parameters (docs/identification.md).

Columns: per link (the body that defines it), the ten inertial parameters in Pinocchio's
order and frame (``computeJointTorqueRegressor``): ``m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz,
Izz`` (first moment ``m c`` and inertia about the link origin, link axes); then per 1-dof
joint, when asked, viscous friction ``fv`` (column ``v``), Coulomb friction ``fc`` (``sign
v``), ``armature`` (``a``) and a constant ``offset``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _core
from ..errors import InvalidInputError

FRICTION_KINDS = ("viscous", "coulomb")


def friction_flags(friction) -> tuple[bool, bool]:
    """``(viscous, coulomb)`` from ``friction``: None/False, True (both), "viscous",
    "coulomb" or a sequence of those."""
    if friction is None or friction is False:
        return False, False
    if friction is True:
        return True, True
    kinds = (friction,) if isinstance(friction, str) else tuple(friction)
    bad = [k for k in kinds if k not in FRICTION_KINDS]
    if bad:
        raise InvalidInputError(
            f"friction: expected True, 'viscous', 'coulomb' or a list of them, got {friction!r}"
        )
    return "viscous" in kinds, "coulomb" in kinds


@dataclass(frozen=True)
class Regressor:
    """``data`` (N · nv, p), sample-major (sample k's joint forces in rows ``k nv … (k+1)
    nv − 1``); ``names`` of the p columns; ``values`` the model's own value of each column
    (friction and offsets zero). With ``actuated`` (v indices) the rows are those joints'
    driving forces and ``nv`` is their number."""

    data: np.ndarray
    names: list[str]
    values: np.ndarray
    nv: int
    actuated: tuple[int, ...] = ()

    def torques(self, parameters=None) -> np.ndarray:
        """``Y π`` as (N, nv) (the model's own parameters by default)."""
        pi = self.values if parameters is None else np.asarray(parameters, float)
        return (self.data @ pi).reshape(-1, self.nv)


def actuated_indices(model, actuated) -> list[int]:
    """v indices of ``actuated`` (v indices or link names of 1-dof joints); [] for None."""
    if actuated is None:
        return []
    items = [actuated] if isinstance(actuated, (str, int, np.integer)) else list(actuated)
    links = list(model.link_names)
    slices = model.joint_slices()
    out = []
    for x in items:
        if isinstance(x, str):
            if x not in links or slices[links.index(x)][3] != 1:
                raise InvalidInputError(
                    f"actuated: expected v indices or names of links with a 1-dof joint {links}, got {x!r}"
                )
            out.append(int(slices[links.index(x)][1]))
        elif isinstance(x, (int, np.integer)) and not isinstance(x, bool) and 0 <= x < model.nv:
            out.append(int(x))
        else:
            raise InvalidInputError(f"actuated: expected v indices below {model.nv} or link names, got {x!r}")
    return out


def torque_regressor(
    model,
    q,
    v,
    a,
    gravity=None,
    friction=None,
    armature: bool = False,
    offset: bool = False,
    actuated=None,
) -> Regressor:
    """The joint torque regressor along N states (``q`` (N, nq), ``v``, ``a`` (N, nv)), one
    call for all of them. ``Y π`` is :meth:`Model.inverse_dynamics` (plus the friction,
    armature and offset columns' terms). ``actuated`` (v indices or link names; required with
    loops): the regressor of those joints' driving forces, ``Y_a = P(q) Y`` with ``P`` the
    actuated rows of ``[S_a | Jᵀ]⁺``, so ``Y_a π`` is ``inverse_dynamics(..., actuated)`` at
    those joints (docs/identification.md §7)."""
    viscous, coulomb = friction_flags(friction)
    q = np.atleast_2d(np.asarray(q, float))
    v = np.atleast_2d(np.asarray(v, float))
    a = np.atleast_2d(np.asarray(a, float))
    act = actuated_indices(model, actuated)
    extras = (bool(viscous), bool(coulomb), bool(armature), bool(offset))
    y = _core.identification_regressor(model, q, v, a, gravity, extras, act)
    names, values = _core.identification_parameters(model, extras)
    if armature:
        arm = np.asarray(model.armature, float)
        one = [i for i, n in enumerate(names) if n.endswith(".armature")]
        values[one] = arm[one_dof_joints(model)]
    return Regressor(y, names, values, len(act) if act else model.nv, tuple(act))


def one_dof_joints(model) -> np.ndarray:
    """v indices of the 1-dof (revolute, prismatic) joints: the joint-space columns' order."""
    return np.array([vi for (_, vi, _, nv) in model.joint_slices() if nv == 1], dtype=int)


@dataclass(frozen=True)
class BaseParameters:
    """The identifiable combinations of a regressor's columns: ``β = K π`` with ``K``
    (rank, p) (:attr:`map`); ``names[k]`` spells base parameter k as the combination it is.
    ``independent`` / ``dependent``: column indices; ``pivots``: the unit-column QR's diagonal
    (how far each independent column is from the span of the ones before it)."""

    rank: int
    independent: list[int]
    dependent: list[int]
    coefficients: np.ndarray
    pivots: np.ndarray
    names: list[str]
    map: np.ndarray

    def of(self, parameters) -> np.ndarray:
        """``β`` of a full parameter vector."""
        return self.map @ np.asarray(parameters, float)


def base_parameters_from(base, names: list[str], p: int) -> BaseParameters:
    """A :class:`BaseParameters` from the core's record (indices into ``names``)."""
    ind, dep, coef = base.independent, base.dependent, base.coefficients
    k = np.zeros((base.rank, p))
    labels = []
    for i, c in enumerate(ind):
        k[i, c] = 1.0
        row = coef[i] if coef.size else np.zeros(0)
        cut = 1e-10 * max(1.0, float(np.abs(row).max(initial=0.0)))
        label = names[c]
        for d, e in enumerate(dep):
            k[i, e] = row[d]
            if abs(row[d]) > cut:
                sign = "-" if row[d] < 0 else "+"
                mag = abs(row[d])
                label += f" {sign} {names[e]}" if abs(mag - 1) < 1e-12 else f" {sign} {mag:.6g}*{names[e]}"
        labels.append(label)
    return BaseParameters(base.rank, list(ind), list(dep), coef, base.pivots, labels, k)


def base_parameters(regressor, names: list[str] | None = None, rank_tol: float = 1e-8) -> BaseParameters:
    """Base parameters of a regressor (a :class:`Regressor` or an (rows, p) array) by
    column-pivoted QR on unit-norm columns; a column whose remaining norm falls to
    ``rank_tol`` depends on the ones before it."""
    if isinstance(regressor, Regressor):
        data, names = regressor.data, regressor.names
    else:
        data = np.asarray(regressor, float)
        if data.ndim != 2:
            raise InvalidInputError(f"regressor: expected a 2-d array, got shape {data.shape}")
        names = names if names is not None else [f"p{k}" for k in range(data.shape[1])]
    if len(names) != data.shape[1]:
        raise InvalidInputError(f"names: expected {data.shape[1]} names, got {len(names)}")
    base = _core.identification_base(data, rank_tol)
    return base_parameters_from(base, list(names), data.shape[1])
