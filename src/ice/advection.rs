//! Advection of the fluid materials (Guilkey Sec. 3.3 step 12): mass,
//! momentum, internal energy and material volume, with compatible fluxes.
//!
//! Across a face normal to `d` with face velocity `u*` the swept volume per
//! cell volume is `u* Δt / h_d`, taken from the donor (upwind) cell. The
//! mass flux is `F_M = (u* Δt / h_d) M_f` with `M_f` the donor mass
//! reconstructed at the centroid of the swept region; every other quantity
//! `q = M φ` is fluxed as `F_q = F_M φ_f` with the *specific* quantity `φ`
//! (velocity, `e = c_v T`, `v`) reconstructed the same way ("compatible"
//! fluxes): a uniform `φ` stays exactly uniform, so a material interface
//! moving at uniform velocity and pressure keeps both.
//!
//! Reconstruction: first order `φ_f = φ_donor`; second order
//! `φ_f = φ_donor ± ½ (1 − ν) σ`, `ν = |u*| Δt / h_d`, with the limited slope
//! `σ` per cell (van Leer or monotonised central), the centroid of the
//! swept region — second order in space and time for linear advection.

use nalgebra::SVector;

use super::par::{par_face_rows, Out};
use super::state::CellLayout;

/// Slope limiter of the second-order reconstruction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Limiter {
    /// van Leer's harmonic limiter `2ab/(a + b)` for `ab > 0`.
    VanLeer,
    /// Monotonised central: `minmod(2a, (a + b)/2, 2b)`.
    MonotonizedCentral,
    /// Roe's superbee: `maxmod(minmod(2a, b), minmod(a, 2b))`.
    Superbee,
    /// Minmod: `minmod(a, b)`.
    Minmod,
}

/// Advection scheme.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Advection {
    /// First-order donor cell.
    FirstOrder,
    /// Second-order limited reconstruction.
    SecondOrder(Limiter),
}

/// Limited slope (change per cell) from the backward difference `a` and the
/// forward difference `b`.
#[inline]
pub fn limited_slope(a: f64, b: f64, limiter: Limiter) -> f64 {
    if a * b <= 0.0 {
        return 0.0;
    }
    match limiter {
        Limiter::VanLeer => 2.0 * a * b / (a + b),
        Limiter::MonotonizedCentral => {
            let c = 0.5 * (a + b);
            let m = (2.0 * a.abs()).min(2.0 * b.abs()).min(c.abs());
            m.copysign(a)
        }
        Limiter::Superbee => {
            let (x, y) = (a.abs(), b.abs());
            (2.0 * x).min(y).max(x.min(2.0 * y)).copysign(a)
        }
        Limiter::Minmod => a.abs().min(b.abs()).copysign(a),
    }
}

/// Value of `q` at the centroid of the region swept out of `donor` across
/// the face on its `sign` side (`+1` upper, `−1` lower); `nu` is the
/// Courant number `|u*| Δt / h`.
#[inline]
pub fn face_value(
    q: &[f64],
    donor: usize,
    stride: usize,
    sign: f64,
    nu: f64,
    scheme: Advection,
) -> f64 {
    let qc = q[donor];
    match scheme {
        Advection::FirstOrder => qc,
        Advection::SecondOrder(lim) => {
            let s = limited_slope(qc - q[donor - stride], q[donor + stride] - qc, lim);
            qc + sign * 0.5 * (1.0 - nu) * s
        }
    }
}

/// Vector version of [`face_value`], component by component.
#[inline]
pub fn face_value_vec<const D: usize>(
    q: &[SVector<f64, D>],
    donor: usize,
    stride: usize,
    sign: f64,
    nu: f64,
    scheme: Advection,
) -> SVector<f64, D> {
    let qc = q[donor];
    match scheme {
        Advection::FirstOrder => qc,
        Advection::SecondOrder(lim) => {
            let (qm, qp) = (q[donor - stride], q[donor + stride]);
            SVector::<f64, D>::from_fn(|k, _| {
                let s = limited_slope(qc[k] - qm[k], qp[k] - qc[k], lim);
                qc[k] + sign * 0.5 * (1.0 - nu) * s
            })
        }
    }
}

/// Donor cell, side sign and Courant number of a face with velocity `u`.
#[inline]
pub(crate) fn donor(face: usize, stride: usize, u: f64, dt: f64, h: f64) -> (usize, f64, f64) {
    let nu = u.abs() * dt / h;
    if u >= 0.0 {
        (face - stride, 1.0, nu)
    } else {
        (face, -1.0, nu)
    }
}

/// Face fluxes of `q` per unit cell volume, `(u* Δt / h) q_f`, into
/// `flux` (indexed by face), for every face normal to `d`.
pub fn scalar_fluxes<const D: usize>(
    layout: &CellLayout<D>,
    d: usize,
    ustar: &[f64],
    q: &[f64],
    dt: f64,
    scheme: Advection,
    flux: &mut [f64],
) {
    let s = layout.strides[d];
    let h = layout.h[d];
    let out = Out::new(flux);
    par_face_rows(layout, d, |row| {
        for f in row {
            let u = ustar[f];
            let (c, sign, nu) = donor(f, s, u, dt, h);
            let v = u * dt / h * face_value(q, c, s, sign, nu, scheme);
            // SAFETY: each face is written by one task only.
            unsafe { out.set(f, v) };
        }
    });
}

/// Buffers for the advection fluxes of one material (per direction, per
/// face).
#[derive(Debug, Clone)]
pub struct AdvectionFluxes<const D: usize> {
    /// Mass flux.
    pub mass: [Vec<f64>; D],
    /// Momentum flux.
    pub momentum: [Vec<SVector<f64, D>>; D],
    /// Internal energy flux `F_M e_f`.
    pub energy: [Vec<f64>; D],
    /// Material volume flux `F_M v_f`.
    pub volume: [Vec<f64>; D],
    /// Kinetic energy flux `F_M k_f`, `k = |u|²/2` (total-energy form).
    pub kinetic: [Vec<f64>; D],
}

impl<const D: usize> AdvectionFluxes<D> {
    /// Buffers for `n` cells.
    pub fn new(n: usize) -> Self {
        Self {
            mass: std::array::from_fn(|_| vec![0.0; n]),
            momentum: std::array::from_fn(|_| vec![SVector::zeros(); n]),
            energy: std::array::from_fn(|_| vec![0.0; n]),
            volume: std::array::from_fn(|_| vec![0.0; n]),
            kinetic: std::array::from_fn(|_| vec![0.0; n]),
        }
    }
}

/// Specific quantities of one material to be advected (ghosts filled).
#[derive(Clone, Copy)]
pub struct AdvectedFields<'a, const D: usize> {
    /// Mass `M`.
    pub mass: &'a [f64],
    /// Velocity `u^L`.
    pub velocity: &'a [SVector<f64, D>],
    /// Specific internal energy `e^L`.
    pub energy: &'a [f64],
    /// Specific volume `v^L`.
    pub sp_vol: &'a [f64],
    /// Specific kinetic energy `|u^L|²/2`, advected when present.
    pub kinetic: Option<&'a [f64]>,
}

/// Computes the compatible fluxes of one material (Guilkey step 12).
pub fn material_fluxes<const D: usize>(
    layout: &CellLayout<D>,
    ustar: &[Vec<f64>; D],
    q: &AdvectedFields<'_, D>,
    dt: f64,
    scheme: Advection,
    out: &mut AdvectionFluxes<D>,
) {
    for d in 0..D {
        let s = layout.strides[d];
        let h = layout.h[d];
        let us = &ustar[d];
        let (fm, fmu, fe, fv, fk) = (
            Out::new(&mut out.mass[d]),
            Out::new(&mut out.momentum[d]),
            Out::new(&mut out.energy[d]),
            Out::new(&mut out.volume[d]),
            Out::new(&mut out.kinetic[d]),
        );
        par_face_rows(layout, d, |row| {
            for f in row {
                let u = us[f];
                let (c, sign, nu) = donor(f, s, u, dt, h);
                let m_flux = u * dt / h * face_value(q.mass, c, s, sign, nu, scheme);
                // SAFETY: each face is written by one task only.
                unsafe {
                    fm.set(f, m_flux);
                    fmu.set(
                        f,
                        face_value_vec(q.velocity, c, s, sign, nu, scheme) * m_flux,
                    );
                    fe.set(f, m_flux * face_value(q.energy, c, s, sign, nu, scheme));
                    fv.set(f, m_flux * face_value(q.sp_vol, c, s, sign, nu, scheme));
                    if let Some(k) = q.kinetic {
                        fk.set(f, m_flux * face_value(k, c, s, sign, nu, scheme));
                    }
                }
            }
        });
    }
}

/// Net inflow of face fluxes into cell `c`: `Σ_d (F_lower − F_upper)`.
#[inline]
pub fn net_inflow<const D: usize>(layout: &CellLayout<D>, flux: &[Vec<f64>; D], c: usize) -> f64 {
    let mut acc = 0.0;
    for d in 0..D {
        acc += flux[d][c] - flux[d][c + layout.strides[d]];
    }
    acc
}

/// Vector version of [`net_inflow`].
#[inline]
pub fn net_inflow_vec<const D: usize>(
    layout: &CellLayout<D>,
    flux: &[Vec<SVector<f64, D>>; D],
    c: usize,
) -> SVector<f64, D> {
    let mut acc = SVector::<f64, D>::zeros();
    for d in 0..D {
        acc += flux[d][c] - flux[d][c + layout.strides[d]];
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limiters() {
        assert_eq!(limited_slope(1.0, -1.0, Limiter::VanLeer), 0.0);
        assert_eq!(limited_slope(1.0, 1.0, Limiter::VanLeer), 1.0);
        assert_eq!(limited_slope(1.0, 3.0, Limiter::VanLeer), 1.5);
        assert_eq!(limited_slope(1.0, 3.0, Limiter::MonotonizedCentral), 2.0);
        assert_eq!(limited_slope(-1.0, -1.2, Limiter::MonotonizedCentral), -1.1);
        // Odd and homogeneous of degree one (needed for the interface test).
        for lim in [
            Limiter::VanLeer,
            Limiter::MonotonizedCentral,
            Limiter::Superbee,
            Limiter::Minmod,
        ] {
            let (a, b) = (0.3, 0.7);
            assert_eq!(limited_slope(-a, -b, lim), -limited_slope(a, b, lim));
            assert!(
                (limited_slope(2.0 * a, 2.0 * b, lim) - 2.0 * limited_slope(a, b, lim)).abs()
                    < 1e-16
            );
        }
    }
}
