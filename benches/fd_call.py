"""Forward dynamics per Python call on chain7 (issue 44): ours with `gravity=` as a keyword,
positional and absent, against `pinocchio.aba`, interleaved in one process, best of each.

    python benches/fd_call.py [ROUNDS]

Under the abi3-py39 limited API a keyword cost ~0.2 µs more than the same argument given
positionally (no vectorcall); the extension is built for abi3-py310 since (benches/README.md).
"""

import sys
import timeit

import numpy as np
import pinocchio as pin
from compare_pinocchio import G, chain_ours, chain_pin

m = chain_ours(7)
pm = chain_pin(7)
d = pm.createData()
q = np.full(7, 0.3)
v = np.linspace(-1, 1, 7)
tau = np.cos(np.arange(7.0))
assert np.abs(m.forward_dynamics(q, v, tau, gravity=G) - pin.aba(pm, d, q, v, tau)).max() < 1e-9
fns = {
    "ours gravity=G": lambda: m.forward_dynamics(q, v, tau, gravity=G),
    "ours no gravity": lambda: m.forward_dynamics(q, v, tau),
    "ours positional G": lambda: m.forward_dynamics(q, v, tau, G),
    "pin.aba": lambda: pin.aba(pm, d, q, v, tau),
    "np.empty(7) (floor)": lambda: np.empty(7),
}
best = dict.fromkeys(fns, float("inf"))
for _ in range(int(sys.argv[1]) if len(sys.argv) > 1 else 15):
    for k, f in fns.items():
        best[k] = min(best[k], min(timeit.repeat(f, number=2000, repeat=3)) / 2000 * 1e6)
for k, b in best.items():
    print(f"{k:22s} {b:.3f} µs  ({b / best['pin.aba']:.2f}× pin.aba)")
