//! File formats: robot descriptions (`urdf`: URDF and SRDF), scene files (`scene`: TOML, both
//! ways), the frame around pickled objects (`persist`) and what it holds (`pickled`).
pub mod persist;
pub mod pickled;
pub mod scene;
pub mod urdf;
