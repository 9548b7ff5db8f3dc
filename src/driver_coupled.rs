//! The driver of coupled MPM-ICE scenes (Guilkey Sec. 3.3): time loop,
//! particle and cell snapshots, history and summary.

use std::path::Path;
use std::time::Instant;

use crate::coupling::CoupledRun;
use crate::driver::{
    progress_bar, write_particles_csv, write_particles_vtu, write_summary, RunOptions, Summary,
};
use crate::driver_fluid::{energies, FluidWriter};
use crate::error::{Error, Result};
use crate::material::eos::EquationOfState;
use crate::output::vtk::PvdSeries;
use crate::scene::{build_coupled_run, Format, Scene};
use crate::stepper::Energies;

/// Particle snapshots of a coupled run (`particles.pvd` + `.vtu`, CSV).
struct ParticleWriter {
    pvd: PvdSeries,
    k: usize,
}

impl ParticleWriter {
    fn write<const D: usize>(
        &mut self,
        dir: &Path,
        formats: &[Format],
        run: &CoupledRun<D>,
    ) -> Result<f64> {
        let start = Instant::now();
        let k = self.k;
        // One field: its particles; several: all of them, field by field.
        let merged;
        let particles = if run.fields.len() == 1 {
            &run.fields[0].particles
        } else {
            merged = run.all_particles();
            &merged
        };
        if formats.contains(&Format::Vtk) {
            let name = format!("particles_{k:04}.vtu");
            let path = dir.join(&name);
            write_particles_vtu(&path, particles).map_err(|e| Error::io(&path, e))?;
            self.pvd
                .push(run.fluid.time, &name)
                .map_err(|e| Error::io(self.pvd.path().to_path_buf(), e))?;
        }
        if formats.contains(&Format::Csv) {
            let path = dir.join(format!("particles_{k:04}.csv"));
            write_particles_csv(&path, particles).map_err(|e| Error::io(&path, e))?;
        }
        self.k += 1;
        Ok(start.elapsed().as_secs_f64())
    }
}

/// Energies of the whole system: kinetic (fluid + particles), internal of
/// the fluids (in `strain`, as in the fluid driver) plus the particles'
/// strain energy.
fn total_energies<const D: usize>(run: &CoupledRun<D>) -> Energies {
    let mut e = energies(&run.fluid);
    // The solid fields' cells are a copy of the particles: count those.
    for f in &run.fields {
        let sc = &run.fluid.cells[f.ice_material];
        let cv = f.eos.specific_heat_cv();
        for &c in &run.fluid.layout.interior {
            e.kinetic -= 0.5 * sc.mass[c] * sc.velocity[c].norm_squared();
            e.strain -= sc.mass[c] * cv * sc.temperature[c];
        }
        e.kinetic += f.particles.kinetic_energy();
        e.strain += f.particles.strain_energy(&run.materials);
    }
    e
}

/// Fluid mass (the solid fields' cells excluded) and particle mass.
fn masses<const D: usize>(run: &CoupledRun<D>) -> (f64, f64) {
    let fluid: f64 = (0..run.num_fluids())
        .map(|r| {
            run.fluid
                .layout
                .interior
                .iter()
                .map(|&c| run.fluid.cells[r].mass[c])
                .sum::<f64>()
        })
        .sum();
    let solid = run.fields.iter().map(|f| f.particles.total_mass()).sum();
    (fluid, solid)
}

/// Runs a validated coupled scene.
pub(crate) fn run_coupled_dim<const D: usize>(
    scene: &Scene,
    opts: &RunOptions,
    threads: usize,
) -> Result<Summary> {
    let mut run = build_coupled_run::<D>(scene)?;
    let dir = &opts.out_dir;
    let formats = &scene.output.formats;
    let mut cells = FluidWriter::new(dir, formats, D)?;
    let mut parts = ParticleWriter {
        pvd: PvdSeries::new(dir.join("particles.pvd")),
        k: 0,
    };
    let mut output_s = parts.write(dir, formats, &run)?;
    cells.snapshot(&run.fluid)?;
    cells.history_row(&run.fluid)?;
    let e0 = total_energies(&run);
    let (mf0, ms0) = masses(&run);
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
    let mut steps = 0u64;
    let mut failure = None;
    let mut iters = crate::driver::IterationStats::default();
    let finished = |t: f64, steps: u64| t >= end * (1.0 - 1e-12) || steps >= max_steps;
    while !finished(run.fluid.time, steps) {
        let s = Instant::now();
        let dt_cap = scene
            .time
            .dt
            .unwrap_or(f64::INFINITY)
            .min(end - run.fluid.time);
        match run.step(dt_cap) {
            Ok(info) => {
                iters.add(info.outer_iterations, info.linear_iterations);
                dt_min = dt_min.min(info.dt);
                dt_max_seen = dt_max_seen.max(info.dt);
                steps += 1;
            }
            Err(e) => {
                failure = Some(e);
                break;
            }
        }
        step_s += s.elapsed().as_secs_f64();
        let t = run.fluid.time;
        if t >= next_hist * (1.0 - 1e-12) {
            cells.history_row(&run.fluid)?;
            next_hist += hist_iv.unwrap_or(0.0);
        }
        if t >= next_out * (1.0 - 1e-12) && !finished(t, steps) {
            output_s += parts.write(dir, formats, &run)?;
            cells.snapshot(&run.fluid)?;
            next_out += interval.unwrap_or(f64::INFINITY);
        }
        if steps.is_multiple_of(16) {
            bar.set_position((1000.0 * t / end) as u64);
            bar.set_message(format!("{t:.4e}"));
        }
    }
    bar.finish_and_clear();
    // The last state is always written, also after a failure.
    output_s += parts.write(dir, formats, &run)?;
    cells.snapshot(&run.fluid)?;
    cells.history_row(&run.fluid)?;
    let wall_s = start.elapsed().as_secs_f64();
    let e1 = total_energies(&run);
    let (mf1, ms1) = masses(&run);
    let n_cells = run.fluid.layout.num_interior();
    let n_particles: usize = run.fields.iter().map(|f| f.particles.len()).sum();
    let per_step = |n: usize| {
        if step_s > 0.0 {
            n as f64 * steps as f64 / step_s
        } else {
            0.0
        }
    };
    let e_scale = e0.kinetic + e0.strain;
    let summary = Summary {
        dim: D,
        mode: scene.time.mode.name().to_string(),
        shape: format!("{:?}", run.mpm.shape).to_lowercase(),
        update: format!("{:?}", run.mpm.scheme).to_lowercase(),
        steps,
        final_time: run.fluid.time,
        wall_s,
        output_s: output_s + cells.output_s,
        n_particles,
        n_cells,
        particle_steps_per_s: per_step(n_particles),
        cell_steps_per_s: per_step(n_cells),
        n_fluid_materials: run.num_fluids(),
        retries: 0,
        threads,
        dt_min: if steps > 0 { dt_min } else { 0.0 },
        dt_max: dt_max_seen,
        // Fluid mass (walls and heat sources keep it; outflow faces do not)
        // and particle mass together.
        mass_drift: ((mf1 + ms1) - (mf0 + ms0)) / (mf0 + ms0),
        // Not reported: walls and the pressure at them exchange momentum
        // with the coupled system (JSON null).
        momentum_drift: f64::NAN,
        energy_drift: if e_scale > 0.0 {
            (e1.kinetic + e1.strain - e_scale) / e_scale
        } else {
            0.0
        },
        initial_energy: e0,
        final_energy: e1,
        phase_times: run.phase_times(),
        iterations: run.ice.implicit.as_ref().map(|_| iters.finish(steps)),
        error: failure.as_ref().map(|e| e.to_string()),
    };
    write_summary(dir, &summary)?;
    match failure {
        Some(e) => Err(e),
        None => Ok(summary),
    }
}
