"""Pareto fronts hold no dominated or repeated point (issue 39): the fronts of docs/design.md
§5, each point's figures recomputed here from its design's analysis along the motion."""

import numpy as np
import pointmass_dyn as pmd
import pytest
from test_design_connected import box_components

# No design here may fall back from the least-mass stage or miss the realised 1 %
# (both are a RuntimeWarning "balance: …"; issue 39).
pytestmark = pytest.mark.filterwarnings("error:balance:RuntimeWarning")

REL = 1e-6  # of each objective's unbalanced value: far above solver and re-analysis error


@pytest.fixture(scope="module")
def doc_problem():
    # docs/design.md §5: the four-bar's crank and rocker as steel plates, connected (the
    # default), on the fronts' coarser grid of 8 mm cells.
    scene = pmd.load_scene("fourbar")
    motion = pmd.prescribed_motion(scene.model, "crank", speed=30.0, samples=120,
                                   q_guess=scene.q0, gravity=np.array([0.0, -9.81, 0.0]))
    plates = [
        pmd.LinkShape("crank", box=([-0.05, -0.02, -0.004], [0.045, 0.02, 0.004]), cell=0.008),
        pmd.LinkShape("rocker", box=([-0.05, -0.02, -0.004], [0.08, 0.02, 0.004]), cell=0.008),
    ]
    return motion, plates


def peak_bearing(analysis):
    f = np.concatenate([analysis.bearing[:, :, :3], analysis.cut[:, :, :3]], axis=1)
    return np.linalg.norm(f, axis=2).max()


def figures(b):
    """(peak bearing, peak shaking force) of the designed model along the motion."""
    return np.array([peak_bearing(b.after), b.after.summary()["shaking force"]["peak"]])


def beats(a, b, tol):
    """a dominates b, or repeats it (both figures within tol)."""
    return bool(np.all(a <= b + tol) and (np.any(a < b - tol) or np.all(np.abs(a - b) <= tol)))


@pytest.mark.parametrize("method", ["weighted", "epsilon"])
def test_doc_fronts_hold_no_dominated_point(doc_problem, method):
    motion, plates = doc_problem
    front = pmd.pareto_front(motion, ("bearing", "force"), count=5, links=plates, norm="peak",
                             method=method)
    tol = REL * np.array([peak_bearing(motion), motion.summary()["shaking force"]["peak"]])
    v = np.array([figures(b) for b in front])
    for i in range(len(v)):
        for j in range(len(v)):
            assert i == j or not beats(v[j], v[i], tol), (method, i, j, v)
    # What was left out is beaten by a point kept (the filter drops nothing it need not).
    dropped = getattr(front, "dropped", [])
    assert len(front) + len(dropped) == 5
    for b in dropped:
        assert any(beats(a, figures(b), tol) for a in v)
    # The figures reported are the re-analysed ones, which the solver's prediction matches.
    for b, row in zip(front, v):
        got = b.solver["analysed"]
        np.testing.assert_allclose([got["bearing"], got["force"]], row, rtol=1e-12, atol=1e-12 * tol.max())
        np.testing.assert_allclose([b.solver["values"]["bearing"], b.solver["values"]["force"]], row,
                                   rtol=0, atol=tol.max())
    np.testing.assert_allclose(front.values, v, rtol=1e-12, atol=1e-12 * tol.max())
    # Every point keeps its solve's certificate: solved (Clarabel's AlmostSolved: feasibility
    # to its reduced tolerance), relative duality gap within tolerance (asked: 1e-10).
    for b in [*front, *dropped]:
        stages = b.solver["stages"]
        # The least-mass stage only refines: where it fails, the optimum stands alone.
        assert [s["stage"] for s in stages] in (["optimum"], ["optimum", "least mass"])
        assert (stages[-1]["status"], stages[-1]["gap_rel"]) == (b.solver["status"], b.solver["gap_rel"])
        for s in stages:
            assert s["status"] in ("Solved", "AlmostSolved"), s
            assert 0 <= s["gap_rel"] <= 1e-8, s
    # Every point is a connected design: each written part one solid (a flood fill over its
    # written boxes' faces, test_design_connected's), the links' connectivity asked.
    assert all(p.connected for p in plates)
    for b in front:
        for name in ("crank", "rocker"):
            assert box_components(b.realised[name].boxes) == 1, (method, name)
    # Along the front one objective falls as the other rises.
    order = np.argsort(v[:, 0])
    assert np.all(np.diff(v[order, 1]) < 0)
