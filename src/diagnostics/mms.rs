//! Exact references for the MPM verification problems, and runners that
//! measure a run against them (shared by the test suite and `verification`).
//!
//! * [`AxisAlignedMms`]: the axis-aligned manufactured solution of Wallstedt &
//!   Guilkey (2008), u_i = A sin(π X_i) sin(c π t + φ_i) on the unit domain,
//!   compressible neo-Hookean, c = √(E/ρ₀), with the body force that makes it
//!   exact.
//! * [`BarMode1`]: the first mode of an elastic bar fixed at x = 0 and free at
//!   x = L, u = (v₀/ω) sin(π x / 2L) sin(ω t), ω = π c / 2L.

use std::time::Instant;

use nalgebra::SVector;

use crate::error::Result;
use crate::grid::{Boundary, Grid};
use crate::material::{ElasticConstants, SolidMaterial, SolidModel};
use crate::mpm::{BodyForce, ExplicitParams, Particles, UpdateScheme};
use crate::shape::ShapeKind;
use crate::stepper::{SolidRun, TimeControl};

/// The axis-aligned manufactured solution.
///
/// F is diagonal with F_ii = 1 + A π cos(π X_i) s_i(t), s_i = sin(cπt + φ_i)
/// (F₃₃ = 1 in 2D plane strain; F₂₂ = F₃₃ = 1 in 1D). With the first Piola
/// stress of the neo-Hookean model P_ii = [λ ln J + μ (F_ii² − 1)]/F_ii the body
/// force is b_i = ü_i − (1/ρ₀) ∂P_ii/∂X_i with
/// ∂P_ii/∂X_i = [λ(1 − ln J) + μ(F_ii² + 1)]/F_ii² · ∂F_ii/∂X_i.
#[derive(Debug, Clone, Copy)]
pub struct AxisAlignedMms {
    /// Amplitude A.
    pub amplitude: f64,
    /// Elastic constants.
    pub elastic: ElasticConstants,
    /// Reference density ρ₀.
    pub rho0: f64,
    /// Time frequency factor c = √(E/ρ₀).
    pub c: f64,
    /// Phase per direction.
    pub phase: [f64; 3],
}

impl AxisAlignedMms {
    /// The study's parameters: E = 1e4, ν = 0.3, ρ₀ = 1, phases (0, π, 0).
    pub fn standard(amplitude: f64) -> Self {
        let (e, nu, rho0) = (1e4, 0.3, 1.0);
        Self {
            amplitude,
            elastic: ElasticConstants::from_young_poisson(e, nu),
            rho0,
            c: (e / rho0).sqrt(),
            phase: [0.0, std::f64::consts::PI, 0.0],
        }
    }

    /// The discretised problem: the unit domain with `n` cells per
    /// direction and symmetry (roller) faces, 2 particles per cell per
    /// direction in the exact initial velocity, neo-Hookean.
    pub fn setup<const D: usize>(&self, n: usize) -> (Grid<D>, SolidMaterial, Particles<D>) {
        let grid = Grid::<D>::new(
            SVector::zeros(),
            SVector::repeat(1.0),
            [n; D],
            [[Boundary::Symmetry; 2]; D],
        );
        let mat = SolidMaterial {
            name: "mms".into(),
            density: self.rho0,
            model: SolidModel::NeoHookean,
            elastic: self.elastic,
        };
        let mut particles = fill_box(&grid, &grid.lower, &grid.upper, 2, self.rho0, |_| true);
        for p in 0..particles.len() {
            particles.v[p] = self.velocity(&particles.x0[p], 0.0);
        }
        (grid, mat, particles)
    }

    fn s(&self, i: usize, t: f64) -> f64 {
        (self.c * std::f64::consts::PI * t + self.phase[i]).sin()
    }

    /// Exact displacement at reference position `x0`, time `t`.
    pub fn displacement<const D: usize>(&self, x0: &SVector<f64, D>, t: f64) -> SVector<f64, D> {
        let pi = std::f64::consts::PI;
        SVector::from_fn(|i, _| self.amplitude * (pi * x0[i]).sin() * self.s(i, t))
    }

    /// Exact velocity.
    pub fn velocity<const D: usize>(&self, x0: &SVector<f64, D>, t: f64) -> SVector<f64, D> {
        let pi = std::f64::consts::PI;
        SVector::from_fn(|i, _| {
            self.amplitude
                * (pi * x0[i]).sin()
                * self.c
                * pi
                * (self.c * pi * t + self.phase[i]).cos()
        })
    }
}

impl<const D: usize> BodyForce<D> for AxisAlignedMms {
    fn accel(&self, x0: &SVector<f64, D>, _x: &SVector<f64, D>, t: f64) -> SVector<f64, D> {
        let pi = std::f64::consts::PI;
        let a = self.amplitude;
        let ElasticConstants { lambda, mu } = self.elastic;
        let fd: [f64; D] =
            std::array::from_fn(|i| 1.0 + a * pi * (pi * x0[i]).cos() * self.s(i, t));
        let j: f64 = fd.iter().product();
        let lnj = j.ln();
        SVector::from_fn(|i, _| {
            let s = self.s(i, t);
            let sx = (pi * x0[i]).sin();
            let udd = -a * (self.c * pi).powi(2) * sx * s;
            let dfdx = -a * pi * pi * sx * s;
            let f = fd[i];
            let dpdx = (lambda * (1.0 - lnj) + mu * (f * f + 1.0)) / (f * f) * dfdx;
            udd - dpdx / self.rho0
        })
    }
}

/// One measured run against an exact solution.
#[derive(Debug, Clone, Copy)]
pub struct Measured {
    /// Cell size.
    pub h: f64,
    /// The error (see the runner for its norm).
    pub error: f64,
    /// Maximum over time of the largest particle displacement error.
    pub max_error: f64,
    /// Steps taken.
    pub steps: u64,
    /// Particles.
    pub particles: usize,
    /// Wall time of the time loop.
    pub wall_s: f64,
    /// Relative total-energy drift over the run (bar only; NaN otherwise).
    pub energy_drift: f64,
}

impl Measured {
    /// Particle updates per second.
    pub fn updates_per_s(&self) -> f64 {
        self.particles as f64 * self.steps as f64 / self.wall_s.max(1e-12)
    }
}

/// Uniform particle fill of a box (`ppc` per cell per direction), at rest,
/// keeping the positions where `keep` holds.
pub fn fill_box<const D: usize>(
    grid: &Grid<D>,
    lower: &SVector<f64, D>,
    upper: &SVector<f64, D>,
    ppc: usize,
    rho0: f64,
    keep: impl Fn(&SVector<f64, D>) -> bool,
) -> Particles<D> {
    let mut p = Particles::default();
    let vol = grid.cell_volume() / (ppc as f64).powi(D as i32);
    let half = grid.h / (2.0 * ppc as f64);
    let counts: [usize; D] =
        std::array::from_fn(|d| ((upper[d] - lower[d]) / grid.h[d]).round() as usize * ppc);
    let total: usize = counts.iter().product();
    for k in 0..total {
        let mut r = k;
        let x = SVector::<f64, D>::from_fn(|d, _| {
            let i = r % counts[d];
            r /= counts[d];
            lower[d] + (i as f64 + 0.5) * grid.h[d] / ppc as f64
        });
        if keep(&x) {
            p.push(x, SVector::zeros(), rho0 * vol, vol, half, 0);
        }
    }
    p
}

/// Volume-weighted RMS and max of the particle displacement error.
pub fn displacement_error<const D: usize>(
    p: &Particles<D>,
    exact: impl Fn(&SVector<f64, D>) -> SVector<f64, D>,
) -> (f64, f64) {
    let (mut num, mut den, mut max) = (0.0, 0.0, 0.0f64);
    for i in 0..p.len() {
        let e = (p.x[i] - p.x0[i] - exact(&p.x0[i])).norm();
        num += p.vol0[i] * e * e;
        den += p.vol0[i];
        max = max.max(e);
    }
    ((num / den).sqrt(), max)
}

/// Runs the axis-aligned MMS on the unit domain with `n` cells per direction,
/// 2 particles per cell per direction, symmetry (roller) faces, to one period
/// t = 2/c at Courant number `cfl` (fixed dt = cfl · h / c_p, c_p the initial
/// dilatational wave speed).
///
/// Error: maximum over all steps of the volume-weighted RMS displacement
/// error, divided by A.
pub fn run_mms<const D: usize>(
    mms: &AxisAlignedMms,
    shape: ShapeKind,
    scheme: UpdateScheme,
    n: usize,
    cfl: f64,
) -> Result<Measured> {
    let (grid, mat, particles) = mms.setup::<D>(n);
    let h = grid.h[0];
    let dt = cfl * h / mat.wave_speed(mms.rho0);
    let end = 2.0 / mms.c;
    let steps = (end / dt).ceil();
    let params = ExplicitParams {
        shape,
        scheme,
        mass_floor: 1e-12 * particles.mass[0],
        damping: 0.0,
        pic_fraction: 0.0,
    };
    let np = particles.len();
    let time = TimeControl {
        end,
        cfl,
        dt: Some(end / steps),
        max_steps: None,
    };
    let mut run = SolidRun::new(grid, vec![mat], particles, params, time);
    run.body = Some(Box::new(*mms));
    let start = Instant::now();
    let (mut err, mut max_err) = (0.0f64, 0.0f64);
    while !run.finished() {
        run.step()?;
        let t = run.t;
        let (e, m) = displacement_error(&run.particles, |x0| mms.displacement(x0, t));
        err = err.max(e);
        max_err = max_err.max(m);
    }
    Ok(Measured {
        h,
        error: err / mms.amplitude,
        max_error: max_err / mms.amplitude,
        steps: run.steps,
        particles: np,
        wall_s: start.elapsed().as_secs_f64(),
        energy_drift: f64::NAN,
    })
}

/// The first mode of a 1D elastic bar of length `length`, fixed at x = 0 and
/// free at x = L, with wave speed c = √(E/ρ) (ν = 0), optionally with
/// mass-proportional damping α: the modal equation q̈ + α q̇ + ω² q = 0 with
/// q(0) = 0, q̇(0) = v₀ gives q = (v₀/ω_d) e^(−αt/2) sin(ω_d t),
/// ω_d = √(ω² − α²/4), and u = q(t) sin(π x / 2L).
#[derive(Debug, Clone, Copy)]
pub struct BarMode1 {
    /// Bar length L.
    pub length: f64,
    /// Young's modulus.
    pub youngs: f64,
    /// Density.
    pub rho: f64,
    /// Velocity amplitude v₀.
    pub v0: f64,
    /// Mass-proportional damping α [1/s] (0: undamped).
    pub damping: f64,
}

impl BarMode1 {
    /// Wave speed √(E/ρ).
    pub fn c(&self) -> f64 {
        (self.youngs / self.rho).sqrt()
    }

    /// Angular frequency ω = π c / 2L.
    pub fn omega(&self) -> f64 {
        std::f64::consts::PI * self.c() / (2.0 * self.length)
    }

    /// The discretised bar: `n` cells along it (the grid 25 %, at least 3
    /// cells, longer and free beyond it; fixed at x = 0), 2 particles per
    /// cell in the mode-1 initial velocity, hypo-elastic with ν = 0.
    pub fn setup(&self, n: usize) -> (Grid<1>, SolidMaterial, Particles<1>) {
        let h = self.length / n as f64;
        let extra = (n / 4).max(3);
        let grid = Grid::<1>::new(
            SVector::from([0.0]),
            SVector::from([self.length + extra as f64 * h]),
            [n + extra],
            [[Boundary::Fixed, Boundary::Free]],
        );
        let mat = SolidMaterial {
            name: "bar".into(),
            density: self.rho,
            model: SolidModel::LinearElastic,
            elastic: ElasticConstants::from_young_poisson(self.youngs, 0.0),
        };
        let mut particles = fill_box(
            &grid,
            &SVector::from([0.0]),
            &SVector::from([self.length]),
            2,
            self.rho,
            |_| true,
        );
        for p in 0..particles.len() {
            particles.v[p] = SVector::from([self.velocity(particles.x0[p][0], 0.0)]);
        }
        (grid, mat, particles)
    }

    /// Damped angular frequency ω_d = √(ω² − α²/4) (under-damped only).
    pub fn omega_d(&self) -> f64 {
        (self.omega().powi(2) - 0.25 * self.damping * self.damping).sqrt()
    }

    /// Exact displacement.
    pub fn displacement(&self, x0: f64, t: f64) -> f64 {
        let k = std::f64::consts::PI / (2.0 * self.length);
        let wd = self.omega_d();
        self.v0 / wd * (-0.5 * self.damping * t).exp() * (k * x0).sin() * (wd * t).sin()
    }

    /// Exact velocity.
    pub fn velocity(&self, x0: f64, t: f64) -> f64 {
        let k = std::f64::consts::PI / (2.0 * self.length);
        let wd = self.omega_d();
        let decay = (-0.5 * self.damping * t).exp();
        self.v0
            * decay
            * (k * x0).sin()
            * ((wd * t).cos() - 0.5 * self.damping / wd * (wd * t).sin())
    }
}

/// Runs the bar with `n` cells along the bar (grid 25 % longer than the bar,
/// free beyond it), 2 particles per cell, hypo-elastic (`linear_elastic`) with
/// ν = 0, to one period 4L/c at Courant number `cfl`.
///
/// Error: maximum over all steps of the volume-weighted RMS displacement
/// error divided by the displacement amplitude v₀/ω_d.
pub fn run_bar(
    bar: &BarMode1,
    shape: ShapeKind,
    scheme: UpdateScheme,
    n: usize,
    cfl: f64,
) -> Result<Measured> {
    let (grid, mat, particles) = bar.setup(n);
    let h = grid.h[0];
    let end = 4.0 * bar.length / bar.c();
    let dt = cfl * h / bar.c();
    let steps = (end / dt).ceil();
    let params = ExplicitParams {
        shape,
        scheme,
        mass_floor: 1e-12 * particles.mass[0],
        damping: bar.damping,
        pic_fraction: 0.0,
    };
    let np = particles.len();
    let time = TimeControl {
        end,
        cfl,
        dt: Some(end / steps),
        max_steps: None,
    };
    let mut run = SolidRun::new(grid, vec![mat], particles, params, time);
    let e0 = run.energies().total();
    let amp = bar.v0 / bar.omega_d();
    let start = Instant::now();
    let (mut err, mut max_err) = (0.0f64, 0.0f64);
    while !run.finished() {
        run.step()?;
        let t = run.t;
        let (e, m) = displacement_error(&run.particles, |x0| {
            SVector::from([bar.displacement(x0[0], t)])
        });
        err = err.max(e);
        max_err = max_err.max(m);
    }
    let wall_s = start.elapsed().as_secs_f64();
    Ok(Measured {
        h,
        error: err / amp,
        max_error: max_err / amp,
        steps: run.steps,
        particles: np,
        wall_s,
        energy_drift: (run.energies().total() - e0) / e0,
    })
}
