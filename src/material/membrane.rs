//! York's membrane material points (York Sec. 3.2): a thin elastic sheet with
//! no bending resistance and constant traction through its thickness,
//! represented by one layer of ordered material points.
//!
//! The stress lives in the membrane's local frame: tangent `t`, normal `n`
//! and the out-of-plane direction `e₃` (the hoop direction of a later
//! axisymmetric run). The strain rate at a point (York Eq. 13 divided by Δt)
//! is projected on that frame, `ε̇_tt = t·L·t`; the traction-free faces give
//! `σ_nn = 0`. York Sec. 3.2 lets the out-of-plane strain give either a
//! uniaxial stress (a string) or a plane-stress state. In plane 2D a
//! membrane is a cross-section of a long sheet, so `ε₃₃ = 0` (plane strain
//! along the sheet) and plane stress through the thickness:
//!
//! `ṡ_tt = E/(1 − ν²) ε̇_tt`, `s₃₃ = ν s_tt`  (York Eq. 18 in the local frame),
//!
//! and the global stress for the internal force (York Eq. 15) is
//! `σ = s_tt t⊗t + s₃₃ e₃⊗e₃`; only the in-plane block enters the 2D force.
//! An axisymmetric run would add the hoop rate `ε̇₃₃ = v_r/r` to the same
//! 2×2 plane-stress law (`ṡ = E/(1 − ν²) [[1, ν], [ν, 1]] ε̇`).

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

    /// One step of the tangential stress: `s + Δt E/(1 − ν²) ε̇_tt`
    /// (York Eq. 18 projected on `t`; the rate is objective because `s` is a
    /// scalar of the local frame).
    #[inline]
    pub fn update(&self, s: f64, eps_rate: f64, dt: f64) -> f64 {
        s + dt * self.modulus() * eps_rate
    }

    /// The out-of-plane stress `s₃₃ = ν s_tt` (ε₃₃ = 0).
    #[inline]
    pub fn out_of_plane(&self, s: f64) -> f64 {
        self.poisson * s
    }

    /// Elastic energy per unit reference volume stored by a tangential
    /// stress `s` (`s²/(2E')`, used for a prestress).
    #[inline]
    pub fn energy_of(&self, s: f64) -> f64 {
        0.5 * s * s / self.modulus()
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
        // A constant rate over a unit time gives E' ε.
        let mut s = 0.0;
        for _ in 0..10 {
            s = m.update(s, 0.01, 0.1);
        }
        assert!((s - 0.01 * m.modulus()).abs() < 1e-9);
        assert_eq!(m.out_of_plane(10.0), 3.0);
    }
}
