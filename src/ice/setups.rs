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
