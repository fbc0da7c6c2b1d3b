//! Effect families: what the global `disable` switch turns off (MuJoCo-style), and the set
//! of disabled ones.
use crate::support::error::{Error, Result};

/// Effect families: what a global disable switch turns off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kind {
    Gravity,
    Springs,
    Dampers,
    Friction,
    Torques,
    External,
    Contact,
    Limits,
}

impl Kind {
    pub const ALL: [Kind; 8] = [
        Kind::Gravity,
        Kind::Springs,
        Kind::Dampers,
        Kind::Friction,
        Kind::Torques,
        Kind::External,
        Kind::Contact,
        Kind::Limits,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Kind::Gravity => "gravity",
            Kind::Springs => "springs",
            Kind::Dampers => "dampers",
            Kind::Friction => "friction",
            Kind::Torques => "torques",
            Kind::External => "external",
            Kind::Contact => "contact",
            Kind::Limits => "limits",
        }
    }

    /// The singular a user may write instead of `name` (the same word when there is none).
    fn singular(self) -> &'static str {
        match self {
            Kind::Springs => "spring",
            Kind::Dampers => "damper",
            Kind::Torques => "torque",
            Kind::Limits => "limit",
            other => other.name(),
        }
    }

    /// The family named `name` (singular forms accepted: `spring`, `damper`, `torque`).
    pub fn parse(name: &str) -> Option<Kind> {
        Kind::ALL
            .into_iter()
            .find(|k| k.name() == name || k.singular() == name)
    }

    fn bit(self) -> u8 {
        1 << (self as u8)
    }
}

/// The set of disabled families (empty by default).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Disabled(u8);

impl Disabled {
    pub fn none() -> Self {
        Disabled(0)
    }
    pub fn with(self, kind: Kind) -> Self {
        Disabled(self.0 | kind.bit())
    }
    pub fn contains(self, kind: Kind) -> bool {
        self.0 & kind.bit() != 0
    }
    /// Parses family names; errors name `arg` and list the valid names.
    pub fn parse<S: AsRef<str>>(names: &[S], arg: &str) -> Result<Self> {
        let mut d = Disabled::none();
        for (k, n) in names.iter().enumerate() {
            let n = n.as_ref();
            let kind = Kind::parse(n).ok_or_else(|| {
                let names: Vec<String> = Kind::ALL
                    .iter()
                    .map(|k| format!("\"{}\"", k.name()))
                    .collect();
                Error::arg(
                    format!("{arg}[{k}]"),
                    format!("one of {}", names.join(", ")),
                    format!("\"{n}\""),
                )
            })?;
            d = d.with(kind);
        }
        Ok(d)
    }
    /// The disabled families' names, in `Kind::ALL` order.
    pub fn names(self) -> Vec<&'static str> {
        Kind::ALL
            .iter()
            .filter(|k| self.contains(**k))
            .map(|k| k.name())
            .collect()
    }
}
