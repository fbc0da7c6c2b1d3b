"""Contact forces in animations (docs/visualisation.md §1, docs/contact.md): the arrows handed
to the page, the GIF and Meshcat against the result's contact arrays and against a static
box whose corners carry m g / 4 each (closed form); the page in headless Chromium."""

from __future__ import annotations

import chromium_driver
import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn import viewer
from pointmass_dyn.errors import InvalidInputError
from viewer_page import f32, page_data

needs_chromium = pytest.mark.skipif(
    chromium_driver.find() is None,
    reason="chromium is not installed (apt-get install chromium; .ci/run installs it)",
)

MASS, K, N, G = 2.0, 1e5, 1.5, 9.81
CORNERS = np.array([[sx * 0.1, sy * 0.05, -0.05] for sx in (1, -1) for sy in (1, -1)])
#: Static penetration of each corner: k δⁿ = m g / 4.
DEPTH = (MASS * G / 4 / K) ** (1 / N)


def _box_scene(lift: float = 0.0) -> pmd.Scene:
    """A 0.2 × 0.1 × 0.1 m box of 2 kg on a free joint, its four bottom corners at the static
    penetration (``lift`` above it), plus a point on its top face that never touches."""
    model = pmd.Model()
    inertia = MASS / 12 * np.diag([0.1**2 + 0.1**2, 0.2**2 + 0.1**2, 0.2**2 + 0.1**2])
    model.add_body(pmd.RigidBody(MASS, [0, 0, 0], inertia), pmd.FreeFlyer(), name="box")
    points = [("box", c.tolist()) for c in CORNERS] + [("box", [0.0, 0.0, 0.05])]
    contact = pmd.GroundContact(points, stiffness=K, exponent=N, damping=1e3, friction=0.5)
    q0 = [0.3, -0.2, 0.05 - DEPTH + lift, 0, 0, 0, 1]
    return pmd.Scene(model, effects=[pmd.Gravity([0, 0, -G]), contact], q0=q0)


@pytest.fixture(scope="module")
def resting():
    scene = _box_scene()
    t = np.linspace(0.0, 0.05, 6)
    res = pmd.simulate(scene, (0.0, 0.05), t_eval=t, method="Radau", rtol=1e-10, atol=1e-12,
                       contact=True)
    assert res.success
    return scene, res


def test_arrows_start_at_the_contact_points_and_scale_with_the_force(resting):
    scene, res = resting
    c = res.contact["contact"]
    # The box rests: the four corners carry m g in all, the top point nothing.
    np.testing.assert_allclose(c.normal_force[:, :4].sum(axis=1), MASS * G, rtol=1e-6)
    assert np.all(c.force[:, 4] == 0)
    scale = 0.01
    d = viewer.prepare(res, scene, frames=6, contact_scale=scale)
    assert d.contact.shape == (6, 5, 2, 3) and d.contact_scale == scale
    # Frames fall on the output times: the arrays drawn are the result's.
    np.testing.assert_allclose(d.contact[:, :, 0], c.position, rtol=0, atol=1e-15)
    np.testing.assert_allclose(d.contact[:, :, 1] - d.contact[:, :, 0], scale * c.force,
                               rtol=0, atol=1e-15)
    # Against the closed form: tails at the corners (box at (0.3, -0.2), bottom δ deep),
    # arrows straight up, m g / 4 · scale long.
    want = CORNERS + np.array([0.3, -0.2, 0.05 - DEPTH])
    for k in range(6):
        np.testing.assert_allclose(d.contact[k, :4, 0], want, atol=1e-7)
        arrow = d.contact[k, :4, 1] - d.contact[k, :4, 0]
        np.testing.assert_allclose(arrow[:, :2], 0.0, atol=1e-6 * scale)
        np.testing.assert_allclose(arrow[:, 2], scale * MASS * G / 4, rtol=1e-6)
        # The point not in contact: no arrow (tail = head), and nothing drawn.
        np.testing.assert_array_equal(d.contact[k, 4, 0], d.contact[k, 4, 1])
        assert len(viewer.contact_segments(d, k)) == 4
    # Default scale: the largest force is a quarter of the scene's size.
    auto = viewer.prepare(res, scene, frames=6)
    lengths = np.linalg.norm(auto.contact[:, :, 1] - auto.contact[:, :, 0], axis=-1)
    assert np.isclose(lengths.max(), viewer.CONTACT_SHARE * auto.size, rtol=1e-12)
    assert np.isclose(auto.contact_scale * np.linalg.norm(c.force, axis=-1).max(),
                      lengths.max(), rtol=1e-12)


def test_page_carries_the_arrows_and_their_legend(resting, tmp_path):
    scene, res = resting
    path = tmp_path / "box.html"
    info = pmd.animate(res, scene, path, frames=6, contact_scale=0.01)
    assert info.contact_scale == 0.01
    data = page_data(path)
    assert data["contact"]["count"] == 5 and data["contact"]["scale"] == 0.01
    arrows = f32(data["contact"]["pos"]).reshape(6, 5, 2, 3)
    c = res.contact["contact"]
    np.testing.assert_allclose(arrows[:, :, 0], c.position, rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(arrows[:, :, 1], c.position + 0.01 * c.force, rtol=1e-6,
                               atol=1e-7)
    assert "forces" in data["show"]
    assert data["colours"]["contact"] == list(viewer.COLOURS["contact"])
    assert "contact forces (10 mm/N)" in path.read_text(encoding="utf-8")


def test_nothing_changes_without_contact_data_and_opt_out(resting, tmp_path):
    scene, res = resting
    pend = pmd.load_scene("pendulum_spatial")
    sol = pmd.simulate(pend, (0.0, 0.2))
    d = viewer.prepare(sol, pend, frames=4)
    assert d.contact is None
    info = pmd.animate(sol, pend, tmp_path / "p.html", frames=4)
    assert info.contact_scale is None
    assert page_data(tmp_path / "p.html")["contact"] is None
    assert "contact forces" not in (tmp_path / "p.html").read_text(encoding="utf-8")
    # A result of a contact scene without contact=True: no arrows unless asked for.
    plain = pmd.simulate(scene, (0.0, 0.05), t_eval=res.t, method="Radau", rtol=1e-10,
                         atol=1e-12)
    assert viewer.prepare(plain, scene, frames=6).contact is None
    # contact=True evaluates the scene's contact at the frames' states: here the same states.
    asked = viewer.prepare(plain, scene, frames=6, contact=True, contact_scale=0.01)
    np.testing.assert_allclose(asked.contact[:, :, 0], res.contact["contact"].position,
                               atol=1e-9)
    np.testing.assert_allclose(asked.contact[:, :, 1] - asked.contact[:, :, 0],
                               0.01 * res.contact["contact"].force, rtol=1e-6, atol=1e-9)
    # Opt out.
    assert viewer.prepare(res, scene, frames=6, contact=False).contact is None
    # A dict of ContactForces for any trajectory of the model.
    given = viewer.prepare((res.t, res.q), scene.model, frames=6, contact=res.contact)
    np.testing.assert_allclose(given.contact, viewer.prepare(res, scene, frames=6).contact)


def test_contact_arguments_are_checked(resting, tmp_path):
    scene, res = resting
    plain = (res.t, res.q, res.v)
    with pytest.raises(InvalidInputError, match="contact: True needs"):
        viewer.prepare(plain, scene.model, contact=True)
    pend = pmd.load_scene("pendulum_spatial")
    sol = pmd.simulate(pend, (0.0, 0.1))
    with pytest.raises(InvalidInputError, match="contact: True needs.*Scene"):
        viewer.prepare(sol, pend, contact=True)
    # A scene whose contact is switched off has none to draw.
    off = pmd.Scene(scene.model, q0=scene.q0, effects=scene.effects, disable="contact")
    assert viewer.has_contact(scene) and not viewer.has_contact(off)
    with pytest.raises(InvalidInputError, match=r"contact: True needs.*not disabled"):
        viewer.prepare(plain, off, contact=True)
    with pytest.raises(InvalidInputError, match="contact: expected None"):
        viewer.prepare(res, scene, contact="yes")
    for bad in (0, -1.0, float("nan"), "1", True):
        with pytest.raises(InvalidInputError, match="contact_scale"):
            pmd.animate(res, scene, tmp_path / "a.html", contact_scale=bad)
    short = {"contact": pmd.ContactForces("contact", res.contact["contact"].position[:3],
                                          *(np.zeros(1),) * 2, res.contact["contact"].force[:3])}
    with pytest.raises(InvalidInputError, match=r"contact\['contact'\].*\(6, P, 3\)"):
        viewer.prepare(res, scene, contact=short)


def test_points_in_the_air_draw_nothing(tmp_path):
    scene = _box_scene(lift=0.01)
    res = pmd.simulate(scene, (0.0, 0.02), t_eval=[0.0, 0.01, 0.02], contact=True)
    d = viewer.prepare(res, scene, frames=3)
    assert d.contact.shape == (3, 5, 2, 3)
    assert all(len(viewer.contact_segments(d, k)) == 0 for k in range(3))
    np.testing.assert_array_equal(d.contact[:, :, 0], d.contact[:, :, 1])


@pytest.fixture(scope="module")
def incline():
    scene = pmd.load_scene("box_incline")
    res = pmd.simulate(scene, (0.0, 0.3), t_eval=np.linspace(0.0, 0.3, 4), contact=True)
    assert res.success
    return scene, res


def test_gif_of_the_box_incline_draws_the_contact_forces(incline, tmp_path):
    from PIL import Image

    scene, res = incline
    size = (320, 240)
    colour = np.array([round(255 * c) for c in viewer.COLOURS["contact"]])
    counts = {}
    for contact in (None, False):
        path = tmp_path / f"incline_{contact}.gif"
        info = pmd.animate(res, scene, path, frames=4, size=size, contact=contact)
        with Image.open(path) as im:
            assert im.n_frames == 4 and im.size == size
            im.seek(2)
            img = np.asarray(im.convert("RGB")).astype(int)
        counts[contact] = int((np.abs(img - colour).max(axis=-1) <= 30).sum())
        assert (info.contact_scale is None) == (contact is False)
    assert counts[None] > 40 and counts[False] < 5, counts
    # The figure's line holds the four arrows of the frame (NaN-separated), dots at the tails.
    import matplotlib.pyplot as plt

    d = viewer.prepare(res, scene, frames=4)
    fig, _ax, update = viewer.figure(d, size)
    update(2)
    line, dots = fig.pmd_contact
    xs, ys, zs = line.get_data_3d()
    got = np.c_[xs, ys, zs].reshape(-1, 3, 3)[:, :2]
    np.testing.assert_allclose(got, d.contact[2], atol=1e-12)
    np.testing.assert_allclose(np.array(dots.get_data_3d()).T, d.contact[2, :, 0], atol=1e-12)
    plt.close(fig)
    # The arrows lean uphill: the box slides (0.47 m/s ≫ v_eps at t = 0.2 s), so each point's
    # friction is μ = 0.3 times its normal force, against the downhill direction.
    f = res.contact["contact"].force[2]
    n, downhill = np.array([0.5, 0, np.sqrt(3) / 2]), np.array([np.sqrt(3) / 2, 0, -0.5])
    np.testing.assert_allclose(f @ downhill, -0.3 * (f @ n), rtol=1e-6)


def test_cli_draws_contact_forces_unless_told_not_to(tmp_path, capsys):
    from pointmass_dyn.cli import main

    out = tmp_path / "a.html"
    assert main(["animate", "box_incline", "--out", str(out), "--t-end", "0.1", "--fps", "30",
                 "--contact-scale", "0.005"]) == 0
    assert "contact forces at 5 mm/N" in capsys.readouterr().out
    data = page_data(out)
    assert data["contact"]["count"] == 4 and data["contact"]["scale"] == 0.005
    assert main(["simulate", "box_incline", "--t-end", "0.1", "--animate", str(out),
                 "--no-contact-forces"]) == 0
    assert page_data(out)["contact"] is None


def test_meshcat_sends_one_cylinder_per_contact_point(resting):
    meshcat = pytest.importorskip("meshcat")
    from test_animate import _Recorder

    scene, res = resting
    window = _Recorder()
    pmd.show_meshcat(res, scene, meshcat.Visualizer(window=window), frames=6,
                     contact_scale=0.01)
    objects = [c["path"] for c in window.commands if c["type"] == "set_object"]
    assert sum("/contact/" in p for p in objects) == 5
    (anim,) = [c for c in window.commands if c["type"] == "set_animation"]
    clips = {a["path"]: a["clip"] for a in anim["animations"]}
    (scale,) = [t for t in clips["/meshcat/pointmass_dyn/contact/0"]["tracks"]
                if t["name"] == ".scale"]
    np.testing.assert_allclose(scale["keys"][3]["value"][1], 0.01 * MASS * G / 4, rtol=1e-6)


@needs_chromium
def test_page_draws_the_contact_arrows(resting, tmp_path):
    scene, res = resting
    path = tmp_path / "box.html"
    info = pmd.animate(res, scene, path, frames=6, contact_scale=0.01,
                       show=("masses", "forces"))
    width, height = 640, 480
    with chromium_driver.Browser(width, height) as browser:
        browser.load(f"{path.as_uri()}#frame=3", 'document.title.startsWith("pmd ")')
        assert browser.evaluate("document.title").startswith("pmd ok frame=3")
        assert browser.evaluate("window.__errors") == []
        assert browser.evaluate("window.__pmd.contactArrows()") == 4
        from test_animate import _png

        img = _png(browser.screenshot()).astype(int)
        colour = np.array([round(255 * c) for c in viewer.COLOURS["contact"]])
        near = np.abs(img - colour).max(axis=-1) <= 60
        near[height - 80:] = False  # the legend's arrow
        ys, xs = np.nonzero(near)
        pix = np.c_[xs + 0.5, ys + 0.5]
        # Every teal pixel lies on one of the four arrows as the page's camera projects them
        # (tail at the corner, head m g / 4 · scale above), and each arrow has pixels.
        c = res.contact["contact"]
        tails = viewer.project(info.camera, width, height, c.position[3, :4])
        heads = viewer.project(info.camera, width, height, c.position[3, :4] + 0.01 * c.force[3, :4])
        d = heads - tails
        s = np.clip(np.einsum("pkc,kc->pk", pix[:, None] - tails[None], d) / np.sum(d * d, axis=1),
                    0, 1)
        gap = np.linalg.norm(pix[:, None] - (tails[None] + s[..., None] * d[None]), axis=-1)
        assert len(pix) > 100
        assert np.mean(gap.min(axis=1) < 8) > 0.98, np.percentile(gap.min(axis=1), [50, 90, 99])
        assert np.all(np.bincount(gap.argmin(axis=1), minlength=4) > 20)
        browser.load(f"{path.as_uri()}#frame=3&show=masses", 'document.title.startsWith("pmd ")')
        assert browser.evaluate("window.__pmd.contactArrows()") == 0
