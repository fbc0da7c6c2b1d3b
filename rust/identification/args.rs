//! The identification calls' options as a binding hands them over ([`Arg`]: a mapping of
//! keywords), parsed here once: the extra columns, the fit's method, columns, prior,
//! weights, cells and actuated joints; and a regressor given as an array.
use nalgebra::DMatrix;

use super::{Extras, LinkCells, Method, Options};
use crate::support::args::{count, flag, items, text, vector, Arg};
use crate::support::error::Error;
use crate::support::spatial::Vec3;

type R<T, A> = Result<T, <A as Arg>::Err>;

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
pub fn fit_options<A: Arg>(o: &A) -> R<(Options, Vec3), A> {
    for key in o.keys().unwrap_or_default() {
        let name = key.text().unwrap_or_default();
        if !FIT_KEYS.contains(&name.as_str()) {
            let expected = format!("keywords among {}", FIT_KEYS.join(", "));
            return Err(Error::arg("options", expected, key.shown()).into());
        }
    }
    let key = |k: &str| o.get(k).flatten().filter(|x| !x.absent());
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
