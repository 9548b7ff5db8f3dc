//! Preconditioned Krylov methods: conjugate gradients (SPD) and BiCGStab
//! (general), with caller-owned workspaces so that repeated solves do not
//! allocate.

use std::time::Instant;

use crate::error::{check_len, is_pos, Result, SolveReport, SolverError};
use crate::operator::{LinearOperator, Preconditioner};

/// Stopping criteria for Krylov and multigrid iterations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KrylovOptions {
    /// Target relative residual `||b - A x|| / ||b||`.
    pub rel_tol: f64,
    /// Maximum number of iterations.
    pub max_iter: usize,
}

impl Default for KrylovOptions {
    fn default() -> Self {
        Self {
            rel_tol: 1e-10,
            max_iter: 1000,
        }
    }
}

/// Caller-owned scratch vectors for [`pcg`] and [`bicgstab`]. Vectors are
/// (re)sized on first use for a given dimension and reused afterwards.
#[derive(Debug, Clone, Default)]
pub struct KrylovWorkspace {
    v: Vec<Vec<f64>>,
}

impl KrylovWorkspace {
    /// Empty workspace (sized lazily).
    pub fn new() -> Self {
        Self::default()
    }

    /// Workspace preallocated for dimension `n` (enough for both methods).
    pub fn with_dim(n: usize) -> Self {
        let mut w = Self::new();
        w.ensure(n, 8);
        w
    }

    fn ensure(&mut self, n: usize, count: usize) {
        if self.v.len() < count {
            self.v.resize_with(count, Vec::new);
        }
        for v in &mut self.v {
            if v.len() != n {
                v.resize(n, 0.0);
            }
        }
    }
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    // Four partial sums: deterministic and vectorisable.
    let mut s = [0.0f64; 4];
    let ca = a.chunks_exact(4);
    let cb = b.chunks_exact(4);
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        s[0] += x[0] * y[0];
        s[1] += x[1] * y[1];
        s[2] += x[2] * y[2];
        s[3] += x[3] * y[3];
    }
    let mut t = (s[0] + s[1]) + (s[2] + s[3]);
    for (x, y) in ra.iter().zip(rb) {
        t += x * y;
    }
    t
}

#[inline]
fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// `r = b - A x`, returns `||r||`.
fn residual<A: LinearOperator + ?Sized>(a: &A, b: &[f64], x: &[f64], r: &mut [f64]) -> f64 {
    a.apply(x, r);
    for (ri, bi) in r.iter_mut().zip(b) {
        *ri = bi - *ri;
    }
    norm(r)
}

fn check_dims<A: LinearOperator + ?Sized>(a: &A, b: &[f64], x: &[f64]) -> Result<usize> {
    let n = a.dim();
    check_len(n, b.len())?;
    check_len(n, x.len())?;
    Ok(n)
}

fn breakdown(iteration: usize, what: &str) -> SolverError {
    SolverError::Breakdown {
        iteration,
        what: what.to_string(),
    }
}

/// Preconditioned conjugate gradients for a symmetric positive definite
/// operator and a symmetric positive definite preconditioner.
///
/// `x` holds the initial guess on entry and the solution on exit (the last
/// iterate if an error is returned). Convergence is declared on the **true**
/// residual: when the recursively updated residual reaches the tolerance the
/// true residual is recomputed and, if it is not yet small enough, the
/// iteration restarts from it (residual replacement). `b = 0` gives `x = 0`
/// with 0 iterations.
pub fn pcg<A, P>(
    a: &A,
    pc: &P,
    b: &[f64],
    x: &mut [f64],
    opts: &KrylovOptions,
    ws: &mut KrylovWorkspace,
) -> Result<SolveReport>
where
    A: LinearOperator + ?Sized,
    P: Preconditioner + ?Sized,
{
    let t0 = Instant::now();
    let n = check_dims(a, b, x)?;
    ws.ensure(n, 4);
    let [r, z, p, q] = match &mut ws.v[..4] {
        [r, z, p, q] => [r, z, p, q],
        _ => unreachable!(),
    };
    let report = |iterations: usize, rel: f64| SolveReport {
        iterations,
        rel_residual: rel,
        setup_s: 0.0,
        solve_s: t0.elapsed().as_secs_f64(),
    };
    let Some(bnorm) = rhs_norm(b, x)? else {
        return Ok(report(0, 0.0));
    };
    let tol = opts.rel_tol * bnorm;
    let mut rnorm = residual(a, b, x, r);
    if !rnorm.is_finite() {
        return Err(breakdown(0, "initial residual is not finite"));
    }
    if rnorm <= tol {
        return Ok(report(0, rnorm / bnorm));
    }
    pc.apply(r, z);
    let mut rz = dot(r, z);
    if !is_pos(rz) {
        return Err(breakdown(
            0,
            "preconditioner not positive definite (r.z <= 0)",
        ));
    }
    p.copy_from_slice(z);
    for it in 1..=opts.max_iter {
        a.apply(p, q);
        let pq = dot(p, q);
        if !is_pos(pq) {
            return Err(breakdown(it, "operator not positive definite (p.Ap <= 0)"));
        }
        let alpha = rz / pq;
        let mut rr = 0.0;
        for i in 0..n {
            x[i] += alpha * p[i];
            let ri = r[i] - alpha * q[i];
            r[i] = ri;
            rr += ri * ri;
        }
        rnorm = rr.sqrt();
        if !rnorm.is_finite() {
            return Err(breakdown(it, "residual is not finite"));
        }
        if rnorm <= tol {
            rnorm = residual(a, b, x, r);
            if rnorm <= tol {
                return Ok(report(it, rnorm / bnorm));
            }
            // Residual replacement: restart from the true residual.
            pc.apply(r, z);
            rz = dot(r, z);
            if !is_pos(rz) {
                return Err(breakdown(
                    it,
                    "preconditioner not positive definite (r.z <= 0)",
                ));
            }
            p.copy_from_slice(z);
            continue;
        }
        pc.apply(r, z);
        let rz_new = dot(r, z);
        if !is_pos(rz_new) {
            return Err(breakdown(
                it,
                "preconditioner not positive definite (r.z <= 0)",
            ));
        }
        let beta = rz_new / rz;
        rz = rz_new;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    let rel = residual(a, b, x, r) / bnorm;
    Err(SolverError::NotConverged {
        iterations: opts.max_iter,
        rel_residual: rel,
    })
}

/// Right-preconditioned BiCGStab for general (non-symmetric) operators.
///
/// Same conventions as [`pcg`]: `x` is the initial guess / solution, the
/// true residual decides convergence, `b = 0` gives `x = 0`. One iteration
/// costs two operator and two preconditioner applications. On a
/// `(r_hat, r) = 0` breakdown the shadow residual is reset once to the
/// current residual before a [`SolverError::Breakdown`] is reported.
pub fn bicgstab<A, P>(
    a: &A,
    pc: &P,
    b: &[f64],
    x: &mut [f64],
    opts: &KrylovOptions,
    ws: &mut KrylovWorkspace,
) -> Result<SolveReport>
where
    A: LinearOperator + ?Sized,
    P: Preconditioner + ?Sized,
{
    let t0 = Instant::now();
    let n = check_dims(a, b, x)?;
    ws.ensure(n, 8);
    let [r, rhat, p, v, y, s, zz, t] = match &mut ws.v[..8] {
        [r, rhat, p, v, y, s, zz, t] => [r, rhat, p, v, y, s, zz, t],
        _ => unreachable!(),
    };
    let report = |iterations: usize, rel: f64| SolveReport {
        iterations,
        rel_residual: rel,
        setup_s: 0.0,
        solve_s: t0.elapsed().as_secs_f64(),
    };
    let Some(bnorm) = rhs_norm(b, x)? else {
        return Ok(report(0, 0.0));
    };
    let tol = opts.rel_tol * bnorm;
    let rnorm0 = residual(a, b, x, r);
    if !rnorm0.is_finite() {
        return Err(breakdown(0, "initial residual is not finite"));
    }
    if rnorm0 <= tol {
        return Ok(report(0, rnorm0 / bnorm));
    }
    rhat.copy_from_slice(r);
    p.fill(0.0);
    v.fill(0.0);
    let (mut rho, mut alpha, mut omega) = (1.0f64, 1.0f64, 1.0f64);
    let mut fresh = true;
    let mut resets = 0usize;
    let mut it = 0usize;
    while it < opts.max_iter {
        it += 1;
        let mut rho_new = dot(rhat, r);
        if rho_new.abs() <= 1e-30 * norm(rhat) * norm(r) || !rho_new.is_finite() {
            if resets >= 1 || !rho_new.is_finite() {
                return Err(breakdown(it, "rho = (r_hat, r) vanished"));
            }
            resets += 1;
            rhat.copy_from_slice(r);
            rho_new = dot(rhat, r);
            fresh = true;
        }
        if fresh {
            p.copy_from_slice(r);
            fresh = false;
        } else {
            let beta = (rho_new / rho) * (alpha / omega);
            for i in 0..n {
                p[i] = r[i] + beta * (p[i] - omega * v[i]);
            }
        }
        rho = rho_new;
        pc.apply(p, y);
        a.apply(y, v);
        let rv = dot(rhat, v);
        if rv == 0.0 || !rv.is_finite() {
            return Err(breakdown(it, "(r_hat, A M^-1 p) vanished"));
        }
        alpha = rho / rv;
        let mut ss = 0.0;
        for i in 0..n {
            let si = r[i] - alpha * v[i];
            s[i] = si;
            ss += si * si;
        }
        if ss.sqrt() <= tol {
            for i in 0..n {
                x[i] += alpha * y[i];
            }
            let rn = residual(a, b, x, r);
            if rn <= tol {
                return Ok(report(it, rn / bnorm));
            }
            rhat.copy_from_slice(r);
            (rho, alpha, omega) = (1.0, 1.0, 1.0);
            fresh = true;
            continue;
        }
        pc.apply(s, zz);
        a.apply(zz, t);
        let tt = dot(t, t);
        if !is_pos(tt) {
            return Err(breakdown(it, "||A M^-1 s|| vanished"));
        }
        omega = dot(t, s) / tt;
        let mut rr = 0.0;
        for i in 0..n {
            x[i] += alpha * y[i] + omega * zz[i];
            let ri = s[i] - omega * t[i];
            r[i] = ri;
            rr += ri * ri;
        }
        let rn = rr.sqrt();
        if !rn.is_finite() {
            return Err(breakdown(it, "residual is not finite"));
        }
        if rn <= tol {
            let rn_true = residual(a, b, x, r);
            if rn_true <= tol {
                return Ok(report(it, rn_true / bnorm));
            }
            rhat.copy_from_slice(r);
            (rho, alpha, omega) = (1.0, 1.0, 1.0);
            fresh = true;
            continue;
        }
        if omega == 0.0 {
            return Err(breakdown(it, "omega vanished (stagnation)"));
        }
    }
    let rel = residual(a, b, x, r) / bnorm;
    Err(SolverError::NotConverged {
        iterations: opts.max_iter,
        rel_residual: rel,
    })
}

/// ‖b‖ for a Krylov solve: an error for a non-finite right-hand side, and
/// `None` (with `x = 0`, the exact solution) for b = 0.
fn rhs_norm(b: &[f64], x: &mut [f64]) -> Result<Option<f64>> {
    let bnorm = norm(b);
    if !bnorm.is_finite() {
        return Err(SolverError::invalid("right-hand side is not finite"));
    }
    if bnorm == 0.0 {
        x.fill(0.0);
        return Ok(None);
    }
    Ok(Some(bnorm))
}
