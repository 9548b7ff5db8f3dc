//! `verification`: runs convergence and work-precision studies and writes
//! `results/STUDY.{json,csv,png}` (full runs also refresh `RESULTS.md`;
//! `--quick` runs write to `results/quick/` and never overwrite them).
//! `verification bench_report` writes `bench/RESULTS.md` from criterion's
//! results instead (`verification::bench_report`).

use std::path::PathBuf;

use anyhow::bail;
use clap::Parser;
use verification::bench_report::{self, BenchReportArgs};
use verification::harness::{write_results_md, write_study, StudyResult};
use verification::STUDIES;

#[derive(Parser)]
#[command(about = "mpmice convergence and work-precision studies")]
struct Args {
    /// Study name, `list`, `all`, `report` (rebuild RESULTS.md from the
    /// stored results only), or `bench_report` (write bench/RESULTS.md from
    /// criterion's results; `bench_report --help` lists its options).
    study: String,
    /// Coarse resolutions only (what the test suite runs).
    #[arg(long)]
    quick: bool,
    /// Output folder (default: verification/results), for the results and
    /// the extra figures some studies draw; `--quick` writes to its
    /// `quick/` subfolder, so it never overwrites the full results.
    #[arg(long)]
    out: Option<PathBuf>,
}

fn main() -> anyhow::Result<()> {
    // `bench_report` has options of its own.
    if std::env::args().nth(1).as_deref() == Some("bench_report") {
        let args = BenchReportArgs::parse_from(std::env::args().skip(1));
        let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
        let root = root.canonicalize().unwrap_or(root);
        let out = bench_report::run(&args, &root)?;
        println!("wrote {}", out.display());
        return Ok(());
    }
    let args = Args::parse();
    if args.study == "list" {
        for (name, about, _) in STUDIES {
            println!("{name:28} {about}");
        }
        return Ok(());
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    if args.study == "report" {
        write_results_md(&root.join("results"), &root.join("RESULTS.md"))?;
        println!("wrote {}", root.join("RESULTS.md").display());
        return Ok(());
    }
    let base = args.out.clone().unwrap_or_else(|| root.join("results"));
    verification::set_results_root(base.clone());
    let out = if args.quick { base.join("quick") } else { base };
    let chosen: Vec<_> = STUDIES
        .iter()
        .filter(|(n, _, _)| args.study == "all" || *n == args.study)
        .collect();
    if chosen.is_empty() {
        let names: Vec<&str> = STUDIES.iter().map(|s| s.0).collect();
        bail!(
            "unknown study `{}`; available: {}, all, list",
            args.study,
            names.join(", ")
        );
    }
    for (name, _, f) in chosen {
        eprintln!("running {name}{}", if args.quick { " (quick)" } else { "" });
        let result: StudyResult = f(args.quick)?;
        for s in &result.series {
            println!("{name:24} {:32} order {:6.3}", s.label, s.observed_order);
            for p in &s.points {
                println!(
                    "    h = {:9.3e}  error = {:10.4e}  wall = {:8.3} s  {:9.3e} updates/s",
                    p.h, p.error, p.wall_s, p.updates_per_s
                );
            }
        }
        write_study(&out, &result)?;
    }
    if !args.quick && args.out.is_none() {
        write_results_md(&out, &root.join("RESULTS.md"))?;
    }
    Ok(())
}
