//! York's membrane material points (York Sec. 3.2): a thin elastic sheet with
//! no bending resistance and constant traction through its thickness,
//! represented by one layer of ordered material points.
//!
//! The stress lives in the membrane's local frame: tangent `t`, normal `n`
//! and the out-of-plane direction `e₃` (the hoop direction `θ` of an
//! axisymmetric run). The strain rate at a point (York Eq. 13 divided by Δt)
//! is projected on that frame, `ε̇_tt = t·L·t`; the traction-free faces give
//! `σ_nn = 0` (plane stress through the thickness, York Sec. 3.2), and the
//! in-surface stresses follow the 2×2 plane-stress law
//!
//! `ṡ_tt = E/(1 − ν²) (ε̇_tt + ν ε̇₃₃)`, `ṡ₃₃ = E/(1 − ν²) (ν ε̇_tt + ε̇₃₃)`
//! (York Eq. 18 in the local frame).
//!
//! * Plane 2D: a membrane is a cross-section of a long sheet, `ε̇₃₃ = 0`
//!   (plane strain along the sheet), so `ṡ_tt = E/(1 − ν²) ε̇_tt` and
//!   `s₃₃ = ν s_tt`.
//! * Axisymmetric r–z: a membrane point is a ring; `ε̇₃₃ = ε̇_θθ = v_r / r`
//!   (the hoop strain rate of a ring of radius r), and `s_θθ` enters the
//!   nodal force through the kernels' hoop term (`V σ_θθ N / r`).
//!
//! The global stress for the internal force (York Eq. 15) is
//! `σ = s_tt t⊗t + s₃₃ e₃⊗e₃`.

/// The elastic membrane law of one membrane material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MembraneLaw {
    /// Young's modulus E.
    pub young: f64,
    /// Poisson's ratio ν.
    pub poisson: f64,
    /// Thickness h (constant: York's single layer of points).
    pub thickness: f64,
    /// Density ρ (mass per unit volume; areal density is ρ h).
    pub density: f64,
}

impl MembraneLaw {
    /// The in-plane modulus of plane 2D, `E/(1 − ν²)` (ε₃₃ = 0, σ_nn = 0).
    #[inline]
    pub fn modulus(&self) -> f64 {
        self.young / (1.0 - self.poisson * self.poisson)
    }

    /// Longitudinal wave speed `√(E/((1 − ν²) ρ))` of the sheet.
    #[inline]
    pub fn wave_speed(&self) -> f64 {
        (self.modulus() / self.density).sqrt()
    }

    /// One step of the in-surface stresses `(s_tt, s₃₃)` under the rates
    /// `(ε̇_tt, ε̇₃₃)`: `s + Δt E/(1 − ν²) [[1, ν], [ν, 1]] ε̇` (York Eq. 18
    /// in the local frame, plane stress through the thickness; the rate is
    /// objective because both components are scalars of the local frame).
    #[inline]
    pub fn update(&self, s: [f64; 2], rate: [f64; 2], dt: f64) -> [f64; 2] {
        let k = dt * self.modulus();
        let nu = self.poisson;
        [
            s[0] + k * (rate[0] + nu * rate[1]),
            s[1] + k * (nu * rate[0] + rate[1]),
        ]
    }

    /// The out-of-plane stress `s₃₃ = ν s_tt` of plane 2D (ε₃₃ = 0).
    #[inline]
    pub fn out_of_plane(&self, s: f64) -> f64 {
        self.poisson * s
    }

    /// Elastic energy per unit reference volume stored by the in-surface
    /// stresses `(s_tt, s₃₃)`: `(s_tt² + s₃₃² − 2ν s_tt s₃₃)/(2E)` (plane
    /// stress; with `s₃₃ = ν s_tt` this is `s_tt²/(2E/(1 − ν²))`).
    #[inline]
    pub fn energy_of(&self, s: [f64; 2]) -> f64 {
        (s[0] * s[0] + s[1] * s[1] - 2.0 * self.poisson * s[0] * s[1]) / (2.0 * self.young)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_strain_modulus_and_wave_speed() {
        let m = MembraneLaw {
            young: 1e4,
            poisson: 0.3,
            thickness: 0.1,
            density: 0.5,
        };
        assert!((m.modulus() - 1e4 / 0.91).abs() < 1e-9);
        assert!((m.wave_speed() - (1e4 / 0.91 / 0.5_f64).sqrt()).abs() < 1e-12);
        // A constant rate over a unit time gives E' ε; with ε̇₃₃ = 0 the
        // out-of-plane stress stays ν s_tt.
        let mut s = [0.0, 0.0];
        for _ in 0..10 {
            s = m.update(s, [0.01, 0.0], 0.1);
        }
        assert!((s[0] - 0.01 * m.modulus()).abs() < 1e-9);
        assert!((s[1] - m.out_of_plane(s[0])).abs() < 1e-9);
        assert_eq!(m.out_of_plane(10.0), 3.0);
        assert!((m.energy_of([10.0, 3.0]) - 100.0 / (2.0 * m.modulus())).abs() < 1e-12);
        // Equal biaxial strain ε (a sphere): s = E ε/(1 − ν) in both.
        let s = m.update([0.0, 0.0], [0.01, 0.01], 1.0);
        let exact = 1e4 * 0.01 / 0.7;
        assert!((s[0] - exact).abs() < 1e-9 && (s[1] - exact).abs() < 1e-9);
    }
}
