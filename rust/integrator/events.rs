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

/// Port of SciPy's `brentq.c` (Charles Harris), so event times agree with SciPy's.
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
mod tests {
    use super::*;
    use crate::integrator::{rk45, FnSystem, Rk45Options, Status};
    use std::f64::consts::PI;

    #[test]
    fn brentq_finds_known_roots() {
        let r = brentq(
            |x| x * x - 2.0,
            0.0,
            2.0,
            4.0 * f64::EPSILON,
            4.0 * f64::EPSILON,
            100,
        );
        assert!((r - 2f64.sqrt()).abs() <= 8.0 * f64::EPSILON, "{r}");
        let r = brentq(
            |x: f64| x.cos(),
            3.0,
            1.0,
            4.0 * f64::EPSILON,
            4.0 * f64::EPSILON,
            100,
        );
        assert!((r - PI / 2.0).abs() <= 8.0 * f64::EPSILON, "{r}");
        // Exact zero at an endpoint is returned as is.
        assert_eq!(brentq(|x| x - 1.0, 1.0, 3.0, 1e-12, 1e-12, 100), 1.0);
        // Same sign at both ends: the endpoint closer to zero.
        assert_eq!(brentq(|x| x + 1e-20, 0.0, 1.0, 1e-12, 1e-12, 100), 0.0);
    }

    #[test]
    fn activity_follows_scipy_find_active_events() {
        use EventDirection::*;
        assert!(
            is_active(-1.0, 1.0, Rising)
                && !is_active(-1.0, 1.0, Falling)
                && is_active(-1.0, 1.0, Any)
        );
        assert!(!is_active(1.0, -1.0, Rising) && is_active(1.0, -1.0, Falling));
        assert!(
            is_active(0.0, 1.0, Rising)
                && is_active(0.0, 1.0, Any)
                && !is_active(0.0, 1.0, Falling)
        );
        assert!(!is_active(1.0, 2.0, Any) && !is_active(f64::NAN, 1.0, Any));
    }

    /// y1 = cos t, y2 = -sin t.
    #[allow(clippy::type_complexity)]
    fn oscillator() -> FnSystem<impl FnMut(f64, &[f64], &mut [f64]) -> Result<(), String>> {
        FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
            dy[0] = y[1];
            dy[1] = -y[0];
            Ok(())
        })
    }

    fn tight() -> Rk45Options {
        Rk45Options {
            rtol: 1e-12.into(),
            atol: 1e-12.into(),
            ..Default::default()
        }
    }

    #[test]
    fn oscillator_zero_crossings_located_to_1e_10() {
        let mut evs = [Event::new(|_t, y: &[f64]| y[0])];
        let sol = rk45(oscillator(), (0.0, 10.0), &[1.0, 0.0], &tight(), &mut evs).unwrap();
        assert_eq!(sol.status, Status::Success);
        let expect = [0.5 * PI, 1.5 * PI, 2.5 * PI];
        assert_eq!(sol.t_events[0].len(), 3, "{:?}", sol.t_events);
        for (k, (&te, &ex)) in sol.t_events[0].iter().zip(&expect).enumerate() {
            assert!((te - ex).abs() < 1e-10, "root {te} vs {ex}");
            let ye = &sol.y_events[0][2 * k..2 * k + 2];
            assert!(
                ye[0].abs() < 1e-10 && (ye[1] + ex.sin()).abs() < 1e-10,
                "{ye:?}"
            );
        }
        // Events do not change the integration itself.
        let plain = rk45(oscillator(), (0.0, 10.0), &[1.0, 0.0], &tight(), &mut []).unwrap();
        assert_eq!((plain.t, plain.nfev), (sol.t, sol.nfev));
    }

    #[test]
    fn direction_filtering() {
        let mut evs = [
            Event::new(|_t, y: &[f64]| y[0]).direction(EventDirection::Rising),
            Event::new(|_t, y: &[f64]| y[0]).direction(EventDirection::Falling),
        ];
        let sol = rk45(oscillator(), (0.0, 12.0), &[1.0, 0.0], &tight(), &mut evs).unwrap();
        let (up, down) = (&sol.t_events[0], &sol.t_events[1]);
        assert_eq!(up.len(), 2, "{up:?}");
        assert_eq!(down.len(), 2, "{down:?}");
        assert!((up[0] - 1.5 * PI).abs() < 1e-10 && (up[1] - 3.5 * PI).abs() < 1e-10);
        assert!((down[0] - 0.5 * PI).abs() < 1e-10 && (down[1] - 2.5 * PI).abs() < 1e-10);
    }

    #[test]
    fn terminal_event_stops_at_the_event_time() {
        // Second rising crossing of y1 = cos t: 3.5 π; the non-terminal event before it is kept.
        let mut evs = [
            Event::new(|_t, y: &[f64]| y[0])
                .direction(EventDirection::Rising)
                .terminal(2),
            Event::new(|_t, y: &[f64]| y[1]),
        ];
        let sol = rk45(oscillator(), (0.0, 20.0), &[1.0, 0.0], &tight(), &mut evs).unwrap();
        let te = 3.5 * PI;
        assert!(
            matches!(sol.status, Status::TerminalEvent { event: 0, t } if (t - te).abs() < 1e-10)
        );
        assert_eq!(sol.status.code(), 1);
        assert!(sol.success());
        assert_eq!(sol.t_events[0].len(), 2);
        // y2 = -sin t: g(t0) = 0 counts as a crossing (as in SciPy), then π, 2π, 3π before
        // the stop, not 4π after it.
        assert_eq!(sol.t_events[1].len(), 4, "{:?}", sol.t_events[1]);
        assert_eq!(sol.t_events[1][0], 0.0);
        let t_last = *sol.t.last().unwrap();
        assert_eq!(t_last, sol.t_events[0][1]);
        assert_eq!(sol.t_reached, t_last);
        let y_last = sol.state(sol.t.len() - 1);
        assert!(
            y_last[0].abs() < 1e-10 && (y_last[1] - 1.0).abs() < 1e-10,
            "{y_last:?}"
        );
        assert!(sol.message.contains("terminal event 0"), "{}", sol.message);
    }

    #[test]
    fn terminal_event_with_t_eval_truncates_output() {
        let opts = Rk45Options {
            t_eval: Some((0..=20).map(|k| k as f64 * 0.5).collect()),
            ..tight()
        };
        let mut evs = [Event::new(|_t, y: &[f64]| y[0]).terminal(1)];
        let sol = rk45(oscillator(), (0.0, 10.0), &[1.0, 0.0], &opts, &mut evs).unwrap();
        // π/2 ≈ 1.5708: t_eval values 0, 0.5, 1.0, 1.5 only.
        assert_eq!(sol.t, vec![0.0, 0.5, 1.0, 1.5]);
        for (i, &t) in sol.t.iter().enumerate() {
            assert!((sol.state(i)[0] - t.cos()).abs() < 1e-10);
        }
    }
}
