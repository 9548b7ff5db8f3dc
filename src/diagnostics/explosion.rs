//! Measures of the confined explosion (Guilkey Sec. 5, Fig. 6): how far
//! the product gas has left the container and mixed with the air, and
//! when the container first failed. One definition for the case's tests,
//! its figure (`paper_figures guilkey_fig6`) and its study
//! (`verification confined_explosion_onset`).

use crate::coupling::CoupledRun;
use crate::mpm::Particles;

/// The product gas's spread at one time ([`vent`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vent {
    /// Product mass in the domain's interior cells.
    pub product_mass: f64,
    /// Share of it in cells whose centre is outside the container
    /// (0 while there is no product).
    pub outside_share: f64,
    /// Cells holding both gases at a volume fraction above 10 % each.
    pub mixed_cells: usize,
    /// The largest product volume fraction in the cells along the
    /// domain's upper faces (the walls the gas reaches in Fig. 6d).
    pub at_upper_walls: f64,
}

/// The spread of fluid `products` in fluid `air` (indices of
/// `run.fluid.cells`), with `outside(x)` saying whether a cell centre lies
/// outside the container.
pub fn vent<const D: usize>(
    run: &CoupledRun<D>,
    products: usize,
    air: usize,
    outside: impl Fn(&[f64]) -> bool,
) -> Vent {
    let lay = &run.fluid.layout;
    let upper: [f64; D] = std::array::from_fn(|a| lay.lower[a] + lay.h[a] * lay.cells[a] as f64);
    let (gas, prod) = (&run.fluid.cells[air], &run.fluid.cells[products]);
    let (mut total, mut out, mut mixed, mut at_walls) = (0.0, 0.0, 0, 0.0f64);
    for &c in &lay.interior {
        let x = lay.centre(c);
        total += prod.mass[c];
        if outside(x.as_slice()) {
            out += prod.mass[c];
        }
        if gas.vol_frac[c] > 0.1 && prod.vol_frac[c] > 0.1 {
            mixed += 1;
        }
        if (0..D).any(|a| x[a] > upper[a] - lay.h[a]) {
            at_walls = at_walls.max(prod.vol_frac[c]);
        }
    }
    Vent {
        product_mass: total,
        outside_share: if total > 0.0 { out / total } else { 0.0 },
        mixed_cells: mixed,
        at_upper_walls: at_walls,
    }
}

/// The failed points of `particles` with their initial angles in the x–y
/// plane \[deg\] (the notch of the cases is at 45°; in 1D every angle is 0).
pub fn failed_angles<const D: usize>(particles: &Particles<D>) -> Vec<f64> {
    (0..particles.len())
        .filter(|&i| particles.failed(i))
        .map(|i| {
            let x = particles.x0[i].as_slice();
            x.get(1).map_or(0.0, |y| y.atan2(x[0]).to_degrees())
        })
        .collect()
}
