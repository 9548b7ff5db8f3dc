//! What the run loop costs over a bare stepping loop (issue 14), one
//! configuration per process so that `/usr/bin/time -f %U` gives its CPU
//! time:
//!
//! `cargo run --release -p probes --bin run_loop_cost -- CASE CELLS MODE`
//!
//! `CASE` is `sod` (1D explicit ICE, `cases/sod.toml` to t = 0.2) or
//! `two_disks` (2D explicit MPM, `cases/two_disks.toml` to t = 1),
//! `CELLS` the cells per direction, no snapshot files in either. `MODE`:
//! - `bare`: `Model::step` in a plain loop (this crate's instantiation);
//! - `loop`: `run_scene` with the scene's defaults (watchdog, history);
//! - `no_watchdog`: the same with `time.watchdog_interval = 0`;
//! - `minimal`: no watchdog and a single history row;
//! - `local_loop`: `run_model` on a model built here (`two_disks` only): the
//!   loop instantiated in this crate, as `bare` is, so the difference from
//!   `bare` is the loop's own work and not the library's code generation;
//! - `parts`: `bare`, then the mean time of one watchdog scan, one copy of
//!   the state into a checkpoint (what the loop keeps as the last good
//!   state) and one history row, over 20 calls each.
//!
//! `loop`, `no_watchdog` and `minimal` call `run_scene`, which builds its own
//! one-thread pool, as `mpmice run --threads 1` does; the other modes run in
//! a one-thread pool built here. Prints the wall time and the step count.

use std::time::Instant;

use mpmice::driver::models::{ExplicitSolid, Fluid};
use mpmice::driver::{run_model, run_scene, DtRequest, Model, RunOptions};
use mpmice::ice::{self, IceWorkspace};
use mpmice::scene::{self, Scene};

/// Mean seconds of one call of `f` over `n` calls.
fn mean_s(n: u32, mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    for _ in 0..n {
        f();
    }
    start.elapsed().as_secs_f64() / f64::from(n)
}

/// Prints what one watchdog scan, one state copy and one history row of
/// `m` cost.
fn parts<M: Model>(m: &M) {
    let mut ck = mpmice::output::checkpoint::Checkpoint::new(&m.kind(), "", 0, 0.0);
    let scan = mean_s(20, || {
        std::hint::black_box(m.watchdog());
    });
    let copy = mean_s(20, || m.save(&mut ck));
    let mut row = Vec::new();
    let history = mean_s(20, || {
        row.clear();
        m.history_row(&mut row);
    });
    println!(
        "watchdog scan {:.3} ms, state copy {:.3} ms, history row {:.3} ms",
        1e3 * scan,
        1e3 * copy,
        1e3 * history
    );
}

/// Steps `m` to `end` with the largest stable steps.
fn bare<M: Model>(m: &mut M, end: f64) -> anyhow::Result<u64> {
    while m.time() < end * (1.0 - 1e-12) {
        let left = end - m.time();
        m.step(DtRequest {
            value: left,
            exact: false,
        })?;
    }
    Ok(m.steps())
}

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let case = a.get(1).map_or("sod", String::as_str);
    let cells: usize = a.get(2).map_or(Ok(3200), |s| s.parse())?;
    let mode = a.get(3).map_or("loop", String::as_str);
    let mut sc: Scene = scene::load(std::path::Path::new(&format!("cases/{case}.toml")))?;
    sc.grid.cells = vec![cells; sc.grid.dim];
    sc.output.formats = vec![];
    if case == "two_disks" {
        sc.time.end = 1.0;
    }
    match mode {
        "no_watchdog" => sc.time.watchdog_interval = 0,
        "minimal" | "local_loop" => {
            sc.time.watchdog_interval = 0;
            sc.output.history_interval = Some(sc.time.end);
        }
        _ => {}
    }
    let out = std::env::temp_dir().join(format!("run_loop_cost_{}", std::process::id()));
    let opts = RunOptions::quiet(&out, 1);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let start = Instant::now();
    // `run_scene` builds its own pool of `opts.threads`, as the CLI's run
    // does: not inside this one.
    let steps = if matches!(mode, "loop" | "no_watchdog" | "minimal") {
        run_scene(&sc, &opts)?.steps
    } else {
        pool.install(|| -> anyhow::Result<u64> {
            match (mode, case) {
                ("bare" | "parts", "two_disks") => {
                    let mut m = ExplicitSolid {
                        run: scene::build_solid_run::<2>(&sc)?,
                    };
                    let steps = bare(&mut m, sc.time.end)?;
                    if mode == "parts" {
                        parts(&m);
                    }
                    Ok(steps)
                }
                ("bare" | "parts", _) => {
                    let (mut state, params) = scene::build_fluid_run::<1>(&sc)?;
                    ice::equilibrate(&mut state, &params)?;
                    let ws = IceWorkspace::new(&state);
                    let mut m = Fluid { state, params, ws };
                    let steps = bare(&mut m, sc.time.end)?;
                    if mode == "parts" {
                        parts(&m);
                    }
                    Ok(steps)
                }
                ("local_loop", "two_disks") => {
                    let mut m = ExplicitSolid {
                        run: scene::build_solid_run::<2>(&sc)?,
                    };
                    Ok(run_model(&mut m, &sc, &opts, 1)?.steps)
                }
                _ => {
                    anyhow::bail!(
                        "MODE: bare | loop | no_watchdog | minimal | local_loop (two_disks)"
                    )
                }
            }
        })?
    };
    println!(
        "{case} {cells} {mode}: {steps} steps, {:.3} s",
        start.elapsed().as_secs_f64()
    );
    let _ = std::fs::remove_dir_all(&out);
    Ok(())
}
