"""Analytic dynamics derivatives per Python call: ours against Pinocchio's
computeRNEADerivatives and computeABADerivatives on identical models (checked to agree first),
in one process.

    python benches/derivatives.py            # chain7, Panda, chain100, chain300
    python benches/derivatives.py --quick    # fewer repeats

chainN as in compare_pinocchio.py (docs/benchmarks.md); Panda from example-robot-data
(mirrored joint by joint from Pinocchio's model). q = 0.3 rad (Panda: a random
configuration), random v, τ and a; gravity (0, 0, −9.81). Ratios are measured in one run:
compare ratios, not µs.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys

import numpy as np
import pinocchio as pin
import pointmass_dyn as pmd
from compare_pinocchio import G, best_us, chain_ours, chain_pin

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))


def panda():
    from test_pinocchio import model_from_pinocchio, panda_urdf

    pm = pin.buildModelFromUrdf(panda_urdf())
    pm.gravity.linear = G
    return model_from_pinocchio(pm), pm


def rel(a, b):
    return np.abs(a - b).max() / max(1.0, np.abs(b).max())


def rows(repeat):
    rng = np.random.default_rng(0)
    models = [("chain7", chain_ours(7), chain_pin(7)), ("panda", *panda()),
              ("chain100", chain_ours(100), chain_pin(100)),
              ("chain300", chain_ours(300), chain_pin(300))]
    for name, ours, pm in models:
        data = pm.createData()
        n = pm.nv
        q = np.full(n, 0.3) if name.startswith("chain") else pin.randomConfiguration(pm)
        v, tau, a = (rng.uniform(-1, 1, n) for _ in range(3))
        # Same numbers first.
        mine = ours.forward_dynamics_derivatives(q, v, tau, G)
        theirs = pin.computeABADerivatives(pm, data, q, v, tau)
        assert max(rel(x, y) for x, y in zip(mine[:2], theirs[:2])) < 1e-9
        mine = ours.inverse_dynamics_derivatives(q, v, a, G)
        theirs = pin.computeRNEADerivatives(pm, data, q, v, a)
        assert max(rel(x, y) for x, y in zip(mine[:2], theirs[:2])) < 1e-9
        number = max(20, 20000 // n)
        pairs = {
            "forward (ABA) derivatives": (
                lambda: ours.forward_dynamics_derivatives(q, v, tau, G),
                lambda: pin.computeABADerivatives(pm, data, q, v, tau),
            ),
            "inverse (RNEA) derivatives": (
                lambda: ours.inverse_dynamics_derivatives(q, v, a, G),
                lambda: pin.computeRNEADerivatives(pm, data, q, v, a),
            ),
        }
        for fn, (f_ours, f_pin) in pairs.items():
            t_ours = best_us(f_ours, number, repeat)
            t_pin = best_us(f_pin, number, repeat)
            yield name, fn, t_ours, t_pin, t_ours / t_pin


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    repeat = 3 if args.quick else 7
    print(f"# {platform.processor() or platform.machine()}, Python {platform.python_version()}, "
          f"pin {pin.__version__}, pointmass_dyn {pmd.__version__}")
    print("\n| model | function | pointmass_dyn (µs) | pinocchio (µs) | ours / pinocchio |")
    print("|---|---|---:|---:|---:|")
    for name, fn, a, b, r in rows(repeat):
        print(f"| {name} | {fn} | {a:.2f} | {b:.2f} | {r:.2f} |")


if __name__ == "__main__":
    main()
