"""``pointmass-dyn``, the command line: one module per command (``_simulate``, ``_animate``,
``_sweep``, ``_balance``, ``_design``, ``_work_precision``, ``_scenes``, ``_point_masses``), each with its
``add_parser`` and ``cmd_*``; :func:`main` is the console entry point."""

from __future__ import annotations

import argparse
import sys

from ..errors import PointMassDynError
from . import (
    _animate,
    _balance,
    _design,
    _point_masses,
    _scenes,
    _simulate,
    _sweep,
    _work_precision,
)

__all__ = ["COMMANDS", "build_parser", "main"]

#: The subcommands in the order ``--help`` lists them.
COMMANDS = (
    _simulate, _point_masses, _scenes, _work_precision, _balance, _design, _sweep, _animate,
)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="pointmass-dyn",
        description="Multibody dynamics with equimomental point masses and DeNOC matrices.",
    )
    sub = p.add_subparsers(dest="command", required=True)
    for command in COMMANDS:
        command.add_parser(sub)
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except PointMassDynError as exc:
        print(f"pointmass-dyn: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # writing --out / --plot (inputs are read with our own errors)
        print(f"pointmass-dyn: error: cannot write the output file: {exc}", file=sys.stderr)
        return 2

