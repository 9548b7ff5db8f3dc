//! The explicit MPM-ICE step (Guilkey Sec. 3.3, steps 1–13): solids on
//! material points and fluids in cell-centred ICE, coupled through the
//! multifield equations on one grid.
//!
//! One solid field (a deformable material or a rigid one with a prescribed
//! velocity) takes part in the cell equations as the last ICE material; its
//! cell state is rebuilt from the nodes every step. The step, in the order of
//! the paper:
//!
//! 1. P2G (Eq. 22) and node → cell: the cell's solid mass and momentum are
//!    the averages of its `2^D` corner nodes (mass-weighted velocity). The
//!    mirror-particle wall treatment of the MPM grid has already doubled the
//!    boundary nodes' mass on symmetry planes, which is Guilkey's "weight of
//!    those nodes on the boundary must be doubled". Empty cells get a tiny
//!    mass floor and the fluid's velocity. The solid's specific volume is
//!    its EOS value at the previous pressure ([`SolidEos`], never the
//!    interpolated volume).
//! 2. Equilibration on the total material volume (Eq. 13, Sec. 3.3 step 2),
//!    3. face velocities of all materials (Eq. 28) and the face exchange,
//!    5. `Δp` (Eq. 29, all materials' volume fluxes), 6. face pressure
//!    (Eq. 31): [`ice::stage_pressure`].
//! 7. Particle stresses; the internal force uses `σ + (p − p_ref) I` with
//!    the cell pressure interpolated cell → node → particle.
//! 8. The pressure force `−V θ_s ∇p*` of each cell goes to its corner nodes
//!    (a quarter / an eighth each, folded at walls); 9. the nodal momentum
//!    equation gives `vᴸ`; node → cell gives the solid's Lagrangian cell
//!    velocity.
//! 10. Exchange among all materials at the cells (Eqs. 38–39,
//!     [`ice::stage_lagrangian`]); the solid's velocity change goes back to
//!     the nodes as the average of the surrounding cells. With a heat
//!     exchange (`CouplingParams::heat_exchange > 0`) the particles carry
//!     a temperature: P2G maps it mass-weighted to the nodes, node → cell as
//!     the velocity, and the exchange's temperature change returns cells →
//!     nodes → particles the same way (conserving `Σ m c_v T` exactly). The
//!     solid has no thermal expansion and no heating by its own
//!     deformation; without a heat exchange it is isothermal and none of
//!     this is computed.
//! 11. Specific volumes (Eqs. 40–41); 12. fluid advection
//!     ([`ice::stage_advect`]); 13. G2P (Eqs. 26–27).

use std::ops::Mul;

use nalgebra::SVector;
use rayon::prelude::*;

use crate::error::{Error, FailureSite, Result};
use crate::grid::{Grid, Reflect};
use crate::ice::{self, Frame, IceParams, IceState, IceWorkspace, StepInfo};
use crate::material::eos::{EquationOfState, SolidEos};
use crate::material::SolidMaterial;
use crate::mpm::{
    stable_dt, BodyForce, CoupledMpm, ExplicitParams, GridState, Particles, StepScratch,
};

/// The MPM phases of the current step, borrowing only the run's MPM fields
/// (so the particles, grid state and scratch can be borrowed mutably
/// beside it).
macro_rules! phases {
    ($run:ident, $dt:expr) => {
        CoupledMpm {
            grid: &$run.grid,
            materials: &$run.materials,
            params: &$run.mpm,
            body: $run.body.as_deref().map(|b| b as &dyn BodyForce<D>),
            t: $run.fluid.time,
            dt: $dt,
            step: $run.steps,
        }
    };
}

/// Settings of the coupling.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CouplingParams {
    /// Reference pressure `p_ref`: the pressure at which the solid is
    /// stress-free (Guilkey Sec. 3.3 step 7).
    pub p_ref: f64,
    /// Initial temperature of the solid: every particle starts at it. With
    /// `heat_exchange = 0` the solid stays at it (isothermal, and no
    /// temperature transfer is computed).
    pub solid_temperature: f64,
    /// Volume-fraction floor: empty cells hold this fraction of solid (at
    /// the solid's density), fully solid cells this fraction of fluid. It
    /// must make `Δt K θ_floor v` negligible (`1e-15` with `K = 1e15`).
    pub floor_fraction: f64,
    /// Momentum exchange coefficient `K` between the solid field and every
    /// fluid (Guilkey Eq. 38; `1e15` drives them to one velocity where they
    /// share a cell: no slip, no interpenetration, Sec. 4.2).
    pub momentum_exchange: f64,
    /// Heat exchange coefficient `H` between the solid field and every
    /// fluid (Guilkey Eq. 39, `dT_r/dt = Σ_s H θ_s v_r (T_s − T_r)/c_v,r`;
    /// 0: none, the solid isothermal). The solid's change goes from the
    /// cells to the nodes and then to the particles' temperatures.
    pub heat_exchange: f64,
}

impl Default for CouplingParams {
    fn default() -> Self {
        Self {
            p_ref: 101_325.0,
            solid_temperature: 300.0,
            floor_fraction: 1e-15,
            momentum_exchange: 1e15,
            heat_exchange: 0.0,
        }
    }
}

/// Node ↔ cell maps of the shared grid.
#[derive(Debug, Clone)]
struct NodeCellMap<const D: usize> {
    /// Per interior cell (in `layout.interior` order): its lower-corner node.
    base: Vec<usize>,
    /// Flat node offsets of the `2^D` corners.
    corners: Vec<usize>,
}

impl<const D: usize> NodeCellMap<D> {
    fn new(grid: &Grid<D>, layout: &ice::CellLayout<D>) -> Self {
        let strides = grid.strides();
        let corners = (0..1usize << D)
            .map(|bits| (0..D).map(|d| ((bits >> d) & 1) * strides[d]).sum())
            .collect();
        let base = layout
            .interior
            .iter()
            .map(|&c| grid.node_index(layout.coords(c)))
            .collect();
        Self { base, corners }
    }
}

/// A coupled MPM-ICE run (explicit or semi-implicit pressure).
pub struct CoupledRun<const D: usize> {
    /// Background grid (nodes) shared with the ICE cells.
    pub grid: Grid<D>,
    /// Solid materials (one solid field: the particles' materials share it).
    pub materials: Vec<SolidMaterial>,
    /// Particles of the solid field.
    pub particles: Particles<D>,
    /// MPM discretisation (shape, update ordering, damping).
    pub mpm: ExplicitParams,
    /// Body force on the particles.
    pub body: Option<Box<dyn BodyForce<D> + Send + Sync>>,
    /// The cell state; the solid field is material `solid`.
    pub fluid: IceState<D>,
    /// ICE parameters (frames set: fluids Eulerian, the solid field
    /// `Particles` or `Rigid`).
    pub ice: IceParams<D>,
    /// Index of the solid field among the ICE materials.
    pub solid: usize,
    /// Prescribed velocity of a rigid solid field (`None`: deformable).
    pub rigid_velocity: Option<SVector<f64, D>>,
    /// Time over which a rigid field's velocity rises smoothly from zero,
    /// `v(t) = V (1 − cos(π t/T))/2` for `t < T` (0: impulsive start).
    pub rigid_ramp: f64,
    /// The solid field's bulk EOS in the cells.
    pub solid_eos: SolidEos,
    /// Coupling settings.
    pub coupling: CouplingParams,
    /// Courant number of the MPM limit (the ICE limit uses `ice.cfl`).
    pub cfl: f64,
    /// Completed steps.
    pub steps: u64,
    /// The rigid velocity of the current step (mid-step value).
    rigid_now: Option<SVector<f64, D>>,
    ws: IceWorkspace<D>,
    gs: GridState<D>,
    scratch: StepScratch<D>,
    map: NodeCellMap<D>,
    node_pressure: Vec<f64>,
    node_force: Vec<SVector<f64, D>>,
    cell_vec: Vec<SVector<f64, D>>,
    particle_velocity: Vec<Vec<SVector<f64, D>>>,
    solid_l: Vec<SVector<f64, D>>,
    /// Per interior cell: (mass, momentum) of the solid from the nodes.
    cell_mass: Vec<f64>,
    /// Whether the solid exchanges heat (`coupling.heat_exchange > 0`):
    /// only then are temperatures transferred.
    heat_on: bool,
    /// Per node: the solid's temperature, then its exchange change.
    node_scalar: Vec<f64>,
    /// Per cell: the solid's exchange temperature change.
    cell_scalar: Vec<f64>,
    /// Per interior cell: the solid's temperature from the nodes.
    cell_temp: Vec<f64>,
}

impl<const D: usize> CoupledRun<D> {
    /// Builds a run from the fluid materials' initial state `fluid`; the
    /// solid field is appended as the last ICE material (named
    /// `solid_name`), `ice.frames` and `ice.normalise_volume` are set. The
    /// fluid masses are reduced where the solid's particles occupy a cell
    /// (`1 − θ_s`, with the floor), so the initial material volume fills
    /// every cell.
    ///
    /// # Errors
    /// [`Error::Fluid`] for invalid ICE parameters or too many materials.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        grid: Grid<D>,
        materials: Vec<SolidMaterial>,
        particles: Particles<D>,
        mpm: ExplicitParams,
        mut fluid: IceState<D>,
        mut ice: IceParams<D>,
        solid_name: &str,
        solid_eos: SolidEos,
        rigid_velocity: Option<SVector<f64, D>>,
        coupling: CouplingParams,
        cfl: f64,
    ) -> Result<Self> {
        let solid = fluid.num_materials();
        if solid + 1 > ice::MAX_MATERIALS {
            return Err(ice::IceError::InvalidInput {
                field: "materials".into(),
                reason: format!("at most {} materials", ice::MAX_MATERIALS),
            }
            .into());
        }
        fluid.push_material(ice::IceMaterial::new(solid_name, solid_eos));
        let nm = solid + 1;
        ice.frames = vec![Frame::Eulerian; nm];
        ice.frames[solid] = if rigid_velocity.is_some() {
            Frame::Rigid
        } else {
            Frame::Particles
        };
        ice.normalise_volume = true;
        {
            // Grow the coefficient matrices by the solid's row and column
            // (`coupling.momentum_exchange`, `coupling.heat_exchange`).
            let ex = ice
                .exchange
                .get_or_insert_with(|| ice::ExchangeCoefficients::uniform(solid, 0.0, 0.0));
            let k = coupling.momentum_exchange;
            let mut momentum = vec![0.0; nm * nm];
            let mut heat = vec![0.0; nm * nm];
            for r in 0..solid {
                for s in 0..solid {
                    momentum[r * nm + s] = ex.momentum[r * solid + s];
                    heat[r * nm + s] = ex.heat[r * solid + s];
                }
                momentum[r * nm + solid] = k;
                momentum[solid * nm + r] = k;
                heat[r * nm + solid] = coupling.heat_exchange;
                heat[solid * nm + r] = coupling.heat_exchange;
            }
            ex.momentum = momentum;
            ex.heat = heat;
        }
        ice.validate(&fluid)?;
        let ws = IceWorkspace::new(&fluid);
        let n_nodes = grid.num_nodes();
        let n_cells = fluid.layout.len();
        let map = NodeCellMap::new(&grid, &fluid.layout);
        let n_int = fluid.layout.num_interior();
        let heat_on = coupling.heat_exchange > 0.0;
        let mut particles = particles;
        particles.temperature.fill(coupling.solid_temperature);
        let mut run = Self {
            heat_on,
            node_scalar: if heat_on {
                vec![0.0; n_nodes]
            } else {
                Vec::new()
            },
            cell_scalar: if heat_on {
                vec![0.0; n_cells]
            } else {
                Vec::new()
            },
            cell_temp: if heat_on {
                vec![0.0; n_int]
            } else {
                Vec::new()
            },
            gs: GridState::new(n_nodes),
            scratch: StepScratch::default(),
            map,
            node_pressure: vec![0.0; n_nodes],
            node_force: vec![SVector::zeros(); n_nodes],
            cell_vec: vec![SVector::zeros(); n_cells],
            particle_velocity: (0..nm)
                .map(|r| {
                    if r == solid {
                        vec![SVector::zeros(); n_cells]
                    } else {
                        Vec::new()
                    }
                })
                .collect(),
            solid_l: vec![SVector::zeros(); n_int],
            cell_mass: vec![0.0; n_int],
            grid,
            materials,
            particles,
            mpm,
            body: None,
            fluid,
            ice,
            solid,
            rigid_velocity,
            rigid_ramp: 0.0,
            rigid_now: rigid_velocity,
            solid_eos,
            coupling,
            cfl,
            steps: 0,
            ws,
        };
        run.initialise()?;
        Ok(run)
    }

    /// Step 1: P2G and node → cell of the solid's mass and velocity (and
    /// temperature, with a heat exchange).
    fn p2g_to_cells(&mut self, dt: f64) -> Result<()> {
        let phases = phases!(self, dt);
        phases.p2g(&self.particles, &mut self.gs, &mut self.scratch)?;
        let gs = &self.gs;
        nodes_to_cells(
            &gs.mass,
            &gs.velocity,
            &self.map,
            &mut self.cell_mass,
            &mut self.solid_l,
        );
        if self.heat_on {
            let p = &self.particles;
            phases.p2g_scalar(p, &p.temperature, gs, &self.scratch, &mut self.node_scalar);
            nodes_to_cells(
                &gs.mass,
                &self.node_scalar,
                &self.map,
                &mut self.cell_mass,
                &mut self.cell_temp,
            );
        }
        Ok(())
    }

    /// The rigid field's velocity at time `t` (with the ramp).
    pub fn rigid_velocity_at(&self, t: f64) -> Option<SVector<f64, D>> {
        let ramp = self.rigid_ramp;
        self.rigid_velocity.map(|v| {
            if ramp > 0.0 && t < ramp {
                v * (0.5 * (1.0 - (std::f64::consts::PI * t / ramp).cos()))
            } else {
                v
            }
        })
    }

    /// Displacement of the rigid field from time 0 to `t` (the integral of
    /// [`Self::rigid_velocity_at`]).
    pub fn rigid_displacement(&self, t: f64) -> Option<SVector<f64, D>> {
        let ramp = self.rigid_ramp;
        self.rigid_velocity.map(|v| {
            if ramp > 0.0 {
                let tr = t.min(ramp);
                let pi = std::f64::consts::PI;
                let during = 0.5 * (tr - ramp / pi * (pi * tr / ramp).sin());
                v * (during + (t - ramp).max(0.0))
            } else {
                v * t
            }
        })
    }

    /// Mass-weighted velocity and temperature of the fluids in interior
    /// cell `c` (what an empty solid cell takes, so that its exchange
    /// changes nothing).
    fn fluid_mixture(&self, c: usize) -> (SVector<f64, D>, f64) {
        let mut m = 0.0;
        let mut p = SVector::<f64, D>::zeros();
        let mut mt = 0.0;
        for r in 0..self.solid {
            let mc = &self.fluid.cells[r];
            m += mc.mass[c];
            p += mc.velocity[c] * mc.mass[c];
            mt += mc.temperature[c] * mc.mass[c];
        }
        if m > 0.0 {
            (p / m, mt / m)
        } else {
            (SVector::zeros(), self.coupling.solid_temperature)
        }
    }

    /// Writes the solid field's cell state from `cell_mass` / `solid_l`.
    fn set_solid_cells(&mut self) {
        let vol = self.fluid.layout.cell_volume();
        let floor = self.coupling.floor_fraction * self.solid_eos.reference_density() * vol;
        let t_s = self.coupling.solid_temperature;
        let rigid = self.rigid_now;
        for (k, &c) in self.fluid.layout.interior.iter().enumerate() {
            let m = self.cell_mass[k];
            // An empty cell's floor moves with the fluid (even for a rigid
            // field): its exchange then changes nothing.
            let (mass, u, t) = if m > floor {
                let t = if self.heat_on { self.cell_temp[k] } else { t_s };
                (m, rigid.unwrap_or(self.solid_l[k]), t)
            } else {
                let (u, t) = self.fluid_mixture(c);
                (floor, u, if self.heat_on { t } else { t_s })
            };
            let p = self.fluid.pressure[c];
            let p = if p > 0.0 { p } else { self.coupling.p_ref };
            let rho = self
                .solid_eos
                .density(p, t)
                .unwrap_or(self.solid_eos.reference_density());
            let sc = &mut self.fluid.cells[self.solid];
            sc.mass[c] = mass;
            sc.velocity[c] = u;
            sc.temperature[c] = t;
            sc.sp_vol[c] = 1.0 / rho;
        }
    }

    /// Initial state: the fluid volume fractions reduced where the solid
    /// sits, the equilibration pressure and the pressure field.
    fn initialise(&mut self) -> Result<()> {
        self.p2g_to_cells(0.0)?;
        let vol = self.fluid.layout.cell_volume();
        let floor = self.coupling.floor_fraction;
        for (k, &c) in self.fluid.layout.interior.iter().enumerate() {
            let p = self.fluid.p_eq[c];
            self.fluid.pressure[c] = p;
            let rho_s = self
                .solid_eos
                .density(if p > 0.0 { p } else { self.coupling.p_ref }, 300.0)
                .unwrap_or(self.solid_eos.reference_density());
            let theta_s = (self.cell_mass[k] / (rho_s * vol)).min(1.0 - floor);
            let keep = (1.0 - theta_s).max(floor);
            for r in 0..self.solid {
                let mc = &mut self.fluid.cells[r];
                mc.mass[c] *= keep;
                if mc.mass[c].is_nan() || mc.mass[c] <= 0.0 {
                    mc.mass[c] = floor * vol / mc.sp_vol[c].max(f64::MIN_POSITIVE);
                }
            }
        }
        self.set_solid_cells();
        ice::equilibrate(&mut self.fluid, &self.ice)?;
        let p_eq = self.fluid.p_eq.clone();
        self.fluid.pressure.copy_from_slice(&p_eq);
        Ok(())
    }

    /// Steps until time `t_end` (the last step shortened to land on it).
    ///
    /// # Errors
    /// As [`Self::step`].
    pub fn advance_to(&mut self, t_end: f64) -> Result<()> {
        while self.fluid.time < t_end * (1.0 - 1e-12) {
            self.step(t_end - self.fluid.time)?;
        }
        Ok(())
    }

    /// Largest stable time step: the ICE limit over all materials (the
    /// solid's sound speed included) and the MPM limit.
    pub fn stable_dt(&self) -> f64 {
        let factor = self
            .ice
            .implicit
            .as_ref()
            .map_or(1.0, |sp| sp.sound_speed_factor);
        // Explicit: every material's sound speed (a deformable solid's too:
        // Eq. 29 in cells it shares; not a rigid one's); semi-implicit:
        // advection only (factor 0 by default) — the solid field stays
        // explicit through `solid_dt`.
        let fluid_dt =
            ice::timestep_with(&self.fluid, self.ice.cfl, factor, &self.ice.rigid_mask());
        let solid_dt = if self.rigid_velocity.is_some() || self.particles.is_empty() {
            f64::INFINITY
        } else {
            stable_dt(&self.grid, &self.materials, &self.particles, self.cfl)
        };
        fluid_dt.min(solid_dt)
    }

    /// The grid nodes' state of the last step.
    pub fn grid_state(&self) -> &GridState<D> {
        &self.gs
    }

    /// Accumulated MPM phase times.
    pub fn phase_times(&self) -> crate::mpm::PhaseTimes {
        self.scratch.times
    }

    /// One coupled step of at most `dt_max` (halved on a retryable ICE
    /// error, up to 20 times). Returns what the ICE part did.
    ///
    /// # Errors
    /// [`Error::Fluid`] naming step, time, cell and material;
    /// [`Error::Numerical`] for a particle failure.
    pub fn step(&mut self, dt_max: f64) -> Result<StepInfo> {
        let dt = self.stable_dt().min(dt_max);
        if !(dt.is_finite() && dt > 0.0) {
            return Err(self.fail(format!("time step is {dt}")));
        }
        let info = self.step_inner(dt)?;
        self.steps += 1;
        Ok(info)
    }

    fn fail(&self, what: String) -> Error {
        Error::Numerical {
            site: FailureSite {
                step: self.steps,
                time: self.fluid.time,
                particle: None,
                cell: None,
            },
            what,
        }
    }

    /// The solid's temperature change of the exchange (Guilkey Eq. 39),
    /// cells → nodes → particles (Sec. 3.3 step 10), before the particles
    /// move. Empty cells contribute nothing. The transfer conserves the
    /// solid's thermal energy: `Σ_p m_p ΔT_p = Σ_i m_i ΔT_i = Σ_c m_c ΔT_c`.
    fn heat_to_particles(&mut self, dt: f64) {
        let layout = &self.fluid.layout;
        let floor = self.coupling.floor_fraction
            * self.solid_eos.reference_density()
            * layout.cell_volume();
        let tl = self.ws.lagrangian_temperature(self.solid);
        let t0 = &self.fluid.cells[self.solid].temperature;
        for (k, &c) in layout.interior.iter().enumerate() {
            self.cell_scalar[c] = if self.cell_mass[k] > floor {
                tl[c] - t0[c]
            } else {
                0.0
            };
        }
        cells_to_nodes(&self.grid, layout, &self.cell_scalar, &mut self.node_scalar);
        self.grid.mirror_ghosts(&mut self.node_scalar);
        let mut temperature = std::mem::take(&mut self.particles.temperature);
        let phases = phases!(self, dt);
        phases.g2p_scalar_add(
            &self.particles,
            &self.node_scalar,
            &self.scratch,
            &mut temperature,
        );
        self.particles.temperature = temperature;
    }

    fn step_inner(&mut self, dt_try: f64) -> Result<StepInfo> {
        let mut dt = dt_try;
        // Step 1: P2G and node → cell (does not change the particles).
        self.p2g_to_cells(dt)?;
        self.rigid_now = self.rigid_velocity_at(self.fluid.time + 0.5 * dt);
        self.set_solid_cells();
        // Steps 2–6.
        let mut tries = 0;
        let info = loop {
            match ice::stage_pressure(&mut self.fluid, &self.ice, &mut self.ws, dt, true) {
                Ok(info) => break info,
                Err(e) if tries < 20 && e.retry_dt().is_some() => {
                    dt *= 0.5;
                    tries += 1;
                    self.rigid_now = self.rigid_velocity_at(self.fluid.time + 0.5 * dt);
                    self.set_solid_cells();
                }
                Err(e) => return Err(e.into()),
            }
        };
        let dt = info.dt;
        let layout = &self.fluid.layout;
        let vol = layout.cell_volume();
        // Cell pressure → nodes (average of the 2^D surrounding cells,
        // ghosts from the boundary conditions).
        {
            let press = self.ws.pressure();
            let grid = &self.grid;
            let inv = 1.0 / (1usize << D) as f64;
            let lo = -(ice::NGHOST as isize);
            self.node_pressure
                .par_iter_mut()
                .enumerate()
                .for_each(|(i, pn)| {
                    let ijk = grid.node_coords(i);
                    let mut sum = 0.0;
                    for bits in 0..1usize << D {
                        let mut cc = [0isize; D];
                        for d in 0..D {
                            let hi = layout.cells[d] as isize + ice::NGHOST as isize - 1;
                            cc[d] = (ijk[d] - ((bits >> d) & 1) as isize).clamp(lo, hi);
                        }
                        sum += press[layout.index(cc)];
                    }
                    *pn = sum * inv;
                });
        }
        // Step 8: the pressure force −V θ_s ∇p* of each cell, to the nodes.
        {
            let pstar = self.ws.face_pressure();
            let theta = &self.fluid.cells[self.solid].vol_frac;
            let out = &mut self.cell_vec;
            for &c in &layout.interior {
                let mut g = SVector::<f64, D>::zeros();
                for d in 0..D {
                    g[d] = (pstar[d][c + layout.strides[d]] - pstar[d][c]) / layout.h[d];
                }
                out[c] = -g * (vol * theta[c]);
            }
        }
        cells_to_nodes(&self.grid, layout, &self.cell_vec, &mut self.node_force);
        // Steps 7–9 on the nodes.
        if let Some(v) = self.rigid_now {
            let gs = &mut self.gs;
            for (i, &m) in gs.mass.iter().enumerate() {
                let u = if m > self.mpm.mass_floor {
                    v
                } else {
                    SVector::zeros()
                };
                gs.velocity_new[i] = u;
                gs.accel[i] = SVector::zeros();
            }
        } else {
            let phases = phases!(self, dt);
            phases.solve(
                &mut self.particles,
                &mut self.gs,
                &mut self.scratch,
                &self.node_pressure,
                self.coupling.p_ref,
                &self.node_force,
            )?;
        }
        // Node → cell: the solid's Lagrangian cell velocity.
        nodes_to_cells(
            &self.gs.mass,
            &self.gs.velocity_new,
            &self.map,
            &mut self.cell_mass,
            &mut self.solid_l,
        );
        {
            let layout = &self.fluid.layout;
            let pv = &mut self.particle_velocity[self.solid];
            let sc = &self.fluid.cells[self.solid];
            let floor = self.coupling.floor_fraction
                * self.solid_eos.reference_density()
                * layout.cell_volume();
            for (k, &c) in layout.interior.iter().enumerate() {
                pv[c] = if self.cell_mass[k] > floor {
                    self.rigid_now.unwrap_or(self.solid_l[k])
                } else {
                    // Empty cell: the floor keeps the velocity it was given.
                    sc.velocity[c]
                };
            }
        }
        // Steps 8–11 at the cells (fluid sources, exchange, specific volume).
        ice::stage_lagrangian(
            &self.fluid,
            &self.ice,
            &mut self.ws,
            dt,
            &self.particle_velocity,
        )?;
        // The solid's exchange velocity change, cells → nodes.
        if self.rigid_velocity.is_none() {
            let layout = &self.fluid.layout;
            let ul = self.ws.lagrangian_velocity(self.solid);
            let pv = &self.particle_velocity[self.solid];
            for &c in &layout.interior {
                self.cell_vec[c] = ul[c] - pv[c];
            }
            cells_to_nodes(&self.grid, layout, &self.cell_vec, &mut self.node_force);
            let inv_dt = 1.0 / dt;
            let floor = self.mpm.mass_floor;
            let gs = &mut self.gs;
            gs.velocity_new
                .par_iter_mut()
                .zip(gs.accel.par_iter_mut())
                .zip(gs.mass.par_iter().zip(self.node_force.par_iter()))
                .for_each(|((v, a), (&m, dv))| {
                    if m > floor {
                        *v += dv;
                        *a += dv * inv_dt;
                    }
                });
            self.grid.mirror_ghosts(&mut gs.velocity_new);
            self.grid.mirror_ghosts(&mut gs.accel);
        }
        if self.heat_on {
            self.heat_to_particles(dt);
        }
        // Step 13: G2P.
        if let Some(v) = self.rigid_now {
            self.particles.x.par_iter_mut().for_each(|x| *x += v * dt);
            self.particles.v.par_iter_mut().for_each(|u| *u = v);
        } else {
            let phases = phases!(self, dt);
            phases.g2p(&mut self.particles, &self.gs, &mut self.scratch)?;
        }
        // Step 12: fluid advection and the commit of the cell state.
        let info = ice::stage_advect(&mut self.fluid, &self.ice, &mut self.ws, info)?;
        Ok(info)
    }
}

/// Node → cell (Guilkey Sec. 3.3 step 1): per interior cell the mass, the
/// average of its `2^D` corner nodes' masses, and the mass-weighted average
/// of a nodal field (velocity, temperature; zero where the corners are
/// massless).
fn nodes_to_cells<const D: usize, T>(
    node_mass: &[f64],
    node_value: &[T],
    map: &NodeCellMap<D>,
    cell_mass: &mut [f64],
    cell_value: &mut [T],
) where
    T: Reflect<D> + Mul<f64, Output = T> + Send + Sync,
{
    let inv = 1.0 / (1usize << D) as f64;
    cell_mass
        .par_iter_mut()
        .zip(cell_value.par_iter_mut())
        .zip(map.base.par_iter())
        .for_each(|((m, u), &b)| {
            let mut mass = 0.0;
            let mut sum = T::zero();
            for &o in &map.corners {
                mass += node_mass[b + o];
                sum = sum.add(&(node_value[b + o] * node_mass[b + o]));
            }
            *m = mass * inv;
            *u = if mass > 0.0 {
                sum * (1.0 / mass)
            } else {
                T::zero()
            };
        });
}

/// Cell values (interior cells) to nodes: each node gets `1/2^D` of every
/// adjacent interior cell's value; then the wall folding of the MPM grid
/// (a boundary node on a symmetry plane gets its own reflection: scalars
/// and tangential components doubled, the normal one cancelled — Guilkey's
/// doubled boundary weights). With the mass average of [`nodes_to_cells`]
/// this conserves: `Σ_i m_i q_i = Σ_c m_c q_c` over the folded nodal masses.
fn cells_to_nodes<const D: usize, T>(
    grid: &Grid<D>,
    layout: &ice::CellLayout<D>,
    cell: &[T],
    node: &mut [T],
) where
    T: Reflect<D> + Mul<f64, Output = T> + Send + Sync,
{
    let inv = 1.0 / (1usize << D) as f64;
    node.par_iter_mut().enumerate().for_each(|(i, q)| {
        let ijk = grid.node_coords(i);
        let mut sum = T::zero();
        'corner: for bits in 0..1usize << D {
            let mut cc = [0isize; D];
            for d in 0..D {
                cc[d] = ijk[d] - ((bits >> d) & 1) as isize;
                if cc[d] < 0 || cc[d] >= layout.cells[d] as isize {
                    continue 'corner;
                }
            }
            sum = sum.add(&cell[layout.index(cc)]);
        }
        *q = sum * inv;
    });
    grid.fold_ghosts(node);
}
