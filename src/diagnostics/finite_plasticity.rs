//! Simple shear of one point of the Hencky model with J2 plasticity
//! ([`crate::material::hencky`]): F = I + γ e₁⊗e₂ to γ_end in equal steps.
//! The principal axes of bₑ turn with γ, so (unlike uniaxial strain or pure
//! shear, where the exponential-map return is exact) the update has a
//! step-size error; the `hencky_simple_shear` study measures its order
//! against a run of many more steps.

use nalgebra::Matrix3;

use crate::material::hencky;
use crate::material::plasticity::{PlasticState, J2};

/// The state at γ_end of a simple-shear run.
#[derive(Debug, Clone, Copy)]
pub struct ShearEnd {
    /// Kirchhoff shear stress τ₁₂.
    pub tau_xy: f64,
    /// Normal stress difference τ₁₁ − τ₂₂ (the Poynting effect).
    pub normal_difference: f64,
    /// Equivalent plastic strain ε̄.
    pub plastic_strain: f64,
}

/// Runs simple shear to `gamma_end` in `steps` equal steps with Lamé
/// constants `lambda`, `mu` and the plasticity `j2` (`None`: elastic), the
/// steps spread over a unit time (the rate enters a rate-dependent flow
/// stress only). `None` when a step inverts.
pub fn simple_shear(
    lambda: f64,
    mu: f64,
    j2: Option<&J2>,
    gamma_end: f64,
    steps: usize,
) -> Option<ShearEnd> {
    let mut tau = Matrix3::zeros();
    let mut state = PlasticState::default();
    let dg = gamma_end / steps as f64;
    // F_{k+1} F_k⁻¹ = I + Δγ e₁⊗e₂ for simple shear.
    let mut f_rel = Matrix3::identity();
    f_rel[(0, 1)] = dg;
    let dt = 1.0 / steps as f64;
    for k in 1..=steps {
        let mut f = Matrix3::identity();
        f[(0, 1)] = dg * k as f64;
        tau = hencky::step(
            lambda, mu, j2, &f_rel, &f, &tau, dt, 7800.0, &mut state, None,
        )?
        .tau;
    }
    Some(ShearEnd {
        tau_xy: tau[(0, 1)],
        normal_difference: tau[(0, 0)] - tau[(1, 1)],
        plastic_strain: state.plastic_strain,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::plasticity::FlowStress;

    /// Elastic simple shear is exact at any step count (bₑ = F Fᵀ), and
    /// the plastic run converges at first order in the step.
    #[test]
    fn elastic_is_exact_and_plastic_converges_at_first_order() {
        let (lambda, mu) = (1.5, 1.0);
        let e1 = simple_shear(lambda, mu, None, 1.0, 1).unwrap();
        let e64 = simple_shear(lambda, mu, None, 1.0, 64).unwrap();
        assert!((e1.tau_xy - e64.tau_xy).abs() < 1e-13);
        let j2 = J2 {
            flow: FlowStress::Linear {
                yield_stress: 0.01,
                hardening: 0.1,
            },
            taylor_quinney: 0.0,
            specific_heat: 1.0,
        };
        let r = simple_shear(lambda, mu, Some(&j2), 1.0, 1 << 14).unwrap();
        let err =
            |n| (simple_shear(lambda, mu, Some(&j2), 1.0, n).unwrap().tau_xy - r.tau_xy).abs();
        let (a, b) = (err(32), err(64));
        let order = (a / b).log2();
        assert!((0.9..1.2).contains(&order), "order {order} ({a:e}, {b:e})");
    }
}
