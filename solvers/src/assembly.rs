//! Triplet assembly with a reusable sparsity pattern.
//!
//! The pattern is analysed once from `(row, col)` lists; later assemblies only
//! take the values (in the same triplet order) and overwrite the matrix values
//! in place, summing duplicates, without any allocation.

use faer::sparse::{SparseColMat, SymbolicSparseColMat};

use crate::error::{check_len, Result, SolverError};

/// Compressed-column sparsity pattern built from a triplet list, together
/// with the map from each triplet to its slot in the compressed value array.
#[derive(Debug, Clone)]
pub struct SparsityPattern {
    nrows: usize,
    ncols: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// `slot[k]` = index in the compressed value array of triplet `k`.
    slot: Vec<usize>,
}

impl SparsityPattern {
    /// Analyses the triplet structure `(rows[k], cols[k])`. Duplicate entries
    /// are allowed and will be summed on assembly. Row indices within each
    /// column are sorted.
    pub fn new(nrows: usize, ncols: usize, rows: &[usize], cols: &[usize]) -> Result<Self> {
        check_len(rows.len(), cols.len())?;
        let nt = rows.len();
        for k in 0..nt {
            if rows[k] >= nrows || cols[k] >= ncols {
                return Err(SolverError::invalid(format!(
                    "triplet {k} = ({}, {}) outside a {nrows}x{ncols} matrix",
                    rows[k], cols[k]
                )));
            }
        }
        // Counting sort of the triplets by column.
        let mut count = vec![0usize; ncols + 1];
        for &c in cols {
            count[c + 1] += 1;
        }
        for j in 0..ncols {
            count[j + 1] += count[j];
        }
        let mut order = vec![0usize; nt];
        let mut next = count.clone();
        for (k, &c) in cols.iter().enumerate() {
            order[next[c]] = k;
            next[c] += 1;
        }
        // Within each column sort by row, then deduplicate.
        let mut col_ptr = Vec::with_capacity(ncols + 1);
        let mut row_idx = Vec::with_capacity(nt);
        let mut slot = vec![0usize; nt];
        col_ptr.push(0);
        for j in 0..ncols {
            let seg = &mut order[count[j]..count[j + 1]];
            seg.sort_unstable_by_key(|&k| (rows[k], k));
            let mut last = usize::MAX;
            for &k in seg.iter() {
                let r = rows[k];
                if r != last {
                    row_idx.push(r);
                    last = r;
                }
                slot[k] = row_idx.len() - 1;
            }
            col_ptr.push(row_idx.len());
        }
        row_idx.shrink_to_fit();
        Ok(Self {
            nrows,
            ncols,
            col_ptr,
            row_idx,
            slot,
        })
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.nrows
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Number of stored (deduplicated) entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Number of triplets the pattern was built from (length of the value
    /// vectors accepted by [`SparsityPattern::scatter`]).
    pub fn n_triplets(&self) -> usize {
        self.slot.len()
    }

    /// Column pointers of the compressed pattern (length `ncols + 1`).
    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    /// Row indices of the compressed pattern (sorted within each column).
    pub fn row_idx(&self) -> &[usize] {
        &self.row_idx
    }

    /// Slot in the compressed value array of each triplet.
    pub fn slots(&self) -> &[usize] {
        &self.slot
    }

    /// Sums the triplet `values` into the compressed value array `out`
    /// (overwritten). No allocation.
    pub fn scatter(&self, values: &[f64], out: &mut [f64]) -> Result<()> {
        check_len(self.slot.len(), values.len())?;
        check_len(self.row_idx.len(), out.len())?;
        out.fill(0.0);
        for (&s, &v) in self.slot.iter().zip(values) {
            out[s] += v;
        }
        Ok(())
    }

    /// Builds a fresh faer matrix with this pattern and the given triplet
    /// values.
    pub fn build(&self, values: &[f64]) -> Result<SparseColMat<usize, f64>> {
        let mut val = vec![0.0; self.row_idx.len()];
        self.scatter(values, &mut val)?;
        let symbolic = SymbolicSparseColMat::new_checked(
            self.nrows,
            self.ncols,
            self.col_ptr.clone(),
            None,
            self.row_idx.clone(),
        );
        Ok(SparseColMat::new(symbolic, val))
    }
}

/// A sparse matrix together with its [`SparsityPattern`], for repeated
/// in-place assembly from triplet values.
#[derive(Debug, Clone)]
pub struct Assembler {
    pattern: SparsityPattern,
    matrix: SparseColMat<usize, f64>,
}

impl Assembler {
    /// Analyses the triplet structure and allocates the matrix (values 0).
    pub fn new(nrows: usize, ncols: usize, rows: &[usize], cols: &[usize]) -> Result<Self> {
        let pattern = SparsityPattern::new(nrows, ncols, rows, cols)?;
        let matrix = pattern.build(&vec![0.0; pattern.n_triplets()])?;
        Ok(Self { pattern, matrix })
    }

    /// Analyses the structure and assembles the first set of values.
    pub fn from_triplets(
        nrows: usize,
        ncols: usize,
        rows: &[usize],
        cols: &[usize],
        values: &[f64],
    ) -> Result<Self> {
        let mut a = Self::new(nrows, ncols, rows, cols)?;
        a.assemble(values)?;
        Ok(a)
    }

    /// Overwrites the matrix values from triplet `values` given in the same
    /// order as the construction triplets (duplicates summed). No allocation.
    pub fn assemble(&mut self, values: &[f64]) -> Result<&SparseColMat<usize, f64>> {
        self.pattern.scatter(values, self.matrix.val_mut())?;
        Ok(&self.matrix)
    }

    /// The assembled matrix.
    pub fn matrix(&self) -> &SparseColMat<usize, f64> {
        &self.matrix
    }

    /// The sparsity pattern and triplet map.
    pub fn pattern(&self) -> &SparsityPattern {
        &self.pattern
    }

    /// Consumes the assembler and returns the matrix.
    pub fn into_matrix(self) -> SparseColMat<usize, f64> {
        self.matrix
    }
}
