//! Diagnostics: conservation, error norms and exact reference solutions.

pub mod riemann;
