"""`Scene(...)` and `scene.replace(...)` read their `effects` the same way: a list of effects,
a lone effect or a non-effect item refused naming the argument (and the item's index)."""
import numpy as np
import pointmass_dyn as pmd
import pytest


@pytest.fixture
def scene():
    m = pmd.Model()
    m.add_body(pmd.RigidBody(1.0, [0.2, 0, 0], np.diag([1e-3, 1e-2, 1e-2])),
               pmd.Revolute([0, 1, 0]), name="arm")
    return pmd.Scene(m, effects=[pmd.Gravity()])


@pytest.mark.parametrize("call", ["new", "replace"])
def test_a_lone_effect_and_a_bad_item_are_refused_naming_them(scene, call):
    make = (lambda e: pmd.Scene(scene.model, effects=e)) if call == "new" else \
        (lambda e: scene.replace(effects=e))
    with pytest.raises(pmd.errors.InvalidInputError,
                       match=r"effects: expected a list of effects.*got Gravity\("):
        make(pmd.Gravity())
    with pytest.raises(pmd.errors.InvalidInputError,
                       match=r"effects\[1\]: expected an effect.*got 'gravity'"):
        make([pmd.Gravity(), "gravity"])


def test_replace_keeps_what_is_not_given_and_takes_a_tuple_of_effects(scene):
    damped = scene.replace(effects=(pmd.Gravity([0, 0, -1.0]), pmd.Damper(None, 0.5)),
                           rtol=1e-4)
    assert [e.kind for e in damped.effects] == ["gravity", "dampers"]
    np.testing.assert_array_equal(damped.effects[0].g, [0, 0, -1.0])
    assert damped.rtol == 1e-4 and damped.name == scene.name
    assert scene.replace().effects == scene.effects and scene.replace().rtol is None
