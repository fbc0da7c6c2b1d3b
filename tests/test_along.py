"""Analyses along a result in one call (``_core.scene_along``): the accelerations and effect
forces at every output state, checked sample by sample against the per-state calls
(``Model.forward_dynamics`` of the summed ``effect_forces``), on a mechanism with a loop, a
robot with a PD torque and limits, and a body on ground contact."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn import _core
from pointmass_dyn.errors import InvalidInputError


def per_sample(scene, result):
    """The reference: one ``effect_forces`` and one ``forward_dynamics`` per state."""
    m = scene.model
    forces = [_core.effect_forces(scene, float(t), q, v) for t, q, v in
              zip(result.t, result.q, result.v)]
    a = np.array([m.forward_dynamics(q, v, sum(f.values())) for q, v, f in
                  zip(result.q, result.v, forces)])
    return a, {k: np.array([f[k] for f in forces]) for k in forces[0]}


@pytest.mark.parametrize("name", ["fourbar", "chain7", "box_incline", "slider_crank"])
def test_accelerations_and_forces_along_a_result_are_the_per_state_ones(name):
    scene = pmd.load_scene(name)
    res = pmd.simulate(scene, (0.0, 0.2), t_eval=np.linspace(0.0, 0.2, 41))
    assert res.success, res.message
    a, forces = _core.scene_along(scene, res.t, res.q, res.v, forces=True)
    a_ref, f_ref = per_sample(scene, res)
    scale = max(np.abs(a_ref).max(), 1.0)
    np.testing.assert_allclose(a, a_ref, rtol=0, atol=1e-9 * scale)
    assert forces.keys() == f_ref.keys()
    for k in forces:
        np.testing.assert_allclose(forces[k], f_ref[k], rtol=0,
                                   atol=1e-12 * max(np.abs(f_ref[k]).max(), 1.0), err_msg=k)


def test_shaking_along_a_result_matches_the_states_accelerations():
    """``shaking(scene, result)`` is ``shaking(model, q, v, a)`` with the per-state a."""
    scene = pmd.load_scene("fourbar")
    res = pmd.simulate(scene, (0.0, 0.3), t_eval=np.linspace(0.0, 0.3, 31))
    a_ref, _ = per_sample(scene, res)
    along = pmd.shaking(scene, res)
    ref = pmd.shaking(scene.model, res.q, res.v, a_ref)
    np.testing.assert_allclose(along.force, ref.force, rtol=0,
                               atol=1e-9 * np.abs(ref.force).max())


@pytest.mark.parametrize("name", ["fourbar", "chain7", "rssr", "iftomm_a04_bricard", "slider_crank"])
def test_folded_shaking_is_model_shaking_at_each_state(name):
    """``_core.scene_shaking`` (the shaking folded into the accelerations' pass, from each
    link's summed point masses) equals ``Model.shaking`` (the sum over every point mass)
    called per state at the per-state accelerations, on planar and spatial mechanisms with a
    loop (RSSR: a ball cut joint and a skew axis; Bricard: overconstrained) and on a tree,
    about a point off the origin."""
    scene = pmd.load_scene(name)
    res = pmd.simulate(scene, (0.0, 0.2), t_eval=np.linspace(0.0, 0.2, 41))
    assert res.success, res.message
    about = np.array([0.05, -0.02, 0.1])
    force, moment = _core.scene_shaking(scene, res.t, res.q, res.v, about=about)
    a_ref, _ = per_sample(scene, res)
    a_along, _ = _core.scene_along(scene, res.t, res.q, res.v)
    ref = [scene.model.shaking(q, v, a, about=about) for q, v, a in zip(res.q, res.v, a_along)]
    f_ref, m_ref = np.array([r[0] for r in ref]), np.array([r[1] for r in ref])
    assert force.shape == moment.shape == (len(res.t), 3)
    for got, want in ((force, f_ref), (moment, m_ref)):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(want).max())
    # And at the accelerations of the independent per-state path (forward_dynamics).
    ref = pmd.shaking(scene.model, res.q, res.v, a_ref, about=about)
    np.testing.assert_allclose(force, ref.force, rtol=0, atol=1e-9 * np.abs(ref.force).max())
    s = pmd.shaking(scene, res, about=about)
    np.testing.assert_array_equal(s.force, force)
    np.testing.assert_array_equal(s.moment, moment)


@pytest.mark.parametrize("name", ["fourbar", "rssr"])
def test_folded_shaking_is_the_same_bits_on_any_thread_count(name):
    scene = pmd.load_scene(name)
    res = pmd.simulate(scene, (0.0, 0.5), t_eval=np.linspace(0.0, 0.5, 301))
    serial = _core.scene_shaking(scene, res.t, res.q, res.v, about=[0.1, 0, 0], threads=1)
    ref = [scene.model.shaking(q, v, a, about=[0.1, 0, 0]) for q, v, a in
           zip(res.q, res.v, _core.scene_along(scene, res.t, res.q, res.v, threads=1)[0])]
    np.testing.assert_allclose(serial[1], [r[1] for r in ref], rtol=0,
                               atol=1e-12 * np.abs([r[1] for r in ref]).max())
    for threads in (2, 3, 5, 64):
        f, m = _core.scene_shaking(scene, res.t, res.q, res.v, about=[0.1, 0, 0],
                                   threads=threads)
        np.testing.assert_array_equal(f, serial[0], err_msg=str(threads))
        np.testing.assert_array_equal(m, serial[1], err_msg=str(threads))
    with pytest.raises(InvalidInputError, match="about"):
        _core.scene_shaking(scene, res.t, res.q, res.v, about=[0.0, np.nan, 0.0])


def test_torque_saturation_is_where_the_limited_torque_reaches_its_limit():
    model = pmd.load_scene("chain7").model
    pd = pmd.PDTorque(model.joint_names[0], kp=400.0, kd=5.0, time=[0.0, 1.0], reference=[1.0, 1.0],
                      limit=3.0)
    scene = pmd.Scene(model, np.zeros(model.nq), np.zeros(model.nv),
                      effects=[pmd.Gravity([0, 0, -9.81]), pd])
    res = pmd.simulate(scene, (0.0, 0.5), t_eval=np.linspace(0.0, 0.5, 51))
    sat = pmd.torque_saturation(scene, res)
    _, f_ref = per_sample(scene, res)
    (name,) = sat.keys()
    expected = np.abs(f_ref[name]) >= 3.0 * (1 - 1e-12)
    assert sat[name].shape == (51, model.nv) and np.array_equal(sat[name], expected)
    assert 0 < sat[name][:, 0].sum() < 51  # saturated at first, free later


def test_bad_states_are_named():
    scene = pmd.load_scene("chain7")
    n = 4
    t, q, v = np.zeros(n), np.zeros((n, scene.model.nq)), np.zeros((n, scene.model.nv))
    with pytest.raises(InvalidInputError, match=r"t, q, v: expected shapes \(N,\)"):
        _core.scene_along(scene, t, q[:, :3], v)
    q[2, 1] = np.nan
    with pytest.raises(InvalidInputError, match="sample 2"):
        _core.scene_along(scene, t, q, v)


@pytest.mark.parametrize("name", ["fourbar", "box_incline", "chain7"])
def test_threads_over_samples_give_the_serial_bits(name):
    """Chunks of samples on threads, each with its own workspaces: the same bits as one
    thread, whatever the count (and at uneven chunk sizes), and the per-state reference."""
    scene = pmd.load_scene(name)
    t = np.linspace(0.0, 0.3, 401)
    res = pmd.simulate(scene, (0.0, 0.3), t_eval=t)
    assert res.success, res.message
    serial = _core.scene_along(scene, res.t, res.q, res.v, forces=True, threads=1)
    for threads in (2, 3, 7):
        a, forces = _core.scene_along(scene, res.t, res.q, res.v, forces=True, threads=threads)
        assert np.array_equal(a, serial[0]), threads
        assert forces.keys() == serial[1].keys()
        assert all(np.array_equal(forces[k], serial[1][k]) for k in forces), threads
    a_ref, _ = per_sample(scene, res)
    np.testing.assert_allclose(serial[0], a_ref, rtol=0, atol=1e-9 * max(np.abs(a_ref).max(), 1.0))


def test_a_failing_sample_is_named_as_on_one_thread():
    """The first failing sample is reported, whichever chunk its thread ran."""
    scene = pmd.load_scene("chain7")
    res = pmd.simulate(scene, (0.0, 0.3), t_eval=np.linspace(0.0, 0.3, 400))
    v = np.array(res.v)
    v[350] = v[390] = 1e200  # finite, but its squares are not
    msgs = []
    for threads in (1, 4):
        with pytest.raises(pmd.errors.PointMassDynError) as e:
            _core.scene_along(scene, res.t, res.q, v, threads=threads)
        msgs.append(str(e.value))
    assert "sample 350" in msgs[0] and "not finite" in msgs[0] and msgs[0] == msgs[1]
    with pytest.raises(InvalidInputError, match="threads"):
        _core.scene_along(scene, res.t, res.q, res.v, threads=0)
