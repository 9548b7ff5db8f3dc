//! Reaction mass exchange (Guilkey Sec. 5): the burning area the surface
//! burn finds on curved and oblique surfaces, and the burnt mass of the
//! coupled run against `K A t`.

use std::time::Instant;

use anyhow::Result;
use nalgebra::Vector2;

use crate::harness::{Point, Series, StudyResult};
use mpmice::coupling::reaction::{burn, BurnLaw, BurnScratch, ProductCells};
use mpmice::diagnostics::explosion::failed_angles;
use mpmice::ice::CellLayout;
use mpmice::mpm::Particles;

/// Burning area of the reactant on `[0,1]²` with `n` cells per side and
/// 2×2 particles per cell wherever `inside(x)`: one dry-rate step of a
/// constant-rate law (burnt mass / (K Δt)).
fn burning_area(n: usize, inside: impl Fn(Vector2<f64>) -> bool) -> f64 {
    let h = 1.0 / n as f64;
    let layout = CellLayout::new(Vector2::zeros(), Vector2::repeat(h), [n, n]).unwrap();
    let mut p = Particles::<2>::default();
    let s = 0.5 * h;
    for i in 0..2 * n {
        for j in 0..2 * n {
            let x = Vector2::new((i as f64 + 0.5) * s, (j as f64 + 0.5) * s);
            if inside(x) {
                p.push(
                    x,
                    Vector2::zeros(),
                    1000.0 * s * s,
                    s * s,
                    Vector2::repeat(0.5 * s),
                    0,
                );
            }
        }
    }
    let law = BurnLaw {
        rate_constant: 1.0,
        pressure_exponent: 0.0,
        threshold_temperature: 1.0,
        heat_of_reaction: 0.0,
    };
    let len = layout.len();
    let (mut m, mut u, mut t, mut v) = (
        vec![1.0; len],
        vec![Vector2::zeros(); len],
        vec![300.0; len],
        vec![1.0; len],
    );
    let fluid_share = vec![1.0; len];
    let mut cells = ProductCells {
        mass: &mut m,
        velocity: &mut u,
        temperature: &mut t,
        sp_vol: &mut v,
        fluid_share: &fluid_share,
        cv: 700.0,
    };
    let dt = 1e-9;
    let pressure = vec![1e5; len];
    let mut scratch = BurnScratch::default();
    let (out, _) = burn(
        &layout,
        &law,
        1000.0,
        &[mpmice::diagnostics::coupled::steel()],
        dt,
        &pressure,
        &mut p,
        Some(500.0),
        &mut cells,
        &mut scratch,
    );
    out.mass / dt
}

/// `reaction_burn`: the burning-area error of a disk and of squares turned
/// by 0°, 15°, 30° and 45° (exposed faces weighted by the Youngs normal),
/// and the coupled slab run's burnt mass against `K A t` at three
/// resolutions.
pub fn reaction_burn(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick {
        &[20, 40]
    } else {
        &[20, 40, 80, 160, 320]
    };
    let mut series = Vec::new();
    // Disk of radius 0.3 at the centre.
    let r = 0.3;
    let c = Vector2::new(0.5, 0.5);
    let pts = ns
        .iter()
        .map(|&n| {
            let t0 = Instant::now();
            let a = burning_area(n, |x| (x - c).norm() < r);
            let exact = 2.0 * std::f64::consts::PI * r;
            Point::new(
                1.0 / n as f64,
                (a - exact).abs() / exact,
                t0.elapsed().as_secs_f64(),
                f64::NAN,
            )
            .with_extra("area", a)
            .with_extra("exact", exact)
        })
        .collect();
    series.push(Series::new("disk r = 0.3: perimeter", "relative", pts));
    for deg in [0.0f64, 15.0, 30.0, 45.0] {
        let (sn, cs) = deg.to_radians().sin_cos();
        let half = 0.2;
        let pts = ns
            .iter()
            .map(|&n| {
                let t0 = Instant::now();
                let a = burning_area(n, |x| {
                    let d = x - c;
                    let (u, v) = (cs * d[0] + sn * d[1], -sn * d[0] + cs * d[1]);
                    u.abs() < half && v.abs() < half
                });
                let exact = 8.0 * half;
                Point::new(
                    1.0 / n as f64,
                    (a - exact).abs() / exact,
                    t0.elapsed().as_secs_f64(),
                    f64::NAN,
                )
                .with_extra("area", a)
            })
            .collect();
        series.push(Series::new(
            format!("square turned {deg}°: perimeter"),
            "relative",
            pts,
        ));
    }
    // The coupled 1D slab (cases/reaction_burn.toml) at three resolutions:
    // burnt mass against K A t = 1.8e-3 kg/m².
    let case = include_str!("../../cases/reaction_burn.toml");
    let cells: &[usize] = if quick { &[125, 250] } else { &[125, 250, 500] };
    let mut pts = Vec::new();
    for &nc in cells {
        let text = case.replace("cells = [250]", &format!("cells = [{nc}]"));
        let scene = mpmice::scene::parse(&text)?;
        let mut run = mpmice::scene::build_coupled_run::<1>(&scene)?;
        let t0 = Instant::now();
        run.advance_to(1e-3)?;
        let wall = t0.elapsed().as_secs_f64();
        let burnt = run.reaction_totals().mass;
        let exact = 1.8e-3;
        let steps = run.steps as f64;
        pts.push(
            Point::new(
                0.5 / nc as f64,
                (burnt - exact).abs() / exact,
                wall,
                steps * nc as f64 / wall,
            )
            .with_extra("burnt", burnt)
            .with_extra("steps", steps),
        );
    }
    series.push(Series::new(
        "1D slab run: burnt mass vs K A t",
        "relative",
        pts,
    ));
    Ok(StudyResult {
        study: "reaction_burn".into(),
        h_axis: "cell size h (unit square 1/N, slab 0.5/N) [m]".into(),
        error_axis: "relative error of burning area or burnt mass (legend) [-]".into(),
        series,
        notes: vec![
            "Burning area = burnt mass / (K dt) of one constant-rate step (kernel \
             mpmice::coupling::reaction::burn), 2x2 particles per cell on [0,1]^2; exact \
             perimeters 2 pi 0.3 and 1.6. The slab run is cases/reaction_burn.toml to 1 ms \
             (n = 0, K = 1.8 kg/(m^2 s)); its error is round-off (no order)."
                .into(),
        ],
    })
}

/// What one run of [`confined_explosion_onset`] measured.
struct Onset {
    /// Time of the first failed steel point [s] (NaN: none by the end).
    t_first: f64,
    /// Initial angle of that point [deg].
    angle: f64,
    /// Reacted mass by then [kg/m].
    reacted: f64,
    /// Mean radius of the steel points below 10° by then [m].
    radius_0: f64,
    steps: f64,
    wall_s: f64,
}

/// Runs `cases/confined_explosion_2d.toml` at `n`² cells with the steel's
/// nonlocal radius `radius` (0: local) until its first steel point fails
/// (checked every step) or `end`.
fn onset_run(n: usize, radius: f64, end: f64) -> Result<Onset> {
    let case = include_str!("../../cases/confined_explosion_2d.toml");
    let (jc, cells) = ("d5 = 0.61 }", "cells = [64, 64]");
    for anchor in [jc, cells] {
        anyhow::ensure!(case.matches(anchor).count() == 1, "anchor `{anchor}`");
    }
    let text = case
        .replace(cells, &format!("cells = [{n}, {n}]"))
        .replace(jc, &format!("d5 = 0.61, nonlocal_radius = {radius:e} }}"));
    let mut run = mpmice::scene::build_coupled_run::<2>(&mpmice::scene::parse(&text)?)?;
    let steel = run
        .field_index("steel")
        .ok_or_else(|| anyhow::anyhow!("no steel"))?;
    let t0 = Instant::now();
    let mut first = None;
    while run.fluid.time < end {
        run.step(end - run.fluid.time)?;
        let angles = failed_angles(&run.fields[steel].particles);
        if !angles.is_empty() {
            // The point nearest the notch when several fail in one step.
            first = angles
                .into_iter()
                .min_by(|a, b| (a - 45.0).abs().total_cmp(&(b - 45.0).abs()));
            break;
        }
    }
    let p = &run.fields[steel].particles;
    let angle = first.unwrap_or(f64::NAN);
    let low: Vec<f64> = (0..p.len())
        .filter(|&i| p.x0[i][1].atan2(p.x0[i][0]) < 10f64.to_radians())
        .map(|i| p.x[i].norm())
        .collect();
    Ok(Onset {
        t_first: if first.is_some() {
            run.fluid.time
        } else {
            f64::NAN
        },
        angle,
        reacted: run.reaction_totals().mass,
        radius_0: low.iter().sum::<f64>() / low.len().max(1) as f64,
        steps: run.steps as f64,
        wall_s: t0.elapsed().as_secs_f64(),
    })
}

/// `confined_explosion_onset`: the time of the first failed steel point
/// of the 2D confined explosion (Guilkey Sec. 5) under refinement, with
/// local Johnson–Cook damage and with the damage averaged over R = 2 mm
/// (`mpm::nonlocal_damage`). There is no exact onset: each series'
/// error is the relative difference from its own finest grid's onset,
/// whose value the notes give.
pub fn confined_explosion_onset(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick { &[32, 48] } else { &[48, 64, 96, 128] };
    let mut series = Vec::new();
    let mut notes = vec![
        "cases/confined_explosion_2d.toml at n x n cells (domain 80 mm), run until the first \
         steel point fails (checked every step) or 0.15 ms; error = |t(h) - t(h_min)| / t(h_min) \
         over the series' own finest run (h_min, not plotted). Extras: the first point's initial \
         angle (the notch is at 45 deg), the reacted mass and the mean radius of the steel below \
         10 deg at that time (the ring's load), steps."
            .to_string(),
    ];
    for (label, radius) in [
        ("local Johnson-Cook damage", 0.0),
        ("nonlocal damage, R = 2 mm", 2e-3),
    ] {
        let runs = ns
            .iter()
            .map(|&n| onset_run(n, radius, 1.5e-4))
            .collect::<Result<Vec<_>>>()?;
        let finest = runs.last().map_or(f64::NAN, |r| r.t_first);
        // A difference from the finest run overstates the order as h nears
        // h_min; the successive differences say how fast the onset settles.
        let steps: Vec<String> = runs
            .windows(2)
            .map(|w| format!("{:.1}", (w[0].t_first - w[1].t_first) * 1e6))
            .collect();
        notes.push(format!(
            "{label}: first failure at {:.2} us on the {} x {} grid (h_min); successive \
             differences {} us (the observed order against h_min overstates the convergence)",
            finest * 1e6,
            ns[ns.len() - 1],
            ns[ns.len() - 1],
            steps.join(", ")
        ));
        let pts = ns
            .iter()
            .zip(&runs)
            .take(ns.len() - 1)
            .map(|(&n, r)| {
                Point::new(
                    0.08 / n as f64,
                    (r.t_first - finest).abs() / finest,
                    r.wall_s,
                    r.steps * (n * n) as f64 / r.wall_s,
                )
                .with_extra("t_first", r.t_first)
                .with_extra("angle_deg", r.angle)
                .with_extra("reacted_mass", r.reacted)
                .with_extra("radius_0deg", r.radius_0)
                .with_extra("steps", r.steps)
            })
            .collect();
        series.push(Series::new(
            format!("{label}: first failure time"),
            "relative to the finest grid",
            pts,
        ));
    }
    Ok(StudyResult {
        study: "confined_explosion_onset".into(),
        h_axis: "cell size h [m]".into(),
        error_axis: "first-failure time, relative difference from the finest grid [-]".into(),
        series,
        notes,
    })
}
