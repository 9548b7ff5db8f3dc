//! Lian's coupled system as a model of the run loop: MPM bodies (solids,
//! gas points) and membranes of finite elements joined by the grid contact
//! (Lian Sec. 5–6, [`crate::contact::MembraneContactStep`]), in 3D. The MPM
//! part is an [`ExplicitSolid`], the membranes a [`MembraneFe`]; this model
//! steps them together and reports both.

use crate::contact::{ContactDetection, ContactLaw, MembraneContactStep};
use crate::driver::model::{
    Conserved, Counts, Description, DtRequest, FieldSet, Model, StepStats, Violation,
};
use crate::driver::models::{ExplicitSolid, MembraneFe};
use crate::error::Error;
use crate::output::checkpoint::{Checkpoint, CheckpointError};

/// MPM bodies and element membranes in grid contact (3D).
pub struct MembraneContact {
    /// The MPM part.
    pub solid: ExplicitSolid<3>,
    /// The membranes (their time follows the MPM's).
    pub membranes: MembraneFe,
    /// The contact's buffers and totals.
    pub contact: MembraneContactStep,
}

impl MembraneContact {
    /// Joins the two parts with the contact `law` and `detection`.
    pub fn new(
        solid: ExplicitSolid<3>,
        membranes: MembraneFe,
        law: ContactLaw,
        detection: ContactDetection,
    ) -> Self {
        let contact = MembraneContactStep::new(&solid.run, &membranes.meshes, law, detection);
        Self {
            solid,
            membranes,
            contact,
        }
    }

    /// The model of a scene with membrane elements and a 3D grid: its MPM
    /// bodies, its membranes and its `[contact]` law (default slip).
    ///
    /// # Errors
    /// A scene whose MPM part or membranes do not build (named).
    pub fn from_scene(scene: &crate::scene::Scene) -> Result<Self, Error> {
        let fe = MembraneFe::from_scene(scene)?;
        let solid = ExplicitSolid {
            run: crate::scene::build_solid_run::<3>(scene)?,
        };
        let spec = scene.contact.clone().unwrap_or_default();
        Ok(Self::new(solid, fe, spec.law(), spec.detection()))
    }
}

/// History columns: the particles', the membranes', the contact's.
/// `contact_dissipated` is the work the contact took from the particles and
/// the membranes' nodes, each force's work taken with the mid-step velocity
/// as the bodies' own accounts do ([`crate::contact::ContactStats`]);
/// `total` counts it as a loss, like the membranes' hourglass and damping
/// losses, so it keeps the initial energy up to the scheme's own error.
const HISTORY: [(&str, &str); 12] = [
    ("particle_kinetic", "J"),
    ("particle_strain", "J"),
    ("particle_potential", "J"),
    ("membrane_kinetic", "J"),
    ("membrane_strain", "J"),
    ("membrane_external_work", "J"),
    ("membrane_hourglass", "J"),
    ("membrane_damping", "J"),
    ("total", "J"),
    ("contact_nodes", "1"),
    ("contact_normal_impulse", "N s"),
    ("contact_dissipated", "J"),
];

impl Model for MembraneContact {
    fn kind(&self) -> String {
        "membrane_contact_3d".into()
    }

    fn time(&self) -> f64 {
        self.solid.run.t
    }

    fn steps(&self) -> u64 {
        self.solid.run.steps
    }

    fn stable_dt(&self) -> f64 {
        self.solid.stable_dt().min(self.membranes.stable_dt())
    }

    fn step(&mut self, dt: DtRequest) -> Result<StepStats, Error> {
        let dt = if dt.exact {
            dt.value
        } else {
            self.stable_dt().min(dt.value)
        };
        let fe = &mut self.membranes;
        let dt = self
            .contact
            .step(&mut self.solid.run, &mut fe.meshes, &fe.names, dt)?;
        fe.t = self.solid.run.t;
        fe.steps = self.solid.run.steps;
        Ok(StepStats {
            dt,
            ..Default::default()
        })
    }

    fn annotate(&self, e: Error) -> Error {
        self.solid.annotate(e)
    }

    fn field_sets(&self) -> Vec<FieldSet<'_>> {
        let mut sets = self.solid.field_sets();
        sets.extend(self.membranes.field_sets());
        sets
    }

    fn history_columns(&self) -> Vec<(&'static str, &'static str)> {
        HISTORY.to_vec()
    }

    fn history_row(&self, row: &mut Vec<f64>) {
        // Solid: kinetic, strain, potential, total; then the membranes:
        // kinetic, strain, external work, hourglass, damping, total. The
        // solid's total goes, the membranes' becomes the sum.
        let start = row.len();
        self.solid.history_row(row);
        let solid_total = row.remove(start + 3);
        self.membranes.history_row(row);
        let lost = self.contact.totals.dissipated;
        if let Some(total) = row.last_mut() {
            *total += solid_total + lost;
        }
        row.push(self.contact.last.contact_nodes as f64);
        row.push(self.contact.totals.normal_impulse);
        row.push(lost);
    }

    fn conserved(&self) -> Conserved {
        let mut c = self.solid.conserved();
        let m = self.membranes.conserved();
        c.materials.extend(m.materials);
        c.energies.kinetic += m.energies.kinetic;
        c.energies.strain += m.energies.strain;
        // The contact's loss is booked like the membranes' losses.
        c.energies.potential += m.energies.potential + self.contact.totals.dissipated;
        c.momentum_scale += m.momentum_scale;
        c
    }

    fn watchdog(&self) -> Option<Violation> {
        self.solid.watchdog().or_else(|| self.membranes.watchdog())
    }

    fn save(&self, ck: &mut Checkpoint) {
        // The MPM part writes the model's time and step count; the
        // membranes take them from it on load.
        self.solid.save(ck);
        self.membranes.save_meshes(ck);
        // The contact's running totals enter the history and the energy
        // account, so a restart resumes them.
        let t = self.contact.totals;
        ck.put_f64_with("contact.totals", vec![6], |buf| {
            buf.extend([t.normal_impulse, t.tangential_impulse, t.dissipated]);
            buf.extend(t.impulse);
        });
    }

    fn load(&mut self, ck: &mut Checkpoint) -> Result<(), CheckpointError> {
        self.solid.load(ck)?;
        self.membranes.load_meshes(ck)?;
        // A checkpoint written before the totals were saved starts them at 0.
        if ck.shape("contact.totals").is_some() {
            let v = ck.take_f64("contact.totals", Some(&[6]))?;
            let t = &mut self.contact.totals;
            t.normal_impulse = v[0];
            t.tangential_impulse = v[1];
            t.dissipated = v[2];
            t.impulse = [v[3], v[4], v[5]];
        }
        self.membranes.t = self.solid.run.t;
        self.membranes.steps = self.solid.run.steps;
        Ok(())
    }

    fn counts(&self) -> Counts {
        let mut c = self.solid.counts();
        c.elements = self.membranes.counts().elements;
        c
    }

    fn describe(&self) -> Description {
        let mut d = self.solid.describe();
        d.momentum_conserved = d.momentum_conserved && self.membranes.describe().momentum_conserved;
        d
    }

    fn dt_limiter(&self) -> Option<crate::driver::limiter::DtLimiter> {
        crate::driver::limiter::tighter(self.solid.dt_limiter(), self.membranes.dt_limiter())
    }
}
