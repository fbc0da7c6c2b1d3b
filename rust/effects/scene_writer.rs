//! The scene-file writer's side of `[[effect]]` tables: each declaration's
//! [`super::Declaration::to_toml`] builds its table with these helpers, so that
//! `Effect::from_toml` of the table gives back an equal declaration (`scene_file.rs` reads
//! what is written here). Numbers are written as floats: TOML keeps an `f64` exactly (the
//! shortest decimal that rounds back to it; `inf` and `-inf` are TOML values too).
use super::{JointRef, PerJoint, Table};
use crate::support::spatial::Vec3;
use toml::Value;

/// An `[[effect]]` table under construction: `type` first, then `name` if given.
pub struct EffectTable(toml::Table);

impl EffectTable {
    pub fn new(ty: &str, name: Option<&str>) -> Self {
        let mut t = toml::Table::new();
        t.insert("type".into(), Value::String(ty.into()));
        if let Some(n) = name {
            t.insert("name".into(), Value::String(n.into()));
        }
        EffectTable(t)
    }

    pub fn set(mut self, key: &str, value: Value) -> Self {
        self.0.insert(key.into(), value);
        self
    }

    /// Sets `key` when `value` is given.
    pub fn maybe(self, key: &str, value: Option<Value>) -> Self {
        match value {
            Some(v) => self.set(key, v),
            None => self,
        }
    }

    /// `joints` as a list of names or indices; nothing for "every joint".
    pub fn joints(self, joints: &Option<Vec<JointRef>>) -> Self {
        let v = joints
            .as_ref()
            .map(|js| Value::Array(js.iter().map(joint_ref).collect()));
        self.maybe("joints", v)
    }

    pub fn done(self) -> toml::Table {
        self.0
    }
}

pub fn number(x: f64) -> Value {
    Value::Float(x)
}

pub fn numbers(xs: &[f64]) -> Value {
    Value::Array(xs.iter().map(|x| number(*x)).collect())
}

pub fn vec3(v: &Vec3) -> Value {
    numbers(v.as_slice())
}

pub fn joint_ref(r: &JointRef) -> Value {
    match r {
        JointRef::Name(n) => Value::String(n.clone()),
        JointRef::Index(i) => Value::Integer(*i as i64),
    }
}

pub fn per_joint(p: &PerJoint) -> Value {
    match p {
        PerJoint::All(x) => number(*x),
        PerJoint::Each(xs) => numbers(xs),
    }
}

/// Row-major `values` of `cols` columns as rows, or as one flat list if `one_d`.
pub fn rows(values: &[f64], cols: usize, one_d: bool) -> Value {
    if one_d || cols == 0 {
        return numbers(values);
    }
    Value::Array(values.chunks(cols).map(numbers).collect())
}

/// A table's `time` and its values (under `values_key`) as the reader takes them.
pub fn table(t: EffectTable, table: &Table, values_key: &str) -> EffectTable {
    t.set("time", numbers(table.time())).set(
        values_key,
        rows(table.values(), table.cols(), table.one_d()),
    )
}
