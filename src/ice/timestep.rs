//! The time step of the ICE step: the CFL limit on `Σ_d (|u_d| + c̃)/h_d`
//! with the sound speed seen through the face specific volumes of Guilkey
//! Eq. 28 ([`timestep`], [`timestep_with`]), the explicit viscous limit,
//! and the choice of one step's `Δt` (semi-implicit growth limit, a fixed
//! `Δt` for an outer stepper).

use super::par::max_rows;
use super::params::IceParams;
use super::state::IceState;
use super::{invalid, IceError, MAX_MATERIALS};
use crate::material::eos::EquationOfState;

/// Stable time step `cfl / max_c Σ_d max_r (|u_r,d| + c̃_r)/h_d` from the
/// current (equilibrated, ghosts filled) state, with the sound speed
/// `c̃ = c √(max_f v_f / v)` seen through the face specific volumes of
/// Guilkey Eq. 28.
pub fn timestep<const D: usize>(state: &IceState<D>, cfl: f64) -> f64 {
    timestep_with(state, cfl, 1.0, &[])
}

/// [`timestep`] with the sound speed scaled by `sound_factor`
/// (`cfl / max_c Σ_d max_r (|u_r,d| + sound_factor c̃_r)/h_d`): `0` is the
/// advective limit of the semi-implicit pressure. Materials with
/// `rigid[r]` (a prescribed velocity, [`super::Frame::Rigid`]) add their velocity
/// but not their sound speed: their face velocities do not respond to the
/// pressure (Eq. 28 is replaced by the prescribed value and the exchange
/// locks the fluid to it where they are present), so no acoustic wave
/// travels through them.
pub fn timestep_with<const D: usize>(
    state: &IceState<D>,
    cfl: f64,
    sound_factor: f64,
    rigid: &[bool],
) -> f64 {
    let layout = &state.layout;
    let inv_h = layout.h.map(|h| 1.0 / h);
    let rate = max_rows(layout, |row| {
        let mut rate: f64 = 0.0;
        // c² per material of the cell (the sound speed is the same in
        // every direction).
        let mut c2 = [0.0; MAX_MATERIALS];
        for c in row {
            for (r, (mat, mc)) in state.materials.iter().zip(&state.cells).enumerate() {
                c2[r] = if sound_factor > 0.0 && !rigid.get(r).copied().unwrap_or(false) {
                    mat.eos
                        .sound_speed_sq(1.0 / mc.sp_vol[c], mc.temperature[c])
                } else {
                    0.0
                };
            }
            let mut sum = 0.0;
            for d in 0..D {
                let mut w: f64 = 0.0;
                let s = layout.strides[d];
                for (r, mc) in state.cells.iter().enumerate() {
                    let v = mc.sp_vol[c];
                    // The face velocity (Guilkey Eq. 28) couples the cell to
                    // its neighbours through v_f = 2 v_c v_n/(v_c + v_n)
                    // (< 2 v_n, increasing in v_n): the effective sound speed
                    // is c √(max v_f/v_c), v_f/v_c = 2 v_n/(v_c + v_n).
                    let vn = mc.sp_vol[c - s].max(mc.sp_vol[c + s]);
                    let ratio = (2.0 * vn / (v + vn)).max(1.0);
                    let cs = if c2[r] > 0.0 {
                        sound_factor * (c2[r] * ratio).sqrt()
                    } else {
                        0.0
                    };
                    w = w.max(mc.velocity[c][d].abs() + cs);
                }
                sum += w * inv_h[d];
            }
            rate = rate.max(sum);
        }
        rate
    });
    if rate > 0.0 {
        cfl / rate
    } else {
        f64::INFINITY
    }
}

/// Largest explicit viscous rate `2 Σ_d max_r μ_r v_r / h_d²` (the time
/// step of the viscous term must stay below `1/rate`); zero without
/// viscosity.
fn viscous_rate<const D: usize>(state: &IceState<D>, mu: &[f64]) -> f64 {
    let layout = &state.layout;
    let inv_h2: f64 = (0..D).map(|d| 1.0 / (layout.h[d] * layout.h[d])).sum();
    max_rows(layout, |row| {
        let mut rate: f64 = 0.0;
        for c in row {
            for (r, mc) in state.cells.iter().enumerate() {
                rate = rate.max(2.0 * mu[r] * mc.sp_vol[c] * inv_h2);
            }
        }
        rate
    })
}

/// The sound-speed factor of a semi-implicit step: `sound_speed_factor`,
/// but at least 1 on a run's first step (no `last_dt`). A gas at rest has
/// no advective limit, so without it the first step took whatever
/// `dt_max` allowed (the whole output interval) and kept what survived the
/// halvings of failed pressure iterations; from the acoustic step the run
/// grows by `max_dt_growth` a step (at 1.2, 100× in 26 steps).
pub fn first_step_factor(sp: &super::SemiImplicit, last_dt: Option<f64>) -> f64 {
    if last_dt.is_none() {
        sp.sound_speed_factor.max(1.0)
    } else {
        sp.sound_speed_factor
    }
}

/// The time step of one step: exactly `dt_max` when `fixed`, otherwise the
/// CFL limit of [`timestep_with`] (semi-implicit: with the sound speed
/// scaled by `sound_speed_factor` and at most `max_dt_growth` times the
/// last step's `last_dt`), the explicit viscous limit, and `dt_max`.
///
/// # Errors
/// [`IceError::InvalidInput`] for a non-finite or non-positive `Δt`.
pub(super) fn step_dt<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    last_dt: Option<f64>,
    dt_max: f64,
    fixed: bool,
) -> Result<f64, IceError> {
    let mu = params
        .viscosity
        .as_deref()
        .filter(|m| m.iter().any(|&x| x > 0.0));
    let implicit = params.implicit.as_ref();
    let dt = if fixed {
        dt_max
    } else {
        // Semi-implicit: the sound speed no longer limits the step (only
        // through `sound_speed_factor`, default 0), and the step grows by at
        // most `max_dt_growth` per step, from an acoustic first step.
        let factor = implicit.map_or(1.0, |sp| first_step_factor(sp, last_dt));
        let mut dt = timestep_with(state, params.cfl, factor, &params.rigid_mask());
        if let Some(mu) = mu {
            let rate = viscous_rate(state, mu);
            if rate > 0.0 {
                dt = dt.min(params.cfl.min(1.0) / rate);
            }
        }
        if let (Some(sp), Some(last)) = (implicit, last_dt) {
            dt = dt.min(sp.max_dt_growth * last);
        }
        dt.min(dt_max)
    };
    if !(dt.is_finite() && dt > 0.0) {
        return Err(invalid(
            "dt",
            format!("time step must be finite and > 0, got {dt}"),
        ));
    }
    Ok(dt)
}
