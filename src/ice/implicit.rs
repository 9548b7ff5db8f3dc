//! Semi-implicit (implicit-pressure) ICE: the pressure of Guilkey Eq. 29
//! solved implicitly, so that the sound speed no longer limits the time step
//! (the paper's conclusion asks for it; DESIGN.md "The implicit pressure").
//!
//! Unknown: the pressure increment `δp` per interior cell in an outer
//! iteration. With the total increment `Δp = Σ δp` the face velocities are
//!
//! ```text
//! u*_r,f(Δp) = E[ u*_r,f,pre − Δt_f v_r,f (Δp_R − Δp_L)/Δx ]
//! ```
//!
//! (`u*_pre` from Guilkey Eq. 28 before the face exchange, `v_r,f` its face
//! specific volume `2 v_L v_R/(v_L + v_R)`, `Δt_f = face_dt_factor Δt`, `E`
//! the pointwise-implicit face momentum exchange), and the pressure
//! equation is Guilkey Eq. 29 multiplied by `V`,
//!
//! ```text
//! R_c(Δp) = V (Σ_r θ_r κ_r Δp_c + Δt Σ_r ∇·(θ u*)_r) = 0,   κ = v/c².
//! ```
//!
//! Its linearisation is the 5-/7-point matrix
//!
//! ```text
//! (M δp)_c = V Σ_r θ_r κ_r δp_c + Σ_f c_f (δp_c − δp_nb),
//! c_f = Δt Δt_f A/Δx Σ_r θ̂_r,f v̂_r,f,
//! ```
//!
//! with `θ̂` the upwind face volume fraction and `v̂ = E v` the face specific
//! volume after the face exchange (so stiff exchange gives the mixture
//! response instead of a plain harmonic mean). Walls, outflow (zero
//! gradient) and symmetry faces contribute nothing (Neumann); inflow faces
//! hold the ghost pressure (Dirichlet, `δp = 0` in the ghost); periodic
//! faces link the two sides. Each outer iteration: `M δp = −R`, `Δp += δp`,
//! face velocities corrected from their pre-exchange values, the face
//! exchange redone, `R` recomputed; converged when `max |R|/V` is below
//! [`SemiImplicit::outer_tolerance`]. The matrix is symmetric positive
//! definite; it is solved by sparse Cholesky with a reused symbolic
//! factorisation, multigrid-preconditioned CG or Jacobi-preconditioned CG
//! ([`LinearSolver`]).

use std::str::FromStr;

use nalgebra::SVector;
use solvers::{
    pcg, Assembler, BoundaryKind, CellStencil, Cholesky, KrylovOptions, KrylovWorkspace,
    LinearOperator, MgOptions, Multigrid, Preconditioner, SolveReport, SolverError,
};

use super::boundary::{fill_scalar, zero_wall_faces, Boundaries, IceBoundary};
use super::exchange::exchange_momentum;
use super::faces::face_exchange;
use super::par::{max_rows, par_face_rows, Out};
use super::state::{CellLayout, IceState};
use super::step::{min_pressure_all, volume_fluxes, IceParams, IceWorkspace};
use super::{invalid, IceError, Site, MAX_MATERIALS};

/// Linear solver of the pressure equation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LinearSolver {
    /// Sparse Cholesky (faer), symbolic factorisation computed once and
    /// reused; numeric refactorisation every step.
    Direct,
    /// Conjugate gradients preconditioned by one geometric multigrid V-cycle
    /// ([`solvers::Multigrid`] with [`pressure_mg_options`], hierarchy
    /// refreshed every step). Periodic directions need an even number of
    /// cells unless the grid is small enough (≤ 128 cells) to be the
    /// multigrid's directly solved coarsest level.
    PcgMultigrid,
    /// Conjugate gradients preconditioned by the diagonal.
    PcgJacobi,
}

impl LinearSolver {
    /// The accepted names, in the order of the variants.
    pub const NAMES: [&'static str; 3] = ["direct", "pcg_multigrid", "pcg_jacobi"];

    /// Stable name of the variant.
    pub fn name(self) -> &'static str {
        match self {
            LinearSolver::Direct => "direct",
            LinearSolver::PcgMultigrid => "pcg_multigrid",
            LinearSolver::PcgJacobi => "pcg_jacobi",
        }
    }
}

impl FromStr for LinearSolver {
    type Err = IceError;

    /// Parses one of [`LinearSolver::NAMES`].
    ///
    /// # Errors
    /// [`IceError::InvalidInput`] naming `implicit.linear_solver`.
    fn from_str(name: &str) -> Result<Self, IceError> {
        match name {
            "direct" => Ok(LinearSolver::Direct),
            "pcg_multigrid" => Ok(LinearSolver::PcgMultigrid),
            "pcg_jacobi" => Ok(LinearSolver::PcgJacobi),
            _ => Err(invalid(
                "implicit.linear_solver",
                format!(
                    "unknown solver `{name}`; expected one of {}",
                    Self::NAMES.join(", ")
                ),
            )),
        }
    }
}

/// Parameters of the semi-implicit pressure ([`IceParams::implicit`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SemiImplicit {
    /// Linear solver of the pressure equation.
    pub linear_solver: LinearSolver,
    /// Relative residual `‖b − Mx‖₂/‖b‖₂` of an iterative linear solve
    /// (`0 < tol < 1`); it must be tighter than the outer tolerance relative
    /// to the residual being solved for, which `1e-10` is by far.
    pub linear_tolerance: f64,
    /// Outer tolerance on `max_c |R_c|/V` (a volume strain per step, the
    /// imbalance of Guilkey Eq. 29), `> 0`.
    pub outer_tolerance: f64,
    /// Largest number of outer iterations (linear solves) per step, `≥ 1`.
    pub max_outer_iterations: usize,
    /// Largest number of Krylov iterations per linear solve, `≥ 1`.
    pub max_linear_iterations: usize,
    /// Factor on the sound speed in the time step estimate
    /// (`cfl / max Σ_d (|u_d| + factor c)/h_d`); `0` (default) limits the
    /// step by advection only, `1` makes `cfl` an acoustic Courant number.
    pub sound_speed_factor: f64,
    /// Largest ratio of a time step to the previous one, `≥ 1`.
    pub max_dt_growth: f64,
    /// Convective predictor `β ∈ [0, 1]`: the cell velocities entering the
    /// face velocities of Guilkey Eq. 28 are `uⁿ + β Δt aⁿ⁻¹`, with
    /// `aⁿ⁻¹ = (uⁿ − u_Lⁿ⁻¹)/Δtⁿ⁻¹` the previous step's advective
    /// acceleration (its advected, step 12, minus its Lagrangian, Eq. 38,
    /// velocity).
    ///
    /// Why: Guilkey (Sec. 3.3, step 3) builds `u*` from "a time advanced
    /// estimate for the cell centered velocity", but Eq. 28 advances the
    /// cell velocity by the pressure (and body-force) acceleration only; the
    /// Lagrangian–Eulerian split adds this step's convective change in
    /// step 12, after Eqs. 29–30 have fixed the pressure. So with `β = 0`
    /// the pressure makes `Σ∇·(θu*)` consistent with a velocity that lacks
    /// this step's convection, which is corrected only by the next step's
    /// pressure: the pressure lags one step, an `O(Δt)` error that is
    /// negligible at the explicit (acoustic) time step and dominant at
    /// large acoustic Courant numbers. `β = 1` adds the convective change
    /// to the time-advanced estimate, extrapolated from the previous step
    /// (first-order extrapolation, error `O(Δt²)` in the estimate), as
    /// projection methods include the convective term in the predicted
    /// face (MAC) velocities they project (Bell, Colella & Glaz, J. Comput.
    /// Phys. 85 (1989) 257). Only the face velocities change: mass,
    /// momentum and energy stay in flux form and are conserved as before.
    /// The first step of a run has no previous acceleration and uses
    /// Eq. 28 as written. Used only by the semi-implicit pressure.
    ///
    /// Measured: `ice_low_mach --quick` (N = 64, t = 0.5) RMS velocity
    /// error at acoustic CFL 10 1.01e-3 → 8.05e-4 and at CFL 50 2.28e-3 →
    /// 9.73e-4 with `β = 1` (explicit CFL 1: 8.25e-4); the full study's
    /// numbers are in `verification/RESULTS.md`. Stable at acoustic CFL
    /// 100 (`acoustic_cfl_100_with_predictor_is_stable`). Default `0`
    /// (Guilkey Eq. 28 as written).
    pub convective_predictor: f64,
}

impl Default for SemiImplicit {
    /// Cholesky, `linear_tolerance = 1e-10`, `outer_tolerance = 1e-9`, 20
    /// outer and 500 linear iterations, `sound_speed_factor = 0`,
    /// `max_dt_growth = 1.2`.
    fn default() -> Self {
        Self {
            linear_solver: LinearSolver::Direct,
            linear_tolerance: 1e-10,
            outer_tolerance: 1e-9,
            max_outer_iterations: 20,
            max_linear_iterations: 500,
            sound_speed_factor: 0.0,
            max_dt_growth: 1.2,
            convective_predictor: 0.0,
        }
    }
}

impl SemiImplicit {
    /// Defaults with the given linear solver.
    pub fn with_solver(linear_solver: LinearSolver) -> Self {
        Self {
            linear_solver,
            ..Self::default()
        }
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`IceError::InvalidInput`] naming the field (`implicit.…`).
    pub fn validate(&self) -> Result<(), IceError> {
        let t = self.linear_tolerance;
        if !(t.is_finite() && t > 0.0 && t < 1.0) {
            return Err(invalid(
                "implicit.linear_tolerance",
                format!("must be in (0, 1), got {t}"),
            ));
        }
        let t = self.outer_tolerance;
        if !(t.is_finite() && t > 0.0) {
            return Err(invalid(
                "implicit.outer_tolerance",
                format!("must be finite and > 0, got {t}"),
            ));
        }
        if self.max_outer_iterations == 0 {
            return Err(invalid("implicit.max_outer_iterations", "must be >= 1"));
        }
        if self.max_linear_iterations == 0 {
            return Err(invalid("implicit.max_linear_iterations", "must be >= 1"));
        }
        let f = self.sound_speed_factor;
        if !(f.is_finite() && f >= 0.0) {
            return Err(invalid(
                "implicit.sound_speed_factor",
                format!("must be finite and >= 0, got {f}"),
            ));
        }
        let g = self.max_dt_growth;
        if !(g.is_finite() && g >= 1.0) {
            return Err(invalid(
                "implicit.max_dt_growth",
                format!("must be finite and >= 1, got {g}"),
            ));
        }
        let b = self.convective_predictor;
        if !(b.is_finite() && (0.0..=1.0).contains(&b)) {
            return Err(invalid(
                "implicit.convective_predictor",
                format!("must be in [0, 1], got {b}"),
            ));
        }
        Ok(())
    }
}

/// Multigrid options of [`LinearSolver::PcgMultigrid`]: the default V(3,3)
/// cycle, with the coarsest level (factorised again every step, as the
/// coefficients change) at most 128 cells instead of 2048. Measured on the
/// `ice_low_mach` vortex at 128², acoustic CFL 50: 0.89 s CPU for the run
/// against 1.14 s with 2048 (the 32² coarsest Cholesky refactorisation and
/// its triangular solves were ~6% of the step), 6.9–7.0 PCG iterations per
/// step either way. A periodic direction with an odd number of cells is
/// only accepted when the whole grid fits this coarsest level (see
/// [`solvers::Multigrid`]).
pub fn pressure_mg_options() -> MgOptions {
    MgOptions {
        coarse_max_cells: 128,
        ..MgOptions::default()
    }
}

/// Relative size of the compressibility diagonal `V Σθκ` below which a
/// closed-domain pressure matrix counts as singular.
const SINGULAR_RATIO: f64 = 1e-14;

/// A matrix connection between two unknowns through one face (or a
/// Dirichlet boundary face, `j == usize::MAX`).
#[derive(Debug, Clone, Copy)]
struct Link {
    /// Unknown on the lower side (the interior cell for a boundary face).
    i: usize,
    /// Unknown on the upper side (`usize::MAX` on a Dirichlet face).
    j: usize,
    /// Flat face index in the ICE layout.
    face: usize,
    /// Face normal.
    d: usize,
    /// Face position in the [`CellStencil`] (position 0 of its direction
    /// for a periodic link, the stencil's wrap face; `usize::MAX` without a
    /// stencil).
    sface: usize,
}

/// The pressure matrix and its solver: built once per layout, boundary
/// conditions and solver; values refreshed every step without allocation.
pub(crate) struct PressureSystem {
    solver: LinearSolver,
    links: Vec<Link>,
    dirichlet: Vec<Link>,
    coeff: Vec<f64>,
    dcoeff: Vec<f64>,
    diag_extra: Vec<f64>,
    diag: Vec<f64>,
    inv_diag: Vec<f64>,
    pub(crate) rhs: Vec<f64>,
    pub(crate) x: Vec<f64>,
    triplets: Vec<f64>,
    assembler: Option<Assembler>,
    chol: Option<Cholesky>,
    stencil: Option<CellStencil>,
    mg: Option<Multigrid>,
    krylov: KrylovWorkspace,
}

/// `y = M x` from the links (the Jacobi-PCG operator).
struct LinkOperator<'a> {
    diag: &'a [f64],
    links: &'a [Link],
    coeff: &'a [f64],
}

impl LinearOperator for LinkOperator<'_> {
    fn dim(&self) -> usize {
        self.diag.len()
    }

    fn apply(&self, x: &[f64], y: &mut [f64]) {
        for ((y, d), x) in y.iter_mut().zip(self.diag).zip(x) {
            *y = d * x;
        }
        for (l, &c) in self.links.iter().zip(self.coeff) {
            y[l.i] -= c * x[l.j];
            y[l.j] -= c * x[l.i];
        }
    }
}

/// Diagonal scaling with a precomputed inverse diagonal.
struct InvDiag<'a>(&'a [f64]);

impl Preconditioner for InvDiag<'_> {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        for ((z, r), d) in z.iter_mut().zip(r).zip(self.0) {
            *z = r * d;
        }
    }
}

impl PressureSystem {
    /// The links of a layout: interior faces, periodic faces (once, at the
    /// lower side) and inflow (Dirichlet) faces; walls and outflow faces are
    /// Neumann and have none.
    pub(crate) fn new<const D: usize>(
        layout: &CellLayout<D>,
        bcs: &Boundaries<D>,
        solver: LinearSolver,
    ) -> Result<Self, IceError> {
        let n = layout.num_interior();
        let mut unknown = vec![usize::MAX; layout.len()];
        for (k, &c) in layout.interior.iter().enumerate() {
            unknown[c] = k;
        }
        let mut sdims = [1usize; 3];
        sdims[..D].copy_from_slice(&layout.cells);
        let mut stencil = if solver == LinearSolver::PcgMultigrid {
            Some(
                CellStencil::new(sdims)
                    .map_err(|e| invalid("implicit.linear_solver", e.to_string()))?,
            )
        } else {
            None
        };
        for d in 0..D {
            let periodic = bcs[d].each_ref().map(|b| *b == IceBoundary::Periodic);
            if periodic[0] != periodic[1] {
                return Err(invalid(
                    format!("boundaries[{d}]"),
                    "periodic must be set on both sides",
                ));
            }
            if let (true, Some(st)) = (periodic[0], stencil.as_mut()) {
                st.set_periodic(d)
                    .map_err(|e| invalid("implicit.linear_solver", e.to_string()))?;
            }
        }
        let mut links = Vec::new();
        let mut dirichlet = Vec::new();
        for d in 0..D {
            let s = layout.strides[d];
            let nd = layout.cells[d] as isize;
            for &f in &layout.faces[d] {
                let ijk = layout.coords(f);
                let mut pos = [0usize; 3];
                for e in 0..D {
                    pos[e] = ijk[e].max(0) as usize;
                }
                let sface = stencil
                    .as_ref()
                    .map_or(usize::MAX, |st| st.face_index(d, pos));
                let side = if ijk[d] == 0 {
                    Some(0)
                } else if ijk[d] == nd {
                    Some(1)
                } else {
                    None
                };
                match side {
                    None => links.push(Link {
                        i: unknown[f - s],
                        j: unknown[f],
                        face: f,
                        d,
                        sface,
                    }),
                    Some(side) => match &bcs[d][side] {
                        IceBoundary::Periodic => {
                            if side == 0 && nd > 1 {
                                links.push(Link {
                                    i: unknown[f + (nd as usize - 1) * s],
                                    j: unknown[f],
                                    face: f,
                                    d,
                                    sface,
                                });
                            }
                        }
                        IceBoundary::Inflow(_) => {
                            let cell = if side == 0 { f } else { f - s };
                            dirichlet.push(Link {
                                i: unknown[cell],
                                j: usize::MAX,
                                face: f,
                                d,
                                sface,
                            });
                            if let Some(st) = stencil.as_mut() {
                                let mut c3 = [0usize; 3];
                                let cc = layout.coords(cell);
                                for e in 0..D {
                                    c3[e] = cc[e] as usize;
                                }
                                st.set_boundary_face(d, side, c3, BoundaryKind::Dirichlet)
                                    .map_err(|e| {
                                        invalid("implicit.linear_solver", e.to_string())
                                    })?;
                            }
                        }
                        IceBoundary::Wall | IceBoundary::Outflow => {}
                    },
                }
            }
        }
        let (assembler, triplets) = if solver == LinearSolver::Direct {
            let nt = n + 4 * links.len() + dirichlet.len();
            let (mut rows, mut cols) = (Vec::with_capacity(nt), Vec::with_capacity(nt));
            for k in 0..n {
                rows.push(k);
                cols.push(k);
            }
            for l in &links {
                rows.extend_from_slice(&[l.i, l.j, l.i, l.j]);
                cols.extend_from_slice(&[l.i, l.j, l.j, l.i]);
            }
            for l in &dirichlet {
                rows.push(l.i);
                cols.push(l.i);
            }
            let a = Assembler::new(n, n, &rows, &cols)
                .map_err(|e| invalid("implicit.linear_solver", e.to_string()))?;
            (Some(a), vec![0.0; nt])
        } else {
            (None, Vec::new())
        };
        Ok(Self {
            solver,
            coeff: vec![0.0; links.len()],
            dcoeff: vec![0.0; dirichlet.len()],
            links,
            dirichlet,
            diag_extra: vec![0.0; n],
            diag: vec![0.0; n],
            inv_diag: vec![0.0; n],
            rhs: vec![0.0; n],
            x: vec![0.0; n],
            triplets,
            assembler,
            chol: None,
            stencil,
            mg: None,
            krylov: KrylovWorkspace::with_dim(n),
        })
    }

    /// Sets the face coefficients from `coef(face, d)`, the extra diagonal
    /// `V Σθκ` per unknown, and refreshes the solver (Cholesky numeric
    /// refactorisation with the reused symbolic analysis, or the multigrid
    /// hierarchy).
    ///
    /// # Errors
    /// [`SolverError::Singular`] when no cell has compressibility and no
    /// face is Dirichlet (closed incompressible box: the constant is in the
    /// null space), or any error of the factorisation / hierarchy.
    pub(crate) fn assemble(
        &mut self,
        mut coef: impl FnMut(usize, usize) -> f64,
        diag_extra: impl Fn(usize) -> f64,
    ) -> Result<(), SolverError> {
        for (k, de) in self.diag_extra.iter_mut().enumerate() {
            *de = diag_extra(k);
        }
        for (c, l) in self.coeff.iter_mut().zip(&self.links) {
            *c = coef(l.face, l.d);
        }
        for (c, l) in self.dcoeff.iter_mut().zip(&self.dirichlet) {
            *c = coef(l.face, l.d);
        }
        self.finish()
    }

    /// Test hook: sets the coefficients directly.
    #[cfg(test)]
    pub(crate) fn assemble_uniform(&mut self, c: f64, de: f64) -> Result<(), SolverError> {
        self.assemble(|_, _| c, |_| de)
    }

    fn finish(&mut self) -> Result<(), SolverError> {
        let bad = |x: &f64| !(x.is_finite() && *x >= 0.0);
        if self.diag_extra.iter().any(bad)
            || self.coeff.iter().any(bad)
            || self.dcoeff.iter().any(bad)
        {
            return Err(sv_invalid(
                "pressure matrix has a negative or non-finite coefficient",
            ));
        }
        self.diag.copy_from_slice(&self.diag_extra);
        for (l, &c) in self.links.iter().zip(&self.coeff) {
            self.diag[l.i] += c;
            self.diag[l.j] += c;
        }
        for (l, &c) in self.dirichlet.iter().zip(&self.dcoeff) {
            self.diag[l.i] += c;
        }
        // Anchoring: a Dirichlet face, or compressibility that is not lost
        // in round-off against the face coefficients (relative 1e-14, i.e.
        // an acoustic Courant number below ~1e7); otherwise the constant
        // pressure mode is (numerically) in the null space.
        let max_diag = self.diag.iter().copied().fold(0.0, f64::max);
        let max_extra = self.diag_extra.iter().copied().fold(0.0, f64::max);
        let anchored = self.dcoeff.iter().any(|&x| x > 0.0)
            || (max_extra > 0.0 && max_extra > SINGULAR_RATIO * max_diag);
        if !anchored {
            return Err(SolverError::Singular {
                detail: format!(
                    "pressure matrix is singular: closed domain (no inflow/Dirichlet face) and max V Σθκ = {max_extra:e} is negligible against the face coefficients (max diagonal {max_diag:e}), so a constant pressure is undetermined"
                ),
            });
        }
        match self.solver {
            LinearSolver::Direct => {
                let n = self.diag.len();
                self.triplets[..n].copy_from_slice(&self.diag);
                let mut k = n;
                for &c in &self.coeff {
                    self.triplets[k..k + 4].copy_from_slice(&[0.0, 0.0, -c, -c]);
                    k += 4;
                }
                self.triplets[k..].fill(0.0);
                let asm = self
                    .assembler
                    .as_mut()
                    .ok_or_else(|| sv_invalid("no assembler"))?;
                let a = asm.assemble(&self.triplets)?;
                match self.chol.as_mut() {
                    Some(ch) => ch.refactor(a)?,
                    None => self.chol = Some(Cholesky::new(a)?),
                }
            }
            LinearSolver::PcgJacobi => {
                for (i, d) in self.inv_diag.iter_mut().zip(&self.diag) {
                    *i = 1.0 / d;
                }
            }
            LinearSolver::PcgMultigrid => {
                let st = self
                    .stencil
                    .as_mut()
                    .ok_or_else(|| sv_invalid("no stencil"))?;
                st.diag_extra_mut().copy_from_slice(&self.diag_extra);
                for (l, &c) in self.links.iter().zip(&self.coeff) {
                    st.face_coeffs_mut(l.d)[l.sface] = c;
                }
                for (l, &c) in self.dirichlet.iter().zip(&self.dcoeff) {
                    st.face_coeffs_mut(l.d)[l.sface] = c;
                }
                match self.mg.as_mut() {
                    Some(mg) => mg.refresh(st)?,
                    None => self.mg = Some(Multigrid::new(st, &pressure_mg_options())?),
                }
            }
        }
        Ok(())
    }

    /// Solves `M x = rhs` (`x` overwritten, starting from 0).
    ///
    /// # Errors
    /// Any error of the solver (not converged, breakdown, singular).
    pub(crate) fn solve(&mut self, opts: &KrylovOptions) -> Result<SolveReport, SolverError> {
        self.x.fill(0.0);
        match self.solver {
            LinearSolver::Direct => {
                self.x.copy_from_slice(&self.rhs);
                let ch = self
                    .chol
                    .as_mut()
                    .ok_or_else(|| sv_invalid("not assembled"))?;
                ch.solve_in_place(&mut self.x)
            }
            LinearSolver::PcgJacobi => {
                let op = LinkOperator {
                    diag: &self.diag,
                    links: &self.links,
                    coeff: &self.coeff,
                };
                pcg(
                    &op,
                    &InvDiag(&self.inv_diag),
                    &self.rhs,
                    &mut self.x,
                    opts,
                    &mut self.krylov,
                )
            }
            LinearSolver::PcgMultigrid => {
                let (st, mg) = match (self.stencil.as_ref(), self.mg.as_ref()) {
                    (Some(s), Some(m)) => (s, m),
                    _ => return Err(sv_invalid("not assembled")),
                };
                pcg(st, mg, &self.rhs, &mut self.x, opts, &mut self.krylov)
            }
        }
    }
}

/// Buffers of the semi-implicit step, created on the first semi-implicit
/// step of a workspace (once per run) and reused.
pub(crate) struct ImplicitWorkspace<const D: usize> {
    solver: LinearSolver,
    system: PressureSystem,
    /// Pre-exchange face velocities per material and direction.
    ustar_pre: Vec<[Vec<f64>; D]>,
    /// Accumulated pressure increment `Δp = Σ δp` (with ghosts).
    dp: Vec<f64>,
}

/// Holder of the lazily created [`ImplicitWorkspace`] inside
/// [`IceWorkspace`]; a clone starts empty (the solver is set up again).
pub struct ImplicitSlot<const D: usize>(Option<Box<ImplicitWorkspace<D>>>);

impl<const D: usize> Default for ImplicitSlot<D> {
    fn default() -> Self {
        Self(None)
    }
}

impl<const D: usize> Clone for ImplicitSlot<D> {
    fn clone(&self) -> Self {
        Self(None)
    }
}

impl<const D: usize> std::fmt::Debug for ImplicitSlot<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.0 {
            Some(w) => write!(f, "ImplicitSlot({})", w.solver.name()),
            None => write!(f, "ImplicitSlot(empty)"),
        }
    }
}

/// Creates the semi-implicit buffers on first use and stores the
/// pre-exchange face velocities (`ws.ustar` right after Guilkey Eq. 28).
///
/// # Errors
/// [`IceError::InvalidInput`] when the pressure system cannot be built.
pub(super) fn save_pre_exchange<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    sp: &SemiImplicit,
    ws: &mut IceWorkspace<D>,
) -> Result<(), IceError> {
    let rebuild = match &ws.implicit.0 {
        Some(w) => w.solver != sp.linear_solver || w.dp.len() != state.layout.len(),
        None => true,
    };
    if rebuild {
        let n = state.layout.len();
        ws.implicit.0 = Some(Box::new(ImplicitWorkspace {
            solver: sp.linear_solver,
            system: PressureSystem::new(&state.layout, &params.boundaries, sp.linear_solver)?,
            ustar_pre: (0..state.num_materials())
                .map(|_| std::array::from_fn(|_| vec![0.0; n]))
                .collect(),
            dp: vec![0.0; n],
        }));
    }
    let iw = ws
        .implicit
        .0
        .as_mut()
        .ok_or_else(|| invalid("implicit", "workspace missing"))?;
    for (pre, cur) in iw.ustar_pre.iter_mut().zip(&ws.ustar) {
        for d in 0..D {
            pre[d].copy_from_slice(&cur[d]);
        }
    }
    Ok(())
}

fn sv_invalid(detail: impl Into<String>) -> SolverError {
    SolverError::InvalidInput {
        detail: detail.into(),
    }
}

/// Harmonic face specific volume of Guilkey Eq. 28.
#[inline]
fn v_face(vl: f64, vr: f64) -> f64 {
    2.0 * vl * vr / (vl + vr)
}

/// The semi-implicit pressure (replaces Guilkey Eq. 29's explicit `Δp`):
/// outer iteration on `M δp = −R` (see the module documentation). On
/// return `ws.ustar` holds the corrected, exchanged face velocities, the
/// volume fluxes (`ws.mix_vflux`, `ws.div_sum`, `ws.kappa`,
/// `ws.sum_theta_kappa`) match them, and `ws.press = p_eq + w Δp`
/// (interior; Guilkey Eq. 30 with the pressure weight `w`). Returns
/// `(outer iterations, linear iterations)`.
///
/// # Errors
/// [`IceError::PressureSolve`]: singular matrix (not retryable); failed
/// linear solve, too many outer iterations, growing residual, non-physical
/// pressure (retryable with a smaller `Δt`).
pub(super) fn implicit_pressure<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    sp: &SemiImplicit,
    ws: &mut IceWorkspace<D>,
    dt: f64,
    fdt: f64,
) -> Result<(usize, usize), IceError> {
    let layout = &state.layout;
    let nm = state.num_materials();
    let k_on = params
        .exchange
        .as_ref()
        .filter(|e| nm > 1 && e.momentum.iter().any(|&k| k > 0.0));
    let mut iw = ws
        .implicit
        .0
        .take()
        .ok_or_else(|| invalid("implicit", "workspace missing"))?;
    let res = outer_iteration(
        state,
        params,
        sp,
        ws,
        &mut iw,
        dt,
        fdt,
        k_on.map(|e| &e.momentum[..]),
    );
    ws.implicit.0 = Some(iw);
    let (outer, linear, res_max) = res?;
    // Guilkey Eq. 30: p = p_eq + Δp (the sources use p_eq + w Δp).
    let iw = ws
        .implicit
        .0
        .as_ref()
        .ok_or_else(|| invalid("implicit", "workspace missing"))?;
    let p_min = min_pressure_all(state);
    for &c in &layout.interior {
        let p = state.p_eq[c] + iw.dp[c];
        if !(p.is_finite() && p > p_min) {
            return Err(IceError::PressureSolve {
                site: site_at(state, c),
                reason: format!("non-physical pressure p = {p:e}"),
                outer,
                residual: res_max,
                dt,
                retryable: true,
            });
        }
        let w = params.source_weight(iw.dp[c], state.p_eq[c], || {
            super::step::cell_shock_sensor(layout, &state.p_eq, c)
        });
        ws.press[c] = state.p_eq[c] + w * iw.dp[c];
    }
    Ok((outer, linear))
}

fn site_at<const D: usize>(state: &IceState<D>, c: usize) -> Site {
    Site {
        step: state.steps,
        time: state.time,
        cell: state.layout.coords(c).to_vec(),
        material: None,
    }
}

/// Largest `|R_c|/V = |Σθκ Δp_c + Δt Σ∇·(θu*)|` over the interior (exact
/// maximum, thread-count independent).
fn residual_max<const D: usize>(
    layout: &CellLayout<D>,
    ws: &IceWorkspace<D>,
    dp: &[f64],
    dt: f64,
) -> f64 {
    let (stk, div) = (&ws.sum_theta_kappa, &ws.div_sum);
    max_rows(layout, |row| {
        let mut m: f64 = 0.0;
        for c in row {
            let r = (stk[c] * dp[c] + dt * div[c]).abs();
            // NaN propagates as the maximum.
            m = if r.is_nan() { f64::NAN } else { m.max(r) };
        }
        m
    })
}

/// The cell of the largest residual (for error messages).
fn residual_argmax<const D: usize>(
    layout: &CellLayout<D>,
    ws: &IceWorkspace<D>,
    dp: &[f64],
    dt: f64,
) -> usize {
    let mut best = (layout.interior[0], -1.0);
    for &c in &layout.interior {
        let r = (ws.sum_theta_kappa[c] * dp[c] + dt * ws.div_sum[c]).abs();
        if r.is_nan() {
            return c;
        }
        if r > best.1 {
            best = (c, r);
        }
    }
    best.0
}

#[allow(clippy::too_many_arguments)]
fn outer_iteration<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    sp: &SemiImplicit,
    ws: &mut IceWorkspace<D>,
    iw: &mut ImplicitWorkspace<D>,
    dt: f64,
    fdt: f64,
    k_mom: Option<&[f64]>,
) -> Result<(usize, usize, f64), IceError> {
    let layout = &state.layout;
    let bcs = &params.boundaries;
    let nm = state.num_materials();
    let vol = layout.cell_volume();
    let opts = KrylovOptions {
        rel_tol: sp.linear_tolerance,
        max_iter: sp.max_linear_iterations,
    };
    iw.dp.fill(0.0);
    let mut linear = 0usize;
    let mut prev = f64::INFINITY;
    let fail = |ws: &IceWorkspace<D>,
                dp: &[f64],
                outer: usize,
                res: f64,
                reason: String,
                retryable: bool| {
        IceError::PressureSolve {
            site: site_at(state, residual_argmax(layout, ws, dp, dt)),
            reason,
            outer,
            residual: res,
            dt,
            retryable,
        }
    };
    for outer in 0..=sp.max_outer_iterations {
        // Guilkey Eq. 29 residual with the current face velocities.
        volume_fluxes(state, params, ws, dt);
        let res = residual_max(layout, ws, &iw.dp, dt);
        if res <= sp.outer_tolerance {
            return Ok((outer, linear, res));
        }
        if !res.is_finite() {
            return Err(fail(
                ws,
                &iw.dp,
                outer,
                res,
                "non-finite residual".into(),
                true,
            ));
        }
        if outer == sp.max_outer_iterations {
            return Err(fail(
                ws,
                &iw.dp,
                outer,
                res,
                format!(
                    "not converged in {} outer iterations",
                    sp.max_outer_iterations
                ),
                true,
            ));
        }
        if outer >= 2 && res > prev {
            return Err(fail(
                ws,
                &iw.dp,
                outer,
                res,
                format!("outer iteration diverges (residual {prev:e} → {res:e})"),
                true,
            ));
        }
        prev = res;
        if outer == 0 {
            // The matrix, once per step: upwind θ̂ from the exchanged face
            // velocities, v̂ = E v (the face exchange applied to the face
            // specific volumes), V Σθκ on the diagonal.
            let cells = &state.cells;
            let ustar = &ws.ustar;
            let stk = &ws.sum_theta_kappa;
            let interior = &layout.interior;
            let scale: [f64; D] =
                std::array::from_fn(|d| dt * fdt * vol / (layout.h[d] * layout.h[d]));
            let r = iw.system.assemble(
                |f, d| {
                    let l = f - layout.strides[d];
                    let mut theta = [0.0; MAX_MATERIALS];
                    let mut v = [0.0; MAX_MATERIALS];
                    let mut w = [0.0; MAX_MATERIALS];
                    let mut vv = [SVector::<f64, 1>::zeros(); MAX_MATERIALS];
                    for m in 0..nm {
                        let mc = &cells[m];
                        theta[m] = 0.5 * (mc.vol_frac[l] + mc.vol_frac[f]);
                        v[m] = v_face(mc.sp_vol[l], mc.sp_vol[f]);
                        w[m] = theta[m] / v[m];
                        vv[m][0] = v[m];
                    }
                    if let Some(k) = k_mom {
                        exchange_momentum(k, dt, &theta[..nm], &v[..nm], &w[..nm], &mut vv[..nm]);
                    }
                    let mut sum = 0.0;
                    for m in 0..nm {
                        let mc = &cells[m];
                        let u = ustar[m][d][f];
                        let th = if u > 0.0 {
                            mc.vol_frac[l]
                        } else if u < 0.0 {
                            mc.vol_frac[f]
                        } else {
                            theta[m]
                        };
                        sum += th * vv[m][0];
                    }
                    scale[d] * sum
                },
                |k| vol * stk[interior[k]],
            );
            if let Err(e) = r {
                let retryable = !matches!(e, SolverError::Singular { .. });
                return Err(fail(
                    ws,
                    &iw.dp,
                    outer,
                    res,
                    format!("pressure matrix: {e}"),
                    retryable,
                ));
            }
        }
        // M δp = −R.
        for (b, &c) in iw.system.rhs.iter_mut().zip(&layout.interior) {
            *b = -vol * (ws.sum_theta_kappa[c] * iw.dp[c] + dt * ws.div_sum[c]);
        }
        match iw.system.solve(&opts) {
            Ok(rep) => linear += rep.iterations,
            Err(e) => {
                let retryable = !matches!(e, SolverError::Singular { .. });
                return Err(fail(
                    ws,
                    &iw.dp,
                    outer,
                    res,
                    format!("linear solve ({}): {e}", sp.linear_solver.name()),
                    retryable,
                ));
            }
        }
        for (&x, &c) in iw.system.x.iter().zip(&layout.interior) {
            iw.dp[c] += x;
        }
        // Ghosts of Δp: zero gradient at walls and outflow, periodic copy,
        // zero (Dirichlet) at inflow.
        fill_scalar(layout, bcs, &mut iw.dp, |_| 0.0);
        // Face velocities from their pre-exchange values:
        // u* = u*_pre − Δt_f v_f ∇Δp, then the face exchange again.
        for r in 0..nm {
            let mc = &state.cells[r];
            for d in 0..D {
                let s = layout.strides[d];
                let inv_h = 1.0 / layout.h[d];
                let pre = &iw.ustar_pre[r][d];
                let dp = &iw.dp;
                let sv = &mc.sp_vol;
                let out = Out::new(&mut ws.ustar[r][d]);
                par_face_rows(layout, d, |row| {
                    for f in row {
                        let u =
                            pre[f] - fdt * v_face(sv[f - s], sv[f]) * (dp[f] - dp[f - s]) * inv_h;
                        // SAFETY: each face is written by one task only.
                        unsafe { out.set(f, u) };
                    }
                });
                zero_wall_faces(layout, bcs, d, &mut ws.ustar[r][d]);
            }
        }
        if let Some(k) = k_mom {
            for d in 0..D {
                face_exchange(
                    layout,
                    d,
                    k,
                    dt,
                    &state.cells,
                    &params.rigid_mask(),
                    &mut ws.ustar,
                );
            }
        }
    }
    // The loop returns at `outer == max_outer_iterations` at the latest.
    Err(invalid(
        "implicit.max_outer_iterations",
        "outer iteration ended without a result",
    ))
}
