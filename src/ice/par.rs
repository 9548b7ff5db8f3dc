//! Deterministic row-parallel loops over cells and faces (rayon).
//!
//! Work is split into x-rows of the layout (contiguous flat indices; a
//! single long row, 1D, into fixed pieces). Every
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

/// Cells (or faces) per task when a layout has a single row (1D): the row
/// is cut into pieces of this length, so a long 1D grid is shared between
/// threads while a short one (up to one piece) runs on the calling thread
/// without a hand-off to the pool. Every kernel here writes only its own
/// index, so how a row is cut does not change the result.
pub(crate) const ROW_PIECE: usize = 4096;

/// The ranges a loop over `rows` (each `n` long, starting at the listed
/// flat index) hands to its tasks: one per row, or a single row cut into
/// [`ROW_PIECE`]-long pieces, in increasing index order.
fn pieces(rows: &[usize], n: usize) -> impl IndexedParallelIterator<Item = Range<usize>> + '_ {
    let single = rows.len() == 1;
    let per_row = if single {
        n.div_ceil(ROW_PIECE).max(1)
    } else {
        1
    };
    let len = if single { per_row } else { rows.len() };
    (0..len).into_par_iter().map(move |k| {
        if single {
            let s = rows[0];
            s + k * ROW_PIECE..s + ((k + 1) * ROW_PIECE).min(n)
        } else {
            rows[k]..rows[k] + n
        }
    })
}

/// Whether the loop over `rows` fits in one task (a single row no longer
/// than a piece): it then runs on the calling thread.
fn one_task(rows: &[usize], n: usize) -> bool {
    rows.len() == 1 && n <= ROW_PIECE
}

/// Runs `f` on every interior x-row (a range of flat cell indices; a long
/// 1D row in pieces) in parallel; returns the first error in index order.
pub(crate) fn try_rows<const D: usize>(
    layout: &CellLayout<D>,
    f: impl Fn(Range<usize>) -> Result<(), IceError> + Sync + Send,
) -> Result<(), IceError> {
    let n = layout.cells[0];
    if one_task(&layout.rows, n) {
        let s = layout.rows[0];
        return f(s..s + n);
    }
    pieces(&layout.rows, n)
        .map(f)
        .reduce(|| Ok(()), |a, b| a.and(b))
}

/// Runs `f` on every interior x-row (a long 1D row in pieces) in parallel.
pub(crate) fn par_rows<const D: usize>(
    layout: &CellLayout<D>,
    f: impl Fn(Range<usize>) + Sync + Send,
) {
    let n = layout.cells[0];
    if one_task(&layout.rows, n) {
        let s = layout.rows[0];
        return f(s..s + n);
    }
    pieces(&layout.rows, n).for_each(f);
}

/// Maximum of `f` over the interior x-rows and 0 (exact, so
/// order-independent); a row that returns NaN makes it NaN.
pub(crate) fn max_rows<const D: usize>(
    layout: &CellLayout<D>,
    f: impl Fn(Range<usize>) -> f64 + Sync + Send,
) -> f64 {
    let n = layout.cells[0];
    if one_task(&layout.rows, n) {
        let s = layout.rows[0];
        return nan_max(f(s..s + n), 0.0);
    }
    pieces(&layout.rows, n).map(f).reduce(|| 0.0, nan_max)
}

/// The larger of `a` and `b`, NaN if either is (`f64::max` drops a NaN).
#[inline]
pub(crate) fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// Runs `f` on every x-row of the faces normal to `d` (the faces of
/// [`CellLayout::faces`]`[d]`; a long 1D row in pieces) in parallel.
pub(crate) fn par_face_rows<const D: usize>(
    layout: &CellLayout<D>,
    d: usize,
    f: impl Fn(Range<usize>) + Sync + Send,
) {
    let n = layout.cells[0] + usize::from(d == 0);
    let rows = &layout.face_rows[d];
    if one_task(rows, n) {
        let s = rows[0];
        return f(s..s + n);
    }
    pieces(rows, n).for_each(f);
}

#[cfg(test)]
mod tests {
    use nalgebra::SVector;

    use super::*;

    /// A long 1D row is cut into pieces that cover it once, in order, and
    /// a NaN from any piece or row is the maximum (`f64::max` would drop
    /// it), in 1D and 2D.
    #[test]
    fn pieces_cover_the_row_and_max_keeps_nan() {
        use std::sync::Mutex;
        let n = 3 * ROW_PIECE + 17;
        let l1 = CellLayout::<1>::new(SVector::zeros(), SVector::repeat(1.0), [n]).expect("1D");
        let seen = Mutex::new(Vec::new());
        par_rows(&l1, |r| seen.lock().expect("lock").push(r));
        let mut seen = seen.into_inner().expect("lock");
        seen.sort_by_key(|r| r.start);
        assert_eq!(seen.len(), 4);
        let s = l1.rows[0];
        assert_eq!(seen[0].start, s);
        assert!(seen.windows(2).all(|w| w[0].end == w[1].start));
        assert_eq!(seen[3].end, s + n);
        let l2 = CellLayout::<2>::new(SVector::zeros(), SVector::repeat(1.0), [8, 9]).expect("2D");
        let bad = l1.rows[0] + 2 * ROW_PIECE + 3;
        assert!(max_rows(&l1, |r| if r.contains(&bad) { f64::NAN } else { 1.0 }).is_nan());
        assert_eq!(
            max_rows(&l1, |r| r.start as f64),
            (s + 3 * ROW_PIECE) as f64
        );
        let row = l2.rows[4];
        assert!(max_rows(&l2, |r| if r.start == row { f64::NAN } else { 2.0 }).is_nan());
        assert_eq!(max_rows(&l2, |_| -1.0), 0.0);
    }
}
