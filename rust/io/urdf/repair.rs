//! Opt-in repairs of a URDF's inertials (docs/robots.md §Repairs): MuJoCo's compiler
//! options `boundmass`, `boundinertia` and `balanceinertia`, applied as MuJoCo applies them
//! (per link, to the link's own `<inertial>`, before the fixed joints merge links into
//! bodies), and the welding of moving joints that move no mass. Every change is recorded.
//! The reader (`parse`) only reads: each link's inertial is repaired, then checked, here
//! ([`inertials`]), before the tree is built.
use super::parse::{Inertial, Kind, RobotData};
use super::tree::Tree;
use super::RepairRecord;
use crate::model::body::RigidBody;
use crate::support::args::{flag, given, Arg};
use crate::support::error::Error;
use crate::support::spatial::{Mat3, Vec3};

/// Which repairs a load may make (`Model.from_urdf(..., repair=...)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Repair {
    /// MuJoCo `balanceinertia`: principal moments violating `A + B ≥ C` all become their mean.
    pub balance_inertia: bool,
    /// MuJoCo `boundmass`: every link's mass is raised to at least this (kg).
    pub bound_mass: f64,
    /// MuJoCo `boundinertia`: every link's principal moments are raised to at least this
    /// (kg m²); with 0, negative moments are raised to 0.
    pub bound_inertia: f64,
    /// A moving joint whose child link and everything below it have no mass moves nothing:
    /// it is made fixed.
    pub weld_massless: bool,
}

impl Default for Repair {
    fn default() -> Self {
        Repair {
            balance_inertia: true,
            bound_mass: 0.0,
            bound_inertia: 0.0,
            weld_massless: true,
        }
    }
}

impl Repair {
    /// `repair=` as a caller writes it: absent or false (no repairs), true (the defaults), a
    /// mapping of the fields, or an object with them all as attributes (`pmd.InertiaRepair`).
    pub fn parse<A: Arg>(x: Option<&A>) -> Result<Option<Repair>, A::Err> {
        const FIELDS: [&str; 4] = [
            "balance_inertia",
            "bound_mass",
            "bound_inertia",
            "weld_massless",
        ];
        let expected = "None, False, True, a dict with keys balance_inertia, bound_mass, bound_inertia, weld_massless, or pmd.InertiaRepair(...)";
        let Some(x) = given(x) else { return Ok(None) };
        if x.is_bool() {
            return Ok(flag(x, "repair")?.then(Repair::default));
        }
        let keys = x.keys();
        let unknown = keys
            .iter()
            .flatten()
            .find(|k| !k.text().is_some_and(|k| FIELDS.contains(&k.as_str())));
        if let Some(k) = unknown {
            return Err(
                Error::arg("repair", expected, format!("a dict with key {}", k.shown())).into(),
            );
        }
        let mut out = Repair::default();
        for name in FIELDS {
            let v = match keys {
                Some(_) => x.get(name).flatten(),
                None => Some(
                    x.attr(name)
                        .ok_or_else(|| Error::arg("repair", expected, x.shown()))?,
                ),
            };
            let Some(v) = v else { continue };
            let arg = format!("repair.{name}");
            let bad = |want: &str| Error::arg(&arg, want, v.shown());
            // Not `flag`/`real`'s type errors: 1 is no bool, and True is not a 1 kg bound.
            let b = || match v.is_bool() {
                true => flag(&v, &arg),
                false => Err(bad("True or False").into()),
            };
            let x = || match v.is_bool() {
                true => None,
                false => v
                    .real(&arg)
                    .ok()
                    .filter(|x: &f64| x.is_finite() && *x >= 0.0),
            };
            let x = || x().ok_or_else(|| bad("a finite number >= 0"));
            match name {
                "balance_inertia" => out.balance_inertia = b()?,
                "weld_massless" => out.weld_massless = b()?,
                "bound_mass" => out.bound_mass = x()?,
                _ => out.bound_inertia = x()?,
            }
        }
        Ok(Some(out))
    }
}

/// Every link's inertial after reading: the opt-in repairs (`repair`; MuJoCo bounds every
/// body, those without `<inertial>` too), then the check of what remains ([`validated`]).
/// Returns the repairs made, in file order.
pub(super) fn inertials(robot: &mut RobotData, repair: Option<&Repair>) -> Vec<RepairRecord> {
    let mut repairs = Vec::new();
    for link in &mut robot.links {
        let mut inertial = link.inertial;
        let line = link.inertial_line;
        if let Some((fixed, record)) =
            repair.and_then(|r| repair_inertial(&link.name, &inertial, r))
        {
            inertial = fixed;
            repairs.push(record);
        }
        let (inertial, invalid) = if link.has_inertial || inertial.mass > 0.0 {
            let (i, m) = validated(inertial, line, repair.is_some());
            (i, m.map(|message| (line, message)))
        } else {
            (inertial, None)
        };
        link.inertial = inertial;
        link.invalid = invalid;
    }
    repairs
}

/// What `repair` would do about an invalid inertia, for the error of a load without it.
const REPAIR_HINT: &str = "Model.from_urdf(..., repair=True) loads it as MuJoCo's compiler options balanceinertia/boundinertia would (docs/robots.md)";

/// Validates a link's own body with our RigidBody's rules and messages. Mass 0 is a massless
/// link (checked later against the tree); its tensor must still be physical. Tolerances
/// scale with the link's inertia about its origin, m (|c|² + (1 mm)²): files written from
/// CAD carry rounding noise (iCub's head: a point mass with ixz = 2.4e-35) that is no error
/// at the scale the link enters the dynamics. A tensor accepted only at that scale is
/// replaced by the nearest physical one (a change of that rounding size), since the
/// point-mass solver must not see a non-physical tensor.
fn validated(inertial: Inertial, line: u32, repaired: bool) -> (Inertial, Option<String>) {
    let hint = if repaired {
        String::new()
    } else {
        format!("; {REPAIR_HINT}")
    };
    let Inertial { mass, com, inertia } = inertial;
    let (check_mass, scale) = if mass == 0.0 {
        (1.0, 0.0)
    } else {
        (mass, mass * (com.norm_squared() + 1e-6))
    };
    if RigidBody::new(check_mass, com, inertia).is_ok() {
        return (inertial, None);
    }
    match RigidBody::new_with_scale(check_mass, com, inertia, scale) {
        Ok(_) => (
            Inertial {
                inertia: nearest_physical(&inertia),
                ..inertial
            },
            None,
        ),
        Err(Error::InvalidInertia { arg, reason }) if arg == "mass" => (
            inertial,
            Some(format!("<inertial><mass value>: {reason} (line {line})")),
        ),
        Err(e) => (
            inertial,
            Some(format!("<inertial>: {e} (line {line}){hint}")),
        ),
    }
}

/// The physical inertia nearest `i` in principal second moments: `σ_k = ½(λ_i + λ_j − λ_k)`
/// clamped at 0, `λ'_k = σ_i + σ_j`, same principal axes.
fn nearest_physical(i: &Mat3) -> Mat3 {
    let eig = i.symmetric_eigen();
    let l = eig.eigenvalues;
    let s = Vec3::new(
        (0.5 * (l[1] + l[2] - l[0])).max(0.0),
        (0.5 * (l[0] + l[2] - l[1])).max(0.0),
        (0.5 * (l[0] + l[1] - l[2])).max(0.0),
    );
    let d = Vec3::new(s.y + s.z, s.x + s.z, s.x + s.y);
    let v = eig.eigenvectors;
    let out = v * Mat3::from_diagonal(&d) * v.transpose();
    (out + out.transpose()) * 0.5
}

/// Ascending principal moments and their axes (columns).
fn principal(i: &Mat3) -> ([f64; 3], Mat3) {
    let eig = i.symmetric_eigen();
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let l = [
        eig.eigenvalues[idx[0]],
        eig.eigenvalues[idx[1]],
        eig.eigenvalues[idx[2]],
    ];
    let v = Mat3::from_columns(&[
        eig.eigenvectors.column(idx[0]).into_owned(),
        eig.eigenvectors.column(idx[1]).into_owned(),
        eig.eigenvectors.column(idx[2]).into_owned(),
    ]);
    (l, v)
}

/// The link's own inertial under `r`, MuJoCo's order (user_objects.cc, mjCBody::Compile):
/// mass bound, principal-moment bound, then balance if `A + B < C` for any ordering (exact
/// comparison, as MuJoCo's). `None`: nothing changed (the tensor is kept bit for bit).
pub(super) fn repair_inertial(
    link: &str,
    inertial: &Inertial,
    r: &Repair,
) -> Option<(Inertial, RepairRecord)> {
    let mut rules = Vec::new();
    let mass = if inertial.mass < r.bound_mass {
        rules.push("bound_mass".to_string());
        r.bound_mass
    } else {
        inertial.mass
    };
    let (before, axes) = principal(&inertial.inertia);
    let mut after = before;
    if after.iter().any(|&l| l < r.bound_inertia) {
        rules.push("bound_inertia".to_string());
        for l in after.iter_mut() {
            *l = l.max(r.bound_inertia);
        }
    }
    let [a, b, c] = after;
    if r.balance_inertia && (a + b < c || a + c < b || b + c < a) {
        rules.push("balance_inertia".to_string());
        after = [(a + b + c) / 3.0; 3];
    }
    if rules.is_empty() {
        return None;
    }
    let inertia = if after == before {
        inertial.inertia
    } else {
        let t = axes * Mat3::from_diagonal(&Vec3::from(after)) * axes.transpose();
        (t + t.transpose()) * 0.5
    };
    Some((
        Inertial {
            mass,
            com: inertial.com,
            inertia,
        },
        RepairRecord {
            link: link.to_string(),
            joint: None,
            rules,
            mass: (inertial.mass, mass),
            principal_moments: (before, after),
            joint_type: None,
        },
    ))
}

/// Makes fixed every moving joint whose child link and all links below it have no mass (they
/// move nothing: the joint's acceleration is undetermined), from the leaves up.
pub(super) fn weld_massless(robot: &mut RobotData, tree: &Tree) -> Vec<RepairRecord> {
    let mut below = vec![0.0; robot.links.len()];
    for (l, link) in robot.links.iter().enumerate() {
        below[l] = link.inertial.mass;
    }
    for &j in tree.order.iter().rev() {
        below[tree.parent_link[j]] += below[tree.child_link[j]];
    }
    let mut records = Vec::new();
    for &j in &tree.order {
        let jd = &mut robot.joints[j];
        if jd.kind != Kind::Fixed && below[tree.child_link[j]] <= 0.0 {
            let m = robot.links[tree.child_link[j]].inertial.mass;
            let moments = principal(&robot.links[tree.child_link[j]].inertial.inertia).0;
            records.push(RepairRecord {
                link: jd.child.clone(),
                joint: Some(jd.name.clone()),
                rules: vec!["weld_massless".to_string()],
                mass: (m, m),
                principal_moments: (moments, moments),
                joint_type: Some((jd.kind.name().to_string(), "fixed".to_string())),
            });
            jd.kind = Kind::Fixed;
            jd.limit = None;
        }
    }
    records
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inertial(mass: f64, d: [f64; 3]) -> Inertial {
        Inertial {
            mass,
            com: Vec3::new(0.1, 0.0, 0.0),
            inertia: Mat3::from_diagonal(&Vec3::from(d)),
        }
    }

    #[test]
    fn balance_sets_the_mean_as_mujoco() {
        // PR2's sensor_mount_link: 1e-3, 1e-3, 1e-2 violates A + B >= C.
        let (out, rec) =
            repair_inertial("s", &inertial(0.05, [1e-3, 1e-3, 1e-2]), &Repair::default()).unwrap();
        let m = 4e-3;
        assert!((out.inertia - Mat3::identity() * m).abs().max() < 1e-18);
        assert_eq!(rec.rules, ["balance_inertia"]);
        assert_eq!(out.com, Vec3::new(0.1, 0.0, 0.0));
    }

    #[test]
    fn valid_inertial_untouched() {
        assert!(
            repair_inertial("s", &inertial(1.0, [1.0, 2.0, 2.5]), &Repair::default()).is_none()
        );
    }

    #[test]
    fn bounds_apply_before_balance() {
        let r = Repair {
            bound_mass: 1e-6,
            bound_inertia: 1e-9,
            ..Repair::default()
        };
        let (out, rec) = repair_inertial("s", &inertial(0.0, [0.0; 3]), &r).unwrap();
        assert_eq!(out.mass, 1e-6);
        assert_eq!(out.inertia, Mat3::identity() * 1e-9);
        assert_eq!(rec.rules, ["bound_mass", "bound_inertia"]);
        // A negative moment is raised to the bound, then the triangle is balanced.
        let (out, rec) =
            repair_inertial("s", &inertial(1.0, [-1e-3, 4e-2, 5e-2]), &Repair::default()).unwrap();
        assert_eq!(rec.rules, ["bound_inertia", "balance_inertia"]);
        assert!((out.inertia.trace() - 9e-2).abs() < 1e-15);
    }
}

impl super::Urdf {
    /// The warning listing the links and joints repaired, if any (`file` as shown).
    pub fn repairs_warning(&self, file: &str) -> Option<String> {
        let lines: Vec<String> = self.repairs().iter().map(|r| r.describe()).collect();
        (!lines.is_empty()).then(|| {
            let n = lines.len();
            let lines = lines.join("\n  ");
            format!("{file}: repaired {n} link(s)/joint(s) (model.repairs lists them):\n  {lines}")
        })
    }
}
