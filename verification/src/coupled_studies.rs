//! Coupled MPM-ICE studies (Guilkey Sec. 4): the pressurised cylinder's
//! order (Eq. 43, Fig. 3) and the adiabatic piston (Eq. 44, Fig. 4).

use std::path::PathBuf;
use std::time::Instant;

use mpmice::coupling::RigidInterface;
use mpmice::diagnostics::coupled::{piston_history, run_cylinder_history};
use mpmice::scene;
use mpmice::shape::ShapeKind;

use crate::harness::{
    plot_field, plot_xy, CellField, PlotSeries, Point, Series, StudyResult, Style,
};
use crate::plot_dir;

pub(crate) fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `(r, σ_r, σ_θ)` of one particle of the Fig. 3a row.
pub type RowStress = (f64, f64, f64);

/// One coupled cylinder run from `cases/pressurized_cylinder.toml` at cell
/// size `dx`, with the case's shape and particles per cell or `variant`'s:
/// (Eq. 43 point, the Fig. 3a row, measured P).
pub fn cylinder_at(
    dx: f64,
    variant: Option<(ShapeKind, usize)>,
) -> anyhow::Result<(Point, Vec<RowStress>, f64)> {
    let path = repo_root().join("cases/pressurized_cylinder.toml");
    let mut sc = scene::load(&path)?;
    if let Some((shape, ppc)) = variant {
        sc.mpm.shape = shape;
        sc.mpm.particles_per_cell = ppc;
    }
    cylinder_scene_at(sc, dx)
}

/// [`cylinder_at`] for any cylinder scene `sc` (e.g. the implicit case):
/// the Eq. 43 point at cell size `dx` (with the steps, particles, cells,
/// measured P and, for implicit solids, the Newton iterations and the
/// time split), the Fig. 3a row and P.
pub fn cylinder_scene_at(
    sc: scene::Scene,
    dx: f64,
) -> anyhow::Result<(Point, Vec<RowStress>, f64)> {
    cylinder_history_at(sc, dx, f64::INFINITY)
}

/// [`cylinder_scene_at`] with Eq. 43 also measured after every step that
/// ends at `t ≥ from` ([`run_cylinder_history`]): its largest and smallest
/// value over those steps as the extras `eq43_max_over_time`,
/// `eq43_min_over_time` (with `history_steps`, their number).
pub fn cylinder_history_at(
    sc: scene::Scene,
    dx: f64,
    from: f64,
) -> anyhow::Result<(Point, Vec<RowStress>, f64)> {
    let (run, m, wall, history) = run_cylinder_history(sc, dx, from)?;
    let it = run.implicit_totals;
    let np = run.fields[0].particles.len();
    let nc = run.fluid.layout.num_interior();
    let point = Point::new(
        dx,
        m.error43,
        wall,
        (np + nc) as f64 * run.steps as f64 / wall.max(1e-12),
    )
    .with_extra("steps", run.steps as f64)
    .with_extra("particles", np as f64)
    .with_extra("cells", nc as f64)
    .with_extra("inner_pressure", m.pressure);
    let point = if history.is_empty() {
        point
    } else {
        let e = history.iter().map(|h| h.error43);
        point
            .with_extra("eq43_max_over_time", e.clone().fold(0.0, f64::max))
            .with_extra("eq43_min_over_time", e.fold(f64::INFINITY, f64::min))
            .with_extra("history_steps", history.len() as f64)
    };
    let point = if it.solves > 0 {
        point
            .with_extra("newton_iterations", it.newton_iterations as f64)
            .with_extra("max_newton_iterations", it.max_newton_iterations as f64)
            .with_extra("factorisations", it.factorisations as f64)
            .with_extra("step_retries", it.step_retries as f64)
            .with_extra("pressure_s", run.pressure_s)
            .with_extra("newton_assembly_s", it.assembly_s)
            .with_extra("newton_factor_s", it.factor_s)
            .with_extra("newton_solve_s", it.solve_s)
            .with_extra("particles_s", it.particles_s)
    } else {
        point
    };
    Ok((point, m.row, m.pressure))
}

/// `cylinder_order`: Guilkey Sec. 4.1 coupled, Eq. 43 vs dx (Fig. 3b) and
/// the stresses of the row nearest the x-axis vs Lamé (Fig. 3a).
pub fn cylinder_order(quick: bool) -> anyhow::Result<StudyResult> {
    let dxs: &[f64] = if quick {
        &[0.1, 0.05]
    } else {
        &[0.05, 0.025, 0.0125, 0.00625]
    };
    let mut pts = Vec::new();
    let mut spline = Vec::new();
    let mut fig3a = None;
    for &dx in dxs {
        let (p, row, pressure) = cylinder_at(dx, None)?;
        if (dx - 0.025).abs() < 1e-12 || fig3a.is_none() {
            fig3a = Some((dx, row, pressure));
        }
        pts.push(p);
        spline.push(cylinder_at(dx, Some((ShapeKind::QuadraticBspline, 3)))?.0);
    }
    if let Some((dx, row, pressure)) = fig3a {
        let (ri, ro) = (0.5f64, 1.0f64);
        let c = pressure * ri * ri / (ro * ro - ri * ri);
        let exact = |r: f64| (c * (1.0 - ro * ro / (r * r)), c * (1.0 + ro * ro / (r * r)));
        let rs: Vec<f64> = (0..=50).map(|k| ri + (ro - ri) * k as f64 / 50.0).collect();
        let series = vec![
            PlotSeries {
                label: "σ_r MPM-ICE".into(),
                points: row.iter().map(|&(r, s, _)| (r, s / 1e6)).collect(),
                style: Style::Markers,
            },
            PlotSeries {
                label: "σ_θ MPM-ICE".into(),
                points: row.iter().map(|&(r, _, s)| (r, s / 1e6)).collect(),
                style: Style::Markers,
            },
            PlotSeries {
                label: "σ_r Lamé".into(),
                points: rs.iter().map(|&r| (r, exact(r).0 / 1e6)).collect(),
                style: Style::Line,
            },
            PlotSeries {
                label: "σ_θ Lamé".into(),
                points: rs.iter().map(|&r| (r, exact(r).1 / 1e6)).collect(),
                style: Style::Line,
            },
        ];
        let dir = plot_dir(quick);
        std::fs::create_dir_all(&dir)?;
        plot_xy(
            &dir.join("cylinder_order_fig3a.png"),
            &format!("Guilkey Fig. 3a: row nearest the x-axis, dx = {dx}"),
            "r [m]",
            "stress [MPa]",
            false,
            false,
            &series,
        )?;
    }
    Ok(StudyResult {
        study: "cylinder_order".into(),
        h_axis: "cell size Δx [m]".into(),
        error_axis: "Eq. 43 stress error ||σr+σθ| − 2P/3| / (2P/3) [-]".into(),
        series: vec![
            Series::new("MPM-ICE GIMP", "Eq. 43 mean ||σr+σθ| − 2P/3| / (2P/3)", pts),
            Series::new(
                "MPM-ICE quadratic B-spline 3x3",
                "Eq. 43 mean ||σr+σθ| − 2P/3| / (2P/3)",
                spline,
            ),
        ],
        notes: vec![
            "Guilkey Sec. 4.1 coupled through the multifield equations only: \
             cases/pressurized_cylinder.toml (quarter annulus ri = 0.5, ro = 1, K = 117 GPa, \
             G = 43.8 GPa, rho = 8900, plane strain, symmetry planes, air everywhere, heat \
             source in the inner air for 3 ms to about 19.4 MPa, solid damping 3000 1/s, \
             end 8 ms), GIMP, USF, 2x2 particles per cell; the grid cells set to 1.2/dx."
                .into(),
            "Series 'quadratic B-spline 3x3': the same case with shape = quadratic_bspline and \
             3x3 particles per cell (the best of the variants tried on the solid-only \
             impm_cylinder and at dx 0.05 / 0.025 here). The error is a boundary layer: \
             within two cells of the inner surface the particles carry 25-35 % error (the \
             first particle row about 80 %: sigma_r -11 MPa against Lame -19 MPa at dx 0.025, \
             the gas load spread over the interface cells), which does not shrink with dx, so \
             the mean over all particles is first order whatever the interior does."
                .into(),
            "P = measured mean inner gauge pressure (cells with r < 0.45); Fig. 3a from the \
             dx = 0.025 run (or the coarsest in --quick): cylinder_order_fig3a.png."
                .into(),
        ],
    })
}

/// `piston_adiabatic`: Guilkey Sec. 4.2, the closed-end pressure against
/// `P1 (V1/V2)^γ` (Eq. 44) at compression ratios 1.5…5.5, and the error at
/// ratio 5 and the largest over the ratios vs h, for each rigid interface
/// (`coupling.rigid_interface`): Guilkey's smeared one (N = 120 … 1920; 1 %
/// only at N = 1920) and the sharp one (N = 120 … 960).
pub fn piston_adiabatic(quick: bool) -> anyhow::Result<StudyResult> {
    let runs: [(RigidInterface, &str, &[usize]); 2] = if quick {
        [
            (RigidInterface::Smeared, "smeared", &[60, 120]),
            (RigidInterface::Sharp, "sharp", &[60, 120]),
        ]
    } else {
        [
            (
                RigidInterface::Smeared,
                "smeared",
                &[120, 240, 480, 960, 1920],
            ),
            (RigidInterface::Sharp, "sharp", &[120, 240, 480, 960]),
        ]
    };
    let (speed, ramp) = (10.0, 0.02);
    let mut series = Vec::new();
    let mut curves = Vec::new();
    for (interface, name, ns) in runs {
        let mut at5 = Vec::new();
        let mut worst = Vec::new();
        for &n in ns {
            let start = Instant::now();
            let (hist, steps) = piston_history(n, speed, ramp, 5.9, interface)?;
            let wall = start.elapsed().as_secs_f64();
            let h = 1.2 / n as f64;
            let ups = n as f64 * steps as f64 / wall;
            if let Some(&(r, p, e)) = hist.iter().find(|s| (s.0 - 5.0).abs() < 0.01) {
                at5.push(
                    Point::new(h, (p / e - 1.0).abs(), wall, ups)
                        .with_extra("ratio", r)
                        .with_extra("signed_error", p / e - 1.0)
                        .with_extra("steps", steps as f64),
                );
            }
            let (r_worst, e_worst) =
                hist.iter()
                    .map(|&(r, p, e)| (r, p / e - 1.0))
                    .fold(
                        (0.0f64, 0.0f64),
                        |a, b| if b.1.abs() > a.1.abs() { b } else { a },
                    );
            worst.push(
                Point::new(h, e_worst.abs(), wall, ups)
                    .with_extra("ratio", r_worst)
                    .with_extra("signed_error", e_worst),
            );
            curves.push(PlotSeries {
                label: format!("{name} N = {n}"),
                points: hist.iter().map(|&(r, p, _)| (r, p / 1e6)).collect(),
                style: Style::LineMarkers,
            });
        }
        series.push(Series::new(
            format!("{name}: closed-end pressure at V1/V2 = 5"),
            "|p/p_exact − 1|",
            at5,
        ));
        series.push(Series::new(
            format!("{name}: largest over V1/V2 = 1.5 … 5.5"),
            "max |p/p_exact − 1|",
            worst,
        ));
    }
    let rs: Vec<f64> = (0..=40).map(|k| 1.0 + 4.9 * k as f64 / 40.0).collect();
    curves.push(PlotSeries {
        label: "P1 (V1/V2)^γ".into(),
        points: rs
            .iter()
            .map(|&r| (r, 101_325.0 * r.powf(1.4) / 1e6))
            .collect(),
        style: Style::Line,
    });
    let dir = plot_dir(quick);
    std::fs::create_dir_all(&dir)?;
    plot_xy(
        &dir.join("piston_adiabatic_fig4.png"),
        "Guilkey Fig. 4: pressure at the closed end vs compression ratio",
        "V1/V2 [-]",
        "p [MPa]",
        false,
        false,
        &curves,
    )?;
    Ok(StudyResult {
        study: "piston_adiabatic".into(),
        h_axis: "cell size h = 1.2 m / N [m]".into(),
        error_axis: "closed-end pressure error |p/p_exact − 1| at V1/V2 = 5 [-]".into(),
        series,
        notes: vec![
            "1D: air (1.1768 kg/m3, 101325 Pa) in [0, 1.2], walls; rigid steel piston of \
             particles in [1.0, 1.1] driven at 10 m/s towards x = 0 (smooth start over 20 ms, \
             to keep the start's acoustic wave small); K = 1e15; exact P1 (V1/V2)^1.4 with V2 \
             from the prescribed displacement. Same setup as cases/piston.toml."
                .into(),
            "Smeared (Guilkey): the error is first order in h (the piston's surface is smeared \
             over about three cells by the node-to-cell transfer, and gas trapped in them is \
             carried with it); the rigid piston's sound speed does not limit the step."
                .into(),
            "Sharp (coupling.rigid_interface = \"sharp\"): the piston's exact volume per cell, \
             rigid faces only where both cells hold it, equilibration on the cell volume; the \
             gas leaves the cells the piston takes over. What is left (-0.6 to -1.2 %, growing \
             with N) does not converge: gas left in the cells the piston covers, and a layer of \
             about one cell of cooler, denser gas at its face (piston_interface_probe)."
                .into(),
        ],
    })
}

/// The cropped domain of the [`wedge_mach3`] study: lower x, upper y.
pub const WEDGE_CROP: (f64, f64) = (0.0, 0.2);

/// One run of [`wedge_run`].
struct WedgeRun {
    /// The measured shock per requested time.
    measured: Vec<mpmice::diagnostics::coupled::WedgeMeasured>,
    h: f64,
    wall: f64,
    cells: usize,
    steps: u64,
    /// The cell pressure at the last time.
    pressure: CellField,
}

/// The Mach 3 wedge case on the domain cropped to `[x_lo, 0.8] × [0, y_hi]`
/// at `factor` times the case's resolution, run to `times` (ascending),
/// the shock measured 0.05–0.15 m behind the tip at each.
fn wedge_run(factor: usize, crop: (f64, f64), times: &[f64]) -> anyhow::Result<WedgeRun> {
    let mut sc = scene::load(&repo_root().join("cases/wedge_mach3.toml"))?;
    let h = (sc.grid.upper[0] - sc.grid.lower[0]) / (sc.grid.cells[0] * factor) as f64;
    sc.grid.lower[0] = crop.0;
    sc.grid.upper[1] = crop.1;
    sc.grid.cells = (0..2)
        .map(|d| ((sc.grid.upper[d] - sc.grid.lower[d]) / h).round() as usize)
        .collect();
    let mut run = scene::build_coupled_run::<2>(&sc)?;
    let start = Instant::now();
    let mut out = Vec::new();
    for &t in times {
        run.advance_to(t)?;
        out.push(mpmice::diagnostics::coupled::measure_wedge_mach3(&run));
    }
    let wall = start.elapsed().as_secs_f64();
    let layout = &run.fluid.layout;
    let (nx, ny) = (layout.cells[0], layout.cells[1]);
    let pressure = CellField {
        lower: (layout.lower[0], layout.lower[1]),
        h: (layout.h[0], layout.h[1]),
        cells: (nx, ny),
        values: (0..nx * ny)
            .map(|k| run.fluid.pressure[layout.index([(k % nx) as isize, (k / nx) as isize])])
            .collect(),
    };
    Ok(WedgeRun {
        measured: out,
        h,
        wall,
        cells: layout.num_interior(),
        steps: run.steps,
        pressure,
    })
}

/// Guilkey Fig. 5: the pressure field of a wedge run with the exact shock
/// line from the tip, the measured shock positions and the wedge's outline
/// (`wedge_mach3_fig5.png`).
fn wedge_fig5(
    quick: bool,
    h: f64,
    m: &mpmice::diagnostics::coupled::WedgeMeasured,
    pressure: &CellField,
) -> anyhow::Result<()> {
    let (ta, tb) = (20f64.to_radians().tan(), 37.76f64.to_radians().tan());
    let (len, tip) = (0.2, m.tip_x);
    let series = vec![
        PlotSeries {
            label: "exact shock, 37.76°".into(),
            points: vec![(tip, 0.0), (tip + 0.2 / tb, 0.2)],
            style: Style::Line,
        },
        PlotSeries {
            label: format!("measured shock, {:.2}°", m.angle_deg),
            points: m.columns.iter().map(|&(d, y, _)| (tip + d, y)).collect(),
            style: Style::Markers,
        },
        PlotSeries {
            label: "wedge".into(),
            points: vec![
                (tip, 0.0),
                (tip + len, len * ta),
                (tip + len, 0.0),
                (tip, 0.0),
            ],
            style: Style::Line,
        },
    ];
    let dir = plot_dir(quick);
    std::fs::create_dir_all(&dir)?;
    plot_field(
        &dir.join("wedge_mach3_fig5.png"),
        &format!("Fig. 5: pressure [Pa], Mach 3 wedge, h = {h}"),
        "x [m]",
        "y [m]",
        "p [Pa]",
        pressure,
        &series,
    )?;
    Ok(())
}

/// `wedge_mach3`: Guilkey Sec. 4.3, the oblique shock of a rigid 20° wedge
/// moving at Mach 3: angle and pressure ratio vs the exact 37.76° and 3.771
/// at h = 0.005, 0.0025 and 0.00125 (quick: h = 0.005), and (full study)
/// the angle's drift with time at h = 0.005.
pub fn wedge_mach3(quick: bool) -> anyhow::Result<StudyResult> {
    let end = scene::load(&repo_root().join("cases/wedge_mach3.toml"))?
        .time
        .end;
    let factors: &[usize] = if quick { &[1] } else { &[1, 2, 4] };
    let (beta, ratio) = (37.76, 3.771);
    let mut angle_pts = Vec::new();
    let mut ratio_pts = Vec::new();
    for &f in factors {
        // The domain cropped to [0, 0.8] × [0, 0.2]: the measured stretch
        // of the shock lies below y = 0.12, and nothing travels upstream of
        // an attached supersonic shock (at h = 0.005 and t = 0.36 ms the
        // angle agrees with the full domain's to the digit).
        let WedgeRun {
            measured,
            h,
            wall,
            cells,
            steps,
            pressure,
        } = wedge_run(f, WEDGE_CROP, &[end])?;
        let m = &measured[0];
        if f == 2 || quick {
            wedge_fig5(quick, h, m, &pressure)?;
        }
        let ups = cells as f64 * steps as f64 / wall.max(1e-12);
        angle_pts.push(
            Point::new(h, (m.angle_deg - beta).abs(), wall, ups)
                .with_extra("angle_deg", m.angle_deg)
                .with_extra("shock_offset_m", m.offset)
                .with_extra("steps", steps as f64),
        );
        ratio_pts.push(
            Point::new(h, (m.pressure_ratio / ratio - 1.0).abs(), wall, ups)
                .with_extra("pressure_ratio", m.pressure_ratio),
        );
    }
    let offsets: Vec<String> = angle_pts
        .iter()
        .filter_map(|p| {
            let o = p.extra.get("shock_offset_m")?.as_f64()?;
            Some(format!("{o:.4} m ({:.1} cells) at h = {}", o / p.h, p.h))
        })
        .collect();
    let offset_note = format!(
        "The fitted shock line passes above the tip: {}. Near the tip, smeared over a few \
         cells, the shock curves as behind a blunted nose; the angle is the line's slope \
         over the measured stretch, where the shock is straight.",
        offsets.join(", ")
    );
    // The angle long after the measured face has settled: one run per
    // resolution on [−0.7, 0.8] × [0, 0.2] (the tip reaches x = −0.65) to
    // 1.2 ms, 2.5× the 0.48 ms at which the steady state covers the face.
    let late_factors: &[usize] = if quick { &[1] } else { &[1, 2, 4] };
    let times = [0.36e-3, 0.48e-3, 0.6e-3, 0.72e-3, 0.96e-3, 1.2e-3];
    let mut late_pts = Vec::new();
    let mut drift_pts = Vec::new();
    let mut histories = Vec::new();
    for &f in late_factors {
        let r = wedge_run(f, (-0.7, WEDGE_CROP.1), &times)?;
        let (a48, a120) = (r.measured[1].angle_deg, r.measured[5].angle_deg);
        let ups = r.cells as f64 * r.steps as f64 / r.wall.max(1e-12);
        late_pts.push(
            Point::new(r.h, (a120 - beta).abs(), r.wall, ups)
                .with_extra("angle_deg", a120)
                .with_extra("pressure_ratio", r.measured[5].pressure_ratio)
                .with_extra("shock_offset_m", r.measured[5].offset),
        );
        drift_pts.push(
            Point::new(r.h, (a120 - a48).abs(), r.wall, ups)
                .with_extra("angle_0_48ms_deg", a48)
                .with_extra("angle_1_2ms_deg", a120),
        );
        let cols: Vec<String> = times
            .iter()
            .zip(&r.measured)
            .map(|(t, m)| format!("{:.2} ms {:.2}°", t * 1e3, m.angle_deg))
            .collect();
        histories.push(format!("h = {}: {}", r.h, cols.join(", ")));
    }
    let drift = format!(
        "Angle against time (one run per h on [−0.7, 0.8] × [0, 0.2]): {}. Before about \
         0.46 ms the measured stretch still carries the impulsive start; after it the angle \
         approaches a steady value above the exact one, so the 0.48 ms series above catches \
         the rise as it crosses 37.76°, and the series 'at 1.2 ms' and 'drift' are the \
         honest measures. The steady flow sees a thicker body: the angle and the post-shock ratio at \
         1.2 ms are those of the oblique shock of a wedge 1.2–1.9° wider (h = 0.005), the shock line passes \
         about ten cells above the tip at every h (a blunted nose), and a gas layer of 2.2–2.7 \
         cells above the face moves within 10 % of the wedge's velocity. A weaker exchange \
         does not help (h = 0.005 at 1.2 ms: K = 1e15 40.06°, 1e8 40.31°, 1e6 41.89°, the \
         layer 2.4, 2.2, 1.4 cells).",
        histories.join("; ")
    );
    Ok(StudyResult {
        study: "wedge_mach3".into(),
        h_axis: "cell size h [m]".into(),
        error_axis: "shock-angle error [deg] or relative p2/p1 error [-] (legend)".into(),
        series: vec![
            Series::new("shock angle", "|β − 37.76°| [deg]", angle_pts),
            Series::new("p2/p1", "|ratio/3.771 − 1|", ratio_pts),
            Series::new("shock angle at 1.2 ms", "|β − 37.76°| [deg]", late_pts),
            Series::new(
                "angle drift 0.48 → 1.2 ms",
                "|β(1.2 ms) − β(0.48 ms)| [deg]",
                drift_pts,
            ),
        ],
        notes: vec![
            "cases/wedge_mach3.toml: rigid 20° half-angle wedge (length 0.2) at 1041.3 m/s \
             (Mach 3 in air at 300 K) through still air, half plane with symmetry at y = 0, \
             end 0.48 ms (2.5 wedge lengths travelled); the case's cells x1, x2 and x4 \
             (h = 0.005 … 0.00125) on the domain cropped to [0, 0.8] × [0, 0.2]."
                .into(),
            "Measurement time: behind the attached shock the flow along the surface runs at \
             u2 = 865 m/s relative to the wedge with c2 = 433 m/s, so the steady state from \
             the tip reaches s behind it at t = s/(u2 − c2), i.e. 0.35 ms for the measured \
             stretch's far end (0.15 m) and 0.46 ms for the whole face (0.2 m); the case ends \
             at 0.48 ms."
                .into(),
            "Shock position per cell column 0.05–0.15 m behind the tip: first crossing of \
             (p1 + p2)/2 above the wedge surface; angle from a least-squares line; p2 = mean \
             pressure between surface and shock."
                .into(),
        ]
        .into_iter()
        .chain([offset_note, drift])
        .collect(),
    })
}

/// `wedge_steady`: Guilkey Sec. 4.3 seen from the wedge
/// (`cases/wedge_mach3_steady.toml`): the rigid wedge at rest in a
/// supersonic stream, run until its shock angle stops changing, against
/// the θ–β–M relation for the paper's 20° wedge at Mach 3, a 15° wedge at
/// Mach 2 and a 25° wedge at Mach 4, at h = 5, 2.5 and 1.25 mm (quick:
/// h = 5 mm). A run is first measured at the case's end (2.4 ms × 3/M,
/// the same lengths of flow), then every 0.3 ms × 3/M until two samples
/// agree within 0.02°, for at most twice that end; a series holds the last
/// change (the settle).
pub fn wedge_steady(quick: bool) -> anyhow::Result<StudyResult> {
    use mpmice::diagnostics::wedge::{run_steady_wedge, steady_wedge_scene};
    const TOLERANCE: f64 = 0.02;
    let base = scene::load(&repo_root().join("cases/wedge_mach3_steady.toml"))?;
    let factors: &[usize] = if quick { &[1] } else { &[1, 2, 4] };
    let wedges = [(3.0, 20.0), (2.0, 15.0), (4.0, 25.0)];
    let mut series = Vec::new();
    let mut settle = Vec::new();
    let mut rows = Vec::new();
    for (mach, theta) in wedges {
        let mut pts = Vec::new();
        for &f in factors {
            let (mut sc, stream) = steady_wedge_scene(&base, mach, theta, f)?;
            sc.time.end = base.time.end * 3.0 / mach;
            let interval = 0.3e-3 * 3.0 / mach;
            let r = run_steady_wedge(&sc, &stream, theta, interval, TOLERANCE, 2.0 * sc.time.end)?;
            let cells = sc.grid.cells.iter().product::<usize>() as f64;
            let ups = cells * r.steps as f64 / r.wall_s.max(1e-12);
            let err = (r.angle_deg - r.exact.beta_deg).abs();
            pts.push(
                Point::new(r.h, err, r.wall_s, ups)
                    .with_extra("angle_deg", r.angle_deg)
                    .with_extra("exact_deg", r.exact.beta_deg)
                    .with_extra("pressure_ratio", r.pressure_ratio)
                    .with_extra("exact_pressure_ratio", r.exact.pressure_ratio)
                    .with_extra("time_ms", r.time * 1e3)
                    .with_extra("settled", if r.settled { 1.0 } else { 0.0 })
                    .with_extra("steps", r.steps as f64),
            );
            settle.push(
                Point::new(r.h, (r.angle_deg - r.angle_before_deg).abs(), r.wall_s, ups)
                    .with_extra("mach", mach)
                    .with_extra("half_angle_deg", theta),
            );
            rows.push(format!(
                "{theta}°, Mach {mach}, h = {}: {:.3}° at {:.2} ms after {:.3}° {:.2} ms \
                 earlier ({}; exact {:.2}°), p2/p1 {:.3} (exact {:.3})",
                r.h,
                r.angle_deg,
                r.time * 1e3,
                r.angle_before_deg,
                interval * 1e3,
                if r.settled { "settled" } else { "NOT settled" },
                r.exact.beta_deg,
                r.pressure_ratio,
                r.exact.pressure_ratio
            ));
        }
        series.push(Series::new(
            format!("{theta}° wedge, Mach {mach}"),
            "|β − β_exact(θ, M)| [deg], steady",
            pts,
        ));
    }
    series.push(Series::new(
        "settle (all wedges)",
        "|β(last) − β(sample before)| [deg]",
        settle,
    ));
    Ok(StudyResult {
        study: "wedge_steady".into(),
        h_axis: "cell size h [m]".into(),
        error_axis: "shock-angle error [deg]".into(),
        series,
        notes: vec![
            "cases/wedge_mach3_steady.toml: the rigid wedge (length 0.2, tip at x = 0.6) at \
             rest, running on as a flat plate through the outflow face, in a stream of air \
             entering at x = 0.4 (Mach M, 300 K); domain [0.4, 1.2] × [0, 0.2], symmetry at \
             y = 0; other half-angles change the shoulder's height, other Mach numbers the \
             stream. Measured at 2.4 ms × 3/M (the same lengths of flow) and then every \
             0.3 ms × 3/M until two samples agree within 0.02° (at most twice that time)."
                .into(),
            "Shock position per cell column 0.05–0.15 m behind the tip, as wedge_mach3; exact \
             β and p2/p1 from the θ–β–M relation (weak shock, γ = 1.4)."
                .into(),
            format!("Runs: {}.", rows.join("; ")),
        ],
    })
}
