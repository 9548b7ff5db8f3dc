//! Scaling study: setup and solve times of Cholesky, PCG-Jacobi and
//! PCG-multigrid on the variable-coefficient cell-centred Poisson problem
//! (ball inclusion with coefficient 1e3 in a background of 1, all-Neumann
//! boundaries, diag_extra = 1e-6 x background face coefficient, zero-mean
//! pseudo-random right-hand side), solved to relative residual 1e-10 on one
//! thread (`--threads N`: a pool of N; the multigrid shares levels of 32k
//! cells and more between them, Cholesky and PCG-Jacobi stay serial).
//!
//! Every run that takes less than 3 s is repeated (3 times by default,
//! `--repeat N`) and the fastest run (by setup + solve) is reported, to
//! reduce the noise of a shared machine.
//!
//! Usage: `cargo run --release -p solvers --example scaling [-- --quick]`
//! Options: `--quick` (small sizes only), `--max-chol-cells-2d N` (default
//! 1100000), `--max-chol-cells-3d N` (default 300000: Cholesky takes ~30 s at
//! 64³ and would take minutes at 96³), `--max-jacobi-cells N` (default
//! 1000000: PCG-Jacobi at 1024² needs ~6500 iterations, > 60 s), `--only 2d|3d`,
//! `--mg-smooth N` (pre = post smoothing sweeps), `--omega W`, `--w-cycle`,
//! `--threads N` (default 1).

#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Instant;

use common::*;
use solvers::*;

#[derive(Clone, Copy)]
struct Row {
    method: &'static str,
    setup: f64,
    solve: f64,
    iters: usize,
    res: f64,
}

fn arg_value(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn problem(dims: [usize; 3]) -> (CellStencil, Vec<f64>) {
    let k = inclusion_field(dims, 1e3);
    let st = from_field(dims, &k, BoundaryKind::Neumann, 1e-6);
    let n = st.num_cells();
    let mut b = pseudo_random(n, 42);
    let mean = b.iter().sum::<f64>() / n as f64;
    b.iter_mut().for_each(|v| *v -= mean);
    (st, b)
}

fn run_cholesky(st: &CellStencil, b: &[f64]) -> Result<Row> {
    let t0 = Instant::now();
    let a = st.to_matrix()?;
    let mut chol = Cholesky::new(&a)?;
    let setup = t0.elapsed().as_secs_f64();
    let mut x = b.to_vec();
    let rep = chol.solve_in_place(&mut x)?;
    let res = rel_residual(st, b, &x);
    Ok(Row {
        method: "Cholesky",
        setup,
        solve: rep.solve_s,
        iters: 0,
        res,
    })
}

fn run_jacobi(st: &CellStencil, b: &[f64]) -> Result<Row> {
    let t0 = Instant::now();
    let pc = Jacobi::from_diagonal(&st.diagonal())?;
    let setup = t0.elapsed().as_secs_f64();
    let mut x = vec![0.0; b.len()];
    let mut ws = KrylovWorkspace::with_dim(b.len());
    let opts = KrylovOptions {
        rel_tol: 1e-10,
        max_iter: 50_000,
    };
    let rep = pcg(st, &pc, b, &mut x, &opts, &mut ws)?;
    Ok(Row {
        method: "PCG-Jacobi",
        setup,
        solve: rep.solve_s,
        iters: rep.iterations,
        res: rel_residual(st, b, &x),
    })
}

fn run_mg(st: &CellStencil, b: &[f64], o: &MgOptions, name: &'static str) -> Result<Row> {
    let t0 = Instant::now();
    let mg = Multigrid::new(st, o)?;
    let setup = t0.elapsed().as_secs_f64();
    let mut x = vec![0.0; b.len()];
    let mut ws = KrylovWorkspace::with_dim(b.len());
    let opts = KrylovOptions {
        rel_tol: 1e-10,
        max_iter: 500,
    };
    let rep = pcg(st, &mg, b, &mut x, &opts, &mut ws)?;
    Ok(Row {
        method: name,
        setup,
        solve: rep.solve_s,
        iters: rep.iterations,
        res: rel_residual(st, b, &x),
    })
}

fn run_mg_standalone(st: &CellStencil, b: &[f64], o: &MgOptions) -> Result<Row> {
    let t0 = Instant::now();
    let mg = Multigrid::new(st, o)?;
    let setup = t0.elapsed().as_secs_f64();
    let mut x = vec![0.0; b.len()];
    let opts = KrylovOptions {
        rel_tol: 1e-10,
        max_iter: 200,
    };
    let rep = mg.solve(b, &mut x, &opts)?;
    Ok(Row {
        method: "MG-standalone",
        setup,
        solve: rep.solve_s,
        iters: rep.iterations,
        res: rel_residual(st, b, &x),
    })
}

/// Least-squares slope of log(t) against log(n).
fn slope(pts: &[(f64, f64)]) -> f64 {
    let m = pts.len() as f64;
    let (sx, sy) = pts
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.0.ln(), a.1 + p.1.ln()));
    let (mx, my) = (sx / m, sy / m);
    let num: f64 = pts.iter().map(|p| (p.0.ln() - mx) * (p.1.ln() - my)).sum();
    let den: f64 = pts.iter().map(|p| (p.0.ln() - mx).powi(2)).sum();
    num / den
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let max_chol_2d: usize = arg_value("--max-chol-cells-2d")
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_100_000);
    let max_chol_3d: usize = arg_value("--max-chol-cells-3d")
        .and_then(|v| v.parse().ok())
        .unwrap_or(300_000);
    let max_jac: usize = arg_value("--max-jacobi-cells")
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let only = arg_value("--only").unwrap_or_default();
    let repeat: usize = arg_value("--repeat")
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let mut sizes: Vec<[usize; 3]> = if quick {
        vec![[128, 128, 1], [256, 256, 1], [32, 32, 32]]
    } else {
        vec![
            [32, 32, 1],
            [64, 64, 1],
            [128, 128, 1],
            [256, 256, 1],
            [512, 512, 1],
            [1024, 1024, 1],
            [16, 16, 16],
            [24, 24, 24],
            [32, 32, 32],
            [64, 64, 64],
            [96, 96, 96],
        ]
    };
    if only == "2d" {
        sizes.retain(|d| d[2] == 1);
    } else if only == "3d" {
        sizes.retain(|d| d[2] > 1);
    }
    // The multigrid shares its large levels between the pool's threads
    // (from 32k cells), so the pool is set explicitly: otherwise small
    // sizes ran on one thread and large ones on all, and the slope mixed
    // the two.
    let threads: usize = arg_value("--threads")
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .expect("the global rayon pool is set once, here");
    let mut mg_opts = MgOptions::default();
    if let Some(v) = arg_value("--mg-smooth").and_then(|v| v.parse().ok()) {
        mg_opts.pre_smooth = v;
        mg_opts.post_smooth = v;
    }
    if let Some(v) = arg_value("--omega").and_then(|v| v.parse().ok()) {
        mg_opts.omega = v;
    }
    if std::env::args().any(|a| a == "--w-cycle") {
        mg_opts.cycle = Cycle::W;
    }
    println!(
        "problem: ball inclusion k=1e3 in k=1, all-Neumann, diag_extra=1e-6*c, zero-mean random rhs, rel_tol 1e-10, {threads} thread(s)"
    );
    println!("multigrid: {mg_opts:?}");
    println!(
        "{:>14} {:>9} {:>15} {:>10} {:>10} {:>10} {:>7} {:>10}",
        "grid", "cells", "method", "setup_s", "solve_s", "total_s", "iters", "rel_res"
    );
    let mut results: Vec<([usize; 3], Row)> = Vec::new();
    for dims in sizes {
        let (st, b) = problem(dims);
        let n = st.num_cells();
        let name = if dims[2] > 1 {
            format!("{}^3", dims[0])
        } else {
            format!("{}^2", dims[0])
        };
        let best = |f: &dyn Fn() -> Result<Row>| -> Result<Row> {
            let mut r = f()?;
            let mut k = 1;
            while k < repeat && r.setup + r.solve < 3.0 {
                let r2 = f()?;
                if r2.setup + r2.solve < r.setup + r.solve {
                    r = r2;
                }
                k += 1;
            }
            Ok(r)
        };
        let mut rows: Vec<std::result::Result<Row, String>> = Vec::new();
        let max_chol = if dims[2] > 1 {
            max_chol_3d
        } else {
            max_chol_2d
        };
        if n <= max_chol {
            rows.push(best(&|| run_cholesky(&st, &b)).map_err(|e| format!("Cholesky: {e}")));
        } else {
            rows.push(Err(format!("Cholesky: skipped (> {max_chol} cells)")));
        }
        if n <= max_jac {
            rows.push(best(&|| run_jacobi(&st, &b)).map_err(|e| format!("PCG-Jacobi: {e}")));
        } else {
            rows.push(Err(format!("PCG-Jacobi: skipped (> {max_jac} cells)")));
        }
        rows.push(
            best(&|| run_mg(&st, &b, &mg_opts, "PCG-MG")).map_err(|e| format!("PCG-MG: {e}")),
        );
        rows.push(best(&|| run_mg_standalone(&st, &b, &mg_opts)).map_err(|e| format!("MG: {e}")));
        for r in rows {
            match r {
                Ok(r) => {
                    println!(
                        "{:>14} {:>9} {:>15} {:>10.4} {:>10.4} {:>10.4} {:>7} {:>10.2e}",
                        name,
                        n,
                        r.method,
                        r.setup,
                        r.solve,
                        r.setup + r.solve,
                        r.iters,
                        r.res
                    );
                    results.push((dims, r));
                }
                Err(e) => println!("{name:>14} {n:>9} {e}"),
            }
        }
    }
    println!();
    for (label, is3d) in [("2D", false), ("3D", true)] {
        for method in ["Cholesky", "PCG-Jacobi", "PCG-MG", "MG-standalone"] {
            let pts: Vec<(f64, f64)> = results
                .iter()
                .filter(|(d, r)| {
                    (d[2] > 1) == is3d && r.method == method && d[0] >= if is3d { 32 } else { 128 }
                })
                .map(|(d, r)| ((d[0] * d[1] * d[2]) as f64, r.setup + r.solve))
                .collect();
            if pts.len() >= 3 {
                let last = &pts[pts.len() - 2..];
                println!(
                    "{label} {method:>14}: slope between the two largest sizes = {:.2}",
                    slope(last)
                );
            }
            if pts.len() >= 2 {
                println!(
                    "{label} {method:>14}: log-log slope of total time vs N = {:.2} ({} sizes from {})",
                    slope(&pts),
                    pts.len(),
                    if is3d { "32^3" } else { "128^2" }
                );
            }
        }
        let mut crossover = None;
        for (d, r) in results
            .iter()
            .filter(|(d, r)| (d[2] > 1) == is3d && r.method == "PCG-MG")
        {
            if let Some((_, c)) = results
                .iter()
                .find(|(dd, rr)| dd == d && rr.method == "Cholesky")
            {
                if r.setup + r.solve < c.setup + c.solve && crossover.is_none() {
                    crossover = Some(*d);
                }
            }
        }
        match crossover {
            Some(d) => println!(
                "{label}: PCG-MG (setup+solve) first beats Cholesky (setup+solve) at {}x{}x{}",
                d[0], d[1], d[2]
            ),
            None => println!("{label}: no crossover among the sizes where both ran"),
        }
    }
}
