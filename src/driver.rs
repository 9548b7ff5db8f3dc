//! Runs a scene end to end: build, step, write snapshots, history and the run
//! summary. The CLI is a thin layer over [`run_scene`].

use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::SVector;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::mpm::Particles;
use crate::output::atomic_write;
use crate::output::csv::{write_columns, CsvAppender};
use crate::output::vtk::{write_vti, write_vtu_points, Field, PvdSeries};
use crate::scene::{build_solid_run, Format, Scene};
use crate::stepper::{Energies, SolidRun};

/// How to run a scene.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Output folder (created if missing).
    pub out_dir: PathBuf,
    /// Worker threads (0: rayon's default, all cores).
    pub threads: usize,
    /// Show a progress bar on stderr.
    pub progress: bool,
}

/// The end-of-run summary written to `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Spatial dimension.
    pub dim: usize,
    /// Integration mode.
    pub mode: String,
    /// Shape function.
    pub shape: String,
    /// MPM update scheme.
    pub update: String,
    /// Steps taken.
    pub steps: u64,
    /// Simulation time reached.
    pub final_time: f64,
    /// Wall-clock seconds of the time loop (output included).
    pub wall_s: f64,
    /// Wall-clock seconds spent writing output.
    pub output_s: f64,
    /// Number of particles.
    pub n_particles: usize,
    /// Number of grid cells.
    pub n_cells: usize,
    /// Particle updates per second of stepping (output excluded; 0 without
    /// particles).
    pub particle_steps_per_s: f64,
    /// Cell updates per second of stepping, all fluid materials of a cell
    /// counted once (0 without fluids).
    pub cell_steps_per_s: f64,
    /// Fluid materials.
    pub n_fluid_materials: usize,
    /// Fluid steps repeated with a smaller timestep.
    pub retries: u64,
    /// Worker threads.
    pub threads: usize,
    /// Smallest and largest timestep.
    pub dt_min: f64,
    /// Largest timestep.
    pub dt_max: f64,
    /// (M_end − M_0)/M_0.
    pub mass_drift: f64,
    /// |P_end − P_0| / Σ m|v| at the start (or M·|v|max if that is zero).
    pub momentum_drift: f64,
    /// (E_end − E_0)/E_0 of kinetic + strain + body-force potential energy.
    pub energy_drift: f64,
    /// Energies at the start (kinetic, strain, potential for solids; for
    /// fluids `strain` holds the internal energy).
    pub initial_energy: Energies,
    /// Energies at the end.
    pub final_energy: Energies,
    /// Wall time per phase of the explicit step (binning, P2G, grid, G2P +
    /// stress).
    pub phase_times: crate::mpm::PhaseTimes,
    /// Iteration counts and time split of implicit modes (absent for
    /// explicit runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterations: Option<IterationStats>,
    /// Error that stopped the run early, if any.
    pub error: Option<String>,
}

/// Iterations per step of an implicit mode: Newton iterations (implicit MPM)
/// or outer pressure iterations (semi-implicit ICE), and the linear
/// iterations behind them; plus the time split where measured.
#[derive(Debug, Clone, Default, Serialize)]
pub struct IterationStats {
    /// Mean nonlinear (Newton / outer) iterations per step.
    pub nonlinear_mean: f64,
    /// Largest nonlinear iterations in a step.
    pub nonlinear_max: usize,
    /// Mean Krylov iterations per step (0 with a direct solver).
    pub linear_mean: f64,
    /// Largest Krylov iterations in a step.
    pub linear_max: usize,
    /// Steps retried with a smaller timestep.
    pub retries: u64,
    /// Seconds assembling (implicit MPM).
    pub assembly_s: f64,
    /// Seconds factorising (implicit MPM).
    pub factor_s: f64,
    /// Seconds in linear solves (implicit MPM).
    pub solve_s: f64,
    /// Seconds in particle updates (implicit MPM).
    pub particles_s: f64,
}

impl IterationStats {
    /// Accumulates one step.
    pub fn add(&mut self, nonlinear: usize, linear: usize) {
        self.nonlinear_mean += nonlinear as f64;
        self.linear_mean += linear as f64;
        self.nonlinear_max = self.nonlinear_max.max(nonlinear);
        self.linear_max = self.linear_max.max(linear);
    }

    /// Turns the sums into means over `steps`.
    pub fn finish(mut self, steps: u64) -> Self {
        let n = steps.max(1) as f64;
        self.nonlinear_mean /= n;
        self.linear_mean /= n;
        self
    }
}

/// Runs a validated scene with outputs in `opts.out_dir`.
pub fn run_scene(scene: &Scene, opts: &RunOptions) -> Result<Summary> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads)
        .build()
        .map_err(|e| Error::io(&opts.out_dir, std::io::Error::other(e.to_string())))?;
    let threads = pool.current_num_threads();
    let fluid = scene
        .materials
        .iter()
        .any(|m| m.kind == crate::scene::MaterialKind::Fluid);
    let implicit = scene.time.mode == crate::scene::Mode::Implicit;
    let solid = scene
        .materials
        .iter()
        .any(|m| m.kind == crate::scene::MaterialKind::Solid);
    if solid && fluid {
        return pool.install(|| match scene.grid.dim {
            1 => crate::driver_coupled::run_coupled_dim::<1>(scene, opts, threads),
            2 => crate::driver_coupled::run_coupled_dim::<2>(scene, opts, threads),
            _ => crate::driver_coupled::run_coupled_dim::<3>(scene, opts, threads),
        });
    }
    pool.install(|| match (scene.grid.dim, fluid) {
        (1, false) if implicit => run_implicit_dim::<1>(scene, opts, threads),
        (2, false) if implicit => run_implicit_dim::<2>(scene, opts, threads),
        (_, false) if implicit => run_implicit_dim::<3>(scene, opts, threads),
        (1, false) => run_dim::<1>(scene, opts, threads),
        (2, false) => run_dim::<2>(scene, opts, threads),
        (_, false) => run_dim::<3>(scene, opts, threads),
        (1, true) => crate::driver_fluid::run_fluid_dim::<1>(scene, opts, threads),
        (2, true) => crate::driver_fluid::run_fluid_dim::<2>(scene, opts, threads),
        (_, true) => crate::driver_fluid::run_fluid_dim::<3>(scene, opts, threads),
    })
}

/// Unit of a quantity per unit of the dimensions a run does not resolve
/// (2D plane strain is per metre of depth, 1D per square metre of section).
pub(crate) fn per_depth(dim: usize) -> &'static str {
    match dim {
        1 => "/m^2",
        2 => "/m",
        _ => "",
    }
}

struct Writer {
    dir: PathBuf,
    formats: Vec<Format>,
    particles_pvd: PvdSeries,
    grid_pvd: PvdSeries,
    history: CsvAppender,
    snapshots: usize,
    output_s: f64,
}

impl Writer {
    fn new(dir: &Path, formats: &[Format], dim: usize) -> Result<Self> {
        let history = open_history(
            dir,
            dim,
            &[
                ("kinetic", "J"),
                ("strain", "J"),
                ("potential", "J"),
                ("total", "J"),
            ],
        )?;
        Ok(Self {
            dir: dir.to_path_buf(),
            formats: formats.to_vec(),
            particles_pvd: PvdSeries::new(dir.join("particles.pvd")),
            grid_pvd: PvdSeries::new(dir.join("grid.pvd")),
            history,
            snapshots: 0,
            output_s: 0.0,
        })
    }

    fn history_row(&mut self, t: f64, e: &Energies) -> Result<()> {
        let start = Instant::now();
        self.history
            .row(&[t, e.kinetic, e.strain, e.potential, e.total()])
            .map_err(|err| Error::io(self.history.path().to_path_buf(), err))?;
        self.output_s += start.elapsed().as_secs_f64();
        Ok(())
    }

    fn snapshot<const D: usize>(&mut self, run: &SolidRun<D>) -> Result<()> {
        self.particle_snapshot(run.t, &run.particles, Some(run))
    }

    /// Particles (and, for explicit runs, the grid) at time `t`.
    fn particle_snapshot<const D: usize>(
        &mut self,
        t: f64,
        particles: &Particles<D>,
        grid: Option<&SolidRun<D>>,
    ) -> Result<()> {
        let start = Instant::now();
        let k = self.snapshots;
        if self.formats.contains(&Format::Vtk) {
            let name = format!("particles_{k:04}.vtu");
            let path = self.dir.join(&name);
            write_particles_vtu(&path, particles).map_err(|e| Error::io(&path, e))?;
            self.particles_pvd
                .push(t, &name)
                .map_err(|e| Error::io(self.particles_pvd.path().to_path_buf(), e))?;
            if let Some(run) = grid {
                let gname = format!("grid_{k:04}.vti");
                let gpath = self.dir.join(&gname);
                write_grid_vti(&gpath, run).map_err(|e| Error::io(&gpath, e))?;
                self.grid_pvd
                    .push(t, &gname)
                    .map_err(|e| Error::io(self.grid_pvd.path().to_path_buf(), e))?;
            }
        }
        if self.formats.contains(&Format::Csv) {
            let path = self.dir.join(format!("particles_{k:04}.csv"));
            write_particles_csv(&path, particles).map_err(|e| Error::io(&path, e))?;
        }
        self.snapshots += 1;
        self.output_s += start.elapsed().as_secs_f64();
        Ok(())
    }
}

pub(crate) fn pad3<const D: usize>(v: &SVector<f64, D>) -> [f64; 3] {
    std::array::from_fn(|i| if i < D { v[i] } else { 0.0 })
}

pub(crate) fn write_particles_vtu<const D: usize>(
    path: &Path,
    p: &Particles<D>,
) -> std::io::Result<()> {
    let pts: Vec<[f64; 3]> = p.x.iter().map(pad3).collect();
    let vel: Vec<[f64; 3]> = p.v.iter().map(pad3).collect();
    let disp: Vec<[f64; 3]> =
        p.x.iter()
            .zip(&p.x0)
            .map(|(x, x0)| pad3(&(x - x0)))
            .collect();
    let stress: Vec<[f64; 9]> = p
        .stress
        .iter()
        .map(|s| std::array::from_fn(|k| s[(k / 3, k % 3)]))
        .collect();
    let f: Vec<[f64; 9]> =
        p.f.iter()
            .map(|s| std::array::from_fn(|k| s[(k / 3, k % 3)]))
            .collect();
    let mat: Vec<f64> = p.material.iter().map(|&m| m as f64).collect();
    let j: Vec<f64> = p.f.iter().map(|f| f.determinant()).collect();
    write_vtu_points(
        path,
        &pts,
        &[
            Field::vector("velocity", &vel),
            Field::vector("displacement", &disp),
            Field::tensor("stress", &stress),
            Field::tensor("deformation_gradient", &f),
            Field::scalar("mass", &p.mass),
            Field::scalar("volume", &p.vol),
            Field::scalar("J", &j),
            Field::scalar("material", &mat),
            Field::scalar("temperature", &p.temperature),
        ],
    )
}

pub(crate) fn write_particles_csv<const D: usize>(
    path: &Path,
    p: &Particles<D>,
) -> std::io::Result<()> {
    let axes = ["x", "y", "z"];
    let u = per_depth(D);
    let mut header: Vec<String> = Vec::new();
    let mut cols: Vec<Vec<f64>> = Vec::new();
    for d in 0..D {
        header.push(format!("{} [m]", axes[d]));
        cols.push(p.x.iter().map(|x| x[d]).collect());
    }
    for d in 0..D {
        header.push(format!("v{} [m/s]", axes[d]));
        cols.push(p.v.iter().map(|v| v[d]).collect());
    }
    for d in 0..D {
        header.push(format!("u{} [m]", axes[d]));
        cols.push(p.x.iter().zip(&p.x0).map(|(x, x0)| x[d] - x0[d]).collect());
    }
    let comps: &[(usize, usize)] = match D {
        1 => &[(0, 0), (1, 1), (2, 2)],
        2 => &[(0, 0), (1, 1), (2, 2), (0, 1)],
        _ => &[(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)],
    };
    for &(a, b) in comps {
        header.push(format!("s{}{} [Pa]", axes[a], axes[b]));
        cols.push(p.stress.iter().map(|s| s[(a, b)]).collect());
    }
    header.push(format!("mass [kg{u}]"));
    cols.push(p.mass.clone());
    header.push(format!("volume [m^3{u}]"));
    cols.push(p.vol.clone());
    header.push("J [-]".into());
    cols.push(p.f.iter().map(|f| f.determinant()).collect());
    header.push("material [-]".into());
    cols.push(p.material.iter().map(|&m| m as f64).collect());
    header.push("temperature [K]".into());
    cols.push(p.temperature.clone());
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    let c: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
    write_columns(path, &h, &c)
}

fn write_grid_vti<const D: usize>(path: &Path, run: &SolidRun<D>) -> std::io::Result<()> {
    let g = &run.grid;
    let gs = run.grid_state();
    let cells: [usize; 3] = std::array::from_fn(|d| if d < D { g.cells[d] } else { 0 });
    let n: [usize; 3] = std::array::from_fn(|d| cells[d] + 1);
    let mut mass = Vec::with_capacity(n[0] * n[1] * n[2]);
    let mut vel = Vec::with_capacity(mass.capacity());
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let c = [i as isize, j as isize, k as isize];
                let idx = g.node_index(std::array::from_fn(|d| c[d]));
                mass.push(gs.mass[idx]);
                vel.push(pad3(&gs.velocity_new[idx]));
            }
        }
    }
    let origin = pad3(&g.lower);
    let spacing: [f64; 3] = std::array::from_fn(|d| if d < D { g.h[d] } else { 1.0 });
    write_vti(
        path,
        origin,
        spacing,
        cells,
        &[
            Field::scalar("mass", &mass),
            Field::vector("velocity", &vel),
        ],
        &[],
    )
}

fn run_dim<const D: usize>(scene: &Scene, opts: &RunOptions, threads: usize) -> Result<Summary> {
    let mut run = build_solid_run::<D>(scene)?;
    let mut writer = Writer::new(&opts.out_dir, &scene.output.formats, D)?;
    let e0 = run.energies();
    let m0 = run.particles.total_mass();
    let p0 = run.particles.momentum();
    let p_scale = run.particles.momentum_scale();
    writer.snapshot(&run)?;
    writer.history_row(0.0, &e0)?;
    let interval = scene.output.interval;
    let hist_iv = scene.output.history_interval.or(interval.map(|i| i / 20.0));
    let mut next_out = interval.unwrap_or(f64::INFINITY);
    let mut next_hist = hist_iv.unwrap_or(0.0);
    let bar = progress_bar(opts.progress);
    let start = Instant::now();
    let mut step_s = 0.0;
    let (mut dt_min, mut dt_max) = (f64::INFINITY, 0.0f64);
    let mut failure = None;
    while !run.finished() {
        let s = Instant::now();
        match run.step() {
            Ok(dt) => {
                dt_min = dt_min.min(dt);
                dt_max = dt_max.max(dt);
            }
            Err(e) => {
                failure = Some(e);
                break;
            }
        }
        step_s += s.elapsed().as_secs_f64();
        if run.t >= next_hist * (1.0 - 1e-12) {
            writer.history_row(run.t, &run.energies())?;
            next_hist += hist_iv.unwrap_or(0.0);
        }
        if run.t >= next_out * (1.0 - 1e-12) && !run.finished() {
            writer.snapshot(&run)?;
            next_out += interval.unwrap_or(f64::INFINITY);
        }
        if run.steps % 16 == 0 {
            bar.set_position((1000.0 * run.t / run.time.end) as u64);
            bar.set_message(format!("{:.4e}", run.t));
        }
    }
    bar.finish_and_clear();
    // The last state is always written, also after a failure (it shows where
    // the run broke down).
    writer.snapshot(&run)?;
    let e1 = run.energies();
    writer.history_row(run.t, &e1)?;
    let wall_s = start.elapsed().as_secs_f64();
    let e_scale = if e0.total().abs() > 0.0 {
        e0.total().abs()
    } else {
        e1.kinetic.max(e1.strain).max(f64::MIN_POSITIVE)
    };
    let dp = (run.particles.momentum() - p0).norm();
    let summary = Summary {
        dim: D,
        mode: scene.time.mode.name().to_string(),
        shape: format!("{:?}", scene.mpm.shape),
        update: format!("{:?}", scene.mpm.update),
        steps: run.steps,
        final_time: run.t,
        wall_s,
        output_s: writer.output_s,
        n_particles: run.particles.len(),
        n_cells: run.grid.num_cells(),
        particle_steps_per_s: if step_s > 0.0 {
            run.particles.len() as f64 * run.steps as f64 / step_s
        } else {
            0.0
        },
        cell_steps_per_s: 0.0,
        n_fluid_materials: 0,
        retries: 0,
        threads,
        dt_min: if run.steps > 0 { dt_min } else { 0.0 },
        dt_max,
        mass_drift: (run.particles.total_mass() - m0) / m0,
        momentum_drift: if p_scale > 0.0 { dp / p_scale } else { dp },
        energy_drift: (e1.total() - e0.total()) / e_scale,
        initial_energy: e0,
        final_energy: e1,
        phase_times: run.phase_times(),
        iterations: None,
        error: failure.as_ref().map(|e| e.to_string()),
    };
    write_summary(&opts.out_dir, &summary)?;
    match failure {
        Some(e) => Err(e),
        None => Ok(summary),
    }
}

/// A progress bar over simulation time (0–1000 ‰), hidden unless `show`.
pub(crate) fn progress_bar(show: bool) -> indicatif::ProgressBar {
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

/// Creates `dir` and its `history.csv` with a time column and one column per
/// `(quantity, unit)`, the units made per depth in 2D and per area in 1D.
pub(crate) fn open_history(
    dir: &Path,
    dim: usize,
    columns: &[(&str, &str)],
) -> Result<CsvAppender> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let u = per_depth(dim);
    let mut header = vec!["time [s]".to_string()];
    header.extend(columns.iter().map(|(q, unit)| format!("{q} [{unit}{u}]")));
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    let path = dir.join("history.csv");
    CsvAppender::create(&path, &header).map_err(|e| Error::io(&path, e))
}

/// Writes `summary.json` atomically.
pub(crate) fn write_summary(dir: &Path, summary: &Summary) -> Result<()> {
    let path = dir.join("summary.json");
    atomic_write(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, summary).map_err(std::io::Error::other)?;
        std::io::Write::write_all(w, b"\n")
    })
    .map_err(|e| Error::io(&path, e))
}

/// Energies of a particle set (no body-force potential: implicit runs ramp
/// their loads, so the total is not conserved anyway).
fn particle_energies<const D: usize>(
    particles: &Particles<D>,
    materials: &[crate::material::SolidMaterial],
) -> Energies {
    Energies {
        kinetic: particles.kinetic_energy(),
        strain: particles.strain_energy(materials),
        potential: 0.0,
    }
}

/// Runs a validated solid scene in implicit mode (Newmark + Newton or
/// quasistatic load steps).
fn run_implicit_dim<const D: usize>(
    scene: &Scene,
    opts: &RunOptions,
    threads: usize,
) -> Result<Summary> {
    let mut run = crate::scene::build_implicit_run::<D>(scene)?;
    let mut writer = Writer::new(&opts.out_dir, &scene.output.formats, D)?;
    let e0 = particle_energies(&run.particles, &run.materials);
    let m0 = run.particles.total_mass();
    let p0 = run.particles.momentum();
    writer.particle_snapshot(0.0, &run.particles, None)?;
    writer.history_row(0.0, &e0)?;
    let interval = scene.output.interval;
    let mut next_out = interval.unwrap_or(f64::INFINITY);
    let start = Instant::now();
    let mut stats = IterationStats::default();
    let (mut dt_min, mut dt_max) = (f64::INFINITY, 0.0f64);
    let mut failure = None;
    let max_steps = scene.time.max_steps.unwrap_or(u64::MAX);
    while !run.finished() && run.steps < max_steps {
        match run.step() {
            Ok(st) => {
                stats.add(st.newton_iterations, st.linear_iterations);
                stats.retries += st.retries as u64;
                stats.assembly_s += st.assembly_s;
                stats.factor_s += st.factor_s;
                stats.solve_s += st.solve_s;
                stats.particles_s += st.particles_s;
                dt_min = dt_min.min(st.dt);
                dt_max = dt_max.max(st.dt);
            }
            Err(e) => {
                failure = Some(e);
                break;
            }
        }
        writer.history_row(run.t, &particle_energies(&run.particles, &run.materials))?;
        if run.t >= next_out * (1.0 - 1e-12) && !run.finished() {
            writer.particle_snapshot(run.t, &run.particles, None)?;
            next_out += interval.unwrap_or(f64::INFINITY);
        }
    }
    writer.particle_snapshot(run.t, &run.particles, None)?;
    let wall_s = start.elapsed().as_secs_f64();
    let e1 = particle_energies(&run.particles, &run.materials);
    let dp = (run.particles.momentum() - p0).norm();
    let summary = Summary {
        dim: D,
        mode: scene.time.mode.name().to_string(),
        shape: format!("{:?}", scene.mpm.shape),
        update: if scene.implicit.dynamic {
            "newmark".into()
        } else {
            "quasistatic".into()
        },
        steps: run.steps,
        final_time: run.t,
        wall_s,
        output_s: writer.output_s,
        n_particles: run.particles.len(),
        n_cells: run.grid.num_cells(),
        particle_steps_per_s: run.particles.len() as f64 * run.steps as f64
            / (wall_s - writer.output_s).max(1e-12),
        cell_steps_per_s: 0.0,
        n_fluid_materials: 0,
        retries: stats.retries,
        threads,
        dt_min: if run.steps > 0 { dt_min } else { 0.0 },
        dt_max,
        mass_drift: (run.particles.total_mass() - m0) / m0,
        momentum_drift: dp,
        energy_drift: if e0.total().abs() > 0.0 {
            (e1.total() - e0.total()) / e0.total()
        } else {
            e1.total()
        },
        initial_energy: e0,
        final_energy: e1,
        phase_times: Default::default(),
        iterations: Some(stats.finish(run.steps)),
        error: failure.as_ref().map(|e| e.to_string()),
    };
    write_summary(&opts.out_dir, &summary)?;
    match failure {
        Some(e) => Err(e),
        None => Ok(summary),
    }
}
