//! Materials: solid constitutive models (`solid`), the equation-of-state
//! interface (`equation_of_state`), fluid equations of state (`eos`,
//! `solid_eos`, `mie_gruneisen`, `jwl`), J2 plasticity (`plasticity`), Hencky
//! hyperelasticity and its multiplicative plasticity (`hencky`), failure
//! and damage (`failure`), the gas on material points
//! (`gas_point`, York Sec. 3.3) and the membrane law (`membrane`, York
//! Sec. 3.2).
//! Imports no physics module.

pub mod eos;
pub mod equation_of_state;
pub mod failure;
pub mod gas_point;
pub mod hencky;
pub mod jwl;
pub mod membrane;
pub mod mie_gruneisen;
pub mod plasticity;
pub mod solid;
pub mod solid_eos;

pub use gas_point::{ArtificialViscosity, GasPoint, PointDensity};
pub use membrane::MembraneLaw;
pub use solid::{ElasticConstants, GasInput, PointState, SolidMaterial, SolidModel};
