"""The cost of starting: `import pointmass_dyn` and the first `simulate` in a process against
the later ones (docs/benchmarks.md, "First call"). Each measurement runs in a fresh
interpreter; the medians over `--runs` processes are printed.

    python benches/first_call.py --runs 15
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys

CHILD = r"""
import json, time
t0 = time.perf_counter()
import pointmass_dyn as pmd
t1 = time.perf_counter()
scene = pmd.load_scene("chain7")
calls = []
for _ in range(6):
    a = time.perf_counter()
    pmd.simulate(scene, (0.0, 0.5))
    calls.append(time.perf_counter() - a)
print(json.dumps({"import": t1 - t0, "first": calls[0], "later": min(calls[1:])}))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=15, help="fresh processes (default 15)")
    args = ap.parse_args()
    rows = [json.loads(subprocess.run([sys.executable, "-c", CHILD], check=True,
                                      capture_output=True, text=True).stdout)
            for _ in range(args.runs)]
    med = {k: statistics.median(r[k] for r in rows) for k in rows[0]}
    ratio = statistics.median(r["first"] / r["later"] for r in rows)
    print(f"import pointmass_dyn: {med['import'] * 1e3:.1f} ms")
    print(f"simulate chain7 (0, 0.5): first call {med['first'] * 1e3:.2f} ms, "
          f"later calls {med['later'] * 1e3:.2f} ms, first/later {ratio:.1f}x "
          f"(medians of {args.runs} processes)")


if __name__ == "__main__":
    main()
