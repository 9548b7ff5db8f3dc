//! Zhang's multiphase MPM ([`crate::multiphase`]) as a model of the run
//! loop.

use nalgebra::SVector;

use crate::driver::model::pad3;
use crate::driver::model::{
    Conserved, Counts, Description, DtRequest, FieldSet, Geometry, MaterialTotals, Model, OutField,
    StepStats, Values, Violation,
};
use crate::driver::models::arrays::{
    failure_fields, gas_point_fields, load_particles, particle_conserved, particle_fields,
    particle_watchdog, plastic_fields, save_particles,
};
use crate::driver::models::solid_explicit::{scene_name, SOLID_HISTORY};
use crate::error::Error;
use crate::multiphase::MultiphaseRun;
use crate::output::checkpoint::{Checkpoint, CheckpointError};

/// A multiphase run.
pub struct Multiphase<const D: usize> {
    /// The run: grid, materials, phases and buffers.
    pub run: MultiphaseRun<D>,
}

impl<const D: usize> Multiphase<D> {
    /// The grid snapshot: each phase's volume fraction `theta_NAME`, their
    /// sum `theta_sum` and the gas pressure `gas_pressure` on the nodes.
    fn grid_fields(&self) -> FieldSet<'_> {
        let r = &self.run;
        let g = &r.grid;
        let cells: [usize; 3] = std::array::from_fn(|d| if d < D { g.cells[d] } else { 0 });
        let n: [usize; 3] = std::array::from_fn(|d| cells[d] + 1);
        let mut order = Vec::with_capacity(n[0] * n[1] * n[2]);
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let c = [i as isize, j as isize, k as isize];
                    order.push(g.node_index(std::array::from_fn(|d| c[d])));
                }
            }
        }
        let mut fields = Vec::new();
        let mut sum = vec![0.0; order.len()];
        for ph in &r.phases {
            let th: Vec<f64> = order.iter().map(|&i| ph.theta[i]).collect();
            sum.iter_mut().zip(&th).for_each(|(s, t)| *s += t);
            let name = format!("theta_{}", r.materials[ph.material].name);
            fields.push(OutField::new(&name, "1", Values::Scalar(th)));
        }
        fields.push(OutField::new("theta_sum", "1", Values::Scalar(sum)));
        fields.push(OutField::new(
            "gas_pressure",
            "Pa",
            Values::Scalar(order.iter().map(|&i| r.gas_pressure[i]).collect()),
        ));
        FieldSet {
            name: "grid",
            geometry: Geometry::Image {
                origin: pad3(&g.lower),
                spacing: std::array::from_fn(|d| if d < D { g.h[d] } else { 1.0 }),
                cells,
                on_cells: false,
                centres: Vec::new(),
            },
            fields,
            csv: false,
        }
    }
}

impl<const D: usize> Model for Multiphase<D> {
    fn kind(&self) -> String {
        format!("multiphase_{D}d")
    }

    fn time(&self) -> f64 {
        self.run.t
    }

    fn steps(&self) -> u64 {
        self.run.steps
    }

    fn stable_dt(&self) -> f64 {
        self.run.stable_dt()
    }

    fn step(&mut self, dt: DtRequest) -> Result<StepStats, Error> {
        let dt = if dt.exact {
            dt.value
        } else {
            self.stable_dt().min(dt.value)
        };
        self.run.step(dt)?;
        // Each phase's walls' reaction (`mpm::wall_reaction`). It counts
        // the phase coupling's nodal forces on the wall nodes as the
        // particles' (their mirror images' share is not taken off), so
        // the momentum drift net of it is not round-off where the phases
        // interact at a wall (the shock on the block: 0.087 of the 49 kg
        // m/s the walls gave).
        let pic = self.run.params.pic_fraction;
        let mut j = SVector::<f64, D>::zeros();
        for ph in &self.run.phases {
            j += ph.gs.wall_impulse(dt, pic);
        }
        Ok(StepStats {
            dt,
            boundary: Some(crate::ice::BoundaryExchange {
                momentum: pad3(&j),
                ..Default::default()
            }),
            ..Default::default()
        })
    }

    fn field_sets(&self) -> Vec<FieldSet<'_>> {
        let r = &self.run;
        let all = r.all_particles();
        let mut particles = particle_fields(&all);
        particles
            .fields
            .extend(gas_point_fields(&all, &r.materials));
        particles.fields.extend(plastic_fields(&all, &r.materials));
        particles.fields.extend(failure_fields(&all, &r.materials));
        // The fields read the joined copy `all`: stored, not computed.
        vec![particles.into_owned(), self.grid_fields()]
    }

    fn history_columns(&self) -> Vec<(&'static str, &'static str)> {
        SOLID_HISTORY.to_vec()
    }

    fn history_row(&self, row: &mut Vec<f64>) {
        let e = self.run.energies();
        row.extend([e.kinetic, e.strain, e.potential, e.total()]);
    }

    fn conserved(&self) -> Conserved {
        let r = &self.run;
        let mut out = Conserved {
            materials: r
                .materials
                .iter()
                .map(|m| MaterialTotals {
                    name: m.name.clone(),
                    ..Default::default()
                })
                .collect(),
            energies: r.energies(),
            momentum_scale: 0.0,
        };
        for ph in &r.phases {
            let c = particle_conserved(&ph.particles, &r.materials, Default::default());
            let (dst, src) = (&mut out.materials[ph.material], &c.materials[ph.material]);
            dst.mass += src.mass;
            for d in 0..3 {
                dst.momentum[d] += src.momentum[d];
            }
            dst.kinetic += src.kinetic;
            dst.internal += src.internal;
            out.momentum_scale += c.momentum_scale;
        }
        out
    }

    fn watchdog(&self) -> Option<Violation> {
        let r = &self.run;
        r.phases.iter().find_map(|ph| {
            particle_watchdog(&ph.particles, &r.materials).map(|mut v| {
                v.material = format!(
                    "{} (points counted within its phase)",
                    r.materials[ph.material].name
                );
                v
            })
        })
    }

    fn save(&self, ck: &mut Checkpoint) {
        for (k, ph) in self.run.phases.iter().enumerate() {
            save_particles(ck, &format!("phase{k}"), &ph.particles);
            // The stable step's input: the stiffening of the last step's
            // start, which the current positions do not give back.
            ck.put_f64(
                &format!("phase{k}.stiffening"),
                vec![ph.stiffening.len()],
                ph.stiffening.clone(),
            );
        }
        ck.put_f64("model.time", vec![1], vec![self.run.t]);
        ck.put_u64("model.steps", vec![1], vec![self.run.steps]);
        ck.put_f64("model.drag_heat", vec![1], vec![self.run.drag_heat]);
        ck.put_f64(
            "model.drag_dissipation",
            vec![1],
            vec![self.run.drag_dissipation],
        );
    }

    fn load(&mut self, ck: &mut Checkpoint) -> Result<(), CheckpointError> {
        let n = self.run.materials.len();
        for k in 0..self.run.phases.len() {
            self.run.phases[k].particles = load_particles(ck, &format!("phase{k}"), n)?;
        }
        self.run.t = ck.take_f64("model.time", Some(&[1]))?[0];
        self.run.steps = ck.take_u64("model.steps", Some(&[1]))?[0];
        if ck.shape("model.drag_heat").is_some() {
            self.run.drag_heat = ck.take_f64("model.drag_heat", Some(&[1]))?[0];
        }
        if ck.shape("model.drag_dissipation").is_some() {
            self.run.drag_dissipation = ck.take_f64("model.drag_dissipation", Some(&[1]))?[0];
        }
        // The nodal fields of the restored points (a failure here shows
        // again, named, at the next step); then the points' stiffening, the
        // stable step's input, as the unbroken run has it: computed at the
        // last step's start, not at the restored positions (recomputed
        // there only for a checkpoint without it).
        let _ = self.run.nodes(0.0);
        for k in 0..self.run.phases.len() {
            let name = format!("phase{k}.stiffening");
            if ck.shape(&name).is_some() {
                let n = self.run.phases[k].particles.len();
                self.run.phases[k].stiffening = ck.take_f64(&name, Some(&[n]))?;
            }
        }
        Ok(())
    }

    fn counts(&self) -> Counts {
        Counts {
            particles: self.run.phases.iter().map(|p| p.particles.len()).sum(),
            cells: self.run.grid.num_cells(),
            fluid_materials: 0,
            elements: 0,
        }
    }

    fn describe(&self) -> Description {
        Description {
            shape: scene_name(&self.run.params.shape),
            update: scene_name(&self.run.params.scheme),
            iterative: false,
            momentum_conserved: !self.run.grid.axisymmetric,
            axial_momentum_only: false,
            phase_times: self.run.phase_times(),
            implicit_split: None,
            coupled_iterations: None,
        }
    }

    fn dt_limiter(&self) -> Option<crate::driver::limiter::DtLimiter> {
        use crate::driver::limiter::{particle_limiter, tighter};
        let r = &self.run;
        r.phases.iter().enumerate().fold(None, |best, (k, ph)| {
            let site = particle_limiter(&r.grid, &r.materials, &ph.particles, &ph.stiffening).map(
                |mut l| {
                    l.site = format!("{} of phase {k}", l.site);
                    l
                },
            );
            tighter(best, site)
        })
    }
}
