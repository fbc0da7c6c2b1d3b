//! Per-call values of the body-frame recursions (like Pinocchio's `Data`): everything here
//! is overwritten by each call before it is read, so a workspace depends on its model only
//! through its sizes, which [`Data::fits`] checks. The model's constants are in
//! [`super::Compiled`].
use super::algebra::LocalInertia;
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::support::spatial::{Mat3, Vec3, Vec6};
use nalgebra::DMatrix;

/// One link's per-call values, in the link's (recursion) frame, about its origin.
#[derive(Debug, Clone, Copy)]
pub struct LinkWork {
    /// Other joints (`LinkKind::Other`): link axes in parent axes, `E`.
    pub rot: Mat3,
    /// Link origin in parent coordinates.
    pub offset: Vec3,
    /// Link orientation in the world (only kept when external wrenches are given).
    pub world_rot: Mat3,
    /// Motion columns of a joint whose columns move with `q` (ZYZ), and of spherical joints.
    pub s: [Vec3; 3],
    pub twist: Vec6,
    /// Velocity-dependent twist rate `ξ`.
    pub xi: Vec6,
    /// Articulated (or composite) inertia.
    pub inertia: LocalInertia,
    /// Articulated bias wrench (or the link's wrench, in inverse dynamics).
    pub bias: Vec6,
    /// `U = M̂ S` (columns); not kept for a revolute joint about a coordinate axis `e_K`,
    /// where it is column `K` of `inertia`.
    pub u: [Vec6; 3],
    /// `D⁻¹ = (Sᵀ M̂ S)⁻¹`, upper-left dof × dof block used.
    pub d_inv: Mat3,
    /// `τ − Sᵀ b̂`.
    pub u_tau: Vec3,
    /// Twist rate `ṫ`.
    pub accel: Vec6,
    /// A revolute joint about a coordinate axis: (cos, sin) of its turn.
    pub cs: (f64, f64),
}

impl Default for LinkWork {
    fn default() -> Self {
        LinkWork {
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
        }
    }
}

/// The workspace of the recursions for models of one size: built by `Data::new(model)`,
/// reusable for any model of the same numbers of links, coordinates and speeds.
#[derive(Debug, Clone)]
pub struct Data {
    /// Body-frame recursion values, per link.
    pub local: Vec<LinkWork>,
    /// World-frame kinematics (orientations, origins, twists), per link: what energies,
    /// body placements and effects read, filled by `kinematics::positions`/`velocities`.
    pub links: Vec<LinkState>,
    /// `nv` zeros (the speeds of a position-only outward pass).
    pub zero_v: Vec<f64>,
    nq: usize,
}

impl Data {
    pub fn new(model: &Model) -> Self {
        let n = model.links.len();
        Data {
            local: vec![LinkWork::default(); n],
            links: vec![LinkState::default(); n],
            zero_v: vec![0.0; model.nv],
            nq: model.nq,
        }
    }

    /// Whether this workspace serves `model`: nothing in it is a model constant, so the
    /// sizes are the whole check.
    pub fn fits(&self, model: &Model) -> bool {
        self.local.len() == model.links.len()
            && self.links.len() == model.links.len()
            && self.zero_v.len() == model.nv
            && self.nq == model.nq
    }
}

/// One link's values in the derivative recursions ([`super::rnea_derivatives`]), world axes
/// about the world origin.
#[derive(Debug, Clone, Copy)]
pub struct DerivLinkWork {
    /// Spatial velocity and acceleration (gravity included as the base's `[0; −g]`).
    pub v: Vec6,
    pub a: Vec6,
    /// Inertia, then the composite inertia of the subtree.
    pub y: crate::support::spatial::BodyInertia,
    /// `B = [[B_aa, 0], [B_la, 0]]` (see the module), then its subtree sum; `B_la` is
    /// skew, `−2 [b_l]×`, and kept as `b_l`.
    pub baa: Mat3,
    pub bl: Vec3,
    /// The body's wrench, then the subtree's.
    pub f: Vec6,
}

impl Default for DerivLinkWork {
    fn default() -> Self {
        DerivLinkWork {
            v: Vec6::zeros(),
            a: Vec6::zeros(),
            y: crate::support::spatial::BodyInertia::zero(),
            baa: Mat3::zeros(),
            bl: Vec3::zeros(),
            f: Vec6::zeros(),
        }
    }
}

/// One speed direction's values in the derivative recursions.
#[derive(Debug, Clone, Copy, Default)]
pub struct DofWork {
    /// The joint column `S_k` (world axes, about the world origin).
    pub s: Vec6,
    /// `dV_k`, `dA_k`, `dAv_k` (see [`super::rnea_derivatives`]).
    pub dv: Vec6,
    pub da: Vec6,
    pub dav: Vec6,
    /// `Y S_k` and `Bᵀ S_k` (its angular part; the linear part is zero) of the subtree.
    pub ys: Vec6,
    pub bts: Vec3,
    /// `∂F/∂q_k` and `∂F/∂v_k` of the subtree's wrench.
    pub g: Vec6,
    pub gv: Vec6,
}

/// Rows (of nv) of [`DerivativeData::columns`].
pub(crate) const SOA_ROWS: usize = 42;

/// The workspace and results of the dynamics derivatives
/// ([`super::rnea_derivatives::inverse_dynamics_derivatives`],
/// [`super::aba_derivatives::forward_dynamics_derivatives`]) for models of one size.
#[derive(Debug, Clone)]
pub struct DerivativeData {
    pub links: Vec<DerivLinkWork>,
    pub dofs: Vec<DofWork>,
    /// `∂τ/∂q`, `∂τ/∂v`, `M = ∂τ/∂a` (nv × nv).
    pub dtau_dq: DMatrix<f64>,
    pub dtau_dv: DMatrix<f64>,
    pub mass: DMatrix<f64>,
    /// `∂q̈/∂q`, `∂q̈/∂v`, `M⁻¹ = ∂q̈/∂τ` (forward dynamics only).
    pub ddq_dq: DMatrix<f64>,
    pub ddq_dv: DMatrix<f64>,
    pub minv: DMatrix<f64>,
    /// `τ` of the inverse dynamics pass (its `a` is `q̈` after the forward derivatives).
    pub tau: Vec<f64>,
    /// `q̈` of the forward derivatives.
    pub qdd: Vec<f64>,
    /// Per dof, the nearest dof upstream (`NO_DOF` at the root); per link, the last dof at or
    /// above it: the tree's shape, refilled by each call.
    pub dof_parent: Vec<usize>,
    pub last_dof: Vec<usize>,
    /// Per link: the dofs above it (how many), and its subtree's dofs (how many, and one past
    /// the highest index), refilled by each call: where they are index ranges, the matrices'
    /// columns are filled by contiguous, vectorised loops.
    pub above_count: Vec<usize>,
    pub subtree_count: Vec<usize>,
    pub subtree_end: Vec<usize>,
    /// Per dof, structure of arrays: `S` (6 rows of nv), `Y S` (6), `Bᵀ S` (3); with
    /// `row_major`, also `g` (6), `g_v` (6), `dA` (6), `dAv` (6), `dV`'s angular part (3).
    pub columns: Vec<f64>,
    /// Whether the derivatives are stored by rows: `dtau_dq`, `dtau_dv`, `ddq_dq`, `ddq_dv`
    /// then hold the transposes (their data is the C order of the derivatives, which NumPy
    /// returns without a transposing copy). `M`, `M⁻¹` are symmetric either way.
    pub row_major: bool,
    /// Scratch: the reciprocal pivots of the mass matrix's Cholesky factor.
    pub inv_diag: Vec<f64>,
    /// Scratch of the mass matrix's inverse from [`crate::linalg::spd::SMALL`] dofs on.
    pub spd_scratch: crate::linalg::spd::SpdScratch,
}

impl DerivativeData {
    pub fn new(model: &Model) -> Self {
        let (n, nv) = (model.links.len(), model.nv);
        let z = || DMatrix::zeros(nv, nv);
        DerivativeData {
            links: vec![DerivLinkWork::default(); n],
            dofs: vec![DofWork::default(); nv],
            dtau_dq: z(),
            dtau_dv: z(),
            mass: z(),
            ddq_dq: z(),
            ddq_dv: z(),
            minv: z(),
            tau: vec![0.0; nv],
            qdd: vec![0.0; nv],
            inv_diag: vec![0.0; nv],
            spd_scratch: crate::linalg::spd::SpdScratch::new(nv),
            dof_parent: vec![0; nv],
            last_dof: vec![0; n],
            above_count: vec![0; n],
            subtree_count: vec![0; n],
            subtree_end: vec![0; n],
            columns: vec![0.0; SOA_ROWS * nv],
            row_major: false,
        }
    }

    /// Whether this workspace serves `model` (sizes only, as [`Data::fits`]).
    pub fn fits(&self, model: &Model) -> bool {
        self.links.len() == model.links.len() && self.dofs.len() == model.nv
    }
}
