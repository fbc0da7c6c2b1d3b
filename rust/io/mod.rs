//! File formats: robot descriptions (`urdf`: URDF and SRDF), scene files (`scene`: TOML, both
//! ways) and the frame around pickled objects (`persist`).
pub mod persist;
pub mod scene;
pub mod urdf;
