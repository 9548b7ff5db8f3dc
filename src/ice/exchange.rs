//! Pointwise-implicit momentum and heat exchange among the materials of a
//! cell or a face (Guilkey Eqs. 38–39; the same operation follows the face
//! velocities of Eq. 28).
//!
//! With the exchange force per unit volume `f_rs = K_rs θ_r θ_s (u_s − u_r)`
//! (Guilkey Sec. 2.1) and `ρ̂_r = θ_r / v_r`, the implicit update of
//! Guilkey Eq. 38 is
//!
//! ```text
//! u_r^L = u_r^{L−} + Σ_s β_rs (u_s^L − u_r^L),   β_rs = Δt K_rs θ_s v_r ,
//! ```
//!
//! i.e. the small dense system `(I + B) u^L = u^{L−}` with
//! `B_rr = Σ_{s≠r} β_rs`, `B_rs = −β_rs`. Heat (Guilkey Eq. 39) is the same
//! with `η_rs = Δt H_rs θ_s v_r / c_v,r` on the temperatures. Because
//! `M_r β_rs = V Δt K_rs θ_r θ_s` is symmetric, the exchange conserves
//! momentum (and `Σ M c_v T`). The system is solved by LU with partial
//! pivoting and the conserved mean is then restored exactly; with
//! `K = 1e15` the matrix is nearly singular only along the conserved
//! direction `(1, …, 1)`, which this projection fixes, so the solve is
//! stable for any `K`.

use nalgebra::SVector;

use super::{invalid, IceError, MAX_MATERIALS};

/// Exchange coefficients among the materials, row-major `N × N`,
/// symmetric, zero diagonal.
#[derive(Debug, Clone, PartialEq)]
pub struct ExchangeCoefficients {
    /// Momentum exchange coefficients `K_rs` (Guilkey Eq. 38).
    pub momentum: Vec<f64>,
    /// Heat exchange coefficients `H_rs` (Guilkey Eq. 39); all zero turns
    /// heat exchange off.
    pub heat: Vec<f64>,
}

impl ExchangeCoefficients {
    /// The same momentum coefficient `k` and heat coefficient `h` between
    /// every pair of `n` materials.
    pub fn uniform(n: usize, k: f64, h: f64) -> Self {
        let mut momentum = vec![k; n * n];
        let mut heat = vec![h; n * n];
        for r in 0..n {
            momentum[r * n + r] = 0.0;
            heat[r * n + r] = 0.0;
        }
        Self { momentum, heat }
    }

    /// Checks sizes, symmetry and signs for `n` materials.
    ///
    /// # Errors
    /// [`IceError::InvalidInput`] naming the offending coefficient.
    pub fn validate(&self, n: usize) -> Result<(), IceError> {
        for (name, a) in [
            ("exchange.momentum", &self.momentum),
            ("exchange.heat", &self.heat),
        ] {
            if a.len() != n * n {
                return Err(invalid(
                    name,
                    format!("needs {} entries, got {}", n * n, a.len()),
                ));
            }
            for r in 0..n {
                for s in 0..n {
                    let v = a[r * n + s];
                    if !(v.is_finite() && v >= 0.0) {
                        return Err(invalid(
                            format!("{name}[{r}][{s}]"),
                            format!("must be finite and >= 0, got {v}"),
                        ));
                    }
                    if v != a[s * n + r] {
                        return Err(invalid(format!("{name}[{r}][{s}]"), "must be symmetric"));
                    }
                }
            }
        }
        Ok(())
    }

    /// `true` when the heat coefficients are all zero.
    pub fn heat_off(&self) -> bool {
        self.heat.iter().all(|&h| h == 0.0)
    }
}

type Mat = [[f64; MAX_MATERIALS]; MAX_MATERIALS];

/// LU factorisation with partial pivoting of the leading `n × n` block, in
/// place; returns the row permutation.
fn lu(n: usize, a: &mut Mat) -> [usize; MAX_MATERIALS] {
    let mut perm = [0usize; MAX_MATERIALS];
    for (i, p) in perm.iter_mut().enumerate() {
        *p = i;
    }
    for k in 0..n {
        let mut piv = k;
        for i in k + 1..n {
            if a[i][k].abs() > a[piv][k].abs() {
                piv = i;
            }
        }
        if piv != k {
            a.swap(piv, k);
            perm.swap(piv, k);
        }
        let d = a[k][k];
        if d == 0.0 {
            continue;
        }
        for i in k + 1..n {
            let f = a[i][k] / d;
            a[i][k] = f;
            for j in k + 1..n {
                a[i][j] -= f * a[k][j];
            }
        }
    }
    perm
}

/// Solves with an LU from [`lu`]; `b` in, `x` out.
fn lu_solve(n: usize, a: &Mat, perm: &[usize; MAX_MATERIALS], b: &[f64], x: &mut [f64]) {
    for i in 0..n {
        let mut s = b[perm[i]];
        for j in 0..i {
            s -= a[i][j] * x[j];
        }
        x[i] = s;
    }
    for i in (0..n).rev() {
        let mut s = x[i];
        for j in i + 1..n {
            s -= a[i][j] * x[j];
        }
        x[i] = if a[i][i] != 0.0 { s / a[i][i] } else { 0.0 };
    }
}

/// Builds `I + B` from the rates `β_rs` (row-major, `n × n`).
fn system(n: usize, beta: impl Fn(usize, usize) -> f64) -> Mat {
    let mut a = [[0.0; MAX_MATERIALS]; MAX_MATERIALS];
    for r in 0..n {
        let mut diag = 1.0;
        for s in 0..n {
            if s != r {
                let b = beta(r, s);
                a[r][s] = -b;
                diag += b;
            }
        }
        a[r][r] = diag;
    }
    a
}

/// `(I + B) x = b` for two materials in closed form: with
/// `det = 1 + β₀₁ + β₁₀` and `d = (b₁ − b₀)/det`, `x₀ = b₀ + β₀₁ d` and
/// `x₁ = b₁ − β₁₀ d` (a weighted average of `b₀` and `b₁` for any β ≥ 0, so
/// stable at `K = 1e15`). The general path's LU gives the same to
/// round-off; this is the exchange of every two-material cell and face
/// without the pivot search and the triangular solves.
#[inline(always)]
fn solve_pair(b01: f64, b10: f64, b: [f64; 2]) -> [f64; 2] {
    let d = (b[1] - b[0]) / (1.0 + b01 + b10);
    [b[0] + b01 * d, b[1] - b10 * d]
}

/// Restores the conserved weighted sum `Σ w_r x_r = Σ w_r b_r`.
fn restore_mean(n: usize, w: &[f64], b: &[f64], x: &mut [f64]) {
    let mut wsum = 0.0;
    let mut target = 0.0;
    let mut got = 0.0;
    for r in 0..n {
        wsum += w[r];
        target += w[r] * b[r];
        got += w[r] * x[r];
    }
    if wsum > 0.0 {
        let shift = (target - got) / wsum;
        for xr in x.iter_mut().take(n) {
            *xr += shift;
        }
    }
}

/// Implicit momentum exchange (Guilkey Eq. 38) of `n` materials at one
/// point: `θ_r`, `v_r`, the conserved weights `w_r` (mass or bulk density),
/// velocities in place.
pub fn exchange_momentum<const D: usize>(
    k: &[f64],
    dt: f64,
    theta: &[f64],
    sp_vol: &[f64],
    weight: &[f64],
    vel: &mut [SVector<f64, D>],
) {
    exchange_momentum_fixed(k, dt, theta, sp_vol, weight, &[], vel);
}

/// [`exchange_momentum`] with some materials' velocities held fixed
/// (`fixed[r]`, a rigid material with a prescribed velocity; empty: none):
/// their rows become `u_r^L = u_r^{L−}`, so the others exchange with the
/// prescribed velocity (with `K = 1e15` they take it). Momentum is then not
/// conserved among the materials (the prescribed motion is an external
/// agent), so the conserved-mean projection is skipped.
pub fn exchange_momentum_fixed<const D: usize>(
    k: &[f64],
    dt: f64,
    theta: &[f64],
    sp_vol: &[f64],
    weight: &[f64],
    fixed: &[bool],
    vel: &mut [SVector<f64, D>],
) {
    let n = theta.len();
    if n < 2 {
        return;
    }
    let is_fixed = |r: usize| fixed.get(r).copied().unwrap_or(false);
    let beta = |r: usize, s: usize| {
        if is_fixed(r) {
            0.0
        } else {
            dt * k[r * n + s] * theta[s] * sp_vol[r]
        }
    };
    let any_fixed = (0..n).any(is_fixed);
    if n == 2 {
        let (b01, b10) = (beta(0, 1), beta(1, 0));
        for comp in 0..D {
            let b = [vel[0][comp], vel[1][comp]];
            let mut x = solve_pair(b01, b10, b);
            if !any_fixed {
                restore_mean(2, weight, &b, &mut x);
            }
            vel[0][comp] = x[0];
            vel[1][comp] = x[1];
        }
        return;
    }
    let mut a = system(n, beta);
    let perm = lu(n, &mut a);
    let mut b = [0.0; MAX_MATERIALS];
    let mut x = [0.0; MAX_MATERIALS];
    for comp in 0..D {
        for r in 0..n {
            b[r] = vel[r][comp];
        }
        lu_solve(n, &a, &perm, &b, &mut x);
        if !any_fixed {
            restore_mean(n, weight, &b, &mut x);
        }
        for r in 0..n {
            vel[r][comp] = x[r];
        }
    }
}

/// Implicit heat exchange (Guilkey Eq. 39) at one point: `θ_r`, `v_r`,
/// `c_v,r`, masses `M_r` (weights `M_r c_v,r` are conserved), temperatures
/// in place.
pub fn exchange_heat(
    h: &[f64],
    dt: f64,
    theta: &[f64],
    sp_vol: &[f64],
    cv: &[f64],
    mass: &[f64],
    temp: &mut [f64],
) {
    let n = theta.len();
    if n < 2 {
        return;
    }
    let eta = |r: usize, s: usize| dt * h[r * n + s] * theta[s] * sp_vol[r] / cv[r];
    let mut b = [0.0; MAX_MATERIALS];
    let mut x = [0.0; MAX_MATERIALS];
    let mut w = [0.0; MAX_MATERIALS];
    for r in 0..n {
        b[r] = temp[r];
        w[r] = mass[r] * cv[r];
    }
    if n == 2 {
        [x[0], x[1]] = solve_pair(eta(0, 1), eta(1, 0), [b[0], b[1]]);
    } else {
        let mut a = system(n, eta);
        let perm = lu(n, &mut a);
        lu_solve(n, &a, &perm, &b, &mut x);
    }
    restore_mean(n, &w[..n], &b, &mut x);
    temp[..n].copy_from_slice(&x[..n]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_k_equalises_velocities_and_conserves_momentum() {
        let n = 3;
        let ex = ExchangeCoefficients::uniform(n, 1e15, 0.0);
        let theta = [0.2, 0.5, 0.3];
        let sp_vol = [1.0 / 1.2, 1.0 / 8000.0, 1.0 / 0.17];
        let vol = 1e-3;
        let mass: Vec<f64> = (0..n).map(|r| theta[r] / sp_vol[r] * vol).collect();
        let mut vel = [
            SVector::<f64, 2>::new(10.0, -3.0),
            SVector::<f64, 2>::new(0.0, 1.0),
            SVector::<f64, 2>::new(-50.0, 7.0),
        ];
        let before: SVector<f64, 2> = (0..n).map(|r| vel[r] * mass[r]).sum();
        exchange_momentum(&ex.momentum, 1e-6, &theta, &sp_vol, &mass, &mut vel);
        let after: SVector<f64, 2> = (0..n).map(|r| vel[r] * mass[r]).sum();
        assert!((after - before).norm() <= 1e-14 * before.norm().max(1.0));
        let mean = before / mass.iter().sum::<f64>();
        for v in &vel {
            assert!((v - mean).norm() <= 1e-6 * mean.norm(), "{v} vs {mean}");
        }
    }

    #[test]
    fn moderate_k_matches_two_material_closed_form() {
        // Two materials: relative velocity decays by 1/(1 + β12 + β21).
        let k = [0.0, 1e3, 1e3, 0.0];
        let theta = [0.4, 0.6];
        let sp_vol = [1.0, 0.5];
        let mass = [0.4, 1.2];
        let dt = 1e-3;
        let mut vel = [SVector::<f64, 1>::new(1.0), SVector::<f64, 1>::new(0.0)];
        exchange_momentum(&k, dt, &theta, &sp_vol, &mass, &mut vel);
        let b12 = dt * 1e3 * theta[1] * sp_vol[0];
        let b21 = dt * 1e3 * theta[0] * sp_vol[1];
        let rel = 1.0 / (1.0 + b12 + b21);
        assert!((vel[0][0] - vel[1][0] - rel).abs() < 1e-14);
        assert!((0.4 * vel[0][0] + 1.2 * vel[1][0] - 0.4).abs() < 1e-15);
    }

    #[test]
    fn two_material_closed_form_matches_the_lu_solve() {
        // β over 30 decades, both orderings, and a fixed row.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..2000 {
            let b01 = 10f64.powf(-15.0 + 30.0 * rnd());
            let b10 = if rnd() < 0.1 {
                0.0
            } else {
                10f64.powf(-15.0 + 30.0 * rnd())
            };
            let b = [rnd() * 200.0 - 100.0, rnd() * 200.0 - 100.0];
            let x = solve_pair(b01, b10, b);
            let mut a = system(2, |r, _| if r == 0 { b01 } else { b10 });
            let perm = lu(2, &mut a);
            let mut y = [0.0; 2];
            lu_solve(2, &a, &perm, &b, &mut y);
            // The LU's own error grows with the condition number
            // (about 1 + β₀₁ + β₁₀); the closed form is a weighted mean.
            let scale = b[0].abs().max(b[1].abs());
            let cond = 1.0 + b01 + b10;
            for r in 0..2 {
                assert!(
                    (x[r] - y[r]).abs() <= 1e-14 * cond * scale,
                    "β ({b01:e}, {b10:e}), b {b:?}: closed form {x:?}, LU {y:?}"
                );
            }
            // The residual of (I + B) x = b.
            let r0 = (1.0 + b01) * x[0] - b01 * x[1] - b[0];
            let r1 = -b10 * x[0] + (1.0 + b10) * x[1] - b[1];
            let big = (1.0 + b01.max(b10)) * scale;
            assert!(r0.abs() <= 1e-13 * big && r1.abs() <= 1e-13 * big);
        }
    }

    #[test]
    fn heat_exchange_conserves_energy() {
        let h = [0.0, 1e12, 1e12, 0.0];
        let theta = [0.5, 0.5];
        let sp_vol = [1.0, 2.0];
        let cv = [717.5, 3116.0];
        let mass = [0.5, 0.25];
        let mut t = [300.0, 600.0];
        let e0 = mass[0] * cv[0] * t[0] + mass[1] * cv[1] * t[1];
        exchange_heat(&h, 1.0, &theta, &sp_vol, &cv, &mass, &mut t);
        let e1 = mass[0] * cv[0] * t[0] + mass[1] * cv[1] * t[1];
        assert!((e1 - e0).abs() <= 1e-14 * e0);
        assert!((t[0] - t[1]).abs() < 1e-6);
    }
}
