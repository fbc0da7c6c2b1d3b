"""Robots that look like robots (docs/visualisation.md): URDF visuals kept on the model, mesh
files read and simplified, the page drawing them in a real headless Chromium — each mesh
vertex projected through the page's camera lands on drawn pixels, the robot fills the view —
missing or broken meshes replaced by inertia boxes with one warning, and the page inline in
a notebook."""

from __future__ import annotations

import html
import io
import pickle
import re
import time
import warnings

import chromium_driver
import numpy as np
import pointmass_dyn as pmd
import pytest
from conftest import robots_dir
from pointmass_dyn import viewer as animation
from pointmass_dyn.errors import InvalidInputError, UrdfWarning, VisualWarning
from pointmass_dyn.viewer import _meshes as viewer_meshes

needs_chromium = pytest.mark.skipif(
    chromium_driver.find() is None,
    reason="chromium is not installed (apt-get install chromium; .ci/run installs it)",
)
W, H = 800, 600


def _robot(rel: str, **kw):
    root = robots_dir()
    if root is None:
        pytest.skip("example-robot-data not installed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UrdfWarning)
        return pmd.Model.from_urdf(str(root / rel), **kw)


def _png(data: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB")).astype(int)


def _self_contained(text: str) -> None:
    """No attribute that would fetch anything: no src/href with a scheme, no <link>."""
    assert not re.search(r"""(src|href)\s*=\s*["']?\s*(https?:|//)""", text, re.I)
    assert "<link" not in text


def _world_vertices(drawing, frame: int) -> np.ndarray:
    """Every drawn mesh vertex at ``frame``, world frame: body pose ∘ instance pose."""
    vis = drawing.visuals
    slot = {b: k for k, b in enumerate(vis["bodies"])}
    out = []
    for inst in vis["scene"].instances:
        p = vis["pose"][frame, slot[inst.body]]
        rot, org = p[:9].reshape(3, 3), p[9:]
        v = vis["scene"].meshes[inst.mesh].vertices.astype(float)
        local = v @ inst.pose[:, :3].T + inst.pose[:, 3]
        out.append(local @ rot.T + org)
    return np.concatenate(out)


def _drawn(img: np.ndarray) -> np.ndarray:
    """Pixels that are neither the white background nor the pale grid, above the controls."""
    grid = np.array([int(round(255 * c)) for c in animation.COLOURS["grid"]])
    bg = (np.abs(img - 255).max(axis=-1) <= 12) | (np.abs(img - grid).max(axis=-1) <= 30)
    drawn = ~bg
    drawn[H - 45:] = False  # the control bar
    return drawn


def _check_page(path, drawing, info, frame: int) -> None:
    text = path.read_text(encoding="utf-8")
    _self_contained(text)
    assert info.bytes <= 8 * 2**20, info.bytes
    assert info.triangles > 1000
    with chromium_driver.Browser(W, H) as browser:
        browser.load(f"{path.as_uri()}#frame={frame}", 'document.title.startsWith("pmd ok") '
                     '|| document.title.startsWith("pmd error")', timeout=120)
        assert browser.evaluate("document.title") == f"pmd ok frame={frame} size={W}x{H}"
        assert browser.evaluate("window.__errors") == []
        assert browser.evaluate("window.__pmd.shown()") == ["forces", "robot"]
        assert browser.evaluate("window.__pmd.triangles()") == info.triangles
        img = _png(browser.screenshot())
        # The same frame without the robot: the robot's pixels are those that differ.
        browser.load(f"{path.as_uri()}#frame={frame}&show=forces",
                     'document.title.startsWith("pmd ok")', timeout=120)
        assert browser.evaluate("window.__pmd.shown()") == ["forces"]
        bare = _png(browser.screenshot())
    drawn = np.abs(img - bare).max(axis=-1) > 12
    drawn[H - 45:] = False
    px = animation.project(info.camera, W, H, _world_vertices(drawing, frame), frame=frame)
    inside = (px[:, 0] >= 1) & (px[:, 0] < W - 1) & (px[:, 1] >= 1) & (px[:, 1] < H - 46)
    assert inside.mean() > 0.99, "the camera cuts the robot off"
    ij = np.floor(px[inside]).astype(int)
    # A vertex on drawn pixels (itself or a neighbour: a silhouette vertex may round off).
    near = np.zeros(len(ij), dtype=bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            near |= drawn[ij[:, 1] + dy, ij[:, 0] + dx]
    assert near.mean() > 0.98, near.mean()
    # The robot fills the view: its projection spans >= 30 % of the width or the height,
    # and so do the drawn pixels.
    span = np.ptp(px[inside], axis=0) / [W, H]
    assert span.max() >= 0.30, span
    ys, xs = np.nonzero(drawn)
    assert max(np.ptp(xs) / W, np.ptp(ys) / H) >= 0.30


@needs_chromium
def test_panda_page_draws_its_meshes_where_the_model_puts_them(tmp_path):
    pytest.importorskip("collada", reason="Panda's COLLADA meshes need the extra [mesh]")
    pytest.importorskip("trimesh", reason="Panda's COLLADA meshes need the extra [mesh]")
    model = _robot("panda_description/urdf/panda.urdf")
    assert model.name == "panda" and len(model.visuals) == 11
    assert all(v["kind"] == "mesh" and v["path"] for v in model.visuals)
    t = np.linspace(0.0, 2.0, 41)
    q = np.tile(model.neutral(), (len(t), 1))
    q[:, 1], q[:, 3] = 0.6 * np.sin(2 * t), -1.6 + 0.4 * t
    path = tmp_path / "panda.html"
    info = pmd.animate((t, q), model, path, frames=41)
    drawing = animation.prepare((t, q), model, frames=41)
    assert info.camera["track"] is None  # a fixed base: the camera frames the whole motion
    assert "<title>pmd loading</title>" in path.read_text() and ">panda<" in path.read_text()
    _check_page(path, drawing, info, 25)


@needs_chromium
def test_solo12_falling_is_followed_by_the_camera(tmp_path):
    model = _robot("solo_description/robots/solo12.urdf", root_joint="free")
    t = np.linspace(0.0, 1.0, 31)
    q = np.tile(model.neutral(), (len(t), 1))
    q[:, 2] = 0.5 - 4.905 * t**2  # a free fall of 4.9 m: ten times the robot's size
    path = tmp_path / "solo.html"
    info = pmd.animate((t, q), model, path, frames=31)
    drawing = animation.prepare((t, q), model, frames=31)
    track = np.asarray(info.camera["track"])
    np.testing.assert_allclose(track - track[0], q[:, :3] - q[0, :3], atol=1e-9)
    _check_page(path, drawing, info, 30)


def test_path_none_returns_the_page_inline_without_writing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    scene = pmd.load_scene("pendulum_spatial")
    result = pmd.simulate(scene, (0.0, 0.5))
    info = pmd.animate(result, scene, None, fps=20)
    assert info.path is None and list(tmp_path.iterdir()) == []
    assert info.html.startswith("<!DOCTYPE html>") and info.bytes == len(info.html.encode())
    frag = info._repr_html_()
    m = re.fullmatch(r'<iframe srcdoc="([^"]*)" style="[^"]*" sandbox="allow-scripts" '
                     r'title="[^"]*"></iframe>', frag, re.S)
    assert m, frag[:200]
    doc = html.unescape(m.group(1))
    assert doc == info.html and doc.rstrip().endswith("</html>")
    _self_contained(frag)
    assert pmd.animate(result, scene, tmp_path / "a.gif", frames=2)._repr_html_() is None


@needs_chromium
def test_inline_page_runs_inside_its_iframe(tmp_path):
    scene = pmd.load_scene("pendulum_spatial")
    info = pmd.animate(pmd.simulate(scene, (0.0, 0.3)), scene, None, fps=20, size=(640, 400))
    host = tmp_path / "notebook.html"
    host.write_text(f"<!DOCTYPE html><html><body>{info._repr_html_()}</body></html>")
    with chromium_driver.Browser(W, H) as browser:
        browser.load(host.as_uri(), "document.readyState === 'complete'")
        assert browser.evaluate("document.querySelector('iframe').offsetHeight") == 400
        for _ in range(100):  # the frame's script runs after the host page has loaded
            drawn = np.mean(np.abs(_png(browser.screenshot()) - 255).max(axis=-1) > 40)
            if drawn > 0.01:
                break
            time.sleep(0.1)
        assert drawn > 0.01


# ---------------------------------------------------------------- URDF visuals

URDF = """<robot name="bot">
  <material name="red"><color rgba="1 0 0 1"/></material>
  <link name="base">
    <inertial><mass value="2"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.25"/></inertial>
    <visual><origin xyz="0 0 0.1" rpy="0 0 1.5707963267948966"/><geometry><box size="0.4 0.2 0.1"/></geometry>
      <material name="red"/></visual>
    <visual><geometry><mesh filename="package://nowhere/meshes/base.stl" scale="2 2 2"/></geometry></visual>
  </link>
  <link name="arm">
    <inertial><origin xyz="0 0 0.25"/><mass value="1"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.001"/></inertial>
    <visual><geometry><cylinder radius="0.03" length="0.5"/></geometry>
      <material name="blue"><color rgba="0 0 1 0.5"/></material></visual>
    <visual><geometry><sphere radius="0.05"/></geometry></visual>
    <visual><geometry><mesh filename="meshes/arm.stl"/></geometry></visual>
    <visual><geometry><box size="1 x 1"/></geometry></visual>
  </link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 1 0"/><limit effort="1" velocity="1" lower="-1" upper="1"/></joint>
</robot>
"""


def _write_urdf(tmp_path, stl: bytes | None = None):
    path = tmp_path / "bot" / "urdf" / "bot.urdf"
    path.parent.mkdir(parents=True)
    path.write_text(URDF)
    if stl is not None:
        (path.parent / "meshes").mkdir()
        (path.parent / "meshes" / "arm.stl").write_bytes(stl)
    return path


def _stl(triangles: np.ndarray) -> bytes:
    rec = np.zeros(len(triangles), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["v"] = triangles
    return b"\0" * 80 + np.uint32(len(triangles)).tobytes() + rec.tobytes()


def test_urdf_visuals_are_kept_with_their_colours_and_pickled(tmp_path):
    path = _write_urdf(tmp_path, stl=_stl(np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]])))
    with pytest.warns(UrdfWarning) as record:
        model = pmd.Model.from_urdf(str(path))
    messages = [str(w.message) for w in record]
    # One warning names the mesh not found; one says which visual was dropped and why.
    missing = [m for m in messages if "mesh file(s) not found" in m]
    assert len(missing) == 1 and "package://nowhere/meshes/base.stl" in missing[0]
    assert any("<box size>" in m and "line" in m for m in messages)
    v = model.visuals
    assert [x["kind"] for x in v] == ["box", "mesh", "cylinder", "sphere", "mesh"]
    box = v[0]
    assert box["body_name"] == "base" and box["rgba"] == [1.0, 0.0, 0.0, 1.0]
    np.testing.assert_allclose(box["size"], [0.4, 0.2, 0.1])
    np.testing.assert_allclose(box["translation"], [0, 0, 0.1])
    np.testing.assert_allclose(box["rotation"], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)
    assert v[1]["path"] is None and v[1]["scale"] == [2.0, 2.0, 2.0]
    assert v[2]["rgba"] == [0.0, 0.0, 1.0, 0.5] and v[2]["radius"] == 0.03
    assert v[3]["rgba"] is None
    assert v[4]["path"] == str(path.parent / "meshes" / "arm.stl")
    back = pickle.loads(pickle.dumps(model))
    assert back.visuals == v and back.name == "bot"
    # package_dirs finds what the file's ancestors do not.
    pkg = tmp_path / "pkgs" / "nowhere" / "meshes"
    pkg.mkdir(parents=True)
    (pkg / "base.stl").write_bytes(_stl(np.eye(3)[None]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UrdfWarning)
        found = pmd.Model.from_urdf(str(path), package_dirs=[str(tmp_path / "pkgs")])
    assert found.visuals[1]["path"] == str(pkg / "base.stl")
    with pytest.raises(InvalidInputError, match="package_dirs"):
        pmd.Model.from_urdf(str(path), package_dirs=3)


@needs_chromium
def test_missing_meshes_animate_as_inertia_boxes_with_one_warning(tmp_path):
    path = _write_urdf(tmp_path)  # neither mesh exists
    with pytest.warns(UrdfWarning) as record:
        model = pmd.Model.from_urdf(str(path))
    found = [w for w in record if "not found" in str(w.message)]
    assert len(found) == 1
    assert "base.stl" in str(found[0].message) and "arm.stl" in str(found[0].message)
    t = np.linspace(0, 1, 5)
    q = np.c_[0.5 * t]
    out = tmp_path / "bot.html"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # already named at load: no second warning
        info = pmd.animate((t, q), model, out, frames=5)
    d = animation.prepare((t, q), model, frames=5)
    fallback = [i for i in d.visuals["scene"].instances if i.fallback]
    assert sorted(i.body for i in fallback) == [0, 1]
    # The stand-in box has the body's mass and principal moments (a uniform box).
    arm = model.body(1)
    mesh, pose = viewer_meshes.inertia_box(arm)
    sides = np.ptp(mesh.vertices, axis=0)
    np.testing.assert_allclose(pose[:, 3], [0, 0, 0.25])  # at the COM
    # The URDF's inertia about the COM (diagonal 0.02, 0.02, 0.001) in the box's axes.
    moments = np.diag(pose[:, :3].T @ np.diag([0.02, 0.02, 0.001]) @ pose[:, :3])
    want = arm.mass / 12 * np.array([sides[1]**2 + sides[2]**2, sides[0]**2 + sides[2]**2,
                                     sides[0]**2 + sides[1]**2])
    np.testing.assert_allclose(moments, want, rtol=1e-5)
    with chromium_driver.Browser(W, H) as browser:
        browser.load(out.as_uri() + "#frame=2", 'document.title.startsWith("pmd ok") '
                     '|| document.title.startsWith("pmd error")', timeout=120)
        assert browser.evaluate("document.title").startswith("pmd ok frame=2")
        img = _png(browser.screenshot())
    centre = animation.project(info.camera, W, H, d.visuals["corners"][2].mean(axis=0))
    assert _drawn(img)[int(centre[1]) - 3:int(centre[1]) + 4,
                       int(centre[0]) - 3:int(centre[0]) + 4].mean() > 0.5


@pytest.mark.parametrize("content, why", [
    (b"", "truncated"),
    (b"\0" * 80 + np.uint32(1000).tobytes() + b"\1" * 50, "truncated"),
    (b"solid x\n this is not an stl\nendsolid x\n", "unreadable|no triangles"),
])
def test_broken_mesh_files_warn_by_name_and_fall_back(tmp_path, content, why):
    path = _write_urdf(tmp_path, stl=content)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UrdfWarning)
        model = pmd.Model.from_urdf(str(path))
    viewer_meshes._read_cached.cache_clear()
    with pytest.warns(VisualWarning, match=f"arm.stl.*({why})"):
        d = animation.prepare((np.zeros(1), np.zeros((1, 1))), model)
    assert sorted({i.body for i in d.visuals["scene"].instances if i.fallback}) == [0, 1]


def test_unknown_formats_and_absurd_sizes_warn_by_name(tmp_path, monkeypatch):
    path = _write_urdf(tmp_path, stl=_stl(np.eye(3)[None]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UrdfWarning)
        model = pmd.Model.from_urdf(str(path))
    vis = model.visuals
    odd = tmp_path / "thing.xyz123"
    odd.write_bytes(b"12 34")
    vis[4]["path"] = str(odd)
    model.set_visuals(vis)
    if viewer_meshes._has_trimesh():
        with pytest.warns(VisualWarning, match="thing.xyz123.*unknown mesh format"):
            animation.prepare((np.zeros(1), np.zeros((1, 1))), model)
    vis[4]["path"] = str(path.parent / "meshes" / "arm.stl")
    model.set_visuals(vis)
    monkeypatch.setattr(viewer_meshes, "MAX_MESH_BYTES", 100)
    viewer_meshes._read_cached.cache_clear()
    with pytest.warns(VisualWarning, match="arm.stl.*more than the 100"):
        animation.prepare((np.zeros(1), np.zeros((1, 1))), model)


def test_bad_visual_and_view_arguments_are_named(tmp_path):
    path = _write_urdf(tmp_path, stl=_stl(np.eye(3)[None]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UrdfWarning)
        model = pmd.Model.from_urdf(str(path))
    with pytest.raises(InvalidInputError, match=r"visuals\[0\].*sizes"):
        model.set_visuals([{"body": 0, "kind": "box", "size": [1, -1, 1]}])
    with pytest.raises(InvalidInputError, match=r"visuals\[0\]\['kind'\]"):
        model.set_visuals([{"body": 0, "kind": "teapot"}])
    with pytest.raises(InvalidInputError, match=r"visuals\[0\].*body"):
        model.set_visuals([{"body": 7, "kind": "sphere", "radius": 1}])
    with pytest.raises(InvalidInputError, match="rgba"):
        model.set_visuals([{"body": 0, "kind": "sphere", "radius": 1, "rgba": [2, 0, 0, 1]}])
    model.set_visuals([{"body": 1, "kind": "capsule", "radius": 0.1, "length": 0.4}], name="b2")
    assert model.name == "b2" and model.visuals[0]["body_name"] == "arm"
    res = (np.zeros(1), np.zeros((1, 1)))
    for kw, match in [({"camera": "orbit"}, "camera"), ({"camera": {"distance": -1}}, "distance"),
                      ({"show": ["robot", "ghosts"]}, "show"), ({"triangles": -5}, "triangles")]:
        with pytest.raises(InvalidInputError, match=match):
            pmd.animate(res, model, None, **kw)


def test_ground_and_camera_follow_gravity():
    scene = pmd.load_scene("fourbar")  # gravity along −y
    result = pmd.simulate(scene, (0.0, 0.1))
    d = animation.prepare(result, scene, fps=30)
    g = np.sum([e.g for e in scene.effects if e.g is not None], axis=0)
    up = -g / np.linalg.norm(g)
    np.testing.assert_allclose(d.camera["up"], up, atol=1e-15)
    np.testing.assert_allclose([np.dot(d.grid["u"], g), np.dot(d.grid["v"], g)], 0, atol=1e-12)
    # The ground is below everything along gravity.
    low = min(float(np.min(d.spheres @ up)), float(np.min(d.links.reshape(-1, 3) @ up)))
    assert np.dot(d.grid["origin"], up) < low
    # The projection puts "up" up on screen: a point above the target is higher in the image.
    target = np.asarray(d.camera["target"])
    px = animation.project(d.camera, W, H, np.stack([target, target + 0.1 * up]))
    assert px[1, 1] < px[0, 1] - 1


# ---------------------------------------------------------------- MJCF geoms

MJCF = """<mujoco model="geoms">
  <compiler angle="radian" meshdir="{meshdir}"/>
  <asset><mesh name="wedge" file="wedge.stl" scale="1 2 0.5"/></asset>
  <worldbody>
    <geom type="plane" size="5 5 0.1"/>
    <body name="a" pos="0.1 0.2 1" quat="0.9 0.1 0.3 0.2">
      <joint name="h" type="hinge" axis="0 1 1" pos="0.05 0 0" ref="0.4"/>
      <joint name="s" type="slide" axis="1 0 0" pos="0 0.1 0"/>
      <geom type="capsule" fromto="0 0 0 0.3 0.1 0" size="0.04" rgba="1 0 0 1"/>
      <geom type="box" pos="0.1 0 0.2" euler="0.3 0.2 0.1" size="0.1 0.05 0.02"/>
      <geom type="box" size="0.3 0.3 0.3" group="3"/>
      <body name="b" pos="0.3 0.1 0">
        <joint name="ball" type="ball" pos="0 0 0.1"/>
        <geom type="mesh" mesh="wedge" pos="0.1 0 0" euler="0.5 0 0.2"/>
        <geom type="ellipsoid" size="0.05 0.1 0.02" pos="0 0.2 0"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_mujoco_geoms_are_placed_where_mujoco_puts_them(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 0], [0, 1, 0], [0.2, 0.3, 1]],
                    [[0, 0, 0], [0.2, 0.3, 1], [1, 0, 0]], [[1, 0, 0], [0.2, 0.3, 1], [0, 1, 0]]])
    (tmp_path / "wedge.stl").write_bytes(_stl(0.2 * tri + [0.3, -0.1, 0.05]))
    mj = mujoco.MjModel.from_xml_string(MJCF.format(meshdir=tmp_path))
    model = pmd.from_mujoco(mj)
    assert model.name == "geoms"
    assert [v["kind"] for v in model.visuals] == ["capsule", "box", "mesh", "ellipsoid"]
    assert model.visuals[0]["rgba"] == [1.0, 0.0, 0.0, 1.0]
    data = mujoco.MjData(mj)
    rng = np.random.default_rng(5)
    data.qpos[:] = rng.normal(size=mj.nq)
    data.qpos[2:6] /= np.linalg.norm(data.qpos[2:6])
    mujoco.mj_forward(mj, data)
    q, _v = pmd.io.mujoco_state(mj, data.qpos, data.qvel)
    rot, org = model.placements(q)
    geoms = [g for g in range(mj.ngeom) if mj.geom_bodyid[g] > 0 and mj.geom_group[g] < 3]
    for v, g in zip(model.visuals, geoms):
        r = rot[v["body"]] @ np.asarray(v["rotation"])
        p = org[v["body"]] + rot[v["body"]] @ np.asarray(v["translation"])
        if v["kind"] != "mesh":
            np.testing.assert_allclose(p, data.geom_xpos[g], atol=1e-12)
            np.testing.assert_allclose(r, data.geom_xmat[g].reshape(3, 3), atol=1e-12)
            continue
        # The file's vertices, scaled and placed by us, are MuJoCo's compiled vertices placed
        # by MuJoCo.
        k = mj.geom_dataid[g]
        ours = (0.2 * tri + [0.3, -0.1, 0.05]).reshape(-1, 3) * v["scale"] @ r.T + p
        theirs = mj.mesh_vert[mj.mesh_vertadr[k]:mj.mesh_vertadr[k] + mj.mesh_vertnum[k]]
        theirs = theirs @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]
        gap = np.linalg.norm(ours[:, None] - theirs[None], axis=-1)
        assert gap.min(axis=1).max() < 1e-6 and gap.min(axis=0).max() < 1e-6
        assert v["path"] == str((tmp_path / "wedge.stl").resolve())
    # A mesh file gone since MuJoCo compiled the model: named once, then an inertia box.
    (tmp_path / "wedge.stl").unlink()
    with pytest.warns(pmd.errors.ModelImportWarning, match="1 mesh file.*wedge.stl"):
        gone = pmd.from_mujoco(mj)
    assert gone.visuals[2]["path"] is None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        d = animation.prepare((np.zeros(1), q[None]), gone)
    assert [i.body for i in d.visuals["scene"].instances if i.fallback] == [gone.visuals[2]["body"]]


def test_simplified_meshes_are_cached_on_disk(tmp_path, monkeypatch):
    tri = np.random.default_rng(2).normal(size=(400, 3, 3))
    path = _write_urdf(tmp_path, stl=_stl(tri))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UrdfWarning)
        model = pmd.Model.from_urdf(str(path))
    monkeypatch.setenv("PMD_MESH_CACHE", str(tmp_path / "cache"))
    # The budget counts every triangle drawn: the primitives and the base's inertia box (12,
    # not simplified) and 200 for the mesh.
    budget = 12 + 200 + sum(viewer_meshes.primitive(v).ntriangles for v in model.visuals
                            if v["kind"] != "mesh")
    first = viewer_meshes.visual_scene(model, triangles=budget)
    assert len(list((tmp_path / "cache").glob("*.npz"))) == 2  # the count, the mesh
    # A new process in effect: nothing in memory, and the file cannot be read again.
    for f in (viewer_meshes._file_mesh, viewer_meshes._triangle_count,
              viewer_meshes._read_cached):
        f.cache_clear()

    def unreadable(path):
        raise AssertionError("read again")

    monkeypatch.setattr(viewer_meshes, "_read", unreadable)
    again = viewer_meshes.visual_scene(model, triangles=budget)
    assert len(first.meshes) == len(again.meshes)
    for a, b in zip(first.meshes, again.meshes):
        np.testing.assert_array_equal(a.vertices, b.vertices)
        np.testing.assert_array_equal(a.faces, b.faces)
        assert a.parts == b.parts
    # Instances in the visuals' order (box, cylinder, sphere, arm.stl), then the inertia box
    # of the base, whose mesh is missing.
    arm = first.meshes[first.instances[3].mesh]
    assert 100 <= len(arm.faces) <= 200  # simplified from 400 to about the budget
    assert first.triangles <= budget
