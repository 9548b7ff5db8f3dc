//! Zhang Sec. 4, Fig. 2: the plate-spall case (`cases/zhang_spall.toml`)
//! run at any resolution, with the time and place of the first failure
//! against the 1D elastic-wave analysis.

use crate::error::Error;
use crate::multiphase::MultiphaseRun;
use crate::scene::{build_multiphase_run, parse};

/// The case file.
pub const SCENE: &str = include_str!("../../cases/zhang_spall.toml");

/// Flyer thickness d \[m\].
pub const FLYER: f64 = 0.0023;
/// The impact face's position \[m\].
pub const IMPACT_FACE: f64 = 0.0023;

/// The analytic spall: time `3 d / c` and plane `d` behind the impact face,
/// `c = √((λ + 2μ)/ρ)` of the plates.
pub fn analytic() -> (f64, f64) {
    let (e, nu, rho): (f64, f64, f64) = (200e9, 0.3, 7800.0);
    let m = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let c = (m / rho).sqrt();
    (3.0 * FLYER / c, IMPACT_FACE + FLYER)
}

/// What a run found.
#[derive(Debug, Clone, Copy)]
pub struct Spall {
    /// Time of the first failed point (the end of the step that failed it).
    pub time: f64,
    /// Mean position of the points failed at that step.
    pub plane: f64,
    /// Lowest and highest position of every failed point at the end.
    pub band: (f64, f64),
    /// Steps and points of the run.
    pub steps: u64,
    /// Points.
    pub points: usize,
}

/// Runs the case with `cells` cells (322: the file's 0.05 mm) to its end.
///
/// # Errors
/// A scene that does not build or a failed step.
pub fn run_spall(cells: usize) -> Result<Spall, Error> {
    let text = SCENE.replace("cells = [322]", &format!("cells = [{cells}]"));
    let scene = parse(&text)?;
    let mut run: MultiphaseRun<1> = build_multiphase_run(&scene)?;
    let plate = run.phase_of("plate").unwrap_or(0);
    let end = scene.time.end;
    let mut first: Option<(f64, f64)> = None;
    while run.t < end * (1.0 - 1e-12) {
        let dt = run.stable_dt().min(end - run.t);
        run.step(dt)?;
        if first.is_none() {
            let p = &run.phases[plate].particles;
            let failed: Vec<f64> = (0..p.len())
                .filter(|&i| p.failed(i))
                .map(|i| p.x[i][0])
                .collect();
            if !failed.is_empty() {
                let mean = failed.iter().sum::<f64>() / failed.len() as f64;
                first = Some((run.t, mean));
            }
        }
    }
    let p = &run.phases[plate].particles;
    let band = (0..p.len())
        .filter(|&i| p.failed(i))
        .map(|i| p.x[i][0])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    let (time, plane) = first.unwrap_or((f64::NAN, f64::NAN));
    Ok(Spall {
        time,
        plane,
        band,
        steps: run.steps,
        points: run.phases.iter().map(|q| q.particles.len()).sum(),
    })
}
