//! Diagnostics: conservation, error norms and exact reference solutions.

pub mod impm;
pub mod mms;
pub mod riemann;
