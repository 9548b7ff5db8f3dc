//! Linear operator and preconditioner traits, and a compressed-row matrix
//! with a fast sparse matrix-vector product.

use faer::sparse::SparseColMat;

use crate::error::{check_len, Result, SolverError};

/// A square linear operator `y = A x`, possibly matrix-free.
///
/// The solvers of this crate check all lengths before calling
/// [`LinearOperator::apply`]; implementations may assume
/// `x.len() == y.len() == self.dim()` (and may panic otherwise).
pub trait LinearOperator {
    /// Dimension `n` of the (square) operator.
    fn dim(&self) -> usize;
    /// Computes `y = A x` (`y` is overwritten). Both slices have length
    /// [`LinearOperator::dim`].
    fn apply(&self, x: &[f64], y: &mut [f64]);
}

/// A preconditioner `z = M^{-1} r`. For [`crate::pcg`] it must be symmetric
/// positive definite. As for [`LinearOperator`], lengths are checked by the
/// solvers before [`Preconditioner::apply`] is called.
pub trait Preconditioner {
    /// Computes `z = M^{-1} r` (`z` is overwritten).
    fn apply(&self, r: &[f64], z: &mut [f64]);
}

impl<T: LinearOperator + ?Sized> LinearOperator for &T {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        (**self).apply(x, y)
    }
}

impl<T: Preconditioner + ?Sized> Preconditioner for &T {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        (**self).apply(r, z)
    }
}

/// Column-oriented product for faer's CSC matrices (scatter form). Prefer
/// [`CsrMatrix`] for repeated products: it is gather-based and faster.
impl LinearOperator for SparseColMat<usize, f64> {
    fn dim(&self) -> usize {
        self.nrows()
    }
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        let (sym, val) = self.parts();
        let row_idx = sym.row_idx();
        for (j, &xj) in x.iter().enumerate().take(sym.ncols()) {
            for k in sym.col_range(j) {
                y[row_idx[k]] += val[k] * xj;
            }
        }
    }
}

/// Compressed sparse row matrix with `f64` values; implements a fast
/// gather-based [`LinearOperator`].
#[derive(Debug, Clone)]
pub struct CsrMatrix {
    nrows: usize,
    ncols: usize,
    row_ptr: Vec<usize>,
    col_idx: Vec<usize>,
    vals: Vec<f64>,
    /// `src[k]` = index in the CSC value array the CSR entry `k` came from.
    src: Vec<usize>,
}

impl CsrMatrix {
    /// Converts a faer CSC matrix (column indices sorted within each row).
    pub fn from_csc(a: &SparseColMat<usize, f64>) -> Self {
        let (sym, val) = a.parts();
        let (nrows, ncols) = (sym.nrows(), sym.ncols());
        let row_idx = sym.row_idx();
        let mut row_ptr = vec![0usize; nrows + 1];
        for j in 0..ncols {
            for k in sym.col_range(j) {
                row_ptr[row_idx[k] + 1] += 1;
            }
        }
        for i in 0..nrows {
            row_ptr[i + 1] += row_ptr[i];
        }
        let nnz = row_ptr[nrows];
        let mut next = row_ptr.clone();
        let mut col_idx = vec![0usize; nnz];
        let mut vals = vec![0.0; nnz];
        let mut src = vec![0usize; nnz];
        for j in 0..ncols {
            for k in sym.col_range(j) {
                let i = row_idx[k];
                let p = next[i];
                next[i] += 1;
                col_idx[p] = j;
                vals[p] = val[k];
                src[p] = k;
            }
        }
        Self {
            nrows,
            ncols,
            row_ptr,
            col_idx,
            vals,
            src,
        }
    }

    /// Refreshes the values from a CSC matrix with the same pattern as the
    /// one this matrix was built from. No allocation.
    pub fn update_from_csc(&mut self, a: &SparseColMat<usize, f64>) -> Result<()> {
        check_len(self.nrows, a.nrows())?;
        check_len(self.ncols, a.ncols())?;
        let val = a.val();
        if a.symbolic().compute_nnz() != self.vals.len() {
            return Err(SolverError::invalid("sparsity pattern changed"));
        }
        for (v, &s) in self.vals.iter_mut().zip(&self.src) {
            *v = val[s];
        }
        Ok(())
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.vals.len()
    }

    /// Row pointers (length `nrows + 1`).
    pub fn row_ptr(&self) -> &[usize] {
        &self.row_ptr
    }

    /// Column indices.
    pub fn col_idx(&self) -> &[usize] {
        &self.col_idx
    }

    /// Values.
    pub fn values(&self) -> &[f64] {
        &self.vals
    }

    /// Main diagonal (0 where no entry is stored; duplicates summed).
    pub fn diagonal(&self) -> Vec<f64> {
        let n = self.nrows.min(self.ncols);
        let mut d = vec![0.0; n];
        for (i, di) in d.iter_mut().enumerate() {
            for k in self.row_ptr[i]..self.row_ptr[i + 1] {
                if self.col_idx[k] == i {
                    *di += self.vals[k];
                }
            }
        }
        d
    }

    /// `y = A x` for a rectangular matrix (lengths `ncols` and `nrows`).
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) -> Result<()> {
        check_len(self.ncols, x.len())?;
        check_len(self.nrows, y.len())?;
        self.spmv(x, y);
        Ok(())
    }

    #[inline]
    fn spmv(&self, x: &[f64], y: &mut [f64]) {
        let rp = &self.row_ptr;
        for (i, yi) in y.iter_mut().enumerate().take(self.nrows) {
            let (a, b) = (rp[i], rp[i + 1]);
            let cols = &self.col_idx[a..b];
            let vals = &self.vals[a..b];
            let mut s = 0.0;
            for (&c, &v) in cols.iter().zip(vals) {
                s += v * x[c];
            }
            *yi = s;
        }
    }
}

impl LinearOperator for CsrMatrix {
    fn dim(&self) -> usize {
        self.nrows
    }
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        self.spmv(x, y)
    }
}
