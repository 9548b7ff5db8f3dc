//! The explicit MPM-ICE step (Guilkey Sec. 3.3, steps 1–13): solids on
//! material points and fluids in cell-centred ICE, coupled through the
//! multifield equations on one grid.
//!
//! Every solid field ([`SolidField`]: a deformable material or a rigid one
//! with a prescribed velocity, with its own particles and nodal velocity
//! field) takes part in the cell equations as an ICE material of its own,
//! after the fluids; its cell state is rebuilt from its nodes every step.
//! Solid fields interact with each other and with the fluids only through
//! the cell equations: the shared pressure and the multifield exchange
//! (Guilkey Eqs. 38–39, every pair of materials). Each phase below runs
//! once per field, the cell stages once for all materials. The step, in the
//! order of the paper:
//!
//! 1. P2G (Eq. 22) and node → cell: the cell's solid mass and momentum are
//!    the averages of its `2^D` corner nodes (mass-weighted velocity). The
//!    mirror-particle wall treatment of the MPM grid has already doubled the
//!    boundary nodes' mass on symmetry planes, which is Guilkey's "weight of
//!    those nodes on the boundary must be doubled". Cells where a field is
//!    absent get a tiny mass floor of it and the velocity of the other
//!    materials there (fluids and present solid fields). A solid's specific
//!    volume is its EOS value at the previous pressure ([`SolidEos`], never
//!    the interpolated volume).
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

pub mod iteration;
pub mod reaction;
pub mod rigid_volume;

pub use rigid_volume::RigidInterface;

use std::ops::Mul;

use nalgebra::SVector;
use rayon::prelude::*;

use crate::error::{Error, FailureSite, Result};
use crate::grid::{Grid, Reflect};
use crate::ice::{self, Frame, IceParams, IceState, IceWorkspace, StepInfo};
use crate::material::eos::{EquationOfState, SolidEos};
use crate::material::SolidMaterial;
use crate::mpm::{
    stable_dt, BodyForce, CoupledMpm, ExplicitParams, GridState, ImplicitRun, Particles,
    StepScratch,
};

/// The MPM phases of the current step, borrowing only the run's MPM fields
/// (so the solid fields' particles, grid states and scratch can be
/// borrowed mutably beside it).
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
    /// Initial temperature of the solids: every particle starts at it. With
    /// `heat_exchange = 0` the solids stay at it (isothermal, and no
    /// temperature transfer is computed).
    pub solid_temperature: f64,
    /// Volume-fraction floor: cells where a solid field is absent hold this
    /// fraction of it (at its density), fully solid cells this fraction of
    /// fluid. It
    /// must make `Δt K θ_floor v` negligible (`1e-15` with `K = 1e15`).
    pub floor_fraction: f64,
    /// Momentum exchange coefficient `K` between every solid field and every
    /// other material, fluid or solid (Guilkey Eq. 38; `1e15` drives them to one velocity where they
    /// share a cell: no slip, no interpenetration, Sec. 4.2).
    pub momentum_exchange: f64,
    /// Heat exchange coefficient `H` between every solid field and every
    /// other material, fluid or solid (Guilkey Eq. 39, `dT_r/dt = Σ_s H θ_s v_r (T_s − T_r)/c_v,r`;
    /// 0: none, the solids isothermal). A field's change goes from the
    /// cells to its nodes and then to its particles' temperatures.
    pub heat_exchange: f64,
    /// A solid field's cell mass below this fraction of the cell at the
    /// field's reference density is a trace: its Lagrangian cell velocity
    /// in the exchange is the one it had at the start of the step, not its
    /// node-to-cell average ([`SOLID_TRACE_FRACTION`]).
    pub trace_fraction: f64,
    /// How a rigid field's volume enters the cells
    /// ([`RigidInterface`]; scene key `coupling.rigid_interface`).
    pub rigid_interface: RigidInterface,
}

/// Default [`CouplingParams::trace_fraction`] (scene key
/// `coupling.solid_trace_fraction`): `1e-3` of a cell. Both `1e-4` and
/// `1e-3` keep the air beside unequal steel blocks meeting in air physical;
/// at the absence floor (`1e-15`) those runs fail.
pub const SOLID_TRACE_FRACTION: f64 = 1e-3;

impl Default for CouplingParams {
    fn default() -> Self {
        Self {
            p_ref: 101_325.0,
            solid_temperature: 300.0,
            floor_fraction: 1e-15,
            momentum_exchange: 1e15,
            heat_exchange: 0.0,
            trace_fraction: SOLID_TRACE_FRACTION,
            rigid_interface: RigidInterface::Smeared,
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

/// What [`CoupledRun::with_fields`] needs to know of one solid field.
#[derive(Debug, Clone)]
pub struct SolidFieldSpec<const D: usize> {
    /// Name of the field's ICE material (the solid material's name in a
    /// scene).
    pub name: String,
    /// The field's particles (`material` indexes the run's `materials`).
    pub particles: Particles<D>,
    /// The field's bulk EOS in the cells (Guilkey Fig. 1).
    pub eos: SolidEos,
    /// Prescribed velocity of a rigid field (`None`: deformable).
    pub rigid_velocity: Option<SVector<f64, D>>,
}

/// One solid velocity field: its particles, its nodal velocity field and
/// its ICE material (Guilkey Sec. 2: every material has its own velocity;
/// solid fields meet each other and the fluids only through the cell
/// exchange, Eqs. 38–39).
pub struct SolidField<const D: usize> {
    /// Index of the field among the ICE materials (after the fluids).
    pub ice_material: usize,
    /// The field's particles.
    pub particles: Particles<D>,
    /// The field's bulk EOS in the cells.
    pub eos: SolidEos,
    /// Prescribed velocity of a rigid field (`None`: deformable).
    pub rigid_velocity: Option<SVector<f64, D>>,
    /// The rigid velocity of the current step (mid-step value).
    rigid_now: Option<SVector<f64, D>>,
    gs: GridState<D>,
    scratch: StepScratch<D>,
    /// Per interior cell: the field's mass from the nodes.
    cell_mass: Vec<f64>,
    /// Per interior cell: the field's velocity from the nodes (P2G, then
    /// Lagrangian).
    cell_velocity: Vec<SVector<f64, D>>,
    /// Per interior cell: the field's temperature from the nodes (only
    /// with a heat exchange).
    cell_temp: Vec<f64>,
    /// Implicit MPM for this field (`time.mode = "implicit"`; `None`:
    /// explicit). It holds no particles between steps: the field lends
    /// them for the solve and the G2P.
    pub implicit: Option<Box<ImplicitRun<D>>>,
    /// This field's implicit solves (all passes), summed over the steps.
    pub implicit_totals: ImplicitTotals,
}

impl<const D: usize> SolidField<D> {
    /// The grid nodes' state of the field's last step.
    pub fn grid_state(&self) -> &GridState<D> {
        &self.gs
    }

    /// Accumulated MPM phase times of the field.
    pub fn phase_times(&self) -> crate::mpm::PhaseTimes {
        self.scratch.times
    }

    /// The floor mass of the field in a cell of volume `vol`: below it the
    /// field is absent from the cell.
    fn floor_mass(&self, floor_fraction: f64, vol: f64) -> f64 {
        floor_fraction * self.eos.reference_density() * vol
    }
}

/// What the implicit solid solves of a coupled run did, summed over its
/// steps and fields (the time split of [`crate::mpm::StepStats`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct ImplicitTotals {
    /// Solves (steps × passes × implicit fields; for one field: steps ×
    /// passes).
    pub solves: u64,
    /// Accepted steps with implicit fields.
    pub steps: u64,
    /// Newton iterations of the accepted solves.
    pub newton_iterations: u64,
    /// Most Newton iterations of one solve.
    pub max_newton_iterations: u64,
    /// Krylov iterations (0 with the direct solver).
    pub linear_iterations: u64,
    /// Tangents assembled and factorised (fewer than the Newton iterations
    /// with `implicit.modified_newton`).
    pub factorisations: u64,
    /// Coupled steps redone with a smaller Δt after a failed solve.
    pub step_retries: u64,
    /// Seconds in P2G, pattern, residual and tangent assembly.
    pub assembly_s: f64,
    /// Seconds in factorisation.
    pub factor_s: f64,
    /// Seconds in triangular solves or Krylov iterations.
    pub solve_s: f64,
    /// Seconds in the particle update.
    pub particles_s: f64,
    /// Passes of the coupling iteration (pressure stage + implicit solves)
    /// of the accepted steps ([`iteration`]).
    pub coupling_iterations: u64,
    /// Most passes of one step.
    pub max_coupling_iterations: u64,
}

impl ImplicitTotals {
    fn add(&mut self, st: &crate::mpm::StepStats) {
        self.solves += 1;
        self.newton_iterations += st.newton_iterations as u64;
        self.max_newton_iterations = self.max_newton_iterations.max(st.newton_iterations as u64);
        self.linear_iterations += st.linear_iterations as u64;
        self.factorisations += st.factorisations as u64;
        self.assembly_s += st.assembly_s;
        self.factor_s += st.factor_s;
        self.solve_s += st.solve_s;
        self.particles_s += st.particles_s;
    }
}

/// `v` with the smooth start `v (1 − cos(π t/T))/2` for `t < T`.
fn ramped<const D: usize>(
    v: Option<SVector<f64, D>>,
    ramp: f64,
    t: f64,
) -> Option<SVector<f64, D>> {
    v.map(|v| {
        if ramp > 0.0 && t < ramp {
            v * (0.5 * (1.0 - (std::f64::consts::PI * t / ramp).cos()))
        } else {
            v
        }
    })
}

/// A coupled MPM-ICE run (explicit or semi-implicit pressure) with one or
/// more solid fields.
pub struct CoupledRun<const D: usize> {
    /// Background grid (nodes) shared with the ICE cells.
    pub grid: Grid<D>,
    /// Solid materials of all fields (the particles' `material` indexes
    /// this list).
    pub materials: Vec<SolidMaterial>,
    /// The solid fields, in ICE material order (after the fluids).
    pub fields: Vec<SolidField<D>>,
    /// MPM discretisation (shape, update ordering, damping).
    pub mpm: ExplicitParams,
    /// Body force on the particles.
    pub body: Option<Box<dyn BodyForce<D> + Send + Sync>>,
    /// The cell state; the fluids come first, then one material per solid
    /// field (`fields[i].ice_material`).
    pub fluid: IceState<D>,
    /// ICE parameters (frames set: fluids Eulerian, the solid fields
    /// `Particles` or `Rigid`).
    pub ice: IceParams<D>,
    /// Time over which a rigid field's velocity rises smoothly from zero,
    /// `v(t) = V (1 − cos(π t/T))/2` for `t < T` (0: impulsive start).
    pub rigid_ramp: f64,
    /// Coupling settings.
    pub coupling: CouplingParams,
    /// Courant number of the MPM limit (the ICE limit uses `ice.cfl`).
    pub cfl: f64,
    /// Completed steps.
    pub steps: u64,
    /// Wall time spent in the pressure stages (Guilkey Sec. 3.3 steps 2–6:
    /// equilibration, face velocities and their exchange, `Δp` or the
    /// implicit pressure solve, face pressure), summed over the steps and
    /// their retries. Not part of the state (a restart starts it at 0).
    pub pressure_s: f64,
    /// How many times the last step halved its Δt because the pressure
    /// stage failed retryably (e.g. the outer iteration of the implicit
    /// pressure not converging); the run summary counts them as retries.
    pub last_halvings: usize,
    /// The last Δt cut and the step it happened in (the step count before
    /// it): a pressure stage that failed retryably and was halved, or an
    /// implicit field's failed solve. The progress guard names it
    /// ([`crate::driver::Model::dt_limiter`]).
    pub last_cut: Option<(u64, crate::mpm::DtCut)>,
    /// The work the rigid fields' prescribed motion did in the last step,
    /// apart from the exchange's part (in the ICE workspace's boundary
    /// exchange): `−Δt U · F` of the cells' pressure force `F` on their
    /// nodes, which holding them at `U` takes, plus their particles'
    /// kinetic energy change.
    pub rigid_work: f64,
    /// The chemical energy the reactions released in the last step.
    pub reaction_step_energy: f64,
    /// Per field, the momentum the cells gave it in the last step: their
    /// pressure force `Σ_c F_c Δt` and the exchange's `Σ_c m_c Δu_c`, both
    /// already in the fluids' account (the face pressures telescope to
    /// the boundary; the exchange sums to zero in each cell).
    pub cell_impulse: Vec<SVector<f64, D>>,
    /// The implicit solid solves (`time.mode = "implicit"`), summed over
    /// the steps and fields. Not part of the state.
    pub implicit_totals: ImplicitTotals,
    /// How many times the last step was redone with a smaller Δt after a
    /// failed implicit solve or coupling iteration.
    pub last_implicit_retries: usize,
    /// Set when the last step failed in an implicit solid solve (nothing
    /// committed: the step is retried with a smaller Δt).
    implicit_failed: bool,
    /// The field whose solve the last step was in when it failed (its
    /// particle indices are the error's); `None` after a good step.
    pub failed_field: Option<usize>,
    /// The coupling iteration of an implicit step ([`iteration`]).
    pub iteration: iteration::CouplingIteration,
    fixed_point: iteration::FixedPoint<D>,
    /// The cells the iteration acts on: (field, interior cell index) of
    /// every implicit field's cells above its trace mass and below
    /// [`iteration::ITERATED_FILL`] of the cell.
    fp_cells: Vec<(usize, usize)>,
    /// Per node: a field's `vⁿ⁺¹ − Δt F_p/m`; per interior cell its
    /// node → cell mass and velocity.
    node_w: Vec<SVector<f64, D>>,
    cell_w_mass: Vec<f64>,
    cell_w: Vec<SVector<f64, D>>,
    ws: IceWorkspace<D>,
    map: NodeCellMap<D>,
    node_pressure: Vec<f64>,
    node_force: Vec<SVector<f64, D>>,
    cell_vec: Vec<SVector<f64, D>>,
    /// Per ICE material: the Lagrangian cell velocity of a solid field
    /// (empty for the fluids).
    particle_velocity: Vec<Vec<SVector<f64, D>>>,
    /// Whether the solids exchange heat (`coupling.heat_exchange > 0`):
    /// only then are temperatures transferred.
    heat_on: bool,
    /// Per node: a field's temperature, then its exchange change.
    node_scalar: Vec<f64>,
    /// Per cell: a field's exchange temperature change.
    cell_scalar: Vec<f64>,
    /// Reactions (solid field → product fluid), applied at the end of each
    /// step ([`reaction`]).
    pub reactions: Vec<reaction::Reaction>,
    burn_scratch: reaction::BurnScratch<D>,
    /// Per cell: the fluids' volume share (the burn's
    /// [`reaction::ProductCells::fluid_share`]).
    burn_share: Vec<f64>,
}

impl<const D: usize> CoupledRun<D> {
    /// Builds a run with one solid field (all `particles`, named
    /// `solid_name`, with the cell EOS `solid_eos`, rigid if
    /// `rigid_velocity` is given): [`Self::with_fields`] with one
    /// [`SolidFieldSpec`].
    ///
    /// # Errors
    /// As [`Self::with_fields`].
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        grid: Grid<D>,
        materials: Vec<SolidMaterial>,
        particles: Particles<D>,
        mpm: ExplicitParams,
        fluid: IceState<D>,
        ice: IceParams<D>,
        solid_name: &str,
        solid_eos: SolidEos,
        rigid_velocity: Option<SVector<f64, D>>,
        coupling: CouplingParams,
        cfl: f64,
    ) -> Result<Self> {
        let field = SolidFieldSpec {
            name: solid_name.to_string(),
            particles,
            eos: solid_eos,
            rigid_velocity,
        };
        Self::with_fields(grid, materials, vec![field], mpm, fluid, ice, coupling, cfl)
    }

    /// Builds a run from the fluid materials' initial state `fluid` and
    /// one or more solid fields, appended in order as ICE materials after
    /// the fluids; `ice.frames` and `ice.normalise_volume` are set and the
    /// exchange coefficients grown: `coupling.momentum_exchange` and
    /// `coupling.heat_exchange` between every solid field and every other
    /// material, solid fields included (Guilkey Eqs. 38–39). The fluid
    /// masses are reduced where the solids' particles occupy a cell
    /// (`1 − Σ θ_s`, with the floor), so the initial material volume fills
    /// every cell.
    ///
    /// # Errors
    /// [`Error::Fluid`] for no solid field, invalid ICE parameters or too
    /// many materials.
    #[allow(clippy::too_many_arguments)]
    pub fn with_fields(
        grid: Grid<D>,
        materials: Vec<SolidMaterial>,
        fields: Vec<SolidFieldSpec<D>>,
        mpm: ExplicitParams,
        mut fluid: IceState<D>,
        mut ice: IceParams<D>,
        coupling: CouplingParams,
        cfl: f64,
    ) -> Result<Self> {
        let nf = fluid.num_materials();
        let nm = nf + fields.len();
        if fields.is_empty() || nm > ice::MAX_MATERIALS {
            return Err(ice::IceError::InvalidInput {
                field: "materials".into(),
                reason: format!(
                    "at least one solid field and at most {} materials in all (got {} fluids, {} \
                     solid fields)",
                    ice::MAX_MATERIALS,
                    nf,
                    fields.len()
                ),
            }
            .into());
        }
        ice.frames = vec![Frame::Eulerian; nm];
        for (i, f) in fields.iter().enumerate() {
            fluid.push_material(ice::IceMaterial::new(&f.name, f.eos));
            ice.frames[nf + i] = if f.rigid_velocity.is_some() {
                Frame::Rigid
            } else {
                Frame::Particles
            };
        }
        // The sharp rigid interface equilibrates on the cell volume when no
        // solid field deforms (`rigid_volume`'s notes).
        let sharp = coupling.rigid_interface == RigidInterface::Sharp;
        ice.normalise_volume = !(sharp && fields.iter().all(|f| f.rigid_velocity.is_some()));
        ice.rigid_faces_sharp = sharp;
        {
            // Grow the coefficient matrices by the solid fields' rows and
            // columns: every pair with a solid field in it exchanges at
            // `coupling.momentum_exchange` / `coupling.heat_exchange`,
            // solid–solid pairs included (Guilkey Eqs. 38–39).
            let ex = ice
                .exchange
                .get_or_insert_with(|| ice::ExchangeCoefficients::uniform(nf, 0.0, 0.0));
            let mut momentum = vec![0.0; nm * nm];
            let mut heat = vec![0.0; nm * nm];
            for r in 0..nm {
                for s in 0..nm {
                    let (m, h) = if r < nf && s < nf {
                        (ex.momentum[r * nf + s], ex.heat[r * nf + s])
                    } else if r != s {
                        (coupling.momentum_exchange, coupling.heat_exchange)
                    } else {
                        (0.0, 0.0)
                    };
                    momentum[r * nm + s] = m;
                    heat[r * nm + s] = h;
                }
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
        let sized = |n: usize| if heat_on { vec![0.0; n] } else { Vec::new() };
        let fields = fields
            .into_iter()
            .enumerate()
            .map(|(i, spec)| {
                let mut particles = spec.particles;
                particles.track_temperature();
                particles.temperature.fill(coupling.solid_temperature);
                SolidField {
                    ice_material: nf + i,
                    particles,
                    eos: spec.eos,
                    rigid_velocity: spec.rigid_velocity,
                    rigid_now: spec.rigid_velocity,
                    gs: GridState::new(n_nodes),
                    scratch: StepScratch::default(),
                    cell_mass: vec![0.0; n_int],
                    cell_velocity: vec![SVector::zeros(); n_int],
                    cell_temp: sized(n_int),
                    implicit: None,
                    implicit_totals: ImplicitTotals::default(),
                }
            })
            .collect();
        let mut run = Self {
            heat_on,
            node_scalar: sized(n_nodes),
            cell_scalar: sized(n_cells),
            map,
            node_pressure: vec![0.0; n_nodes],
            node_force: vec![SVector::zeros(); n_nodes],
            cell_vec: vec![SVector::zeros(); n_cells],
            particle_velocity: (0..nm)
                .map(|r| {
                    if r >= nf {
                        vec![SVector::zeros(); n_cells]
                    } else {
                        Vec::new()
                    }
                })
                .collect(),
            grid,
            materials,
            fields,
            mpm,
            body: None,
            fluid,
            ice,
            rigid_ramp: 0.0,
            coupling,
            cfl,
            steps: 0,
            pressure_s: 0.0,
            last_halvings: 0,
            last_cut: None,
            rigid_work: 0.0,
            reaction_step_energy: 0.0,
            cell_impulse: Vec::new(),
            implicit_totals: ImplicitTotals::default(),
            last_implicit_retries: 0,
            implicit_failed: false,
            failed_field: None,
            iteration: iteration::CouplingIteration::default(),
            fixed_point: iteration::FixedPoint::default(),
            fp_cells: Vec::new(),
            node_w: Vec::new(),
            cell_w_mass: Vec::new(),
            cell_w: Vec::new(),
            ws,
            reactions: Vec::new(),
            burn_scratch: reaction::BurnScratch::default(),
            burn_share: Vec::new(),
        };
        run.initialise()?;
        Ok(run)
    }

    /// Number of fluid materials (the ICE materials before the solid
    /// fields).
    pub fn num_fluids(&self) -> usize {
        self.fields[0].ice_material
    }

    /// All particles of all fields, in field order (a copy, for output).
    pub fn all_particles(&self) -> Particles<D> {
        let mut all = self.fields[0].particles.clone();
        for f in &self.fields[1..] {
            all.append(&f.particles);
        }
        all
    }

    /// Step 1: P2G and node → cell of every field's mass and velocity (and
    /// temperature, with a heat exchange); with [`RigidInterface::Sharp`] a
    /// rigid field's cell mass from its particles' domains.
    fn p2g_to_cells(&mut self, dt: f64) -> Result<()> {
        let phases = phases!(self, dt);
        let sharp = self.coupling.rigid_interface == RigidInterface::Sharp;
        for f in &mut self.fields {
            phases.p2g(&f.particles, &mut f.gs, &mut f.scratch)?;
            nodes_to_cells(
                &f.gs.mass,
                &f.gs.velocity,
                &self.map,
                &mut f.cell_mass,
                &mut f.cell_velocity,
            );
            if self.heat_on {
                let p = &f.particles;
                phases.p2g_scalar(p, &p.temperature, &f.gs, &f.scratch, &mut self.node_scalar);
                nodes_to_cells(
                    &f.gs.mass,
                    &self.node_scalar,
                    &self.map,
                    &mut f.cell_mass,
                    &mut f.cell_temp,
                );
            }
            // After the temperature's transfer, which writes the node
            // average into `cell_mass` again.
            if f.rigid_velocity.is_some() && sharp {
                rigid_volume::box_cell_mass(&self.fluid.layout, &f.particles, &mut f.cell_mass);
            }
        }
        Ok(())
    }

    /// The rigid velocity of field `field` at time `t` (with the ramp;
    /// `None` for a deformable field).
    pub fn rigid_velocity_at(&self, field: usize, t: f64) -> Option<SVector<f64, D>> {
        ramped(self.fields[field].rigid_velocity, self.rigid_ramp, t)
    }

    /// Displacement of rigid field `field` from time 0 to `t` (the integral
    /// of [`Self::rigid_velocity_at`]).
    pub fn rigid_displacement(&self, field: usize, t: f64) -> Option<SVector<f64, D>> {
        let ramp = self.rigid_ramp;
        self.fields[field].rigid_velocity.map(|v| {
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

    /// Sets every rigid field's velocity of the step (at time `t`).
    fn set_rigid_now(&mut self, t: f64) {
        for f in &mut self.fields {
            f.rigid_now = ramped(f.rigid_velocity, self.rigid_ramp, t);
        }
    }

    /// Writes every solid field's cell state from its node → cell mass and
    /// velocity (Guilkey Sec. 3.3 step 1). Where a field is absent (mass at
    /// or below its floor) it keeps the floor mass, moving with (and at the
    /// temperature of) the mass-weighted mixture of the other materials in
    /// the cell, fluids and present solid fields: its exchange then changes
    /// nothing (Eqs. 38–39 with equal velocities).
    fn set_solid_cells(&mut self) {
        let vol = self.fluid.layout.cell_volume();
        let ff = self.coupling.floor_fraction;
        let t_s = self.coupling.solid_temperature;
        let heat_on = self.heat_on;
        let nf = self.num_fluids();
        let (fluids, solids) = self.fluid.cells.split_at_mut(nf);
        let layout = &self.fluid.layout;
        let pressure = &self.fluid.pressure;
        for (i, (f, sc)) in self.fields.iter().zip(solids.iter_mut()).enumerate() {
            let floor = f.floor_mass(ff, vol);
            for (k, &c) in layout.interior.iter().enumerate() {
                let m = f.cell_mass[k];
                let (mass, u, t) = if m > floor {
                    let t = if heat_on { f.cell_temp[k] } else { t_s };
                    (m, f.rigid_now.unwrap_or(f.cell_velocity[k]), t)
                } else {
                    // Even for a rigid field.
                    let (u, t) =
                        others_mixture(fluids, &self.fields, i, (k, c), ff, vol, heat_on, t_s);
                    (floor, u, if heat_on { t } else { t_s })
                };
                let p = pressure[c];
                let p = if p > 0.0 { p } else { self.coupling.p_ref };
                let rho = f.eos.density(p, t).unwrap_or(f.eos.reference_density());
                sc.mass[c] = mass;
                sc.velocity[c] = u;
                sc.temperature[c] = t;
                sc.sp_vol[c] = 1.0 / rho;
            }
        }
    }

    /// Initial state: the fluid volume fractions reduced where the solids
    /// sit, the equilibration pressure and the pressure field.
    fn initialise(&mut self) -> Result<()> {
        self.p2g_to_cells(0.0)?;
        let vol = self.fluid.layout.cell_volume();
        let floor = self.coupling.floor_fraction;
        let nf = self.num_fluids();
        for (k, &c) in self.fluid.layout.interior.iter().enumerate() {
            let p = self.fluid.p_eq[c];
            self.fluid.pressure[c] = p;
            let mut theta_s = 0.0;
            for f in &self.fields {
                let rho_s = f
                    .eos
                    .density(if p > 0.0 { p } else { self.coupling.p_ref }, 300.0)
                    .unwrap_or(f.eos.reference_density());
                theta_s += (f.cell_mass[k] / (rho_s * vol)).min(1.0 - floor);
            }
            let keep = (1.0 - theta_s).max(floor);
            for mc in &mut self.fluid.cells[..nf] {
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

    /// Sets every reaction's time-step limit for the first step (a dry
    /// run of the burn: nothing changes). Called by whoever adds reactions
    /// to a new run.
    pub fn init_reactions(&mut self) {
        let mut exempt = vec![false; self.fluid.num_materials()];
        for r in &self.reactions {
            exempt[r.product] = true;
        }
        self.ice.isothermal_exempt = exempt;
        self.react(0.0);
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
    /// solids' sound speeds included) and the MPM limit of every
    /// deformable field; with the semi-implicit pressure, at most
    /// `max_dt_growth` times the last accepted step, from an acoustic first
    /// step (as a fluid-only run), except with implicit solids.
    pub fn stable_dt(&self) -> f64 {
        let implicit = self.ice.implicit.as_ref();
        let last = self.ws.last_dt();
        // The first step is acoustic, then grows (semi-implicit mode); with
        // implicit solids their Newton control sets the step from
        // `time.dt` on (the temporal-order study halves it from the start).
        let newton = self.fields.iter().any(|f| f.implicit.is_some());
        let factor = implicit.map_or(1.0, |sp| {
            if newton {
                sp.sound_speed_factor
            } else {
                ice::timestep::first_step_factor(sp, last)
            }
        });
        let growth = match (implicit, last) {
            (Some(sp), Some(last)) => sp.max_dt_growth * last,
            _ => f64::INFINITY,
        };
        // Explicit: every material's sound speed (a deformable solid's too:
        // Eq. 29 in cells it shares; not a rigid one's); semi-implicit:
        // advection only (factor 0 by default) — the solid fields stay
        // explicit through `solid_dt`.
        let fluid_dt =
            ice::timestep_with(&self.fluid, self.ice.cfl, factor, &self.ice.rigid_mask());
        // An implicit field: the Δt its Newton control asks for next.
        let solid_dt = self
            .fields
            .iter()
            .filter(|f| f.rigid_velocity.is_none() && !f.particles.is_empty())
            .map(|f| match &f.implicit {
                Some(imp) => imp.dt,
                None => stable_dt(&self.grid, &self.materials, &f.particles, self.cfl),
            })
            .fold(f64::INFINITY, f64::min);
        let burn_dt = self
            .reactions
            .iter()
            .map(|r| r.dt_limit)
            .fold(f64::INFINITY, f64::min);
        fluid_dt.min(solid_dt).min(burn_dt).min(growth)
    }

    /// Accumulated MPM phase times, summed over the fields.
    pub fn phase_times(&self) -> crate::mpm::PhaseTimes {
        let mut t = crate::mpm::PhaseTimes::default();
        for f in &self.fields {
            let s = f.phase_times();
            t.bin_s += s.bin_s;
            t.p2g_s += s.p2g_s;
            t.grid_s += s.grid_s;
            t.g2p_s += s.g2p_s;
        }
        t
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
        let info = self.step_retried(dt)?;
        self.ws.set_last_dt(info.dt);
        self.steps += 1;
        Ok(info)
    }

    /// [`Self::step_inner`], redone with Δt cut by the implicit fields'
    /// `dt_cut` while an implicit solid solve fails (nothing of the failed
    /// attempt is committed), down to their `dt_min`.
    fn step_retried(&mut self, dt: f64) -> Result<StepInfo> {
        let mut dt = dt;
        self.last_implicit_retries = 0;
        loop {
            self.implicit_failed = false;
            match self.step_inner(dt) {
                Err(e) if self.implicit_failed => {
                    let (cut, dt_min) = self
                        .fields
                        .iter()
                        .filter_map(|f| f.implicit.as_ref())
                        .fold((0.5f64, 0.0f64), |(c, m), imp| {
                            (c.max(imp.params.dt_cut), m.max(imp.params.dt_min))
                        });
                    if dt * cut < dt_min {
                        return Err(match e {
                            Error::Numerical { site, what } => Error::Numerical {
                                site,
                                what: format!(
                                    "{what}; the implicit step failed at every Δt down \
                                     to {dt:e}, the smallest allowed"
                                ),
                            },
                            e => e,
                        });
                    }
                    self.last_cut = Some((
                        self.steps,
                        crate::mpm::DtCut {
                            particle: None,
                            what: e.to_string(),
                            dt,
                        },
                    ));
                    dt *= cut;
                    self.implicit_totals.step_retries += 1;
                    self.last_implicit_retries += 1;
                    for imp in self.fields.iter_mut().filter_map(|f| f.implicit.as_mut()) {
                        imp.dt = dt;
                    }
                }
                r => return r,
            }
        }
    }

    /// Makes every deformable field implicit (Newmark/Newton or
    /// quasistatic MPM with `params`, first Δt `dt`): Guilkey's step with
    /// steps 7–9 and 13 solved implicitly under the same pressure terms,
    /// the pressure of steps 2–6 (explicit or semi-implicit) unchanged.
    /// A body force is the caller's to set on each field's run.
    ///
    /// # Errors
    /// Invalid parameters; a field with a reaction (its particles change
    /// in number).
    pub fn make_implicit(&mut self, params: crate::mpm::ImplicitParams, dt: f64) -> Result<()> {
        if let Some(r) = self.reactions.first() {
            return Err(self.fail(format!(
                "field {} reacts: implicit MPM needs a fixed particle set",
                r.field
            )));
        }
        for f in self
            .fields
            .iter_mut()
            .filter(|f| f.rigid_velocity.is_none())
        {
            let mut imp = ImplicitRun::new(
                self.grid.clone(),
                self.materials.clone(),
                f.particles.clone(),
                params,
                f64::INFINITY,
                dt,
            )?;
            imp.particles = Particles::default();
            f.implicit = Some(Box::new(imp));
        }
        let n_int = self.fluid.layout.interior.len();
        self.node_w = vec![SVector::zeros(); self.grid.num_nodes()];
        self.cell_w_mass = vec![0.0; n_int];
        self.cell_w = vec![SVector::zeros(); n_int];
        Ok(())
    }

    /// Holds every quasistatic implicit field's face velocities in the
    /// pressure stage at its cells' velocity, where it fills both cells of
    /// a face ([`ice::IceParams::held_solids`]; scene
    /// `implicit.hold_solid_faces`). Without it the pressure stage moves
    /// the solid's faces by `−Δt ∇p/ρ_s` as if it had no stiffness, and
    /// the gas the exchange locks to them is advected into and through the
    /// solid. Call after [`Self::make_implicit`].
    pub fn hold_solid_faces(&mut self) {
        for f in &self.fields {
            if f.implicit.as_ref().is_some_and(|imp| !imp.params.dynamic) {
                let r = f.ice_material;
                if self.ice.held_solids.len() <= r {
                    self.ice.held_solids.resize(r + 1, false);
                }
                self.ice.held_solids[r] = true;
            }
        }
    }

    /// One step of `dt` (a fixed time step), at most the advective limit
    /// `cfl / max Σ_d |u_d|/h_d` of the cells' velocities (every material,
    /// a rigid one's prescribed velocity too; no sound speed); the pressure
    /// stage may still halve it on a cell emptied by the flux.
    ///
    /// A step past that limit fails the pressure stage's outflow check and
    /// is halved until it passes, at the cost of a pressure stage per
    /// halving: the implicit adiabatic piston at `time.dt` = 1e-3 s (240
    /// cells, 10 m/s, outflow Courant number 2) took 303 steps and 545
    /// halvings; capped at its `cfl` = 0.5, 328 steps and none.
    ///
    /// # Errors
    /// As [`Self::step`].
    pub fn step_exact(&mut self, dt: f64) -> Result<StepInfo> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(self.fail(format!("time step is {dt}")));
        }
        let dt = dt.min(ice::timestep_with(&self.fluid, self.ice.cfl, 0.0, &[]));
        let info = self.step_retried(dt)?;
        self.ws.set_last_dt(info.dt);
        self.steps += 1;
        Ok(info)
    }

    /// The ICE workspace (its carried part is saved in a checkpoint).
    pub fn ice_workspace(&self) -> &IceWorkspace<D> {
        &self.ws
    }

    /// The ICE workspace, to restore its carried part from a checkpoint.
    pub fn ice_workspace_mut(&mut self) -> &mut IceWorkspace<D> {
        &mut self.ws
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

    fn step_inner(&mut self, dt_try: f64) -> Result<StepInfo> {
        let mut dt = dt_try;
        // Step 1: P2G and node → cell (does not change the particles).
        self.p2g_to_cells(dt)?;
        self.set_rigid_now(self.fluid.time + 0.5 * dt);
        self.set_solid_cells();
        // Steps 2–9, once (explicit solids, the staggered implicit step)
        // or as the passes of the coupling iteration ([`iteration`]).
        let iterate =
            self.iteration.max_iterations > 1 && self.fields.iter().any(|f| f.implicit.is_some());
        if iterate {
            self.start_fixed_point();
        }
        let mut pass = 0;
        let info = loop {
            let info = self.pressure_stage(&mut dt, pass == 0)?;
            self.pressure_to_nodes();
            self.solve_fields(info.dt, iterate)?;
            pass += 1;
            if !iterate {
                break info;
            }
            // Relative to ‖w̃‖, or to 1e-9 m/s per cell where the solid
            // is at rest (round-off then sets w̃).
            let v_floor = 1e-9 * (self.fixed_point.w.len().max(1) as f64).sqrt();
            let res = self.fixed_point.update(self.iteration.relaxation, v_floor);
            tracing::debug!(
                step = self.steps,
                pass,
                residual = res,
                cells = self.fixed_point.w.len(),
                "coupling iteration"
            );
            if res <= self.iteration.tolerance {
                break info;
            }
            if pass >= self.iteration.max_iterations {
                self.implicit_failed = true;
                let r = &self.fixed_point.residuals;
                let last: Vec<String> = r[r.len().saturating_sub(4)..]
                    .iter()
                    .map(|x| format!("{x:.3e}"))
                    .collect();
                return Err(self.fail(format!(
                    "the coupling iteration of the implicit step (Δt = {:e}) did not reach \
                     {:e} in {pass} passes; last relative residuals {}",
                    info.dt,
                    self.iteration.tolerance,
                    last.join(", ")
                )));
            }
            self.scatter_fixed_point();
        };
        let dt = info.dt;
        if self.fields.iter().any(|f| f.implicit.is_some()) {
            let t = &mut self.implicit_totals;
            t.steps += 1;
            t.coupling_iterations += pass as u64;
            t.max_coupling_iterations = t.max_coupling_iterations.max(pass as u64);
        }
        let layout = &self.fluid.layout;
        let vol = layout.cell_volume();
        let ff = self.coupling.floor_fraction;
        let phases = phases!(self, dt);
        // Steps 8–11 at the cells (fluid sources, exchange among all
        // materials — Eqs. 38–39 —, specific volume).
        ice::stage_lagrangian(
            &self.fluid,
            &self.ice,
            &mut self.ws,
            dt,
            &self.particle_velocity,
        )?;
        for (fi, f) in self.fields.iter_mut().enumerate() {
            let r = f.ice_material;
            // The field's exchange velocity change, cells → nodes.
            if f.rigid_velocity.is_none() {
                let ul = self.ws.lagrangian_velocity(r);
                let pv = &self.particle_velocity[r];
                for &c in &layout.interior {
                    self.cell_vec[c] = ul[c] - pv[c];
                    self.cell_impulse[fi] += self.cell_vec[c] * self.fluid.cells[r].mass[c];
                }
                cells_to_nodes(&self.grid, layout, &self.cell_vec, &mut self.node_force);
                let inv_dt = 1.0 / dt;
                let floor = self.mpm.mass_floor;
                let gs = &mut f.gs;
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
            // The field's temperature change of the exchange (Guilkey
            // Eq. 39), cells → nodes → particles (Sec. 3.3 step 10),
            // before the particles move. Absent cells contribute nothing.
            // The transfer conserves the field's thermal energy:
            // `Σ_p m_p ΔT_p = Σ_i m_i ΔT_i = Σ_c m_c ΔT_c`.
            if self.heat_on {
                let floor = f.floor_mass(ff, vol);
                let tl = self.ws.lagrangian_temperature(r);
                let t0 = &self.fluid.cells[r].temperature;
                for (k, &c) in layout.interior.iter().enumerate() {
                    self.cell_scalar[c] = if f.cell_mass[k] > floor {
                        tl[c] - t0[c]
                    } else {
                        0.0
                    };
                }
                cells_to_nodes(&self.grid, layout, &self.cell_scalar, &mut self.node_scalar);
                self.grid.mirror_ghosts(&mut self.node_scalar);
                let mut temperature = std::mem::take(&mut f.particles.temperature);
                phases.g2p_add(
                    &f.particles,
                    &self.node_scalar,
                    &f.scratch,
                    &mut temperature,
                );
                f.particles.temperature = temperature;
            }
            // Step 13: G2P.
            if let Some(v) = f.rigid_now {
                // The prescribed motion's work on the field itself: its
                // kinetic energy change.
                let ke0 = f.particles.kinetic_energy();
                f.particles.x.par_iter_mut().for_each(|x| *x += v * dt);
                f.particles.v.par_iter_mut().for_each(|u| *u = v);
                self.rigid_work += f.particles.kinetic_energy() - ke0;
            } else if let Some(imp) = f.implicit.as_deref_mut() {
                // The pending solve to the particles, with the exchange's
                // velocity change (still in `node_force`).
                std::mem::swap(&mut f.particles, &mut imp.particles);
                let res = imp.commit_pending(&self.node_force);
                std::mem::swap(&mut f.particles, &mut imp.particles);
                self.implicit_totals.particles_s += res?.particles_s;
            } else {
                phases.g2p(&mut f.particles, &f.gs, &mut f.scratch, &[])?;
            }
        }
        // Step 12: fluid advection and the commit of the cell state.
        let info = ice::stage_advect(&mut self.fluid, &self.ice, &mut self.ws, info)?;
        // Step 4 (operator split, [`reaction`]): the step's burn, with its
        // Δt and pressure; the next equilibration fits the product in.
        self.react(info.dt);
        Ok(info)
    }

    /// Steps 2–6 (equilibration, face velocities, Δp, face pressure);
    /// on the first pass Δt is halved while the stage fails retryably
    /// (`dt` updated), on a later pass of the coupling iteration such a
    /// failure fails the step (retried by [`Self::step_retried`]).
    fn pressure_stage(&mut self, dt: &mut f64, first: bool) -> Result<StepInfo> {
        let mut tries = 0;
        let start = std::time::Instant::now();
        let res = loop {
            match ice::stage_pressure(&mut self.fluid, &self.ice, &mut self.ws, *dt, true) {
                Ok(info) => break Ok(info),
                Err(e) if first && tries < 20 && e.retry_dt().is_some() => {
                    self.last_cut = Some((
                        self.steps,
                        crate::mpm::DtCut {
                            particle: None,
                            what: format!("the pressure stage: {e}"),
                            dt: *dt,
                        },
                    ));
                    *dt *= 0.5;
                    tries += 1;
                    self.set_rigid_now(self.fluid.time + 0.5 * *dt);
                    self.set_solid_cells();
                }
                Err(e) => {
                    self.implicit_failed = !first && e.retry_dt().is_some();
                    break Err(e.into());
                }
            }
        };
        self.pressure_s += start.elapsed().as_secs_f64();
        if first {
            self.last_halvings = tries;
        }
        res
    }

    /// Cell pressure → nodes (average of the 2^D surrounding cells,
    /// ghosts from the boundary conditions).
    fn pressure_to_nodes(&mut self) {
        let layout = &self.fluid.layout;
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

    /// The coupling iteration's cells (every implicit field's cells above
    /// its trace mass and below [`iteration::ITERATED_FILL`] of the cell)
    /// and its first iterate, their start-of-step velocities (set by
    /// [`Self::set_solid_cells`]).
    fn start_fixed_point(&mut self) {
        let layout = &self.fluid.layout;
        let vol = layout.cell_volume();
        let trace_fraction = self
            .coupling
            .floor_fraction
            .max(self.coupling.trace_fraction);
        self.fp_cells.clear();
        self.fixed_point.w.clear();
        for (fi, f) in self.fields.iter().enumerate() {
            if f.implicit.is_none() {
                continue;
            }
            let trace = f.floor_mass(trace_fraction, vol);
            let full = f.floor_mass(iteration::ITERATED_FILL, vol);
            let sc = &self.fluid.cells[f.ice_material];
            for (k, &c) in layout.interior.iter().enumerate() {
                if f.cell_mass[k] > trace && f.cell_mass[k] < full {
                    self.fp_cells.push((fi, k));
                    self.fixed_point.w.push(sc.velocity[c]);
                }
            }
        }
        self.fixed_point.start();
    }

    /// The relaxed iterate into the solid fields' cell velocities, which
    /// the next pressure stage starts from.
    fn scatter_fixed_point(&mut self) {
        let layout = &self.fluid.layout;
        for (&(fi, k), w) in self.fp_cells.iter().zip(&self.fixed_point.w) {
            let r = self.fields[fi].ice_material;
            self.fluid.cells[r].velocity[layout.interior[k]] = *w;
        }
    }

    /// Steps 7–9 of every solid field under the pressure stage's result
    /// (its force −V θ_s ∇p* and the node pressure): the nodal solve
    /// (rigid, explicit or implicit), node → cell, and the field's
    /// Lagrangian cell velocity for the exchange. With `iterate`, each
    /// implicit field's `vⁿ⁺¹ − Δt F_p/m` (node → cell) goes to the
    /// coupling iteration's new value.
    fn solve_fields(&mut self, dt: f64, iterate: bool) -> Result<()> {
        let layout = &self.fluid.layout;
        let vol = layout.cell_volume();
        let ff = self.coupling.floor_fraction;
        let phases = phases!(self, dt);
        let nf = self.num_fluids();
        // This pass's value (a coupling iteration's last pass stands).
        self.rigid_work = 0.0;
        self.cell_impulse
            .resize(self.fields.len(), SVector::zeros());
        for (fi, f) in self.fields.iter_mut().enumerate() {
            self.failed_field = Some(fi);
            let r = f.ice_material;
            // Step 8: the pressure force −V θ_s ∇p* of each cell on this
            // field, to the nodes, shared among the cell's corners by their
            // mass: node i gets `m_i Σ_c a_c / 2^D` with the cell's
            // acceleration `a_c = F_c / m_c` (`m_c` the corner-mass average
            // of step 1). This is the transpose of the mass-weighted node →
            // cell average, so `Σ_i F_i = Σ_c F_c` and the field's momentum
            // change is the cells' exactly; an equal share per corner
            // dropped the part of a massless corner node at the field's
            // surface (a momentum leak of 3.8e-6 of Σ m|v| in the two-body
            // collision test, and less load on the surface than the cells
            // carry).
            //
            // A quasistatic implicit field has no inertia to take the
            // exchange's velocity change, so the fluids that the exchange
            // locks to it in a cell load it at once: it gets their part of
            // the cell's force too, `−V (θ_s + Σ_f λ_f θ_f) ∇p*` with the
            // locked fraction λ_f = β/(1 + β), β = Δt K_fs θ_s v_f (the
            // two-material exchange against a solid that does not yield).
            // Without it the steel of the pressurised cylinder carried 60 %
            // of the gas load at Δt = 1e-5 s; the same force lagged by a
            // step (the exchange's m dv/Δt) went unstable.
            {
                let pstar = self.ws.face_pressure();
                let cells = &self.fluid.cells;
                let theta = &cells[r].vol_frac;
                let out = &mut self.cell_vec;
                let m_floor = f.floor_mass(ff, vol);
                let locked = f.implicit.as_ref().is_some_and(|imp| !imp.params.dynamic);
                let nm = cells.len();
                let kmom = self.ice.exchange.as_ref().map(|e| &e.momentum[..]);
                for (k, &c) in layout.interior.iter().enumerate() {
                    let m = f.cell_mass[k];
                    out[c] = if m > m_floor {
                        let mut g = SVector::<f64, D>::zeros();
                        for d in 0..D {
                            g[d] = (pstar[d][c + layout.strides[d]] - pstar[d][c]) / layout.h[d];
                        }
                        let mut th = theta[c];
                        if let (true, Some(kk)) = (locked, kmom) {
                            for (fl, mc) in cells.iter().enumerate().take(nf) {
                                let beta = dt * kk[fl * nm + r] * theta[c] * mc.sp_vol[c];
                                th += mc.vol_frac[c] * beta / (1.0 + beta);
                            }
                        }
                        -g * (vol * th / m)
                    } else {
                        SVector::zeros()
                    };
                }
            }
            // The cells' force on the field, `Σ_c F_c Δt` (this pass's).
            self.cell_impulse[fi] = layout
                .interior
                .iter()
                .zip(&f.cell_mass)
                .map(|(&c, &m)| self.cell_vec[c] * (m * dt))
                .sum();
            cells_to_nodes(&self.grid, layout, &self.cell_vec, &mut self.node_force);
            for (fi, &m) in self.node_force.iter_mut().zip(&f.gs.mass) {
                *fi *= m;
            }
            // Steps 7–9 on the field's nodes.
            if let Some(v) = f.rigid_now {
                // The cells' pressure force on the held field, which its
                // prescribed motion takes: its work −Δt U · F.
                let force: SVector<f64, D> = self.node_force.iter().sum();
                self.rigid_work -= dt * v.dot(&force);
                let gs = &mut f.gs;
                for (i, &m) in gs.mass.iter().enumerate() {
                    let u = if m > self.mpm.mass_floor {
                        v
                    } else {
                        SVector::zeros()
                    };
                    gs.velocity_new[i] = u;
                    gs.accel[i] = SVector::zeros();
                }
            } else if let Some(imp) = f.implicit.as_deref_mut() {
                // Implicit MPM (Newmark/Newton or quasistatic) under the
                // same two pressure terms: the cells' force −V θ_s ∇p* as
                // an external nodal force and σ + (p − p_ref) I inside.
                let load = imp.fluid_load.get_or_insert_with(Default::default);
                load.node_force.clone_from(&self.node_force);
                load.node_pressure.clone_from(&self.node_pressure);
                load.p_ref = self.coupling.p_ref;
                imp.t = self.fluid.time;
                imp.steps = self.steps;
                std::mem::swap(&mut f.particles, &mut imp.particles);
                let res = imp.solve_pending(dt).map(|st| {
                    self.implicit_totals.add(st);
                    f.implicit_totals.add(st);
                });
                std::mem::swap(&mut f.particles, &mut imp.particles);
                if let Err(e) = res {
                    self.implicit_failed = true;
                    return Err(e);
                }
                imp.pending_node_velocity(&mut f.gs.velocity_new);
                if iterate {
                    // The field's velocity without the step's pressure
                    // force, which the next pressure stage adds back.
                    let floor = self.mpm.mass_floor;
                    let gs = &f.gs;
                    self.node_w
                        .par_iter_mut()
                        .zip(gs.velocity_new.par_iter())
                        .zip(gs.mass.par_iter().zip(self.node_force.par_iter()))
                        .for_each(|((w, v), (&m, fp))| {
                            *w = if m > floor {
                                v - fp * (dt / m)
                            } else {
                                SVector::zeros()
                            };
                        });
                    nodes_to_cells(
                        &gs.mass,
                        &self.node_w,
                        &self.map,
                        &mut self.cell_w_mass,
                        &mut self.cell_w,
                    );
                    let fp = &mut self.fixed_point;
                    for (wn, &(fj, k)) in fp.w_new.iter_mut().zip(&self.fp_cells) {
                        if fj == fi {
                            *wn = self.cell_w[k];
                        }
                    }
                }
            } else {
                phases.solve(
                    &mut f.particles,
                    &mut f.gs,
                    &mut f.scratch,
                    Some((&self.node_pressure, self.coupling.p_ref)),
                    &self.node_force,
                )?;
            }
            // Node → cell: the field's Lagrangian cell velocity.
            nodes_to_cells(
                &f.gs.mass,
                &f.gs.velocity_new,
                &self.map,
                &mut f.cell_mass,
                &mut f.cell_velocity,
            );
            let pv = &mut self.particle_velocity[r];
            let sc = &self.fluid.cells[r];
            // A trace of the field (below `trace_fraction` of the cell at
            // its reference density: node-mass spill beside its surface)
            // keeps the velocity it was given at the start of the step.
            // Its node-to-cell velocity is that of light surface nodes,
            // whose internal force is not balanced within the cell: in a
            // pure-air cell beside a steel block after a collision, the
            // steel trace (θ = 2.6e-5, yet a quarter of the cell's mass)
            // came out at (359, −480) m/s against the block's (63, −10),
            // and the exchange dragged the air to 1000 m/s within 1 µs;
            // unequal blocks meeting in air failed with negative air
            // temperatures at 0.30 and 0.35 ms (tests/two_solids_in_air.rs).
            // (A rigid field's nodes carry its prescribed velocity: no
            // trace of it is polluted.)
            let floor = f.floor_mass(ff, vol);
            let trace = f.floor_mass(ff.max(self.coupling.trace_fraction), vol);
            for (k, &c) in layout.interior.iter().enumerate() {
                let m = f.cell_mass[k];
                pv[c] = match f.rigid_now {
                    Some(v) if m > floor => v,
                    None if m > trace => f.cell_velocity[k],
                    // Absent or a trace: the velocity it was given.
                    _ => sc.velocity[c],
                };
            }
        }
        self.failed_field = None;
        Ok(())
    }

    /// The index of the fluid material `name` (in `fluid.materials` and
    /// `fluid.cells`), if the run has one.
    pub fn fluid_index(&self, name: &str) -> Option<usize> {
        self.fluid.materials[..self.num_fluids()]
            .iter()
            .position(|m| m.name == name)
    }

    /// The index in `fields` of the solid field of material `name`, if the
    /// run has one.
    pub fn field_index(&self, name: &str) -> Option<usize> {
        self.fields
            .iter()
            .position(|f| self.fluid.materials[f.ice_material].name == name)
    }

    /// What the reactions have done since the start, summed.
    pub fn reaction_totals(&self) -> reaction::ReactionTotals {
        let mut t = reaction::ReactionTotals::default();
        for r in &self.reactions {
            t.mass += r.totals.mass;
            t.energy += r.totals.energy;
            t.heat += r.totals.heat;
        }
        t
    }

    /// The run's account: the total mass and the energies of the fluids in
    /// the cells and of the particles (the solid fields' cell copies are
    /// not counted): kinetic, the fluids' internal plus the particles'
    /// stored and plastic work (in `strain`), and in `potential` minus the
    /// energy the reactions released into the products (the reactant's
    /// internal and kinetic energy and the heat of reaction; the solid is
    /// isothermal and its chemical energy is not otherwise counted), so
    /// that the total is conserved by the exact dynamics.
    pub fn account(&self) -> (f64, crate::stepper::Energies) {
        let nf = self.num_fluids();
        let mut m = 0.0;
        let mut e = crate::stepper::Energies {
            kinetic: 0.0,
            strain: 0.0,
            potential: -self.reaction_totals().energy,
        };
        for (mat, mc) in self.fluid.materials[..nf].iter().zip(&self.fluid.cells) {
            let cv = mat.eos.specific_heat_cv();
            for &c in &self.fluid.layout.interior {
                m += mc.mass[c];
                e.kinetic += 0.5 * mc.mass[c] * mc.velocity[c].norm_squared();
                e.strain += mc.mass[c] * cv * mc.temperature[c];
            }
        }
        for f in &self.fields {
            m += f.particles.total_mass();
            e.kinetic += f.particles.kinetic_energy();
            e.strain += f.particles.strain_energy(&self.materials);
        }
        (m, e)
    }

    /// Whether the momentum account closes: every solid field explicit and
    /// deformable, no damping, no gravity, no reaction and a plane grid (a
    /// held field's impulse, Newmark's update, the damping and gravity on
    /// the nodes, the burn's transfer and r–z's hoop force are not booked).
    pub fn momentum_accounted(&self) -> bool {
        !self.grid.axisymmetric
            && self
                .fields
                .iter()
                .all(|f| f.rigid_velocity.is_none() && f.implicit.is_none())
            && self.mpm.damping == 0.0
            && self.ice.gravity.iter().all(|&g| g == 0.0)
            && self.reactions.is_empty()
    }

    /// What the last step took in from outside the system: the fluids'
    /// flow through the domain boundary and the face pressures' impulse
    /// and work there, the walls' reaction on each solid field, the heat
    /// sources' and the reactions' energy, the prescribed motion's work
    /// (the exchange's part and [`Self::rigid_work`]) and the solids'
    /// damping (the run summary's account,
    /// [`crate::ice::BoundaryExchange`]).
    ///
    /// Momentum: the cells' pressure forces on all materials, solids
    /// included, telescope to the boundary faces' impulse (the ICE part),
    /// and the exchange sums to zero in each cell. A field's particles get
    /// from the grid its own share of each node's change; less the cells'
    /// force and exchange on it ([`Self::cell_impulse`]), what is left is
    /// booked as its walls' reaction (the mirror images' share of the
    /// nodes on a wall). That remainder is inferred, not computed from the
    /// wall nodes alone as the solid-only account's
    /// ([`crate::mpm::wall_reaction`]): it also holds whatever the MPM side
    /// does not conserve (forces dropped on nodes below the mass floor,
    /// the cell → node map at a wall), so the drift checks the cells'
    /// balance (the fluids' change and the cells' forces on the solids add
    /// up to the boundary impulse) and G2P's consistency, not whether the
    /// particles receive what the cells give nor the MPM forces' own
    /// balance. Zero where [`Self::momentum_accounted`] is false.
    pub fn step_inputs(&self) -> ice::BoundaryExchange {
        let mut b = self.ws.boundary_exchange();
        if self.momentum_accounted() {
            let dt = self.ws.last_dt().unwrap_or(0.0);
            let pic = self.mpm.pic_fraction;
            for (f, cell) in self.fields.iter().zip(&self.cell_impulse) {
                let j = f.gs.particle_momentum_change(dt, pic) - cell;
                for d in 0..D {
                    b.momentum[d] += j[d];
                }
            }
        } else {
            b.momentum = [0.0; 3];
            b.body_momentum = [0.0; 3];
        }
        b.prescribed_work += self.rigid_work;
        b.reaction_energy += self.reaction_step_energy;
        b.damping_work += self.fields.iter().map(|f| f.gs.damping_work()).sum::<f64>();
        b
    }

    /// Total mass and energy (kinetic + internal + stored and plastic work)
    /// of [`Self::account`]; with [`Self::reaction_totals`]'s energy the
    /// energy balance of a run.
    pub fn mass_and_energy(&self) -> (f64, f64) {
        let (m, e) = self.account();
        (m, e.kinetic + e.strain)
    }

    /// The reactants' temperature where the solids' is not tracked (no heat
    /// exchange: `[coupling] solid_temperature`), else `None` (their
    /// particles' own).
    fn reactant_temperature(&self) -> Option<f64> {
        (!self.heat_on).then_some(self.coupling.solid_temperature)
    }

    /// Where a reaction limits the next step most, at the current state
    /// ([`reaction::limiting_cell`]); `None` where nothing burns. For the
    /// run loop's diagnostics.
    pub fn burn_limit(&self) -> Option<reaction::BurnLimit> {
        let uniform_t = self.reactant_temperature();
        let mut share = Vec::new();
        self.fluid_share(&mut share);
        let mut best: Option<reaction::BurnLimit> = None;
        for (k, r) in self.reactions.iter().enumerate() {
            let mass = &self.fluid.cells[r.product].mass;
            let found = reaction::limiting_cell(
                &self.fluid.layout,
                &r.law,
                &self.fluid.pressure,
                &self.fields[r.field].particles,
                uniform_t,
                mass,
                &share,
            );
            if let Some((cell, inflow, dt)) = found {
                if best.as_ref().is_none_or(|b| dt < b.dt) {
                    best = Some(reaction::BurnLimit {
                        reaction: k,
                        cell,
                        mass: mass[cell],
                        inflow,
                        dt,
                    });
                }
            }
        }
        best
    }

    /// Per cell into `out`: the fluids' share `φ` of the material volume
    /// `Σ_r M_r v_r` where the particle materials fill the cell, so that its
    /// equilibration normalises on that volume
    /// ([`ice::pressure::normalising_weight`] = 1); 1 elsewhere and
    /// without normalisation (the burn's
    /// [`reaction::ProductCells::fluid_share`]).
    fn fluid_share(&self, out: &mut Vec<f64>) {
        let state = &self.fluid;
        let vol = state.layout.cell_volume();
        out.clear();
        out.resize(state.layout.len(), 1.0);
        if !self.ice.normalise_volume {
            return;
        }
        for &c in &state.layout.interior {
            let (mut solid, mut fluid) = (0.0, 0.0);
            for (r, mc) in state.cells.iter().enumerate() {
                let mv = mc.mass[c] * mc.sp_vol[c];
                if self.ice.frame(r) == ice::Frame::Eulerian {
                    fluid += mv;
                } else {
                    solid += mv;
                }
            }
            if ice::pressure::normalising_weight(solid, vol) >= 1.0 {
                out[c] = fluid / (fluid + solid);
            }
        }
    }

    /// Applies every reaction's surface burn over a step of `dt`.
    fn react(&mut self, dt: f64) {
        let uniform_t = self.reactant_temperature();
        let mut share = std::mem::take(&mut self.burn_share);
        self.fluid_share(&mut share);
        self.reaction_step_energy = 0.0;
        for r in &mut self.reactions {
            let product_cv = self.fluid.materials[r.product].eos.specific_heat_cv();
            let pc = &mut self.fluid.cells[r.product];
            let mut cells = reaction::ProductCells {
                mass: &mut pc.mass,
                velocity: &mut pc.velocity,
                temperature: &mut pc.temperature,
                sp_vol: &mut pc.sp_vol,
                fluid_share: &share,
                cv: product_cv,
            };
            let (step, dt_limit) = reaction::burn(
                &self.fluid.layout,
                &r.law,
                r.reactant_cv,
                &self.materials,
                dt,
                &self.fluid.pressure,
                &mut self.fields[r.field].particles,
                uniform_t,
                &mut cells,
                &mut self.burn_scratch,
            );
            r.dt_limit = dt_limit;
            r.totals.mass += step.mass;
            r.totals.energy += step.energy;
            r.totals.heat += step.heat;
            self.reaction_step_energy += step.energy;
        }
        self.burn_share = share;
        self.mark_fed_cells();
    }

    /// Sets [`ice::IceParams::isothermal_exempt_cells`] to the cells the
    /// reactions feed and burn in at the current state (a dry run of their
    /// rates, [`reaction::mark_fed`]), so that a product is not held
    /// isothermal where the burn feeds it or will soon (held isothermal
    /// in the burning cells too, the very fast burn of `tests/reaction.rs`
    /// balanced its energy to −4.3e-2 instead of −6.1e-3), and is
    /// elsewhere. A function of the state alone, so that a restart sets the
    /// same cells.
    pub fn mark_fed_cells(&mut self) {
        let uniform_t = self.reactant_temperature();
        let mut fed = std::mem::take(&mut self.ice.isothermal_exempt_cells);
        fed.clear();
        fed.resize(self.fluid.layout.len(), false);
        for r in &self.reactions {
            reaction::mark_fed(
                &self.fluid.layout,
                &r.law,
                &self.fluid.pressure,
                &self.fields[r.field].particles,
                uniform_t,
                &mut self.burn_scratch,
                &mut fed,
            );
        }
        self.ice.isothermal_exempt_cells = fed;
    }
}

/// Mass-weighted velocity and temperature in interior cell `c` (index `k`
/// among the interior cells) of every material but solid field `skip`: the
/// fluids and the solid fields present there (mass above their floor).
/// What an absent field's floor takes, so that its exchange changes
/// nothing (Guilkey Eqs. 38–39 with equal velocities and temperatures).
#[allow(clippy::too_many_arguments)]
fn others_mixture<const D: usize>(
    fluids: &[ice::MaterialCells<D>],
    fields: &[SolidField<D>],
    skip: usize,
    (k, c): (usize, usize),
    floor_fraction: f64,
    vol: f64,
    heat_on: bool,
    t_s: f64,
) -> (SVector<f64, D>, f64) {
    let mut m = 0.0;
    let mut p = SVector::<f64, D>::zeros();
    let mut mt = 0.0;
    for mc in fluids {
        m += mc.mass[c];
        p += mc.velocity[c] * mc.mass[c];
        mt += mc.temperature[c] * mc.mass[c];
    }
    for (j, g) in fields.iter().enumerate() {
        let mg = g.cell_mass[k];
        if j != skip && mg > g.floor_mass(floor_fraction, vol) {
            let t = if heat_on { g.cell_temp[k] } else { t_s };
            m += mg;
            p += g.rigid_now.unwrap_or(g.cell_velocity[k]) * mg;
            mt += t * mg;
        }
    }
    if m > 0.0 {
        (p / m, mt / m)
    } else {
        (SVector::zeros(), t_s)
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
