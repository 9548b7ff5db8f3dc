//! Reaction mass exchange in the coupled MPM-ICE step (Guilkey Sec. 3.3
//! steps 4 and 8, Sec. 5: a solid reactant burning on its surface into a
//! product gas at Γ = A K pⁿ), on `cases/reaction_burn.toml`: a slab of
//! reactant against a wall in a closed tube of its product.

use mpmice::coupling::CoupledRun;
use mpmice::scene::{build_coupled_run, parse};

const CASE: &str = include_str!("../cases/reaction_burn.toml");

/// The case with `edits` (pairs of exact text → replacement) applied.
fn run_of(edits: &[(&str, &str)]) -> CoupledRun<1> {
    let mut text = CASE.to_string();
    for (from, to) in edits {
        assert!(text.contains(from), "the case has no `{from}`");
        text = text.replace(from, to);
    }
    build_coupled_run::<1>(&parse(&text).unwrap()).unwrap()
}

/// Mass of the fluids (in cells) and of the particles.
fn masses(run: &CoupledRun<1>) -> (f64, f64) {
    let nf = run.num_fluids();
    let fluid: f64 = run.fluid.cells[..nf]
        .iter()
        .map(|mc| {
            run.fluid
                .layout
                .interior
                .iter()
                .map(|&c| mc.mass[c])
                .sum::<f64>()
        })
        .sum();
    let solid: f64 = run.fields.iter().map(|f| f.particles.total_mass()).sum();
    (fluid, solid)
}

/// Energy of the fluids and particles (kinetic, internal, strain).
fn energy(run: &CoupledRun<1>) -> f64 {
    let nf = run.num_fluids();
    let mut e = 0.0;
    for (mat, mc) in run.fluid.materials[..nf].iter().zip(&run.fluid.cells) {
        use mpmice::material::eos::EquationOfState;
        let cv = mat.eos.specific_heat_cv();
        for &c in &run.fluid.layout.interior {
            e += mc.mass[c] * (cv * mc.temperature[c] + 0.5 * mc.velocity[c].norm_squared());
        }
    }
    for f in &run.fields {
        e += f.particles.kinetic_energy() + f.particles.strain_energy(&run.materials);
    }
    e
}

/// With n = 0 the face regresses at a constant rate: by t = 1 ms exactly
/// K A t = 1.8e-3 kg per m² has become product (A = 1: one face; the wall
/// is a symmetry plane). The fluid gains exactly what the particles lose,
/// and the energy the products received accounts for the energy change.
#[test]
fn constant_rate_burn_converts_exactly_k_a_t() {
    let mut run = run_of(&[]);
    let (f0, s0) = masses(&run);
    let e0 = energy(&run);
    run.advance_to(1e-3).unwrap();
    let (f1, s1) = masses(&run);
    let t = run.reaction_totals();
    let exact = 1.8 * 1.0 * 1e-3;
    eprintln!(
        "burnt {:.16e} (exact {exact:e}), fluid gain {:e}, solid loss {:e}",
        t.mass,
        f1 - f0,
        s0 - s1
    );
    assert!(
        (t.mass - exact).abs() < 1e-12 * exact,
        "{} vs {exact}",
        t.mass
    );
    // Mass: the sums change by the burnt mass, the total by round-off.
    assert!(((f1 - f0) - t.mass).abs() < 1e-12 * (f0 + s0));
    assert!(((s0 - s1) - t.mass).abs() < 1e-12 * (f0 + s0));
    assert!(((f1 + s1) - (f0 + s0)).abs() < 1e-14 * (f0 + s0));
    // The heat of reaction is Q per kg burnt.
    assert!((t.heat - 5e6 * t.mass).abs() < 1e-12 * t.heat);
    // Energy: what the products received explains the change to 1 % of it
    // (measured 2.0e-3; the rest is the coupled step's own energy error).
    let e1 = energy(&run);
    let balance = (e1 - e0 - t.energy) / t.energy;
    eprintln!("energy change − released = {balance:e} of the released energy");
    assert!(balance.abs() < 1e-2, "{balance:e}");
}

/// The semi-implicit pressure (`time.mode = "semi_implicit"`) runs the same
/// burn: K A t to round-off, mass conserved.
#[test]
fn semi_implicit_burn_converts_k_a_t() {
    let mut run = run_of(&[("mode = \"explicit\"", "mode = \"semi_implicit\"")]);
    let (f0, s0) = masses(&run);
    run.advance_to(1e-3).unwrap();
    let (f1, s1) = masses(&run);
    let burnt = run.reaction_totals().mass;
    assert!((burnt - 1.8e-3).abs() < 1e-12 * 1.8e-3, "{burnt:e}");
    assert!(((f1 + s1) - (f0 + s0)).abs() < 1e-14 * (f0 + s0));
}

/// With n = 0.8 the rate follows the cell pressure: the burnt mass lies
/// between `K A Σ p_minⁿ Δt` and `K A Σ p_maxⁿ Δt` over the steps, with the
/// pressure extremes of the tube at the end of each step (the pressure the
/// burn uses), which differ by a few per cent as the gas builds up.
#[test]
fn pressure_dependent_burn_follows_k_p_to_the_n() {
    let (k, n) = (1.8e-4, 0.8);
    let mut run = run_of(&[
        ("rate_constant = 1.8", "rate_constant = 1.8e-4"),
        ("pressure_exponent = 0.0", "pressure_exponent = 0.8"),
    ]);
    let (mut lo, mut hi) = (0.0, 0.0);
    let (mut p_lo, mut p_hi) = (f64::INFINITY, 0.0f64);
    while run.fluid.time < 1e-3 * (1.0 - 1e-12) {
        let info = run.step(1e-3 - run.fluid.time).unwrap();
        let (mut a, mut b) = (f64::INFINITY, 0.0f64);
        for &c in &run.fluid.layout.interior {
            a = a.min(run.fluid.pressure[c]);
            b = b.max(run.fluid.pressure[c]);
        }
        lo += k * a.powf(n) * info.dt;
        hi += k * b.powf(n) * info.dt;
        p_lo = p_lo.min(a);
        p_hi = p_hi.max(b);
    }
    let burnt = run.reaction_totals().mass;
    eprintln!("burnt {burnt:e} in [{lo:e}, {hi:e}]; p in [{p_lo:e}, {p_hi:e}]");
    assert!(burnt >= lo * (1.0 - 1e-12) && burnt <= hi * (1.0 + 1e-12));
    // The bracket is tight (the pressure stays within 10 %), so this pins
    // the law, not just its order of magnitude.
    assert!(hi / lo < 1.1, "{hi:e} / {lo:e}");
}

/// Below the threshold temperature nothing burns.
#[test]
fn cold_reactant_does_not_burn() {
    let mut run = run_of(&[("solid_temperature = 650.0", "solid_temperature = 599.0")]);
    let (f0, _) = masses(&run);
    run.advance_to(2e-4).unwrap();
    let (f1, _) = masses(&run);
    assert_eq!(run.reaction_totals().mass, 0.0);
    assert!((f1 - f0).abs() < 1e-14 * f0);
}

/// A very fast burn (K = 2e5: the pressure rises from 1 bar past 100 bar
/// within 2e-5 s, whole cells burn out and their particles are removed)
/// stays finite and conserves the total mass to round-off; the energy the
/// products received accounts for the energy change to 1 %.
#[test]
fn very_fast_burn_stays_finite_and_conserves_mass() {
    let mut run = run_of(&[("rate_constant = 1.8", "rate_constant = 2e5")]);
    let (f0, s0) = masses(&run);
    let e0 = energy(&run);
    let n0: usize = run.fields.iter().map(|f| f.particles.len()).sum();
    let mut p_max = 0.0f64;
    let mut t_100 = f64::NAN;
    while run.fluid.time < 1e-4 * (1.0 - 1e-12) {
        run.step(1e-4 - run.fluid.time).unwrap();
        for &c in &run.fluid.layout.interior {
            p_max = p_max.max(run.fluid.pressure[c]);
        }
        if t_100.is_nan() && p_max > 100.0 * 101_325.0 {
            t_100 = run.fluid.time;
        }
    }
    let (f1, s1) = masses(&run);
    let n1: usize = run.fields.iter().map(|f| f.particles.len()).sum();
    let t = run.reaction_totals();
    let balance = (energy(&run) - e0 - t.energy) / t.energy;
    eprintln!(
        "p_max {p_max:e} (100 bar at t = {t_100:e}), particles {n0} → {n1}, burnt {:e}, \
         energy balance {balance:e}",
        t.mass
    );
    assert!(t_100 < 2e-5, "{t_100:e}");
    assert!(n1 < n0, "burnt-out particles are removed");
    assert!(((f1 + s1) - (f0 + s0)).abs() < 1e-13 * (f0 + s0));
    assert!(balance.abs() < 1e-2, "{balance:e}");
    assert!(run.fluid.cells.iter().all(|mc| mc
        .temperature
        .iter()
        .zip(&mc.mass)
        .all(|(t, m)| t.is_finite() && m.is_finite())));
}

/// Bad reactions are rejected with the key named.
#[test]
fn bad_reactions_name_their_key() {
    let cases: &[(&str, &str, &str)] = &[
        (
            "reactant = \"pbx\"",
            "reactant = \"products\"",
            "reactions[0].reactant",
        ),
        (
            "product = \"products\"",
            "product = \"pbx\"",
            "reactions[0].product",
        ),
        (
            "rate_constant = 1.8",
            "rate_constant = -1.0",
            "reactions[0].rate_constant",
        ),
        (
            "pressure_exponent = 0.0",
            "pressure_exponent = -0.5",
            "reactions[0].pressure_exponent",
        ),
        (
            "threshold_temperature = 600.0",
            "threshold_temperature = 0.0",
            "reactions[0].threshold_temperature",
        ),
        (
            "heat_of_reaction = 5e6",
            "heat_of_reaction = -1.0",
            "reactions[0].heat_of_reaction",
        ),
        (
            "cv = 1000.0\n\n[[materials]]",
            "\n[[materials]]",
            "reactions[0].reactant",
        ),
    ];
    for (from, to, key) in cases {
        let text = CASE.replacen(from, to, 1);
        assert_ne!(text, CASE, "edit `{from}` did not apply");
        let e = parse(&text).expect_err(key).to_string();
        assert!(e.contains(key), "`{e}` does not name {key}");
    }
}
