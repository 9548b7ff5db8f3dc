//! Grid contact between an MPM body and a body of points that lives off the
//! grid — Lian's membrane finite-element nodes (Lian, Liu, Zhang Sec. 5,
//! Eqs. 49–59; the algorithm of Sec. 6 step 4).
//!
//! Each step both bodies first advance on their own (trial solutions, as if
//! they did not touch): the MPM body `s` on the grid (its nodal mass and
//! trial velocity after the internal force, [`crate::mpm::CoupledMpm`]),
//! the point body `r` on its own nodes. Then the points' mass, momentum
//! and surface normal are mapped to the grid ([`GridContact::map_points`],
//! Eq. 49), the nodes where both bodies approach each other are found
//! (Eq. 52), the contact force that restores the impenetrability condition
//! (stick, Eq. 55) — or its normal part with a Coulomb-limited tangential
//! part (slip, Eqs. 56–58) — is applied to the MPM body's nodes (Eq. 53)
//! ([`GridContact::resolve`]), and the points take the opposite force back
//! through the same weights (Eq. 59, [`GridContact::correct_points`]). The
//! forces on the two bodies are equal and opposite node by node and the
//! map and its transpose use the same weights, so the total momentum is
//! conserved to round-off.
//!
//! The points map to the grid with the linear hat functions (their 2^D
//! surrounding nodes), whatever shape function the MPM body uses. Points
//! held in every direction (a membrane's fixed edge) make their grid nodes
//! a wall of infinite mass, so that the MPM body cannot push through them
//! (with the finite mapped mass the stick force would stop only the share
//! `m^r/(m^r + m^s)` of the approach); the wall takes that impulse.

use nalgebra::SVector;

use crate::grid::{Boundary, Grid, Reflect};
use crate::mpm::explicit::offset;
use crate::shape::{LinearHat, ParticleWeights};

mod run;
pub use run::{node_normals, ContactTimes, MembraneContactStep};

/// A surface normal under the mirror convention: its image across any
/// wall or symmetry face flips the component normal to the face (a
/// velocity's image on a no-slip face is −v instead).
#[derive(Debug, Clone, Copy)]
struct Direction<const D: usize>(SVector<f64, D>);

impl<const D: usize> Reflect<D> for Direction<D> {
    fn reflect(&self, axis: usize, _: Boundary) -> Self {
        Direction(self.0.reflect(axis, Boundary::Symmetry))
    }
    fn add(&self, other: &Self) -> Self {
        Direction(self.0 + other.0)
    }
    fn zero() -> Self {
        Direction(SVector::zeros())
    }
}

/// How the contact force acts tangentially.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactLaw {
    /// Stick: the two bodies share the node's velocity (Lian Eq. 55).
    Stick,
    /// Coulomb slip: the normal part of the stick force, and a tangential
    /// part at most `friction` times the normal one (Lian Eq. 58);
    /// `friction = 0` is free slip.
    Slip {
        /// Friction coefficient μ ≥ 0.
        friction: f64,
    },
}

/// Where a contact force may act.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum ContactDetection {
    /// Lian's rule: at every node both bodies reach where they approach
    /// (Eq. 52). Both bodies' shape functions reach a node up to a cell
    /// before they touch, so the force starts acting that much early.
    Approach,
    /// Lian's rule and a closing gap: the bodies also have to close, within
    /// the step, the gap between them measured along the node's normal —
    /// from the point body's surface at the node (its nodes' mass-weighted
    /// mean position, [`GridContact::centre`], plus their mean half
    /// thickness, [`GridContact::half_thickness`]) to the MPM body's nearest
    /// particle surface among the particles the node reaches (each
    /// particle's centre less its half extent along the normal,
    /// [`GridContact::surface`]). The gap at the end of the step is
    /// predicted with the trial velocities:
    /// `g − Δt (v̄^r − v̄^s)·n ≤ 0`. The default.
    #[default]
    Gap,
}

/// The point body as the contact sees it (Lian's FE nodes): positions at
/// the start of the step, lumped masses, trial velocities `v̄^{n+1/2}`
/// (Lian Eq. 46) and nodal normals (the sum of the adjoining elements'
/// area-weighted normals; any consistent orientation: the contact turns
/// each grid normal towards the MPM body).
#[derive(Debug, Clone, Copy)]
pub struct PointBody<'a, const D: usize> {
    /// Positions.
    pub x: &'a [SVector<f64, D>],
    /// Lumped masses.
    pub mass: &'a [f64],
    /// Trial velocities.
    pub v: &'a [SVector<f64, D>],
    /// Surface normals (not necessarily unit).
    pub normal: &'a [SVector<f64, D>],
    /// Points held in every direction (empty: none): a wall of infinite
    /// mass for the contact (see [`GridContact::resolve`]).
    pub held: &'a [bool],
    /// Each point's half thickness, the distance from its position to the
    /// body's surface along its normal (empty: zero, a surface of no
    /// thickness; only [`ContactDetection::Gap`] uses it).
    pub half_thickness: &'a [f64],
}

/// The MPM body's side of a contact step: its nodal mass, its trial nodal
/// velocity and acceleration after the internal force (corrected in place
/// by the contact force) and its nodal mass gradient (Lian Eq. 51,
/// [`crate::mpm::CoupledMpm::mass_gradient`]).
pub struct MpmNodes<'a, const D: usize> {
    /// Nodal mass `m_I^s`.
    pub mass: &'a [f64],
    /// Trial velocity `v̄_I^{s,n+1/2}` (corrected).
    pub velocity: &'a mut [SVector<f64, D>],
    /// Nodal acceleration (corrected by `f/m`, so a FLIP update sees the
    /// contact).
    pub accel: &'a mut [SVector<f64, D>],
    /// `Σ_p m_p ∇N_I(x_p)`: the MPM body's outward normal (unnormalised).
    pub mass_gradient: &'a [SVector<f64, D>],
    /// Nodes with less mass are empty.
    pub mass_floor: f64,
}

/// What one contact step did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactStats {
    /// Grid nodes both bodies reach.
    pub shared_nodes: usize,
    /// Nodes where the bodies approached and a force acted.
    pub contact_nodes: usize,
    /// Of those, the nodes where the Coulomb limit held the tangential
    /// force (slipping).
    pub slipping_nodes: usize,
    /// Total impulse on the point body, `Δt Σ_I f_I^r`.
    pub impulse: [f64; 3],
    /// `Δt Σ_I |f_I·n_I|`: the normal impulse's magnitude.
    pub normal_impulse: f64,
    /// `Δt Σ_I |f_I − (f_I·n_I) n_I|`: the tangential (friction) impulse's
    /// magnitude.
    pub tangential_impulse: f64,
    /// Energy the contact took from both bodies: minus its work on the
    /// particles, `Σ_p m_p δv_p·(v_p^n + v_p^{n+1})/2` (δv_p the contact's
    /// share of the nodal velocity change), and on the points, `Σ_k m_k
    /// δv_k·(v_k^{n−½} + v_k^{n+½})/2` — each with the mid-step velocity,
    /// which splits a body's kinetic-energy change exactly between the
    /// forces. Filled by [`MembraneContactStep`] (0 from
    /// [`GridContact::resolve`] alone). Stick and slip bring the bodies'
    /// normal velocities together at a node, an inelastic collision.
    pub dissipated: f64,
}

impl ContactStats {
    /// Adds another step's or membrane's counts and impulses.
    pub fn add(&mut self, o: &ContactStats) {
        self.shared_nodes += o.shared_nodes;
        self.contact_nodes += o.contact_nodes;
        self.slipping_nodes += o.slipping_nodes;
        self.normal_impulse += o.normal_impulse;
        self.tangential_impulse += o.tangential_impulse;
        self.dissipated += o.dissipated;
        for d in 0..3 {
            self.impulse[d] += o.impulse[d];
        }
    }
}

/// Grid buffers of the contact (no allocation once sized): the point
/// body's nodal mass, momentum and normal, the contact force on it, and
/// the list of nodes it touches (so every pass is over that list, not the
/// whole grid — a membrane is a surface in a volume of nodes).
#[derive(Debug, Clone)]
pub struct GridContact<const D: usize> {
    /// `m_I^r` (Lian Eq. 49).
    pub mass: Vec<f64>,
    /// `p̄_I^r`.
    pub momentum: Vec<SVector<f64, D>>,
    /// `Σ_K N_I(x_K) n_K`.
    pub normal: Vec<SVector<f64, D>>,
    /// Contact force on the point body `f_I^{r,c}` (Lian Eqs. 55, 58).
    pub force: Vec<SVector<f64, D>>,
    /// Nodes the point body reaches, in first-touch order.
    pub touched: Vec<usize>,
    /// Whether a held point reaches the node.
    pub held: Vec<bool>,
    /// The point body's position at the node, `Σ_K N_I(x_K) m_K x_K / m_I^r`
    /// (before the mirror folding at walls).
    pub centre: Vec<SVector<f64, D>>,
    /// The point body's half thickness at a node, mass-weighted like
    /// [`Self::centre`] (zero where the body gives none).
    pub half_thickness: Vec<f64>,
    /// The unit contact normal at a node both bodies reach, from the point
    /// body into the MPM body ([`Self::measure_gaps`]; zero elsewhere).
    pub unit_normal: Vec<SVector<f64, D>>,
    /// The MPM body's nearest surface along the node's normal,
    /// `min_p (x_p·n − Σ_d |n_d| l_{p,d})` over the particles the node
    /// reaches (`l_p` a particle's current half extents,
    /// [`Self::add_surface_point`]).
    pub surface: Vec<f64>,
    /// Each point's weights and first node from [`Self::map_points`], for
    /// the correction back (Eq. 59) at the same positions.
    weights: Vec<(ParticleWeights<D, 2>, usize)>,
    /// The grid's strides.
    strides: [usize; D],
}

/// The 2^D linear-hat weights of point `x` and the flat index of their
/// first node (`None` off the grid).
#[inline]
fn hat_weights<const D: usize>(
    grid: &Grid<D>,
    x: &SVector<f64, D>,
) -> Option<(ParticleWeights<D, 2>, usize)> {
    let xi = grid.to_grid_units(x);
    if (0..D).any(|d| !(xi[d] >= 0.0 && xi[d] <= grid.cells[d] as f64)) {
        return None;
    }
    let pw = ParticleWeights::<D, 2>::new(LinearHat, &xi, &SVector::zeros());
    Some((pw, grid.node_index(pw.base())))
}

impl<const D: usize> GridContact<D> {
    /// Buffers for `grid`.
    pub fn new(grid: &Grid<D>) -> Self {
        let n = grid.num_nodes();
        Self {
            mass: vec![0.0; n],
            momentum: vec![SVector::zeros(); n],
            normal: vec![SVector::zeros(); n],
            force: vec![SVector::zeros(); n],
            touched: Vec::with_capacity(n.min(4096)),
            held: vec![false; n],
            centre: vec![SVector::zeros(); n],
            half_thickness: vec![0.0; n],
            unit_normal: vec![SVector::zeros(); n],
            surface: vec![f64::INFINITY; n],
            weights: Vec::new(),
            strides: grid.strides(),
        }
    }

    /// Step 4(a): maps the point body's mass, trial momentum and normal to
    /// the grid (Lian Eq. 49), clearing only what the last step touched.
    ///
    /// # Errors
    /// The index of the first point off the grid.
    pub fn map_points(&mut self, grid: &Grid<D>, body: &PointBody<'_, D>) -> Result<(), usize> {
        for &i in &self.touched {
            self.mass[i] = 0.0;
            self.momentum[i] = SVector::zeros();
            self.normal[i] = SVector::zeros();
            self.force[i] = SVector::zeros();
            self.held[i] = false;
            self.centre[i] = SVector::zeros();
            self.half_thickness[i] = 0.0;
            self.unit_normal[i] = SVector::zeros();
        }
        self.touched.clear();
        self.weights.clear();
        let strides = self.strides;
        for k in 0..body.x.len() {
            let Some((pw, base)) = hat_weights(grid, &body.x[k]) else {
                return Err(k);
            };
            self.weights.push((pw, base));
            let (m, p, n) = (body.mass[k], body.v[k] * body.mass[k], body.normal[k]);
            let held = body.held.get(k).copied().unwrap_or(false);
            let half = body.half_thickness.get(k).copied().unwrap_or(0.0);
            pw.for_each(|o, w, _| {
                if w <= 0.0 {
                    return;
                }
                let i = base + offset(o, &strides);
                if self.mass[i] == 0.0 {
                    self.touched.push(i);
                }
                self.mass[i] += w * m;
                self.momentum[i] += p * w;
                self.normal[i] += n * w;
                self.centre[i] += body.x[k] * (w * m);
                self.half_thickness[i] += half * (w * m);
                self.held[i] |= held;
            });
        }
        for &i in &self.touched {
            self.centre[i] /= self.mass[i];
            self.half_thickness[i] /= self.mass[i];
        }
        self.mirror_at_walls(grid);
        Ok(())
    }

    /// The mirror-point convention of the MPM body ([`Grid::fold_ghosts`])
    /// for the points: a node on a fixed or symmetry face holds a point and
    /// its mirror image ([`Grid::fold_on_faces`]: the mass doubled, the
    /// mirrored component of the momentum and of the normal cancelled). Without it the MPM body's
    /// folded node on a face weighed (and pushed) twice against the points:
    /// in Lian's gas expansion, one cell deep between two symmetry planes,
    /// the membrane carried twice the gas pressure (tension 2.1–2.3 p r at
    /// rest) and turned twice as sharply at its ends on the x and y
    /// symmetry planes (curvature 1.9 against 1.0 between).
    fn mirror_at_walls(&mut self, grid: &Grid<D>) {
        for &i in &self.touched {
            self.mass[i] = grid.fold_on_faces(i, self.mass[i]);
            self.momentum[i] = grid.fold_on_faces(i, self.momentum[i]);
            // A direction's mirror image flips its component across the
            // face on a no-slip face too (the velocity's −v rule would
            // cancel the normal there).
            self.normal[i] = grid.fold_on_faces(i, Direction(self.normal[i])).0;
        }
    }

    /// The unit normal at node `i` if both bodies reach it: the point
    /// body's mapped normal turned towards the MPM body, against the MPM
    /// body's outward normal (its mass gradient, Lian Eq. 51).
    fn oriented_normal(&self, i: usize, s: &MpmNodes<'_, D>) -> Option<SVector<f64, D>> {
        if s.mass[i] <= s.mass_floor || self.mass[i] <= 0.0 {
            return None;
        }
        let nn = self.normal[i].norm();
        if nn <= 0.0 {
            return None;
        }
        let n = self.normal[i] / nn;
        // `Σ m_p ∇N_I(x_p)` points out of the MPM body: n must point the
        // other way, from r into s.
        Some(if n.dot(&s.mass_gradient[i]) > 0.0 {
            -n
        } else {
            n
        })
    }

    /// Starts the gap measurement of [`ContactDetection::Gap`] (after
    /// [`Self::map_points`]): the normal of every node both bodies reach,
    /// and an open gap. Then [`Self::add_surface_point`] for every particle
    /// and node of its stencil.
    /// Returns the number of such nodes (none: no particle pass is needed).
    pub fn measure_gaps(&mut self, s: &MpmNodes<'_, D>) -> usize {
        let mut shared = 0;
        for k in 0..self.touched.len() {
            let i = self.touched[k];
            let n = self.oriented_normal(i, s);
            shared += usize::from(n.is_some());
            self.unit_normal[i] = n.unwrap_or_else(SVector::zeros);
            self.surface[i] = f64::INFINITY;
        }
        shared
    }

    /// A particle at `x` with half extents `half` reaches node `i`: the MPM
    /// body's surface there is at most `x·n − Σ_d |n_d| half_d` along the
    /// node's normal.
    #[inline]
    pub fn add_surface_point(&mut self, i: usize, x: &SVector<f64, D>, half: &SVector<f64, D>) {
        if self.mass[i] <= 0.0 {
            return;
        }
        let n = self.unit_normal[i];
        if n == SVector::<f64, D>::zeros() {
            return;
        }
        let reach = n
            .iter()
            .zip(half.iter())
            .map(|(a, b)| a.abs() * b)
            .sum::<f64>();
        let d = x.dot(&n) - reach;
        if d < self.surface[i] {
            self.surface[i] = d;
        }
    }

    /// The gap between the bodies along the normal at node `i`
    /// ([`Self::measure_gaps`] first): the MPM body's surface less the
    /// point body's (its position plus its half thickness).
    pub fn gap(&self, i: usize) -> f64 {
        self.surface[i] - self.centre[i].dot(&self.unit_normal[i]) - self.half_thickness[i]
    }

    /// Steps 4(b)–(d) on the grid: at every node both bodies reach, the
    /// normal is the point body's mapped normal turned towards the MPM
    /// body (against the MPM body's outward normal, its mass gradient); where the bodies
    /// approach (Lian Eq. 52, `(m^s p̄^r − m^r p̄^s)·n > 0`) the contact
    /// force on the point body is the stick force (Lian Eq. 55, derived
    /// from the common velocity `(p̄^r + p̄^s)/(m^r + m^s)`):
    ///
    /// `f^r = (m^r p̄^s − m^s p̄^r) / ((m^r + m^s) Δt)`,
    ///
    /// or, for Coulomb slip, its normal part `f_n = f^r·n` plus its
    /// tangential part capped at `μ |f_n|` (Lian Eqs. 56–58). The MPM body
    /// takes `−f^r` (Eq. 53) in its velocity and acceleration. Separating
    /// bodies feel nothing; with [`ContactDetection::Gap`] (after
    /// [`Self::measure_gaps`]) neither do bodies that stay apart through
    /// the step (its normals are `measure_gaps`'s).
    pub fn resolve(
        &mut self,
        s: &mut MpmNodes<'_, D>,
        law: ContactLaw,
        detection: ContactDetection,
        dt: f64,
    ) -> ContactStats {
        let mut stats = ContactStats::default();
        let mut impulse = SVector::<f64, D>::zeros();
        for &i in &self.touched {
            let (mr, ms) = (self.mass[i], s.mass[i]);
            if ms <= s.mass_floor || mr <= 0.0 {
                continue;
            }
            stats.shared_nodes += 1;
            // The gap check has the normal already (`measure_gaps`).
            let n = match detection {
                ContactDetection::Gap => {
                    Some(self.unit_normal[i]).filter(|n| *n != SVector::<f64, D>::zeros())
                }
                ContactDetection::Approach => self.oriented_normal(i, s),
            };
            let Some(n) = n else {
                continue;
            };
            let pr = self.momentum[i];
            let ps = s.velocity[i] * ms;
            // Lian Eq. 52: r moves towards s along n.
            if (pr * ms - ps * mr).dot(&n) <= 0.0 {
                continue;
            }
            if detection == ContactDetection::Gap {
                let closing = (pr / mr - ps / ms).dot(&n);
                if self.gap(i) - dt * closing > 0.0 {
                    continue;
                }
            }
            // Lian Eq. 55; where a held point reaches the node the point
            // body is a wall (m^r → ∞): the MPM body takes its velocity,
            // f^r = (p̄^s − m^s v̄^r)/Δt.
            let stick = if self.held[i] {
                (ps - pr * (ms / mr)) / dt
            } else {
                (ps * mr - pr * ms) / ((mr + ms) * dt)
            };
            let f = match law {
                ContactLaw::Stick => stick,
                ContactLaw::Slip { friction } => {
                    // Lian Eqs. 56–58: f_n ≤ 0 pushes r back, away from s.
                    let fn_ = stick.dot(&n);
                    let tangential = stick - n * fn_;
                    let ft = tangential.norm();
                    let cap = friction * fn_.abs();
                    if ft > cap {
                        stats.slipping_nodes += 1;
                        n * fn_ + tangential * (cap / ft)
                    } else {
                        stick
                    }
                }
            };
            stats.contact_nodes += 1;
            let f_n = f.dot(&n);
            stats.normal_impulse += f_n.abs() * dt;
            stats.tangential_impulse += (f - n * f_n).norm() * dt;
            self.force[i] = f;
            impulse += f * dt;
            // Lian Eq. 53 for the MPM body: −f.
            let a = f / ms;
            s.velocity[i] -= a * dt;
            s.accel[i] -= a;
        }
        for d in 0..D {
            stats.impulse[d] = impulse[d];
        }
        stats
    }

    /// Step 4(d) for the points: `v_K = v̄_K + Δt Σ_I N_I(x_K) f_I^r / m_I^r`
    /// (Lian Eq. 59), with the weights of the last [`Self::map_points`] (the
    /// positions the points were mapped from; `v` in the same order).
    pub fn correct_points(&self, dt: f64, v: &mut [SVector<f64, D>]) {
        let strides = self.strides;
        for ((pw, base), vk) in self.weights.iter().zip(v.iter_mut()) {
            pw.for_each(|o, w, _| {
                let i = base + offset(o, &strides);
                if w > 0.0 && self.mass[i] > 0.0 {
                    *vk += self.force[i] * (w * dt / self.mass[i]);
                }
            });
        }
    }
}
