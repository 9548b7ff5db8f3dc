//! Periodic boundaries of [`CellStencil`]: the operator against an
//! independent wrap-around reference and an exact discrete Fourier
//! eigenpair, and the multigrid (standalone and as a PCG preconditioner)
//! against the direct Cholesky solve on 2D/3D periodic and mixed
//! periodic/Neumann/Dirichlet problems, constant and 1e3-jump coefficients.

mod common;

use std::f64::consts::PI;

use common::*;
use solvers::*;

const OPTS: KrylovOptions = KrylovOptions {
    rel_tol: 1e-10,
    max_iter: 200,
};

/// Periodic Poisson stencil: `uniform` with every axis periodic.
fn periodic_poisson(dims: [usize; 3], diag_extra_rel: f64) -> CellStencil {
    poisson(dims, BoundaryKind::Periodic, diag_extra_rel)
}

/// Reference `y = A x` written independently of the library kernels:
/// neighbours by index arithmetic modulo `n` on periodic axes, boundary
/// kinds read through the public API.
fn reference_apply(st: &CellStencil, x: &[f64]) -> Vec<f64> {
    let dims = st.dims();
    let mut y: Vec<f64> = st.diag_extra().iter().zip(x).map(|(d, x)| d * x).collect();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let c = [i, j, k];
                let p = st.cell_index(c);
                for a in 0..st.ndim() {
                    let n = dims[a];
                    let per = st.is_periodic(a);
                    // Low face (position c[a]) and high face (c[a] + 1).
                    for side in 0..2 {
                        let mut f = c;
                        f[a] += side;
                        let at_boundary = f[a] == 0 || f[a] == n;
                        if at_boundary && per {
                            if n == 1 {
                                continue;
                            }
                            f[a] = 0;
                            let coef = st.face_coeffs(a)[st.face_index(a, f)];
                            let mut nb = c;
                            nb[a] = if side == 0 { n - 1 } else { 0 };
                            y[p] += coef * (x[p] - x[st.cell_index(nb)]);
                        } else if at_boundary {
                            let kind = st.boundary_kind(a, side, c).unwrap();
                            if kind == BoundaryKind::Dirichlet {
                                let coef = st.face_coeffs(a)[st.face_index(a, f)];
                                y[p] += coef * x[p];
                            }
                        } else {
                            let coef = st.face_coeffs(a)[st.face_index(a, f)];
                            let mut nb = c;
                            nb[a] = if side == 0 { c[a] - 1 } else { c[a] + 1 };
                            y[p] += coef * (x[p] - x[st.cell_index(nb)]);
                        }
                    }
                }
            }
        }
    }
    y
}

/// The discrete Fourier mode `Π_a cos(2π m_a (i_a + 1/2)/n_a + φ_a)` is an
/// exact eigenvector of the constant-coefficient periodic operator with
/// eigenvalue `d + Σ_a c (2 − 2 cos(2π m_a/n_a))`: a manufactured solution
/// that is exact at the discrete level.
fn fourier_mode(dims: [usize; 3], modes: [usize; 3]) -> (Vec<f64>, [f64; 3]) {
    let phase = [0.3, 1.1, -0.7];
    let mut u = Vec::with_capacity(dims.iter().product());
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let c = [i, j, k];
                let mut v = 1.0;
                for a in 0..3 {
                    if dims[a] > 1 {
                        let t = 2.0 * PI * modes[a] as f64 * (c[a] as f64 + 0.5) / dims[a] as f64;
                        v *= (t + phase[a]).cos();
                    }
                }
                u.push(v);
            }
        }
    }
    let theta = std::array::from_fn(|a| 2.0 * PI * modes[a] as f64 / dims[a] as f64);
    (u, theta)
}

fn solve_direct(st: &CellStencil, b: &[f64]) -> Vec<f64> {
    let mut x = b.to_vec();
    Cholesky::new(&st.to_matrix().unwrap())
        .unwrap()
        .solve_in_place(&mut x)
        .unwrap();
    x
}

/// Matrix-free product, assembled matrix, diagonal and triplet count of
/// periodic stencils (all-periodic, mixed with Neumann and Dirichlet, two
/// and one cells along a periodic axis, variable coefficients) agree with
/// the independent wrap-around reference to round-off.
#[test]
fn periodic_operator_matches_reference() {
    let cases: Vec<(&str, CellStencil)> = vec![
        ("2D periodic 16x12", {
            let d = [16, 12, 1];
            from_field(
                d,
                &checkerboard_field(d, 3, 1e3),
                BoundaryKind::Periodic,
                1e-3,
            )
        }),
        ("3D periodic 6x8x4", {
            let d = [6, 8, 4];
            from_field(d, &inclusion_field(d, 1e3), BoundaryKind::Periodic, 1e-3)
        }),
        ("2D periodic x, Dirichlet y", {
            let d = [10, 7, 1];
            let mut s = from_field(
                d,
                &checkerboard_field(d, 2, 5.0),
                BoundaryKind::Dirichlet,
                0.0,
            );
            s.set_periodic(0).unwrap();
            s
        }),
        ("3D Neumann x, periodic y and z", {
            let d = [5, 4, 6];
            let mut s = from_field(d, &inclusion_field(d, 0.1), BoundaryKind::Neumann, 1e-2);
            s.set_periodic(1).unwrap();
            s.set_periodic(2).unwrap();
            s
        }),
        ("2D two cells along periodic x", {
            let d = [2, 9, 1];
            let mut s = from_field(
                d,
                &checkerboard_field(d, 2, 7.0),
                BoundaryKind::Periodic,
                1e-2,
            );
            s.face_coeffs_mut(0)
                .iter_mut()
                .enumerate()
                .for_each(|(i, c)| *c += i as f64);
            s
        }),
        (
            "2D one cell along periodic y",
            periodic_poisson([9, 1, 1], 1e-2),
        ),
    ];
    for (name, st) in &cases {
        st.validate().unwrap();
        let n = st.num_cells();
        let x = pseudo_random(n, 3);
        let want = reference_apply(st, &x);
        let mut y = vec![0.0; n];
        st.apply_checked(&x, &mut y).unwrap();
        assert!(rel_diff(&y, &want) < 1e-14, "{name}: apply");
        let a = st.to_matrix().unwrap();
        let mut ym = vec![0.0; n];
        CsrMatrix::from_csc(&a).apply(&x, &mut ym);
        assert!(rel_diff(&ym, &want) < 1e-14, "{name}: matrix");
        assert_eq!(st.triplet_pattern().0.len(), st.num_triplets(), "{name}");
        // Diagonal: A e_p at p.
        let diag = st.diagonal();
        for p in [0, n / 2, n - 1] {
            let mut e = vec![0.0; n];
            e[p] = 1.0;
            let col = reference_apply(st, &e);
            assert!(
                (diag[p] - col[p]).abs() <= 1e-14 * col[p].abs(),
                "{name}: diag {p}"
            );
        }
        // Symmetric: <A x, z> = <x, A z>.
        let z = pseudo_random(n, 4);
        let az = reference_apply(st, &z);
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let (s1, s2) = (dot(&ym, &z), dot(&x, &az));
        let scale = dot(&ym, &ym).sqrt() * dot(&z, &z).sqrt();
        assert!((s1 - s2).abs() <= 1e-14 * scale, "{name}: symmetry");
    }
}

/// Exact discrete eigenpairs (manufactured solutions) of the periodic
/// Poisson operator in 2D and 3D, and a PCG-multigrid solve that recovers
/// them from `b = λ u` to the accuracy the 1e-10 residual allows.
#[test]
fn periodic_fourier_manufactured_solution() {
    for (dims, modes) in [([128, 64, 1], [3, 5, 0]), ([16, 16, 32], [1, 2, 7])] {
        let st = periodic_poisson(dims, 1e-3);
        let (u, theta) = fourier_mode(dims, modes);
        let c = scale(dims);
        let d = st.diag_extra()[0];
        let lambda = d
            + (0..st.ndim())
                .map(|a| c * (2.0 - 2.0 * theta[a].cos()))
                .sum::<f64>();
        let mut au = vec![0.0; u.len()];
        st.apply_checked(&u, &mut au).unwrap();
        let b: Vec<f64> = u.iter().map(|v| lambda * v).collect();
        assert!(rel_diff(&au, &b) < 1e-13, "{dims:?}: eigenpair");
        let mg = Multigrid::new(&st, &MgOptions::default()).unwrap();
        let mut x = vec![0.0; u.len()];
        let mut ws = KrylovWorkspace::new();
        let rep = pcg(&st, &mg, &b, &mut x, &OPTS, &mut ws).unwrap();
        // ‖x − u‖/‖u‖ ≤ ‖A⁻¹‖ ‖r‖/‖u‖ ≤ (λ/λ_min) 1e-10 for an eigenvector.
        let err = rel_diff(&x, &u);
        println!("{dims:?}: PCG-MG {} its, error {err:.2e}", rep.iterations);
        assert!(err < lambda / d * 1e-10 && err < 1e-7, "{dims:?}: {err:e}");
        assert!(rep.iterations <= 12, "{dims:?}: {}", rep.iterations);
    }
}

/// PCG-multigrid and standalone multigrid reach relative residual 1e-10 on
/// periodic problems (2D, 3D, constant and 1e3-jump coefficients, mixed
/// periodic/Neumann/Dirichlet) and agree with the direct Cholesky solve.
#[test]
fn periodic_pcg_multigrid_agrees_with_cholesky() {
    let d2 = [128, 128, 1];
    let d3 = [32, 32, 32];
    let cases: Vec<(&str, CellStencil)> = vec![
        ("2D periodic Poisson", periodic_poisson(d2, 1e-4)),
        ("3D periodic Poisson", periodic_poisson(d3, 1e-4)),
        (
            "2D periodic inclusion 1e3",
            from_field(d2, &inclusion_field(d2, 1e3), BoundaryKind::Periodic, 1e-4),
        ),
        (
            "2D periodic checkerboard 1e3",
            from_field(
                d2,
                &checkerboard_field(d2, 8, 1e3),
                BoundaryKind::Periodic,
                1e-4,
            ),
        ),
        (
            "3D periodic inclusion 1e-3",
            from_field(d3, &inclusion_field(d3, 1e-3), BoundaryKind::Periodic, 1e-4),
        ),
        ("2D periodic x, Dirichlet y", {
            let mut s = from_field(d2, &inclusion_field(d2, 1e3), BoundaryKind::Dirichlet, 0.0);
            s.set_periodic(0).unwrap();
            s
        }),
        ("2D periodic x, Neumann y", {
            let mut s = from_field(
                [96, 64, 1],
                &checkerboard_field([96, 64, 1], 4, 1e3),
                BoundaryKind::Neumann,
                1e-4,
            );
            s.set_periodic(0).unwrap();
            s
        }),
        ("2D Dirichlet x, periodic y", {
            let mut s = poisson([64, 128, 1], BoundaryKind::Dirichlet, 0.0);
            s.set_periodic(1).unwrap();
            s
        }),
        ("3D periodic z, Dirichlet x and y", {
            let mut s = from_field(d3, &inclusion_field(d3, 1e3), BoundaryKind::Dirichlet, 0.0);
            s.set_periodic(2).unwrap();
            s
        }),
        ("3D periodic x and y, Neumann z", {
            let mut s = poisson([32, 32, 16], BoundaryKind::Neumann, 1e-4);
            s.set_periodic(0).unwrap();
            s.set_periodic(1).unwrap();
            s
        }),
    ];
    for (name, st) in &cases {
        let n = st.num_cells();
        let b = zero_mean_rhs(n, 5);
        let xd = solve_direct(st, &b);
        let mg = Multigrid::new(st, &MgOptions::default()).unwrap();
        let mut x = vec![0.0; n];
        let mut ws = KrylovWorkspace::new();
        let rep = pcg(st, &mg, &b, &mut x, &OPTS, &mut ws).unwrap();
        let res = rel_residual(st, &b, &x);
        let diff = rel_diff(&x, &xd);
        println!(
            "{name}: {} levels, PCG-MG {} its, residual {res:.2e}, vs Cholesky {diff:.2e}",
            mg.num_levels(),
            rep.iterations
        );
        assert!(mg.num_levels() >= 2, "{name}");
        assert!(
            rep.rel_residual <= 1e-10 && res <= 1.5e-10,
            "{name}: {res:e}"
        );
        assert!(diff < 1e-8, "{name}: {diff:e}");
        assert!(rep.iterations <= 20, "{name}: {}", rep.iterations);
        let mut x = vec![0.0; n];
        let w = MgOptions {
            cycle: Cycle::W,
            ..Default::default()
        };
        let rep = Multigrid::new(st, &w)
            .unwrap()
            .solve(&b, &mut x, &OPTS)
            .unwrap();
        let res = rel_residual(st, &b, &x);
        println!("{name}: standalone W {} cycles", rep.iterations);
        assert!(res <= 1.5e-10, "{name}: standalone {res:e}");
        assert!(rel_diff(&x, &xd) < 1e-8, "{name}: standalone vs Cholesky");
    }
}

/// Stationary V(3,3) convergence factor below 0.2 on periodic Poisson
/// problems (2D 128², 3D 32³; default and deep hierarchies; a mixed
/// periodic/Dirichlet case).
#[test]
fn periodic_vcycle_factor() {
    let mut mixed = poisson([128, 128, 1], BoundaryKind::Dirichlet, 0.0);
    mixed.set_periodic(1).unwrap();
    let cases = [
        ("2D periodic 128^2", periodic_poisson([128, 128, 1], 1e-4)),
        ("3D periodic 32^3", periodic_poisson([32, 32, 32], 1e-4)),
        ("2D Dirichlet x, periodic y 128^2", mixed),
    ];
    for (name, st) in &cases {
        let n = st.num_cells();
        for coarse_max_cells in [2048, 8] {
            let mg = Multigrid::new(
                st,
                &MgOptions {
                    coarse_max_cells,
                    ..Default::default()
                },
            )
            .unwrap();
            let f = mg_factor(&mg, n, 3, 40);
            println!("{name}: V(3,3) factor {f:.3} ({} levels)", mg.num_levels());
            assert!(
                f < 0.2,
                "{name}, coarse_max_cells {coarse_max_cells}: factor {f}"
            );
        }
    }
}

/// The multigrid cycle stays a symmetric preconditioner with periodic axes
/// (ghost fill and restriction fold are transposes; exact red–black order):
/// `⟨M⁻¹ r₁, r₂⟩ = ⟨r₁, M⁻¹ r₂⟩` to round-off, also with a deep hierarchy
/// whose periodic axes shrink to two and one cells.
#[test]
fn periodic_cycle_is_symmetric() {
    let d = [32, 16, 8];
    let mut mixed = from_field(d, &inclusion_field(d, 1e3), BoundaryKind::Neumann, 1e-3);
    mixed.set_periodic(0).unwrap();
    mixed.set_periodic(2).unwrap();
    // Periodic y inside the plane-fused 3D sweep.
    let mut fused = from_field(d, &inclusion_field(d, 1e3), BoundaryKind::Dirichlet, 0.0);
    fused.set_periodic(1).unwrap();
    for st in [
        from_field(
            [64, 32, 1],
            &checkerboard_field([64, 32, 1], 4, 1e3),
            BoundaryKind::Periodic,
            1e-4,
        ),
        from_field(d, &inclusion_field(d, 1e3), BoundaryKind::Periodic, 1e-4),
        mixed,
        fused,
    ] {
        let n = st.num_cells();
        let mg = Multigrid::new(
            &st,
            &MgOptions {
                coarse_max_cells: 1,
                ..Default::default()
            },
        )
        .unwrap();
        let (r1, r2) = (pseudo_random(n, 1), pseudo_random(n, 2));
        let (mut z1, mut z2) = (vec![0.0; n], vec![0.0; n]);
        mg.apply(&r1, &mut z1);
        mg.apply(&r2, &mut z2);
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let (s12, s21) = (dot(&z1, &r2), dot(&r1, &z2));
        println!(
            "{:?}: {} levels, <Mr1,r2> {s12:e} vs {s21:e}",
            st.dims(),
            mg.num_levels()
        );
        assert!(
            (s12 - s21).abs() <= 1e-12 * s12.abs().max(s21.abs()),
            "{:?}",
            st.dims()
        );
        // Positive definite on these vectors.
        assert!(dot(&z1, &r1) > 0.0 && dot(&z2, &r2) > 0.0);
    }
}

/// Nearly singular all-periodic operators (tiny `diag_extra`) are solved;
/// the exactly singular one (no `diag_extra`) is rejected at setup with
/// [`SolverError::Singular`]; a half-periodic axis, per-face periodic
/// kinds and an odd periodic axis that would need smoothing are rejected
/// with [`SolverError::InvalidInput`] naming the axis; small odd periodic
/// grids (solved directly) and even grids with an odd coarse level (which
/// becomes the coarsest) work.
#[test]
fn periodic_singular_and_invalid_input() {
    // Nearly singular: λ_min / λ_max ≈ 1e-10 / 8.
    let st = periodic_poisson([64, 64, 1], 1e-10);
    let mg = Multigrid::new(&st, &MgOptions::default()).unwrap();
    let b = zero_mean_rhs(st.num_cells(), 9);
    let mut x = vec![0.0; b.len()];
    let mut ws = KrylovWorkspace::new();
    let rep = pcg(&st, &mg, &b, &mut x, &OPTS, &mut ws).unwrap();
    println!("nearly singular: {} its", rep.iterations);
    assert!(rel_residual(&st, &b, &x) <= 1.5e-10 && rep.iterations <= 20);
    // Exactly singular, 2D and 3D, also through refresh.
    for dims in [[32, 32, 1], [8, 8, 8]] {
        let sing = periodic_poisson(dims, 0.0);
        let err = Multigrid::new(&sing, &MgOptions::default()).unwrap_err();
        assert!(
            matches!(err, SolverError::Singular { ref detail } if detail.contains("periodic")),
            "{dims:?}: {err}"
        );
        assert!(sing.to_matrix().is_ok());
        assert!(matches!(
            Cholesky::new(&sing.to_matrix().unwrap()),
            Err(SolverError::Singular { .. })
        ));
    }
    let mut mg =
        Multigrid::new(&periodic_poisson([32, 32, 1], 1e-3), &MgOptions::default()).unwrap();
    assert!(matches!(
        mg.refresh(&periodic_poisson([32, 32, 1], 0.0)),
        Err(SolverError::Singular { .. })
    ));
    // Two components joined only through the wrap faces are one component.
    let mut st = poisson([8, 8, 1], BoundaryKind::Neumann, 0.0);
    for j in 0..8 {
        st.set_face(0, [4, j, 0], 0.0).unwrap();
    }
    st.set_periodic(0).unwrap();
    st.diag_extra_mut()[0] = 1.0;
    st.check_nonsingular().unwrap();
    // Half-periodic axis.
    let mut half = poisson([16, 16, 1], BoundaryKind::Dirichlet, 0.0);
    half.set_boundary_side(1, 0, BoundaryKind::Periodic)
        .unwrap();
    let err = Multigrid::new(&half, &MgOptions::default()).unwrap_err();
    assert!(
        matches!(err, SolverError::InvalidInput { ref detail } if detail.contains("axis 1")),
        "{err}"
    );
    assert!(half.to_matrix().is_err());
    // Periodic is per axis, not per face.
    let mut s = poisson([16, 16, 1], BoundaryKind::Periodic, 1e-3);
    assert!(s
        .set_boundary_face(0, 0, [0, 3, 0], BoundaryKind::Periodic)
        .is_err());
    s.set_boundary_face(0, 0, [0, 3, 0], BoundaryKind::Dirichlet)
        .unwrap();
    assert!(!s.is_periodic(0) && s.validate().is_err());
    // Odd periodic axis on a level that must be smoothed.
    let odd = periodic_poisson([65, 64, 1], 1e-3);
    let err = Multigrid::new(&odd, &MgOptions::default()).unwrap_err();
    assert!(
        matches!(err, SolverError::InvalidInput { ref detail } if detail.contains("axis 0") && detail.contains("odd")),
        "{err}"
    );
    // ... fine when small enough to be solved directly, and an even grid
    // whose coarse level is odd (100 -> 50 -> 25) stops there.
    for (dims, max) in [([15, 9, 1], 2048), ([100, 100, 1], 64)] {
        let st = from_field(
            dims,
            &inclusion_field(dims, 1e3),
            BoundaryKind::Periodic,
            1e-3,
        );
        let mg = Multigrid::new(
            &st,
            &MgOptions {
                coarse_max_cells: max,
                ..Default::default()
            },
        )
        .unwrap();
        let n = st.num_cells();
        let b = pseudo_random(n, 4);
        let mut x = vec![0.0; n];
        let rep = pcg(&st, &mg, &b, &mut x, &OPTS, &mut ws).unwrap();
        println!(
            "{dims:?}: levels {:?}, {} its",
            (0..mg.num_levels())
                .map(|l| mg.level_dims(l).unwrap())
                .collect::<Vec<_>>(),
            rep.iterations
        );
        assert!(rel_diff(&x, &solve_direct(&st, &b)) < 1e-8, "{dims:?}");
        if max == 64 {
            assert_eq!(mg.level_dims(mg.num_levels() - 1), Some([25, 25, 1]));
        }
    }
}

/// `refresh` with new periodic coefficients equals a fresh hierarchy.
#[test]
fn periodic_refresh_matches_new() {
    let d = [64, 48, 1];
    let s1 = from_field(d, &inclusion_field(d, 1e3), BoundaryKind::Periodic, 1e-4);
    let s2 = from_field(
        d,
        &checkerboard_field(d, 4, 1e-2),
        BoundaryKind::Periodic,
        1e-2,
    );
    let mut mg = Multigrid::new(&s1, &MgOptions::default()).unwrap();
    mg.refresh(&s2).unwrap();
    let fresh = Multigrid::new(&s2, &MgOptions::default()).unwrap();
    let r = pseudo_random(s2.num_cells(), 3);
    let (mut z1, mut z2) = (vec![0.0; r.len()], vec![0.0; r.len()]);
    mg.apply(&r, &mut z1);
    fresh.apply(&r, &mut z2);
    assert!(rel_diff(&z1, &z2) < 1e-13);
    // Other boundary kinds than the hierarchy's are an error.
    let s3 = from_field(d, &inclusion_field(d, 1e3), BoundaryKind::Neumann, 1e-4);
    let err = mg.refresh(&s3).unwrap_err();
    assert!(
        matches!(err, SolverError::InvalidInput { ref detail } if detail.contains("periodic")),
        "{err}"
    );
}
