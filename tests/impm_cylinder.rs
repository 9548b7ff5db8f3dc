//! The pressurised thick cylinder of Guilkey Sec. 4.1 as a solid-only
//! quasistatic implicit problem (pressure as a traction on the inner-surface
//! particles): Guilkey Eq. 43 and the Lamé radial displacement (Eq. 42).
//! Bounds are measured values with a small margin.

use mpmice::diagnostics::impm::Cylinder;
use mpmice::shape::ShapeKind;

#[test]
fn cylinder_eq43_error_and_lame_displacement_converge() {
    let cy = Cylinder::guilkey();
    let a = cy.run_implicit(ShapeKind::Linear, 0.025, 1).unwrap();
    let b = cy.run_implicit(ShapeKind::Linear, 0.0125, 1).unwrap();
    // Measured Eq. 43: 7.449e-2 → 3.886e-2 (order 0.94); u_r: 3.76e-3 → 1.36e-3.
    let p = (a.error / b.error).ln() / 2f64.ln();
    assert!(p > 0.9, "Eq. 43 order {p}");
    assert!(b.error < 3.95e-2, "Eq. 43 error {}", b.error);
    assert!(b.error2 < 1.4e-3, "u_r error {}", b.error2);
    assert!(
        a.error2 / b.error2 > 2.6,
        "u_r ratio {}",
        a.error2 / b.error2
    );
    // Nearly linear problem: Newton takes 3 iterations, residual drops 1e11.
    let s = &b.stats[0];
    assert_eq!(s.newton_iterations, 3, "{:?}", s.residuals);
    assert!(s.residuals[3] < 1e-10 * s.residuals[0], "{:?}", s.residuals);
    assert!(s.symbolic_rebuilt && !s.used_lu);
}

#[test]
fn pcg_and_load_steps_agree_with_the_direct_single_step() {
    let cy = Cylinder::guilkey();
    let direct = cy.run_implicit(ShapeKind::Linear, 0.05, 1).unwrap();
    let mut run = cy.build_implicit(ShapeKind::Linear, 0.05, 4).unwrap();
    run.params.linear = mpmice::mpm::LinearSolver::PcgJacobi {
        rel_tol: 1e-12,
        max_iter: 20000,
    };
    run.run().unwrap();
    let (e43, eu) = cy.errors(&run.particles);
    assert_eq!(run.steps, 4);
    assert!(run.stats.iter().all(|s| s.linear_iterations > 0));
    // Only the pattern of the first step is new (particles barely move).
    assert!(run.stats[1..].iter().all(|s| !s.symbolic_rebuilt));
    // Four load steps re-evaluate the weights at the moved particles, so they
    // differ slightly from one step (measured 0.13 % in Eq. 43).
    assert!(
        (e43 - direct.error).abs() < 3e-3 * direct.error,
        "{e43} vs {}",
        direct.error
    );
    // The u_r errors (relative to |u_r|) differ by 1.26e-4 (measured).
    assert!(
        (eu - direct.error2).abs() < 2e-4,
        "{eu} vs {}",
        direct.error2
    );
}

#[test]
fn modified_newton_reaches_the_same_solution() {
    let cy = Cylinder::guilkey();
    let full = cy.run_implicit(ShapeKind::Linear, 0.05, 1).unwrap();
    let mut run = cy.build_implicit(ShapeKind::Linear, 0.05, 1).unwrap();
    run.params.modified_newton = true;
    let m = cy.measure_implicit(run, 0.05).unwrap();
    // Measured: 4 iterations with one factorisation (full Newton: 3).
    assert_eq!(
        m.stats[0].newton_iterations, 4,
        "{:?}",
        m.stats[0].residuals
    );
    assert!((m.error - full.error).abs() < 1e-9 * full.error);
    assert!((m.error2 - full.error2).abs() < 1e-8 * full.error2);
}
