//! Tables in time: strictly increasing times, one row of values per time, linear
//! interpolation between rows and the end rows held outside (clamped). Lookups keep a hint,
//! so the integrator's nearly monotone sweep costs O(1) per evaluation.
use crate::support::error::{Error, Result};

use super::{check_values, Matrix, Sign};

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "TableData")]
pub struct Table {
    time: Vec<f64>,
    /// Row-major `len × cols`.
    values: Vec<f64>,
    cols: usize,
    /// The values were given as a flat list (one column), for error messages.
    one_d: bool,
}

/// A deserialised table, checked by [`Table::new`] before use.
#[derive(serde::Deserialize)]
struct TableData {
    time: Vec<f64>,
    values: Vec<f64>,
    cols: usize,
    one_d: bool,
}

impl TryFrom<TableData> for Table {
    type Error = Error;
    fn try_from(t: TableData) -> Result<Table> {
        let rows = t.time.len();
        let values = Matrix {
            values: t.values,
            rows,
            cols: t.cols,
            one_d: t.one_d,
        };
        Table::new(t.time, values, "time", "values")
    }
}

impl Table {
    /// Checks the times (finite, strictly increasing, at least one) and the values (finite,
    /// one row per time); errors name `time_arg` or `values_arg`.
    pub fn new(time: Vec<f64>, values: Matrix, time_arg: &str, values_arg: &str) -> Result<Table> {
        if time.is_empty() {
            return Err(Error::arg(time_arg, "at least one time", "an empty list"));
        }
        check_values(time_arg, &time, Sign::Any)?;
        if let Some(k) = time.windows(2).position(|w| w[1] <= w[0]) {
            return Err(Error::arg(
                time_arg,
                "strictly increasing times",
                format!(
                    "{time_arg}[{}] = {} after {time_arg}[{k}] = {}",
                    k + 1,
                    time[k + 1],
                    time[k]
                ),
            ));
        }
        if values.rows != time.len()
            || values.cols == 0
            || values.values.len() != values.rows * values.cols
        {
            return Err(Error::arg(
                values_arg,
                format!(
                    "one row per time: shape ({},) or ({}, ncols)",
                    time.len(),
                    time.len()
                ),
                values.shape(),
            ));
        }
        check_values(values_arg, &values.values, Sign::Any)?;
        Ok(Table {
            time,
            values: values.values,
            cols: values.cols,
            one_d: values.one_d,
        })
    }

    /// The same times with new values (row-major, one row per time; a batch's parameter).
    pub fn with_values(&self, values: &[f64]) -> Result<Table> {
        let (rows, cols) = (self.time().len(), self.cols());
        if values.len() != rows * cols {
            return Err(Error::arg(
                "values",
                format!("{rows} × {cols} values (the table's times × columns)"),
                format!("{} values", values.len()),
            ));
        }
        let m = Matrix {
            values: values.to_vec(),
            rows,
            cols,
            one_d: cols == 1,
        };
        Table::new(self.time().to_vec(), m, "time", "values")
    }

    pub fn len(&self) -> usize {
        self.time.len()
    }
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }
    pub fn cols(&self) -> usize {
        self.cols
    }
    pub fn time(&self) -> &[f64] {
        &self.time
    }
    /// Whether the values were given as one flat list (shape `(len,)`).
    pub fn one_d(&self) -> bool {
        self.one_d
    }
    pub fn values(&self) -> &[f64] {
        &self.values
    }
    pub fn shape(&self) -> String {
        if self.one_d {
            format!("shape ({},)", self.len())
        } else {
            format!("shape ({}, {})", self.len(), self.cols)
        }
    }
    fn row(&self, i: usize) -> &[f64] {
        &self.values[i * self.cols..(i + 1) * self.cols]
    }

    /// Index `i` of the segment `[t_i, t_{i+1})` holding `t` (`len − 1` past the end, 0
    /// before the start); `hint` is the last answer.
    #[inline]
    fn locate(&self, t: f64, hint: &mut usize) -> usize {
        let n = self.time.len();
        let ok = |i: usize| self.time[i] <= t && (i + 1 == n || t < self.time[i + 1]);
        let h = (*hint).min(n - 1);
        let i = if ok(h) {
            h
        } else if h + 1 < n && ok(h + 1) {
            h + 1
        } else {
            // First index with time > t, minus one (0 before the table).
            self.time.partition_point(|x| *x <= t).saturating_sub(1)
        };
        *hint = i;
        i
    }

    /// Values at `t` into `out` (length `cols`): linear between rows, clamped outside.
    #[inline]
    pub fn eval(&self, t: f64, hint: &mut usize, out: &mut [f64]) {
        let i = self.locate(t, hint);
        let n = self.time.len();
        if i + 1 == n || t <= self.time[i] {
            out.copy_from_slice(self.row(i));
            return;
        }
        let w = (t - self.time[i]) / (self.time[i + 1] - self.time[i]);
        let (a, b) = (self.row(i), self.row(i + 1));
        for ((o, x), y) in out.iter_mut().zip(a).zip(b) {
            *o = x + w * (y - x);
        }
    }

    /// Values and slopes at `t`: the slope is the segment's (right-continuous at the
    /// breakpoints) and zero outside the table, where the values are held.
    #[inline]
    pub fn eval_with_slope(&self, t: f64, hint: &mut usize, out: &mut [f64], slope: &mut [f64]) {
        let i = self.locate(t, hint);
        let n = self.time.len();
        if i + 1 == n || t < self.time[0] {
            out.copy_from_slice(self.row(i));
            slope.fill(0.0);
            return;
        }
        let dt = self.time[i + 1] - self.time[i];
        let w = (t - self.time[i]) / dt;
        let (a, b) = (self.row(i), self.row(i + 1));
        for k in 0..self.cols {
            out[k] = a[k] + w * (b[k] - a[k]);
            slope[k] = (b[k] - a[k]) / dt;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> Table {
        Table::new(
            vec![0.0, 1.0, 3.0],
            Matrix {
                values: vec![0.0, 10.0, 2.0, 10.0, 6.0, -10.0],
                rows: 3,
                cols: 2,
                one_d: false,
            },
            "time",
            "values",
        )
        .unwrap()
    }

    #[test]
    fn interpolates_and_clamps() {
        let tb = table();
        let mut h = 0;
        let mut out = [0.0; 2];
        for (t, want) in [
            (-1.0, [0.0, 10.0]),
            (0.0, [0.0, 10.0]),
            (0.5, [1.0, 10.0]),
            (1.0, [2.0, 10.0]),
            (2.0, [4.0, 0.0]),
            (3.0, [6.0, -10.0]),
            (9.0, [6.0, -10.0]),
            (0.25, [0.5, 10.0]),
        ] {
            tb.eval(t, &mut h, &mut out);
            assert!(
                (out[0] - want[0]).abs() < 1e-15 && (out[1] - want[1]).abs() < 1e-15,
                "{t}: {out:?}"
            );
        }
        let mut s = [0.0; 2];
        tb.eval_with_slope(2.0, &mut h, &mut out, &mut s);
        assert_eq!(s, [2.0, -10.0]);
        tb.eval_with_slope(1.0, &mut h, &mut out, &mut s);
        assert_eq!(s, [2.0, -10.0]); // right-continuous
        tb.eval_with_slope(5.0, &mut h, &mut out, &mut s);
        assert_eq!(s, [0.0, 0.0]);
        tb.eval_with_slope(-5.0, &mut h, &mut out, &mut s);
        assert_eq!((s, out), ([0.0, 0.0], [0.0, 10.0]));
    }

    #[test]
    fn refuses_bad_tables() {
        let m = |rows, cols| Matrix {
            values: vec![0.0; rows * cols],
            rows,
            cols,
            one_d: false,
        };
        let e = Table::new(vec![0.0, 1.0, 1.0], m(3, 1), "time", "values").unwrap_err();
        assert!(e.to_string().contains("strictly increasing"), "{e}");
        let e = Table::new(vec![0.0, 1.0], m(3, 1), "time", "values").unwrap_err();
        assert!(e.to_string().starts_with("values:"), "{e}");
        let e = Table::new(vec![], m(0, 1), "time", "values").unwrap_err();
        assert!(e.to_string().starts_with("time:"), "{e}");
        let e = Table::new(vec![0.0, f64::NAN], m(2, 1), "time", "values").unwrap_err();
        assert!(e.to_string().contains("finite"), "{e}");
    }
}
