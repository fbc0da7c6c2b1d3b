//! An [`Envelope`] from a binding's arrays, and a [`Problem`] from its mapping ([`Arg`]): the design program as
//! `pointmass_dyn.design` states it (built by our Python, not by users), read key by key into
//! typed fields here, once, so the binding only converts. Every refusal names the key.
use nalgebra::{DMatrix, DVector};

use super::results::{maps, Maps};
use super::{Envelope, Flow, Norm, Problem, Quantity};
use crate::model::args::{states, Stack};
use crate::model::Model;
use crate::support::args::{choice, count, flag, given, items, text, vec3, vector, Arg};
use crate::support::error::Error;
use crate::support::spatial::Vec3;

/// `spec[key]`, required (`None` counts as given: optional keys read it so).
fn key<A: Arg>(spec: &A, key: &str) -> Result<A, A::Err> {
    match spec.get(key) {
        Some(Some(x)) => Ok(x),
        Some(None) => Err(Error::arg(key, "a value", "a missing key").into()),
        None => Err(spec.wrong_type(key, "a dict")),
    }
}

fn real<A: Arg>(spec: &A, k: &str) -> Result<f64, A::Err> {
    key(spec, k)?.real(k)
}

/// `spec[key]`, `None` (or missing) for nothing said.
fn opt_real<A: Arg>(spec: &A, k: &str) -> Result<Option<f64>, A::Err> {
    match spec.get(k).flatten().filter(|x| !x.absent()) {
        Some(x) => x.real(k).map(Some),
        None => Ok(None),
    }
}

/// The entries of an array of real numbers, in C order.
fn reals<A: Arg>(x: &A, arg: &str) -> Result<Vec<f64>, A::Err> {
    Ok(x.array(arg)?.1)
}

/// A sequence of counts (indices).
fn counts<A: Arg>(x: &A, arg: &str) -> Result<Vec<usize>, A::Err> {
    let expected = "a list of indices >= 0";
    let list = items(x, arg, expected)?;
    list.iter().map(|n| count(n, arg, expected)).collect()
}

/// A sequence of fixed-length tuples, each read by `f`.
fn tuples<A: Arg, T>(
    x: &A,
    arg: &str,
    len: usize,
    f: impl Fn(&[A]) -> Result<T, A::Err>,
) -> Result<Vec<T>, A::Err> {
    let expected = format!("a list of {len}-tuples");
    let mut out = Vec::new();
    for t in items(x, arg, &expected)? {
        let t = items(&t, arg, &expected)?;
        if t.len() != len {
            return Err(Error::arg(arg, expected, format!("a {}-tuple", t.len())).into());
        }
        out.push(f(&t)?);
    }
    Ok(out)
}

fn pairs<A: Arg>(x: &A, arg: &str) -> Result<Vec<(usize, usize)>, A::Err> {
    let idx = "an index >= 0";
    tuples(x, arg, 2, |t| {
        Ok((count(&t[0], arg, idx)?, count(&t[1], arg, idx)?))
    })
}

impl Problem {
    /// The program from `spec`, a mapping with the keys of [`Problem`] (the map as
    /// `map_rows`/`map_cols`/`map_vals`; `flows` optional), the sizes checked against
    /// each other.
    pub fn from_arg<A: Arg>(spec: &A) -> Result<Problem, A::Err> {
        let ndelta = count(&key(spec, "ndelta")?, "ndelta", "a count >= 0")?;
        let rows = counts(&key(spec, "map_rows")?, "map_rows")?;
        let cols = counts(&key(spec, "map_cols")?, "map_cols")?;
        let vals = reals(&key(spec, "map_vals")?, "map_vals")?;
        if cols.len() != rows.len() || vals.len() != rows.len() {
            let expected = "rows, columns and values of one length";
            return Err(Error::arg("map", expected, "different lengths").into());
        }
        let groups = tuples(&key(spec, "groups")?, "groups", 3, |t| {
            Ok((
                counts(&t[0], "groups")?,
                t[1].real("groups")?,
                t[2].real("groups")?,
            ))
        })?;
        let norm = [("rms", Norm::Rms), ("peak", Norm::Peak)];
        let quantities = items(&key(spec, "quantities")?, "quantities", "a list of dicts")?;
        let flows = match spec.get("flows").flatten().filter(|x| !x.absent()) {
            Some(f) => items(&f, "flows", "a list of dicts")?,
            None => Vec::new(),
        };
        Ok(Problem {
            lower: reals(&key(spec, "lower")?, "lower")?,
            upper: reals(&key(spec, "upper")?, "upper")?,
            map: rows
                .into_iter()
                .zip(cols)
                .zip(vals)
                .map(|((r, c), v)| (r, c, v))
                .collect(),
            ndelta,
            groups,
            equal: pairs(&key(spec, "equal")?, "equal")?,
            quantities: quantities
                .iter()
                .map(|q| quantity(q, ndelta))
                .collect::<Result<_, _>>()?,
            norm: choice(&key(spec, "norm")?, "norm", &norm, "\"rms\" or \"peak\"")?,
            mass_weight: real(spec, "mass_weight")?,
            mass_reference: real(spec, "mass_reference")?,
            mass_limit: opt_real(spec, "mass_limit")?,
            least_mass: flag(&key(spec, "least_mass")?, "least_mass")?,
            flows: flows.iter().map(flow).collect::<Result<_, _>>()?,
        })
    }
}

/// One quantity: `rows` (R, ndelta), `constant` (R,), and its weights and limits.
fn quantity<A: Arg>(q: &A, ndelta: usize) -> Result<Quantity, A::Err> {
    let name = text(&key(q, "name")?, "name", "a string")?;
    let (shape, rows) = key(q, "rows")?.array("quantities")?;
    if shape.len() != 2 || shape[1] != ndelta {
        let want = format!("rows of shape (R, {ndelta})");
        return Err(Error::arg(name, want, format!("{shape:?}")).into());
    }
    let samples = count(&key(q, "samples")?, "samples", "a count >= 0")?;
    // A member's stress: its limit at every sample whatever the norm (optional key).
    let peak = match q.get("peak").flatten() {
        Some(p) => flag(&p, "peak")?,
        None => false,
    };
    Ok(Quantity {
        rows: DMatrix::from_row_slice(shape[0], ndelta, &rows),
        constant: DVector::from_vec(reals(&key(q, "constant")?, "constant")?),
        dim: count(&key(q, "dim")?, "dim", "a count >= 0")?,
        samples,
        weight: real(q, "weight")?,
        reference: real(q, "reference")?,
        limit: opt_real(q, "limit")?,
        zero: flag(&key(q, "zero")?, "zero")?,
        peak,
        name,
    })
}

/// Connected links' flows (crate::design::connectivity).
fn flow<A: Arg>(f: &A) -> Result<Flow, A::Err> {
    let bosses = items(&key(f, "bosses")?, "bosses", "a list of index lists")?;
    Ok(Flow {
        nodes: counts(&key(f, "nodes")?, "nodes")?,
        edges: pairs(&key(f, "edges")?, "edges")?,
        bosses: bosses
            .iter()
            .map(|b| counts(b, "bosses"))
            .collect::<Result<_, _>>()?,
        web: real(f, "web")?,
        hang: real(f, "hang")?,
    })
}

/// An array of `shape[1..]`-sized rows (`shape[0]` of them): its entries, or `expected`
/// refused naming `arg` and the shape given.
fn rows<A: Arg>(x: &A, arg: &str, tail: &[usize], expected: &str) -> Result<Vec<f64>, A::Err> {
    let (shape, data) = x.array(arg)?;
    if shape.len() != tail.len() + 1 || shape[1..] != *tail {
        return Err(Error::arg(arg, expected, format!("shape {shape:?}")).into());
    }
    Ok(data)
}

impl Envelope {
    /// Exactly one of a `box` (2, 3) of (lower, upper) corners, a `polygon` (P, 2) extruded
    /// over `z` (z_low, z_high), or a mesh of `triangles` (T, 3, 3).
    pub fn from_args<A: Arg>(
        r#box: Option<&A>,
        polygon: Option<&A>,
        z: Option<&A>,
        triangles: Option<&A>,
    ) -> Result<Envelope, A::Err> {
        let v = |c: &[f64]| Vec3::new(c[0], c[1], c[2]);
        Ok(match (given(r#box), given(polygon), given(triangles)) {
            (Some(b), None, None) => {
                let c = rows(b, "box", &[3], "an (N, 3) array")?;
                if c.len() != 6 {
                    let got = format!("{} points", c.len() / 3);
                    return Err(Error::arg("box", "(lower, upper) corners", got).into());
                }
                Envelope::Box {
                    lower: v(&c[..3]),
                    upper: v(&c[3..]),
                }
            }
            (None, Some(p), None) => {
                let p = rows(p, "polygon", &[2], "a (P, 2) array of vertices")?;
                let Some(z) = given(z) else {
                    return Err(Error::arg("z", "(z_low, z_high) for a polygon", "None").into());
                };
                let z = vector(z, "z", Some(2))?;
                let polygon = p.chunks(2).map(|c| [c[0], c[1]]).collect();
                Envelope::Prism {
                    polygon,
                    z: (z[0], z[1]),
                }
            }
            (None, None, Some(t)) => {
                let t = rows(t, "triangles", &[3, 3], "a (T, 3, 3) array")?;
                let triangles = t
                    .chunks(9)
                    .map(|c| [v(c), v(&c[3..]), v(&c[6..])])
                    .collect();
                Envelope::Mesh { triangles }
            }
            _ => {
                let expected = "exactly one of box, polygon or triangles";
                return Err(Error::arg("envelope", expected, "none or several").into());
            }
        })
    }
}

/// `design_regressor`'s motion: the states (`q`, `v`, `a` stacked, their shapes checked;
/// their values row by row by [`MapsCall::maps`], which may take long), gravity and the
/// point the moments are taken about.
pub struct MapsCall {
    states: Stack,
    g: Vec3,
    about: Vec3,
}

impl MapsCall {
    /// Gravity, `about`, then the states.
    pub fn from_args<A: Arg>(
        model: &Model,
        [q, v, a]: [&A; 3],
        g: Option<&A>,
        about: &A,
    ) -> Result<Self, A::Err> {
        let g = crate::model::args::gravity(g)?;
        let about = vec3(about, "about")?;
        let states = states(model, q, v, a)?;
        Ok(MapsCall { states, g, about })
    }

    /// The maps of the `actuated` joints along the motion ([`maps`]).
    pub fn maps(&self, model: &Model, actuated: &[usize]) -> crate::support::error::Result<Maps> {
        let (count, q, v, a) = &self.states;
        maps(model, (*count, [q, v, a]), (&self.g, &self.about), actuated)
    }
}
