//! Face-centred quantities: the advective face velocities (Guilkey Eq. 28)
//! with their momentum exchange, and the face pressure (Guilkey Eq. 31).

use nalgebra::SVector;

use super::advection::{limited_slope, Limiter};
use super::exchange::exchange_momentum_fixed;
use super::par::{par_face_rows, Out};
use super::state::{CellLayout, MaterialCells};
use super::MAX_MATERIALS;

/// The MUSCL–Hancock half-step predictor of the face states of
/// [`face_velocities`].
#[derive(Debug, Clone, Copy)]
pub struct FacePredictor<'a> {
    /// The half step `τ = Δt/2`.
    pub tau: f64,
    /// Mixture bulk modulus `K = 1/Σ_s θ_s κ_s` per cell, ghosts included.
    pub bulk: &'a [f64],
    /// Whether the predicted velocity includes the convective term
    /// `u ∂u/∂x` (Eulerian face velocity) or not (Lagrangian).
    pub velocity_convection: bool,
}

/// Face velocities of one material normal to direction `d`
/// (Guilkey Eq. 28):
///
/// ```text
/// u*_f = (ρ̂_L u_L + ρ̂_R u_R)/(ρ̂_L + ρ̂_R)
///        − Δt (2 v_L v_R/(v_L + v_R)) (p_eq,R − p_eq,L)/Δx + Δt g_d
/// ```
///
/// with `ρ̂ = M/V` (so the cell masses are used directly), the normal
/// velocity component and the specific volumes `v` from the equilibration;
/// the face specific volume written `2 v_L v_R/(v_L + v_R)` is
/// [`face_specific_volume`], which equals it where the material fills both
/// cells.
///
/// With `reconstruct = Some(limiter)` the normal velocity and the pressure
/// on either side of the face are the limited linear reconstructions of the
/// left and right cells at the face (MUSCL), `u_L + σ_L/2`, `u_R − σ_R/2`,
/// `p_L + σ^p_L/2`, `p_R − σ^p_R/2`, instead of the cell values. The
/// `Δt`-proportional pressure term of Eq. 28 then acts on the jump of the
/// reconstructed pressures, which is `O(h²)` where `p` is smooth and the full
/// jump at a discontinuity (the way a MUSCL–Riemann scheme limits its
/// dissipation); a uniform state stays uniform. `None` is Eq. 28 as written.
///
/// With `predictor = Some(`[`FacePredictor`]`)` (needs `reconstruct`) the
/// reconstructed face states are advanced by the half step `τ = Δt/2`
/// with the primitive-variable equations of the normal direction and the
/// limited slopes of the cell (the MUSCL–Hancock predictor, van Leer 1984;
/// Toro, *Riemann Solvers*, Sec. 14.4):
///
/// ```text
/// u_L = u_l + σ^u_l/2 − (τ/h)(a u_l σ^u_l + v_l σ^p_l)
/// p_L = p_l + σ^p_l/2 − (τ/h)(u_l σ^p_l + K_l σ^u_l)
/// ```
///
/// (and the mirror image for the right cell), `K = 1/Σ_s θ_s κ_s` the
/// mixture bulk modulus of Guilkey Eq. 29 per cell. The pressure gradient
/// then enters the face velocity through the predicted states (so
/// `smooth_dt` should be zero); a uniform state stays uniform. With
/// `a = 1` (`velocity_convection`) the face velocity is the Eulerian one
/// at `(x_f, t + Δt/2)`; with `a = 0` it is the Lagrangian (material)
/// velocity of the face at `t + Δt/2`, the one that moves the faces of the
/// Lagrangian cells whose contents the advection remaps (see
/// [`super::IceParams::lagrangian_remap`]). The predicted pressures, which
/// only enter the jump (dissipation) term, keep their convective term.
///
/// With `acoustic = Some((λ, c))` the jump part is taken over the time
/// `λ_f h_d/(c_L + c_R)` (`c` the mixture sound speed per cell) instead of
/// `dt`: for equal states on both sides it is then `λ_f [p]/(2ρc)`, the
/// acoustic Riemann solver's velocity at `λ_f = 1`. The factor is switched
/// by the relative jump of the reconstructed pressures,
/// `λ_f = 1 − (1 − λ) min(1, |p_R − p_L|/(s p̄))` with
/// `p̄ = (p_l + p_r)/2` and `s = ` [`JUMP_SWITCH_SCALE`] (`1e-2`): `λ` at
/// discontinuities and large jumps, the Godunov value where the states
/// nearly agree (acoustic amplitudes). With `λ = 1/2` everywhere the
/// superbee face states of an acoustic wave were under-damped and the
/// wave converged at first order (0.96 at N = 512); the switch restores
/// order 1.96 and leaves Sod within 1 %.
#[allow(clippy::too_many_arguments)]
pub fn face_velocities<const D: usize>(
    layout: &CellLayout<D>,
    d: usize,
    mass: &[f64],
    velocity: &[SVector<f64, D>],
    sp_vol: &[f64],
    p_eq: &[f64],
    dt: f64,
    gravity_d: f64,
    reconstruct: Option<Limiter>,
    smooth_dt: f64,
    predictor: Option<FacePredictor<'_>>,
    acoustic: Option<(f64, &[f64])>,
    out: &mut [f64],
) {
    let s = layout.strides[d];
    let h = layout.h[d];
    let inv_h = 1.0 / h;
    let sh = Out::new(out);
    par_face_rows(layout, d, |row| {
        for f in row {
            let (l, r) = (f - s, f);
            let (ml, mr) = (mass[l], mass[r]);
            let msum = ml + mr;
            let (mut ul, mut ur) = (velocity[l][d], velocity[r][d]);
            let (mut pl, mut pr) = (p_eq[l], p_eq[r]);
            if let Some(lim) = reconstruct {
                let su_l = limited_slope(ul - velocity[l - s][d], ur - ul, lim);
                let su_r = limited_slope(ur - velocity[l][d], velocity[r + s][d] - ur, lim);
                let sp_l = limited_slope(pl - p_eq[l - s], pr - pl, lim);
                let sp_r = limited_slope(pr - p_eq[l], p_eq[r + s] - pr, lim);
                let (u0l, u0r) = (ul, ur);
                ul += 0.5 * su_l;
                ur -= 0.5 * su_r;
                pl += 0.5 * sp_l;
                pr -= 0.5 * sp_r;
                if let Some(FacePredictor {
                    tau,
                    bulk,
                    velocity_convection,
                }) = predictor
                {
                    let k = tau * inv_h;
                    let a = if velocity_convection { 1.0 } else { 0.0 };
                    ul -= k * (a * u0l * su_l + sp_vol[l] * sp_l);
                    ur -= k * (a * u0r * su_r + sp_vol[r] * sp_r);
                    pl -= k * (u0l * sp_l + bulk[l] * su_l);
                    pr -= k * (u0r * sp_r + bulk[r] * su_r);
                }
            }
            // The mass-weighted velocity and [`face_specific_volume`], with
            // one division.
            let (avg, v_face) = if msum > 0.0 {
                let inv = 1.0 / msum;
                (
                    (ml * ul + mr * ur) * inv,
                    (ml * sp_vol[l] + mr * sp_vol[r]) * inv,
                )
            } else {
                (0.5 * (ul + ur), harmonic_mean(sp_vol[l], sp_vol[r]))
            };
            // Jump part (dissipation) with `dt`, resolved part (the
            // reconstructed slopes, zero without reconstruction) with
            // `smooth_dt`.
            let jump = pr - pl;
            let resolved = (p_eq[r] - p_eq[l]) - jump;
            let jump_dt = match acoustic {
                Some((lambda, c)) if c[l] + c[r] > 0.0 => {
                    // λ at a pressure jump, the Godunov value 1 where the
                    // reconstructed states nearly agree.
                    let pm = 0.5 * (p_eq[l] + p_eq[r]);
                    let sw = if pm > 0.0 {
                        (jump.abs() / (JUMP_SWITCH_SCALE * pm)).min(1.0)
                    } else {
                        1.0
                    };
                    (1.0 - (1.0 - lambda) * sw) * h / (c[l] + c[r])
                }
                _ => dt,
            };
            let u = avg - v_face * (jump_dt * jump + smooth_dt * resolved) * inv_h + dt * gravity_d;
            // SAFETY: each face index is written by exactly one task.
            unsafe { sh.set(f, u) };
        }
    });
}

/// The face specific volume of one material between cells `L` and `R`
/// (masses `M`, specific volumes `v`), the `v_f` of Guilkey Eq. 28:
///
/// ```text
/// v_f = θ_f / ρ̂_f = (M_L v_L + M_R v_R)/(M_L + M_R),
/// θ_f = (θ_L + θ_R)/2,   ρ̂_f = (M_L + M_R)/(2V),
/// ```
///
/// the volume fraction per unit mass of the material in the staggered
/// control volume of the face (half of each cell). Its pressure
/// acceleration `−Δt v_f ∇p` is then the force `−θ_f A Δp` over the mass
/// `ρ̂_f V` of that volume, and the face exchange's conserved weights
/// `θ_f / v_f` are the masses `ρ̂_f`, so that stiff exchange gives the
/// mixture's `u* = ū − Δt (2/(ρ_L + ρ_R)) Δp/Δx` (`ρ` the mixture bulk
/// densities). Where one material fills both cells (`θ_L = θ_R = 1`) it is
/// the paper's harmonic mean `2 v_L v_R/(v_L + v_R)`. Where the volume
/// fraction jumps (a material interface) the harmonic mean is wrong: it
/// follows the smaller `v`, that of the trace of the material on the far
/// side, whose density is whatever its EOS gives at that cell's pressure
/// and temperature (water at an air cell's 7 K: 111 times its density),
/// and with `θ_f / v_f` as the weight that trace outweighed the material
/// filling the other cell (water–air shock tube: interface face velocity
/// 5.2 m/s instead of 287 m/s at step 0, a negative air temperature).
/// Both masses zero (no material on either side): the harmonic mean.
#[inline]
pub fn face_specific_volume(ml: f64, vl: f64, mr: f64, vr: f64) -> f64 {
    let msum = ml + mr;
    if msum > 0.0 {
        (ml * vl + mr * vr) / msum
    } else {
        harmonic_mean(vl, vr)
    }
}

/// `2 a b/(a + b)`: the face specific volume where neither cell holds the
/// material.
#[inline]
fn harmonic_mean(a: f64, b: f64) -> f64 {
    2.0 * a * b / (a + b)
}

/// Pointwise-implicit momentum exchange of the face velocities normal to
/// `d` among all materials (Guilkey Sec. 3.3 step 3, "done in the same
/// manner as step 10"): at each face `θ_f = (θ_L + θ_R)/2`,
/// `v_f` of [`face_specific_volume`] and the conserved weights `θ_f / v_f`
/// (the face masses).
///
/// `ustar[r][d]` holds material `r`'s face velocities normal to `d`. The
/// materials that `params` holds at a face
/// ([`super::params::HeldFaces`]: rigid ones, and held solids where
/// they fill both cells) keep their face velocity there; with
/// [`super::IceParams::rigid_faces_sharp`] a rigid material's `θ_f` is the
/// smaller of its two cells' instead of the mean.
pub fn face_exchange<const D: usize>(
    layout: &CellLayout<D>,
    d: usize,
    k: &[f64],
    dt: f64,
    cells: &[MaterialCells<D>],
    params: &super::IceParams<D>,
    ustar: &mut [[Vec<f64>; D]],
) {
    let hold = params.held_faces();
    let any_held = hold.any();
    let rigid = params.rigid_mask();
    let sharp_fixed = params.rigid_faces_sharp;
    let n = cells.len();
    let s = layout.strides[d];
    let mut outs = [Out::empty(); MAX_MATERIALS];
    for (o, us) in outs.iter_mut().zip(ustar.iter_mut()) {
        *o = Out::new(&mut us[d]);
    }
    par_face_rows(layout, d, |row| {
        let mut theta = [0.0; MAX_MATERIALS];
        let mut v = [0.0; MAX_MATERIALS];
        let mut w = [0.0; MAX_MATERIALS];
        let mut u = [SVector::<f64, 1>::zeros(); MAX_MATERIALS];
        let mut held = [false; MAX_MATERIALS];
        for f in row {
            let (l, r) = (f - s, f);
            for m in 0..n {
                let mc = &cells[m];
                held[m] = any_held && hold.at(m, &mc.vol_frac, l, r);
                theta[m] = if sharp_fixed && rigid[m] {
                    mc.vol_frac[l].min(mc.vol_frac[r])
                } else {
                    0.5 * (mc.vol_frac[l] + mc.vol_frac[r])
                };
                v[m] = face_specific_volume(mc.mass[l], mc.sp_vol[l], mc.mass[r], mc.sp_vol[r]);
                w[m] = theta[m] / v[m];
                // SAFETY: face f is read and written by this task only.
                u[m][0] = unsafe { outs[m].get(f) };
            }
            let fixed: &[bool] = if held[..n].contains(&true) {
                &held[..n]
            } else {
                &[]
            };
            exchange_momentum_fixed(k, dt, &theta[..n], &v[..n], &w[..n], fixed, &mut u[..n]);
            for m in 0..n {
                // SAFETY: as above.
                unsafe { outs[m].set(f, u[m][0]) };
            }
        }
    });
}

/// Face pressure normal to `d` (Guilkey Eq. 31),
/// `p* = (p_L/ρ_L + p_R/ρ_R)/(1/ρ_L + 1/ρ_R)` with the mixture bulk
/// densities `ρ = Σ_r M_r/V` (here the total masses; `V` cancels),
/// computed as `(p_L M_R + p_R M_L)/(M_L + M_R)` (one division, not three).
pub fn face_pressure<const D: usize>(
    layout: &CellLayout<D>,
    d: usize,
    p: &[f64],
    mix_mass: &[f64],
    out: &mut [f64],
) {
    let s = layout.strides[d];
    let o = Out::new(out);
    par_face_rows(layout, d, |row| {
        for f in row {
            let (l, r) = (f - s, f);
            let (ml, mr) = (mix_mass[l], mix_mass[r]);
            // SAFETY: each face is written by one task only.
            unsafe { o.set(f, (p[l] * mr + p[r] * ml) / (ml + mr)) };
        }
    });
}

/// Relative jump `|p_R − p_L|/p̄` of the reconstructed face pressures at
/// which the acoustic jump term of [`face_velocities`] takes its set `λ`;
/// below it `λ` tends linearly to the Godunov value 1.
pub const JUMP_SWITCH_SCALE: f64 = 1.0e-2;

/// Pressure shock sensor of the face between cells `l` and `r = l + s`
/// (Jameson, Schmidt & Turkel 1981, on the four cells `l−s, l, r, r+s`):
/// `|(p_{r+s} − p_r) − (p_l − p_{l−s})|/(p_{l−s} + p_l + p_r + p_{r+s})`,
/// the sum of the two cells' second differences over four times the mean
/// pressure: `O(h²)` where `p` is smooth, `O(1)` at a shock.
#[inline]
fn shock_sensor(p: &[f64], l: usize, r: usize, s: usize) -> f64 {
    let (pa, pb) = (p[l - s], p[r + s]);
    let den = pa + p[l] + p[r] + pb;
    if den > 0.0 {
        ((pb - p[r]) - (p[l] - pa)).abs() / den
    } else {
        0.0
    }
}

/// Value of the face shock sensor of [`face_viscosity`] at which the
/// viscosity is fully on (below it, it is scaled by `ψ/ψ_0`).
pub const SHOCK_SENSOR_SCALE: f64 = 0.01;

/// Linear artificial viscosity of the face pressures normal to `d`
/// (Guilkey Eq. 31, `pstar` updated in place): at every face where the
/// mixture normal velocities of the two cells are compressive
/// (`u_L > u_R`),
///
/// ```text
/// p*_f += μ Z_L Z_R/(Z_L + Z_R) (u_L − u_R),   Z = √(K ρ) = ρ c,
/// ```
///
/// the pressure term of the acoustic Riemann solver limited to
/// compression (a linear, Landshoff-type viscosity; the limited
/// reconstruction of the velocities instead was measured to lose its
/// benefit on Sod), scaled by `min(1, ψ/ψ_0)` with the pressure shock
/// sensor of Jameson, Schmidt & Turkel (1981, AIAA 81-1259) on the four
/// cells `l−1, l, r, r+1` of the face,
///
/// ```text
/// ψ = |(p_{r+1} − p_r) − (p_l − p_{l−1})| / (p_{l−1} + p_l + p_r + p_{r+1}),
/// ```
///
/// (the sum of the two cells' second differences), `O(h²)` where `p` is
/// smooth and `O(1)` at a shock, and `ψ_0 = ` [`SHOCK_SENSOR_SCALE`]: a
/// smooth compression sees an `O(h³)` viscosity instead of `O(h)`. `p` is
/// the equilibration pressure (ghosts filled). `bulk` is
/// `K = 1/Σ θ κ` and `mix_mass` the mixture mass `ρ V` per cell (ghosts
/// included); the mixture velocity is the mass-weighted mean of the
/// materials' (ghosts filled).
#[allow(clippy::too_many_arguments)]
pub fn face_viscosity<const D: usize>(
    layout: &CellLayout<D>,
    d: usize,
    cells: &[MaterialCells<D>],
    mix_mass: &[f64],
    bulk: &[f64],
    p: &[f64],
    mu: f64,
    pstar: &mut [f64],
) {
    let s = layout.strides[d];
    let inv_vol = 1.0 / layout.cell_volume();
    let o = Out::new(pstar);
    // Mixture normal velocity of cell `i`.
    let vel = |i: usize| -> f64 {
        if let [mc] = cells {
            return mc.velocity[i][d];
        }
        let m = mix_mass[i];
        if m > 0.0 {
            cells
                .iter()
                .map(|mc| mc.mass[i] * mc.velocity[i][d])
                .sum::<f64>()
                / m
        } else {
            0.0
        }
    };
    par_face_rows(layout, d, |row| {
        for f in row {
            let (l, r) = (f - s, f);
            let compression = vel(l) - vel(r);
            let psi = shock_sensor(p, l, r, s);
            let compression = compression * (psi / SHOCK_SENSOR_SCALE).min(1.0);
            if compression > 0.0 {
                let zl = (bulk[l] * mix_mass[l] * inv_vol).sqrt();
                let zr = (bulk[r] * mix_mass[r] * inv_vol).sqrt();
                if zl + zr > 0.0 {
                    // SAFETY: each face is read and written by one task only.
                    unsafe { o.set(f, o.get(f) + mu * zl * zr / (zl + zr) * compression) };
                }
            }
        }
    });
}
