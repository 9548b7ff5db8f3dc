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

/// The scene with its first material replaced by copper (Steinberg,
/// UCRL-MA-106439: ρ₀ = 8930 kg/m³, c₀ = 3940 m/s, s = 1.49, Γ₀ = 2.02;
/// c_v = 383 J/(kg K)), at the same reference temperature and pressure.
pub fn copper(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    if let Some(m) = s.materials.first_mut() {
        m.name = "copper".into();
        m.reference_density = Some(8930.0);
        m.c0 = Some(3940.0);
        m.s = Some(1.49);
        m.gruneisen = Some(2.02);
        m.cv = Some(383.0);
    }
    for r in &mut s.regions {
        for st in &mut r.states {
            st.material = "copper".into();
        }
    }
    s
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
    let mut row = Vec::new();
    for k in 0..samples {
        let t = t_end * (0.25 + 0.75 * k as f64 / (samples - 1) as f64);
        let run = run_fluid(state, &params, t, 10_000_000)?;
        steps += run.steps;
        wall_s += run.wall_s;
        state = run.state;
        for &c in &state.layout.interior {
            p_max = p_max.max(state.p_eq[c].abs());
        }
        cell_profile(&state, &mut row);
        let x = front_of(&row, p_mid).ok_or_else(|| {
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

/// The wall shock of [`wall_shock`] with the material of `scene` (its
/// first, a Mie–Grüneisen fluid) on gas material points (York Sec. 3.3,
/// `frame = "particles"`, York's artificial viscosity with the paper's
/// constants, GIMP, MUSL): a 2D strip one cell high, `cells` cells of
/// `1/cells` m along x, 3 × 3 points per cell, a symmetry plane (wall) at
/// `x = 0` and a free surface at the far end. The release from the free
/// surface runs into the material at `c₀`, so the shock is followed over
/// `0.4 L` only (it meets the release later for every `u_p` here);
/// `samples` fit times in the last three quarters.
///
/// # Errors
/// Scene errors, and any failure of the run.
pub fn gas_point_wall_shock(
    scene: &Scene,
    cells: usize,
    up: f64,
    samples: usize,
) -> Result<WallShock, Error> {
    let eos = mie_gruneisen(scene)?;
    let m = &scene.materials[0];
    let (rho0, p0, t0) = (
        eos.reference_density(),
        eos.reference_pressure(),
        eos.reference_temperature(),
    );
    let h = 1.0 / cells as f64;
    let us_exact = eos.shock_speed(up);
    let t_end = 0.4 / (us_exact - up);
    let text = format!(
        r#"
[grid]
dim = 2
lower = [0.0, 0.0]
upper = [1.0, {h}]
cells = [{cells}, 1]
boundary = {{ x_lower = "symmetry", x_upper = "free", y_lower = "symmetry", y_upper = "symmetry" }}

[time]
end = {t_end}
cfl = 0.4

[mpm]
shape = "gimp"
update = "musl"

[[materials]]
name = "{name}"
type = "fluid"
frame = "particles"
eos = "mie_gruneisen"
reference_density = {rho0}
c0 = {c0}
s = {s}
gruneisen = {g0}
cv = {cv}
reference_temperature = {t0}
reference_pressure = {p0}

[[objects]]
material = "{name}"
geometry = {{ type = "box", lower = [0.0, 0.0], upper = [1.0, {h}] }}
particles_per_cell = 3
density = {rho0}
pressure = {p0}
velocity = [{v}, 0.0]
"#,
        name = m.name,
        c0 = eos.c0(),
        s = eos.s(),
        g0 = eos.gruneisen(),
        cv = crate::material::eos::EquationOfState::specific_heat_cv(&eos),
        v = -up,
    );
    let scene = crate::scene::parse(&text)?;
    let mut run = crate::scene::build_solid_run::<2>(&scene)?;
    let gas = run.materials[0].gas().copied().ok_or_else(|| {
        SceneError::new(
            "materials[0].frame",
            "expected gas points (frame = \"particles\")",
        )
    })?;
    let p_exact = p0 + rho0 * us_exact * up;
    let p_mid = 0.5 * (p0 + p_exact);
    let samples = samples.max(2);
    let start = std::time::Instant::now();
    let mut fit = LineFit::default();
    let mut p_max = 0.0f64;
    let mut next = 0;
    let mut row: Vec<(f64, f64)> = Vec::new();
    // Pressure of the points of the lowest row, sorted by x.
    let profile = |run: &crate::stepper::SolidRun<2>, row: &mut Vec<(f64, f64)>| {
        let pt = &run.particles;
        row.clear();
        for i in 0..pt.len() {
            if pt.x0[i][1] < h / 3.0 {
                let rho = pt.mass[i] / pt.vol[i];
                let e = pt.work_of(i) * pt.vol0[i] / pt.mass[i];
                row.push((pt.x[i][0], gas.pressure(rho, e)));
            }
        }
        row.sort_by(|a, b| a.0.total_cmp(&b.0));
    };
    while !run.finished() {
        run.step()?;
        let t_next = t_end * (0.25 + 0.75 * next as f64 / (samples - 1) as f64);
        if next < samples && run.t >= t_next * (1.0 - 1e-12) {
            profile(&run, &mut row);
            p_max = row.iter().fold(p_max, |a, r| a.max(r.1.abs()));
            let x = front_of(&row, p_mid).ok_or_else(|| {
                SceneError::new("time.end", format!("no shock front at t = {:.6e}", run.t))
            })?;
            fit.add(run.t, x);
            next += 1;
        }
    }
    let wall_s = start.elapsed().as_secs_f64();
    profile(&run, &mut row);
    let x_s = fit.at(run.t);
    let mid: Vec<f64> = row
        .iter()
        .filter(|r| r.0 >= 0.25 * x_s && r.0 <= 0.75 * x_s)
        .map(|r| r.1)
        .collect();
    Ok(WallShock {
        up,
        h,
        us_exact,
        us: fit.slope() + up,
        p_exact,
        p_post: mid.iter().sum::<f64>() / mid.len() as f64,
        p_max,
        steps: run.steps,
        wall_s,
    })
}

/// Position where the pressure of `(x, p)` points sorted by `x`, scanned
/// from the largest `x`, first reaches `p_mid` (linear interpolation).
fn front_of(row: &[(f64, f64)], p_mid: f64) -> Option<f64> {
    for i in (0..row.len()).rev() {
        let (x, p) = row[i];
        if p >= p_mid {
            let Some(&(x1, p1)) = row.get(i + 1) else {
                return Some(x);
            };
            return Some(x + (p_mid - p) / (p1 - p) * (x1 - x));
        }
    }
    None
}

/// `(x, p)` of the interior cells (x from the lower boundary), in order.
fn cell_profile(state: &IceState<1>, row: &mut Vec<(f64, f64)>) {
    row.clear();
    let lower = state.layout.lower[0];
    for &c in &state.layout.interior {
        row.push((state.layout.centre(c)[0] - lower, state.p_eq[c]));
    }
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
