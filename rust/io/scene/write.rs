//! A scene as a scene file ([`Scene::to_toml`]): what [`Scene::from_toml`] reads back as an
//! equal scene, whatever built it (a file, Python, a URDF, MuJoCo or Pinocchio import).
//!
//! The model is written inline, body by body (`[[body]]` with its own inertial, joint,
//! placement, point-mass centre and armature; `[[loop]]`, `[[coupling]]`), never as a
//! reference to the file it came from: the file stands alone, and a model changed after
//! loading (a body replaced, a coupling added) is written as it is. What is no part of the
//! dynamics (the source file's joints with their names and limits, repairs, visuals, the
//! model's name) goes to `[records]`. Angles are radians; every number is written as the
//! shortest decimal that reads back to the same `f64`.
use super::Scene;
use crate::effects::scene_writer::{number, numbers, vec3};
use crate::joint::Joint;
use crate::model::Model;
use crate::support::error::{Error, Result};
use crate::support::spatial::{Mat3, Placement};
use toml::Value;

/// `[records]`: what the model keeps beside the dynamics (`crate::model::joint_records`).
#[derive(Default, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RecordsFile {
    #[serde(default)]
    pub model: String,
    #[serde(default)]
    pub joints: Vec<crate::model::joint_records::UrdfJoint>,
    #[serde(default)]
    pub repairs: Vec<crate::model::joint_records::RepairRecord>,
    #[serde(default)]
    pub visuals: Vec<crate::model::visual::Visual>,
}

fn rows(m: &Mat3) -> Value {
    Value::Array(
        (0..3)
            .map(|i| numbers(&[m[(i, 0)], m[(i, 1)], m[(i, 2)]]))
            .collect(),
    )
}

fn string(s: &str) -> Value {
    Value::String(s.to_string())
}

fn joint(j: &Joint) -> Value {
    let mut t = toml::Table::new();
    t.insert("type".into(), string(j.kind()));
    if let Some(a) = j.axis() {
        t.insert("axis".into(), vec3(&a));
    }
    Value::Table(t)
}

/// Sets `translation`/`rotation` keys (with `suffix`) of a placement; identity parts are
/// left out.
fn placement(t: &mut toml::Table, p: &Placement, suffix: &str) {
    if p.translation != crate::support::spatial::Vec3::zeros() {
        t.insert(format!("translation{suffix}"), vec3(&p.translation));
    }
    if p.rotation != Mat3::identity() {
        t.insert(format!("rotation{suffix}"), rows(&p.rotation));
    }
}

fn bodies(m: &Model) -> Vec<Value> {
    m.bodies
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let mut t = toml::Table::new();
            t.insert("name".into(), string(&b.name));
            if let Some(p) = b.parent {
                t.insert("parent".into(), string(&m.bodies[p].name));
            }
            t.insert("joint".into(), joint(&b.joint));
            placement(&mut t, &b.placement, "");
            t.insert("mass".into(), number(b.body.mass));
            t.insert("com".into(), vec3(&b.body.com));
            t.insert("inertia".into(), rows(&b.body.inertia));
            if let Some(c) = &b.point_mass_center {
                t.insert("point_mass_center".into(), vec3(c));
            }
            // Rotor inertia of the body's own joint, if any is non-zero.
            let own = b.link.map(|l| &m.links[l]).filter(|l| l.body == k);
            if let (Some(l), false) = (own, m.armature.is_empty()) {
                let a = &m.armature[l.v_index..l.v_index + l.joint.nv()];
                if a.iter().any(|x| *x != 0.0) {
                    t.insert("armature".into(), numbers(a));
                }
            }
            Value::Table(t)
        })
        .collect()
}

fn loops(m: &Model) -> Vec<Value> {
    let body = |b: Option<usize>| string(b.map_or("world", |b| m.bodies[b].name.as_str()));
    m.loops
        .iter()
        .map(|l| {
            let mut t = toml::Table::new();
            t.insert("name".into(), string(&l.name));
            t.insert("body_a".into(), body(l.body_a));
            t.insert("body_b".into(), body(l.body_b));
            t.insert("joint".into(), joint(&l.joint));
            placement(&mut t, &l.frame_a, "_a");
            placement(&mut t, &l.frame_b, "_b");
            Value::Table(t)
        })
        .collect()
}

fn couplings(m: &Model) -> Vec<Value> {
    m.couplings
        .iter()
        .map(|c| {
            let mut t = toml::Table::new();
            t.insert("name".into(), string(&c.name));
            t.insert("joint".into(), string(&m.bodies[c.joint].name));
            t.insert("reference".into(), string(&m.bodies[c.reference].name));
            t.insert("ratio".into(), number(c.ratio));
            t.insert("offset".into(), number(c.offset));
            Value::Table(t)
        })
        .collect()
}

fn records(m: &Model) -> Result<Option<Value>> {
    let r = RecordsFile {
        model: m.name.clone(),
        joints: m.records.joints.clone(),
        repairs: m.records.repairs.clone(),
        visuals: m.visuals.clone(),
    };
    if r.model.is_empty() && r.joints.is_empty() && r.repairs.is_empty() && r.visuals.is_empty() {
        return Ok(None);
    }
    Value::try_from(&r)
        .map(Some)
        .map_err(|e| Error::arg("model", "records a scene file can hold", e.to_string()))
}

fn simulate(s: &super::Settings) -> toml::Table {
    let mut t = toml::Table::new();
    let mut put = |k: &str, v: Option<Value>| {
        if let Some(v) = v {
            t.insert(k.into(), v);
        }
    };
    put("t_span", s.t_span.map(|(a, b)| numbers(&[a, b])));
    put("rtol", s.rtol.map(number));
    put("atol", s.atol.map(number));
    put("max_step", s.max_step.map(number));
    put("max_steps", s.max_steps.map(|n| Value::Integer(n as i64)));
    put("first_step", s.first_step.map(number));
    put(
        "disable",
        s.disable
            .map(|d| Value::Array(d.names().into_iter().map(string).collect())),
    );
    put("method", s.method.map(|m| string(m.name())));
    put("dt", s.dt.map(number));
    t
}

impl Scene {
    /// The scene as scene-file text that [`Scene::from_toml`] reads back as an equal scene
    /// (model, effects, start state and settings); see the module docs. An effect no file
    /// can state (a Python-function torque) is an error naming it.
    pub fn to_toml(&self) -> Result<String> {
        let m = &*self.model;
        let mut doc = toml::Table::new();
        doc.insert("name".into(), string(&self.name));
        doc.insert("description".into(), string(&self.description));
        let mut initial = toml::Table::new();
        initial.insert("q0".into(), numbers(&self.q0));
        initial.insert("v0".into(), numbers(&self.v0));
        doc.insert("initial".into(), Value::Table(initial));
        doc.insert("body".into(), Value::Array(bodies(m)));
        if !m.loops.is_empty() {
            doc.insert("loop".into(), Value::Array(loops(m)));
        }
        if !m.couplings.is_empty() {
            doc.insert("coupling".into(), Value::Array(couplings(m)));
        }
        if let Some(r) = records(m)? {
            doc.insert("records".into(), r);
        }
        let effects = self
            .effects
            .iter()
            .enumerate()
            .map(|(k, e)| {
                e.to_toml()
                    .map(Value::Table)
                    .map_err(|x| x.map_arg(|_| format!("effects[{k}]")))
            })
            .collect::<Result<Vec<_>>>()?;
        if !effects.is_empty() {
            doc.insert("effect".into(), Value::Array(effects));
        }
        let sim = simulate(&self.settings);
        if !sim.is_empty() {
            doc.insert("simulate".into(), Value::Table(sim));
        }
        toml::to_string(&doc)
            .map_err(|e| Error::arg("scene", "a scene a TOML file can hold", e.to_string()))
    }

    /// Writes [`Scene::to_toml`] to `path`; errors name the path.
    pub fn write(&self, path: &std::path::Path) -> Result<()> {
        let text = self.to_toml()?;
        std::fs::write(path, text).map_err(|e| {
            let at =
                crate::support::error::Location::new(crate::support::files::display_path(path), "");
            Error::file(
                crate::support::error::FileKind::Scene,
                at,
                format!("cannot write: {e}"),
            )
        })
    }
}
