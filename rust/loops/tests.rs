use nalgebra::{DMatrix, DVector};

use super::factor::{cholesky, solve_semidefinite};
use crate::body::RigidBody;
use crate::joint::Joint;
use crate::model::Model;
use crate::spatial::{Mat3, Placement, Vec3};

#[test]
fn semidefinite_solve_finds_the_rank_and_solves_consistent_systems() {
    // A = B Bᵀ with B 5×3 of rank 3: rank 3, and b in its range is solved exactly.
    let b = DMatrix::from_fn(5, 3, |i, j| {
        ((i * 7 + j * 3) % 5) as f64 - 1.5 + (i == j) as u8 as f64
    });
    let a0 = &b * b.transpose();
    let x_true = DVector::from_fn(3, |i, _| i as f64 - 0.7);
    let rhs = &b * &x_true;
    let mut a = a0.clone();
    let mut x = DVector::zeros(5);
    let (mut perm, mut work) = (vec![0; 5], vec![0.0; 5]);
    let rank = solve_semidefinite(
        &mut a,
        5,
        rhs.as_slice(),
        x.as_mut_slice(),
        &mut perm,
        &mut work,
    );
    assert_eq!(rank, 3);
    let miss = (&a0 * &x - &rhs).amax();
    assert!(miss < 1e-12 * rhs.amax(), "{miss}");
}

#[test]
fn cholesky_reproduces_the_matrix_and_refuses_indefinite_ones() {
    let b = DMatrix::from_fn(4, 4, |i, j| {
        (i + 2 * j) as f64 * 0.1 + (i == j) as u8 as f64
    });
    let m0 = &b * b.transpose();
    let mut m = m0.clone();
    cholesky(&mut m).unwrap();
    let l = m.lower_triangle();
    assert!((&l * l.transpose() - &m0).amax() < 1e-13);
    let mut bad = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
    assert_eq!(cholesky(&mut bad), Err(1));
}

#[test]
fn rotation_vector_is_accurate_near_identity_and_half_turns() {
    for angle in [1e-9, 1e-4, 0.5, 2.0, std::f64::consts::PI - 1e-9] {
        let axis = Vec3::new(0.3, -0.5, 0.8).normalize();
        let r = crate::joint::axis_angle(&axis, angle);
        let w = super::constraints::rotation_vector(&r);
        assert!(
            (w - axis * angle).norm() < 1e-15 + 1e-9 * angle,
            "{angle}: {w}"
        );
    }
}

#[test]
fn deserialised_loops_are_checked() {
    let mut m = Model::new();
    let body = RigidBody::new(1.0, Vec3::zeros(), Mat3::identity() * 0.1).unwrap();
    m.add_body(
        body,
        Joint::Spherical,
        None,
        Placement::identity(),
        None,
        None,
    )
    .unwrap();
    m.add_loop(
        Some(0),
        None,
        Joint::Spherical,
        Placement::identity(),
        Placement::identity(),
        None,
    )
    .unwrap();
    let good = toml::Value::try_from(&m).unwrap();
    let back: Model = good.clone().try_into().unwrap();
    assert_eq!(back.loops, m.loops);
    let mut bad = good;
    bad["loops"][0]["body_a"] = toml::Value::Integer(5);
    let back: Result<Model, _> = bad.try_into();
    assert!(back.is_err());
}
