//! mpmice: a research solver for large-deformation fluid–structure interaction.
pub mod diagnostics;
pub mod driver;
pub mod error;
pub mod grid;
pub mod material;
pub mod mpm;
pub mod output;
pub mod scene;
pub mod shape;
pub mod stepper;
