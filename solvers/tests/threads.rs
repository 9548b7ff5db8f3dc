//! The parallel paths (red–black sweeps in blocks, residual and restriction
//! by rows, the gathered stencil product) give the serial results to the
//! bit: one and two threads must agree exactly on grids large enough to be
//! shared, for every boundary kind, in 2D and 3D.

mod common;

use common::*;
use solvers::*;

fn run(threads: usize, st: &CellStencil, b: &[f64]) -> (Vec<f64>, Vec<f64>, usize, Vec<f64>) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let mut y = vec![0.0; b.len()];
        st.apply(b, &mut y);
        let mg = Multigrid::new(st, &MgOptions::default()).expect("hierarchy");
        let tol = KrylovOptions {
            rel_tol: 1e-10,
            max_iter: 200,
        };
        let mut ws = KrylovWorkspace::with_dim(b.len());
        let mut x = vec![0.0; b.len()];
        let rep = pcg(st, &mg, b, &mut x, &tol, &mut ws).expect("pcg");
        let mut hist = Vec::new();
        let mut x2 = vec![0.0; b.len()];
        let opts = KrylovOptions {
            rel_tol: 1e-6,
            max_iter: 200,
        };
        mg.solve_with_history(b, &mut x2, &opts, &mut hist)
            .expect("mg");
        assert!(rel_residual(st, b, &x) < 1e-9);
        (y, x, rep.iterations, hist)
    })
}

#[test]
fn one_and_two_threads_agree_to_the_bit() {
    for (dims, bc) in [
        ([256, 256, 1], BoundaryKind::Neumann),
        ([301, 211, 1], BoundaryKind::Dirichlet),
        ([96, 400, 1], BoundaryKind::Periodic),
        ([48, 50, 37], BoundaryKind::Dirichlet),
        ([40, 36, 32], BoundaryKind::Periodic),
    ] {
        let st = from_field(dims, &inclusion_field(dims, 1e3), bc, 1e-6);
        let b = zero_mean_rhs(st.num_cells(), 7);
        let one = run(1, &st, &b);
        let two = run(2, &st, &b);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one.0), bits(&two.0), "{dims:?} {bc:?}: A x differs");
        assert_eq!(one.2, two.2, "{dims:?} {bc:?}: PCG iterations differ");
        assert_eq!(
            bits(&one.1),
            bits(&two.1),
            "{dims:?} {bc:?}: PCG solution differs"
        );
        assert_eq!(
            bits(&one.3),
            bits(&two.3),
            "{dims:?} {bc:?}: MG history differs"
        );
    }
}
