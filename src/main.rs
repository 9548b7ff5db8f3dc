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
    },
    /// Validate a scene without running it.
    Check {
        /// Scene file (TOML).
        scene: PathBuf,
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
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
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
        Command::Check { scene } => {
            let s = mpmice::scene::load(&scene)?;
            if !s.membrane_elements.is_empty() {
                writeln!(
                    std::io::stdout(),
                    "{}: ok (3D, {} membrane element meshes, mode {})",
                    scene.display(),
                    s.membrane_elements.len(),
                    s.time.mode.name()
                )?;
                return Ok(());
            }
            writeln!(
                std::io::stdout(),
                "{}: ok ({}D, {} cells, {} materials, {} objects, mode {})",
                scene.display(),
                s.grid.dim,
                s.grid.cells.iter().product::<usize>(),
                s.materials.len(),
                s.objects.len(),
                s.time.mode.name()
            )?;
            Ok(())
        }
        Command::Run {
            scene,
            out,
            threads,
            quiet,
            restart,
        } => {
            let s = mpmice::scene::load(&scene)?;
            let out_dir = out.unwrap_or_else(|| {
                PathBuf::from("out").join(scene.file_stem().unwrap_or_default())
            });
            let opts = mpmice::driver::RunOptions {
                out_dir: out_dir.clone(),
                threads,
                progress: !quiet,
                restart,
                interrupt: Some(interrupt_flag()?),
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
