//! `paper_figures`: regenerates the paper figures and tables this project
//! reproduces (PNG + CSV).
//!
//! `paper_figures FIGURE [--quick] [--out DIR]` makes one figure,
//! `paper_figures all [--quick] [--out DIR]` every one in turn (a failing
//! figure does not stop the rest; the failures are listed at the end and
//! the exit status is non-zero), `paper_figures list` names them. The
//! output goes to `DIR` (default `paper_figures/output/`); `--quick`
//! (coarse resolutions) writes to `DIR/quick/` instead, so it never
//! overwrites the full figures. Figures that copy or read a verification
//! study's output take it from `verification/results/` (`--quick`:
//! `verification/results/quick/`, where `verification --quick` writes).
//!
//! Available: the convergence figure of the explicit MPM study
//! (`mpm_convergence`, from the axis-aligned manufactured solution), and the
//! Guilkey figures of the MPM-ICE coupling: `guilkey_fig3` (pressurised
//! cylinder: 3a stresses of the row nearest the x-axis vs Lamé, 3b ln error
//! vs ln dx with the fitted slope), `guilkey_fig4` (piston: closed-end
//! pressure vs compression ratio against P1 (V1/V2)^γ) and `guilkey_fig5`
//! (Mach 3 wedge: pressure field with the exact and measured shock), and
//! `york_fig6` (York Sec. 4.1: Sod with gas material points — density,
//! velocity, pressure and specific internal energy against exact) and
//! `york_fig9` (York Sec. 4.2: piston displacement history of the
//! piston–container with Eq. 27's periods), `york_fig11` / `york_fig13`
//! (York Sec. 4.3: dog-bone membrane expansion — point positions at several
//! times; radii at 0° and 90° and the energies against time), and
//! `york_fig16` / `york_fig17` (York Sec. 4.4: airbag impact — bag shapes
//! at release, peak penetration and end; probe displacement, bag pressure
//! and energies against time), and
//! `axisym_lame` (axisymmetric r–z MPM: σ_r and σ_θ of the Lamé thick
//! cylinder and sphere against the exact solutions), and `lian_vibration`
//! (Lian Sec. 4 membrane elements: centre deflection of the pre-tensioned
//! square membrane against the exact mode-(1,1) vibration), and the Zhang
//! figures: `zhang_block` (block test: air-pressure change against time
//! for the weak constraint Eq. 18, the strong one Eq. 7 and Guilkey's
//! MPM-ICE on the same scene), `zhang_shock` (a Mach 1.5 shock on a steel
//! block, both formulations: probe pressure against the exact reflected
//! pressure, block momentum against the 1D rate) and `zhang_fig2` (plate
//! spall, Zhang Fig. 2: first-failure time and plane against h and the
//! 1D elastic-wave analysis) and `zhang_fig4` (tungsten rod into steel,
//! Zhang Figs. 3–4: penetration and residual length against time at three
//! cell sizes, from the `zhang_rod` study, with the Alekseevskii–Tate
//! band).

use std::path::{Path, PathBuf};

use anyhow::bail;
use clap::Parser;
use mpmice::diagnostics::explosion::{vent, Vent};
use verification::harness::{fit_line, plot_field, plot_xy, CellField, PlotSeries, Style};

#[derive(Parser)]
#[command(about = "Regenerate paper figures")]
struct Args {
    /// Figure name, `all` or `list`.
    figure: String,
    /// Coarse resolutions only (written to the `quick/` subfolder of the
    /// output folder).
    #[arg(long)]
    quick: bool,
    /// Output folder (default: paper_figures/output).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// One figure: writes its files into the folder given (`quick`: coarse
/// resolutions).
type Figure = fn(bool, &Path) -> anyhow::Result<()>;

/// Every figure: name, description and the function that makes it.
const FIGURES: &[(&str, &str, Figure)] = &[
    (
        "lian_fig6_9_11",
        "membrane-sphere impacts (Lian 7.1): membrane centre and corner z(t) (Fig. 6), membrane centre and sphere top z(t) (Figs. 9, 11) at every cell size of the lian_impact study",
        lian_impacts,
    ),
    (
        "lian_fig12",
        "water drop on a soft membrane (Lian 7.2): membrane centre and the drop's top z(t) (Fig. 12) at every cell size of the lian_water study, with Lian's detection and the gap check",
        lian_water,
    ),
    (
        "lian_vibration",
        "pre-tensioned square membrane (Lian 4 elements): centre deflection vs time against exact mode (1,1)",
        lian_vibration,
    ),
    (
        "axisym_lame",
        "axisymmetric r-z MPM, Lame thick cylinder and sphere: sigma_r, sigma_theta vs r against exact",
        axisym_lame,
    ),
    (
        "mpm_convergence",
        "error vs h of the axis-aligned MMS, 2D, every shape function, A = 0.05 (cell crossing)",
        mpm_convergence,
    ),
    (
        "guilkey_fig3",
        "pressurised cylinder, MPM-ICE: 3a stresses vs Lame, 3b ln(Eq. 43 error) vs ln(dx)",
        guilkey_fig3,
    ),
    (
        "guilkey_fig4",
        "adiabatic piston, MPM-ICE: closed-end pressure vs compression ratio",
        guilkey_fig4,
    ),
    (
        "guilkey_fig5",
        "Mach 3 wedge, MPM-ICE: pressure field with the exact and measured shock",
        guilkey_fig5,
    ),
    (
        "guilkey_fig6",
        "confined explosion, 2D (Guilkey Sec. 5): product volume fraction and steel points at 0, 100, 160, 300 us; history every 10 us",
        guilkey_fig6,
    ),
    (
        "guilkey_fig6_3d",
        "confined explosion, 3D one-eighth (Guilkey Sec. 5): product volume fraction and steel points on two sections at 0, 100, 160, 300 us; history every 10 us",
        guilkey_fig6_3d,
    ),
    (
        "york_fig9",
        "piston-container (York 4.2): piston displacement vs time, m = 0.1 and 1.0, exact periods",
        york_fig9,
    ),
    (
        "york_fig11",
        "dog-bone membrane expansion (York 4.3): point positions at several times",
        |q, o| york_dogbone_figures(q, o, true),
    ),
    (
        "york_fig13",
        "dog-bone membrane expansion (York 4.3): radii at 0 and 90 deg and energies vs time",
        |q, o| york_dogbone_figures(q, o, false),
    ),
    (
        "york_fig16",
        "airbag impact (York 4.4): bag and probe at release, peak penetration and end",
        |q, o| york_airbag_figures(q, o, true),
    ),
    (
        "york_fig17",
        "airbag impact (York 4.4): probe displacement, bag pressure (point mean, pV) and energies vs time",
        |q, o| york_airbag_figures(q, o, false),
    ),
    (
        "zhang_block",
        "block test (Zhang 3): air-pressure change vs time, weak (Eq. 18) vs strong (Eq. 7) constraint and Guilkey MPM-ICE",
        zhang_block,
    ),
    (
        "zhang_shock",
        "Mach 1.5 shock on a steel block, Zhang multiphase vs Guilkey MPM-ICE: probe pressure vs p5, block momentum vs 1D",
        zhang_shock,
    ),
    (
        "zhang_fig2",
        "plate spall (Zhang 4, Fig. 2): first-failure time and plane vs h against 3d/c and the mid-plane",
        zhang_fig2,
    ),
    (
        "zhang_fig4",
        "tungsten rod into steel (Zhang Figs. 3-4): penetration and residual length vs time at three cell sizes (from the zhang_rod study) with the Alekseevskii-Tate band",
        zhang_fig4,
    ),
    (
        "york_fig6",
        "Sod with gas material points (York 4.1): density, velocity, pressure, energy vs exact",
        york_fig6,
    ),
];

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    if args.figure == "list" {
        for (n, d, _) in FIGURES {
            println!("{n:20} {d}");
        }
        return Ok(());
    }
    let chosen: Vec<_> = FIGURES
        .iter()
        .filter(|f| args.figure == "all" || f.0 == args.figure)
        .collect();
    if chosen.is_empty() {
        bail!(
            "unknown figure `{}`; available: {}, all, list",
            args.figure,
            FIGURES.iter().map(|f| f.0).collect::<Vec<_>>().join(", ")
        );
    }
    let out = output_dir(args.out.as_deref(), args.quick)?;
    let mut failed = Vec::new();
    for (name, _, make) in chosen {
        eprintln!("figure {name}{}", if args.quick { " (quick)" } else { "" });
        if let Err(e) = make(args.quick, &out) {
            eprintln!("figure {name} failed: {e:#}");
            failed.push(*name);
        }
    }
    if !failed.is_empty() {
        bail!("{} figure(s) failed: {}", failed.len(), failed.join(", "));
    }
    Ok(())
}

/// The folder figures are written to, created: `out` (default
/// `paper_figures/output`), or its `quick/` subfolder when `quick`.
fn output_dir(out: Option<&Path>, quick: bool) -> anyhow::Result<PathBuf> {
    let base = out.map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("output"),
        Path::to_path_buf,
    );
    let dir = if quick { base.join("quick") } else { base };
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}

/// Where the `verification` studies keep their output (as its default):
/// `verification/results`, or its `quick/` subfolder.
fn study_results_dir(quick: bool) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../verification/results");
    if quick {
        dir.join("quick")
    } else {
        dir
    }
}

/// Error against h of the axis-aligned MMS (the `mpm_mms_axis_aligned`
/// study), 2D, A = 0.05, one series per shape function, log-log with a
/// reference slope triangle; one PNG, one CSV.
fn mpm_convergence(quick: bool, out: &Path) -> anyhow::Result<()> {
    let result = verification::mpm_studies::mpm_mms_axis_aligned(quick)?;
    let series: Vec<PlotSeries> = result
        .series
        .iter()
        .filter(|s| s.label.starts_with("2D") && s.label.contains("A=5e-2"))
        .map(|s| PlotSeries {
            label: format!("{} (order {:.2})", s.label, s.observed_order),
            points: s.points.iter().map(|p| (p.h, p.error)).collect(),
            style: Style::LineMarkers,
        })
        .collect();
    let mut csv = String::from("series,h [m],error [-]\n");
    for s in &series {
        for (h, e) in &s.points {
            csv.push_str(&format!("{},{h},{e}\n", s.label));
        }
    }
    std::fs::write(out.join("mpm_convergence.csv"), csv)?;
    plot_xy(
        &out.join("mpm_convergence.png"),
        "MPM, axis-aligned MMS, 2D, A = 0.05",
        "h [m]",
        "max_t RMS displacement error / A [-]",
        true,
        true,
        &series,
    )?;
    println!("wrote {}", out.join("mpm_convergence.png").display());
    Ok(())
}

/// The study's own plots live next to its results; copy one here.
fn copy_study_plot(name: &str, quick: bool, out: &Path) -> anyhow::Result<()> {
    std::fs::copy(study_results_dir(quick).join(name), out.join(name))?;
    println!("wrote {}", out.join(name).display());
    Ok(())
}

/// Guilkey Fig. 3 (pressurised cylinder, the `cylinder_order` study): 3a
/// the study's stress plot, 3b ln error against ln dx with the
/// least-squares line ([`fit_line`], the series' observed order).
fn guilkey_fig3(quick: bool, out: &Path) -> anyhow::Result<()> {
    let result = verification::coupled_studies::cylinder_order(quick)?;
    copy_study_plot("cylinder_order_fig3a.png", quick, out)?;
    let s = &result.series[0];
    let pts: Vec<(f64, f64)> = s.points.iter().map(|p| (p.h.ln(), p.error.ln())).collect();
    // Least-squares line through (ln dx, ln error), as Guilkey Fig. 3b: the
    // harness's fit, whose slope is the series' observed order.
    let (slope, icpt) =
        fit_line(&pts).ok_or_else(|| anyhow::anyhow!("cylinder_order: no line through {pts:?}"))?;
    let mut csv = String::from("ln dx,ln error\n");
    for (x, y) in &pts {
        csv.push_str(&format!("{x},{y}\n"));
    }
    std::fs::write(out.join("guilkey_fig3b.csv"), csv)?;
    let (x0, x1) = pts.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
        (a.0.min(p.0), a.1.max(p.0))
    });
    plot_xy(
        &out.join("guilkey_fig3b.png"),
        &format!("Guilkey Fig. 3b: ln error vs ln dx, slope {slope:.2} (paper: 0.89)"),
        "ln(dx / 1 m)",
        "ln(Eq. 43 error) [-]",
        false,
        false,
        &[
            PlotSeries {
                label: "MPM-ICE GIMP".into(),
                points: pts.clone(),
                style: Style::Markers,
            },
            PlotSeries {
                label: format!("fit, slope {slope:.2}"),
                points: vec![(x0, icpt + slope * x0), (x1, icpt + slope * x1)],
                style: Style::Line,
            },
        ],
    )?;
    println!(
        "wrote {} (slope {slope:.3})",
        out.join("guilkey_fig3b.png").display()
    );
    Ok(())
}

/// Guilkey Fig. 4 (adiabatic piston): the `piston_adiabatic` study's plot.
fn guilkey_fig4(quick: bool, out: &Path) -> anyhow::Result<()> {
    verification::coupled_studies::piston_adiabatic(quick)?;
    copy_study_plot("piston_adiabatic_fig4.png", quick, out)
}

/// Guilkey Fig. 5: the `wedge_mach3` study's pressure field (h = 0.0025;
/// the quick study's h = 0.005).
fn guilkey_fig5(quick: bool, out: &Path) -> anyhow::Result<()> {
    verification::coupled_studies::wedge_mach3(quick)?;
    copy_study_plot("wedge_mach3_fig5.png", quick, out)
}

/// Guilkey Fig. 6 in 2D plane strain: `cases/confined_explosion_2d.toml`
/// (64² cells; `--quick`: 32²) to 0.3 ms: the product gas's volume fraction
/// in the cells with the steel's points (intact and failed apart) and the
/// PBX's on top at t = 0, 100, 160 and 300 µs, one PNG per time
/// (`guilkey_fig6_a.png` … `guilkey_fig6_d.png`: b, the ring open at the
/// notch and the product venting; c, the product at the domain's walls; d,
/// the ring's halves at the walls too, as in the paper's Fig. 6d), and
/// `guilkey_fig6.csv` with `guilkey_fig6_history.png`, the history every
/// 10 µs (see [`confined_explosion_figure`]).
fn guilkey_fig6(quick: bool, out: &Path) -> anyhow::Result<()> {
    confined_explosion_figure::<2>(
        &ExplosionFigure {
            case: "confined_explosion_2d.toml",
            cells: ("cells = [64, 64]", "cells = [32, 32]"),
            stem: "guilkey_fig6",
            sections: &[Section {
                axes: [0, 1],
                across: None,
                name: "",
            }],
            panels: &[0.0, 1e-4, 1.6e-4, 3e-4],
            every: 1e-5,
            // Beyond the ring's outer radius.
            outside: |x| x[0].hypot(x[1]) > 0.04,
        },
        quick,
        out,
    )
}

/// Guilkey Fig. 6 in 3D, one-eighth symmetric: `cases/confined_explosion.toml`
/// (40 × 40 × 50 cells; `--quick`: 20 × 20 × 25) at t = 0, 100, 160 and
/// 300 µs, as [`guilkey_fig6`] does, on two sections: the mid-length
/// symmetry plane z = 0 (`guilkey_fig6_3d_a_xy.png` …, the notch's
/// cross-section) and the plane y = 0 through the axis (`…_xz.png`, the
/// wall's length and the end cap), each the first cell layer with the steel
/// points inside it; and `guilkey_fig6_3d.csv` with
/// `guilkey_fig6_3d_history.png`, the history every 10 µs.
fn guilkey_fig6_3d(quick: bool, out: &Path) -> anyhow::Result<()> {
    confined_explosion_figure::<3>(
        &ExplosionFigure {
            case: "confined_explosion.toml",
            cells: ("cells = [40, 40, 50]", "cells = [20, 20, 25]"),
            stem: "guilkey_fig6_3d",
            sections: &[
                Section {
                    axes: [0, 1],
                    across: Some(2),
                    name: "_xy",
                },
                Section {
                    axes: [0, 2],
                    across: Some(1),
                    name: "_xz",
                },
            ],
            panels: &[0.0, 1e-4, 1.6e-4, 3e-4],
            every: 1e-5,
            // Beyond the container's outer surface: 40 mm from its axis
            // along the 40 mm half-length, 40 mm from the head's centre
            // (0, 0, 40 mm) past it.
            outside: |x| {
                let z = x[2] - x[2].clamp(0.0, 0.04);
                (x[0] * x[0] + x[1] * x[1] + z * z).sqrt() > 0.04
            },
        },
        quick,
        out,
    )
}

/// A plane section of a confined-explosion run drawn by
/// [`confined_explosion_figure`]: the two axes drawn and, in 3D, the axis
/// across the plane (the first cell layer along it is drawn, with the
/// points inside that layer); `name` ends the PNG's file name.
struct Section {
    axes: [usize; 2],
    across: Option<usize>,
    name: &'static str,
}

/// One confined-explosion figure: the case, what it draws and when.
struct ExplosionFigure {
    /// The case's file in `cases/`.
    case: &'static str,
    /// `--quick` replaces `cells.0` in the case by `cells.1`.
    cells: (&'static str, &'static str),
    /// Start of the output files' names.
    stem: &'static str,
    /// The sections drawn at each panel time.
    sections: &'static [Section],
    /// The panels' times (a, b, …) \[s\], increasing.
    panels: &'static [f64],
    /// The interval of the CSV's history rows \[s\].
    every: f64,
    /// Whether a point lies outside the container (the product there has
    /// vented).
    outside: fn(&[f64]) -> bool,
}

/// Runs the confined explosion `fig.case` to its last panel time. At each
/// panel time and section a PNG `{stem}_{letter}{section}.png` of the
/// product volume fraction with the steel points (intact, failed) and the
/// PBX's; and `{stem}.csv`, a row every `fig.every` and at each panel: the
/// steps taken, the reacted mass, the failed steel points, the share of the
/// product mass outside the container, the cells holding both gases at more
/// than 10 % each, the largest product volume fraction in the cells along
/// the domain's upper faces (the walls the gas reaches, Fig. 6d), the
/// intact steel points' least distance to those faces, the total-mass drift and the
/// energy balance (kinetic + internal + stored and plastic work, less the
/// start and the chemical energy released, over the released); and
/// `{stem}_history.png`, the product's share outside, the failed share of
/// the steel points and the energy missing from the account against time.
fn confined_explosion_figure<const D: usize>(
    fig: &ExplosionFigure,
    quick: bool,
    out: &Path,
) -> anyhow::Result<()> {
    let case = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../cases")
        .join(fig.case);
    let mut text = std::fs::read_to_string(&case)?;
    if quick {
        text = text.replace(fig.cells.0, fig.cells.1);
    }
    let mut run = mpmice::scene::build_coupled_run::<D>(&mpmice::scene::parse(&text)?)?;
    let fluid = |name: &str| {
        run.fluid_index(name)
            .ok_or_else(|| anyhow::anyhow!("{}: no fluid `{name}`", case.display()))
    };
    let (prod, air) = (fluid("products")?, fluid("air")?);
    let solid = |name: &str| {
        run.field_index(name)
            .ok_or_else(|| anyhow::anyhow!("{}: no solid `{name}`", case.display()))
    };
    let (steel, pbx) = (solid("steel")?, solid("pbx")?);
    // The history's times: every `every` up to the last panel, and the panels.
    let end = fig.panels.last().copied().unwrap_or(0.0);
    let mut times: Vec<f64> = (0..)
        .map(|k| k as f64 * fig.every)
        .take_while(|&t| t < end * (1.0 - 1e-9))
        .chain(fig.panels.iter().copied())
        .collect();
    times.sort_by(f64::total_cmp);
    times.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * end);
    // Total mass and energy (fluids' c_v T + ½|u|², particles' kinetic and
    // stored energy, the plastic work included).
    let (m0, e0) = run.mass_and_energy();
    let mut csv = String::from(
        "t,steps,reacted_mass,failed_points,product_outside,mixed_cells,\
         product_at_walls,steel_to_walls,mass_drift,energy_balance\n",
    );
    let mut panel = 0;
    let mut history: [Vec<(f64, f64)>; 3] = Default::default();
    for t in times {
        while run.fluid.time < t * (1.0 - 1e-12) {
            run.step(t - run.fluid.time)?;
        }
        let lay = &run.fluid.layout;
        let p = &run.fields[steel].particles;
        if panel < fig.panels.len() && (fig.panels[panel] - t).abs() <= 1e-9 * end {
            let letter = char::from(b'a' + panel as u8);
            panel += 1;
            for sec in fig.sections {
                let [a, b] = sec.axes;
                let (na, nb) = (lay.cells[a], lay.cells[b]);
                let mut values = Vec::with_capacity(na * nb);
                for j in 0..nb {
                    for i in 0..na {
                        let mut idx = [0isize; D];
                        idx[a] = i as isize;
                        idx[b] = j as isize;
                        values.push(run.fluid.cells[prod].vol_frac[lay.index(idx)]);
                    }
                }
                let field = CellField {
                    lower: (lay.lower[a], lay.lower[b]),
                    h: (lay.h[a], lay.h[b]),
                    cells: (na, nb),
                    values,
                };
                let in_layer =
                    |x: &[f64]| sec.across.is_none_or(|c| x[c] < lay.lower[c] + lay.h[c]);
                let (failed, intact): (Vec<usize>, Vec<usize>) = (0..p.len())
                    .filter(|&i| in_layer(p.x[i].as_slice()))
                    .partition(|&i| p.failed(i));
                let q = &run.fields[pbx].particles;
                let charge: Vec<usize> = (0..q.len())
                    .filter(|&i| in_layer(q.x[i].as_slice()))
                    .collect();
                let series: Vec<PlotSeries> = [
                    ("steel", p, &intact),
                    ("steel, failed", p, &failed),
                    ("PBX", q, &charge),
                ]
                .into_iter()
                .map(|(label, p, ids)| PlotSeries {
                    label: label.into(),
                    points: ids.iter().map(|&i| (p.x[i][a], p.x[i][b])).collect(),
                    style: Style::Markers,
                })
                .collect();
                let axis = ["x", "y", "z"];
                let plane = match sec.across {
                    Some(c) => format!("{D}D, {} = 0 layer", axis[c]),
                    None => format!("{D}D"),
                };
                let path = out.join(format!("{}_{letter}{}.png", fig.stem, sec.name));
                plot_field(
                    &path,
                    &format!(
                        "Guilkey Fig. 6{letter} ({plane}): product volume fraction, t = {:.0} us",
                        t * 1e6
                    ),
                    &format!("{} [m]", axis[a]),
                    &format!("{} [m]", axis[b]),
                    "product volume fraction [-]",
                    &field,
                    &series,
                )?;
                println!("wrote {}", path.display());
            }
        }
        let failed = (0..p.len()).filter(|&i| p.failed(i)).count();
        let upper: [f64; D] =
            std::array::from_fn(|a| lay.lower[a] + lay.h[a] * lay.cells[a] as f64);
        let Vent {
            outside_share: outside,
            mixed_cells: mixed,
            at_upper_walls: at_walls,
            ..
        } = vent(&run, prod, air, fig.outside);
        let to_walls = (0..p.len())
            .filter(|&i| !p.failed(i))
            .flat_map(|i| (0..D).map(move |a| upper[a] - p.x[i][a]))
            .fold(f64::INFINITY, f64::min);
        let (m, e) = run.mass_and_energy();
        let released = run.reaction_totals();
        let balance = if released.energy > 0.0 {
            (e - e0 - released.energy) / released.energy
        } else {
            0.0
        };
        let row = format!(
            "{t:.4e},{},{},{failed},{outside},{mixed},{at_walls},{to_walls},{},{balance}\n",
            run.steps,
            released.mass,
            (m - m0) / m0
        );
        history[0].push((t * 1e6, outside));
        history[1].push((t * 1e6, failed as f64 / p.len().max(1) as f64));
        history[2].push((t * 1e6, -balance));
        print!("{}: {row}", fig.stem);
        csv.push_str(&row);
    }
    std::fs::write(out.join(format!("{}.csv", fig.stem)), csv)?;
    let labels = [
        "product outside the container (share of its mass)",
        "steel points failed (share)",
        "energy missing from the account (share of the release)",
    ];
    let series: Vec<PlotSeries> = labels
        .into_iter()
        .zip(history)
        .map(|(label, points)| PlotSeries {
            label: label.into(),
            points,
            style: Style::LineMarkers,
        })
        .collect();
    let path = out.join(format!("{}_history.png", fig.stem));
    plot_xy(
        &path,
        &format!("Guilkey Fig. 6 ({D}D): history"),
        "t [us]",
        "share [-]",
        false,
        false,
        &series,
    )?;
    println!("wrote {}", path.display());
    Ok(())
}

/// York Fig. 6: Sod with gas material points at t = 0.143 (200 cells of
/// 0.005, 3 points per cell per direction, `cases/york_sod.toml`; `--quick`:
/// 100 cells): density, velocity, pressure and specific internal energy of
/// the points of one row against the exact Riemann solution. One PNG per
/// variable (`york_fig6_<var>.png`) and one CSV.
fn york_fig6(quick: bool, out: &Path) -> anyhow::Result<()> {
    use mpmice::diagnostics::york::{run_york_sod, sod_exact, YorkSod};
    let setup = YorkSod {
        cells: if quick { 100 } else { 200 },
        ..YorkSod::default()
    };
    let run = run_york_sod(&setup)?;
    let exact = sod_exact()?;
    let t = setup.end;
    let gamma = 1.4;
    let sample = |x: f64| {
        let s = exact.sample((x - 0.5) / t);
        let e = if s.rho > 0.0 {
            s.p / ((gamma - 1.0) * s.rho)
        } else {
            0.0
        };
        [s.rho, s.u, s.p, e]
    };
    let mut csv = String::from("x,rho,u,p,e,rho_exact,u_exact,p_exact,e_exact\n");
    for r in &run.profile {
        let ex = sample(r[0]);
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{},{}\n",
            r[0], r[1], r[2], r[3], r[4], ex[0], ex[1], ex[2], ex[3]
        ));
    }
    std::fs::write(out.join("york_fig6.csv"), csv)?;
    let fine: Vec<f64> = (0..=2000).map(|i| i as f64 / 2000.0).collect();
    for (k, (name, label)) in [
        ("density", "density [-]"),
        ("velocity", "velocity [-]"),
        ("pressure", "pressure [-]"),
        ("energy", "specific internal energy [-]"),
    ]
    .into_iter()
    .enumerate()
    {
        let path = out.join(format!("york_fig6_{name}.png"));
        plot_xy(
            &path,
            &format!(
                "York Fig. 6: Sod with gas points, t = {t}, dx = {} (L1 rho = {:.2e})",
                1.0 / setup.cells as f64,
                run.l1_density
            ),
            "x [-]",
            label,
            false,
            false,
            &[
                PlotSeries {
                    label: "exact".into(),
                    points: fine.iter().map(|&x| (x, sample(x)[k])).collect(),
                    style: Style::Line,
                },
                PlotSeries {
                    label: "gas points (GIMP, MUSL, York q)".into(),
                    points: run.profile.iter().map(|r| (r[0], r[k + 1])).collect(),
                    style: Style::Markers,
                },
            ],
        )?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// York Fig. 9: the piston's displacement against time in the
/// piston–container (h = 0.5; `--quick`: h = 1), m = 0.1 and 1.0, three
/// periods, with vertical lines at multiples of Eq. 27's period. One PNG per
/// mass (`york_fig9_m0.1.png`, `york_fig9_m1.png`) and one CSV each.
fn york_fig9(quick: bool, out: &Path) -> anyhow::Result<()> {
    use mpmice::diagnostics::york::{run_piston_container, PistonContainer};
    for mass in [0.1, 1.0] {
        let s = PistonContainer {
            mass,
            h: if quick { 1.0 } else { 0.5 },
            periods: 3.0,
            ..PistonContainer::default()
        };
        let r = run_piston_container(&s)?;
        let period = 2.0 * std::f64::consts::PI / r.omega_exact;
        let amp = r.history.iter().fold(0.0_f64, |a, p| a.max(p.1.abs()));
        let mut csv = String::from("t [s],displacement [m]\n");
        for (t, u) in &r.history {
            csv.push_str(&format!("{t},{u}\n"));
        }
        std::fs::write(out.join(format!("york_fig9_m{mass}.csv")), csv)?;
        let mut series = vec![PlotSeries {
            label: format!("piston (measured period {:.6} s)", r.period),
            points: r.history.clone(),
            style: Style::Line,
        }];
        for k in 1..=3 {
            let t = k as f64 * period;
            series.push(PlotSeries {
                label: if k == 1 {
                    format!("Eq. 27 period {period:.6} s")
                } else {
                    String::new()
                },
                points: vec![(t, -amp), (t, amp)],
                style: Style::Line,
            });
        }
        let path = out.join(format!("york_fig9_m{mass}.png"));
        plot_xy(
            &path,
            &format!("York Fig. 9: piston displacement, m = {mass}, h = {}", s.h),
            "t [s]",
            "displacement [m]",
            false,
            false,
            &series,
        )?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// Centre deflection z(t) of the pre-tensioned square membrane
/// (`SquareVibration`, 16 and 32 elements per side; quick: 8 and 16) over
/// two exact periods against z = (V/ω) sin ωt, ω = 2π f₁₁.
fn lian_vibration(quick: bool, out: &Path) -> anyhow::Result<()> {
    use mpmice::diagnostics::membrane_fe::{square_membrane_f11, SquareVibration};
    let cfg = SquareVibration::default();
    let f11 = square_membrane_f11(cfg.side, cfg.prestress, cfg.material.density);
    let omega = 2.0 * std::f64::consts::PI * f11;
    let end = 2.0 / f11;
    let mut series = Vec::new();
    let mut csv = String::from("cells,t [s],z_centre [m],z_exact [m]\n");
    for n in if quick { [8, 16] } else { [16, 32] } {
        let mut m = cfg.mesh(n)?;
        let centre = n / 2 + (n + 1) * (n / 2);
        let dt = cfg.cfl * m.stable_dt();
        let (mut t, mut k) = (0.0, 0u64);
        let mut pts = vec![(0.0, 0.0)];
        while t < end {
            m.step(dt, k)?;
            k += 1;
            t += dt;
            let z = m.x[centre][2];
            pts.push((t, z));
            csv.push_str(&format!(
                "{n},{t},{z},{}\n",
                cfg.amplitude / omega * (omega * t).sin()
            ));
        }
        series.push(PlotSeries {
            label: format!("{n} x {n} elements"),
            points: pts,
            style: Style::Line,
        });
    }
    series.push(PlotSeries {
        label: "exact (V/omega) sin(omega t)".into(),
        points: (0..=400)
            .map(|k| {
                let t = end * k as f64 / 400.0;
                (t, cfg.amplitude / omega * (omega * t).sin())
            })
            .collect(),
        style: Style::Line,
    });
    std::fs::write(out.join("lian_vibration.csv"), csv)?;
    plot_xy(
        &out.join("lian_vibration.png"),
        "pre-tensioned square membrane, Belytschko-Tsay quads: centre deflection",
        "t [s]",
        "z centre [m]",
        false,
        false,
        &series,
    )?;
    println!("wrote {}", out.join("lian_vibration.png").display());
    Ok(())
}

/// Lian Sec. 7.1's impacts from the `lian_impact` study's curves (run
/// `verification lian_impact [--quick]` first): the membrane on the held
/// sphere, its centre and corner z(t) (Fig. 6); the sphere on the clamped
/// membrane, the membrane centre and the sphere's top z(t) (Figs. 9, 11),
/// one line per cell size. One PNG per case and contact detection
/// (`lian_impact_{case}.png`, Lian's; `lian_impact_{case}_gap.png`, the gap
/// check).
fn lian_impacts(quick: bool, out: &Path) -> anyhow::Result<()> {
    let cases = [
        (
            "membrane_on_sphere",
            "Lian 7.1, membrane on a held sphere (Fig. 6)",
            [
                ("centre", "membrane_centre_z [m]"),
                ("corner", "membrane_corner_z [m]"),
            ],
        ),
        (
            "sphere_on_membrane",
            "Lian 7.1, sphere on a clamped membrane (Figs. 9, 11)",
            [
                ("membrane centre", "membrane_centre_z [m]"),
                ("sphere top", "sphere_top_z [m]"),
            ],
        ),
    ];
    impact_curves(quick, out, "lian_impact", &cases)
}

/// Lian Sec. 7.2's water drop from the `lian_water` study's curves (run
/// `verification lian_water [--quick]` first): the membrane centre and the
/// drop's top z(t) (Fig. 12), one line per cell size; one PNG per contact
/// detection (`lian_impact_water_sphere.png`, `…_gap.png`).
fn lian_water(quick: bool, out: &Path) -> anyhow::Result<()> {
    let cases = [(
        "water_sphere",
        "Lian 7.2, water drop on a soft clamped membrane (Fig. 12)",
        [
            ("membrane centre", "membrane_centre_z [m]"),
            ("drop top", "sphere_top_z [m]"),
        ],
    )];
    impact_curves(quick, out, "lian_water", &cases)
}

/// A case's name, its figure's title and two (label, CSV column) curves.
type ImpactFigure<'a> = (&'a str, &'a str, [(&'a str, &'a str); 2]);

/// The z(t) curves of Lian's impact cases from `study`'s CSVs
/// (`lian_impact_{case}[_gap]_h{h}.csv`), one line per cell size, one PNG
/// per case and detection.
fn impact_curves(
    quick: bool,
    out: &Path,
    study: &str,
    cases: &[ImpactFigure<'_>],
) -> anyhow::Result<()> {
    let dir = study_results_dir(quick);
    let detections = [("", ""), ("_gap", ", gap check")];
    let figures = cases
        .iter()
        .flat_map(|c| detections.iter().map(move |d| (c, *d)));
    for ((case, title, curves), (suffix, tag)) in figures {
        let mut series = Vec::new();
        for h in ["2", "1", "0.5"] {
            let path = dir.join(format!("lian_impact_{case}{suffix}_h{h}.csv"));
            let Ok(text) = std::fs::read_to_string(&path) else {
                continue;
            };
            let mut lines = text.lines();
            let head: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
            let rows: Vec<Vec<f64>> = lines
                .map(|l| {
                    l.split(',')
                        .map(|x| x.parse().unwrap_or(f64::NAN))
                        .collect()
                })
                .collect();
            for &(name, column) in curves {
                let c = head
                    .iter()
                    .position(|x| *x == column)
                    .ok_or_else(|| anyhow::anyhow!("{}: no column {column}", path.display()))?;
                series.push(PlotSeries {
                    label: format!("{name}, h = {h} mm"),
                    points: rows.iter().map(|r| (r[0] * 1e3, r[c] * 1e3)).collect(),
                    style: Style::Line,
                });
            }
        }
        if series.is_empty() {
            bail!(
                "no lian_impact_{case}{suffix}_h*.csv in {}; run `verification {study}{}` first",
                dir.display(),
                if quick { " --quick" } else { "" }
            );
        }
        let png = out.join(format!("lian_impact_{case}{suffix}.png"));
        let title = format!("{title}{tag}");
        plot_xy(&png, &title, "t [ms]", "z [mm]", false, false, &series)?;
        println!("wrote {}", png.display());
    }
    Ok(())
}

/// Axisymmetric r–z MPM against Lamé (the `axisym_lame` study's setup,
/// 16 cells across the wall; `--quick`: 8): σ_r/P and σ_θ/P (hoop,
/// `stress[(2,2)]`) of every particle against the exact curves, one PNG per
/// problem (`axisym_lame_cylinder.png`, `axisym_lame_sphere.png`) and one
/// CSV each.
fn axisym_lame(quick: bool, out: &Path) -> anyhow::Result<()> {
    use mpmice::diagnostics::axisymmetric::{Lame, LameShape, Relax};
    let n = if quick { 8 } else { 16 };
    for shape in [LameShape::Cylinder, LameShape::Sphere] {
        let lame = Lame::standard(shape);
        let mut run = lame.build(n, &Relax::default());
        while !run.finished() {
            run.step()?;
        }
        let p = &run.particles;
        let pr = lame.pressure;
        let mut csv =
            String::from("r0,sigma_r/P,sigma_theta/P,sigma_r_exact/P,sigma_theta_exact/P\n");
        let (mut sr, mut st) = (Vec::new(), Vec::new());
        for i in 0..p.len() {
            let x0 = p.x0[i];
            let (r, er) = match shape {
                LameShape::Cylinder => (x0[0], [1.0, 0.0]),
                LameShape::Sphere => (x0.norm(), [x0[0] / x0.norm(), x0[1] / x0.norm()]),
            };
            let s = &p.stress.get(i);
            let rad = er[0] * er[0] * s[(0, 0)]
                + 2.0 * er[0] * er[1] * s[(0, 1)]
                + er[1] * er[1] * s[(1, 1)];
            let ex = lame.exact(r);
            sr.push((r, rad / pr));
            st.push((r, s[(2, 2)] / pr));
            csv.push_str(&format!(
                "{r},{},{},{},{}\n",
                rad / pr,
                s[(2, 2)] / pr,
                ex.sigma_r / pr,
                ex.sigma_theta / pr
            ));
        }
        let name = format!("axisym_lame_{}", shape.name());
        std::fs::write(out.join(format!("{name}.csv")), csv)?;
        let curve = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
            (0..=100)
                .map(|k| {
                    let r = lame.r_inner + (lame.r_outer - lame.r_inner) * k as f64 / 100.0;
                    (r, f(r) / pr)
                })
                .collect()
        };
        plot_xy(
            &out.join(format!("{name}.png")),
            &format!(
                "axisymmetric MPM, Lame {} (P = 1e-5 E, GIMP, {n} cells across the wall)",
                shape.name()
            ),
            "r (reference) [m]",
            "stress / P [-]",
            false,
            false,
            &[
                PlotSeries {
                    label: "sigma_r exact".into(),
                    points: curve(&|r| lame.exact(r).sigma_r),
                    style: Style::Line,
                },
                PlotSeries {
                    label: "sigma_theta exact".into(),
                    points: curve(&|r| lame.exact(r).sigma_theta),
                    style: Style::Line,
                },
                PlotSeries {
                    label: "sigma_r particles".into(),
                    points: sr,
                    style: Style::Markers,
                },
                PlotSeries {
                    label: "sigma_theta (hoop) particles".into(),
                    points: st,
                    style: Style::Markers,
                },
            ],
        )?;
        println!("wrote {}", out.join(format!("{name}.png")).display());
    }
    Ok(())
}

/// York Figs. 11–13: the dog-bone membrane expansion at element size 0.1
/// (`--quick`: 0.4) to t = 4. `positions`: one PNG per snapshot time with
/// the membrane (line) and gas points (markers), `york_fig11_tT.png`, and
/// a CSV of all points; otherwise the radii at 0° and 90° and the kinetic
/// (of the points and of the grid), gas internal, membrane strain and total
/// energies against time
/// (`york_fig13_radii.png`, `york_fig13_energy.png`, `york_fig13.csv`).
fn york_dogbone_figures(quick: bool, out: &Path, positions: bool) -> anyhow::Result<()> {
    use mpmice::diagnostics::york_membrane::{run_dog_bone, DogBone};
    let h = if quick { 0.4 } else { 0.1 };
    let r = run_dog_bone(&DogBone {
        h,
        ..DogBone::default()
    })?;
    if positions {
        let mut csv = String::from("t,kind,x,y\n");
        for ((t, mem), (_, gas)) in r.snapshots.iter().zip(&r.gas_snapshots) {
            for (kind, pts) in [("membrane", mem), ("gas", gas)] {
                for p in pts {
                    csv.push_str(&format!("{t},{kind},{},{}\n", p[0], p[1]));
                }
            }
            let mut line: Vec<(f64, f64)> = mem.iter().map(|p| (p[0], p[1])).collect();
            if let Some(&first) = line.first() {
                line.push(first);
            }
            let frame = DogBone::HALF_WIDTH;
            let series = vec![
                PlotSeries {
                    label: "gas points".into(),
                    points: gas.iter().map(|p| (p[0], p[1])).collect(),
                    style: Style::Markers,
                },
                PlotSeries {
                    label: "membrane points".into(),
                    points: line,
                    style: Style::Line,
                },
                // The domain's fixed walls (they also fix the axes).
                PlotSeries {
                    label: "fixed walls".into(),
                    points: vec![
                        (-frame, -frame),
                        (frame, -frame),
                        (frame, frame),
                        (-frame, frame),
                        (-frame, -frame),
                    ],
                    style: Style::Line,
                },
            ];
            let path = out.join(format!("york_fig11_t{t:.2}.png"));
            plot_xy(
                &path,
                &format!("York Fig. 11/12: dog-bone, h = {h}, t = {t:.2}"),
                "x [-]",
                "y [-]",
                false,
                false,
                &series,
            )?;
            println!("wrote {}", path.display());
        }
        std::fs::write(out.join("york_fig11.csv"), csv)?;
        return Ok(());
    }
    let csv = r.history_csv();
    std::fs::write(out.join("york_fig13.csv"), csv)?;
    let col = |f: &dyn Fn(&mpmice::diagnostics::york_membrane::DogBoneSample) -> f64| {
        r.history.iter().map(|x| (x.t, f(x))).collect::<Vec<_>>()
    };
    let radii = vec![
        PlotSeries {
            label: "radius at 0 deg".into(),
            points: col(&|x| x.radius_0),
            style: Style::Line,
        },
        PlotSeries {
            label: "radius at 90 deg".into(),
            points: col(&|x| x.radius_90),
            style: Style::Line,
        },
    ];
    let path = out.join("york_fig13_radii.png");
    plot_xy(
        &path,
        &format!("York Fig. 13: dog-bone radii, h = {h}"),
        "t [-]",
        "radius [-]",
        false,
        false,
        &radii,
    )?;
    println!("wrote {}", path.display());
    let energy = vec![
        PlotSeries {
            label: "kinetic (points)".into(),
            points: col(&|x| x.kinetic),
            style: Style::Line,
        },
        PlotSeries {
            label: "kinetic (grid)".into(),
            points: col(&|x| x.grid_kinetic),
            style: Style::Line,
        },
        PlotSeries {
            label: "gas internal".into(),
            points: col(&|x| x.internal),
            style: Style::Line,
        },
        PlotSeries {
            label: "membrane strain".into(),
            points: col(&|x| x.strain),
            style: Style::Line,
        },
        PlotSeries {
            label: "total".into(),
            points: col(&|x| x.kinetic + x.internal + x.strain),
            style: Style::Line,
        },
    ];
    let path = out.join("york_fig13_energy.png");
    plot_xy(
        &path,
        &format!("York Fig. 13: dog-bone energies, h = {h}"),
        "t [-]",
        "energy per unit depth [-]",
        false,
        false,
        &energy,
    )?;
    println!("wrote {}", path.display());
    Ok(())
}

/// York Figs. 16–17: the airbag impact at cell size 10 mm (`--quick`:
/// 20 mm). `shapes`: the bag's meridian and the probe at release, at the
/// peak penetration and at the end (`york_fig16.png`, `york_fig16.csv`);
/// otherwise the probe's displacement into the bag, the bag pressure (point
/// mean and `p V` over the enclosed volume) and the energies against time
/// (`york_fig17_displacement.png`, `york_fig17_pressure.png`,
/// `york_fig17_energy.png`, `york_fig17.csv`).
fn york_airbag_figures(quick: bool, out: &Path, shapes: bool) -> anyhow::Result<()> {
    use mpmice::diagnostics::york_airbag::{run_airbag, Airbag, AirbagSample};
    let h = if quick { 0.02 } else { 0.01 };
    let r = run_airbag(&Airbag {
        h,
        ..Airbag::default()
    })?;
    if shapes {
        let mut csv = String::from("t,kind,r,z\n");
        let mut series = Vec::new();
        for (t, pts) in &r.shapes {
            let pen = r
                .history
                .iter()
                .min_by(|a, b| (a.t - t).abs().total_cmp(&(b.t - t).abs()))
                .map_or(0.0, |s| s.penetration);
            let z0 = r.probe_bottom0 - pen;
            let (pr, pl) = (Airbag::PROBE_RADIUS, Airbag::PROBE_LENGTH);
            let probe = vec![(0.0, z0), (pr, z0), (pr, z0 + pl), (0.0, z0 + pl)];
            for p in pts {
                csv.push_str(&format!("{t},membrane,{},{}\n", p[0], p[1]));
            }
            for p in &probe {
                csv.push_str(&format!("{t},probe,{},{}\n", p.0, p.1));
            }
            series.push(PlotSeries {
                label: format!("bag, t = {:.1} ms", 1e3 * t),
                points: pts.iter().map(|p| (p[0], p[1])).collect(),
                style: Style::Line,
            });
            series.push(PlotSeries {
                label: format!("probe, t = {:.1} ms", 1e3 * t),
                points: probe,
                style: Style::Line,
            });
        }
        series.push(PlotSeries {
            label: String::new(),
            points: vec![(0.0, 0.0), (Airbag::R_MAX, Airbag::Z_MAX)],
            style: Style::Markers,
        });
        std::fs::write(out.join("york_fig16.csv"), csv)?;
        let path = out.join("york_fig16.png");
        plot_xy(
            &path,
            &format!("York Fig. 16: airbag and probe (r-z), h = {} mm", 1e3 * h),
            "r [m]",
            "z [m]",
            false,
            false,
            &series,
        )?;
        println!("wrote {}", path.display());
        return Ok(());
    }
    std::fs::write(out.join("york_fig17.csv"), r.history_csv())?;
    let col = |f: &dyn Fn(&AirbagSample) -> f64| {
        r.history
            .iter()
            .map(|x| (1e3 * x.t, f(x)))
            .collect::<Vec<_>>()
    };
    /// Curves of one plot: (label, points).
    type Curves<'a> = Vec<(&'a str, Vec<(f64, f64)>)>;
    let plots: [(&str, &str, &str, Curves); 3] = [
        (
            "york_fig17_displacement.png",
            "York Fig. 17: probe displacement into the airbag",
            "displacement [mm]",
            vec![("probe", col(&|x| 1e3 * x.penetration))],
        ),
        (
            "york_fig17_pressure.png",
            "airbag pressure",
            "pressure [Pa]",
            vec![
                ("gas point mean", col(&|x| x.mean_pressure)),
                ("sum p V / V_bag", col(&|x| x.volume_pressure)),
            ],
        ),
        (
            "york_fig17_energy.png",
            "airbag energies (change from release)",
            "energy [J]",
            vec![
                ("probe kinetic", col(&|x| x.probe_kinetic)),
                (
                    "gas internal",
                    col(&|x| x.gas_internal - r.inflated.gas_internal),
                ),
                ("gas kinetic", col(&|x| x.gas_kinetic)),
                ("membrane strain", col(&|x| x.membrane_strain)),
                ("total", col(&|x| x.total - r.inflated.total)),
            ],
        ),
    ];
    for (file, title, ylabel, lines) in plots {
        let series: Vec<PlotSeries> = lines
            .into_iter()
            .map(|(label, points)| PlotSeries {
                label: label.into(),
                points,
                style: Style::Line,
            })
            .collect();
        let path = out.join(file);
        plot_xy(
            &path,
            &format!("{title}, h = {} mm", 1e3 * h),
            "t [ms]",
            ylabel,
            false,
            false,
            &series,
        )?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// Zhang Sec. 3, the block test on the scene both formulations run
/// (`cases/zhang_vs_guilkey_block_*.toml`, 40 cells per side; `--quick`:
/// 20): the largest relative air-pressure change at each step against time
/// for Zhang's weak constraint (Eq. 18), the strong one (Eq. 7, until it
/// fails) and Guilkey's MPM-ICE. Log scale; one PNG and one CSV.
fn zhang_block(quick: bool, out: &Path) -> anyhow::Result<()> {
    use mpmice::diagnostics::formulations::{run_block, BlockCase, Formulation};
    let cells = if quick { 20 } else { 40 };
    let runs = [
        (
            Formulation::Multiphase,
            "weak",
            "Zhang, weak constraint (Eq. 18)",
        ),
        (
            Formulation::Multiphase,
            "strong",
            "Zhang, strong constraint (Eq. 7)",
        ),
        (Formulation::Coupled, "weak", "Guilkey MPM-ICE"),
    ];
    let mut series = Vec::new();
    let mut csv = String::from("run,t [s],max |p - p1|/p1 [-],max |v - u|/|u| [-]\n");
    for (f, constraint, label) in runs {
        let r = run_block(&BlockCase {
            formulation: f,
            cells,
            constraint,
            shape: "gimp",
            end: 0.05,
        })?;
        for (t, dp, dv) in &r.history {
            csv.push_str(&format!("{label},{t},{dp},{dv}\n"));
        }
        let end = if r.completed {
            String::new()
        } else {
            format!(
                ", failed at t = {:.2e} s",
                r.history.last().map_or(0.0, |h| h.0)
            )
        };
        series.push(PlotSeries {
            label: format!("{label}: max {:.1e}{end}", r.pressure),
            points: r.history.iter().map(|h| (h.0, h.1)).collect(),
            style: Style::Line,
        });
    }
    std::fs::write(out.join("zhang_block.csv"), csv)?;
    let path = out.join("zhang_block.png");
    plot_xy(
        &path,
        &format!("Zhang block test: disk moving diagonally with the air, {cells} x {cells} cells"),
        "t [s]",
        "max |p - p1| / p1 of the air [-]",
        false,
        true,
        &series,
    )?;
    println!("wrote {}", path.display());
    Ok(())
}

/// A Mach 1.5 shock on a steel block (`cases/shock_on_steel_block_*.toml`,
/// h = 2.5 mm; `--quick`: 5 mm), Zhang's multiphase and Guilkey's MPM-ICE:
/// the probe pressure 2 cm in front of the block against the exact p2 and
/// p5 (`zhang_shock_pressure.png`), and the half block's momentum against
/// the 1D rate (p5 − p1) b from the exact arrival (`zhang_shock_momentum.png`);
/// one CSV.
fn zhang_shock(quick: bool, out: &Path) -> anyhow::Result<()> {
    use mpmice::diagnostics::formulations::{
        run_shock, shock_exact, shock_window, Formulation, ShockCase, HALF_HEIGHT, P1,
    };
    let cells = if quick { 100 } else { 200 };
    let e = shock_exact();
    let end = 6.34e-4;
    let mut pressure = Vec::new();
    let mut momentum = Vec::new();
    let mut csv = String::from("formulation,t [s],probe pressure [Pa],block momentum [N s/m]\n");
    for (f, label) in [
        (Formulation::Multiphase, "Zhang multiphase"),
        (Formulation::Coupled, "Guilkey MPM-ICE"),
    ] {
        let r = run_shock(&ShockCase {
            formulation: f,
            cells,
            end,
        })?;
        for s in &r.history {
            csv.push_str(&format!("{label},{},{},{}\n", s.t, s.probe, s.momentum));
        }
        pressure.push(PlotSeries {
            label: format!("{label}: window mean {:.4} p5", r.front_pressure / e.p5),
            points: r
                .history
                .iter()
                .map(|s| (s.t * 1e3, s.probe / P1))
                .collect(),
            style: Style::Line,
        });
        momentum.push(PlotSeries {
            label: format!(
                "{label}: {:.3} of 1D at the window's end",
                r.momentum_ratio()
            ),
            points: r.history.iter().map(|s| (s.t * 1e3, s.momentum)).collect(),
            style: Style::Line,
        });
    }
    let (w0, w1) = shock_window();
    for (p, name) in [(e.p2, "p2 (incident)"), (e.p5, "p5 (reflected, exact 1D)")] {
        pressure.push(PlotSeries {
            label: format!("{name} = {:.4} p1", p / P1),
            points: vec![(0.0, p / P1), (end * 1e3, p / P1)],
            style: Style::Line,
        });
    }
    pressure.push(PlotSeries {
        label: "averaging window".into(),
        points: vec![
            (w0 * 1e3, 1.0),
            (w0 * 1e3, 6.0),
            (w1 * 1e3, 6.0),
            (w1 * 1e3, 1.0),
        ],
        style: Style::Line,
    });
    momentum.push(PlotSeries {
        label: "1D: (p5 - p1) b (t - t_hit)".into(),
        points: vec![
            (e.t_hit * 1e3, 0.0),
            (end * 1e3, (e.p5 - P1) * HALF_HEIGHT * (end - e.t_hit)),
        ],
        style: Style::Line,
    });
    std::fs::write(out.join("zhang_shock.csv"), csv)?;
    let h = 0.5 / cells as f64;
    for (name, title, ylabel, s) in [
        (
            "zhang_shock_pressure.png",
            format!("Mach 1.5 shock on a steel block, probe 2 cm ahead, h = {h} m"),
            "p / p1 [-]",
            &pressure,
        ),
        (
            "zhang_shock_momentum.png",
            format!("Mach 1.5 shock on a steel block: half block's x-momentum, h = {h} m"),
            "momentum [N s/m]",
            &momentum,
        ),
    ] {
        plot_xy(&out.join(name), &title, "t [ms]", ylabel, false, false, s)?;
        println!("wrote {}", out.join(name).display());
    }
    Ok(())
}

/// Zhang Sec. 4, Fig. 2 (plate spall, `cases/zhang_spall.toml`): the time
/// and the plane of the first failure against the cell size (the
/// `zhang_spall` study's resolutions), with the 1D elastic-wave analysis
/// (3d/c, the target's mid-plane) and the band of every point failed by the
/// end; one PNG each, one CSV.
fn zhang_fig2(quick: bool, out: &Path) -> anyhow::Result<()> {
    use mpmice::diagnostics::zhang_spall::{analytic, run_spall};
    let cells: &[usize] = if quick { &[161, 322] } else { &[161, 322, 644] };
    let (t_exact, x_exact) = analytic();
    let mut csv = String::from("cells,h [m],spall time [s],plane [m],band low [m],band high [m]\n");
    let (mut times, mut planes, mut lows, mut highs) = (vec![], vec![], vec![], vec![]);
    for &n in cells {
        let s = run_spall(n)?;
        let h = 0.0161 / n as f64;
        csv.push_str(&format!(
            "{n},{h},{},{},{},{}\n",
            s.time, s.plane, s.band.0, s.band.1
        ));
        times.push((h * 1e6, s.time * 1e6));
        planes.push((h * 1e6, s.plane * 1e3));
        lows.push((h * 1e6, s.band.0 * 1e3));
        highs.push((h * 1e6, s.band.1 * 1e3));
    }
    std::fs::write(out.join("zhang_fig2.csv"), csv)?;
    let span = |v: &[(f64, f64)]| {
        v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
            (a.0.min(p.0), a.1.max(p.0))
        })
    };
    let (h0, h1) = span(&times);
    plot_xy(
        &out.join("zhang_fig2_time.png"),
        "Zhang Fig. 2 plate spall: first-failure time vs h",
        "h [um]",
        "t [us]",
        false,
        false,
        &[
            PlotSeries {
                label: "multiphase (first failed point)".into(),
                points: times,
                style: Style::LineMarkers,
            },
            PlotSeries {
                label: format!("1D analysis 3d/c = {:.3} us", t_exact * 1e6),
                points: vec![(h0, t_exact * 1e6), (h1, t_exact * 1e6)],
                style: Style::Line,
            },
            PlotSeries {
                label: "Zhang's computed 1.12 us (his plates)".into(),
                points: vec![(h0, 1.12), (h1, 1.12)],
                style: Style::Line,
            },
        ],
    )?;
    plot_xy(
        &out.join("zhang_fig2_plane.png"),
        "Zhang Fig. 2 plate spall: spall plane vs h",
        "h [um]",
        "x [mm]",
        false,
        false,
        &[
            PlotSeries {
                label: "first failed points (mean)".into(),
                points: planes,
                style: Style::LineMarkers,
            },
            PlotSeries {
                label: "lowest failed point at the end".into(),
                points: lows,
                style: Style::LineMarkers,
            },
            PlotSeries {
                label: "highest failed point at the end".into(),
                points: highs,
                style: Style::LineMarkers,
            },
            PlotSeries {
                label: format!("1D analysis: x = {:.2} mm", x_exact * 1e3),
                points: vec![(h0, x_exact * 1e3), (h1, x_exact * 1e3)],
                style: Style::Line,
            },
        ],
    )?;
    println!("wrote {}", out.join("zhang_fig2_time.png").display());
    println!("wrote {}", out.join("zhang_fig2_plane.png").display());
    Ok(())
}

/// Zhang Figs. 3–4 (tungsten rod into steel, `cases/zhang_rod.toml`):
/// penetration P(t) and residual length L(t) at every cell size of the
/// `zhang_rod` study, read from its JSON (run `verification zhang_rod
/// [--quick]` first: R/4 takes about 15 minutes), with the
/// Alekseevskii–Tate model at the study's two target resistances. One PNG
/// each, one CSV.
fn zhang_fig4(quick: bool, out: &Path) -> anyhow::Result<()> {
    use mpmice::diagnostics::zhang_rod::{tate, RHO_PLATE, RHO_ROD, ROD_LENGTH, SPEED};
    use verification::harness::StudyResult;
    use verification::multiphase_rod::{TATE_R, TATE_Y};
    let path = study_results_dir(quick).join("zhang_rod.json");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        anyhow::anyhow!(
            "{}: {e}; run `verification zhang_rod{}` first",
            path.display(),
            if quick { " --quick" } else { "" }
        )
    })?;
    let study: StudyResult = serde_json::from_str(&text)?;
    let runs = study
        .series
        .iter()
        .find(|s| s.label.starts_with("penetration vs"))
        .ok_or_else(|| anyhow::anyhow!("{}: no Tate series", path.display()))?;
    let column = |p: &verification::harness::Point, key: &str| -> Vec<f64> {
        p.extra
            .get(key)
            .and_then(|v| v.as_array())
            .map(|a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect())
            .unwrap_or_default()
    };
    let mut csv = String::from("series,t [s],penetration [m],residual length [m]\n");
    let (mut pen, mut len) = (Vec::new(), Vec::new());
    for p in &runs.points {
        let (t, pp, ll) = (
            column(p, "t_s"),
            column(p, "penetration_m"),
            column(p, "length_m"),
        );
        let label = format!("multiphase h = R/{:.0}", 0.002 / p.h);
        for ((t, pp), ll) in t.iter().zip(&pp).zip(&ll) {
            csv.push_str(&format!("{label},{t},{pp},{ll}\n"));
        }
        pen.push(PlotSeries {
            label: label.clone(),
            points: t.iter().zip(&pp).map(|(t, p)| (t * 1e6, p * 1e3)).collect(),
            style: Style::Line,
        });
        len.push(PlotSeries {
            label,
            points: t.iter().zip(&ll).map(|(t, l)| (t * 1e6, l * 1e3)).collect(),
            style: Style::Line,
        });
    }
    for rt in TATE_R {
        let states = tate(
            SPEED, ROD_LENGTH, RHO_ROD, RHO_PLATE, TATE_Y, rt, 50e-6, 1e-6,
        );
        let label = format!(
            "Tate, Y_p = {:.3} GPa, R_t = {:.2} GPa",
            TATE_Y / 1e9,
            rt / 1e9
        );
        for s in &states {
            csv.push_str(&format!("{label},{},{},{}\n", s.t, s.penetration, s.length));
        }
        pen.push(PlotSeries {
            label: label.clone(),
            points: states
                .iter()
                .map(|s| (s.t * 1e6, s.penetration * 1e3))
                .collect(),
            style: Style::Line,
        });
        len.push(PlotSeries {
            label,
            points: states.iter().map(|s| (s.t * 1e6, s.length * 1e3)).collect(),
            style: Style::Line,
        });
    }
    std::fs::write(out.join("zhang_fig4.csv"), csv)?;
    for (name, title, ylabel, s) in [
        (
            "zhang_fig4_penetration.png",
            "Tungsten rod into steel at 1.7 km/s: penetration vs time",
            "P [mm]",
            &pen,
        ),
        (
            "zhang_fig4_length.png",
            "Tungsten rod into steel at 1.7 km/s: residual rod length vs time",
            "L [mm]",
            &len,
        ),
    ] {
        plot_xy(&out.join(name), title, "t [us]", ylabel, false, false, s)?;
        println!("wrote {}", out.join(name).display());
    }
    Ok(())
}
