//! mpmice: a research solver for large-deformation fluid–structure interaction.
//!
//! Solids live on material points (`mpm`), fluids in cell-centred
//! multi-material ICE (`ice`), on one background grid (`grid`). See
//! `../shared/DESIGN.md` for the architecture and the step order.

// Dimension loops `for d in 0..D` index several arrays in lockstep (position,
// cell size, strides); iterator chains would hide the maths.
#![allow(clippy::needless_range_loop)]
pub mod contact;
pub mod coupling;
pub mod diagnostics;
pub mod driver;
pub mod error;
pub mod grid;
pub mod ice;
pub mod material;
pub mod membrane;
pub mod mpm;
pub mod multiphase;
pub mod output;
pub mod scene;
pub mod shape;
pub mod stepper;
pub mod study;
