//! Implicit MPM-ICE (`time.mode = "implicit"` in a coupled scene): the
//! pressurised cylinder of Guilkey Sec. 4.1 at steps far beyond the steel's
//! sound-speed limit, against Lamé (Eq. 43) and the explicit coupled run;
//! the mode's scene checks and its failure path.

use std::path::Path;

use mpmice::diagnostics::coupled::{measure_cylinder, run_cylinder_history, run_cylinder_scene};
use mpmice::driver::{run_scene, RunOptions};
use mpmice::scene::{self, Scene};

fn case(name: &str) -> Scene {
    let path = format!("{}/cases/{name}", env!("CARGO_MANIFEST_DIR"));
    scene::load(Path::new(&path)).expect("case parses")
}

/// Eq. 43 (`||σr + σθ| − 2P/3| / (2P/3)` averaged over the particles, P the
/// measured inner gauge pressure): first order in dx in 40 steps of 1e-4 s
/// (the explicit run takes 3594 steps at dx = 0.05), and as close to Lamé
/// as the explicit coupled run at the same dx.
///
/// Over time: the quasistatic steel is in equilibrium with each step's load,
/// so Lamé holds at every step with that step's P. During the heating
/// (t from 1 to 3 ms) every step's Eq. 43 stays below 0.27 at dx 0.1 and
/// 0.15 at dx 0.05 (measured 0.254–0.259 and 0.128–0.143). After the heating
/// stops a transient of a few steps lifts it (dx 0.05: 0.295 at 3.4 ms,
/// back to 0.137 at 3.7 ms; printed, not asserted; the study's series
/// 'max over t in [1, 4] ms' shows it shrinking with dx).
#[test]
fn implicit_cylinder_converges_to_lame_at_large_steps() {
    let mut errors = Vec::new();
    for (dx, heating_bound) in [(0.1, 0.27), (0.05, 0.15)] {
        let (run, m, _, history) =
            run_cylinder_history(case("pressurized_cylinder_implicit.toml"), dx, 1e-3)
                .expect("implicit cylinder runs");
        let heating: Vec<f64> = history
            .iter()
            .filter(|h| h.t <= 3.0e-3 + 1e-9)
            .map(|h| h.error43)
            .collect();
        let after = history
            .iter()
            .filter(|h| h.t > 3.0e-3 + 1e-9)
            .fold(0.0_f64, |a, h| a.max(h.error43));
        let heating_max = heating.iter().copied().fold(0.0, f64::max);
        println!(
            "dx {dx}: Eq. 43 over the heating (t in [1, 3] ms, {} steps) {:.4e} … {:.4e}, \
             largest after it {after:.4e}",
            heating.len(),
            heating.iter().copied().fold(f64::INFINITY, f64::min),
            heating_max
        );
        assert_eq!(heating.len(), 21, "a sample every step from 1 to 3 ms");
        assert!(heating_max < heating_bound, "dx {dx}: {heating_max}");
        let it = run.implicit_totals;
        println!(
            "dx {dx}: Eq. 43 {:.4e}, P {:.4e} Pa, {} steps, {} Newton iterations (max {}), \
             {} retries",
            m.error43,
            m.pressure,
            run.steps,
            it.newton_iterations,
            it.max_newton_iterations,
            it.step_retries
        );
        assert_eq!(run.steps, 40, "Δt = 1e-4 s to 4 ms, no cut");
        assert!(it.max_newton_iterations <= 4, "{it:?}");
        // The heated air reaches about 19 MPa (19.25 MPa at Δt = 1e-5 s;
        // the large step loses a few per cent, see the study).
        assert!(
            m.pressure > 1.8e7 && m.pressure < 1.95e7,
            "P = {}",
            m.pressure
        );
        errors.push(m.error43);
    }
    let order = (errors[0] / errors[1]).log2();
    println!("order {order:.3}");
    assert!(errors[1] < 0.15, "Eq. 43 at dx 0.05: {}", errors[1]);
    assert!(order > 0.75, "observed order {order}");
    let (_, explicit, _) =
        run_cylinder_scene(case("pressurized_cylinder.toml"), 0.1).expect("explicit runs");
    println!("explicit dx 0.1: Eq. 43 {:.4e}", explicit.error43);
    assert!(
        errors[0] < 1.1 * explicit.error43,
        "implicit {} against explicit {}",
        errors[0],
        explicit.error43
    );
}

/// Reproducer (ignored: a known defect of issue 20): after the heating stops
/// nothing should change the inner gas pressure but the steel's tiny
/// creep, yet in implicit mode it decays and air reaches into the steel's
/// cells (air density in the first full steel cell ×7 from 3 to 8 ms at
/// dx 0.025), because each step's pressure stage moves the steel's faces
/// by Δt² ∇p/ρ_s as if the steel had no stiffness, and the gas locked to
/// them is advected with them: held there (`implicit.hold_solid_faces`,
/// the next test) P stays at 1.9286e7 Pa. This is Guilkey's step, still
/// the default. At dx 0.05, Δt 1e-4 s, P falls from
/// 1.8746e7 Pa at 3.2 ms to 1.7922e7 at 8 ms (−4.4 %); the explicit case
/// holds 19.24 MPa at 8 ms.
/// Asserted: P at 8 ms within 0.5 % of P at 3.2 ms.
#[test]
#[ignore = "issue 20: Guilkey's step (the default) leaks the gas into the steel's cells; implicit.hold_solid_faces does not"]
fn implicit_cylinder_keeps_its_gas_after_the_heating() {
    let mut sc = case("pressurized_cylinder_implicit.toml");
    sc.time.end = 8e-3;
    let (_, m, _, history) = run_cylinder_history(sc, 0.05, 3.2e-3 - 1e-9).expect("runs");
    let p0 = history[0].pressure;
    println!(
        "P {:.4e} Pa at {:.2e} s, {:.4e} Pa at 8 ms",
        p0, history[0].t, m.pressure
    );
    assert!(
        (m.pressure / p0 - 1.0).abs() < 5e-3,
        "{p0} → {}",
        m.pressure
    );
}

/// The remedy of the reproducer above (`implicit.hold_solid_faces`): the
/// pressure stage holds the steel's faces at its cells' velocity where it
/// fills both cells, so no gas is carried into the wall. After the heating
/// the gas is closed in the steel: its pressure must stay at the value the
/// heat put in, `(γ − 1) q t_heat = 0.4 × 1.608e10 W/m³ × 3 ms = 1.9296e7
/// Pa` (a rigid container; the steel's expansion takes a little of it),
/// at every step from 4 to 8 ms. Measured at dx 0.05: 1.9286e7 Pa at
/// Δt 1e-4 s and 1.9281e7 at Δt 1e-3 s (without the hold P falls to
/// 1.7922e7 and 1.4758e7 by 8 ms). Eq. 43 at Δt 1e-4 s: 0.146 at 8 ms
/// (without: 0.144); largest after the heating, in its transient, 0.302
/// (without: 0.295). At Δt 1e-3 s the transient is longer: largest from
/// 4 ms on 0.440, 0.239 at 8 ms (without the hold 0.708 at 8 ms).
#[test]
fn held_solid_faces_keep_the_cylinders_gas_at_small_and_large_steps() {
    let exact = 0.4 * 1.608e10 * 3e-3;
    for (dt, e43_end, e43_max) in [(1e-4, 0.16, 0.33), (1e-3, 0.26, 0.5)] {
        let mut sc = case("pressurized_cylinder_implicit.toml");
        sc.time.end = 8e-3;
        sc.time.dt = Some(dt);
        sc.implicit.hold_solid_faces = true;
        let (_, m, _, history) = run_cylinder_history(sc, 0.05, 3.2e-3).expect("runs");
        let after: Vec<_> = history.iter().filter(|s| s.t > 3.9e-3).collect();
        let worst_p = after
            .iter()
            .map(|s| (s.pressure / exact - 1.0).abs())
            .fold(0.0, f64::max);
        let worst_e43 = history.iter().map(|s| s.error43).fold(0.0, f64::max);
        println!(
            "Δt {dt:e}: P {:.4e} Pa at 8 ms against the heat input's {exact:.4e}, \
             largest departure from 4 ms on {worst_p:.2e} ({} samples); Eq. 43 {:.4e} at 8 ms, \
             largest from 3.2 ms on {worst_e43:.4e}",
            m.pressure,
            after.len(),
            m.error43
        );
        assert!(after.len() >= 4, "Δt {dt:e}: {} samples", after.len());
        assert!(worst_p < 2e-3, "Δt {dt:e}: P departs {worst_p:e}");
        assert!(m.error43 < e43_end, "Δt {dt:e}: Eq. 43 {}", m.error43);
        assert!(worst_e43 < e43_max, "Δt {dt:e}: Eq. 43 up to {worst_e43}");
    }
}

/// The Newmark (dynamic) solid under the same load: undamped, it rings
/// about the Lamé state (radial mode ≈ 0.8 ms), and its mean hoop load,
/// averaged over the 2 ms after the heating stops (steady gas pressure),
/// matches the gas's: measured +0.12 %. (A snapshot at 4 ms caught the
/// ring at −25 %.)
#[test]
fn implicit_newmark_cylinder_carries_the_gas_load() {
    let mut sc = case("pressurized_cylinder_implicit.toml");
    sc.implicit.dynamic = true;
    sc.time.dt = Some(2.5e-5);
    sc.grid.cells = vec![24, 24];
    let mut run = scene::build_coupled_run::<2>(&sc).expect("builds");
    run.advance_to(3e-3).expect("heating");
    // Plane-strain Lamé: the mean in-plane stress (σr + σθ)/2 is P/3
    // everywhere in the wall.
    let (mut mean, mut target, mut n) = (0.0, 0.0, 0.0);
    while run.fluid.time < 5e-3 - 1e-12 {
        run.step(2.5e-5).expect("steps");
        let p = &run.fields[0].particles;
        mean += p
            .stress
            .iter()
            .map(|s| 0.5 * (s[(0, 0)] + s[(1, 1)]))
            .sum::<f64>()
            / p.len() as f64;
        let m = measure_cylinder(&run, 0.5, sc.coupling.reference_pressure);
        target += m.pressure / 3.0;
        n += 1.0;
    }
    let (mean, target) = (mean / n, target / n);
    println!("mean in-plane stress over 3–5 ms {mean:.4e} against P/3 = {target:.4e}");
    assert!((mean / target - 1.0).abs() < 0.02, "{mean} vs {target}");
}

/// Scene checks of the mode: reactions are refused (their particles burn
/// away), `[fluid.pressure]` is read, and a Newton solve that cannot
/// converge stops with the step, time, particle and material after Δt was
/// cut down to the smallest allowed.
#[test]
fn implicit_coupled_scene_checks_and_failure() {
    let base = std::fs::read_to_string(format!(
        "{}/cases/pressurized_cylinder_implicit.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("case");
    let with_pressure = format!("{base}\n[fluid.pressure]\nlinear_tolerance = 1e-10\n");
    scene::parse(&with_pressure).expect("[fluid.pressure] is read in implicit coupled mode");
    let reacting = format!(
        "{base}\n[[reactions]]\nreactant = \"steel\"\nproduct = \"air\"\n\
         rate_constant = 1.0\npressure_exponent = 0.0\nthreshold_temperature = 600.0\n\
         heat_of_reaction = 5e6\n"
    );
    let err = scene::parse(&reacting)
        .expect_err("reactions refused")
        .to_string();
    assert!(err.contains("reactions"), "{err}");
    // Grips and surface pressures are solid-only loads: refused, not
    // silently dropped.
    let gripped =
        format!("{base}\n[[implicit.prescribed]]\nobject = 0\ndisplacement = [0.0, 0.01]\n");
    let err = scene::parse(&gripped).expect_err("grips").to_string();
    assert!(err.contains("implicit.prescribed[0]"), "{err}");
    let loaded = base.replace("clip = true", "clip = true\ninner_pressure = 1e6");
    let err = scene::parse(&loaded).expect_err("surface load").to_string();
    assert!(err.contains("objects[0].inner_pressure"), "{err}");
    let mut sc = case("pressurized_cylinder_implicit.toml");
    sc.implicit.max_newton_iterations = 1;
    let dir = tempdir("coupled_implicit_failure");
    let err = run_scene(&sc, &RunOptions::quiet(&dir, 1))
        .expect_err("one Newton iteration is not enough")
        .to_string();
    println!("{err}");
    assert!(err.contains("step 1") || err.contains("step 0"), "{err}");
    assert!(err.contains("particle"), "{err}");
    assert!(err.contains("`steel`"), "{err}");
    assert!(err.contains("smallest allowed"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

fn tempdir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("mpmice_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The steel slab of `cases/slab_in_gas_implicit.toml` on its two air
/// springs, Newmark at steps 60–500× the steel's explicit limit: its
/// displacement after a quarter period against the gas-spring model
/// `x = (v₀/ω) sin ωt`, `ω² = 2γp₀/(ρ_s t L)` (3.487 mm; the explicit
/// coupled run at this h reaches 3.407 mm, 2.3 % below the model, which
/// ignores the slab's spread over the cells). Measured 3.486 / 3.447 mm at
/// Δt = 2.5e-3 / 3.125e-4 s; with the exchange's velocity change counted
/// twice (once as an impulse, again through the end-of-step acceleration
/// in the next step's trapezoidal update) the slab came out at 3.201 /
/// 2.876 mm, and worse the smaller the step. The coupling iteration gives
/// the same within 0.1 % in at most 4 passes a step.
#[test]
fn newmark_slab_on_gas_springs() {
    for (dt, passes) in [(2.5e-3, 1), (3.125e-4, 1), (2.5e-3, 30)] {
        let mut sc = case("slab_in_gas_implicit.toml");
        sc.time.dt = Some(dt);
        sc.implicit.coupling.max_iterations = passes;
        let mut run = scene::build_coupled_run::<2>(&sc).expect("builds");
        let x0 = slab_x(&run);
        let end = sc.time.end;
        while run.fluid.time < end * (1.0 - 1e-9) {
            run.step_exact(dt.min(end - run.fluid.time)).expect("steps");
        }
        let x = slab_x(&run) - x0;
        let model = slab_model(end);
        let it = run.implicit_totals;
        println!(
            "Δt {dt:e}, {passes} passes allowed: x {x:.5e} m against {model:.5e} \
             ({:+.2} %), {} steps, {} passes (max {})",
            100.0 * (x / model - 1.0),
            run.steps,
            it.coupling_iterations,
            it.max_coupling_iterations
        );
        assert!((x / model - 1.0).abs() < 0.03, "Δt {dt}: {x} vs {model}");
        assert!(it.max_coupling_iterations <= 4, "{it:?}");
        assert_eq!(it.step_retries, 0);
    }
}

/// The slab started smoothly (`cases/slab_in_gas_pressure_step.toml`: at
/// rest under ±1 kPa) against `x = x_eq (1 − cos ωt)`, `x_eq = Δp L/(2γp₀)`
/// (2.687 mm at 0.05 s; measured 2.669 mm at Δt = 6.25e-4 s, the explicit
/// run 2.658 mm). Before the solid's round-off entered the Newton floor,
/// this Δt stalled at a residual of 8.8e-7 N and collapsed to 2e-7 s
/// (4649 steps instead of 80).
#[test]
fn newmark_slab_from_a_pressure_difference() {
    let mut sc = case("slab_in_gas_pressure_step.toml");
    sc.time.dt = Some(6.25e-4);
    let mut run = scene::build_coupled_run::<2>(&sc).expect("builds");
    let x0 = slab_x(&run);
    while run.fluid.time < sc.time.end * (1.0 - 1e-9) {
        run.step_exact(6.25e-4).expect("steps");
    }
    let x = slab_x(&run) - x0;
    let model = 1e3 * 0.45 / (1.4 * 101_325.0) * (1.0 - (slab_omega() * sc.time.end).cos());
    println!(
        "x {x:.5e} against {model:.5e}, {} steps, {} retries",
        run.steps, run.implicit_totals.step_retries
    );
    assert_eq!(run.steps, 80);
    assert_eq!(run.implicit_totals.step_retries, 0);
    assert!((x / model - 1.0).abs() < 0.03, "{x} vs {model}");
}

/// The slab's mean x.
fn slab_x(run: &mpmice::coupling::CoupledRun<2>) -> f64 {
    let p = &run.fields[0].particles;
    p.x.iter().map(|x| x[0]).sum::<f64>() / p.len() as f64
}

/// The slab cases' gas-spring frequency: 0.1 m of steel (7850 kg/m³)
/// between two 0.45 m columns of air at 101325 Pa, γ 1.4,
/// `ω² = 2γp₀/(ρ_s t L)`.
fn slab_omega() -> f64 {
    (2.0 * 1.4 * 101_325.0 / (7850.0 * 0.1 * 0.45_f64)).sqrt()
}

/// The gas-spring model of the impulsive slab case at time `t` (starting
/// at 0.1 m/s).
fn slab_model(t: f64) -> f64 {
    let omega = slab_omega();
    0.1 / omega * (omega * t).sin()
}

/// The iteration's keys are checked with the key named, and an iteration
/// that cannot converge cuts Δt down to the smallest allowed, then stops
/// naming the step, time and the last residuals.
#[test]
fn coupling_iteration_checks_and_failure() {
    let base = std::fs::read_to_string(format!(
        "{}/cases/pressurized_cylinder_implicit.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("case");
    for (extra, key) in [
        ("max_iterations = 0", "implicit.coupling.max_iterations"),
        ("tolerance = -1.0", "implicit.coupling.tolerance"),
        ("omega = 2.5", "implicit.coupling.omega"),
        ("relaxation = \"anderson\"", "relaxation"),
        ("passes = 3", "passes"),
    ] {
        let text = base.replace(
            "[implicit]\ndynamic = false",
            &format!("[implicit]\ndynamic = true\ncoupling = {{ {extra} }}"),
        );
        assert_ne!(text, base);
        let err = scene::parse(&text).expect_err(extra).to_string();
        assert!(err.contains(key), "{extra}: {err}");
    }
    // A quasistatic solid is refused (the iteration diverged on it).
    let text = base.replace(
        "[implicit]\ndynamic = false",
        "[implicit]\ndynamic = false\ncoupling = { max_iterations = 5 }",
    );
    let err = scene::parse(&text).expect_err("quasistatic").to_string();
    assert!(err.contains("implicit.coupling.max_iterations"), "{err}");
    assert!(err.contains("dynamic"), "{err}");

    let mut sc = case("pressurized_cylinder_implicit.toml");
    sc.implicit.dynamic = true;
    sc.implicit.coupling.max_iterations = 2;
    sc.implicit.coupling.tolerance = 1e-14;
    sc.grid.cells = vec![24, 24];
    let mut run = scene::build_coupled_run::<2>(&sc).expect("builds");
    // Two cuts at most: the iteration would reach 1e-14 at a Δt small
    // enough for round-off to be all that changes.
    for f in &mut run.fields {
        if let Some(imp) = f.implicit.as_mut() {
            imp.params.dt_min = 2e-5;
        }
    }
    let mut err = None;
    for _ in 0..3 {
        if let Err(e) = run.step_exact(1e-4) {
            err = Some(e.to_string());
            break;
        }
    }
    let err = err.expect("two passes cannot reach 1e-14 once the gas is heated");
    println!("{err}");
    assert!(err.contains("step "), "{err}");
    assert!(err.contains("coupling iteration"), "{err}");
    assert!(err.contains("relative residuals"), "{err}");
    assert!(err.contains("smallest allowed"), "{err}");
}

/// `implicit.modified_newton` (the case's setting) against full Newton on
/// the cylinder at dx 0.05: both stop at the same tolerances, so the
/// Eq. 43 error and the gas pressure agree to the tolerance's level, while
/// modified Newton factorises the tangent about once a step instead of once
/// an iteration (measured: 44 against 105 factorisations; 2.14 s against
/// 3.43 s at dx 0.0125 on one thread, the probe `cylinder_implicit_probe`).
#[test]
fn modified_newton_reaches_the_same_cylinder_with_fewer_factorisations() {
    let mut out = Vec::new();
    for modified in [false, true] {
        let mut sc = case("pressurized_cylinder_implicit.toml");
        sc.implicit.modified_newton = modified;
        let (run, m, _) = run_cylinder_scene(sc, 0.05).expect("implicit cylinder runs");
        let it = run.implicit_totals;
        println!(
            "modified {modified}: Eq. 43 {:.6e}, P {:.6e} Pa, {} Newton iterations, {} \
             factorisations",
            m.error43, m.pressure, it.newton_iterations, it.factorisations
        );
        assert_eq!(run.steps, 40);
        out.push((m.error43, m.pressure, it));
    }
    let ((e_full, p_full, full), (e_mod, p_mod, md)) = (out[0], out[1]);
    assert_eq!(full.factorisations, full.newton_iterations, "{full:?}");
    assert!(
        2 * md.factorisations <= full.factorisations,
        "{} against {}",
        md.factorisations,
        full.factorisations
    );
    assert!(
        (e_mod - e_full).abs() <= 1e-6 * e_full,
        "{e_mod} against {e_full}"
    );
    assert!(
        (p_mod - p_full).abs() <= 1e-9 * p_full,
        "{p_mod} against {p_full}"
    );
}

/// `summary.json` of a coupled implicit run reports the coupling
/// iteration's passes and each implicit field's Newton iterations per
/// step: every pass solves the field at least once, so its mean Newton
/// count is at least the mean number of passes.
#[test]
fn coupled_implicit_summary_reports_passes_and_newton_per_field() {
    let mut sc = case("slab_in_gas_implicit.toml");
    sc.time.end = 0.01;
    sc.implicit.coupling.max_iterations = 30;
    let dir = tempdir("coupled_implicit_summary");
    run_scene(&sc, &RunOptions::quiet(&dir, 1)).expect("slab runs");
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary");
    let v: serde_json::Value = serde_json::from_str(&text).expect("json");
    let c = &v["iterations"]["coupled"];
    println!("{c}");
    let passes = c["passes_mean"].as_f64().expect("passes_mean");
    assert!((1.0..=4.0).contains(&passes), "{c}");
    assert!(c["passes_max"].as_u64().expect("passes_max") <= 4, "{c}");
    assert!(c["cells_s"].as_f64().expect("cells_s") > 0.0, "{c}");
    let f = &c["fields"][0];
    assert_eq!(f["material"], "steel");
    assert!(
        f["newton_mean"].as_f64().expect("newton_mean") >= passes,
        "{c}"
    );
    // Full Newton (the slab case's default): one factorisation an iteration.
    assert_eq!(f["factorisations_mean"], f["newton_mean"], "{c}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A steel bar in air pulled into tension (its two halves start apart at
/// ±1 m/s), Newmark at Δt = 1e-4 s (60× the explicit step): the pure-steel
/// cells expand on the solid's threshold EOS (Guilkey Fig. 1), where the
/// linearised pressure equation asked for −1.6 MPa and Δt was halved 166
/// times in 2 ms. The cell's volume balance solved exactly keeps the
/// pressure admissible: no Δt cut, the air within 1 kPa of its start, no
/// energy created, and the momentum zero by symmetry. (The bar rings at
/// 69 µs, 1.5 periods a step: the implicit step keeps 22 % of its 78.5 J/m
/// of kinetic plus strain energy after 2 ms, implicit MPM on the bar alone
/// 51 %, the explicit coupled run 102 %; measured, not asserted.)
#[test]
fn implicit_bar_in_tension_next_to_gas() {
    let base = std::fs::read_to_string(format!(
        "{}/cases/slab_in_gas_implicit.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("case");
    let text = base
        .replace(
            "geometry = { type = \"box\", lower = [0.45, 0.0], upper = [0.55, 0.1] }\nvelocity = [0.1, 0.0]",
            "geometry = { type = \"box\", lower = [0.4, 0.0], upper = [0.5, 0.1] }\n\
             velocity = [-1.0, 0.0]\n\n[[objects]]\nmaterial = \"steel\"\n\
             geometry = { type = \"box\", lower = [0.5, 0.0], upper = [0.6, 0.1] }\n\
             velocity = [1.0, 0.0]",
        )
        .replace("end = 0.05", "end = 0.002")
        .replace("dt = 2.5e-3", "dt = 1e-4");
    assert_ne!(text, base);
    let sc = scene::parse(&text).expect("bar scene");
    let dir = tempdir("bar_in_tension");
    run_scene(&sc, &RunOptions::quiet(&dir, 1)).expect("bar in tension runs");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).expect("summary"))
            .expect("json");
    println!(
        "steps {}, retries {}, energy drift {}, final {}",
        s["steps"], s["retries"], s["energy_drift"], s["final_materials"]
    );
    assert_eq!(s["steps"], 20);
    assert_eq!(s["retries"], 0);
    let drift = s["energy_drift"].as_f64().expect("drift");
    assert!(drift <= 1e-9, "energy created: {drift}");
    let (air0, air1) = (&s["initial_materials"][0], &s["final_materials"][0]);
    assert_eq!(air1["name"], "air");
    // Mean air pressure change from its internal energy, p = (γ−1) e / V.
    let dp = 0.4 * (air1["internal"].as_f64().unwrap() - air0["internal"].as_f64().unwrap())
        / (0.8 * 0.1);
    assert!(dp.abs() < 1e3, "air pressure moved {dp} Pa");
    let steel = &s["final_materials"][1];
    let p = steel["momentum"][0].as_f64().unwrap();
    assert!(p.abs() < 1e-9 * 157.0, "momentum {p}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A fixed `time.dt` past the advective limit (the implicit adiabatic
/// piston, 240 cells, 10 m/s, Δt = 1e-3 s: an outflow Courant number of 2)
/// is capped at the scene's `cfl` before the pressure stage instead of
/// being halved by it, step after step. Before the cap the CLI run
/// (`mpmice run cases/piston_semi_implicit.toml --set time.mode=implicit
/// --set time.dt=1e-3`) took 303 steps and 545 halvings; now 328 steps and
/// none (324 here, without the output times). The closed-end
/// pressure at the end (compression ratio about 5) stays on the adiabat
/// `P1 r^1.4` as closely as at the small steps (measured 3.6 % here, 3.6 %
/// at Δt = 2.5e-5 in the study `piston_implicit`: the smeared piston's
/// spatial error).
#[test]
fn implicit_piston_steps_past_its_advective_limit_without_halving() {
    let mut sc = case("piston_semi_implicit.toml");
    sc.time.mode = scene::Mode::Implicit;
    sc.time.dt = Some(1e-3);
    let mut run = scene::build_coupled_run::<1>(&sc).expect("builds");
    let mut halvings = 0;
    while run.fluid.time < sc.time.end * (1.0 - 1e-9) {
        run.step_exact(1e-3f64.min(sc.time.end - run.fluid.time))
            .expect("steps");
        halvings += run.last_halvings;
    }
    let ratio = 1.0 / (1.0 + run.rigid_displacement(0, run.fluid.time).expect("rigid")[0]);
    let p = run.fluid.pressure[run.fluid.layout.interior[0]];
    let error = p / (101_325.0 * ratio.powf(1.4)) - 1.0;
    println!(
        "{} steps, {halvings} halvings; ratio {ratio:.4}, closed-end error {error:+.4e}",
        run.steps
    );
    assert_eq!(halvings, 0);
    assert!(run.steps < 340, "{} steps", run.steps);
    assert!(error.abs() < 0.045, "{error}");
}
