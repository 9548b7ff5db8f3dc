//! Lian's membrane finite elements (Lian Sec. 4) on their own as a model of
//! the run loop: one or more [`MembraneMesh`]es stepped by central
//! differences with the smallest stable Δt of all of them.

use crate::driver::model::{
    Conserved, Counts, Description, DtRequest, FieldSet, Geometry, Location, MaterialTotals, Model,
    OutField, StepStats, Values, Violation,
};
use crate::driver::models::arrays::{put_scalars, put_vectors, take_scalars, take_vectors};
use crate::error::{Error, FailureSite};
use crate::membrane::element::{MembraneMesh, V3};
use crate::output::checkpoint::{Checkpoint, CheckpointError};
use crate::scene::Scene;
use crate::stepper::Energies;

/// Membranes of Belytschko–Tsay quadrilaterals, without grid or particles.
pub struct MembraneFe {
    /// The meshes, in scene order.
    pub meshes: Vec<MembraneMesh>,
    /// Their scene names.
    pub names: Vec<String>,
    /// Time step over the stable one (`time.cfl`).
    pub cfl: f64,
    /// Current time.
    pub t: f64,
    /// Completed steps.
    pub steps: u64,
}

impl MembraneFe {
    /// Builds the meshes of a scene's `[[membrane_elements]]`.
    ///
    /// # Errors
    /// A mesh that cannot be built, naming its key.
    pub fn from_scene(scene: &Scene) -> Result<Self, Error> {
        let g = scene
            .gravity
            .as_ref()
            .map_or(V3::zeros(), |g| V3::new(g[0], g[1], g[2]));
        let mut meshes = Vec::new();
        for (i, spec) in scene.membrane_elements.iter().enumerate() {
            meshes.push(spec.build(i, g)?);
        }
        Ok(Self {
            meshes,
            names: scene
                .membrane_elements
                .iter()
                .map(|m| m.name.clone())
                .collect(),
            cfl: scene.time.cfl,
            t: 0.0,
            steps: 0,
        })
    }

    /// The energies of the whole state: kinetic, stored, and in `potential`
    /// the balance −W_ext + (hourglass and damping losses), so that the
    /// total is conserved by the exact dynamics.
    pub fn energies(&self) -> Energies {
        let mut e = Energies::default();
        for m in &self.meshes {
            e.kinetic += m.kinetic_energy();
            e.strain += m.strain_energy_total();
            e.potential += m.hourglass_energy() + m.damping_energy() - m.external_work_total();
        }
        e
    }

    /// Node positions, quads (node ids offset per mesh) and the mesh index
    /// of every node and element, all meshes together.
    fn geometry(&self) -> JoinedMesh {
        let (mut x, mut quads, mut nb, mut eb) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (b, m) in self.meshes.iter().enumerate() {
            let off = x.len() as u32;
            x.extend(m.x.iter().map(|p| [p[0], p[1], p[2]]));
            quads.extend(m.quads.iter().map(|q| q.map(|n| n + off)));
            nb.extend(std::iter::repeat_n(b as f64, m.num_nodes()));
            eb.extend(std::iter::repeat_n(b as f64, m.num_elements()));
        }
        (x, quads, nb, eb)
    }
}

/// All meshes as one: positions, quads, mesh index of each node and element.
type JoinedMesh = (Vec<[f64; 3]>, Vec<[u32; 4]>, Vec<f64>, Vec<f64>);

fn v3(v: &V3) -> [f64; 3] {
    [v[0], v[1], v[2]]
}

fn tensor9(m: &nalgebra::Matrix3<f64>) -> [f64; 9] {
    std::array::from_fn(|k| m[(k / 3, k % 3)])
}

impl Model for MembraneFe {
    fn kind(&self) -> String {
        "membrane_fe_3d".into()
    }

    fn time(&self) -> f64 {
        self.t
    }

    fn steps(&self) -> u64 {
        self.steps
    }

    fn stable_dt(&self) -> f64 {
        self.cfl
            * self
                .meshes
                .iter()
                .map(MembraneMesh::stable_dt)
                .fold(f64::INFINITY, f64::min)
    }

    fn step(&mut self, dt: DtRequest) -> Result<StepStats, Error> {
        let dt = if dt.exact {
            dt.value
        } else {
            self.stable_dt().min(dt.value)
        };
        for (m, name) in self.meshes.iter_mut().zip(&self.names) {
            m.step(dt, self.steps).map_err(|e| Error::Numerical {
                site: FailureSite {
                    step: self.steps,
                    time: self.t,
                    particle: None,
                    cell: None,
                },
                what: format!("membrane `{name}` element {}: {}", e.element, e.failure),
            })?;
        }
        self.t += dt;
        self.steps += 1;
        Ok(StepStats {
            dt,
            ..Default::default()
        })
    }

    fn field_sets(&self) -> Vec<FieldSet<'_>> {
        let (points, quads, node_body, elem_body) = self.geometry();
        let mut vel = Vec::new();
        let mut disp = Vec::new();
        let mut stress = Vec::new();
        let mut strain = Vec::new();
        let mut thick = Vec::new();
        let mut centres = Vec::new();
        for m in &self.meshes {
            vel.extend(m.v.iter().map(v3));
            disp.extend(m.x.iter().zip(&m.x0).map(|(x, x0)| v3(&(x - x0))));
            for e in 0..m.num_elements() {
                stress.push(tensor9(&m.stress_global(e)));
                strain.push(tensor9(&m.green_strain(e)));
                let q = &m.quads[e];
                let c = q.iter().fold(V3::zeros(), |s, &n| s + m.x[n as usize]) * 0.25;
                centres.push(v3(&c));
            }
            thick.extend_from_slice(&m.thickness);
        }
        vec![
            FieldSet {
                name: "membrane_nodes",
                geometry: Geometry::Quads {
                    points: points.clone(),
                    quads: quads.clone(),
                    on_cells: false,
                    centres: Vec::new(),
                },
                fields: vec![
                    OutField::with_csv("velocity", Some("v"), "m/s", Values::Vector(vel)),
                    OutField::with_csv("displacement", Some("u"), "m", Values::Vector(disp)),
                    OutField::new("membrane", "-", Values::Scalar(node_body)),
                ],
                csv: true,
            },
            FieldSet {
                name: "membrane_elements",
                geometry: Geometry::Quads {
                    points,
                    quads,
                    on_cells: true,
                    centres,
                },
                fields: vec![
                    OutField::with_csv("stress", Some("s"), "Pa", Values::Tensor(stress)),
                    OutField::with_csv("green_strain", Some("e"), "-", Values::Tensor(strain)),
                    OutField::new("thickness", "m", Values::Scalar(thick)),
                    OutField::new("membrane", "-", Values::Scalar(elem_body)),
                ],
                csv: true,
            },
        ]
    }

    fn history_columns(&self) -> Vec<(&'static str, &'static str)> {
        vec![
            ("kinetic", "J"),
            ("strain", "J"),
            ("external_work", "J"),
            ("hourglass", "J"),
            ("damping", "J"),
            ("total", "J"),
        ]
    }

    fn history_row(&self, row: &mut Vec<f64>) {
        let (mut w, mut hg, mut damp) = (0.0, 0.0, 0.0);
        for m in &self.meshes {
            w += m.external_work_total();
            hg += m.hourglass_energy();
            damp += m.damping_energy();
        }
        let e = self.energies();
        row.extend([e.kinetic, e.strain, w, hg, damp, e.total()]);
    }

    fn conserved(&self) -> Conserved {
        let mut c = Conserved {
            energies: self.energies(),
            ..Default::default()
        };
        for (m, name) in self.meshes.iter().zip(&self.names) {
            let p = m.momentum();
            c.materials.push(MaterialTotals {
                name: name.clone(),
                mass: m.total_mass(),
                momentum: v3(&p),
                kinetic: m.kinetic_energy(),
                internal: m.strain_energy_total(),
            });
            c.momentum_scale += m
                .mass
                .iter()
                .zip(&m.v)
                .map(|(mm, v)| mm * v.norm())
                .sum::<f64>();
        }
        c
    }

    fn watchdog(&self) -> Option<Violation> {
        for (m, name) in self.meshes.iter().zip(&self.names) {
            let bad = |at, field, value, rule| {
                Some(Violation {
                    at,
                    material: name.clone(),
                    field,
                    value,
                    rule,
                })
            };
            for n in 0..m.num_nodes() {
                for (field, v) in [("position", &m.x[n]), ("velocity", &m.v[n])] {
                    if let Some(c) = v.iter().find(|c| !c.is_finite()) {
                        return bad(Location::Node(n), field, *c, "finite");
                    }
                }
            }
            for e in 0..m.num_elements() {
                if let Some(c) = m.stress[e].iter().find(|c| !c.is_finite()) {
                    return bad(Location::Element(e), "stress", *c, "finite");
                }
                let t = m.thickness[e];
                if !(t.is_finite() && t > 0.0) {
                    return bad(Location::Element(e), "thickness", t, "> 0 and finite");
                }
            }
        }
        None
    }

    fn save(&self, ck: &mut Checkpoint) {
        self.save_meshes(ck);
        ck.put_f64("model.time", vec![1], vec![self.t]);
        ck.put_u64("model.steps", vec![1], vec![self.steps]);
    }

    fn load(&mut self, ck: &mut Checkpoint) -> Result<(), CheckpointError> {
        self.load_meshes(ck)?;
        self.t = ck.take_f64("model.time", Some(&[1]))?[0];
        self.steps = ck.take_u64("model.steps", Some(&[1]))?[0];
        Ok(())
    }

    fn counts(&self) -> Counts {
        Counts {
            elements: self.meshes.iter().map(MembraneMesh::num_elements).sum(),
            ..Default::default()
        }
    }

    fn describe(&self) -> Description {
        // Fixed nodes, pressure, gravity and point loads exchange momentum
        // with the outside.
        let closed = self.meshes.iter().all(|m| {
            m.fixed.iter().all(|f| !f.iter().any(|&b| b))
                && m.pressure == 0.0
                && m.gravity == V3::zeros()
                && m.f_applied.iter().all(|f| *f == V3::zeros())
        });
        Description {
            update: "central_difference".into(),
            momentum_conserved: closed,
            ..Default::default()
        }
    }

    fn dt_limiter(&self) -> Option<crate::driver::limiter::DtLimiter> {
        crate::driver::limiter::element_limiter(&self.meshes, &self.names)
    }
}

impl MembraneFe {
    /// Writes every mesh's state (prefix `membrane{i}.`), not the time.
    pub fn save_meshes(&self, ck: &mut Checkpoint) {
        for (i, m) in self.meshes.iter().enumerate() {
            let n = |s: &str| format!("membrane{i}.{s}");
            put_vectors(ck, &n("x"), &m.x);
            put_vectors(ck, &n("v"), &m.v);
            put_vectors(ck, &n("normal"), &m.normal);
            ck.put_f64_with(&n("stress"), vec![m.num_elements(), 3], |buf| {
                buf.extend(m.stress.iter().flatten().copied());
            });
            put_scalars(ck, &n("thickness"), &m.thickness);
            put_scalars(ck, &n("strain_energy"), &m.strain_energy);
            put_scalars(ck, &n("hourglass_work"), &m.hourglass_work);
            put_scalars(ck, &n("external_work"), &m.external_work);
            put_scalars(ck, &n("damping_work"), &m.damping_work);
        }
    }

    /// Reads what [`Self::save_meshes`] wrote.
    ///
    /// # Errors
    /// A missing or mis-shaped array.
    pub fn load_meshes(&mut self, ck: &mut Checkpoint) -> Result<(), CheckpointError> {
        for (i, m) in self.meshes.iter_mut().enumerate() {
            let n = |s: &str| format!("membrane{i}.{s}");
            let (nn, ne) = (m.num_nodes(), m.num_elements());
            m.x = take_vectors(ck, &n("x"), nn)?;
            m.v = take_vectors(ck, &n("v"), nn)?;
            m.normal = take_vectors(ck, &n("normal"), ne)?;
            let s = ck.take_f64(&n("stress"), Some(&[ne, 3]))?;
            m.stress = s.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            m.thickness = take_scalars(ck, &n("thickness"), ne)?;
            m.strain_energy = take_scalars(ck, &n("strain_energy"), ne)?;
            m.hourglass_work = take_scalars(ck, &n("hourglass_work"), ne)?;
            m.external_work = take_scalars(ck, &n("external_work"), nn)?;
            m.damping_work = take_scalars(ck, &n("damping_work"), nn)?;
        }
        Ok(())
    }
}
