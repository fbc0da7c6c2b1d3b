//! A run's configuration and which of its settings a run uses: the caller's [`RunConfig`]
//! beats the scene's (`[simulate]`, [`Settings`]), which beats the default. The one place
//! that decides it ([`RunConfig::resolve`]); the bindings only parse the arguments.
use crate::effects::{Disabled, Effect, Kind};
use crate::integrator::{Controller, Method, SolverOptions, StiffnessCheck, Tol};
use crate::io::scene::Settings;
use crate::support::error::{Error, Result};

use super::Record;

/// One run's configuration, as a caller (or a scene file) states it: `None` where it says
/// nothing (an infinite `max_step` counts as nothing said). The scene file's `[simulate]`
/// table is the subset [`Settings`] (`RunConfig::from(&settings)`); what the integrator
/// gets is the resolved [`SolverOptions`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunConfig {
    pub t_span: Option<(f64, f64)>,
    pub rtol: Option<Tol>,
    pub atol: Option<Tol>,
    pub first_step: Option<f64>,
    pub max_step: Option<f64>,
    pub max_steps: Option<usize>,
    pub method: Option<Method>,
    /// Fixed step of RK4 and Euler.
    pub dt: Option<f64>,
    /// Effect families left out.
    pub disable: Option<Disabled>,
    /// Output only at these times.
    pub t_eval: Option<Vec<f64>>,
    pub controller: Option<Controller>,
    pub stiffness: Option<StiffnessCheck>,
    /// Keep every step's interpolant (`solve_ivp`'s `dense_output`).
    pub dense: Option<bool>,
    /// Record the energy at the output times.
    pub energy: Option<bool>,
    /// Record each effect's power at the output times.
    pub power: Option<bool>,
}

/// The settings a run uses.
#[derive(Debug, Clone, PartialEq)]
pub struct Resolved {
    pub t_span: (f64, f64),
    pub disabled: Disabled,
    pub opts: SolverOptions,
    pub record: Record,
}

impl From<&Settings> for RunConfig {
    fn from(s: &Settings) -> Self {
        RunConfig {
            t_span: s.t_span,
            rtol: s.rtol.map(Tol::Scalar),
            atol: s.atol.map(Tol::Scalar),
            first_step: s.first_step,
            max_step: s.max_step,
            max_steps: s.max_steps,
            method: s.method,
            dt: s.dt,
            disable: s.disable,
            ..RunConfig::default()
        }
    }
}

impl RunConfig {
    /// A scene's settings (`base`) with the ones this config states replaced, checked
    /// (`Settings::check`): the scene's constructor and `replace` parse their keywords as
    /// `RunConfig`'s. A scene holds the settings a file can state: one tolerance for every
    /// component, no output times or recording.
    pub fn onto_scene(self, base: Settings) -> Result<Settings> {
        let scalar = |tol: Option<Tol>, arg: &str| match tol {
            None => Ok(None),
            Some(Tol::Scalar(x)) => Ok(Some(x)),
            Some(Tol::PerComponent(v)) => Err(Error::arg(
                arg,
                "a number (a scene's tolerance holds for every component)",
                format!("{} values", v.len()),
            )),
        };
        let settings = Settings {
            t_span: self.t_span.or(base.t_span),
            rtol: scalar(self.rtol, "rtol")?.or(base.rtol),
            atol: scalar(self.atol, "atol")?.or(base.atol),
            max_step: self.max_step.or(base.max_step),
            max_steps: self.max_steps.or(base.max_steps),
            first_step: self.first_step.or(base.first_step),
            disable: self.disable.or(base.disable),
            method: self.method.or(base.method),
            dt: self.dt.or(base.dt),
        };
        settings.check()?;
        Ok(settings)
    }
}

/// The effect families to leave out: the caller's, else the scene's, else none.
pub fn disabled(caller: Option<Disabled>, scene: &Settings) -> Disabled {
    caller.or(scene.disable).unwrap_or_default()
}

/// The method of a run of `effects` that names none (neither the caller nor the scene):
/// `auto` when an enabled effect is a ground contact or a joint limit — compliant
/// constraints, stiff by design, where RK45 takes 10–100× the right-hand sides of Radau
/// (docs/contact.md §5) — else RK45 (SciPy's, step for step). `auto` steps as RK45 until
/// its stiffness test fires (Adams at rtol ≤ 1e-8, DOP853 with loops), then Radau; the
/// result says so.
pub fn default_method(effects: &[Effect], disabled: Disabled) -> Method {
    let stiff = effects
        .iter()
        .map(Effect::kind)
        .any(|k| matches!(k, Kind::Contact | Kind::Limits) && !disabled.contains(k));
    if stiff {
        Method::Auto
    } else {
        Method::Rk45
    }
}

impl RunConfig {
    /// `self` where it says something, else `below` (`dt` too: see [`RunConfig::resolve`]).
    pub fn over(self, below: RunConfig) -> RunConfig {
        RunConfig {
            t_span: self.t_span.or(below.t_span),
            rtol: self.rtol.or(below.rtol),
            atol: self.atol.or(below.atol),
            first_step: self.first_step.or(below.first_step),
            max_step: self.max_step.or(below.max_step),
            max_steps: self.max_steps.or(below.max_steps),
            method: self.method.or(below.method),
            dt: self.dt.or(below.dt),
            disable: self.disable.or(below.disable),
            t_eval: self.t_eval.or(below.t_eval),
            controller: self.controller.or(below.controller),
            stiffness: self.stiffness.or(below.stiffness),
            dense: self.dense.or(below.dense),
            energy: self.energy.or(below.energy),
            power: self.power.or(below.power),
        }
    }

    /// The run's settings: the caller's (`self`), else the scene's, else the defaults
    /// ([`SolverOptions::default`]; the method: [`default_method`] of the scene's
    /// `effects`). `dim` is the state's length (per-component tolerances must match it).
    /// Without a `t_span` from either, an `InvalidArgument` naming `t_span`.
    pub fn resolve(self, scene: &Settings, effects: &[Effect], dim: usize) -> Result<Resolved> {
        let disabled = disabled(self.disable, scene);
        // The scene's dt belongs to its fixed-step method: a caller who picks an adaptive
        // one leaves it out (a dt of the caller's own is checked by the driver).
        let caller_dt = self.dt;
        let c = self.over(RunConfig::from(scene));
        let d = SolverOptions::default();
        let method = c
            .method
            .unwrap_or_else(|| default_method(effects, disabled));
        let dt = caller_dt.or(c.dt.filter(|_| method.is_fixed_step()));
        let (rtol, atol) = (
            check_tol(c.rtol, "rtol", dim)?,
            check_tol(c.atol, "atol", dim)?,
        );
        let t_span = c
            .t_span
            .ok_or_else(|| Error::arg("t_span", "(t0, t_end): the scene sets none", "None"))?;
        Ok(Resolved {
            t_span,
            disabled,
            record: Record {
                energy: c.energy.unwrap_or(false),
                power: c.power.unwrap_or(false),
            },
            opts: SolverOptions {
                method,
                dt,
                rtol: rtol.unwrap_or(d.rtol),
                atol: atol.unwrap_or(d.atol),
                first_step: c.first_step,
                max_step: c.max_step.unwrap_or(d.max_step),
                max_steps: c.max_steps.unwrap_or(d.max_steps),
                controller: c.controller.unwrap_or(d.controller),
                dense: c.dense.unwrap_or(d.dense),
                t_eval: c.t_eval,
                stiffness: c.stiffness.unwrap_or(d.stiffness),
            },
        })
    }
}

/// A per-component tolerance has one value per state component.
fn check_tol(tol: Option<Tol>, arg: &str, dim: usize) -> Result<Option<Tol>> {
    match &tol {
        Some(Tol::PerComponent(v)) if v.len() != dim => Err(Error::arg(
            arg,
            format!("a number or shape ({dim},)"),
            format!("shape ({},)", v.len()),
        )),
        _ => Ok(tol),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::Kind;

    fn scene() -> Settings {
        Settings {
            t_span: Some((0.0, 2.0)),
            rtol: Some(1e-5),
            atol: Some(1e-7),
            max_step: Some(0.1),
            max_steps: Some(50),
            first_step: Some(1e-3),
            disable: Some(Disabled::none().with(Kind::Gravity)),
            ..Default::default()
        }
    }

    #[test]
    fn a_config_onto_a_scene_replaces_what_it_states_and_keeps_the_rest() {
        let config = RunConfig {
            rtol: Some(Tol::Scalar(1e-9)),
            method: Some(Method::Dop853),
            max_step: None,
            energy: Some(true), // not a scene's: dropped
            ..Default::default()
        };
        let s = config.onto_scene(scene()).unwrap();
        assert_eq!(s.rtol, Some(1e-9));
        assert_eq!(s.method, Some(Method::Dop853));
        let kept = Settings {
            rtol: Some(1e-9),
            method: Some(Method::Dop853),
            ..scene()
        };
        assert_eq!(s, kept);
        // One tolerance per component is a run's, not a scene's; bad values are refused
        // by the scene's own check, naming the setting.
        let per = RunConfig {
            atol: Some(Tol::PerComponent(vec![1e-6, 1e-7])),
            ..Default::default()
        };
        let arg = |e: Error| match e {
            Error::InvalidArgument { arg, .. } => arg,
            other => panic!("{other}"),
        };
        assert_eq!(arg(per.onto_scene(scene()).unwrap_err()), "atol");
        let negative = RunConfig {
            rtol: Some(Tol::Scalar(-1.0)),
            ..Default::default()
        };
        assert_eq!(arg(negative.onto_scene(scene()).unwrap_err()), "rtol");
    }

    #[test]
    fn the_caller_beats_the_scene_which_beats_the_default() {
        let caller = RunConfig {
            t_span: Some((1.0, 0.0)),
            rtol: Some(Tol::PerComponent(vec![1e-4, 1e-4])),
            atol: Some(Tol::Scalar(1e-9)),
            first_step: Some(0.5),
            max_step: Some(0.2),
            max_steps: Some(7),
            disable: Some(Disabled::none()),
            energy: Some(true),
            ..Default::default()
        };
        let r = caller.resolve(&scene(), &[], 2).unwrap();
        assert_eq!(r.t_span, (1.0, 0.0));
        assert_eq!(r.disabled, Disabled::none());
        assert_eq!(r.opts.rtol, Tol::PerComponent(vec![1e-4, 1e-4]));
        assert_eq!(r.opts.atol, Tol::Scalar(1e-9));
        assert_eq!(
            (r.opts.first_step, r.opts.max_step, r.opts.max_steps),
            (Some(0.5), 0.2, 7)
        );
        assert!(r.record.energy && !r.record.power);

        let r = RunConfig::default().resolve(&scene(), &[], 2).unwrap();
        assert_eq!(r.t_span, (0.0, 2.0));
        assert_eq!(r.disabled, Disabled::none().with(Kind::Gravity));
        assert_eq!(
            (r.opts.rtol, r.opts.atol),
            (Tol::Scalar(1e-5), Tol::Scalar(1e-7))
        );
        assert_eq!(
            (r.opts.first_step, r.opts.max_step, r.opts.max_steps),
            (Some(1e-3), 0.1, 50)
        );

        let caller = RunConfig {
            t_span: Some((0.0, 1.0)),
            dense: Some(true),
            ..Default::default()
        };
        let r = caller.resolve(&Settings::default(), &[], 2).unwrap();
        let base = SolverOptions {
            dense: true,
            ..Default::default()
        };
        assert_eq!((r.opts, r.disabled), (base, Disabled::none()));
    }

    #[test]
    fn the_scenes_dt_goes_with_its_fixed_step_method_only() {
        let rk4 = Settings {
            t_span: Some((0.0, 1.0)),
            method: Some(Method::Rk4),
            dt: Some(1e-2),
            ..Default::default()
        };
        let r = RunConfig::default().resolve(&rk4, &[], 2).unwrap();
        assert_eq!((r.opts.method, r.opts.dt), (Method::Rk4, Some(1e-2)));
        let adaptive = RunConfig {
            method: Some(Method::Dop853),
            ..Default::default()
        };
        let r = adaptive.resolve(&rk4, &[], 2).unwrap();
        assert_eq!((r.opts.method, r.opts.dt), (Method::Dop853, None));
    }

    #[test]
    fn a_per_component_tolerance_of_the_wrong_length_names_its_argument() {
        let caller = RunConfig {
            t_span: Some((0.0, 1.0)),
            atol: Some(Tol::PerComponent(vec![1e-6; 3])),
            ..Default::default()
        };
        let e = caller.resolve(&Settings::default(), &[], 4).unwrap_err();
        assert_eq!(
            e.to_string(),
            "atol: expected a number or shape (4,), got shape (3,)"
        );
    }

    #[test]
    fn contact_and_joint_limits_default_to_auto_unless_disabled() {
        use crate::effects::{ContactPoint, GroundContact, JointLimit, JointRef, PerJoint};
        let contact = Effect::GroundContact(
            GroundContact::new(
                None,
                vec![ContactPoint {
                    body: JointRef::Index(0),
                    point: crate::support::spatial::Vec3::zeros(),
                    radius: 0.0,
                }],
                crate::support::spatial::Vec3::z(),
                0.0,
                None,
                1.5,
                None,
                0.5,
                1e-3,
            )
            .unwrap(),
        );
        let all = PerJoint::All(1.0);
        let limit = JointLimit::new(None, None, None, None, all.clone(), all).unwrap();
        let gravity = Effect::gravity(crate::support::spatial::Vec3::z()).unwrap();
        let none = Disabled::none();
        assert_eq!(default_method(&[], none), Method::Rk45);
        assert_eq!(
            default_method(std::slice::from_ref(&gravity), none),
            Method::Rk45
        );
        let stiff = [gravity, contact, Effect::JointLimit(limit)];
        assert_eq!(default_method(&stiff, none), Method::Auto);
        assert_eq!(default_method(&stiff[..2], none), Method::Auto);
        let off = none.with(Kind::Contact);
        assert_eq!(default_method(&stiff[..2], off), Method::Rk45);
        assert_eq!(default_method(&stiff, off), Method::Auto);
        assert_eq!(default_method(&stiff, off.with(Kind::Limits)), Method::Rk45);
    }

    #[test]
    fn a_run_without_t_span_names_it() {
        let e = RunConfig::default()
            .resolve(&Settings::default(), &[], 2)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "t_span: expected (t0, t_end): the scene sets none, got None"
        );
    }
}
