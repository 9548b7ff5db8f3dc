//! Zhang's multi-velocity, multi-pressure multiphase MPM (Zhang, Zou, Ma,
//! VanderHeyden, Giguere, LA-UR-07-5202, Secs. 2–3; the CartaBlanca
//! method): every material — solids and the gas alike — is a phase with its
//! own material points, its own velocity field on the grid, its own volume
//! fraction and its own stress.
//!
//! One explicit step (update-stress-last):
//!
//! 1. Per phase: mass and momentum to the nodes (Eq. 9), velocity `ū_il`.
//! 2. Per phase: nodal volume fraction `θ_il = Σ_p v_p S_l / V_l` (Eq. 13);
//!    `Σ_j θ_j κ_j` on the nodes; the pressure `p_g,l = Σ v κ p S_l / Σ v κ
//!    S_l` over all points (κ = 1/(ρc²)): the gas pressure wherever there
//!    is gas (its κ dwarfs a solid's), the solids' mean pressure elsewhere.
//! 3. Per phase, the momentum equation (Eq. 4 in the MPM form Eq. 8): the
//!    nodal force `−Σ_p v_p (σ_p + p_g,l I)·∇S_l(x_p) + m g`, i.e. Eq. 8's
//!    `−θ_i ∇p_g V_l` and the gas pressure of the stress difference
//!    combined at the node: `∫ S_l [−θ_i ∇p_g + ∇·(θ_i p_g I)] = ∫ S_l p_g
//!    ∇θ_i ≈ −p_g,l ∫ θ_i ∇S_l`. A uniform pressure in gas and solids then
//!    gives no force at all. Summed over the phases this leaves
//!    `−p_g,l G_l`, `G_l = Σ_i Σ_p v_p ∇S_l` (≈ −V∇Σθ: the sampling error
//!    of Σθ, Eq. 14), which conserves momentum only where p_g is uniform;
//!    the mixture therefore sees one reference pressure on it, `−p_ref
//!    G_l`, and the excess `(p_g,l − p_ref) G_l` is handed back to the
//!    phases by volume share, so that momentum is conserved exactly.
//! 4. The phase interaction `f_i = Σ_j K_ij (ū_j − ū_i)` (Eq. 5) on every
//!    node, pointwise implicit (the exchange solver of
//!    [`crate::ice::exchange`], conservative and stable for any K).
//! 5. Per phase, at its points: the volume rate `α_i ∇·ū_i + B_i` (Eqs.
//!    1–2) with the chosen volume-fraction constraint ([`closure`]; its
//!    interface part is built on the nodes from the same volume gradients
//!    as the force of step 3, so the pressure work balances), which
//!    replaces `∇·ū_i` in the point's velocity gradient (the deviatoric
//!    part, Eq. 3, is kept); the stress update; FLIP velocity and position
//!    (Eqs. 10–11).
//!
//! Eq. 12 (the nodal velocity from the moved points) is the next step's 1.

pub mod closure;

use nalgebra::SVector;

use crate::error::{Error, FailureSite, Result};
use crate::grid::Grid;
use crate::ice::exchange::exchange_momentum;
use crate::material::SolidMaterial;
use crate::mpm::explicit::stable_dt_stiffened;
use crate::mpm::{BodyForce, CoupledMpm, ExplicitParams, GridState, Particles, StepScratch};
use crate::stepper::{Energies, TimeControl};

pub use closure::{Constraint, MAX_PHASES};

/// Model settings (scene table `[multiphase]`).
#[derive(Debug, Clone, PartialEq)]
pub struct MultiphaseParams {
    /// How the volume-fraction constraint sets the volume rates.
    pub constraint: Constraint,
    /// Drag coefficients K_ij [kg/(m³ s)] (Eq. 5), row-major M × M over the
    /// phases, symmetric with a zero diagonal.
    pub drag: Vec<f64>,
    /// α_i of Eq. 1 per phase, in [0, 1].
    pub alpha: Vec<f64>,
    /// The most `κ_p / Σθκ` a point's share of the volume mismatch (and
    /// its stiffening) may reach: `1 / multiphase.min_fraction`, infinite
    /// for Zhang's closure exactly.
    pub max_share: f64,
}

/// One phase: the points of one material and its grid fields.
#[derive(Debug, Clone)]
pub struct Phase<const D: usize> {
    /// Index of the phase's material in [`MultiphaseRun::materials`].
    pub material: usize,
    /// Its material points (`material` field = the index above).
    pub particles: Particles<D>,
    /// Nodal mass, momentum, velocities and force.
    pub gs: GridState<D>,
    /// Nodal volume fraction θ_il (Eq. 13), ghosts mirrored.
    pub theta: Vec<f64>,
    scratch: StepScratch<D>,
    grad: Vec<SVector<f64, D>>,
    /// Per point: v_p κ_p, then v_p p_p, then the extra volume rate.
    point: Vec<f64>,
    /// Per point, `max(1, κ_p / Σθκ)` at the last step's start: the square
    /// of the factor by which the closure raises the point's sound speed.
    pub stiffening: Vec<f64>,
    /// Per node, the velocity change Δu_i the phase interaction (Eq. 5)
    /// made this step, ghosts mirrored.
    drag_dv: Vec<SVector<f64, D>>,
    /// Per point, the kinetic energy the phase interaction took from it
    /// this step.
    drag_heat: Vec<f64>,
}

impl<const D: usize> Phase<D> {
    /// A phase of `particles` (all of material `material`) on a grid of
    /// `nodes` nodes.
    pub fn new(material: usize, particles: Particles<D>, nodes: usize) -> Self {
        Self {
            material,
            particles,
            gs: GridState::new(nodes),
            theta: vec![0.0; nodes],
            scratch: StepScratch::default(),
            grad: vec![SVector::zeros(); nodes],
            point: Vec::new(),
            stiffening: Vec::new(),
            drag_dv: vec![SVector::zeros(); nodes],
            drag_heat: Vec::new(),
        }
    }
}

/// A multiphase run: grid, materials, phases and buffers.
pub struct MultiphaseRun<const D: usize> {
    /// Background grid.
    pub grid: Grid<D>,
    /// Every material of the scene on points, indexed by `Phase::material`.
    pub materials: Vec<SolidMaterial>,
    /// One phase per material.
    pub phases: Vec<Phase<D>>,
    /// Which phase is the gas (its pressure is `p_g`), if any.
    pub gas: Option<usize>,
    /// Shape function, update scheme (USL), mass floor.
    pub params: ExplicitParams,
    /// Model settings.
    pub model: MultiphaseParams,
    /// Body force per unit mass.
    pub body: Option<Box<dyn BodyForce<D> + Send + Sync>>,
    /// Uniform gravity used for the potential energy (zero if none).
    pub gravity: SVector<f64, D>,
    /// Time step control.
    pub time: TimeControl,
    /// Current time.
    pub t: f64,
    /// Completed steps.
    pub steps: u64,
    /// Nodal gas pressure p_g,l, ghosts mirrored.
    pub gas_pressure: Vec<f64>,
    /// Kinetic energy the phase interaction (Eq. 5) has taken from the
    /// points since t = 0: friction heat, counted with the stored energy in
    /// [`Self::energies`] (no phase's temperature takes it). Each step it is
    /// Σ_p ½ m_p (|v_p' − δ_p|² − |v_p'|²), v_p' the point's new velocity
    /// and δ_p = Σ_i S_ip Δu_i the interaction's part of it.
    pub drag_heat: f64,
    /// Kinetic energy the phase interaction has taken from the nodal
    /// velocities since t = 0, Σ ½ m_i (|u_i|² − |u_i'|²) (Eq. 5's
    /// dissipation on the grid). It exceeds [`Self::drag_heat`] by what
    /// FLIP keeps on the points: the points see Δu_i only through S_ip, and
    /// a change that varies from node to node (a light phase braked hard on
    /// a few mixed nodes) leaves part of its kinetic energy on them. Booked
    /// instead of `drag_heat`, that part counted as heat while the points
    /// kept it: +1.4 % of the rod's kinetic energy by 20 µs in
    /// `cases/zhang_rod.toml` at R/2.
    pub drag_dissipation: f64,
    /// Nodal Σ_j θ_j κ_j, ghosts mirrored.
    compressibility: Vec<f64>,
    /// Nodal volume V_l: the cell volume, or in r–z the volume per radian
    /// `∫ S_l r dr dz` ([`node_volumes`]).
    node_volume: Vec<f64>,
    node_tmp: Vec<f64>,
    mix_num: Vec<f64>,
    /// Nodal interface rate per unit compressibility, Y_l / Σθκ_l.
    interface: Vec<f64>,
    force: Vec<SVector<f64, D>>,
    /// Per node, `(p_g − p_ref) G / Σθ`: the mixture's excess pressure
    /// force on the sampling error of Σθ per unit volume fraction (see
    /// `advance`).
    mixture: Vec<SVector<f64, D>>,
    /// `p_ref = Σ v κ p / Σ v κ` over every point at the step's start: the
    /// pressure the mixture's Σθ sampling error sees.
    reference_pressure: f64,
}

/// Compressibility κ = 1/(ρ c²) of a point: a gas point's adiabatic one from
/// its EOS, a solid's 1/K (bulk modulus).
fn compressibility<const D: usize>(m: &SolidMaterial, p: &Particles<D>, i: usize) -> f64 {
    match m.gas() {
        Some(g) => {
            let rho = p.mass[i] / p.vol[i];
            let e = p.work_of(i) * p.vol0[i] / p.mass[i];
            let c = g.sound_speed(rho, e);
            1.0 / (rho * c * c)
        }
        None => 1.0 / m.elastic.bulk(),
    }
}

impl<const D: usize> MultiphaseRun<D> {
    /// A run at t = 0; `phases[k].material` indexes `materials`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        grid: Grid<D>,
        materials: Vec<SolidMaterial>,
        phases: Vec<Phase<D>>,
        gas: Option<usize>,
        params: ExplicitParams,
        model: MultiphaseParams,
        time: TimeControl,
    ) -> Self {
        let n = grid.num_nodes();
        let node_volume = node_volumes(&grid, params.shape);
        Self {
            grid,
            materials,
            phases,
            gas,
            params,
            model,
            body: None,
            gravity: SVector::zeros(),
            time,
            t: 0.0,
            steps: 0,
            gas_pressure: vec![0.0; n],
            drag_heat: 0.0,
            drag_dissipation: 0.0,
            compressibility: vec![0.0; n],
            node_volume,
            node_tmp: vec![0.0; n],
            mix_num: vec![0.0; n],
            interface: vec![0.0; n],
            force: vec![SVector::zeros(); n],
            mixture: vec![SVector::zeros(); n],
            reference_pressure: 0.0,
        }
    }

    /// The stable explicit step: the smallest over the points of every
    /// phase of `h / (c + |v|)` (a gas point's own limit,
    /// [`SolidMaterial::dt_limit`]), with `c` raised by the closure's
    /// stiffening `√s_p`.
    pub fn stable_dt(&self) -> f64 {
        self.phases
            .iter()
            .map(|ph| {
                stable_dt_stiffened(
                    &self.grid,
                    &self.materials,
                    &ph.particles,
                    self.time.cfl,
                    &ph.stiffening,
                )
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Kinetic, stored (strain, gas internal and the drag's friction heat
    /// [`Self::drag_heat`]) and potential energies of all phases.
    pub fn energies(&self) -> Energies {
        let mut e = Energies {
            strain: self.drag_heat,
            ..Default::default()
        };
        for ph in &self.phases {
            e.kinetic += ph.particles.kinetic_energy();
            e.strain += ph.particles.strain_energy(&self.materials);
            e.potential += ph.particles.potential_energy(&self.gravity);
        }
        e
    }

    fn fail(&self, what: String) -> Error {
        Error::Numerical {
            site: FailureSite {
                step: self.steps,
                time: self.t,
                particle: None,
                cell: None,
            },
            what,
        }
    }

    /// Advances every phase by one explicit step of `dt`.
    ///
    /// # Errors
    /// A particle off the grid or inverted (naming the point and its
    /// phase), or a non-finite gas pressure (naming the node).
    pub fn step(&mut self, dt: f64) -> Result<()> {
        self.nodes(dt)?;
        self.advance(dt)
    }

    /// Steps 1–2 at the current positions: the nodal fields of every phase,
    /// the gas pressure, and each point's stiffening (see
    /// [`Phase::stiffening`]). Also called once when the run is built, so
    /// that the first [`Self::stable_dt`] knows it.
    ///
    /// # Errors
    /// A particle off the grid, or a non-finite gas pressure.
    pub fn nodes(&mut self, dt: f64) -> Result<()> {
        let Self {
            grid,
            materials,
            phases,
            params,
            model,
            body,
            t,
            steps,
            gas_pressure,
            compressibility: comp,
            node_volume,
            node_tmp,
            mix_num,
            reference_pressure,
            ..
        } = self;
        let mpm = CoupledMpm {
            grid,
            materials,
            params,
            body: body.as_deref().map(|b| b as &dyn BodyForce<D>),
            t: *t,
            dt,
            step: *steps,
        };
        let name = |ph: &Phase<D>, e: Error| name_phase(e, &materials[ph.material].name);
        // 1–2: mass, momentum, volume fractions, compressibility, and the
        // pressure sums Σ S v p of the gas and of all phases.
        comp.iter_mut().for_each(|c| *c = 0.0);
        mix_num.iter_mut().for_each(|c| *c = 0.0);
        let (mut sum_vk, mut sum_vkp) = (0.0, 0.0);
        for ph in phases.iter_mut() {
            mpm.p2g(&ph.particles, &mut ph.gs, &mut ph.scratch)
                .map_err(|e| name(ph, e))?;
            mpm.p2g_sum(&ph.particles, &ph.particles.vol, &ph.scratch, &mut ph.theta);
            ph.theta
                .iter_mut()
                .zip(node_volume.iter())
                .for_each(|(q, v)| *q /= v);
            grid.mirror_ghosts(&mut ph.theta);
            let m = &materials[ph.material];
            let p = &ph.particles;
            ph.point.clear();
            ph.point
                .extend((0..p.len()).map(|i| p.vol[i] * compressibility(m, p, i)));
            mpm.p2g_sum(p, &ph.point, &ph.scratch, node_tmp);
            comp.iter_mut()
                .zip(node_tmp.iter().zip(node_volume.iter()))
                .for_each(|(c, (q, v))| *c += q / v);
            sum_vk += ph.point.iter().sum::<f64>();
            for (q, s) in ph.point.iter_mut().zip(p.stress.iter()) {
                *q *= -s.trace() / 3.0;
            }
            sum_vkp += ph.point.iter().sum::<f64>();
            mpm.p2g_sum(p, &ph.point, &ph.scratch, node_tmp);
            mix_num
                .iter_mut()
                .zip(node_tmp.iter())
                .for_each(|(a, b)| *a += b);
        }
        grid.mirror_ghosts(comp);
        *reference_pressure = if sum_vk > 0.0 { sum_vkp / sum_vk } else { 0.0 };
        // The pressure p_g on a node: the compressibility-weighted mean of
        // the points' pressures, Σ S v κ p / Σ S v κ. Where there is gas it
        // is the gas pressure (κ of air is 1e4–1e6 times a solid's), with
        // no floor however little gas the node holds (a floor left the gas
        // force unbalanced on a node the gas barely reaches: 4e9 m/s² in
        // the block test); where there is none, the solids' mean pressure,
        // which only completes the stress difference σ + p_g I (p_g
        // cancels in the continuous equations where θ is uniform). This
        // weighting is what makes the closure's interface rate do exactly
        // the work of the pressure force (see `closure::node_rate`).
        for l in 0..gas_pressure.len() {
            gas_pressure[l] = if comp[l] > 0.0 {
                mix_num[l] / (node_volume[l] * comp[l])
            } else {
                0.0
            };
            if !gas_pressure[l].is_finite() {
                return Err(gas_pressure_failure(grid, materials, phases, l, *steps, *t));
            }
        }
        grid.mirror_ghosts(gas_pressure);
        // The closure gives a point the volume rate κ_p X / Σθκ: where the
        // gas is a small part of the mixture at a gas point, its pressure
        // responds as if its bulk modulus were K / θ_g, and the explicit
        // step must resolve that wave (c √(κ_p / Σθκ)); without it the
        // block test at rest grew round-off by 40× per 0.02 s at CFL 0.4.
        // `max_share` caps it with the share itself (`min_fraction`).
        let cap = model.max_share;
        for ph in phases.iter_mut() {
            let m = &materials[ph.material];
            let mut s = std::mem::take(&mut ph.stiffening);
            s.resize(ph.particles.len(), 1.0);
            let p = &ph.particles;
            let comp = &*comp;
            mpm.gather(
                p,
                &ph.scratch,
                &mut s,
                |c: &mut f64, l, w, _| *c += w * comp[l],
                |i, c| {
                    if c > 0.0 {
                        (compressibility(m, p, i) / c).clamp(1.0, cap.max(1.0))
                    } else {
                        1.0
                    }
                },
            );
            ph.stiffening = s;
        }
        Ok(())
    }

    /// Steps 3–5 after [`Self::nodes`].
    fn advance(&mut self, dt: f64) -> Result<()> {
        let Self {
            grid,
            materials,
            phases,
            params,
            model,
            body,
            t,
            steps,
            gas_pressure,
            drag_heat,
            drag_dissipation,
            compressibility: comp,
            node_volume,
            interface,
            force,
            mixture,
            reference_pressure,
            ..
        } = self;
        let mpm = CoupledMpm {
            grid,
            materials,
            params,
            body: body.as_deref().map(|b| b as &dyn BodyForce<D>),
            t: *t,
            dt,
            step: *steps,
        };
        let name = |ph: &Phase<D>, e: Error| name_phase(e, &materials[ph.material].name);
        // 3: the momentum equation per phase (Eq. 8).
        for ph in phases.iter_mut() {
            mpm.volume_gradient(&ph.particles, &ph.scratch, &mut ph.grad);
            grid.fold_ghosts(&mut ph.grad);
        }
        // Summed over the phases, the force −p_g,l g_il leaves the mixture
        // −p_g,l G_l with G_l = Σ_i g_il ≈ −V ∇Σθ, the gradient of the
        // point-sampled Σθ (zero in the continuum, where Σθ = 1: Zhang's
        // −Σθ∇p_g + ∇·(Σθ p_g I) = p_g ∇Σθ). Σ_l G_l = 0, but Σ_l p_g,l G_l
        // is not where p_g varies: at a metal–metal interface at tens of
        // GPa it made or destroyed a tenth of the rod's momentum. The
        // mixture sees instead the one pressure p_ref on that sampling
        // error, −p_ref G_l (summing to zero over the nodes: momentum is
        // conserved), and the difference (p_g,l − p_ref) G_l goes back to
        // the phases by volume share θ_il/Σθ_l: phase i is then pushed by
        // p_g,l across the mean of its own and its neighbours' volume
        // gradients, g_il − (θ_il/Σθ_l) G_l, which sum to zero over the
        // phases (action and reaction), plus its share of −p_ref G_l. A
        // uniform pressure p_g = p_ref is untouched (the block test).
        // Shares by mass instead gave the same momentum and, within a few
        // tenths, the same shock and energy errors.
        let p_ref = *reference_pressure;
        for (l, mx) in mixture.iter_mut().enumerate() {
            let (mut g, mut share) = (SVector::<f64, D>::zeros(), 0.0);
            for ph in phases.iter() {
                g += ph.grad[l];
                share += ph.theta[l];
            }
            *mx = if share > 0.0 {
                g * ((gas_pressure[l] - p_ref) / share)
            } else {
                SVector::zeros()
            };
        }
        for ph in phases.iter_mut() {
            for l in 0..force.len() {
                force[l] = -ph.grad[l] * gas_pressure[l] + mixture[l] * ph.theta[l];
            }
            mpm.solve(&mut ph.particles, &mut ph.gs, &mut ph.scratch, None, force)
                .map_err(|e| name(ph, e))?;
        }
        // 4: the phase interaction (Eq. 5), pointwise implicit.
        let drag_on = exchange(phases, &model.drag, dt, node_volume, params.mass_floor)
            .map(|d| *drag_dissipation += d)
            .is_some();
        // FLIP velocities (Eq. 10), then the nodal velocities remapped from
        // them (MUSL): the closure and the stress read those.
        for ph in phases.iter_mut() {
            grid.mirror_ghosts(&mut ph.gs.velocity_new);
            grid.mirror_ghosts(&mut ph.gs.accel);
            if drag_on {
                grid.mirror_ghosts(&mut ph.drag_dv);
                *drag_heat += points_drag_heat(&mpm, ph, dt);
            }
            mpm.musl_velocity(&mut ph.particles, &ph.gs, &mut ph.scratch)
                .map_err(|e| name(ph, e))?;
            mpm.musl_remap(&ph.particles, &mut ph.gs, &mut ph.scratch);
            grid.mirror_ghosts(&mut ph.gs.mass);
        }
        // 5: volume rates (Eqs. 1–2 with the constraint), stress, G2P.
        let n = phases.len();
        {
            let mut u = [SVector::<f64, D>::zeros(); MAX_PHASES];
            let mut th = [0.0; MAX_PHASES];
            let mut g = [SVector::<f64, D>::zeros(); MAX_PHASES];
            for l in 0..interface.len() {
                let mut theta_sum = 0.0;
                for (j, ph) in phases.iter().enumerate() {
                    u[j] = ph.gs.velocity[l];
                    th[j] = ph.theta[l];
                    g[j] = ph.grad[l];
                    theta_sum += ph.theta[l];
                }
                interface[l] = if comp[l] > 0.0 {
                    closure::node_rate(
                        &u[..n],
                        &th[..n],
                        &g[..n],
                        theta_sum,
                        node_volume[l],
                        model.constraint,
                        dt,
                    ) / comp[l]
                } else {
                    0.0
                };
            }
            grid.mirror_ghosts(interface);
        }
        let dispersed = model.alpha.iter().any(|&a| a < 1.0);
        let max_share = model.max_share;
        let axi = grid.axisymmetric;
        for i in 0..n {
            let mut rate = std::mem::take(&mut phases[i].point);
            rate.resize(phases[i].particles.len(), 0.0);
            {
                let ph = &phases[i];
                let alpha = &model.alpha;
                let own = &ph.gs.velocity;
                let (comp, phases_ref) = (&*comp, &*phases);
                let m = &materials[ph.material];
                let p = &ph.particles;
                let interface = &*interface;
                mpm.gather(
                    p,
                    &ph.scratch,
                    &mut rate,
                    |s: &mut closure::Stencil<D>, l, w, g| {
                        s.node_share += w * interface[l];
                        s.compressibility += w * comp[l];
                        s.div_own += own[l].dot(g);
                        s.radial_own += w * own[l][0];
                        if !dispersed {
                            return;
                        }
                        for (j, q) in phases_ref.iter().enumerate() {
                            let mj = q.gs.mass[l];
                            if mj <= 0.0 {
                                continue;
                            }
                            let u = q.gs.velocity[l];
                            s.mass[j] += w * mj;
                            s.momentum[j] += u * (w * mj);
                            s.grad_theta[j] += g * q.theta[l];
                            s.div_theta_u[j] += q.theta[l] * u.dot(g);
                            s.radial_theta_u[j] += w * q.theta[l] * u[0];
                            s.theta_sum += w * q.theta[l];
                        }
                    },
                    |pi, mut s| {
                        if axi {
                            // r–z: the divergences' hoop parts u_r / r.
                            s.add_hoop(p.x[pi][0]);
                        }
                        let x = closure::dispersed(&s, &alpha[..n]);
                        let kappa = compressibility(m, p, pi);
                        closure::extra_rate(&s, alpha[i], kappa, x, max_share)
                    },
                );
            }
            let ph = &mut phases[i];
            let r = mpm.musl_stress(&mut ph.particles, &ph.gs, &mut ph.scratch, &rate);
            ph.point = rate;
            r.map_err(|e| name(ph, e))?;
            if grid.any_periodic() {
                ph.particles.x.iter_mut().for_each(|x| grid.wrap(x));
            }
        }
        *t += dt;
        *steps += 1;
        Ok(())
    }

    /// Wall time per phase of the MPM step, summed over the phases.
    pub fn phase_times(&self) -> crate::mpm::PhaseTimes {
        let mut t = crate::mpm::PhaseTimes::default();
        for ph in &self.phases {
            let s = ph.scratch.times;
            t.bin_s += s.bin_s;
            t.p2g_s += s.p2g_s;
            t.grid_s += s.grid_s;
            t.g2p_s += s.g2p_s;
        }
        t
    }

    /// All phases' points in one set (outputs), phase after phase.
    pub fn all_particles(&self) -> Particles<D> {
        let mut all = Particles::<D>::default();
        for ph in &self.phases {
            all.append(&ph.particles);
        }
        all
    }

    /// Phase of the run whose material is named `name`.
    pub fn phase_of(&self, name: &str) -> Option<usize> {
        self.phases
            .iter()
            .position(|ph| self.materials[ph.material].name == name)
    }

    /// A failure naming `what` at the current step (for callers that check
    /// the state between steps).
    pub fn failure(&self, what: impl Into<String>) -> Error {
        self.fail(what.into())
    }
}

/// The failure of a non-finite gas pressure on node `l`: names the node
/// and the first point (its index within its phase, and the phase's
/// material) whose pressure or compressibility is not finite, the source of
/// the node's value; where no point is (the nodal sums overflowed), the
/// phases whose pressures meet there.
fn gas_pressure_failure<const D: usize>(
    grid: &Grid<D>,
    materials: &[SolidMaterial],
    phases: &[Phase<D>],
    l: usize,
    step: u64,
    time: f64,
) -> Error {
    let node = format!("gas pressure not finite on node {:?}", grid.node_coords(l));
    let culprit = phases.iter().find_map(|ph| {
        let m = &materials[ph.material];
        let p = &ph.particles;
        (0..p.len())
            .find(|&i| {
                let k = p.vol[i] * compressibility(m, p, i);
                !(k.is_finite() && (k * p.stress.get(i).trace()).is_finite())
            })
            .map(|i| (i, m.name.as_str()))
    });
    let site = |particle| FailureSite {
        step,
        time,
        particle,
        cell: Some(l),
    };
    match culprit {
        Some((i, name)) => name_phase(
            Error::Numerical {
                site: site(Some(i)),
                what: format!(
                    "{node}: the pressure or compressibility of point {i} of `{name}` is not \
                     finite"
                ),
            },
            name,
        ),
        None => Error::Numerical {
            site: site(None),
            what: format!(
                "{node} (phase pressures of {})",
                materials
                    .iter()
                    .map(|m| format!("`{}`", m.name))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        },
    }
}

/// Adds the phase's material name to a numerical failure.
fn name_phase(e: Error, name: &str) -> Error {
    match e {
        Error::Numerical { site, what } => Error::Numerical {
            site,
            what: format!(
                "{what} (material `{name}`; the particle index counts its phase's points)"
            ),
        },
        e => e,
    }
}

/// Eq. 5 on every node: `m_i du_i = Δt V Σ_j K_ij (u_j − u_i)`, implicit in
/// the new velocities, among the phases with mass on the node; the change
/// goes into `velocity_new`, the acceleration and each phase's `drag_dv`.
/// Returns the nodal kinetic energy it dissipates, Σ ½ m (|u|² − |u'|²) ≥
/// 0, or `None` where no pair has a drag (nothing changed).
fn exchange<const D: usize>(
    phases: &mut [Phase<D>],
    drag: &[f64],
    dt: f64,
    node_volume: &[f64],
    floor: f64,
) -> Option<f64> {
    let n = phases.len();
    if n < 2 || drag.iter().all(|&k| k == 0.0) {
        return None;
    }
    for ph in phases.iter_mut() {
        ph.drag_dv.fill(SVector::zeros());
    }
    let mut heat = 0.0;
    let nodes = phases[0].gs.mass.len();
    let mut k = [0.0; MAX_PHASES * MAX_PHASES];
    let mut idx = [0usize; MAX_PHASES];
    let ones = [1.0; MAX_PHASES];
    let mut sp = [0.0; MAX_PHASES];
    let mut w = [0.0; MAX_PHASES];
    let mut vel = [SVector::<f64, D>::zeros(); MAX_PHASES];
    for l in 0..nodes {
        let mut c = 0;
        for (j, ph) in phases.iter().enumerate() {
            let m = ph.gs.mass[l];
            if m > floor {
                idx[c] = j;
                w[c] = m;
                sp[c] = node_volume[l] / m;
                vel[c] = ph.gs.velocity_new[l];
                c += 1;
            }
        }
        if c < 2 {
            continue;
        }
        for r in 0..c {
            for s in 0..c {
                k[r * c + s] = drag[idx[r] * n + idx[s]];
            }
        }
        exchange_momentum(
            &k[..c * c],
            dt,
            &ones[..c],
            &sp[..c],
            &w[..c],
            &mut vel[..c],
        );
        for r in 0..c {
            let gs = &mut phases[idx[r]].gs;
            let old = gs.velocity_new[l];
            heat += 0.5 * w[r] * (old.norm_squared() - vel[r].norm_squared());
            gs.velocity_new[l] = vel[r];
            gs.accel[l] += (vel[r] - old) / dt;
            phases[idx[r]].drag_dv[l] = vel[r] - old;
        }
    }
    Some(heat)
}

/// Σ_i S_ip of a_i, u_i' and Δu_i at one point ([`points_drag_heat`]).
struct Interpolated<const D: usize>([SVector<f64, D>; 3]);

impl<const D: usize> Default for Interpolated<D> {
    fn default() -> Self {
        Self([SVector::zeros(); 3])
    }
}

/// The kinetic energy the phase interaction takes from the points of `ph`
/// this step, Σ_p ½ m_p (|v_p' − δ_p|² − |v_p'|²): v_p' is the velocity
/// [`CoupledMpm::musl_velocity`] gives the point, (1 − β)(v_p + Σ_i S_ip a_i
/// Δt) + β Σ_i S_ip u_i' with PIC share β, and δ_p = Σ_i S_ip Δu_i the
/// interaction's part of it (Δu_i enters a_i Δt and u_i' alike). Call it
/// after [`exchange`], with the nodal fields' ghosts mirrored, before the
/// points move.
fn points_drag_heat<const D: usize>(mpm: &CoupledMpm<'_, D>, ph: &mut Phase<D>, dt: f64) -> f64 {
    let pic = mpm.params.pic_fraction;
    let Phase {
        particles,
        gs,
        scratch,
        drag_dv,
        drag_heat,
        ..
    } = ph;
    drag_heat.resize(particles.len(), 0.0);
    mpm.gather(
        particles,
        scratch,
        drag_heat,
        |acc: &mut Interpolated<D>, i, w, _| {
            acc.0[0] += gs.accel[i] * w;
            acc.0[1] += gs.velocity_new[i] * w;
            acc.0[2] += drag_dv[i] * w;
        },
        |p, Interpolated([a, u, du])| {
            let v = (particles.v[p] + a * dt) * (1.0 - pic) + u * pic;
            0.5 * particles.mass[p] * ((v - du).norm_squared() - v.norm_squared())
        },
    );
    drag_heat.iter().sum()
}

/// Nodal volumes V_l for the volume fractions (Zhang Eq. 13) and the
/// drag: the cell volume on a plane grid; on an r–z grid the volume per
/// radian `h_z ∫ N_i(r) ρ(r) dr`, where `ρ(r) = r₀ + |r − r₀|` counts the
/// mirror images beyond the face `r₀ = grid.lower[0]` that the wall folding
/// adds (at the axis, `|r|`). Away from the face (`r_i` beyond the
/// support) this is `r_i h_r h_z`; on the first nodes it is integrated
/// with 3-point Gauss–Legendre on half-cells, exact since the shape
/// functions are piecewise polynomials with knots at whole or half cells
/// (uGIMP is taken as the hat, its `lp → 0` limit).
pub fn node_volumes<const D: usize>(grid: &Grid<D>, shape: crate::shape::ShapeKind) -> Vec<f64> {
    let cell = grid.cell_volume();
    let n = grid.num_nodes();
    if !grid.axisymmetric {
        return vec![cell; n];
    }
    let (h, r0) = (grid.h[0], grid.lower[0]);
    let gauss = [
        (-(0.6f64).sqrt(), 5.0 / 9.0),
        (0.0, 8.0 / 9.0),
        ((0.6f64).sqrt(), 5.0 / 9.0),
    ];
    // ∫ N(ξ − i) ρ(r₀ + h ξ) dξ over the support |ξ − i| < 2.
    let radial = |i: isize| -> f64 {
        if i >= 3 {
            return r0 + h * i as f64;
        }
        let mut sum = 0.0;
        for k in (2 * i - 4)..(2 * i + 4) {
            let mid = 0.5 * k as f64 + 0.25;
            for (x, w) in gauss {
                let xi = mid + 0.25 * x;
                sum += 0.25 * w * shape.value(xi - i as f64) * (r0 + h * xi.abs());
            }
        }
        sum
    };
    (0..n)
        .map(|l| cell * radial(grid.node_coords(l)[0].abs()))
        .collect()
}
