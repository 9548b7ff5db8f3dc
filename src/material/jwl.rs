//! Jones–Wilkins–Lee (JWL) equation of state for detonation products, in
//! the `(ρ, T)` form of the ICE caloric law `e = c_v T` (see
//! [`super::eos`]).
//!
//! With the relative volume `V = ρ₀/ρ` (`ρ₀` the density of the unreacted
//! explosive) and the specific internal energy `e`,
//!
//! ```text
//! p = A (1 − ω/(R₁V)) e^(−R₁V) + B (1 − ω/(R₂V)) e^(−R₂V) + ω ρ e
//! ```
//!
//! (the usual form with `ω E/V`, `E = ρ₀ e` the energy per initial volume).
//! Here `e = c_v T`, with `e = 0` at `T = 0` (the JWL's own energy
//! reference: the energy released by the detonation is part of `e`), so
//!
//! ```text
//! p(ρ, T) = p_c(V) + ω ρ c_v T,
//! (∂p/∂ρ)_T = −(V/ρ) p_c′(V) + ω c_v T,   (∂p/∂T)_ρ = ω ρ c_v,
//! p_c′(V) = Σ_i A_i e^(−R_i V) (ω/(R_i V²) + ω/V − R_i),
//! c² = (∂p/∂ρ)_T + ω p/ρ .
//! ```
//!
//! As `ρ → 0` the exponentials vanish and the products become the ideal gas
//! `p = ω ρ c_v T` (`γ = 1 + ω`), so the admissible pressures are `p > 0`.
//! At extreme compression (`V < ω/R_i`) the cold terms turn negative and the
//! isotherm has a maximum; [`EquationOfState::density`] reports a pressure
//! above it as out of range.
//!
//! Admissible parameters: finite `A`, `B`; `R₁, R₂, ω, ρ₀, c_v, T₀ > 0`,
//! and a positive pressure at the reference state, `p(ρ₀, T₀) > 0`.

use super::equation_of_state::{
    check_gt, check_pressure, check_temperature, EosError, EquationOfState,
};

/// The JWL detonation-products EOS with `e = c_v T` (module notes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jwl {
    a: f64,
    b: f64,
    r1: f64,
    r2: f64,
    omega: f64,
    rho0: f64,
    cv: f64,
}

impl Jwl {
    /// Largest compression `ρ/ρ₀` searched by [`EquationOfState::density`].
    const MAX_COMPRESSION: f64 = 1.0e3;

    /// Creates the EOS from `A`, `B` \[Pa\], `R₁`, `R₂`, `ω`, the reference
    /// density `ρ₀` and `c_v`; `t0` is the reference temperature at which
    /// the pressure `p(ρ₀, T₀)` must be positive.
    ///
    /// # Errors
    ///
    /// [`EosError::Invalid`] naming the scene key: `"a"` or `"b"` (not
    /// finite), `"r1"`, `"r2"`, `"omega"`, `"reference_density"`, `"cv"`,
    /// `"reference_temperature"` (not finite and > 0), or `"a"` when the
    /// parameters give `p(ρ₀, T₀) ≤ 0`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        a: f64,
        b: f64,
        r1: f64,
        r2: f64,
        omega: f64,
        rho0: f64,
        cv: f64,
        t0: f64,
    ) -> Result<Self, EosError> {
        for (field, v) in [("a", a), ("b", b)] {
            if !v.is_finite() {
                return Err(EosError::Invalid {
                    field,
                    allowed: "finite",
                    got: v,
                });
            }
        }
        let r1 = check_gt("r1", "finite and > 0", r1, 0.0)?;
        let r2 = check_gt("r2", "finite and > 0", r2, 0.0)?;
        let omega = check_gt("omega", "finite and > 0", omega, 0.0)?;
        let rho0 = check_gt("reference_density", "finite and > 0", rho0, 0.0)?;
        let cv = check_gt("cv", "finite and > 0", cv, 0.0)?;
        let t0 = check_gt("reference_temperature", "finite and > 0", t0, 0.0)?;
        let eos = Self {
            a,
            b,
            r1,
            r2,
            omega,
            rho0,
            cv,
        };
        let p_ref = eos.pressure(rho0, t0);
        if p_ref.is_nan() || p_ref <= 0.0 {
            return Err(EosError::Invalid {
                field: "a",
                allowed: "A, B, R1, R2, omega with a positive pressure p(rho0, T0) at the \
                          reference state",
                got: p_ref,
            });
        }
        Ok(eos)
    }

    /// Reference density `ρ₀` of `V = ρ₀/ρ`.
    pub fn reference_density(&self) -> f64 {
        self.rho0
    }

    /// Grüneisen coefficient `ω`.
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// The cold part `p_c(V)` and `dp_c/dV`.
    #[inline]
    fn cold(&self, v: f64) -> (f64, f64) {
        let w = self.omega;
        let term = |amp: f64, r: f64| {
            let x = amp * (-r * v).exp();
            (x * (1.0 - w / (r * v)), x * (w / (r * v * v) + w / v - r))
        };
        let (p1, d1) = term(self.a, self.r1);
        let (p2, d2) = term(self.b, self.r2);
        (p1 + p2, d1 + d2)
    }
}

impl EquationOfState for Jwl {
    fn pressure(&self, rho: f64, t: f64) -> f64 {
        self.cold(self.rho0 / rho).0 + self.omega * rho * self.cv * t
    }

    fn dp_drho(&self, rho: f64, t: f64) -> f64 {
        let v = self.rho0 / rho;
        // dV/dρ = −V/ρ.
        -self.cold(v).1 * v / rho + self.omega * self.cv * t
    }

    fn dp_dt(&self, rho: f64, _t: f64) -> f64 {
        self.omega * rho * self.cv
    }

    fn sound_speed_sq(&self, rho: f64, t: f64) -> f64 {
        // c² = (∂p/∂ρ)_T + (p/(ρ² c_v)) ω ρ c_v.
        self.dp_drho(rho, t) + self.omega * self.pressure(rho, t) / rho
    }

    fn density(&self, p: f64, t: f64) -> Result<f64, EosError> {
        let t = check_temperature(t)?;
        let p = check_pressure(p, 0.0)?;
        let f = |rho: f64| self.pressure(rho, t) - p;
        let too_high = EosError::Invalid {
            field: "pressure",
            allowed: "below the largest pressure of the JWL isotherm",
            got: p,
        };
        // Bracket [lo, hi] with f(lo) < 0 ≤ f(hi), stepping from ρ₀.
        let (mut lo, mut hi) = (self.rho0, self.rho0);
        if f(self.rho0) < 0.0 {
            loop {
                lo = hi;
                hi *= 1.5;
                if f(hi) >= 0.0 {
                    break;
                }
                if hi > Self::MAX_COMPRESSION * self.rho0 || self.dp_drho(hi, t) <= 0.0 {
                    return Err(too_high);
                }
            }
        } else {
            loop {
                hi = lo;
                lo *= 0.5;
                if lo == 0.0 {
                    return Err(EosError::PressureOutOfRange { p, p_min: 0.0 });
                }
                if f(lo) < 0.0 {
                    break;
                }
            }
        }
        // Newton safeguarded by bisection.
        let mut rho = 0.5 * (lo + hi);
        for _ in 0..200 {
            let r = f(rho);
            if r == 0.0 {
                break;
            }
            if r > 0.0 {
                hi = rho;
            } else {
                lo = rho;
            }
            let mut next = rho - r / self.dp_drho(rho, t);
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            let done = (next - rho).abs() <= 2.0 * f64::EPSILON * next
                || hi - lo <= 2.0 * f64::EPSILON * hi;
            rho = next;
            if done {
                break;
            }
        }
        Ok(rho)
    }

    fn specific_heat_cv(&self) -> f64 {
        self.cv
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// TNT (Dobratz & Crawford, LLNL Explosives Handbook, UCRL-52997):
    /// ρ₀ = 1630, A = 371.2 GPa, B = 3.231 GPa, R₁ = 4.15, R₂ = 0.95,
    /// ω = 0.30; c_v = 1000 J/(kg K) (a caloric scale for e = c_v T).
    fn tnt() -> Jwl {
        Jwl::new(371.2e9, 3.231e9, 4.15, 0.95, 0.30, 1630.0, 1000.0, 300.0).unwrap()
    }

    fn states() -> Vec<(f64, f64)> {
        let mut v = Vec::new();
        for rel in [0.001, 0.05, 0.3, 0.8, 1.0, 1.3, 2.0] {
            for t in [50.0, 300.0, 4000.0] {
                v.push((rel * 1630.0, t));
            }
        }
        v
    }

    #[test]
    fn derivatives_and_sound_speed() {
        let m = tnt();
        for (rho, t) in states() {
            let h = 1e-6 * rho;
            let fd = (m.pressure(rho + h, t) - m.pressure(rho - h, t)) / (2.0 * h);
            assert_relative_eq!(m.dp_drho(rho, t), fd, max_relative = 1e-7);
            let k = 1e-4 * t;
            let fd = (m.pressure(rho, t + k) - m.pressure(rho, t - k)) / (2.0 * k);
            assert_relative_eq!(m.dp_dt(rho, t), fd, max_relative = 1e-7);
            // Isentrope slope (RK4 in (ρ, e)).
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
            let slope = (step(h) - step(-h)) / (2.0 * h);
            assert_relative_eq!(m.sound_speed_sq(rho, t), slope, max_relative = 1e-7);
        }
    }

    #[test]
    fn density_inverts_pressure() {
        let m = tnt();
        for (rho, t) in states() {
            let p = m.pressure(rho, t);
            let back = m.density(p, t).unwrap();
            assert_relative_eq!(back, rho, max_relative = 1e-13);
            assert_relative_eq!(m.pressure(back, t), p, max_relative = 1e-14);
        }
        // Dilute products are the ideal gas p = ω ρ c_v T.
        assert_relative_eq!(
            m.density(1.0e3, 300.0).unwrap(),
            1.0e3 / (0.3 * 1000.0 * 300.0),
            max_relative = 1e-14
        );
        assert!(matches!(
            m.density(0.0, 300.0),
            Err(EosError::PressureOutOfRange { .. })
        ));
        assert!(m.density(-1.0, 300.0).is_err());
        assert!(m.density(1e5, -1.0).is_err());
    }

    #[test]
    fn reference_state_and_bad_parameters() {
        let m = tnt();
        // p(ρ₀, 0) = A (1 − ω/R₁) e^(−R₁) + B (1 − ω/R₂) e^(−R₂).
        let cold = 371.2e9 * (1.0 - 0.3 / 4.15) * (-4.15f64).exp()
            + 3.231e9 * (1.0 - 0.3 / 0.95) * (-0.95f64).exp();
        assert_relative_eq!(m.pressure(1630.0, 1e-300), cold, max_relative = 1e-14);
        let field = |r: Result<Jwl, EosError>| match r.unwrap_err() {
            EosError::Invalid { field, .. } => field,
            e => panic!("{e:?}"),
        };
        assert_eq!(
            field(Jwl::new(f64::NAN, 1.0, 4.0, 1.0, 0.3, 1630.0, 1e3, 300.0)),
            "a"
        );
        assert_eq!(
            field(Jwl::new(1e9, 1e9, 0.0, 1.0, 0.3, 1630.0, 1e3, 300.0)),
            "r1"
        );
        assert_eq!(
            field(Jwl::new(1e9, 1e9, 4.0, -1.0, 0.3, 1630.0, 1e3, 300.0)),
            "r2"
        );
        assert_eq!(
            field(Jwl::new(1e9, 1e9, 4.0, 1.0, 0.0, 1630.0, 1e3, 300.0)),
            "omega"
        );
        assert_eq!(
            field(Jwl::new(1e9, 1e9, 4.0, 1.0, 0.3, 0.0, 1e3, 300.0)),
            "reference_density"
        );
        assert_eq!(
            field(Jwl::new(1e9, 1e9, 4.0, 1.0, 0.3, 1630.0, -1.0, 300.0)),
            "cv"
        );
        // ω > R₁, R₂ and a cold reference state: negative pressure at (ρ₀, T₀).
        assert_eq!(
            field(Jwl::new(
                371.2e9, 3.231e9, 4.15, 0.95, 5.0, 1630.0, 1.0, 1.0
            )),
            "a"
        );
    }
}
