//! The recursive algorithms against the explicit DeNOC products, and the identities the
//! equations of motion must satisfy, on random trees mixing every joint type.
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;

use super::compiled::{self, LinkKind};
use super::reference::{
    forward_dynamics_world, inverse_dynamics_world, mass_matrix_world, Workspace,
};
use super::*;
use crate::dynamics::denoc;
use crate::joint::Joint;
use crate::model::body::RigidBody;
use crate::model::Model;
use crate::support::spatial::{Mat3, Placement, Vec3};

/// A deterministic pseudo-random stream, so a failure is reproducible from its seed.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64)
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
    fn vec3(&mut self, s: f64) -> Vec3 {
        Vec3::new(self.range(-s, s), self.range(-s, s), self.range(-s, s))
    }
}

pub(crate) fn random_tree(seed: u64, n: usize) -> Model {
    let mut rng = Lcg(seed);
    let mut model = Model::new();
    for k in 0..n {
        let ext = Vec3::new(
            rng.range(0.05, 0.5),
            rng.range(0.05, 0.5),
            rng.range(0.05, 0.5),
        );
        let m = rng.range(0.5, 3.0);
        let sq = ext.component_mul(&ext);
        let d = Vec3::new(sq.y + sq.z, sq.x + sq.z, sq.x + sq.y) * (m / 3.0);
        let r = nalgebra::Rotation3::from_scaled_axis(rng.vec3(2.0));
        let body = RigidBody::new(
            m,
            rng.vec3(0.3),
            r.matrix() * Mat3::from_diagonal(&d) * r.matrix().transpose(),
        )
        .unwrap();
        let joint = match k % 5 {
            0 => Joint::revolute(rng.vec3(1.0)).unwrap(),
            1 => Joint::Spherical,
            2 => Joint::prismatic(rng.vec3(1.0)).unwrap(),
            3 => Joint::SphericalZYZ,
            _ => {
                if k % 2 == 0 {
                    Joint::Fixed
                } else if k % 3 == 0 {
                    Joint::FreeFlyer
                } else {
                    Joint::revolute(rng.vec3(1.0)).unwrap()
                }
            }
        };
        let parent = if k == 0 {
            None
        } else {
            Some((rng.next() * k as f64) as usize)
        };
        let rot = nalgebra::Rotation3::from_scaled_axis(rng.vec3(1.5));
        let place = Placement::new(*rot.matrix(), rng.vec3(0.6));
        let center = if k % 3 == 0 {
            Some(rng.vec3(0.5))
        } else {
            None
        };
        model
            .add_body(body, joint, parent, place, None, center)
            .unwrap();
    }
    model
}

pub(crate) fn random_state(model: &Model, seed: u64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut rng = Lcg(seed ^ 0x9e3779b97f4a7c15);
    let mut q: Vec<f64> = (0..model.nq).map(|_| rng.range(-1.0, 1.0)).collect();
    // Keep ZYZ θ away from the Euler singularity.
    for l in &model.links {
        if let Joint::SphericalZYZ = l.joint {
            q[l.q_index + 1] = rng.range(0.4, 2.7);
        }
    }
    model.normalize(&mut q);
    let v = (0..model.nv).map(|_| rng.range(-1.5, 1.5)).collect();
    let a = (0..model.nv).map(|_| rng.range(-2.0, 2.0)).collect();
    (q, v, a)
}

fn rel(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).norm() / b.norm().max(1e-300)
}

const G: Vec3 = Vec3::new(0.0, 0.0, -9.81);

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn recursive_agrees_with_explicit(seed in 0u64..1_000_000, n in 1usize..16) {
        let model = random_tree(seed, n);
        let (q, v, a) = random_state(&model, seed);
        let mut data = Data::new(&model);
        let nv = model.nv;
        let mut gim = DMatrix::zeros(nv, nv);
        mass_matrix(&model, &mut data, &q, &mut gim);
        let gim_explicit = denoc::mass_matrix(&model, &q).unwrap();
        prop_assert!((&gim - &gim_explicit).norm() <= 1e-12 * gim_explicit.norm());

        let mut tau = vec![0.0; nv];
        inverse_dynamics(&model, &mut data, &q, &v, &a, &G, None, &mut tau);
        let tau_explicit = denoc::inverse_dynamics(&model, &q, &v, &a, &G).unwrap();
        prop_assert!(rel(&DVector::from_vec(tau.clone()), &tau_explicit) <= 1e-11);

        let mut acc = vec![0.0; nv];
        forward_dynamics(&model, &mut data, &q, &v, &tau, &G, None, &mut acc).unwrap();
        prop_assert!(rel(&DVector::from_vec(acc), &DVector::from_vec(a.clone())) <= 1e-9);
    }

    #[test]
    fn gim_spd_and_passivity(seed in 0u64..1_000_000, n in 1usize..12) {
        let model = random_tree(seed, n);
        let (q, v, _) = random_state(&model, seed);
        let gim = denoc::mass_matrix(&model, &q).unwrap();
        prop_assert!(gim.clone().cholesky().is_some());
        // İ by central differences along q(t) with q̇ from v; İ − 2C must be skew.
        let h = 1e-6;
        let mut qd = vec![0.0; model.nq];
        model.velocity_to_qdot(&q, &v, &mut qd);
        let step = |s: f64| { let mut x: Vec<f64> = q.iter().zip(&qd).map(|(a, b)| a + s * b).collect(); model.normalize(&mut x); x };
        let idot = (denoc::mass_matrix(&model, &step(h)).unwrap() - denoc::mass_matrix(&model, &step(-h)).unwrap()) / (2.0 * h);
        let c = denoc::convective_matrix(&model, &q, &v).unwrap();
        let n_mat = &idot - &c * 2.0;
        prop_assert!((&n_mat + n_mat.transpose()).norm() <= 1e-6 * idot.norm().max(1.0));
        // And İ = C + Cᵀ.
        prop_assert!((&idot - (&c + c.transpose())).norm() <= 1e-6 * idot.norm().max(1.0));
    }
}

#[test]
fn energy_power_balance() {
    // d(T + V)/dt = τ·v along the motion, with T, V from the recursion.
    let model = random_tree(7, 9);
    let (q, v, _) = random_state(&model, 7);
    let tau: Vec<f64> = (0..model.nv).map(|k| 0.3 * (k as f64).sin()).collect();
    let mut data = Data::new(&model);
    let mut a = vec![0.0; model.nv];
    forward_dynamics(&model, &mut data, &q, &v, &tau, &G, None, &mut a).unwrap();
    let energy = |s: f64| {
        let mut qd = vec![0.0; model.nq];
        model.velocity_to_qdot(&q, &v, &mut qd);
        // Second-order Taylor step of the state (enough for a central difference).
        let vv: Vec<f64> = v.iter().zip(&a).map(|(x, y)| x + s * y).collect();
        let mut qq: Vec<f64> = q.iter().zip(&qd).map(|(x, y)| x + s * y).collect();
        model.normalize(&mut qq);
        let mut d = Data::new(&model);
        crate::kinematics::positions(&model, &qq, &mut d.links);
        crate::kinematics::velocities(&model, &qq, &vv, &mut d.links);
        kinetic_energy(&d) + potential_energy(&d, &G)
    };
    let h = 1e-5;
    let de = (energy(h) - energy(-h)) / (2.0 * h);
    let power: f64 = tau.iter().zip(&v).map(|(x, y)| x * y).sum();
    assert!(
        (de - power).abs() < 1e-6 * (1.0 + power.abs()),
        "{de} vs {power}"
    );
}

#[test]
fn recursive_agrees_with_explicit_on_50_body_trees() {
    for seed in [11u64, 12, 13] {
        let model = random_tree(seed, 50);
        let (q, v, a) = random_state(&model, seed);
        let nv = model.nv;
        let mut data = Data::new(&model);
        let mut gim = DMatrix::zeros(nv, nv);
        mass_matrix(&model, &mut data, &q, &mut gim);
        let gim_explicit = denoc::mass_matrix(&model, &q).unwrap();
        assert!((&gim - &gim_explicit).norm() <= 1e-12 * gim_explicit.norm());
        let mut tau = vec![0.0; nv];
        inverse_dynamics(&model, &mut data, &q, &v, &a, &G, None, &mut tau);
        let tau_explicit = denoc::inverse_dynamics(&model, &q, &v, &a, &G).unwrap();
        assert!(rel(&DVector::from_vec(tau.clone()), &tau_explicit) <= 1e-10);
        let mut acc = vec![0.0; nv];
        forward_dynamics(&model, &mut data, &q, &v, &tau, &G, None, &mut acc).unwrap();
        let acc_explicit = denoc::forward_dynamics(&model, &q, &v, &tau, &G).unwrap();
        assert!(
            rel(&DVector::from_vec(acc.clone()), &acc_explicit) <= 1e-10,
            "seed {seed}"
        );
        assert!(
            rel(&DVector::from_vec(acc), &DVector::from_vec(a)) <= 1e-9,
            "seed {seed}"
        );
    }
}

#[test]
fn thousand_body_chain_inverse_of_forward() {
    let model = crate::benchmark_models::chain(1000);
    let n = model.nv;
    let q: Vec<f64> = (0..n).map(|k| 0.3 * ((k as f64) * 0.37).sin()).collect();
    let v: Vec<f64> = (0..n).map(|k| 0.5 * ((k as f64) * 0.11).cos()).collect();
    let tau: Vec<f64> = (0..n).map(|k| ((k as f64) * 0.73).sin()).collect();
    let mut data = Data::new(&model);
    let mut a = vec![0.0; n];
    forward_dynamics(&model, &mut data, &q, &v, &tau, &G, None, &mut a).unwrap();
    assert!(a.iter().all(|x| x.is_finite()));
    let mut back = vec![0.0; n];
    inverse_dynamics(&model, &mut data, &q, &v, &a, &G, None, &mut back);
    let err = DVector::from_vec(back.clone()) - DVector::from_vec(tau.clone());
    let scale = DVector::from_vec(tau).norm();
    assert!(
        err.norm() <= 1e-8 * scale,
        "relative {}",
        err.norm() / scale
    );
    // The composite-body GIM of the long chain stays symmetric positive definite.
    let mut gim = DMatrix::zeros(n, n);
    mass_matrix(&model, &mut data, &q, &mut gim);
    assert!((&gim - gim.transpose()).norm() == 0.0);
    assert!(gim.cholesky().is_some());
}

// ---- The body-frame recursion (`aba`) against the world-frame one and the
// ---- explicit DeNOC path.

fn random_wrenches(model: &Model, seed: u64) -> Vec<crate::support::spatial::Vec6> {
    let mut rng = Lcg(seed ^ 0x5851f42d4c957f2d);
    (0..model.links.len())
        .map(|_| {
            crate::support::spatial::Vec6::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-5.0, 5.0),
                rng.range(-5.0, 5.0),
                rng.range(-5.0, 5.0),
            )
        })
        .collect()
}

/// Both recursions on one state; returns (local, world).
fn both_forward(
    model: &Model,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    ext: Option<&[crate::support::spatial::Vec6]>,
) -> (DVector<f64>, DVector<f64>) {
    let mut data = Data::new(model);
    let mut loc = vec![0.0; model.nv];
    let mut world = vec![0.0; model.nv];
    aba::forward_dynamics_local(model, &mut data, q, v, tau, &G, ext, &mut loc).unwrap();
    forward_dynamics_world(
        model,
        &mut Workspace::new(model),
        q,
        v,
        tau,
        &G,
        ext,
        &mut world,
    )
    .unwrap();
    (DVector::from_vec(loc), DVector::from_vec(world))
}

#[test]
fn local_forward_agrees_with_world_on_random_trees() {
    for n in (1..=50).step_by(1) {
        for seed in [n as u64 * 31 + 1, n as u64 * 977 + 5] {
            let model = random_tree(seed, n);
            let (q, v, a) = random_state(&model, seed);
            let tau: Vec<f64> = a.iter().map(|x| 3.0 * x).collect();
            let ext = random_wrenches(&model, seed);
            for e in [None, Some(ext.as_slice())] {
                let (loc, world) = both_forward(&model, &q, &v, &tau, e);
                assert!(
                    rel(&loc, &world) <= 1e-10,
                    "n {n} seed {seed} ext {}: relative {}",
                    e.is_some(),
                    rel(&loc, &world)
                );
            }
            // Zero speeds and no gravity-free shortcut: the pure inertial case too.
            let zero = vec![0.0; model.nv];
            let (loc, world) = both_forward(&model, &q, &zero, &tau, None);
            assert!(rel(&loc, &world) <= 1e-10, "n {n} seed {seed} at rest");
        }
    }
}

#[test]
fn local_forward_inverts_inverse_dynamics_with_wrenches() {
    for seed in [3u64, 4, 5, 6] {
        let model = random_tree(seed, 40);
        let (q, v, a) = random_state(&model, seed);
        let ext = random_wrenches(&model, seed);
        let mut data = Data::new(&model);
        let mut tau = vec![0.0; model.nv];
        inverse_dynamics_world(
            &model,
            &mut Workspace::new(&model),
            &q,
            &v,
            &a,
            &G,
            Some(&ext),
            &mut tau,
        );
        let mut acc = vec![0.0; model.nv];
        aba::forward_dynamics_local(&model, &mut data, &q, &v, &tau, &G, Some(&ext), &mut acc)
            .unwrap();
        assert!(
            rel(&DVector::from_vec(acc), &DVector::from_vec(a)) <= 1e-9,
            "seed {seed}"
        );
    }
}

#[test]
fn local_forward_agrees_with_explicit_on_50_body_trees() {
    for seed in [11u64, 12, 13, 14, 15] {
        let model = random_tree(seed, 50);
        let (q, v, a) = random_state(&model, seed);
        let tau: Vec<f64> = a.iter().map(|x| 2.0 * x - 0.5).collect();
        let mut data = Data::new(&model);
        let mut acc = vec![0.0; model.nv];
        aba::forward_dynamics_local(&model, &mut data, &q, &v, &tau, &G, None, &mut acc).unwrap();
        let explicit = denoc::forward_dynamics(&model, &q, &v, &tau, &G).unwrap();
        assert!(
            rel(&DVector::from_vec(acc), &explicit) <= 1e-10,
            "seed {seed}"
        );
    }
}

/// Placement rotations of the joint-pair models: none, a general one, and exact turns about
/// x, y, z (built entry by entry, as URDF `rpy = (r, 0, 0)` gives them).
fn pair_placements() -> Vec<(&'static str, Mat3)> {
    let (c, s) = (0.7f64.cos(), 0.7f64.sin());
    vec![
        ("unrotated", Mat3::identity()),
        (
            "rotated",
            *nalgebra::Rotation3::from_scaled_axis(Vec3::new(0.4, -0.7, 0.2)).matrix(),
        ),
        (
            "turned about x",
            Mat3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c),
        ),
        (
            "turned about y",
            Mat3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c),
        ),
        (
            "turned about z",
            Mat3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0),
        ),
        // Signed permutations, absorbed into the link frames (`compiled`): a quarter
        // turn about x (URDF rpy = (π/2, 0, 0) after snapping), a half turn about y, and
        // rpy = (π/2, 0, π/2).
        (
            "quarter turn about x",
            Mat3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0),
        ),
        (
            "half turn about y",
            Mat3::new(-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0),
        ),
        (
            "signed permutation",
            Mat3::new(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0),
        ),
    ]
}

/// Two bodies, every pair of joint types, at the root and below each placement rotation of
/// `pair_placements`, so the plane-rotation fast paths (with every placement kind) and the
/// general path all run: (label, pair index, model).
fn joint_pair_models(with_fixed: bool) -> Vec<(String, usize, Model)> {
    let body = RigidBody::new(
        1.3,
        Vec3::new(0.1, -0.2, 0.05),
        Mat3::from_diagonal(&Vec3::new(0.02, 0.03, 0.025)),
    )
    .unwrap();
    let mut joints = vec![
        Joint::revolute(Vec3::x()).unwrap(),
        Joint::revolute(Vec3::y()).unwrap(),
        Joint::revolute(Vec3::z()).unwrap(),
        Joint::revolute(Vec3::new(0.3, -0.4, 0.8)).unwrap(),
        Joint::prismatic(Vec3::new(0.2, 0.9, -0.1)).unwrap(),
        Joint::Spherical,
        Joint::SphericalZYZ,
        Joint::FreeFlyer,
    ];
    if with_fixed {
        joints.push(Joint::Fixed);
    }
    let mut out = Vec::new();
    for (k, j0) in joints.iter().enumerate() {
        for j1 in &joints {
            for (placed, rot) in pair_placements() {
                let place = |t: Vec3| Placement::new(rot, t);
                let mut model = Model::new();
                let b0 = model
                    .add_body(body, *j0, None, place(Vec3::new(0.0, 0.1, 0.0)), None, None)
                    .unwrap();
                model
                    .add_body(
                        body,
                        *j1,
                        Some(b0),
                        place(Vec3::new(0.4, -0.1, 0.2)),
                        None,
                        None,
                    )
                    .unwrap();
                let label = format!("{} / {} {placed}", j0.kind(), j1.kind());
                out.push((label, k, model));
            }
        }
    }
    out
}

#[test]
fn placement_kinds_are_recognised() {
    // The fast paths the joint-pair tests mean to cover: the kinds of a revolute joint about
    // z below each placement of `pair_placements`.
    let body = RigidBody::new(1.0, Vec3::zeros(), Mat3::identity() * 0.1).unwrap();
    let codes: Vec<(LinkKind, f64)> = pair_placements()
        .into_iter()
        .map(|(_, rot)| {
            let mut model = Model::new();
            let joint = Joint::revolute(Vec3::z()).unwrap();
            let place = Placement::new(rot, Vec3::new(0.1, 0.2, 0.3));
            model
                .add_body(body, joint, None, place, None, None)
                .unwrap();
            let l = compiled::link_consts(&model.links[0], &Mat3::identity(), [0.0; 3]).0;
            (l.kind, l.sign)
        })
        .collect();
    // Revolute about z below each placement (none, general, a turn about x-z).
    // The signed permutations are absorbed: the joint turns about Q e_z with no placement
    // (−e_y, −e_z, +e_x).
    use LinkKind::*;
    let want = vec![
        (RevoluteZUnplaced, 1.0),
        (RevoluteZPlaced, 1.0),
        (RevoluteZTurnX, 1.0),
        (RevoluteZTurnY, 1.0),
        (RevoluteZTurnZ, 1.0),
        (RevoluteYUnplaced, -1.0),
        (RevoluteZUnplaced, -1.0),
        (RevoluteXUnplaced, 1.0),
    ];
    assert_eq!(codes, want);
}

/// A random tree whose joints are mostly revolute about a coordinate axis (the dispatch
/// `Revolute*` kinds of `LinkKind`), below every placement kind of `pair_placements`, at
/// offsets of every form (zero, along x, y or z only, anywhere), with some spherical and
/// prismatic joints among them, and branching, so that links have several children.
fn random_axis_tree(seed: u64, n: usize) -> Model {
    let mut rng = Lcg(seed);
    let placements = pair_placements();
    let mut model = Model::new();
    for k in 0..n {
        let body = RigidBody::new(
            rng.range(0.2, 3.0),
            rng.vec3(0.3),
            Mat3::from_diagonal(&Vec3::new(
                rng.range(0.03, 0.05),
                rng.range(0.03, 0.05),
                rng.range(0.03, 0.05),
            )),
        )
        .unwrap();
        let pick = |rng: &mut Lcg, m: usize| ((rng.next() * m as f64) as usize).min(m - 1);
        let axis = [Vec3::x(), Vec3::y(), Vec3::z()][pick(&mut rng, 3)];
        let joint = match k % 9 {
            4 => Joint::Spherical,
            7 => Joint::prismatic(rng.vec3(1.0)).unwrap(),
            _ => Joint::revolute(axis).unwrap(),
        };
        let t = rng.range(-0.4, 0.4);
        let offset = match pick(&mut rng, 5) {
            0 => Vec3::zeros(),
            1 => Vec3::new(t, 0.0, 0.0),
            2 => Vec3::new(0.0, t, 0.0),
            3 => Vec3::new(0.0, 0.0, t),
            _ => rng.vec3(0.4),
        };
        let rot = placements[pick(&mut rng, placements.len())].1;
        let parent = (k > 0).then(|| pick(&mut rng, k));
        model
            .add_body(body, joint, parent, Placement::new(rot, offset), None, None)
            .unwrap();
    }
    model
}

#[test]
fn local_forward_on_axis_trees_with_every_offset_form() {
    let mut kinds = std::collections::BTreeSet::new();
    let mut forms = std::collections::BTreeSet::new();
    let mut several_children = false;
    for seed in 0..40u64 {
        let n = 2 + (seed as usize * 7) % 30;
        let model = random_axis_tree(seed, n);
        for (i, l) in model.compiled().links.iter().enumerate() {
            kinds.insert(l.kind);
            if model.links[i].parent.is_some() {
                forms.insert(l.offset_form);
            }
            several_children |= !l.first_child && model.links[i].parent.is_some();
        }
        let (q, v, a) = random_state(&model, seed);
        let tau: Vec<f64> = a.iter().map(|x| 3.0 * x - 0.2).collect();
        let ext = random_wrenches(&model, seed);
        for e in [None, Some(ext.as_slice())] {
            let (loc, world) = both_forward(&model, &q, &v, &tau, e);
            assert!(
                rel(&loc, &world) <= 1e-10,
                "seed {seed} n {n}: {}",
                rel(&loc, &world)
            );
            let (loc, world) = both_inverse(&model, &q, &v, &a, &G, e);
            let explicit = explicit_inverse(&model, &q, &v, &a, e);
            assert!(rel(&loc, &world) <= 1e-10, "ID seed {seed} n {n}");
            assert!(
                rel(&loc, &explicit) <= 1e-10,
                "ID explicit seed {seed} n {n}"
            );
        }
        // The workspace reused: a call at another state first must leave no trace.
        let mut data = Data::new(&model);
        let mut acc = vec![0.0; model.nv];
        let (q0, v0, _) = random_state(&model, seed + 1000);
        aba::forward_dynamics_local(&model, &mut data, &q0, &v0, &a, &G, None, &mut acc).unwrap();
        aba::forward_dynamics_local(&model, &mut data, &q, &v, &tau, &G, None, &mut acc).unwrap();
        let explicit = denoc::forward_dynamics(&model, &q, &v, &tau, &G).unwrap();
        let acc = DVector::from_vec(acc);
        assert!(rel(&acc, &explicit) <= 1e-10, "explicit seed {seed}");
        // The link-frame GIM (same frames and dispatch) against the world-frame one and the
        // explicit product, symmetric and positive definite.
        let nv = model.nv;
        let (mut local, mut world) = (DMatrix::zeros(nv, nv), DMatrix::zeros(nv, nv));
        mass_matrix_local(&model, &mut data, &q, &mut local);
        mass_matrix_world(&model, &mut Workspace::new(&model), &q, &mut world);
        let explicit = denoc::mass_matrix(&model, &q).unwrap();
        assert!(
            (&local - &world).norm() <= 1e-12 * world.norm(),
            "GIM seed {seed}"
        );
        assert!(
            (&local - &explicit).norm() <= 1e-12 * explicit.norm(),
            "GIM seed {seed}"
        );
        assert_eq!(local, local.transpose());
        assert!(local.clone().cholesky().is_some(), "GIM seed {seed}");
    }
    // Every fast path ran: all 15 revolute-on-axis kinds, `Other`, all five offset forms, and
    // links that add into a parent another child already wrote.
    assert_eq!(kinds.len(), 16, "{kinds:?}");
    assert_eq!(forms.len(), 5, "{forms:?}");
    assert!(several_children);
}

#[test]
fn local_forward_on_every_single_joint_type() {
    for (label, k, model) in joint_pair_models(false) {
        let (q, v, a) = random_state(&model, 100 + k as u64);
        let ext = random_wrenches(&model, 7);
        for e in [None, Some(ext.as_slice())] {
            let (loc, world) = both_forward(&model, &q, &v, &a, e);
            assert!(rel(&loc, &world) <= 1e-12, "{label}: {}", rel(&loc, &world));
        }
    }
}

#[test]
fn local_forward_refuses_zyz_singularity() {
    let model = crate::benchmark_models::paper_pendulum();
    let mut data = Data::new(&model);
    let mut acc = vec![0.0; 3];
    let r = aba::forward_dynamics_local(
        &model,
        &mut data,
        &[0.2, 0.0, 0.1],
        &[0.0; 3],
        &[0.0; 3],
        &G,
        None,
        &mut acc,
    );
    assert!(matches!(r, Err(crate::support::error::Error::Singular(_))));
}

#[test]
fn local_forward_thousand_body_chain() {
    let model = crate::benchmark_models::chain(1000);
    let n = model.nv;
    let q: Vec<f64> = (0..n).map(|k| 0.3 * ((k as f64) * 0.37).sin()).collect();
    let v: Vec<f64> = (0..n).map(|k| 0.5 * ((k as f64) * 0.11).cos()).collect();
    let tau: Vec<f64> = (0..n).map(|k| ((k as f64) * 0.73).sin()).collect();
    let mut data = Data::new(&model);
    let mut a = vec![0.0; n];
    aba::forward_dynamics_local(&model, &mut data, &q, &v, &tau, &G, None, &mut a).unwrap();
    let mut back = vec![0.0; n];
    inverse_dynamics_world(
        &model,
        &mut Workspace::new(&model),
        &q,
        &v,
        &a,
        &G,
        None,
        &mut back,
    );
    let err = DVector::from_vec(back) - DVector::from_vec(tau.clone());
    let scale = DVector::from_vec(tau.clone()).norm();
    // The world-frame inverse dynamics rebuilds the geometry with its own rounding, and on a
    // 1000-link chain τ is that sensitive to it: the world-frame forward dynamics at q moved
    // by about one ulp already leaves a residual of 2e-8 to 7e-7 (it passes 1e-8 only at the
    // very same rounded geometry). The body-frame recursion stays at that floor.
    assert!(
        err.norm() <= 1e-6 * scale,
        "relative {}",
        err.norm() / scale
    );
    // And the accelerations agree with the world-frame recursion.
    let (loc, world) = both_forward(&model, &q, &v, &tau, None);
    assert!(rel(&loc, &world) <= 1e-10, "relative {}", rel(&loc, &world));
}

// ---- The body-frame inverse dynamics (`rnea`) against the world-frame one and the
// ---- explicit DeNOC products; and the body-frame pair inverting each other.

/// `τ` by the body-frame and the world-frame recursions on one state; returns (local, world).
fn both_inverse(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    g: &Vec3,
    ext: Option<&[crate::support::spatial::Vec6]>,
) -> (DVector<f64>, DVector<f64>) {
    let mut data = Data::new(model);
    let mut loc = vec![0.0; model.nv];
    let mut world = vec![0.0; model.nv];
    inverse_dynamics_local(model, &mut data, q, v, a, g, ext, &mut loc);
    inverse_dynamics_world(
        model,
        &mut Workspace::new(model),
        q,
        v,
        a,
        g,
        ext,
        &mut world,
    );
    (DVector::from_vec(loc), DVector::from_vec(world))
}

/// The explicit DeNOC `τ`, with external wrenches (about link origins, world axes) mapped by
/// `(N_l N_d)ᵀ`.
fn explicit_inverse(
    model: &Model,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    ext: Option<&[crate::support::spatial::Vec6]>,
) -> DVector<f64> {
    let mut tau = denoc::inverse_dynamics(model, q, v, a, &G).unwrap();
    if let Some(f) = ext {
        let den = denoc::matrices(model, q).unwrap();
        let stacked = DVector::from_iterator(6 * f.len(), f.iter().flat_map(|w| w.iter().copied()));
        tau -= (&den.nl * &den.nd).transpose() * stacked;
    }
    tau
}

#[test]
fn local_inverse_agrees_with_world_and_explicit_on_random_trees() {
    for n in 1..=50 {
        for seed in [n as u64 * 31 + 1, n as u64 * 977 + 5] {
            let model = random_tree(seed, n);
            let (q, v, a) = random_state(&model, seed);
            let ext = random_wrenches(&model, seed);
            for e in [None, Some(ext.as_slice())] {
                let (loc, world) = both_inverse(&model, &q, &v, &a, &G, e);
                let explicit = explicit_inverse(&model, &q, &v, &a, e);
                let tag = format!("n {n} seed {seed} ext {}", e.is_some());
                assert!(
                    rel(&loc, &world) <= 1e-10,
                    "{tag}: world {}",
                    rel(&loc, &world)
                );
                assert!(
                    rel(&loc, &explicit) <= 1e-10,
                    "{tag}: explicit {}",
                    rel(&loc, &explicit)
                );
            }
            // At rest without gravity (pure inertial), and gravity alone.
            let zero = vec![0.0; model.nv];
            let (loc, world) = both_inverse(&model, &q, &zero, &a, &Vec3::zeros(), None);
            assert!(rel(&loc, &world) <= 1e-10, "n {n} seed {seed} inertial");
            let (loc, world) = both_inverse(&model, &q, &zero, &zero, &G, None);
            assert!(rel(&loc, &world) <= 1e-10, "n {n} seed {seed} gravity");
        }
    }
}

#[test]
fn local_inverse_on_every_single_joint_type() {
    for (label, k, model) in joint_pair_models(true) {
        if model.nv == 0 {
            continue;
        }
        let (q, v, a) = random_state(&model, 200 + k as u64);
        let ext = random_wrenches(&model, 9);
        for e in [None, Some(ext.as_slice())] {
            let (loc, world) = both_inverse(&model, &q, &v, &a, &G, e);
            let explicit = explicit_inverse(&model, &q, &v, &a, e);
            assert!(
                rel(&loc, &world) <= 1e-12 && rel(&loc, &explicit) <= 1e-12,
                "{label}: world {} explicit {}",
                rel(&loc, &world),
                rel(&loc, &explicit)
            );
        }
    }
}

#[test]
fn local_pair_inverts_on_random_trees_with_wrenches() {
    for seed in [3u64, 4, 5, 6] {
        let model = random_tree(seed, 40);
        let (q, v, a) = random_state(&model, seed);
        let ext = random_wrenches(&model, seed);
        let mut data = Data::new(&model);
        let mut tau = vec![0.0; model.nv];
        inverse_dynamics_local(&model, &mut data, &q, &v, &a, &G, Some(&ext), &mut tau);
        let mut acc = vec![0.0; model.nv];
        forward_dynamics_local(&model, &mut data, &q, &v, &tau, &G, Some(&ext), &mut acc).unwrap();
        assert!(
            rel(&DVector::from_vec(acc), &DVector::from_vec(a)) <= 1e-9,
            "seed {seed}"
        );
    }
}

#[test]
fn local_pair_thousand_body_chain_inverse_of_forward() {
    let model = crate::benchmark_models::chain(1000);
    let n = model.nv;
    let q: Vec<f64> = (0..n).map(|k| 0.3 * ((k as f64) * 0.37).sin()).collect();
    let v: Vec<f64> = (0..n).map(|k| 0.5 * ((k as f64) * 0.11).cos()).collect();
    let tau: Vec<f64> = (0..n).map(|k| ((k as f64) * 0.73).sin()).collect();
    let mut data = Data::new(&model);
    let mut a = vec![0.0; n];
    forward_dynamics_local(&model, &mut data, &q, &v, &tau, &G, None, &mut a).unwrap();
    let mut back = vec![0.0; n];
    inverse_dynamics_local(&model, &mut data, &q, &v, &a, &G, None, &mut back);
    let err = DVector::from_vec(back) - DVector::from_vec(tau.clone());
    let scale = DVector::from_vec(tau).norm();
    assert!(
        err.norm() <= 1e-8 * scale,
        "relative {}",
        err.norm() / scale
    );
    // And the body-frame τ of these accelerations agrees with the world-frame one (both
    // evaluate the same, ill-conditioned, map; 1e-6 is the rounding floor measured for it).
    let (loc, world) = both_inverse(&model, &q, &v, &a, &G, None);
    assert!(rel(&loc, &world) <= 1e-6, "relative {}", rel(&loc, &world));
}

#[test]
fn avx2_copy_is_bit_identical() {
    // The dispatching entry points run the AVX2 copy on CPUs that have it (as CI's do); it
    // must round exactly as the baseline build does (no FMA contraction in Rust).
    #[cfg(target_arch = "x86_64")]
    if !crate::support::cpu::has_avx2() {
        eprintln!("no AVX2 on this CPU: both sides run the baseline build");
    }
    let models: Vec<Model> = (0..12u64)
        .flat_map(|seed| [random_tree(seed, 30), random_axis_tree(seed, 30)])
        .chain([crate::benchmark_models::chain(7)])
        .collect();
    for (k, model) in models.iter().enumerate() {
        let (q, v, a) = random_state(model, k as u64);
        let tau: Vec<f64> = a.iter().map(|x| 2.0 * x + 0.1).collect();
        let ext = random_wrenches(model, k as u64);
        for e in [None, Some(ext.as_slice())] {
            let mut data = Data::new(model);
            let (mut fast, mut base) = (vec![0.0; model.nv], vec![0.0; model.nv]);
            aba::forward_dynamics_local(model, &mut data, &q, &v, &tau, &G, e, &mut fast).unwrap();
            aba::forward_dynamics_baseline(model, &mut data, &q, &v, &tau, &G, e, &mut base)
                .unwrap();
            let bits = |x: &[f64]| x.iter().map(|y| y.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&fast), bits(&base), "FD model {k}");
            rnea::inverse_dynamics_local(model, &mut data, &q, &v, &a, &G, e, &mut fast);
            rnea::inverse_dynamics_baseline(model, &mut data, &q, &v, &a, &G, e, &mut base);
            assert_eq!(bits(&fast), bits(&base), "ID model {k}");
        }
        let nv = model.nv;
        let (mut fast, mut base) = (DMatrix::zeros(nv, nv), DMatrix::zeros(nv, nv));
        let mut data = Data::new(model);
        mass_matrix_local(model, &mut data, &q, &mut fast);
        crba::mass_matrix_baseline(model, &mut data, &q, &mut base);
        let bits = |m: &DMatrix<f64>| m.iter().map(|y| y.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fast), bits(&base), "GIM model {k}");
    }
}
