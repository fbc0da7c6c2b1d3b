"""Former module path (the flat layout before the subpackages) of work–precision, kept so that code
importing it keeps working; the names live in :mod:`pointmass_dyn.benchmarking`."""

from .benchmarking import (
    DEFAULT_TOLERANCES,
    REFERENCE_TOL,
    WorkPrecision,
    plot_work_precision,
    rk4_fixed,
    scene_rhs,
    work_precision,
    write_csv,
)

__all__ = [
    "DEFAULT_TOLERANCES",
    "REFERENCE_TOL",
    "WorkPrecision",
    "plot_work_precision",
    "rk4_fixed",
    "scene_rhs",
    "work_precision",
    "write_csv",
]
