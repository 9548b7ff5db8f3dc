//! The one run loop and the models it drives.
//!
//! [`run_scene`] builds the scene's model — explicit solid, implicit solid,
//! ICE (explicit or semi-implicit pressure), coupled MPM-ICE or membrane
//! finite elements — and hands
//! it to [`run_model`], which owns time control, retries, the watchdog,
//! snapshots, history, checkpoints, restart, a clean stop on interrupt,
//! progress and the summary. A new system implements [`Model`] (see
//! [`model`]) and is run by the same loop.

pub mod limiter;
pub mod memory;
pub mod model;
pub mod models;
pub mod outputs;
pub mod run_loop;
pub mod summary;

pub use limiter::{DtLimiter, LimitCause};
pub use memory::MemoryEstimate;
pub use model::{CoupledIterations, DtRequest, FieldIterations, Model, StepStats};
pub use run_loop::{
    preflight, run_model, scene_hash, Preflight, RunOptions, LAST_GOOD_DIR, MAX_RETRIES,
};
pub use summary::{IterationStats, Summary};

use crate::error::{Error, Result};
use crate::scene::{MaterialKind, Mode, Scene};

/// Builds the scene's model and runs it with outputs in `opts.out_dir`
/// (continuing from `opts.restart` if given).
///
/// It goes through the same checks as [`check_scene`] before the first
/// step: the memory estimate, building the model, and the run loop's
/// [`preflight`].
///
/// # Errors
/// As [`run_model`]; a scene that cannot be built names its key; one that
/// needs more memory than `opts.memory_limit` (default: what the machine
/// has) is refused before allocating unless `opts.ignore_memory_limit`.
pub fn run_scene(scene: &Scene, opts: &RunOptions) -> Result<Summary> {
    run_keeping(scene, opts, false).map(|k| k.summary)
}

/// What a run leaves for a study: its summary, the snapshot fields of its
/// initial and final states and its last history row (all three empty
/// from [`run_scene`], which keeps only the summary).
#[derive(Debug, Clone)]
pub struct KeptRun {
    /// The run summary (as `summary.json`).
    pub summary: Summary,
    /// [`Model::field_sets`] before the first step.
    pub initial: Vec<model::FieldSet<'static>>,
    /// [`Model::field_sets`] at the end.
    pub last: Vec<model::FieldSet<'static>>,
    /// `(column, value)` of the history row at the end (time first).
    pub history: Vec<(String, f64)>,
}

/// [`run_scene`], keeping the initial and final snapshot fields and the
/// final history values (for `mpmice study`).
///
/// # Errors
/// As [`run_scene`].
pub fn run_scene_keep(scene: &Scene, opts: &RunOptions) -> Result<KeptRun> {
    run_keeping(scene, opts, true)
}

/// The memory guard, the thread pool and the run; with `keep`, the fields
/// and history a study reads too.
fn run_keeping(scene: &Scene, opts: &RunOptions, keep: bool) -> Result<KeptRun> {
    guard_memory(scene, opts)?;
    let (pool, threads) = pool(opts)?;
    pool.install(|| {
        with_model(
            scene,
            RunIt {
                opts,
                threads,
                keep,
            },
        )
    })
    .map_err(|e| run_loop::label_error(e, scene))
}

/// What `check` reports of a scene that would run.
#[derive(Debug, Clone)]
pub struct CheckReport {
    /// The model's kind, e.g. `explicit_solid_2d`.
    pub model: String,
    /// Its sizes.
    pub counts: model::Counts,
    /// The memory estimate.
    pub memory: MemoryEstimate,
    /// The first step's Δt and the projected number of steps.
    pub preflight: Preflight,
}

/// Checks a scene the way [`run_scene`] does before its first step —
/// memory estimate, building the model (particles, cells, equilibration)
/// and the run loop's [`preflight`] — without writing anything: a scene
/// `check` accepts is not rejected by `run` before it steps.
///
/// # Errors
/// As [`run_scene`] before its first step.
pub fn check_scene(scene: &Scene, opts: &RunOptions) -> Result<CheckReport> {
    let memory = guard_memory(scene, opts)?;
    let (pool, _) = pool(opts)?;
    pool.install(|| with_model(scene, CheckIt { memory }))
        .map_err(|e| run_loop::label_error(e, scene))
}

/// The memory estimate of `scene`, refused above the limit.
fn guard_memory(scene: &Scene, opts: &RunOptions) -> Result<MemoryEstimate> {
    let est = MemoryEstimate::of(scene);
    if !opts.ignore_memory_limit {
        memory::check_memory(&est, opts.memory_limit)?;
    }
    Ok(est)
}

fn pool(opts: &RunOptions) -> Result<(rayon::ThreadPool, usize)> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads)
        .build()
        .map_err(|e| Error::io(&opts.out_dir, std::io::Error::other(e.to_string())))?;
    let threads = pool.current_num_threads();
    Ok((pool, threads))
}

/// What to do with the scene's model once it is built: run it, or only
/// check it. One building path serves both verbs.
trait WithModel {
    type Out;
    fn with<M: Model>(self, model: &mut M, scene: &Scene) -> Result<Self::Out>;
}

struct RunIt<'a> {
    opts: &'a RunOptions,
    threads: usize,
    /// Keep the initial and final fields and the last history row.
    keep: bool,
}

/// Field sets independent of the model they were read from.
fn owned(sets: Vec<model::FieldSet<'_>>) -> Vec<model::FieldSet<'static>> {
    sets.into_iter().map(model::FieldSet::into_owned).collect()
}

impl WithModel for RunIt<'_> {
    type Out = KeptRun;
    fn with<M: Model>(self, model: &mut M, scene: &Scene) -> Result<KeptRun> {
        let initial = if self.keep {
            owned(model.field_sets())
        } else {
            Vec::new()
        };
        let summary = run_model(model, scene, self.opts, self.threads)?;
        if !self.keep {
            return Ok(KeptRun {
                summary,
                initial,
                last: Vec::new(),
                history: Vec::new(),
            });
        }
        let mut row = vec![model.time()];
        model.history_row(&mut row);
        let names = std::iter::once("time").chain(model.history_columns().into_iter().map(|c| c.0));
        Ok(KeptRun {
            summary,
            initial,
            last: owned(model.field_sets()),
            history: names.map(str::to_string).zip(row).collect(),
        })
    }
}

struct CheckIt {
    memory: MemoryEstimate,
}

impl WithModel for CheckIt {
    type Out = CheckReport;
    fn with<M: Model>(self, model: &mut M, scene: &Scene) -> Result<CheckReport> {
        let preflight = preflight(model, scene)?;
        Ok(CheckReport {
            model: model.kind(),
            counts: model.counts(),
            memory: self.memory,
            preflight,
        })
    }
}

/// Builds the scene's model and hands it to `w`.
fn with_model<W: WithModel>(scene: &Scene, w: W) -> Result<W::Out> {
    if !scene.membrane_elements.is_empty() {
        if scene.grid.dim == 0 {
            let mut m = models::MembraneFe::from_scene(scene)?;
            return w.with(&mut m, scene);
        }
        // Lian Sec. 5–6: MPM bodies and membranes in grid contact.
        let mut m = models::MembraneContact::from_scene(scene)?;
        return w.with(&mut m, scene);
    }
    match scene.grid.dim {
        1 => with_dim::<1, W>(scene, w),
        2 => with_dim::<2, W>(scene, w),
        _ => with_dim::<3, W>(scene, w),
    }
}

fn with_dim<const D: usize, W: WithModel>(scene: &Scene, w: W) -> Result<W::Out> {
    // Gas points (fluids with frame = "particles") run with the solids in
    // the explicit MPM model (York Eq. 17: one nodal velocity field).
    let solid = scene
        .materials
        .iter()
        .any(|m| m.kind == MaterialKind::Solid);
    let fluid = scene.materials.iter().any(|m| m.in_cells());
    if scene.multiphase.is_some() {
        let mut m = models::Multiphase {
            run: crate::scene::build_multiphase_run::<D>(scene)?,
        };
        w.with(&mut m, scene)
    } else if solid && fluid {
        let mut m = models::Coupled {
            run: crate::scene::build_coupled_run::<D>(scene)?,
        };
        w.with(&mut m, scene)
    } else if fluid {
        let (mut state, params) = crate::scene::build_fluid_run::<D>(scene)?;
        crate::ice::equilibrate(&mut state, &params)?;
        let ws = crate::ice::IceWorkspace::new(&state);
        let mut m = models::Fluid { state, params, ws };
        w.with(&mut m, scene)
    } else if scene.time.mode == Mode::Implicit {
        let mut m = models::ImplicitSolid {
            run: crate::scene::build_implicit_run::<D>(scene)?,
            shape: models::scene_name(&scene.mpm.shape),
        };
        w.with(&mut m, scene)
    } else {
        let mut m = models::ExplicitSolid {
            run: crate::scene::build_solid_run::<D>(scene)?,
        };
        w.with(&mut m, scene)
    }
}
