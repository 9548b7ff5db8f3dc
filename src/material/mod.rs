//! Materials: solid constitutive models (`solid`), fluid equations of state
//! (`eos`) and the gas on material points (`gas_point`, York Sec. 3.3). Imports no physics module.

pub mod eos;
pub mod gas_point;
pub mod solid;
pub mod solid_eos;

pub use gas_point::{ArtificialViscosity, GasPoint};
pub use solid::{ElasticConstants, GasInput, PointState, SolidMaterial, SolidModel};
