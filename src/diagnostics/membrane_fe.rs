//! Exact references for the membrane finite elements (Lian Sec. 4):
//! Hencky's clamped circular membrane under pressure and the vibration of
//! a pre-tensioned square membrane.

use std::time::Instant;

use crate::membrane::element::{MembraneError, MembraneMaterial, MembraneMesh, V3};
use crate::membrane::quad_mesh::{boundary_nodes, disc, rectangle};

/// Hencky's solution of a clamped circular membrane of radius a,
/// thickness t and Young's modulus E under a uniform pressure p (Hencky
/// 1915, with the correction of Chien 1948; Fichter 1997, NASA TP-3658,
/// Eqs. 8–16): returns `(b0, K)` with the centre deflection
/// w₀ = K a (p a / (E t))^{1/3} and the centre radial stress
/// σ_r(0) = b0/4 (E p² a² / t²)^{1/3}.
///
/// The membrane equations (no bending) for the radial membrane force
/// N_r = N₀ s(ρ), ρ = r/a, N₀ = ¼ (E t p² a²)^{1/3}, reduce to
/// s'' + 3 s'/ρ = −8/s², s'(0) = 0, with the clamped edge (zero hoop
/// strain) (1 − ν) s(1) + s'(1) = 0, and w₀ = a (pa/(Et))^{1/3} ∫₀¹ dx/s
/// with x = ρ². This solves them by Hencky's power series in x: s = Σ bₙ xⁿ
/// with 4 n (n+1) bₙ = −8 [xⁿ⁻¹] s⁻², b₀ by bisection on the edge
/// condition, K = Σ hₙ/(n+1) with 1/s = Σ hₙ xⁿ.
pub fn hencky(poisson: f64) -> (f64, f64) {
    const TERMS: usize = 400;
    // Series of s, s² and 1/s² up to TERMS, for a given b0.
    let series = |b0: f64| -> Vec<f64> {
        let mut b = vec![0.0; TERMS];
        let mut s2 = vec![0.0; TERMS];
        let mut g = vec![0.0; TERMS];
        b[0] = b0;
        s2[0] = b0 * b0;
        g[0] = 1.0 / s2[0];
        for n in 1..TERMS {
            let nf = n as f64;
            b[n] = -8.0 * g[n - 1] / (4.0 * nf * (nf + 1.0));
            s2[n] = (0..=n).map(|k| b[k] * b[n - k]).sum();
            g[n] = -(1..=n).map(|k| s2[k] * g[n - k]).sum::<f64>() / s2[0];
        }
        b
    };
    // Edge condition (1 − ν) s(1) + s'(1) = Σ (1 − ν + 2n) bₙ (ρ s' = 2x ds/dx).
    let edge = |b0: f64| -> f64 {
        series(b0)
            .iter()
            .enumerate()
            .map(|(n, bn)| (1.0 - poisson + 2.0 * n as f64) * bn)
            .sum()
    };
    let (mut lo, mut hi) = (1.0, 4.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if edge(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let b0 = 0.5 * (lo + hi);
    let b = series(b0);
    // 1/s = Σ hₙ xⁿ: s · h = 1.
    let mut h = vec![0.0; TERMS];
    h[0] = 1.0 / b[0];
    for n in 1..TERMS {
        h[n] = -(1..=n).map(|k| b[k] * h[n - k]).sum::<f64>() / b[0];
    }
    let k = h
        .iter()
        .enumerate()
        .map(|(n, hn)| hn / (n as f64 + 1.0))
        .sum();
    (b0, k)
}

/// Fundamental frequency \[Hz\] of a square membrane of side `side` with
/// fixed edges under the isotropic tension T = σ₀ t: f₁₁ = c / (√2 L),
/// c = √(T / (ρ t)) = √(σ₀/ρ).
pub fn square_membrane_f11(side: f64, prestress: f64, density: f64) -> f64 {
    (prestress / density).sqrt() / (std::f64::consts::SQRT_2 * side)
}

/// The pre-tensioned square membrane of the vibration study: side 1 m,
/// thickness 1 mm, ρ = 1000 kg/m³, E = 1 MPa, ν = 0.3, isotropic
/// prestress σ₀ = 10 kPa (E/σ₀ = 100), edges fixed in every direction.
#[derive(Debug, Clone, Copy)]
pub struct SquareVibration {
    /// Side L \[m\].
    pub side: f64,
    /// Thickness \[m\].
    pub thickness: f64,
    /// Material (hourglass coefficient included).
    pub material: MembraneMaterial,
    /// Prestress σ₀ \[Pa\].
    pub prestress: f64,
    /// Centre velocity amplitude of the initial mode-(1,1) velocity [m/s].
    pub amplitude: f64,
    /// Time step over the stable one.
    pub cfl: f64,
}

impl Default for SquareVibration {
    fn default() -> Self {
        Self {
            side: 1.0,
            thickness: 1e-3,
            material: MembraneMaterial {
                density: 1000.0,
                young: 1e6,
                poisson: 0.3,
                hourglass: 0.1,
                damping: 0.0,
            },
            prestress: 1e4,
            amplitude: 1e-5,
            cfl: 0.9,
        }
    }
}

/// One run of [`SquareVibration`].
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct VibrationResult {
    /// Elements per side.
    pub cells: usize,
    /// Measured period (between the 1st and 3rd zero crossing of the centre
    /// deflection) \[s\].
    pub period: f64,
    /// Exact period 1/f₁₁ \[s\].
    pub exact: f64,
    /// |T − T_exact| / T_exact.
    pub error: f64,
    /// Steps taken.
    pub steps: u64,
    /// Elements.
    pub elements: usize,
    /// Wall seconds of the stepping.
    pub wall_s: f64,
}

impl SquareVibration {
    /// The mesh of `cells × cells` elements in the x–y plane with the
    /// initial velocity v_z = A sin(πx/L) sin(πy/L).
    pub fn mesh(&self, cells: usize) -> Result<MembraneMesh, MembraneError> {
        let l = self.side;
        let r = rectangle(
            V3::zeros(),
            V3::new(l, 0.0, 0.0),
            V3::new(0.0, l, 0.0),
            cells,
            cells,
        );
        let s = self.prestress;
        let mut m =
            MembraneMesh::new(r.nodes, r.quads, self.thickness, self.material, [s, s, 0.0])?;
        let edge = boundary_nodes(m.num_nodes(), &m.quads);
        for (n, p) in r.params.iter().enumerate() {
            if edge[n] {
                m.fixed[n] = [true; 3];
            }
            let pi = std::f64::consts::PI;
            m.v[n][2] = self.amplitude * (pi * p[0]).sin() * (pi * p[1]).sin();
        }
        m.apply_fixed();
        Ok(m)
    }

    /// Runs `cells × cells` elements for 1.6 exact periods and measures the
    /// period from the centre node's zero crossings.
    ///
    /// # Errors
    /// An element failure.
    pub fn run(&self, cells: usize) -> Result<VibrationResult, MembraneError> {
        let exact = 1.0 / square_membrane_f11(self.side, self.prestress, self.material.density);
        let mut m = self.mesh(cells)?;
        let centre = cells / 2 + (cells + 1) * (cells / 2);
        let dt = self.cfl * m.stable_dt();
        let start = Instant::now();
        let mut crossings = Vec::new();
        let (mut t, mut steps) = (0.0, 0u64);
        let mut z_prev = m.x[centre][2];
        while t < 1.6 * exact {
            m.step(dt, steps)?;
            steps += 1;
            let z = m.x[centre][2];
            if steps > 1 && (z_prev > 0.0) != (z > 0.0) {
                crossings.push(t + dt * z_prev / (z_prev - z));
            }
            z_prev = z;
            t += dt;
        }
        let wall_s = start.elapsed().as_secs_f64();
        let period = if crossings.len() >= 3 {
            crossings[2] - crossings[0]
        } else {
            f64::NAN
        };
        Ok(VibrationResult {
            cells,
            period,
            exact,
            error: ((period - exact) / exact).abs(),
            steps,
            elements: m.num_elements(),
            wall_s,
        })
    }
}

/// The clamped circular membrane under pressure of the Hencky study:
/// radius 1 m, thickness 1 mm, E = 1 GPa, ν = 0.3, ρ = 1000 kg/m³,
/// p a/(E t) = 1e-5, relaxed by mass-proportional damping.
#[derive(Debug, Clone, Copy)]
pub struct HenckyDisc {
    /// Radius a \[m\].
    pub radius: f64,
    /// Thickness \[m\].
    pub thickness: f64,
    /// Material; `damping` is set from the expected lowest frequency.
    pub material: MembraneMaterial,
    /// p a / (E t).
    pub load: f64,
    /// Time step over the stable one.
    pub cfl: f64,
    /// End time in units of 1/ω₁ (ω₁ the lowest frequency of the loaded
    /// membrane).
    pub periods: f64,
}

impl Default for HenckyDisc {
    fn default() -> Self {
        Self {
            radius: 1.0,
            thickness: 1e-3,
            material: MembraneMaterial {
                density: 1000.0,
                young: 1e9,
                poisson: 0.3,
                hourglass: 0.1,
                damping: 0.0,
            },
            load: 1e-5,
            cfl: 0.9,
            periods: 40.0,
        }
    }
}

/// One run of [`HenckyDisc`].
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct HenckyResult {
    /// Elements across the diameter.
    pub cells: usize,
    /// Centre deflection at the end \[m\].
    pub w0: f64,
    /// Hencky's w₀ = K a (p a/(E t))^{1/3} \[m\].
    pub exact: f64,
    /// |w₀ − exact| / exact.
    pub error: f64,
    /// Kinetic over strain energy at the end (how static the end state is).
    pub kinetic_ratio: f64,
    /// Hourglass over strain energy at the end.
    pub hourglass_ratio: f64,
    /// Steps taken.
    pub steps: u64,
    /// Elements.
    pub elements: usize,
    /// Wall seconds of the stepping.
    pub wall_s: f64,
}

impl HenckyDisc {
    /// Runs a disc of `cells × cells` elements ([`disc`]) to a damped
    /// static state.
    ///
    /// # Errors
    /// An element failure.
    pub fn run(&self, cells: usize) -> Result<HenckyResult, MembraneError> {
        let a = self.radius;
        let mat0 = self.material;
        let (b0, k) = hencky(mat0.poisson);
        let p = self.load * mat0.young * self.thickness / a;
        // Radial membrane stress at the centre (Hencky), and the lowest
        // frequency of a membrane of that tension: ω₁ ≈ 2.405 c_T / a.
        let sigma = 0.25 * b0 * (mat0.young * p * p * a * a / self.thickness.powi(2)).cbrt();
        let omega = 2.405 * (sigma / mat0.density).sqrt() / a;
        let mut mat = mat0;
        mat.damping = 2.0 * omega;
        let d = disc(V3::zeros(), a, cells);
        let mut m = MembraneMesh::new(d.nodes, d.quads, self.thickness, mat, [0.0; 3])?;
        m.pressure = p;
        let edge = boundary_nodes(m.num_nodes(), &m.quads);
        for (n, e) in edge.iter().enumerate() {
            m.fixed[n] = [*e; 3];
        }
        let centre = cells / 2 + (cells + 1) * (cells / 2);
        let dt = self.cfl * m.stable_dt();
        let end = self.periods / omega;
        let start = Instant::now();
        let (mut t, mut steps) = (0.0, 0u64);
        while t < end {
            m.step(dt, steps)?;
            steps += 1;
            t += dt;
        }
        let wall_s = start.elapsed().as_secs_f64();
        let w0 = m.x[centre][2];
        let exact = k * a * self.load.cbrt();
        let u = m.strain_energy_total();
        Ok(HenckyResult {
            cells,
            w0,
            exact,
            error: ((w0 - exact) / exact).abs(),
            kinetic_ratio: m.kinetic_energy() / u,
            hourglass_ratio: m.hourglass_energy() / u,
            steps,
            elements: m.num_elements(),
            wall_s,
        })
    }
}

/// Energies at the end of a point-load run (hourglass check).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct PointLoadResult {
    /// Elements per side.
    pub cells: usize,
    /// Energy taken out by the hourglass forces \[J\].
    pub hourglass: f64,
    /// Stored energy \[J\].
    pub strain: f64,
    /// Work of the point load \[J\].
    pub work: f64,
    /// Steps taken.
    pub steps: u64,
}

/// The [`SquareVibration`] membrane at rest under a point load
/// −0.01 σ₀ t L ẑ on its centre node (the load that excites hourglass
/// patterns most: no smooth field resolves it), run for `periods` periods
/// of the (1,1) mode with mass-proportional damping `damping` [1/s]; the
/// load ramps up as ½(1 − cos(π t/t_r)) over t_r = `ramp_periods` periods
/// (0: applied at once).
///
/// # Errors
/// An element failure.
pub fn point_load(
    cells: usize,
    damping: f64,
    periods: f64,
    ramp_periods: f64,
) -> Result<PointLoadResult, MembraneError> {
    let mut cfg = SquareVibration::default();
    cfg.material.damping = damping;
    cfg.amplitude = 0.0;
    let mut m = cfg.mesh(cells)?;
    let centre = cells / 2 + (cells + 1) * (cells / 2);
    let t = cfg.prestress * cfg.thickness;
    m.f_applied[centre] = V3::new(0.0, 0.0, -0.01 * t * cfg.side);
    let dt = cfg.cfl * m.stable_dt();
    let period = 1.0 / square_membrane_f11(cfg.side, cfg.prestress, cfg.material.density);
    let ramp = ramp_periods * period;
    let steps = (periods * period / dt) as u64;
    let full = m.f_applied[centre];
    for k in 0..steps {
        // Load ramp 0.5 (1 − cos(π t / t_ramp)) up to t_ramp.
        let t = k as f64 * dt;
        let s = if t < ramp {
            0.5 * (1.0 - (std::f64::consts::PI * t / ramp).cos())
        } else {
            1.0
        };
        m.f_applied[centre] = full * s;
        m.step(dt, k)?;
    }
    Ok(PointLoadResult {
        cells,
        hourglass: m.hourglass_energy(),
        strain: m.strain_energy_total(),
        work: m.external_work_total(),
        steps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hencky_coefficient_matches_the_tabulated_value() {
        // Fichter 1997 (Table 1, Hencky with Chien's correction) for
        // ν = 0.3: b0 = 1.7244; an independent RK4 shooting solution of
        // the same ODE gives b0 = 1.72440406438, K = 0.65344334473.
        let (b0, k) = hencky(0.3);
        assert!((b0 - 1.724_404_064_38).abs() < 1e-9, "b0 = {b0}");
        assert!((k - 0.653_443_344_73).abs() < 1e-9, "K = {k}");
    }
}
