//! The banded solver's own order of the coordinates, so that its cost does not depend on how
//! the model's bodies were numbered. The banded QRs work on `Jᵀ` with the coordinates as
//! rows: a cut joint's rows touch the joints on its two bodies' paths to the root, and
//! their envelope is the span of those joints' positions. A numbering that adds every
//! vertical bar of the N-four-bar before every horizontal one puts each loop's three joints
//! ~N apart (a band of width N instead of 3: 3.6× the time of the interleaved numbering).
//!
//! As sparse solvers order columns, the order is chosen once per model from the structure
//! alone: a Cuthill–McKee sweep (breadth first from a pseudo-peripheral link, neighbours by
//! increasing degree) of the graph of links joined by tree joints, cut joints and couplings
//! ranks the links, then the tree is laid out in preorder (each subtree contiguous, parents
//! first: the mass matrix's Cholesky factor stays inside each tree's block), children and
//! roots by the least rank in their subtree. It replaces the model's order only when its
//! [`profile`] is smaller, so an already good numbering runs exactly as before.
use crate::model::Model;

/// A coordinate order: `order[i]` is the model's v index at the solver's position `i`.
pub struct CoordinateOrder {
    pub order: Vec<usize>,
    /// `tree_end[i]`: one past the last position of the tree (under one root joint) that
    /// holds position `i`; the mass matrix and its factor are zero past it in column `i`.
    pub tree_end: Vec<usize>,
}

/// Each link's neighbours: its parent and children, and the links a cut joint or a coupling
/// joins to it (sorted, without repeats).
fn link_graph(model: &Model) -> Vec<Vec<usize>> {
    let nl = model.links.len();
    let mut adj = vec![Vec::new(); nl];
    let link_of = |body: Option<usize>| body.and_then(|b| model.bodies.get(b)?.link);
    let mut join = |a: Option<usize>, b: Option<usize>| {
        if let (Some(a), Some(b)) = (a, b) {
            if a != b && a < nl && b < nl {
                adj[a].push(b);
                adj[b].push(a);
            }
        }
    };
    for (l, link) in model.links.iter().enumerate() {
        join(Some(l), link.parent);
    }
    for lp in &model.loops {
        join(link_of(lp.body_a), link_of(lp.body_b));
    }
    for c in &model.couplings {
        join(link_of(Some(c.joint)), link_of(Some(c.reference)));
    }
    for a in &mut adj {
        a.sort_unstable();
        a.dedup();
    }
    adj
}

/// Breadth-first levels from `start` over the links not yet `ranked`, neighbours by
/// increasing (degree, index); `out` receives the links in visiting order. Returns where the
/// last level starts in `out` and the number of levels.
fn sweep(
    adj: &[Vec<usize>],
    ranked: &[bool],
    start: usize,
    seen: &mut [bool],
    out: &mut Vec<usize>,
) -> (usize, usize) {
    out.clear();
    seen.fill(false);
    seen[start] = true;
    out.push(start);
    let (mut level_start, mut head, mut levels) = (0, 0, 0);
    while head < out.len() {
        let level_end = out.len();
        level_start = head;
        levels += 1;
        while head < level_end {
            let l = out[head];
            head += 1;
            let first = out.len();
            for &k in &adj[l] {
                if !seen[k] && !ranked[k] {
                    seen[k] = true;
                    out.push(k);
                }
            }
            out[first..].sort_unstable_by_key(|&k| (adj[k].len(), k));
        }
    }
    (level_start, levels)
}

/// Cuthill–McKee ranks of the links: each connected component from a pseudo-peripheral link
/// (George and Liu: from the last level's least-degree link while that lengthens the sweep).
fn cuthill_mckee(adj: &[Vec<usize>]) -> Vec<usize> {
    let nl = adj.len();
    let mut rank = vec![usize::MAX; nl];
    let mut ranked = vec![false; nl];
    let (mut seen, mut out) = (vec![false; nl], Vec::with_capacity(nl));
    let mut next = 0;
    for first in 0..nl {
        if ranked[first] {
            continue;
        }
        let mut start = first;
        let (mut last, mut depth) = sweep(adj, &ranked, start, &mut seen, &mut out);
        for _ in 0..nl {
            let candidate = *out[last..]
                .iter()
                .min_by_key(|&&k| (adj[k].len(), k))
                .unwrap_or(&start);
            let (l, d) = sweep(adj, &ranked, candidate, &mut seen, &mut out);
            if d <= depth {
                break;
            }
            (start, last, depth) = (candidate, l, d);
        }
        sweep(adj, &ranked, start, &mut seen, &mut out);
        for &l in &out {
            rank[l] = next;
            ranked[l] = true;
            next += 1;
        }
    }
    rank
}

/// The links in preorder, each node's children (and the roots) by the least Cuthill–McKee
/// rank in their subtree. `None` if a link's parent does not precede it.
fn preorder(model: &Model, rank: &[usize]) -> Option<Vec<usize>> {
    let nl = model.links.len();
    let mut key = rank.to_vec();
    for l in (0..nl).rev() {
        if let Some(p) = model.links[l].parent {
            if p >= l {
                return None;
            }
            key[p] = key[p].min(key[l]);
        }
    }
    let mut children = vec![Vec::new(); nl];
    let mut roots = Vec::new();
    for (l, link) in model.links.iter().enumerate() {
        match link.parent {
            Some(p) => children[p].push(l),
            None => roots.push(l),
        }
    }
    // A stack: pushed in decreasing key so the least comes off first.
    roots.sort_unstable_by_key(|&l| std::cmp::Reverse(key[l]));
    for c in &mut children {
        c.sort_unstable_by_key(|&l| std::cmp::Reverse(key[l]));
    }
    let mut stack = roots;
    let mut out = Vec::with_capacity(nl);
    while let Some(l) = stack.pop() {
        out.push(l);
        stack.extend_from_slice(&children[l]);
    }
    Some(out)
}

/// The positions of the model's coordinates (`position[v] = i` with `order[i] = v`).
fn positions(order: &[usize]) -> Vec<usize> {
    let mut position = vec![0; order.len()];
    for (i, &v) in order.iter().enumerate() {
        position[v] = i;
    }
    position
}

/// One past the last position of each position's tree (the links under one root).
fn tree_ends(model: &Model, position: &[usize]) -> Vec<usize> {
    let nl = model.links.len();
    let root = |mut l: usize| {
        while let Some(p) = model.links[l].parent {
            l = p;
        }
        l
    };
    let roots: Vec<usize> = (0..nl).map(root).collect();
    let mut end = vec![0; nl];
    for (l, link) in model.links.iter().enumerate() {
        for v in link.v_index..link.v_index + link.joint.nv() {
            end[roots[l]] = end[roots[l]].max(position[v] + 1);
        }
    }
    let mut out = vec![0; position.len()];
    for (l, link) in model.links.iter().enumerate() {
        for v in link.v_index..link.v_index + link.joint.nv() {
            out[position[v]] = end[roots[l]];
        }
    }
    out
}

/// Each constraint row's structural positions `lo[r]..hi[r]` under `position`: a cut
/// joint's, the span of the joints on its two bodies' paths to the root (as
/// `constraints::jacobian` fills them); a coupling's, every position.
pub fn structural_rows(model: &Model, position: &[usize], lo: &mut [usize], hi: &mut [usize]) {
    let n = model.nv;
    lo.fill(0);
    hi.fill(n);
    let mut r = 0;
    for lp in &model.loops {
        let (mut a, mut b) = (n, 0);
        for body in [lp.body_a, lp.body_b].into_iter().flatten() {
            let mut next = model.bodies.get(body).and_then(|x| x.link);
            while let Some(l) = next {
                let link = &model.links[l];
                for v in link.v_index..link.v_index + link.joint.nv() {
                    a = a.min(position[v]);
                    b = b.max(position[v] + 1);
                }
                next = link.parent;
            }
        }
        for _ in 0..lp.kind().rows() {
            (lo[r], hi[r]) = (a, b.max(a));
            r += 1;
        }
    }
}

/// The banded factorisations' work under `position`, structurally: per cut-joint row, the
/// span of `Jᵀ`'s column (the joints on its paths) plus that of `Y = L⁻¹ Jᵀ`'s (to the end
/// of the trees of those joints: the Cholesky factor fills a tree's block below them).
pub fn profile(model: &Model, position: &[usize]) -> usize {
    let m = model.nconstraints();
    let (mut lo, mut hi) = (vec![0; m], vec![0; m]);
    structural_rows(model, position, &mut lo, &mut hi);
    let ends = tree_ends(model, position);
    let mut total = 0;
    let mut r = 0;
    for lp in &model.loops {
        let mut reach = hi[r];
        for body in [lp.body_a, lp.body_b].into_iter().flatten() {
            if let Some(l) = model.bodies.get(body).and_then(|x| x.link) {
                let v = model.links[l].v_index;
                reach = reach.max(ends[position[v]]);
            }
        }
        let rows = lp.kind().rows();
        total += rows * (hi[r] - lo[r] + reach - lo[r]);
        r += rows;
    }
    total
}

/// The coordinates of the links in preorder by `rank` (`None` if the tree's links are not
/// numbered parents first).
fn laid_out(model: &Model, rank: &[usize]) -> Option<Vec<usize>> {
    let mut order = Vec::with_capacity(model.nv);
    for l in preorder(model, rank)? {
        let link = &model.links[l];
        order.extend(link.v_index..link.v_index + link.joint.nv());
    }
    (order.len() == model.nv).then_some(order)
}

/// The order for the banded solver: `None` when the model's own is at least as good.
pub fn choose(model: &Model) -> Option<CoordinateOrder> {
    let cm = cuthill_mckee(&link_graph(model));
    // Parents come first in the layout, so the sweep's direction matters (a chain swept
    // from its far end would put each v_k before the h_k that leads to it): both are tried.
    let reversed: Vec<usize> = cm.iter().map(|&r| cm.len() - 1 - r).collect();
    let identity: Vec<usize> = (0..model.nv).collect();
    let mut best = (profile(model, &identity), None);
    for rank in [cm, reversed] {
        let Some(order) = laid_out(model, &rank) else {
            continue;
        };
        let p = profile(model, &positions(&order));
        if p < best.0 {
            best = (p, Some(order));
        }
    }
    let order = best.1?;
    let tree_end = tree_ends(model, &positions(&order));
    Some(CoordinateOrder { order, tree_end })
}

/// The positions of an order (the inverse permutation).
pub fn inverse(order: &[usize]) -> Vec<usize> {
    positions(order)
}

/// What [`super::solver_layout`] reports: whether the banded QRs are taken, the solver's
/// order of the coordinates, and the [`profile`] of that order and of the model's own.
pub struct Layout {
    pub banded: bool,
    pub order: Vec<usize>,
    pub profile: usize,
    pub model_profile: usize,
}

pub fn layout(model: &Model, banded: bool, order: &[usize]) -> Layout {
    let identity: Vec<usize> = (0..model.nv).collect();
    Layout {
        banded,
        order: order.to_vec(),
        profile: profile(model, &positions(order)),
        model_profile: profile(model, &identity),
    }
}

/// Fewest speeds for the banded QRs: below, the dense ones cost microseconds anyway, and
/// their column pivoting picks the best-conditioned independent rows.
pub const ENVELOPE_MIN_NV: usize = 24;

/// Whether the banded QRs pay: a long mechanism whose constraint rows touch at most a
/// quarter of the coordinates on average (structurally: a cut joint's rows touch the joints
/// on its two bodies' paths to the root, a coupling's two).
pub(super) fn envelope_pays(model: &Model) -> bool {
    let (m, n) = (model.nconstraints(), model.nv);
    if n < ENVELOPE_MIN_NV || m == 0 {
        return false;
    }
    let mut seen = vec![usize::MAX; model.links.len()];
    let mut touched = 2 * model.couplings.len();
    for (k, lp) in model.loops.iter().enumerate() {
        let mut cols = 0;
        for body in [lp.body_a, lp.body_b].into_iter().flatten() {
            let mut next = model.bodies.get(body).and_then(|b| b.link);
            while let Some(l) = next {
                if seen[l] != k {
                    seen[l] = k;
                    cols += model.links[l].joint.nv();
                }
                next = model.links[l].parent;
            }
        }
        touched += cols * lp.kind().rows();
    }
    4 * touched <= m * n
}
