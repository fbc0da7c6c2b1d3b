"""Andrews' squeezing mechanism as published: the equations of the Test Set for IVP Solvers
(Mazzia & Magherini, problem "andrews", file andrews.f; Hairer & Wanner, Solving ODEs II,
§VII.7), transcribed to NumPy — the independent reference our model is checked against.

Coordinates (the paper's order): β, Θ (relative to β), γ, Φ (relative to δ), δ, Ω (relative
to ε), ε. Equations: M(q) q̈ = f(q, q̇) − Gᵀ(q) λ, g(q) = 0. Geometry of the bodies (which
frame each length is measured in) from the PyMbs model of the mechanism; the parameters are
the Test Set's (da = 115e-4)."""

from __future__ import annotations

import numpy as np

P = dict(
    m1=0.04325, m2=0.00365, m3=0.02373, m4=0.00706, m5=0.07050, m6=0.00706, m7=0.05498,
    xa=-0.06934, ya=-0.00227, xb=-0.03635, yb=0.03273, xc=0.014, yc=0.072, c0=4530.0,
    i1=2.194e-6, i2=4.410e-7, i3=5.255e-6, i4=5.667e-7, i5=1.169e-5, i6=5.667e-7, i7=1.912e-5,
    d=28e-3, da=115e-4, e=2e-2, ea=1421e-5, rr=7e-3, ra=92e-5, l0=7785e-5,
    ss=35e-3, sa=1874e-5, sb=1043e-5, sc=18e-3, sd=2e-2, ta=2308e-5, tb=916e-5,
    u=4e-2, ua=1228e-5, ub=449e-5, zf=2e-2, zt=4e-2, fa=1421e-5, mom=33e-3,
)  # fmt: skip

#: Consistent initial state (positions; speeds are zero) and the accelerations and
#: multipliers there, from the Test Set.
Q0 = np.array([
    -0.0617138900142764496358948458001, 0.0, 0.455279819163070380255912382449,
    0.222668390165885884674473185609, 0.487364979543842550225598953530,
    -0.222668390165885884674473185609, 1.23054744454982119249735015568,
])  # fmt: skip
A0 = np.array([14222.4439199541138705911625887, -10666.8329399655854029433719415, 0, 0, 0, 0, 0])
LAMBDA0 = np.array([98.5668703962410896057654982170, -6.12268834425566265503114393122, 0, 0, 0, 0])

#: Reference solution at t = 0.03 (PSIDE, rtol = atol = 1e-14, Cray double precision; it
#: carries about 1e-9 rad of error itself): positions, then speeds.
T_END = 0.03
Q_END = np.array([
    0.1581077119629904e2, -0.1575637105984298e2, 0.4082224013073101e-1, -0.5347301163226948,
    0.5244099658805304, 0.5347301163226948, 0.1048080741042263e1,
])  # fmt: skip
V_END = np.array([
    0.1139920302151208e4, -0.1424379294994111e4, 0.1103291221937134e2, 0.1929337464421385e2,
    0.5735699284790808, -0.1929337464421385e2, 0.3231791658026955,
])  # fmt: skip


def mass_matrix(q):
    b, th, ga, ph, de, om, ep = q
    p = P
    m = np.zeros((7, 7))
    m[0, 0] = (
        p["m1"] * p["ra"] ** 2
        + p["m2"] * (p["rr"] ** 2 - 2 * p["da"] * p["rr"] * np.cos(th) + p["da"] ** 2)
        + p["i1"]
        + p["i2"]
    )
    m[1, 0] = p["m2"] * (p["da"] ** 2 - p["da"] * p["rr"] * np.cos(th)) + p["i2"]
    m[1, 1] = p["m2"] * p["da"] ** 2 + p["i2"]
    m[2, 2] = p["m3"] * (p["sa"] ** 2 + p["sb"] ** 2) + p["i3"]
    ee = p["e"] - p["ea"]
    m[3, 3] = p["m4"] * ee**2 + p["i4"]
    m[4, 3] = p["m4"] * (ee**2 + p["zt"] * ee * np.sin(ph)) + p["i4"]
    m[4, 4] = (
        p["m4"] * (p["zt"] ** 2 + 2 * p["zt"] * ee * np.sin(ph) + ee**2)
        + p["m5"] * (p["ta"] ** 2 + p["tb"] ** 2)
        + p["i4"]
        + p["i5"]
    )
    zz = p["zf"] - p["fa"]
    m[5, 5] = p["m6"] * zz**2 + p["i6"]
    m[6, 5] = p["m6"] * (zz**2 - p["u"] * zz * np.sin(om)) + p["i6"]
    m[6, 6] = (
        p["m6"] * (zz**2 - 2 * p["u"] * zz * np.sin(om) + p["u"] ** 2)
        + p["m7"] * (p["ua"] ** 2 + p["ub"] ** 2)
        + p["i6"]
        + p["i7"]
    )
    return np.tril(m) + np.tril(m, -1).T


def velocity_forces(q, qd):
    """The velocity-product part of f (Coriolis and centrifugal), on the right-hand side."""
    _, th, _, ph, _, om, _ = q
    bep, thp, _, php, dep, omp, epp = qd
    p = P
    ee, zz = p["e"] - p["ea"], p["zf"] - p["fa"]
    return np.array([
        -p["m2"] * p["da"] * p["rr"] * thp * (thp + 2 * bep) * np.sin(th),
        p["m2"] * p["da"] * p["rr"] * bep**2 * np.sin(th),
        0.0,
        p["m4"] * p["zt"] * ee * dep**2 * np.cos(ph),
        -p["m4"] * p["zt"] * ee * php * (php + 2 * dep) * np.cos(ph),
        -p["m6"] * p["u"] * zz * epp**2 * np.cos(om),
        p["m6"] * p["u"] * zz * omp * (omp + 2 * epp) * np.cos(om),
    ])  # fmt: skip


def spring_point(q):
    """Point D of body 3 (the spring's moving end), world."""
    ga = q[2]
    p = P
    return np.array(
        [
            p["sd"] * np.cos(ga) + p["sc"] * np.sin(ga) + p["xb"],
            p["sd"] * np.sin(ga) - p["sc"] * np.cos(ga) + p["yb"],
        ]
    )


def applied_forces(q):
    """The drive torque on β and the spring's generalized force (on γ)."""
    p = P
    ga = q[2]
    xd, yd = spring_point(q)
    length = np.hypot(xd - p["xc"], yd - p["yc"])
    force = -p["c0"] * (length - p["l0"]) / length
    fx, fy = force * (xd - p["xc"]), force * (yd - p["yc"])
    out = np.zeros(7)
    out[0] = p["mom"]
    out[2] = fx * (p["sc"] * np.cos(ga) - p["sd"] * np.sin(ga)) + fy * (
        p["sd"] * np.cos(ga) + p["sc"] * np.sin(ga)
    )
    return out


def constraints(q):
    b, th, ga, ph, de, om, ep = q
    p = P
    e_x = p["rr"] * np.cos(b) - p["d"] * np.cos(b + th)
    e_y = p["rr"] * np.sin(b) - p["d"] * np.sin(b + th)
    return np.array([
        e_x - p["ss"] * np.sin(ga) - p["xb"],
        e_y + p["ss"] * np.cos(ga) - p["yb"],
        e_x - p["e"] * np.sin(ph + de) - p["zt"] * np.cos(de) - p["xa"],
        e_y + p["e"] * np.cos(ph + de) - p["zt"] * np.sin(de) - p["ya"],
        e_x - p["zf"] * np.cos(om + ep) - p["u"] * np.sin(ep) - p["xa"],
        e_y - p["zf"] * np.sin(om + ep) + p["u"] * np.cos(ep) - p["ya"],
    ])  # fmt: skip


def constraint_jacobian(q):
    b, th, ga, ph, de, om, ep = q
    p = P
    s, c = np.sin, np.cos
    g = np.zeros((6, 7), dtype=np.result_type(q, float))
    for r in (0, 2, 4):
        g[r, 0] = -p["rr"] * s(b) + p["d"] * s(b + th)
        g[r, 1] = p["d"] * s(b + th)
    for r in (1, 3, 5):
        g[r, 0] = p["rr"] * c(b) - p["d"] * c(b + th)
        g[r, 1] = -p["d"] * c(b + th)
    g[0, 2] = -p["ss"] * c(ga)
    g[1, 2] = -p["ss"] * s(ga)
    g[2, 3] = -p["e"] * c(ph + de)
    g[2, 4] = -p["e"] * c(ph + de) + p["zt"] * s(de)
    g[3, 3] = -p["e"] * s(ph + de)
    g[3, 4] = -p["e"] * s(ph + de) - p["zt"] * c(de)
    g[4, 5] = p["zf"] * s(om + ep)
    g[4, 6] = p["zf"] * s(om + ep) - p["u"] * c(ep)
    g[5, 5] = -p["zf"] * c(om + ep)
    g[5, 6] = -p["zf"] * c(om + ep) - p["u"] * s(ep)
    return g


def index1_rhs(q, qd):
    """Accelerations and multipliers of the index-1 form: [M Gᵀ; G 0][q̈; λ] = [f; −g_qq(q̇, q̇)],
    with g_qq(q̇, q̇) = d(G q̇)/dt at q̈ = 0 by a complex-step derivative of G along q̇ (exact to
    round-off: G is analytic)."""
    m = mass_matrix(q)
    g = constraint_jacobian(q)
    h = 1e-30
    gqq = constraint_jacobian(q + 1j * h * qd).imag @ qd / h
    f = velocity_forces(q, qd) + applied_forces(q)
    k = np.block([[m, g.T], [g, np.zeros((6, 6))]])
    x = np.linalg.solve(k, np.concatenate([f, -gqq]))
    return x[:7], x[7:]
