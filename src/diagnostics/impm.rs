//! Benchmark problems of the implicit MPM (quasistatic and dynamic) and
//! runners that measure them against exact solutions (shared by the test
//! suite and `verification`).
//!
//! * [`Column`]: a self-weight column under gravity ramped over load steps.
//! * [`Cylinder`]: the internally pressurised thick cylinder of Guilkey
//!   Sec. 4.1 as a solid-only problem with the pressure applied as a traction
//!   on the particles of the inner surface; Lamé solution (Guilkey Eq. 42) and
//!   the error of Guilkey Eq. 43.

use std::time::Instant;

use nalgebra::SVector;

use crate::error::Result;
use crate::grid::{Boundary, Grid};
use crate::material::{ElasticConstants, SolidMaterial, SolidModel};
use crate::mpm::explicit::Uniform;
use crate::mpm::{
    BodyForce, ExplicitParams, ImplicitParams, ImplicitRun, Particles, StepStats, SurfaceLoad,
    UpdateScheme,
};
use crate::shape::ShapeKind;
use crate::stepper::{SolidRun, TimeControl};

/// The uniform box fill shared with the explicit references.
pub use super::mms::fill_box;

/// Outcome of one benchmark run.
#[derive(Debug, Clone)]
pub struct ImpmMeasured {
    /// Cell size.
    pub h: f64,
    /// Primary error (see the runner).
    pub error: f64,
    /// Secondary error (see the runner; NaN if none).
    pub error2: f64,
    /// Steps taken.
    pub steps: u64,
    /// Particles.
    pub particles: usize,
    /// Wall time of the time loop.
    pub wall_s: f64,
    /// Per-step statistics (implicit runs; empty for explicit).
    pub stats: Vec<StepStats>,
}

impl ImpmMeasured {
    /// Total Newton iterations.
    pub fn newton_iterations(&self) -> usize {
        self.stats.iter().map(|s| s.newton_iterations).sum()
    }
}

/// The self-weight column: height `l0`, one cell wide, plane strain, rollers
/// on the sides and the base, ν = 0, gravity ramped linearly over the load
/// steps (pseudo-time 0…1).
///
/// With ν = 0 (λ = 0) the neo-Hookean column is in uniaxial strain with
/// F = diag(1, F_yy, 1), J = F_yy and first Piola stress P_yy = J σ_yy /
/// F_yy = σ_yy. Equilibrium in the reference configuration, dP_yy/dY = ρ₀ g,
/// with P_yy(l0) = 0 gives the **exact large-deformation** solution
/// σ_yy(Y) = −ρ₀ g (l₀ − Y) at reference height Y (it coincides with the
/// small-strain solution when written in reference coordinates).
#[derive(Debug, Clone, Copy)]
pub struct Column {
    /// Height l₀.
    pub height: f64,
    /// Young's modulus.
    pub youngs: f64,
    /// Density ρ₀.
    pub rho: f64,
    /// Gravity magnitude.
    pub g: f64,
    /// Load steps.
    pub load_steps: usize,
}

impl Column {
    /// The study's column: l₀ = 50 m, E = 1 MPa, ρ = 80 kg/m³, g = 10 m/s²,
    /// 20 load steps.
    pub fn standard() -> Self {
        Self {
            height: 50.0,
            youngs: 1e6,
            rho: 80.0,
            g: 10.0,
            load_steps: 20,
        }
    }

    /// Exact σ_yy at reference height `y0`.
    pub fn sigma_yy(&self, y0: f64) -> f64 {
        -self.rho * self.g * (self.height - y0)
    }

    /// Builds the implicit run with `n` cells along the height and `ppc`
    /// particles per cell per direction.
    pub fn build(&self, shape: ShapeKind, n: usize, ppc: usize) -> Result<ImplicitRun<2>> {
        let h = self.height / n as f64;
        let grid = Grid::<2>::new(
            SVector::from([0.0, 0.0]),
            SVector::from([h, self.height]),
            [1, n],
            [
                [Boundary::Symmetry, Boundary::Symmetry],
                [Boundary::Symmetry, Boundary::Free],
            ],
        );
        let mat = SolidMaterial {
            name: "column".into(),
            density: self.rho,
            model: SolidModel::NeoHookean,
            elastic: ElasticConstants::from_young_poisson(self.youngs, 0.0),
        };
        let particles = fill_box(&grid, &grid.lower, &grid.upper, ppc, self.rho, |_| true);
        let mut params = ImplicitParams::new(shape, false, 1e-12 * particles.mass[0]);
        params.max_cell_fraction = f64::INFINITY;
        let dt = 1.0 / self.load_steps as f64;
        params.dt_max = dt;
        let mut run = ImplicitRun::new(grid, vec![mat], particles, params, 1.0, dt)?;
        run.body = Some(Box::new(Uniform(SVector::from([0.0, -self.g]))));
        run.load_ramp = Some(1.0);
        Ok(run)
    }

    /// Runs the column. Error: volume-weighted RMS over particles of
    /// σ_yy − σ_yy,exact(Y), divided by ρ₀ g l₀ (`error`); maximum of the
    /// same (`error2`).
    pub fn run(&self, shape: ShapeKind, n: usize, ppc: usize) -> Result<ImpmMeasured> {
        let mut run = self.build(shape, n, ppc)?;
        let start = Instant::now();
        run.run()?;
        let wall_s = start.elapsed().as_secs_f64();
        let p = &run.particles;
        let scale = self.rho * self.g * self.height;
        let (mut num, mut den, mut max) = (0.0, 0.0, 0.0f64);
        for i in 0..p.len() {
            let e = (p.stress.get(i)[(1, 1)] - self.sigma_yy(p.x0[i][1])) / scale;
            num += p.vol0[i] * e * e;
            den += p.vol0[i];
            max = max.max(e.abs());
        }
        Ok(ImpmMeasured {
            h: self.height / n as f64,
            error: (num / den).sqrt(),
            error2: max,
            steps: run.steps,
            particles: p.len(),
            wall_s,
            stats: run.stats,
        })
    }
}

/// The pressurised thick cylinder of Guilkey Sec. 4.1 (quarter annulus,
/// plane strain, symmetry planes x = 0 and y = 0), solid only: the internal
/// pressure acts as a traction on the particles whose centres lie within one
/// particle spacing of the inner radius, each receiving P × (its share of the
/// inner arc: rᵢ times its angular extent between the midpoints to its
/// neighbours in angle) along the outward radial direction.
#[derive(Debug, Clone, Copy)]
pub struct Cylinder {
    /// Inner radius rᵢ.
    pub r_inner: f64,
    /// Outer radius r_o.
    pub r_outer: f64,
    /// Bulk modulus K.
    pub bulk: f64,
    /// Shear modulus G.
    pub shear: f64,
    /// Density.
    pub rho: f64,
    /// Internal pressure P.
    pub pressure: f64,
    /// Particles per cell per direction.
    pub ppc: usize,
}

impl Cylinder {
    /// Guilkey's parameters: rᵢ = 0.5, r_o = 1, K = 117 GPa, G = 43.8 GPa,
    /// ρ = 8900, P = 19.4 MPa.
    pub fn guilkey() -> Self {
        Self {
            r_inner: 0.5,
            r_outer: 1.0,
            bulk: 117e9,
            shear: 43.8e9,
            rho: 8900.0,
            pressure: 19.4e6,
            ppc: 2,
        }
    }

    fn elastic(&self) -> ElasticConstants {
        ElasticConstants::from_bulk_shear(self.bulk, self.shear)
    }

    /// Lamé radial and hoop stress (Guilkey Eq. 42).
    pub fn stresses(&self, r: f64) -> (f64, f64) {
        let (ri, ro) = (self.r_inner, self.r_outer);
        let c = self.pressure * ri * ri / (ro * ro - ri * ri);
        (c * (1.0 - ro * ro / (r * r)), c * (1.0 + ro * ro / (r * r)))
    }

    /// Lamé radial displacement in plane strain, u_r = A r + B/r with
    /// A = C/(2(λ+μ)), B = C r_o²/(2μ), C = P rᵢ²/(r_o² − rᵢ²).
    pub fn radial_displacement(&self, r: f64) -> f64 {
        let ElasticConstants { lambda, mu } = self.elastic();
        let (ri, ro) = (self.r_inner, self.r_outer);
        let c = self.pressure * ri * ri / (ro * ro - ri * ri);
        c / (2.0 * (lambda + mu)) * r + c * ro * ro / (2.0 * mu) / r
    }

    fn setup(&self, dx: f64) -> (Grid<2>, SolidMaterial, Particles<2>, Vec<usize>, Vec<f64>) {
        let n = (self.r_outer / dx).round() as usize + 2;
        let len = n as f64 * dx;
        let grid = Grid::<2>::new(
            SVector::from([0.0, 0.0]),
            SVector::from([len, len]),
            [n, n],
            [
                [Boundary::Symmetry, Boundary::Free],
                [Boundary::Symmetry, Boundary::Free],
            ],
        );
        let mat = SolidMaterial {
            name: "steel".into(),
            density: self.rho,
            model: SolidModel::NeoHookean,
            elastic: self.elastic(),
        };
        let (ri, ro) = (self.r_inner, self.r_outer);
        let particles = fill_box(&grid, &grid.lower, &grid.upper, self.ppc, self.rho, |x| {
            let r = x.norm();
            r >= ri && r <= ro
        });
        let spacing = dx / self.ppc as f64;
        let band: Vec<usize> = (0..particles.len())
            .filter(|&p| particles.x0[p].norm() < ri + spacing)
            .collect();
        // Each band particle's share of the inner arc: rᵢ times the angular
        // extent from the midpoint to its neighbours in angle (shares sum to
        // the whole arc rᵢ π/2, and the load per unit arc is uniform even
        // where the square particle lattice meets the circle unevenly).
        let angle = |p: usize| particles.x0[p][1].atan2(particles.x0[p][0]);
        let mut order: Vec<usize> = (0..band.len()).collect();
        order.sort_by(|&a, &b| angle(band[a]).total_cmp(&angle(band[b])).then(a.cmp(&b)));
        let mut area = vec![0.0; band.len()];
        let half_pi = 0.5 * std::f64::consts::PI;
        for (k, &i) in order.iter().enumerate() {
            let lo = if k == 0 {
                0.0
            } else {
                0.5 * (angle(band[order[k - 1]]) + angle(band[i]))
            };
            let hi = if k + 1 == order.len() {
                half_pi
            } else {
                0.5 * (angle(band[i]) + angle(band[order[k + 1]]))
            };
            area[i] = ri * (hi - lo);
        }
        (grid, mat, particles, band, area)
    }

    /// Errors of a solved cylinder: (Guilkey Eq. 43, relative RMS error of
    /// the radial displacement against Lamé, volume-weighted).
    pub fn errors(&self, p: &Particles<2>) -> (f64, f64) {
        let target = 2.0 * self.pressure / 3.0;
        let mut e43 = 0.0;
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..p.len() {
            let s = p.stress.get(i)[(0, 0)] + p.stress.get(i)[(1, 1)];
            e43 += ((s.abs() - target) / target).abs();
            let r0 = p.x0[i].norm();
            let ur = (p.x[i] - p.x0[i]).dot(&(p.x0[i] / r0));
            let ex = self.radial_displacement(r0);
            num += p.vol0[i] * (ur - ex) * (ur - ex);
            den += p.vol0[i] * ex * ex;
        }
        (e43 / p.len() as f64, (num / den).sqrt())
    }

    /// The implicit quasistatic run at cell size `dx` with the load applied
    /// in `load_steps` equal steps.
    pub fn build_implicit(
        &self,
        shape: ShapeKind,
        dx: f64,
        load_steps: usize,
    ) -> Result<ImplicitRun<2>> {
        let (grid, mat, particles, band, area) = self.setup(dx);
        let dirs: Vec<SVector<f64, 2>> = band.iter().map(|&p| particles.x0[p]).collect();
        let mut params = ImplicitParams::new(shape, false, 1e-12 * particles.mass[0]);
        let dt = 1.0 / load_steps as f64;
        params.dt_max = dt;
        let mut run = ImplicitRun::new(grid, vec![mat], particles, params, 1.0, dt)?;
        run.surface = SurfaceLoad::pressure(self.pressure, band, &area, &dirs);
        run.load_ramp = Some(1.0);
        Ok(run)
    }

    /// Runs the implicit quasistatic cylinder. `error` = Guilkey Eq. 43,
    /// `error2` = relative RMS radial-displacement error.
    pub fn run_implicit(
        &self,
        shape: ShapeKind,
        dx: f64,
        load_steps: usize,
    ) -> Result<ImpmMeasured> {
        let run = self.build_implicit(shape, dx, load_steps)?;
        self.measure_implicit(run, dx)
    }

    /// Runs a cylinder built by [`Self::build_implicit`] (possibly with
    /// changed parameters) and measures it as [`Self::run_implicit`].
    pub fn measure_implicit(&self, mut run: ImplicitRun<2>, dx: f64) -> Result<ImpmMeasured> {
        let start = Instant::now();
        run.run()?;
        let wall_s = start.elapsed().as_secs_f64();
        let (e43, eu) = self.errors(&run.particles);
        Ok(ImpmMeasured {
            h: dx,
            error: e43,
            error2: eu,
            steps: run.steps,
            particles: run.particles.len(),
            wall_s,
            stats: run.stats,
        })
    }

    /// The explicit run damped to the quasistatic state: the load ramps
    /// linearly over `ramp` seconds, mass-proportional damping `damping`,
    /// USL, CFL `cfl`, to time `end`.
    #[allow(clippy::too_many_arguments)]
    pub fn run_explicit(
        &self,
        shape: ShapeKind,
        dx: f64,
        cfl: f64,
        damping: f64,
        ramp: f64,
        end: f64,
    ) -> Result<ImpmMeasured> {
        let (grid, mat, particles, band, area) = self.setup(dx);
        let mut accel = vec![SVector::<f64, 2>::zeros(); particles.len()];
        for (k, &p) in band.iter().enumerate() {
            accel[p] = particles.x0[p].normalize() * (self.pressure * area[k] / particles.mass[p]);
        }
        let mut table: Vec<([u64; 2], SVector<f64, 2>)> = band
            .iter()
            .map(|&p| {
                let x = particles.x0[p];
                ([x[0].to_bits(), x[1].to_bits()], accel[p])
            })
            .collect();
        table.sort_by_key(|a| a.0);
        let band_load = BandLoad {
            r_band: self.r_inner + dx / self.ppc as f64,
            table,
            ramp,
        };
        let params = ExplicitParams {
            shape,
            scheme: UpdateScheme::Usl,
            mass_floor: 1e-12 * particles.mass[0],
            damping,
            pic_fraction: 0.0,
        };
        let np = particles.len();
        let time = TimeControl {
            end,
            cfl,
            dt: None,
            max_steps: None,
        };
        let mut run = SolidRun::new(grid, vec![mat], particles, params, time);
        run.body = Some(Box::new(band_load));
        let start = Instant::now();
        while !run.finished() {
            run.step()?;
        }
        let wall_s = start.elapsed().as_secs_f64();
        let (e43, eu) = self.errors(&run.particles);
        Ok(ImpmMeasured {
            h: dx,
            error: e43,
            error2: eu,
            steps: run.steps,
            particles: np,
            wall_s,
            stats: Vec::new(),
        })
    }
}

/// The cylinder's inner-surface traction as a body force on the band
/// particles, identified by their reference position (bit-exact lookup).
#[derive(Debug, Clone)]
struct BandLoad {
    r_band: f64,
    table: Vec<([u64; 2], SVector<f64, 2>)>,
    ramp: f64,
}

impl BodyForce<2> for BandLoad {
    fn accel(&self, x0: &SVector<f64, 2>, _x: &SVector<f64, 2>, t: f64) -> SVector<f64, 2> {
        if x0.norm() >= self.r_band {
            return SVector::zeros();
        }
        let key = [x0[0].to_bits(), x0[1].to_bits()];
        match self.table.binary_search_by(|e| e.0.cmp(&key)) {
            Ok(i) => {
                let f = if self.ramp > 0.0 {
                    (t / self.ramp).min(1.0)
                } else {
                    1.0
                };
                self.table[i].1 * f
            }
            Err(_) => SVector::zeros(),
        }
    }
}

/// The axis-aligned manufactured solution of `diagnostics::mms` run with the
/// dynamic implicit step (Newmark β = 1/4, γ = 1/2) on the unit domain with
/// `n` cells per direction, 2 particles per cell per direction, symmetry
/// faces, over `periods` periods (one period is t = 2/c), fixed Δt =
/// `courant` · h / c_p (c_p the initial dilatational wave speed; `courant`
/// may exceed 1).
///
/// Error: maximum over steps of the volume-weighted RMS displacement error
/// divided by A (as `mms::run_mms`).
pub fn run_mms_implicit<const D: usize>(
    mms: &crate::diagnostics::mms::AxisAlignedMms,
    shape: ShapeKind,
    n: usize,
    courant: f64,
    periods: f64,
) -> Result<ImpmMeasured> {
    let (grid, mat, particles) = mms.setup::<D>(n);
    let h = grid.h[0];
    let end = 2.0 * periods / mms.c;
    let steps = (end / (courant * h / mat.wave_speed(mms.rho0))).ceil();
    let dt = end / steps;
    let mut params = ImplicitParams::new(shape, true, 1e-12 * particles.mass[0]);
    params.dt_max = dt;
    params.max_cell_fraction = f64::INFINITY;
    let np = particles.len();
    let mut run = ImplicitRun::new(grid, vec![mat], particles, params, end, dt)?;
    run.body = Some(Box::new(*mms));
    let start = Instant::now();
    let mut err = 0.0f64;
    while !run.finished() {
        run.step()?;
        let t = run.t;
        let p = &run.particles;
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..p.len() {
            let e = (p.x[i] - p.x0[i] - mms.displacement(&p.x0[i], t)).norm();
            num += p.vol0[i] * e * e;
            den += p.vol0[i];
        }
        err = err.max((num / den).sqrt());
    }
    Ok(ImpmMeasured {
        h,
        error: err / mms.amplitude,
        error2: f64::NAN,
        steps: run.steps,
        particles: np,
        wall_s: start.elapsed().as_secs_f64(),
        stats: run.stats,
    })
}

/// The bar of `mms::run_bar` (mode 1, fixed–free, hypo-elastic, ν = 0, one
/// period 4L/c, `n` cells along the bar, 2 particles per cell) run with the
/// dynamic implicit step at Δt = `courant` · h / c.
///
/// Error: maximum over steps of the volume-weighted RMS displacement error
/// divided by the amplitude v₀/ω_d (as `mms::run_bar`).
pub fn run_bar_implicit(
    bar: &crate::diagnostics::mms::BarMode1,
    shape: ShapeKind,
    n: usize,
    courant: f64,
) -> Result<ImpmMeasured> {
    let (grid, mat, particles) = bar.setup(n);
    let h = grid.h[0];
    let end = 4.0 * bar.length / bar.c();
    let steps = (end / (courant * h / bar.c())).ceil();
    let dt = end / steps;
    let mut params = ImplicitParams::new(shape, true, 1e-12 * particles.mass[0]);
    params.dt_max = dt;
    params.max_cell_fraction = f64::INFINITY;
    let np = particles.len();
    let mut run = ImplicitRun::new(grid, vec![mat], particles, params, end, dt)?;
    let amp = bar.v0 / bar.omega_d();
    let start = Instant::now();
    let mut err = 0.0f64;
    while !run.finished() {
        run.step()?;
        let t = run.t;
        let (rms, _) = crate::diagnostics::mms::displacement_error(&run.particles, |x0| {
            SVector::from([bar.displacement(x0[0], t)])
        });
        err = err.max(rms);
    }
    Ok(ImpmMeasured {
        h,
        error: err / amp,
        error2: f64::NAN,
        steps: run.steps,
        particles: np,
        wall_s: start.elapsed().as_secs_f64(),
        stats: run.stats,
    })
}

/// A neo-Hookean bar in uniaxial strain (plane strain, one cell wide,
/// rollers on both sides and the base) stretched or compressed by a rigid
/// grip: the bar fills 0 ≤ Y ≤ (`gauge_cells` + `grip_cells`) h, its top
/// `grip_cells` cells are gripped and moved by `displacement_cells` · h,
/// ramped over `load_steps` equal quasistatic load steps.
///
/// Exact solution (the grip is rigid, the gauge of length G = `gauge_cells` h
/// deforms homogeneously): F = diag(1, s, 1) with s = 1 + δ/G, and the
/// neo-Hookean Cauchy stress σ = (λ ln J / J) I + (μ/J)(F Fᵀ − I) (Bonet &
/// Wood Eq. 5.29, J = s) gives σ_yy = [μ (s² − 1) + λ ln s]/s, σ_xx = σ_zz =
/// λ ln s / s; the force of the grip per unit depth is σ_yy times the width
/// h (the width does not change in uniaxial strain).
///
/// The discrete solution reproduces it to round-off when the grip's lower
/// edge lies on a node row at the start of every step (increments of whole
/// cells; a single step of any size with the linear hat and GIMP), because
/// the grip nodes then border exactly the gauge material; GIMP keeps it
/// over several steps because its domains follow F and tile the stretched
/// gauge.
#[derive(Debug, Clone, Copy)]
pub struct GripBar {
    /// Cells of the deforming gauge.
    pub gauge_cells: usize,
    /// Cells of the gripped end.
    pub grip_cells: usize,
    /// Grip displacement at full load, in cells (negative: compression).
    pub displacement_cells: f64,
    /// Load steps.
    pub load_steps: usize,
    /// Young's modulus.
    pub youngs: f64,
    /// Poisson's ratio.
    pub poisson: f64,
    /// Density.
    pub rho: f64,
}

/// Errors of a [`GripBar`] run against the exact solution.
#[derive(Debug, Clone)]
pub struct GripMeasured {
    /// Largest |F_yy − s| over the gauge particles.
    pub f_error: f64,
    /// Largest |σ_yy − exact| / |σ_yy exact| over the gauge particles.
    pub syy_error: f64,
    /// Largest |σ_xx − exact| / |σ_yy exact| over the gauge particles.
    pub sxx_error: f64,
    /// Largest |reaction − σ_yy(s_k) h| / |σ_yy(s_k) h| over the steps k.
    pub reaction_error: f64,
    /// Largest |displacement − δ| / δ over the gripped particles.
    pub grip_error: f64,
    /// The implicit run's statistics.
    pub measured: ImpmMeasured,
}

impl GripBar {
    /// Gauge 8 cells, grip 2 cells, E = 1 MPa, ν = 0.3, ρ = 1000, stretched
    /// by 4 cells (s = 1.5) in 4 load steps.
    pub fn standard() -> Self {
        Self {
            gauge_cells: 8,
            grip_cells: 2,
            displacement_cells: 4.0,
            load_steps: 4,
            youngs: 1e6,
            poisson: 0.3,
            rho: 1000.0,
        }
    }

    fn material(&self) -> SolidMaterial {
        SolidMaterial {
            name: "bar".into(),
            density: self.rho,
            model: SolidModel::NeoHookean,
            elastic: ElasticConstants::from_young_poisson(self.youngs, self.poisson),
        }
    }

    /// Exact (σ_xx, σ_yy) at stretch s (Bonet & Wood Eq. 5.29).
    pub fn exact_stress(&self, s: f64) -> (f64, f64) {
        let ElasticConstants { lambda, mu } = self.material().elastic;
        let sxx = lambda * s.ln() / s;
        (sxx, sxx + mu * (s * s - 1.0) / s)
    }

    /// The implicit quasistatic run with cell size `h`; the grip is
    /// [`ImplicitRun::prescribed`]`[0]`.
    pub fn build(&self, shape: ShapeKind, h: f64) -> Result<ImplicitRun<2>> {
        let length = (self.gauge_cells + self.grip_cells) as f64 * h;
        let rows = self.gauge_cells
            + self.grip_cells
            + self.displacement_cells.max(0.0).ceil() as usize
            + 2;
        let grid = Grid::<2>::new(
            SVector::from([0.0, 0.0]),
            SVector::from([h, rows as f64 * h]),
            [1, rows],
            [
                [Boundary::Symmetry, Boundary::Symmetry],
                [Boundary::Symmetry, Boundary::Free],
            ],
        );
        let upper = SVector::from([h, length]);
        let particles = fill_box(&grid, &grid.lower, &upper, 2, self.rho, |_| true);
        let gauge = self.gauge_cells as f64 * h;
        let grip: Vec<usize> = (0..particles.len())
            .filter(|&p| particles.x0[p][1] > gauge)
            .collect();
        let mut params = ImplicitParams::new(shape, false, 1e-12 * particles.mass[0]);
        params.max_cell_fraction = f64::INFINITY;
        let dt = 1.0 / self.load_steps as f64;
        params.dt_max = dt;
        let mut run = ImplicitRun::new(grid, vec![self.material()], particles, params, 1.0, dt)?;
        run.load_ramp = Some(1.0);
        run.prescribed
            .push(crate::mpm::implicit::PrescribedDisplacement {
                particle: grip,
                displacement: SVector::from([0.0, self.displacement_cells * h]),
                components: [false, true],
            });
        Ok(run)
    }

    /// Runs the bar with cell size `h` and measures it against the exact
    /// solution.
    pub fn run(&self, shape: ShapeKind, h: f64) -> Result<GripMeasured> {
        let run = self.build(shape, h)?;
        self.measure(run, h)
    }

    /// Runs a bar built by [`Self::build`] (possibly with changed
    /// parameters) and measures it as [`Self::run`].
    pub fn measure(&self, mut run: ImplicitRun<2>, h: f64) -> Result<GripMeasured> {
        let start = Instant::now();
        run.run()?;
        let wall_s = start.elapsed().as_secs_f64();
        let gauge = self.gauge_cells as f64 * h;
        let delta = self.displacement_cells * h;
        let s = 1.0 + delta / gauge;
        let (sxx, syy) = self.exact_stress(s);
        let p = &run.particles;
        let (mut ef, mut eyy, mut exx, mut eg) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for i in 0..p.len() {
            if p.x0[i][1] < gauge {
                ef = ef.max((p.f.get(i)[(1, 1)] - s).abs());
                let st = p.stress.get(i);
                eyy = eyy.max((st[(1, 1)] - syy).abs() / syy.abs());
                exx = exx.max((st[(0, 0)] - sxx).abs() / syy.abs());
            } else {
                let u = p.x[i] - p.x0[i];
                eg = eg.max((u - SVector::from([0.0, delta])).norm() / delta.abs());
            }
        }
        let mut er = 0.0f64;
        for st in &run.stats {
            let sk = 1.0 + st.load * delta / gauge;
            let force = self.exact_stress(sk).1 * h;
            er = er.max((st.reactions[0][1] - force).abs() / force.abs());
        }
        Ok(GripMeasured {
            f_error: ef,
            syy_error: eyy,
            sxx_error: exx,
            reaction_error: er,
            grip_error: eg,
            measured: ImpmMeasured {
                h,
                error: eyy,
                error2: er,
                steps: run.steps,
                particles: p.len(),
                wall_s,
                stats: run.stats,
            },
        })
    }
}
