//! The fluid-only (ICE) run of a scene: stepping with retries, cell outputs
//! (`.vti` cell data, `cells_NNNN.csv`), history and summary.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::driver::{open_history, pad3, progress_bar, write_summary, RunOptions, Summary};
use crate::error::{Error, Result};
use crate::ice::{equilibrate, step, IceError, IceParams, IceState, IceWorkspace, StepInfo};
use crate::material::eos::EquationOfState;
use crate::output::csv::{write_columns, CsvAppender};
use crate::output::vtk::{write_vti, Field, PvdSeries};
use crate::scene::{build_fluid_run, Format, Scene};
use crate::stepper::Energies;

/// Halvings of the timestep tried before a step is given up.
const MAX_RETRIES: u32 = 20;

/// Kinetic and internal energy of the fluid (internal reported as `strain`
/// in [`Energies`], which the solid run uses for stored elastic energy).
pub(crate) fn energies<const D: usize>(state: &IceState<D>) -> Energies {
    let (mut kinetic, mut internal) = (0.0, 0.0);
    for (mat, mc) in state.materials.iter().zip(&state.cells) {
        let cv = mat.eos.specific_heat_cv();
        for &c in &state.layout.interior {
            kinetic += 0.5 * mc.mass[c] * mc.velocity[c].norm_squared();
            internal += mc.mass[c] * cv * mc.temperature[c];
        }
    }
    Energies {
        kinetic,
        strain: internal,
        potential: 0.0,
    }
}

pub(crate) struct FluidWriter {
    dir: PathBuf,
    formats: Vec<Format>,
    pvd: PvdSeries,
    history: CsvAppender,
    snapshots: usize,
    pub(crate) output_s: f64,
}

impl FluidWriter {
    pub(crate) fn new(dir: &Path, formats: &[Format], dim: usize) -> Result<Self> {
        let history = open_history(
            dir,
            dim,
            &[
                ("mass", "kg"),
                ("kinetic", "J"),
                ("internal", "J"),
                ("total", "J"),
            ],
        )?;
        Ok(Self {
            dir: dir.to_path_buf(),
            formats: formats.to_vec(),
            pvd: PvdSeries::new(dir.join("cells.pvd")),
            history,
            snapshots: 0,
            output_s: 0.0,
        })
    }

    pub(crate) fn history_row<const D: usize>(&mut self, state: &IceState<D>) -> Result<()> {
        let start = Instant::now();
        let e = energies(state);
        let (mass, _, _) = state.totals();
        self.history
            .row(&[state.time, mass, e.kinetic, e.strain, e.kinetic + e.strain])
            .map_err(|err| Error::io(self.history.path().to_path_buf(), err))?;
        self.output_s += start.elapsed().as_secs_f64();
        Ok(())
    }

    pub(crate) fn snapshot<const D: usize>(&mut self, state: &IceState<D>) -> Result<()> {
        let start = Instant::now();
        let k = self.snapshots;
        let fields = CellFields::of(state);
        if self.formats.contains(&Format::Vtk) {
            let name = format!("cells_{k:04}.vti");
            let path = self.dir.join(&name);
            fields
                .write_vti(&path, state)
                .map_err(|e| Error::io(&path, e))?;
            self.pvd
                .push(state.time, &name)
                .map_err(|e| Error::io(self.pvd.path().to_path_buf(), e))?;
        }
        if self.formats.contains(&Format::Csv) && D <= 2 {
            let path = self.dir.join(format!("cells_{k:04}.csv"));
            fields
                .write_csv(&path, state)
                .map_err(|e| Error::io(&path, e))?;
        }
        self.snapshots += 1;
        self.output_s += start.elapsed().as_secs_f64();
        Ok(())
    }
}

/// Output fields of one fluid material.
struct MaterialFields {
    /// Macroscopic density m/V, true density 1/v, volume fraction,
    /// temperature.
    scalars: [Vec<f64>; 4],
    /// Velocity.
    velocity: Vec<[f64; 3]>,
}

/// Interior cell fields in output order (x fastest).
struct CellFields {
    pressure: Vec<f64>,
    p_eq: Vec<f64>,
    mixture_density: Vec<f64>,
    per_material: Vec<MaterialFields>,
}

impl CellFields {
    fn of<const D: usize>(state: &IceState<D>) -> Self {
        let interior = &state.layout.interior;
        let vol = state.layout.cell_volume();
        let pick = |v: &[f64]| interior.iter().map(|&c| v[c]).collect::<Vec<f64>>();
        let per_material = state
            .cells
            .iter()
            .map(|mc| MaterialFields {
                scalars: [
                    interior.iter().map(|&c| mc.mass[c] / vol).collect(),
                    interior.iter().map(|&c| 1.0 / mc.sp_vol[c]).collect(),
                    pick(&mc.vol_frac),
                    pick(&mc.temperature),
                ],
                velocity: interior.iter().map(|&c| pad3(&mc.velocity[c])).collect(),
            })
            .collect();
        Self {
            pressure: pick(&state.pressure),
            p_eq: pick(&state.p_eq),
            mixture_density: interior.iter().map(|&c| state.mixture_density(c)).collect(),
            per_material,
        }
    }

    fn write_vti<const D: usize>(&self, path: &Path, state: &IceState<D>) -> std::io::Result<()> {
        let l = &state.layout;
        let cells: [usize; 3] = std::array::from_fn(|d| if d < D { l.cells[d] } else { 0 });
        let spacing: [f64; 3] = std::array::from_fn(|d| if d < D { l.h[d] } else { 1.0 });
        let names: Vec<[String; 5]> = state
            .materials
            .iter()
            .map(|m| {
                [
                    "density",
                    "true_density",
                    "volume_fraction",
                    "temperature",
                    "velocity",
                ]
                .map(|f| format!("{}_{f}", m.name))
            })
            .collect();
        let mut fields = vec![
            Field::scalar("pressure", &self.pressure),
            Field::scalar("p_eq", &self.p_eq),
            Field::scalar("mixture_density", &self.mixture_density),
        ];
        for (mf, n) in self.per_material.iter().zip(&names) {
            for (k, v) in mf.scalars.iter().enumerate() {
                fields.push(Field::scalar(&n[k], v));
            }
            fields.push(Field::vector(&n[4], &mf.velocity));
        }
        write_vti(path, pad3(&l.lower), spacing, cells, &[], &fields)
    }

    fn write_csv<const D: usize>(&self, path: &Path, state: &IceState<D>) -> std::io::Result<()> {
        let axes = ["x", "y", "z"];
        let l = &state.layout;
        let mut header: Vec<String> = Vec::new();
        let mut cols: Vec<Vec<f64>> = Vec::new();
        for d in 0..D {
            header.push(format!("{} [m]", axes[d]));
            cols.push(l.interior.iter().map(|&c| l.centre(c)[d]).collect());
        }
        header.push("pressure [Pa]".into());
        cols.push(self.pressure.clone());
        header.push("p_eq [Pa]".into());
        cols.push(self.p_eq.clone());
        header.push("mixture_density [kg/m^3]".into());
        cols.push(self.mixture_density.clone());
        for (m, mf) in state.materials.iter().zip(&self.per_material) {
            let n = &m.name;
            let names = [
                ("density", "kg/m^3"),
                ("true_density", "kg/m^3"),
                ("volume_fraction", "-"),
                ("temperature", "K"),
            ];
            for ((key, unit), values) in names.iter().zip(&mf.scalars) {
                header.push(format!("{n}_{key} [{unit}]"));
                cols.push(values.clone());
            }
            for d in 0..D {
                header.push(format!("{n}_u{} [m/s]", axes[d]));
                cols.push(mf.velocity.iter().map(|v| v[d]).collect());
            }
        }
        let h: Vec<&str> = header.iter().map(String::as_str).collect();
        let c: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        write_columns(path, &h, &c)
    }
}

/// One step with retries on a retryable error (an outflux larger than a
/// cell's content, or a failed implicit pressure solve); returns what the
/// step did and the retries used.
fn step_with_retries<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    mut dt_max: f64,
) -> std::result::Result<(StepInfo, u64), IceError> {
    let mut retries = 0;
    loop {
        match step(state, params, ws, dt_max) {
            Ok(info) => return Ok((info, retries)),
            Err(e) if e.is_retryable() && retries < MAX_RETRIES as u64 => {
                let dt = e.retry_dt().unwrap_or(dt_max);
                dt_max = 0.5 * dt;
                retries += 1;
            }
            Err(e) => return Err(e),
        }
    }
}

/// Runs a validated fluid-only scene.
pub(crate) fn run_fluid_dim<const D: usize>(
    scene: &Scene,
    opts: &RunOptions,
    threads: usize,
) -> Result<Summary> {
    let (mut state, params) = build_fluid_run::<D>(scene)?;
    equilibrate(&mut state, &params)?;
    let mut writer = FluidWriter::new(&opts.out_dir, &scene.output.formats, D)?;
    let mut ws = IceWorkspace::new(&state);
    let e0 = energies(&state);
    let (m0, p0, _) = state.totals();
    let p_scale: f64 = state
        .cells
        .iter()
        .map(|mc| {
            state
                .layout
                .interior
                .iter()
                .map(|&c| mc.mass[c] * mc.velocity[c].norm())
                .sum::<f64>()
        })
        .sum();
    writer.snapshot(&state)?;
    writer.history_row(&state)?;
    let end = scene.time.end;
    let interval = scene.output.interval;
    let hist_iv = scene.output.history_interval.or(interval.map(|i| i / 20.0));
    let mut next_out = interval.unwrap_or(f64::INFINITY);
    let mut next_hist = hist_iv.unwrap_or(0.0);
    let max_steps = scene.time.max_steps.unwrap_or(u64::MAX);
    let bar = progress_bar(opts.progress);
    let start = Instant::now();
    let mut step_s = 0.0;
    let (mut dt_min, mut dt_max_seen) = (f64::INFINITY, 0.0f64);
    let (mut steps, mut retries) = (0u64, 0u64);
    let mut failure = None;
    let mut iters = crate::driver::IterationStats::default();
    let finished = |t: f64, steps: u64| t >= end * (1.0 - 1e-12) || steps >= max_steps;
    while !finished(state.time, steps) {
        let s = Instant::now();
        let dt_cap = scene.time.dt.unwrap_or(f64::INFINITY).min(end - state.time);
        match step_with_retries(&mut state, &params, &mut ws, dt_cap) {
            Ok((info, r)) => {
                let dt = info.dt;
                iters.add(info.outer_iterations, info.linear_iterations);
                retries += r;
                dt_min = dt_min.min(dt);
                dt_max_seen = dt_max_seen.max(dt);
                steps += 1;
            }
            Err(e) => {
                failure = Some(Error::from(e));
                break;
            }
        }
        step_s += s.elapsed().as_secs_f64();
        if state.time >= next_hist * (1.0 - 1e-12) {
            writer.history_row(&state)?;
            next_hist += hist_iv.unwrap_or(0.0);
        }
        if state.time >= next_out * (1.0 - 1e-12) && !finished(state.time, steps) {
            writer.snapshot(&state)?;
            next_out += interval.unwrap_or(f64::INFINITY);
        }
        if steps % 16 == 0 {
            bar.set_position((1000.0 * state.time / end) as u64);
            bar.set_message(format!("{:.4e}", state.time));
        }
    }
    bar.finish_and_clear();
    // The last state is always written, also after a failure.
    writer.snapshot(&state)?;
    writer.history_row(&state)?;
    let wall_s = start.elapsed().as_secs_f64();
    let e1 = energies(&state);
    let (m1, p1, _) = state.totals();
    let n_cells = state.layout.num_interior();
    let dp = (p1 - p0).norm();
    let e_total0 = e0.kinetic + e0.strain;
    let summary = Summary {
        dim: D,
        mode: scene.time.mode.name().to_string(),
        shape: String::new(),
        update: String::new(),
        steps,
        final_time: state.time,
        wall_s,
        output_s: writer.output_s,
        n_particles: 0,
        n_cells,
        particle_steps_per_s: 0.0,
        cell_steps_per_s: if step_s > 0.0 {
            n_cells as f64 * steps as f64 / step_s
        } else {
            0.0
        },
        n_fluid_materials: state.num_materials(),
        retries,
        threads,
        dt_min: if steps > 0 { dt_min } else { 0.0 },
        dt_max: dt_max_seen,
        mass_drift: (m1 - m0) / m0,
        momentum_drift: if p_scale > 0.0 { dp / p_scale } else { dp },
        energy_drift: (e1.kinetic + e1.strain - e_total0) / e_total0,
        initial_energy: e0,
        final_energy: e1,
        phase_times: Default::default(),
        iterations: params.implicit.as_ref().map(|_| {
            let mut it = iters.finish(steps);
            it.retries = retries;
            it
        }),
        error: failure.as_ref().map(|e| e.to_string()),
    };
    write_summary(&opts.out_dir, &summary)?;
    match failure {
        Some(e) => Err(e),
        None => Ok(summary),
    }
}
