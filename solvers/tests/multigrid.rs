//! Geometric multigrid on cell-centred stencils.

mod common;

use common::*;
use solvers::*;

const OPTS: KrylovOptions = KrylovOptions {
    rel_tol: 1e-10,
    max_iter: 200,
};

/// Stationary V-cycle convergence factor (default options, V(3,3)) below
/// 0.2 on 2D (128²) and 3D (32³) Poisson problems with Dirichlet and with
/// Neumann + diag_extra boundaries; also the piecewise-constant
/// prolongation and V(2,2) in 2D.
#[test]
fn vcycle_factor_poisson() {
    let cases = [
        (
            "2D Dirichlet 128^2",
            poisson([128, 128, 1], BoundaryKind::Dirichlet, 0.0),
        ),
        (
            "2D Neumann+1e-6 128^2",
            poisson([128, 128, 1], BoundaryKind::Neumann, 1e-6),
        ),
        (
            "3D Dirichlet 32^3",
            poisson([32, 32, 32], BoundaryKind::Dirichlet, 0.0),
        ),
        (
            "3D Neumann+1e-6 32^3",
            poisson([32, 32, 32], BoundaryKind::Neumann, 1e-6),
        ),
    ];
    for (name, st) in &cases {
        let n = st.num_cells();
        let mg = Multigrid::new(st, &MgOptions::default()).unwrap();
        let f = mg_factor(&mg, n, 3, 40);
        println!("{name}: V(3,3) factor {f:.3} ({} levels)", mg.num_levels());
        assert!(f < 0.2, "{name}: V-cycle factor {f}");
        // Deep hierarchy down to <= 8 cells.
        let deep = Multigrid::new(
            st,
            &MgOptions {
                coarse_max_cells: 8,
                ..Default::default()
            },
        )
        .unwrap();
        let fd = mg_factor(&deep, n, 3, 40);
        println!(
            "{name}: V(3,3) factor {fd:.3} ({} levels)",
            deep.num_levels()
        );
        assert!(fd < 0.2, "{name}: deep V-cycle factor {fd}");
        let c = Multigrid::new(
            st,
            &MgOptions {
                prolongation: Prolongation::Constant,
                pre_smooth: 2,
                post_smooth: 2,
                ..Default::default()
            },
        )
        .unwrap();
        let fc = mg_factor(&c, n, 3, 40);
        println!("{name}: constant-prolongation V(2,2) factor {fc:.3}");
        assert!(fc < 0.2, "{name}: constant V-cycle factor {fc}");
        if st.ndim() == 2 {
            let v22 = Multigrid::new(
                st,
                &MgOptions {
                    pre_smooth: 2,
                    post_smooth: 2,
                    ..Default::default()
                },
            )
            .unwrap();
            let f22 = mg_factor(&v22, n, 3, 40);
            println!("{name}: V(2,2) factor {f22:.3}");
            assert!(f22 < 0.2, "{name}: V(2,2) factor {f22}");
        }
    }
}

/// Standalone multigrid reaches relative residual 1e-10 on 1e3-jump
/// problems (V-cycle for inclusions, W-cycle for checkerboards, whose cross
/// points defeat the standalone V-cycle) and agrees with Cholesky; PCG-MG
/// with the default V-cycle handles all of them.
#[test]
fn standalone_mg_jump_problems() {
    let d2 = [64, 64, 1];
    let d3 = [16, 16, 16];
    let w = MgOptions {
        cycle: Cycle::W,
        ..Default::default()
    };
    let v = MgOptions::default();
    let cases = [
        (
            "2D inclusion 1e3",
            from_field(d2, &inclusion_field(d2, 1e3), BoundaryKind::Dirichlet, 0.0),
            v,
        ),
        (
            "2D inclusion 1e-3 Neumann",
            from_field(d2, &inclusion_field(d2, 1e-3), BoundaryKind::Neumann, 1e-6),
            v,
        ),
        (
            "3D inclusion 1e3",
            from_field(d3, &inclusion_field(d3, 1e3), BoundaryKind::Dirichlet, 0.0),
            v,
        ),
        (
            "2D checkerboard 1e3",
            from_field(
                d2,
                &checkerboard_field(d2, 8, 1e3),
                BoundaryKind::Dirichlet,
                0.0,
            ),
            w,
        ),
        (
            "3D checkerboard 1e3",
            from_field(
                d3,
                &checkerboard_field(d3, 4, 1e3),
                BoundaryKind::Dirichlet,
                0.0,
            ),
            w,
        ),
    ];
    for (name, st, o) in &cases {
        let n = st.num_cells();
        let b = zero_mean_rhs(n, 5);
        let mut xd = b.clone();
        Cholesky::new(&st.to_matrix().unwrap())
            .unwrap()
            .solve_in_place(&mut xd)
            .unwrap();
        let mg = Multigrid::new(st, o).unwrap();
        let mut x = vec![0.0; n];
        let rep = mg.solve(&b, &mut x, &OPTS).unwrap();
        let res = rel_residual(st, &b, &x);
        println!(
            "{name}: standalone {:?} {} cycles, residual {res:.2e}",
            o.cycle, rep.iterations
        );
        assert!(
            rep.rel_residual <= 1e-10 && res <= 1.5e-10,
            "{name}: {res:e}"
        );
        assert!(rep.setup_s > 0.0);
        let near_singular = name.contains("Neumann");
        let demean = |x: &[f64]| -> Vec<f64> {
            let m = if near_singular {
                x.iter().sum::<f64>() / n as f64
            } else {
                0.0
            };
            x.iter().map(|v| v - m).collect()
        };
        assert!(rel_diff(&demean(&x), &demean(&xd)) < 1e-8, "{name}");
        let mg_v = Multigrid::new(st, &v).unwrap();
        let mut x = vec![0.0; n];
        let mut ws = KrylovWorkspace::new();
        let rep = pcg(st, &mg_v, &b, &mut x, &OPTS, &mut ws).unwrap();
        println!("{name}: PCG-MG(V) {} iterations", rep.iterations);
        assert!(rep.iterations <= 20);
    }
}

/// The singular all-Neumann system with diag_extra = 0 is rejected at
/// setup (2D and 3D), as is an island cut off by zero coefficients; giving
/// the island a diag_extra (or a Dirichlet face) makes it solvable.
#[test]
fn singular_all_neumann_is_an_error() {
    for dims in [[32, 32, 1], [8, 8, 8], [5, 7, 1]] {
        let st = poisson(dims, BoundaryKind::Neumann, 0.0);
        let err = Multigrid::new(&st, &MgOptions::default()).unwrap_err();
        assert!(
            matches!(err, SolverError::Singular { .. }),
            "{dims:?}: {err}"
        );
        assert!(st.check_nonsingular().is_err());
    }
    // Dirichlet grid with a 2x2 island isolated by zero faces.
    let dims = [8, 8, 1];
    let mut k = vec![1.0; 64];
    let mut st = from_field(dims, &k, BoundaryKind::Dirichlet, 0.0);
    for (axis, faces) in [
        (0usize, [[3, 3, 0], [3, 4, 0], [5, 3, 0], [5, 4, 0]]),
        (1, [[3, 3, 0], [4, 3, 0], [3, 5, 0], [4, 5, 0]]),
    ] {
        for f in faces {
            st.set_face(axis, f, 0.0).unwrap();
        }
    }
    let err = Multigrid::new(&st, &MgOptions::default()).unwrap_err();
    assert!(
        matches!(err, SolverError::Singular { ref detail } if detail.contains("4 cells")),
        "{err}"
    );
    let island = st.cell_index([4, 4, 0]);
    st.diag_extra_mut()[island] = 1e-3;
    let mg = Multigrid::new(&st, &MgOptions::default()).unwrap();
    let b = pseudo_random(64, 1);
    let mut x = vec![0.0; 64];
    let mut ws = KrylovWorkspace::new();
    assert!(
        pcg(&st, &mg, &b, &mut x, &OPTS, &mut ws)
            .unwrap()
            .rel_residual
            <= 1e-10
    );
    // Invalid data is an error too.
    k[3] = -1.0;
    assert!(CellStencil::from_cell_field(dims, &k, 1.0, BoundaryKind::Neumann).is_err());
    assert!(st.set_face(0, [0, 0, 0], f64::NAN).is_err());
    let bad = MgOptions {
        omega: 2.5,
        ..Default::default()
    };
    assert!(Multigrid::new(&st, &bad).is_err());
}

/// Odd and anisotropic grid sizes (coarse cells covering one fine cell),
/// mixed per-face boundary kinds and a thin 3D slab are solved by PCG-MG
/// and standalone MG; the matrix-free stencil product equals the assembled
/// matrix product.
#[test]
fn odd_sizes_and_mixed_boundaries() {
    for dims in [
        [37, 23, 1],
        [9, 15, 11],
        [33, 33, 3],
        [101, 1, 1],
        [65, 64, 1],
    ] {
        let mut st = from_field(
            dims,
            &checkerboard_field(dims, 3, 30.0),
            BoundaryKind::Neumann,
            0.0,
        );
        // Dirichlet patch on part of the low-x side only.
        for j in 0..dims[1].div_ceil(2) {
            for k in 0..dims[2] {
                st.set_boundary_face(0, 0, [0, j, k], BoundaryKind::Dirichlet)
                    .unwrap();
            }
        }
        st.check_nonsingular().unwrap();
        let n = st.num_cells();
        let x0 = pseudo_random(n, 8);
        let mut y1 = vec![0.0; n];
        let mut y2 = vec![0.0; n];
        st.apply(&x0, &mut y1);
        CsrMatrix::from_csc(&st.to_matrix().unwrap()).apply(&x0, &mut y2);
        assert!(rel_diff(&y1, &y2) < 1e-14, "{dims:?}");
        let b = pseudo_random(n, 6);
        let mg = Multigrid::new(
            &st,
            &MgOptions {
                coarse_max_cells: 16,
                ..Default::default()
            },
        )
        .unwrap();
        let mut x = vec![0.0; n];
        let mut ws = KrylovWorkspace::new();
        let rep = pcg(&st, &mg, &b, &mut x, &OPTS, &mut ws).unwrap();
        assert!(
            rep.iterations <= 25,
            "{dims:?}: {} iterations",
            rep.iterations
        );
        let mut x = vec![0.0; n];
        let w = MgOptions {
            cycle: Cycle::W,
            coarse_max_cells: 16,
            ..Default::default()
        };
        let rep2 = Multigrid::new(&st, &w)
            .unwrap()
            .solve(&b, &mut x, &OPTS)
            .unwrap();
        println!(
            "{dims:?}: {} levels, PCG-MG {} its, standalone W {} cycles",
            mg.num_levels(),
            rep.iterations,
            rep2.iterations
        );
        assert!(rel_residual(&st, &b, &x) <= 1.5e-10);
    }
}

/// `refresh` with new coefficients on the same grid gives the same cycle
/// as building a new hierarchy; a zero rhs gives x = 0.
#[test]
fn refresh_matches_new() {
    let dims = [48, 40, 1];
    let s1 = from_field(
        dims,
        &inclusion_field(dims, 1e3),
        BoundaryKind::Neumann,
        1e-6,
    );
    let s2 = from_field(
        dims,
        &checkerboard_field(dims, 4, 1e-2),
        BoundaryKind::Dirichlet,
        0.0,
    );
    let mut mg = Multigrid::new(&s1, &MgOptions::default()).unwrap();
    mg.refresh(&s2).unwrap();
    let fresh = Multigrid::new(&s2, &MgOptions::default()).unwrap();
    let r = pseudo_random(s2.num_cells(), 3);
    let mut z1 = vec![0.0; r.len()];
    let mut z2 = vec![0.0; r.len()];
    mg.apply(&r, &mut z1);
    fresh.apply(&r, &mut z2);
    assert!(rel_diff(&z1, &z2) < 1e-13);
    assert!(mg
        .refresh(&poisson([40, 48, 1], BoundaryKind::Dirichlet, 0.0))
        .is_err());
    let mut x = pseudo_random(r.len(), 1);
    let rep = mg.solve(&vec![0.0; r.len()], &mut x, &OPTS).unwrap();
    assert_eq!(rep.iterations, 0);
    assert!(x.iter().all(|&v| v == 0.0));
}
