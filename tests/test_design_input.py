"""The design API under bad input: link shapes, counterweights, ``balance``, ``pareto_front``,
``analyze_motion``, ``prescribed_motion``, scene and URDF writing and the ``design`` command
refuse what they cannot use with a ``pmd.errors`` exception (``TypeError`` for a wrong Python
type) naming the argument, the form expected and what was given — before any work."""

from __future__ import annotations

import math
import re
import warnings

import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import G
from pointmass_dyn.errors import (
    InvalidInputError,
    SceneError,
)


@pytest.fixture(scope="module")
def fourbar_motion():
    scene = pmd.load_scene("fourbar")
    motion = pmd.prescribed_motion(
        scene.model, "crank", speed=2 * np.pi, samples=36, q_guess=scene.q0, gravity=G
    )
    return scene, motion


G_PLANE = np.array([0.0, -9.81, 0.0])


@pytest.fixture(scope="module")
def fourbar():
    return pmd.load_scene("fourbar")


@pytest.fixture(scope="module")
def motion(fourbar):
    return pmd.prescribed_motion(fourbar.model, "crank", speed=30.0, samples=24,
                                 q_guess=fourbar.q0, gravity=G_PLANE)


BOX = ([-0.05, -0.02, -0.004], [0.045, 0.02, 0.004])


@pytest.fixture(scope="module")
def fourbar_model():
    return pmd.load_scene("fourbar").model


@pytest.fixture(scope="module")
def balanced(motion):
    return pmd.balance(motion, counterweights=[pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 8)])


def test_analyze_motion_refuses_arrays_of_other_lengths(fourbar_motion):
    scene, mo = fourbar_motion
    with pytest.raises(InvalidInputError, match=r"q: expected shape \(36, 3\).*\(35, 3\)"):
        pmd.analyze_motion(scene.model, mo.t, mo.q[:-1], mo.v, mo.a, actuated=["crank"])
    with pytest.raises(InvalidInputError, match=r"a: expected shape"):
        pmd.analyze_motion(scene.model, mo.t, mo.q, mo.v, mo.a[:, :2], actuated=["crank"])
    with pytest.raises(InvalidInputError, match="t: expected"):
        pmd.analyze_motion(scene.model, [], mo.q[:0], mo.v[:0], mo.a[:0], actuated=["crank"])


def test_prescribed_motion_refuses_empty_motions(fourbar_motion):
    scene, _ = fourbar_motion
    for revolutions in (0, -1, np.nan):
        with pytest.raises(InvalidInputError, match="revolutions"):
            pmd.prescribed_motion(scene.model, "crank", speed=1.0, revolutions=revolutions,
                                  q_guess=scene.q0)
    with pytest.raises(InvalidInputError, match="input"):
        pmd.prescribed_motion(scene.model, "crank", input=([], [], [], []), q_guess=scene.q0)
    with pytest.raises(InvalidInputError, match="input: expected finite"):
        pmd.prescribed_motion(scene.model, "crank", input=([0, 1], [0, np.nan], [1, 1], [0, 0]),
                              q_guess=scene.q0)


def test_prescribed_motion_refuses_a_driver_of_another_type(fourbar_motion):
    scene, mo = fourbar_motion
    for driver in (np.inf, b"", 1.5, True):
        with pytest.raises(InvalidInputError, match="driver: expected a body name or an int"):
            pmd.prescribed_motion(scene.model, driver, speed=1.0, q_guess=scene.q0)
    with pytest.raises(InvalidInputError, match="actuated: expected"):
        pmd.analyze_motion(scene.model, mo.t, mo.q, mo.v, mo.a, actuated=[0.5])


def test_balance_refuses_weights_and_counts_that_mean_nothing(fourbar_motion):
    _, mo = fourbar_motion
    cw = [pmd.Counterweight.ring("crank", [0, 0, 0], 0.05, count=8)]
    for objective in ({"force": np.nan}, {"force": -1.0}, {"force": 0.0}, {"force": True}):
        with pytest.raises(InvalidInputError, match="objective"):
            pmd.balance(mo, counterweights=cw, objective=objective)
    # (`regularization` is gone with the conic solver: the least design mass decides ties.)
    for kwargs in ({"count": -1}, {"count": 1}, {"objectives": ("force", "moment", "torque")},
                   {"objectives": ("force", "force")}):
        with pytest.raises(InvalidInputError, match="count|objectives"):
            pmd.pareto_front(mo, counterweights=cw, **kwargs)


def test_balance_flags_and_factors_are_checked_always(motion):
    ring = [pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 8)]
    with pytest.raises(InvalidInputError, match="least_mass: expected True or False, got 'yes'"):
        pmd.balance(motion, counterweights=ring, least_mass="yes")
    for bad in ((np.nan, 1.0), (2.0, 1.0), (1.0,), "ab"):
        with pytest.raises(InvalidInputError, match="link_mass: expected factors"):
            pmd.balance(motion, counterweights=ring, link_mass=bad)


@pytest.mark.filterwarnings("error::numpy.exceptions.ComplexWarning")
def test_counterweight_ring_checks_its_centre_radius_and_normal():
    # A string centre was a builtin ValueError, a complex one lost its imaginary part, a
    # radius of NaN gave NaN candidates, a normal of 1e300 overflowed its norm.
    ring = pmd.Counterweight.ring
    for center in ("", [0, 0], [0, 0, np.nan], [0j, 1j, 0]):
        with pytest.raises(InvalidInputError, match="center: expected a finite"):
            ring("crank", center, 0.02, 4)
    for radius in (np.nan, -0.01, 0.0, "0.02", np.inf):
        with pytest.raises(InvalidInputError, match="radius: expected a finite number > 0"):
            ring("crank", [0, 0, 0], radius, 4)
    for normal in ("", [1j, 0, 1], [0, 0, 0]):
        with pytest.raises(InvalidInputError, match="normal: expected a finite non-zero"):
            ring("crank", [0, 0, 0], 0.02, 4, normal=normal)
    big = ring("crank", [0, 0, 0], 0.02, 4, normal=[0, 0, 1e300])
    flat = ring("crank", [0, 0, 0], 0.02, 4, normal=[0, 0, 1])
    np.testing.assert_allclose(big.points, flat.points, rtol=0, atol=1e-15)


def test_balance_objective_and_limits_must_be_dicts(motion):
    ring = [pmd.Counterweight.ring("crank", [0, 0, 0], 0.02, 8)]
    # dict("0.3") was a builtin ValueError.
    for arg in ("objective", "limits"):
        with pytest.raises(InvalidInputError, match=f"{arg}: expected None or a dict"):
            pmd.balance(motion, counterweights=ring, **{arg: "0.3"})


def test_link_shape_envelopes_of_strings_are_refused(fourbar):
    # np.asarray("", float): a builtin ValueError from LinkShape.cells.
    with pytest.raises(InvalidInputError, match=r"box: expected \(lower, upper\) corners"):
        pmd.LinkShape("crank", box="", cell=0.01).cells(fourbar.model)
    with pytest.raises(InvalidInputError, match="polygon: expected"):
        pmd.LinkShape("crank", polygon="ab", z=(0, 1), cell=0.01).cells(fourbar.model)


def test_analyze_motion_refuses_arrays_it_cannot_read(fourbar):
    # Found by tests/test_fuzz_api.py: t = "" was NumPy's builtin ValueError.
    m, z = fourbar.model, np.zeros((1, fourbar.model.nv))
    for name, args in (("t", ("", z, z, z)), ("q", ([0.0], "ab", z, z)),
                       ("a", ([0.0], z, z, [["x", 1.0, 2.0]]))):
        with pytest.raises(InvalidInputError, match=f"{name}: expected an array of real numbers"):
            pmd.analyze_motion(m, *args, actuated=["crank"])


def test_a_link_shape_body_of_the_wrong_type_names_the_argument(fourbar_model):
    with pytest.raises(TypeError, match="body"):
        pmd.LinkShape(1.5, box=BOX, cell=0.004).cells(fourbar_model)


@pytest.mark.parametrize("boss", [math.nan, -1.0, math.inf, "x", True])
def test_link_shape_boss_must_be_a_finite_radius(fourbar_model, boss):
    # NaN kept no pin (every comparison false), -1 none, inf every cell: all silently.
    with pytest.raises(InvalidInputError, match="boss: expected None or a finite radius"):
        pmd.LinkShape("crank", box=BOX, cell=0.004, boss=boss).cells(fourbar_model)


@pytest.mark.parametrize("arg", ["cell", "density"])
def test_link_shape_refuses_a_bool_cell_or_density(fourbar_model, arg):
    # cell=True was taken as a 1 m cell.
    with pytest.raises(InvalidInputError, match=f"{arg}: expected a positive number, got True"):
        pmd.LinkShape("crank", box=BOX, **{"cell": 0.004, arg: True}).cells(fourbar_model)


def test_an_stl_envelope_that_cannot_be_read_is_our_error(tmp_path, fourbar_model):
    # A missing file was FileNotFoundError; a truncated ASCII vertex an IndexError; a word
    # where a number goes a ValueError.
    with pytest.raises(InvalidInputError, match="stl: expected a readable STL file"):
        pmd.LinkShape("crank", stl=tmp_path / "missing.stl").cells(fourbar_model)
    for body in ("solid x\nvertex 1 2\n", "solid x\nvertex 1 2 abc\n"):
        bad = tmp_path / "bad.stl"
        bad.write_text(body)
        with pytest.raises(InvalidInputError, match="stl: expected 'vertex x y z'"):
            pmd.LinkShape("crank", stl=bad).cells(fourbar_model)


@pytest.mark.parametrize("mass", ["ab", (1.0,), (1.0, 2.0, 3.0), 5.0])
def test_link_shape_mass_that_is_not_a_pair_is_refused(motion, mass):
    # Were builtin ValueErrors ("could not convert string to float", "not enough values").
    shape = pmd.LinkShape("crank", box=BOX, cell=0.004, mass=mass)
    with pytest.raises(InvalidInputError, match=r"mass: expected None or \(low, high\)"):
        pmd.balance(motion, links=[shape], zero=("force",))


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
