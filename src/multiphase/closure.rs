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
//! velocity `u_m = Σ_j Σ S m_jl ū_jl / Σ_j Σ S m_jl`, a uniform motion of
//! every phase gives `X = 0` to round-off under the weak constraint however
//! far Σθ is from one: the block-in-air test of Zhang Sec. 3.

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
        }
    }
}

/// The mismatch `X` of Eq. 2 at a point (see the module docs) for `n`
/// phases with coefficients `alpha`, time step `dt` (strong constraint
/// only).
pub fn mismatch<const D: usize>(
    s: &Stencil<D>,
    alpha: &[f64],
    constraint: Constraint,
    dt: f64,
) -> f64 {
    let n = alpha.len();
    let mut x = 0.0;
    let mut m_tot = 0.0;
    let mut p_tot = SVector::<f64, D>::zeros();
    let mut grad_sum = SVector::<f64, D>::zeros();
    for j in 0..n {
        if s.mass[j] <= 0.0 {
            // The phase has no mass in the stencil: θ_j = 0 on it.
            continue;
        }
        let u = s.momentum[j] / s.mass[j];
        // ∇·(θū) − α θ∇·ū with θ∇·ū = ∇·(θū) − ū·∇θ.
        x += (1.0 - alpha[j]) * s.div_theta_u[j] + alpha[j] * u.dot(&s.grad_theta[j]);
        m_tot += s.mass[j];
        p_tot += s.momentum[j];
        grad_sum += s.grad_theta[j];
    }
    match constraint {
        Constraint::Weak => {
            if m_tot > 0.0 {
                x -= (p_tot / m_tot).dot(&grad_sum);
            }
        }
        Constraint::Strong => x += (1.0 - s.theta_sum) / dt,
        Constraint::Eulerian => {}
    }
    x
}

/// The volumetric strain rate added to a particle's own `∇·ū_i` so that its
/// volume changes at `α_i ∇·ū_i + B_i` (Eq. 1): `(α_i − 1) ∇·ū_i + κ_p X /
/// Σθκ`, with κ_p the particle's compressibility.
pub fn extra_rate<const D: usize>(s: &Stencil<D>, alpha_own: f64, kappa: f64, x: f64) -> f64 {
    let b = if s.compressibility > 0.0 {
        kappa * x / s.compressibility
    } else {
        0.0
    };
    (alpha_own - 1.0) * s.div_own + b
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_phase(u: [SVector<f64, 2>; 2], theta_grad: SVector<f64, 2>) -> Stencil<2> {
        let mut s = Stencil::<2>::default();
        s.mass[0] = 2.0;
        s.mass[1] = 0.5;
        s.momentum[0] = u[0] * 2.0;
        s.momentum[1] = u[1] * 0.5;
        // Σθ not one and not uniform: the sampling error of Eq. 14.
        s.grad_theta[0] = theta_grad;
        s.grad_theta[1] = -theta_grad * 0.9;
        s.div_theta_u[0] = u[0].dot(&s.grad_theta[0]);
        s.div_theta_u[1] = u[1].dot(&s.grad_theta[1]);
        s.theta_sum = 0.97;
        s.compressibility = 1e-5;
        s
    }

    #[test]
    fn weak_constraint_sees_no_mismatch_in_a_uniform_motion() {
        let u = SVector::from([3.0, -4.0]);
        let s = two_phase([u, u], SVector::from([10.0, 7.0]));
        for alpha in [[1.0, 1.0], [0.0, 0.0], [0.3, 1.0]] {
            let w = mismatch(&s, &alpha, Constraint::Weak, 1e-6);
            assert!(w.abs() < 1e-13, "weak X = {w}");
            // The other two turn the sampling error into a volume rate.
            let e = mismatch(&s, &alpha, Constraint::Eulerian, 1e-6);
            assert!((e - u.dot(&SVector::from([1.0, 0.7]))).abs() < 1e-12);
            let st = mismatch(&s, &alpha, Constraint::Strong, 1e-6);
            assert!((st - e - 0.03 / 1e-6).abs() < 1e-6);
        }
    }

    #[test]
    fn encroaching_solid_compresses_the_gas() {
        // Phase 0 (solid) moves at +x into phase 1 (gas at rest); θ_solid
        // falls along +x at the solid's front.
        let mut s = Stencil::<2>::default();
        let g = SVector::from([-5.0, 0.0]);
        s.mass = [1.0, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        s.momentum[0] = SVector::from([2.0, 0.0]);
        s.grad_theta[0] = g;
        s.grad_theta[1] = -g;
        s.theta_sum = 1.0;
        s.compressibility = 0.5 * 1e-5;
        let x = mismatch(&s, &[1.0, 1.0], Constraint::Weak, 1.0);
        // (u_s − u_g)·∇θ_s ρ-weighted: negative, the gas loses volume.
        assert!(x < 0.0);
        let b_gas = extra_rate(&s, 1.0, 1e-5, x);
        assert!(b_gas < 0.0);
        // Exactly the relative-motion form Σ_j (ū_j − u_m)·∇θ_j.
        let um = s.momentum[0][0] / 1.1;
        let expect = (2.0 - um) * -5.0 + (0.0 - um) * 5.0;
        assert!((x - expect).abs() < 1e-12);
    }
}
