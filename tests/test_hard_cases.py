"""Hard cases, each against something the library does not compute itself: the exact
compound-pendulum solution (Jacobi elliptic functions), Euler's equations of a symmetric rod,
the closed-form seven point masses, an mpmath evaluation of the same equations of motion at
50 digits, NumPy solves of the mass matrix, mirror symmetry, conservation of energy, and
SciPy's RK45. The errors seen are recorded for the report (conftest `record`).

Accuracy is asserted against the conditioning the problem itself has: a result is accurate
if its error is within c·eps·cond(GIM) of the exact answer (backward stable), c ≤ 4."""

from __future__ import annotations

import math
import re

import mpmath as mp
import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import record, rod_inertia
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation
from scipy.special import ellipj, ellipk, ellipkinc

EPS = np.finfo(float).eps
G = np.array([0.0, 0.0, -9.81])
M_ROD, A_ROD, D_ROD = 2.51, 1.0, 0.02


def rod(m=M_ROD, a=A_ROD, d=D_ROD) -> pmd.RigidBody:
    return pmd.RigidBody(m, [a / 2, 0.0, 0.0], rod_inertia(m, a, d))


# ============================================================================================
# 1. Euler singularity: the ZYZ joint driven through sin θ = 0
# ============================================================================================
# The rod on a ZYZ joint with φ = ψ = 0 and θ = −60°: body x (the rod) points 60° above the
# horizontal; released from rest it swings in the x-z plane. Its direction is
# (cos θ, 0, −sin θ), so it is horizontal — and the joint singular, sin θ = 0 — whenever it
# passes θ = 0 or π. Exact motion: a compound pendulum of amplitude α0 = 150° from the
# downward vertical, sin(α/2) = k sn(K − ω0 t | k²), k = sin(α0/2); horizontal at α = ±90°.
ELEV0 = math.radians(60.0)
I_O = M_ROD * A_ROD**2 / 3 + M_ROD * D_ROD**2 / 16
W0 = math.sqrt(M_ROD * 9.81 * A_ROD / 2 / I_O)
K_AMP = math.sin(math.radians(150.0) / 2)
K_FULL = ellipk(K_AMP**2)
PERIOD = 4 * K_FULL / W0
_U_HORIZ = ellipkinc(math.asin(math.sin(math.radians(45.0)) / K_AMP), K_AMP**2)
T_CROSS1 = (K_FULL - _U_HORIZ) / W0
#: Times at which the rod is horizontal (sin θ = 0 for the ZYZ chart), first two periods.
CROSSINGS = np.sort([k * PERIOD / 2 + s * T_CROSS1 for k in range(5) for s in (-1, 1)
                     if 0 < k * PERIOD / 2 + s * T_CROSS1 < 2 * PERIOD])
Q_POLE = np.array([0.0, -ELEV0, 0.0])


def exact_swing(t):
    """(α, α̇) of the compound pendulum, α from the downward vertical."""
    sn, cn, dn, _ = ellipj(K_FULL - W0 * np.asarray(t), K_AMP**2)
    return 2 * np.arcsin(K_AMP * sn), -2 * K_AMP * W0 * cn


def pole_scenes():
    zyz = pmd.Model()
    zyz.add_body(rod(), pmd.SphericalZYZ(), name="rod", point_mass_center=[A_ROD, 0, 0])
    quat = pmd.Model()
    quat.add_body(rod(), pmd.Spherical(), name="rod", point_mass_center=[A_ROD, 0, 0])
    q_quat = Rotation.from_euler("ZYZ", Q_POLE).as_quat()
    return (pmd.Scene(zyz, Q_POLE, np.zeros(3), effects=[pmd.Gravity(G)]),
            pmd.Scene(quat, q_quat, np.zeros(3), effects=[pmd.Gravity(G)]))


def test_exact_crossing_times_are_consistent():
    # The exact solution is horizontal (α = ±90°) at the crossing times.
    alpha, _ = exact_swing(CROSSINGS)
    assert np.max(np.abs(np.abs(alpha) - np.pi / 2)) < 1e-12
    assert CROSSINGS[0] == pytest.approx(0.48108397, abs=1e-7)
    assert CROSSINGS.shape == (8,)


def test_zyz_forward_dynamics_refuses_the_pole_naming_it():
    zyz, _ = pole_scenes()
    with pytest.raises(pmd.SingularityError, match=r"Euler singularity.*sin\(theta\)"):
        zyz.model.forward_dynamics([0.3, 0.0, 0.2], [0.0, 1.0, 0.0], np.zeros(3), gravity=G)


@pytest.mark.parametrize("tol", [1e-3, 1e-6, 1e-8])  # 1e-3 used to step over the pole
def test_zyz_through_the_pole_stops_with_the_singularity_and_its_time(tol):
    zyz, _ = pole_scenes()
    r = pmd.simulate(zyz, (0.0, 3.0), rtol=tol, atol=tol)
    assert r.success is False and r.status == -1
    msg = r.message
    assert "Euler singularity" in msg and "sin theta = 0" in msg, msg
    assert "Spherical (a quaternion)" in msg, msg  # says what to do instead
    at = float(re.search(r"singularity \(sin theta = 0\) at t = ([-+0-9.eE]+)", msg).group(1))
    reached = float(re.search(r"stopped at t = ([-+0-9.eE]+)", msg).group(1))
    assert reached == pytest.approx(r.t_reached, rel=1e-15) and r.t[-1] == r.t_reached
    assert r.t_reached == at
    # Early: located on the dense output, not approached with ever smaller steps (the
    # integrator used to crawl for 1.6e6 evaluations at tol 1e-8 before the step failed).
    assert r.nfev < 20_000, r.nfev
    # The time named is a true crossing (independent: the elliptic-function solution).
    miss = np.min(np.abs(CROSSINGS - at))
    record(f"ZYZ pole: |t named - exact crossing| at tol {tol:g} (s)", miss)
    record(f"ZYZ pole: evaluations spent before the error at tol {tol:g}", r.nfev)
    assert miss <= 100 * tol
    with pytest.raises(pmd.SimulationError) as info:
        r.raise_for_status()
    assert info.value.t == r.t_reached


def test_quaternion_joint_passes_the_same_motion_conserving_energy():
    _, quat = pole_scenes()

    def horizontal(t, q, v):  # z of the rod direction (body x axis in the world)
        return Rotation.from_quat(q).as_matrix()[2, 0]

    r = pmd.simulate(quat, (0.0, 2 * PERIOD), rtol=1e-11, atol=1e-12, energy=True,
                     events=[horizontal])
    assert r.success and r.status == 0, r.message
    crossings = r.t_events[0]
    assert crossings.shape == CROSSINGS.shape
    err_t = np.max(np.abs(crossings - CROSSINGS))
    record("quaternion pole: crossing times vs elliptic solution (s)", err_t)
    assert err_t <= 1e-8
    kinetic = max(quat.model.kinetic_energy(q, v) for q, v in zip(r.q, r.v))
    drift = np.max(np.abs(r.energy - r.energy[0])) / kinetic
    record("quaternion pole: energy drift / max kinetic energy", drift)
    assert drift <= 1e-9
    # It swings up to 60° above the horizontal on the far side, as energy demands.
    elev = np.array([Rotation.from_quat(q).as_matrix()[2, 0] for q in r.q])
    assert abs(np.max(elev) - math.sin(ELEV0)) <= 1e-8
    # Planar: the rod stays in the x-z plane through the pole.
    assert np.max(np.abs([Rotation.from_quat(q).as_matrix()[1, 0] for q in r.q])) <= 1e-12


# ============================================================================================
# 2. Slender and flat bodies, d/a from 1e-2 to 1e-8
# ============================================================================================
RATIOS = [1e-2, 1e-4, 1e-6, 1e-8]
SIGNS = np.array([  # docs/method.md §1, paper Table I
    [1, 1, 1], [1, 1, -1], [-1, 1, -1], [-1, 1, 1], [-1, -1, 1], [1, -1, 1], [1, -1, -1]])


def exact_point_masses(m, com, inertia, center):
    """The seven masses by docs/method.md §1 (paper eqs 1–7), at 50 digits (mpmath): the ±1 sign
    system."""
    mp.mp.dps = 50
    m = mp.mpf(m)
    inertia = [[mp.mpf(float(x)) for x in row] for row in inertia]
    r = [mp.mpf(float(c)) - mp.mpf(float(p)) for c, p in zip(com, center)]
    tr = inertia[0][0] + inertia[1][1] + inertia[2][2]
    jc = [[(tr / 2 if i == j else 0) - inertia[i][j] for j in range(3)] for i in range(3)]
    jp = [[jc[i][j] + m * r[i] * r[j] for j in range(3)] for i in range(3)]
    h = [mp.sqrt(jp[i][i] / m) for i in range(3)]
    s = SIGNS
    rows = [[1] * 7, list(s[:, 0]), list(s[:, 1]), list(s[:, 2]), list(s[:, 0] * s[:, 1]),
            list(s[:, 1] * s[:, 2]), list(s[:, 0] * s[:, 2])]
    rhs = [m] + [m * r[k] / h[k] if h[k] != 0 else mp.mpf(0) for k in range(3)] + [
        jp[0][1] / (h[0] * h[1]) if h[0] * h[1] != 0 else 0,
        jp[1][2] / (h[1] * h[2]) if h[1] * h[2] != 0 else 0,
        jp[0][2] / (h[0] * h[2]) if h[0] * h[2] != 0 else 0]
    sol = mp.lu_solve(mp.matrix([[mp.mpf(int(x)) for x in row] for row in rows]),
                      mp.matrix(rhs))
    return np.array([float(x) for x in sol]), np.array([float(x) for x in h])


@pytest.mark.parametrize("ratio", RATIOS)
@pytest.mark.parametrize("center", ["com", "far end"])
def test_slender_rod_point_masses_are_exact(ratio, center):
    d = ratio * A_ROD
    body = rod(d=d)
    c = [A_ROD / 2, 0, 0] if center == "com" else [A_ROD, 0, 0]
    pts = body.point_masses(center=c)
    masses, h = exact_point_masses(M_ROD, body.com, body.inertia, c)
    # Closed forms too: half-sides (a/√12 or a/√3, d/4, d/4).
    hx = A_ROD / math.sqrt(12) if center == "com" else A_ROD / math.sqrt(3)
    np.testing.assert_allclose(h, [hx, d / 4, d / 4], rtol=1e-15)
    err_h = np.max(np.abs(pts.half_sides - h) / h)
    err_m = np.max(np.abs(pts.masses - masses)) / M_ROD
    record("slender rod: point masses / m vs mpmath", err_m)
    record("slender rod: half-sides (relative) vs mpmath", err_h)
    assert err_h <= 4 * EPS and err_m <= 8 * EPS
    # And they rebuild the body: same mass, COM and inertia (the small axial moment too).
    back = pts.to_body()
    assert abs(back.mass - M_ROD) <= 4 * EPS * M_ROD
    i_axial = M_ROD * d * d / 8
    assert abs(back.inertia[0, 0] - i_axial) <= 16 * EPS * M_ROD * max(d * d, 1e-300) + 1e-300


@pytest.mark.parametrize("ratio", RATIOS)
@pytest.mark.parametrize("method", ["recursive", "denoc"])
def test_slender_rod_on_a_revolute_joint(ratio, method):
    # About a transverse axis the problem is well-conditioned whatever d: exact θ̈.
    d = ratio * A_ROD
    model = pmd.Model()
    model.add_body(rod(d=d), pmd.Revolute([0, 1, 0]), name="rod", point_mass_center=[A_ROD, 0, 0])
    i_o = M_ROD * A_ROD**2 / 3 + M_ROD * d * d / 16
    for theta, w in [(0.3, 0.7), (1.2, -2.0), (-2.5, 5.0)]:
        acc = model.forward_dynamics([theta], [w], [0.0], gravity=G, method=method)[0]
        exact = M_ROD * 9.81 * A_ROD / 2 * math.cos(theta) / i_o
        err = abs(acc - exact) / abs(exact)
        record(f"slender rod, revolute, {method}: θ̈ relative error", err)
        assert err <= 8 * EPS
        gim = model.mass_matrix([theta], method=method)[0, 0]
        assert abs(gim - i_o) <= 8 * EPS * i_o


@pytest.mark.parametrize("ratio", RATIOS)
@pytest.mark.parametrize("method", ["recursive", "denoc"])
def test_slender_rod_on_a_quaternion_joint_within_its_conditioning(ratio, method):
    # Speeds are the body-frame angular velocity, so the GIM is the constant body inertia
    # about the pivot, diag(m d²/8, I_O, I_O): cond = 8 I_O/(m d²) ≈ 2.7 (a/d)². Euler's
    # equations give the exact accelerations; the axial one is exactly 0 (symmetric rod,
    # gravity's moment is transverse). The transverse ones are well-conditioned.
    d = ratio * A_ROD
    model = pmd.Model()
    model.add_body(rod(d=d), pmd.Spherical(), name="rod")
    i_ax = M_ROD * d * d / 8
    i_o = M_ROD * A_ROD**2 / 3 + M_ROD * d * d / 16
    ib = np.diag([i_ax, i_o, i_o])
    cond = i_o / i_ax
    rng = np.random.default_rng(7)
    worst = 0.0
    for k in range(6):
        quat = Rotation.random(random_state=k).as_quat()
        w = rng.normal(size=3)
        gim = model.mass_matrix(quat, method=method)
        err_m = np.max(np.abs(gim - ib)) / i_o
        record(f"slender rod, quaternion, {method}: GIM error / I_O", err_m)
        assert err_m <= 8 * EPS
        rot = Rotation.from_quat(quat).as_matrix()
        tau = np.cross([A_ROD / 2, 0, 0], rot.T @ (M_ROD * G))
        exact = np.array([0.0, (tau[1] - (i_ax - i_o) * w[2] * w[0]) / i_o,
                          (tau[2] - (i_o - i_ax) * w[0] * w[1]) / i_o])
        try:
            acc = model.forward_dynamics(quat, w, np.zeros(3), gravity=G, method=method)
        except pmd.SingularityError as exc:
            # Allowed only where the axial direction is numerically singular.
            assert EPS * cond > 1e-2, (ratio, exc)
            assert "slender" in str(exc) and "denoc" in str(exc)
            continue
        scale = np.max(np.abs(exact))
        transverse = np.max(np.abs(acc[1:] - exact[1:])) / scale
        axial = abs(acc[0]) / scale
        record(f"slender rod, quaternion, {method}: transverse error", transverse)
        record(f"slender rod, quaternion, {method}: axial error / (eps cond)", axial / (EPS * cond))
        assert transverse <= 16 * EPS
        assert axial <= 4 * EPS * cond
        worst = max(worst, axial)
    # Both paths stay within the conditioning bound asserted above (the body-frame recursion,
    # now the default, at ~0.05 eps·cond; the former world-frame one reached ~0.6 eps·cond).
    record(f"slender rod, quaternion, {method} d/a={ratio:g}: worst axial error", worst)


@pytest.mark.parametrize("ratio", RATIOS + [0.0])
@pytest.mark.parametrize("method", ["recursive", "denoc"])
def test_flat_plate_is_well_conditioned_whatever_its_thickness(ratio, method):
    # A square plate a × a × d on a quaternion joint at the middle of one edge: its box of
    # point masses degenerates (hz = d/√12 → 0) but the GIM does not.
    a, m = 0.4, 1.7
    d = ratio * a
    i_c = m / 12 * np.diag([a * a + d * d, a * a + d * d, 2 * a * a])
    com = np.array([a / 2, 0.0, 0.0])
    body = pmd.RigidBody(m, com, i_c)
    pts = body.point_masses(center=com)
    # The thickness is in the data only as I_xx + I_yy − I_zz = m d²/6, a difference of
    # numbers of size m a²/6: the given floats determine hz to relative ~eps (a/d)², and the
    # library must get the hz of the given floats (mpmath) to that accuracy, not better.
    masses, h = exact_point_masses(m, com, i_c, com)
    assert h[2] == pytest.approx(d / math.sqrt(12), rel=4 * EPS * (a / d) ** 2 if d else 0)
    cond_h = np.trace(i_c) / max(2 * m * h[2] ** 2, np.finfo(float).tiny)
    err_h = abs(pts.half_sides[2] - h[2]) / max(h[2], np.finfo(float).tiny)
    record("flat plate: hz error / (eps cond)", err_h / (EPS * cond_h))
    if d == 0:
        assert pts.half_sides[2] == 0.0
    else:
        assert err_h <= 4 * EPS * cond_h
    np.testing.assert_allclose(pts.half_sides[:2], h[:2], rtol=4 * EPS)
    assert np.max(np.abs(pts.masses - masses)) <= 8 * EPS * m
    model = pmd.Model()
    model.add_body(body, pmd.Spherical(), name="plate")
    i_o = i_c + m * (com @ com * np.eye(3) - np.outer(com, com))
    rng = np.random.default_rng(3)
    for k in range(4):
        quat = Rotation.random(random_state=10 + k).as_quat()
        w = rng.normal(size=3) * 3
        rot = Rotation.from_quat(quat).as_matrix()
        tau = np.cross(com, rot.T @ (m * G))
        exact = np.linalg.solve(i_o, tau - np.cross(w, i_o @ w))
        acc = model.forward_dynamics(quat, w, np.zeros(3), gravity=G, method=method)
        err = np.max(np.abs(acc - exact)) / np.max(np.abs(exact))
        record(f"flat plate, quaternion, {method}: acceleration error", err)
        assert err <= 64 * EPS * np.linalg.cond(i_o)


# ============================================================================================
# 3. Mass ratios 1e-6 … 1e6 between neighbouring bodies, against mpmath
# ============================================================================================
def planar_reference(cart, masses, lengths, thick, q, v, g=9.81):
    """Mass matrix and accelerations, at 50 digits, of a planar chain in the x-z plane: an
    optional cart (prismatic x, a block of mass masses[0]) carrying revolute-y links, link k a
    rod of length lengths[k] and diameter thick[k], pinned at its end, x along the rod.
    Lagrange's equations written out by hand: COM of link k is
    x0 + Σ_{j<k} l_j e(Φ_j) + (l_k/2) e(Φ_k), e(Φ) = (cos Φ, −sin Φ) (x, z), Φ_k = Σ_{j≤k} θ_j."""
    mp.mp.dps = 50
    q = [mp.mpf(float(x)) for x in q]
    v = [mp.mpf(float(x)) for x in v]
    n = len(q)
    off = 1 if cart else 0
    mass = mp.zeros(n, n)
    bias = mp.zeros(n, 1)  # C v − τ_g
    if cart:
        mass[0, 0] += mp.mpf(masses[0])
    for k in range(off, n):
        m = mp.mpf(masses[k])
        lk, dk = mp.mpf(lengths[k]), mp.mpf(thick[k])
        i_yy = m * dk * dk / 16 + m * lk * lk / 12
        jx, jz = [mp.mpf(0)] * n, [mp.mpf(0)] * n
        ax = az = mp.mpf(0)  # COM acceleration at q̈ = 0
        if cart:
            jx[0] = mp.mpf(1)
        for j in range(off, k + 1):
            phi = sum(q[off:j + 1])
            phid = sum(v[off:j + 1])
            lj = mp.mpf(lengths[j]) * (mp.mpf(1) / 2 if j == k else 1)
            for i in range(off, j + 1):
                jx[i] += -lj * mp.sin(phi)
                jz[i] += -lj * mp.cos(phi)
            ax += -lj * mp.cos(phi) * phid**2
            az += lj * mp.sin(phi) * phid**2
        for r in range(n):
            for c in range(n):
                mass[r, c] += m * (jx[r] * jx[c] + jz[r] * jz[c])
            bias[r] += m * (jx[r] * ax + jz[r] * az) + m * mp.mpf(g) * jz[r]
        for r in range(off, k + 1):
            for c in range(off, k + 1):
                mass[r, c] += i_yy
    acc = mp.lu_solve(mass, -bias)
    return (np.array([float(x) for x in acc]),
            np.array([[float(mass[i, j]) for j in range(n)] for i in range(n)]))


def planar_model(cart, masses, lengths, thick) -> pmd.Model:
    model = pmd.Model()
    parent = -1
    off = 1 if cart else 0
    if cart:
        mc, s = masses[0], 0.1
        parent = model.add_body(pmd.RigidBody(mc, [0, 0, 0], np.eye(3) * mc * s * s / 6),
                                pmd.Prismatic([1, 0, 0]), name="cart")
    for k in range(off, len(masses)):
        t = (0, 0, 0) if k == off else (lengths[k - 1], 0, 0)
        parent = model.add_body(rod(masses[k], lengths[k], thick[k]), pmd.Revolute([0, 1, 0]),
                                parent=parent, translation=t, name=f"link{k}")
    return model


MASS_CASES = {
    # a light cart carrying a heavy pendulum (and the reverse)
    "cart-pole": lambda r: (True, [1.0, r], [0.0, 0.5], [0.0, 0.02]),
    # a heavy arm with a light tip (and the reverse)
    "arm": lambda r: (False, [1.0, 1.0 / r], [0.5, 0.3], [0.05, 0.03]),
    # alternating heavy and light links
    "alternating": lambda r: (False, [1.0, r, 1.0, r], [0.4, 0.3, 0.4, 0.3],
                              [0.04, 0.03, 0.04, 0.03]),
}


@pytest.mark.parametrize("ratio", [1e-6, 1e-3, 1.0, 1e3, 1e6])
@pytest.mark.parametrize("case", sorted(MASS_CASES))
def test_mass_ratios_match_mpmath_to_the_conditioning(case, ratio):
    cart, masses, lengths, thick = MASS_CASES[case](ratio)
    model = planar_model(cart, masses, lengths, thick)
    n = model.nv
    rng = np.random.default_rng(int(ratio * 1e6) % 1000 + len(case))
    for _ in range(4):
        q = rng.uniform(-2.0, 2.0, size=n)
        v = rng.normal(size=n)
        exact, gim = planar_reference(cart, masses, lengths, thick, q, v)
        cond = np.linalg.cond(gim)
        for method in ("recursive", "denoc"):
            m_ours = model.mass_matrix(q, method=method)
            err_m = np.max(np.abs(m_ours - gim)) / np.max(np.abs(gim))
            acc = model.forward_dynamics(q, v, np.zeros(n), gravity=G, method=method)
            err = np.max(np.abs(acc - exact)) / np.max(np.abs(exact))
            record(f"mass ratio {case}, {method}: GIM error", err_m)
            record(f"mass ratio {case}, {method}: acceleration error", err)
            record(f"mass ratio {case}, {method}: acceleration error / (eps cond)",
                   err / (EPS * cond))
            assert err_m <= 8 * EPS
            assert err <= 4 * EPS * cond + 8 * EPS


# ============================================================================================
# 4. Long chains
# ============================================================================================
def rope_link(mass, length, d) -> pmd.RigidBody:
    return rod(mass, length, d)


def test_200_link_rope_released_horizontally_keeps_its_symmetry():
    # A 1 m, 1 kg rope of 200 links pinned at its middle: two 100-link halves, the second
    # the mirror image of the first (rotated by exactly π about z), released horizontally.
    # They must stay mirror images, stay in the x-z plane, and conserve energy.
    n, half_len, half_mass = 100, 0.5, 0.5
    link = rope_link(half_mass / n, half_len / n, 0.005)
    model = pmd.Model()
    for _side, rot in [(0, np.eye(3)), (1, np.diag([-1.0, -1.0, 1.0]))]:
        parent = -1
        for k in range(n):
            parent = model.add_body(link, pmd.Revolute([0, 1, 0]), parent=parent,
                                    translation=(0, 0, 0) if k == 0 else (half_len / n, 0, 0),
                                    rotation=rot if k == 0 else np.eye(3))
    assert model.nv == 200
    scene = pmd.Scene(model, np.zeros(200), np.zeros(200), effects=[pmd.Gravity(G)])
    r = pmd.simulate(scene, (0.0, 2.0), rtol=1e-5, atol=1e-5, energy=True)
    assert r.success, r.message
    assert np.all(np.isfinite(r.q)) and np.all(np.isfinite(r.v))
    asym = max(np.max(np.abs(r.q[:, :n] - r.q[:, n:])), np.max(np.abs(r.v[:, :n] - r.v[:, n:])))
    record("200-link rope: mirror asymmetry of q, v (absolute)", asym)
    assert asym <= 1e-12 * np.max(np.abs(r.v))
    # The tip whips: joint rates reach thousands of rad/s, and still nothing overflows.
    assert np.max(np.abs(r.v)) > 100.0
    origins = np.array([model.placements(q)[1] for q in r.q[:: max(1, len(r.t) // 50)]])
    assert np.max(np.abs(origins[..., 1])) == 0.0  # exactly planar
    kinetic = max(model.kinetic_energy(q, v) for q, v in zip(r.q, r.v))
    drift = np.max(np.abs(r.energy - r.energy[0])) / kinetic
    record("200-link rope: energy drift / max kinetic energy at 1e-5", drift)
    assert drift <= 5e-3


def test_1000_link_chain_forward_dynamics():
    n = 1000
    model = pmd.Model()
    parent = -1
    for k in range(n):
        axis = (0, 1, 0) if k % 2 == 0 else (0, 0, 1)
        parent = model.add_body(pmd.RigidBody(1.0, [0.15, 0, 0], np.diag([1e-3, 7.5e-3, 7.5e-3])),
                                pmd.Revolute(axis), parent=parent,
                                translation=(0, 0, 0) if k == 0 else (0.3, 0, 0))
    rng = np.random.default_rng(11)
    for vscale in (0.1, 10.0):
        q = rng.uniform(-np.pi, np.pi, size=n)
        v = rng.normal(size=n) * vscale
        tau = rng.normal(size=n)
        acc = model.forward_dynamics(q, v, tau, gravity=G)
        assert np.all(np.isfinite(acc))
        gim = model.mass_matrix(q)
        assert np.all(np.isfinite(gim))
        assert np.array_equal(gim, gim.T)  # symmetric exactly
        bias = model.bias_forces(q, v, gravity=G)
        exact = np.linalg.solve(gim, tau - bias)
        cond = np.linalg.cond(gim)
        err = np.max(np.abs(acc - exact)) / np.max(np.abs(exact))
        record("1000-link chain: FD vs solve(M, tau - bias)", err)
        record("1000-link chain: FD error / (eps cond)", err / (EPS * cond))
        assert err <= 4 * EPS * cond
        back = model.inverse_dynamics(q, v, acc, gravity=G)
        res = np.max(np.abs(back - tau)) / (np.max(np.abs(tau)) + np.max(np.abs(bias)))
        record("1000-link chain: ID(FD) residual", res)
        assert res <= 1e-9


def test_200_link_rope_pinned_at_one_end():
    # The other form of the brief's rope: one 200-link rope pinned at one end, 2 s.
    n = 200
    link = rope_link(1.0 / n, 1.0 / n, 0.01)
    model = pmd.Model()
    parent = -1
    for k in range(n):
        parent = model.add_body(link, pmd.Revolute([0, 1, 0]), parent=parent,
                                translation=(0, 0, 0) if k == 0 else (1.0 / n, 0, 0))
    scene = pmd.Scene(model, np.zeros(n), np.zeros(n), effects=[pmd.Gravity(G)])
    r = pmd.simulate(scene, (0.0, 2.0), rtol=1e-4, atol=1e-4, energy=True)
    assert r.success, r.message
    assert np.all(np.isfinite(r.q)) and np.all(np.isfinite(r.v))
    kinetic = max(model.kinetic_energy(q, v) for q, v in zip(r.q[::20], r.v[::20]))
    drift = np.max(np.abs(r.energy - r.energy[0])) / kinetic
    record("200-link rope (one end): energy drift / max KE at 1e-4", drift)
    assert drift <= 1e-2
    # The rope ends up hanging around the vertical: the free end falls about a rope length.
    tip = model.placements(r.q[-1])[1][-1]
    assert -1.01 <= tip[2] <= 0.0


# ============================================================================================
# 5. Long horizon: a conservative double pendulum over 1000 s
# ============================================================================================
def double_pendulum() -> pmd.Model:
    model = pmd.Model()
    p = model.add_body(rod(1.0, 1.0, 0.05), pmd.Revolute([0, 1, 0]), name="upper")
    model.add_body(rod(1.0, 1.0, 0.05), pmd.Revolute([0, 1, 0]), parent=p, translation=(1, 0, 0),
                   name="lower")
    return model


LONG_TOLS = [1e-6, 1e-8, 1e-10]


@pytest.fixture(scope="module")
def long_runs():
    model = double_pendulum()
    scene = pmd.Scene(model, [1.2, 0.5], [0.0, 0.0], effects=[pmd.Gravity(G)])
    out = {}
    for tol in LONG_TOLS:
        r = pmd.simulate(scene, (0.0, 1000.0), rtol=tol, atol=tol, energy=True)
        assert r.success, r.message
        kinetic = max(model.kinetic_energy(q, v) for q, v in zip(r.q[::100], r.v[::100]))
        out[tol] = (r, kinetic)
    return out


@pytest.mark.parametrize("tol", LONG_TOLS)
def test_double_pendulum_1000_s_energy_drift_is_bounded(long_runs, tol):
    r, kinetic = long_runs[tol]
    e = (r.energy - r.energy[0]) / kinetic
    drift = np.max(np.abs(e))
    record(f"double pendulum 1000 s: energy drift / max KE at {tol:g}", drift)
    # RK45 is not symplectic: the drift grows linearly, like tol^(4/5) (the global error of
    # a 5th-order pair with local control), 50-150 × tol^0.8 here.
    assert drift <= 500 * tol**0.8
    # Drift, not a random walk: half of it by half time.
    mid = e[np.searchsorted(r.t, 500.0)]
    assert 0.3 <= mid / e[-1] <= 0.7


def test_double_pendulum_drift_falls_with_the_tolerance(long_runs):
    drifts = [np.max(np.abs(long_runs[t][0].energy - long_runs[t][0].energy[0])) for t in LONG_TOLS]
    assert drifts[0] > 20 * drifts[1] > 400 * drifts[2]


# ============================================================================================
# 6. Stiffness: detected and reported, max_steps honoured
# ============================================================================================
LAMBDA = -1e5


def prothero_robinson(t, y):
    """y' = λ (y − cos t) − sin t: exact y = cos t; stiff for |λ| ≫ 1."""
    return LAMBDA * (y - np.cos(t)) - np.sin(t)


def test_stiff_linear_system_is_detected_and_steps_stay_scipys():
    r = pmd.rk45(prothero_robinson, (0.0, 0.05), [1.0], rtol=1e-6, atol=1e-6)
    ref = solve_ivp(prothero_robinson, (0.0, 0.05), [1.0], method="RK45", rtol=1e-6, atol=1e-6)
    assert r.success and r.status == 0
    # Detection only observes: SciPy's steps. Not step for step: at the stability boundary
    # accept/reject alternates on rounding-sized margins (perturbing SciPy's inputs by 1e-15
    # moved its nfev by 0.34 %), so counts within 2 % and the same accuracy.
    assert abs(r.nfev - ref.nfev) <= 0.02 * ref.nfev
    assert abs(len(r.t) - len(ref.t)) <= 0.02 * len(ref.t)
    assert abs(ref.y[0, -1] - np.cos(0.05)) < 1e-6
    stiff = r.stiff
    assert stiff is not None
    assert stiff["t"] < 0.002  # within the first few dozen steps
    assert abs(stiff["lambda"] / abs(LAMBDA) - 1) < 0.05  # the Jacobian is exactly λ
    assert stiff["h_lambda"] > 3.25
    assert "looks stiff" in r.message and "implicit" in r.message
    # Still accurate: stability-limited steps are tiny.
    assert abs(r.y[0, -1] - np.cos(0.05)) < 1e-6
    off = pmd._core.rk45(prothero_robinson, (0.0, 0.05), [1.0], 1e-6, 1e-6, stiffness="off")
    assert off["stiff"] is None and "stiff" not in off["message"]
    np.testing.assert_array_equal(off["t"], r.t)


def test_stiff_linear_system_stop_and_max_steps():
    stop = pmd._core.rk45(prothero_robinson, (0.0, 10.0), [1.0], 1e-6, 1e-6,
                          stiffness="stop")
    assert stop["status"] == -1 and stop["success"] is False
    assert stop["message"].startswith("the problem is stiff at t = ")
    assert stop["n_accepted"] < 100 and stop["t_reached"] == stop["stiff"]["t"]
    capped = pmd.rk45(prothero_robinson, (0.0, 10.0), [1.0], rtol=1e-6, atol=1e-6,
                      max_steps=1000)
    assert capped.status == -1 and capped.n_accepted == 1000
    assert "maximum number of steps (1000)" in capped.message
    assert "looks stiff" in capped.message  # says why so many steps were needed
    with pytest.raises(pmd.InvalidInputError, match="stiffness"):
        pmd._core.rk45(prothero_robinson, (0.0, 1.0), [1.0], stiffness="sometimes")


def spring_scene(k, c):
    model = pmd.Model()
    model.add_body(pmd.RigidBody(1.0, [0.15, 0, 0], np.diag([1e-3, 7.5e-3, 7.5e-3])),
                   pmd.Revolute([0, 1, 0]), name="link")
    return pmd.Scene(model, [0.3], [0.0],
                     effects=[pmd.Gravity(G), pmd.Spring("link", k), pmd.Damper("link", c)])


@pytest.mark.parametrize("k, c, lam", [
    (1e4, 3e3, 1e5),  # overdamped: fast real eigenvalue −c/I_O
    (1e6, 10.0, math.sqrt(1e6 / 0.03)),  # a stiff spring whose oscillation has died out
])
def test_stiff_joint_spring_scene_is_reported(k, c, lam):
    scene = spring_scene(k, c)
    stop = pmd._core.simulate_scene(scene, (0.0, 2.0), 1e-6, 1e-6, stiffness="stop")
    assert stop.status == -1 and "the problem is stiff" in stop.message
    # The typed status carries the same estimate the message prints.
    assert isinstance(stop.outcome, pmd.RunStatus.Stiff)
    est = float(re.search(r", \|λ\| ≈ ([0-9.e+-]+)\)", stop.message).group(1))
    assert est == pytest.approx(stop.outcome.h_lambda / stop.outcome.h, rel=1e-3)
    record(f"stiff spring k={k:g}: |λ| estimate / expected", est / lam)
    assert 0.5 < est / lam < 2.5
    n = stop.n_accepted
    assert n < 20000
    # Default (warn): the run goes on, and when it runs out of steps it says why.
    r = pmd.simulate(scene, (0.0, 2.0), rtol=1e-6, atol=1e-6, max_steps=n + 500)
    assert r.success is False and r.n_accepted == n + 500
    assert f"maximum number of steps ({n + 500})" in r.message
    assert "looks stiff" in r.message, r.message
    # The explicit method's cost: the whole 2 s would take ~ 2 |λ| / 3.3 steps.
    assert 2.0 / (r.t_reached / r.n_accepted) > 0.2 * 2 * lam / 3.3


def test_resolved_stiff_oscillation_is_not_flagged():
    # An undamped stiff spring, oscillating with its full amplitude: the step is set by
    # accuracy (the oscillation is the solution), not stability: no warning.
    r = pmd.simulate(spring_scene(1e6, 0.0), (0.0, 0.5), rtol=1e-6, atol=1e-6)
    assert r.success and "stiff" not in r.message, r.message


@pytest.mark.parametrize("name", ["pendulum_planar", "pendulum_spatial", "chain7", "panda"])
def test_bundled_scenes_are_never_flagged(name):
    scene = pmd.load_scene(name)
    for tol in (1e-2, 1e-4, 1e-7, 1e-10):
        r = pmd.simulate(scene, rtol=tol, atol=tol)
        assert r.success and "stiff" not in r.message, (tol, r.message)


# ============================================================================================
# 7. Bad states and time spans: a clear error, never a hang or a panic
# ============================================================================================
def _spatial():
    return pmd.load_scene("pendulum_spatial")


def _ball():
    model = pmd.Model()
    model.add_body(pmd.RigidBody(1.0, [0.1, 0, 0], np.eye(3) * 0.01), pmd.Spherical())
    return model


BAD = {
    "NaN in q0": (lambda: pmd.Scene(_spatial().model, [np.nan, 0.5, 0.2], [0, 0, 0]), "q0"),
    "inf in v0": (lambda: pmd.Scene(_spatial().model, [0.1, 0.5, 0.2], [0, np.inf, 0]), "v0"),
    "NaN in q (FD)": (lambda: _spatial().model.forward_dynamics([0.1, np.nan, 0.2], [0] * 3,
                                                                [0] * 3), "q"),
    "inf in v (FD)": (lambda: _spatial().model.forward_dynamics([0.1, 0.5, 0.2], [0, 0, -np.inf],
                                                                [0] * 3), "v"),
    "NaN in tau": (lambda: _spatial().model.forward_dynamics([0.1, 0.5, 0.2], [0] * 3,
                                                             [np.nan, 0, 0]), "tau"),
    "zero quaternion": (lambda: pmd.Scene(_ball(), [0, 0, 0, 0], [0, 0, 0]), "norm at least 1e-8"),
    "zero quaternion (FD)": (lambda: _ball().forward_dynamics([0, 0, 0, 0], [0] * 3, [0] * 3),
                             "norm at least 1e-8"),
    "underflowing quaternion": (lambda: _ball().forward_dynamics([1e-200, 0, 0, 0], [0] * 3,
                                                                 [0] * 3), "norm at least 1e-8"),
    "NaN quaternion": (lambda: pmd.Scene(_ball(), [np.nan, 0, 0, 1], [0, 0, 0]), "q0"),
    "empty time span": (lambda: pmd.simulate(_spatial(), (1.0, 1.0)), "t_span"),
    "NaN time span": (lambda: pmd.simulate(_spatial(), (0.0, np.nan)), "t_span"),
    "infinite time span": (lambda: pmd.simulate(_spatial(), (0.0, np.inf)), "t_span"),
    "one time only": (lambda: pmd.simulate(_spatial(), (0.0,)), "t_span"),
    "NaN rtol": (lambda: pmd.simulate(_spatial(), (0.0, 1.0), rtol=np.nan), "rtol"),
    "negative atol": (lambda: pmd.simulate(_spatial(), (0.0, 1.0), atol=-1.0), "atol"),
    "max_steps 0": (lambda: pmd.simulate(_spatial(), (0.0, 1.0), max_steps=0), "max_steps"),
    "NaN max_step": (lambda: pmd.simulate(_spatial(), (0.0, 1.0), max_step=np.nan), "max_step"),
    "t_eval against a backward span": (
        lambda: pmd.simulate(_spatial(), (1.0, 0.0), t_eval=[0.2, 0.5]), "t_eval"),
    "rk45: NaN in y0": (lambda: pmd.rk45(lambda t, y: -y, (0, 1), [np.nan]), "y0"),
    "rk45: empty span": (lambda: pmd.rk45(lambda t, y: -y, (0, 0), [1.0]), "t_span"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_is_a_clear_error(case):
    fn, names = BAD[case]
    with pytest.raises(pmd.InvalidInputError, match=re.escape(names)) as info:
        fn()
    assert isinstance(info.value, ValueError)


def test_state_that_overflows_midway_stops_with_a_message():
    s = _spatial()
    r = pmd.simulate(pmd.Scene(s.model, s.q0, [0, 1e300, 0], effects=[pmd.Gravity(G)]), (0, 1))
    assert r.success is False and "non-finite" in r.message and "t = 0" in r.message
    with pytest.raises(pmd.NumericalError, match="overflow"):
        s.model.forward_dynamics(s.q0, [0, 1e200, 0], np.zeros(3), gravity=G)


def test_nan_from_a_torque_function_fails_the_run_with_its_time():
    # As a NaN from a built-in effect does (issue 11): success=False, the time reached and
    # the trajectory up to it, not an exception that throws the run away.
    s = _spatial()

    def bad(t, q, v):
        return np.array([np.nan, 0, 0]) if t > 0.5 else np.zeros(3)

    scene = pmd.Scene(s.model, s.q0, s.v0, effects=[pmd.Gravity(G), pmd.TorqueFunction(bad)])
    r = pmd.simulate(scene, (0.0, 1.0))
    assert not r.success and r.status == -1
    assert "finite" in r.message and "torque function" in r.message
    # The NaN came in a step from t_reached towards t > 0.5; nothing after it was accepted.
    assert 0.1 < r.t_reached < 1.0 and r.t[-1] == r.t_reached and len(r.t) > 1
    assert f"{r.t_reached}" in r.message
    with pytest.raises(pmd.SimulationError) as info:
        r.raise_for_status()
    assert info.value.t == r.t_reached and info.value.result is r


def test_rk45_nan_derivative_stops_at_once():
    r = pmd.rk45(lambda t, y: y * np.nan, (0, 1), [1.0])
    assert r.status == -1 and "non-finite" in r.message and r.t_reached == 0.0


def test_backward_span_integrates_backward_and_retraces():
    # A backward span is not an error (as in SciPy): it integrates towards t_end < t0.
    s = _spatial()
    fwd = pmd.simulate(s, (0.0, 1.0), rtol=1e-11, atol=1e-12)
    back_scene = pmd.Scene(s.model, fwd.q[-1], fwd.v[-1], effects=[pmd.Gravity(G)])
    back = pmd.simulate(back_scene, (1.0, 0.0), rtol=1e-11, atol=1e-12)
    assert back.success and back.t[-1] == 0.0 and np.all(np.diff(back.t) < 0)
    assert np.max(np.abs(back.q[-1] - s.q0)) <= 1e-8
    assert np.max(np.abs(back.v[-1] - s.v0)) <= 1e-8


def test_huge_span_respects_max_steps():
    r = pmd.simulate(_spatial(), (0.0, 1e300), max_steps=50)
    assert r.status == -1 and r.n_accepted == 50 and "maximum number of steps (50)" in r.message
    # Times far from 1 are printed readably in the messages.
    tiny = pmd.rk45(lambda t, y: -y, (0.0, 1e-300), [1.0], max_steps=1)
    assert "e-" in tiny.message and "0.0000000000" not in tiny.message
