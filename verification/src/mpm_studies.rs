//! Explicit MPM studies: the 1D bar and the axis-aligned manufactured solution.

use mpmice::diagnostics::mms::{run_bar, run_mms, AxisAlignedMms, BarMode1, Measured};
use mpmice::mpm::UpdateScheme;
use mpmice::shape::ShapeKind;

use crate::harness::{Point, Series, StudyResult};

/// Shape functions in every MPM study, with short labels.
pub const SHAPES: [(ShapeKind, &str); 5] = [
    (ShapeKind::Linear, "linear"),
    (ShapeKind::Gimp, "gimp"),
    (ShapeKind::QuadraticBspline, "bspline2"),
    (ShapeKind::CubicBspline, "bspline3"),
    (ShapeKind::QuadraticBsplineGimp, "bspline2_gimp"),
];

fn point(m: &Measured) -> Point {
    let mut p = Point::new(m.h, m.error, m.wall_s, m.updates_per_s())
        .with_extra("max_error", m.max_error)
        .with_extra("steps", m.steps as f64)
        .with_extra("particles", m.particles as f64);
    if m.energy_drift.is_finite() {
        p = p.with_extra("energy_drift", m.energy_drift);
    }
    p
}

/// `mpm_bar_1d`: elastic bar, fixed–free, mode 1, one period, USL, CFL 0.2.
pub fn mpm_bar_1d(quick: bool) -> anyhow::Result<StudyResult> {
    let bar = BarMode1 {
        length: 1.0,
        youngs: 100.0,
        rho: 1.0,
        v0: 1e-3,
        damping: 0.0,
    };
    let ns: &[usize] = if quick {
        &[8, 16, 32]
    } else {
        &[8, 16, 32, 64, 128, 256]
    };
    let mut series = Vec::new();
    for (shape, label) in SHAPES {
        let mut points = Vec::new();
        for &n in ns {
            let m = run_bar(&bar, shape, UpdateScheme::Usl, n, 0.2)?;
            points.push(point(&m));
        }
        series.push(Series::new(
            label.to_string(),
            "max_t RMS displacement error / amplitude".to_string(),
            points,
        ));
    }
    Ok(StudyResult {
        study: "mpm_bar_1d".into(),
        h_axis: "cell size h = 1/N (nondimensional) [-]".into(),
        error_axis: "max_t RMS displacement error / amplitude [-]".into(),
        series,
        notes: vec![
            "Bar L = 1, E = 100, rho = 1, nu = 0 (c = 10), v0 = 1e-3 in mode 1, fixed at x = 0, \
             free at x = L; 2 particles per cell; USL, FLIP, CFL 0.2; one period 4L/c."
                .into(),
            "extra.energy_drift: relative change of kinetic + strain energy over the period."
                .into(),
        ],
    })
}

/// `mpm_mms_axis_aligned`: Wallstedt & Guilkey's axis-aligned MMS in 1D and
/// 2D, every shape function, A = 1e-4 (no cell crossing) and A = 0.05.
pub fn mpm_mms_axis_aligned(quick: bool) -> anyhow::Result<StudyResult> {
    let mut series = Vec::new();
    let n1: &[usize] = if quick {
        &[8, 16, 32]
    } else {
        &[8, 16, 32, 64, 128, 256]
    };
    let n2: &[usize] = if quick {
        &[8, 16]
    } else {
        &[8, 16, 32, 64, 128]
    };
    for amplitude in [1e-4, 0.05] {
        let mms = AxisAlignedMms::standard(amplitude);
        for (shape, label) in SHAPES {
            for dim in [1usize, 2] {
                let mut points = Vec::new();
                for &n in if dim == 1 { n1 } else { n2 } {
                    let m = if dim == 1 {
                        run_mms::<1>(&mms, shape, UpdateScheme::Usl, n, 0.2)?
                    } else {
                        run_mms::<2>(&mms, shape, UpdateScheme::Usl, n, 0.2)?
                    };
                    points.push(point(&m));
                }
                series.push(Series::new(
                    format!("{dim}D {label} A={amplitude:e}"),
                    "max_t RMS displacement error / A".to_string(),
                    points,
                ));
            }
        }
    }
    Ok(StudyResult {
        study: "mpm_mms_axis_aligned".into(),
        h_axis: "cell size h = 1/N (nondimensional) [-]".into(),
        error_axis: "max_t RMS displacement error / A [-]".into(),
        series,
        notes: vec![
            "u_i = A sin(pi X_i) sin(c pi t + phi_i), phi = (0, pi), unit domain, roller faces, \
             neo-Hookean E = 1e4, nu = 0.3, rho0 = 1, c = sqrt(E/rho0); manufactured body force; \
             2 particles per cell per direction; USL, FLIP; dt = 0.2 h / c_p; one period t = 2/c."
                .into(),
        ],
    })
}
