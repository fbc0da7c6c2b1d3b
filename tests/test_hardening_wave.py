"""Issue 29, second round: the newer entry points (ground contact, joint and torque limits,
couplings and armature, link shapes, balance, Pareto fronts, scene/URDF writing and the
``design`` command) under bad input and interrupts. Each test is a defect the round found:
an exception outside ``pmd.errors`` (or a ``TypeError`` not naming its argument), a value
silently reinterpreted, an allocation bomb, or work lost on an interrupt. The contract
(BRIEF.md): a ``pmd.errors`` exception (``TypeError`` for a wrong Python type) naming the
argument, the form expected and what was given."""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn.errors import InvalidInputError, SceneError

Z = [0.0, 0.0, 1.0]
G = np.array([0.0, -9.81, 0.0])
BOX = ([-0.05, -0.02, -0.004], [0.045, 0.02, 0.004])


@pytest.fixture(scope="module")
def motion():
    scene = pmd.load_scene("fourbar")
    return pmd.prescribed_motion(scene.model, "crank", speed=30.0, samples=24, q_guess=scene.q0, gravity=G)


@pytest.fixture(scope="module")
def fourbar():
    return pmd.load_scene("fourbar").model


def _arm() -> pmd.Model:
    arm = pmd.Model()
    arm.add_body(pmd.RigidBody(1.2, [0.2, 0, 0], np.diag([1e-3, 0.02, 0.02])), pmd.Revolute(Z), name="upper")
    arm.add_body(pmd.RigidBody(0.8, [0.15, 0, 0], np.diag([1e-3, 0.01, 0.01])), pmd.Revolute(Z),
                 parent="upper", translation=[0.4, 0, 0], name="fore")
    return arm


# --- contact ------------------------------------------------------------------------------


@pytest.mark.parametrize("xyz, radius", [("0 x 0", "0.01"), ("0 0 0", "abc"), ("0 0", "0.01")])
def test_urdf_contact_points_with_malformed_numbers_name_the_link(tmp_path, xyz, radius):
    # Was a builtin ValueError ("could not convert string to float"), or a 2-vector point.
    path = tmp_path / "r.urdf"
    path.write_text(
        f'<robot name="r"><link name="foot"><collision><origin xyz="{xyz}"/>'
        f'<geometry><sphere radius="{radius}"/></geometry></collision></link></robot>'
    )
    with pytest.raises(InvalidInputError, match="link 'foot'"):
        pmd.urdf_contact_points(path, ["foot"])


# --- couplings and armature ---------------------------------------------------------------


@pytest.mark.parametrize("joint", [1.0, None, [1]])
def test_a_joint_of_the_wrong_type_is_a_type_error_naming_the_argument(joint):
    # Was "'float' object cannot be interpreted as an integer": no argument named.
    with pytest.raises(TypeError, match="joint: expected a body index, a joint name or a body name"):
        _arm().add_coupling(joint, "upper")
    with pytest.raises(TypeError, match="joint: expected"):
        _arm().set_armature(joint, 0.1)


@pytest.mark.parametrize("arg", ["ratio", "offset"])
@pytest.mark.parametrize("value", [True, "x", [1.0, 2.0]])
def test_a_coupling_ratio_or_offset_that_is_not_a_number_is_refused(arg, value):
    # True was taken as 1.0 (bools are refused as numbers elsewhere); "x" and a list were a
    # TypeError without the argument's name.
    with pytest.raises(InvalidInputError, match=f"{arg}: expected"):
        _arm().add_coupling("fore", "upper", **{arg: value})


def test_armature_refuses_a_bool():
    with pytest.raises(InvalidInputError, match="value: expected .* got the bool True"):
        _arm().set_armature("fore", True)


def test_a_link_shape_body_of_the_wrong_type_names_the_argument(fourbar):
    with pytest.raises(TypeError, match="body"):
        pmd.LinkShape(1.5, box=BOX, cell=0.004).cells(fourbar)


# --- link shapes --------------------------------------------------------------------------


@pytest.mark.parametrize("boss", [math.nan, -1.0, math.inf, "x", True])
def test_link_shape_boss_must_be_a_finite_radius(fourbar, boss):
    # NaN kept no pin (every comparison false), -1 none, inf every cell: all silently.
    with pytest.raises(InvalidInputError, match="boss: expected None or a finite radius"):
        pmd.LinkShape("crank", box=BOX, cell=0.004, boss=boss).cells(fourbar)


@pytest.mark.parametrize("arg", ["cell", "density"])
def test_link_shape_refuses_a_bool_cell_or_density(fourbar, arg):
    # cell=True was taken as a 1 m cell.
    with pytest.raises(InvalidInputError, match=f"{arg}: expected a positive number, got True"):
        pmd.LinkShape("crank", box=BOX, **{"cell": 0.004, arg: True}).cells(fourbar)


def test_an_stl_envelope_that_cannot_be_read_is_our_error(tmp_path, fourbar):
    # A missing file was FileNotFoundError; a truncated ASCII vertex an IndexError; a word
    # where a number goes a ValueError.
    with pytest.raises(InvalidInputError, match="stl: expected a readable STL file"):
        pmd.LinkShape("crank", stl=tmp_path / "missing.stl").cells(fourbar)
    for body in ("solid x\nvertex 1 2\n", "solid x\nvertex 1 2 abc\n"):
        bad = tmp_path / "bad.stl"
        bad.write_text(body)
        with pytest.raises(InvalidInputError, match="stl: expected 'vertex x y z'"):
            pmd.LinkShape("crank", stl=bad).cells(fourbar)


@pytest.mark.parametrize("mass", ["ab", (1.0,), (1.0, 2.0, 3.0), 5.0])
def test_link_shape_mass_that_is_not_a_pair_is_refused(motion, mass):
    # Were builtin ValueErrors ("could not convert string to float", "not enough values").
    shape = pmd.LinkShape("crank", box=BOX, cell=0.004, mass=mass)
    with pytest.raises(InvalidInputError, match=r"mass: expected None or \(low, high\)"):
        pmd.balance(motion, links=[shape], zero=("force",))


# --- counterweights, balance, Pareto fronts ----------------------------------------------


@pytest.mark.parametrize("count", [10**9, 0, -1, 2.5, True])
def test_a_ring_count_out_of_range_is_refused_before_allocating(count):
    # 10**9 tried to allocate 7.45 GiB (numpy MemoryError); -1 and 0 gave an empty ring.
    with pytest.raises(InvalidInputError, match=r"count: expected an integer number of candidates in \[1, 1000000\]"):
        pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, count)


@pytest.mark.parametrize("normal", [(0, 0, 0), (math.nan, 0, 1), (0, 1)])
def test_a_ring_normal_must_be_a_finite_nonzero_vector(normal):
    with pytest.raises(InvalidInputError, match="normal: expected a finite non-zero"):
        pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 8, normal=normal)


def test_a_counterweight_point_far_enough_to_overflow_is_refused_by_name(motion):
    # Was an overflow RuntimeWarning, then "map: expected finite entries inside (nδ × nx)".
    cw = pmd.Counterweight("crank", [[1e300, 0, 0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(InvalidInputError, match=r"counterweights\[0\]: points of 'crank' .* within 1e100 m"):
            pmd.balance(motion, counterweights=[cw])
    with pytest.raises(InvalidInputError, match=r"counterweights\[0\]"):
        pmd.balance(motion, counterweights=[pmd.Counterweight("crank", [["a", 0, 0]])])


def test_pareto_count_is_bounded(motion):
    # count=10**9 allocated 7.45 GiB of weights (numpy MemoryError) before solving anything.
    ring = [pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 8)]
    with pytest.raises(InvalidInputError, match=r"count: expected an integer in \[2, 10000\]"):
        pmd.pareto_front(motion, ("force", "moment"), count=10**9, counterweights=ring)


def test_a_progress_that_is_not_callable_is_a_type_error_naming_it(motion):
    # Was "'int' object is not callable", after the motion maps were built.
    ring = [pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 8)]
    with pytest.raises(TypeError, match="progress: expected None or a callable"):
        pmd.balance(motion, counterweights=ring, progress=5)
    with pytest.raises(TypeError, match="progress: expected None or a callable"):
        pmd.pareto_front(motion, count=3, counterweights=ring, progress="x")


@pytest.mark.parametrize("method", ["weighted", "epsilon"])
def test_an_interrupted_pareto_front_keeps_the_points_solved(motion, method):
    # Ctrl-C (or a failing point) at the third point lost the two already solved.
    ring = [pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 8, max_mass=0.05)]

    def stop_at_third(text):
        if text.startswith("Pareto point 3/"):
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt) as info:
        pmd.pareto_front(motion, ("force", "moment"), count=4, counterweights=ring,
                         progress=stop_at_third, method=method)
    done = info.value.result
    assert len(done) == 2  # epsilon: the first end and the first level (the far end is dropped)
    assert all(isinstance(b, pmd.design.Balance) for b in done)
    # The first point is the force optimum: the same as solving it alone.
    alone = pmd.balance(motion, counterweights=ring, objective={"force": 1.0})
    assert pmd.design.objective_value(done[0], "force") == pytest.approx(
        pmd.design.objective_value(alone, "force"), rel=1e-6, abs=1e-9)


# --- writing designs ----------------------------------------------------------------------


@pytest.fixture(scope="module")
def balanced(motion):
    return pmd.balance(motion, counterweights=[pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 8)])


def test_write_scene_from_an_unknown_source_is_a_scene_error(balanced, tmp_path):
    # Were FileNotFoundError ('nope') and IsADirectoryError (a directory).
    with pytest.raises(SceneError, match="source: expected a bundled scene name or a readable scene file"):
        balanced.write_scene("no_such_scene", tmp_path / "x.toml")
    with pytest.raises(SceneError, match="source:"):
        balanced.write_scene(tmp_path, tmp_path / "x.toml")


def test_write_scene_and_urdf_create_the_directory_or_name_the_path(balanced, tmp_path):
    # A missing directory was FileNotFoundError (write_stl creates it); an unwritable path
    # a builtin OSError.
    path = balanced.write_scene("fourbar", tmp_path / "a" / "b" / "designed.toml")
    again = pmd.load_scene(path)
    assert again.model.body("crank").mass == pytest.approx(balanced.bodies["crank"].mass, rel=1e-12)
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(InvalidInputError, match="path: expected a writable file path"):
        balanced.write_scene("fourbar", blocker / "x.toml")
    urdf = tmp_path / "r.urdf"
    urdf.write_text('<robot name="r"><link name="crank"/></robot>')
    with pytest.raises(InvalidInputError, match="path: expected a writable file path"):
        pmd.design.write_urdf(balanced.bodies, urdf, blocker / "x.urdf")


# --- the design command -------------------------------------------------------------------


@pytest.mark.parametrize(
    "lines, message",
    [
        (['samples = "abc"'], "'samples' in the top level: expected an integer"),
        (["samples = 24.5"], "'samples' in the top level: expected an integer"),
        (['speed = "fast"'], "'speed' in the top level: expected a number"),
        (["samples = 24", "[[counterweight]]", 'body = "crank"', "ring = { radius = 0.02, count = 1000000000 }"],
         r"count: expected an integer number of candidates"),
        (["samples = 24", "[[counterweight]]", 'body = "crank"', "ring = { count = 8 }"],
         r"'radius' in \[\[counterweight\]\] 1 ring: expected a number, got None"),
        (["samples = 24", "[[counterweight]]", 'body = "crank"', "ring = { radius = 0.02 }", "[pareto]",
          'objectives = ["force", "moment"]', 'count = "many"'], r"'count' in \[pareto\]: expected an integer"),
    ],
)
def test_the_design_command_reports_a_malformed_spec_number(tmp_path, capsys, lines, message):
    # 'abc' and a missing radius were tracebacks (ValueError, KeyError), exit status 1; a
    # ring of 10**9 candidates ran out of memory.
    from pointmass_dyn.cli import main

    spec = tmp_path / "spec.toml"
    speed = [] if any(ln.startswith("speed") for ln in lines) else ["speed = 30.0"]
    spec.write_text("\n".join(['driver = "crank"', *speed, *lines]) + "\n")
    assert main(["design", "fourbar", str(spec), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert re.search(message, err), err
