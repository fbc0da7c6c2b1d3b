//! The scene-file reader of `[[effect]]` tables: one table per effect, `type` selecting it;
//! every type but gravity takes an optional `name` (its output key; default the family's
//! name, numbered `springs_2`, ... from the second on). `joints` is a body name or index or a
//! list of them (omitted: every moving joint); per-joint numbers are one number or a list,
//! one per joint. Each effect's file declares its types and keys ([`TomlType`]); this file
//! holds the typed readers, whose errors name the key.
use super::{Effect, JointRef, PerJoint};
use crate::support::error::{check_finite, Error, Result};
use crate::support::spatial::Vec3;

/// One scene-file `type` of an effect: its name, its keys besides `type` (unknown keys are
/// refused against them) and its parser (given the type's name, for types sharing one).
pub struct TomlType {
    pub name: &'static str,
    pub keys: &'static [&'static str],
    pub parse: fn(&str, &mut Fields<'_>) -> Result<Effect>,
}

/// Parses one `[[effect]]` table against the registry's `types`.
pub(super) fn parse<'t>(
    table: &toml::Table,
    types: impl Iterator<Item = &'t TomlType> + Clone,
) -> Result<Effect> {
    let mut f = Fields::new(table);
    let ty = f.string("type")?;
    let found = find_type(ty.as_deref(), types)?;
    // A misspelt key first: it is usually why a required one is missing.
    check_keys(found, table.keys().filter(|k| *k != "type"))?;
    (found.parse)(found.name, &mut f)
}

/// The type named `ty` among `types`; an error naming `type` and listing them otherwise.
pub(super) fn find_type<'t>(
    ty: Option<&str>,
    mut types: impl Iterator<Item = &'t TomlType> + Clone,
) -> Result<&'t TomlType> {
    let names: Vec<String> = types.clone().map(|t| format!("\"{}\"", t.name)).collect();
    let one_of = format!("one of {}", names.join(", "));
    match ty {
        None => Err(Error::arg("type", one_of, "nothing")),
        Some(ty) => types
            .find(|t| t.name == ty)
            .ok_or_else(|| Error::arg("type", one_of, format!("\"{ty}\""))),
    }
}

/// Errors on a key that is not one of `ty`'s, listing those.
pub(super) fn check_keys<S: AsRef<str>>(
    ty: &TomlType,
    given: impl IntoIterator<Item = S>,
) -> Result<()> {
    for key in given {
        let key = key.as_ref();
        if !ty.keys.contains(&key) {
            let expected = format!(
                "a key of a \"{}\" effect (type, {})",
                ty.name,
                ty.keys.join(", ")
            );
            return Err(Error::arg(key, expected, "an unknown key"));
        }
    }
    Ok(())
}

/// The keys of one `[[effect]]` table, read with errors that name the key; `check_keys` refuses
/// unknown keys up front.
pub struct Fields<'a> {
    table: &'a toml::Table,
}

/// A key's value that must be given: `value`, or an error naming `key`, what was `expected`
/// and "nothing".
pub fn required<T>(value: Option<T>, key: &str, expected: &str) -> Result<T> {
    value.ok_or_else(|| Error::arg(key, expected, "nothing"))
}

fn toml_got(v: &toml::Value) -> String {
    let s = v.to_string();
    if s.len() > 60 {
        format!(
            "{}...",
            &s[..s.char_indices().nth(57).map(|(i, _)| i).unwrap_or(s.len())]
        )
    } else {
        s
    }
}

fn toml_number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

impl<'a> Fields<'a> {
    pub fn new(table: &'a toml::Table) -> Self {
        Fields { table }
    }

    pub fn get(&mut self, key: &'static str) -> Option<&'a toml::Value> {
        self.table.get(key)
    }

    pub fn has(&self, key: &str) -> bool {
        self.table.contains_key(key)
    }

    /// `key`'s value as `convert` reads it, `None` when the key is absent; an error naming
    /// the key and what was `expected` when `convert` refuses the value.
    pub(super) fn typed<T>(
        &mut self,
        key: &'static str,
        expected: &str,
        convert: impl Fn(&toml::Value) -> Option<T>,
    ) -> Result<Option<T>> {
        match self.get(key) {
            None => Ok(None),
            Some(v) => convert(v)
                .map(Some)
                .ok_or_else(|| Error::arg(key, expected, toml_got(v))),
        }
    }

    pub fn string(&mut self, key: &'static str) -> Result<Option<String>> {
        self.typed(key, "a string", |v| v.as_str().map(str::to_string))
    }

    pub fn number(&mut self, key: &'static str) -> Result<Option<f64>> {
        self.typed(key, "a number", toml_number)
    }

    pub fn list(&mut self, key: &'static str) -> Result<Option<Vec<f64>>> {
        self.typed(key, "a list of numbers", list_of_numbers)
    }

    pub fn vec3(&mut self, key: &'static str) -> Result<Option<Vec3>> {
        let x = self.typed(key, "a list of 3 numbers", |v| {
            list_of_numbers(v).filter(|x| x.len() == 3)
        })?;
        match x {
            None => Ok(None),
            Some(x) => {
                check_finite(key, &x)?;
                Ok(Some(Vec3::new(x[0], x[1], x[2])))
            }
        }
    }

    /// The `name` and `joints` keys of an effect on joints.
    pub fn name_and_joints(&mut self) -> Result<(Option<String>, Option<Vec<JointRef>>)> {
        Ok((self.string("name")?, self.joints("joints")?))
    }

    /// A number (for all joints) or a list of numbers (one per joint).
    pub fn per_joint(&mut self, key: &'static str) -> Result<Option<PerJoint>> {
        self.typed(key, "a number or a list of numbers", |v| {
            toml_number(v)
                .map(PerJoint::All)
                .or_else(|| list_of_numbers(v).map(PerJoint::Each))
        })
    }

    /// A body name or index, or a list of them.
    pub fn joints(&mut self, key: &'static str) -> Result<Option<Vec<JointRef>>> {
        let one = |v: &toml::Value| -> Option<JointRef> {
            match v {
                toml::Value::String(s) => Some(JointRef::Name(s.clone())),
                toml::Value::Integer(i) if *i >= 0 => Some(JointRef::Index(*i as usize)),
                _ => None,
            }
        };
        self.typed(
            key,
            "a body name or index (>= 0), or a list of them",
            |v| match v {
                toml::Value::Array(a) => a.iter().map(one).collect(),
                _ => one(v).map(|r| vec![r]),
            },
        )
    }

    /// A table of numbers: a list (one column) or a list of equal-length rows. Returns
    /// `(values row-major, rows, cols, given as one list)`.
    pub fn matrix(&mut self, key: &'static str) -> Result<Option<Matrix>> {
        match self.get(key) {
            None => Ok(None),
            Some(v) => {
                if let Some(x) = list_of_numbers(v) {
                    let n = x.len();
                    return Ok(Some(Matrix {
                        values: x,
                        rows: n,
                        cols: 1,
                        one_d: true,
                    }));
                }
                let bad = || {
                    Error::arg(
                        key,
                        "a list of numbers or a list of rows of numbers",
                        toml_got(v),
                    )
                };
                let toml::Value::Array(rows) = v else {
                    return Err(bad());
                };
                let mut values = Vec::new();
                let mut cols = None;
                for (i, r) in rows.iter().enumerate() {
                    let row = list_of_numbers(r).ok_or_else(bad)?;
                    match cols {
                        None => cols = Some(row.len()),
                        Some(c) if c != row.len() => {
                            return Err(Error::arg(
                                key,
                                format!("rows of equal length ({c})"),
                                format!("row {i} of length {}", row.len()),
                            ))
                        }
                        _ => {}
                    }
                    values.extend(row);
                }
                Ok(Some(Matrix {
                    values,
                    rows: rows.len(),
                    cols: cols.unwrap_or(0),
                    one_d: false,
                }))
            }
        }
    }
}

fn list_of_numbers(v: &toml::Value) -> Option<Vec<f64>> {
    match v {
        toml::Value::Array(a) => a.iter().map(toml_number).collect(),
        _ => None,
    }
}

/// A numeric table as given (row-major).
#[derive(Debug, Clone, PartialEq)]
pub struct Matrix {
    pub values: Vec<f64>,
    pub rows: usize,
    pub cols: usize,
    /// Given as a flat list (shape `(rows,)`).
    pub one_d: bool,
}

impl Matrix {
    pub fn shape(&self) -> String {
        if self.one_d {
            format!("shape ({},)", self.rows)
        } else {
            format!("shape ({}, {})", self.rows, self.cols)
        }
    }
}
