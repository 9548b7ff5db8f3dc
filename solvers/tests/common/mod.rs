//! Shared problem generators for tests, benches and examples (no physics:
//! just coefficient fields on structured grids).
#![allow(dead_code)]

use solvers::{BoundaryKind, CellStencil};

/// Deterministic pseudo-random numbers in [-1, 1) (64-bit LCG).
pub fn pseudo_random(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        })
        .collect()
}

/// Face-coefficient scale `h^(d-2)` for the unit square / cube with `n`
/// cells along x (so that coefficients mimic a finite-volume Laplacian).
pub fn scale(dims: [usize; 3]) -> f64 {
    if dims[2] > 1 {
        1.0 / dims[0] as f64
    } else {
        1.0
    }
}

/// Constant-coefficient Laplacian with the same boundary kind everywhere.
pub fn poisson(dims: [usize; 3], bc: BoundaryKind, diag_extra: f64) -> CellStencil {
    let mut s = CellStencil::uniform(dims, scale(dims), 0.0, bc).unwrap();
    let d = diag_extra * scale(dims);
    s.diag_extra_mut().iter_mut().for_each(|v| *v = d);
    s
}

fn centre(dims: [usize; 3], c: [usize; 3]) -> [f64; 3] {
    let mut x = [0.5; 3];
    for a in 0..3 {
        if dims[a] > 1 {
            x[a] = (c[a] as f64 + 0.5) / dims[a] as f64;
        }
    }
    x
}

/// Cell field: `inside` in a ball of radius 0.25 centred in the unit box,
/// 1 outside.
pub fn inclusion_field(dims: [usize; 3], inside: f64) -> Vec<f64> {
    let mut k = Vec::with_capacity(dims.iter().product());
    for kk in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let x = centre(dims, [i, j, kk]);
                let r2: f64 = x.iter().map(|v| (v - 0.5) * (v - 0.5)).sum();
                k.push(if r2 < 0.0625 { inside } else { 1.0 });
            }
        }
    }
    k
}

/// Cell field: checkerboard of `blocks` blocks per axis alternating 1 and
/// `ratio`.
pub fn checkerboard_field(dims: [usize; 3], blocks: usize, ratio: f64) -> Vec<f64> {
    let mut k = Vec::with_capacity(dims.iter().product());
    for kk in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let x = centre(dims, [i, j, kk]);
                let mut par = 0usize;
                for a in 0..3 {
                    if dims[a] > 1 {
                        par += (x[a] * blocks as f64) as usize;
                    }
                }
                k.push(if par & 1 == 0 { 1.0 } else { ratio });
            }
        }
    }
    k
}

/// Variable-coefficient stencil from a cell field with harmonic face
/// averages; `diag_extra = extra_rel · scale` in every cell.
pub fn from_field(dims: [usize; 3], k: &[f64], bc: BoundaryKind, extra_rel: f64) -> CellStencil {
    let mut s = CellStencil::from_cell_field(dims, k, scale(dims), bc).unwrap();
    let d = extra_rel * scale(dims);
    s.diag_extra_mut().iter_mut().for_each(|v| *v = d);
    s
}

/// Relative residual `||b - A x|| / ||b||` for any operator.
pub fn rel_residual(a: &dyn solvers::LinearOperator, b: &[f64], x: &[f64]) -> f64 {
    let mut ax = vec![0.0; b.len()];
    a.apply(x, &mut ax);
    let r: f64 = b
        .iter()
        .zip(&ax)
        .map(|(b, a)| (b - a) * (b - a))
        .sum::<f64>()
        .sqrt();
    let nb: f64 = b.iter().map(|v| v * v).sum::<f64>().sqrt();
    r / nb
}

/// Relative 2-norm difference `||x - y|| / ||y||`.
pub fn rel_diff(x: &[f64], y: &[f64]) -> f64 {
    let d: f64 = x
        .iter()
        .zip(y)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt();
    let n: f64 = y.iter().map(|v| v * v).sum::<f64>().sqrt();
    d / n
}

/// Asymptotic convergence factor of the stationary multigrid iteration
/// (zero-mean random rhs, random initial guess): geometric mean of the ratios of
/// successive residual norms, skipping the first `skip` cycles and stopping
/// at relative residual 1e-10 (safely above the round-off floor, ~1e-12 for
/// 1e3 jumps) or after `max_cycles`.
pub fn mg_factor(mg: &solvers::Multigrid, n: usize, skip: usize, max_cycles: usize) -> f64 {
    let b = zero_mean_rhs(n, 7);
    let mut x = pseudo_random(n, 11);
    let mut hist = Vec::new();
    let opts = solvers::KrylovOptions {
        rel_tol: 1e-10,
        max_iter: max_cycles,
    };
    let _ = mg.solve_with_history(&b, &mut x, &opts, &mut hist);
    let m = hist.len() - 1;
    let s = skip.min(m.saturating_sub(1));
    (hist[m] / hist[s]).powf(1.0 / (m - s) as f64)
}

/// Non-symmetric upwind convection–diffusion matrix on an `nx × ny` grid
/// (Dirichlet Laplacian plus velocity `v` along +x and `v/2` along +y).
pub fn convection_diffusion(nx: usize, ny: usize, v: f64) -> solvers::SparseColMat<usize, f64> {
    let st = CellStencil::uniform([nx, ny, 1], 1.0, 0.0, BoundaryKind::Dirichlet).unwrap();
    let (mut r, mut c, mut val) = st.to_triplets();
    let h = 1.0 / nx as f64;
    for j in 0..ny {
        for i in 0..nx {
            let p = i + nx * j;
            r.push(p);
            c.push(p);
            val.push(v * h + 0.5 * v * h);
            if i > 0 {
                r.push(p);
                c.push(p - 1);
                val.push(-v * h);
            }
            if j > 0 {
                r.push(p);
                c.push(p - nx);
                val.push(-0.5 * v * h);
            }
        }
    }
    solvers::Assembler::from_triplets(nx * ny, nx * ny, &r, &c, &val)
        .unwrap()
        .into_matrix()
}

/// Pseudo-random right-hand side with zero mean. With all-Neumann boundaries
/// and a tiny `diag_extra` a non-zero mean makes the solution's constant
/// component ~ mean/diag_extra, and the attainable relative residual in f64
/// is then limited to ~1e-10 whatever the solver.
pub fn zero_mean_rhs(n: usize, seed: u64) -> Vec<f64> {
    let mut b = pseudo_random(n, seed);
    let m = b.iter().sum::<f64>() / n as f64;
    b.iter_mut().for_each(|v| *v -= m);
    b
}
