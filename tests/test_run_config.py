"""``pmd.RunConfig``: one run's settings, layered as the call's keywords over the config over
the scene's ``[simulate]`` table over the defaults (docs/architecture.md)."""

import inspect
import pickle

import numpy as np
import pointmass_dyn as pmd
import pytest


def pendulum(**settings):
    model = pmd.Model()
    model.add_body(pmd.RigidBody(1.0, [0.5, 0, 0], np.diag([1e-3, 2e-2, 2e-2])),
                   pmd.Revolute([0, 1, 0]), name="link")
    return pmd.Scene(model, [0.3], [0.0], effects=[pmd.Gravity()], **settings)


def same_run(a, b):
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.q, b.q)
    assert (a.method, a.nfev) == (b.method, b.nfev)


def test_a_config_runs_as_its_keywords_do():
    scene = pendulum()
    config = pmd.RunConfig((0.0, 1.0), rtol=1e-8, atol=1e-10, method="DOP853", energy=True)
    by_config = pmd.simulate(scene, config=config)
    by_keywords = pmd.simulate(scene, (0.0, 1.0), rtol=1e-8, atol=1e-10, method="DOP853",
                               energy=True)
    same_run(by_config, by_keywords)
    assert by_config.energy is not None
    # Energy is conserved to the tolerance asked (an independent check the settings took).
    assert np.ptp(by_config.energy) < 1e-6


def test_keywords_beat_the_config_which_beats_the_scene_which_beats_the_default():
    scene = pendulum(t_span=(0.0, 2.0), rtol=1e-9, method="DOP853")
    # The scene's settings alone.
    r = pmd.simulate(scene)
    assert r.method == "DOP853" and r.t[-1] == 2.0
    # The config beats the scene where it says something, the scene fills the rest.
    config = pmd.RunConfig(rtol=1e-4, method="RK45")
    r = pmd.simulate(scene, config=config)
    same_run(r, pmd.simulate(scene, rtol=1e-4, method="RK45"))
    assert r.t[-1] == 2.0
    # A keyword beats the config.
    r = pmd.simulate(scene, (0.0, 0.5), config=config, method="Radau")
    assert r.method == "Radau" and r.t[-1] == 0.5
    # Nothing said anywhere: the default method and tolerances.
    bare = pendulum()
    same_run(pmd.simulate(bare, (0.0, 1.0), config=pmd.RunConfig()),
             pmd.simulate(bare, (0.0, 1.0), rtol=1e-3, atol=1e-6, method="RK45"))


def test_batch_and_solve_ivp_take_a_config():
    scene = pendulum()
    config = pmd.RunConfig((0.0, 1.0), rtol=1e-7, t_eval=np.linspace(0, 1, 11))
    batch = pmd.simulate_batch(scene, q0=[[0.1], [0.2]], config=config)
    assert batch.q.shape == (2, 11, 1)
    single = pmd.simulate(scene.replace(q0=[0.2]), config=config)
    np.testing.assert_array_equal(batch.q[1], single.q)
    # solve_ivp's own keywords beat a config's: y' = -y, y(1) = e^-1.
    r = pmd.solve_ivp(lambda t, y: -y, (0.0, 1.0), [1.0], rtol=1e-10, atol=1e-12)
    assert abs(r.y[0, -1] - np.exp(-1.0)) < 1e-9


def test_getters_replace_equality_and_pickle():
    c = pmd.RunConfig((0, 1), rtol=[1e-6, 1e-7], method="dop853", disable="gravity",
                      max_step=np.inf, controller="scipy")
    assert c.t_span == (0.0, 1.0) and c.method == "DOP853" and c.disable == ("gravity",)
    np.testing.assert_array_equal(c.rtol, [1e-6, 1e-7])
    assert c.max_step is None  # inf: no limit, as if not given
    assert c.controller == "standard" and c.atol is None and c.energy is None
    d = c.replace(rtol=1e-5, method=None)
    assert d.rtol == 1e-5 and d.method is None and d.disable == ("gravity",)
    assert c.method == "DOP853"  # unchanged
    assert pickle.loads(pickle.dumps(d)) == d and d != c
    assert pmd.RunConfig(**d.as_dict()) == d
    assert repr(pmd.RunConfig(rtol=1e-6)) == "RunConfig(rtol=1e-06)"


def test_bad_settings_name_their_argument():
    with pytest.raises(pmd.InvalidInputError, match="method"):
        pmd.RunConfig(method="RK23")
    with pytest.raises(pmd.InvalidInputError, match="t_span"):
        pmd.RunConfig((1.0, 1.0))
    with pytest.raises(pmd.InvalidInputError, match="rtl"):
        pmd.RunConfig().replace(rtl=1e-3)
    # A per-component tolerance must have one value per state component (nq + nv = 2).
    with pytest.raises(pmd.InvalidInputError, match=r"atol: expected a number or shape \(2,\)"):
        pmd.simulate(pendulum(), (0.0, 1.0), config=pmd.RunConfig(atol=[1e-6] * 3))
    with pytest.raises(pmd.InvalidInputError, match="t_span"):
        pmd.simulate(pendulum(), config=pmd.RunConfig(rtol=1e-6))


@pytest.mark.parametrize("key, bad", [
    ("rtol", "tight"), ("max_step", "big"), ("method", "RK99"), ("t_span", (1.0, 1.0)),
    ("disable", ["gravity", "wind"]), ("dt", "small"),
])
def test_a_scene_and_a_config_read_a_setting_alike(key, bad):
    # One parser for the run settings: a scene refuses what RunConfig refuses, in its words.
    with pytest.raises(pmd.InvalidInputError) as config:
        pmd.RunConfig(**{key: bad})
    with pytest.raises(pmd.InvalidInputError) as scene:
        pendulum(**{key: bad})
    assert str(scene.value) == str(config.value) and str(config.value).startswith(key)
    with pytest.raises(pmd.InvalidInputError) as replaced:
        pendulum().replace(**{key: bad})
    assert str(replaced.value) == str(config.value)


def test_a_scene_takes_the_settings_its_signature_names_and_no_other():
    # The keywords a Scene documents (its signature) against those the parser takes: each
    # run setting outside them (t_eval, energy, ..., a typo) is refused as an unexpected
    # keyword is, a TypeError naming it, even when None; each inside is held.
    documented = set(inspect.signature(pmd.Scene).parameters)
    settings = set(pmd.RunConfig((0.0, 1.0), rtol=1e-6, t_eval=[0.5], energy=True,
                                 controller="pi", stiffness="off", power=True,
                                 dense_output=True, first_step=1e-3).as_dict())
    for key in sorted(settings - documented) + ["rtl"]:
        for value in (None, 1.0):
            with pytest.raises(TypeError, match=f"^{key}: expected a keyword of Scene"):
                pendulum().replace(**{key: value})
    assert pendulum(max_steps=7).replace(first_step=1e-3).max_steps == 7
    assert pendulum().replace(first_step=1e-3, dt=0.01).first_step == 1e-3


def test_a_scene_holds_one_tolerance_for_every_component():
    # A run config may hold one per state component; a scene (as its file) one number.
    assert pmd.RunConfig(rtol=[1e-6, 1e-7]).rtol.shape == (2,)
    with pytest.raises(pmd.InvalidInputError, match=r"^rtol: expected a number .*got 2 values"):
        pendulum(rtol=[1e-6, 1e-7])
    assert pendulum(rtol=1e-7, max_step=np.inf).rtol == 1e-7
    assert pendulum(max_step=np.inf).max_step is None


def test_a_value_of_the_wrong_type_is_our_error_and_a_type_error():
    # A float step count, an int method name, a number for a flag: refused naming the
    # argument, as ours (InvalidInputError) and as Python's TypeError alike.
    for key, bad in [("max_steps", 2.5), ("method", 5), ("energy", 3), ("controller", 1.0)]:
        with pytest.raises(pmd.errors.ArgumentTypeError, match=f"^{key}: expected") as e:
            pmd.RunConfig(**{key: bad})
        assert isinstance(e.value, pmd.InvalidInputError) and isinstance(e.value, TypeError)
    with pytest.raises(pmd.InvalidInputError, match="rtl"):
        pmd.RunConfig(rtl=1e-3)


def test_simulation_results_compare_by_identity():
    scene = pendulum()
    a, b = pmd.simulate(scene, (0.0, 0.1)), pmd.simulate(scene, (0.0, 0.1))
    assert a == a and a != b and len({a, a, b}) == 2  # no ValueError from the arrays
    np.testing.assert_array_equal(a.q, b.q)
