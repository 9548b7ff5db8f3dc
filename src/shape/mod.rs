//! MPM shape functions: linear hat, uGIMP, quadratic and cubic B-splines,
//! and the quadratic B-spline integrated over the particle domain.
//!
//! All are tensor products of 1D functions of `r = ξ − i`, the distance from
//! node `i` in cell units (`ξ = (x − x_lower)/h`). Each 1D evaluation returns the
//! first node of a fixed-width stencil and the weights and derivatives (with
//! respect to ξ; divide by h for the physical gradient) on its `S` nodes, so hot
//! loops are monomorphised over `S`.

use nalgebra::SVector;

/// Which shape function the background grid uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    /// Piecewise-linear hat (classic MPM, Sulsky et al.); support 2 nodes.
    Linear,
    /// Uniform GIMP (Bardenhagen & Kober): hat convolved with the particle's
    /// characteristic function of half-width `lp`; support 3 nodes.
    Gimp,
    /// Quadratic B-spline; support 3 nodes.
    QuadraticBspline,
    /// Cubic B-spline; support 4 nodes.
    CubicBspline,
    /// Quadratic B-spline averaged over the particle's domain of half-width
    /// `lp` (B-spline GIMP: the B-spline convolved with the particle's
    /// characteristic function, as uGIMP does for the hat); support 4 nodes.
    /// Removes the particle-quadrature error that stalls the point-sampled
    /// B-splines under large stretch (verification `mpm_mms_axis_aligned`).
    QuadraticBsplineGimp,
}

impl ShapeKind {
    /// Stencil width per direction.
    pub const fn stencil(self) -> usize {
        match self {
            ShapeKind::Linear => 2,
            ShapeKind::Gimp | ShapeKind::QuadraticBspline => 3,
            ShapeKind::CubicBspline | ShapeKind::QuadraticBsplineGimp => 4,
        }
    }

    /// Whether the weights depend on the particle's domain half-width `lp`
    /// (the GIMP family); the others ignore it.
    pub const fn uses_particle_domain(self) -> bool {
        matches!(self, ShapeKind::Gimp | ShapeKind::QuadraticBsplineGimp)
    }

    /// Every kind, in the order of [`Self::NAMES`].
    pub const ALL: [ShapeKind; 5] = [
        ShapeKind::Linear,
        ShapeKind::Gimp,
        ShapeKind::QuadraticBspline,
        ShapeKind::CubicBspline,
        ShapeKind::QuadraticBsplineGimp,
    ];

    /// The name of this kind in scene files (one of [`Self::NAMES`]).
    pub const fn name(self) -> &'static str {
        match self {
            ShapeKind::Linear => "linear",
            ShapeKind::Gimp => "gimp",
            ShapeKind::QuadraticBspline => "quadratic_bspline",
            ShapeKind::CubicBspline => "cubic_bspline",
            ShapeKind::QuadraticBsplineGimp => "quadratic_bspline_gimp",
        }
    }

    /// Names accepted in scene files.
    pub const NAMES: &'static str =
        "linear, gimp, quadratic_bspline, cubic_bspline, quadratic_bspline_gimp";

    /// The 1D shape function of a node at distance `r` from it (cell
    /// units); the GIMP kernels as their `lp → 0` limits (the hat, the
    /// quadratic B-spline). For set-up integrals
    /// (the nodal volumes of an r–z grid), not for hot loops.
    pub fn value(self, r: f64) -> f64 {
        fn node0<const S: usize>(q: Weights1<S>) -> f64 {
            usize::try_from(-q.base)
                .ok()
                .and_then(|k| q.w.get(k).copied())
                .unwrap_or(0.0)
        }
        match self {
            ShapeKind::Linear | ShapeKind::Gimp => node0(linear(r)),
            ShapeKind::QuadraticBspline | ShapeKind::QuadraticBsplineGimp => {
                node0(quadratic_bspline(r))
            }
            ShapeKind::CubicBspline => node0(cubic_bspline(r)),
        }
    }
}

/// 1D weights on a stencil of `S` nodes starting at node `base`.
#[derive(Debug, Clone, Copy)]
pub struct Weights1<const S: usize> {
    /// First node of the stencil.
    pub base: isize,
    /// Shape function values.
    pub w: [f64; S],
    /// Derivatives with respect to ξ (cell units).
    pub dw: [f64; S],
}

/// ⌊x⌋ for x > −16 by a truncating cast (a single instruction; `f64::floor`
/// is a libm call on baseline x86-64). Particles on the grid always satisfy
/// the bound (they stay within one cell of the domain, see `Grid::holds`).
#[inline(always)]
fn floor_on_grid(x: f64) -> f64 {
    ((x + 16.0) as i64 - 16) as f64
}

/// Linear hat on 2 nodes.
#[inline(always)]
pub fn linear(xi: f64) -> Weights1<2> {
    let base = floor_on_grid(xi);
    let f = xi - base;
    Weights1 {
        base: base as isize,
        w: [1.0 - f, f],
        dw: [-1.0, 1.0],
    }
}

/// uGIMP on 3 nodes, particle half-width `lp` in cell units (0 < lp ≤ 0.5).
///
/// S(r) = 1 − (r² + lp²)/(2 lp) for |r| < lp; 1 − |r| for lp ≤ |r| < 1 − lp;
/// (1 + lp − |r|)²/(4 lp) for 1 − lp ≤ |r| < 1 + lp; 0 beyond.
#[inline(always)]
pub fn gimp(xi: f64, lp: f64) -> Weights1<3> {
    let base = floor_on_grid(xi - lp);
    let mut w = [0.0; 3];
    let mut dw = [0.0; 3];
    for k in 0..3 {
        let r = xi - (base + k as f64);
        let a = r.abs();
        let s = r.signum();
        if a < lp {
            w[k] = 1.0 - (r * r + lp * lp) / (2.0 * lp);
            dw[k] = -r / lp;
        } else if a < 1.0 - lp {
            w[k] = 1.0 - a;
            dw[k] = -s;
        } else if a < 1.0 + lp {
            let q = 1.0 + lp - a;
            w[k] = q * q / (4.0 * lp);
            dw[k] = -s * q / (2.0 * lp);
        }
    }
    Weights1 {
        base: base as isize,
        w,
        dw,
    }
}

/// Quadratic B-spline on 3 nodes: 3/4 − r² for |r| < 1/2, (3/2 − |r|)²/2 for
/// 1/2 ≤ |r| < 3/2.
#[inline(always)]
pub fn quadratic_bspline(xi: f64) -> Weights1<3> {
    let base = floor_on_grid(xi - 0.5);
    // Distances to the three nodes: r0 ∈ [0.5, 1.5), r1 ∈ [-0.5, 0.5), r2 ∈ [-1.5, -0.5).
    let f = xi - base; // ∈ [0.5, 1.5)
    let a = 1.5 - f;
    let b = f - 1.0;
    let c = f - 0.5;
    Weights1 {
        base: base as isize,
        w: [0.5 * a * a, 0.75 - b * b, 0.5 * c * c],
        dw: [-a, -2.0 * b, c],
    }
}

/// Cubic B-spline on 4 nodes: |r|³/2 − r² + 2/3 for |r| < 1, (2 − |r|)³/6 for
/// 1 ≤ |r| < 2.
#[inline(always)]
pub fn cubic_bspline(xi: f64) -> Weights1<4> {
    let base = floor_on_grid(xi) - 1.0;
    // f ∈ [1, 2): distances f, f − 1, f − 2, f − 3 each fall in a fixed piece,
    // so the weights are branch-free: with g = f − 1 ∈ [0, 1) and a = 1 − g,
    // w = (a³/6, g³/2 − g² + 2/3, a³/2 − a² + 2/3, g³/6).
    let g = xi - base - 1.0;
    let a = 1.0 - g;
    let (g2, a2) = (g * g, a * a);
    Weights1 {
        base: base as isize,
        w: [
            a2 * a / 6.0,
            0.5 * g2 * g - g2 + 2.0 / 3.0,
            0.5 * a2 * a - a2 + 2.0 / 3.0,
            g2 * g / 6.0,
        ],
        dw: [-0.5 * a2, 1.5 * g2 - 2.0 * g, -1.5 * a2 + 2.0 * a, 0.5 * g2],
    }
}

/// The quadratic B-spline of one node at distance `r` (cell units) and its
/// derivative.
#[inline(always)]
fn quadratic_bspline_node(r: f64) -> (f64, f64) {
    let a = r.abs();
    if a < 0.5 {
        (0.75 - r * r, -2.0 * r)
    } else if a < 1.5 {
        let q = 1.5 - a;
        (0.5 * q * q, -r.signum() * q)
    } else {
        (0.0, 0.0)
    }
}

/// ∫₋∞^r of the quadratic B-spline of one node: 0 below −3/2, (r + 3/2)³/6 up
/// to −1/2, 1/6 + 3(r + 1/2)/4 − (r³ + 1/8)/3 up to 1/2, 1 − (3/2 − r)³/6 up
/// to 3/2, and 1 beyond.
#[inline(always)]
fn quadratic_bspline_cumulative(r: f64) -> f64 {
    if r <= -1.5 {
        0.0
    } else if r <= -0.5 {
        let q = r + 1.5;
        q * q * q / 6.0
    } else if r <= 0.5 {
        1.0 / 6.0 + 0.75 * (r + 0.5) - (r * r * r + 0.125) / 3.0
    } else if r <= 1.5 {
        let q = 1.5 - r;
        1.0 - q * q * q / 6.0
    } else {
        1.0
    }
}

/// Quadratic B-spline averaged over the particle domain [ξ − lp, ξ + lp]
/// (0 ≤ lp ≤ 1/2, cell units) on 4 nodes:
/// S̄(r) = [C(r + lp) − C(r − lp)]/(2 lp), dS̄/dξ = [N(r + lp) − N(r − lp)]/(2 lp),
/// N the quadratic B-spline and C its integral. The stencil starts at the
/// first node within 3/2 + lp of ξ, ⌊ξ − lp − 1/2⌋. Below lp = 10⁻⁴ (where
/// the difference quotient loses digits) the point values are used: the
/// averaged spline differs from them by O(lp²).
#[inline(always)]
pub fn quadratic_bspline_gimp(xi: f64, lp: f64) -> Weights1<4> {
    let base = floor_on_grid(xi - lp - 0.5);
    let mut w = [0.0; 4];
    let mut dw = [0.0; 4];
    for k in 0..4 {
        let r = xi - (base + k as f64);
        if lp < 1e-4 {
            (w[k], dw[k]) = quadratic_bspline_node(r);
        } else {
            let inv = 0.5 / lp;
            w[k] =
                (quadratic_bspline_cumulative(r + lp) - quadratic_bspline_cumulative(r - lp)) * inv;
            dw[k] = (quadratic_bspline_node(r + lp).0 - quadratic_bspline_node(r - lp).0) * inv;
        }
    }
    Weights1 {
        base: base as isize,
        w,
        dw,
    }
}

/// Evaluates a shape function with stencil `S` along every direction.
pub trait Stencil<const S: usize>: Copy + Send + Sync {
    /// 1D weights at `xi` (cell units) for particle half-width `lp` (cell units).
    fn eval(self, xi: f64, lp: f64) -> Weights1<S>;
}

/// Marker for the linear hat.
#[derive(Debug, Clone, Copy)]
pub struct LinearHat;
/// Marker for uGIMP.
#[derive(Debug, Clone, Copy)]
pub struct Gimp;
/// Marker for the quadratic B-spline.
#[derive(Debug, Clone, Copy)]
pub struct QuadraticBspline;
/// Marker for the cubic B-spline.
#[derive(Debug, Clone, Copy)]
pub struct CubicBspline;
/// Marker for the quadratic B-spline averaged over the particle domain.
#[derive(Debug, Clone, Copy)]
pub struct QuadraticBsplineGimp;

impl Stencil<2> for LinearHat {
    #[inline(always)]
    fn eval(self, xi: f64, _lp: f64) -> Weights1<2> {
        linear(xi)
    }
}
impl Stencil<3> for Gimp {
    #[inline(always)]
    fn eval(self, xi: f64, lp: f64) -> Weights1<3> {
        gimp(xi, lp)
    }
}
impl Stencil<3> for QuadraticBspline {
    #[inline(always)]
    fn eval(self, xi: f64, _lp: f64) -> Weights1<3> {
        quadratic_bspline(xi)
    }
}
impl Stencil<4> for CubicBspline {
    #[inline(always)]
    fn eval(self, xi: f64, _lp: f64) -> Weights1<4> {
        cubic_bspline(xi)
    }
}
impl Stencil<4> for QuadraticBsplineGimp {
    #[inline(always)]
    fn eval(self, xi: f64, lp: f64) -> Weights1<4> {
        quadratic_bspline_gimp(xi, lp)
    }
}

/// Per-direction weights of one particle.
#[derive(Debug, Clone, Copy)]
pub struct ParticleWeights<const D: usize, const S: usize> {
    /// One 1D evaluation per direction.
    pub dirs: [Weights1<S>; D],
}

impl<const D: usize, const S: usize> ParticleWeights<D, S> {
    /// Evaluates `kernel` at position `xi` (cell units) with half-widths `lp`;
    /// gradients in cell units.
    #[inline(always)]
    pub fn new<K: Stencil<S>>(kernel: K, xi: &SVector<f64, D>, lp: &SVector<f64, D>) -> Self {
        Self {
            dirs: std::array::from_fn(|d| kernel.eval(xi[d], lp[d])),
        }
    }

    /// Evaluates `kernel` and scales the derivatives by `inv_h` (1/h per
    /// direction), so [`Self::for_each`] yields physical gradients.
    #[inline(always)]
    pub fn new_physical<K: Stencil<S>>(
        kernel: K,
        xi: &SVector<f64, D>,
        lp: &SVector<f64, D>,
        inv_h: &SVector<f64, D>,
    ) -> Self {
        let mut pw = Self::new(kernel, xi, lp);
        for d in 0..D {
            for k in 0..S {
                pw.dirs[d].dw[k] *= inv_h[d];
            }
        }
        pw
    }

    /// Calls `f(node_offset_multi_index, weight, gradient)` for
    /// every node of the tensor-product stencil (x fastest).
    #[inline(always)]
    pub fn for_each(&self, mut f: impl FnMut([usize; D], f64, SVector<f64, D>)) {
        let total = S.pow(D as u32);
        for k in 0..total {
            let mut rem = k;
            let mut m = [0usize; D];
            for md in m.iter_mut() {
                *md = rem % S;
                rem /= S;
            }
            let mut w = 1.0;
            let mut g = SVector::<f64, D>::repeat(1.0);
            for d in 0..D {
                let wd = self.dirs[d].w[m[d]];
                w *= wd;
                for e in 0..D {
                    g[e] *= if e == d { self.dirs[d].dw[m[d]] } else { wd };
                }
            }
            f(m, w, g);
        }
    }

    /// First node of the stencil in grid coordinates.
    #[inline(always)]
    pub fn base(&self) -> [isize; D] {
        std::array::from_fn(|d| self.dirs[d].base)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_1d<const S: usize>(f: impl Fn(f64) -> Weights1<S>, name: &str) {
        // Partition of unity, linear completeness (Σ N r = 0 ⇒ reproduces x),
        // derivative sums to zero, derivative matches finite differences.
        for k in 0..997 {
            let xi = 3.0 + k as f64 * 0.001003;
            let a = f(xi);
            let sum: f64 = a.w.iter().sum();
            assert!((sum - 1.0).abs() < 1e-13, "{name}: Σw = {sum} at {xi}");
            let first: f64 = (0..S).map(|i| a.w[i] * (a.base + i as isize) as f64).sum();
            assert!(
                (first - xi).abs() < 1e-12,
                "{name}: Σ w x_i = {first} ≠ {xi}"
            );
            let dsum: f64 = a.dw.iter().sum();
            assert!(dsum.abs() < 1e-12, "{name}: Σ dw = {dsum}");
            let dfirst: f64 = (0..S).map(|i| a.dw[i] * (a.base + i as isize) as f64).sum();
            assert!((dfirst - 1.0).abs() < 1e-12, "{name}: Σ dw x_i = {dfirst}");
            let eps = 1e-6;
            let (p, m) = (f(xi + eps), f(xi - eps));
            if p.base == a.base && m.base == a.base {
                for i in 0..S {
                    let fd = (p.w[i] - m.w[i]) / (2.0 * eps);
                    assert!((fd - a.dw[i]).abs() < 1e-6, "{name}: dw[{i}] at {xi}");
                }
            }
        }
    }

    #[test]
    fn one_dimensional_consistency() {
        check_1d(linear, "linear");
        check_1d(|x| gimp(x, 0.25), "gimp lp=0.25");
        check_1d(|x| gimp(x, 0.5), "gimp lp=0.5");
        check_1d(quadratic_bspline, "quadratic");
        check_1d(cubic_bspline, "cubic");
        for lp in [1e-5, 1e-3, 0.125, 0.25, 0.5] {
            check_1d(|x| quadratic_bspline_gimp(x, lp), "quadratic gimp");
        }
    }

    /// Every kind's scene name parses back to it and is listed in `NAMES`.
    #[test]
    fn every_kind_has_its_scene_name() {
        for k in ShapeKind::ALL {
            let parsed: ShapeKind =
                serde_json::from_str(&format!("\"{}\"", k.name())).expect("name parses");
            assert_eq!(parsed, k);
            assert!(ShapeKind::NAMES.split(", ").any(|n| n == k.name()));
        }
        assert_eq!(ShapeKind::NAMES.split(", ").count(), ShapeKind::ALL.len());
    }

    /// The B-spline GIMP weight is the average of the quadratic B-spline over
    /// the particle domain (checked against 2000-point midpoint quadrature,
    /// error O(10⁻⁷)), and tends to the point value as lp → 0.
    #[test]
    fn quadratic_bspline_gimp_is_the_domain_average() {
        for k in 0..97 {
            let xi = 3.0 + k as f64 * 0.0103;
            for lp in [0.05, 0.25, 0.5] {
                let a = quadratic_bspline_gimp(xi, lp);
                for j in 0..4 {
                    let node = (a.base + j as isize) as f64;
                    let m = 2000;
                    let avg: f64 = (0..m)
                        .map(|q| {
                            let x = xi - lp + (q as f64 + 0.5) * 2.0 * lp / m as f64;
                            quadratic_bspline_node(x - node).0
                        })
                        .sum::<f64>()
                        / m as f64;
                    assert!((a.w[j] - avg).abs() < 1e-6, "xi {xi} lp {lp} node {j}");
                }
            }
            let point = quadratic_bspline(xi);
            let small = quadratic_bspline_gimp(xi, 2e-4);
            for j in 0..3 {
                let jj = (point.base + j as isize - small.base) as usize;
                assert!((small.w[jj] - point.w[j]).abs() < 1e-7);
                assert!((small.dw[jj] - point.dw[j]).abs() < 1e-3);
            }
        }
    }

    /// Partition of unity (Σ w = 1), linear reproduction (Σ w x_i = x) and
    /// gradient consistency (Σ ∇w = 0, Σ x_i ⊗ ∇w = I) of the tensor product,
    /// in physical units with anisotropic cells.
    fn check_tensor<const D: usize, const S: usize, K: Stencil<S>>(kernel: K, name: &str) {
        let h = SVector::<f64, D>::from_fn(|d, _| 0.1 + 0.05 * d as f64);
        let inv_h = h.map(|v| 1.0 / v);
        let lp = SVector::<f64, D>::repeat(0.25);
        for k in 0..200 {
            let xi = SVector::<f64, D>::from_fn(|d, _| {
                3.0 + ((k * (7 + 3 * d)) % 200) as f64 * 0.00497 + 0.1 * d as f64
            });
            let pw = ParticleWeights::<D, S>::new_physical(kernel, &xi, &lp, &inv_h);
            let base = pw.base();
            let mut sum = 0.0;
            let mut first = SVector::<f64, D>::zeros();
            let mut gsum = SVector::<f64, D>::zeros();
            let mut gx = nalgebra::SMatrix::<f64, D, D>::zeros();
            pw.for_each(|m, w, g| {
                let xn = SVector::<f64, D>::from_fn(|d, _| (base[d] + m[d] as isize) as f64 * h[d]);
                sum += w;
                first += xn * w;
                gsum += g;
                gx += xn * g.transpose();
            });
            let x = xi.component_mul(&h);
            assert!((sum - 1.0).abs() < 1e-13, "{name} {D}D: Σw = {sum}");
            assert!((first - x).norm() < 1e-13, "{name} {D}D: Σ w x_i ≠ x");
            assert!(gsum.norm() < 1e-11, "{name} {D}D: Σ∇w = {gsum}");
            let err = (gx - nalgebra::SMatrix::<f64, D, D>::identity()).norm();
            assert!(err < 1e-12, "{name} {D}D: Σ x_i ⊗ ∇w ≠ I ({err})");
        }
    }

    #[test]
    fn tensor_products_are_consistent_in_every_dimension() {
        macro_rules! all_dims {
            ($k:expr, $s:literal, $n:literal) => {
                check_tensor::<1, $s, _>($k, $n);
                check_tensor::<2, $s, _>($k, $n);
                check_tensor::<3, $s, _>($k, $n);
            };
        }
        all_dims!(LinearHat, 2, "linear");
        all_dims!(Gimp, 3, "gimp");
        all_dims!(QuadraticBspline, 3, "quadratic");
        all_dims!(CubicBspline, 4, "cubic");
        all_dims!(QuadraticBsplineGimp, 4, "quadratic gimp");
    }
}
