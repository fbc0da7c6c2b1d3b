//! The model's constants for the body-frame recursions, computed once per model (like the
//! constant part of Pinocchio's `Model`): per link, its joint case ([`LinkKind`]), the
//! placement and offset in the recursion's link frames, constant motion columns, its own
//! inertia in the form that starts its articulated inertia, and its place in the tree.
//! [`Model::compiled`] builds them on first use and `add_body` discards them.
//!
//! The recursion's link frames may differ from the model's by a signed permutation `Q` (new
//! coordinates `Q x`), chosen so that exact quarter-turn placements vanish (the
//! `rpy = (±π/2, 0, 0)` of robot descriptions): a revolute joint about a coordinate axis
//! `e_K` below such a placement `P` absorbs it, since `Q_p P R_K(q) Qᵀ = R_{Q e_K}(q)` is a
//! turn about a coordinate axis again. Joint coordinates keep their meaning (a joint now
//! about `−e_K` turns by `−q`: [`LinkConsts::sign`]) and external wrenches are brought into
//! the turned frames, so results do not depend on `Q`.
use super::algebra::{General, LocalInertia, Rot, Sym3};
use super::shift::OffsetForm;
use crate::joint::MotionClass;
use crate::model::{Link, Model};
use crate::support::spatial::{Mat3, Vec3};

/// A link's case in the recursions, one jump per link and pass, each case compiled with its
/// known zeros. `Revolute{K}{P}`: a revolute joint about coordinate axis `K` (after the frame
/// turn `Q`) whose joint frame is placed by `P`: `Unplaced` no rotation, `TurnX`, `TurnY`,
/// `TurnZ` a plane rotation about that axis (by [`LinkConsts::placement_cs`]), `Placed` a
/// general rotation ([`LinkConsts::placement`]). Every other joint goes by its motion class.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(u8)]
pub enum LinkKind {
    RevoluteXUnplaced,
    RevoluteXTurnX,
    RevoluteXTurnY,
    RevoluteXTurnZ,
    RevoluteXPlaced,
    RevoluteYUnplaced,
    RevoluteYTurnX,
    RevoluteYTurnY,
    RevoluteYTurnZ,
    RevoluteYPlaced,
    RevoluteZUnplaced,
    RevoluteZTurnX,
    RevoluteZTurnY,
    RevoluteZTurnZ,
    RevoluteZPlaced,
    /// Any other joint (revolute about another axis, prismatic, spherical, fixed).
    Other,
}

/// The placement of a revolute joint's frame, for [`LinkKind`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PlacementTurn {
    Unplaced,
    TurnX,
    TurnY,
    TurnZ,
    Placed,
}

impl LinkKind {
    const ON_AXIS: [[LinkKind; 5]; 3] = {
        use LinkKind::*;
        [
            [
                RevoluteXUnplaced,
                RevoluteXTurnX,
                RevoluteXTurnY,
                RevoluteXTurnZ,
                RevoluteXPlaced,
            ],
            [
                RevoluteYUnplaced,
                RevoluteYTurnX,
                RevoluteYTurnY,
                RevoluteYTurnZ,
                RevoluteYPlaced,
            ],
            [
                RevoluteZUnplaced,
                RevoluteZTurnX,
                RevoluteZTurnY,
                RevoluteZTurnZ,
                RevoluteZPlaced,
            ],
        ]
    };
    fn revolute(axis: usize, turn: PlacementTurn) -> LinkKind {
        Self::ON_AXIS[axis][turn as usize]
    }
}

/// One link's constants in the recursion's frames.
#[derive(Debug, Clone, Copy)]
pub struct LinkConsts {
    pub kind: LinkKind,
    /// The model's tree and coordinate slots (`Link`'s), next to the rest.
    pub parent: Option<usize>,
    pub q_index: usize,
    pub v_index: usize,
    /// The joint's motion class (`Angular1` for every `Revolute*` kind).
    pub motion: MotionClass,
    /// Its number of speeds and whether it moves along angular axes (from `motion`, kept
    /// as plain fields for the column walks).
    pub nv: usize,
    pub angular: bool,
    /// How the offset lies; it picks the shift's form.
    pub offset_form: OffsetForm,
    /// A revolute joint about a coordinate axis: ±1 as it turns about `±e_K`.
    pub sign: f64,
    /// `Revolute*Placed`: the placement `P` (joint frame axes in parent axes). Other joints:
    /// the placement in the recursion's frames (`x_parent = placement x + offset` at q = 0).
    pub placement: Mat3,
    /// `Revolute*Turn*`: (cos, sin) of the placement's plane rotation.
    pub placement_cs: (f64, f64),
    /// Other joints: whether `placement` turns at all.
    pub placement_rotated: bool,
    /// Link origin in parent coordinates (at q = 0 for a prismatic joint, whose moving
    /// offset the outward pass writes in `LinkWork::offset`).
    pub offset: Vec3,
    /// Motion columns in the link frame when constant (angular part, or linear part for
    /// linear motion); ZYZ columns move and come from its outward step.
    pub columns: [Vec3; 3],
    /// No children: the articulated inertia starts as the link's own.
    pub leaf: bool,
    /// The child of its parent whose inward step comes first (the highest index): it writes
    /// the parent's articulated inertia as the parent's own plus its contribution, so that no
    /// link's inertia is copied before its children add into it.
    pub first_child: bool,
    /// The link's own inertia about its origin, in the recursion's link frame.
    pub inertia: LocalInertia,
    /// Rotor inertia of the joint's speeds (`super::armature`); a link with any takes the
    /// `Other` path, whose joint block `D` adds it.
    pub armature: [f64; 3],
}

/// All constants of a model for the body-frame recursions.
#[derive(Debug, Clone, Default)]
pub struct Compiled {
    pub links: Vec<LinkConsts>,
    /// `(link, q index)` of the revolute joints about a coordinate axis, whose sines and
    /// cosines the outward pass takes four at a time.
    pub axis_angles: Vec<(usize, usize)>,
    /// Whether any link moves on a free flyer (the GIM's column walk then tests for them).
    pub has_free_flyer: bool,
    /// The world-frame pose pass's decisions (`kinematics::frame_poses`), built beside.
    pub poses: crate::kinematics::plan::PosePlan,
}

impl Compiled {
    pub fn new(model: &Model) -> Compiled {
        let n = model.links.len();
        let mut links = Vec::with_capacity(n);
        let mut frames: Vec<Mat3> = Vec::with_capacity(n);
        for (i, l) in model.links.iter().enumerate() {
            let frame_p = l.parent.map_or(Mat3::identity(), |p| frames[p]);
            let (link, frame) = link_consts(l, &frame_p, model.link_armature(i));
            links.push(link);
            frames.push(frame);
        }
        // Links come parents first, so the inward loop meets each parent's children from
        // the highest index down.
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
        let axis_angles = links
            .iter()
            .zip(&model.links)
            .enumerate()
            .filter(|(_, (c, _))| c.kind != LinkKind::Other)
            .map(|(i, (_, link))| (i, link.q_index))
            .collect();
        let has_free_flyer = links.iter().any(|l| l.motion == MotionClass::Free);
        Compiled {
            links,
            axis_angles,
            has_free_flyer,
            poses: crate::kinematics::plan::PosePlan::new(model),
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

/// The placement turn of a constant rotation `p` and, for a plane rotation, its (cos, sin).
fn placement_turn(p: &Mat3) -> (PlacementTurn, (f64, f64)) {
    if *p == Mat3::identity() {
        return (PlacementTurn::Unplaced, (1.0, 0.0));
    }
    // A turn about coordinate axis `a` (plane pair I, J) keeps e_a exactly and has the 2×2
    // block [[c, −s], [s, c]] in rows and columns I, J.
    let turns = [
        PlacementTurn::TurnX,
        PlacementTurn::TurnY,
        PlacementTurn::TurnZ,
    ];
    for (a, i, j) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)] {
        let (c, sn) = (p[(i, i)], p[(j, i)]);
        let keeps_axis = p[(a, a)] == 1.0
            && p[(a, i)] == 0.0
            && p[(a, j)] == 0.0
            && p[(i, a)] == 0.0
            && p[(j, a)] == 0.0;
        if keeps_axis && p[(j, j)] == c && p[(i, j)] == -sn {
            return (turns[a], (c, sn));
        }
    }
    (PlacementTurn::Placed, (1.0, 0.0))
}

/// The link's constants and its frame turn `Q`, given its parent's, `frame_p`.
///
/// A revolute joint about a coordinate axis `e_K` below a placement `P` that is a signed
/// permutation absorbs `P` into the link frame: `Q = Q_p P`. Otherwise `Q = Q_p` and the
/// placement becomes `Q_p P Q_pᵀ` (a plane rotation stays one, about the permuted axis).
/// Other joints keep their own frame (`Q = 1`) and take `Q_p P` as placement.
pub(super) fn link_consts(l: &Link, frame_p: &Mat3, armature: [f64; 3]) -> (LinkConsts, Mat3) {
    let pl = &l.placement;
    // Signed permutations: these products are exact.
    let offset = frame_p * pl.translation;
    let motion = l.joint.motion();
    let mut out = LinkConsts {
        kind: LinkKind::Other,
        parent: l.parent,
        q_index: l.q_index,
        v_index: l.v_index,
        motion,
        nv: motion.nv(),
        angular: motion.angular(),
        offset_form: match motion {
            // The offset moves with q.
            MotionClass::Linear1 | MotionClass::Free => OffsetForm::Anywhere,
            _ => OffsetForm::of(&offset),
        },
        sign: 1.0,
        placement: Mat3::identity(),
        placement_cs: (1.0, 0.0),
        placement_rotated: false,
        offset,
        columns: l.joint.local_columns(),
        leaf: true,
        first_child: false,
        inertia: LocalInertia::default(),
        armature,
    };
    // The coordinate-axis cases drop the joint row of the articulated inertia, which
    // armature keeps: a link with armature takes the general path.
    let on_axis = l
        .joint
        .revolute_axis()
        .filter(|a| coordinate_axis(a).is_some() && armature == [0.0; 3]);
    let mut frame = Mat3::identity();
    let mut other = true;
    if let Some(axis) = on_axis {
        let (turned_frame, placement) = if is_signed_permutation(&pl.rotation) {
            (frame_p * pl.rotation, Mat3::identity())
        } else {
            (*frame_p, frame_p * pl.rotation * frame_p.transpose())
        };
        let turned = turned_frame * axis;
        if let Some((k, sign)) = coordinate_axis(&turned) {
            let (turn, cs) = placement_turn(&placement);
            out.kind = LinkKind::revolute(k, turn);
            out.sign = sign;
            out.columns[0] = turned;
            out.placement_cs = cs;
            out.placement = placement;
            frame = turned_frame;
            other = false;
        }
    }
    if other {
        // Other joints keep their own frame: the parent's turn goes into the placement.
        out.placement = frame_p * pl.rotation;
        out.placement_rotated = out.placement != Mat3::identity();
    }
    out.inertia = own_inertia(l, &frame);
    (out, frame)
}

/// The link's own inertia about its origin as a `LocalInertia`, turned into the recursion's
/// link frame by `frame`.
fn own_inertia(l: &Link, frame: &Mat3) -> LocalInertia {
    let bi = &l.inertia;
    let h = bi.first_moment;
    let mass = bi.mass;
    let turn = General(*frame);
    LocalInertia {
        p: turn.conj_sym(&Sym3::from_mat(&bi.rotational)),
        q: turn.conj::<false>(&Mat3::new(0.0, -h.z, h.y, h.z, 0.0, -h.x, -h.y, h.x, 0.0)),
        r: turn.conj_sym(&Sym3([mass, mass, mass, 0.0, 0.0, 0.0])),
    }
}

/// A `match` on `$c.kind` (`$c`: a link's [`LinkConsts`]): for a revolute joint about
/// coordinate axis K below placement turn P, `$cb!(placement, K, I, J, extra…)` with the
/// placement rotation and the plane (I, J) that the joint turns; `$other` for every other
/// joint. One jump per link and pass, each arm monomorphised.
macro_rules! match_axis_kind {
    ($c:expr, $cb:ident, $other:expr $(, $extra:tt)*) => {{
        use $crate::recursive::algebra::{General, Identity, Plane};
        use $crate::recursive::compiled::LinkKind as K;
        match $c.kind {
            K::RevoluteXUnplaced => $cb!(Identity, 0, 1, 2 $(, $extra)*),
            K::RevoluteXTurnX => $cb!(Plane::<1, 2>::new($c.placement_cs), 0, 1, 2 $(, $extra)*),
            K::RevoluteXTurnY => $cb!(Plane::<2, 0>::new($c.placement_cs), 0, 1, 2 $(, $extra)*),
            K::RevoluteXTurnZ => $cb!(Plane::<0, 1>::new($c.placement_cs), 0, 1, 2 $(, $extra)*),
            K::RevoluteXPlaced => $cb!(General($c.placement), 0, 1, 2 $(, $extra)*),
            K::RevoluteYUnplaced => $cb!(Identity, 1, 2, 0 $(, $extra)*),
            K::RevoluteYTurnX => $cb!(Plane::<1, 2>::new($c.placement_cs), 1, 2, 0 $(, $extra)*),
            K::RevoluteYTurnY => $cb!(Plane::<2, 0>::new($c.placement_cs), 1, 2, 0 $(, $extra)*),
            K::RevoluteYTurnZ => $cb!(Plane::<0, 1>::new($c.placement_cs), 1, 2, 0 $(, $extra)*),
            K::RevoluteYPlaced => $cb!(General($c.placement), 1, 2, 0 $(, $extra)*),
            K::RevoluteZUnplaced => $cb!(Identity, 2, 0, 1 $(, $extra)*),
            K::RevoluteZTurnX => $cb!(Plane::<1, 2>::new($c.placement_cs), 2, 0, 1 $(, $extra)*),
            K::RevoluteZTurnY => $cb!(Plane::<2, 0>::new($c.placement_cs), 2, 0, 1 $(, $extra)*),
            K::RevoluteZTurnZ => $cb!(Plane::<0, 1>::new($c.placement_cs), 2, 0, 1 $(, $extra)*),
            K::RevoluteZPlaced => $cb!(General($c.placement), 2, 0, 1 $(, $extra)*),
            K::Other => $other,
        }
    }};
}

/// `with_rot!`'s arm: `$e` bound to `E = P R_K(q)`, `$r` to the constant offset, `$s` to the
/// constant columns.
macro_rules! with_rot_arm {
    ($pl:expr, $k:tt, $i:tt, $j:tt, $c:expr, $w:expr, $e:ident, $r:ident, $s:ident, $body:expr) => {{
        let $e = $crate::recursive::algebra::Placed(
            $pl,
            $crate::recursive::algebra::Plane::<$i, $j>::new($w.cs),
        );
        let $r = &$c.offset;
        let $s = &$c.columns;
        $body
    }};
}

/// Runs `$body` monomorphised per [`LinkKind`] (`$c` the link's constants, `$w` its
/// workspace) with `$e` bound to the link's rotation `E` (child axes in parent axes), `$r` to
/// its offset and `$s` to its motion columns: model constants for a revolute joint about a
/// coordinate axis, the outward pass's values for other joints.
macro_rules! with_rot {
    ($c:expr, $w:expr, $e:ident, $r:ident, $s:ident => $body:expr) => {
        match_axis_kind!(
            $c,
            with_rot_arm,
            {
                let $e = $crate::recursive::algebra::General($w.rot);
                let $r = &$w.offset;
                let $s = &$w.s;
                $body
            },
            $c,
            $w,
            $e,
            $r,
            $s,
            $body
        )
    };
}
pub(crate) use {match_axis_kind, with_rot, with_rot_arm};
