//! York's membrane material points (York Sec. 3.2): ordered chains of
//! material points along a curve, their local frame, and the discretisation
//! of a membrane's curve into points.
//!
//! A membrane is one layer of points numbered consecutively along its
//! contour, so a point's neighbours are known and give the tangent `t`
//! (York Sec. 3.2, Fig. 4). The points of one membrane are contiguous in the
//! particle arrays; a [`MembraneChain`] names their range. Before each
//! stress update [`Membranes::update_frames`] computes every point's unit
//! tangent from its neighbours' current positions into a buffer kept between
//! steps and turns each point's stress to its new frame, `σ = s t⊗t` (the
//! tangential stress `s` is a scalar of the local frame, hence objective).
//!
//! Lian's membrane finite elements (Belytschko–Tsay quadrilaterals with
//! their own nodes) are in [`element`], their meshes in [`quad_mesh`].

pub mod element;
pub mod quad_mesh;

use nalgebra::SVector;

use crate::mpm::Stresses;

/// The particles of one membrane: `first .. first + count`, in order along
/// the contour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MembraneChain {
    /// Index of the first point.
    pub first: usize,
    /// Number of points (≥ 2).
    pub count: usize,
    /// Whether the last point joins the first.
    pub closed: bool,
    /// Open chains: whether the two end points are held at their initial
    /// positions (they sit on a fixed wall, whose nodes hold them).
    pub fixed_ends: bool,
}

impl MembraneChain {
    /// The neighbours (previous, next) of the chain's `k`-th point; an open
    /// chain's end is its own neighbour on the missing side.
    #[inline]
    pub fn neighbours(&self, k: usize) -> (usize, usize) {
        let n = self.count;
        let (prev, next) = if self.closed {
            ((k + n - 1) % n, (k + 1) % n)
        } else {
            (k.saturating_sub(1), (k + 1).min(n - 1))
        };
        (self.first + prev, self.first + next)
    }
}

/// The membranes of a run and their per-point frame buffer.
#[derive(Debug, Clone, Default)]
pub struct Membranes<const D: usize> {
    /// One chain per membrane object.
    pub chains: Vec<MembraneChain>,
    /// Unit tangent of every particle (zero for particles of other
    /// materials); refreshed by [`Self::update_frames`]. Empty when the run
    /// has no membranes.
    pub tangent: Vec<SVector<f64, D>>,
    /// Length of each point's segment at t = 0 (half the distances to its
    /// two neighbours); zero for other particles.
    pub segment0: Vec<f64>,
}

impl<const D: usize> Membranes<D> {
    /// The membranes `chains` of `n` particles at positions `x` (t = 0).
    pub fn new(chains: Vec<MembraneChain>, x: &[SVector<f64, D>]) -> Self {
        let n = x.len();
        let mut m = Self {
            chains,
            tangent: Vec::new(),
            segment0: Vec::new(),
        };
        if !m.chains.is_empty() {
            m.tangent = vec![SVector::zeros(); n];
            m.segment0 = vec![0.0; n];
            for c in &m.chains {
                for k in 0..c.count {
                    m.segment0[c.first + k] = segment_length(c, k, x);
                }
            }
        }
        m
    }

    /// Whether there are membranes.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.chains.is_empty()
    }

    /// Computes each membrane point's unit tangent from its neighbours'
    /// current positions (central difference along the contour, one-sided
    /// at an open end; York Sec. 3.2) and rewrites its stress in the new
    /// frame, `σ = s t⊗t + s₃₃ e₃⊗e₃` with `s` the in-plane trace of the
    /// old stress. No allocation.
    ///
    /// # Errors
    /// The first point whose neighbour coincides with it (no tangent).
    pub fn update_frames(
        &mut self,
        x: &[SVector<f64, D>],
        stress: &mut Stresses<D>,
    ) -> Result<(), usize> {
        for c in &self.chains {
            for k in 0..c.count {
                let p = c.first + k;
                let (a, b) = c.neighbours(k);
                let tol = 1e-9 * self.segment0[p];
                let (da, db) = ((x[p] - x[a]).norm(), (x[b] - x[p]).norm());
                // A coinciding (or non-finite) neighbour leaves no tangent.
                let apart = |d: f64| d.is_finite() && d > tol;
                if (a != p && !apart(da)) || (b != p && !apart(db)) {
                    return Err(p);
                }
                let d = x[b] - x[a];
                let t = d / d.norm();
                self.tangent[p] = t;
                let mut sp = stress.get(p);
                let s: f64 = (0..D).map(|i| sp[(i, i)]).sum();
                for i in 0..D {
                    for j in 0..D {
                        sp[(i, j)] = s * t[i] * t[j];
                    }
                }
                stress.set(p, &sp);
            }
        }
        Ok(())
    }

    /// Holds the end points of open chains with `fixed_ends` at their
    /// initial positions, at rest; returns the impulse that takes them to
    /// rest (the supports' reaction, `−Σ m v`).
    pub fn fix_ends(
        &self,
        x: &mut [SVector<f64, D>],
        x0: &[SVector<f64, D>],
        v: &mut [SVector<f64, D>],
        mass: &[f64],
    ) -> SVector<f64, D> {
        let mut impulse = SVector::zeros();
        for c in self.chains.iter().filter(|c| c.fixed_ends && !c.closed) {
            for p in [c.first, c.first + c.count - 1] {
                x[p] = x0[p];
                impulse -= v[p] * mass[p];
                v[p] = SVector::zeros();
            }
        }
        impulse
    }

    /// Stretch of every particle's segment: current length / initial
    /// (1 for particles of other materials).
    pub fn stretch(&self, x: &[SVector<f64, D>]) -> Vec<f64> {
        let mut out = vec![1.0; x.len()];
        for c in &self.chains {
            for k in 0..c.count {
                let p = c.first + k;
                out[p] = segment_length(c, k, x) / self.segment0[p];
            }
        }
        out
    }
}

/// Length of the `k`-th point's segment: half the distances to its two
/// neighbours (one at an open end).
fn segment_length<const D: usize>(c: &MembraneChain, k: usize, x: &[SVector<f64, D>]) -> f64 {
    let p = c.first + k;
    let (a, b) = c.neighbours(k);
    0.5 * ((x[p] - x[a]).norm() + (x[b] - x[p]).norm())
}

/// Points along a polyline at equal arc-length intervals of at most
/// `spacing`: `n + 1` points from end to end when open, `n` when closed.
/// Returns the points and the interval Δ (the perimeter or length / n).
pub fn resample(vertices: &[[f64; 2]], closed: bool, spacing: f64) -> (Vec<[f64; 2]>, f64) {
    resample_offset(vertices, closed, spacing, [false, false])
}

/// [`resample`] with an open polyline's ends optionally left bare: where
/// `bare[e]` the first (last) point sits half an interval Δ inside that end
/// instead of on it, so the end point's segment `Δ` runs to the curve's end
/// (an axisymmetric surface closed at the axis: no ring of radius 0). The
/// length is `(n + a + b) Δ` with `a, b = ½` at bare ends, 0 otherwise.
pub fn resample_offset(
    vertices: &[[f64; 2]],
    closed: bool,
    spacing: f64,
    bare: [bool; 2],
) -> (Vec<[f64; 2]>, f64) {
    let nv = vertices.len();
    let nseg = if closed { nv } else { nv - 1 };
    let seg = |i: usize| (vertices[i], vertices[(i + 1) % nv]);
    let len = |a: [f64; 2], b: [f64; 2]| ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    let total: f64 = (0..nseg).map(|i| len(seg(i).0, seg(i).1)).sum();
    let half = |b: bool| if b && !closed { 0.5 } else { 0.0 };
    let (a0, b0) = (half(bare[0]), half(bare[1]));
    // (less a rounding allowance: a length of exactly k spacings gives k)
    let n = ((total / spacing - a0 - b0 - 1e-9).ceil().max(0.0) as usize).max(if closed {
        3
    } else {
        1
    });
    let delta = total / (n as f64 + a0 + b0);
    let npts = if closed { n } else { n + 1 };
    let mut out = Vec::with_capacity(npts);
    let (mut i, mut start) = (0usize, 0.0f64);
    for k in 0..npts {
        let s = ((k as f64 + a0) * delta).min(total);
        while i + 1 < nseg && start + len(seg(i).0, seg(i).1) < s {
            start += len(seg(i).0, seg(i).1);
            i += 1;
        }
        let (a, b) = seg(i);
        let l = len(a, b);
        let f = if l > 0.0 {
            ((s - start) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push([a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]);
    }
    (out, delta)
}

/// `n = ⌈2πR / spacing⌉` points on a circle at equal angles, counter-
/// clockwise from angle 0, and the arc length 2πR/n between them.
pub fn circle_points(center: [f64; 2], radius: f64, spacing: f64) -> (Vec<[f64; 2]>, f64) {
    let tau = std::f64::consts::TAU;
    let n = ((tau * radius / spacing - 1e-9).ceil() as usize).max(3);
    let pts = (0..n)
        .map(|k| {
            let a = tau * k as f64 / n as f64;
            [center[0] + radius * a.cos(), center[1] + radius * a.sin()]
        })
        .collect();
    (pts, tau * radius / n as f64)
}

/// The dog-bone outline (York Fig. 10, reconstructed): two circular lobes of
/// radius `r` centred at `center ± (offset, 0)` joined by a straight neck of
/// half-width `neck` (< r), counter-clockwise, as a polygon whose arcs are
/// sampled every `max_step` or finer.
pub fn dog_bone_outline(
    center: [f64; 2],
    r: f64,
    offset: f64,
    neck: f64,
    max_step: f64,
) -> Vec<[f64; 2]> {
    let th = (neck / r).asin();
    let pi = std::f64::consts::PI;
    let sweep = 2.0 * (pi - th);
    let m = ((sweep * r / max_step).ceil() as usize).max(8);
    let mut out = Vec::with_capacity(2 * m + 2);
    // Right lobe from its lower junction (−π + θ) counter-clockwise to its
    // upper junction (π − θ); then the neck's upper edge to the left lobe's
    // upper junction (θ), its arc to 2π − θ, and the lower edge back.
    for (cx, a0) in [(center[0] + offset, -pi + th), (center[0] - offset, th)] {
        for k in 0..=m {
            let a = a0 + sweep * k as f64 / m as f64;
            out.push([cx + r * a.cos(), center[1] + r * a.sin()]);
        }
    }
    out
}

/// Perimeter and enclosed area of a closed polygon (shoelace).
pub fn polygon_perimeter_area(v: &[[f64; 2]]) -> (f64, f64) {
    let n = v.len();
    let (mut per, mut area) = (0.0, 0.0);
    for i in 0..n {
        let (a, b) = (v[i], v[(i + 1) % n]);
        per += ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        area += a[0] * b[1] - b[0] * a[1];
    }
    (per, 0.5 * area.abs())
}

/// Whether the polyline through `v` (closed or open) crosses itself: the
/// first pair of non-adjacent segments `(i, j)` that intersect.
pub fn self_intersection(v: &[[f64; 2]], closed: bool) -> Option<(usize, usize)> {
    let n = v.len();
    let nseg = if closed { n } else { n.saturating_sub(1) };
    let orient = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let on = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        c[0] >= a[0].min(b[0])
            && c[0] <= a[0].max(b[0])
            && c[1] >= a[1].min(b[1])
            && c[1] <= a[1].max(b[1])
    };
    for i in 0..nseg {
        for j in i + 1..nseg {
            let adjacent = j == i + 1 || (closed && i == 0 && j == nseg - 1);
            let (p1, p2) = (v[i], v[(i + 1) % n]);
            let (q1, q2) = (v[j], v[(j + 1) % n]);
            let (d1, d2) = (orient(q1, q2, p1), orient(q1, q2, p2));
            let (d3, d4) = (orient(p1, p2, q1), orient(p1, p2, q2));
            if adjacent {
                // Adjacent segments meet at their shared vertex; they overlap
                // only when they fold back onto each other (collinear and
                // pointing back).
                let (a, s, b) = if j == i + 1 {
                    (p1, p2, q2)
                } else {
                    (q1, p1, p2)
                };
                let u = [s[0] - a[0], s[1] - a[1]];
                let w = [b[0] - s[0], b[1] - s[1]];
                let cross = u[0] * w[1] - u[1] * w[0];
                let dot = u[0] * w[0] + u[1] * w[1];
                let scale = (u[0].hypot(u[1])) * (w[0].hypot(w[1]));
                if dot < 0.0 && cross.abs() <= 1e-12 * scale {
                    return Some((i, j));
                }
                continue;
            }
            let proper = ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
                && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0));
            let touch = (d1 == 0.0 && on(q1, q2, p1))
                || (d2 == 0.0 && on(q1, q2, p2))
                || (d3 == 0.0 && on(p1, p2, q1))
                || (d4 == 0.0 && on(p1, p2, q2));
            if proper || touch {
                return Some((i, j));
            }
        }
    }
    None
}

/// Where the edge from `a` to `b` crosses the line y = `py`, if it
/// straddles it (one end above, the other not): the crossing of the
/// even–odd rule, which every inside test here counts (a point is inside
/// when an odd number of its polygon's edges cross its row beyond it).
#[inline]
pub fn edge_crossing(a: [f64; 2], b: [f64; 2], py: f64) -> Option<f64> {
    ((a[1] > py) != (b[1] > py)).then(|| (b[0] - a[0]) * (py - a[1]) / (b[1] - a[1]) + a[0])
}

/// Whether point `x` lies inside the closed polygon through `v`
/// (even–odd rule, [`edge_crossing`]).
pub fn inside_polygon<const D: usize>(x: &SVector<f64, D>, v: &[SVector<f64, D>]) -> bool {
    let (px, py) = (x[0], x[1]);
    let n = v.len();
    let xy = |p: &SVector<f64, D>| [p[0], p[1]];
    (0..n)
        .filter(|&i| edge_crossing(xy(&v[i]), xy(&v[(i + n - 1) % n]), py).is_some_and(|c| px < c))
        .count()
        % 2
        == 1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resample_keeps_length_and_spacing() {
        let v = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]];
        let (p, d) = resample(&v, false, 0.3);
        assert_eq!(p.len(), 8); // 2 / 0.3 → 7 intervals
        assert!((d - 2.0 / 7.0).abs() < 1e-15);
        assert_eq!(p[0], [0.0, 0.0]);
        assert!((p[7][0] - 1.0).abs() < 1e-15 && (p[7][1] - 1.0).abs() < 1e-15);
        let (c, dc) = resample(
            &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            true,
            0.25,
        );
        assert_eq!(c.len(), 16);
        assert!((dc - 0.25).abs() < 1e-15);
        // Both ends bare: points at the middles of n equal intervals.
        let (p, d) = resample_offset(&[[0.0, 0.0], [0.0, 1.0]], false, 0.3, [true, true]);
        assert_eq!(p.len(), 4);
        assert!((d - 0.25).abs() < 1e-15);
        assert!((p[0][1] - 0.125).abs() < 1e-15 && (p[3][1] - 0.875).abs() < 1e-15);
        // One bare end: the other end keeps its point.
        let (p, d) = resample_offset(&[[0.0, 0.0], [0.0, 1.0]], false, 0.3, [true, false]);
        assert!((d - 1.0 / 3.5).abs() < 1e-15);
        assert!((p[0][1] - 0.5 * d).abs() < 1e-15 && (p[p.len() - 1][1] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn dog_bone_outline_perimeter_and_area() {
        // Perimeter 2·2r(π − θ) + 4(a − r cos θ), θ = asin(w/r).
        let (r, a, w) = (0.45, 1.25, 0.2);
        let v = dog_bone_outline([0.0, 0.0], r, a, w, 1e-4);
        let th = (w / r).asin();
        let exact = 4.0 * r * (std::f64::consts::PI - th) + 4.0 * (a - r * th.cos());
        let (per, area) = polygon_perimeter_area(&v);
        assert!((per - exact).abs() < 1e-6, "{per} vs {exact}");
        assert!(area > 1.9 && area < 1.95, "{area}");
        assert!(self_intersection(&v, true).is_none());
    }

    #[test]
    fn crossing_and_folding_polylines_are_found() {
        let bow = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(self_intersection(&bow, true).is_some());
        let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(self_intersection(&square, true).is_none());
        let fold = [[0.0, 0.0], [1.0, 0.0], [0.5, 0.0]];
        assert!(self_intersection(&fold, false).is_some());
    }
}
