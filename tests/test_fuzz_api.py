"""Thousands of random calls across the public API (issue 11) with valid, borderline and bad
arguments. The contract, whatever the input:

* no ``PanicException`` (or any other exception) from outside ``pmd.errors``, except
  ``TypeError`` for an argument of the wrong Python type;
* no NaN or inf in a result unless an exception says why;
* no call that allocates without bound: the module runs under an address-space limit, so a
  count taken from a huge number fails here as a MemoryError instead of exhausting the machine.
"""

from __future__ import annotations

import math

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import assert_finite, rod_body
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

ALLOWED = (pmd.errors.PointMassDynError, TypeError)

# Headroom over what the process has mapped when the module starts: far more than any sane
# call here needs, far less than a machine has.
ADDRESS_SPACE_HEADROOM = 6 << 30


@pytest.fixture(autouse=True, scope="module")
def bounded_address_space():
    try:
        import resource

        with open("/proc/self/statm") as f:
            mapped = int(f.read().split()[0]) * resource.getpagesize()
        soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    except (ImportError, OSError):  # not Linux: run unbounded
        yield
        return
    limit = mapped + ADDRESS_SPACE_HEADROOM
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))

# Numbers a user might pass, good and bad: the float edge cases, not just random bits.
edge_floats = st.sampled_from(
    [0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, 5e-324, -5e-324, 1e200, -1e200, 1e300, 1.7e308,
     9e307, math.pi, math.nan, math.inf, -math.inf]
)
floats = st.one_of(st.floats(allow_nan=True, allow_infinity=True), edge_floats,
                   st.floats(-10, 10))
ints = st.one_of(st.integers(-3, 12), st.sampled_from([-1, 2**31, 2**63, 2**70, -(2**70)]))
junk = st.one_of(
    st.none(), st.text(max_size=5), st.binary(max_size=4), st.booleans(),
    st.complex_numbers(allow_nan=False, max_magnitude=10), st.dictionaries(st.text(max_size=2),
    st.integers(), max_size=2), st.just("0.3"), st.just(object()), ints, floats,
)


@st.composite
def arrays(draw, n: int | None = None):
    """A 1-D array-like of length n (most of the time) with edge values, or something else."""
    kind = draw(st.integers(0, 9))
    length = n if n is not None else draw(st.integers(0, 8))
    if kind <= 4:  # the right length, numbers from the edge cases
        return np.array(draw(st.lists(floats, min_size=length, max_size=length)), dtype=float)
    if kind == 5:  # well-behaved values
        return np.array(draw(st.lists(st.floats(-3, 3), min_size=length, max_size=length)))
    if kind == 6:  # the wrong length or shape
        other = draw(st.integers(0, 10))
        return np.zeros(other) if draw(st.booleans()) else np.zeros((length, 2))
    if kind == 7:  # a foreign dtype of the right length
        choice = draw(st.integers(0, 4))
        base = np.arange(length)
        return [base + 1j, base.astype(str), base.astype(object), np.ma.masked_array(base * 1.0,
                mask=base % 2 == 0), base.astype(bool)][choice]
    if kind == 8:
        return draw(st.lists(floats, min_size=length, max_size=length))
    return draw(junk)


def model_zoo() -> list[pmd.Model]:
    """A chain of revolutes and a tree with every joint type (quaternion and Euler)."""
    chain = pmd.Model()
    p = -1
    for k in range(3):
        p = chain.add_body(rod_body(1.0, 0.4, 0.02), pmd.Revolute([0, 1, 0] if k % 2 else [0, 0, 1]),
                           parent=p, translation=[0.4 if k else 0, 0, 0])
    tree = pmd.Model()
    a = tree.add_body(rod_body(), pmd.Spherical(), name="ball")
    b = tree.add_body(rod_body(0.5, 0.3, 0.03), pmd.Prismatic([1, 0, 0]), parent=a,
                      translation=[1, 0, 0], name="slider")
    tree.add_body(rod_body(0.2, 0.2, 0.01), pmd.Fixed(), parent=b, translation=[0, 0.1, 0])
    tree.add_body(rod_body(0.3, 0.2, 0.02), pmd.SphericalZYZ(), parent=a,
                  translation=[0, 0, 0.5], name="euler")
    free = pmd.Model()
    box = free.add_body(rod_body(), pmd.FreeFlyer(), name="box")
    free.add_body(rod_body(0.4, 0.3, 0.02), pmd.Revolute([0, 1, 0]), parent=box,
                  translation=[0.2, 0, 0], name="flap")
    return [chain, tree, free]


MODELS = model_zoo()


def call(data, name: str, f, /, *args, **kwargs):
    """Calls f; the outcome must be a finite result or an allowed exception."""
    try:
        out = f(*args, **kwargs)
    except ALLOWED:
        return None
    except BaseException as exc:
        pytest.fail(f"{name}{args!r:.300} {kwargs!r:.200} raised {type(exc).__module__}."
                    f"{type(exc).__name__}: {exc}")
    assert_finite(name, out)
    return out


def model_calls(data, model: pmd.Model) -> None:
    nq, nv = model.nq, model.nv
    op = data.draw(st.sampled_from([
        "mass_matrix", "mass_matrix_denoc", "forward", "forward_denoc", "inverse", "bias",
        "kinetic", "potential", "gravity_forces", "generalized_forces", "placements",
        "point_masses", "qdot", "denoc", "convective", "body_info", "external",
    ]))
    q = data.draw(arrays(nq))
    v = data.draw(arrays(nv))
    x = data.draw(arrays(nv))
    g = data.draw(st.one_of(arrays(3), st.none()))
    if op == "mass_matrix":
        call(data, op, model.mass_matrix, q)
    elif op == "mass_matrix_denoc":
        call(data, op, model.mass_matrix, q, method=data.draw(st.sampled_from(["denoc", "x", 3])))
    elif op == "forward":
        call(data, op, model.forward_dynamics, q, v, x, gravity=g)
    elif op == "forward_denoc":
        call(data, op, model.forward_dynamics, q, v, x, gravity=g, method="denoc")
    elif op == "inverse":
        call(data, op, model.inverse_dynamics, q, v, x, gravity=g)
    elif op == "bias":
        call(data, op, model.bias_forces, q, v, gravity=g)
    elif op == "kinetic":
        call(data, op, model.kinetic_energy, q, v)
    elif op == "potential":
        call(data, op, model.potential_energy, q, g)
    elif op == "gravity_forces":
        call(data, op, model.gravity_forces, q, g)
    elif op == "generalized_forces":
        forces = data.draw(st.one_of(arrays(None), st.just(np.ones((model.nlinks, 7, 3)) * data.draw(floats))))
        call(data, op, model.generalized_forces, q, forces)
    elif op == "placements":
        call(data, op, model.placements, q)
    elif op == "point_masses":
        call(data, op, model.point_masses, q)
    elif op == "qdot":
        call(data, op, model.velocity_to_qdot, q, v)
    elif op == "denoc":
        call(data, op, model.denoc, q)
    elif op == "convective":
        call(data, op, model.convective_matrix, q, v)
    elif op == "body_info":
        call(data, op, model.body_info, data.draw(st.one_of(ints, junk)))
    elif op == "external":
        ext = data.draw(st.one_of(st.just(np.ones((model.nlinks, 6)) * data.draw(floats)), junk))
        call(data, op, model.forward_dynamics, q, v, x, gravity=g, external=ext)


def build_calls(data) -> None:
    op = data.draw(st.sampled_from(["body", "joint", "add_body", "points", "inertia_about",
                                    "from_points", "event"]))
    if op == "body":
        call(data, op, pmd.RigidBody, data.draw(st.one_of(floats, junk)), data.draw(arrays(3)),
             data.draw(st.one_of(st.builds(lambda d: np.diag(d), st.lists(floats, min_size=3, max_size=3)),
                                 arrays(9), junk)))
    elif op == "joint":
        f = data.draw(st.sampled_from([pmd.Revolute, pmd.Prismatic]))
        call(data, op, f, data.draw(arrays(3)))
    elif op == "add_body":
        m = pmd.Model()
        call(data, op, m.add_body, rod_body(), pmd.Revolute([0, 0, 1]),
             parent=data.draw(st.one_of(ints, junk)), translation=data.draw(arrays(3)),
             rotation=data.draw(st.one_of(st.none(), st.just(np.diag([data.draw(floats)] * 3)), arrays(9))),
             name=data.draw(st.one_of(st.none(), st.text(max_size=4), junk)),
             point_mass_center=data.draw(st.one_of(st.none(), arrays(3))))
    elif op == "points":
        call(data, op, rod_body().point_masses, data.draw(st.one_of(st.none(), arrays(3))))
    elif op == "inertia_about":
        call(data, op, rod_body().inertia_about, data.draw(arrays(3)))
    elif op == "from_points":
        call(data, op, pmd.RigidBody.from_point_masses, data.draw(arrays(7)),
             data.draw(st.one_of(st.just(np.ones((7, 3)) * data.draw(floats)), arrays(None))))
    elif op == "event":
        call(data, op, pmd.StateEvent, data.draw(st.sampled_from(["q", "v", "x", 1])),
             data.draw(st.one_of(ints, junk)), value=data.draw(st.one_of(floats, junk)),
             direction=data.draw(st.one_of(ints, junk)), terminal=data.draw(st.one_of(ints, junk)))


def effect(data, nv: int):
    kind = data.draw(st.integers(0, 7))
    joints = data.draw(st.one_of(st.none(), st.integers(-1, 4), st.sampled_from(["ball", "slider", "nope"]), junk))
    per = data.draw(st.one_of(floats, arrays(None), junk))
    if kind == 0:
        return pmd.Gravity(data.draw(arrays(3)))
    if kind == 1:
        return pmd.Spring(joints, per, data.draw(st.one_of(st.none(), floats)))
    if kind == 2:
        return pmd.Damper(joints, per)
    if kind == 3:
        return pmd.JointFriction(joints, per, v_eps=data.draw(st.one_of(floats, junk)))
    if kind == 4:
        return pmd.JointTorque(joints, per)
    if kind == 5:
        return pmd.TabulatedTorque(joints, data.draw(arrays(None)), data.draw(arrays(None)))
    if kind == 6:
        return pmd.PDTorque(joints, per, per, data.draw(arrays(None)), data.draw(arrays(None)))
    return pmd.ExternalForce(data.draw(st.one_of(st.integers(-1, 4), junk)), force=data.draw(arrays(3)),
                             point=data.draw(arrays(3)), moment=data.draw(st.one_of(st.none(), arrays(3))),
                             frame=data.draw(st.sampled_from(["world", "body", "x"])))


def scene_calls(data, model: pmd.Model) -> None:
    effects = []
    for _ in range(data.draw(st.integers(0, 3))):
        try:
            effects.append(effect(data, model.nv))
        except ALLOWED:
            pass
        except BaseException as exc:
            pytest.fail(f"effect factory raised {type(exc).__name__}: {exc}")
    good_state = data.draw(st.booleans())
    q0 = model.neutral() if good_state else data.draw(arrays(model.nq))
    v0 = np.zeros(model.nv) if good_state else data.draw(arrays(model.nv))
    scene = call(data, "Scene", pmd.Scene, model, q0, v0, effects=effects,
                 rtol=data.draw(st.one_of(st.none(), floats)))
    if scene is None:
        return
    op = data.draw(st.sampled_from(["simulate", "energies", "effect_forces"]))
    if op == "simulate":
        call(data, op, pmd.simulate, scene, data.draw(st.one_of(st.just((0.0, 0.05)), arrays(2), junk)),
             rtol=data.draw(st.one_of(st.none(), st.sampled_from([1e-3, 1e-8, 0.0, -1.0, math.nan]), junk)),
             atol=data.draw(st.one_of(st.none(), st.sampled_from([1e-6, 1e-300, math.inf]), arrays(model.nq + model.nv))),
             max_step=data.draw(st.one_of(st.none(), floats)), max_steps=200,
             energy=data.draw(st.booleans()), power=data.draw(st.booleans()),
             t_eval=data.draw(st.one_of(st.none(), arrays(None))),
             first_step=data.draw(st.one_of(st.none(), floats)))
    elif op == "energies":
        call(data, op, pmd.energies, scene, data.draw(arrays(model.nq)), data.draw(arrays(model.nv)))
    else:
        call(data, op, pmd.effect_forces, scene, data.draw(st.one_of(floats, junk)),
             data.draw(arrays(model.nq)), data.draw(arrays(model.nv)))


def rk45_calls(data) -> None:
    y0 = data.draw(arrays(None))
    scale = data.draw(floats)

    def fun(t, y):
        with np.errstate(all="ignore"):  # overflow here is the point: rk45 must report it
            return -scale * np.asarray(y)

    r = call(data, "rk45", pmd.rk45, fun, data.draw(st.one_of(st.just((0.0, 1.0)), arrays(2), junk)),
             y0, rtol=data.draw(st.one_of(st.sampled_from([1e-3, 1e-9]), floats, junk)),
             atol=data.draw(st.one_of(st.sampled_from([1e-6]), floats, arrays(None))),
             max_steps=100, dense_output=data.draw(st.booleans()),
             first_step=data.draw(st.one_of(st.none(), floats)))
    if r is not None and r.get("sol") is not None:
        call(data, "sol", r.sol, data.draw(st.one_of(floats, arrays(None), junk)))


FOURBAR = pmd.load_scene("fourbar")
PENDULUM = pmd.load_scene("pendulum_planar")
points_arg = st.one_of(
    st.none(),
    st.just([("crank", [0.1, 0.0, 0.0])]),
    st.lists(st.tuples(st.one_of(st.sampled_from(["crank", "coupler", "nope"]), ints, junk),
                       st.one_of(arrays(3), junk)), max_size=3),
    junk,
)


def newer_model_calls(data, model: pmd.Model) -> None:
    """Derivatives, point motions, shaking and bearing forces, poses (issue 29)."""
    nq, nv = model.nq, model.nv
    q, v, x = data.draw(arrays(nq)), data.draw(arrays(nv)), data.draw(arrays(nv))
    g = data.draw(st.one_of(arrays(3), st.none()))
    op = data.draw(st.sampled_from(["fd_derivs", "id_derivs", "point_motion", "regressor",
                                    "shaking", "bearing", "poses", "poses_stack"]))
    if op == "fd_derivs":
        call(data, op, model.forward_dynamics_derivatives, q, v, x, gravity=g)
    elif op == "id_derivs":
        call(data, op, model.inverse_dynamics_derivatives, q, v, x, gravity=g)
    elif op == "point_motion":
        call(data, op, model.point_motion, q, v, x)
    elif op == "regressor":
        call(data, op, model.point_regressor, q, v, x, points=data.draw(points_arg), gravity=g)
    elif op == "shaking":
        call(data, op, model.shaking, q, v, x, about=data.draw(st.one_of(st.none(), arrays(3))))
    elif op == "bearing":
        call(data, op, model.bearing_forces, q, v, x, gravity=g)
    elif op == "poses":
        call(data, op, model.body_poses, q)
    else:
        call(data, op, model.body_poses, np.tile(model.neutral(), (2, 1)) * data.draw(floats))


def newer_scene_calls(data, model: pmd.Model) -> None:
    """Scene derivatives, every integrator, solve_ivp with jac, batches (issue 29)."""
    scene = pmd.Scene(model, model.neutral(), np.zeros(model.nv),
                      effects=[pmd.Gravity([0, 0, -9.81])])
    nq, nv = model.nq, model.nv
    op = data.draw(st.sampled_from(["fd_derivs", "state_jacobian", "methods", "solve_ivp",
                                    "batch"]))
    if op == "fd_derivs":
        call(data, op, scene.forward_dynamics_derivatives, data.draw(arrays(nq)),
             data.draw(arrays(nv)), data.draw(st.one_of(st.none(), arrays(nv))),
             t=data.draw(floats))
    elif op == "state_jacobian":
        call(data, op, scene.state_jacobian, data.draw(arrays(nq + nv)), t=data.draw(floats))
    elif op == "methods":
        call(data, op, pmd.simulate, scene, (0.0, 0.05),
             method=data.draw(st.sampled_from(["RK45", "DOP853", "RK4", "Euler", "Radau", "auto",
                                               "rk45", None, 3])),
             dt=data.draw(st.one_of(st.none(), st.sampled_from([1e-3, 0.0, -1.0]), floats)),
             rtol=data.draw(st.one_of(st.none(), st.sampled_from([1e-6, 0.0, -1.0, math.nan]))),
             atol=data.draw(st.one_of(st.none(), st.sampled_from([1e-9, 0.0, -1.0, math.nan]))),
             max_steps=200)
    elif op == "solve_ivp":
        n = data.draw(st.integers(1, 3))
        jac = data.draw(st.one_of(st.none(), st.just(lambda t, y: -np.eye(n)),
                                  st.just(lambda t, y: np.eye(n + 1)), arrays(n * n),
                                  st.just(np.full((n, n), data.draw(floats))), junk))
        call(data, op, pmd.solve_ivp, lambda t, y: -np.asarray(y), (0.0, 1.0), np.ones(n),
             method=data.draw(st.sampled_from(["RK45", "Radau", "auto", "RK4", "DOP853"])),
             dt=0.1, jac=jac, max_steps=200,
             rtol=data.draw(st.one_of(st.sampled_from([1e-6, 0.0, -1.0, math.nan]), floats)),
             atol=data.draw(st.one_of(st.sampled_from([1e-9, 0.0, -1.0, math.nan]), floats)))
    else:
        call(data, op, pmd.simulate_batch, scene, (0.0, 0.05), t_eval=[0.0, 0.05],
             q0=data.draw(st.one_of(st.none(), st.just(np.tile(model.neutral(), (2, 1))),
                                    arrays(None))),
             threads=data.draw(st.one_of(st.none(), st.integers(-1, 3), junk)),
             params=data.draw(st.one_of(st.none(), st.just({"gravity": [[0, 0, -9.81]] * 2}),
                                        st.dictionaries(st.sampled_from(["gravity", "x"]),
                                                        st.one_of(arrays(None), junk),
                                                        max_size=1))),
             max_steps=200)


def design_calls(data) -> None:
    """Shaking analysis along prescribed motions of the bundled fourbar (issue 29)."""
    model = FOURBAR.model
    op = data.draw(st.sampled_from(["prescribed", "analyze", "to_mjcf"]))
    if op == "prescribed":
        call(data, op, pmd.prescribed_motion, model,
             data.draw(st.one_of(st.sampled_from(["crank", "coupler", "nope"]), ints, junk)),
             speed=data.draw(st.one_of(st.none(), floats)),
             samples=data.draw(st.one_of(st.integers(-1, 12), junk)),
             revolutions=data.draw(st.one_of(floats, st.just(1.0))), q_guess=FOURBAR.q0)
    elif op == "analyze":
        n = data.draw(st.integers(0, 3))
        call(data, op, pmd.analyze_motion, model, data.draw(arrays(n)),
             np.tile(FOURBAR.q0, (data.draw(st.integers(0, 3)), 1)), np.zeros((n, model.nv)),
             data.draw(st.one_of(st.just(np.zeros((n, model.nv))), arrays(None))),
             actuated=["crank"])
    else:
        call(data, op, pmd.to_mjcf, data.draw(st.sampled_from([PENDULUM, PENDULUM.model] + MODELS)),
             timestep=data.draw(st.one_of(floats, junk)),
             integrator=data.draw(st.sampled_from(["RK4", "Euler", "x", 3])))


def loop_calls(data) -> None:
    """Closed loops on a copy of the bundled fourbar: cut joints of any kind between any
    bodies, assembly with any held coordinates and iteration counts (issue 29, round 2)."""
    import pickle

    model = pickle.loads(pickle.dumps(FOURBAR.model))
    q0 = FOURBAR.q0
    body = st.one_of(st.sampled_from(["crank", "coupler", "rocker", "world", None, "nope"]),
                     ints, junk)
    op = data.draw(st.sampled_from(["add_loop", "assemble", "velocity", "forces"]))
    if op == "add_loop":
        call(data, op, model.add_loop, data.draw(body), data.draw(body),
             data.draw(st.sampled_from([pmd.Revolute([0, 0, 1]), pmd.Prismatic([1, 0, 0]),
                                        pmd.Spherical(), pmd.Fixed(), pmd.FreeFlyer()])),
             translation_a=data.draw(st.one_of(st.none(), arrays(3))),
             rotation_b=data.draw(st.one_of(st.none(), st.just(np.eye(3)), arrays(9))),
             name=data.draw(st.one_of(st.none(), st.text(max_size=3), junk)))
    elif op == "assemble":
        call(data, op, model.assemble, data.draw(st.one_of(st.just(q0 + 0.05), arrays(model.nq))),
             fixed=data.draw(st.one_of(st.none(), st.lists(st.one_of(ints, body), max_size=3),
                                       body)),
             tol=data.draw(st.one_of(st.just(1e-12), floats)),
             max_iterations=data.draw(st.one_of(st.just(50), ints, junk)))
    elif op == "velocity":
        call(data, op, model.assemble_velocity, q0, data.draw(arrays(model.nv)),
             fixed=data.draw(st.one_of(st.none(), st.lists(ints, max_size=3), body)))
    else:
        call(data, op, model.constraint_forces, q0, data.draw(arrays(model.nv)),
             data.draw(arrays(model.nv)), gravity=data.draw(st.one_of(st.none(), arrays(3))))


def visual_calls(data, model: pmd.Model) -> None:
    """set_visuals with random shapes, then the page's geometry (issue 29, round 2)."""
    import pickle

    from pointmass_dyn.viewer import _meshes

    model = pickle.loads(pickle.dumps(model))
    kind = data.draw(st.sampled_from(["box", "cylinder", "sphere", "capsule", "ellipsoid",
                                      "mesh", "teapot"]))
    size = {"box": {"size": data.draw(arrays(3))},
            "cylinder": {"radius": data.draw(floats), "length": data.draw(floats)},
            "sphere": {"radius": data.draw(floats)},
            "capsule": {"radius": data.draw(floats), "length": data.draw(floats)},
            "ellipsoid": {"radii": data.draw(arrays(3))},
            "mesh": {"uri": data.draw(st.text(max_size=4)),
                     "path": data.draw(st.one_of(st.none(), st.text(max_size=4),
                                                 st.just("/dev/null"), st.just("/tmp"))),
                     "scale": data.draw(arrays(3))},
            "teapot": {}}[kind]
    visual = {"body": data.draw(st.one_of(st.integers(-1, 4), junk)), "kind": kind,
              "rotation": data.draw(st.one_of(st.just(np.eye(3)), arrays(9))),
              "translation": data.draw(arrays(3)),
              "rgba": data.draw(st.one_of(st.none(), arrays(4))), **size}
    call(data, "set_visuals", model.set_visuals, [visual])
    if model.visuals:  # accepted (the zoo's models have none of their own)
        scene = _meshes.visual_scene(model, warn=False)
        for mesh in scene.meshes:
            assert np.isfinite(mesh.vertices).all(), visual


@settings(max_examples=300, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
@given(st.data())
def test_random_calls_to_loops_and_visuals(data):
    if data.draw(st.booleans()):
        loop_calls(data)
    else:
        visual_calls(data, data.draw(st.sampled_from(MODELS)))


@settings(max_examples=600, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
@given(st.data())
def test_random_calls_to_the_newer_entry_points(data):
    area = data.draw(st.sampled_from(["model", "scene", "design"]))
    model = data.draw(st.sampled_from(MODELS))
    if area == "model":
        newer_model_calls(data, model)
    elif area == "scene":
        newer_scene_calls(data, model)
    else:
        design_calls(data)


@settings(max_examples=2500, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
@given(st.data())
def test_random_calls_across_the_public_api(data):
    area = data.draw(st.sampled_from(["model", "model", "build", "scene", "rk45"]))
    model = data.draw(st.sampled_from(MODELS))
    if area == "model":
        model_calls(data, model)
    elif area == "build":
        build_calls(data)
    elif area == "scene":
        scene_calls(data, model)
    else:
        rk45_calls(data)
