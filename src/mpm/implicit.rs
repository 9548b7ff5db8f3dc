//! Implicit MPM: Newmark (β = 1/4, γ = 1/2) on the grid displacement increment
//! solved by Newton's method with the consistent tangent (Guilkey & Weiss
//! 2003, "Implicit time integration for the material point method:
//! quantitative and algorithmic comparisons with the finite element method",
//! IJNME 57), and a quasistatic mode (no inertia, ramped load steps).
//!
//! One step from tⁿ to tⁿ⁺¹ = tⁿ + Δt, all weights at the particle positions xⁿ:
//!
//! 1. P2G of mass, velocity and acceleration (Guilkey Eq. 22, mass-weighted),
//!    folded onto the independent degrees of freedom (see *Walls* below).
//! 2. Newton on the nodal displacement increment u (one D-vector per active
//!    node). Per particle, ΔF = I + Σᵢ uᵢ ⊗ ∇Nᵢ(xⁿ), F = ΔF Fⁿ, σ = σ(F) from the
//!    constitutive model ([`SolidMaterial::implicit_stress`]); the spatial
//!    gradient is ∇ₓNᵢ = ΔF⁻ᵀ ∇Nᵢ(xⁿ) and the current volume v = J_Δ Vⁿ.
//!    * internal force f_int,i = Σ_p v σ ∇ₓNᵢ (Guilkey Eq. 24 on the current
//!      configuration);
//!    * Newmark acceleration aᵢ(u) = 4/Δt² (uᵢ − Δt vᵢⁿ) − aᵢⁿ (β = 1/4);
//!    * residual R = f_ext − f_int − M a(u) (no inertia when quasistatic);
//!    * tangent K = Σ_p v [∇ₓNᵢ · c · ∇ₓNⱼ + (∇ₓNᵢ · σ ∇ₓNⱼ) I] + 4M/Δt²: the
//!      material stiffness with the spatial elasticity tensor c of
//!      [`SolidMaterial::spatial_tangent`] plus the textbook geometric
//!      (initial-stress) stiffness (Bonet & Wood Eq. 7.37 / 7.43 in the
//!      updated-Lagrangian form), symmetric;
//!    * K δu = R, u ← u + δu until ‖δu‖ ≤ tol_d ‖u‖ and |δu·R| ≤ tol_e |δu₀·R₀|.
//! 3. G2P: xₚ += Σ Nᵢ uᵢ, F and σ from the converged iterate, vₚ += Σ Nᵢ (vᵢⁿ⁺¹ −
//!    vᵢⁿ) with vᵢⁿ⁺¹ = vᵢⁿ + Δt/2 (aᵢⁿ + aᵢⁿ⁺¹), aₚ = Σ Nᵢ aᵢⁿ⁺¹.
//!
//! **Walls.** The explicit step folds ghost-node contributions onto mirror
//! nodes (`Grid::fold_ghosts`). For the implicit step the same mirror-particle
//! treatment is the linear constraint u_ghost = R u_mirror (R = ±1 per
//! component: all components odd on `Fixed` faces, the normal one on
//! `Symmetry` faces), applied as u_full = T u_reduced: every stencil node maps
//! to its mirror node with a sign per component, forces and tangent become
//! Tᵀ f and Tᵀ K T (symmetric), and the odd components of boundary nodes are
//! eliminated. The boundary rows are half the explicit folded rows (mass and
//! force alike), so both give the same accelerations.
//!
//! Assembly is on active nodes only (folded mass above the floor). The sparsity
//! pattern (node blocks) is rebuilt each step from the particle stencils and
//! compared with the last one; the symbolic factorisation is redone only when
//! it changed. Linear solves go through the `solvers` crate: sparse Cholesky by
//! default, assembled as the lower triangle only (all it reads; once a
//! factorisation fails the full matrix is assembled and the attempt redone
//! with the LU fallback), or Jacobi-preconditioned CG on the full matrix. The per-particle evaluation of stress, internal
//! force and tangent runs in parallel over slab-coloured particle bins (the
//! explicit step's `Bins`): every residual entry and tangent slot receives its
//! contributions in the same order for any thread count (bit-identical
//! results with 1 or N threads).
//!
//! **GIMP domains** follow the deformation as in the explicit step: the
//! half-width of particle p along axis d is l = l⁰ |F_dd| (capped at half a
//! cell), taken from Fⁿ and frozen over the step, so the particle domains
//! tile the deformed body (uGIMP of Bardenhagen & Kober 2004 with the
//! stretch-following domains of the explicit path).
//!
//! **Prescribed displacement** ([`PrescribedDisplacement`]): a set of
//! particles held by a rigid grip that moves by a ramped displacement. Every
//! reduced node in the support of a gripped particle (weight above
//! [`GRIP_WEIGHT_FLOOR`]) has its prescribed components fixed at the step's
//! increment Δū — the rigid-body convention of MPM (nodes touched by rigid
//! material move with it), under which the gripped particles move by exactly
//! Δū (partition of unity). The fixed DOFs stay in the Newton system with
//! nonzero values, eliminated symmetrically: the first iteration solves
//! K_ff δu_f = R_f − K_fp Δū_p (the increment enters through the tangent at
//! the start of the step, so a large increment does not distort the cell
//! next to the grip before the first solve), the prescribed rows and columns
//! are replaced by their diagonal, and later iterations keep δu_p = 0. The
//! residual at the fixed DOFs is the reaction: the force of the grip on the
//! body is −R_p = f_int − f_ext + M a (reported per grip and component).

use std::time::Instant;

use nalgebra::{Matrix3, SMatrix, SVector};
use rayon::prelude::*;
use solvers::{Assembler, Cholesky, Jacobi, KrylovOptions, KrylovWorkspace, Lu, SolverError};

use super::explicit::BodyForce;
use super::particles::Particles;
use super::scatter::{Bins, SharedMut};
use crate::error::{Error, FailureSite, Result, SceneError};
use crate::grid::{Boundary, Grid};
use crate::material::plasticity::PlasticState;
use crate::material::SolidMaterial;
use crate::shape::{
    CubicBspline, Gimp, LinearHat, ParticleWeights, QuadraticBspline, QuadraticBsplineGimp,
    ShapeKind, Stencil,
};

/// Linear solver for the Newton systems.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LinearSolver {
    /// Sparse Cholesky with symbolic reuse; LU when the tangent is not SPD.
    Cholesky,
    /// Conjugate gradients with a Jacobi preconditioner.
    PcgJacobi {
        /// Relative residual tolerance.
        rel_tol: f64,
        /// Iteration limit.
        max_iter: usize,
    },
}

/// Parameters of the implicit MPM step and its timestep control.
#[derive(Debug, Clone, Copy)]
pub struct ImplicitParams {
    /// Shape function.
    pub shape: ShapeKind,
    /// Newmark dynamics (`true`) or quasistatic load steps (`false`).
    pub dynamic: bool,
    /// Nodes with less folded mass than this are inactive.
    pub mass_floor: f64,
    /// Newton tolerance on ‖δu‖ / ‖u‖ (> 0).
    pub tol_displacement: f64,
    /// Newton tolerance on |δu·R| / |δu₀·R₀| (energy norm, > 0).
    pub tol_energy: f64,
    /// Newton iteration limit per attempt (≥ 1).
    pub max_newton: usize,
    /// Linear solver.
    pub linear: LinearSolver,
    /// Smallest allowed Δt: a failure below it stops the run.
    pub dt_min: f64,
    /// Largest allowed Δt.
    pub dt_max: f64,
    /// Factor applied to Δt after a failed or rejected attempt (0 < · < 1).
    pub dt_cut: f64,
    /// Factor applied to Δt after an easy step (≥ 1).
    pub dt_grow: f64,
    /// A step is easy when Newton took at most this many iterations.
    pub easy_newton: usize,
    /// Modified Newton: assemble and factorise the tangent only at the first
    /// iteration of an attempt (and again after a contraction slower than
    /// 0.1); linear convergence instead of quadratic, far fewer
    /// factorisations on nearly linear problems.
    pub modified_newton: bool,
    /// Largest particle displacement per step as a fraction of the smallest
    /// cell size; a step moving a particle further is redone with a smaller Δt.
    pub max_cell_fraction: f64,
}

impl ImplicitParams {
    /// Defaults for `shape`: tolerances 1e-9 (displacement) and 1e-16
    /// (energy), 25 Newton iterations, Cholesky, Δt ∈ [1e-12, ∞), cut 0.5,
    /// grow 1.25 after ≤ 4 iterations, full Newton, at most half a cell per
    /// step.
    pub fn new(shape: ShapeKind, dynamic: bool, mass_floor: f64) -> Self {
        Self {
            shape,
            dynamic,
            mass_floor,
            tol_displacement: 1e-9,
            tol_energy: 1e-16,
            max_newton: 25,
            linear: LinearSolver::Cholesky,
            dt_min: 1e-12,
            dt_max: f64::INFINITY,
            dt_cut: 0.5,
            dt_grow: 1.25,
            easy_newton: 4,
            modified_newton: false,
            max_cell_fraction: 0.5,
        }
    }

    /// Checks every parameter and that every material has a tangent; the
    /// error names the offending field (`implicit.<field>` or
    /// `materials[i].model`).
    pub fn validate(&self, materials: &[SolidMaterial]) -> Result<()> {
        let bad = |field: &str, msg: String| -> Result<()> {
            Err(SceneError::new(format!("implicit.{field}"), msg).into())
        };
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !pos(self.tol_displacement) {
            return bad(
                "tol_displacement",
                format!("must be finite and > 0, got {}", self.tol_displacement),
            );
        }
        if !pos(self.tol_energy) {
            return bad(
                "tol_energy",
                format!("must be finite and > 0, got {}", self.tol_energy),
            );
        }
        if self.max_newton == 0 {
            return bad("max_newton", "must be ≥ 1, got 0".into());
        }
        if !(self.mass_floor >= 0.0 && self.mass_floor.is_finite()) {
            return bad(
                "mass_floor",
                format!("must be finite and ≥ 0, got {}", self.mass_floor),
            );
        }
        if !pos(self.dt_min) {
            return bad("dt_min", format!("must be > 0, got {}", self.dt_min));
        }
        if self.dt_max.is_nan() || self.dt_max < self.dt_min {
            return bad(
                "dt_max",
                format!("must be ≥ dt_min = {}, got {}", self.dt_min, self.dt_max),
            );
        }
        if !(self.dt_cut > 0.0 && self.dt_cut < 1.0) {
            return bad("dt_cut", format!("must lie in (0, 1), got {}", self.dt_cut));
        }
        if !(self.dt_grow >= 1.0 && self.dt_grow.is_finite()) {
            return bad("dt_grow", format!("must be ≥ 1, got {}", self.dt_grow));
        }
        if self.max_cell_fraction.is_nan() || self.max_cell_fraction <= 0.0 {
            return bad(
                "max_cell_fraction",
                format!("must be > 0, got {}", self.max_cell_fraction),
            );
        }
        if let LinearSolver::PcgJacobi { rel_tol, max_iter } = self.linear {
            if !pos(rel_tol) {
                return bad("linear.rel_tol", format!("must be > 0, got {rel_tol}"));
            }
            if max_iter == 0 {
                return bad("linear.max_iter", "must be ≥ 1, got 0".into());
            }
        }
        for (i, m) in materials.iter().enumerate() {
            if !m.has_implicit_tangent() {
                return Err(SceneError::new(
                    format!("materials[{i}].model"),
                    format!(
                        "material `{}` has no tangent; the implicit mode needs one",
                        m.name
                    ),
                )
                .into());
            }
        }
        Ok(())
    }
}

/// External forces applied to particles (surface tractions lumped onto the
/// particles next to a surface), given at full load; the step scales them by
/// the load factor.
#[derive(Debug, Clone, Default)]
pub struct SurfaceLoad<const D: usize> {
    /// Loaded particles.
    pub particle: Vec<usize>,
    /// Force on each at full load.
    pub force: Vec<SVector<f64, D>>,
}

impl<const D: usize> SurfaceLoad<D> {
    /// A pressure `p` on a surface represented by the particles `particle`:
    /// particle k receives p · `area[k]` along the unit `direction[k]` (the
    /// direction into the body; for an internally pressurised cylinder the
    /// outward radial direction).
    pub fn pressure(
        p: f64,
        particle: Vec<usize>,
        area: &[f64],
        direction: &[SVector<f64, D>],
    ) -> Self {
        let force = area
            .iter()
            .zip(direction)
            .map(|(a, n)| n.normalize() * (p * a))
            .collect();
        Self { particle, force }
    }
}

/// Smallest weight with which a gripped particle makes a node a grip node
/// (weights of one particle sum to 1; an exact-contact weight of round-off
/// size does not count).
pub const GRIP_WEIGHT_FLOOR: f64 = 1e-12;

/// A prescribed displacement of a set of particles (a rigid grip): at load
/// factor λ the gripped particles have moved by λ · `displacement` in the
/// prescribed components (the load factor of [`ImplicitRun::load_ramp`]).
/// See the module documentation for how it enters the Newton system.
#[derive(Debug, Clone)]
pub struct PrescribedDisplacement<const D: usize> {
    /// Gripped particles.
    pub particle: Vec<usize>,
    /// Displacement at full load.
    pub displacement: SVector<f64, D>,
    /// Prescribed components (the others are free).
    pub components: [bool; D],
}

/// Statistics of one accepted step.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct StepStats {
    /// Time at the end of the step.
    pub t: f64,
    /// Timestep taken.
    pub dt: f64,
    /// Load factor at the end of the step.
    pub load: f64,
    /// Newton iterations of the accepted attempt.
    pub newton_iterations: usize,
    /// Linear (Krylov) iterations of the accepted attempt (0 for direct).
    pub linear_iterations: usize,
    /// Tangents assembled and factorised in the accepted attempt (one per
    /// Newton iteration with full Newton; fewer with
    /// [`ImplicitParams::modified_newton`]).
    pub factorisations: usize,
    /// Euclidean residual norm ‖R‖ at every Newton iterate (first = at u = 0,
    /// last = at the converged u).
    pub residuals: Vec<f64>,
    /// Failed or rejected attempts before this one.
    pub retries: usize,
    /// Whether the symbolic factorisation was rebuilt (pattern changed).
    pub symbolic_rebuilt: bool,
    /// Whether the LU fallback was used.
    pub used_lu: bool,
    /// Unknowns of the Newton system.
    pub dofs: usize,
    /// Seconds in P2G, pattern and tangent/residual assembly.
    pub assembly_s: f64,
    /// Part of `assembly_s` in P2G and the sparsity pattern (the rest is the
    /// stress, residual and tangent evaluation).
    pub setup_s: f64,
    /// Seconds in numeric (and symbolic) factorisation / preconditioner setup.
    pub factor_s: f64,
    /// Part of `factor_s` in the symbolic analysis (ordering; only when the
    /// pattern changed).
    pub symbolic_s: f64,
    /// Force of each grip of [`ImplicitRun::prescribed`] on the body at the
    /// end of the step (D components, the sum of −R over its fixed DOFs).
    pub reactions: Vec<Vec<f64>>,
    /// Work the grips, the surface loads and the body force did on the
    /// particles over the step ([`ImplicitRun::step`]; trapezoidal in the
    /// load factor).
    pub external_work: f64,
    /// Seconds in triangular solves / Krylov iterations.
    pub solve_s: f64,
    /// Seconds in the particle update (stress evaluation and G2P).
    pub particles_s: f64,
    /// Wall time of the step including retries.
    pub wall_s: f64,
}

/// Why an attempt failed (internal; the run turns it into a retry or an error).
/// A failed implicit attempt after which Δt was cut.
#[derive(Debug, Clone, PartialEq)]
pub struct DtCut {
    /// The particle the failure names, if any.
    pub particle: Option<usize>,
    /// The reason (Newton did not converge, J ≤ 0, ...).
    pub what: String,
    /// The Δt that failed \[s\].
    pub dt: f64,
}

#[derive(Debug)]
struct Failure {
    what: String,
    particle: Option<usize>,
    /// Inconsistent input that a smaller Δt cannot mend: the key path to
    /// report in a scene error, and the run stops at once.
    fatal: Option<String>,
    /// Redo the attempt with the same Δt (the linear-solver set-up changed).
    redo: bool,
}

impl Failure {
    fn new(what: impl Into<String>, particle: Option<usize>) -> Self {
        Self {
            what: what.into(),
            particle,
            fatal: None,
            redo: false,
        }
    }
}

/// What one linear solve did.
#[derive(Debug, Default)]
struct LinearReport {
    iterations: usize,
    used_lu: bool,
    factor_s: f64,
    symbolic_s: f64,
    solve_s: f64,
}

/// The linear-solver state kept between steps.
#[derive(Default)]
struct LinearCache {
    /// Node-block pattern of the last assembly: dof map, block rows, block columns.
    key: (Vec<usize>, Vec<usize>, Vec<usize>),
    assembler: Option<Assembler>,
    chol: Option<Cholesky>,
    lu: Option<Lu>,
    krylov: KrylovWorkspace,
    /// Whether the stored pattern holds only the lower triangle (Cholesky
    /// reads nothing else).
    stored_lower: bool,
    /// Set once a Cholesky factorisation failed: from then on the full
    /// matrix is assembled, for the LU fallback.
    full_storage: bool,
}

impl LinearCache {
    /// Solves with the stored factorisation (LU when `lu`, else Cholesky);
    /// a missing factorisation is an error, not a panic.
    fn solve_factored(&mut self, lu: bool, rhs: &mut [f64]) -> Result<(), SolverError> {
        let missing = || SolverError::Factorisation("no stored factorisation to reuse".into());
        if lu {
            self.lu.as_mut().ok_or_else(missing)?.solve_in_place(rhs)?;
        } else {
            self.chol
                .as_mut()
                .ok_or_else(missing)?
                .solve_in_place(rhs)?;
        }
        Ok(())
    }
}

/// A solid-only implicit MPM run.
pub struct ImplicitRun<const D: usize> {
    /// Background grid.
    pub grid: Grid<D>,
    /// Solid materials, indexed by `Particles::material`.
    pub materials: Vec<SolidMaterial>,
    /// Particles.
    pub particles: Particles<D>,
    /// Method parameters.
    pub params: ImplicitParams,
    /// Body force per unit mass (scaled by the load factor).
    pub body: Option<Box<dyn BodyForce<D> + Send + Sync>>,
    /// Particle surface forces (scaled by the load factor).
    pub surface: SurfaceLoad<D>,
    /// Load factor min(t / ramp, 1); `None`: always 1.
    pub load_ramp: Option<f64>,
    /// End time (pseudo-time when quasistatic).
    pub end: f64,
    /// Next timestep to try.
    pub dt: f64,
    /// Current time.
    pub t: f64,
    /// Completed steps.
    pub steps: u64,
    /// Statistics of every accepted step.
    pub stats: Vec<StepStats>,
    /// The last failed attempt that cut Δt (what the progress guard names
    /// when Δt collapses); not part of a checkpoint.
    pub last_cut: Option<DtCut>,
    /// Particle accelerations aₚ (Newmark state).
    pub accel: Vec<SVector<f64, D>>,
    /// Grips: particle sets with a prescribed (ramped) displacement.
    pub prescribed: Vec<PrescribedDisplacement<D>>,
    /// Force of each grip on the body at the end of the last step (the
    /// start of the next one's work; empty before the first step).
    pub grip_reactions: Vec<SVector<f64, D>>,
    /// The particles' positions at the start of the step (for the work of
    /// the surface and body loads; empty without such loads).
    x_start: Vec<SVector<f64, D>>,
    /// The fluid's load in a coupled MPM-ICE step (set by the coupling
    /// before each solve; `None` for a solid alone).
    pub fluid_load: Option<FluidLoad<D>>,
    /// Load factor up to which the prescribed displacements are applied.
    prescribed_applied: f64,
    /// A converged coupled solve awaiting [`Self::commit_pending`].
    pending: Option<Pending<D>>,
    map_target: Vec<usize>,
    map_sign: Vec<SVector<f64, D>>,
    node_fixed: Vec<[bool; D]>,
    cache: LinearCache,
    bins: Bins,
    eval: Eval,
    initialised: bool,
}

/// The state an [`ImplicitRun`] carries between steps besides its public
/// fields (see [`ImplicitRun::carried`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImplicitCarried {
    /// Load factor up to which the prescribed displacements are applied.
    pub prescribed_applied: f64,
    /// Whether the initial acceleration has been computed.
    pub initialised: bool,
    /// Whether a failed Cholesky switched the matrix to full storage (LU).
    pub full_storage: bool,
}

/// The fluid's load on a solid field in a coupled MPM-ICE step (Guilkey
/// Sec. 3.3 steps 7–8), on the full grid (ghost nodes included, as the
/// explicit coupled step holds them).
#[derive(Debug, Clone, Default)]
pub struct FluidLoad<const D: usize> {
    /// The cells' pressure force −V θ_s ∇p* on the field's nodes, folded
    /// at walls (an external force of the step).
    pub node_force: Vec<SVector<f64, D>>,
    /// Cell pressure averaged to the nodes; interpolated to each particle
    /// at xⁿ, it enters the internal force as σ + (p − p_ref) I.
    pub node_pressure: Vec<f64>,
    /// Reference pressure p_ref.
    pub p_ref: f64,
}

/// A converged solve of a coupled step, not yet applied to the particles.
struct Pending<const D: usize> {
    sd: StepData<D>,
    u: Vec<f64>,
    /// The particles' displacements (checked against the per-step limit).
    dx: Vec<SVector<f64, D>>,
    dt: f64,
    stats: StepStats,
}

/// Per-step grid data (stencils, dofs, nodal fields).
struct StepData<const D: usize> {
    /// Stencil entries per particle.
    nst: usize,
    /// One particle per distinct stencil base node.
    reps: Vec<usize>,
    /// Mapped (reduced) node of each stencil entry.
    node: Vec<usize>,
    /// Sign of each component of each stencil entry (0 where eliminated).
    sign: Vec<SVector<f64, D>>,
    /// Weight.
    w: Vec<f64>,
    /// Gradient at xⁿ.
    g: Vec<SVector<f64, D>>,
    /// dof[node·D + a], or usize::MAX.
    dof: Vec<usize>,
    /// Lumped mass per dof.
    mass: Vec<f64>,
    /// Grid velocity and acceleration at tⁿ per dof.
    v0: Vec<f64>,
    a0: Vec<f64>,
    /// External force per dof at tⁿ⁺¹.
    fext: Vec<f64>,
    /// Per particle: the fluid pressure p − p_ref added to the stress in the
    /// internal force (empty without a [`FluidLoad`]).
    pp: Vec<f64>,
    /// A residual norm that counts as converged whatever the relative test
    /// says (0 without a [`FluidLoad`]): 1e-10 of the force that the larger
    /// of p_ref and max |p − p_ref| exerts on the particles' domains,
    /// √Σ_p (p V_p / h)². The fluid's pressure carries the rounding of
    /// p − p_ref and the solver's tolerance, which Newton cannot reduce;
    /// near the rest state (a solid at p_ref) the relative test waited for
    /// 7.7e-12 N to shrink (the pressurised cylinder, step 0).
    force_floor: f64,
    /// Compact active-node numbering: node of each block row, and the inverse.
    active: Vec<usize>,
    compact: Vec<usize>,
    /// Block pattern (CSR over compact nodes).
    bptr: Vec<usize>,
    bcol: Vec<usize>,
    /// Slot of each pattern block in the triplet value list, per component
    /// pair (usize::MAX where a dof is eliminated).
    bslot: Vec<[usize; 9]>,
    rows: Vec<usize>,
    cols: Vec<usize>,
    /// Whether the triplets cover only the lower triangle (row ≥ column).
    lower: bool,
    /// Prescribed increment per dof (NaN where free).
    presc: Vec<f64>,
    /// Fixed dofs: (dof, grip, component, diagonal slot).
    presc_list: Vec<(usize, usize, usize, usize)>,
    /// Off-diagonal slots in a prescribed row or column.
    presc_off: Vec<usize>,
    /// Slots of free rows in prescribed columns: (slot, row dof, column dof).
    presc_lift: Vec<(usize, usize, usize)>,
}

/// Particle-level results of one Newton evaluation (buffers kept between
/// steps).
#[derive(Default)]
struct Eval {
    df: Vec<Matrix3<f64>>,
    stress: Vec<Matrix3<f64>>,
    j: Vec<f64>,
    /// Hencky models only (empty otherwise): the plastic state at the end
    /// of the step and the particle's `work` then (stored energy plus
    /// plastic work), committed with the step.
    plastic: Vec<PlasticState>,
    work: Vec<f64>,
}

impl<const D: usize> ImplicitRun<D> {
    /// A run at t = 0 with first timestep `dt` (validated).
    pub fn new(
        grid: Grid<D>,
        materials: Vec<SolidMaterial>,
        particles: Particles<D>,
        params: ImplicitParams,
        end: f64,
        dt: f64,
    ) -> Result<Self> {
        params.validate(&materials)?;
        let mut particles = particles;
        if materials.iter().any(|m| m.plasticity().is_some()) {
            // The plastic state travels with the particles (Hencky's
            // multiplicative plasticity; the heating of its plastic work).
            particles.track_plastic_strain();
            particles.track_temperature();
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(SceneError::new("implicit.dt", format!("must be > 0, got {dt}")).into());
        }
        let (map_target, map_sign, node_fixed) = node_map(&grid);
        let np = particles.len();
        Ok(Self {
            grid,
            materials,
            particles,
            params,
            body: None,
            surface: SurfaceLoad::default(),
            load_ramp: None,
            end,
            dt,
            t: 0.0,
            steps: 0,
            stats: Vec::new(),
            last_cut: None,
            accel: vec![SVector::zeros(); np],
            prescribed: Vec::new(),
            grip_reactions: Vec::new(),
            x_start: Vec::new(),
            fluid_load: None,
            prescribed_applied: 0.0,
            pending: None,
            map_target,
            map_sign,
            node_fixed,
            cache: LinearCache::default(),
            bins: Bins::default(),
            eval: Eval::default(),
            initialised: false,
        })
    }

    /// Whether the end time is reached.
    pub fn finished(&self) -> bool {
        self.t >= self.end * (1.0 - 1e-12)
    }

    /// What a later step reads besides the particles, accelerations, time,
    /// step count and next Δt: for a checkpoint.
    pub fn carried(&self) -> ImplicitCarried {
        ImplicitCarried {
            prescribed_applied: self.prescribed_applied,
            initialised: self.initialised,
            full_storage: self.cache.full_storage,
        }
    }

    /// Restores what [`Self::carried`] returned.
    pub fn restore_carried(&mut self, c: ImplicitCarried) {
        self.prescribed_applied = c.prescribed_applied;
        self.initialised = c.initialised;
        self.cache.full_storage = c.full_storage;
    }

    /// The work of the grips, the surface loads and the body force on the
    /// particles over the accepted step `st` from time `t0` (load factor
    /// `load0`, grips applied to `applied0`), the trapezoidal rule in the
    /// load: a grip's `½ (R⁰ + R¹) · Δd` over its prescribed components, a
    /// surface force's `½ (λ⁰ + λ¹) f · Δx_p`, the body force's
    /// `½ m_p (λ⁰ b⁰ + λ¹ b¹) · Δx_p` (exact for a linear response). Updates
    /// the grips' start-of-step reactions.
    fn external_work(&mut self, st: &StepStats, t0: f64, load0: f64, applied0: f64) -> f64 {
        let load1 = st.load;
        let mut work = 0.0;
        self.grip_reactions
            .resize(self.prescribed.len(), SVector::zeros());
        for ((grip, r0), r1) in self
            .prescribed
            .iter()
            .zip(self.grip_reactions.iter_mut())
            .zip(&st.reactions)
        {
            let r1 = SVector::<f64, D>::from_fn(|a, _| r1[a]);
            for a in (0..D).filter(|&a| grip.components[a]) {
                work += 0.5 * (r0[a] + r1[a]) * grip.displacement[a] * (load1 - applied0);
            }
            *r0 = r1;
        }
        let x = &self.particles.x;
        for (&p, f) in self.surface.particle.iter().zip(&self.surface.force) {
            work += 0.5 * (load0 + load1) * f.dot(&(x[p] - self.x_start[p]));
        }
        if let Some(b) = &self.body {
            let parts = &self.particles;
            for p in 0..parts.len() {
                let b0 = b.accel(&parts.x0[p], &self.x_start[p], t0) * load0;
                let b1 = b.accel(&parts.x0[p], &x[p], st.t) * load1;
                work += 0.5 * parts.mass[p] * (b0 + b1).dot(&(x[p] - self.x_start[p]));
            }
        }
        work
    }

    /// Load factor at time `t`.
    pub fn load_factor(&self, t: f64) -> f64 {
        match self.load_ramp {
            Some(r) if r > 0.0 => (t / r).min(1.0),
            _ => 1.0,
        }
    }

    /// Runs to the end time.
    pub fn run(&mut self) -> Result<()> {
        while !self.finished() {
            self.step()?;
        }
        Ok(())
    }

    /// Takes one step, cutting Δt and retrying on a failed, slow or too-large
    /// step; grows Δt after an easy step. Returns the step's statistics.
    ///
    /// # Errors
    /// [`Error::Numerical`] naming the step, time and worst particle when
    /// Newton fails at the smallest allowed Δt.
    pub fn step(&mut self) -> Result<StepStats> {
        let start = Instant::now();
        // The work of the models that keep it (sized once; after a load too).
        self.particles.track_work_for(&self.materials);
        if self.params.dynamic && !self.initialised {
            self.initial_acceleration()?;
        }
        self.initialised = true;
        let mut dt = self.dt.min(self.params.dt_max);
        if self.params.dynamic {
            // Cap: particles at their current speed cross at most
            // `max_cell_fraction` of a cell (checked again after the solve).
            let vmax = self
                .particles
                .v
                .iter()
                .map(|v| v.norm())
                .fold(0.0, f64::max);
            if vmax > 0.0 {
                dt = dt.min(self.params.max_cell_fraction * self.grid.h.min() / vmax);
            }
        }
        let mut dt = dt.max(self.params.dt_min);
        let mut retries = 0;
        let (t0, load0, applied0) = (self.t, self.load_factor(self.t), self.prescribed_applied);
        if !self.surface.particle.is_empty() || self.body.is_some() {
            self.x_start.clone_from(&self.particles.x);
        }
        loop {
            let dt_try = dt.min(self.end - self.t);
            let last = dt_try >= self.end - self.t;
            match self.attempt(dt_try) {
                Ok(mut st) => {
                    st.retries = retries;
                    st.wall_s = start.elapsed().as_secs_f64();
                    self.t = if last { self.end } else { self.t + dt_try };
                    st.t = self.t;
                    st.external_work = self.external_work(&st, t0, load0, applied0);
                    self.steps += 1;
                    if st.newton_iterations <= self.params.easy_newton {
                        dt *= self.params.dt_grow;
                    }
                    self.dt = dt.min(self.params.dt_max);
                    self.prescribed_applied = st.load;
                    self.stats.push(st.clone());
                    return Ok(st);
                }
                Err(f) => {
                    if let Some(path) = f.fatal {
                        return Err(SceneError::new(path, f.what).into());
                    }
                    if f.redo {
                        retries += 1;
                        continue;
                    }
                    if dt_try <= self.params.dt_min * (1.0 + 1e-12) {
                        return Err(Error::Numerical {
                            site: FailureSite {
                                step: self.steps,
                                time: self.t,
                                particle: f.particle,
                                cell: None,
                            },
                            what: format!(
                                "implicit step failed at the smallest allowed Δt = {:e} \
                                 after {retries} retries: {}",
                                dt_try, f.what
                            ),
                        });
                    }
                    retries += 1;
                    self.last_cut = Some(DtCut {
                        particle: f.particle,
                        what: f.what,
                        dt: dt_try,
                    });
                    dt = (dt_try * self.params.dt_cut).max(self.params.dt_min);
                }
            }
        }
    }

    /// One attempt of a step of size `dt`; the particles change only when
    /// it succeeds.
    fn attempt(&mut self, dt: f64) -> std::result::Result<StepStats, Failure> {
        let mut ev = std::mem::take(&mut self.eval);
        let res = self.attempt_with(dt, &mut ev).and_then(|(mut st, sd, u)| {
            let clock = Instant::now();
            let dx = self.particle_moves(&sd, &u)?;
            self.g2p(&sd, &u, &dx, &ev, dt, &[])?;
            st.particles_s += clock.elapsed().as_secs_f64();
            Ok(st)
        });
        self.eval = ev;
        res
    }

    /// Coupled MPM-ICE: solves a step of `dt` under [`Self::fluid_load`]
    /// (redone on a switch of the linear solver) and keeps the solution
    /// pending; the particles do not change until [`Self::commit_pending`].
    /// The caller owns the time step: a failure here leaves everything as
    /// it was, to be retried with a smaller Δt.
    ///
    /// # Errors
    /// [`Error::Numerical`] naming the step, time and worst particle when
    /// Newton fails or a particle would move more than `max_cell_fraction`
    /// of a cell; a scene error for inconsistent grips.
    pub fn solve_pending(&mut self, dt: f64) -> Result<&StepStats> {
        let start = Instant::now();
        self.pending = None;
        if self.params.dynamic && !self.initialised {
            self.initial_acceleration()?;
        }
        self.initialised = true;
        let mut retries = 0;
        loop {
            let mut ev = std::mem::take(&mut self.eval);
            let res = self
                .attempt_with(dt, &mut ev)
                .and_then(|(st, sd, u)| self.particle_moves(&sd, &u).map(|dx| (st, sd, u, dx)));
            self.eval = ev;
            match res {
                Ok((mut stats, sd, u, dx)) => {
                    stats.retries = retries;
                    stats.wall_s = start.elapsed().as_secs_f64();
                    let p = self.pending.insert(Pending {
                        sd,
                        u,
                        dx,
                        dt,
                        stats,
                    });
                    return Ok(&p.stats);
                }
                Err(f) if f.redo && f.fatal.is_none() && retries < 2 => retries += 1,
                Err(f) => return Err(self.fail(f)),
            }
        }
    }

    /// The pending step's grid velocity at every node of the full grid
    /// (a ghost node by its mirror image, 0 where no particle reaches):
    /// vⁿ⁺¹ = vⁿ + Δt/2 (aⁿ + aⁿ⁺¹) = 2u/Δt − vⁿ (Newmark), u/Δt when
    /// quasistatic. Zero without a pending step.
    pub fn pending_node_velocity(&self, out: &mut [SVector<f64, D>]) {
        let Some(pd) = &self.pending else {
            out.iter_mut().for_each(|v| *v = SVector::zeros());
            return;
        };
        let (sd, inv_dt) = (&pd.sd, 1.0 / pd.dt);
        let dynamic = self.params.dynamic;
        for (n, v) in out.iter_mut().enumerate() {
            let (r, s) = (self.map_target[n], self.map_sign[n]);
            *v = SVector::from_fn(|a, _| {
                let d = sd.dof[r * D + a];
                if d == usize::MAX {
                    0.0
                } else if dynamic {
                    s[a] * (2.0 * pd.u[d] * inv_dt - sd.v0[d])
                } else {
                    s[a] * pd.u[d] * inv_dt
                }
            });
        }
    }

    /// Applies the pending step to the particles (G2P) with `dv`, a grid
    /// velocity increment on the full grid's nodes (the coupling's
    /// momentum exchange, folded at walls; empty for none), added to vⁿ⁺¹
    /// as an impulse at the end of the step (dropped when quasistatic).
    /// The stored aⁿ⁺¹ stays the solve's: carried into the next step's
    /// trapezoidal update as 2 dv/Δt it applied dv a second time, and the
    /// slab on gas springs (`cases/slab_in_gas_implicit.toml`) drifted
    /// from the explicit run the more, the smaller the step (x after a
    /// quarter period −16 % at Δt = 3.1e-4 s, now +1.2 %). Advances the
    /// time and sets the next Δt (grown after an easy step, at most
    /// `dt_max`).
    ///
    /// # Errors
    /// [`Error::Numerical`] without a pending step.
    pub fn commit_pending(&mut self, dv: &[SVector<f64, D>]) -> Result<StepStats> {
        let Some(pd) = self.pending.take() else {
            return Err(self.fail(Failure::new("no solved step to apply", None)));
        };
        let mut extra = vec![0.0; pd.u.len()];
        add_interior(&self.map_target, &pd.sd.dof, dv, |_| 1.0, &mut extra);
        let clock = Instant::now();
        let ev = std::mem::take(&mut self.eval);
        let res = self.g2p(&pd.sd, &pd.u, &pd.dx, &ev, pd.dt, &extra);
        self.eval = ev;
        res.map_err(|f| self.fail(f))?;
        let mut st = pd.stats;
        st.particles_s += clock.elapsed().as_secs_f64();
        self.t += pd.dt;
        st.t = self.t;
        self.steps += 1;
        let grow = if st.newton_iterations <= self.params.easy_newton {
            self.params.dt_grow
        } else {
            1.0
        };
        self.dt = (pd.dt * grow).min(self.params.dt_max);
        self.stats.push(st.clone());
        Ok(st)
    }

    /// Every particle's displacement Σ Nᵢ uᵢ for the grid displacement `u`;
    /// an error when one moves more than `max_cell_fraction` of a cell.
    fn particle_moves(
        &self,
        sd: &StepData<D>,
        u: &[f64],
    ) -> std::result::Result<Vec<SVector<f64, D>>, Failure> {
        let hmin = self.grid.h.min();
        let mut worst = (0.0, 0);
        let mut dx = vec![SVector::<f64, D>::zeros(); self.particles.len()];
        for (p, x) in dx.iter_mut().enumerate() {
            for k in p * sd.nst..(p + 1) * sd.nst {
                *x += gather(sd, u, k) * sd.w[k];
            }
            let m = x.norm();
            if m > worst.0 {
                worst = (m, p);
            }
        }
        if worst.0 > self.params.max_cell_fraction * hmin {
            return Err(Failure::new(
                format!(
                    "particle moved {:.3} cells in one step (limit {})",
                    worst.0 / hmin,
                    self.params.max_cell_fraction
                ),
                Some(worst.1),
            ));
        }
        Ok(dx)
    }

    /// One Newton solve of a step of `dt`: its statistics, grid data and
    /// converged displacement (the particles do not change).
    #[allow(clippy::type_complexity)]
    fn attempt_with(
        &mut self,
        dt: f64,
        ev: &mut Eval,
    ) -> std::result::Result<(StepStats, StepData<D>, Vec<f64>), Failure> {
        let mut st = StepStats {
            dt,
            reactions: vec![vec![0.0; D]; self.prescribed.len()],
            ..Default::default()
        };
        let mut clock = Instant::now();
        let lap = |clock: &mut Instant| {
            let now = Instant::now();
            let s = (now - *clock).as_secs_f64();
            *clock = now;
            s
        };
        let t1 = self.t + dt;
        let load = self.load_factor(t1);
        st.load = load;
        self.bin_particles()?;
        let mut sd = self.p2g(t1, load)?;
        let ndof = sd.mass.len();
        st.dofs = ndof;
        let rebuilt = self.pattern(&mut sd)?;
        st.symbolic_rebuilt = rebuilt;
        st.setup_s = lap(&mut clock);
        st.assembly_s += st.setup_s;
        let dynamic = self.params.dynamic;
        let c_mass = 4.0 / (dt * dt);
        let mut u = vec![0.0; ndof];
        let mut r = vec![0.0; ndof];
        let mut rhs = vec![0.0; ndof];
        let mut du = vec![0.0; ndof];
        let mut vals = vec![0.0; sd.rows.len()];
        let mut converged = false;
        let mut e0 = 0.0;
        let mut r0 = 0.0;
        let mut k = 0;
        // The prescribed increments still to be imposed (first iteration).
        let mut lift = sd.presc_list.iter().any(|e| sd.presc[e.0] != 0.0);
        let mut fscale = norm(&sd.fext);
        loop {
            // Residual R = f_ext − f_int − M a(u); the tangent when needed
            // (every iteration, or with modified Newton only at the first
            // iteration and whenever the last contraction was slower than 0.1).
            let res = &st.residuals;
            let slow = res.len() >= 2 && res[res.len() - 1] > 0.1 * res[res.len() - 2];
            let assemble = !converged && (k == 0 || !self.params.modified_newton || slow);
            if assemble {
                vals.iter_mut().for_each(|v| *v = 0.0);
            }
            self.evaluate(&sd, &u, dt, &mut r, assemble.then_some(&mut vals[..]), ev)?;
            if dynamic {
                for d in 0..ndof {
                    let a = c_mass * (u[d] - dt * sd.v0[d]) - sd.a0[d];
                    r[d] -= sd.mass[d] * a;
                }
                if assemble {
                    for (ci, &node) in sd.active.iter().enumerate() {
                        let diag = sd.bptr[ci]
                            + sd.bcol[sd.bptr[ci]..sd.bptr[ci + 1]]
                                .binary_search(&ci)
                                .expect("diagonal block");
                        for a in 0..D {
                            let d = sd.dof[node * D + a];
                            if d != usize::MAX {
                                vals[sd.bslot[diag][a * D + a]] += c_mass * sd.mass[d];
                            }
                        }
                    }
                }
            }
            // Convergence is judged on the free dofs (the fixed ones carry
            // the reactions).
            let rn = free_norm(&r, &sd.presc);
            st.residuals.push(rn);
            st.assembly_s += lap(&mut clock);
            if !rn.is_finite() {
                return Err(Failure::new("residual is not finite", None));
            }
            if k == 0 {
                r0 = rn;
            }
            fscale = fscale.max(r0);
            if converged || (!lift && rn <= (1e-14 * fscale).max(sd.force_floor)) || ndof == 0 {
                break;
            }
            if k >= self.params.max_newton {
                return Err(Failure::new(
                    format!("Newton did not converge in {k} iterations (residual {r0:e} → {rn:e})"),
                    worst_particle(ev),
                ));
            }
            // Against the step's force scale, not r₀ alone: a step that
            // starts in equilibrium (r₀ at round-off) and is driven by a
            // prescribed displacement has its load in the lifted right-hand
            // side.
            if k > 2 && rn > 1e6 * fscale {
                return Err(Failure::new(
                    format!("Newton diverged (residual {r0:e} → {rn:e})"),
                    worst_particle(ev),
                ));
            }
            // Right-hand side. Fixed dofs: at the first iteration their
            // increment enters as R_f − K_fp Δū_p, and their rows and
            // columns are replaced by the diagonal (d δu_p = d Δū_p, then 0).
            rhs.copy_from_slice(&r);
            if assemble && !sd.presc_list.is_empty() {
                if lift {
                    for &(slot, i, j) in &sd.presc_lift {
                        rhs[i] -= vals[slot] * sd.presc[j];
                    }
                }
                for &slot in &sd.presc_off {
                    vals[slot] = 0.0;
                }
                for &(_, _, _, slot) in &sd.presc_list {
                    if !(vals[slot] > 0.0 && vals[slot].is_finite()) {
                        vals[slot] = 1.0;
                    }
                }
            }
            for &(d, _, _, slot) in &sd.presc_list {
                rhs[d] = if lift { vals[slot] * sd.presc[d] } else { 0.0 };
            }
            if lift {
                fscale = fscale.max(free_norm(&rhs, &sd.presc));
            }
            du.copy_from_slice(&rhs);
            let lin = self.solve(&vals, &mut du, assemble)?;
            st.factorisations += usize::from(assemble);
            st.linear_iterations += lin.iterations;
            st.used_lu |= lin.used_lu;
            st.factor_s += lin.factor_s;
            st.symbolic_s += lin.symbolic_s;
            st.solve_s += lin.solve_s;
            clock = Instant::now();
            let energy = dot(&du, &rhs).abs();
            if k == 0 {
                e0 = energy;
            }
            for (ui, di) in u.iter_mut().zip(&du) {
                *ui += di;
            }
            lift = false;
            k += 1;
            converged = norm(&du) <= self.params.tol_displacement * norm(&u).max(1e-300)
                && energy <= self.params.tol_energy * e0;
        }
        st.newton_iterations = k;
        for &(d, grip, a, _) in &sd.presc_list {
            st.reactions[grip][a] -= r[d];
        }
        st.assembly_s += lap(&mut clock);
        Ok((st, sd, u))
    }

    /// Bins the particles into slabs for the coloured parallel evaluation.
    fn bin_particles(&mut self) -> std::result::Result<(), Failure> {
        self.bins.build(&self.grid, &self.particles.x).map_err(|p| {
            Failure::new(
                "particle position is not finite or has left the grid",
                Some(p),
            )
        })
    }

    /// Consistent initial acceleration (Newmark needs aⁿ): M a⁰ = f_ext −
    /// f_int at t = 0 on the grid, interpolated to the particles.
    fn initial_acceleration(&mut self) -> Result<()> {
        let load = self.load_factor(self.t);
        self.bin_particles().map_err(|f| self.fail(f))?;
        let sd = self.p2g(self.t, load).map_err(|f| self.fail(f))?;
        let ndof = sd.mass.len();
        let u = vec![0.0; ndof];
        let mut r = vec![0.0; ndof];
        let mut ev = std::mem::take(&mut self.eval);
        let res = self.evaluate(&sd, &u, 0.0, &mut r, None, &mut ev);
        self.eval = ev;
        res.map_err(|f| self.fail(f))?;
        let a: Vec<f64> = r.iter().zip(&sd.mass).map(|(f, m)| f / m).collect();
        for p in 0..self.particles.len() {
            let mut ap = SVector::<f64, D>::zeros();
            for k in p * sd.nst..(p + 1) * sd.nst {
                let node = sd.node[k];
                for c in 0..D {
                    let d = sd.dof[node * D + c];
                    if d != usize::MAX {
                        ap[c] += sd.w[k] * sd.sign[k][c] * a[d];
                    }
                }
            }
            self.accel[p] = ap;
        }
        Ok(())
    }

    fn fail(&self, f: Failure) -> Error {
        if let Some(path) = f.fatal {
            return SceneError::new(path, f.what).into();
        }
        Error::Numerical {
            site: FailureSite {
                step: self.steps,
                time: self.t,
                particle: f.particle,
                cell: None,
            },
            what: f.what,
        }
    }

    /// Stencils at xⁿ, active dofs, lumped mass, grid vⁿ, aⁿ and f_ext
    /// (Guilkey Eq. 22, folded with signs onto the reduced dofs).
    fn p2g(&self, t1: f64, load: f64) -> std::result::Result<StepData<D>, Failure> {
        let nst = self.params.shape.stencil().pow(D as u32);
        let np = self.particles.len();
        let mut node = vec![0usize; np * nst];
        let mut w = vec![0.0; np * nst];
        let mut g = vec![SVector::<f64, D>::zeros(); np * nst];
        let grid = &self.grid;
        let parts = &self.particles;
        let shape = self.params.shape;
        let off_grid = std::sync::atomic::AtomicUsize::new(usize::MAX);
        node.par_chunks_mut(nst)
            .zip(w.par_chunks_mut(nst))
            .zip(g.par_chunks_mut(nst))
            .enumerate()
            .for_each(|(p, ((nd, wd), gd))| {
                let xi = grid.to_grid_units(&parts.x[p]);
                if !grid.holds(&xi) || !xi.iter().all(|v| v.is_finite()) {
                    off_grid.fetch_min(p, std::sync::atomic::Ordering::Relaxed);
                    return;
                }
                // uGIMP half-width in cell units from the domain stretched by
                // Fⁿ, l = l⁰ |F_dd| ≤ h/2, frozen over the step (the explicit
                // step's rule); ignored by the other kernels.
                let f = &parts.f.get(p);
                let lp = SVector::<f64, D>::from_fn(|d, _| {
                    (parts.half_size.get(p)[d] * f[(d, d)].abs() * grid.inv_h[d]).min(0.5)
                });
                match shape {
                    ShapeKind::Linear => stencil::<D, 2, _>(grid, LinearHat, &xi, &lp, nd, wd, gd),
                    ShapeKind::Gimp => stencil::<D, 3, _>(grid, Gimp, &xi, &lp, nd, wd, gd),
                    ShapeKind::QuadraticBspline => {
                        stencil::<D, 3, _>(grid, QuadraticBspline, &xi, &lp, nd, wd, gd)
                    }
                    ShapeKind::CubicBspline => {
                        stencil::<D, 4, _>(grid, CubicBspline, &xi, &lp, nd, wd, gd)
                    }
                    ShapeKind::QuadraticBsplineGimp => {
                        stencil::<D, 4, _>(grid, QuadraticBsplineGimp, &xi, &lp, nd, wd, gd)
                    }
                }
            });
        let p = off_grid.load(std::sync::atomic::Ordering::Relaxed);
        if p != usize::MAX {
            return Err(Failure::new(
                "particle position is not finite or has left the grid",
                Some(p),
            ));
        }
        // One representative particle per stencil base node (the node set
        // of a stencil depends on its base only): the pattern loops over these.
        let mut reps: Vec<(usize, usize)> = (0..np).map(|p| (node[p * nst], p)).collect();
        reps.sort_unstable();
        reps.dedup_by_key(|e| e.0);
        let reps: Vec<usize> = reps.into_iter().map(|e| e.1).collect();
        // The fluid pressure at each particle (Guilkey Sec. 3.3 step 7), from
        // the full-grid node values, fixed over the step.
        let pp: Vec<f64> = match &self.fluid_load {
            Some(fl) => (0..np)
                .map(|p| {
                    (p * nst..(p + 1) * nst)
                        .map(|k| w[k] * fl.node_pressure[node[k]])
                        .sum::<f64>()
                        - fl.p_ref
                })
                .collect(),
            None => Vec::new(),
        };
        let force_floor = match &self.fluid_load {
            Some(fl) => {
                let p_scale = pp.iter().fold(fl.p_ref.abs(), |m, v| m.max(v.abs()));
                // The stress of a stiff solid near its reference state
                // carries the round-off of its modulus, ε (λ + 2μ): steel
                // (265 GPa) pushed by a 2 kPa difference of air pressure
                // stalled at a residual of 8.8e-7 N, above the fluid-only
                // floor of 5e-7 N, and Δt collapsed to 2e-7 s.
                let stiff = self
                    .materials
                    .iter()
                    .map(|m| m.elastic.p_wave())
                    .fold(0.0, f64::max);
                let h = grid.h.min();
                (1e-10 * p_scale).max(16.0 * f64::EPSILON * stiff)
                    * parts
                        .vol
                        .iter()
                        .map(|v| (v / h).powi(2))
                        .sum::<f64>()
                        .sqrt()
            }
            None => 0.0,
        };
        // Map full nodes to reduced nodes with signs.
        let mut sign = vec![SVector::<f64, D>::zeros(); np * nst];
        for k in 0..np * nst {
            sign[k] = self.map_sign[node[k]];
            node[k] = self.map_target[node[k]];
        }
        let nn = grid.num_nodes();
        let mut nmass = vec![0.0; nn];
        for k in 0..np * nst {
            nmass[node[k]] += w[k] * parts.mass[k / nst];
        }
        let mut dof = vec![usize::MAX; nn * D];
        let mut ndof = 0;
        let mut active = Vec::new();
        let mut compact = vec![usize::MAX; nn];
        for n in 0..nn {
            if nmass[n] > self.params.mass_floor {
                compact[n] = active.len();
                active.push(n);
                for a in 0..D {
                    if !self.node_fixed[n][a] {
                        dof[n * D + a] = ndof;
                        ndof += 1;
                    }
                }
            }
        }
        // Eliminated components get sign 0 so gathers ignore them.
        for k in 0..np * nst {
            for a in 0..D {
                if dof[node[k] * D + a] == usize::MAX {
                    sign[k][a] = 0.0;
                }
            }
        }
        let mut mass = vec![0.0; ndof];
        let mut v0 = vec![0.0; ndof];
        let mut a0 = vec![0.0; ndof];
        let mut fext = vec![0.0; ndof];
        for p in 0..np {
            let mp = parts.mass[p];
            let mut fb = self
                .body
                .as_ref()
                .map(|b| b.accel(&parts.x0[p], &parts.x[p], t1) * (mp * load))
                .unwrap_or_else(SVector::zeros);
            if fb.iter().any(|v| !v.is_finite()) {
                fb = SVector::repeat(f64::NAN);
            }
            for k in p * nst..(p + 1) * nst {
                for a in 0..D {
                    let d = dof[node[k] * D + a];
                    if d == usize::MAX {
                        continue;
                    }
                    let ws = w[k] * sign[k][a];
                    mass[d] += w[k] * mp;
                    v0[d] += ws * mp * parts.v[p][a];
                    a0[d] += ws * mp * self.accel[p][a];
                    fext[d] += ws * fb[a];
                }
            }
        }
        for (&p, f) in self.surface.particle.iter().zip(&self.surface.force) {
            for k in p * nst..(p + 1) * nst {
                for a in 0..D {
                    let d = dof[node[k] * D + a];
                    if d != usize::MAX {
                        fext[d] += w[k] * sign[k][a] * f[a] * load;
                    }
                }
            }
        }
        if let Some(fl) = &self.fluid_load {
            // The cells' pressure force is already folded onto the interior
            // nodes (each its own reduced node). The fold doubles a node on
            // a mirror face, whose reduced row here is half the folded row
            // (see *Walls*): halved once per such face.
            let mirror = |bc| matches!(bc, Boundary::Fixed | Boundary::Symmetry);
            let share = |n: usize| {
                let c = grid.node_coords(n);
                (0..D)
                    .filter(|&d| {
                        let [lo, hi] = grid.bc[d];
                        (c[d] == 0 && mirror(lo)) || (c[d] == grid.cells[d] as isize && mirror(hi))
                    })
                    .fold(1.0, |s, _| 0.5 * s)
            };
            add_interior(&self.map_target, &dof, &fl.node_force, share, &mut fext);
        }
        for d in 0..ndof {
            v0[d] /= mass[d];
            a0[d] /= mass[d];
        }
        // Grips: every reduced node in the support of a gripped particle has
        // its prescribed components fixed at the increment of the step (the
        // value for a mirrored stencil node carries the mirror sign); walls
        // keep the components they eliminate.
        let mut presc = vec![f64::NAN; ndof];
        let mut presc_list = Vec::new();
        let mut owner = vec![usize::MAX; if self.prescribed.is_empty() { 0 } else { ndof }];
        for (gi, grip) in self.prescribed.iter().enumerate() {
            let inc = grip.displacement * (load - self.prescribed_applied);
            for &p in &grip.particle {
                for k in p * nst..(p + 1) * nst {
                    if w[k] <= GRIP_WEIGHT_FLOOR {
                        continue;
                    }
                    for a in (0..D).filter(|&a| grip.components[a]) {
                        let d = dof[node[k] * D + a];
                        if d == usize::MAX {
                            continue;
                        }
                        let val = sign[k][a] * inc[a];
                        if presc[d].is_nan() {
                            presc[d] = val;
                            owner[d] = gi;
                            presc_list.push((d, gi, a, usize::MAX));
                            continue;
                        }
                        let tol = 1e-12 * (presc[d].abs() + val.abs());
                        if owner[d] != gi || (presc[d] - val).abs() > tol {
                            return Err(Failure {
                                what: format!(
                                    "grips {} and {gi} prescribe different displacements \
                                     of grid node {} (component {a}); keep grips at least \
                                     two cells apart and consistent with mirror walls",
                                    owner[d], node[k]
                                ),
                                particle: Some(p),
                                fatal: Some(format!("implicit.prescribed[{gi}]")),
                                redo: false,
                            });
                        }
                    }
                }
            }
        }
        Ok(StepData {
            nst,
            reps,
            node,
            sign,
            w,
            g,
            dof,
            mass,
            v0,
            a0,
            fext,
            pp,
            force_floor,
            active,
            compact,
            bptr: Vec::new(),
            bcol: Vec::new(),
            bslot: Vec::new(),
            rows: Vec::new(),
            cols: Vec::new(),
            lower: false,
            presc,
            presc_list,
            presc_off: Vec::new(),
            presc_lift: Vec::new(),
        })
    }

    /// Node-block pattern and triplet lists; returns whether it differs from
    /// the last step's (then the factorisation is redone symbolically).
    fn pattern(&mut self, sd: &mut StepData<D>) -> std::result::Result<bool, Failure> {
        let na = sd.active.len();
        let nst = sd.nst;
        let mut nb: Vec<Vec<usize>> = vec![Vec::new(); na];
        let mut local = Vec::with_capacity(nst);
        for &p in &sd.reps {
            local.clear();
            for k in p * nst..(p + 1) * nst {
                let c = sd.compact[sd.node[k]];
                if c != usize::MAX {
                    local.push(c);
                }
            }
            for &a in &local {
                nb[a].extend_from_slice(&local);
            }
        }
        let mut bptr = Vec::with_capacity(na + 1);
        let mut bcol = Vec::new();
        bptr.push(0);
        for (i, row) in nb.iter_mut().enumerate() {
            row.push(i);
            row.sort_unstable();
            row.dedup();
            bcol.extend_from_slice(row);
            bptr.push(bcol.len());
        }
        // The Cholesky factorisation reads only the lower triangle: assemble
        // just that (half the triplets, scatter work and matrix copies),
        // unless a failed factorisation asked for the full matrix (LU).
        let lower = self.params.linear == LinearSolver::Cholesky && !self.cache.full_storage;
        sd.lower = lower;
        // At most D² triplets per block (fewer where walls eliminate dofs).
        let mut rows = Vec::with_capacity(bcol.len() * D * D);
        let mut cols = Vec::with_capacity(bcol.len() * D * D);
        let mut bslot = vec![[usize::MAX; 9]; bcol.len()];
        for ci in 0..na {
            let ni = sd.active[ci];
            for b in bptr[ci]..bptr[ci + 1] {
                let nj = sd.active[bcol[b]];
                for a in 0..D {
                    let di = sd.dof[ni * D + a];
                    if di == usize::MAX {
                        continue;
                    }
                    for c in 0..D {
                        let dj = sd.dof[nj * D + c];
                        if dj == usize::MAX || (lower && di < dj) {
                            continue;
                        }
                        bslot[b][a * D + c] = rows.len();
                        rows.push(di);
                        cols.push(dj);
                    }
                }
            }
        }
        let same = self.cache.assembler.is_some()
            && self.cache.stored_lower == lower
            && self.cache.key.0 == sd.dof
            && self.cache.key.1 == bptr
            && self.cache.key.2 == bcol;
        if !same {
            let ndof = sd.mass.len();
            let asm = Assembler::new(ndof, ndof, &rows, &cols)
                .map_err(|e| Failure::new(format!("assembly: {e}"), None))?;
            self.cache.assembler = Some(asm);
            self.cache.chol = None;
            self.cache.lu = None;
            self.cache.stored_lower = lower;
            self.cache.key = (sd.dof.clone(), bptr.clone(), bcol.clone());
        }
        // Fixed dofs: their diagonal slots, the other slots of their rows
        // and columns, and the coupling slots K_fp used by the first
        // iteration's right-hand side.
        if !sd.presc_list.is_empty() {
            let fixed = |d: usize| !sd.presc[d].is_nan();
            let mut diag = vec![usize::MAX; sd.mass.len()];
            for (slot, (&i, &j)) in rows.iter().zip(&cols).enumerate() {
                match (fixed(i), fixed(j)) {
                    (true, true) if i == j => diag[i] = slot,
                    (false, false) => {}
                    (fi, fj) => {
                        sd.presc_off.push(slot);
                        if !fi {
                            sd.presc_lift.push((slot, i, j));
                        } else if lower && !fj {
                            // Lower storage holds K_ij = K_ji once.
                            sd.presc_lift.push((slot, j, i));
                        }
                    }
                }
            }
            for e in sd.presc_list.iter_mut() {
                e.3 = diag[e.0];
            }
            if sd.presc_list.iter().any(|e| e.3 == usize::MAX) {
                return Err(Failure::new("fixed dof without a diagonal entry", None));
            }
        }
        sd.bptr = bptr;
        sd.bcol = bcol;
        sd.bslot = bslot;
        sd.rows = rows;
        sd.cols = cols;
        Ok(!same)
    }

    /// Per-particle ΔF, σ and J at displacement `u` of a step `dt` into `ev`
    /// (and a Hencky model's plastic state and work change); the residual
    /// f_ext − f_int into `r`, and the tangent triplet values added into
    /// `vals` if given.
    ///
    /// Runs over the slab-coloured bins: particles of slabs of one colour in
    /// parallel, each slab in index order, so concurrent tasks write disjoint
    /// reduced nodes (rows of `r` and of the tangent) and every entry sums its
    /// contributions in an order that does not depend on the thread count.
    fn evaluate(
        &self,
        sd: &StepData<D>,
        u: &[f64],
        dt: f64,
        r: &mut [f64],
        vals: Option<&mut [f64]>,
        ev: &mut Eval,
    ) -> std::result::Result<(), Failure> {
        let np = self.particles.len();
        let nst = sd.nst;
        r.copy_from_slice(&sd.fext);
        ev.df.resize(np, Matrix3::identity());
        ev.stress.resize(np, Matrix3::zeros());
        ev.j.resize(np, 1.0);
        let hencky = self.materials.iter().any(SolidMaterial::is_hencky);
        if hencky {
            ev.plastic.resize(np, PlasticState::default());
            ev.work.resize(np, 0.0);
        }
        let parts = &self.particles;
        let materials = &self.materials;
        let r_out = SharedMut::new(r);
        let vals_out = vals.map(SharedMut::new);
        let df_out = SharedMut::new(&mut ev.df);
        let stress_out = SharedMut::new(&mut ev.stress);
        let j_out = SharedMut::new(&mut ev.j);
        let plastic_out = SharedMut::new(&mut ev.plastic);
        let work_out = SharedMut::new(&mut ev.work);
        let assembling = vals_out.is_some();
        // The failing particle with the lowest index (deterministic) and why.
        let failed = std::sync::Mutex::new(None::<(usize, &'static str)>);
        let fail = |p: usize, what: &'static str| {
            let mut f = failed.lock().unwrap_or_else(|e| e.into_inner());
            if f.is_none_or(|(q, _)| p < q) {
                *f = Some((p, what));
            }
        };
        self.bins.for_each_colored(|p| {
            let rng = p * nst..(p + 1) * nst;
            let mut grad = SMatrix::<f64, D, D>::zeros();
            for k in rng.clone() {
                grad += gather(sd, u, k) * sd.g[k].transpose();
            }
            // ΔF = diag(ΔF_D, I) in 3×3 (plane strain / uniaxial strain).
            let mut df = Matrix3::identity();
            for a in 0..D {
                for b in 0..D {
                    df[(a, b)] += grad[(a, b)];
                }
            }
            let jd = df.determinant();
            let f_new: Matrix3<f64> = df * parts.f.get(p);
            let j = f_new.determinant();
            if !(jd > 0.0 && j > 0.0 && j.is_finite()) {
                fail(p, "deformation gradient inverted or not finite (J ≤ 0)");
                return;
            }
            let mat = &materials[parts.material[p] as usize];
            // A Hencky model: its update from the plastic state at the start
            // of the step, with the tangent ∂τ/∂h when assembling.
            let mut tangent = None;
            let sigma = if mat.is_hencky() {
                let mut sigma = parts.stress.get(p);
                let mut st = PlasticState {
                    plastic_strain: parts.plastic_strain_of(p),
                    temperature: parts.temperature_of(p),
                    damage: 0.0,
                    damage_increment: 0.0,
                };
                let mut w = parts.work_of(p);
                let mut a = assembling.then(|| [[Matrix3::zeros(); 3]; 3]);
                let rho0 = parts.mass[p] / parts.vol0[p];
                if mat
                    .hencky_update(
                        &df,
                        &f_new,
                        j,
                        j / jd,
                        dt,
                        rho0,
                        &mut sigma,
                        &mut w,
                        &mut st,
                        a.as_mut(),
                    )
                    .is_none()
                {
                    fail(p, "elastic left Cauchy–Green tensor not positive definite");
                    return;
                }
                tangent = a;
                // SAFETY: each particle writes only its own entries.
                unsafe {
                    *plastic_out.get(p) = st;
                    *work_out.get(p) = w;
                }
                sigma
            } else {
                mat.implicit_stress(&df, &f_new, j, &parts.stress.get(p))
            };
            let v = jd * parts.vol[p];
            let Some(inv3) = df.try_inverse() else {
                fail(p, "singular incremental deformation gradient");
                return;
            };
            let inv = SMatrix::<f64, D, D>::from_fn(|a, b| inv3[(a, b)]);
            // σ + (p − p_ref) I in a coupled step: ICE applies −θ∇p to the
            // solid, so the pressure is not counted twice (Guilkey Sec. 3.3
            // step 7, as in the explicit step).
            let pf = sd.pp.get(p).copied().unwrap_or(0.0);
            let s =
                SMatrix::<f64, D, D>::from_fn(|a, b| sigma[(a, b)] + if a == b { pf } else { 0.0 });
            // At most 4³ stencil entries (cubic B-spline in 3D).
            let mut gx = [SVector::<f64, D>::zeros(); 64];
            let mut ci = [usize::MAX; 64];
            for (l, k) in rng.clone().enumerate() {
                // Spatial gradient ∇ₓN = ΔF⁻ᵀ ∇N(xⁿ).
                gx[l] = inv.transpose() * sd.g[k];
                // Internal force v σ ∇ₓN (Guilkey Eq. 24), folded with signs.
                let fi = s * gx[l] * v;
                for a in 0..D {
                    let d = sd.dof[sd.node[k] * D + a];
                    if d != usize::MAX {
                        // SAFETY: slab colouring gives concurrent tasks
                        // disjoint reduced nodes, hence disjoint dofs.
                        unsafe { *r_out.get(d) -= sd.sign[k][a] * fi[a] };
                    }
                }
                ci[l] = sd.compact[sd.node[k]];
            }
            if let Some(vals_out) = vals_out {
                let (lam, mu) = match (&tangent, mat.spatial_tangent(j)) {
                    (Some(_), _) => (0.0, 0.0),
                    (None, Some(lm)) => lm,
                    (None, None) => {
                        fail(p, "material has no tangent");
                        return;
                    }
                };
                // Kirchhoff stress and reference volume of a general tangent.
                let tau = sigma * j;
                let v0 = v / j;
                for (l, k) in rng.clone().enumerate() {
                    if ci[l] == usize::MAX {
                        continue;
                    }
                    let row = &sd.bcol[sd.bptr[ci[l]]..sd.bptr[ci[l] + 1]];
                    let sg_i = s * gx[l];
                    for (m, kk) in rng.clone().enumerate() {
                        // Dofs are numbered node by node in compact order, so
                        // a block right of the diagonal is all upper triangle.
                        if ci[m] == usize::MAX || (sd.lower && ci[m] > ci[l]) {
                            continue;
                        }
                        let Ok(pos) = row.binary_search(&ci[m]) else {
                            continue;
                        };
                        let slots = &sd.bslot[sd.bptr[ci[l]] + pos];
                        let (gi, gj) = (&gx[l], &gx[m]);
                        let geo = sg_i.dot(gj);
                        let gg = gi.dot(gj);
                        for a in 0..D {
                            for c in 0..D {
                                let slot = slots[a * D + c];
                                if slot == usize::MAX {
                                    continue;
                                }
                                let kv = if let Some(t) = &tangent {
                                    // General tangent 𝔸 = ∂τ/∂h (Hencky,
                                    // `material::hencky`): V⁰ (𝔸_abcd ∂_b N_i
                                    // ∂_d N_j − τ_ab ∂_b N_j ∂_c N_i), and the
                                    // coupled pressure's own derivative
                                    // v p (∂_a N_i ∂_c N_j − ∂_c N_i ∂_a N_j).
                                    let mut m = 0.0;
                                    for b in 0..D {
                                        for d in 0..D {
                                            m += t[c][d][(a, b)] * gi[b] * gj[d];
                                        }
                                    }
                                    let tg: f64 = (0..D).map(|b| tau[(a, b)] * gj[b]).sum();
                                    v0 * (m - tg * gi[c]) + v * pf * (gi[a] * gj[c] - gi[c] * gj[a])
                                } else {
                                    // Material (isotropic c: λ', μ') plus
                                    // geometric stiffness (∇N_i·σ∇N_j) δ_ac.
                                    let mut kv = lam * gi[a] * gj[c] + mu * gi[c] * gj[a];
                                    if a == c {
                                        kv += mu * gg + geo;
                                    }
                                    v * kv
                                };
                                // SAFETY: the slot lies in the row of a node
                                // of this particle (disjoint across tasks).
                                unsafe {
                                    *vals_out.get(slot) += kv * sd.sign[k][a] * sd.sign[kk][c]
                                };
                            }
                        }
                    }
                }
            }
            // SAFETY: each particle writes only its own entries.
            unsafe {
                *df_out.get(p) = df;
                *stress_out.get(p) = sigma;
                *j_out.get(p) = j;
            }
        });
        match failed.into_inner().unwrap_or_else(|e| e.into_inner()) {
            Some((p, what)) => Err(Failure::new(what, Some(p))),
            None => Ok(()),
        }
    }
}

/// Value of stencil entry `k` of a dof field: u_full = R u_reduced (0 where eliminated).
#[inline]
fn gather<const D: usize>(sd: &StepData<D>, u: &[f64], k: usize) -> SVector<f64, D> {
    {
        let node = sd.node[k];
        SVector::from_fn(|a, _| {
            let d = sd.dof[node * D + a];
            if d == usize::MAX {
                0.0
            } else {
                sd.sign[k][a] * u[d]
            }
        })
    }
}

impl<const D: usize> ImplicitRun<D> {
    /// Solves K x = rhs in place (refactorising when `refactor`, else with
    /// the stored factorisation where there is one).
    fn solve(
        &mut self,
        vals: &[f64],
        rhs: &mut [f64],
        refactor: bool,
    ) -> std::result::Result<LinearReport, Failure> {
        let lin = |e: SolverError| Failure::new(format!("linear solve: {e}"), None);
        let t0 = Instant::now();
        let mut rep = LinearReport::default();
        let asm = self.cache.assembler.as_mut().expect("pattern built");
        let have_factor = self.cache.chol.is_some() || self.cache.lu.is_some();
        if !refactor && have_factor && self.params.linear == LinearSolver::Cholesky {
            // Modified Newton: reuse the factorisation of the last tangent.
            rep.used_lu = self.cache.chol.is_none();
            self.cache.solve_factored(rep.used_lu, rhs).map_err(lin)?;
            rep.solve_s = t0.elapsed().as_secs_f64();
            return Ok(rep);
        }
        let a = if refactor {
            asm.assemble(vals).map_err(lin)?
        } else {
            asm.matrix()
        };
        match self.params.linear {
            LinearSolver::Cholesky => {
                let mut used_lu = self.cache.lu.is_some();
                if !used_lu {
                    let res = match self.cache.chol.as_mut() {
                        Some(c) => c.refactor(a),
                        None => Cholesky::new(a).map(|c| {
                            rep.symbolic_s = c.symbolic_s();
                            self.cache.chol = Some(c);
                        }),
                    };
                    if res.is_err() {
                        self.cache.chol = None;
                        if self.cache.stored_lower {
                            // LU needs the full matrix: assemble it from
                            // now on and redo the attempt.
                            self.cache.full_storage = true;
                            let mut f = Failure::new(
                                "tangent not positive definite: full storage and LU from here",
                                None,
                            );
                            f.redo = true;
                            return Err(f);
                        }
                        used_lu = true;
                    }
                }
                if used_lu {
                    match self.cache.lu.as_mut() {
                        Some(l) => l.refactor(a).map_err(lin)?,
                        None => self.cache.lu = Some(Lu::new(a).map_err(lin)?),
                    }
                }
                rep.used_lu = used_lu;
                rep.factor_s = t0.elapsed().as_secs_f64();
                let t1 = Instant::now();
                self.cache.solve_factored(used_lu, rhs).map_err(lin)?;
                rep.solve_s = t1.elapsed().as_secs_f64();
                Ok(rep)
            }
            LinearSolver::PcgJacobi { rel_tol, max_iter } => {
                let pc = Jacobi::new(a).map_err(lin)?;
                rep.factor_s = t0.elapsed().as_secs_f64();
                let t1 = Instant::now();
                let b = rhs.to_vec();
                rhs.iter_mut().for_each(|v| *v = 0.0);
                let kr = solvers::pcg(
                    a,
                    &pc,
                    &b,
                    rhs,
                    &KrylovOptions { rel_tol, max_iter },
                    &mut self.cache.krylov,
                )
                .map_err(lin)?;
                rep.iterations = kr.iterations;
                rep.solve_s = t1.elapsed().as_secs_f64();
                Ok(rep)
            }
        }
    }

    /// G2P: positions (by the displacements `dx` of
    /// [`Self::particle_moves`]), F, σ, volume, and (dynamic) velocity and
    /// acceleration from the converged increment; `extra` (per dof, empty
    /// for none) is a velocity increment added at the end of the step (see
    /// [`Self::commit_pending`]).
    fn g2p(
        &mut self,
        sd: &StepData<D>,
        u: &[f64],
        dx: &[SVector<f64, D>],
        ev: &Eval,
        dt: f64,
        extra: &[f64],
    ) -> std::result::Result<(), Failure> {
        let np = self.particles.len();
        let nst = sd.nst;
        let ndof = u.len();
        let c_mass = 4.0 / (dt * dt);
        let mut a1 = vec![0.0; ndof];
        let mut dv = vec![0.0; ndof];
        if self.params.dynamic {
            for d in 0..ndof {
                a1[d] = c_mass * (u[d] - dt * sd.v0[d]) - sd.a0[d];
                dv[d] = 0.5 * dt * (sd.a0[d] + a1[d]);
                if let Some(&e) = extra.get(d) {
                    dv[d] += e;
                }
            }
        }
        let parts = &mut self.particles;
        for p in 0..np {
            parts.x[p] += dx[p];
            let mat = &self.materials[parts.material[p] as usize];
            let old = parts.stress.get(p);
            parts.f.set(p, &(ev.df[p] * parts.f.get(p)));
            parts.stress.set(p, &ev.stress[p]);
            parts.vol[p] = ev.j[p] * parts.vol0[p];
            if !ev.plastic.is_empty() && mat.is_hencky() {
                parts.work[p] = ev.work[p];
                if let Some(e) = parts.plastic_strain.get_mut(p) {
                    *e = ev.plastic[p].plastic_strain;
                }
                if let Some(t) = parts.temperature.get_mut(p) {
                    *t = ev.plastic[p].temperature;
                }
            }
            if mat.model == crate::material::SolidModel::LinearElastic {
                let g = ev.df[p] - Matrix3::identity();
                let d = 0.5 * (g + g.transpose());
                parts.work[p] += ev.j[p] * 0.5 * (old + ev.stress[p]).component_mul(&d).sum();
            }
            if self.params.dynamic {
                let mut dvp = SVector::<f64, D>::zeros();
                let mut ap = SVector::<f64, D>::zeros();
                for k in p * nst..(p + 1) * nst {
                    dvp += gather(sd, &dv, k) * sd.w[k];
                    ap += gather(sd, &a1, k) * sd.w[k];
                }
                parts.v[p] += dvp;
                self.accel[p] = ap;
            } else if self.fluid_load.is_some() {
                // Coupled: the velocity of the load step, which the cells
                // see in the next step's P2G (a solid held at zero velocity
                // lets the fluid's pressure solve treat it as a resting
                // fluid, and its pressure relaxes to the gas's).
                parts.v[p] = dx[p] / dt;
            } else {
                parts.v[p] = SVector::zeros();
            }
        }
        Ok(())
    }
}

/// The particle with the smallest Jacobian of the last Newton iterate.
/// Adds `scale(n) values[n]` of every interior node `n` (its own reduced
/// node) to its free dofs in `out` (`dof`: the step's dof map).
fn add_interior<const D: usize>(
    map_target: &[usize],
    dof: &[usize],
    values: &[SVector<f64, D>],
    scale: impl Fn(usize) -> f64,
    out: &mut [f64],
) {
    for (n, v) in values.iter().enumerate() {
        if map_target[n] != n {
            continue;
        }
        let s = scale(n);
        for a in 0..D {
            let d = dof[n * D + a];
            if d != usize::MAX {
                out[d] += s * v[a];
            }
        }
    }
}

fn worst_particle(ev: &Eval) -> Option<usize> {
    ev.j.iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .map(|(p, _)| p)
}

/// Stencil node indices (full grid), weights and physical gradients of one
/// particle.
#[allow(clippy::too_many_arguments)]
fn stencil<const D: usize, const S: usize, K: Stencil<S>>(
    grid: &Grid<D>,
    kernel: K,
    xi: &SVector<f64, D>,
    lp: &SVector<f64, D>,
    node: &mut [usize],
    w: &mut [f64],
    g: &mut [SVector<f64, D>],
) {
    let pw = ParticleWeights::<D, S>::new_physical(kernel, xi, lp, &grid.inv_h);
    let base = grid.node_index(pw.base());
    let strides = grid.strides();
    let mut k = 0;
    pw.for_each(|m, wk, gk| {
        let mut o = 0;
        for d in 0..D {
            o += m[d] * strides[d];
        }
        node[k] = base + o;
        w[k] = wk;
        g[k] = gk;
        k += 1;
    });
}

/// For every grid node: the reduced node it maps to under the mirror
/// constraint u_ghost = R u_mirror, the sign per component, and which
/// components of a reduced node are eliminated (odd on a wall it lies on).
#[allow(clippy::type_complexity)]
fn node_map<const D: usize>(grid: &Grid<D>) -> (Vec<usize>, Vec<SVector<f64, D>>, Vec<[bool; D]>) {
    let nn = grid.num_nodes();
    let mut target = vec![0; nn];
    let mut sign = vec![SVector::<f64, D>::repeat(1.0); nn];
    let mut fixed = vec![[false; D]; nn];
    let flip = |s: &mut SVector<f64, D>, axis: usize, bc: Boundary| match bc {
        Boundary::Fixed => *s = -*s,
        Boundary::Symmetry => s[axis] = -s[axis],
        // Periodic faces are rejected for solids by scene validation.
        Boundary::Free | Boundary::Periodic => {}
    };
    for idx in 0..nn {
        let mut c = grid.node_coords(idx);
        let mut s = SVector::<f64, D>::repeat(1.0);
        for d in 0..D {
            let n = grid.cells[d] as isize;
            let [lo, hi] = grid.bc[d];
            // Reflect repeatedly until inside (narrow domains, wide stencils).
            for _ in 0..8 {
                if c[d] < 0 && !matches!(lo, Boundary::Free | Boundary::Periodic) {
                    c[d] = -c[d];
                    flip(&mut s, d, lo);
                } else if c[d] > n && !matches!(hi, Boundary::Free | Boundary::Periodic) {
                    c[d] = 2 * n - c[d];
                    flip(&mut s, d, hi);
                } else {
                    break;
                }
            }
        }
        target[idx] = grid.node_index(c);
        sign[idx] = s;
        for d in 0..D {
            let n = grid.cells[d] as isize;
            for (on, bc) in [(c[d] == 0, grid.bc[d][0]), (c[d] == n, grid.bc[d][1])] {
                if !on {
                    continue;
                }
                match bc {
                    Boundary::Fixed => fixed[idx].iter_mut().for_each(|f| *f = true),
                    Boundary::Symmetry => fixed[idx][d] = true,
                    Boundary::Free | Boundary::Periodic => {}
                }
            }
        }
    }
    // `fixed[i]` describes the reduced node `target[i]` (only read for
    // reduced nodes, for which it is their own).
    (target, sign, fixed)
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Euclidean norm over the free dofs (`presc` is NaN there).
fn free_norm(v: &[f64], presc: &[f64]) -> f64 {
    v.iter()
        .zip(presc)
        .filter(|(_, p)| p.is_nan())
        .map(|(x, _)| x * x)
        .sum::<f64>()
        .sqrt()
}
