//! The end-of-run summary (`summary.json`).

use std::path::Path;

use serde::Serialize;

use crate::driver::model::{CoupledIterations, MaterialTotals};
use crate::error::{Error, Result};
use crate::output::atomic_write;
use crate::stepper::Energies;

/// The end-of-run summary written to `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// Spatial dimension.
    pub dim: usize,
    /// Integration mode.
    pub mode: String,
    /// The model the loop drove (checkpoint kind).
    pub model: String,
    /// Shape function.
    pub shape: String,
    /// MPM update scheme.
    pub update: String,
    /// Steps taken (in all runs of a restarted chain).
    pub steps: u64,
    /// Simulation time reached.
    pub final_time: f64,
    /// Wall-clock seconds of this run's time loop (output included).
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
    /// Membrane finite elements.
    pub n_elements: usize,
    /// Membrane element updates per second of stepping (output excluded; 0
    /// without membrane elements).
    pub element_steps_per_s: f64,
    /// The process's peak resident memory when the summary was written
    /// \[bytes\] (program, model, last good state, snapshots; `null` where
    /// the system does not report it).
    pub peak_memory_bytes: Option<u64>,
    /// [`Summary::peak_memory_bytes`] per particle (`null` without
    /// particles).
    pub peak_memory_per_particle: Option<f64>,
    /// Steps repeated with a smaller timestep (the loop's retries and the
    /// model's own cuts).
    pub retries: u64,
    /// Worker threads.
    pub threads: usize,
    /// Smallest timestep.
    pub dt_min: f64,
    /// Largest timestep.
    pub dt_max: f64,
    /// (M_end − M_0 − M_in)/M_0, `M_in` the mass that came in through the
    /// boundary (`boundary_exchange`; 0 where the model does not account
    /// for it).
    pub mass_drift: f64,
    /// |P_end − P_0 − P_in| / Σ m|v| at the start (|…| if that is zero),
    /// `P_in` the momentum that came in through the boundary (advected, and
    /// the boundary faces' pressure impulse; for MPM the walls' reaction),
    /// and the body force's impulse; NaN (JSON null) where walls exchange
    /// momentum with the system unaccounted; in an r–z MPM run, of the
    /// axial component only (the hoop force changes the radial one).
    pub momentum_drift: f64,
    /// (E_end − E_0 − E_in)/E_scale of kinetic + stored + body-force
    /// potential energy, `E_scale` the largest of |E_0|, |E_end| and their
    /// kinetic and stored parts (what the account holds; a run that takes
    /// in much more than it starts with is measured against that), `E_in`
    /// the energy advected in, the boundary faces' pressure work, and what
    /// heat sources, reactions, prescribed motion and loads, and damping
    /// put in or took out ([`crate::ice::BoundaryExchange::energy_in`]).
    pub energy_drift: f64,
    /// What crossed the domain boundary over the run (mass, momentum,
    /// energy in) and the energy put in from outside (heat sources,
    /// reactions, prescribed motion and loads, damping), where the model
    /// accounts for it (ICE fluids, explicit and implicit MPM, coupled
    /// MPM-ICE, multiphase; absent otherwise).
    /// The drifts above are net of it; the raw change of a total is its
    /// drift plus this.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub boundary_exchange: Option<crate::ice::BoundaryExchange>,
    /// Energies at the start (kinetic, strain, potential for solids; for
    /// fluids `strain` holds the internal energy).
    pub initial_energy: Energies,
    /// Energies at the end.
    pub final_energy: Energies,
    /// Per material at the start: mass, momentum, kinetic and stored energy.
    pub initial_materials: Vec<MaterialTotals>,
    /// Per material at the end.
    pub final_materials: Vec<MaterialTotals>,
    /// Wall time per phase of the explicit MPM step (binning, P2G, grid,
    /// G2P + stress).
    pub phase_times: crate::mpm::PhaseTimes,
    /// Iteration counts and time split of implicit modes (absent for
    /// explicit runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub iterations: Option<IterationStats>,
    /// Steps between watchdog scans (0: off).
    pub watchdog_interval: u64,
    /// Checkpoint folders this run wrote.
    pub checkpoints: Vec<String>,
    /// The checkpoint this run continued from.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub restarted_from: Option<String>,
    /// Error that stopped the run early, if any.
    pub error: Option<String>,
    /// Warnings of the run (a 100-fold Δt drop), also printed on stderr.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Program, commit, date, command line, threads and the scene as run.
    pub provenance: Provenance,
}

/// Where a run's numbers come from: the program and the scene as run.
#[derive(Debug, Clone, Serialize)]
pub struct Provenance {
    /// Program name.
    pub program: &'static str,
    /// Its version (`Cargo.toml`).
    pub version: &'static str,
    /// The git commit it was built from ("unknown" outside a checkout).
    pub git: &'static str,
    /// When the summary was written, UTC (ISO 8601).
    pub date_utc: String,
    /// The command line (empty when run as a library).
    pub command_line: Vec<String>,
    /// Worker threads.
    pub threads: usize,
    /// The scene's content hash (the checkpoint's).
    pub scene_hash: String,
    /// The scene as run: every key resolved, defaults and `--set`
    /// overrides included.
    pub scene: serde_json::Value,
}

impl Provenance {
    /// The provenance of a run of `scene` now.
    pub fn of(scene: &crate::scene::Scene, command_line: &[String], threads: usize) -> Self {
        Self {
            program: env!("CARGO_PKG_NAME"),
            version: env!("CARGO_PKG_VERSION"),
            git: env!("MPMICE_GIT_HASH"),
            date_utc: utc_now(),
            command_line: command_line.to_vec(),
            threads,
            scene_hash: super::scene_hash(scene),
            // Plain data always serialises.
            scene: serde_json::to_value(scene).unwrap_or_default(),
        }
    }
}

/// The current UTC time as `YYYY-MM-DDThh:mm:ssZ`.
pub fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    utc_of(secs)
}

/// `YYYY-MM-DDThh:mm:ssZ` of `secs` seconds after 1970-01-01T00:00:00Z
/// (the proleptic Gregorian calendar: days to year, month, day by the
/// 400-year cycle of 146 097 days, years starting on 1 March).
pub fn utc_of(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
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
    /// Coupled implicit MPM-ICE: the coupling iteration's passes, the
    /// pressure stages' time and each implicit field's Newton solves
    /// (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub coupled: Option<CoupledIterations>,
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

/// Writes `summary.json` atomically.
pub(crate) fn write_summary(dir: &Path, summary: &Summary) -> Result<()> {
    let path = dir.join("summary.json");
    atomic_write(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, summary).map_err(std::io::Error::other)?;
        std::io::Write::write_all(w, b"\n")
    })
    .map_err(|e| Error::io(&path, e))
}

#[cfg(test)]
mod tests {
    use super::utc_of;

    #[test]
    fn utc_dates_of_known_instants() {
        assert_eq!(utc_of(0), "1970-01-01T00:00:00Z");
        // 2000-02-29 (a leap day of a century leap year) 12:34:56.
        assert_eq!(utc_of(951_827_696), "2000-02-29T12:34:56Z");
        // 2026-11-26T20:00:00Z.
        assert_eq!(utc_of(1_795_723_200), "2026-11-26T20:00:00Z");
        // 2100-03-01 (2100 is no leap year).
        assert_eq!(utc_of(4_107_542_400), "2100-03-01T00:00:00Z");
    }
}
