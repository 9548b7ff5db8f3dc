//! Coupled MPM-ICE (Guilkey Sec. 3.3; explicit or semi-implicit pressure,
//! one or more solid fields) as a model of the run loop.

use crate::coupling::CoupledRun;
use crate::driver::model::{
    Conserved, Counts, Description, DtRequest, FieldSet, MaterialTotals, Model, StepStats,
    Violation,
};
use crate::driver::models::arrays::{
    cell_fields, cell_material_totals, cell_watchdog, failure_fields, load_cells, load_particles,
    name_particle_material, particle_fields, particle_material_totals, particle_watchdog,
    plastic_fields, put_vectors, save_cells, save_particles, take_vectors,
};
use crate::driver::models::fluid::{
    cell_momentum_scale, load_carried, save_carried, FLUID_HISTORY,
};
use crate::driver::models::solid_explicit::scene_name;
use crate::driver::{CoupledIterations, FieldIterations};
use crate::error::Error;
use crate::output::checkpoint::{Checkpoint, CheckpointError};

/// History columns of a run with reactions (sums over its reactions since
/// the start): the reactant mass converted, the energy the products received
/// with it (`Σ Δm (c_v,s T + Q + ½|v|²)`) and the heat of reaction in it.
const REACTION_HISTORY: [(&str, &str); 3] = [
    ("reacted_mass", "kg"),
    ("reaction_energy", "J"),
    ("reaction_heat", "J"),
];

/// A coupled run.
pub struct Coupled<const D: usize> {
    /// The run.
    pub run: CoupledRun<D>,
}

impl<const D: usize> Model for Coupled<D> {
    fn kind(&self) -> String {
        format!("coupled_mpm_ice_{D}d")
    }

    fn time(&self) -> f64 {
        self.run.fluid.time
    }

    fn steps(&self) -> u64 {
        self.run.steps
    }

    fn stable_dt(&self) -> f64 {
        self.run.stable_dt()
    }

    fn step(&mut self, dt: DtRequest) -> Result<StepStats, Error> {
        // Implicit solids: `time.dt` is the largest step, cut on a failed
        // solve (the implicit solid run's meaning of it).
        let implicit = self.run.fields.iter().any(|f| f.implicit.is_some());
        let info = if dt.exact && !implicit {
            self.run.step_exact(dt.value)?
        } else {
            self.run.step(dt.value)?
        };
        Ok(StepStats {
            dt: info.dt,
            nonlinear_iterations: info.outer_iterations,
            linear_iterations: info.linear_iterations,
            retries: self.run.last_halvings + self.run.last_implicit_retries,
            boundary: Some(self.run.step_inputs()),
        })
    }

    fn annotate(&self, e: Error) -> Error {
        // A particle failure names the field's material.
        match self.run.failed_field.and_then(|i| self.run.fields.get(i)) {
            Some(f) => name_particle_material(e, &f.particles, &self.run.materials),
            None => e,
        }
    }

    fn retry_dt(&self, _e: &Error) -> Option<f64> {
        // The coupled step halves Δt itself on a retryable pressure stage;
        // a failure after that may have moved the particles.
        None
    }

    fn field_sets(&self) -> Vec<FieldSet<'_>> {
        let run = &self.run;
        // One field: its particles (read as written); several: all of
        // them, field by field (a joined copy, so its values are stored).
        // With the plastic strain, damage and failure flags of plastic and
        // failing materials.
        fn solid<'a, const D: usize>(
            p: &'a crate::mpm::Particles<D>,
            materials: &[crate::material::SolidMaterial],
        ) -> FieldSet<'a> {
            let mut set = particle_fields(p);
            set.fields.extend(plastic_fields(p, materials));
            set.fields.extend(failure_fields(p, materials));
            set
        }
        let particles = if run.fields.len() == 1 {
            solid(&run.fields[0].particles, &run.materials)
        } else {
            solid(&run.all_particles(), &run.materials).into_owned()
        };
        vec![particles, cell_fields(&run.fluid)]
    }

    fn history_columns(&self) -> Vec<(&'static str, &'static str)> {
        let mut c = FLUID_HISTORY.to_vec();
        if !self.run.reactions.is_empty() {
            // Summed over the reactions since the start of the run.
            c.extend(REACTION_HISTORY);
        }
        c
    }

    fn history_row(&self, row: &mut Vec<f64>) {
        // The coupled account, as the summary's: the fluids in the cells and
        // the particles, not the solid fields' cell copies (which count a
        // solid's c_v T instead of its stored work, and its burnt mass
        // twice, once in `reaction_energy`).
        let (mass, e) = self.run.account();
        row.extend([mass, e.kinetic, e.strain, e.kinetic + e.strain]);
        if !self.run.reactions.is_empty() {
            let t = self.run.reaction_totals();
            row.extend([t.mass, t.energy, t.heat]);
        }
    }

    fn conserved(&self) -> Conserved {
        let run = &self.run;
        let mut materials: Vec<MaterialTotals> = (0..run.num_fluids())
            .map(|r| cell_material_totals(&run.fluid, r))
            .collect();
        for k in 0..run.materials.len() {
            let mut t = MaterialTotals {
                name: run.materials[k].name.clone(),
                ..Default::default()
            };
            for f in &run.fields {
                let ft = particle_material_totals(&f.particles, &run.materials, k);
                t.mass += ft.mass;
                t.kinetic += ft.kinetic;
                t.internal += ft.internal;
                for d in 0..3 {
                    t.momentum[d] += ft.momentum[d];
                }
            }
            materials.push(t);
        }
        // The released chemical energy is an input of the summary's
        // account (`BoundaryExchange::reaction_energy`), not a negative
        // potential as in the history's balance.
        let mut energies = self.run.account().1;
        energies.potential += self.run.reaction_totals().energy;
        Conserved {
            materials,
            energies,
            momentum_scale: cell_momentum_scale(&run.fluid, 0..run.num_fluids())
                + run
                    .fields
                    .iter()
                    .map(|f| f.particles.momentum_scale())
                    .sum::<f64>(),
        }
    }

    fn watchdog(&self) -> Option<Violation> {
        let run = &self.run;
        run.fields
            .iter()
            .find_map(|f| particle_watchdog(&f.particles, &run.materials))
            .or_else(|| cell_watchdog(&run.fluid))
    }

    fn save(&self, ck: &mut Checkpoint) {
        let run = &self.run;
        save_cells(ck, "cells", &run.fluid);
        for (i, f) in run.fields.iter().enumerate() {
            save_particles(ck, &format!("field{i}"), &f.particles);
            if let Some(imp) = &f.implicit {
                // The Newmark state and the Newton Δt control.
                put_vectors(ck, &format!("field{i}.accel"), &imp.accel);
                let c = imp.carried();
                ck.put_f64(&format!("field{i}.implicit_dt"), vec![1], vec![imp.dt]);
                ck.put_u64(
                    &format!("field{i}.implicit_flags"),
                    vec![2],
                    vec![c.initialised as u64, c.full_storage as u64],
                );
            }
        }
        save_carried(ck, "workspace", run.ice_workspace());
        if !run.reactions.is_empty() {
            let data = run
                .reactions
                .iter()
                .flat_map(|r| [r.totals.mass, r.totals.energy, r.totals.heat, r.dt_limit])
                .collect();
            // With each reaction's step limit, which came from the rates of
            // the last step (a dry run at the restored state would differ).
            ck.put_f64("reactions.totals", vec![run.reactions.len(), 4], data);
        }
        ck.put_u64("model.steps", vec![1], vec![run.steps]);
    }

    fn load(&mut self, ck: &mut Checkpoint) -> Result<(), CheckpointError> {
        let run = &mut self.run;
        load_cells(ck, "cells", &mut run.fluid)?;
        let n_materials = run.materials.len();
        for i in 0..run.fields.len() {
            run.fields[i].particles = load_particles(ck, &format!("field{i}"), n_materials)?;
            let n = run.fields[i].particles.len();
            if let Some(imp) = run.fields[i].implicit.as_mut() {
                imp.accel = take_vectors(ck, &format!("field{i}.accel"), n)?;
                imp.dt = ck.take_f64(&format!("field{i}.implicit_dt"), Some(&[1]))?[0];
                let flags = ck.take_u64(&format!("field{i}.implicit_flags"), Some(&[2]))?;
                let mut c = imp.carried();
                c.initialised = flags[0] != 0;
                c.full_storage = flags[1] != 0;
                imp.restore_carried(c);
            }
        }
        let cells = run.fluid.layout.len();
        load_carried(ck, "workspace", run.ice_workspace_mut(), cells)?;
        if !run.reactions.is_empty() {
            let n = run.reactions.len();
            let data = ck.take_f64("reactions.totals", Some(&[n, 4]))?;
            for (r, t) in run.reactions.iter_mut().zip(data.chunks_exact(4)) {
                r.totals.mass = t[0];
                r.totals.energy = t[1];
                r.totals.heat = t[2];
                r.dt_limit = t[3];
            }
            run.mark_fed_cells();
        }
        run.steps = ck.take_u64("model.steps", Some(&[1]))?[0];
        Ok(())
    }

    fn counts(&self) -> Counts {
        let run = &self.run;
        Counts {
            particles: run.fields.iter().map(|f| f.particles.len()).sum(),
            cells: run.fluid.layout.num_interior(),
            fluid_materials: run.num_fluids(),
            elements: 0,
        }
    }

    fn dt_limiter(&self) -> Option<crate::driver::limiter::DtLimiter> {
        use crate::driver::limiter::{
            cell_limiter, particle_limiter, tighter, DtLimiter, LimitCause,
        };
        let run = &self.run;
        // An implicit solid's Newton step control, not a wave limit, sets
        // Δt: there, and after a cut in the step just taken, the last cut
        // names the cause (the implicit cylinder without exchange blamed
        // a steel particle's sound speed for a Δt the pressure stage had
        // halved 100-fold).
        let newton = run.fields.iter().any(|f| f.implicit.is_some());
        if let Some((step, cut)) = &run.last_cut {
            if newton || step + 1 == run.steps {
                return Some(DtLimiter {
                    site: "the coupled step".into(),
                    material: run
                        .fluid
                        .materials
                        .iter()
                        .map(|m| m.name.as_str())
                        .collect::<Vec<_>>()
                        .join("`, `"),
                    cause: LimitCause::FailedSolve {
                        what: cut.what.clone(),
                    },
                    dt: cut.dt,
                });
            }
        }
        let cells = cell_limiter(&run.fluid, 0..run.num_fluids());
        let waves = run
            .fields
            .iter()
            .filter(|f| f.implicit.is_none() && f.rigid_velocity.is_none())
            .fold(cells, |best, f| {
                tighter(
                    best,
                    particle_limiter(&run.grid, &run.materials, &f.particles, &[]),
                )
            });
        let burn = run.burn_limit().map(|b| {
            let r = &run.reactions[b.reaction];
            let particles = &run.fields[r.field].particles;
            DtLimiter {
                site: format!("cell {:?}", run.fluid.layout.coords(b.cell)),
                material: run.fluid.materials[r.product].name.clone(),
                cause: LimitCause::Burn {
                    reactant: particles
                        .material
                        .first()
                        .map_or_else(String::new, |&m| run.materials[m as usize].name.clone()),
                    mass: b.mass,
                    inflow: b.inflow,
                },
                dt: b.dt,
            }
        });
        tighter(waves, burn)
    }

    fn describe(&self) -> Description {
        let run = &self.run;
        Description {
            shape: scene_name(&run.mpm.shape),
            update: scene_name(&run.mpm.scheme),
            iterative: run.ice.implicit.is_some(),
            // The walls' reaction and the boundary faces' impulse are in
            // the account where it closes (`CoupledRun::momentum_accounted`).
            momentum_conserved: run.momentum_accounted(),
            axial_momentum_only: false,
            phase_times: run.phase_times(),
            // Implicit solid fields: their Newton solves' time split.
            implicit_split: run.fields.iter().any(|f| f.implicit.is_some()).then(|| {
                let t = &run.implicit_totals;
                [t.assembly_s, t.factor_s, t.solve_s, t.particles_s]
            }),
            coupled_iterations: coupled_iterations(run),
        }
    }
}

/// The coupled implicit step's iteration report for the run summary
/// (`None` without implicit fields): passes per step, the pressure stages'
/// time, each implicit field's Newton and Krylov iterations per step (a
/// field is named by its particles' first material).
fn coupled_iterations<const D: usize>(run: &CoupledRun<D>) -> Option<CoupledIterations> {
    let t = &run.implicit_totals;
    let n = t.steps.max(1) as f64;
    let fields: Vec<FieldIterations> = run
        .fields
        .iter()
        .filter(|f| f.implicit.is_some())
        .map(|f| FieldIterations {
            material: f
                .particles
                .material
                .first()
                .and_then(|&m| run.materials.get(usize::from(m)))
                .map_or_else(String::new, |m| m.name.clone()),
            newton_mean: f.implicit_totals.newton_iterations as f64 / n,
            newton_max: f.implicit_totals.max_newton_iterations,
            linear_mean: f.implicit_totals.linear_iterations as f64 / n,
            factorisations_mean: f.implicit_totals.factorisations as f64 / n,
        })
        .collect();
    (!fields.is_empty()).then(|| CoupledIterations {
        passes_mean: t.coupling_iterations as f64 / n,
        passes_max: t.max_coupling_iterations,
        cells_s: run.pressure_s,
        fields,
    })
}
