//! The contact law against its closed forms (static Hunt–Crossley force, saturated Coulomb
//! friction), its Jacobians against central differences, its power against the potential's
//! rate (it never adds energy), and its refusals.
#![allow(clippy::needless_range_loop)]
use super::*;
use crate::effects::Effect;
use crate::joint::Joint;
use crate::model::body::RigidBody;
use crate::recursive::tangent::integrate;
use crate::support::spatial::Placement;
use nalgebra::DMatrix;

fn body(m: f64) -> RigidBody {
    RigidBody::new(m, Vec3::new(0.0, 0.0, -0.05), Mat3::identity() * 0.01).unwrap()
}

/// base (free flyer) → hip (revolute y) → shin (revolute y) → foot (quaternion ball).
fn leg() -> Model {
    let mut m = Model::new();
    let base = m
        .add_body(
            body(2.0),
            Joint::FreeFlyer,
            None,
            Placement::identity(),
            Some("base".into()),
            None,
        )
        .unwrap();
    let hip = m
        .add_body(
            body(0.5),
            Joint::revolute(Vec3::y()).unwrap(),
            Some(base),
            Placement::new(Mat3::identity(), Vec3::new(0.2, 0.1, 0.0)),
            Some("hip".into()),
            None,
        )
        .unwrap();
    let shin = m
        .add_body(
            body(0.3),
            Joint::revolute(Vec3::new(0.0, 0.6, 0.8)).unwrap(),
            Some(hip),
            Placement::new(Mat3::identity(), Vec3::new(0.0, 0.0, -0.2)),
            Some("shin".into()),
            None,
        )
        .unwrap();
    m.add_body(
        body(0.1),
        Joint::Spherical,
        Some(shin),
        Placement::new(Mat3::identity(), Vec3::new(0.0, 0.0, -0.2)),
        Some("foot".into()),
        None,
    )
    .unwrap();
    m
}

fn contact(points: &[(&str, [f64; 3])], mu: f64) -> GroundContact {
    contact_at(points, mu, 0.05)
}

fn contact_at(points: &[(&str, [f64; 3])], mu: f64, height: f64) -> GroundContact {
    GroundContact::new(
        None,
        points
            .iter()
            .map(|(b, p)| ContactPoint {
                body: JointRef::Name(b.to_string()),
                point: Vec3::from(*p),
                radius: 0.0,
            })
            .collect(),
        Vec3::new(0.1, -0.2, 1.0),
        height,
        Some(2.0e4),
        1.5,
        Some(300.0),
        mu,
        0.05,
    )
    .unwrap()
}

/// The contact with its plane raised so that every point is 3 mm or more into it at `q`.
fn sunk(m: &Model, points: &[(&str, [f64; 3])], mu: f64, q: &[f64]) -> GroundContactLaw {
    let mut law = contact_at(points, mu, 0.0).law(m).unwrap();
    let v = vec![0.0; m.nv];
    let mut top = f64::NEG_INFINITY;
    law.evaluate(m, q, &v, |_, p, _| top = top.max(law_normal().dot(p)));
    contact_at(points, mu, top + 3e-3).law(m).unwrap()
}

fn law_normal() -> Vec3 {
    Vec3::new(0.1, -0.2, 1.0).normalize()
}

/// A state moving in every direction.
fn state(m: &Model) -> (Vec<f64>, Vec<f64>) {
    let n = (0.1f64 * 0.1 + 0.2 * 0.2 + 0.05 * 0.05 + 1.0).sqrt();
    let mut q = vec![0.0; m.nq];
    q[..7].copy_from_slice(&[0.01, -0.02, 0.38, 0.1 / n, -0.2 / n, 0.05 / n, 1.0 / n]);
    q[7] = 0.3;
    q[8] = -0.5;
    let nb = (0.2f64 * 0.2 + 0.1 * 0.1 + 0.3 * 0.3 + 0.9 * 0.9).sqrt();
    q[9..13].copy_from_slice(&[0.2 / nb, 0.1 / nb, -0.3 / nb, 0.9 / nb]);
    let v = vec![
        0.03, -0.02, -0.04, 0.2, -0.1, 0.3, 0.25, -0.4, 0.5, -0.2, 0.1,
    ];
    assert_eq!(v.len(), m.nv);
    (q, v)
}

fn tau(law: &mut GroundContactLaw, m: &Model, q: &[f64], v: &[f64]) -> Vec<f64> {
    let mut t = vec![0.0; m.nv];
    let mut w = vec![Vec6::zeros(); m.links.len()];
    let cx = Context {
        model: m,
        t: 0.0,
        q,
        v,
    };
    assert!(!law.apply(&cx, &mut t, &mut w).unwrap());
    t
}

#[test]
fn static_force_is_k_delta_to_the_n_along_the_normal() {
    let c = GroundContact::new(
        None,
        vec![ContactPoint {
            body: JointRef::Name("foot".into()),
            point: Vec3::zeros(),
            radius: 0.0,
        }],
        Vec3::z(),
        0.0,
        Some(1.0e5),
        1.5,
        Some(50.0),
        0.8,
        1e-3,
    )
    .unwrap();
    let law = c.law(&leg()).unwrap();
    let d = 2.0e-3;
    let f = law.point_force(&Vec3::new(0.3, -0.1, -d), &Vec3::zeros(), 0.0);
    let expected = 1.0e5 * d.powf(1.5);
    assert!(
        (f.force.z - expected).abs() <= 1e-12 * expected,
        "{}",
        f.force.z
    );
    assert_eq!((f.force.x, f.force.y), (0.0, 0.0));
    assert_eq!(f.penetration, d);
    // Above the plane: nothing.
    let f = law.point_force(&Vec3::new(0.0, 0.0, 1e-9), &Vec3::new(0.0, 0.0, -5.0), 0.0);
    assert_eq!(f.force, Vec3::zeros());
    // Leaving fast: the damping would pull, the force stops at zero instead.
    let f = law.point_force(&Vec3::new(0.0, 0.0, -d), &Vec3::new(0.0, 0.0, 1.0e4), 0.0);
    assert_eq!(f.force, Vec3::zeros());
    // Sliding well above v_eps: |F_t| = μ F_n against the motion (tanh(100) = 1 to 1e-16).
    let f = law.point_force(&Vec3::new(0.0, 0.0, -d), &Vec3::new(0.06, -0.08, 0.0), 0.0);
    let ft = Vec3::new(f.force.x, f.force.y, 0.0);
    assert!((ft.norm() - 0.8 * f.normal).abs() <= 1e-12 * f.normal);
    assert!((ft.normalize() - Vec3::new(-0.6, 0.8, 0.0)).norm() < 1e-12);
}

#[test]
fn point_force_jacobians_are_its_central_differences() {
    let law = contact(&[("foot", [0.0; 3])], 0.7).law(&leg()).unwrap();
    let n = law.normal;
    // Inside, sliding slowly (the tanh's curved part), fast, and through v_t = 0's series.
    for (depth, vt) in [(3e-3, 0.02), (1e-2, 0.5), (2e-3, 1e-5), (4e-3, 0.0)] {
        let t1 = n.cross(&Vec3::x()).normalize();
        let p = n * (law.height - depth) + t1 * 0.3;
        let pd = t1 * vt + n.cross(&t1) * (0.3 * vt) - n * 0.01;
        let f = law.point_force(&p, &pd, 0.0);
        assert!(f.normal > 0.0);
        let h = 1e-7;
        for k in 0..3 {
            let mut e = Vec3::zeros();
            e[k] = h;
            let dp = (law.point_force(&(p + e), &pd, 0.0).force
                - law.point_force(&(p - e), &pd, 0.0).force)
                / (2.0 * h);
            let dv = (law.point_force(&p, &(pd + e), 0.0).force
                - law.point_force(&p, &(pd - e), 0.0).force)
                / (2.0 * h);
            let scale = f.force.norm() / depth + f.normal * 0.7 / 0.05;
            assert!(
                (f.dp.column(k) - dp).norm() <= 1e-6 * scale,
                "dp {k} at {depth} {vt}: {} vs {dp}",
                f.dp.column(k)
            );
            assert!(
                (f.dv.column(k) - dv).norm() <= 1e-6 * scale,
                "dv {k} at {depth} {vt}: {} vs {dv}",
                f.dv.column(k)
            );
        }
    }
}

#[test]
fn generalized_force_derivatives_are_its_central_differences() {
    let m = leg();
    let points = [
        ("foot", [0.02, 0.01, -0.03]),
        ("shin", [0.0, 0.02, -0.22]),
        ("base", [0.1, -0.1, -0.3]),
    ];
    let (q, v) = state(&m);
    let mut law = sunk(&m, &points, 0.6, &q);
    // Every point is in contact at this state (else the test checks nothing).
    law.evaluate(&m, &q, &v, |k, _, pf| {
        assert!(
            pf.normal > 0.0,
            "point {k} is not in contact: {}",
            pf.penetration
        )
    });
    let (mut dq, mut dv) = (DMatrix::zeros(m.nv, m.nv), DMatrix::zeros(m.nv, m.nv));
    let cx = Context {
        model: &m,
        t: 0.0,
        q: &q,
        v: &v,
    };
    assert!(law.add_derivatives(&cx, &mut dq, &mut dv).unwrap());
    let h = 1e-6;
    let (mut qp, mut qm) = (q.clone(), q.clone());
    let mut worst = 0.0f64;
    let scale = tau(&mut law, &m, &q, &v)
        .iter()
        .fold(0.0f64, |a, x| a.max(x.abs()));
    for c in 0..m.nv {
        let mut d = vec![0.0; m.nv];
        d[c] = h;
        integrate(&m, &q, &d, &mut qp);
        d[c] = -h;
        integrate(&m, &q, &d, &mut qm);
        let (tp, tm) = (tau(&mut law, &m, &qp, &v), tau(&mut law, &m, &qm, &v));
        let (mut vp, mut vm) = (v.clone(), v.clone());
        vp[c] += h;
        vm[c] -= h;
        let (sp, sm) = (tau(&mut law, &m, &q, &vp), tau(&mut law, &m, &q, &vm));
        for r in 0..m.nv {
            let nq = (tp[r] - tm[r]) / (2.0 * h);
            let nv = (sp[r] - sm[r]) / (2.0 * h);
            worst = worst
                .max((dq[(r, c)] - nq).abs())
                .max((dv[(r, c)] - nv).abs());
            assert!(
                (dq[(r, c)] - nq).abs() <= 1e-5 * scale / 0.01,
                "dq[{r},{c}] {} vs {nq}",
                dq[(r, c)]
            );
            assert!(
                (dv[(r, c)] - nv).abs() <= 1e-5 * scale / 0.01,
                "dv[{r},{c}] {} vs {nv}",
                dv[(r, c)]
            );
        }
    }
    assert!(worst > 0.0);
}

#[test]
fn contact_never_adds_energy() {
    // P = f · ṗ ≤ −dV/dt = −k δᵉ δ̇ at any state: damping and friction only take energy.
    let law = contact(&[("foot", [0.0; 3])], 0.9).law(&leg()).unwrap();
    let n = law.normal;
    let (mut worst, mut least) = (f64::NEG_INFINITY, 0.0f64);
    let mut x = 0.123456789f64;
    let mut rand = || {
        x = (x * 9301.0 + 0.49297).fract();
        2.0 * x - 1.0
    };
    for _ in 0..2000 {
        let p = Vec3::new(rand(), rand(), law.height / n.z + 0.01 * rand());
        let pd = Vec3::new(rand(), rand(), rand()) * (0.5 * (1.0 + rand()));
        let f = law.point_force(&p, &pd, 0.0);
        let delta = law.height - n.dot(&p);
        let rate = if delta > 0.0 {
            law.k * delta.powf(law.e) * (-n.dot(&pd))
        } else {
            0.0
        };
        let excess = f.force.dot(&pd) + rate;
        assert!(
            excess <= 1e-12 * (1.0 + f.force.norm()),
            "power above −dV/dt by {excess}"
        );
        worst = worst.max(excess);
        least = least.min(excess);
    }
    assert!(
        least < -1e-3,
        "no state dissipated anything ({worst}, {least})"
    );
}

#[test]
fn potential_is_the_elastic_work() {
    // −dV/dδ = k δᵉ, the static force along the normal.
    let m = leg();
    let (q, _) = state(&m);
    let law = sunk(&m, &[("foot", [0.0; 3])], 0.0, &q);
    let mut links = vec![LinkState::default(); m.links.len()];
    crate::kinematics::positions(&m, &q, &mut links);
    let cx = Context {
        model: &m,
        t: 0.0,
        q: &q,
        v: &[],
    };
    let v0 = law.potential_energy(&cx, &links).unwrap();
    let delta = law.height - law.normal.dot(&law.set.position_from(&links, 0));
    assert!(delta > 0.0);
    let expected = law.k * delta.powf(law.e + 1.0) / (law.e + 1.0);
    assert!((v0 - expected).abs() <= 1e-12 * expected);
}

#[test]
fn refusals_name_the_argument() {
    let p = || {
        vec![ContactPoint {
            body: JointRef::Name("foot".into()),
            point: Vec3::zeros(),
            radius: 0.0,
        }]
    };
    let make = |k: f64, e: f64, c: f64, mu: f64, ve: f64, n: Vec3| {
        GroundContact::new(None, p(), n, 0.0, Some(k), e, Some(c), mu, ve)
            .unwrap_err()
            .to_string()
    };
    let z = Vec3::z();
    assert!(make(-1.0, 1.5, 1.0, 0.5, 1e-3, z).contains("stiffness"));
    assert!(make(1.0, 1.5, -1.0, 0.5, 1e-3, z).contains("damping"));
    assert!(make(1.0, 1.5, 1.0, -0.5, 1e-3, z).contains("friction"));
    assert!(make(1.0, 0.5, 1.0, 0.5, 1e-3, z).contains("exponent"));
    assert!(make(1.0, 1.5, 1.0, 0.5, 0.0, z).contains("v_eps"));
    assert!(make(1.0, 1.5, 1.0, 0.5, 1e-3, Vec3::zeros()).contains("normal"));
    let e =
        GroundContact::new(None, vec![], z, 0.0, Some(1.0), 1.5, Some(1.0), 0.5, 1e-3).unwrap_err();
    assert!(e.to_string().contains("points"));
    let bad = GroundContact::new(
        None,
        vec![ContactPoint {
            body: JointRef::Name("toe".into()),
            point: Vec3::zeros(),
            radius: 0.0,
        }],
        z,
        0.0,
        Some(1.0),
        1.5,
        Some(1.0),
        0.5,
        1e-3,
    )
    .unwrap();
    let e = bad.law(&leg()).err().unwrap().to_string();
    assert!(e.contains("points[0]") && e.contains("toe"), "{e}");
}

#[test]
fn scene_file_table_parses_and_refuses() {
    let t: toml::Table = toml::from_str(
        r#"type = "ground_contact"
points = [["foot", [0, 0, -0.01]], [2, [0.1, 0, 0]]]
stiffness = 1e5
damping = 100
friction = 0.8"#,
    )
    .unwrap();
    let Effect::GroundContact(c) = Effect::from_toml(&t).unwrap() else {
        panic!("not a contact")
    };
    assert_eq!(c.points.len(), 2);
    assert_eq!(c.points[1].body, JointRef::Index(2));
    assert_eq!(
        (c.exponent, c.v_eps, c.normal),
        (DEFAULT_EXPONENT, DEFAULT_V_EPS, Vec3::z())
    );
    let t: toml::Table = toml::from_str(
        r#"type = "ground_contact"
points = [["foot", [0, 0]]]
stiffness = 1e5
damping = 100
friction = 0.8"#,
    )
    .unwrap();
    assert!(Effect::from_toml(&t)
        .unwrap_err()
        .to_string()
        .contains("points[0]"));
}

#[test]
fn defaults_sink_one_millimetre_with_critical_damping() {
    let m = leg();
    let pts = ["base", "hip", "shin", "foot"].map(|b| ContactPoint {
        body: JointRef::Name(b.into()),
        point: Vec3::zeros(),
        radius: 0.01,
    });
    let make = |k: Option<f64>, c: Option<f64>, e: f64| {
        GroundContact::new(None, pts.to_vec(), Vec3::z(), 0.0, k, e, c, 0.5, 1e-3).unwrap()
    };
    let (mass, g, n) = (2.9, 9.81, 4.0); // leg(): 2 + 0.5 + 0.3 + 0.1 kg
    for e in [1.0, 1.5, 2.0] {
        let (k, c) = make(None, None, e).resolved(&m).unwrap();
        // The law's static force at 1 mm carries a quarter of the weight each.
        let law = make(None, None, e).law(&m).unwrap();
        let down = law.point_force(&Vec3::new(0.0, 0.0, 0.01 - 1e-3), &Vec3::zeros(), 0.01);
        assert!(
            (down.normal - mass * g / n).abs() <= 1e-12 * mass * g,
            "{e}"
        );
        // Linearised there (stiffness −∂F/∂z, damping −∂F/∂ż) on a quarter of the mass:
        // damping ratio 1.
        let (k_lin, c_lin) = (-down.dp[(2, 2)], -down.dv[(2, 2)]);
        let zeta = c_lin / (2.0 * (k_lin * mass / n).sqrt());
        assert!((zeta - 1.0).abs() < 1e-12, "e = {e}: ζ = {zeta}");
        assert!((k_lin - e * mass * g / n / 1e-3).abs() < 1e-9 * k_lin);
        // Given values are kept; a given stiffness sets the sink the damping is critical at.
        assert_eq!(
            make(Some(7.0), Some(0.0), e).resolved(&m).unwrap(),
            (7.0, 0.0)
        );
        let (k2, c2) = make(Some(k * 8.0), None, e).resolved(&m).unwrap();
        assert_eq!(k2, k * 8.0);
        let sink = (mass * g / n / k2).powf(1.0 / e);
        let at = make(Some(k2), Some(c2), e).law(&m).unwrap();
        let f = at.point_force(&Vec3::new(0.0, 0.0, 0.01 - sink), &Vec3::zeros(), 0.01);
        let zeta = -f.dv[(2, 2)] / (2.0 * (-f.dp[(2, 2)] * mass / n).sqrt());
        assert!((zeta - 1.0).abs() < 1e-9, "e = {e}: ζ = {zeta}");
        assert!(c > 0.0);
        // A scene keeps the values (what its effects' repr shows).
        let filled = make(None, None, e).with_model_defaults(&m).unwrap();
        assert_eq!((filled.stiffness, filled.damping), (Some(k), Some(c)));
        assert!(filled.repr().contains(&format!("stiffness={k}")));
        assert!(make(None, None, e).repr().contains("stiffness=None"));
    }
    // No mass, no default: the error names the argument.
    let massless = Model::new();
    let one = GroundContact::new(
        None,
        pts[..1].to_vec(),
        Vec3::z(),
        0.0,
        None,
        1.5,
        Some(1.0),
        0.5,
        1e-3,
    );
    let e = one.unwrap().resolved(&massless).unwrap_err().to_string();
    assert!(
        e.starts_with("stiffness:") && e.contains("total mass 0"),
        "{e}"
    );
    // Scene files may leave them out.
    let t: toml::Table = toml::from_str(
        "type = \"ground_contact\"\npoints = [[\"foot\", [0, 0, 0]]]\nfriction = 0.8",
    )
    .unwrap();
    let Effect::GroundContact(c) = Effect::from_toml(&t).unwrap() else {
        panic!("not a contact")
    };
    assert_eq!((c.stiffness, c.damping), (None, None));
}
