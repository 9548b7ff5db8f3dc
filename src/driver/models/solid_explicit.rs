//! The explicit MPM solid as a model of the run loop.

use crate::driver::model::pad3;
use crate::driver::model::{
    Conserved, Counts, Description, DtRequest, FieldSet, Geometry, Model, OutField, StepStats,
    Values, Violation,
};
use crate::driver::models::arrays::{
    failure_fields, gas_point_fields, load_particles, name_particle_material, particle_conserved,
    particle_fields, particle_watchdog, plastic_fields, save_particles,
};
use crate::error::Error;
use crate::ice::BoundaryExchange;
use crate::mpm::stable_dt;
use crate::output::checkpoint::{Checkpoint, CheckpointError};
use crate::stepper::SolidRun;

/// A solid-only explicit MPM run.
pub struct ExplicitSolid<const D: usize> {
    /// The run: grid, materials, particles and buffers.
    pub run: SolidRun<D>,
}

/// The name a scene file uses for a serialisable choice (`quadratic_bspline`).
pub fn scene_name<T: serde::Serialize>(x: &T) -> String {
    match serde_json::to_value(x) {
        Ok(serde_json::Value::String(s)) => s,
        _ => String::new(),
    }
}

/// Membrane point outputs (York Sec. 3.2): the tangential stress `s`
/// (in-plane trace of σ = s t⊗t), the stretch of the point's segment
/// (current / initial length) and the unit tangent; none without membranes.
fn membrane_fields<const D: usize>(r: &SolidRun<D>) -> Vec<OutField<'static>> {
    let m = &r.membranes;
    if m.is_empty() {
        return Vec::new();
    }
    let p = &r.particles;
    let s = (0..p.len())
        .map(|i| {
            if m.segment0[i] > 0.0 {
                (0..D).map(|d| p.stress.get(i)[(d, d)]).sum()
            } else {
                0.0
            }
        })
        .collect();
    let t = m.tangent.iter().map(pad3).collect();
    vec![
        OutField::new("membrane_stress", "Pa", Values::Scalar(s)),
        OutField::new("stretch", "1", Values::Scalar(m.stretch(&p.x))),
        OutField::new("tangent", "1", Values::Vector(t)),
    ]
}

/// Solid energies as history columns.
pub(crate) const SOLID_HISTORY: [(&str, &str); 4] = [
    ("kinetic", "J"),
    ("strain", "J"),
    ("potential", "J"),
    ("total", "J"),
];

/// Solid energies of an axisymmetric (r–z) run: particle volumes and masses
/// are per radian, so the sums are energies per radian (× 2π for the whole
/// body of revolution).
pub(crate) const SOLID_HISTORY_AXISYMMETRIC: [(&str, &str); 4] = [
    ("kinetic", "J/rad"),
    ("strain", "J/rad"),
    ("potential", "J/rad"),
    ("total", "J/rad"),
];

impl<const D: usize> Model for ExplicitSolid<D> {
    fn kind(&self) -> String {
        format!("explicit_solid_{D}d")
    }

    fn time(&self) -> f64 {
        self.run.t
    }

    fn steps(&self) -> u64 {
        self.run.steps
    }

    fn stable_dt(&self) -> f64 {
        let r = &self.run;
        stable_dt(&r.grid, &r.materials, &r.particles, r.time.cfl)
    }

    fn step(&mut self, dt: DtRequest) -> Result<StepStats, Error> {
        let dt = if dt.exact {
            dt.value
        } else {
            self.stable_dt().min(dt.value)
        };
        let dt = self.run.step_dt(dt)?;
        // The walls' reaction and the body force's impulse, so that the
        // summary's momentum drift is what the scheme itself lost.
        Ok(StepStats {
            dt,
            boundary: Some(BoundaryExchange {
                momentum: pad3(&self.run.wall_impulse),
                body_momentum: pad3(&self.run.body_impulse),
                damping_work: self.run.damping_work,
                ..Default::default()
            }),
            ..Default::default()
        })
    }

    fn annotate(&self, e: Error) -> Error {
        name_particle_material(e, &self.run.particles, &self.run.materials)
    }

    fn field_sets(&self) -> Vec<FieldSet<'_>> {
        let r = &self.run;
        let g = &r.grid;
        let gs = r.grid_state();
        let cells: [usize; 3] = std::array::from_fn(|d| if d < D { g.cells[d] } else { 0 });
        let n: [usize; 3] = std::array::from_fn(|d| cells[d] + 1);
        // The image's node `i` (x fastest) in the grid's arrays, read as the
        // snapshot is written: a copy of the node fields would cost 32 B a
        // node (12 B a particle in the memory bench, issue 24).
        let node = move |i: usize| {
            let c = [i % n[0], i / n[0] % n[1], i / (n[0] * n[1])];
            g.node_index(std::array::from_fn(|d| c[d] as isize))
        };
        let nodes = n[0] * n[1] * n[2];
        let mass = Values::computed(nodes, 1, move |i, o| o[0] = gs.mass[node(i)]);
        let vel = Values::computed(nodes, 3, move |i, o| {
            o[..3].copy_from_slice(&pad3(&gs.velocity_new[node(i)]))
        });
        let grid = FieldSet {
            name: "grid",
            geometry: Geometry::Image {
                origin: pad3(&g.lower),
                spacing: std::array::from_fn(|d| if d < D { g.h[d] } else { 1.0 }),
                cells,
                on_cells: false,
                centres: Vec::new(),
            },
            fields: vec![
                OutField::new("mass", "kg", mass),
                OutField::new("velocity", "m/s", vel),
            ],
            csv: false,
        };
        let mut particles = particle_fields(&r.particles);
        if g.axisymmetric {
            // Masses and volumes are per radian in r–z.
            for f in particles.fields.iter_mut() {
                if f.name == "mass" || f.name == "volume" {
                    let base = if f.name == "mass" { "kg" } else { "m^3" };
                    f.unit = format!("{base}/rad");
                }
            }
        }
        particles
            .fields
            .extend(gas_point_fields(&r.particles, &r.materials));
        particles
            .fields
            .extend(plastic_fields(&r.particles, &r.materials));
        particles
            .fields
            .extend(failure_fields(&r.particles, &r.materials));
        particles.fields.extend(membrane_fields(r));
        vec![particles, grid]
    }

    fn history_columns(&self) -> Vec<(&'static str, &'static str)> {
        if self.run.grid.axisymmetric {
            SOLID_HISTORY_AXISYMMETRIC.to_vec()
        } else {
            SOLID_HISTORY.to_vec()
        }
    }

    fn history_row(&self, row: &mut Vec<f64>) {
        let e = self.run.energies();
        row.extend([e.kinetic, e.strain, e.potential, e.total()]);
    }

    fn conserved(&self) -> Conserved {
        let r = &self.run;
        particle_conserved(&r.particles, &r.materials, r.energies())
    }

    fn watchdog(&self) -> Option<Violation> {
        particle_watchdog(&self.run.particles, &self.run.materials)
    }

    fn save(&self, ck: &mut Checkpoint) {
        save_particles(ck, "particles", &self.run.particles);
        ck.put_f64("model.time", vec![1], vec![self.run.t]);
        ck.put_u64("model.steps", vec![1], vec![self.run.steps]);
    }

    fn load(&mut self, ck: &mut Checkpoint) -> Result<(), CheckpointError> {
        self.run.particles = load_particles(ck, "particles", self.run.materials.len())?;
        self.run.t = ck.take_f64("model.time", Some(&[1]))?[0];
        self.run.steps = ck.take_u64("model.steps", Some(&[1]))?[0];
        let r = &mut self.run;
        if !r.membranes.is_empty() {
            // Refresh the membrane tangents for outputs; the stress itself is
            // turned at the next step's start, as in an unbroken run.
            let p = &r.particles;
            let mut stress = p.stress.clone();
            let _ = r.membranes.update_frames(&p.x, &mut stress);
        }
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

    fn dt_limiter(&self) -> Option<crate::driver::limiter::DtLimiter> {
        let r = &self.run;
        crate::driver::limiter::particle_limiter(&r.grid, &r.materials, &r.particles, &[])
    }

    fn describe(&self) -> Description {
        Description {
            shape: scene_name(&self.run.params.shape),
            update: scene_name(&self.run.params.scheme),
            iterative: false,
            // Mass-proportional damping is a drag to the ground: no drift
            // is reported.
            momentum_conserved: self.run.params.damping == 0.0,
            // r–z: the hoop force changes the radial momentum.
            axial_momentum_only: self.run.grid.axisymmetric,
            phase_times: self.run.phase_times(),
            implicit_split: None,
            coupled_iterations: None,
        }
    }
}
