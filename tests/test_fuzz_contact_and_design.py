"""Random calls to the entry points newer than ``test_fuzz_api.py``'s:
ground contact, joint limits, torque limits, couplings, armature, URDF contact points and
the design API (link shapes, counterweights, ``balance``, ``pareto_front``). The contract is
``test_fuzz_api``'s: whatever the input, a finite result or a ``pmd.errors`` exception
(``TypeError`` for a wrong Python type), never another exception and never a silent NaN;
the module runs under the same address-space limit. Every size drawn is bounded (ring
counts, cells, Pareto counts, list lengths): hypothesis draws differ between the in-tree and
the installed package, and an unbounded one once allocated gigabytes in CI."""

from __future__ import annotations

import math
import os
import pickle
import tempfile
from types import SimpleNamespace

import numpy as np
import pointmass_dyn as pmd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_fuzz_api import (
    ALLOWED,
    FOURBAR,
    MODELS,
    arrays,
    assert_finite,
    bounded_address_space,  # the module's autouse address-space limit
    call,
    floats,
    junk,
)

G = np.array([0.0, -9.81, 0.0])
MOTION = pmd.prescribed_motion(FOURBAR.model, "crank", speed=30.0, samples=12,
                               q_guess=FOURBAR.q0, gravity=G)
BOX = ([-0.05, -0.02, -0.004], [0.045, 0.02, 0.004])
SHAPES = [pmd.LinkShape("coupler", box=BOX, cell=c) for c in (0.008, 0.02)]
# Bodies of the zoo's models and the fourbar, and names no model has.
body_names = st.sampled_from(["ball", "slider", "euler", "box", "flap", "crank", "coupler",
                              "rocker", "nope", ""])
joint_refs = st.one_of(st.none(), st.integers(-2, 5), body_names,
                       st.lists(st.one_of(st.integers(-1, 4), body_names), max_size=3), junk)
# Sizes: cells of at most a few thousand in BOX, small Pareto counts and rings.
cells = st.one_of(st.sampled_from([0.0, -0.01, math.nan, math.inf, 1e-300, 1e-4]), junk)
big_counts = st.one_of(st.integers(-1, 1), st.sampled_from([2**31, 2**70, 10**9]), junk)
sane = st.floats(-2.0, 2.0)
vec3 = st.lists(st.floats(-0.05, 0.05), min_size=3, max_size=3)


def pick(data, good, bad=None, p_bad: int = 2):
    """Mostly ``good`` (a strategy), ``p_bad`` times in ten ``bad`` (default: any edge
    number or junk): each argument valid most of the time, so that many calls get through
    their checks to the computation, and a few go wrong one argument at a time."""
    if data.draw(st.integers(0, 9)) >= 10 - p_bad:  # 0, the simplest draw, is good
        return data.draw(bad if bad is not None else st.one_of(floats, arrays(None), junk))
    return data.draw(good)


def simulate_briefly(data, model, effects) -> None:
    """A scene of ``effects`` (accepted or refused), run for 20 ms at most 200 steps."""
    scene = call(data, "Scene", pmd.Scene, model, model.neutral(), np.zeros(model.nv),
                 effects=effects)
    if scene is None:
        return
    r = call(data, "simulate", pmd.simulate, scene, (0.0, 0.02), max_steps=200,
             energy=data.draw(st.booleans()))
    if r is not None and any(e.kind == "contact" for e in scene.effects):
        state = r if data.draw(st.booleans()) else SimpleNamespace(
            q=np.atleast_2d(data.draw(arrays(model.nq))), v=np.atleast_2d(data.draw(arrays(model.nv))))
        out = call(data, "contact_forces", pmd.contact_forces, scene, state)
        for forces in (out or {}).values():
            assert_finite("contact_forces", vars(forces))


def own_bodies(model) -> st.SearchStrategy:
    return st.sampled_from(list(model.body_names))


def contact_calls(data, model) -> None:
    point = st.tuples(own_bodies(model), vec3, st.floats(0.0, 0.1))
    points = pick(data, st.lists(point, min_size=1, max_size=3), st.one_of(
        st.lists(st.tuples(st.one_of(body_names, st.integers(-1, 4), junk),
                           st.one_of(arrays(3), junk), st.one_of(floats, junk)), max_size=3), junk))
    gc = call(data, "GroundContact", pmd.GroundContact, points,
              normal=pick(data, st.just((0.0, 0.0, 1.0)), arrays(3)),
              height=pick(data, st.floats(-0.1, 0.1)),
              stiffness=pick(data, st.sampled_from([1e3, 1e5, 1e7])),
              exponent=pick(data, st.sampled_from([1.0, 1.5, 2.0])),
              damping=pick(data, st.sampled_from([0.0, 10.0, 1e3])),
              friction=pick(data, st.sampled_from([0.0, 0.5, 1.0])),
              v_eps=pick(data, st.sampled_from([1e-3, 1e-2])),
              name=pick(data, st.one_of(st.none(), st.text(max_size=3)), junk))
    if gc is not None:
        simulate_briefly(data, model, [gc, pmd.Gravity([0, 0, -9.81])])


def limit_calls(data, model) -> None:
    bound = st.one_of(st.none(), st.floats(-3, 3), st.just(math.inf), st.just(-math.inf))
    lower = pick(data, bound)
    upper = pick(data, bound)
    jl = call(data, "JointLimit", pmd.JointLimit, pick(data, st.none(), joint_refs), lower,
              upper, stiffness=pick(data, st.sampled_from([0.0, 1e3, 1e6])),
              damping=pick(data, st.sampled_from([0.0, 1.0])))
    if jl is not None:
        simulate_briefly(data, model, [jl])


def torque_limit_calls(data, model) -> None:
    limit = st.one_of(st.none(), st.just(math.inf), st.floats(0.01, 100), st.just("effort"))
    ones = [b for b, info in ((b, model.body_info(k)) for k, b in enumerate(model.body_names))
            if info[1] in ("Revolute", "Prismatic")]
    joints = pick(data, st.one_of(st.none(), st.sampled_from(ones)), joint_refs)
    if data.draw(st.booleans()):
        eff = call(data, "JointTorque", pmd.JointTorque, joints, pick(data, sane),
                   limit=pick(data, limit))
    else:
        eff = call(data, "PDTorque", pmd.PDTorque, joints, pick(data, st.floats(0, 100)),
                   pick(data, st.floats(0, 10)), pick(data, st.just([0.0, 1.0]), arrays(None)),
                   pick(data, st.just([[0.1], [0.2]]), arrays(None)), limit=pick(data, limit))
    if eff is not None:
        try:
            per_speed = eff.torque_limit_per_speed(model)  # inf where unlimited
        except ALLOWED:
            per_speed = np.ones(1)
        assert not np.isnan(per_speed).any() and (per_speed > 0).all(), per_speed
        simulate_briefly(data, model, [eff])


def coupling_calls(data) -> None:
    """Couplings and armature on copies of the revolute chain and the fourbar."""
    model = pickle.loads(pickle.dumps(data.draw(st.sampled_from([MODELS[0], FOURBAR.model]))))
    names = list(model.body_names)
    if data.draw(st.booleans()):
        out = call(data, "add_coupling", model.add_coupling, pick(data, st.sampled_from(names), joint_refs),
                   pick(data, st.sampled_from(names), joint_refs),
                   ratio=pick(data, st.floats(-3, 3)), offset=pick(data, st.floats(-1, 1)),
                   name=pick(data, st.one_of(st.none(), st.text(max_size=3)), junk))
    else:
        out = call(data, "set_armature", model.set_armature, pick(data, st.sampled_from(names), joint_refs),
                   pick(data, st.one_of(st.floats(0, 1), st.lists(st.floats(0, 1), min_size=1, max_size=1))))
    if out is not None or data.draw(st.booleans()):
        q = model.neutral() if model.nloops == 0 else FOURBAR.q0
        call(data, "mass_matrix", model.mass_matrix, q)
        call(data, "forward_dynamics", model.forward_dynamics, q, np.zeros(model.nv),
             np.zeros(model.nv))
        simulate_briefly(data, model, [pmd.Gravity([0, 0, -9.81])])


def _text(x) -> str:
    return repr(float(x)) if isinstance(x, float) else str(x)[:8]


def urdf_contact_calls(data) -> None:
    radius = pick(data, st.floats(0, 0.1), st.one_of(floats, st.sampled_from(["", "abc", "1 2", "0x10"])))
    xyz = " ".join(_text(pick(data, st.floats(-1, 1)))
                   for _ in range(pick(data, st.just(3), st.integers(0, 4))))
    geometry = pick(data, st.just(f'<sphere radius="{_text(radius)}"/>'),
                    st.sampled_from(["<sphere/>", '<box size="1 1 1"/>', ""]))
    urdf = (f'<robot name="r"><link name="a"><collision><origin xyz="{xyz}"/>'
            f"<geometry>{geometry}</geometry></collision></link>"
            '<link name="b"/><joint name="j" type="revolute"><parent link="a"/>'
            '<child link="b"/><axis xyz="0 0 1"/></joint></robot>')
    if data.draw(st.integers(0, 9)) == 0:
        urdf = urdf[: data.draw(st.integers(0, len(urdf)))]  # a truncated file
    links = pick(data, st.lists(st.sampled_from(["a", "b"]), min_size=1, max_size=2),
                 st.one_of(st.lists(st.sampled_from(["a", "b", "nope", ""]), max_size=3), junk))
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "r.urdf")
        with open(path, "w") as f:
            f.write(urdf)
        target = pick(data, st.just(path), st.sampled_from([tmp, os.path.join(tmp, "missing.urdf")]))
        call(data, "urdf_contact_points", pmd.urdf_contact_points, target, links)


def check_balance(what: str, b) -> None:
    assert_finite(f"{what}.masses", np.asarray(b.masses, dtype=float))
    for name in ("force", "moment"):
        assert_finite(f"{what}.after.shaking.{name}", getattr(b.after.shaking, name))
    for body, rb in b.bodies.items():
        assert_finite(f"{what}.bodies[{body}]", [rb.mass, np.asarray(rb.com), np.asarray(rb.inertia)])


def design_calls(data) -> None:
    op = data.draw(st.sampled_from(["shape", "counterweight", "ring", "balance", "balance",
                                    "pareto"]))
    moving = st.sampled_from(["crank", "coupler", "rocker"])
    body = pick(data, moving, st.one_of(body_names, st.integers(-1, 4), junk))
    if op == "shape":
        ls = call(data, "LinkShape", pmd.LinkShape, body,
                  box=pick(data, st.just(BOX), st.one_of(arrays(None), junk)),
                  cell=pick(data, st.sampled_from([0.004, 0.008, 0.02]), cells),
                  density=pick(data, st.just(7850.0)),
                  mass=pick(data, st.one_of(st.none(), st.tuples(st.floats(0, 0.01), st.floats(0.01, 1))),
                            st.one_of(st.tuples(floats, floats), junk)),
                  boss=pick(data, st.one_of(st.none(), st.floats(0, 0.01))),
                  symmetric=pick(data, st.booleans(), junk))
        if ls is not None:
            call(data, "cells", ls.cells, FOURBAR.model)
            if data.draw(st.booleans()):
                check_balance_call(data, [], [ls])
        return
    if op == "counterweight":
        k = data.draw(st.integers(0, 4))
        cw = call(data, "Counterweight", pmd.Counterweight, body,
                  pick(data, st.just(np.full((k, 3), 0.01) * np.arange(k)[:, None]),
                       st.one_of(st.just(np.full((k, 3), data.draw(floats))), arrays(None), junk)),
                  pick(data, st.one_of(st.none(), st.floats(0, 1))))
        if cw is not None:
            check_balance_call(data, [cw], [])
        return
    ring = call(data, "ring", pmd.Counterweight.ring, body, pick(data, vec3, st.one_of(arrays(3), junk)),
                pick(data, st.floats(0.001, 0.05)), pick(data, st.integers(1, 8), big_counts),
                normal=pick(data, st.just((0, 0, 1)), arrays(3)),
                max_mass=pick(data, st.one_of(st.none(), st.floats(0, 1))))
    if ring is None or op == "ring":
        return
    links = pick(data, st.lists(st.one_of(moving, st.sampled_from(SHAPES)), max_size=2),
                 st.lists(st.one_of(body_names, st.sampled_from(SHAPES), junk), max_size=2))
    if op == "balance":
        check_balance_call(data, [ring], links)
        return
    front = call(data, "pareto_front", pmd.pareto_front, MOTION,
                 pick(data, st.tuples(st.sampled_from(["force", "moment"]), st.sampled_from(["mass", "torque"])),
                      st.one_of(st.tuples(st.sampled_from(["force", "moment", "mass", "torque", "x"]),
                                          st.sampled_from(["force", "moment", "mass"])), junk)),
                 count=pick(data, st.integers(2, 4), big_counts),
                 method=pick(data, st.sampled_from(["weighted", "epsilon"]), st.just("x")),
                 counterweights=[ring], links=links)
    for k, b in enumerate(front or []):
        check_balance(f"pareto_front[{k}]", b)


def check_balance_call(data, counterweights, links) -> None:
    names = st.sampled_from(["force", "moment", "mass", "torque", "bearing:crank"])
    weights = st.dictionaries(names, st.floats(0, 1), min_size=1, max_size=2)
    b = call(data, "balance", pmd.balance, MOTION, counterweights=counterweights, links=links,
             objective=pick(data, st.one_of(st.none(), weights),
                            st.one_of(st.dictionaries(st.one_of(names, st.just("x")), st.one_of(floats, junk),
                                                      max_size=2), junk), p_bad=1),
             norm=pick(data, st.sampled_from(["rms", "peak"]), st.just("x"), p_bad=1),
             limits=pick(data, st.one_of(st.none(), st.dictionaries(names, st.floats(0, 100), max_size=1)),
                         st.one_of(st.dictionaries(names, st.one_of(floats, junk), max_size=2), junk),
                         p_bad=1),
             zero=pick(data, st.one_of(st.just(()), st.lists(st.sampled_from(["force", "moment"]), max_size=1)),
                       st.one_of(st.lists(names, max_size=2), junk), p_bad=1),
             link_mass=pick(data, st.sampled_from([(1.0, 1.0), (0.5, 2.0), (1.0, math.inf)]),
                            st.one_of(st.tuples(floats, floats), junk), p_bad=1),
             least_mass=pick(data, st.booleans(), junk, p_bad=1))
    if b is not None:
        check_balance("balance", b)


# A complex number cast to a real one is a silent reinterpretation: an error here.
@pytest.mark.filterwarnings("error::numpy.exceptions.ComplexWarning")
@settings(max_examples=2500, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
@given(st.data())
def test_random_calls_to_contact_limits_couplings_and_design(data):
    area = data.draw(st.sampled_from(["contact", "limit", "torque_limit", "coupling", "urdf",
                                      "design", "design"]))
    model = data.draw(st.sampled_from(MODELS))
    if area == "contact":
        contact_calls(data, model)
    elif area == "limit":
        limit_calls(data, model)
    elif area == "torque_limit":
        torque_limit_calls(data, model)
    elif area == "coupling":
        coupling_calls(data)
    elif area == "urdf":
        urdf_contact_calls(data)
    else:
        design_calls(data)


def test_these_random_calls_run_under_the_address_space_bound():
    # The limit of test_fuzz_api applies here too (the fixture is imported, autouse).
    assert bounded_address_space is not None and ALLOWED
    with pytest.raises(pmd.errors.InvalidInputError):
        pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 10**9)
