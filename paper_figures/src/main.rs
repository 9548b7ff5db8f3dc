//! `paper_figures`: regenerates the paper figures and tables this project
//! reproduces (PNG + CSV in `paper_figures/output/`).
//!
//! Available now: the convergence figure of the explicit MPM study
//! (`mpm_convergence`, from the axis-aligned manufactured solution). The
//! Guilkey figures (pressurised cylinder 3a/3b, piston 4, wedge 5) arrive with
//! the MPM-ICE coupling.

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

const FIGURES: &[(&str, &str)] = &[(
    "mpm_convergence",
    "error vs h of the axis-aligned MMS, 2D, every shape function, A = 0.05 (cell crossing)",
)];

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
