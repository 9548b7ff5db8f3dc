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
    },
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
        } => {
            let s = mpmice::scene::load(&scene)?;
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
        } => {
            let s = mpmice::scene::load(&scene)?;
            if !quiet {
                eprintln!(
                    "memory: about {}",
                    mpmice::driver::MemoryEstimate::of(&s).describe()
                );
            }
            let out_dir = out.unwrap_or_else(|| {
                PathBuf::from("out").join(scene.file_stem().unwrap_or_default())
            });
            let opts = mpmice::driver::RunOptions {
                out_dir: out_dir.clone(),
                threads,
                progress: !quiet,
                restart,
                interrupt: Some(interrupt_flag()?),
                ignore_memory_limit,
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
            writeln!(
                std::io::stdout(),
                "{}: {} steps to t = {:.6e} in {:.2} s ({rate} on {} threads)",
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
    }
}
