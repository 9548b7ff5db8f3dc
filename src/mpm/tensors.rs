//! Per-particle 3×3 tensors (the deformation gradient F and the Cauchy
//! stress σ) stored without the entries the dimension keeps zero, and a
//! symmetric one (σ) without its lower triangle.
//!
//! In 2D (plane strain, and r–z) the velocity gradient lives in the
//! in-plane block, so F = [F_D 0; 0 F₃₃] and σ = [σ_D 0; 0 σ₃₃]: five
//! entries instead of nine. In 1D (uniaxial strain) both are diagonal:
//! three entries. In 3D all nine are kept. The Cauchy stress is symmetric
//! (balance of angular momentum), so [`Stresses`] keeps only its upper
//! triangle: four entries in 2D, six in 3D. The two tensors of a 2D
//! particle take 72 bytes instead of 144, of a 3D particle 120 instead of
//! 144 (issue 24's leaner particle state). The kernels still compute with
//! full [`Matrix3`]s: [`Tensors::get`] fills the zero (and mirrored)
//! entries in and [`Tensors::set`] leaves them out, so every result is
//! the same to the bit as with 3×3 storage — for a stress whose kernel
//! gives it exactly symmetric. One that comes out asymmetric by round-off
//! (a rotated or a spectrally built stress) is stored as its symmetric
//! part, ½(σ_ij + σ_ji), which is σ_ij itself when the two are equal.

use nalgebra::Matrix3;

/// One 3×3 tensor per particle, stored as its [`Tensors::ENTRIES`];
/// symmetric ones ([`Stresses`]) without their lower triangle when `SYM`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Tensors<const D: usize, const SYM: bool = false> {
    /// `ENTRIES.len()` values per particle, in the order of `ENTRIES`.
    data: Vec<f64>,
}

/// Symmetric per-particle tensors (the Cauchy stress): the entries on and
/// above the diagonal.
pub type Stresses<const D: usize> = Tensors<D, true>;

impl<const D: usize, const SYM: bool> Tensors<D, SYM> {
    /// The `(row, column)` entries stored in `D` dimensions; the others are
    /// zero, or (when `SYM`) the mirror of a stored one.
    pub const ENTRIES: &'static [(usize, usize)] = match (D, SYM) {
        (1, _) => &[(0, 0), (1, 1), (2, 2)],
        (2, false) => &[(0, 0), (0, 1), (1, 0), (1, 1), (2, 2)],
        (2, true) => &[(0, 0), (0, 1), (1, 1), (2, 2)],
        (_, true) => &[(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)],
        _ => &[
            (0, 0),
            (0, 1),
            (0, 2),
            (1, 0),
            (1, 1),
            (1, 2),
            (2, 0),
            (2, 1),
            (2, 2),
        ],
    };

    /// Values stored per particle.
    pub const STRIDE: usize = Self::ENTRIES.len();

    /// Number of tensors.
    pub fn len(&self) -> usize {
        self.data.len() / Self::STRIDE
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Tensor `p`.
    #[inline(always)]
    pub fn get(&self, p: usize) -> Matrix3<f64> {
        unpack::<D, SYM>(&self.data[p * Self::STRIDE..(p + 1) * Self::STRIDE])
    }

    /// Sets tensor `p` to `m`, whose entries outside [`Self::ENTRIES`] must
    /// be zero (checked in debug builds), or when `SYM` to the symmetric
    /// part of `m`.
    #[inline(always)]
    pub fn set(&mut self, p: usize, m: &Matrix3<f64>) {
        pack::<D, SYM>(m, &mut self.data[p * Self::STRIDE..(p + 1) * Self::STRIDE]);
    }

    /// Appends `m` (entries outside [`Self::ENTRIES`] zero, as for
    /// [`Self::set`]).
    pub fn push(&mut self, m: &Matrix3<f64>) {
        let n = self.data.len();
        self.data.resize(n + Self::STRIDE, 0.0);
        pack::<D, SYM>(m, &mut self.data[n..]);
    }

    /// The tensors in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = Matrix3<f64>> + '_ {
        self.data.chunks_exact(Self::STRIDE).map(unpack::<D, SYM>)
    }

    /// The tensors of `m` (entries outside the dimension's zero; when `SYM`
    /// their symmetric parts), or the index of the first that has a
    /// non-zero entry outside the dimension's.
    pub fn try_from_matrices(m: &[Matrix3<f64>]) -> Result<Self, usize> {
        if let Some(p) = m.iter().position(|a| !fits::<D, SYM>(a)) {
            return Err(p);
        }
        let mut t = Self {
            data: Vec::with_capacity(m.len() * Self::STRIDE),
        };
        for a in m {
            t.push(a);
        }
        Ok(t)
    }

    /// Shared access for kernels in which each task reads and writes only
    /// its own particles.
    pub fn shared(&mut self) -> SharedTensors<D, SYM> {
        SharedTensors(self.data.as_mut_ptr())
    }

    /// The stored values, [`Self::STRIDE`] per particle in the order of
    /// [`Self::ENTRIES`].
    pub fn values(&self) -> &[f64] {
        &self.data
    }

    /// Tensors from their stored values ([`Self::values`]); `None` unless
    /// their number is a multiple of [`Self::STRIDE`].
    pub fn from_values(data: Vec<f64>) -> Option<Self> {
        data.len()
            .is_multiple_of(Self::STRIDE)
            .then_some(Self { data })
    }

    /// The stored values, `ENTRIES.len()` per particle.
    pub(crate) fn values_mut(&mut self) -> &mut Vec<f64> {
        &mut self.data
    }
}

/// Whether `m` is zero outside the entries a `D`-dimensional tensor holds
/// (those stored, and when `SYM` their mirrors).
fn fits<const D: usize, const SYM: bool>(m: &Matrix3<f64>) -> bool {
    let held = |i, j| {
        let e = Tensors::<D, SYM>::ENTRIES;
        e.contains(&(i, j)) || (SYM && e.contains(&(j, i)))
    };
    (0..3).all(|i| (0..3).all(|j| m[(i, j)] == 0.0 || held(i, j)))
}

#[inline(always)]
fn unpack<const D: usize, const SYM: bool>(s: &[f64]) -> Matrix3<f64> {
    let mut m = Matrix3::zeros();
    for (k, &(i, j)) in Tensors::<D, SYM>::ENTRIES.iter().enumerate() {
        m[(i, j)] = s[k];
        if SYM {
            m[(j, i)] = s[k];
        }
    }
    m
}

#[inline(always)]
fn pack<const D: usize, const SYM: bool>(m: &Matrix3<f64>, s: &mut [f64]) {
    debug_assert!(
        fits::<D, SYM>(m),
        "a {D}D particle tensor with entries outside its plane: {m}"
    );
    for (k, &(i, j)) in Tensors::<D, SYM>::ENTRIES.iter().enumerate() {
        // The symmetric part: exactly m_ij when m_ji equals it (a + a and
        // the halving are exact).
        s[k] = if SYM && i != j {
            0.5 * (m[(i, j)] + m[(j, i)])
        } else {
            m[(i, j)]
        };
    }
}

/// [`Tensors`] shared by the tasks of a parallel kernel (see
/// [`Tensors::shared`]).
pub struct SharedTensors<const D: usize, const SYM: bool = false>(*mut f64);

// SAFETY: callers guarantee that no two tasks touch the same particle.
unsafe impl<const D: usize, const SYM: bool> Send for SharedTensors<D, SYM> {}
// SAFETY: as above.
unsafe impl<const D: usize, const SYM: bool> Sync for SharedTensors<D, SYM> {}

impl<const D: usize, const SYM: bool> SharedTensors<D, SYM> {
    /// Tensor `p`.
    ///
    /// # Safety
    /// `p` is in bounds and no other task writes particle `p` meanwhile.
    #[inline(always)]
    pub unsafe fn get(&self, p: usize) -> Matrix3<f64> {
        let s = Tensors::<D, SYM>::STRIDE;
        unpack::<D, SYM>(std::slice::from_raw_parts(self.0.add(p * s), s))
    }

    /// Sets tensor `p` (as [`Tensors::set`]).
    ///
    /// # Safety
    /// `p` is in bounds and no other task accesses particle `p` meanwhile.
    #[inline(always)]
    pub unsafe fn set(&self, p: usize, m: &Matrix3<f64>) {
        let s = Tensors::<D, SYM>::STRIDE;
        pack::<D, SYM>(m, std::slice::from_raw_parts_mut(self.0.add(p * s), s));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip<const D: usize>(m: &Matrix3<f64>) {
        let mut t = Tensors::<D>::default();
        t.push(&Matrix3::identity());
        t.push(m);
        assert_eq!((t.len(), t.get(1), t.get(0)), (2, *m, Matrix3::identity()));
        t.set(0, m);
        assert_eq!(t.iter().collect::<Vec<_>>(), vec![*m, *m]);
        let shared = t.shared();
        // SAFETY: one thread, particle 1 in bounds.
        unsafe {
            shared.set(1, &Matrix3::identity());
            assert_eq!(shared.get(1), Matrix3::identity());
        }
    }

    /// Each dimension gives back exactly the tensors it may hold.
    #[test]
    fn tensors_round_trip_bit_exactly() {
        let plane = Matrix3::new(1.5, -0.25, 0.0, 1e-300, 0.75, 0.0, 0.0, 0.0, 1.0 / 3.0);
        let diag = Matrix3::from_diagonal(&nalgebra::Vector3::new(0.9, 1.0, -7e5));
        let full = Matrix3::from_fn(|i, j| (3 * i + j) as f64 - 4.5);
        round_trip::<1>(&diag);
        round_trip::<2>(&plane);
        round_trip::<2>(&diag);
        round_trip::<3>(&full);
        assert_eq!(Tensors::<2>::ENTRIES.len(), 5);
        assert_eq!(
            Tensors::<2>::try_from_matrices(&[plane, full]),
            Err(1),
            "an out-of-plane entry is refused"
        );
        assert_eq!(Tensors::<1>::try_from_matrices(&[plane]), Err(0));
        let t = Tensors::<2>::try_from_matrices(&[plane, diag]).expect("in plane");
        assert_eq!(t.iter().collect::<Vec<_>>(), vec![plane, diag]);
    }

    /// A symmetric tensor comes back to the bit from its upper triangle;
    /// an asymmetric one as its symmetric part.
    #[test]
    fn stresses_keep_the_upper_triangle() {
        assert_eq!(
            (
                Stresses::<1>::STRIDE,
                Stresses::<2>::STRIDE,
                Stresses::<3>::STRIDE
            ),
            (3, 4, 6)
        );
        let plane = Matrix3::new(1.5, -0.25, 0.0, -0.25, 0.75, 0.0, 0.0, 0.0, 1.0 / 3.0);
        let full = Matrix3::from_fn(|i, j| ((i + 1) * (j + 1)) as f64 / 7.0 + 1e-300);
        let mut t = Stresses::<2>::default();
        t.push(&plane);
        assert_eq!(t.get(0), plane);
        let mut skew = plane;
        skew[(1, 0)] = -0.75;
        t.set(0, &skew);
        assert_eq!(t.get(0)[(0, 1)], -0.5);
        assert_eq!(t.get(0)[(1, 0)], -0.5);
        assert_eq!(Stresses::<2>::try_from_matrices(&[plane, full]), Err(1));
        let t3 = Stresses::<3>::try_from_matrices(&[full, plane]).expect("3D");
        assert_eq!(t3.iter().collect::<Vec<_>>(), vec![full, plane]);
        let mut t3 = t3;
        let shared = t3.shared();
        // SAFETY: one thread, particle 1 in bounds.
        unsafe {
            shared.set(1, &skew);
            assert_eq!(shared.get(1)[(1, 0)], -0.5);
        }
    }
}
