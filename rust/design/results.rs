//! The design calls' results as the bindings hand them over, each field a plain value: the
//! maps along a motion with the links' parameters now ([`maps`]), and a pin's load with its
//! source spelt out ([`PinRecord`]).
use super::strength::{pin_loads, PinSource};
use super::{model_parameters, regressor};
use crate::dynamics::stacked::StateRows;
use crate::model::args::check_rows;
use crate::model::Model;
use crate::support::error::{check_result, Result};
use crate::support::spatial::{Mat3, Vec3};
use nalgebra::DMatrix;

/// [`regressor`] along a motion: `data` (N · rows, 10 · nlinks), its layout, and
/// `parameters`, the links' current ten numbers.
pub struct Maps {
    pub data: DMatrix<f64>,
    pub rows: usize,
    pub nactuated: usize,
    pub nlinks: usize,
    pub nloops: usize,
    pub parameters: Vec<f64>,
}

/// The maps along stacked states `(q, v, a)` (checked row by row: `check_rows`) under
/// gravity `g`, moments about `about`, checked finite.
pub fn maps(
    model: &Model,
    (count, [q, v, a]): StateRows<'_>,
    (g, about): (&Vec3, &Vec3),
    actuated: &[usize],
) -> Result<Maps> {
    check_rows(model, count, q, v, a)?;
    let reg = regressor(model, q, v, a, g, about, actuated)?;
    check_result("design regressor", reg.data.as_slice())?;
    let (layout, parameters) = (reg.layout, model_parameters(model));
    Ok(Maps {
        rows: layout.rows(),
        nactuated: layout.nactuated,
        nlinks: layout.nlinks,
        nloops: layout.nloops,
        data: reg.data,
        parameters,
    })
}

/// A pin of body `b` (`pin_loads`' order) with where its force comes from: `kind` "joint"
/// or "cut", `index` (link or cut joint), `sign`, `frame_body` (the body whose axes the
/// rows are in after `frame_rotation`; -1: the world).
pub struct PinRecord {
    pub point: Vec<f64>,
    pub axis: Vec<f64>,
    pub kind: String,
    pub index: usize,
    pub sign: f64,
    pub frame_body: i64,
    pub frame_rotation: Mat3,
}

/// The pins of body `b`, each a [`PinRecord`].
pub fn pin_records(model: &Model, b: usize) -> Vec<PinRecord> {
    let record = |p: super::strength::PinLoad| {
        let (kind, index, sign, frame_body, frame_rotation) = match p.source {
            PinSource::Tree { link, sign } => ("joint", link, sign, -1, Mat3::identity()),
            PinSource::Cut {
                k,
                sign,
                body_a,
                frame_a,
            } => ("cut", k, sign, body_a.map_or(-1, |a| a as i64), frame_a),
        };
        let (point, axis) = (p.point.as_slice().to_vec(), p.axis.as_slice().to_vec());
        let kind = kind.to_string();
        PinRecord {
            point,
            axis,
            kind,
            index,
            sign,
            frame_body,
            frame_rotation,
        }
    };
    pin_loads(model, b).into_iter().map(record).collect()
}
