//! Convergence and work-precision studies of the explicit multi-material
//! ICE fluid solver (`mpmice::ice`): Sod against the exact Riemann solution,
//! an advected entropy wave, and a linear acoustic wave.

use std::f64::consts::PI;

use anyhow::{Context, Result};
use nalgebra::SVector;

use crate::harness::{plot_xy, PlotSeries, Point, Series, StudyResult, Style};
use mpmice::diagnostics::riemann::{ExactRiemann, PrimitiveState};
use mpmice::ice::{
    periodic_vortex, periodic_vortex_exact, run_fluid, shock_tube, Advection, CellLayout,
    IceBoundary, IceMaterial, IceParams, IceState, Limiter, LinearSolver, MaterialInit,
    SemiImplicit,
};
use mpmice::material::eos::IdealGas;

fn gas(gamma: f64) -> Result<IceMaterial> {
    Ok(IceMaterial::new(
        "gas",
        IdealGas::new(gamma, 1.0 / (gamma - 1.0))?,
    ))
}

fn label(adv: Advection) -> &'static str {
    match adv {
        Advection::FirstOrder => "first order (donor cell)",
        Advection::SecondOrder(Limiter::VanLeer) => "second order (van Leer)",
        Advection::SecondOrder(Limiter::MonotonizedCentral) => "second order (MC)",
        Advection::SecondOrder(Limiter::Superbee) => "second order (superbee)",
        Advection::SecondOrder(Limiter::Minmod) => "second order (minmod)",
        Advection::DimensionByDimension(Limiter::VanLeer) => {
            "second order, dimension by dimension (van Leer)"
        }
        Advection::DimensionByDimension(Limiter::MonotonizedCentral) => {
            "second order, dimension by dimension (MC)"
        }
        Advection::DimensionByDimension(Limiter::Superbee) => {
            "second order, dimension by dimension (superbee)"
        }
        Advection::DimensionByDimension(Limiter::Minmod) => {
            "second order, dimension by dimension (minmod)"
        }
    }
}

fn periodic1() -> [[IceBoundary<1>; 2]; 1] {
    [[IceBoundary::Periodic, IceBoundary::Periodic]]
}

/// A 2D density wave `ρ = 1 + 0.2 sin 2πx sin 2πy` advected diagonally at
/// `u = (1, 1)` with uniform `p = 10⁻⁴` (so `c ≈ 0.012` and the Courant
/// number is essentially advective) on the periodic unit square to `t = 1`
/// (one period: the exact solution is the initial state). Explicit ICE at
/// `cfl = 0.1, 0.4, 1` (`ν = |u_d| Δt/h ≈ 0.05, 0.2, 0.49` per direction),
/// corner transport (the default second order) against the
/// dimension-by-dimension scheme: L1 density error against N, and its
/// growth with the Courant number.
///
/// # Errors
/// Any solver error.
pub fn ice_diagonal_wave(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick { &[32, 64] } else { &[32, 64, 128] };
    let rho = |x: &SVector<f64, 2>| 1.0 + 0.2 * (2.0 * PI * x[0]).sin() * (2.0 * PI * x[1]).sin();
    let periodic = [
        [IceBoundary::Periodic, IceBoundary::Periodic],
        [IceBoundary::Periodic, IceBoundary::Periodic],
    ];
    let mut series = Vec::new();
    let mut notes = vec![
        "2D entropy wave along (1, 1), p = 1e-4 (Mach ~ 120: pressure and velocity stay uniform, the density translates), explicit ICE, van Leer; nu = N/steps (per direction); L1 density error at t = 1 (one period)".to_string(),
    ];
    let cfls = [0.1, 0.4, 0.7, 1.0];
    for adv in [
        Advection::SecondOrder(Limiter::VanLeer),
        Advection::DimensionByDimension(Limiter::VanLeer),
    ] {
        let mut finest = Vec::new();
        'cfl: for cfl in cfls {
            let mut points = Vec::new();
            let mut nu = 0.0;
            for &n in ns {
                let h = 1.0 / n as f64;
                let layout = CellLayout::<2>::new(
                    SVector::<f64, 2>::zeros(),
                    SVector::<f64, 2>::new(h, h),
                    [n, n],
                )?;
                let st = IceState::new(layout, vec![gas(1.4)?], |x| {
                    vec![MaterialInit::new(
                        1.0,
                        rho(x),
                        1e-4,
                        SVector::<f64, 2>::new(1.0, 1.0),
                    )]
                })?;
                let mut params = IceParams::new(periodic.clone());
                params.advection = adv;
                params.cfl = cfl;
                let run = match run_fluid(st, &params, 1.0, 10_000_000) {
                    Ok(run) => run,
                    Err(e) => {
                        // Reported, not hidden: the dimension-by-dimension
                        // scheme is unstable near Σ_d ν_d = 1.
                        notes.push(format!("{}, cfl {cfl}, N = {n}: failed: {e}", label(adv)));
                        continue 'cfl;
                    }
                };
                let s = &run.state;
                let err = density_l1(s, |x| rho(x));
                nu = n as f64 / run.steps as f64;
                let ups = ((n * n) as f64 * run.steps as f64) / run.wall_s.max(1e-12);
                points.push(
                    Point::new(h, err, run.wall_s, ups)
                        .with_extra("steps", run.steps as f64)
                        .with_extra("courant", nu),
                );
            }
            if let Some(p) = points.last() {
                finest.push((nu, p.error));
            }
            series.push(Series::new(
                format!("{}, nu {nu:.3}", label(adv)),
                "L1",
                points,
            ));
        }
        if let (Some(a), Some(b)) = (finest.first(), finest.last()) {
            notes.push(format!(
                "{}: N = {}: L1 at nu = {:.3} / L1 at nu = {:.3} = {:.2}",
                label(adv),
                ns[ns.len() - 1],
                b.0,
                a.0,
                b.1 / a.1
            ));
        }
    }
    Ok(StudyResult {
        study: "ice_diagonal_wave".into(),
        h_axis: "cell size Δx = 1/N, unit square (nondimensional) [-]".into(),
        error_axis: "L1 density error vs exact at cell centres (nondimensional) [-]".into(),
        series,
        notes,
    })
}

/// Sod's shock tube, `(ρ, u, p) = (1, 0, 1) | (0.125, 0, 0.1)`, `γ = 1.4`,
/// `x0 = 0.5`, `t = 0.2`: mean L1 density error against the exact cell
/// averages, for first- and second-order advection.
///
/// # Errors
/// Any solver or exact-solution error.
pub fn ice_sod(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick {
        &[100, 200, 400]
    } else {
        &[100, 200, 400, 800, 1600, 3200]
    };
    let (l, r) = ((1.0, 0.0, 1.0), (0.125, 0.0, 0.1));
    let exact = ExactRiemann::solve(
        PrimitiveState::new(l.0, l.1, l.2),
        PrimitiveState::new(r.0, r.1, r.2),
        1.4,
    )?;
    let bcs = [[IceBoundary::Outflow, IceBoundary::Outflow]];
    let literal = |adv: Advection, face_dt: f64| {
        let mut p = IceParams::new(bcs.clone());
        p.advection = adv;
        p.face_dt_factor = face_dt;
        p
    };
    let variants: Vec<(IceParams<1>, String)> = vec![
        (
            literal(Advection::FirstOrder, 1.0),
            label(Advection::FirstOrder).into(),
        ),
        (
            literal(Advection::SecondOrder(Limiter::VanLeer), 1.0),
            label(Advection::SecondOrder(Limiter::VanLeer)).into(),
        ),
        (
            literal(Advection::SecondOrder(Limiter::MonotonizedCentral), 1.0),
            label(Advection::SecondOrder(Limiter::MonotonizedCentral)).into(),
        ),
        (
            literal(Advection::SecondOrder(Limiter::VanLeer), 0.5),
            "second order (van Leer), Eq. 28 with Δt/2".into(),
        ),
        (
            IceParams::high_resolution(bcs.clone()),
            "high resolution (MUSCL Eq. 28, p_eq + Δp/2, superbee, cfl 0.4)".into(),
        ),
        (
            IceParams {
                cfl: 0.5,
                ..IceParams::high_resolution(bcs.clone())
            },
            "high resolution, cfl 0.5".into(),
        ),
        (
            IceParams {
                advection: Advection::SecondOrder(Limiter::MonotonizedCentral),
                face_reconstruction: Some(Limiter::MonotonizedCentral),
                cfl: 0.5,
                ..IceParams::high_resolution(bcs.clone())
            },
            "high resolution with MC, cfl 0.5".into(),
        ),
        (
            IceParams::hancock(bcs.clone()),
            "Hancock (high resolution + MUSCL-Hancock face states, α 0.625, cfl 0.8)".into(),
        ),
        (
            IceParams {
                cfl: 0.4,
                face_dt_factor: 1.0,
                ..IceParams::hancock(bcs.clone())
            },
            "Hancock, α 1, cfl 0.4".into(),
        ),
        (
            IceParams::hancock_acoustic(bcs.clone()),
            "acoustic Hancock (switched: acoustic jump λ 0.5, Δp weight 1 in compression / 0.4 in expansion, shock-sensed face viscosity 0.25, cfl 0.9)".into(),
        ),
    ];
    let mut series = Vec::new();
    let mut notes = vec![
        "explicit ICE (Guilkey Sec. 3.1), conservative energy form, forward Euler; literal variants cfl = 0.5 on |u| + c".to_string(),
        "reference: a Fortran Roe/MC code reaches L1 = 5.1e-4 in 0.053 s (N = 800) and 3.1e-4 in 0.16 s (N = 1600) on this machine".to_string(),
    ];
    for (params, series_label) in variants {
        let mut points = Vec::new();
        for &n in ns {
            let st = shock_tube(gas(1.4)?, n, l, r, 0.5)?;
            let run =
                run_fluid(st, &params, 0.2, 10_000_000).with_context(|| format!("Sod N = {n}"))?;
            let h = 1.0 / n as f64;
            let err = exact.l1_density_error(&run.state, 0.5)?;
            let ups = (n as f64 * run.steps as f64) / run.wall_s.max(1e-12);
            points.push(Point::new(h, err, run.wall_s, ups).with_extra("steps", run.steps as f64));
        }
        if let Some(p) = points.iter().find(|p| (p.h - 1.0 / 400.0).abs() < 1e-12) {
            notes.push(format!(
                "{series_label}: L1 at N = 400 = {:.3e} (target ≤ 1.5e-3)",
                p.error
            ));
        }
        for (target, fortran) in [(5.1e-4, 0.053), (3.1e-4, 0.16)] {
            let line = match wall_to_reach(&points, target) {
                Some((t, extrapolated)) => format!(
                    "{series_label}: wall time to reach L1 = {target:.1e}: {t:.3} s{} (Fortran Roe/MC: {fortran} s, ratio {:.2})",
                    if extrapolated { " (extrapolated)" } else { "" },
                    t / fortran
                ),
                None => format!("{series_label}: L1 = {target:.1e} not bracketed"),
            };
            eprintln!("{line}");
            notes.push(line);
        }
        series.push(Series::new(series_label, "L1", points));
    }
    Ok(StudyResult {
        study: "ice_sod".into(),
        h_axis: "cell size Δx = 1/N (nondimensional) [-]".into(),
        error_axis: "L1 density error vs exact cell averages (nondimensional) [-]".into(),
        series,
        notes,
    })
}

/// Wall time at which a series (points ordered by decreasing `h`) reaches
/// the error `target`: log-log interpolation of wall time against error
/// between the two points that bracket it, or extrapolation from the last
/// two points (flagged `true`) when the finest error is still above it.
/// `None` when every error is below the target or fewer than two points.
pub fn wall_to_reach(points: &[Point], target: f64) -> Option<(f64, bool)> {
    if points.len() < 2 || points[0].error <= target {
        return None;
    }
    let interp = |a: &Point, b: &Point| {
        let s = (target.ln() - a.error.ln()) / (b.error.ln() - a.error.ln());
        (a.wall_s.ln() + s * (b.wall_s.ln() - a.wall_s.ln())).exp()
    };
    for w in points.windows(2) {
        if w[0].error > target && w[1].error <= target {
            return Some((interp(&w[0], &w[1]), false));
        }
    }
    let n = points.len();
    let (a, b) = (&points[n - 2], &points[n - 1]);
    (b.error < a.error).then(|| (interp(a, b), true))
}

/// A density wave `ρ = 1 + 0.2 sin 2πx` advected at `u = 1`, `p = 1`
/// (periodic, one period, `t = 1`): the exact solution is the translation.
///
/// # Errors
/// Any solver error.
pub fn ice_entropy_wave(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick {
        &[32, 64, 128]
    } else {
        &[32, 64, 128, 256, 512]
    };
    let rho = |x: f64| 1.0 + 0.2 * (2.0 * PI * x).sin();
    let mut series = Vec::new();
    let literal = |adv: Advection| {
        let mut p = IceParams::new(periodic1());
        p.advection = adv;
        (p, label(adv).to_string())
    };
    for (params, series_label) in [
        literal(Advection::FirstOrder),
        literal(Advection::SecondOrder(Limiter::VanLeer)),
        literal(Advection::SecondOrder(Limiter::MonotonizedCentral)),
        (
            IceParams::hancock(periodic1()),
            "Hancock (superbee, cfl 0.8)".to_string(),
        ),
        (
            IceParams::hancock_acoustic(periodic1()),
            "acoustic Hancock (superbee, cfl 0.9)".to_string(),
        ),
    ] {
        let mut points = Vec::new();
        for &n in ns {
            let h = 1.0 / n as f64;
            let layout =
                CellLayout::<1>::new(SVector::<f64, 1>::zeros(), SVector::<f64, 1>::new(h), [n])?;
            let st = IceState::new(layout, vec![gas(1.4)?], |x| {
                vec![MaterialInit::new(
                    1.0,
                    rho(x[0]),
                    1.0,
                    SVector::<f64, 1>::new(1.0),
                )]
            })?;
            let run = run_fluid(st, &params, 1.0, 10_000_000)?;
            let s = &run.state;
            let err = density_l1(s, |x| rho(x[0] - 1.0));
            let ups = (n as f64 * run.steps as f64) / run.wall_s.max(1e-12);
            points.push(Point::new(h, err, run.wall_s, ups));
        }
        series.push(Series::new(series_label, "L1", points));
    }
    Ok(StudyResult {
        study: "ice_entropy_wave".into(),
        h_axis: "cell size Δx = 1/N (nondimensional) [-]".into(),
        error_axis: "L1 density error vs exact at cell centres (nondimensional) [-]".into(),
        series,
        notes: vec!["density wave at uniform u = 1, p = 1, gamma = 1.4, periodic, t = 1, cfl = 0.5 on |u| + c (Hancock 0.8, acoustic Hancock 0.9); L1 = mean |ρ − ρ_exact| over cells (cell-centre samples)".into()],
    })
}

/// A right-running linear acoustic wave `ρ = 1 + ε sin 2πx`,
/// `u = c ε sin 2πx`, `p = 1/γ + ε sin 2πx` (`c = 1`, `ε = 1e-5`), periodic,
/// one period: L1 of the density perturbation error relative to `ε`.
///
/// # Errors
/// Any solver error.
pub fn ice_acoustic(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick {
        &[32, 64, 128]
    } else {
        &[32, 64, 128, 256, 512]
    };
    let gamma = 1.4;
    let eps = 1e-5;
    let wave = |x: f64| (2.0 * PI * x).sin();
    let mut series = Vec::new();
    let lit = |time| {
        let mut p = IceParams::new(periodic1());
        p.time = time;
        p
    };
    for (params, tag) in [
        (
            lit(mpmice::ice::TimeIntegration::ForwardEuler),
            "second order (van Leer), forward Euler",
        ),
        (
            lit(mpmice::ice::TimeIntegration::Heun),
            "second order (van Leer), Heun",
        ),
        (
            IceParams::high_resolution(periodic1()),
            "high resolution (MUSCL Eq. 28, p_eq + Δp/2, superbee, cfl 0.4)",
        ),
        (
            IceParams {
                advection: Advection::SecondOrder(Limiter::MonotonizedCentral),
                face_reconstruction: Some(Limiter::MonotonizedCentral),
                ..IceParams::high_resolution(periodic1())
            },
            "high resolution with MC, cfl 0.4",
        ),
        (
            IceParams::hancock(periodic1()),
            "Hancock (MUSCL-Hancock face states, superbee, cfl 0.8)",
        ),
        (
            IceParams::hancock_acoustic(periodic1()),
            "acoustic Hancock (switched Δp weight and jump, shock-sensed face viscosity, cfl 0.9)",
        ),
    ] {
        let mut points = Vec::new();
        for &n in ns {
            let h = 1.0 / n as f64;
            let layout =
                CellLayout::<1>::new(SVector::<f64, 1>::zeros(), SVector::<f64, 1>::new(h), [n])?;
            let st = IceState::new(layout, vec![gas(gamma)?], |x| {
                let w = eps * wave(x[0]);
                vec![MaterialInit::new(
                    1.0,
                    1.0 + w,
                    1.0 / gamma + w,
                    SVector::<f64, 1>::new(w),
                )]
            })?;
            let run = run_fluid(st, &params, 1.0, 10_000_000)?;
            let s = &run.state;
            let err = density_l1(s, |x| 1.0 + eps * wave(x[0] - 1.0)) / eps;
            let ups = (n as f64 * run.steps as f64) / run.wall_s.max(1e-12);
            points.push(Point::new(h, err, run.wall_s, ups));
        }
        series.push(Series::new(tag, "L1/eps", points));
    }
    Ok(StudyResult {
        study: "ice_acoustic".into(),
        h_axis: "cell size Δx = 1/N (nondimensional) [-]".into(),
        error_axis: "L1 density error / wave amplitude ε [-]".into(),
        series,
        notes: vec!["linear acoustic wave, eps = 1e-5, c = 1, periodic, one period, cfl = 0.5 (high resolution 0.4, Hancock 0.8, acoustic Hancock 0.9); error relative to the amplitude".into()],
    })
}

/// Ratio of specific heats of the [`ice_simple_wave`] gas.
const SW_GAMMA: f64 = 1.4;

/// The isentropic right-running simple wave of [`ice_simple_wave`]:
/// `u₀(ξ) = ε sin 2πξ` (`c₀ = 1`), with `J₋ = u − 2c/(γ−1) = −2/(γ−1)`
/// and `p/ρ^γ = 1/γ` (`ρ₀ = 1`, `p₀ = 1/γ`), so that `c = 1 + (γ−1)u/2`,
/// `ρ = c^{2/(γ−1)}`, `p = ρ^γ/γ`.
#[derive(Clone, Copy, Debug)]
pub struct SimpleWave {
    /// Velocity amplitude relative to `c₀ = 1`.
    pub eps: f64,
}

impl SimpleWave {
    /// `(ρ, u, p)` of the state with velocity `u` on the wave.
    pub fn state_of_u(&self, u: f64) -> (f64, f64, f64) {
        let g = SW_GAMMA;
        let c = 1.0 + 0.5 * (g - 1.0) * u;
        let rho = c.powf(2.0 / (g - 1.0));
        (rho, u, rho.powf(g) / g)
    }

    /// Shock-formation time `1/max_ξ(−d(u₀ + c)/dξ) = 1/(π (γ+1) ε)`.
    pub fn shock_time(&self) -> f64 {
        1.0 / (PI * (SW_GAMMA + 1.0) * self.eps)
    }

    /// Exact velocity at `(x, t)`, `t` below [`Self::shock_time`]: `u₀(ξ)`
    /// with `x = ξ + (1 + (γ+1)u₀(ξ)/2) t`, the foot `ξ` found by Newton's
    /// method safeguarded by bisection (the map is increasing).
    pub fn velocity(&self, x: f64, t: f64) -> f64 {
        let a = 0.5 * (SW_GAMMA + 1.0) * t * self.eps;
        let y = x - t;
        // ξ + a sin 2πξ = y; the root lies in [y − a, y + a].
        let f = |xi: f64| xi + a * (2.0 * PI * xi).sin() - y;
        let (mut lo, mut hi) = (y - a - 1e-14, y + a + 1e-14);
        let mut xi = y;
        for _ in 0..100 {
            let fx = f(xi);
            if fx.abs() <= 1e-15 {
                break;
            }
            if fx > 0.0 {
                hi = xi;
            } else {
                lo = xi;
            }
            let d = 1.0 + 2.0 * PI * a * (2.0 * PI * xi).cos();
            let next = xi - fx / d;
            xi = if next > lo && next < hi {
                next
            } else {
                0.5 * (lo + hi)
            };
            if hi - lo < 1e-15 {
                break;
            }
        }
        self.eps * (2.0 * PI * xi).sin()
    }

    /// The initial state of a cell from the averages of the conserved
    /// mass, momentum and total energy, `average(f)` being the cell average
    /// of `f(s)` over the wave coordinate `s`: `(ρ̄, ū = (ρu)‾/ρ̄,
    /// p̄ = (γ−1)(Ē − ρ̄ū²/2))`.
    pub fn averaged_initial_state(
        &self,
        average: impl Fn(&dyn Fn(f64) -> f64) -> f64,
    ) -> (f64, f64, f64) {
        let g = SW_GAMMA;
        let at = |s: f64| self.state_of_u(self.eps * (2.0 * PI * s).sin());
        let rho = average(&|s| at(s).0);
        let mom = average(&|s| {
            let (r, u, _) = at(s);
            r * u
        });
        let energy = average(&|s| {
            let (r, u, p) = at(s);
            p / (g - 1.0) + 0.5 * r * u * u
        });
        let u = mom / rho;
        (rho, u, (g - 1.0) * (energy - 0.5 * rho * u * u))
    }

    /// Exact `(ρ, u, p)` at `(x, t)`.
    pub fn state(&self, x: f64, t: f64) -> (f64, f64, f64) {
        self.state_of_u(self.velocity(x, t))
    }
}

/// 4-point Gauss–Legendre nodes and weights on `[−1, 1]` (exact for
/// degree 7: the cell averages below are `O(h⁸)` accurate).
const GAUSS4: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];

/// Cell average over `[xc − h/2, xc + h/2]` of `f`, 4-point Gauss.
fn cell_average(xc: f64, h: f64, f: impl Fn(f64) -> f64) -> f64 {
    GAUSS4
        .iter()
        .map(|&(s, w)| 0.5 * w * f(xc + 0.5 * h * s))
        .sum()
}

/// One run of the simple wave: `N` cells on the periodic `[0, 1]`,
/// initialised from the cell averages of the conserved mass, momentum and
/// total energy (`ρ̄`, `ū = (ρu)‾/ρ̄`, `p̄ = (γ−1)(Ē − ρ̄ū²/2)`), run to
/// `t_end` (below the shock time); returns `(L1/ε, steps, wall_s)` with
/// `L1 = mean over cells of |ρ_cell − ρ̄_exact|`, the exact cell averages
/// by the 4-point Gauss rule.
///
/// # Errors
/// Any solver error, or `t_end` not below the shock-formation time.
pub fn simple_wave_run(
    params: &IceParams<1>,
    eps: f64,
    t_end: f64,
    n: usize,
) -> Result<(f64, u64, f64)> {
    let wave = SimpleWave { eps };
    anyhow::ensure!(
        t_end < wave.shock_time(),
        "t_end = {t_end} is not below the shock time {}",
        wave.shock_time()
    );
    let g = SW_GAMMA;
    let h = 1.0 / n as f64;
    let layout = CellLayout::<1>::new(SVector::<f64, 1>::zeros(), SVector::<f64, 1>::new(h), [n])?;
    let st = IceState::new(layout, vec![gas(g)?], |x| {
        let (rho, u, p) = wave.averaged_initial_state(|f| cell_average(x[0], h, f));
        vec![MaterialInit::new(1.0, rho, p, SVector::<f64, 1>::new(u))]
    })?;
    let run = run_fluid(st, params, t_end, 10_000_000)?;
    let s = &run.state;
    let err = density_l1(s, |x| cell_average(x[0], h, |y| wave.state(y, s.time).0)) / eps;
    Ok((err, run.steps, run.wall_s))
}

/// The simple wave of [`simple_wave_run`] along the diagonal of the
/// periodic unit square, `N × N` cells: the state at `(x, y, t)` is the 1D
/// wave's at `(x + y, √2 t)` with the velocity along `(1, 1)/√2` (the
/// wave in `ξ = (x + y)/√2` has period `1/√2`; in `s = √2 ξ` and
/// `t' = √2 t` it is the 1D wave). Initial cell averages of mass, momentum
/// and total energy by the 4 × 4 Gauss rule; returns `(L1/ε, steps,
/// wall_s)` of the density against exact 4 × 4 Gauss cell averages.
/// `t_end` must be below the shock time over `√2`.
///
/// # Errors
/// Any solver error, or `t_end` too late.
pub fn simple_wave_run_diagonal(
    params: &IceParams<2>,
    eps: f64,
    t_end: f64,
    n: usize,
) -> Result<(f64, u64, f64)> {
    let wave = SimpleWave { eps };
    let r2 = std::f64::consts::SQRT_2;
    anyhow::ensure!(
        t_end * r2 < wave.shock_time(),
        "t_end = {t_end} is not below the shock time {}",
        wave.shock_time() / r2
    );
    let g = SW_GAMMA;
    let h = 1.0 / n as f64;
    let avg2 = |x: &SVector<f64, 2>, f: &dyn Fn(f64) -> f64| {
        cell_average(x[0], h, |xa| cell_average(x[1], h, |yb| f(xa + yb)))
    };
    let layout = CellLayout::<2>::new(SVector::zeros(), SVector::from_element(h), [n, n])?;
    let st = IceState::new(layout, vec![gas(g)?], |x| {
        let (rho, u, p) = wave.averaged_initial_state(|f| avg2(x, f));
        let v = u / r2;
        vec![MaterialInit::new(1.0, rho, p, SVector::<f64, 2>::new(v, v))]
    })?;
    let run = run_fluid(st, params, t_end, 10_000_000)?;
    let s = &run.state;
    let t = s.time * r2;
    let err = density_l1(s, |x| avg2(x, &|s| wave.state(s, t).0)) / eps;
    Ok((err, run.steps, run.wall_s))
}

/// A finite-amplitude right-running simple wave of an ideal gas
/// (`γ = 1.4`), periodic on `[0, 1]`: `u₀ = ε sin 2πx` (`c₀ = 1`), `ρ` and
/// `p` from the Riemann invariant `J₋ = −2c₀/(γ−1)` and isentropy
/// (`ρ₀ = 1`, `p₀ = 1/γ`) — see [`SimpleWave`]; exact solution by
/// characteristics before the shock forms. `ε = 1e-2` to `t = 1` and
/// `ε = 0.1` to `t = 0.5` (shock times 13.3 and 1.33), Hancock, acoustic
/// Hancock and high resolution: L1 of density relative to `ε` against
/// exact cell averages (see [`simple_wave_run`]). Unlike
/// [`ice_acoustic`] (`ε = 1e-5`), the amplitudes reach the thresholds of
/// the amplitude switches of [`IceParams::hancock_acoustic`].
///
/// # Errors
/// Any solver error.
pub fn ice_simple_wave(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick {
        &[32, 64, 128]
    } else {
        &[32, 64, 128, 256, 512, 1024]
    };
    let mut series = Vec::new();
    let mut notes = vec![
        "the last two series per amplitude are diagnostics: acoustic Hancock without its Δp weight switch (weight 1/2 everywhere) and without its jump switch (Hancock's face_dt_factor 0.625 instead of the switched acoustic jump)".to_string(),
        "isentropic simple wave, gamma = 1.4, u0 = eps sin 2 pi x, c0 = 1, rho0 = 1, p0 = 1/gamma, J- = u - 2c/(gamma-1) constant, periodic; exact by characteristics (safeguarded Newton for the foot); initial state = cell averages of mass, momentum, total energy (4-point Gauss); error = mean |rho - exact cell average (4-point Gauss)| / eps".to_string(),
    ];
    for (eps, t_end) in [(1e-2, 1.0), (0.1, 0.5)] {
        let ts = SimpleWave { eps }.shock_time();
        notes.push(format!("eps = {eps}: t = {t_end}, shock time {ts:.4}"));
        for (params, tag) in [
            (
                IceParams::hancock(periodic1()),
                "Hancock (superbee, cfl 0.8)",
            ),
            (
                IceParams::hancock_acoustic(periodic1()),
                "acoustic Hancock (cfl 0.9)",
            ),
            (
                IceParams::high_resolution(periodic1()),
                "high resolution (superbee, cfl 0.4)",
            ),
            (
                IceParams {
                    lagrangian_remap: false,
                    ..IceParams::hancock(periodic1())
                },
                "Hancock without the Lagrangian remap",
            ),
            // Diagnostics: acoustic Hancock with one amplitude switch
            // removed each.
            (
                IceParams {
                    pressure_weight: 0.5,
                    pressure_weight_compression: None,
                    ..IceParams::hancock_acoustic(periodic1())
                },
                "acoustic Hancock, Δp weight 1/2 unswitched",
            ),
            (
                IceParams {
                    acoustic_jump: None,
                    ..IceParams::hancock_acoustic(periodic1())
                },
                "acoustic Hancock, Eq. 28 jump unswitched (α 0.625)",
            ),
        ] {
            let mut points: Vec<Point> = Vec::new();
            for &n in ns {
                let (err, steps, wall) = simple_wave_run(&params, eps, t_end, n)
                    .with_context(|| format!("simple wave eps = {eps}, N = {n}, {tag}"))?;
                let ups = (n as f64 * steps as f64) / wall.max(1e-12);
                points.push(
                    Point::new(1.0 / n as f64, err, wall, ups).with_extra("steps", steps as f64),
                );
            }
            push_simple_wave_series(format!("{tag}, eps {eps}"), points, &mut notes, &mut series);
        }
    }
    // 2D: the wave along the diagonal of the unit square (corner
    // transport; the remap's strain is the full divergence).
    let eps = 0.1;
    let t_end = 0.35;
    notes.push(format!(
        "2D: the eps = {eps} wave along (1, 1)/sqrt 2 on the periodic unit square (state at (x, y, t) = 1D state at (x + y, sqrt 2 t)), t = {t_end}, N x N cells, 4 x 4 Gauss cell averages"
    ));
    let ns2: &[usize] = if quick {
        &[32, 64]
    } else {
        &[32, 64, 128, 256]
    };
    let bcs2 = || {
        let p = [IceBoundary::Periodic, IceBoundary::Periodic];
        [p.clone(), p]
    };
    // Superbee (the variant's limiter) and MC: superbee's compression of
    // the steepening wave costs order at 256², MC stays at 2.
    for (remap, lim, tag) in [
        (true, Limiter::Superbee, "Hancock, 2D diagonal"),
        (
            true,
            Limiter::MonotonizedCentral,
            "Hancock with MC limiter, 2D diagonal",
        ),
        (
            false,
            Limiter::Superbee,
            "Hancock without the Lagrangian remap, 2D diagonal",
        ),
    ] {
        let params = IceParams {
            lagrangian_remap: remap,
            advection: Advection::SecondOrder(lim),
            face_reconstruction: Some(lim),
            ..IceParams::hancock(bcs2())
        };
        let mut points: Vec<Point> = Vec::new();
        for &n in ns2 {
            let (err, steps, wall) = simple_wave_run_diagonal(&params, eps, t_end, n)
                .with_context(|| format!("diagonal simple wave N = {n}, {tag}"))?;
            let ups = (n as f64 * n as f64 * steps as f64) / wall.max(1e-12);
            points
                .push(Point::new(1.0 / n as f64, err, wall, ups).with_extra("steps", steps as f64));
        }
        push_simple_wave_series(format!("{tag}, eps {eps}"), points, &mut notes, &mut series);
    }
    Ok(StudyResult {
        study: "ice_simple_wave".into(),
        h_axis: "cell size Δx = 1/N (nondimensional) [-]".into(),
        error_axis: "L1 density error vs exact cell averages / ε [-]".into(),
        series,
        notes,
    })
}

/// Adds one [`ice_simple_wave`] series and its note (the errors and the
/// observed order of each refinement).
fn push_simple_wave_series(
    label: String,
    points: Vec<Point>,
    notes: &mut Vec<String>,
    series: &mut Vec<Series>,
) {
    let orders: Vec<String> = points
        .windows(2)
        .map(|w| {
            format!(
                "{:.3}",
                (w[0].error / w[1].error).ln() / (w[0].h / w[1].h).ln()
            )
        })
        .collect();
    let errors: Vec<String> = points.iter().map(|p| format!("{:.4e}", p.error)).collect();
    notes.push(format!(
        "{label}: L1/eps {}; orders per refinement {}",
        errors.join(", "),
        orders.join(", ")
    ));
    series.push(Series::new(label, "L1/eps", points));
}

/// L1 density error averaged over the interior cells: mean of
/// `|ρ_mix − exact(x_c)|`, `x_c` the cell centre.
fn density_l1<const D: usize>(s: &IceState<D>, exact: impl Fn(&SVector<f64, D>) -> f64) -> f64 {
    let int = &s.layout.interior;
    int.iter()
        .map(|&c| (s.mixture_density(c) - exact(&s.layout.centre(c))).abs())
        .sum::<f64>()
        / int.len() as f64
}

/// Semi-implicit ICE parameters with `cfl` an acoustic Courant number
/// (`sound_speed_factor = 1`).
fn semi_params<const D: usize>(
    bcs: [[IceBoundary<D>; 2]; D],
    solver: LinearSolver,
    acoustic_cfl: f64,
) -> IceParams<D> {
    let mut p = IceParams::new(bcs);
    p.cfl = acoustic_cfl;
    p.implicit = Some(SemiImplicit {
        sound_speed_factor: 1.0,
        ..SemiImplicit::with_solver(solver)
    });
    p
}

/// Sod's shock tube (as [`ice_sod`], second order van Leer, literal
/// Eq. 28) with the explicit and the semi-implicit pressure at acoustic
/// Courant numbers 0.5 and 1: both errors against the exact Riemann
/// solution, and the L1 distance between the two solutions.
///
/// # Errors
/// Any solver or exact-solution error.
pub fn ice_sod_semi_implicit(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick {
        &[100, 200, 400]
    } else {
        &[100, 200, 400, 800, 1600]
    };
    let (l, r) = ((1.0, 0.0, 1.0), (0.125, 0.0, 0.1));
    let exact = ExactRiemann::solve(
        PrimitiveState::new(l.0, l.1, l.2),
        PrimitiveState::new(r.0, r.1, r.2),
        1.4,
    )?;
    let bcs = [[IceBoundary::Outflow, IceBoundary::Outflow]];
    let mut variants: Vec<(IceParams<1>, String)> = Vec::new();
    for cfl in [0.5, 1.0] {
        let mut p = IceParams::new(bcs.clone());
        p.cfl = cfl;
        variants.push((p, format!("explicit, cfl {cfl}")));
        variants.push((
            semi_params(bcs.clone(), LinearSolver::Direct, cfl),
            format!("semi-implicit (direct), acoustic cfl {cfl}"),
        ));
    }
    variants.push((
        semi_params(bcs.clone(), LinearSolver::Direct, 2.0),
        "semi-implicit (direct), acoustic cfl 2".into(),
    ));
    let mut series = Vec::new();
    let mut notes = vec![
        "explicit vs semi-implicit ICE: same discretisation (Guilkey Eqs. 28-41, second order van Leer, conservative energy); the semi-implicit mode solves Eq. 29 implicitly (outer iteration, Cholesky); cfl is on |u| + c".to_string(),
    ];
    let mut finals: Vec<Vec<Vec<f64>>> = Vec::new();
    for (params, series_label) in &variants {
        let mut points = Vec::new();
        let mut sols = Vec::new();
        for &n in ns {
            let st = shock_tube(gas(1.4)?, n, l, r, 0.5)?;
            let run = run_fluid(st, params, 0.2, 10_000_000)
                .with_context(|| format!("Sod N = {n}, {series_label}"))?;
            let s = &run.state;
            let h = 1.0 / n as f64;
            let mut err = 0.0;
            let mut rho = Vec::with_capacity(n);
            for &c in &s.layout.interior {
                let x = s.layout.centre(c)[0];
                let avg = exact.cell_average(x - 0.5 * h, x + 0.5 * h, 0.5, s.time, 4)?;
                err += (s.mixture_density(c) - avg.rho).abs();
                rho.push(s.mixture_density(c));
            }
            err /= n as f64;
            sols.push(rho);
            let ups = (n as f64 * run.steps as f64) / run.wall_s.max(1e-12);
            let per = |x: u64| x as f64 / run.steps.max(1) as f64;
            points.push(
                Point::new(h, err, run.wall_s, ups)
                    .with_extra("steps", run.steps as f64)
                    .with_extra("outer_per_step", per(run.outer_iterations))
                    .with_extra("linear_per_step", per(run.linear_iterations)),
            );
        }
        finals.push(sols);
        series.push(Series::new(series_label.clone(), "L1", points));
    }
    // Explicit vs semi-implicit at the same cfl: distance of the solutions.
    for (k, cfl) in [0.5, 1.0].iter().enumerate() {
        let (ex, si) = (&finals[2 * k], &finals[2 * k + 1]);
        let (se, ss) = (&series[2 * k], &series[2 * k + 1]);
        for (i, &n) in ns.iter().enumerate() {
            let d: f64 = ex[i]
                .iter()
                .zip(&si[i])
                .map(|(a, b)| (a - b).abs())
                .sum::<f64>()
                / n as f64;
            notes.push(format!(
                "cfl {cfl}, N = {n}: L1 explicit {:.3e}, semi-implicit {:.3e}, |explicit − semi-implicit| {:.3e}",
                se.points[i].error, ss.points[i].error, d
            ));
        }
    }
    Ok(StudyResult {
        study: "ice_sod_semi_implicit".into(),
        h_axis: "cell size Δx = 1/N (nondimensional) [-]".into(),
        error_axis: "L1 density error vs exact cell averages (nondimensional) [-]".into(),
        series,
        notes,
    })
}

/// RMS velocity error `sqrt(mean |u − u_exact|²)` and the RMS error of the
/// pressure fluctuation (means removed) of the periodic vortex.
fn vortex_errors(s: &IceState<2>, amplitude: f64) -> (f64, f64) {
    let n = s.layout.num_interior() as f64;
    let (mut eu, mut pm, mut pem) = (0.0, 0.0, 0.0);
    for &c in &s.layout.interior {
        let x = s.layout.centre(c);
        let (u, v, p) = periodic_vortex_exact(&x, s.time, amplitude, 0.0);
        let w = s.cells[0].velocity[c];
        eu += (w[0] - u).powi(2) + (w[1] - v).powi(2);
        pm += s.p_eq[c];
        pem += p;
    }
    let (pm, pem) = (pm / n, pem / n);
    let mut ep = 0.0;
    for &c in &s.layout.interior {
        let x = s.layout.centre(c);
        let (_, _, p) = periodic_vortex_exact(&x, s.time, amplitude, 0.0);
        ep += ((s.p_eq[c] - pm) - (p - pem)).powi(2);
    }
    ((eu / n).sqrt(), (ep / n).sqrt())
}

/// Time needed to reach `target` error along a work-precision curve
/// (log-log interpolation between the points, sorted by wall time); `None`
/// if the curve never gets there.
fn time_to_error(points: &[Point], target: f64) -> Option<f64> {
    let mut pts: Vec<(f64, f64)> = points.iter().map(|p| (p.wall_s, p.error)).collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some(&(t, e)) = pts.first() {
        if e <= target {
            return Some(t);
        }
    }
    for w in pts.windows(2) {
        let ((t0, e0), (t1, e1)) = (w[0], w[1]);
        if e1 <= target && e0 > target {
            let s = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
            return Some((t0.ln() + s * (t1.ln() - t0.ln())).exp());
        }
    }
    None
}

/// Wall time at which a work-precision curve reaches `target` error, by
/// log-log interpolation between the two points (sorted by wall time) that
/// bracket it; `None` when `target` is outside the curve's error range (no
/// extrapolation).
fn time_at_error_bracketed(points: &[Point], target: f64) -> Option<f64> {
    let mut pts: Vec<(f64, f64)> = points.iter().map(|p| (p.wall_s, p.error)).collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    for w in pts.windows(2) {
        let ((t0, e0), (t1, e1)) = (w[0], w[1]);
        let (lo, hi) = (e0.min(e1), e0.max(e1));
        if target >= lo && target <= hi && t0 > 0.0 && t1 > 0.0 {
            if e0 == e1 {
                return Some(t0);
            }
            let s = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
            return Some((t0.ln() + s * (t1.ln() - t0.ln())).exp());
        }
    }
    None
}

/// The low-Mach periodic vortex (`ice_low_mach`): the inviscid (`ν = 0`)
/// 2D periodic vortex on `[0, 2π]²`, `u = 1 − A cos(x−t) sin(y−t)`,
/// `v = 1 + A sin(x−t) cos(y−t)`, `p = p_ref − (A²/4)[cos 2(x−t) + cos 2(y−t)]`,
/// `A = 0.5`, run as an ideal gas (`γ = 1.4`, `ρ = 1` uniform initially,
/// pressure from the formula) with `c = 100` (Mach ≤ 0.021) to `t = 1`, on
/// 16² … 128², explicit (cfl 1) and semi-implicit at acoustic Courant
/// numbers 1, 10 and 50 (Guilkey Eq. 28 as written), and 10, 20 and 50
/// with the convective predictor (`SemiImplicit::convective_predictor =
/// 1`), the latter with both the direct (sparse Cholesky) and the
/// multigrid-preconditioned CG pressure solve (periodic multigrid); RMS
/// velocity error against the exact solution against wall time,
/// the speed-up at equal error (both ways, log-log interpolation, no
/// extrapolation), and the Mach-number floor at fixed resolution.
///
/// # Errors
/// Any solver error.
pub fn ice_low_mach(quick: bool) -> Result<StudyResult> {
    let amplitude = 0.5;
    let gamma = 1.4;
    let ns: &[usize] = if quick {
        &[16, 32, 64]
    } else {
        &[16, 32, 64, 128]
    };
    let t_end = if quick { 0.5 } else { 1.0 };
    let c0 = 100.0;
    let periodic = || {
        [
            [IceBoundary::Periodic, IceBoundary::Periodic],
            [IceBoundary::Periodic, IceBoundary::Periodic],
        ]
    };
    let run_case = |params: &IceParams<2>, n: usize, c: f64| -> Result<(f64, f64, FluidRunStats)> {
        let st = periodic_vortex(gas(gamma)?, n, amplitude, c * c / gamma)?;
        let cpu0 = process_cpu_s();
        let run = run_fluid(st, params, t_end, 10_000_000)
            .with_context(|| format!("low-Mach vortex N = {n}, c = {c}"))?;
        let cpu_s = process_cpu_s() - cpu0;
        let (eu, ep) = vortex_errors(&run.state, amplitude);
        Ok((
            eu,
            ep,
            FluidRunStats {
                steps: run.steps,
                wall_s: run.wall_s,
                cpu_s,
                outer: run.outer_iterations,
                linear: run.linear_iterations,
                retries: run.retries,
            },
        ))
    };
    let mut modes: Vec<(IceParams<2>, String)> = Vec::new();
    let mut ex = IceParams::new(periodic());
    ex.cfl = 1.0;
    modes.push((ex, "explicit, acoustic cfl 1".into()));
    for cfl in [1.0, 10.0, 50.0] {
        modes.push((
            semi_params(periodic(), LinearSolver::Direct, cfl),
            format!("semi-implicit (direct), acoustic cfl {cfl}"),
        ));
    }
    modes.push((
        semi_params(periodic(), LinearSolver::PcgJacobi, 10.0),
        "semi-implicit (pcg_jacobi), acoustic cfl 10".into(),
    ));
    // The convective predictor (`SemiImplicit::convective_predictor = 1`):
    // Eq. 28's time-advanced velocity estimate includes the previous step's
    // advective acceleration, so the pressure no longer lags one step.
    for cfl in [10.0, 20.0, 50.0] {
        let mut p = semi_params(periodic(), LinearSolver::Direct, cfl);
        if let Some(sp) = p.implicit.as_mut() {
            sp.convective_predictor = 1.0;
        }
        modes.push((
            p,
            format!("semi-implicit (direct, predictor 1), acoustic cfl {cfl}"),
        ));
    }
    // The same with PCG preconditioned by the periodic geometric multigrid
    // (`pcg_multigrid`): same solutions (to the 1e-10 linear tolerance),
    // cheaper solves than the serial sparse Cholesky.
    for cfl in [10.0, 20.0, 50.0] {
        let mut p = semi_params(periodic(), LinearSolver::PcgMultigrid, cfl);
        if let Some(sp) = p.implicit.as_mut() {
            sp.convective_predictor = 1.0;
        }
        modes.push((
            p,
            format!("semi-implicit (pcg_multigrid, predictor 1), acoustic cfl {cfl}"),
        ));
    }
    let mut series = Vec::new();
    let mut notes = vec![format!(
        "inviscid (nu = 0) periodic vortex, A = {amplitude}, gamma = {gamma}, rho = 1, c = {c0} (max Mach {:.3}), t = {t_end}; error = RMS velocity error vs the exact incompressible solution at the cell centres; cfl on |u| + c (second order corner-transport van Leer; Guilkey Eq. 28 as written, except the 'predictor 1' series, whose Eq. 28 sees u + dt a with a the previous step's advective acceleration); wall times from a shared 2-core machine, compare within one run",
        (2.0f64.sqrt() * (1.0 + amplitude)) / c0
    )];
    for (params, label) in &modes {
        let mut points = Vec::new();
        let mut pressure_points = Vec::new();
        for &n in ns {
            let (eu, ep, st) = run_case(params, n, c0)?;
            let h = 2.0 * PI / n as f64;
            let ups = (n * n) as f64 * st.steps as f64 / st.wall_s.max(1e-12);
            let per = |x: u64| x as f64 / st.steps.max(1) as f64;
            points.push(
                Point::new(h, eu, st.wall_s, ups)
                    .with_extra("steps", st.steps as f64)
                    .with_extra("retries", st.retries as f64)
                    .with_extra("outer_per_step", per(st.outer))
                    .with_extra("linear_per_step", per(st.linear))
                    .with_extra("cpu_s", st.cpu_s),
            );
            pressure_points.push(Point::new(h, ep, st.wall_s, ups));
            notes.push(format!(
                "{label}, N = {n}: velocity RMS {eu:.3e}, pressure RMS {ep:.3e}, wall {:.3} s, {} steps, {:.2} outer / {:.1} linear iterations per step",
                st.wall_s,
                st.steps,
                per(st.outer),
                per(st.linear)
            ));
        }
        series.push(Series::new(label.clone(), "RMS velocity", points));
        series.push(Series::new(
            format!("{label} (pressure)"),
            "RMS p'",
            pressure_points,
        ));
    }
    // Work-precision, (a): time for each semi-implicit series to reach the
    // explicit error on the finest grid (log-log interpolation of the
    // semi-implicit curve; its first point if that is already below).
    let explicit = &series[0];
    let mut best: Option<(f64, String)> = None;
    let mut keep_best = |x: f64, what: String| {
        if best.as_ref().is_none_or(|b| x > b.0) {
            best = Some((x, what));
        }
    };
    if let Some(last) = explicit.points.last() {
        for s in series.iter().skip(2).step_by(2) {
            match time_to_error(&s.points, last.error) {
                Some(t) => {
                    let x = last.wall_s / t;
                    notes.push(format!(
                        "{}: reaches the explicit N = {} error {:.3e} in {:.3} s vs {:.3} s explicit: {:.2}x faster",
                        s.label,
                        ns[ns.len() - 1],
                        last.error,
                        t,
                        last.wall_s,
                        x
                    ));
                    keep_best(
                        x,
                        format!(
                            "{}, at the explicit N = {} error",
                            s.label,
                            ns[ns.len() - 1]
                        ),
                    );
                }
                None => notes.push(format!(
                    "{}: does not reach the explicit N = {} error {:.3e} on these grids",
                    s.label,
                    ns[ns.len() - 1],
                    last.error
                )),
            }
        }
    }
    // Work-precision, (b): the explicit wall time at each semi-implicit
    // point's error (log-log interpolation of the explicit curve, no
    // extrapolation) over the semi-implicit wall time.
    let explicit_pts = series[0].points.clone();
    let cpu_of = |p: &Point| p.extra.get("cpu_s").and_then(|v| v.as_f64());
    let explicit_cpu: Vec<Point> = explicit_pts
        .iter()
        .filter_map(|p| cpu_of(p).map(|c| Point::new(p.h, p.error, c, 0.0)))
        .collect();
    let mut finest_b = Vec::new();
    let mut finest_cpu: Option<(f64, String)> = None;
    for s in series.iter_mut().skip(2).step_by(2) {
        for (i, p) in s.points.iter_mut().enumerate() {
            let cpu_speedup = cpu_of(p)
                .and_then(|c| time_at_error_bracketed(&explicit_cpu, p.error).map(|t| t / c))
                .filter(|x| x.is_finite());
            p.extra.insert(
                "speedup_at_equal_error_cpu".into(),
                serde_json::Value::from(cpu_speedup),
            );
            if let Some(x) = cpu_speedup {
                notes.push(format!(
                    "CPU-time speed-up at equal error: {}, N = {}: {x:.2}x",
                    s.label, ns[i]
                ));
                if i == ns.len() - 1 && finest_cpu.as_ref().is_none_or(|b| x > b.0) {
                    finest_cpu = Some((x, format!("{}, N = {}", s.label, ns[i])));
                }
            }
            let t_ex = time_at_error_bracketed(&explicit_pts, p.error);
            let speedup = t_ex.map_or(f64::NAN, |t| t / p.wall_s.max(1e-12));
            p.extra.insert(
                "explicit_wall_at_equal_error".into(),
                serde_json::Value::from(t_ex.filter(|t| t.is_finite())),
            );
            p.extra.insert(
                "speedup_at_equal_error".into(),
                serde_json::Value::from(Some(speedup).filter(|x| x.is_finite())),
            );
            match t_ex {
                Some(t) => {
                    notes.push(format!(
                        "speed-up at equal error: {}, N = {}: error {:.3e} in {:.3} s; explicit reaches it in {:.3} s (interpolated): {:.2}x",
                        s.label, ns[i], p.error, p.wall_s, t, speedup
                    ));
                    if i == ns.len() - 1 {
                        finest_b.push((speedup, format!("{}, N = {}", s.label, ns[i])));
                    }
                }
                None => notes.push(format!(
                    "speed-up at equal error: {}, N = {}: error {:.3e} outside the explicit curve's range (no extrapolation)",
                    s.label, ns[i], p.error
                )),
            }
        }
    }
    for (x, what) in finest_b {
        keep_best(x, what);
    }
    if let Some((x, what)) = &finest_cpu {
        notes.push(format!(
            "best CPU-time speed-up at equal error on the finest grid: {x:.2}x ({what}); target >= 5x: {}",
            if *x >= 5.0 { "met" } else { "not met" }
        ));
    }
    match best {
        Some((x, l)) => notes.push(format!(
            "best speed-up at equal error on the finest grid: {x:.2}x ({l}); target >= 5x: {}",
            if x >= 5.0 { "met" } else { "not met" }
        )),
        None => notes.push(format!(
            "no equal-error comparison on the finest grid (N = {})",
            ns[ns.len() - 1]
        )),
    }
    // Compressibility floor: error against Mach number at a fixed grid.
    let nf = if quick { 32 } else { 64 };
    let mut floor = Vec::new();
    for c in [5.0, 10.0, 20.0, 40.0, 100.0, 300.0] {
        // The same (advective, cfl 0.5) time step for every Mach number.
        let mut params = semi_params(periodic(), LinearSolver::Direct, 0.5);
        if let Some(sp) = params.implicit.as_mut() {
            sp.sound_speed_factor = 0.0;
        }
        let (eu, _, st) = run_case(&params, nf, c)?;
        let mach = 2.0f64.sqrt() * (1.0 + amplitude) / c;
        floor.push(Point::new(mach, eu, st.wall_s, 0.0));
        notes.push(format!(
            "Mach floor, N = {nf}, semi-implicit, advective cfl 0.5 (same dt for all c): c = {c} (Mach {mach:.3}): velocity RMS {eu:.3e}, {} steps",
            st.steps
        ));
    }
    // Order of the Mach-dependent part: error minus the low-Mach limit.
    let lim = floor.last().map_or(0.0, |p| p.error);
    let excess: Vec<Point> = floor
        .iter()
        .take(floor.len() - 1)
        .map(|p| Point::new(p.h, (p.error - lim).abs().max(1e-300), p.wall_s, 0.0))
        .collect();
    let mut fs = Series::new(
        format!("Mach floor at N = {nf}: |e(M) - e(M_min)| vs M (h column = Mach)"),
        "RMS velocity",
        excess,
    );
    fs.observed_order = crate::harness::fit_order(&fs.points);
    notes.push(format!(
        "Mach-dependent part of the error scales as M^{:.2}",
        fs.observed_order
    ));
    series.push(fs);

    let dir = crate::plot_dir(quick);
    std::fs::create_dir_all(&dir)?;
    let plot: Vec<PlotSeries> = series
        .iter()
        .filter(|s| s.norm == "RMS velocity" && !s.label.starts_with("Mach"))
        .map(|s| PlotSeries {
            label: s.label.clone(),
            points: s.points.iter().map(|p| (p.wall_s, p.error)).collect(),
            style: Style::LineMarkers,
        })
        .collect();
    plot_xy(
        &dir.join("ice_low_mach_work_precision.png"),
        "low-Mach periodic vortex: RMS velocity error vs wall time",
        "wall time [s]",
        "RMS velocity error [-]",
        true,
        true,
        &plot,
    )?;
    Ok(StudyResult {
        study: "ice_low_mach".into(),
        h_axis: "cell size Δx = 2π/N (nondimensional) [-]; Mach-floor series: Mach number M [-]"
            .into(),
        error_axis: "RMS velocity or p' error (legend), nondimensional [-]".into(),
        series,
        notes,
    })
}

/// CPU time (user + system, all threads) consumed by this process so far,
/// from `/proc/self/stat` (clock ticks of 10 ms); NaN where unavailable.
/// Less sensitive than wall time to other processes on a shared machine.
fn process_cpu_s() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // Fields after the command name `(...)`: state is field 3, utime 14,
    // stime 15.
    let Some(rest) = stat.rsplit_once(')').map(|(_, r)| r) else {
        return f64::NAN;
    };
    let f: Vec<&str> = rest.split_whitespace().collect();
    match (
        f.get(11).and_then(|x| x.parse::<f64>().ok()),
        f.get(12).and_then(|x| x.parse::<f64>().ok()),
    ) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => f64::NAN,
    }
}

/// Counters of one run of [`ice_low_mach`].
struct FluidRunStats {
    /// CPU time (user + system, all threads) of the run; NaN off Linux.
    cpu_s: f64,
    steps: u64,
    wall_s: f64,
    outer: u64,
    linear: u64,
    retries: u64,
}
