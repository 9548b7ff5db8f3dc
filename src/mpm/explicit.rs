//! The explicit MPM step (Guilkey Sec. 3.2, Eqs. 21–27).
//!
//! One step is P2G (Eq. 22, internal force Eq. 24), the grid solve
//! M a = f_ext − f_int (Eq. 21, 25) with boundary conditions, and G2P
//! (Eqs. 26–27, FLIP velocity update) with the particle velocity gradient
//! (Eq. 23) driving the constitutive update. The three classic orderings:
//!
//! * **USL** (update stress last): stress from the updated grid velocity vᴸ.
//! * **MUSL** (modified USL): the updated particle momenta are mapped to the
//!   grid again and the stress uses that velocity.
//! * **USF** (update stress first): stress from the P2G velocity before the
//!   force is computed.
//!
//! All weights of a step are evaluated at the particle positions at the start
//! of the step; positions move at the end.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use nalgebra::{Matrix3, SMatrix, SVector};
use rayon::prelude::*;

use super::nonlocal_damage::NonlocalDamage;
use super::particles::Particles;
use super::scatter::{Bins, SharedMut};
use super::wall_reaction::WallRecord;
use crate::error::{Error, FailureSite, Result};
use crate::grid::{Grid, GHOST};
use crate::material::failure::failed_stress;
use crate::material::plasticity::PlasticState;
use crate::material::{GasInput, PointState, SolidMaterial};
use crate::shape::{
    CubicBspline, Gimp, LinearHat, ParticleWeights, QuadraticBspline, QuadraticBsplineGimp,
    ShapeKind, Stencil,
};

/// Ordering of stress update and momentum update in an explicit step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UpdateScheme {
    /// Update stress first.
    Usf,
    /// Update stress last.
    Usl,
    /// Modified update stress last.
    Musl,
}

impl UpdateScheme {
    /// Names accepted in scene files.
    pub const NAMES: &'static str = "usf, usl, musl";
}

/// A body force per unit mass, possibly varying in space and time (gravity, or
/// the body force of a manufactured solution).
pub trait BodyForce<const D: usize>: Sync {
    /// Acceleration at reference position `x0`, current position `x`, time `t`.
    fn accel(&self, x0: &SVector<f64, D>, x: &SVector<f64, D>, t: f64) -> SVector<f64, D>;
    /// The acceleration if it is the same everywhere and always (sums
    /// over the particles then need only their masses).
    fn uniform(&self) -> Option<SVector<f64, D>> {
        None
    }
}

/// A uniform body force (gravity).
#[derive(Debug, Clone, Copy)]
pub struct Uniform<const D: usize>(pub SVector<f64, D>);

impl<const D: usize> BodyForce<D> for Uniform<D> {
    fn accel(&self, _: &SVector<f64, D>, _: &SVector<f64, D>, _: f64) -> SVector<f64, D> {
        self.0
    }
    fn uniform(&self) -> Option<SVector<f64, D>> {
        Some(self.0)
    }
}

/// Parameters of the explicit MPM step.
#[derive(Debug, Clone, Copy)]
pub struct ExplicitParams {
    /// Shape function.
    pub shape: ShapeKind,
    /// Stress update ordering.
    pub scheme: UpdateScheme,
    /// Nodes with less mass than this are treated as empty.
    pub mass_floor: f64,
    /// Mass-proportional damping α ≥ 0 [1/s]: the grid momentum equation
    /// becomes m a = f − α m v, time-centred (drives a solid to its
    /// quasistatic state; 0 = off).
    pub damping: f64,
    /// PIC share β ∈ [0, 1] of the particle velocity update: v_p ← (1 − β)
    /// (v_p + Δt Σ S a_i) + β Σ S v_i (0: FLIP, Eq. 26; 1: PIC). A share
    /// β damps the particle velocities the grid cannot see (the null space
    /// of the grid-to-particle map) by the factor 1 − β a step. A gas
    /// point's kinetic energy lost to the blend becomes its internal
    /// energy; a solid's is dissipated.
    pub pic_fraction: f64,
}

/// Node fields of the background grid (ghost nodes included).
#[derive(Debug, Clone)]
pub struct GridState<const D: usize> {
    /// Nodal mass M_i (Eq. 22).
    pub mass: Vec<f64>,
    /// Nodal momentum Σ S m v.
    pub momentum: Vec<SVector<f64, D>>,
    /// Nodal velocity v_i at the start of the step.
    pub velocity: Vec<SVector<f64, D>>,
    /// Updated nodal velocity vᴸ (Eq. 25).
    pub velocity_new: Vec<SVector<f64, D>>,
    /// Nodal acceleration a_i after boundary conditions. Until the grid
    /// solve it holds the nodal force f_ext − f_int, which P2G sums into
    /// it; the solve reads the force and writes a_i in its place, one node
    /// at a time (the force is not read after the solve, so the two share
    /// one array: 16 bytes a node less in 2D).
    pub accel: Vec<SVector<f64, D>>,
    /// The particles' own fields on the nodes the wall fold touches, for
    /// the walls' reaction ([`GridState::wall_impulse`]).
    walls: WallRecord<D>,
    /// Gas points that read their density from the grid
    /// ([`crate::material::PointDensity::Grid`]): their nodal mass, folded
    /// like `mass` (empty when no material does).
    gas_mass: Vec<f64>,
    /// Their nodal density `gas_mass / node_volume`, ghosts mirrored.
    gas_density: Vec<f64>,
    /// Each node's share of the domain as the points sample it
    /// ([`node_volumes`]); empty until a step needs it.
    node_volume: Vec<f64>,
    /// The work of the mass-proportional damping (`ExplicitParams::damping`)
    /// in the last grid solve, `−α Δt Σ_i m_i^r |v̄_i|²` with `v̄` the
    /// step's time-centred nodal velocity and `m^r` the particles' own
    /// nodal mass ([`GridState::damping_work`]); 0 without damping.
    damping_work: f64,
}

impl<const D: usize> GridState<D> {
    /// Zeroed fields for `n` nodes.
    pub fn new(n: usize) -> Self {
        Self {
            mass: vec![0.0; n],
            momentum: vec![SVector::zeros(); n],
            velocity: vec![SVector::zeros(); n],
            velocity_new: vec![SVector::zeros(); n],
            accel: vec![SVector::zeros(); n],
            walls: WallRecord::default(),
            gas_mass: Vec::new(),
            gas_density: Vec::new(),
            node_volume: Vec::new(),
            damping_work: 0.0,
        }
    }

    /// The work the mass-proportional damping did on the particles in the
    /// last grid solve (≤ 0; 0 without damping). The damped update
    /// `vᴸ = (v (1 − αΔt/2) + Δt f/m)/(1 + αΔt/2)` differs from the
    /// undamped `v + Δt f/m` by `−α Δt v̄`, `v̄ = (v + vᴸ)/2`; its work on
    /// the nodes is `−α Δt Σ m |v̄|²`, with the real particles' mass on the
    /// nodes the wall fold doubles ([`WallRecord`]). The particles' FLIP
    /// update takes it to first order; the run summary books it as energy
    /// taken out.
    pub fn damping_work(&self) -> f64 {
        self.damping_work
    }

    /// The momentum the last step's G2P (PIC share `pic`) gave the
    /// particles, from the grid: the particles' own share of every node's
    /// `m a Δt` (FLIP) or `m vᴸ − p` (PIC), the fold's images left out
    /// ([`WallRecord`]). A coupled run takes the cells' forces and the
    /// exchange off it to find the walls' reaction.
    pub fn particle_momentum_change(&self, dt: f64, pic: f64) -> SVector<f64, D> {
        self.walls.particle_momentum_change(
            &self.mass,
            &self.momentum,
            &self.accel,
            &self.velocity_new,
            dt,
            pic,
        )
    }

    /// The impulse the fixed walls and symmetry planes gave the particles
    /// in the last step of `dt` with PIC share `pic`
    /// ([`super::wall_reaction`]): zero without such faces. Valid after a
    /// complete explicit step (its P2G recorded the unfolded fields).
    pub fn wall_impulse(&self, dt: f64, pic: f64) -> SVector<f64, D> {
        self.walls.impulse(&self.accel, &self.velocity_new, dt, pic)
    }

    /// Kinetic energy on the nodes after the step, ½ Σ m_i |vᴸ_i|², over
    /// every node (the fold leaves no mass on the ghosts beyond walls and
    /// symmetry planes). FLIP points can carry velocities the grid does not
    /// see (the null space of the grid-to-particle map); their own kinetic
    /// energy counts those, this does not.
    pub fn kinetic_energy(&self) -> f64 {
        super::particles::kinetic_energy(&self.mass, &self.velocity_new)
    }
}

/// Wall time spent in each phase of the explicit step, accumulated over steps.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct PhaseTimes {
    /// Binning particles into slabs.
    pub bin_s: f64,
    /// Particle-to-grid transfers (all P2G passes of a step).
    pub p2g_s: f64,
    /// Grid clearing, boundary folding and the nodal momentum equation.
    pub grid_s: f64,
    /// Grid-to-particle transfers and the constitutive update.
    pub g2p_s: f64,
}

/// Reusable buffers of the step (no allocation inside the time loop).
#[derive(Debug, Clone, Default)]
pub struct StepScratch<const D: usize> {
    bins: Bins,
    dx: Vec<SVector<f64, D>>,
    /// GIMP half-widths (cell units) of the step, frozen at its start so
    /// every transfer of the step uses the same particle domains.
    lp: Vec<SVector<f64, D>>,
    /// The nonlocal damage average's buffers.
    nonlocal: NonlocalDamage<D>,
    /// Accumulated phase timings.
    pub times: PhaseTimes,
}

/// Largest stable explicit timestep times `cfl`: min over particles of
/// h_min / (c_p + |v_p|), c_p the dilatational wave speed at the particle's
/// current density; a gas point adds its viscous and artificial-viscosity
/// diffusion limit ([`crate::material::GasPoint::dt_limit`]).
pub fn stable_dt<const D: usize>(
    grid: &Grid<D>,
    materials: &[SolidMaterial],
    particles: &Particles<D>,
    cfl: f64,
) -> f64 {
    stable_dt_stiffened(grid, materials, particles, cfl, &[])
}

/// [`stable_dt`] with each particle's signal speed raised by `√s_p`
/// (`stiffening[p]`; missing entries count as 1): the multiphase closure's
/// stiffening of a gas that is a small part of the mixture.
pub fn stable_dt_stiffened<const D: usize>(
    grid: &Grid<D>,
    materials: &[SolidMaterial],
    particles: &Particles<D>,
    cfl: f64,
    stiffening: &[f64],
) -> f64 {
    let hmin = grid.h.min();
    let c_max = gas_sound_speed_max(materials, particles);
    let limit = (0..particles.len())
        .into_par_iter()
        .map(|p| particle_dt_limit(materials, particles, stiffening, hmin, c_max, p))
        .reduce(|| f64::INFINITY, f64::min);
    cfl * limit
}

/// Particle `p`'s limit of [`stable_dt_stiffened`] before the Courant
/// number: its material's `dt_limit` at the smallest cell size `hmin` (gas
/// points' `c_max` from [`gas_sound_speed_max`]) over `√stiffening[p]`
/// where `stiffening` has an entry for it.
#[inline(always)]
pub fn particle_dt_limit<const D: usize>(
    materials: &[SolidMaterial],
    particles: &Particles<D>,
    stiffening: &[f64],
    hmin: f64,
    c_max: f64,
    p: usize,
) -> f64 {
    let state = PointState {
        mass: particles.mass[p],
        vol: particles.vol[p],
        vol0: particles.vol0[p],
        work: particles.work_of(p),
        stress: &particles.stress.get(p),
        speed: particles.v[p].norm(),
    };
    let limit = materials[particles.material[p] as usize].dt_limit(hmin, &state, c_max);
    match stiffening.get(p) {
        Some(s) => limit / s.sqrt(),
        None => limit,
    }
}

/// The largest sound speed among the gas points (York Eq. 24's `c_max`);
/// 0 when there are none (no pass over the particles then).
pub fn gas_sound_speed_max<const D: usize>(
    materials: &[SolidMaterial],
    particles: &Particles<D>,
) -> f64 {
    if materials.iter().all(|m| m.gas().is_none()) {
        return 0.0;
    }
    (0..particles.len())
        .into_par_iter()
        .with_min_len(512)
        .map(|p| match materials[particles.material[p] as usize].gas() {
            Some(g) => {
                let rho = particles.mass[p] / particles.vol[p];
                let e = particles.work_of(p) * particles.vol0[p] / particles.mass[p];
                g.sound_speed(rho, e)
            }
            None => 0.0,
        })
        .reduce(|| 0.0, f64::max)
}

/// Advances particles and grid by one explicit step of size `dt` from time `t`.
///
/// `step` is only used to name the step in errors. `tangent` holds the unit
/// tangent of every membrane point (York Sec. 3.2; zero for other
/// particles), or is empty when the run has no membranes.
#[allow(clippy::too_many_arguments)]
pub fn explicit_step<const D: usize>(
    grid: &Grid<D>,
    materials: &[SolidMaterial],
    params: &ExplicitParams,
    body: Option<&dyn BodyForce<D>>,
    tangent: &[SVector<f64, D>],
    particles: &mut Particles<D>,
    gs: &mut GridState<D>,
    scratch: &mut StepScratch<D>,
    t: f64,
    dt: f64,
    step: u64,
) -> Result<()> {
    let ctx = Ctx {
        grid,
        materials,
        params,
        body,
        t,
        dt,
        step,
        pressure: None,
        tangent,
        vol_rate: &[],
    };
    // The geometry is hoisted out of every loop: each pass is compiled once
    // for plane strain (no hoop terms, no extra work) and once for r–z.
    if grid.axisymmetric {
        step_shape::<D, true>(&ctx, particles, gs, scratch)
    } else {
        step_shape::<D, false>(&ctx, particles, gs, scratch)
    }
}

fn step_shape<const D: usize, const AXI: bool>(
    ctx: &Ctx<'_, D>,
    particles: &mut Particles<D>,
    gs: &mut GridState<D>,
    scratch: &mut StepScratch<D>,
) -> Result<()> {
    match ctx.params.shape {
        ShapeKind::Linear => step_with::<D, 2, _, AXI>(ctx, LinearHat, particles, gs, scratch),
        ShapeKind::Gimp => step_with::<D, 3, _, AXI>(ctx, Gimp, particles, gs, scratch),
        ShapeKind::QuadraticBspline => {
            step_with::<D, 3, _, AXI>(ctx, QuadraticBspline, particles, gs, scratch)
        }
        ShapeKind::CubicBspline => {
            step_with::<D, 4, _, AXI>(ctx, CubicBspline, particles, gs, scratch)
        }
        ShapeKind::QuadraticBsplineGimp => {
            step_with::<D, 4, _, AXI>(ctx, QuadraticBsplineGimp, particles, gs, scratch)
        }
    }
}

struct Ctx<'a, const D: usize> {
    grid: &'a Grid<D>,
    materials: &'a [SolidMaterial],
    params: &'a ExplicitParams,
    body: Option<&'a dyn BodyForce<D>>,
    t: f64,
    dt: f64,
    step: u64,
    /// Coupled MPM-ICE: the nodal pressure and `p_ref`; the internal force
    /// then uses `σ + (p − p_ref) I` (Guilkey Sec. 3.3 step 7).
    pressure: Option<(&'a [f64], f64)>,
    /// Unit tangents of the membrane points (York Sec. 3.2), or empty.
    tangent: &'a [SVector<f64, D>],
    /// Multiphase (Zhang Eqs. 1–2): a volumetric strain rate per particle
    /// added to the trace of its velocity gradient, spread evenly over the
    /// D in-plane diagonal entries; empty for none.
    vol_rate: &'a [f64],
}

impl<const D: usize> Ctx<'_, D> {
    fn fail(&self, particle: Option<usize>, cell: Option<usize>, what: &str) -> Error {
        Error::Numerical {
            site: FailureSite {
                step: self.step,
                time: self.t,
                particle,
                cell,
            },
            what: what.to_string(),
        }
    }
}

// G2P variants, as const-generic parameters so that each pass compiles to
// its own loop without per-node branches.
/// Position update: none.
const POS_NONE: u8 = 0;
/// x += Δt Σ S vᴸ now (Eq. 27).
const POS_APPLY: u8 = 1;
/// Store Δt Σ S vᴸ for later (MUSL).
const POS_STORE: u8 = 2;
/// Apply the stored displacement (MUSL).
const POS_APPLY_STORED: u8 = 3;
/// No velocity gradient / stress update.
const GRAD_NONE: u8 = 0;
/// Stress from the gradient of vᴸ (USL).
const GRAD_VEL_NEW: u8 = 1;
/// Stress from the gradient of the latest P2G velocity (USF, MUSL).
const GRAD_VEL: u8 = 2;

fn step_with<const D: usize, const S: usize, K: Stencil<S>, const AXI: bool>(
    ctx: &Ctx<'_, D>,
    kernel: K,
    particles: &mut Particles<D>,
    gs: &mut GridState<D>,
    scratch: &mut StepScratch<D>,
) -> Result<()> {
    let mut clock = Instant::now();
    let mut lap = |slot: &mut f64| {
        let now = Instant::now();
        *slot += (now - clock).as_secs_f64();
        clock = now;
    };
    let mut t = scratch.times;
    prepare(ctx, particles, scratch)?;
    lap(&mut t.bin_s);
    let bins = &scratch.bins;
    let dx = &mut scratch.dx;
    let nl = &mut scratch.nonlocal;
    let lp = &scratch.lp;
    match ctx.params.scheme {
        UpdateScheme::Usl => {
            clear(gs);
            lap(&mut t.grid_s);
            p2g::<D, S, K, true, true, true, AXI>(ctx, kernel, bins, lp, particles, gs);
            lap(&mut t.p2g_s);
            grid_solve(ctx, gs);
            lap(&mut t.grid_s);
            g2p::<D, S, K, true, POS_APPLY, GRAD_VEL_NEW, AXI>(
                ctx, kernel, lp, particles, gs, dx, nl,
            )?;
            lap(&mut t.g2p_s);
        }
        UpdateScheme::Musl => {
            clear(gs);
            lap(&mut t.grid_s);
            p2g::<D, S, K, true, true, true, AXI>(ctx, kernel, bins, lp, particles, gs);
            lap(&mut t.p2g_s);
            grid_solve(ctx, gs);
            lap(&mut t.grid_s);
            g2p::<D, S, K, true, POS_STORE, GRAD_NONE, AXI>(
                ctx, kernel, lp, particles, gs, dx, nl,
            )?;
            lap(&mut t.g2p_s);
            // Map the updated momenta back (Sulsky's modified USL).
            gs.momentum
                .par_iter_mut()
                .for_each(|m| *m = SVector::zeros());
            lap(&mut t.grid_s);
            p2g::<D, S, K, false, true, false, AXI>(ctx, kernel, bins, lp, particles, gs);
            lap(&mut t.p2g_s);
            grid_velocity(ctx, gs);
            lap(&mut t.grid_s);
            g2p::<D, S, K, false, POS_APPLY_STORED, GRAD_VEL, AXI>(
                ctx, kernel, lp, particles, gs, dx, nl,
            )?;
            lap(&mut t.g2p_s);
        }
        UpdateScheme::Usf => {
            clear(gs);
            lap(&mut t.grid_s);
            p2g::<D, S, K, true, true, false, AXI>(ctx, kernel, bins, lp, particles, gs);
            lap(&mut t.p2g_s);
            grid_velocity(ctx, gs);
            lap(&mut t.grid_s);
            g2p::<D, S, K, false, POS_NONE, GRAD_VEL, AXI>(ctx, kernel, lp, particles, gs, dx, nl)?;
            lap(&mut t.g2p_s);
            p2g::<D, S, K, false, false, true, AXI>(ctx, kernel, bins, lp, particles, gs);
            lap(&mut t.p2g_s);
            grid_solve(ctx, gs);
            lap(&mut t.grid_s);
            g2p::<D, S, K, true, POS_APPLY, GRAD_NONE, AXI>(
                ctx, kernel, lp, particles, gs, dx, nl,
            )?;
            lap(&mut t.g2p_s);
        }
    }
    scratch.times = t;
    Ok(())
}

/// The explicit MPM step split into the three phases that the coupled
/// MPM-ICE step interleaves with the cell equations (Guilkey Sec. 3.3):
/// [`CoupledMpm::p2g`] (step 1), [`CoupledMpm::solve`] (steps 7–9 on the
/// nodes, with the cell pressure) and [`CoupledMpm::g2p`] (step 13). USF
/// updates the stress at the start of `solve` from the P2G velocity; USL in
/// `g2p` from the final grid velocity. MUSL is not offered here.
pub struct CoupledMpm<'a, const D: usize> {
    /// Background grid.
    pub grid: &'a Grid<D>,
    /// Solid materials.
    pub materials: &'a [SolidMaterial],
    /// Discretisation choices.
    pub params: &'a ExplicitParams,
    /// Body force per unit mass.
    pub body: Option<&'a dyn BodyForce<D>>,
    /// Time at the start of the step.
    pub t: f64,
    /// Time step.
    pub dt: f64,
    /// Step number (for errors).
    pub step: u64,
}

macro_rules! with_kernel {
    // `$f::<D, S, K, $g…>`: a pass with more generic parameters after the
    // kernel's.
    ($shape:expr, $f:ident::<$($g:ty),+>, $($arg:expr),*) => {
        match $shape {
            ShapeKind::Linear => $f::<D, 2, _, $($g),+>(LinearHat, $($arg),*),
            ShapeKind::Gimp => $f::<D, 3, _, $($g),+>(Gimp, $($arg),*),
            ShapeKind::QuadraticBspline => $f::<D, 3, _, $($g),+>(QuadraticBspline, $($arg),*),
            ShapeKind::CubicBspline => $f::<D, 4, _, $($g),+>(CubicBspline, $($arg),*),
            ShapeKind::QuadraticBsplineGimp => {
                $f::<D, 4, _, $($g),+>(QuadraticBsplineGimp, $($arg),*)
            }
        }
    };
    ($shape:expr, $f:ident, $($arg:expr),*) => {
        match $shape {
            ShapeKind::Linear => $f::<D, 2, _>(LinearHat, $($arg),*),
            ShapeKind::Gimp => $f::<D, 3, _>(Gimp, $($arg),*),
            ShapeKind::QuadraticBspline => $f::<D, 3, _>(QuadraticBspline, $($arg),*),
            ShapeKind::CubicBspline => $f::<D, 4, _>(CubicBspline, $($arg),*),
            ShapeKind::QuadraticBsplineGimp => $f::<D, 4, _>(QuadraticBsplineGimp, $($arg),*),
        }
    };
}

/// [`with_kernel!`] for passes that differ in r–z: `$f::<D, S, K, AXI>`
/// with `AXI = $axi` (the grid's `axisymmetric`), so that each compiles
/// once for plane geometry and once for r–z.
macro_rules! with_kernel_axi {
    ($shape:expr, $axi:expr, $f:ident, $($arg:expr),*) => {
        if $axi {
            with_kernel_axi!(@k $shape, true, $f, $($arg),*)
        } else {
            with_kernel_axi!(@k $shape, false, $f, $($arg),*)
        }
    };
    (@k $shape:expr, $a:literal, $f:ident, $($arg:expr),*) => {
        match $shape {
            ShapeKind::Linear => $f::<D, 2, _, $a>(LinearHat, $($arg),*),
            ShapeKind::Gimp => $f::<D, 3, _, $a>(Gimp, $($arg),*),
            ShapeKind::QuadraticBspline => $f::<D, 3, _, $a>(QuadraticBspline, $($arg),*),
            ShapeKind::CubicBspline => $f::<D, 4, _, $a>(CubicBspline, $($arg),*),
            ShapeKind::QuadraticBsplineGimp => {
                $f::<D, 4, _, $a>(QuadraticBsplineGimp, $($arg),*)
            }
        }
    };
}

impl<const D: usize> CoupledMpm<'_, D> {
    fn ctx<'b>(&'b self, pressure: Option<(&'b [f64], f64)>) -> Ctx<'b, D> {
        Ctx {
            grid: self.grid,
            materials: self.materials,
            params: self.params,
            body: self.body,
            t: self.t,
            dt: self.dt,
            step: self.step,
            pressure,
            tangent: &[],
            vol_rate: &[],
        }
    }

    /// Step 1: bins the particles, freezes the GIMP domains and maps mass
    /// and momentum to the nodes (Guilkey Eq. 22, mirror folding at walls);
    /// sets the nodal velocity `v = p/m`. Does not change the particles.
    ///
    /// # Errors
    /// A particle off the grid or not finite.
    pub fn p2g(
        &self,
        particles: &Particles<D>,
        gs: &mut GridState<D>,
        scratch: &mut StepScratch<D>,
    ) -> Result<()> {
        fn run<const D: usize, const S: usize, K: Stencil<S>>(
            kernel: K,
            ctx: &Ctx<'_, D>,
            particles: &Particles<D>,
            gs: &mut GridState<D>,
            scratch: &mut StepScratch<D>,
        ) -> Result<()> {
            let start = Instant::now();
            prepare(ctx, particles, scratch)?;
            clear(gs);
            p2g::<D, S, K, true, true, false, false>(
                ctx,
                kernel,
                &scratch.bins,
                &scratch.lp,
                particles,
                gs,
            );
            grid_velocity(ctx, gs);
            scratch.times.p2g_s += start.elapsed().as_secs_f64();
            Ok(())
        }
        let ctx = self.ctx(None);
        with_kernel!(self.params.shape, run, &ctx, particles, gs, scratch)
    }

    /// The nodal gradient of the particle mass, `Σ_p m_p ∇S_ip` (Lian
    /// Eq. 51; Bardenhagen et al. 2000). `∇S_ip` is the gradient in the
    /// particle's position, so at a node outside the body, where `S_i`
    /// falls off towards the particles, the sum points from the body to the
    /// node: the body's outward normal. Uses this step's bins and
    /// particle domains (call [`Self::p2g`] first). Not folded at walls (a
    /// mirror image's gradient reflects unlike a velocity at a fixed wall):
    /// on wall nodes it is the one-sided sum.
    pub fn mass_gradient(
        &self,
        particles: &Particles<D>,
        scratch: &StepScratch<D>,
        node: &mut [SVector<f64, D>],
    ) {
        self.weighted_gradient(particles, &particles.mass, scratch, node);
    }

    /// `Σ_p w_p ∇S_ip` on the nodes for particle weights `w` (the mass:
    /// [`Self::mass_gradient`]; Zhang's volume gradient, with its r–z hoop
    /// part, is [`Self::volume_gradient`]). Unfolded, with this step's bins
    /// and domains (call [`Self::p2g`] first).
    pub fn weighted_gradient(
        &self,
        particles: &Particles<D>,
        weights: &[f64],
        scratch: &StepScratch<D>,
        node: &mut [SVector<f64, D>],
    ) {
        self.gradient_sum(particles, weights, false, scratch, node);
    }

    /// The phase's volume gradient `g_i = Σ_p v_p ∇S_ip` (≈ `−∫ θ ∇S_i`,
    /// Zhang's pressure term), and in r–z `Σ_p v_p (∇S_ip + S_ip/r_p e_r)`:
    /// the nodal force of a unit pressure `−∫ θ ∇·(S_i I)` there carries the
    /// hoop part `S_i / r` of the divergence (the kernels' hoop term with
    /// `σ = −I`), without which a uniform pressure would push every node
    /// off the axis. Unfolded, with this step's bins and domains.
    pub fn volume_gradient(
        &self,
        particles: &Particles<D>,
        scratch: &StepScratch<D>,
        node: &mut [SVector<f64, D>],
    ) {
        let hoop = self.grid.axisymmetric;
        self.gradient_sum(particles, &particles.vol, hoop, scratch, node);
    }

    /// `Σ_p w_p ∇S_ip` (+ `w_p S_ip / r_p` radially if `hoop`).
    fn gradient_sum(
        &self,
        particles: &Particles<D>,
        weights: &[f64],
        hoop: bool,
        scratch: &StepScratch<D>,
        node: &mut [SVector<f64, D>],
    ) {
        #[allow(clippy::too_many_arguments)]
        fn run<const D: usize, const S: usize, K: Stencil<S>>(
            kernel: K,
            ctx: &Ctx<'_, D>,
            particles: &Particles<D>,
            weights: &[f64],
            hoop: bool,
            scratch: &StepScratch<D>,
            node: &mut [SVector<f64, D>],
        ) {
            let grid = ctx.grid;
            let strides = grid.strides();
            node.par_iter_mut().for_each(|q| *q = SVector::zeros());
            let out = SharedMut::new(node);
            scratch.bins.for_each_colored(|p| {
                let x = &particles.x[p];
                let (pw, base) = weights_at(grid, kernel, x, &scratch.lp, p);
                let mp = weights[p];
                let radial = if hoop { mp / x[0] } else { 0.0 };
                pw.for_each(|m, w, g| {
                    // SAFETY: slab colouring gives concurrent tasks disjoint
                    // nodes.
                    let q = unsafe { out.get(base + offset(m, &strides)) };
                    *q += g * mp;
                    q[0] += w * radial;
                });
            });
        }
        let ctx = self.ctx(None);
        with_kernel!(
            self.params.shape,
            run,
            &ctx,
            particles,
            weights,
            hoop,
            scratch,
            node
        )
    }

    /// Steps 7–9 on the nodes: (USF) the stress update from the P2G
    /// velocity, the internal force with `σ + (p − p_ref) I` (`pressure` =
    /// the nodal pressure and `p_ref`; `None` outside MPM-ICE: σ alone) and
    /// the body force (Guilkey Eq. 24), plus `extra_force` (the pressure
    /// force `−θ_s V ∇p*` carried from the cells, already folded at walls;
    /// empty for none), and the grid momentum equation (Eqs. 21, 25) giving
    /// `vᴸ` and `a`.
    ///
    /// # Errors
    /// An inverted particle (USF).
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &self,
        particles: &mut Particles<D>,
        gs: &mut GridState<D>,
        scratch: &mut StepScratch<D>,
        pressure: Option<(&[f64], f64)>,
        extra_force: &[SVector<f64, D>],
    ) -> Result<()> {
        #[allow(clippy::too_many_arguments)]
        fn run<const D: usize, const S: usize, K: Stencil<S>, const AXI: bool>(
            kernel: K,
            ctx: &Ctx<'_, D>,
            particles: &mut Particles<D>,
            gs: &mut GridState<D>,
            scratch: &mut StepScratch<D>,
            extra_force: &[SVector<f64, D>],
        ) -> Result<()> {
            let start = Instant::now();
            if ctx.params.scheme == UpdateScheme::Usf {
                g2p::<D, S, K, false, POS_NONE, GRAD_VEL, AXI>(
                    ctx,
                    kernel,
                    &scratch.lp,
                    particles,
                    gs,
                    &mut scratch.dx,
                    &mut scratch.nonlocal,
                )?;
            }
            let mid = Instant::now();
            scratch.times.g2p_s += (mid - start).as_secs_f64();
            p2g::<D, S, K, false, false, true, AXI>(
                ctx,
                kernel,
                &scratch.bins,
                &scratch.lp,
                particles,
                gs,
            );
            gs.accel
                .par_iter_mut()
                .zip(extra_force.par_iter())
                .for_each(|(f, e)| *f += e);
            let mid2 = Instant::now();
            scratch.times.p2g_s += (mid2 - mid).as_secs_f64();
            grid_solve(ctx, gs);
            scratch.times.grid_s += mid2.elapsed().as_secs_f64();
            Ok(())
        }
        let ctx = self.ctx(pressure);
        with_kernel_axi!(
            self.params.shape,
            self.grid.axisymmetric,
            run,
            &ctx,
            particles,
            gs,
            scratch,
            extra_force
        )
    }

    /// Step 13: particle velocity (FLIP, Guilkey Eq. 26) and position
    /// (Eq. 27) from the grid, after the caller has added the exchange's
    /// velocity change to `gs.velocity_new` and `gs.accel`; (USL) the stress
    /// update from the final grid velocity. `vol_rate` (USL only; empty for
    /// none) adds a volumetric strain rate to each particle's velocity
    /// gradient (Zhang Eqs. 1–2, [`crate::mpm`] users outside multiphase
    /// pass `&[]`).
    ///
    /// # Errors
    /// An inverted particle.
    pub fn g2p(
        &self,
        particles: &mut Particles<D>,
        gs: &GridState<D>,
        scratch: &mut StepScratch<D>,
        vol_rate: &[f64],
    ) -> Result<()> {
        fn run<const D: usize, const S: usize, K: Stencil<S>, const AXI: bool>(
            kernel: K,
            ctx: &Ctx<'_, D>,
            particles: &mut Particles<D>,
            gs: &GridState<D>,
            scratch: &mut StepScratch<D>,
        ) -> Result<()> {
            let start = Instant::now();
            let (lp, dx, nl) = (&scratch.lp, &mut scratch.dx, &mut scratch.nonlocal);
            if ctx.params.scheme == UpdateScheme::Usf {
                g2p::<D, S, K, true, POS_APPLY, GRAD_NONE, AXI>(
                    ctx, kernel, lp, particles, gs, dx, nl,
                )?;
            } else {
                g2p::<D, S, K, true, POS_APPLY, GRAD_VEL_NEW, AXI>(
                    ctx, kernel, lp, particles, gs, dx, nl,
                )?;
            }
            scratch.times.g2p_s += start.elapsed().as_secs_f64();
            Ok(())
        }
        let mut ctx = self.ctx(None);
        ctx.vol_rate = vol_rate;
        let axi = self.grid.axisymmetric;
        with_kernel_axi!(self.params.shape, axi, run, &ctx, particles, gs, scratch)
    }
}

impl<const D: usize> CoupledMpm<'_, D> {
    /// Mass-weighted map of a particle scalar to the nodes (the solid's
    /// temperature in Guilkey Sec. 3.3 step 1): `q_i = Σ_p S_ip m_p q_p /
    /// m_i`, the numerator folded at walls like the mass, with the bins and
    /// particle domains of this step's [`Self::p2g`] (call it first;
    /// `gs.mass` is its nodal mass). Nodes at or below the mass floor get 0.
    pub fn p2g_scalar(
        &self,
        particles: &Particles<D>,
        values: &[f64],
        gs: &GridState<D>,
        scratch: &StepScratch<D>,
        node: &mut [f64],
    ) {
        let mass = &particles.mass;
        self.scatter_sum(particles, scratch, node, |p| mass[p] * values[p]);
        let floor = self.params.mass_floor;
        node.par_iter_mut()
            .zip(gs.mass.par_iter())
            .for_each(|(q, &m)| *q = if m > floor { *q / m } else { 0.0 });
    }

    /// Adds a nodal increment to a particle quantity (a scalar or a
    /// vector): `q_p += Σ_i S_ip Δq_i` (Guilkey Sec. 3.3 step 10's exchange
    /// change, nodes → particles; the velocity change a grid contact made,
    /// [`crate::contact::MembraneContactStep`]), at the positions and
    /// domains of this step's [`Self::p2g`] (call it before the particles
    /// move). `node` must have its ghosts mirrored.
    pub fn g2p_add<T: NodalValue>(
        &self,
        particles: &Particles<D>,
        node: &[T],
        scratch: &StepScratch<D>,
        values: &mut [T],
    ) {
        fn run<const D: usize, const S: usize, K: Stencil<S>, T: NodalValue>(
            kernel: K,
            ctx: &Ctx<'_, D>,
            particles: &Particles<D>,
            node: &[T],
            scratch: &StepScratch<D>,
            values: &mut [T],
        ) {
            let grid = ctx.grid;
            let strides = grid.strides();
            values
                .par_iter_mut()
                .enumerate()
                .with_min_len(512)
                .for_each(|(p, q)| {
                    let (pw, base) = weights_at(grid, kernel, &particles.x[p], &scratch.lp, p);
                    let mut dq = T::zero();
                    pw.for_each(|m, w, _| dq += node[base + offset(m, &strides)] * w);
                    *q += dq;
                });
        }
        let ctx = self.ctx(None);
        with_kernel!(
            self.params.shape,
            run::<T>,
            &ctx,
            particles,
            node,
            scratch,
            values
        )
    }

    /// Calls `f(p, i)` for every particle `p` and every node `i` of its
    /// stencil with a positive weight, at the positions and domains of this
    /// step's [`Self::p2g`] (call it first), particle by particle on one
    /// thread. Ghost nodes are visited as they are (not folded).
    pub fn for_each_support(
        &self,
        particles: &Particles<D>,
        scratch: &StepScratch<D>,
        f: &mut dyn FnMut(usize, usize),
    ) {
        fn run<const D: usize, const S: usize, K: Stencil<S>>(
            kernel: K,
            ctx: &Ctx<'_, D>,
            particles: &Particles<D>,
            scratch: &StepScratch<D>,
            f: &mut dyn FnMut(usize, usize),
        ) {
            let grid = ctx.grid;
            let strides = grid.strides();
            for p in 0..particles.len() {
                let (pw, base) = weights_at(grid, kernel, &particles.x[p], &scratch.lp, p);
                pw.for_each(|m, w, _| {
                    if w > 0.0 {
                        f(p, base + offset(m, &strides));
                    }
                });
            }
        }
        let ctx = self.ctx(None);
        with_kernel!(self.params.shape, run, &ctx, particles, scratch, f)
    }
}

/// A nodal quantity [`CoupledMpm::g2p_add`] interpolates: a scalar or a
/// vector.
pub trait NodalValue:
    Copy + Send + Sync + std::ops::AddAssign + std::ops::Mul<f64, Output = Self>
{
    /// The additive zero.
    fn zero() -> Self;
}

impl NodalValue for f64 {
    fn zero() -> Self {
        0.0
    }
}

impl<const N: usize> NodalValue for SVector<f64, N> {
    fn zero() -> Self {
        SVector::zeros()
    }
}

/// Start of a step: bins the particles into slabs and freezes the GIMP
/// half-widths (l = l⁰|F_dd|) for every transfer of the step.
fn prepare<const D: usize>(
    ctx: &Ctx<'_, D>,
    particles: &Particles<D>,
    scratch: &mut StepScratch<D>,
) -> Result<()> {
    if let Err(p) = scratch.bins.build(ctx.grid, &particles.x) {
        return Err(ctx.fail(
            Some(p),
            None,
            "particle position is not finite or has left the grid",
        ));
    }
    if ctx.params.shape.uses_particle_domain() {
        let inv_h = ctx.grid.inv_h;
        scratch.lp.resize(particles.len(), SVector::zeros());
        let f = &particles.f;
        scratch.lp.par_iter_mut().enumerate().for_each(|(p, lp)| {
            *lp = gimp_half_width(&particles.half_size.get(p), &f.get(p), &inv_h)
        });
    } else {
        scratch.lp.clear();
    }
    Ok(())
}

fn clear<const D: usize>(gs: &mut GridState<D>) {
    gs.mass.par_iter_mut().for_each(|m| *m = 0.0);
    gs.momentum
        .par_iter_mut()
        .zip(gs.accel.par_iter_mut())
        .for_each(|(m, f)| {
            *m = SVector::zeros();
            *f = SVector::zeros();
        });
}

/// Flat node offsets of a stencil multi-index.
#[inline(always)]
pub(crate) fn offset<const D: usize>(m: [usize; D], strides: &[usize; D]) -> usize {
    let mut o = 0;
    for d in 0..D {
        o += m[d] * strides[d];
    }
    o
}

/// GIMP particle half-width in cell units, following the deformation
/// (cpGIMP-style, axis-aligned): l_d = l⁰_d |F_dd|, capped at half a cell
/// (where the uGIMP weight formula holds). Other shape functions ignore it.
#[inline(always)]
fn gimp_half_width<const D: usize>(
    l0: &SVector<f64, D>,
    f: &Matrix3<f64>,
    inv_h: &SVector<f64, D>,
) -> SVector<f64, D> {
    SVector::from_fn(|d, _| (l0[d] * f[(d, d)].abs() * inv_h[d]).min(0.5))
}

/// The frozen GIMP half-width of particle `p` (zero for other kernels, which
/// ignore it).
#[inline(always)]
fn half_width<const D: usize>(lp: &[SVector<f64, D>], p: usize) -> SVector<f64, D> {
    lp.get(p).copied().unwrap_or_else(SVector::zeros)
}

/// Shape-function weights of particle `p` at the position `x` with the
/// step's frozen domains `lp`, and the flat index of its stencil's base
/// node.
#[inline(always)]
fn weights_at<const D: usize, const S: usize, K: Stencil<S>>(
    grid: &Grid<D>,
    kernel: K,
    x: &SVector<f64, D>,
    lp: &[SVector<f64, D>],
    p: usize,
) -> (ParticleWeights<D, S>, usize) {
    let xi = grid.to_grid_units(x);
    let pw = ParticleWeights::<D, S>::new_physical(kernel, &xi, &half_width(lp, p), &grid.inv_h);
    let base = grid.node_index(pw.base());
    (pw, base)
}

/// Determinant of a D×D matrix, D ≤ 3, in closed form.
#[inline(always)]
fn det_small<const D: usize>(m: &SMatrix<f64, D, D>) -> f64 {
    match D {
        1 => m[(0, 0)],
        2 => m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)],
        _ => {
            m[(0, 0)] * (m[(1, 1)] * m[(2, 2)] - m[(1, 2)] * m[(2, 1)])
                - m[(0, 1)] * (m[(1, 0)] * m[(2, 2)] - m[(1, 2)] * m[(2, 0)])
                + m[(0, 2)] * (m[(1, 0)] * m[(2, 1)] - m[(1, 1)] * m[(2, 0)])
        }
    }
}

/// The D×D block of a 3×3 tensor.
#[inline(always)]
fn block<const D: usize>(s: &Matrix3<f64>) -> SMatrix<f64, D, D> {
    SMatrix::<f64, D, D>::from_fn(|i, j| s[(i, j)])
}

/// Particle to grid (Guilkey Eq. 22 and Eq. 24, f = f_ext − f_int).
///
/// Axisymmetric (`AXI`, coordinates (r, z), volumes and masses per radian):
/// the virtual work of the stress in cylindrical coordinates,
/// ∫ (σ_rr ∂w_r/∂r + σ_rz ∂w_r/∂z + σ_θθ w_r/r) r dr dz (the last term is
/// the virtual hoop strain δε_θθ = w_r/r: the "spatial variation of the
/// basis vectors" of York's remark after Eq. 14, and York's ref. 12, Sulsky &
/// Schreyer 1996, CMAME 139, axisymmetric MPM), with particle quadrature and
/// V_p = ∫ r dA per radian, adds f_i,r −= V_p σ_θθ N_i(x_p)/r_p to the plane
/// gradient term. Whatever the model, σ_θθ is `stress[(2,2)]`.
fn p2g<
    const D: usize,
    const S: usize,
    K: Stencil<S>,
    const MASS: bool,
    const MOMENTUM: bool,
    const FORCE: bool,
    const AXI: bool,
>(
    ctx: &Ctx<'_, D>,
    kernel: K,
    bins: &Bins,
    lp: &[SVector<f64, D>],
    particles: &Particles<D>,
    gs: &mut GridState<D>,
) {
    let grid = ctx.grid;
    let strides = grid.strides();
    // Gas points that read their density from the grid (York Eq. 16
    // replaced): their own nodal mass beside the total.
    let grid_rho = MASS && ctx.materials.iter().any(SolidMaterial::reads_grid_density);
    if grid_rho {
        if gs.node_volume.is_empty() {
            // Once per run: the grid, the shape function and the points'
            // seeding are fixed; the lattice is the first reading point's.
            let half = (0..particles.len())
                .find(|&p| ctx.materials[particles.material[p] as usize].reads_grid_density())
                .map_or_else(|| grid.h * 0.25, |p| particles.half_size.get(p));
            gs.node_volume = node_volumes(grid, kernel, &half);
            gs.gas_mass = vec![0.0; gs.mass.len()];
            gs.gas_density = vec![0.0; gs.mass.len()];
        }
        gs.gas_mass.par_iter_mut().for_each(|m| *m = 0.0);
    }
    let mass = SharedMut::new(&mut gs.mass);
    let gas_mass = SharedMut::new(&mut gs.gas_mass);
    let momentum = SharedMut::new(&mut gs.momentum);
    let force = SharedMut::new(&mut gs.accel);
    let (t, body) = (ctx.t, ctx.body);
    bins.for_each_colored(|p| {
        let (pw, base) = weights_at(grid, kernel, &particles.x[p], lp, p);
        let mp = particles.mass[p];
        let gas_mp = grid_rho && ctx.materials[particles.material[p] as usize].reads_grid_density();
        let mv = particles.v[p] * mp;
        let mut fb = SVector::<f64, D>::zeros();
        let mut vs = SMatrix::<f64, D, D>::zeros();
        let mut hoop = 0.0;
        if FORCE {
            if let Some(b) = body {
                fb = b.accel(&particles.x0[p], &particles.x[p], t) * mp;
            }
            let mut sigma = particles.stress.get(p);
            if let Some((pn, p_ref)) = ctx.pressure {
                // Guilkey Sec. 3.3 step 7: ICE applies −θ∇p to the solid, so
                // the particle stress carries σ + (p − p_ref) I (the
                // pressure is not counted twice).
                let mut pp = 0.0;
                pw.for_each(|m, w, _| pp += w * pn[base + offset(m, &strides)]);
                for d in 0..3 {
                    sigma[(d, d)] += pp - p_ref;
                }
            }
            vs = block::<D>(&sigma) * particles.vol[p];
            if AXI {
                // V_p σ_θθ / r_p (r_p > 0: particles stay off the axis).
                hoop = particles.vol[p] * sigma[(2, 2)] / particles.x[p][0];
            }
        }
        pw.for_each(|m, w, g| {
            let idx = base + offset(m, &strides);
            // SAFETY: slab colouring gives concurrent tasks disjoint nodes.
            unsafe {
                if MASS {
                    *mass.get(idx) += w * mp;
                    if gas_mp {
                        *gas_mass.get(idx) += w * mp;
                    }
                }
                if MOMENTUM {
                    *momentum.get(idx) += mv * w;
                }
                if FORCE {
                    let f = force.get(idx);
                    *f += fb * w - vs * g;
                    if AXI {
                        f[0] -= hoop * w;
                    }
                }
            }
        });
    });
    // The walls' reaction needs the particles' own fields where the fold
    // changes them: the first mapping's mass and momentum, and the force.
    if MASS || FORCE {
        gs.walls.record(
            grid,
            MASS.then_some((&gs.mass[..], &gs.momentum[..])),
            FORCE.then_some(&gs.accel[..]),
        );
    }
    // Mirror-particle boundary treatment (see `Grid::fold_ghosts`).
    if MASS {
        grid.fold_ghosts(&mut gs.mass);
    }
    if grid_rho {
        grid.fold_ghosts(&mut gs.gas_mass);
        gs.gas_density
            .par_iter_mut()
            .zip(gs.gas_mass.par_iter().zip(gs.node_volume.par_iter()))
            .for_each(|(rho, (&m, &v))| *rho = if v > 0.0 { m / v } else { 0.0 });
        grid.mirror_ghosts(&mut gs.gas_density);
    }
    if MOMENTUM {
        grid.fold_ghosts(&mut gs.momentum);
    }
    if FORCE {
        grid.fold_ghosts(&mut gs.accel);
    }
}

/// Each node's share of the domain, `V_i = ∫_Ω S_i dV` (r–z: `∫_Ω S_i r
/// dr dz`, per radian), as the points sample it: the sum `Σ_q S_iq V_q`
/// over a lattice of points with half-size `half` (per axis; `ppc = h / 2
/// half` to a cell, at the sub-cell centres, as the scene seeds them)
/// filling the domain, folded at the walls as P2G folds the nodal mass. So
/// `Σ_p S_ip m_p / V_i` is exact for a uniform gas seeded so, at walls,
/// symmetry planes and the axis too, where the points' sum is not the
/// integral (at the axis `∫ S_0 |r| dr` against the points' midpoint sum:
/// 9 % apart for the hat at 2 points per cell).
fn node_volumes<const D: usize, const S: usize, K: Stencil<S>>(
    grid: &Grid<D>,
    kernel: K,
    half: &SVector<f64, D>,
) -> Vec<f64> {
    let axes: Vec<Vec<f64>> = (0..D)
        .map(|d| {
            let ppc = (grid.h[d] / (2.0 * half[d])).round().max(1.0) as usize;
            let lp = half[d] * grid.inv_h[d];
            let mut v = vec![0.0; grid.node_dims[d]];
            for k in 0..grid.cells[d] * ppc {
                let xi = (k as f64 + 0.5) / ppc as f64;
                let radius = if d == 0 && grid.axisymmetric {
                    grid.lower[0] + xi * grid.h[0]
                } else {
                    1.0
                };
                let wq = grid.h[d] / ppc as f64 * radius;
                let w1 = kernel.eval(xi, lp);
                for (j, w) in w1.w.iter().enumerate() {
                    v[(w1.base + j as isize + GHOST as isize) as usize] += w * wq;
                }
            }
            v
        })
        .collect();
    let mut vol: Vec<f64> = (0..grid.num_nodes())
        .map(|i| {
            let c = grid.node_coords(i);
            (0..D)
                .map(|d| axes[d][(c[d] + GHOST as isize) as usize])
                .product()
        })
        .collect();
    grid.fold_ghosts(&mut vol);
    vol
}

/// v = p/m on nodes with mass, zero elsewhere; ghosts mirrored (the boundary
/// conditions were imposed by folding in P2G).
fn grid_velocity<const D: usize>(ctx: &Ctx<'_, D>, gs: &mut GridState<D>) {
    let floor = ctx.params.mass_floor;
    gs.velocity
        .par_iter_mut()
        .zip(gs.mass.par_iter().zip(gs.momentum.par_iter()))
        .for_each(|(v, (&m, p))| *v = if m > floor { p / m } else { SVector::zeros() });
    ctx.grid.mirror_ghosts(&mut gs.velocity);
}

/// Grid momentum equation: v = p/m, vᴸ = v + Δt f/m (Guilkey Eqs. 21, 25) on
/// the folded fields with a = f/m, ghosts mirrored.
fn grid_solve<const D: usize>(ctx: &Ctx<'_, D>, gs: &mut GridState<D>) {
    let floor = ctx.params.mass_floor;
    let alpha = ctx.params.damping;
    let dt = ctx.dt;
    let inv_dt = 1.0 / dt;
    let damp = 1.0 / (1.0 + 0.5 * alpha * dt);
    // One pass: the wall conditions are already in the folded p and f (their
    // odd components vanish on the boundary nodes), so a = f/m needs no fix-up
    // on domain nodes; ghosts are mirrored afterwards. `accel` holds the
    // force on entry and the acceleration on exit.
    gs.velocity
        .par_iter_mut()
        .zip(gs.velocity_new.par_iter_mut())
        .zip(gs.accel.par_iter_mut())
        .zip(gs.mass.par_iter().zip(gs.momentum.par_iter()))
        .for_each(|(((v, vl), a), (&m, p))| {
            if m > floor {
                let f = *a;
                let inv_m = 1.0 / m;
                *v = p * inv_m;
                // Damping time-centred (trapezoidal): second order, and stable
                // for any α Δt.
                *vl = (*v * (1.0 - 0.5 * alpha * dt) + f * (inv_m * dt)) * damp;
                *a = (*vl - *v) * inv_dt;
            } else {
                *v = SVector::zeros();
                *a = SVector::zeros();
                *vl = SVector::zeros();
            }
        });
    ctx.grid.mirror_ghosts(&mut gs.velocity);
    ctx.grid.mirror_ghosts(&mut gs.velocity_new);
    ctx.grid.mirror_ghosts(&mut gs.accel);
    gs.damping_work = if alpha > 0.0 {
        let (v, vl) = (&gs.velocity, &gs.velocity_new);
        -alpha
            * dt
            * gs.walls
                .real_mass_weighted(&gs.mass, &gs.momentum, |i| (v[i] + vl[i]) * 0.5)
    } else {
        0.0
    };
}

/// The stress update of a membrane point (York Sec. 3.2) with unit tangent
/// `t`: the strain rate projected on the tangent, `ε̇_tt = t·L·t`, and the
/// out-of-plane rate `eps_hoop` (0 in plane 2D; the hoop rate `v_r / r` of
/// a ring in r–z) advance the in-surface stresses `(s_tt, s₃₃)`
/// ([`crate::material::MembraneLaw::update`], plane stress through the
/// thickness); the stress goes back to the global frame as
/// `σ = s_tt t⊗t + s₃₃ e₃⊗e₃` (York Eq. 15 takes it from there; in r–z
/// the kernels' hoop term carries `s₃₃ = σ_θθ` to the nodes). The point's
/// volume follows its length and (r–z) its radius at constant thickness,
/// `V = λ V⁰` with `λ ← λ(1 + Δt ε̇_tt)(1 + Δt ε̇₃₃)` (per radian
/// `V = r h Δs`), and `work` gathers the stress power
/// `V (s_tt ε̇_tt + s₃₃ ε̇₃₃)` per unit reference volume. Returns false when
/// the stretch is not positive and finite.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn membrane_update<const D: usize>(
    m: &crate::material::MembraneLaw,
    t: &SVector<f64, D>,
    l: &SMatrix<f64, D, D>,
    eps_hoop: f64,
    dt: f64,
    vol0: f64,
    stress: &mut Matrix3<f64>,
    work: &mut f64,
    vol: &mut f64,
) -> bool {
    let eps_rate = t.dot(&(l * t));
    let lam = *vol / vol0 * (1.0 + dt * eps_rate) * (1.0 + dt * eps_hoop);
    if !(lam.is_finite() && lam > 0.0) {
        return false;
    }
    // The in-plane trace of σ = s t⊗t is s in any frame.
    let s_old = [(0..D).map(|i| stress[(i, i)]).sum(), stress[(2, 2)]];
    let s = m.update(s_old, [eps_rate, eps_hoop], dt);
    let mut sigma = Matrix3::zeros();
    for i in 0..D {
        for j in 0..D {
            sigma[(i, j)] = s[0] * t[i] * t[j];
        }
    }
    if D < 3 {
        sigma[(2, 2)] = s[1];
    }
    *stress = sigma;
    *work += dt * lam * 0.5 * ((s_old[0] + s[0]) * eps_rate + (s_old[1] + s[1]) * eps_hoop);
    *vol = lam * vol0;
    true
}

/// Grid to particle (Guilkey Eqs. 23, 26, 27) and the constitutive update.
///
/// Axisymmetric (`AXI`): the hoop rate L_θθ = v_r(x_p)/r_p, with v_r
/// interpolated from the same nodal velocity as the gradient and r_p the
/// position at the start of the step (where the weights are), enters the
/// 3×3 L as L₃₃ (York Eq. 14 with the cylindrical basis: the velocity
/// gradient's hoop component is v_r/r); F₃₃ ← (1 + Δt L_θθ) F₃₃ and J =
/// det(F_D) F₃₃. Every model gets the whole 3×3 L and F.
fn g2p<
    const D: usize,
    const S: usize,
    K: Stencil<S>,
    const FLIP: bool,
    const POS: u8,
    const GRAD: u8,
    const AXI: bool,
>(
    ctx: &Ctx<'_, D>,
    kernel: K,
    lp: &[SVector<f64, D>],
    particles: &mut Particles<D>,
    gs: &GridState<D>,
    dx_store: &mut Vec<SVector<f64, D>>,
    nonlocal: &mut NonlocalDamage<D>,
) -> Result<()> {
    let grid = ctx.grid;
    let strides = grid.strides();
    let dt = ctx.dt;
    let np = particles.len();
    if POS == POS_STORE {
        dx_store.resize(np, SVector::zeros());
    }
    let grad_field: &[SVector<f64, D>] = if GRAD == GRAD_VEL_NEW {
        &gs.velocity_new
    } else {
        &gs.velocity
    };
    let failed = AtomicUsize::new(usize::MAX);
    let pic = ctx.params.pic_fraction;
    let tangent = ctx.tangent;
    let has_membrane = !tangent.is_empty();
    // York Eq. 24's c_max from the state at the start of the stress update.
    let c_max = if GRAD != GRAD_NONE {
        gas_sound_speed_max(ctx.materials, particles)
    } else {
        0.0
    };
    // Gas points reading the grid's density: looked up per point only when
    // some material does.
    let grid_rho = GRAD != GRAD_NONE && ctx.materials.iter().any(SolidMaterial::reads_grid_density);
    // Plastic state travels only when some material is plastic, damage
    // only when some material fails.
    let plastic = GRAD != GRAD_NONE && ctx.materials.iter().any(|m| m.plasticity().is_some());
    let failing = GRAD != GRAD_NONE && ctx.materials.iter().any(|m| m.failure().is_some());
    if failing {
        // Sized once, at the first step of a run with failure.
        particles.track_damage();
    }
    // A nonlocal failure model: the update writes each point's local
    // damage increment, averaged after the loop.
    let averaging = failing
        && nonlocal.prepare(
            np,
            ctx.materials
                .iter()
                .map(|m| m.failure().map_or(0.0, |f| f.nonlocal_radius())),
        );
    if plastic {
        // Sized once, at the first step of a run with plasticity (plastic
        // work heats the particles).
        particles.track_plastic_strain();
        particles.track_temperature();
    }
    particles.track_work_for(ctx.materials);
    let tracks_work = !particles.work.is_empty();
    {
        let mass = &particles.mass;
        let eps_p = SharedMut::new(&mut particles.plastic_strain);
        let damage = SharedMut::new(&mut particles.damage);
        let temp = SharedMut::new(&mut particles.temperature);
        let x = SharedMut::new(&mut particles.x);
        let v = SharedMut::new(&mut particles.v);
        let fgrad = particles.f.shared();
        let stress = particles.stress.shared();
        let work = SharedMut::new(&mut particles.work);
        let vol = SharedMut::new(&mut particles.vol);
        let dxs = SharedMut::new(dx_store);
        let increment = SharedMut::new(&mut nonlocal.increment);
        let radius = &nonlocal.radius;
        let (vol0, mat) = (&particles.vol0, &particles.material);
        (0..np).into_par_iter().with_min_len(512).for_each(|p| {
            // SAFETY: each task touches only particle p's entries.
            let (xp, vp) = unsafe { (x.get(p), v.get(p)) };
            let (pw, base) = weights_at(grid, kernel, xp, lp, p);
            let r_old = xp[0];
            let mut acc = SVector::<f64, D>::zeros();
            let mut vel = SVector::<f64, D>::zeros();
            let mut l = SMatrix::<f64, D, D>::zeros();
            let mut v_r = 0.0;
            // A gas point that reads its density from the grid: ρ at x_p,
            // where P2G mapped it ([`crate::material::PointDensity::Grid`]).
            let reads_rho = grid_rho && ctx.materials[mat[p] as usize].reads_grid_density();
            let mut rho_grid = 0.0;
            pw.for_each(|m, w, g| {
                let idx = base + offset(m, &strides);
                if FLIP {
                    acc += gs.accel[idx] * w;
                }
                if reads_rho {
                    rho_grid += gs.gas_density[idx] * w;
                }
                if POS == POS_APPLY || POS == POS_STORE {
                    vel += gs.velocity_new[idx] * w;
                }
                if GRAD != GRAD_NONE {
                    l += grad_field[idx] * g.transpose();
                    if AXI {
                        v_r += grad_field[idx][0] * w;
                    }
                }
            });
            if FLIP {
                if pic > 0.0 {
                    let v_flip = *vp + acc * dt;
                    let v_new = v_flip * (1.0 - pic) + vel * pic;
                    if ctx.materials[mat[p] as usize].gas().is_some() {
                        // A gas point's kinetic energy that the share takes
                        // out becomes its heat (internal energy ρ_ref e per
                        // reference volume), as York's q does (Eq. 23): the
                        // blend conserves the point's total energy. A point
                        // the blend speeds up cools by as much, unless that
                        // would leave it no internal energy.
                        let heat = 0.5 * mass[p] / vol0[p]
                            * (v_flip.norm_squared() - v_new.norm_squared());
                        // SAFETY: as above.
                        let e = unsafe { work.get(p) };
                        if *e + heat > 0.0 {
                            *e += heat;
                        }
                    }
                    *vp = v_new;
                } else {
                    *vp += acc * dt; // Eq. 26
                }
            }
            match POS {
                POS_APPLY => *xp += vel * dt, // Eq. 27
                // SAFETY: as above.
                POS_STORE => unsafe { *dxs.get(p) = vel * dt },
                POS_APPLY_STORED => unsafe { *xp += *dxs.get(p) },
                _ => {}
            }
            if GRAD != GRAD_NONE {
                // Zhang Eq. 1: the phase's volume change α ∇·ū + B
                // replaces ∇·ū; the deviatoric part (Eq. 3) is kept: the
                // extra rate is spread evenly over the D in-plane diagonal
                // entries, and in r–z the hoop one as well.
                let share = ctx
                    .vol_rate
                    .get(p)
                    .map_or(0.0, |r| r / (D + usize::from(AXI)) as f64);
                if share != 0.0 {
                    for a in 0..D {
                        l[(a, a)] += share;
                    }
                }
                let mut l3 = Matrix3::<f64>::zeros();
                for i in 0..D {
                    for j in 0..D {
                        l3[(i, j)] = l[(i, j)];
                    }
                }
                // SAFETY: as above.
                // A material that does not read the work (neo-Hookean)
                // leaves it alone: untracked, the update gets a spare.
                let mut spare = 0.0;
                let (fp, mut sp, vp_vol) = unsafe { (fgrad.get(p), stress.get(p), vol.get(p)) };
                let wp = match tracks_work {
                    true => unsafe { work.get(p) },
                    false => &mut spare,
                };
                if has_membrane {
                    if let Some(m) = ctx.materials[mat[p] as usize].membrane() {
                        // r–z: a membrane point is a ring of radius r > 0
                        // whose hoop rate is v_r / r.
                        let eps_hoop = if AXI { v_r / r_old } else { 0.0 };
                        if (AXI && r_old <= 0.0)
                            || !membrane_update(
                                m,
                                &tangent[p],
                                &l,
                                eps_hoop,
                                dt,
                                vol0[p],
                                &mut sp,
                                wp,
                                vp_vol,
                            )
                        {
                            failed.fetch_min(p, Ordering::Relaxed);
                        }
                        // SAFETY: as above.
                        unsafe { stress.set(p, &sp) };
                        return;
                    }
                }
                // Plane strain: L lives in the D×D block, so F stays
                // diag(F_D, I) and only that block changes: F_D ← (I + Δt L)
                // F_D, J = det F_D. Axisymmetric: F₃₃ follows the hoop rate.
                let fd = block::<D>(&fp);
                let fd_new = fd + (l * fd) * dt;
                let mut j = det_small(&fd_new);
                let mut f_new = fp;
                for a in 0..D {
                    for b in 0..D {
                        f_new[(a, b)] = fd_new[(a, b)];
                    }
                }
                if AXI {
                    // Hoop stretch: F = diag(F_D, F₃₃), F₃₃ → r/R.
                    let l_hoop = v_r / r_old + share;
                    l3[(2, 2)] = l_hoop;
                    f_new[(2, 2)] = fp[(2, 2)] * (1.0 + dt * l_hoop);
                    j *= f_new[(2, 2)];
                }
                let rho_ref = mass[p] / vol0[p];
                let mut j_old = *vp_vol / vol0[p];
                if reads_rho {
                    // The step starts from the grid's density and advances
                    // it by continuity, J = J_grid det(I + Δt L) (with the
                    // hoop factor in r–z); F is rescaled to that J (a gas
                    // reads nothing else of it).
                    let j_grid = rho_ref / rho_grid;
                    let hoop_old = if AXI { fp[(2, 2)] } else { 1.0 };
                    let j_step = j / (det_small(&fd) * hoop_old);
                    let scale = (j_grid * j_step / j).powf(1.0 / (D + usize::from(AXI)) as f64);
                    for a in 0..D {
                        for b in 0..D {
                            f_new[(a, b)] *= scale;
                        }
                    }
                    if AXI {
                        f_new[(2, 2)] *= scale;
                    }
                    j_old = j_grid;
                    j = j_grid * j_step;
                }
                if !j.is_finite() || j <= 0.0 {
                    failed.fetch_min(p, Ordering::Relaxed);
                    return;
                }
                let gas = GasInput {
                    rho_ref,
                    j_old,
                    c_max,
                };
                // SAFETY: as above.
                unsafe { fgrad.set(p, &f_new) };
                *vp_vol = j * vol0[p];
                let material = &ctx.materials[mat[p] as usize];
                // SAFETY: as above.
                let mut state = if plastic {
                    unsafe {
                        PlasticState {
                            plastic_strain: *eps_p.get(p),
                            temperature: *temp.get(p),
                            damage: 0.0,
                            damage_increment: 0.0,
                        }
                    }
                } else {
                    PlasticState::default()
                };
                if failing {
                    // SAFETY: as above.
                    state.damage = unsafe { *damage.get(p) };
                }
                if !material.update_stress(&l3, &f_new, j, dt, &gas, &mut sp, wp, &mut state) {
                    failed.fetch_min(p, Ordering::Relaxed);
                    return;
                }
                // SAFETY: as above.
                unsafe { stress.set(p, &sp) };
                if plastic {
                    // SAFETY: as above.
                    unsafe {
                        *eps_p.get(p) = state.plastic_strain;
                        *temp.get(p) = state.temperature;
                    }
                }
                if failing {
                    // SAFETY: as above.
                    unsafe { *damage.get(p) = state.damage };
                }
                if averaging && radius[mat[p] as usize] > 0.0 && state.damage < 1.0 {
                    // SAFETY: as above. (A point failed before the step is
                    // left out of the average: its entry stays −1.)
                    unsafe { *increment.get(p) = state.damage_increment };
                }
            }
        });
    }
    let p = failed.load(Ordering::Relaxed);
    if p != usize::MAX {
        return Err(ctx.fail(
            Some(p),
            None,
            "deformation gradient inverted or not finite (J ≤ 0; a membrane point: stretch not \
             positive, or in r–z its ring reached the axis, r ≤ 0); try a smaller CFL",
        ));
    }
    if averaging {
        nonlocal.average_increments(grid, &particles.x, &particles.vol, &particles.material);
        for (p, &avg) in nonlocal.average.iter().enumerate() {
            if avg.is_nan() {
                continue;
            }
            let d = &mut particles.damage[p];
            *d += avg;
            if *d >= 1.0 {
                // The failed point's stress (module `material::failure`),
                // which the next step's forces and stress power use.
                *d = 1.0;
                let s = particles.stress.get(p);
                particles.stress.set(p, &failed_stress(&s));
            }
        }
    }
    Ok(())
}

impl<const D: usize> CoupledMpm<'_, D> {
    /// `q_i = Σ_p S_ip values_p` on the nodes, folded at walls like the mass
    /// (the nodal volume Σ S v_p of Zhang Eq. 13 with `values` = volumes),
    /// with this step's bins and domains (call [`Self::p2g`] first).
    pub fn p2g_sum(
        &self,
        particles: &Particles<D>,
        values: &[f64],
        scratch: &StepScratch<D>,
        node: &mut [f64],
    ) {
        self.scatter_sum(particles, scratch, node, |p| values[p]);
    }

    /// `node = Σ_p S_ip value(p)`, folded at walls, with this step's bins
    /// and domains: the one scalar scatter behind [`Self::p2g_sum`] and
    /// [`Self::p2g_scalar`].
    fn scatter_sum<F: Fn(usize) -> f64 + Sync>(
        &self,
        particles: &Particles<D>,
        scratch: &StepScratch<D>,
        node: &mut [f64],
        value: F,
    ) {
        fn run<const D: usize, const S: usize, K: Stencil<S>, F: Fn(usize) -> f64 + Sync>(
            kernel: K,
            grid: &Grid<D>,
            particles: &Particles<D>,
            scratch: &StepScratch<D>,
            node: &mut [f64],
            value: &F,
        ) {
            let strides = grid.strides();
            node.par_iter_mut().for_each(|q| *q = 0.0);
            {
                let out = SharedMut::new(node);
                scratch.bins.for_each_colored(|p| {
                    let (pw, base) = weights_at(grid, kernel, &particles.x[p], &scratch.lp, p);
                    let q = value(p);
                    pw.for_each(|m, w, _| {
                        // SAFETY: slab colouring gives concurrent tasks
                        // disjoint nodes.
                        unsafe { *out.get(base + offset(m, &strides)) += w * q };
                    });
                });
            }
            grid.fold_ghosts(node);
        }
        let (g, v) = (self.grid, &value);
        match self.params.shape {
            ShapeKind::Linear => run::<D, 2, _, F>(LinearHat, g, particles, scratch, node, v),
            ShapeKind::Gimp => run::<D, 3, _, F>(Gimp, g, particles, scratch, node, v),
            ShapeKind::QuadraticBspline => {
                run::<D, 3, _, F>(QuadraticBspline, g, particles, scratch, node, v)
            }
            ShapeKind::CubicBspline => {
                run::<D, 4, _, F>(CubicBspline, g, particles, scratch, node, v)
            }
            ShapeKind::QuadraticBsplineGimp => {
                run::<D, 4, _, F>(QuadraticBsplineGimp, g, particles, scratch, node, v)
            }
        }
    }

    /// A per-particle reduction over its stencil: for every particle `p`,
    /// `visit(&mut acc, node, S_ip, ∇S_ip)` over its stencil nodes from
    /// `A::default()`, then `out[p] = finish(p, acc)`. With this step's
    /// domains at the particles' current positions (call [`Self::p2g`]
    /// first and this before the particles move). Nodal fields read by
    /// `visit` need their ghosts mirrored.
    pub fn gather<A, V, F>(
        &self,
        particles: &Particles<D>,
        scratch: &StepScratch<D>,
        out: &mut [f64],
        visit: V,
        finish: F,
    ) where
        A: Default,
        V: Fn(&mut A, usize, f64, &SVector<f64, D>) + Sync,
        F: Fn(usize, A) -> f64 + Sync,
    {
        #[allow(clippy::too_many_arguments)]
        fn run<const D: usize, const S: usize, K: Stencil<S>, A, V, F>(
            kernel: K,
            grid: &Grid<D>,
            particles: &Particles<D>,
            scratch: &StepScratch<D>,
            out: &mut [f64],
            visit: &V,
            finish: &F,
        ) where
            A: Default,
            V: Fn(&mut A, usize, f64, &SVector<f64, D>) + Sync,
            F: Fn(usize, A) -> f64 + Sync,
        {
            let strides = grid.strides();
            out.par_iter_mut()
                .enumerate()
                .with_min_len(512)
                .for_each(|(p, o)| {
                    let (pw, base) = weights_at(grid, kernel, &particles.x[p], &scratch.lp, p);
                    let mut acc = A::default();
                    pw.for_each(|m, w, g| visit(&mut acc, base + offset(m, &strides), w, &g));
                    *o = finish(p, acc);
                });
        }
        let (g, v, f) = (self.grid, &visit, &finish);
        match self.params.shape {
            ShapeKind::Linear => {
                run::<D, 2, _, A, V, F>(LinearHat, g, particles, scratch, out, v, f)
            }
            ShapeKind::Gimp => run::<D, 3, _, A, V, F>(Gimp, g, particles, scratch, out, v, f),
            ShapeKind::QuadraticBspline => {
                run::<D, 3, _, A, V, F>(QuadraticBspline, g, particles, scratch, out, v, f)
            }
            ShapeKind::CubicBspline => {
                run::<D, 4, _, A, V, F>(CubicBspline, g, particles, scratch, out, v, f)
            }
            ShapeKind::QuadraticBsplineGimp => {
                run::<D, 4, _, A, V, F>(QuadraticBsplineGimp, g, particles, scratch, out, v, f)
            }
        }
    }
}

/// Modified update-stress-last (Sulsky's MUSL) in three calls, for models
/// that work between them (the multiphase closure reads the remapped
/// velocities of every phase before any stress update): after
/// [`CoupledMpm::solve`] (and any exchange on `velocity_new`/`accel`),
/// [`CoupledMpm::musl_velocity`], [`CoupledMpm::musl_remap`], then
/// [`CoupledMpm::musl_stress`].
impl<const D: usize> CoupledMpm<'_, D> {
    /// FLIP particle velocity (Guilkey Eq. 26, Zhang Eq. 10); the
    /// displacement `Δt Σ S vᴸ` (Eq. 11) is stored for
    /// [`Self::musl_stress`].
    ///
    /// # Errors
    /// None in practice (no stress update here).
    pub fn musl_velocity(
        &self,
        particles: &mut Particles<D>,
        gs: &GridState<D>,
        scratch: &mut StepScratch<D>,
    ) -> Result<()> {
        fn run<const D: usize, const S: usize, K: Stencil<S>>(
            kernel: K,
            ctx: &Ctx<'_, D>,
            particles: &mut Particles<D>,
            gs: &GridState<D>,
            scratch: &mut StepScratch<D>,
        ) -> Result<()> {
            let start = Instant::now();
            let (lp, dx, nl) = (&scratch.lp, &mut scratch.dx, &mut scratch.nonlocal);
            g2p::<D, S, K, true, POS_STORE, GRAD_NONE, false>(
                ctx, kernel, lp, particles, gs, dx, nl,
            )?;
            scratch.times.g2p_s += start.elapsed().as_secs_f64();
            Ok(())
        }
        let ctx = self.ctx(None);
        with_kernel!(self.params.shape, run, &ctx, particles, gs, scratch)
    }

    /// Maps the updated particle momenta back to the nodes at the step's
    /// positions and sets `gs.velocity = p/m` (Zhang Eq. 12 at the old
    /// positions) on every node with mass, however small: `p/m` is a
    /// weighted mean of particle velocities, bounded, so no mass floor is
    /// needed (a zero below the floor would give the stress update a
    /// spurious gradient where a support edge passes a node). Ghosts
    /// mirrored.
    pub fn musl_remap(
        &self,
        particles: &Particles<D>,
        gs: &mut GridState<D>,
        scratch: &mut StepScratch<D>,
    ) {
        fn run<const D: usize, const S: usize, K: Stencil<S>>(
            kernel: K,
            ctx: &Ctx<'_, D>,
            particles: &Particles<D>,
            gs: &mut GridState<D>,
            scratch: &mut StepScratch<D>,
        ) {
            let start = Instant::now();
            gs.momentum
                .par_iter_mut()
                .for_each(|m| *m = SVector::zeros());
            p2g::<D, S, K, false, true, false, false>(
                ctx,
                kernel,
                &scratch.bins,
                &scratch.lp,
                particles,
                gs,
            );
            gs.velocity
                .par_iter_mut()
                .zip(gs.mass.par_iter().zip(gs.momentum.par_iter()))
                .for_each(|(v, (&m, p))| {
                    *v = if m > 0.0 { p / m } else { SVector::zeros() };
                });
            ctx.grid.mirror_ghosts(&mut gs.velocity);
            scratch.times.p2g_s += start.elapsed().as_secs_f64();
        }
        let ctx = self.ctx(None);
        with_kernel!(self.params.shape, run, &ctx, particles, gs, scratch)
    }

    /// The stress update from the gradient of the remapped velocity, with
    /// `vol_rate` added to each particle's volumetric rate (empty: none),
    /// then the stored displacement.
    ///
    /// # Errors
    /// An inverted particle.
    pub fn musl_stress(
        &self,
        particles: &mut Particles<D>,
        gs: &GridState<D>,
        scratch: &mut StepScratch<D>,
        vol_rate: &[f64],
    ) -> Result<()> {
        fn run<const D: usize, const S: usize, K: Stencil<S>, const AXI: bool>(
            kernel: K,
            ctx: &Ctx<'_, D>,
            particles: &mut Particles<D>,
            gs: &GridState<D>,
            scratch: &mut StepScratch<D>,
        ) -> Result<()> {
            let start = Instant::now();
            let (lp, dx, nl) = (&scratch.lp, &mut scratch.dx, &mut scratch.nonlocal);
            g2p::<D, S, K, false, POS_APPLY_STORED, GRAD_VEL, AXI>(
                ctx, kernel, lp, particles, gs, dx, nl,
            )?;
            scratch.times.g2p_s += start.elapsed().as_secs_f64();
            Ok(())
        }
        let mut ctx = self.ctx(None);
        ctx.vol_rate = vol_rate;
        let axi = self.grid.axisymmetric;
        with_kernel_axi!(self.params.shape, axi, run, &ctx, particles, gs, scratch)
    }
}
