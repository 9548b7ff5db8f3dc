//! Settings of the semi-implicit (implicit-pressure) ICE step
//! ([`super::IceParams::implicit`]): the outer iteration on Guilkey Eq. 29
//! ([`SemiImplicit`]) and the linear solver of its pressure matrix
//! ([`LinearSolver`], [`pressure_mg_options`]). The iteration itself is in
//! [`super::implicit`], the matrix in `pressure_system`.

use std::str::FromStr;

use solvers::MgOptions;

use super::{invalid, IceError};

/// Linear solver of the pressure equation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LinearSolver {
    /// Sparse Cholesky (faer), symbolic factorisation computed once and
    /// reused; numeric refactorisation every step.
    Direct,
    /// Conjugate gradients preconditioned by one geometric multigrid V-cycle
    /// ([`solvers::Multigrid`] with [`pressure_mg_options`], hierarchy
    /// refreshed every step). Periodic directions need an even number of
    /// cells unless the grid is small enough (≤ 128 cells) to be the
    /// multigrid's directly solved coarsest level.
    PcgMultigrid,
    /// Conjugate gradients preconditioned by the diagonal.
    PcgJacobi,
}

impl LinearSolver {
    /// The accepted names, in the order of the variants.
    pub const NAMES: [&'static str; 3] = ["direct", "pcg_multigrid", "pcg_jacobi"];

    /// Stable name of the variant.
    pub fn name(self) -> &'static str {
        match self {
            LinearSolver::Direct => "direct",
            LinearSolver::PcgMultigrid => "pcg_multigrid",
            LinearSolver::PcgJacobi => "pcg_jacobi",
        }
    }
}

impl FromStr for LinearSolver {
    type Err = IceError;

    /// Parses one of [`LinearSolver::NAMES`].
    ///
    /// # Errors
    /// [`IceError::InvalidInput`] naming `implicit.linear_solver`.
    fn from_str(name: &str) -> Result<Self, IceError> {
        match name {
            "direct" => Ok(LinearSolver::Direct),
            "pcg_multigrid" => Ok(LinearSolver::PcgMultigrid),
            "pcg_jacobi" => Ok(LinearSolver::PcgJacobi),
            _ => Err(invalid(
                "implicit.linear_solver",
                format!(
                    "unknown solver `{name}`; expected one of {}",
                    Self::NAMES.join(", ")
                ),
            )),
        }
    }
}

/// Parameters of the semi-implicit pressure ([`super::IceParams::implicit`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SemiImplicit {
    /// Linear solver of the pressure equation.
    pub linear_solver: LinearSolver,
    /// Relative residual `‖b − Mx‖₂/‖b‖₂` of an iterative linear solve
    /// (`0 < tol < 1`); it must be tighter than the outer tolerance relative
    /// to the residual being solved for, which `1e-10` is by far.
    pub linear_tolerance: f64,
    /// Outer tolerance on `max_c |R_c|/V` (a volume strain per step, the
    /// imbalance of Guilkey Eq. 29), `> 0`.
    pub outer_tolerance: f64,
    /// Largest number of outer iterations (linear solves) per step, `≥ 1`.
    pub max_outer_iterations: usize,
    /// Largest number of Krylov iterations per linear solve, `≥ 1`.
    pub max_linear_iterations: usize,
    /// Factor on the sound speed in the time step estimate
    /// (`cfl / max Σ_d (|u_d| + factor c)/h_d`); `0` (default) limits the
    /// step by advection only, `1` makes `cfl` an acoustic Courant number.
    pub sound_speed_factor: f64,
    /// Largest ratio of a time step to the previous one, `≥ 1`; a run's
    /// first step is acoustic ([`super::timestep::first_step_factor`]).
    pub max_dt_growth: f64,
    /// Convective predictor `β ∈ [0, 1]`: the cell velocities entering the
    /// face velocities of Guilkey Eq. 28 are `uⁿ + β Δt aⁿ⁻¹`, with
    /// `aⁿ⁻¹ = (uⁿ − u_Lⁿ⁻¹)/Δtⁿ⁻¹` the previous step's advective
    /// acceleration (its advected, step 12, minus its Lagrangian, Eq. 38,
    /// velocity).
    ///
    /// Why: Guilkey (Sec. 3.3, step 3) builds `u*` from "a time advanced
    /// estimate for the cell centered velocity", but Eq. 28 advances the
    /// cell velocity by the pressure (and body-force) acceleration only; the
    /// Lagrangian–Eulerian split adds this step's convective change in
    /// step 12, after Eqs. 29–30 have fixed the pressure. So with `β = 0`
    /// the pressure makes `Σ∇·(θu*)` consistent with a velocity that lacks
    /// this step's convection, which is corrected only by the next step's
    /// pressure: the pressure lags one step, an `O(Δt)` error that is
    /// negligible at the explicit (acoustic) time step and dominant at
    /// large acoustic Courant numbers. `β = 1` adds the convective change
    /// to the time-advanced estimate, extrapolated from the previous step
    /// (first-order extrapolation, error `O(Δt²)` in the estimate), as
    /// projection methods include the convective term in the predicted
    /// face (MAC) velocities they project (Bell, Colella & Glaz, J. Comput.
    /// Phys. 85 (1989) 257). Only the face velocities change: mass,
    /// momentum and energy stay in flux form and are conserved as before.
    /// The first step of a run has no previous acceleration and uses
    /// Eq. 28 as written. Used only by the semi-implicit pressure.
    ///
    /// Measured: `ice_low_mach --quick` (N = 64, t = 0.5) RMS velocity
    /// error at acoustic CFL 10 1.01e-3 → 8.05e-4 and at CFL 50 2.28e-3 →
    /// 9.73e-4 with `β = 1` (explicit CFL 1: 8.25e-4); the full study's
    /// numbers are in `verification/RESULTS.md`. Stable at acoustic CFL
    /// 100 (`acoustic_cfl_100_with_predictor_is_stable`). Default `0`
    /// (Guilkey Eq. 28 as written).
    pub convective_predictor: f64,
}

impl Default for SemiImplicit {
    /// Cholesky, `linear_tolerance = 1e-10`, `outer_tolerance = 1e-9`, 20
    /// outer and 500 linear iterations, `sound_speed_factor = 0`,
    /// `max_dt_growth = 1.2`.
    fn default() -> Self {
        Self {
            linear_solver: LinearSolver::Direct,
            linear_tolerance: 1e-10,
            outer_tolerance: 1e-9,
            max_outer_iterations: 20,
            max_linear_iterations: 500,
            sound_speed_factor: 0.0,
            max_dt_growth: 1.2,
            convective_predictor: 0.0,
        }
    }
}

impl SemiImplicit {
    /// Defaults with the given linear solver.
    pub fn with_solver(linear_solver: LinearSolver) -> Self {
        Self {
            linear_solver,
            ..Self::default()
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`IceError::InvalidInput`] naming the field (`implicit.…`).
    pub fn validate(&self) -> Result<(), IceError> {
        let t = self.linear_tolerance;
        if !(t.is_finite() && t > 0.0 && t < 1.0) {
            return Err(invalid(
                "implicit.linear_tolerance",
                format!("must be in (0, 1), got {t}"),
            ));
        }
        let t = self.outer_tolerance;
        if !(t.is_finite() && t > 0.0) {
            return Err(invalid(
                "implicit.outer_tolerance",
                format!("must be finite and > 0, got {t}"),
            ));
        }
        if self.max_outer_iterations == 0 {
            return Err(invalid("implicit.max_outer_iterations", "must be >= 1"));
        }
        if self.max_linear_iterations == 0 {
            return Err(invalid("implicit.max_linear_iterations", "must be >= 1"));
        }
        let f = self.sound_speed_factor;
        if !(f.is_finite() && f >= 0.0) {
            return Err(invalid(
                "implicit.sound_speed_factor",
                format!("must be finite and >= 0, got {f}"),
            ));
        }
        let g = self.max_dt_growth;
        if !(g.is_finite() && g >= 1.0) {
            return Err(invalid(
                "implicit.max_dt_growth",
                format!("must be finite and >= 1, got {g}"),
            ));
        }
        let b = self.convective_predictor;
        if !(b.is_finite() && (0.0..=1.0).contains(&b)) {
            return Err(invalid(
                "implicit.convective_predictor",
                format!("must be in [0, 1], got {b}"),
            ));
        }
        Ok(())
    }
}

/// Multigrid options of [`LinearSolver::PcgMultigrid`]: the default V(3,3)
/// cycle, with the coarsest level (factorised again every step, as the
/// coefficients change) at most 128 cells instead of 2048. Measured on the
/// `ice_low_mach` vortex at 128², acoustic CFL 50: 0.89 s CPU for the run
/// against 1.14 s with 2048 (the 32² coarsest Cholesky refactorisation and
/// its triangular solves were ~6% of the step), 6.9–7.0 PCG iterations per
/// step either way. A periodic direction with an odd number of cells is
/// only accepted when the whole grid fits this coarsest level (see
/// [`solvers::Multigrid`]).
pub fn pressure_mg_options() -> MgOptions {
    MgOptions {
        coarse_max_cells: 128,
        ..MgOptions::default()
    }
}
