//! Studies of York, Sulsky & Schreyer's all-MPM fluid: Sod's shock tube with
//! gas material points (York Sec. 4.1) against the exact Riemann solution,
//! beside the project's ICE at the same Δx; the piston–container (York
//! Sec. 4.2) against Eq. 27.

use anyhow::{Context, Result};

use crate::harness::{Point, Series, StudyResult};
use mpmice::diagnostics::york::{
    run_piston_container, run_york_sod, sod_exact, PistonContainer, YorkSod, SOD_LEFT, SOD_RIGHT,
};
use mpmice::ice::{run_fluid, shock_tube, Advection, IceBoundary, IceMaterial, IceParams};
use mpmice::material::eos::IdealGas;
use mpmice::material::PointDensity;
use mpmice::shape::ShapeKind;

/// York Sec. 4.1: Sod (ρ, u, p) = (1, 0, 1 | 0.125, 0, 0.1), γ = 1.4, to
/// t = 0.143, on a strip one cell high at Δx = 0.01 … 0.0003125 (six
/// halvings; quick: the two coarsest) with 3 points per cell per direction,
/// MUSL and York's q (g = √2 Δx, κ̃ = 0.75, c₁ = c₂ = 1): L1(ρ) against the
/// exact Riemann solution for GIMP, York's bilinear hats and the quadratic
/// and cubic B-splines (York Eq. 16's continuity density), for GIMP and the
/// cubic B-splines with the points' grid density (`point_density =
/// "grid"`), and the
/// project's explicit ICE (first-order donor cell; high resolution) at the
/// same Δx and time.
///
/// # Errors
/// Any solver error.
pub fn york_sod(quick: bool) -> Result<StudyResult> {
    let cells: &[usize] = if quick {
        &[100, 200]
    } else {
        &[100, 200, 400, 800, 1600, 3200]
    };
    let end = YorkSod::default().end;
    let mut series = Vec::new();
    let (continuity, grid) = (PointDensity::Continuity, PointDensity::Grid);
    for (shape, point_density, label) in [
        (
            ShapeKind::Gimp,
            continuity,
            "gas points, GIMP, MUSL, York q (3 points per cell per direction)",
        ),
        (
            ShapeKind::Linear,
            continuity,
            "gas points, bilinear hats (York's choice), MUSL, York q",
        ),
        (
            ShapeKind::QuadraticBspline,
            continuity,
            "gas points, quadratic B-splines, MUSL, York q",
        ),
        (
            ShapeKind::CubicBspline,
            continuity,
            "gas points, cubic B-splines, MUSL, York q",
        ),
        (
            ShapeKind::Gimp,
            grid,
            "gas points, GIMP, grid density, MUSL, York q",
        ),
        (
            ShapeKind::CubicBspline,
            grid,
            "gas points, cubic B-splines, grid density, MUSL, York q",
        ),
    ] {
        let mut points = Vec::new();
        for &n in cells {
            let run = run_york_sod(&YorkSod {
                cells: n,
                shape,
                point_density,
                ..YorkSod::default()
            })
            .with_context(|| format!("York Sod, {n} cells"))?;
            let ups = run.particles as f64 * run.steps as f64 / run.wall_s.max(1e-12);
            points.push(
                Point::new(1.0 / n as f64, run.l1_density, run.wall_s, ups)
                    .with_extra("steps", run.steps as f64)
                    .with_extra("particles", run.particles as f64),
            );
        }
        series.push(Series::new(label, "L1", points));
    }
    let exact = sod_exact()?;
    let bcs = [[IceBoundary::Outflow, IceBoundary::Outflow]];
    let first = IceParams {
        advection: Advection::FirstOrder,
        ..IceParams::new(bcs.clone())
    };
    for (params, label) in [
        (first, "ICE explicit, literal, first order (donor cell)"),
        (
            IceParams::high_resolution(bcs.clone()),
            "ICE explicit, high resolution (as cases/sod.toml)",
        ),
    ] {
        let mut points = Vec::new();
        for &n in cells {
            let gas = IceMaterial::new("gas", IdealGas::new(1.4, 2.5)?);
            let st = shock_tube(gas, n, SOD_LEFT, SOD_RIGHT, 0.5)?;
            let run = run_fluid(st, &params, end, 10_000_000)
                .with_context(|| format!("ICE Sod N = {n}"))?;
            let err = exact.l1_density_error(&run.state, 0.5)?;
            let ups = n as f64 * run.steps as f64 / run.wall_s.max(1e-12);
            points.push(
                Point::new(1.0 / n as f64, err, run.wall_s, ups)
                    .with_extra("steps", run.steps as f64),
            );
        }
        series.push(Series::new(label, "L1", points));
    }
    let mut notes = vec![
        "York Sec. 4.1 with gas points (York Sec. 3.3): L1(rho) = sum_p |m_p/V_p - rho_exact(x_p)| V_p / H (particle quadrature); ICE: mean over cells of |rho - exact cell average|; both at t = 0.143".to_string(),
        "target: gas points within 1.5x the ICE's L1 at equal dx and order >= 0.8".to_string(),
    ];
    for (gas, name) in [
        (&series[0], "GIMP"),
        (&series[3], "cubic B-splines"),
        (&series[4], "GIMP, grid density"),
        (&series[5], "cubic B-splines, grid density"),
    ] {
        for ice in series.iter().filter(|s| s.label.starts_with("ICE")) {
            let ratios: Vec<String> = gas
                .points
                .iter()
                .zip(&ice.points)
                .map(|(g, i)| format!("dx {:.6}: {:.2}", g.h, g.error / i.error))
                .collect();
            notes.push(format!(
                "L1 ratio gas points ({name}) / {}: {}",
                ice.label,
                ratios.join(", ")
            ));
        }
    }
    for s in &series {
        notes.push(format!(
            "{}: observed order {:.2}",
            s.label, s.observed_order
        ));
    }
    for n in &notes {
        eprintln!("{n}");
    }
    Ok(StudyResult {
        study: "york_sod".into(),
        h_axis: "cell size Δx = 1/N (nondimensional) [-]".into(),
        error_axis: "L1 density error vs exact (nondimensional) [-]".into(),
        series,
        notes,
    })
}

/// York Sec. 4.2: the piston–container period (Eq. 27, Table I) for
/// m = 0.1 and 1.0 at h = 1, 0.5, 0.25 (quick: 1, 0.5), three periods each:
/// `|T/T_exact − 1|` with `T_exact = 2π/ω` from Eq. 27's fundamental root.
///
/// # Errors
/// Any solver error.
pub fn york_piston_container(quick: bool) -> Result<StudyResult> {
    let hs: &[f64] = if quick {
        &[1.0, 0.5]
    } else {
        &[1.0, 0.5, 0.25]
    };
    let mut series = Vec::new();
    let mut notes = vec![
        "spring of elastic points (E A/L = K = 100, L = 20, mass 1e-5 m), one piston point of mass m, gas points (rho = 1e-4, L = 20, stiffened gas at p = 0 with p_inf = b/gamma so the bulk modulus is b = 1.58e6, recovered from Table I), GIMP, MUSL, York q; period = 2 pi / omega of the single-frequency least-squares fit of the piston displacement over six periods (the velocity zero-crossing period, kept as the extra `period_crossings`, is biased by the gas column's high-frequency ripple, which refinement damps less: it does not converge for m = 0.1)".to_string(),
        "target: both periods within 0.5 % of Eq. 27's roots and converging".to_string(),
    ];
    for (mass, table) in [
        (0.1, (886.2, 0.00709, 0.0071)),
        (1.0, (281.2, 0.02234, 0.022)),
    ] {
        let mut points = Vec::new();
        let mut omega = 0.0;
        for &h in hs {
            let s = PistonContainer {
                mass,
                h,
                periods: 6.0,
                ..PistonContainer::default()
            };
            let r = run_piston_container(&s).with_context(|| format!("m = {mass}, h = {h}"))?;
            omega = r.omega_exact;
            let exact = 2.0 * std::f64::consts::PI / r.omega_exact;
            let err = (r.period / exact - 1.0).abs();
            notes.push(format!(
                "m = {mass}, h = {h}: period {:.7} s vs Eq. 27 {exact:.7} s (rel. error {err:.2e}; zero crossings {:.2e}), {} steps, {:.2} s",
                r.period, (r.period_crossings / exact - 1.0).abs(), r.steps, r.wall_s
            ));
            let cells = 2.0 * s.length / h;
            points.push(
                Point::new(
                    h,
                    err,
                    r.wall_s,
                    cells * r.steps as f64 / r.wall_s.max(1e-12),
                )
                .with_extra("period", r.period)
                .with_extra("period_crossings", r.period_crossings)
                .with_extra("steps", r.steps as f64),
            );
        }
        notes.push(format!(
            "m = {mass}: Eq. 27 root omega = {omega:.2} rad/s, period {:.5} s; York Table I: {} rad/s, {} s, MPM {} s",
            2.0 * std::f64::consts::PI / omega,
            table.0,
            table.1,
            table.2
        ));
        series.push(Series::new(
            format!("piston-container m = {mass}"),
            "|T/T_exact - 1|",
            points,
        ));
    }
    for n in &notes {
        eprintln!("{n}");
    }
    Ok(StudyResult {
        study: "york_piston_container".into(),
        h_axis: "cell size h [m]".into(),
        error_axis: "relative period error |T/T_exact − 1| [-]".into(),
        series,
        notes,
    })
}

/// York Sec. 4.3: the dog-bone membrane expansion (York Fig. 10, Tables
/// II–IV) at element sizes 0.4, 0.2, 0.1, 0.05 (quick: 0.4, 0.2; or the
/// list in `YORK_DOGBONE_H`) with the quadratic B-spline and the gas
/// points' grid density at CFL 0.2 (the case), the same with York Eq. 16's
/// continuity density at CFL 0.4 to h = 0.1, and at 0.4, 0.2 with GIMP
/// and the grid density (the control: there gas points drift through the
/// membrane), membrane points an eighth of a cell apart, to t =
/// `YORK_DOGBONE_END` (default 4): final mean radius and pressure, radii
/// at 0° and 90°, hoop stress against p r / t, energy, gas points outside
/// the membrane, Σ V_p over the enclosed area, wall time. Series: the hoop
/// stress's relative difference from Laplace's p r / t (p from the gas's
/// p V over the enclosed area), per configuration, and the radii's
/// difference |r(0°) − r(90°)| / r, and the mean-radius history's largest
/// difference over time from the next finer size's. Each run's history goes to
/// `york_dogbone[_continuity|_gimp]_h{h}.csv` beside the study's JSON
/// (`results/`, `results/quick/` or `--out`).
///
/// # Errors
/// Any solver error.
pub fn york_dogbone(quick: bool) -> Result<StudyResult> {
    use mpmice::diagnostics::york_membrane::{run_dog_bone, DogBone};
    use mpmice::material::PointDensity;
    let hs: Vec<f64> = match std::env::var("YORK_DOGBONE_H") {
        Ok(v) => v.split(',').filter_map(|x| x.trim().parse().ok()).collect(),
        Err(_) if quick => vec![0.4, 0.2],
        Err(_) => vec![0.4, 0.2, 0.1, 0.05],
    };
    let end: f64 = std::env::var("YORK_DOGBONE_END")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(4.0);
    let paper = [
        (0.4, 1.07, 50.3, 101.0),
        (0.2, 1.33, 28.8, 399.0),
        (0.1, 1.35, 31.2, 400.0),
        (0.05, 1.36, 31.7, 433.0),
    ];
    let mut notes = vec![
        format!(
            "reconstructed dog-bone: lobes r = {}, centres at +-{}, neck half-width {} (perimeter {:.3}); E = 1e4 (exponent recovered from York Table IV: E = {:.3e}); nu = 0.3, thickness 0.1, membrane rho 0.5; gas rho 1, e0 250 (p0 = 100), mu 0.2, York q; MUSL, FLIP, 2x2 gas points per cell filling the membrane's polygon, end t = {end}",
            DogBone::LOBE_RADIUS,
            DogBone::LOBE_OFFSET,
            DogBone::NECK,
            DogBone::perimeter(),
            DogBone::recovered_young()
        ),
        "targets: final radius converges; at the two finest sizes hoop within 2 % of p r / t and radii at 0 and 90 deg within 1 %; no gas point outside".to_string(),
        "shapes: the quadratic B-spline is the case's; with GIMP gas points drift onto the membrane and through it (6 out at h = 0.2, 10 at h = 0.1 in the stored run of 6d54763, with continuity density, which took 678 s at h = 0.1 as the escaped points expanded)".to_string(),
        "density: the case's gas points read their density from the grid (point_density = grid) at CFL 0.2; York Eq. 16's continuity density (CFL 0.4) is the second series: its points' volumes outgrow the enclosed area (sum V_p / area 3.5 at t = 4, h = 0.2), which halves the point-mean pressure and inflates the viscous stress and the viscous time-step limit".to_string(),
    ];
    // Beside the study's JSON: `results/`, `results/quick/` or `--out`.
    let root = crate::plot_dir(quick);
    std::fs::create_dir_all(&root)?;
    let mut series = Vec::new();
    let gimp_hs: Vec<f64> = hs.iter().copied().filter(|&h| h >= 0.2).collect();
    // York Eq. 16's continuity density at CFL 0.4 to h = 0.1 (at 0.05 it
    // took 2079 s, the inflated points' viscous limit setting Δt).
    let continuity_hs: Vec<f64> = hs.iter().copied().filter(|&h| h >= 0.1).collect();
    let grid = PointDensity::Grid;
    for (shape, tag, sizes, density, cfl) in [
        ("quadratic_bspline", "", &hs, grid, 0.2),
        (
            "quadratic_bspline",
            "_continuity",
            &continuity_hs,
            PointDensity::Continuity,
            0.4,
        ),
        ("gimp", "_gimp", &gimp_hs, grid, 0.2),
    ] {
        let mut points = Vec::new();
        let mut round_points = Vec::new();
        let mut histories = Vec::new();
        let name = format!("{shape}, {} density, CFL {cfl}", density.name());
        for &h in sizes {
            let s = DogBone {
                h,
                end,
                shape,
                point_density: density,
                cfl,
                ..DogBone::default()
            };
            let r = run_dog_bone(&s).with_context(|| format!("dog-bone h = {h}, {name}"))?;
            let m = r.last;
            let laplace = m.area_pressure * m.mean_radius / DogBone::THICKNESS;
            let err = (m.mean_stress - laplace).abs() / laplace;
            let round = (m.radius_0 - m.radius_90).abs() / m.mean_radius;
            let total = |x: &mpmice::diagnostics::york_membrane::DogBoneSample| {
                x.kinetic + x.internal + x.strain
            };
            let e0 = r.history.first().map_or(0.0, total);
            let e1 = r.history.last().map_or(0.0, total);
            let (k1, g1) = r
                .history
                .last()
                .map_or((0.0, 0.0), |x| (x.kinetic, x.grid_kinetic));
            let (pr, pp, ps) = paper
                .iter()
                .find(|x| (x.0 - h).abs() < 1e-9)
                .map_or((f64::NAN, f64::NAN, f64::NAN), |x| (x.1, x.2, x.3));
            notes.push(format!(
                "{name}, h = {h}: mean radius {:.4} (York {pr}), radius 0/90 deg {:.4}/{:.4} (differ {:.2} %), point-mean pressure {:.2} (York {pp}), p from p V / area {:.2}, hoop {:.1} (York {ps}) vs p r / t {:.1} ({:.2} %), energy {:.2} -> {:.2} ({:+.3} %; kinetic at the end {:.3} on the points, {:.3} on the grid), gas points outside {} at the end (max {}), sum V_p / area {:.3}, {} steps, {} particles, {:.1} s",
                m.mean_radius, m.radius_0, m.radius_90, 100.0 * round, m.mean_pressure, m.area_pressure,
                m.mean_stress, laplace, 100.0 * err, e0, e1, 100.0 * (e1 / e0 - 1.0), k1, g1,
                r.outside_end, r.outside_max, m.gas_volume / m.area, r.steps, r.particles, r.wall_s
            ));
            eprintln!("{}", notes.last().map_or("", |s| s.as_str()));
            std::fs::write(
                root.join(format!("york_dogbone{tag}_h{h}.csv")),
                r.history_csv(),
            )?;
            let mut snaps = String::from("t,kind,x,y\n");
            for ((t, mem), (_, gas)) in r.snapshots.iter().zip(&r.gas_snapshots) {
                for (kind, pts) in [("membrane", mem), ("gas", gas)] {
                    for p in pts.iter() {
                        snaps.push_str(&format!("{t},{kind},{},{}\n", p[0], p[1]));
                    }
                }
            }
            std::fs::write(
                root.join(format!("york_dogbone{tag}_points_h{h}.csv")),
                snaps,
            )?;
            let ups = r.particles as f64 * r.steps as f64 / r.wall_s.max(1e-12);
            points.push(
                Point::new(h, err, r.wall_s, ups)
                    .with_extra("mean_radius", m.mean_radius)
                    .with_extra("radius_0", m.radius_0)
                    .with_extra("radius_90", m.radius_90)
                    .with_extra("point_pressure", m.mean_pressure)
                    .with_extra("area_pressure", m.area_pressure)
                    .with_extra("hoop", m.mean_stress)
                    .with_extra("laplace", laplace)
                    .with_extra("energy_change", e1 / e0 - 1.0)
                    .with_extra("kinetic_end", k1)
                    .with_extra("grid_kinetic_end", g1)
                    .with_extra("gas_volume_over_area", m.gas_volume / m.area)
                    .with_extra("outside_end", r.outside_end as f64)
                    .with_extra("outside_max", r.outside_max as f64)
                    .with_extra("steps", r.steps as f64),
            );
            round_points.push(Point::new(h, round, r.wall_s, ups));
            histories.push((h, r.wall_s, r.history));
        }
        if points.is_empty() {
            continue;
        }
        series.push(Series::new(
            format!("dog-bone, {name}: hoop stress vs Laplace p r / t"),
            "|s/(p r/t) - 1|",
            points,
        ));
        series.push(Series::new(
            format!("dog-bone, {name}: radii at 0 and 90 deg"),
            "|r(0) - r(90)| / r",
            round_points,
        ));
        // Over time: each size's mean-radius history against the next finer
        // size's, sampled at the same times (York Fig. 13's curves).
        histories.sort_by(|a, b| b.0.total_cmp(&a.0));
        let pairs: Vec<Point> = histories
            .windows(2)
            .map(|w| {
                let ((h, wall, a), (_, _, b)) = (&w[0], &w[1]);
                let gap = a
                    .iter()
                    .zip(b)
                    .filter(|(x, y)| (x.t - y.t).abs() < 1e-9)
                    .map(|(x, y)| (x.mean_radius - y.mean_radius).abs())
                    .fold(0.0, f64::max);
                Point::new(*h, gap, *wall, 0.0)
            })
            .collect();
        // (An order needs two pairs: not for GIMP's two sizes.)
        if pairs.len() >= 2 {
            series.push(Series::new(
                format!("dog-bone, {name}: mean-radius history vs the next finer size"),
                "max_t |r_h(t) - r_h/2(t)|",
                pairs,
            ));
        }
    }
    Ok(StudyResult {
        study: "york_dogbone".into(),
        h_axis: "cell size h (nondimensional) [-]".into(),
        error_axis: "relative error (legend) [-]".into(),
        series,
        notes,
    })
}

/// York Sec. 4.4: the airbag impact (Tables V–VI, Figs. 14–17; shape and
/// the moduli reconstructed, see `mpmice::diagnostics::york_airbag::Airbag`)
/// at cell sizes 20, 10, 5 mm (quick: 20, 10; or the list in
/// `YORK_AIRBAG_H`, metres): peak penetration and its time, rebound
/// velocity, peak pressure (point mean and `p V`), the drift of `p V^γ` of
/// the bag's gas, the energy balance error (relative to the probe's kinetic
/// energy), gas points outside the bag, with York's dog-bone gas viscosity
/// (0.2 Pa s, the default) and, at 20 and 10 mm, inviscid (York Table VI),
/// with FLIP and with a PIC share of 0.01.
/// The series' error is the peak penetration's difference from the finest
/// size's. Histories go to `york_airbag[_inviscid[_pic]]_h{h}.csv`,
/// membrane shapes (release, peak, end) to
/// `york_airbag[_inviscid[_pic]]_shapes_h{h}.csv`, beside the study's JSON
/// (`results/`, `results/quick/` or `--out`).
///
/// # Errors
/// Any solver error.
pub fn york_airbag(quick: bool) -> Result<StudyResult> {
    use mpmice::diagnostics::york_airbag::{run_airbag, Airbag};
    let hs: Vec<f64> = match std::env::var("YORK_AIRBAG_H") {
        Ok(v) => v.split(',').filter_map(|x| x.trim().parse().ok()).collect(),
        Err(_) if quick => vec![0.02, 0.01],
        Err(_) => vec![0.02, 0.01, 0.005],
    };
    let cfg0 = Airbag::default();
    let mut notes = vec![format!(
        "reconstructed airbag (York Sec. 4.4): oblate spheroid a = {} m, c = {} m (surface 1.108 m^2 -> York's 367.2 g), back pole {} m above a no-slip floor; fabric E = {:.1e} Pa (York's exponent lost), nu {}, t {} m, rho {}; air gamma {}, rho {}, e0 {} (p0 = {:.1} Pa, acting as gauge); probe r = {} m, length {} m, {} kg, E = {:.0e} Pa, {} m/s; gas viscosity {} Pa s (and 0); inflation {} s with damping {} /s, impact {} s; GIMP, MUSL, 2x2 gas points per cell filling the spheroid shrunk by {} h (density raised to keep York's gas mass), membrane points h/8 apart",
        Airbag::BAG_RADIUS, Airbag::BAG_HALF_DEPTH, Airbag::FLOOR_GAP, cfg0.young, Airbag::POISSON,
        Airbag::THICKNESS, Airbag::FABRIC_DENSITY, Airbag::GAMMA, Airbag::AIR_DENSITY,
        Airbag::AIR_ENERGY, Airbag::pressure0(), Airbag::PROBE_RADIUS, Airbag::PROBE_LENGTH,
        Airbag::PROBE_MASS, Airbag::PROBE_YOUNG, Airbag::PROBE_SPEED, cfg0.gas_viscosity, cfg0.inflate_time,
        cfg0.inflate_damping, cfg0.impact_time, cfg0.gas_margin_over_h
    )];
    // Beside the study's JSON: `results/`, `results/quick/` or `--out`.
    let root = crate::plot_dir(quick);
    std::fs::create_dir_all(&root)?;
    let mut series = Vec::new();
    // The inviscid gas at the two coarsest sizes beside York's dog-bone
    // viscosity (the default) at every size.
    let inviscid: Vec<f64> = hs.iter().copied().filter(|&h| h >= 0.01 - 1e-12).collect();
    // And the inviscid gas with a PIC share of 0.01 (`mpm.pic_fraction`).
    for (mu, pic, sizes) in [
        (cfg0.gas_viscosity, 0.0, hs.clone()),
        (0.0, 0.0, inviscid.clone()),
        (0.0, 0.01, inviscid),
    ] {
        let mut runs = Vec::new();
        for &h in &sizes {
            let r = match run_airbag(&Airbag {
                h,
                gas_viscosity: mu,
                pic_fraction: pic,
                ..Airbag::default()
            }) {
                Ok(r) => r,
                // The inviscid gas is shown for its noise; its failure is a
                // result, not the study's end.
                Err(e) if mu == 0.0 => {
                    notes.push(format!(
                        "mu = 0 Pa s, PIC share {pic}, h = {h}: the run stopped: {e}"
                    ));
                    eprintln!("{}", notes.last().map_or("", |s| s.as_str()));
                    continue;
                }
                Err(e) => return Err(e).with_context(|| format!("airbag h = {h}, mu = {mu}")),
            };
            let i = r.inflated;
            let gas_ke = r.history.last().map_or(0.0, |s| s.gas_kinetic);
            notes.push(format!(
            "mu = {mu} Pa s, PIC share {pic}, h = {h}: gas kinetic energy {:.2} J at release, {gas_ke:.2} J at the end; bag mass {:.4} kg, probe mass {:.4} kg; after inflation p {:.1} (pV {:.1}) Pa, volume {:.5} m^3 (gas point volumes {:.5}, those inside {:.5}); peak penetration {:.4} m at {:.4} s, rebound velocity {:+.3} m/s (at the end {:+.3}), peak pressure {:.1} (pV {:.1}) Pa, p V^gamma drift {:.2e} (pV {:.2e}), energy error {:.2e} of the probe's kinetic energy, gas points outside max {}, {} steps, {} particles, {:.1} s",
            i.gas_kinetic, r.bag_mass, r.probe_mass, i.mean_pressure, i.volume_pressure, i.volume, i.gas_volume, i.gas_volume_inside,
            r.peak_penetration.0, r.peak_penetration.1, r.rebound_velocity, r.end_velocity, r.peak_pressure.0,
            r.peak_pressure.1, r.adiabat_drift.0, r.adiabat_drift.1, r.energy_error,
            r.history.iter().map(|s| s.outside).max().unwrap_or(0), r.steps, r.particles, r.wall_s
        ));
            eprintln!("{}", notes.last().map_or("", |s| s.as_str()));
            let tag = format!(
                "{}{}",
                if mu > 0.0 { "" } else { "_inviscid" },
                if pic > 0.0 { "_pic" } else { "" }
            );
            std::fs::write(
                root.join(format!("york_airbag{tag}_h{h}.csv")),
                r.history_csv(),
            )?;
            let mut shapes = String::from("t,r,z\n");
            for (t, pts) in &r.shapes {
                for p in pts {
                    shapes.push_str(&format!("{t},{},{}\n", p[0], p[1]));
                }
            }
            std::fs::write(
                root.join(format!("york_airbag{tag}_shapes_h{h}.csv")),
                shapes,
            )?;
            runs.push((h, r));
        }
        let finest = runs
            .iter()
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map_or(0.0, |(_, r)| r.peak_penetration.0);
        let points = runs
            .iter()
            .map(|(h, r)| {
                let ups = r.particles as f64 * r.steps as f64 / r.wall_s.max(1e-12);
                Point::new(*h, (r.peak_penetration.0 - finest).abs(), r.wall_s, ups)
                    .with_extra("peak_penetration", r.peak_penetration.0)
                    .with_extra("peak_time", r.peak_penetration.1)
                    .with_extra("rebound_velocity", r.rebound_velocity)
                    .with_extra("peak_pressure_mean", r.peak_pressure.0)
                    .with_extra("peak_pressure_pv", r.peak_pressure.1)
                    .with_extra("adiabat_drift_mean", r.adiabat_drift.0)
                    .with_extra("adiabat_drift_pv", r.adiabat_drift.1)
                    .with_extra("energy_error", r.energy_error)
                    .with_extra("steps", r.steps as f64)
                    .with_extra(
                        "gas_kinetic_end",
                        r.history.last().map_or(0.0, |s| s.gas_kinetic),
                    )
            })
            .collect();
        series.push(Series::new(
            format!(
                "airbag, gas viscosity {mu} Pa s{}: peak penetration vs the finest size",
                if pic > 0.0 {
                    format!(", PIC share {pic}")
                } else {
                    String::new()
                }
            ),
            "|d_peak(h) - d_peak(finest)| [m]",
            points,
        ));
    }
    Ok(StudyResult {
        study: "york_airbag".into(),
        h_axis: "cell size h [m]".into(),
        error_axis: "peak penetration difference to the finest h [m]".into(),
        series,
        notes,
    })
}
