//! Coupled MPM-ICE (Guilkey Sec. 3.3): conservation-law and exact-solution
//! checks of the explicit step.

use mpmice::diagnostics::coupled::block_in_air;

/// Largest fluid speed and largest particle speed.
fn speeds(run: &mpmice::coupling::CoupledRun<2>) -> (f64, f64) {
    let air = &run.fluid.cells[0];
    let uf = run
        .fluid
        .layout
        .interior
        .iter()
        .map(|&c| air.velocity[c].norm())
        .fold(0.0, f64::max);
    let up = run.particles.v.iter().map(|v| v.norm()).fold(0.0, f64::max);
    (uf, up)
}

/// Largest relative deviation of the cell pressure from `p0`.
fn pressure_dev(run: &mpmice::coupling::CoupledRun<2>, p0: f64) -> f64 {
    run.fluid
        .layout
        .interior
        .iter()
        .map(|&c| ((run.fluid.pressure[c] - p0) / p0).abs())
        .fold(0.0, f64::max)
}

#[test]
fn solid_at_rest_in_still_gas_stays_at_rest() {
    let mut run = block_in_air(20, [0.3, 0.3], [0.7, 0.65], [0.0; 2], [0.0; 2], false).unwrap();
    for _ in 0..200 {
        run.step(f64::INFINITY).unwrap();
    }
    let (uf, up) = speeds(&run);
    let dp = pressure_dev(&run, 101_325.0);
    eprintln!("t = {:e}, fluid {uf:e}, particles {up:e}, dp {dp:e}", run.fluid.time);
    assert!(uf < 1e-9 && up < 1e-9, "spurious currents: fluid {uf:e}, particles {up:e}");
    assert!(dp < 1e-12, "pressure changed by {dp:e}");
}

/// Zhang Sec. 3: a solid block translating through air at the air's
/// velocity produces no pressure change, over ten cell crossings.
fn translating_block(rigid: bool) {
    let u = [100.0, 0.0];
    let mut run = block_in_air(20, [0.1, 0.4], [0.3, 0.6], u, u, rigid).unwrap();
    let x0 = run.particles.x[0][0];
    while run.fluid.time < 5e-3 {
        run.step(5e-3 - run.fluid.time).unwrap();
    }
    let moved = (run.particles.x[0][0] - x0) / 0.05;
    let dp = pressure_dev(&run, 101_325.0);
    let air = &run.fluid.cells[0];
    let du = run
        .fluid
        .layout
        .interior
        .iter()
        .map(|&c| (air.velocity[c] - nalgebra::SVector::<f64, 2>::from(u)).norm())
        .fold(0.0, f64::max);
    eprintln!("rigid {rigid}: {} steps, moved {moved} cells, dp {dp:e}, du {du:e}", run.steps);
    assert!(moved > 9.99, "moved {moved} cells");
    assert!(dp < 1e-10, "relative pressure change {dp:e}");
    assert!(du < 1e-8 * 100.0, "velocity change {du:e}");
}

#[test]
fn block_translating_with_the_air_keeps_the_pressure_deformable() {
    translating_block(false);
}

#[test]
fn block_translating_with_the_air_keeps_the_pressure_rigid() {
    translating_block(true);
}
