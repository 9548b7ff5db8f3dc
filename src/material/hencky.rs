//! Hencky (logarithmic-strain) hyperelasticity, and J2 plasticity in the
//! multiplicative split F = Fₑ Fₚ (Simo 1992, *CMAME* 99, 61–112; de Souza
//! Neto, Perić & Owen, *Computational Methods for Plasticity*, Sec. 14.5).
//!
//! **Elastic law.** With the elastic left Cauchy–Green tensor bₑ = Fₑ Fₑᵀ
//! and the logarithmic strain εₑ = ½ ln bₑ, the Kirchhoff stress is
//! τ = λ tr(εₑ) I + 2μ εₑ = J σ, from the stored energy
//! W = ½ λ (tr εₑ)² + μ εₑ : εₑ (per unit reference volume). Without
//! plasticity Fₑ = F.
//!
//! **One step** (the exponential map of de Souza Neto Box 14.3), from the
//! step's relative deformation gradient f = Fⁿ⁺¹ (Fⁿ)⁻¹:
//! 1. the elastic strain at the start of the step is recovered from the
//!    stored stress, εₑⁿ = dev τⁿ/(2μ) + tr τⁿ/(9K) I (the elastic law
//!    inverted; K = λ + 2μ/3), so the particle stores no more than F, σ and
//!    ε̄; bₑⁿ = exp(2εₑⁿ);
//! 2. elastic trial bₑᵗʳ = f bₑⁿ fᵀ, εᵗʳ = ½ ln bₑᵗʳ (principal values and
//!    axes of bₑᵗʳ), τᵗʳ = λ tr εᵗʳ I + 2μ εᵗʳ;
//! 3. the small-strain radial return of [`J2::return_map`] on τᵗʳ in those
//!    axes (the yield condition is on the Kirchhoff stress, and plastic flow
//!    is isochoric, det Fₚ = 1);
//! 4. τⁿ⁺¹ in the trial axes, σ = τ/J.
//!
//! Where the principal axes of bₑ do not turn (uniaxial strain, pure shear,
//! any coaxial path) the update is the small-strain return in logarithmic
//! strains, which is exact for linear hardening at any step size; the tests
//! check that to round-off against the closed forms.
//!
//! **Consistent tangent** ([`Tangent`]): the derivative 𝔸 = ∂τ/∂h of the
//! algorithmic Kirchhoff stress under a spatial perturbation
//! Fⁿ⁺¹ → (I + h) Fⁿ⁺¹, which gives Newton's stiffness
//! `K_ij^ac = V⁰ (𝔸_abcd ∂_b N_i ∂_d N_j − τ_ab ∂_b N_j ∂_c N_i)`
//! ([`crate::mpm::ImplicitRun`]). In the principal axes of bₑᵗʳ (values
//! Bᵢ): δτ̂_ii = Σ_k D_ik ĥ_kk with D the small-strain consistent moduli
//! (de Souza Neto Eq. 7.120 restricted to principal values), and for i ≠ j
//! δτ̂_ij = (τᵢ − τⱼ)/(Bᵢ − Bⱼ) (ĥ_ij Bⱼ + Bᵢ ĥ_ji), the derivative of an
//! isotropic tensor function, where (τᵢ − τⱼ)/(Bᵢ − Bⱼ) = μ s (ln Bᵢ −
//! ln Bⱼ)/(Bᵢ − Bⱼ) with s the radial-return scale, computed without
//! cancellation as Bᵢ → Bⱼ.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use super::plasticity::{PlasticState, Return, J2};

/// ∂τ/∂h: `a[c][d]` is the change of τ per unit h = e_c ⊗ e_d.
pub type Tangent = [[Matrix3<f64>; 3]; 3];

/// The elastic logarithmic strain εₑ whose Hencky stress is the Kirchhoff
/// stress `tau`: dev τ/(2μ) + tr τ/(9K) I.
#[inline]
pub fn elastic_strain(tau: &Matrix3<f64>, lambda: f64, mu: f64) -> Matrix3<f64> {
    let k = lambda + 2.0 * mu / 3.0;
    let mean = tau.trace() / 3.0;
    (tau - Matrix3::identity() * mean) / (2.0 * mu) + Matrix3::identity() * (mean / (3.0 * k))
}

/// Stored energy W = ½ τ : εₑ per unit reference volume at Kirchhoff stress
/// `tau`.
#[inline]
pub fn stored_energy(tau: &Matrix3<f64>, lambda: f64, mu: f64) -> f64 {
    // ½ τ : εₑ = dev τ : dev τ/(4μ) + (tr τ)²/(18K), with
    // dev τ : dev τ = τ : τ − (tr τ)²/3.
    let k = lambda + 2.0 * mu / 3.0;
    let tr = tau.trace();
    (tau.norm_squared() - tr * tr / 3.0) / (4.0 * mu) + tr * tr / (18.0 * k)
}

/// Eigenvalues and eigenvectors (columns) of a symmetric 3×3 tensor. In
/// plane strain and r–z the tensors here have no (1,3), (2,3) coupling, so
/// that block is solved in closed form (one Jacobi rotation), which costs a
/// fraction of the general iterative solver used otherwise.
#[inline]
fn sym_eigen(m: &Matrix3<f64>) -> (Vector3<f64>, Matrix3<f64>) {
    if m[(0, 2)] == 0.0 && m[(1, 2)] == 0.0 && m[(2, 0)] == 0.0 && m[(2, 1)] == 0.0 {
        let (a, b, d) = (m[(0, 0)], m[(0, 1)], m[(1, 1)]);
        if b == 0.0 {
            return (Vector3::new(a, d, m[(2, 2)]), Matrix3::identity());
        }
        // The rotation by θ with tan 2θ = 2b/(a − d) diagonalises the block.
        let theta = 0.5 * (2.0 * b).atan2(a - d);
        let (sn, cs) = theta.sin_cos();
        let l1 = a * cs * cs + 2.0 * b * cs * sn + d * sn * sn;
        let l2 = a * sn * sn - 2.0 * b * cs * sn + d * cs * cs;
        let q = Matrix3::new(cs, -sn, 0.0, sn, cs, 0.0, 0.0, 0.0, 1.0);
        return (Vector3::new(l1, l2, m[(2, 2)]), q);
    }
    let e = SymmetricEigen::new(*m);
    (e.eigenvalues, e.eigenvectors)
}

/// (ln a − ln b)/(a − b) for a, b > 0, without cancellation as a → b.
#[inline]
fn log_slope(a: f64, b: f64) -> f64 {
    let x = (a - b) / b;
    if x.abs() < 1e-4 {
        // ln(1 + x)/x = 1 − x/2 + x²/3 − x³/4 …
        (1.0 - x * (0.5 - x * (1.0 / 3.0 - 0.25 * x))) / b
    } else {
        (a / b).ln() / (a - b)
    }
}

/// What one step gives.
#[derive(Debug, Clone, Copy)]
pub struct Step {
    /// Kirchhoff stress τ = J σ at the end of the step.
    pub tau: Matrix3<f64>,
    /// The return's plastic increment, and its plastic work per unit
    /// reference volume by the trapezoidal rule on the flow stress,
    /// ½ (σ_y(ε̄ⁿ) + σ_y(ε̄ⁿ⁺¹)) Δε̄ (exact for linear hardening on a
    /// coaxial path, where the return itself is exact).
    pub ret: Return,
}

/// One step of the Hencky model (the module's steps 1–4).
///
/// `f_rel` is the step's relative deformation gradient, `f_new` the total
/// one at the end of the step, `tau_old` the Kirchhoff stress at its start,
/// `j2` the plasticity (`None`: elastic, then bₑ = F Fᵀ from `f_new`
/// directly), `dt` the step and `rho0` the reference density (for the
/// heating of the plastic work). `state` is updated. With `tangent`, 𝔸 is
/// written there. `None` when bₑᵗʳ is not positive definite (an inverted
/// step).
#[allow(clippy::too_many_arguments)]
pub fn step(
    lambda: f64,
    mu: f64,
    j2: Option<&J2>,
    f_rel: &Matrix3<f64>,
    f_new: &Matrix3<f64>,
    tau_old: &Matrix3<f64>,
    dt: f64,
    rho0: f64,
    state: &mut PlasticState,
    tangent: Option<&mut Tangent>,
) -> Option<Step> {
    let b_trial = match j2 {
        None => f_new * f_new.transpose(),
        Some(_) => {
            let b_old = if tau_old.iter().all(|&v| v == 0.0) {
                Matrix3::identity()
            } else {
                let (ev, q) = sym_eigen(&elastic_strain(tau_old, lambda, mu));
                q * Matrix3::from_diagonal(&ev.map(|v| (2.0 * v).exp())) * q.transpose()
            };
            f_rel * b_old * f_rel.transpose()
        }
    };
    let b_trial = 0.5 * (b_trial + b_trial.transpose());
    let (bv, q) = sym_eigen(&b_trial);
    if !(bv.iter().all(|&v| v > 0.0 && v.is_finite())) {
        return None;
    }
    let e: Vector3<f64> = bv.map(|v| 0.5 * v.ln());
    let tr = e.sum();
    let t_trial = e.map(|v| lambda * tr + 2.0 * mu * v);
    let mut t = Matrix3::from_diagonal(&t_trial);
    let mean = tr * (lambda + 2.0 * mu / 3.0);
    let s_trial = t_trial.map(|v| v - mean);
    let q_trial = (1.5 * s_trial.norm_squared()).sqrt();
    let (eps0, t0) = (state.plastic_strain, state.temperature);
    let ret = match j2 {
        Some(j2) => {
            let mut r = j2.return_map(mu, dt, rho0, &mut t, state);
            if r.dplastic > 0.0 {
                let rate = if dt > 0.0 { r.dplastic / dt } else { 0.0 };
                let (sy0, sy1) = (
                    j2.flow.stress(eps0, rate, t0),
                    j2.flow
                        .stress(state.plastic_strain, rate, state.temperature),
                );
                r.plastic_work = 0.5 * (sy0 + sy1) * r.dplastic;
            }
            r
        }
        None => Return {
            dplastic: 0.0,
            plastic_work: 0.0,
        },
    };
    let tv = t.diagonal();
    let tau = q * Matrix3::from_diagonal(&tv) * q.transpose();
    if let Some(a) = tangent {
        let de = ret.dplastic;
        // Radial-return scale s and the principal consistent moduli D
        // (de Souza Neto Eq. 7.120).
        let (scale, plastic_term) = if de > 0.0 {
            let j2 = j2.expect("a plastic increment comes from a plasticity");
            let hp = j2.hardening_slope(eps0, t0, de, dt, rho0);
            (
                1.0 - 3.0 * mu * de / q_trial,
                6.0 * mu * mu * (de / q_trial - 1.0 / (3.0 * mu + hp)),
            )
        } else {
            (1.0, 0.0)
        };
        let n = if de > 0.0 {
            s_trial / s_trial.norm()
        } else {
            Vector3::zeros()
        };
        let k = lambda + 2.0 * mu / 3.0;
        let d = Matrix3::from_fn(|i, kk| {
            let dev = if i == kk { 2.0 / 3.0 } else { -1.0 / 3.0 };
            k + 2.0 * mu * scale * dev + plastic_term * n[i] * n[kk]
        });
        let c = Matrix3::from_fn(|i, j| {
            if i == j {
                0.0
            } else {
                mu * scale * log_slope(bv[i], bv[j])
            }
        });
        for (cc, row) in a.iter_mut().enumerate() {
            for (dd, out) in row.iter_mut().enumerate() {
                // ĥ = Qᵀ (e_c ⊗ e_d) Q.
                let hh = Matrix3::from_fn(|i, j| q[(cc, i)] * q[(dd, j)]);
                let mut dt_hat = Matrix3::zeros();
                for i in 0..3 {
                    dt_hat[(i, i)] = (0..3).map(|m| d[(i, m)] * hh[(m, m)]).sum();
                    for j in 0..3 {
                        if i != j {
                            dt_hat[(i, j)] = c[(i, j)] * (hh[(i, j)] * bv[j] + bv[i] * hh[(j, i)]);
                        }
                    }
                }
                *out = q * dt_hat * q.transpose();
            }
        }
    }
    Some(Step { tau, ret })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::plasticity::steel::{lame, linear, H, SY};
    use crate::material::plasticity::{FlowStress, UniaxialStrainResponse};

    fn virgin() -> PlasticState {
        PlasticState {
            plastic_strain: 0.0,
            temperature: 293.0,
            damage: 0.0,
            damage_increment: 0.0,
        }
    }

    /// Drives one point through total deformation gradients `path` (one
    /// step each), calling `check(k, F, τ, ε̄)` after each.
    fn drive(
        j2: Option<&J2>,
        path: &[Matrix3<f64>],
        mut check: impl FnMut(usize, &Matrix3<f64>, &Matrix3<f64>, f64),
    ) {
        let (lambda, mu) = lame();
        let mut f_old = Matrix3::identity();
        let mut tau = Matrix3::zeros();
        let mut st = virgin();
        for (k, f) in path.iter().enumerate() {
            let f_rel = f * f_old.try_inverse().unwrap();
            let s = step(lambda, mu, j2, &f_rel, f, &tau, 1e-3, 7800.0, &mut st, None).unwrap();
            tau = s.tau;
            f_old = *f;
            check(k, f, &tau, st.plastic_strain);
        }
    }

    /// Uniaxial strain F = diag(s, 1, 1), logarithmic strain ε = ln s:
    /// elastic to ε_y = σ₀/2μ, then q = σ₀ + H ε̄ with
    /// ε̄ = 2μ(ε − ε_y)/(3μ + H), τ₁₁ = Kε + 2q/3, τ₂₂ = Kε − q/3; unloading
    /// elastic until the reverse yield at −(σ₀ + H ε̄_max). Large strains
    /// (to ln s = 0.3 with a soft yield), big uneven steps, and the same
    /// path under a rigid rotation of the frame (τ rotates with it).
    #[test]
    fn uniaxial_strain_matches_the_log_strain_closed_form() {
        let (lambda, mu) = lame();
        let (sy, h) = (0.002 * mu, 0.05 * mu);
        let j2 = linear(sy, h);
        let exact = UniaxialStrainResponse {
            bulk: lambda + 2.0 * mu / 3.0,
            mu,
            yield_stress: sy,
            hardening: h,
        };
        let eps_y = sy / (2.0 * mu);
        let peak = 0.3;
        let end = exact.reverse_yield(peak) - 0.2;
        let mut eps_path: Vec<f64> = (1..=23)
            .map(|i| peak * (i as f64 / 23.0).powf(1.3))
            .collect();
        eps_path.extend((1..=31).map(|i| peak + (end - peak) * i as f64 / 31.0));
        let exact = |k_idx: usize, eps: f64| exact.at(eps, (k_idx >= 23).then_some(peak));
        for angle in [0.0, 0.7] {
            let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), angle).into_inner();
            let path: Vec<Matrix3<f64>> = eps_path
                .iter()
                .map(|&e| {
                    r * Matrix3::from_diagonal(&Vector3::new(e.exp(), 1.0, 1.0)) * r.transpose()
                })
                .collect();
            let mut worst: f64 = 0.0;
            drive(Some(&j2), &path, |i, _, tau, ebar| {
                let (t11, t22, eb) = exact(i, eps_path[i]);
                let local = r.transpose() * tau * r;
                let err = ((local[(0, 0)] - t11).abs()
                    + (local[(1, 1)] - t22).abs()
                    + (local[(2, 2)] - t22).abs()
                    + local[(0, 1)].abs())
                    / sy
                    + (ebar - eb).abs() / eps_y;
                worst = worst.max(err);
            });
            println!("uniaxial strain, frame angle {angle}: worst relative error {worst:.2e}");
            assert!(
                worst < 1e-9,
                "angle {angle}: worst relative error {worst:e}"
            );
        }
    }

    /// Isochoric pure shear F = diag(e^γ/2, e^−γ/2, 1) (logarithmic shear
    /// strain γ/2 on the principal axes, the equivalent of an engineering
    /// shear γ) through `gammas` (one step each), with the steel's linear
    /// hardening: calls `check(τ, ε̄, τ₁₁ exact, ε̄ exact)` after each step,
    /// where τ₁₁ = −τ₂₂ = μγ to γ_y = σ₀/(√3 μ), then
    /// ε̄ = √3 μ (γ − γ_y)/(3μ + H) and τ₁₁ = (σ₀ + H ε̄)/√3.
    fn pure_shear(gammas: &[f64], mut check: impl FnMut(&Matrix3<f64>, f64, f64, f64)) {
        let (_, mu) = lame();
        let gamma_y = SY / (3f64.sqrt() * mu);
        let path: Vec<Matrix3<f64>> = gammas
            .iter()
            .map(|&g| Matrix3::from_diagonal(&Vector3::new((0.5 * g).exp(), (-0.5 * g).exp(), 1.0)))
            .collect();
        drive(Some(&linear(SY, H)), &path, |i, _, tau, ebar| {
            let g = gammas[i];
            let (t, eb) = if g <= gamma_y {
                (mu * g, 0.0)
            } else {
                let eb = 3f64.sqrt() * mu * (g - gamma_y) / (3.0 * mu + H);
                ((SY + H * eb) / 3f64.sqrt(), eb)
            };
            check(tau, ebar, t, eb);
        });
    }

    #[test]
    fn pure_shear_matches_the_log_strain_closed_form() {
        let (_, mu) = lame();
        let gamma_y = SY / (3f64.sqrt() * mu);
        let gammas: Vec<f64> = (1..=17).map(|i| 0.5 * i as f64 / 17.0).collect();
        let mut worst: f64 = 0.0;
        pure_shear(&gammas, |tau, ebar, t, eb| {
            let err = ((tau[(0, 0)] - t).abs() + (tau[(1, 1)] + t).abs() + tau.trace().abs()) / SY
                + (ebar - eb).abs() / gamma_y;
            worst = worst.max(err);
        });
        println!("pure shear: worst relative error {worst:.2e}");
        assert!(worst < 1e-9, "worst relative error {worst:e}");
    }

    /// Extreme plastic strain (issue 18's hard case, ε̄ > 10): pure shear to
    /// γ = 25 (principal stretches e^±12.5) in 40 steps stays exact.
    #[test]
    fn extreme_plastic_strain_stays_exact() {
        let gammas: Vec<f64> = (1..=40).map(|i| 25.0 * i as f64 / 40.0).collect();
        let (mut worst, mut last): (f64, f64) = (0.0, 0.0);
        pure_shear(&gammas, |tau, ebar, t, eb| {
            worst = worst.max((tau[(0, 0)] - t).abs() / t + (ebar - eb).abs() / eb);
            last = ebar;
        });
        println!("pure shear to γ = 25: ε̄ {last:.3}, worst relative error {worst:.2e}");
        assert!(last > 10.0 && worst < 1e-9, "{last} {worst:e}");
    }

    /// Without plasticity the model is hyperelastic: τ depends on F alone,
    /// whatever the path, and equals the Hencky law of the left stretch.
    #[test]
    fn elastic_hencky_is_path_independent() {
        let (lambda, mu) = lame();
        let f = Matrix3::new(1.3, 0.4, 0.0, -0.2, 0.8, 0.1, 0.05, 0.0, 1.1);
        let mut st = virgin();
        let direct = step(
            lambda,
            mu,
            None,
            &f,
            &f,
            &Matrix3::zeros(),
            1.0,
            1.0,
            &mut st,
            None,
        )
        .unwrap()
        .tau;
        // The plastic path with an unreachable yield stress, in 7 steps.
        let path: Vec<Matrix3<f64>> = (1..=7)
            .map(|i| Matrix3::identity() + (f - Matrix3::identity()) * (i as f64 / 7.0))
            .collect();
        let mut tau = Matrix3::zeros();
        drive(Some(&linear(1e30, 0.0)), &path, |_, _, t, _| tau = *t);
        let rel = (tau - direct).norm() / direct.norm();
        println!("elastic Hencky: path dependence {rel:.2e}");
        assert!(rel < 1e-12, "path dependence {rel:e}");
        // W = ½λ(tr ε)² + μ ε:ε from ε = ½ ln(F Fᵀ).
        let e = SymmetricEigen::new(f * f.transpose());
        let ev = e.eigenvalues.map(|v| 0.5 * v.ln());
        let w = 0.5 * lambda * ev.sum().powi(2) + mu * ev.norm_squared();
        let w_tau = stored_energy(&direct, lambda, mu);
        assert!((w_tau / w - 1.0).abs() < 1e-12, "{w_tau} vs {w}");
    }

    /// The tangent against central differences of the update, at an elastic
    /// point, a plastic point (linear and Johnson–Cook-like power-law
    /// hardening) and nearly equal principal stretches.
    #[test]
    fn tangent_matches_finite_differences() {
        let (lambda, mu) = lame();
        let soft = linear(0.002 * mu, 0.05 * mu);
        let power = J2 {
            flow: FlowStress::PowerLaw {
                yield_stress: 0.002 * mu,
                k: 0.01 * mu,
                n: 0.3,
            },
            taylor_quinney: 0.9,
            specific_heat: 450.0,
        };
        // A start state: some plastic history, then a trial step.
        let f_old = Matrix3::new(1.05, 0.1, 0.0, 0.02, 0.97, 0.0, 0.0, 0.0, 1.0);
        let cases: [(Option<&J2>, Matrix3<f64>); 5] = [
            (
                None,
                Matrix3::new(1.02, 0.03, 0.0, -0.01, 0.99, 0.0, 0.0, 0.0, 1.0),
            ),
            (
                Some(&soft),
                Matrix3::new(1.02, 0.03, 0.0, -0.01, 0.99, 0.0, 0.0, 0.0, 1.0),
            ),
            (
                Some(&power),
                Matrix3::new(1.03, 0.05, 0.01, -0.02, 0.98, 0.0, 0.0, 0.01, 1.0),
            ),
            (
                Some(&soft),
                Matrix3::new(0.97, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            ),
            (None, Matrix3::identity() * 1.0000001),
        ];
        for (ci, (j2, f_rel)) in cases.iter().enumerate() {
            // Start stress: the state after f_old from rest.
            let mut st0 = virgin();
            let tau0 = step(
                lambda,
                mu,
                *j2,
                &f_old,
                &f_old,
                &Matrix3::zeros(),
                1e-3,
                7800.0,
                &mut st0,
                None,
            )
            .unwrap()
            .tau;
            let f_new = f_rel * f_old;
            let eval = |h: &Matrix3<f64>| {
                let p = Matrix3::identity() + h;
                let mut st = st0;
                step(
                    lambda,
                    mu,
                    *j2,
                    &(p * f_rel),
                    &(p * f_new),
                    &tau0,
                    1e-3,
                    7800.0,
                    &mut st,
                    None,
                )
                .unwrap()
                .tau
            };
            let mut a: Tangent = [[Matrix3::zeros(); 3]; 3];
            let mut st = st0;
            let tau = step(
                lambda,
                mu,
                *j2,
                f_rel,
                &f_new,
                &tau0,
                1e-3,
                7800.0,
                &mut st,
                Some(&mut a),
            )
            .unwrap()
            .tau;
            let scale = a.iter().flatten().map(|m| m.norm()).fold(0.0, f64::max);
            let eps = 1e-7;
            let mut worst: f64 = 0.0;
            for c in 0..3 {
                for d in 0..3 {
                    let mut h = Matrix3::zeros();
                    h[(c, d)] = eps;
                    let fd = (eval(&h) - eval(&(-h))) / (2.0 * eps);
                    worst = worst.max((fd - a[c][d]).norm() / scale);
                }
            }
            println!(
                "case {ci}: plastic increment {:.3e}, tangent error {worst:.2e}",
                st.plastic_strain - st0.plastic_strain
            );
            assert!(worst < 1e-7, "case {ci}: tangent error {worst:e}");
            // Newton's stiffness (module doc) is symmetric, so the implicit
            // solve may keep one triangle: K_ij^ac = K_ji^ca.
            let (gi, gj) = (Vector3::new(0.3, -1.1, 0.7), Vector3::new(-0.4, 0.2, 0.9));
            let k = |gi: &Vector3<f64>, gj: &Vector3<f64>, aa: usize, cc: usize| {
                let mut v = -(tau.row(aa).transpose().dot(gj)) * gi[cc];
                for b in 0..3 {
                    for d in 0..3 {
                        v += a[cc][d][(aa, b)] * gi[b] * gj[d];
                    }
                }
                v
            };
            let mut asym: f64 = 0.0;
            for aa in 0..3 {
                for cc in 0..3 {
                    asym = asym.max((k(&gi, &gj, aa, cc) - k(&gj, &gi, cc, aa)).abs() / scale);
                }
            }
            println!("case {ci}: stiffness asymmetry {asym:.2e}");
            assert!(asym < 1e-12, "case {ci}: asymmetric stiffness {asym:e}");
        }
    }
}
