//! The structured Cartesian background grid: nodes, cells, ghost layers and
//! boundary conditions. Dimension-generic through `const D: usize`.
//!
//! Node coordinates are integers `i` with node `i = 0` on the lower domain
//! boundary and `i = cells` on the upper one; `ghost` extra node layers on each
//! side hold the support of wide shape functions (GIMP, B-splines) so kernels
//! never index out of bounds. Flat node index: x fastest.

use nalgebra::SVector;

/// Boundary condition on one face of the domain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Boundary {
    /// Reflective plane: zero normal velocity on the face and beyond, tangential free.
    Symmetry,
    /// No-slip wall: zero velocity on the face and beyond.
    Fixed,
    /// Free / outflow: nothing imposed.
    Free,
    /// Periodic (fluid-only scenes; both sides of an axis).
    Periodic,
}

/// Number of ghost node layers on each side of the domain. Cubic B-splines
/// reach two nodes beyond the particle's cell, so two layers hold every stencil
/// of a particle within one cell of the domain.
pub const GHOST: usize = 2;

/// A nodal quantity that can be mirrored across a boundary face.
pub trait Reflect<const D: usize>: Copy {
    /// The value of the mirror image across a face normal to `axis`.
    fn reflect(&self, axis: usize, bc: Boundary) -> Self;
    /// Sum.
    fn add(&self, other: &Self) -> Self;
    /// Zero.
    fn zero() -> Self;
}

impl<const D: usize> Reflect<D> for f64 {
    #[inline]
    fn reflect(&self, _: usize, _: Boundary) -> Self {
        *self
    }
    #[inline]
    fn add(&self, o: &Self) -> Self {
        self + o
    }
    fn zero() -> Self {
        0.0
    }
}

impl<const D: usize> Reflect<D> for SVector<f64, D> {
    #[inline]
    fn reflect(&self, axis: usize, bc: Boundary) -> Self {
        match bc {
            Boundary::Fixed => -self,
            Boundary::Symmetry => {
                let mut r = *self;
                r[axis] = -r[axis];
                r
            }
            Boundary::Free | Boundary::Periodic => *self,
        }
    }
    #[inline]
    fn add(&self, o: &Self) -> Self {
        self + o
    }
    fn zero() -> Self {
        SVector::zeros()
    }
}

/// The background grid.
#[derive(Debug, Clone)]
pub struct Grid<const D: usize> {
    /// Lower corner of the domain.
    pub lower: SVector<f64, D>,
    /// Upper corner of the domain.
    pub upper: SVector<f64, D>,
    /// Number of cells per direction.
    pub cells: [usize; D],
    /// Cell size per direction.
    pub h: SVector<f64, D>,
    /// 1/h per direction.
    pub inv_h: SVector<f64, D>,
    /// Nodes per direction including ghosts: `cells + 1 + 2 GHOST`.
    pub node_dims: [usize; D],
    /// Boundary condition per direction, `[lower, upper]`.
    pub bc: [[Boundary; 2]; D],
    /// Axisymmetric (2D only): the coordinates are (r, z), r = x ≥ 0, and
    /// the explicit MPM kernels add the hoop terms (volumes and masses are
    /// per radian; see `mpm::explicit`). False for plane strain.
    pub axisymmetric: bool,
}

impl<const D: usize> Grid<D> {
    /// Builds a grid; the caller validates the inputs (see `scene`).
    pub fn new(
        lower: SVector<f64, D>,
        upper: SVector<f64, D>,
        cells: [usize; D],
        bc: [[Boundary; 2]; D],
    ) -> Self {
        let mut h = SVector::<f64, D>::zeros();
        let mut node_dims = [0; D];
        for d in 0..D {
            h[d] = (upper[d] - lower[d]) / cells[d] as f64;
            node_dims[d] = cells[d] + 1 + 2 * GHOST;
        }
        Self {
            lower,
            upper,
            cells,
            h,
            inv_h: h.map(|v| 1.0 / v),
            node_dims,
            bc,
            axisymmetric: false,
        }
    }

    /// Total number of nodes including ghosts.
    pub fn num_nodes(&self) -> usize {
        self.node_dims.iter().product()
    }

    /// Total number of cells inside the domain.
    pub fn num_cells(&self) -> usize {
        self.cells.iter().product()
    }

    /// Stride of the flat node index along each direction.
    pub fn strides(&self) -> [usize; D] {
        let mut s = [1; D];
        for d in 1..D {
            s[d] = s[d - 1] * self.node_dims[d - 1];
        }
        s
    }

    /// Flat index of the node with grid coordinates `i` (node 0 on the lower
    /// boundary; ghosts have negative or `> cells` coordinates).
    #[inline]
    pub fn node_index(&self, i: [isize; D]) -> usize {
        let mut idx = 0usize;
        let mut stride = 1usize;
        for d in 0..D {
            idx += (i[d] + GHOST as isize) as usize * stride;
            stride *= self.node_dims[d];
        }
        idx
    }

    /// Grid coordinates of a flat node index (inverse of [`Self::node_index`]).
    pub fn node_coords(&self, mut idx: usize) -> [isize; D] {
        let mut c = [0isize; D];
        for d in 0..D {
            c[d] = (idx % self.node_dims[d]) as isize - GHOST as isize;
            idx /= self.node_dims[d];
        }
        c
    }

    /// Position of the node with grid coordinates `i`.
    pub fn node_position(&self, i: [isize; D]) -> SVector<f64, D> {
        let mut x = self.lower;
        for d in 0..D {
            x[d] += i[d] as f64 * self.h[d];
        }
        x
    }

    /// Position in node units: `(x - lower) / h`.
    #[inline]
    pub fn to_grid_units(&self, x: &SVector<f64, D>) -> SVector<f64, D> {
        (x - self.lower).component_mul(&self.inv_h)
    }

    /// Volume of one cell.
    pub fn cell_volume(&self) -> f64 {
        self.h.iter().product()
    }

    /// Whether a position in node units lies where every shape function's
    /// stencil stays on the grid (within one cell outside the domain).
    #[inline]
    pub fn holds(&self, xi: &SVector<f64, D>) -> bool {
        (0..D).all(|d| xi[d] >= -1.0 && xi[d] < self.cells[d] as f64 + 1.0)
    }

    /// Folds what P2G put on ghost nodes back onto the domain, as if mirror
    /// images of the particles stood beyond every `Fixed` or `Symmetry` face:
    /// node `k` inside gains the reflected value of ghost node `−k`, and the
    /// boundary node gains its own reflection (mass doubles; odd components
    /// cancel). Odd components are all of them on a `Fixed` face (no-slip) and
    /// the normal one on a `Symmetry` face. Applied to nodal mass, momentum and
    /// force, this gives every shape function, however wide, the consistent
    /// boundary treatment; ghosts are cleared afterwards. Along a `Periodic`
    /// axis the ghosts beyond one face are the nodes inside the other: ghost
    /// `−k` adds onto node `n − k`, ghost `n + k` onto node `k`, and the two
    /// boundary nodes `0` and `n`, one node of the periodic grid, both get
    /// their sum. Axis by axis, so corners fold once per axis.
    pub fn fold_ghosts<T: Reflect<D>>(&self, q: &mut [T]) {
        for axis in 0..D {
            if self.periodic(axis) {
                self.for_each_periodic_pair(axis, |ghost, inner| {
                    q[inner] = q[inner].add(&q[ghost]);
                    q[ghost] = T::zero();
                });
                self.for_each_boundary_pair(axis, |lo, hi| {
                    let s = q[lo].add(&q[hi]);
                    q[lo] = s;
                    q[hi] = s;
                });
                continue;
            }
            self.for_each_mirror_pair(axis, |ghost, mirror, axis, bc| {
                if ghost == mirror {
                    let r = q[ghost].reflect(axis, bc);
                    q[ghost] = q[ghost].add(&r);
                } else {
                    let r = q[ghost].reflect(axis, bc);
                    q[mirror] = q[mirror].add(&r);
                    q[ghost] = T::zero();
                }
            });
        }
    }

    /// [`Self::fold_ghosts`] at one node for a value that puts nothing on
    /// the ghosts (a body mapped by the linear hat from inside the grid):
    /// only a node on a `Fixed` or `Symmetry` face changes, to
    /// `q + reflect(q)` (it holds a point and its mirror image), face by
    /// face as the fold does.
    pub fn fold_on_faces<T: Reflect<D>>(&self, i: usize, mut q: T) -> T {
        let c = self.node_coords(i);
        for axis in 0..D {
            for (side, layer) in [(0, 0), (1, self.cells[axis] as isize)] {
                let bc = self.bc[axis][side];
                if c[axis] == layer && matches!(bc, Boundary::Fixed | Boundary::Symmetry) {
                    q = q.add(&q.reflect(axis, bc));
                }
            }
        }
        q
    }

    /// Sets every ghost node beyond a `Fixed` or `Symmetry` face to the
    /// reflection of its mirror node inside (the counterpart of
    /// [`Self::fold_ghosts`] for grid velocities and accelerations); along a
    /// `Periodic` axis, to the value of the node it stands for inside.
    pub fn mirror_ghosts<T: Reflect<D>>(&self, q: &mut [T]) {
        for axis in 0..D {
            if self.periodic(axis) {
                self.for_each_periodic_pair(axis, |ghost, inner| q[ghost] = q[inner]);
                continue;
            }
            self.for_each_mirror_pair(axis, |ghost, mirror, axis, bc| {
                if ghost != mirror {
                    q[ghost] = q[mirror].reflect(axis, bc);
                }
            });
        }
    }

    /// Every node that [`Self::fold_ghosts`] reads or changes at a `Fixed`
    /// or `Symmetry` face (ghost layers and their mirror layers inside,
    /// boundary layers included), sorted, each once; empty without such
    /// faces. Elsewhere the fold leaves a nodal value as the particles put
    /// it.
    pub fn mirrored_nodes(&self) -> Vec<usize> {
        let mut nodes = Vec::new();
        for axis in 0..D {
            if self.periodic(axis) {
                continue;
            }
            self.for_each_mirror_pair(axis, |ghost, mirror, _, _| {
                nodes.push(ghost);
                nodes.push(mirror);
            });
        }
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }

    /// Whether `axis` is periodic (the scene sets both faces alike).
    #[inline]
    pub fn periodic(&self, axis: usize) -> bool {
        self.bc[axis][0] == Boundary::Periodic
    }

    /// Whether any axis is periodic.
    pub fn any_periodic(&self) -> bool {
        (0..D).any(|d| self.periodic(d))
    }

    /// Brings a position back into the domain along the periodic axes
    /// (`lower ≤ x < upper`); other axes are left alone.
    #[inline]
    pub fn wrap(&self, x: &mut SVector<f64, D>) {
        for d in 0..D {
            if self.periodic(d) {
                let len = self.upper[d] - self.lower[d];
                let mut r = (x[d] - self.lower[d]).rem_euclid(len);
                if r >= len {
                    r = 0.0;
                }
                x[d] = self.lower[d] + r;
            }
        }
    }

    /// Calls `f(ghost, inner)` for every ghost node of a periodic axis and
    /// the node inside that it stands for (ghost `−k` ↔ `n − k`, ghost
    /// `n + k` ↔ `k`; ghosts of the other axes included).
    fn for_each_periodic_pair(&self, axis: usize, mut f: impl FnMut(usize, usize)) {
        let strides = self.strides();
        let n = self.cells[axis] as isize;
        for k in 1..=GHOST as isize {
            for (ghost, inner) in [(-k, n - k), (n + k, k)] {
                let shift = (inner - ghost) * strides[axis] as isize;
                self.for_each_node_in_layer(axis, ghost, |g| f(g, (g as isize + shift) as usize));
            }
        }
    }

    /// Calls `f(lower, upper)` for every pair of nodes on the two boundary
    /// layers of `axis` that face each other.
    fn for_each_boundary_pair(&self, axis: usize, mut f: impl FnMut(usize, usize)) {
        let strides = self.strides();
        let shift = self.cells[axis] * strides[axis];
        self.for_each_node_in_layer(axis, 0, |lo| f(lo, lo + shift));
    }

    /// Calls `f(ghost, mirror, axis, bc)` for every ghost layer of each
    /// non-free, non-periodic face of `axis` and then every node of its
    /// boundary layers (with `ghost == mirror`); the callers go axis by axis
    /// so that corners fold twice.
    ///
    /// Within an axis the ghosts of both faces go first, outermost in, and
    /// the boundary layers last. Where the domain is thick, no ghost of one
    /// face folds onto a boundary layer, so the order is immaterial. Where it
    /// is one cell thick (a strip, with a stencil that reaches a ghost), the
    /// ghost beyond one face folds onto the other face's boundary layer, and
    /// the mirror images beyond that face must reflect it again (the images
    /// of a strip between two mirrors repeat with period 2h): folding the
    /// boundary layers last does that for both faces alike. Folding one
    /// face's boundary layer before the other face's ghosts reflected the
    /// lower face's ghost twice and the upper face's once, and a gas at rest
    /// on a one-cell strip with quadratic B-splines then drifted (ρ up to
    /// 1.017 and |v| 0.79 by t = 0.1, `probes/src/bin/york_sod_probe.rs`, `CASE=rest
    /// SHAPE=q`).
    fn for_each_mirror_pair(&self, axis: usize, mut f: impl FnMut(usize, usize, usize, Boundary)) {
        let strides = self.strides();
        {
            let n = self.cells[axis] as isize;
            for k in (0..=GHOST as isize).rev() {
                // k = GHOST … 1: ghost layers; k = 0: boundary layers.
                if k > n {
                    continue;
                }
                for side in 0..2 {
                    let bc = self.bc[axis][side];
                    if matches!(bc, Boundary::Free | Boundary::Periodic) {
                        continue;
                    }
                    let (ghost, mirror) = if side == 0 { (-k, k) } else { (n + k, n - k) };
                    let shift = (mirror - ghost) * strides[axis] as isize;
                    self.for_each_node_in_layer(axis, ghost, |g| {
                        f(g, (g as isize + shift) as usize, axis, bc)
                    });
                }
            }
        }
    }

    /// Calls `f` with the flat index of every node whose coordinate along
    /// `axis` equals `layer` (ghosts included in the other directions).
    pub fn for_each_node_in_layer(&self, axis: usize, layer: isize, mut f: impl FnMut(usize)) {
        let strides = self.strides();
        let base = (layer + GHOST as isize) as usize * strides[axis];
        let total: usize = (0..D)
            .filter(|&d| d != axis)
            .map(|d| self.node_dims[d])
            .product();
        for k in 0..total {
            let mut rem = k;
            let mut idx = base;
            for d in 0..D {
                if d == axis {
                    continue;
                }
                idx += (rem % self.node_dims[d]) * strides[d];
                rem /= self.node_dims[d];
            }
            f(idx);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_index_round_trip() {
        let g = Grid::<2>::new(
            SVector::from([0.0, 0.0]),
            SVector::from([1.0, 2.0]),
            [4, 8],
            [[Boundary::Free; 2]; 2],
        );
        for idx in 0..g.num_nodes() {
            assert_eq!(g.node_index(g.node_coords(idx)), idx);
        }
        assert_eq!(g.node_position([4, 8]), SVector::from([1.0, 2.0]));
    }

    #[test]
    fn folding_mirrors_momentum_and_doubles_boundary_mass() {
        let g = Grid::<2>::new(
            SVector::from([0.0, 0.0]),
            SVector::from([1.0, 1.0]),
            [4, 4],
            [
                [Boundary::Symmetry, Boundary::Free],
                [Boundary::Fixed, Boundary::Free],
            ],
        );
        let mut m = vec![1.0; g.num_nodes()];
        let mut v = vec![SVector::from([1.0, 2.0]); g.num_nodes()];
        g.fold_ghosts(&mut m);
        g.fold_ghosts(&mut v);
        // x = 0 symmetry: boundary node doubles mass, normal momentum cancels.
        // (Row y = 3 is untouched by the y = 0 face, whose ghosts fold onto y = 1, 2.)
        assert_eq!(m[g.node_index([0, 3])], 2.0);
        assert_eq!(v[g.node_index([0, 3])], SVector::from([0.0, 4.0]));
        // Interior node x = 1 gains ghost x = -1 reflected: (1,2) + (-1,2).
        assert_eq!(v[g.node_index([1, 3])], SVector::from([0.0, 4.0]));
        assert_eq!(m[g.node_index([1, 3])], 2.0);
        assert_eq!(v[g.node_index([-1, 3])], SVector::<f64, 2>::zeros());
        // Row y = 2 gains the y = -2 ghost row as well: mass 1 + 1 (x) then + 2 (y).
        assert_eq!(m[g.node_index([1, 2])], 4.0);
        // y = 0 fixed: everything odd, boundary node momentum vanishes.
        assert_eq!(v[g.node_index([3, 0])], SVector::<f64, 2>::zeros());
        let mut w = vec![SVector::from([1.0, 2.0]); g.num_nodes()];
        g.mirror_ghosts(&mut w);
        assert_eq!(w[g.node_index([-2, 3])], SVector::from([-1.0, 2.0]));
        assert_eq!(w[g.node_index([3, -1])], SVector::from([-1.0, -2.0]));
    }

    #[test]
    fn periodic_folding_wraps_ghosts_and_joins_the_boundary_nodes() {
        let g = Grid::<2>::new(
            SVector::from([0.0, 0.0]),
            SVector::from([1.0, 1.0]),
            [4, 4],
            [[Boundary::Periodic; 2], [Boundary::Fixed, Boundary::Fixed]],
        );
        let mut m = vec![0.0; g.num_nodes()];
        // Ghost x = -1 stands for x = 3; ghost x = 6 for x = 2; x = 4 is x = 0.
        m[g.node_index([-1, 2])] = 1.0;
        m[g.node_index([6, 2])] = 2.0;
        m[g.node_index([4, 2])] = 4.0;
        m[g.node_index([0, 2])] = 8.0;
        g.fold_ghosts(&mut m);
        assert_eq!(m[g.node_index([3, 2])], 1.0);
        assert_eq!(m[g.node_index([2, 2])], 2.0);
        assert_eq!(m[g.node_index([0, 2])], 12.0);
        assert_eq!(m[g.node_index([4, 2])], 12.0);
        assert_eq!(m[g.node_index([-1, 2])], 0.0);
        let mut v: Vec<f64> = (0..g.num_nodes()).map(|i| i as f64).collect();
        g.mirror_ghosts(&mut v);
        assert_eq!(v[g.node_index([-2, 1])], v[g.node_index([2, 1])]);
        assert_eq!(v[g.node_index([5, 1])], v[g.node_index([1, 1])]);
        let mut x = SVector::from([-0.25, 0.5]);
        g.wrap(&mut x);
        assert_eq!(x, SVector::from([0.75, 0.5]));
        let mut x = SVector::from([1.0, 0.5]);
        g.wrap(&mut x);
        assert_eq!(x, SVector::from([0.0, 0.5]));
    }
}
