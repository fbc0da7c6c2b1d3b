//! Arguments as a binding hands them over, and the forms a caller may write them in (a body
//! by name or index, one number or one per joint, a family name or a list of them, ...).
//! The parsing lives here, once, so a binding only converts: it implements [`Arg`] for its
//! own objects (Python's in `rust/python/convert.rs`) and maps [`Error`] to its exceptions.
//! Every refusal names the argument, the expected form and what was given.
use super::error::Error;
use super::spatial::{Mat3, Placement, Vec3};

/// An integer as a binding sees it: a value, one beyond 64 bits, or not an integer at all.
pub enum Int {
    Value(i64),
    TooBig,
    No,
}

/// A caller's value, not yet given a meaning. `Err` is the binding's error type: the core's
/// errors convert into it, and the binding's own conversions (an array of the wrong dtype,
/// Ctrl-C while converting) pass through unchanged.
pub trait Arg: Sized {
    type Err: From<Error>;
    /// The "not given" value (Python's `None`).
    fn absent(&self) -> bool;
    fn is_bool(&self) -> bool;
    /// A string, if it is one.
    fn text(&self) -> Option<String>;
    /// An integer (a bool is not one).
    fn int(&self) -> Int;
    /// The value as the caller wrote it, for messages.
    fn shown(&self) -> String;
    /// The items of a sequence (not of a string); `None` for a value that has none.
    fn items(&self) -> Option<Result<Vec<Self>, Self::Err>>;
    /// A real number (an array of shape `()` included).
    fn real(&self, arg: &str) -> Result<f64, Self::Err>;
    /// An array of real numbers: its shape and its entries in C order.
    fn array(&self, arg: &str) -> Result<(Vec<usize>, Vec<f64>), Self::Err>;
    /// Copies a plain array of exactly `out.len()` reals (a C-ordered float64 vector) into
    /// `out` without converting or allocating; `false` for any other value (read it with
    /// `array`). The fast path of the per-call 3-vectors (gravity).
    fn copy_plain(&self, _out: &mut [f64]) -> bool {
        false
    }
    /// A value of the wrong kind altogether (a float for a count): the binding's type error.
    fn wrong_type(&self, arg: &str, expected: &str) -> Self::Err;
    /// A mapping's (a dict's) value under `key`: `Some(None)` for a key it lacks, `None` for
    /// a value that is no mapping.
    fn get(&self, key: &str) -> Option<Option<Self>>;
    /// A mapping's keys; `None` for a value that is no mapping.
    fn keys(&self) -> Option<Vec<Self>> {
        None
    }
    /// An object's attribute `name` (a record such as a dataclass), if it has one.
    fn attr(&self, _name: &str) -> Option<Self> {
        None
    }
}

pub fn shape_str(shape: &[usize]) -> String {
    match shape {
        [n] => format!("shape ({n},)"),
        _ => format!(
            "shape ({})",
            shape
                .iter()
                .map(|s| s.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// `Some(x)` for a value given (not `None`).
pub fn given<A: Arg>(x: Option<&A>) -> Option<&A> {
    x.filter(|x| !x.absent())
}

/// `f` of the value, if one was given.
pub fn opt<A: Arg, T>(
    x: Option<&A>,
    f: impl FnOnce(&A) -> Result<T, A::Err>,
) -> Result<Option<T>, A::Err> {
    given(x).map(f).transpose()
}

/// An integer in `lo..=hi`; a bool or an out-of-range int is refused naming the value,
/// another kind is the binding's type error.
pub fn int<A: Arg>(x: &A, arg: &str, lo: i64, hi: i64, expected: &str) -> Result<i64, A::Err> {
    if x.is_bool() {
        return Err(Error::arg(arg, expected, format!("the bool {}", x.shown())).into());
    }
    match x.int() {
        Int::Value(n) if (lo..=hi).contains(&n) => Ok(n),
        Int::Value(n) => Err(Error::arg(arg, expected, n.to_string()).into()),
        Int::TooBig => Err(Error::arg(arg, expected, x.shown()).into()),
        Int::No => Err(x.wrong_type(arg, expected)),
    }
}

/// A count or index `>= 0`.
pub fn count<A: Arg>(x: &A, arg: &str, expected: &str) -> Result<usize, A::Err> {
    int(x, arg, 0, i64::MAX, expected).map(|n| n as usize)
}

/// A thread count `>= 1`; `None` (not given): one per core.
pub fn threads<A: Arg>(x: Option<&A>) -> Result<usize, A::Err> {
    let expected = "a thread count >= 1 (or None: one per core)";
    match opt(x, |t| int(t, "threads", 1, i64::MAX, expected))? {
        Some(n) => Ok(n as usize),
        None => Ok(std::thread::available_parallelism().map_or(1, |n| n.get())),
    }
}

/// A 1-D array of length `len` (`None`: any length).
pub fn vector<A: Arg>(x: &A, arg: &str, len: Option<usize>) -> Result<Vec<f64>, A::Err> {
    if let Some(n) = len {
        let mut v = vec![0.0; n];
        if x.copy_plain(&mut v) {
            return Ok(v);
        }
    }
    let (shape, data) = x.array(arg)?;
    if shape.len() != 1 || len.is_some_and(|n| n != shape[0]) {
        let want = match len {
            Some(n) => format!("shape ({n},)"),
            None => "a 1-D array".into(),
        };
        return Err(Error::arg(arg, want, shape_str(&shape)).into());
    }
    Ok(data)
}

pub fn vec3<A: Arg>(x: &A, arg: &str) -> Result<Vec3, A::Err> {
    let mut v = [0.0; 3];
    if x.copy_plain(&mut v) {
        return Ok(Vec3::from(v));
    }
    vector(x, arg, Some(3)).map(|v| Vec3::from_column_slice(&v))
}

/// A string out of `choices` (`(spelling, value)`); `expected` says which.
pub fn choice<A: Arg, T: Copy>(
    x: &A,
    arg: &str,
    choices: &[(&str, T)],
    expected: &str,
) -> Result<T, A::Err> {
    let Some(s) = x.text() else {
        return Err(x.wrong_type(arg, expected));
    };
    choices
        .iter()
        .find(|(name, _)| *name == s)
        .map(|(_, v)| *v)
        .ok_or_else(|| Error::arg(arg, expected, format!("'{s}'")).into())
}

/// A bool (`True`/`False` only).
pub fn flag<A: Arg>(x: &A, arg: &str) -> Result<bool, A::Err> {
    match (x.is_bool(), x.int()) {
        (true, Int::Value(n)) => Ok(n != 0),
        _ => Err(x.wrong_type(arg, "True or False")),
    }
}

/// A string, or the binding's type error.
pub fn text<A: Arg>(x: &A, arg: &str, expected: &str) -> Result<String, A::Err> {
    x.text().ok_or_else(|| x.wrong_type(arg, expected))
}

/// The items of a sequence that is not a string, or `expected` refused naming `x`.
pub fn items<A: Arg>(x: &A, arg: &str, expected: &str) -> Result<Vec<A>, A::Err> {
    match x.items() {
        Some(items) if x.text().is_none() => items,
        _ => Err(Error::arg(arg, expected, x.shown()).into()),
    }
}

/// A 3 × 3 matrix, given in rows.
pub fn mat3<A: Arg>(x: &A, arg: &str) -> Result<Mat3, A::Err> {
    let (shape, data) = x.array(arg)?;
    if shape != [3, 3] {
        return Err(Error::arg(arg, "shape (3, 3)", shape_str(&shape)).into());
    }
    Ok(Mat3::from_row_slice(&data))
}

/// A frame from an optional translation (default zero) and rotation (default identity).
pub fn placement<A: Arg>(
    t: Option<&A>,
    r: Option<&A>,
    t_arg: &str,
    r_arg: &str,
) -> Result<Placement, A::Err> {
    let t = opt(t, |t| vec3(t, t_arg))?.unwrap_or_else(Vec3::zeros);
    let r = opt(r, |r| mat3(r, r_arg))?.unwrap_or_else(Mat3::identity);
    Ok(Placement::new(r, t))
}

/// A `rows × cols` matrix, given in rows: its entries row-major.
pub fn matrix<A: Arg>(x: &A, arg: &str, rows: usize, cols: usize) -> Result<Vec<f64>, A::Err> {
    let (shape, data) = x.array(arg)?;
    if shape != [rows, cols] {
        return Err(Error::arg(arg, format!("shape ({rows}, {cols})"), shape_str(&shape)).into());
    }
    Ok(data)
}

/// An (n, 3) array of points; (a, b, 3) and more axes are flattened over the leading ones.
pub fn points<A: Arg>(x: &A, arg: &str) -> Result<Vec<Vec3>, A::Err> {
    let (shape, data) = x.array(arg)?;
    if shape.len() < 2 || shape[shape.len() - 1] != 3 {
        return Err(Error::arg(arg, "shape (n, 3)", shape_str(&shape)).into());
    }
    Ok(data.chunks_exact(3).map(Vec3::from_column_slice).collect())
}

/// A real number from an array's `(shape, entries)` (as [`Arg::array`] gives them): the one
/// entry of a 0-d array; any other shape is refused naming it.
pub fn scalar((shape, x): (Vec<usize>, Vec<f64>), arg: &str) -> Result<f64, Error> {
    match shape.is_empty() {
        true => Ok(x.first().copied().unwrap_or(f64::NAN)),
        false => {
            let got = format!("an array of {}", shape_str(&shape));
            Err(Error::arg(arg, "a real number", got))
        }
    }
}

/// A binding's value refused as real numbers, by what it is: which values are refused and
/// why, worded here once; the binding only finds the case ([`NotReal::at`] gives the error).
pub enum NotReal {
    /// An array of a NumPy dtype of kind `.0` (its one-letter code), named `.1`.
    Dtype(u8, String),
    /// A masked array (its mask would be dropped silently).
    Masked,
    /// A string or bytes: its type name and its repr.
    Text(String, String),
    /// No array-like at all: its type name.
    Object(String),
    /// An int of so many bits, beyond the double range.
    HugeInt(u64),
}

impl NotReal {
    /// The refusal of a dtype of kind `kind`, `None` for the real ones (integer, floating);
    /// `name` gives the dtype's name.
    pub fn dtype(kind: u8, name: impl FnOnce() -> String) -> Option<NotReal> {
        (!matches!(kind, b'i' | b'u' | b'f')).then(|| NotReal::Dtype(kind, name()))
    }

    /// The error for argument `arg`.
    pub fn at(self, arg: &str) -> Error {
        let real = "real numbers";
        let (expected, got) = match self {
            NotReal::Dtype(b'b', _) => (real, "a bool array (bools are refused as numbers)".into()),
            NotReal::Dtype(b'c', d) => {
                let got = format!("a complex array (dtype {d}): the imaginary part would be lost");
                (real, got)
            }
            NotReal::Dtype(b'U' | b'S', d) => (real, format!("an array of strings (dtype {d})")),
            NotReal::Dtype(b'O', _) => (
                real,
                "an array of Python objects (dtype object: ragged, non-numeric or out-of-range entries)"
                    .into(),
            ),
            NotReal::Dtype(_, d) => (real, format!("an array of dtype {d}")),
            NotReal::Masked => (
                "real numbers (a plain array)",
                "a masked array: fill it (a.filled(...)) or drop the masked entries first".into(),
            ),
            NotReal::Text(ty, repr) => (real, format!("a {ty}: {repr}")),
            NotReal::Object(ty) => ("an array of real numbers", format!("an object of type {ty}")),
            NotReal::HugeInt(bits) => (
                "a real number within the double range (|x| < 1.8e308)",
                format!("an int of {bits} bits"),
            ),
        };
        Error::arg(arg, expected, got)
    }
}

/// A value as a message shows it (its `repr`), cut to 60 characters.
pub fn shortened(shown: String) -> String {
    let n = shown.chars().count();
    if n <= 60 {
        return shown;
    }
    let head: String = shown.chars().take(50).collect();
    format!("{head}… ({n} characters)")
}
