//! A planar shock in a Mie–Grüneisen liquid or metal, measured against the
//! linear `U_s–u_p` Hugoniot (`cases/mie_gruneisen_shock.toml`).
//!
//! The material at its EOS reference state `(ρ₀, T₀, p₀)` fills `[0, L]`
//! and moves at `−u_p` into a reflecting wall at `x = 0`. The reflected
//! shock leaves the wall with the material behind it at rest, so relative
//! to the undisturbed material it is the shock of piston speed `u_p`:
//!
//! ```text
//! U_s = c₀ + s u_p,     x_s(t) = (U_s − u_p) t,     p₁ − p₀ = ρ₀ U_s u_p
//! ```
//!
//! (the jump conditions with the principal Hugoniot, Lian Eq. 66's `p_H`).
//! The measured shock speed is the least-squares slope of the front
//! position (where the pressure crosses `p₀ + ρ₀ U_s u_p / 2`, interpolated
//! between cell centres) over `samples` times in the last three quarters of
//! the run, plus `u_p`; the post-shock pressure is the mean over the middle
//! half of the shocked layer at the end.

use crate::error::{Error, SceneError};
use crate::ice::{run_fluid, IceState};
use crate::material::eos::{FluidEos, MieGruneisen};
use crate::scene::{build_fluid_run, Scene};

/// What [`wall_shock`] measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallShock {
    /// Piston (particle) speed `u_p`.
    pub up: f64,
    /// Cell size `h`.
    pub h: f64,
    /// Exact shock speed `c₀ + s u_p`.
    pub us_exact: f64,
    /// Measured shock speed relative to the undisturbed material.
    pub us: f64,
    /// Exact post-shock pressure `p₀ + ρ₀ U_s u_p`.
    pub p_exact: f64,
    /// Measured post-shock pressure.
    pub p_post: f64,
    /// Largest `|p|` anywhere at the sample times (overshoot check).
    pub p_max: f64,
    /// Time steps taken.
    pub steps: u64,
    /// Wall-clock seconds of the time loops.
    pub wall_s: f64,
}

impl WallShock {
    /// `|U_s − U_s,exact| / U_s,exact`.
    pub fn us_error(&self) -> f64 {
        (self.us - self.us_exact).abs() / self.us_exact
    }

    /// `|p₁ − p₁,exact| / (p₁,exact − p₀)`: relative to the pressure jump.
    pub fn p_error(&self, p0: f64) -> f64 {
        (self.p_post - self.p_exact).abs() / (self.p_exact - p0)
    }
}

/// The 1D scene `scene` (one Mie–Grüneisen fluid, one region moving at
/// `velocity = [−u_p]`, a wall at `x_lower`) with `cells` cells and piston
/// speed `up`; its end time is set so the shock travels `0.8 L`.
///
/// # Errors
/// A [`SceneError`] when the scene is not of that form.
pub fn wall_shock_scene(scene: &Scene, cells: usize, up: f64) -> Result<Scene, SceneError> {
    let mut s = scene.clone();
    let eos = mie_gruneisen(&s)?;
    if s.grid.dim != 1 || s.regions.len() != 1 || s.regions[0].states.len() != 1 {
        return Err(SceneError::new(
            "regions",
            "the wall shock needs dim = 1 and one region of one material",
        ));
    }
    s.grid.cells = vec![cells];
    s.regions[0].states[0].velocity = Some(vec![-up]);
    let length = s.grid.upper[0] - s.grid.lower[0];
    s.time.end = 0.8 * length / (eos.shock_speed(up) - up);
    Ok(s)
}

fn mie_gruneisen(scene: &Scene) -> Result<MieGruneisen, SceneError> {
    match scene.materials.first().map(|m| m.fluid_eos()) {
        Some(Ok(FluidEos::MieGruneisen(m))) => Ok(m),
        _ => Err(SceneError::new(
            "materials[0].eos",
            "the wall shock needs a first material with eos = \"mie_gruneisen\"",
        )),
    }
}

/// Runs the wall shock of a scene from [`wall_shock_scene`] and measures it
/// at `samples ≥ 2` times (module notes).
///
/// # Errors
/// Scene errors (also when the material does not start at its reference
/// state), and any fluid failure of the run.
pub fn wall_shock(scene: &Scene, samples: usize) -> Result<WallShock, Error> {
    let eos = mie_gruneisen(scene)?;
    let (mut state, params) = build_fluid_run::<1>(scene)?;
    let c_first = state.layout.interior[0];
    let (rho_a, p_a) = (1.0 / state.cells[0].sp_vol[c_first], state.p_eq[c_first]);
    let rho0 = eos.reference_density();
    if (rho_a / rho0 - 1.0).abs() > 1e-12
        || (p_a - eos.reference_pressure()).abs() > 1e-9 * p_a.abs().max(1.0)
    {
        return Err(SceneError::new(
            "regions[0]",
            format!(
                "the material must start at its reference state (rho0 = {rho0}, p0 = {}), got \
                 rho = {rho_a}, p = {p_a}",
                eos.reference_pressure()
            ),
        )
        .into());
    }
    let up = -state.cells[0].velocity[c_first][0];
    let us_exact = eos.shock_speed(up);
    let p0 = eos.reference_pressure();
    let p_exact = p0 + rho0 * us_exact * up;
    let p_mid = 0.5 * (p0 + p_exact);
    let t_end = scene.time.end;
    let samples = samples.max(2);
    let (mut steps, mut wall_s, mut p_max) = (0u64, 0.0, 0.0f64);
    let mut fit = LineFit::default();
    for k in 0..samples {
        let t = t_end * (0.25 + 0.75 * k as f64 / (samples - 1) as f64);
        let run = run_fluid(state, &params, t, 10_000_000)?;
        steps += run.steps;
        wall_s += run.wall_s;
        state = run.state;
        for &c in &state.layout.interior {
            p_max = p_max.max(state.p_eq[c].abs());
        }
        let x = front(&state, p_mid).ok_or_else(|| {
            SceneError::new(
                "time.end",
                format!("no shock front found at t = {t:.6e} (has it left the domain?)"),
            )
        })?;
        fit.add(state.time, x);
    }
    let us = fit.slope() + up;
    // Mean pressure over the middle half of the shocked layer.
    let x_s = fit.at(state.time);
    let (mut sum, mut n) = (0.0, 0usize);
    for &c in &state.layout.interior {
        let x = state.layout.centre(c)[0] - state.layout.lower[0];
        if x >= 0.25 * x_s && x <= 0.75 * x_s {
            sum += state.p_eq[c];
            n += 1;
        }
    }
    Ok(WallShock {
        up,
        h: state.layout.h[0],
        us_exact,
        us,
        p_exact,
        p_post: if n > 0 { sum / n as f64 } else { f64::NAN },
        p_max,
        steps,
        wall_s,
    })
}

/// Position (from the lower boundary) where the pressure, scanned from the
/// upper end, first reaches `p_mid`, interpolated linearly between cell
/// centres.
fn front(state: &IceState<1>, p_mid: f64) -> Option<f64> {
    let cells = &state.layout.interior;
    let lower = state.layout.lower[0];
    for i in (0..cells.len()).rev() {
        let (c, p) = (cells[i], state.p_eq[cells[i]]);
        if p >= p_mid {
            let x = state.layout.centre(c)[0] - lower;
            let Some(&up) = cells.get(i + 1) else {
                return Some(x);
            };
            let (x1, p1) = (state.layout.centre(up)[0] - lower, state.p_eq[up]);
            return Some(x + (p_mid - p) / (p1 - p) * (x1 - x));
        }
    }
    None
}

/// Least-squares straight line through `(t, x)` points.
#[derive(Debug, Default, Clone, Copy)]
struct LineFit {
    n: f64,
    st: f64,
    sx: f64,
    stt: f64,
    stx: f64,
}

impl LineFit {
    fn add(&mut self, t: f64, x: f64) {
        self.n += 1.0;
        self.st += t;
        self.sx += x;
        self.stt += t * t;
        self.stx += t * x;
    }

    fn slope(&self) -> f64 {
        (self.n * self.stx - self.st * self.sx) / (self.n * self.stt - self.st * self.st)
    }

    fn at(&self, t: f64) -> f64 {
        (self.sx - self.slope() * self.st) / self.n + self.slope() * t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_fit_recovers_a_line() {
        let mut f = LineFit::default();
        for k in 0..7 {
            let t = 0.1 * k as f64;
            f.add(t, 2.5 - 3.0 * t);
        }
        assert!((f.slope() + 3.0).abs() < 1e-13);
        assert!((f.at(1.0) + 0.5).abs() < 1e-13);
    }
}
