//! Lian's coupled step (Lian, Liu, Zhang Sec. 6): MPM bodies (solids, gas
//! points) on the grid and membranes of finite elements
//! ([`MembraneMesh`]) on their own nodes, joined by the grid contact of
//! [`super::GridContact`]. In 3D.
//!
//! One step, in the paper's order:
//! 1–2. MPM trial solution on the grid: P2G, the mass gradient (Eq. 51),
//!    stresses and the grid momentum equation (Eqs. 60–64).
//! 3. Each membrane's trial solution: element forces (Eqs. 39–45) and the
//!    trial nodal velocities (Eq. 46).
//! 4. Contact per membrane: its nodes mapped to the grid (Eq. 49), the
//!    contact force where the bodies approach (Eqs. 52–58), the MPM nodes
//!    corrected (Eq. 53) and the membrane nodes (Eq. 59); fixed membrane
//!    directions stay at rest (the wall takes the reaction).
//! 5. G2P: particle velocities and positions (Eq. 65, Eq. 19).
//! 6. Membrane positions (Eq. 47) and element stresses.

use std::time::Instant;

use nalgebra::SVector;

use super::{ContactDetection, ContactLaw, ContactStats, GridContact, MpmNodes, PointBody};
use crate::error::{Error, FailureSite, Result};
use crate::membrane::element::{MembraneMesh, V3};
use crate::mpm::{BodyForce, CoupledMpm, UpdateScheme};
use crate::stepper::SolidRun;

/// The buffers of the coupled step: per membrane its grid contact and
/// nodal normals, and the MPM body's nodal mass gradient. The state itself
/// (the MPM run, the membranes) stays with the caller.
pub struct MembraneContactStep {
    /// Stick or Coulomb slip.
    pub law: ContactLaw,
    /// Where the force may act: Lian's approach rule, or that and a closing
    /// gap.
    pub detection: ContactDetection,
    /// One set of grid contact buffers per membrane.
    contact: Vec<GridContact<3>>,
    /// Nodal normals of each membrane (area-weighted element normals).
    normals: Vec<Vec<V3>>,
    /// Each membrane's nodes held in all three directions.
    held: Vec<Vec<bool>>,
    /// Each membrane's half thickness at its nodes and the nodes' adjoining
    /// areas (scratch), for the gap check.
    half_thickness: Vec<(Vec<f64>, Vec<f64>)>,
    /// The MPM body's nodal mass gradient.
    grad: Vec<SVector<f64, 3>>,
    /// The contact's change of the MPM body's nodal velocity, `−Δt Σ f/m`
    /// over the membranes (zero off the contact nodes).
    kick: Vec<SVector<f64, 3>>,
    /// Each membrane's trial nodal velocities, before the contact.
    trial: Vec<Vec<V3>>,
    /// Its share of each particle's velocity change, `Σ_i S_ip` kick.
    particle_kick: Vec<SVector<f64, 3>>,
    /// What the contact did over the run, all membranes together.
    pub totals: ContactStats,
    /// Wall time of the step's parts outside the MPM body's own phases
    /// ([`SolidRun::phase_times`]), accumulated over the run.
    pub times: ContactTimes,
    /// The last step's.
    pub last: ContactStats,
}

fn failure(solid: &SolidRun<3>, what: String) -> Error {
    Error::Numerical {
        site: FailureSite {
            step: solid.steps,
            time: solid.t,
            particle: None,
            cell: None,
        },
        what,
    }
}

impl MembraneContactStep {
    /// Buffers for `solid`'s grid and `meshes`.
    pub fn new(
        solid: &SolidRun<3>,
        meshes: &[MembraneMesh],
        law: ContactLaw,
        detection: ContactDetection,
    ) -> Self {
        let n = solid.grid.num_nodes();
        Self {
            law,
            detection,
            contact: (0..meshes.len())
                .map(|_| GridContact::new(&solid.grid))
                .collect(),
            normals: meshes
                .iter()
                .map(|m| vec![V3::zeros(); m.num_nodes()])
                .collect(),
            held: meshes
                .iter()
                .map(|m| m.fixed.iter().map(|f| f.iter().all(|&b| b)).collect())
                .collect(),
            grad: vec![SVector::zeros(); n],
            kick: vec![SVector::zeros(); n],
            trial: meshes
                .iter()
                .map(|m| vec![V3::zeros(); m.num_nodes()])
                .collect(),
            half_thickness: meshes
                .iter()
                .map(|m| (vec![0.0; m.num_nodes()], vec![0.0; m.num_nodes()]))
                .collect(),
            particle_kick: Vec::new(),
            totals: ContactStats::default(),
            times: ContactTimes::default(),
            last: ContactStats::default(),
        }
    }

    /// One coupled step of `dt` (Lian Sec. 6, steps 1–6) of `solid` and
    /// `meshes` (named `names`); advances `solid`'s time and step count.
    /// The MPM update must be USL or USF (the split step, [`CoupledMpm`],
    /// has no MUSL).
    ///
    /// # Errors
    /// A particle off the grid or inverted, a membrane node off the grid, a
    /// membrane element collapsed, inverted or not finite — each named.
    pub fn step(
        &mut self,
        s: &mut SolidRun<3>,
        meshes: &mut [MembraneMesh],
        names: &[String],
        dt: f64,
    ) -> Result<f64> {
        if s.params.scheme == UpdateScheme::Musl {
            return Err(failure(
                s,
                "membrane contact needs the USL or USF update (mpm.update), not MUSL".into(),
            ));
        }
        let mpm = CoupledMpm {
            grid: &s.grid,
            materials: &s.materials,
            params: &s.params,
            body: s.body.as_deref().map(|b| b as &dyn BodyForce<3>),
            t: s.t,
            dt,
            step: s.steps,
        };
        // Steps 1–2: the MPM trial solution.
        mpm.p2g(&s.particles, &mut s.grid_state, &mut s.scratch)?;
        let mut clock = Instant::now();
        let mut lap = |acc: &mut f64| {
            let now = Instant::now();
            *acc += (now - clock).as_secs_f64();
            clock = now;
        };
        mpm.mass_gradient(&s.particles, &s.scratch, &mut self.grad);
        lap(&mut self.times.contact_s);
        mpm.solve(
            &mut s.particles,
            &mut s.grid_state,
            &mut s.scratch,
            None,
            &[],
        )?;
        let mut step_stats = ContactStats::default();
        lap(&mut 0.0);
        for (k, mesh) in meshes.iter_mut().enumerate() {
            // Step 3: the membrane's trial solution.
            mesh.compute_forces(dt);
            mesh.trial_velocities(dt);
            lap(&mut self.times.membrane_s);
            // The membrane's half thickness only for the gap check.
            let gap = self.detection == ContactDetection::Gap;
            let (h, a) = &mut self.half_thickness[k];
            let half = gap.then_some((h.as_mut_slice(), a.as_mut_slice()));
            node_normals(mesh, &mut self.normals[k], half);
            // Step 4: contact.
            let body = PointBody {
                x: &mesh.x,
                mass: &mesh.mass,
                v: &mesh.v,
                normal: &self.normals[k],
                held: &self.held[k],
                half_thickness: if gap { &self.half_thickness[k].0 } else { &[] },
            };
            if let Err(node) = self.contact[k].map_points(&s.grid, &body) {
                let what = format!("membrane `{}` node {node} has left the grid", names[k]);
                return Err(failure(s, what));
            }
            let gs = &mut s.grid_state;
            let mut nodes = MpmNodes {
                mass: &gs.mass,
                velocity: &mut gs.velocity_new,
                accel: &mut gs.accel,
                mass_gradient: &self.grad,
                mass_floor: s.params.mass_floor,
            };
            let contact = &mut self.contact[k];
            if self.detection == ContactDetection::Gap && contact.measure_gaps(&nodes) > 0 {
                // The particles' current half extents `l0_d |F_dd|` (the
                // GIMP domain's rule), once per particle.
                let p = &s.particles;
                let mut half = (usize::MAX, SVector::<f64, 3>::zeros());
                mpm.for_each_support(p, &s.scratch, &mut |q, i| {
                    if half.0 != q {
                        let f = p.f.get(q);
                        half = (
                            q,
                            SVector::from_fn(|d, _| p.half_size.get(q)[d] * f[(d, d)].abs()),
                        );
                    }
                    contact.add_surface_point(i, &p.x[q], &half.1);
                });
            }
            let st = contact.resolve(&mut nodes, self.law, self.detection, dt);
            // Without a contact force the correction changes nothing.
            let acted = st.contact_nodes > 0;
            if acted {
                self.trial[k].copy_from_slice(&mesh.v);
                for &i in &self.contact[k].touched {
                    let f = self.contact[k].force[i];
                    if f != V3::zeros() {
                        self.kick[i] -= f * (dt / s.grid_state.mass[i]);
                    }
                }
            }
            self.contact[k].correct_points(dt, &mut mesh.v);
            // The wall holds a fixed direction; it takes the reaction.
            mesh.apply_fixed();
            let mut st = st;
            if acted {
                st.dissipated -= mesh.correction_work(&self.trial[k]);
            }
            step_stats.add(&st);
            lap(&mut self.times.contact_s);
        }
        s.grid.mirror_ghosts(&mut s.grid_state.velocity_new);
        s.grid.mirror_ghosts(&mut s.grid_state.accel);
        // The contact's work on the particles, `Σ m_p δv_p·(v_p^n + v_p^{n+1})/2`,
        // with δv_p its share of the velocity change (FLIP and PIC alike take
        // the nodes' change), interpolated at the positions G2P uses: the
        // mid-step velocity splits a particle's kinetic-energy change exactly
        // between the forces, as for the membranes
        // ([`MembraneMesh::correction_work`]).
        let touched = step_stats.contact_nodes > 0;
        let work = |p: &crate::mpm::Particles<3>, kick: &[SVector<f64, 3>]| -> f64 {
            (0..p.len())
                .map(|q| p.mass[q] * kick[q].dot(&p.v[q]))
                .sum::<f64>()
        };
        let mut particle_work = 0.0;
        lap(&mut self.times.contact_s);
        if touched {
            s.grid.mirror_ghosts(&mut self.kick);
            self.particle_kick.clear();
            self.particle_kick
                .resize(s.particles.len(), SVector::zeros());
            mpm.g2p_add(
                &s.particles,
                &self.kick,
                &s.scratch,
                &mut self.particle_kick,
            );
            particle_work += 0.5 * work(&s.particles, &self.particle_kick);
        }
        lap(&mut self.times.loss_s);
        // Step 5: G2P.
        mpm.g2p(&mut s.particles, &s.grid_state, &mut s.scratch, &[])?;
        lap(&mut 0.0);
        if touched {
            particle_work += 0.5 * work(&s.particles, &self.particle_kick);
            step_stats.dissipated -= particle_work;
            self.kick.iter_mut().for_each(|k| *k = SVector::zeros());
        }
        lap(&mut self.times.loss_s);
        // Step 6: the membranes move and update their stresses.
        for (mesh, name) in meshes.iter_mut().zip(names) {
            mesh.update_positions(dt);
            if let Err(e) = mesh.update_stress(dt, s.steps) {
                let what = format!("membrane `{name}` element {}: {}", e.element, e.failure);
                return Err(failure(s, what));
            }
        }
        lap(&mut self.times.membrane_s);
        s.t += dt;
        s.steps += 1;
        self.last = step_stats;
        self.totals.add(&step_stats);
        Ok(dt)
    }
}

/// Wall time of the coupled step's own parts, accumulated over steps (the
/// MPM body's P2G, grid and G2P are in its [`SolidRun::phase_times`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct ContactTimes {
    /// The membranes' trial solution and update (forces, velocities,
    /// positions, stresses).
    pub membrane_s: f64,
    /// The contact: mass gradient, normals, map, gaps, forces, correction.
    pub contact_s: f64,
    /// Measuring the contact's loss on the particles (steps with contact).
    pub loss_s: f64,
}

/// The nodal normals of a membrane: each quad's area vector
/// `½ (x₃ − x₁) × (x₄ − x₂)` (its area times its unit normal, exact for a
/// planar quad) added to its four corners. With `half = Some((h, area))`
/// also the half thickness at the nodes: the mean of the adjoining quads'
/// `t/2` weighted by their areas (the area vectors' lengths), `area` being
/// scratch of the same length.
pub fn node_normals(
    mesh: &MembraneMesh,
    out: &mut [V3],
    mut half: Option<(&mut [f64], &mut [f64])>,
) {
    out.iter_mut().for_each(|n| *n = V3::zeros());
    if let Some((h, area)) = half.as_mut() {
        h.iter_mut().for_each(|v| *v = 0.0);
        area.iter_mut().for_each(|v| *v = 0.0);
    }
    for (q, t) in mesh.quads.iter().zip(&mesh.thickness) {
        let p = q.map(|n| mesh.x[n as usize]);
        let a = (p[2] - p[0]).cross(&(p[3] - p[1])) * 0.5;
        for &n in q {
            out[n as usize] += a;
        }
        if let Some((h, area)) = half.as_mut() {
            let len = a.norm();
            for &n in q {
                h[n as usize] += 0.5 * t * len;
                area[n as usize] += len;
            }
        }
    }
    if let Some((h, area)) = half {
        h.iter_mut().zip(area.iter()).for_each(|(v, a)| {
            if *a > 0.0 {
                *v /= a;
            }
        });
    }
}
