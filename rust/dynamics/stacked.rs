//! `Model.point_regressor` and `Model.shaking` over one state or a stack of them: the
//! computation run, its arrays named, shaped (a leading axis of the states done for a
//! stack) and checked finite, and an early stop (an interrupt) described, so that the
//! binding only converts.
use super::reactions::{self, States};
use crate::model::args::{self as args, about, body_points, check_rows, gravity, Stack};
use crate::model::Model;
use crate::support::args::Arg;
use crate::support::error::{check_result, Error, Result};
use crate::support::spatial::Vec3;

/// Named arrays, each with its shape, and why the states stopped short, if they did.
pub struct Stacked {
    pub arrays: Vec<(&'static str, Vec<f64>, Vec<usize>)>,
    pub stopped: Option<Stop>,
}

/// A computation stopped after `states` states: `why`, and a `message` saying how far it came.
pub struct Stop {
    pub why: Error,
    pub states: usize,
    pub message: String,
}

/// The states of `q`, `v`, `a` row by row: `count` of them for a stack, `None` for one.
pub type StateRows<'a> = (Option<usize>, [&'a [f64]; 3]);

/// The states checked row by row (`check_rows`: Ctrl-C honoured, a bad row named).
fn states<'a>(model: &Model, (count, [q, v, a]): StateRows<'a>) -> Result<States<'a>> {
    check_rows(model, count, q, v, a)?;
    let rows = count.unwrap_or(1);
    Ok(States { rows, q, v, a })
}

impl Stacked {
    /// `items` (key, values of the `done` states, shape per state) of `what` over `total`
    /// states, each checked finite.
    fn new<const N: usize>(
        what: &str,
        (stack, total): (bool, usize),
        done: usize,
        stopped: Option<Error>,
        items: [(&'static str, Vec<f64>, &[usize]); N],
    ) -> Result<Self> {
        let mut arrays = Vec::with_capacity(N);
        for (key, x, tail) in items {
            check_result(&format!("{what}['{key}']"), &x)?;
            let lead = stack.then_some(done);
            arrays.push((
                key,
                x,
                lead.into_iter().chain(tail.iter().copied()).collect(),
            ));
        }
        let stopped = stopped.map(|why| Stop {
            why,
            states: done,
            message: format!("{what} stopped after {done} of {total} states: interrupted"),
        });
        Ok(Stacked { arrays, stopped })
    }
}

/// [`reactions::point_regressor`]: `positions`, `accelerations` (P, 3) and `generalized`
/// (P, nv) per state.
pub fn point_regressor(
    model: &Model,
    rows: StateRows<'_>,
    points: &[(usize, Vec3)],
    g: &Vec3,
) -> Result<Stacked> {
    let states = states(model, rows)?;
    let done = reactions::point_regressor(model, &states, points, g)?;
    let (np, nv, r) = (points.len(), model.nv, done.value);
    Stacked::new(
        "point_regressor",
        (rows.0.is_some(), states.rows),
        done.rows,
        done.stopped,
        [
            ("positions", r.positions, &[np, 3]),
            ("accelerations", r.accelerations, &[np, 3]),
            ("generalized", r.generalized, &[np, nv]),
        ],
    )
}

/// [`reactions::shaking_of_states`]: `force` and `moment` (3,) per state.
pub fn shaking(model: &Model, rows: StateRows<'_>, about: &Vec3) -> Result<Stacked> {
    let states = states(model, rows)?;
    let done = reactions::shaking_of_states(model, &states, about);
    let (force, moment) = done.value;
    Stacked::new(
        "shaking",
        (rows.0.is_some(), states.rows),
        done.rows,
        done.stopped,
        [("force", force, &[3]), ("moment", moment, &[3])],
    )
}

/// `point_regressor`'s or `shaking`'s arguments read: the states (`q`, `v`, `a`, one or a
/// stack, their shapes checked; their values row by row by the computation), and gravity
/// and the points, or the point the moments are taken about (the others left empty).
pub struct Call {
    states: Stack,
    g: Vec3,
    points: Vec<(usize, Vec3)>,
    about: Vec3,
}

impl Call {
    /// `point_regressor`'s: gravity, the states, then the points (`None`: every point mass).
    pub fn point_regressor<A: Arg>(
        model: &Model,
        [q, v, a]: [&A; 3],
        points: Option<&A>,
        g: Option<&A>,
    ) -> std::result::Result<Self, A::Err> {
        let g = gravity(g)?;
        let states = args::states(model, q, v, a)?;
        let points = body_points(model, points)?;
        let about = Vec3::zeros();
        Ok(Call {
            states,
            g,
            points,
            about,
        })
    }

    /// `shaking`'s: the states, then `about` (`None`: the world origin).
    pub fn shaking<A: Arg>(
        model: &Model,
        [q, v, a]: [&A; 3],
        point: Option<&A>,
    ) -> std::result::Result<Self, A::Err> {
        let states = args::states(model, q, v, a)?;
        let (g, points, about) = (Vec3::zeros(), vec![], about(point)?);
        Ok(Call {
            states,
            g,
            points,
            about,
        })
    }

    /// [`point_regressor`] of the call read by [`Call::point_regressor`].
    pub fn regressor(&self, model: &Model) -> Result<Stacked> {
        let (count, q, v, a) = &self.states;
        point_regressor(model, (*count, [q, v, a]), &self.points, &self.g)
    }

    /// [`shaking`] of the call read by [`Call::shaking`].
    pub fn shaking_forces(&self, model: &Model) -> Result<Stacked> {
        let (count, q, v, a) = &self.states;
        shaking(model, (*count, [q, v, a]), &self.about)
    }
}
