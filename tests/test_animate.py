"""Animations (docs/visualisation.md): the poses they draw against the model's own kinematics,
the WebGL page in a real headless Chromium (marker pixels where forward kinematics puts the
body, no JavaScript error), the GIF's frames and point masses, subsampling of long results."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import time
from types import SimpleNamespace

import chromium_driver
import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn import viewer as animation
from pointmass_dyn.errors import AnimationWriterError, InvalidInputError
from viewer_page import f32, page_data

needs_chromium = pytest.mark.skipif(
    chromium_driver.find() is None,
    reason="chromium is not installed (apt-get install chromium; .ci/run installs it)",
)

CYAN = "#00ffff"


@pytest.fixture(scope="module")
def pendulum():
    """The README's spatial pendulum sampled at 61 instants, so frame k is sample k."""
    scene = pmd.load_scene("pendulum_spatial")
    t = np.linspace(0.0, 2.0, 61)
    result = pmd.simulate(scene, (0.0, 2.0), t_eval=t, rtol=1e-10, atol=1e-12)
    assert result.success
    return scene, result


def _tip(model, q) -> np.ndarray:
    """World position of the rod's point (1, 0, 0), from ``placements`` (not body_poses)."""
    rot, org = model.placements(q)
    return org[0] + rot[0] @ np.array([1.0, 0.0, 0.0])


# ---------------------------------------------------------------- body_poses


def _prismatic_model():
    m = pmd.Model()
    rod = pmd.RigidBody(1.0, [0.2, 0, 0], np.diag([0.01, 0.02, 0.02]))
    a = m.add_body(rod, pmd.Revolute([0, 0, 1]), name="a")
    rot = np.array([[0.0, 0, 1], [0, 1, 0], [-1, 0, 0]])  # a quarter turn about y
    b = m.add_body(rod, pmd.Prismatic([1, 0, 0]), parent=a, translation=[0.5, 0.1, 0],
                   rotation=rot, name="b")
    m.add_body(rod, pmd.Spherical(), parent=b, translation=[0.3, 0, 0], name="c")
    m.add_body(rod, pmd.Fixed(), parent=-1, translation=[0, 0, -1], name="base")
    return m


def test_body_poses_agree_with_placements_and_point_masses():
    m = _prismatic_model()
    rng = np.random.default_rng(3)
    qs = np.zeros((5, m.nq))
    qs[:, :2] = rng.normal(size=(5, 2))
    quat = rng.normal(size=(5, 4))
    qs[:, 2:] = quat / np.linalg.norm(quat, axis=1, keepdims=True)
    poses = m.body_poses(qs)
    assert poses["rotations"].shape == (5, 4, 3, 3)
    assert poses["points"].shape == (5, m.nlinks, 7, 3)
    for k, q in enumerate(qs):
        rot, org = m.placements(q)
        np.testing.assert_allclose(poses["rotations"][k], rot, atol=1e-14)
        np.testing.assert_allclose(poses["origins"][k], org, atol=1e-14)
        np.testing.assert_allclose(poses["points"][k], m.point_masses(q)[1], atol=1e-14)
        one = m.body_poses(q)  # a single state: the same without the leading axis
        np.testing.assert_array_equal(one["joint_origins"], poses["joint_origins"][k])
        jo, ax = poses["joint_origins"][k], poses["joint_axes"][k]
        # Revolute and spherical joints: the body origin is the joint origin.
        np.testing.assert_allclose(jo[[0, 2]], org[[0, 2]], atol=1e-14)
        # Joint frames at their placement in the parent's body frame.
        np.testing.assert_allclose(jo[1], org[0] + rot[0] @ [0.5, 0.1, 0], atol=1e-14)
        np.testing.assert_allclose(jo[3], [0, 0, -1], atol=1e-14)
        # The prismatic body slides q along its world axis: the parent's x turned about y.
        np.testing.assert_allclose(ax[1], rot[0] @ [0, 0, -1], atol=1e-14)
        np.testing.assert_allclose(org[1], jo[1] + q[1] * ax[1], atol=1e-14)
        np.testing.assert_allclose(ax[0], [0, 0, 1], atol=1e-14)
        np.testing.assert_array_equal(ax[2:], 0.0)  # spherical, fixed: no axis


def test_body_poses_cut_joint_ends_meet_when_the_loop_is_closed():
    scene = pmd.load_scene("fourbar")
    m = scene.model
    q = m.assemble(scene.q0, fixed=["crank"])
    p = m.body_poses(q)
    assert p["loop_a"].shape == (1, 3)
    np.testing.assert_allclose(p["loop_a"], p["loop_b"], atol=1e-10)
    np.testing.assert_allclose(p["loop_axes"][0], [0, 0, 1], atol=1e-14)
    # Frame a is 0.09 m along the coupler: the coupler's origin plus its rotated x.
    rot, org = m.placements(q)
    np.testing.assert_allclose(p["loop_a"][0], org[1] + rot[1] @ [0.09, 0, 0], atol=1e-14)


def test_body_poses_rejects_bad_q():
    m = _prismatic_model()
    with pytest.raises(InvalidInputError, match=r"q.*\(N, 6\)"):
        m.body_poses(np.zeros((3, 5)))
    bad = np.zeros((2, m.nq))
    bad[:, 5] = 1.0
    bad[1, 0] = np.nan
    with pytest.raises(InvalidInputError, match=r"q\[1\]"):
        m.body_poses(bad)


# ---------------------------------------------------------------- sampling


def test_long_result_is_subsampled_to_the_frame_rate(tmp_path):
    scene = pmd.load_scene("pendulum_spatial")
    result = pmd.simulate(scene, (0.0, 10.0), max_step=1e-3)
    assert result.success and len(result.t) >= 10_000
    info = pmd.animate(result, scene, tmp_path / "long.html", fps=30)
    assert info.frames == 300  # duration · fps, not one frame per step
    data = page_data(tmp_path / "long.html")
    assert data["nframes"] == 300
    times = f32(data["times"])
    np.testing.assert_allclose(times, np.linspace(0, 10, 300), atol=1e-5)
    assert f32(data["spheres"]["pos"]).size == 300 * 7 * 3
    assert info.bytes < 200_000
    # Self-contained: nothing fetched (no URL, no src=, no link element).
    text = (tmp_path / "long.html").read_text()
    assert not re.search(r"https?://|src=|<link", text)
    # Frames between output samples: linear interpolation (as NumPy's, column by column).
    qs = animation.sample(result.t, result.q, info.times)
    want = np.stack([np.interp(info.times, result.t, c) for c in result.q.T], axis=1)
    np.testing.assert_allclose(qs, want, rtol=0, atol=1e-12)
    # Playback duration sets the frame count.
    assert pmd.animate(result, scene, tmp_path / "d.html", fps=20, duration=2.5).frames == 50


def test_quaternions_are_interpolated_on_the_unit_sphere():
    # A rotation about z at 1 rad/s, sampled every 0.5 s, with one sample's sign flipped.
    t = np.arange(0, 3.01, 0.5)
    quat = np.stack([0 * t, 0 * t, np.sin(t / 2), np.cos(t / 2)], axis=1)
    quat[3] *= -1
    times = np.linspace(0, 3, 31)
    out = animation.sample(t, quat, times, [slice(0, 4)])
    np.testing.assert_allclose(np.linalg.norm(out, axis=1), 1.0, atol=1e-14)
    angle = 2 * np.arctan2(out[:, 2], out[:, 3])
    angle = np.where(angle < -1e-9, angle + 2 * np.pi, angle)
    # Normalised linear interpolation between rotations θ = 0.5 rad apart: at fraction s of
    # an interval the rotation angle is 2·atan2(s·sin φ, 1 − s + s·cos φ), φ = θ/2 (closed
    # form); within 1e-3 rad of the true s·θ.
    i = np.minimum((times // 0.5).astype(int), len(t) - 2)
    frac, phi = (times - t[i]) / 0.5, 0.25
    exact = t[i] + 2 * np.arctan2(frac * np.sin(phi), 1 - frac + frac * np.cos(phi))
    np.testing.assert_allclose(angle, exact, atol=1e-12)
    assert np.max(np.abs(angle - times)) < 1e-3


# ---------------------------------------------------------------- the page in Chromium


def _marker_centroid(img: np.ndarray, rgb, tol=40) -> tuple[np.ndarray, int]:
    """Centroid (pixel centres, x right, y down) of the pixels of colour ``rgb`` whose eight
    neighbours have it too: a disc's interior, without a 1-pixel line of the same colour."""
    d = np.abs(img[..., :3].astype(int) - np.array(rgb)).max(axis=-1)
    hit = d <= tol
    inner = hit.copy()
    inner[0, :] = inner[-1, :] = inner[:, 0] = inner[:, -1] = False
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            inner[1:-1, 1:-1] &= hit[1 + dy:hit.shape[0] - 1 + dy, 1 + dx:hit.shape[1] - 1 + dx]
    ys, xs = np.nonzero(inner)
    return np.array([xs.mean() + 0.5, ys.mean() + 0.5]) if len(xs) else None, len(xs)


def _png(data: bytes) -> np.ndarray:
    import io

    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))


@needs_chromium
def test_page_draws_the_body_where_forward_kinematics_puts_it(pendulum, tmp_path):
    scene, result = pendulum
    path = tmp_path / "pendulum.html"
    info = pmd.animate(result, scene, path, frames=61, trails=[("rod", [1, 0, 0], CYAN)])
    np.testing.assert_array_equal(info.times, result.t)  # frame k is sample k
    width, height = 800, 600
    with chromium_driver.Browser(width, height) as browser:
        for frame in (0, 40):
            browser.load(f"{path.as_uri()}#frame={frame}", 'document.title.startsWith("pmd ")')
            title = browser.evaluate("document.title")
            assert title == f"pmd ok frame={frame} size={width}x{height}", title
            assert browser.evaluate("window.__errors") == []
            img = _png(browser.screenshot())
            assert img.shape == (height, width, 3)
            # Not blank: many non-white pixels in many colours.
            drawn = np.any(img < 235, axis=-1)
            assert drawn.mean() > 0.02
            assert len(np.unique(img.reshape(-1, 3), axis=0)) > 50
            # The rod's point (1, 0, 0) carries the flat cyan marker: its pixels' centroid is
            # where the page's camera projects the forward-kinematics position.
            want = animation.project(info.camera, width, height, _tip(scene.model,
                                                                      result.q[frame]))
            got, count = _marker_centroid(img, (0, 255, 255))
            assert count > 30, "marker not found"
            assert np.linalg.norm(got - want) < 1.5, (got, want)
            # The point-mass box the page computes (from the link's pose) has the seven
            # points at seven of its corners.
            m, x = scene.model.point_masses(result.q[frame])
            corners = np.array(browser.evaluate("window.__pmd.boxEdges()")).reshape(-1, 3)
            gap = np.linalg.norm(x[0][:, None, :] - corners[None], axis=-1).min(axis=1)
            assert np.all(gap < 1e-5), gap
            # And the heaviest point mass (blue, lit) is drawn at its projection.
            j = int(np.argmax(m[0]))
            px = np.round(animation.project(info.camera, width, height, x[0, j])).astype(int)
            patch = img[px[1] - 2:px[1] + 3, px[0] - 2:px[0] + 3].reshape(-1, 3).astype(int)
            blue = patch[:, 2] - np.maximum(patch[:, 0], patch[:, 1])
            assert np.median(blue) > 60, patch


@needs_chromium
def test_page_with_loops_and_shaking_arrow_and_its_error_report(tmp_path):
    scene = pmd.load_scene("fourbar")
    result = pmd.simulate(scene, (0.0, 0.2))
    path = tmp_path / "fourbar.html"
    info = pmd.animate(result, scene, path, fps=50, shaking=True, trails=["coupler"])
    assert info.frames == 10
    data = page_data(path)
    assert data["cuts"]["count"] == 1 and data["arrow"] is not None
    # The arrow is the shaking force −Σ m a, scaled: its direction at each frame.
    arrow = f32(data["arrow"]).reshape(10, 2, 3)
    sub = SimpleNamespace(t=info.times, q=animation.sample(result.t, result.q, info.times),
                          v=animation.sample(result.t, result.v, info.times))
    force = pmd.shaking(scene, sub).force
    d = arrow[:, 1] - arrow[:, 0]
    cos = np.sum(d * force, axis=1) / np.linalg.norm(d, axis=1) / np.linalg.norm(force, axis=1)
    np.testing.assert_allclose(cos, 1.0, atol=1e-5)
    # Two broken pages: data that do not fit together, and undecodable base64.
    slow = tmp_path / "slow.html"  # 10 frames over 2 s of playback
    slow_info = pmd.animate(result, scene, slow, fps=5, duration=2.0)
    assert slow_info.frames == 10
    broken = [tmp_path / "broken1.html", tmp_path / "broken2.html"]
    broken[0].write_text(path.read_text().replace('"nframes":10', '"nframes":11'))
    broken[1].write_text(path.read_text().replace('"times":"', '"times":"A'))
    with chromium_driver.Browser(640, 480) as browser:
        browser.load(path.as_uri() + "#paused", 'document.title.startsWith("pmd ")')
        assert browser.evaluate("document.title").startswith("pmd ok frame=0")
        assert browser.evaluate("window.__errors") == []
        assert np.any(_png(browser.screenshot()) < 200)
        # A page whose script fails says so: the test above can fail.
        # Playing: frames advance by themselves; pause holds; the slider scrubs.
        browser.load(slow.as_uri(), "window.__pmd && window.__pmd.frame() >= 3", timeout=30)
        browser.evaluate('document.getElementById("play").click()')
        held = browser.evaluate("window.__pmd.frame()")
        time.sleep(0.5)
        assert browser.evaluate("window.__pmd.frame()") == held
        browser.evaluate('var s = document.getElementById("slider"); s.value = "7"; '
                         's.dispatchEvent(new Event("input"))')
        assert browser.evaluate("window.__pmd.frame()") == 7
        assert browser.evaluate('document.getElementById("time").textContent') == (
            f"t = {slow_info.times[7]:.3f} s")
        assert browser.evaluate("window.__errors") == []
        for page in broken:
            browser.load(page.as_uri(), 'document.title.startsWith("pmd ")')
            assert browser.evaluate("document.title").startswith("pmd error")
            assert browser.evaluate("window.__errors.length") >= 1


@needs_chromium
def test_every_bundled_scene_loads_without_error(tmp_path):
    pages = {}
    for name in pmd.builtin_scenes():
        scene = pmd.load_scene(name)
        result = pmd.simulate(scene, (0.0, 0.1))
        pages[name] = tmp_path / f"{name}.html"
        pmd.animate(result, scene, pages[name], fps=50, trails=[scene.model.body_names[-1]],
                    shaking=scene.model.nloops > 0)
    with chromium_driver.Browser(480, 360) as browser:
        for name, path in pages.items():
            browser.load(path.as_uri() + "#frame=4", 'document.title.startsWith("pmd ")')
            assert browser.evaluate("document.title").startswith("pmd ok frame=4"), name
            assert browser.evaluate("window.__errors") == [], name
            img = _png(browser.screenshot())
            assert np.any(img < 235, axis=-1).mean() > 0.01, name


# ---------------------------------------------------------------- GIF and MP4


def test_gif_frames_size_and_point_masses(pendulum, tmp_path):
    from mpl_toolkits.mplot3d import proj3d
    from PIL import Image
    from pointmass_dyn import viewer as viewer_video

    scene, result = pendulum
    size = (360, 280)
    path = tmp_path / "p.gif"
    info = pmd.animate(result, scene, path, frames=7, size=size)
    assert info.frames == 7
    with Image.open(path) as im:
        assert im.n_frames == 7 and im.size == size
        im.seek(0)
        first = np.asarray(im.convert("RGB"))
    # The same figure, to read its axes' projection (fixed limits: the same for all frames).
    d = animation.prepare(result, scene, frames=7)
    fig, ax, _update = viewer_video.figure(d, size)
    fig.canvas.draw()
    m, x = scene.model.point_masses(result.q[0])
    m, x = m.reshape(-1), x.reshape(-1, 3)
    px, py, _ = proj3d.proj_transform(x[:, 0], x[:, 1], x[:, 2], ax.get_proj())
    disp = ax.transData.transform(np.c_[px, py])
    want = np.c_[disp[:, 0], size[1] - disp[:, 1]]  # pixels, y down
    # Artist data: each point mass's disc sits at its projection.
    for j, art in fig.pmd_masses.items():
        got = ax.transData.transform(art.get_offsets())[0]
        np.testing.assert_allclose(got, disp[j], atol=1e-6)
    import matplotlib.pyplot as plt

    plt.close(fig)
    ys, xs = np.mgrid[: size[1], : size[0]]

    def around(centre, radius=30):
        """The frame with everything farther than ``radius`` px from ``centre`` white (the
        legend's coloured bullets are elsewhere)."""
        img = first.copy()
        img[np.hypot(xs + 0.5 - centre[0], ys + 0.5 - centre[1]) > radius] = 255
        return img

    # Pixels: the negative masses (red discs, smaller than their positive neighbours and so
    # drawn on top) are centred on their projection.
    red = tuple(int(round(255 * c)) for c in animation.COLOURS["negative"])
    centre = want[m < 0].mean(axis=0)
    got, count = _marker_centroid(around(centre), red, tol=30)
    assert count > 20
    np.testing.assert_allclose(got, centre, atol=1.0)
    # The two heaviest (blue) discs at the rod's near end, around the small m = 0 one between
    # them: the blue pixels there are centred on the pair's projections.
    blue = tuple(int(round(255 * c)) for c in animation.COLOURS["positive"])
    heavy = m > 1.0
    centre = want[heavy].mean(axis=0)
    got, count = _marker_centroid(around(centre), blue, tol=30)
    assert count > 20
    np.testing.assert_allclose(got, centre, atol=1.5)


@pytest.mark.skipif(shutil.which("ffmpeg") is None or shutil.which("ffprobe") is None,
                    reason="ffmpeg/ffprobe not installed (MP4 is optional)")
def test_mp4_frames_and_size(pendulum, tmp_path):
    scene, result = pendulum
    path = tmp_path / "p.mp4"
    pmd.animate(result, scene, path, frames=9, size=(320, 240), fps=10)
    out = subprocess.run(
        ["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
         "stream=nb_read_frames,width,height", "-of", "json", str(path)],
        capture_output=True, text=True, check=True).stdout
    stream = json.loads(out)["streams"][0]
    assert (int(stream["nb_read_frames"]), stream["width"], stream["height"]) == (9, 320, 240)
    with pytest.raises(AnimationWriterError, match="even"):
        pmd.animate(result, scene, tmp_path / "odd.mp4", frames=2, size=(321, 240))


def test_mp4_without_ffmpeg_says_so(pendulum, tmp_path, monkeypatch):
    from matplotlib import animation as mpl_animation

    scene, result = pendulum
    monkeypatch.setattr(mpl_animation.writers, "is_available", lambda name: False)
    with pytest.raises(AnimationWriterError, match="ffmpeg"):
        pmd.animate(result, scene, tmp_path / "a.mp4", frames=3)


class _Recorder:
    """A Meshcat window that keeps the commands it is sent (no server, no browser)."""

    def __init__(self):
        self.commands = []

    def send(self, command):
        self.commands.append(command.lower())


def test_meshcat_view_sends_the_point_masses_and_one_animation(pendulum):
    meshcat = pytest.importorskip("meshcat")
    scene, result = pendulum
    window = _Recorder()
    vis = pmd.show_meshcat(result, scene, meshcat.Visualizer(window=window), frames=61,
                           trails=["rod"])
    assert vis.window is window
    objects = {c["path"]: c for c in window.commands if c["type"] == "set_object"}
    masses = sorted(p for p in objects if p.startswith("/meshcat/pointmass_dyn/masses/"))
    assert len(masses) == 7
    (anim,) = [c for c in window.commands if c["type"] == "set_animation"]
    clips = {a["path"]: a["clip"] for a in anim["animations"]}
    m, x = scene.model.point_masses(result.q[40])
    for j in range(7):
        (track,) = [t for t in clips[f"/meshcat/pointmass_dyn/masses/{j}"]["tracks"]
                    if t["name"] == ".position"]
        assert len(track["keys"]) == 61
        key = track["keys"][40]
        assert key["time"] == 40
        np.testing.assert_allclose(key["value"], x[0, j], atol=1e-12)
    # The rod (the leaf's segment, origin to twice the COM) spans its length: scale y = 1 m.
    scales = [t for c, clip in clips.items() if "/links/" in c for t in clip["tracks"]
              if t["name"] == ".scale"]
    assert any(np.isclose(t["keys"][0]["value"][1], 1.0) for t in scales)


# ---------------------------------------------------------------- errors and CLI


def test_bad_arguments_are_named(pendulum, tmp_path):
    scene, result = pendulum
    with pytest.raises(InvalidInputError, match="path.*.html, .gif or .mp4"):
        pmd.animate(result, scene, tmp_path / "a.png")
    with pytest.raises(InvalidInputError, match="model_or_scene"):
        pmd.animate(result, "pendulum", tmp_path / "a.html")
    with pytest.raises(InvalidInputError, match=r"result.q.*\(N, 3\)"):
        pmd.animate((result.t, result.q[:, :2]), scene, tmp_path / "a.html")
    with pytest.raises(InvalidInputError, match="shaking.*Scene"):
        pmd.animate(result, scene.model, tmp_path / "a.html", shaking=True)
    with pytest.raises(InvalidInputError, match="trails"):
        pmd.animate(result, scene, tmp_path / "a.html", trails=["nobody"])
    with pytest.raises(InvalidInputError, match="fps"):
        pmd.animate(result, scene, tmp_path / "a.html", fps=0)
    with pytest.raises(InvalidInputError, match="size"):
        pmd.animate(result, scene, tmp_path / "a.gif", size=(10, 10))


def test_cli_animate_and_simulate_animate(tmp_path, capsys):
    from pointmass_dyn.cli import main

    out = tmp_path / "a.html"
    assert main(["animate", "pendulum_spatial", "--out", str(out), "--t-end", "1",
                 "--fps", "12", "--trail", "rod:1,0,0"]) == 0
    data = page_data(out)
    assert data["nframes"] == 12 and len(data["trails"]["colour"]) == 1
    gif = tmp_path / "b.gif"
    assert main(["simulate", "pendulum_spatial", "--t-end", "0.5", "--animate", str(gif),
                 "--frames", "4", "--size", "200x150"]) == 0
    assert "animation written" in capsys.readouterr().out
    from PIL import Image

    with Image.open(gif) as im:
        assert im.n_frames == 4 and im.size == (200, 150)
    assert main(["animate", "pendulum_spatial", "--out", str(out), "--size", "big"]) == 2
    assert "--size" in capsys.readouterr().err
