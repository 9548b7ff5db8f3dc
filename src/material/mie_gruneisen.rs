//! Mie–Grüneisen equation of state with a linear `U_s–u_p` Hugoniot
//! reference (water, metals), in the `(ρ, T)` form of the ICE caloric law
//! `e = c_v T` (see [`super::eos`]).
//!
//! # The `(ρ, e)` form (Lian Eq. 66)
//!
//! With the compression `η = 1 − ρ₀/ρ` (Lian writes `μ = ρ/ρ₀ − 1`, so
//! `η = μ/(1 + μ)`), the linear shock-velocity fit `U_s = c₀ + s u_p` gives
//! the principal Hugoniot centred on `(ρ₀, p₀, e₀)`
//!
//! ```text
//! p_H(η) = ρ₀ c₀² η / (1 − s η)²  ( = ρ₀ c₀² μ (1 + μ) / [1 − (s − 1) μ]², Lian Eq. 66)
//! e_H(η) = e₀ + (p_H + 2 p₀) η / (2 ρ₀)        (Rankine–Hugoniot energy jump)
//! ```
//!
//! and the Mie–Grüneisen form with `Γ ρ = Γ₀ ρ₀` (Lian's `γ = γ₀ ρ₀/ρ`)
//!
//! ```text
//! p = p₀ + p_H + Γ₀ ρ₀ (e − e_H)
//!   = p₀ + p_H (1 − Γ₀ η / 2) − Γ₀ p₀ η + Γ₀ ρ₀ (e − e₀)        (η ≥ 0)
//! ```
//!
//! which is Lian Eq. 66 (`p_H (1 − γ μ/2) + γ₀ E`, `E = ρ₀ e`) with the
//! reference state moved from `p = 0` to `p₀`. On the principal Hugoniot
//! (`e = e_H`) it gives exactly `p − p₀ = ρ₀ U_s u_p` with `η = u_p / U_s`.
//!
//! # The `(ρ, T)` form used here
//!
//! The ICE energy equation carries `e = c_v T` (a caloric temperature, see
//! [`super::eos`]); the energy reference is chosen so that the reference
//! state `(ρ₀, T₀)` has `p = p₀`, i.e. `e₀ = c_v T₀`:
//!
//! ```text
//! p(ρ, T) = p₀ + p_H(η) (1 − Γ₀ η / 2) − Γ₀ p₀ η + Γ₀ ρ₀ c_v (T − T₀)     (η ≥ 0)
//! ```
//!
//! **Tension branch** (`η < 0`, `ρ < ρ₀`): the Hugoniot has no meaning
//! there and `p_H` has a minimum at `η = −1/s` (it would fold back). Lian
//! Eq. 66 sets `p = 0`, which has no inverse `ρ(p, T)` for the
//! equilibration pressure of ICE. Here the reference curve is continued by
//! its tangent (the acoustic, LS-DYNA-style `p = ρ₀ c₀² μ` in tension) and
//! the Grüneisen coefficient is held at `Γ = Γ₀` (instead of `Γ₀ ρ₀/ρ`):
//!
//! ```text
//! p(ρ, T) = p₀ + K (ρ/ρ₀ − 1) + Γ₀ ρ c_v (T − T₀),   K = ρ₀ c₀² − Γ₀ p₀     (η < 0)
//! ```
//!
//! `p` and `(∂p/∂T)_ρ` are continuous at `ρ = ρ₀`, `(∂p/∂ρ)_T` is continuous
//! on the reference isotherm `T = T₀` (it jumps by `Γ₀ c_v (T − T₀)` off it).
//! This branch is linear in `ρ` at fixed `T`, so it inverts in closed form,
//! and its hyperbolic range `c² > 0` is `p > p_min = (p₀ − K)/(1 + Γ₀)` at
//! every temperature (water: about −1.5 GPa, far below any cavitation
//! pressure; there is no cavitation model, the fluid just stretches). Every
//! state with `p > p_min` has a density ([`EquationOfState::density`]).
//!
//! # Admissible parameters
//!
//! `ρ₀ > 0`, `c₀ > 0`, `1 ≤ s ≤ 4`, `0 ≤ Γ₀ < 2 s`, `c_v > 0`, `T₀ > 0`,
//! finite `p₀`, and `K − Γ₀ ρ₀ c_v T₀ > 0`:
//!
//! * `s ≥ 1`: with `s < 1` the Hugoniot pressure stays bounded as
//!   `ρ → ∞`, so strong shocks would have no state. The Hugoniot is
//!   singular at `η = 1/s` (`ρ/ρ₀ = s/(s − 1)`); `s ≤ 4` keeps that limit
//!   beyond `ρ/ρ₀ = 4/3` (measured linear fits: water 1.75–1.92, copper
//!   1.49, aluminium 1.34, iron 1.92).
//! * `Γ₀ < 2 s`: the reference isotherm then rises monotonically up to the
//!   singular compression (`d/dη [p_H (1 − Γ₀η/2)] = ρ₀ c₀² (1 + (s − Γ₀)η)
//!   / (1 − sη)³ > 0` on `0 ≤ η < 1/s`), so `density` has one root.
//! * `K > Γ₀ ρ₀ c_v T₀`: the tension isotherm `(∂p/∂ρ)_T = K/ρ₀ + Γ₀ c_v
//!   (T − T₀)` stays positive at every `T > 0`.

use super::equation_of_state::{
    check_gt, check_pressure, check_temperature, EosError, EquationOfState,
};

/// Largest admissible Hugoniot slope `s` (see the module notes).
pub const MAX_HUGONIOT_SLOPE: f64 = 4.0;

/// Mie–Grüneisen EOS with a linear `U_s–u_p` Hugoniot reference, `e = c_v T`
/// (module notes: Lian Eq. 66 and the tension branch).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MieGruneisen {
    rho0: f64,
    c0: f64,
    s: f64,
    gamma0: f64,
    cv: f64,
    t0: f64,
    p0: f64,
    /// `K = ρ₀ c₀² − Γ₀ p₀`: the isothermal `ρ (∂p/∂ρ)_T` at `(ρ₀, T₀)`.
    k: f64,
}

impl MieGruneisen {
    /// Creates the EOS from the reference density `ρ₀`, bulk sound speed
    /// `c₀`, Hugoniot slope `s`, Grüneisen coefficient `Γ₀`, specific heat
    /// `c_v`, and the reference temperature `T₀` and pressure `p₀` (the
    /// state `(ρ₀, T₀)` has `p = p₀`).
    ///
    /// # Errors
    ///
    /// [`EosError::Invalid`] naming the scene key of the first parameter
    /// outside the ranges of the module notes: `"reference_density"`,
    /// `"c0"`, `"s"`, `"gruneisen"`, `"cv"`, `"reference_temperature"` or
    /// `"reference_pressure"`.
    pub fn new(
        rho0: f64,
        c0: f64,
        s: f64,
        gamma0: f64,
        cv: f64,
        t0: f64,
        p0: f64,
    ) -> Result<Self, EosError> {
        let rho0 = check_gt("reference_density", "finite and > 0", rho0, 0.0)?;
        let c0 = check_gt("c0", "finite and > 0", c0, 0.0)?;
        if !(s.is_finite() && (1.0..=MAX_HUGONIOT_SLOPE).contains(&s)) {
            return Err(EosError::Invalid {
                field: "s",
                allowed: "in [1, 4] (s < 1 bounds the Hugoniot pressure; the Hugoniot is singular \
                          at rho/rho0 = s/(s - 1))",
                got: s,
            });
        }
        if !(gamma0.is_finite() && gamma0 >= 0.0 && gamma0 < 2.0 * s) {
            return Err(EosError::Invalid {
                field: "gruneisen",
                allowed: ">= 0 and < 2 s (a rising reference isotherm)",
                got: gamma0,
            });
        }
        let cv = check_gt("cv", "finite and > 0", cv, 0.0)?;
        let t0 = check_gt("reference_temperature", "finite and > 0", t0, 0.0)?;
        let k = rho0 * c0 * c0 - gamma0 * p0;
        if !(p0.is_finite() && k > 0.0) {
            return Err(EosError::Invalid {
                field: "reference_pressure",
                allowed: "finite and < rho0 c0^2 / gruneisen",
                got: p0,
            });
        }
        if k - gamma0 * rho0 * cv * t0 <= 0.0 {
            return Err(EosError::Invalid {
                field: "cv",
                allowed: "< (c0^2 - gruneisen p0/rho0) / (gruneisen T0) (a rising tension \
                          isotherm at every T > 0)",
                got: cv,
            });
        }
        Ok(Self {
            rho0,
            c0,
            s,
            gamma0,
            cv,
            t0,
            p0,
            k,
        })
    }

    /// Reference density `ρ₀`.
    pub fn reference_density(&self) -> f64 {
        self.rho0
    }

    /// Bulk sound speed `c₀` (the sound speed at the reference state).
    pub fn c0(&self) -> f64 {
        self.c0
    }

    /// Slope `s` of the `U_s–u_p` fit.
    pub fn s(&self) -> f64 {
        self.s
    }

    /// Grüneisen coefficient `Γ₀` at the reference density.
    pub fn gruneisen(&self) -> f64 {
        self.gamma0
    }

    /// Reference temperature `T₀`.
    pub fn reference_temperature(&self) -> f64 {
        self.t0
    }

    /// Reference pressure `p₀ = p(ρ₀, T₀)`.
    pub fn reference_pressure(&self) -> f64 {
        self.p0
    }

    /// Infimum of the admissible pressures, `(p₀ − K)/(1 + Γ₀)`: the
    /// hyperbolic (`c² > 0`) limit of the tension branch at every `T`.
    pub fn min_pressure(&self) -> f64 {
        (self.p0 - self.k) / (1.0 + self.gamma0)
    }

    /// Shock velocity `U_s = c₀ + s u_p` of the linear Hugoniot fit.
    pub fn shock_speed(&self, up: f64) -> f64 {
        self.c0 + self.s * up
    }

    /// The principal Hugoniot pressure `p_H(η) = ρ₀ c₀² η / (1 − s η)²`
    /// above `p₀` (Lian Eq. 66); `+∞` at and beyond the singular
    /// compression `η ≥ 1/s`.
    #[inline]
    pub fn hugoniot_pressure(&self, eta: f64) -> f64 {
        let w = 1.0 - self.s * eta;
        if w <= 0.0 {
            return f64::INFINITY;
        }
        self.rho0 * self.c0 * self.c0 * eta / (w * w)
    }

    /// The cold (reference-isotherm) part `G(η) = p_H (1 − Γ₀η/2) − Γ₀ p₀ η`
    /// of the compression branch and its derivative `dG/dη`.
    #[inline]
    fn cold(&self, eta: f64) -> (f64, f64) {
        let w = 1.0 - self.s * eta;
        if w <= 0.0 {
            return (f64::INFINITY, f64::INFINITY);
        }
        let r = self.rho0 * self.c0 * self.c0;
        let ph = r * eta / (w * w);
        let dph = r * (1.0 + self.s * eta) / (w * w * w);
        let g = 1.0 - 0.5 * self.gamma0 * eta;
        (
            ph * g - self.gamma0 * self.p0 * eta,
            dph * g - 0.5 * self.gamma0 * ph - self.gamma0 * self.p0,
        )
    }

    /// `Γ ρ c_v`: the isochoric slope `(∂p/∂T)_ρ` (`Γ₀ ρ₀ c_v` in
    /// compression, `Γ₀ ρ c_v` in tension).
    #[inline]
    fn thermal_slope(&self, rho: f64) -> f64 {
        self.gamma0 * rho.min(self.rho0) * self.cv
    }
}

impl EquationOfState for MieGruneisen {
    fn pressure(&self, rho: f64, t: f64) -> f64 {
        let thermal = self.thermal_slope(rho) * (t - self.t0);
        if rho >= self.rho0 {
            self.p0 + self.cold(1.0 - self.rho0 / rho).0 + thermal
        } else {
            // Tension branch (module notes).
            self.p0 + self.k * (rho / self.rho0 - 1.0) + thermal
        }
    }

    fn dp_drho(&self, rho: f64, t: f64) -> f64 {
        if rho >= self.rho0 {
            // dη/dρ = ρ₀/ρ².
            self.cold(1.0 - self.rho0 / rho).1 * self.rho0 / (rho * rho)
        } else {
            self.k / self.rho0 + self.gamma0 * self.cv * (t - self.t0)
        }
    }

    fn dp_dt(&self, rho: f64, _t: f64) -> f64 {
        self.thermal_slope(rho)
    }

    fn sound_speed_sq(&self, rho: f64, t: f64) -> f64 {
        // c² = (∂p/∂ρ)_T + (p/(ρ² c_v)) (∂p/∂T)_ρ for e = c_v T.
        self.dp_drho(rho, t)
            + self.pressure(rho, t) * self.thermal_slope(rho) / (rho * rho * self.cv)
    }

    fn density(&self, p: f64, t: f64) -> Result<f64, EosError> {
        let t = check_temperature(t)?;
        let p = check_pressure(p, self.min_pressure())?;
        let target = p - self.p0 - self.gamma0 * self.rho0 * self.cv * (t - self.t0);
        if target < 0.0 {
            // Tension branch: linear in ρ; its slope K/ρ₀ + Γ₀ c_v (T − T₀)
            // is positive for every T > 0 (validated in `new`).
            let slope = self.k / self.rho0 + self.gamma0 * self.cv * (t - self.t0);
            let rho = (p - self.p0 + self.k) / slope;
            return Ok(rho.min(self.rho0));
        }
        // Compression: G(η) = target on [0, 1/s), G increasing and convex
        // near the singularity; Newton safeguarded by bisection.
        let (mut lo, mut hi) = (0.0, 1.0 / self.s);
        let mut eta = (target / self.k).min(0.5 * hi);
        for _ in 0..200 {
            let (g, dg) = self.cold(eta);
            let f = g - target;
            if f == 0.0 {
                break;
            }
            if f > 0.0 {
                hi = eta;
            } else {
                lo = eta;
            }
            let mut next = eta - f / dg;
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            let done = (next - eta).abs() <= 2.0 * f64::EPSILON * next.abs()
                || hi - lo <= 2.0 * f64::EPSILON * hi;
            eta = next;
            if done {
                break;
            }
        }
        Ok(self.rho0 / (1.0 - eta))
    }

    fn specific_heat_cv(&self) -> f64 {
        self.cv
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Water: ρ₀ = 998 kg/m³, c₀ = 1483 m/s, s = 1.75 (the LASL shock
    /// Hugoniot fit quoted by Steinberg, UCRL-MA-106439, for water, with
    /// Γ₀ ≈ 0.5 there rounded here), c_v = 4180 J/(kg K), T₀ = 293 K.
    fn water() -> MieGruneisen {
        MieGruneisen::new(998.0, 1483.0, 1.75, 0.5, 4180.0, 293.0, 1.0e5).unwrap()
    }

    /// Copper (Steinberg: ρ₀ = 8930, c₀ = 3940, s = 1.49, Γ₀ = 2.02),
    /// c_v = 383 J/(kg K).
    fn copper() -> MieGruneisen {
        MieGruneisen::new(8930.0, 3940.0, 1.49, 2.02, 383.0, 300.0, 0.0).unwrap()
    }

    /// Compressions from strong tension to near the Hugoniot singularity.
    fn densities(m: &MieGruneisen) -> Vec<f64> {
        let rho_sing = m.rho0 * m.s / (m.s - 1.0);
        let mut v: Vec<f64> = [0.55, 0.7, 0.85, 0.95, 0.999, 1.0, 1.001, 1.01, 1.1]
            .iter()
            .map(|f| f * m.rho0)
            .collect();
        for f in [0.3, 0.6, 0.9, 0.98] {
            v.push(m.rho0 + f * (rho_sing - m.rho0));
        }
        v
    }

    #[test]
    fn reference_state_and_sound_speed() {
        for m in [water(), copper()] {
            assert_relative_eq!(
                m.pressure(m.rho0, m.t0),
                m.p0,
                max_relative = 1e-15,
                epsilon = 1e-6
            );
            assert_relative_eq!(
                m.sound_speed_sq(m.rho0, m.t0),
                m.c0 * m.c0,
                max_relative = 1e-14
            );
            assert_relative_eq!(m.density(m.p0, m.t0).unwrap(), m.rho0, max_relative = 1e-15);
        }
    }

    #[test]
    fn derivatives_match_central_differences() {
        for m in [water(), copper()] {
            for t in [50.0, m.t0, 900.0, 4000.0] {
                for rho in densities(&m) {
                    if (rho - m.rho0).abs() < 1e-3 * m.rho0 {
                        continue; // the branch switch (a kink off T₀)
                    }
                    let h = 1e-6 * rho;
                    let fd = (m.pressure(rho + h, t) - m.pressure(rho - h, t)) / (2.0 * h);
                    let d = m.dp_drho(rho, t);
                    assert!(
                        (d - fd).abs() <= 1e-7 * d.abs().max(m.k / m.rho0),
                        "ρ {rho} T {t}: {d} vs {fd}"
                    );
                    // p is linear in T: a wide difference only sees round-off.
                    let k = 0.5 * t;
                    let fd = (m.pressure(rho, t + k) - m.pressure(rho, t - k)) / (2.0 * k);
                    assert_relative_eq!(m.dp_dt(rho, t), fd, max_relative = 1e-7);
                }
            }
        }
    }

    #[test]
    fn sound_speed_is_the_isentropic_derivative() {
        // Slope of p along the isentrope de = (p/ρ²) dρ (RK4), both branches.
        for m in [water(), copper()] {
            for t in [m.t0, 1500.0] {
                for rho in densities(&m) {
                    if (rho - m.rho0).abs() < 1e-3 * m.rho0
                        || m.pressure(rho, t) <= m.min_pressure()
                    {
                        continue; // the branch switch; the non-hyperbolic range
                    }
                    let step = |h: f64| {
                        let rhs = |r: f64, e: f64| m.pressure(r, m.temperature(e)) / (r * r);
                        let e0 = m.internal_energy(t);
                        let k1 = rhs(rho, e0);
                        let k2 = rhs(rho + 0.5 * h, e0 + 0.5 * h * k1);
                        let k3 = rhs(rho + 0.5 * h, e0 + 0.5 * h * k2);
                        let k4 = rhs(rho + h, e0 + h * k3);
                        m.pressure(
                            rho + h,
                            m.temperature(e0 + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)),
                        )
                    };
                    let h = 1e-6 * rho;
                    let slope = (step(h) - step(-h)) / (2.0 * h);
                    let c2 = m.sound_speed_sq(rho, t);
                    assert!(c2 > 0.0);
                    assert!(
                        (c2 - slope).abs() <= 1e-7 * c2,
                        "ρ {rho} T {t}: {c2} vs {slope}"
                    );
                }
            }
        }
    }

    /// Round-off of `p(ρ)` at `ρ`: `ε (|p| + K + ρ ∂p/∂ρ)` (the last term is
    /// the conditioning of `p` in `ρ` near the Hugoniot singularity).
    fn round_off(m: &MieGruneisen, rho: f64, t: f64) -> f64 {
        f64::EPSILON * (m.pressure(rho, t).abs() + m.k + rho * m.dp_drho(rho, t))
    }

    #[test]
    fn density_inverts_pressure_in_compression_and_tension() {
        for m in [water(), copper()] {
            for t in [20.0, m.t0, 1200.0, 6000.0] {
                for rho in densities(&m) {
                    let p = m.pressure(rho, t);
                    if p <= m.min_pressure() {
                        continue;
                    }
                    let back = m.density(p, t).unwrap();
                    let pb = m.pressure(back, t);
                    assert!((pb - p).abs() <= 8.0 * round_off(&m, rho, t), "{p} vs {pb}");
                    // ρ to the round-off of p over the slope ∂p/∂ρ.
                    let tol = 8.0 * round_off(&m, rho, t) / m.dp_drho(rho, t);
                    assert!((back - rho).abs() <= tol, "{rho} {t}: {back}");
                }
            }
        }
    }

    #[test]
    fn density_covers_every_pressure_above_the_limit() {
        let m = water();
        let p_min = m.min_pressure();
        for t in [1.0, 293.0, 2000.0] {
            for p in [p_min * 0.999, p_min * 0.5, -1e6, 0.0, 1e8, 1e10, 1e12, 1e14] {
                let rho = m.density(p, t).unwrap();
                assert!(rho > 0.0 && rho.is_finite());
                assert!(m.sound_speed_sq(rho, t) > 0.0);
                assert!((m.pressure(rho, t) - p).abs() <= 8.0 * round_off(&m, rho, t));
            }
            assert!(matches!(
                m.density(p_min, t),
                Err(EosError::PressureOutOfRange { .. })
            ));
            assert!(m.density(f64::NAN, t).is_err());
        }
        assert!(m.density(1e5, 0.0).is_err());
    }

    #[test]
    fn principal_hugoniot_gives_rho0_us_up() {
        // On the Rankine–Hugoniot energy e − e₀ = (p + p₀)(1/ρ₀ − 1/ρ)/2 from
        // the reference state, p − p₀ = ρ₀ U_s u_p with U_s = c₀ + s u_p.
        for m in [water(), copper()] {
            for up in [10.0, 100.0, 500.0, 1000.0, 3000.0] {
                let us = m.shock_speed(up);
                let eta = up / us;
                let rho = m.rho0 / (1.0 - eta);
                let p_exact = m.p0 + m.rho0 * us * up;
                let e = m.internal_energy(m.t0) + 0.5 * (p_exact + m.p0) * eta / m.rho0;
                let p = m.pressure(rho, m.temperature(e));
                assert_relative_eq!(p, p_exact, max_relative = 1e-13);
                assert_relative_eq!(
                    m.hugoniot_pressure(eta),
                    m.rho0 * us * up,
                    max_relative = 1e-13
                );
            }
        }
    }

    #[test]
    fn lian_eq_66_form() {
        // With p₀ = 0 and e₀ = 0 the compression branch is Lian Eq. 66:
        // p = p_H (1 − γ μ/2) + γ₀ E, μ = ρ/ρ₀ − 1, γ = γ₀ ρ₀/ρ, E = ρ₀ e.
        let (rho0, c0, s, g0, cv) = (1000.0, 1647.0, 1.921, 0.1, 4180.0);
        let m = MieGruneisen::new(rho0, c0, s, g0, cv, 1.0, 0.0).unwrap();
        for (mu, t) in [(0.05, 300.0), (0.3, 1000.0)] {
            let rho = rho0 * (1.0 + mu);
            let ph = rho0 * c0 * c0 * mu * (1.0 + mu) / (1.0 - (s - 1.0) * mu).powi(2);
            let gamma = g0 * rho0 / rho;
            // e measured from e₀ = c_v T₀.
            let e = cv * (t - 1.0);
            let lian = ph * (1.0 - 0.5 * gamma * mu) + g0 * rho0 * e;
            assert_relative_eq!(m.pressure(rho, t), lian, max_relative = 1e-13);
        }
    }

    #[test]
    fn invalid_parameters_name_their_key() {
        let field = |r: Result<MieGruneisen, EosError>| match r.unwrap_err() {
            EosError::Invalid { field, .. } => field,
            e => panic!("{e:?}"),
        };
        let ok = (998.0, 1483.0, 1.75, 0.5, 4180.0, 293.0, 1.0e5);
        let mk = |v: [f64; 7]| MieGruneisen::new(v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
        let base = [ok.0, ok.1, ok.2, ok.3, ok.4, ok.5, ok.6];
        for (i, bad, name) in [
            (0, 0.0, "reference_density"),
            (0, -1.0, "reference_density"),
            (1, 0.0, "c0"),
            (1, f64::NAN, "c0"),
            (2, -0.5, "s"),
            (2, 0.9, "s"),
            (2, 4.5, "s"),
            (3, -0.1, "gruneisen"),
            (3, 3.5, "gruneisen"),
            (4, 0.0, "cv"),
            (4, 1.0e5, "cv"),
            (5, 0.0, "reference_temperature"),
            (6, f64::INFINITY, "reference_pressure"),
            (6, 1.0e10, "reference_pressure"),
        ] {
            let mut v = base;
            v[i] = bad;
            assert_eq!(field(mk(v)), name, "{i} = {bad}");
        }
        assert!(mk(base).is_ok());
    }
}
