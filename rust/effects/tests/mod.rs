//! Effects against things they do not compute themselves: potentials against their forces
//! (finite differences), external forces against virtual work on the point's world path,
//! and the right-hand side's composition against the sum of per-effect forces.
#![allow(clippy::needless_range_loop)]
use super::*;
use crate::joint::rot_z;
use crate::joint::Joint;
use crate::kinematics;
use crate::model::body::RigidBody;
use crate::recursive::{self, Data};
use crate::simulate::Dynamics;
use crate::support::spatial::{Mat3, Placement};

fn body(m: f64, c: [f64; 3], d: [f64; 3]) -> RigidBody {
    RigidBody::new(m, Vec3::from(c), Mat3::from_diagonal(&Vec3::from(d))).unwrap()
}

/// base (revolute z) → ball (quaternion) → plate (welded, rotated) → slider (prismatic x).
fn model() -> Model {
    let mut m = Model::new();
    let base = m
        .add_body(
            body(1.0, [0.1, 0.0, 0.0], [0.01, 0.02, 0.02]),
            Joint::revolute(Vec3::z()).unwrap(),
            None,
            Placement::identity(),
            Some("base".into()),
            None,
        )
        .unwrap();
    let ball = m
        .add_body(
            body(0.8, [0.0, 0.1, -0.05], [0.01, 0.015, 0.02]),
            Joint::Spherical,
            Some(base),
            Placement::new(Mat3::identity(), Vec3::new(0.3, 0.0, 0.0)),
            Some("ball".into()),
            None,
        )
        .unwrap();
    let plate = m
        .add_body(
            body(0.5, [0.05, 0.0, 0.0], [0.002, 0.003, 0.004]),
            Joint::Fixed,
            Some(ball),
            Placement::new(rot_z(0.7), Vec3::new(0.1, 0.2, 0.0)),
            Some("plate".into()),
            None,
        )
        .unwrap();
    m.add_body(
        body(0.3, [0.02, 0.0, 0.01], [0.001, 0.001, 0.001]),
        Joint::prismatic(Vec3::new(1.0, 0.0, 0.5)).unwrap(),
        Some(plate),
        Placement::new(Mat3::identity(), Vec3::new(0.0, 0.0, 0.2)),
        Some("slider".into()),
        None,
    )
    .unwrap();
    m
}

fn state(m: &Model) -> (Vec<f64>, Vec<f64>) {
    let n = (0.2f64 * 0.2 + 0.4 * 0.4 + 0.1 * 0.1 + 0.88 * 0.88).sqrt();
    let q = vec![0.4, 0.2 / n, -0.4 / n, 0.1 / n, 0.88 / n, 0.15];
    let v = vec![0.7, -0.3, 1.1, 0.4, -0.6];
    assert_eq!((q.len(), v.len()), (m.nq, m.nv));
    (q, v)
}

/// `q ⊕ h e_k`: a step of size h along speed k (body-frame rotation for quaternions).
fn step(m: &Model, q: &[f64], k: usize, h: f64) -> Vec<f64> {
    let mut out = q.to_vec();
    for l in &m.links {
        let (iq, iv, nv) = (l.q_index, l.v_index, l.joint.nv());
        if !(iv..iv + nv).contains(&k) {
            continue;
        }
        if let Joint::Spherical = l.joint {
            let mut axis = [0.0; 3];
            axis[k - iv] = 1.0;
            let (s, c) = (h / 2.0).sin_cos();
            let e = [axis[0] * s, axis[1] * s, axis[2] * s, c];
            let a = &q[iq..iq + 4];
            // a ⊗ e
            out[iq] = a[3] * e[0] + e[3] * a[0] + (a[1] * e[2] - a[2] * e[1]);
            out[iq + 1] = a[3] * e[1] + e[3] * a[1] + (a[2] * e[0] - a[0] * e[2]);
            out[iq + 2] = a[3] * e[2] + e[3] * a[2] + (a[0] * e[1] - a[1] * e[0]);
            out[iq + 3] = a[3] * e[3] - (a[0] * e[0] + a[1] * e[1] + a[2] * e[2]);
        } else {
            out[iq + (k - iv)] += h;
        }
    }
    out
}

fn effects(m: &Model, specs: &[Effect]) -> Effects {
    Effects::new(m, specs, Disabled::none(), "effects").unwrap()
}

fn forces(m: &Model, e: &mut Effects, t: f64, q: &[f64], v: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; e.len() * m.nv];
    let cx = Context { model: m, t, q, v };
    Probe::new(m).forces(e, &cx, &mut out).unwrap();
    out
}

fn potential(m: &Model, e: &Effects, q: &[f64]) -> f64 {
    let mut links = vec![crate::kinematics::LinkState::default(); m.links.len()];
    kinematics::positions(m, q, &mut links);
    let cx = Context {
        model: m,
        t: 0.0,
        q,
        v: &[],
    };
    e.potential_energy(&cx, &links)
}

#[test]
fn potentials_are_the_forces_of_springs_and_gravity() {
    let m = model();
    let (q, v) = state(&m);
    let specs = [
        Effect::gravity(Vec3::new(0.3, -1.0, -9.81)).unwrap(),
        Effect::Spring(
            Spring::new(
                None,
                None,
                PerJoint::Each(vec![3.0, 7.0, 11.0]),
                Some(PerJoint::Each(vec![0.1, 0.1, 0.2, -0.3, 0.9, -0.05])),
            )
            .unwrap(),
        ),
    ];
    let mut e = effects(&m, &specs);
    let f = forces(&m, &mut e, 0.0, &q, &v);
    let total: Vec<f64> = (0..m.nv).map(|k| f[k] + f[m.nv + k]).collect();
    let h = 1e-6;
    for k in 0..m.nv {
        let dv = (potential(&m, &e, &step(&m, &q, k, h)) - potential(&m, &e, &step(&m, &q, k, -h)))
            / (2.0 * h);
        assert!(
            (dv + total[k]).abs() < 1e-7,
            "dof {k}: dV = {dv}, tau = {}",
            total[k]
        );
    }
    // The gravity row is Nᵀ f^G from the explicit DeNOC path.
    let tg = crate::dynamics::denoc::gravity_forces(&m, &q, &Vec3::new(0.3, -1.0, -9.81)).unwrap();
    for k in 0..m.nv {
        assert!((f[k] - tg[k]).abs() < 1e-12);
    }
}

#[test]
fn quaternion_spring_is_minus_k_theta() {
    let r = [0.0, 0.0, 0.0, 1.0];
    let a = 0.8f64;
    let q = [0.0, (a / 2.0).sin(), 0.0, (a / 2.0).cos()];
    let th = spring::relative_rotation_vector(&r, &q);
    assert!((th[1] - a).abs() < 1e-15 && th[0] == 0.0 && th[2] == 0.0);
    // Past π the short way round is taken.
    let b = 3.5f64;
    let q = [(b / 2.0).sin(), 0.0, 0.0, (b / 2.0).cos()];
    let th = spring::relative_rotation_vector(&r, &q);
    assert!(
        (th[0] - (b - 2.0 * std::f64::consts::PI)).abs() < 1e-14,
        "{th:?}"
    );
}

/// World position and orientation of body `b`'s point `p` at `q`.
fn point(m: &Model, q: &[f64], b: usize, p: &Vec3) -> (Vec3, Mat3) {
    let mut links = vec![crate::kinematics::LinkState::default(); m.links.len()];
    kinematics::positions(m, q, &mut links);
    let pl = kinematics::body_placement(m, &links, b);
    (pl.act_point(p), pl.rotation)
}

#[test]
fn external_force_is_virtual_work_on_the_point() {
    let m = model();
    let (q, v) = state(&m);
    let p = Vec3::new(0.05, -0.1, 0.2);
    let f_w = Vec3::new(1.5, -2.0, 0.7);
    let m_w = Vec3::new(-0.3, 0.4, 0.25);
    let f_b = Vec3::new(0.2, 1.0, -0.4);
    for (body, frame) in [
        ("plate", Frame::World),
        ("plate", Frame::Body),
        ("slider", Frame::World),
        ("ball", Frame::Body),
    ] {
        let b = m.body_index(body).unwrap();
        let (force, moment) = if frame == Frame::World {
            (f_w, m_w)
        } else {
            (f_b, m_w)
        };
        let spec = Effect::External(
            External::constant(None, JointRef::Name(body.into()), p, force, moment, frame).unwrap(),
        );
        let mut e = effects(&m, &[spec]);
        let tau = forces(&m, &mut e, 0.0, &q, &v);
        let (_, rb) = point(&m, &q, b, &p);
        let (fw, mw) = if frame == Frame::World {
            (force, moment)
        } else {
            (rb * force, rb * moment)
        };
        let h = 1e-6;
        for k in 0..m.nv {
            let (xp, rp) = point(&m, &step(&m, &q, k, h), b, &p);
            let (xm, rm) = point(&m, &step(&m, &q, k, -h), b, &p);
            let dx = (xp - xm) / (2.0 * h);
            let w = (rp - rm) / (2.0 * h) * rb.transpose();
            let omega = Vec3::new(w[(2, 1)], w[(0, 2)], w[(1, 0)]);
            let want = fw.dot(&dx) + mw.dot(&omega);
            assert!(
                (tau[k] - want).abs() < 1e-8,
                "{body} {frame:?} dof {k}: {} vs {want}",
                tau[k]
            );
        }
    }
}

#[test]
fn rhs_composes_the_sum_of_the_effects() {
    let m = model();
    let (q, v) = state(&m);
    let time = vec![0.0, 0.5, 2.0];
    let specs = vec![
        Effect::gravity(Vec3::new(0.0, 0.0, -9.81)).unwrap(),
        Effect::Spring(
            Spring::new(
                None,
                Some(vec![JointRef::Name("slider".into())]),
                PerJoint::All(40.0),
                Some(PerJoint::All(0.05)),
            )
            .unwrap(),
        ),
        Effect::Damper(Damper::new(None, None, PerJoint::All(0.3)).unwrap()),
        Effect::Friction(
            Friction::new(
                Some("stiction".into()),
                None,
                PerJoint::Each(vec![0.1, 0.2, 0.3]),
                Some(0.05),
            )
            .unwrap(),
        ),
        Effect::Torque(
            Torque::constant(
                None,
                Some(vec![JointRef::Index(1)]),
                PerJoint::Each(vec![0.1, -0.2, 0.3]),
            )
            .unwrap(),
        ),
        Effect::Torque(
            Torque::tabulated(
                None,
                Some(vec![JointRef::Name("base".into())]),
                Table::new(
                    time.clone(),
                    torque::column(vec![0.0, 1.0, -1.0]),
                    "time",
                    "values",
                )
                .unwrap(),
            )
            .unwrap(),
        ),
        Effect::Torque(
            Torque::pd(
                None,
                Some(vec![
                    JointRef::Name("base".into()),
                    JointRef::Name("slider".into()),
                ]),
                PerJoint::All(5.0),
                PerJoint::Each(vec![0.5, 0.1]),
                Table::new(
                    time.clone(),
                    Matrix {
                        values: vec![0.0, 0.0, 1.0, 0.1, 1.0, 0.2],
                        rows: 3,
                        cols: 2,
                        one_d: false,
                    },
                    "time",
                    "reference",
                )
                .unwrap(),
            )
            .unwrap(),
        ),
        Effect::External(
            External::constant(
                None,
                JointRef::Name("plate".into()),
                Vec3::new(0.1, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 2.0),
                Vec3::zeros(),
                Frame::Body,
            )
            .unwrap(),
        ),
    ];
    let mut sys = Dynamics::try_new(&m, &specs, Disabled::none()).unwrap();
    assert_eq!(
        sys.effects.labels(),
        [
            "gravity",
            "springs",
            "dampers",
            "stiction",
            "torques",
            "torques_2",
            "torques_3",
            "external"
        ]
    );
    let t = 0.3;
    let mut a = vec![0.0; m.nv];
    sys.accelerations(t, &q, &v, &mut a).unwrap();
    let mut f = vec![0.0; specs.len() * m.nv];
    sys.effect_forces(t, &q, &v, &mut f).unwrap();
    let total: Vec<f64> = (0..m.nv)
        .map(|k| (0..specs.len()).map(|e| f[e * m.nv + k]).sum())
        .collect();
    let mut data = Data::new(&m);
    let mut b = vec![0.0; m.nv];
    recursive::forward_dynamics(&m, &mut data, &q, &v, &total, &Vec3::zeros(), None, &mut b)
        .unwrap();
    for k in 0..m.nv {
        assert!(
            (a[k] - b[k]).abs() < 1e-10 * (1.0 + b[k].abs()),
            "{k}: {a:?} vs {b:?}"
        );
    }
    // Individual laws, by hand.
    let row = |e: usize| &f[e * m.nv..(e + 1) * m.nv];
    let close = |x: &[f64], y: &[f64]| x.iter().zip(y).all(|(a, b)| (a - b).abs() < 1e-14);
    assert!(close(row(1), &[0.0, 0.0, 0.0, 0.0, -40.0 * (0.15 - 0.05)]));
    assert!(close(
        row(2),
        &v.iter().map(|x| -0.3 * x).collect::<Vec<_>>()
    ));
    let w = (v[1] * v[1] + v[2] * v[2] + v[3] * v[3]).sqrt();
    let fb = 0.2 * (w / 0.05).tanh() / w;
    assert!(close(
        row(3),
        &[
            -0.1 * (v[0] / 0.05).tanh(),
            -fb * v[1],
            -fb * v[2],
            -fb * v[3],
            -0.3 * (v[4] / 0.05).tanh()
        ]
    ));
    assert!(close(row(4), &[0.0, 0.1, -0.2, 0.3, 0.0]));
    assert!(close(row(5), &[0.6, 0.0, 0.0, 0.0, 0.0]));
    // PD at t = 0.3: reference (0.6, 0.06), slope (2, 0.2).
    assert!(close(
        row(6),
        &[
            5.0 * (0.6 - q[0]) + 0.5 * (2.0 - v[0]),
            0.0,
            0.0,
            0.0,
            5.0 * (0.06 - q[5]) + 0.1 * (0.2 - v[4])
        ]
    ));
}

#[test]
fn disabled_families_are_left_out() {
    let m = model();
    let specs = vec![
        Effect::gravity(Vec3::new(0.0, 0.0, -9.81)).unwrap(),
        Effect::Spring(
            Spring::new(
                None,
                Some(vec![JointRef::Index(0)]),
                PerJoint::All(1.0),
                None,
            )
            .unwrap(),
        ),
        Effect::Damper(Damper::new(None, None, PerJoint::All(0.3)).unwrap()),
    ];
    let d = Disabled::parse(&["gravity", "spring"], "disable").unwrap();
    let e = Effects::new(&m, &specs, d, "effects").unwrap();
    assert_eq!(e.labels(), ["dampers"]);
    assert_eq!(e.gravity, Vec3::zeros());
    assert_eq!(d.names(), ["gravity", "springs"]);
    let err = Disabled::parse(&["gravity", "sprigs"], "disable")
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("disable[1]: expected one of"), "{err}");
    // A free scene does nothing in the right-hand side.
    let mut none = Effects::none();
    let (q, v) = state(&m);
    let mut tau = vec![7.0; m.nv];
    let cx = Context {
        model: &m,
        t: 0.0,
        q: &q,
        v: &v,
    };
    assert!(!none.apply(&cx, &mut tau, &mut []).unwrap());
    assert_eq!(tau, vec![7.0; m.nv]);
}

#[test]
fn resolution_errors_name_the_field() {
    let m = model();
    let bad = |spec: Effect| {
        Effects::new(&m, &[spec], Disabled::none(), "effects")
            .err()
            .unwrap()
            .to_string()
    };
    let e = bad(Effect::Spring(
        Spring::new(
            None,
            Some(vec![JointRef::Name("elbow".into())]),
            PerJoint::All(1.0),
            None,
        )
        .unwrap(),
    ));
    assert!(
        e.starts_with("effects[0].joints:") && e.contains("'elbow'") && e.contains("'slider'"),
        "{e}"
    );
    let e = bad(Effect::Damper(
        Damper::new(
            None,
            Some(vec![JointRef::Name("plate".into())]),
            PerJoint::All(1.0),
        )
        .unwrap(),
    ));
    assert!(
        e.starts_with("effects[0].joints:") && e.contains("Fixed"),
        "{e}"
    );
    let e = bad(Effect::Damper(
        Damper::new(None, None, PerJoint::Each(vec![1.0, 2.0])).unwrap(),
    ));
    assert!(
        e.starts_with("effects[0].damping:") && e.contains("3 values"),
        "{e}"
    );
    let e = bad(Effect::Torque(
        Torque::tabulated(
            None,
            None,
            Table::new(
                vec![0.0, 1.0],
                torque::column(vec![0.0, 1.0]),
                "time",
                "values",
            )
            .unwrap(),
        )
        .unwrap(),
    ));
    assert!(
        e.starts_with("effects[0].values:") && e.contains("(2, 5)") && e.contains("(2,)"),
        "{e}"
    );
    let e = bad(Effect::Torque(
        Torque::pd(
            None,
            Some(vec![JointRef::Index(1)]),
            PerJoint::All(1.0),
            PerJoint::All(1.0),
            Table::new(vec![0.0], torque::column(vec![0.0]), "time", "reference").unwrap(),
        )
        .unwrap(),
    ));
    assert!(
        e.starts_with("effects[0].joints:") && e.contains("Spherical"),
        "{e}"
    );
    let e = bad(Effect::External(
        External::constant(
            None,
            JointRef::Index(9),
            Vec3::zeros(),
            Vec3::x(),
            Vec3::zeros(),
            Frame::World,
        )
        .unwrap(),
    ));
    assert!(
        e.starts_with("effects[0].body:") && e.contains("0..4"),
        "{e}"
    );
    assert!(Spring::new(None, None, PerJoint::All(-1.0), None)
        .unwrap_err()
        .to_string()
        .starts_with("stiffness:"));
    assert!(Friction::new(None, None, PerJoint::All(1.0), Some(0.0))
        .unwrap_err()
        .to_string()
        .starts_with("v_eps:"));
    // Names: unique, not reserved.
    let named =
        |n: &str| Effect::Damper(Damper::new(Some(n.into()), None, PerJoint::All(1.0)).unwrap());
    let e = Effects::new(&m, &[named("d"), named("d")], Disabled::none(), "effects")
        .err()
        .unwrap()
        .to_string();
    assert!(e.starts_with("effects[1].name:"), "{e}");
    let e = Effects::new(&m, &[named("total")], Disabled::none(), "effects")
        .err()
        .unwrap()
        .to_string();
    assert!(e.starts_with("effects[0].name:"), "{e}");
}

#[test]
fn toml_tables_parse_and_refuse() {
    let parse = |s: &str| Effect::from_toml(&s.parse::<toml::Table>().unwrap());
    let e = parse(
        "type = \"spring\"\njoints = [\"a\", 2]\nstiffness = [1, 2.5]\nrest = 0.1\nname = \"s\"",
    )
    .unwrap();
    assert_eq!(
        e,
        Effect::Spring(Spring {
            name: Some("s".into()),
            joints: Some(vec![JointRef::Name("a".into()), JointRef::Index(2)]),
            stiffness: PerJoint::Each(vec![1.0, 2.5]),
            rest: PerJoint::All(0.1),
        })
    );
    let e = parse(
        "type = \"tabulated_torque\"\njoints = \"a\"\ntime = [0, 1]\nvalues = [[1, 2], [3, 4]]",
    )
    .unwrap();
    let Effect::Torque(Torque {
        law: TorqueLaw::Tabulated(t),
        ..
    }) = e
    else {
        panic!()
    };
    assert_eq!((t.len(), t.cols()), (2, 2));
    let e =
        parse("type = \"external\"\nbody = \"a\"\ntime = [0, 1]\nforce = [[1, 2, 3], [3, 4, 5]]")
            .unwrap();
    assert!(matches!(
        e,
        Effect::External(External {
            load: ExternalLoad::Tabulated(_),
            ..
        })
    ));
    for (text, key) in [
        ("type = \"spring\"\nstifness = 1", "stifness"),
        ("type = \"spring\"", "stiffness"),
        ("type = \"spring\"\nstiffness = -2", "stiffness"),
        ("type = \"spring\"\nstiffness = \"x\"", "stiffness"),
        ("type = \"springs\"", "type"),
        ("g = [0, 0, 1]", "type"),
        ("type = \"damper\"\ndamping = 1\njoints = [-1]", "joints"),
        (
            "type = \"tabulated_torque\"\ntime = [0, 2, 1]\nvalues = [1, 2, 3]",
            "time",
        ),
        (
            "type = \"tabulated_torque\"\ntime = [0, 1]\nvalues = [1, 2, 3]",
            "values",
        ),
        (
            "type = \"tabulated_torque\"\ntime = [0, 1]\nvalues = [[1, 2], [3]]",
            "values",
        ),
        (
            "type = \"pd_torque\"\nkp = 1\nkd = 1\ntime = [0]\nreference = [[0]]\nfoo = 2",
            "foo",
        ),
        ("type = \"external\"\nbody = \"a\"\nforce = [1, 2]", "force"),
        (
            "type = \"external\"\nbody = \"a\"\ntime = [0, 1]\nforce = [1, 2]",
            "force",
        ),
        ("type = \"external\"\nforce = [1, 2, 3]", "body"),
        (
            "type = \"external\"\nbody = \"a\"\nforce = [1, 2, 3]\nframe = \"link\"",
            "frame",
        ),
        ("type = \"friction\"\nfriction = 1\nv_eps = 0", "v_eps"),
    ] {
        let err = parse(text).unwrap_err();
        let Error::InvalidArgument { arg, .. } = &err else {
            panic!("{err}")
        };
        assert_eq!(arg, key, "{text}: {err}");
    }
}

/// The lists of valid names in error messages come from the registries (`TOML_TYPES`,
/// `Kind::ALL`); these are the messages as they were written out by hand before.
#[test]
fn error_messages_list_every_type_and_family() {
    let parse = |s: &str| Effect::from_toml(&s.parse::<toml::Table>().unwrap());
    // The test build registers the guide's toy effect too (`toy_spring.rs`), last.
    let types = "one of \"gravity\", \"spring\", \"damper\", \"friction\", \"torque\", \
\"tabulated_torque\", \"pd_torque\", \"external\", \"point_spring\", \"ground_contact\", \"joint_limit\", \
\"toy_spring\"";
    for (text, got) in [
        ("type = \"springs\"", "\"springs\""),
        ("g = [0, 0, 1]", "nothing"),
    ] {
        let Error::InvalidArgument {
            arg,
            expected,
            got: g,
        } = parse(text).unwrap_err()
        else {
            panic!()
        };
        assert_eq!(
            (arg.as_str(), expected.as_str(), g.as_str()),
            ("type", types, got)
        );
    }
    let err = Disabled::parse(&["sprigs"], "disable").unwrap_err();
    let Error::InvalidArgument { expected, .. } = err else {
        panic!()
    };
    assert_eq!(
        expected,
        "one of \"gravity\", \"springs\", \"dampers\", \"friction\", \"torques\", \"external\", \"contact\", \"limits\""
    );
    for (name, kind) in [
        ("spring", Kind::Springs),
        ("springs", Kind::Springs),
        ("damper", Kind::Dampers),
        ("torque", Kind::Torques),
        ("friction", Kind::Friction),
        ("external", Kind::External),
        ("contact", Kind::Contact),
        ("limit", Kind::Limits),
        ("limits", Kind::Limits),
        ("gravity", Kind::Gravity),
    ] {
        assert_eq!(Kind::parse(name), Some(kind), "{name}");
    }
    assert_eq!(Kind::parse("frictions"), None);
}

fn point_spring(
    a: Option<&str>,
    pa: [f64; 3],
    b: Option<&str>,
    pb: [f64; 3],
    k: f64,
    rest: f64,
    c: f64,
) -> Effect {
    let r = |x: Option<&str>| x.map(|n| JointRef::Name(n.into()));
    Effect::PointSpring(
        PointSpring::new(None, r(a), Vec3::from(pa), r(b), Vec3::from(pb), k, rest, c).unwrap(),
    )
}

/// World position of point `p` of body `b` (`None`: the world) at `q`, by the full
/// kinematics (not the law's own path walk).
fn world_point(m: &Model, q: &[f64], b: Option<&str>, p: [f64; 3]) -> Vec3 {
    match b {
        None => Vec3::from(p),
        Some(n) => point(m, q, m.body_index(n).unwrap(), &Vec3::from(p)).0,
    }
}

#[test]
fn point_springs_forces_are_minus_the_gradient_of_their_potential() {
    let m = model();
    let (q, v) = state(&m);
    // Ends on a prismatic, a welded and a quaternion body, on the world, nested (slider
    // below ball), with and without rest length.
    let specs = [
        point_spring(
            None,
            [0.3, -0.2, 0.4],
            Some("slider"),
            [0.05, 0.1, -0.02],
            40.0,
            0.0,
            0.0,
        ),
        point_spring(
            Some("plate"),
            [0.1, 0.0, 0.05],
            Some("base"),
            [-0.1, 0.2, 0.0],
            25.0,
            0.07,
            0.0,
        ),
        point_spring(
            Some("ball"),
            [0.0, 0.1, 0.2],
            Some("slider"),
            [0.02, 0.0, 0.0],
            13.0,
            0.3,
            0.0,
        ),
    ];
    for spec in specs {
        let mut e = effects(&m, std::slice::from_ref(&spec));
        let tau = forces(&m, &mut e, 0.0, &q, &v);
        assert!(tau.iter().any(|x| x.abs() > 1e-2), "{tau:?}");
        let h = 1e-6;
        for k in 0..m.nv {
            let dv = (potential(&m, &e, &step(&m, &q, k, h))
                - potential(&m, &e, &step(&m, &q, k, -h)))
                / (2.0 * h);
            assert!(
                (dv + tau[k]).abs() < 1e-7 * (1.0 + dv.abs()),
                "{spec:?} dof {k}: dV = {dv}, tau = {}",
                tau[k]
            );
        }
    }
}

#[test]
fn point_spring_law_is_k_stretch_plus_c_rate_along_the_line() {
    let m = model();
    let (q, v) = state(&m);
    let (pa, pb) = ([0.1, 0.0, 0.05], [0.02, 0.03, -0.01]);
    let (k, l0, c) = (30.0, 0.2, 1.7);
    let spec = point_spring(Some("plate"), pa, Some("slider"), pb, k, l0, c);
    let mut e = effects(&m, &[spec]);
    let tau = forces(&m, &mut e, 0.0, &q, &v);
    // Independently: positions from the full kinematics, the Jacobians and l̇ by central
    // differences along each speed, the force by its formula.
    let at = |q: &[f64]| {
        (
            world_point(&m, q, Some("plate"), pa),
            world_point(&m, q, Some("slider"), pb),
        )
    };
    let (xa, xb) = at(&q);
    let d = xb - xa;
    let (l, u) = (d.norm(), d / d.norm());
    let h = 1e-6;
    let mut ja = Vec::new();
    let mut jb = Vec::new();
    for s in 0..m.nv {
        let (ap, bp) = at(&step(&m, &q, s, h));
        let (am, bm) = at(&step(&m, &q, s, -h));
        ja.push((ap - am) / (2.0 * h));
        jb.push((bp - bm) / (2.0 * h));
    }
    let l_dot: f64 = (0..m.nv).map(|s| u.dot(&(jb[s] - ja[s])) * v[s]).sum();
    let f_b = -(k * (l - l0) + c * l_dot) * u;
    for s in 0..m.nv {
        let want = f_b.dot(&jb[s]) - f_b.dot(&ja[s]);
        assert!(
            (tau[s] - want).abs() < 1e-8 * (1.0 + want.abs()),
            "dof {s}: {} vs {want}",
            tau[s]
        );
    }
    // Its power is −k (l − l₀) l̇ − c l̇²: positive damping takes energy out.
    let p: f64 = tau.iter().zip(&v).map(|(a, b)| a * b).sum();
    let want = -(k * (l - l0) + c * l_dot) * l_dot;
    assert!(
        (p - want).abs() < 1e-8 * (1.0 + want.abs()),
        "{p} vs {want}"
    );
}

#[test]
fn point_spring_on_a_body_welded_to_the_world_acts_at_its_world_point() {
    // A body fixed to the world at a rotated placement: the spring's end there is a fixed
    // world point, the same as declaring it on the world.
    let mut m = Model::new();
    m.add_body(
        body(1.0, [0.0; 3], [0.1, 0.1, 0.1]),
        Joint::Fixed,
        None,
        Placement::new(rot_z(0.9), Vec3::new(0.2, -0.1, 0.3)),
        Some("post".into()),
        None,
    )
    .unwrap();
    m.add_body(
        body(1.0, [0.1, 0.0, 0.0], [0.01, 0.02, 0.02]),
        Joint::revolute(Vec3::new(0.3, 0.0, 1.0)).unwrap(),
        None,
        Placement::identity(),
        Some("arm".into()),
        None,
    )
    .unwrap();
    let p = Vec3::new(0.05, 0.1, 0.0);
    let w = rot_z(0.9) * p + Vec3::new(0.2, -0.1, 0.3);
    let (q, v) = (vec![0.4], vec![1.3]);
    let on_post = point_spring(
        Some("post"),
        p.into(),
        Some("arm"),
        [0.3, 0.0, 0.1],
        9.0,
        0.1,
        0.5,
    );
    let on_world = point_spring(None, w.into(), Some("arm"), [0.3, 0.0, 0.1], 9.0, 0.1, 0.5);
    let a = forces(
        &m,
        &mut effects(&m, std::slice::from_ref(&on_post)),
        0.0,
        &q,
        &v,
    );
    let b = forces(
        &m,
        &mut effects(&m, std::slice::from_ref(&on_world)),
        0.0,
        &q,
        &v,
    );
    assert!(
        a[0].abs() > 1e-2 && (a[0] - b[0]).abs() < 1e-14,
        "{a:?} {b:?}"
    );
    let va = potential(&m, &effects(&m, &[on_post]), &q);
    let vb = potential(&m, &effects(&m, &[on_world]), &q);
    assert!(va > 1e-3 && (va - vb).abs() < 1e-15, "{va} {vb}");
}

#[test]
fn point_spring_stops_where_its_points_coincide() {
    let m = model();
    let (q, v) = state(&m);
    // A point on the base's axis (z through the origin) stays exactly where it is.
    let on_axis = [0.0, 0.0, 0.3];
    let cx = Context {
        model: &m,
        t: 0.0,
        q: &q,
        v: &v,
    };
    let mut tau = vec![0.0; m.nv];
    for (rest, c) in [(0.1, 0.0), (0.0, 0.5), (0.1, 0.5)] {
        let spec = point_spring(None, on_axis, Some("base"), on_axis, 10.0, rest, c);
        let mut e = effects(&m, &[spec]);
        let err = match e.apply(&cx, &mut tau, &mut []) {
            Err(msg) => msg,
            Ok(_) => panic!("rest {rest} c {c}: no error, tau = {tau:?}"),
        };
        assert!(
            err.contains("coincide") && err.contains("'base'") && err.contains("world"),
            "{err}"
        );
        assert!(tau.iter().all(|t| t.is_finite()));
    }
    // l₀ = 0 and no damping: −k d is defined there (zero).
    let spec = point_spring(None, on_axis, Some("base"), on_axis, 10.0, 0.0, 0.0);
    let mut e = effects(&m, &[spec]);
    tau.fill(0.0);
    e.apply(&cx, &mut tau, &mut []).unwrap();
    assert!(tau.iter().all(|t| *t == 0.0), "{tau:?}");
}

#[test]
fn point_spring_refusals_name_the_argument() {
    let m = model();
    let name = |n: &str| Some(JointRef::Name(n.into()));
    let new = |a: Option<JointRef>, b: Option<JointRef>, p: Vec3, k: f64, l0: f64, c: f64| {
        PointSpring::new(None, a, p, b, Vec3::zeros(), k, l0, c)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    let ok = Vec3::zeros();
    for (e, arg) in [
        (
            new(None, name("ball"), ok, -1.0, 0.0, 0.0),
            "stiffness: expected a finite number >= 0, got -1",
        ),
        (
            new(None, name("ball"), ok, f64::NAN, 0.0, 0.0),
            "stiffness:",
        ),
        (new(None, name("ball"), ok, 1.0, -0.5, 0.0), "rest_length:"),
        (
            new(None, name("ball"), ok, 1.0, 0.0, f64::INFINITY),
            "damping:",
        ),
        (
            new(
                None,
                name("ball"),
                Vec3::new(0.0, f64::NAN, 0.0),
                1.0,
                0.0,
                0.0,
            ),
            "point_a:",
        ),
        (
            new(None, None, ok, 1.0, 0.0, 0.0),
            "body_b: expected a body other than body_a",
        ),
        (
            new(name("ball"), name("ball"), ok, 1.0, 0.0, 0.0),
            "body_b:",
        ),
    ] {
        assert!(e.starts_with(arg), "{e}");
    }
    let bad = |a: Option<JointRef>, b: Option<JointRef>| {
        let spec =
            Effect::PointSpring(PointSpring::new(None, a, ok, b, ok, 1.0, 0.0, 0.0).unwrap());
        Effects::new(&m, &[spec], Disabled::none(), "effects")
            .err()
            .unwrap()
            .to_string()
    };
    let e = bad(None, name("elbow"));
    assert!(
        e.starts_with("effects[0].body_b:") && e.contains("'elbow'"),
        "{e}"
    );
    let e = bad(Some(JointRef::Index(9)), None);
    assert!(
        e.starts_with("effects[0].body_a:") && e.contains("0..4"),
        "{e}"
    );
    // The plate is welded to the ball: one rigid link.
    let e = bad(name("ball"), name("plate"));
    assert!(
        e.starts_with("effects[0].body_b:") && e.contains("'plate'") && e.contains("welded"),
        "{e}"
    );
}

#[test]
fn point_spring_tables_parse_and_refuse() {
    let parse = |s: &str| Effect::from_toml(&s.parse::<toml::Table>().unwrap());
    let e = parse(
        "type = \"point_spring\"\nbody_a = \"K3\"\npoint_a = [0.02, -0.018, 0]\nbody_b = \"world\"\n\
         point_b = [0.014, 0.072, 0]\nstiffness = 4530\nrest_length = 0.07785\nname = \"c0\"",
    )
    .unwrap();
    assert_eq!(
        e,
        Effect::PointSpring(PointSpring {
            name: Some("c0".into()),
            body_a: Some(JointRef::Name("K3".into())),
            point_a: Vec3::new(0.02, -0.018, 0.0),
            body_b: None,
            point_b: Vec3::new(0.014, 0.072, 0.0),
            stiffness: 4530.0,
            rest_length: 0.07785,
            damping: 0.0,
        })
    );
    let e = parse(
        "type = \"point_spring\"\nbody_a = -1\npoint_a = [0, 0, 0]\nbody_b = 2\npoint_b = [1, 0, 0]\nstiffness = 1\ndamping = 0.5",
    )
    .unwrap();
    let Effect::PointSpring(s) = e else { panic!() };
    assert_eq!((s.body_a, s.body_b), (None, Some(JointRef::Index(2))));
    assert_eq!((s.rest_length, s.damping), (0.0, 0.5));
    let full = "type = \"point_spring\"\nbody_a = \"a\"\npoint_a = [0, 0, 0]\nbody_b = \"b\"\npoint_b = [0, 0, 1]\n";
    for (text, key) in [
        (full.to_string(), "stiffness"),
        (format!("{full}stiffness = -1"), "stiffness"),
        (format!("{full}stiffness = 1\nrest_length = -0.1"), "rest_length"),
        (format!("{full}stiffness = 1\ndamping = \"lots\""), "damping"),
        (format!("{full}stiffness = 1\nrest = 0.1"), "rest"),
        ("type = \"point_spring\"\nbody_a = -2".into(), "body_a"),
        ("type = \"point_spring\"\nbody_a = 1.5".into(), "body_a"),
        ("type = \"point_spring\"\nbody_a = \"a\"\nbody_b = \"b\"\npoint_b = [0, 0, 1]\nstiffness = 1".into(), "point_a"),
        ("type = \"point_spring\"\npoint_a = [0, 0, 0]\nbody_b = \"b\"\npoint_b = [0, 0, 1]\nstiffness = 1".into(), "body_a"),
        ("type = \"point_spring\"\nbody_a = \"a\"\npoint_a = [0, 0]\nbody_b = \"b\"\npoint_b = [0, 0, 1]\nstiffness = 1".into(), "point_a"),
        ("type = \"point_spring\"\nbody_a = \"world\"\npoint_a = [0, 0, 0]\nbody_b = -1\npoint_b = [0, 0, 1]\nstiffness = 1".into(), "body_b"),
    ] {
        let err = parse(&text).unwrap_err();
        let Error::InvalidArgument { arg, .. } = &err else {
            panic!("{err}")
        };
        assert_eq!(arg, key, "{text}: {err}");
    }
}
