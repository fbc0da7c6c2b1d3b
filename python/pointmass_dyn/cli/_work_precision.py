"""``pointmass-dyn work-precision``: error, time and evaluations of ``simulate`` against
tolerance beside SciPy and a fixed-step RK4, or across methods (``--methods``)."""

from __future__ import annotations

import sys

from ..benchmarking import (
    DEFAULT_TOLERANCES,
    plot_methods,
    plot_work_precision,
    work_precision,
    write_csv,
    write_methods_csv,
)


def add_parser(sub):
    """The ``work-precision`` subcommand."""
    wp = sub.add_parser(
        "work-precision",
        help="error, time and evaluations of simulate against tolerance, beside SciPy RK45 "
             "and fixed-step RK4",
    )
    wp.add_argument("scene", nargs="+", help="one or more scene files or bundled names")
    wp.add_argument("--plot", default=None, help="write the work-precision plot (PNG)")
    wp.add_argument("--out", default=None, help="write the table to a .csv file")
    wp.add_argument("--t-end", type=float, default=None, help="end time (s); default: the scene's")
    wp.add_argument("--tolerances", type=float, nargs="+", default=None,
                    help="rtol = atol values (default 1e-3 ... 1e-12)")
    wp.add_argument("--repeats", type=int, default=5, help="timing runs of simulate (best kept)")
    wp.add_argument("--scipy-repeats", type=int, default=2, help="timing runs of SciPy RK45")
    wp.add_argument("--no-scipy", action="store_true", help="skip SciPy RK45 (the slow part)")
    wp.add_argument("--no-rk4", action="store_true", help="skip the fixed-step RK4 line")
    wp.add_argument("--methods", nargs="+", default=None,
                    help="compare methods instead: 'all' or names among RK45 DOP853 Radau "
                         "auto RK4 Euler scipy:RK45 scipy:DOP853 scipy:Radau mujoco:RK4 "
                         "mujoco:Euler mujoco:implicitfast numpy:RK4; prints the cheapest "
                         "method per accuracy decade")
    wp.add_argument("--dt", type=float, nargs="+", default=None,
                    help="fixed steps for RK4/Euler/MuJoCo (default: a sweep per method)")
    wp.add_argument("-v", "--verbose", action="store_true", help="report progress on stderr")
    wp.set_defaults(func=cmd_work_precision)
    return wp


def cmd_work_precision(args) -> int:
    tols = DEFAULT_TOLERANCES if not args.tolerances else tuple(args.tolerances)
    results = []
    for name in args.scene:
        def say(msg: str) -> None:
            if args.verbose:
                print(f"  {msg}", file=sys.stderr, flush=True)

        res = work_precision(
            name, tols, t_end=args.t_end, repeats=args.repeats, scipy=not args.no_scipy,
            scipy_repeats=args.scipy_repeats, rk4=not args.no_rk4, progress=say,
            methods=args.methods, dts=args.dt,
        )
        results.append(res)
        print(res.table() if args.methods is None else
              res.methods_table() + "\n\n" + res.cheapest_table())
        print()
    writer, plotter = write_csv, plot_work_precision
    if args.methods is not None:
        writer, plotter = write_methods_csv, plot_methods
    if args.out:
        writer(results, args.out)
        print(f"table written to {args.out}")
    if args.plot:
        plotter(results, args.plot)
        print(f"plot written to {args.plot}")
    return 0
