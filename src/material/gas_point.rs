//! Compressible viscous gas on material points (York Sec. 3.3).
//!
//! A gas point is an MPM particle whose material computes a fluid stress
//! (York Eq. 21, Stokes condition)
//!
//! ```text
//! σ = 2μ ε̇′ − (p + q) I,      ε̇′ = ε̇ − (tr ε̇ / 3) I,
//! ```
//!
//! with `p` from the fluid equation of state ([`FluidEos`]: the ideal gas of
//! York Eq. 22, a stiffened gas, Mie–Grüneisen or JWL) at the point's
//! density and specific
//! internal energy (`e = c_v T`), the density from continuity (York Eq. 16,
//! `ρ = m / V`, `V = J V⁰`), the internal energy advanced per point (York
//! Eq. 23) and the Wilkins-type artificial viscosity `q` in compression only
//! (York Eqs. 24–25).
//!
//! # Reading of York Eq. 24
//!
//! The OCR copy of the paper loses the layout of Eq. 24 and prints "√" as
//! "(" (compare Eq. 27, `ω − √([K + ρωcA cot(ωL/c)]/m) = 0`, and "c is the
//! wave speed √(b/ρ)"). We implement the Wilkins form (one linear and one
//! quadratic term, both ∝ `ρ κ̃ g |D|`)
//!
//! ```text
//! q = κ̃ ρ g |D| (c₁ c_max + c₂ g |D|),   D = ∇·v if ∇·v < 0, else 0  (Eq. 25)
//! ```
//!
//! with `c_max` the largest sound speed among the gas points and `g` the
//! geometric length. With the paper's constants c₁ = c₂ = 1 the assignment
//! of c₁ and c₂ to the two terms does not matter. The paper's `g` reads
//! "g = (2 dx", i.e. `g = √2 Δx` (the diagonal of a square element), which
//! is the default here ([`ArtificialViscosity::DEFAULT_G_OVER_DX`]).
//!
//! # Energy update
//!
//! York Eq. 23 adds `σⁿ⁺¹ : Δε / ρⁿ⁺¹` to the specific internal energy. We
//! use the same step with the thermodynamic pressure time-centred,
//! `Δe = −((pⁿ + pⁿ⁺¹)/2 + q) Δv + 2μ ε̇′:ε̇′ Δt / ρⁿ⁺¹` (`v = 1/ρ`),
//! which every fluid EOS makes linear in `eⁿ⁺¹` (p is linear in e at fixed
//! ρ), so it
//! is solved exactly without iteration. It is second order in time and keeps
//! an isentropic compression on its isentrope; `q` is taken at the new
//! level as in the paper.

use nalgebra::Matrix3;

use super::eos::{EquationOfState, FluidEos};

/// The Wilkins-type artificial viscosity of York Eqs. 24–25.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArtificialViscosity {
    /// Geometric length g \[m\] (York: `√2 Δx`).
    pub g: f64,
    /// Artificial bulk coefficient κ̃ ≥ 0 (York: 0.75).
    pub kappa: f64,
    /// Coefficient of the linear (sound-speed) term c₁ ≥ 0 (York: 1).
    pub c1: f64,
    /// Coefficient of the quadratic term c₂ ≥ 0 (York: 1).
    pub c2: f64,
}

impl ArtificialViscosity {
    /// York's `g / Δx` (Sec. 4.1: `g = √2 dx`).
    pub const DEFAULT_G_OVER_DX: f64 = std::f64::consts::SQRT_2;
    /// York's κ̃ (Sec. 4.1).
    pub const DEFAULT_KAPPA: f64 = 0.75;
    /// York's c₁ (Sec. 4.1).
    pub const DEFAULT_C1: f64 = 1.0;
    /// York's c₂ (Sec. 4.1).
    pub const DEFAULT_C2: f64 = 1.0;

    /// York Eqs. 24–25: `q` at density `rho` and velocity divergence `div`
    /// (zero unless the point is in compression).
    #[inline]
    pub fn q(&self, rho: f64, div: f64, c_max: f64) -> f64 {
        // York Eq. 25: D = ∇·v in compression, 0 in expansion.
        let d = (-div).max(0.0);
        // York Eq. 24 (Wilkins: linear + quadratic).
        self.kappa * rho * self.g * d * (self.c1 * c_max + self.c2 * self.g * d)
    }

    /// The kinematic viscosity `q / (ρ |D|)` that `q` acts with at the
    /// (compressive) divergence magnitude `d` [m²/s].
    #[inline]
    pub fn kinematic(&self, d: f64, c_max: f64) -> f64 {
        self.kappa * self.g * (self.c1 * c_max + self.c2 * self.g * d)
    }

    /// The compressive divergence magnitude `|D|` at which `q` takes the
    /// value `q` (the positive root of Eq. 24 in `|D|`); 0 for `q ≤ 0`.
    #[inline]
    pub fn divergence_of(&self, q: f64, rho: f64, c_max: f64) -> f64 {
        if q <= 0.0 || self.kappa <= 0.0 || self.g <= 0.0 {
            return 0.0;
        }
        let s = q / (self.kappa * rho * self.g);
        let (a, b) = (self.c2 * self.g, self.c1 * c_max);
        if a > 0.0 {
            (-b + (b * b + 4.0 * a * s).sqrt()) / (2.0 * a)
        } else if b > 0.0 {
            s / b
        } else {
            0.0
        }
    }
}

/// Where a gas point's density comes from at the start of each step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PointDensity {
    /// York Eq. 16: `ρ = m / V`, `V = J V⁰`, J carried by the point and
    /// advanced by `det(I + Δt L)` every step.
    #[default]
    Continuity,
    /// The gas's own density on the grid: the nodal mass of the points of
    /// every gas material that reads it, `m_i = Σ_p S_ip m_p` (folded at the
    /// walls like the nodal mass), over the node's share of the domain
    /// `V_i` (`∫_Ω S_i dV` as a lattice of points seeded like the scene's
    /// samples it, folded likewise; per radian in r–z), interpolated back,
    /// `ρ_p = Σ_i S_ip m_i / V_i`: exact for a uniform gas so seeded,
    /// whatever volumes and J its points carry. The step then advances it
    /// by continuity, `J = (ρ_ref / ρ_p) det(I + Δt L)`. A point's J
    /// otherwise measures only its own history: FLIP lets points crowd and
    /// part without their volumes following, so the carried volumes of an
    /// expanding gas come to exceed the space it fills (issue 16's
    /// dog-bone: Σ V_p 3.5 times the enclosed area by t = 4 at h = 0.2).
    /// An ideal gas's nodal force `(γ − 1) m e ∇S`
    /// and energy update do not read ρ; its pressure reading, `q`, the
    /// viscous stress and the time-step limits do. Near a wall, another
    /// material or a free surface the gas's nodes are part-filled and read
    /// low; another EOS's forces would feel that, so the scene accepts this
    /// for the ideal gas only.
    Grid,
}

impl PointDensity {
    /// The scene's name (`point_density`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Continuity => "continuity",
            Self::Grid => "grid",
        }
    }
}

/// A gas on material points: equation of state, shear viscosity and
/// artificial viscosity (York Sec. 3.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GasPoint {
    /// Equation of state (York Eq. 22 for the ideal gas), with `e = c_v T`.
    pub eos: FluidEos,
    /// Shear viscosity μ ≥ 0 (York Eq. 21, Stokes condition λ = −2μ/3).
    pub viscosity: f64,
    /// Artificial viscosity (York Eqs. 24–25).
    pub q: ArtificialViscosity,
    /// Pressure floor \[Pa\]: the EOS's pressure is taken as at least this
    /// (Lian Eq. 66 sets a liquid's pressure to 0 in tension, so that it can
    /// break up); `f64::NEG_INFINITY` for none.
    pub min_pressure: f64,
    /// Where the point's density comes from ([`PointDensity`]).
    pub density: PointDensity,
}

/// The per-point inputs of a gas-point update beyond its velocity gradient.
#[derive(Debug, Clone, Copy)]
pub struct GasStep {
    /// Density at the start of the step ρⁿ.
    pub rho_old: f64,
    /// Density at the end of the step ρⁿ⁺¹ (York Eq. 16).
    pub rho_new: f64,
    /// Time step Δt.
    pub dt: f64,
    /// Largest sound speed among the gas points (York Eq. 24).
    pub c_max: f64,
}

impl GasPoint {
    /// Thermodynamic pressure at density `rho` and specific internal energy
    /// `e` (York Eq. 22 for the ideal gas).
    #[inline]
    pub fn pressure(&self, rho: f64, e: f64) -> f64 {
        self.eos
            .pressure(rho, self.eos.temperature(e))
            .max(self.min_pressure)
    }

    /// Sound speed at `rho`, `e` (0 where the state has none).
    #[inline]
    pub fn sound_speed(&self, rho: f64, e: f64) -> f64 {
        self.eos
            .sound_speed_sq(rho, self.eos.temperature(e))
            .max(0.0)
            .sqrt()
    }

    /// Specific internal energy at which the EOS gives pressure `p` at
    /// density `rho` (every fluid EOS is linear in e at fixed ρ; a
    /// Mie–Grüneisen fluid needs Γ₀ > 0, which the scene checks).
    pub fn energy_of(&self, rho: f64, p: f64) -> f64 {
        let cv = self.eos.specific_heat_cv();
        let (t0, t1) = (1.0, 2.0);
        let (p0, p1) = (self.eos.pressure(rho, t0), self.eos.pressure(rho, t1));
        cv * (t0 + (p - p0) * (t1 - t0) / (p1 - p0))
    }

    /// Advances one gas point over a step with velocity gradient `l`:
    /// returns the new stress (York Eq. 21) and specific internal energy
    /// (York Eq. 23, time-centred pressure; see the module notes), and the
    /// artificial viscosity `q` used (York Eqs. 24–25).
    ///
    /// Kept out of line: inlined into the particle update it made the solid
    /// paths of that loop slower (two_disks, neo-Hookean: 9.2e6 → 8.0e6
    /// particle-steps/s).
    #[inline(never)]
    pub fn update(&self, l: &Matrix3<f64>, e_old: f64, s: &GasStep) -> (Matrix3<f64>, f64, f64) {
        let d = 0.5 * (l + l.transpose());
        let div = d.trace();
        let dev = d - Matrix3::identity() * (div / 3.0);
        // York Eqs. 24–25 at the new density.
        let q = self.q.q(s.rho_new, div, s.c_max);
        // York Eq. 23: Δe = −(p̄ + q) Δv + 2μ ε̇′:ε̇′ Δt / ρ, with p̄ the
        // time-centred pressure and p linear in e at fixed ρ:
        // pⁿ⁺¹ = p* + a (eⁿ⁺¹ − eⁿ), p* = p(ρⁿ⁺¹, eⁿ).
        let dv = 1.0 / s.rho_new - 1.0 / s.rho_old;
        let p_old = self.pressure(s.rho_old, e_old);
        // The EOS's own p* (not floored): the linear step stays on the EOS,
        // and only its result is held at the floor.
        let t_old = self.eos.temperature(e_old);
        let p_star = self.eos.pressure(s.rho_new, t_old);
        let a = self.eos.dp_dt(s.rho_new, t_old) / self.eos.specific_heat_cv();
        let heat = 2.0 * self.viscosity * dev.component_mul(&dev).sum() * s.dt / s.rho_new;
        let mut de = (-(0.5 * (p_old + p_star) + q) * dv + heat) / (1.0 + 0.5 * a * dv);
        let mut p_new = p_star + a * de;
        if p_new < self.min_pressure {
            // On the floor the pressure no longer follows e: the work is
            // done at the floor's pressure.
            p_new = self.min_pressure;
            de = -(0.5 * (p_old + p_new) + q) * dv + heat;
        }
        let e_new = e_old + de;
        // York Eq. 21 (Stokes condition: the spherical part is −(p + q)).
        let sigma = dev * (2.0 * self.viscosity) - Matrix3::identity() * (p_new + q);
        (sigma, e_new, q)
    }

    /// The artificial viscosity a point carries in its stress: `−tr σ / 3 −
    /// p(ρ, e)` (York Eq. 21: the viscous part is traceless), never negative.
    #[inline]
    pub fn q_of(&self, stress: &Matrix3<f64>, rho: f64, e: f64) -> f64 {
        (-stress.trace() / 3.0 - self.pressure(rho, e)).max(0.0)
    }

    /// The largest stable explicit step of a point in a cell of smallest
    /// size `h`: `h / (|v| + Q + √(Q² + c²))` with `Q = 2ν/h` and `ν` the
    /// kinematic viscosity of the shear (4μ/3ρ) and artificial (York Eq. 24)
    /// terms together — the sound-speed limit with the diffusion limit
    /// `Δt ≤ h²/2ν` folded in.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn dt_limit(
        &self,
        h: f64,
        rho: f64,
        e: f64,
        stress: &Matrix3<f64>,
        speed: f64,
        c_max: f64,
    ) -> f64 {
        let c = self.sound_speed(rho, e);
        let q = self.q_of(stress, rho, e);
        let nu_q = if q > 0.0 {
            self.q.kinematic(self.q.divergence_of(q, rho, c_max), c_max)
        } else {
            0.0
        };
        let nu = 4.0 * self.viscosity / (3.0 * rho) + nu_q;
        let big_q = 2.0 * nu / h;
        h / (speed + big_q + (big_q * big_q + c * c).sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::eos::IdealGas;

    fn air() -> GasPoint {
        GasPoint {
            eos: IdealGas::new(1.4, 717.5).unwrap().into(),
            viscosity: 0.0,
            q: ArtificialViscosity {
                g: 0.01,
                kappa: 0.75,
                c1: 1.0,
                c2: 1.0,
            },
            min_pressure: f64::NEG_INFINITY,
            density: PointDensity::Continuity,
        }
    }

    #[test]
    fn energy_of_inverts_pressure() {
        let g = air();
        let e = g.energy_of(1.2, 1.0e5);
        assert!((g.pressure(1.2, e) / 1.0e5 - 1.0).abs() < 1e-14);
    }

    #[test]
    fn a_pressure_floor_holds_a_stretched_liquid_at_it_and_does_its_work() {
        // Lian Eq. 66: water stretched below ρ₀ has p = 0. On the floor
        // the energy changes by −(p̄ + q) Δv with p̄ = ½ (pⁿ + 0); q is 0 in
        // expansion.
        use crate::material::mie_gruneisen::MieGruneisen;
        let mut g = air();
        g.eos = MieGruneisen::new(1000.0, 1647.0, 1.921, 0.1, 4180.0, 300.0, 0.0)
            .unwrap()
            .into();
        let e0 = g.energy_of(1000.0, 0.0);
        let free = g.eos.pressure(999.0, g.eos.temperature(e0));
        assert!(free < -1e6, "the EOS's own tension {free}");
        g.min_pressure = 0.0;
        assert_eq!(g.pressure(999.0, e0), 0.0);
        // A point at 2 kPa stretched to 999 kg/m³ in one step.
        let e1 = g.energy_of(1000.0, 2.0e3);
        let step = GasStep {
            rho_old: 1000.0,
            rho_new: 999.0,
            dt: 1e-6,
            c_max: 1647.0,
        };
        let l = Matrix3::from_diagonal_element(1.0e-3 / 3.0 / 1e-6);
        let (sigma, e2, q) = g.update(&l, e1, &step);
        assert_eq!(q, 0.0);
        assert_eq!(sigma.trace(), 0.0);
        let dv = 1.0 / 999.0 - 1.0 / 1000.0;
        assert!((e2 - (e1 - 0.5 * 2.0e3 * dv)).abs() < 1e-12 * e1);
    }

    #[test]
    fn q_is_zero_in_expansion_and_its_divergence_inverts() {
        let g = air();
        assert_eq!(g.q.q(1.0, 3.0, 340.0), 0.0);
        let q = g.q.q(1.0, -30.0, 340.0);
        assert!(q > 0.0);
        assert!((g.q.divergence_of(q, 1.0, 340.0) - 30.0).abs() < 1e-10);
    }

    #[test]
    fn adiabatic_compression_follows_the_isentrope() {
        // Uniform compression with q off: p ρ^-γ stays constant to O(Δt²).
        let mut g = air();
        g.q.kappa = 0.0;
        let (mut rho, mut e) = (1.0, g.energy_of(1.0, 1.0e5));
        let rate = -0.5; // ∇·v [1/s]
        let n = 1000;
        let dt = 1.0 / n as f64;
        for _ in 0..n {
            let l = Matrix3::from_diagonal_element(rate / 3.0);
            let rho_new = rho / (1.0 + rate * dt);
            let step = GasStep {
                rho_old: rho,
                rho_new,
                dt,
                c_max: 340.0,
            };
            let (_, e_new, _) = g.update(&l, e, &step);
            rho = rho_new;
            e = e_new;
        }
        let s0 = 1.0e5;
        let s1 = g.pressure(rho, e) / rho.powf(1.4);
        assert!((s1 / s0 - 1.0).abs() < 1e-6, "{}", s1 / s0 - 1.0);
    }
}
