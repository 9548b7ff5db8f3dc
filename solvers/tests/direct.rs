//! Sparse Cholesky and LU.

mod common;

use common::*;
use solvers::*;

/// The test problems: 2D 64² and 3D 16³ Laplacians and 1e3-jump operators.
fn problems() -> Vec<(&'static str, CellStencil)> {
    let d2 = [64, 64, 1];
    let d3 = [16, 16, 16];
    vec![
        (
            "2D Laplacian Dirichlet",
            poisson(d2, BoundaryKind::Dirichlet, 0.0),
        ),
        (
            "3D Laplacian Dirichlet",
            poisson(d3, BoundaryKind::Dirichlet, 0.0),
        ),
        (
            "2D inclusion 1e3 Neumann+1e-6",
            from_field(d2, &inclusion_field(d2, 1e3), BoundaryKind::Neumann, 1e-6),
        ),
        (
            "2D checkerboard 1e3 Dirichlet",
            from_field(
                d2,
                &checkerboard_field(d2, 8, 1e3),
                BoundaryKind::Dirichlet,
                0.0,
            ),
        ),
        (
            "3D inclusion 1e3 Dirichlet",
            from_field(d3, &inclusion_field(d3, 1e3), BoundaryKind::Dirichlet, 0.0),
        ),
    ]
}

/// Cholesky and LU solve every SPD test problem to a true relative residual
/// below 1e-10 and agree with each other.
#[test]
fn cholesky_and_lu_solve_test_problems() {
    for (name, st) in problems() {
        let a = st.to_matrix().unwrap();
        let b = zero_mean_rhs(st.num_cells(), 3);
        let mut chol = Cholesky::new(&a).unwrap();
        let mut x = b.clone();
        let rep = chol.solve_in_place(&mut x).unwrap();
        let res = rel_residual(&st, &b, &x);
        assert!(
            res < 1e-10 && rep.rel_residual < 1e-10,
            "{name}: Cholesky {res:e}"
        );
        assert!(rep.setup_s > 0.0 && rep.iterations == 0);
        let mut lu = Lu::new(&a).unwrap();
        let mut y = b.clone();
        let rep = lu.solve_in_place(&mut y).unwrap();
        assert!(
            rep.rel_residual < 1e-10,
            "{name}: LU {:e}",
            rep.rel_residual
        );
        assert!(rel_diff(&y, &x) < 1e-8, "{name}: LU vs Cholesky");
    }
}

/// Numeric refactorisation with new values (same pattern) equals a fresh
/// factorisation; repeated solves give identical results; a changed
/// pattern is rejected.
#[test]
fn cholesky_refactor_matches_fresh() {
    let dims = [20, 17, 1];
    let s1 = from_field(
        dims,
        &inclusion_field(dims, 5.0),
        BoundaryKind::Dirichlet,
        0.0,
    );
    let s2 = from_field(
        dims,
        &checkerboard_field(dims, 3, 50.0),
        BoundaryKind::Neumann,
        0.1,
    );
    let a1 = s1.to_matrix().unwrap();
    let a2 = s2.to_matrix().unwrap();
    let b = pseudo_random(s1.num_cells(), 9);
    let mut chol = Cholesky::new(&a1).unwrap();
    let nnz = chol.factor_nnz();
    chol.refactor(&a2).unwrap();
    assert_eq!(nnz, chol.factor_nnz());
    let mut x = b.clone();
    chol.solve_in_place(&mut x).unwrap();
    let mut fresh = Cholesky::new(&a2).unwrap();
    let mut y = b.clone();
    fresh.solve_in_place(&mut y).unwrap();
    assert!(rel_diff(&x, &y) < 1e-13);
    let mut z = b.clone();
    chol.solve_in_place(&mut z).unwrap();
    assert_eq!(x, z);
    // LU likewise.
    let mut lu = Lu::new(&a1).unwrap();
    lu.refactor(&a2).unwrap();
    let mut w = b.clone();
    lu.solve_in_place(&mut w).unwrap();
    assert!(rel_diff(&w, &y) < 1e-10);
    // Different pattern: error.
    let other = poisson([17, 20, 1], BoundaryKind::Dirichlet, 0.0)
        .to_matrix()
        .unwrap();
    assert!(chol.refactor(&other).is_err());
    // Wrong rhs length: error.
    assert!(matches!(
        chol.solve_in_place(&mut [0.0; 3]),
        Err(SolverError::Dimension { .. })
    ));
}

/// The singular all-Neumann Laplacian, an indefinite matrix and a matrix
/// with a negative diagonal are reported as `Singular` by Cholesky; LU
/// reports a structurally/numerically singular matrix.
#[test]
fn direct_singular_detection() {
    for dims in [[32, 32, 1], [8, 8, 8]] {
        let st = poisson(dims, BoundaryKind::Neumann, 0.0);
        let a = st.to_matrix().unwrap();
        let err = Cholesky::new(&a).unwrap_err();
        assert!(
            matches!(err, SolverError::Singular { .. }),
            "{dims:?}: {err}"
        );
    }
    // Indefinite: Laplacian shifted by -5.
    let st = poisson([10, 10, 1], BoundaryKind::Dirichlet, 0.0);
    let (r, c, mut v) = st.to_triplets();
    for k in 0..r.len() {
        if r[k] == c[k] {
            v[k] -= 5.0;
        }
    }
    let a = Assembler::from_triplets(100, 100, &r, &c, &v)
        .unwrap()
        .into_matrix();
    assert!(matches!(
        Cholesky::new(&a),
        Err(SolverError::Singular { .. })
    ));
    // LU handles the indefinite (nonsingular) matrix.
    let mut lu = Lu::new(&a).unwrap();
    let b = pseudo_random(100, 1);
    let mut x = b.clone();
    assert!(lu.solve_in_place(&mut x).unwrap().rel_residual < 1e-10);
    // LU: a zero column is singular.
    let sing = Assembler::from_triplets(3, 3, &[0, 1, 2, 0], &[0, 1, 1, 2], &[1.0, 2.0, 3.0, 0.0])
        .unwrap()
        .into_matrix();
    assert!(matches!(Lu::new(&sing), Err(SolverError::Singular { .. })));
}

/// Non-symmetric convection–diffusion matrix (upwind) assembled from
/// triplets, solved by LU to 1e-12.
#[test]
fn lu_nonsymmetric() {
    let a = convection_diffusion(40, 30, 25.0);
    let n = a.nrows();
    let b = pseudo_random(n, 5);
    let mut lu = Lu::new(&a).unwrap();
    let mut x = b.clone();
    let rep = lu.solve_in_place(&mut x).unwrap();
    assert!(rep.rel_residual < 1e-12, "{:e}", rep.rel_residual);
    let csr = CsrMatrix::from_csc(&a);
    assert!(rel_residual(&csr, &b, &x) < 1e-12);
}
