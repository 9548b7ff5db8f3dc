//! The implicit MPM solid (Newmark + Newton, or quasistatic load steps) as a
//! model of the run loop. Its Δt control is its own (cut on a failed or slow
//! Newton solve, grown after easy steps): the loop's request only bounds it
//! through the end time the run already knows.

use crate::driver::model::{
    Conserved, Counts, Description, DtRequest, FieldSet, Model, StepStats, Violation,
};
use crate::driver::models::arrays::{
    load_particles, name_particle_material, particle_conserved, particle_fields, particle_watchdog,
    put_vectors, save_particles, take_vectors,
};
use crate::driver::models::solid_explicit::SOLID_HISTORY;
use crate::driver::{DtLimiter, LimitCause};
use crate::error::Error;
use crate::mpm::{ImplicitCarried, ImplicitRun};
use crate::output::checkpoint::{Checkpoint, CheckpointError};
use crate::stepper::Energies;

/// A solid-only implicit MPM run.
pub struct ImplicitSolid<const D: usize> {
    /// The run.
    pub run: ImplicitRun<D>,
    /// The scene's shape function name.
    pub shape: String,
}

impl<const D: usize> ImplicitSolid<D> {
    /// Energies (no body-force potential: implicit runs ramp their loads, so
    /// the total is not conserved anyway).
    fn energies(&self) -> Energies {
        Energies {
            kinetic: self.run.particles.kinetic_energy(),
            strain: self.run.particles.strain_energy(&self.run.materials),
            potential: 0.0,
        }
    }
}

impl<const D: usize> Model for ImplicitSolid<D> {
    fn kind(&self) -> String {
        format!("implicit_solid_{D}d")
    }

    fn time(&self) -> f64 {
        self.run.t
    }

    fn steps(&self) -> u64 {
        self.run.steps
    }

    fn stable_dt(&self) -> f64 {
        self.run.dt.min(self.run.params.dt_max)
    }

    fn step(&mut self, _dt: DtRequest) -> Result<StepStats, Error> {
        let st = self.run.step()?;
        // The loads' and grips' work is put in from outside (the summary's
        // energy drift is net of it); momentum is left as it was.
        Ok(StepStats {
            dt: st.dt,
            nonlinear_iterations: st.newton_iterations,
            linear_iterations: st.linear_iterations,
            retries: st.retries,
            boundary: Some(crate::ice::BoundaryExchange {
                prescribed_work: st.external_work,
                ..Default::default()
            }),
        })
    }

    fn annotate(&self, e: Error) -> Error {
        name_particle_material(e, &self.run.particles, &self.run.materials)
    }

    /// Δt here is the Newton step control's: the site is the last failed
    /// attempt that cut it (its particle and material, or every material
    /// when the failure names no particle), `None` before any cut.
    fn dt_limiter(&self) -> Option<DtLimiter> {
        let r = &self.run;
        let cut = r.last_cut.as_ref()?;
        let (site, material) = match cut.particle {
            Some(p) if p < r.particles.len() => (
                format!("particle {p}"),
                r.materials[r.particles.material[p] as usize].name.clone(),
            ),
            _ => (
                "the implicit solve".to_string(),
                r.materials
                    .iter()
                    .map(|m| m.name.as_str())
                    .collect::<Vec<_>>()
                    .join("`, `"),
            ),
        };
        Some(DtLimiter {
            site,
            material,
            cause: LimitCause::FailedSolve {
                what: cut.what.clone(),
            },
            dt: cut.dt,
        })
    }

    fn field_sets(&self) -> Vec<FieldSet<'_>> {
        vec![particle_fields(&self.run.particles)]
    }

    fn history_columns(&self) -> Vec<(&'static str, &'static str)> {
        SOLID_HISTORY.to_vec()
    }

    fn history_row(&self, row: &mut Vec<f64>) {
        let e = self.energies();
        row.extend([e.kinetic, e.strain, e.potential, e.total()]);
    }

    fn conserved(&self) -> Conserved {
        let r = &self.run;
        particle_conserved(&r.particles, &r.materials, self.energies())
    }

    fn watchdog(&self) -> Option<Violation> {
        particle_watchdog(&self.run.particles, &self.run.materials)
    }

    fn save(&self, ck: &mut Checkpoint) {
        let r = &self.run;
        save_particles(ck, "particles", &r.particles);
        put_vectors(ck, "model.accel", &r.accel);
        let c = r.carried();
        ck.put_f64(
            "model.scalars",
            vec![4],
            vec![r.t, r.dt, c.prescribed_applied, r.end],
        );
        ck.put_u64(
            "model.counters",
            vec![3],
            vec![r.steps, c.initialised as u64, c.full_storage as u64],
        );
        if !r.grip_reactions.is_empty() {
            put_vectors(ck, "model.grip_reactions", &r.grip_reactions);
        }
    }

    fn load(&mut self, ck: &mut Checkpoint) -> Result<(), CheckpointError> {
        let r = &mut self.run;
        r.particles = load_particles(ck, "particles", r.materials.len())?;
        let n = r.particles.len();
        r.accel = take_vectors(ck, "model.accel", n)?;
        let s = ck.take_f64("model.scalars", Some(&[4]))?;
        let c = ck.take_u64("model.counters", Some(&[3]))?;
        r.t = s[0];
        r.dt = s[1];
        r.steps = c[0];
        r.restore_carried(ImplicitCarried {
            prescribed_applied: s[2],
            initialised: c[1] != 0,
            full_storage: c[2] != 0,
        });
        // Absent before the first step, and in checkpoints before the
        // grips' work was booked (their next step then starts from zero).
        r.grip_reactions = match ck.shape("model.grip_reactions") {
            Some(_) => take_vectors(ck, "model.grip_reactions", r.prescribed.len())?,
            None => Vec::new(),
        };
        Ok(())
    }

    fn counts(&self) -> Counts {
        Counts {
            particles: self.run.particles.len(),
            cells: self.run.grid.num_cells(),
            fluid_materials: 0,
            elements: 0,
        }
    }

    fn describe(&self) -> Description {
        let r = &self.run;
        let sum = |f: fn(&crate::mpm::StepStats) -> f64| r.stats.iter().map(f).sum::<f64>();
        Description {
            shape: self.shape.clone(),
            update: if r.params.dynamic {
                "newmark".into()
            } else {
                "quasistatic".into()
            },
            iterative: true,
            momentum_conserved: true,
            axial_momentum_only: false,
            phase_times: Default::default(),
            implicit_split: Some([
                sum(|s| s.assembly_s),
                sum(|s| s.factor_s),
                sum(|s| s.solve_s),
                sum(|s| s.particles_s),
            ]),
            coupled_iterations: None,
        }
    }
}
