//! The identification calls' options as a binding hands them over ([`Arg`]: a mapping of
//! keywords), parsed here once: the extra columns, the fit's method, columns, prior,
//! weights, cells and actuated joints; and a regressor given as an array.
use nalgebra::DMatrix;

use super::{Extras, Identified, LinkCells, Method, Options};
use crate::model::args::{check_rows, states, Stack};
use crate::model::Model;
use crate::support::args::{count, flag, items, text, vector, Arg};
use crate::support::error::{check_result, Error};
use crate::support::spatial::Vec3;

type R<T, A> = std::result::Result<T, <A as Arg>::Err>;

/// The fit's keywords; any other is refused (a misspelt one would be silently ignored).
const FIT_KEYS: [&str; 13] = [
    "gravity",
    "method",
    "free",
    "prior",
    "prior_weight",
    "weights",
    "cells",
    "viscous",
    "coulomb",
    "armature",
    "offset",
    "rank_tol",
    "actuated",
];

/// The extra columns `(viscous, coulomb, armature, offset)`.
pub fn extras((viscous, coulomb, armature, offset): (bool, bool, bool, bool)) -> Extras {
    Extras {
        viscous,
        coulomb,
        armature,
        offset,
    }
}

/// The fit's options and gravity from its keywords (`FIT_KEYS`; absent: the defaults).
pub fn fit_options<A: Arg>(o: Option<&A>) -> R<(Options, Vec3), A> {
    for key in o.and_then(|o| o.keys()).unwrap_or_default() {
        let name = key.text().unwrap_or_default();
        if !FIT_KEYS.contains(&name.as_str()) {
            let expected = format!("keywords among {}", FIT_KEYS.join(", "));
            return Err(Error::arg("options", expected, key.shown()).into());
        }
    }
    let key = |k: &str| o.and_then(|o| o.get(k)).flatten().filter(|x| !x.absent());
    let on = |k: &str| key(k).map_or(Ok(false), |x| flag(&x, k));
    let numbers = |k: &str| key(k).map_or(Ok(vec![]), |x| vector(&x, k, None));
    let real = |k: &str, default: f64| key(k).map_or(Ok(default), |x| x.real(k));
    let method = match key("method").map(|m| text(&m, "method", "'cells' or 'ols'")) {
        None => Method::Ols,
        Some(m) => match m?.as_str() {
            "ols" => Method::Ols,
            "cells" => Method::Cells(cells(key("cells").as_ref())?),
            other => {
                return Err(Error::arg("method", "'cells' or 'ols'", format!("{other:?}")).into())
            }
        },
    };
    let free = match key("free") {
        Some(f) => items(&f, "free", "a list of bools")?
            .iter()
            .map(|x| flag(x, "free"))
            .collect::<Result<_, _>>()?,
        None => vec![],
    };
    let actuated = match key("actuated") {
        Some(x) => items(&x, "actuated", "a list of v indices")?
            .iter()
            .map(|i| count(i, "actuated", "a v index"))
            .collect::<Result<_, _>>()?,
        None => vec![],
    };
    let options = Options {
        extras: extras((
            on("viscous")?,
            on("coulomb")?,
            on("armature")?,
            on("offset")?,
        )),
        free,
        prior: numbers("prior")?,
        prior_weight: real("prior_weight", 0.0)?,
        weights: numbers("weights")?,
        rank_tol: real("rank_tol", 1e-8)?,
        method,
        actuated,
    };
    Ok((
        options,
        crate::model::args::gravity(key("gravity").as_ref())?,
    ))
}

/// `[(link, centres (n, 3), side), ...]`: each identified link's cells.
fn cells<A: Arg>(x: Option<&A>) -> R<Vec<LinkCells>, A> {
    let expected = "a list of (link index, centres (n, 3), side)";
    let Some(x) = x else { return Ok(vec![]) };
    let mut out = Vec::new();
    for item in items(x, "cells", expected)? {
        let parts = items(&item, "cells", expected)?;
        let [link, centres, side] = &parts[..] else {
            return Err(Error::arg("cells", expected, item.shown()).into());
        };
        let (shape, data) = centres.array("cells")?;
        if shape.len() < 2 || shape[shape.len() - 1] != 3 {
            let got = crate::support::args::shape_str(&shape);
            return Err(Error::arg("cells", "centres of shape (n, 3)", got).into());
        }
        out.push(LinkCells {
            link: count(link, "cells", "a link index")?,
            centres: data.chunks_exact(3).map(Vec3::from_column_slice).collect(),
            side: side.real("cells")?,
        });
    }
    Ok(out)
}

/// A regressor given as a 2-d array (rows, columns).
pub fn regressor<A: Arg>(y: &A) -> R<DMatrix<f64>, A> {
    let (shape, data) = y.array("regressor")?;
    let &[rows, cols] = shape.as_slice() else {
        return Err(Error::arg("regressor", "a 2-d array", format!("{shape:?}")).into());
    };
    Ok(DMatrix::from_row_slice(rows, cols, &data))
}

/// An identification call's arguments read: the states (`q`, `v`, `a` stacked, their shapes
/// checked; their values row by row when computing, which may take long), gravity, and for
/// a fit the joint forces and options.
pub struct Call {
    pub states: Stack,
    pub g: Vec3,
    pub tau: Vec<f64>,
    pub options: Options,
}

/// `identification_regressor`'s arguments: gravity, then the states.
pub fn regressor_call<A: Arg>(model: &Model, [q, v, a]: [&A; 3], g: Option<&A>) -> R<Call, A> {
    let g = crate::model::args::gravity(g)?;
    let states = states(model, q, v, a)?;
    let options = fit_options::<A>(None)?.0;
    Ok(Call {
        states,
        g,
        tau: vec![],
        options,
    })
}

/// `identification_fit`'s arguments: the states, `tau`, then the options (keywords).
pub fn fit_call<A: Arg>(model: &Model, [q, v, a, tau]: [&A; 4], options: Option<&A>) -> R<Call, A> {
    let states = states(model, q, v, a)?;
    let tau = tau.array("tau")?.1;
    let (options, g) = fit_options(options)?;
    Ok(Call {
        states,
        g,
        tau,
        options,
    })
}

impl Call {
    /// The states checked row by row (Ctrl-C honoured).
    fn checked(&self, model: &Model) -> crate::support::error::Result<[&[f64]; 3]> {
        let (count, q, v, a) = &self.states;
        check_rows(model, *count, q, v, a)?;
        Ok([q, v, a])
    }

    /// The joint-force regressor with the `extras` columns (of the `actuated` joints' forces
    /// alone, if any), checked finite.
    pub fn regressor(
        &self,
        model: &Model,
        extras: &Extras,
        actuated: &[usize],
    ) -> crate::support::error::Result<DMatrix<f64>> {
        let [q, v, a] = self.checked(model)?;
        let y = super::joint_force_regressor(model, q, v, a, &self.g, extras, actuated)?;
        check_result("torque regressor", y.as_slice())?;
        Ok(y)
    }

    /// The fit ([`super::identify`]).
    pub fn identify(&self, model: &Model) -> crate::support::error::Result<Identified> {
        let [q, v, a] = self.checked(model)?;
        super::identify(model, q, v, a, &self.tau, &self.g, &self.options)
    }
}
