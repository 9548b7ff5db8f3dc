//! `mpmice study` on a user's scene (issue 23): the same machinery as the
//! built-in studies, against an exact reference and against the finest run.

use mpmice::scene::Override;
use mpmice::study::{run_study, Reference, StudySpec};

const SOD: &str = include_str!("../../cases/sod.toml");

fn spec(reference: Reference) -> StudySpec {
    StudySpec {
        name: "user_sod".into(),
        refine: 2,
        field: Some("cells.mixture_density".into()),
        reference,
        quantity: None,
        sweep: None,
    }
}

fn out(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("user-study-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// `cases/sod.toml` from 100 cells, refined twice, against the exact
/// Riemann solution, gives the built-in `ice_sod --quick` high-resolution
/// series: the same errors (the same scheme, N = 100, 200, 400, the same
/// norm) and so its order to well within 0.1 (measured: 0.9753 both). The
/// snapshots are left out (`output.interval` = the end time): the run loop
/// lands a step on every snapshot time, which the built-in loop does not
/// (with the case's four snapshots: order 0.9759, errors within 0.1 %).
#[test]
fn sod_study_from_the_scene_matches_the_built_in_study() {
    let set = [
        Override::parse("grid.cells=[100]").unwrap(),
        Override::parse("output.interval=0.2").unwrap(),
    ];
    let dir = out("riemann");
    let r = run_study(SOD, &set, &spec(Reference::Riemann), &dir, 2, &mut |_| {}).unwrap();
    let user = &r.series[0];
    let builtin = verification::ice_studies::ice_sod(true).unwrap();
    let hr = builtin
        .series
        .iter()
        .find(|s| s.label.starts_with("high resolution (MUSCL"))
        .expect("high-resolution series");
    eprintln!(
        "user order {:.4}, built-in {:.4}",
        user.observed_order, hr.observed_order
    );
    assert!((user.observed_order - hr.observed_order).abs() < 0.1);
    // The plot's axes: the refined cell size, and the field's norm,
    // reference and unit (from the runs' output).
    assert_eq!(r.h_axis, "cell size Δx [m]");
    assert_eq!(
        r.error_axis,
        "L1 cell-mean error of cells.mixture_density vs exact Riemann [kg/m^3]"
    );
    for (a, b) in user.points.iter().zip(&hr.points) {
        assert_eq!(a.h, b.h);
        assert!((a.error - b.error).abs() <= 1e-9 * b.error, "{a:?} {b:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Against the finest run, level k's error differs from its exact error by
/// at most the finest run's exact error: the triangle inequality, with the
/// restriction (averaging over the coarser cells) an L1 contraction that
/// maps the finest grid's exact cell averages to the coarser grid's.
#[test]
fn finest_run_reference_is_within_the_finest_error_of_the_exact_one() {
    let set = [Override::parse("grid.cells=[100]").unwrap()];
    let (d1, d2) = (out("exact"), out("finest"));
    let exact = run_study(SOD, &set, &spec(Reference::Riemann), &d1, 2, &mut |_| {}).unwrap();
    let finest = run_study(SOD, &set, &spec(Reference::Finest), &d2, 2, &mut |_| {}).unwrap();
    let (e, f) = (&exact.series[0].points, &finest.series[0].points);
    assert_eq!(f.len(), 2);
    let e_n = e[2].error;
    for k in 0..2 {
        let gap = (f[k].error - e[k].error).abs();
        eprintln!(
            "h {:.4e}: vs finest {:.4e}, vs exact {:.4e}, gap {gap:.3e} <= {e_n:.3e}",
            f[k].h, f[k].error, e[k].error
        );
        assert!(gap <= e_n * (1.0 + 1e-9), "level {k}: {gap:e} > {e_n:e}");
    }
    // Each run's outputs are kept.
    assert!(d2.join("series_0/level_2/summary.json").is_file());
    let _ = std::fs::remove_dir_all(&d1);
    let _ = std::fs::remove_dir_all(&d2);
}

/// A sweep gives one series per value, each with its own scene.
#[test]
fn a_sweep_gives_a_series_per_value() {
    let set = [
        Override::parse("grid.cells=[50]").unwrap(),
        Override::parse("time.end=0.1").unwrap(),
    ];
    let mut s = spec(Reference::Riemann);
    s.refine = 1;
    s.sweep = Some((
        "fluid.variant".into(),
        vec!["literal".into(), "high_resolution".into()],
    ));
    let dir = out("sweep");
    let r = run_study(SOD, &set, &s, &dir, 2, &mut |_| {}).unwrap();
    assert_eq!(r.series.len(), 2);
    assert!(r.series[0].label.contains("fluid.variant=literal"));
    // The literal scheme (first-order advection) is the less accurate one.
    assert!(r.series[0].points[1].error > r.series[1].points[1].error);
    let bad = spec(Reference::Riemann);
    let bad = StudySpec {
        sweep: Some(("fluid.variant".into(), vec!["nonsense".into()])),
        ..bad
    };
    let e = run_study(SOD, &set, &bad, &dir, 2, &mut |_| {}).unwrap_err();
    assert!(format!("{e:#}").contains("fluid.variant"), "{e:#}");
    let _ = std::fs::remove_dir_all(&dir);
}
