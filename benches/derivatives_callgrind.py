"""A loop of derivative (or dynamics) calls for callgrind (instruction counts per Python call,
steadier than times on a shared machine): ours or Pinocchio's, forward or inverse, on chain7 or
Panda.

    valgrind --tool=callgrind python benches/derivatives_callgrind.py WHICH MODEL N

WHICH: ``oi``/``of`` (ours, inverse/forward), ``pi``/``pf`` (Pinocchio's
computeRNEADerivatives/computeABADerivatives); ``ofd``/``pfd``: forward dynamics itself, ours
with ``gravity=`` as a keyword (the call of benches/fd_call.py) or ``pin.aba``. MODEL:
``chain7`` or ``panda``; N calls after one warm-up. Divide the binding's inclusive cost by
N + 1, or subtract a run with N = 0.
"""

from __future__ import annotations

import os
import sys

import numpy as np
import pinocchio as pin

sys.path.insert(0, os.path.dirname(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
from compare_pinocchio import G, chain_ours, chain_pin


def main() -> None:
    which, model, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
    if model == "panda":
        from test_pinocchio import model_from_pinocchio, panda_urdf

        pm = pin.buildModelFromUrdf(panda_urdf())
        pm.gravity.linear = G
        ours = model_from_pinocchio(pm)
        q = pin.randomConfiguration(pm)
    else:
        ours, pm = chain_ours(7), chain_pin(7)
        q = np.full(7, 0.3)
    data = pm.createData()
    rng = np.random.default_rng(0)
    v, tau, a = (rng.uniform(-1, 1, pm.nv) for _ in range(3))
    f = {
        "oi": lambda: ours.inverse_dynamics_derivatives(q, v, a, G),
        "of": lambda: ours.forward_dynamics_derivatives(q, v, tau, G),
        "pi": lambda: pin.computeRNEADerivatives(pm, data, q, v, a),
        "pf": lambda: pin.computeABADerivatives(pm, data, q, v, tau),
        "ofd": lambda: ours.forward_dynamics(q, v, tau, gravity=G),
        "pfd": lambda: pin.aba(pm, data, q, v, tau),
    }[which]
    f()
    for _ in range(n):
        f()


if __name__ == "__main__":
    main()
