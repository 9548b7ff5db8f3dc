//! The 1D elastic bar, fixed at x = 0 and free at x = L, in its first mode:
//! u = (v₀/ω) sin(πx/2L) sin(ωt). Error and energy drift over one period.

use mpmice::diagnostics::mms::{run_bar, BarMode1};
use mpmice::mpm::UpdateScheme;
use mpmice::shape::ShapeKind;

const BAR: BarMode1 = BarMode1 {
    length: 1.0,
    youngs: 100.0,
    rho: 1.0,
    v0: 1e-3,
    damping: 0.0,
};

#[test]
fn bar_mode_one_converges_at_second_order_and_conserves_energy() {
    // (shape, error bound at N = 32 (measured 1.4e-3 … 3.6e-3), energy bound)
    for (shape, bound) in [
        (ShapeKind::Linear, 1.6e-3),
        (ShapeKind::Gimp, 1.6e-3),
        (ShapeKind::QuadraticBspline, 3.1e-3),
        (ShapeKind::CubicBspline, 3.9e-3),
        (ShapeKind::QuadraticBsplineGimp, 3.1e-3),
    ] {
        let a = run_bar(&BAR, shape, UpdateScheme::Usl, 16, 0.2).expect("run");
        let b = run_bar(&BAR, shape, UpdateScheme::Usl, 32, 0.2).expect("run");
        let p = (a.error / b.error).ln() / 2f64.ln();
        assert!(p > 1.9, "{shape:?}: order {p}");
        assert!(b.error < bound, "{shape:?}: error {}", b.error);
        // Energy drift over a period shrinks with h (measured ~1e-4 at N = 32).
        assert!(
            b.energy_drift.abs() < 1.5e-4,
            "{shape:?}: drift {}",
            b.energy_drift
        );
        assert!(b.energy_drift.abs() < a.energy_drift.abs() / 4.0);
    }
}

#[test]
fn usl_and_musl_converge_at_second_order_on_the_bar() {
    for scheme in [UpdateScheme::Usl, UpdateScheme::Musl] {
        let a = run_bar(&BAR, ShapeKind::Gimp, scheme, 16, 0.2).expect("run");
        let b = run_bar(&BAR, ShapeKind::Gimp, scheme, 32, 0.2).expect("run");
        let p = (a.error / b.error).ln() / 2f64.ln();
        assert!(p > 1.8, "{scheme:?}: order {p} ({} → {})", a.error, b.error);
        assert!(b.error < 1.6e-3, "{scheme:?}: error {}", b.error);
    }
}

/// USF computes the stress from the P2G velocity of the start of the step,
/// half a step behind the staggered velocity USL uses: its error is O(Δt)
/// (measured at N = 32: 1.31e-2, 6.20e-3, 2.75e-3, 1.45e-3 for CFL 0.2, 0.1,
/// 0.05, 0.025) and meets USL's spatial error (1.46e-3) as Δt → 0.
#[test]
fn usf_error_is_first_order_in_time() {
    let run = |scheme, cfl| {
        run_bar(&BAR, ShapeKind::Gimp, scheme, 32, cfl)
            .expect("run")
            .error
    };
    let (e1, e2) = (run(UpdateScheme::Usf, 0.2), run(UpdateScheme::Usf, 0.1));
    let ratio = e1 / e2;
    assert!(ratio > 1.8 && ratio < 2.4, "USF Δt ratio {ratio}");
    let fine = run(UpdateScheme::Usf, 0.025);
    let usl = run(UpdateScheme::Usl, 0.025);
    assert!((fine - usl).abs() < 0.05 * usl, "USF {fine} vs USL {usl}");
}

/// Mass-proportional damping (`mpm.damping`) against the exact damped mode
/// u = (v₀/ω_d) e^(−αt/2) sin(ω_d t) sin(πx/2L): converges with h, and the
/// energy decays like the exact e^(−αt) envelope.
#[test]
fn damped_bar_matches_the_exact_damped_mode() {
    let bar = BarMode1 {
        damping: 2.0, // ω = 5π ≈ 15.7 rad/s: damping ratio 0.064
        ..BAR
    };
    let a = run_bar(&bar, ShapeKind::Gimp, UpdateScheme::Usl, 16, 0.2).expect("run");
    let b = run_bar(&bar, ShapeKind::Gimp, UpdateScheme::Usl, 32, 0.2).expect("run");
    let p = (a.error / b.error).ln() / 2f64.ln();
    eprintln!(
        "damped bar: error {:.3e} → {:.3e}, order {p:.3}, energy change {:.4}",
        a.error, b.error, b.energy_drift
    );
    assert!(p > 1.8, "damped order {p} ({} → {})", a.error, b.error);
    assert!(b.error < 1.1e-3, "damped error {}", b.error); // measured 9.83e-4
                                                           // Over one period 4L/c = 0.4 s the energy falls to about e^(−αt) = e^(−0.8)
                                                           // (the exact modal energy at t = T is that times a factor within 1 % of 1).
    let expected = (-2.0f64 * 0.4).exp() - 1.0;
    assert!(
        (b.energy_drift - expected).abs() < 0.02,
        "energy change {} vs {expected}",
        b.energy_drift
    );
}
