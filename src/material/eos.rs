//! Equations of state (EOS) for the Eulerian (ICE) fluid materials.
//!
//! Every fluid material of the multifield model needs two closure relations
//! (Guilkey et al., Sec. 2.1):
//!
//! * the caloric EOS `e_r = e_r(v_r, T_r)` (Guilkey Eq. 10), and
//! * the thermal EOS `v_r = v_r(p, T_r)`, i.e. `ρ_r = ρ_r(p, T_r)`
//!   (Guilkey Eq. 11).
//!
//! The equilibration pressure solve of the multifield EOS
//! `0 = 1 − Σ_s ρ_s v_s` (Guilkey Eq. 13) is a per-cell Newton iteration on
//! `p` which needs, per material, the specific volume at `(p, T)` — that is
//! [`EquationOfState::density`] — and its pressure derivative
//! `(∂v/∂p)_T = −v/(ρ (∂p/∂ρ)_T)`, i.e. [`EquationOfState::dp_drho`]. The
//! pressure increment of the Lagrangian phase (Guilkey Eq. 29)
//!
//! ```text
//! Δp = Δt (Σ_r v_r Γ_r − Σ_r ∇·(θ u*)_r) / Σ_r (θ κ)_r
//! ```
//!
//! needs the bulk compressibility `κ_r`, which is
//! [`EquationOfState::compressibility`]. The specific-volume evolution
//! (Guilkey Eqs. 40, 48) additionally needs the volumetric expansivity `β_r`,
//! [`EquationOfState::thermal_expansivity`].
//!
//! # Which compressibility `κ`
//!
//! The Appendix (Guilkey Eq. 47) *defines* `κ_r = −(1/v)(∂v/∂p)_T`, the
//! isothermal compressibility, and derives the pressure rate equation
//! (Guilkey Eq. 51)
//!
//! ```text
//! κ Dp/Dt = −∇·u + Σ_s θ_s β_s D_s T_s/Dt .
//! ```
//!
//! The discrete update actually used, Guilkey Eq. 29, drops the
//! `θ β DT/Dt` term. During the Lagrangian phase a fluid parcel is compressed
//! adiabatically (the only energy source is the flow work of Guilkey Eq. 34),
//! so `DT/Dt` is itself proportional to `Dp/Dt`; substituting the isentropic
//! temperature change into `Dv/Dt = v(−κ_T Dp/Dt + β DT/Dt)` (Guilkey Eq. 46)
//! gives `Dv/Dt = −v κ_s Dp/Dt` with the *isentropic* compressibility
//!
//! ```text
//! κ_s = 1/(ρ c²),   c² = (∂p/∂ρ)_s .
//! ```
//!
//! Eq. 29 without the temperature term is therefore consistent only with
//! `κ = κ_s`; using `κ_T` would propagate pressure waves at the isothermal
//! (Newton) speed `√((∂p/∂ρ)_T)` instead of the true sound speed (a factor
//! `√γ` too slow for air). [`EquationOfState::compressibility`] returns
//! `κ_s`; the isothermal `κ_T = 1/(ρ (∂p/∂ρ)_T)` of Guilkey Eq. 47 is
//! available as [`EquationOfState::isothermal_compressibility`] for code that
//! keeps the `β DT/Dt` terms explicitly.
//!
//! # Energy convention
//!
//! The ICE energy equation carries the specific internal energy with the
//! caloric EOS `e = c_v T` (constant specific heat, Guilkey Appendix: "ideal
//! materials with constant specific heats are assumed"), and changes it by
//! the flow work `de = −p dv` (Guilkey Eqs. 9, 34). Both EOS here use exactly
//! that caloric relation, so the isentrope followed by the discrete energy
//! equation is the one whose sound speed [`EquationOfState::sound_speed_sq`]
//! reports:
//!
//! ```text
//! c² = (∂p/∂ρ)_T + (p/(ρ² c_v)) (∂p/∂T)_ρ      (because de = c_v dT = (p/ρ²) dρ)
//! ```
//!
//! See [`StiffenedGas`] for why this fixes the stiffened-gas form.

use super::equation_of_state::{check_gt, check_pressure, check_temperature};
pub use super::equation_of_state::{EosError, EquationOfState};
pub use super::jwl::Jwl;
pub use super::mie_gruneisen::MieGruneisen;
pub use super::solid_eos::SolidEos;

/// Calorically perfect (ideal) gas.
///
/// ```text
/// p = (γ − 1) ρ c_v T = (γ − 1) ρ e,     e = c_v T,
/// (∂p/∂ρ)_T = (γ − 1) c_v T,   (∂p/∂T)_ρ = (γ − 1) ρ c_v,
/// c² = γ p / ρ = γ (γ − 1) c_v T,
/// ρ(p, T) = p / ((γ − 1) c_v T),
/// κ_s = 1/(γ p),   κ_T = 1/p,   β = 1/T .
/// ```
///
/// The specific gas constant is `R = (γ − 1) c_v` (air: `γ = 1.4`,
/// `c_v = 717.5`, `R = 287`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdealGas {
    gamma: f64,
    cv: f64,
}

impl IdealGas {
    /// Creates an ideal gas with ratio of specific heats `γ` and specific
    /// heat `c_v`.
    ///
    /// # Errors
    ///
    /// [`EosError::Invalid`] naming `"gamma"` unless `γ` is finite and
    /// `> 1`, or naming `"cv"` unless `c_v` is finite and `> 0`.
    pub fn new(gamma: f64, cv: f64) -> Result<Self, EosError> {
        let gamma = check_gt("gamma", "finite and > 1", gamma, 1.0)?;
        let cv = check_gt("cv", "finite and > 0", cv, 0.0)?;
        Ok(Self { gamma, cv })
    }

    /// Ratio of specific heats `γ = c_p / c_v`.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// Specific heat at constant volume `c_v`.
    pub fn cv(&self) -> f64 {
        self.cv
    }

    /// Specific gas constant `R = (γ − 1) c_v`.
    pub fn gas_constant(&self) -> f64 {
        (self.gamma - 1.0) * self.cv
    }
}

impl EquationOfState for IdealGas {
    fn pressure(&self, rho: f64, t: f64) -> f64 {
        (self.gamma - 1.0) * rho * self.cv * t
    }

    fn dp_drho(&self, _rho: f64, t: f64) -> f64 {
        (self.gamma - 1.0) * self.cv * t
    }

    fn dp_dt(&self, rho: f64, _t: f64) -> f64 {
        (self.gamma - 1.0) * rho * self.cv
    }

    fn sound_speed_sq(&self, _rho: f64, t: f64) -> f64 {
        // c² = γ p/ρ = γ (γ − 1) c_v T
        self.gamma * (self.gamma - 1.0) * self.cv * t
    }

    fn density(&self, p: f64, t: f64) -> Result<f64, EosError> {
        let t = check_temperature(t)?;
        let p = check_pressure(p, 0.0)?;
        Ok(p / ((self.gamma - 1.0) * self.cv * t))
    }

    fn specific_heat_cv(&self) -> f64 {
        self.cv
    }
}

/// Stiffened gas for liquids (water, ...), in the form consistent with the
/// ICE caloric EOS `e = c_v T`.
///
/// The stiffened gas is the Mie–Grüneisen EOS with a constant Grüneisen
/// coefficient `γ − 1` and a constant "stiffening" pressure `p_∞`:
///
/// ```text
/// p = (γ − 1) ρ e − γ p_∞                           (e form)
/// ```
///
/// Two temperature closures are in use for this `p(ρ, e)`:
///
/// 1. `e = c_v T + p_∞/ρ`, which gives the often quoted temperature form
///    `p = (γ − 1) ρ c_v T − p_∞` and is thermodynamically complete (a
///    Helmholtz energy exists).
/// 2. `e = c_v T`, which gives
///
///    ```text
///    p = (γ − 1) ρ c_v T − γ p_∞                    (T form, used here)
///    ```
///
/// **This type implements form 2.** The ICE energy equation (Guilkey Eqs. 9,
/// 34, 39) evolves `e = c_v T` with the flow work `−p dv`, and the trait's
/// caloric relation ([`EquationOfState::internal_energy`]) is `e = c_v T`.
/// With form 2 that isentrope has exactly the stiffened-gas sound speed
///
/// ```text
/// c² = (∂p/∂ρ)_T + (p/(ρ² c_v)) (∂p/∂T)_ρ
///    = (γ − 1) c_v T + (γ − 1) p/ρ = γ (p + p_∞)/ρ ,
/// ```
///
/// which is the `c` that enters `κ_s = 1/(ρ c²)` in Guilkey Eq. 29, so the
/// pressure-increment step and the following equilibration (Guilkey Eq. 13)
/// see the same stiffness. Pairing form 1's pressure with `e = c_v T` would
/// instead follow `c² = (γ p + p_∞)/ρ` (water: ≈ 775 m/s instead of
/// ≈ 1625 m/s) while Eq. 29 used `γ (p + p_∞)/ρ`. The price of form 2 is that
/// `T = e/c_v` is a caloric ("ICE") temperature rather than the
/// thermodynamic one, so `c_v` is a fitted parameter: pick it so that a
/// reference state `(ρ₀, p₀, T₀)` satisfies the EOS, see
/// [`StiffenedGas::from_reference_state`].
///
/// Other relations:
///
/// ```text
/// (∂p/∂ρ)_T = (γ − 1) c_v T,    (∂p/∂T)_ρ = (γ − 1) ρ c_v,
/// ρ(p, T)   = (p + γ p_∞) / ((γ − 1) c_v T),
/// κ_s = 1/(γ (p + p_∞)),   κ_T = 1/(p + γ p_∞),   β = 1/T .
/// ```
///
/// Admissible range: `p > −p_∞` (equivalently `c² > 0`). The algebra above
/// also returns a positive density for `−γ p_∞ < p ≤ −p_∞`, but those states
/// are not hyperbolic, so [`EquationOfState::density`] rejects them. With
/// `p_∞ = 0` this reduces to [`IdealGas`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StiffenedGas {
    gamma: f64,
    p_inf: f64,
    cv: f64,
}

impl StiffenedGas {
    /// Creates a stiffened gas with Grüneisen exponent `γ`, stiffening
    /// pressure `p_∞` and specific heat `c_v`.
    ///
    /// # Errors
    ///
    /// [`EosError::Invalid`] naming `"gamma"` unless `γ` is finite and
    /// `> 1`, `"p_inf"` unless `p_∞` is finite and `≥ 0`, or `"cv"` unless
    /// `c_v` is finite and `> 0`.
    pub fn new(gamma: f64, p_inf: f64, cv: f64) -> Result<Self, EosError> {
        let gamma = check_gt("gamma", "finite and > 1", gamma, 1.0)?;
        if !(p_inf.is_finite() && p_inf >= 0.0) {
            return Err(EosError::Invalid {
                field: "p_inf",
                allowed: "finite and >= 0",
                got: p_inf,
            });
        }
        let cv = check_gt("cv", "finite and > 0", cv, 0.0)?;
        Ok(Self { gamma, p_inf, cv })
    }

    /// Creates a stiffened gas whose `c_v` is fitted so that the reference
    /// state `(ρ₀, p₀, T₀)` lies on the EOS:
    ///
    /// ```text
    /// c_v = (p₀ + γ p_∞) / ((γ − 1) ρ₀ T₀) .
    /// ```
    ///
    /// # Errors
    ///
    /// [`EosError::Invalid`] for invalid `γ` or `p_∞` (as in
    /// [`StiffenedGas::new`]), a non-finite or non-positive `ρ₀`
    /// (`"rho0"`) or `T₀` (`"temperature"`), a non-finite `p₀`
    /// (`"pressure"`); [`EosError::PressureOutOfRange`] for `p₀ ≤ −p_∞`.
    pub fn from_reference_state(
        gamma: f64,
        p_inf: f64,
        rho0: f64,
        p0: f64,
        t0: f64,
    ) -> Result<Self, EosError> {
        // Validate γ and p_∞ first with a placeholder c_v.
        let probe = Self::new(gamma, p_inf, 1.0)?;
        let rho0 = check_gt("rho0", "finite and > 0", rho0, 0.0)?;
        let t0 = check_temperature(t0)?;
        check_pressure(p0, -probe.p_inf)?;
        let cv = (p0 + gamma * p_inf) / ((gamma - 1.0) * rho0 * t0);
        Self::new(gamma, p_inf, cv)
    }

    /// Grüneisen exponent `γ`.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// Stiffening pressure `p_∞`.
    pub fn p_inf(&self) -> f64 {
        self.p_inf
    }

    /// Specific heat at constant volume `c_v` (caloric, see the type docs).
    pub fn cv(&self) -> f64 {
        self.cv
    }

    /// Pressure from the e form `p = (γ − 1) ρ e − γ p_∞`; identical to
    /// [`EquationOfState::pressure`] at `e = c_v T`.
    pub fn pressure_from_energy(&self, rho: f64, e: f64) -> f64 {
        (self.gamma - 1.0) * rho * e - self.gamma * self.p_inf
    }
}

impl EquationOfState for StiffenedGas {
    fn pressure(&self, rho: f64, t: f64) -> f64 {
        (self.gamma - 1.0) * rho * self.cv * t - self.gamma * self.p_inf
    }

    fn dp_drho(&self, _rho: f64, t: f64) -> f64 {
        (self.gamma - 1.0) * self.cv * t
    }

    fn dp_dt(&self, rho: f64, _t: f64) -> f64 {
        (self.gamma - 1.0) * rho * self.cv
    }

    fn sound_speed_sq(&self, rho: f64, t: f64) -> f64 {
        // c² = γ (p + p_∞)/ρ = γ (γ − 1) c_v T − γ (γ − 1) p_∞/ρ,
        // written without forming p to avoid cancellation in p + p_∞.
        self.gamma * (self.gamma - 1.0) * (self.cv * t - self.p_inf / rho)
    }

    fn density(&self, p: f64, t: f64) -> Result<f64, EosError> {
        let t = check_temperature(t)?;
        let p = check_pressure(p, -self.p_inf)?;
        Ok((p + self.gamma * self.p_inf) / ((self.gamma - 1.0) * self.cv * t))
    }

    fn specific_heat_cv(&self) -> f64 {
        self.cv
    }
}

/// Closed set of fluid EOS, dispatched with a `match` so that per-cell loops
/// over one material are monomorphic and inlinable (no virtual calls).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FluidEos {
    /// [`IdealGas`]: `p = (γ − 1) ρ c_v T`.
    IdealGas(IdealGas),
    /// [`StiffenedGas`]: `p = (γ − 1) ρ c_v T − γ p_∞`.
    StiffenedGas(StiffenedGas),
    /// [`SolidEos`]: the bulk response of a solid material in the cells of
    /// a coupled MPM-ICE scene (Guilkey Fig. 1).
    Solid(SolidEos),
    /// [`MieGruneisen`]: linear `U_s–u_p` Hugoniot reference (Lian Eq. 66).
    MieGruneisen(MieGruneisen),
    /// [`Jwl`]: Jones–Wilkins–Lee detonation products.
    Jwl(Jwl),
}

impl FluidEos {
    /// Short stable identifier of the variant: `"ideal_gas"`,
    /// `"stiffened_gas"`, `"solid"`, `"mie_gruneisen"` or `"jwl"`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::IdealGas(_) => "ideal_gas",
            Self::StiffenedGas(_) => "stiffened_gas",
            Self::Solid(_) => "solid",
            Self::MieGruneisen(_) => "mie_gruneisen",
            Self::Jwl(_) => "jwl",
        }
    }

    /// Lowest admissible pressure (exclusive), the same at every
    /// temperature: `0` for an ideal gas, JWL products and the solid's
    /// threshold law (Guilkey Fig. 1), `−p_∞` for a stiffened gas,
    /// [`MieGruneisen::min_pressure`] for Mie–Grüneisen. Above it
    /// [`EquationOfState::density`] has a root at every `T > 0` (JWL: up to
    /// the maximum of its isotherm).
    pub fn min_pressure(&self) -> f64 {
        match self {
            Self::IdealGas(_) | Self::Solid(_) | Self::Jwl(_) => 0.0,
            Self::StiffenedGas(s) => -s.p_inf(),
            Self::MieGruneisen(m) => m.min_pressure(),
        }
    }
}

impl From<IdealGas> for FluidEos {
    fn from(eos: IdealGas) -> Self {
        Self::IdealGas(eos)
    }
}

impl From<SolidEos> for FluidEos {
    fn from(eos: SolidEos) -> Self {
        Self::Solid(eos)
    }
}

impl From<MieGruneisen> for FluidEos {
    fn from(eos: MieGruneisen) -> Self {
        Self::MieGruneisen(eos)
    }
}

impl From<Jwl> for FluidEos {
    fn from(eos: Jwl) -> Self {
        Self::Jwl(eos)
    }
}

impl From<StiffenedGas> for FluidEos {
    fn from(eos: StiffenedGas) -> Self {
        Self::StiffenedGas(eos)
    }
}

/// Forwards a trait method to the wrapped EOS.
macro_rules! dispatch {
    ($self:ident, $eos:ident => $call:expr) => {
        match $self {
            FluidEos::IdealGas($eos) => $call,
            FluidEos::StiffenedGas($eos) => $call,
            FluidEos::Solid($eos) => $call,
            FluidEos::MieGruneisen($eos) => $call,
            FluidEos::Jwl($eos) => $call,
        }
    };
}

impl EquationOfState for FluidEos {
    #[inline]
    fn pressure(&self, rho: f64, t: f64) -> f64 {
        dispatch!(self, eos => eos.pressure(rho, t))
    }

    #[inline]
    fn dp_drho(&self, rho: f64, t: f64) -> f64 {
        dispatch!(self, eos => eos.dp_drho(rho, t))
    }

    #[inline]
    fn dp_dt(&self, rho: f64, t: f64) -> f64 {
        dispatch!(self, eos => eos.dp_dt(rho, t))
    }

    #[inline]
    fn sound_speed_sq(&self, rho: f64, t: f64) -> f64 {
        dispatch!(self, eos => eos.sound_speed_sq(rho, t))
    }

    #[inline]
    fn density(&self, p: f64, t: f64) -> Result<f64, EosError> {
        dispatch!(self, eos => eos.density(p, t))
    }

    #[inline]
    fn specific_heat_cv(&self) -> f64 {
        dispatch!(self, eos => eos.specific_heat_cv())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn air() -> IdealGas {
        IdealGas::new(1.4, 717.5).unwrap()
    }

    /// Water-like stiffened gas fitted to (1000 kg/m³, 1e5 Pa, 300 K).
    fn water() -> StiffenedGas {
        StiffenedGas::from_reference_state(4.4, 6.0e8, 1000.0, 1.0e5, 300.0).unwrap()
    }

    fn all_eos() -> Vec<FluidEos> {
        vec![
            air().into(),
            water().into(),
            IdealGas::new(5.0 / 3.0, 3115.6).unwrap().into(),
            StiffenedGas::new(2.35, 1.0e9, 1816.0).unwrap().into(),
        ]
    }

    /// Logarithmically spaced samples in `[lo, hi]`.
    fn logspace(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f64> {
        (0..n).map(move |i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
    }

    /// `γ p_∞` (zero for an ideal gas) and `p_∞`.
    fn stiffening(eos: &FluidEos) -> (f64, f64) {
        match eos {
            FluidEos::IdealGas(_) => (0.0, 0.0),
            FluidEos::StiffenedGas(sg) => (sg.gamma() * sg.p_inf(), sg.p_inf()),
            _ => unreachable!("ideal and stiffened gases only in these tests"),
        }
    }

    #[test]
    fn density_pressure_round_trip() {
        for eos in all_eos() {
            let (gamma_p_inf, p_inf) = stiffening(&eos);
            for t in logspace(1.0, 1.0e4, 13) {
                // Pressures from deep tension (−0.999 p_∞) to 1e12 Pa.
                let pressures = logspace(1.0e-3, 1.0e12, 31)
                    .chain(logspace(1.0e-3, 0.999, 7).map(|f| -f * p_inf))
                    .filter(|&p| p > -p_inf);
                for p in pressures {
                    let rho = eos.density(p, t).unwrap();
                    assert!(rho > 0.0 && rho.is_finite());
                    let back = eos.pressure(rho, t);
                    // Relative to the stiffened pressure scale |p| + γ p_∞ (exactly
                    // |p| for an ideal gas): ρ carries ~1 ulp of relative error, so
                    // p + γ p_∞ cannot be recovered better than that.
                    let scale = p.abs() + gamma_p_inf;
                    assert!(
                        (back - p).abs() <= 1e-14 * scale,
                        "{}: p = {p}, T = {t}, back = {back}",
                        eos.name()
                    );
                }
            }
        }
    }

    #[test]
    fn ideal_gas_round_trip_is_relative_1e14() {
        let eos = air();
        for t in logspace(10.0, 5.0e3, 9) {
            for p in logspace(1.0e-6, 1.0e12, 37) {
                let back = eos.pressure(eos.density(p, t).unwrap(), t);
                assert_relative_eq!(back, p, max_relative = 1e-14);
            }
        }
    }

    #[test]
    fn derivatives_match_central_differences() {
        for eos in all_eos() {
            for &(p, t) in &[(1.0e5, 300.0), (3.0e7, 1200.0), (2.0e3, 50.0)] {
                let rho = eos.density(p, t).unwrap();
                let h = 1e-6 * rho;
                let fd_rho = (eos.pressure(rho + h, t) - eos.pressure(rho - h, t)) / (2.0 * h);
                let k = 1e-6 * t;
                let fd_t = (eos.pressure(rho, t + k) - eos.pressure(rho, t - k)) / (2.0 * k);
                // Both EOS are linear in ρ and T, so only round-off remains; it is
                // amplified by (|p| + γ p_∞)/(h ∂p/∂ρ).
                assert_relative_eq!(eos.dp_drho(rho, t), fd_rho, max_relative = 1e-6);
                assert_relative_eq!(eos.dp_dt(rho, t), fd_t, max_relative = 1e-6);
            }
        }
    }

    #[test]
    fn sound_speed_is_the_isentropic_derivative() {
        // c² = (∂p/∂ρ)_T + p/(ρ² c_v) (∂p/∂T)_ρ for e = c_v T, and it must equal
        // the numerical slope of p along the isentrope de = (p/ρ²) dρ.
        for eos in all_eos() {
            let cv = eos.specific_heat_cv();
            for &(p, t) in &[(1.0e5, 300.0), (3.0e7, 1200.0)] {
                let rho = eos.density(p, t).unwrap();
                let identity = eos.dp_drho(rho, t) + p / (rho * rho * cv) * eos.dp_dt(rho, t);
                assert_relative_eq!(eos.sound_speed_sq(rho, t), identity, max_relative = 1e-10);

                // Integrate the isentrope ± h with RK4 in (ρ, e).
                let step = |h: f64| {
                    let rhs = |r: f64, e: f64| eos.pressure(r, eos.temperature(e)) / (r * r);
                    let e0 = eos.internal_energy(t);
                    let k1 = rhs(rho, e0);
                    let k2 = rhs(rho + 0.5 * h, e0 + 0.5 * h * k1);
                    let k3 = rhs(rho + 0.5 * h, e0 + 0.5 * h * k2);
                    let k4 = rhs(rho + h, e0 + h * k3);
                    let e1 = e0 + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
                    eos.pressure(rho + h, eos.temperature(e1))
                };
                let h = 1e-5 * rho;
                let slope = (step(h) - step(-h)) / (2.0 * h);
                assert_relative_eq!(eos.sound_speed_sq(rho, t), slope, max_relative = 1e-5);
            }
        }
    }

    #[test]
    fn air_sound_speed_at_300_k() {
        let eos = air();
        assert_relative_eq!(eos.gas_constant(), 287.0, max_relative = 1e-15);
        let c = eos.sound_speed(1.2, 300.0);
        assert!((c - 347.2).abs() < 0.05, "c = {c}");
        assert_relative_eq!(
            c * c,
            1.4 * eos.pressure(1.2, 300.0) / 1.2,
            max_relative = 1e-14
        );
    }

    #[test]
    fn water_sound_speed() {
        let eos = water();
        let rho = eos.density(1.0e5, 300.0).unwrap();
        assert_relative_eq!(rho, 1000.0, max_relative = 1e-14);
        let c = eos.sound_speed(rho, 300.0);
        // √(4.4 × (1e5 + 6e8) / 1000) = 1624.93 m/s
        assert!((c - 1625.0).abs() < 0.5, "c = {c}");
        assert_relative_eq!(c * c, 4.4 * (1.0e5 + 6.0e8) / 1000.0, max_relative = 1e-12);
        // e form p = (γ − 1) ρ e − γ p_∞ agrees with the T form at e = c_v T.
        assert_relative_eq!(
            eos.pressure_from_energy(rho, eos.internal_energy(300.0)),
            1.0e5,
            max_relative = 1e-9
        );
    }

    #[test]
    fn compressibilities() {
        let eos = air();
        let (rho, t) = (1.2, 300.0);
        let p = eos.pressure(rho, t);
        assert_relative_eq!(
            eos.compressibility(rho, t),
            1.0 / (1.4 * p),
            max_relative = 1e-14
        );
        assert_relative_eq!(
            eos.isothermal_compressibility(rho, t),
            1.0 / p,
            max_relative = 1e-14
        );
        assert_relative_eq!(
            eos.thermal_expansivity(rho, t),
            1.0 / t,
            max_relative = 1e-14
        );

        let w = water();
        let rho = w.density(1.0e5, 300.0).unwrap();
        assert_relative_eq!(
            w.compressibility(rho, 300.0),
            1.0 / (4.4 * (1.0e5 + 6.0e8)),
            max_relative = 1e-12
        );
        assert_relative_eq!(
            w.isothermal_compressibility(rho, 300.0),
            1.0 / (1.0e5 + 4.4 * 6.0e8),
            max_relative = 1e-12
        );
        assert_relative_eq!(
            w.thermal_expansivity(rho, 300.0),
            1.0 / 300.0,
            max_relative = 1e-14
        );
    }

    #[test]
    fn energy_temperature_round_trip() {
        for eos in all_eos() {
            for t in logspace(1.0, 1.0e4, 9) {
                let e = eos.internal_energy(t);
                assert_relative_eq!(e, eos.specific_heat_cv() * t, max_relative = 1e-15);
                assert_relative_eq!(eos.temperature(e), t, max_relative = 1e-15);
            }
        }
    }

    #[test]
    fn enum_dispatch_matches_concrete_types() {
        let a = air();
        let w = water();
        let fa = FluidEos::from(a);
        let fw = FluidEos::from(w);
        assert_eq!(fa.name(), "ideal_gas");
        assert_eq!(fw.name(), "stiffened_gas");
        let (rho, t) = (3.0, 450.0);
        assert_eq!(fa.pressure(rho, t), a.pressure(rho, t));
        assert_eq!(fa.sound_speed_sq(rho, t), a.sound_speed_sq(rho, t));
        assert_eq!(fw.pressure(1000.0, t), w.pressure(1000.0, t));
        assert_eq!(fw.dp_dt(1000.0, t), w.dp_dt(1000.0, t));
        assert_eq!(fw.density(2e5, t), w.density(2e5, t));
        // Usable as a trait object too.
        let boxed: Box<dyn EquationOfState> = Box::new(fw);
        assert_eq!(boxed.specific_heat_cv(), w.cv());
    }

    #[test]
    fn stiffened_gas_with_zero_p_inf_is_ideal_gas() {
        let sg = StiffenedGas::new(1.4, 0.0, 717.5).unwrap();
        let ig = air();
        for &(rho, t) in &[(1.2, 300.0), (0.01, 5000.0)] {
            assert_relative_eq!(
                sg.pressure(rho, t),
                ig.pressure(rho, t),
                max_relative = 1e-15
            );
            assert_relative_eq!(
                sg.sound_speed_sq(rho, t),
                ig.sound_speed_sq(rho, t),
                max_relative = 1e-15
            );
        }
    }

    fn invalid_field(err: EosError) -> &'static str {
        match err {
            EosError::Invalid { field, .. } => field,
            other => panic!("expected EosError::Invalid, got {other:?}"),
        }
    }

    #[test]
    fn invalid_parameters_are_rejected_with_field_name() {
        for g in [1.0, 0.5, -2.0, f64::NAN, f64::INFINITY] {
            assert_eq!(invalid_field(IdealGas::new(g, 717.5).unwrap_err()), "gamma");
            assert_eq!(
                invalid_field(StiffenedGas::new(g, 6e8, 1.0).unwrap_err()),
                "gamma"
            );
        }
        for cv in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(invalid_field(IdealGas::new(1.4, cv).unwrap_err()), "cv");
            assert_eq!(
                invalid_field(StiffenedGas::new(4.4, 6e8, cv).unwrap_err()),
                "cv"
            );
        }
        for p_inf in [-1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(
                invalid_field(StiffenedGas::new(4.4, p_inf, 1.0).unwrap_err()),
                "p_inf"
            );
        }
        let err = IdealGas::new(1.0, 717.5).unwrap_err();
        assert_eq!(
            err,
            EosError::Invalid {
                field: "gamma",
                allowed: "finite and > 1",
                got: 1.0
            }
        );
        assert!(err.to_string().contains("gamma"));
        assert_eq!(
            invalid_field(
                StiffenedGas::from_reference_state(4.4, 6e8, 0.0, 1e5, 300.0).unwrap_err()
            ),
            "rho0"
        );
    }

    #[test]
    fn density_rejects_unreachable_pressure_and_bad_temperature() {
        let a = air();
        assert_eq!(
            a.density(0.0, 300.0),
            Err(EosError::PressureOutOfRange { p: 0.0, p_min: 0.0 })
        );
        assert!(matches!(
            a.density(-5.0, 300.0),
            Err(EosError::PressureOutOfRange { .. })
        ));
        assert_eq!(
            invalid_field(a.density(1e5, 0.0).unwrap_err()),
            "temperature"
        );
        assert_eq!(
            invalid_field(a.density(1e5, -3.0).unwrap_err()),
            "temperature"
        );
        assert_eq!(
            invalid_field(a.density(1e5, f64::NAN).unwrap_err()),
            "temperature"
        );
        assert_eq!(
            invalid_field(a.density(f64::NAN, 300.0).unwrap_err()),
            "pressure"
        );

        let w = water();
        assert!(w.density(-5.0e8, 300.0).is_ok());
        assert_eq!(
            w.density(-6.0e8, 300.0),
            Err(EosError::PressureOutOfRange {
                p: -6.0e8,
                p_min: -6.0e8
            })
        );
        assert!(matches!(
            w.density(-1.0e9, 300.0),
            Err(EosError::PressureOutOfRange { .. })
        ));
        assert_eq!(
            invalid_field(w.density(1e5, 0.0).unwrap_err()),
            "temperature"
        );
        let fe = FluidEos::from(w);
        assert!(fe.density(-7.0e8, 300.0).is_err());
    }
}
