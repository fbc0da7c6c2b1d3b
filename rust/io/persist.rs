//! Serialised objects (what the Python bindings pickle): a small frame around the
//! [postcard](https://docs.rs/postcard) encoding of any serde type of the core.
//!
//! ```text
//! "PMD"  version (1 byte)  postcard body  FNV-1a 64 checksum of everything before (8 bytes LE)
//! ```
//!
//! Postcard writes every `f64` as its 8 little-endian bytes, so numbers (−0.0, ±∞, NaN and its
//! payload included) come back bit for bit; integers are varints, strings and sequences
//! length-prefixed. Its wire format is frozen for postcard 1.x. The version byte lets a future
//! layout refuse older data by name rather than misread it, and the checksum catches
//! truncated or altered bytes before anything is decoded. Decoding never panics: every
//! failure is a [`PersistError`] saying what is wrong. Types with invariants check them as
//! they are decoded (`Model::check_structure`, `Table::new`, the dense output's lengths).
use serde::de::DeserializeOwned;
use serde::Serialize;

/// The first bytes of every frame.
pub const MAGIC: &[u8; 3] = b"PMD";

/// The layout written now. Bump it whenever a serialised type changes shape (a field, a
/// variant, an order): older frames are then refused with a message naming both versions.
pub const FORMAT_VERSION: u8 = 9;

const HEADER: usize = MAGIC.len() + 1;
const CHECKSUM: usize = 8;

/// Why bytes could not be decoded (or a value encoded).
#[derive(Debug, Clone, PartialEq)]
pub struct PersistError(pub String);

impl std::fmt::Display for PersistError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PersistError {}

/// FNV-1a, 64 bits: enough to tell damaged data from intact data (not an authenticator).
fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Encodes `value` in a frame of the current version.
pub fn encode<T: Serialize + ?Sized>(value: &T) -> Result<Vec<u8>, PersistError> {
    let mut out = Vec::with_capacity(256);
    out.extend_from_slice(MAGIC);
    out.push(FORMAT_VERSION);
    let out = postcard::to_extend(value, out).map_err(|e| {
        // Postcard drops the message; the only value that refuses is this one.
        PersistError(format!(
            "cannot serialise ({e}): it holds a torque function without a source (a Rust closure)"
        ))
    })?;
    let mut out = out;
    let sum = fnv1a64(&out);
    out.extend_from_slice(&sum.to_le_bytes());
    Ok(out)
}

/// Decodes a frame written by [`encode`] (of this format version).
pub fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, PersistError> {
    if bytes.len() < HEADER + CHECKSUM || &bytes[..MAGIC.len()] != MAGIC {
        return Err(PersistError(format!(
            "not pointmass_dyn data: expected a frame starting with b\"PMD\" and at least {} bytes, got {} bytes starting with {:?}",
            HEADER + CHECKSUM,
            bytes.len(),
            &bytes[..bytes.len().min(4)]
        )));
    }
    let version = bytes[MAGIC.len()];
    if version != FORMAT_VERSION {
        return Err(PersistError(format!(
            "data in serialisation format version {version}, but this pointmass_dyn ({}) reads version {FORMAT_VERSION} only: recreate the object with the version that wrote it and save its inputs (e.g. the scene file) instead",
            env!("CARGO_PKG_VERSION")
        )));
    }
    let (framed, sum) = bytes.split_at(bytes.len() - CHECKSUM);
    let mut stored = [0u8; CHECKSUM];
    stored.copy_from_slice(sum);
    if fnv1a64(framed) != u64::from_le_bytes(stored) {
        return Err(PersistError(format!(
            "corrupt data: the checksum of the {} bytes does not match (truncated or altered after it was written)",
            bytes.len()
        )));
    }
    let (value, rest) = postcard::take_from_bytes::<T>(&framed[HEADER..])
        .map_err(|e| {
            PersistError(format!(
                "corrupt or inconsistent data (intact frame, but not a valid object of the expected type): {e}"
            ))
        })?;
    if !rest.is_empty() {
        return Err(PersistError(format!(
            "corrupt data: {} bytes left over after the object",
            rest.len()
        )));
    }
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::benchmark_models;
    use crate::effects::{Effect, PerJoint, Spring, Table, Torque, TorqueFunction};
    use crate::integrator::DenseOutput;
    use crate::model::body::RigidBody;
    use crate::model::Model;
    use crate::support::spatial::{Mat3, Vec3};
    use std::sync::Arc;

    fn bits(x: &[f64]) -> Vec<u64> {
        x.iter().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn floats_round_trip_bit_for_bit() {
        let odd = [
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::from_bits(0x7ff8_0000_dead_beef),
            f64::MIN_POSITIVE / 3.0,
            0.1 + 0.2,
        ];
        let back: Vec<f64> = decode(&encode(&odd.to_vec()).unwrap()).unwrap();
        assert_eq!(bits(&back), bits(&odd));
        // Inside a core type too (no validation on a bare RigidBody).
        let b = RigidBody {
            mass: -0.0,
            com: Vec3::new(f64::NAN, f64::INFINITY, 1e-310),
            inertia: Mat3::from_element(0.1),
        };
        let back: RigidBody = decode(&encode(&b).unwrap()).unwrap();
        assert_eq!(back.mass.to_bits(), b.mass.to_bits());
        assert_eq!(bits(back.com.as_slice()), bits(b.com.as_slice()));
    }

    fn same_model(a: &Model, b: &Model) {
        // Debug prints every f64 with its shortest round-trip form: equal strings, equal bits
        // (NaN aside, which no valid model holds).
        // (The private name index is a HashMap: its Debug order varies, so it is compared as
        // what it answers.)
        assert_eq!(format!("{:?}", a.bodies), format!("{:?}", b.bodies));
        assert_eq!(format!("{:?}", a.links), format!("{:?}", b.links));
        assert_eq!((a.nq, a.nv), (b.nq, b.nv));
        for (k, body) in a.bodies.iter().enumerate() {
            assert_eq!(b.body_index(&body.name), Some(k));
        }
    }

    #[test]
    fn models_round_trip_with_their_derived_data() {
        for m in [
            benchmark_models::chain(7),
            benchmark_models::tree(3, 3),
            benchmark_models::paper_pendulum(),
        ] {
            let back: Model = decode(&encode(&m).unwrap()).unwrap();
            same_model(&m, &back);
        }
        let panda = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/python/pointmass_dyn/scenes/panda.urdf"
        );
        let u = crate::io::urdf::load_urdf(
            std::path::Path::new(panda),
            crate::io::urdf::RootJoint::Fixed,
        )
        .unwrap();
        let back: Model = decode(&encode(&u.model).unwrap()).unwrap();
        same_model(&u.model, &back);
        assert!(!back.records.joints.is_empty());
        assert_eq!(back.records, u.model.records);
    }

    #[test]
    fn broken_models_and_tables_are_refused() {
        let mut m = benchmark_models::chain(3);
        m.links[2].q_index = 7;
        // Postcard keeps no custom message; the check's own is seen with other formats.
        assert!(decode::<Model>(&encode(&m).unwrap()).is_err());
        let e = crate::model::Model::check_structure(&m).unwrap_err();
        assert!(e.to_string().contains("link 2"), "{e}");
        let mut m = benchmark_models::chain(3);
        m.bodies[1].parent = Some(2);
        assert!(decode::<Model>(&encode(&m).unwrap()).is_err());
        // A table whose times do not increase fails Table::new's check.
        let t = Table::new(
            vec![0.0, 1.0],
            crate::effects::torque::column(vec![1.0, 2.0]),
            "time",
            "values",
        )
        .unwrap();
        let mut bytes = postcard::to_stdvec(&t).unwrap();
        bytes[1..9].copy_from_slice(&2.0f64.to_le_bytes()); // time[0] = 2 > time[1]
        assert!(postcard::from_bytes::<Table>(&bytes).is_err());
    }

    #[test]
    fn damaged_frames_give_errors_never_panics() {
        let m = benchmark_models::tree(2, 3);
        let good = encode(&m).unwrap();
        // Every truncation and every single-byte change is refused.
        for n in 0..good.len() {
            assert!(decode::<Model>(&good[..n]).is_err(), "truncated to {n}");
        }
        for k in 0..good.len() {
            let mut bad = good.clone();
            bad[k] ^= 0x41;
            assert!(decode::<Model>(&bad).is_err(), "byte {k} changed");
        }
        // A valid frame of another type, and another version.
        let e = decode::<Model>(&encode(&vec![1u8; 40]).unwrap()).unwrap_err();
        assert!(!e.0.is_empty());
        let mut v2 = good.clone();
        v2[3] = FORMAT_VERSION + 1;
        let e = decode::<Model>(&v2).unwrap_err();
        let other = format!("format version {}", FORMAT_VERSION + 1);
        assert!(e.0.contains(&other), "{e}");
        let e = decode::<Model>(b"not a pickle at all").unwrap_err();
        assert!(e.0.starts_with("not pointmass_dyn data"), "{e}");
    }

    #[test]
    fn torque_functions_need_a_source_and_come_back_unrestored() {
        let f: Arc<crate::effects::torque::TorqueFn> = Arc::new(|_, _, _, out| {
            out.fill(1.0);
            Ok(())
        });
        let bare = Effect::Torque(Torque::function(None, TorqueFunction::new(f.clone())));
        let e = encode(&bare).unwrap_err();
        assert!(e.0.contains("without a source"), "{e}");
        let with = Effect::Torque(Torque::function(
            Some("motor".into()),
            TorqueFunction::with_source(f, Arc::new("the source")),
        ));
        let spring = Effect::Spring(Spring::new(None, None, PerJoint::All(2.0), None).unwrap());
        let back: Vec<Effect> = decode(&encode(&vec![spring.clone(), with]).unwrap()).unwrap();
        assert_eq!(back[0], spring);
        let Effect::Torque(t) = &back[1] else {
            panic!("{back:?}")
        };
        assert_eq!(t.name.as_deref(), Some("motor"));
        let crate::effects::TorqueLaw::Function(g) = &t.law else {
            panic!("{t:?}")
        };
        assert!(g.source().is_none());
        assert!((g.0)(0.0, &[], &[], &mut []).is_err());
    }

    /// One of everything that can be serialised, from literal numbers only (no arithmetic, so
    /// the bytes are the same on every platform).
    fn one_of_everything() -> Vec<u8> {
        use crate::effects::{
            ContactPoint, Damper, Disabled, External, Frame, Friction, GroundContact, JointLimit,
            JointRef, Kind, PerJoint, TorqueLimit,
        };
        use crate::io::scene::{Scene, Settings};
        use crate::io::urdf::{Limit, Mimic, UrdfJoint};
        use crate::joint::Joint;
        use crate::model::point_masses::EquimomentalSet;
        use crate::model::{BodyRecord, Link};
        use crate::simulate::StateEvent;
        use crate::support::spatial::{BodyInertia, Placement};
        let v = |x: f64| Vec3::new(x, -x, 0.5);
        let body = RigidBody {
            mass: 2.0,
            com: v(0.25),
            inertia: Mat3::identity(),
        };
        let placement = Placement::new(Mat3::identity(), v(1.0));
        let joints = [
            Joint::Revolute { axis: Vec3::x() },
            Joint::Prismatic { axis: Vec3::y() },
            Joint::SphericalZYZ,
            Joint::Spherical,
            Joint::Fixed,
            Joint::FreeFlyer,
        ];
        let points = EquimomentalSet {
            masses: [0.25, -0.5, 1.0, 0.0, 1.0, -0.5, 0.75],
            positions: [v(0.125); 7],
            half_sides: v(0.0625),
            center: v(2.0),
        };
        // Fields set one by one: `Model` keeps a private name index (not serialised).
        let mut model = Model::new();
        model.bodies = vec![BodyRecord {
            name: "b".into(),
            body,
            joint: joints[0],
            parent: None,
            placement,
            link: Some(0),
            in_link: Placement::identity(),
            point_mass_center: Some(v(3.0)),
        }];
        model.links = vec![Link {
            body: 0,
            parent: None,
            joint: joints[0],
            placement,
            placement_rotated: false,
            q_index: 0,
            v_index: 0,
            rigid: body,
            points,
            inertia: BodyInertia {
                mass: 2.0,
                first_moment: v(4.0),
                rotational: Mat3::identity(),
            },
        }];
        model.nq = 1;
        model.nv = 1;
        model.name = "m".into();
        model.armature = vec![0.25];
        model.couplings = vec![crate::model::constraints::Coupling {
            name: "c".into(),
            joint: 0,
            reference: 0,
            ratio: -0.5,
            offset: 0.125,
        }];
        use crate::model::visual::{Shape, Visual};
        let shapes = [
            Shape::Box {
                size: Vec3::new(0.5, 0.25, 1.0),
            },
            Shape::Cylinder {
                radius: 0.5,
                length: 2.0,
            },
            Shape::Sphere { radius: 0.25 },
            Shape::Capsule {
                radius: 0.5,
                length: 1.0,
            },
            Shape::Ellipsoid {
                radii: Vec3::new(0.75, 0.5, 0.25),
            },
            Shape::Mesh {
                uri: "package://p/m.stl".into(),
                path: Some("/m.stl".into()),
                scale: v(2.0),
            },
        ];
        model.visuals = shapes
            .into_iter()
            .map(|shape| Visual {
                body: 0,
                origin: placement,
                shape,
                rgba: Some([0.5, 0.25, 1.0, 1.0]),
            })
            .collect();
        let col = |x: Vec<f64>| crate::effects::torque::column(x);
        let table = Table::new(vec![0.0, 1.0], col(vec![1.0, 2.0]), "t", "v").unwrap();
        let each = PerJoint::Each(vec![1.0, 2.0]);
        let refs = Some(vec![JointRef::Name("b".into()), JointRef::Index(0)]);
        let source: crate::effects::TorqueSource = Arc::new(());
        let f = TorqueFunction::with_source(Arc::new(|_, _, _, _| Ok(())), source);
        let effects = vec![
            Effect::Gravity { g: v(9.5) },
            Effect::Spring(
                Spring::new(Some("s".into()), refs.clone(), each.clone(), None).unwrap(),
            ),
            Effect::Damper(Damper::new(None, refs.clone(), PerJoint::All(0.5)).unwrap()),
            Effect::Friction(Friction::new(None, None, each.clone(), Some(0.25)).unwrap()),
            Effect::Torque(Torque::constant(None, refs.clone(), each.clone()).unwrap()),
            Effect::Torque(Torque::tabulated(None, None, table.clone()).unwrap()),
            Effect::Torque(
                Torque::pd(None, refs, each.clone(), each, table)
                    .unwrap()
                    .with_limit(Some(TorqueLimit::Given(PerJoint::All(2.0)))),
            ),
            Effect::Torque(Torque::function(Some("f".into()), f)),
            Effect::External(
                External::constant(
                    None,
                    JointRef::Index(0),
                    v(1.0),
                    v(2.0),
                    v(3.0),
                    Frame::Body,
                )
                .unwrap(),
            ),
            Effect::External(
                External::tabulated(
                    None,
                    JointRef::Index(0),
                    v(1.0),
                    vec![0.0, 1.0],
                    Some(crate::effects::Matrix {
                        values: vec![1.0; 6],
                        rows: 2,
                        cols: 3,
                        one_d: false,
                    }),
                    None,
                    Frame::World,
                )
                .unwrap(),
            ),
            Effect::PointSpring(
                crate::effects::PointSpring::new(
                    Some("p".into()),
                    Some(JointRef::Index(0)),
                    v(1.0),
                    None,
                    v(2.0),
                    4.5,
                    0.25,
                    0.5,
                )
                .unwrap(),
            ),
            Effect::GroundContact(
                GroundContact::new(
                    Some("c".into()),
                    vec![ContactPoint {
                        body: JointRef::Index(0),
                        point: v(0.5),
                        radius: 0.125,
                    }],
                    v(1.0),
                    0.25,
                    Some(1.0e4),
                    1.5,
                    Some(20.0),
                    0.75,
                    1e-3,
                )
                .unwrap(),
            ),
            Effect::JointLimit(
                JointLimit::new(
                    None,
                    Some(vec![JointRef::Index(0)]),
                    Some(PerJoint::All(-1.0)),
                    None,
                    PerJoint::All(100.0),
                    PerJoint::Each(vec![2.0]),
                )
                .unwrap(),
            ),
        ];
        let scene = Scene {
            name: "n".into(),
            description: "d".into(),
            model: model.into(),
            q0: vec![0.5],
            v0: vec![-0.5],
            effects,
            settings: Settings {
                t_span: Some((0.0, 1.0)),
                rtol: Some(1e-6),
                atol: None,
                max_step: Some(0.5),
                max_steps: Some(1000),
                first_step: None,
                disable: Some(Disabled::none().with(Kind::Springs)),
                method: Some(crate::integrator::Method::Dop853),
                dt: Some(1e-3),
            },
        };
        let event = StateEvent {
            on_velocity: true,
            index: 3,
            value: 0.5,
            direction: -1,
            terminal: 2,
        };
        let urdf = UrdfJoint {
            name: "j".into(),
            kind: "continuous",
            parent: "p".into(),
            child: "c".into(),
            body: 1,
            link: None,
            q_index: Some(0),
            v_index: Some(0),
            axis: Vec3::z(),
            limit: Some(Limit {
                lower: f64::NEG_INFINITY,
                upper: f64::INFINITY,
                effort: 1.0,
                velocity: 2.0,
            }),
            damping: 0.5,
            friction: 0.25,
            mimic: Some(Mimic {
                joint: "k".into(),
                multiplier: -1.0,
                offset: 0.5,
            }),
        };
        let mut dense = DenseOutput::new(1, 0.0);
        dense.push_segment(0.0, 0.5, &[1.0], &[1.0, 2.0, 3.0, 4.0]);
        dense.push_breakpoint(0.5);
        encode(&(scene, joints, event, urdf, dense)).unwrap()
    }

    /// The layout is pinned: if this fails, a serialised type changed shape. Bump
    /// `FORMAT_VERSION` (old pickles are then refused by name, not misread) and update the
    /// checksum below.
    #[test]
    fn the_format_layout_is_pinned() {
        let bytes = one_of_everything();
        assert_eq!(bytes[3], FORMAT_VERSION);
        let sum = fnv1a64(&bytes[HEADER..bytes.len() - CHECKSUM]);
        assert_eq!(
            (FORMAT_VERSION, bytes.len(), sum),
            (9, 3002, 0xd1f5_6d0c_bf34_8c6e),
            "a serialised type changed shape: bump FORMAT_VERSION, then update this test"
        );
    }

    #[test]
    fn dense_output_lengths_are_checked() {
        let mut bytes = postcard::to_stdvec(&(2usize, vec![0.0f64, 1.0])).unwrap();
        // dim 2, two breakpoints, then no segments at all: inconsistent.
        bytes.extend(postcard::to_stdvec(&(Vec::<f64>::new(), Vec::<f64>::new())).unwrap());
        bytes.extend(postcard::to_stdvec(&(Vec::<f64>::new(), Vec::<f64>::new())).unwrap());
        assert!(postcard::from_bytes::<DenseOutput>(&bytes).is_err());
    }
}
