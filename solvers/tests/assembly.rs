//! Triplet assembly with a reusable pattern.

mod common;

use approx::assert_relative_eq;
use solvers::{Assembler, SolverError, SparsityPattern};

fn dense(a: &solvers::SparseColMat<usize, f64>) -> Vec<Vec<f64>> {
    let mut d = vec![vec![0.0; a.ncols()]; a.nrows()];
    for (i, j, v) in a.triplet_iter().map(|t| (t.row, t.col, *t.val)) {
        d[i][j] += v;
    }
    d
}

/// Reassembling new values in place gives exactly the matrix a fresh build
/// gives, duplicates are summed, and the value buffer is not reallocated.
#[test]
fn reassembly_matches_fresh_build() {
    let rows = [0, 1, 2, 0, 2, 1, 0, 2, 2];
    let cols = [0, 1, 2, 2, 0, 1, 0, 2, 1];
    let v1 = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];
    let v2 = [-1.0, 0.5, 2.5, 1.0, -3.0, 0.25, 10.0, -8.0, 4.0];
    let mut asm = Assembler::from_triplets(3, 3, &rows, &cols, &v1).unwrap();
    let d1 = dense(asm.matrix());
    assert_relative_eq!(d1[0][0], 8.0); // 1 + 7 summed
    assert_relative_eq!(d1[1][1], 8.0); // 2 + 6
    assert_relative_eq!(d1[2][2], 11.0); // 3 + 8
    assert_eq!(asm.matrix().compute_nnz(), 6);
    let ptr = asm.matrix().val().as_ptr();
    asm.assemble(&v2).unwrap();
    assert_eq!(ptr, asm.matrix().val().as_ptr(), "values reallocated");
    let fresh = SparsityPattern::new(3, 3, &rows, &cols)
        .unwrap()
        .build(&v2)
        .unwrap();
    assert_eq!(dense(asm.matrix()), dense(&fresh));
    // Structure is sorted CSC.
    let sym = asm.matrix().symbolic();
    for j in 0..3 {
        let r = &sym.row_idx()[sym.col_range(j)];
        assert!(r.windows(2).all(|w| w[0] < w[1]));
    }
}

/// Wrong lengths and out-of-range indices are errors, not panics.
#[test]
fn assembly_errors() {
    assert!(matches!(
        SparsityPattern::new(2, 2, &[0, 1], &[0]),
        Err(SolverError::Dimension { .. })
    ));
    assert!(matches!(
        SparsityPattern::new(2, 2, &[0, 2], &[0, 1]),
        Err(SolverError::InvalidInput { .. })
    ));
    let mut asm = Assembler::new(2, 2, &[0, 1], &[0, 1]).unwrap();
    assert!(matches!(
        asm.assemble(&[1.0]),
        Err(SolverError::Dimension {
            expected: 2,
            got: 1
        })
    ));
}

/// The stencil's triplet pattern is value independent, so an assembler
/// built from it can be refreshed in place with new coefficients.
#[test]
fn stencil_triplets_reassemble() {
    let dims = [7, 5, 1];
    let s1 = common::from_field(
        dims,
        &common::inclusion_field(dims, 10.0),
        solvers::BoundaryKind::Dirichlet,
        0.0,
    );
    let s2 = common::from_field(
        dims,
        &common::checkerboard_field(dims, 2, 100.0),
        solvers::BoundaryKind::Neumann,
        1.0,
    );
    let (r, c) = s1.triplet_pattern();
    let mut v = vec![0.0; s1.num_triplets()];
    s1.triplet_values(&mut v).unwrap();
    let n = s1.num_cells();
    let mut asm = Assembler::from_triplets(n, n, &r, &c, &v).unwrap();
    assert_eq!(dense(asm.matrix()), dense(&s1.to_matrix().unwrap()));
    s2.triplet_values(&mut v).unwrap();
    asm.assemble(&v).unwrap();
    assert_eq!(dense(asm.matrix()), dense(&s2.to_matrix().unwrap()));
}
