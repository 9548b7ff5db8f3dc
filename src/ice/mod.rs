//! Cell-centred, multi-material, explicit ICE for the fluid materials
//! (Guilkey et al., Sec. 3.1 and Sec. 3.3 steps 2, 3, 5, 6, 8–12).
//!
//! Every fluid material `r` carries, per cell, its mass `M_r`, velocity
//! `u_r`, temperature `T_r` (internal energy `e_r = c_v T_r`), specific
//! volume `v_r` and volume fraction `θ_r = M_r v_r / V`; the mixture carries
//! the equilibration pressure `p_eq` (Guilkey Eq. 13) and the time-advanced
//! pressure `p = p_eq + Δp` (Guilkey Eqs. 29–30).
//!
//! One explicit step ([`step::step`], [`mod@step`]) is, in order:
//!
//! 1. ghost cells from the boundary conditions ([`boundary`]);
//! 2. equilibration pressure per cell, Newton on Guilkey Eq. 13
//!    ([`pressure::equilibrate`], per cell [`equilibration`]);
//! 3. the time step ([`mod@timestep`]), face velocities (Guilkey Eq. 28) and
//!    the face momentum exchange ([`pressure`], with the kernels of
//!    [`faces`] and [`exchange`]);
//! 4. `Δp` (Guilkey Eq. 29, from the volume fluxes of [`volume_flux`]),
//!    `p = p_eq + Δp` (Eq. 30), face pressure (Eq. 31) ([`pressure`]);
//! 5. momentum and energy sources (Eqs. 33–34, [`sources`]) and Lagrangian
//!    values (Eqs. 35–37) ([`lagrangian`]);
//! 6. pointwise-implicit momentum and heat exchange (Eqs. 38–39)
//!    ([`lagrangian`], with the kernels of [`exchange`]);
//! 7. specific-volume evolution (Eqs. 40–41, Appendix Eq. 53)
//!    ([`specific_volume`]);
//! 8. advection of mass, momentum, energy and material volume with
//!    compatible fluxes, first-order donor cell or second-order limited
//!    ([`advect`], with the kernels of [`advection`]).
//!
//! The knobs are in [`params`], the scratch memory in [`workspace`].
//! With [`IceParams::implicit`] set, step 4 is the semi-implicit pressure
//! ([`implicit`], settings in [`implicit_params`]): Guilkey Eq. 29 solved
//! implicitly for the pressure increment by an outer iteration on a
//! 5-/7-point SPD matrix, so that the time step is limited by advection
//! only.
//!
//! Cells are indexed with the module's own ghost layers ([`CellLayout`]);
//! [`crate::grid::Grid`] is used for geometry only.

// Per-direction and per-material index loops (`for d in 0..D`) mirror the
// equations and index several arrays at once.
#![allow(clippy::needless_range_loop)]
pub mod advect;
pub mod advection;
pub mod boundary;
pub mod boundary_exchange;
mod carried;
pub mod equilibration;
pub mod exchange;
pub mod faces;
pub mod implicit;
pub mod implicit_params;
pub mod lagrangian;
mod par;
pub mod params;
pub mod pressure;
mod pressure_system;
pub mod setups;
pub mod sources;
pub mod specific_volume;
pub mod state;
pub mod step;
pub mod timestep;
pub mod volume_flux;
pub mod workspace;

use crate::material::eos::{EosError, FluidEos};

pub use advect::stage_advect;
pub use advection::{Advection, Limiter};
pub use boundary::{IceBoundary, InflowState};
pub use boundary_exchange::BoundaryExchange;
pub use equilibration::EquilibrationSettings;
pub use exchange::ExchangeCoefficients;
pub use implicit_params::{pressure_mg_options, LinearSolver, SemiImplicit};
pub use lagrangian::stage_lagrangian;
pub use params::{
    EnergyForm, Frame, HeatSource, IceParams, TimeIntegration, HELD_FACE_FILL, ISOTHERMAL_FRACTION,
};
pub use pressure::{equilibrate, stage_pressure};
pub use setups::{periodic_vortex, periodic_vortex_exact, shock_tube};
pub use state::{CellLayout, IceState, MaterialCells, MaterialInit, NGHOST};
pub use step::{run_fluid, step, step_with_dt, FluidRun};
pub use timestep::{timestep, timestep_with};
pub use workspace::{IceWorkspace, StepInfo};

/// Largest number of fluid materials in one scene (per-cell kernels use
/// fixed-size stack arrays of this length, so they never allocate).
pub const MAX_MATERIALS: usize = 8;

/// A fluid material of the multifield model.
#[derive(Debug, Clone, PartialEq)]
pub struct IceMaterial {
    /// Name used in error messages and output.
    pub name: String,
    /// Equation of state (Guilkey Eqs. 10–11).
    pub eos: FluidEos,
}

impl IceMaterial {
    /// A material with a name and an equation of state.
    pub fn new(name: impl Into<String>, eos: impl Into<FluidEos>) -> Self {
        Self {
            name: name.into(),
            eos: eos.into(),
        }
    }
}

/// Where and when a failure happened: step number, time, cell (interior
/// coordinates, `D` entries) and material index (`None` for mixture
/// quantities).
#[derive(Debug, Clone, PartialEq)]
pub struct Site {
    /// Step number (0 for the first step).
    pub step: u64,
    /// Time at the start of the step.
    pub time: f64,
    /// Interior cell coordinates (`D` entries; ghosts are negative or
    /// `≥ cells`).
    pub cell: Vec<isize>,
    /// Material index, `None` for a mixture quantity (`u32` keeps the
    /// crate's error small).
    pub material: Option<u32>,
    /// The material as shown (instead of the index when known): its scene
    /// name in backticks, to which the driver adds its `materials[i]`
    /// index.
    pub material_name: Option<Box<str>>,
}

impl std::fmt::Display for Site {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "step {}, t = {:e}, cell {:?}",
            self.step, self.time, self.cell
        )?;
        match (&self.material_name, self.material) {
            (Some(name), _) => write!(f, ", material {name}")?,
            (None, Some(m)) => write!(f, ", material {m}")?,
            (None, None) => {}
        }
        Ok(())
    }
}

/// Errors of the ICE kernels.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IceError {
    /// A parameter or initial value is outside its admissible range.
    #[error("invalid ICE input `{field}`: {reason}")]
    InvalidInput {
        /// Name of the offending input.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The time step is too large: a cell would lose more than its content
    /// (the caller should retry the step with a smaller `Δt`; the state is
    /// unchanged).
    #[error("time step too large at {site}: outflow Courant number {courant} > 1 (retry with a smaller dt = {dt:e})")]
    TimestepTooLarge {
        /// Where.
        site: Site,
        /// Sum over the faces of the outgoing `|u*| Δt / h`.
        courant: f64,
        /// The time step that was tried.
        dt: f64,
    },
    /// A state variable left its physical range (negative mass, density,
    /// pressure, temperature/energy, or a NaN).
    #[error("non-physical {quantity} = {value:e} at {site}")]
    NonPhysical {
        /// Where.
        site: Site,
        /// `"mass"`, `"pressure"`, `"temperature"`, `"specific volume"`,
        /// `"velocity"`.
        quantity: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The equilibration pressure iteration (Guilkey Eq. 13) failed.
    #[error("equilibration pressure failed at {site}: |Σθ − 1| = {residual:e} after {iterations} iterations (p = {pressure:e})")]
    Equilibration {
        /// Where.
        site: Site,
        /// Last residual `|Σ_r ρ̂_r v_r − 1|`.
        residual: f64,
        /// Iterations performed.
        iterations: usize,
        /// Last pressure iterate.
        pressure: f64,
    },
    /// The semi-implicit pressure solve failed: a singular pressure matrix
    /// (not retryable), a failed linear solve, a diverging or too long outer
    /// iteration, or a non-physical pressure (retryable with a smaller
    /// `Δt`; the state is unchanged).
    #[error("pressure solve failed at {site} (dt = {dt:e}, outer iteration {outer}, max |residual|/V = {residual:e}): {reason}")]
    PressureSolve {
        /// Where (the cell of the largest residual).
        site: Site,
        /// What went wrong.
        reason: String,
        /// Outer iteration at which it failed.
        outer: usize,
        /// Largest `|residual|/V` of the pressure equation (Guilkey Eq. 29).
        residual: f64,
        /// The time step that was tried.
        dt: f64,
        /// `true` when a smaller time step may help.
        retryable: bool,
    },
    /// An equation of state rejected a state.
    #[error("equation of state failed at {site}: {source}")]
    Eos {
        /// Where.
        site: Site,
        /// The EOS error.
        source: EosError,
    },
}

impl IceError {
    /// `true` when retrying the step with a smaller time step may help.
    pub fn is_retryable(&self) -> bool {
        self.retry_dt().is_some()
    }

    /// The time step that failed, for a retryable error (`None` otherwise).
    pub fn retry_dt(&self) -> Option<f64> {
        match self {
            IceError::TimestepTooLarge { dt, .. } => Some(*dt),
            IceError::PressureSolve {
                dt,
                retryable: true,
                ..
            } => Some(*dt),
            _ => None,
        }
    }
}

/// The [`Site`] of cell `c` (and `material`) at the state's step and time.
pub(crate) fn site<const D: usize>(state: &IceState<D>, c: usize, material: Option<usize>) -> Site {
    Site {
        step: state.steps,
        time: state.time,
        cell: state.layout.coords(c).to_vec(),
        material: material.map(|m| m as u32),
        material_name: material.and_then(|m| {
            state
                .materials
                .get(m)
                .map(|x| format!("`{}`", x.name).into())
        }),
    }
}

/// Shorthand for an [`IceError::InvalidInput`].
pub(crate) fn invalid(field: impl Into<String>, reason: impl Into<String>) -> IceError {
    IceError::InvalidInput {
        field: field.into(),
        reason: reason.into(),
    }
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_implicit;
