//! One ICE step for a fluid-only scene as the sequence of its stages
//! (Guilkey Sec. 3.3 steps 2, 3, 5, 6, 8–12): [`super::pressure`] (steps
//! 2–6), [`super::lagrangian`] (steps 8–11) and [`super::advect`] (step
//! 12), once (forward Euler) or twice (Heun); and a small driver
//! ([`run_fluid`]).

use std::time::Instant;

use super::advect::stage_advect;
use super::lagrangian::stage_lagrangian;
use super::params::{EnergyForm, IceParams, TimeIntegration};
use super::pressure::{equilibrate, stage_pressure};
use super::state::IceState;
use super::workspace::{IceWorkspace, StepInfo};
use super::{invalid, IceError};
use crate::material::eos::EquationOfState;

/// One explicit ICE step with `Δt = min(dt_max, cfl-limited Δt)`.
///
/// Sequence (Guilkey Sec. 3.3): ghosts; equilibration pressure (Eq. 13);
/// face velocities (Eq. 28) and face exchange; `Δp` (Eq. 29) and `p`
/// (Eq. 30); face pressure (Eq. 31); sources (Eqs. 33–34); Lagrangian
/// values (Eqs. 35–37); exchange (Eqs. 38–39); specific volume (Eqs. 40–41);
/// advection (step 12).
///
/// On error the primary state (mass, velocity, temperature, time) is
/// unchanged; [`IceError::TimestepTooLarge`] asks for a retry with a smaller
/// `dt_max`.
///
/// # Errors
/// [`IceError::Equilibration`], [`IceError::TimestepTooLarge`],
/// [`IceError::NonPhysical`], naming step, time, cell and material.
pub fn step<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt_max: f64,
) -> Result<StepInfo, IceError> {
    advance(state, params, ws, dt_max, false)
}

/// [`step`] with exactly the time step `dt` (no CFL limit), for a stepper
/// that chooses `Δt` itself (e.g. from the solid's sound speed); a `dt`
/// that empties a cell returns [`IceError::TimestepTooLarge`].
///
/// # Errors
/// As [`step`].
pub fn step_with_dt<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt: f64,
) -> Result<StepInfo, IceError> {
    advance(state, params, ws, dt, true)
}

fn advance<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt_max: f64,
    fixed: bool,
) -> Result<StepInfo, IceError> {
    let info = advance_inner(state, params, ws, dt_max, fixed)?;
    ws.last_dt = Some(info.dt);
    Ok(info)
}

fn advance_inner<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt_max: f64,
    fixed: bool,
) -> Result<StepInfo, IceError> {
    match params.time {
        TimeIntegration::ForwardEuler => stage(state, params, ws, dt_max, fixed),
        TimeIntegration::Heun => heun(state, params, ws, dt_max, fixed),
    }
}

/// Heun / SSP-RK2 ([`TimeIntegration::Heun`]): two passes of the sequence
/// with the same `Δt`, then `U^{n+1} = (U^n + S(S(U^n)))/2` on the
/// conserved quantities. On an error of the second pass the state is
/// restored.
fn heun<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt_max: f64,
    fixed: bool,
) -> Result<StepInfo, IceError> {
    let (t0, n0) = (state.time, state.steps);
    for (saved, mc) in ws.saved.iter_mut().zip(&state.cells) {
        saved.mass.copy_from_slice(&mc.mass);
        saved.velocity.copy_from_slice(&mc.velocity);
        saved.temperature.copy_from_slice(&mc.temperature);
        saved.sp_vol.copy_from_slice(&mc.sp_vol);
    }
    let first = stage(state, params, ws, dt_max, fixed)?;
    let second = stage(state, params, ws, first.dt, true);
    let restore = |state: &mut IceState<D>, ws: &IceWorkspace<D>| {
        for (saved, mc) in ws.saved.iter().zip(state.cells.iter_mut()) {
            mc.mass.copy_from_slice(&saved.mass);
            mc.velocity.copy_from_slice(&saved.velocity);
            mc.temperature.copy_from_slice(&saved.temperature);
            mc.sp_vol.copy_from_slice(&saved.sp_vol);
        }
        state.time = t0;
        state.steps = n0;
    };
    let second = match second {
        Ok(s) => s,
        Err(e) => {
            restore(state, ws);
            return Err(e);
        }
    };
    heun_average(state, params, ws);
    state.time = t0 + first.dt;
    state.steps = n0 + 1;
    Ok(StepInfo {
        dt: first.dt,
        max_equilibration_iterations: first
            .max_equilibration_iterations
            .max(second.max_equilibration_iterations),
        outer_iterations: first.outer_iterations + second.outer_iterations,
        linear_iterations: first.linear_iterations + second.linear_iterations,
    })
}

/// `U^{n+1} = (U^n + S(S(U^n)))/2` on the conserved quantities (mass,
/// momentum, energy, material volume) of every interior cell, from the
/// saved `U^n` (`ws.saved`) and the state after the second pass.
fn heun_average<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &IceWorkspace<D>,
) {
    let conservative = params.energy == EnergyForm::Conservative;
    for (r, (saved, mc)) in ws.saved.iter().zip(state.cells.iter_mut()).enumerate() {
        let cv = state.materials[r].eos.specific_heat_cv();
        for &c in &state.layout.interior {
            let (m0, m2) = (saved.mass[c], mc.mass[c]);
            let m = 0.5 * (m0 + m2);
            let (u0, u2) = (saved.velocity[c], mc.velocity[c]);
            let u = (u0 * m0 + u2 * m2) * (0.5 / m);
            let mut me = 0.5 * cv * (m0 * saved.temperature[c] + m2 * mc.temperature[c]);
            if conservative {
                let ke = 0.25 * (m0 * u0.norm_squared() + m2 * u2.norm_squared())
                    - 0.5 * m * u.norm_squared();
                if me + ke > 0.0 {
                    me += ke;
                }
            }
            mc.sp_vol[c] = 0.5 * (m0 * saved.sp_vol[c] + m2 * mc.sp_vol[c]) / m;
            mc.mass[c] = m;
            mc.velocity[c] = u;
            mc.temperature[c] = me / (m * cv);
        }
    }
}

/// One forward-Euler pass of the step sequence; `fixed` uses exactly
/// `dt_max` instead of the CFL limit.
fn stage<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt_max: f64,
    fixed: bool,
) -> Result<StepInfo, IceError> {
    let info = stage_pressure(state, params, ws, dt_max, fixed)?;
    stage_lagrangian(state, params, ws, info.dt, &[])?;
    stage_advect(state, params, ws, info)
}

/// Result of [`run_fluid`].
#[derive(Debug, Clone)]
pub struct FluidRun<const D: usize> {
    /// Final state (equilibrated: `p_eq`, `sp_vol`, `vol_frac` are
    /// consistent with the final masses and temperatures).
    pub state: IceState<D>,
    /// Steps taken.
    pub steps: u64,
    /// Steps retried with a smaller time step.
    pub retries: u64,
    /// Wall-clock time of the time loop in seconds.
    pub wall_s: f64,
    /// Semi-implicit pressure: outer iterations summed over the steps.
    pub outer_iterations: u64,
    /// Semi-implicit pressure: Krylov iterations summed over the steps.
    pub linear_iterations: u64,
    /// Semi-implicit pressure: largest outer iteration count of a step.
    pub max_outer_iterations: usize,
    /// Semi-implicit pressure: largest Krylov iteration count of a step.
    pub max_linear_iterations: usize,
}

impl<const D: usize> FluidRun<D> {
    /// One line for a run summary: steps, retries, wall time and (for the
    /// semi-implicit pressure) the outer and linear iterations per step.
    pub fn summary(&self) -> String {
        let per = |x: u64| x as f64 / self.steps.max(1) as f64;
        format!(
            "{} steps ({} retried) in {:.3} s; pressure solve: {:.2} outer (max {}) and {:.1} linear (max {}) iterations per step",
            self.steps,
            self.retries,
            self.wall_s,
            per(self.outer_iterations),
            self.max_outer_iterations,
            per(self.linear_iterations),
            self.max_linear_iterations
        )
    }
}

/// Runs a fluid-only scene from `state` to `t_end` (at most `max_steps`
/// steps), retrying a step with half the time step when it reports a
/// retryable error ([`IceError::TimestepTooLarge`], or a failed semi-implicit
/// pressure solve, [`IceError::PressureSolve`]; up to 20 times in a row).
///
/// # Errors
/// [`IceError::InvalidInput`] for invalid parameters, a non-finite `t_end`
/// or exceeding `max_steps`; any error of [`step`].
pub fn run_fluid<const D: usize>(
    mut state: IceState<D>,
    params: &IceParams<D>,
    t_end: f64,
    max_steps: u64,
) -> Result<FluidRun<D>, IceError> {
    params.validate(&state)?;
    if !(t_end.is_finite() && t_end >= state.time) {
        return Err(invalid(
            "t_end",
            format!(
                "must be finite and >= the current time {}, got {t_end}",
                state.time
            ),
        ));
    }
    let mut ws = IceWorkspace::new(&state);
    let start = Instant::now();
    let mut steps = 0u64;
    let mut retries = 0u64;
    let (mut outer, mut linear, mut max_outer, mut max_linear) = (0u64, 0u64, 0usize, 0usize);
    // Stop within a relative round-off of t_end.
    while state.time < t_end * (1.0 - 1e-14) {
        if steps >= max_steps {
            return Err(invalid(
                "max_steps",
                format!(
                    "{max_steps} steps reached at t = {} < t_end = {t_end}",
                    state.time
                ),
            ));
        }
        let mut dt_max = t_end - state.time;
        let mut tries = 0;
        loop {
            match step(&mut state, params, &mut ws, dt_max) {
                Ok(info) => {
                    outer += info.outer_iterations as u64;
                    linear += info.linear_iterations as u64;
                    max_outer = max_outer.max(info.outer_iterations);
                    max_linear = max_linear.max(info.linear_iterations);
                    break;
                }
                Err(e) if tries < 20 && e.retry_dt().is_some() => {
                    dt_max = 0.5 * e.retry_dt().unwrap_or(dt_max);
                    tries += 1;
                    retries += 1;
                }
                Err(e) => return Err(e),
            }
        }
        steps += 1;
    }
    let wall_s = start.elapsed().as_secs_f64();
    equilibrate(&mut state, params)?;
    Ok(FluidRun {
        state,
        steps,
        retries,
        wall_s,
        outer_iterations: outer,
        linear_iterations: linear,
        max_outer_iterations: max_outer,
        max_linear_iterations: max_linear,
    })
}
