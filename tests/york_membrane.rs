//! York Sec. 3.2: membrane material points against exact answers — a taut
//! string's transverse and longitudinal periods, a ring in rigid rotation
//! that keeps its stress (objectivity), a gas-filled ring at Laplace
//! equilibrium (hoop stress p r / t) that keeps its gas, energy in an
//! inviscid closed case, and a clean failure when two neighbours coincide.

use mpmice::diagnostics::york_membrane::{gas_outside, membrane_measures};
use mpmice::scene::{build_solid_run, parse};
use mpmice::stepper::SolidRun;

fn build(text: &str) -> SolidRun<2> {
    let scene = parse(text).expect("scene parses");
    build_solid_run::<2>(&scene).expect("run builds")
}

/// A unit box of `cells`² with fixed walls, one membrane material
/// (ρ = 1, E' = E/(1 − ν²) = 1000, h = `thickness`), and `objects`.
fn scene(cells: usize, end: f64, thickness: f64, objects: &str) -> String {
    format!(
        r#"
[grid]
dim = 2
lower = [0.0, 0.0]
upper = [1.0, 1.0]
cells = [{cells}, {cells}]
boundary = {{ x_lower = "fixed", x_upper = "fixed", y_lower = "fixed", y_upper = "fixed" }}
[time]
end = {end:e}
cfl = 0.4
[mpm]
shape = "gimp"
update = "musl"
particles_per_cell = 2
[[materials]]
name = "skin"
type = "membrane"
density = 1.0
youngs_modulus = 910.0
poisson_ratio = 0.3
thickness = {thickness:e}
{objects}
"#
    )
}

/// Times at which `y(t)` crosses zero upwards (linear interpolation).
fn upward_crossings(t: &[f64], y: &[f64]) -> Vec<f64> {
    (1..t.len())
        .filter(|&k| y[k - 1] < 0.0 && y[k] >= 0.0)
        .map(|k| t[k - 1] + (t[k] - t[k - 1]) * (-y[k - 1]) / (y[k] - y[k - 1]))
        .collect()
}

/// A string from (0, 0.5) to (1, 0.5) with fixed ends on the walls,
/// prestress s₀ = 100 (c = √(s₀/ρ) = 10), started in its first mode
/// along `axis` (0: longitudinal, 1: transverse); returns the measured
/// period from the displacement of the point at `probe` (fraction of L).
fn string_period(axis: usize, amplitude: f64, probe: f64, periods: f64, exact: f64) -> f64 {
    let text = scene(
        16,
        periods * exact,
        0.01,
        r#"
[[objects]]
material = "skin"
geometry = { type = "polyline", vertices = [[0.0, 0.5], [1.0, 0.5]] }
spacing = 0.015625
fixed_ends = true
prestress = 100.0
"#,
    );
    let mut run = build(&text);
    let n = run.particles.len();
    let pi = std::f64::consts::PI;
    let omega = 2.0 * pi / exact;
    for p in 0..n {
        let x = run.particles.x[p][0];
        run.particles.v[p][axis] = amplitude * omega * (pi * x).sin();
    }
    let k = (probe * (n - 1) as f64).round() as usize;
    // Start at the upward zero crossing: the displacement is −A cos(ωt + π/2).
    let (mut ts, mut ys) = (vec![0.0], vec![0.0]);
    while !run.finished() {
        run.step().expect("step");
        ts.push(run.t);
        ys.push(run.particles.x[k][axis] - run.particles.x0[k][axis]);
    }
    // Crossings downward at T/2, upward at T: use the upward ones after 0.
    let up = upward_crossings(&ts, &ys.iter().map(|y| -y).collect::<Vec<_>>());
    let down = upward_crossings(&ts, &ys);
    let mut all: Vec<f64> = up.into_iter().chain(down).filter(|&t| t > 0.0).collect();
    all.sort_by(f64::total_cmp);
    // Zero crossings every half period.
    assert!(all.len() >= 3, "crossings {all:?}");
    2.0 * (all[all.len() - 1] - all[0]) / (all.len() - 1) as f64
}

#[test]
fn taut_string_transverse_period_is_2l_over_c() {
    // Exact: T = 2L/c with c = √(s₀/ρ) = 10 (the tension s₀ h over the
    // mass per length ρ h), L = 1: T = 0.2.
    let exact = 0.2;
    let t = string_period(1, 0.005, 0.5, 2.0, exact);
    let err = (t - exact).abs() / exact;
    println!(
        "transverse period {t:.5} vs {exact} (error {:.2} %)",
        100.0 * err
    );
    assert!(err < 0.02, "transverse period {t} vs {exact}");
}

#[test]
fn taut_string_longitudinal_period_is_2l_over_c_bar() {
    // Exact: T = 2L/c with c = √(E/((1 − ν²) ρ)) = √1000 (plane-strain
    // membrane modulus), L = 1.
    let exact = 2.0 / 1000f64.sqrt();
    let t = string_period(0, 0.001, 0.25, 2.0, exact);
    let err = (t - exact).abs() / exact;
    println!(
        "longitudinal period {t:.5} vs {exact:.5} (error {:.2} %)",
        100.0 * err
    );
    assert!(err < 0.02, "longitudinal period {t} vs {exact}");
}

/// A ring of radius R = 0.3 spinning at ω = 2π with s₀ = ρ ω² R² (the
/// tension s₀ h / R is the centripetal force ρ h ω² R: equilibrium) on a
/// grid of `cells`², four points per cell, for a quarter revolution;
/// returns (relative error of the mean stress, relative error of the mean
/// radius, angle turned in degrees).
fn spinning_ring(cells: usize) -> (f64, f64, f64) {
    let (r, omega) = (0.3, std::f64::consts::TAU);
    let s0 = omega * omega * r * r;
    let text = scene(
        cells,
        0.25,
        0.01,
        &format!(
            r#"
[[objects]]
material = "skin"
geometry = {{ type = "circle", center = [0.5, 0.5], radius = {r} }}
spacing = {sp:e}
prestress = {s0:e}
"#,
            sp = 0.25 / cells as f64
        ),
    );
    let mut run = build(&text);
    for p in 0..run.particles.len() {
        let d = run.particles.x[p] - nalgebra::Vector2::new(0.5, 0.5);
        run.particles.v[p] = nalgebra::Vector2::new(-d[1], d[0]) * omega;
    }
    while !run.finished() {
        run.step().expect("step");
    }
    let m = membrane_measures(&run, [0.5, 0.5]);
    let turned = run.particles.x[0] - nalgebra::Vector2::new(0.5, 0.5);
    let angle = turned[1].atan2(turned[0]).to_degrees();
    println!(
        "spinning ring, {cells} cells: mean radius {:.5} (R {r}), mean stress {:.4} (s0 {s0:.4}), \
         stress range {:.4}..{:.4}, point 0 turned to {angle:.2} deg",
        m.mean_radius, m.mean_stress, m.min_stress, m.max_stress,
    );
    (
        (m.mean_stress - s0).abs() / s0,
        (m.mean_radius - r).abs() / r,
        angle,
    )
}

#[test]
fn a_ring_in_rigid_rotation_keeps_its_stress() {
    // The tangential stress is a scalar of the rotating local frame, so a
    // quarter revolution leaves it at s₀ up to the discretisation error,
    // which halves with the cell size (a frame-dependent update would not
    // converge). Measured: 4.0 % at 32 cells, 2.1 % at 64.
    let (e32, r32, a32) = spinning_ring(32);
    let (e64, r64, a64) = spinning_ring(64);
    for a in [a32, a64] {
        assert!((a - 90.0).abs() < 1.0, "turned {a} deg");
    }
    assert!(r32 < 0.005 && r64 < 0.005, "radius errors {r32} {r64}");
    assert!(e32 < 0.05 && e64 < 0.025, "stress errors {e32} {e64}");
    assert!(
        e64 < 0.6 * e32,
        "stress error must shrink with h: {e32} -> {e64}"
    );
}

/// A ring of radius 0.3 around gas points (ρ = 1, p = 1, γ = 1.4, viscosity
/// `mu`, artificial viscosity `kappa`) with prestress `s0`, on 40² cells.
fn gas_ring(end: f64, mu: f64, kappa: f64, s0: f64) -> String {
    ring_around_gas(40, end, 0.3, 1.0, mu, kappa, s0)
}

/// A ring of `radius` about (0.5, 0.5), its points a quarter of a cell
/// apart, with prestress `s0`, around gas points (ρ = 1, pressure `p`,
/// γ = 1.4, viscosity `mu`, artificial viscosity `kappa`), on `cells`².
fn ring_around_gas(
    cells: usize,
    end: f64,
    radius: f64,
    p: f64,
    mu: f64,
    kappa: f64,
    s0: f64,
) -> String {
    let circle = format!("{{ type = \"circle\", center = [0.5, 0.5], radius = {radius:e} }}");
    let mut text = scene(
        cells,
        end,
        0.01,
        &format!(
            r#"
[[objects]]
material = "skin"
geometry = {circle}
spacing = {spacing:e}
prestress = {s0:e}
[[objects]]
material = "gas"
geometry = {circle}
density = 1.0
pressure = {p:e}
"#,
            spacing = 0.25 / cells as f64,
        ),
    );
    text.push_str(&format!(
        r#"
[[materials]]
name = "gas"
type = "fluid"
frame = "particles"
eos = "ideal_gas"
gamma = 1.4
cv = 1.0
viscosity = {mu:e}
artificial_viscosity = {{ kappa = {kappa:e} }}
"#
    ));
    text
}

#[test]
fn a_gas_filled_ring_holds_laplace_equilibrium_and_its_gas() {
    // Laplace: a membrane of thickness t around a gas at pressure p has hoop
    // stress p r / t. Prestressed to it, the ring stays there: p = 1,
    // r = 0.3, t = 0.01 gives 30.
    let mut run = build(&gas_ring(0.2, 0.01, 0.75, 30.0));
    while !run.finished() {
        run.step().expect("step");
    }
    let m = membrane_measures(&run, [0.5, 0.5]);
    let laplace = m.mean_pressure * m.mean_radius / 0.01;
    let out = gas_outside(&run);
    println!(
        "gas ring: r {:.5}, p {:.5}, hoop {:.4} vs p r / t {:.4}, radii 0/90 deg {:.5}/{:.5}, \
         outside {out}",
        m.mean_radius, m.mean_pressure, m.mean_stress, laplace, m.radius_0, m.radius_90
    );
    assert_eq!(out, 0, "gas points outside the membrane");
    assert!(
        (m.mean_stress - laplace).abs() < 0.02 * laplace,
        "hoop {} vs {laplace}",
        m.mean_stress
    );
    assert!(
        (m.mean_radius - 0.3).abs() < 0.003,
        "radius {}",
        m.mean_radius
    );
}

#[test]
fn inviscid_gas_in_a_ring_conserves_energy() {
    // No viscosity, no artificial viscosity: the ring starts unstressed and
    // oscillates; kinetic + gas internal + membrane strain energy is
    // conserved up to the time discretisation.
    let mut run = build(&gas_ring(0.1, 0.0, 0.0, 0.0));
    let e0 = run.energies().total();
    let mut worst: f64 = 0.0;
    let mut ke_max: f64 = 0.0;
    while !run.finished() {
        run.step().expect("step");
        let e = run.energies();
        worst = worst.max((e.total() - e0).abs() / e0);
        ke_max = ke_max.max(e.kinetic);
    }
    println!(
        "inviscid ring: energy {e0:.6}, worst drift {:.3e}, peak kinetic {ke_max:.4e}",
        worst
    );
    assert!(
        ke_max > 1e-3 * e0,
        "the ring must move (peak kinetic {ke_max})"
    );
    assert!(worst < 1e-3, "energy drift {worst}");
    assert_eq!(gas_outside(&run), 0);
}

#[test]
fn coinciding_neighbours_stop_the_run_naming_step_time_material_and_particle() {
    use mpmice::driver::Model;
    let text = scene(
        16,
        0.01,
        0.01,
        r#"
[[objects]]
material = "skin"
geometry = { type = "polyline", vertices = [[0.0, 0.5], [1.0, 0.5]] }
spacing = 0.05
fixed_ends = true
"#,
    );
    let mut model = mpmice::driver::models::ExplicitSolid { run: build(&text) };
    model
        .step(mpmice::driver::DtRequest {
            value: 1e-4,
            exact: true,
        })
        .expect("first step");
    let p = 7;
    model.run.particles.x[p + 1] = model.run.particles.x[p];
    let e = model
        .step(mpmice::driver::DtRequest {
            value: 1e-4,
            exact: true,
        })
        .map(|_| ())
        .map_err(|e| model.annotate(e))
        .expect_err("coinciding neighbours must stop the run");
    let msg = e.to_string();
    println!("{msg}");
    for word in ["step 1", "particle 7", "`skin`", "neighbour"] {
        assert!(msg.contains(word), "`{word}` missing in: {msg}");
    }
    assert!(msg.contains("t = 1.000000e-4"), "{msg}");
    assert!(model
        .run
        .particles
        .x
        .iter()
        .all(|x| x.iter().all(|v| v.is_finite())));
}

/// York Sec. 4.3's dog-bone (reconstructed, [`DogBone`]) at element size
/// 0.2 to t = 4: the gas pushes the membrane out to a circle and the
/// viscosity brings it to rest. York's three checks: no gas point leaves
/// the membrane (at any recorded time), the shape is a circle, and the
/// membrane's stress is Laplace's p r / t (p from the gas's p V over the
/// enclosed area). The total energy is kept (York: 1.5 % lost at h = 0.4,
/// +0.03 % at 0.05) and the grid's motion has died down.
///
/// Measured (quadratic B-spline, York Eq. 16's continuity density at CFL
/// 0.4): 0 out, hoop −0.95 % from p r / t, radii at 0° and 90° 1.64 %
/// apart (0.43 % at h = 0.1), energy −0.31 %, grid kinetic energy 5e-4 of
/// the total. With GIMP the same run lets 6 gas points through the
/// membrane (they start a few hundredths of a cell inside it and drift
/// onto it). The case's grid density: `the_dog_bone_with_grid_density_…`.
#[test]
fn the_dog_bone_expands_to_a_laplace_circle_and_keeps_its_gas() {
    use mpmice::diagnostics::york_membrane::DogBone;
    let r = dog_bone_h02_to_t4(true);
    let m = r.last;
    let laplace = m.area_pressure * m.mean_radius / DogBone::THICKNESS;
    let hoop = m.mean_stress / laplace - 1.0;
    let round = (m.radius_0 - m.radius_90).abs() / m.mean_radius;
    let total =
        |x: &mpmice::diagnostics::york_membrane::DogBoneSample| x.kinetic + x.internal + x.strain;
    let (first, last) = (&r.history[0], r.history.last().expect("history"));
    let de = total(last) / total(first) - 1.0;
    let grid_ke = last.grid_kinetic / total(first);
    println!(
        "dog-bone h 0.2: out {} (max {}), mean r {:.4}, hoop {hoop:+.4}, radii {round:.4}, \
         energy {de:+.3e}, grid kinetic {grid_ke:.2e}",
        r.outside_end, r.outside_max, m.mean_radius
    );
    assert_eq!(r.outside_max, 0, "gas points left the membrane");
    assert!(hoop.abs() < 0.02, "hoop stress {hoop:+.4} off p r / t");
    assert!(round < 0.025, "radii at 0 and 90 deg differ by {round:.4}");
    assert!(de.abs() < 0.01, "energy changed by {de:+.3e}");
    assert!(
        grid_ke < 2e-3,
        "grid kinetic energy {grid_ke:.2e} of the total"
    );
    // The circle's radius from the final area agrees with the mean radius
    // of the points (the shape is round, not only its two radii).
    let r_area = (m.area / std::f64::consts::PI).sqrt();
    assert!(
        (r_area / m.mean_radius - 1.0).abs() < 5e-3,
        "area radius {r_area:.4} against mean radius {:.4}",
        m.mean_radius
    );
}

/// A hard case (issue 16): a weak ring (E' = 1000, t = 0.01, r = 0.2)
/// around gas at p = 1000, 20 000 times the hoop stress it can hold
/// at its size (Laplace: p r / t = 2e4 against a stretch of 20). It must
/// give a physical result or a clean stop, never NaN: the balloon
/// inflates until the box's fixed walls hold it, the membrane stretched
/// many times over, every value finite, the gas inside the membrane, and
/// the total energy never rising (the walls stop the membrane inelastically,
/// the viscosity dissipates). Measured at 20² cells: the enclosed area
/// 0.988 of the box, largest stretch 7.2, energy −2.1 %, 0 gas points
/// out, largest rise of the total 1.5e-6 in one early step.
#[test]
fn a_weak_membrane_under_a_bursting_pressure_inflates_to_the_walls_without_nan() {
    let text = ring_around_gas(20, 0.2, 0.2, 1000.0, 0.01, 0.75, 0.0)
        .replace("shape = \"gimp\"", "shape = \"quadratic_bspline\"");
    let mut run = build(&text);
    let e0 = run.energies().total();
    let mut e_max: f64 = e0;
    while !run.finished() {
        run.step().expect("step");
        e_max = e_max.max(run.energies().total());
    }
    let e_prev = run.energies().total();
    // An explicit step's energy error is O(Δt²) either way (the total rose by
    // 1.5e-6 in one early step); no rise above it beyond 1e-3.
    assert!(
        e_max <= e0 * (1.0 + 1e-3),
        "energy rose to {e_max} from {e0}"
    );
    let p = &run.particles;
    let finite = (0..p.len()).all(|i| {
        p.x[i].iter().chain(p.v[i].iter()).all(|v| v.is_finite())
            && p.stress.get(i).iter().all(|v| v.is_finite())
            && p.vol[i].is_finite()
            && p.vol[i] > 0.0
    });
    let m = membrane_measures(&run, [0.5, 0.5]);
    let stretch = run
        .membranes
        .stretch(&p.x)
        .into_iter()
        .fold(0.0_f64, f64::max);
    let out = gas_outside(&run);
    let de = e_prev / e0 - 1.0;
    println!(
        "burst: area {:.4} of the box, largest stretch {stretch:.2}, energy {de:+.3e}, out {out}",
        m.area
    );
    assert!(finite, "a non-finite or non-positive particle value");
    assert_eq!(out, 0, "gas points outside the membrane");
    assert!(m.area > 0.9, "enclosed area {:.4} of the box", m.area);
    assert!(stretch > 5.0, "largest stretch {stretch:.2}");
    assert!(de > -0.05, "energy lost {de:+.3e}");
}

/// The dog-bone at h = 0.2, run to t = 4, with the case's grid density at
/// CFL 0.2 or (`continuity`) York Eq. 16's at CFL 0.4 (the dog-bone tests).
fn dog_bone_h02_to_t4(continuity: bool) -> mpmice::diagnostics::york_membrane::DogBoneRun {
    use mpmice::diagnostics::york_membrane::{run_dog_bone, DogBone};
    use mpmice::material::PointDensity;
    let (point_density, cfl) = if continuity {
        (PointDensity::Continuity, 0.4)
    } else {
        (PointDensity::Grid, 0.2)
    };
    run_dog_bone(&DogBone {
        h: 0.2,
        end: 4.0,
        point_density,
        cfl,
        ..DogBone::default()
    })
    .expect("dog-bone runs")
}

/// The case's dog-bone (gas points with `point_density = "grid"`, CFL 0.2)
/// at h = 0.2 to t = 4 against York Table III at this size (mean radius
/// 1.33, point-mean pressure 28.8): the gas points' volumes follow the
/// enclosed area instead of outgrowing it (continuity: 2.1 → 3.5 times it
/// from t = 1.2 to 4, the ignored test below), so their pressure reading is
/// the gas's. Their sum stays above the area by the part-filled nodes along
/// the membrane, an O(h) excess (0.128 / 0.055 / 0.022 at t = 4 at h =
/// 0.2 / 0.1 / 0.05), and steady after t = 1 (1.098 … 1.139).
///
/// Measured: mean radius 1.3277, point-mean pressure 27.90, energy
/// −0.32 %, 0 out, Σ V_p / area 1.128 at the end.
#[test]
fn the_dog_bone_with_grid_density_matches_york_table_iii_and_its_points_fill_the_membrane() {
    let r = dog_bone_h02_to_t4(false);
    let m = r.last;
    let total =
        |x: &mpmice::diagnostics::york_membrane::DogBoneSample| x.kinetic + x.internal + x.strain;
    let (first, last) = (&r.history[0], r.history.last().expect("history"));
    let de = total(last) / total(first) - 1.0;
    let ratio = |x: &mpmice::diagnostics::york_membrane::DogBoneSample| x.gas_volume / x.area;
    let late: Vec<f64> = r.history.iter().filter(|x| x.t >= 1.0).map(ratio).collect();
    let (lo, hi) = late
        .iter()
        .fold((f64::INFINITY, 0.0_f64), |(a, b), &x| (a.min(x), b.max(x)));
    println!(
        "dog-bone h 0.2, grid density: out {}, mean r {:.4}, point-mean p {:.2}, energy {de:+.3e}, \
         sum V / area at the end {:.3}, after t = 1 {lo:.3} … {hi:.3}, {} steps",
        r.outside_max,
        m.mean_radius,
        m.mean_pressure,
        ratio(last),
        r.steps
    );
    assert_eq!(r.outside_max, 0, "gas points left the membrane");
    assert!(
        (m.mean_radius / 1.33 - 1.0).abs() < 0.01,
        "mean radius {}",
        m.mean_radius
    );
    assert!(
        (m.mean_pressure / 28.8 - 1.0).abs() < 0.05,
        "pressure {}",
        m.mean_pressure
    );
    assert!(de.abs() < 0.01, "energy changed by {de:+.3e}");
    assert!(
        (ratio(last) - 1.0).abs() < 0.15,
        "sum V / area {}",
        ratio(last)
    );
    assert!(
        hi - lo < 0.1,
        "sum V / area drifts after t = 1: {lo} … {hi}"
    );
}

/// Open defect (issue 16), kept as a reproducer: the gas points' own
/// volumes with York Eq. 16's continuity density (not the case's: the grid
/// density above is the remedy) should add up to the area inside the
/// membrane. In the dog-bone at h = 0.2 they fall behind it while the
/// membrane overshoots (0.89 of it at t = 0.1), reach 1.54 times it by t = 0.4
/// and go on growing once the area is steady (1.90 at t = 0.8, 3.51 at
/// t = 4, area 5.71–5.76 throughout): an ideal-gas point pushes the nodes
/// with (γ − 1) m e whatever its volume, so nothing holds its J to the
/// space it takes. Taking J from the rate's trace alone (York Eq. 16 to
/// the letter, instead of det(I + Δt L)) gives 4.09; a PIC share of 0.01
/// gives 2.39.
#[test]
#[ignore = "open defect of continuity density: the dog-bone's gas point volumes outgrow the membrane's area (issue 16)"]
fn the_dog_bones_gas_point_volumes_add_up_to_the_enclosed_area() {
    let r = dog_bone_h02_to_t4(true);
    for x in &r.history {
        let ratio = x.gas_volume / x.area;
        assert!(
            (ratio - 1.0).abs() < 0.1,
            "t = {:.2}: gas point volumes {:.3} against the enclosed area {:.3} ({ratio:.3})",
            x.t,
            x.gas_volume,
            x.area
        );
    }
}
