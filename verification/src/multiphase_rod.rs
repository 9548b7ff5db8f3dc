//! Zhang Figs. 3–4: the tungsten rod into steel (three phases, r–z) at
//! three cell sizes, with the Alekseevskii–Tate model beside it.

use anyhow::Result;

use crate::harness::{Point, Series, StudyResult};
use mpmice::diagnostics::zhang_rod::{
    run, scene, tate, RodRun, PLATE, RHO_PLATE, RHO_ROD, ROD_LENGTH, SPEED,
};

/// Rod strength Y_p of the Tate model: the tungsten's Johnson–Cook A.
pub const TATE_Y: f64 = 1.506e9;
/// Target resistances R_t of the Tate model: the cavity-expansion
/// estimates (2/3) Y_t (1 + ln(2E/3Y_t)) and Y_t (2/3 + ln(0.57 E/Y_t))
/// (Tate 1986) with the steel's Johnson–Cook flow stress at ε̄ = 0.3
/// (Y_t = 1.165 GPa, E = 200 GPa).
pub const TATE_R: [f64; 2] = [4.46e9, 6.11e9];

/// `zhang_rod`: penetration P(t) and residual length L(t) at 2, 3, 4 cells
/// per rod radius (quick: 2); the error of each is its distance from the
/// next finer run at the end (a Cauchy sequence: no exact answer), and
/// against the Tate band.
pub fn zhang_rod(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick { &[2] } else { &[2, 3, 4] };
    let end = 50e-6;
    let every = 2e-6;
    let mut runs: Vec<RodRun> = Vec::new();
    for &n in ns {
        let r = run(&scene(n, end)?, every)?;
        let last = r.samples.last().copied();
        println!(
            "R/{n}: {} points, {} steps, {:.1} s, dt_min {:.2e}, stopped {:?}, P {:.2} mm, L {:.2} mm, momentum drift {:.1e}, energy error {:.1e}, drag heat {:.3e} of K0 (nodal {:.3e})",
            r.points,
            r.steps,
            r.wall_s,
            r.dt_min,
            r.stopped_at,
            last.map_or(f64::NAN, |s| s.penetration * 1e3),
            last.map_or(f64::NAN, |s| s.length * 1e3),
            r.momentum_drift,
            r.energy_error,
            r.drag_heat,
            r.drag_dissipation
        );
        for (name, d, v) in &r.phase_drift {
            println!(
                "  {name}: axial momentum change {d:+.2e} of the total, fastest point {v:.3e} m/s"
            );
        }
        runs.push(r);
    }
    let tates: Vec<_> = TATE_R
        .iter()
        .map(|&rt| {
            tate(
                SPEED, ROD_LENGTH, RHO_ROD, RHO_PLATE, TATE_Y, rt, end, every,
            )
        })
        .collect();
    let at = |r: &RodRun, t: f64| {
        r.samples
            .iter()
            .min_by(|a, b| (a.t - t).abs().total_cmp(&(b.t - t).abs()))
            .copied()
    };
    let (mut p_pts, mut l_pts, mut tate_pts) = (Vec::new(), Vec::new(), Vec::new());
    for (k, r) in runs.iter().enumerate() {
        let last = match r.samples.last() {
            Some(s) => *s,
            None => continue,
        };
        let rate = r.points as f64 * r.steps as f64 / r.wall_s.max(1e-9);
        let base = |e: f64| {
            let mut p = Point::new(r.h, e, r.wall_s, rate)
                .with_extra("t_end_s", last.t)
                .with_extra("steps", r.steps as f64)
                .with_extra("dt_min_s", r.dt_min)
                .with_extra("momentum_drift", r.momentum_drift)
                .with_extra("energy_error", r.energy_error)
                .with_extra("drag_heat_over_k0", r.drag_heat)
                .with_extra("drag_dissipation_over_k0", r.drag_dissipation)
                .with_extra("stopped_at_s", r.stopped_at.unwrap_or(f64::NAN));
            p.extra.insert(
                "t_s".into(),
                r.samples.iter().map(|s| s.t).collect::<Vec<_>>().into(),
            );
            p.extra.insert(
                "penetration_m".into(),
                r.samples
                    .iter()
                    .map(|s| s.penetration)
                    .collect::<Vec<_>>()
                    .into(),
            );
            p.extra.insert(
                "length_m".into(),
                r.samples
                    .iter()
                    .map(|s| s.length)
                    .collect::<Vec<_>>()
                    .into(),
            );
            p
        };
        if let Some(finer) = runs.get(k + 1) {
            if let Some(f) = at(finer, last.t) {
                p_pts.push(base((last.penetration - f.penetration).abs()));
                l_pts.push(base((last.length - f.length).abs()));
            }
        }
        // Distance from the Tate band at the run's last sample.
        let band: Vec<f64> = tates
            .iter()
            .map(|tt| {
                tt.iter()
                    .min_by(|a, b| (a.t - last.t).abs().total_cmp(&(b.t - last.t).abs()))
                    .map_or(f64::NAN, |s| s.penetration)
            })
            .collect();
        let (lo, hi) = (band[1].min(band[0]), band[1].max(band[0]));
        let off = if last.penetration < lo {
            lo - last.penetration
        } else if last.penetration > hi {
            last.penetration - hi
        } else {
            0.0
        };
        tate_pts.push(
            base(off)
                .with_extra("penetration_m_at_end", last.penetration)
                .with_extra("tate_low_m", lo)
                .with_extra("tate_high_m", hi),
        );
    }
    Ok(StudyResult {
        study: "zhang_rod".into(),
        h_axis: "cell size h (R/2, R/3, R/4) [m]".into(),
        error_axis: "difference to the next finer run or Tate band (legend) [m]".into(),
        series: vec![
            Series::new("penetration at the end", "|P_h - P_h/next| [m]", p_pts),
            Series::new("residual length at the end", "|L_h - L_h/next| [m]", l_pts),
            Series::new(
                "penetration vs Alekseevskii-Tate band",
                "distance from [P_Tate(R_t = 6.11 GPa), P_Tate(4.46 GPa)] [m]",
                tate_pts,
            ),
        ],
        notes: vec![format!(
            "cases/zhang_rod.toml: tungsten alloy rod L = 50 mm, D = 4 mm at 1.7 km/s into \
                 {:.1} mm of 4340 steel, Johnson-Cook (Johnson & Cook 1983) for both, air a \
                 third phase; r-z, h = R/2, R/3, R/4. Tate model: Y_p = 1.506 GPa, R_t = 4.46 \
                 and 6.11 GPa (cavity-expansion estimates, not fitted). The experimental data \
                 (Anderson et al. 1995) are not in the library: not compared.",
            PLATE * 1e3
        )],
    })
}
