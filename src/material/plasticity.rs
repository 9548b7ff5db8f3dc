//! J2 (von Mises) plasticity by radial return, for the hypo-elastic (Jaumann
//! rate) solid path: flow stresses with linear or power-law isotropic
//! hardening and Johnson–Cook's (strain hardening, rate sensitivity,
//! thermal softening, with adiabatic heating from the plastic work).
//!
//! The update of one step (Simo & Hughes, *Computational Inelasticity*,
//! Box 3.1, written for the Cauchy stress of a hypo-elastic rate model):
//!
//! 1. rotate: σ* = σⁿ + Δt (W σⁿ − σⁿ W) (the Jaumann rate, York Eq. 19);
//! 2. elastic trial: σᵗʳ = σ* + Δt (λ tr D I + 2μ D);
//! 3. trial von Mises stress qᵗʳ = √(3/2 s:s), s = dev σᵗʳ; if
//!    qᵗʳ ≤ σ_y(ε̄ⁿ, 0, Tⁿ) the step is elastic;
//! 4. otherwise the plastic increment Δε̄ > 0 solves the consistency
//!    condition g(Δε̄) = qᵗʳ − 3μ Δε̄ − σ_y(ε̄ⁿ + Δε̄, Δε̄/Δt, T(Δε̄)) = 0
//!    (regula falsi with the Anderson–Björck weight on the bracket
//!    [0, g(0)/3μ], or [g(0)/3μ, qᵗʳ/3μ] where heating softens faster
//!    than the flow stress hardens), with adiabatic
//!    heating T = Tⁿ + β σ_y Δε̄ /(ρ c_p) when the flow stress softens with
//!    temperature (β the Taylor–Quinney fraction);
//! 5. s = (1 − 3μ Δε̄/qᵗʳ) sᵗʳ, σ = s + (tr σᵗʳ/3) I: the return is radial,
//!    so the pressure stays elastic.
//!
//! For linear hardening and a loading whose deviatoric direction does not
//! change (uniaxial strain, pure shear) the return is exact for any step
//! size, which the tests check to round-off against the closed forms.

use nalgebra::Matrix3;

/// Johnson–Cook flow stress (Johnson & Cook 1983):
/// σ_y = (A + B ε̄ⁿ)(1 + C ln ε̇*)(1 − T*ᵐ), ε̇* = max(ε̄̇/ε̇₀, 1),
/// T* = (T − T_room)/(T_melt − T_room) clamped to [0, 1].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JohnsonCook {
    /// Initial yield stress A \[Pa\].
    pub a: f64,
    /// Hardening modulus B \[Pa\].
    pub b: f64,
    /// Hardening exponent n.
    pub n: f64,
    /// Strain-rate coefficient C.
    pub c: f64,
    /// Thermal-softening exponent m > 0.
    pub m: f64,
    /// Reference strain rate ε̇₀ > 0 [1/s].
    pub rate0: f64,
    /// Room (reference) temperature \[K\].
    pub t_room: f64,
    /// Melting temperature \[K\] (> `t_room`).
    pub t_melt: f64,
}

/// The flow stress σ_y(ε̄, ε̄̇, T) of an isotropically hardening von Mises
/// material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FlowStress {
    /// σ_y = σ₀ + H ε̄.
    Linear {
        /// Initial yield stress σ₀ ≥ 0 \[Pa\].
        yield_stress: f64,
        /// Plastic hardening modulus H ≥ 0 \[Pa\].
        hardening: f64,
    },
    /// σ_y = σ₀ + K ε̄ⁿ (Ludwik).
    PowerLaw {
        /// Initial yield stress σ₀ ≥ 0 \[Pa\].
        yield_stress: f64,
        /// Strength coefficient K ≥ 0 \[Pa\].
        k: f64,
        /// Hardening exponent n in (0, 1].
        n: f64,
    },
    /// [`JohnsonCook`].
    JohnsonCook(JohnsonCook),
}

/// A parameter out of range: the key (as a scene names it, relative to the
/// material) and the allowed values.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BadParameter {
    /// Key, e.g. `"yield_stress"`.
    pub key: &'static str,
    /// Allowed values, e.g. `"finite and ≥ 0"`.
    pub allowed: &'static str,
}

/// `Ok` when `ok`, else the named [`BadParameter`].
pub(crate) fn check(
    ok: bool,
    key: &'static str,
    allowed: &'static str,
) -> Result<(), BadParameter> {
    if ok {
        Ok(())
    } else {
        Err(BadParameter { key, allowed })
    }
}

impl FlowStress {
    /// Checks the parameters' ranges.
    ///
    /// # Errors
    /// The first parameter out of range, named.
    pub fn validate(&self) -> Result<(), BadParameter> {
        let nonneg = |v: f64| v.is_finite() && v >= 0.0;
        match *self {
            FlowStress::Linear {
                yield_stress,
                hardening,
            } => {
                check(nonneg(yield_stress), "yield_stress", "finite and ≥ 0")?;
                check(nonneg(hardening), "hardening_modulus", "finite and ≥ 0")
            }
            FlowStress::PowerLaw { yield_stress, k, n } => {
                check(nonneg(yield_stress), "yield_stress", "finite and ≥ 0")?;
                check(nonneg(k), "hardening_coefficient", "finite and ≥ 0")?;
                check(n > 0.0 && n <= 1.0, "hardening_exponent", "in (0, 1]")
            }
            FlowStress::JohnsonCook(jc) => {
                check(nonneg(jc.a), "a", "finite and ≥ 0")?;
                check(nonneg(jc.b), "b", "finite and ≥ 0")?;
                check(jc.n > 0.0 && jc.n <= 1.0, "n", "in (0, 1]")?;
                check(nonneg(jc.c), "c", "finite and ≥ 0")?;
                check(jc.m.is_finite() && jc.m > 0.0, "m", "finite and > 0")?;
                check(
                    jc.rate0.is_finite() && jc.rate0 > 0.0,
                    "reference_rate",
                    "finite and > 0",
                )?;
                check(
                    jc.t_room.is_finite() && jc.t_room > 0.0,
                    "room_temperature",
                    "finite and > 0 [K]",
                )?;
                check(
                    jc.t_melt.is_finite() && jc.t_melt > jc.t_room,
                    "melt_temperature",
                    "finite and > room_temperature [K]",
                )
            }
        }
    }

    /// Flow stress at equivalent plastic strain `eps`, plastic strain rate
    /// `rate` and temperature `t`.
    #[inline]
    pub fn stress(&self, eps: f64, rate: f64, t: f64) -> f64 {
        match *self {
            FlowStress::Linear {
                yield_stress,
                hardening,
            } => yield_stress + hardening * eps,
            FlowStress::PowerLaw { yield_stress, k, n } => yield_stress + k * eps.max(0.0).powf(n),
            FlowStress::JohnsonCook(jc) => jc.strain_rate_part(eps, rate) * jc.thermal_factor(t),
        }
    }

    /// Whether the flow stress depends on temperature (then the plastic
    /// work heats the point).
    pub fn softens_with_temperature(&self) -> bool {
        matches!(self, FlowStress::JohnsonCook(_))
    }
}

impl JohnsonCook {
    /// Johnson & Cook 1983's 4340 steel (A 792 MPa, B 510 MPa, n 0.26,
    /// C 0.014, m 1.03, T_melt 1793 K; room 293 K, ε̇₀ 1 /s) with the
    /// strain-rate coefficient `c` (0: rate-independent).
    pub fn steel_4340(c: f64) -> Self {
        Self {
            a: 792e6,
            b: 510e6,
            n: 0.26,
            c,
            m: 1.03,
            rate0: 1.0,
            t_room: 293.0,
            t_melt: 1793.0,
        }
    }

    /// The flow stress's factors that do not depend on temperature,
    /// (A + B ε̄ⁿ)(1 + C ln ε̇*): the flow stress is this times
    /// [`Self::thermal_factor`].
    #[inline]
    pub fn strain_rate_part(&self, eps: f64, rate: f64) -> f64 {
        let strain = self.a + self.b * eps.max(0.0).powf(self.n);
        let rate_star = (rate / self.rate0).max(1.0);
        strain * (1.0 + self.c * rate_star.ln())
    }

    /// 1 − T*ᵐ, T* clamped to [0, 1] (no strength at and above melt).
    #[inline]
    pub fn thermal_factor(&self, t: f64) -> f64 {
        let ts = ((t - self.t_room) / (self.t_melt - self.t_room)).clamp(0.0, 1.0);
        1.0 - ts.powf(self.m)
    }
}

/// J2 plasticity with a flow stress and the heat its plastic work makes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct J2 {
    /// Flow stress.
    pub flow: FlowStress,
    /// Taylor–Quinney fraction β of the plastic work turned into heat
    /// (0.9 is the usual value); used when the flow stress softens.
    pub taylor_quinney: f64,
    /// Specific heat c_p [J/(kg K)] for the adiabatic heating.
    pub specific_heat: f64,
}

/// A point's plastic state (default: virgin, at 300 K, undamaged).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlasticState {
    /// Equivalent plastic strain ε̄.
    pub plastic_strain: f64,
    /// Temperature \[K\].
    pub temperature: f64,
    /// Damage D ∈ [0, 1] of a failing material (1: failed; see
    /// [`crate::material::failure`]); 0 elsewhere.
    pub damage: f64,
    /// Output of a nonlocal failure model: the step's local damage
    /// increment ΔD, which the step averages before adding it to `damage`
    /// ([`crate::mpm::nonlocal_damage`]); 0 otherwise.
    pub damage_increment: f64,
}

impl Default for PlasticState {
    fn default() -> Self {
        Self {
            plastic_strain: 0.0,
            temperature: 300.0,
            damage: 0.0,
            damage_increment: 0.0,
        }
    }
}

/// What one return did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Return {
    /// Plastic strain increment Δε̄ (0: elastic step).
    pub dplastic: f64,
    /// Plastic work per unit current volume, σ_y Δε̄ [J/m³].
    pub plastic_work: f64,
}

/// Deviatoric part of a 3×3 tensor.
#[inline]
pub fn deviator(s: &Matrix3<f64>) -> Matrix3<f64> {
    s - Matrix3::identity() * (s.trace() / 3.0)
}

/// Von Mises equivalent stress √(3/2 s:s) of a stress.
#[inline]
pub fn von_mises(s: &Matrix3<f64>) -> f64 {
    let d = deviator(s);
    (1.5 * d.component_mul(&d).sum()).sqrt()
}

impl J2 {
    /// Checks the parameters (the flow stress's, β in [0, 1], c_p > 0).
    ///
    /// # Errors
    /// The first parameter out of range, named.
    pub fn validate(&self) -> Result<(), BadParameter> {
        self.flow.validate()?;
        check(
            (0.0..=1.0).contains(&self.taylor_quinney),
            "taylor_quinney",
            "in [0, 1]",
        )?;
        check(
            self.specific_heat.is_finite() && self.specific_heat > 0.0,
            "specific_heat",
            "finite and > 0",
        )
    }

    /// Whether the plastic work heats the point (a temperature-dependent
    /// flow stress and β > 0).
    #[inline]
    fn heats(&self) -> bool {
        self.flow.softens_with_temperature() && self.taylor_quinney > 0.0
    }

    /// Flow stress after a plastic increment `de` over `dt` from ε̄ = `eps0`
    /// at temperature `t0`, with the heating it implies at density `rho`
    /// (a fixed point in T, converged by the outer iteration on Δε̄), and
    /// that temperature.
    ///
    /// The fixed point changes only the thermal factor: the strain and
    /// rate factors are taken once, and the iteration stops as soon as T
    /// repeats to the bit (the iterations left would repeat it, so the
    /// result is the four iterations' to the bit; with the narrower bracket
    /// of [`Self::return_map`], the Taylor anvil at 36 × 84 cells to 40 µs
    /// went from 8.22 to 6.02 s on one thread).
    #[inline]
    fn flow_after(&self, eps0: f64, t0: f64, de: f64, dt: f64, rho: f64) -> (f64, f64) {
        let rate = if dt > 0.0 { de / dt } else { 0.0 };
        match self.flow {
            FlowStress::JohnsonCook(jc) if self.heats() => {
                let part = jc.strain_rate_part(eps0 + de, rate);
                let heat = self.taylor_quinney / (rho * self.specific_heat);
                let mut t = t0;
                let mut sy = part * jc.thermal_factor(t);
                for _ in 0..4 {
                    let tn = t0 + heat * sy * de;
                    if tn == t {
                        // A fixed point to the bit: the rest repeat it.
                        break;
                    }
                    t = tn;
                    sy = part * jc.thermal_factor(t);
                }
                (sy, t)
            }
            _ => (self.flow.stress(eps0 + de, rate, t0), t0),
        }
    }

    /// The slope H' = dσ_y/dΔε̄ of the flow stress along the return (strain
    /// hardening, rate and heating together) at the converged increment
    /// `de` of a step that started from ε̄ = `eps0`, T = `t0`: exact for
    /// linear hardening, a central difference otherwise (one-sided at
    /// Δε̄ = 0). Used by the consistent tangent of
    /// [`crate::material::hencky`].
    pub fn hardening_slope(&self, eps0: f64, t0: f64, de: f64, dt: f64, rho: f64) -> f64 {
        if let FlowStress::Linear { hardening, .. } = self.flow {
            return hardening;
        }
        let h = 1e-6 * de.max(1e-6);
        let lo = (de - h).max(0.0);
        let hi = de + h;
        let f = |x: f64| self.flow_after(eps0, t0, x, dt, rho).0;
        (f(hi) - f(lo)) / (hi - lo)
    }

    /// Radial return of a trial stress (steps 3–5 of the module's update)
    /// with shear modulus `mu`, step `dt` and current density `rho` (for
    /// the heating). Updates `trial` into the returned stress and `state`.
    pub fn return_map(
        &self,
        mu: f64,
        dt: f64,
        rho: f64,
        trial: &mut Matrix3<f64>,
        state: &mut PlasticState,
    ) -> Return {
        let mean = trial.trace() / 3.0;
        let s = *trial - Matrix3::identity() * mean;
        let q_trial = (1.5 * s.component_mul(&s).sum()).sqrt();
        let (eps0, t0) = (state.plastic_strain, state.temperature);
        let sy0 = self.flow.stress(eps0, 0.0, t0);
        if q_trial <= sy0 {
            return Return {
                dplastic: 0.0,
                plastic_work: 0.0,
            };
        }
        let heats = self.heats();
        // g(Δε̄) = qᵗʳ − 3μ Δε̄ − σ_y(Δε̄), with σ_y and T there.
        let eval = |de: f64| {
            let (sy, t) = self.flow_after(eps0, t0, de, dt, rho);
            (q_trial - 3.0 * mu * de - sy, sy, t)
        };
        let (de, sy, t) = match self.flow {
            // Linear hardening, no heating: the closed form.
            FlowStress::Linear {
                yield_stress,
                hardening,
            } => {
                let de =
                    ((q_trial - yield_stress - hardening * eps0) / (3.0 * mu + hardening)).max(0.0);
                let (_, sy, t) = eval(de);
                (de, sy, t)
            }
            _ => {
                // Regula falsi on a bracket, with the Anderson–Björck
                // weight on an end kept twice: one evaluation per
                // iteration and superlinear, without the derivative, which
                // is infinite at ε̄ = 0 for n < 1 (a Newton iteration from
                // a secant slope needed up to 100 evaluation pairs there:
                // 190× a solid point's update in the bench).
                // g(0) = qᵗʳ − σ_y(ε̄ⁿ, 0, Tⁿ) > 0 is the yield check's.
                // The perfectly plastic increment Δε̄ₚ = g(0)/3μ closes the
                // bracket wherever the flow stress grows along the return
                // (g(Δε̄ₚ) = σ_y(0) − σ_y(Δε̄ₚ) ≤ 0), inside [0, qᵗʳ/3μ];
                // where heating softens it more, the root lies in
                // [Δε̄ₚ, qᵗʳ/3μ] (g(qᵗʳ/3μ) = −σ_y ≤ 0). On the Taylor
                // anvil (36 × 84 cells to 40 µs) a return took 10.6
                // evaluations with Illinois' halving on [0, qᵗʳ/3μ], 9.4
                // on the narrower bracket and 8.2 with this weight; the
                // particles agree to 2.4e-13 of each field's largest value.
                let tol_g = 1e-14 * q_trial.max(f64::MIN_POSITIVE);
                let fa0 = q_trial - sy0;
                let dp = fa0 / (3.0 * mu);
                let at_dp = eval(dp);
                let (mut lo, mut fa, mut hi, mut fb, mut last) = if at_dp.0 <= 0.0 {
                    (0.0, fa0, dp, at_dp.0, (dp, at_dp.1, at_dp.2))
                } else {
                    let hi = q_trial / (3.0 * mu);
                    let at_hi = eval(hi);
                    (dp, at_dp.0, hi, at_hi.0, (hi, at_hi.1, at_hi.2))
                };
                // Else σ_y = 0 at the far end (melted), or that end is the
                // root.
                if fb < -tol_g {
                    let mut side = 0i8;
                    for _ in 0..200 {
                        let c = (lo * fb - hi * fa) / (fb - fa);
                        let (fc, sy, t) = eval(c);
                        last = (c, sy, t);
                        if fc.abs() <= tol_g || hi - lo <= 1e-15 * hi {
                            break;
                        }
                        if fc > 0.0 {
                            if side == -1 {
                                let m = 1.0 - fc / fa;
                                fb *= if m > 0.0 { m } else { 0.5 };
                            }
                            lo = c;
                            fa = fc;
                            side = -1;
                        } else {
                            if side == 1 {
                                let m = 1.0 - fc / fb;
                                fa *= if m > 0.0 { m } else { 0.5 };
                            }
                            hi = c;
                            fb = fc;
                            side = 1;
                        }
                    }
                }
                if last.0 >= 0.0 {
                    last
                } else {
                    let (_, sy, t) = eval(0.0);
                    (0.0, sy, t)
                }
            }
        };
        let scale = if q_trial > 0.0 {
            1.0 - 3.0 * mu * de / q_trial
        } else {
            1.0
        };
        *trial = s * scale + Matrix3::identity() * mean;
        state.plastic_strain = eps0 + de;
        if heats {
            state.temperature = t;
        }
        Return {
            dplastic: de,
            plastic_work: sy * de,
        }
    }

    /// One hypo-elastic–plastic step (the module's steps 1–5) from the
    /// velocity gradient `l` over `dt`, with Lamé constants `lambda`, `mu`
    /// and current density `rho`: updates `stress` and `state`.
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &self,
        l: &Matrix3<f64>,
        dt: f64,
        lambda: f64,
        mu: f64,
        rho: f64,
        stress: &mut Matrix3<f64>,
        state: &mut PlasticState,
    ) -> Return {
        let d = 0.5 * (l + l.transpose());
        let w = 0.5 * (l - l.transpose());
        let old = *stress;
        // York Eq. 19 (Jaumann rate) for the elastic trial.
        let mut trial = old
            + dt * (w * old - old * w)
            + dt * (lambda * d.trace() * Matrix3::identity() + 2.0 * mu * d);
        let r = self.return_map(mu, dt, rho, &mut trial, state);
        *stress = trial;
        r
    }
}

/// The exact response of J2 plasticity with linear hardening to uniaxial
/// strain ε (D = ε̇ e₁⊗e₁), loaded monotonically from rest and, past
/// `peak`, reversed: elastic to ε_y = σ₀/2μ, then q = σ₀ + H ε̄ with
/// ε̄ = 2μ(|ε| − ε_y)/(3μ + H); σ₁₁ = Kε + 2q/3, σ₂₂ = σ₃₃ = Kε − q/3
/// (q signed); on reversal elastic (q falls by 2μ Δε) to the reverse yield
/// at −(σ₀ + H ε̄_max), then hardening again. The small-strain radial return
/// ([`J2::update`]) follows it exactly in the strain its updates
/// accumulate, and the Hencky model ([`crate::material::hencky`]) in the
/// logarithmic strain for the Kirchhoff stress: the tests' reference.
#[derive(Debug, Clone, Copy)]
pub struct UniaxialStrainResponse {
    /// Bulk modulus K.
    pub bulk: f64,
    /// Shear modulus μ.
    pub mu: f64,
    /// Initial yield stress σ₀.
    pub yield_stress: f64,
    /// Hardening modulus H.
    pub hardening: f64,
}

impl UniaxialStrainResponse {
    /// (σ₁₁, σ₂₂, ε̄) at strain `eps`: still loading from rest when `peak` is
    /// `None`, else unloading (and reverse loading) from a positive `peak`.
    pub fn at(&self, eps: f64, peak: Option<f64>) -> (f64, f64, f64) {
        let Self {
            bulk,
            mu,
            yield_stress: sy,
            hardening: h,
        } = *self;
        let ey = sy / (2.0 * mu);
        let hardened = |e: f64| 2.0 * mu * (e - ey) / (3.0 * mu + h);
        let (q, eb) = match peak {
            None if eps.abs() <= ey => (2.0 * mu * eps, 0.0),
            None => {
                let eb = hardened(eps.abs());
                (eps.signum() * (sy + h * eb), eb)
            }
            Some(peak) => {
                let eb_max = hardened(peak).max(0.0);
                let q_max = sy + h * eb_max;
                let reverse = peak - q_max / mu;
                if eps >= reverse {
                    (q_max - 2.0 * mu * (peak - eps), eb_max)
                } else {
                    let eb = eb_max + 2.0 * mu * (reverse - eps) / (3.0 * mu + h);
                    (-(sy + h * eb), eb)
                }
            }
        };
        (bulk * eps + 2.0 * q / 3.0, bulk * eps - q / 3.0, eb)
    }

    /// The strain at which reverse yield starts after `peak`.
    pub fn reverse_yield(&self, peak: f64) -> f64 {
        let ey = self.yield_stress / (2.0 * self.mu);
        let eb_max = (2.0 * self.mu * (peak - ey) / (3.0 * self.mu + self.hardening)).max(0.0);
        peak - (self.yield_stress + self.hardening * eb_max) / self.mu
    }
}

#[cfg(test)]
pub(crate) mod steel {
    //! The test steel shared by the plasticity tests.
    use super::{FlowStress, J2};

    pub const E: f64 = 200e9;
    pub const NU: f64 = 0.3;
    pub const SY: f64 = 300e6;
    pub const H: f64 = 2e9;

    /// (λ, μ).
    pub fn lame() -> (f64, f64) {
        let mu = E / (2.0 * (1.0 + NU));
        (E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU)), mu)
    }

    /// Linear hardening σ₀ + H ε̄ (β 0.9, c_p 450).
    pub fn linear(sy: f64, h: f64) -> J2 {
        J2 {
            flow: FlowStress::Linear {
                yield_stress: sy,
                hardening: h,
            },
            taylor_quinney: 0.9,
            specific_heat: 450.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::steel::{lame, H, SY};
    use super::*;

    fn linear() -> J2 {
        super::steel::linear(SY, H)
    }

    /// Drives one point through the strain path `strain(t)` (rate `rate`
    /// times the unit velocity gradient `dir`) with `steps` steps per unit
    /// time, calling `check(t, σ, ε̄)` after each step.
    fn drive(
        j2: &J2,
        dir: &Matrix3<f64>,
        legs: &[(f64, usize)],
        mut check: impl FnMut(f64, &Matrix3<f64>, f64),
    ) {
        let (lambda, mu) = lame();
        let mut s = Matrix3::zeros();
        let mut st = PlasticState {
            plastic_strain: 0.0,
            temperature: 293.0,
            damage: 0.0,
            damage_increment: 0.0,
        };
        let mut strain = 0.0;
        for &(rate, steps) in legs {
            let dt = 1.0 / steps as f64;
            for _ in 0..steps {
                j2.update(&(dir * rate), dt, lambda, mu, 7800.0, &mut s, &mut st);
                strain += rate * dt;
                check(strain, &s, st.plastic_strain);
            }
        }
    }

    /// Uniaxial strain (D = ε̇ e₁⊗e₁) to 10 ε_y and back past reverse
    /// yield against [`UniaxialStrainResponse`]. Exact for any step size.
    #[test]
    fn uniaxial_strain_matches_the_closed_form() {
        let (lambda, mu) = lame();
        let exact = UniaxialStrainResponse {
            bulk: lambda + 2.0 * mu / 3.0,
            mu,
            yield_stress: SY,
            hardening: H,
        };
        let dir = Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let eps_y = SY / (2.0 * mu);
        let peak = 10.0 * eps_y;
        let reverse = exact.reverse_yield(peak);
        let mut worst: f64 = 0.0;
        let mut loading = true;
        drive(
            &linear(),
            &dir,
            &[(peak, 37), (-(peak - reverse) - 3.0 * eps_y, 53)],
            |eps, s, ebar| {
                if (eps - peak).abs() < 1e-12 * peak {
                    loading = false;
                }
                let (s11, s22, eb) = exact.at(eps, (!loading).then_some(peak));
                let err = ((s[(0, 0)] - s11).abs() + (s[(1, 1)] - s22).abs()) / SY
                    + (ebar - eb).abs() / eps_y;
                worst = worst.max(err);
            },
        );
        assert!(worst < 1e-12, "worst relative error {worst:e}");
    }

    /// Pure shear γ (D = γ̇/2 (e₁⊗e₂ + e₂⊗e₁), no spin): τ = μγ to
    /// τ_y = σ₀/√3, then ε̄ = √3 μ (γ − γ_y)/(3μ + H), τ = (σ₀ + H ε̄)/√3.
    #[test]
    fn pure_shear_matches_the_closed_form() {
        let (_, mu) = lame();
        let dir = Matrix3::new(0.0, 0.5, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0);
        let gamma_y = SY / (3f64.sqrt() * mu);
        let mut worst: f64 = 0.0;
        drive(&linear(), &dir, &[(12.0 * gamma_y, 41)], |g, s, ebar| {
            let (tau, eb) = if g <= gamma_y {
                (mu * g, 0.0)
            } else {
                let eb = 3f64.sqrt() * mu * (g - gamma_y) / (3.0 * mu + H);
                ((SY + H * eb) / 3f64.sqrt(), eb)
            };
            let err =
                (s[(0, 1)] - tau).abs() / SY + s.trace().abs() / SY + (ebar - eb).abs() / gamma_y;
            worst = worst.max(err);
        });
        assert!(worst < 1e-12, "worst relative error {worst:e}");
    }

    fn jc(c: f64) -> J2 {
        J2 {
            flow: FlowStress::JohnsonCook(JohnsonCook::steel_4340(c)),
            taylor_quinney: 0.9,
            specific_heat: 477.0,
        }
    }

    /// Homogeneous adiabatic pure shear of Johnson–Cook 4340 steel (rate
    /// term off) to γ = 1, against the consistency ODE integrated
    /// independently by RK4 in γ: with q = σ_y(ε̄, T), dT/dε̄ = β q/(ρ c_p)
    /// and q = √3 μ (γ − √3 ε̄), dε̄/dγ = √3 μ /(3μ + dq/dε̄) where
    /// dq/dε̄ = ∂σ_y/∂ε̄ + ∂σ_y/∂T dT/dε̄ (0 at ε̄ = 0, where ∂σ_y/∂ε̄ is
    /// infinite for n < 1).
    #[test]
    fn johnson_cook_adiabatic_shear_matches_its_ode() {
        let (lambda, mu) = lame();
        let j2 = jc(0.0);
        let FlowStress::JohnsonCook(p) = j2.flow else {
            unreachable!()
        };
        let rho = 7800.0;
        let heat = j2.taylor_quinney / (rho * j2.specific_heat);
        let sy = |e: f64, t: f64| j2.flow.stress(e, 0.0, t);
        let gamma_y = p.a / (3f64.sqrt() * mu);
        let rhs = |e: f64, t: f64| {
            let e = e.max(0.0);
            let dq_de = if e > 0.0 {
                // ∂/∂ε̄ of (A + B ε̄ⁿ) times the thermal factor.
                p.b * p.n * e.powf(p.n - 1.0) * p.thermal_factor(t)
            } else {
                f64::INFINITY
            };
            let dq_dt = (sy(e, t + 1e-3) - sy(e, t - 1e-3)) / 2e-3;
            let dt_de = heat * sy(e, t);
            let de_dg = 3f64.sqrt() * mu / (3.0 * mu + dq_de + dq_dt * dt_de);
            (de_dg, dt_de * de_dg)
        };
        // ε̄ = 0 is a spurious fixed point of the ODE (its slope is infinite
        // there): start on the physical branch at a tiny ε̄₀, where
        // γ₀ = γ_y + (3μ ε̄₀ + B ε̄₀ⁿ)/(√3 μ) (heating negligible).
        let e0: f64 = 1e-12;
        let g0 = gamma_y + (3.0 * mu * e0 + p.b * e0.powf(p.n)) / (3f64.sqrt() * mu);
        let g_end = 1.0;
        let n = 200_000;
        let dg = (g_end - g0) / n as f64;
        let (mut e, mut t) = (e0, 293.0);
        let mut path = vec![(g0, sy(e, t), t)];
        for k in 0..n {
            let k1 = rhs(e, t);
            let k2 = rhs(e + 0.5 * dg * k1.0, t + 0.5 * dg * k1.1);
            let k3 = rhs(e + 0.5 * dg * k2.0, t + 0.5 * dg * k2.1);
            let k4 = rhs(e + dg * k3.0, t + dg * k3.1);
            e += dg / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
            t += dg / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
            path.push((g0 + (k + 1) as f64 * dg, sy(e, t), t));
        }
        let t_rise = path.last().unwrap().2 - 293.0;
        // The model, 1000 steps over the same γ (rate-independent: time is
        // a parameter).
        let dir = Matrix3::new(0.0, 0.5, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut s = Matrix3::zeros();
        let mut st = PlasticState {
            plastic_strain: 0.0,
            temperature: 293.0,
            damage: 0.0,
            damage_increment: 0.0,
        };
        let steps = 1000;
        let dt = 1.0 / steps as f64;
        let (mut worst_q, mut worst_t): (f64, f64) = (0.0, 0.0);
        let mut gamma = 0.0;
        for _ in 0..steps {
            j2.update(&(dir * g_end), dt, lambda, mu, rho, &mut s, &mut st);
            gamma += g_end * dt;
            if gamma > g0 {
                let x = (gamma - g0) / dg;
                let k = (x.floor() as usize).min(n - 1);
                let w = x - k as f64;
                let (_, q0, t0) = path[k];
                let (_, q1, t1) = path[k + 1];
                let q_ref = q0 + w * (q1 - q0);
                let t_ref = t0 + w * (t1 - t0);
                worst_q = worst_q.max((von_mises(&s) - q_ref).abs() / q_ref);
                worst_t = worst_t.max((st.temperature - t_ref).abs() / t_rise);
            }
        }
        println!(
            "JC adiabatic shear to γ = 1: ε̄ {:.4}, T {:.2} K (ODE {:.2} K); worst relative \
             error q {worst_q:.2e}, T {worst_t:.2e} of the rise",
            st.plastic_strain,
            st.temperature,
            path.last().unwrap().2
        );
        assert!(t_rise > 100.0, "heats: {t_rise}");
        assert!(worst_q < 3e-4 && worst_t < 3e-4, "{worst_q:e} {worst_t:e}");
    }

    /// Johnson–Cook rate sensitivity: in steady pure-shear flow at two
    /// strain rates 10³ apart (thermal term off: β = 0), the flow stresses
    /// at the same ε̄ differ by the factor (1 + C ln ε̇₁*)/(1 + C ln ε̇₂*).
    #[test]
    fn johnson_cook_rate_factor() {
        let (lambda, mu) = lame();
        let mut j2 = jc(0.014);
        j2.taylor_quinney = 0.0;
        let dir = Matrix3::new(0.0, 0.5, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0);
        let run = |rate: f64| {
            let mut s = Matrix3::zeros();
            let mut st = PlasticState {
                plastic_strain: 0.0,
                temperature: 293.0,
                damage: 0.0,
                damage_increment: 0.0,
            };
            // γ to 0.2 in 4000 steps; the plastic rate is then ≈ γ̇/√3.
            let steps = 4000;
            let dt = 0.2 / rate / steps as f64;
            for _ in 0..steps {
                j2.update(&(dir * rate), dt, lambda, mu, 7800.0, &mut s, &mut st);
            }
            (
                von_mises(&s),
                st.plastic_strain,
                j2.flow.stress(st.plastic_strain, 0.0, 293.0),
            )
        };
        let (q1, e1, base1) = run(1e1);
        let (q2, e2, base2) = run(1e4);
        // Normalise out the strain hardening at each ε̄.
        let measured = (q2 / base2) / (q1 / base1);
        // The plastic strain rate in steady flow: dε̄/dt = (√3μγ̇ − dq/dt)/(3μ)
        // ≈ γ̇/√3 (dq/dt small): compare with the factor at those rates.
        let factor = |g: f64| 1.0 + 0.014 * (g / 3f64.sqrt()).ln();
        let expected = factor(1e4) / factor(1e1);
        println!("JC rate: ε̄ {e1:.4} / {e2:.4}, ratio {measured:.6} vs {expected:.6}");
        assert!(
            (measured / expected - 1.0).abs() < 1e-3,
            "{measured} vs {expected}"
        );
    }

    /// The return's Δε̄ solves the consistency condition g(Δε̄) = qᵗʳ − 3μ
    /// Δε̄ − σ_y(ε̄ⁿ + Δε̄, Δε̄/Δt, T) = 0 to round-off, from a virgin and a
    /// hardened point, with the rate term on, and where heating near the
    /// melt softens the flow stress faster than it hardens (the root then
    /// lies past the perfectly plastic increment, the bracket's other
    /// branch); the returned stress is radial and its von Mises value is
    /// that flow stress.
    #[test]
    fn the_return_solves_the_consistency_condition() {
        let (_, mu) = lame();
        let rho = 7800.0;
        let dt = 1e-7;
        let cases = [
            // (A, B, n, C, ε̄ⁿ, Tⁿ, qᵗʳ / σ_y(ε̄ⁿ, 0, Tⁿ))
            (792e6, 510e6, 0.26, 0.014, 0.0, 293.0, 1.05),
            (792e6, 510e6, 0.26, 0.014, 0.3, 600.0, 1.3),
            (0.0, 292e6, 0.31, 0.025, 0.0, 300.0, 2.0),
            (90e6, 292e6, 0.31, 0.025, 1e-4, 300.0, 1.001),
            // B = 0, no rate term, near the melt: heating softens only.
            (400e6, 0.0, 0.5, 0.0, 0.5, 1750.0, 3.0),
        ];
        let mut branches = [0usize; 2];
        for (a, b, n, c, eps0, t0, over) in cases {
            let j2 = J2 {
                flow: FlowStress::JohnsonCook(JohnsonCook {
                    a,
                    b,
                    n,
                    c,
                    ..JohnsonCook::steel_4340(c)
                }),
                taylor_quinney: 0.9,
                specific_heat: 477.0,
            };
            let sy0 = j2.flow.stress(eps0, 0.0, t0);
            // (A = 0 at ε̄ = 0 flows at any stress: qᵗʳ = `over` × 100 MPa.)
            let q = over * if sy0 > 0.0 { sy0 } else { 1e8 };
            // A deviatoric trial stress of von Mises value q plus a pressure.
            let dir = Matrix3::new(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0) / 3f64.sqrt();
            let mut trial = dir * q - Matrix3::identity() * 1e8;
            let mut st = PlasticState {
                plastic_strain: eps0,
                temperature: t0,
                ..PlasticState::default()
            };
            let r = j2.return_map(mu, dt, rho, &mut trial, &mut st);
            let de = r.dplastic;
            let (sy, t) = j2.flow_after(eps0, t0, de, dt, rho);
            let g = q - 3.0 * mu * de - sy;
            let dp = (q - sy0) / (3.0 * mu);
            branches[usize::from(de > dp)] += 1;
            println!(
                "A {a:e} ε̄ⁿ {eps0} Tⁿ {t0}: Δε̄ {de:.6e} (Δε̄ₚ {dp:.6e}), g/q {:.2e}",
                g / q
            );
            assert!(de > 0.0);
            assert!(g.abs() <= 1e-12 * q, "g {g:e} of q {q:e}");
            assert!((von_mises(&trial) / sy - 1.0).abs() < 1e-12);
            assert!((st.temperature - t).abs() <= 1e-12 * t);
            assert!((trial.trace() / 3.0 + 1e8).abs() < 1e-6, "pressure kept");
            let s = deviator(&trial);
            assert!((s - dir * von_mises(&trial)).norm() < 1e-9 * sy, "radial");
        }
        assert!(branches[0] > 0 && branches[1] > 0, "{branches:?}");
    }

    #[test]
    fn bad_parameters_are_named() {
        let mut j = jc(0.01);
        if let FlowStress::JohnsonCook(p) = &mut j.flow {
            p.m = 0.0;
        }
        assert_eq!(j.validate().unwrap_err().key, "m");
        let l = FlowStress::Linear {
            yield_stress: -1.0,
            hardening: 0.0,
        };
        assert_eq!(l.validate().unwrap_err().key, "yield_stress");
        let mut k = linear();
        k.taylor_quinney = 1.5;
        assert_eq!(k.validate().unwrap_err().key, "taylor_quinney");
    }
}
