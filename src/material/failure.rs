//! Failure of hypo-elastic(-plastic) and Hencky(-plastic) solids:
//! Johnson–Cook ductile damage and brittle tensile failure (a spall
//! strength), with the failed point's stress (no tension, compression
//! kept).
//!
//! A point carries a damage D ∈ [0, 1]; it has failed when D = 1 (D is set
//! to exactly 1 then, so the flag is `D ≥ 1`).
//!
//! * **Johnson–Cook** (Johnson & Cook 1985, *Fracture characteristics of
//!   three metals subjected to various strains, strain rates, temperatures
//!   and pressures*, Eng. Fract. Mech. 21, Eqs. 1–2): D = Σ Δε̄ / ε_f with
//!   ε_f = (D₁ + D₂ exp(D₃ σ*))(1 + D₄ ln ε̇*)(1 + D₅ T*), the stress
//!   triaxiality σ* = σ_m / q = −p/q (positive in tension), ε̇* =
//!   max(ε̄̇/ε̇₀, 1) and the homologous temperature T* clamped to [0, 1]. The
//!   increment of a step uses the stress, rate and temperature at its end
//!   (after the radial return). Where the fit gives ε_f ≤ 0 (possible for
//!   D₁ < 0 at high triaxiality) any plastic increment fails the point.
//! * **Tensile** (brittle): the point fails when its largest principal
//!   stress reaches the spall strength σ_s. The maximum principal stress is
//!   used rather than a pressure cut-off because a spall strength is
//!   measured in plate impact as the longitudinal stress of uniaxial strain
//!   at which the free-surface velocity pulls back, which is the largest
//!   principal stress there: the measured number enters as it is, whereas a
//!   cut-off on the mean stress would need the ratio K/(λ + 2μ) of the
//!   material to convert it, and would never fail a point loaded in shear
//!   or uniaxial tension with a small mean stress.
//!
//! A failed point carries no tension and keeps only a pressure: each step
//! its mean stress follows the hypo-elastic volumetric rate,
//! σ_m ← σ_m + K tr(D) Δt (the Jaumann spin leaves an isotropic stress
//! unchanged), clamped at σ_m ≤ 0, and its deviator is zero:
//! σ = min(σ_m, 0) I. It resists compression as soon as it is compressed
//! (voids close at once) and opens freely in tension. On the Hencky path
//! ([`crate::material::solid::SolidMaterial::hencky_update`]) the same
//! rule holds for the Kirchhoff mean stress, whose volumetric response is
//! exactly `K ln J`: τ_m ← min(τ_m + K ln(J/Jⁿ), 0).

use nalgebra::Matrix3;

use super::plasticity::{check, BadParameter, PlasticState, J2};

/// Johnson–Cook failure constants (Johnson & Cook 1985).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JohnsonCookFailure {
    /// D₁ (may be negative; D₁ + D₂ > 0).
    pub d1: f64,
    /// D₂ ≥ 0.
    pub d2: f64,
    /// D₃ (usually negative: ductility falls with triaxiality).
    pub d3: f64,
    /// D₄ ≥ 0 (rate term).
    pub d4: f64,
    /// D₅ > −1 (temperature term).
    pub d5: f64,
    /// Reference strain rate ε̇₀ > 0 [1/s].
    pub rate0: f64,
    /// Room temperature \[K\] of T*.
    pub t_room: f64,
    /// Melting temperature \[K\] of T* (> `t_room`).
    pub t_melt: f64,
    /// Interaction radius R \[m\] of the nonlocal damage average
    /// ([`crate::mpm::nonlocal_damage`]); 0: local damage (each point
    /// accumulates its own Δε̄/ε_f).
    pub nonlocal_radius: f64,
}

impl JohnsonCookFailure {
    /// The failure strain ε_f(σ*, ε̄̇, T) (Johnson & Cook 1985, Eq. 2).
    #[inline]
    pub fn failure_strain(&self, triaxiality: f64, rate: f64, t: f64) -> f64 {
        let rate_star = (rate / self.rate0).max(1.0);
        let t_star = ((t - self.t_room) / (self.t_melt - self.t_room)).clamp(0.0, 1.0);
        (self.d1 + self.d2 * (self.d3 * triaxiality).exp())
            * (1.0 + self.d4 * rate_star.ln())
            * (1.0 + self.d5 * t_star)
    }
}

/// A failure model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Failure {
    /// Johnson–Cook ductile damage (needs plasticity).
    JohnsonCook(JohnsonCookFailure),
    /// Brittle failure when the largest principal stress reaches
    /// `spall_strength` \[Pa\] (> 0).
    Tensile {
        /// Spall strength σ_s > 0 \[Pa\].
        spall_strength: f64,
    },
}

impl Failure {
    /// The interaction radius of a nonlocal damage average (0: local; the
    /// tensile model is always local).
    pub fn nonlocal_radius(&self) -> f64 {
        match *self {
            Failure::JohnsonCook(jc) => jc.nonlocal_radius,
            Failure::Tensile { .. } => 0.0,
        }
    }

    /// Accumulates the damage of one step in `state.damage` (set to
    /// exactly 1 at failure): `stress` is the Cauchy stress at the end of
    /// the step (after any return) and `dplastic` its plastic increment
    /// Δε̄ over `dt`. Johnson–Cook adds Δε̄/ε_f (Johnson & Cook 1985 Eq. 1)
    /// at the stress triaxiality, rate and temperature at the end of the
    /// step (where ε_f ≤ 0 the increment is 1, a full damage); the tensile
    /// model fails the point where its largest principal stress reaches
    /// the spall strength. A nonlocal Johnson–Cook model leaves
    /// `state.damage` as it is and writes the local increment to
    /// `state.damage_increment`: the step averages it over the point's
    /// neighbours and adds the average ([`crate::mpm::nonlocal_damage`]).
    pub fn accumulate(
        &self,
        stress: &Matrix3<f64>,
        dplastic: f64,
        dt: f64,
        state: &mut PlasticState,
    ) {
        match *self {
            Failure::JohnsonCook(jc) => {
                if dplastic > 0.0 {
                    let q = super::plasticity::von_mises(stress);
                    let triaxiality = if q > 0.0 {
                        stress.trace() / 3.0 / q
                    } else {
                        0.0
                    };
                    let rate = if dt > 0.0 { dplastic / dt } else { 0.0 };
                    let ef = jc.failure_strain(triaxiality, rate, state.temperature);
                    // Johnson & Cook 1985 Eq. 1: D = Σ Δε̄/ε_f.
                    let increment = if ef > 0.0 { dplastic / ef } else { 1.0 };
                    if jc.nonlocal_radius > 0.0 {
                        state.damage_increment = increment;
                    } else {
                        state.damage += increment;
                    }
                } else {
                    state.damage_increment = 0.0;
                }
            }
            Failure::Tensile { spall_strength } => {
                if max_principal(stress) >= spall_strength {
                    state.damage = 1.0;
                }
            }
        }
        if state.damage >= 1.0 {
            state.damage = 1.0;
        }
    }

    /// Checks the parameters' ranges.
    ///
    /// # Errors
    /// The first parameter out of range, named as a scene names it
    /// (relative to the failure table).
    pub fn validate(&self) -> Result<(), BadParameter> {
        match *self {
            Failure::JohnsonCook(f) => {
                let fin = |v: f64| v.is_finite();
                check(fin(f.d1), "d1", "finite")?;
                check(fin(f.d2) && f.d2 >= 0.0, "d2", "finite and ≥ 0")?;
                check(
                    f.d1 + f.d2 > 0.0,
                    "d1",
                    "such that d1 + d2 > 0 (the failure strain at zero triaxiality)",
                )?;
                check(fin(f.d3), "d3", "finite")?;
                check(fin(f.d4) && f.d4 >= 0.0, "d4", "finite and ≥ 0")?;
                check(fin(f.d5) && f.d5 > -1.0, "d5", "finite and > -1")?;
                check(
                    fin(f.rate0) && f.rate0 > 0.0,
                    "reference_rate",
                    "finite and > 0",
                )?;
                check(
                    fin(f.t_room) && f.t_room > 0.0,
                    "room_temperature",
                    "finite and > 0 [K]",
                )?;
                check(
                    fin(f.t_melt) && f.t_melt > f.t_room,
                    "melt_temperature",
                    "finite and > room_temperature [K]",
                )?;
                check(
                    fin(f.nonlocal_radius) && f.nonlocal_radius >= 0.0,
                    "nonlocal_radius",
                    "finite and ≥ 0 [m] (0: local damage)",
                )
            }
            Failure::Tensile { spall_strength } => check(
                spall_strength.is_finite() && spall_strength > 0.0,
                "spall_strength",
                "finite and > 0 [Pa]",
            ),
        }
    }
}

/// A hypo-elastic solid (Jaumann rate), optionally J2-plastic, that fails.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fracturing {
    /// J2 plasticity (required by [`Failure::JohnsonCook`]).
    pub plasticity: Option<J2>,
    /// The failure model.
    pub failure: Failure,
}

/// Largest eigenvalue of a symmetric 3×3 matrix, in closed form (the
/// trigonometric solution of the characteristic cubic, Smith 1961,
/// *Eigenvalues of a symmetric 3 × 3 matrix*, Commun. ACM 4).
#[inline]
pub fn max_principal(s: &Matrix3<f64>) -> f64 {
    let p1 = s[(0, 1)] * s[(0, 1)] + s[(0, 2)] * s[(0, 2)] + s[(1, 2)] * s[(1, 2)];
    let q = s.trace() / 3.0;
    if p1 == 0.0 {
        return s[(0, 0)].max(s[(1, 1)]).max(s[(2, 2)]);
    }
    let (a, b, c) = (s[(0, 0)] - q, s[(1, 1)] - q, s[(2, 2)] - q);
    let p2 = a * a + b * b + c * c + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let bm = (s - Matrix3::identity() * q) / p;
    let r = (bm.determinant() / 2.0).clamp(-1.0, 1.0);
    q + 2.0 * p * (r.acos() / 3.0).cos()
}

/// The stress of a failed point: σ = min(σ_m, 0) I.
#[inline]
pub fn failed_stress(s: &Matrix3<f64>) -> Matrix3<f64> {
    Matrix3::identity() * (s.trace() / 3.0).min(0.0)
}

/// The hypo-elastic trial stress of York Eq. 19 (Jaumann rate):
/// σ* = σⁿ + Δt (W σⁿ − σⁿ W) + Δt (λ tr D I + 2μ D).
#[inline]
pub fn jaumann_trial(
    l: &Matrix3<f64>,
    dt: f64,
    lambda: f64,
    mu: f64,
    old: &Matrix3<f64>,
) -> Matrix3<f64> {
    let d = 0.5 * (l + l.transpose());
    let w = 0.5 * (l - l.transpose());
    old + dt * (w * old - old * w) + dt * (lambda * d.trace() * Matrix3::identity() + 2.0 * mu * d)
}

impl Fracturing {
    /// Checks the plasticity and failure parameters.
    ///
    /// # Errors
    /// The first parameter out of range, named.
    pub fn validate(&self) -> Result<(), BadParameter> {
        if let Some(j2) = &self.plasticity {
            j2.validate()?;
        }
        self.failure.validate()
    }

    /// One step from the velocity gradient `l` over `dt` with Lamé
    /// constants `lambda`, `mu` and current density `rho`: a failed point
    /// (`state.damage ≥ 1`) keeps its pressure only (the module's rule);
    /// otherwise the hypo-elastic(-plastic) update, then the failure
    /// model's damage; a point that fails in this step ends it with the
    /// failed stress. Updates `stress` and `state`.
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
    ) {
        if state.damage >= 1.0 {
            // The volumetric part of York Eq. 19, clamped to no tension.
            let bulk = lambda + 2.0 * mu / 3.0;
            let mean = stress.trace() / 3.0 + bulk * l.trace() * dt;
            *stress = Matrix3::identity() * mean.min(0.0);
            return;
        }
        let dplastic = match &self.plasticity {
            Some(j2) => j2.update(l, dt, lambda, mu, rho, stress, state).dplastic,
            None => {
                *stress = jaumann_trial(l, dt, lambda, mu, stress);
                0.0
            }
        };
        self.failure.accumulate(stress, dplastic, dt, state);
        if state.damage >= 1.0 {
            *stress = failed_stress(stress);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::plasticity::{FlowStress, JohnsonCook};
    use crate::material::solid::{ElasticConstants, SolidMaterial, SolidModel};

    #[test]
    fn max_principal_matches_the_eigen_solver() {
        let cases = [
            Matrix3::new(2.0, 0.5, 0.1, 0.5, -1.0, 0.3, 0.1, 0.3, 0.7),
            Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            Matrix3::new(-3.0, 1e-9, 0.0, 1e-9, -3.0, 0.0, 0.0, 0.0, -3.0),
            Matrix3::new(0.0, 4.0, 0.0, 4.0, 0.0, 0.0, 0.0, 0.0, -1.0),
        ];
        for s in cases {
            let e = s.symmetric_eigen().eigenvalues.max();
            assert!(
                (max_principal(&s) - e).abs() <= 1e-12 * s.norm(),
                "{s}: {} vs {e}",
                max_principal(&s)
            );
        }
    }

    /// OFHC copper: Johnson & Cook 1983 flow (A 90 MPa, B 292 MPa, n 0.31,
    /// C 0.025, m 1.09, T_melt 1356 K) and Johnson & Cook 1985 failure
    /// (D₁ 0.54, D₂ 4.89, D₃ −3.03, D₄ 0.014, D₅ 1.12).
    fn copper(beta: f64) -> Fracturing {
        Fracturing {
            plasticity: Some(J2 {
                flow: FlowStress::JohnsonCook(JohnsonCook {
                    a: 90e6,
                    b: 292e6,
                    n: 0.31,
                    c: 0.025,
                    m: 1.09,
                    rate0: 1.0,
                    t_room: 294.0,
                    t_melt: 1356.0,
                }),
                taylor_quinney: beta,
                specific_heat: 383.0,
            }),
            failure: Failure::JohnsonCook(JohnsonCookFailure {
                d1: 0.54,
                d2: 4.89,
                d3: -3.03,
                d4: 0.014,
                d5: 1.12,
                rate0: 1.0,
                t_room: 294.0,
                t_melt: 1356.0,
                nonlocal_radius: 0.0,
            }),
        }
    }

    /// Homogeneous uniaxial stress (σ₂₂ = σ₃₃ = 0: constant triaxiality
    /// σ* = 1/3) of JC copper at a constant axial rate, heating
    /// adiabatically. Each step solves for the lateral rate that keeps
    /// σ₂₂ = 0 (secant), so the path is the exact uniaxial-stress path.
    /// The damage is checked against the integral D(ε̄) = ∫ dε̄ / ε_f(1/3,
    /// ε̄̇, T(ε̄)) evaluated from the point's own (ε̄, ε̄̇, T) history by the
    /// same rule (right-endpoint sum) and independently by the trapezoid
    /// rule: the two differ by O(Δε̄), and the failure step is the first
    /// whose integral reaches 1.
    #[test]
    fn uniaxial_stress_damage_integrates_the_failure_strain() {
        let fr = copper(0.9);
        let (e, nu, rho) = (124e9, 0.34, 8960.0);
        let mu = e / (2.0 * (1.0 + nu));
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let Failure::JohnsonCook(jc) = fr.failure else {
            unreachable!()
        };
        let rate = 1e3;
        let dt = 2e-6; // Δε = 2e-3 per step
        let mut s = Matrix3::zeros();
        let mut st = PlasticState {
            plastic_strain: 0.0,
            temperature: 294.0,
            damage: 0.0,
            damage_increment: 0.0,
        };
        let mut lateral = -nu * rate;
        let mut history = vec![(0.0, 0.0, 294.0, 0.0)]; // (ε̄, ε̄̇, T, σ*)
        let mut failed_at = None;
        let mut worst_triax: f64 = 0.0;
        for step in 0..2000 {
            // Secant on the lateral rate so that σ₂₂ = 0 at the step's end.
            let trial = |lat: f64| {
                let l = Matrix3::from_diagonal(&nalgebra::Vector3::new(rate, lat, lat));
                let mut s1 = s;
                let mut st1 = st;
                fr.update(&l, dt, lambda, mu, rho, &mut s1, &mut st1);
                (s1, st1)
            };
            let (mut a, mut b) = (lateral, lateral * 1.01 - 1.0);
            let (mut fa, mut fb) = (trial(a).0[(1, 1)], trial(b).0[(1, 1)]);
            for _ in 0..60 {
                if fb == fa || fb.abs() < 1e-6 {
                    break;
                }
                let c = b - fb * (b - a) / (fb - fa);
                a = b;
                fa = fb;
                b = c;
                fb = trial(b).0[(1, 1)];
            }
            lateral = b;
            let (s1, st1) = trial(b);
            if st1.damage >= 1.0 {
                failed_at = Some(step);
                // The failed stress: no tension left.
                assert_eq!(s1, failed_stress(&s1));
                assert!(s1.trace() <= 0.0);
                break;
            }
            let de = st1.plastic_strain - st.plastic_strain;
            s = s1;
            st = st1;
            if de > 0.0 {
                let q = crate::material::plasticity::von_mises(&s);
                let tri = s.trace() / 3.0 / q;
                worst_triax = worst_triax.max((tri - 1.0 / 3.0).abs());
                history.push((st.plastic_strain, de / dt, st.temperature, tri));
            }
            // Damage by the right-endpoint sum over the history.
            let sum: f64 = history
                .windows(2)
                .map(|w| (w[1].0 - w[0].0) / jc.failure_strain(w[1].3, w[1].1, w[1].2))
                .sum();
            assert!(
                (st.damage - sum).abs() <= 1e-12 * sum.max(1e-300),
                "step {step}: damage {} vs sum {sum}",
                st.damage
            );
        }
        let step = failed_at.expect("the point fails");
        // Trapezoid rule of the same integral at σ* = 1/3 exactly.
        let ef = |h: &(f64, f64, f64, f64)| jc.failure_strain(1.0 / 3.0, h.1, h.2);
        let trap: f64 = history
            .windows(2)
            .map(|w| (w[1].0 - w[0].0) * 0.5 * (1.0 / ef(&w[0]).max(1e-300) + 1.0 / ef(&w[1])))
            .sum();
        let last = history.last().unwrap();
        let d_next = st.damage + 2e-3 / ef(last);
        println!(
            "JC uniaxial stress: fails at step {step} (ε̄ {:.4}, T {:.1} K), damage before {:.5} \
             (trapezoid {trap:.5}), |σ* − 1/3| ≤ {worst_triax:.1e}",
            last.0, last.2, st.damage
        );
        assert!(worst_triax < 1e-6, "triaxiality drifts: {worst_triax:e}");
        // The step before failure is short of 1 and the next increment
        // (Δε̄ ≈ Δε) crosses it.
        assert!(st.damage < 1.0 && d_next >= 0.99, "{} {d_next}", st.damage);
        // The right-endpoint sum agrees with the trapezoid rule to O(Δε̄).
        assert!((st.damage - trap).abs() < 0.01, "{} vs {trap}", st.damage);
        // Failure strain at 1/3 (isothermal, rate 1e3): ≈ 1.45; heating
        // raises it by (1 + D₅ T*).
        let ef_room = jc.failure_strain(1.0 / 3.0, 1e3, 294.0);
        assert!(last.0 > ef_room * 0.99, "{} vs {ef_room}", last.0);
    }

    /// Extreme plastic strain: simple shear of JC copper to γ = 30 (ε̄ ≈ 17)
    /// with adiabatic heating towards the melt: every value stays finite and
    /// the stress stays on the (softened) yield surface.
    #[test]
    fn extreme_plastic_strain_stays_finite() {
        let mut fr = copper(0.9);
        fr.failure = Failure::Tensile {
            spall_strength: 1e20,
        };
        let (e, nu, rho) = (124e9, 0.34, 8960.0);
        let mu = e / (2.0 * (1.0 + nu));
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let l = Matrix3::new(0.0, 30.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let mut s = Matrix3::zeros();
        let mut st = PlasticState {
            plastic_strain: 0.0,
            temperature: 294.0,
            damage: 0.0,
            damage_increment: 0.0,
        };
        let n = 3000;
        let dt = 1.0 / n as f64;
        let mut de = 0.0;
        for _ in 0..n {
            let e0 = st.plastic_strain;
            fr.update(&l, dt, lambda, mu, rho, &mut s, &mut st);
            de = st.plastic_strain - e0;
            assert!(s.iter().all(|x| x.is_finite()) && st.plastic_strain.is_finite());
        }
        println!(
            "γ = 30: ε̄ {:.3}, T {:.0} K, q {:.3e}",
            st.plastic_strain,
            st.temperature,
            crate::material::plasticity::von_mises(&s)
        );
        assert!(st.plastic_strain > 10.0);
        // Heated towards the melt (approached asymptotically: the heating
        // vanishes with the flow stress), still on the yield surface.
        assert!(st.temperature > 1200.0 && st.temperature < 1356.0);
        let fr_j2 = fr.plasticity.unwrap();
        let sy = fr_j2
            .flow
            .stress(st.plastic_strain, de / dt, st.temperature);
        let q = crate::material::plasticity::von_mises(&s);
        assert!((q / sy - 1.0).abs() < 1e-9, "{q} vs {sy}");
    }

    #[test]
    fn failed_point_keeps_compression_only() {
        let fr = Fracturing {
            plasticity: None,
            failure: Failure::Tensile {
                spall_strength: 1e6,
            },
        };
        let (lambda, mu) = (1e9, 1e9);
        let bulk = lambda + 2.0 * mu / 3.0;
        let mut s = Matrix3::zeros();
        let mut st = PlasticState::default();
        // Pull along x: σ₁₁ = (λ + 2μ) ε reaches 1 MPa at ε = 3.33e-4.
        let l = Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let dt = 1e-5;
        let mut k = 0;
        while st.damage < 1.0 {
            fr.update(&l, dt, lambda, mu, 1.0, &mut s, &mut st);
            k += 1;
        }
        // Fails at the first step with (λ + 2μ) k Δt ≥ σ_s.
        assert_eq!(k, (1e6 / (3e9 * dt)).ceil() as usize);
        assert_eq!(s, Matrix3::zeros());
        // Further pull: no stress. Then compress by tr D Δt = −1e-3 in
        // total: p = K 1e-3 exactly (volumetric, no deviator).
        for _ in 0..50 {
            fr.update(&l, dt, lambda, mu, 1.0, &mut s, &mut st);
            assert_eq!(s, Matrix3::zeros());
        }
        let c = Matrix3::from_diagonal(&nalgebra::Vector3::new(-1.0, -0.5, 0.0));
        for _ in 0..100 {
            fr.update(&c, dt / 1.5, lambda, mu, 1.0, &mut s, &mut st);
        }
        let p = -s.trace() / 3.0;
        assert!((p / (bulk * 1e-3) - 1.0).abs() < 1e-12, "{p}");
        assert_eq!(s, Matrix3::identity() * (-p));
    }

    /// One explicit step of the Hencky solid `m` from the total deformation
    /// gradient `f_old` to `f_new`: updates `stress`, `work` and `st`.
    fn hencky_step(
        m: &SolidMaterial,
        f_old: &Matrix3<f64>,
        f_new: &Matrix3<f64>,
        stress: &mut Matrix3<f64>,
        work: &mut f64,
        st: &mut PlasticState,
    ) {
        let f_rel = f_new * f_old.try_inverse().unwrap();
        let (j, j_old) = (f_new.determinant(), f_old.determinant());
        m.hencky_update(
            &f_rel, f_new, j, j_old, 1e-6, 7800.0, stress, work, st, None,
        )
        .expect("a Hencky step");
    }

    fn hencky(fr: Fracturing) -> SolidMaterial {
        SolidMaterial {
            name: "steel".into(),
            density: 7800.0,
            model: SolidModel::HenckyFracturing(fr),
            elastic: ElasticConstants {
                lambda: 1e11,
                mu: 8e10,
            },
        }
    }

    /// Hencky with brittle failure in uniaxial strain F = diag(λ₁, 1, 1):
    /// σ₁₁ = (λ + 2μ) ln λ₁ / λ₁ exactly, so the point fails at the first
    /// stretch that reaches the spall strength. It then carries no
    /// tension, and compressed by ln(J/J₀) = −1e-3 from any opened state
    /// its Kirchhoff pressure is K·1e-3 (voids close at once) with no
    /// deviator; its work is the energy stored at failure (now dissipated)
    /// plus the (tr τ)²/(18K) it stores again.
    #[test]
    fn hencky_point_fails_at_the_spall_strength_and_keeps_compression_only() {
        let sigma_s = 2e9;
        let m = hencky(Fracturing {
            plasticity: None,
            failure: Failure::Tensile {
                spall_strength: sigma_s,
            },
        });
        let ElasticConstants { lambda, mu } = m.elastic;
        let bulk = lambda + 2.0 * mu / 3.0;
        let (mut s, mut w, mut st) = (Matrix3::zeros(), 0.0, PlasticState::default());
        let mut f = Matrix3::identity();
        let stretch = |k: usize| 1.0 + 1e-4 * k as f64;
        let mut k = 0;
        let mut w_fail = 0.0;
        while st.damage < 1.0 {
            k += 1;
            let f1 = Matrix3::from_diagonal(&nalgebra::Vector3::new(stretch(k), 1.0, 1.0));
            let w0 = w;
            hencky_step(&m, &f, &f1, &mut s, &mut w, &mut st);
            let l1 = stretch(k);
            let exact = (lambda + 2.0 * mu) * l1.ln() / l1;
            if st.damage < 1.0 {
                assert!(
                    (s[(0, 0)] / exact - 1.0).abs() < 1e-12,
                    "{} vs {exact}",
                    s[(0, 0)]
                );
                // The work is the stored energy ½ (λ + 2μ) (ln λ₁)².
                let stored = 0.5 * (lambda + 2.0 * mu) * l1.ln().powi(2);
                assert!((w / stored - 1.0).abs() < 1e-12, "{w} vs {stored}");
            } else {
                // The step's stored energy stays in the work (dissipated).
                w_fail = w;
                assert!(w > w0);
            }
            f = f1;
        }
        let first = (1..k)
            .find(|&i| (lambda + 2.0 * mu) * stretch(i).ln() / stretch(i) >= sigma_s)
            .unwrap_or(k);
        assert_eq!(k, first, "fails at the first stretch past σ_s");
        assert_eq!(s, Matrix3::zeros());
        // Pulled further (and sheared): no stress, no work.
        for i in 1..=20 {
            let mut f1 = f;
            f1[(0, 0)] *= 1.0 + 1e-3;
            f1[(0, 1)] += 1e-3 * i as f64;
            hencky_step(&m, &f, &f1, &mut s, &mut w, &mut st);
            assert_eq!(s, Matrix3::zeros());
            f = f1;
        }
        assert_eq!(w, w_fail);
        // Compress: J falls by the factor exp(−1e-3) in 10 steps.
        let j0 = f.determinant();
        for _ in 0..10 {
            let f1 = f * (-1e-4f64 / 3.0).exp();
            hencky_step(&m, &f, &f1, &mut s, &mut w, &mut st);
            f = f1;
        }
        let j = f.determinant();
        assert!(((j / j0).ln() + 1e-3).abs() < 1e-15);
        let tau_m = s.trace() / 3.0 * j;
        assert!((tau_m / (-bulk * 1e-3) - 1.0).abs() < 1e-9, "{tau_m}");
        assert_eq!(s, Matrix3::identity() * (s.trace() / 3.0));
        let stored = 0.5 * bulk * 1e-6;
        assert!(
            ((w - w_fail) / stored - 1.0).abs() < 1e-9,
            "{} vs {stored}",
            w - w_fail
        );
    }

    /// Johnson–Cook damage on the Hencky path in isochoric plane strain
    /// F = diag(eᵃ, e⁻ᵃ, 1): the Kirchhoff mean stress is K ln J = 0, so
    /// the triaxiality is exactly 0 and, with D₄ = D₅ = 0, ε_f = D₁ + D₂.
    /// With linear hardening on this coaxial path the return is exact:
    /// ε̄ₚ = (3μ ε̄ − σ₀)/(3μ + H) with ε̄ = 2a/√3, so D = ε̄ₚ/ε_f at every
    /// step and the point fails at the first step where ε̄ₚ ≥ ε_f.
    #[test]
    fn hencky_johnson_cook_damage_is_the_plastic_strain_over_the_failure_strain() {
        let (sigma0, h) = (4e8, 2e9);
        let (d1, d2) = (0.1, 0.15);
        let m = hencky(Fracturing {
            plasticity: Some(J2 {
                flow: FlowStress::Linear {
                    yield_stress: sigma0,
                    hardening: h,
                },
                taylor_quinney: 0.0,
                specific_heat: 477.0,
            }),
            failure: Failure::JohnsonCook(JohnsonCookFailure {
                d1,
                d2,
                d3: -1.5,
                d4: 0.0,
                d5: 0.0,
                rate0: 1.0,
                t_room: 300.0,
                t_melt: 1800.0,
                nonlocal_radius: 0.0,
            }),
        });
        let mu = m.elastic.mu;
        let ef = d1 + d2;
        let (mut s, mut w, mut st) = (Matrix3::zeros(), 0.0, PlasticState::default());
        let mut f = Matrix3::identity();
        let da = 2e-3;
        let mut failed_at = None;
        for k in 1..=400 {
            let a = da * k as f64;
            let f1 = Matrix3::from_diagonal(&nalgebra::Vector3::new(a.exp(), (-a).exp(), 1.0));
            hencky_step(&m, &f, &f1, &mut s, &mut w, &mut st);
            f = f1;
            let eps_p = ((3.0 * mu * 2.0 * a / 3f64.sqrt() - sigma0) / (3.0 * mu + h)).max(0.0);
            if st.damage >= 1.0 {
                assert!(eps_p >= ef * (1.0 - 1e-9), "fails early at ε̄ₚ = {eps_p}");
                // Isochoric: no pressure to keep.
                assert!(s.norm() <= 1e-6 * sigma0, "{s}");
                failed_at = Some(k);
                break;
            }
            assert!(
                (st.plastic_strain - eps_p).abs() < 1e-12,
                "{} vs {eps_p}",
                st.plastic_strain
            );
            assert!(
                (st.damage - eps_p / ef).abs() < 1e-12,
                "{} vs {}",
                st.damage,
                eps_p / ef
            );
        }
        let k = failed_at.expect("the point fails");
        let a_prev = da * (k - 1) as f64;
        let eps_prev = (3.0 * mu * 2.0 * a_prev / 3f64.sqrt() - sigma0) / (3.0 * mu + h);
        assert!(eps_prev < ef, "the step before failure is short of ε_f");
    }

    #[test]
    fn bad_parameters_are_named() {
        let mut f = copper(0.9).failure;
        if let Failure::JohnsonCook(jc) = &mut f {
            jc.d1 = -5.0;
        }
        assert_eq!(f.validate().unwrap_err().key, "d1");
        let t = Failure::Tensile {
            spall_strength: -1.0,
        };
        assert_eq!(t.validate().unwrap_err().key, "spall_strength");
    }
}
