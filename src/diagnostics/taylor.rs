//! The Taylor anvil (`cases/taylor_anvil.toml`): a Johnson–Cook copper rod
//! on a rigid frictionless wall in axisymmetric r–z MPM, with its final
//! length, its mushroom diameter and an energy account (shared by
//! `tests/taylor_anvil.rs` and the `taylor_anvil` study).
//!
//! The grid is sized from the rod: with R₀ = D₀/2 and L₀ = 20 R₀/3 (25.4 and
//! 3.81 mm), a cell of R₀/n (n a multiple of 3) puts both on cell faces;
//! the domain is 3 R₀ by 7 R₀ (21 units of R₀/3). Everything is per radian.
//!
//! Measures at the end time:
//! * the final length L = max (z + a_z) − min (z − a_z) over the particles,
//!   a_z = F_zz a⁰_z the current half-size of a particle (the rod may have
//!   left the wall by then);
//! * the mushroom (largest) diameter D = 2 max (r + F_rr a⁰_r) over the
//!   particles, and the footprint diameter, the same over the particles of
//!   the rod's initial bottom row (X_z < a⁰_z · 2), which stay on the face;
//! * energies per radian: the initial kinetic energy K₀ = ½ M v₀², the final
//!   kinetic K, the total stress work W = Σ V⁰ w (stored and dissipated; the
//!   particles' `work`), the elastic energy left E_e = Σ V (p²/2K + q²/6μ)
//!   of the final stresses, and the plastic work from the heat it made,
//!   W_p = Σ m c_p (T − T₀)/β (adiabatic heating: each step adds
//!   β σ_y Δε̄/(ρ c_p) to T, so this is Σ V σ_y Δε̄ accumulated separately
//!   from W). The energy account: K₀ − K = W (the scheme's own energy
//!   error) and W_p = K₀ − K − E_e (plastic work = kinetic energy lost minus
//!   the elastic energy left), to the scheme's energy error plus the
//!   time-integration difference between W and W_p.

use std::time::Instant;

use crate::error::Result;
use crate::material::plasticity::von_mises;
use crate::scene::{build_solid_run, Scene};

/// Rod radius R₀ \[m\] (D₀ = 7.62 mm).
pub const R0: f64 = 3.81e-3;
/// Rod length L₀ \[m\].
pub const L0: f64 = 25.4e-3;

/// Measured final shapes of OFHC copper rods of this size, (speed [m/s],
/// L_f/L₀, D_f/D₀ of the impact face): Johnson & Cook 1983's test at 190
/// m/s as reproduced by Zerilli & Armstrong 1987 (J. Appl. Phys. 61, 1816,
/// p. 1822) and the 146 and 130 m/s tests, digitized in Banerjee's
/// HighRateExptData (`TaylorData/DAT/CuZerilli.dat`).
pub const MEASURED: [(f64, f64, f64); 3] = [
    (130.0, 0.770, 1.30),
    (146.0, 0.736, 1.40),
    (190.0, 0.638, 1.78),
];

/// What one Taylor run measured.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct TaylorMeasured {
    /// Cell size h \[m\].
    pub h: f64,
    /// Impact speed [m/s].
    pub speed: f64,
    /// Final length L \[m\].
    pub length: f64,
    /// Lowest particle edge min (z − a_z) \[m\]: the gap between the rod and
    /// the wall (≈ 0 while the rod sits on it).
    pub gap: f64,
    /// Largest (mushroom) diameter \[m\].
    pub diameter: f64,
    /// Footprint diameter (initial bottom row) \[m\].
    pub footprint: f64,
    /// Initial kinetic energy K₀ [J/rad].
    pub kinetic0: f64,
    /// Final kinetic energy [J/rad].
    pub kinetic: f64,
    /// Total stress work W [J/rad].
    pub work: f64,
    /// Elastic energy left [J/rad].
    pub elastic: f64,
    /// Plastic work from the heat W_p [J/rad].
    pub plastic: f64,
    /// Largest equivalent plastic strain.
    pub max_plastic_strain: f64,
    /// Largest damage.
    pub max_damage: f64,
    /// Failed particles.
    pub failed: usize,
    /// Particles.
    pub particles: usize,
    /// Steps.
    pub steps: u64,
    /// Wall time of the stepping \[s\].
    pub wall_s: f64,
}

impl TaylorMeasured {
    /// L/L₀.
    pub fn length_ratio(&self) -> f64 {
        self.length / L0
    }

    /// D/D₀ of the mushroom (largest) diameter.
    pub fn diameter_ratio(&self) -> f64 {
        self.diameter / (2.0 * R0)
    }

    /// |K₀ − K − W| / K₀: the scheme's energy error.
    pub fn energy_error(&self) -> f64 {
        (self.kinetic0 - self.kinetic - self.work).abs() / self.kinetic0
    }

    /// |W_p − (K₀ − K − E_e)| / K₀: the plastic-work account.
    pub fn plastic_account_error(&self) -> f64 {
        (self.plastic - (self.kinetic0 - self.kinetic - self.elastic)).abs() / self.kinetic0
    }
}

/// Runs the Taylor scene `base` (`cases/taylor_anvil.toml`) with a cell of
/// R₀/`n` (`n` rounded up to a multiple of 3), impact speed `speed` [m/s],
/// to `end` \[s\].
///
/// # Errors
/// A scene that does not build, or a step that fails.
pub fn run(base: &Scene, n: usize, speed: f64, end: f64) -> Result<TaylorMeasured> {
    // Both R₀ and L₀ on cell faces: a multiple of 3 cells per radius.
    let n = n.max(1).div_ceil(3) * 3;
    let mut scene = base.clone();
    scene.grid.cells = vec![3 * n, 7 * n];
    scene.grid.lower = vec![0.0, 0.0];
    scene.grid.upper = vec![3.0 * R0, 7.0 * R0];
    scene.time.end = end;
    for o in &mut scene.objects {
        o.velocity = Some(vec![0.0, -speed]);
    }
    let mut run = build_solid_run::<2>(&scene)?;
    let h = R0 / n as f64;
    let kinetic0 = run.particles.kinetic_energy();
    run.particles.track_temperature();
    let t0 = run.particles.temperature.clone();
    let clock = Instant::now();
    while !run.finished() {
        run.step()?;
    }
    let wall_s = clock.elapsed().as_secs_f64();
    let p = &run.particles;
    let (mut top, mut bottom, mut rmax, mut rfoot) = (f64::MIN, f64::MAX, 0.0f64, 0.0f64);
    let (mut elastic, mut plastic) = (0.0, 0.0);
    let (mut max_eps, mut max_d, mut failed) = (0.0f64, 0.0f64, 0);
    for i in 0..p.len() {
        let m = &run.materials[p.material[i] as usize];
        let az = p.f.get(i)[(1, 1)] * p.half_size.get(i)[1];
        let ar = p.f.get(i)[(0, 0)] * p.half_size.get(i)[0];
        top = top.max(p.x[i][1] + az);
        bottom = bottom.min(p.x[i][1] - az);
        rmax = rmax.max(p.x[i][0] + ar);
        if p.x0[i][1] < 2.0 * p.half_size.get(i)[1] {
            rfoot = rfoot.max(p.x[i][0] + ar);
        }
        let k = m.elastic.bulk();
        let mu = m.elastic.mu;
        let s = &p.stress.get(i);
        let pr = s.trace() / 3.0;
        let q = von_mises(s);
        elastic += p.vol[i] * (pr * pr / (2.0 * k) + q * q / (6.0 * mu));
        if let Some(j2) = m.plasticity() {
            if j2.taylor_quinney > 0.0 {
                plastic += p.mass[i] * j2.specific_heat * (p.temperature_of(i) - t0[i])
                    / j2.taylor_quinney;
            }
        }
        max_eps = max_eps.max(p.plastic_strain_of(i));
        if let Some(&d) = p.damage.get(i) {
            max_d = max_d.max(d);
            failed += usize::from(d >= 1.0);
        }
    }
    let e = run.energies();
    Ok(TaylorMeasured {
        h,
        speed,
        length: top - bottom,
        gap: bottom,
        diameter: 2.0 * rmax,
        footprint: 2.0 * rfoot,
        kinetic0,
        kinetic: e.kinetic,
        work: e.strain,
        elastic,
        plastic,
        max_plastic_strain: max_eps,
        max_damage: max_d,
        failed,
        particles: p.len(),
        steps: run.steps,
        wall_s,
    })
}
