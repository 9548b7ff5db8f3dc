//! `paper_figures`: regenerates the paper figures and tables this project
//! reproduces (PNG + CSV in `paper_figures/output/`).
//!
//! Available: the convergence figure of the explicit MPM study
//! (`mpm_convergence`, from the axis-aligned manufactured solution), and the
//! Guilkey figures of the MPM-ICE coupling: `guilkey_fig3` (pressurised
//! cylinder: 3a stresses of the row nearest the x-axis vs Lamé, 3b ln error
//! vs ln dx with the fitted slope), `guilkey_fig4` (piston: closed-end
//! pressure vs compression ratio against P1 (V1/V2)^γ) and `guilkey_fig5`
//! (Mach 3 wedge: pressure field with the exact and measured shock).

use std::path::PathBuf;

use anyhow::bail;
use clap::Parser;
use verification::harness::{plot_xy, PlotSeries, Style};

#[derive(Parser)]
#[command(about = "Regenerate paper figures")]
struct Args {
    /// Figure name or `list`.
    figure: String,
    /// Coarse resolutions only.
    #[arg(long)]
    quick: bool,
}

const FIGURES: &[(&str, &str)] = &[
    (
        "mpm_convergence",
        "error vs h of the axis-aligned MMS, 2D, every shape function, A = 0.05 (cell crossing)",
    ),
    (
        "guilkey_fig3",
        "pressurised cylinder, MPM-ICE: 3a stresses vs Lame, 3b ln(Eq. 43 error) vs ln(dx)",
    ),
    (
        "guilkey_fig4",
        "adiabatic piston, MPM-ICE: closed-end pressure vs compression ratio",
    ),
    (
        "guilkey_fig5",
        "Mach 3 wedge, MPM-ICE: pressure field with the exact and measured shock",
    ),
];

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    match args.figure.as_str() {
        "list" => {
            for (n, d) in FIGURES {
                println!("{n:20} {d}");
            }
            Ok(())
        }
        "mpm_convergence" => mpm_convergence(args.quick),
        "guilkey_fig3" => guilkey_fig3(args.quick),
        "guilkey_fig4" => guilkey_fig4(args.quick),
        "guilkey_fig5" => guilkey_fig5(args.quick),
        other => bail!(
            "unknown figure `{other}`; available: {}, list",
            FIGURES.iter().map(|f| f.0).collect::<Vec<_>>().join(", ")
        ),
    }
}

fn mpm_convergence(quick: bool) -> anyhow::Result<()> {
    let out = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("output");
    std::fs::create_dir_all(&out)?;
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
        "h",
        "max_t RMS displacement error / A",
        true,
        true,
        &series,
    )?;
    println!("wrote {}", out.join("mpm_convergence.png").display());
    Ok(())
}

fn out_dir() -> anyhow::Result<PathBuf> {
    let out = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("output");
    std::fs::create_dir_all(&out)?;
    Ok(out)
}

/// The study's own plots live next to its results; copy one here.
fn copy_study_plot(name: &str, quick: bool, out: &std::path::Path) -> anyhow::Result<()> {
    let mut src = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../verification/results");
    if quick {
        src = src.join("quick");
    }
    std::fs::copy(src.join(name), out.join(name))?;
    println!("wrote {}", out.join(name).display());
    Ok(())
}

fn guilkey_fig3(quick: bool) -> anyhow::Result<()> {
    let out = out_dir()?;
    let result = verification::coupled_studies::cylinder_order(quick)?;
    copy_study_plot("cylinder_order_fig3a.png", quick, &out)?;
    let s = &result.series[0];
    let pts: Vec<(f64, f64)> = s.points.iter().map(|p| (p.h.ln(), p.error.ln())).collect();
    // Least-squares line through (ln dx, ln error), as Guilkey Fig. 3b.
    let n = pts.len() as f64;
    let (sx, sy) = pts.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let (sxx, sxy) = pts
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0 * p.0, a.1 + p.0 * p.1));
    let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    let icpt = (sy - slope * sx) / n;
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
        "ln dx",
        "ln error (Eq. 43)",
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

fn guilkey_fig4(quick: bool) -> anyhow::Result<()> {
    let out = out_dir()?;
    verification::coupled_studies::piston_adiabatic(quick)?;
    copy_study_plot("piston_adiabatic_fig4.png", quick, &out)
}

/// Guilkey Fig. 5: the `wedge_mach3` study's pressure field (h = 0.0025;
/// the quick study's h = 0.005).
fn guilkey_fig5(quick: bool) -> anyhow::Result<()> {
    let out = out_dir()?;
    verification::coupled_studies::wedge_mach3(quick)?;
    copy_study_plot("wedge_mach3_fig5.png", quick, &out)
}
