//! Hand-written factorisations, in one place. Each file says in one line why it is not
//! nalgebra's (or faer's) own.
pub mod cholesky;
pub mod envelope_qr;
pub(crate) mod lu;
pub mod pivoted_qr;
pub mod rank_qr;
pub mod spd;

pub use spd::spd_inverse;
