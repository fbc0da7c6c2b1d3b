"""Animations (docs/visualisation.md): the cost of a long result, and of the poses.

* ``Model.body_poses`` over 300 Panda configurations in one call, against a Python loop of
  ``placements`` + ``point_masses`` (what a viewer would do without it);
* ``pmd.animate`` to .html of a 10,000-step result (the spatial pendulum for 10 s at
  ``max_step=1e-3``): 300 frames at 30 fps, page size;
* the README's GIF (96 frames, 480 × 360) through matplotlib's Pillow writer;
* robots with their meshes (example-robot-data, ``pip install ".[mesh]"``): Talos (53
  visuals, 25 STL files) to .html, and 300 frames of Panda (11 COLLADA files): in a fresh
  process with an empty mesh cache (files read, simplified), in a second fresh process (the
  disk cache) and again in that process (meshes in memory).

    python benches/animate.py

Ratios come from one run on one machine; the absolute times vary with load."""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import numpy as np
import pointmass_dyn as pmd


def best(f, repeats=5):
    out = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        out = min(out, time.perf_counter() - t0)
    return out


def main() -> None:
    panda = pmd.load_scene("panda")
    res = pmd.simulate(panda, (0.0, 1.0))
    qs = pmd.viewer.sample(res.t, res.q, np.linspace(0, 1, 300))
    m = panda.model
    batched = best(lambda: m.body_poses(qs))
    looped = best(lambda: [(m.placements(q), m.point_masses(q)) for q in qs])
    print(f"Panda, 300 configurations: body_poses {batched * 1e3:.2f} ms, loop of placements + "
          f"point_masses {looped * 1e3:.2f} ms ({looped / batched:.1f}x)")

    scene = pmd.load_scene("pendulum_spatial")
    long = pmd.simulate(scene, (0.0, 10.0), max_step=1e-3)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "long.html"
        t = best(lambda: pmd.animate(long, scene, out, fps=30, trails=["rod"]))
        print(f"pendulum_spatial, {long.n_accepted} steps ({len(long.t)} samples) -> "
              f"{pmd.animate(long, scene, out).frames} frames: animate(.html) {t * 1e3:.1f} ms, "
              f"page {out.stat().st_size / 1e3:.0f} kB")
        gif = Path(tmp) / "p.gif"
        short = pmd.simulate(scene, (0.0, 8.0))
        t = best(lambda: pmd.animate(short, scene, gif, fps=12, size=(480, 360),
                                     trails=[("rod", [1, 0, 0])]), repeats=1)
        print(f"README GIF (96 frames, 480x360): {t:.1f} s, {gif.stat().st_size / 1e3:.0f} kB")


ROBOT = """
import sys, time, warnings
import numpy as np
import pointmass_dyn as pmd
warnings.simplefilter("ignore")
path, free, frames, out = sys.argv[1], sys.argv[2] == "free", int(sys.argv[3]), sys.argv[4]
t0 = time.perf_counter()
m = pmd.Model.from_urdf(path, root_joint="free" if free else None)
t = np.linspace(0.0, 10.0, frames)
q = np.tile(m.neutral(), (frames, 1))
q[:, 7 if free else 1] = 0.5 * np.sin(t)
times = []
for _ in range(3):
    t1 = time.perf_counter()
    info = pmd.animate((t, q), m, out, frames=frames)
    times.append(time.perf_counter() - t1)
print(f"{time.perf_counter() - t0 - sum(times[1:]):.2f} {min(times[1:]):.3f} {info.bytes} "
      f"{info.triangles} {len(m.visuals)}")
"""


def robots() -> None:
    import importlib.metadata
    import subprocess
    import sys

    try:  # the cmeel wheel has no Python module to ask where its files are
        dist = importlib.metadata.distribution("example-robot-data")
        root = Path(dist.locate_file("cmeel.prefix/share/example-robot-data/robots"))
    except importlib.metadata.PackageNotFoundError:
        root = None
    if root is None or not root.is_dir():
        print("robots: example-robot-data not installed")
        return
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, PMD_MESH_CACHE=str(Path(tmp) / "cache"))
        for name, rel, free, frames in [("Talos", "talos_data/robots/talos_full_v2.urdf", True, 30),
                                        ("Panda", "panda_description/urdf/panda.urdf", False, 300)]:
            runs = [subprocess.run([sys.executable, "-c", ROBOT, str(root / rel),
                                    "free" if free else "fixed", str(frames),
                                    str(Path(tmp) / "r.html")], env=env,
                                   capture_output=True, text=True, check=True).stdout.split()
                    for _ in range(2)]
            (cold, _w, size, tris, nvis), (disk, warm, *_rest) = runs
            print(f"{name} ({nvis} visuals), {frames} frames to .html (from_urdf + animate): "
                  f"{float(cold):.2f} s in a fresh process, empty cache; {float(disk):.2f} s in "
                  f"a fresh process, disk cache; {float(warm):.3f} s again in it; page "
                  f"{int(size) / 1e6:.2f} MB, {int(tris)} triangles drawn")


if __name__ == "__main__":
    main()
    robots()
