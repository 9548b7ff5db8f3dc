//! Zhang's multiphase formulation beside Guilkey's MPM-ICE on the same
//! scenes (issue 19; `mpmice::diagnostics::formulations`, the case files
//! `cases/zhang_vs_guilkey_block_*.toml` and
//! `cases/shock_on_steel_block_*.toml`), coarse versions of the
//! `zhang_vs_guilkey` study.

use mpmice::diagnostics::formulations::{
    run_block, run_shock, shock_exact, shock_window, BlockCase, Formulation, ShockCase, P1,
};

/// The block test at 20 cells, 10 cell crossings diagonally. Exact: nothing
/// changes. Zhang's weak constraint (Eq. 18) keeps it to round-off (measured
/// 1.8e-14 in pressure, 2.4e-13 in velocity); Guilkey's MPM-ICE changes
/// the air pressure by 2.6e-5 of p1 and the velocities by 5.7e-4 of the
/// speed (the disk's edge crossing cells diagonally): its bounds are those
/// measurements with a factor of about 4, so a change of the coupled path
/// that makes it worse shows here.
#[test]
fn block_test_weak_constraint_keeps_the_air_guilkey_changes_it_a_little() {
    let case = |formulation| BlockCase {
        formulation,
        cells: 20,
        constraint: "weak",
        shape: "gimp",
        end: 0.05,
    };
    let m = run_block(&case(Formulation::Multiphase)).unwrap();
    let c = run_block(&case(Formulation::Coupled)).unwrap();
    eprintln!(
        "multiphase: dp/p1 {:.3e}, dv/|u| {:.3e}, {} steps; coupled: dp/p1 {:.3e}, dv/|u| {:.3e}, {} steps, pressure share {:?}",
        m.pressure, m.velocity, m.cost.steps, c.pressure, c.velocity, c.cost.steps, c.cost.pressure_share
    );
    assert!(m.completed && c.completed);
    assert!(m.pressure < 1e-10, "multiphase dp/p1 = {:e}", m.pressure);
    assert!(m.velocity < 1e-10, "multiphase dv/|u| = {:e}", m.velocity);
    assert!(
        c.pressure.is_finite() && c.pressure < 1e-4,
        "coupled dp/p1 = {:e}",
        c.pressure
    );
    assert!(
        c.velocity.is_finite() && c.velocity < 2e-3,
        "coupled dv/|u| = {:e}",
        c.velocity
    );
    // The pressure share is a share.
    let share = c.cost.pressure_share.unwrap();
    assert!(share > 0.0 && share < 1.0, "pressure share {share}");
    assert!(m.cost.pressure_share.is_none());
}

/// A Mach 1.5 shock on a steel block, MPM-ICE at h = 1 cm (10 cells over
/// the half height), multiphase at h = 1 and 0.5 cm. The probe 2 cm in
/// front of the face, averaged over 0.1–0.2 ms after the hit, must read the
/// exact 1D reflected-shock pressure p5 = 5.425 p1 within 5 % (measured:
/// 3.1 % low MPM-ICE, whose probe rings by ±30 % about it; multiphase 8.4 %
/// low at 1 cm, 3.1 % at 0.5 cm and 0.8 % at 0.25 cm in the study, so the
/// multiphase bound applies at 0.5 cm, and its error must fall with h). By
/// 0.2 ms after the hit the block's momentum must lie within 15 % of the 1D
/// value (p5 − p1) b (t − t_hit) (measured: 1.11 MPM-ICE, 0.90 and 0.90
/// multiphase: the smeared shock loads the face early, the corner's
/// diffraction unloads it). Until 0.15 ms the closed box's x-momentum must
/// follow the walls' exact impulse (p4 − p1) H t (measured: within 3.0e-4
/// MPM-ICE; multiphase 1.2e-4 at 1 cm, 4.5e-7 at 0.5 cm, where it was
/// 8.8e-3 at 1 cm before the mixture's pressure force on the sampling
/// error of Σθ was made conservative).
#[test]
fn shock_on_steel_block_reflects_at_the_1d_pressure() {
    let e = shock_exact();
    let mut multiphase_errors = Vec::new();
    for (f, cells, front, balance) in [
        (Formulation::Multiphase, 50, 0.1, 1e-3),
        (Formulation::Multiphase, 100, 0.05, 1e-5),
        (Formulation::Coupled, 50, 0.05, 1e-3),
    ] {
        let r = run_shock(&ShockCase {
            formulation: f,
            cells,
            end: shock_window().1 + 1e-5,
        })
        .unwrap();
        eprintln!(
            "{} at {cells} cells: front p/p5 {:.4} (p2/p1 {:.4}, p5/p1 {:.4}), momentum / 1D {:.4}, momentum balance {:.3e}, {} steps, {:.3e} s/step, pressure share {:?}",
            f.name(),
            r.front_pressure / e.p5,
            e.p2 / P1,
            e.p5 / P1,
            r.momentum_ratio(),
            r.momentum_balance_error(),
            r.cost.steps,
            r.cost.median_step_s,
            r.cost.pressure_share
        );
        assert!(r.front_error() < front, "{}: {}", f.name(), r.front_error());
        if f == Formulation::Multiphase {
            multiphase_errors.push(r.front_error());
        }
        let ratio = r.momentum_ratio();
        assert!((ratio - 1.0).abs() < 0.15, "{}: {ratio}", f.name());
        let b = r.momentum_balance_error();
        assert!(b < balance, "{}: momentum balance {b:e}", f.name());
    }
    assert!(
        multiphase_errors[1] < 0.5 * multiphase_errors[0],
        "multiphase front errors {multiphase_errors:?} do not fall with h"
    );
}
