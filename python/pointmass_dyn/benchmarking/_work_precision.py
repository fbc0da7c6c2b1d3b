"""Work–precision of :func:`pointmass_dyn.simulate`: error against an independent reference,
wall time, right-hand-side evaluations and steps, tolerance by tolerance; beside it SciPy's
RK45 driving the same right-hand side from Python, and a fixed-step classical RK4 (MuJoCo's
integrator) given the same number of evaluations.

    result = pmd.work_precision("chain7")           # a scene, or a bundled scene's name
    print(result.table())
    result.to_csv("chain7.csv"); result.plot("chain7.png")

or ``pointmass-dyn work-precision chain7 --plot wp.png --out table.csv``.

Definitions (all errors on the state ``y = [q; v]``, radians and SI units):

* reference: SciPy ``solve_ivp(method="DOP853", rtol=atol=1e-13, dense_output=True)`` on the
  scene's right-hand side called from Python (``Model.forward_dynamics``, plus the effects'
  generalized forces) — a different method, step sequence and code path from ``simulate``.
  It is cross-checked once against ``simulate`` at ``rtol = atol = 1e-13``
  (``WorkPrecision.reference_check``).
* ``err_final``: ``max|y(T) − y_ref(T)| / max|y_ref(T)|``.
* ``err_dense``: the same over ``n_dense`` equally spaced times (our dense output, i.e. what
  ``t_eval`` returns): ``max_t max|y(t) − y_ref(t)| / max_t max|y_ref(t)|``.
* ``err_energy``: ``max|E − E(0)|`` over the accepted steps divided by the largest kinetic
  energy along the reference (E = kinetic + gravity + springs, as ``energy=True`` records).
* ``time``: best wall time of ``repeats`` calls of ``simulate`` (no output options); SciPy's
  the best of ``scipy_repeats``. Since our RK45 takes exactly SciPy's steps, equal tolerance
  means equal error, and ``speedup = scipy_time / time`` is the time ratio at equal error.
* RK4: ``N = nfev / 4`` equal steps over the span (the same number of evaluations as
  ``simulate`` at that tolerance), errors measured the same way at its step times.
"""

from __future__ import annotations

import csv
import os
from collections.abc import Callable, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import _core
from .._helpers import attach_partial, pyplot, stop_reason
from .._simulation import energies, simulate
from ..errors import InvalidInputError, SimulationError
from ..scenes import load_scene
from ._methods import DECADES, cheapest, cheapest_text, measure, methods_text, parse_methods
from ._rhs import best_time, rk4_fixed, scene_rhs

#: Tolerances of the study (rtol = atol), loose to tight.
DEFAULT_TOLERANCES = tuple(10.0**-k for k in range(3, 13))
#: Reference tolerance (DOP853, and our own cross-check run).
REFERENCE_TOL = 1e-13


def _scene_of(scene: Any):
    if isinstance(scene, _core.Scene):
        return scene
    return load_scene(scene)


def _rel(diff: np.ndarray, ref: np.ndarray) -> float:
    scale = float(np.max(np.abs(ref)))
    err = float(np.max(np.abs(diff)))
    return err / scale if scale > 0 else err


@dataclass
class WorkPrecision:
    """Result of :func:`work_precision`: one row (a dict) per tolerance."""

    scene: str
    t_span: tuple[float, float]
    rows: list[dict] = field(default_factory=list)
    #: How the reference was computed and how well it agrees with ``simulate`` at 1e-13.
    reference_check: dict = field(default_factory=dict)
    #: ``work_precision(..., methods=...)``: one dict per method and setting (see
    #: :mod:`pointmass_dyn.benchmarking`).
    method_rows: list[dict] = field(default_factory=list)
    #: False for the rows of a run that stopped (attached to its exception as ``.result``);
    #: ``message`` then says at which measurement and why.
    success: bool = True
    message: str = "complete"

    def methods_table(self) -> str:
        """Every method's rows (``methods=``), as text."""
        return methods_text(self.scene, self.method_rows)

    def cheapest(self, decades: Sequence[float] | None = None) -> list[dict]:
        """The cheapest method per accuracy decade (``methods=``); see
        :func:`pointmass_dyn.benchmarking.cheapest`."""
        return cheapest(self.method_rows, DECADES if decades is None else decades)

    def cheapest_table(self) -> str:
        return cheapest_text(self.scene, self.method_rows)

    COLUMNS = (
        "tol", "nfev", "steps", "rejected", "time", "err_final", "err_dense", "err_energy",
        "scipy_time", "scipy_nfev", "scipy_err_final", "speedup",
        "rk4_steps", "rk4_err_final", "rk4_err_dense", "rk4_err_energy",
    )

    def column(self, name: str) -> np.ndarray:
        return np.array([r.get(name, np.nan) for r in self.rows], dtype=float)

    def table(self) -> str:
        """A fixed-width text table (times in ms)."""
        head = (f"{'tol':>7} {'nfev':>7} {'steps':>6} {'time ms':>8} {'err_final':>9} "
                f"{'err_dense':>9} {'err_E':>9} {'scipy ms':>9} {'speedup':>7} "
                f"{'rk4 err':>9}")
        lines = [f"{self.scene}: t = {self.t_span[0]:g} .. {self.t_span[1]:g} s; "
                 f"reference {self.reference_check.get('method', '?')}; "
                 f"ours at {REFERENCE_TOL:g} vs reference: "
                 f"{self.reference_check.get('err_final', float('nan')):.1e} (final), "
                 f"{self.reference_check.get('err_dense', float('nan')):.1e} (dense)", head]

        def f(x, spec, width):
            return format(x, spec) if x is not None and np.isfinite(x) else "-".rjust(width)

        for r in self.rows:
            lines.append(
                f"{r['tol']:>7.0e} {r['nfev']:>7d} {r['steps']:>6d} {r['time'] * 1e3:>8.2f} "
                f"{f(r['err_final'], '9.2e', 9)} {f(r['err_dense'], '9.2e', 9)} "
                f"{f(r['err_energy'], '9.2e', 9)} "
                f"{f(r.get('scipy_time', np.nan) * 1e3, '9.1f', 9)} "
                f"{f(r.get('speedup', np.nan), '7.1f', 7)} "
                f"{f(r.get('rk4_err_final', np.nan), '9.2e', 9)}"
            )
        return "\n".join(lines)

    def to_csv(self, path: str | os.PathLike) -> None:
        write_csv([self], path)

    def plot(self, path: str | os.PathLike | None = None):
        """Error against wall time and against tolerance; saves to ``path`` if given."""
        return plot_work_precision([self], path)


@contextmanager
def _keeping_partial(out: WorkPrecision, progress):
    """Yields ``say(msg)`` (``progress``, remembering the measurement under way); any exception
    inside (Ctrl-C and a raising ``progress`` included) leaves with ``out``, the rows measured
    so far, as its ``.result`` (``success=False``, ``message``: where and why it stopped)."""
    doing = ["setting up"]

    def say(msg: str) -> None:
        doing[0] = msg
        if progress is not None:
            progress(msg)

    try:
        yield say
    except BaseException as exc:
        done = len(out.rows) + len(out.method_rows)
        out.success = False
        out.message = f"stopped at '{doing[0]}' after {done} rows: {stop_reason(exc)}"
        attach_partial(exc, out, f"pointmass_dyn: work_precision {out.message}; the rows "
                       "measured are in this exception's .result")
        raise


def _tolerances_arg(tolerances) -> list[float]:
    """Real tolerances in (0, 1), or ``InvalidInputError`` naming the argument."""
    given = repr(tolerances)[:80]
    try:
        arr = np.asarray(tolerances)
    except (ValueError, TypeError):
        arr = None
    if arr is None or arr.ndim > 1 or arr.dtype.kind not in "iuf":
        raise InvalidInputError(f"tolerances: expected a sequence of real numbers > 0, got {given}")
    tols = [float(x) for x in np.atleast_1d(arr)]
    if not all(0 < t < 1 for t in tols):
        raise InvalidInputError(f"tolerances: expected numbers in (0, 1), got {given}")
    return tols


def _rk4_row(rhs, span, y0, nfev, ref, total_energy, e_scale) -> dict[str, Any]:
    """Classical RK4 with the evaluations ``simulate`` used (``nfev / 4`` steps): its errors
    against the reference, or infinities when it blows up."""
    y_ref_end = ref.y[:, -1]
    n = max(1, int(round(nfev / 4)))
    with np.errstate(all="ignore"):
        try:
            ts, ys = rk4_fixed(rhs, span, y0, n)
            ok = bool(np.all(np.isfinite(ys)))
        except Exception:  # a blown-up RK4 state makes the dynamics refuse it
            ts, ys, ok = None, None, False
    if not ok:
        return dict(rk4_steps=n, rk4_err_final=np.inf, rk4_err_dense=np.inf,
                    rk4_err_energy=np.inf)
    y_at = ref.sol(ts).T
    pick = np.unique(np.linspace(0, n, min(n + 1, 2001)).astype(int))
    e4 = np.array([total_energy(ys[k]) for k in pick])
    return dict(rk4_steps=n, rk4_err_final=_rel(ys[-1] - y_ref_end, y_ref_end),
                rk4_err_dense=_rel(ys - y_at, y_at),
                rk4_err_energy=float(np.max(np.abs(e4 - e4[0])) / e_scale))


# About 95 lines: the reference, then one measurement row per tolerance whose columns read
# top to bottom in the order the table prints them; the RK4 column is `_rk4_row`.
def work_precision(
    scene: Any,
    tolerances: Sequence[float] = DEFAULT_TOLERANCES,
    *,
    t_end: float | None = None,
    repeats: int = 5,
    scipy: bool = True,
    scipy_repeats: int = 2,
    rk4: bool = True,
    n_dense: int = 1001,
    reference_check: bool = True,
    progress: Callable[[str], Any] | None = None,
    methods: Any = None,
    dts: Sequence[float] | None = None,
) -> WorkPrecision:
    """Measures ``simulate`` on ``scene`` (a :class:`Scene`, a scene file or a bundled name)
    at ``rtol = atol = tol`` for each tolerance; see the module docstring for the
    definitions. ``t_end`` overrides the scene's end time (default: the scene's, else 10 s).
    ``scipy`` / ``rk4`` switch the comparison lines off (they cost Python time, up to
    seconds per tolerance). ``progress(msg)`` is called before each measurement.

    ``methods`` (``"all"`` or names such as ``["RK45", "Radau", "scipy:DOP853",
    "mujoco:RK4"]``) measures those methods instead, into ``method_rows`` (the per-tolerance
    ``rows`` above are then not measured): adaptive ones over ``tolerances``, fixed-step ones
    over ``dts`` (default :func:`~pointmass_dyn.benchmarking.default_dts`); see
    :mod:`pointmass_dyn.benchmarking` for the definitions, and
    ``cheapest_table()`` for the cheapest method per accuracy decade.

    Ctrl-C, or a ``progress`` that raises, stops it (between or within measurements): the
    exception propagates as itself with the rows measured so far attached as ``.result`` (a
    :class:`WorkPrecision` with ``success=False`` and ``message`` naming the measurement
    under way and the reason)."""
    try:
        from scipy.integrate import solve_ivp
    except ImportError as exc:
        raise ImportError(
            "work_precision needs SciPy for its independent reference solution: "
            "pip install 'pointmass-dyn[bench]'"
        ) from exc

    sc = _scene_of(scene)
    tolerances = _tolerances_arg(tolerances)
    if methods is not None:
        methods = parse_methods(methods)
        if dts is not None:
            dts = _tolerances_arg(dts) if np.ndim(dts) else None
            if dts is None:
                raise InvalidInputError("dts: expected a sequence of steps in (0, 1) s")
    t0, t1 = sc.t_span or (0.0, 10.0)
    if t_end is not None:
        if isinstance(t_end, (str, bytes, complex)) or not np.isrealobj(t_end):
            raise InvalidInputError(f"t_end: expected a real number, got {t_end!r}")
        t1 = float(t_end)
    span = (float(t0), float(t1))
    model = sc.model
    nq = model.nq
    y0 = np.concatenate([sc.q0, sc.v0])
    rhs = scene_rhs(sc)
    t_grid = np.linspace(span[0], span[1], n_dense)

    out = WorkPrecision(scene=sc.name, t_span=span)
    with _keeping_partial(out, progress) as say:
        say(f"{sc.name}: reference (DOP853, rtol = atol = {REFERENCE_TOL:g})")
        ref = solve_ivp(rhs, span, y0, method="DOP853", rtol=REFERENCE_TOL, atol=REFERENCE_TOL,
                        dense_output=True)
        if not ref.success:
            raise SimulationError(f"{sc.name}: the DOP853 reference failed: {ref.message}")
        y_ref_end = ref.y[:, -1]
        y_ref_grid = ref.sol(t_grid).T
        kinetic = max(model.kinetic_energy(y[:nq], y[nq:]) for y in y_ref_grid)
        e_scale = kinetic if kinetic > 0 else 1.0

        def total_energy(y):
            return energies(sc, y[:nq], y[nq:])["total"]

        out.reference_check = {"method": f"DOP853 rtol=atol={REFERENCE_TOL:g}",
                               "nfev": int(ref.nfev), "energy_scale": float(e_scale)}
        if reference_check:
            say(f"{sc.name}: cross-check, simulate at {REFERENCE_TOL:g}")
            ours = simulate(sc, span, rtol=REFERENCE_TOL, atol=REFERENCE_TOL, t_eval=t_grid)
            y_ours = np.hstack([ours.q, ours.v])
            out.reference_check.update(
                err_final=_rel(y_ours[-1] - y_ref_end, y_ref_end),
                err_dense=_rel(y_ours - y_ref_grid, y_ref_grid),
                ours_nfev=int(ours.nfev),
            )
        if methods is not None:
            measure(sc, span, ref.sol, methods, tolerances, dts, repeats, scipy_repeats, say,
                    out.method_rows)
            return out

        for tol in tolerances:
            row: dict[str, Any] = {"tol": float(tol)}
            say(f"{sc.name}: simulate at {tol:g}")
            t_run, r = best_time(lambda: simulate(sc, span, rtol=tol, atol=tol), repeats)
            if not r.success:
                row.update(tol=float(tol), nfev=r.nfev, steps=r.n_accepted, rejected=r.n_rejected,
                           time=t_run, err_final=np.nan, err_dense=np.nan, err_energy=np.nan,
                           message=r.message)
                out.rows.append(row)
                continue
            y_end = np.concatenate([r.q[-1], r.v[-1]])
            dense = simulate(sc, span, rtol=tol, atol=tol, t_eval=t_grid)
            y_dense = np.hstack([dense.q, dense.v])
            withe = simulate(sc, span, rtol=tol, atol=tol, energy=True)
            e = np.asarray(withe.energy)
            row.update(
                nfev=int(r.nfev), steps=int(r.n_accepted), rejected=int(r.n_rejected), time=t_run,
                err_final=_rel(y_end - y_ref_end, y_ref_end),
                err_dense=_rel(y_dense - y_ref_grid, y_ref_grid),
                err_energy=float(np.max(np.abs(e - e[0])) / e_scale),
                message=r.message,
            )
            if scipy:
                say(f"{sc.name}: SciPy RK45 at {tol:g}")
                t_sp, s = best_time(
                    lambda: solve_ivp(rhs, span, y0, method="RK45", rtol=tol, atol=tol),
                    scipy_repeats)
                row.update(scipy_time=t_sp, scipy_nfev=int(s.nfev),
                           scipy_err_final=_rel(s.y[:, -1] - y_ref_end, y_ref_end),
                           speedup=t_sp / t_run)
            if rk4:
                say(f"{sc.name}: RK4 with {r.nfev} evaluations")
                row.update(_rk4_row(rhs, span, y0, r.nfev, ref, total_energy, e_scale))
            out.rows.append(row)
        return out


def write_csv(results: Sequence[WorkPrecision], path: str | os.PathLike) -> None:
    """All rows of ``results`` in one CSV file, a ``scene`` column first."""
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(("scene",) + WorkPrecision.COLUMNS)
        for res in results:
            for r in res.rows:
                w.writerow((res.scene,) + tuple(
                    repr(r[c]) if isinstance(r.get(c), float) else r.get(c, "")
                    for c in WorkPrecision.COLUMNS))


def plot_work_precision(results: Sequence[WorkPrecision], path=None, title: str = ""):
    """One row per scene: error against wall time (ours, SciPy RK45 on our right-hand side,
    fixed-step RK4 with our number of evaluations, drawn at our time), and errors against the
    tolerance."""
    plt = pyplot()
    n = len(results)
    fig, axes = plt.subplots(n, 2, figsize=(10, 3.4 * n + 0.4), squeeze=False)
    for (ax_t, ax_tol), res in zip(axes, results):
        tol = res.column("tol")
        tm = res.column("time") * 1e3
        ef = res.column("err_final")
        ax_t.loglog(tm, ef, "o-", color="C0", label="ours (simulate), final")
        ax_t.loglog(tm, res.column("err_dense"), "s--", color="C0", mfc="none", ms=4,
                    label="ours, max over dense output")
        if np.isfinite(res.column("scipy_time")).any():
            ax_t.loglog(res.column("scipy_time") * 1e3, res.column("scipy_err_final"), "o-",
                        color="C3", label="SciPy RK45, our rhs from Python")
        if np.isfinite(res.column("rk4_err_final")).any():
            r4 = res.column("rk4_err_final")
            r4 = np.where(np.isfinite(r4), r4, np.nan)
            ax_t.loglog(tm, r4, "^-", color="C2", label="fixed-step RK4, same nfev")
        floor = res.reference_check.get("err_final")
        if floor is not None and np.isfinite(floor) and floor > 0:
            ax_t.axhline(floor, color="gray", ls=":", lw=1,
                         label=f"reference floor (ours at {REFERENCE_TOL:g} vs DOP853)")
        # Loose tolerances cost about the same time, so their points crowd together:
        # alternate the labels' sides of the curve so that neighbours never overlap.
        for k, (x, y, t) in enumerate(zip(tm, ef, tol)):
            right = k % 2 == 0
            ax_t.annotate(f"{t:.0e}", (x, y), fontsize=6, textcoords="offset points",
                          xytext=(4, 2) if right else (-4, -2), ha="left" if right else "right",
                          va="bottom" if right else "top")
        ax_t.set_xlabel("wall time (ms)")
        ax_t.set_ylabel("relative error")
        ax_t.set_title(f"{res.scene}, {res.t_span[1] - res.t_span[0]:g} s", fontsize=9)
        ax_t.grid(alpha=0.3, which="both")
        ax_t.legend(fontsize=7)
        ax_tol.loglog(tol, ef, "o-", color="C0", label="final state")
        ax_tol.loglog(tol, res.column("err_dense"), "s--", color="C0", mfc="none", ms=4,
                      label="max over dense output")
        ax_tol.loglog(tol, res.column("err_energy"), "d-", color="C1", label="energy")
        ax_tol.loglog(tol, tol, ":", color="gray", label="error = tol")
        ax_tol.invert_xaxis()
        ax_tol.set_xlabel("rtol = atol")
        ax_tol.grid(alpha=0.3, which="both")
        ax_tol.legend(fontsize=7)
    if title:
        fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return fig
