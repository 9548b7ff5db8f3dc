//! Materials: solid constitutive models (`solid`) and fluid equations of state
//! (`eos`). Imports no physics module.

pub mod eos;
pub mod equation_of_state;
pub mod solid;
pub mod solid_eos;

pub use solid::{ElasticConstants, SolidMaterial, SolidModel};
