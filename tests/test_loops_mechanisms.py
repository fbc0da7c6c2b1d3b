"""The bundled loop mechanisms (scenes fourbar, slider_crank, rssr) against results that do
not come from our code: Freudenstein's equation, the slider-crank's closed form, the RSSR
closure equation solved by SciPy's brentq, crank torques from Lagrangians derived in SymPy,
the Newton–Euler balance of single links under the reported cut-joint forces, and energy.

Every reference is computed from the scene file's own inputs (lengths, masses, inertias,
gravity), read with tomllib: the file is the mechanism's definition, the model built from it
is what is tested."""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pointmass_dyn as pmd
import pytest
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

sp = pytest.importorskip("sympy")
try:
    import tomllib
except ImportError:  # Python < 3.11
    tomllib = pytest.importorskip("tomli")


def scene_file(name):
    """The bundled scene's TOML as a dict, with bodies and loops by name."""
    with open(pmd.builtin_scenes()[name], "rb") as f:
        data = tomllib.load(f)
    data["bodies"] = {b["name"]: b for b in data["body"]}
    data["loops"] = {lp["name"]: lp for lp in data["loop"]}
    (gravity,) = [e for e in data["effect"] if e["type"] == "gravity"]
    data["g"] = np.array(gravity["g"], float)
    return data


def ops(symbolic):
    """cos, sin, sqrt, atan2 for SymPy expressions or NumPy arrays."""
    if symbolic:
        return sp.cos, sp.sin, sp.sqrt, sp.atan2
    return np.cos, np.sin, np.sqrt, np.arctan2


def wrap(x):
    """Angle(s) in (−π, π]."""
    return np.angle(np.exp(1j * np.asarray(x)))


def assert_planar_xy(data):
    """The closed forms below are for links in the x–y plane on z axes, each link's COM on
    its x axis: check the file says so."""
    for b in data["bodies"].values():
        if b["joint"]["type"] == "Revolute":
            assert b["joint"]["axis"] == [0.0, 0.0, 1.0]
        assert b.get("translation", [0.0] * 3)[2] == 0.0 and "rpy" not in b
        assert b["com"][1:] == [0.0, 0.0]
    for lp in data["loops"].values():
        assert lp["joint"] == {"type": "Revolute", "axis": [0.0, 0.0, 1.0]}
        assert lp["translation_a"][1:] == lp["translation_b"][1:] == [0.0, 0.0]
    assert data["g"][2] == 0.0


# --------------------------------------------------------------------------------------------
# A one-degree-of-freedom mechanism's Lagrangian in SymPy
# --------------------------------------------------------------------------------------------
THETA, OMEGA, ALPHA = sp.symbols("theta omega alpha")  # crank angle, speed, acceleration


class OneDof:
    """A one-degree-of-freedom mechanism in SymPy, positions as functions of the crank angle
    θ. Dependent angles enter as undefined functions f(θ) (so the Lagrangian stays small),
    each with its closed form, whose derivatives SymPy takes when a function is evaluated."""

    def __init__(self, closed_forms):
        # (f or one of its derivatives, the symbol standing for it, its closed form as a
        # NumPy function of θ)
        self.args = []
        for f, expr in closed_forms.items():
            for k in (2, 1, 0):  # highest first: substituting f would touch its derivatives
                key = f.diff(THETA, k) if k else f
                value = expr.diff(THETA, k) if k else expr
                sym = sp.Symbol(f"{f.func.__name__}_{k}")
                self.args.append((key, sym, sp.lambdify(THETA, value, "numpy", cse=True)))

    def numeric(self, expr):
        """`expr` (of θ, ω, α and the dependent angles) as a NumPy function of (θ, ω, α)."""
        for key, sym, _ in self.args:
            expr = expr.subs(key, sym)
        syms = [sym for _, sym, _ in self.args]
        f = sp.lambdify((THETA, OMEGA, ALPHA, *syms), expr, "numpy", cse=True)
        return lambda th, w, a: f(th, w, a, *[value(th) for _, _, value in self.args])

    def rates(self, expr):
        """Value, velocity and acceleration of `expr`(θ(t)), functions of (θ, ω, α)."""
        d1 = expr.diff(THETA)
        return [self.numeric(e) for e in (expr, d1 * OMEGA, d1.diff(THETA) * OMEGA**2 + d1 * ALPHA)]

    def crank_torque(self, parts, g):
        """τ(θ, ω, α) = d/dt ∂L/∂θ̇ − ∂L/∂θ with L = T − V, T = Σ ½ m |ṙ_G|² + ½ I φ̇²,
        V = −Σ m g·r_G. `parts`: (mass, I_zz about the COM, COM x, COM y, link angle) per
        link, expressions of θ; velocities are ∂/∂θ · θ̇ (one coordinate)."""
        kinetic = sum(
            m * ((x.diff(THETA) * OMEGA) ** 2 + (y.diff(THETA) * OMEGA) ** 2) / 2
            + izz * (phi.diff(THETA) * OMEGA) ** 2 / 2
            for m, izz, x, y, phi in parts
        )
        potential = -sum(m * (g[0] * x + g[1] * y) for m, _, x, y, _ in parts)
        lag = kinetic - potential
        p = lag.diff(OMEGA)
        # d/dt of p(θ, θ̇) along the motion: ∂p/∂θ θ̇ + ∂p/∂θ̇ θ̈.
        return self.numeric(p.diff(THETA) * OMEGA + p.diff(OMEGA) * ALPHA - lag.diff(THETA))


def prescribed_states(model, q0, crank_angles, omega, alpha):
    """Closed states along the crank angles by continuation from q0 (each assemble starts
    at the previous state), with the crank's speed and acceleration prescribed."""
    q = np.array(q0, float)
    out = []
    for th in crank_angles:
        guess = q.copy()
        guess[0] = th
        q = model.assemble(guess, fixed=["crank"])
        assert q[0] == th and np.abs(model.constraint_residual(q)).max() <= 1e-12
        v = model.assemble_velocity(q, np.r_[omega, np.zeros(model.nv - 1)], fixed=["crank"])
        a = model.assemble_acceleration(q, v, np.r_[alpha, np.zeros(model.nv - 1)], fixed=["crank"])
        assert v[0] == omega and a[0] == alpha
        out.append((q, v, a))
    return out


# --------------------------------------------------------------------------------------------
# Four-bar
# --------------------------------------------------------------------------------------------
class FourBar:
    """The file's four-bar: lengths a (crank), b (coupler), c (rocker), d (ground)."""

    def __init__(self):
        data = scene_file("fourbar")
        assert_planar_xy(data)
        bodies, (loop,) = data["bodies"], data["loops"].values()
        assert (loop["body_a"], loop["body_b"]) == ("coupler", "rocker")
        assert bodies["coupler"]["parent"] == "crank" and bodies["rocker"]["parent"] == "world"
        assert bodies["crank"].get("translation", [0.0] * 3) == [0.0] * 3
        assert bodies["rocker"]["translation"][1] == 0.0
        self.a = bodies["coupler"]["translation"][0]
        self.b = loop["translation_a"][0]
        self.c = loop["translation_b"][0]
        self.d = bodies["rocker"]["translation"][0]
        self.bodies, self.g = bodies, data["g"]

    def rocker_angle(self, th, symbolic=False):
        """Freudenstein: K1 cos θ4 − K2 cos θ2 + K3 = cos(θ2 − θ4) solved for θ4 (Norton's
        A, B, C form), open configuration."""
        cos, sin, sqrt, atan2 = ops(symbolic)
        a, b, c, d = self.a, self.b, self.c, self.d
        k1, k2, k3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
        big_a = cos(th) - k1 - k2 * cos(th) + k3
        big_b = -2 * sin(th)
        big_c = k1 - (k2 + 1) * cos(th) + k3
        # 2 atan2(y, x) equals 2 atan(y/x) modulo 2π, and stays smooth where x changes sign.
        return 2 * atan2(-big_b - sqrt(big_b**2 - 4 * big_a * big_c), 2 * big_a)

    def coupler_angle(self, th, th4, symbolic=False):
        """From the loop a e^{iθ2} + b e^{iθ3} = d + c e^{iθ4}."""
        cos, sin, _, atan2 = ops(symbolic)
        return atan2(
            self.c * sin(th4) - self.a * sin(th), self.d + self.c * cos(th4) - self.a * cos(th)
        )

    def symbolic(self):
        """The mechanism in SymPy (closed forms for the coupler and rocker angles) and each
        link's COM x, y and angle as expressions of θ."""
        th3, th4 = sp.Function("theta3")(THETA), sp.Function("theta4")(THETA)
        rocker = self.rocker_angle(THETA, symbolic=True)
        mech = OneDof({th4: rocker, th3: self.coupler_angle(THETA, rocker, symbolic=True)})
        cx = {n: b["com"][0] for n, b in self.bodies.items()}
        pin_a = (self.a * sp.cos(THETA), self.a * sp.sin(THETA))
        links = {
            "crank": (cx["crank"] * sp.cos(THETA), cx["crank"] * sp.sin(THETA), THETA),
            "coupler": (pin_a[0] + cx["coupler"] * sp.cos(th3),
                        pin_a[1] + cx["coupler"] * sp.sin(th3), th3),
            "rocker": (self.d + cx["rocker"] * sp.cos(th4), cx["rocker"] * sp.sin(th4), th4),
        }
        return mech, links


@functools.cache
def fourbar_reference():
    """The file's four-bar, its SymPy links and its crank torque τ(θ, ω, α)."""
    fb = FourBar()
    mech, links = fb.symbolic()
    parts = [(fb.bodies[n]["mass"], fb.bodies[n]["inertia_diag"][2], *links[n]) for n in links]
    return fb, mech, links, mech.crank_torque(parts, fb.g)


@pytest.fixture(scope="module")
def fourbar_run():
    scene = pmd.load_scene("fourbar")
    res = pmd.simulate(scene, energy=True)  # the file's own t_end and tolerances
    assert res.success, res.message
    return scene, res


def test_fourbar_scene_is_the_textbook_grashof_crank_rocker():
    fb = FourBar()
    links = sorted([fb.a, fb.b, fb.c, fb.d])
    assert links[0] + links[3] < links[1] + links[2]  # Grashof
    assert fb.a == links[0]  # the crank (next to the ground) is the shortest: crank-rocker
    m = pmd.load_scene("fourbar").model
    assert (m.nq, m.nloops, m.nconstraints, m.loop_names) == (3, 1, 5, ["coupler-rocker"])


def test_fourbar_rocker_follows_freudenstein(fourbar_run):
    scene, res = fourbar_run
    fb = FourBar()
    th2, th3, th4 = res.q[:, 0], res.q[:, 0] + res.q[:, 1], res.q[:, 2]
    assert np.ptp(th2) > 4 * np.pi  # full turns of the crank, so every crank angle is seen
    ref4 = fb.rocker_angle(th2)
    err4 = np.abs(wrap(th4 - ref4)).max()
    err3 = np.abs(wrap(th3 - fb.coupler_angle(th2, ref4))).max()
    assert err4 < 1e-10 and err3 < 1e-10, (err4, err3)
    # The run is the one the file declares: started where it says, closed to round-off.
    np.testing.assert_allclose([res.q[0, 0], res.v[0, 0]], [scene.q0[0], scene.v0[0]], rtol=1e-14)
    assert res.constraint_residual.max() < 1e-13


def test_fourbar_energy_is_conserved(fourbar_run):
    scene, res = fourbar_run
    m = scene.model
    kinetic = max(m.kinetic_energy(q, v) for q, v in zip(res.q, res.v))
    # Gravity only: T + V constant to the integration tolerance (rtol 1e-10; measured
    # ~1e-10 of the largest kinetic energy over the run).
    assert np.abs(res.energy - res.energy[0]).max() < 5e-9 * kinetic
    # The energy is the file's: T from the SymPy model of the same links at the first state.
    fb, mech, links, _ = fourbar_reference()
    th, w = res.q[0, 0], res.v[0, 0]
    t_ref = 0.0
    for n, (x, y, phi) in links.items():
        (_, dx, _), (_, dy, _), (_, dphi, _) = mech.rates(x), mech.rates(y), mech.rates(phi)
        b = fb.bodies[n]
        t_ref += 0.5 * b["mass"] * (dx(th, w, 0) ** 2 + dy(th, w, 0) ** 2)
        t_ref += 0.5 * b["inertia_diag"][2] * dphi(th, w, 0) ** 2
    assert abs(m.kinetic_energy(res.q[0], res.v[0]) - t_ref) < 1e-12 * t_ref


@pytest.mark.parametrize("alpha", [0.0, 150.0])
def test_fourbar_crank_torque_equals_the_sympy_lagrangian(alpha):
    """Crank torque to drive the four-bar at 25 rad/s (constant, and accelerating) over a
    revolution: inverse dynamics with the crank the only actuator against τ = d/dt ∂L/∂θ̇ −
    ∂L/∂θ of the closed-form kinematics."""
    fb, _, _, tau_ref = fourbar_reference()
    scene = pmd.load_scene("fourbar")
    m, g, omega = scene.model, fb.g, 25.0
    angles = np.linspace(0.0, 2 * np.pi, 37)[:-1]
    got, ref = [], []
    for q, v, a in prescribed_states(m, scene.q0, angles, omega, alpha):
        tau = m.inverse_dynamics(q, v, a, gravity=g, actuated=["crank"])
        assert tau[1] == tau[2] == 0.0
        got.append(tau[0])
        ref.append(tau_ref(q[0], omega, alpha))
    got, ref = np.array(got), np.array(ref)
    assert np.abs(got - ref).max() < 1e-13 * np.abs(ref).max(), np.abs(got - ref).max()
    assert np.ptp(ref) > 0.5 * np.abs(ref).max()  # a torque that varies over the revolution


def test_fourbar_cut_joint_force_balances_the_rocker_and_the_coupler():
    """The reported force at the coupler–rocker pin, with the driving torque applied, in
    Newton–Euler balances of single links (their accelerations from the closed form):

    * rocker about its ground pivot O: I_O θ̈4 = (r_B − O) × F + (r_G − O) × m g;
    * coupler about the crank pin A (moving): (r_B − A) × (−F) + (r_G − A) × m g =
      I_G θ̈3 + (r_G − A) × m a_G.

    Two independent equations: together they fix both in-plane components of F."""
    fb, mech, links, tau_ref = fourbar_reference()
    scene = pmd.load_scene("fourbar")
    m, g, omega, alpha = scene.model, fb.g, 25.0, 150.0
    kin = {n: [mech.rates(e) for e in links[n]] for n in links}

    def cross(u, v):
        return u[0] * v[1] - u[1] * v[0]

    angles = np.linspace(0.0, 2 * np.pi, 13)[:-1]
    for q, v, a in prescribed_states(m, scene.q0, angles, omega, alpha):
        tau = m.inverse_dynamics(q, v, a, gravity=g, actuated=["crank"])
        (f,) = m.constraint_forces(q, v, tau, gravity=g)
        # Frictionless revolute: no moment about its axis; out-of-plane parts (statically
        # indeterminate) are the minimum-norm zero.
        assert np.abs(f[2:]).max() <= 1e-12 * np.abs(f[:2]).max()
        rot, _ = m.placements(q)
        # Frame a is the coupler's body frame (no rotation_a): F in world axes.
        force = (rot[m.body_names.index("coupler")] @ f[:3])[:2]
        state = (q[0], omega, alpha)
        th = q[0]
        pin_a = np.array([fb.a * np.cos(th), fb.a * np.sin(th)])
        th4 = fb.rocker_angle(th)
        pin_b = np.array([fb.d + fb.c * np.cos(th4), fb.c * np.sin(th4)])
        pivot = np.array([fb.d, 0.0])

        def com(n, k):
            return np.array([kin[n][0][k](*state), kin[n][1][k](*state)])

        rk, cp = fb.bodies["rocker"], fb.bodies["coupler"]
        i_o = rk["inertia_diag"][2] + rk["mass"] * rk["com"][0] ** 2
        lhs = i_o * kin["rocker"][2][2](*state)
        rhs = cross(pin_b - pivot, force) + cross(com("rocker", 0) - pivot, rk["mass"] * g[:2])
        scale = abs(cross(pin_b - pivot, force)) + abs(lhs)
        assert abs(lhs - rhs) < 1e-13 * scale, (lhs, rhs)
        r_g = com("coupler", 0) - pin_a
        lhs = cross(pin_b - pin_a, -force) + cross(r_g, cp["mass"] * g[:2])
        rhs = cp["inertia_diag"][2] * kin["coupler"][2][2](*state) + cross(
            r_g, cp["mass"] * com("coupler", 2)
        )
        scale = abs(cross(pin_b - pin_a, force)) + abs(rhs)
        assert abs(lhs - rhs) < 1e-13 * scale, (lhs, rhs)


# --------------------------------------------------------------------------------------------
# Slider-crank
# --------------------------------------------------------------------------------------------
class SliderCrank:
    def __init__(self):
        data = scene_file("slider_crank")
        assert_planar_xy(data)
        bodies, (loop,) = data["bodies"], data["loops"].values()
        assert (loop["body_a"], loop["body_b"]) == ("rod", "slider")
        assert bodies["slider"]["joint"] == {"type": "Prismatic", "axis": [1.0, 0.0, 0.0]}
        assert bodies["slider"]["translation"][0] == 0.0 and loop["translation_b"] == [0.0] * 3
        self.r = bodies["rod"]["translation"][0]
        self.l = loop["translation_a"][0]
        self.e = bodies["slider"]["translation"][1]
        self.bodies, self.g = bodies, data["g"]

    def stroke(self, th, symbolic=False):
        """s = r cos θ + √(l² − (r sin θ − e)²)."""
        cos, sin, sqrt, _ = ops(symbolic)
        return self.r * cos(th) + sqrt(self.l**2 - (self.r * sin(th) - self.e) ** 2)


@functools.cache
def slider_crank_reference():
    """The file's slider-crank, its SymPy links and its crank torque τ(θ, ω, α)."""
    sc = SliderCrank()
    s, phi = sp.Function("s")(THETA), sp.Function("phi")(THETA)
    stroke = sc.stroke(THETA, symbolic=True)
    # The rod's angle: from the crank pin (r cos θ, r sin θ) to the wrist pin (s, e).
    rod = sp.atan2(sc.e - sc.r * sp.sin(THETA), stroke - sc.r * sp.cos(THETA))
    mech = OneDof({s: stroke, phi: rod})
    cx = {n: b["com"][0] for n, b in sc.bodies.items()}
    links = {
        "crank": (cx["crank"] * sp.cos(THETA), cx["crank"] * sp.sin(THETA), THETA),
        "rod": (sc.r * sp.cos(THETA) + cx["rod"] * sp.cos(phi),
                sc.r * sp.sin(THETA) + cx["rod"] * sp.sin(phi), phi),
        "slider": (s + cx["slider"], sp.Float(sc.e), sp.Integer(0)),
    }
    parts = [(sc.bodies[n]["mass"], sc.bodies[n]["inertia_diag"][2], *links[n]) for n in links]
    return sc, mech, links, mech.crank_torque(parts, sc.g)


def test_slider_follows_the_closed_form_stroke():
    scene = pmd.load_scene("slider_crank")
    res = pmd.simulate(scene, energy=True)
    assert res.success, res.message
    sc = SliderCrank()
    th = res.q[:, 0]
    assert np.ptp(th) > 4 * np.pi
    err = np.abs(res.q[:, 2] - sc.stroke(th)).max()
    assert err < 1e-12 * sc.l, err
    # The rod's absolute angle points from the crank pin to the wrist pin (s, e).
    phi = np.arctan2(sc.e - sc.r * np.sin(th), res.q[:, 2] - sc.r * np.cos(th))
    assert np.abs(wrap(res.q[:, 0] + res.q[:, 1] - phi)).max() < 1e-10
    kinetic = max(scene.model.kinetic_energy(q, v) for q, v in zip(res.q, res.v))
    assert np.abs(res.energy - res.energy[0]).max() < 5e-9 * kinetic
    assert res.constraint_residual.max() < 1e-13


@pytest.mark.parametrize("alpha", [0.0, -200.0])
def test_slider_crank_torque_equals_the_sympy_lagrangian(alpha):
    sc, mech, links, tau_ref = slider_crank_reference()
    scene = pmd.load_scene("slider_crank")
    m, g, omega = scene.model, sc.g, 30.0
    angles = np.linspace(0.0, 2 * np.pi, 37)[:-1]
    _, _, s_acc = mech.rates(links["slider"][0])
    got, ref = [], []
    for q, v, a in prescribed_states(m, scene.q0, angles, omega, alpha):
        tau = m.inverse_dynamics(q, v, a, gravity=g, actuated=["crank"])
        got.append(tau[0])
        ref.append(tau_ref(q[0], omega, alpha))
        # The wrist-pin force on the slider (body b) is all that drives it along the rail
        # (gravity and the rail's reaction are normal to it): F_x = m s̈.
        (f,) = m.constraint_forces(q, v, tau, gravity=g)
        rot, _ = m.placements(q)
        fx = (rot[m.body_names.index("rod")] @ f[:3])[0]  # frame a: the rod's body frame
        m_slider = sc.bodies["slider"]["mass"]
        expected = m_slider * s_acc(q[0], omega, alpha)
        # Measured ~8e-15 (round-off: the minimum-norm solves are orthogonal factorizations).
        assert abs(fx - expected) < 1e-13 * m_slider * sc.r * omega**2, (fx, expected)
    got, ref = np.array(got), np.array(ref)
    # Measured ~2e-14: the torque is small beside the pin forces it is solved with.
    assert np.abs(got - ref).max() < 1e-13 * np.abs(ref).max(), np.abs(got - ref).max()


# --------------------------------------------------------------------------------------------
# RSSR
# --------------------------------------------------------------------------------------------
class RSSR:
    """The file's RSSR: crank tip A(θ) on a circle about z, rocker tip B(φ) on a circle about
    the rocker's skew axis, |B − A| = coupler length."""

    def __init__(self):
        data = scene_file("rssr")
        bodies, (loop,) = data["bodies"], data["loops"].values()
        assert bodies["crank"]["joint"] == {"type": "Revolute", "axis": [0.0, 0.0, 1.0]}
        assert bodies["crank"].get("translation", [0.0] * 3) == [0.0] * 3
        assert bodies["coupler"]["joint"]["type"] == "Spherical"
        assert bodies["coupler"]["parent"] == "crank" and bodies["rocker"]["parent"] == "world"
        assert bodies["rocker"]["joint"] == {"type": "Revolute", "axis": [0.0, 0.0, 1.0]}
        assert loop["joint"] == {"type": "Spherical"}
        assert (loop["body_a"], loop["body_b"]) == ("coupler", "rocker")
        assert bodies["coupler"]["translation"][1:] == [0.0, 0.0]
        assert loop["translation_a"][1:] == loop["translation_b"][1:] == [0.0, 0.0]
        assert data.get("angles", "radians") == "radians"
        self.r1 = bodies["coupler"]["translation"][0]
        self.length = loop["translation_a"][0]
        self.r3 = loop["translation_b"][0]
        self.pivot = np.array(bodies["rocker"]["translation"], float)
        # URDF rpy: R = Rz(yaw) Ry(pitch) Rx(roll).
        frame = Rotation.from_euler("ZYX", bodies["rocker"]["rpy"][::-1]).as_matrix()
        self.u, self.w, self.axis = frame.T

    def a(self, th):
        return self.r1 * np.array([np.cos(th), np.sin(th), 0.0])

    def b(self, phi):
        return self.pivot + self.r3 * (np.cos(phi) * self.u + np.sin(phi) * self.w)

    def closure(self, phi, th):
        d = self.b(phi) - self.a(th)
        return d @ d - self.length**2

    def output_angles(self, th):
        """Both roots φ of the closure equation in [−π, π) (brentq on the sign changes of a
        grid), each with the sign of ∂f/∂φ there, which tells the two assembly branches
        apart for every crank angle."""
        grid = np.linspace(-np.pi, np.pi, 73)
        f = np.array([self.closure(p, th) for p in grid])
        roots = []
        for k in np.flatnonzero(np.sign(f[:-1]) != np.sign(f[1:])):
            phi = brentq(self.closure, grid[k], grid[k + 1], args=(th,), xtol=1e-15, rtol=1e-15)
            roots.append((phi, np.sign(f[k + 1] - f[k])))
        assert len(roots) == 2, roots  # the crank turns fully: always two assemblies
        return roots


def test_rssr_axes_are_skew():
    r = RSSR()
    z = np.array([0.0, 0.0, 1.0])
    # Not parallel, and the common normal has length > 0: the axes neither meet nor are
    # parallel, so the mechanism is truly spatial.
    normal = np.cross(z, r.axis)
    assert np.linalg.norm(normal) > 0.3
    assert abs(r.pivot @ normal) / np.linalg.norm(normal) > 0.01


def test_rssr_output_angle_equals_the_closure_equations_root():
    scene = pmd.load_scene("rssr")
    m = scene.model
    res = pmd.simulate(scene, (0.0, 0.5), energy=True)
    assert res.success, res.message
    assert res.constraint_residual.max() <= 1e-10
    kinetic = max(m.kinetic_energy(q, v) for q, v in zip(res.q, res.v))
    assert np.abs(res.energy - res.energy[0]).max() < 5e-9 * kinetic
    r = RSSR()
    th, phi = res.q[:, 0], res.q[:, -1]
    assert np.ptp(th) > 2 * np.pi  # the crank turns fully
    # The branch the scene starts on, then the same branch at every sample.
    (branch,) = [s for p, s in r.output_angles(th[0]) if abs(wrap(p - phi[0])) < 1e-6]
    worst = 0.0
    for t_k, p_k in zip(th[::4], phi[::4]):
        (ref,) = [p for p, s in r.output_angles(t_k) if s == branch]
        worst = max(worst, abs(wrap(p_k - ref)))
    assert worst < 1e-10, worst
    # The rocker's speed from the closure's time derivative:
    # (B − A)·(∂B/∂φ φ̇ − ∂A/∂θ θ̇) = 0.
    for q, v in zip(res.q[::25], res.v[::25]):
        d = r.b(q[-1]) - r.a(q[0])
        db = r.r3 * (-np.sin(q[-1]) * r.u + np.cos(q[-1]) * r.w)
        da = r.r1 * np.array([-np.sin(q[0]), np.cos(q[0]), 0.0])
        assert abs(v[-1] - (d @ da) * v[0] / (d @ db)) < 1e-9 * abs(v[0])


@pytest.mark.parametrize("method", ["RK45", "auto"])
def test_bricard_at_loose_tolerances_is_never_called_locked(method):
    """The Bricard linkage (IFToMM A04) moves only by its special geometry: a trial stage far
    off the loops' manifolds (rtol 1e-2) is generically rigid. Such a stage is a rejected
    trial, not a verdict on the mechanism: the run never reports it locked (it did, advising
    to remove a cut joint), and a failure at that tolerance says to tighten rtol/atol."""
    scene = pmd.load_scene("iftomm_a04_bricard")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for tol in (1e-2, 3e-3):
            r = pmd.simulate(scene, (0.0, 10.0), method=method, rtol=tol, atol=tol)
            assert "no freedom of motion" not in r.message, r.message
            assert r.success or "tighten rtol/atol" in r.message, r.message
