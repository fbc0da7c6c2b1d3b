//! What every layer uses and that knows no model: errors, the 3-/6-vector algebra, fast
//! `sin_cos`, CPU dispatch, fallible allocation, interruption, reading input files.
pub mod alloc;
pub mod args;
pub mod array;
pub mod cpu;
pub mod error;
pub mod files;
pub mod interrupt;
pub mod pacing;
pub mod spatial;
pub mod trig;
