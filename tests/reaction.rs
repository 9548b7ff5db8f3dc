//! Reaction mass exchange in the coupled MPM-ICE step (Guilkey Sec. 3.3
//! steps 4 and 8, Sec. 5: a solid reactant burning on its surface into a
//! product gas at Γ = A K pⁿ), on `cases/reaction_burn.toml`: a slab of
//! reactant against a wall in a closed tube of its product.

use mpmice::coupling::CoupledRun;
use mpmice::diagnostics::explosion::{failed_angles, vent};
use mpmice::driver::models::arrays::cell_material_totals;
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
fn masses<const D: usize>(run: &CoupledRun<D>) -> (f64, f64) {
    let fluid: f64 = (0..run.num_fluids())
        .map(|r| cell_material_totals(&run.fluid, r).mass)
        .sum();
    let solid: f64 = run.fields.iter().map(|f| f.particles.total_mass()).sum();
    (fluid, solid)
}

/// With n = 0 the face regresses at a constant rate: by t = 1 ms exactly
/// K A t = 1.8e-3 kg per m² has become product (A = 1: one face; the wall
/// is a symmetry plane). The fluid gains exactly what the particles lose,
/// and the energy the products received accounts for the energy change.
#[test]
fn constant_rate_burn_converts_exactly_k_a_t() {
    let mut run = run_of(&[]);
    let (f0, s0) = masses(&run);
    let e0 = run.mass_and_energy().1;
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
    // (measured −7.2e-6; −2.6e-3 while the product cell beside the face
    // booked its flow work by Guilkey Eq. 34, see `ice::lagrangian`).
    let e1 = run.mass_and_energy().1;
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
/// products received accounts for the energy change to 1 % (measured
/// −9.4e-4; −6.05e-3 before, met then only because every product trace in
/// the slab took the slab's flow work, at 2.9e7 K and a 20 times smaller
/// Δt).
#[test]
fn very_fast_burn_stays_finite_and_conserves_mass() {
    let mut run = run_of(&[("rate_constant = 1.8", "rate_constant = 2e5")]);
    let (f0, s0) = masses(&run);
    let e0 = run.mass_and_energy().1;
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
    let balance = (run.mass_and_energy().1 - e0 - t.energy) / t.energy;
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

/// The energy balance across burn rates, between the constant-rate case
/// (K = 1.8) and the very fast burn (K = 2e5): at K = 2e3 and 2e4 (0.2 and
/// 2 kg per m² burnt by t = 1e-4 s) exactly K A t becomes product and the
/// energy the products received accounts for the energy change to 1 %
/// (measured −6.4e-5 and +8.6e-7; −3.2e-3 and −3.3e-4 while the product
/// cells beside the face booked their flow work by Guilkey Eq. 34). A guard
/// for changes to how the product
/// takes its room: bounding the free normalisation of the cells beside the
/// face at 2 max(V, V_solid) (tried for the very fast burn's burn-out, not
/// landed) lost 4.6 % and 2.5 % here.
#[test]
fn energy_balance_holds_across_burn_rates() {
    for k in [2e3, 2e4] {
        let mut run = run_of(&[("rate_constant = 1.8", &format!("rate_constant = {k:e}"))]);
        let (f0, s0) = masses(&run);
        let e0 = run.mass_and_energy().1;
        run.advance_to(1e-4).unwrap();
        let (f1, s1) = masses(&run);
        let t = run.reaction_totals();
        let exact = k * 1e-4;
        let balance = (run.mass_and_energy().1 - e0 - t.energy) / t.energy;
        eprintln!(
            "K = {k:e}: burnt {:e} (exact {exact:e}), energy balance {balance:e}",
            t.mass
        );
        assert!(
            (t.mass - exact).abs() < 1e-12 * exact,
            "{} vs {exact}",
            t.mass
        );
        assert!(((f1 + s1) - (f0 + s0)).abs() < 1e-14 * (f0 + s0));
        assert!(balance.abs() < 1e-2, "K = {k:e}: {balance:e}");
    }
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

/// The lumped model of `cases/reaction_burn_confined.toml` (its header):
/// the lid's displacement and velocity at `t_end`, by RK4 with 40 000
/// steps (converged to 1e-9).
fn lumped_lid(t_end: f64) -> (f64, f64) {
    let (k, e_in, g1, rho_s) = (1.8, 1000.0 * 650.0 + 5e6, 0.3, 1800.0);
    let (m_lid, p_out) = (7830.0 * 0.1, 101_325.0);
    let uniaxial = |kk: f64, g: f64| kk + 4.0 / 3.0 * g;
    let c = 0.1 / uniaxial(10e9, 3e9) + 0.1 / uniaxial(160e9, 77e9);
    // p (m/ρ + x + C p) = (γ − 1)(W − C p²/2), the positive root.
    let pressure = |t: f64, y: [f64; 3]| {
        let (b, a) = (y[0] + k * t / rho_s, c * (1.0 + 0.5 * g1));
        if y[2] > 0.0 {
            (-b + (b * b + 4.0 * a * g1 * y[2]).sqrt()) / (2.0 * a)
        } else {
            0.0
        }
    };
    let rhs = |t: f64, y: [f64; 3]| {
        let p = pressure(t, y);
        [y[1], (p - p_out) / m_lid, k * e_in - p * y[1]]
    };
    let n = 40_000;
    let h = t_end / n as f64;
    let mut y = [0.0; 3];
    let axpy =
        |y: [f64; 3], a: f64, d: [f64; 3]| [y[0] + a * d[0], y[1] + a * d[1], y[2] + a * d[2]];
    for i in 0..n {
        let t = i as f64 * h;
        let k1 = rhs(t, y);
        let k2 = rhs(t + 0.5 * h, axpy(y, 0.5 * h, k1));
        let k3 = rhs(t + 0.5 * h, axpy(y, 0.5 * h, k2));
        let k4 = rhs(t + h, axpy(y, h, k3));
        for j in 0..3 {
            y[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
        }
    }
    (y[0], y[1])
}

/// A confined burn pressurises (Guilkey Sec. 5; issue 18): the PBX slab
/// with a steel lid on its burning face (`cases/reaction_burn_confined.toml`).
/// The product is born in cells the solids fill and takes the volume the
/// burnt PBX frees; before that it made its own room there (no pressure
/// rise), and the burn's step limit on its trace stopped the run at once
/// (Δt 1e-18 s). The lid's mean displacement and velocity at 0.2 ms against
/// the lumped model (x = 9.174e-5 m, v = 0.9997 m/s): measured −2.8 % and
/// −4.8 % at 125 cells, −1.3 % and −3.6 % at 250 (before the product cells
/// kept the total-energy form: −2.6 %/−4.6 %, −1.5 %/−4.0 %, and −0.8 %/−3.6 %
/// at 500, not run here). Mass is
/// conserved to round-off.
#[test]
fn confined_burn_drives_the_lid_as_the_lumped_model() {
    let text = include_str!("../cases/reaction_burn_confined.toml");
    let (x_ref, v_ref) = lumped_lid(2e-4);
    let mut errors = Vec::new();
    for cells in [125, 250] {
        let scene = parse(&text.replace("cells = [250]", &format!("cells = [{cells}]"))).unwrap();
        let mut run = build_coupled_run::<1>(&scene).unwrap();
        let (f0, s0) = masses(&run);
        run.advance_to(2e-4).unwrap();
        let (f1, s1) = masses(&run);
        let steel = run
            .materials
            .iter()
            .position(|m| m.name == "steel")
            .unwrap() as u16;
        let (mut m, mut mx, mut mv) = (0.0, 0.0, 0.0);
        for f in &run.fields {
            let p = &f.particles;
            for i in (0..p.len()).filter(|&i| p.material[i] == steel) {
                m += p.mass[i];
                mx += p.mass[i] * (p.x[i][0] - p.x0[i][0]);
                mv += p.mass[i] * p.v[i][0];
            }
        }
        let (ex, ev) = (mx / m / x_ref - 1.0, mv / m / v_ref - 1.0);
        let peak = run.fluid.pressure.iter().copied().fold(0.0, f64::max);
        eprintln!(
            "{cells} cells: lid x {:.5e} ({ex:+.4}), v {:.5} ({ev:+.4}), peak pressure {peak:.3e} Pa",
            mx / m,
            mv / m
        );
        assert!(((f1 + s1) - (f0 + s0)).abs() < 1e-13 * (f0 + s0));
        assert!(ev.abs() < 0.06, "{ev}");
        errors.push(ex.abs());
    }
    assert!(errors[0] < 0.03 && errors[1] < 0.02, "{errors:?}");
    assert!(errors[1] < 0.7 * errors[0], "{errors:?}");
}

/// The 2D confined explosion (`cases/confined_explosion_2d.toml`, Guilkey
/// Sec. 5) at 48 cells a side (the case has 64), in one run to 0.2 ms:
/// - the notched steel ring, pressurised by its burning PBX, fails first
///   at the notch (45°; the ring's symmetry makes the failed points come
///   in pairs about it);
/// - past the rupture the product vents through the notch and mixes with
///   the air, and the run goes on (before the case coupled its two gases,
///   `[fluid] exchange`, the products slipped through the air in the jet
///   and a cell's air went below 0 K at 0.160 ms);
/// - the total mass of all four materials inside the closed domain is
///   conserved to round-off through the burn, the rupture and the vent.
///
/// Measured: first failed points at 43.2° and 46.8° at 59.5 µs; at 0.2 ms
/// 84.0 % of the product beyond the ring's outer radius, 101 cells holding
/// both gases at more than 10 % each, the total mass drifting 1.3e-15
/// (3591 steps).
#[test]
fn confined_explosion_2d_ruptures_at_the_notch_then_vents_and_mixes() {
    let text = include_str!("../cases/confined_explosion_2d.toml")
        .replace("cells = [64, 64]", "cells = [48, 48]");
    let mut run = build_coupled_run::<2>(&parse(&text).unwrap()).unwrap();
    let m0 = run.mass_and_energy().0;
    let steel = run.field_index("steel").unwrap();
    let mut first = None;
    let end = 2e-4;
    while run.fluid.time < end * (1.0 - 1e-12) {
        run.step(end - run.fluid.time).unwrap();
        if first.is_none() {
            let angles = failed_angles(&run.fields[steel].particles);
            if !angles.is_empty() {
                first = Some((run.fluid.time, angles));
            }
        }
    }
    let (t_fail, angles) = first.expect("the container fails");
    let (air, products) = (
        run.fluid_index("air").unwrap(),
        run.fluid_index("products").unwrap(),
    );
    // Beyond the ring's outer radius, r = 40 mm.
    let vented = vent(&run, products, air, |x| x[0].hypot(x[1]) > 0.04);
    let mixed = vented.mixed_cells;
    let drift = (run.mass_and_energy().0 - m0) / m0;
    eprintln!(
        "first failure at {t_fail:e} s at {angles:?} deg; {} steps: product beyond r = 40 mm \
         {:.4}, mixed cells {mixed}, mass drift {drift:e}, reacted {:e} kg",
        run.steps,
        vented.outside_share,
        run.reaction_totals().mass
    );
    assert!(
        angles.iter().all(|a| (a - 45.0).abs() < 5.0),
        "first failed points at {angles:?} deg, the notch is at 45"
    );
    assert!(vented.outside_share > 0.5, "{vented:?}");
    assert!(mixed >= 20, "{mixed} mixed cells");
    assert!(drift.abs() < 1e-12, "{drift:e}");
}

/// Guilkey's own failure (Sec. 5): with no failure model, the ring of the
/// 2D confined explosion (the case, without its Johnson–Cook failure, at
/// 48² cells) still opens, by MPM's separation: initially adjacent steel
/// points that end a whole cell further apart no longer share a node and
/// stop interacting. By 0.14 ms such pairs exist, and in every 10-µs
/// snapshot from 80 µs all of them lie at the notch (measured: none until
/// 110 µs, 2 at 120 µs, 6 at 130 µs and 14 at 140 µs, all at 43.1°–46.9°;
/// at the case's 64² the first pair is at 110 µs and 16 at 120 µs, at
/// 43.5°–46.5°; with the failure model the first pair is a cell apart at
/// 90 µs, after the first failed points at 45 µs).
#[test]
fn confined_explosion_2d_separates_at_the_notch_without_a_failure_model() {
    let case = include_str!("../cases/confined_explosion_2d.toml");
    let failure = case
        .lines()
        .find(|l| l.starts_with("failure = "))
        .expect("the case's steel has a failure model");
    let text = case
        .replace(failure, "")
        .replace("cells = [64, 64]", "cells = [48, 48]");
    let mut run = build_coupled_run::<2>(&parse(&text).unwrap()).unwrap();
    // Initially adjacent steel points now a whole cell further apart, by
    // the angle of the first point of each pair.
    let apart_pairs = |run: &CoupledRun<2>| {
        let p = &run.fields[run.field_index("steel").unwrap()].particles;
        let h = run.fluid.layout.h[0];
        let spacing = h / 2.0; // 2 points per cell per direction
        let mut apart = Vec::new();
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                let d0 = (p.x0[i] - p.x0[j]).norm();
                if d0 <= 1.05 * spacing && (p.x[i] - p.x[j]).norm() - d0 >= h {
                    apart.push(p.x0[i][1].atan2(p.x0[i][0]).to_degrees());
                }
            }
        }
        apart
    };
    let end = 1.4e-4;
    let mut apart = Vec::new();
    for k in 8..=14 {
        let t = k as f64 * 1e-5;
        while run.fluid.time < t * (1.0 - 1e-12) {
            run.step(t - run.fluid.time).unwrap();
        }
        apart = apart_pairs(&run);
        eprintln!(
            "t = {t:.1e}: {} pairs a cell apart, at {apart:?} deg",
            apart.len()
        );
        assert!(
            apart.iter().all(|a| (a - 45.0).abs() < 5.0),
            "t = {t:e}: pairs a cell apart at {apart:?} deg, the notch is at 45"
        );
    }
    assert!(!apart.is_empty(), "the ring has not separated by {end} s");
}

/// The 3D one-eighth confined explosion (`cases/confined_explosion.toml`)
/// at 20 × 20 × 25 cells (the case has 40 × 40 × 50): the intersections
/// fill the notched wall with its hemispherical head and the charge with
/// the volumes of the exact solids (the notched section's area, from its
/// polygon, times the 40 mm half-length, plus an eighth of the spherical
/// shell; the charge's quarter disk times 40 mm plus an eighth of the
/// ball) to within the point lattice's resolution of the curved faces, and
/// through 30 µs of burn the total mass of the four materials is conserved
/// to round-off. (Measured: volumes −0.37 % and +1.31 %, mass drift
/// 2.2e-15. The energy balance is printed, not asserted: the coupled
/// scheme books 5.2 % less than the burn releases here, and about
/// 5.5 % at the end of the 2D and 3D cases; an open defect, see the
/// README.)
/// (This grid is too coarse for the notch, 4 mm deep, to fail first: at
/// 20 cells the head fails first, at 130 µs; at the case's 40 cells the
/// wall fails at the notch first, by 80 µs; see the README.)
#[test]
fn confined_explosion_3d_fills_its_container_and_conserves_mass() {
    use mpmice::scene::Geometry;
    use std::f64::consts::PI;
    let case = include_str!("../cases/confined_explosion.toml");
    assert!(case.contains("cells = [40, 40, 50]"));
    let scene = parse(&case.replace("cells = [40, 40, 50]", "cells = [20, 20, 25]")).unwrap();
    let Geometry::Intersection { parts } = &scene.objects[0].geometry else {
        panic!("the wall is an intersection")
    };
    let Geometry::Polygon { vertices: v } = &parts[1] else {
        panic!("the wall's section is a polygon")
    };
    let n = v.len();
    let area = 0.5
        * (0..n)
            .map(|i| v[i][0] * v[(i + 1) % n][1] - v[(i + 1) % n][0] * v[i][1])
            .sum::<f64>()
            .abs();
    let (half_length, r_in, r_out): (f64, f64, f64) = (0.04, 0.03, 0.04);
    let steel_exact = area * half_length + PI / 6.0 * (r_out.powi(3) - r_in.powi(3));
    let pbx_exact = PI / 4.0 * r_in * r_in * half_length + PI / 6.0 * r_in.powi(3);
    let mut run = build_coupled_run::<3>(&scene).unwrap();
    let volume = |name: &str| {
        let f = run
            .fields
            .iter()
            .find(|f| run.fluid.materials[f.ice_material].name == name)
            .unwrap();
        f.particles.vol.iter().sum::<f64>()
    };
    let (steel, pbx) = (
        volume("steel") / steel_exact - 1.0,
        volume("pbx") / pbx_exact - 1.0,
    );
    let (m0, e0) = run.mass_and_energy();
    let end = 3e-5;
    while run.fluid.time < end * (1.0 - 1e-12) {
        run.step(end - run.fluid.time).unwrap();
    }
    let (m, e) = run.mass_and_energy();
    let released = run.reaction_totals();
    let (drift, balance) = ((m - m0) / m0, (e - e0 - released.energy) / released.energy);
    eprintln!(
        "volume error steel {steel:+.4}, pbx {pbx:+.4}; mass drift {drift:e}, energy balance \
         {balance:+.4} of {:e} J released, reacted {:e} kg",
        released.energy, released.mass
    );
    assert!(steel.abs() < 0.02 && pbx.abs() < 0.02, "{steel} {pbx}");
    assert!(drift.abs() < 1e-12, "{drift:e}");
    assert!(released.mass > 0.0);
}
