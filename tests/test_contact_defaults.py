"""Contact without an expert (issue 38): contact spheres from the bounds of mesh feet, the
default stiffness and damping from the robot's weight, and the default method of a contact
scene. References: the mesh files' own vertices (read here), MuJoCo Menagerie's Go2 foot
sphere, force balance at rest, the linearised contact mode's critically damped response."""

from __future__ import annotations

import math
import pickle
import re
import struct
import sys
import warnings
import xml.etree.ElementTree as ET

import numpy as np
import pointmass_dyn as pmd
import pytest

G0 = 9.81  # the documented g₀ of the defaults
SINK = 1e-3  # the documented static sink of the default stiffness
GO2 = "go2_description/urdf/go2.urdf"
FEET = ["FL_foot", "FR_foot", "RL_foot", "RR_foot"]


def go2_urdf():
    pytest.importorskip("pointmass_dyn.robots")
    try:
        return pmd.robots.urdf_path(GO2)
    except pmd.errors.InvalidInputError as e:  # example-robot-data not installed
        pytest.skip(str(e))


def stl_vertices(path) -> np.ndarray:
    """A binary STL's vertices, read with struct (independently of the library)."""
    data = path.read_bytes()
    (n,) = struct.unpack_from("<I", data, 80)
    rows = [struct.unpack_from("<9f", data, 84 + 50 * i + 12) for i in range(n)]
    return np.array(rows, dtype=float).reshape(-1, 3)


def test_go2_mesh_feet_get_the_sphere_inside_their_bounding_box():
    urdf = go2_urdf()
    root = ET.parse(urdf).getroot()
    points = pmd.urdf_contact_points(urdf, FEET)
    assert [p[0] for p in points] == FEET
    for (_, centre, radius), link in zip(points, FEET):
        # The foot's collision mesh, found through the URDF by hand.
        elem = root.find(f"link[@name='{link}']/collision/geometry/mesh")
        rel = elem.get("filename").split("go2_description/", 1)[1]
        v = stl_vertices(urdf.parent.parent / rel)
        lo, hi = v.min(axis=0), v.max(axis=0)
        np.testing.assert_allclose(centre, (lo + hi) / 2, rtol=0, atol=1e-12)
        assert radius == pytest.approx((hi - lo).min() / 2, rel=1e-12)
        # Physically a Go2 foot: its bottom is the mesh's lowest point, and the sphere is
        # close to MuJoCo Menagerie's (r = 22 mm at (−2, 0, 0) mm, bottom 22 mm down).
        assert centre[2] - radius == pytest.approx(lo[2], abs=1e-12)
        assert abs((centre[2] - radius) - (-0.022)) < 1.5e-3
        assert abs(radius - 0.022) < 4e-3 and abs(centre[0] + 0.002) < 3e-3


def write_urdf(tmp_path, links: str) -> str:
    path = tmp_path / "robot.urdf"
    path.write_text(f'<robot name="r">{links}</robot>')
    return str(path)


def test_shapes_and_meshes_are_bounded_in_the_link_frame(tmp_path):
    # An ASCII STL tetrahedron, scaled and placed by its <origin>.
    tet = np.array([[0, 0, 0], [2, 0, 0], [0, 1, 0], [0, 0, 4]], dtype=float)
    faces = [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)]
    lines = ["solid t"]
    for f in faces:
        lines += ["facet normal 0 0 0", "outer loop"]
        lines += [f"vertex {' '.join(map(str, tet[i]))}" for i in f]
        lines += ["endloop", "endfacet"]
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "tet.stl").write_text("\n".join(lines + ["endsolid t"]))
    (tmp_path / "meshes" / "tet.obj").write_text(
        "\n".join(f"v {x} {y} {z}" for x, y, z in tet) + "\nf 1 2 3\n")
    rot_x = '<origin xyz="0.1 0.2 0.3" rpy="1.5707963267948966 0 0"/>'
    urdf = write_urdf(tmp_path, f"""
      <link name="box"><collision>{rot_x}<geometry><box size="0.2 0.4 0.6"/></geometry>
        </collision></link>
      <link name="stl"><collision>{rot_x}<geometry>
        <mesh filename="meshes/tet.stl" scale="0.01 0.01 0.01"/></geometry></collision></link>
      <link name="obj"><collision><geometry>
        <mesh filename="package://{tmp_path.name}/meshes/tet.obj"/></geometry></collision></link>
      <link name="wheel"><collision>{rot_x}<geometry><cylinder radius="0.05" length="0.02"/>
        </geometry></collision></link>
      <link name="bare"/>""")
    pts = {n: (c, r) for n, c, r in pmd.urdf_contact_points(
        urdf, ["box", "stl", "obj", "wheel", "bare"], package_dirs=[tmp_path.parent])}
    # Rotation about x by 90°: (x, y, z) → (x, −z, y).
    (c, r) = pts["box"]
    np.testing.assert_allclose(c, [0.1, 0.2, 0.3], atol=1e-12)
    assert r == pytest.approx(0.1)  # sides 0.2, 0.6, 0.4
    lo, hi = tet.min(0) * 0.01, tet.max(0) * 0.01  # (0..0.02, 0..0.01, 0..0.04)
    lo, hi = np.array([lo[0], -hi[2], lo[1]]), np.array([hi[0], -lo[2], hi[1]])
    c, r = pts["stl"]
    np.testing.assert_allclose(c, (lo + hi) / 2 + [0.1, 0.2, 0.3], atol=1e-9)
    assert r == pytest.approx(0.005, rel=1e-12)
    c, r = pts["obj"]
    np.testing.assert_allclose(c, [1, 0.5, 2], atol=1e-12)
    assert r == pytest.approx(0.5)
    # A disc about y (its axis z turned onto −y): 0.1 × 0.02 × 0.1, bounded by its thickness.
    c, r = pts["wheel"]
    np.testing.assert_allclose(c, [0.1, 0.2, 0.3], atol=1e-12)
    assert r == pytest.approx(0.01)
    assert pts["bare"] == ([0.0, 0.0, 0.0], 0.0)


def test_a_mesh_that_needs_the_extra_falls_back_and_says_so(tmp_path, monkeypatch):
    (tmp_path / "foot.dae").write_text("<COLLADA/>")
    urdf = write_urdf(tmp_path, """
      <link name="foot">
        <collision><geometry><mesh filename="foot.dae"/></geometry></collision>
        <visual><origin xyz="0 0 -0.01"/><geometry><box size="0.04 0.04 0.02"/></geometry>
        </visual></link>
      <link name="toe">
        <collision><geometry><mesh filename="foot.dae"/></geometry></collision></link>
      <link name="heel">
        <collision><geometry><mesh filename="missing.stl"/></geometry></collision></link>""")
    monkeypatch.setitem(sys.modules, "trimesh", None)  # as without the extra
    with pytest.warns(pmd.errors.UrdfWarning) as caught:
        pts = pmd.urdf_contact_points(urdf, ["foot", "toe", "heel"])
    # The collision mesh cannot be read: the visual box, then the origin.
    assert pts[0][0] == "foot"
    np.testing.assert_allclose(pts[0][1], [0, 0, -0.01], atol=1e-12)
    assert pts[0][2] == pytest.approx(0.01)
    assert pts[1] == ("toe", [0.0, 0.0, 0.0], 0.0)
    assert pts[2] == ("heel", [0.0, 0.0, 0.0], 0.0)
    said = [str(w.message) for w in caught]
    assert len(said) == 2
    assert "'toe'" in said[0] and "foot.dae" in said[0] and "pointmass-dyn[mesh]" in said[0]
    assert "'heel'" in said[1] and "missing.stl" in said[1] and "no such file" in said[1]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the foot itself fell back to its visual silently
        pmd.urdf_contact_points(urdf, ["foot"])


def ball(mass=2.0, radius=0.05):
    m = pmd.Model()
    m.add_body(pmd.RigidBody(mass, [0, 0, 0], np.eye(3) * 0.4 * mass * radius**2),
               pmd.Prismatic([0, 0, 1]), name="ball")
    return m


@pytest.mark.parametrize("n", [1.0, 1.5])
def test_default_contact_sinks_1_mm_with_a_critically_damped_mode(n):
    # A ball on a slider: one point carries the weight. The defaults put its rest 1 mm
    # deep; a 10 µm push from there relaxes as the critically damped linearised mode,
    # x(t) = x0 (1 + ω t) e^(−ω t), ω = sqrt(n g₀ / δ₀), without crossing the rest point.
    mass, r = 2.0, 0.05
    contact = pmd.GroundContact([("ball", [0, 0, 0], r)], exponent=n, friction=0.0)
    assert contact.contact_parameters["stiffness"] is None
    assert pickle.loads(pickle.dumps(contact)) == contact  # defaults still to come
    scene = pmd.Scene(ball(mass, r), q0=[r - SINK + 1e-5],
                      effects=[contact, pmd.Gravity([0, 0, -G0])])
    used = scene.effects[0].contact_parameters
    k = mass * G0 / SINK**n
    assert used["stiffness"] == pytest.approx(k, rel=1e-12)
    assert used.stiffness == used["stiffness"] and used.exponent == n  # typed, and indexable
    with pytest.raises(KeyError):
        used["__class__"]
    shown = re.search(r"stiffness=([^,]+),", repr(scene.effects[0])).group(1)
    assert float(shown) == used["stiffness"]
    omega = math.sqrt(n * G0 / SINK)
    t = np.linspace(0, 8 / omega, 41)
    res = pmd.simulate(scene, (0, t[-1]), t_eval=t, method="Radau", rtol=1e-10, atol=1e-13)
    res.raise_for_status()
    x = res.q[:, 0] - (r - SINK)
    expected = 1e-5 * (1 + omega * t) * np.exp(-omega * t)
    np.testing.assert_allclose(x, expected, rtol=0, atol=3e-2 * 1e-5)  # 1 % push: ~1 % nonlinear
    assert np.all(x > -1e-9)  # no overshoot
    # At rest 1 mm deep.
    rest = pmd.simulate(scene, (0, 0.3), method="Radau", rtol=1e-10, atol=1e-13)
    assert r - rest.q[-1, 0] == pytest.approx(SINK, rel=1e-6)


def go2_standing():
    urdf = go2_urdf()
    go2 = pmd.example_robot(GO2, root_joint="free")
    feet = pmd.urdf_contact_points(urdf, FEET)
    legs = [f"{leg}_{part}" for leg in ("FL", "FR", "RL", "RR") for part in ("hip", "thigh", "calf")]
    pose = [0.0, 0.9, -1.8] * 4  # MuJoCo Menagerie's "home" keyframe
    q0 = go2.neutral()
    q0[7:] = pose
    # Base height: each foot sphere's bottom 1 mm into the ground.
    rot, org = go2.placements(q0)
    names = [go2.body_info(i)[0] for i in range(go2.nbodies)]
    bottoms = [(org[names.index(f)] + rot[names.index(f)] @ c)[2] - r for f, c, r in feet]
    q0[2] = -np.mean(bottoms) - SINK
    effects = [
        pmd.Gravity([0, 0, -G0]),
        pmd.GroundContact(feet, friction=1.0, v_eps=1e-4),  # stiffness, damping: defaults
        pmd.PDTorque(legs, kp=100.0, kd=5.0, time=[0, 1], reference=[pose, pose]),
    ]
    return pmd.Scene(go2, q0=q0, effects=effects), ET.parse(urdf).getroot()


def test_go2_stands_on_the_default_contact_with_the_default_method():
    scene, root = go2_standing()
    mass = sum(float(m.get("value")) for m in root.iter("mass"))  # from the URDF itself
    k = mass * G0 / 4 / SINK**1.5
    used = scene.effects[1].contact_parameters
    assert used["stiffness"] == pytest.approx(k, rel=1e-9)
    k_lin = 1.5 * k * SINK**0.5
    assert used["damping"] == pytest.approx(2 * math.sqrt(k_lin * mass / 4) / SINK**1.5, rel=1e-9)
    res = pmd.simulate(scene, (0, 2.0), t_eval=[2.0], rtol=1e-6, atol=1e-9, contact=True)
    res.raise_for_status()
    # The default for a contact scene is auto, which found it stiff and went on with Radau.
    assert res.method == "auto" and res.switched_to == "Radau", repr(res)
    feet = res.contact["contact"]
    assert np.abs(res.v[-1]).max() < 1e-3  # at rest
    # Force balance, and the documented sink: the mean of δ^1.5 is δ₀^1.5 at rest.
    assert feet.normal_force[-1].sum() == pytest.approx(mass * G0, rel=2e-3)
    delta = feet.penetration[-1]
    assert np.mean(delta**1.5) ** (1 / 1.5) == pytest.approx(SINK, rel=2e-3)
    assert np.all((delta > 0.5 * SINK) & (delta < 1.5 * SINK))


def test_the_default_method_follows_the_scene():
    box = pmd.load_scene("box_incline")  # its file says Radau
    effects = list(box.effects)
    bare = pmd.Scene(box.model, q0=box.q0, effects=effects)
    assert pmd.simulate(box, (0, 0.01)).method == "Radau"
    assert pmd.simulate(bare, (0, 0.01)).method == "auto"
    assert pmd.simulate(bare, (0, 0.01), method="RK45").method == "RK45"
    # Contact switched off: nothing stiff by design is left, RK45 (SciPy's) as before.
    assert pmd.simulate(bare, (0, 0.01), disable="contact").method == "RK45"
    limits = pmd.Scene(ball(), q0=[0.0], effects=[
        pmd.Gravity(), pmd.JointLimit(lower=-0.01, upper=1.0, stiffness=1e3, damping=1.0)])
    assert pmd.simulate(limits, (0, 0.01)).method == "auto"
    batch = pmd.simulate_batch([bare, limits, pmd.Scene(ball(), q0=[0.0])], t_span=(0, 0.01))
    assert [r.method for r in batch.results] == ["auto", "auto", "RK45"]


@pytest.mark.parametrize("geometry", [
    '<box size="1 nan 1"/>', '<box size="1 -1 1"/>', '<cylinder radius="0.1"/>',
    '<mesh filename="m.stl" scale="1 1"/>'])
def test_malformed_geometry_numbers_name_the_link(tmp_path, geometry):
    urdf = write_urdf(tmp_path, f'<link name="foot"><collision><geometry>{geometry}</geometry>'
                                '</collision></link>')
    (tmp_path / "m.stl").write_bytes(bytes(84))
    with pytest.raises(pmd.errors.InvalidInputError, match="urdf: link 'foot' of .*expected"):
        pmd.urdf_contact_points(urdf, ["foot"])
