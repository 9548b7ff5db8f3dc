//! Geometric multigrid for cell-centred structured-grid operators
//! ([`CellStencil`]) in 2D and 3D with variable coefficients.
//!
//! * Coarsening by 2 along every axis with more than one cell; an odd axis
//!   gets a last coarse cell covering a single fine cell. Coarsening stops
//!   at [`MgOptions::coarse_max_cells`] cells, where a sparse Cholesky
//!   factorisation solves exactly.
//! * Coarse operators by rediscretisation with series/parallel conductances:
//!   along each fine line crossing a coarse face, the resistance between the
//!   two coarse cell centres is `ρ_left + 1/c_cross + ρ_right`, `ρ` being half
//!   the resistance of the coarse cell's interior fine face (0 for a coarse
//!   cell made of one fine cell); the coarse coefficient is the sum over the
//!   crossing lines of the conductances. For constant coefficients this is
//!   exactly half the summed fine coefficients (the classical choice); across
//!   jumps it gives the flux-continuous (harmonic) value. Dirichlet faces use
//!   the same rule with a ghost at 0, Neumann faces stay 0. Coarse
//!   `diag_extra` is the sum of the fine values.
//! * Prolongation [`Prolongation::Linear`] (default): per axis, linear
//!   interpolation between coarse centres with *operator-dependent* weights
//!   `ρ_own / R` taken from the same resistances (3/4–1/4 for constant
//!   coefficients, i.e. bilinear/trilinear; follows the flux across jumps),
//!   combined as a tensor product. Restriction is its transpose, so the
//!   cycle is symmetric.
//! * Red–black Gauss–Seidel (optionally SOR) smoothing; pre-smoothing sweeps
//!   red then black, post-smoothing black then red, so a cycle with
//!   `pre_smooth == post_smooth` is a symmetric positive definite
//!   preconditioner for [`crate::pcg`]. All the sweeps of a smoothing step
//!   are fused into one pass over memory (each half-sweep trails the one
//!   before by one row/plane, see `rb_sweeps`), with the same result to
//!   the bit as separate sweeps.
//! * Large levels run on the threads of the calling rayon pool, with results
//!   identical to the bit to one thread's (see `rb_sweeps_blocks`,
//!   `restrict_residual`).
//!
//! Measured (see `tests/multigrid.rs` and `examples/mg_factors.rs`): V(3,3)
//! stationary convergence factors ≈ 0.11 (2D) and ≈ 0.15 (3D) on Poisson
//! problems, ≈ 0.2–0.35 with 1e3 inclusions; checkerboards with 1e3 jumps
//! need the W-cycle for the standalone iteration (as a PCG preconditioner the
//! V-cycle is fine).
//!
//! All-Neumann problems are accepted when some `diag_extra > 0`; a component
//! without `diag_extra` and without Dirichlet face is rejected at setup with
//! [`SolverError::Singular`].
//!
//! # Periodic axes
//!
//! A periodic axis of the [`CellStencil`] stays periodic on every coarse
//! level (until it is one cell wide, where the wrap face links a cell to
//! itself and drops out). The padded arrays' ghost layers hold copies of
//! the opposite side along periodic axes (zeros along the others): they are
//! refreshed before each red–black half-sweep reads them, before every
//! residual and before the prolongation reads the coarse correction, and
//! the restriction folds what it scatters into ghosts back onto the cells
//! they copy (the transpose of the ghost fill), so the cycle stays
//! symmetric. The coarse wrap face uses the same series/parallel rule as an
//! interior face. The sweep fused along the outermost axis (rows in 2D,
//! planes in 3D) would let the second colour of the first row read the
//! first colour of the last row before it is updated, so along a periodic
//! outermost axis the last row's (plane's) first colour is updated before
//! the fused loop, and the sweeps along such an axis are done one at a
//! time (see `rb_sweep_periodic`): the order stays exactly red–black.
//!
//! Red–black ordering needs an **even** number of cells along a periodic
//! axis: with an odd count, cells `0` and `n − 1` have the same colour but
//! are neighbours, so a half-sweep is no longer a set of independent
//! updates, its result depends on the order inside the colour, and the
//! post-smoother is no longer the adjoint of the pre-smoother (the
//! preconditioner would not be symmetric and CG could fail). Therefore:
//! a finest level with an odd periodic axis is rejected by
//! [`Multigrid::new`] with [`SolverError::InvalidInput`] unless it is small
//! enough to be the coarsest level ([`MgOptions::coarse_max_cells`]);
//! coarsening stops at the first level with an odd periodic axis, which is
//! then solved directly (e.g. 2D 96² stops at 24² as usual, 2D 150² would
//! stop at 75² — correct, but a larger coarse factorisation).
//!
//! An all-periodic operator is singular without `diag_extra` (rejected at
//! setup, [`SolverError::Singular`]); with a small positive `diag_extra` it
//! is SPD but nearly singular, and the coarsest level (whose `diag_extra`
//! is the sum of the fine values, so it is relatively better conditioned
//! than the fine level) is factorised by Cholesky without a pivot
//! threshold. Should round-off make that factorisation fail, setup reports
//! [`SolverError::Singular`] naming the coarsest level.

use std::sync::{Mutex, MutexGuard};
use std::time::Instant;

use crate::assembly::Assembler;
use crate::direct::Cholesky;
use crate::error::{check_len, is_pos, Result, SolveReport, SolverError};
use crate::krylov::KrylovOptions;
use crate::operator::Preconditioner;
use crate::stencil::CellStencil;

/// Interpolation from a coarse grid to the next finer one (the
/// restriction is always its transpose).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Prolongation {
    /// Piecewise constant (each fine cell takes its coarse parent's value;
    /// restriction = summation). Very effective for smooth coefficients
    /// (V(2,2) factor ≈ 0.1) but **not robust to coefficient jumps** (the
    /// stationary iteration can diverge there).
    Constant,
    /// Operator-dependent linear interpolation (bilinear / trilinear for
    /// constant coefficients, flux-weighted across jumps; ghost value 0
    /// behind Dirichlet faces, constant extrapolation behind Neumann faces).
    Linear,
}

/// Multigrid cycle shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cycle {
    /// One coarse-grid visit per level.
    V,
    /// Two coarse-grid visits per level.
    W,
}

/// Multigrid parameters. The default is a V(3,3) cycle with red–black
/// Gauss–Seidel, operator-dependent linear prolongation and a direct solve
/// below 2048 cells.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MgOptions {
    /// Red–black Gauss–Seidel sweeps before the coarse-grid correction.
    pub pre_smooth: usize,
    /// Sweeps after the correction (reverse colour order). Keep equal to
    /// `pre_smooth` when the cycle is used as a PCG preconditioner.
    pub post_smooth: usize,
    /// Relaxation factor of the red–black Gauss–Seidel (SOR) smoother;
    /// 1 = plain Gauss–Seidel. Must lie in (0, 2).
    pub omega: f64,
    /// Prolongation (restriction is its transpose).
    pub prolongation: Prolongation,
    /// Cycle shape.
    pub cycle: Cycle,
    /// Stop coarsening once a level has at most this many cells; it is
    /// then solved with a sparse Cholesky factorisation.
    pub coarse_max_cells: usize,
    /// Maximum number of levels (including the finest).
    pub max_levels: usize,
}

impl Default for MgOptions {
    fn default() -> Self {
        Self {
            pre_smooth: 3,
            post_smooth: 3,
            omega: 1.0,
            prolongation: Prolongation::Linear,
            cycle: Cycle::V,
            coarse_max_cells: 2048,
            max_levels: 30,
        }
    }
}

/// One grid level, stored on a padded array with one ghost layer on every
/// side (ghost values of `u` are always 0).
#[derive(Debug, Clone)]
struct Level {
    n: [usize; 3],
    d3: bool,
    /// Axis that wraps (periodic with at least two cells): its ghosts are
    /// copies of the opposite side.
    periodic: [bool; 3],
    sy: usize,
    sz: usize,
    len: usize,
    /// `a[axis][p]` = coefficient of the face between `p - s_axis` and `p`
    /// (boundary faces on the low side at the first cell, on the high side
    /// at the ghost position; Neumann faces are 0).
    a: [Vec<f64>; 3],
    diag: Vec<f64>,
    inv_diag: Vec<f64>,
    extra: Vec<f64>,
}

impl Level {
    fn new(n: [usize; 3], d3: bool, periodic: [bool; 3]) -> Self {
        let sy = n[0] + 2;
        let sz = if d3 { sy * (n[1] + 2) } else { 0 };
        let len = sy * (n[1] + 2) * if d3 { n[2] + 2 } else { 1 };
        let axes = if d3 { 3 } else { 2 };
        let periodic = std::array::from_fn(|a| a < axes && periodic[a] && n[a] >= 2);
        Self {
            n,
            d3,
            periodic,
            sy,
            sz,
            len,
            a: [
                vec![0.0; len],
                vec![0.0; len],
                if d3 { vec![0.0; len] } else { Vec::new() },
            ],
            diag: vec![0.0; len],
            inv_diag: vec![0.0; len],
            extra: vec![0.0; len],
        }
    }

    #[inline]
    fn pidx(&self, i: usize, j: usize, k: usize) -> usize {
        (i + 1) + (j + 1) * self.sy + (k + 1) * self.sz
    }

    #[inline]
    fn stride(&self, axis: usize) -> usize {
        [1, self.sy, self.sz][axis]
    }

    fn ndim(&self) -> usize {
        if self.d3 {
            3
        } else {
            2
        }
    }

    fn cells(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    /// First periodic axis with an odd number of cells (red–black colouring
    /// inconsistent across the wrap), if any.
    fn odd_periodic_axis(&self) -> Option<usize> {
        (0..self.ndim()).find(|&a| self.periodic[a] && self.n[a] % 2 == 1)
    }

    fn compute_diag(&mut self) -> Result<()> {
        let [nx, ny, nz] = self.n;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let p = self.pidx(i, j, k);
                    let mut d = self.extra[p];
                    for a in 0..self.ndim() {
                        d += self.a[a][p] + self.a[a][p + self.stride(a)];
                    }
                    if !is_pos(d) || !d.is_finite() {
                        return Err(SolverError::Singular {
                            detail: format!(
                                "multigrid: zero diagonal at cell ({i}, {j}, {k}) of a {nx}x{ny}x{nz} level"
                            ),
                        });
                    }
                    self.diag[p] = d;
                    self.inv_diag[p] = 1.0 / d;
                }
            }
        }
        Ok(())
    }

    fn fill_from_stencil(&mut self, s: &CellStencil) {
        let [nx, ny, nz] = self.n;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let c = [i, j, k];
                    let p = self.pidx(i, j, k);
                    self.extra[p] = s.diag_extra()[s.cell_index(c)];
                    for a in 0..self.ndim() {
                        let own = s.face_coeffs(a)[s.face_index(a, c)];
                        self.a[a][p] = if c[a] == 0 && !self.periodic[a] {
                            s.boundary_coeff(a, 0, c)
                        } else {
                            own
                        };
                        if c[a] + 1 == self.n[a] {
                            let st = self.stride(a);
                            self.a[a][p + st] = if self.periodic[a] {
                                let mut f0 = c;
                                f0[a] = 0;
                                s.face_coeffs(a)[s.face_index(a, f0)]
                            } else {
                                s.boundary_coeff(a, 1, c)
                            };
                        }
                    }
                }
            }
        }
    }

    /// Calls `emit(row, col, value)` for the triplets of this level's
    /// matrix in natural (unpadded) ordering, in a fixed order that depends
    /// only on the dimensions and periodic axes.
    fn for_each_triplet(&self, mut emit: impl FnMut(usize, usize, f64)) {
        let [nx, ny, nz] = self.n;
        let idx = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let c = [i, j, k];
                    let p = self.pidx(i, j, k);
                    let me = idx(i, j, k);
                    emit(me, me, self.diag[p]);
                    for a in 0..self.ndim() {
                        let st = self.stride(a);
                        // Periodic: the wrap neighbour (with two cells both
                        // neighbours coincide; duplicates are summed).
                        if c[a] > 0 || self.periodic[a] {
                            let mut nb = c;
                            nb[a] = if c[a] > 0 { c[a] - 1 } else { self.n[a] - 1 };
                            emit(me, idx(nb[0], nb[1], nb[2]), -self.a[a][p]);
                        }
                        if c[a] + 1 < self.n[a] || self.periodic[a] {
                            let mut nb = c;
                            nb[a] = if c[a] + 1 < self.n[a] { c[a] + 1 } else { 0 };
                            emit(me, idx(nb[0], nb[1], nb[2]), -self.a[a][p + st]);
                        }
                    }
                }
            }
        }
    }

    /// Assembler of this level's matrix (pattern analysed once) with the
    /// current values.
    fn assembler(&self) -> Result<(Assembler, Vec<f64>)> {
        let (mut rows, mut cols, mut vals) = (Vec::new(), Vec::new(), Vec::new());
        self.for_each_triplet(|r, c, v| {
            rows.push(r);
            cols.push(c);
            vals.push(v);
        });
        let n = self.cells();
        let mut asm = Assembler::new(n, n, &rows, &cols)?;
        asm.assemble(&vals)?;
        Ok((asm, vals))
    }

    /// Current triplet values (order of [`Level::for_each_triplet`]) into
    /// `out`, without allocation.
    fn triplet_values(&self, out: &mut [f64]) {
        let mut t = 0;
        self.for_each_triplet(|_, _, v| {
            out[t] = v;
            t += 1;
        });
    }
}

/// Interpolation data from a fine level to the next coarser one.
#[derive(Debug, Clone)]
struct Transfer {
    coarsen: [bool; 3],
    /// `tab[axis][m]` = (own coarse padded index, neighbour coarse padded
    /// index) along `axis` for fine index `m`.
    tab: [Vec<(usize, usize)>; 3],
    /// `w[axis][p]` = interpolation weight of the neighbouring coarse cell
    /// along `axis` for fine padded cell `p` (the own cell gets `1 - w`).
    /// Empty for axes that are not coarsened.
    w: [Vec<f64>; 3],
    constant: bool,
}

/// Mutable state used by a cycle.
#[derive(Debug)]
struct Work {
    u: Vec<f64>,
    f: Vec<f64>,
    /// One row of residual values.
    row: Vec<f64>,
    /// The residual on the padded layout, when rows are done in parallel.
    r: Vec<f64>,
    /// One value per padded row (squared residual norms of parallel rows).
    partial: Vec<f64>,
}

#[derive(Debug)]
struct State {
    work: Vec<Work>,
    coarse: Cholesky,
    cbuf: Vec<f64>,
}

/// Geometric multigrid hierarchy for a [`CellStencil`]; implements
/// [`Preconditioner`] (one cycle from a zero initial guess) and a
/// standalone iterative [`Multigrid::solve`]. Levels of at least 32k cells
/// are shared between the threads of the calling rayon pool (red–black
/// sweeps in blocks of rows or planes, residuals, restriction and
/// prolongation by rows); every result is the same to the bit for any
/// number of threads (`tests/threads.rs`).
#[derive(Debug)]
pub struct Multigrid {
    opts: MgOptions,
    levels: Vec<Level>,
    transfers: Vec<Transfer>,
    /// Matrix of the coarsest level, refreshed in place by `refresh`.
    coarse_asm: Assembler,
    /// Triplet values of the coarsest level.
    coarse_vals: Vec<f64>,
    state: Mutex<State>,
    setup_s: f64,
}

fn coarse_dims(n: [usize; 3], d3: bool) -> ([usize; 3], [bool; 3]) {
    let mut nc = n;
    let mut co = [false; 3];
    for a in 0..if d3 { 3 } else { 2 } {
        if n[a] >= 2 {
            nc[a] = n[a].div_ceil(2);
            co[a] = true;
        }
    }
    (nc, co)
}

#[inline]
fn resist(c: f64) -> f64 {
    if c > 0.0 {
        1.0 / c
    } else {
        f64::INFINITY
    }
}

/// Fraction `part / (part + rest)` of a series resistance, with the limits
/// for infinite resistances (zero coefficients).
#[inline]
fn share(part: f64, rest: f64) -> f64 {
    let total = part + rest;
    if total.is_finite() {
        if total > 0.0 {
            part / total
        } else {
            0.0
        }
    } else if part.is_infinite() && rest.is_finite() {
        1.0
    } else {
        0.0
    }
}

impl Transfer {
    fn new(fine: &Level, coarse: &Level, co: [bool; 3], constant: bool) -> Self {
        let mut tab: [Vec<(usize, usize)>; 3] = Default::default();
        let mut w: [Vec<f64>; 3] = Default::default();
        for a in 0..3 {
            let nf = fine.n[a];
            let nc = coarse.n[a];
            tab[a] = (0..nf)
                .map(|m| {
                    if a == 2 && !fine.d3 {
                        (0, 0)
                    } else if !co[a] {
                        (m + 1, m + 1)
                    } else {
                        let ci = m / 2;
                        let wide = nf - 2 * ci >= 2;
                        let nb = if !wide {
                            ci + 1
                        } else if m % 2 == 0 {
                            ci // coarse padded index of ci - 1 (ghost 0 if ci = 0)
                        } else {
                            ci + 2 // ci + 1, or the high ghost nc + 1
                        };
                        debug_assert!(nb <= nc + 1);
                        (ci + 1, nb)
                    }
                })
                .collect();
            if co[a] && (a < 2 || fine.d3) {
                w[a] = vec![0.0; fine.len];
            }
        }
        Self {
            coarsen: co,
            tab,
            w,
            constant,
        }
    }
}

/// Fills the coefficients of `coarse` and the interpolation weights of `tr`
/// from `fine`.
///
/// Along a coarsened axis, the coarse face `F` between coarse cells `F-1`
/// and `F` is crossed by one fine line per transverse fine cell. On each
/// line the resistance between the coarse centres is
/// `ρ_left + 1/c_cross + ρ_right`, where `ρ` is the resistance from a coarse
/// centre to the centre of its fine cell next to the face (half the
/// resistance of the coarse cell's interior fine face; 0 for a coarse cell
/// made of a single fine cell). The coarse coefficient is the sum over the
/// lines of `1/R` (for constant coefficients: half the summed fine
/// coefficients), and the interpolation weight of the neighbouring coarse
/// cell for a fine cell next to the face is `ρ_own / R` (3/4–1/4 for
/// constant coefficients; flux-continuous for jumps). Boundary faces use a
/// ghost coarse cell with `ρ = 0` and value 0.
fn coarsen_level(fine: &Level, coarse: &mut Level, tr: &mut Transfer) {
    let [nx, ny, nz] = fine.n;
    let co = tr.coarsen;
    for a in 0..coarse.ndim() {
        coarse.a[a].fill(0.0);
    }
    coarse.extra.fill(0.0);
    let cmap = |c: usize, a: usize| if co[a] { c / 2 } else { c };
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let p = fine.pidx(i, j, k);
                let q = coarse.pidx(cmap(i, 0), cmap(j, 1), cmap(k, 2));
                coarse.extra[q] += fine.extra[p];
            }
        }
    }
    for a in 0..fine.ndim() {
        let nf = fine.n[a];
        let s = fine.stride(a);
        let af = &fine.a[a];
        let wide = |ci: usize| nf - 2 * ci >= 2;
        if fine.periodic[a] && co[a] {
            coarsen_periodic_axis(fine, coarse, tr, a);
            continue;
        }
        if !co[a] {
            // Axis not coarsened: faces map one to one (summed transversally).
            let ext = |b: usize| usize::from(a == b);
            for k in 0..nz + ext(2) {
                for j in 0..ny + ext(1) {
                    for i in 0..nx + ext(0) {
                        let mut cc = [cmap(i, 0), cmap(j, 1), cmap(k, 2)];
                        cc[a] = [i, j, k][a];
                        let q = coarse.pidx(cc[0], cc[1], cc[2]);
                        coarse.a[a][q] += af[fine.pidx(i, j, k)];
                    }
                }
            }
            continue;
        }
        let wa = &mut tr.w[a];
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let c = [i, j, k];
                    let m = c[a];
                    let p = fine.pidx(i, j, k);
                    let mut cc = [cmap(i, 0), cmap(j, 1), cmap(k, 2)];
                    if m % 2 == 0 {
                        // Fine cell right of coarse face F = m / 2.
                        let f = m / 2;
                        let rho_r = if wide(f) {
                            0.5 * resist(af[p + s])
                        } else {
                            0.0
                        };
                        let rho_l = if f > 0 { 0.5 * resist(af[p - s]) } else { 0.0 };
                        let cross = resist(af[p]);
                        let total = rho_l + cross + rho_r;
                        cc[a] = f;
                        let q = coarse.pidx(cc[0], cc[1], cc[2]);
                        if total.is_finite() {
                            coarse.a[a][q] += 1.0 / total;
                        }
                        wa[p] = share(rho_r, rho_l + cross);
                        if f > 0 {
                            wa[p - s] = share(rho_l, cross + rho_r);
                        }
                    }
                    if m + 1 == nf {
                        // High boundary face F = nc.
                        let f = nf.div_ceil(2);
                        let rho_l = if m % 2 == 1 { 0.5 * resist(af[p]) } else { 0.0 };
                        let cross = resist(af[p + s]);
                        let total = rho_l + cross;
                        cc[a] = f;
                        let q = coarse.pidx(cc[0], cc[1], cc[2]);
                        if total.is_finite() {
                            coarse.a[a][q] += 1.0 / total;
                        }
                        if m % 2 == 1 {
                            wa[p] = share(rho_l, cross);
                        }
                    }
                }
            }
        }
    }
    if tr.constant {
        for w in &mut tr.w {
            w.fill(0.0);
        }
    }
}

/// Coarse coefficients and interpolation weights along a periodic axis `a`
/// with an even number `nf` of fine cells (see [`coarsen_level`]): every
/// coarse cell is made of two fine cells, and the coarse face 0 is the wrap
/// face between coarse cells `nc − 1` and `0` (its fine crossing face is
/// the fine wrap face; `ρ_left` comes from coarse cell `nc − 1`). The
/// coarse high-side wrap position gets the same value. With `nc = 1` the
/// coarse wrap face would link the cell to itself: no coarse coefficient,
/// and piecewise-constant interpolation.
fn coarsen_periodic_axis(fine: &Level, coarse: &mut Level, tr: &mut Transfer, a: usize) {
    let [nx, ny, nz] = fine.n;
    let nf = fine.n[a];
    let s = fine.stride(a);
    let af = &fine.a[a];
    let wa = &mut tr.w[a];
    debug_assert!(nf.is_multiple_of(2));
    if !coarse.periodic[a] {
        wa.fill(0.0);
        return;
    }
    let co = tr.coarsen;
    let cmap = |c: usize, b: usize| if co[b] { c / 2 } else { c };
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let c = [i, j, k];
                let m = c[a];
                if m % 2 == 1 {
                    continue;
                }
                let p = fine.pidx(i, j, k);
                // Fine cell right of coarse face F = m / 2; its left
                // neighbour across that face (wrapping for F = 0).
                let f = m / 2;
                let left = if f > 0 { p - s } else { p + (nf - 1) * s };
                let rho_r = 0.5 * resist(af[p + s]);
                let rho_l = 0.5 * resist(af[left]);
                let cross = resist(af[p]);
                let total = rho_l + cross + rho_r;
                let mut cc = [cmap(i, 0), cmap(j, 1), cmap(k, 2)];
                cc[a] = f;
                let q = coarse.pidx(cc[0], cc[1], cc[2]);
                if total.is_finite() {
                    coarse.a[a][q] += 1.0 / total;
                }
                wa[p] = share(rho_r, rho_l + cross);
                wa[left] = share(rho_l, cross + rho_r);
            }
        }
    }
    // High-side wrap positions repeat the coarse face 0.
    let [cx, cy, cz] = coarse.n;
    let cs = coarse.stride(a);
    let ncl = coarse.n[a];
    for k in 0..cz {
        for j in 0..cy {
            for i in 0..cx {
                let c = [i, j, k];
                if c[a] == 0 {
                    let q = coarse.pidx(i, j, k);
                    coarse.a[a][q + ncl * cs] = coarse.a[a][q];
                }
            }
        }
    }
}

/// Copies, along every periodic axis, the cells next to one side into the
/// ghost layer beyond the other, axis by axis over the full padded extent of
/// the previous axes (so edge and corner ghosts are right too).
fn fill_ghosts(lv: &Level, u: &mut [f64]) {
    let [nx, ny, nz] = lv.n;
    if lv.periodic[0] {
        for k in 0..nz {
            for j in 0..ny {
                let p0 = lv.pidx(0, j, k);
                u[p0 - 1] = u[p0 + nx - 1];
                u[p0 + nx] = u[p0];
            }
        }
    }
    if lv.periodic[1] {
        for k in 0..nz {
            fill_ghost_rows(lv, u, k);
        }
    }
    if lv.d3 && lv.periodic[2] {
        fill_ghost_planes(lv, u);
    }
}

/// Periodic y ghost rows of plane `k` (whole padded rows).
#[inline]
fn fill_ghost_rows(lv: &Level, u: &mut [f64], k: usize) {
    let (sy, ny) = (lv.sy, lv.n[1]);
    let base = (k + 1) * lv.sz;
    let ghost_lo = base;
    let first = base + sy;
    let last = base + ny * sy;
    let ghost_hi = base + (ny + 1) * sy;
    u.copy_within(last..last + sy, ghost_lo);
    u.copy_within(first..first + sy, ghost_hi);
}

/// Periodic z ghost planes (whole padded planes).
#[inline]
fn fill_ghost_planes(lv: &Level, u: &mut [f64]) {
    let (sz, nz) = (lv.sz, lv.n[2]);
    u.copy_within(nz * sz..(nz + 1) * sz, 0);
    u.copy_within(sz..2 * sz, (nz + 1) * sz);
}

/// Transpose of [`fill_ghosts`]: adds what was scattered into the ghost
/// layers of periodic axes onto the cells they copy (in the reverse axis
/// order) and clears those ghosts.
fn fold_ghosts(lv: &Level, v: &mut [f64]) {
    let [nx, ny, nz] = lv.n;
    let (sy, sz) = (lv.sy, lv.sz);
    if lv.d3 && lv.periodic[2] {
        for t in 0..sz {
            let lo = v[t];
            let hi = v[(nz + 1) * sz + t];
            v[nz * sz + t] += lo;
            v[sz + t] += hi;
            v[t] = 0.0;
            v[(nz + 1) * sz + t] = 0.0;
        }
    }
    if lv.periodic[1] {
        for k in 0..nz {
            let base = (k + 1) * sz;
            for t in 0..sy {
                let lo = v[base + t];
                let hi = v[base + (ny + 1) * sy + t];
                v[base + ny * sy + t] += lo;
                v[base + sy + t] += hi;
                v[base + t] = 0.0;
                v[base + (ny + 1) * sy + t] = 0.0;
            }
        }
    }
    if lv.periodic[0] {
        for k in 0..nz {
            for j in 0..ny {
                let p0 = lv.pidx(0, j, k);
                let (lo, hi) = (v[p0 - 1], v[p0 + nx]);
                v[p0 + nx - 1] += lo;
                v[p0] += hi;
                v[p0 - 1] = 0.0;
                v[p0 + nx] = 0.0;
            }
        }
    }
}

/// A padded level array shared by the tasks of a red–black sweep. Tasks
/// update different cells of the same rows (one colour each, and each row
/// by one task), so the array is read and written element by element
/// through a raw pointer, never through overlapping slices.
#[derive(Clone, Copy)]
struct Cells {
    ptr: *mut f64,
    len: usize,
}

// SAFETY: the callers (`rb_sweeps`, `rb_sweeps_blocks`) give every element to
// at most one writing task at a time, and no task reads an element another
// task writes in the same phase (red–black independence).
unsafe impl Send for Cells {}
// SAFETY: as above.
unsafe impl Sync for Cells {}

impl Cells {
    fn new(u: &mut [f64]) -> Self {
        Self {
            ptr: u.as_mut_ptr(),
            len: u.len(),
        }
    }

    /// Reads element `i`.
    ///
    /// # Safety
    /// No other task writes `i` during the phase.
    #[inline(always)]
    unsafe fn get(self, i: usize) -> f64 {
        debug_assert!(i < self.len);
        // SAFETY: in bounds (the padded layout), no concurrent writer.
        unsafe { *self.ptr.add(i) }
    }

    /// Writes element `i`.
    ///
    /// # Safety
    /// No other task reads or writes `i` during the phase.
    #[inline(always)]
    unsafe fn set(self, i: usize, v: f64) {
        debug_assert!(i < self.len);
        // SAFETY: in bounds, exclusive.
        unsafe { *self.ptr.add(i) = v }
    }
}

/// The face coefficients around the `nx` cells of the row starting at
/// padded index `p0`: x faces (`nx + 1`), south and north, bottom and top
/// (empty in 2D).
struct RowCoeffs<'a> {
    ax: &'a [f64],
    ays: &'a [f64],
    ayn: &'a [f64],
    azb: &'a [f64],
    azt: &'a [f64],
}

#[inline(always)]
fn row_coeffs<const D3: bool>(lv: &Level, p0: usize) -> RowCoeffs<'_> {
    let (nx, sy, sz) = (lv.n[0], lv.sy, lv.sz);
    let (azb, azt): (&[f64], &[f64]) = if D3 {
        (&lv.a[2][p0..p0 + nx], &lv.a[2][p0 + sz..p0 + sz + nx])
    } else {
        (&[], &[])
    };
    RowCoeffs {
        ax: &lv.a[0][p0..p0 + nx + 1],
        ays: &lv.a[1][p0..p0 + nx],
        ayn: &lv.a[1][p0 + sy..p0 + sy + nx],
        azb,
        azt,
    }
}

/// Gauss–Seidel/SOR update of the cells of one colour on row `(j, k)`.
///
/// # Safety
/// During the call no other task writes this row's cells of the other
/// colour or the other-colour cells of the four (six) neighbouring rows, nor
/// reads this row's cells of `color` or its ghost ends.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn gs_row<const D3: bool>(
    lv: &Level,
    u: Cells,
    f: &[f64],
    j: usize,
    k: usize,
    color: usize,
    omega: f64,
) {
    let nx = lv.n[0];
    let p0 = lv.pidx(0, j, k);
    let (sy, sz) = (lv.sy, lv.sz);
    // SAFETY (all accesses below): the padded layout keeps every index in
    // bounds, and the caller's contract excludes concurrent conflicting
    // access.
    unsafe {
        if lv.periodic[0] {
            // The colour being updated reads only the other colour, whose
            // values at the row ends are current.
            u.set(p0 - 1, u.get(p0 + nx - 1));
            u.set(p0 + nx, u.get(p0));
        }
        let co = row_coeffs::<D3>(lv, p0);
        let inv = &lv.inv_diag[p0..p0 + nx];
        let fr = &f[p0..p0 + nx];
        let mut i = (j + k + color) & 1;
        while i < nx {
            let c = p0 + i;
            let mut s = fr[i]
                + co.ax[i] * u.get(c - 1)
                + co.ax[i + 1] * u.get(c + 1)
                + co.ays[i] * u.get(c - sy)
                + co.ayn[i] * u.get(c + sy);
            if D3 {
                s += co.azb[i] * u.get(c - sz) + co.azt[i] * u.get(c + sz);
            }
            let old = u.get(c);
            u.set(c, old + omega * (s * inv[i] - old));
            i += 2;
        }
    }
}

/// First half-sweep from a zero initial guess on row `(j, k)`: cells of
/// `color` get `omega f / d`, the others 0.
///
/// # Safety
/// No other task reads or writes this row's interior cells during the call.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn zero_row(lv: &Level, u: Cells, f: &[f64], j: usize, k: usize, color: usize, omega: f64) {
    let nx = lv.n[0];
    let p0 = lv.pidx(0, j, k);
    let inv = &lv.inv_diag[p0..p0 + nx];
    let fr = &f[p0..p0 + nx];
    let first = (j + k + color) & 1;
    for (i, (fi, di)) in fr.iter().zip(inv).enumerate() {
        let v = if (i & 1) == first {
            omega * fi * di
        } else {
            0.0
        };
        // SAFETY: in bounds; exclusive per the contract.
        unsafe { u.set(p0 + i, v) };
    }
}

/// Periodic y ghost rows of plane `k` (whole padded rows), on shared cells.
///
/// # Safety
/// No other task writes plane `k`'s first or last interior row or reads its
/// ghost rows during the call.
#[inline]
unsafe fn fill_ghost_rows_shared(lv: &Level, u: Cells, k: usize) {
    let (sy, ny) = (lv.sy, lv.n[1]);
    let base = (k + 1) * lv.sz;
    for t in 0..sy {
        // SAFETY: in bounds; per the contract.
        unsafe {
            u.set(base + t, u.get(base + ny * sy + t));
            u.set(base + (ny + 1) * sy + t, u.get(base + sy + t));
        }
    }
}

/// One colour pass over "unit" `t` of the outermost axis (row `t` in 2D,
/// plane `t` in 3D, whose periodic y ghost rows are refreshed first).
///
/// # Safety
/// As [`gs_row`] (or [`zero_row`] with `zero`) for every row of the unit.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn colour_pass<const D3: bool>(
    lv: &Level,
    u: Cells,
    f: &[f64],
    t: usize,
    color: usize,
    omega: f64,
    zero: bool,
) {
    // SAFETY: forwarded contract.
    unsafe {
        if D3 {
            if lv.periodic[1] {
                fill_ghost_rows_shared(lv, u, t);
            }
            for j in 0..lv.n[1] {
                if zero {
                    zero_row(lv, u, f, j, t, color, omega);
                } else {
                    gs_row::<true>(lv, u, f, j, t, color, omega);
                }
            }
        } else if zero {
            zero_row(lv, u, f, t, 0, color, omega);
        } else {
            gs_row::<false>(lv, u, f, t, 0, color, omega);
        }
    }
}

/// Periodic ghosts of the outermost axis (rows in 2D, planes in 3D).
#[inline]
fn fill_outer_ghosts<const D3: bool>(lv: &Level, u: &mut [f64]) {
    if D3 {
        fill_ghost_planes(lv, u);
    } else {
        fill_ghost_rows(lv, u, 0);
    }
}

/// The number of units of the outermost axis (rows in 2D, planes in 3D)
/// and whether that axis is periodic.
#[inline]
fn outer_units<const D3: bool>(lv: &Level) -> (usize, bool) {
    let axis = if D3 { 2 } else { 1 };
    (lv.n[axis], lv.periodic[axis])
}

/// Units (rows in 2D, planes in 3D) per task below which a sweep is not
/// shared between threads.
const PAR_MIN_UNITS: usize = 8;
/// Cells below which a level is done on one thread (with 8k, the 128²
/// PCG-multigrid solve took 3.73 ms on two threads against 3.35 ms on one:
/// its levels are too small for the hand-off).
const PAR_MIN_CELLS: usize = 32 * 1024;

/// Whether work on `lv` is shared between threads: the pool has more than
/// one and the level is large enough to pay for the hand-off. The result of
/// every kernel is the same to the bit either way.
fn parallel(lv: &Level) -> bool {
    lv.cells() >= PAR_MIN_CELLS && rayon::current_num_threads() > 1
}

/// Half-sweep `h` of a run of red–black sweeps on unit `t`: the `first`
/// colour when `h` is even, the other when odd (every sweep starts with
/// `first`); the zero-guess pass when `h = 0` and `from_zero`.
///
/// # Safety
/// As [`colour_pass`].
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn half_sweep<const D3: bool>(
    lv: &Level,
    u: Cells,
    f: &[f64],
    t: usize,
    h: usize,
    first: usize,
    omega: f64,
    from_zero: bool,
) {
    let color = if h.is_multiple_of(2) {
        first
    } else {
        1 - first
    };
    // SAFETY: forwarded contract.
    unsafe { colour_pass::<D3>(lv, u, f, t, color, omega, from_zero && h == 0) }
}

/// `sweeps` red–black sweeps (each the `first` colour, then the other),
/// fused into one pass over the level: half-sweep `h` (of `2 sweeps`) of
/// unit `t` (row in 2D, plane in 3D) needs half-sweep `h − 1` of units
/// `t − 1 … t + 1` and nothing later, so half-sweep `h` trails half-sweep
/// `h − 1` by one unit and the data of a unit are read once for all the
/// sweeps while they are in cache (a window of `2 sweeps` units), instead
/// of once a sweep. Red–black Gauss–Seidel gives the same result to the bit
/// in any order that keeps those dependencies (a cell's update reads only
/// the other colour), so this is exactly `sweeps` separate sweeps. With
/// `from_zero` the previous content of `u` is ignored (taken as 0).
///
/// Along a periodic outermost axis (`m` rows/planes) the sweeps are done
/// one at a time: the second colour of unit 0 needs the *updated* first
/// colour of unit `m − 1`, so that unit's first colour is done before the
/// loop (it reads only the second colour of units `m − 2` and 0, not yet
/// updated); the ghost units are refreshed around it and before the last
/// unit's second colour. The order is still exactly red–black.
///
/// On a large level with more than one thread (and a non-periodic outermost
/// axis) the units are cut into blocks swept in parallel, see
/// [`rb_sweeps_blocks`]; the result is the same to the bit.
fn rb_sweeps<const D3: bool>(
    lv: &Level,
    u: &mut [f64],
    f: &[f64],
    first: usize,
    omega: f64,
    from_zero: bool,
    sweeps: usize,
) {
    let stages = 2 * sweeps;
    let (m, outer_periodic) = outer_units::<D3>(lv);
    if outer_periodic {
        for s in 0..sweeps {
            rb_sweep_periodic::<D3>(lv, u, f, first, omega, from_zero && s == 0);
        }
        return;
    }
    if m >= 2 * block_units(stages) && parallel(lv) {
        rb_sweeps_blocks::<D3>(lv, Cells::new(u), f, first, omega, from_zero, stages);
        return;
    }
    let cells = Cells::new(u);
    for t in 0..m + stages - 1 {
        for h in 0..stages.min(t + 1) {
            if t - h < m {
                // SAFETY: one task, so no concurrent access; the exclusive
                // borrow of `u` is not used while `cells` is.
                unsafe { half_sweep::<D3>(lv, cells, f, t - h, h, first, omega, from_zero) };
            }
        }
    }
}

/// One red–black sweep along a periodic outermost axis ([`rb_sweeps`]),
/// the second colour trailing the first by one unit.
fn rb_sweep_periodic<const D3: bool>(
    lv: &Level,
    u: &mut [f64],
    f: &[f64],
    first: usize,
    omega: f64,
    from_zero: bool,
) {
    let second = 1 - first;
    let m = outer_units::<D3>(lv).0;
    fill_outer_ghosts::<D3>(lv, u);
    let cells = Cells::new(u);
    // SAFETY (every `colour_pass` below): one task, so no concurrent access;
    // the exclusive borrow of `u` is not used while `cells` is.
    unsafe { colour_pass::<D3>(lv, cells, f, m - 1, first, omega, from_zero) };
    fill_outer_ghosts::<D3>(lv, u);
    for t in 0..=m {
        if t + 1 < m {
            // SAFETY: as above.
            unsafe { colour_pass::<D3>(lv, cells, f, t, first, omega, from_zero) };
        }
        if t >= 1 {
            if t == m {
                fill_outer_ghosts::<D3>(lv, u);
            }
            // SAFETY: as above.
            unsafe { colour_pass::<D3>(lv, cells, f, t - 1, second, omega, false) };
        }
    }
}

/// The fewest units a parallel block of [`rb_sweeps_blocks`] holds for
/// `stages` half-sweeps: at least `PAR_MIN_UNITS`, and more than the two
/// triangles of its ends, so that the triangles of neighbouring block ends
/// neither overlap nor read each other's units.
fn block_units(stages: usize) -> usize {
    PAR_MIN_UNITS.max(2 * stages)
}

/// [`rb_sweeps`] on contiguous blocks of units `[lo, hi)` in parallel
/// (non-periodic outermost axis), in two phases:
/// 1. each block runs the fused pass over its own units, doing half-sweep
///    `h` only on units `lo + h … hi − h − 1` (a trapezoid: those need
///    nothing from the neighbouring blocks but the start values of the
///    second colour on their end units, which nobody writes in this
///    phase);
/// 2. then every block end `b` (the start of each block, and `m`) does
///    the triangle left: half-sweep `h = 1, 2, …` on units `b − h … b + h − 1`
///    (clipped to the level), in order of `h`.
///
/// In phase 1 a block writes the first colour of its end units and reads
/// the other colour of its neighbours' end units; in phase 2 a triangle
/// writes within `stages − 1` units of its end and reads one more, and ends
/// are at least [`block_units`] apart. So no element is read and written by
/// two tasks at once, every half-sweep finds the values it needs at the
/// stage it needs, and the result is exactly red–black, as the serial pass.
/// With one sweep (`stages = 2`) phase 2 is the second colour of each
/// block's first and last unit.
#[allow(clippy::too_many_arguments)]
fn rb_sweeps_blocks<const D3: bool>(
    lv: &Level,
    u: Cells,
    f: &[f64],
    first: usize,
    omega: f64,
    from_zero: bool,
    stages: usize,
) {
    use rayon::prelude::*;
    let m = outer_units::<D3>(lv).0;
    let blocks = (m / block_units(stages)).min(4 * rayon::current_num_threads());
    let bounds = |b: usize| (b * m / blocks, (b + 1) * m / blocks);
    (0..blocks).into_par_iter().for_each(|b| {
        let (lo, hi) = bounds(b);
        for t in lo..hi + stages - 1 {
            for h in 0..stages.min(t + 1) {
                let v = t - h;
                if v >= lo + h && v + h < hi {
                    // SAFETY: see the function docs (phase 1).
                    unsafe { half_sweep::<D3>(lv, u, f, v, h, first, omega, from_zero) };
                }
            }
        }
    });
    (0..=blocks).into_par_iter().for_each(|b| {
        let end = bounds(b).0;
        for h in 1..stages {
            for v in end.saturating_sub(h)..(end + h).min(m) {
                // SAFETY: see the function docs (phase 2).
                unsafe { half_sweep::<D3>(lv, u, f, v, h, first, omega, from_zero) };
            }
        }
    });
}

/// Residual `r = f - A u` of interior row `(j, k)` into `out` (length nx);
/// returns its squared norm.
#[inline(always)]
fn residual_row<const D3: bool>(
    lv: &Level,
    u: &[f64],
    f: &[f64],
    j: usize,
    k: usize,
    out: &mut [f64],
) -> f64 {
    let nx = lv.n[0];
    let p0 = lv.pidx(0, j, k);
    let (sy, sz) = (lv.sy, lv.sz);
    let cur = &u[p0 - 1..p0 + nx + 1];
    let south = &u[p0 - sy..p0 - sy + nx];
    let north = &u[p0 + sy..p0 + sy + nx];
    let (bottom, top): (&[f64], &[f64]) = if D3 {
        (&u[p0 - sz..p0 - sz + nx], &u[p0 + sz..p0 + sz + nx])
    } else {
        (&[], &[])
    };
    let co = row_coeffs::<D3>(lv, p0);
    let d = &lv.diag[p0..p0 + nx];
    let fr = &f[p0..p0 + nx];
    let out = &mut out[..nx];
    let mut acc = 0.0;
    for i in 0..nx {
        let mut s = fr[i] - d[i] * cur[i + 1]
            + co.ax[i] * cur[i]
            + co.ax[i + 1] * cur[i + 2]
            + co.ays[i] * south[i]
            + co.ayn[i] * north[i];
        if D3 {
            s += co.azb[i] * bottom[i] + co.azt[i] * top[i];
        }
        out[i] = s;
        acc += s * s;
    }
    acc
}

/// Runs `f(j, k, row, slot)` on every interior row `(j, k)` of `lv`, with
/// `row` the row's `nx` interior entries in the padded array `buf` and
/// `slot` the row's entry of `slots` (one per padded row), in parallel when
/// `par`. Every call touches only its own row, so the result does not depend
/// on `par`.
fn rows_mut(
    lv: &Level,
    buf: &mut [f64],
    slots: &mut [f64],
    par: bool,
    f: impl Fn(usize, usize, &mut [f64], &mut f64) + Sync + Send,
) {
    use rayon::prelude::*;
    let (nx, ny, nz) = (lv.n[0], lv.n[1], lv.n[2]);
    let body = |(q, (chunk, slot)): (usize, (&mut [f64], &mut f64))| {
        let (jp, kp) = (q % (ny + 2), q / (ny + 2));
        if jp == 0 || jp == ny + 1 || (lv.d3 && (kp == 0 || kp == nz + 1)) {
            return;
        }
        let k = if lv.d3 { kp - 1 } else { 0 };
        f(jp - 1, k, &mut chunk[1..1 + nx], slot);
    };
    if par {
        buf.par_chunks_mut(lv.sy)
            .zip(slots.par_iter_mut())
            .enumerate()
            .with_min_len(PAR_MIN_UNITS)
            .for_each(body);
    } else {
        buf.chunks_mut(lv.sy)
            .zip(slots.iter_mut())
            .enumerate()
            .for_each(body);
    }
}

/// `||f - A u||^2` over the interior. Serially the residual is not stored;
/// in parallel each row's residual goes to its place in `w.r` and its
/// squared norm to `w.partial`, summed afterwards in row order, so the sum
/// is the serial one to the bit.
fn residual_norm2<const D3: bool>(lv: &Level, w: &mut Work) -> f64 {
    let [_, ny, nz] = lv.n;
    if parallel(lv) {
        let (u, f) = (&w.u, &w.f);
        rows_mut(lv, &mut w.r, &mut w.partial, true, |j, k, row, slot| {
            *slot = residual_row::<D3>(lv, u, f, j, k, row);
        });
        let mut acc = 0.0;
        for k in 0..nz {
            for j in 0..ny {
                let q = (j + 1) + (k + usize::from(lv.d3)) * (ny + 2);
                acc += w.partial[q];
            }
        }
        return acc;
    }
    let mut acc = 0.0;
    for k in 0..nz {
        for j in 0..ny {
            acc += residual_row::<D3>(lv, &w.u, &w.f, j, k, &mut w.row);
        }
    }
    acc
}

/// Scatters `P^T` of one fine row `rrow` (row `(j, k)`) through
/// `add(coarse padded index, value)`, in a fixed order.
#[inline(always)]
fn restrict_row(
    tr: &Transfer,
    fine: &Level,
    coarse: &Level,
    j: usize,
    k: usize,
    rrow: &[f64],
    mut add: impl FnMut(usize, f64),
) {
    let nx = fine.n[0];
    let (sy, sz) = (coarse.sy, coarse.sz);
    let (tx, ty, tz) = (&tr.tab[0][..nx], &tr.tab[1][j], &tr.tab[2][k]);
    let p0 = fine.pidx(0, j, k);
    let (yo, yn) = (ty.0 * sy, ty.1 * sy);
    let (zo, zn) = (tz.0 * sz, tz.1 * sz);
    let wx: &[f64] = if tr.w[0].is_empty() {
        &[]
    } else {
        &tr.w[0][p0..p0 + nx]
    };
    let wy: &[f64] = if tr.w[1].is_empty() {
        &[]
    } else {
        &tr.w[1][p0..p0 + nx]
    };
    let wz: &[f64] = if tr.w[2].is_empty() {
        &[]
    } else {
        &tr.w[2][p0..p0 + nx]
    };
    for (i, &(xo, xn)) in tx.iter().enumerate() {
        let v = rrow[i];
        let wxi = if wx.is_empty() { 0.0 } else { wx[i] };
        let wyi = if wy.is_empty() { 0.0 } else { wy[i] };
        let (vx0, vx1) = ((1.0 - wxi) * v, wxi * v);
        let planes = if wz.is_empty() {
            [(zo, 1.0), (zn, 0.0)]
        } else {
            [(zo, 1.0 - wz[i]), (zn, wz[i])]
        };
        for &(zoff, wzz) in &planes {
            if wzz == 0.0 {
                continue;
            }
            let b0 = zoff + yo;
            let b1 = zoff + yn;
            let f0 = wzz * (1.0 - wyi);
            let f1 = wzz * wyi;
            add(b0 + xo, f0 * vx0);
            add(b0 + xn, f0 * vx1);
            if f1 != 0.0 {
                add(b1 + xo, f1 * vx0);
                add(b1 + xn, f1 * vx1);
            }
        }
    }
}

/// `fc = P^T (f - A u)` (`u`'s periodic ghosts must be current; ghost
/// entries of `fc` along non-periodic axes receive contributions that are
/// never read, those along periodic axes are folded back).
///
/// Serially the residual is computed row by row and scattered at once,
/// without being stored. In parallel the residual rows are computed into
/// `w.r` first; then the coarse array is cut into blocks of units (rows in
/// 2D, planes in 3D) and each task scatters every fine row that reaches
/// its block, keeping only its block's entries. Every coarse entry thus
/// receives its contributions in the serial order, and the result is the
/// same to the bit.
fn restrict_residual<const D3: bool>(
    tr: &Transfer,
    fine: &Level,
    coarse: &Level,
    w: &mut Work,
    fc: &mut [f64],
) {
    use rayon::prelude::*;
    fc.fill(0.0);
    let [_, ny, nz] = fine.n;
    if !parallel(fine) {
        for k in 0..nz {
            for j in 0..ny {
                residual_row::<D3>(fine, &w.u, &w.f, j, k, &mut w.row);
                restrict_row(tr, fine, coarse, j, k, &w.row, |i, v| fc[i] += v);
            }
        }
        fold_ghosts(coarse, fc);
        return;
    }
    {
        let (u, f) = (&w.u, &w.f);
        rows_mut(fine, &mut w.r, &mut w.partial, true, |j, k, row, _| {
            residual_row::<D3>(fine, u, f, j, k, row);
        });
    }
    // Coarse units along the outermost axis, their stride, and the fine
    // units' targets there.
    let (units, stride, targets) = if D3 {
        (coarse.n[2] + 2, coarse.sz, &tr.tab[2])
    } else {
        (coarse.n[1] + 2, coarse.sy, &tr.tab[1])
    };
    let per_block = units
        .div_ceil(4 * rayon::current_num_threads())
        .max(PAR_MIN_UNITS / 2);
    let r = &w.r;
    let nx = fine.n[0];
    fc.par_chunks_mut(per_block * stride)
        .enumerate()
        .for_each(|(b, chunk)| {
            let (lo, hi) = (b * per_block, b * per_block + chunk.len() / stride);
            let base = lo * stride;
            let (first, last) = (base, base + chunk.len());
            for (t, &(own, nb)) in targets.iter().enumerate() {
                if !(lo..hi).contains(&own) && !(lo..hi).contains(&nb) {
                    continue;
                }
                let mut row = |j: usize, k: usize| {
                    let p0 = fine.pidx(0, j, k);
                    restrict_row(tr, fine, coarse, j, k, &r[p0..p0 + nx], |i, v| {
                        if (first..last).contains(&i) {
                            chunk[i - base] += v;
                        }
                    });
                };
                if D3 {
                    for j in 0..ny {
                        row(j, t);
                    }
                } else {
                    row(t, 0);
                }
            }
        });
    fold_ghosts(coarse, fc);
}

/// `u += P uc` (`uc`'s periodic ghosts must be current), row by row (in
/// parallel on a large level; each fine cell is written once, so the
/// result is the same either way). `slots` is scratch with one entry per
/// padded fine row.
fn prolong_add(
    tr: &Transfer,
    fine: &Level,
    coarse: &Level,
    uc: &[f64],
    u: &mut [f64],
    slots: &mut [f64],
) {
    let (sy, sz) = (coarse.sy, coarse.sz);
    let (tx, ty, tz) = (&tr.tab[0], &tr.tab[1], &tr.tab[2]);
    let zero: &[f64] = &[];
    let wz = if tr.w[2].is_empty() {
        zero
    } else {
        &tr.w[2][..]
    };
    rows_mut(fine, u, slots, parallel(fine), |j, k, urow, _| {
        let (zo, zn) = (tz[k].0 * sz, tz[k].1 * sz);
        let (yo, yn) = (ty[j].0 * sy, ty[j].1 * sy);
        let row = fine.pidx(0, j, k);
        for (i, (&(xo, xn), ui)) in tx.iter().zip(urow.iter_mut()).enumerate() {
            let p = row + i;
            let wx = if tr.w[0].is_empty() { 0.0 } else { tr.w[0][p] };
            let wy = if tr.w[1].is_empty() { 0.0 } else { tr.w[1][p] };
            let plane = |zoff: usize| {
                let b0 = zoff + yo;
                let b1 = zoff + yn;
                (1.0 - wy) * ((1.0 - wx) * uc[b0 + xo] + wx * uc[b0 + xn])
                    + wy * ((1.0 - wx) * uc[b1 + xo] + wx * uc[b1 + xn])
            };
            let s = if wz.is_empty() {
                plane(zo)
            } else {
                let w = wz[p];
                (1.0 - w) * plane(zo) + w * plane(zn)
            };
            *ui += s;
        }
    });
}

/// Names the coarsest level in a failed factorisation (e.g. an all-periodic
/// or all-Neumann operator whose tiny `diag_extra` is lost in round-off).
fn coarse_error(lv: &Level, e: SolverError) -> SolverError {
    match e {
        SolverError::Singular { detail } => SolverError::Singular {
            detail: format!(
                "multigrid coarsest level {:?} (periodic axes {:?}) is numerically singular: {detail}",
                lv.n, lv.periodic
            ),
        },
        other => other,
    }
}

impl Multigrid {
    /// Builds the hierarchy. Fails with [`SolverError::Singular`] if the
    /// operator is singular (see [`CellStencil::check_nonsingular`]) and
    /// with [`SolverError::InvalidInput`] for invalid data or options.
    pub fn new(stencil: &CellStencil, opts: &MgOptions) -> Result<Self> {
        let t0 = Instant::now();
        stencil.check_nonsingular()?;
        if opts.max_levels == 0 {
            return Err(SolverError::invalid("max_levels must be >= 1"));
        }
        if !(opts.omega > 0.0 && opts.omega < 2.0) {
            return Err(SolverError::invalid(format!(
                "smoother relaxation factor {} outside (0, 2)",
                opts.omega
            )));
        }
        let d3 = stencil.ndim() == 3;
        let periodic = std::array::from_fn(|a| stencil.is_periodic(a));
        let mut levels = Vec::new();
        let mut fine = Level::new(stencil.dims(), d3, periodic);
        if let Some(a) = fine.odd_periodic_axis() {
            if fine.cells() > opts.coarse_max_cells.max(1) && opts.max_levels > 1 {
                return Err(SolverError::invalid(format!(
                    "multigrid: periodic axis {a} has an odd number of cells ({}); red–black Gauss–Seidel needs an even count along a periodic axis (cells 0 and n−1 would be neighbours of the same colour); use an even grid or a direct solver",
                    fine.n[a]
                )));
            }
        }
        fine.fill_from_stencil(stencil);
        fine.compute_diag()?;
        levels.push(fine);
        let mut transfers = Vec::new();
        loop {
            let lv = levels.last().expect("at least one level");
            if lv.cells() <= opts.coarse_max_cells.max(1) || levels.len() >= opts.max_levels {
                break;
            }
            // A level with an odd periodic axis cannot be smoothed by
            // red–black Gauss–Seidel: it becomes the (directly solved)
            // coarsest level.
            if lv.odd_periodic_axis().is_some() {
                break;
            }
            let (nc, co) = coarse_dims(lv.n, d3);
            if !co.iter().any(|&c| c) {
                break;
            }
            let mut coarse = Level::new(nc, d3, lv.periodic);
            let mut tr =
                Transfer::new(lv, &coarse, co, opts.prolongation == Prolongation::Constant);
            coarsen_level(lv, &mut coarse, &mut tr);
            coarse.compute_diag()?;
            transfers.push(tr);
            levels.push(coarse);
        }
        let last = levels.last().expect("at least one level");
        let (coarse_asm, coarse_vals) = last.assembler()?;
        let coarse = Cholesky::with_pivot_tol(coarse_asm.matrix(), 0.0)
            .map_err(|e| coarse_error(last, e))?;
        let work = levels
            .iter()
            .map(|l| Work {
                u: vec![0.0; l.len],
                f: vec![0.0; l.len],
                row: vec![0.0; l.n[0]],
                r: vec![0.0; l.len],
                partial: vec![0.0; l.len / l.sy],
            })
            .collect();
        let cbuf = vec![0.0; last.cells()];
        Ok(Self {
            opts: *opts,
            levels,
            transfers,
            coarse_asm,
            coarse_vals,
            state: Mutex::new(State { work, coarse, cbuf }),
            setup_s: t0.elapsed().as_secs_f64(),
        })
    }

    /// Recomputes all level operators for new coefficients on the same grid
    /// (same dimensions and boundary kinds), reusing all memory (no
    /// allocation unless the coefficients disconnect the grid, see
    /// [`CellStencil::check_nonsingular`]); the coarsest factorisation is
    /// refactorised numerically only.
    pub fn refresh(&mut self, stencil: &CellStencil) -> Result<()> {
        let t0 = Instant::now();
        if stencil.dims() != self.levels[0].n {
            return Err(SolverError::invalid(format!(
                "grid dims {:?} differ from the hierarchy's {:?}",
                stencil.dims(),
                self.levels[0].n
            )));
        }
        let fine = &self.levels[0];
        let periodic: [bool; 3] =
            std::array::from_fn(|a| a < fine.ndim() && stencil.is_periodic(a) && fine.n[a] >= 2);
        if periodic != fine.periodic {
            return Err(SolverError::invalid(format!(
                "periodic axes {periodic:?} differ from the hierarchy's {:?}",
                fine.periodic
            )));
        }
        stencil.check_nonsingular()?;
        self.levels[0].fill_from_stencil(stencil);
        self.levels[0].compute_diag()?;
        for l in 0..self.transfers.len() {
            let (f, c) = self.levels.split_at_mut(l + 1);
            coarsen_level(&f[l], &mut c[0], &mut self.transfers[l]);
            c[0].compute_diag()?;
        }
        let last = self.levels.last().expect("levels");
        last.triplet_values(&mut self.coarse_vals);
        let m = self.coarse_asm.assemble(&self.coarse_vals)?;
        let state = match self.state.get_mut() {
            Ok(s) => s,
            Err(p) => p.into_inner(),
        };
        state
            .coarse
            .refactor(m)
            .map_err(|e| coarse_error(last, e))?;
        self.setup_s = t0.elapsed().as_secs_f64();
        Ok(())
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        match self.state.lock() {
            Ok(g) => g,
            Err(p) => p.into_inner(),
        }
    }

    /// Number of levels (1 = direct solve only).
    pub fn num_levels(&self) -> usize {
        self.levels.len()
    }

    /// Cell dimensions of level `l` (0 = finest).
    pub fn level_dims(&self, l: usize) -> Option<[usize; 3]> {
        self.levels.get(l).map(|lv| lv.n)
    }

    /// Seconds spent in [`Multigrid::new`] (or the last `refresh`).
    pub fn setup_s(&self) -> f64 {
        self.setup_s
    }

    /// Options used to build the hierarchy.
    pub fn options(&self) -> &MgOptions {
        &self.opts
    }

    /// Number of unknowns of the finest level.
    pub fn dim(&self) -> usize {
        self.levels[0].cells()
    }

    fn smooth(
        &self,
        l: usize,
        u: &mut [f64],
        f: &[f64],
        sweeps: usize,
        reverse: bool,
        from_zero: bool,
    ) {
        let lv = &self.levels[l];
        let first = usize::from(reverse);
        if sweeps > 0 {
            if lv.d3 {
                rb_sweeps::<true>(lv, u, f, first, self.opts.omega, from_zero, sweeps);
            } else {
                rb_sweeps::<false>(lv, u, f, first, self.opts.omega, from_zero, sweeps);
            }
        }
        if from_zero && sweeps == 0 {
            u.fill(0.0);
        }
    }

    /// `||f - A u||` on level `l`.
    fn residual_norm(&self, l: usize, w: &mut Work) -> f64 {
        let lv = &self.levels[l];
        fill_ghosts(lv, &mut w.u);
        let n2 = if lv.d3 {
            residual_norm2::<true>(lv, w)
        } else {
            residual_norm2::<false>(lv, w)
        };
        n2.sqrt()
    }

    fn coarse_solve(&self, st: &mut State) {
        let l = self.levels.len() - 1;
        let lv = &self.levels[l];
        let State { work, coarse, cbuf } = st;
        let w = &mut work[l];
        let [nx, ny, nz] = lv.n;
        let mut t = 0;
        for k in 0..nz {
            for j in 0..ny {
                let row = lv.pidx(0, j, k);
                cbuf[t..t + nx].copy_from_slice(&w.f[row..row + nx]);
                t += nx;
            }
        }
        // The coarsest matrix was factorised successfully, so the solve only
        // fails on non-finite input; the NaNs then propagate to the caller.
        let _ = coarse.solve_in_place(cbuf);
        let mut t = 0;
        for k in 0..nz {
            for j in 0..ny {
                let row = lv.pidx(0, j, k);
                w.u[row..row + nx].copy_from_slice(&cbuf[t..t + nx]);
                t += nx;
            }
        }
    }

    fn cycle(&self, l: usize, st: &mut State, zero_guess: bool) {
        if l + 1 == self.levels.len() {
            self.coarse_solve(st);
            return;
        }
        {
            let (a, b) = st.work.split_at_mut(l + 1);
            let w = &mut a[l];
            let (fine, coarse) = (&self.levels[l], &self.levels[l + 1]);
            self.smooth(l, &mut w.u, &w.f, self.opts.pre_smooth, false, zero_guess);
            fill_ghosts(fine, &mut w.u);
            if fine.d3 {
                restrict_residual::<true>(&self.transfers[l], fine, coarse, w, &mut b[0].f);
            } else {
                restrict_residual::<false>(&self.transfers[l], fine, coarse, w, &mut b[0].f);
            }
        }
        let visits = match self.opts.cycle {
            Cycle::V => 1,
            Cycle::W => 2,
        };
        for v in 0..visits {
            self.cycle(l + 1, st, v == 0);
        }
        let (a, b) = st.work.split_at_mut(l + 1);
        fill_ghosts(&self.levels[l + 1], &mut b[0].u);
        let w = &mut a[l];
        prolong_add(
            &self.transfers[l],
            &self.levels[l],
            &self.levels[l + 1],
            &b[0].u,
            &mut w.u,
            &mut w.partial,
        );
        self.smooth(l, &mut w.u, &w.f, self.opts.post_smooth, true, false);
    }

    /// Copies the compact vector `src` into the finest level's padded
    /// array `dst` (`slots`: scratch, one entry per padded row).
    fn load(&self, src: &[f64], dst: &mut [f64], slots: &mut [f64]) {
        let lv = &self.levels[0];
        let [nx, ny, _] = lv.n;
        rows_mut(lv, dst, slots, parallel(lv), |j, k, row, _| {
            let t = nx * (j + ny * k);
            row.copy_from_slice(&src[t..t + nx]);
        });
    }

    /// Copies the finest level's padded array `src` into the compact `dst`.
    fn store(&self, src: &[f64], dst: &mut [f64]) {
        use rayon::prelude::*;
        let lv = &self.levels[0];
        let [nx, ny, _] = lv.n;
        let copy = |(r, row): (usize, &mut [f64])| {
            let p0 = lv.pidx(0, r % ny, r / ny);
            row.copy_from_slice(&src[p0..p0 + nx]);
        };
        if parallel(lv) {
            dst.par_chunks_mut(nx)
                .enumerate()
                .with_min_len(PAR_MIN_UNITS)
                .for_each(copy);
        } else {
            dst.chunks_mut(nx).enumerate().for_each(copy);
        }
    }

    /// Stationary multigrid iteration `x ← x + M^{-1}(b − A x)` (one cycle
    /// per iteration) from the initial guess in `x` until the relative
    /// residual reaches `opts.rel_tol`. The report's `setup_s` is the
    /// hierarchy setup time.
    pub fn solve(&self, b: &[f64], x: &mut [f64], opts: &KrylovOptions) -> Result<SolveReport> {
        self.solve_impl(b, x, opts, None)
    }

    /// As [`Multigrid::solve`], also pushing the relative residual before
    /// the first and after every cycle to `history`.
    pub fn solve_with_history(
        &self,
        b: &[f64],
        x: &mut [f64],
        opts: &KrylovOptions,
        history: &mut Vec<f64>,
    ) -> Result<SolveReport> {
        self.solve_impl(b, x, opts, Some(history))
    }

    fn solve_impl(
        &self,
        b: &[f64],
        x: &mut [f64],
        opts: &KrylovOptions,
        mut history: Option<&mut Vec<f64>>,
    ) -> Result<SolveReport> {
        let t0 = Instant::now();
        let n = self.dim();
        check_len(n, b.len())?;
        check_len(n, x.len())?;
        let report = |iterations: usize, rel: f64| SolveReport {
            iterations,
            rel_residual: rel,
            setup_s: self.setup_s,
            solve_s: t0.elapsed().as_secs_f64(),
        };
        let bnorm = b.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !bnorm.is_finite() {
            return Err(SolverError::invalid("right-hand side is not finite"));
        }
        if bnorm == 0.0 {
            x.fill(0.0);
            return Ok(report(0, 0.0));
        }
        let mut guard = self.lock();
        let st = &mut *guard;
        {
            let w = &mut st.work[0];
            w.u.fill(0.0);
            self.load(b, &mut w.f, &mut w.partial);
            self.load(x, &mut w.u, &mut w.partial);
        }
        let mut rel = self.residual_norm(0, &mut st.work[0]) / bnorm;
        if let Some(h) = history.as_deref_mut() {
            h.push(rel);
        }
        let mut it = 0;
        while rel > opts.rel_tol {
            if it == opts.max_iter {
                self.store(&st.work[0].u, x);
                return Err(SolverError::NotConverged {
                    iterations: it,
                    rel_residual: rel,
                });
            }
            it += 1;
            self.cycle(0, st, false);
            rel = self.residual_norm(0, &mut st.work[0]) / bnorm;
            if let Some(h) = history.as_deref_mut() {
                h.push(rel);
            }
            if !rel.is_finite() {
                self.store(&st.work[0].u, x);
                return Err(SolverError::Breakdown {
                    iteration: it,
                    what: "multigrid residual is not finite".into(),
                });
            }
        }
        self.store(&st.work[0].u, x);
        Ok(report(it, rel))
    }
}

impl Preconditioner for Multigrid {
    /// One cycle on `A z = r` from `z = 0`.
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let mut guard = self.lock();
        let st = &mut *guard;
        let w = &mut st.work[0];
        self.load(r, &mut w.f, &mut w.partial);
        self.cycle(0, st, true);
        self.store(&st.work[0].u, z);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stencil::BoundaryKind;

    /// Values in [−1, 1), evenly spread and in no order (a Weyl sequence
    /// with the golden ratio, from `seed`).
    fn values(n: usize, seed: u64) -> Vec<f64> {
        (0..n)
            .map(|i| ((i as f64 + seed as f64) * 0.618_033_988_749_895).fract() * 2.0 - 1.0)
            .collect()
    }

    /// The finest level of a hierarchy on a field with a 1e3 jump, and a
    /// padded right-hand side and start (interior values, ghosts 0).
    fn level(dims: [usize; 3], bc: BoundaryKind) -> (Multigrid, Vec<f64>, Vec<f64>) {
        let n: usize = dims.iter().product();
        let k: Vec<f64> = values(n, 3)
            .iter()
            .map(|v| if *v > 0.6 { 1e3 } else { 1.0 })
            .collect();
        let mut st = CellStencil::from_cell_field(dims, &k, 1.0, bc).expect("stencil");
        st.diag_extra_mut().iter_mut().for_each(|v| *v = 1e-6);
        let mg = Multigrid::new(&st, &MgOptions::default()).expect("hierarchy");
        let lv = &mg.levels[0];
        let (mut f, mut u) = (vec![0.0; lv.len], vec![0.0; lv.len]);
        let mut slots = vec![0.0; lv.len];
        mg.load(&values(n, 5), &mut f, &mut slots);
        mg.load(&values(n, 9), &mut u, &mut slots);
        (mg, f, u)
    }

    /// Three sweeps fused into one pass give, to the bit, what three
    /// separate sweeps give, serial and in parallel blocks, from a start
    /// and from zero, in either colour order, in 2D and 3D, with a
    /// periodic outermost axis too (done sweep by sweep).
    #[test]
    fn fused_sweeps_equal_separate_sweeps_to_the_bit() {
        for (dims, bc) in [
            ([256, 256, 1], BoundaryKind::Dirichlet),
            ([301, 211, 1], BoundaryKind::Neumann),
            ([48, 50, 40], BoundaryKind::Dirichlet),
            ([96, 400, 1], BoundaryKind::Periodic),
        ] {
            let (mg, f, u0) = level(dims, bc);
            let lv = &mg.levels[0];
            let sweep = |u: &mut [f64], first, zero, sweeps| {
                if lv.d3 {
                    rb_sweeps::<true>(lv, u, &f, first, 1.2, zero, sweeps);
                } else {
                    rb_sweeps::<false>(lv, u, &f, first, 1.2, zero, sweeps);
                }
            };
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("pool");
                pool.install(|| {
                    for (first, zero) in [(0, false), (1, false), (0, true)] {
                        let mut fused = u0.clone();
                        sweep(&mut fused, first, zero, 3);
                        let mut apart = u0.clone();
                        for s in 0..3 {
                            sweep(&mut apart, first, zero && s == 0, 1);
                        }
                        let differ = bits(&fused)
                            .iter()
                            .zip(bits(&apart))
                            .position(|(a, b)| *a != b);
                        assert_eq!(
                            differ, None,
                            "{dims:?} {bc:?}, {threads} threads, first {first}, zero {zero}: first padded index that differs"
                        );
                        assert!(bits(&fused) != bits(&u0), "the sweeps changed nothing");
                    }
                });
            }
        }
    }
}
