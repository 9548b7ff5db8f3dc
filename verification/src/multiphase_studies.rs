//! Zhang's multiphase MPM (Zhang Sec. 3): the block-in-air test under the
//! weak volume-fraction constraint (Eq. 18) and the strong one (Eq. 7 via
//! Eq. 15), in 2D and 3D, along a grid axis and diagonally.

use std::time::Instant;

use anyhow::Result;

use crate::harness::{Point, Series, StudyResult};
use mpmice::diagnostics::zhang_block::{run_block, BlockCase, BlockOutcome};

fn point(h: f64, c: &BlockCase, o: &BlockOutcome, wall: f64) -> Point {
    let mut p = Point::new(
        h,
        o.pressure,
        wall,
        (o.points as f64 * o.steps as f64) / wall.max(1e-9),
    );
    p.extra.insert("velocity_error".into(), o.velocity.into());
    p.extra.insert("steps".into(), (o.steps as f64).into());
    p.extra.insert("completed".into(), o.completed.into());
    p.extra.insert("cfl".into(), c.cfl.into());
    p
}

fn run(c: &BlockCase) -> Result<(BlockOutcome, f64)> {
    let start = Instant::now();
    let o = match c.dim {
        2 => run_block::<2>(c)?,
        _ => run_block::<3>(c)?,
    };
    Ok((o, start.elapsed().as_secs_f64()))
}

/// `zhang_block`: the largest relative pressure change of any point over
/// 10 cell crossings (2D) of a disk (3 points per cell per direction) in
/// air (2 per cell), both at the same velocity, periodic unit box; the
/// velocity change in `extra`. Strong constraint: over one cell crossing
/// (it fails soon after), showing that its error does not shrink with Δx.
pub fn zhang_block(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick { &[10] } else { &[10, 20, 40] };
    let mut series = Vec::new();
    let base = |n: usize, constraint: &'static str, u: [f64; 3], crossings: f64| BlockCase {
        dim: 2,
        cells: n,
        constraint,
        velocity: u,
        end: crossings / (n as f64 * u[0].abs().max(u[1].abs())),
        cfl: 0.4,
        solid: "sphere",
        solid_ppc: 3,
    };
    let sets: [(&str, &'static str, [f64; 3], f64, f64); 3] = [
        (
            "weak (Eq. 18), disk, diagonal",
            "weak",
            [10.0, 10.0, 0.0],
            10.0,
            0.4,
        ),
        (
            "weak (Eq. 18), disk, along x",
            "weak",
            [10.0, 0.0, 0.0],
            10.0,
            0.4,
        ),
        (
            "strong (Eq. 7), disk, diagonal, 1 crossing",
            "strong",
            [10.0, 10.0, 0.0],
            1.0,
            0.4,
        ),
    ];
    for (label, constraint, u, crossings, cfl) in sets {
        let mut pts = Vec::new();
        // CFL 0.1 takes four times the steps: not at the finest grid.
        let ns = if cfl < 0.4 && ns.len() > 2 {
            &ns[..2]
        } else {
            ns
        };
        for &n in ns {
            let c = BlockCase {
                cfl,
                ..base(n, constraint, u, crossings)
            };
            let (o, wall) = run(&c)?;
            pts.push(point(1.0 / n as f64, &c, &o, wall));
        }
        series.push(Series::new(
            label,
            "max |p - p0| / p0 over points and time",
            pts,
        ));
    }
    // 3D: a sphere moving diagonally, two cell crossings per axis.
    let n3: &[usize] = if quick { &[6] } else { &[8, 12] };
    let mut pts = Vec::new();
    for &n in n3 {
        let c = BlockCase {
            dim: 3,
            cells: n,
            constraint: "weak",
            velocity: [10.0, 5.0, -7.5],
            end: 2.0 / (n as f64 * 10.0),
            cfl: 0.4,
            solid: "sphere",
            solid_ppc: 3,
        };
        let (o, wall) = run(&c)?;
        pts.push(point(1.0 / n as f64, &c, &o, wall));
    }
    series.push(Series::new(
        "weak (Eq. 18), sphere, 3D diagonal, 2 crossings",
        "max |p - p0| / p0 over points and time",
        pts,
    ));
    Ok(StudyResult {
        study: "zhang_block".into(),
        h_axis: "cell size h = 1/N (unit box) [m]".into(),
        error_axis: "max relative pressure change |p − p0| / p0 [-]".into(),
        series,
        notes: vec![
            "Solid: linear elastic, rho = 1000, E = 1e8, nu = 0.3, prestressed to the air's \
             1e5 Pa; air: ideal gas, 1.2 kg/m^3, 1e5 Pa; GIMP; periodic unit box; disk/sphere \
             radius 0.2 on 3 points per cell per direction, the air on 2 (the sampled volume \
             fractions do not sum to one at the solid's edge: Zhang Eq. 14)."
                .into(),
            "Exact: no change at all. The observed order is meaningless for the weak series \
             (round-off) and shows for the strong one that Eq. 17's O((dx)^d / dt) error does \
             not fall with dx."
                .into(),
            "The interface rate of the closure is built from the same nodal volume gradients \
             as the pressure force, and p_g is the compressibility-weighted mean pressure, so \
             the pressure work across an interface balances; before that, a mode at oblique \
             interfaces grew from round-off (1.5e-8 at h = 0.025 diagonally, 2.8e-7 along x)."
                .into(),
        ],
    })
}
