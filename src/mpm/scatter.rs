//! Deterministic parallel particle-to-grid scatter.
//!
//! Particles are binned into slabs of `SLAB_WIDTH` cells along the last axis
//! (a stable counting sort of indices, so each slab lists its particles in
//! index order). A particle in cell c touches nodes c−1 … c+2 along that axis,
//! so slabs two apart never touch the same node when the width exceeds 2. The
//! scatter runs the even slabs in parallel, then the odd ones; every node thus
//! receives its contributions in the same order for any thread count, and the
//! result is bit-identical with 1 or N threads.

use nalgebra::SVector;
use rayon::prelude::*;

use crate::grid::Grid;

/// Cells per slab along the last axis (must exceed 2, see module docs).
pub const SLAB_WIDTH: usize = 4;

/// Particle indices grouped by slab.
#[derive(Debug, Clone, Default)]
pub struct Bins {
    /// Particle indices, slab by slab, each slab in increasing index order.
    pub order: Vec<u32>,
    /// `order[start[s]..start[s + 1]]` are the particles of slab `s`.
    pub start: Vec<usize>,
    slab: Vec<u32>,
    cursor: Vec<usize>,
}

impl Bins {
    /// Bins particle positions (no allocation once the buffers have grown).
    /// Returns the first particle (lowest index) that is off the grid or not
    /// finite, if any.
    pub fn build<const D: usize>(
        &mut self,
        grid: &Grid<D>,
        x: &[SVector<f64, D>],
    ) -> Result<(), usize> {
        let axis = D - 1;
        let n_slabs = (grid.cells[axis] + 2).div_ceil(SLAB_WIDTH);
        self.start.clear();
        self.start.resize(n_slabs + 1, 0);
        self.slab.resize(x.len(), 0);
        // Classify in parallel (u32::MAX marks a particle off the grid), then
        // count and fill serially in index order.
        self.slab
            .par_iter_mut()
            .zip(x.par_iter())
            .with_min_len(4096)
            .for_each(|(s, xp)| {
                let xi = grid.to_grid_units(xp);
                *s = if xi.iter().all(|v| v.is_finite()) && grid.holds(&xi) {
                    // xi ≥ −1 on the grid, so the cast truncates like floor.
                    (((xi[axis] + 1.0) as usize / SLAB_WIDTH).min(n_slabs - 1)) as u32
                } else {
                    u32::MAX
                };
            });
        for (p, &s) in self.slab.iter().enumerate() {
            if s == u32::MAX {
                return Err(p);
            }
            self.start[s as usize + 1] += 1;
        }
        for s in 0..n_slabs {
            self.start[s + 1] += self.start[s];
        }
        self.order.resize(x.len(), 0);
        self.cursor.clone_from(&self.start);
        for p in 0..x.len() {
            let s = self.slab[p] as usize;
            self.order[self.cursor[s]] = p as u32;
            self.cursor[s] += 1;
        }
        Ok(())
    }

    /// Number of slabs.
    pub fn num_slabs(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// Runs `f(particle)` for every particle, slab-coloured: even slabs in
    /// parallel, then odd slabs in parallel; sequential within a slab.
    pub fn for_each_colored(&self, f: impl Fn(usize) + Sync) {
        let n = self.num_slabs();
        for color in 0..2 {
            (0..n.div_ceil(2)).into_par_iter().for_each(|k| {
                let s = 2 * k + color;
                if s < n {
                    for &p in &self.order[self.start[s]..self.start[s + 1]] {
                        f(p as usize);
                    }
                }
            });
        }
    }
}

/// A raw pointer shared across the threads of a coloured or per-index loop.
///
/// Safety rests on the callers: in [`Bins::for_each_colored`] concurrent tasks
/// write disjoint node sets (see module docs); in per-particle loops each task
/// writes only its own index.
#[derive(Clone, Copy)]
pub struct SharedMut<T>(*mut T);

// SAFETY: see the type's documentation; callers guarantee disjoint access.
unsafe impl<T: Send> Send for SharedMut<T> {}
// SAFETY: as above.
unsafe impl<T: Send> Sync for SharedMut<T> {}

impl<T> SharedMut<T> {
    /// Wraps a slice.
    pub fn new(s: &mut [T]) -> Self {
        Self(s.as_mut_ptr())
    }

    /// Mutable access to element `i`.
    ///
    /// # Safety
    /// `i` is in bounds and no other thread accesses element `i` meanwhile.
    #[inline(always)]
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn get(&self, i: usize) -> &mut T {
        &mut *self.0.add(i)
    }
}
