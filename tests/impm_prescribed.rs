//! Quasistatic loading by prescribed displacement (a rigid grip) in the
//! implicit MPM, against the exact uniaxial-strain solution of a neo-Hookean
//! bar (see `diagnostics::impm::GripBar`): stretch and compression over
//! several load steps with GIMP, one step with the linear hat, modified
//! Newton, the scene route (`[[implicit.prescribed]]`) and its bad input.

use mpmice::diagnostics::impm::{GripBar, GripMeasured};
use mpmice::error::Error;
use mpmice::shape::ShapeKind;

fn assert_exact(m: &GripMeasured, what: &str) {
    eprintln!(
        "{what}: F {:.2e}, σ_yy {:.2e}, σ_xx {:.2e}, reaction {:.2e}, grip {:.2e}, \
         Newton per step {:?}",
        m.f_error,
        m.syy_error,
        m.sxx_error,
        m.reaction_error,
        m.grip_error,
        m.measured
            .stats
            .iter()
            .map(|s| s.newton_iterations)
            .collect::<Vec<_>>()
    );
    // Exact to round-off (the Newton tolerance is 1e-9 on ‖δu‖/‖u‖, and
    // Newton converges quadratically, so the last iterate is far below it).
    assert!(m.f_error < 1e-10, "{what}: F error {}", m.f_error);
    assert!(m.syy_error < 1e-10, "{what}: σ_yy error {}", m.syy_error);
    assert!(m.sxx_error < 1e-10, "{what}: σ_xx error {}", m.sxx_error);
    assert!(
        m.reaction_error < 1e-10,
        "{what}: reaction error {}",
        m.reaction_error
    );
    assert!(m.grip_error < 1e-12, "{what}: grip error {}", m.grip_error);
}

#[test]
fn gimp_grip_stretch_and_compression_are_exact_over_load_steps() {
    let bar = GripBar::standard();
    let m = bar.run(ShapeKind::Gimp, 1.0).unwrap();
    assert_eq!(m.measured.steps, 4);
    assert_exact(&m, "GIMP stretch s = 1.5");
    // Large deformation, quadratic Newton: a handful of iterations per step.
    assert!(m.measured.stats.iter().all(|s| s.newton_iterations <= 6));
    let squeeze = GripBar {
        displacement_cells: -4.0,
        ..bar
    };
    let m = squeeze.run(ShapeKind::Gimp, 0.5).unwrap();
    assert_exact(&m, "GIMP compression s = 0.5");
}

#[test]
fn linear_hat_grip_is_exact_in_one_load_step() {
    let bar = GripBar {
        displacement_cells: 2.0,
        load_steps: 1,
        ..GripBar::standard()
    };
    let m = bar.run(ShapeKind::Linear, 1.0).unwrap();
    assert_exact(&m, "linear hat one step s = 1.25");
}

#[test]
fn modified_newton_reaches_the_exact_grip_solution() {
    let bar = GripBar::standard();
    let mut run = bar.build(ShapeKind::Gimp, 1.0).unwrap();
    run.params.modified_newton = true;
    let m = bar.measure(run, 1.0).unwrap();
    assert_exact(&m, "GIMP stretch, modified Newton");
}

fn scene_text() -> String {
    let path = format!("{}/cases/bar_stretch_impm.toml", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(path).unwrap()
}

#[test]
fn grip_scene_matches_the_exact_solution() {
    let s = mpmice::scene::parse(&scene_text()).expect("valid scene");
    let mut run = mpmice::scene::build_implicit_run::<2>(&s).expect("build");
    run.run().expect("run");
    let bar = GripBar::standard();
    let (sxx, syy) = bar.exact_stress(1.5);
    let p = &run.particles;
    let mut worst = 0.0f64;
    for i in 0..p.len() {
        if p.x0[i][1] < 8.0 {
            worst = worst
                .max((p.stress.get(i)[(1, 1)] - syy).abs() / syy)
                .max((p.stress.get(i)[(0, 0)] - sxx).abs() / syy);
        } else {
            assert!((p.x[i][1] - p.x0[i][1] - 4.0).abs() < 1e-12);
        }
    }
    assert!(worst < 1e-10, "stress error {worst}");
    let last = run.stats.last().unwrap();
    assert!((last.reactions[0][1] - syy).abs() < 1e-10 * syy);
    assert_eq!(run.steps, 4);
}

#[test]
fn grip_scene_bad_input_names_the_key() {
    let text = scene_text();
    let cases: [(&str, &str, &str); 6] = [
        ("object = 0", "object = 3", "implicit.prescribed[0].object"),
        (
            "displacement = [0.0, 4.0]",
            "displacement = [0.0, 4.0, 1.0]",
            "implicit.prescribed[0].displacement",
        ),
        (
            "components = [false, true]",
            "components = [false, false]",
            "implicit.prescribed[0].components",
        ),
        (
            "lower = [0.0, 8.0], upper = [1.0, 10.0]",
            "lower = [0.0, 8.0], upper = [1.0, 7.0]",
            "implicit.prescribed[0].region.upper[1]",
        ),
        (
            "max_cell_fraction = 1.5",
            "max_cell_fraction = 0.0",
            "implicit.max_cell_fraction",
        ),
        (
            "mode = \"implicit\"",
            "mode = \"explicit\"",
            "implicit.prescribed[0]",
        ),
    ];
    for (from, to, key) in cases {
        assert!(text.contains(from), "{from}");
        match mpmice::scene::parse(&text.replace(from, to)) {
            Err(e) => assert_eq!(e.path, key, "{to}: {e}"),
            Ok(_) => panic!("{to}: accepted"),
        }
    }
    // A region that holds no particle of the object: rejected when built.
    let s = mpmice::scene::parse(&text.replace(
        "lower = [0.0, 8.0], upper = [1.0, 10.0]",
        "lower = [0.0, 12.0], upper = [1.0, 14.0]",
    ))
    .expect("valid schema");
    match mpmice::scene::build_implicit_run::<2>(&s) {
        Err(Error::Scene(e)) => assert_eq!(e.path, "implicit.prescribed[0].region"),
        other => panic!("expected a scene error, got {:?}", other.err()),
    }
    // Two grips sharing grid nodes with different displacements: the run
    // stops at once, naming the second grip, and the particles stay put.
    let two = text.replace(
        "region = { type = \"box\", lower = [0.0, 8.0], upper = [1.0, 10.0] }",
        "region = { type = \"box\", lower = [0.0, 8.0], upper = [1.0, 9.0] }\n\n\
         [[implicit.prescribed]]\nobject = 0\ndisplacement = [0.0, 2.0]\n\
         region = { type = \"box\", lower = [0.0, 9.0], upper = [1.0, 10.0] }",
    );
    let s = mpmice::scene::parse(&two).expect("valid schema");
    let mut run = mpmice::scene::build_implicit_run::<2>(&s).expect("build");
    let before = run.particles.x.clone();
    match run.step() {
        Err(Error::Scene(e)) => assert_eq!(e.path, "implicit.prescribed[1]", "{e}"),
        other => panic!("expected a scene error, got {other:?}"),
    }
    assert_eq!(run.particles.x, before);
}

#[test]
fn newton_with_a_grip_and_gravity_converges_quadratically() {
    // Gripped bar pulled up under its own weight (g = 10: the weight of the
    // gauge is a quarter of the grip force): the solution is no longer
    // linear, so Newton iterates after the lifted first solve.
    use mpmice::mpm::explicit::Uniform;
    use nalgebra::SVector;
    let bar = GripBar::standard();
    let mut run = bar.build(ShapeKind::Gimp, 1.0).unwrap();
    run.body = Some(Box::new(Uniform(SVector::from([0.0, -10.0]))));
    run.run().unwrap();
    for s in &run.stats {
        let r = &s.residuals;
        eprintln!("t = {}: {r:?}, reaction {:?}", s.t, s.reactions[0]);
        assert!(s.newton_iterations >= 2, "{r:?}");
        // Quadratic: (r_{k+1}/r₀)/(r_k/r₀)² bounded while above round-off
        // (measured ≤ 7.0e-3; e.g. 4677 → 888 → 1.18 → 8.8e-7 → 2.6e-10).
        for k in 1..r.len() - 1 {
            if r[k + 1] > 1e-10 * r[0] {
                let q = (r[k + 1] / r[0]) / (r[k] / r[0]).powi(2);
                assert!(q < 2e-2, "ratio {q} in {r:?}");
            }
        }
        assert!(r[r.len() - 1] < 1e-12 * r[0], "{r:?}");
        // The grip pulls (measured 1.66e5 … 5.36e5 over the steps).
        assert!(s.reactions[0][1] > 0.0);
    }
}

/// Kirchhoff (τ_yy, τ_xx) of Hencky + J2 (linear hardening) in uniaxial
/// strain at logarithmic strain `e` on monotone loading, and ε̄
/// (`UniaxialStrainResponse` in the logarithmic strain).
fn hencky_uniaxial(e: f64, young: f64, nu: f64, sy: f64, h: f64) -> (f64, f64, f64) {
    mpmice::material::plasticity::UniaxialStrainResponse {
        bulk: young / (3.0 * (1.0 - 2.0 * nu)),
        mu: young / (2.0 * (1.0 + nu)),
        yield_stress: sy,
        hardening: h,
    }
    .at(e, None)
}

/// The elastic-plastic bar (`cases/bar_stretch_plastic_impm.toml`) through
/// the scene: stretched to s = 1.5 and squeezed to s = 0.5, the gauge's
/// stress, plastic strain and the grip's reaction equal the closed form to
/// round-off after four load steps, and Newton with the consistent tangent
/// converges quadratically (a handful of iterations, residual ratios
/// r_{k+1}/r_k² bounded).
#[test]
fn plastic_grip_scene_matches_the_closed_form() {
    let path = format!(
        "{}/cases/bar_stretch_plastic_impm.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(path).unwrap();
    // The last run drops the plasticity table: Hencky hyperelastic.
    for (disp, s_exact, sy) in [("4.0", 1.5, 2e4), ("-4.0", 0.5, 2e4), ("4.0", 1.5, 1e30)] {
        let mut t = text.replace(
            "displacement = [0.0, 4.0]",
            &format!("displacement = [0.0, {disp}]"),
        );
        if sy > 1e20 {
            t = t.replace(
                "plasticity = { flow = \"linear\", yield_stress = 2e4, hardening_modulus = 1e5 }",
                "",
            );
        }
        let sc = mpmice::scene::parse(&t).expect("valid scene");
        let mut run = mpmice::scene::build_implicit_run::<2>(&sc).expect("build");
        run.run().expect("run");
        let (tyy, txx, eb) = hencky_uniaxial(f64::ln(s_exact), 1e6, 0.3, sy, 1e5);
        let (syy, sxx) = (tyy / s_exact, txx / s_exact);
        // Work per unit reference volume ∫ τ_yy de over the path (τ_yy is
        // piecewise linear in e: elastic, then hardening; Simpson per piece
        // is exact).
        let e_end = f64::ln(s_exact);
        let ey = (sy / (2.0 * 1e6 / 2.6)).min(1.0) * e_end.signum();
        let simpson = |a: f64, b: f64| {
            let f = |e: f64| hencky_uniaxial(e, 1e6, 0.3, sy, 1e5).0;
            (b - a) / 6.0 * (f(a) + 4.0 * f(0.5 * (a + b)) + f(b))
        };
        let work_exact = simpson(0.0, ey) + simpson(ey, e_end);
        let p = &run.particles;
        let mut worst = 0.0f64;
        let mut gauge = 0;
        for i in 0..p.len() {
            if p.x0[i][1] < 8.0 {
                gauge += 1;
                let st = p.stress.get(i);
                worst = worst
                    .max((st[(1, 1)] - syy).abs() / 2e4)
                    .max((st[(0, 0)] - sxx).abs() / 2e4)
                    .max((st[(2, 2)] - sxx).abs() / 2e4)
                    .max(
                        (p.plastic_strain.get(i).copied().unwrap_or(0.0) - eb).abs()
                            / eb.max(1e-300),
                    )
                    .max((p.work_of(i) - work_exact).abs() / work_exact);
            }
        }
        let last = run.stats.last().unwrap();
        let reaction = (last.reactions[0][1] - syy).abs() / 2e4;
        let iters: Vec<usize> = run.stats.iter().map(|s| s.newton_iterations).collect();
        eprintln!(
            "Hencky (σ₀ {sy:e}) grip s = {s_exact}: ε̄ {eb:.4}, σ_yy {syy:.6e}, work {work_exact:.6e}; \
             worst error {worst:.2e} (of σ₀, ε̄, work), reaction {reaction:.2e}; Newton per step {iters:?}; last step's \
             residuals {:?}",
            last.residuals
        );
        assert!(gauge > 0);
        assert!(worst < 1e-9, "s = {s_exact}: error {worst:e}");
        assert!(
            reaction < 1e-9,
            "s = {s_exact}: reaction error {reaction:e}"
        );
        assert_eq!(run.steps, 4);
        assert!(iters.iter().all(|&k| k <= 6), "{iters:?}");
        // Quadratic: r_{k+1} ≤ C r_k² with a small C on every step's
        // iterates above round-off (a linearly converging Newton, e.g. with
        // the elastic tangent, has r_{k+1}/r_k² growing as r_k falls).
        for st in &run.stats {
            for w in st.residuals.windows(2).skip(1) {
                if w[1] > 1e-8 {
                    assert!(w[1] / (w[0] * w[0]) < 1e-4, "{:?}", st.residuals);
                }
            }
        }
    }
}

/// The plastic grip bar in 3D (one cell in x and z, rollers on the four
/// sides): the same closed form, through the 3D tangent assembly.
#[test]
fn plastic_grip_scene_in_3d_matches_the_closed_form() {
    let path = format!(
        "{}/cases/bar_stretch_plastic_impm.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let t = std::fs::read_to_string(path)
        .unwrap()
        .replace("dim = 2", "dim = 3")
        .replace(
            "lower = [0.0, 0.0]\nupper = [1.0, 16.0]",
            "lower = [0.0, 0.0, 0.0]\nupper = [1.0, 16.0, 1.0]",
        )
        .replace("cells = [1, 16]", "cells = [1, 16, 1]")
        .replace(
            "y_upper = \"free\" }",
            "y_upper = \"free\", z_lower = \"symmetry\", z_upper = \"symmetry\" }",
        )
        .replace(
            "displacement = [0.0, 4.0]",
            "displacement = [0.0, 4.0, 0.0]",
        )
        .replace(
            "components = [false, true]",
            "components = [false, true, false]",
        )
        .replace(
            "region = { type = \"box\", lower = [0.0, 8.0], upper = [1.0, 10.0] }",
            "region = { type = \"box\", lower = [0.0, 8.0, 0.0], upper = [1.0, 10.0, 1.0] }",
        )
        .replace(
            "geometry = { type = \"box\", lower = [0.0, 0.0], upper = [1.0, 10.0] }",
            "geometry = { type = \"box\", lower = [0.0, 0.0, 0.0], upper = [1.0, 10.0, 1.0] }",
        );
    let sc = mpmice::scene::parse(&t).expect("valid 3D scene");
    let mut run = mpmice::scene::build_implicit_run::<3>(&sc).expect("build");
    run.run().expect("run");
    let (tyy, txx, eb) = hencky_uniaxial(f64::ln(1.5), 1e6, 0.3, 2e4, 1e5);
    let (syy, sxx) = (tyy / 1.5, txx / 1.5);
    let p = &run.particles;
    let mut worst = 0.0f64;
    for i in 0..p.len() {
        if p.x0[i][1] < 8.0 {
            let st = p.stress.get(i);
            worst = worst
                .max((st[(1, 1)] - syy).abs() / 2e4)
                .max((st[(0, 0)] - sxx).abs() / 2e4)
                .max((st[(2, 2)] - sxx).abs() / 2e4)
                .max((p.plastic_strain[i] - eb).abs() / eb);
        }
    }
    let iters: Vec<usize> = run.stats.iter().map(|s| s.newton_iterations).collect();
    eprintln!("3D Hencky + J2 grip s = 1.5: worst error {worst:.2e}; Newton per step {iters:?}");
    assert!(worst < 1e-9, "{worst:e}");
    assert_eq!(run.steps, 4);
}
