//! Scratch memory of the ICE step ([`IceWorkspace`]: face velocities,
//! volume fluxes, pressures, Lagrangian values and advected values,
//! allocated once per layout and material count so that the step does not
//! allocate) and what a step reports ([`StepInfo`]).

use nalgebra::SVector;

use super::advection::AdvectionFluxes;
use super::pressure_system::ImplicitSlot;
use super::state::{IceState, MaterialCells};

/// Scratch memory of the step, allocated once per layout and material count.
#[derive(Debug, Clone)]
pub struct IceWorkspace<const D: usize> {
    pub(super) ustar: Vec<[Vec<f64>; D]>,
    pub(super) div: Vec<Vec<f64>>,
    pub(super) kappa: Vec<Vec<f64>>,
    pub(super) div_sum: Vec<f64>,
    pub(super) sum_theta_kappa: Vec<f64>,
    pub(super) mix_mass: Vec<f64>,
    pub(super) press: Vec<f64>,
    pub(super) pstar: [Vec<f64>; D],
    pub(super) theta_flux: [Vec<f64>; D],
    pub(super) mix_vflux: [Vec<f64>; D],
    pub(super) ke: Vec<Vec<f64>>,
    pub(super) vel_l: Vec<Vec<SVector<f64, D>>>,
    pub(super) temp_l: Vec<Vec<f64>>,
    pub(super) e_l: Vec<Vec<f64>>,
    pub(super) v_l: Vec<Vec<f64>>,
    pub(super) fluxes: AdvectionFluxes<D>,
    /// What crossed the boundary in the last step (Eulerian materials).
    pub(super) exchange: super::BoundaryExchange,
    /// Per cell, the exchange's work of a material held at its prescribed
    /// velocity in the last Lagrangian phase (sized only where a scene has
    /// one).
    pub(super) fixed_work: Vec<f64>,
    pub(super) new_mass: Vec<Vec<f64>>,
    pub(super) new_vel: Vec<Vec<SVector<f64, D>>>,
    pub(super) new_temp: Vec<Vec<f64>>,
    pub(super) new_spvol: Vec<Vec<f64>>,
    pub(super) saved: Vec<MaterialCells<D>>,
    pub(super) implicit: ImplicitSlot<D>,
    pub(super) last_dt: Option<f64>,
    pub(super) accel: Vec<Vec<SVector<f64, D>>>,

    pub(super) vel_pred: Vec<Vec<SVector<f64, D>>>,
    /// Mixture bulk modulus `1/Σ θ κ` per cell, ghosts included (face
    /// predictor, acoustic jump and face viscosity only).
    pub(super) bulk: Vec<f64>,
    /// Mixture sound speed `√(K V/Σ M)` per cell, ghosts included (with
    /// `bulk`).
    pub(super) sound: Vec<f64>,
    /// `V/V^L` per cell of the material being advected, ghosts included
    /// (`IceParams::lagrangian_remap` only).
    pub(super) remap: Vec<f64>,
}

impl<const D: usize> IceWorkspace<D> {
    /// What crossed the domain boundary in the last step: the Eulerian
    /// materials' advection and the face pressures' impulse and work
    /// ([`super::boundary_exchange`]).
    pub fn boundary_exchange(&self) -> super::BoundaryExchange {
        self.exchange
    }

    /// Workspace for a state's layout and materials.
    pub fn new(state: &IceState<D>) -> Self {
        let n = state.layout.len();
        let nm = state.num_materials();
        let s = || vec![0.0; n];
        let sv = || vec![SVector::<f64, D>::zeros(); n];
        Self {
            ustar: (0..nm).map(|_| std::array::from_fn(|_| s())).collect(),
            div: (0..nm).map(|_| s()).collect(),
            kappa: (0..nm).map(|_| s()).collect(),
            div_sum: s(),
            sum_theta_kappa: s(),
            mix_mass: s(),
            press: s(),
            pstar: std::array::from_fn(|_| s()),
            theta_flux: std::array::from_fn(|_| s()),
            mix_vflux: std::array::from_fn(|_| s()),
            ke: (0..nm).map(|_| s()).collect(),
            vel_l: (0..nm).map(|_| sv()).collect(),
            temp_l: (0..nm).map(|_| s()).collect(),
            e_l: (0..nm).map(|_| s()).collect(),
            v_l: (0..nm).map(|_| s()).collect(),
            fluxes: AdvectionFluxes::new(n),
            exchange: super::BoundaryExchange::default(),
            fixed_work: Vec::new(),
            new_mass: (0..nm).map(|_| s()).collect(),
            new_vel: (0..nm).map(|_| sv()).collect(),
            new_temp: (0..nm).map(|_| s()).collect(),
            new_spvol: (0..nm).map(|_| s()).collect(),
            saved: state.cells.clone(),
            implicit: Default::default(),
            last_dt: None,
            accel: Vec::new(),

            vel_pred: Vec::new(),
            bulk: Vec::new(),
            sound: Vec::new(),
            remap: s(),
        }
    }
}

impl<const D: usize> IceWorkspace<D> {
    /// The pressure of the current step (`p_eq + w Δp`, Guilkey Eq. 30),
    /// ghosts filled, after [`super::stage_pressure`].
    pub fn pressure(&self) -> &[f64] {
        &self.press
    }

    /// The face pressures normal to each direction (Guilkey Eq. 31), after
    /// [`super::stage_pressure`].
    pub fn face_pressure(&self) -> &[Vec<f64>; D] {
        &self.pstar
    }

    /// The Lagrangian velocities after the exchange (Guilkey Eq. 38) of
    /// material `r`, after [`super::stage_lagrangian`].
    pub fn lagrangian_velocity(&self, r: usize) -> &[SVector<f64, D>] {
        &self.vel_l[r]
    }

    /// Per cell, material `r`'s Lagrangian temperature after the exchange
    /// (Guilkey Eqs. 37 and 39), after [`super::stage_lagrangian`].
    pub fn lagrangian_temperature(&self, r: usize) -> &[f64] {
        &self.temp_l[r]
    }

    /// Per material and direction, the face velocities `u*` after the face
    /// exchange (Guilkey Eq. 28), after [`super::stage_pressure`].
    pub fn face_velocities(&self) -> &[[Vec<f64>; D]] {
        &self.ustar
    }
}

/// What a step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepInfo {
    /// The time step taken.
    pub dt: f64,
    /// Largest number of equilibration iterations in a cell.
    pub max_equilibration_iterations: usize,
    /// Semi-implicit pressure: outer iterations (linear solves) of the step
    /// (0 for the explicit pressure).
    pub outer_iterations: usize,
    /// Semi-implicit pressure: Krylov iterations summed over the outer
    /// iterations (0 for the direct solver and the explicit pressure).
    pub linear_iterations: usize,
}
