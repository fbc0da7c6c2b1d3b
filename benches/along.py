"""Analyses along a 10,000-sample result: one core call (``_core.scene_along``) against the
per-sample loop from Python it replaced (one ``effect_forces`` and one ``forward_dynamics``
call per state). Contact forces: ``pmd.contact_forces(scene, result)`` (one vectorised
``contact_state`` call per contact since it shipped) against the per-state query a user loops
over (``contact_state`` of one state, stacked). Ratios measured in one process;
``python benches/along.py``."""

from __future__ import annotations

import time

import numpy as np
import pointmass_dyn as pmd
from pointmass_dyn import _core

N = 10_000


def per_sample_accelerations(scene, res):
    m = scene.model
    return np.array([m.forward_dynamics(q, v, sum(_core.effect_forces(scene, float(t), q, v).values()))
                     for t, q, v in zip(res.t, res.q, res.v)])


def per_sample_saturation(scene, res, name, limit):
    return np.array([np.abs(_core.effect_forces(scene, float(t), q, v)[name]) >= limit
                     for t, q, v in zip(res.t, res.q, res.v)])


def per_sample_contacts(scene, res):
    """Each contact's forces state by state (``contact_state`` of one state), stacked."""
    m = scene.model
    out = {}
    for e in scene.effects:
        if e.kind == "contact":
            rows = [e.contact_state(m, q[None], v[None]) for q, v in zip(res.q, res.v)]
            out[e.name] = {k: np.concatenate([r[k] for r in rows]) for k in rows[0]}
    return out


def best(f, repeat=3):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    rows = []
    fourbar = pmd.load_scene("fourbar")
    res = pmd.simulate(fourbar, (0.0, 2.0), t_eval=np.linspace(0.0, 2.0, N))
    old = best(lambda: pmd.shaking(fourbar.model, res.q, res.v,
                                   per_sample_accelerations(fourbar, res)))
    new = best(lambda: pmd.shaking(fourbar, res))
    rows.append(("fourbar shaking(scene, result)", old, new))

    chain = pmd.load_scene("chain7")
    pd = pmd.PDTorque(chain.model.joint_names[0], kp=400.0, kd=5.0, time=[0.0, 1.0],
                      reference=[1.0, 1.0], limit=3.0)
    scene = chain.replace(effects=list(chain.effects) + [pd])
    res = pmd.simulate(scene, (0.0, 2.0), t_eval=np.linspace(0.0, 2.0, N))
    (name,) = pmd.torque_saturation(scene, res).keys()
    old = best(lambda: per_sample_saturation(scene, res, name, 3.0))
    new = best(lambda: pmd.torque_saturation(scene, res))
    rows.append(("chain7 torque_saturation", old, new))

    box = pmd.load_scene("box_incline")
    res = pmd.simulate(box, (0.0, 1.0), t_eval=np.linspace(0.0, 1.0, N))
    ref, got = per_sample_contacts(box, res), pmd.contact_forces(box, res)
    assert ref.keys() == got.keys() and all(
        np.array_equal(ref[k]["force"], got[k].force) for k in ref)
    old = best(lambda: per_sample_contacts(box, res))
    new = best(lambda: pmd.contact_forces(box, res))
    rows.append(("box_incline contact_forces", old, new))

    print(f"{'analysis of a ' + str(N) + '-sample result':48s} {'per sample':>11s} {'one call':>10s} {'ratio':>7s}")
    for label, o, n in rows:
        print(f"{label:48s} {1e3 * o:9.1f} ms {1e3 * n:8.1f} ms {o / n:6.1f}×")


if __name__ == "__main__":
    main()
