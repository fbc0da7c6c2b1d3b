//! `Model.point_motion` and `Model.bearing_forces` at one state as a binding hands its
//! arguments over ([`Arg`]): parsed, computed and checked here, so the binding converts.
use super::reactions::{self, BearingForces, PointMotion};
use crate::model::args::{external, gravity, loop_actuation, one_state};
use crate::model::Model;
use crate::recursive::reference::Workspace;
use crate::support::args::Arg;
use crate::support::error::check_result;

/// The links' point masses in motion at the state `(q, v, a)`, checked finite.
pub fn point_motion<A: Arg>(model: &Model, [q, v, a]: [&A; 3]) -> Result<PointMotion, A::Err> {
    let [q, v, a] = one_state(model, q, v, a)?;
    let mut pm = PointMotion::default();
    reactions::point_motion(model, &mut Workspace::new(model), &q, &v, &a, &mut pm);
    pm.check_finite("point_motion")?;
    Ok(pm)
}

/// What every joint transmits at the state `(q, v, a)` under `gravity` and `external`
/// wrenches, a model with loops driven by `actuated`; in the joints' axes or, `frame`
/// "world", the world's; checked finite.
pub fn bearing_forces<A: Arg>(
    model: &Model,
    [q, v, a]: [&A; 3],
    (g, ext, actuated): (Option<&A>, Option<&A>, Option<&A>),
    frame: &str,
) -> Result<BearingForces, A::Err> {
    let world = reactions::world_frame(frame)?;
    let g = gravity(g)?;
    let [q, v, a] = one_state(model, q, v, a)?;
    let ext = external(model, ext)?;
    let actuated = loop_actuation(model, actuated)?;
    let (ext, actuated) = (ext.as_deref(), actuated.as_deref());
    let out = reactions::bearing_forces(model, &q, &v, &a, &g, ext, actuated, world)?;
    check_result("bearing_forces", &out.joints)?;
    Ok(out)
}
