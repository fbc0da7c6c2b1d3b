"""`simulate` per call on the bundled chain7 scene (rtol 1e-3, atol 1e-6): over 0-1 s and
over 0-0.05 s, where the per-call overhead (arguments, result conversion) shows. Best of
7 x 50 calls. Compare two builds by running this script alternately with each on PYTHONPATH:

    PYTHONPATH=/path/to/other/python python benches/simulate_call.py other
    python benches/simulate_call.py this
"""

import sys
import time

import pointmass_dyn as pmd


def best(f, n=50, k=7):
    out = []
    for _ in range(k):
        t0 = time.perf_counter()
        for _ in range(n):
            f()
        out.append((time.perf_counter() - t0) / n)
    return min(out)


def main(label):
    scene = pmd.load_scene("chain7")
    for span in [(0.0, 1.0), (0.0, 0.05)]:
        t = best(lambda span=span: pmd.simulate(scene, t_span=span, rtol=1e-3, atol=1e-6))
        r = pmd.simulate(scene, t_span=span, rtol=1e-3, atol=1e-6)
        print(f"{label} span {span}: {t * 1e6:.1f} us per call, nfev {r.nfev}, samples {len(r.t)}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "this")
