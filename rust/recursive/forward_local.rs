//! Body-frame articulated-body forward dynamics (Featherstone / Pinocchio style).
//!
//! The same recursion as `forward::forward_dynamics_world` — twists `[ω; v_O]` about each
//! link origin, "twist rates" `[ω̇; a_O]` (classical accelerations), the Newton–Euler wrench
//! `M ṫ + [ω × I ω; ω × (ω × h)]` — but every per-link quantity is kept in the link's own
//! frame. Then the link inertia is the constant one built from the seven point masses (no
//! rotation per call), the joint columns are constant for revolute, prismatic and quaternion
//! joints (`S = [a; 0]`, `[0; a]`, `[1; 0]`) and depend on ψ, θ only for ZYZ, and no world
//! orientation is needed (except to bring external wrenches, given in world axes, into the
//! body). Going from link `i` to its parent takes the joint's rotation `E` (child axes in
//! parent axes) and offset `r` (child origin in parent coordinates): twists go down as
//! `[Eᵀ ω; Eᵀ (v + ω × r)]`, wrenches up as `[E n + r × E f; E f]`, articulated inertias up
//! as `E M Eᵀ` by 3×3 blocks followed by the shift to the parent origin.
//!
//! Revolute joints about a coordinate axis (the common case) rotate blocks with a plane
//! rotation instead of a full 3×3 product. A placement that is a signed permutation (the
//! exact quarter and half turns of robot descriptions, `rpy = (±π/2, 0, 0)`) is absorbed into
//! the link frames (`local_links_of`); any other rotated joint frame gives `E = P R_axis(q)`,
//! with the constant `P` applied after the plane rotation — itself a plane rotation when `P`
//! turns about one coordinate axis. Each link's case is one dispatch code
//! (`LocalLink::kind`), and offsets along one axis take a shorter shift (`offset_axis`).
use super::{singular_message, Data};
use crate::error::{Error, Result};
use crate::joint::{axis_angle, quat_to_matrix, Joint};
use crate::model::{Link, Model};
use crate::spatial::{Mat3, Vec3, Vec6};
use crate::trig::{sin_cos, sin_cos4};

/// Per-link workspace of the body-frame recursion (all in the link's frame, about its origin).
#[derive(Debug, Clone, Copy)]
pub struct LocalLink {
    /// Link axes in parent axes (`x_parent = rot x + offset`); for a revolute joint about a
    /// coordinate axis (`kind` < 15) the constant placement rotation `P` instead (used when
    /// its placement kind is 4, general), the joint's own turn being `cs`.
    pub rot: Mat3,
    /// Link origin in parent coordinates.
    pub offset: Vec3,
    /// Link orientation in the world (only kept when external wrenches are given).
    pub world_rot: Mat3,
    /// Joint columns: their angular part (linear part for a prismatic joint).
    pub s: [Vec3; 3],
    pub twist: Vec6,
    /// Velocity-dependent twist rate `ξ` (body frame).
    pub xi: Vec6,
    pub inertia: LocalInertia,
    pub bias: Vec6,
    pub u: [Vec6; 3],
    pub d_inv: Mat3,
    pub u_tau: Vec3,
    pub accel: Vec6,
    /// A revolute joint about a coordinate axis: (cos, sin) of its turn.
    pub cs: (f64, f64),
    /// Dispatch code: `5 K + P` (0..15) for a revolute joint about coordinate axis `K`
    /// (x, y, z: 0, 1, 2) whose joint frame is placed by `P`: 0 no rotation, 1, 2, 3 a plane
    /// rotation about x, y, z by `pcs`, 4 a general one (in `rot`); [`OTHER_KIND`] for every
    /// other joint. Model constants.
    pub kind: u8,
    pub pcs: (f64, f64),
    /// How the offset lies: 0 zero, 1, 2, 3 along x, y, z only, 4 anywhere (always 4 for a
    /// prismatic joint, whose offset moves). Model constant; it picks the shift's form.
    pub offset_axis: u8,
    /// No children: the articulated inertia starts as the link's own (copied outward).
    pub leaf: bool,
    /// The child of its parent whose inward step comes first (the highest index): it writes
    /// the parent's articulated inertia as the parent's own plus its contribution, so that no
    /// link's inertia is copied before its children add into it.
    pub first_child: bool,
    /// A revolute joint about a coordinate axis: ±1 as it turns about `±e_K` in the
    /// recursion's link frames (see [`local_links_of`]). Model constant.
    pub sign: f64,
    /// Other joints: the constant placement in the recursion's frames (`x_parent =
    /// place_rot x + place_t` at q = 0), and whether it turns. Model constants.
    pub place_rot: Mat3,
    pub place_t: Vec3,
    pub place_rotated: bool,
}

/// `LocalLink::kind` of every joint other than a revolute joint about a coordinate axis.
pub const OTHER_KIND: u8 = u8::MAX;

impl Default for LocalLink {
    fn default() -> Self {
        LocalLink {
            rot: Mat3::identity(),
            offset: Vec3::zeros(),
            world_rot: Mat3::identity(),
            s: [Vec3::zeros(); 3],
            twist: Vec6::zeros(),
            xi: Vec6::zeros(),
            inertia: LocalInertia::default(),
            bias: Vec6::zeros(),
            u: [Vec6::zeros(); 3],
            d_inv: Mat3::zeros(),
            u_tau: Vec3::zeros(),
            accel: Vec6::zeros(),
            cs: (1.0, 0.0),
            pcs: (1.0, 0.0),
            kind: OTHER_KIND,
            offset_axis: 4,
            leaf: true,
            first_child: false,
            sign: 1.0,
            place_rot: Mat3::identity(),
            place_t: Vec3::zeros(),
            place_rotated: false,
        }
    }
}

/// Whether every entry of `m` is exactly 0 or ±1: for a rotation, a signed permutation (an
/// exact quarter or half turn, as `model::checked_rotation` snaps them).
fn is_signed_permutation(m: &Mat3) -> bool {
    m.iter().all(|&x| x == 0.0 || x.abs() == 1.0)
}

/// `(k, σ)` with `a = σ e_k`, if `a` is a signed coordinate axis.
fn coordinate_axis(a: &Vec3) -> Option<(usize, f64)> {
    (0..3).find_map(|k| {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        (a[i] == 0.0 && a[j] == 0.0 && a[k].abs() == 1.0).then_some((k, a[k]))
    })
}

/// The placement kind of a constant rotation `p` (`P` of `LocalLink::kind`) and, for a plane
/// rotation, its (cos, sin).
fn placement_kind(p: &Mat3) -> (u8, (f64, f64)) {
    if *p == Mat3::identity() {
        return (0, (1.0, 0.0));
    }
    // A turn about coordinate axis `a` (plane pair I, J) keeps e_a exactly and has the 2×2
    // block [[c, −s], [s, c]] in rows and columns I, J.
    for (a, i, j) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)] {
        let (c, sn) = (p[(i, i)], p[(j, i)]);
        let keeps_axis = p[(a, a)] == 1.0
            && p[(a, i)] == 0.0
            && p[(a, j)] == 0.0
            && p[(i, a)] == 0.0
            && p[(j, a)] == 0.0;
        if keeps_axis && p[(j, j)] == c && p[(i, j)] == -sn {
            return (a as u8 + 1, (c, sn));
        }
    }
    (4, (1.0, 0.0))
}

/// The link's workspace with its model constants, and its frame turn `Q` (see
/// [`local_links_of`]) given its parent's, `frame_p`.
///
/// A revolute joint about a coordinate axis `e_K` below a placement `P` that is a signed
/// permutation (the exact quarter turns of robot descriptions) absorbs `P` into the link
/// frame: with `Q = Q_p P`, `E = Q_p P R_K(q) Qᵀ = R_{Q e_K}(q)`, a turn about a coordinate
/// axis again, now without placement. Otherwise `Q = Q_p` and the placement becomes
/// `Q_p P Q_pᵀ` (a plane rotation stays one, about the permuted axis). Other joints keep
/// their own frame (`Q = 1`) and take `Q_p P` as placement.
pub(super) fn local_link_of(l: &Link, frame_p: &Mat3) -> (LocalLink, Mat3) {
    let mut out = LocalLink::default();
    let pl = &l.placement;
    // Signed permutations: these products are exact.
    let t = frame_p * pl.translation;
    out.offset = t;
    out.place_t = t;
    out.offset_axis = match l.joint {
        Joint::Prismatic { .. } => 4,
        _ if t == Vec3::zeros() => 0,
        _ if t.y == 0.0 && t.z == 0.0 => 1,
        _ if t.x == 0.0 && t.z == 0.0 => 2,
        _ if t.x == 0.0 && t.y == 0.0 => 3,
        _ => 4,
    };
    let on_axis = match l.joint {
        Joint::Revolute { axis } => coordinate_axis(&axis).map(|_| axis),
        _ => None,
    };
    if let Some(axis) = on_axis {
        let (frame, placement) = if is_signed_permutation(&pl.rotation) {
            (frame_p * pl.rotation, Mat3::identity())
        } else {
            (*frame_p, frame_p * pl.rotation * frame_p.transpose())
        };
        let turned = frame * axis;
        if let Some((k, sign)) = coordinate_axis(&turned) {
            let (kind, pcs) = placement_kind(&placement);
            out.sign = sign;
            out.s[0] = turned;
            out.pcs = pcs;
            out.rot = placement;
            out.kind = 5 * k as u8 + kind;
            return (out, frame);
        }
    }
    // Other joints keep their own frame: the parent's turn goes into the placement.
    out.place_rot = frame_p * pl.rotation;
    out.place_rotated = out.place_rot != Mat3::identity();
    match l.joint {
        Joint::Revolute { axis } => out.s[0] = axis,
        Joint::Prismatic { axis } => {
            out.s[0] = axis;
            out.rot = out.place_rot;
        }
        Joint::Spherical => out.s = [Vec3::x(), Vec3::y(), Vec3::z()],
        Joint::SphericalZYZ => {}
        Joint::Fixed => out.rot = out.place_rot,
    }
    (out, Mat3::identity())
}

/// Every link's body-frame workspace with its model constants ([`local_link_of`]) and its
/// place in the tree (`leaf`, `first_child`), and each link's own inertia in its (possibly
/// turned) frame, which starts its articulated inertia.
///
/// The recursion's link frames may differ from the model's by a signed permutation `Q`
/// (new coordinates `Q x`), chosen so that exact quarter-turn placements vanish; joint
/// coordinates keep their meaning (a joint now about `−e_K` turns by `−q`, `LocalLink::sign`)
/// and external wrenches are brought into the turned frames, so results do not depend on it.
pub(super) fn local_links_of(model: &Model) -> (Vec<LocalLink>, Vec<LocalInertia>) {
    let n = model.links.len();
    let mut links = Vec::with_capacity(n);
    let mut frames: Vec<Mat3> = Vec::with_capacity(n);
    let mut bodies = Vec::with_capacity(n);
    for l in &model.links {
        let frame_p = l.parent.map_or(Mat3::identity(), |p| frames[p]);
        let (link, frame) = local_link_of(l, &frame_p);
        let own = body_inertia_of(l);
        let turn = General(frame);
        bodies.push(LocalInertia {
            p: turn.conj_sym(&own.p),
            q: turn.conj::<false>(&own.q),
            r: turn.conj_sym(&own.r),
        });
        links.push(link);
        frames.push(frame);
    }
    // Links come parents first, so the inward loop meets each parent's children from the
    // highest index down.
    let mut seen = vec![false; n];
    for i in (0..n).rev() {
        if let Some(p) = model.links[i].parent {
            links[i].first_child = !seen[p];
            seen[p] = true;
        }
    }
    for (l, has_children) in links.iter_mut().zip(seen) {
        l.leaf = !has_children;
    }
    (links, bodies)
}

/// The link's own inertia about its origin as a `LocalInertia`, in the model's link frame.
fn body_inertia_of(l: &Link) -> LocalInertia {
    let bi = &l.inertia;
    let h = bi.first_moment;
    let mass = bi.mass;
    LocalInertia {
        p: Sym3::from_mat(&bi.rotational),
        q: Mat3::new(0.0, -h.z, h.y, h.z, 0.0, -h.x, -h.y, h.x, 0.0),
        r: Sym3([mass, mass, mass, 0.0, 0.0, 0.0]),
    }
}

impl LocalInertia {
    /// The first moment `h` (mass times COM) from the block `Q = h̃`.
    #[inline(always)]
    pub(super) fn first_moment(&self) -> Vec3 {
        Vec3::new(self.q[(2, 1)], self.q[(0, 2)], self.q[(1, 0)])
    }
}

/// A symmetric 3×3 matrix by its upper triangle: `[xx, yy, zz, xy, xz, yz]`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Sym3(pub [f64; 6]);

/// Index of entry `(i, j)` in `Sym3`.
#[inline(always)]
const fn sidx(i: usize, j: usize) -> usize {
    if i == j {
        i
    } else {
        i + j + 2 // (0, 1) → 3, (0, 2) → 4, (1, 2) → 5
    }
}

impl Sym3 {
    #[inline(always)]
    fn at(&self, i: usize, j: usize) -> f64 {
        self.0[sidx(i, j)]
    }
    #[inline(always)]
    fn from_mat(m: &Mat3) -> Self {
        Sym3([
            m[(0, 0)],
            m[(1, 1)],
            m[(2, 2)],
            m[(0, 1)],
            m[(0, 2)],
            m[(1, 2)],
        ])
    }
    #[inline(always)]
    pub(super) fn mul(&self, x: &Vec3) -> Vec3 {
        let [xx, yy, zz, xy, xz, yz] = self.0;
        Vec3::new(
            xx * x.x + xy * x.y + xz * x.z,
            xy * x.x + yy * x.y + yz * x.z,
            xz * x.x + yz * x.y + zz * x.z,
        )
    }
    /// `self − k a aᵀ`.
    #[inline(always)]
    fn sub_outer(&mut self, a: &Vec3, k: f64) {
        let ka = a * k;
        self.0[0] -= ka.x * a.x;
        self.0[1] -= ka.y * a.y;
        self.0[2] -= ka.z * a.z;
        self.0[3] -= ka.x * a.y;
        self.0[4] -= ka.x * a.z;
        self.0[5] -= ka.y * a.z;
    }
    pub fn to_mat(&self) -> Mat3 {
        let [xx, yy, zz, xy, xz, yz] = self.0;
        Mat3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
    }
}

/// Articulated inertia `[[P, Q], [Qᵀ, R]]` with the symmetric blocks stored as such.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LocalInertia {
    pub p: Sym3,
    pub q: Mat3,
    pub r: Sym3,
}

#[inline(always)]
pub(super) fn v3(t: &Vec6, o: usize) -> Vec3 {
    Vec3::new(t[o], t[o + 1], t[o + 2])
}

#[inline(always)]
pub(super) fn six(a: &Vec3, b: &Vec3) -> Vec6 {
    Vec6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

#[inline(always)]
pub(super) fn cross(a: &Vec3, b: &Vec3) -> Vec3 {
    Vec3::new(
        a.y * b.z - a.z * b.y,
        a.z * b.x - a.x * b.z,
        a.x * b.y - a.y * b.x,
    )
}

#[inline(always)]
pub(super) fn mul(m: &Mat3, x: &Vec3) -> Vec3 {
    Vec3::new(
        m[(0, 0)] * x.x + m[(0, 1)] * x.y + m[(0, 2)] * x.z,
        m[(1, 0)] * x.x + m[(1, 1)] * x.y + m[(1, 2)] * x.z,
        m[(2, 0)] * x.x + m[(2, 1)] * x.y + m[(2, 2)] * x.z,
    )
}

#[inline(always)]
pub(super) fn tr_mul(m: &Mat3, x: &Vec3) -> Vec3 {
    Vec3::new(
        m[(0, 0)] * x.x + m[(1, 0)] * x.y + m[(2, 0)] * x.z,
        m[(0, 1)] * x.x + m[(1, 1)] * x.y + m[(2, 1)] * x.z,
        m[(0, 2)] * x.x + m[(1, 2)] * x.y + m[(2, 2)] * x.z,
    )
}

/// `a b` for 3×3 matrices, written out.
#[inline(always)]
fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut c = Mat3::zeros();
    for j in 0..3 {
        for i in 0..3 {
            c[(i, j)] = a[(i, 0)] * b[(0, j)] + a[(i, 1)] * b[(1, j)] + a[(i, 2)] * b[(2, j)];
        }
    }
    c
}

/// A rotation `E` (child axes in parent axes) applied to vectors and 3×3 blocks.
pub(super) trait Rot: Copy {
    /// The identity (lets callers skip work at compile time).
    const IDENTITY: bool = false;
    /// `K < 3`: the joint's own turn is about coordinate axis `K` (a revolute joint there,
    /// `w_J = q̇ e_K`, no `v_J`, no `Ṡ q̇`); 3: unknown.
    const AXIS: usize = 3;
    /// `E x`.
    fn mul(&self, x: &Vec3) -> Vec3;
    /// `Eᵀ x`.
    fn tr_mul(&self, x: &Vec3) -> Vec3;
    /// `E X Eᵀ`; `SYM` when X (hence the result) is symmetric.
    fn conj<const SYM: bool>(&self, x: &Mat3) -> Mat3;
    /// `E X Eᵀ` for symmetric X.
    fn conj_sym(&self, x: &Sym3) -> Sym3;
    /// `R_p E` (world orientation of the child from its parent's).
    fn after(&self, rp: &Mat3) -> Mat3;
}

#[derive(Clone, Copy)]
pub(super) struct General(pub(super) Mat3);

impl Rot for General {
    #[inline(always)]
    fn mul(&self, x: &Vec3) -> Vec3 {
        mul(&self.0, x)
    }
    #[inline(always)]
    fn tr_mul(&self, x: &Vec3) -> Vec3 {
        tr_mul(&self.0, x)
    }
    #[inline(always)]
    fn conj<const SYM: bool>(&self, x: &Mat3) -> Mat3 {
        let e = &self.0;
        // Y = X Eᵀ: Y[r][c] = Σ_k X[r][k] E[c][k].
        let mut y = Mat3::zeros();
        for c in 0..3 {
            for r in 0..3 {
                y[(r, c)] = x[(r, 0)] * e[(c, 0)] + x[(r, 1)] * e[(c, 1)] + x[(r, 2)] * e[(c, 2)];
            }
        }
        let mut z = Mat3::zeros();
        for c in 0..3 {
            for r in 0..3 {
                if SYM && r > c {
                    continue;
                }
                let v = e[(r, 0)] * y[(0, c)] + e[(r, 1)] * y[(1, c)] + e[(r, 2)] * y[(2, c)];
                z[(r, c)] = v;
                if SYM {
                    z[(c, r)] = v;
                }
            }
        }
        z
    }
    #[inline(always)]
    fn conj_sym(&self, x: &Sym3) -> Sym3 {
        let e = &self.0;
        // Y = E X (full), then the upper triangle of Y Eᵀ.
        let mut y = Mat3::zeros();
        for c in 0..3 {
            for r in 0..3 {
                y[(r, c)] =
                    e[(r, 0)] * x.at(0, c) + e[(r, 1)] * x.at(1, c) + e[(r, 2)] * x.at(2, c);
            }
        }
        let z = |r: usize, c: usize| {
            y[(r, 0)] * e[(c, 0)] + y[(r, 1)] * e[(c, 1)] + y[(r, 2)] * e[(c, 2)]
        };
        Sym3([z(0, 0), z(1, 1), z(2, 2), z(0, 1), z(0, 2), z(1, 2)])
    }
    #[inline(always)]
    fn after(&self, rp: &Mat3) -> Mat3 {
        mat_mul(rp, &self.0)
    }
}

/// Rotation by an angle (cosine `c`, sine `s`) about a coordinate axis, turning `e_I`
/// towards `e_J`: `E e_I = c e_I + s e_J`, `E e_J = −s e_I + c e_J` (x: I, J = 1, 2; y: 2, 0;
/// z: 0, 1).
#[derive(Clone, Copy)]
pub(super) struct Plane<const I: usize, const J: usize> {
    pub(super) c: f64,
    pub(super) s: f64,
}

impl<const I: usize, const J: usize> Plane<I, J> {
    #[inline(always)]
    pub(super) fn new((c, s): (f64, f64)) -> Self {
        Plane { c, s }
    }
}

impl<const I: usize, const J: usize> Rot for Plane<I, J> {
    const AXIS: usize = 3 - I - J;
    #[inline(always)]
    fn mul(&self, x: &Vec3) -> Vec3 {
        let mut y = *x;
        y[I] = self.c * x[I] - self.s * x[J];
        y[J] = self.s * x[I] + self.c * x[J];
        y
    }
    #[inline(always)]
    fn tr_mul(&self, x: &Vec3) -> Vec3 {
        let mut y = *x;
        y[I] = self.c * x[I] + self.s * x[J];
        y[J] = -self.s * x[I] + self.c * x[J];
        y
    }
    #[inline(always)]
    fn conj<const SYM: bool>(&self, x: &Mat3) -> Mat3 {
        let (c, s) = (self.c, self.s);
        // Rows first: Y = E X.
        let mut y = *x;
        for col in 0..3 {
            let (a, b) = (x[(I, col)], x[(J, col)]);
            y[(I, col)] = c * a - s * b;
            y[(J, col)] = s * a + c * b;
        }
        // Then columns: Z = Y Eᵀ.
        let mut z = y;
        for row in 0..3 {
            let (a, b) = (y[(row, I)], y[(row, J)]);
            z[(row, I)] = c * a - s * b;
            z[(row, J)] = s * a + c * b;
        }
        z
    }
    #[inline(always)]
    fn conj_sym(&self, x: &Sym3) -> Sym3 {
        const { assert!(I < 3 && J < 3 && I != J) };
        let k = 3 - I - J;
        let (c, s) = (self.c, self.s);
        let (a, b, d) = (x.at(I, I), x.at(I, J), x.at(J, J));
        let (cc, ss, cs) = (c * c, s * s, c * s);
        let cs2b = 2.0 * cs * b;
        let mut out = *x;
        out.0[sidx(I, I)] = cc * a - cs2b + ss * d;
        out.0[sidx(J, J)] = ss * a + cs2b + cc * d;
        out.0[sidx(I, J)] = cs * (a - d) + (cc - ss) * b;
        let (ik, jk) = (x.at(I, k), x.at(J, k));
        out.0[sidx(I, k)] = c * ik - s * jk;
        out.0[sidx(J, k)] = s * ik + c * jk;
        out
    }
    #[inline(always)]
    fn after(&self, rp: &Mat3) -> Mat3 {
        let mut out = *rp;
        for row in 0..3 {
            let (x, y) = (rp[(row, I)], rp[(row, J)]);
            out[(row, I)] = self.c * x + self.s * y;
            out[(row, J)] = -self.s * x + self.c * y;
        }
        out
    }
}

/// No rotation: the placement of a joint frame that is not rotated in its parent.
#[derive(Clone, Copy)]
pub(super) struct Identity;

impl Rot for Identity {
    const IDENTITY: bool = true;
    #[inline(always)]
    fn mul(&self, x: &Vec3) -> Vec3 {
        *x
    }
    #[inline(always)]
    fn tr_mul(&self, x: &Vec3) -> Vec3 {
        *x
    }
    #[inline(always)]
    fn conj<const SYM: bool>(&self, x: &Mat3) -> Mat3 {
        *x
    }
    #[inline(always)]
    fn conj_sym(&self, x: &Sym3) -> Sym3 {
        *x
    }
    #[inline(always)]
    fn after(&self, rp: &Mat3) -> Mat3 {
        *rp
    }
}

/// `E = P J`: the joint's rotation `J` in a joint frame placed by the constant `P`.
#[derive(Clone, Copy)]
pub(super) struct Placed<P: Rot, J: Rot>(pub(super) P, pub(super) J);

impl<P: Rot, J: Rot> Rot for Placed<P, J> {
    const IDENTITY: bool = P::IDENTITY && J::IDENTITY;
    const AXIS: usize = J::AXIS;
    #[inline(always)]
    fn mul(&self, x: &Vec3) -> Vec3 {
        self.0.mul(&self.1.mul(x))
    }
    #[inline(always)]
    fn tr_mul(&self, x: &Vec3) -> Vec3 {
        self.1.tr_mul(&self.0.tr_mul(x))
    }
    #[inline(always)]
    fn conj<const SYM: bool>(&self, x: &Mat3) -> Mat3 {
        self.0.conj::<SYM>(&self.1.conj::<SYM>(x))
    }
    #[inline(always)]
    fn conj_sym(&self, x: &Sym3) -> Sym3 {
        self.0.conj_sym(&self.1.conj_sym(x))
    }
    #[inline(always)]
    fn after(&self, rp: &Mat3) -> Mat3 {
        self.1.after(&self.0.after(rp))
    }
}

/// Shifts articulated-inertia blocks (parent axes, about the child origin) to the parent
/// origin, which sits at `−r` from the child origin: `AᵀMA` with `A = [[1, 0], [K, 1]]`,
/// `K = −r̃` (`[[P + QK + (QK)ᵀ − KRK, Q − KR], [·, R]]`), and deposits the result in `out`
/// (see [`deposit`]). `ZR < 3`: row and column `ZR` of `p` and row `ZR` of `q` are zero (and
/// not read). `offset_axis` (`LocalLink::offset_axis`) picks the form: coincident origins
/// need no shift, and an offset along one coordinate axis makes `K` two entries (a third of
/// the products).
#[inline(always)]
pub(super) fn shift_add<const ZR: usize>(
    p: &Sym3,
    q: &Mat3,
    rr: &Sym3,
    r: &Vec3,
    offset_axis: u8,
    start: Option<&LocalInertia>,
    out: &mut LocalInertia,
) {
    match offset_axis {
        // Coincident origins (common in robot descriptions: intersecting wrist axes).
        0 => deposit(out, start, p, q, rr),
        1 => shift_on_axis::<ZR, 0, 1, 2>(p, q, rr, r.x, start, out),
        2 => shift_on_axis::<ZR, 1, 2, 0>(p, q, rr, r.y, start, out),
        3 => shift_on_axis::<ZR, 2, 0, 1>(p, q, rr, r.z, start, out),
        _ => shift_general::<ZR>(p, q, rr, r, start, out),
    }
}

/// `out = start + (P, Q, R)` when this child writes first, else `out += (P, Q, R)`.
#[inline(always)]
fn deposit(out: &mut LocalInertia, start: Option<&LocalInertia>, p: &Sym3, q: &Mat3, r: &Sym3) {
    match start {
        Some(s) => {
            for k in 0..6 {
                out.p.0[k] = s.p.0[k] + p.0[k];
                out.r.0[k] = s.r.0[k] + r.0[k];
            }
            out.q = s.q + q;
        }
        None => {
            for k in 0..6 {
                out.p.0[k] += p.0[k];
                out.r.0[k] += r.0[k];
            }
            out.q += q;
        }
    }
}

/// [`shift_add`] for an offset `t e_A` ((A, B, C) cyclic): `K` has only `K_BC = t`,
/// `K_CB = −t`, so `QK` has two columns, `KR` two rows and `KRK` the (B, C) block
/// `−t² [[R_CC, −R_BC], [−R_BC, R_BB]]`.
#[inline(always)]
fn shift_on_axis<const ZR: usize, const A: usize, const B: usize, const C: usize>(
    p: &Sym3,
    q: &Mat3,
    rr: &Sym3,
    t: f64,
    start: Option<&LocalInertia>,
    out: &mut LocalInertia,
) {
    let tt = t * t;
    // Known zeros (row/column ZR) are `None` and left out at compile time, not added as 0.0.
    let pz = |a: usize, b: usize| (a != ZR && b != ZR).then(|| p.at(a, b));
    let qt = |a: usize, b: usize, k: f64| (a != ZR).then(|| q[(a, b)] * k);
    let mut dp = Sym3::default();
    // (QK)_aC = t Q_aB, (QK)_aB = −t Q_aC, (QK)_aA = 0.
    dp.0[sidx(A, A)] = sum([pz(A, A)]);
    dp.0[sidx(B, B)] = sum([pz(B, B), qt(B, C, -2.0 * t), Some(tt * rr.at(C, C))]);
    dp.0[sidx(C, C)] = sum([pz(C, C), qt(C, B, 2.0 * t), Some(tt * rr.at(B, B))]);
    dp.0[sidx(B, C)] = sum([
        pz(B, C),
        qt(B, B, t),
        qt(C, C, -t),
        Some(-(tt * rr.at(B, C))),
    ]);
    dp.0[sidx(A, B)] = sum([pz(A, B), qt(A, C, -t)]);
    dp.0[sidx(A, C)] = sum([pz(A, C), qt(A, B, t)]);
    // Q − KR: row B − t R_C·, row C + t R_B·.
    let mut dq = Mat3::zeros();
    for col in 0..3 {
        dq[(A, col)] = sum([qt(A, col, 1.0)]);
        dq[(B, col)] = sum([qt(B, col, 1.0), Some(-(t * rr.at(C, col)))]);
        dq[(C, col)] = sum([qt(C, col, 1.0), Some(t * rr.at(B, col))]);
    }
    deposit(out, start, &dp, &dq, rr);
}

/// The sum, left to right, of the terms that are not known zeros (`None`); 0 if none is left.
#[inline(always)]
fn sum<const N: usize>(terms: [Option<f64>; N]) -> f64 {
    let mut acc: Option<f64> = None;
    #[allow(clippy::needless_range_loop)] // an index loop unrolls; `into_iter().flatten()` did not
    for k in 0..N {
        if let Some(x) = terms[k] {
            acc = Some(match acc {
                Some(a) => a + x,
                None => x,
            });
        }
    }
    acc.unwrap_or(0.0)
}

/// [`shift_add`] for an offset anywhere.
#[inline(always)]
fn shift_general<const ZR: usize>(
    p: &Sym3,
    q: &Mat3,
    rr: &Sym3,
    r: &Vec3,
    start: Option<&LocalInertia>,
    out: &mut LocalInertia,
) {
    // K = skew(−r) = [[0, z, −y], [−z, 0, x], [y, −x, 0]].
    let (x, y, z) = (r.x, r.y, r.z);
    let mut qk = Mat3::zeros();
    let mut kr = Mat3::zeros();
    for a in 0..3 {
        if a != ZR {
            qk[(a, 0)] = -q[(a, 1)] * z + q[(a, 2)] * y;
            qk[(a, 1)] = q[(a, 0)] * z - q[(a, 2)] * x;
            qk[(a, 2)] = -q[(a, 0)] * y + q[(a, 1)] * x;
        }
        kr[(0, a)] = z * rr.at(1, a) - y * rr.at(2, a);
        kr[(1, a)] = -z * rr.at(0, a) + x * rr.at(2, a);
        kr[(2, a)] = y * rr.at(0, a) - x * rr.at(1, a);
    }
    // (KR)K, symmetric.
    let krk = |a: usize, b: usize| match b {
        0 => -kr[(a, 1)] * z + kr[(a, 2)] * y,
        1 => kr[(a, 0)] * z - kr[(a, 2)] * x,
        _ => -kr[(a, 0)] * y + kr[(a, 1)] * x,
    };
    let mut dp = Sym3::default();
    for (k, (a, b)) in [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
        .into_iter()
        .enumerate()
    {
        dp.0[k] = if a == ZR && b == ZR {
            -krk(a, b)
        } else if a == ZR {
            qk[(b, a)] - krk(a, b)
        } else if b == ZR {
            qk[(a, b)] - krk(a, b)
        } else {
            p.0[k] + qk[(a, b)] + qk[(b, a)] - krk(a, b)
        };
    }
    let mut dq = Mat3::zeros();
    for b in 0..3 {
        for a in 0..3 {
            dq[(a, b)] = if a == ZR {
                -kr[(a, b)]
            } else {
                q[(a, b)] - kr[(a, b)]
            };
        }
    }
    deposit(out, start, &dp, &dq, rr);
}

/// A `match` on `$cur.kind`: for a revolute joint about coordinate axis K below placement
/// kind P (kind `5 K + P`), `$cb!(placement, K, I, J, extra…)` with the placement rotation
/// and the plane (I, J) that the joint turns; `$other` for every other joint. One jump per
/// link and pass, each arm monomorphised.
macro_rules! match_axis_kind {
    ($cur:expr, $cb:ident, $other:expr $(, $extra:tt)*) => {
        match $cur.kind {
            0 => $cb!(Identity, 0, 1, 2 $(, $extra)*),
            1 => $cb!(Plane::<1, 2>::new($cur.pcs), 0, 1, 2 $(, $extra)*),
            2 => $cb!(Plane::<2, 0>::new($cur.pcs), 0, 1, 2 $(, $extra)*),
            3 => $cb!(Plane::<0, 1>::new($cur.pcs), 0, 1, 2 $(, $extra)*),
            4 => $cb!(General($cur.rot), 0, 1, 2 $(, $extra)*),
            5 => $cb!(Identity, 1, 2, 0 $(, $extra)*),
            6 => $cb!(Plane::<1, 2>::new($cur.pcs), 1, 2, 0 $(, $extra)*),
            7 => $cb!(Plane::<2, 0>::new($cur.pcs), 1, 2, 0 $(, $extra)*),
            8 => $cb!(Plane::<0, 1>::new($cur.pcs), 1, 2, 0 $(, $extra)*),
            9 => $cb!(General($cur.rot), 1, 2, 0 $(, $extra)*),
            10 => $cb!(Identity, 2, 0, 1 $(, $extra)*),
            11 => $cb!(Plane::<1, 2>::new($cur.pcs), 2, 0, 1 $(, $extra)*),
            12 => $cb!(Plane::<2, 0>::new($cur.pcs), 2, 0, 1 $(, $extra)*),
            13 => $cb!(Plane::<0, 1>::new($cur.pcs), 2, 0, 1 $(, $extra)*),
            14 => $cb!(General($cur.rot), 2, 0, 1 $(, $extra)*),
            _ => $other,
        }
    };
}

/// `with_rot!`'s arm: `$e` bound to `E = P R_K(q)`.
macro_rules! with_rot_arm {
    ($pl:expr, $k:tt, $i:tt, $j:tt, $cur:expr, $e:ident, $body:expr) => {{
        let $e = Placed($pl, Plane::<$i, $j>::new($cur.cs));
        $body
    }};
}
pub(super) use with_rot_arm;

/// Runs `$body` with `$e` bound to the link's rotation `E` (child axes in parent axes),
/// monomorphised per dispatch code (`LocalLink::kind`).
macro_rules! with_rot {
    ($cur:expr, $e:ident => $body:expr) => {
        match_axis_kind!(
            $cur,
            with_rot_arm,
            {
                let $e = General($cur.rot);
                $body
            },
            $cur,
            $e,
            $body
        )
    };
}
pub(super) use {match_axis_kind, with_rot};

crate::cpu::multiversion! {
    /// Accelerations `a` from `I a + C v − τ_g − Nᵀ f_ext = τ`, by the articulated-body
    /// recursion in body frames. Same contract as `forward_dynamics_world`: `external` holds
    /// one wrench per link, `[moment about the link origin; force]` in world axes; errors at a
    /// ZYZ Euler singularity or a non-positive joint block.
    ///
    /// On a CPU with AVX2 the same code runs compiled for it (see [`crate::cpu`]); the
    /// results are bit for bit those of the baseline build.
    pub fn forward_dynamics_local / forward_dynamics_avx2 / forward_dynamics_baseline [] (
        model: &Model,
        data: &mut Data,
        q: &[f64],
        v: &[f64],
        tau: &[f64],
        g: &Vec3,
        external: Option<&[Vec6]>,
        a: &mut [f64],
    ) -> Result<()> => forward_dynamics_body
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn forward_dynamics_body(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    g: &Vec3,
    external: Option<&[Vec6]>,
    a: &mut [f64],
) -> Result<()> {
    let n = model.links.len();
    let loc = &mut data.local[..n];

    // Outward: joint transforms, twists, ξ, body inertias and velocity-product wrenches; it
    // also finds the first ZYZ joint at its Euler singularity (`check_singularities`).
    let (body, angles) = (&data.local_body[..n], &data.axis_angles[..]);
    if let Some(i) = outward_pass::<true>(model, loc, body, angles, q, v, external) {
        return Err(Error::Singular(singular_message(model, i, q)));
    }

    // Inward: articulated inertias and biases.
    let body = &data.local_body[..n];
    for i in (0..n).rev() {
        let l = &model.links[i];
        let (head, tail) = loc.split_at_mut(i);
        let cur = &mut tail[0];
        // The parent's own inertia when this child writes its articulated inertia first.
        let (parent, start) = match l.parent {
            Some(p) => (
                Some(&mut head[p]),
                Some(&body[p]).filter(|_| cur.first_child),
            ),
            None => (None, None),
        };
        let ti = &tau[l.v_index..];
        macro_rules! axis {
            ($pl:expr, $k:tt, $i:tt, $j:tt) => {
                backward_axis::<_, $k, $i, $j>($pl, cur, parent, start, ti[0] * cur.sign)
            };
        }
        let ok = match_axis_kind!(cur, axis, backward_other(l, cur, parent, start, ti));
        if !ok {
            return Err(Error::Singular(singular_message(model, i, q)));
        }
    }

    // Outward: accelerations.
    let base = Vec6::new(0.0, 0.0, 0.0, -g.x, -g.y, -g.z);
    for i in 0..n {
        let l = &model.links[i];
        let (head, tail) = loc.split_at_mut(i);
        let cur = &mut tail[0];
        let pacc = match l.parent {
            Some(p) => &head[p].accel,
            None => &base,
        };
        let out = &mut a[l.v_index..];
        macro_rules! axis {
            ($pl:expr, $k:tt, $i:tt, $j:tt) => {{
                let e = Placed($pl, Plane::<$i, $j>::new(cur.cs));
                out[0] = forward_1::<_, $k, true>(e, cur, pacc) * cur.sign;
            }};
        }
        match_axis_kind!(cur, axis, forward_other(l, cur, pacc, out));
    }
    Ok(())
}

/// The inward step of every joint but a revolute one about a coordinate axis; false at a
/// non-positive joint block.
#[inline(never)]
fn backward_other(
    l: &Link,
    cur: &mut LocalLink,
    parent: Option<&mut LocalLink>,
    start: Option<&LocalInertia>,
    tau: &[f64],
) -> bool {
    match l.joint {
        Joint::Revolute { .. } => {
            backward_1::<_, 3, true>(General(cur.rot), cur, parent, start, tau[0])
        }
        Joint::Prismatic { .. } => {
            backward_1::<_, 3, false>(General(cur.rot), cur, parent, start, tau[0])
        }
        Joint::Spherical | Joint::SphericalZYZ => backward_3(cur, parent, start, tau),
        Joint::Fixed => {
            if let Some(p) = parent {
                let m = cur.inertia;
                let (ba, bl) = (v3(&cur.bias, 0), v3(&cur.bias, 3));
                let z = Vec3::zeros();
                finish(General(cur.rot), &m, &ba, &bl, &z, &z, cur, p, start);
            }
            true
        }
    }
}

/// The acceleration step of every joint but a revolute one about a coordinate axis.
#[inline(never)]
fn forward_other(l: &Link, cur: &mut LocalLink, pacc: &Vec6, out: &mut [f64]) {
    match l.joint {
        Joint::Revolute { .. } => {
            out[0] = forward_1::<_, 3, true>(General(cur.rot), cur, pacc);
        }
        Joint::Prismatic { .. } => {
            out[0] = forward_1::<_, 3, false>(General(cur.rot), cur, pacc);
        }
        Joint::Spherical | Joint::SphericalZYZ => forward_3(cur, pacc, out),
        Joint::Fixed => {
            let (ya, yl) = carry(General(cur.rot), cur, pacc);
            cur.accel = six(&ya, &yl);
        }
    }
}

/// The outward kinematic pass shared by the body-frame forward and inverse dynamics: per
/// link, the joint rotation `E` (or its plane-rotation cosine and sine) and offset, the joint
/// columns, the twist, `ξ`, and in `bias` the velocity-product wrench minus the external
/// wrench (in body axes). `ABI`: also start each articulated inertia at the link's own.
#[inline(always)]
pub(super) fn outward_pass<const ABI: bool>(
    model: &Model,
    loc: &mut [LocalLink],
    body: &[LocalInertia],
    angles: &[(usize, usize)],
    q: &[f64],
    v: &[f64],
    external: Option<&[Vec6]>,
) -> Option<usize> {
    let n = model.links.len();
    plane_turns(loc, angles, q);
    let mut singular = None;
    for i in 0..n {
        let l = &model.links[i];
        let (head, tail) = loc.split_at_mut(i);
        let cur = &mut tail[0];
        let parent = l.parent.map(|p| &head[p]);
        let qi = &q[l.q_index..];
        let vi = &v[l.v_index..];
        let fext = external.map(|f| &f[i]);
        // A revolute joint about coordinate axis K (the offset, the column e_K and the
        // placement are model constants).
        macro_rules! axis {
            ($pl:expr, $k:tt, $i:tt, $j:tt) => {{
                let pl = $pl;
                let (c, s) = cur.cs;
                let mut w_j = Vec3::zeros();
                w_j[$k] = vi[0] * cur.sign;
                let e = Placed(pl, Plane::<$i, $j>::new((c, s)));
                let z = Vec3::zeros();
                outward(e, cur, parent, &w_j, &z, &z, fext);
            }};
        }
        match_axis_kind!(cur, axis, {
            if outward_other(l, cur, parent, qi, vi, fext) && singular.is_none() {
                singular = Some(i);
            }
        });
        let own = &body[i];
        let h = own.first_moment();
        if ABI && cur.leaf {
            // A leaf's articulated inertia is its own; other links' are written by their
            // first child inward (`LocalLink::first_child`).
            cur.inertia = *own;
        }
        let w = v3(&cur.twist, 0);
        let iw = own.p.mul(&w);
        cur.bias += six(&cross(&w, &iw), &cross(&w, &cross(&w, &h)));
    }
    singular
}

/// The (cos, sin) of every revolute joint about a coordinate axis (`Data::axis_angles`), four
/// joints at a time (the last group padded).
#[inline(always)]
pub(super) fn plane_turns(loc: &mut [LocalLink], angles: &[(usize, usize)], q: &[f64]) {
    for group in angles.chunks(4) {
        let x: [f64; 4] = std::array::from_fn(|j| group.get(j).map_or(0.0, |g| q[g.1]));
        let (s, c) = sin_cos4(x).unwrap_or_else(|| {
            let one = x.map(sin_cos);
            (one.map(|p| p.0), one.map(|p| p.1))
        });
        for (j, &(i, _)) in group.iter().enumerate() {
            // About ±e_K (`sign`): sin turns sign with the angle, cos does not.
            loc[i].cs = (c[j], s[j] * loc[i].sign);
        }
    }
}

/// The outward step of every joint but a revolute one about a coordinate axis; true when a
/// ZYZ joint sits at its Euler singularity.
#[inline(never)]
pub(super) fn outward_other(
    l: &Link,
    cur: &mut LocalLink,
    parent: Option<&LocalLink>,
    qi: &[f64],
    vi: &[f64],
    fext: Option<&Vec6>,
) -> bool {
    let mut w_j = Vec3::zeros();
    let mut v_j = Vec3::zeros();
    let mut sdot_qd = Vec3::zeros();
    let mut singular = false;
    match l.joint {
        Joint::Revolute { axis } => {
            let rq = axis_angle(&axis, qi[0]);
            cur.rot = if cur.place_rotated {
                mat_mul(&cur.place_rot, &rq)
            } else {
                rq
            };
            w_j = axis * vi[0];
        }
        Joint::Prismatic { axis } => {
            cur.offset = cur.place_t + mul(&cur.place_rot, &(axis * qi[0]));
            v_j = axis * vi[0];
        }
        Joint::Spherical => {
            let rq = quat_to_matrix(qi);
            cur.rot = if cur.place_rotated {
                mat_mul(&cur.place_rot, &rq)
            } else {
                rq
            };
            w_j = Vec3::new(vi[0], vi[1], vi[2]);
        }
        Joint::SphericalZYZ => {
            singular = l.joint.singularity(qi).is_some();
            let (sp, cp) = sin_cos(qi[0]);
            let (st, ct) = sin_cos(qi[1]);
            let (ss, cs) = sin_cos(qi[2]);
            // Rz(φ) Ry(θ) Rz(ψ).
            let rq = Mat3::new(
                cp * ct * cs - sp * ss,
                -cp * ct * ss - sp * cs,
                cp * st,
                sp * ct * cs + cp * ss,
                -sp * ct * ss + cp * cs,
                sp * st,
                -st * cs,
                st * ss,
                ct,
            );
            cur.rot = if cur.place_rotated {
                mat_mul(&cur.place_rot, &rq)
            } else {
                rq
            };
            // Relative angular velocity in the body frame: R_qᵀ L(φ, θ) q̇ = S q̇, with
            // S = [R_qᵀ e_z, Rz(−ψ) e_y, e_z] (independent of φ).
            cur.s = [
                Vec3::new(-st * cs, st * ss, ct),
                Vec3::new(ss, cs, 0.0),
                Vec3::z(),
            ];
            let (dphi, dtheta, dpsi) = (vi[0], vi[1], vi[2]);
            w_j = cur.s[0] * dphi + cur.s[1] * dtheta + cur.s[2] * dpsi;
            // Ṡ q̇: the body-frame columns turn with θ and ψ.
            let d0 = Vec3::new(
                -ct * cs * dtheta + st * ss * dpsi,
                ct * ss * dtheta + st * cs * dpsi,
                -st * dtheta,
            );
            let d1 = Vec3::new(cs * dpsi, -ss * dpsi, 0.0);
            sdot_qd = d0 * dphi + d1 * dtheta;
        }
        // The placement rotation and offset are constants (`local_link_of`).
        Joint::Fixed => {}
    }
    outward(General(cur.rot), cur, parent, &w_j, &v_j, &sdot_qd, fext);
    singular
}

/// Twist, `ξ`, and the external wrench in body axes (stored negated in `bias`).
#[inline(always)]
fn outward<R: Rot>(
    e: R,
    cur: &mut LocalLink,
    parent: Option<&LocalLink>,
    w_j: &Vec3,
    v_j: &Vec3,
    sdot_qd: &Vec3,
    fext: Option<&Vec6>,
) {
    let offset = cur.offset;
    let (wpc, vpc) = match parent {
        Some(p) => {
            // Parent twist carried to this origin, in this frame.
            let wp = v3(&p.twist, 0);
            let vp = v3(&p.twist, 3) + cross_offset(&wp, &offset, cur.offset_axis);
            (e.tr_mul(&wp), e.tr_mul(&vp))
        }
        None => (Vec3::zeros(), Vec3::zeros()),
    };
    // ξ = [ω × w_J + Ṡ q̇; ω_p × (v − v_p) + ω × v_J], with ω × w_J = ω_p × w_J and
    // v − v_p = ω_p × r + v_J (this frame).
    let vp_here = match parent {
        Some(p) => e.tr_mul(&v3(&p.twist, 3)),
        None => Vec3::zeros(),
    };
    if R::AXIS < 3 {
        // Revolute about e_K: the same sums with the known zeros left out.
        let k = R::AXIS;
        let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
        let qd = w_j[k];
        let mut w = wpc;
        w[k] += qd;
        cur.twist = six(&w, &vpc);
        let mut xa = Vec3::zeros();
        xa[k1] = wpc[k2] * qd;
        xa[k2] = -(wpc[k1] * qd);
        cur.xi = six(&xa, &cross(&wpc, &(vpc - vp_here)));
    } else {
        let w = wpc + w_j;
        let vlin = vpc + v_j;
        cur.twist = six(&w, &vlin);
        let xa = cross(&wpc, w_j) + sdot_qd;
        let xl = cross(&wpc, &(vlin - vp_here)) + cross(&w, v_j);
        cur.xi = six(&xa, &xl);
    }
    match fext {
        Some(f) => {
            let rw = match parent {
                Some(p) => e.after(&p.world_rot),
                None => e.after(&Mat3::identity()),
            };
            cur.world_rot = rw;
            cur.bias = -six(&tr_mul(&rw, &v3(f, 0)), &tr_mul(&rw, &v3(f, 3)));
        }
        None => cur.bias = Vec6::zeros(),
    }
}

/// One 1-dof joint inward: `U = M̂ S`, `D`, `u`, then `M^a`, `b^a` into the parent. `AX < 3`:
/// a revolute joint about coordinate axis `AX` (S = e_AX, no products); `ANG`: the joint
/// moves along an angular (else linear) axis.
#[inline(always)]
fn backward_1<R: Rot, const AX: usize, const ANG: bool>(
    e: R,
    cur: &mut LocalLink,
    parent: Option<&mut LocalLink>,
    start: Option<&LocalInertia>,
    tau: f64,
) -> bool {
    let m = &cur.inertia;
    let (ba, bl) = (v3(&cur.bias, 0), v3(&cur.bias, 3));
    let s0 = cur.s[0];
    let (ua, ul) = if AX < 3 {
        (
            Vec3::new(m.p.at(0, AX), m.p.at(1, AX), m.p.at(2, AX)),
            Vec3::new(m.q[(AX, 0)], m.q[(AX, 1)], m.q[(AX, 2)]),
        )
    } else if ANG {
        (m.p.mul(&s0), tr_mul(&m.q, &s0))
    } else {
        (mul(&m.q, &s0), m.r.mul(&s0))
    };
    let (d, sb) = if AX < 3 {
        (ua[AX], ba[AX])
    } else if ANG {
        (s0.dot(&ua), s0.dot(&ba))
    } else {
        (s0.dot(&ul), s0.dot(&bl))
    };
    if d.is_nan() || d <= 0.0 {
        return false;
    }
    let dinv = 1.0 / d;
    let ut = tau - sb;
    cur.u[0] = six(&ua, &ul);
    cur.d_inv[(0, 0)] = dinv;
    cur.u_tau[0] = ut;
    if let Some(parent) = parent {
        // M^a = M̂ − U Uᵀ / d; b^a = b̂ + M^a ξ + U ut / d.
        let da = ua * dinv;
        let mut ma = *m;
        ma.p.sub_outer(&ua, dinv);
        ma.r.sub_outer(&ul, dinv);
        for c in 0..3 {
            for r in 0..3 {
                ma.q[(r, c)] -= da[r] * ul[c];
            }
        }
        let k = ut * dinv;
        finish(e, &ma, &ba, &bl, &(ua * k), &(ul * k), cur, parent, start);
    }
    true
}

/// A revolute joint about coordinate axis `K` (plane rotation `Plane<I, J>`, S = e_K) inward.
/// After the rank-1 update `M^a = M̂ − U Uᵀ / d` with `U = M̂ e_K`, row and column `K` of
/// `P^a` and row `K` of `Q^a` vanish, and stay so under the rotation about `e_K`: they are
/// neither formed nor rotated, and `(M^a ξ)_K = 0` leaves `f_K = b_K + u`. Without a
/// placement rotation (`Pl = Identity`) they are not shifted either; otherwise the blocks
/// are turned by the placement `pl` before the shift.
#[inline(always)]
fn backward_axis<Pl: Rot, const K: usize, const I: usize, const J: usize>(
    pl: Pl,
    cur: &mut LocalLink,
    parent: Option<&mut LocalLink>,
    start: Option<&LocalInertia>,
    tau: f64,
) -> bool {
    let m = &cur.inertia;
    let (ba, bl) = (v3(&cur.bias, 0), v3(&cur.bias, 3));
    let ua = Vec3::new(m.p.at(0, K), m.p.at(1, K), m.p.at(2, K));
    let ul = Vec3::new(m.q[(K, 0)], m.q[(K, 1)], m.q[(K, 2)]);
    let d = ua[K];
    if d.is_nan() || d <= 0.0 {
        return false;
    }
    let dinv = 1.0 / d;
    let ut = tau - ba[K];
    cur.u[0] = six(&ua, &ul);
    cur.d_inv[(0, 0)] = dinv;
    cur.u_tau[0] = ut;
    let Some(parent) = parent else {
        return true;
    };
    let (c, s) = cur.cs;
    // Rows I, J of the projected blocks (rows K vanish).
    let (di, dj) = (ua[I] * dinv, ua[J] * dinv);
    let pii = m.p.at(I, I) - di * ua[I];
    let pjj = m.p.at(J, J) - dj * ua[J];
    let pij = m.p.at(I, J) - di * ua[J];
    let qi = Vec3::new(m.q[(I, 0)], m.q[(I, 1)], m.q[(I, 2)]) - ul * di;
    let qj = Vec3::new(m.q[(J, 0)], m.q[(J, 1)], m.q[(J, 2)]) - ul * dj;
    let mut ra = m.r;
    ra.sub_outer(&ul, dinv);
    // b^a = b̂ + M^a ξ + U ut / d.
    let (xa, xl) = (v3(&cur.xi, 0), v3(&cur.xi, 3));
    let k = ut * dinv;
    let mut fa = Vec3::zeros();
    fa[K] = ba[K] + ut;
    fa[I] = ba[I] + pii * xa[I] + pij * xa[J] + qi.dot(&xl) + ua[I] * k;
    fa[J] = ba[J] + pij * xa[I] + pjj * xa[J] + qj.dot(&xl) + ua[J] * k;
    let fl = bl + qi * xa[I] + qj * xa[J] + ra.mul(&xl) + ul * k;
    // E P^a Eᵀ: the I, J block turned by the plane rotation.
    let (cc, ss, cs) = (c * c, s * s, c * s);
    let cs2b = 2.0 * cs * pij;
    let mut pp = Sym3::default();
    pp.0[sidx(I, I)] = cc * pii - cs2b + ss * pjj;
    pp.0[sidx(J, J)] = ss * pii + cs2b + cc * pjj;
    pp.0[sidx(I, J)] = cs * (pii - pjj) + (cc - ss) * pij;
    // E Q^a Eᵀ: rows I, J mixed, then columns I, J of those rows.
    let ri = qi * c - qj * s;
    let rj = qi * s + qj * c;
    let mut qq = Mat3::zeros();
    for (row, v) in [(I, ri), (J, rj)] {
        qq[(row, I)] = c * v[I] - s * v[J];
        qq[(row, J)] = s * v[I] + c * v[J];
        qq[(row, K)] = v[K];
    }
    let e = Plane::<I, J> { c, s };
    let (r, oa) = (&cur.offset, cur.offset_axis);
    let rr = e.conj_sym(&ra);
    if Pl::IDENTITY {
        shift_add::<K>(&pp, &qq, &rr, r, oa, start, &mut parent.inertia);
    } else {
        let (pp, qq, rr) = (pl.conj_sym(&pp), pl.conj::<false>(&qq), pl.conj_sym(&rr));
        shift_add::<3>(&pp, &qq, &rr, r, oa, start, &mut parent.inertia);
    }
    parent.bias += to_parent(Placed(pl, e), r, oa, &fa, &fl);
    true
}

/// One 3-dof (spherical) joint inward.
#[inline(always)]
fn backward_3(
    cur: &mut LocalLink,
    parent: Option<&mut LocalLink>,
    start: Option<&LocalInertia>,
    tau: &[f64],
) -> bool {
    let m = &cur.inertia;
    let (ba, bl) = (v3(&cur.bias, 0), v3(&cur.bias, 3));
    let mut u = [Vec6::zeros(); 3];
    let mut d = Mat3::zeros();
    let mut ut = Vec3::zeros();
    for k in 0..3 {
        let sk = cur.s[k];
        u[k] = six(&m.p.mul(&sk), &tr_mul(&m.q, &sk));
        ut[k] = tau[k] - sk.dot(&ba);
    }
    for r in 0..3 {
        for c in r..3 {
            let x = cur.s[r].dot(&v3(&u[c], 0));
            d[(r, c)] = x;
            d[(c, r)] = x;
        }
    }
    let d_inv = match d.cholesky() {
        Some(ch) => ch.inverse(),
        None => return false,
    };
    cur.u = u;
    cur.d_inv = d_inv;
    cur.u_tau = ut;
    if let Some(parent) = parent {
        let mut ma = *m;
        let dut = d_inv * ut;
        let mut ud_u = Vec6::zeros();
        for r in 0..3 {
            let ud = u[0] * d_inv[(0, r)] + u[1] * d_inv[(1, r)] + u[2] * d_inv[(2, r)];
            let (ua, ul) = (v3(&u[r], 0), v3(&u[r], 3));
            let (da, dl) = (v3(&ud, 0), v3(&ud, 3));
            // U D⁻¹ Uᵀ is symmetric as a whole: its upper triangles suffice.
            for (k, (i, j)) in [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
                .into_iter()
                .enumerate()
            {
                ma.p.0[k] -= da[i] * ua[j];
                ma.r.0[k] -= dl[i] * ul[j];
            }
            for c in 0..3 {
                for rr in 0..3 {
                    ma.q[(rr, c)] -= da[rr] * ul[c];
                }
            }
            ud_u += u[r] * dut[r];
        }
        let e = General(cur.rot);
        finish(
            e,
            &ma,
            &ba,
            &bl,
            &v3(&ud_u, 0),
            &v3(&ud_u, 3),
            cur,
            parent,
            start,
        );
    }
    true
}

/// `b^a = b̂ + M^a ξ + k` (`k = U D⁻¹ u`), then `M^a`, `b^a` carried to the parent (rotated
/// by `E`, shifted by the offset) and added there.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn finish<R: Rot>(
    e: R,
    ma: &LocalInertia,
    ba: &Vec3,
    bl: &Vec3,
    ka: &Vec3,
    kl: &Vec3,
    cur: &LocalLink,
    parent: &mut LocalLink,
    start: Option<&LocalInertia>,
) {
    let xa = v3(&cur.xi, 0);
    let xl = v3(&cur.xi, 3);
    let fa = ba + ma.p.mul(&xa) + mul(&ma.q, &xl) + ka;
    let fl = bl + tr_mul(&ma.q, &xa) + ma.r.mul(&xl) + kl;
    let r = &cur.offset;
    shift_add::<3>(
        &e.conj_sym(&ma.p),
        &e.conj::<false>(&ma.q),
        &e.conj_sym(&ma.r),
        r,
        cur.offset_axis,
        start,
        &mut parent.inertia,
    );
    parent.bias += to_parent(e, r, cur.offset_axis, &fa, &fl);
}

/// A wrench `[n; f]` about the child origin in child axes, as seen at the parent origin in
/// parent axes: `[E n + r × E f; E f]` (`form`: the offset's, `LocalLink::offset_axis`).
#[inline(always)]
pub(super) fn to_parent<R: Rot>(e: R, r: &Vec3, form: u8, n: &Vec3, f: &Vec3) -> Vec6 {
    let n = e.mul(n);
    let f = e.mul(f);
    six(&(n - cross_offset(&f, r, form)), &f)
}

/// The offset form (`LocalLink::offset_axis`) that takes the general cross product: the
/// walks that carry one wrench per step (inverse dynamics inward, GIM columns) count fewer
/// instructions without the branch.
pub(super) const ANYWHERE: u8 = 4;

/// `w × r` for an offset `r` of the given form (`LocalLink::offset_axis`: 0 zero, 1, 2, 3
/// along x, y, z only, 4 anywhere): along one axis it takes two products instead of six.
/// The values are `cross(w, r)`'s (only the signs of exact zeros may differ).
#[inline(always)]
pub(super) fn cross_offset(w: &Vec3, r: &Vec3, form: u8) -> Vec3 {
    match form {
        0 => Vec3::zeros(),
        1 => Vec3::new(0.0, w.z * r.x, -(w.y * r.x)),
        2 => Vec3::new(-(w.z * r.y), 0.0, w.x * r.y),
        3 => Vec3::new(w.y * r.z, -(w.x * r.z), 0.0),
        _ => cross(w, r),
    }
}

/// The parent's twist rate carried to this link plus `ξ` (this frame).
#[inline(always)]
pub(super) fn carry<R: Rot>(e: R, cur: &LocalLink, pacc: &Vec6) -> (Vec3, Vec3) {
    let ap = v3(pacc, 0);
    let lp = v3(pacc, 3) + cross_offset(&ap, &cur.offset, cur.offset_axis);
    (
        e.tr_mul(&ap) + v3(&cur.xi, 0),
        e.tr_mul(&lp) + v3(&cur.xi, 3),
    )
}

#[inline(always)]
fn forward_1<R: Rot, const AX: usize, const ANG: bool>(
    e: R,
    cur: &mut LocalLink,
    pacc: &Vec6,
) -> f64 {
    let (mut ya, mut yl) = carry(e, cur, pacc);
    let u = &cur.u[0];
    let uy = u[0] * ya.x + u[1] * ya.y + u[2] * ya.z + u[3] * yl.x + u[4] * yl.y + u[5] * yl.z;
    let qdd = (cur.u_tau[0] - uy) * cur.d_inv[(0, 0)];
    if AX < 3 {
        ya[AX] += qdd;
    } else if ANG {
        ya += cur.s[0] * qdd;
    } else {
        yl += cur.s[0] * qdd;
    }
    cur.accel = six(&ya, &yl);
    qdd
}

#[inline(always)]
fn forward_3(cur: &mut LocalLink, pacc: &Vec6, out: &mut [f64]) {
    let (mut ya, yl) = carry(General(cur.rot), cur, pacc);
    let y = six(&ya, &yl);
    let mut rhs = Vec3::zeros();
    for k in 0..3 {
        rhs[k] = cur.u_tau[k] - cur.u[k].dot(&y);
    }
    let qdd = cur.d_inv * rhs;
    for k in 0..3 {
        out[k] = qdd[k];
        ya += cur.s[k] * qdd[k];
    }
    cur.accel = six(&ya, &yl);
}
