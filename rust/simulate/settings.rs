//! Which setting a run uses: the caller's argument beats the scene's setting, which beats
//! the default. The one place that decides it; the bindings only parse the arguments.
use crate::effects::{Disabled, Effect, Kind};
use crate::error::{Error, Result};
use crate::integrator::{Method, SolverOptions, Tol};
use crate::scene::{Scene, Settings};

/// What the caller of a run asked for: `None` where they said nothing (an infinite
/// `max_step` counts as nothing said).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Requested {
    pub t_span: Option<(f64, f64)>,
    pub rtol: Option<Tol>,
    pub atol: Option<Tol>,
    pub first_step: Option<f64>,
    pub max_step: Option<f64>,
    pub max_steps: Option<usize>,
    pub disable: Option<Disabled>,
    pub method: Option<crate::integrator::Method>,
    pub dt: Option<f64>,
}

/// The settings a run uses.
#[derive(Debug, Clone, PartialEq)]
pub struct Resolved {
    pub t_span: (f64, f64),
    pub disabled: Disabled,
    pub opts: SolverOptions,
}

/// The effect families to leave out: the caller's, else the scene's, else none.
pub fn disabled(caller: Option<Disabled>, scene: &Settings) -> Disabled {
    caller.or(scene.disable).unwrap_or_default()
}

/// The method of a run of `effects` that names none (neither the caller nor the scene):
/// `auto` when an enabled effect is a ground contact or a joint limit — compliant
/// constraints, stiff by design, where RK45 takes 10–100× the right-hand sides of Radau
/// (docs/contact.md §5) — else RK45 (SciPy's, step for step). `auto` steps as RK45 until
/// Hairer's stiffness test fires (DOP853 at rtol ≤ 1e-8), then Radau; the result says so.
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

impl Requested {
    /// [`Requested::resolve`] against a scene, whose effects choose the method when neither
    /// the caller nor the scene's settings name one ([`default_method`]).
    pub fn resolve_scene(self, scene: &Scene, base: SolverOptions) -> Result<Resolved> {
        let off = disabled(self.disable, &scene.settings);
        let base = SolverOptions {
            method: default_method(&scene.effects, off),
            ..base
        };
        self.resolve(&scene.settings, base)
    }

    /// The run's settings against a scene's: `base` carries the options a scene does not
    /// set (controller, `t_eval`, dense output, stiffness check) and the defaults of the rest.
    /// Without a `t_span` from either, an `InvalidArgument` naming `t_span`.
    pub fn resolve(self, scene: &Settings, base: SolverOptions) -> Result<Resolved> {
        let t_span = self
            .t_span
            .or(scene.t_span)
            .ok_or_else(|| Error::arg("t_span", "(t0, t_end): the scene sets none", "None"))?;
        Ok(Resolved {
            t_span,
            disabled: disabled(self.disable, scene),
            opts: self.options(scene, base),
        })
    }

    /// `base` with the tolerances and step limits resolved (all but `t_span` and `disable`).
    pub fn options(self, scene: &Settings, base: SolverOptions) -> SolverOptions {
        let method = self.method.or(scene.method).unwrap_or(base.method);
        SolverOptions {
            rtol: self
                .rtol
                .or(scene.rtol.map(Tol::Scalar))
                .unwrap_or(base.rtol),
            atol: self
                .atol
                .or(scene.atol.map(Tol::Scalar))
                .unwrap_or(base.atol),
            first_step: self.first_step.or(scene.first_step).or(base.first_step),
            max_step: self.max_step.or(scene.max_step).unwrap_or(base.max_step),
            max_steps: self.max_steps.or(scene.max_steps).unwrap_or(base.max_steps),
            method,
            // The scene's dt belongs to its fixed-step method: a caller who picks an
            // adaptive one leaves it out (a dt of the caller's own is checked by the driver).
            dt: self
                .dt
                .or(base.dt)
                .or(scene.dt.filter(|_| method.is_fixed_step())),
            ..base
        }
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
    fn the_caller_beats_the_scene_which_beats_the_default() {
        let caller = Requested {
            t_span: Some((1.0, 0.0)),
            rtol: Some(Tol::PerComponent(vec![1e-4, 1e-4])),
            atol: Some(Tol::Scalar(1e-9)),
            first_step: Some(0.5),
            max_step: Some(0.2),
            max_steps: Some(7),
            disable: Some(Disabled::none()),
            ..Default::default()
        };
        let r = caller.resolve(&scene(), SolverOptions::default()).unwrap();
        assert_eq!(r.t_span, (1.0, 0.0));
        assert_eq!(r.disabled, Disabled::none());
        assert_eq!(r.opts.rtol, Tol::PerComponent(vec![1e-4, 1e-4]));
        assert_eq!(r.opts.atol, Tol::Scalar(1e-9));
        assert_eq!(
            (r.opts.first_step, r.opts.max_step, r.opts.max_steps),
            (Some(0.5), 0.2, 7)
        );

        let r = Requested::default()
            .resolve(&scene(), SolverOptions::default())
            .unwrap();
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

        let caller = Requested {
            t_span: Some((0.0, 1.0)),
            ..Default::default()
        };
        let base = SolverOptions {
            dense: true,
            ..Default::default()
        };
        let r = caller.resolve(&Settings::default(), base.clone()).unwrap();
        assert_eq!((r.opts, r.disabled), (base, Disabled::none()));
    }

    #[test]
    fn contact_and_joint_limits_default_to_auto_unless_disabled() {
        use crate::effects::{ContactPoint, GroundContact, JointLimit, JointRef, PerJoint};
        let contact = Effect::GroundContact(
            GroundContact::new(
                None,
                vec![ContactPoint {
                    body: JointRef::Index(0),
                    point: crate::spatial::Vec3::zeros(),
                    radius: 0.0,
                }],
                crate::spatial::Vec3::z(),
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
        let gravity = Effect::gravity(crate::spatial::Vec3::z()).unwrap();
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
        let e = Requested::default()
            .resolve(&Settings::default(), SolverOptions::default())
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "t_span: expected (t0, t_end): the scene sets none, got None"
        );
    }
}
