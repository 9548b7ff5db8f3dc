//! Sparse direct solvers: Cholesky ($LL^\top$) for SPD systems and LU with
//! partial pivoting for general square systems, both built on faer's
//! low-level sparse API with a reusable symbolic analysis and preallocated
//! scratch memory.

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::linalg::LuError;
use faer::sparse::SparseColMat;
use faer::{Conj, MatMut, Par, Side};

use crate::error::{check_len, Result, SolveReport, SolverError};

fn alloc_err<E: std::fmt::Debug>(e: E) -> SolverError {
    SolverError::Factorisation(format!("allocation failed: {e:?}"))
}

fn mem(req: StackReq) -> Result<MemBuffer> {
    MemBuffer::try_new(req).map_err(alloc_err)
}

fn norm2(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// Owned copy of a CSC matrix (pattern + values) used for pattern checks and
/// residual computation.
#[derive(Debug, Clone)]
struct CscCopy {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    vals: Vec<f64>,
}

impl CscCopy {
    fn new(a: &SparseColMat<usize, f64>) -> Self {
        let (sym, val) = a.parts();
        let n = sym.ncols();
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(val.len());
        let mut vals = Vec::with_capacity(val.len());
        col_ptr.push(0);
        for j in 0..n {
            for k in sym.col_range(j) {
                row_idx.push(sym.row_idx()[k]);
                vals.push(val[k]);
            }
            col_ptr.push(row_idx.len());
        }
        Self {
            n,
            col_ptr,
            row_idx,
            vals,
        }
    }

    /// Overwrites the values; errors if the pattern differs.
    fn update(&mut self, a: &SparseColMat<usize, f64>) -> Result<()> {
        check_len(self.n, a.ncols())?;
        check_len(self.n, a.nrows())?;
        let (sym, val) = a.parts();
        let mut p = 0usize;
        for j in 0..self.n {
            let r = sym.col_range(j);
            if r.len() != self.col_ptr[j + 1] - self.col_ptr[j] {
                return Err(SolverError::invalid(format!(
                    "sparsity pattern changed in column {j}"
                )));
            }
            for k in r {
                if sym.row_idx()[k] != self.row_idx[p] {
                    return Err(SolverError::invalid(format!(
                        "sparsity pattern changed in column {j}"
                    )));
                }
                self.vals[p] = val[k];
                p += 1;
            }
        }
        Ok(())
    }

    /// `y = A x` using all stored entries.
    fn mul_full(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for (j, &xj) in x.iter().enumerate().take(self.n) {
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                y[self.row_idx[k]] += self.vals[k] * xj;
            }
        }
    }

    /// `y = A x` where `A` is the symmetric matrix defined by the stored
    /// lower triangle (upper entries ignored).
    fn mul_sym_lower(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for j in 0..self.n {
            let xj = x[j];
            let mut acc = 0.0;
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[k];
                let v = self.vals[k];
                if i > j {
                    y[i] += v * xj;
                    acc += v * x[i];
                } else if i == j {
                    acc += v * xj;
                }
            }
            y[j] += acc;
        }
    }

    fn diagonal(&self) -> Vec<f64> {
        let mut d = vec![0.0; self.n];
        self.diagonal_into(&mut d);
        d
    }

    /// The diagonal into `d` (length `n`), without allocation.
    fn diagonal_into(&self, d: &mut [f64]) {
        for (j, dj) in d.iter_mut().enumerate() {
            *dj = 0.0;
            for k in self.col_ptr[j]..self.col_ptr[j + 1] {
                if self.row_idx[k] == j {
                    *dj += self.vals[k];
                }
            }
        }
    }
}

/// Sparse Cholesky factorisation `P A P^T = L L^T` of a symmetric positive
/// definite matrix (AMD ordering, simplicial or supernodal as chosen by faer).
///
/// Only the **lower triangle** of the matrix is read (the upper part may be
/// present or absent). The symbolic analysis is done once in
/// [`Cholesky::new`]; [`Cholesky::refactor`] recomputes the numeric factor
/// for new values with the same pattern, reusing all memory. Everything runs
/// on one thread.
pub struct Cholesky {
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    factor_mem: MemBuffer,
    solve_mem: MemBuffer,
    a: CscCopy,
    a_diag: Vec<f64>,
    rhs_copy: Vec<f64>,
    work: Vec<f64>,
    pivot_tol: f64,
    setup_s: f64,
    symbolic_s: f64,
}

impl Cholesky {
    /// Default relative pivot tolerance: the factorisation is declared
    /// singular if `min_j L_jj^2 / A_jj < n * eps * 16` (after permutation).
    pub fn default_pivot_tol(n: usize) -> f64 {
        16.0 * (n.max(1) as f64) * f64::EPSILON
    }

    /// Symbolic analysis and numeric factorisation of `a`.
    pub fn new(a: &SparseColMat<usize, f64>) -> Result<Self> {
        Self::with_pivot_tol(a, Self::default_pivot_tol(a.nrows()))
    }

    /// As [`Cholesky::new`] with an explicit relative pivot tolerance (see
    /// [`Cholesky::default_pivot_tol`]; 0 disables the check so that only
    /// non-positive pivots are reported).
    pub fn with_pivot_tol(a: &SparseColMat<usize, f64>, pivot_tol: f64) -> Result<Self> {
        let t0 = Instant::now();
        check_len(a.nrows(), a.ncols())?;
        let n = a.nrows();
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| SolverError::Factorisation(format!("symbolic Cholesky: {e:?}")))?;
        let factor_req =
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
        let solve_req = symbolic.solve_in_place_scratch::<f64>(1, Par::Seq);
        let mut l_values = Vec::new();
        l_values
            .try_reserve_exact(symbolic.len_val())
            .map_err(alloc_err)?;
        l_values.resize(symbolic.len_val(), 0.0);
        let a_copy = CscCopy::new(a);
        let symbolic_s = t0.elapsed().as_secs_f64();
        let mut chol = Self {
            factor_mem: mem(factor_req)?,
            solve_mem: mem(solve_req)?,
            symbolic,
            l_values,
            a_diag: a_copy.diagonal(),
            a: a_copy,
            rhs_copy: vec![0.0; n],
            work: vec![0.0; n],
            pivot_tol,
            setup_s: 0.0,
            symbolic_s,
        };
        chol.factor_numeric()?;
        chol.setup_s = t0.elapsed().as_secs_f64();
        Ok(chol)
    }

    /// Numeric refactorisation for new values with the **same** sparsity
    /// pattern (checked). No reallocation.
    pub fn refactor(&mut self, a: &SparseColMat<usize, f64>) -> Result<()> {
        let t0 = Instant::now();
        self.a.update(a)?;
        self.a.diagonal_into(&mut self.a_diag);
        self.factor_numeric()?;
        self.setup_s = t0.elapsed().as_secs_f64();
        Ok(())
    }

    fn factor_numeric(&mut self) -> Result<()> {
        let n = self.a.n;
        // SAFETY of pattern: self.a was built from / checked against the
        // matrix used for the symbolic analysis.
        let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(
            n,
            n,
            &self.a.col_ptr,
            None,
            &self.a.row_idx,
        );
        let a_ref = faer::sparse::SparseColMatRef::new(sym, &self.a.vals);
        let stack = MemStack::new(&mut self.factor_mem);
        let res = self.symbolic.factorize_numeric_llt::<f64>(
            &mut self.l_values,
            a_ref,
            Side::Lower,
            LltRegularization::default(),
            Par::Seq,
            stack,
            Default::default(),
        );
        if let Err(e) = res {
            return Err(SolverError::Singular {
                detail: format!("Cholesky: {e:?} (matrix not positive definite)"),
            });
        }
        let (ratio, idx) = self.min_pivot_ratio();
        if ratio.is_nan() || ratio < self.pivot_tol {
            return Err(SolverError::Singular {
                detail: format!(
                    "Cholesky: relative pivot {ratio:e} at elimination step {idx} below tolerance {:e} (numerically singular)",
                    self.pivot_tol
                ),
            });
        }
        Ok(())
    }

    /// Smallest `L_jj^2 / A_jj` over the (permuted) diagonal and its index.
    fn min_pivot_ratio(&self) -> (f64, usize) {
        let n = self.a.n;
        let perm_fwd: Option<&[usize]> = self.symbolic.perm().map(|p| p.arrays().0);
        let orig = |j: usize| perm_fwd.map_or(j, |p| p[j]);
        let mut best = (f64::INFINITY, 0usize);
        let mut consider = |j: usize, l: f64| {
            let a = self.a_diag[orig(j)];
            let r = if a > 0.0 {
                l * l / a
            } else {
                f64::NEG_INFINITY
            };
            if r.is_nan() || r < best.0 {
                best = (r, j);
            }
        };
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let cp = s.col_ptr();
                for (j, &c) in cp.iter().enumerate().take(n) {
                    consider(j, self.l_values[c]);
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let begin = s.supernode_begin();
                let vptr = s.col_ptr_for_val();
                for sn in 0..s.n_supernodes() {
                    let start = begin[sn];
                    let ncols = s.supernode_end()[sn] - start;
                    let len = vptr[sn + 1] - vptr[sn];
                    let nrows = len / ncols.max(1);
                    let block = &self.l_values[vptr[sn]..vptr[sn + 1]];
                    for c in 0..ncols {
                        consider(start + c, block[c * nrows + c]);
                    }
                }
            }
        }
        best
    }

    /// Dimension of the system.
    pub fn dim(&self) -> usize {
        self.a.n
    }

    /// Number of stored values of the factor `L`.
    pub fn factor_nnz(&self) -> usize {
        self.l_values.len()
    }

    /// Seconds spent in the last `new` (symbolic + numeric) or `refactor`.
    pub fn setup_s(&self) -> f64 {
        self.setup_s
    }

    /// Seconds of the symbolic analysis in `new`.
    pub fn symbolic_s(&self) -> f64 {
        self.symbolic_s
    }

    /// Solves `A x = b` in place (`rhs` holds `b` on entry and `x` on exit).
    /// The report contains the true relative residual (one extra product
    /// with the stored matrix). No allocation.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) -> Result<SolveReport> {
        let t0 = Instant::now();
        let n = self.a.n;
        check_len(n, rhs.len())?;
        self.rhs_copy.copy_from_slice(rhs);
        let stack = MemStack::new(&mut self.solve_mem);
        LltRef::<'_, usize, f64>::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            stack,
        );
        if rhs.iter().any(|v| !v.is_finite()) {
            return Err(SolverError::Singular {
                detail: "Cholesky solve produced non-finite values".into(),
            });
        }
        self.a.mul_sym_lower(rhs, &mut self.work);
        let rel_residual = rel_res(&self.rhs_copy, &self.work);
        Ok(SolveReport {
            iterations: 0,
            rel_residual,
            setup_s: self.setup_s,
            solve_s: t0.elapsed().as_secs_f64(),
        })
    }
}

fn rel_res(b: &[f64], ax: &[f64]) -> f64 {
    let nb = norm2(b);
    let r = b
        .iter()
        .zip(ax)
        .map(|(b, a)| (b - a) * (b - a))
        .sum::<f64>()
        .sqrt();
    if nb > 0.0 {
        r / nb
    } else {
        r
    }
}

/// Sparse LU factorisation with partial pivoting (COLAMD column ordering)
/// for general square systems. Symbolic analysis once, numeric
/// refactorisation with the same pattern, in-place solves. One thread.
pub struct Lu {
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    factor_mem: MemBuffer,
    solve_mem: MemBuffer,
    a: CscCopy,
    rhs_copy: Vec<f64>,
    work: Vec<f64>,
    setup_s: f64,
}

impl Lu {
    /// Symbolic analysis and numeric factorisation of `a`.
    pub fn new(a: &SparseColMat<usize, f64>) -> Result<Self> {
        let t0 = Instant::now();
        check_len(a.nrows(), a.ncols())?;
        let n = a.nrows();
        let symbolic = factorize_symbolic_lu(a.symbolic(), Default::default())
            .map_err(|e| SolverError::Factorisation(format!("symbolic LU: {e:?}")))?;
        let factor_req = symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default());
        let solve_req = symbolic.solve_in_place_scratch::<f64>(1, Par::Seq);
        let mut lu = Self {
            symbolic,
            numeric: NumericLu::new(),
            factor_mem: mem(factor_req)?,
            solve_mem: mem(solve_req)?,
            a: CscCopy::new(a),
            rhs_copy: vec![0.0; n],
            work: vec![0.0; n],
            setup_s: 0.0,
        };
        lu.factor_numeric()?;
        lu.setup_s = t0.elapsed().as_secs_f64();
        Ok(lu)
    }

    /// Numeric refactorisation for new values with the same pattern.
    pub fn refactor(&mut self, a: &SparseColMat<usize, f64>) -> Result<()> {
        let t0 = Instant::now();
        self.a.update(a)?;
        self.factor_numeric()?;
        self.setup_s = t0.elapsed().as_secs_f64();
        Ok(())
    }

    fn factor_numeric(&mut self) -> Result<()> {
        let n = self.a.n;
        let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(
            n,
            n,
            &self.a.col_ptr,
            None,
            &self.a.row_idx,
        );
        let a_ref = faer::sparse::SparseColMatRef::new(sym, &self.a.vals);
        let stack = MemStack::new(&mut self.factor_mem);
        match self.symbolic.factorize_numeric_lu::<f64>(
            &mut self.numeric,
            a_ref,
            Par::Seq,
            stack,
            Default::default(),
        ) {
            Ok(_) => {}
            Err(LuError::SymbolicSingular { index }) => {
                return Err(SolverError::Singular {
                    detail: format!("LU: no pivot found at step {index}"),
                })
            }
            Err(LuError::Generic(e)) => {
                return Err(SolverError::Factorisation(format!("LU: {e:?}")))
            }
        }
        // Probe solve: exact zero pivots show up as non-finite values.
        let mut probe = std::mem::take(&mut self.work);
        probe.fill(1.0);
        self.raw_solve(&mut probe);
        let ok = probe.iter().all(|v| v.is_finite());
        self.work = probe;
        if !ok {
            return Err(SolverError::Singular {
                detail: "LU: zero pivot (probe solve not finite)".into(),
            });
        }
        Ok(())
    }

    fn raw_solve(&mut self, rhs: &mut [f64]) {
        let n = self.a.n;
        let stack = MemStack::new(&mut self.solve_mem);
        LuRef::<'_, usize, f64>::new_unchecked(&self.symbolic, &self.numeric)
            .solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(rhs, n, 1),
                Par::Seq,
                stack,
            );
    }

    /// Dimension of the system.
    pub fn dim(&self) -> usize {
        self.a.n
    }

    /// Seconds spent in the last `new` or `refactor`.
    pub fn setup_s(&self) -> f64 {
        self.setup_s
    }

    /// Solves `A x = b` in place; the report holds the true relative
    /// residual. No allocation.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) -> Result<SolveReport> {
        let t0 = Instant::now();
        check_len(self.a.n, rhs.len())?;
        self.rhs_copy.copy_from_slice(rhs);
        self.raw_solve(rhs);
        if rhs.iter().any(|v| !v.is_finite()) {
            return Err(SolverError::Singular {
                detail: "LU solve produced non-finite values".into(),
            });
        }
        self.a.mul_full(rhs, &mut self.work);
        let rel_residual = rel_res(&self.rhs_copy, &self.work);
        Ok(SolveReport {
            iterations: 0,
            rel_residual,
            setup_s: self.setup_s,
            solve_s: t0.elapsed().as_secs_f64(),
        })
    }
}

impl std::fmt::Debug for Cholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Cholesky")
            .field("dim", &self.a.n)
            .field("factor_nnz", &self.l_values.len())
            .field("pivot_tol", &self.pivot_tol)
            .field("setup_s", &self.setup_s)
            .finish_non_exhaustive()
    }
}

impl std::fmt::Debug for Lu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Lu")
            .field("dim", &self.a.n)
            .field("setup_s", &self.setup_s)
            .finish_non_exhaustive()
    }
}
