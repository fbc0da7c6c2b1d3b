"""What a new user meets first (issue 26): bodies' parents by name, short reprs of results,
scene errors that name a field once, and the cost of the first import and the first call —
the causes, checked without timing anything (the timings are in benches/first_call.py)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn.errors import ModelStructureError, SceneError


def bar(length=0.3):
    i = length**2 / 12 + 1e-4
    return pmd.RigidBody(1.0, [length / 2, 0, 0], np.diag([1e-4, i, i]))


def parents(model):
    return [model.body_info(k)[2] for k in range(model.nbodies)]


def chain_by(parents):
    m = pmd.Model()
    for k, parent in enumerate(parents):
        m.add_body(bar(), pmd.Revolute([0, 0, 1]), parent=parent, translation=[0.3, 0, 0],
                   name=f"b{k}")
    return m


def test_parent_by_name_is_parent_by_index():
    by_name = chain_by(["world", "b0", "b1", "b0"])
    by_index = chain_by([-1, 0, 1, 0])
    assert parents(by_name) == parents(by_index) == [-1, 0, 1, 0]
    q = np.array([0.3, -0.2, 0.7, 1.1])
    np.testing.assert_array_equal(by_name.mass_matrix(q), by_index.mass_matrix(q))
    assert parents(chain_by([None, "b0"])) == [-1, 0]


def test_unknown_parent_name_lists_the_names():
    m = chain_by(["world", "b0"])
    with pytest.raises(ModelStructureError,
                       match=r"parent: no body named 'crank': expected one of 'b0', 'b1', 'world'"):
        m.add_body(bar(), pmd.Revolute([0, 0, 1]), parent="crank")
    assert m.nbodies == 2  # nothing added
    with pytest.raises(TypeError):
        m.add_body(bar(), pmd.Revolute([0, 0, 1]), parent=1.5)


def test_add_body_docstring_says_what_each_argument_is():
    doc = pmd.Model.add_body.__doc__
    for arg in ("parent", "translation", "rotation", "name", "point_mass_center"):
        assert arg in doc, arg
    assert "name or index" in doc


def test_reprs_are_short_summaries():
    scene = pmd.load_scene("chain7")
    r = pmd.simulate(scene, (0, 2), t_eval=np.linspace(0, 2, 20001), energy=True)
    text = repr(r)
    assert len(text) < 400, text
    assert text.startswith("SimulationResult(scene='chain7', method='RK45', success=True")
    assert "(20001 points)" in text and "q: (20001, 7)" in text and f"nfev={r.nfev}" in text
    assert str(r.q[5, 0]) not in text


def test_animation_info_repr_is_short(tmp_path):
    scene = pmd.load_scene("pendulum_spatial")
    r = pmd.simulate(scene, (0, 1))
    info = pmd.animate(r, scene, tmp_path / "a.html", frames=500)
    text = repr(info)
    assert len(text) < 200, text
    assert "frames=500" in text and "a.html" in text and "times=[0, 1] s" in text


def test_scene_error_names_the_field_once(tmp_path):
    text = pmd.builtin_scenes()["pendulum_planar"].read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("mass = 2.51", "mass = -2.51", 1))
    with pytest.raises(SceneError) as e:
        pmd.load_scene(bad)
    message = str(e.value)
    assert ".mass: " in message and "mass: mass" not in message, message


def run(code):
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    return out.stdout.split()


def test_import_does_not_load_xml_email_http():
    # xml.sax.saxutils (used only to write MJCF) pulled in urllib.request, http and email:
    # ~20 % of the import time.
    loaded = run("import sys, pointmass_dyn; print(*sorted(sys.modules))")
    for mod in ("xml.sax", "email", "http", "http.client"):
        assert mod not in loaded, mod


def test_first_simulate_does_not_import_numpy_ma():
    # The masked-array check imported numpy.ma on the first call (~8 ms, 15x a chain7 run):
    # no masked array can exist before numpy.ma is imported.
    loaded = run(
        "import sys, pointmass_dyn as pmd; "
        "pmd.simulate(pmd.load_scene('chain7'), (0, 0.5)); print(*sorted(sys.modules))"
    )
    assert "numpy.ma" not in loaded


def test_masked_arrays_are_still_refused():
    m = chain_by(["world"])
    with pytest.raises(pmd.InvalidInputError, match="masked"):
        m.mass_matrix(np.ma.masked_array([0.1], mask=[True]))


def test_the_package_under_test_is_the_one_asked_for():
    # CI runs the suite against the installed wheel (POINTMASS_DYN_TEST_INSTALLED=1) and in
    # the portable build (POINTMASS_DYN_BASELINE=1): make sure that is what was imported.
    import os
    from pathlib import Path

    where = Path(pmd.__file__).resolve()
    if os.environ.get("POINTMASS_DYN_TEST_INSTALLED"):
        source = Path(__file__).resolve().parents[1] / "python"
        assert source not in where.parents, where
        assert "site-packages" in where.parts, where
    expected = "baseline" if os.environ.get("POINTMASS_DYN_BASELINE") else None
    assert pmd._core.cpu_dispatch in ("avx512", "avx2", "baseline")
    if expected:
        assert pmd._core.cpu_dispatch == expected


def test_a_lone_effect_is_refused_as_effects_naming_the_argument():
    # Issue 38's walk: Scene(model, effects=pmd.Gravity()) said "'Effect' object is not
    # iterable" (a TypeError naming nothing).
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0.2, 0, 0], np.diag([1e-3, 1e-2, 1e-2])),
               pmd.Revolute([0, 1, 0]), name="arm")
    with pytest.raises(pmd.errors.InvalidInputError,
                       match=r"effects: expected a list of effects.*got Gravity\("):
        pmd.Scene(m, effects=pmd.Gravity())


def test_animate_with_the_scene_first_says_the_order(tmp_path):
    # Issue 38's walk: animate(scene, result, path), in simulate's order, said only
    # "expected a Model or a Scene, got SimulationResult".
    sc = pmd.load_scene("pendulum_planar")
    res = pmd.simulate(sc, (0, 0.1))
    with pytest.raises(pmd.errors.InvalidInputError, match=r"the result first"):
        pmd.animate(sc, res, tmp_path / "x.html")
