//! York Sec. 4.1: Sod's shock tube with gas material points, against the
//! exact Riemann solution — the scene ([`york_sod_scene`], the same as
//! `cases/york_sod.toml` at any resolution), a run through the explicit
//! MPM model ([`run_york_sod`]) and its L1 density error.

use std::time::Instant;

use super::riemann::{ExactRiemann, PrimitiveState};
use crate::error::{Result, SceneError};
use crate::material::{ArtificialViscosity, PointDensity};
use crate::shape::ShapeKind;

/// One York Sod run's settings: a Riemann problem with gas points on a
/// strip one cell high, diaphragm at x = 0.5. The defaults are York's Sod
/// case; other states and a longer tube give the hard cases (a tube longer
/// than [0, 1] keeps the closed ends' reflections out of [0, 1] until
/// `end`).
#[derive(Debug, Clone, Copy)]
pub struct YorkSod {
    /// Cells per unit length along x (York: 200, Δx = 0.005); the strip is
    /// one cell high.
    pub cells: usize,
    /// Points per cell per direction (York: 3 along x; the strip's y rows
    /// carry identical states).
    pub ppc: usize,
    /// Shape function (York: bilinear hats, `Linear`).
    pub shape: ShapeKind,
    /// Artificial viscosity `(g/Δx, κ̃, c₁, c₂)` (York Eqs. 24–25).
    pub q: (f64, f64, f64, f64),
    /// Courant number.
    pub cfl: f64,
    /// End time (York: 0.143).
    pub end: f64,
    /// Left state `(ρ, u, p)` (x < 0.5).
    pub left: (f64, f64, f64),
    /// Right state `(ρ, u, p)` (x > 0.5).
    pub right: (f64, f64, f64),
    /// The tube `[lower, upper]` along x, closed at both ends (York: [0, 1]).
    pub tube: (f64, f64),
    /// PIC share of the point velocity update (`mpm.pic_fraction`; York: 0,
    /// FLIP).
    pub pic_fraction: f64,
    /// Where the points' density comes from (`point_density`; York Eq. 16:
    /// continuity).
    pub point_density: PointDensity,
}

impl Default for YorkSod {
    /// The case of `cases/york_sod.toml`.
    fn default() -> Self {
        Self {
            cells: 200,
            ppc: 3,
            shape: ShapeKind::Gimp,
            q: (
                ArtificialViscosity::DEFAULT_G_OVER_DX,
                ArtificialViscosity::DEFAULT_KAPPA,
                ArtificialViscosity::DEFAULT_C1,
                ArtificialViscosity::DEFAULT_C2,
            ),
            cfl: 0.4,
            end: 0.143,
            left: SOD_LEFT,
            right: SOD_RIGHT,
            tube: (0.0, 1.0),
            pic_fraction: 0.0,
            point_density: PointDensity::Continuity,
        }
    }
}

/// The left and right states of Sod's problem `(ρ, u, p)`, diaphragm at
/// x = 0.5, γ = 1.4.
pub const SOD_LEFT: (f64, f64, f64) = (1.0, 0.0, 1.0);
/// See [`SOD_LEFT`].
pub const SOD_RIGHT: (f64, f64, f64) = (0.125, 0.0, 0.1);

/// The scene text of a York Sod run (`cases/york_sod.toml` at `s.cells`).
pub fn york_sod_scene(s: &YorkSod) -> String {
    let h = 1.0 / s.cells as f64;
    let shape = s.shape.name();
    let (g, kappa, c1, c2) = s.q;
    let (lo, hi) = s.tube;
    format!(
        r#"
description = "York Sec. 4.1, Sod with gas points"
[grid]
dim = 2
lower = [{lo:e}, 0.0]
upper = [{hi:e}, {h:e}]
cells = [{n}, 1]
boundary = {{ x_lower = "symmetry", x_upper = "symmetry", y_lower = "symmetry", y_upper = "symmetry" }}
[time]
end = {end:e}
cfl = {cfl:e}
[mpm]
shape = "{shape}"
update = "musl"
pic_fraction = {pic:e}
[[materials]]
name = "gas"
type = "fluid"
frame = "particles"
eos = "ideal_gas"
gamma = 1.4
cv = 2.5
artificial_viscosity = {{ g_over_dx = {g:e}, kappa = {kappa:e}, c1 = {c1:e}, c2 = {c2:e} }}
point_density = "{density}"
[[objects]]
material = "gas"
geometry = {{ type = "box", lower = [{lo:e}, 0.0], upper = [0.5, {h:e}] }}
particles_per_cell = {ppc}
density = {rl:e}
pressure = {pl:e}
velocity = [{ul:e}, 0.0]
[[objects]]
material = "gas"
geometry = {{ type = "box", lower = [0.5, 0.0], upper = [{hi:e}, {h:e}] }}
particles_per_cell = {ppc}
density = {rr:e}
pressure = {pr:e}
velocity = [{ur:e}, 0.0]
"#,
        n = ((hi - lo) * s.cells as f64).round() as usize,
        end = s.end,
        cfl = s.cfl,
        pic = s.pic_fraction,
        density = s.point_density.name(),
        ppc = s.ppc,
        rl = s.left.0,
        ul = s.left.1,
        pl = s.left.2,
        rr = s.right.0,
        ur = s.right.1,
        pr = s.right.2,
    )
}

/// The exact solution of Sod's problem (γ = 1.4).
///
/// # Errors
/// None for these states (the exact solver's errors are mapped to a scene
/// error for completeness).
pub fn sod_exact() -> Result<ExactRiemann> {
    riemann_exact(SOD_LEFT, SOD_RIGHT)
}

/// The exact solution of the Riemann problem `left | right` `(ρ, u, p)`,
/// γ = 1.4.
///
/// # Errors
/// States the exact solver rejects (vacuum generated, non-positive
/// density or pressure), as a scene error.
pub fn riemann_exact(left: (f64, f64, f64), right: (f64, f64, f64)) -> Result<ExactRiemann> {
    ExactRiemann::solve(
        PrimitiveState::new(left.0, left.1, left.2),
        PrimitiveState::new(right.0, right.1, right.2),
        1.4,
    )
    .map_err(|e| SceneError::new("york_sod", e.to_string()).into())
}

/// A York Sod run's result.
#[derive(Debug, Clone)]
pub struct YorkSodRun {
    /// L1 density error ∫|ρ − ρ_exact| dx over [0, 1], by particle
    /// quadrature: Σ_p |m_p/V_p − ρ_exact(x_p)| V_p / H over the points in
    /// [0, 1] (H the strip height).
    pub l1_density: f64,
    /// Smallest and largest point density over the whole tube.
    pub density_range: (f64, f64),
    /// Smallest specific internal energy over the whole tube.
    pub energy_min: f64,
    /// Wall time of the time loop \[s\].
    pub wall_s: f64,
    /// Time steps taken.
    pub steps: u64,
    /// Number of gas points.
    pub particles: usize,
    /// Per point of the bottom row, in x order: `[x, ρ, u, p, e]` (York
    /// Fig. 6's variables; e the specific internal energy).
    pub profile: Vec<[f64; 5]>,
}

/// Runs York Sod through the scene path and the explicit MPM model's step,
/// and measures it against the exact solution.
///
/// # Errors
/// A scene or numerical error.
pub fn run_york_sod(s: &YorkSod) -> Result<YorkSodRun> {
    let scene = crate::scene::parse(&york_sod_scene(s))?;
    let mut run = crate::scene::build_solid_run::<2>(&scene)?;
    let start = Instant::now();
    while !run.finished() {
        run.step()?;
    }
    let wall_s = start.elapsed().as_secs_f64();
    let exact = riemann_exact(s.left, s.right)?;
    let height = 1.0 / s.cells as f64;
    let p = &run.particles;
    let gas = run.materials[0].gas().copied();
    let mut l1 = 0.0;
    let mut profile = Vec::new();
    let (mut rho_lo, mut rho_hi, mut e_lo) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY);
    for i in 0..p.len() {
        let x = p.x[i][0];
        let rho = p.mass[i] / p.vol[i];
        let e = p.work_of(i) * p.vol0[i] / p.mass[i];
        rho_lo = rho_lo.min(rho);
        rho_hi = rho_hi.max(rho);
        e_lo = e_lo.min(e);
        if !(0.0..=1.0).contains(&x) {
            continue;
        }
        let ex = exact.sample((x - 0.5) / run.t);
        l1 += (rho - ex.rho).abs() * p.vol[i];
        if p.x0[i][1] < height / s.ppc as f64 {
            let pr = gas.map_or(0.0, |g| g.pressure(rho, e));
            profile.push([x, rho, p.v[i][0], pr, e]);
        }
    }
    profile.sort_by(|a, b| a[0].total_cmp(&b[0]));
    Ok(YorkSodRun {
        l1_density: l1 / height,
        density_range: (rho_lo, rho_hi),
        energy_min: e_lo,
        wall_s,
        steps: run.steps,
        particles: p.len(),
        profile,
    })
}

/// York Sec. 4.2's piston–container: a spring of stiffness `K` and length
/// `L` (elastic material points) fixed at x = 0, a heavy piston point of
/// mass `m` at its end, and a column of compressible, inviscid gas of
/// density `ρ`, bulk modulus `b` and length `L` closed by a wall.
///
/// The text loses `b`'s exponent ("b = 1.58 × 10"); Table I's exact
/// frequencies fix it: Eq. 27 at ω = 281.2 rad/s, m = 1 gives
/// `ρ ω c cot(ωL/c) = m ω² − K = 78976`, and with `ωL/c ≪ 1` (cot x ≈ 1/x)
/// `ρ c²/L ≈ 78976`, so `b = ρ c² ≈ 1.58 × 10⁶`; the m = 0.1 root 886.2 rad/s
/// then agrees to 0.1 %.
#[derive(Debug, Clone, Copy)]
pub struct PistonContainer {
    /// Piston mass m (York: 0.1 and 1.0).
    pub mass: f64,
    /// Spring constant K (York: 100).
    pub k: f64,
    /// Spring and gas column length L (York: 20).
    pub length: f64,
    /// Gas density ρ (York: 1e-4).
    pub rho: f64,
    /// Gas (isentropic) bulk modulus b (recovered: 1.58e6).
    pub bulk: f64,
    /// Cell size.
    pub h: f64,
    /// Initial piston velocity (small).
    pub v0: f64,
    /// Number of periods of Eq. 27's root to run.
    pub periods: f64,
    /// Courant number.
    pub cfl: f64,
}

impl Default for PistonContainer {
    /// York Sec. 4.2 with m = 0.1 at h = 0.5.
    fn default() -> Self {
        Self {
            mass: 0.1,
            k: 100.0,
            length: 20.0,
            rho: 1e-4,
            bulk: 1.58e6,
            h: 0.5,
            v0: 0.1,
            periods: 2.0,
            cfl: 0.4,
        }
    }
}

impl PistonContainer {
    /// The fundamental root of York Eq. 27,
    /// `ω − √([K + ρ ω c A cot(ωL/c)]/m) = 0` (A = 1, c = √(b/ρ)), by
    /// bisection of `m ω² − K − ρ ω c cot(ωL/c)` on (0, π c/L).
    pub fn exact_omega(&self) -> f64 {
        let c = (self.bulk / self.rho).sqrt();
        let f = |w: f64| {
            let x = w * self.length / c;
            self.mass * w * w - self.k - self.rho * w * c * x.cos() / x.sin()
        };
        let (mut lo, mut hi) = (1e-9, std::f64::consts::PI * c / self.length * (1.0 - 1e-12));
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if f(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// The scene (1D): spring `[0, L]` (linear elastic, ν = 0, E = K L so
    /// E A / L = K, density 1e-3 m / L: its mass is 0.1 % of the piston's),
    /// the piston one cell `[L, L + h]` holding one point of mass m (stiff:
    /// E = 1e9), the gas `[L + h, 2L + h]` on points — a stiffened gas at
    /// p = 0 with p_∞ = b/γ, so its bulk modulus γ(p + p_∞) is b — and
    /// fixed walls at both ends. Two points per cell per direction in the
    /// spring and the gas.
    pub fn scene(&self) -> String {
        let (l, h) = (self.length, self.h);
        let cells = ((2.0 * l + h) / h).round() as usize;
        let gamma = 1.4;
        let end = self.periods * 2.0 * std::f64::consts::PI / self.exact_omega();
        format!(
            r#"
description = "York Sec. 4.2 piston-container"
[grid]
dim = 1
lower = [0.0]
upper = [{upper:e}]
cells = [{cells}]
boundary = {{ x_lower = "fixed", x_upper = "fixed" }}
[time]
end = {end:e}
cfl = {cfl:e}
[mpm]
shape = "gimp"
update = "musl"
particles_per_cell = 2
[[materials]]
name = "spring"
type = "solid"
model = "linear_elastic"
density = {rho_s:e}
youngs_modulus = {e_s:e}
poisson_ratio = 0.0
[[materials]]
name = "piston"
type = "solid"
model = "linear_elastic"
density = {rho_p:e}
youngs_modulus = 1e9
poisson_ratio = 0.0
[[materials]]
name = "gas"
type = "fluid"
frame = "particles"
eos = "stiffened_gas"
gamma = {gamma}
cv = 1.0
p_inf = {p_inf:e}
[[objects]]
material = "spring"
geometry = {{ type = "box", lower = [0.0], upper = [{l:e}] }}
[[objects]]
material = "piston"
geometry = {{ type = "box", lower = [{l:e}], upper = [{lh:e}] }}
particles_per_cell = 1
velocity = [{v0:e}]
[[objects]]
material = "gas"
geometry = {{ type = "box", lower = [{lh:e}], upper = [{upper:e}] }}
density = {rho:e}
pressure = 0.0
"#,
            upper = 2.0 * l + h,
            cfl = self.cfl,
            rho_s = 1e-5 * self.mass / l,
            e_s = self.k * l,
            rho_p = self.mass / h,
            p_inf = self.bulk / gamma,
            lh = l + h,
            v0 = self.v0,
            rho = self.rho,
        )
    }
}

/// A piston–container run's result.
#[derive(Debug, Clone)]
pub struct PistonRun {
    /// Exact ω of Eq. 27 [rad/s].
    pub omega_exact: f64,
    /// Measured period \[s\]: `2π/ω` of the single-frequency least-squares
    /// fit of the displacement history ([`fit_frequency`]), which averages
    /// out the gas column's and the spring's high-frequency ripple.
    pub period: f64,
    /// The period from the mean spacing of the piston velocity's downward
    /// zero crossings (linearly interpolated) \[s\]: the fit's starting guess.
    /// The ripple shifts each crossing by its velocity over the
    /// fundamental's slope, and the finer the grid the less the ripple is
    /// damped, so this estimate does not converge (m = 0.1, three periods:
    /// 6.8e-5, 1.1e-4, 1.6e-4 at h = 1, 0.5, 0.25).
    pub period_crossings: f64,
    /// Piston displacement history `(t, x − x0)`.
    pub history: Vec<(f64, f64)>,
    /// Wall time \[s\].
    pub wall_s: f64,
    /// Steps.
    pub steps: u64,
}

/// Runs the piston–container and measures its period.
///
/// # Errors
/// A scene or numerical error, or fewer than two measured crossings.
pub fn run_piston_container(s: &PistonContainer) -> Result<PistonRun> {
    let scene = crate::scene::parse(&s.scene())?;
    let mut run = crate::scene::build_solid_run::<1>(&scene)?;
    let piston = run
        .materials
        .iter()
        .position(|m| m.name == "piston")
        .and_then(|k| run.particles.material.iter().position(|&q| q as usize == k))
        .ok_or_else(|| SceneError::new("objects[1]", "no piston point"))?;
    let x0 = run.particles.x[piston][0];
    let mut history = vec![(0.0, 0.0)];
    let mut crossings = Vec::new();
    let mut prev = (0.0, run.particles.v[piston][0]);
    let start = Instant::now();
    while !run.finished() {
        run.step()?;
        let (t, v) = (run.t, run.particles.v[piston][0]);
        history.push((t, run.particles.x[piston][0] - x0));
        if prev.1 > 0.0 && v <= 0.0 {
            crossings.push(prev.0 + (t - prev.0) * prev.1 / (prev.1 - v));
        }
        prev = (t, v);
    }
    let wall_s = start.elapsed().as_secs_f64();
    if crossings.len() < 2 {
        return Err(SceneError::new(
            "time.end",
            format!(
                "{} velocity crossings; need ≥ 2 to measure a period",
                crossings.len()
            ),
        )
        .into());
    }
    let period_crossings =
        (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let omega = fit_frequency(&history, 2.0 * std::f64::consts::PI / period_crossings);
    Ok(PistonRun {
        omega_exact: s.exact_omega(),
        period: 2.0 * std::f64::consts::PI / omega,
        period_crossings,
        history,
        wall_s,
        steps: run.steps,
    })
}

/// The angular frequency ω of the single sinusoid that best fits a sampled
/// history `(t, x)` in least squares, `x ≈ a sin ωt + b cos ωt + c`,
/// weighted by a Hann window over the record (it suppresses the leakage of
/// other frequencies into the fit, which an unweighted fit over a
/// non-integer number of periods keeps): for each trial ω the amplitudes
/// `(a, b, c)` solve the 3×3 weighted normal equations,
/// and ω minimises the residual by golden-section search within ±5 % of
/// `guess` (the fit's main lobe is ±1/(periods) wide, so the bracket holds
/// one minimum for runs of up to about ten periods).
pub fn fit_frequency(history: &[(f64, f64)], guess: f64) -> f64 {
    let (Some(first), Some(last)) = (history.first(), history.last()) else {
        return guess;
    };
    let (t0, span) = (first.0, (last.0 - first.0).max(f64::MIN_POSITIVE));
    let hann = |t: f64| (std::f64::consts::PI * (t - t0) / span).sin().powi(2);
    let residual = |w: f64| {
        let mut m = nalgebra::Matrix3::<f64>::zeros();
        let mut r = nalgebra::Vector3::<f64>::zeros();
        for &(t, x) in history {
            let phi = nalgebra::Vector3::new((w * t).sin(), (w * t).cos(), 1.0);
            m += phi * phi.transpose() * hann(t);
            r += phi * (x * hann(t));
        }
        let Some(c) = m.lu().solve(&r) else {
            return f64::INFINITY;
        };
        history
            .iter()
            .map(|&(t, x)| {
                let f = c[0] * (w * t).sin() + c[1] * (w * t).cos() + c[2];
                hann(t) * (x - f) * (x - f)
            })
            .sum::<f64>()
    };
    let ratio = 0.5 * (5f64.sqrt() - 1.0);
    let (mut lo, mut hi) = (0.95 * guess, 1.05 * guess);
    let mut a = hi - ratio * (hi - lo);
    let mut b = lo + ratio * (hi - lo);
    let (mut fa, mut fb) = (residual(a), residual(b));
    while hi - lo > 1e-12 * guess {
        if fa < fb {
            hi = b;
            b = a;
            fb = fa;
            a = hi - ratio * (hi - lo);
            fa = residual(a);
        } else {
            lo = a;
            a = b;
            fa = fb;
            b = lo + ratio * (hi - lo);
            fb = residual(b);
        }
    }
    0.5 * (lo + hi)
}
