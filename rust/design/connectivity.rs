//! Connected links as linear constraints (docs/design.md §3, "Connected links"): flows
//! through the faces between a link's cells, each face's flow bounded by the lesser fill of
//! its two cells (`x_j / upper_j`). Two families, linear in the cell masses and the flows:
//!
//! * **web**: for every boss but the first, a flow of `web` from the first boss to it. By
//!   max-flow/min-cut it exists exactly when every set of faces separating the two bosses
//!   has `Σ min(fill_a, fill_b) ≥ web`: every cross-section between two joints holds at
//!   least `web` cell faces of material.
//! * **hang**: one flow from all the bosses that each cell draws its own fill from, a face
//!   carrying at most `hang × min(fill_a, fill_b)`: every region of cells without a boss is
//!   joined to the rest by faces holding `Σ min fill ≥ (its fill) / hang`.
//!
//! The flows are variables of their own; the program stays convex and Clarabel's
//! certificate covers them.
use crate::support::error::{Error, Result};

use clarabel::solver::SupportedConeT;

/// One link's connectivity requirement over its cells (design variables).
#[derive(Debug, Clone)]
pub struct Flow {
    /// The design variables (cells) of the link, by local node index.
    pub nodes: Vec<usize>,
    /// Face-neighbour pairs, local node indices.
    pub edges: Vec<(usize, usize)>,
    /// Each pin's boss (local node indices, cells held full), the first the web's source.
    pub bosses: Vec<Vec<usize>>,
    /// Cross-section (in cell faces) the web between the first boss and each other carries.
    pub web: f64,
    /// Cells' worth of fill one face may carry in the hanging flow (0: no hanging flow).
    pub hang: f64,
}

impl Flow {
    /// Variables: per web commodity the edges' flows, the source's and the sink's boss
    /// terms; the hanging flow: the edges' flows and every boss cell's supply.
    pub fn count(&self) -> usize {
        let e = self.edges.len();
        let src = self.bosses.first().map_or(0, Vec::len);
        let web: usize = self.bosses.iter().skip(1).map(|b| e + src + b.len()).sum();
        let hang = if self.hang > 0.0 {
            e + self.bosses.iter().map(Vec::len).sum::<usize>()
        } else {
            0
        };
        web + hang
    }

    /// Checks indices and numbers.
    pub fn check(&self, nx: usize, upper: &[f64]) -> Result<()> {
        let n = self.nodes.len();
        let bad = |what: &str, got: String| Err(Error::arg("flows", what.to_string(), got));
        if let Some(&j) = self
            .nodes
            .iter()
            .find(|&&j| j >= nx || !upper[j].is_finite())
        {
            return bad(
                "cells among the design masses, each with a finite upper bound",
                format!("design mass {j}"),
            );
        }
        if let Some(e) = self
            .edges
            .iter()
            .find(|e| e.0 >= n || e.1 >= n || e.0 == e.1)
        {
            return bad("edges between distinct cells of the link", format!("{e:?}"));
        }
        if self.bosses.iter().flatten().any(|&v| v >= n) || self.bosses.iter().any(Vec::is_empty) {
            return bad(
                "non-empty bosses of cells of the link",
                "an empty or outside boss".into(),
            );
        }
        if !(self.web.is_finite() && self.web >= 0.0 && self.hang.is_finite() && self.hang >= 0.0) {
            return bad(
                "web >= 0 and hang >= 0",
                format!("{} and {}", self.web, self.hang),
            );
        }
        if self.bosses.is_empty() {
            return bad("at least one boss", "none".into());
        }
        Ok(())
    }
}

/// Sparse rows: `(row, column, value)` triplets, right-hand sides, and the cones in order.
pub(crate) struct Rows<'a> {
    pub rows: &'a mut Vec<usize>,
    pub cols: &'a mut Vec<usize>,
    pub vals: &'a mut Vec<f64>,
    pub b: &'a mut Vec<f64>,
    pub cones: &'a mut Vec<SupportedConeT<f64>>,
}

impl Rows<'_> {
    fn row(&mut self, rhs: f64) -> usize {
        self.b.push(rhs);
        self.b.len() - 1
    }
    fn put(&mut self, r: usize, c: usize, v: f64) {
        self.rows.push(r);
        self.cols.push(c);
        self.vals.push(v);
    }
}

/// Appends every flow's rows (variables from column `at`): conservation at each cell
/// (zero cone), then the faces' capacities and the boss terms' signs (nonnegative cone).
pub(crate) fn append(out: &mut Rows, flows: &[Flow], upper: &[f64], mut at: usize) {
    for flow in flows {
        let src = &flow.bosses[0];
        for sink in flow.bosses.iter().skip(1) {
            commodity(out, flow, upper, at, src, Some(sink), 1.0);
            at += flow.edges.len() + src.len() + sink.len();
        }
        if flow.hang > 0.0 {
            let all: Vec<usize> = flow.bosses.iter().flatten().copied().collect();
            commodity(out, flow, upper, at, &all, None, flow.hang);
            at += flow.edges.len() + all.len();
        }
    }
}

/// One commodity: edge flows `f` (signed, columns `at..`), supplies `s ≥ 0` at `src`, and
/// either draws `d ≥ 0` at `sink` with `Σ s = web`, or, without a sink, every cell drawing
/// its own fill. Capacity `|f_e| ≤ scale · fill` at both ends.
fn commodity(
    out: &mut Rows,
    flow: &Flow,
    upper: &[f64],
    at: usize,
    src: &[usize],
    sink: Option<&Vec<usize>>,
    scale: f64,
) {
    let fill = |v: usize| 1.0 / upper[flow.nodes[v]];
    let (ne, n) = (flow.edges.len(), flow.nodes.len());
    let (s_at, d_at) = (at + ne, at + ne + src.len());
    // Conservation: out − in − supply + draw = 0 at each cell.
    let first = out.b.len();
    for _ in 0..n {
        out.row(0.0);
    }
    for (e, &(a, b)) in flow.edges.iter().enumerate() {
        out.put(first + a, at + e, 1.0);
        out.put(first + b, at + e, -1.0);
    }
    for (k, &v) in src.iter().enumerate() {
        out.put(first + v, s_at + k, -1.0);
    }
    match sink {
        Some(sink) => {
            for (k, &v) in sink.iter().enumerate() {
                out.put(first + v, d_at + k, 1.0);
            }
            // Σ s = web (Σ d follows from conservation).
            let r = out.row(flow.web);
            (0..src.len()).for_each(|k| out.put(r, s_at + k, 1.0));
        }
        None => (0..n).for_each(|v| out.put(first + v, flow.nodes[v], fill(v))),
    }
    out.cones
        .push(SupportedConeT::ZeroConeT(out.b.len() - first));
    // |f_e| ≤ scale · x_j / u_j at both ends; boss terms ≥ 0.
    let first = out.b.len();
    for (e, &(a, b)) in flow.edges.iter().enumerate() {
        for end in [a, b] {
            for sign in [1.0, -1.0] {
                let r = out.row(0.0);
                out.put(r, at + e, sign);
                out.put(r, flow.nodes[end], -scale * fill(end));
            }
        }
    }
    for k in 0..src.len() + sink.map_or(0, Vec::len) {
        let r = out.row(0.0);
        out.put(r, s_at + k, -1.0);
    }
    out.cones
        .push(SupportedConeT::NonnegativeConeT(out.b.len() - first));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::{solve, Norm, Problem};

    /// A row of cells `0..lower.len()` (each of bound 1) with the mass minimised, joined by
    /// `flow` (bosses, web, hang) when given.
    fn row(lower: Vec<f64>, flow: Option<(Vec<Vec<usize>>, f64, f64)>) -> Problem {
        let n = lower.len();
        Problem {
            lower,
            upper: vec![1.0; n],
            map: (0..n).map(|j| (0, j, 1.0)).collect(),
            ndelta: 1,
            groups: vec![],
            equal: vec![],
            quantities: vec![],
            norm: Norm::Rms,
            mass_weight: 1.0,
            mass_reference: 1.0,
            mass_limit: None,
            least_mass: false,
            flows: flow
                .map(|(bosses, web, hang)| Flow {
                    nodes: (0..n).collect(),
                    edges: (0..n - 1).map(|j| (j, j + 1)).collect(),
                    bosses,
                    web,
                    hang,
                })
                .into_iter()
                .collect(),
        }
    }

    /// A row of five cells, bosses at both ends (held full): with the mass minimised, the
    /// web makes the three between carry a fill of `web` each (min-cut: one face each).
    #[test]
    fn a_web_fills_the_cells_between_two_bosses() {
        let ends = || vec![1.0, 0.0, 0.0, 0.0, 1.0];
        let web = |web: f64| row(ends(), Some((vec![vec![0], vec![4]], web, 0.0)));
        let s = solve(&web(0.5)).unwrap();
        for j in 1..4 {
            assert!((s.x[j] - 0.5).abs() < 1e-7, "{:?}", s.x);
        }
        let s = solve(&row(ends(), None)).unwrap();
        assert!(s.x[1..4].iter().all(|&x| x.abs() < 1e-7), "{:?}", s.x);
        // A web of more than a full cell cannot pass one cell's face.
        assert!(solve(&web(1.5)).is_err());
    }

    /// Hanging: a cell forced to hold material (lower bound) pulls a path of fill at least
    /// its own fill / hang back to the boss.
    #[test]
    fn hanging_material_is_joined_to_a_boss() {
        let problem = row(vec![1.0, 0.0, 0.0, 0.8], Some((vec![vec![0]], 0.0, 4.0)));
        let s = solve(&problem).unwrap();
        // A face carries what hangs beyond it, at most 4 × the lesser fill: face 1–2 carries
        // f2 + 0.8 ≤ 4 f2, face 0–1 carries f1 + f2 + 0.8 ≤ 4 f1. The least f1 + f2:
        // f2 = 0.8 / 3, f1 = (f2 + 0.8) / 3.
        let f2 = 0.8 / 3.0;
        assert!((s.x[2] - f2).abs() < 1e-7, "{:?}", s.x);
        assert!((s.x[1] - (f2 + 0.8) / 3.0).abs() < 1e-7, "{:?}", s.x);
    }
}
