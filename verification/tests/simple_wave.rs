//! The finite-amplitude simple wave of `ice_simple_wave` at `ε = 0.1`
//! (`t = 0.5`, shock time 1.33) with the acoustic Hancock variant, N = 64
//! and 128: a regression bound on the error and on the observed order.
//!
//! Measured (release): L1/ε = 2.5809e-2 (N = 64), 1.3454e-2 (N = 128),
//! order 0.94. The variant is first order here, not second: its Δp weight
//! switch (`WEIGHT_SWITCH_SCALE = 1e-3` on `|Δp|/p_eq`) is saturated on
//! this wave at every N ≤ 512, so the wave runs at the shock weights
//! (1 in compression, 0.4 in expansion); Hancock gives 3.4673e-3 and
//! 1.2242e-3 (order 1.50). The bounds are the measured values with 20 %
//! margin on the error and 0.09 on the order; they guard against a
//! regression and must be tightened when the switch is fixed.

use mpmice::ice::{IceBoundary, IceParams};
use verification::ice_studies::simple_wave_run;

#[test]
fn acoustic_hancock_simple_wave_eps_0_1() {
    let params = IceParams::hancock_acoustic([[IceBoundary::Periodic, IceBoundary::Periodic]]);
    let (e64, _, _) = simple_wave_run(&params, 0.1, 0.5, 64).unwrap();
    let (e128, steps, _) = simple_wave_run(&params, 0.1, 0.5, 128).unwrap();
    let order = (e64 / e128).log2();
    eprintln!("L1/eps N = 64: {e64:.4e}, N = 128: {e128:.4e} ({steps} steps), order {order:.3}");
    assert!(e128 <= 1.2 * 1.3454e-2, "L1/eps at N = 128: {e128:.4e}");
    assert!(order >= 0.85, "observed order {order:.3}");
}
