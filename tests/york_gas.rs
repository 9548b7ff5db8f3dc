//! York Sec. 3.3: compressible gas as material points — sanity against
//! exact answers (rest, uniform translation, Zhang's co-moving block, energy
//! in a closed box), bad input named by key, and York Sec. 4.1's Sod at
//! coarse resolution against the exact Riemann solution.

use mpmice::diagnostics::york::{run_york_sod, YorkSod};
use mpmice::scene::{build_solid_run, parse};
use mpmice::stepper::SolidRun;

/// A 2D gas-point scene: `[0, lx] × [0, ly]` with `cells`, walls `bc`
/// (x faces) and symmetry in y, gas (γ = 1.4, c_v = 2.5, ρ = 1, p = 1,
/// so c = √1.4) in `x ∈ [x0, x1]` moving at `(u, 0)`, plus `extra` TOML.
#[allow(clippy::too_many_arguments)]
fn gas_scene(
    lx: f64,
    ly: f64,
    cells: [usize; 2],
    bc: &str,
    x0: f64,
    x1: f64,
    u: f64,
    end: f64,
    extra: &str,
) -> String {
    format!(
        r#"
[grid]
dim = 2
lower = [0.0, 0.0]
upper = [{lx:e}, {ly:e}]
cells = [{cx}, {cy}]
boundary = {{ x_lower = "{bc}", x_upper = "{bc}", y_lower = "symmetry", y_upper = "symmetry" }}
[time]
end = {end:e}
cfl = 0.4
[mpm]
shape = "gimp"
particles_per_cell = 2
[[materials]]
name = "air"
type = "fluid"
frame = "particles"
eos = "ideal_gas"
gamma = 1.4
cv = 2.5
[[objects]]
material = "air"
geometry = {{ type = "box", lower = [{x0:e}, 0.0], upper = [{x1:e}, {ly:e}] }}
velocity = [{u:e}, 0.0]
density = 1.0
pressure = 1.0
{extra}
"#,
        cx = cells[0],
        cy = cells[1],
    )
}

fn build(text: &str) -> SolidRun<2> {
    let scene = parse(text).expect("scene parses");
    build_solid_run::<2>(&scene).expect("run builds")
}

fn run_to_end(run: &mut SolidRun<2>) {
    while !run.finished() {
        run.step().expect("step");
    }
}

/// Pressure of particle `i` (gas points: −tr σ/3 − q = p with q = 0 here).
fn mean_stress(run: &SolidRun<2>, i: usize) -> f64 {
    -run.particles.stress.get(i).trace() / 3.0
}

#[test]
fn gas_at_rest_stays_at_rest() {
    let mut run = build(&gas_scene(
        1.0,
        0.5,
        [10, 5],
        "symmetry",
        0.0,
        1.0,
        0.0,
        0.5,
        "",
    ));
    stays_at_rest(&mut run, "gas at rest");
}

/// Runs a gas at rest (p = 1) to its end and asserts it stayed there: more
/// than 50 steps, max |v| and max |p − 1| at most 1e-13.
fn stays_at_rest(run: &mut SolidRun<2>, label: &str) {
    run_to_end(run);
    let vmax = run.particles.v.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let pdev = (0..run.particles.len())
        .map(|i| (mean_stress(run, i) - 1.0).abs())
        .fold(0.0, f64::max);
    println!(
        "{label}: {} steps, max |v| = {vmax:.3e} (c = 1.18), max |p − 1| = {pdev:.3e}",
        run.steps
    );
    assert!(run.steps > 50, "{label}");
    assert!(vmax <= 1e-13, "{label}: max |v| = {vmax:e}");
    assert!(pdev <= 1e-13, "{label}: max |p - 1| = {pdev:e}");
}

/// A gas at rest on a strip one cell high (York's Sod layout, 40 × 1 cells
/// between symmetry walls) stays at rest with every shape function. The
/// wide stencils reach the ghost beyond one wall, which folds onto the
/// other wall's boundary nodes; before the grid folded its ghosts before
/// its boundary layers, the quadratic B-spline strip drifted (|v| 0.79 by
/// t = 0.1 at 100 × 1 cells).
#[test]
fn gas_at_rest_on_a_one_cell_strip_stays_at_rest_for_every_shape() {
    for shape in mpmice::shape::ShapeKind::ALL.map(|s| s.name()) {
        let text = gas_scene(1.0, 0.025, [40, 1], "symmetry", 0.0, 1.0, 0.0, 0.3, "")
            .replace("shape = \"gimp\"", &format!("shape = \"{shape}\""));
        stays_at_rest(&mut build(&text), shape);
    }
}

/// The interior of a gas strip [0.5, 3.5] moving at u = 1 (free ends, so
/// rarefactions enter from both ends at c ≈ 1.18; the points that started
/// within [1.75, 2.25] stay well out of their smeared reach by t = 0.05):
/// velocity and pressure unchanged to round-off.
#[test]
fn uniform_translation_stays_uniform() {
    let mut run = build(&gas_scene(
        4.0,
        0.1,
        [80, 2],
        "free",
        0.5,
        3.5,
        1.0,
        0.05,
        "",
    ));
    run_to_end(&mut run);
    let p = &run.particles;
    let inner: Vec<usize> = (0..p.len())
        .filter(|&i| (1.75..=2.25).contains(&p.x0[i][0]))
        .collect();
    let dv = inner
        .iter()
        .map(|&i| (p.v[i] - nalgebra::Vector2::new(1.0, 0.0)).norm())
        .fold(0.0, f64::max);
    let dp = inner
        .iter()
        .map(|&i| (mean_stress(&run, i) - 1.0).abs())
        .fold(0.0, f64::max);
    let dx = inner
        .iter()
        .map(|&i| (p.x[i][0] - p.x0[i][0] - run.t).abs())
        .fold(0.0, f64::max);
    println!(
        "uniform translation: {} steps, {} interior points: max |v − u| = {dv:.3e}, max |p − 1| = \
         {dp:.3e}, max |x − x0 − u t| = {dx:.3e}",
        run.steps,
        inner.len()
    );
    assert!(dv <= 1e-12, "{dv:e}");
    assert!(dp <= 1e-12, "{dp:e}");
    assert!(dx <= 1e-12, "{dx:e}");
}

/// Zhang Sec. 3's test with gas points: a solid block moving with the gas
/// at the gas's speed (and in equilibrium with it, σ = −p I) changes no
/// pressure: relative change < 1e-10.
#[test]
fn zhang_block_moving_with_the_gas_changes_no_pressure() {
    let solid = r#"
[[materials]]
name = "block"
type = "solid"
model = "linear_elastic"
density = 3.0
youngs_modulus = 100.0
poisson_ratio = 0.3
[[objects]]
material = "block"
geometry = { type = "box", lower = [1.9, 0.0], upper = [2.1, 0.1] }
velocity = [1.0, 0.0]
"#;
    // The gas covers [0.5, 1.9] and [2.1, 3.5]: two objects.
    let text = gas_scene(4.0, 0.1, [80, 2], "free", 0.5, 1.9, 1.0, 0.05, solid).replace(
        "[[materials]]\nname = \"block\"",
        "[[objects]]\nmaterial = \"air\"\ngeometry = { type = \"box\", lower = [2.1, 0.0], upper \
         = [3.5, 0.1] }\nvelocity = [1.0, 0.0]\ndensity = 1.0\npressure = 1.0\n[[materials]]\nname \
         = \"block\"",
    );
    let mut run = build(&text);
    let block = run
        .materials
        .iter()
        .position(|m| m.gas().is_none())
        .expect("block material") as u16;
    // The block starts in equilibrium with the gas around it.
    for i in 0..run.particles.len() {
        if run.particles.material[i] == block {
            run.particles.stress.set(i, &-nalgebra::Matrix3::identity());
        }
    }
    run_to_end(&mut run);
    let p = &run.particles;
    let near: Vec<usize> = (0..p.len())
        .filter(|&i| (1.75..=2.25).contains(&p.x0[i][0]))
        .collect();
    let (mut gas_dp, mut block_dp, mut dv) = (0.0_f64, 0.0_f64, 0.0_f64);
    for &i in &near {
        let rel = (mean_stress(&run, i) - 1.0).abs();
        if p.material[i] == block {
            block_dp = block_dp.max(rel);
        } else {
            gas_dp = gas_dp.max(rel);
        }
        dv = dv.max((p.v[i] - nalgebra::Vector2::new(1.0, 0.0)).norm());
    }
    println!(
        "Zhang: {} steps, {} points near the block: gas |Δp|/p = {gas_dp:.3e}, block |Δp|/p = \
         {block_dp:.3e}, max |v − u| = {dv:.3e}",
        run.steps,
        near.len()
    );
    assert!(gas_dp < 1e-10, "{gas_dp:e}");
    assert!(block_dp < 1e-10, "{block_dp:e}");
}

/// A closed box (symmetry walls) with a pressure jump (1.5 | 1): waves
/// reflect back and forth, q turns kinetic energy into heat; kinetic +
/// internal energy stays constant to the stated bound.
#[test]
fn energy_is_conserved_in_a_closed_box() {
    let text = gas_scene(1.0, 0.1, [40, 2], "symmetry", 0.0, 0.5, 0.0, 2.0, "").replace(
        "pressure = 1.0\n",
        "pressure = 1.5\n[[objects]]\nmaterial = \"air\"\ngeometry = { type = \"box\", lower = \
         [0.5, 0.0], upper = [1.0, 0.1] }\ndensity = 1.0\npressure = 1.0\n",
    );
    let mut run = build(&text);
    let e0 = run.energies();
    let mut ke_max = 0.0_f64;
    while !run.finished() {
        run.step().expect("step");
        ke_max = ke_max.max(run.energies().kinetic);
    }
    let e1 = run.energies();
    let drift = (e1.total() - e0.total()).abs();
    println!(
        "closed box: {} steps, E0 = {:.6e} (internal), max kinetic {ke_max:.3e}, final kinetic \
         {:.3e}; |ΔE| = {drift:.3e} = {:.3e} of E0 = {:.3e} of max kinetic",
        run.steps,
        e0.total(),
        e1.kinetic,
        drift / e0.total(),
        drift / ke_max
    );
    assert!(drift / e0.total() < 1e-4, "{}", drift / e0.total());
    assert!(drift / ke_max < 2e-2, "{}", drift / ke_max);
}

/// York Sec. 4.1 at Δx = 0.01 and 0.005 (GIMP, MUSL, York's q): L1(ρ)
/// against the exact Riemann solution within the measured bounds, and the
/// observed order between them.
#[test]
fn york_sod_coarse_l1_density() {
    let run = |cells| {
        run_york_sod(&YorkSod {
            cells,
            ..YorkSod::default()
        })
        .expect("York Sod runs")
    };
    let (a, b) = (run(100), run(200));
    let order = (a.l1_density / b.l1_density).log2();
    println!(
        "York Sod: L1(rho) = {:.4e} (dx 0.01, {} steps), {:.4e} (dx 0.005, {} steps), order {order:.2}",
        a.l1_density, a.steps, b.l1_density, b.steps
    );
    assert!(a.l1_density < 0.0115, "{}", a.l1_density);
    assert!(b.l1_density < 0.0060, "{}", b.l1_density);
    assert!(order > 0.85, "{order}");
}

/// York Sec. 4.1 with the points' grid density (`point_density = "grid"`,
/// GIMP) at Δx = 0.005 and 0.0025: L1(ρ) against the exact Riemann
/// solution below York Eq. 16's continuity density at the same Δx
/// (5.608e-3, 3.030e-3 in the `york_sod` study) and first order. Measured
/// 5.135e-3, 2.636e-3, order 0.96. The grid's density smooths the contact's
/// start-up ringing and GIMP's standing three-point pattern behind the
/// shock, which the ideal gas's forces never see (they do not read ρ), so
/// the order holds to Δx = 0.0003125 (the study; continuity falls to 0.65).
#[test]
fn york_sod_with_grid_density_is_first_order() {
    let run = |cells| {
        run_york_sod(&YorkSod {
            cells,
            point_density: mpmice::material::PointDensity::Grid,
            ..YorkSod::default()
        })
        .expect("York Sod runs")
    };
    let (a, b) = (run(200), run(400));
    let order = (a.l1_density / b.l1_density).log2();
    println!(
        "York Sod, grid density: L1(rho) = {:.4e} (dx 0.005), {:.4e} (dx 0.0025), order {order:.2}",
        a.l1_density, b.l1_density
    );
    assert!(a.l1_density < 5.2e-3, "{}", a.l1_density);
    assert!(b.l1_density < 2.7e-3, "{}", b.l1_density);
    assert!(order > 0.9, "{order}");
}

/// Hard cases with gas points (issue 15), coarse. A pressure ratio of 1e4
/// (ρ = 1 both sides, p = 1000 | 0.1, to t = 0.012, Δx 0.01 and 0.005):
/// positive, below the strong-shock compression limit (γ + 1)/(γ − 1) = 6
/// of any single shock, and converging on the exact solution (measured
/// L1(ρ) 1.632e-1, 9.310e-2, order 0.81). The 123 problem (ρ = 1,
/// u = ∓2, p = 0.4, to t = 0.15, Δx 0.01, a tube [−0.5, 1.5] so that the
/// closed ends' shocks stay out of [0, 1]): density and energy stay
/// positive (measured ρ ≥ 0.130, e ≥ 0.446), but the points tear apart in
/// the near-vacuum (one point per side left within 0.12 of the centre,
/// where the exact ρ is 0.02), so the L1 error does not converge (1.83e-2,
/// 1.54e-2, 1.49e-2 at Δx 0.01, 0.005, 0.0025: a property of points in a
/// near-vacuum, not of the step); it is bounded here at its measured
/// value.
#[test]
fn york_gas_hard_cases_stay_positive() {
    let ratio = |cells| {
        run_york_sod(&YorkSod {
            cells,
            left: (1.0, 0.0, 1000.0),
            right: (1.0, 0.0, 0.1),
            end: 0.012,
            ..YorkSod::default()
        })
        .expect("the 1e4 pressure ratio runs")
    };
    let (a, b) = (ratio(100), ratio(200));
    let order = (a.l1_density / b.l1_density).log2();
    println!(
        "1e4 ratio: L1(rho) {:.4e}, {:.4e} (order {order:.2}); rho in [{:.3e}, {:.3e}], e_min {:.3e}",
        a.l1_density, b.l1_density, b.density_range.0, b.density_range.1, b.energy_min
    );
    for r in [&a, &b] {
        assert!(r.density_range.0 > 0.0 && r.energy_min > 0.0);
        assert!(r.density_range.1 < 6.0, "{:?}", r.density_range);
    }
    assert!(a.l1_density < 0.17, "{}", a.l1_density);
    assert!(b.l1_density < 0.097, "{}", b.l1_density);
    assert!(order > 0.75, "{order}");
    let r = run_york_sod(&YorkSod {
        cells: 100,
        left: (1.0, -2.0, 0.4),
        right: (1.0, 2.0, 0.4),
        tube: (-0.5, 1.5),
        end: 0.15,
        ..YorkSod::default()
    })
    .expect("the 123 problem runs");
    println!(
        "123: L1(rho) {:.4e}; rho in [{:.3e}, {:.3e}], e_min {:.3e}",
        r.l1_density, r.density_range.0, r.density_range.1, r.energy_min
    );
    assert!(
        r.density_range.0 > 0.1 && r.energy_min > 0.4,
        "{:?} {}",
        r.density_range,
        r.energy_min
    );
    assert!(r.l1_density < 0.019, "{}", r.l1_density);
}

/// Bad gas-point input names its key and the allowed values.
#[test]
fn bad_gas_point_input_names_its_key() {
    let good = gas_scene(1.0, 0.5, [10, 5], "symmetry", 0.0, 1.0, 0.0, 0.5, "");
    parse(&good).expect("the good gas scene");
    let edit = |from: &str, to: &str| {
        assert_eq!(good.matches(from).count(), 1, "anchor `{from}`");
        good.replacen(from, to, 1)
    };
    let cases: Vec<(String, &str, &str)> = vec![
        (edit("gamma = 1.4\n", ""), "materials[0].gamma", "missing"),
        (
            edit("cv = 2.5\n", "cv = 2.5\npoint_density = \"nodes\"\n"),
            "materials[0].point_density",
            "expected `continuity` or `grid`",
        ),
        (
            edit(
                "eos = \"ideal_gas\"\ngamma = 1.4\ncv = 2.5\n",
                "eos = \"stiffened_gas\"\ngamma = 1.4\ncv = 2.5\np_inf = 1.0\npoint_density = \
                 \"grid\"\n",
            ),
            "materials[0].point_density",
            "only with eos = \"ideal_gas\"",
        ),
        (
            format!(
                "{good}\n[[materials]]\nname = \"steel\"\ntype = \"solid\"\nmodel = \
                 \"linear_elastic\"\ndensity = 1.0\nyoungs_modulus = 1.0\npoisson_ratio = \
                 0.3\npoint_density = \"grid\"\n"
            ),
            "materials[1].point_density",
            "only for fluid",
        ),
        (
            edit("cv = 2.5\n", "cv = 2.5\nviscosity = -1.0\n"),
            "materials[0].viscosity",
            "≥ 0",
        ),
        (
            edit(
                "cv = 2.5\n",
                "cv = 2.5\nartificial_viscosity = { kappa = -0.5 }\n",
            ),
            "materials[0].artificial_viscosity.kappa",
            "0 ≤ kappa",
        ),
        (
            edit(
                "cv = 2.5\n",
                "cv = 2.5\nartificial_viscosity = { g_over_dx = 0.0 }\n",
            ),
            "materials[0].artificial_viscosity.g_over_dx",
            "0 < g_over_dx",
        ),
        (
            edit(
                "cv = 2.5\n",
                "cv = 2.5\nartificial_viscosity = { c2 = 1e9 }\n",
            ),
            "materials[0].artificial_viscosity.c2",
            "≤ 100",
        ),
        (
            edit("cfl = 0.4\n", "cfl = 0.4\nmode = \"implicit\"\ndt = 0.01\n"),
            "time.mode",
            "explicit",
        ),
        (
            edit("cfl = 0.4\n", "cfl = 0.4\nmode = \"semi_implicit\"\n"),
            "time.mode",
            "explicit",
        ),
        (edit("density = 1.0\n", ""), "objects[0].density", "missing"),
        (
            edit("pressure = 1.0\n", "pressure = -2.0\n"),
            "objects[0].pressure",
            "> 0",
        ),
        (
            format!(
                "{good}\n[[regions]]\npressure = 1.0\nstates = [{{ material = \"air\", \
                 volume_fraction = 1.0, density = 1.0 }}]\n"
            ),
            "regions[0].states[0].material",
            "one frame",
        ),
        (
            format!(
                "{good}\n[[materials]]\nname = \"water\"\ntype = \"fluid\"\neos = \
                 \"ideal_gas\"\ngamma = 1.4\ncv = 1.0\n"
            ),
            "materials[0].frame",
            "cells",
        ),
        (
            format!(
                "{good}\n[[materials]]\nname = \"steel\"\ntype = \"solid\"\nmodel = \
                 \"linear_elastic\"\ndensity = 1.0\nyoungs_modulus = 1.0\npoisson_ratio = \
                 0.3\nframe = \"particles\"\n"
            ),
            "materials[1].frame",
            "only for fluid",
        ),
        (
            edit(
                "frame = \"particles\"\n",
                "frame = \"particles\"\nrigid = true\n",
            ),
            "materials[0].rigid",
            "rigid",
        ),
    ];
    let mut wrong = Vec::new();
    for (text, path, word) in &cases {
        match parse(text) {
            Ok(_) => wrong.push(format!("accepted, expected `{path}`")),
            Err(e) if e.path != *path || !e.message.contains(word) => {
                wrong.push(format!("expected `{path}` with `{word}`, got: {e}"))
            }
            Err(_) => {}
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    // A cell fluid in an object names the frame key.
    let cells = edit("frame = \"particles\"\n", "");
    let e = parse(&cells).expect_err("a cell fluid in an object");
    assert_eq!(e.path, "objects[0].material");
    assert!(e.message.contains("frame = \"particles\""), "{e}");
}

/// York Sec. 4.2 (Eq. 27, Table I), coarse (h = 1, 40 cells): the
/// piston–container periods for m = 0.1 and 1.0 against Eq. 27's roots
/// (ω = 886.43 and 281.15 rad/s; York's Table I: 886.2 and 281.2).
#[test]
fn york_piston_container_period() {
    use mpmice::diagnostics::york::{run_piston_container, PistonContainer};
    for (mass, periods, bound) in [(0.1, 3.0, 2e-4), (1.0, 2.0, 2e-4)] {
        let s = PistonContainer {
            mass,
            h: 1.0,
            periods,
            ..PistonContainer::default()
        };
        let r = run_piston_container(&s).expect("runs");
        let exact = 2.0 * std::f64::consts::PI / r.omega_exact;
        let err = (r.period / exact - 1.0).abs();
        println!(
            "piston m = {mass}, h = 1: omega exact {:.2}, period {:.6} vs {exact:.6} ({:.3e}; zero \
             crossings {:.3e}), {} steps, {:.2} s",
            r.omega_exact,
            r.period,
            err,
            (r.period_crossings / exact - 1.0).abs(),
            r.steps,
            r.wall_s
        );
        assert!(err < bound, "m = {mass}: {err:e}");
    }
}

/// The piston's period estimator: a sinusoid with an offset and a 5 %
/// ripple at 23 times its frequency, sampled over two and a half periods,
/// gives back its frequency to 1e-5 from a guess 3 % off (the zero
/// crossings of its derivative are off by about 1e-3 there).
#[test]
fn fit_frequency_sees_through_ripple() {
    use mpmice::diagnostics::york::fit_frequency;
    let w = 886.43;
    let history: Vec<(f64, f64)> = (0..20_000)
        .map(|k| {
            let t = k as f64 * 2.5 * std::f64::consts::TAU / w / 20_000.0;
            let x = 0.3 + (w * t + 0.4).sin() + 0.05 * (23.0 * w * t).sin();
            (t, x)
        })
        .collect();
    let fit = fit_frequency(&history, 1.03 * w);
    assert!((fit / w - 1.0).abs() < 1e-5, "{fit} vs {w}");
}

/// Scales each point's carried volume and J by 1 ± 0.3 (not its reference
/// volume, so mass and internal energy stay) and its stress by the inverse,
/// as an ideal gas's pressure at that density: the points' forces V σ are
/// those of the uniform gas.
pub(crate) fn scramble_volumes(run: &mut SolidRun<2>, deformation: bool) {
    // The deformation gradient carries J (plane: its 2×2 block; r–z: the
    // hoop stretch too).
    let n = if !deformation {
        0
    } else if run.grid.axisymmetric {
        3
    } else {
        2
    };
    let p = &mut run.particles;
    for i in 0..p.len() {
        let f = 1.0 + 0.3 * (1.7 * i as f64).sin();
        p.vol[i] *= f;
        let s = p.stress.get(i) / f;
        p.stress.set(i, &s);
        let mut fg = p.f.get(i);
        for a in 0..n {
            for b in 0..n {
                fg[(a, b)] *= f.powf(1.0 / n as f64);
            }
        }
        p.f.set(i, &fg);
    }
}

/// Scrambles the gas points' carried volumes ([`scramble_volumes`]), takes `steps` steps and returns the
/// largest |m/V − 1|, |p − 1| and |v| over the points (ρ = p = 1 at rest).
pub(crate) fn scrambled_volumes_after(
    run: &mut SolidRun<2>,
    deformation: bool,
    steps: usize,
) -> [f64; 3] {
    scramble_volumes(run, deformation);
    for _ in 0..steps {
        run.step().expect("step");
    }
    let p = &run.particles;
    (0..p.len()).fold([0.0_f64; 3], |m, i| {
        [
            m[0].max((p.mass[i] / p.vol[i] - 1.0).abs()),
            m[1].max((-p.stress.get(i).trace() / 3.0 - 1.0).abs()),
            m[2].max(p.v[i].norm()),
        ]
    })
}

/// `point_density = "grid"` (the gas's nodal mass over each node's share of
/// the domain, interpolated back) reads a uniform gas exactly wherever the
/// points lie and whatever volumes they carry: with every shape function,
/// between fixed walls and between symmetry planes (the fold gives the
/// boundary nodes their mirror images' mass), scrambled carried volumes
/// (±30 %) are back to m/ρ after one step and the pressure to 1. An ideal
/// gas's forces do not read the volume, so the gas stays at rest. With
/// York's continuity density the scramble stays.
#[test]
fn grid_density_reads_a_uniform_gas_exactly_for_every_shape_and_wall() {
    for shape in mpmice::shape::ShapeKind::ALL.map(|s| s.name()) {
        for bc in ["fixed", "symmetry"] {
            let text = gas_scene(1.0, 0.5, [10, 5], bc, 0.0, 1.0, 0.0, 1.0, "")
                .replace("shape = \"gimp\"", &format!("shape = \"{shape}\""));
            let grid = text.replace("cv = 2.5\n", "cv = 2.5\npoint_density = \"grid\"\n");
            let [rho, p, v] = scrambled_volumes_after(&mut build(&grid), false, 3);
            println!("{shape}, {bc}: max |rho - 1| {rho:.2e}, |p - 1| {p:.2e}, |v| {v:.2e}");
            assert!(rho < 1e-13 && p < 1e-13 && v < 1e-13, "{shape}, {bc}");
            let [rho, ..] = scrambled_volumes_after(&mut build(&text), true, 3);
            assert!(
                rho > 0.25,
                "{shape}, {bc}: continuity keeps the scramble ({rho})"
            );
        }
    }
}
