//! The sharp interface of a rigid solid field in the cells
//! ([`RigidInterface::Sharp`]): the field's cell mass from the exact
//! overlap of its particles' domains with the cells, instead of the node →
//! cell average of its nodal masses (Guilkey Sec. 3.3 step 1), which
//! spreads a rigid face over about three cells.
//!
//! Why (issue 21, the adiabatic piston of Guilkey Sec. 4.2): with the
//! smeared fraction, gas sits in cells the piston fills, is held there at
//! the piston's velocity by the `K = 1e15` exchange and rides with it
//! (2.5 % of the gas at 120 cells), while the gas cells ahead stay
//! under-filled; the closed-end pressure came out 7.2 % high at N = 120
//! and 3.4 % at N = 240. A rigid body's volume in a cell is known exactly
//! from its particles, and three pieces together let the gas leave the
//! cells the body takes over: the exact cell volume ([`box_cell_mass`]); a
//! face that is rigid only as far as both its cells are (the smaller
//! fraction, [`crate::ice::IceParams::rigid_faces_sharp`]), so that a face
//! the body has not reached lets the gas out at its own velocity; and the
//! equilibration on the cell volume where no solid deforms
//! ([`crate::ice::IceParams::normalise_volume`] off), so that the gas a
//! body squeezes is compressed and pushed out.
//!
//! What it leaves (measured on the piston, issue 21; experimental): a
//! little gas stays in each cell as the body covers it (about 1 % of a
//! cell's gas), at high pressure and held at the body's velocity, and is
//! carried with the body or released behind it; a layer of cooler,
//! denser gas forms at the body's face. The piston's pressure error at
//! ratio 5 is −0.7, −0.6, −0.8 and −1.2 % at 120, 240, 480 and 960 cells:
//! far better than the smeared interface at coarse cells, but it does not
//! converge (the smeared one does, at first order, and is better from 960
//! cells on). The small masses of those cells also amplify round-off (two
//! runs that differ in the last bit at the start differ by 5e-5 in the
//! closed-end pressure at ratio 3). Tried and dropped: closing the faces
//! the body covers to the gas (the gas left in covered cells then stays
//! where it is and ends up behind the body: −2 %), and merging covered
//! cells' gas into their open neighbour (negative temperatures in the
//! floor left behind).

use serde::{Deserialize, Serialize};

use crate::ice::CellLayout;
use crate::mpm::Particles;

/// How a rigid solid field's volume enters the cells (scene key
/// `coupling.rigid_interface`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RigidInterface {
    /// Guilkey's: the node → cell average of the field's nodal masses, the
    /// face exchange at the mean of its two cells' volume fractions and
    /// the normalised equilibration.
    #[default]
    Smeared,
    /// The exact overlap of the particles' domains with the cells, a rigid
    /// face fraction that is the smaller of its two cells', and the
    /// equilibration on the cell volume when every solid field is rigid
    /// (module notes).
    Sharp,
}

/// Most cells one particle's domain spans per direction (a domain wider
/// than three cells is cut to its first four).
const MAX_SPAN: usize = 4;

/// Distance (in cells) within which a box face is taken to lie on a cell
/// face: particle boxes of a body placed on the grid end on cell faces up
/// to round-off, and a round-off sliver in the next cell would count as
/// the body reaching it (its velocity then held there by the exchange).
const SNAP: f64 = 1e-9;

/// `y` moved onto the nearest cell face when within [`SNAP`] of it.
#[inline]
fn snapped(y: f64) -> f64 {
    let r = y.round();
    if (y - r).abs() < SNAP {
        r
    } else {
        y
    }
}

/// The fraction of the interval `[lo, hi]` (in cell units, ends within
/// [`SNAP`] of a cell face moved onto it) inside each cell it touches: the
/// first cell's index and up to [`MAX_SPAN`] fractions.
#[inline]
fn overlaps(lo: f64, hi: f64) -> (isize, usize, [f64; MAX_SPAN]) {
    let (lo, hi) = (snapped(lo), snapped(hi));
    let first = lo.floor() as isize;
    let last = (hi.ceil() as isize - 1).max(first);
    let count = ((last - first + 1) as usize).min(MAX_SPAN);
    let mut frac = [0.0; MAX_SPAN];
    let len = hi - lo;
    for (j, fr) in frac.iter_mut().enumerate().take(count) {
        let c0 = (first + j as isize) as f64;
        *fr = if len > 0.0 {
            ((hi.min(c0 + 1.0) - lo.max(c0)) / len).max(0.0)
        } else {
            1.0
        };
    }
    (first, count, frac)
}

/// Per interior cell (in `layout.interior` order) the mass of
/// `particles` inside it, each particle's mass spread over the box `x_p ±
/// l_p` (`l_p` its half size) by the box's overlap with each cell; mass
/// outside the interior cells is left out. Exact for a body tiled by its
/// particles' boxes (a rigid field keeps its boxes: it translates).
pub fn box_cell_mass<const D: usize>(
    layout: &CellLayout<D>,
    particles: &Particles<D>,
    cell_mass: &mut [f64],
) {
    cell_mass.fill(0.0);
    let n = layout.cells;
    for ((x, l), &m) in particles
        .x
        .iter()
        .zip(particles.half_size.iter())
        .zip(&particles.mass)
    {
        let mut first = [0isize; D];
        let mut count = [0usize; D];
        let mut frac = [[0.0; MAX_SPAN]; D];
        for d in 0..D {
            let to_cells = |y: f64| (y - layout.lower[d]) / layout.h[d];
            (first[d], count[d], frac[d]) = overlaps(to_cells(x[d] - l[d]), to_cells(x[d] + l[d]));
        }
        let total: usize = count.iter().product();
        'cell: for t in 0..total {
            let (mut rem, mut w, mut k, mut stride) = (t, m, 0usize, 1usize);
            for d in 0..D {
                let j = rem % count[d];
                rem /= count[d];
                let i = first[d] + j as isize;
                if i < 0 || i >= n[d] as isize {
                    continue 'cell;
                }
                w *= frac[d][j];
                k += i as usize * stride;
                stride *= n[d];
            }
            cell_mass[k] += w;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SVector;

    /// A block of `k × k` particles per cell over cells `[i0, i0 + w) ×
    /// [j0, j0 + w)`, shifted by `shift` (cell units), with mass 1 each.
    fn block(h: f64, k: usize, i0: usize, j0: usize, w: usize, shift: [f64; 2]) -> Particles<2> {
        let mut p = Particles::<2>::default();
        let s = h / k as f64;
        for a in 0..w * k {
            for b in 0..w * k {
                let x = SVector::<f64, 2>::new(
                    (i0 as f64 + shift[0]) * h + (a as f64 + 0.5) * s,
                    (j0 as f64 + shift[1]) * h + (b as f64 + 0.5) * s,
                );
                p.x.push(x);
                p.half_size.push(SVector::repeat(0.5 * s));
                p.mass.push(1.0);
            }
        }
        p
    }

    fn layout(n: usize, h: f64) -> CellLayout<2> {
        CellLayout::<2>::new(SVector::zeros(), SVector::repeat(h), [n, n]).unwrap()
    }

    /// A 3 × 3-cell block of 2 × 2 particles per cell at cells (2, 3),
    /// shifted by `(sx, sy)` cells: every cell holds 4 × (its area inside
    /// the block), to round-off of the fractions' sums, and the total is
    /// kept.
    fn assert_block_overlap(sx: f64, sy: f64) {
        let (h, n) = (0.1, 8);
        let lay = layout(n, h);
        let p = block(h, 2, 2, 3, 3, [sx, sy]);
        let mut m = vec![0.0; n * n];
        box_cell_mass(&lay, &p, &mut m);
        let overlap = |c: f64, lo: f64| ((c + 1.0).min(lo + 3.0) - c.max(lo)).max(0.0);
        for j in 0..n {
            for i in 0..n {
                let want = 4.0 * overlap(i as f64, 2.0 + sx) * overlap(j as f64, 3.0 + sy);
                assert!((m[i + n * j] - want).abs() < 1e-12, "cell ({i}, {j})");
            }
        }
        let total: f64 = m.iter().sum();
        assert!((total - 36.0).abs() < 1e-12);
    }

    #[test]
    fn a_block_on_the_cells_fills_them_exactly() {
        // 4 in each of the 9 cells, 0 elsewhere.
        assert_block_overlap(0.0, 0.0);
    }

    #[test]
    fn a_shifted_block_shares_its_mass_by_overlap() {
        // Not a multiple of the particle spacing.
        assert_block_overlap(0.3, 0.55);
    }

    #[test]
    fn mass_outside_the_cells_is_left_out() {
        let (h, n) = (0.1, 4);
        let lay = layout(n, h);
        // Cells 2..5 in x: the last column is outside the grid.
        let p = block(h, 1, 2, 0, 3, [0.0, 0.0]);
        let mut m = vec![0.0; n * n];
        box_cell_mass(&lay, &p, &mut m);
        let total: f64 = m.iter().sum();
        assert_eq!(total, 6.0);
    }
}
