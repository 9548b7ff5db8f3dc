//! The `mpmice` command-line program.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "mpmice",
    version,
    about = "MPM-ICE fluid-structure interaction solver"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene and write its outputs.
    Run {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Output folder (default: out/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Worker threads (default: all cores).
        #[arg(long, default_value_t = 0)]
        threads: usize,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Continue from a checkpoint folder (`OUT/checkpoints/step_N`) of a
        /// run of the same scene; the outputs continue in the output folder.
        #[arg(long, value_name = "DIR")]
        restart: Option<PathBuf>,
        /// Run a scene whose memory estimate exceeds the available memory.
        #[arg(long)]
        ignore_memory_limit: bool,
        /// Override a scene key: `--set grid.cells=[800] --set
        /// materials.gas.gamma=1.4` (repeatable; see the README).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Write into a non-empty output folder: a previous run's outputs
        /// there (snapshots, series, history, summary, checkpoints) are
        /// removed first.
        #[arg(long)]
        force: bool,
    },
    /// A convergence study of the scene: run it at grid.cells × 1, 2, …,
    /// 2^N (particles per cell fixed), measure a field's error against a
    /// reference and the observed order; writes STUDY.json, .csv and .png
    /// like the built-in studies, and each run's outputs below.
    Study(StudyArgs),
    /// Validate a scene without running it: everything `run` checks before
    /// its first step (building the particles and cells included), and the
    /// memory estimate.
    Check {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Accept a scene whose memory estimate exceeds the available
        /// memory (it is then built to check it).
        #[arg(long)]
        ignore_memory_limit: bool,
        /// Override a scene key (repeatable), as for `run`.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        // A closed stdout (`mpmice run … | head -1`) is no failure of the run.
        Err(e)
            if e.downcast_ref::<std::io::Error>()
                .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe) =>
        {
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {}", message(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes, each cause once: a cause whose text the
/// message already holds (an I/O error quoted by its wrapper) is not
/// repeated.
fn message(e: &anyhow::Error) -> String {
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !msg.contains(&c) {
            msg.push_str(": ");
            msg.push_str(&c);
        }
    }
    msg
}

/// A flag set by the first Ctrl-C (SIGINT): the run stops cleanly at the end
/// of the current step and writes a checkpoint. A second Ctrl-C exits at
/// once (status 130).
fn interrupt_flag() -> anyhow::Result<Arc<AtomicBool>> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    ctrlc::set_handler(move || {
        if f.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    })?;
    Ok(flag)
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Check {
            scene,
            ignore_memory_limit,
            set,
        } => {
            let s = mpmice::scene::load_with(&scene, &overrides(&set)?)?;
            let opts = mpmice::driver::RunOptions {
                ignore_memory_limit,
                ..Default::default()
            };
            let report = mpmice::driver::check_scene(&s, &opts)?;
            let mut out = std::io::stdout();
            if !s.membrane_elements.is_empty() {
                writeln!(
                    out,
                    "{}: ok (3D, {} membrane element meshes, mode {})",
                    scene.display(),
                    s.membrane_elements.len(),
                    s.time.mode.name()
                )?;
            } else {
                writeln!(
                    out,
                    "{}: ok ({}D, {} cells, {} materials, {} objects, {} particles, mode {})",
                    scene.display(),
                    s.grid.dim,
                    s.grid.cells.iter().product::<usize>(),
                    s.materials.len(),
                    s.objects.len(),
                    report.counts.particles,
                    s.time.mode.name()
                )?;
            }
            let available = mpmice::driver::memory::available_memory()
                .map_or("unknown".to_string(), |b| {
                    mpmice::driver::memory::bytes(b as f64)
                });
            writeln!(
                out,
                "memory: about {} ({available} available)",
                report.memory.describe()
            )?;
            writeln!(
                out,
                "first Δt {:.3e} s, about {:.3e} steps to time.end",
                report.preflight.dt, report.preflight.projected_steps
            )?;
            Ok(())
        }
        Command::Run {
            scene,
            out,
            threads,
            quiet,
            restart,
            ignore_memory_limit,
            set,
            force,
        } => {
            let s = mpmice::scene::load_with(&scene, &overrides(&set)?)?;
            if !quiet {
                eprintln!(
                    "memory: about {}",
                    mpmice::driver::MemoryEstimate::of(&s).describe()
                );
            }
            let out_dir = out.unwrap_or_else(|| {
                PathBuf::from("out").join(scene.file_stem().unwrap_or_default())
            });
            if restart.is_none() {
                claim_out_dir(&out_dir, force)?;
            }
            let opts = mpmice::driver::RunOptions {
                out_dir: out_dir.clone(),
                threads,
                progress: !quiet,
                restart,
                interrupt: Some(interrupt_flag()?),
                ignore_memory_limit,
                command_line: std::env::args().collect(),
                ..Default::default()
            };
            let sum = mpmice::driver::run_scene(&s, &opts)?;
            let rate = if sum.n_elements > 0 {
                format!(
                    "{} membrane elements, {:.3e} element-steps/s",
                    sum.n_elements, sum.element_steps_per_s
                )
            } else if sum.n_particles > 0 {
                format!(
                    "{} particles, {} cells, {:.3e} particle-steps/s",
                    sum.n_particles, sum.n_cells, sum.particle_steps_per_s
                )
            } else {
                format!(
                    "{} cells, {} fluid materials, {:.3e} cell-steps/s",
                    sum.n_cells, sum.n_fluid_materials, sum.cell_steps_per_s
                )
            };
            let peak = sum.peak_memory_bytes.map_or(String::new(), |b| {
                let per = sum
                    .peak_memory_per_particle
                    .map_or(String::new(), |p| format!(", {p:.0} B a particle"));
                format!(
                    "; peak memory {}{per}",
                    mpmice::driver::memory::bytes(b as f64)
                )
            });
            writeln!(
                std::io::stdout(),
                "{}: {} steps to t = {:.6e} in {:.2} s ({rate} on {} threads{peak})",
                scene.display(),
                sum.steps,
                sum.final_time,
                sum.wall_s,
                sum.threads
            )?;
            // A drift a mode does not report (NaN, JSON null) prints "n/a".
            let show = |x: f64| {
                if x.is_nan() {
                    "n/a".to_string()
                } else {
                    format!("{x:.2e}")
                }
            };
            if let Some(b) = &sum.boundary_exchange {
                let crossed =
                    b.mass != 0.0 || b.energy != 0.0 || b.momentum.iter().any(|&x| x != 0.0);
                // Where the model does not account for momentum (its drift
                // is n/a), no impulse is shown.
                let momentum = if sum.momentum_drift.is_nan() {
                    "n/a".to_string()
                } else {
                    format!(
                        "({:.4e}, {:.4e}, {:.4e})",
                        b.momentum[0], b.momentum[1], b.momentum[2]
                    )
                };
                if crossed {
                    writeln!(
                        std::io::stdout(),
                        "through the boundary: mass {:.4e}, momentum {momentum}, energy {:.4e} (the drifts are net of it)",
                        b.mass, b.energy
                    )?;
                }
                let sources = [
                    ("heat sources", b.source_energy),
                    ("reactions", b.reaction_energy),
                    ("prescribed motion and loads", b.prescribed_work),
                    ("damping", b.damping_work),
                ];
                if sources.iter().any(|s| s.1 != 0.0) {
                    let list: Vec<String> = sources
                        .iter()
                        .filter(|s| s.1 != 0.0)
                        .map(|(what, e)| format!("{what} {e:.4e}"))
                        .collect();
                    writeln!(
                        std::io::stdout(),
                        "energy put in by {} (the energy drift is net of it)",
                        list.join(", ")
                    )?;
                }
                let g = b.body_momentum;
                if g.iter().any(|&x| x != 0.0) {
                    writeln!(
                        std::io::stdout(),
                        "body force impulse: ({:.4e}, {:.4e}, {:.4e}), work {:.4e} outside the potential energy (the drifts are net of them)",
                        g[0], g[1], g[2], b.body_work
                    )?;
                }
            }
            writeln!(
                std::io::stdout(),
                "drift: mass {}, momentum {}, energy {}; outputs in {}",
                show(sum.mass_drift),
                show(sum.momentum_drift),
                show(sum.energy_drift),
                out_dir.display()
            )?;
            Ok(())
        }
        Command::Study(args) => study(args),
    }
}

/// The `--set` arguments.
fn overrides(set: &[String]) -> anyhow::Result<Vec<mpmice::scene::Override>> {
    Ok(set
        .iter()
        .map(|a| mpmice::scene::Override::parse(a))
        .collect::<Result<_, _>>()?)
}

/// Refuses a non-empty output folder unless `force`; with `force`,
/// removes what a previous run wrote there (snapshots, series, history,
/// summary, study results, checkpoints and study runs), so that no stale
/// file sits beside the new ones. Other files are left alone.
fn claim_out_dir(dir: &std::path::Path, force: bool) -> anyhow::Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    let entries: Vec<_> = entries.filter_map(|e| e.ok()).collect();
    if entries.is_empty() {
        return Ok(());
    }
    if !force {
        anyhow::bail!(
            "output folder {} is not empty ({} entries): pass --force to replace a previous \
             run's outputs there, or choose another --out",
            dir.display(),
            entries.len()
        );
    }
    for e in entries {
        let name = e.file_name().to_string_lossy().to_string();
        let path = e.path();
        let ours_dir =
            name == "checkpoints" || name.starts_with("series_") || name.ends_with("_npy");
        let ours_file = name == "history.csv"
            || name == "summary.json"
            || [".pvd", ".vtu", ".vti", ".vtp", ".csv", ".json", ".png"]
                .iter()
                .any(|x| name.ends_with(x));
        if ours_dir && path.is_dir() {
            std::fs::remove_dir_all(&path)
                .map_err(|err| anyhow::anyhow!("removing {}: {err}", path.display()))?;
        } else if ours_file && path.is_file() {
            std::fs::remove_file(&path)
                .map_err(|err| anyhow::anyhow!("removing {}: {err}", path.display()))?;
        }
    }
    Ok(())
}

/// The arguments of `mpmice study`.
#[derive(clap::Args)]
struct StudyArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Halvings of the cell size (N + 1 runs per series).
    #[arg(long, default_value_t = 2)]
    refine: usize,
    /// Override a scene key (repeatable), as for `run`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Sweep a key: one series per value, `--sweep fluid.variant=literal,high_resolution`
    /// (commas inside [ ], { } and quotes do not split).
    #[arg(long, value_name = "KEY=V1,V2,...")]
    sweep: Option<String>,
    /// The field whose error is measured, SET.FIELD (default
    /// cells.mixture_density, or particles.velocity without cells).
    #[arg(long)]
    field: Option<String>,
    /// What the errors are measured against: `finest` (the finest run)
    /// or `riemann` (exact solution of a 1D two-state fluid scene).
    #[arg(long, default_value = "finest")]
    reference: String,
    /// A history column whose final value gets Richardson's estimate
    /// of its order, converged value and uncertainty.
    #[arg(long)]
    quantity: Option<String>,
    /// Output folder (default: out/study_<scene name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write into a non-empty output folder (see `run --force`).
    #[arg(long)]
    force: bool,
    /// Worker threads per run (default: all cores).
    #[arg(long, default_value_t = 0)]
    threads: usize,
}

fn study(a: StudyArgs) -> anyhow::Result<()> {
    use mpmice::study::{harness, run_study, Reference, StudySpec};
    let text = std::fs::read_to_string(&a.scene)
        .map_err(|e| anyhow::anyhow!("cannot read {}: {e}", a.scene.display()))?;
    let set = overrides(&a.set)?;
    // The scene as given must load (errors named by key path).
    mpmice::scene::parse_with(&text, &set)?;
    let sweep = match &a.sweep {
        None => None,
        Some(arg) => {
            let (key, list) = arg
                .split_once('=')
                .ok_or_else(|| anyhow::anyhow!("--sweep `{arg}` is not KEY=V1,V2,..."))?;
            Some((key.trim().to_string(), mpmice::scene::split_values(list)))
        }
    };
    let stem = a.scene.file_stem().unwrap_or_default().to_string_lossy();
    let spec = StudySpec {
        name: format!("study_{stem}"),
        refine: a.refine,
        field: a.field,
        reference: Reference::parse(&a.reference)?,
        quantity: a.quantity,
        sweep,
    };
    let out = a
        .out
        .unwrap_or_else(|| mpmice::study::default_out(&a.scene));
    claim_out_dir(&out, a.force)?;
    let result = run_study(&text, &set, &spec, &out, a.threads, &mut |line| {
        eprintln!("{line}")
    })?;
    harness::write_study(&out, &result)?;
    let mut o = std::io::stdout();
    for s in &result.series {
        writeln!(
            o,
            "{} [{}]: observed order {:.3}",
            s.label, s.norm, s.observed_order
        )?;
        for p in &s.points {
            writeln!(
                o,
                "  h = {:.4e}  error = {:.4e}  wall {:.2} s",
                p.h, p.error, p.wall_s
            )?;
        }
    }
    for n in &result.notes {
        writeln!(o, "{n}")?;
    }
    writeln!(o, "results in {}", out.display())?;
    Ok(())
}
