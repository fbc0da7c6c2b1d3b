//! Event functions and their root finding, as in SciPy's `solve_ivp`:
//! a sign change of `g(t, y)` over an accepted step (filtered by direction) is located on
//! the step's interpolant with Brent's method (`brentq`, xtol = rtol = 4·EPS).

/// Which zero crossings of an event function count.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EventDirection {
    /// Both directions (SciPy `direction = 0`).
    #[default]
    Any,
    /// From negative to positive (SciPy `direction > 0`).
    Rising,
    /// From positive to negative (SciPy `direction < 0`).
    Falling,
}

impl EventDirection {
    /// SciPy convention: the sign of `d` (0 or NaN → `Any`).
    pub fn from_sign(d: f64) -> Self {
        if d > 0.0 {
            EventDirection::Rising
        } else if d < 0.0 {
            EventDirection::Falling
        } else {
            EventDirection::Any
        }
    }
}

/// An event function `g(t, y)`.
pub type EventFn<'a> = Box<dyn FnMut(f64, &[f64]) -> f64 + 'a>;

/// An event `g(t, y) = 0`.
///
/// A NaN from `func` never counts as a crossing (comparisons with NaN are false); a caller
/// that must abort (e.g. a Python exception) should record it and return NaN.
pub struct Event<'a> {
    pub func: EventFn<'a>,
    pub direction: EventDirection,
    /// 0: not terminal. n >= 1: stop at the n-th occurrence (SciPy's int `terminal`; `True` is 1).
    pub terminal: usize,
}

impl<'a> Event<'a> {
    /// A non-terminal event counting crossings in both directions.
    pub fn new(func: impl FnMut(f64, &[f64]) -> f64 + 'a) -> Self {
        Self {
            func: Box::new(func),
            direction: EventDirection::Any,
            terminal: 0,
        }
    }

    pub fn direction(mut self, direction: EventDirection) -> Self {
        self.direction = direction;
        self
    }

    /// Stop the integration at the `count`-th occurrence (0 = never).
    pub fn terminal(mut self, count: usize) -> Self {
        self.terminal = count;
        self
    }
}

/// SciPy's `find_active_events` for one event: a sign change (zero counts as either sign).
pub(crate) fn is_active(g: f64, g_new: f64, direction: EventDirection) -> bool {
    let up = g <= 0.0 && g_new >= 0.0;
    let down = g >= 0.0 && g_new <= 0.0;
    match direction {
        EventDirection::Rising => up,
        EventDirection::Falling => down,
        EventDirection::Any => up || down,
    }
}

/// SciPy's `solve_event_equation`: `brentq(f, t_old, t, xtol=4*EPS, rtol=4*EPS)`.
pub(crate) fn solve_event_equation(t_old: f64, t: f64, f: impl FnMut(f64) -> f64) -> f64 {
    brentq(f, t_old, t, 4.0 * f64::EPSILON, 4.0 * f64::EPSILON, 100)
}

/// Port of SciPy's `brentq.c` (Charles Harris), so event times agree with SciPy's. One
/// function of ~80 lines on purpose: it follows the C line for line, to be checked against it.
///
/// Differences, where SciPy raises: if `f(a)` and `f(b)` have the same sign (possible when the
/// interpolant's end value differs from the step's end state by round-off), the endpoint with
/// the smaller |f| is returned; a NaN value stops the iteration at the current best estimate;
/// non-convergence after `maxiter` returns the current estimate.
pub(crate) fn brentq(
    mut f: impl FnMut(f64) -> f64,
    xa: f64,
    xb: f64,
    xtol: f64,
    rtol: f64,
    maxiter: usize,
) -> f64 {
    let mut xpre = xa;
    let mut xcur = xb;
    let (mut xblk, mut fblk, mut spre, mut scur) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut fpre = f(xpre);
    let mut fcur = f(xcur);
    if fpre.is_nan() || fcur.is_nan() {
        return if fpre.is_nan() { xcur } else { xpre };
    }
    if fpre * fcur > 0.0 {
        return if fpre.abs() < fcur.abs() { xpre } else { xcur };
    }
    if fpre == 0.0 {
        return xpre;
    }
    if fcur == 0.0 {
        return xcur;
    }
    for _ in 0..maxiter {
        if fpre * fcur < 0.0 {
            xblk = xpre;
            fblk = fpre;
            spre = xcur - xpre;
            scur = spre;
        }
        if fblk.abs() < fcur.abs() {
            xpre = xcur;
            xcur = xblk;
            xblk = xpre;
            fpre = fcur;
            fcur = fblk;
            fblk = fpre;
        }
        let delta = (xtol + rtol * xcur.abs()) / 2.0;
        let sbis = (xblk - xcur) / 2.0;
        if fcur == 0.0 || sbis.abs() < delta {
            return xcur;
        }
        if spre.abs() > delta && fcur.abs() < fpre.abs() {
            let stry = if xpre == xblk {
                // interpolate
                -fcur * (xcur - xpre) / (fcur - fpre)
            } else {
                // extrapolate (inverse quadratic)
                let dpre = (fpre - fcur) / (xpre - xcur);
                let dblk = (fblk - fcur) / (xblk - xcur);
                -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            };
            if 2.0 * stry.abs() < spre.abs().min(3.0 * sbis.abs() - delta) {
                spre = scur;
                scur = stry;
            } else {
                spre = sbis;
                scur = sbis;
            }
        } else {
            spre = sbis;
            scur = sbis;
        }
        xpre = xcur;
        fpre = fcur;
        if scur.abs() > delta {
            xcur += scur;
        } else {
            xcur += if sbis > 0.0 { delta } else { -delta };
        }
        fcur = f(xcur);
        if fcur.is_nan() {
            return xpre;
        }
    }
    xcur
}

#[cfg(test)]
#[path = "tests/events.rs"]
mod tests;
