//! The equation-of-state interface shared by every fluid and solid EOS of
//! the multifield model: the thermal and caloric closure relations
//! (Guilkey Eqs. 10–11), their derivatives and the error type. The concrete
//! laws live in [`super::eos`] (ideal and stiffened gas, the cell-fluid
//! enum), [`super::mie_gruneisen`] (liquids and metals), [`super::jwl`]
//! (detonation products) and [`super::solid_eos`] (the solid's bulk
//! response); the choice of
//! compressibility and the energy convention are explained in
//! [`super::eos`].

use std::fmt;

/// Errors from constructing or inverting an equation of state.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum EosError {
    /// A parameter or argument is outside its admissible range.
    #[error("invalid equation-of-state value `{field}`: must be {allowed}, got {got}")]
    Invalid {
        /// Name of the offending parameter (`"gamma"`, `"cv"`, `"p_inf"`,
        /// `"pressure"`, `"temperature"`, ...).
        field: &'static str,
        /// Human-readable admissible range.
        allowed: &'static str,
        /// The rejected value.
        got: f64,
    },
    /// No positive density (in the hyperbolic range `c² > 0`) produces this
    /// pressure at the requested temperature.
    #[error("no positive density gives pressure {p} (the equation of state requires p > {p_min})")]
    PressureOutOfRange {
        /// The requested pressure.
        p: f64,
        /// Infimum of the admissible pressures (exclusive): `0` for an ideal
        /// gas and JWL products, `−p_∞` for a stiffened gas, the tension
        /// limit `(p₀ − K)/(1 + Γ₀)` for Mie–Grüneisen.
        p_min: f64,
    },
}

/// Validates that `value` is finite and strictly greater than `bound`.
pub(crate) fn check_gt(
    field: &'static str,
    allowed: &'static str,
    value: f64,
    bound: f64,
) -> Result<f64, EosError> {
    if value.is_finite() && value > bound {
        Ok(value)
    } else {
        Err(EosError::Invalid {
            field,
            allowed,
            got: value,
        })
    }
}

/// Validates a pressure argument: finite and `p > p_min` (the EOS's
/// hyperbolic range).
pub(crate) fn check_pressure(p: f64, p_min: f64) -> Result<f64, EosError> {
    if !p.is_finite() {
        return Err(EosError::Invalid {
            field: "pressure",
            allowed: "finite",
            got: p,
        });
    }
    if p <= p_min {
        return Err(EosError::PressureOutOfRange { p, p_min });
    }
    Ok(p)
}

/// Validates a temperature argument: finite and `T > 0`.
pub(crate) fn check_temperature(t: f64) -> Result<f64, EosError> {
    check_gt("temperature", "finite and > 0", t, 0.0)
}

/// An equation of state for a fluid material of the multifield model.
///
/// Notation: `ρ` material (true) density `[kg/m³]`, `v = 1/ρ` specific
/// volume, `T` temperature `[K]`, `e` specific internal energy `[J/kg]`,
/// `p` pressure `[Pa]`, `c_v` specific heat at constant volume
/// `[J/(kg K)]`.
///
/// The methods are infallible and branch-free for use inside per-cell hot
/// loops; they assume `ρ > 0` and `T > 0` (callers keep the state there).
/// Only the inverse [`density`](EquationOfState::density) validates its
/// arguments, because it is where an out-of-range state first appears (the
/// equilibration pressure iteration of Guilkey Eq. 13).
pub trait EquationOfState: Send + Sync + fmt::Debug {
    /// Thermal EOS `p(ρ, T)` (Guilkey Eq. 11, solved for `p`).
    fn pressure(&self, rho: f64, t: f64) -> f64;

    /// Isothermal density derivative `(∂p/∂ρ)_T`.
    fn dp_drho(&self, rho: f64, t: f64) -> f64;

    /// Isochoric temperature derivative `(∂p/∂T)_ρ`.
    fn dp_dt(&self, rho: f64, t: f64) -> f64;

    /// Isentropic sound speed squared `c² = (∂p/∂ρ)_s`.
    ///
    /// With the caloric EOS `e = c_v T` and `de = −p dv = (p/ρ²) dρ` along an
    /// isentrope,
    ///
    /// ```text
    /// c² = (∂p/∂ρ)_T + (p/(ρ² c_v)) (∂p/∂T)_ρ .
    /// ```
    fn sound_speed_sq(&self, rho: f64, t: f64) -> f64;

    /// Inverse of the thermal EOS: the density `ρ > 0` with
    /// `pressure(ρ, T) = p` (Guilkey Eq. 11, `v(p, T) = 1/ρ`).
    ///
    /// # Errors
    ///
    /// [`EosError::Invalid`] for a non-finite `p` or a non-finite or
    /// non-positive `T`; [`EosError::PressureOutOfRange`] when no positive
    /// density in the admissible range gives `p`.
    fn density(&self, p: f64, t: f64) -> Result<f64, EosError>;

    /// Caloric EOS `e(T) = c_v T` (Guilkey Eq. 10), the same for every EOS
    /// here.
    #[inline]
    fn internal_energy(&self, t: f64) -> f64 {
        self.specific_heat_cv() * t
    }

    /// Inverse caloric EOS `T(e) = e / c_v`.
    #[inline]
    fn temperature(&self, e: f64) -> f64 {
        e / self.specific_heat_cv()
    }

    /// Constant specific heat at constant volume `c_v`.
    fn specific_heat_cv(&self) -> f64;

    /// Isentropic sound speed `c = √(c²)`; `NaN` outside the hyperbolic
    /// range (`c² < 0`).
    fn sound_speed(&self, rho: f64, t: f64) -> f64 {
        self.sound_speed_sq(rho, t).sqrt()
    }

    /// Bulk compressibility `κ` used in the pressure increment of
    /// Guilkey Eq. 29 and in `f_r^θ = θ_r κ_r / Σ_s θ_s κ_s` (Guilkey
    /// Eq. 53): the **isentropic** compressibility
    ///
    /// ```text
    /// κ_s = −(1/v)(∂v/∂p)_s = 1/(ρ c²) .
    /// ```
    ///
    /// The isentropic (not the isothermal, Guilkey Eq. 47) value is used
    /// because Eq. 29 omits the `θ β DT/Dt` term of Guilkey Eq. 51; see the
    /// module documentation.
    fn compressibility(&self, rho: f64, t: f64) -> f64 {
        1.0 / (rho * self.sound_speed_sq(rho, t))
    }

    /// Isothermal compressibility of Guilkey Eq. 47,
    ///
    /// ```text
    /// κ_T = −(1/v)(∂v/∂p)_T = 1/(ρ (∂p/∂ρ)_T) .
    /// ```
    fn isothermal_compressibility(&self, rho: f64, t: f64) -> f64 {
        1.0 / (rho * self.dp_drho(rho, t))
    }

    /// Constant-pressure volumetric expansivity of Guilkey Eq. 48 (used in
    /// the specific-volume update, Guilkey Eq. 40),
    ///
    /// ```text
    /// β = (1/v)(∂v/∂T)_p = (∂p/∂T)_ρ / (ρ (∂p/∂ρ)_T) .
    /// ```
    fn thermal_expansivity(&self, rho: f64, t: f64) -> f64 {
        self.dp_dt(rho, t) / (rho * self.dp_drho(rho, t))
    }
}
