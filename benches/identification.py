"""Identification timings (docs/identification.md): the joint torque regressor of the Panda
arm (fingers welded, 7 links) along 20,000 samples, and ``identify(method="cells")`` with
about 200 cells per link on those samples (1 % torque noise).

    PYTHONPATH=python python benches/identification.py

Targets (issue 43): regressor ≤ 0.5 s, identify(cells) ≤ 10 s on the 2-core machine."""

from __future__ import annotations

import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import pointmass_dyn as pmd
from pointmass_dyn import identification as ident

G = np.array([0.0, 0.0, -9.81])


def panda_arm(folder: Path):
    text = pmd.robots.urdf_path("panda").read_text()
    for j in ("panda_finger_joint1", "panda_finger_joint2"):
        text = text.replace(f'<joint name="{j}" type="prismatic">', f'<joint name="{j}" type="fixed">')
    path = folder / "panda_arm.urdf"
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pmd.errors.UrdfWarning)
        return pmd.Model.from_urdf(str(path), package_dirs=[str(pmd.robots.directory().parent.parent)])


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        model = panda_arm(Path(tmp))
    n = 20_000
    traj = pmd.excitation_trajectory(model, 20.0, harmonics=5, rate=n / 20.0, iterations=10, seed=0, gravity=G)
    q, v, a = traj.q[:n], traj.v[:n], traj.a[:n]
    t0 = time.perf_counter()
    reg = ident.torque_regressor(model, q, v, a, gravity=G)
    t_reg = time.perf_counter() - t0
    tau = reg.torques()
    sigma = 0.01 * np.sqrt(np.mean(tau**2, axis=0))
    tau = tau + np.random.default_rng(0).normal(size=tau.shape) * sigma
    t0 = time.perf_counter()
    res = pmd.identify(model, (q, v, a, tau), method="cells", cells=200, noise=sigma, gravity=G)
    t_cells = time.perf_counter() - t0
    t0 = time.perf_counter()
    pmd.identify(model, (q, v, a, tau), method="ols", noise=sigma, gravity=G)
    t_ols = time.perf_counter() - t0
    print(f"regressor, Panda, {n} samples ({reg.data.shape[0]} x {reg.data.shape[1]}): {t_reg:.3f} s (target 0.5 s)")
    print(f"identify(cells, ~200 cells/link), {n} samples: {t_cells:.2f} s (target 10 s); physical: {res.physical}")
    print(f"identify(ols), {n} samples: {t_ols:.2f} s")
    print(f"residual RMS / noise per joint: {np.round(res.rms / sigma, 3).tolist()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
