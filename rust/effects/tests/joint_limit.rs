//! Joint limits against their closed form, their derivatives against central differences,
//! the model's bounds as defaults, and their refusals.
use super::*;
use crate::model::body::RigidBody;
use crate::support::spatial::{Mat3, Placement, Vec3};
use nalgebra::DMatrix;

/// arm (revolute z) → slider (prismatic x) → ball (quaternion).
fn model() -> Model {
    let b = || RigidBody::new(1.0, Vec3::new(0.1, 0.0, 0.0), Mat3::identity() * 0.01).unwrap();
    let mut m = Model::new();
    let arm = m
        .add_body(
            b(),
            Joint::revolute(Vec3::z()).unwrap(),
            None,
            Placement::identity(),
            Some("arm".into()),
            None,
        )
        .unwrap();
    let slider = m
        .add_body(
            b(),
            Joint::prismatic(Vec3::x()).unwrap(),
            Some(arm),
            Placement::identity(),
            Some("slider".into()),
            None,
        )
        .unwrap();
    m.add_body(
        b(),
        Joint::Spherical,
        Some(slider),
        Placement::identity(),
        Some("ball".into()),
        None,
    )
    .unwrap();
    m
}

fn limit(lower: Option<PerJoint>, upper: Option<PerJoint>) -> JointLimit {
    JointLimit::new(
        None,
        None,
        lower,
        upper,
        PerJoint::Each(vec![100.0, 50.0]),
        PerJoint::All(2.0),
    )
    .unwrap()
}

fn tau(law: &mut Box<dyn ForceLaw>, m: &Model, q: &[f64], v: &[f64]) -> Vec<f64> {
    let mut t = vec![0.0; m.nv];
    let mut w = vec![Vec6::zeros(); m.links.len()];
    let cx = Context {
        model: m,
        t: 0.0,
        q,
        v,
    };
    law.apply(&cx, &mut t, &mut w).unwrap();
    t
}

#[test]
fn force_is_a_one_sided_spring_damper_outside_the_range() {
    let m = model();
    let l = limit(
        Some(PerJoint::Each(vec![-1.0, 0.0])),
        Some(PerJoint::Each(vec![1.0, f64::INFINITY])),
    );
    let mut law = l.build(&m).unwrap();
    let quat = [0.0, 0.0, 0.0, 1.0];
    let q = |a: f64, s: f64| [a, s, quat[0], quat[1], quat[2], quat[3]];
    let v = |a: f64, s: f64| [a, s, 0.3, 0.2, 0.1];
    // Inside: nothing, whatever the speed.
    assert_eq!(tau(&mut law, &m, &q(0.5, 3.0), &v(5.0, -5.0)), vec![0.0; 5]);
    // Past the upper bound, moving out: k δ + c q̇ pushes back.
    let t = tau(&mut law, &m, &q(1.1, 0.0), &v(0.5, 0.0));
    assert!((t[0] - -(100.0 * 0.1 + 2.0 * 0.5)).abs() < 1e-12, "{t:?}");
    // Below the lower bound of the slider, moving back in fast: the damper would pull, so 0.
    let t = tau(&mut law, &m, &q(0.0, -0.01), &v(0.0, 1.0));
    assert_eq!(t[1], 0.0);
    let t = tau(&mut law, &m, &q(0.0, -0.01), &v(0.0, 0.1));
    assert!((t[1] - (50.0 * 0.01 - 2.0 * 0.1)).abs() < 1e-12);
    // The slider has no upper bound.
    assert_eq!(tau(&mut law, &m, &q(0.0, 1e6), &v(0.0, 1.0))[1], 0.0);
}

#[test]
fn derivatives_are_central_differences_and_energy_is_its_potential() {
    let m = model();
    let l = limit(Some(PerJoint::All(-1.0)), Some(PerJoint::All(1.0)));
    let mut law = l.build(&m).unwrap();
    let q = [1.2, -1.05, 0.0, 0.0, 0.0, 1.0];
    let v = [0.4, -0.3, 0.0, 0.0, 0.0];
    let (mut dq, mut dv) = (DMatrix::zeros(5, 5), DMatrix::zeros(5, 5));
    let cx = Context {
        model: &m,
        t: 0.0,
        q: &q,
        v: &v,
    };
    assert!(law.add_derivatives(&cx, &mut dq, &mut dv).unwrap());
    let h = 1e-7;
    for c in 0..2 {
        let (mut qp, mut qm, mut vp, mut vm) = (q, q, v, v);
        qp[c] += h;
        qm[c] -= h;
        vp[c] += h;
        vm[c] -= h;
        let nq: Vec<f64> = tau(&mut law, &m, &qp, &v)
            .iter()
            .zip(tau(&mut law, &m, &qm, &v))
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect();
        let nv: Vec<f64> = tau(&mut law, &m, &q, &vp)
            .iter()
            .zip(tau(&mut law, &m, &q, &vm))
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect();
        for r in 0..5 {
            assert!((dq[(r, c)] - nq[r]).abs() < 1e-5, "dq[{r},{c}]");
            assert!((dv[(r, c)] - nv[r]).abs() < 1e-5, "dv[{r},{c}]");
        }
    }
    assert_eq!((dq[(0, 0)], dv[(1, 1)]), (-100.0, -2.0));
    let links = vec![LinkState::default(); 3];
    let e = law.potential_energy(&cx, &links).unwrap();
    assert!((e - (0.5 * 100.0 * 0.2f64.powi(2) + 0.5 * 50.0 * 0.05f64.powi(2))).abs() < 1e-12);
}

#[test]
fn missing_bounds_are_the_models() {
    let m = model();
    let l = JointLimit::new(
        None,
        None,
        None,
        None,
        PerJoint::All(10.0),
        PerJoint::All(0.0),
    )
    .unwrap();
    // Without the model's bounds it cannot build, and says which argument is missing.
    let e = l.build(&m).err().unwrap().to_string();
    assert!(e.contains("lower"), "{e}");
    let filled = l
        .with_model_limits(&m, |link| [(-0.5, 0.5), (0.0, 0.3), (0.0, 0.0)][link])
        .unwrap();
    assert_eq!(filled.lower, Some(PerJoint::Each(vec![-0.5, 0.0])));
    assert_eq!(filled.upper, Some(PerJoint::Each(vec![0.5, 0.3])));
    filled.build(&m).unwrap();
}

#[test]
fn refusals_name_the_argument() {
    let k = || PerJoint::All(1.0);
    let e = JointLimit::new(
        None,
        None,
        Some(PerJoint::All(1.0)),
        Some(PerJoint::All(-1.0)),
        k(),
        k(),
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("lower") && e.to_string().contains("upper"),
        "{e}"
    );
    let e = JointLimit::new(None, None, None, None, PerJoint::All(-1.0), k()).unwrap_err();
    assert!(e.to_string().contains("stiffness"), "{e}");
    let e = JointLimit::new(None, None, None, None, k(), PerJoint::All(-1.0)).unwrap_err();
    assert!(e.to_string().contains("damping"), "{e}");
    let e = JointLimit::new(None, None, Some(PerJoint::All(f64::NAN)), None, k(), k()).unwrap_err();
    assert!(e.to_string().contains("lower"), "{e}");
    // Per joint, compared once the model is known.
    let l = JointLimit::new(
        None,
        None,
        Some(PerJoint::Each(vec![0.0, 2.0])),
        Some(PerJoint::All(1.0)),
        k(),
        k(),
    )
    .unwrap_err();
    assert!(l.to_string().contains("lower"), "{l}");
    let l = JointLimit::new(
        None,
        Some(vec![JointRef::Name("ball".into())]),
        Some(PerJoint::All(0.0)),
        Some(PerJoint::All(1.0)),
        k(),
        k(),
    )
    .unwrap();
    let e = l.build(&model()).err().unwrap().to_string();
    assert!(e.contains("joints") && e.contains("ball"), "{e}");
}
