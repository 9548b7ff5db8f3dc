//! Study of the multiplicative (Hencky) J2 plasticity's step-size error:
//! simple shear to γ = 1 ([`mpmice::diagnostics::finite_plasticity`]).

use anyhow::{anyhow, Result};

use crate::harness::{Point, Series, StudyResult};
use mpmice::diagnostics::finite_plasticity::simple_shear;
use mpmice::material::plasticity::{FlowStress, JohnsonCook, J2};

/// Simple shear of one point of Hencky steel with J2 plasticity (E 200 GPa,
/// ν 0.3) to γ = 1 in N equal steps, for three flow-stress laws: the
/// relative error of τ₁₂ at γ = 1 against the same update run with 2¹⁶
/// steps (2¹² quick), h = Δγ. Uniaxial strain and pure shear are exact at
/// any step (tests); simple shear turns the principal axes, so the
/// exponential-map return has a first-order step error, which this study
/// measures. ε̄ and the normal-stress difference ride along as extras.
///
/// # Errors
/// A step that inverts (none should).
pub fn hencky_simple_shear(quick: bool) -> Result<StudyResult> {
    let (e, nu) = (200e9, 0.3);
    let mu = e / (2.0 * (1.0 + nu));
    let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let ns: Vec<usize> = if quick {
        vec![8, 16, 32]
    } else {
        (2..=10).map(|k| 1usize << k).collect()
    };
    let n_ref = if quick { 1 << 12 } else { 1 << 16 };
    let laws: [(&str, J2); 3] = [
        (
            "linear hardening (sigma0 300 MPa, H 2 GPa)",
            J2 {
                flow: FlowStress::Linear {
                    yield_stress: 300e6,
                    hardening: 2e9,
                },
                taylor_quinney: 0.0,
                specific_heat: 477.0,
            },
        ),
        (
            "power law (sigma0 300 MPa, K 500 MPa, n 0.3)",
            J2 {
                flow: FlowStress::PowerLaw {
                    yield_stress: 300e6,
                    k: 500e6,
                    n: 0.3,
                },
                taylor_quinney: 0.0,
                specific_heat: 477.0,
            },
        ),
        (
            "Johnson-Cook 4340 steel, adiabatic (beta 0.9)",
            J2 {
                flow: FlowStress::JohnsonCook(JohnsonCook::steel_4340(0.014)),
                taylor_quinney: 0.9,
                specific_heat: 477.0,
            },
        ),
    ];
    let mut series = Vec::new();
    for (label, j2) in &laws {
        let run = |n: usize| {
            let t0 = std::time::Instant::now();
            let r = simple_shear(lambda, mu, Some(j2), 1.0, n)
                .ok_or_else(|| anyhow!("{label}: a step inverted at N = {n}"));
            (r, t0.elapsed().as_secs_f64())
        };
        let (reference, _) = run(n_ref);
        let reference = reference?;
        let mut points = Vec::new();
        for &n in &ns {
            let (r, wall) = run(n);
            let r = r?;
            points.push(
                Point::new(
                    1.0 / n as f64,
                    (r.tau_xy - reference.tau_xy).abs() / reference.tau_xy.abs(),
                    wall,
                    n as f64 / wall.max(1e-12),
                )
                .with_extra("steps", n as f64)
                .with_extra("tau_xy", r.tau_xy)
                .with_extra("tau_xy_reference", reference.tau_xy)
                .with_extra(
                    "plastic_strain_error",
                    (r.plastic_strain - reference.plastic_strain).abs() / reference.plastic_strain,
                )
                .with_extra("normal_difference", r.normal_difference),
            );
        }
        series.push(Series::new(format!("tau_xy, {label}"), "relative", points));
    }
    Ok(StudyResult {
        study: "hencky_simple_shear".into(),
        series,
        notes: vec![
            format!(
                "one point, F = I + gamma e1 x e2 to gamma = 1 in N equal steps over a unit time; \
                 reference: the same update with {n_ref} steps (a self-convergence study: uniaxial \
                 strain and pure shear are exact at any step and are tested against closed forms)"
            ),
            "Hencky elasticity (tau = lambda tr(eps) I + 2 mu eps, eps = ln V_e) with J2 plasticity \
             on the Kirchhoff stress, exponential-map return (material::hencky); E 200 GPa, nu 0.3"
                .into(),
        ],
        h_axis: "shear step Δγ [-]".into(),
        error_axis: "relative error of τ₁₂ at γ = 1 [-]".into(),
    })
}
