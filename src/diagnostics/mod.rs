//! Diagnostics: conservation, error norms and exact reference solutions.

pub mod axisymmetric;
pub mod bench_cases;
pub mod coupled;
pub mod explosion;
pub mod finite_plasticity;
pub mod formulations;
pub mod impm;
pub mod interface_tube;
pub mod lian_gas;
pub mod lian_impact;
pub mod membrane_fe;
pub mod mms;
pub mod riemann;
pub mod shock;
pub mod taylor;
pub mod wedge;
pub mod york;
pub mod york_airbag;
pub mod york_membrane;
pub mod zhang_block;
pub mod zhang_rod;
pub mod zhang_spall;
