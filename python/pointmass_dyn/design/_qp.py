"""The convex quadratic program of balancing, solved exactly: a primal–dual interior point
(Mehrotra's predictor–corrector) with a polish on the active set it finds. Written here
because NumPy has no QP solver and the core install stays NumPy only."""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInputError, NumericalError


def solve_qp(h, c, ce, de, lb, ub, x0=None):
    """min ½ xᵀ H x + cᵀ x  s.t.  Cₑ x = dₑ (independent rows), lb ≤ x ≤ ub (lb finite).

    A primal–dual interior-point method (Mehrotra's predictor–corrector), which degenerate
    problems — many masses at zero, more equalities than free masses — do not trouble, then
    a polish: the bounds it finds active are fixed and the equality-constrained problem on
    the others is solved exactly, kept if it is feasible and no worse. Variables with
    equal bounds are substituted first."""
    pinned = lb >= ub
    if pinned.any():
        keep = ~pinned
        xp = np.where(pinned, lb, 0.0)
        sub = solve_qp(
            h[np.ix_(keep, keep)],
            c[keep] + h[np.ix_(keep, pinned)] @ xp[pinned],
            ce[:, keep],
            de - ce[:, pinned] @ xp[pinned],
            lb[keep],
            ub[keep],
            None if x0 is None else x0[keep],
        )
        xp[keep] = sub
        return xp
    n, m = len(c), ce.shape[0]
    finite_ub = np.isfinite(ub)
    span = np.where(finite_ub, ub - lb, 1.0)
    x = lb + np.where(finite_ub, 0.5 * span, 1.0)
    if x0 is not None:
        x = np.clip(x0, lb + 1e-3 * span, np.where(finite_ub, ub - 1e-3 * span, np.inf))
    y = np.zeros(m)
    zl = np.ones(n)
    zu = np.where(finite_ub, 1.0, 0.0)
    scale = 1.0 + max(np.abs(h).max(initial=0.0), np.abs(c).max(initial=0.0))
    for _ in range(100):
        sl = x - lb
        su = np.where(finite_ub, ub - x, 1.0)
        r_dual = h @ x + c + ce.T @ y - zl + zu
        r_prim = ce @ x - de
        mu = (sl @ zl + (su * zu)[finite_ub].sum()) / (n + finite_ub.sum())
        # The polish below makes the answer exact; the interior point needs only to find
        # the active bounds (its residuals stall near 1e-11 as gaps reach 1e-20).
        if (
            np.abs(r_dual).max(initial=0.0) < 1e-10 * scale
            and np.abs(r_prim).max(initial=0.0) < 1e-11 * (1.0 + np.abs(de).max(initial=0.0))
            and mu < 1e-13 * scale
        ):
            break
        d = zl / sl + np.where(finite_ub, zu / su, 0.0)
        kkt = np.zeros((n + m, n + m))
        kkt[:n, :n] = h + np.diag(d)
        kkt[:n, n:] = ce.T
        kkt[n:, :n] = ce

        def direction(sigma_mu, dx_aff=None, dzl_aff=None, dzu_aff=None):
            # Complementarity targets sl·zl = σμ (− the predictor's second-order term).
            cl = sigma_mu - sl * zl
            cu = np.where(finite_ub, sigma_mu - su * zu, 0.0)
            if dx_aff is not None:
                cl = cl - dx_aff * dzl_aff
                cu = cu + np.where(finite_ub, dx_aff * dzu_aff, 0.0)
            rhs = np.concatenate([-r_dual + cl / sl - np.where(finite_ub, cu / su, 0.0), -r_prim])
            try:
                sol = np.linalg.solve(kkt, rhs)
            except np.linalg.LinAlgError:
                sol = np.linalg.lstsq(kkt, rhs, rcond=1e-14)[0]
            dx = sol[:n]
            dzl = (cl - zl * dx) / sl
            dzu = np.where(finite_ub, (cu + zu * dx) / su, 0.0)
            return dx, sol[n:], dzl, dzu

        def longest(dx, dzl, dzu):
            steps = [1.0]
            for v, dv in ((sl, dx), (zl, dzl)):
                neg = dv < 0
                if neg.any():
                    steps.append(np.min(-v[neg] / dv[neg]))
            for v, dv in ((su, -dx), (zu, dzu)):
                neg = finite_ub & (dv < 0)
                if neg.any():
                    steps.append(np.min(-v[neg] / dv[neg]))
            return min(steps)

        dx, dy, dzl, dzu = direction(0.0)
        a_aff = longest(dx, dzl, dzu)
        sl_a, zl_a = sl + a_aff * dx, zl + a_aff * dzl
        su_a, zu_a = su - a_aff * dx, zu + a_aff * dzu
        mu_aff = (sl_a @ zl_a + (su_a * zu_a)[finite_ub].sum()) / (n + finite_ub.sum())
        sigma = (mu_aff / mu) ** 3 if mu > 0 else 0.0
        dx, dy, dzl, dzu = direction(sigma * mu, dx, dzl, dzu)
        alpha = 0.99 * longest(dx, dzl, dzu)
        x, y = x + alpha * dx, y + alpha * dy
        zl, zu = zl + alpha * dzl, np.where(finite_ub, zu + alpha * dzu, 0.0)
    else:
        raise NumericalError(
            f"balance: the quadratic program did not converge ({n} design masses); the "
            f"problem may be badly scaled"
        )
    return _polish(h, c, ce, de, lb, ub, x, zl, zu)


def _polish(h, c, ce, de, lb, ub, x, zl, zu):
    """The exact solution on the active set the interior point found (bounds whose
    multiplier exceeds their gap), if it is feasible and no worse; else ``x``."""
    at_lb = (x - lb) < zl
    at_ub = np.isfinite(ub) & ((ub - x) < zu)
    fixed = at_lb | at_ub
    free = np.flatnonzero(~fixed)
    xf = np.where(at_lb, lb, np.where(at_ub, ub, 0.0))
    m = ce.shape[0]
    k = len(free)
    kkt = np.zeros((k + m, k + m))
    kkt[:k, :k] = h[np.ix_(free, free)]
    kkt[:k, k:] = ce[:, free].T
    kkt[k:, :k] = ce[:, free]
    rhs = np.concatenate([-(c[free] + h[free] @ xf), de - ce @ xf])
    sol = np.linalg.lstsq(kkt, rhs, rcond=1e-14)[0]
    polished = xf.copy()
    polished[free] = sol[:k]
    feasible = (
        np.all(polished >= lb - 1e-12 * (1 + np.abs(lb)))
        and np.all(polished <= ub + 1e-12 * (1 + np.abs(ub)))
        and np.abs(ce @ polished - de).max(initial=0.0)
        <= max(1e-12 * (1.0 + np.abs(de).max(initial=0.0)), np.abs(ce @ x - de).max(initial=0.0))
    )
    if not feasible:
        return x
    polished = np.clip(polished, lb, ub)

    def cost(v):
        return 0.5 * v @ h @ v + c @ v

    return polished if cost(polished) <= cost(x) + 1e-12 * (1 + abs(cost(x))) else x


def row_space(ce: np.ndarray, de: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Equalities ``Cₑ x = dₑ`` as an orthonormal basis of their row space (N instants give
    many more rows than design variables), after checking they can be met at all."""
    p = ce.shape[1]
    if ce.shape[0] == 0:
        return np.zeros((0, p)), np.zeros(0)
    # Round-off entries (a planar mechanism's out-of-plane rows, ~1e-300 after scaling) are
    # flushed: subnormal numbers slow LAPACK down a thousandfold.
    big = np.abs(ce).max(initial=0.0)
    ce = np.where(np.abs(ce) < 1e-15 * big, 0.0, ce)
    # Tall systems are first reduced to a square one by QR in blocks of rows: a tall SVD or
    # QR goes to multithreaded LAPACK, which a busy machine slows a thousandfold, small
    # factorisations do not. `lost²` is the part of dₑ that no combination of rows reaches.
    lost2 = 0.0
    if ce.shape[0] > 2 * p:
        rf, tf = np.zeros((0, p)), np.zeros(0)
        for k in range(0, ce.shape[0], 2 * p):
            stack = np.vstack([rf, ce[k : k + 2 * p]])
            rhs = np.concatenate([tf, de[k : k + 2 * p]])
            qb, rf = np.linalg.qr(stack)
            tf = qb.T @ rhs
            lost2 += float(np.sum((rhs - qb @ tf) ** 2))
        ce, de = rf, tf
    u, sv, vt = np.linalg.svd(ce, full_matrices=False)
    r = int(np.sum(sv > 1e-12 * sv.max(initial=0.0)))
    outside = np.sqrt(lost2 + float(np.sum((de - u[:, :r] @ (u[:, :r].T @ de)) ** 2)))
    if outside > 1e-9 * (1.0 + np.linalg.norm(de)):
        raise InvalidInputError(
            f"zero: no masses at the design points make {what} vanish at every instant "
            f"(residual {outside:.3e}); add counterweight candidates on other links"
        )
    return vt[:r], (u[:, :r].T @ de) / sv[:r]
