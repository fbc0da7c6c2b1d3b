"""Times loading a large URDF and a large scene TOML: model building must be linear in the
number of links/bodies (issue 11, defect 8).

    PYTHONPATH=python python benches/build_scaling.py [--links 150000] [--bodies 250000]

Generates, in a temporary directory, a URDF chain of ``--links`` links (every tenth joint
fixed, so welding is exercised; about 50 MB for 150k) and a scene with ``--bodies`` bodies
(a chain of revolute joints with a fixed body every tenth), then prints the seconds each
load takes. A tenth of the size is timed first: linear loading takes about a tenth of the
time.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import pointmass_dyn as pmd


def write_urdf(path: str, n: int) -> None:
    with open(path, "w") as f:
        f.write('<?xml version="1.0"?>\n<robot name="long_chain">\n')
        for k in range(n):
            f.write(
                f'  <link name="link{k}">\n'
                "    <inertial>\n"
                '      <origin xyz="0.05 0.001 -0.002" rpy="0 0 0"/>\n'
                '      <mass value="1.25"/>\n'
                '      <inertia ixx="0.0021" ixy="0.0" ixz="0.0" iyy="0.0034" iyz="0.0" izz="0.0031"/>\n'
                "    </inertial>\n"
                "  </link>\n"
            )
            if k:
                kind = "fixed" if k % 10 == 0 else "revolute"
                f.write(
                    f'  <joint name="joint{k:07d}" type="{kind}">\n'
                    f'    <parent link="link{k - 1}"/>\n'
                    f'    <child link="link{k}"/>\n'
                    '    <origin xyz="0.1 0 0" rpy="0 0 0.1"/>\n'
                    '    <axis xyz="0 0 1"/>\n'
                    '    <limit lower="-3.14" upper="3.14" effort="100" velocity="10"/>\n'
                    '    <dynamics damping="0.1" friction="0.05"/>\n'
                    "  </joint>\n"
                )
        f.write("</robot>\n")


def write_scene(path: str, n: int) -> None:
    with open(path, "w") as f:
        f.write('name = "long_chain"\n')
        for k in range(n):
            parent = f'parent = "b{k - 1}"\n' if k else ""
            joint = "Fixed" if k % 10 == 9 else "Revolute"
            axis = ", axis = [0, 0, 1]" if joint == "Revolute" else ""
            f.write(
                "[[body]]\n"
                f'name = "b{k}"\n{parent}'
                f'joint = {{ type = "{joint}"{axis} }}\n'
                "translation = [0.1, 0, 0]\n"
                "mass = 1.0\ncom = [0.05, 0, 0]\ninertia_diag = [0.001, 0.002, 0.002]\n"
            )
        f.write('[[effect]]\ntype = "gravity"\ng = [0, 0, -9.81]\n')


def timed(label: str, fn, path: str) -> float:
    t0 = time.perf_counter()
    out = fn(path)
    dt = time.perf_counter() - t0
    size = os.path.getsize(path) / 1e6
    model = out.model if hasattr(out, "q0") else out
    print(f"{label:<32} {size:8.1f} MB  {model.nbodies:>7} bodies  {dt:7.2f} s", flush=True)
    return dt


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--links", type=int, default=150_000)
    ap.add_argument("--bodies", type=int, default=250_000)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        for n in (args.links // 10, args.links):
            p = os.path.join(d, f"chain{n}.urdf")
            write_urdf(p, n)
            timed(f"Model.from_urdf ({n} links)", pmd.Model.from_urdf, p)
            os.remove(p)
        for n in (args.bodies // 10, args.bodies):
            p = os.path.join(d, f"chain{n}.toml")
            write_scene(p, n)
            timed(f"load_scene ({n} bodies)", pmd.load_scene, p)
            os.remove(p)


if __name__ == "__main__":
    main()
