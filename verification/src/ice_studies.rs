//! Convergence and work-precision studies of the explicit multi-material
//! ICE fluid solver (`mpmice::ice`): Sod against the exact Riemann solution,
//! an advected entropy wave, and a linear acoustic wave.

use std::f64::consts::PI;

use anyhow::{Context, Result};
use nalgebra::SVector;

use crate::harness::{Point, Series, StudyResult};
use mpmice::diagnostics::riemann::{ExactRiemann, PrimitiveState};
use mpmice::ice::{
    run_fluid, shock_tube, Advection, CellLayout, IceBoundary, IceMaterial, IceParams, IceState,
    Limiter, MaterialInit,
};
use mpmice::material::eos::IdealGas;

fn gas(gamma: f64) -> Result<IceMaterial> {
    Ok(IceMaterial::new(
        "gas",
        IdealGas::new(gamma, 1.0 / (gamma - 1.0))?,
    ))
}

fn label(adv: Advection) -> &'static str {
    match adv {
        Advection::FirstOrder => "first order (donor cell)",
        Advection::SecondOrder(Limiter::VanLeer) => "second order (van Leer)",
        Advection::SecondOrder(Limiter::MonotonizedCentral) => "second order (MC)",
        Advection::SecondOrder(Limiter::Superbee) => "second order (superbee)",
        Advection::SecondOrder(Limiter::Minmod) => "second order (minmod)",
    }
}

fn periodic1() -> [[IceBoundary<1>; 2]; 1] {
    [[IceBoundary::Periodic, IceBoundary::Periodic]]
}

/// Sod's shock tube, `(ρ, u, p) = (1, 0, 1) | (0.125, 0, 0.1)`, `γ = 1.4`,
/// `x0 = 0.5`, `t = 0.2`: mean L1 density error against the exact cell
/// averages, for first- and second-order advection.
///
/// # Errors
/// Any solver or exact-solution error.
pub fn ice_sod(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick {
        &[100, 200, 400]
    } else {
        &[100, 200, 400, 800, 1600, 3200]
    };
    let (l, r) = ((1.0, 0.0, 1.0), (0.125, 0.0, 0.1));
    let exact = ExactRiemann::solve(
        PrimitiveState::new(l.0, l.1, l.2),
        PrimitiveState::new(r.0, r.1, r.2),
        1.4,
    )?;
    let bcs = [[IceBoundary::Outflow, IceBoundary::Outflow]];
    let literal = |adv: Advection, face_dt: f64| {
        let mut p = IceParams::new(bcs.clone());
        p.advection = adv;
        p.face_dt_factor = face_dt;
        p
    };
    let variants: Vec<(IceParams<1>, String)> = vec![
        (
            literal(Advection::FirstOrder, 1.0),
            label(Advection::FirstOrder).into(),
        ),
        (
            literal(Advection::SecondOrder(Limiter::VanLeer), 1.0),
            label(Advection::SecondOrder(Limiter::VanLeer)).into(),
        ),
        (
            literal(Advection::SecondOrder(Limiter::MonotonizedCentral), 1.0),
            label(Advection::SecondOrder(Limiter::MonotonizedCentral)).into(),
        ),
        (
            literal(Advection::SecondOrder(Limiter::VanLeer), 0.5),
            "second order (van Leer), Eq. 28 with Δt/2".into(),
        ),
        (
            IceParams::high_resolution(bcs.clone()),
            "high resolution (MUSCL Eq. 28, p_eq + Δp/2, superbee, cfl 0.4)".into(),
        ),
        (
            IceParams {
                cfl: 0.5,
                ..IceParams::high_resolution(bcs.clone())
            },
            "high resolution, cfl 0.5".into(),
        ),
        (
            IceParams {
                advection: Advection::SecondOrder(Limiter::MonotonizedCentral),
                face_reconstruction: Some(Limiter::MonotonizedCentral),
                cfl: 0.5,
                ..IceParams::high_resolution(bcs.clone())
            },
            "high resolution with MC, cfl 0.5".into(),
        ),
    ];
    let mut series = Vec::new();
    let mut notes = vec![
        "explicit ICE (Guilkey Sec. 3.1), conservative energy form, forward Euler; literal variants cfl = 0.5 on |u| + c".to_string(),
        "reference: a Fortran Roe/MC code reaches L1 = 5.1e-4 in 0.053 s (N = 800) and 3.1e-4 in 0.16 s (N = 1600) on this machine".to_string(),
    ];
    for (params, series_label) in variants {
        let mut points = Vec::new();
        for &n in ns {
            let st = shock_tube(gas(1.4)?, n, l, r, 0.5)?;
            let run =
                run_fluid(st, &params, 0.2, 10_000_000).with_context(|| format!("Sod N = {n}"))?;
            let s = &run.state;
            let h = 1.0 / n as f64;
            let mut err = 0.0;
            for &c in &s.layout.interior {
                let x = s.layout.centre(c)[0];
                let avg = exact.cell_average(x - 0.5 * h, x + 0.5 * h, 0.5, s.time, 4)?;
                err += (s.mixture_density(c) - avg.rho).abs();
            }
            err /= n as f64;
            let ups = (n as f64 * run.steps as f64) / run.wall_s.max(1e-12);
            points.push(Point::new(h, err, run.wall_s, ups).with_extra("steps", run.steps as f64));
        }
        if let Some(p) = points.iter().find(|p| (p.h - 1.0 / 400.0).abs() < 1e-12) {
            notes.push(format!(
                "{series_label}: L1 at N = 400 = {:.3e} (target ≤ 1.5e-3)",
                p.error
            ));
        }
        series.push(Series::new(series_label, "L1", points));
    }
    Ok(StudyResult {
        study: "ice_sod".into(),
        series,
        notes,
    })
}

/// A density wave `ρ = 1 + 0.2 sin 2πx` advected at `u = 1`, `p = 1`
/// (periodic, one period, `t = 1`): the exact solution is the translation.
///
/// # Errors
/// Any solver error.
pub fn ice_entropy_wave(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick {
        &[32, 64, 128]
    } else {
        &[32, 64, 128, 256, 512]
    };
    let rho = |x: f64| 1.0 + 0.2 * (2.0 * PI * x).sin();
    let mut series = Vec::new();
    for adv in [
        Advection::FirstOrder,
        Advection::SecondOrder(Limiter::VanLeer),
        Advection::SecondOrder(Limiter::MonotonizedCentral),
    ] {
        let mut points = Vec::new();
        for &n in ns {
            let h = 1.0 / n as f64;
            let layout =
                CellLayout::<1>::new(SVector::<f64, 1>::zeros(), SVector::<f64, 1>::new(h), [n])?;
            let st = IceState::new(layout, vec![gas(1.4)?], |x| {
                vec![MaterialInit::new(
                    1.0,
                    rho(x[0]),
                    1.0,
                    SVector::<f64, 1>::new(1.0),
                )]
            })?;
            let mut params = IceParams::new(periodic1());
            params.advection = adv;
            let run = run_fluid(st, &params, 1.0, 10_000_000)?;
            let s = &run.state;
            let err = s
                .layout
                .interior
                .iter()
                .map(|&c| (s.mixture_density(c) - rho(s.layout.centre(c)[0] - 1.0)).abs())
                .sum::<f64>()
                / n as f64;
            let ups = (n as f64 * run.steps as f64) / run.wall_s.max(1e-12);
            points.push(Point::new(h, err, run.wall_s, ups));
        }
        series.push(Series::new(label(adv), "L1", points));
    }
    Ok(StudyResult {
        study: "ice_entropy_wave".into(),
        series,
        notes: vec!["density wave at uniform u = 1, p = 1, gamma = 1.4, periodic, t = 1, cfl = 0.5 on |u| + c; L1 = mean |ρ − ρ_exact| over cells (cell-centre samples)".into()],
    })
}

/// A right-running linear acoustic wave `ρ = 1 + ε sin 2πx`,
/// `u = c ε sin 2πx`, `p = 1/γ + ε sin 2πx` (`c = 1`, `ε = 1e-5`), periodic,
/// one period: L1 of the density perturbation error relative to `ε`.
///
/// # Errors
/// Any solver error.
pub fn ice_acoustic(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick {
        &[32, 64, 128]
    } else {
        &[32, 64, 128, 256, 512]
    };
    let gamma = 1.4;
    let eps = 1e-5;
    let wave = |x: f64| (2.0 * PI * x).sin();
    let mut series = Vec::new();
    let lit = |time| {
        let mut p = IceParams::new(periodic1());
        p.time = time;
        p
    };
    for (params, tag) in [
        (
            lit(mpmice::ice::TimeIntegration::ForwardEuler),
            "second order (van Leer), forward Euler",
        ),
        (
            lit(mpmice::ice::TimeIntegration::Heun),
            "second order (van Leer), Heun",
        ),
        (
            IceParams::high_resolution(periodic1()),
            "high resolution (MUSCL Eq. 28, p_eq + Δp/2, superbee, cfl 0.4)",
        ),
        (
            IceParams {
                advection: Advection::SecondOrder(Limiter::MonotonizedCentral),
                face_reconstruction: Some(Limiter::MonotonizedCentral),
                ..IceParams::high_resolution(periodic1())
            },
            "high resolution with MC, cfl 0.4",
        ),
    ] {
        let mut points = Vec::new();
        for &n in ns {
            let h = 1.0 / n as f64;
            let layout =
                CellLayout::<1>::new(SVector::<f64, 1>::zeros(), SVector::<f64, 1>::new(h), [n])?;
            let st = IceState::new(layout, vec![gas(gamma)?], |x| {
                let w = eps * wave(x[0]);
                vec![MaterialInit::new(
                    1.0,
                    1.0 + w,
                    1.0 / gamma + w,
                    SVector::<f64, 1>::new(w),
                )]
            })?;
            let run = run_fluid(st, &params, 1.0, 10_000_000)?;
            let s = &run.state;
            let err = s
                .layout
                .interior
                .iter()
                .map(|&c| {
                    (s.mixture_density(c) - 1.0 - eps * wave(s.layout.centre(c)[0] - 1.0)).abs()
                })
                .sum::<f64>()
                / (n as f64 * eps);
            let ups = (n as f64 * run.steps as f64) / run.wall_s.max(1e-12);
            points.push(Point::new(h, err, run.wall_s, ups));
        }
        series.push(Series::new(tag, "L1/eps", points));
    }
    Ok(StudyResult {
        study: "ice_acoustic".into(),
        series,
        notes: vec!["linear acoustic wave, eps = 1e-5, c = 1, periodic, one period, cfl = 0.5 (high resolution 0.4); error relative to the amplitude".into()],
    })
}
