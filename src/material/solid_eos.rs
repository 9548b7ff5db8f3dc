//! The equation of state of a solid material in the multifield equations
//! (Guilkey Sec. 3.3 step 2 and Fig. 1).
//!
//! In a coupled MPM-ICE step every solid material also lives in the cells,
//! and the equilibration pressure (Guilkey Eq. 13) needs its specific volume
//! at a trial pressure, `v_s(p)`, from the bulk part of its constitutive
//! response — never from the interpolated mass and volume. The bulk response
//! used here is the compressible neo-Hookean one,
//!
//! ```text
//! p − p_ref = (K/2) (x − 1/x),   x = ρ/ρ₀ = 1/J,
//! ρ(p) = ρ₀ (g/K + √((g/K)² + 1)),   g = p − p_ref ,
//! ```
//!
//! whose tangent at the reference state is the bulk modulus `K`.
//!
//! **Threshold modification (Guilkey Fig. 1).** Below a positive threshold
//! pressure `p_th` (typically one atmosphere) the solid's pressure follows a
//! power law that is continuous with the full law and with its slope at
//! `p_th` and tends to zero as the specific volume grows:
//!
//! ```text
//! p = p_th (ρ/ρ_th)^n,   ρ_th = ρ(p_th),   n = ρ_th (dp/dρ)(ρ_th) / p_th ,
//! ```
//!
//! (a polynomial in `1/v` for integer `n`). The solid then cannot pull the
//! equilibration pressure below zero when it is in tension next to a gas: its
//! cell specific volume decouples from its stress there, and the full stress
//! on the particles carries the response ("a configuration stress acting on
//! an incompressible material", Guilkey Sec. 3.3). The same law is what
//! Uintah's MPM-ICE calls the modified EOS (`n = p_ref/K` in its inverse).
//!
//! The solid is isothermal in the cells (no thermal expansion: `∂p/∂T = 0`,
//! so the isentropic and isothermal compressibilities agree); `c_v` only
//! enters a heat exchange.

use super::equation_of_state::{EosError, EquationOfState};

/// Bulk equation of state of a solid in the multifield equations, with the
/// threshold modification of Guilkey Fig. 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolidEos {
    rho0: f64,
    bulk: f64,
    p_ref: f64,
    p_threshold: f64,
    rho_threshold: f64,
    exponent: f64,
    cv: f64,
}

impl SolidEos {
    /// A solid of reference density `rho0` at the reference pressure
    /// `p_ref`, bulk modulus `bulk`, threshold pressure `p_threshold`
    /// (`0 < p_threshold`; the power law applies below it) and specific heat
    /// `cv`.
    ///
    /// # Errors
    /// [`EosError::Invalid`] for a non-positive or non-finite `rho0`,
    /// `bulk`, `p_threshold` or `cv`, or a non-finite `p_ref`.
    pub fn new(
        rho0: f64,
        bulk: f64,
        p_ref: f64,
        p_threshold: f64,
        cv: f64,
    ) -> Result<Self, EosError> {
        let pos = |field, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(EosError::Invalid {
                    field,
                    allowed: "finite and > 0",
                    got: v,
                })
            }
        };
        pos("density", rho0)?;
        pos("bulk_modulus", bulk)?;
        pos("threshold_pressure", p_threshold)?;
        pos("cv", cv)?;
        if !p_ref.is_finite() {
            return Err(EosError::Invalid {
                field: "reference_pressure",
                allowed: "finite",
                got: p_ref,
            });
        }
        let mut eos = Self {
            rho0,
            bulk,
            p_ref,
            p_threshold,
            rho_threshold: 0.0,
            exponent: 1.0,
            cv,
        };
        let rho_th = eos.full_density(p_threshold);
        eos.rho_threshold = rho_th;
        eos.exponent = rho_th * eos.full_dp_drho(rho_th) / p_threshold;
        Ok(eos)
    }

    /// Reference density `ρ₀` (at `p_ref`).
    pub fn reference_density(&self) -> f64 {
        self.rho0
    }

    /// Bulk modulus `K` of the full law at the reference state.
    pub fn bulk_modulus(&self) -> f64 {
        self.bulk
    }

    /// Reference pressure `p_ref` (zero stress on the particles).
    pub fn reference_pressure(&self) -> f64 {
        self.p_ref
    }

    /// Threshold pressure `p_th` below which the power law applies.
    pub fn threshold_pressure(&self) -> f64 {
        self.p_threshold
    }

    /// Exponent `n` of the power law below the threshold.
    pub fn exponent(&self) -> f64 {
        self.exponent
    }

    #[inline]
    fn full_density(&self, p: f64) -> f64 {
        let g = (p - self.p_ref) / self.bulk;
        // x = g + √(g² + 1), written to avoid cancellation for g ≪ −1.
        let x = if g >= 0.0 {
            g + (g * g + 1.0).sqrt()
        } else {
            1.0 / ((g * g + 1.0).sqrt() - g)
        };
        self.rho0 * x
    }

    #[inline]
    fn full_dp_drho(&self, rho: f64) -> f64 {
        let x = rho / self.rho0;
        0.5 * self.bulk * (1.0 + 1.0 / (x * x)) / self.rho0
    }
}

impl EquationOfState for SolidEos {
    #[inline]
    fn pressure(&self, rho: f64, _t: f64) -> f64 {
        if rho >= self.rho_threshold {
            let x = rho / self.rho0;
            self.p_ref + 0.5 * self.bulk * (x - 1.0 / x)
        } else {
            self.p_threshold * (rho / self.rho_threshold).powf(self.exponent)
        }
    }

    #[inline]
    fn dp_drho(&self, rho: f64, t: f64) -> f64 {
        if rho >= self.rho_threshold {
            self.full_dp_drho(rho)
        } else {
            self.exponent * self.pressure(rho, t) / rho
        }
    }

    #[inline]
    fn dp_dt(&self, _rho: f64, _t: f64) -> f64 {
        0.0
    }

    #[inline]
    fn sound_speed_sq(&self, rho: f64, t: f64) -> f64 {
        self.dp_drho(rho, t)
    }

    fn density(&self, p: f64, _t: f64) -> Result<f64, EosError> {
        if !p.is_finite() {
            return Err(EosError::Invalid {
                field: "pressure",
                allowed: "finite",
                got: p,
            });
        }
        if p >= self.p_threshold {
            Ok(self.full_density(p))
        } else if p > 0.0 {
            Ok(self.rho_threshold * (p / self.p_threshold).powf(1.0 / self.exponent))
        } else {
            Err(EosError::PressureOutOfRange { p, p_min: 0.0 })
        }
    }

    #[inline]
    fn specific_heat_cv(&self) -> f64 {
        self.cv
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steel() -> SolidEos {
        SolidEos::new(8900.0, 117.0e9, 101_325.0, 101_325.0, 450.0).unwrap()
    }

    #[test]
    fn reference_state_and_bulk_modulus() {
        let s = steel();
        let rho = s.density(101_325.0, 300.0).unwrap();
        assert!((rho - 8900.0).abs() <= 1e-12 * 8900.0);
        // K = ρ dp/dρ at the reference state.
        assert!((rho * s.dp_drho(rho, 300.0) - 117.0e9).abs() <= 1e-9 * 117.0e9);
    }

    #[test]
    fn round_trip_above_and_below_the_threshold() {
        let s = steel();
        for p in [1.0, 1e3, 5e4, 101_325.0, 1e6, 1.94e7, 1e9, 5e10] {
            let rho = s.density(p, 300.0).unwrap();
            let back = s.pressure(rho, 300.0);
            assert!((back - p).abs() <= 1e-9 * p, "{p}: {back}");
        }
        assert!(s.density(0.0, 300.0).is_err());
        assert!(s.density(-1.0, 300.0).is_err());
    }

    #[test]
    fn continuous_and_smooth_at_the_threshold() {
        let s = steel();
        let rho_th = s.density(s.threshold_pressure(), 300.0).unwrap();
        let (below, above) = (rho_th * (1.0 - 1e-12), rho_th * (1.0 + 1e-12));
        let (p_lo, p_hi) = (s.pressure(below, 0.0), s.pressure(above, 0.0));
        let (d_lo, d_hi) = (s.dp_drho(below, 0.0), s.dp_drho(above, 0.0));
        // No jump beyond the slope across the 2e-12 relative interval.
        let jump = (p_hi - p_lo) - d_hi * (above - below);
        assert!(jump.abs() <= 1e-6 * s.threshold_pressure(), "jump {jump}");
        // The power law's slope varies as ρ^(n−1): over the 2e-12 relative
        // interval by about 2e-12 n; anything beyond would be a kink.
        let tol = 2.0 * 2e-12 * s.exponent() * d_hi;
        assert!((d_lo - d_hi).abs() <= tol, "{d_lo} vs {d_hi}");
        // Below the threshold p tends to zero as the specific volume grows.
        assert!(s.pressure(0.999 * rho_th, 0.0) < 1e-100);
    }
}
