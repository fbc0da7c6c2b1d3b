//! A [`RunConfig`] from a binding's keyword arguments ([`Arg`]): one parser for
//! `RunConfig(...)`, the run calls' keywords and a `Scene`'s settings, so each refuses a
//! setting in the same words.
use super::RunConfig;
use crate::effects::args::disable;
use crate::integrator::{Controller, Method, StiffnessCheck, Tol};
use crate::io::scene::Settings;
use crate::support::args::{choice, count, flag, int, opt, shape_str, vector, Arg, Int};
use crate::support::error::Error;

/// The settings, in the constructor's order (`t_span` may also come first by position).
pub const KEYS: [&str; 15] = [
    "t_span",
    "rtol",
    "atol",
    "t_eval",
    "first_step",
    "max_step",
    "max_steps",
    "method",
    "dt",
    "controller",
    "stiffness",
    "disable",
    "energy",
    "power",
    "dense_output",
];

/// The settings a scene holds (a scene file's `[simulate]` table): the keywords of a
/// `Scene`'s constructor and `replace`.
pub const SCENE_KEYS: [&str; 9] = [
    "t_span",
    "rtol",
    "atol",
    "first_step",
    "max_step",
    "max_steps",
    "method",
    "dt",
    "disable",
];

impl RunConfig {
    /// The settings given as `(keyword, value)` (a `None` value: not given), read in
    /// [`KEYS`]' order; an unknown keyword is refused naming the ones there are.
    pub fn from_args<'a, A: Arg + 'a>(
        given: impl IntoIterator<Item = (&'a str, &'a A)>,
    ) -> Result<RunConfig, A::Err> {
        let given: Vec<(&str, &A)> = given.into_iter().collect();
        if let Some((key, _)) = given.iter().find(|(k, _)| !KEYS.contains(k)) {
            let expected = format!("a setting of RunConfig: {}", KEYS.join(", "));
            return Err(Error::arg(*key, expected, "an unknown keyword").into());
        }
        let mut c = RunConfig::default();
        for key in KEYS {
            for (_, x) in given.iter().filter(|(k, x)| *k == key && !x.absent()) {
                let x: &A = x;
                c.set(key, x)?;
            }
        }
        Ok(c)
    }

    /// The settings of a call: its `named` keywords (`None`: not given) and `settings`, a
    /// mapping of more (its `**settings`), read as [`RunConfig::from_args`] reads them.
    pub fn from_call<A: Arg>(
        settings: Option<&A>,
        named: &[(&str, Option<&A>)],
    ) -> Result<RunConfig, A::Err> {
        let mapped = mapped(settings);
        RunConfig::from_args(call_args(&mapped, named))
    }

    /// These settings with those of `changes` (a mapping, keyword to value) replaced; a
    /// `None` value unsets its setting.
    pub fn replaced<A: Arg>(&self, changes: Option<&A>) -> Result<RunConfig, A::Err> {
        let mut below = self.clone();
        for key in changes.and_then(Arg::keys).unwrap_or_default() {
            below.take(&key.text().unwrap_or_default());
        }
        Ok(RunConfig::from_call(changes, &[])?.over(below))
    }

    /// The keywords of the settings given, in [`KEYS`]' order.
    pub fn given(&self) -> Vec<&'static str> {
        KEYS.into_iter().filter(|k| self.clone().take(k)).collect()
    }

    /// Unsets the setting `key`; whether it was set.
    fn take(&mut self, key: &str) -> bool {
        match key {
            "t_span" => self.t_span.take().is_some(),
            "rtol" => self.rtol.take().is_some(),
            "atol" => self.atol.take().is_some(),
            "t_eval" => self.t_eval.take().is_some(),
            "first_step" => self.first_step.take().is_some(),
            "max_step" => self.max_step.take().is_some(),
            "max_steps" => self.max_steps.take().is_some(),
            "method" => self.method.take().is_some(),
            "dt" => self.dt.take().is_some(),
            "controller" => self.controller.take().is_some(),
            "stiffness" => self.stiffness.take().is_some(),
            "disable" => self.disable.take().is_some(),
            "energy" => self.energy.take().is_some(),
            "power" => self.power.take().is_some(),
            _ => self.dense.take().is_some(),
        }
    }

    /// `base` with the scene settings a call gave (its `named` keywords, `None`: not given,
    /// and `settings`, a mapping of more) laid over it and checked
    /// ([`RunConfig::onto_scene`]); a keyword no scene holds is the binding's type error (as
    /// an unexpected keyword argument), naming those it holds.
    pub fn scene_call<A: Arg>(
        settings: Option<&A>,
        named: &[(&str, Option<&A>)],
        base: Settings,
    ) -> Result<Settings, A::Err> {
        let mapped = mapped(settings);
        let given: Vec<(&str, &A)> = call_args(&mapped, named).collect();
        if let Some((key, x)) = given.iter().find(|(k, _)| !SCENE_KEYS.contains(k)) {
            let expected = format!("a keyword of Scene: {}", SCENE_KEYS.join(", "));
            return Err(x.wrong_type(key, &expected));
        }
        Ok(RunConfig::from_args(given)?.onto_scene(base)?)
    }

    fn set<A: Arg>(&mut self, key: &str, x: &A) -> Result<(), A::Err> {
        match key {
            "t_span" => self.t_span = Some(t_span(x)?),
            "rtol" => self.rtol = Some(tol(x, key)?),
            "atol" => self.atol = Some(tol(x, key)?),
            "t_eval" => self.t_eval = Some(vector(x, key, None)?),
            "first_step" => self.first_step = Some(x.real(key)?),
            "max_step" => self.max_step = Some(x.real(key)?).filter(|h| *h != f64::INFINITY),
            "max_steps" => self.max_steps = Some(count(x, key, "a step count >= 0 (or None)")?),
            "method" => self.method = Some(method(x)?),
            "dt" => self.dt = Some(x.real(key)?),
            "controller" => self.controller = Some(controller(x)?),
            "stiffness" => self.stiffness = Some(stiffness(x)?),
            "disable" => self.disable = disable(Some(x))?,
            "energy" => self.energy = Some(flag(x, key)?),
            "power" => self.power = Some(flag(x, key)?),
            _ => self.dense = Some(flag(x, key)?),
        }
        Ok(())
    }
}

/// Two different finite times `(t0, t_end)`.
pub fn t_span<A: Arg>(x: &A) -> Result<(f64, f64), A::Err> {
    let v = vector(x, "t_span", Some(2))?;
    if !(v[0].is_finite() && v[1].is_finite()) || v[0] == v[1] {
        let expected = "two different finite times (t0, t_end)";
        return Err(Error::arg("t_span", expected, format!("({}, {})", v[0], v[1])).into());
    }
    Ok((v[0], v[1]))
}

/// A tolerance: a number, or one per state component (its length is checked by the run).
fn tol<A: Arg>(x: &A, arg: &str) -> Result<Tol, A::Err> {
    let (shape, values) = x.array(arg)?;
    match shape.len() {
        0 => Ok(Tol::Scalar(values[0])),
        1 => Ok(Tol::PerComponent(values)),
        _ => {
            let expected = "a number or one per state component (n,)";
            Err(Error::arg(arg, expected, shape_str(&shape)).into())
        }
    }
}

/// SciPy's spelling of a method (any case).
pub fn method<A: Arg>(x: &A) -> Result<Method, A::Err> {
    let expected = format!("one of {}", Method::NAMES);
    let Some(name) = x.text() else {
        return Err(x.wrong_type("method", &expected));
    };
    Method::parse(&name).ok_or_else(|| Error::arg("method", expected, format!("'{name}'")).into())
}

pub fn controller<A: Arg>(x: &A) -> Result<Controller, A::Err> {
    let pi = Controller::hairer_pi();
    let choices = [
        ("standard", Controller::Standard),
        ("scipy", Controller::Standard),
        ("pi", pi),
    ];
    choice(
        x,
        "controller",
        &choices,
        "'standard' (SciPy's) or 'pi' (Hairer's PI)",
    )
}

/// `"warn"` (detect, report, steps unchanged), `"stop"` or `"off"`.
pub fn stiffness<A: Arg>(x: &A) -> Result<StiffnessCheck, A::Err> {
    use StiffnessCheck::*;
    let choices = [("warn", Warn), ("stop", Stop), ("off", Off)];
    let expected = "'warn' (detect and report), 'stop' (stop at the detection) or 'off'";
    choice(x, "stiffness", &choices, expected)
}

impl Controller {
    pub fn name(self) -> &'static str {
        match self {
            Controller::Standard => "standard",
            Controller::PI { .. } => "pi",
        }
    }
}

impl StiffnessCheck {
    pub fn name(self) -> &'static str {
        match self {
            StiffnessCheck::Warn => "warn",
            StiffnessCheck::Stop => "stop",
            StiffnessCheck::Off => "off",
        }
    }
}

impl super::StateEvent {
    /// `variable` (`"q"` or `"v"`) `[index]` crossing `value` (default 0) in `direction`'s
    /// sign (default either way), stopping the run at the `terminal`-th crossing (a bool
    /// or a count; default never).
    pub fn from_args<A: Arg>(
        variable: &str,
        index: &A,
        value: Option<&A>,
        direction: Option<&A>,
        terminal: Option<&A>,
    ) -> Result<Self, A::Err> {
        let index = count(index, "index", "a coordinate index >= 0")?;
        let value = opt(value, |x| x.real("value"))?.unwrap_or(0.0);
        let direction = opt(direction, |d| {
            int(d, "direction", i64::MIN, i64::MAX, "-1, 0 or 1")
        })?;
        let on_velocity = match variable {
            "q" => false,
            "v" => true,
            other => return Err(Error::arg("variable", "'q' or 'v'", format!("'{other}'")).into()),
        };
        if !value.is_finite() {
            return Err(Error::arg("value", "a finite number", value.to_string()).into());
        }
        Ok(super::StateEvent {
            on_velocity,
            index,
            value,
            direction: direction.unwrap_or(0).signum() as i32,
            terminal: opt(terminal, terminal_count)?.unwrap_or(0),
        })
    }
}

/// `StateEvent('q', 0, value=0.5, direction=-1, terminal=1)`: how it was built.
impl std::fmt::Display for super::StateEvent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let variable = if self.on_velocity { "v" } else { "q" };
        write!(
            f,
            "StateEvent('{variable}', {}, value={}, direction={}, terminal={})",
            self.index, self.value, self.direction, self.terminal
        )
    }
}

/// How the caller's event function `events[index]` counts: its `terminal` (a crossing
/// count, 0: never) and `direction` (a sign, 0: either way), attributes it may have
/// (SciPy's convention).
pub struct EventFunction {
    pub index: usize,
    pub terminal: usize,
    pub direction: f64,
}

impl EventFunction {
    pub fn from_args<A: Arg>(index: usize, e: &A) -> Result<Self, A::Err> {
        let attr = |name| e.attr(name).filter(|x| !x.absent());
        let terminal = attr("terminal").map(|t| terminal_count(&t)).transpose()?;
        let direction = attr("direction").map(|d| d.real(&format!("events[{index}].direction")));
        Ok(EventFunction {
            index,
            terminal: terminal.unwrap_or(0),
            direction: direction.transpose()?.unwrap_or(0.0),
        })
    }
}

/// An event's `terminal`: a bool, or the count of crossings that stops the run.
pub fn terminal_count<A: Arg>(x: &A) -> Result<usize, A::Err> {
    match x.int() {
        Int::Value(n) if n >= 0 => Ok(n as usize),
        _ => Err(Error::arg("terminal", "a bool or a count >= 0", x.shown()).into()),
    }
}

/// A finite time `t`.
pub fn time(t: f64) -> Result<f64, Error> {
    match t.is_finite() {
        true => Ok(t),
        false => Err(Error::arg("t", "a finite time", t.to_string())),
    }
}

/// `(q, v)` of `scene`'s model: nq and nv numbers making a valid state.
pub fn scene_state<A: Arg>(
    scene: &crate::io::scene::Scene,
    q: &A,
    v: &A,
) -> Result<(Vec<f64>, Vec<f64>), A::Err> {
    let q = vector(q, "q", Some(scene.model.nq))?;
    let v = vector(v, "v", Some(scene.model.nv))?;
    scene.model.check_state(&q, Some(&v))?;
    Ok((q, v))
}

/// `progress_interval`: seconds between progress calls, 0 to 3600 (`None`: not given).
pub fn progress_interval(x: Option<f64>) -> Result<Option<std::time::Duration>, Error> {
    match x {
        None => Ok(None),
        Some(x) if (0.0..=3600.0).contains(&x) => Ok(Some(std::time::Duration::from_secs_f64(x))),
        Some(x) => {
            let expected = "seconds between progress calls, 0 to 3600";
            Err(Error::arg("progress_interval", expected, x.to_string()))
        }
    }
}

/// The entries of a call's `**settings` mapping, keyword to value.
pub fn mapped<A: Arg>(settings: Option<&A>) -> Vec<(String, A)> {
    let keys = settings.and_then(Arg::keys).unwrap_or_default();
    (keys.iter())
        .filter_map(|k| Some((k.text()?, settings?.get(&k.text()?)??)))
        .collect()
}

/// A call's keywords: those of its `**settings` (`mapped`), then its `named` ones given.
fn call_args<'a, A: Arg>(
    mapped: &'a [(String, A)],
    named: &'a [(&'a str, Option<&'a A>)],
) -> impl Iterator<Item = (&'a str, &'a A)> {
    let named = named.iter().filter_map(|(k, v)| v.map(|v| (*k, v)));
    mapped.iter().map(|(k, v)| (k.as_str(), v)).chain(named)
}

/// SciPy's `jac` (given) for a system of `dim` components integrated with `method`: a
/// callable (`callable`; `first()` calls it at the start) or a constant `(dim, dim)` matrix,
/// returned. Only the implicit methods use a Jacobian, so one given to another method is
/// refused rather than ignored. With `auto` a callable is called once at the start `(t0,
/// y0)`: Radau calls it at once, but `auto` only if it switches, which would leave a wrong
/// `jac` unnoticed until then.
pub fn ode_jacobian<A: Arg>(
    jac: &A,
    callable: bool,
    dim: usize,
    method: Method,
    first: impl FnOnce() -> Result<A, A::Err>,
) -> Result<Option<Vec<f64>>, A::Err> {
    if !matches!(method, Method::Radau | Method::Auto) {
        let expected =
            format!("None with method '{method}' (only 'Radau' and 'auto' use a Jacobian)");
        return Err(Error::arg("jac", expected, "a Jacobian").into());
    }
    let finite = |m: &A, arg: &str, label: &str| -> Result<Vec<f64>, A::Err> {
        let m = crate::support::args::matrix(m, arg, dim, dim)?;
        crate::support::error::check_finite_matrix(label, &m, dim)?;
        Ok(m)
    };
    if !callable {
        return finite(jac, "jac", "jac").map(Some);
    }
    if method == Method::Auto {
        finite(&first()?, "jac(t, y)", "jac(t0, y0)")?;
    }
    Ok(None)
}
