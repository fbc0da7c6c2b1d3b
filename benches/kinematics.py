"""Frames and inverse kinematics (docs/kinematics.md) against Pinocchio:

* the frame Jacobian of Panda's hand (LOCAL) per Python call, by name and by index in
  ``frame_names``, against Pinocchio's ``computeFrameJacobian`` (which takes an index);
* over 1,000 configurations in one call, against a Python loop over Pinocchio;
* the COM Jacobian likewise (``jacobianCenterOfMass``);
* inverse kinematics on Panda: the hand's pose of random configurations from the neutral
  one (median and 95th percentile time, iterations).

    python benches/kinematics.py [ROUNDS]    # ours and Pinocchio alternate, best of each

Needs a release build (``maturin develop --release``) for meaningful numbers; ratios come
from one run on one machine, absolute times vary with load."""

from __future__ import annotations

import sys
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


def main(rounds: int = 5) -> None:
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
    hand = model.frame_names.index("panda_hand")

    # Ours and Pinocchio's alternate round by round (best of each): a busy spell of this
    # shared machine then slows both sides, not one.
    cases = {
        "frame Jacobian per call": (
            lambda: model.frame_jacobian("panda_hand", q),
            lambda: pin.computeFrameJacobian(pm, data, q, fid), 2000, 1e6, "us"),
        "frame Jacobian per call, by index": (
            lambda: model.frame_jacobian(hand, q),
            lambda: pin.computeFrameJacobian(pm, data, q, fid), 2000, 1e6, "us"),
        "frame Jacobian x1000 (one call vs a Pinocchio loop)": (
            lambda: model.frame_jacobian("panda_hand", qs),
            lambda: [pin.computeFrameJacobian(pm, data, x, fid) for x in qs], 3, 1e3, "ms"),
        "COM Jacobian per call": (
            lambda: model.center_of_mass(q, jacobian=True),
            lambda: pin.jacobianCenterOfMass(pm, data, q), 2000, 1e6, "us"),
        "COM Jacobian x1000 (one call vs a Pinocchio loop)": (
            lambda: model.center_of_mass(qs, jacobian=True),
            lambda: [pin.jacobianCenterOfMass(pm, data, x) for x in qs], 3, 1e3, "ms"),
    }
    got = {k: [np.inf, np.inf] for k in cases}
    for _ in range(rounds):
        for k, (f_ours, f_pin, number, _, _) in cases.items():
            got[k][0] = min(got[k][0], best(f_ours, repeats=3, number=number))
            got[k][1] = min(got[k][1], best(f_pin, repeats=3, number=number))
    for k, (_, _, _, scale, unit) in cases.items():
        o, t = got[k]
        print(f"{k}: ours {o * scale:.3f} {unit}, Pinocchio {t * scale:.3f} {unit}, "
              f"Pinocchio / ours {t / o:.2f}")

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
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
