"""Scene files (TOML: units, per-body state, inertia forms, placements, errors naming the file
and key), the bundled scenes, the command line (in process and as ``python -m``), and the
type stubs of the extension."""

from __future__ import annotations

import ast
import inspect
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
import pointmass_dyn._core as core
import pytest
from pointmass_dyn import cli
from scipy.spatial.transform import Rotation

PKG_DIR = Path(pmd.__file__).resolve().parent
PYTHON_DIR = PKG_DIR.parent

ROD = """
name = "rod"
angles = "degrees"

[[body]]
name = "rod"
joint = { type = "SphericalZYZ" }
mass = 2.51
com = [0.5, 0, 0]
inertia_diag = [1.255e-4, 0.2092294166666666, 0.2092294166666666]
q0 = [90, 45, 45]
v0 = [0, 57.29577951308232, 0]

[[effect]]
type = "gravity"
g = [0, 0, -9.81]
"""


def write(tmp_path: Path, text: str, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def scene_error(tmp_path: Path, text: str, name: str = "bad.toml") -> str:
    path = write(tmp_path, text, name)
    with pytest.raises(pmd.SceneError) as info:
        pmd.load_scene(path)
    msg = str(info.value)
    assert str(path) in msg, msg  # every scene error names the file
    return msg


# --------------------------------------------------------------------------------------------
# Bundled scenes
# --------------------------------------------------------------------------------------------
def test_builtin_scenes_include_the_paper_and_chain7():
    scenes = pmd.builtin_scenes()
    assert {"pendulum_planar", "pendulum_spatial", "chain7"} <= set(scenes)
    for name, path in scenes.items():
        assert Path(path).is_file() and Path(path).stem == name
        assert pmd.load_scene(name).name == name
        assert pmd.load_scene(path).name == name


def test_bundled_pendulums_are_the_papers():
    planar = pmd.load_scene("pendulum_planar")
    spatial = pmd.load_scene("pendulum_spatial")
    np.testing.assert_allclose(planar.q0, np.radians([90, 90, 90]), rtol=1e-15)
    np.testing.assert_array_equal(planar.v0, [0, 0, 0])
    np.testing.assert_allclose(spatial.q0, np.radians([90, 45, 45]), rtol=1e-15)
    np.testing.assert_array_equal(spatial.v0, [0.0, 1.0, 0.0])  # rates = "radians"
    for s in (planar, spatial):
        assert s.effects == [pmd.Gravity((0.0, 0.0, -9.81))]
        assert s.t_span == (0.0, 10.0)
        assert s.model.nq == s.model.nv == 3 and s.model.link_names == ["rod"]
        assert s.model.total_mass == 2.51


def test_bundled_chain7_is_the_benchmark():
    s = pmd.load_scene("chain7")
    m = s.model
    assert (m.nq, m.nv, m.nbodies) == (7, 7, 7)
    np.testing.assert_array_equal(s.q0, np.full(7, 0.3))
    np.testing.assert_array_equal(s.v0, np.zeros(7))
    assert (s.rtol, s.atol, s.t_span) == (1e-6, 1e-9, (0.0, 10.0))
    # Same model as docs/benchmarks.md's chainN built in Python: same mass matrix and dynamics.
    ref = pmd.Model()
    body = pmd.RigidBody(1.0, [0.15, 0, 0], np.diag([1e-3, 7.5e-3, 7.5e-3]))
    for k in range(7):
        axis = [0, 1, 0] if k % 2 == 0 else [0, 0, 1]
        ref.add_body(body, pmd.Revolute(axis), parent=k - 1, translation=[0.3 * (k > 0), 0, 0])
    q = np.linspace(-1, 1, 7)
    v = np.linspace(0.5, -0.5, 7)
    np.testing.assert_allclose(m.mass_matrix(q), ref.mass_matrix(q), rtol=1e-13, atol=1e-15)
    g = [0, 0, -9.81]
    np.testing.assert_allclose(
        m.forward_dynamics(q, v, np.zeros(7), gravity=g),
        ref.forward_dynamics(q, v, np.zeros(7), gravity=g), rtol=1e-12, atol=1e-12,
    )


# --------------------------------------------------------------------------------------------
# Loading: units, per-body state, inertia, placements, settings
# --------------------------------------------------------------------------------------------
def test_angle_and_rate_units(tmp_path):
    deg = pmd.load_scene(write(tmp_path, ROD))
    np.testing.assert_allclose(deg.q0, np.radians([90, 45, 45]), rtol=1e-15)
    np.testing.assert_allclose(deg.v0, [0, 1, 0], rtol=1e-14, atol=0)  # rates default to angles
    rad_rates = pmd.load_scene(write(tmp_path, ROD.replace(
        'angles = "degrees"', 'angles = "degrees"\nrates = "radians"')))
    np.testing.assert_array_equal(rad_rates.v0, [0, 57.29577951308232, 0])
    np.testing.assert_allclose(rad_rates.q0, deg.q0, rtol=0)
    radians = pmd.load_scene(write(tmp_path, ROD.replace('angles = "degrees"', "")))
    np.testing.assert_array_equal(radians.q0, [90, 45, 45])  # radians is the default
    only_rates = pmd.load_scene(write(tmp_path, ROD.replace('angles = "degrees"', 'rates = "degrees"')))
    np.testing.assert_array_equal(only_rates.q0, [90, 45, 45])
    np.testing.assert_allclose(only_rates.v0, [0, 1, 0], rtol=1e-14)


def test_per_body_state_in_a_tree(tmp_path):
    text = """
angles = "degrees"
[[body]]
name = "base"
joint = { type = "Revolute", axis = [0, 0, 1] }
mass = 1.0
inertia_diag = [0.01, 0.01, 0.01]
q0 = [30]
v0 = [90]
[[body]]
name = "slider"
parent = "base"
joint = { type = "Prismatic", axis = [1, 0, 0] }
translation = [0.5, 0, 0]
mass = 0.5
inertia_diag = [0.001, 0.002, 0.002]
q0 = [0.25]
v0 = [-0.5]
[[body]]
name = "welded"
parent = "slider"
joint = { type = "Fixed" }
translation = [0.1, 0, 0]
mass = 0.2
inertia_diag = [0.001, 0.001, 0.001]
[[body]]
name = "ball"
parent = "welded"
joint = { type = "Spherical" }
mass = 0.3
com = [0, 0, -0.1]
inertia_diag = [0.001, 0.001, 0.0005]
q0 = [0, 0, 2, 2]
v0 = [1, 2, 3]
[[body]]
name = "idle"
parent = "base"
joint = { type = "Revolute", axis = [0, 1, 0] }
mass = 0.1
inertia_diag = [0.001, 0.001, 0.001]
"""
    s = pmd.load_scene(write(tmp_path, text))
    m = s.model
    assert m.body_names == ["base", "slider", "welded", "ball", "idle"]
    assert m.link_names == ["base", "slider", "ball", "idle"]
    assert (m.nq, m.nv) == (1 + 1 + 4 + 1, 1 + 1 + 3 + 1)
    # Revolute angles and rates in degrees; prismatic in metres; quaternion normalised,
    # its angular velocity scaled like any rate; a body without q0/v0 at neutral and rest.
    r = np.sqrt(0.5)
    np.testing.assert_allclose(s.q0, [np.pi / 6, 0.25, 0, 0, r, r, 0.0], rtol=1e-15, atol=0)
    np.testing.assert_allclose(
        s.v0, [np.pi / 2, -0.5, *np.radians([1, 2, 3]), 0.0], rtol=1e-15, atol=0)
    assert m.body_info(2) == ("welded", "Fixed", 1, 1)  # welded into the slider's link
    assert s.effects == [] and s.t_span is None


def test_full_inertia_equals_python_body(tmp_path):
    inertia = np.array([[0.05, 0.004, -0.002], [0.004, 0.03, 0.001], [-0.002, 0.001, 0.04]])
    com = [0.1, -0.02, 0.03]
    rows = ", ".join("[" + ", ".join(repr(float(x)) for x in row) + "]" for row in inertia)
    text = f"""
[[body]]
name = "b"
joint = {{ type = "Spherical" }}
mass = 1.7
com = {list(com)}
inertia = [{rows}]
"""
    s = pmd.load_scene(write(tmp_path, text))
    ref = pmd.Model()
    ref.add_body(pmd.RigidBody(1.7, com, inertia), pmd.Spherical())
    q = Rotation.from_euler("zyx", [0.4, -0.3, 1.2]).as_quat()
    np.testing.assert_allclose(s.model.mass_matrix(q), ref.mass_matrix(q), rtol=1e-14, atol=1e-16)
    np.testing.assert_allclose(s.model.mass_matrix(q), inertia + 1.7 * (np.dot(com, com) * np.eye(3)
                               - np.outer(com, com)), rtol=1e-13)
    # inertia_diag is the diagonal tensor.
    diag = pmd.load_scene(write(tmp_path, text.replace(f"inertia = [{rows}]", "inertia_diag = [0.05, 0.03, 0.04]")))
    ref2 = pmd.Model()
    ref2.add_body(pmd.RigidBody(1.7, com, np.diag([0.05, 0.03, 0.04])), pmd.Spherical())
    np.testing.assert_allclose(diag.model.mass_matrix(q), ref2.mass_matrix(q), rtol=1e-14, atol=1e-16)


@pytest.mark.parametrize("angles", ["radians", "degrees"])
def test_rpy_and_rotation_place_the_joint_frame(tmp_path, angles):
    rpy = np.array([0.3, -0.5, 1.2])
    given = [float(x) for x in (np.degrees(rpy) if angles == "degrees" else rpy)]
    text = f"""
angles = "{angles}"
[[body]]
name = "b"
joint = {{ type = "Revolute", axis = [0, 0, 1] }}
translation = [0.1, 0.2, 0.3]
rpy = [{given[0]!r}, {given[1]!r}, {given[2]!r}]
mass = 1.0
inertia_diag = [0.01, 0.01, 0.01]
"""
    s = pmd.load_scene(write(tmp_path, text))
    rot, origin = s.model.placements([0.0])
    expected = Rotation.from_euler("ZYX", rpy[::-1]).as_matrix()  # URDF: Rz(y) Ry(p) Rx(r)
    np.testing.assert_allclose(rot[0], expected, rtol=0, atol=1e-15)
    np.testing.assert_allclose(origin[0], [0.1, 0.2, 0.3], rtol=0, atol=0)
    # The same placement as an explicit matrix (rows).
    rows = ", ".join("[" + ", ".join(repr(float(x)) for x in row) + "]" for row in expected)
    explicit = pmd.load_scene(write(tmp_path, re.sub(r"rpy = .*", f"rotation = [{rows}]", text)))
    np.testing.assert_allclose(explicit.model.placements([0.0])[0][0], expected, rtol=0, atol=1e-15)
    # Rotating the joint by q turns the body about the joint frame's z axis.
    rot_q = s.model.placements([0.7])[0][0]
    np.testing.assert_allclose(rot_q, expected @ Rotation.from_rotvec([0, 0, 0.7]).as_matrix(), atol=1e-15)


def test_simulate_settings_from_the_file(tmp_path):
    s = pmd.load_scene(write(tmp_path, ROD + "\n[simulate]\nt_end = 3\nrtol = 1e-7\natol = 1e-10\nmax_steps = 5\n"))
    assert (s.t_span, s.rtol, s.atol, s.max_steps) == ((0.0, 3.0), 1e-7, 1e-10, 5)
    r = pmd.simulate(s)
    assert not r.success and r.n_accepted == 5  # the file's max_steps applies
    r = pmd.simulate(s, max_steps=100000)  # the caller's arguments win
    assert r.success and r.t[-1] == 3.0


def test_from_toml_text_names_the_given_file():
    s = pmd.Scene.from_toml(ROD, "inline.toml")
    assert s.name == "rod" and s.model.nq == 3
    with pytest.raises(pmd.SceneError, match=r"^inline\.toml: "):
        pmd.Scene.from_toml(ROD.replace("mass = 2.51", "mass = 0"), "inline.toml")


# --------------------------------------------------------------------------------------------
# Errors name the file and the key
# --------------------------------------------------------------------------------------------
def test_scene_error_is_a_value_error():
    assert issubclass(pmd.SceneError, ValueError)
    assert issubclass(pmd.SceneError, pmd.PointMassDynError)


def test_unknown_parent(tmp_path):
    text = ROD + """
[[body]]
name = "tip"
parent = "rood"
joint = { type = "Revolute", axis = [0, 0, 1] }
mass = 1.0
inertia_diag = [0.01, 0.01, 0.01]
"""
    msg = scene_error(tmp_path, text)
    assert "body[1] ('tip').parent" in msg and "rood" in msg


def test_missing_inertia(tmp_path):
    msg = scene_error(tmp_path, re.sub(r"inertia_diag = .*\n", "", ROD))
    assert "body[0] ('rod').inertia" in msg and "missing" in msg


def test_negative_inertia(tmp_path):
    msg = scene_error(tmp_path, ROD.replace("inertia_diag = [1.255e-4", "inertia_diag = [-1.255e-4"))
    assert "body[0] ('rod').inertia" in msg
    msg = scene_error(tmp_path, ROD.replace("mass = 2.51", "mass = -2.51"))
    assert "body[0] ('rod').mass" in msg


def test_both_inertia_forms(tmp_path):
    msg = scene_error(tmp_path, ROD.replace("mass = 2.51", "mass = 2.51\ninertia = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]"))
    assert "body[0] ('rod').inertia" in msg and "not both" in msg


def test_bad_toml_syntax_gives_the_line(tmp_path):
    lines = ROD.splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("mass"))
    lines[k] = "mass = = 2.51"
    msg = scene_error(tmp_path, "\n".join(lines))
    assert f"line {k + 1}" in msg


def test_unknown_key_typo(tmp_path):
    text = ROD.replace("mass = 2.51", "mass = 2.51\nmas = 3")
    msg = scene_error(tmp_path, text)
    line = text.splitlines().index("mas = 3") + 1
    assert "`mas`" in msg and f"line {line}" in msg
    msg = scene_error(tmp_path, ROD.replace('angles = "degrees"', 'angle = "degrees"'))
    assert "`angle`" in msg
    msg = scene_error(tmp_path, ROD.replace('angles = "degrees"', 'angles = "degree"'))
    assert "angles" in msg and "degree" in msg


def test_wrong_q0_length(tmp_path):
    msg = scene_error(tmp_path, ROD.replace("q0 = [90, 45, 45]", "q0 = [90, 45]"))
    assert "body[0] ('rod').q0" in msg and "3" in msg and "2" in msg
    msg = scene_error(tmp_path, ROD.replace("v0 = [0, 57.29577951308232, 0]", "v0 = [0, 1, 0, 0]"))
    assert "body[0] ('rod').v0" in msg


def test_bad_simulate_settings(tmp_path):
    msg = scene_error(tmp_path, ROD + "\n[simulate]\nt_span = [1, 1]\n")
    assert "simulate.t_span" in msg
    msg = scene_error(tmp_path, ROD + "\n[simulate]\nrtol = -1e-6\n")
    assert "simulate.rtol" in msg


def test_missing_file(tmp_path):
    missing = tmp_path / "nowhere.toml"
    with pytest.raises(pmd.SceneError) as info:
        pmd.load_scene(missing)
    assert str(missing) in str(info.value)


# --------------------------------------------------------------------------------------------
# The command line, in process
# --------------------------------------------------------------------------------------------
def test_cli_scenes(capsys):
    assert cli.main(["scenes"]) == 0
    out = capsys.readouterr().out
    names = [line.split()[0] for line in out.splitlines() if line.strip()]
    assert names == sorted(pmd.builtin_scenes())


def test_cli_point_masses_prints_the_papers_masses(capsys):
    assert cli.main(["point-masses", "pendulum_planar"]) == 0
    out = capsys.readouterr().out
    for text in ("0.6275", "-0.543431", "1.17093"):
        assert text in out
    rows = [line.split() for line in out.splitlines() if re.match(r"^\s+[1-7]\s", line)]
    assert [int(r[0]) for r in rows] == list(range(1, 8))
    masses = np.array([float(r[1]) for r in rows])
    # docs/conventions.md §7: (0.6275, −0.5434, 1.1709, 0, 1.1709, −0.5434, 0.6275) kg,
    # total m.
    np.testing.assert_allclose(masses, [0.6275, -0.5434, 1.1709, 0, 1.1709, -0.5434, 0.6275], atol=1e-4)
    assert abs(masses.sum() - 2.51) <= 1e-5
    # Printed positions are the world positions at q0: the points of the model itself.
    _, pos = pmd.load_scene("pendulum_planar").model.point_masses(np.radians([90, 90, 90]))
    printed = np.array([[float(x) for x in r[2:5]] for r in rows])
    np.testing.assert_allclose(printed, pos[0], rtol=1e-5, atol=1e-9)


def read_csv(path: Path):
    header = path.read_text(encoding="utf-8").splitlines()[0].split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return header, data


def check_trajectory_file_against_simulate(t, q, v, energy):
    scene = pmd.load_scene("pendulum_planar")
    ref = pmd.simulate(scene, (0.0, 2.0), energy=True)  # the scene's own tolerances
    assert t[0] == 0.0 and t[-1] == 2.0
    np.testing.assert_allclose(t, ref.t, rtol=1e-15, atol=0)
    np.testing.assert_allclose(q, ref.q, rtol=1e-15, atol=0)
    np.testing.assert_allclose(v, ref.v, rtol=1e-15, atol=1e-300)
    np.testing.assert_allclose(energy, ref.energy, rtol=1e-12, atol=1e-18)


def test_cli_simulate_writes_csv_and_png(tmp_path, capsys):
    csv, png = tmp_path / "x.csv", tmp_path / "x.png"
    assert cli.main(["simulate", "pendulum_planar", "--t-end", "2", "--out", str(csv), "--plot", str(png)]) == 0
    out = capsys.readouterr().out
    assert "pendulum_planar" in out and str(csv) in out
    header, data = read_csv(csv)
    assert header[0] == "t" and header[-1] == "energy" and len(header) == 1 + 3 + 3 + 1
    assert all(h.startswith("q[") for h in header[1:4]) and all(h.startswith("v[") for h in header[4:7])
    check_trajectory_file_against_simulate(data[:, 0], data[:, 1:4], data[:, 4:7], data[:, 7])
    blob = png.read_bytes()
    assert blob[:8] == b"\x89PNG\r\n\x1a\n" and len(blob) > 10_000


def test_cli_simulate_writes_npz(tmp_path, capsys):
    npz = tmp_path / "x.npz"
    assert cli.main(["simulate", "pendulum_planar", "--t-end", "2", "--out", str(npz)]) == 0
    capsys.readouterr()
    with np.load(npz) as f:
        assert {"t", "q", "v", "energy"} <= set(f.files)
        assert f["q"].shape == (len(f["t"]), 3) and f["v"].shape == (len(f["t"]), 3)
        check_trajectory_file_against_simulate(f["t"], f["q"], f["v"], f["energy"])


def test_cli_errors(tmp_path, capsys):
    bad = tmp_path / "missing.toml"
    assert cli.main(["simulate", str(bad)]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "error" in err
    broken = write(tmp_path, ROD.replace("mass = 2.51", "mass = -1"), "broken.toml")
    assert cli.main(["point-masses", str(broken)]) == 2
    assert "body[0] ('rod').mass" in capsys.readouterr().err
    assert cli.main(["simulate", "pendulum_planar", "--t-end", "0.1", "--out", str(tmp_path / "x.txt")]) == 2
    assert "--out" in capsys.readouterr().err
    # animate refuses a file name it cannot write before the run, not after it (issue 38's
    # walk: `animate fourbar --out x.xyz` ran the whole simulation first).
    assert cli.main(["animate", "pendulum_planar", "--out", str(tmp_path / "x.xyz")]) == 2
    captured = capsys.readouterr()
    assert "--out" in captured.err and ".html, .gif or .mp4" in captured.err
    assert "reached the end" not in captured.out
    # A run that cannot finish exits 1.
    failing = write(tmp_path, ROD + "\n[simulate]\nt_end = 1\nmax_steps = 3\n", "failing.toml")
    assert cli.main(["simulate", str(failing)]) == 1
    assert "steps" in capsys.readouterr().out
    with pytest.raises(SystemExit) as info:
        cli.main(["no-such-command"])
    assert info.value.code == 2
    capsys.readouterr()


# --------------------------------------------------------------------------------------------
# The command line, as `python -m pointmass_dyn`
# --------------------------------------------------------------------------------------------
def run_module(args, cwd):
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in [str(PYTHON_DIR), env.get("PYTHONPATH", "")] if p)
    env["MPLBACKEND"] = "Agg"
    return subprocess.run(
        [sys.executable, "-m", "pointmass_dyn", *args], cwd=cwd, env=env, capture_output=True,
        text=True, timeout=120,
    )


def test_module_simulate_csv_png(tmp_path):
    p = run_module(["simulate", "pendulum_planar", "--t-end", "2", "--out", "x.csv", "--plot", "x.png"], tmp_path)
    assert p.returncode == 0, p.stderr
    _, data = read_csv(tmp_path / "x.csv")
    check_trajectory_file_against_simulate(data[:, 0], data[:, 1:4], data[:, 4:7], data[:, 7])
    blob = (tmp_path / "x.png").read_bytes()
    assert blob[:8] == b"\x89PNG\r\n\x1a\n" and len(blob) > 10_000


def test_module_scenes_and_bad_path(tmp_path):
    p = run_module(["scenes"], tmp_path)
    assert p.returncode == 0, p.stderr
    assert [line.split()[0] for line in p.stdout.splitlines()] == sorted(pmd.builtin_scenes())
    p = run_module(["simulate", "does/not/exist.toml"], tmp_path)
    assert p.returncode == 2
    assert "does/not/exist.toml" in p.stderr and p.stdout == ""


# --------------------------------------------------------------------------------------------
# Type stubs: every export of the extension is declared, with the runtime's parameters
# --------------------------------------------------------------------------------------------
def _stub_tree():
    return ast.parse((PKG_DIR / "_core.pyi").read_text(encoding="utf-8"))


def _public(obj) -> set[str]:
    return {n for n in dir(obj) if not n.startswith("_")}


def _stub_bases(tree) -> dict[str, ast.ClassDef]:
    """The stub-only base classes (`_Record`): private, absent at runtime, and each the base
    of a declared class, whose runtime class must then have the base's methods."""
    classes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}
    used = {b.id for n in classes.values() for b in n.bases if isinstance(b, ast.Name)}
    bases = {name: n for name, n in classes.items() if not hasattr(core, name)}
    assert all(name.startswith("_") and name in used for name in bases), sorted(bases)
    return bases


def _body(node: ast.ClassDef, bases: dict[str, ast.ClassDef]) -> list[ast.stmt]:
    """A class's declarations, with those of its stub-only bases."""
    inherited = [m for b in node.bases if isinstance(b, ast.Name) and b.id in bases
                 for m in bases[b.id].body]
    return list(node.body) + inherited


def test_stub_declares_every_export():
    tree = _stub_tree()
    bases = _stub_bases(tree)
    classes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef) and n.name not in bases}
    functions = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    constants = {n.target.id for n in tree.body
                 if isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name)}
    runtime = {n for n in dir(core) if not n.startswith("_")}
    declared = set(classes) | set(functions) | constants
    assert runtime == {n for n in declared if not n.startswith("_")}
    # Private functions (pickling's _dumps/_loads) are declared only if they exist.
    assert all(hasattr(core, n) for n in functions)
    for name, node in classes.items():
        body = _body(node, bases)
        declared = {
            m.name for m in body if isinstance(m, ast.FunctionDef)
        } | {t.id for m in body if isinstance(m, ast.AnnAssign) for t in [m.target] if isinstance(t, ast.Name)
        } | {m.name for m in body if isinstance(m, ast.ClassDef)}  # variants (RunStatus.Stiff)
        # The base's dunders too: a stub-only base promises them on each runtime class.
        assert all(hasattr(getattr(core, name), m.name) for m in body if isinstance(m, ast.FunctionDef)), name
        missing = _public(getattr(core, name)) - declared
        assert not missing, f"{name}: not in _core.pyi: {sorted(missing)}"


def _params(fn: ast.FunctionDef) -> list[str]:
    args = fn.args
    named = [a.arg for a in args.posonlyargs + args.args + args.kwonlyargs]
    return [a for a in named if a not in ("self", "cls")] + (
        ["**" + args.kwarg.arg] if args.kwarg else []
    )


def test_stub_signatures_match_the_runtime():
    tree = _stub_tree()
    bases = _stub_bases(tree)
    checked = 0
    for node in tree.body:
        targets = []
        if isinstance(node, ast.FunctionDef):
            targets.append((node, getattr(core, node.name)))
        elif isinstance(node, ast.ClassDef) and node.name not in bases:
            cls = getattr(core, node.name)
            for m in _body(node, bases):
                if isinstance(m, ast.FunctionDef) and not m.name.startswith("__") or (
                    isinstance(m, ast.FunctionDef) and m.name == "__new__"
                ):
                    attr = inspect.getattr_static(cls, m.name)
                    if isinstance(attr, property) or type(attr).__name__ == "getset_descriptor":
                        continue
                    targets.append((m, cls if m.name == "__new__" else getattr(cls, m.name)))
        for fn, obj in targets:
            sig = getattr(obj, "__text_signature__", None)
            if not sig:
                continue
            runtime = [p.strip().split("=")[0].strip() for p in sig.strip("()").split(",")]
            runtime = [p for p in runtime if p and p not in ("$self", "$cls", "/", "*", "self", "cls", "$type")]
            assert _params(fn) == runtime, f"{fn.name}: stub {_params(fn)} vs runtime {runtime}"
            checked += 1
    assert checked >= 30


def test_cli_simulate_reports_the_energy_balance_of_a_damped_scene(capsys):
    """A damped run reports E(t) − E(0) against the dampers' work (it reads as a balance,
    not as a drift of 100 % of the energy), and the balance holds: the dampers' work over
    0.3 s, recomputed here from the recorded trajectory as −Σ c v² by Simpson's rule on a
    fine resampling, matches the reported E(end) − E(0)."""
    import re

    assert cli.main(["simulate", "chain_stiff", "--t-end", "0.3", "--rtol", "1e-9",
                     "--atol", "1e-9"]) == 0
    out = capsys.readouterr().out
    assert "energy balance" in out and "work of dampers" in out
    m = re.search(r"E\(end\) - E\(0\) = (\S+) J, work of dampers = (\S+) J; "
                  r"max \|E - E\(0\) - W\| = (\S+) J", out)
    change, work, imbalance = (float(x) for x in m.groups())
    assert change < 0 and abs(work - change) <= 1e-6 * abs(change)
    assert imbalance <= 1e-6 * abs(change)
    # An undamped run still reports a drift, and no work.
    assert cli.main(["simulate", "pendulum_planar", "--t-end", "1"]) == 0
    out = capsys.readouterr().out
    assert "energy: E(0)" in out and "work of" not in out
