//! Failure in the explicit MPM step (issue 18): Johnson–Cook damage of a
//! homogeneous uniaxial-strain load against the closed-form path and its
//! failure step, and brittle spall of a bar pulled at both ends
//! (`cases/tensile_bar_spall.toml`, hypo-elastic and Hencky, alone and in
//! air in the coupled MPM-ICE step) against the elastic wave solution.

use mpmice::driver::models::arrays::cell_material_totals;
use mpmice::scene::{build_solid_run, parse};

/// A bar so heavy (ρ = 1e20) that its particles keep the velocity field
/// v = ε̇ (x − 1) it is given (as in `tests/plasticity.rs`): every point
/// follows the same uniaxial-strain path. Linear hardening (σ₀ 300 MPa,
/// H 2 GPa) and Johnson–Cook damage with 4340 steel's D₁..D₃ (Johnson &
/// Cook 1985; D₄ = D₅ = 0: the rate and temperature terms are 1 here).
const JC_SCENE: &str = r#"
[grid]
dim = 1
lower = [0.0]
upper = [2.0]
cells = [40]
boundary = { x_lower = "free", x_upper = "free" }
[time]
end = 1.0
dt = 1e-4
[mpm]
shape = "gimp"
particles_per_cell = 2
[[materials]]
name = "steel"
type = "solid"
model = "linear_elastic"
density = 1e20
youngs_modulus = 200e9
poisson_ratio = 0.3
plasticity = { flow = "linear", yield_stress = 300e6, hardening_modulus = 2e9 }
failure = { model = "johnson_cook", d1 = 0.05, d2 = 3.44, d3 = -2.12 }
[[objects]]
material = "steel"
geometry = { type = "box", lower = [0.5], upper = [1.5] }
"#;

/// Uniaxial strain ε (closed form, as in `tests/plasticity.rs`): ε̄ =
/// 2μ(ε − ε_y)/(3μ + H), q = σ₀ + H ε̄, mean stress σ_m = K ε, so the
/// triaxiality σ* = K ε / q rises along the path and ε_f = D₁ + D₂ exp(D₃
/// σ*) falls. The damage after n steps is the sum Σ Δε̄_k / ε_f(σ*_k) over
/// the closed-form values at the strains the point's updates accumulated
/// (read back from F), and the point fails at the first step where that sum
/// reaches 1; the sum agrees with the integral ∫ dε̄ / ε_f (Simpson, 10⁵
/// panels) to O(Δε̄). After failure the point carries no stress in further
/// tension, and on reversal resists compression with p = K |Δ ln J|
/// exactly (volumetric only).
#[test]
fn johnson_cook_damage_follows_the_closed_form_path() {
    let scene = parse(JC_SCENE).expect("scene parses");
    let mut run = build_solid_run::<1>(&scene).expect("run builds");
    let (e, nu, sy, h) = (200e9, 0.3, 300e6, 2e9);
    let (d1, d2, d3) = (0.05, 3.44, -2.12);
    let mu = e / (2.0 * (1.0 + nu));
    let k = e / (3.0 * (1.0 - 2.0 * nu));
    let eps_y = sy / (2.0 * mu);
    let n = run.particles.len();
    let set_field = |run: &mut mpmice::stepper::SolidRun<1>, a: f64| {
        for p in 0..n {
            run.particles.v[p][0] = a * (run.particles.x[p][0] - 1.0);
        }
    };
    set_field(&mut run, 1.0);
    let mid = midpoint(&run.particles);
    let ebar = |eps: f64| (2.0 * mu * (eps - eps_y) / (3.0 * mu + h)).max(0.0);
    let ef = |eps: f64| {
        let q = sy + h * ebar(eps);
        d1 + d2 * (d3 * k * eps / q).exp()
    };
    let (mut eps, mut sum) = (0.0, 0.0);
    let mut worst: f64 = 0.0;
    let mut expected_fail = None;
    let mut failed_at = None;
    for step in 0..1500 {
        let f_old = run.particles.f.get(mid)[(0, 0)];
        run.step_dt(1e-4).expect("step");
        let eps_new = eps + (run.particles.f.get(mid)[(0, 0)] / f_old - 1.0);
        let de = ebar(eps_new) - ebar(eps);
        eps = eps_new;
        if de > 0.0 {
            sum += de / ef(eps);
        }
        if expected_fail.is_none() && sum >= 1.0 {
            expected_fail = Some(step);
        }
        let d = run.particles.damage[mid];
        if d >= 1.0 {
            failed_at = Some(step);
            break;
        }
        worst = worst.max((d - sum).abs());
    }
    let step = failed_at.expect("the point fails");
    // The continuum integral of dε̄/ε_f over the strain at failure.
    let panels = 100_000;
    let (a, b) = (eps_y, eps);
    let hh = (b - a) / panels as f64;
    let g = |x: f64| 2.0 * mu / (3.0 * mu + h) / ef(x);
    let mut simpson = g(a) + g(b);
    for i in 1..panels {
        simpson += g(a + i as f64 * hh) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    simpson *= hh / 3.0;
    println!(
        "JC damage in MPM: fails at step {step} (closed-form sum: step {:?}), ε {eps:.5}, ε̄ \
         {:.5}, ε_f {:.5}; worst |D − sum| before failure {worst:.2e}; ∫ dε̄/ε_f to the failure \
         strain {simpson:.5}",
        expected_fail,
        run.particles.plastic_strain[mid],
        ef(eps)
    );
    assert_eq!(Some(step), expected_fail, "failure step");
    assert!(worst < 1e-9, "damage vs closed-form sum: {worst:e}");
    assert!(
        (simpson - 1.0).abs() < 0.02,
        "integral at failure {simpson}"
    );
    // Every point of the homogeneous interior fails in the same step (the
    // points within a cell or two of the free ends see the boundary's
    // partial stencils).
    assert!((0..n)
        .filter(|&p| (run.particles.x0[p][0] - 1.0).abs() < 0.4)
        .all(|p| run.particles.failed(p)));
    // Further tension: no stress at all.
    for _ in 0..20 {
        run.step_dt(1e-4).expect("step");
        assert_eq!(run.particles.stress.get(mid), nalgebra::Matrix3::zeros());
    }
    // Reverse: compression builds a pressure K Σ |tr L Δt| (no deviator).
    set_field(&mut run, -1.0);
    let mut compress = 0.0;
    for _ in 0..30 {
        let f_old = run.particles.f.get(mid)[(0, 0)];
        run.step_dt(1e-4).expect("step");
        compress += 1.0 - run.particles.f.get(mid)[(0, 0)] / f_old;
    }
    let s = run.particles.stress.get(mid);
    let p = -s.trace() / 3.0;
    assert!(
        (p / (k * compress) - 1.0).abs() < 1e-9,
        "{p} vs {}",
        k * compress
    );
    assert_eq!(s, nalgebra::Matrix3::identity() * (-p));
}

/// The point of [`JC_SCENE`]'s bar nearest its middle, x = 1.
fn midpoint(p: &mpmice::mpm::Particles<1>) -> usize {
    (0..p.len())
        .min_by(|&a, &b| (p.x[a][0] - 1.0).abs().total_cmp(&(p.x[b][0] - 1.0).abs()))
        .expect("the bar has points")
}

/// Nonlocal damage (`nonlocal_radius`, `mpm::nonlocal_damage`) on the
/// path of [`JC_SCENE`], against the average computed here by brute force.
/// Until a point fails, damage does not change the stress, so a local run
/// and a nonlocal run move identically; each step the local run's
/// increments ΔD_q (its damage differences) averaged with the bell weight
/// (1 − r²/R²)² V_q over the points within R of the midpoint must be the
/// nonlocal run's increment there. R = 0.15 (six points on each side; the
/// field is not quite uniform: the local damage of the four points around
/// x = 1 trails the rest by 6e-4 of itself). Checked to 1e-12 until the
/// first point within 2R fails in either run, then the nonlocal midpoint
/// must go on to fail and, failed, carry no tension.
#[test]
fn nonlocal_damage_is_the_bell_weighted_average_of_the_local_increments() {
    let r = 0.15;
    let nl_text = JC_SCENE.replacen("d3 = -2.12 }", "d3 = -2.12, nonlocal_radius = 0.15 }", 1);
    assert_ne!(nl_text, JC_SCENE);
    let mut local = build_solid_run::<1>(&parse(JC_SCENE).unwrap()).unwrap();
    let mut nl = build_solid_run::<1>(&parse(&nl_text).unwrap()).unwrap();
    let n = local.particles.len();
    for run in [&mut local, &mut nl] {
        for p in 0..n {
            run.particles.v[p][0] = run.particles.x[p][0] - 1.0;
        }
    }
    let mid = midpoint(&local.particles);
    let near: Vec<usize> = (0..n)
        .filter(|&q| (local.particles.x0[q][0] - local.particles.x0[mid][0]).abs() < 2.0 * r)
        .collect();
    let (mut expected, mut worst, mut steps) = (0.0, 0.0f64, 0);
    let mut d_old: Vec<f64> = vec![0.0; n];
    loop {
        local.step_dt(1e-4).unwrap();
        nl.step_dt(1e-4).unwrap();
        let lp = &local.particles;
        if near.iter().any(|&q| lp.failed(q) || nl.particles.failed(q)) {
            break;
        }
        // The brute-force average at the midpoint, positions and volumes
        // at the end of the step (as the step takes them).
        let (mut num, mut den) = (0.0, 0.0);
        for (q, old) in d_old.iter().enumerate() {
            let d2 = (lp.x[q][0] - lp.x[mid][0]).powi(2);
            if d2 < r * r {
                let w = (1.0 - d2 / (r * r)).powi(2) * lp.vol[q];
                num += w * (lp.damage[q] - old);
                den += w;
            }
        }
        expected += num / den;
        worst = worst.max((nl.particles.damage[mid] - expected).abs());
        d_old.copy_from_slice(&lp.damage);
        steps += 1;
        assert_eq!(lp.x, nl.particles.x, "the runs move alike until failure");
    }
    println!(
        "nonlocal damage: {steps} steps checked, midpoint D {:.6} (local {:.6}), worst |D − \
         brute-force average| {worst:.2e}",
        nl.particles.damage[mid], local.particles.damage[mid]
    );
    assert!(expected > 0.9, "the check reached D = {expected}");
    assert!(worst < 1e-12, "{worst:e}");
    for _ in 0..200 {
        if nl.particles.failed(mid) {
            break;
        }
        nl.step_dt(1e-4).unwrap();
    }
    assert!(nl.particles.failed(mid), "the nonlocal midpoint fails");
    for _ in 0..5 {
        nl.step_dt(1e-4).unwrap();
        assert_eq!(nl.particles.stress.get(mid), nalgebra::Matrix3::zeros());
    }
}

/// What one run of `cases/tensile_bar_spall.toml` measured.
struct Spall {
    /// Time of the first failure minus the exact meeting time [s].
    lag: f64,
    /// Cell size and c (for the bounds).
    h: f64,
    c: f64,
    /// Largest |X − L/2| of the points failed at the first failure.
    zone: f64,
}

/// The text of `cases/tensile_bar_spall.toml` with `from` replaced by `to`
/// (each edit's anchor must occur once).
fn spall_case(edits: &[(&str, &str)]) -> String {
    let path = format!(
        "{}/cases/tensile_bar_spall.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut text = std::fs::read_to_string(path).expect("case reads");
    for (from, to) in edits {
        assert_eq!(text.matches(from).count(), 1, "anchor `{from}`");
        text = text.replacen(from, to, 1);
    }
    text
}

/// The largest |X − L/2| of the failed points, `None` before any fails;
/// asserts that every failed point carries no tension (σ = σ₁₁ I with
/// σ₁₁ ≤ 0, exactly: no deviator).
fn failed_zone(p: &mpmice::mpm::Particles<1>) -> Option<f64> {
    let mut zone = None;
    for i in (0..p.len()).filter(|&i| p.failed(i)) {
        let s = p.stress.get(i);
        assert!(s[(0, 0)] <= 0.0, "failed point {i} in tension: {s}");
        assert_eq!(
            s,
            nalgebra::Matrix3::identity() * s[(0, 0)],
            "deviator of {i}"
        );
        zone = Some(zone.unwrap_or(0.0f64).max((p.x0[i][0] - 0.5).abs()));
    }
    zone
}

/// Runs the spall case on `cells` cells, asserting on every step that the
/// failed points carry no tension (σ = σ₁₁ I with σ₁₁ ≤ 0, exactly: no
/// deviator) and that the total momentum stays zero to round-off; and
/// that no single pulse reaches the spall strength before they meet.
fn spall_run(cells: usize, model: &str) -> Spall {
    let to = format!("model = \"{model}\"");
    let text = spall_case(&[("model = \"linear_elastic\"", &to)]);
    let mut scene = parse(&text).expect("case parses");
    scene.grid.cells = vec![cells];
    let mut run = build_solid_run::<1>(&scene).expect("run builds");
    let (e, nu, rho, v0): (f64, f64, f64, f64) = (200e9, 0.3, 7800.0, 10.0);
    let m_mod = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let c = (m_mod / rho).sqrt();
    let spall = 343.7e6;
    let h = 1.1 / cells as f64;
    let t_meet = (0.5 - 0.125) / c;
    let scale = run.particles.momentum_scale();
    let mut t_fail = None;
    let mut worst_p: f64 = 0.0;
    let mut single_peak: f64 = 0.0;
    let mut zone = f64::NAN;
    while !run.finished() {
        run.step().expect("step");
        let p = &run.particles;
        worst_p = worst_p.max(p.momentum()[0].abs() / scale);
        let failed = failed_zone(p);
        if t_fail.is_none() {
            if let Some(z) = failed {
                t_fail = Some(run.t);
                zone = z;
            } else if run.t < t_meet - 3.0 * h / c {
                single_peak = single_peak.max(
                    p.stress
                        .iter()
                        .map(|s| s[(0, 0)])
                        .fold(f64::NEG_INFINITY, f64::max),
                );
            }
        }
    }
    let t_fail = t_fail.expect("the bar spalls");
    println!(
        "{model} spall on {cells} cells: fails at t = {:.3} us (pulses meet at {:.3} us; lag {:.2} \
         cells/c), single pulse peak {:.1} MPa (exact {:.1}, spall {:.1}), momentum drift \
         {worst_p:.1e} of Σ m|v|, first failed points within {:.2} mm of the centre",
        t_fail * 1e6,
        t_meet * 1e6,
        (t_fail - t_meet) * c / h,
        single_peak / 1e6,
        rho * c * v0 / 2e6,
        spall / 1e6,
        zone * 1e3
    );
    assert!(single_peak < spall, "a single pulse must not spall");
    assert!(worst_p < 1e-13, "momentum drift {worst_p:e}");
    Spall {
        lag: t_fail - t_meet,
        h,
        c,
        zone,
    }
}

/// `cases/tensile_bar_spall.toml`: the bar spalls at its centre when the
/// two tensile pulses meet, at t = (L/2 − a)/c, late by the time the
/// smeared fronts (GIMP's dispersion) need to add up to the spall strength:
/// under 3 cells/c of the coarse grid, and shrinking with h (measured
/// 2.44, 1.59, 0.99, 0.61 µs at 220, 440, 880, 1760 cells, 2.9 to 5.7
/// cells of each grid: the lag falls as h^0.6, the dispersive broadening
/// of a front); the first
/// failed points lie within 14 mm of the centre, a zone that shrinks with
/// h as well (13.8, 9.4, 6.6, 3.6 mm). Every step, the failed points carry
/// no tension and the momentum stays zero (`spall_run`).
#[test]
fn bar_pulled_at_both_ends_spalls_where_the_pulses_meet() {
    spalls_where_the_pulses_meet("linear_elastic");
}

/// The same bar with the Hencky model (`model = "hencky"`, whose failed
/// points keep only a compressive Kirchhoff pressure): at these strains
/// (v/c ≈ 2e-3) the two models agree to O(ε), and the same bounds hold.
#[test]
fn hencky_bar_pulled_at_both_ends_spalls_where_the_pulses_meet() {
    spalls_where_the_pulses_meet("hencky");
}

fn spalls_where_the_pulses_meet(model: &str) {
    let coarse = spall_run(220, model);
    let fine = spall_run(440, model);
    let bound = 3.0 * coarse.h / coarse.c;
    for r in [&coarse, &fine] {
        assert!(
            r.lag > 0.0 && r.lag < bound,
            "lag {:.3e} s, 3 coarse cells/c {bound:.3e} s",
            r.lag
        );
    }
    assert!(fine.lag < 0.7 * coarse.lag, "{} {}", fine.lag, coarse.lag);
    assert!(coarse.zone < 0.015 && fine.zone < coarse.zone);
}

/// Bad failure input names its key and the allowed values.
#[test]
fn bad_failure_input_names_its_key() {
    let edit = |from: &str, to: &str| {
        assert_eq!(JC_SCENE.matches(from).count(), 1, "anchor `{from}`");
        JC_SCENE.replacen(from, to, 1)
    };
    let jc = "failure = { model = \"johnson_cook\", d1 = 0.05, d2 = 3.44, d3 = -2.12 }";
    // An elastic brittle material (no plasticity table).
    let brittle = edit(
        "plasticity = { flow = \"linear\", yield_stress = 300e6, hardening_modulus = 2e9 }\n",
        "",
    )
    .replace(
        jc,
        "failure = { model = \"tensile\", spall_strength = 1e8 }",
    );
    parse(&brittle).expect("a brittle elastic material parses");
    let cases: Vec<(String, &str, &str)> = vec![
        (
            edit(jc, "failure = { model = \"tensile\", spall_strength = -1.0 }"),
            "materials[0].failure.spall_strength",
            "> 0",
        ),
        (
            edit(jc, "failure = { model = \"tensile\" }"),
            "materials[0].failure.spall_strength",
            "missing",
        ),
        (
            edit(jc, "failure = { model = \"tensile\", spall_strength = 1e8, d1 = 0.1 }"),
            "materials[0].failure.d1",
            "not read",
        ),
        (
            edit("d1 = 0.05, d2 = 3.44", "d1 = -4.0, d2 = 3.44"),
            "materials[0].failure.d1",
            "d1 + d2 > 0",
        ),
        (
            edit("d2 = 3.44", "d2 = -3.44"),
            "materials[0].failure.d2",
            "≥ 0",
        ),
        (
            edit("d3 = -2.12 }", "d3 = -2.12, d4 = -0.1 }"),
            "materials[0].failure.d4",
            "≥ 0",
        ),
        (
            edit(
                "d3 = -2.12 }",
                "d3 = -2.12, d5 = -1.5, melt_temperature = 1800.0 }",
            ),
            "materials[0].failure.d5",
            "> -1",
        ),
        (
            edit("d3 = -2.12 }", "d3 = -2.12, d5 = 0.6 }"),
            "materials[0].failure.melt_temperature",
            "missing",
        ),
        (
            edit(", d3 = -2.12", ""),
            "materials[0].failure.d3",
            "missing",
        ),
        (
            edit(
                "plasticity = { flow = \"linear\", yield_stress = 300e6, hardening_modulus = 2e9 }\n",
                "",
            ),
            "materials[0].failure",
            "plasticity",
        ),
        (
            edit("d3 = -2.12 }", "d3 = -2.12, nonlocal_radius = -1e-3 }"),
            "materials[0].failure.nonlocal_radius",
            "≥ 0",
        ),
        (
            edit(
                jc,
                "failure = { model = \"tensile\", spall_strength = 1e8, nonlocal_radius = 1e-3 }",
            ),
            "materials[0].failure.nonlocal_radius",
            "not read",
        ),
        (
            edit(jc, "failure = { model = \"ductile\" }"),
            "materials[0].failure.model",
            "johnson_cook",
        ),
        (
            brittle.replace("model = \"linear_elastic\"", "model = \"neo_hookean\""),
            "materials[0].failure",
            "linear_elastic",
        ),
        (
            brittle.replace("dt = 1e-4", "dt = 1e-4\nmode = \"implicit\""),
            "materials[0].failure",
            "explicit",
        ),
    ];
    for (text, path, needle) in cases {
        let e = parse(&text).expect_err(path);
        assert_eq!(e.path, path, "{e}");
        assert!(e.message.contains(needle), "{path}: {e}");
    }
}

/// The spall bar of `cases/tensile_bar_spall.toml` in air, between closed
/// ends (coupled MPM-ICE: air at 1 atm around and inside the bar's cells,
/// the steel stress-free at that pressure, `coupling.reference_pressure`):
/// the air's impedance
/// (ρc ≈ 400 Pa s/m against the bar's 4.6e7) leaves the waves as they are,
/// so the coupled step must spall the bar at the same moment and place as
/// the solid-only run, within the same bounds of the exact meeting time;
/// every step the failed points carry no tension, and the total mass
/// (particles and air) stays constant to round-off.
#[test]
fn coupled_bar_in_air_spalls_where_the_pulses_meet() {
    // Closed ends, so that the air's mass stays in the domain (the bar's
    // ends, 5 cm from them, move 1.2 mm by the end).
    let text = spall_case(&[
        (
            "boundary = { x_lower = \"free\", x_upper = \"free\" }",
            "boundary = { x_lower = \"symmetry\", x_upper = \"symmetry\" }",
        ),
        (
            "[[materials]]",
            "[coupling]\nreference_pressure = 101325.0\n\n[[materials]]\nname = \"air\"\n\
             type = \"fluid\"\neos = \"ideal_gas\"\ngamma = 1.4\ncv = 717.5\n\n[[materials]]",
        ),
    ]) + "\n[[regions]]\npressure = 101325.0\nstates = [{ material = \"air\", \
         volume_fraction = 1.0, density = 1.1768 }]\n";
    let solid_only = spall_run(220, "linear_elastic");
    let scene = parse(&text).expect("coupled case parses");
    let mut run = mpmice::scene::build_coupled_run::<1>(&scene).expect("run builds");
    let total_mass = |run: &mpmice::coupling::CoupledRun<1>| {
        let fluid: f64 = (0..run.num_fluids())
            .map(|r| cell_material_totals(&run.fluid, r).mass)
            .sum();
        fluid + run.fields[0].particles.total_mass()
    };
    let m0 = total_mass(&run);
    let (t_end, c, h) = (1.2e-4, solid_only.c, solid_only.h);
    let t_meet = (0.5 - 0.125) / c;
    let mut t_fail = None;
    let mut zone = f64::NAN;
    while run.fluid.time < t_end * (1.0 - 1e-12) {
        run.step(t_end - run.fluid.time).expect("step");
        let failed = failed_zone(&run.fields[0].particles);
        if let (None, Some(z)) = (t_fail, failed) {
            t_fail = Some(run.fluid.time);
            zone = z;
        }
    }
    let t_fail = t_fail.expect("the bar spalls in air");
    let drift = (total_mass(&run) - m0) / m0;
    println!(
        "coupled spall on 220 cells: fails at t = {:.3} us (solid only {:.3} us, meet {:.3} \
         us), first failed points within {:.2} mm (solid only {:.2} mm), mass drift {drift:.1e}",
        t_fail * 1e6,
        (t_meet + solid_only.lag) * 1e6,
        t_meet * 1e6,
        zone * 1e3,
        solid_only.zone * 1e3
    );
    let lag = t_fail - t_meet;
    assert!(lag > 0.0 && lag < 3.0 * h / c, "lag {lag:e}");
    assert!(
        (lag - solid_only.lag).abs() < 0.1 * h / c,
        "{lag:e} vs {:e}",
        solid_only.lag
    );
    assert!(zone < 0.015, "{zone}");
    assert!(drift.abs() < 1e-12, "{drift:e}");
}
