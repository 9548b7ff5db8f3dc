//! Algebraic preconditioners: identity, Jacobi and incomplete Cholesky IC(0).

use faer::sparse::SparseColMat;

use crate::error::{check_len, is_pos, Result, SolverError};
use crate::operator::Preconditioner;

/// The identity preconditioner `z = r`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Identity;

impl Preconditioner for Identity {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
    }
}

/// Diagonal (Jacobi) preconditioner `z_i = r_i / a_ii`.
#[derive(Debug, Clone)]
pub struct Jacobi {
    inv_diag: Vec<f64>,
}

impl Jacobi {
    /// Builds from the diagonal of a square sparse matrix (duplicates
    /// summed). A zero or non-finite diagonal entry gives
    /// [`SolverError::Singular`].
    pub fn new(a: &SparseColMat<usize, f64>) -> Result<Self> {
        check_len(a.nrows(), a.ncols())?;
        let (sym, val) = a.parts();
        let mut d = vec![0.0; a.nrows()];
        for (j, dj) in d.iter_mut().enumerate() {
            for k in sym.col_range(j) {
                if sym.row_idx()[k] == j {
                    *dj += val[k];
                }
            }
        }
        Self::from_diagonal(&d)
    }

    /// Builds from an explicit diagonal.
    pub fn from_diagonal(diag: &[f64]) -> Result<Self> {
        let mut inv_diag = Vec::with_capacity(diag.len());
        for (i, &d) in diag.iter().enumerate() {
            if d == 0.0 || !d.is_finite() {
                return Err(SolverError::Singular {
                    detail: format!("Jacobi: diagonal entry {i} is {d}"),
                });
            }
            inv_diag.push(1.0 / d);
        }
        Ok(Self { inv_diag })
    }

    /// Inverse diagonal.
    pub fn inv_diag(&self) -> &[f64] {
        &self.inv_diag
    }
}

impl Preconditioner for Jacobi {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        for ((zi, ri), di) in z.iter_mut().zip(r).zip(&self.inv_diag) {
            *zi = ri * di;
        }
    }
}

/// Zero fill-in incomplete Cholesky `A ≈ L L^T` computed on the pattern of
/// the lower triangle of `A` (upper entries are ignored).
///
/// If a pivot becomes non-positive (possible for SPD matrices that are not
/// M-matrices) the factorisation is retried on `A + α diag(A)` with
/// `α = 1e-3, 1e-2, …, 1` (Manteuffel shift); [`IncompleteCholesky::shift`]
/// reports the shift used.
#[derive(Debug, Clone)]
pub struct IncompleteCholesky {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Strictly lower entries of `L` (diagonal stored separately).
    vals: Vec<f64>,
    inv_diag: Vec<f64>,
    shift: f64,
}

impl IncompleteCholesky {
    /// Computes IC(0) of the symmetric matrix whose lower triangle is stored
    /// in `a`. Every diagonal entry must be present and positive.
    pub fn new(a: &SparseColMat<usize, f64>) -> Result<Self> {
        check_len(a.nrows(), a.ncols())?;
        let n = a.nrows();
        let (sym, val) = a.parts();
        // Extract strictly lower part (sorted rows) and the diagonal.
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        let mut lower = Vec::new();
        let mut diag = vec![0.0; n];
        let mut has_diag = vec![false; n];
        col_ptr.push(0);
        let mut tmp: Vec<(usize, f64)> = Vec::new();
        for (j, dj) in diag.iter_mut().enumerate() {
            tmp.clear();
            for k in sym.col_range(j) {
                let i = sym.row_idx()[k];
                if i == j {
                    *dj += val[k];
                    has_diag[j] = true;
                } else if i > j {
                    tmp.push((i, val[k]));
                }
            }
            tmp.sort_unstable_by_key(|e| e.0);
            for &(i, v) in &tmp {
                if row_idx.len() > col_ptr[j] && *row_idx.last().unwrap_or(&usize::MAX) == i {
                    *lower.last_mut().expect("nonempty") += v;
                } else {
                    row_idx.push(i);
                    lower.push(v);
                }
            }
            col_ptr.push(row_idx.len());
        }
        for j in 0..n {
            if !has_diag[j] || !is_pos(diag[j]) {
                return Err(SolverError::Singular {
                    detail: format!("IC(0): diagonal entry {j} is missing or not positive"),
                });
            }
        }
        let mut ic = Self {
            n,
            col_ptr,
            row_idx,
            vals: vec![0.0; lower.len()],
            inv_diag: vec![0.0; n],
            shift: 0.0,
        };
        let mut marker = vec![usize::MAX; n];
        let mut d = vec![0.0; n];
        let shifts = [0.0, 1e-3, 1e-2, 1e-1, 1.0];
        for &alpha in &shifts {
            ic.vals.copy_from_slice(&lower);
            for j in 0..n {
                d[j] = diag[j] * (1.0 + alpha);
            }
            if ic.factor(&mut d, &diag, &mut marker) {
                ic.shift = alpha;
                return Ok(ic);
            }
        }
        Err(SolverError::Singular {
            detail: "IC(0): breakdown even with diagonal shift 1.0".into(),
        })
    }

    /// Right-looking IC(0); returns false on a non-positive pivot.
    fn factor(&mut self, d: &mut [f64], diag: &[f64], marker: &mut [usize]) -> bool {
        let (cp, ri) = (&self.col_ptr, &self.row_idx);
        let vals = &mut self.vals;
        for k in 0..self.n {
            let dk = d[k];
            if !is_pos(dk - 1e-14 * diag[k]) || !dk.is_finite() {
                return false;
            }
            let lkk = dk.sqrt();
            let inv = 1.0 / lkk;
            self.inv_diag[k] = inv;
            let (s, e) = (cp[k], cp[k + 1]);
            for v in &mut vals[s..e] {
                *v *= inv;
            }
            for q in s..e {
                let j = ri[q];
                let ljk = vals[q];
                d[j] -= ljk * ljk;
                if q + 1 == e {
                    continue;
                }
                for t in cp[j]..cp[j + 1] {
                    marker[ri[t]] = t;
                }
                for p in q + 1..e {
                    let t = marker[ri[p]];
                    if t != usize::MAX {
                        vals[t] -= vals[p] * ljk;
                    }
                }
                for t in cp[j]..cp[j + 1] {
                    marker[ri[t]] = usize::MAX;
                }
            }
        }
        true
    }

    /// Relative diagonal shift `α` that was needed (0 if none).
    pub fn shift(&self) -> f64 {
        self.shift
    }
}

impl Preconditioner for IncompleteCholesky {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        z.copy_from_slice(r);
        let (cp, ri, v) = (&self.col_ptr, &self.row_idx, &self.vals);
        // Forward: L y = r.
        for j in 0..self.n {
            let yj = z[j] * self.inv_diag[j];
            z[j] = yj;
            for k in cp[j]..cp[j + 1] {
                z[ri[k]] -= v[k] * yj;
            }
        }
        // Backward: L^T z = y.
        for j in (0..self.n).rev() {
            let mut s = z[j];
            for k in cp[j]..cp[j + 1] {
                s -= v[k] * z[ri[k]];
            }
            z[j] = s * self.inv_diag[j];
        }
    }
}
