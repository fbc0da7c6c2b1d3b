"""A scene's right-hand side ``f(t, y)`` in Python and its Jacobian (what SciPy's integrators
are given), a fixed-step classical RK4 in NumPy, and the timer of every measurement."""

from __future__ import annotations

import math
import re
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from .. import _core
from ..io import layout, probe_effects

_GRAVITY_REPR = re.compile(r"^Gravity\(g=\[([^,\]]+), ([^,\]]+), ([^,\]]+)\]\)$")


def scene_rhs(scene) -> Callable[[float, np.ndarray], np.ndarray]:
    """``f(t, y)`` of the scene in Python, ``y = [q; v]``: ``q̇`` from ``v`` and ``v̇`` from
    ``Model.forward_dynamics``. Gravity alone rides on ``forward_dynamics(..., gravity=g)``
    (SciPy's cheapest faithful call); any other declared effect is added through
    :func:`pointmass_dyn.effect_forces`."""
    model = scene.model
    nq, nv = model.nq, model.nv
    disabled = set(scene.disable or ())
    g = None
    others = False
    for e in scene.effects:
        if e.kind in disabled:
            continue
        m = _GRAVITY_REPR.match(repr(e)) if e.kind == "gravity" else None
        if m is not None and g is None:
            cand = np.array([float(x) for x in m.groups()])
            if e == _core.Effect.gravity(cand):
                g = cand
                continue
        others = True
    kinds = [model.body_info(i)[1] for i in range(model.nbodies)]
    qdot_is_v = nq == nv and not {"Spherical", "FreeFlyer"} & set(kinds)
    zeros = np.zeros(nv)

    if not others:

        def rhs(t, y):
            q, v = y[:nq], y[nq:]
            a = model.forward_dynamics(q, v, zeros, gravity=g)
            qd = v if qdot_is_v else model.velocity_to_qdot(q, v)
            return np.concatenate([qd, a])

        return rhs

    def rhs_effects(t, y):
        q, v = y[:nq], y[nq:]
        tau = sum(_core.effect_forces(scene, t, q, v, None).values())
        a = model.forward_dynamics(q, v, np.asarray(tau, dtype=float), gravity=None)
        qd = v if qdot_is_v else model.velocity_to_qdot(q, v)
        return np.concatenate([qd, a])

    return rhs_effects


def rk4_fixed(rhs, t_span, y0, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Classical fixed-step RK4 (MuJoCo's ``mjINT_RK4``): times and states, ``n_steps + 1``
    rows."""
    t0, t1 = float(t_span[0]), float(t_span[1])
    h = (t1 - t0) / n_steps
    ys = np.empty((n_steps + 1, len(y0)))
    ts = t0 + h * np.arange(n_steps + 1)
    ts[-1] = t1
    y = np.array(y0, dtype=float)
    ys[0] = y
    for k in range(n_steps):
        t = ts[k]
        k1 = rhs(t, y)
        k2 = rhs(t + h / 2, y + (h / 2) * k1)
        k3 = rhs(t + h / 2, y + (h / 2) * k2)
        k4 = rhs(t + h, y + h * k3)
        y = y + (h / 6) * (k1 + 2 * k2 + 2 * k3 + k4)
        ys[k + 1] = y
    return ts, ys


def best_time(fn: Callable[[], Any], repeats: int) -> tuple[float, Any]:
    """The least wall time of ``repeats`` calls of ``fn`` (at least one), and the last
    call's result."""
    best, out = math.inf, None
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def analytic_jacobian(sc) -> Callable[[float, np.ndarray], np.ndarray] | None:
    """``J(t, y)`` of :func:`scene_rhs` for models whose q is v (no quaternion joints):
    ``Scene.state_jacobian`` where this build has it, else ``Model.forward_dynamics_derivatives``
    plus the springs' and dampers' terms (scenes of gravity, springs and dampers only);
    ``None`` when neither applies."""
    model = sc.model
    if model.nq != model.nv:
        return None
    if hasattr(sc, "state_jacobian"):       # the scene's own: every effect included
        n2 = model.nq + model.nv
        try:
            ok = np.shape(sc.state_jacobian(np.concatenate([sc.q0, sc.v0]), t=0.0)) == (n2, n2)
        except Exception:
            ok = False
        if ok:
            return lambda t, y: np.asarray(sc.state_jacobian(np.asarray(y, float), t=float(t)))
    if not hasattr(model, "forward_dynamics_derivatives"):
        return None
    try:
        g, stiff, _, damp = probe_effects(sc, model, layout(model))
    except Exception:
        return None
    n = model.nv
    rhs = _core_rhs(sc)

    def jac(t, y):
        q, v = y[:n], y[n:]
        tau = rhs.tau(t, q, v)
        d = model.forward_dynamics_derivatives(q, v, tau, gravity=g)
        dq, dv, minv = (np.asarray(x) for x in d[:3])
        j = np.zeros((2 * n, 2 * n))
        j[:n, n:] = np.eye(n)
        j[n:, :n] = dq - minv * stiff        # τ = −k (q − r) − c v: ∂τ/∂q = −diag(k)
        j[n:, n:] = dv - minv * damp
        return j

    return jac


class _core_rhs:
    """The effects' generalized force of a scene, gravity excluded (for the Jacobian)."""

    def __init__(self, sc):
        others = [e for e in sc.effects if e.kind != "gravity"
                  and e.kind not in set(sc.disable or ())]
        self.sub = _core.Scene(sc.model, effects=others) if others else None
        self.nv = sc.model.nv

    def tau(self, t, q, v):
        if self.sub is None:
            return np.zeros(self.nv)
        return np.sum(list(_core.effect_forces(self.sub, t, q, v, None).values()), axis=0)
