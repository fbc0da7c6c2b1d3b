"""Issue 38, item 4: a run that leaves its branch at a singular position, or loses its
accuracy passing one, must say so. A family of one-degree-of-freedom mechanisms, each
against its exact reduction (a one-degree-of-freedom Lagrangian from closed-form positions,
SymPy, integrated by SciPy at tight tolerances; A02 and A04 as tests/test_iftomm.py builds
them): every run is within 100 rtol of the reference (largest angle error), or it reported a
passage (``singular_passage``, with a warning) or a singular position passed at a tolerance
tighter than such a passage keeps (``singular_crossings`` and a note in its message)."""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pointmass_dyn as pmd
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from test_iftomm import G, Z, bricard_reduction, n_fourbar_rate, rod

TH = sp.Symbol("theta")


def unit(angle):
    return sp.Matrix([sp.cos(angle), sp.sin(angle)])


def four_bar(crank, coupler, rocker, ground, masses):
    """Crank at the origin, rocker pivoted at (ground, 0), the cut joint between the
    coupler's and the rocker's free ends (as tests/test_iftomm.py's parallelogram)."""
    m = pmd.Model()
    m.add_body(rod(crank, masses[0]), pmd.Revolute(Z), name="crank")
    m.add_body(rod(coupler, masses[1]), pmd.Revolute(Z), parent=0, translation=[crank, 0, 0],
               name="coupler")
    m.add_body(rod(rocker, masses[2]), pmd.Revolute(Z), translation=[ground, 0, 0], name="rocker")
    m.add_loop("coupler", "rocker", pmd.Revolute(Z), translation_a=[coupler, 0, 0],
               translation_b=[rocker, 0, 0])
    return m


class Reduction:
    """The one-degree-of-freedom motion theta(t) of a planar mechanism whose links' COM
    positions and angles are closed forms in theta: L = T - V, T = sum m |c'|^2 / 2 +
    I phi'^2 / 2 (times theta'^2), V = sum m g y_c; theta'' = -(V' + M' theta'^2 / 2) / M."""

    def __init__(self, links, coords):
        # links: (mass, I about the COM, COM (2-vector), angle); coords: the model's q(theta).
        mass = sum(m * (c.diff(TH).dot(c.diff(TH))) + i * phi.diff(TH) ** 2
                   for m, i, c, phi in links)
        pot = sum(m * G * c[1] for m, _, c, _ in links)
        self.mass = sp.lambdify(TH, mass, "numpy", cse=True)
        self.dmass = sp.lambdify(TH, mass.diff(TH), "numpy", cse=True)
        self.dpot = sp.lambdify(TH, pot.diff(TH), "numpy", cse=True)
        self.coords = sp.lambdify(TH, sp.Matrix(coords), "numpy", cse=True)
        self.rates = sp.lambdify(TH, sp.Matrix(coords).diff(TH), "numpy", cse=True)

    def state(self, theta, rate):
        return (np.ravel(self.coords(theta)).astype(float),
                rate * np.ravel(self.rates(theta)).astype(float))

    def crank(self, theta0, rate0, t):
        def rhs(_, y):
            th, w = y
            return [w, -(self.dpot(th) + 0.5 * self.dmass(th) * w * w) / self.mass(th)]

        sol = solve_ivp(rhs, (t[0], t[-1]), [theta0, rate0], t_eval=t, rtol=1e-13, atol=1e-14,
                        method="DOP853")
        assert sol.success
        return sol.y[0]


def rod_links(lengths, masses, pivots, angles):
    """Rods (COM at mid-length, I = m l^2 / 12) from their pivots at their angles."""
    return [(m, m * ln**2 / 12, p + ln / 2 * unit(a), a)
            for ln, m, p, a in zip(lengths, masses, pivots, angles)]


@functools.cache
def parallelogram():
    """Crank 0.3, coupler 0.8, rocker 0.3, ground 0.8: the coupler translates, the rocker
    turns with the crank; flat-folded change points at theta = 0 and pi."""
    lengths, masses = (0.3, 0.8, 0.3), (0.5, 1.5, 0.7)
    model = four_bar(*lengths, 0.8, masses)
    origin = sp.Matrix([0, 0])
    links = rod_links(lengths, masses, [origin, 0.3 * unit(TH), sp.Matrix([0.8, 0])],
                      [TH, sp.Integer(0), TH])
    return model, Reduction(links, [TH, -TH, TH])


@functools.cache
def kite():
    """Deltoid: crank = ground = 0.3, coupler = rocker = 0.8. The crank turns fully; at
    theta = 0 its end meets the rocker's pivot, coupler and rocker fold onto each other and
    may turn together about it (a change point). On the branch followed here the rocker's
    end is B = (A + D)/2 + h (cos theta/2, sin theta/2), h = sqrt(0.8^2 - 0.3^2 sin^2 theta/2)."""
    a, c = 0.3, 0.8
    lengths, masses = (a, c, c), (0.4, 1.2, 1.0)
    model = four_bar(a, c, c, a, masses)
    crank_end, pivot = a * unit(TH), sp.Matrix([a, 0])
    h = sp.sqrt(c**2 - a**2 * sp.sin(TH / 2) ** 2)
    tip = (crank_end + pivot) / 2 + h * unit(TH / 2)
    coupler = sp.atan2(tip[1] - crank_end[1], tip[0] - crank_end[0])
    rocker = sp.atan2(tip[1] - pivot[1], tip[0] - pivot[0])
    links = rod_links(lengths, masses, [sp.Matrix([0, 0]), crank_end, pivot],
                      [TH, coupler, rocker])
    return model, Reduction(links, [TH, coupler - TH, rocker])


@functools.cache
def slider_crank():
    """The bundled offset slider-crank (its crank turns through both dead centres, where
    crank and rod are collinear: singular for the slider as input, not a bifurcation)."""
    scene = pmd.load_scene("slider_crank")
    r, rl, e = 0.04, 0.12, 0.01
    masses, inertia = (0.022608, 0.067824, 0.0942), (3.285696e-06, 8.2202688e-05, 0.0)
    coms = (0.02, 0.06)
    crank_end = r * unit(TH)
    s = r * sp.cos(TH) + sp.sqrt(rl**2 - (r * sp.sin(TH) - e) ** 2)
    phi = sp.atan2(e - crank_end[1], s - crank_end[0])
    links = [(masses[0], inertia[0], coms[0] * unit(TH), TH),
             (masses[1], inertia[1], crank_end + coms[1] * unit(phi), phi),
             (masses[2], inertia[2], sp.Matrix([s, e]), sp.Integer(0))]
    return scene.model, Reduction(links, [TH, phi - TH, s])


def run(scene, t_end, method, rtol):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = pmd.simulate(scene, (0, t_end), method=method, rtol=rtol, atol=rtol * 1e-2,
                           max_steps=5000)
    said = [w for w in caught if issubclass(w.category, pmd.errors.SingularPassageWarning)]
    return res, said


def check(res, said, angle_error, rtol):
    if res.singular_passage is not None:
        assert len(said) == 1 and "singular position" in str(said[0].message)
        return
    # No warning: on its branch (a run that leaves it is off by ~1 rad), and within 100 rtol
    # unless the message says why not.
    assert not said
    assert res.success, res.message
    assert angle_error < 1e-3, (angle_error, res.singular_crossings)
    if angle_error > 100 * rtol:
        assert res.singular_crossings[0] > 0, (angle_error, res.message)
        assert "singular position" in res.message


RTOLS = [1e-6, 1e-9, 1e-12, 1e-13]
FOUR_BARS = {
    # (theta0, rate0, t_end): through the change point, driven by gravity and the rate
    "parallelogram": (0.5, 2.0, 4.0),
    "parallelogram-down": (0.5, -2.0, 2.0),
    "kite": (1.0, 6.0, 1.5),
}


@pytest.mark.parametrize("rtol", RTOLS)
@pytest.mark.parametrize("case", list(FOUR_BARS) + ["slider_crank"])
@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_planar_runs_are_accurate_or_say_why_not(case, method, rtol):
    if case == "slider_crank":
        (model, red), (th0, w0, t_end) = slider_crank(), (0.0, 30.0, 0.5)
    else:
        model, red = (kite if case == "kite" else parallelogram)()
        th0, w0, t_end = FOUR_BARS[case]
    q0, v0 = red.state(th0, w0)
    scene = pmd.Scene(model, q0, v0, effects=[pmd.Effect.gravity([0, -G, 0])])
    res, said = run(scene, t_end, method, rtol)
    t = np.asarray(res.t)
    err = np.abs(np.asarray(res.q)[:, 0] - red.crank(th0, w0, t)).max()
    print(case, method, rtol, res.success, f"{err:.1e}", res.singular_passage,
          res.singular_crossings, res.n_accepted)
    check(res, said, err, rtol)


@pytest.mark.parametrize("rtol", RTOLS)
def test_n_fourbar_a02_through_its_first_crossing_is_accurate_or_says_why_not(rtol):
    # The benchmark scene (N = 40) through its crossings (theta = 0, -pi at t = 0.72, 1.24,
    # 2.69, 3.21 s). A02's rows lose N = 40 dimensions there at once, an even number, so the
    # kernel's orientation does not reverse: the rows' volume dipping over a step reports
    # them (rust/simulate/dynamics.rs, Crossings). Measured: 1.4, 0.27, 3.1 and 50 x 100 rtol
    # at 1e-6, 1e-9, 1e-12, 1e-13 (the crossing's cost at tight rtol, a long step over the
    # top at 1e-6), every run reporting the 4 crossings.
    sc = pmd.load_scene("iftomm_a02_nfourbar")
    res, said = run(sc, 3.5, "DOP853", rtol)
    t = np.asarray(res.t)
    c = n_fourbar_rate(40)
    ref = solve_ivp(lambda _, y: [y[1], -c * np.cos(y[0])], (0, t[-1]), [np.pi / 2, -1.0],
                    t_eval=t, rtol=1e-13, atol=1e-14, method="DOP853")
    err = np.abs(np.asarray(res.q)[:, 0] - ref.y[0]).max()
    print("A02", rtol, res.success, f"{err:.1e}", res.singular_passage, res.singular_crossings,
          res.n_accepted)
    check(res, said, err, rtol)
    assert res.singular_crossings[0] == int(np.sum(np.diff(np.floor(ref.y[0] / np.pi)) != 0))


@pytest.mark.parametrize("rtol", [1e-6, 1e-9])
def test_bricard_a04_is_accurate_and_passes_no_singular_position(rtol):
    # A redundant row (rank 5 of 6): the kept rows may change between steps. The reduction
    # (tests/test_iftomm.py) is good to ~1e-10, hence no tighter rtol here.
    sc = pmd.load_scene("iftomm_a04_bricard")
    t = np.linspace(0, 2.0, 41)
    with warnings.catch_warnings():
        warnings.simplefilter("error", pmd.errors.SingularPassageWarning)
        res = pmd.simulate(sc, (0, 2.0), t_eval=t, method="DOP853", rtol=rtol,
                           atol=rtol * 1e-2)
    ref = bricard_reduction(sc.model, sc.q0, t)
    err = np.abs(np.asarray(res.q) - ref).max()
    print("A04", rtol, res.success, f"{err:.1e}", res.singular_passage, res.singular_crossings)
    assert res.singular_passage is None
    assert res.singular_crossings[0] == 0
    assert err <= 100 * rtol


def test_the_issue_parallelogram_leaving_its_branch_warns():
    # Issue 38: DOP853 at rtol = atol = 1e-12 through the flat-folded change points ended
    # 2.3 rad (here 16 rad) from the exact motion with success and no warning: its accepted
    # states crawled within a pivot ratio of 1.0e-7 of the run's best, just above the old
    # threshold (1e-7; now 1e-5). Whether a given run crawls off turns on rounding: at least
    # one of these does (all three did on the machine that wrote this), and each run either
    # warns or stays on its branch within 100 rtol or with its crossings noted.
    model, red = parallelogram()
    q0, v0 = red.state(0.5, 2.0)
    scene = pmd.Scene(model, q0, v0, effects=[pmd.Effect.gravity([0, -G, 0])])
    warned = 0
    for method, rtol, atol in [("DOP853", 1e-12, 1e-12), ("DOP853", 1e-13, 1e-15),
                               ("RK45", 1e-12, 1e-14)]:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = pmd.simulate(scene, (0, 5.0), method=method, rtol=rtol, atol=atol,
                               max_steps=5000)
        said = [w for w in caught if issubclass(w.category, pmd.errors.SingularPassageWarning)]
        t = np.asarray(res.t)
        err = np.abs(np.asarray(res.q)[:, 0] - red.crank(0.5, 2.0, t)).max()
        check(res, said, err, rtol)
        warned += res.singular_passage is not None
    assert warned >= 1
