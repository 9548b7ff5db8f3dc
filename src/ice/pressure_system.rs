//! The pressure matrix of the semi-implicit ICE step and its linear solve
//! (DESIGN.md "The implicit pressure"): the 5-/7-point SPD matrix of the
//! linearised Guilkey Eq. 29, `(M δp)_c = V Σ_r θ_r κ_r δp_c + Σ_f c_f
//! (δp_c − δp_nb)`, its links (interior, periodic and Dirichlet faces),
//! assembly without allocation and the direct / multigrid-PCG / Jacobi-PCG
//! solves; and the lazily created buffers of the semi-implicit step
//! ([`ImplicitSlot`]). The outer iteration that uses them is in
//! [`super::implicit`].

use solvers::{
    pcg, Assembler, BoundaryKind, CellStencil, Cholesky, KrylovOptions, KrylovWorkspace,
    LinearOperator, Multigrid, Preconditioner, SolveReport, SolverError,
};

use super::boundary::{Boundaries, IceBoundary};
use super::implicit_params::{pressure_mg_options, LinearSolver};
use super::state::CellLayout;
use super::{invalid, IceError};

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

/// The multigrid's cell stencil of the layout (with its periodic axes)
/// when `solver` is PCG–multigrid; checks that periodic faces come in
/// pairs for every solver.
fn multigrid_stencil<const D: usize>(
    layout: &CellLayout<D>,
    bcs: &Boundaries<D>,
    solver: LinearSolver,
) -> Result<Option<CellStencil>, IceError> {
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
    Ok(stencil)
}

/// The links between unknowns (interior faces, and periodic faces once, at
/// the lower side) and the Dirichlet links of inflow faces, in face order;
/// inflow faces are marked in the multigrid stencil too.
fn face_links<const D: usize>(
    layout: &CellLayout<D>,
    bcs: &Boundaries<D>,
    mut stencil: Option<&mut CellStencil>,
) -> Result<(Vec<Link>, Vec<Link>), IceError> {
    let mut unknown = vec![usize::MAX; layout.len()];
    for (k, &c) in layout.interior.iter().enumerate() {
        unknown[c] = k;
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
                        if let Some(st) = stencil.as_deref_mut() {
                            let mut c3 = [0usize; 3];
                            let cc = layout.coords(cell);
                            for e in 0..D {
                                c3[e] = cc[e] as usize;
                            }
                            st.set_boundary_face(d, side, c3, BoundaryKind::Dirichlet)
                                .map_err(|e| invalid("implicit.linear_solver", e.to_string()))?;
                        }
                    }
                    IceBoundary::Wall | IceBoundary::Outflow => {}
                },
            }
        }
    }
    Ok((links, dirichlet))
}

/// The direct solver's sparse pattern over `n` unknowns (the diagonal, four
/// entries a link, one a Dirichlet link) and its triplet values.
fn direct_assembler(
    n: usize,
    links: &[Link],
    dirichlet: &[Link],
) -> Result<(Assembler, Vec<f64>), IceError> {
    let nt = n + 4 * links.len() + dirichlet.len();
    let (mut rows, mut cols) = (Vec::with_capacity(nt), Vec::with_capacity(nt));
    for k in 0..n {
        rows.push(k);
        cols.push(k);
    }
    for l in links {
        rows.extend_from_slice(&[l.i, l.j, l.i, l.j]);
        cols.extend_from_slice(&[l.i, l.j, l.j, l.i]);
    }
    for l in dirichlet {
        rows.push(l.i);
        cols.push(l.i);
    }
    let a = Assembler::new(n, n, &rows, &cols)
        .map_err(|e| invalid("implicit.linear_solver", e.to_string()))?;
    Ok((a, vec![0.0; nt]))
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
        let mut stencil = multigrid_stencil(layout, bcs, solver)?;
        let (links, dirichlet) = face_links(layout, bcs, stencil.as_mut())?;
        let (assembler, triplets) = if solver == LinearSolver::Direct {
            let (a, t) = direct_assembler(n, &links, &dirichlet)?;
            (Some(a), t)
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
    /// The linear solver the system was built for.
    pub(super) solver: LinearSolver,
    /// The pressure matrix and its solver.
    pub(super) system: PressureSystem,
    /// Pre-exchange face velocities per material and direction.
    pub(super) ustar_pre: Vec<[Vec<f64>; D]>,
    /// Accumulated pressure increment `Δp = Σ δp` (with ghosts).
    pub(super) dp: Vec<f64>,
}

/// Holder of the lazily created `ImplicitWorkspace` inside
/// [`super::IceWorkspace`]; a clone starts empty (the solver is set up again).
pub struct ImplicitSlot<const D: usize>(pub(super) Option<Box<ImplicitWorkspace<D>>>);

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

/// A [`SolverError::InvalidInput`] with `detail`.
fn sv_invalid(detail: impl Into<String>) -> SolverError {
    SolverError::InvalidInput {
        detail: detail.into(),
    }
}
