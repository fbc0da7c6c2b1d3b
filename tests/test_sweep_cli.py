"""``pointmass-dyn sweep`` (issue 16): a grid of parameters and perturbed initial states run
through ``simulate_batch``; the .npz it writes is the batch's result bit for bit, the plot is
written, failures are reported per run, bad arguments exit with 2 naming the option."""

from __future__ import annotations

import itertools

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn import cli

pytest.importorskip("matplotlib")

GRID = ["--param", "link0.mass=0.8:1.2:3", "--param", "gravity.z=-9.81,-5"]


def test_sweep_npz_is_simulate_batch_bit_for_bit(tmp_path, capsys):
    npz, png = tmp_path / "runs.npz", tmp_path / "runs.png"
    argv = ["sweep", "chain7", *GRID, "--runs", "2", "--q0-noise", "1e-3", "--v0-noise", "2e-3",
            "--seed", "7", "--t-end", "1", "--samples", "21", "--threads", "2",
            "--out", str(npz), "--plot", str(png), "--no-progress"]
    assert cli.main(argv) == 0
    cap = capsys.readouterr()
    assert cap.err == ""  # --no-progress: no bar
    out = cap.out
    assert "chain7: 12 runs (grid 3 × 2 of link0.mass, gravity.z" in out
    assert "12 succeeded, 0 failed" in out and "runs/s" in out
    assert "final state at t = 1 s" in out and "link6 dq/dt" in out

    # The same runs built by hand: the grid with the first --param slowest, each point twice,
    # q0 then v0 perturbed from default_rng(seed); run on one thread.
    scene = pmd.load_scene("chain7")
    points = list(itertools.product(np.linspace(0.8, 1.2, 3), [-9.81, -5.0]))
    values = np.repeat(np.array(points), 2, axis=0)
    count = len(values)
    gravity = np.zeros((count, 3))
    gravity[:, 2] = values[:, 1]
    rng = np.random.default_rng(7)
    q0 = scene.q0 + 1e-3 * rng.standard_normal((count, 7))
    v0 = scene.v0 + 2e-3 * rng.standard_normal((count, 7))
    ref = pmd.simulate_batch(
        scene, (0.0, 1.0), q0=q0, v0=v0, params={"link0.mass": values[:, 0], "gravity": gravity},
        t_eval=np.linspace(0.0, 1.0, 21), threads=1,
    )
    got = np.load(npz)
    assert ref.success.all()
    for key in ("t", "q", "v", "success", "status", "t_reached", "nfev"):
        assert np.array_equal(got[key], getattr(ref, key)), key
    assert got["q"].shape == (12, 21, 7)
    assert list(got["message"]) == ref.message
    assert np.array_equal(got["q0"], q0) and np.array_equal(got["v0"], v0)
    assert list(got["param_names"]) == ["link0.mass", "gravity.z"]
    assert np.array_equal(got["param_values"], values)
    assert list(got["q_names"])[0] == "link0 q"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000
    assert "plot written to" in out


def test_sweep_noise_only_progress_bar_and_coord(tmp_path, capsys):
    png = tmp_path / "fan.png"
    argv = ["sweep", "pendulum_planar", "--runs", "6", "--q0-noise", "0.05", "--t-end", "0.5",
            "--samples", "11", "--progress", "--plot", str(png), "--coord", "rod"]
    assert cli.main(argv) == 0
    cap = capsys.readouterr()
    assert "6 runs (q0 σ = 0.05, seed 0)" in cap.out
    assert "coordinate 0: rod φ" in cap.out and png.is_file()
    assert "] 6/6 runs" in cap.err and cap.err.endswith("\n")  # the bar, ended


def test_sweep_reports_failed_runs(tmp_path, capsys):
    # A ZYZ rod thrown through its Euler singularity: every run stops there.
    scene = tmp_path / "singular.toml"
    scene.write_text(
        'name = "rod_singular"\nangles = "degrees"\n[[body]]\nname = "rod"\n'
        'joint = { type = "SphericalZYZ" }\nmass = 1.0\ncom = [0.5, 0, 0]\n'
        "inertia_diag = [1e-4, 0.08, 0.08]\nq0 = [0, 1, 0]\nv0 = [0, -90, 0]\n",
        encoding="utf-8",
    )
    npz = tmp_path / "f.npz"
    assert cli.main(["sweep", str(scene), "--param", "rod.mass=1,2", "--t-end", "0.5",
                     "--out", str(npz)]) == 1
    out = capsys.readouterr().out
    assert "0 succeeded, 2 failed" in out and "2 runs (0, 1): " in out
    assert "Euler singularity" in out
    got = np.load(npz)
    assert not got["success"].any() and np.isnan(got["q"][:, -1]).all()


@pytest.mark.parametrize(
    "args, option, words",
    [
        (["--param", "link9.mass=1,2"], "--param", "unknown key 'link9.mass'"),
        (["--param", "springs.stiffness=1,2"], "--param", "unknown key"),
        (["--param", "link0.mass=1:2"], "--param", "START:STOP:COUNT"),
        (["--param", "link0.mass=1:2:x"], "--param", "whole COUNT"),
        (["--param", "link0.mass=1:2:0"], "--param", "COUNT >= 1"),
        (["--param", "link0.mass=1,two"], "--param", "numbers separated by commas"),
        (["--param", "link0.mass=-1,1"], "--param", "mass"),
        (["--param", "link0.mass=1,2", "--param", "link0.mass=3"], "--param", "twice"),
        (["--q0-noise", "-0.1"], "--q0-noise", ">= 0"),
        (["--v0-noise", "-1"], "--v0-noise", ">= 0"),
        (["--runs", "3"], "--runs", "identical"),
        (["--runs", "0"], "--runs", ">= 1"),
        (["--samples", "1"], "--samples", "at least 2"),
        (["--threads", "0"], "--threads", "at least 1"),
        (["--coord", "99"], "--coord", "0..6"),
        (["--out", "runs.csv"], "--out", ".npz"),
    ],
)
def test_sweep_bad_arguments_exit_2_naming_the_option(args, option, words, capsys):
    assert cli.main(["sweep", "chain7", "--t-end", "0.1", *args]) == 2
    cap = capsys.readouterr()
    assert cap.err.startswith(f"pointmass-dyn: error: {option}: "), cap.err
    assert words in cap.err, cap.err
    assert cap.out == ""  # refused before anything ran


def test_sweep_noise_refused_on_closed_loops(capsys):
    assert cli.main(["sweep", "fourbar", "--runs", "2", "--v0-noise", "0.1"]) == 2
    assert "--v0-noise: fourbar has closed loops" in capsys.readouterr().err


def test_sweep_help_documents_the_syntax(capsys):
    with pytest.raises(SystemExit) as info:
        cli.main(["sweep", "--help"])
    assert info.value.code == 0
    out = capsys.readouterr().out
    for text in ("KEY=START:STOP:COUNT", "V1,V2", "gravity.x|y|z", "<body>.mass", "--q0-noise",
                 "--progress", "param_values", "examples:"):
        assert text in out, text
    with pytest.raises(SystemExit) as info:  # argparse's own: not a number
        cli.main(["sweep", "chain7", "--runs", "many"])
    assert info.value.code == 2 and "--runs" in capsys.readouterr().err


def test_scene_gravity_is_what_the_simulation_applies():
    """One scene gravity for sweep and balance: the sum of the enabled gravity effects (None
    when the family is disabled); `gravity.x|y|z` sweeps keep the rest of that sum. Checked
    against the generalized forces the scene's effects apply."""
    from pointmass_dyn._helpers import scene_gravity
    from pointmass_dyn.cli._sweep import sweep_runs

    base = pmd.load_scene("pendulum_spatial")
    model = base.model
    rng = np.random.default_rng(3)
    q, v = rng.uniform(-1, 1, model.nq), np.zeros(model.nv)
    two = base.replace(effects=[pmd.Gravity((0.0, 0.0, -9.81)), pmd.Gravity((1.5, 0.0, 0.0))])
    g = scene_gravity(two)
    one = base.replace(effects=[pmd.Gravity(g)])
    np.testing.assert_allclose(sum(pmd.effect_forces(two, 0.0, q, v).values()),
                               sum(pmd.effect_forces(one, 0.0, q, v).values()), atol=1e-12)
    np.testing.assert_array_equal(g, [1.5, 0.0, -9.81])
    runs = sweep_runs(two, ["gravity.z=-5,-1"])
    np.testing.assert_array_equal(runs.params["gravity"], [[1.5, 0.0, -5.0], [1.5, 0.0, -1.0]])

    off = pmd.Scene(model, q0=base.q0, effects=list(two.effects), disable="gravity")
    assert scene_gravity(off) is None
    assert not np.any(sum(pmd.effect_forces(off, 0.0, q, v).values(), np.zeros(model.nv)))
    runs = sweep_runs(off, ["gravity.x=2"])
    np.testing.assert_array_equal(runs.params["gravity"], [[2.0, 0.0, 0.0]])
