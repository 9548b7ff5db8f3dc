//! The Taylor anvil (issue 18): a Johnson–Cook OFHC copper rod (L₀ 25.4 mm,
//! D₀ 7.62 mm) on a rigid frictionless wall in axisymmetric r–z MPM
//! (`cases/taylor_anvil.toml`, `mpmice::diagnostics::taylor`), final length
//! and impact-face diameter against the measured rods at 190, 146 and 130
//! m/s, with the energy account.

use anyhow::{Context, Result};

use crate::harness::{Point, Series, StudyResult};
use mpmice::diagnostics::taylor::{run, MEASURED};

/// Cells per rod radius R₀/h: 3, 6, 12, 24 at 190 m/s and 3, 6, 12 at 146
/// and 130 m/s (quick: 3, 6), to 80 µs. Errors: |L_f/L₀ − measured| and
/// |D_f/D₀ − measured| (absolute, in units of L₀ and D₀).
///
/// # Errors
/// A run that fails.
pub fn taylor_anvil(quick: bool) -> Result<StudyResult> {
    let path = format!("{}/../cases/taylor_anvil.toml", env!("CARGO_MANIFEST_DIR"));
    let base = mpmice::scene::load(std::path::Path::new(&path)).context("taylor case")?;
    let end = 80e-6;
    let mut series = Vec::new();
    let mut notes = vec![
        "OFHC copper, Johnson & Cook 1983 flow stress (A 90 MPa, B 292 MPa, n 0.31, C 0.025, \
         m 1.09, T_melt 1356 K, rho 8960, c_p 383, beta 0.9, E 124 GPa, nu 0.34), hypo-elastic \
         J2 radial return, axisymmetric GIMP, MUSL, CFL 0.4, 2x2 particles per cell, rigid \
         frictionless wall = symmetry face, t_end = 80 us; reference: measured final shapes \
         (Zerilli & Armstrong 1987 p. 1822 / Johnson & Cook 1983 test, digitized in Banerjee's \
         HighRateExptData CuZerilli.dat): 190 m/s L_f/L0 0.638, D_f/D0 1.78; 146 m/s 0.736, \
         1.40; 130 m/s 0.770, 1.30. D_f: impact-face diameter (initial bottom particle row, \
         outer edge)"
            .to_string(),
    ];
    for &(speed, l_ref, d_ref) in MEASURED.iter().rev() {
        let ns: &[usize] = match (quick, speed == 190.0) {
            (true, _) => &[3, 6],
            (false, true) => &[3, 6, 12, 24],
            (false, false) => &[3, 6, 12],
        };
        let (mut lp, mut dp) = (Vec::new(), Vec::new());
        for &n in ns {
            let m = run(&base, n, speed, end).with_context(|| format!("{speed} m/s at R0/{n}"))?;
            let ups = m.particles as f64 * m.steps as f64 / m.wall_s.max(1e-12);
            notes.push(format!(
                "{speed} m/s, h = R0/{n}: L/L0 {:.4} (measured {l_ref}), D_f/D0 {:.4} (largest \
                 {:.4}; measured {d_ref}), energy error |K0 - K - W|/K0 {:.2e}, plastic \
                 account |W_p - (K0 - K - E_e)|/K0 {:.2e}, K/K0 {:.3e}, E_e/K0 {:.3e}, max eps \
                 {:.3}, gap to the wall {:.1e} m; {} particles, {} steps, {:.2} s",
                m.length_ratio(),
                m.footprint / 7.62e-3,
                m.diameter_ratio(),
                m.energy_error(),
                m.plastic_account_error(),
                m.kinetic / m.kinetic0,
                m.elastic / m.kinetic0,
                m.max_plastic_strain,
                m.gap,
                m.particles,
                m.steps,
                m.wall_s
            ));
            let pt = |e: f64| {
                Point::new(m.h, e, m.wall_s, ups)
                    .with_extra("length_ratio", m.length_ratio())
                    .with_extra("diameter_ratio", m.footprint / 7.62e-3)
                    .with_extra("energy_error", m.energy_error())
                    .with_extra("plastic_account_error", m.plastic_account_error())
                    .with_extra("particles", m.particles as f64)
                    .with_extra("steps", m.steps as f64)
            };
            lp.push(pt((m.length_ratio() - l_ref).abs()));
            dp.push(pt((m.footprint / 7.62e-3 - d_ref).abs()));
        }
        series.push(Series::new(
            format!("{speed} m/s L_f/L0 vs measured"),
            "abs",
            lp,
        ));
        series.push(Series::new(
            format!("{speed} m/s D_f/D0 vs measured"),
            "abs",
            dp,
        ));
    }
    // Sensitivity at R0/6, 190 m/s: is the gap to the measurement a
    // discretisation error? Shape function, update scheme, particles per
    // cell.
    if !quick {
        type Change = fn(&mut mpmice::scene::Scene);
        let variants: [(&str, Change); 3] = [
            ("quadratic B-spline", |s| {
                s.mpm.shape = mpmice::shape::ShapeKind::QuadraticBspline
            }),
            ("USL", |s| {
                s.mpm.update = Some(mpmice::mpm::UpdateScheme::Usl)
            }),
            ("3x3 particles per cell", |s| s.mpm.particles_per_cell = 3),
        ];
        for (name, change) in variants {
            let mut sc = base.clone();
            change(&mut sc);
            let m = run(&sc, 6, 190.0, end).with_context(|| name.to_string())?;
            notes.push(format!(
                "sensitivity, 190 m/s, h = R0/6, {name}: L/L0 {:.4}, D_f/D0 {:.4}, gap to the \
                 wall {:.1e} m",
                m.length_ratio(),
                m.footprint / 7.62e-3,
                m.gap
            ));
        }
    }
    Ok(StudyResult {
        study: "taylor_anvil".into(),
        h_axis: "cell size h = R₀/n [m]".into(),
        error_axis: "|L_f/L₀ − measured| or |D_f/D₀ − measured| (legend) [-]".into(),
        series,
        notes,
    })
}
