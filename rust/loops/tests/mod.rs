use nalgebra::{DMatrix, DVector};

use crate::joint::Joint;
use crate::linalg::cholesky::{cholesky, min_norm_solve, RANK_TOL};
use crate::model::body::RigidBody;
use crate::model::Model;
use crate::support::spatial::{Mat3, Placement, Vec3};

#[test]
fn cholesky_reproduces_the_matrix_and_refuses_indefinite_ones() {
    let b = DMatrix::from_fn(4, 4, |i, j| {
        (i + 2 * j) as f64 * 0.1 + (i == j) as u8 as f64
    });
    let m0 = &b * b.transpose();
    let mut m = m0.clone();
    cholesky(&mut m, &mut []).unwrap();
    let l = m.lower_triangle();
    assert!((&l * l.transpose() - &m0).amax() < 1e-13);
    let mut bad = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
    assert_eq!(cholesky(&mut bad, &mut []), Err(1));
}

/// The factor's column ends as `cholesky` reports them, against a scan of the factor: a
/// tree-like mass matrix (two branches, zero between them) keeps its zeros.
#[test]
fn cholesky_column_ends_match_the_factor() {
    // Coordinates 0-1-2 a chain, 3-4 another branch; 5 alone.
    let pairs = [(0, 1), (0, 2), (1, 2), (3, 4)];
    let mut m0 = DMatrix::from_diagonal_element(6, 6, 3.0);
    for (k, &(i, j)) in pairs.iter().enumerate() {
        let x = 0.3 + 0.1 * k as f64;
        (m0[(i, j)], m0[(j, i)]) = (x, x);
    }
    let mut m = m0.clone();
    let mut ends = vec![usize::MAX; 6];
    cholesky(&mut m, &mut ends).unwrap();
    let l = m.lower_triangle();
    assert!((&l * l.transpose() - &m0).amax() < 1e-13);
    let scanned: Vec<usize> = (0..6)
        .map(|k| {
            (k + 1..6)
                .rev()
                .find(|&i| l[(i, k)] != 0.0)
                .map_or(k + 1, |i| i + 1)
        })
        .collect();
    assert_eq!(ends, scanned);
    assert_eq!(ends, [3, 3, 3, 5, 5, 6]);
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

/// `min_norm_solve` on a copy of `a`: the solution and the rank.
fn min_norm(a: &DMatrix<f64>, b: &DVector<f64>) -> (DVector<f64>, usize) {
    let (mut a, mut b) = (a.clone(), b.clone());
    let cols = a.ncols();
    let mut x = DVector::zeros(cols);
    let (mut pivots, mut work) = (vec![0; cols], vec![0.0; cols]);
    let rank = min_norm_solve(
        a.view_mut((0, 0), (a.nrows(), cols)),
        b.as_mut_slice(),
        x.as_mut_slice(),
        &mut pivots,
        &mut work,
        RANK_TOL,
    );
    (x, rank)
}

#[test]
fn min_norm_solve_keeps_round_off_where_the_svd_loses_digits() {
    // Upper triangular with a small off-diagonal and |a11| < |a22|: nalgebra's 2 × 2 SVD
    // kernel cancels here (its ‖UΣVᵀ − A‖ is ~1e-9 of ‖A‖, the error of the slider-crank's
    // driving torque). Dyadic entries: b = A x* is exact, and so is x* = (1, −3). Zero
    // columns beside it, as the vanishing rows of a planar loop leave in [S_a | Jᵀ], must get
    // zero.
    let eps = f64::EPSILON;
    let a = DMatrix::from_row_slice(2, 4, &[0.5, 0.0, 2f64.powi(-24), 0.0, 0.0, 0.0, 0.875, 0.0]);
    let x_true = DVector::from_row_slice(&[1.0, 0.0, -3.0, 0.0]);
    let (x, rank) = min_norm(&a, &(&a * &x_true));
    assert_eq!(rank, 2);
    assert!((&x - &x_true).amax() <= 4.0 * eps * 3.0, "{x}");
}

#[test]
fn min_norm_solve_gives_the_minimum_norm_solution_of_badly_scaled_redundant_systems() {
    // Integers, one row the sum of two others (rank 3, as redundant cut-joint rows), columns
    // scaled by 2^-8 … 2^8 (meters against radians, and worse). Every x* = Bᵀw solves
    // B x = B x* with the least norm (x* lies in B's row space, the orthogonal complement of
    // its null space), and here both are exact in floating point.
    let ints = DMatrix::from_row_slice(
        4,
        6,
        &[
            3.0, -1.0, 4.0, 1.0, -5.0, 9.0, //
            2.0, 6.0, -5.0, 3.0, 5.0, -8.0, //
            9.0, -7.0, 9.0, 3.0, -2.0, 3.0, //
            5.0, 5.0, -1.0, 4.0, 0.0, 1.0, // row 0 + row 1
        ],
    );
    let scales = [-8, 0, 5, -3, 8, 1];
    let b_mat = DMatrix::from_fn(4, 6, |i, j| ints[(i, j)] * 2f64.powi(scales[j]));
    for w in [
        [1.0, -2.0, 3.0, 0.0],
        [0.0, 0.0, 1.0, -7.0],
        [4.0, 1.0, 0.0, 2.0],
    ] {
        let x_true = b_mat.transpose() * DVector::from_row_slice(&w);
        let (x, rank) = min_norm(&b_mat, &(&b_mat * &x_true));
        assert_eq!(rank, 3);
        let err = (&x - &x_true).amax() / x_true.amax();
        assert!(err < 1e-13, "{err:e}: {x} against {x_true}");
    }
    // The square semi-definite case of the constraint forces, G = C Cᵀ (C: the integers, rank
    // 3): λ* = C z is in G's range, so it is the least-norm solution of G λ = G λ*.
    let g = &ints * ints.transpose();
    for z in [
        [1.0, 0.0, -1.0, 2.0, 0.0, 1.0],
        [0.0, 3.0, 1.0, -1.0, 2.0, 0.0],
    ] {
        let lam_true = &ints * DVector::from_row_slice(&z);
        let (lam, rank) = min_norm(&g, &(&g * &lam_true));
        assert_eq!(rank, 3);
        let err = (&lam - &lam_true).amax() / lam_true.amax();
        assert!(err < 1e-13, "{err:e}: {lam} against {lam_true}");
    }
}

#[test]
fn min_norm_solve_fits_inconsistent_systems_in_least_squares_and_zero_ones_with_zero() {
    // b = A (1, 2) + 5 e₃, the residual orthogonal to A's range: x = (1, 2).
    let a = DMatrix::from_row_slice(3, 2, &[0.0, 2.0, 1.0, 0.0, 0.0, 0.0]);
    let (x, rank) = min_norm(&a, &DVector::from_row_slice(&[4.0, 1.0, 5.0]));
    assert_eq!(rank, 2);
    assert_eq!(x.as_slice(), &[1.0, 2.0]);
    let (x, rank) = min_norm(&DMatrix::zeros(2, 3), &DVector::from_row_slice(&[1.0, 2.0]));
    assert_eq!(rank, 0);
    assert_eq!(x.as_slice(), &[0.0; 3]);
}

/// The benchmark's N-four-bar (tests/test_iftomm.py, `n_fourbar`): vertical bars v_k pinned
/// at x = k, horizontal bar h_k on v_k's top, cut revolute h_k's end — v_(k+1)'s top.
fn n_fourbar(n: usize) -> Model {
    let i = 1.0 / 12.0;
    let rod = || {
        RigidBody::new(
            1.0,
            Vec3::new(0.5, 0.0, 0.0),
            Mat3::from_diagonal(&Vec3::new(1e-8, i, i)),
        )
        .unwrap()
    };
    let at = |x: f64| Placement::new(Mat3::identity(), Vec3::new(x, 0.0, 0.0));
    let z = Joint::Revolute { axis: Vec3::z() };
    let mut m = Model::new();
    for k in 0..=n {
        m.add_body(rod(), z, None, at(k as f64), None, None)
            .unwrap();
        if k < n {
            m.add_body(rod(), z, Some(2 * k), at(1.0), None, None)
                .unwrap();
        }
    }
    for k in 0..n {
        m.add_loop(Some(2 * k + 1), Some(2 * k + 2), z, at(1.0), at(1.0), None)
            .unwrap();
    }
    m
}

/// Every vertical bar at `phi`, every horizontal one level, turning at `rate`.
fn parallel_state(n: usize, phi: f64, rate: f64) -> (Vec<f64>, Vec<f64>) {
    let q = (0..2 * n + 1)
        .map(|k| if k % 2 == 0 { phi } else { -phi })
        .collect();
    let v = (0..2 * n + 1)
        .map(|k| if k % 2 == 0 { rate } else { -rate })
        .collect();
    (q, v)
}

/// Constrained accelerations with the banded or the dense QRs.
fn accelerations(m: &Model, q: &[f64], v: &[f64], envelope: bool) -> (Vec<f64>, usize) {
    let mut data = crate::recursive::Data::new(m);
    let mut solver = super::LoopSolver::with_envelope(m, envelope);
    let mut a = vec![0.0; m.nv];
    let g = Vec3::new(0.0, -9.81, 0.0);
    let tau = vec![0.0; m.nv];
    crate::recursive::forward_dynamics(m, &mut data, q, v, &tau, &g, None, &mut a).unwrap();
    super::constrained_forward_dynamics(m, &mut data, &mut solver, q, v, &mut a).unwrap();
    (a, solver.rank)
}

#[test]
fn long_loop_chains_take_the_banded_qr_and_agree_with_the_dense_one() {
    let n = 12;
    let m = n_fourbar(n);
    assert!(super::LoopSolver::new(&m).envelope);
    assert!(!super::LoopSolver::new(&n_fourbar(4)).envelope);
    // φ'' = −c cos φ for the parallel motion (tests/test_iftomm.py, `n_fourbar_rate`).
    let nf = n as f64;
    let c = 9.81 * ((nf + 1.0) / 2.0 + nf) / ((nf + 1.0) / 3.0 + nf);
    for (phi, rank) in [(0.7, 2 * n), (1e-3, 2 * n), (1e-7, 2 * n), (0.0, n)] {
        let (q, v) = parallel_state(n, phi, 0.0);
        let (banded, rank_b) = accelerations(&m, &q, &v, true);
        let (dense, rank_d) = accelerations(&m, &q, &v, false);
        assert_eq!((rank_b, rank_d), (rank, rank), "{phi}");
        for (b, d) in banded.iter().zip(&dense) {
            assert!((b - d).abs() < 1e-9 * (1.0 + d.abs()), "{phi}: {b} {d}");
        }
        if phi > 0.0 {
            // Near the singular position the motion stays the parallel one.
            assert!(
                (banded[0] + c * phi.cos()).abs() < 1e-8,
                "{phi}: {}",
                banded[0]
            );
        }
    }
    // Moving off the parallel motion: generic speeds made to keep the loops closed.
    let (q, _) = parallel_state(n, 0.4, 0.0);
    let mut v: Vec<f64> = (0..m.nv).map(|k| (k as f64 * 1.7).sin()).collect();
    super::project_velocity_like(&m, &q, None, &mut v, &vec![false; m.nv]).unwrap();
    let (banded, _) = accelerations(&m, &q, &v, true);
    let (dense, _) = accelerations(&m, &q, &v, false);
    for (b, d) in banded.iter().zip(&dense) {
        assert!((b - d).abs() < 1e-9 * (1.0 + d.abs()), "{b} {d}");
    }
}

#[test]
fn banded_projection_closes_the_loops_as_the_dense_one() {
    let n = 12;
    let m = n_fourbar(n);
    let (q, v) = parallel_state(n, 0.3, -0.8);
    let mut y0: Vec<f64> = q.iter().chain(&v).copied().collect();
    // Off both manifolds by ~1e-6.
    for (k, x) in y0.iter_mut().enumerate() {
        *x += 1e-6 * ((k * 7 % 11) as f64 - 5.0);
    }
    let mut out = Vec::new();
    for envelope in [true, false] {
        let mut solver = super::LoopSolver::with_envelope(&m, envelope);
        let mut y = y0.clone();
        super::project_state(&m, &mut solver, &mut y).unwrap();
        out.push(y);
    }
    for (b, d) in out[0].iter().zip(&out[1]) {
        assert!((b - d).abs() < 1e-12, "{b} {d}");
    }
    let mut kin = super::LoopKinematics::new(&m);
    kin.positions(&m, &out[0][..m.nq]);
    let mut r = vec![0.0; m.nconstraints()];
    super::residual(&m, &kin, &mut r);
    assert!(r.iter().all(|x| x.abs() < 1e-13), "{r:?}");
}

#[test]
fn oriented_kernel_is_the_rows_cross_product_and_reverses_at_the_change_point() {
    // N-four-bars on the parallel motion (one degree of freedom; the change point at φ = 0):
    // the kernel is the motion's tangent (1, −1, 1, …), oriented so that det[J_B; kᵀ] > 0
    // with the kept rows in increasing order (an LU determinant, independent of the QR),
    // for the dense (pivoted) and the banded QRs alike; that orientation keeps its sign on
    // either side of φ = 0 and across it takes the sign of the N rows that pass through zero
    // there (each loop's row along the bars): it reverses for odd N only.
    for (n, envelope) in [
        (1, false),
        (2, false),
        (3, true),
        (12, true),
        (12, false),
        (13, true),
    ] {
        let m = n_fourbar(n);
        let nv = m.nv;
        let mut solver = super::LoopSolver::with_envelope(&m, envelope);
        let (mut rows, mut order) = (Vec::new(), Vec::new());
        let mut kernel_at = |phi: f64| {
            let (q, v) = parallel_state(n, phi, 0.3);
            let mut y: Vec<f64> = q.iter().chain(&v).copied().collect();
            super::project_state(&m, &mut solver, &mut y).unwrap();
            let mut k = vec![0.0; nv];
            assert!(solver.oriented_kernel(&mut k, &mut rows, &mut order));
            assert_eq!(rows.len(), nv - 1);
            let mut a = DMatrix::zeros(nv, nv);
            for (i, &r) in rows.iter().enumerate() {
                for c in 0..nv {
                    a[(i, c)] = solver.cons.jacobian[(r, c)];
                }
            }
            for c in 0..nv {
                a[(nv - 1, c)] = k[c];
            }
            assert!(a.determinant() > 0.0, "n = {n}, φ = {phi}");
            let tangent = 1.0 / (nv as f64).sqrt();
            for (c, x) in k.iter().enumerate() {
                let want = if c % 2 == 0 { tangent } else { -tangent };
                assert!((x.abs() - tangent).abs() < 1e-9 && x * want * k[0].signum() > 0.0);
            }
            k
        };
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let (far, near) = (kernel_at(0.4), kernel_at(1e-3));
        let (below, far_below) = (kernel_at(-1e-3), kernel_at(-0.4));
        assert!(dot(&far, &near) > 0.99 && dot(&below, &far_below) > 0.99);
        let across = if n % 2 == 1 { -1.0 } else { 1.0 };
        assert!(dot(&near, &below) * across > 0.99, "n = {n}: across φ = 0");
    }
}

/// The N-four-bar with its bodies added in `bodies`' order (logical body `2k` is v_k,
/// `2k + 1` is h_k; each after its parent) and its loops in `loops`' order. Returns the
/// model and each logical body's index (= its coordinate).
fn n_fourbar_numbered(n: usize, bodies: &[usize], loops: &[usize]) -> (Model, Vec<usize>) {
    let i = 1.0 / 12.0;
    let rod = || {
        RigidBody::new(
            1.0,
            Vec3::new(0.5, 0.0, 0.0),
            Mat3::from_diagonal(&Vec3::new(1e-8, i, i)),
        )
        .unwrap()
    };
    let mut index = vec![usize::MAX; 2 * n + 1];
    let mut m = Model::new();
    let at = |x: f64| Placement::new(Mat3::identity(), Vec3::new(x, 0.0, 0.0));
    let z = Joint::Revolute { axis: Vec3::z() };
    for (k, &b) in bodies.iter().enumerate() {
        let (parent, x) = if b % 2 == 0 {
            (None, (b / 2) as f64)
        } else {
            (Some(index[b - 1]), 1.0)
        };
        m.add_body(rod(), z, parent, at(x), None, None).unwrap();
        index[b] = k;
    }
    for &k in loops {
        let (a, b) = (index[2 * k + 1], index[2 * k + 2]);
        m.add_loop(Some(a), Some(b), z, at(1.0), at(1.0), None)
            .unwrap();
    }
    (m, index)
}

/// A pseudo-random order of the N-four-bar's bodies with each h_k after its v_k, and of its
/// loops.
fn shuffled(n: usize, seed: u64) -> (Vec<usize>, Vec<usize>) {
    let mut state = seed | 1;
    let mut next = |below: usize| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % below as u64) as usize
    };
    let mut ready: Vec<usize> = (0..=n).map(|k| 2 * k).collect();
    let mut bodies = Vec::new();
    while !ready.is_empty() {
        let b = ready.swap_remove(next(ready.len()));
        bodies.push(b);
        if b % 2 == 0 && b < 2 * n {
            ready.push(b + 1);
        }
    }
    let mut loops: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        loops.swap(i, next(i + 1));
    }
    (bodies, loops)
}

#[test]
fn any_numbering_of_a_loop_chain_gets_the_interleaved_band() {
    let n = 12;
    let interleaved: Vec<usize> = (0..=2 * n).collect();
    let in_order: Vec<usize> = (0..n).collect();
    let rods_first: Vec<usize> = (0..=n)
        .map(|k| 2 * k)
        .chain((0..n).map(|k| 2 * k + 1))
        .collect();
    let band = |m: &Model| {
        let solver = super::LoopSolver::new(m);
        assert!(solver.envelope);
        super::ordering::profile(m, &super::ordering::inverse(solver.order()))
    };
    let (m0, _) = n_fourbar_numbered(n, &interleaved, &in_order);
    let best = band(&m0);
    // Each loop's rows touch three joints, adjacent at best (5 rows, J's span 3), and Y's
    // reach the end of v_(k+1)'s tree (span 4; 3 for the last loop: v_n has no h_n).
    assert_eq!(best, 5 * (n * (3 + 4) - 1));
    let identity: Vec<usize> = (0..m0.nv).collect();
    let (m1, _) = n_fourbar_numbered(n, &rods_first, &in_order);
    // The model's own order would be a band of width ~n.
    assert!(super::ordering::profile(&m1, &identity) > 3 * best);
    assert_eq!(band(&m1), best);
    for seed in 1..6 {
        let (bodies, loops) = shuffled(n, 0x9e37_79b9_7f4a_7c15_u64.wrapping_mul(seed));
        let (m, _) = n_fourbar_numbered(n, &bodies, &loops);
        assert_eq!(band(&m), best, "{bodies:?}");
    }
}

#[test]
fn reordered_banded_solver_agrees_with_the_dense_one_and_the_interleaved_numbering() {
    let n = 12;
    let interleaved: Vec<usize> = (0..=2 * n).collect();
    let in_order: Vec<usize> = (0..n).collect();
    let (q0, _) = parallel_state(n, 0.4, 0.0);
    let (m0, _) = n_fourbar_numbered(n, &interleaved, &in_order);
    let mut v0: Vec<f64> = (0..m0.nv).map(|k| (k as f64 * 1.7).sin()).collect();
    super::project_velocity_like(&m0, &q0, None, &mut v0, &vec![false; m0.nv]).unwrap();
    let (a0, _) = accelerations(&m0, &q0, &v0, true);
    for seed in 1..4 {
        let (bodies, loops) = shuffled(n, 0x2545_f491_4f6c_dd1d_u64.wrapping_mul(seed));
        let (m, index) = n_fourbar_numbered(n, &bodies, &loops);
        assert!(super::LoopSolver::new(&m).order() != (0..m.nv).collect::<Vec<_>>());
        let (mut q, mut v) = (vec![0.0; m.nv], vec![0.0; m.nv]);
        for (b, &i) in index.iter().enumerate() {
            (q[i], v[i]) = (q0[b], v0[b]);
        }
        let (banded, rank_b) = accelerations(&m, &q, &v, true);
        let (dense, rank_d) = accelerations(&m, &q, &v, false);
        assert_eq!((rank_b, rank_d), (2 * n, 2 * n));
        for (b, &i) in index.iter().enumerate() {
            let scale = 1.0 + a0[b].abs();
            assert!((banded[i] - dense[i]).abs() < 1e-9 * scale, "{seed} {b}");
            assert!((banded[i] - a0[b]).abs() < 1e-9 * scale, "{seed} {b}");
        }
        // The projection maps its steps back to the model's coordinates.
        let mut y: Vec<f64> = q.iter().chain(&v).map(|x| x + 1e-7).collect();
        let mut solver = super::LoopSolver::new(&m);
        super::project_state(&m, &mut solver, &mut y).unwrap();
        let mut kin = super::LoopKinematics::new(&m);
        kin.positions(&m, &y[..m.nq]);
        let mut r = vec![0.0; m.nconstraints()];
        super::residual(&m, &kin, &mut r);
        assert!(r.iter().all(|x| x.abs() < 1e-13), "{r:?}");
    }
}
