//! A scene's equations evaluated at one state, from a caller's arguments (a binding's
//! objects, through [`Arg`]): what `effect_forces`, `energies`, `Scene.state_jacobian` and
//! the scene's derivatives return, parsed, computed and checked here in one call each.
use super::config_args::{scene_state, time};
use super::derivatives::SceneDerivatives;
use super::{disabled, Dynamics};
use crate::io::scene::Scene;
use crate::support::args::{opt, vector, Arg};

/// The scene's equations of motion with the `disable`d families (the caller's, else the
/// scene's) left out.
pub fn scene_dynamics<'s, A: Arg>(
    s: &'s Scene,
    disable: Option<&A>,
) -> Result<Dynamics<'s>, A::Err> {
    let disabled = disabled(crate::effects::args::disable(disable)?, &s.settings);
    Ok(Dynamics::try_new(&s.model, &s.effects, disabled)?)
}

/// [`Dynamics::labelled_effect_forces`] at the caller's `(t, q, v)`.
pub fn effect_forces<A: Arg>(
    s: &Scene,
    t: &A,
    (q, v): (&A, &A),
    disable: Option<&A>,
) -> Result<Vec<(String, Vec<f64>)>, A::Err> {
    let t = time(t.real("t")?)?;
    let (q, v) = scene_state(s, q, v)?;
    Ok(scene_dynamics(s, disable)?.labelled_effect_forces(t, &q, &v)?)
}

/// [`Dynamics::labelled_energies`] at the caller's `(q, v)`.
pub fn energies<A: Arg>(
    s: &Scene,
    (q, v): (&A, &A),
    disable: Option<&A>,
) -> Result<Vec<(String, f64)>, A::Err> {
    let (q, v) = scene_state(s, q, v)?;
    Ok(scene_dynamics(s, disable)?.labelled_energies(&q, &v)?)
}

/// [`Dynamics::forward_derivatives`] at the caller's `(t, q, v)` with joint forces `tau`.
pub fn forward_derivatives<A: Arg>(
    s: &Scene,
    t: f64,
    (q, v, tau): (&A, &A, Option<&A>),
    disable: Option<&A>,
) -> Result<SceneDerivatives, A::Err> {
    let (t, (q, v)) = (time(t)?, scene_state(s, q, v)?);
    let tau = opt(tau, |x| vector(x, "tau", Some(s.model.nv)))?;
    let mut sys = scene_dynamics(s, disable)?;
    Ok(sys.forward_derivatives(t, &q, &v, tau.as_deref())?)
}

/// [`Dynamics::inverse_derivatives_of`] at the caller's `(t, q, v)` and accelerations `a`.
pub fn inverse_derivatives<A: Arg>(
    s: &Scene,
    t: f64,
    (q, v, a): (&A, &A, &A),
    disable: Option<&A>,
) -> Result<SceneDerivatives, A::Err> {
    let (t, (q, v)) = (time(t)?, scene_state(s, q, v)?);
    let a = vector(a, "a", Some(s.model.nv))?;
    Ok(scene_dynamics(s, disable)?.inverse_derivatives_of(t, &q, &v, &a)?)
}

/// [`Dynamics::checked_state_jacobian`] at the caller's `(t, y)`.
pub fn state_jacobian<A: Arg>(
    s: &Scene,
    t: f64,
    y: &A,
    disable: Option<&A>,
) -> Result<Option<Vec<f64>>, A::Err> {
    let (nq, nv) = (s.model.nq, s.model.nv);
    let (t, y) = (time(t)?, vector(y, "y", Some(nq + nv))?);
    s.model.check_state(&y[..nq], Some(&y[nq..]))?;
    Ok(scene_dynamics(s, disable)?.checked_state_jacobian(t, &y)?)
}
