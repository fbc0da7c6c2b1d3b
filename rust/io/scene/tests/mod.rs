//! The scene loader's tests.
use super::*;
use crate::support::spatial::Vec3;

const PENDULUM: &str = r#"
name = "pendulum"
angles = "degrees"
[[body]]
name = "rod"
joint = { type = "SphericalZYZ" }
mass = 2.51
com = [0.5, 0, 0]
inertia_diag = [1.255e-4, 0.2092294166666666, 0.2092294166666666]
q0 = [90, 45, 45]
v0 = [0, 57.29577951308232, 0]
[[effect]]
type = "gravity"
g = [0, 0, -9.81]
[simulate]
t_end = 10
rtol = 1e-9
"#;

#[test]
fn parses_units_and_effects() {
    let s = Scene::from_toml(PENDULUM, "p.toml").unwrap();
    assert_eq!(s.model.nq, 3);
    assert!((s.q0[1] - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
    assert!((s.v0[1] - 1.0).abs() < 1e-14);
    assert_eq!(
        s.effects,
        vec![Effect::Gravity {
            g: Vec3::new(0.0, 0.0, -9.81)
        }]
    );
    assert_eq!(s.settings.t_span, Some((0.0, 10.0)));
}

#[test]
fn errors_name_file_and_key() {
    let bad_parent = PENDULUM.replace("name = \"rod\"", "name = \"rod\"\nparent = \"nope\"");
    let e = Scene::from_toml(&bad_parent, "p.toml")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("p.toml: body[0] ('rod').parent"), "{e}");
    let bad_mass = PENDULUM.replace("mass = 2.51", "mass = -1");
    let e = Scene::from_toml(&bad_mass, "p.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("body[0] ('rod').mass: "), "{e}");
    assert!(!e.contains("mass: mass"), "the argument is named once: {e}");
    let typo = PENDULUM.replace("mass = 2.51", "mass = 2.51\nmas = 3");
    let e = Scene::from_toml(&typo, "p.toml").unwrap_err().to_string();
    assert!(e.contains("p.toml") && e.contains("mas"), "{e}");
    let e = Scene::from_toml("[[body]\n", "x.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("x.toml") && e.contains("line 1"), "{e}");
    let neg = PENDULUM.replace("inertia_diag = [1.255e-4,", "inertia_diag = [-1.255e-4,");
    let e = Scene::from_toml(&neg, "p.toml").unwrap_err().to_string();
    assert!(e.contains("inertia") && e.contains("semidefinite"), "{e}");
}

#[test]
fn errors_carry_their_location() {
    use crate::support::error::{Error, FileKind};
    let bad_parent = PENDULUM.replace("name = \"rod\"", "name = \"rod\"\nparent = \"nope\"");
    match Scene::from_toml(&bad_parent, "p.toml").unwrap_err() {
        Error::File { kind, at, .. } => {
            assert_eq!(kind, FileKind::Scene);
            assert_eq!(
                (at.file.as_str(), at.key.as_str()),
                ("p.toml", "body[0] ('rod').parent")
            );
        }
        other => panic!("not a file error: {other}"),
    }
    match Scene::from_toml("[[body]\n", "x.toml").unwrap_err() {
        Error::File { at, message, .. } => {
            assert_eq!(at.line, Some(1));
            let column = at.column.unwrap();
            assert!(
                message.contains(&format!("line 1, column {column}")),
                "{message}"
            );
        }
        other => panic!("not a file error: {other}"),
    }
}

const GEARED: &str = r#"
angles = "degrees"
[[body]]
name = "upper"
joint = { type = "Revolute", axis = [0, 0, 1] }
mass = 1.0
inertia_diag = [0.01, 0.01, 0.01]
armature = 0.05
[[body]]
name = "slider"
parent = "upper"
joint = { type = "Prismatic", axis = [1, 0, 0] }
mass = 0.5
inertia_diag = [0.01, 0.01, 0.01]
[[coupling]]
joint = "slider"
reference = "upper"
ratio = 0.001
offset = 0.1
[armature]
slider = [0.2]
"#;

#[test]
fn couplings_and_armature_in_file_units() {
    let s = Scene::from_toml(GEARED, "g.toml").unwrap();
    let c = &s.model.couplings[0];
    // 1 mm per degree of the revolute reference: 0.001 · 180/π m per radian; the
    // prismatic joint's offset is in metres.
    assert!((c.ratio - 0.001 * 180.0 / std::f64::consts::PI).abs() < 1e-15);
    assert_eq!(c.offset, 0.1);
    assert_eq!(s.model.armature, vec![0.05, 0.2]);
    // The initial state is put on the coupling.
    assert!((s.q0[1] - c.ratio * s.q0[0] - 0.1).abs() < 1e-12);
    for (from, to, key) in [
        (
            "ratio = 0.001",
            "ratio = true",
            "g.toml: coupling[0].ratio: expected a number",
        ),
        (
            "slider = [0.2]",
            "slider = -1",
            "g.toml: armature.slider: expected finite numbers >= 0",
        ),
        (
            "reference = \"upper\"",
            "reference = \"world\"",
            "g.toml: coupling[0].reference",
        ),
    ] {
        let e = Scene::from_toml(&GEARED.replace(from, to), "g.toml").unwrap_err();
        assert!(e.to_string().starts_with(key), "{e}");
    }
}
