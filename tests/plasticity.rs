//! J2 plasticity in the explicit MPM step (issue 18): the scene's
//! `plasticity` table, the plastic state carried by the particles, and a
//! homogeneous uniaxial-strain load and unload against the closed form.

use mpmice::material::plasticity::UniaxialStrainResponse;
use mpmice::scene::{build_solid_run, parse};

const SCENE: &str = r#"
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
[[objects]]
material = "steel"
geometry = { type = "box", lower = [0.5], upper = [1.5] }
"#;

/// What [`drive_uniaxial`] measured.
struct Uniaxial {
    worst: f64,
    peak: f64,
    eps: f64,
    eps_y: f64,
    reverse: f64,
    ebar_max: f64,
    final_ebar: f64,
}

/// A bar so heavy that its particles keep their velocities (ρ = 1e20: the
/// release waves from its free ends move at 5e-5 m/s) is given the linear
/// velocity field v = ε̇ (x − 1) for 140 steps of 1e-4 s, then the reverse
/// field for 120 more (compression past reverse yield). The centre point's
/// stress must follow the closed-form uniaxial-strain path of its strain:
/// elastic to ε_y = σ₀/2μ, then q = σ₀ + H ε̄ with ε̄ = 2μ(ε − ε_y)/(3μ + H),
/// σ₁₁ = Kε + 2q/3, σ₂₂ = Kε − q/3; elastic unloading, reverse yield at
/// −(σ₀ + H ε̄_max). The plastic strain is the particles' output.
///
/// Hypo-elastic (`log = false`): ε = Σ Δt L, the strain its updates
/// accumulated (read back from its F, which each step multiplies by
/// 1 + Δt L), and the stress is σ. Hencky (`log = true`): ε = ln F, the
/// logarithmic strain, and the closed form holds for the Kirchhoff stress
/// τ = J σ at any strain.
fn drive_uniaxial(scene: &str, rate: f64, log: bool) -> Uniaxial {
    let scene = parse(scene).expect("scene parses");
    let mut run = build_solid_run::<1>(&scene).expect("run builds");
    let (e, nu, sy, h) = (200e9, 0.3, 300e6, 2e9);
    let mu = e / (2.0 * (1.0 + nu));
    let exact = UniaxialStrainResponse {
        bulk: e / (3.0 * (1.0 - 2.0 * nu)),
        mu,
        yield_stress: sy,
        hardening: h,
    };
    let eps_y = sy / (2.0 * mu);
    let n = run.particles.len();
    let set_field = |run: &mut mpmice::stepper::SolidRun<1>, a: f64| {
        for p in 0..n {
            run.particles.v[p][0] = a * (run.particles.x[p][0] - 1.0);
        }
    };
    set_field(&mut run, rate);
    // Probe: the point nearest the centre.
    let mid = (0..n)
        .min_by(|&a, &b| {
            let da = (run.particles.x[a][0] - 1.0).abs();
            let db = (run.particles.x[b][0] - 1.0).abs();
            da.total_cmp(&db)
        })
        .unwrap();
    let (mut eps, mut peak, mut ebar_max) = (0.0, 0.0, 0.0);
    let mut loading = true;
    let mut worst: f64 = 0.0;
    let mut reverse = f64::NAN;
    for step in 0..260 {
        if step == 140 {
            // Reverse: compress at the same rate.
            set_field(&mut run, -rate);
            loading = false;
            peak = eps;
            ebar_max = exact.at(peak, None).2;
            reverse = exact.reverse_yield(peak);
        }
        let f_old = run.particles.f.get(mid)[(0, 0)];
        run.step_dt(1e-4).expect("step");
        let f_new = run.particles.f.get(mid)[(0, 0)];
        eps = if log {
            f_new.ln()
        } else {
            // The strain increment the point's update saw: F ← (1 + Δt L) F.
            eps + f_new / f_old - 1.0
        };
        let (s11, s22, eb) = exact.at(eps, (!loading).then_some(peak));
        let j = if log { f_new } else { 1.0 };
        let s = run.particles.stress.get(mid) * j;
        let err = ((s[(0, 0)] - s11).abs() + (s[(1, 1)] - s22).abs()) / sy
            + (run.particles.plastic_strain[mid] - eb).abs() / eps_y;
        worst = worst.max(err);
    }
    Uniaxial {
        worst,
        peak,
        eps,
        eps_y,
        reverse,
        ebar_max,
        final_ebar: run.particles.plastic_strain[mid],
    }
}

fn assert_uniaxial(u: &Uniaxial, what: &str, bound: f64) {
    println!(
        "{what}: peak ε {:.4e} ({:.1} ε_y), final ε {:.4e}, ε̄ {:.4e}, worst relative error \
         {:.2e}",
        u.peak,
        u.peak / u.eps_y,
        u.eps,
        u.final_ebar,
        u.worst
    );
    assert!(
        u.peak > 6.0 * u.eps_y && u.eps < u.reverse,
        "{what}: the path must yield both ways"
    );
    assert!(
        u.final_ebar > 1.5 * u.ebar_max,
        "{what}: reverse plastic flow: {}",
        u.final_ebar
    );
    assert!(u.worst < bound, "{what}: {:e}", u.worst);
}

#[test]
fn homogeneous_uniaxial_strain_follows_the_closed_form() {
    let u = drive_uniaxial(SCENE, 1.0, false);
    assert_uniaxial(&u, "uniaxial strain in MPM, hypo-elastic", 1e-11);
}

/// The multiplicative (Hencky) model through the explicit MPM step, at
/// large strain: ln F to 0.25 (126 yield strains) and back, exact in the
/// logarithmic strain for the Kirchhoff stress.
#[test]
fn hencky_plasticity_follows_the_log_strain_closed_form_at_large_strain() {
    let scene = SCENE.replace("model = \"linear_elastic\"", "model = \"hencky\"");
    let u = drive_uniaxial(&scene, 20.0, true);
    assert_uniaxial(&u, "uniaxial strain in MPM, Hencky", 1e-9);
    assert!(u.peak > 0.2, "large strain: {}", u.peak);
}

/// Bad plasticity input names its key and the allowed values.
#[test]
fn bad_plasticity_input_names_its_key() {
    let edit = |from: &str, to: &str| {
        assert_eq!(SCENE.matches(from).count(), 1, "anchor `{from}`");
        SCENE.replacen(from, to, 1)
    };
    let jc = "plasticity = { flow = \"johnson_cook\", a = 792e6, b = 510e6, n = 0.26, c = 0.014, \
              m = 1.03, melt_temperature = 1793.0, specific_heat = 477.0 }";
    parse(&edit(
        "plasticity = { flow = \"linear\", yield_stress = 300e6, hardening_modulus = 2e9 }",
        jc,
    ))
    .expect("a Johnson-Cook steel parses");
    let cases: Vec<(String, &str, &str)> =
        vec![
        (
            edit("yield_stress = 300e6", "yield_stress = -1.0"),
            "materials[0].plasticity.yield_stress",
            "≥ 0",
        ),
        (
            edit("yield_stress = 300e6, ", ""),
            "materials[0].plasticity.yield_stress",
            "missing",
        ),
        (
            edit("hardening_modulus = 2e9", "hardening_exponent = 0.5"),
            "materials[0].plasticity.hardening_exponent",
            "not read",
        ),
        (
            edit("hardening_modulus = 2e9", "hardening_modulus = 2e9, m = 1.0"),
            "materials[0].plasticity.m",
            "not read",
        ),
        (
            edit(
                "plasticity = { flow = \"linear\", yield_stress = 300e6, hardening_modulus = 2e9 }",
                &jc.replace("m = 1.03", "m = 0.0"),
            ),
            "materials[0].plasticity.m",
            "> 0",
        ),
        (
            edit(
                "plasticity = { flow = \"linear\", yield_stress = 300e6, hardening_modulus = 2e9 }",
                &jc.replace(", specific_heat = 477.0", ""),
            ),
            "materials[0].plasticity.specific_heat",
            "missing",
        ),
        (
            edit("model = \"linear_elastic\"", "model = \"neo_hookean\""),
            "materials[0].plasticity",
            "linear_elastic",
        ),
        (
            edit("dt = 1e-4", "dt = 1e-4\nmode = \"implicit\""),
            "materials[0].plasticity",
            "hencky",
        ),
        (
            edit(
                "model = \"linear_elastic\"",
                "model = \"hencky\"\nfailure = { model = \"tensile\", spall_strength = 1e9 }",
            )
            .replace("dt = 1e-4", "dt = 1e-4\nmode = \"implicit\""),
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
