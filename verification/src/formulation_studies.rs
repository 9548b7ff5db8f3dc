//! Zhang's multiphase formulation beside Guilkey's MPM-ICE on the same
//! scenes (issue 19, `mpmice::diagnostics::formulations`): the block test
//! (a disk moving diagonally with the air) and a Mach 1.5 shock on a steel
//! block; errors against the exact answers and the cost per step.

use anyhow::Result;

use crate::harness::{Point, Series, StudyResult};
use mpmice::diagnostics::formulations::{
    run_block, run_shock, shock_exact, BlockCase, Cost, Formulation, ShockCase,
};

/// A study point with the cost columns of the comparison: `steps`,
/// `wall_per_step_s` (median), `pressure_share` (null without a pressure
/// solve); `updates_per_s` counts cell-steps (the same grid for both).
fn point(h: f64, error: f64, cells: usize, cost: &Cost) -> Point {
    Point::new(
        h,
        error,
        cost.wall_s,
        cells as f64 * cost.steps as f64 / cost.wall_s.max(1e-9),
    )
    .with_extra("steps", cost.steps as f64)
    .with_extra("wall_per_step_s", cost.median_step_s)
    .with_extra("pressure_share", cost.pressure_share.unwrap_or(f64::NAN))
}

const FORMULATIONS: [(Formulation, &str); 2] = [
    (
        Formulation::Multiphase,
        "Zhang multiphase, weak constraint (Eq. 18)",
    ),
    (Formulation::Coupled, "Guilkey MPM-ICE"),
];

/// `zhang_vs_guilkey`: both formulations on the block test (20, 40, 80
/// cells per side; quick: 20) and the shock on the steel block (h = 10, 5,
/// 2.5 mm; quick: 10 mm).
pub fn zhang_vs_guilkey(quick: bool) -> Result<StudyResult> {
    let block_cells: &[usize] = if quick { &[20] } else { &[20, 40, 80] };
    let shock_cells: &[usize] = if quick { &[50] } else { &[50, 100, 200] };
    let mut series = Vec::new();
    let block_runs = [
        (FORMULATIONS[0].0, FORMULATIONS[0].1, "gimp"),
        (FORMULATIONS[1].0, FORMULATIONS[1].1, "gimp"),
        (
            Formulation::Coupled,
            "Guilkey MPM-ICE, linear hat",
            "linear",
        ),
    ];
    for (f, name, shape) in block_runs {
        let mut pts = Vec::new();
        for &n in block_cells {
            let r = run_block(&BlockCase {
                formulation: f,
                cells: n,
                constraint: "weak",
                shape,
                end: 0.05,
            })?;
            eprintln!(
                "block {} {shape} n = {n}: dp/p = {:.3e} (after the first crossing {:.3e}), dv/|u| = {:.3e}, {} steps, {:.3e} s/step, pressure share {:?}",
                f.name(),
                r.pressure,
                r.pressure_late,
                r.velocity,
                r.cost.steps,
                r.cost.median_step_s,
                r.cost.pressure_share
            );
            pts.push(
                point(1.0 / n as f64, r.pressure, n * n, &r.cost)
                    .with_extra("velocity_error", r.velocity)
                    .with_extra("pressure_error_after_first_crossing", r.pressure_late),
            );
        }
        series.push(Series::new(
            format!("block test, {name}, disk diagonal"),
            "max |p - p1| / p1 of the air over time",
            pts,
        ));
    }
    let e = shock_exact();
    for (f, name) in FORMULATIONS {
        let mut pts = Vec::new();
        for &n in shock_cells {
            let r = run_shock(&ShockCase {
                formulation: f,
                cells: n,
                end: 6.34e-4,
            })?;
            eprintln!(
                "shock {} n = {n}: front p/p5 = {:.4}, momentum / 1D = {:.4}, momentum balance {:.3e}, {} steps, {:.3e} s/step, pressure share {:?}",
                f.name(),
                r.front_pressure / e.p5,
                r.momentum_ratio(),
                r.momentum_balance_error(),
                r.cost.steps,
                r.cost.median_step_s,
                r.cost.pressure_share
            );
            pts.push(
                point(0.5 / n as f64, r.front_error(), n * n * 2 / 5, &r.cost)
                    .with_extra("front_pressure_pa", r.front_pressure)
                    .with_extra("momentum_over_1d", r.momentum_ratio())
                    .with_extra("momentum_balance_error", r.momentum_balance_error()),
            );
        }
        series.push(Series::new(
            format!("shock on steel block, {name}"),
            "|mean probe p - p5| / p5",
            pts,
        ));
    }
    Ok(StudyResult {
        study: "zhang_vs_guilkey".into(),
        h_axis: "cell size h (block 1/N, shock 0.5/N) [m]".into(),
        error_axis: "relative pressure error (legend) [-]".into(),
        series,
        notes: vec![
            "Scenes: cases/zhang_vs_guilkey_block_{multiphase,coupled}.toml and \
             cases/shock_on_steel_block_{multiphase,coupled}.toml, cells edited. Same solid, air, \
             cells, GIMP, CFL 0.4 and end time for both formulations; MPM-ICE also with its \
             customary linear hat (block test)."
                .into(),
            "Block test: linear-elastic disk (rho 1000, E 1e8, nu 0.3, r = 0.15) and air \
             (1.1768 kg/m^3, 101325 Pa) at (10, 10) m/s, t = 0.05 (10/20/40 cell crossings). \
             Exact: no change. Multiphase: periodic faces (air points would leave); MPM-ICE: free \
             (outflow) faces (no periodic faces for solids). Error: largest relative air-pressure \
             change over every step (multiphase: the air points; MPM-ICE: interior cells); \
             velocity_error: largest velocity change over the speed; \
             pressure_error_after_first_crossing: the error without the start-up transient."
                .into(),
            format!(
                "Shock: Mach {} shock (p4/p1 = {:.4} driver at x < 0.1, 300 K) on a steel block \
                 [0.3, 0.4] x [0, 0.1] (symmetry at y = 0), h = 0.5 / cells. Exact 1D reflected \
                 pressure p5 = {:.1} Pa; error: mean probe pressure at (0.28, 0) over \
                 [t_hit + 0.1 ms, t_hit + 0.2 ms] (t_hit = {:.4e} s) against p5. \
                 momentum_over_1d: the half block's x-momentum at t_hit + 0.2 ms over \
                 (p5 - p1) b (t - t_hit), b = 0.1 m (below 1 once the corner's diffraction \
                 unloads the face). momentum_balance_error: the closed box's x-momentum until \
                 0.15 ms against the walls' exact impulse (p4 - p1) H t (H = 0.2 m), relative \
                 to its value at 0.15 ms.",
                e.mach,
                e.p4 / 101_325.0,
                e.p5,
                e.t_hit
            ),
            "Cost: wall_per_step_s is the median wall time of one step (its stable-step \
             computation included); pressure_share the share of the stepping spent in the \
             MPM-ICE pressure stages (Guilkey Sec. 3.3 steps 2-6, CoupledRun::pressure_s); null \
             for the multiphase model, which solves no pressure equation (each point's pressure \
             is its own EOS). updates_per_s: cell-steps per second."
                .into(),
        ],
    })
}
