//! The analytic derivatives against central differences of our own recursions (in the
//! tangent space, `tangent::integrate`), whose truncation error must fall as h²; and the
//! simulation's state Jacobian against central differences of its right-hand side.
use nalgebra::DMatrix;

use super::tangent::integrate;
use super::tests::{random_state, random_tree};
use super::*;
use crate::effects::{Damper, Disabled, Effect, JointRef, PerJoint, Spring};
use crate::integrator::OdeSystem;
use crate::joint::Joint;
use crate::model::Model;
use crate::support::spatial::Vec3;

const G: Vec3 = Vec3::new(0.0, 0.0, -9.81);

/// Central differences of `f(q ⊕ δ)` in every tangent direction.
fn central_dq(
    model: &Model,
    q: &[f64],
    h: f64,
    mut f: impl FnMut(&[f64], &mut [f64]),
) -> DMatrix<f64> {
    let nv = model.nv;
    let mut out = DMatrix::zeros(nv, nv);
    let (mut qp, mut d) = (vec![0.0; model.nq], vec![0.0; nv]);
    let (mut fp, mut fm) = (vec![0.0; nv], vec![0.0; nv]);
    for c in 0..nv {
        d[c] = h;
        integrate(model, q, &d, &mut qp);
        f(&qp, &mut fp);
        d[c] = -h;
        integrate(model, q, &d, &mut qp);
        f(&qp, &mut fm);
        d[c] = 0.0;
        for r in 0..nv {
            out[(r, c)] = (fp[r] - fm[r]) / (2.0 * h);
        }
    }
    out
}

fn max_abs(m: &DMatrix<f64>) -> f64 {
    m.iter().fold(0.0, |a, x| a.max(x.abs()))
}

#[test]
fn inverse_and_forward_derivatives_are_the_limit_of_central_differences() {
    // Every joint kind (the random trees mix them), the benchmark chain and the paper's ZYZ.
    let models = [
        random_tree(3, 12),
        random_tree(8, 10),
        crate::benchmark_models::chain(7),
        crate::benchmark_models::tree(2, 3),
        crate::benchmark_models::paper_pendulum(),
    ];
    for (k, model) in models.iter().enumerate() {
        let (q, v, a) = random_state(model, 40 + k as u64);
        let mut data = Data::new(model);
        let mut dd = DerivativeData::new(model);
        let mut data2 = Data::new(model);
        // Inverse dynamics.
        inverse_dynamics_derivatives(model, &mut data, &mut dd, &q, &v, &a, &G);
        let exact = dd.dtau_dq.clone();
        let mut id = |x: &[f64], out: &mut [f64]| {
            inverse_dynamics(model, &mut data2, x, &v, &a, &G, None, out)
        };
        let e1 = max_abs(&(central_dq(model, &q, 2e-3, &mut id) - &exact));
        let e2 = max_abs(&(central_dq(model, &q, 1e-3, &mut id) - &exact));
        assert!((3.5..4.5).contains(&(e1 / e2)), "model {k}: {e1} {e2}");
        assert!(e2 < 1e-5 * max_abs(&exact), "model {k}: {e2}");
        // The τ of the pass is the inverse dynamics.
        let mut tau = vec![0.0; model.nv];
        inverse_dynamics(model, &mut data2, &q, &v, &a, &G, None, &mut tau);
        for (x, y) in tau.iter().zip(&dd.tau) {
            assert!((x - y).abs() < 1e-10 * (1.0 + x.abs()));
        }
        // Forward dynamics at τ.
        forward_dynamics_derivatives(model, &mut data, &mut dd, &q, &v, &tau, &G).unwrap();
        let exact = dd.ddq_dq.clone();
        let mut fd = |x: &[f64], out: &mut [f64]| {
            forward_dynamics(model, &mut data2, x, &v, &tau, &G, None, out).unwrap()
        };
        let e1 = max_abs(&(central_dq(model, &q, 2e-3, &mut fd) - &exact));
        let e2 = max_abs(&(central_dq(model, &q, 1e-3, &mut fd) - &exact));
        assert!((3.5..4.5).contains(&(e1 / e2)), "model {k}: {e1} {e2}");
        // ∂q̈/∂τ = M⁻¹, against the composite-body mass matrix.
        let mut m = DMatrix::zeros(model.nv, model.nv);
        mass_matrix(model, &mut data2, &q, &mut m);
        let eye = &dd.minv * &m;
        assert!(max_abs(&(eye - DMatrix::identity(model.nv, model.nv))) < 1e-9);
    }
}

#[test]
fn state_jacobian_matches_central_differences_of_the_rhs() {
    let model = random_tree(5, 9);
    // Springs on the joints that take them (not ZYZ, not free flyers), dampers on all.
    let sprung: Vec<JointRef> = model
        .links
        .iter()
        .filter(|l| {
            matches!(
                l.joint,
                Joint::Revolute { .. } | Joint::Prismatic { .. } | Joint::Spherical
            )
        })
        .map(|l| JointRef::Index(l.body))
        .collect();
    assert!(sprung.len() >= 3);
    let effects = [
        Effect::gravity(G).unwrap(),
        Effect::Damper(Damper::new(None, None, PerJoint::All(0.4)).unwrap()),
        Effect::Spring(Spring::new(None, Some(sprung), PerJoint::All(1.5), None).unwrap()),
    ];
    let mut sys = crate::simulate::Dynamics::try_new(&model, &effects, Disabled::none()).unwrap();
    let (q, v, _) = random_state(&model, 7);
    let y: Vec<f64> = q.iter().chain(&v).copied().collect();
    let dim = y.len();
    let mut jac = vec![0.0; dim * dim];
    assert!(sys.jacobian(0.1, &y, &mut jac).unwrap());
    let h = 1e-6;
    let (mut yp, mut fp, mut fm) = (y.clone(), vec![0.0; dim], vec![0.0; dim]);
    let mut worst: f64 = 0.0;
    let scale = jac.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for c in 0..dim {
        yp[c] = y[c] + h;
        sys.rhs(0.1, &yp, &mut fp).unwrap();
        yp[c] = y[c] - h;
        sys.rhs(0.1, &yp, &mut fm).unwrap();
        yp[c] = y[c];
        for r in 0..dim {
            let num = (fp[r] - fm[r]) / (2.0 * h);
            worst = worst.max((num - jac[r * dim + c]).abs());
        }
    }
    assert!(worst < 1e-7 * scale, "{worst} vs {scale}");
}

#[test]
fn state_jacobian_is_not_declined_with_closed_loops() {
    let mut model = crate::benchmark_models::chain(3);
    let end = crate::support::spatial::Placement::new(
        crate::support::spatial::Mat3::identity(),
        Vec3::new(0.3, 0.0, 0.0),
    );
    model
        .add_loop(
            Some(2),
            None,
            Joint::revolute(Vec3::y()).unwrap(),
            end,
            crate::support::spatial::Placement::new(
                crate::support::spatial::Mat3::identity(),
                Vec3::new(0.5, 0.0, 0.0),
            ),
            None,
        )
        .unwrap();
    let mut sys = crate::simulate::Dynamics::try_new(&model, &[], Disabled::none()).unwrap();
    let dim = model.nq + model.nv;
    let mut jac = vec![0.0; dim * dim];
    let y = vec![0.1; dim];
    // The constrained dynamics' Jacobian (rust/loops/derivatives.rs; checked against central
    // differences in tests/test_iftomm.py), or the locked mechanism's error: no longer
    // `Ok(false)` (the integrator's numerical fallback).
    assert!(!matches!(sys.jacobian(0.0, &y, &mut jac), Ok(false)));
}

#[test]
fn derivatives_by_rows_are_the_transposes_of_the_column_fill() {
    // Trees of every shape the fills distinguish: chains (both ranges contiguous), branches
    // (the path above not `0..`), random parents (dofs not numbered subtree by subtree).
    let models = [
        random_tree(3, 12),
        random_tree(8, 10),
        crate::benchmark_models::chain(9),
        crate::benchmark_models::tree(3, 3),
        crate::benchmark_models::paper_pendulum(),
    ];
    for (k, model) in models.iter().enumerate() {
        let (q, v, a) = random_state(model, 60 + k as u64);
        let mut data = Data::new(model);
        let (mut cols, mut rows) = (DerivativeData::new(model), DerivativeData::new(model));
        rows.row_major = true;
        inverse_dynamics_derivatives(model, &mut data, &mut cols, &q, &v, &a, &G);
        inverse_dynamics_derivatives(model, &mut data, &mut rows, &q, &v, &a, &G);
        let close =
            |x: &DMatrix<f64>, y: &DMatrix<f64>| max_abs(&(x - y)) <= 1e-13 * (1.0 + max_abs(y));
        assert!(close(&rows.dtau_dq.transpose(), &cols.dtau_dq), "model {k}");
        assert!(close(&rows.dtau_dv.transpose(), &cols.dtau_dv), "model {k}");
        assert_eq!(rows.mass, cols.mass, "model {k}");
        assert_eq!(rows.mass, rows.mass.transpose(), "model {k}");
        // Straight into the caller's buffers: the same bits (NaN-filled first: every entry
        // must be written).
        let nv2 = model.nv * model.nv;
        let mut out = vec![f64::NAN; 3 * nv2];
        let (x, rest) = out.split_at_mut(nv2);
        let (y, z) = rest.split_at_mut(nv2);
        inverse_dynamics_derivatives_into(model, &mut data, &mut cols, &q, &v, &a, &G, [x, y, z]);
        assert_eq!(&out[..nv2], rows.dtau_dq.as_slice(), "model {k}");
        assert_eq!(&out[nv2..2 * nv2], rows.dtau_dv.as_slice(), "model {k}");
        assert_eq!(&out[2 * nv2..], rows.mass.as_slice(), "model {k}");
        assert!(rows_surely_finite(&cols));
        cols.row_major = false;
        let tau: Vec<f64> = cols.tau.clone();
        forward_dynamics_derivatives(model, &mut data, &mut cols, &q, &v, &tau, &G).unwrap();
        forward_dynamics_derivatives(model, &mut data, &mut rows, &q, &v, &tau, &G).unwrap();
        assert!(close(&rows.ddq_dq.transpose(), &cols.ddq_dq), "model {k}");
        assert!(close(&rows.ddq_dv.transpose(), &cols.ddq_dv), "model {k}");
        assert_eq!(rows.minv, cols.minv, "model {k}");
    }
}

#[test]
fn fixed_size_inverse_and_products_match_nalgebra() {
    use super::aba_derivatives_small::{
        inverse_and_products, inverse_and_products_baseline, MAX_FIXED,
    };
    let mut seed = 7u64;
    let mut rnd = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for n in 1..=MAX_FIXED + 1 {
        let a = DMatrix::from_fn(n, n, |_, _| rnd());
        let m = &a * a.transpose() + DMatrix::identity(n, n) * 0.1;
        let d: [DMatrix<f64>; 2] = std::array::from_fn(|_| DMatrix::from_fn(n, n, |_, _| rnd()));
        let (mut minv, mut out) = (
            vec![f64::NAN; n * n],
            [vec![f64::NAN; n * n], vec![f64::NAN; n * n]],
        );
        let [o0, o1] = &mut out;
        let r = inverse_and_products(
            n,
            m.as_slice(),
            [d[0].as_slice(), d[1].as_slice()],
            &mut minv,
            [o0, o1],
        );
        if n > MAX_FIXED {
            assert!(r.is_none());
            continue;
        }
        assert_eq!(r, Some(Ok(())));
        let want = m.clone().cholesky().unwrap().inverse();
        let scale = max_abs(&want);
        let minv = DMatrix::from_column_slice(n, n, &minv);
        assert!(max_abs(&(&minv - &want)) < 1e-12 * scale, "n = {n}");
        assert_eq!(minv, minv.transpose(), "n = {n}");
        for (o, d) in out.iter().zip(&d) {
            let o = DMatrix::from_column_slice(n, n, o);
            assert!(
                max_abs(&(o + &want * d)) < 1e-12 * scale * max_abs(d) * n as f64,
                "n = {n}"
            );
        }
        // The baseline build: the same bits.
        let (mut minv2, mut out2) = (vec![0.0; n * n], [vec![0.0; n * n], vec![0.0; n * n]]);
        let [p0, p1] = &mut out2;
        let r = inverse_and_products_baseline(
            n,
            m.as_slice(),
            [d[0].as_slice(), d[1].as_slice()],
            &mut minv2,
            [p0, p1],
        );
        assert_eq!(r, Some(Ok(())));
        assert_eq!(minv.as_slice(), &minv2[..]);
        assert_eq!(out, out2);
        // Not positive definite: the failing pivot.
        let mut bad = m.clone();
        let [p0, p1] = &mut out2;
        bad[(n - 1, n - 1)] = -1.0;
        let r = inverse_and_products(
            n,
            bad.as_slice(),
            [d[0].as_slice(), d[1].as_slice()],
            &mut minv2,
            [p0, p1],
        );
        assert_eq!(r, Some(Err(n - 1)));
    }
}
