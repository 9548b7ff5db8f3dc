//! Cell-centred structured-grid operators with variable face coefficients.
//!
//! A [`CellStencil`] represents, on an `nx × ny (× nz)` grid of cells,
//!
//! ```text
//! (A u)_i = diag_extra_i u_i + Σ_{faces f of i} c_f (u_i − u_j(f))
//! ```
//!
//! where `j(f)` is the neighbour across face `f`. On a domain-boundary face
//! of kind [`BoundaryKind::Neumann`] nothing is added; on a
//! [`BoundaryKind::Dirichlet`] face the coefficient is added to the diagonal
//! (ghost value 0). An axis whose boundary faces are all
//! [`BoundaryKind::Periodic`] (both sides; see [`CellStencil::set_periodic`])
//! wraps around: its face at position 0, which is the same face as position
//! `n_a`, links cell `0` and cell `n_a − 1` like an interior face. The
//! matrix is symmetric, and positive definite when every connected component
//! (through faces with `c > 0`, wrap faces included) touches a Dirichlet
//! face with `c > 0` or contains a cell with `diag_extra > 0` (an
//! all-periodic or all-Neumann operator without `diag_extra` has the
//! constant in its null space).
//!
//! Indexing: cells are numbered `i + nx (j + ny k)`. Face coefficients are
//! stored per axis, including both boundary layers: along axis `a` with
//! `n_a` cells there are `n_a + 1` face positions, position `m` being the
//! face between cells `m − 1` and `m` (positions `0` and `n_a` are boundary
//! faces; on a periodic axis position 0 holds the wrap face and position
//! `n_a` is not read). See [`CellStencil::face_index`]. A grid with
//! `nz == 1` is 2D and has no axis-2 faces.

use faer::sparse::SparseColMat;

use crate::assembly::SparsityPattern;
use crate::error::{check_len, Result, SolverError};
use crate::operator::LinearOperator;

/// Kind of a domain-boundary face.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BoundaryKind {
    /// Zero flux: the face contributes nothing.
    #[default]
    Neumann,
    /// Homogeneous Dirichlet (ghost value 0): the face coefficient is added
    /// to the diagonal.
    Dirichlet,
    /// Periodic: the boundary face at the low end of the axis is the one at
    /// the high end, linking cell `0` and cell `n_a − 1` with the coefficient
    /// stored at face position 0. Must be set on every face of both sides
    /// of an axis ([`CellStencil::set_periodic`]); anything else is rejected
    /// by [`CellStencil::validate`].
    Periodic,
}

/// Variable-coefficient cell-centred operator on a 2D or 3D structured grid
/// (see the module documentation for the definition and indexing).
#[derive(Debug, Clone)]
pub struct CellStencil {
    dims: [usize; 3],
    ndim: usize,
    face: [Vec<f64>; 3],
    /// `bc[axis][side][t]`, `t` = transverse index (see `boundary_slot`).
    bc: [[Vec<BoundaryKind>; 2]; 3],
    /// Axis with [`BoundaryKind::Periodic`] on every face of both sides.
    periodic: [bool; 3],
    diag_extra: Vec<f64>,
}

impl CellStencil {
    /// A grid of `dims = [nx, ny, nz]` cells (`nz = 1` for 2D) with all
    /// coefficients zero and all boundaries Neumann.
    pub fn new(dims: [usize; 3]) -> Result<Self> {
        if dims.contains(&0) {
            return Err(SolverError::invalid(format!(
                "grid dims {dims:?} must be >= 1"
            )));
        }
        let ndim = if dims[2] > 1 { 3 } else { 2 };
        let n = dims[0] * dims[1] * dims[2];
        let mut face: [Vec<f64>; 3] = Default::default();
        let mut bc: [[Vec<BoundaryKind>; 2]; 3] = Default::default();
        for (a, (f, b)) in face.iter_mut().zip(bc.iter_mut()).enumerate().take(ndim) {
            *f = vec![0.0; n / dims[a] * (dims[a] + 1)];
            let nt = n / dims[a];
            b[0] = vec![BoundaryKind::Neumann; nt];
            b[1] = vec![BoundaryKind::Neumann; nt];
        }
        Ok(Self {
            dims,
            ndim,
            face,
            bc,
            periodic: [false; 3],
            diag_extra: vec![0.0; n],
        })
    }

    /// Constant face coefficient `coeff`, constant `diag_extra` and the same
    /// boundary kind on every boundary face.
    pub fn uniform(
        dims: [usize; 3],
        coeff: f64,
        diag_extra: f64,
        boundary: BoundaryKind,
    ) -> Result<Self> {
        let mut s = Self::new(dims)?;
        for a in 0..s.ndim {
            s.face[a].fill(coeff);
            s.set_boundary_side(a, 0, boundary)?;
            s.set_boundary_side(a, 1, boundary)?;
        }
        s.diag_extra.fill(diag_extra);
        s.validate()?;
        Ok(s)
    }

    /// Face coefficients from a cell field `k` (length = number of cells):
    /// interior face `c = scale · 2 k_a k_b / (k_a + k_b)` (harmonic mean, 0 if
    /// both vanish), boundary face `c = scale · k_cell` (ghost cell with the
    /// same value; with [`BoundaryKind::Periodic`] the harmonic mean of the
    /// two cells the wrap face links, at positions 0 and `n_a`), `diag_extra`
    /// zero, all boundaries set to `boundary`.
    pub fn from_cell_field(
        dims: [usize; 3],
        k: &[f64],
        scale: f64,
        boundary: BoundaryKind,
    ) -> Result<Self> {
        let mut s = Self::new(dims)?;
        check_len(s.num_cells(), k.len())?;
        let [nx, ny, nz] = dims;
        let harm = |a: f64, b: f64| {
            if a + b > 0.0 {
                2.0 * a * b / (a + b)
            } else {
                0.0
            }
        };
        for a in 0..s.ndim {
            let na = dims[a];
            for kk in 0..nz + usize::from(a == 2) {
                for j in 0..ny + usize::from(a == 1) {
                    for i in 0..nx + usize::from(a == 0) {
                        let f = [i, j, kk];
                        let m = f[a];
                        let mut lo = f;
                        let hi = f;
                        let c = if (m == 0 || m == na) && boundary == BoundaryKind::Periodic {
                            let mut a_lo = f;
                            a_lo[a] = na - 1;
                            let mut a_hi = f;
                            a_hi[a] = 0;
                            harm(k[s.cell_index(a_lo)], k[s.cell_index(a_hi)])
                        } else if m == 0 {
                            k[s.cell_index(hi)]
                        } else if m == na {
                            lo[a] -= 1;
                            k[s.cell_index(lo)]
                        } else {
                            lo[a] -= 1;
                            harm(k[s.cell_index(lo)], k[s.cell_index(hi)])
                        };
                        let idx = s.face_index(a, f);
                        s.face[a][idx] = scale * c;
                    }
                }
            }
            s.set_boundary_side(a, 0, boundary)?;
            s.set_boundary_side(a, 1, boundary)?;
        }
        s.validate()?;
        Ok(s)
    }

    /// Grid dimensions `[nx, ny, nz]`.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// 2 or 3.
    pub fn ndim(&self) -> usize {
        self.ndim
    }

    /// Number of cells (unknowns).
    pub fn num_cells(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// Linear index of cell `[i, j, k]`.
    #[inline]
    pub fn cell_index(&self, c: [usize; 3]) -> usize {
        c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])
    }

    /// Linear index into [`CellStencil::face_coeffs`]`(axis)` of the face at
    /// position `f[axis]` (0..=n_axis) and transverse cell indices given by
    /// the other components of `f`.
    #[inline]
    pub fn face_index(&self, axis: usize, f: [usize; 3]) -> usize {
        let mut d = self.dims;
        d[axis] += 1;
        f[0] + d[0] * (f[1] + d[1] * f[2])
    }

    /// Face coefficients of `axis` (length `(n_axis + 1) · Π other dims`;
    /// empty for axis 2 of a 2D grid or an invalid axis). Boundary positions
    /// are used only on Dirichlet faces and, on a periodic axis, position 0
    /// (the wrap face; position `n_axis` is then not read).
    pub fn face_coeffs(&self, axis: usize) -> &[f64] {
        self.face.get(axis).map_or(&[], |v| &v[..])
    }

    /// Mutable face coefficients of `axis` (empty for a non-existent axis).
    /// [`Multigrid::new`](crate::Multigrid::new) and
    /// [`CellStencil::to_matrix`] validate the values.
    pub fn face_coeffs_mut(&mut self, axis: usize) -> &mut [f64] {
        match self.face.get_mut(axis) {
            Some(v) => &mut v[..],
            None => &mut [],
        }
    }

    /// Sets one face coefficient (see [`CellStencil::face_index`]).
    pub fn set_face(&mut self, axis: usize, f: [usize; 3], c: f64) -> Result<()> {
        self.check_axis(axis)?;
        for a in 0..3 {
            let lim = self.dims[a] + usize::from(a == axis);
            if f[a] >= lim {
                return Err(SolverError::invalid(format!(
                    "face {f:?} of axis {axis} out of range"
                )));
            }
        }
        if !(c >= 0.0 && c.is_finite()) {
            return Err(SolverError::invalid(format!(
                "face coefficient {c} must be finite and >= 0"
            )));
        }
        let idx = self.face_index(axis, f);
        self.face[axis][idx] = c;
        Ok(())
    }

    /// Per-cell extra diagonal term (length = number of cells).
    pub fn diag_extra(&self) -> &[f64] {
        &self.diag_extra
    }

    /// Mutable per-cell extra diagonal term.
    pub fn diag_extra_mut(&mut self) -> &mut [f64] {
        &mut self.diag_extra
    }

    fn check_axis(&self, axis: usize) -> Result<()> {
        if axis >= self.ndim {
            return Err(SolverError::invalid(format!(
                "axis {axis} does not exist in a {}D grid",
                self.ndim
            )));
        }
        Ok(())
    }

    /// Transverse slot of the boundary face of `cell` on `axis`.
    #[inline]
    fn boundary_slot(&self, axis: usize, c: [usize; 3]) -> usize {
        match axis {
            0 => c[1] + self.dims[1] * c[2],
            1 => c[0] + self.dims[0] * c[2],
            _ => c[0] + self.dims[0] * c[1],
        }
    }

    /// Sets the kind of every face on one domain side (`side` 0 = low,
    /// 1 = high end of `axis`). [`BoundaryKind::Periodic`] takes effect once
    /// both sides of the axis are periodic ([`CellStencil::set_periodic`]
    /// does both at once); a half-periodic axis fails
    /// [`CellStencil::validate`].
    pub fn set_boundary_side(
        &mut self,
        axis: usize,
        side: usize,
        kind: BoundaryKind,
    ) -> Result<()> {
        self.check_axis(axis)?;
        if side > 1 {
            return Err(SolverError::invalid("side must be 0 or 1"));
        }
        self.bc[axis][side].fill(kind);
        self.update_periodic(axis);
        Ok(())
    }

    /// Makes `axis` periodic: every boundary face of both sides becomes
    /// [`BoundaryKind::Periodic`], and the face at position 0 links cell 0
    /// and cell `n_axis − 1`.
    pub fn set_periodic(&mut self, axis: usize) -> Result<()> {
        self.set_boundary_side(axis, 0, BoundaryKind::Periodic)?;
        self.set_boundary_side(axis, 1, BoundaryKind::Periodic)
    }

    /// Whether `axis` is periodic (every face of both sides
    /// [`BoundaryKind::Periodic`]); `false` for a non-existent axis.
    pub fn is_periodic(&self, axis: usize) -> bool {
        self.periodic.get(axis).copied().unwrap_or(false)
    }

    fn update_periodic(&mut self, axis: usize) {
        self.periodic[axis] = self.bc[axis]
            .iter()
            .all(|side| side.iter().all(|&k| k == BoundaryKind::Periodic));
    }

    /// Whether `axis` wraps with a real link (periodic and at least two
    /// cells; with one cell the wrap face links the cell to itself and
    /// contributes nothing).
    #[inline]
    pub(crate) fn wraps(&self, axis: usize) -> bool {
        self.periodic[axis] && self.dims[axis] >= 2
    }

    /// Sets the kind of the single boundary face of `cell` on the given
    /// side of `axis` (the cell must touch that side). Periodicity is a
    /// property of a whole axis: [`BoundaryKind::Periodic`] is rejected here
    /// (use [`CellStencil::set_periodic`]); setting another kind on a
    /// periodic axis makes it half-periodic, which
    /// [`CellStencil::validate`] rejects.
    pub fn set_boundary_face(
        &mut self,
        axis: usize,
        side: usize,
        cell: [usize; 3],
        kind: BoundaryKind,
    ) -> Result<()> {
        self.check_axis(axis)?;
        if kind == BoundaryKind::Periodic {
            return Err(SolverError::invalid(format!(
                "periodic boundaries are set per axis (set_periodic({axis})), not per face"
            )));
        }
        let want = if side == 0 { 0 } else { self.dims[axis] - 1 };
        if side > 1 || cell[axis] != want || (0..3).any(|a| cell[a] >= self.dims[a]) {
            return Err(SolverError::invalid(format!(
                "cell {cell:?} is not on side {side} of axis {axis}"
            )));
        }
        let t = self.boundary_slot(axis, cell);
        self.bc[axis][side][t] = kind;
        self.update_periodic(axis);
        Ok(())
    }

    /// Kind of the boundary face of `cell` on `side` (0 = low, 1 = high) of
    /// `axis`; only the transverse components of `cell` are used.
    pub fn boundary_kind(
        &self,
        axis: usize,
        side: usize,
        cell: [usize; 3],
    ) -> Result<BoundaryKind> {
        self.check_axis(axis)?;
        if side > 1 || (0..3).any(|a| a != axis && cell[a] >= self.dims[a]) {
            return Err(SolverError::invalid(format!(
                "no boundary face for cell {cell:?} on side {side} of axis {axis}"
            )));
        }
        Ok(self.kind_unchecked(axis, side, cell))
    }

    #[inline]
    fn kind_unchecked(&self, axis: usize, side: usize, cell: [usize; 3]) -> BoundaryKind {
        self.bc[axis][side][self.boundary_slot(axis, cell)]
    }

    /// Effective coefficient of a boundary face added to the diagonal (0 for
    /// Neumann and Periodic; the wrap link is handled by the callers).
    #[inline]
    pub(crate) fn boundary_coeff(&self, axis: usize, side: usize, cell: [usize; 3]) -> f64 {
        if self.kind_unchecked(axis, side, cell) == BoundaryKind::Dirichlet {
            let mut f = cell;
            f[axis] = if side == 0 { 0 } else { self.dims[axis] };
            self.face[axis][self.face_index(axis, f)]
        } else {
            0.0
        }
    }

    /// Checks array lengths, that all coefficients are finite and `>= 0`,
    /// and that every axis with a [`BoundaryKind::Periodic`] face is
    /// periodic on all faces of both sides.
    pub fn validate(&self) -> Result<()> {
        fn first_bad(x: &[f64]) -> Option<(usize, f64)> {
            // Branch-free scan first (vectorisable), then locate.
            let bad = x
                .iter()
                .fold(false, |acc, &c| acc | !(0.0..=f64::MAX).contains(&c));
            if bad {
                x.iter()
                    .copied()
                    .enumerate()
                    .find(|&(_, c)| !(0.0..=f64::MAX).contains(&c))
            } else {
                None
            }
        }
        let n = self.num_cells();
        check_len(n, self.diag_extra.len())?;
        for a in 0..self.ndim {
            let any_periodic = self.bc[a]
                .iter()
                .any(|side| side.contains(&BoundaryKind::Periodic));
            if any_periodic && !self.periodic[a] {
                return Err(SolverError::invalid(format!(
                    "axis {a} is periodic on some boundary faces only; periodic must be set on every face of both sides (set_periodic({a}))"
                )));
            }
        }
        for a in 0..self.ndim {
            check_len(n / self.dims[a] * (self.dims[a] + 1), self.face[a].len())?;
            if let Some((i, c)) = first_bad(&self.face[a]) {
                return Err(SolverError::invalid(format!(
                    "face coefficient {i} of axis {a} is {c} (must be finite and >= 0)"
                )));
            }
        }
        if let Some((i, c)) = first_bad(&self.diag_extra) {
            return Err(SolverError::invalid(format!(
                "diag_extra[{i}] = {c} (must be finite and >= 0)"
            )));
        }
        Ok(())
    }

    /// Returns [`SolverError::Singular`] if some connected component of the
    /// grid graph (cells linked by faces with `c > 0`) has neither a cell
    /// with `diag_extra > 0` nor a Dirichlet face with `c > 0`: its constant
    /// mode is then in the null space. Also validates the data.
    pub fn check_nonsingular(&self) -> Result<()> {
        self.validate()?;
        let n = self.num_cells();
        let [nx, ny, nz] = self.dims;
        // Fast path (no allocation, as every step's multigrid refresh calls
        // this): every interior face has c > 0, so the grid is connected and
        // one anchor anywhere suffices.
        let all_connected = (0..self.ndim).all(|a| {
            let na = self.dims[a];
            self.interior_faces(a)
                .all(|(f, _, _)| self.face[a][f] > 0.0)
                || na == 1
        });
        let periodic_axes = (0..self.ndim).filter(|&a| self.periodic[a]).count();
        if all_connected {
            let mut any = self.diag_extra.iter().any(|&d| d > 0.0);
            if !any {
                self.for_each_boundary_anchor(|_| any = true);
            }
            if any {
                return Ok(());
            }
            return Err(SolverError::Singular {
                detail: format!(
                    "the {nx}x{ny}x{nz} grid ({periodic_axes} periodic axes) has no Dirichlet face with c > 0 and no diag_extra > 0 (constant mode in the null space)"
                ),
            });
        }
        // Anchored cells: diag_extra > 0 or a Dirichlet face with c > 0.
        let mut anchored: Vec<bool> = self.diag_extra.iter().map(|&d| d > 0.0).collect();
        self.for_each_boundary_anchor(|p| anchored[p] = true);
        // General case: union-find over faces with c > 0.
        let mut parent: Vec<usize> = (0..n).collect();
        fn find(parent: &mut [usize], mut x: usize) -> usize {
            while parent[x] != x {
                parent[x] = parent[parent[x]];
                x = parent[x];
            }
            x
        }
        for a in 0..self.ndim {
            for (f, lo, hi) in self.interior_faces(a).chain(self.wrap_faces(a)) {
                if self.face[a][f] > 0.0 {
                    let (ra, rb) = (find(&mut parent, lo), find(&mut parent, hi));
                    if ra != rb {
                        let (small, big) = if ra < rb { (ra, rb) } else { (rb, ra) };
                        parent[big] = small;
                    }
                }
            }
        }
        let mut root_ok = vec![false; n];
        for (p, &anch) in anchored.iter().enumerate() {
            if anch {
                let r = find(&mut parent, p);
                root_ok[r] = true;
            }
        }
        for p in 0..n {
            let r = find(&mut parent, p);
            if !root_ok[r] {
                let size = (0..n).filter(|&q| find(&mut parent, q) == r).count();
                let c = [p % nx, (p / nx) % ny, p / (nx * ny)];
                return Err(SolverError::Singular {
                    detail: format!(
                        "connected component of {size} cells containing cell {c:?} has no Dirichlet face and no diag_extra > 0 (constant mode in the null space; grid {nx}x{ny}x{nz})"
                    ),
                });
            }
        }
        Ok(())
    }

    /// Calls `f(cell)` for every cell with a Dirichlet face with `c > 0`.
    fn for_each_boundary_anchor(&self, mut f: impl FnMut(usize)) {
        let [nx, ny, nz] = self.dims;
        for a in 0..self.ndim {
            let na = self.dims[a];
            let ext = |b: usize| if b == a { 1 } else { [nx, ny, nz][b] };
            for side in 0..2 {
                for k in 0..ext(2) {
                    for j in 0..ext(1) {
                        for i in 0..ext(0) {
                            let mut c = [i, j, k];
                            c[a] = if side == 0 { 0 } else { na - 1 };
                            if self.boundary_coeff(a, side, c) > 0.0 {
                                f(self.cell_index(c));
                            }
                        }
                    }
                }
            }
        }
    }

    /// Iterator over the interior faces of `axis`: (face index, low cell,
    /// high cell).
    fn interior_faces(&self, axis: usize) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        let [nx, ny, nz] = self.dims;
        let step = [1, nx, nx * ny][axis];
        let na = self.dims[axis];
        (0..nz).flat_map(move |k| {
            (0..ny).flat_map(move |j| {
                (0..nx).filter_map(move |i| {
                    let c = [i, j, k];
                    if c[axis] == 0 {
                        return None;
                    }
                    let _ = na;
                    let hi = i + nx * (j + ny * k);
                    Some((self.face_index(axis, c), hi - step, hi))
                })
            })
        })
    }

    /// Iterator over the wrap faces of a periodic `axis` (none otherwise, or
    /// with a single cell along it): (face index at position 0, cell
    /// `n_a − 1`, cell 0).
    fn wrap_faces(&self, axis: usize) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        let [nx, ny, nz] = self.dims;
        let wraps = self.wraps(axis);
        let na = self.dims[axis];
        (0..nz).flat_map(move |k| {
            (0..ny).flat_map(move |j| {
                (0..nx).filter_map(move |i| {
                    let c = [i, j, k];
                    if !wraps || c[axis] != 0 {
                        return None;
                    }
                    let mut last = c;
                    last[axis] = na - 1;
                    Some((
                        self.face_index(axis, c),
                        self.cell_index(last),
                        self.cell_index(c),
                    ))
                })
            })
        })
    }

    /// Number of triplets produced by [`CellStencil::triplet_pattern`].
    pub fn num_triplets(&self) -> usize {
        let n = self.num_cells();
        let mut t = n;
        for a in 0..self.ndim {
            let links = if self.wraps(a) {
                self.dims[a]
            } else {
                self.dims[a] - 1
            };
            t += 2 * (n / self.dims[a]) * links;
        }
        t
    }

    /// Row and column indices of the matrix triplets, in the fixed order
    /// used by [`CellStencil::triplet_values`]: for each cell, its diagonal,
    /// then its neighbours in the order −z, −y, −x, +x, +y, +z (across a
    /// periodic axis the wrap neighbour; with two cells along a periodic
    /// axis both neighbours are the same cell and the duplicate triplets are
    /// summed on assembly).
    /// The pattern depends only on the grid dimensions (zero coefficients
    /// are kept), so the values can be refreshed in place.
    pub fn triplet_pattern(&self) -> (Vec<usize>, Vec<usize>) {
        let nt = self.num_triplets();
        let mut rows = Vec::with_capacity(nt);
        let mut cols = Vec::with_capacity(nt);
        self.for_each_entry(|r, c, _| {
            rows.push(r);
            cols.push(c);
        });
        (rows, cols)
    }

    /// Triplet values matching [`CellStencil::triplet_pattern`].
    pub fn triplet_values(&self, out: &mut [f64]) -> Result<()> {
        check_len(self.num_triplets(), out.len())?;
        let mut k = 0;
        self.for_each_entry(|_, _, v| {
            out[k] = v;
            k += 1;
        });
        Ok(())
    }

    /// `(rows, cols, values)` of the symmetric matrix (both triangles).
    pub fn to_triplets(&self) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let (r, c) = self.triplet_pattern();
        let mut v = vec![0.0; r.len()];
        // Lengths match by construction.
        let _ = self.triplet_values(&mut v);
        (r, c, v)
    }

    /// The matrix as a faer CSC matrix (both triangles stored).
    pub fn to_matrix(&self) -> Result<SparseColMat<usize, f64>> {
        self.validate()?;
        let (r, c, v) = self.to_triplets();
        let n = self.num_cells();
        SparsityPattern::new(n, n, &r, &c)?.build(&v)
    }

    fn for_each_entry(&self, mut emit: impl FnMut(usize, usize, f64)) {
        let [nx, ny, nz] = self.dims;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let c = [i, j, k];
                    let p = self.cell_index(c);
                    let mut off = [(usize::MAX, 0.0f64); 6];
                    let mut diag = self.diag_extra[p];
                    for a in 0..self.ndim {
                        let lo_f = self.face_index(a, c);
                        let mut hc = c;
                        hc[a] += 1;
                        let hi_f = self.face_index(a, hc);
                        let (clo, chi) = (self.face[a][lo_f], self.face[a][hi_f]);
                        let wraps = self.wraps(a);
                        if c[a] == 0 && wraps {
                            let mut nb = c;
                            nb[a] = self.dims[a] - 1;
                            diag += clo;
                            off[2 - a] = (self.cell_index(nb), -clo);
                        } else if c[a] == 0 {
                            diag += self.boundary_coeff(a, 0, c);
                        } else {
                            let mut nb = c;
                            nb[a] -= 1;
                            diag += clo;
                            off[2 - a] = (self.cell_index(nb), -clo);
                        }
                        if c[a] + 1 == self.dims[a] && wraps {
                            let mut f0 = c;
                            f0[a] = 0;
                            let cw = self.face[a][self.face_index(a, f0)];
                            diag += cw;
                            off[3 + a] = (self.cell_index(f0), -cw);
                        } else if c[a] + 1 == self.dims[a] {
                            diag += self.boundary_coeff(a, 1, c);
                        } else {
                            diag += chi;
                            off[3 + a] = (self.cell_index(hc), -chi);
                        }
                    }
                    emit(p, p, diag);
                    for &(q, v) in &off {
                        if q != usize::MAX {
                            emit(p, q, v);
                        }
                    }
                }
            }
        }
    }

    /// Diagonal of the operator.
    pub fn diagonal(&self) -> Vec<f64> {
        let mut d = vec![0.0; self.num_cells()];
        self.for_each_entry(|r, c, v| {
            if r == c {
                d[r] = v;
            }
        });
        d
    }

    /// `y = A x` (matrix-free), with dimension checks.
    pub fn apply_checked(&self, x: &[f64], y: &mut [f64]) -> Result<()> {
        check_len(self.num_cells(), x.len())?;
        check_len(self.num_cells(), y.len())?;
        self.apply_impl(x, y);
        Ok(())
    }

    /// `y = A x`, one x-row at a time (rows in parallel when the grid is
    /// large and the pool has more than one thread; the result is the same
    /// to the bit either way, see [`CellStencil::apply_row`]).
    fn apply_impl(&self, x: &[f64], y: &mut [f64]) {
        use rayon::prelude::*;
        let [nx, ny, _] = self.dims;
        let row = |(r, yr): (usize, &mut [f64])| self.apply_row(x, yr, r % ny, r / ny);
        if y.len() >= PAR_MIN_CELLS && rayon::current_num_threads() > 1 {
            y.par_chunks_mut(nx)
                .enumerate()
                .with_min_len(PAR_MIN_CELLS / 8 / nx.max(1) + 1)
                .for_each(row);
        } else {
            y.chunks_mut(nx).enumerate().for_each(row);
        }
    }

    /// `y = A x` on x-row `(j, k)` (`yr`: its `nx` entries), gathered: each
    /// cell starts from `diag_extra x` and adds the flux `c (x_low − x_high)`
    /// of each of its faces (minus on its high side of the face), axis by
    /// axis, the low face before the high one, and the boundary or periodic
    /// face after the interior ones.
    fn apply_row(&self, x: &[f64], yr: &mut [f64], j: usize, k: usize) {
        let [nx, ny, nz] = self.dims;
        let b = nx * (j + ny * k);
        let xr = &x[b..b + nx];
        for ((yi, xi), d) in yr.iter_mut().zip(xr).zip(&self.diag_extra[b..b + nx]) {
            *yi = d * xi;
        }
        // Axis 0: the faces inside the row, then its two ends.
        let fb = (nx + 1) * (j + ny * k);
        let cr = &self.face[0][fb..fb + nx + 1];
        for i in 0..nx {
            let mut v = yr[i];
            if i >= 1 {
                v -= cr[i] * (xr[i - 1] - xr[i]);
            }
            if i + 1 < nx {
                v += cr[i + 1] * (xr[i] - xr[i + 1]);
            }
            yr[i] = v;
        }
        if self.wraps(0) {
            let flux = cr[0] * (xr[nx - 1] - xr[0]);
            yr[nx - 1] += flux;
            yr[0] -= flux;
        } else {
            yr[0] += self.boundary_coeff(0, 0, [0, j, k]) * xr[0];
            yr[nx - 1] += self.boundary_coeff(0, 1, [nx - 1, j, k]) * xr[nx - 1];
        }
        // Axis 1: the faces below and above the row, then the boundary.
        let fy = &self.face[1];
        let (plane, fplane) = (nx * ny * k, nx * (ny + 1) * k);
        if j >= 1 {
            let c = &fy[fplane + nx * j..fplane + nx * (j + 1)];
            let xlo = &x[plane + nx * (j - 1)..plane + nx * j];
            for i in 0..nx {
                yr[i] -= c[i] * (xlo[i] - xr[i]);
            }
        }
        if j + 1 < ny {
            let c = &fy[fplane + nx * (j + 1)..fplane + nx * (j + 2)];
            let xhi = &x[plane + nx * (j + 1)..plane + nx * (j + 2)];
            for i in 0..nx {
                yr[i] += c[i] * (xr[i] - xhi[i]);
            }
        }
        let wraps = self.wraps(1);
        if j == 0 {
            let last = plane + nx * (ny - 1);
            for i in 0..nx {
                if wraps {
                    yr[i] -= fy[fplane + i] * (x[last + i] - xr[i]);
                } else {
                    yr[i] += self.boundary_coeff(1, 0, [i, 0, k]) * xr[i];
                }
            }
        }
        if j + 1 == ny {
            for i in 0..nx {
                if wraps {
                    yr[i] += fy[fplane + i] * (xr[i] - x[plane + i]);
                } else {
                    yr[i] += self.boundary_coeff(1, 1, [i, ny - 1, k]) * xr[i];
                }
            }
        }
        // Axis 2.
        if self.ndim == 3 {
            let fz = &self.face[2];
            let pl = nx * ny;
            let t0 = nx * j;
            if k >= 1 {
                let c = &fz[pl * k + t0..pl * k + t0 + nx];
                let xlo = &x[pl * (k - 1) + t0..pl * (k - 1) + t0 + nx];
                for i in 0..nx {
                    yr[i] -= c[i] * (xlo[i] - xr[i]);
                }
            }
            if k + 1 < nz {
                let c = &fz[pl * (k + 1) + t0..pl * (k + 1) + t0 + nx];
                let xhi = &x[pl * (k + 1) + t0..pl * (k + 1) + t0 + nx];
                for i in 0..nx {
                    yr[i] += c[i] * (xr[i] - xhi[i]);
                }
            }
            let wraps = self.wraps(2);
            if k == 0 {
                let last = pl * (nz - 1) + t0;
                for i in 0..nx {
                    if wraps {
                        yr[i] -= fz[t0 + i] * (x[last + i] - xr[i]);
                    } else {
                        yr[i] += self.boundary_coeff(2, 0, [i, j, 0]) * xr[i];
                    }
                }
            }
            if k + 1 == nz {
                for i in 0..nx {
                    if wraps {
                        yr[i] += fz[t0 + i] * (xr[i] - x[t0 + i]);
                    } else {
                        yr[i] += self.boundary_coeff(2, 1, [i, j, nz - 1]) * xr[i];
                    }
                }
            }
        }
    }
}

/// Cells below which [`CellStencil::apply`] runs on one thread.
const PAR_MIN_CELLS: usize = 32 * 1024;

impl LinearOperator for CellStencil {
    fn dim(&self) -> usize {
        self.num_cells()
    }
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.apply_impl(x, y)
    }
}
