//! Face-centred quantities: the advective face velocities (Guilkey Eq. 28)
//! with their momentum exchange, and the face pressure (Guilkey Eq. 31).

use nalgebra::SVector;

use super::exchange::exchange_momentum;
use super::state::{CellLayout, MaterialCells};
use super::MAX_MATERIALS;

/// Face velocities of one material normal to direction `d`
/// (Guilkey Eq. 28):
///
/// ```text
/// u*_f = (ρ̂_L u_L + ρ̂_R u_R)/(ρ̂_L + ρ̂_R)
///        − Δt (2 v_L v_R/(v_L + v_R)) (p_eq,R − p_eq,L)/Δx + Δt g_d
/// ```
///
/// with `ρ̂ = M/V` (so the cell masses are used directly), the normal
/// velocity component and the specific volumes `v` from the equilibration.
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
    out: &mut [f64],
) {
    let s = layout.strides[d];
    let inv_h = 1.0 / layout.h[d];
    for &f in &layout.faces[d] {
        let (l, r) = (f - s, f);
        let (ml, mr) = (mass[l], mass[r]);
        let msum = ml + mr;
        let avg = if msum > 0.0 {
            (ml * velocity[l][d] + mr * velocity[r][d]) / msum
        } else {
            0.5 * (velocity[l][d] + velocity[r][d])
        };
        let (vl, vr) = (sp_vol[l], sp_vol[r]);
        let v_face = 2.0 * vl * vr / (vl + vr);
        out[f] = avg - dt * v_face * (p_eq[r] - p_eq[l]) * inv_h + dt * gravity_d;
    }
}

/// Pointwise-implicit momentum exchange of the face velocities normal to
/// `d` among all materials (Guilkey Sec. 3.3 step 3, "done in the same
/// manner as step 10"): at each face `θ_f = (θ_L + θ_R)/2`,
/// `v_f = 2 v_L v_R/(v_L + v_R)` and the conserved weights `θ_f / v_f`.
///
/// `ustar[r][d]` holds material `r`'s face velocities normal to `d`.
pub fn face_exchange<const D: usize>(
    layout: &CellLayout<D>,
    d: usize,
    k: &[f64],
    dt: f64,
    cells: &[MaterialCells<D>],
    ustar: &mut [[Vec<f64>; D]],
) {
    let n = cells.len();
    let s = layout.strides[d];
    let mut theta = [0.0; MAX_MATERIALS];
    let mut v = [0.0; MAX_MATERIALS];
    let mut w = [0.0; MAX_MATERIALS];
    let mut u = [SVector::<f64, 1>::zeros(); MAX_MATERIALS];
    for &f in &layout.faces[d] {
        let (l, r) = (f - s, f);
        for m in 0..n {
            let mc = &cells[m];
            theta[m] = 0.5 * (mc.vol_frac[l] + mc.vol_frac[r]);
            let (vl, vr) = (mc.sp_vol[l], mc.sp_vol[r]);
            v[m] = 2.0 * vl * vr / (vl + vr);
            w[m] = theta[m] / v[m];
            u[m][0] = ustar[m][d][f];
        }
        exchange_momentum(k, dt, &theta[..n], &v[..n], &w[..n], &mut u[..n]);
        for m in 0..n {
            ustar[m][d][f] = u[m][0];
        }
    }
}

/// Face pressure normal to `d` (Guilkey Eq. 31),
/// `p* = (p_L/ρ_L + p_R/ρ_R)/(1/ρ_L + 1/ρ_R)` with the mixture bulk
/// densities `ρ = Σ_r M_r/V` (here the total masses; `V` cancels).
pub fn face_pressure<const D: usize>(
    layout: &CellLayout<D>,
    d: usize,
    p: &[f64],
    mix_mass: &[f64],
    out: &mut [f64],
) {
    let s = layout.strides[d];
    for &f in &layout.faces[d] {
        let (l, r) = (f - s, f);
        let (il, ir) = (1.0 / mix_mass[l], 1.0 / mix_mass[r]);
        out[f] = (p[l] * il + p[r] * ir) / (il + ir);
    }
}
