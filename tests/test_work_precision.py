"""`pmd.work_precision` and `pointmass-dyn work-precision`: the numbers it reports are checked
against quantities computed here independently — the exact compound-pendulum solution
(elliptic functions), SciPy's own RK45 run, a hand-written right-hand side with the spring
and damper laws, and the order of the classical RK4. Short spans keep this fast; timings are
never asserted."""

from __future__ import annotations

import csv
import math

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import PAPER_A, PAPER_D, PAPER_M, record
from pointmass_dyn.benchmarking import rk4_fixed, scene_rhs
from pointmass_dyn.cli import main
from scipy.integrate import solve_ivp
from scipy.special import ellipj, ellipk

G = np.array([0.0, 0.0, -9.81])
T_END = 2.0
TOLS = (1e-4, 1e-6, 1e-8)


def planar_exact(t):
    """ψ and ψ̇ of the paper's planar pendulum (released horizontal, ψ0 = 90°)."""
    i_o = PAPER_M * PAPER_A**2 / 3 + PAPER_M * PAPER_D**2 / 16
    w0 = math.sqrt(PAPER_M * 9.81 * PAPER_A / 2 / i_o)
    k = math.sin(math.pi / 4)
    sn, cn, _, _ = ellipj(ellipk(k * k) - w0 * t, k * k)
    return 2 * np.arcsin(k * sn), -2 * k * w0 * cn


@pytest.fixture(scope="module")
def planar_wp():
    return pmd.work_precision("pendulum_planar", TOLS, t_end=T_END, repeats=1, scipy_repeats=1,
                              n_dense=201)


def test_rows_and_reference(planar_wp):
    wp = planar_wp
    assert isinstance(wp, pmd.WorkPrecision)
    assert wp.scene == "pendulum_planar" and wp.t_span == (0.0, T_END)
    assert [r["tol"] for r in wp.rows] == list(TOLS)
    # The reference agrees with simulate at 1e-13 (the cross-check it reports).
    assert wp.reference_check["err_final"] < 1e-11
    scene = pmd.load_scene("pendulum_planar")
    psi, psid = planar_exact(T_END)
    for row in wp.rows:
        # Our own measurement of the same run against the exact solution.
        r = pmd.simulate(scene, (0.0, T_END), rtol=row["tol"], atol=row["tol"])
        assert r.nfev == row["nfev"] and r.n_accepted == row["steps"]
        y = np.concatenate([r.q[-1], r.v[-1]])
        y_exact = np.array([*scene.q0[:2], psi, 0.0, 0.0, psid])
        err = np.max(np.abs(y - y_exact)) / np.max(np.abs(y_exact))
        record(f"work-precision: |reported - exact-based error| at {row['tol']:g}",
               abs(row["err_final"] - err) / err)
        assert row["err_final"] == pytest.approx(err, rel=1e-3)
        # The dense error, measured here on the same grid against the exact solution.
        grid = np.linspace(0.0, T_END, 201)
        rd = pmd.simulate(scene, (0.0, T_END), rtol=row["tol"], atol=row["tol"], t_eval=grid)
        psi_g, psid_g = planar_exact(grid)
        ex = np.zeros((grid.size, 6))
        ex[:, :2] = scene.q0[:2]
        ex[:, 2], ex[:, 5] = psi_g, psid_g
        err_d = np.max(np.abs(np.hstack([rd.q, rd.v]) - ex)) / np.max(np.abs(ex))
        assert row["err_dense"] == pytest.approx(err_d, rel=1e-3)
        assert 0 <= row["err_energy"] < 10 * row["err_dense"]
        assert row["time"] > 0


def test_error_falls_monotonically(planar_wp):
    errs = planar_wp.column("err_final")
    assert np.all(np.diff(errs) < 0), errs
    assert np.all(errs < 1000 * np.array(TOLS))
    assert np.all(np.diff(planar_wp.column("nfev")) > 0)


def test_scipy_line_takes_the_same_steps(planar_wp):
    rhs = scene_rhs(pmd.load_scene("pendulum_planar"))
    y0 = np.concatenate([pmd.load_scene("pendulum_planar").q0, np.zeros(3)])
    for row in planar_wp.rows:
        ref = solve_ivp(rhs, (0.0, T_END), y0, method="RK45", rtol=row["tol"], atol=row["tol"])
        assert row["scipy_nfev"] == ref.nfev == row["nfev"]
        # Equal steps, so equal error: the time ratio is at equal error.
        assert row["scipy_err_final"] == pytest.approx(row["err_final"], rel=1e-4)
        assert row["speedup"] == pytest.approx(row["scipy_time"] / row["time"])


def test_rk4_line_is_at_equal_cost_and_fourth_order(planar_wp):
    rows = planar_wp.rows
    for row in rows:
        assert row["rk4_steps"] == max(1, round(row["nfev"] / 4))
    # Fourth order: error ∝ N^-4 between the two tightest tolerances.
    n = np.array([r["rk4_steps"] for r in rows[1:]], dtype=float)
    e = np.array([r["rk4_err_final"] for r in rows[1:]])
    order = -math.log(e[1] / e[0]) / math.log(n[1] / n[0])
    record("work-precision: observed RK4 order", order)
    assert 3.3 < order < 4.7


def test_rk4_fixed_is_classical_rk4():
    ts, ys = rk4_fixed(lambda t, y: np.array([y[1], -y[0]]), (0.0, 1.0), [0.0, 1.0], 10)
    assert ts.shape == (11,) and ys.shape == (11, 2) and ts[-1] == 1.0
    # One step of RK4 on y' = λ y multiplies by 1 + z + z²/2 + z³/6 + z⁴/24.
    lam, h = -0.7, 0.3
    _, y = rk4_fixed(lambda t, y: lam * y, (0.0, h), [1.0], 1)
    z = lam * h
    assert y[-1, 0] == pytest.approx(1 + z + z * z / 2 + z**3 / 6 + z**4 / 24, rel=1e-15)


def test_scene_rhs_with_springs_and_dampers_matches_the_laws():
    model = pmd.Model()
    p = model.add_body(pmd.RigidBody(1.0, [0.15, 0, 0], np.diag([1e-3, 7.5e-3, 7.5e-3])),
                       pmd.Revolute([0, 1, 0]), name="a")
    model.add_body(pmd.RigidBody(0.5, [0.1, 0, 0], np.diag([1e-3, 4e-3, 4e-3])),
                   pmd.Revolute([0, 0, 1]), parent=p, translation=(0.3, 0, 0), name="b")
    scene = pmd.Scene(model, [0.2, -0.4], [0.5, 1.0], effects=[
        pmd.Gravity(G), pmd.Spring("a", 7.0, rest=0.1), pmd.Damper(["a", "b"], 0.3)])
    rhs = scene_rhs(scene)
    rng = np.random.default_rng(5)
    for _ in range(5):
        q, v = rng.normal(size=2), rng.normal(size=2)
        tau = np.array([-7.0 * (q[0] - 0.1), 0.0]) - 0.3 * v
        acc = model.forward_dynamics(q, v, tau, gravity=G)
        got = rhs(0.0, np.concatenate([q, v]))
        np.testing.assert_allclose(got, np.concatenate([v, acc]), rtol=1e-12, atol=1e-12)
    # Gravity alone: the cheap path, exactly forward_dynamics.
    plain = scene_rhs(pmd.load_scene("chain7"))
    c7 = pmd.load_scene("chain7")
    y = np.concatenate([c7.q0, c7.v0])
    np.testing.assert_array_equal(
        plain(0.0, y)[7:], c7.model.forward_dynamics(c7.q0, c7.v0, np.zeros(7), gravity=G))


def test_table_csv_and_plot(planar_wp, tmp_path):
    text = planar_wp.table()
    assert "pendulum_planar" in text and "speedup" in text
    assert len(text.splitlines()) == 2 + len(TOLS)
    path = tmp_path / "wp.csv"
    planar_wp.to_csv(path)
    rows = list(csv.DictReader(open(path)))
    assert len(rows) == len(TOLS)
    assert float(rows[1]["tol"]) == TOLS[1] and int(rows[1]["nfev"]) == planar_wp.rows[1]["nfev"]
    pytest.importorskip("matplotlib")
    png = tmp_path / "wp.png"
    planar_wp.plot(png)
    assert png.stat().st_size > 10_000


def test_cli_subcommand(tmp_path, capsys):
    out, png = tmp_path / "t.csv", tmp_path / "p.png"
    code = main(["work-precision", "pendulum_spatial", "chain7", "--tolerances", "1e-4", "1e-7",
                 "--t-end", "0.5", "--repeats", "1", "--scipy-repeats", "1", "--no-rk4",
                 "--out", str(out), "--plot", str(png)])
    assert code == 0
    text = capsys.readouterr().out
    assert "pendulum_spatial" in text and "chain7" in text
    rows = list(csv.DictReader(open(out)))
    assert [r["scene"] for r in rows] == ["pendulum_spatial"] * 2 + ["chain7"] * 2
    assert all(r["rk4_err_final"] == "" for r in rows)
    assert png.exists()


def test_cli_unknown_scene_is_a_clean_error(capsys):
    assert main(["work-precision", "no_such_scene", "--repeats", "1"]) == 2
    assert "no such scene" in capsys.readouterr().err


# --------------------------------------------------------------------------------------------
# Across methods (issue 15): ours, SciPy's and MuJoCo's on one scene, one reference
# --------------------------------------------------------------------------------------------
from pointmass_dyn import benchmarking as wpm  # noqa: E402

PLANAR_METHODS = ["RK45", "DOP853", "Radau", "RK4", "scipy:RK45", "scipy:DOP853",
                  "scipy:Radau", "mujoco:RK4", "mujoco:implicitfast", "numpy:RK4"]
M_T_END = 1.0
M_DTS = (0.01, 0.0025)


@pytest.fixture(scope="module")
def planar_methods():
    return pmd.work_precision("pendulum_planar", (1e-4, 1e-7), t_end=M_T_END, repeats=1,
                              scipy_repeats=1, methods=PLANAR_METHODS, dts=M_DTS)


def test_methods_rows_and_errors_against_the_exact_pendulum(planar_methods):
    """Every method has its rows, and each reported error is the error against the exact
    (elliptic-function) solution at the 21 check times, measured here independently from a
    rerun of the same method."""
    pytest.importorskip("mujoco")
    wp = planar_methods
    by = {}
    for r in wp.method_rows:
        by.setdefault(r["method"], []).append(r)
    assert set(by) == set(PLANAR_METHODS)
    grid = np.linspace(0.0, M_T_END, wpm.N_CHECK + 1)
    psi, psid = planar_exact(grid)
    scene = pmd.load_scene("pendulum_planar")
    exact = np.zeros((grid.size, 6))
    exact[:, :2] = scene.q0[:2]
    exact[:, 2], exact[:, 5] = psi, psid
    scale = np.max(np.abs(exact))
    for m, rows in by.items():
        # One build has every method: a row "not available" is a broken method, not skipped.
        assert not rows[0]["note"].startswith("not available"), (m, rows[0]["note"])
        fixed = m in ("RK4", "mujoco:RK4", "mujoco:implicitfast", "numpy:RK4")
        assert [r["dt" if fixed else "tol"] for r in rows] == list(M_DTS if fixed else
                                                                     (1e-4, 1e-7))
        for r in rows:
            assert r["time"] > 0 and r["nfev"] > 0
            if m == "RK45" or m == "scipy:RK45":
                y = pmd.simulate(scene, (0, M_T_END), rtol=r["tol"], atol=r["tol"], t_eval=grid)
                y = np.hstack([y.q, y.v])
            elif m == "numpy:RK4" or m == "mujoco:RK4":
                n = int(round(M_T_END / r["dt"]))
                _, ys = rk4_fixed(scene_rhs(scene), (0, M_T_END), np.r_[scene.q0, scene.v0], n)
                y = ys[:: n // wpm.N_CHECK]
            else:
                continue   # checked through the reference below
            err = np.max(np.abs(y - exact)) / scale
            assert r["err"] == pytest.approx(err, rel=1e-3, abs=1e-12), (m, r)
        for r in rows:   # every method: the error is what the reference says, > its floor
            assert 1e-13 < r["err"] < 1e-1, (m, r)


def test_mujoco_rk4_is_classical_rk4_on_our_dynamics(planar_methods):
    """MuJoCo's RK4 on the converted model and NumPy's RK4 on our right-hand side take the
    same steps of the same ODE: their errors agree to round-off."""
    pytest.importorskip("mujoco")
    rows = planar_methods.method_rows
    mj = [r for r in rows if r["method"] == "mujoco:RK4"]
    npy = [r for r in rows if r["method"] == "numpy:RK4"]
    assert [r["dt"] for r in mj] == [r["dt"] for r in npy] and mj
    for a, b in zip(mj, npy):
        assert a["nfev"] == b["nfev"]
        record("work-precision: |err MuJoCo RK4 - err NumPy RK4| / err",
               abs(a["err"] - b["err"]) / b["err"])
        assert a["err"] == pytest.approx(b["err"], rel=1e-6)
        assert a["err_final"] == pytest.approx(b["err_final"], rel=1e-6)


def test_our_rk45_and_scipys_take_the_same_steps(planar_methods):
    rows = planar_methods.method_rows
    ours = [r for r in rows if r["method"] == "RK45"]
    sp = [r for r in rows if r["method"] == "scipy:RK45"]
    for a, b in zip(ours, sp):
        assert a["nfev"] == b["nfev"]
        assert a["err"] == pytest.approx(b["err"], rel=1e-6)


def test_time_to_reach_interpolates_in_log_log():
    rows = [dict(method="A", time=1e-3, err=1e-2), dict(method="A", time=1e-2, err=1e-6),
            dict(method="A", time=1e-1, err=1e-8)]
    # 1e-4 is halfway between 1e-2 and 1e-6 in log error: halfway in log time.
    assert wpm.time_to_reach(rows, 1e-4) == pytest.approx(math.sqrt(1e-3 * 1e-2))
    assert wpm.time_to_reach(rows, 1e-2) == pytest.approx(1e-3)
    assert wpm.time_to_reach(rows, 1.0) == pytest.approx(1e-3)     # already below
    assert math.isnan(wpm.time_to_reach(rows, 1e-9))               # never reached
    # A slower setting that is less accurate does not hide a cheaper one below e.
    noisy = rows + [dict(method="A", time=1.0, err=1e-3)]
    assert wpm.time_to_reach(noisy, 1e-4) == pytest.approx(math.sqrt(1e-3 * 1e-2))
    # Diverged or failed settings (inf error) are ignored.
    assert wpm.time_to_reach(rows + [dict(method="A", time=1e-4, err=math.inf)], 1e-2) == \
        pytest.approx(1e-3)


def test_cheapest_and_ratio_tables():
    rows = [dict(method="RK45", time=1e-4, err=1e-3), dict(method="RK45", time=1e-3, err=1e-9),
            dict(method="mujoco:RK4", time=1e-3, err=1e-3),
            dict(method="mujoco:RK4", time=1e-2, err=1e-10),
            dict(method="scipy:DOP853", time=1e-2, err=1e-4),
            dict(method="scipy:DOP853", time=2e-2, err=1e-11)]
    c = wpm.cheapest(rows, (1e-3, 1e-6, 1e-10))
    assert [x["method"] for x in c] == ["RK45", "RK45", "mujoco:RK4"]
    assert c[0]["time"] == pytest.approx(1e-4)
    assert c[1]["time"] == pytest.approx(math.sqrt(1e-4 * 1e-3))
    r = wpm.ratio_table(rows, (1e-3, 1e-10))
    assert r[0]["ours"] == "RK45" and r[0]["vs_mujoco_rk4"] == pytest.approx(10.0)
    assert r[0]["scipy"] == "scipy:DOP853" and r[0]["vs_scipy"] == pytest.approx(100.0)
    assert r[1]["ours"] is None and math.isnan(r[1]["vs_mujoco_rk4"])
    text = wpm.cheapest_text("x", rows, (1e-3,))
    assert "RK45" in text and "10.0" in text and "100.0" in text


def test_methods_argument_errors():
    assert wpm.parse_methods("all") == list(wpm.DEFAULT_METHODS)
    assert wpm.parse_methods(["RK45", "all"])[0] == "RK45"
    assert wpm.parse_methods("RK45,scipy:Radau") == ["RK45", "scipy:Radau"]
    for bad, words in [(["RK46"], "RK46"), ([], "at least one"), (3, "sequence")]:
        with pytest.raises(pmd.InvalidInputError, match=words):
            pmd.work_precision("pendulum_planar", (1e-4,), t_end=0.1, methods=bad)
    with pytest.raises(pmd.InvalidInputError, match="dt"):
        pmd.work_precision("pendulum_planar", (1e-4,), t_end=0.1, methods=["mujoco:RK4"],
                           dts=[0.03])


def test_default_dts_divide_the_check_grid():
    dts = wpm.default_dts((0.0, 2.0), "mujoco:RK4")
    assert dts[0] == pytest.approx(2.0 / 100) and len(dts) > 8
    for dt in dts:
        n = 2.0 / dt
        assert abs(n - round(n)) < 1e-6 and round(n) % wpm.N_CHECK == 0
    assert max(2.0 / d for d in wpm.default_dts((0.0, 2.0), "Euler")) <= 200_000


def central_jacobian(f, y, h=1e-6):
    """∂f/∂y of ``f(y)`` by central differences."""
    n = y.size
    jac = np.empty((n, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = h
        jac[:, i] = (f(y + e) - f(y - e)) / (2 * h)
    return jac


def chain_stiff_in_pinocchio():
    """chain_stiff.toml rebuilt in Pinocchio from its numbers, with its springs and dampers
    written out: ``f(y)`` of an implementation that shares no code with ours."""
    pin = pytest.importorskip("pinocchio")
    pm = pin.Model()
    pm.gravity.linear = np.array([0.0, 0.0, -9.81])
    parent = 0
    inertia = pin.Inertia(1.0, np.array([0.15, 0.0, 0.0]), np.diag([1e-3, 7.5e-3, 7.5e-3]))
    for k, axis in enumerate("YZYZY"):
        placement = pin.SE3(np.eye(3), np.array([0.3 if k else 0.0, 0.0, 0.0]))
        joint = pin.JointModelRY() if axis == "Y" else pin.JointModelRZ()
        parent = pm.addJoint(parent, joint, placement, f"j{k}")
        pm.appendBodyToJoint(parent, inertia, pin.SE3.Identity())
    pd = pm.createData()

    def f(y):
        q, v = y[:5], y[5:]
        tau = np.zeros(5)
        tau[1:] = -600.0 * q[1:] - 300.0 * v[1:]      # stiffness 600, rest 0; damping 300
        return np.concatenate([v, pin.aba(pm, pd, q, v, tau)])

    return f


def test_chain_stiff_is_stiff():
    """The bundled stiff scene: the linearised dynamics of an independent implementation
    (Pinocchio's ABA with the scene's springs and dampers written out, central differences)
    have eigenvalues from ~1e2 to ~3e4 /s beside slow ones of ~2 /s (its TOML comments), and
    ours linearise to the same Jacobian; RK45's stiffness test fires, and an implicit method
    (SciPy's Radau) needs over 10x fewer evaluations for a smaller error."""
    scene = pmd.load_scene("chain_stiff")
    rhs = scene_rhs(scene)
    y0 = np.concatenate([scene.q0, scene.v0])
    n = y0.size
    theirs = central_jacobian(chain_stiff_in_pinocchio(), y0)
    lam = np.linalg.eigvals(theirs)
    fast = np.sort(np.abs(lam.real))[::-1]
    assert 1e4 < fast[0] < 1e5 and fast[3] > 50               # four stiff modes, c / I_eff
    assert np.all(lam.real < 1e-9)
    slow = lam[np.abs(lam) < 10]
    assert len(slow) == 6 and np.max(np.abs(slow)) < 3      # the swing and the creep
    assert fast[0] / np.max(np.abs(slow)) > 1e3               # the stiffness ratio
    ours = central_jacobian(lambda y: rhs(0.0, y), y0)
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-7 * np.max(np.abs(theirs)))
    ours = pmd.simulate(scene, rtol=1e-6, atol=1e-6)
    assert ours.success and "stiff" in ours.message
    radau = solve_ivp(rhs, scene.t_span, y0, method="Radau", rtol=1e-6, atol=1e-6)
    ref = solve_ivp(rhs, scene.t_span, y0, method="Radau", rtol=1e-11, atol=1e-11)
    y_ours = np.concatenate([ours.q[-1], ours.v[-1]])
    err_ours = np.max(np.abs(y_ours - ref.y[:, -1]))
    err_radau = np.max(np.abs(radau.y[:, -1] - ref.y[:, -1]))
    assert err_radau <= err_ours
    assert 10 * (radau.nfev + n * radau.njev) < ours.nfev
    # The slow motion is visible: the chain swings through more than 1.5 rad, the bends relax.
    full = pmd.simulate(scene, rtol=1e-6, atol=1e-6, t_eval=np.linspace(0, 3, 61))
    assert np.ptp(full.q[:, 0]) > 1.5 and np.all(np.abs(full.q[-1, 1:]) < 0.01)


def test_cli_methods(tmp_path, capsys):
    pytest.importorskip("mujoco")
    out = tmp_path / "m.csv"
    code = main(["work-precision", "pendulum_planar", "--t-end", "1", "--tolerances", "1e-4",
                 "1e-6", "--methods", "RK45", "mujoco:RK4", "--dt", "0.01", "0.005",
                 "--repeats", "1", "--out", str(out)])
    assert code == 0
    text = capsys.readouterr().out
    assert "cheapest method per accuracy" in text and "mujoco:RK4" in text
    with open(out) as fh:
        rows = list(csv.DictReader(fh))
    assert [r["method"] for r in rows] == ["RK45", "RK45", "mujoco:RK4", "mujoco:RK4"]
    assert all(float(r["err"]) < 1e-2 and r["scene"] == "pendulum_planar" for r in rows)


def test_analytic_jacobian_with_springs_and_dampers():
    """SciPy Radau's Jacobian: the model's forward-dynamics derivatives plus the springs' and
    dampers' −M⁻¹K, −M⁻¹C, against central differences of scene_rhs on chain_stiff."""
    scene = pmd.load_scene("chain_stiff")
    jac = wpm.analytic_jacobian(scene)
    assert jac is not None  # one build: the derivatives are always there
    rhs = scene_rhs(scene)
    rng = np.random.default_rng(3)
    y = np.concatenate([scene.q0, scene.v0]) + rng.uniform(-0.3, 0.3, 10)
    n = y.size
    fd = np.empty((n, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = 1e-6
        fd[:, i] = (rhs(0.0, y + e) - rhs(0.0, y - e)) / 2e-6
    assert np.max(np.abs(jac(0.0, y) - fd)) <= 1e-7 * np.max(np.abs(fd))
    # Models whose q is not v (quaternions) fall back to finite differences.
    assert wpm.analytic_jacobian(pmd.load_scene("satellite")) is None


def test_our_fixed_step_methods_are_mujocos():
    """On chain7 (hinges: MuJoCo's coordinates are ours), our RK4 and semi-implicit Euler and
    MuJoCo's take the same steps of the same ODE: equal errors at every dt."""
    pytest.importorskip("mujoco")
    wp = pmd.work_precision("chain7", (1e-6,), t_end=0.4, repeats=1,
                            methods=["RK4", "Euler", "mujoco:RK4", "mujoco:Euler"],
                            dts=(0.02, 0.002))
    by = {}
    for r in wp.method_rows:
        by.setdefault(r["method"], []).append(r)
    for ours, theirs in (("RK4", "mujoco:RK4"), ("Euler", "mujoco:Euler")):
        assert len(by[ours]) == len(by[theirs]) == 2
        for a, b in zip(by[ours], by[theirs]):
            assert a["dt"] == pytest.approx(b["dt"]) and a["steps"] == b["steps"]
            record(f"work-precision: |err ours {ours} - err MuJoCo| / err",
                   abs(a["err"] - b["err"]) / b["err"])
            assert a["err"] == pytest.approx(b["err"], rel=1e-6)
