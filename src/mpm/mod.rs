//! Material point method: particles (struct of arrays) and the explicit step
//! (Guilkey Sec. 3.2, Eqs. 21–27) with USF, USL and MUSL orderings, and the
//! implicit step (Newmark + Newton, quasistatic load steps).

pub mod explicit;
pub mod implicit;
pub mod nonlocal_damage;
pub mod particles;
mod scatter;
pub mod tensors;
pub mod wall_reaction;

pub use explicit::{
    explicit_step, stable_dt, BodyForce, CoupledMpm, ExplicitParams, GridState, PhaseTimes,
    StepScratch, UpdateScheme,
};
pub use implicit::{
    DtCut, FluidLoad, ImplicitCarried, ImplicitParams, ImplicitRun, LinearSolver, StepStats,
    SurfaceLoad,
};
pub use particles::{HalfSizes, Particles};
pub use tensors::{SharedTensors, Stresses, Tensors};
