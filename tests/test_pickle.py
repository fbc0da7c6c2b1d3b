"""Pickling and copies: every public class survives pickle (all protocols), copy.copy and
copy.deepcopy with bit-identical behaviour; damaged data raises our error, never a panic;
scenes run in spawned worker processes."""

from __future__ import annotations

import copy
import multiprocessing
import pickle
import re
from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn import _core
from pointmass_dyn._pickle import _load
from pointmass_dyn.errors import PointMassDynError, UnpicklingError

PANDA = Path(pmd.__file__).with_name("scenes") / "panda.urdf"
G = (0.0, 0.0, -9.81)
PROTOCOLS = range(2, pickle.HIGHEST_PROTOCOL + 1)


def copies(x):
    """(how, copy) for every pickle protocol, copy.copy and copy.deepcopy."""
    for p in PROTOCOLS:
        yield f"pickle protocol {p}", pickle.loads(pickle.dumps(x, protocol=p))
    yield "copy.copy", copy.copy(x)
    yield "copy.deepcopy", copy.deepcopy(x)


def same(a, b, what=""):
    """Equal arrays bit for bit (so -0.0 ≠ 0.0 and NaN == NaN with the same payload)."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape and a.dtype == b.dtype, what
    assert a.tobytes() == b.tobytes(), what


def same_dict(a: dict, b: dict, what=""):
    assert a.keys() == b.keys(), what
    for k in a:
        same(a[k], b[k], f"{what}[{k}]")


# --------------------------------------------------------------------------------------------
# Models
# --------------------------------------------------------------------------------------------
def torque(t, q, v):
    """A module-level torque law (pickles by reference)."""
    return -0.3 * v + 0.1 * np.sin(t)


def every_joint_model() -> pmd.Model:
    """Every joint kind, welded bodies, a noisy rotation (re-orthonormalised on add), a
    point-mass centre away from the COM and a body from point masses."""
    rng = np.random.default_rng(7)
    m = pmd.Model()
    rod = pmd.RigidBody(2.51, [0.5, 0, 0], np.diag([1.255e-4, 0.2092, 0.2092]))
    box = pmd.RigidBody(1.3, [0.01, -0.02, 0.05], [[0.02, 1e-3, 0], [1e-3, 0.03, 2e-4], [0, 2e-4, 0.04]])
    pts = box.point_masses(center=[0.1, 0.0, 0.0])
    from_points = pmd.RigidBody.from_point_masses(pts.masses, pts.positions)
    a, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    a *= np.sign(np.linalg.det(a))
    noisy_quarter = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]) + 1e-12 * rng.normal(size=(3, 3))
    b0 = m.add_body(rod, pmd.SphericalZYZ(), name="shoulder", point_mass_center=[1.0, 0, 0])
    b1 = m.add_body(box, pmd.Revolute([0, 1, 1]), b0, [1.0, 0, 0], a, name="elbow")
    m.add_body(from_points, pmd.Fixed(), b1, [0.1, 0.2, 0.0], noisy_quarter, name="bracket")
    b3 = m.add_body(box, pmd.Prismatic([1, 0, 0]), b1, [0, 0, 0.3], name="slide")
    m.add_body(rod, pmd.Spherical(), b3, [0.2, 0, 0], name="wrist")
    m.add_body(box, pmd.Fixed(), -1, [0, 0, -1.0], name="base")
    return m


def random_state(model: pmd.Model, rng: np.random.Generator):
    q = model.neutral() + rng.normal(scale=0.7, size=model.nq)
    for iq, _iv, nq, _nv in model.joint_slices():
        if nq == 4:
            q[iq : iq + 4] /= np.linalg.norm(q[iq : iq + 4])
    return q, rng.normal(size=model.nv), rng.normal(size=model.nv)


def assert_same_model(a: pmd.Model, b: pmd.Model, what: str):
    assert type(b) is pmd.Model
    assert (a.nq, a.nv, a.nbodies, a.nlinks) == (b.nq, b.nv, b.nbodies, b.nlinks), what
    assert a.body_names == b.body_names and a.link_names == b.link_names, what
    assert a.joint_slices() == b.joint_slices(), what
    assert [a.body_info(i) for i in range(a.nbodies)] == [b.body_info(i) for i in range(b.nbodies)]
    same(a.total_mass, b.total_mass, what)
    same(a.neutral(), b.neutral(), what)
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, v, x = random_state(a, rng)
        for method in ("recursive", "denoc"):
            same(a.mass_matrix(q, method=method), b.mass_matrix(q, method=method), what)
            try:
                fa = a.forward_dynamics(q, v, x, gravity=G, method=method)
            except pmd.SingularityError as e:
                # A random state far off a mechanism's manifold can lock it (Bricard's five
                # rows are independent there): the copy must refuse it alike.
                with pytest.raises(pmd.SingularityError, match=re.escape(str(e))):
                    b.forward_dynamics(q, v, x, gravity=G, method=method)
                continue
            same(fa, b.forward_dynamics(q, v, x, gravity=G, method=method), what)
            if a.nloops == 0:  # with loops, inverse dynamics needs a consistent state
                same(
                    a.inverse_dynamics(q, v, x, gravity=G, method=method),
                    b.inverse_dynamics(q, v, x, gravity=G, method=method),
                    what,
                )
        if a.nloops:
            assert a.loop_names == b.loop_names, what
            same(a.constraint_residual(q), b.constraint_residual(q), what)
            same(a.constraint_jacobian(q), b.constraint_jacobian(q), what)
        same_dict(a.denoc(q), b.denoc(q), what)
        for f in ("placements", "point_masses"):
            for xa, xb in zip(getattr(a, f)(q), getattr(b, f)(q)):
                same(xa, xb, f"{what} {f}")
        same(a.bias_forces(q, v, G), b.bias_forces(q, v, G), what)
        same(a.kinetic_energy(q, v), b.kinetic_energy(q, v), what)


@pytest.mark.parametrize("build", ["every_joint", "panda", "chain7"])
def test_models_round_trip_bit_identically(build):
    if build == "every_joint":
        m = every_joint_model()
    elif build == "panda":
        m = pmd.Model.from_urdf(PANDA)
    else:
        m = pmd.load_scene("chain7").model
    for how, c in copies(m):
        assert c is not m
        assert_same_model(m, c, f"{build}, {how}")


def test_urdf_joint_metadata_is_kept():
    m = pmd.Model.from_urdf(PANDA)
    assert m.joint_names and any(np.isfinite(lim[0]) for lim in m.joint_limits().values())
    for how, c in copies(m):
        assert c.joint_names == m.joint_names, how
        assert c.joint_limits() == m.joint_limits(), how
        assert c.joint_dynamics() == m.joint_dynamics(), how


def test_model_copies_are_independent():
    m = every_joint_model()
    c = copy.copy(m)
    c.add_body(pmd.RigidBody(1.0, [0, 0, 0], np.eye(3) * 1e-2), pmd.Revolute([0, 0, 1]), 0)
    assert c.nbodies == m.nbodies + 1 and c.nq == m.nq + 1
    # The copy keeps working with its own workspace.
    q, v, x = random_state(c, np.random.default_rng(1))
    assert np.all(np.isfinite(c.forward_dynamics(q, v, x, gravity=G)))


# --------------------------------------------------------------------------------------------
# Bodies, point masses, joints, events
# --------------------------------------------------------------------------------------------
def test_bodies_and_point_masses_round_trip_exactly():
    body = pmd.RigidBody(2.51, [0.5, -0.0, 1e-300], np.diag([1.255e-4, 0.2092294166666666, 0.2092294166666666]))
    pts = body.point_masses(center=[1.0, 0, 0])
    from_points = pmd.RigidBody.from_point_masses(pts.masses, pts.positions)
    for b in (body, from_points):
        for how, c in copies(b):
            assert type(c) is pmd.RigidBody
            same(c.mass, b.mass, how)
            same(c.com, b.com, how)
            same(c.inertia, b.inertia, how)
            assert repr(c) == repr(b)
            same(c.point_masses().masses, b.point_masses().masses, how)
    for how, c in copies(pts):
        assert type(c) is pmd.PointMasses
        for attr in ("masses", "positions", "half_sides", "center"):
            same(getattr(c, attr), getattr(pts, attr), f"{attr}, {how}")
        same(c.to_body().inertia, pts.to_body().inertia, how)


@pytest.mark.parametrize(
    "joint",
    [
        pmd.Revolute([0, 0.6, 0.8]),
        pmd.Prismatic([1, 2, 3]),
        pmd.SphericalZYZ(),
        pmd.Spherical(),
        pmd.Fixed(),
    ],
    ids=lambda j: j.kind,
)
def test_joints_round_trip_exactly(joint):
    for how, c in copies(joint):
        assert type(c) is pmd.Joint
        assert (c.kind, c.nq, c.nv, repr(c)) == (joint.kind, joint.nq, joint.nv, repr(joint)), how
        if joint.axis is not None:
            same(c.axis, joint.axis, how)


def test_state_events_round_trip_exactly():
    for e in (pmd.StateEvent("q", 2, 0.1 + 0.2, direction=-1, terminal=3), pmd.StateEvent("v", 0)):
        for how, c in copies(e):
            assert type(c) is pmd.StateEvent
            assert (c.terminal, c.direction, repr(c)) == (e.terminal, e.direction, repr(e)), how


# --------------------------------------------------------------------------------------------
# Effects and scenes
# --------------------------------------------------------------------------------------------
def every_effect() -> list[pmd.Effect]:
    t = [0.0, 0.5, 1.0]
    return [
        pmd.Gravity(G),
        pmd.Spring("elbow", stiffness=50.0, rest=0.3),
        pmd.Spring(["elbow", "slide", "wrist"], stiffness=[1.0, 2.0, 3.0], rest=[0.1, 0.2, 0, 0, 0, 1], name="s2"),
        pmd.Damper(None, damping=0.1),
        pmd.Damper([1, "slide"], damping=[0.1, 0.2], name="d2"),
        pmd.JointFriction("elbow", friction=0.2, v_eps=1e-3),
        pmd.JointTorque("slide", tau=-0.5),
        pmd.TabulatedTorque(["elbow", "slide"], time=t, values=[[0, 1], [1, 0], [0.5, 0.5]]),
        pmd.TabulatedTorque("elbow", time=t, values=[0, 1, 0.3], name="tab1d"),
        pmd.PDTorque(["elbow", "slide"], kp=[100, 10], kd=[10, 1], time=t, reference=[[0, 0], [0.5, 0.1], [0.5, 0.1]]),
        pmd.ExternalForce("wrist", force=(0, 0, -5), point=(0.1, 0, 0), frame="world"),
        pmd.ExternalForce("bracket", force=[[0, 0, 1], [0, 1, 0], [1, 0, 0]], moment=[[0, 0, 0.1]] * 3, time=t, frame="body", name="thrust"),
        pmd.TorqueFunction(torque, name="motor"),
        pmd.PointSpring("wrist", (0.1, 0, 0), "world", (0, 0.5, -0.5), 30.0, rest_length=0.2, damping=0.5),
        pmd.PointSpring("base", (0, 0, 0.1), 1, (0.2, 0, 0), 12.0, name="tendon"),
        pmd.GroundContact([("wrist", (0.1, 0, 0)), ("elbow", (0, 0, 0), 0.02)], normal=(0, 0.1, 1),
                          height=-0.5, stiffness=1e5, damping=1e3, friction=0.8),
        pmd.JointLimit(["elbow", "slide"], [-1.0, 0.0], [1.0, 0.3], stiffness=100.0, damping=1.0),
        pmd.PDTorque("elbow", kp=10, kd=1, time=t, reference=[0, 0.1, 0.2], limit=2.0, name="sat"),
    ]


def test_effects_round_trip_and_compare_equal():
    for e in every_effect():
        for how, c in copies(e):
            assert type(c) is pmd.Effect
            assert (c.name, c.kind, repr(c)) == (e.name, e.kind, repr(e)), how
            if e.name != "motor":  # a torque function equals only itself (identity)
                assert c == e, f"{e!r}, {how}"


def full_scene() -> pmd.Scene:
    m = every_joint_model()
    q, v, _ = random_state(m, np.random.default_rng(11))
    return pmd.Scene(
        m, q, 0.1 * v, effects=every_effect(), t_span=(0.0, 0.2), rtol=1e-7, atol=1e-9,
        name="everything", description="every effect", disable=("friction",),
    )


def assert_same_scene(a: pmd.Scene, b: pmd.Scene, what: str, t_span=None):
    assert type(b) is pmd.Scene
    for attr in ("name", "description", "t_span", "rtol", "atol", "max_step", "max_steps",
                 "first_step", "disable"):
        assert getattr(a, attr) == getattr(b, attr), f"{attr}, {what}"
    same(a.q0, b.q0, what)
    same(a.v0, b.v0, what)
    assert [e.name for e in a.effects] == [e.name for e in b.effects]
    ra = pmd.simulate(a, t_span, energy=True, power=True)
    rb = pmd.simulate(b, t_span, energy=True, power=True)
    assert ra.success and rb.success, (ra.message, rb.message)
    for attr in ("t", "q", "v", "energy"):
        same(getattr(ra, attr), getattr(rb, attr), f"{attr}, {what}")
    same_dict(ra.power, rb.power, what)
    assert (ra.nfev, ra.n_accepted, ra.n_rejected) == (rb.nfev, rb.n_accepted, rb.n_rejected)


@pytest.mark.parametrize("name", sorted(pmd.builtin_scenes()))
def test_bundled_scenes_simulate_identically(name):
    s = pmd.load_scene(name)
    for how, c in copies(s):
        assert_same_scene(s, c, f"{name}, {how}", t_span=(0.0, 0.05))
        assert_same_model(s.model, c.model, f"{name}, {how}")


def test_a_scene_with_every_effect_and_setting_simulates_identically():
    s = full_scene()
    for how, c in copies(s):
        assert_same_scene(s, c, how)
        for ea, eb in zip(s.effects, c.effects):
            assert ea == eb or ea.name == "motor", how


def test_torque_function_callable_is_kept_not_dropped():
    s = pmd.Scene(pmd.load_scene("chain7").model, effects=[pmd.Gravity(G), pmd.TorqueFunction(torque)])
    data, callables = _core._dumps(s)
    assert callables == (torque,)
    c = pickle.loads(pickle.dumps(s))
    assert_same_scene(s, c, "module-level function", t_span=(0.0, 0.05))
    # The copy calls the same function: without it the torque would be missing.
    t_off = pmd.simulate(pmd.Scene(s.model, effects=[pmd.Gravity(G)]), (0.0, 0.05))
    assert not np.array_equal(t_off.q, pmd.simulate(c, (0.0, 0.05)).q)


def test_a_lambda_fails_to_pickle_loudly_but_copies():
    s = pmd.Scene(pmd.load_scene("chain7").model, effects=[pmd.TorqueFunction(lambda t, q, v: -v)])
    for p in PROTOCOLS:
        with pytest.raises((pickle.PicklingError, AttributeError)):
            pickle.dumps(s, protocol=p)
        with pytest.raises((pickle.PicklingError, AttributeError)):
            pickle.dumps(s.effects[0], protocol=p)
    # copy/deepcopy keep the lambda itself (functions are atomic to copy).
    for c in (copy.copy(s), copy.deepcopy(s)):
        assert_same_scene(s, c, "lambda", t_span=(0.0, 0.05))


def test_callable_objects_are_deep_copied_with_the_scene():
    class Gain:
        def __init__(self):
            self.k = 0.5

        def __call__(self, t, q, v):
            return -self.k * v

    g = Gain()
    s = pmd.Scene(pmd.load_scene("chain7").model, effects=[pmd.TorqueFunction(g)])
    assert _core._dumps(copy.copy(s))[1][0] is g
    assert _core._dumps(copy.deepcopy(s))[1][0] is not g


# --------------------------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------------------------
def oscillator(t, y):
    return [y[1], -y[0] - 0.1 * y[1]]


def test_dense_solution_and_results_round_trip():
    r = pmd.rk45(oscillator, (0.0, 5.0), [1.0, 0.0], dense_output=True, rtol=1e-8)
    sol = r.sol
    ts = np.linspace(-0.5, 5.5, 301)
    for how, c in copies(sol):
        assert type(c) is type(sol)
        same(c.ts, sol.ts, how)
        same(c(ts), sol(ts), how)
        same(c(2.345), sol(2.345), how)
    back = pickle.loads(pickle.dumps(r))
    assert isinstance(back, pmd.OdeResult) and back.keys() == r.keys()
    same(back.y, r.y)
    same(back.sol(ts), r.sol(ts))
    res = pmd.simulate(pmd.load_scene("pendulum_planar"), (0.0, 0.1), energy=True)
    back = pickle.loads(pickle.dumps(res))
    assert isinstance(back, pmd.SimulationResult)
    for attr in ("t", "q", "v", "energy"):
        same(getattr(back, attr), getattr(res, attr))
    assert back.message == res.message and back.nfev == res.nfev


# --------------------------------------------------------------------------------------------
# Damaged data
# --------------------------------------------------------------------------------------------
def loads_error(data, callables=()) -> BaseException:
    try:
        _load(data, callables)
    except BaseException as exc:  # a PanicException derives from BaseException
        assert type(exc).__name__ != "PanicException", exc
        return exc
    raise AssertionError("damaged data loaded")


def test_damaged_data_raises_our_error_never_a_panic():
    data, _ = _core._dumps(full_scene().model)
    rng = np.random.default_rng(5)
    cases = [b"", b"PMD", b"PMD\x01", b"garbage" * 10, data[:-1], data[:20], data + b"\0"]
    for k in rng.choice(len(data), size=40, replace=False):
        bad = bytearray(data)
        bad[k] ^= 1 << int(rng.integers(8))
        cases.append(bytes(bad))
    for bad in cases:
        exc = loads_error(bad)
        assert isinstance(exc, UnpicklingError), repr(exc)
        assert isinstance(exc, PointMassDynError) and isinstance(exc, pickle.UnpicklingError)
    # Other format versions are refused by name.
    future = bytearray(data)
    future[3] += 1
    exc = loads_error(bytes(future))
    assert isinstance(exc, UnpicklingError) and f"format version {future[3]}" in str(exc)
    # A pickle stream whose payload was altered fails the same way through pickle.loads.
    stream = pickle.dumps(pmd.RigidBody(1.0, [0, 0, 0], np.eye(3)))
    i = stream.index(b"PMD") + 6
    with pytest.raises(UnpicklingError):
        pickle.loads(stream[:i] + bytes([stream[i] ^ 0xFF]) + stream[i + 1 :])


def test_callables_must_match_the_torque_functions():
    s = pmd.Scene(pmd.load_scene("chain7").model, effects=[pmd.TorqueFunction(torque)])
    data, callables = _core._dumps(s)
    assert isinstance(loads_error(data, ()), UnpicklingError)
    assert isinstance(loads_error(data, (torque, torque)), UnpicklingError)
    with pytest.raises(TypeError):
        _core._dumps(object())


# --------------------------------------------------------------------------------------------
# Worker processes (spawn: everything crosses by pickle)
# --------------------------------------------------------------------------------------------
def _simulate_in_worker(scene: pmd.Scene):
    r = pmd.simulate(scene, (0.0, 0.05))
    return r.t, r.q, r.v


def test_scenes_run_in_a_spawned_pool_identically():
    scenes = [pmd.load_scene(n) for n in sorted(pmd.builtin_scenes())]
    scenes.append(pmd.Scene(pmd.load_scene("chain7").model, effects=[pmd.TorqueFunction(torque)]))
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        results = pool.map(_simulate_in_worker, scenes)
    for s, (t, q, v) in zip(scenes, results):
        here = pmd.simulate(s, (0.0, 0.05))
        same(t, here.t, s.name)
        same(q, here.q, s.name)
        same(v, here.v, s.name)
