//! An array of any rank as the core hands a result over: its entries and its shape, so a
//! binding converts it as it is, without knowing what it holds.

/// Entries in C order (the last index fastest) and the shape they fill.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Array {
    pub data: Vec<f64>,
    pub shape: Vec<usize>,
}

impl Array {
    /// Zeros of `shape`.
    pub fn zeros(shape: &[usize]) -> Array {
        let data = vec![0.0; shape.iter().product()];
        Array {
            data,
            shape: shape.to_vec(),
        }
    }
}
