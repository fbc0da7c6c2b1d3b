//! A toy effect, compiled in the test build only: the complete file that
//! docs/adding-an-effect.md shows (tests/test_guides.py holds the guide's copy equal to this
//! file). A spring pulling each selected revolute or prismatic joint to `q = 0`: `τ = −k q`,
//! potential `V = ½ k q²`, power `−k q v`.
use super::scene_writer as w;
use super::{check_values, joints_repr, label_repr, one_number, required, resolve_joints};
use super::{Context, Declaration, Effect, Fields, ForceLaw, JointRef, Kind, Sign, TomlType};
use crate::kinematics::LinkState;
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::Vec6;

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ToySpring {
    pub name: Option<String>,
    /// `None`: every moving joint (each must be revolute or prismatic).
    pub joints: Option<Vec<JointRef>>,
    /// N·m/rad or N/m, the same for every selected joint.
    pub stiffness: f64,
}

impl ToySpring {
    pub fn new(
        name: Option<String>,
        joints: Option<Vec<JointRef>>,
        stiffness: f64,
    ) -> Result<ToySpring> {
        check_values("stiffness", &[stiffness], Sign::NonNegative)?;
        Ok(ToySpring {
            name,
            joints,
            stiffness,
        })
    }

    fn from_toml(f: &mut Fields<'_>) -> Result<ToySpring> {
        let (name, joints) = f.name_and_joints()?;
        let stiffness = f.number("stiffness")?;
        let stiffness = required(stiffness, "stiffness", "a number >= 0")?;
        ToySpring::new(name, joints, stiffness)
    }
}

impl Declaration for ToySpring {
    fn kind(&self) -> Kind {
        Kind::Springs
    }
    fn label(&self) -> Option<&str> {
        self.name.as_deref()
    }
    fn build(&self, model: &Model) -> Result<Box<dyn ForceLaw>> {
        let mut dofs = Vec::new();
        for s in resolve_joints(model, &self.joints, "joints")? {
            if s.joint.nq() != 1 || s.joint.nv() != 1 {
                let got = format!("'{}' on a {} joint", s.name, s.joint.kind());
                return Err(Error::arg("joints", "revolute or prismatic joints", got));
            }
            dofs.push((s.q_index, s.v_index));
        }
        let k = self.stiffness;
        Ok(Box::new(ToySpringLaw { dofs, k }))
    }
    fn parameters(&self) -> &'static [&'static str] {
        &["stiffness"]
    }
    fn with_parameter(&self, key: &str, values: &[f64]) -> Result<Effect> {
        let k = one_number(key, values)?;
        let e = ToySpring::new(self.name.clone(), self.joints.clone(), k)?;
        Ok(Effect::ToySpring(e))
    }
    fn repr(&self) -> String {
        let label = label_repr(self.label());
        format!("ToySpring(joints={}{label})", joints_repr(&self.joints))
    }
    fn to_toml(&self) -> Result<toml::Table> {
        Ok(w::EffectTable::new("toy_spring", self.label())
            .joints(&self.joints)
            .set("stiffness", w::number(self.stiffness))
            .done())
    }
    fn toml_types() -> &'static [TomlType] {
        const TYPES: &[TomlType] = &[TomlType {
            name: "toy_spring",
            keys: &["name", "joints", "stiffness"],
            parse: |_, f| ToySpring::from_toml(f).map(Effect::ToySpring),
        }];
        TYPES
    }
}

/// `(q index, v index)` of each sprung joint, resolved once.
struct ToySpringLaw {
    dofs: Vec<(usize, usize)>,
    k: f64,
}

impl ForceLaw for ToySpringLaw {
    fn apply(
        &mut self,
        cx: &Context<'_>,
        tau: &mut [f64],
        _wrenches: &mut [Vec6],
    ) -> std::result::Result<bool, String> {
        for &(iq, iv) in &self.dofs {
            tau[iv] -= self.k * cx.q[iq];
        }
        Ok(false)
    }

    fn potential_energy(&self, cx: &Context<'_>, _links: &[LinkState]) -> Option<f64> {
        let v = self.dofs.iter().map(|&(iq, _)| cx.q[iq] * cx.q[iq]);
        Some(0.5 * self.k * v.sum::<f64>())
    }

    /// `∂τ/∂q = −k` on each sprung joint (a 1-dof joint's tangent is its coordinate).
    fn add_derivatives(
        &mut self,
        _cx: &Context<'_>,
        dq: &mut nalgebra::DMatrix<f64>,
        _dv: &mut nalgebra::DMatrix<f64>,
    ) -> std::result::Result<bool, String> {
        for &(_, iv) in &self.dofs {
            dq[(iv, iv)] -= self.k;
        }
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::effects::Disabled;
    use crate::joint::Joint;
    use crate::model::body::RigidBody;
    use crate::simulate::Dynamics;
    use crate::support::spatial::{Mat3, Placement, Vec3};

    /// A scene file's table, through the registry, against the pendulum's analytic values.
    #[test]
    fn the_toy_spring_runs_through_the_registry() {
        // 2 kg, COM 0.5 m out on x, I_zz = 0.03 about the COM: 0.53 kg·m² about the axis.
        let inertia = Mat3::from_diagonal(&Vec3::new(0.01, 0.02, 0.03));
        let body = RigidBody::new(2.0, Vec3::new(0.5, 0.0, 0.0), inertia).unwrap();
        let mut m = Model::new();
        let joint = Joint::revolute(Vec3::z()).unwrap();
        m.add_body(body, joint, None, Placement::identity(), None, None)
            .unwrap();
        let table: toml::Table = "type = 'toy_spring'\nstiffness = 4.0".parse().unwrap();
        let e = Effect::from_toml(&table).unwrap();
        assert_eq!(e.repr(), "ToySpring(joints=all)");
        assert_eq!(Effect::from_toml(&e.to_toml().unwrap()).unwrap(), e);
        let mut sys = Dynamics::try_new(&m, std::slice::from_ref(&e), Disabled::none()).unwrap();
        let (q, v) = ([0.3], [0.0]);
        let mut a = [0.0];
        sys.accelerations(0.0, &q, &v, &mut a).unwrap();
        assert!((a[0] - (-4.0 * 0.3 / 0.53)).abs() < 1e-12, "{a:?}");
        let (_, potentials) = sys.energies(&q, &v);
        assert!((potentials[0].1 - 0.5 * 4.0 * 0.09).abs() < 1e-15);
        // A batch's parameter, and the refusals that name the field.
        let stiffer = e.with_parameter("stiffness", &[8.0]).unwrap();
        assert!(matches!(
            stiffer,
            Effect::ToySpring(ToySpring { stiffness: 8.0, .. })
        ));
        assert!(e.with_parameter("stiffness", &[-1.0]).is_err());
        let mut ball = Model::new();
        let ball_joint = Joint::Spherical;
        ball.add_body(body, ball_joint, None, Placement::identity(), None, None)
            .unwrap();
        let err = e.build(&ball).err().unwrap().to_string();
        assert!(
            err.starts_with("joints: expected revolute or prismatic"),
            "{err}"
        );
    }
}
