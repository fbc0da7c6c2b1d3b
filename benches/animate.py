"""Animations (docs/visualisation.md): the cost of a long result, and of the poses.

* ``Model.body_poses`` over 300 Panda configurations in one call, against a Python loop of
  ``placements`` + ``point_masses`` (what a viewer would do without it);
* ``pmd.animate`` to .html of a 10,000-step result (the spatial pendulum for 10 s at
  ``max_step=1e-3``): 300 frames at 30 fps, page size;
* the README's GIF (96 frames, 480 × 360) through matplotlib's Pillow writer.

    python benches/animate.py

Ratios come from one run on one machine; the absolute times vary with load."""

from __future__ import annotations

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


if __name__ == "__main__":
    main()
