"""Bad input: every validation rule raises the right class of pointmass_dyn.errors with a
message that names the argument (and the expected shape where one is wrong); nothing ever
escapes as a Rust panic (pyo3's PanicException, a BaseException)."""

from __future__ import annotations

import math

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import (
    BodySpec,
    G,
    TreeSpec,
    assert_finite,
    build_model,
    paper_pendulum_tree,
    rod_body,
)
from hypothesis import given, settings
from hypothesis import strategies as st
from pointmass_dyn import errors

NAN, INF = math.nan, math.inf
I3 = np.eye(3)


def test_hierarchy():
    assert issubclass(errors.InvalidInputError, ValueError)
    assert issubclass(errors.InvalidInputError, errors.PointMassDynError)
    assert issubclass(errors.InertiaError, errors.InvalidInputError)
    assert issubclass(errors.ModelStructureError, errors.InvalidInputError)
    assert issubclass(errors.SingularityError, ArithmeticError)
    assert pmd.InvalidInputError is errors.InvalidInputError


def raises(cls, *words):
    """pytest.raises(cls) whose message must contain every word (case-sensitive)."""

    class _Ctx:
        def __enter__(self):
            self.ctx = pytest.raises(cls)
            self.info = self.ctx.__enter__()
            return self.info

        def __exit__(self, *exc):
            out = self.ctx.__exit__(*exc)
            msg = str(self.info.value)
            assert type(self.info.value).__name__ != "PanicException"
            for w in words:
                assert w in msg, (w, msg)
            return out

    return _Ctx()


# ---------------------------------------------------------------------------------------------
# RigidBody
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("mass", [0.0, -1.0, -1e-300, NAN, INF, -INF])
def test_bad_mass(mass):
    with raises(errors.InertiaError, "mass"):
        pmd.RigidBody(mass, [0, 0, 0], I3)


@pytest.mark.parametrize(
    "com, words",
    [
        ([0.0, NAN, 0.0], ("com", "finite")),
        ([INF, 0.0, 0.0], ("com", "finite")),
        ([0.0, 0.0], ("com", "(3,)", "(2,)")),
        ([[0.0, 0.0, 0.0]], ("com", "(3,)", "(1, 3)")),
        ("abc", ("com",)),
    ],
)
def test_bad_com(com, words):
    with raises(errors.InvalidInputError, *words):
        pmd.RigidBody(1.0, com, I3)


@pytest.mark.parametrize(
    "inertia, cls, words",
    [
        (np.diag([1.0, 1.0, NAN]), errors.InvalidInputError, ("inertia", "finite")),
        (np.eye(2), errors.InvalidInputError, ("inertia", "(3, 3)", "(2, 2)")),
        (np.ones(9), errors.InvalidInputError, ("inertia", "(3, 3)", "(9,)")),
        ([[1, 0.1, 0], [0, 1, 0], [0, 0, 1]], errors.InertiaError, ("inertia", "symmetric")),
        (-np.eye(3), errors.InertiaError, ("inertia", "semidefinite")),
        (np.diag([1.0, 2.0, -0.5]), errors.InertiaError, ("inertia", "semidefinite")),
        (np.diag([1.0, 1.0, 3.0]), errors.InertiaError, ("inertia", "triangle")),
        (np.diag([0.0, 0.0, 1.0]), errors.InertiaError, ("inertia", "triangle")),
    ],
)
def test_bad_inertia(inertia, cls, words):
    with raises(cls, *words):
        pmd.RigidBody(1.0, [0, 0, 0], inertia)


def test_valid_boundary_bodies_are_accepted():
    """Flat plate (on the triangle inequality), rod without axial inertia, point mass, and a
    tensor rounded at the 1e-12 level: valid."""
    pmd.RigidBody(1.0, [0, 0, 0], np.diag([1.0, 2.0, 3.0]))
    pmd.RigidBody(1.0, [0, 0, 0], np.diag([0.0, 1.0, 1.0]))
    pmd.RigidBody(1.0, [0, 0, 0], np.zeros((3, 3)))
    pmd.RigidBody(1.0, [0, 0, 0], np.diag([1.0, 2.0, 3.0 + 1e-12]))
    # Lists and integer arrays are accepted.
    b = pmd.RigidBody(2, np.array([0, 1, 0]), np.eye(3, dtype=int).tolist())
    assert b.com.dtype == np.float64 and b.inertia.dtype == np.float64


def test_bad_point_mass_arguments():
    body = rod_body()
    with raises(errors.InvalidInputError, "center", "(3,)"):
        body.point_masses([0, 0])
    with raises(errors.InvalidInputError, "center", "finite"):
        body.point_masses([0, 0, NAN])
    with raises(errors.InvalidInputError, "point", "finite"):
        body.inertia_about([INF, 0, 0])
    with raises(errors.InvalidInputError, "positions"):
        pmd.RigidBody.from_point_masses([1.0, 2.0], [[0, 0, 0]])
    with raises(errors.InvalidInputError, "positions", "(n, 3)"):
        pmd.RigidBody.from_point_masses([1.0], [0, 0, 0])
    with raises(errors.InvalidInputError, "masses"):
        pmd.RigidBody.from_point_masses(np.ones((2, 2)), np.zeros((4, 3)))
    with raises(errors.InvalidInputError, "masses", "finite"):
        pmd.RigidBody.from_point_masses([1.0, NAN], np.zeros((2, 3)))
    with raises(errors.InertiaError, "masses"):
        pmd.RigidBody.from_point_masses([1.0, -2.0], [[0, 0, 0], [1, 0, 0]])
    with raises(errors.InvalidInputError, "positions"):
        pmd.RigidBody.from_point_masses([], np.zeros((0, 3)))


@pytest.mark.parametrize("make", [pmd.Revolute, pmd.Prismatic])
@pytest.mark.parametrize(
    "axis, words",
    [([0, 0, 0], ("axis", "non-zero")), ([NAN, 0, 1], ("axis",)), ([1, 0], ("axis", "(3,)"))],
)
def test_bad_axis(make, axis, words):
    with raises(errors.InvalidInputError, *words):
        make(axis)


# ---------------------------------------------------------------------------------------------
# Model structure
# ---------------------------------------------------------------------------------------------


def one_body_model():
    m = pmd.Model()
    m.add_body(rod_body(), pmd.Spherical(), name="a")
    return m


@pytest.mark.parametrize(
    "kwargs, cls, words",
    [
        ({"parent": 1}, errors.ModelStructureError, ("parent", "1")),
        ({"parent": 7}, errors.ModelStructureError, ("parent", "7")),
        ({"parent": -2}, errors.ModelStructureError, ("parent", "-2")),
        ({"name": "a"}, errors.ModelStructureError, ("name", "'a'")),
        ({"rotation": 2 * I3}, errors.InvalidInputError, ("rotation",)),
        (
            {"rotation": np.diag([1.0, 1.0, -1.0])},
            errors.InvalidInputError,
            ("rotation", "determinant"),
        ),
        (
            {"rotation": [[1, 0.01, 0], [0, 1, 0], [0, 0, 1]]},
            errors.InvalidInputError,
            ("rotation",),
        ),
        ({"rotation": np.eye(2)}, errors.InvalidInputError, ("rotation", "(3, 3)")),
        ({"rotation": np.full((3, 3), NAN)}, errors.InvalidInputError, ("rotation", "finite")),
        ({"translation": [0, 0]}, errors.InvalidInputError, ("translation", "(3,)")),
        ({"translation": [0, 0, INF]}, errors.InvalidInputError, ("translation", "finite")),
        ({"point_mass_center": [0, 0]}, errors.InvalidInputError, ("point_mass_center", "(3,)")),
        (
            {"point_mass_center": [0, NAN, 0]},
            errors.InvalidInputError,
            ("point_mass_center", "finite"),
        ),
    ],
)
def test_bad_add_body_leaves_model_unchanged(kwargs, cls, words):
    model = one_body_model()
    with raises(cls, *words):
        model.add_body(rod_body(), pmd.Revolute([0, 0, 1]), **{"parent": 0, **kwargs})
    assert (model.nbodies, model.nq, model.nv, model.nlinks) == (1, 4, 3, 1)
    assert model.body_names == ["a"]
    # The model still works.
    assert model.mass_matrix([0, 0, 0, 1]).shape == (3, 3)


def test_rotation_rounded_input_is_accepted_and_reorthonormalised():
    """A rotation with 1e-12 rounding is a rotation (tolerance 1e-9)."""
    c, s = math.cos(0.3), math.sin(0.3)
    r = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) + 1e-12
    model = pmd.Model()
    model.add_body(rod_body(), pmd.Revolute([0, 1, 0]), rotation=r)
    rots, _ = model.placements([0.0])
    np.testing.assert_allclose(rots[0] @ rots[0].T, I3, atol=1e-15)


def test_body_info_index():
    model = one_body_model()
    with raises(errors.ModelStructureError, "index"):
        model.body_info(3)


# ---------------------------------------------------------------------------------------------
# States and arguments of the dynamics functions
# ---------------------------------------------------------------------------------------------


def mixed_model():
    """Spherical (nq 4, nv 3) + Revolute + ZYZ: nq = 8, nv = 7."""
    m = pmd.Model()
    m.add_body(rod_body(), pmd.Spherical())
    m.add_body(rod_body(), pmd.Revolute([0, 1, 0]), parent=0, translation=[1, 0, 0])
    m.add_body(rod_body(), pmd.SphericalZYZ(), parent=1, translation=[1, 0, 0])
    assert (m.nq, m.nv) == (8, 7)
    return m


Q = np.array([0, 0, 0, 1, 0.3, 0.2, 0.7, 0.1])
V = np.linspace(-1, 1, 7)


def calls(model, q=Q, v=V, x=V):
    """Every state-taking method, as (name, thunk)."""
    return [
        ("mass_matrix", lambda: model.mass_matrix(q)),
        ("mass_matrix denoc", lambda: model.mass_matrix(q, method="denoc")),
        ("convective_matrix", lambda: model.convective_matrix(q, v)),
        ("gravity_forces", lambda: model.gravity_forces(q, G)),
        ("bias_forces", lambda: model.bias_forces(q, v, G)),
        ("forward_dynamics", lambda: model.forward_dynamics(q, v, x, G)),
        ("forward_dynamics denoc", lambda: model.forward_dynamics(q, v, x, G, method="denoc")),
        ("inverse_dynamics", lambda: model.inverse_dynamics(q, v, x, G)),
        ("inverse_dynamics denoc", lambda: model.inverse_dynamics(q, v, x, G, method="denoc")),
        ("denoc", lambda: model.denoc(q)),
        ("denoc_rates", lambda: model.denoc_rates(q, v)),
        ("point_masses", lambda: model.point_masses(q)),
        ("placements", lambda: model.placements(q)),
        ("kinetic_energy", lambda: model.kinetic_energy(q, v)),
        ("potential_energy", lambda: model.potential_energy(q, G)),
        ("velocity_to_qdot", lambda: model.velocity_to_qdot(q, v)),
    ]


def uses(name, arg):
    if arg == "q":
        return True
    if arg == "v":
        return name.split()[0] in (
            "convective_matrix",
            "bias_forces",
            "forward_dynamics",
            "inverse_dynamics",
            "denoc_rates",
            "kinetic_energy",
            "velocity_to_qdot",
        )
    if arg == "x":
        return name.split()[0] in ("forward_dynamics", "inverse_dynamics")
    raise AssertionError(arg)


@pytest.mark.parametrize(
    "bad_q, words",
    [
        (Q[:7], ("q", "(8,)", "(7,)")),
        (np.append(Q, 0.0), ("q", "(8,)", "(9,)")),
        (Q.reshape(2, 4), ("q", "(8,)", "(2, 4)")),
        (np.where(np.arange(8) == 5, NAN, Q), ("q", "finite")),
        (np.where(np.arange(8) == 2, INF, Q), ("q", "finite")),
        (np.r_[0, 0, 0, 0, Q[4:]], ("q", "quaternion")),
    ],
)
def test_bad_q_everywhere(bad_q, words):
    model = mixed_model()
    for _name, call in calls(model, q=bad_q):
        with raises(errors.InvalidInputError, *words):
            call()


@pytest.mark.parametrize(
    "bad, words",
    [
        (V[:6], ("(7,)", "(6,)")),
        (np.r_[V, 1.0], ("(7,)", "(8,)")),
        (np.where(np.arange(7) == 3, NAN, V), ("finite",)),
        (np.where(np.arange(7) == 0, -INF, V), ("finite",)),
    ],
)
def test_bad_v_tau_a_everywhere(bad, words):
    model = mixed_model()
    for arg in ("v", "x"):
        for name, call in calls(model, **{arg: bad}):
            if not uses(name, arg):
                continue
            argname = "v" if arg == "v" else ("tau" if name.startswith("forward") else "a")
            with raises(errors.InvalidInputError, argname, *words):
                call()


@pytest.mark.parametrize("method", ["fast", "Recursive", "", "DENOC"])
def test_bad_method(method):
    model = mixed_model()
    for call in (
        lambda: model.mass_matrix(Q, method=method),
        lambda: model.forward_dynamics(Q, V, V, method=method),
        lambda: model.inverse_dynamics(Q, V, V, method=method),
    ):
        with raises(errors.InvalidInputError, "method", "recursive", "denoc"):
            call()


@pytest.mark.parametrize(
    "gravity, words", [([0, 0], ("(3,)",)), ([0, 0, NAN], ("finite",)), (np.eye(3), ("(3,)",))]
)
def test_bad_gravity(gravity, words):
    model = mixed_model()
    for call in (
        lambda: model.gravity_forces(Q, gravity),
        lambda: model.bias_forces(Q, V, gravity),
        lambda: model.forward_dynamics(Q, V, V, gravity),
        lambda: model.inverse_dynamics(Q, V, V, gravity),
        lambda: model.potential_energy(Q, gravity),
    ):
        with raises(errors.InvalidInputError, "gravity", *words):
            call()


def test_bad_external_and_point_forces():
    model = mixed_model()
    with raises(errors.InvalidInputError, "external", "(3, 6)"):
        model.forward_dynamics(Q, V, V, external=np.zeros((2, 6)))
    with raises(errors.InvalidInputError, "external", "finite"):
        model.inverse_dynamics(Q, V, V, external=np.full((3, 6), NAN))
    with raises(errors.InvalidInputError, "external", "denoc"):
        model.forward_dynamics(Q, V, V, external=np.zeros((3, 6)), method="denoc")
    with raises(errors.InvalidInputError, "forces"):
        model.generalized_forces(Q, np.zeros((20, 3)))
    with raises(errors.InvalidInputError, "forces", "finite"):
        model.generalized_forces(Q, np.full((21, 3), NAN))


def test_lists_ints_and_strided_arrays_are_accepted():
    model = mixed_model()
    ref = model.forward_dynamics(Q, V, V, G)
    strided = np.zeros(16)
    strided[::2] = Q
    assert np.array_equal(model.forward_dynamics(list(Q), list(V), list(V), list(G)), ref)
    assert np.array_equal(model.forward_dynamics(strided[::2], V, V, G), ref)
    assert np.array_equal(
        model.forward_dynamics(Q.astype(np.float32).astype(float), V, V, G).shape, ref.shape
    )
    qi = np.array([0, 0, 0, 1, 0, 1, 1, 1])
    assert np.array_equal(model.mass_matrix(qi), model.mass_matrix(qi.astype(float)))


def layouts(a):
    """The same 2-D values as a C-ordered array and as a Fortran-ordered one."""
    a = np.array(a, dtype=float)
    f = np.asfortranarray(a)
    assert f.flags.f_contiguous and not f.flags.c_contiguous and np.array_equal(a, f)
    return np.ascontiguousarray(a), f


def test_fortran_ordered_rotation_is_read_by_value():
    c, s = math.cos(0.5), math.sin(0.5)
    rc, rf = layouts([[1, 0, 0], [0, c, -s], [0, s, c]])
    results = []
    for r in (rc, rf):
        model = pmd.Model()
        model.add_body(rod_body(), pmd.Revolute([0, 0, 1]), rotation=r)
        results.append(model.placements([0.0])[0][0])
    np.testing.assert_array_equal(results[0], rc)
    # Got: the transpose of R for the Fortran-ordered copy (also for rotation=R.T, a view).
    np.testing.assert_array_equal(results[1], rc)


def test_fortran_ordered_positions_are_read_by_value():
    pc, pf = layouts([[0, 0, 0], [1, 2, 3], [0, 0, 1]])
    np.testing.assert_allclose(
        pmd.RigidBody.from_point_masses([1, 1, 1], pc).com, [1 / 3, 2 / 3, 4 / 3]
    )
    # Got: [0, 2, 1/3].
    np.testing.assert_allclose(
        pmd.RigidBody.from_point_masses([1, 1, 1], pf).com, [1 / 3, 2 / 3, 4 / 3]
    )


def test_fortran_ordered_external_wrenches_are_read_by_value():
    model = mixed_model()
    ec, ef = layouts(np.arange(18.0).reshape(3, 6) / 10)
    np.testing.assert_array_equal(
        model.forward_dynamics(Q, V, V, G, external=ef),
        model.forward_dynamics(Q, V, V, G, external=ec),
    )


# ---------------------------------------------------------------------------------------------
# Singular states
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "q",
    [
        [0.0, 0.0, 0.0],
        [0.3, 0.0, 0.2],
        [0.3, math.pi, 0.2],
        [-2.0, -math.pi, 1.0],
        [0.3, 1e-12, 0.2],
    ],
    ids=["theta=0 phi=0", "theta=0", "theta=pi", "theta=-pi", "theta=1e-12"],
)
@pytest.mark.parametrize("method", ["recursive", "denoc"])
def test_zyz_singularity_is_singularity_error(q, method):
    model = build_model(paper_pendulum_tree())
    with raises(errors.SingularityError):
        model.forward_dynamics(q, [0, 1, 0], [0, 0, 0], G, method=method)


@pytest.mark.parametrize("method", ["recursive", "denoc"])
def test_zyz_singular_state_still_has_mass_matrix_and_inverse_dynamics(method):
    model = build_model(paper_pendulum_tree())
    q = [0.3, 0.0, 0.2]
    m = model.mass_matrix(q, method=method)
    eig = np.linalg.eigvalsh(m)
    assert abs(eig[0]) <= 1e-14 * eig[-1] and eig[1] > 0.1 * eig[-1]  # rank 2, as L(φ, 0) is
    assert np.all(np.isfinite(model.inverse_dynamics(q, [0, 1, 0], [0, 0, 0], G, method=method)))


# ---------------------------------------------------------------------------------------------
# No panics, whatever comes in
# ---------------------------------------------------------------------------------------------

junk_scalars = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-(10**20), 10**20),
    st.sampled_from([0.0, -0.0, 1e-320, 1e308, -1e308]),
)
junk = st.one_of(
    st.none(),
    st.text(max_size=3),
    junk_scalars,
    st.lists(junk_scalars, max_size=10),
    st.lists(st.lists(junk_scalars, min_size=3, max_size=3), max_size=4),
    st.integers(0, 10).map(lambda n: np.zeros(n)),
    st.integers(0, 10).map(lambda n: np.ones((n, 3))),
    st.lists(junk_scalars, min_size=8, max_size=8).map(np.array),
    st.lists(junk_scalars, min_size=7, max_size=7).map(np.array),
)


def no_panic(thunk):
    """The fuzz tests' contract (tests/test_fuzz_api.py): an error of ours or a ``TypeError``
    (a wrong Python type), else a finite result."""
    try:
        out = thunk()
    except (errors.PointMassDynError, TypeError):
        return
    except BaseException as e:
        pytest.fail(f"{type(e).__module__}.{type(e).__name__}: {e}")
    assert_finite("result", out)


@settings(max_examples=300, deadline=None)
@given(a=junk, b=junk, c=junk, d=junk)
def test_no_panic_on_junk(a, b, c, d):
    model = mixed_model()
    for thunk in (
        lambda: pmd.RigidBody(1.0, a, b),
        lambda: pmd.RigidBody(a, [0, 0, 0], I3),
        lambda: pmd.RigidBody.from_point_masses(a, b),
        lambda: rod_body().point_masses(a),
        lambda: pmd.Revolute(a),
        lambda: pmd.Prismatic(a),
        lambda: model.add_body(rod_body(), pmd.Fixed(), parent=0, translation=a, rotation=b),
        lambda: model.mass_matrix(a),
        lambda: model.mass_matrix(a, method="denoc"),
        lambda: model.convective_matrix(a, b),
        lambda: model.gravity_forces(a, b),
        lambda: model.bias_forces(a, b, c),
        lambda: model.forward_dynamics(a, b, c, d),
        lambda: model.forward_dynamics(Q, a, b, c, method="denoc"),
        lambda: model.inverse_dynamics(a, b, c, d),
        lambda: model.inverse_dynamics(Q, V, a, b, external=c),
        lambda: model.forward_dynamics(Q, V, V, G, external=a),
        lambda: model.generalized_forces(a, b),
        lambda: model.denoc(a),
        lambda: model.denoc_rates(a, b),
        lambda: model.point_masses(a),
        lambda: model.placements(a),
        lambda: model.kinetic_energy(a, b),
        lambda: model.potential_energy(a, b),
        lambda: model.velocity_to_qdot(a, b),
    ):
        no_panic(thunk)


@settings(max_examples=60, deadline=None)
@given(
    q=st.lists(st.floats(-1e300, 1e300), min_size=8, max_size=8),
    v=st.lists(st.floats(-1e300, 1e300), min_size=7, max_size=7),
    x=st.lists(st.floats(-1e300, 1e300), min_size=7, max_size=7),
)
def test_no_panic_on_extreme_finite_states(q, v, x):
    """Finite but extreme states (overflowing to inf inside) must not panic."""
    model = mixed_model()
    for _, call in calls(model, q=np.array(q), v=np.array(v), x=np.array(x)):
        no_panic(call)


def test_empty_and_world_welded_models():
    empty = pmd.Model()
    assert (empty.nq, empty.nv, empty.nlinks) == (0, 0, 0)
    assert empty.mass_matrix([]).shape == (0, 0)
    assert empty.forward_dynamics([], [], [], G).shape == (0,)
    welded = pmd.Model()
    welded.add_body(rod_body(), pmd.Fixed())
    assert (welded.nq, welded.nv, welded.nlinks, welded.nbodies) == (0, 0, 0, 1)
    assert welded.inverse_dynamics([], [], [], G).shape == (0,)
    with raises(errors.InvalidInputError, "q", "(0,)"):
        welded.mass_matrix([0.0])


def test_zyz_singularity_message_names_the_body():
    tree = TreeSpec([BodySpec(rod_body(), "SphericalZYZ", -1, I3, np.zeros(3))])
    model = build_model(tree)
    with raises(errors.SingularityError, "b0", "theta"):
        model.forward_dynamics([0.0, 0.0, 0.0], [0, 0, 0], [0, 0, 0], G)


@pytest.mark.parametrize("robot", ["chain7", "go2"])
def test_a_non_finite_coordinate_is_named_by_its_index_in_q_and_its_joint(robot):
    """The index is the one in q (not inside its joint) and the joint is the one Pinocchio
    says owns that coordinate (`idx_qs`, `nqs`; `idx_vs`, `nvs` for v)."""
    pin = pytest.importorskip("pinocchio")
    if robot == "chain7":
        model = pmd.load_scene("chain7").model
        names = model.joint_names
        ref = pin.Model()
        parent = 0
        for k, name in enumerate(names):
            joint = pin.JointModelRY() if k % 2 == 0 else pin.JointModelRZ()
            parent = ref.addJoint(parent, joint, pin.SE3.Identity(), name)
    else:
        from pointmass_dyn.robots import urdf_path

        path = urdf_path("go2_description/urdf/go2.urdf")
        model = pmd.example_robot("go2_description/urdf/go2.urdf", root_joint="free")
        ref = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    assert model.nq == ref.nq and model.nv == ref.nv

    def owner(k, starts, sizes):
        return next(ref.names[j] for j in range(1, ref.njoints)
                    if starts[j] <= k < starts[j] + sizes[j])

    for k in range(model.nq):
        q = model.neutral()
        q[k] = np.nan
        with pytest.raises(pmd.errors.InvalidInputError) as e:
            model.mass_matrix(q)
        assert f"at index {k} (joint '{owner(k, ref.idx_qs, ref.nqs)}')" in str(e.value)
    for k in range(model.nv):
        v = np.zeros(model.nv)
        v[k] = np.inf
        with pytest.raises(pmd.errors.InvalidInputError) as e:
            model.forward_dynamics(model.neutral(), v, np.zeros(model.nv))
        assert f"at index {k} (joint '{owner(k, ref.idx_vs, ref.nvs)}')" in str(e.value)
