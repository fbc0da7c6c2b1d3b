"""The banded loop solver's own order of the coordinates (issue 38, item 8): any numbering of
the IFToMM N-four-bar gets the band of the interleaved one (checked on the returned order
against the mechanism's structure: each loop's three joints adjacent), and runs the same
motion: the exact one-degree-of-freedom reduction (tests/test_iftomm.py). The speed itself is
benches/iftomm.py --shuffled's."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from scipy.integrate import solve_ivp

G = 9.81
Z = [0.0, 0.0, 1.0]
N = 12  # 25 speeds: the banded QRs (>= 24)


def rod():
    i = 1.0 / 12
    return pmd.RigidBody(1.0, [0.5, 0, 0], np.diag([1e-8, i, i]))


def n_fourbar(n, bodies, loops):
    """The N-four-bar with its bodies added in ``bodies``' order (names "v<k>", "h<k>"; each
    h_k after its v_k) and its loops in ``loops``' order. One revolute per body: body i has
    coordinate i."""
    m = pmd.Model()
    for name in bodies:
        k = int(name[1:])
        if name[0] == "v":
            m.add_body(rod(), pmd.Revolute(Z), translation=[k, 0, 0], name=name)
        else:
            m.add_body(rod(), pmd.Revolute(Z), parent=f"v{k}", translation=[1, 0, 0], name=name)
    for k in loops:
        m.add_loop(f"h{k}", f"v{k + 1}", pmd.Revolute(Z), translation_a=[1, 0, 0],
                   translation_b=[1, 0, 0])
    return m


def interleaved(n):
    return [b for k in range(n + 1) for b in (f"v{k}", f"h{k}")][:-1]


def rods_first(n):
    return [f"v{k}" for k in range(n + 1)] + [f"h{k}" for k in range(n)]


def shuffled(n, seed):
    """A random order with every h_k after its v_k, and a random order of the loops."""
    rng = np.random.default_rng(seed)
    ready, out = [f"v{k}" for k in range(n + 1)], []
    while ready:
        name = ready.pop(rng.integers(len(ready)))
        out.append(name)
        if name[0] == "v" and int(name[1:]) < n:
            ready.append(f"h{name[1:]}")
    return out, list(rng.permutation(n))


NUMBERINGS = {"rods_first": (rods_first(N), list(range(N)))} | {
    f"shuffled{s}": shuffled(N, s) for s in range(3)
}


def loop_span(order, bodies, n):
    """The widest span of positions, in the solver's order, of a loop's three joints (v_k,
    h_k, v_(k+1): the coordinates its rows touch)."""
    position = {v: i for i, v in enumerate(order)}
    index = {b: i for i, b in enumerate(bodies)}
    spans = []
    for k in range(n):
        p = [position[index[b]] for b in (f"v{k}", f"h{k}", f"v{k + 1}")]
        spans.append(max(p) - min(p) + 1)
    return max(spans)


@pytest.mark.parametrize("name", NUMBERINGS)
def test_any_numbering_gets_the_band_of_the_interleaved_one(name):
    best = n_fourbar(N, interleaved(N), range(N)).loop_solver_info()
    assert best["banded"] and best["order"] == list(range(2 * N + 1))
    bodies, loops = NUMBERINGS[name]
    info = n_fourbar(N, bodies, loops).loop_solver_info()
    assert info["banded"]
    assert sorted(info["order"]) == list(range(2 * N + 1))
    # Each loop's joints adjacent, as in the interleaved numbering (span 3).
    assert loop_span(info["order"], bodies, N) == 3
    assert info["profile"] == best["profile"]
    if name == "rods_first":
        # The model's own order: joints ~N apart (what the solver used to factor).
        assert loop_span(list(range(2 * N + 1)), bodies, N) == N + 2
        assert info["model_profile"] > 3 * info["profile"]


def test_small_mechanisms_keep_the_model_order():
    # Below 24 speeds the dense QRs: nothing is reordered.
    bodies, loops = shuffled(4, 7)
    info = n_fourbar(4, bodies, loops).loop_solver_info()
    assert not info["banded"] and info["order"] == list(range(9))


@pytest.mark.parametrize("name", ["rods_first", "shuffled0"])
def test_reordered_numbering_follows_the_exact_reduction(name):
    bodies, loops = NUMBERINGS[name]
    m = n_fourbar(N, bodies, loops)
    # Every vertical bar upright and turning at -1 rad/s, the horizontal ones level.
    q0 = np.array([np.pi / 2 if b[0] == "v" else -np.pi / 2 for b in bodies])
    v0 = np.array([-1.0 if b[0] == "v" else 1.0 for b in bodies])
    t = np.linspace(0, 2, 41)
    res = pmd.simulate(pmd.Scene(m, q0, v0, effects=[pmd.Effect.gravity([0, -G, 0])]),
                       (0, 2), t_eval=t, method="DOP853", rtol=1e-10, atol=1e-12)
    assert res.success, res.message
    c = G * ((N + 1) / 2 + N) / ((N + 1) / 3 + N)
    ref = solve_ivp(lambda _, y: [y[1], -c * np.cos(y[0])], (0, 2), [np.pi / 2, -1.0],
                    t_eval=t, rtol=1e-13, atol=1e-13, method="DOP853")
    q = np.asarray(res.q)
    vertical = [i for i, b in enumerate(bodies) if b[0] == "v"]
    horizontal = [i for i, b in enumerate(bodies) if b[0] == "h"]
    assert np.abs(q[:, vertical] - ref.y[0][:, None]).max() < 1e-7
    assert np.abs(q[:, horizontal] + ref.y[0][:, None]).max() < 1e-7


def generic_state(bodies):
    """A closed state off the parallel motion: bars at 0.4 rad, generic speeds projected onto
    the loops (assemble_velocity), in the numbering's coordinates."""
    m = n_fourbar(N, bodies, range(N))
    q = np.array([0.4 if b[0] == "v" else -0.4 for b in bodies])
    v = np.array([np.sin(1.7 * int(b[1:]) + (b[0] == "h")) for b in bodies])
    return q, m.assemble_velocity(q, v)


@pytest.mark.parametrize("name", ["rods_first", "shuffled1"])
def test_reordered_dynamics_and_forces_are_those_of_the_interleaved_numbering(name):
    # The same mechanism in another numbering: the same accelerations and cut-joint wrenches
    # (an invariant of the physics), body by body and loop by loop.
    ref_bodies = interleaved(N)
    ref = n_fourbar(N, ref_bodies, range(N))
    q0, v0 = generic_state(ref_bodies)
    g = [0, -G, 0]
    a_ref = ref.forward_dynamics(q0, v0, np.zeros(ref.nv), gravity=g)
    f_ref = ref.constraint_forces(q0, v0, np.zeros(ref.nv), gravity=g)
    bodies, loops = NUMBERINGS[name]
    m = n_fourbar(N, bodies, loops)
    to_ref = [ref_bodies.index(b) for b in bodies]
    q, v = q0[to_ref], v0[to_ref]
    a = m.forward_dynamics(q, v, np.zeros(m.nv), gravity=g)
    scale = np.abs(a_ref).max()
    assert np.abs(a - a_ref[to_ref]).max() < 1e-10 * scale
    f = m.constraint_forces(q, v, np.zeros(m.nv), gravity=g)
    assert np.abs(f - f_ref[list(loops)]).max() < 1e-9 * np.abs(f_ref).max()


def test_reordered_state_jacobian_matches_central_differences():
    # The constrained derivatives' solves (M⁻¹ and the constrained correction) in the
    # solver's order, against central differences of the dynamics themselves.
    bodies, loops = NUMBERINGS["shuffled2"]
    m = n_fourbar(N, bodies, loops)
    q0, v0 = generic_state(interleaved(N))
    to_ref = [interleaved(N).index(b) for b in bodies]
    sc = pmd.Scene(m, q0[to_ref], v0[to_ref], effects=[pmd.Effect.gravity([0, -G, 0])])
    y = np.concatenate([sc.q0, sc.v0])
    jac = sc.state_jacobian(y)

    def rhs(y):
        q, v = y[: m.nq], y[m.nq:]
        return np.concatenate([v, m.forward_dynamics(q, v, np.zeros(m.nv), gravity=[0, -G, 0])])

    # Along the velocity directions (any v is a state; q directions leave the manifold).
    directions = np.eye(len(y))[m.nq:]
    h = 1e-6
    num = np.column_stack([(rhs(y + h * d) - rhs(y - h * d)) / (2 * h) for d in directions])
    err = np.abs(jac[:, m.nq:] - num).max() / np.abs(num).max()
    assert err < 1e-6, err
