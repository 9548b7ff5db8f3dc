//! York Sec. 4.1: Sod's shock tube with gas material points, against the
//! exact Riemann solution — the scene ([`york_sod_scene`], the same as
//! `cases/york_sod.toml` at any resolution), a run through the explicit
//! MPM model ([`run_york_sod`]) and its L1 density error.

use std::time::Instant;

use super::riemann::{ExactRiemann, PrimitiveState};
use crate::error::{Result, SceneError};
use crate::material::ArtificialViscosity;
use crate::shape::ShapeKind;

/// One York Sod run's settings.
#[derive(Debug, Clone, Copy)]
pub struct YorkSod {
    /// Cells along x on [0, 1] (York: 200, Δx = 0.005); the strip is one
    /// cell high.
    pub cells: usize,
    /// Points per cell per direction (York: 3 along x; the strip's y rows
    /// carry identical states).
    pub ppc: usize,
    /// Shape function (York: bilinear hats, `Linear`).
    pub shape: ShapeKind,
    /// Artificial viscosity `(g/Δx, κ̃, c₁, c₂)` (York Eqs. 24–25).
    pub q: (f64, f64, f64, f64),
    /// Courant number.
    pub cfl: f64,
    /// End time (York: 0.143).
    pub end: f64,
}

impl Default for YorkSod {
    /// The case of `cases/york_sod.toml`.
    fn default() -> Self {
        Self {
            cells: 200,
            ppc: 3,
            shape: ShapeKind::Gimp,
            q: (
                ArtificialViscosity::DEFAULT_G_OVER_DX,
                ArtificialViscosity::DEFAULT_KAPPA,
                ArtificialViscosity::DEFAULT_C1,
                ArtificialViscosity::DEFAULT_C2,
            ),
            cfl: 0.4,
            end: 0.143,
        }
    }
}

/// The left and right states of Sod's problem `(ρ, u, p)`, diaphragm at
/// x = 0.5, γ = 1.4.
pub const SOD_LEFT: (f64, f64, f64) = (1.0, 0.0, 1.0);
/// See [`SOD_LEFT`].
pub const SOD_RIGHT: (f64, f64, f64) = (0.125, 0.0, 0.1);

/// The scene text of a York Sod run (`cases/york_sod.toml` at `s.cells`).
pub fn york_sod_scene(s: &YorkSod) -> String {
    let h = 1.0 / s.cells as f64;
    let shape = match s.shape {
        ShapeKind::Linear => "linear",
        ShapeKind::Gimp => "gimp",
        ShapeKind::QuadraticBspline => "quadratic_bspline",
        ShapeKind::CubicBspline => "cubic_bspline",
    };
    let (g, kappa, c1, c2) = s.q;
    format!(
        r#"
description = "York Sec. 4.1, Sod with gas points"
[grid]
dim = 2
lower = [0.0, 0.0]
upper = [1.0, {h:e}]
cells = [{n}, 1]
boundary = {{ x_lower = "symmetry", x_upper = "symmetry", y_lower = "symmetry", y_upper = "symmetry" }}
[time]
end = {end:e}
cfl = {cfl:e}
[mpm]
shape = "{shape}"
update = "musl"
[[materials]]
name = "gas"
type = "fluid"
frame = "particles"
eos = "ideal_gas"
gamma = 1.4
cv = 2.5
artificial_viscosity = {{ g_over_dx = {g:e}, kappa = {kappa:e}, c1 = {c1:e}, c2 = {c2:e} }}
[[objects]]
material = "gas"
geometry = {{ type = "box", lower = [0.0, 0.0], upper = [0.5, {h:e}] }}
particles_per_cell = {ppc}
density = {rl:e}
pressure = {pl:e}
[[objects]]
material = "gas"
geometry = {{ type = "box", lower = [0.5, 0.0], upper = [1.0, {h:e}] }}
particles_per_cell = {ppc}
density = {rr:e}
pressure = {pr:e}
"#,
        n = s.cells,
        end = s.end,
        cfl = s.cfl,
        ppc = s.ppc,
        rl = SOD_LEFT.0,
        pl = SOD_LEFT.2,
        rr = SOD_RIGHT.0,
        pr = SOD_RIGHT.2,
    )
}

/// The exact solution of Sod's problem (γ = 1.4).
///
/// # Errors
/// None for these states (the exact solver's errors are mapped to a scene
/// error for completeness).
pub fn sod_exact() -> Result<ExactRiemann> {
    ExactRiemann::solve(
        PrimitiveState::new(SOD_LEFT.0, SOD_LEFT.1, SOD_LEFT.2),
        PrimitiveState::new(SOD_RIGHT.0, SOD_RIGHT.1, SOD_RIGHT.2),
        1.4,
    )
    .map_err(|e| SceneError::new("york_sod", e.to_string()).into())
}

/// A York Sod run's result.
#[derive(Debug, Clone)]
pub struct YorkSodRun {
    /// L1 density error ∫|ρ − ρ_exact| dx over [0, 1], by particle
    /// quadrature: Σ_p |m_p/V_p − ρ_exact(x_p)| V_p / H (H the strip height).
    pub l1_density: f64,
    /// Wall time of the time loop [s].
    pub wall_s: f64,
    /// Time steps taken.
    pub steps: u64,
    /// Number of gas points.
    pub particles: usize,
    /// Per point of the bottom row, in x order: `[x, ρ, u, p, e]` (York
    /// Fig. 6's variables; e the specific internal energy).
    pub profile: Vec<[f64; 5]>,
}

/// Runs York Sod through the scene path and the explicit MPM model's step,
/// and measures it against the exact solution.
///
/// # Errors
/// A scene or numerical error.
pub fn run_york_sod(s: &YorkSod) -> Result<YorkSodRun> {
    let scene = crate::scene::parse(&york_sod_scene(s))?;
    let mut run = crate::scene::build_solid_run::<2>(&scene)?;
    let start = Instant::now();
    while !run.finished() {
        run.step()?;
    }
    let wall_s = start.elapsed().as_secs_f64();
    let exact = sod_exact()?;
    let height = 1.0 / s.cells as f64;
    let p = &run.particles;
    let gas = run.materials[0].gas().copied();
    let mut l1 = 0.0;
    let mut profile = Vec::new();
    for i in 0..p.len() {
        let x = p.x[i][0];
        let rho = p.mass[i] / p.vol[i];
        let ex = exact.sample((x - 0.5) / run.t);
        l1 += (rho - ex.rho).abs() * p.vol[i];
        if p.x0[i][1] < height / s.ppc as f64 {
            let e = p.work[i] * p.vol0[i] / p.mass[i];
            let pr = gas.map_or(0.0, |g| g.pressure(rho, e));
            profile.push([x, rho, p.v[i][0], pr, e]);
        }
    }
    profile.sort_by(|a, b| a[0].total_cmp(&b[0]));
    Ok(YorkSodRun {
        l1_density: l1 / height,
        wall_s,
        steps: run.steps,
        particles: p.len(),
        profile,
    })
}
