"""The fast paths of a ``simulate`` call against the general ones they skip: a result built
field by field as the dataclass's ``__init__`` builds it, and tolerances and ``t_eval``
read directly (a float, an int, a float64 vector) as NumPy's ``asarray`` reads them."""

from __future__ import annotations

import dataclasses

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn import _core
from pointmass_dyn._simulation import SimulationResult, result_from_run
from pointmass_dyn.errors import InvalidInputError


def _same(a, b):
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(a, b)
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    # Objects without value equality (a `RunStatus`): by their repr.
    return a == b or repr(a) == repr(b)


@pytest.mark.parametrize(
    "kwargs",
    [{}, {"energy": True, "power": True, "t_eval": np.linspace(0, 0.1, 5)}],
)
def test_result_from_run_sets_every_field_as_init_does(kwargs):
    scene = pmd.load_scene("chain7")
    settings = {k: v for k, v in kwargs.items() if k != "t_eval"}
    run = _core.simulate_scene(scene, (0.0, 0.1), t_eval=kwargs.get("t_eval"), **settings)
    model = scene.model
    fast = result_from_run(run, scene.name, model)
    names = [f.name for f in dataclasses.fields(SimulationResult)]
    plain = SimulationResult(
        scene=scene.name,
        model=model,
        **{n: getattr(run, n) for n in names if hasattr(_core.RunResult, n)},
    )
    assert type(fast) is SimulationResult
    assert list(vars(fast)) == list(vars(plain)) == names
    for n in names:
        assert _same(getattr(fast, n), getattr(plain, n)), n
    # Each result its own `extras`.
    assert fast.extras == {} and fast.extras is not result_from_run(run).extras


def test_tolerances_and_t_eval_in_any_real_form_run_alike():
    scene = pmd.load_scene("chain7")
    te = np.linspace(0.0, 0.2, 7)

    def run(rtol, atol, t_eval):
        r = pmd.simulate(scene, (0.0, 0.2), rtol=rtol, atol=atol, t_eval=t_eval)
        return r.t, r.q, r.v, r.nfev

    # The general path: 0-d arrays and a strided (not contiguous) vector go through NumPy.
    ref = run(np.asarray(1e-5), np.asarray(0), np.repeat(te, 2)[::2])
    forms = [
        (1e-5, 0, te),
        (np.float64(1e-5), 0.0, tuple(te)),
        (np.array([1e-5] * 14), np.zeros(14, dtype=np.int64), np.asfortranarray(te)),
        (1e-5, np.int32(0), list(te)),
    ]
    for rtol, atol, t_eval in forms:
        got = run(rtol, atol, t_eval)
        assert all(_same(a, b) for a, b in zip(got, ref)), (rtol, atol)
    # An int the double range holds exactly, and one NumPy reads as uint64 (no fast path).
    assert _same(run(1e-5, 2**53, te), run(1e-5, float(2**53), te))
    assert _same(run(1e-5, 2**63, te), run(1e-5, float(2**63), te))


@pytest.mark.parametrize("bad", [True, np.bool_(True), "1e-3", 1 + 0j, [[1e-3]], 10**400])
def test_tolerances_not_real_numbers_are_refused(bad):
    scene = pmd.load_scene("chain7")
    with pytest.raises(InvalidInputError, match="rtol"):
        pmd.simulate(scene, (0.0, 0.01), rtol=bad)
