"""Frames and inverse kinematics (docs/kinematics.md) against Pinocchio:

* the frame Jacobian of Panda's hand (LOCAL) per Python call, against Pinocchio's
  ``computeFrameJacobian``;
* over 1,000 configurations in one call, against a Python loop over Pinocchio;
* the COM Jacobian likewise (``jacobianCenterOfMass``);
* inverse kinematics on Panda: the hand's pose of random configurations from the neutral
  one (median and 95th percentile time, iterations).

    python benches/kinematics.py

Needs a release build (``maturin develop --release``) for meaningful numbers; ratios come
from one run on one machine, absolute times vary with load."""

from __future__ import annotations

import time
import warnings

import numpy as np
import pinocchio as pin
import pointmass_dyn as pmd


def best(f, repeats=7, number=1):
    out = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(number):
            f()
        out = min(out, (time.perf_counter() - t0) / number)
    return out


def main() -> None:
    warnings.simplefilter("ignore", pmd.errors.UrdfWarning)
    path = str(pmd.robots.urdf_path("panda"))
    model = pmd.Model.from_urdf(path, mimic=False)
    pm = pin.buildModelFromUrdf(path)
    data = pm.createData()
    fid = pm.getFrameId("panda_hand")
    rng = np.random.default_rng(0)
    lo, hi = pm.lowerPositionLimit, pm.upperPositionLimit
    qs = rng.uniform(lo, hi, size=(1000, pm.nq))
    q = qs[0]

    ours = best(lambda: model.frame_jacobian("panda_hand", q), number=2000)
    theirs = best(lambda: pin.computeFrameJacobian(pm, data, q, fid), number=2000)
    print(f"frame Jacobian per call: ours {ours * 1e6:.2f} us, Pinocchio {theirs * 1e6:.2f} us")

    ours = best(lambda: model.frame_jacobian("panda_hand", qs), number=3)
    theirs = best(lambda: [pin.computeFrameJacobian(pm, data, x, fid) for x in qs], number=3)
    print(f"frame Jacobian x1000: ours {ours * 1e3:.3f} ms (one call), Pinocchio loop {theirs * 1e3:.3f} ms, ratio {theirs / ours:.1f}")

    ours = best(lambda: model.center_of_mass(q, jacobian=True), number=2000)
    theirs = best(lambda: pin.jacobianCenterOfMass(pm, data, q), number=2000)
    print(f"COM Jacobian per call: ours {ours * 1e6:.2f} us, Pinocchio {theirs * 1e6:.2f} us")
    ours = best(lambda: model.center_of_mass(qs, jacobian=True), number=3)
    theirs = best(lambda: [pin.jacobianCenterOfMass(pm, data, x) for x in qs], number=3)
    print(f"COM Jacobian x1000: ours {ours * 1e3:.3f} ms, Pinocchio loop {theirs * 1e3:.3f} ms, ratio {theirs / ours:.1f}")

    times, iters, ok = [], [], 0
    for x in qs[:200]:
        goal = model.frame_placement("panda_hand", x)
        t0 = time.perf_counter()
        res = pmd.inverse_kinematics(model, {"panda_hand": goal})
        times.append(time.perf_counter() - t0)
        iters.append(res.iterations)
        ok += res.converged
    times = np.array(times) * 1e3
    print(f"IK Panda hand pose (200 targets): median {np.median(times):.3f} ms, 95% {np.percentile(times, 95):.3f} ms, "
          f"median iterations {np.median(iters):.0f}, converged {ok}/200")


if __name__ == "__main__":
    main()
