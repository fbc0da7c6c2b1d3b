"""The equimomental seven point masses: the paper's printed values, the paper's own linear
system, and round trips (masses, COM and inertia rebuilt from the seven points) for random,
slender, flat and degenerate bodies."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import (
    PAPER_A,
    PAPER_D,
    PAPER_M,
    inertia_from_second_moments,
    quat_to_matrix,
    record,
    rod_body,
    rod_inertia,
)
from hypothesis import assume, given, settings
from hypothesis import strategies as st

# Paper Table I: vertex signs of the seven point masses (the eighth vertex (−,−,−) unused).
SIGNS = np.array(
    [
        [+1, +1, +1],
        [+1, +1, -1],
        [-1, +1, -1],
        [-1, +1, +1],
        [-1, -1, +1],
        [+1, -1, +1],
        [+1, -1, -1],
    ],
    dtype=float,
)

# Paper, Section V: m1..m7 as printed, far-end-centred box.
PRINTED = [0.628, -0.543, 1.17, 0.0, 1.17, -0.543, 0.628]


def printed_tolerance(printed: float) -> float:
    """Half a unit in the last printed digit (the printed values are 3 significant figures,
    '0' is printed as is)."""
    if printed == 0:
        return 5e-4
    digits = 3 - 1 - int(np.floor(np.log10(abs(printed))))
    return 0.5 * 10.0 ** (-digits) * (1 + 1e-9)


def paper_system_solve(m, com, inertia_c, center):
    """Solves the paper's eqs 1-7 as printed (rows scaled by h, products Σ m x y), with
    numpy, from the definitions: an independent implementation of the method."""
    r = np.asarray(com, float) - np.asarray(center, float)
    i_p = inertia_c + m * (np.dot(r, r) * np.eye(3) - np.outer(r, r))
    j = 0.5 * np.trace(i_p) * np.eye(3) - i_p  # J = Σ m d dᵀ about the centre
    h = np.sqrt(np.diag(j) / m)
    pos = SIGNS * h
    x, y, z = pos.T
    a = np.array([np.ones(7), x, y, z, x * y, y * z, x * z])
    b = np.array([m, m * r[0], m * r[1], m * r[2], j[0, 1], j[1, 2], j[0, 2]])
    return np.linalg.solve(a, b), h


# ---------------------------------------------------------------------------------------------
# The paper's rod
# ---------------------------------------------------------------------------------------------


def test_paper_rod_far_end_printed_values():
    body = rod_body()
    pts = body.point_masses([PAPER_A, 0.0, 0.0])
    for j, (got, printed) in enumerate(zip(pts.masses, PRINTED)):
        assert abs(got - printed) <= printed_tolerance(printed), (j, got, printed)
    np.testing.assert_allclose(
        pts.half_sides, [PAPER_A / np.sqrt(3), PAPER_D / 4, PAPER_D / 4], rtol=1e-15, atol=0
    )
    np.testing.assert_allclose(pts.center, [PAPER_A, 0, 0], rtol=0, atol=0)


def test_paper_rod_far_end_closed_form_and_paper_system():
    """Closed form for this rod (r = (−a/2, 0, 0), h = (a/√3, d/4, d/4)):
    m1 = m7 = m/4, m2 = m6 = −m√3/8, m3 = m5 = m/4 + m√3/8, m4 = 0; and the same from the
    paper's h-scaled system solved by numpy."""
    m = PAPER_M
    pts = rod_body().point_masses([PAPER_A, 0.0, 0.0])
    s = m * np.sqrt(3) / 8
    closed = [m / 4, -s, m / 4 + s, 0.0, m / 4 + s, -s, m / 4]
    np.testing.assert_allclose(pts.masses, closed, rtol=0, atol=1e-14)
    ref, h = paper_system_solve(
        m, [PAPER_A / 2, 0, 0], rod_inertia(m, PAPER_A, PAPER_D), [PAPER_A, 0, 0]
    )
    # The paper's form has condition number ~5e4 here: agreement to ~1e-11 is its floor.
    np.testing.assert_allclose(pts.masses, ref, rtol=0, atol=1e-11)
    np.testing.assert_allclose(pts.positions, [PAPER_A, 0, 0] + SIGNS * h, rtol=0, atol=1e-15)


def test_paper_rod_com_centred_is_tetrahedron():
    m = PAPER_M
    body = rod_body()
    pts = body.point_masses()  # default: the COM
    np.testing.assert_allclose(pts.center, [PAPER_A / 2, 0, 0], rtol=0, atol=0)
    np.testing.assert_allclose(
        pts.masses, [m / 4, 0, m / 4, 0, m / 4, 0, m / 4], rtol=0, atol=1e-15
    )
    np.testing.assert_allclose(
        pts.half_sides, [PAPER_A / np.sqrt(12), PAPER_D / 4, PAPER_D / 4], rtol=1e-15
    )
    explicit = body.point_masses([PAPER_A / 2, 0, 0])
    np.testing.assert_array_equal(explicit.masses, pts.masses)


def test_positions_follow_table_one():
    body = pmd.RigidBody(
        1.3,
        [0.1, -0.2, 0.3],
        inertia_from_second_moments(1.3, [0.02, 0.05, 0.011], quat_to_matrix([0.1, 0.2, 0.3, 0.9])),
    )
    center = np.array([0.4, 0.5, -0.6])
    pts = body.point_masses(center)
    assert pts.positions.shape == (7, 3) and pts.masses.shape == (7,)
    np.testing.assert_allclose(pts.positions, center + SIGNS * pts.half_sides, rtol=0, atol=1e-15)
    ref, h = paper_system_solve(body.mass, body.com, body.inertia, center)
    np.testing.assert_allclose(pts.half_sides, h, rtol=1e-13)
    np.testing.assert_allclose(pts.masses, ref, rtol=0, atol=1e-12 * body.mass)


# ---------------------------------------------------------------------------------------------
# Round trips
# ---------------------------------------------------------------------------------------------


def rebuild_numpy(masses, positions):
    """Mass, COM and inertia about the COM of point masses, from the definitions."""
    masses = np.asarray(masses, float)
    positions = np.asarray(positions, float)
    m = masses.sum()
    c = masses @ positions / m
    d = positions - c
    inertia = np.zeros((3, 3))
    for mi, di in zip(masses, d):
        # Σ m (y² + z²) per diagonal component, no |d|² − d_x² cancellation.
        inertia += mi * np.array(
            [
                [di[1] ** 2 + di[2] ** 2, -di[0] * di[1], -di[0] * di[2]],
                [-di[0] * di[1], di[0] ** 2 + di[2] ** 2, -di[1] * di[2]],
                [-di[0] * di[2], -di[1] * di[2], di[0] ** 2 + di[1] ** 2],
            ]
        )
    return m, c, inertia


def round_trip_errors(
    body: pmd.RigidBody, center, via: str = "library"
) -> tuple[float, float, float]:
    """Relative errors of mass, COM and inertia rebuilt from the seven points: through
    PointMasses.to_body() and RigidBody.from_point_masses (which must agree), or with numpy
    from the definitions (`via="numpy"`)."""
    pts = body.point_masses(center)
    assert np.all(np.isfinite(pts.masses)) and np.all(np.isfinite(pts.positions))
    if via == "library":
        back = pts.to_body()
        back2 = pmd.RigidBody.from_point_masses(pts.masses, pts.positions)
        np.testing.assert_array_equal(back.inertia, back2.inertia)
        mass, com, inertia = back.mass, back.com, back.inertia
    else:
        mass, com, inertia = rebuild_numpy(pts.masses, pts.positions)
    m = body.mass
    r = np.asarray(body.com) - np.asarray(pts.center)
    # Scale: the inertia plus the parallel-axis term m|c − p|² (as specified), plus m|p||h|:
    # the positions are stored in body coordinates, p + s·h, so each carries a rounding error
    # eps·|p| that no rebuild can undo (this term matters only for boxes far from the origin
    # compared with their size).
    h = np.asarray(pts.half_sides)
    scale = (
        np.linalg.norm(body.inertia)
        + m * np.dot(r, r)
        + m * np.linalg.norm(pts.center) * np.linalg.norm(h)
    )
    # The COM is a weighted mean of points at distance ≲ |c| + |c − p| + h from the origin.
    length = np.linalg.norm(body.com) + np.linalg.norm(r) + np.sqrt(np.trace(body.inertia) / m)
    e_mass = abs(mass - m) / m
    e_com = (
        np.linalg.norm(com - body.com) / length if length > 0 else np.linalg.norm(com - body.com)
    )
    e_inertia = (
        np.linalg.norm(inertia - body.inertia) / scale if scale > 0 else np.linalg.norm(inertia)
    )
    return e_mass, e_com, e_inertia


RT_TOL = 1e-14

finite = {"allow_nan": False, "allow_infinity": False}


@st.composite
def bodies_and_centers(draw):
    m = 10 ** draw(st.floats(-3, 3, **finite))
    # Principal second moments Σ m x² > 0; any such triple gives principal moments satisfying
    # the triangle inequality, and every valid inertia arises this way.
    sigma = [m * draw(st.floats(1e-4, 4.0, **finite)) for _ in range(3)]
    quat = np.array(draw(st.lists(st.floats(-1, 1, **finite), min_size=4, max_size=4)))
    assume(np.linalg.norm(quat) > 0.1)
    com = np.array(draw(st.lists(st.floats(-3, 3, **finite), min_size=3, max_size=3)))
    center = draw(
        st.one_of(
            st.just(None),
            st.lists(st.floats(-5, 5, **finite), min_size=3, max_size=3).map(np.array),
        )
    )
    # No exact zero here: a zero-thickness rod or plate turned slightly off the body axes
    # loses accuracy (see the xfail tests below); exactly flat/degenerate bodies have their own
    # tests.
    assume(min(sigma) > 0)
    inertia = inertia_from_second_moments(m, sigma, quat_to_matrix(quat))
    return pmd.RigidBody(m, com, inertia), center


@settings(max_examples=500, deadline=None)
@given(bodies_and_centers())
def test_round_trip_random_bodies(bc):
    body, center = bc
    e = round_trip_errors(body, center)
    record("round trip: random body (mass, com, inertia)", max(e))
    assert e[0] <= RT_TOL and e[1] <= RT_TOL and e[2] <= RT_TOL, e


@settings(max_examples=100, deadline=None)
@given(
    ratio_exp=st.floats(-8, -1, **finite),
    px=st.floats(-3, 3, **finite),
    m=st.floats(0.01, 100, **finite),
)
def test_round_trip_slender_rod_keeps_axial_inertia(ratio_exp, px, m):
    """Rod along x with d/a down to 1e-8, box centred anywhere on the axis: the small axial
    moment I_xx survives relative to itself (the naive ½tr(I) − I_yy would lose it all)."""
    a = 1.0
    d = a * 10**ratio_exp
    body = pmd.RigidBody(m, [a / 2, 0, 0], rod_inertia(m, a, d))
    e = round_trip_errors(body, [px, 0, 0])
    assert max(e) <= RT_TOL, e
    back = body.point_masses([px, 0, 0]).to_body()
    ixx = m * d * d / 8
    rel_axial = abs(back.inertia[0, 0] - ixx) / ixx
    record("slender rod: axial I_xx relative to itself", rel_axial)
    assert rel_axial <= 1e-13, (d, px, back.inertia[0, 0], ixx)
    # The off-diagonal terms stay at the axial scale, too (no spurious products).
    assert np.max(np.abs(back.inertia - body.inertia)) <= 1e-13 * m * a * a


@settings(max_examples=100, deadline=None)
@given(
    ratio_exp=st.floats(-6, -1, **finite),
    quat=st.lists(st.floats(-1, 1, **finite), min_size=4, max_size=4),
    center=st.lists(st.floats(-2, 2, **finite), min_size=3, max_size=3),
)
def test_round_trip_rotated_slender_rod(ratio_exp, quat, center):
    assume(np.linalg.norm(quat) > 0.1)
    r = quat_to_matrix(quat)
    m, a, d = PAPER_M, 1.0, 10**ratio_exp
    body = pmd.RigidBody(m, [0.3, 0.1, -0.2], r @ rod_inertia(m, a, d) @ r.T)
    e = round_trip_errors(body, center)
    record("round trip: rotated slender rod d/a >= 1e-6", max(e))
    assert max(e) <= RT_TOL, e


def rotated_zero_thickness_rod(theta: float) -> np.ndarray:
    """Ry(θ) diag(0, 1/12, 1/12) Ry(θ)ᵀ: a 1 kg, 1 m rod with no axial inertia, turned by θ."""
    c, s = np.cos(theta), np.sin(theta)
    r = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return r @ np.diag([0.0, 1 / 12, 1 / 12]) @ r.T


def rotated_plate(theta: float) -> np.ndarray:
    """Rz(θ) diag(2, 1, 1) Rz(θ)ᵀ: a 1 kg flat plate (zero thickness along x), turned by θ."""
    c, s = np.cos(theta), np.sin(theta)
    r = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    return r @ np.diag([2.0, 1.0, 1.0]) @ r.T


@pytest.mark.parametrize(
    "inertia",
    [rotated_zero_thickness_rod(1e-8), rotated_plate(1e-9)],
    ids=["rod Ry(1e-8) diag(0,1/12,1/12)", "plate Rz(1e-9) diag(2,1,1)"],
)
def test_round_trip_slightly_rotated_degenerate_body(inertia):
    body = pmd.RigidBody(1.0, [0, 0, 0], inertia)
    e = round_trip_errors(body, None)
    # Got: inertia error 2.9e-9 (rod: ΔI_xz ≈ 2.4e-10, all of I_xz = −θ/12 lost) and
    # 5.8e-10 (plate) relative to |I|.
    assert e[2] <= RT_TOL, e


def test_round_trip_rotated_zero_thickness_rod_is_finite():
    """What is achieved today for the case above, so a regression beyond it is caught."""
    worst = 0.0
    for theta in [1e-9, 1e-8, 1e-7, 1e-5, 1e-3, 0.1, 1.0]:
        for inertia in (rotated_zero_thickness_rod(theta), rotated_plate(theta)):
            body = pmd.RigidBody(1.0, [0, 0, 0], inertia)
            pts = body.point_masses()
            assert np.all(np.isfinite(pts.masses))
            worst = max(worst, max(round_trip_errors(body, None)))
    record("round trip: slightly rotated zero-thickness rod/plate", worst)
    assert worst <= 1e-7


def test_slender_rod_off_axis_center_loses_only_what_rounding_must():
    """An off-axis centre puts the axial moment into a difference of O(|r|²) numbers; it is
    then exact only relative to the whole inertia (m|c − p|² scale), not to itself."""
    m, a, d = PAPER_M, 1.0, 1e-8
    body = pmd.RigidBody(m, [a / 2, 0, 0], rod_inertia(m, a, d))
    e = round_trip_errors(body, [1.0, 0.3, 0.2])
    assert max(e) <= RT_TOL, e


@pytest.mark.parametrize(
    "center",
    [
        None,
        [0, 0, 0],
        [1, 0, 0],
        [0.3, -0.2, 0.1],
        [-1, -1, -1],
        [2, 2, 2],
        [0, 0.5, 0],
        [-0.4, 0, 0.7],
    ],
)
@pytest.mark.parametrize(
    "name, sigma, rot",
    [
        ("zero-axial rod", [0.25, 0.0, 0.0], None),
        ("zero-axial rod rotated", [0.25, 0.0, 0.0], [0.3, -0.2, 0.5, 0.8]),
        ("flat plate", [0.2, 0.05, 0.0], None),
        ("flat plate rotated", [0.2, 0.05, 0.0], [0.1, 0.7, -0.2, 0.4]),
        ("square plate", [0.1, 0.1, 0.0], None),
        ("point mass", [0.0, 0.0, 0.0], None),
        ("sphere", [0.1, 0.1, 0.1], None),
    ],
)
def test_degenerate_bodies(name, sigma, rot, center):
    """Zero half-sides make some of the paper's right-hand sides 0/0: the answer must be
    finite and still reproduce the body."""
    m = 1.7
    r = np.eye(3) if rot is None else quat_to_matrix(rot)
    inertia = inertia_from_second_moments(m, m * np.array(sigma), r)
    body = pmd.RigidBody(m, [0.1, -0.2, 0.05], inertia)
    pts = body.point_masses(center)
    assert np.all(np.isfinite(pts.masses)), pts.masses
    assert np.all(np.isfinite(pts.half_sides))
    assert np.all(pts.half_sides >= 0)
    e = round_trip_errors(body, center, via="numpy")
    assert max(e) <= RT_TOL, (name, center, e)
    e = round_trip_errors(body, center)
    record("round trip: degenerate bodies", max(e))
    assert max(e) <= RT_TOL, (name, center, e)


def test_point_mass_off_centre_to_body():
    body = pmd.RigidBody(1.7, [0.1, -0.2, 0.05], np.zeros((3, 3)))
    pts = body.point_masses([1.0, 0.0, 0.0])  # a valid equimomental set (checked above with numpy)
    back = pts.to_body()  # raises InertiaError: "expected a positive semidefinite tensor"
    np.testing.assert_allclose(back.inertia, np.zeros((3, 3)), atol=1e-14)


def test_point_mass_at_centre_has_zero_box():
    body = pmd.RigidBody(2.0, [0.3, 0.1, -0.2], np.zeros((3, 3)))
    pts = body.point_masses()
    np.testing.assert_array_equal(pts.half_sides, [0, 0, 0])
    np.testing.assert_allclose(pts.positions, np.tile([0.3, 0.1, -0.2], (7, 1)), atol=0)
    assert abs(pts.masses.sum() - 2.0) <= 1e-15


@settings(max_examples=100, deadline=None)
@given(
    masses=st.lists(st.floats(0.01, 10, **finite), min_size=1, max_size=12),
    seed=st.integers(0, 2**32 - 1),
)
def test_from_point_masses_matches_definition(masses, seed):
    """RigidBody.from_point_masses against the definitions: Σm, Σm x / Σm,
    I = Σ m (|d|² 1 − d dᵀ) about the COM, standard sign convention."""
    rng = np.random.default_rng(seed)
    masses = np.array(masses)
    pos = rng.uniform(-2, 2, size=(len(masses), 3))
    body = pmd.RigidBody.from_point_masses(masses, pos)
    m = masses.sum()
    c = masses @ pos / m
    d = pos - c
    inertia = sum(mi * (np.dot(di, di) * np.eye(3) - np.outer(di, di)) for mi, di in zip(masses, d))
    assert abs(body.mass - m) <= 1e-14 * m
    np.testing.assert_allclose(body.com, c, rtol=0, atol=1e-14 * (1 + np.abs(pos).max()))
    np.testing.assert_allclose(
        body.inertia, inertia, rtol=0, atol=1e-13 * (np.abs(inertia).max() + 1e-300)
    )


def test_inertia_about_is_parallel_axis():
    m = 2.0
    body = pmd.RigidBody(m, [0.1, 0.2, 0.3], np.diag([0.1, 0.2, 0.25]))
    p = np.array([1.0, -1.0, 0.5])
    r = body.com - p
    np.testing.assert_allclose(
        body.inertia_about(p),
        body.inertia + m * (np.dot(r, r) * np.eye(3) - np.outer(r, r)),
        rtol=1e-15,
        atol=1e-15,
    )


def test_products_of_inertia_use_standard_sign():
    """Two unit masses at (1,1,0) and (−1,−1,0): I_xy = −Σ m x y = −2 (standard convention)."""
    body = pmd.RigidBody.from_point_masses([1.0, 1.0], [[1, 1, 0], [-1, -1, 0]])
    assert body.inertia[0, 1] == pytest.approx(-2.0, abs=1e-15)
    assert body.inertia[2, 2] == pytest.approx(4.0, abs=1e-15)
