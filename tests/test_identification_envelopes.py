"""Envelopes besides the box for identification's cells (docs/identification.md §3): a prism
(a non-convex polygon extruded) and a closed mesh (triangles or an STL file). Inside tests
against the shapes' analytic definitions (including points whose rays graze a mesh's edges and
vertices), cells wholly inside, and an identification of the four-bar with a prism and a mesh
envelope recovering its base parameters with every body's centre of mass in its envelope."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn.identification._shapes import Mesh, Prism, envelope_of, winding_numbers
from test_identification_loops import G, crank_motion, crank_torque, other_fourbar

R = 0.05


def octahedron(r=R, centre=(0.0, 0.0, 0.0)):
    """|x| + |y| + |z| ≤ r as 8 outward triangles."""
    tri = []
    for sx in (-1, 1):
        for sy in (-1, 1):
            for sz in (-1, 1):
                a, b, c = np.array([sx * r, 0, 0]), np.array([0, sy * r, 0]), np.array([0, 0, sz * r])
                tri.append((a, b, c) if sx * sy * sz > 0 else (a, c, b))
    return np.array(tri) + np.asarray(centre)


def box_mesh(lo, hi):
    """An axis-aligned box as 12 triangles."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    v = np.array([[hi[0] if i & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2]] for i in range(8)])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return np.array([t for a, b, c, d in quads for t in ((v[a], v[b], v[c]), (v[a], v[c], v[d]))])


def write_ascii_stl(path, triangles):
    lines = ["solid s"]
    for t in triangles:
        lines += ["facet normal 0 0 0", "outer loop", *[f"vertex {x:.17g} {y:.17g} {z:.17g}" for x, y, z in t], "endloop", "endfacet"]
    path.write_text("\n".join(lines + ["endsolid s"]))


L_SHAPE = np.array([[0, 0], [0.06, 0], [0.06, 0.02], [0.02, 0.02], [0.02, 0.05], [0, 0.05]], float)


def in_l(p):
    x, y = p[:, 0], p[:, 1]
    return ((x >= 0) & (x <= 0.06) & (y >= 0) & (y <= 0.02)) | ((x >= 0) & (x <= 0.02) & (y >= 0) & (y <= 0.05))


def test_mesh_inside_test_is_the_octahedron_including_grazing_rays():
    mesh = Mesh(octahedron())
    rng = np.random.default_rng(0)
    pts = rng.uniform(-1.2 * R, 1.2 * R, (3000, 3))
    # Points on the axes and on the planes through the edges: a ray cast along an axis or in
    # those planes grazes vertices and edges.
    s = np.linspace(-1.2 * R, 1.2 * R, 41)
    pts = np.vstack([pts, *[np.eye(3)[k] * s[:, None] for k in range(3)], np.c_[s, s, 0 * s], np.c_[s, 0 * s, s]])
    l1 = np.abs(pts).sum(1)
    clear = np.abs(l1 - R) > 1e-9
    np.testing.assert_array_equal(mesh.contains(pts)[clear], (l1 < R)[clear])
    # The winding number is ±1 and 0 to rounding, whichever way the faces point.
    w = winding_numbers(octahedron()[:, ::-1], pts[clear])
    assert np.abs(np.abs(w) - (l1[clear] < R)).max() < 1e-9
    assert abs(mesh.volume - 4 * R**3 / 3) < 1e-15


def test_mesh_cells_lie_inside_and_fill_it(tmp_path):
    path = tmp_path / "octa.stl"
    write_ascii_stl(path, octahedron())
    for spec in (path, str(path), {"stl": path}, {"stl": octahedron()}):
        mesh = envelope_of("link", spec)
        centres, side = mesh.cells(200)
        h = side / 2
        corners = centres[:, None, :] + h * np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        assert (np.abs(corners).sum(2) <= R * (1 + 1e-9)).all()
        # The inscribed cubes of a convex solid on a grid: a good part of its volume.
        assert 0.3 < len(centres) * side**3 / mesh.volume <= 1.0
        assert 40 <= len(centres) <= 400


def test_prism_cells_and_inside_test_are_the_l_shape():
    prism = envelope_of("link", {"polygon": L_SHAPE, "z": (-0.005, 0.005)})
    assert isinstance(prism, Prism) and abs(prism.volume - (0.06 * 0.02 + 0.02 * 0.03) * 0.01) < 1e-15
    centres, side = prism.cells(150)
    h = side / 2
    for dx in (-h, h):
        for dy in (-h, h):
            assert in_l(centres + [dx * (1 - 1e-9), dy * (1 - 1e-9), 0]).all()
    assert (np.abs(centres[:, 2]) + h <= 0.005 * (1 + 1e-9)).all()
    rng = np.random.default_rng(1)
    pts = rng.uniform([-0.01, -0.01, -0.008], [0.07, 0.06, 0.008], (3000, 3))
    ref = in_l(pts) & (np.abs(pts[:, 2]) <= 0.005)
    np.testing.assert_array_equal(prism.contains(pts), ref)


def test_bad_envelopes_are_refused_naming_the_link():
    with pytest.raises(pmd.errors.InvalidInputError, match=r"envelopes\['crank'\].*polygon"):
        envelope_of("crank", {"polygon": [[0, 0], [1, 0]], "z": (0, 1)})
    with pytest.raises(pmd.errors.InvalidInputError, match=r"envelopes\['crank'\].*keys"):
        envelope_of("crank", {"mesh": octahedron()})
    with pytest.raises(pmd.errors.InvalidInputError, match=r"envelopes\['crank'\].*triangles"):
        envelope_of("crank", {"stl": np.zeros((2, 3, 3))})


def test_fourbar_identified_with_prism_and_mesh_envelopes():
    """Exact crank torques, the crank's envelope a prism (its bar outline with rounded-off
    corners), the coupler's a closed box mesh, the rocker's a box: the base parameters to
    1e-9 and every body physical with its centre of mass in its own envelope."""
    scene = pmd.load_scene("fourbar")
    m = scene.model
    t = np.linspace(0.0, 2.0, 241)
    qs, vs, acs = crank_motion(m, scene.q0, t, [9.0, 0.8, 0.3, 0.2])
    tau = crank_torque(m, qs, vs, acs)
    crank = np.array([[-0.008, -0.004], [-0.004, -0.008], [0.04, -0.008], [0.044, -0.004], [0.044, 0.004], [0.04, 0.008], [-0.004, 0.008], [-0.008, 0.004]])
    env = {
        "crank": {"polygon": crank, "z": (-0.004, 0.004)},
        "coupler": {"stl": box_mesh([-0.01, -0.01, -0.005], [0.1, 0.01, 0.005])},
        "rocker": [[-0.01, -0.01, -0.005], [0.08, 0.01, 0.005]],
    }
    res = pmd.identify(m, (qs, vs, acs, tau), actuated=["crank"], gravity=G, envelopes=env, cells=80, prior=other_fourbar(m))
    reg = pmd.identification.torque_regressor(m, qs, vs, acs, G, actuated=["crank"])
    truth = res.base.of(reg.values)
    assert np.abs(res.base_values - truth).max() < 1e-9 * np.abs(truth).max()
    assert res.physical and all(b.inside_envelope for b in res.bodies.values())
    centres = res.cells["crank"][0]
    assert Prism(crank, (-0.004, 0.004)).contains(centres).all()
