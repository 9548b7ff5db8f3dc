//! Nonlocal (integral) averaging of the damage increment, the
//! regularisation of a softening failure model that makes the failure
//! zone's width a material length instead of the particle spacing.
//!
//! With a local Johnson–Cook damage (Johnson & Cook 1985, Eq. 1: D = Σ
//! Δε̄/ε_f per point) the failure localises into the smallest band the
//! discretisation can carry: at a notch the first point fails when the
//! strain concentration *it resolves* reaches ε_f, and finer particles
//! resolve more of the concentration, so they fail earlier. The integral
//! nonlocal model (Pijaudier-Cabot & Bažant 1987, *Nonlocal damage
//! theory*, J. Eng. Mech. 113; the averaging of Bažant & Jirásek 2002,
//! *Nonlocal integral formulations of plasticity and damage: survey of
//! progress*, J. Eng. Mech. 128, Eqs. 1–2) drives the damage with the
//! weighted average of the local driving variable over a neighbourhood of
//! fixed size:
//!
//! ΔD̄_p = Σ_q w(|x_p − x_q|) V_q ΔD_q / Σ_q w(|x_p − x_q|) V_q,
//!
//! with the truncated quartic ("bell") weight w(r) = (1 − r²/R²)² for r <
//! R and 0 beyond (Bažant & Jirásek 2002, Eq. 8), R the interaction
//! radius. Here the driving variable is the local damage increment of the
//! step, ΔD_q = Δε̄_q/ε_f,q (each point's own triaxiality, rate and
//! temperature enter through its ε_f), the sum runs over the intact points
//! of the same material (failed points carry no more plastic strain and
//! other materials are not the same continuum), and the denominator
//! renormalises the weight near free surfaces and cracks. A face with a
//! symmetry condition is a mirror: the neighbourhood includes the mirror
//! images of the points within R of it, so a quarter model averages as the
//! whole would. In r–z the average is taken in the (r, z) plane with the
//! points' volumes per radian (not the solid ring's true 3D neighbourhood).
//!
//! Neighbours are found by sorting the averaged points by the bin of size
//! R (the largest radius of any material) that holds them; each point
//! looks in the 3^D bins around itself and around each of its mirror
//! images. The sort and the averages reuse their buffers, so a step
//! allocates nothing once the particle count has been reached.

use nalgebra::SVector;
use rayon::prelude::*;

use crate::grid::{Boundary, Grid};

/// The buffers of the nonlocal pass, kept from step to step.
#[derive(Debug, Clone, Default)]
pub struct NonlocalDamage<const D: usize> {
    /// This step's local damage increment ΔD_p of each particle; negative
    /// for a particle that is not averaged (another material, a local
    /// model, or failed before the step).
    pub increment: Vec<f64>,
    /// The interaction radius R of each material (0: local).
    pub radius: Vec<f64>,
    /// The averaged points, sorted by bin.
    sorted: Vec<([i64; D], u32)>,
    /// The averaged increment ΔD̄_p (NaN for a particle not averaged).
    pub average: Vec<f64>,
}

/// The bell weight w(r) = (1 − r²/R²)² inside R, from r² and R².
#[inline]
fn bell(r2: f64, big_r2: f64) -> f64 {
    if r2 >= big_r2 {
        0.0
    } else {
        let s = 1.0 - r2 / big_r2;
        s * s
    }
}

/// The bin of `x` for bins of size `size` from the origin.
#[inline]
fn bin_of<const D: usize>(x: &SVector<f64, D>, size: f64) -> [i64; D] {
    let mut b = [0i64; D];
    for a in 0..D {
        // Positions are finite (the step stops on a non-finite one), so
        // the cast saturates only for absurd sizes.
        b[a] = (x[a] / size).floor() as i64;
    }
    b
}

impl<const D: usize> NonlocalDamage<D> {
    /// Takes the materials' radii and, when some material averages, sizes
    /// the increments to `np` particles (each −1, not averaged, until the
    /// update writes it); returns whether any material averages. A run
    /// whose failure is local keeps no per-particle buffer. No allocation
    /// once these counts have been seen.
    pub fn prepare(&mut self, np: usize, radii: impl Iterator<Item = f64>) -> bool {
        self.radius.clear();
        self.radius.extend(radii);
        let any = self.any();
        if any {
            self.increment.clear();
            self.increment.resize(np, -1.0);
        }
        any
    }

    /// Whether any material averages its damage.
    pub fn any(&self) -> bool {
        self.radius.iter().any(|&r| r > 0.0)
    }

    /// Computes [`Self::average`] from [`Self::increment`]: ΔD̄_p for every
    /// particle with ΔD_p ≥ 0, over the particles of its material (`material`)
    /// with ΔD_q ≥ 0, at positions `x` with current volumes `vol`, mirrored
    /// across the `grid`'s symmetry faces (module doc).
    pub fn average_increments(
        &mut self,
        grid: &Grid<D>,
        x: &[SVector<f64, D>],
        vol: &[f64],
        material: &[u16],
    ) {
        let np = self.increment.len();
        let size = self.radius.iter().copied().fold(0.0, f64::max);
        self.average.clear();
        self.average.resize(np, f64::NAN);
        if size <= 0.0 {
            return;
        }
        let inc = &self.increment;
        self.sorted.clear();
        self.sorted.extend(
            (0..np)
                .filter(|&p| inc[p] >= 0.0)
                .map(|p| (bin_of(&x[p], size), p as u32)),
        );
        self.sorted.par_sort_unstable();
        let sorted = &self.sorted;
        let radius = &self.radius;
        self.average
            .par_iter_mut()
            .enumerate()
            .with_min_len(256)
            .for_each(|(p, out)| {
                if inc[p] < 0.0 {
                    return;
                }
                let mat = material[p];
                let r = radius[mat as usize];
                let r2 = r * r;
                let (mut num, mut den) = (0.0, 0.0);
                for_each_image(grid, &x[p], r, |xi| {
                    for_each_neighbour_bin(bin_of(&xi, size), |b| {
                        let start = sorted.partition_point(|(k, _)| *k < b);
                        for &(k, q) in &sorted[start..] {
                            if k != b {
                                break;
                            }
                            let q = q as usize;
                            if material[q] != mat {
                                continue;
                            }
                            let w = bell((x[q] - xi).norm_squared(), r2) * vol[q];
                            num += w * inc[q];
                            den += w;
                        }
                    });
                });
                // The point itself is in its own neighbourhood (w = 1), so
                // den > 0 unless its volume is zero.
                *out = if den > 0.0 { num / den } else { inc[p] };
            });
    }
}

/// Calls `f` for `x` and each of its mirror images across the grid's
/// symmetry faces that lie within `r` of it (and their combinations at
/// corners). Reflecting the point instead of its neighbours gives the same
/// distances: |x_p′ − x_q| = |x_p − x_q′|.
fn for_each_image<const D: usize>(
    grid: &Grid<D>,
    x: &SVector<f64, D>,
    r: f64,
    mut f: impl FnMut(SVector<f64, D>),
) {
    // Per axis: the point itself, and up to two reflections.
    let mut choices = [[None::<f64>; 3]; D];
    for a in 0..D {
        choices[a][0] = Some(x[a]);
        let [lo, hi] = grid.bc[a];
        if lo == Boundary::Symmetry && x[a] - grid.lower[a] < r {
            choices[a][1] = Some(2.0 * grid.lower[a] - x[a]);
        }
        if hi == Boundary::Symmetry && grid.upper[a] - x[a] < r {
            choices[a][2] = Some(2.0 * grid.upper[a] - x[a]);
        }
    }
    let mut pick = [0usize; D];
    loop {
        if (0..D).all(|a| choices[a][pick[a]].is_some()) {
            let mut xi = *x;
            for a in 0..D {
                xi[a] = choices[a][pick[a]].unwrap_or(x[a]);
            }
            f(xi);
        }
        if !next_of_three(&mut pick) {
            return;
        }
    }
}

/// Steps `digits` (each 0, 1 or 2) to the next of the 3^D combinations,
/// the first fastest; `false` after the last.
fn next_of_three<const D: usize>(digits: &mut [usize; D]) -> bool {
    for d in digits.iter_mut() {
        *d += 1;
        if *d < 3 {
            return true;
        }
        *d = 0;
    }
    false
}

/// Calls `f` with each of the 3^D bins around `b` (itself included).
fn for_each_neighbour_bin<const D: usize>(b: [i64; D], mut f: impl FnMut([i64; D])) {
    let mut d = [0usize; D];
    loop {
        let mut n = b;
        for a in 0..D {
            n[a] += d[a] as i64 - 1;
        }
        f(n);
        if !next_of_three(&mut d) {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    fn grid(bc: Boundary) -> Grid<2> {
        Grid::new(
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, 1.0),
            [10, 10],
            [[bc, bc], [bc, bc]],
        )
    }

    /// Points on a jittered lattice in the unit square, volume h².
    fn lattice(n: usize) -> (Vec<Vector2<f64>>, Vec<f64>) {
        let h = 1.0 / n as f64;
        let mut x = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let jit = 0.1 * h * (((i * 7 + j * 13) % 5) as f64 / 5.0 - 0.4);
                x.push(Vector2::new(
                    (i as f64 + 0.5) * h + jit,
                    (j as f64 + 0.5) * h - jit,
                ));
            }
        }
        let v = vec![h * h; x.len()];
        (x, v)
    }

    /// The average by brute force over all pairs (and mirror images).
    fn brute(
        g: &Grid<2>,
        x: &[Vector2<f64>],
        v: &[f64],
        mat: &[u16],
        inc: &[f64],
        r: f64,
    ) -> Vec<f64> {
        (0..x.len())
            .map(|p| {
                if inc[p] < 0.0 {
                    return f64::NAN;
                }
                let (mut num, mut den) = (0.0, 0.0);
                let mut images = vec![x[p]];
                for a in 0..2 {
                    let mut more = Vec::new();
                    for xi in &images {
                        if g.bc[a][0] == Boundary::Symmetry && xi[a] < r {
                            let mut m = *xi;
                            m[a] = -xi[a];
                            more.push(m);
                        }
                        if g.bc[a][1] == Boundary::Symmetry && 1.0 - xi[a] < r {
                            let mut m = *xi;
                            m[a] = 2.0 - xi[a];
                            more.push(m);
                        }
                    }
                    images.extend(more);
                }
                for xi in images {
                    for q in 0..x.len() {
                        if inc[q] < 0.0 || mat[q] != mat[p] {
                            continue;
                        }
                        let w = bell((x[q] - xi).norm_squared(), r * r) * v[q];
                        num += w * inc[q];
                        den += w;
                    }
                }
                num / den
            })
            .collect()
    }

    #[test]
    fn a_uniform_increment_is_its_own_average() {
        // The renormalised average of a constant is the constant, at free
        // faces and mirrored ones alike (to round-off).
        for bc in [Boundary::Free, Boundary::Symmetry] {
            let g = grid(bc);
            let (x, v) = lattice(20);
            let mat = vec![0u16; x.len()];
            let mut nl = NonlocalDamage::<2>::default();
            assert!(nl.prepare(x.len(), [0.13].into_iter()));
            nl.increment.iter_mut().for_each(|d| *d = 0.037);
            nl.average_increments(&g, &x, &v, &mat);
            for &a in &nl.average {
                assert!((a - 0.037).abs() < 1e-15, "{a}");
            }
        }
    }

    #[test]
    fn the_binned_average_equals_the_all_pairs_sum() {
        // A varying increment, two materials, some points left out: the
        // binned search finds exactly the neighbours the all-pairs sum
        // weights, mirror images included.
        for bc in [Boundary::Free, Boundary::Symmetry] {
            let g = grid(bc);
            let (x, v) = lattice(24);
            let mat: Vec<u16> = (0..x.len()).map(|p| u16::from(x[p][0] > 0.6)).collect();
            let mut nl = NonlocalDamage::<2>::default();
            assert!(nl.prepare(x.len(), [0.11, 0.07].into_iter()));
            for p in 0..x.len() {
                nl.increment[p] = if p % 17 == 3 {
                    -1.0
                } else {
                    (x[p][0] * 3.0).sin().powi(2) + x[p][1]
                };
            }
            nl.average_increments(&g, &x, &v, &mat);
            for m in 0..2u16 {
                let r = nl.radius[m as usize];
                let want = brute(&g, &x, &v, &mat, &nl.increment, r);
                for p in (0..x.len()).filter(|&p| mat[p] == m) {
                    if nl.increment[p] < 0.0 {
                        assert!(nl.average[p].is_nan());
                    } else {
                        assert!(
                            (nl.average[p] - want[p]).abs() < 1e-13,
                            "{p}: {} vs {}",
                            nl.average[p],
                            want[p]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_mirrored_quarter_averages_as_the_whole() {
        // A field symmetric about x = 0 and y = 0: the quarter model with
        // symmetry faces at its lower sides gives the whole square's
        // average at every point.
        let n = 16;
        let h = 1.0 / n as f64;
        let f = |p: &Vector2<f64>| (p[0] * p[0] + 0.5 * p[1] * p[1]).exp();
        let quarter_grid = Grid::new(
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, 1.0),
            [4, 4],
            [
                [Boundary::Symmetry, Boundary::Free],
                [Boundary::Symmetry, Boundary::Free],
            ],
        );
        let whole_grid = Grid::new(
            Vector2::new(-1.0, -1.0),
            Vector2::new(1.0, 1.0),
            [8, 8],
            [[Boundary::Free; 2]; 2],
        );
        let cell = |i: usize| (i as f64 + 0.5) * h;
        let quarter: Vec<Vector2<f64>> = (0..n * n)
            .map(|k| Vector2::new(cell(k / n), cell(k % n)))
            .collect();
        let whole: Vec<Vector2<f64>> = (0..4 * n * n)
            .map(|k| Vector2::new(cell(k / (2 * n)) - 1.0, cell(k % (2 * n)) - 1.0))
            .collect();
        let run = |g: &Grid<2>, x: &[Vector2<f64>]| {
            let mut nl = NonlocalDamage::<2>::default();
            assert!(nl.prepare(x.len(), [0.3].into_iter()));
            for (d, p) in nl.increment.iter_mut().zip(x) {
                *d = f(p);
            }
            nl.average_increments(g, x, &vec![h * h; x.len()], &vec![0; x.len()]);
            nl.average
        };
        let (aq, aw) = (run(&quarter_grid, &quarter), run(&whole_grid, &whole));
        for (p, xp) in quarter.iter().enumerate() {
            let k = whole.iter().position(|w| (w - xp).norm() < 1e-12).unwrap();
            assert!(
                (aq[p] - aw[k]).abs() < 1e-13,
                "{xp}: {} vs {}",
                aq[p],
                aw[k]
            );
        }
    }
}
