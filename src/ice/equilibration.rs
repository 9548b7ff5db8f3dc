//! Equilibration pressure (Guilkey Eq. 13, Sec. 3.3 step 2).
//!
//! Per cell, find the pressure `p` with
//!
//! ```text
//! S(p) = Σ_r ρ̂_r v_r(p, T_r) = 1,     ρ̂_r = M_r / V,   v_r = 1/ρ_r(p, T_r)
//! ```
//!
//! (Guilkey Eqs. 11–13), then `v_r = v_r(p, T_r)` and `θ_r = ρ̂_r v_r`
//! (Eq. 12). Newton's method is applied to `φ(p) = 1/S(p) − 1`, which is
//! exactly linear in `p` for a single ideal or stiffened gas (one step
//! converges) and nearly linear for mixtures; it is safeguarded by bisection
//! on the bracket `[p_lo, p_hi]` with `S(p_lo) > 1 > S(p_hi)`.

use crate::material::eos::{EquationOfState, FluidEos};

use super::state::IceState;
use super::MAX_MATERIALS;

/// Settings of the equilibration iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EquilibrationSettings {
    /// Convergence tolerance on `|Σ_r θ_r − 1|`.
    pub tolerance: f64,
    /// Iteration cap.
    pub max_iterations: usize,
}

impl Default for EquilibrationSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-14,
            max_iterations: 100,
        }
    }
}

/// Why a cell's equilibration failed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EquilibrationFailure {
    /// Last `|S − 1|`.
    pub residual: f64,
    /// Iterations performed.
    pub iterations: usize,
    /// Last pressure iterate.
    pub pressure: f64,
}

/// Lowest admissible pressure of an EOS (exclusive), e.g. `−p_∞`
/// ([`FluidEos::min_pressure`]; Guilkey Fig. 1: the solid's threshold law
/// is defined for p > 0 only).
#[inline]
pub fn min_pressure(eos: &FluidEos) -> f64 {
    eos.min_pressure()
}

/// `S(p)` and `dS/dp`; `None` when some EOS has no density at `p`.
#[inline]
fn volume_sum(eos: &[FluidEos], rho_bulk: &[f64], temp: &[f64], p: f64) -> Option<(f64, f64)> {
    let mut s = 0.0;
    let mut ds = 0.0;
    for ((e, &rb), &t) in eos.iter().zip(rho_bulk).zip(temp) {
        let rho = e.density(p, t).ok()?;
        let v = 1.0 / rho;
        s += rb * v;
        // dv/dp = −v² / (∂p/∂ρ)_T
        ds -= rb * v * v / e.dp_drho(rho, t);
    }
    Some((s, ds))
}

/// Solves Guilkey Eq. 13 in one cell.
///
/// Inputs: per material the EOS, the bulk density `ρ̂_r = M_r/V` and the
/// temperature; `p_guess` (e.g. the previous step's value). Outputs: the
/// specific volumes `v_r` and volume fractions `θ_r` in `sp_vol` and
/// `vol_frac`; returns `(p, iterations)`.
///
/// # Errors
/// [`EquilibrationFailure`] when no admissible pressure satisfies Eq. 13
/// (e.g. a stiffened gas in tension) or the iteration does not converge.
pub fn equilibrate_cell(
    eos: &[FluidEos],
    rho_bulk: &[f64],
    temp: &[f64],
    p_guess: f64,
    settings: &EquilibrationSettings,
    sp_vol: &mut [f64],
    vol_frac: &mut [f64],
) -> Result<(f64, usize), EquilibrationFailure> {
    let nm = eos.len();
    debug_assert!(nm <= MAX_MATERIALS);
    let p_min = eos
        .iter()
        .map(min_pressure)
        .fold(f64::NEG_INFINITY, f64::max);
    let fail = |residual, iterations, pressure| EquilibrationFailure {
        residual,
        iterations,
        pressure,
    };
    let mut lo = p_min;
    let mut hi = f64::INFINITY;
    let mut p = if p_guess.is_finite() && p_guess > p_min {
        p_guess
    } else {
        p_min.abs().max(1.0)
    };
    let mut last_res = f64::NAN;
    for it in 1..=settings.max_iterations {
        let Some((s, ds)) = volume_sum(eos, rho_bulk, temp, p) else {
            return Err(fail(f64::NAN, it, p));
        };
        let res = s - 1.0;
        last_res = res.abs();
        if !res.is_finite() {
            return Err(fail(last_res, it, p));
        }
        if res.abs() <= settings.tolerance {
            for r in 0..nm {
                let rho = eos[r]
                    .density(p, temp[r])
                    .map_err(|_| fail(last_res, it, p))?;
                sp_vol[r] = 1.0 / rho;
                vol_frac[r] = rho_bulk[r] * sp_vol[r];
            }
            return Ok((p, it));
        }
        // S decreases with p: S > 1 means p is too low.
        if res > 0.0 {
            lo = p;
        } else {
            hi = p;
        }
        // Newton on φ(p) = 1/S − 1: φ' = −S'/S².
        let phi = 1.0 / s - 1.0;
        let dphi = -ds / (s * s);
        let mut p_new = p - phi / dphi;
        if !(p_new > lo && p_new < hi && p_new.is_finite()) {
            p_new = if hi.is_finite() {
                0.5 * (lo + hi)
            } else {
                // No upper bracket yet: grow geometrically from the lower one.
                lo + 2.0 * (p - lo).abs().max(1.0)
            };
        }
        if (p_new - p).abs() <= 4.0 * f64::EPSILON * p.abs() {
            // Stagnation at round-off: accept if close enough.
            if res.abs() <= 1e3 * settings.tolerance {
                for r in 0..nm {
                    let rho = eos[r]
                        .density(p, temp[r])
                        .map_err(|_| fail(last_res, it, p))?;
                    sp_vol[r] = 1.0 / rho;
                    vol_frac[r] = rho_bulk[r] * sp_vol[r];
                }
                return Ok((p, it));
            }
            return Err(fail(last_res, it, p));
        }
        p = p_new;
    }
    Err(fail(last_res, settings.max_iterations, p))
}

/// Largest of the materials' lowest admissible pressures ([`min_pressure`]).
pub(super) fn min_pressure_all<const D: usize>(state: &IceState<D>) -> f64 {
    state
        .materials
        .iter()
        .map(|m| min_pressure(&m.eos))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The pressure `p ∈ (p_min, p_eq)` at which the materials of cell `c`,
/// each following its EOS at its own temperature, fill the relative volume
/// change `dv = Δt Σ ∇·(θu*)` (> 0: net volume outflow, an expansion):
/// `Σ_r θ_r (v_r(p)/v_r(p_eq) − 1) = dv`, the balance that Guilkey Eq. 29
/// linearises. Bisection in `ln(p − p_min)`; `None` when no admissible
/// pressure satisfies it.
pub(super) fn expanded_pressure<const D: usize>(
    st: &IceState<D>,
    c: usize,
    dv: f64,
    p_min: f64,
) -> Option<f64> {
    let p_eq = st.p_eq[c];
    if !(dv > 0.0 && p_eq > p_min) {
        return None;
    }
    let excess = |p: f64| -> Option<f64> {
        let mut sum = 0.0;
        for (mat, mc) in st.materials.iter().zip(&st.cells) {
            let t = mc.temperature[c];
            let v0 = mc.sp_vol[c];
            let v = 1.0 / mat.eos.density(p, t).ok()?;
            sum += mc.vol_frac[c] * (v / v0 - 1.0);
        }
        Some(sum - dv)
    };
    // excess decreases with p; at p_eq it is −dv < 0.
    let (mut lo, mut hi) = ((1e-300f64).ln(), (p_eq - p_min).ln());
    let at = |s: f64| p_min + s.exp();
    if excess(at(lo)).is_none_or(|e| e < 0.0) {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        match excess(at(mid)) {
            Some(e) if e > 0.0 => lo = mid,
            Some(_) => hi = mid,
            None => lo = mid,
        }
        if hi - lo < 1e-12 {
            break;
        }
    }
    let p = at(hi);
    (p > p_min).then_some(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::eos::{IdealGas, StiffenedGas};

    #[test]
    fn single_ideal_gas_is_exact() {
        let eos = [FluidEos::from(IdealGas::new(1.4, 717.5).unwrap())];
        let t = [300.0];
        let rb = [1.2];
        let (mut v, mut th) = ([0.0], [0.0]);
        let (p, it) =
            equilibrate_cell(&eos, &rb, &t, 5e4, &Default::default(), &mut v, &mut th).unwrap();
        let exact = 0.4 * 1.2 * 717.5 * 300.0;
        assert!((p - exact).abs() <= 1e-14 * exact, "p = {p}");
        assert!(it <= 3, "{it} iterations");
        assert!((th[0] - 1.0).abs() <= 1e-14);
    }

    #[test]
    fn air_water_mixture_converges_to_1e14() {
        let air = FluidEos::from(IdealGas::new(1.4, 717.5).unwrap());
        let water = FluidEos::from(
            StiffenedGas::from_reference_state(4.4, 6e8, 1000.0, 1e5, 300.0).unwrap(),
        );
        let eos = [air, water];
        // 30 % air at 1.3 kg/m3, 70 % water at 1001 kg/m3, at different T.
        let rb = [0.3 * 1.3, 0.7 * 1001.0];
        let t = [350.0, 301.0];
        let (mut v, mut th) = ([0.0; 2], [0.0; 2]);
        for guess in [1e5, 1.0, 1e9, -1e7] {
            let (p, it) =
                equilibrate_cell(&eos, &rb, &t, guess, &Default::default(), &mut v, &mut th)
                    .unwrap();
            assert!(
                (th[0] + th[1] - 1.0).abs() <= 1e-14,
                "guess {guess}: {th:?}"
            );
            assert!(
                p > 0.0 && it < 60,
                "guess {guess}: p = {p}, {it} iterations"
            );
            for r in 0..2 {
                let pr = eos[r].pressure(1.0 / v[r], t[r]);
                assert!(
                    (pr - p).abs() <= 1e-8 * p.abs().max(1e5),
                    "material {r}: {pr} vs {p}"
                );
            }
        }
    }

    #[test]
    fn water_in_tension_fails_cleanly() {
        let water = FluidEos::from(
            StiffenedGas::from_reference_state(4.4, 6e8, 1000.0, 1e5, 300.0).unwrap(),
        );
        // Far too little mass to fill the cell at any admissible pressure.
        let (mut v, mut th) = ([0.0], [0.0]);
        let r = equilibrate_cell(
            &[water],
            &[100.0],
            &[300.0],
            1e5,
            &Default::default(),
            &mut v,
            &mut th,
        );
        assert!(r.is_err());
    }
}
