//! The volumetric split of Zhang's multiphase model (Zhang Eqs. 1–2) with
//! the volume-fraction constraint (Eq. 7 through Eq. 15, or the weak form
//! Eq. 18), evaluated at one material point.
//!
//! Each phase's volume changes at the rate `α_i ∇·ū_i + B_i` (Eq. 1). The
//! second part shares the mismatch of the phases' volume rates among them
//! in proportion to their compressibilities κ = 1/(ρ⁰c²) (Eq. 2):
//!
//! ```text
//! B_i = κ_i X / Σ_j θ_j κ_j,
//! X   = T + Σ_j [∇·(θ_j ū_j) − α_j θ_j ∇·ū_j],
//! ```
//!
//! where `T` is the rate of change of Σθ that the constraint asks for:
//! summing `∂θ_j/∂t + ∇·(θ_j ū_j) = θ_j (α_j ∇·ū_j + B_j)` over the phases
//! gives `∂(Σθ)/∂t = T`. Zhang's Eq. 2 as printed is `T = 0` (Σθ fixed in
//! the Eulerian frame, [`Constraint::Eulerian`]); enforcing Eq. 7 at every
//! step (Eq. 15) drives Σθ back to one, `T = (1 − Σθ)/Δt`
//! ([`Constraint::Strong`]); the weak form Eq. 18 keeps Σθ constant
//! following the mixture, `T = −u_m · ∇(Σθ)` ([`Constraint::Weak`]), so the
//! O((Δx)^d) error of the point-sampled Σθ (Eq. 14) is carried along instead
//! of turned into pressure.
//!
//! The discrete terms at a point `x_p` use the nodal θ_j (Eq. 13), masses
//! m_j and Lagrangian velocities ū_j with the particle's shape functions:
//! `∇θ_j = Σ_l θ_jl ∇S_l`, `∇·(θ_j ū_j) = Σ_l θ_jl ū_jl·∇S_l`, the
//! phase velocity at the point `ū_j(x_p) = Σ S_l m_jl ū_jl / Σ S_l m_jl`
//! (defined wherever the phase has mass in the stencil), and `θ_j ∇·ū_j`
//! as `∇·(θ_j ū_j) − ū_j(x_p)·∇θ_j`. With this last choice, and the mixture
//! velocity of [`node_rate`], a uniform motion of every phase gives `X = 0`
//! to round-off under the weak constraint however far Σθ is from one: the
//! block-in-air test of Zhang Sec. 3.

use nalgebra::SVector;
use serde::{Deserialize, Serialize};

/// Most phases of one scene.
pub const MAX_PHASES: usize = 8;

/// How the volume-fraction constraint sets the pressure (Zhang Sec. 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Constraint {
    /// Eq. 18: Σθ constant following the mixture (`T = −u_m·∇Σθ`).
    #[default]
    Weak,
    /// Eq. 7 through Eq. 15: Σθ driven to one at every step
    /// (`T = (1 − Σθ)/Δt`), the approach Zhang shows to fail.
    Strong,
    /// Eq. 2 as printed: Σθ constant at a fixed point (`T = 0`).
    Eulerian,
}

impl Constraint {
    /// The scene name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Weak => "weak",
            Self::Strong => "strong",
            Self::Eulerian => "eulerian",
        }
    }
}

/// Sums over one particle's stencil of every phase's nodal fields.
#[derive(Debug, Clone, Copy)]
pub struct Stencil<const D: usize> {
    /// Σ S_l m_jl per phase.
    pub mass: [f64; MAX_PHASES],
    /// Σ S_l m_jl ū_jl per phase.
    pub momentum: [SVector<f64, D>; MAX_PHASES],
    /// ∇θ_j = Σ θ_jl ∇S_l per phase.
    pub grad_theta: [SVector<f64, D>; MAX_PHASES],
    /// ∇·(θ_j ū_j) = Σ θ_jl ū_jl·∇S_l per phase.
    pub div_theta_u: [f64; MAX_PHASES],
    /// Σθ at the point, Σ_l S_l Σ_j θ_jl.
    pub theta_sum: f64,
    /// Σ_j θ_j κ_j at the point.
    pub compressibility: f64,
    /// ∇·ū_i of the particle's own phase.
    pub div_own: f64,
    /// Σ_l S_l Y_l / Σθκ_l: the nodal interface rate per unit
    /// compressibility at the point ([`node_rate`]).
    pub node_share: f64,
    /// r–z: the own phase's radial velocity at the point, Σ S_l ū_l,r.
    pub radial_own: f64,
    /// r–z: Σ S_l θ_jl ū_jl,r per phase.
    pub radial_theta_u: [f64; MAX_PHASES],
}

impl<const D: usize> Default for Stencil<D> {
    fn default() -> Self {
        Self {
            mass: [0.0; MAX_PHASES],
            momentum: [SVector::zeros(); MAX_PHASES],
            grad_theta: [SVector::zeros(); MAX_PHASES],
            div_theta_u: [0.0; MAX_PHASES],
            theta_sum: 0.0,
            compressibility: 0.0,
            div_own: 0.0,
            node_share: 0.0,
            radial_own: 0.0,
            radial_theta_u: [0.0; MAX_PHASES],
        }
    }
}

impl<const D: usize> Stencil<D> {
    /// In r–z the divergences carry the hoop rate `u_r / r` at the point's
    /// radius `r`: `∇·ū = ∂u_r/∂r + ∂u_z/∂z + u_r/r`, and likewise for
    /// `∇·(θ ū)`.
    pub fn add_hoop(&mut self, r: f64) {
        let inv_r = 1.0 / r;
        self.div_own += self.radial_own * inv_r;
        for (d, q) in self.div_theta_u.iter_mut().zip(self.radial_theta_u) {
            *d += q * inv_r;
        }
    }
}

/// The interface part of Eq. 2's mismatch on one node, from the phases'
/// nodal velocities `u` (MUSL-remapped), volume fractions `theta` and volume gradients
/// `g_i = Σ_p v_p ∇S_l(x_p)` (≈ −V ∇θ_i, the same vectors that carry the
/// gas pressure's force `−p_g g_i`), for node volume `v`:
///
/// ```text
/// Y = −(1/V) Σ_i (ū_i − w)·g_i  (+ (1 − Σθ)/Δt, strong)
/// ```
///
/// ≈ `Σ_i (ū_i − w)·∇θ_i`, with `w` = the mixture velocity `u_m` (weak,
/// Eq. 18: `−u_m·∇Σθ`) or zero (Eulerian, strong). Zhang leaves `u_m`
/// open; it is the volume-weighted `Σ θ_i ū_i / Σ θ_i` here: the sampling
/// error of Σθ is carried by the phase that holds the volume. The
/// mass-weighted velocity let a heavy phase's few points carry the light
/// phase's error: a tungsten square sliding through still air (19 000 : 1)
/// compressed the air steadily, 2.7 % of its volume by 3.8 ms, gaining
/// 1.8e-4 of the energy; volume-weighted, 3.9e-5. Built from the force's
/// own vectors, the volume it hands the phases does exactly the work the
/// force does: Σ_l p_g,l V Y_l = −Σ_l p_g,l Σ_i ū_i·g_i when Σ_i g_i = 0
/// (Σθ uniform), so the pressure exchange across an interface neither makes
/// nor loses energy. A uniform motion gives `Y = 0` exactly (weak).
pub fn node_rate<const D: usize>(
    u: &[SVector<f64, D>],
    theta: &[f64],
    g: &[SVector<f64, D>],
    theta_sum: f64,
    volume: f64,
    constraint: Constraint,
    dt: f64,
) -> f64 {
    let mut w = SVector::<f64, D>::zeros();
    if constraint == Constraint::Weak {
        let vt: f64 = theta.iter().sum();
        if vt > 0.0 {
            for (ui, &ti) in u.iter().zip(theta) {
                w += ui * ti;
            }
            w /= vt;
        }
    }
    let mut y = 0.0;
    for ((ui, &ti), gi) in u.iter().zip(theta).zip(g) {
        if ti > 0.0 {
            y -= (ui - w).dot(gi);
        }
    }
    y /= volume;
    if constraint == Constraint::Strong {
        y += (1.0 - theta_sum) / dt;
    }
    y
}

/// The part of Eq. 2's mismatch from phases with α < 1 at a point:
/// `Σ_j (1 − α_j) θ_j ∇·ū_j` with `θ_j ∇·ū_j = ∇·(θ_j ū_j) − ū_j(x_p)·∇θ_j`
/// (zero for a uniform motion).
pub fn dispersed<const D: usize>(s: &Stencil<D>, alpha: &[f64]) -> f64 {
    let mut x = 0.0;
    for (j, &a) in alpha.iter().enumerate() {
        if a < 1.0 && s.mass[j] > 0.0 {
            let u = s.momentum[j] / s.mass[j];
            x += (1.0 - a) * (s.div_theta_u[j] - u.dot(&s.grad_theta[j]));
        }
    }
    x
}

/// The volumetric strain rate added to a particle's own `∇·ū_i` so that its
/// volume changes at `α_i ∇·ū_i + B_i` (Eq. 1): `(α_i − 1) ∇·ū_i + κ_p (Σ_l
/// S_l Y_l / Σθκ_l + X_dispersed / Σθκ(x_p))`, with κ_p the particle's
/// compressibility and `s.node_share = Σ_l S_l Y_l / Σθκ_l`. Where the
/// point's share `r = κ_p / Σθκ(x_p)` exceeds `c = max_share` (a vanishing
/// phase, `multiphase.min_fraction`), B_i is scaled to the share
/// `c (2 − r/c)`, falling to zero at `r = 2c`.
pub fn extra_rate<const D: usize>(
    s: &Stencil<D>,
    alpha_own: f64,
    kappa: f64,
    dispersed: f64,
    max_share: f64,
) -> f64 {
    let b = if s.compressibility > 0.0 {
        dispersed / s.compressibility
    } else {
        0.0
    };
    // The share r = κ_p / Σθκ up to the cap c; tapered to zero between c
    // and 2c (continuous), zero beyond: a vanishing phase's points follow
    // their own flow.
    let limit = max_share * s.compressibility;
    let scale = if kappa > limit && kappa > 0.0 {
        (limit / kappa * (2.0 - kappa / limit)).max(0.0)
    } else {
        1.0
    };
    (alpha_own - 1.0) * s.div_own + kappa * scale * (s.node_share + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weak_constraint_sees_no_mismatch_in_a_uniform_motion() {
        let u = SVector::from([3.0, -4.0]);
        // Volume gradients that do not cancel: Σθ not uniform (Eq. 14).
        let g = [SVector::from([10.0, 7.0]), SVector::from([-9.0, -6.3])];
        let m = [2.0, 0.5];
        let y = node_rate(&[u, u], &m, &g, 0.97, 0.5, Constraint::Weak, 1e-6);
        assert!(y.abs() < 1e-13, "weak Y = {y}");
        // Eq. 2 as printed turns the sampling error into a volume rate,
        // Eq. 15 adds (1 − Σθ)/Δt.
        let e = node_rate(&[u, u], &m, &g, 0.97, 0.5, Constraint::Eulerian, 1e-6);
        assert!((e + u.dot(&(g[0] + g[1])) / 0.5).abs() < 1e-12);
        let st = node_rate(&[u, u], &m, &g, 0.97, 0.5, Constraint::Strong, 1e-6);
        assert!((st - e - 0.03 / 1e-6).abs() < 1e-6);
    }

    #[test]
    fn a_vanishing_phase_takes_a_capped_then_no_share() {
        // Σθκ = 1, node share 2: a point of κ_p takes κ_p · 2 uncapped.
        let s = Stencil::<2> {
            compressibility: 1.0,
            node_share: 2.0,
            ..Default::default()
        };
        let rate = |kappa: f64| extra_rate(&s, 1.0, kappa, 0.0, 5.0);
        // Below the cap (share 5): unchanged.
        assert!((rate(4.0) - 8.0).abs() < 1e-12);
        // At the cap, at 1.5 × and at twice it: share c(2 − r/c) = 5, 2.5, 0.
        assert!((rate(5.0) - 10.0).abs() < 1e-12);
        assert!((rate(7.5) - 5.0).abs() < 1e-12);
        assert!(rate(10.0).abs() < 1e-12 && rate(40.0).abs() < 1e-12);
        // No cap: Zhang's closure.
        assert!((extra_rate(&s, 1.0, 40.0, 0.0, f64::INFINITY) - 80.0).abs() < 1e-12);
    }

    #[test]
    fn encroaching_solid_compresses_the_gas() {
        // Phase 0 (solid) moves at +x into phase 1 (gas at rest) on a node
        // ahead of the solid: θ_solid falls along +x, so its volume
        // gradient g = −V∇θ points along +x.
        let g = [SVector::from([5.0, 0.0]), SVector::from([-5.0, 0.0])];
        let u = [SVector::from([2.0, 0.0]), SVector::zeros()];
        let y = node_rate(&u, &[1.0, 0.1], &g, 1.0, 1.0, Constraint::Weak, 1.0);
        // The gas loses volume at the rate the solid sweeps: −2 × 5.
        assert!((y + 10.0).abs() < 1e-12, "{y}");
        // Dispersed phases add nothing in a uniform motion.
        let mut s = Stencil::<2>::default();
        s.mass[0] = 1.0;
        s.momentum[0] = SVector::from([3.0, 1.0]);
        s.grad_theta[0] = SVector::from([2.0, -1.0]);
        s.div_theta_u[0] = 3.0 * 2.0 - 1.0;
        assert!(dispersed(&s, &[0.0]).abs() < 1e-14);
    }
}
