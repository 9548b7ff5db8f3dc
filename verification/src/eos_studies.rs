//! Studies of the equations of state: the Mie–Grüneisen wall shock in
//! explicit ICE (`cases/mie_gruneisen_shock.toml`, water and copper), and
//! the water–air (stiffened gas | ideal gas) shock tube against the exact
//! two-material Riemann solution (`cases/water_air_shock_tube.toml`).

use anyhow::Result;

use crate::harness::{Point, Series, StudyResult};
use mpmice::diagnostics::shock::{copper, gas_point_wall_shock, wall_shock, wall_shock_scene};
use mpmice::scene::parse;

const CASE: &str = include_str!("../../cases/mie_gruneisen_shock.toml");

/// Water (and copper) at its reference state driven into a wall at `u_p`
/// (`mpmice::diagnostics::shock`): the relative error of the measured shock
/// speed against `U_s = c₀ + s u_p` and of the post-shock pressure against
/// `p₀ + ρ₀ U_s u_p`, against the cell size, per material and `u_p`
/// (explicit ICE, the case's high-resolution variant, `cfl = 0.4`, shock
/// run over 0.8 of the 1 m domain, front fitted at 9 times); and the water
/// on gas material points (York Sec. 3.3; `gas_point_wall_shock`).
///
/// # Errors
/// Any scene or solver error.
pub fn mie_gruneisen_shock(quick: bool) -> Result<StudyResult> {
    let ns: &[usize] = if quick {
        &[100, 200]
    } else {
        &[100, 200, 400, 800]
    };
    let water = parse(CASE)?;
    let cu = copper(&water);
    let mut series = Vec::new();
    let mut notes = vec![
        "reflected shock from a wall, material at its reference state moving at -u_p; U_s from a least-squares fit of the front (p = p0 + rho0 U_s u_p / 2) at 9 times in [t_end/4, t_end]; p1 the mean over the middle half of the shocked layer; h = 1/N m".to_string(),
        "water: rho0 998, c0 1483, s 1.75, Gamma0 0.5, cv 4180 (Steinberg UCRL-MA-106439); copper: rho0 8930, c0 3940, s 1.49, Gamma0 2.02, cv 383".to_string(),
    ];
    let cases: &[(&str, &mpmice::scene::Scene, &[f64])] = &[
        ("water", &water, &[100.0, 500.0, 1000.0, 3000.0]),
        ("copper", &cu, &[100.0, 500.0, 1000.0, 3000.0]),
    ];
    for &(name, base, ups) in cases {
        for &up in ups {
            let (mut us_pts, mut p_pts) = (Vec::new(), Vec::new());
            for &n in ns {
                let s = wall_shock_scene(base, n, up)?;
                let r = wall_shock(&s, 9)?;
                let ups_rate = n as f64 * r.steps as f64 / r.wall_s.max(1e-12);
                let p0 = 101_325.0;
                us_pts.push(
                    Point::new(r.h, r.us_error(), r.wall_s, ups_rate)
                        .with_extra("us", r.us)
                        .with_extra("us_exact", r.us_exact)
                        .with_extra("steps", r.steps as f64)
                        .with_extra("p_max_over_p1", r.p_max / r.p_exact),
                );
                p_pts.push(
                    Point::new(r.h, r.p_error(p0), r.wall_s, ups_rate)
                        .with_extra("p1", r.p_post)
                        .with_extra("p1_exact", r.p_exact),
                );
                notes.push(format!(
                    "{name} u_p {up} N {n}: U_s {:.2} (exact {:.2}), p1 {:.5e} (exact {:.5e}), max p/p1 {:.3}, {} steps, {:.2} s",
                    r.us, r.us_exact, r.p_post, r.p_exact, r.p_max / r.p_exact, r.steps, r.wall_s
                ));
            }
            series.push(Series::new(
                format!("{name} u_p = {up} m/s: U_s vs c0 + s u_p"),
                "relative",
                us_pts,
            ));
            series.push(Series::new(
                format!("{name} u_p = {up} m/s: p1 vs p0 + rho0 U_s u_p"),
                "relative to the jump",
                p_pts,
            ));
        }
    }
    // The water on gas material points (York Sec. 3.3), shock followed
    // over 0.4 m of the 1 m strip (the free-surface release comes later).
    let gp_ns: &[usize] = if quick { &[100] } else { &[100, 200, 400] };
    for up in [100.0, 500.0, 1000.0, 3000.0] {
        let (mut us_pts, mut p_pts) = (Vec::new(), Vec::new());
        for &n in gp_ns {
            let r = match gas_point_wall_shock(&water, n, up, 9) {
                Ok(r) => r,
                Err(e) => {
                    notes.push(format!("gas points u_p {up} N {n}: failed: {e}"));
                    continue;
                }
            };
            let rate = (9 * n) as f64 * r.steps as f64 / r.wall_s.max(1e-12);
            us_pts.push(
                Point::new(r.h, r.us_error(), r.wall_s, rate)
                    .with_extra("us", r.us)
                    .with_extra("us_exact", r.us_exact)
                    .with_extra("steps", r.steps as f64)
                    .with_extra("p_max_over_p1", r.p_max / r.p_exact),
            );
            p_pts.push(
                Point::new(r.h, r.p_error(101_325.0), r.wall_s, rate)
                    .with_extra("p1", r.p_post)
                    .with_extra("p1_exact", r.p_exact),
            );
            notes.push(format!(
                "gas points water u_p {up} N {n}: U_s {:.2} (exact {:.2}), p1 {:.5e} (exact {:.5e}), max p/p1 {:.3}, {} steps, {:.2} s",
                r.us, r.us_exact, r.p_post, r.p_exact, r.p_max / r.p_exact, r.steps, r.wall_s
            ));
        }
        series.push(Series::new(
            format!("gas points, water u_p = {up} m/s: U_s vs c0 + s u_p"),
            "relative",
            us_pts,
        ));
        series.push(Series::new(
            format!("gas points, water u_p = {up} m/s: p1 vs p0 + rho0 U_s u_p"),
            "relative to the jump",
            p_pts,
        ));
    }
    Ok(StudyResult {
        study: "mie_gruneisen_shock".into(),
        h_axis: "cell size h = 1/N [m]".into(),
        error_axis: "relative error: U_s, or p1 relative to the jump (legend) [-]".into(),
        series,
        notes,
    })
}

const WATER_AIR: &str = include_str!("../../cases/water_air_shock_tube.toml");

/// The water–air shock tube (`cases/water_air_shock_tube.toml`: water, a
/// stiffened gas, at 1000 kg/m³ against air at 50 kg/m³ and 1e5 Pa) at
/// pressure ratios 10, 100 and 1e4 (water at 1e6, 1e7, 1e9 Pa), explicit
/// two-material ICE with stiff momentum exchange
/// (`mpmice::diagnostics::interface_tube`): mean L1 error of the mixture
/// density against the exact cell averages of the two-material Riemann
/// solution, and the error of the interface position (the water volume)
/// against the contact `x0 + u* t`, against the cell size.
///
/// # Errors
/// Any scene or solver error.
pub fn water_air_shock_tube(quick: bool) -> Result<StudyResult> {
    use mpmice::diagnostics::interface_tube::{interface_tube, with_cells};
    let ns: &[usize] = if quick {
        &[100, 200, 400]
    } else {
        &[100, 200, 400, 800, 1600]
    };
    let base = parse(WATER_AIR)?;
    let mut series = Vec::new();
    let mut notes = vec![
        "explicit ICE (and semi-implicit where labelled: direct solver, sound_speed_factor 1), high_resolution variant, cfl 0.4, momentum exchange 1e15, no heat exchange; domain [0, 1] m, diaphragm at 0.7 m, t = 2e-4 s; h = 1/N m".to_string(),
        "L1(rho): mean over the cells of |rho_mix - exact cell average| (kg/m^3); beyond 2h of the contact: the same sum without the cells whose centre is within 2h of x0 + u* t, over all cells (the waves' error: the smeared contact adds about h |rho_water - rho_air| / L times a factor set by where the contact sits in its cell, which at ratio 100, where the contact moves 1.2 mm, does not settle); interface: |x_lower + sum(theta_water h) - (x0 + u* t)| (m)".to_string(),
    ];
    // The semi-implicit pressure (Guilkey Eq. 29 solved implicitly) with
    // the acoustic Courant number at cfl (sound_speed_factor = 1; with 0 its
    // first step, at rest, would take the whole run).
    let runs = [
        ("ratio 10", 1.0e6, false),
        ("ratio 100", 1.0e7, false),
        ("ratio 1e4", 1.0e9, false),
        ("semi-implicit ratio 10", 1.0e6, true),
        ("semi-implicit ratio 1e4", 1.0e9, true),
    ];
    for (label, p_water, semi) in runs {
        let (mut l1, mut waves, mut xi) = (Vec::new(), Vec::new(), Vec::new());
        for &n in ns {
            let mut s = with_cells(&base, n);
            s.regions[1].pressure = p_water;
            if semi {
                s.time.mode = mpmice::scene::Mode::SemiImplicit;
                s.fluid.pressure.sound_speed_factor = 1.0;
            }
            let r = interface_tube(&s)?;
            let ups = n as f64 * r.steps as f64 / r.wall_s.max(1e-12);
            l1.push(
                Point::new(r.h, r.l1_rho, r.wall_s, ups)
                    .with_extra("l1_rho_relative", r.l1_rho_relative)
                    .with_extra("steps", r.steps as f64)
                    .with_extra("mass_drift", r.mass_drift)
                    .with_extra("energy_drift", r.energy_drift)
                    .with_extra("min_temperature", r.min_temperature)
                    .with_extra("min_density", r.min_density),
            );
            waves.push(Point::new(r.h, r.l1_rho_waves, r.wall_s, ups));
            xi.push(
                Point::new(r.h, r.interface_error(), r.wall_s, ups)
                    .with_extra("interface", r.interface)
                    .with_extra("interface_exact", r.interface_exact),
            );
            notes.push(format!(
                "{label} N {n}: p* {:.6e} u* {:.5}; L1(rho) {:.4e} (relative {:.3e}); interface {:.6} (exact {:.6}); mass drift {:.1e}, energy drift {:.1e}; min T {:.4}, min rho {:.4e}; {} steps, {:.3} s",
                r.p_star, r.u_star, r.l1_rho, r.l1_rho_relative, r.interface, r.interface_exact,
                r.mass_drift, r.energy_drift, r.min_temperature, r.min_density, r.steps, r.wall_s
            ));
        }
        series.push(Series::new(format!("{label} density"), "L1", l1));
        series.push(Series::new(
            format!("{label} density beyond 2h of the contact"),
            "L1",
            waves,
        ));
        series.push(Series::new(
            format!("{label} interface position"),
            "abs",
            xi,
        ));
    }
    Ok(StudyResult {
        study: "water_air_shock_tube".into(),
        h_axis: "cell size h = 1/N [m]".into(),
        error_axis: "L1 density error [kg/m³] or interface error [m] (legend)".into(),
        series,
        notes,
    })
}
