"""A loop of ``simulate`` calls for callgrind: the fixed cost of a call, in instructions.

    valgrind --tool=callgrind python benches/simulate_call_callgrind.py WHICH N

WHICH: ``plain`` (``pmd.simulate(sc, (0, 1e-6), rtol=1e-4, atol=1e-4)`` on chain7: 8
evaluations), ``teval`` (the same with ``t_eval=np.linspace(0, 1e-6, 21)``), ``core`` /
``coreteval`` (``_core.simulate_scene`` with those arguments: the binding alone; add
``--toggle-collect='*__pyfunction_simulate_scene*'``). N calls after one warm-up; subtract
a run with N = 0 (or, with the toggle, divide by N + 1).
"""

from __future__ import annotations

import sys

import numpy as np
import pointmass_dyn as pmd
from pointmass_dyn import _core


def main() -> None:
    which, n = sys.argv[1], int(sys.argv[2])
    sc = pmd.load_scene("chain7")
    te = np.linspace(0, 1e-6, 21)
    calls = {
        "plain": lambda: pmd.simulate(sc, (0, 1e-6), rtol=1e-4, atol=1e-4),
        "teval": lambda: pmd.simulate(sc, (0, 1e-6), t_eval=te, rtol=1e-4, atol=1e-4),
        "core": lambda: _core.simulate_scene(sc, (0, 1e-6), 1e-4, 1e-4),
        "coreteval": lambda: _core.simulate_scene(sc, (0, 1e-6), 1e-4, 1e-4, t_eval=te),
    }
    call = calls[which]
    call()
    for _ in range(n):
        call()


if __name__ == "__main__":
    main()
