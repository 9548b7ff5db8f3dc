//! Tests of the ICE module against exact solutions and invariants.

use nalgebra::SVector;

use super::*;
use crate::diagnostics::riemann::{ExactRiemann, PrimitiveState};
use crate::material::eos::IdealGas;

fn gas(gamma: f64) -> IceMaterial {
    IceMaterial::new("gas", IdealGas::new(gamma, 1.0 / (gamma - 1.0)).unwrap())
}

/// L1 density error (mean over cells) of a 1D shock tube against the exact
/// Riemann solution.
pub(crate) fn shock_tube_l1(
    state: &IceState<1>,
    left: (f64, f64, f64),
    right: (f64, f64, f64),
    gamma: f64,
    x0: f64,
) -> f64 {
    let ex = ExactRiemann::solve(
        PrimitiveState::new(left.0, left.1, left.2),
        PrimitiveState::new(right.0, right.1, right.2),
        gamma,
    )
    .unwrap();
    ex.l1_density_error(state, x0).unwrap()
}

fn walls1() -> [[IceBoundary<1>; 2]; 1] {
    [[IceBoundary::Outflow, IceBoundary::Outflow]]
}

const SOD_L: (f64, f64, f64) = (1.0, 0.0, 1.0);
const SOD_R: (f64, f64, f64) = (0.125, 0.0, 0.1);

fn run_sod(n: usize, adv: Advection) -> (f64, FluidRun<1>) {
    let st = shock_tube(gas(1.4), n, SOD_L, SOD_R, 0.5).unwrap();
    let mut p = IceParams::new(walls1());
    p.advection = adv;
    let run = run_fluid(st, &p, 0.2, 100_000).unwrap();
    (shock_tube_l1(&run.state, SOD_L, SOD_R, 1.4, 0.5), run)
}

/// Sod at N = 200 against the exact solution. Measured L1(ρ): second
/// order 6.56e-3, first order 1.085e-2 (cfl 0.5, Guilkey Eq. 28 as written).
#[test]
fn sod_n200_matches_exact_solution() {
    let (e2, _) = run_sod(200, Advection::SecondOrder(Limiter::VanLeer));
    let (e1, _) = run_sod(200, Advection::FirstOrder);
    assert!(e2 < 6.9e-3, "second order L1 = {e2:e}");
    assert!(e1 < 1.15e-2, "first order L1 = {e1:e}");
    assert!(e2 < 0.7 * e1);
}

/// The Hancock variant ([`IceParams::hancock`]: MUSCL–Hancock face states,
/// cfl 0.8) on Sod at N = 400. Measured L1(ρ) 1.511e-3 in 240 steps
/// (1.607e-3 before the Lagrangian remap, when the bound was 1.65e-3; high
/// resolution at cfl 0.4 then: 1.467e-3 in 467 steps; without the
/// predictor at cfl 0.8 the error is 2.39e-3 and it grows with N).
#[test]
fn hancock_sod_n400_matches_exact_solution_at_cfl_08() {
    let st = shock_tube(gas(1.4), 400, SOD_L, SOD_R, 0.5).unwrap();
    let run = run_fluid(st, &IceParams::hancock(walls1()), 0.2, 100_000).unwrap();
    let e = shock_tube_l1(&run.state, SOD_L, SOD_R, 1.4, 0.5);
    assert!(e < 1.6e-3, "L1 = {e:e}");
    assert!(run.steps <= 245, "{} steps", run.steps);
}

/// The acoustic Hancock variant ([`IceParams::hancock_acoustic`]) on Sod
/// at N = 800 and 1600; at N = 1600 it is below the error of a Roe/MC
/// finite-volume code at the same resolution (3.1e-4). Measured L1(ρ)
/// 4.601e-4 in 403 steps and 2.635e-4 in 804 steps with the Lagrangian
/// remap (`lagrangian_remap`) and the shock-sensed expansion weight
/// (`EXPANSION_SENSOR_SCALE`; without either 5.418e-4 in 403 and 2.993e-4 in
/// 805 steps, when the bounds were 5.5e-4 and 3.1e-4; Hancock at cfl 0.8
/// then: 7.96e-4 in 481 steps, 4.48e-4 in 961).
#[test]
fn hancock_acoustic_sod_matches_roe_mc_at_n1600() {
    for (n, bound, max_steps) in [(800, 4.8e-4, 410), (1600, 2.8e-4, 815)] {
        let st = shock_tube(gas(1.4), n, SOD_L, SOD_R, 0.5).unwrap();
        let run = run_fluid(st, &IceParams::hancock_acoustic(walls1()), 0.2, 100_000).unwrap();
        let e = shock_tube_l1(&run.state, SOD_L, SOD_R, 1.4, 0.5);
        assert!(e < bound, "N = {n}: L1 = {e:e}");
        assert!(run.steps <= max_steps, "N = {n}: {} steps", run.steps);
    }
}

/// The new options are checked: the acoustic jump in (0, 1], the weights
/// and the face viscosity in [0, 1].
#[test]
fn acoustic_options_are_validated() {
    let ok = || shock_tube(gas(1.4), 10, SOD_L, SOD_R, 0.5).unwrap();
    let field_of = |p: &IceParams<1>| match run_fluid(ok(), p, 0.1, 10) {
        Err(IceError::InvalidInput { field, .. }) => field,
        other => panic!("expected invalid input, got {other:?}"),
    };
    let base = IceParams::hancock_acoustic(walls1());
    for (bad, name) in [
        (
            IceParams {
                acoustic_jump: Some(0.0),
                ..base.clone()
            },
            "acoustic_jump",
        ),
        (
            IceParams {
                acoustic_jump: Some(f64::NAN),
                ..base.clone()
            },
            "acoustic_jump",
        ),
        (
            IceParams {
                pressure_weight_compression: Some(1.5),
                ..base.clone()
            },
            "pressure_weight_compression",
        ),
        (
            IceParams {
                face_viscosity: Some(-0.1),
                ..base.clone()
            },
            "face_viscosity",
        ),
    ] {
        assert_eq!(field_of(&bad), name);
    }
}

#[test]
fn the_face_predictor_needs_a_reconstruction() {
    let st = shock_tube(gas(1.4), 10, SOD_L, SOD_R, 0.5).unwrap();
    let mut p = IceParams::new(walls1());
    p.face_predictor = true;
    match p.validate(&st) {
        Err(IceError::InvalidInput { field, .. }) => assert_eq!(field, "face_predictor"),
        other => panic!("{other:?}"),
    }
}

/// The unit square in `n × n` cells.
fn unit_square(n: usize) -> CellLayout<2> {
    let h = 1.0 / n as f64;
    CellLayout::<2>::new(SVector::zeros(), SVector::<f64, 2>::new(h, h), [n, n]).unwrap()
}

fn smooth_2d(nx: usize) -> IceState<2> {
    let layout = unit_square(nx);
    IceState::new(layout, vec![gas(1.4)], |x| {
        let tp = 2.0 * std::f64::consts::PI;
        let rho = 1.0 + 0.3 * (tp * x[0]).sin() * (tp * x[1]).cos();
        let p = 1.0 + 0.2 * (tp * x[1]).sin();
        let u = SVector::<f64, 2>::new(0.5 + 0.2 * (tp * x[1]).sin(), -0.3 * (tp * x[0]).cos());
        vec![MaterialInit::new(1.0, rho, p, u)]
    })
    .unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

#[test]
fn periodic_box_conserves_mass_momentum_energy() {
    let st = smooth_2d(24);
    let (m0, p0, e0) = st.totals();
    let mut params = IceParams::new([
        [IceBoundary::Periodic, IceBoundary::Periodic],
        [IceBoundary::Periodic, IceBoundary::Periodic],
    ]);
    params.cfl = 0.4;
    let run = run_fluid(st, &params, 0.1, 10_000).unwrap();
    let (m1, p1, e1) = run.state.totals();
    assert!(rel(m1, m0) < 1e-14, "mass {m0} -> {m1}");
    assert!((p1 - p0).norm() < 1e-13 * m0, "momentum {p0} -> {p1}");
    assert!(rel(e1, e0) < 1e-13, "energy {e0} -> {e1}");
}

/// A uniform gas falling freely in a periodic box keeps its density,
/// pressure and temperature, and its velocity grows by `g t` (Guilkey
/// Eq. 33's `Δt M g`); gravity's work goes to the kinetic energy. In the
/// conservative energy form the internal energy used to pay for it: T fell
/// by `|g|² t²/(2 c_v)` (0.8 of its start in the `gravity = [-10]` box of
/// issue 23's note, at t = 0.1).
#[test]
fn a_gas_falling_freely_keeps_its_state() {
    let u0 = SVector::<f64, 2>::new(0.3, -0.2);
    let g = SVector::<f64, 2>::new(0.5, -10.0);
    for energy in [EnergyForm::Conservative, EnergyForm::FlowWork] {
        let st = IceState::new(unit_square(8), vec![gas(1.4)], |_| {
            vec![MaterialInit::new(1.0, 1.0, 1.0, u0)]
        })
        .unwrap();
        let t0 = st.cells[0].temperature[st.layout.interior[0]];
        let mut params = IceParams::new([
            [IceBoundary::Periodic, IceBoundary::Periodic],
            [IceBoundary::Periodic, IceBoundary::Periodic],
        ]);
        params.gravity = g;
        params.energy = energy;
        let run = run_fluid(st, &params, 0.1, 10_000).unwrap();
        let s = &run.state;
        let u = u0 + g * s.time;
        let vol = s.layout.cell_volume();
        for &c in &s.layout.interior {
            let mc = &s.cells[0];
            assert!(
                rel(mc.temperature[c], t0) < 1e-12,
                "{energy:?}: T {}",
                mc.temperature[c]
            );
            assert!(rel(mc.mass[c] / vol, 1.0) < 1e-12, "{energy:?}: rho");
            assert!(
                (mc.velocity[c] - u).norm() < 1e-12 * u.norm(),
                "{energy:?}: u {}",
                mc.velocity[c]
            );
        }
    }
}

#[test]
fn closed_wall_box_conserves_mass_and_energy() {
    // Sod between walls, run past the reflections of both waves.
    let st = shock_tube(gas(1.4), 100, SOD_L, SOD_R, 0.5).unwrap();
    let (m0, _, e0) = st.totals();
    let params = IceParams::new([[IceBoundary::Wall, IceBoundary::Wall]]);
    let run = run_fluid(st, &params, 0.6, 10_000).unwrap();
    let (m1, p1, e1) = run.state.totals();
    assert!(rel(m1, m0) < 1e-14, "mass {m0} -> {m1}");
    assert!(rel(e1, e0) < 1e-13, "energy {e0} -> {e1}");
    assert!(p1.norm().is_finite());
}

#[test]
fn flow_work_form_is_not_conservative_but_close() {
    let st = shock_tube(gas(1.4), 100, SOD_L, SOD_R, 0.5).unwrap();
    let (_, _, e0) = st.totals();
    let mut params = IceParams::new([[IceBoundary::Wall, IceBoundary::Wall]]);
    params.energy = EnergyForm::FlowWork;
    let run = run_fluid(st, &params, 0.2, 10_000).unwrap();
    let (_, _, e1) = run.state.totals();
    // Measured drift 4.77e-3 at N = 100.
    assert!(
        rel(e1, e0) > 1e-3 && rel(e1, e0) < 6e-3,
        "energy drift {}",
        rel(e1, e0)
    );
}

/// (a) One gas split into two identical materials evolves like one.
#[test]
fn split_material_matches_single_material() {
    let n = 100;
    let single = shock_tube(gas(1.4), n, SOD_L, SOD_R, 0.5).unwrap();
    let layout = single.layout.clone();
    let split = IceState::new(layout, vec![gas(1.4), gas(1.4)], |x| {
        let (rho, p) = if x[0] < 0.5 { (1.0, 1.0) } else { (0.125, 0.1) };
        let s = MaterialInit::new(0.5, rho, p, SVector::<f64, 1>::zeros());
        vec![s, s]
    })
    .unwrap();
    let params = IceParams::new(walls1());
    let a = run_fluid(single, &params, 0.15, 10_000).unwrap();
    let b = run_fluid(split, &params, 0.15, 10_000).unwrap();
    assert_eq!(a.steps, b.steps);
    for &c in &a.state.layout.interior {
        assert!(rel(b.state.mixture_density(c), a.state.mixture_density(c)) < 1e-12);
        assert!(rel(b.state.p_eq[c], a.state.p_eq[c]) < 1e-12);
        let (ua, ub) = (
            a.state.cells[0].velocity[c][0],
            b.state.cells[1].velocity[c][0],
        );
        assert!((ua - ub).abs() < 1e-12, "{ua} vs {ub}");
    }
}

fn air() -> IceMaterial {
    IceMaterial::new("air", IdealGas::new(1.4, 717.5).unwrap())
}

fn helium() -> IceMaterial {
    IceMaterial::new("helium", IdealGas::new(1.66, 3115.6).unwrap())
}

/// (b) An air/helium interface at uniform velocity and pressure keeps both.
#[test]
fn interface_keeps_uniform_pressure_and_velocity() {
    for k in [None, Some(1e15)] {
        let n = 64;
        let layout = CellLayout::<1>::new(
            SVector::<f64, 1>::zeros(),
            SVector::<f64, 1>::new(1.0 / n as f64),
            [n],
        )
        .unwrap();
        let p0 = 1e5;
        let u0 = SVector::<f64, 1>::new(100.0);
        let st = IceState::new(layout, vec![air(), helium()], |x| {
            let th = if (0.3..0.6).contains(&x[0]) {
                1.0 - 1e-6
            } else {
                1e-6
            };
            vec![
                MaterialInit::new(1.0 - th, 1.2, p0, u0),
                MaterialInit::new(th, 0.17, p0, u0),
            ]
        })
        .unwrap();
        let mut params = IceParams::new([[IceBoundary::Periodic, IceBoundary::Periodic]]);
        params.exchange = k.map(|k| ExchangeCoefficients::uniform(2, k, 0.0));
        let run = run_fluid(st, &params, 0.005, 10_000).unwrap();
        assert!(run.steps > 50);
        let s = &run.state;
        for &c in &s.layout.interior {
            assert!(
                rel(s.p_eq[c], p0) < 1e-10,
                "K = {k:?}: p = {} at {c}",
                s.p_eq[c]
            );
            for m in &s.cells {
                assert!(rel(m.velocity[c][0], u0[0]) < 1e-10);
            }
        }
    }
}

/// (c) A 2D cylindrical explosion centred on the diagonal stays symmetric.
#[test]
fn cylindrical_explosion_is_symmetric_about_the_diagonal() {
    let n = 40;
    let layout = unit_square(n);
    let st = IceState::new(layout, vec![gas(1.4)], |x| {
        let r = ((x[0] - 0.35).powi(2) + (x[1] - 0.35).powi(2)).sqrt();
        let (rho, p) = if r < 0.2 { (1.0, 1.0) } else { (0.125, 0.1) };
        vec![MaterialInit::new(1.0, rho, p, SVector::<f64, 2>::zeros())]
    })
    .unwrap();
    let params = IceParams::new([
        [IceBoundary::Wall, IceBoundary::Outflow],
        [IceBoundary::Wall, IceBoundary::Outflow],
    ]);
    let run = run_fluid(st, &params, 0.15, 10_000).unwrap();
    let s = &run.state;
    let mut umax: f64 = 0.0;
    for &c in &s.layout.interior {
        umax = umax.max(s.cells[0].velocity[c].norm());
    }
    assert!(umax > 0.1);
    for i in 0..n as isize {
        for j in 0..n as isize {
            let (a, b) = (s.layout.index([i, j]), s.layout.index([j, i]));
            assert!(rel(s.mixture_density(a), s.mixture_density(b)) < 1e-12);
            let (ua, ub) = (s.cells[0].velocity[a], s.cells[0].velocity[b]);
            assert!((ua[0] - ub[1]).abs() < 1e-12 * umax && (ua[1] - ub[0]).abs() < 1e-12 * umax);
        }
    }
}

fn strong_run(
    left: (f64, f64, f64),
    right: (f64, f64, f64),
    t_end: f64,
    params: &IceParams<1>,
) -> Result<(f64, FluidRun<1>), IceError> {
    let st = shock_tube(gas(1.4), 200, left, right, 0.5)?;
    let run = run_fluid(st, params, t_end, 100_000)?;
    let e = shock_tube_l1(&run.state, left, right, 1.4, 0.5);
    Ok((e, run))
}

fn assert_positive_or_clean(r: Result<(f64, FluidRun<1>), IceError>, name: &str) -> Option<f64> {
    match r {
        Ok((e, run)) => {
            for &c in &run.state.layout.interior {
                let m = &run.state.cells[0];
                assert!(
                    m.mass[c] > 0.0 && m.temperature[c] > 0.0 && run.state.p_eq[c] > 0.0,
                    "{name}: cell {c}"
                );
            }
            Some(e)
        }
        Err(e @ (IceError::NonPhysical { .. } | IceError::Equilibration { .. })) => {
            let msg = e.to_string();
            assert!(msg.contains("cell ["), "{name}: {msg}");
            None
        }
        Err(e) => panic!("{name}: unexpected error {e}"),
    }
}

/// The "123" double rarefaction and the 1e4 pressure-ratio shock tube run
/// with `p`: both must reach the end with positive states; their L1(ρ).
fn hard_cases(p: &IceParams<1>) -> (f64, f64) {
    let e123 = assert_positive_or_clean(
        strong_run((1.0, -2.0, 0.4), (1.0, 2.0, 0.4), 0.15, p),
        "123",
    );
    let e_ratio = assert_positive_or_clean(
        strong_run((1.0, 0.0, 1000.0), (1.0, 0.0, 0.1), 0.012, p),
        "1e4 ratio",
    );
    (
        e123.expect("123 runs to the end"),
        e_ratio.expect("1e4 ratio runs to the end"),
    )
}

/// (d) The "123" double rarefaction and a 1e4 pressure-ratio shock tube.
#[test]
fn strong_rarefaction_and_shock_stay_positive() {
    let (e123, e_ratio) = hard_cases(&IceParams::new(walls1()));
    // Measured (N = 200, L1 of ρ): 123 6.79e-3, 1e4 ratio 3.86e-2.
    assert!(e123 < 7.5e-3, "123 L1 = {e123}");
    assert!(e_ratio < 4.2e-2, "1e4 ratio L1 = {e_ratio}");
}

/// The hard cases with the acoustic Hancock variant (its compression
/// weight and face viscosity act hardest there): they run to the end with
/// positive density, pressure and temperature, and the errors stay at the
/// literal scheme's level or below. Measured (N = 200): 123 5.253e-3,
/// 1e4 ratio 3.265e-2 (literal: 6.79e-3, 3.86e-2). Before the Lagrangian
/// remap (`lagrangian_remap`): 4.631e-3 and 3.282e-2, with bounds 5.0e-3
/// and 3.5e-2. The 123 bound was moved to 5.5e-3 with the remap, a
/// deliberate trade: the remap is second order on smooth flow of finite
/// amplitude (simple wave ε = 0.1: L1 7.6× lower at N = 1024) and lowers
/// Sod's error by 15 % at N = 800, but in the 123 problem's first steps,
/// where the fan is narrower than a cell, its uniform-stretch assumption
/// does not hold (see `advection::remap_strain`).
#[test]
fn hancock_acoustic_hard_cases_stay_positive() {
    let (e123, e_ratio) = hard_cases(&IceParams::hancock_acoustic(walls1()));
    eprintln!("hancock_acoustic: 123 L1 {e123:e}, 1e4 ratio L1 {e_ratio:e}");
    assert!(e123 < 5.5e-3, "123 L1 = {e123}");
    assert!(e_ratio < 3.5e-2, "1e4 ratio L1 = {e_ratio}");
}

/// K = 1e15 among two mixed materials in a shock tube: stable, one velocity.
#[test]
fn stiff_exchange_is_stable() {
    let n = 100;
    let layout = CellLayout::<1>::new(
        SVector::<f64, 1>::zeros(),
        SVector::<f64, 1>::new(1.0 / n as f64),
        [n],
    )
    .unwrap();
    let st = IceState::new(layout, vec![air(), helium()], |x| {
        let p = if x[0] < 0.5 { 1e6 } else { 1e5 };
        let z = SVector::<f64, 1>::zeros();
        vec![
            MaterialInit::new(0.7, 1.2 * p / 1e5, p, z),
            MaterialInit::new(0.3, 0.17 * p / 1e5, p, z),
        ]
    })
    .unwrap();
    let mut params = IceParams::new(walls1());
    params.exchange = Some(ExchangeCoefficients::uniform(2, 1e15, 1e10));
    let (m0, _, e0) = st.totals();
    let run = run_fluid(st, &params, 2e-4, 100_000).unwrap();
    let s = &run.state;
    let (m1, _, e1) = s.totals();
    assert!(rel(m1, m0) < 1e-14 && rel(e1, e0) < 1e-12);
    let mut umax: f64 = 0.0;
    for &c in &s.layout.interior {
        umax = umax.max(s.cells[0].velocity[c][0].abs());
    }
    assert!(umax > 10.0);
    for &c in &s.layout.interior {
        let (a, b) = (s.cells[0].velocity[c][0], s.cells[1].velocity[c][0]);
        assert!((a - b).abs() <= 1e-6 * umax, "cell {c}: {a} vs {b}");
    }
}

fn entropy_wave_error(n: usize, adv: Advection) -> f64 {
    let layout = CellLayout::<1>::new(
        SVector::<f64, 1>::zeros(),
        SVector::<f64, 1>::new(1.0 / n as f64),
        [n],
    )
    .unwrap();
    let rho = |x: f64| 1.0 + 0.2 * (2.0 * std::f64::consts::PI * x).sin();
    let st = IceState::new(layout, vec![gas(1.4)], |x| {
        vec![MaterialInit::new(
            1.0,
            rho(x[0]),
            1.0,
            SVector::<f64, 1>::new(1.0),
        )]
    })
    .unwrap();
    let mut params = IceParams::new([[IceBoundary::Periodic, IceBoundary::Periodic]]);
    params.advection = adv;
    let run = run_fluid(st, &params, 1.0, 100_000).unwrap();
    let s = &run.state;
    s.layout
        .interior
        .iter()
        .map(|&c| (s.mixture_density(c) - rho(s.layout.centre(c)[0] - 1.0)).abs())
        .sum::<f64>()
        / n as f64
}

#[test]
fn entropy_wave_second_order() {
    let a = entropy_wave_error(64, Advection::SecondOrder(Limiter::VanLeer));
    let b = entropy_wave_error(128, Advection::SecondOrder(Limiter::VanLeer));
    let order = (a / b).log2();
    assert!(order >= 1.8, "order {order}: {a:e} {b:e}");
}

#[test]
fn invalid_inputs_are_errors() {
    let ok = || shock_tube(gas(1.4), 10, SOD_L, SOD_R, 0.5).unwrap();
    let mut p = IceParams::new(walls1());
    p.cfl = 0.0;
    assert!(matches!(
        run_fluid(ok(), &p, 0.1, 10),
        Err(IceError::InvalidInput { .. })
    ));
    p.cfl = 1.5;
    assert!(matches!(
        run_fluid(ok(), &p, 0.1, 10),
        Err(IceError::InvalidInput { .. })
    ));
    let p = IceParams::new([[IceBoundary::Periodic, IceBoundary::Wall]]);
    assert!(matches!(
        run_fluid(ok(), &p, 0.1, 10),
        Err(IceError::InvalidInput { .. })
    ));
    let p = IceParams::new(walls1());
    assert!(matches!(
        run_fluid(ok(), &p, f64::NAN, 10),
        Err(IceError::InvalidInput { .. })
    ));
    assert!(matches!(
        run_fluid(ok(), &p, 1.0, 3),
        Err(IceError::InvalidInput { .. })
    ));
    let mut p = IceParams::new(walls1());
    p.exchange = Some(ExchangeCoefficients::uniform(2, 1.0, 0.0));
    assert!(matches!(
        run_fluid(ok(), &p, 0.1, 10),
        Err(IceError::InvalidInput { .. })
    ));
    assert!(shock_tube(gas(1.4), 10, (-1.0, 0.0, 1.0), SOD_R, 0.5).is_err());
    assert!(shock_tube(gas(1.4), 0, SOD_L, SOD_R, 0.5).is_err());
    let layout = CellLayout::<1>::new(
        SVector::<f64, 1>::zeros(),
        SVector::<f64, 1>::new(0.1),
        [10],
    )
    .unwrap();
    let z = SVector::<f64, 1>::zeros();
    let r = IceState::new(layout.clone(), vec![air(), helium()], |_| {
        vec![
            MaterialInit::new(0.5, 1.0, 1e5, z),
            MaterialInit::new(0.6, 1.0, 1e5, z),
        ]
    });
    assert!(matches!(r, Err(IceError::InvalidInput { .. })));
    let r = IceState::new(layout.clone(), vec![air(), helium()], |_| {
        vec![
            MaterialInit::new(0.5, 1.0, 1e5, z),
            MaterialInit::new(0.5, 1.0, 2e5, z),
        ]
    });
    assert!(matches!(r, Err(IceError::InvalidInput { .. })));
    let r = IceState::new(layout, vec![air()], |_| {
        vec![MaterialInit::new(1.0, 1.0, -1e5, z)]
    });
    assert!(matches!(r, Err(IceError::InvalidInput { .. })));
}

#[test]
fn oversized_step_asks_for_a_retry() {
    let mut st = shock_tube(gas(1.4), 20, SOD_L, SOD_R, 0.5).unwrap();
    let p = IceParams::new(walls1());
    let mut ws = IceWorkspace::new(&st);
    let before = st.cells[0].mass.clone();
    // Δt = 2 h / c: the face velocity of the pressure jump empties a cell.
    match step_with_dt(&mut st, &p, &mut ws, 0.1) {
        Err(e @ IceError::TimestepTooLarge { .. }) => {
            assert!(e.is_retryable());
            for &c in &st.layout.interior {
                assert_eq!(st.cells[0].mass[c], before[c]);
            }
            assert_eq!(st.time, 0.0);
        }
        other => panic!("expected a retry request, got {other:?}"),
    }
    assert!(step_with_dt(&mut st, &p, &mut ws, 1e-3).is_ok());
}

/// The high-resolution variant (MUSCL reconstruction in Guilkey Eq. 28,
/// time-centred pressure, superbee, cfl 0.4) reaches the Sod
/// target. Measured L1(ρ) at N = 400: 1.467e-3 (literal Eq. 28: 3.73e-3).
#[test]
fn sod_high_resolution_n400_meets_target() {
    let st = shock_tube(gas(1.4), 400, SOD_L, SOD_R, 0.5).unwrap();
    let p = IceParams::high_resolution(walls1());
    let run = run_fluid(st, &p, 0.2, 100_000).unwrap();
    let e = shock_tube_l1(&run.state, SOD_L, SOD_R, 1.4, 0.5);
    assert!(e <= 1.5e-3, "L1 = {e:e}");
}

/// A Mach 1.2 shock in air and a helium bubble, 2D.
pub(crate) fn shock_bubble(nx: usize) -> IceState<2> {
    let ny = nx / 2;
    let h = 0.2 / nx as f64;
    let layout = CellLayout::<2>::new(
        SVector::<f64, 2>::zeros(),
        SVector::<f64, 2>::new(h, h),
        [nx, ny],
    )
    .unwrap();
    // Rankine–Hugoniot for M = 1.2, γ = 1.4, ahead: ρ = 1.2, p = 1e5.
    let (g, m) = (1.4_f64, 1.2_f64);
    let p2 = 1e5 * (1.0 + 2.0 * g / (g + 1.0) * (m * m - 1.0));
    let r2 = 1.2 * (g + 1.0) * m * m / ((g - 1.0) * m * m + 2.0);
    let c1 = (g * 1e5 / 1.2).sqrt();
    let u2 = c1 * m * (1.0 - 1.2 / r2);
    IceState::new(layout, vec![air(), helium()], move |x| {
        let inside = (x[0] - 0.08).powi(2) + (x[1] - 0.05).powi(2) < 0.025f64.powi(2);
        let th = if inside { 1.0 - 1e-6 } else { 1e-6 };
        let (rho_a, p, u) = if x[0] < 0.03 {
            (r2, p2, SVector::<f64, 2>::new(u2, 0.0))
        } else {
            (1.2, 1e5, SVector::<f64, 2>::zeros())
        };
        let rho_he = 0.17 * p / 1e5;
        vec![
            MaterialInit::new(1.0 - th, rho_a, p, u),
            MaterialInit::new(th, rho_he, p, u),
        ]
    })
    .unwrap()
}

pub(crate) fn closed2() -> [[IceBoundary<2>; 2]; 2] {
    [
        [IceBoundary::Wall, IceBoundary::Wall],
        [IceBoundary::Wall, IceBoundary::Wall],
    ]
}

/// A Mach 1.2 shock passes a helium bubble in a closed box (coarse 48×24,
/// stiff momentum exchange): positive masses, temperatures and pressures,
/// no NaN, mass of each material conserved to round-off and total energy
/// to 1e-12, for the literal, high-resolution and acoustic Hancock
/// variants.
#[test]
fn shock_helium_bubble_2d_is_stable_and_conservative() {
    for hr in ["literal", "high_resolution", "hancock_acoustic"] {
        let st = shock_bubble(48);
        let m0: Vec<f64> = st
            .cells
            .iter()
            .map(|mc| st.layout.interior.iter().map(|&c| mc.mass[c]).sum())
            .collect();
        let (_, _, e0) = st.totals();
        let mut p = match hr {
            "high_resolution" => IceParams::high_resolution(closed2()),
            "hancock_acoustic" => IceParams::hancock_acoustic(closed2()),
            _ => IceParams::new(closed2()),
        };
        p.exchange = Some(ExchangeCoefficients::uniform(2, 1e15, 0.0));
        let run = run_fluid(st, &p, 1.5e-4, 100_000).unwrap();
        let s = &run.state;
        for (r, mc) in s.cells.iter().enumerate() {
            let m1: f64 = s.layout.interior.iter().map(|&c| mc.mass[c]).sum();
            assert!(rel(m1, m0[r]) < 1e-13, "{hr}: material {r} mass");
            for &c in &s.layout.interior {
                assert!(
                    mc.mass[c] > 0.0 && mc.temperature[c] > 0.0,
                    "{hr}: cell {c}"
                );
                assert!(mc.velocity[c].iter().all(|v| v.is_finite()));
            }
        }
        for &c in &s.layout.interior {
            assert!(s.p_eq[c] > 0.0 && s.p_eq[c].is_finite());
        }
        let (_, _, e1) = s.totals();
        assert!(rel(e1, e0) < 1e-12, "{hr}: energy {e0} -> {e1}");
        // The shock reached and compressed the bubble: helium above ambient
        // pressure somewhere.
        let pmax_he = s
            .layout
            .interior
            .iter()
            .filter(|&&c| s.cells[1].vol_frac[c] > 0.5)
            .map(|&c| s.p_eq[c])
            .fold(0.0, f64::max);
        assert!(pmax_he > 1.2e5, "{hr}: helium p_max = {pmax_he}");
    }
}

/// The step gives bit-identical results with 1 and 2 rayon threads.
#[test]
fn one_and_two_threads_are_bit_identical() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut p = IceParams::high_resolution(closed2());
            p.exchange = Some(ExchangeCoefficients::uniform(2, 1e15, 1e8));
            run_fluid(shock_bubble(32), &p, 5e-5, 100_000).unwrap()
        })
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.steps, b.steps);
    for (ma, mb) in a.state.cells.iter().zip(&b.state.cells) {
        for &c in &a.state.layout.interior {
            assert_eq!(ma.mass[c].to_bits(), mb.mass[c].to_bits());
            assert_eq!(ma.temperature[c].to_bits(), mb.temperature[c].to_bits());
            assert_eq!(ma.sp_vol[c].to_bits(), mb.sp_vol[c].to_bits());
            for k in 0..2 {
                assert_eq!(ma.velocity[c][k].to_bits(), mb.velocity[c][k].to_bits());
            }
        }
    }
    for &c in &a.state.layout.interior {
        assert_eq!(a.state.p_eq[c].to_bits(), b.state.p_eq[c].to_bits());
    }
}

fn shear_wave(mu: Option<f64>, n: usize, t_end: f64) -> (f64, FluidRun<2>) {
    let h = 1.0 / n as f64;
    let layout = CellLayout::<2>::new(
        SVector::<f64, 2>::zeros(),
        SVector::<f64, 2>::new(h, h),
        [n, 4],
    )
    .unwrap();
    let a = 1e-3;
    let st = IceState::new(layout, vec![gas(1.4)], |x| {
        let u = SVector::<f64, 2>::new(0.0, a * (2.0 * std::f64::consts::PI * x[0]).sin());
        vec![MaterialInit::new(1.0, 1.0, 1.0, u)]
    })
    .unwrap();
    let mut p = IceParams::new([
        [IceBoundary::Periodic, IceBoundary::Periodic],
        [IceBoundary::Periodic, IceBoundary::Periodic],
    ]);
    p.viscosity = mu.map(|m| vec![m]);
    let run = run_fluid(st, &p, t_end, 100_000).unwrap();
    let s = &run.state;
    // Amplitude of the sin(2πx) mode of u_y.
    let amp = s
        .layout
        .interior
        .iter()
        .map(|&c| {
            let x = s.layout.centre(c)[0];
            s.cells[0].velocity[c][1] * (2.0 * std::f64::consts::PI * x).sin()
        })
        .sum::<f64>()
        * 2.0
        / s.layout.num_interior() as f64;
    (amp / a, run)
}

/// Newtonian viscosity: a shear wave `u_y = A sin 2πx` decays as
/// `exp(−4π²νt)` (ν = μ/ρ = 0.02, t = 0.5: factor 0.674).
#[test]
fn viscous_shear_wave_decays_at_the_exact_rate() {
    let mu = 0.02;
    let t = 0.5;
    let exact = (-4.0 * std::f64::consts::PI.powi(2) * mu * t).exp();
    let (r32, _) = shear_wave(Some(mu), 32, t);
    let (r64, _) = shear_wave(Some(mu), 64, t);
    let (e32, e64) = ((r32 - exact).abs(), (r64 - exact).abs());
    // Measured: relative errors 3.2e-4 (N = 32) and 8.0e-5 (N = 64), order 2.
    assert!(e32 < 4e-4 * exact, "N = 32: {r32} vs {exact}");
    assert!(e64 < 0.3 * e32, "N = 64: {r64} vs {exact}");
    // Without viscosity the wave is not damped by the pressure terms (no
    // pressure gradient) and only weakly by advection (none here).
    let (r0, _) = shear_wave(None, 32, t);
    assert!((r0 - 1.0).abs() < 1e-6, "inviscid ratio {r0}");
    let (rz, _) = shear_wave(Some(0.0), 32, t);
    assert_eq!(r0.to_bits(), rz.to_bits());
}

/// Full explicit ICE step, 2D density wave `ρ = 1 + 0.2 sin 2πx sin 2πy`
/// advected along `(1, 1)` at uniform `p = 10⁻⁴` (Courant number
/// `≈ 0.49` per direction, `cfl = 1`), one period: L1 density error and the
/// largest deviations of pressure and velocity from uniform.
fn diagonal_wave(n: usize, adv: Advection) -> (f64, f64, f64) {
    let layout = unit_square(n);
    let tp = 2.0 * std::f64::consts::PI;
    let rho = |x: &SVector<f64, 2>| 1.0 + 0.2 * (tp * x[0]).sin() * (tp * x[1]).sin();
    let u0 = SVector::<f64, 2>::new(1.0, 1.0);
    let st = IceState::new(layout, vec![gas(1.4)], |x| {
        vec![MaterialInit::new(1.0, rho(x), 1e-4, u0)]
    })
    .unwrap();
    let mut params = IceParams::new([
        [IceBoundary::Periodic, IceBoundary::Periodic],
        [IceBoundary::Periodic, IceBoundary::Periodic],
    ]);
    params.advection = adv;
    params.cfl = 1.0;
    let run = run_fluid(st, &params, 1.0, 100_000).unwrap();
    let s = &run.state;
    let (mut err, mut dp, mut du) = (0.0, 0.0f64, 0.0f64);
    for &c in &s.layout.interior {
        err += (s.mixture_density(c) - rho(&s.layout.centre(c))).abs();
        dp = dp.max(rel(s.p_eq[c], 1e-4));
        du = du.max((s.cells[0].velocity[c] - u0).norm());
    }
    (err / (n * n) as f64, dp, du)
}

/// Corner-transport advection in the full step: second order (measured
/// 1.85 between N = 32 and 64) for diagonal advection at Courant number
/// 0.49 per direction; pressure and velocity stay uniform to a second-order
/// error. The dimension-by-dimension scheme is first order there (order 0.56 at
/// Courant number 0.34, `ice_diagonal_wave`) and fails at 0.49.
#[test]
fn diagonal_density_wave_is_second_order_at_courant_one_half() {
    let adv = Advection::SecondOrder(Limiter::VanLeer);
    let (a, dpa, dua) = diagonal_wave(32, adv);
    let (b, dpb, dub) = diagonal_wave(64, adv);
    let order = (a / b).log2();
    assert!(order >= 1.8, "order {order}: {a:e} {b:e}");
    // Pressure and velocity are not exactly uniform: the compatible fluxes
    // carry `F_M e_f` with `M_f` and `e_f` reconstructed apart, so
    // `ρe ∝ p` is uniform only to the reconstruction error. Measured
    // deviations: p 2.47e-3 → 5.52e-4 (relative), u 9.87e-7 → 2.75e-7;
    // the dimension-by-dimension scheme at cfl 0.7 does not converge
    // (p 7.5e-3 → 6.7e-3, u 5.1e-6 → 9.9e-6).
    let p_order = (dpa / dpb).log2();
    let u_order = (dua / dub).log2();
    assert!(p_order >= 1.8, "pressure deviation {dpa:e} {dpb:e}");
    assert!(u_order >= 1.8, "velocity deviation {dua:e} {dub:e}");
    assert!(dpb < 1e-3 && dub < 1e-6, "p {dpb:e}, u {dub:e}");
}

/// The normalised equilibration of a coupled scene (Guilkey Sec. 3.3 step
/// 2) normalises freely where a particle material fills at least
/// `SOLID_FILL_FOR_NORMALISING` of the cell and keeps a fluid-only cell's
/// total material volume within `[V/R, R V]`: after equilibration
/// `Σ_r M_r v_r` equals the reference volume `V_t` exactly.
#[test]
fn normalised_equilibration_is_bounded_without_solid() {
    let layout = CellLayout::<1>::new(SVector::zeros(), SVector::<f64, 1>::new(1.0), [4]).unwrap();
    let vol = layout.cell_volume();
    let solid = IceMaterial::new("solid", IdealGas::new(1.4, 717.5).unwrap());
    let mut st = IceState::new(layout, vec![air(), solid], |_| {
        let z = SVector::<f64, 1>::zeros();
        vec![
            MaterialInit::new(0.5, 1.2, 1.0e5, z),
            MaterialInit::new(0.5, 1.2, 1.0e5, z),
        ]
    })
    .unwrap();
    let (r, f) = (
        pressure::FLUID_NORMALISING_RANGE,
        pressure::SOLID_FILL_FOR_NORMALISING,
    );
    // Per cell: (fluid M v, solid M v) as fractions of V, and the expected
    // V_t / V.
    let w = 0.5; // the last cell's solid fill is f / 2
    let cases = [
        (0.03, 0.0, 1.0 / r),
        (0.3, 0.5, 0.8),
        (1.5, 0.0, 1.5),
        (0.03, 0.5 * f, 1.0 / r + w * (0.03 + 0.5 * f - 1.0 / r)),
    ];
    let interior = st.layout.interior.clone();
    for (&c, &(fluid, sol, _)) in interior.iter().zip(&cases) {
        for (k, frac) in [(0, fluid), (1, sol)] as [(usize, f64); 2] {
            let mc = &mut st.cells[k];
            mc.mass[c] = if frac > 0.0 { 1.2 * vol } else { 1e-15 * vol };
            mc.sp_vol[c] = frac.max(1e-15) * vol / mc.mass[c];
        }
    }
    let mut params = IceParams::new([[IceBoundary::Wall, IceBoundary::Wall]]);
    params.frames = vec![Frame::Eulerian, Frame::Rigid];
    params.normalise_volume = true;
    equilibrate(&mut st, &params).unwrap();
    for (&c, &(_, _, vt)) in interior.iter().zip(&cases) {
        let total: f64 = st.cells.iter().map(|mc| mc.mass[c] * mc.sp_vol[c]).sum();
        assert!(
            rel(total, vt * vol) < 1e-9,
            "cell {c}: {total} vs {}",
            vt * vol
        );
    }
}
