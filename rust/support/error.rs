//! Errors of the core: one type. Every variant names the argument (or, for input files, the
//! file, element or key and line) at fault, what was expected and what was given, so the
//! bindings only translate the variant to an exception class and pass the message through.
use thiserror::Error;

/// Which loader an input-file error comes from (the bindings raise `UrdfError` or
/// `SceneError`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    Urdf,
    Scene,
}

/// Where in an input file: the file as shown in messages, and within it the element
/// (`joint 'elbow'`) or key (`body[0] ('rod').mass`), and the line and column when known.
/// Shown as `file` or `file: key`; the message says the line where its sentence needs it.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Location {
    pub file: String,
    /// Element or key; empty for the file as a whole.
    pub key: String,
    pub line: Option<usize>,
    pub column: Option<usize>,
}

impl Location {
    pub fn new(file: impl Into<String>, key: impl Into<String>) -> Self {
        Location {
            file: file.into(),
            key: key.into(),
            line: None,
            column: None,
        }
    }
    pub fn at_line(self, line: usize) -> Self {
        Location {
            line: Some(line),
            ..self
        }
    }
    pub fn at_column(self, column: usize) -> Self {
        Location {
            column: Some(column),
            ..self
        }
    }
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}", self.file)
        } else {
            write!(f, "{}: {}", self.file, self.key)
        }
    }
}

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
    /// Finite inputs gave a meaningless result (an effect's failure inside a computation that
    /// is not a simulation, which reports its own).
    #[error("{0}")]
    Numerical(String),
    /// A loop that cannot be closed (or kept closed) from the given state; names the loop.
    #[error("{0}")]
    Closure(String),
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
    /// A run's result asked for what the run never produced (the dense output of a run that
    /// took no step), or a run's machinery failed (a batch thread panicked).
    #[error("{0}")]
    Simulation(String),
    /// The caller asked to stop (Ctrl-C from Python) while a long computation ran.
    #[error("{0}: interrupted")]
    Interrupted(String),
    /// An input file (URDF, scene) that cannot be loaded: where, and what is wrong there.
    #[error("{at}: {message}")]
    File {
        kind: FileKind,
        at: Location,
        message: String,
    },
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
    /// The error's kind as the bindings' exception hierarchy names it (`pointmass_dyn.errors`
    /// in Python); `None` for an interruption, which a binding raises as its own (Ctrl-C).
    pub fn kind_name(&self) -> Option<&'static str> {
        Some(match self {
            Error::InvalidArgument { .. } | Error::InvalidSetting(_) => "InvalidInputError",
            Error::InvalidInertia { .. } => "InertiaError",
            Error::InvalidModel { .. } => "ModelStructureError",
            Error::Singular(_) => "SingularityError",
            Error::Numerical(_) => "NumericalError",
            Error::Closure(_) => "LoopClosureError",
            Error::OutOfMemory { .. } => "OutOfMemoryError",
            Error::Simulation(_) => "SimulationError",
            Error::File {
                kind: FileKind::Urdf,
                ..
            } => "UrdfError",
            Error::File {
                kind: FileKind::Scene,
                ..
            } => "SceneError",
            Error::Interrupted(_) => return None,
        })
    }

    pub fn arg(
        arg: impl Into<String>,
        expected: impl Into<String>,
        got: impl Into<String>,
    ) -> Self {
        // Numbers printed with `{}` (1e-300 as 0.000…1) in exponent form, here once for all.
        Error::InvalidArgument {
            arg: arg.into(),
            expected: compact_numbers(&expected.into()),
            got: compact_numbers(&got.into()),
        }
    }
    pub fn inertia(arg: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::InvalidInertia {
            arg: arg.into(),
            reason: compact_numbers(&reason.into()),
        }
    }
    pub fn model(arg: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::InvalidModel {
            arg: arg.into(),
            reason: compact_numbers(&reason.into()),
        }
    }
    pub fn file(kind: FileKind, at: Location, message: impl Into<String>) -> Self {
        Error::File {
            kind,
            at,
            message: message.into(),
        }
    }

    /// The one way to say where the argument at fault sits: `outer` becomes the prefix of the
    /// argument's name (`joints` in `effects[2]` → `effects[2].joints`; an empty name becomes
    /// `outer`), or of the message of an error that names none (`effects[2]: ...`).
    pub fn in_arg(self, outer: &str) -> Self {
        let tell = |m: String| {
            if outer.is_empty() {
                m
            } else {
                format!("{outer}: {m}")
            }
        };
        match self {
            Error::Singular(m) => Error::Singular(tell(m)),
            Error::Numerical(m) => Error::Numerical(tell(m)),
            Error::Closure(m) => Error::Closure(tell(m)),
            Error::InvalidSetting(m) => Error::InvalidSetting(tell(m)),
            Error::Interrupted(m) => Error::Interrupted(tell(m)),
            named => named.map_arg(|inner| joined(outer, inner)),
        }
    }

    /// Renames the argument (or computation, or file key) this error names, as `f` says
    /// (`q` → `q0` for a binding whose argument is called otherwise); an error that names
    /// none is returned as it is. [`Error::in_arg`] is the way to prefix one.
    pub fn map_arg(self, f: impl FnOnce(String) -> String) -> Self {
        match self {
            Error::InvalidArgument { arg, expected, got } => Error::InvalidArgument {
                arg: f(arg),
                expected,
                got,
            },
            Error::InvalidInertia { arg, reason } => Error::InvalidInertia {
                arg: f(arg),
                reason,
            },
            Error::InvalidModel { arg, reason } => Error::InvalidModel {
                arg: f(arg),
                reason,
            },
            Error::OutOfMemory {
                what,
                bytes,
                detail,
            } => Error::OutOfMemory {
                what: f(what),
                bytes,
                detail,
            },
            Error::File { kind, at, message } => Error::File {
                kind,
                at: Location {
                    key: f(at.key),
                    ..at
                },
                message,
            },
            unnamed @ (Error::Singular(_)
            | Error::Numerical(_)
            | Error::Closure(_)
            | Error::InvalidSetting(_)
            | Error::Simulation(_)
            | Error::Interrupted(_)) => unnamed,
        }
    }

    /// This error met while reading an input file at `at`: the message is this error's whole
    /// text (argument name included), placed after the file and key.
    pub fn in_file(self, kind: FileKind, at: Location) -> Self {
        // Where the key already ends with the argument's name (`body[0] ('rod').mass`), the
        // message says it once: `….mass: expected …`, not `….mass: mass: expected …`.
        let named = |arg: &str| {
            !arg.is_empty()
                && (at.key == arg || at.key.strip_suffix(arg).is_some_and(|k| k.ends_with('.')))
        };
        let message = match &self {
            Error::InvalidArgument { arg, expected, got } if named(arg) => {
                format!("expected {expected}, got {got}")
            }
            Error::InvalidInertia { arg, reason } | Error::InvalidModel { arg, reason }
                if named(arg) =>
            {
                reason.clone()
            }
            _ => self.to_string(),
        };
        Error::file(kind, at, message)
    }

    /// Like [`Error::in_file`], but an invalid argument's name is appended to the key (as
    /// [`Error::in_arg`] joins names) and the message only says what was expected and given:
    /// `effect[1].stiffness: expected ..., got ...`.
    pub fn at_arg_in_file(self, kind: FileKind, at: Location) -> Self {
        match self {
            Error::InvalidArgument { arg, expected, got } => Error::file(
                kind,
                Location {
                    key: joined(&at.key, arg),
                    ..at
                },
                format!("expected {expected}, got {got}"),
            ),
            other => other.in_file(kind, at),
        }
    }
}

/// `outer.inner`, or whichever of the two is not empty.
fn joined(outer: &str, inner: String) -> String {
    match (outer.is_empty(), inner.is_empty()) {
        (true, _) => inner,
        (false, true) => outer.to_string(),
        (false, false) => format!("{outer}.{inner}"),
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
            format!("{} at index {}", num(values[k]), k),
        )),
    }
}

/// Checks that every entry of a row-major matrix with `cols` columns is finite; names the
/// first bad one by row and column.
pub fn check_finite_matrix(arg: &str, values: &[f64], cols: usize) -> Result<()> {
    match values.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(k) => {
            let at = format!(
                "{} at ({}, {})",
                values[k],
                k / cols.max(1),
                k % cols.max(1)
            );
            Err(Error::arg(arg, "finite entries", at))
        }
    }
}

/// `Error::Numerical` if a result computed from finite inputs is not finite (`what` names it).
pub fn check_result(what: &str, values: &[f64]) -> Result<()> {
    match values.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(k) => Err(Error::Numerical(format!(
            "{what}: the result is not finite ({} at index {k}) although the inputs are: the \
             state overflows double precision",
            values[k]
        ))),
    }
}

/// Whether every value is finite, in one vectorisable pass (`x · 0` is NaN exactly for a
/// non-finite `x`; eight independent lanes): a caller then names the first bad index.
pub fn all_finite(x: &[f64]) -> bool {
    let mut acc = [0.0f64; 8];
    let chunks = x.chunks_exact(8);
    let rest = chunks.remainder();
    for ch in chunks {
        for (a, v) in acc.iter_mut().zip(ch) {
            *a += v * 0.0;
        }
    }
    for (a, v) in acc.iter_mut().zip(rest) {
        *a += v * 0.0;
    }
    acc.iter().all(|a| *a == 0.0)
}

/// A name given for a body, loop or coupling: None (one is generated) or not blank (a blank
/// one would leave it unnamed in every listing and message).
pub fn check_name(what: &str, name: Option<&str>) -> Result<()> {
    match name {
        Some(s) if s.trim().is_empty() => Err(Error::arg(
            "name",
            format!("a non-empty {what} name (or None for a generated one)"),
            format!("{s:?}"),
        )),
        _ => Ok(()),
    }
}

/// `x` for a message: as Rust prints it for ordinary magnitudes, in exponent form
/// (`1e-300`, `-2.5e300`) beyond them, where plain decimals run to hundreds of digits.
pub fn num(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (1e-4..1e15).contains(&a) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `message` with every decimal number written with more than [`LONG_NUMBER`] digits (how
/// `{}` prints an f64 such as 1e-300) rewritten as [`num`] does: what the argument errors'
/// constructors do with their text, and every message on its way to Python.
pub fn compact_numbers(message: &str) -> String {
    let b = message.as_bytes();
    let mut out = String::with_capacity(message.len());
    let (mut i, mut copied) = (0, 0);
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            && (i == 0
                || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'.' || b[i - 1] == b'_'));
        if !starts {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < b.len() && (b[j].is_ascii_digit() || b[j] == b'.') {
            j += 1;
        }
        let digits = b[i..j].iter().filter(|c| c.is_ascii_digit()).count();
        // A number, not the start of a word or a hexadecimal digest.
        let ends = j == b.len() || !(b[j].is_ascii_alphanumeric() || b[j] == b'_');
        if digits > LONG_NUMBER && ends {
            if let Ok(x) = message[i..j].parse::<f64>() {
                out.push_str(&message[copied..i]);
                out.push_str(&num(x));
                copied = j;
            }
        }
        i = j;
    }
    out.push_str(&message[copied..]);
    out
}

/// More digits than any integer index or count has (`u64::MAX` has 20).
const LONG_NUMBER: usize = 24;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_decimals_are_compacted_and_others_kept() {
        let tiny = format!("mass: expected > 0, got -{}", 1e-300);
        assert_eq!(compact_numbers(&tiny), "mass: expected > 0, got -1e-300");
        let huge = format!("lower {} > upper {} (entry 3)", 1e300, 2.5e299);
        assert_eq!(
            compact_numbers(&huge),
            "lower 1e300 > upper 2.5e299 (entry 3)"
        );
        let plain = "q[12]: got 0.125 at index 3 of 18446744073709551615, v2 1e-300";
        assert_eq!(compact_numbers(plain), plain);
        let digest = "checksum 12345678901234567890123456789abc differs";
        assert_eq!(compact_numbers(digest), digest);
        assert_eq!(num(1e-320), "1e-320");
        assert_eq!(num(0.5), "0.5");
        let e = Error::arg("mass", "a finite number > 0", format!("{}", -1e-300));
        assert_eq!(
            e.to_string(),
            "mass: expected a finite number > 0, got -1e-300"
        );
    }

    #[test]
    fn in_arg_prefixes_names_and_messages_and_file_keys() {
        let e = Error::arg("joints", "known joints", "'x'").in_arg("effects[2]");
        assert_eq!(
            e.to_string(),
            "effects[2].joints: expected known joints, got 'x'"
        );
        let e = Error::arg("", "an effect", "3").in_arg("effects[2]");
        assert_eq!(e.to_string(), "effects[2]: expected an effect, got 3");
        let e = Error::Singular("sin(theta) = 0".into()).in_arg("q");
        assert_eq!(e.to_string(), "q: sin(theta) = 0");
        let at = Location::new("s.toml", "g").at_line(3);
        let e = Error::file(FileKind::Scene, at, "expected 3 values").in_arg("effect[0]");
        assert_eq!(e.to_string(), "s.toml: effect[0].g: expected 3 values");
        let e = Error::arg("q", "finite numbers", "nan at index 0").map_arg(|a| a + "0");
        assert_eq!(
            e.to_string(),
            "q0: expected finite numbers, got nan at index 0"
        );
    }

    #[test]
    fn a_core_error_placed_in_a_file() {
        let e = Error::arg("stiffness", "numbers >= 0", "-40");
        let at = || Location::new("b.toml", "effect[1]");
        assert_eq!(
            e.clone().at_arg_in_file(FileKind::Scene, at()).to_string(),
            "b.toml: effect[1].stiffness: expected numbers >= 0, got -40"
        );
        assert_eq!(
            e.in_file(FileKind::Urdf, at()).to_string(),
            "b.toml: effect[1]: stiffness: expected numbers >= 0, got -40"
        );
        let whole_file = Error::file(FileKind::Urdf, Location::new("r.urdf", ""), "no <link>");
        assert_eq!(whole_file.to_string(), "r.urdf: no <link>");
    }
}
