//! Deterministic row-parallel loops over cells and faces (rayon).
//!
//! Work is split into x-rows of the layout (contiguous flat indices). Every
//! kernel computes the value of a cell or face from read-only inputs and
//! writes it to that cell's or face's own index only, so the result does not
//! depend on the number of threads or on the scheduling (bit-identical for
//! any thread count). Reductions are order-preserving (`reduce` on an
//! indexed iterator) or exact (`max`), and the first error in row order is
//! reported. Nothing is allocated.

use std::marker::PhantomData;
use std::ops::Range;

use rayon::prelude::*;

use super::state::CellLayout;
use super::IceError;

/// A shared view of a mutable slice for disjoint per-index writes from
/// several rayon tasks.
pub(crate) struct Out<'a, T> {
    ptr: *mut T,
    len: usize,
    _m: PhantomData<&'a mut [T]>,
}

impl<T> Clone for Out<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Out<'_, T> {}

// SAFETY: `Out` is only used for writes (and reads) of disjoint indices by
// different tasks; see `set` and `get`.
unsafe impl<T: Send + Sync> Send for Out<'_, T> {}
// SAFETY: as above.
unsafe impl<T: Send + Sync> Sync for Out<'_, T> {}

impl<'a, T> Out<'a, T> {
    /// Wraps a slice for the duration of a parallel loop.
    pub(crate) fn new(s: &'a mut [T]) -> Self {
        Self {
            ptr: s.as_mut_ptr(),
            len: s.len(),
            _m: PhantomData,
        }
    }

    /// An empty view (placeholder in fixed-size arrays).
    pub(crate) fn empty() -> Self {
        Self {
            ptr: std::ptr::NonNull::dangling().as_ptr(),
            len: 0,
            _m: PhantomData,
        }
    }

    /// Writes `v` at `i`.
    ///
    /// # Safety
    /// No other task may read or write index `i` during the loop.
    #[inline]
    pub(crate) unsafe fn set(&self, i: usize, v: T) {
        assert!(i < self.len);
        // SAFETY: in bounds (checked); exclusive per the contract.
        unsafe { *self.ptr.add(i) = v }
    }

    /// Reads index `i`.
    ///
    /// # Safety
    /// No other task may write index `i` during the loop.
    #[inline]
    pub(crate) unsafe fn get(&self, i: usize) -> T
    where
        T: Copy,
    {
        assert!(i < self.len);
        // SAFETY: in bounds (checked); no concurrent writer per the contract.
        unsafe { *self.ptr.add(i) }
    }
}

/// Runs `f` on every interior x-row (a range of flat cell indices) in
/// parallel; returns the first error in row order. A layout with one row
/// (1D) runs on the calling thread (every helper here does).
pub(crate) fn try_rows<const D: usize>(
    layout: &CellLayout<D>,
    f: impl Fn(Range<usize>) -> Result<(), IceError> + Sync + Send,
) -> Result<(), IceError> {
    let n = layout.cells[0];
    if let [s] = layout.rows[..] {
        // One row (1D): no work to share; running it here avoids the
        // hand-off to the thread pool (the result is the same).
        return f(s..s + n);
    }
    layout
        .rows
        .par_iter()
        .map(|&s| f(s..s + n))
        .reduce(|| Ok(()), |a, b| a.and(b))
}

/// Runs `f` on every interior x-row in parallel.
pub(crate) fn par_rows<const D: usize>(
    layout: &CellLayout<D>,
    f: impl Fn(Range<usize>) + Sync + Send,
) {
    let n = layout.cells[0];
    if let [s] = layout.rows[..] {
        return f(s..s + n);
    }
    layout.rows.par_iter().for_each(|&s| f(s..s + n));
}

/// Maximum of `f` over the interior x-rows (exact, so order-independent).
pub(crate) fn max_rows<const D: usize>(
    layout: &CellLayout<D>,
    f: impl Fn(Range<usize>) -> f64 + Sync + Send,
) -> f64 {
    let n = layout.cells[0];
    if let [s] = layout.rows[..] {
        return f(s..s + n).max(0.0);
    }
    layout
        .rows
        .par_iter()
        .map(|&s| f(s..s + n))
        .reduce(|| 0.0, f64::max)
}

/// Runs `f` on every x-row of the faces normal to `d` (the faces of
/// [`CellLayout::faces`]`[d]`) in parallel.
pub(crate) fn par_face_rows<const D: usize>(
    layout: &CellLayout<D>,
    d: usize,
    f: impl Fn(Range<usize>) + Sync + Send,
) {
    let n = layout.cells[0] + usize::from(d == 0);
    if let [s] = layout.face_rows[d][..] {
        return f(s..s + n);
    }
    layout.face_rows[d].par_iter().for_each(|&s| f(s..s + n));
}
