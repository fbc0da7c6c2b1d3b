"""Connected, exactly realised links (docs/design.md §3 "Connected links", §4 "Realised
parts"): every written part is one face-connected solid holding its joints' bosses — checked
by a flood fill over its written boxes and by the connected components of its STL's
triangles — and the written parts' mass properties, computed here from the STL's triangles
by the divergence theorem, give the motion's shaking and bearing forces within 1 % of the
design's prediction when the motion is analysed again with them."""

from __future__ import annotations

import struct

import numpy as np
import pointmass_dyn as pmd
import pytest

G = np.array([0.0, -9.81, 0.0])


def plates(cell=0.004, coupler=True, **kw):
    box = lambda x0, x1, y: ([x0, -y, -0.004], [x1, y, 0.004])  # noqa: E731
    out = [pmd.LinkShape("crank", box=box(-0.05, 0.045, 0.02), cell=cell, **kw),
           pmd.LinkShape("rocker", box=box(-0.05, 0.08, 0.02), cell=cell, **kw)]
    if coupler:
        out.append(pmd.LinkShape("coupler", box=box(-0.01, 0.10, 0.01), cell=cell, **kw))
    return out


@pytest.fixture(scope="module")
def designs():
    scene = pmd.load_scene("fourbar")
    motion = pmd.prescribed_motion(scene.model, "crank", speed=30.0, samples=120, q_guess=scene.q0, gravity=G)
    limit = 0.1 * motion.summary()["shaking force"]["peak"]
    links = plates(coupler=False)
    return motion, {
        "force-balanced": pmd.balance(motion, links=links, zero=("force",), objective={"mass": 1.0}),
        "peak bearing": pmd.balance(motion, links=links, objective={"bearing": 1.0}, norm="peak",
                                    limits={"force": limit}),
        "three links, zero force": pmd.balance(motion, links=plates(), zero=("force",),
                                                objective={"mass": 1.0}),
    }


def box_components(boxes: np.ndarray) -> int:
    """Connected components of boxes touching along a face of positive area (a flood fill)."""
    n = len(boxes)
    lo, hi = boxes[:, 0], boxes[:, 1]
    label = -np.ones(n, int)
    count = 0
    for s in range(n):
        if label[s] >= 0:
            continue
        label[s], stack = count, [s]
        while stack:
            a = stack.pop()
            overlap = np.minimum(hi[a], hi) - np.maximum(lo[a], lo)  # (n, 3)
            touch = np.zeros(n, bool)
            for k in range(3):
                others = [j for j in range(3) if j != k]
                touch |= (np.all(overlap[:, others] > 0, axis=1)
                          & ((hi[:, k] == lo[a, k]) | (lo[:, k] == hi[a, k])))
            for b in np.nonzero(touch & (label < 0))[0]:
                label[b] = count
                stack.append(b)
        count += 1
    return count


def read_triangles(path) -> np.ndarray:
    data = path.read_bytes()
    (count,) = struct.unpack("<I", data[80:84])
    rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
                        offset=84, count=count)
    return rec["v"].astype(float)


def triangle_components(tri: np.ndarray) -> tuple[int, np.ndarray]:
    """Components of triangles sharing an edge (union-find), and each edge's use count."""
    verts, inv = np.unique(tri.reshape(-1, 3), axis=0, return_inverse=True)
    f = inv.reshape(-1, 3)
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    owner = np.tile(np.arange(len(f)), 3)
    key = edges[:, 0] * len(verts) + edges[:, 1]
    parent = np.arange(len(f))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    order = np.argsort(key)
    for a, b in zip(order[:-1], order[1:]):
        if key[a] == key[b]:
            ra, rb = root(owner[a]), root(owner[b])
            parent[ra] = rb
    roots = {root(i) for i in range(len(f))}
    _, uses = np.unique(key, return_counts=True)
    return len(roots), uses


def stl_mass_properties(tri: np.ndarray, density: float):
    """Mass, COM and inertia about the COM of the solid a closed outward mesh bounds: each
    triangle and the origin span a signed tetrahedron (the divergence theorem)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    vol = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    mass = density * vol.sum()
    com = density * (vol[:, None] * (a + b + c) / 4.0).sum(axis=0) / mass
    # Σ x xᵀ over a tetrahedron (0, a, b, c): V/20 (Σ p pᵀ + (Σ p)(Σ p)ᵀ).
    s = a + b + c
    second = (vol[:, None, None] / 20.0 * (np.einsum("ti,tj->tij", a, a) + np.einsum("ti,tj->tij", b, b)
                                            + np.einsum("ti,tj->tij", c, c) + np.einsum("ti,tj->tij", s, s)))
    second = density * second.sum(axis=0)
    inertia_o = np.trace(second) * np.eye(3) - second
    inertia = inertia_o - mass * (com @ com * np.eye(3) - np.outer(com, com))
    return mass, com, inertia


def world_bearing(a):
    names = list(a.model.body_names)
    tree = np.array([[a.model.placements(q)[0][names.index(n)] @ f for n, f in zip(a.model.link_names, fk)]
                     for q, fk in zip(a.q, a.bearing[:, :, :3])])
    return np.concatenate([tree, a.cut[:, :, :3]], axis=1)


def stl_reanalysed_within(motion, b, tmp_path, label):
    """Each written part's STL, its mass properties by the divergence theorem equal to the
    realised body's; the motion analysed again with them: shaking and bearing forces within
    1 % of the design's predicted peaks."""
    model = motion.model
    for name, part in b.realised.parts.items():
        part.write_stl(tmp_path / f"{name}.stl")
        mass, com, inertia = stl_mass_properties(read_triangles(tmp_path / f"{name}.stl"), part.density)
        body = b.realised.bodies[name]
        assert mass == pytest.approx(body.mass, rel=1e-9)
        np.testing.assert_allclose(com, body.com, rtol=0, atol=1e-9 * np.abs(body.com).max())
        np.testing.assert_allclose(inertia, body.inertia, rtol=0, atol=1e-9 * np.abs(body.inertia).max())
        model = model.with_body(name, pmd.RigidBody(mass, com, inertia))
    # The motion analysed again with the STL's bodies: shaking and bearing forces within 1 %
    # of the design's predicted peaks (a quantity the design cancels: of 1e-3 of its peak
    # before, the float32 STL's resolution).
    again = pmd.analyze_motion(model, motion.t, motion.q, motion.v, motion.a, actuated=motion.actuated,
                               gravity=motion.gravity, about=motion.shaking.about)
    for what, got, before in (("force", again.shaking.force, motion.shaking.force),
                              ("bearing", world_bearing(again), world_bearing(motion))):
        pred = b.predicted[what]
        peak = np.linalg.norm(pred, axis=-1).max()
        floor = 1e-3 * np.linalg.norm(before, axis=-1).max()
        dev = np.linalg.norm(got - pred, axis=-1).max()
        assert dev <= 0.01 * max(peak, floor), (label, what, dev, peak)


@pytest.mark.parametrize("label", ["force-balanced", "peak bearing", "three links, zero force"])
def test_written_parts_are_one_face_connected_solid_holding_the_bosses(designs, label, tmp_path):
    motion, ds = designs
    b = ds[label]
    assert set(b.realised.parts) == set(b.shapes)
    for name, part in b.realised.parts.items():
        assert box_components(part.boxes) == 1, (label, name)
        # Every joint on the link lies inside the written solid.
        for point, _axis in pmd._core.design_pins(motion.model, name):
            inside = np.all((part.boxes[:, 0] <= point + 1e-12) & (point - 1e-12 <= part.boxes[:, 1]), axis=1)
            assert inside.any(), (label, name, point)
        part.write_stl(tmp_path / f"{name}.stl")
        count, uses = triangle_components(read_triangles(tmp_path / f"{name}.stl"))
        assert count == 1, (label, name)
        assert np.all(uses % 2 == 0), (label, name)  # closed: every edge shared by an even number


def test_unconnected_designs_fall_apart_and_connected_ones_cost_mass(designs):
    """The issue's observation, kept with connected=False: the least-mass force balance of
    the crank is pieces (its written cells, flood-filled here, are not one part)."""
    motion, ds = designs
    loose = pmd.balance(motion, links=plates(coupler=False, connected=False), zero=("force",),
                        objective={"mass": 1.0})
    shape = loose.shapes["crank"]
    solid = shape.fill >= 0.5
    c = shape.centers[solid]
    half = 0.5 * shape.cell
    assert box_components(np.stack([c - half, c + half], axis=1)) > 1
    assert ds["force-balanced"].shapes["crank"].mass > shape.mass


@pytest.mark.parametrize("label", [
    # The three-link zero-force case (a coupler plate five cells wide) was an xfail until the
    # polish weighed each row by its scale in the 1 % check (realised force 18 % of FLOOR).
    "force-balanced", "peak bearing", "three links, zero force",
])
def test_realised_parts_from_the_stl_reproduce_the_design(designs, label, tmp_path):
    motion, ds = designs
    b = ds[label]
    stl_reanalysed_within(motion, b, tmp_path, label)
    # Rounding alone (without the polish) is what the issue reports: several per cent.
    assert b.realised.polish["status"] in ("Solved", "AlmostSolved")


def test_shape_writes_its_realised_part_beside_the_design(designs, tmp_path):
    """``Shape.write_stl`` writes the realised part (not thresholded cells): the STL's mass
    properties by the divergence theorem are the written part's; ``mass_properties`` gives
    them beside the design's, which are the designed body's (the Rust parameters)."""
    motion, ds = designs
    b = ds["peak bearing"]
    for name, shape in b.shapes.items():
        path = tmp_path / f"{name}.stl"
        count = shape.write_stl(path)
        tri = read_triangles(path)
        assert len(tri) == count
        assert triangle_components(tri)[0] == 1
        mass, com, inertia = stl_mass_properties(tri, b.realised[name].density)
        props = shape.mass_properties()
        written, designed = props["written"], props["designed"]
        assert mass == pytest.approx(written["mass"], rel=1e-9)
        np.testing.assert_allclose(com, written["com"], rtol=0, atol=1e-9 * np.abs(com).max())
        np.testing.assert_allclose(inertia, written["inertia"], rtol=0, atol=1e-9 * np.abs(inertia).max())
        body = b.bodies[name]  # the plates are the whole link: its designed body
        assert designed["mass"] == pytest.approx(body.mass, rel=1e-12)
        np.testing.assert_allclose(designed["com"], body.com, rtol=0, atol=1e-12)
        np.testing.assert_allclose(designed["inertia"], body.inertia, rtol=0, atol=1e-12 * np.abs(body.inertia).max())
        assert "designed" in shape.table() and "written" in shape.table()
        with pytest.warns(RuntimeWarning, match="not the design"):
            shape.write_stl(tmp_path / "cells.stl", threshold=0.5)


def test_the_spatial_rssr_of_the_docs_is_connected_strong_and_realised(tmp_path):
    """docs/design.md §7c: the RSSR's crank and rocker, connected and strength-checked (safety
    ≥ 4): each written part one solid holding its joints (flood fill over its boxes, and the
    STL's triangles), the STL's bodies reproducing the predicted shaking and bearing forces
    within 1 %, the members at the asked safety, and the solves' certificates."""
    rs = pmd.load_scene("rssr")
    rm = pmd.prescribed_motion(rs.model, "crank", speed=300.0, samples=48, q_guess=rs.q0,
                               gravity=np.array([0.0, 0.0, -9.81]))
    steel = pmd.Material.steel()
    links = [pmd.LinkShape("crank", box=([-0.03, -0.012, -0.004], [0.036, 0.012, 0.004]), cell=0.004,
                           material=steel),
             pmd.LinkShape("rocker", box=([-0.04, -0.012, -0.004], [0.076, 0.012, 0.004]), cell=0.004,
                           material=steel)]
    b = pmd.balance(rm, links=links, objective={"force": 1.0, "moment": 1.0}, limits={"safety": 4.0})
    for s in b.solver["stages"]:
        assert s["status"] in ("Solved", "AlmostSolved") and 0 <= s["gap_rel"] <= 1e-8, s
    # Spatial: the shaking force has a z component that matters.
    assert np.abs(rm.shaking.force[:, 2]).max() > 1e-2 * np.abs(rm.shaking.force).max()
    assert b.after.shaking.rms["force"] < 0.6 * rm.shaking.rms["force"]
    for name, part in b.realised.parts.items():
        assert box_components(part.boxes) == 1, name
        for point, _axis in pmd._core.design_pins(rm.model, name):
            inside = np.all((part.boxes[:, 0] <= point + 1e-12) & (point - 1e-12 <= part.boxes[:, 1]), axis=1)
            assert inside.any(), (name, point)
        part.write_stl(tmp_path / f"{name}.stl")
        assert triangle_components(read_triangles(tmp_path / f"{name}.stl"))[0] == 1, name
    stl_reanalysed_within(rm, b, tmp_path, "rssr")
    # Strength: the least safety factor (allowable over the largest |stress| along the motion,
    # re-analysed from the designed model) at the limit or above, for every checked link.
    assert set(b.strength) == {"crank", "rocker"}
    for name, st in b.strength.items():
        assert st.safety >= 4.0 * (1 - 1e-6), (name, st.safety)
        assert st.safety == pytest.approx(steel.allowable_stress / np.abs(st.stress).max(), rel=1e-12)


@pytest.mark.parametrize("kw, message", [
    ({"section": "a"}, r"section: expected a finite number >= 0"),
    ({"section": -1.0}, r"section: expected a finite number >= 0"),
    ({"hang": 0.0}, r"hang: expected a finite number > 0 or None"),
    ({"connected": "yes"}, r"connected: expected True or False"),
])
def test_bad_connectivity_arguments_are_refused(kw, message):
    scene = pmd.load_scene("fourbar")
    motion = pmd.prescribed_motion(scene.model, "crank", speed=30.0, samples=12, q_guess=scene.q0, gravity=G)
    shape = pmd.LinkShape("crank", box=([-0.05, -0.02, -0.004], [0.045, 0.02, 0.004]), cell=0.004, **kw)
    with pytest.raises(pmd.errors.InvalidInputError, match=message):
        pmd.balance(motion, links=[shape], zero=("force",))


def test_a_connected_link_must_reach_its_joints():
    """The coupler in the crank's envelope misses its far joint: an error naming the link."""
    scene = pmd.load_scene("fourbar")
    motion = pmd.prescribed_motion(scene.model, "crank", speed=30.0, samples=12, q_guess=scene.q0, gravity=G)
    shape = pmd.LinkShape("coupler", box=([-0.05, -0.02, -0.004], [0.045, 0.02, 0.004]), cell=0.004)
    with pytest.raises(pmd.errors.InvalidInputError, match="LinkShape 'coupler': joint 1"):
        pmd.balance(motion, links=[shape], zero=("force",))


@pytest.fixture(scope="module")
def doc_designs(design_page_run):
    """Every design docs/design.md makes with link shapes (its blocks run once per session,
    conftest.py's ``design_page_run``, shared with tests/test_docs.py), with ``balance``'s own
    warnings (a written part off the design, a stage that failed) as errors."""
    return [(m, b) for m, b in design_page_run if b.realised is not None]


def test_every_doc_design_is_written_connected_and_within_one_percent(doc_designs, tmp_path):
    """docs/design.md's examples (four-bar, fronts, strength, slider-crank engine, Watt
    six-bar, RSSR): every written part one solid holding its joints (flood fill over its
    boxes), and from its STL (mass properties by the divergence theorem) the motion analysed
    again: shaking and bearing forces within 1 % of the design's prediction."""
    assert len(doc_designs) >= 10
    for k, (motion, b) in enumerate(doc_designs):
        for name, part in b.realised.parts.items():
            assert box_components(part.boxes) == 1, (k, name)
            for point, _axis in pmd._core.design_pins(motion.model, name):
                inside = np.all((part.boxes[:, 0] <= point + 1e-12) & (point - 1e-12 <= part.boxes[:, 1]),
                                axis=1)
                assert inside.any(), (k, name, point)
        stl_reanalysed_within(motion, b, tmp_path, f"doc design {k}")
        for s in b.solver["stages"]:
            assert s["status"] in ("Solved", "AlmostSolved") and 0 <= s["gap_rel"] <= 1e-8, (k, s)
