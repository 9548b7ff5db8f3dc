//! Axisymmetric (r–z) explicit MPM against Lamé's exact solutions (York
//! Sec. 2, the remark after Eq. 14; York Sec. 4.4 runs axisymmetric): the
//! thick cylinder (plane strain) and the thick sphere under internal
//! pressure, damped to the quasistatic state.

use anyhow::{Context, Result};

use crate::harness::{Point, Series, StudyResult};
use mpmice::diagnostics::axisymmetric::{run_gas_loaded, Lame, LameShape, Relax};

/// Lamé cylinder and sphere (rᵢ = 0.5, r_o = 1, E = 1, ν = 0.3, ρ = 1,
/// P = 1e-5, Jaumann hypo-elastic, GIMP, USL, 2 particles per cell per
/// direction) at 4, 8, 16, 32 cells across the wall (quick: 4, 8; the
/// cylinder also at 64): relative L2 errors over the particles of σ_r,
/// σ_θ (hoop) and u_r, with the wall time; then the same walls loaded by
/// gas points in the bore / cavity (the scenes of `cases/axisym_lame_*.toml`)
/// at 4 … 32 (sphere 4 … 16).
///
/// # Errors
/// Any solver error.
pub fn axisym_lame(quick: bool) -> Result<StudyResult> {
    let relax = Relax::default();
    let mut series = Vec::new();
    let mut notes = vec![format!(
        "r_i = 0.5, r_o = 1, E = 1, nu = 0.3, rho = 1, P = 1e-5, Jaumann hypo-elastic (York Eqs. 18-20), \
         GIMP, USL, 2 particles per cell per direction (sphere: polar lattice of the same spacing), \
         CFL {}, damping alpha = {}, load ramp 0.5(1 - cos(pi t/T)) with T = {}, end t = {}; \
         pressure as a body force on the first particle layer with the axisymmetric surface measure; \
         errors: relative L2 over particles weighted by V0 (per radian), exact at the reference radius",
        relax.cfl, relax.damping, relax.ramp, relax.end
    )];
    for shape in [LameShape::Cylinder, LameShape::Sphere] {
        let ns: &[usize] = match (quick, shape) {
            (true, _) => &[4, 8],
            (false, LameShape::Cylinder) => &[4, 8, 16, 32, 64],
            (false, LameShape::Sphere) => &[4, 8, 16, 32],
        };
        let lame = Lame::standard(shape);
        let mut pts: [Vec<Point>; 6] = Default::default();
        for &n in ns {
            let m = lame
                .run(n, &relax)
                .with_context(|| format!("{} with {n} cells across the wall", shape.name()))?;
            let ups = m.particles as f64 * m.steps as f64 / m.wall_s.max(1e-12);
            notes.push(format!(
                "{} n = {n} (h = {:.5}): sigma_r {:.3e}, sigma_theta {:.3e}, u_r {:.3e}, {} {:.3e}; \
                 beyond the first cell (r0 >= r_i + h): sigma_r {:.3e}, sigma_theta {:.3e}; \
                 KE/strain {:.1e}; {} particles, {} steps, {:.2} s",
                shape.name(),
                m.h,
                m.sigma_r,
                m.sigma_theta,
                m.u_r,
                if shape == LameShape::Sphere { "sigma_phi" } else { "sigma_z" },
                m.sigma_third,
                m.sigma_r_interior,
                m.sigma_theta_interior,
                m.kinetic_ratio,
                m.particles,
                m.steps,
                m.wall_s
            ));
            for (k, e) in [
                m.sigma_r,
                m.sigma_theta,
                m.u_r,
                m.sigma_third,
                m.sigma_r_interior,
                m.sigma_theta_interior,
            ]
            .into_iter()
            .enumerate()
            {
                pts[k].push(
                    Point::new(m.h, e, m.wall_s, ups)
                        .with_extra("steps", m.steps as f64)
                        .with_extra("particles", m.particles as f64)
                        .with_extra("kinetic_over_strain", m.kinetic_ratio),
                );
            }
        }
        let third = if shape == LameShape::Sphere {
            "sigma_phi (meridional)"
        } else {
            "sigma_z (plane strain)"
        };
        for (k, q) in [
            "sigma_r",
            "sigma_theta (hoop)",
            "u_r",
            third,
            "sigma_r beyond the first cell",
            "sigma_theta beyond the first cell",
        ]
        .iter()
        .enumerate()
        {
            series.push(Series::new(
                format!("{} {q}", shape.name()),
                "relative L2",
                std::mem::take(&mut pts[k]),
            ));
        }
    }
    // The same walls loaded through the grid by gas points at P filling the
    // bore / cavity (the scenes of cases/axisym_lame_*.toml at n = 8).
    notes.push(
        "gas-loaded: the same walls loaded by gas points (ideal gas, rho = 1e-4, p = P) filling \
         the bore / cavity, as scenes (cases/axisym_lame_cylinder.toml, \
         cases/axisym_lame_sphere.toml at n = 8): square particle lattice (the sphere's surfaces \
         are staircases), GIMP, MUSL, damping 3, t = 20"
            .to_string(),
    );
    for shape in [LameShape::Cylinder, LameShape::Sphere] {
        let ns: &[usize] = match (quick, shape) {
            (true, _) => &[4, 8],
            (false, LameShape::Cylinder) => &[4, 8, 16, 32],
            (false, LameShape::Sphere) => &[4, 8, 16],
        };
        let lame = Lame::standard(shape);
        let mut pts: [Vec<Point>; 3] = Default::default();
        for &n in ns {
            let m = run_gas_loaded(&lame, n)
                .with_context(|| format!("gas-loaded {} n = {n}", shape.name()))?;
            let ups = m.particles as f64 * m.steps as f64 / m.wall_s.max(1e-12);
            notes.push(format!(
                "gas-loaded {} n = {n} (h = {:.5}): sigma_r {:.3e}, sigma_theta {:.3e}, u_r {:.3e}; \
                 wall KE/strain {:.1e}; {} particles, {} steps, {:.2} s",
                shape.name(),
                m.h,
                m.sigma_r,
                m.sigma_theta,
                m.u_r,
                m.kinetic_ratio,
                m.particles,
                m.steps,
                m.wall_s
            ));
            for (k, e) in [m.sigma_r, m.sigma_theta, m.u_r].into_iter().enumerate() {
                pts[k].push(
                    Point::new(m.h, e, m.wall_s, ups)
                        .with_extra("steps", m.steps as f64)
                        .with_extra("particles", m.particles as f64)
                        .with_extra("kinetic_over_strain", m.kinetic_ratio),
                );
            }
        }
        for (k, q) in ["sigma_r", "sigma_theta (hoop)", "u_r"].iter().enumerate() {
            series.push(Series::new(
                format!("{} gas-loaded {q}", shape.name()),
                "relative L2",
                std::mem::take(&mut pts[k]),
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
        study: "axisym_lame".into(),
        h_axis: "cell size h = 0.5/n across the wall (nondimensional) [-]".into(),
        error_axis: "relative L2 error (quantity in the legend) [-]".into(),
        series,
        notes,
    })
}
