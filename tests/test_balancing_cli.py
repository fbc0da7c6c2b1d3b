"""``pointmass-dyn balance`` in process (analysis, complete force balance checked against
Berkof–Lowen, the Pareto front, argument errors) and the balancing plots."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn import cli

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

from pointmass_dyn.plotting import plot_balance, plot_motion, plot_pareto  # noqa: E402

RINGS = ["--counterweight", "crank:0.02", "--counterweight", "rocker:0.02"]


def read_rows(path: Path) -> tuple[list[str], list[list[str]]]:
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def is_png(path: Path) -> bool:
    blob = path.read_bytes()
    return blob[:8] == b"\x89PNG\r\n\x1a\n" and len(blob) > 20_000


def fourbar_motion(samples: int = 72):
    sc = pmd.load_scene("fourbar")
    return sc, pmd.prescribed_motion(sc.model, "crank", speed=30.0, samples=samples,
                                     q_guess=sc.q0, gravity=[0.0, -9.81, 0.0])


# --------------------------------------------------------------------------------------------
# The command
# --------------------------------------------------------------------------------------------
def test_analysis_only_uses_the_scenes_driver_speed_and_gravity(tmp_path, capsys):
    out = tmp_path / "a.csv"
    assert cli.main(["balance", "fourbar", "--samples", "72", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    # The driver is the scene's [initial] fixed body, the speed its v0 (30 rad/s).
    assert "'crank' driven at 30 rad/s" in text and "gravity (0, -9.81, 0)" in text
    assert "RMS before" not in text and "counterweight" not in text
    header, rows = read_rows(out)
    assert header == ["quantity", "rms", "peak"]
    _, ref = fourbar_motion(72)
    summary = ref.summary()
    assert [r[0] for r in rows] == list(summary)
    for name, rms, peak in rows:
        assert float(rms) == pytest.approx(summary[name]["rms"], rel=1e-14)
        assert float(peak) == pytest.approx(summary[name]["peak"], rel=1e-14)


def test_complete_force_balance_of_the_fourbar(tmp_path, capsys):
    png, out = tmp_path / "b.png", tmp_path / "b.csv"
    args = ["balance", "fourbar", "--samples", "72", *RINGS, "--zero", "force",
            "--plot", str(png), "--out", str(out)]
    assert cli.main(args) == 0
    text = capsys.readouterr().out
    header, rows = read_rows(out)
    assert header == ["quantity", "rms_before", "rms_after", "peak_before", "peak_after"]
    table = {r[0]: [float(x) for x in r[1:]] for r in rows}
    before, after = table["shaking force"][0], table["shaking force"][1]
    # The conic solver stops at its 1e-8 tolerance (the residual left is rounding-dependent).
    assert before > 1.0 and after <= 1e-8 * before
    assert table["shaking force"][3] <= 1e-8 * table["shaking force"][2]
    assert is_png(png)
    # The counterweights printed are Berkof–Lowen's: with the coupler's COM on its line,
    # m_crank r_crank = m_c L_crank (r_c / L_c − 1), m_rocker r_rocker = −m_c r_c L_rocker / L_c,
    # the counterweight at radius 0.02 m opposite each link.
    model = pmd.load_scene("fourbar").model
    coupler = model.body("coupler")
    need = {
        "crank": coupler.mass * 0.035 * (coupler.com[0] / 0.09 - 1.0),
        "rocker": -coupler.mass * coupler.com[0] * 0.07 / 0.09,
    }
    placed = re.findall(r"^\s+(crank|rocker)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)$",
                        text.split("counterweights placed")[1].split("new bodies")[0], re.M)
    assert sorted(p[0] for p in placed) == ["crank", "rocker"]
    for body, mass, x, y, z in placed:
        own = model.body(body)
        expected = (need[body] - own.mass * own.com[0]) / -0.02
        assert float(mass) == pytest.approx(expected, rel=1e-5)
        assert (float(x), float(y), float(z)) == (-0.02, 0.0, 0.0)
    assert "new bodies" in text and "mass added" in text


def test_weights_center_and_axis_of_a_ring(tmp_path, capsys):
    # A pendulum on a revolute joint about y (no loops, one dof): the driver is its only
    # joint, the ring lies in the x–z plane about the given centre, and a counterweight on it
    # balances the shaking force exactly.
    scene = tmp_path / "arm.toml"
    scene.write_text("""
name = "arm"
[[body]]
name = "arm"
joint = { type = "Revolute", axis = [0.0, 1.0, 0.0] }
mass = 0.5
com = [0.1, 0.0, 0.0]
inertia_diag = [1e-4, 2e-3, 2e-3]
[[effect]]
type = "gravity"
g = [0.0, 0.0, -9.81]
""", encoding="utf-8")
    out = tmp_path / "w.csv"
    args = ["balance", str(scene), "--samples", "36", "--counterweight", "arm:0.05:12@0.01,0,0",
            "--weight", "force=1", "--weight", "moment=0", "--out", str(out)]
    assert cli.main(args) == 0
    text = capsys.readouterr().out
    assert "'arm' driven at 6.28319 rad/s" in text  # 2π: the scene has no initial speed
    _, rows = read_rows(out)
    force = next(r for r in rows if r[0] == "shaking force")
    assert float(force[2]) <= 1e-6 * float(force[1])
    placed = re.findall(r"^\s+arm\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)$",
                        text.split("counterweights placed")[1].split("new bodies")[0], re.M)
    assert placed
    for _, x, y, z in placed:
        p = np.array([float(x), float(y), float(z)])
        assert p[1] == 0.0  # in the plane normal to the joint axis (y)
        assert np.linalg.norm(p - [0.01, 0, 0]) == pytest.approx(0.05, rel=1e-5)


def test_pareto_front(tmp_path, capsys):
    png, out = tmp_path / "p.png", tmp_path / "p.csv"
    args = ["balance", "fourbar", "--samples", "48", *RINGS, "--pareto", "force,moment:3",
            "--plot", str(png), "--out", str(out)]
    assert cli.main(args) == 0
    text = capsys.readouterr().out
    assert "Pareto front, 3 balances of 3" in text
    header, rows = read_rows(out)
    assert header == ["weight_force", "weight_moment", "rms_force", "rms_moment", "mass_added"]
    data = np.array(rows, dtype=float)
    assert data.shape == (3, 5)
    # The ends weight the other objective 1e-5 (pmd.design.TIE_WEIGHT): ties broken by it.
    np.testing.assert_allclose(data[:, 1], [0.0, 0.5, 1.0], rtol=0, atol=2e-5)
    # Along the front the force rises and the moment falls.
    assert np.all(np.diff(data[:, 2]) > 0) and np.all(np.diff(data[:, 3]) < 0)
    assert is_png(png)


@pytest.mark.parametrize(
    "extra, option",
    [
        (["--counterweight", "crank"], "--counterweight"),
        (["--counterweight", "cranck:0.02"], "--counterweight"),
        (["--counterweight", "crank:-0.02"], "--counterweight"),
        (["--counterweight", "crank:0.02:zero"], "--counterweight"),
        (["--counterweight", "crank:0.02@1,2"], "--counterweight"),
        (["--weight", "force"], "--weight"),
        (["--weight", "shake=1", *RINGS], "--weight"),
        (["--weight", "force=-1", *RINGS], "--weight"),
        (["--pareto", "force,force", *RINGS], "--pareto"),
        (["--pareto", "force,moment", "--weight", "force=1", *RINGS], "--pareto"),
        (["--zero", "force"], "--zero"),
        (["--driver", "rockr"], "--driver"),
        (["--driver", "world"], "--driver"),
        (["--samples", "1"], "--samples"),
        (["--speed", "0"], "--speed"),
        (["--speed", "nan"], "--speed"),
        (["--max-mass", "0", *RINGS], "--max-mass"),
        (["--redesign", "ground"], "--redesign"),
        (["--samples", "12", *RINGS, "--out", "table.txt"], "--out"),
    ],
)
def test_bad_arguments_name_the_option(extra, option, capsys):
    assert cli.main(["balance", "fourbar", *extra]) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith("pointmass-dyn: error: " + option), captured.err


def test_argparse_errors_and_scenes_without_a_driver(capsys):
    with pytest.raises(SystemExit) as info:
        cli.main(["balance", "fourbar", "--zero", "shake"])
    assert info.value.code == 2
    assert "--zero" in capsys.readouterr().err
    # A scene that fixes no single body and has no one-dof joint to drive.
    assert cli.main(["balance", "pendulum_planar"]) == 2
    err = capsys.readouterr().err
    assert "--driver" in err and "pendulum_planar" in err
    assert cli.main(["balance", "pendulum_planar", "--driver", "rod"]) == 2
    assert "1-dof" in capsys.readouterr().err
    # Counterweights on the crank alone cannot cancel the shaking force: the library's error.
    assert cli.main(["balance", "fourbar", "--samples", "24", "--counterweight", "crank:0.02",
                     "--zero", "force"]) == 2
    assert "vanish" in capsys.readouterr().err


def test_help_documents_the_syntax(capsys):
    with pytest.raises(SystemExit) as info:
        cli.main(["balance", "--help"])
    assert info.value.code == 0
    text = capsys.readouterr().out
    for part in ("BODY:RADIUS[:COUNT][@X,Y,Z]", "--redesign", "--zero", "--weight Q=W",
                 "Q1,Q2[:COUNT]", "--plot", "--out", "examples:"):
        assert part in text


# --------------------------------------------------------------------------------------------
# The plots
# --------------------------------------------------------------------------------------------
def test_plot_balance_and_plot_motion_write_pngs(tmp_path):
    plt = matplotlib.pyplot
    sc, motion = fourbar_motion(48)
    rings = [pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, count=12),
             pmd.Counterweight.ring("rocker", [0, 0, 0], 0.02, count=12)]
    b = pmd.balance(motion, counterweights=rings, zero=("force",))
    plot_balance(b, tmp_path / "balance.png", title="fourbar")
    plot_motion(motion, tmp_path / "motion.png")
    assert is_png(tmp_path / "balance.png") and is_png(tmp_path / "motion.png")
    # Without a path the figure is returned: four panels, before and after in each.
    fig = plot_balance(b)
    try:
        axes = fig.axes
        assert len(axes) == 4
        assert axes[0].get_aspect() == 1.0  # the polar diagram has equal axes
        labels = [t.get_text() for t in axes[0].get_legend().get_texts()]
        assert labels[0].startswith("before") and labels[1].startswith("after")
        caption = "\n".join(t.get_text() for t in fig.texts)
        assert "counterweight on crank" in caption and "counterweight on rocker" in caption
        assert "crank angle (deg)" in axes[1].get_xlabel()
    finally:
        plt.close(fig)
    front = pmd.pareto_front(motion, ("force", "moment"), 3, counterweights=rings)
    plot_pareto(front, ("force", "moment"), tmp_path / "front.png")
    assert (tmp_path / "front.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_plot_motion_picks_the_plane_and_the_moment_component(tmp_path):
    plt = matplotlib.pyplot
    # A link turning about y: the force locus lies in the x–z plane, the moment along y.
    arm = pmd.Model()
    arm.add_body(pmd.RigidBody(0.5, [0.1, 0, 0], np.diag([1e-4, 2e-3, 2e-3])),
                 pmd.Revolute([0, 1, 0]), name="arm")
    t = np.linspace(0.0, 1.0, 36, endpoint=False)
    w = 2 * np.pi
    swing = (t, 0.5 * np.sin(w * t), 0.5 * w * np.cos(w * t), -0.5 * w * w * np.sin(w * t))
    motion = pmd.prescribed_motion(arm, "arm", input=swing, gravity=[0, 0, -9.81])
    fig = plot_motion(motion, title="arm")
    try:
        assert fig.axes[0].get_xlabel() == "shaking force Fx (N)"
        assert fig.axes[0].get_ylabel() == "shaking force Fz (N)"
        assert fig.axes[1].get_ylabel() == "shaking moment My (N·m)"
    finally:
        plt.close(fig)
    # A spatial pendulum along a simulated motion (no driver): time on the x axis, |M|.
    sc = pmd.load_scene("pendulum_spatial")
    r = pmd.simulate(sc, (0.0, 0.3), t_eval=np.linspace(0.0, 0.3, 31))
    g = [0.0, 0.0, -9.81]
    a = [sc.model.forward_dynamics(q, v, np.zeros(3), gravity=g) for q, v in zip(r.q, r.v)]
    analysis = pmd.analyze_motion(sc.model, r.t, r.q, r.v, a, gravity=g)
    plot_motion(analysis, tmp_path / "spatial.png")
    assert is_png(tmp_path / "spatial.png")
    fig = plot_motion(analysis)
    try:
        assert fig.axes[1].get_ylabel() == "shaking moment |M| (N·m)"
        assert fig.axes[1].get_xlabel() == "t (s)"
    finally:
        plt.close(fig)


# --------------------------------------------------------------------------------------------
# Units (issue 38 #9): every figure the design and balance commands print has its unit
# --------------------------------------------------------------------------------------------
#: The SI unit of each quantity the tables print: the fourbar's driver is a revolute joint,
#: so its driving force is a torque.
EXPECTED_UNIT = {"shaking force": "N", "shaking moment": "N·m", "driving force": "N·m",
                 "bearing": "N", "cut joint": "N"}


def _table_units(text: str) -> dict[str, str]:
    """The unit printed with each quantity row of a before/after or RMS/peak table."""
    out = {}
    for line in text.splitlines():
        m = re.match(r"^((?:shaking|driving|bearing|cut joint)[^(]*?)\s*\(([^)]*)\)\s+[-\d.]",
                     line)
        if m:
            out[m.group(1)] = m.group(2)
        elif re.match(r"^(shaking|driving|bearing|cut joint)", line):
            out[line.split("  ")[0]] = None  # a row without a unit
    return out


def _check_units(text: str) -> None:
    units = _table_units(text)
    assert len(units) == 7, text  # force, moment, one driver, three bearings, one cut joint
    for name, unit in units.items():
        kind = next(k for k in EXPECTED_UNIT if name.startswith(k))
        assert unit == EXPECTED_UNIT[kind], (name, unit)


def test_design_and_balance_print_every_figure_with_its_unit(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text('speed = 30.0\nsamples = 24\n[[counterweight]]\nbody = "rocker"\n'
                    'ring = { center = [0, 0, 0], radius = 0.02, count = 8 }\nmax_mass = 0.05\n')
    assert cli.main(["design", "fourbar", str(spec), "--out", str(tmp_path / "d")]) == 0
    text = capsys.readouterr().out
    assert "'crank' driven at 30 rad/s over one revolution" in text
    _check_units(text)
    # A front: each objective's value with its unit (bearing and shaking forces: N).
    spec.write_text(spec.read_text() + '[pareto]\nobjectives = ["bearing", "moment"]\ncount = 2\n')
    assert cli.main(["design", "fourbar", str(spec), "--out", str(tmp_path / "p")]) == 0
    text = capsys.readouterr().out
    assert "bearing (N) / moment (N·m)" in text
    rows = [r for r in text.splitlines() if "design mass" in r]
    assert len(rows) == 2
    assert all(re.fullmatch(r"\s+\S+ N\s+\S+ N·m\s+design mass \S+ kg", r) for r in rows), rows
    # The balance command's tables.
    assert cli.main(["balance", "fourbar", "--samples", "24"]) == 0
    _check_units(capsys.readouterr().out)
    assert cli.main(["balance", "fourbar", "--samples", "24", *RINGS]) == 0
    text = capsys.readouterr().out
    _check_units(text)
    assert "COM x (m)" in text and "Ixx (kg·m²)" in text
