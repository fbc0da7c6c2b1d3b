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
from pointmass_dyn.cli import main
from pointmass_dyn.work_precision import rk4_fixed, scene_rhs
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
