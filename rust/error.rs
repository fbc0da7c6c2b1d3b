//! Errors of the core. Every variant names the argument (or element) at fault, what was
//! expected and what was given, so the bindings can pass the message through unchanged.
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum Error {
    /// A value of the wrong form: shape, range, non-finite number.
    #[error("{arg}: expected {expected}, got {got}")]
    InvalidArgument {
        arg: String,
        expected: String,
        got: String,
    },
    /// A mass, centre of mass or inertia tensor that no rigid body can have.
    #[error("{arg}: {reason}")]
    InvalidInertia { arg: String, reason: String },
    /// The tree structure is wrong (unknown parent, duplicate name).
    #[error("{arg}: {reason}")]
    InvalidModel { arg: String, reason: String },
    /// The equations cannot be solved at this state (singular mass matrix, Euler singularity).
    #[error("{0}")]
    Singular(String),
    /// An integrator setting out of range (the message names it).
    #[error("{0}")]
    InvalidSetting(String),
    /// A memory request sized by the input that the system refused (or that cannot even be
    /// expressed); `what` names the computation and the array.
    #[error("{what}: cannot allocate {} ({detail})", human_bytes(*bytes))]
    OutOfMemory {
        what: String,
        bytes: u128,
        detail: String,
    },
    /// The caller asked to stop (Ctrl-C from Python) while a long computation ran.
    #[error("{0}: interrupted")]
    Interrupted(String),
}

/// `2.5e10` bytes as "25.0 GB".
pub fn human_bytes(bytes: u128) -> String {
    let b = bytes as f64;
    match b {
        b if b >= 1e9 => format!("{:.1} GB", b / 1e9),
        b if b >= 1e6 => format!("{:.1} MB", b / 1e6),
        b if b >= 1e3 => format!("{:.1} kB", b / 1e3),
        b => format!("{b} bytes"),
    }
}

impl Error {
    pub fn arg(
        arg: impl Into<String>,
        expected: impl Into<String>,
        got: impl Into<String>,
    ) -> Self {
        Error::InvalidArgument {
            arg: arg.into(),
            expected: expected.into(),
            got: got.into(),
        }
    }
    pub fn inertia(arg: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::InvalidInertia {
            arg: arg.into(),
            reason: reason.into(),
        }
    }
    pub fn model(arg: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::InvalidModel {
            arg: arg.into(),
            reason: reason.into(),
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;

/// Checks that every entry is finite; names the first bad one.
pub fn check_finite(arg: &str, values: &[f64]) -> Result<()> {
    match values.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(k) => Err(Error::arg(
            arg,
            "finite numbers",
            format!("{} at index {}", values[k], k),
        )),
    }
}
