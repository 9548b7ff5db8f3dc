//! The systems the run loop drives, one file a model, and the array
//! conversions and particle/cell parts they share.

pub mod arrays;
pub mod coupled;
pub mod fluid;
pub mod membrane_contact;
pub mod membrane_fe;
pub mod multiphase;
pub mod solid_explicit;
pub mod solid_implicit;

pub use coupled::Coupled;
pub use fluid::Fluid;
pub use membrane_contact::MembraneContact;
pub use membrane_fe::MembraneFe;
pub use multiphase::Multiphase;
pub use solid_explicit::{scene_name, ExplicitSolid};
pub use solid_implicit::ImplicitSolid;
