"""Work–precision across methods: every integrator of ours, SciPy's on our right-hand side and
MuJoCo's own engine on the same scene, against the same reference; and the cheapest method
per accuracy decade.

    wp = pmd.work_precision("chain_stiff", methods="all")
    print(wp.methods_table()); print(wp.cheapest_table())

or ``pointmass-dyn work-precision chain7 chain_stiff --methods all --plot wp.png``.

Methods (names as ``methods=`` takes them):

* ours: ``RK45``, ``DOP853``, ``Vern9``, ``Adams``, ``Radau``, ``auto`` (adaptive, swept over ``tolerances``,
  rtol = atol) and ``RK4``, ``Euler`` (fixed step, swept over ``dt``), all through
  :func:`pointmass_dyn.simulate` (``method=``; a method this build does not have is skipped
  with a note);
* ``scipy:RK45``, ``scipy:DOP853``, ``scipy:Radau``, ``scipy:LSODA``: ``scipy.integrate.solve_ivp`` on
  :func:`~pointmass_dyn.benchmarking.scene_rhs` (our forward dynamics called from Python).
  Radau gets an analytic Jacobian when the model has ``forward_dynamics_derivatives`` and
  the scene only gravity, springs and dampers on 1-dof joints (``jac`` column says
  ``analytic``), else SciPy's finite differences (``fd``);
* ``mujoco:RK4``, ``mujoco:Euler``, ``mujoco:implicitfast``: MuJoCo's ``mj_step`` (run by
  ``mujoco.rollout``, one thread) on the model :func:`pointmass_dyn.to_mjcf` writes, states
  converted both ways by :mod:`pointmass_dyn.io`; swept over ``dt``;
* ``numpy:RK4``: the classical RK4 of :func:`~pointmass_dyn.benchmarking.rk4_fixed` in
  NumPy on ``scene_rhs`` (slow; a check of MuJoCo's RK4 error, not a contender).

Every row: ``err`` = ``max_k max|y(t_k) − y_ref(t_k)| / max_k max|y_ref(t_k)|`` over the
check times ``t_k = t0 + k (t1 − t0) / n_check`` (k = 0 … n_check; adaptive methods through
``t_eval``, fixed-step methods at their own steps: every ``dt`` divides the check interval),
``err_final`` the same at t1 alone, ``time`` the best wall time of ``repeats`` runs (the
run with ``t_eval`` on the check grid, 21 points: the output costs nothing measurable),
``nfev`` right-hand-side evaluations (MuJoCo: stages × steps), ``steps`` accepted steps
(0 for SciPy, which does not report them). The reference is the one of
:func:`~pointmass_dyn.work_precision`: SciPy DOP853 at 1e-13.

The cheapest method at an accuracy ``e``: per method, the time to reach ``err ≤ e`` read off
its time–error curve by log–log interpolation between the two settings around ``e`` (or the
cheapest setting already below ``e``); the method with the least such time wins. A method
that never reaches ``e`` has no time there.
"""

from __future__ import annotations

import csv
import math
import time
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

from .._helpers import pyplot
from .._simulation import simulate
from ..errors import InvalidInputError
from ..io import from_mujoco_state, layout, to_mjcf, to_mujoco_state
from ._rhs import analytic_jacobian, best_time, rk4_fixed, scene_rhs

OURS_ADAPTIVE = ("RK45", "DOP853", "Vern9", "Adams", "Radau", "auto")
OURS_FIXED = ("RK4", "Euler")
SCIPY = ("scipy:RK45", "scipy:DOP853", "scipy:Radau", "scipy:LSODA")
MUJOCO = ("mujoco:RK4", "mujoco:Euler", "mujoco:implicitfast")
NUMPY = ("numpy:RK4",)
ALL_METHODS = OURS_ADAPTIVE + OURS_FIXED + SCIPY + MUJOCO + NUMPY
#: ``methods="all"``: everything but the slow NumPy RK4 check line.
DEFAULT_METHODS = OURS_ADAPTIVE + OURS_FIXED + SCIPY + MUJOCO
#: Accuracy decades of the cheapest-method table.
DECADES = tuple(10.0**-k for k in range(3, 11))
N_CHECK = 20


def parse_methods(methods: Any) -> list[str]:
    """``"all"``, one name, or a sequence of names (see the module docstring)."""
    if isinstance(methods, str):
        if methods == "all":
            return list(DEFAULT_METHODS)
        methods = [m.strip() for m in methods.split(",") if m.strip()]
    try:
        names = list(methods)
    except TypeError:
        raise InvalidInputError(f"methods: expected 'all' or a sequence of method names, got "
                                f"{methods!r}") from None
    if not names:
        raise InvalidInputError("methods: expected at least one method name, got an empty list")
    if "all" in names:
        names = [m for m in names if m != "all"] + list(DEFAULT_METHODS)
    for m in names:
        if not isinstance(m, str) or m not in ALL_METHODS:
            raise InvalidInputError(f"methods: expected names among {', '.join(ALL_METHODS)} "
                                    f"or 'all', got {m!r}")
    return list(dict.fromkeys(names))


def default_dts(t_span: tuple[float, float], method: str, n_check: int = N_CHECK,
                max_steps: int = 400_000) -> list[float]:
    """Fixed steps to sweep: spans divided into n_check × m steps, m growing ~×2.15 per point
    (three per decade) from 5, up to ``max_steps`` steps (RK4) or half that (Euler,
    implicitfast: first order, they reach 1e-4 at best here anyway)."""
    span = t_span[1] - t_span[0]
    cap = max_steps // (1 if method.endswith("RK4") else 2)
    out = []
    j = 0
    while True:
        m = int(round(5 * 10 ** (j / 3)))
        n = n_check * m
        if n > cap:
            break
        out.append(span / n)
        j += 1
    return out


class _Reference:
    """The reference solution on the check grid."""

    def __init__(self, sol, span, n_check):
        self.grid = np.linspace(span[0], span[1], n_check + 1)
        self.y = sol(self.grid).T            # (n_check + 1, n)
        self.scale = float(np.max(np.abs(self.y)))
        self.scale_final = float(np.max(np.abs(self.y[-1])))

    def errors(self, y: np.ndarray) -> tuple[float, float]:
        """(err over the check grid, err at the end) of states y (n_check + 1, n)."""
        if y.shape != self.y.shape or not np.all(np.isfinite(y)):
            return math.inf, math.inf
        d = np.abs(y - self.y)
        return float(np.max(d)) / self.scale, float(np.max(d[-1])) / self.scale_final


def _row(method, tol=math.nan, dt=math.nan, **kw) -> dict:
    r = dict(method=method, tol=float(tol), dt=float(dt), nfev=0, steps=0, time=math.nan,
             err=math.inf, err_final=math.inf, jac="", note="")
    r.update(kw)
    return r


# ----------------------------------------------------------------------------- ours


def _ours(sc, span, ref: _Reference, method, settings, repeats, say) -> list[dict]:
    fixed = method in OURS_FIXED
    rows = []
    for s in settings:
        kw = dict(method=method, dt=s) if fixed else dict(method=method, rtol=s, atol=s)
        say(f"{sc.name}: ours {method} at {'dt' if fixed else 'tol'} {s:g}")
        try:
            t, r = best_time(lambda: simulate(sc, span, t_eval=ref.grid, **kw),
                         repeats)
        except TypeError as exc:          # this build's simulate has no method= / dt=
            if method != "RK45":
                return [_row(method, note=f"not available: {exc}")]
            kw.pop("method")              # RK45 is what simulate always did
            t, r = best_time(lambda: simulate(sc, span, t_eval=ref.grid, **kw), repeats)
        except InvalidInputError as exc:
            if "method" in str(exc) and s == settings[0]:
                return [_row(method, note=f"not available: {exc}")]
            raise
        y = np.hstack([r.q, r.v]) if r.success and len(r.t) == len(ref.grid) else None
        err, errf = ref.errors(y) if y is not None else (math.inf, math.inf)
        extra = {k: getattr(r, k) for k in ("njev", "nlu") if hasattr(r, k)}
        rows.append(_row(method, **({"dt": s} if fixed else {"tol": s}), nfev=int(r.nfev),
                         steps=int(r.n_accepted), time=t, err=err, err_final=errf,
                         note="" if r.success else r.message[:120], **extra))
        if fixed and err < 1e-12:
            break
    return rows


# ----------------------------------------------------------------------------- SciPy


def _scipy(sc, span, y0, rhs, ref, method, tols, repeats, say) -> list[dict]:
    from scipy.integrate import solve_ivp

    name = method.split(":")[1]
    kw: dict[str, Any] = {}
    jac_kind = ""
    if name == "Radau":
        jac = analytic_jacobian(sc)
        jac_kind = "analytic" if jac is not None else "fd"
        if jac is not None:
            kw["jac"] = jac
    rows = []
    for tol in tols:
        say(f"{sc.name}: {method} at {tol:g}")
        t, s = best_time(lambda: solve_ivp(rhs, span, y0, method=name, rtol=tol, atol=tol,
                                       t_eval=ref.grid, **kw), repeats)
        ok = s.success and s.y.shape[1] == len(ref.grid)
        err, errf = ref.errors(s.y.T) if ok else (math.inf, math.inf)
        rows.append(_row(method, tol=tol, nfev=int(s.nfev), steps=0,
                         time=t, err=err, err_final=errf, jac=jac_kind,
                         njev=int(getattr(s, "njev", 0)), nlu=int(getattr(s, "nlu", 0)),
                         note="" if s.success else str(s.message)[:120]))
    return rows


# ----------------------------------------------------------------------------- MuJoCo


def _mujoco(sc, span, ref, method, dts, repeats, say) -> list[dict]:
    try:
        import mujoco
        import mujoco.rollout
    except ImportError:
        return [_row(method, note="not available: pip install 'pointmass-dyn[mujoco]'")]
    integ = method.split(":")[1]
    model = sc.model
    try:
        lay = layout(model)
        to_mjcf(sc)
    except InvalidInputError as exc:
        return [_row(method, note=f"not convertible: {exc}")]
    qpos0, qvel0 = to_mujoco_state(model, sc.q0, sc.v0)
    nq = model.nq
    stages = 4 if integ == "RK4" else 1
    rows = []
    span_len = span[1] - span[0]
    for dt in dts:
        n = int(round(span_len / dt))
        per = n // N_CHECK
        if per * N_CHECK != n:
            raise InvalidInputError(f"dts: every dt must divide the span into a multiple of "
                                    f"{N_CHECK} steps, got dt = {dt!r} ({span_len / dt} steps)")
        say(f"{sc.name}: {method} at dt {dt:g} ({n} steps)")
        m = mujoco.MjModel.from_xml_string(to_mjcf(sc, timestep=span_len / n, integrator=integ))
        d = mujoco.MjData(m)
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        i_qpos = mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_TIME)
        d.time = span[0]
        d.qpos[:], d.qvel[:] = qpos0, qvel0
        x0 = np.empty(mujoco.mj_stateSize(m, spec))
        mujoco.mj_getState(m, d, x0, spec)
        state = np.empty((1, n, x0.size))

        def run():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                mujoco.rollout.rollout(m, d, x0[None], nstep=n, state=state)
        t, _ = best_time(run, repeats)
        idx = np.arange(per - 1, n, per)
        xs = np.vstack([x0[None], state[0, idx]])
        qpos = xs[:, i_qpos:i_qpos + lay.nq]
        qvel = xs[:, i_qpos + lay.nq:i_qpos + lay.nq + lay.nv]
        ok = np.all(np.isfinite(xs)) and abs(xs[-1, 0] - span[1]) <= 1e-9 * max(1, span[1])
        if ok:
            q, v = from_mujoco_state(model, qpos, qvel, q_like=ref.y[:, :nq])
            err, errf = ref.errors(np.hstack([q, v]))
        else:
            err, errf = math.inf, math.inf
        rows.append(_row(method, dt=span_len / n, nfev=stages * n, steps=n, time=t, err=err,
                         err_final=errf, note="" if ok else "diverged"))
        if err < 1e-12:
            break
    return rows


# ----------------------------------------------------------------------------- NumPy RK4


def _numpy_rk4(sc, span, rhs, y0, ref, dts, say) -> list[dict]:
    rows = []
    for dt in dts:
        n = int(round((span[1] - span[0]) / dt))
        if n > 20_000:
            break
        say(f"{sc.name}: numpy:RK4 at dt {dt:g}")
        t0 = time.perf_counter()
        with np.errstate(all="ignore"):
            try:
                _, ys = rk4_fixed(rhs, span, y0, n)
            except Exception:
                ys = None
        t = time.perf_counter() - t0
        err = errf = math.inf
        if ys is not None:
            err, errf = ref.errors(ys[:: n // N_CHECK])
        rows.append(_row("numpy:RK4", dt=dt, nfev=4 * n, steps=n, time=t, err=err,
                         err_final=errf))
    return rows


def measure(sc, span, ref_sol, methods, tolerances, dts, repeats, scipy_repeats,
            say, rows: list[dict] | None = None) -> list[dict]:
    """All rows of the listed methods (see :func:`pointmass_dyn.work_precision`), appended
    to ``rows`` as each method is measured (so a stopped run keeps the methods done)."""
    ref = _Reference(ref_sol, span, N_CHECK)
    y0 = np.concatenate([sc.q0, sc.v0])
    rhs = scene_rhs(sc)
    rows = [] if rows is None else rows
    for m in methods:
        steps = list(dts) if dts is not None else default_dts(span, m)
        if m in OURS_ADAPTIVE:
            rows += _ours(sc, span, ref, m, list(tolerances), repeats, say)
        elif m in OURS_FIXED:
            rows += _ours(sc, span, ref, m, steps, repeats, say)
        elif m in SCIPY:
            rows += _scipy(sc, span, y0, rhs, ref, m, list(tolerances), scipy_repeats, say)
        elif m in MUJOCO:
            rows += _mujoco(sc, span, ref, m, steps, repeats, say)
        else:
            rows += _numpy_rk4(sc, span, rhs, y0, ref, steps, say)
    return rows


# ----------------------------------------------------------------------------- analysis


def time_to_reach(rows: Sequence[dict], e: float) -> float:
    """Least time for ``err ≤ e`` along one method's rows: the cheapest setting already at
    or below ``e``, or the log–log interpolation between a setting above and one below it,
    whichever is less; NaN if no setting reaches ``e``."""
    pts = sorted((r["time"], r["err"]) for r in rows
                 if np.isfinite(r["time"]) and r["time"] > 0 and np.isfinite(r["err"])
                 and r["err"] > 0)
    best = math.inf
    for t, err in pts:
        if err <= e:
            best = min(best, t)
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if e0 > e >= e1:
            f = (math.log(e0) - math.log(e)) / (math.log(e0) - math.log(e1))
            best = min(best, math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0))))
    return best if math.isfinite(best) else math.nan


def cheapest(rows: Sequence[dict], decades: Sequence[float] = DECADES) -> list[dict]:
    """Per accuracy ``e``: ``{"err": e, "method": best, "time": its time, "times": {method:
    time}}`` (``method`` None when nothing reaches ``e``)."""
    by: dict[str, list[dict]] = {}
    for r in rows:
        by.setdefault(r["method"], []).append(r)
    out = []
    for e in decades:
        times = {m: time_to_reach(rs, e) for m, rs in by.items()}
        reach = {m: t for m, t in times.items() if np.isfinite(t)}
        best = min(reach, key=reach.get) if reach else None
        out.append(dict(err=e, method=best, time=reach.get(best, math.nan), times=times))
    return out


def ratio_table(rows: Sequence[dict], decades: Sequence[float] = DECADES) -> list[dict]:
    """Per accuracy: our best method and time, MuJoCo RK4's time and SciPy's best, and the
    ratios (how many times faster ours is)."""
    out = []
    for c in cheapest(rows, decades):
        times = c["times"]
        ours = {m: t for m, t in times.items() if m in OURS_ADAPTIVE + OURS_FIXED
                and np.isfinite(t)}
        sp = {m: t for m, t in times.items() if m in SCIPY and np.isfinite(t)}
        best = min(ours, key=ours.get) if ours else None
        sbest = min(sp, key=sp.get) if sp else None
        t_ours = ours.get(best, math.nan)
        t_mj = times.get("mujoco:RK4", math.nan)
        t_sp = sp.get(sbest, math.nan)
        out.append(dict(err=c["err"], ours=best, t_ours=t_ours, t_mujoco_rk4=t_mj,
                        scipy=sbest, t_scipy=t_sp, vs_mujoco_rk4=t_mj / t_ours,
                        vs_scipy=t_sp / t_ours, overall=c["method"]))
    return out


def methods_text(scene: str, rows: Sequence[dict]) -> str:
    """Every row, method by method (times in ms)."""
    lines = [f"{scene}: {'method':<20} {'tol':>7} {'dt':>9} {'nfev':>9} {'time ms':>9} "
             f"{'err':>9} {'err_final':>9}  note"]
    for r in rows:
        tol = f"{r['tol']:.0e}" if np.isfinite(r["tol"]) else "-"
        dt = f"{r['dt']:.3g}" if np.isfinite(r["dt"]) else "-"
        note = (f"jac {r['jac']} " if r.get("jac") else "") + r.get("note", "")
        lines.append(f"{'':{len(scene) + 1}} {r['method']:<20} {tol:>7} {dt:>9} "
                     f"{r['nfev']:>9d} {r['time'] * 1e3:>9.3f} {r['err']:>9.2e} "
                     f"{r['err_final']:>9.2e}  {note}")
    return "\n".join(lines)


def cheapest_text(scene: str, rows: Sequence[dict], decades=DECADES) -> str:
    """The cheapest method per accuracy decade, with the ratios against MuJoCo RK4 and
    SciPy's best."""
    lines = [f"{scene}: cheapest method per accuracy (err over the check times)",
             f"  {'err':>7} {'cheapest':<20} {'ms':>9} {'ours best':<10} {'ms':>9} "
             f"{'x MuJoCo RK4':>12} {'x SciPy best':>12}"]
    for c, r in zip(cheapest(rows, decades), ratio_table(rows, decades)):
        def f(x, spec):
            return format(x, spec) if np.isfinite(x) else "-"
        lines.append(f"  {c['err']:>7.0e} {c['method'] or '(none)':<20} "
                     f"{f(c['time'] * 1e3, '9.3f'):>9} {r['ours'] or '-':<10} "
                     f"{f(r['t_ours'] * 1e3, '9.3f'):>9} {f(r['vs_mujoco_rk4'], '12.1f'):>12} "
                     f"{f(r['vs_scipy'], '12.1f'):>12}")
    return "\n".join(lines)


STYLE = {
    "RK45": ("C0", "o-"), "DOP853": ("C1", "o-"), "Radau": ("C2", "o-"), "auto": ("C9", "o:"),
    "Vern9": ("C6", "o-"), "Adams": ("k", "D-"), "scipy:LSODA": ("C9", "x--"),
    "RK4": ("C4", "s-"), "Euler": ("C5", "s-"),
    "scipy:RK45": ("C0", "x--"), "scipy:DOP853": ("C1", "x--"), "scipy:Radau": ("C2", "x--"),
    "mujoco:RK4": ("C3", "^-"), "mujoco:Euler": ("C7", "v-"),
    "mujoco:implicitfast": ("C8", "v-"), "numpy:RK4": ("C6", "+:"),
}


def plot_methods(results, path=None):
    """Error over the check times against wall time, one panel per scene, every method."""
    plt = pyplot()
    n = len(results)
    cols = 2 if n > 1 else 1
    nrows = (n + cols - 1) // cols
    fig, axes = plt.subplots(nrows, cols, figsize=(6.2 * cols, 4.6 * nrows), squeeze=False)
    for ax, res in zip(axes.flat, results):
        by: dict[str, list[dict]] = {}
        for r in res.method_rows:
            by.setdefault(r["method"], []).append(r)
        for m, rs in by.items():
            # In the order measured (loose to tight), not by time: timing noise would zigzag.
            pts = [(r["time"] * 1e3, r["err"]) for r in rs
                   if np.isfinite(r["time"]) and np.isfinite(r["err"]) and 0 < r["err"] < 10]
            if not pts:
                continue
            x, y = zip(*pts)
            color, style = STYLE.get(m, ("k", "o-"))
            label = m if ":" in m else f"ours {m}"
            ax.loglog(x, y, style, color=color, ms=3.5, lw=1.2, label=label)
        for e in DECADES:
            ax.axhline(e, color="gray", lw=0.3, alpha=0.5)
        ax.set_ylim(1e-12, 10)
        ax.set_xlabel("wall time (ms)")
        ax.set_ylabel("max relative error at 21 check times")
        ax.set_title(f"{res.scene}, {res.t_span[1] - res.t_span[0]:g} s", fontsize=9)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=6.5, ncol=2)
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=110)
        plt.close(fig)
    return fig


CSV_COLUMNS = ("scene", "t_end", "method", "tol", "dt", "nfev", "steps", "time", "err",
               "err_final", "jac", "note")


def write_methods_csv(results, path) -> None:
    """Every method row of ``results`` (``WorkPrecision`` with ``method_rows``), one CSV."""
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(CSV_COLUMNS)
        for res in results:
            for r in res.method_rows:
                w.writerow([res.scene, res.t_span[1]] + [
                    repr(float(r[c])) if isinstance(r.get(c), (float, np.floating))
                    else r.get(c, "") for c in CSV_COLUMNS[2:]])
