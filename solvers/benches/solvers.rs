//! Criterion benchmarks: setup and solve of Cholesky, PCG-Jacobi and
//! PCG-multigrid on the variable-coefficient cell-centred Poisson problem
//! (1e3 ball inclusion, all-Neumann, diag_extra = 1e-6·c, zero-mean random
//! rhs, rel_tol 1e-10). The `pcg_multigrid` rows (setup, solve, V-cycle)
//! run on explicit rayon pools of 1 and 2 threads, the thread count the
//! last part of the id (`pcg_multigrid/solve/256^2/2`); the other groups
//! run outside any pool of ours, as before.
//!
//! Default sizes are kept small so that `cargo bench -p solvers` finishes in
//! a few minutes; set `SOLVERS_BENCH_LARGE=1` to add 1024² and 96³ for the
//! multigrid paths. The `pcg_multigrid_periodic` group repeats the
//! multigrid rows with all boundaries periodic (256²: setup, refresh,
//! solve; 1024²: setup + solve). The full scaling table (all sizes and methods, slopes,
//! crossover) is printed by `cargo run --release -p solvers --example
//! scaling`.

#[path = "../tests/common/mod.rs"]
mod common;

use std::hint::black_box;
use std::time::Duration;

use common::*;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use solvers::*;

fn problem(dims: [usize; 3]) -> (CellStencil, Vec<f64>) {
    let st = from_field(
        dims,
        &inclusion_field(dims, 1e3),
        BoundaryKind::Neumann,
        1e-6,
    );
    let b = zero_mean_rhs(st.num_cells(), 42);
    (st, b)
}

fn label(d: [usize; 3]) -> String {
    if d[2] > 1 {
        format!("{}^3", d[0])
    } else {
        format!("{}^2", d[0])
    }
}

const TOL: KrylovOptions = KrylovOptions {
    rel_tol: 1e-10,
    max_iter: 50_000,
};

fn benches(c: &mut Criterion) {
    let large = std::env::var("SOLVERS_BENCH_LARGE").is_ok();
    let mut mg_sizes = vec![
        [128, 128, 1],
        [256, 256, 1],
        [512, 512, 1],
        [32, 32, 32],
        [64, 64, 64],
    ];
    if large {
        mg_sizes.extend([[1024, 1024, 1], [96, 96, 96]]);
    }
    let chol_sizes = [[128, 128, 1], [256, 256, 1], [32, 32, 32]];
    let jac_sizes = [[128, 128, 1], [32, 32, 32]];

    let mut g = c.benchmark_group("cholesky");
    g.sample_size(10).measurement_time(Duration::from_secs(3));
    for d in chol_sizes {
        let (st, b) = problem(d);
        let a = st.to_matrix().unwrap();
        g.bench_function(format!("setup/{}", label(d)), |bch| {
            bch.iter(|| black_box(Cholesky::new(&a).unwrap()))
        });
        let mut chol = Cholesky::new(&a).unwrap();
        let mut x = b.clone();
        g.bench_function(format!("solve/{}", label(d)), |bch| {
            bch.iter(|| {
                x.copy_from_slice(&b);
                black_box(chol.solve_in_place(&mut x).unwrap())
            })
        });
    }
    g.finish();

    let mut g = c.benchmark_group("pcg_jacobi");
    g.sample_size(10).measurement_time(Duration::from_secs(3));
    for d in jac_sizes {
        let (st, b) = problem(d);
        let pc = Jacobi::from_diagonal(&st.diagonal()).unwrap();
        let mut ws = KrylovWorkspace::with_dim(b.len());
        let mut x = vec![0.0; b.len()];
        g.bench_function(format!("solve/{}", label(d)), |bch| {
            bch.iter(|| {
                x.fill(0.0);
                black_box(pcg(&st, &pc, &b, &mut x, &TOL, &mut ws).unwrap())
            })
        });
    }
    g.finish();

    // Setup, solve and one V-cycle, each on explicit rayon pools of 1 and 2
    // threads: ids `setup/256^2/1`, `solve/256^2/2`, ...
    let pools: Vec<(usize, rayon::ThreadPool)> = [1usize, 2]
        .into_iter()
        .map(|t| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .expect("thread pool");
            (t, pool)
        })
        .collect();
    let mut g = c.benchmark_group("pcg_multigrid");
    g.sample_size(10).measurement_time(Duration::from_secs(3));
    for d in mg_sizes {
        let (st, b) = problem(d);
        let o = MgOptions::default();
        for (threads, pool) in &pools {
            g.bench_with_input(
                BenchmarkId::new(format!("setup/{}", label(d)), threads),
                threads,
                |bch, _| pool.install(|| bch.iter(|| black_box(Multigrid::new(&st, &o).unwrap()))),
            );
            let mg = pool.install(|| Multigrid::new(&st, &o).unwrap());
            let mut ws = KrylovWorkspace::with_dim(b.len());
            let mut x = vec![0.0; b.len()];
            g.bench_with_input(
                BenchmarkId::new(format!("solve/{}", label(d)), threads),
                threads,
                |bch, _| {
                    pool.install(|| {
                        bch.iter(|| {
                            x.fill(0.0);
                            black_box(pcg(&st, &mg, &b, &mut x, &TOL, &mut ws).unwrap())
                        })
                    })
                },
            );
            let mut z = vec![0.0; b.len()];
            g.bench_with_input(
                BenchmarkId::new(format!("vcycle/{}", label(d)), threads),
                threads,
                |bch, _| {
                    pool.install(|| {
                        bch.iter(|| {
                            mg.apply(&b, &mut z);
                            black_box(z[0])
                        })
                    })
                },
            );
        }
    }
    g.finish();

    // Periodic boundaries (all axes), the same 1e3 inclusion: the
    // pressure operator of the periodic ICE vortex. Setup, `refresh` (what
    // the ICE step does when only the values change) and solve at 256²;
    // setup + solve together at 1024² (one row, to keep the bench short).
    let mut g = c.benchmark_group("pcg_multigrid_periodic");
    g.sample_size(10).measurement_time(Duration::from_secs(3));
    for d in [[256, 256, 1], [1024, 1024, 1]] {
        let st = from_field(d, &inclusion_field(d, 1e3), BoundaryKind::Periodic, 1e-6);
        let b = zero_mean_rhs(st.num_cells(), 42);
        let o = MgOptions::default();
        let mut ws = KrylovWorkspace::with_dim(b.len());
        let mut x = vec![0.0; b.len()];
        if d[0] >= 1024 {
            g.bench_function(format!("setup+solve/{}", label(d)), |bch| {
                bch.iter(|| {
                    let mg = Multigrid::new(&st, &o).unwrap();
                    x.fill(0.0);
                    black_box(pcg(&st, &mg, &b, &mut x, &TOL, &mut ws).unwrap())
                })
            });
            continue;
        }
        g.bench_function(format!("setup/{}", label(d)), |bch| {
            bch.iter(|| black_box(Multigrid::new(&st, &o).unwrap()))
        });
        let mut mg = Multigrid::new(&st, &o).unwrap();
        g.bench_function(format!("refresh/{}", label(d)), |bch| {
            bch.iter(|| {
                mg.refresh(&st).unwrap();
                black_box(mg.setup_s())
            })
        });
        g.bench_function(format!("solve/{}", label(d)), |bch| {
            bch.iter(|| {
                x.fill(0.0);
                black_box(pcg(&st, &mg, &b, &mut x, &TOL, &mut ws).unwrap())
            })
        });
    }
    g.finish();
}

criterion_group!(solver_benches, benches);
criterion_main!(solver_benches);
