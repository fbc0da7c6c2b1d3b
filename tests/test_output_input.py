"""The outputs under bad input: the CLI refuses paths and options it cannot write before
running, ``animate`` bounds its frame count and survives broken visuals, ``to_mjcf`` of an
imported body with two joints compiles in MuJoCo and agrees with us."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest
from pointmass_dyn.errors import (
    InvalidInputError,
)


def _binary_stl(path, triangles):
    import struct

    with open(path, "wb") as fh:
        fh.write(b" " * 80 + struct.pack("<I", len(triangles)))
        for t in triangles:
            fh.write(struct.pack("<12fH", 0, 0, 1, *np.ravel(t), 0))


def test_to_mjcf_of_an_imported_two_joint_body_compiles_and_agrees():
    mujoco = pytest.importorskip("mujoco")
    xml = """
    <mujoco><option gravity="0 0 -9.81"/><worldbody>
      <body name="arm" pos="0 0 1" quat="0.9 0.1 0.3 0.2">
        <joint name="pitch" type="hinge" axis="0 1 0" pos="0.1 0 0"/>
        <joint name="slide" type="slide" axis="1 0 0.2"/>
        <geom type="capsule" size="0.05" fromto="0 0 0 0.5 0 0" mass="1.3"/>
        <body name="tip" pos="0.5 0 0">
          <joint name="roll" type="hinge" axis="1 0 0"/>
          <joint name="ball" type="ball" pos="0 0.05 0"/>
          <geom type="sphere" size="0.07" mass="0.4" pos="0.02 0.03 0"/>
        </body>
      </body>
    </worldbody></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    ours = pmd.from_mujoco(m)
    assert ours.nbodies > 2  # split: massless parts between the joints
    back = mujoco.MjModel.from_xml_string(pmd.to_mjcf(ours, gravity=[0, 0, -9.81]))  # main: refused
    assert (back.nq, back.nv, back.njnt) == (m.nq, m.nv, m.njnt)
    rng = np.random.default_rng(3)
    d0, d1 = mujoco.MjData(m), mujoco.MjData(back)
    for _ in range(3):
        qpos = rng.normal(size=m.nq)
        qpos[3:7] /= np.linalg.norm(qpos[3:7])
        qvel = rng.normal(size=m.nv)
        for mm, dd in ((m, d0), (back, d1)):
            dd.qpos[:], dd.qvel[:] = qpos, qvel
            mujoco.mj_forward(mm, dd)
        np.testing.assert_allclose(d1.qacc, d0.qacc, rtol=1e-9, atol=1e-9)


def test_animate_bounds_the_frame_count_and_checks_the_directory(tmp_path, monkeypatch):
    from pointmass_dyn.viewer import _animation

    scene = pmd.load_scene("pendulum_planar")
    sol = pmd.simulate(scene, (0, 0.5))
    # Refused before any frame is sampled (not OOM-killed after minutes), whatever the clock.
    linspace = np.linspace

    def no_huge_linspace(start, stop, num=50, *args, **kwargs):
        assert num <= _animation.MAX_FRAMES, f"{num} frame times made before the refusal"
        return linspace(start, stop, num, *args, **kwargs)

    with monkeypatch.context() as patch:
        patch.setattr(_animation.np, "linspace", no_huge_linspace)
        patch.setattr(_animation, "sample", lambda *a, **k: pytest.fail("a frame was sampled"))
        for kwargs in ({"fps": 1e9}, {"duration": 1e9}, {"frames": 10**9}):
            with pytest.raises(InvalidInputError, match="at most 108000"):
                pmd.animate(sol, scene, tmp_path / "x.html", **kwargs)
            assert not (tmp_path / "x.html").exists()
    with pytest.raises(InvalidInputError, match="path: expected a file in an existing dir"):
        pmd.animate(sol, scene, tmp_path / "missing" / "x.html")
    info = pmd.animate(sol, scene, tmp_path / "x.html", fps=20)
    assert info.frames == 10 and info.bytes > 0  # round(0.5 s × 20 fps), as before


def test_animate_survives_broken_visuals(tmp_path, monkeypatch):
    import os
    import pickle
    import warnings

    from pointmass_dyn.errors import VisualWarning
    from pointmass_dyn.viewer import _meshes as viewer_meshes

    monkeypatch.setenv("PMD_MESH_CACHE", "0")
    viewer_meshes._read_cached.cache_clear()
    good = np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]])
    _binary_stl(tmp_path / "nan.stl", [good, good + np.nan])
    os.mkfifo(tmp_path / "fifo.stl")
    scene = pmd.load_scene("pendulum_planar")
    eye = np.eye(3).tolist()

    def mesh(path):
        return {"body": 0, "kind": "mesh", "rotation": eye, "translation": [0, 0, 0],
                "uri": path, "path": path, "scale": [1, 1, 1], "rgba": None}

    model = pickle.loads(pickle.dumps(scene.model))
    model.set_visuals([
        mesh(str(tmp_path / "nan.stl")),
        mesh(str(tmp_path / "fifo.stl")),
        mesh(str(tmp_path / "a\x00b.stl")),
        {"body": 0, "kind": "box", "size": [1e308] * 3, "rotation": eye,
         "translation": [0, 0, 0], "rgba": None},
    ])
    vs = viewer_meshes.visual_scene(model, warn=False)
    # The one finite triangle of nan.stl is kept, exactly (float32 of the file's values).
    drawn = [m for m in vs.meshes if len(m.faces) == 1]
    assert len(drawn) == 1
    np.testing.assert_array_equal(np.sort(drawn[0].vertices, axis=0),
                                  np.sort(good.astype(np.float32), axis=0))
    assert all(np.isfinite(m.vertices).all() for m in vs.meshes)
    assert set(vs.failed) == {str(tmp_path / "fifo.stl"), str(tmp_path / "a\x00b.stl"),
                              "box of body 'rod'"}
    sol = pmd.simulate(scene, (0, 0.2))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pmd.animate(sol, pmd.Scene(model, scene.q0, scene.v0, scene.effects),
                    tmp_path / "x.html")
    msgs = [str(w.message) for w in caught if issubclass(w.category, VisualWarning)]
    assert len(msgs) == 1 and "3 mesh file(s) or shape(s)" in msgs[0]
    assert "not a regular file" in msgs[0] and "beyond float32" in msgs[0]
    page = (tmp_path / "x.html").read_text()
    assert "NaN" not in page and "Infinity" not in page


@pytest.mark.parametrize("argv, named", [
    (["simulate", "pendulum_planar", "--out", "{d}/missing/x.csv"], "--out"),
    (["simulate", "pendulum_planar", "--plot", "{d}/missing/x.png"], "--plot"),
    (["simulate", "pendulum_planar", "--animate", "{d}/x.html", "--trail", "nobody"], "--trail"),
    (["simulate", "pendulum_planar", "--animate", "{d}/x.gif", "--size", "big"], "--size"),
    (["animate", "pendulum_planar", "--out", "{d}/missing/x.html"], "--out"),
    (["sweep", "pendulum_planar", "--runs", "2", "--q0-noise", "0.1",
      "--out", "{d}/missing/x.npz"], "--out"),
])
def test_cli_refuses_bad_outputs_before_running(argv, named, tmp_path, monkeypatch, capsys):
    from pointmass_dyn import cli
    from pointmass_dyn.cli import _animate, _simulate, _sweep

    def no_run(*args, **kwargs):
        raise AssertionError("the run started before the arguments were checked")

    for module, name in ((_simulate, "simulate"), (_animate, "simulate"),
                         (_sweep, "simulate_batch")):
        monkeypatch.setattr(module, name, no_run)
    assert cli.main([a.format(d=tmp_path) for a in argv]) == 2
    err = capsys.readouterr().err
    assert f"error: {named}: expected" in err
