"""Issue 11, defects 8-10: files read with limits, no silent inf/NaN from extreme finite
input, real numeric input only, and our own exceptions (never OverflowError, OSError, a plain
ValueError or a Rust panic). Each test asserts the exception class and that the message names
the argument or file."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn.errors import (
    InertiaError,
    InvalidInputError,
    NumericalError,
    SceneError,
    UrdfError,
)

CAP = 128 * 1024 * 1024

URDF = """<?xml version="1.0"?>
<robot name="r">
  <link name="base"/>
  <link name="arm">
    <inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
  </link>
  <joint name="j" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/></joint>
</robot>
"""


_LOADER = """
import sys
import pointmass_dyn as pmd
kind, path = sys.argv[1], sys.argv[2]
try:
    (pmd.Model.from_urdf if kind == "urdf" else pmd.load_scene)(path)
    print("no error")
except Exception as exc:
    print(type(exc).__name__)
    print(exc)
"""


def load_in_subprocess(kind, path, seconds=20):
    """(exception class name, message) of loading ``path`` in a child process, killed if it
    takes longer than ``seconds``: a regressed reader blocks in open() holding the GIL, which
    no thread or signal handler in this process could interrupt."""
    env = dict(os.environ)
    here = os.path.dirname(os.path.dirname(pmd.__file__))
    env["PYTHONPATH"] = os.pathsep.join([here, env.get("PYTHONPATH", "")])
    try:
        r = subprocess.run(
            [sys.executable, "-c", _LOADER, kind, str(path)],
            capture_output=True,
            text=True,
            timeout=seconds,
            env=env,
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"loading {path} ({kind}) still blocked after {seconds} s")
    name, _, message = r.stdout.partition("\n")
    return name, message


def body():
    return pmd.RigidBody(1.0, [0.5, 0, 0], np.diag([0.01, 0.1, 0.1]))


def model():
    m = pmd.Model()
    m.add_body(body(), pmd.Revolute([0, 0, 1]), name="a")
    m.add_body(body(), pmd.Prismatic([1, 0, 0]), parent=0, name="p")
    return m


# ---------------------------------------------------------------- defect 8: files


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
@pytest.mark.parametrize("kind", ["urdf", "scene", "scene_urdf"])
def test_fifo_is_refused_without_blocking(tmp_path, kind):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    if kind == "scene_urdf":
        scene = tmp_path / "s.toml"
        scene.write_text('urdf = "pipe"\n')
        name, message = load_in_subprocess("scene", scene)
        assert name == "SceneError" and str(scene) in message
    else:
        name, message = load_in_subprocess(kind, fifo)
        assert name == ("UrdfError" if kind == "urdf" else "SceneError"), (name, message)
    assert str(fifo) in message and "FIFO" in message and "regular" in message, message


def test_directory_is_refused(tmp_path):
    with pytest.raises(UrdfError, match="directory") as e:
        pmd.Model.from_urdf(tmp_path)
    assert str(tmp_path) in str(e.value) and "regular URDF file" in str(e.value)
    with pytest.raises(SceneError, match="directory") as e:
        pmd.load_scene(tmp_path)
    assert str(tmp_path) in str(e.value)


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="no /dev/zero")
def test_dev_zero_is_refused_as_urdf_and_in_a_scene(tmp_path):
    with pytest.raises(UrdfError, match="character device") as e:
        pmd.Model.from_urdf("/dev/zero")
    assert "/dev/zero" in str(e.value)
    scene = tmp_path / "s.toml"
    scene.write_text('urdf = "/dev/zero"\n')
    with pytest.raises(SceneError, match="character device") as e:
        pmd.load_scene(scene)
    assert str(scene) in str(e.value) and "urdf" in str(e.value) and "/dev/zero" in str(e.value)
    with pytest.raises(SceneError, match="character device"):
        pmd.load_scene("/dev/zero")


@pytest.mark.parametrize("suffix", ["urdf", "toml"])
def test_oversize_file_is_refused(tmp_path, suffix):
    big = tmp_path / f"big.{suffix}"
    with open(big, "wb") as f:
        f.truncate(CAP + 1)  # sparse: no disk used
    cls = UrdfError if suffix == "urdf" else SceneError
    load = pmd.Model.from_urdf if suffix == "urdf" else pmd.load_scene
    with pytest.raises(cls, match="at most 128 MiB") as e:
        load(big)
    assert str(big) in str(e.value) and str(CAP + 1) in str(e.value)


def test_over_long_and_invalid_paths_are_our_errors(tmp_path):
    long = str(tmp_path / ("x" * 5000))
    with pytest.raises(UrdfError, match="cannot read the URDF file") as e:
        pmd.Model.from_urdf(long)
    assert "xxxxxxxx" in str(e.value) and "5" in str(e.value) and len(str(e.value)) < 600
    with pytest.raises(SceneError, match="cannot read the scene file") as e:
        pmd.load_scene(long)
    assert "xxxxxxxx" in str(e.value) and len(str(e.value)) < 600
    with pytest.raises(SceneError, match="scene"):
        pmd.load_scene("a/" * 3000 + "s.toml")
    with pytest.raises(UrdfError, match="NUL"):
        pmd.Model.from_urdf("a\0b.urdf")
    with pytest.raises(SceneError, match="nope.toml"):
        pmd.load_scene(tmp_path / "nope.toml")


def test_regular_files_still_load(tmp_path):
    (tmp_path / "r.urdf").write_text(URDF)
    assert pmd.Model.from_urdf(tmp_path / "r.urdf").nv == 1
    (tmp_path / "s.toml").write_text('urdf = "r.urdf"\n')
    assert pmd.load_scene(tmp_path / "s.toml").model.nv == 1
    assert pmd.load_scene("pendulum_planar").model.nv >= 1


def test_non_utf8_file_is_refused(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b'name = "\xff"\n')
    with pytest.raises(SceneError, match="UTF-8") as e:
        pmd.load_scene(bad)
    assert str(bad) in str(e.value)


def test_add_body_many_names_still_checked():
    m = pmd.Model()
    for k in range(200):
        m.add_body(body(), pmd.Revolute([0, 0, 1]), parent=k - 1, name=f"b{k}")
    with pytest.raises(pmd.errors.ModelStructureError, match="'b17' already exists"):
        m.add_body(body(), pmd.Fixed(), parent=3, name="b17")
    # A failed add leaves the model usable and the name index consistent.
    assert m.add_body(body(), pmd.Fixed(), parent=3, name="tip") == 200
    s = pmd.Scene(m, effects=[pmd.Spring("b150", stiffness=1.0)])
    assert s.model.nbodies == 201


# ------------------------------------------------ defect 9: extreme finite input


def test_overflowing_inertia_is_refused():
    with pytest.raises(InertiaError, match="overflow") as e:
        pmd.RigidBody(1.0, [0, 0, 0], np.diag([9e307, 9e307, 9e307]))
    assert "inertia" in str(e.value)
    with pytest.raises(InertiaError, match="overflow"):
        pmd.RigidBody(1e300, [1e10, 0, 0], np.eye(3))


def test_overflow_in_a_link_is_refused_and_leaves_the_model_intact():
    m = pmd.Model()
    m.add_body(body(), pmd.Revolute([0, 0, 1]), name="a")
    with pytest.raises(InertiaError, match="overflow") as e:
        m.add_body(body(), pmd.Fixed(), parent=0, translation=[1e200, 0, 0], name="w")
    assert "'w'" in str(e.value) and "'a'" in str(e.value)
    assert m.nbodies == 1
    assert np.isfinite(m.mass_matrix([0.0])).all()


def test_friction_v_eps_with_infinite_reciprocal_is_refused():
    with pytest.raises(InvalidInputError, match="v_eps") as e:
        pmd.JointFriction(None, 1.0, v_eps=5e-324)
    assert "5e-324" in str(e.value)
    m = model()
    s = pmd.Scene(m, effects=[pmd.JointFriction(None, 1.0, v_eps=1e-300)])
    f = pmd.effect_forces(s, 0.0, [0, 0], [0.0, 1.0])
    assert np.isfinite(f["friction"]).all()


def test_float_results_never_silently_inf_or_nan():
    m = model()
    s = pmd.Scene(m, effects=[pmd.Gravity((0, 0, -9.81)), pmd.Damper(None, 1e300)])
    cases = [
        ("energies", lambda: pmd.energies(s, [0, 0], [1e200, 0])),
        ("effect_forces", lambda: pmd.effect_forces(s, 0.0, [0, 0], [1e200, 1e300])),
        ("kinetic_energy", lambda: m.kinetic_energy([0, 0], [1e200, 1e200])),
        ("potential_energy", lambda: m.potential_energy([0, 1e300], [1e300, 0, 0])),
        ("gravity_forces", lambda: m.gravity_forces([0, 1e300], [0, 1e300, 0])),
        ("inertia_about", lambda: body().inertia_about([1e200, 0, 0])),
        ("point_masses", lambda: body().point_masses(center=[1e200, 0, 0])),
        ("mass_matrix", lambda: m.mass_matrix([0, 1e200])),
        ("generalized_forces", lambda: m.generalized_forces([0, 0], np.full((2, 7, 3), 1e308))),
    ]
    for name, call in cases:
        with pytest.raises(NumericalError) as e:
            call()
        assert name in str(e.value), (name, str(e.value))


def test_dense_output_refuses_non_finite_values():
    r = pmd.rk45(lambda t, y: -y, (0, 1), [1.0], dense_output=True)
    with pytest.raises(NumericalError, match=r"sol\(t\)") as e:
        r["sol"](1e308)
    assert "1e308" in str(e.value)
    with pytest.raises(NumericalError, match=r"sol\(t\)"):
        r["sol"]([0.5, 1e308])
    with pytest.raises(InvalidInputError, match="t: expected finite times"):
        r["sol"](float("nan"))
    assert np.isfinite(r["sol"](0.5)).all() and r["sol"]([0.1, 0.9]).shape == (1, 2)


def test_event_returning_nan_or_a_non_number_is_an_error():
    with pytest.raises(NumericalError, match=r"events\[1\].*NaN at t = ") as e:
        pmd.rk45(lambda t, y: -y, (0, 1), [1.0], events=[lambda t, y: y[0], lambda t, y: float("nan")])
    assert "events[1]" in str(e.value)
    with pytest.raises(InvalidInputError, match=r"events\[0\].*'x' at t = "):
        pmd.rk45(lambda t, y: -y, (0, 1), [1.0], events=[lambda t, y: "x"])
    scene = pmd.load_scene("pendulum_planar")
    with pytest.raises(NumericalError, match=r"events\[0\]"):
        pmd.simulate(scene, (0, 0.1), events=[lambda t, q, v: float("nan")])


# ------------------------------------------ defect 10: over-permissive, foreign errors


@pytest.mark.parametrize(
    "value, what",
    [
        (np.array([0.0, 1j]), "complex"),
        (["0.3", "0"], "strings"),
        ("0.3", "str"),
        (np.ma.masked_array([0.0, 1.0], mask=[0, 1]), "masked"),
        (np.array([0.0, 1.0], dtype=object), "object"),
        ([0.0, 2**70], "object"),
        (np.array([True, False]), "bool"),
    ],
)
def test_arrays_must_be_real_numbers(value, what):
    m = model()
    for call in (m.mass_matrix, lambda q: m.forward_dynamics(q, [0, 0], [0, 0])):
        with pytest.raises(InvalidInputError, match=what) as e:
            call(value)
        assert str(e.value).startswith("q: expected real numbers")


def test_scalars_must_be_real_numbers():
    with pytest.raises(InvalidInputError, match="mass: .*complex"):
        pmd.RigidBody(np.complex128(1 + 1j), [0, 0, 0], np.eye(3))
    with pytest.raises(InvalidInputError, match="mass: .*double range"):
        pmd.RigidBody(2**2000, [0, 0, 0], np.eye(3))
    with pytest.raises(InvalidInputError, match="mass: .*str"):
        pmd.RigidBody("1.0", [0, 0, 0], np.eye(3))
    with pytest.raises(InvalidInputError, match="com: .*complex"):
        pmd.RigidBody(1.0, [0, 1j, 0], np.eye(3))
    with pytest.raises(InvalidInputError, match="v_eps"):
        pmd.JointFriction(None, 1.0, v_eps=np.complex128(1e-3 + 1j))
    with pytest.raises(InvalidInputError, match="stiffness: .*str"):
        pmd.Spring(None, stiffness="10")
    with pytest.raises(InvalidInputError, match="rtol"):
        pmd.rk45(lambda t, y: -y, (0, 1), [1.0], rtol=np.complex128(1e-3))
    with pytest.raises(InvalidInputError, match="t: "):
        pmd.effect_forces(pmd.load_scene("pendulum_planar"), 1j, [0.0], [0.0])
    # Integers, NumPy scalars and integer arrays are still numbers.
    assert pmd.RigidBody(np.float32(2), np.array([0, 0, 0]), np.eye(3, dtype=int)).mass == 2.0


@pytest.mark.parametrize(
    "call, arg",
    [
        (lambda: pmd.StateEvent("q", -1), "index"),
        (lambda: pmd.StateEvent("q", 2**70), "index"),
        (lambda: pmd.StateEvent("q", 0, direction=2**70), "direction"),
        (lambda: pmd.StateEvent("q", 0, terminal=2**70), "terminal"),
        (lambda: model().body_info(-1), "index"),
        (lambda: model().body_info(2**64), "index"),
        (lambda: model().add_body(body(), pmd.Fixed(), parent=2**70), "parent"),
        (lambda: model().add_body(body(), pmd.Fixed(), parent=-2), "parent"),
        (lambda: pmd.rk45(lambda t, y: -y, (0, 1), [1.0], max_steps=-1), "max_steps"),
        (lambda: pmd.simulate(pmd.load_scene("pendulum_planar"), (0, 1), max_steps=2**70), "max_steps"),
        (lambda: pmd.Spring(2**70, stiffness=1.0), "joints"),
    ],
)
def test_out_of_range_ints_are_invalid_input_not_overflow(call, arg):
    with pytest.raises(InvalidInputError) as e:
        call()
    assert not isinstance(e.value, OverflowError)
    assert str(e.value).startswith(f"{arg}:") or f"{arg}:" in str(e.value), str(e.value)


def test_non_int_index_is_a_type_error():
    with pytest.raises(TypeError):
        pmd.StateEvent("q", 1.5)


def test_huge_axis_is_normalised_not_refused():
    assert np.allclose(pmd.Revolute([1e200, 1e200, 0]).axis, [2**-0.5, 2**-0.5, 0])
    assert np.allclose(pmd.Prismatic([0, 1e-300, 0]).axis, [0, 1, 0])
    assert np.array_equal(pmd.Revolute([0, 0, 1]).axis, [0.0, 0.0, 1.0])
    with pytest.raises(InvalidInputError, match="axis"):
        pmd.Revolute([0, 0, 0])
    with pytest.raises(InvalidInputError, match="axis"):
        pmd.Revolute([np.nan, 1, 0])


def test_work_precision_tolerances_are_checked():
    scene = pmd.load_scene("pendulum_planar")
    for bad in (["0.3"], [1e-3, "a"], [1j], [0.0], [[1e-3]]):
        with pytest.raises(InvalidInputError, match="tolerances"):
            pmd.work_precision(scene, bad)


def test_cli_reports_unreadable_and_unwritable_files(tmp_path, capsys):
    from pointmass_dyn.cli import main

    assert main(["simulate", str(tmp_path), "--t-end", "0.01"]) == 2
    assert "directory" in capsys.readouterr().err
    out = tmp_path / "missing" / "traj.csv"
    assert main(["simulate", "pendulum_planar", "--t-end", "0.01", "--out", str(out)]) == 2
    # Refused before the run (issue 29, round 2), naming the option.
    assert "--out: expected a file in an existing directory" in capsys.readouterr().err

if __name__ == "__main__":  # pragma: no cover
    sys.exit(pytest.main([__file__, "-q"]))
