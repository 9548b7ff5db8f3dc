//! The one run loop: time control, retries, the watchdog, snapshot and
//! history cadence, checkpoints, restart, a clean stop on interrupt,
//! progress and the summary — for every [`Model`].

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use crate::driver::model::{Conserved, DtRequest, MaterialTotals, Model};
use crate::driver::outputs::Outputs;
use crate::driver::summary::{write_summary, IterationStats, Summary};
use crate::error::{Error, Result};
use crate::ice::BoundaryExchange;
use crate::output::checkpoint::{content_hash, Checkpoint, CheckpointError};
use crate::scene::{OutputSpec, Scene};
use crate::stepper::Energies;

/// Halvings of the time step tried before a recoverable step failure is
/// given up.
pub const MAX_RETRIES: u32 = 20;

/// A time reached "at" a target within this relative round-off.
const NEAR: f64 = 1.0 - 1e-12;

/// How to run a scene.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Output folder (created if missing).
    pub out_dir: PathBuf,
    /// Worker threads (0: rayon's default, all cores).
    pub threads: usize,
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// Continue from this checkpoint folder instead of the initial state.
    pub restart: Option<PathBuf>,
    /// The command line, recorded in the summary's provenance.
    pub command_line: Vec<String>,
    /// Set (e.g. by a Ctrl-C handler) to stop cleanly at the end of the
    /// current step, with a checkpoint.
    pub interrupt: Option<Arc<AtomicBool>>,
    /// The memory a scene may use \[bytes\] (`None`: what the machine has
    /// available); a scene estimated above it is refused before anything
    /// is allocated.
    pub memory_limit: Option<u64>,
    /// Go on with a scene estimated above the memory limit.
    pub ignore_memory_limit: bool,
}

impl RunOptions {
    /// Writing to `out_dir` on `threads` threads without a progress bar,
    /// everything else as [`Default`]: how tests and scripts run a scene.
    pub fn quiet(out_dir: impl Into<PathBuf>, threads: usize) -> Self {
        Self {
            out_dir: out_dir.into(),
            threads,
            ..Default::default()
        }
    }
}

/// What the run loop checks before the first step (shared by `check` and
/// `run`): the state passes the watchdog (unless it is off), and the first
/// Δt is positive and
/// does not project more than `time.max_projected_steps` steps to the end
/// (unless `time.max_steps` bounds the run).
#[derive(Debug, Clone)]
pub struct Preflight {
    /// The first step's Δt: `time.dt`, else the model's stable Δt.
    pub dt: f64,
    /// `(end − t) / dt`.
    pub projected_steps: f64,
    /// What sets the stable Δt, where the model says.
    pub limiter: Option<crate::driver::DtLimiter>,
}

/// The checks before the first step; see [`Preflight`].
///
/// # Errors
/// [`Error::Watchdog`] for an impossible initial value; [`Error::Progress`]
/// for a Δt that is not positive or projects an absurd number of steps,
/// naming what sets it.
pub fn preflight<M: Model>(model: &M, scene: &Scene) -> Result<Preflight> {
    let scan = scene.time.watchdog_interval > 0;
    if let Some(v) = scan.then(|| model.watchdog()).flatten() {
        return Err(Error::Watchdog {
            step: model.steps(),
            time: model.time(),
            what: scene.label_materials(&v.to_string()),
        });
    }
    let t = &scene.time;
    let dt = t.dt.unwrap_or_else(|| model.stable_dt());
    let left = (t.end - model.time()).max(0.0);
    let projected_steps = left / dt;
    let limiter = model.dt_limiter();
    let bounded = t
        .max_steps
        .is_some_and(|n| (n as f64) <= t.max_projected_steps);
    let no_progress = |why: String| Error::Progress {
        step: model.steps(),
        time: model.time(),
        what: scene.label_materials(&why),
    };
    let set_by = |l: &Option<crate::driver::DtLimiter>| match (t.dt, l) {
        (Some(_), _) => "set by time.dt".to_string(),
        (None, Some(l)) => format!("set by {l}"),
        (None, None) => "the model's stable step".to_string(),
    };
    if dt.is_nan() || dt <= 0.0 {
        return Err(no_progress(format!(
            "the first Δt is {dt:e} ({}); check the material constants",
            set_by(&limiter)
        )));
    }
    if !bounded && projected_steps > t.max_projected_steps {
        return Err(no_progress(format!(
            "time.end = {:e} at Δt = {dt:.3e} s projects {projected_steps:.3e} steps, more \
             than time.max_projected_steps = {:e} (Δt {}); check the material constants \
             and time.dt, or raise time.max_projected_steps or set time.max_steps",
            t.end,
            t.max_projected_steps,
            set_by(&limiter)
        )));
    }
    Ok(Preflight {
        dt,
        projected_steps,
        limiter,
    })
}

/// The content hash of a scene's physics: everything but its description,
/// outputs, end time, step limit and watchdog interval (a checkpoint may be
/// continued with those changed, never with another set-up).
pub fn scene_hash(scene: &Scene) -> String {
    let mut s = scene.clone();
    s.description = String::new();
    s.output = OutputSpec::default();
    s.time.end = 0.0;
    s.time.max_steps = None;
    s.time.watchdog_interval = 0;
    s.time.last_good = crate::scene::LastGood::Auto;
    s.time.min_dt_fraction = crate::scene::DEFAULT_MIN_DT_FRACTION;
    s.time.max_projected_steps = crate::scene::DEFAULT_MAX_PROJECTED_STEPS;
    // A scene always serialises (plain data); an error would hash as empty.
    content_hash(&serde_json::to_vec(&s).unwrap_or_default())
}

/// Time control and output cadence from the scene.
struct Cadence {
    end: f64,
    fixed_dt: Option<f64>,
    max_steps: u64,
    interval: Option<f64>,
    history: Option<f64>,
    checkpoint: Option<f64>,
    keep: usize,
    watchdog: u64,
    min_dt_fraction: f64,
}

impl Cadence {
    fn of(scene: &Scene) -> Self {
        let o = &scene.output;
        Self {
            end: scene.time.end,
            fixed_dt: scene.time.dt,
            max_steps: scene.time.max_steps.unwrap_or(u64::MAX),
            interval: o.interval,
            history: o.history_interval.or(o.interval.map(|i| i / 20.0)),
            checkpoint: o.checkpoint_interval,
            keep: o.checkpoint_keep,
            watchdog: scene.time.watchdog_interval,
            min_dt_fraction: scene.time.min_dt_fraction,
        }
    }

    fn finished(&self, t: f64, steps: u64) -> bool {
        t >= self.end * NEAR || steps >= self.max_steps
    }
}

/// The loop's own state: saved in every checkpoint, so that a restarted run
/// continues its cadence, statistics and drifts.
#[derive(Debug, Clone)]
struct LoopState {
    next_out: f64,
    next_hist: f64,
    next_ckpt: f64,
    dt_min: f64,
    dt_max: f64,
    /// The loop's retries (steps repeated with a smaller Δt).
    retries: u64,
    iters: IterationStats,
    initial: Conserved,
    /// What entered through the domain boundary so far, where the model
    /// accounts for it (`None`: it does not).
    exchange: Option<BoundaryExchange>,
}

impl LoopState {
    fn fresh(c: &Cadence, initial: Conserved) -> Self {
        Self {
            next_out: c.interval.unwrap_or(f64::INFINITY),
            next_hist: c.history.unwrap_or(0.0),
            next_ckpt: c.checkpoint.unwrap_or(f64::INFINITY),
            dt_min: f64::INFINITY,
            dt_max: 0.0,
            retries: 0,
            iters: IterationStats::default(),
            initial,
            exchange: None,
        }
    }

    fn save(&self, ck: &mut Checkpoint) {
        let e = &self.initial.energies;
        ck.put_f64(
            "loop.scalars",
            vec![11],
            vec![
                self.next_out,
                self.next_hist,
                self.next_ckpt,
                self.dt_min,
                self.dt_max,
                self.iters.nonlinear_mean,
                self.iters.linear_mean,
                self.initial.momentum_scale,
                e.kinetic,
                e.strain,
                e.potential,
            ],
        );
        ck.put_u64(
            "loop.counters",
            vec![4],
            vec![
                self.retries,
                self.iters.nonlinear_max as u64,
                self.iters.linear_max as u64,
                self.iters.retries,
            ],
        );
        let m = &self.initial.materials;
        let data = m
            .iter()
            .flat_map(|t| {
                [
                    t.mass,
                    t.momentum[0],
                    t.momentum[1],
                    t.momentum[2],
                    t.kinetic,
                    t.internal,
                ]
            })
            .collect();
        ck.put_f64("loop.initial_materials", vec![m.len(), 6], data);
        let x = self.exchange;
        let b = x.unwrap_or_default();
        ck.put_f64(
            "loop.exchange",
            vec![14],
            vec![
                if x.is_some() { 1.0 } else { 0.0 },
                b.mass,
                b.momentum[0],
                b.momentum[1],
                b.momentum[2],
                b.energy,
                b.body_momentum[0],
                b.body_momentum[1],
                b.body_momentum[2],
                b.body_work,
                b.source_energy,
                b.prescribed_work,
                b.damping_work,
                b.reaction_energy,
            ],
        );
    }

    /// Restores the state saved by [`Self::save`]; `names` are the model's
    /// material names, in order.
    fn load(ck: &mut Checkpoint, names: &[String]) -> Result<Self, CheckpointError> {
        let s = ck.take_f64("loop.scalars", Some(&[11]))?;
        let c = ck.take_u64("loop.counters", Some(&[4]))?;
        let m = ck.take_f64("loop.initial_materials", Some(&[names.len(), 6]))?;
        // Checkpoints before the body-force columns hold 6 entries, before
        // the source, prescribed-motion, damping and reaction columns 10.
        let mut x = ck.take_f64("loop.exchange", None)?;
        if ![6, 10, 14].contains(&x.len()) {
            return Err(CheckpointError::Malformed {
                what: "array loop.exchange".into(),
                reason: format!("{} entries, expected 6, 10 or 14", x.len()),
            });
        }
        x.resize(14, 0.0);
        let exchange = (x[0] != 0.0).then_some(BoundaryExchange {
            mass: x[1],
            momentum: [x[2], x[3], x[4]],
            energy: x[5],
            body_momentum: [x[6], x[7], x[8]],
            body_work: x[9],
            source_energy: x[10],
            prescribed_work: x[11],
            damping_work: x[12],
            reaction_energy: x[13],
        });
        let materials = names
            .iter()
            .zip(m.chunks_exact(6))
            .map(|(name, v)| MaterialTotals {
                name: name.clone(),
                mass: v[0],
                momentum: [v[1], v[2], v[3]],
                kinetic: v[4],
                internal: v[5],
            })
            .collect();
        Ok(Self {
            next_out: s[0],
            next_hist: s[1],
            next_ckpt: s[2],
            dt_min: s[3],
            dt_max: s[4],
            retries: c[0],
            iters: IterationStats {
                nonlinear_mean: s[5],
                linear_mean: s[6],
                nonlinear_max: c[1] as usize,
                linear_max: c[2] as usize,
                retries: c[3],
                ..Default::default()
            },
            initial: Conserved {
                materials,
                energies: Energies {
                    kinetic: s[8],
                    strain: s[9],
                    potential: s[10],
                },
                momentum_scale: s[7],
            },
            exchange,
        })
    }
}

/// A model's state and the loop's, held in memory (the last good state) or
/// on its way to a checkpoint folder; `reuse` (an earlier capture) lends
/// its buffers, so that the watchdog's regular capture does not allocate.
fn capture<M: Model>(
    model: &M,
    hash: &str,
    ls: &LoopState,
    out: &Outputs,
    reuse: Option<Checkpoint>,
) -> Result<Checkpoint> {
    let mut ck = match reuse {
        Some(mut ck) => {
            ck.recycle(&model.kind(), hash, model.steps(), model.time());
            ck
        }
        None => Checkpoint::new(&model.kind(), hash, model.steps(), model.time()),
    };
    model.save(&mut ck);
    ls.save(&mut ck);
    ck.set_meta(
        "history_rows",
        (out.history.len() / out.history_width()).into(),
    );
    ck.set_meta("snapshots", out.snapshots().into());
    ck.seal()?;
    Ok(ck)
}

/// The folder, inside the output folder, of a last good state kept on disk
/// (`time.last_good`); removed when the run ends.
pub const LAST_GOOD_DIR: &str = ".last_good";

/// An empty last good state, streamed to `dir/.last_good` where
/// `time.last_good` (and for `auto` the size of the model's state) asks
/// for it; `None`: captured in memory.
fn last_good_store<M: Model>(
    model: &M,
    scene: &Scene,
    dir: &Path,
    hash: &str,
) -> Result<Option<Checkpoint>> {
    use crate::scene::{LastGood, LAST_GOOD_MEMORY_LIMIT};
    let on_disk = match scene.time.last_good {
        LastGood::Memory => false,
        LastGood::Disk => true,
        LastGood::Auto => {
            let mut size = Checkpoint::measuring();
            model.save(&mut size);
            size.measured_bytes() > LAST_GOOD_MEMORY_LIMIT
        }
    };
    Ok(match on_disk {
        true => Some(Checkpoint::streaming(
            &dir.join(LAST_GOOD_DIR),
            &model.kind(),
            hash,
            model.steps(),
            model.time(),
        )?),
        false => None,
    })
}

/// An empty checkpoint of the model's current state streamed into a
/// temporary folder beside `DIR/checkpoints/step_NNNNNNNNNN`, which
/// [`write_checkpoint`] renames into place: a checkpoint costs no copy of
/// the state in memory.
fn checkpoint_store<M: Model>(model: &M, hash: &str, dir: &Path) -> Result<Checkpoint> {
    let tmp = dir.join("checkpoints").join(format!(
        ".step_{:010}.tmp-{}",
        model.steps(),
        std::process::id()
    ));
    if tmp.exists() {
        std::fs::remove_dir_all(&tmp).map_err(|e| Error::io(&tmp, e))?;
    }
    Ok(Checkpoint::streaming_folder(
        &tmp,
        &model.kind(),
        hash,
        model.steps(),
        model.time(),
    )?)
}

/// Writes a captured state as `DIR/checkpoints/step_NNNNNNNNNN`, with the
/// history and snapshot times as they were at its capture; returns the
/// folder.
fn write_checkpoint(mut ck: Checkpoint, out: &Outputs, dir: &Path) -> Result<PathBuf> {
    let rows = ck.meta_u64("history_rows")? as usize;
    let snaps = ck.meta_u64("snapshots")? as usize;
    let w = out.history_width();
    ck.put_f64(
        "loop.history",
        vec![rows, w],
        out.history[..rows * w].to_vec(),
    );
    ck.put_f64(
        "loop.snapshot_times",
        vec![snaps],
        out.times[..snaps].to_vec(),
    );
    let root = dir.join("checkpoints");
    std::fs::create_dir_all(&root).map_err(|e| Error::io(&root, e))?;
    let path = root.join(format!("step_{:010}", ck.step()));
    if path.exists() {
        // The same step of the same scene (a restarted run passing a step
        // its predecessor already saved).
        std::fs::remove_dir_all(&path).map_err(|e| Error::io(&path, e))?;
    }
    ck.write(&path)?;
    Ok(path)
}

/// Restores a model and the loop from checkpoint folder `dir`.
fn restore<M: Model>(
    model: &mut M,
    dir: &Path,
    hash: &str,
    out: &mut Outputs,
) -> Result<LoopState> {
    let mut ck = Checkpoint::read(dir, Some(hash))?;
    if ck.model() != model.kind() {
        return Err(CheckpointError::Malformed {
            what: format!("checkpoint {}", dir.display()),
            reason: format!(
                "it holds a `{}` model, this scene runs `{}`",
                ck.model(),
                model.kind()
            ),
        }
        .into());
    }
    model.load(&mut ck)?;
    if model.time().to_bits() != ck.time().to_bits() || model.steps() != ck.step() {
        return Err(CheckpointError::Malformed {
            what: format!("checkpoint {}", dir.display()),
            reason: format!(
                "the manifest says step {} at t = {:e}, the arrays step {} at t = {:e}",
                ck.step(),
                ck.time(),
                model.steps(),
                model.time()
            ),
        }
        .into());
    }
    let names: Vec<String> = model
        .conserved()
        .materials
        .into_iter()
        .map(|m| m.name)
        .collect();
    let ls = LoopState::load(&mut ck, &names)?;
    let w = out.history_width();
    let rows = ck.shape("loop.history").map_or(0, |s| s[0]);
    let history = ck.take_f64("loop.history", Some(&[rows, w]))?;
    let k = ck.shape("loop.snapshot_times").map_or(0, |s| s[0]);
    let times = ck.take_f64("loop.snapshot_times", Some(&[k]))?;
    out.restore(times, history, &model.field_sets())?;
    Ok(ls)
}

/// Removes the oldest interval checkpoints beyond `keep` (0: keep all).
fn prune(written: &mut Vec<PathBuf>, keep: usize) -> Result<()> {
    while keep > 0 && written.len() > keep {
        let old = written.remove(0);
        std::fs::remove_dir_all(&old).map_err(|e| Error::io(&old, e))?;
    }
    Ok(())
}

/// One step, repeated with half the failed Δt (up to [`MAX_RETRIES`]
/// times) where the error says a smaller step may help; returns the step's
/// statistics and the retries used.
fn step_with_retries<M: Model>(
    model: &mut M,
    mut req: DtRequest,
) -> Result<(crate::driver::model::StepStats, u32)> {
    let mut tries = 0;
    loop {
        match model.step(req) {
            Ok(st) => return Ok((st, tries)),
            Err(e) => match model.retry_dt(&e) {
                Some(dt) if tries < MAX_RETRIES => {
                    req.value = 0.5 * dt;
                    tries += 1;
                }
                _ => return Err(e),
            },
        }
    }
}

/// A progress bar over simulation time (0–1000 ‰), hidden unless `show`.
fn progress_bar(show: bool) -> indicatif::ProgressBar {
    if !show {
        return indicatif::ProgressBar::hidden();
    }
    let b = indicatif::ProgressBar::new(1000);
    b.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {percent:>3}% t = {msg} [{elapsed_precise} < {eta_precise}]",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    b
}

/// Runs `model` (built from `scene`) to the scene's end, writing outputs
/// into `opts.out_dir`; `threads` is reported in the summary.
///
/// # Errors
/// A step failure (after retries), a watchdog finding or an interrupt stop
/// the run with [`Error::Stopped`] naming the cause and the checkpoint of
/// the last good state; everything already written stays whole. A bad
/// restart checkpoint is [`Error::Checkpoint`]; an output failure
/// [`Error::Io`].
pub fn run_model<M: Model>(
    model: &mut M,
    scene: &Scene,
    opts: &RunOptions,
    threads: usize,
) -> Result<Summary> {
    preflight(model, scene)?;
    let mut run = Run::begin(model, scene, opts)?;
    let bar = progress_bar(opts.progress);
    let start = Instant::now();
    let steps0 = model.steps();
    let mut step_s = 0.0;
    let mut failure: Option<Error> = None;
    while failure.is_none() && !run.cad.finished(model.time(), model.steps()) {
        let s = Instant::now();
        if let Err(e) = run.step(model, scene) {
            failure = Some(label_error(model.annotate(e), scene));
            break;
        }
        step_s += s.elapsed().as_secs_f64();
        failure = run.after_step(model, opts)?.map(|e| label_error(e, scene));
        if model.steps().is_multiple_of(16) {
            let t = model.time();
            bar.set_position((1000.0 * t / run.cad.end) as u64);
            bar.set_message(format!("{t:.4e}"));
        }
    }
    bar.finish_and_clear();
    let stopped = run.finish(model, failure)?;
    let stopped = stopped.map(|e| label_error(e, scene));
    let summary = summarise(
        model,
        scene,
        &run.ls,
        threads,
        start.elapsed().as_secs_f64(),
        (step_s, model.steps().saturating_sub(steps0)),
        run.out.output_s,
        &run.written,
        opts,
        stopped.as_ref(),
        &run.warnings,
    );
    write_summary(&run.dir, &summary)?;
    match stopped {
        Some(e) => Err(e),
        None => Ok(summary),
    }
}

/// What the loop carries from step to step besides the model: the cadence,
/// the loop state, the writers, the last good state and the checkpoints
/// written.
struct Run {
    cad: Cadence,
    hash: String,
    dir: PathBuf,
    out: Outputs,
    ls: LoopState,
    last_good: Option<Checkpoint>,
    /// The folder of a last good state kept on disk, removed at the end.
    last_good_dir: Option<PathBuf>,
    written: Vec<PathBuf>,
    /// Warnings given (the Δt drop, once).
    warnings: Vec<String>,
}

impl Drop for Run {
    /// Removes a last good state kept on disk: it is a working copy, not an
    /// output (a failure has written it as a checkpoint by now).
    fn drop(&mut self) {
        if let Some(dir) = &self.last_good_dir {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

impl Run {
    /// Opens the outputs and starts from the initial state (writing its
    /// snapshot and history row) or from the restart checkpoint.
    fn begin<M: Model>(model: &mut M, scene: &Scene, opts: &RunOptions) -> Result<Self> {
        let dir = opts.out_dir.clone();
        let cad = Cadence::of(scene);
        let hash = scene_hash(scene);
        let mut out = Outputs::new(&dir, &scene.output, scene.dim(), &model.history_columns())?;
        let ls = match &opts.restart {
            Some(ck_dir) => restore(model, ck_dir, &hash, &mut out)?,
            None => {
                let ls = LoopState::fresh(&cad, model.conserved());
                out.snapshot(model.time(), &model.field_sets())?;
                out.history_row(model.time(), |r| model.history_row(r));
                out.flush_history()?;
                ls
            }
        };
        let last_good = match cad.watchdog > 0 {
            true => {
                let store = last_good_store(model, scene, &dir, &hash)?;
                let on_disk = store
                    .as_ref()
                    .and_then(|c| c.stream_dir().map(Path::to_path_buf));
                match capture(model, &hash, &ls, &out, store) {
                    Ok(ck) => Some(ck),
                    Err(e) => {
                        if let Some(d) = on_disk {
                            let _ = std::fs::remove_dir_all(d);
                        }
                        return Err(e);
                    }
                }
            }
            false => None,
        };
        Ok(Self {
            cad,
            hash,
            dir,
            out,
            ls,
            last_good_dir: last_good
                .as_ref()
                .and_then(|ck| ck.stream_dir().map(Path::to_path_buf)),
            last_good,
            written: Vec::new(),
            warnings: Vec::new(),
        })
    }

    /// One step of the model (with retries) to the end time or by the fixed
    /// Δt, its statistics added to the loop's.
    fn step<M: Model>(&mut self, model: &mut M, scene: &Scene) -> Result<()> {
        // Steps end on the end time and on every snapshot time (a snapshot
        // asked for at t = 0.1 is taken at 0.1, not at the first step past
        // it).
        let t = model.time();
        let left = self.cad.end - t;
        let to_out = self.ls.next_out - t;
        let cap = if to_out > (1.0 - NEAR) * self.cad.end && to_out < left {
            to_out
        } else {
            left
        };
        let (req, nominal) = match self.cad.fixed_dt {
            Some(dt) => (
                DtRequest {
                    value: dt.min(cap),
                    exact: true,
                },
                dt,
            ),
            None => (
                DtRequest {
                    value: cap,
                    exact: false,
                },
                f64::INFINITY,
            ),
        };
        let (st, tries) = step_with_retries(model, req)?;
        // A step the loop shortened to land on an output or the end time is
        // no sign of a collapsing Δt: it is left out of the progress guard
        // and of the Δt statistics.
        let shortened = req.value < nominal && st.dt >= req.value * NEAR;
        // The progress guard: Δt against the largest of the run so far
        // (the last step to the end time is as short as it needs to be).
        let reference = if self.ls.dt_max > 0.0 {
            self.ls.dt_max
        } else {
            st.dt
        };
        if !self.cad.finished(model.time(), model.steps()) && !shortened {
            let drop = st.dt / reference;
            if drop.is_nan() || drop < self.cad.min_dt_fraction {
                let by = model
                    .dt_limiter()
                    .map_or(String::new(), |l| format!("; the stable Δt is set by {l}"));
                return Err(Error::Progress {
                    step: model.steps(),
                    time: model.time(),
                    what: format!(
                        "Δt = {:.3e} s fell below time.min_dt_fraction = {:e} of the run's largest Δt {reference:.3e} s{by}",
                        st.dt, self.cad.min_dt_fraction
                    ),
                });
            }
            if drop < 0.01 && self.warnings.is_empty() {
                let by = model
                    .dt_limiter()
                    .map_or(String::new(), |l| format!(", set by {l}"));
                let warning = format!(
                    "Δt dropped 100-fold to {:.3e} s (largest {reference:.3e} s) at \
                     step {}, t = {:.6e}{}",
                    st.dt,
                    model.steps(),
                    model.time(),
                    scene.label_materials(&by)
                );
                eprintln!("warning: {warning}");
                self.warnings.push(warning);
            }
        }
        let ls = &mut self.ls;
        if let Some(b) = st.boundary {
            ls.exchange.get_or_insert_with(Default::default).add(&b);
        }
        if !shortened || ls.dt_max == 0.0 {
            ls.dt_min = ls.dt_min.min(st.dt);
            ls.dt_max = ls.dt_max.max(st.dt);
        }
        ls.iters.add(st.nonlinear_iterations, st.linear_iterations);
        ls.iters.retries += st.retries as u64 + tries as u64;
        ls.retries += tries as u64;
        Ok(())
    }

    /// After a step: the watchdog scan (every `time.watchdog_interval`
    /// steps, and before every snapshot and checkpoint so that none shows
    /// a state it would reject), history row, snapshot, keeping the state
    /// of a regular or checkpoint scan as the last good one, an interval
    /// checkpoint and the interrupt flag. Returns the reason to stop, if
    /// any.
    fn after_step<M: Model>(&mut self, model: &M, opts: &RunOptions) -> Result<Option<Error>> {
        let (t, steps) = (model.time(), model.steps());
        let (cad, ls) = (&self.cad, &mut self.ls);
        let done = cad.finished(t, steps);
        let snapshot_due = t >= ls.next_out * NEAR && !done;
        let checkpoint_due = t >= ls.next_ckpt * NEAR && !done;
        let keep = cad.watchdog > 0 && (steps % cad.watchdog == 0 || checkpoint_due);
        if keep || (cad.watchdog > 0 && snapshot_due) {
            if let Some(v) = model.watchdog() {
                return Ok(Some(Error::Watchdog {
                    step: steps,
                    time: t,
                    what: v.to_string(),
                }));
            }
        }
        if t >= ls.next_hist * NEAR {
            self.out.history_row(t, |r| model.history_row(r));
            ls.next_hist += cad.history.unwrap_or(0.0);
        }
        if snapshot_due {
            self.out.snapshot(t, &model.field_sets())?;
            self.out.flush_history()?;
            ls.next_out += cad.interval.unwrap_or(f64::INFINITY);
        }
        if checkpoint_due {
            ls.next_ckpt += cad.checkpoint.unwrap_or(f64::INFINITY);
        }
        if keep {
            let reuse = self.last_good.take();
            self.last_good = Some(capture(model, &self.hash, &self.ls, &self.out, reuse)?);
        }
        if checkpoint_due {
            let store = checkpoint_store(model, &self.hash, &self.dir)?;
            let ck = capture(model, &self.hash, &self.ls, &self.out, Some(store))?;
            self.written
                .push(write_checkpoint(ck, &self.out, &self.dir)?);
            prune(&mut self.written, self.cad.keep)?;
        }
        let interrupted = opts
            .interrupt
            .as_ref()
            .is_some_and(|f| f.load(Ordering::SeqCst));
        Ok(interrupted.then_some(Error::Interrupted {
            step: steps,
            time: t,
        }))
    }

    /// Ends the run: the last snapshot and history row, and after a stop
    /// the checkpoint — of the current state after an interrupt or the
    /// progress guard (whole steps; if it passes the watchdog), of the last
    /// good one after a failure. After a
    /// failure the model goes back to the last good state (the failed step
    /// may have left it half-updated) and that state is the last snapshot,
    /// unless it already is one; without a last good state (watchdog off)
    /// no snapshot is added. No time appears twice in the snapshot series.
    /// Returns the stop as [`Error::Stopped`] when a checkpoint was written.
    fn finish<M: Model>(&mut self, model: &mut M, failure: Option<Error>) -> Result<Option<Error>> {
        let saved = match failure {
            None => None,
            // An interrupt, or the progress guard, stops after a whole
            // step: that state is the one to keep if it passes the watchdog.
            Some(e @ (Error::Interrupted { .. } | Error::Progress { .. })) => {
                match model.watchdog() {
                    None => {
                        let store = checkpoint_store(model, &self.hash, &self.dir)?;
                        let ck = capture(model, &self.hash, &self.ls, &self.out, Some(store))?;
                        Some((e, Some(ck)))
                    }
                    Some(v) => Some((
                        Error::Watchdog {
                            step: model.steps(),
                            time: model.time(),
                            what: v.to_string(),
                        },
                        self.last_good.take(),
                    )),
                }
            }
            Some(e) => Some((e, self.last_good.take())),
        };
        let interrupted = matches!(saved, Some((Error::Interrupted { .. }, _)));
        let failed = saved.is_some() && !interrupted;
        // After a failure: back to the last good state, if there is one.
        let good = match &saved {
            Some((_, Some(ck))) if failed => ck
                .to_memory()
                .and_then(|mut ck| model.load(&mut ck))
                .is_ok(),
            _ => !failed,
        };
        if !interrupted && good {
            let t = model.time();
            if self.out.times.last().is_none_or(|&last| t > last) {
                self.out.snapshot(t, &model.field_sets())?;
            }
            if self.out.last_history_time().is_none_or(|last| t > last) {
                self.out.history_row(t, |r| model.history_row(r));
            }
        }
        self.out.flush_history()?;
        let Some((e, ck)) = saved else {
            return Ok(None);
        };
        let Some(ck) = ck else {
            return Ok(Some(e));
        };
        let (step, time) = (ck.step(), ck.time());
        let path = write_checkpoint(ck.into_writable()?, &self.out, &self.dir)?;
        self.written.push(path.clone());
        Ok(Some(Error::Stopped {
            cause: Box::new(e),
            checkpoint: path,
            step,
            time,
        }))
    }
}

/// Names every material of a run's error by its scene name and its
/// `materials[i]` index (models name them by their scene name alone; ICE
/// errors carry the name in backticks).
pub(crate) fn label_error(e: Error, scene: &Scene) -> Error {
    use crate::ice::IceError;
    match e {
        Error::Scene(mut se) => {
            se.message = scene.label_materials(&se.message);
            Error::Scene(se)
        }
        Error::Numerical { site, what } => Error::Numerical {
            site,
            what: scene.label_materials(&what),
        },
        Error::Watchdog { step, time, what } => Error::Watchdog {
            step,
            time,
            what: scene.label_materials(&what),
        },
        Error::Progress { step, time, what } => Error::Progress {
            step,
            time,
            what: scene.label_materials(&what),
        },
        Error::Stopped {
            cause,
            checkpoint,
            step,
            time,
        } => Error::Stopped {
            cause: Box::new(label_error(*cause, scene)),
            checkpoint,
            step,
            time,
        },
        Error::Fluid(mut ice) => {
            match &mut ice {
                IceError::TimestepTooLarge { site, .. }
                | IceError::NonPhysical { site, .. }
                | IceError::Equilibration { site, .. }
                | IceError::PressureSolve { site, .. }
                | IceError::Eos { site, .. } => {
                    if let Some(name) = site.material_name.take() {
                        let labelled = scene.label_materials(&format!("material {name}"));
                        site.material_name = Some(labelled["material ".len()..].into());
                    }
                }
                IceError::InvalidInput { reason, .. } => {
                    *reason = scene.label_materials(reason);
                }
            }
            Error::Fluid(ice)
        }
        e => e,
    }
}

/// The summary of a finished or stopped run.
#[allow(clippy::too_many_arguments)]
fn summarise<M: Model>(
    model: &M,
    scene: &Scene,
    ls: &LoopState,
    threads: usize,
    wall_s: f64,
    (step_s, run_steps): (f64, u64),
    output_s: f64,
    written: &[PathBuf],
    opts: &RunOptions,
    error: Option<&Error>,
    warnings: &[String],
) -> Summary {
    let end = model.conserved();
    let desc = model.describe();
    let counts = model.counts();
    let steps = model.steps();
    let per_step = |n: usize| {
        if step_s > 0.0 {
            n as f64 * run_steps as f64 / step_s
        } else {
            0.0
        }
    };
    // The drifts are what is left of the change of each total after what
    // crossed the boundary (where the model accounts for it).
    let b = ls.exchange.unwrap_or_default();
    let (m0, m1) = (ls.initial.mass(), end.mass() - b.mass);
    let (p0, p1) = (ls.initial.momentum(), end.momentum());
    let dp = (0..3)
        .filter(|&d| !desc.axial_momentum_only || d == 1)
        .map(|d| (p1[d] - b.momentum[d] - b.body_momentum[d] - p0[d]).powi(2))
        .sum::<f64>()
        .sqrt();
    let (e0, e1) = (ls.initial.energies, end.energies);
    // The largest energy the account holds at the start or the end (a
    // total, or its kinetic or stored part where a potential cancels the
    // total): a run that takes in much more energy than it starts with (a
    // heat source, a piston) is measured against what it holds, not its
    // small start.
    let e_scale = [e0, e1]
        .iter()
        .flat_map(|e| [e.total(), e.kinetic, e.strain])
        .fold(f64::MIN_POSITIVE, |s, x| s.max(x.abs()));
    let p_scale = ls.initial.momentum_scale;
    let peak = super::memory::peak_resident_bytes();
    let iterations = desc.iterative.then(|| {
        let mut it = ls.iters.clone();
        if let Some([a, f, s, p]) = desc.implicit_split {
            (it.assembly_s, it.factor_s, it.solve_s, it.particles_s) = (a, f, s, p);
        }
        it.coupled = desc.coupled_iterations.clone();
        // Sums over all steps of a restarted chain: means over all steps.
        it.finish(steps)
    });
    Summary {
        dim: scene.dim(),
        mode: scene.time.mode.name().to_string(),
        model: model.kind(),
        shape: desc.shape,
        update: desc.update,
        steps,
        final_time: model.time(),
        wall_s,
        output_s,
        n_particles: counts.particles,
        n_cells: counts.cells,
        particle_steps_per_s: per_step(counts.particles),
        cell_steps_per_s: if counts.fluid_materials > 0 {
            per_step(counts.cells)
        } else {
            0.0
        },
        n_fluid_materials: counts.fluid_materials,
        n_elements: counts.elements,
        element_steps_per_s: per_step(counts.elements),
        peak_memory_bytes: peak,
        peak_memory_per_particle: peak
            .filter(|_| counts.particles > 0)
            .map(|b| b as f64 / counts.particles as f64),
        retries: ls.iters.retries,
        threads,
        dt_min: if ls.dt_min.is_finite() {
            ls.dt_min
        } else {
            0.0
        },
        dt_max: ls.dt_max,
        mass_drift: if m0 > 0.0 { (m1 - m0) / m0 } else { m1 - m0 },
        momentum_drift: if !desc.momentum_conserved {
            f64::NAN
        } else if p_scale > 0.0 {
            dp / p_scale
        } else {
            dp
        },
        energy_drift: (e1.total() - b.energy_in() - e0.total()) / e_scale,
        boundary_exchange: ls.exchange,
        initial_energy: e0,
        final_energy: e1,
        initial_materials: ls.initial.materials.clone(),
        final_materials: end.materials,
        phase_times: desc.phase_times,
        iterations,
        watchdog_interval: scene.time.watchdog_interval,
        checkpoints: written.iter().map(|p| p.display().to_string()).collect(),
        restarted_from: opts.restart.as_deref().map(|p| p.display().to_string()),
        error: error.map(|e| e.to_string()),
        warnings: warnings.to_vec(),
        provenance: super::summary::Provenance::of(scene, &opts.command_line, threads),
    }
}
