//! Ready-made initial states for tests and studies.

use nalgebra::SVector;

use super::state::{CellLayout, IceState, MaterialInit};
use super::{IceError, IceMaterial};

/// A 1D shock tube on `[0, 1]` with `n` cells: one material, primitive
/// states `(ρ, u, p)` left and right of `x0`.
///
/// # Errors
/// As [`IceState::new`] and [`CellLayout::new`].
pub fn shock_tube(
    material: IceMaterial,
    n: usize,
    left: (f64, f64, f64),
    right: (f64, f64, f64),
    x0: f64,
) -> Result<IceState<1>, IceError> {
    let layout = CellLayout::<1>::new(
        SVector::<f64, 1>::zeros(),
        SVector::<f64, 1>::new(1.0 / n as f64),
        [n],
    )?;
    IceState::new(layout, vec![material], move |x| {
        let (rho, u, p) = if x[0] < x0 { left } else { right };
        vec![MaterialInit::new(1.0, rho, p, SVector::<f64, 1>::new(u))]
    })
}

/// The exact incompressible 2D periodic vortex on `[0, 2π]²` (a
/// Taylor–Green array carried by the uniform flow `(1, 1)`):
///
/// ```text
/// u = 1 − A cos(x−t) sin(y−t) e^(−2νt)
/// v = 1 + A sin(x−t) cos(y−t) e^(−2νt)
/// p − p_ref = −(A²/4) e^(−4νt) [cos 2(x−t) + cos 2(y−t)]   (ρ = 1)
/// ```
///
/// Returns `(u, v, p − p_ref)` at `x` and time `t` for amplitude `A` and
/// kinematic viscosity `ν`.
pub fn periodic_vortex_exact(
    x: &SVector<f64, 2>,
    t: f64,
    amplitude: f64,
    nu: f64,
) -> (f64, f64, f64) {
    let (xs, ys) = (x[0] - t, x[1] - t);
    let e2 = (-2.0 * nu * t).exp();
    let u = 1.0 - amplitude * xs.cos() * ys.sin() * e2;
    let v = 1.0 + amplitude * xs.sin() * ys.cos() * e2;
    let p = -0.25 * amplitude * amplitude * e2 * e2 * ((2.0 * xs).cos() + (2.0 * ys).cos());
    (u, v, p)
}

/// The periodic vortex of [`periodic_vortex_exact`] at `t = 0` as a gas on
/// `n × n` cells of `[0, 2π]²`: uniform density `ρ = 1`, the exact
/// velocity, and `p = p_ref + p'(x)` (the incompressible pressure on top of
/// the reference pressure `p_ref`, which sets the Mach number:
/// `c² = γ p_ref` for an ideal gas).
///
/// # Errors
/// As [`IceState::new`] and [`CellLayout::new`].
pub fn periodic_vortex(
    material: IceMaterial,
    n: usize,
    amplitude: f64,
    p_ref: f64,
) -> Result<IceState<2>, IceError> {
    let h = 2.0 * std::f64::consts::PI / n as f64;
    let layout = CellLayout::<2>::new(
        SVector::<f64, 2>::zeros(),
        SVector::<f64, 2>::repeat(h),
        [n, n],
    )?;
    IceState::new(layout, vec![material], move |x| {
        let (u, v, p) = periodic_vortex_exact(x, 0.0, amplitude, 0.0);
        vec![MaterialInit::new(
            1.0,
            1.0,
            p_ref + p,
            SVector::<f64, 2>::new(u, v),
        )]
    })
}
