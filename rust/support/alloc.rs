//! Fallible allocation for arrays whose size the user decides (the explicit DeNOC matrices,
//! the n × n mass matrix): a refused request is an `Error::OutOfMemory` naming the array and
//! its size, never an abort of the whole process.
use nalgebra::{DMatrix, DVector};

use crate::support::error::{Error, Result};

/// A `Vec<f64>` of `len` zeros, or an error naming `what`.
pub fn try_zeros_vec(len: usize, what: &str) -> Result<Vec<f64>> {
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|e| Error::OutOfMemory {
        what: what.to_string(),
        bytes: len as u128 * 8,
        detail: e.to_string(),
    })?;
    v.resize(len, 0.0);
    Ok(v)
}

/// An `rows × cols` zero matrix, or an error naming `what` and the shape.
pub fn try_zeros(rows: usize, cols: usize, what: &str) -> Result<DMatrix<f64>> {
    let len = rows.checked_mul(cols).ok_or_else(|| Error::OutOfMemory {
        what: what.to_string(),
        bytes: rows as u128 * cols as u128 * 8,
        detail: format!("{rows} × {cols} entries do not fit in the address space"),
    })?;
    let data = try_zeros_vec(len, &format!("{what} ({rows} × {cols})"))?;
    Ok(DMatrix::from_vec(rows, cols, data))
}

pub fn try_zeros_vector(len: usize, what: &str) -> Result<DVector<f64>> {
    Ok(DVector::from_vec(try_zeros_vec(len, what)?))
}

/// Checks up front that `bytes` can be had (allocated and freed at once), so that a chain of
/// dense products fails before it starts rather than halfway, with the total named.
pub fn ensure_available(bytes: u128, what: &str) -> Result<()> {
    let refused = |detail: String| Error::OutOfMemory {
        what: what.to_string(),
        bytes,
        detail,
    };
    let len = usize::try_from(bytes / 8 + 1)
        .map_err(|_| refused("more than the address space".into()))?;
    let mut probe: Vec<f64> = Vec::new();
    probe
        .try_reserve_exact(len)
        .map_err(|e| refused(e.to_string()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refused_sizes_are_errors_not_aborts() {
        // More than any address space: the request is refused and named, the process lives.
        let e = try_zeros(usize::MAX / 2, 4, "test matrix").unwrap_err();
        assert!(matches!(e, Error::OutOfMemory { .. }), "{e}");
        assert!(e.to_string().contains("test matrix"), "{e}");
        let e = try_zeros_vec(usize::MAX / 4, "test vector").unwrap_err();
        assert!(e.to_string().contains("test vector"), "{e}");
        assert!(ensure_available(u128::MAX / 2, "whole").is_err());
        let m = try_zeros(3, 2, "small").unwrap();
        assert_eq!(m.shape(), (3, 2));
        assert!(m.iter().all(|&x| x == 0.0));
    }
}

/// A counting global allocator for the unit tests (the project rule "hot paths allocate
/// nothing" as a test): [`counting::count`] runs a closure and returns how many allocations
/// (and reallocations) this thread made meanwhile; other threads are not counted.
#[cfg(test)]
pub mod counting {
    use std::alloc::{GlobalAlloc, Layout, System};
    use std::cell::Cell;

    thread_local! {
        static COUNT: Cell<Option<usize>> = const { Cell::new(None) };
    }

    struct Counting;

    fn bump() {
        let _ = COUNT.try_with(|c| {
            if let Some(n) = c.get() {
                c.set(Some(n + 1));
            }
        });
    }

    // SAFETY: every call is forwarded unchanged to the system allocator.
    unsafe impl GlobalAlloc for Counting {
        unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
            bump();
            unsafe { System.alloc(layout) }
        }
        unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
            bump();
            unsafe { System.alloc_zeroed(layout) }
        }
        unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
            bump();
            unsafe { System.realloc(ptr, layout, new_size) }
        }
        unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
            unsafe { System.dealloc(ptr, layout) }
        }
    }

    #[global_allocator]
    static GLOBAL: Counting = Counting;

    /// `f`'s result and the number of allocations it made on this thread.
    pub fn count<R>(f: impl FnOnce() -> R) -> (R, usize) {
        COUNT.with(|c| c.set(Some(0)));
        let r = f();
        let n = COUNT.with(|c| c.replace(None)).unwrap_or(0);
        (r, n)
    }

    #[test]
    fn counts_this_threads_allocations() {
        let (v, n) = count(|| vec![1.0f64; 100]);
        assert_eq!((v.len(), n), (100, 1));
        let (_, n) = count(|| 2 + 2);
        assert_eq!(n, 0);
    }
}
