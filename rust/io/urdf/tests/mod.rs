//! The URDF loader's tests: small robots written inline by the fixtures below.
use super::*;
use crate::joint::{rot_x, rot_y, rot_z, Joint};
use crate::support::spatial::{Mat3, Vec3};

fn inertial(mass: f64, xyz: &str, rpy: &str, diag: [f64; 3]) -> String {
    format!(
        r#"<inertial><origin xyz="{xyz}" rpy="{rpy}"/><mass value="{mass}"/><inertia ixx="{}" ixy="0" ixz="0" iyy="{}" iyz="0" izz="{}"/></inertial>"#,
        diag[0], diag[1], diag[2]
    )
}

fn link(name: &str, mass: f64) -> String {
    format!(
        r#"<link name="{name}">{}</link>"#,
        inertial(mass, "0.1 0 0", "0 0 0", [0.01, 0.02, 0.02])
    )
}

fn joint(name: &str, kind: &str, parent: &str, child: &str, extra: &str) -> String {
    format!(
        r#"<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>{extra}</joint>"#
    )
}

/// A revolute joint about x with the `<limit>` URDF requires (effort 1, velocity 1).
fn revolute(name: &str, parent: &str, child: &str) -> String {
    joint(
        name,
        "revolute",
        parent,
        child,
        r#"<limit effort="1" velocity="1"/>"#,
    )
}

/// Links `base` and `a` (mass 1) on the revolute joint `j` whose other elements are `extra`.
fn base_and_a(extra: &str) -> String {
    robot(&[
        link("base", 1.0),
        link("a", 1.0),
        joint("j", "revolute", "base", "a", extra),
    ])
}

fn robot(parts: &[String]) -> String {
    format!(
        "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n{}\n</robot>\n",
        parts.join("\n")
    )
}

fn load(text: &str) -> Urdf {
    model_from_urdf(text, "t.urdf", None, RootJoint::Fixed).unwrap()
}

fn error(text: &str) -> String {
    model_from_urdf(text, "t.urdf", None, RootJoint::Fixed)
        .unwrap_err()
        .to_string()
}

#[test]
#[allow(clippy::approx_constant)] // 1.5708 is the point: near π/2 but not it
fn quarter_turn_rpy_is_exact() {
    // The decimal π/2 leaves cos = 6e-17; the model holds the exact quarter turn
    // (model::checked_rotation), while an angle that is not π/2 to double precision stays
    // as written.
    let placed = |rpy: &str| {
        let text = base_and_a(&format!(
            r#"<origin xyz="0 0 0.3" rpy="{rpy}"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="5" velocity="2"/>"#
        ));
        load(&text).model.links[0].placement.rotation
    };
    let r = placed("-1.5707963267948966 0 0");
    assert_eq!(r, Mat3::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0));
    let r = placed("1.5707963267948966 0 1.5707963267948966");
    assert_eq!(r, Mat3::new(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0));
    let r = placed("3.141592653589793 0 0");
    assert_eq!(r, Mat3::new(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0));
    let r = placed("1.5708 0 0");
    assert_eq!(r, rot_x(1.5708));
    assert!(r[(1, 1)] != 0.0);
}

#[test]
fn rpy_is_z_y_x() {
    // Yaw π/2: x → y.
    let r = rpy_matrix(&Vec3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2));
    assert!((r * Vec3::x() - Vec3::y()).norm() < 1e-15);
    let (a, b, c) = (0.3, -0.7, 1.9);
    let text = base_and_a(&format!(
        r#"<origin xyz="1 2 3" rpy="{a} {b} {c}"/><axis xyz="0 0 2"/><limit lower="-1" upper="1" effort="5" velocity="2"/>"#
    ));
    let u = load(&text);
    let l = &u.model.links[0];
    let expect = rot_z(c) * rot_y(b) * rot_x(a);
    assert!((l.placement.rotation - expect).norm() < 1e-15);
    assert_eq!(l.placement.translation, Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(l.joint, Joint::Revolute { axis: Vec3::z() });
    let j = &u.joints()[0];
    assert_eq!(
        j.limit,
        Some(Limit {
            lower: -1.0,
            upper: 1.0,
            effort: 5.0,
            velocity: 2.0
        })
    );
    assert_eq!(
        (j.q_index, j.v_index, j.body, j.link),
        (Some(0), Some(0), 1, Some(0))
    );
}

#[test]
fn inertial_origin_rotates_the_tensor() {
    let text = robot(&[
        link("base", 1.0),
        format!(
            r#"<link name="a">{}</link>"#,
            inertial(
                2.0,
                "0.1 0.2 0.3",
                "0 0 1.5707963267948966",
                [1.0, 2.0, 3.0]
            )
        ),
        joint(
            "j",
            "prismatic",
            "base",
            "a",
            r#"<limit effort="1" velocity="1"/><dynamics damping="0.5" friction="0.25"/>"#,
        ),
    ]);
    let u = load(&text);
    let b = &u.model.bodies[1].body;
    assert_eq!(b.mass, 2.0);
    assert!((b.com - Vec3::new(0.1, 0.2, 0.3)).norm() < 1e-15);
    // Rotating by 90° about z swaps the x and y moments.
    assert!((b.inertia - Mat3::from_diagonal(&Vec3::new(2.0, 1.0, 3.0))).norm() < 1e-14);
    assert!((u.model.links[0].rigid.inertia - b.inertia).norm() < 1e-14);
    assert_eq!((u.joints()[0].damping, u.joints()[0].friction), (0.5, 0.25));
    assert_eq!(u.joints()[0].kind, "prismatic");
    assert_eq!(u.model.links[0].joint, Joint::Prismatic { axis: Vec3::x() });
}

#[test]
fn fixed_links_are_welded_and_massless_ones_add_nothing() {
    let text = robot(&[
        r#"<link name="world"/>"#.to_string(),
        link("base", 1.0),
        link("a", 1.0),
        link("b", 3.0),
        r#"<link name="tool"/>"#.to_string(),
        joint(
            "fix_base",
            "fixed",
            "world",
            "base",
            r#"<axis xyz="0 0 0"/>"#,
        ),
        joint("j", "continuous", "base", "a", ""),
        joint("weld", "fixed", "a", "b", r#"<origin xyz="0 0 1"/>"#),
        joint("tool_joint", "fixed", "b", "tool", ""),
    ]);
    let u = load(&text);
    assert_eq!(u.model.nq, 1);
    assert_eq!(u.model.links.len(), 1);
    let names: Vec<&str> = u.model.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["world", "base", "a", "b", "tool"]);
    let rigid = &u.model.links[0].rigid;
    assert_eq!(rigid.mass, 4.0);
    // COM: a's (0.1, 0, 0) and b's (0.1, 0, 1), weighted 1 : 3.
    assert!((rigid.com - Vec3::new(0.1, 0.0, 0.75)).norm() < 1e-15);
    let moving: Vec<&str> = u.moving_joints().map(|j| j.name.as_str()).collect();
    assert_eq!(moving, ["j"]);
    assert_eq!(u.joint("j").unwrap().kind, "continuous");
    assert_eq!(u.model.links[0].joint, Joint::Revolute { axis: Vec3::x() });
    assert!(u.warnings.is_empty(), "{:?}", u.warnings);
    // Point masses reproduce the merged body.
    let p = &u.model.links[0].inertia;
    assert!((p.mass - 4.0).abs() < 1e-12);
}

#[test]
fn siblings_follow_joint_name_order() {
    let text = robot(&[
        link("base", 1.0),
        link("zz", 1.0),
        link("aa", 1.0),
        link("mm", 1.0),
        link("c", 1.0),
        revolute("q1", "base", "mm"),
        revolute("a1", "base", "zz"),
        revolute("j_c", "aa", "c"),
        joint("M1", "fixed", "base", "aa", ""),
    ]);
    let u = load(&text);
    let names: Vec<&str> = u.joints().iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["M1", "j_c", "a1", "q1"]);
    let bodies: Vec<&str> = u.model.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(bodies, ["base", "aa", "c", "zz", "mm"]);
}

#[test]
fn massless_moving_links() {
    // A massless intermediate link with mass below it: a zero body.
    let text = robot(&[
        link("base", 1.0),
        r#"<link name="virtual"/>"#.to_string(),
        link("leg", 2.0),
        revolute("hip_x", "base", "virtual"),
        joint(
            "hip_y",
            "revolute",
            "virtual",
            "leg",
            r#"<axis xyz="0 1 0"/><limit effort="1" velocity="1"/>"#,
        ),
    ]);
    let u = load(&text);
    assert_eq!(u.model.links.len(), 2);
    assert_eq!(u.model.links[0].rigid.mass, 0.0);
    assert_eq!(u.model.links[0].inertia.mass, 0.0);
    assert_eq!(u.model.total_mass(), 2.0);
    // Nothing with mass below: an error naming the joint.
    let text = robot(&[
        link("base", 1.0),
        r#"<link name="finger"/>"#.to_string(),
        revolute("f", "base", "finger"),
    ]);
    let e = error(&text);
    assert!(
        e.starts_with("t.urdf: joint 'f': child link 'finger' has no mass"),
        "{e}"
    );
    // Mass 0 with inertia: fine on a fixed joint (added to the parent link), not alone.
    let foot = format!(
        r#"<link name="foot">{}</link>"#,
        inertial(0.0, "0 0 0", "0 0 0", [1e-3, 1e-3, 1e-3])
    );
    let text = robot(&[
        link("base", 1.0),
        link("leg", 1.0),
        foot.clone(),
        revolute("knee", "base", "leg"),
        joint("ankle", "fixed", "leg", "foot", ""),
    ]);
    let u = load(&text);
    assert!((u.model.links[0].rigid.inertia[(0, 0)] - (0.01 + 1e-3)).abs() < 1e-15);
    let text = robot(&[link("base", 1.0), foot, revolute("ankle", "base", "foot")]);
    let e = error(&text);
    assert!(
        e.contains("link 'foot'") && e.contains("zero mass with a non-zero"),
        "{e}"
    );
}

#[test]
fn rounding_noise_in_an_inertia_is_projected_away() {
    // iCub's head: a point mass whose tensor is rounding noise with a negative eigenvalue.
    let text = robot(&[
        link("base", 1.0),
        r#"<link name="head"><inertial><origin xyz="0.0185 -0.1108 0"/><mass value="1.33687"/><inertia ixx="0" ixy="0" ixz="2.40741e-35" iyy="0" iyz="0" izz="0"/></inertial></link>"#.to_string(),
        revolute("neck", "base", "head"),
    ]);
    let u = load(&text);
    let l = &u.model.links[0];
    assert!(l.rigid.inertia.abs().max() < 1e-34);
    // The seven points stay a point mass (no spurious spread from the noise).
    assert!(
        l.points.half_sides.norm() < 1e-15,
        "{}",
        l.points.half_sides
    );
    // A real violation is still an error, at any scale.
    let bad = text.replace(
        r#"ixx="0" ixy="0" ixz="2.40741e-35""#,
        r#"ixx="1e-4" ixy="0" ixz="0""#,
    );
    assert!(error(&bad).contains("triangle"));
}

#[test]
fn mimic_loads_as_coupling_and_ignored_elements_warn() {
    let text = robot(&[
        link("base", 1.0),
        link("a", 1.0),
        link("b", 1.0),
        joint(
            "j1",
            "revolute",
            "base",
            "a",
            r#"<limit effort="1" velocity="1"/><calibration rising="0"/>"#,
        ),
        joint(
            "j2",
            "revolute",
            "a",
            "b",
            r#"<limit effort="1" velocity="1"/><mimic joint="j1" multiplier="2"/>"#,
        ),
        "<gazebo reference=\"a\"/><transmission name=\"t\"/><material name=\"m\"/>".to_string(),
    ]);
    let u = load(&text);
    assert_eq!(u.model.nv, 2);
    assert_eq!(
        u.joints()[1].mimic,
        Some(Mimic {
            joint: "j1".into(),
            multiplier: 2.0,
            offset: 0.0
        })
    );
    let c = &u.model.couplings[0];
    assert_eq!(
        (c.joint, c.reference, c.ratio, c.offset),
        (u.joints()[1].body, u.joints()[0].body, 2.0, 0.0)
    );
    assert_eq!(c.name, "j2");
    assert_eq!(u.warnings.len(), 1, "{:?}", u.warnings);
    assert!(u.warnings[0].contains("<gazebo>") && u.warnings[0].contains("<transmission>"));
    assert!(u.warnings[0].contains("<joint><calibration>"));
    assert!(!u.warnings[0].contains("material"));
}

#[test]
fn errors_name_file_and_element() {
    let ok = [
        link("base", 1.0),
        link("a", 1.0),
        revolute("j", "base", "a"),
    ];
    load(&robot(&ok));
    // Malformed XML: the line.
    let e = error("<robot name=\"r\">\n<link name=\"a\">\n</robot>\n");
    assert!(e.starts_with("t.urdf: malformed XML at line 3"), "{e}");
    let e = error("<robot name=\"r\">\n<link name=\"a\"/>\n");
    assert!(e.contains("malformed XML at line"), "{e}");
    let e = error("<robot><link name=\"a\"><inertial><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link></robot>");
    assert!(
        e.starts_with("t.urdf: link 'a': <inertial> has no <mass"),
        "{e}"
    );
    let e = error("<robot><link name=\"a\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link></robot>");
    assert!(
        e.contains("link 'a'") && e.contains("missing the 'ixy' attribute"),
        "{e}"
    );
    // An invalid inertial on a moving link is an error; on the root (welded to the world,
    // outside the dynamics) a warning.
    let on_moving = |mass: f64, diag: [f64; 3]| {
        robot(&[
            link("base", 1.0),
            format!(
                r#"<link name="a">{}</link>"#,
                inertial(mass, "0 0 0", "0 0 0", diag)
            ),
            revolute("j", "base", "a"),
        ])
    };
    let e = error(&on_moving(1.0, [-1.0, 1.0, 1.0]));
    assert!(
        e.starts_with("t.urdf: link 'a': <inertial>: inertia: expected a positive semidefinite"),
        "{e}"
    );
    let e = error(&on_moving(1.0, [1.0, 1.0, 3.0]));
    assert!(e.contains("link 'a'") && e.contains("triangle"), "{e}");
    let e = error(&on_moving(-1.0, [1.0, 1.0, 1.0]));
    assert!(e.contains("link 'a': <inertial><mass value>"), "{e}");
    let root_only = robot(&[format!(
        r#"<link name="a">{}</link>"#,
        inertial(1e-3, "0 0 0", "0 0 0", [0.0, 0.0, 3e-6])
    )]);
    let u = load(&root_only);
    assert_eq!(u.model.nv, 0);
    assert!(
        u.warnings[0].contains("welded to the world")
            && u.warnings[0].contains("link 'a': <inertial>: inertia: principal moments")
            && u.warnings[0].contains("triangle"),
        "{:?}",
        u.warnings
    );
    let mut bad = ok.clone();
    bad[2] = joint("j", "revolute", "base", "x", "");
    let e = error(&robot(&bad));
    assert!(
        e.starts_with("t.urdf: joint 'j': child link 'x' is not defined"),
        "{e}"
    );
    bad[2] = joint("j", "revolute", "y", "a", "");
    let e = error(&robot(&bad));
    assert!(
        e.starts_with("t.urdf: joint 'j': parent link 'y' is not defined"),
        "{e}"
    );
    bad[2] = joint("j", "floating", "base", "a", "");
    let e = error(&robot(&bad));
    assert!(
        e.contains("joint 'j'")
            && e.contains("floating joints are not supported yet; got joint 'j' of type floating"),
        "{e}"
    );
    bad[2] = joint("j", "planar", "base", "a", "");
    assert!(error(&robot(&bad)).contains("planar joints are not supported yet"));
    // Two parents.
    let mut two = ok.to_vec();
    two.push(link("c", 1.0));
    two.push(joint("k", "fixed", "c", "a", ""));
    let e = error(&robot(&two));
    assert!(
        e.contains("joint 'k'") && e.contains("already has a parent through joint 'j'"),
        "{e}"
    );
    // A cycle with no root.
    let e = error(&robot(&[
        link("a", 1.0),
        link("b", 1.0),
        joint("ab", "fixed", "a", "b", ""),
        joint("ba", "fixed", "b", "a", ""),
    ]));
    assert!(
        e.contains("robot: no root link") && e.contains("'ab'") && e.contains("'ba'"),
        "{e}"
    );
    // A cycle detached from the root.
    let e = error(&robot(&[
        link("r", 1.0),
        link("a", 1.0),
        link("b", 1.0),
        joint("ab", "fixed", "a", "b", ""),
        joint("ba", "fixed", "b", "a", ""),
    ]));
    assert!(e.contains("form a cycle") && e.contains("'r'"), "{e}");
    // Two roots.
    let e = error(&robot(&[link("a", 1.0), link("b", 1.0)]));
    assert!(e.contains("several root links ('a', 'b')"), "{e}");
    // Zero axis on a moving joint; unknown type; bad number.
    bad[2] = joint("j", "revolute", "base", "a", r#"<axis xyz="0 0 0"/>"#);
    assert!(error(&robot(&bad)).contains("joint 'j': <axis xyz>: expected a non-zero vector"));
    bad[2] = joint("j", "ball", "base", "a", "");
    assert!(error(&robot(&bad)).contains("unknown joint type 'ball'"));
    bad[2] = joint("j", "revolute", "base", "a", r#"<origin xyz="1 x 2"/>"#);
    let e = error(&robot(&bad));
    assert!(
        e.contains("joint 'j': <origin xyz>: expected three finite numbers, got '1 x 2'"),
        "{e}"
    );
    assert!(error("<robot/>").contains("no <link> elements"));
    assert!(error("<model/>").contains("expected a <robot> root element"));
}

#[test]
fn errors_carry_their_location() {
    use crate::support::error::{Error, FileKind, Location};
    let located =
        |text: &str| match model_from_urdf(text, "t.urdf", None, RootJoint::Fixed).unwrap_err() {
            Error::File { kind, at, .. } => (kind, at),
            other => panic!("not a file error: {other}"),
        };
    let (kind, at) = located("<robot name=\"r\">\n<link name=\"a\">\n</robot>\n");
    assert_eq!(kind, FileKind::Urdf);
    assert_eq!(
        (at.file.as_str(), at.key.as_str(), at.line),
        ("t.urdf", "", Some(3))
    );
    assert!(at.column.is_some());
    let (_, at) = located(&base_and_a(r#"<axis xyz="0 0 0"/>"#));
    assert_eq!(at, Location::new("t.urdf", "joint 'j'").at_line(5));
}

fn load_repaired(text: &str, r: &Repair) -> Result<Urdf> {
    model_from_urdf_with(text, "t.urdf", None, RootJoint::Fixed, Some(r), &[])
}

#[test]
fn triangle_violation_refused_with_the_option_named_then_balanced() {
    let bad = robot(&[
        link("base", 1.0),
        format!(
            r#"<link name="a">{}</link>"#,
            inertial(2.0, "0.1 0 0", "0.3 0.2 0.1", [1e-3, 1e-3, 1e-2])
        ),
        revolute("j", "base", "a"),
    ]);
    let e = error(&bad);
    assert!(e.contains("triangle") && e.contains("repair=True"), "{e}");
    let u = load_repaired(&bad, &Repair::default()).unwrap();
    assert_eq!(u.repairs().len(), 1);
    assert_eq!(u.repairs()[0].rules, ["balance_inertia"]);
    // MuJoCo's rule: all three principal moments become their mean, 4e-3, about the COM.
    let body = u.model.link_bodies()[0];
    assert!((body.inertia - Mat3::identity() * 4e-3).abs().max() < 1e-17);
    assert_eq!(body.mass, 2.0);
}

#[test]
fn massless_leaf_welded_and_recorded() {
    let text = robot(&[
        link("base", 1.0),
        link("a", 1.0),
        r#"<link name="tip"/>"#.to_string(),
        revolute("j", "base", "a"),
        revolute("k", "a", "tip"),
    ]);
    assert!(error(&text).contains("repair=True"));
    let u = load_repaired(&text, &Repair::default()).unwrap();
    assert_eq!(u.model.nv, 1);
    assert_eq!(u.joint("k").unwrap().kind, "fixed");
    let r = &u.repairs()[0];
    assert_eq!(r.joint.as_deref(), Some("k"));
    assert_eq!(
        r.joint_type,
        Some(("revolute".to_string(), "fixed".to_string()))
    );
    // Without welding, MuJoCo's bounds give it a tiny body instead.
    let bounded = Repair {
        bound_mass: 1e-6,
        bound_inertia: 1e-9,
        weld_massless: false,
        ..Repair::default()
    };
    let u = load_repaired(&text, &bounded).unwrap();
    assert_eq!(u.model.nv, 2);
    assert_eq!(u.model.link_bodies()[1].mass, 1e-6);
}

#[test]
fn undeclared_prefix_accepted_and_its_elements_ignored() {
    let text = robot(&[
        link("base", 1.0),
        r#"<link name="a" drake:x="1"><drake:joint name="q"/></link>"#.to_string(),
        revolute("j", "base", "a"),
        r#"<drake:joint name="z" type="planar"/>"#.to_string(),
    ])
    .replace(
        r#"<link name="a" drake:x="1">"#,
        &format!(
            r#"<link name="a" drake:x="1">{}"#,
            inertial(1.0, "0 0 0", "0 0 0", [1.0, 1.0, 1.0])
        ),
    );
    let u = load(&text);
    assert_eq!(u.model.nv, 1);
    assert!(
        u.warnings.iter().any(|w| w.contains("'drake:'")),
        "{:?}",
        u.warnings
    );
    assert!(
        u.warnings.iter().any(|w| w.contains("<drake:joint>")),
        "{:?}",
        u.warnings
    );
}

#[test]
fn parts_keep_order_and_allow_massless_intermediates() {
    let part = |name: &str, parent: Option<usize>, joint: Joint, mass: f64| Part {
        name: name.to_string(),
        parent,
        placement: crate::support::spatial::Placement::identity(),
        joint,
        joint_name: format!("{name}_j"),
        mass,
        com: Vec3::new(0.1, 0.0, 0.0),
        inertia: Mat3::identity() * mass * 0.01,
        range: None,
    };
    let x = Joint::revolute(Vec3::x()).unwrap();
    let z = Joint::revolute(Vec3::z()).unwrap();
    let u = model_from_parts(&[
        part("b/h1", None, x, 0.0),
        part("b", Some(0), z, 2.0),
        part("c", None, Joint::Spherical, 1.0),
    ])
    .unwrap();
    assert_eq!(u.model.nv, 5);
    let names: Vec<&str> = u.joints().iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["b/h1_j", "b_j", "c_j"]);
    assert_eq!(u.joints()[2].kind, "spherical");
    // A massless body that moves nothing is refused.
    let e = model_from_parts(&[part("lonely", None, x, 0.0)]).unwrap_err();
    assert!(e.to_string().contains("moves nothing"), "{e}");
}

#[test]
fn visuals_are_kept_on_the_links_bodies_with_their_materials() {
    let arm = format!(
        r#"<link name="a">{}<visual><origin xyz="0 0 0.5" rpy="0 0 0"/><geometry><cylinder radius="0.1" length="1"/></geometry><material name="steel"/></visual><visual><geometry><mesh filename="package://nowhere/a.stl" scale="1 -1 1"/></geometry></visual><visual><geometry><torus/></geometry></visual></link>"#,
        inertial(1.0, "0.1 0 0", "0 0 0", [0.01, 0.02, 0.02])
    );
    let text = robot(&[
        r#"<material name="steel"><color rgba="0.5 0.5 0.6 1"/></material>"#.to_string(),
        link("base", 1.0),
        arm,
        revolute("j", "base", "a"),
    ]);
    let u = load(&text);
    let m = &u.model;
    assert_eq!(m.visuals.len(), 2);
    let a = m.body_index("a").unwrap();
    assert_eq!(m.visuals[0].body, a);
    assert_eq!(
        m.visuals[0].shape,
        crate::model::visual::Shape::Cylinder {
            radius: 0.1,
            length: 1.0
        }
    );
    assert_eq!(m.visuals[0].rgba, Some([0.5, 0.5, 0.6, 1.0]));
    assert_eq!(m.visuals[0].origin.translation, Vec3::new(0.0, 0.0, 0.5));
    let crate::model::visual::Shape::Mesh { uri, path, scale } = &m.visuals[1].shape else {
        panic!("{:?}", m.visuals[1])
    };
    assert_eq!(uri, "package://nowhere/a.stl");
    assert!(path.is_none());
    assert_eq!(*scale, Vec3::new(1.0, -1.0, 1.0));
    // One warning names the mesh not found; one the geometry that could not be read.
    let missing: Vec<_> = u
        .warnings
        .iter()
        .filter(|w| w.contains("not found"))
        .collect();
    assert_eq!(missing.len(), 1, "{:?}", u.warnings);
    assert!(missing[0].contains("package://nowhere/a.stl"));
    assert!(u
        .warnings
        .iter()
        .any(|w| w.contains("link 'a'") && w.contains("<torus>")));
    assert!(m.check_structure().is_ok());
}
