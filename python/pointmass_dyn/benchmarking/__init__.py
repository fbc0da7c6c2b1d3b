"""Work–precision (docs/numerical-stability.md, benches/README.md): error against an
independent reference, wall time, evaluations and steps of :func:`pointmass_dyn.simulate`
tolerance by tolerance, beside SciPy and a fixed-step RK4; or across methods (ours, SciPy's,
MuJoCo's own engine) with the cheapest method per accuracy decade.

    wp = pmd.work_precision("chain7")                        # print(wp.table())
    wp = pmd.work_precision("chain_stiff", methods="all")   # print(wp.cheapest_table())
"""

from ._methods import (
    ALL_METHODS,
    CSV_COLUMNS,
    DECADES,
    DEFAULT_METHODS,
    MUJOCO,
    N_CHECK,
    NUMPY,
    OURS_ADAPTIVE,
    OURS_FIXED,
    SCIPY,
    STYLE,
    cheapest,
    cheapest_text,
    default_dts,
    measure,
    methods_text,
    parse_methods,
    plot_methods,
    ratio_table,
    time_to_reach,
    write_methods_csv,
)
from ._rhs import analytic_jacobian, best_time, rk4_fixed, scene_rhs
from ._work_precision import (
    DEFAULT_TOLERANCES,
    REFERENCE_TOL,
    WorkPrecision,
    plot_work_precision,
    work_precision,
    write_csv,
)

__all__ = [
    "ALL_METHODS",
    "CSV_COLUMNS",
    "DECADES",
    "DEFAULT_METHODS",
    "DEFAULT_TOLERANCES",
    "MUJOCO",
    "NUMPY",
    "N_CHECK",
    "OURS_ADAPTIVE",
    "OURS_FIXED",
    "REFERENCE_TOL",
    "SCIPY",
    "STYLE",
    "WorkPrecision",
    "analytic_jacobian",
    "best_time",
    "cheapest",
    "cheapest_text",
    "default_dts",
    "measure",
    "methods_text",
    "parse_methods",
    "plot_methods",
    "plot_work_precision",
    "ratio_table",
    "rk4_fixed",
    "scene_rhs",
    "time_to_reach",
    "work_precision",
    "write_csv",
    "write_methods_csv",
]
