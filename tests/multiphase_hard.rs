//! Hard cases of Zhang's multiphase model (issue 19, "Hard cases and bad
//! input"): a 19 000 : 1 density ratio (tungsten in air), K = 1e15 between
//! phases, near-empty gas cells, a phase leaving nodes, failures that name
//! their site, and bad input rejected with its key path.
//!
//! Every scene is a periodic box unless said otherwise, so that the exact
//! answers are simple: a state in equilibrium, or in a uniform motion of
//! every phase, does not change (Zhang Sec. 3); the phase interaction
//! (Zhang Eq. 5) conserves the total momentum, and so do the pressure
//! forces between phases where the sampled Σθ is uniform.

use mpmice::error::Error;
use mpmice::multiphase::MultiphaseRun;
use mpmice::scene::{build_multiphase_run, parse};

/// Tungsten: ρ = 19 300 kg/m³, E = 411 GPa, ν = 0.28 (K = 3.11e11 Pa,
/// longitudinal wave speed 5.2 km/s).
const TUNGSTEN: &str = r#"
[[materials]]
name = "tungsten"
type = "solid"
model = "linear_elastic"
density = 19300.0
youngs_modulus = 4.11e11
poisson_ratio = 0.28
"#;

/// Steel: ρ = 7 850 kg/m³, E = 200 GPa, ν = 0.3.
const STEEL: &str = r#"
[[materials]]
name = "steel"
type = "solid"
model = "linear_elastic"
density = 7850.0
youngs_modulus = 2.0e11
poisson_ratio = 0.3
"#;

// Ideal-gas air (γ = 1.4, c_v = 717.5 J/(kg K)) on points.
use mpmice::diagnostics::zhang_block::AIR_POINTS as AIR;

/// The air's density: tungsten's over 19 000 (the issue's ratio), at
/// p = 1e5 Pa.
const AIR_DENSITY: f64 = 19300.0 / 19000.0;
const P0: f64 = 1e5;

/// A `[[objects]]` entry: a box of `material` at velocity `v`, starting at
/// pressure `P0` (a solid's hydrostatic prestress, the air's state), with
/// 2 points per cell per direction.
fn object(material: &str, lower: [f64; 2], upper: [f64; 2], v: [f64; 2], except: &str) -> String {
    let density = if material == "air" {
        format!("density = {AIR_DENSITY:?}\n")
    } else {
        String::new()
    };
    format!(
        "\n[[objects]]\nmaterial = \"{material}\"\ngeometry = {{ type = \"box\", lower = \
         [{:?}, {:?}], upper = [{:?}, {:?}] }}\nparticles_per_cell = 2\nvelocity = [{:?}, \
         {:?}]\npressure = {P0:?}\n{density}{except}",
        lower[0], lower[1], upper[0], upper[1], v[0], v[1]
    )
}

/// A 2D multiphase scene on the unit square of `cells`² cells, periodic
/// (or with symmetry walls), GIMP, with the `[multiphase]` table's body
/// `table`, the material blocks and the objects.
fn scene(
    cells: usize,
    periodic: bool,
    end: f64,
    table: &str,
    materials: &[&str],
    objects: &[String],
) -> String {
    let bc = if periodic { "periodic" } else { "symmetry" };
    format!(
        r#"
[grid]
dim = 2
lower = [0.0, 0.0]
upper = [1.0, 1.0]
cells = [{cells}, {cells}]
boundary = {{ x_lower = "{bc}", x_upper = "{bc}", y_lower = "{bc}", y_upper = "{bc}" }}

[time]
end = {end:?}
cfl = 0.4

[mpm]
shape = "gimp"

[multiphase]
{table}
{materials}
{objects}
"#,
        materials = materials.concat(),
        objects = objects.concat(),
    )
}

/// A tungsten square [0.3, 0.7]² at `v_w` in air at `v_a` filling the rest
/// of the periodic unit square (20² cells: the square's faces on grid
/// lines, both phases on the same point lattice).
fn tungsten_in_air(v_w: [f64; 2], v_a: [f64; 2], end: f64, table: &str) -> String {
    scene(
        20,
        true,
        end,
        table,
        &[TUNGSTEN, AIR],
        &[
            object("tungsten", [0.3, 0.3], [0.7, 0.7], v_w, ""),
            object("air", [0.0, 0.0], [1.0, 1.0], v_a, "except = [0]\n"),
        ],
    )
}

fn build(text: &str) -> MultiphaseRun<2> {
    let scene = parse(text).expect("scene parses");
    build_multiphase_run(&scene).expect("scene builds")
}

/// Per phase: the largest pressure change |p − P0| (Pa) and velocity change
/// |v − u| (m/s) over its points, `u` per phase.
fn changes(run: &MultiphaseRun<2>, u: &[[f64; 2]]) -> Vec<(f64, f64)> {
    run.phases
        .iter()
        .zip(u)
        .map(|(ph, u)| {
            let p = &ph.particles;
            let (mut dp, mut dv) = (0.0f64, 0.0f64);
            for i in 0..p.len() {
                let pr = -p.stress.get(i).trace() / 3.0;
                dp = dp.max((pr - P0).abs());
                dv = dv.max(((p.v[i][0] - u[0]).powi(2) + (p.v[i][1] - u[1]).powi(2)).sqrt());
            }
            (dp, dv)
        })
        .collect()
}

/// Total momentum of all phases.
fn momentum(run: &MultiphaseRun<2>) -> [f64; 2] {
    let mut m = [0.0; 2];
    for ph in &run.phases {
        let q = ph.particles.momentum();
        m[0] += q[0];
        m[1] += q[1];
    }
    m
}

/// Whether every point's state and every nodal field is finite.
fn all_finite(run: &MultiphaseRun<2>) -> bool {
    let points = run.phases.iter().all(|ph| {
        let p = &ph.particles;
        (0..p.len()).all(|i| {
            p.x[i].iter().all(|c| c.is_finite())
                && p.v[i].iter().all(|c| c.is_finite())
                && p.stress.get(i).iter().all(|c| c.is_finite())
                && p.vol[i].is_finite()
                && p.work_of(i).is_finite()
        })
    });
    let nodes = run.gas_pressure.iter().all(|q| q.is_finite())
        && run
            .phases
            .iter()
            .all(|ph| ph.theta.iter().all(|q| q.is_finite()));
    points && nodes
}

/// Steps `run` with its stable step to `end`, checking after each step that
/// everything is finite and the stable step finite and positive; calls
/// `each` after every step. Returns the smallest stable step.
fn run_to(run: &mut MultiphaseRun<2>, end: f64, mut each: impl FnMut(&MultiphaseRun<2>)) -> f64 {
    let mut dt_min = f64::INFINITY;
    while run.t < end * (1.0 - 1e-12) {
        let dt = run.stable_dt();
        assert!(
            dt.is_finite() && dt > 0.0,
            "stable step {dt} at step {}",
            run.steps
        );
        dt_min = dt_min.min(dt);
        run.step(dt.min(end - run.t)).expect("step");
        assert!(all_finite(run), "not finite after step {}", run.steps);
        each(run);
    }
    dt_min
}

/// Tungsten's bulk modulus E / (3 (1 − 2ν)).
const K_TUNGSTEN: f64 = 4.11e11 / (3.0 * (1.0 - 2.0 * 0.28));

#[test]
fn tungsten_in_air_at_rest_and_moving_with_the_air_changes_nothing() {
    // 19 000 : 1. The exact answer: nothing changes, at rest and in a
    // uniform motion (diagonal, 100 m/s along x: 4 cell crossings along x).
    // The air's pressure must hold to 1e-10 relative; tungsten's pressure
    // can only be resolved to its bulk modulus times the round-off of a
    // strain, K ε = 6.9e-5 Pa (6.9e-10 of p0): it must stay within a few
    // of those, and the velocities within 1e-10 of the speed.
    let floor = K_TUNGSTEN * f64::EPSILON;
    let cases = [([0.0, 0.0], 0.4e-3), ([100.0, 60.0], 2e-3)];
    for (u, end) in cases {
        let mut run = build(&tungsten_in_air(u, u, end, "constraint = \"weak\""));
        let (w, a) = (
            run.phase_of("tungsten").unwrap(),
            run.phase_of("air").unwrap(),
        );
        let mut worst = vec![(0.0f64, 0.0f64); 2];
        let mut trace = Vec::new();
        run_to(&mut run, end, |r| {
            let c = changes(r, &[u, u]);
            for (wk, ck) in worst.iter_mut().zip(&c) {
                *wk = (wk.0.max(ck.0), wk.1.max(ck.1));
            }
            if r.steps % 100 == 0 {
                trace.push(format!("{:.1e}", c[w].0 / floor));
            }
        });
        let speed = (u[0] * u[0] + u[1] * u[1]).sqrt().max(1.0);
        println!(
            "tungsten/air u = {u:?}: {} steps; air max |Δp|/p0 = {:.2e}, |Δv| = {:.2e} m/s; \
             tungsten max |Δp| = {:.2e} Pa = {:.2} K ε, |Δv| = {:.2e} m/s; tungsten |Δp|/(K ε) \
             every 100 steps: {}",
            run.steps,
            worst[a].0 / P0,
            worst[a].1,
            worst[w].0,
            worst[w].0 / floor,
            worst[w].1,
            trace.join(" ")
        );
        assert!(worst[a].0 < 1e-10 * P0, "u = {u:?}: air pressure {worst:?}");
        assert!(
            worst[w].0 < 4.0 * floor,
            "u = {u:?}: tungsten pressure {worst:?}"
        );
        for (dp, dv) in &worst {
            assert!(
                *dv < 1e-10 * speed,
                "u = {u:?}: velocity change {dv:e} ({dp})"
            );
        }
    }
}

/// Nodes (of the first `cells`² block, ghosts aside) where `phase` has mass.
fn occupied(run: &MultiphaseRun<2>, phase: usize) -> Vec<bool> {
    run.phases[phase].gs.mass.iter().map(|&m| m > 0.0).collect()
}

#[test]
fn tungsten_into_still_air_with_drag_conserves_momentum_and_leaves_nodes() {
    // The tungsten square at 100 m/s along x into air at rest, with drag
    // between them, to t = 2 ms (0.2 m: 4 cells). The periodic box has no
    // outside force, so the exact total momentum is constant. The drag
    // (Eq. 5) conserves it to round-off (see the K = 1e15 test), and so do
    // the pressure forces: the mixture sees one reference pressure on the
    // sampling error of Σθ (Zhang Eq. 14), the excess going back to the
    // phases (see `multiphase::MultiphaseRun::advance`). Measured drift
    // 1.9e-15, 2.6e-15 relative without drag and with K = 1e6 (before
    // that: 4.4e-6 and 4.5e-7); bound 1e-12. The total energy, the drag's
    // friction heat counted as stored energy, rises by at most 2.0e-5
    // (without drag, and with K = 1e6 and 1e15) by 2 ms: the open defect
    // of a solid sliding past the gas (the ignored reproducer below),
    // bounded here at 5e-5 so that it cannot grow unseen; the drag heat
    // must be positive.
    // The square leaves the nodes behind it: its phase vanishes there,
    // with no NaN and a finite stable step.
    for (k, momentum_bound, energy_bound) in
        [(0.0, 1e-12, 5e-5), (1e6, 1e-12, 5e-5), (1e15, 1e-12, 5e-5)]
    {
        let end = 2e-3;
        let table = format!("constraint = \"weak\"\ndrag = {k:?}");
        let mut run = build(&tungsten_in_air([100.0, 0.0], [0.0, 0.0], end, &table));
        let w = run.phase_of("tungsten").unwrap();
        let before = occupied(&run, w);
        let m0 = momentum(&run);
        let e0 = run.energies().total();
        let mut e_max = e0;
        let mut drift = 0.0f64;
        let dt_min = run_to(&mut run, end, |r| {
            let m = momentum(r);
            drift = drift.max((m[0] - m0[0]).abs().max(m[1].abs()));
            e_max = e_max.max(r.energies().total());
        });
        let after = occupied(&run, w);
        let left = before
            .iter()
            .zip(&after)
            .filter(|(b, a)| **b && !**a)
            .count();
        let air = run.phase_of("air").unwrap();
        let air_x: f64 = run.phases[air].particles.momentum()[0];
        println!(
            "K = {k:e}: {} steps, Δt_min = {dt_min:.3e} s; momentum {:.6e} → drift {:.2e} \
             relative; air momentum {air_x:.4e}; energy {e0:.6e} → max {:.2e} relative \
             growth, final {:.4e}, drag heat {:.3e}; nodes left by tungsten: {left}",
            run.steps,
            m0[0],
            drift / m0[0],
            (e_max - e0) / e0,
            run.energies().total() / e0 - 1.0,
            run.drag_heat / e0
        );
        assert!(left > 0, "the square left no node");
        assert!(
            drift < momentum_bound * m0[0],
            "K = {k:e}: momentum drift {drift:e}"
        );
        assert!(
            e_max <= e0 * (1.0 + energy_bound),
            "K = {k:e}: energy grew to {e_max}"
        );
        assert!(
            (k == 0.0) == (run.drag_heat == 0.0) && run.drag_heat >= 0.0,
            "K = {k:e}: drag heat {:e}",
            run.drag_heat
        );
    }
}

#[test]
#[ignore = "open defect: without drag a solid sliding past the gas gains energy (see the report)"]
fn without_drag_a_square_sliding_through_air_conserves_energy_like_a_slab() {
    // Reproducer. The tungsten slab spanning the box (no faces along its
    // motion) keeps the total energy to 1.3e-5 relative over 4 ms; the
    // square [0.3, 0.7]², whose top and bottom faces slide past the air,
    // to 3.9e-5. With the weak constraint's mixture velocity weighted by
    // mass (it is by volume now, see `closure::node_rate`) the square
    // gained energy faster and faster, 1.8e-4 by 4 ms, all of it in the
    // gas's internal energy: the air lost 2.7 % of its volume by 3.8 ms.
    // It follows the sampling error of Σθ (Zhang Eq. 14) where the phases
    // move relative to each other: with the air moving along with the
    // square the energy holds to 4e-16, and under the Eulerian constraint
    // (Eq. 2 as printed) the still-air case gained 4.0e-3.
    let end = 4e-3;
    for (lo, hi, label) in [
        ([0.3, 0.0], [0.7, 1.0], "slab"),
        ([0.3, 0.3], [0.7, 0.7], "square"),
    ] {
        let text = scene(
            20,
            true,
            end,
            "constraint = \"weak\"",
            &[TUNGSTEN, AIR],
            &[
                object("tungsten", lo, hi, [100.0, 0.0], ""),
                object("air", [0.0, 0.0], [1.0, 1.0], [0.0, 0.0], "except = [0]\n"),
            ],
        );
        let mut run = build(&text);
        let e0 = run.energies().total();
        let mut worst = 0.0f64;
        run_to(&mut run, end, |r| {
            worst = worst.max((r.energies().total() / e0 - 1.0).abs());
        });
        println!("{label}: max |ΔE|/E0 = {worst:.2e}");
        assert!(worst < 3e-5, "{label}: energy changed by {worst:e} of E0");
    }
}

/// Densities of steel, tungsten and air, in the order of their phases in
/// [`interpenetrating`].
const RHO: [f64; 3] = [7850.0, 19300.0, AIR_DENSITY];

/// Steel, tungsten and air (or only the two solids), each filling the
/// whole periodic box at its own uniform velocity, with drag `k` between
/// every pair: Σθ is uniform (2 or 3), so the only force is the drag.
fn interpenetrating(k: f64, with_air: bool, u: &[[f64; 2]; 3]) -> String {
    let table = format!("constraint = \"weak\"\ndrag = {k:?}");
    let mut materials = vec![STEEL, TUNGSTEN];
    let mut objects = vec![
        object("steel", [0.0, 0.0], [1.0, 1.0], u[0], ""),
        object("tungsten", [0.0, 0.0], [1.0, 1.0], u[1], ""),
    ];
    if with_air {
        materials.push(AIR);
        objects.push(object("air", [0.0, 0.0], [1.0, 1.0], u[2], ""));
    }
    scene(8, true, 1.0, &table, &materials, &objects)
}

/// The backward-Euler exchange (Eq. 5 implicit) of uniform phases of
/// densities `rho` over `dt`: `u_r − u_r⁰ = (Δt/ρ_r) Σ_s K (u_s − u_r)`.
fn implicit_exchange(rho: &[f64], k: f64, dt: f64, u0: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let n = rho.len();
    let a = nalgebra::DMatrix::from_fn(n, n, |r, s| {
        if r == s {
            1.0 + dt * k * (n - 1) as f64 / rho[r]
        } else {
            -dt * k / rho[r]
        }
    });
    let lu = a.lu();
    let mut out = vec![[0.0; 2]; n];
    for d in 0..2 {
        let b = nalgebra::DVector::from_fn(n, |r, _| u0[r][d]);
        let x = lu.solve(&b).expect("regular");
        for r in 0..n {
            out[r][d] = x[r];
        }
    }
    out
}

#[test]
fn drag_of_1e15_relaxes_the_phases_in_one_step_and_stays_stable() {
    // Zhang Eq. 5 with K = 1e15 kg/(m³ s) between two solids (steel and
    // tungsten) and between solids and air. Exact: the momentum Σ ρ_r u_r
    // is kept, and after one step every point moves at the backward-Euler
    // velocity of its phase, within 1/(1 + Δt K Σ 1/ρ) of the common
    // velocity u* = Σ ρ u / Σ ρ (a few 1e-6 of the velocity difference for
    // the solids, ~1e-10 for the air); after that the phases move as one,
    // nothing else changes, over 1000 steps.
    let u0 = [[10.0, 0.0], [-5.0, 3.0], [0.0, -20.0]];
    let k = 1e15;
    for with_air in [false, true] {
        let n = if with_air { 3 } else { 2 };
        let mut run = build(&interpenetrating(k, with_air, &u0));
        let rho = &RHO[..n];
        let total: f64 = rho.iter().sum();
        let star: [f64; 2] =
            std::array::from_fn(|d| (0..n).map(|r| rho[r] * u0[r][d]).sum::<f64>() / total);
        let m0 = momentum(&run);
        let dt = run.stable_dt();
        run.step(dt).expect("first step");
        let exact = implicit_exchange(rho, k, dt, &u0[..n]);
        let mut err = 0.0f64;
        let mut off_star = 0.0f64;
        for (r, ph) in run.phases.iter().enumerate() {
            for v in &ph.particles.v {
                err = err.max((v[0] - exact[r][0]).abs().max((v[1] - exact[r][1]).abs()));
                off_star = off_star.max((v[0] - star[0]).abs().max((v[1] - star[1]).abs()));
            }
        }
        let m1 = momentum(&run);
        let scale = m0[0].abs().max(m0[1].abs());
        let dm1 = (m1[0] - m0[0]).abs().max((m1[1] - m0[1]).abs()) / scale;
        println!(
            "K = 1e15, {n} phases: Δt = {dt:.3e} s; after one step max |v − u*| = \
             {off_star:.2e} m/s (velocity differences 25 m/s), |v − backward Euler| = \
             {err:.2e} m/s, momentum change {dm1:.1e} relative"
        );
        // The velocity differences are O(20 m/s); round-off of the
        // (Δt K / ρ ~ 1e5–1e10)-conditioned 3 × 3 solve is ~1e-16 of that
        // times its condition.
        assert!(err < 1e-6, "{n} phases: {err:e} from the implicit exchange");
        assert!(off_star < 1e-4, "{n} phases: {off_star:e} from u*");
        assert!(dm1 < 1e-14, "{n} phases: momentum {dm1:e}");
        let mut worst = (0.0f64, 0.0f64, 0.0f64);
        for _ in 0..1000 {
            let dt = run.stable_dt();
            assert!(dt.is_finite() && dt > 0.0);
            run.step(dt).expect("step");
            for ph in &run.phases {
                let p = &ph.particles;
                for i in 0..p.len() {
                    let dv = (p.v[i][0] - star[0]).abs().max((p.v[i][1] - star[1]).abs());
                    let dp = (-p.stress.get(i).trace() / 3.0 - P0).abs() / P0;
                    worst = (worst.0.max(dv), worst.1.max(dp), worst.2);
                }
            }
            let m = momentum(&run);
            let dm = (m[0] - m0[0]).abs().max((m[1] - m0[1]).abs()) / scale;
            worst.2 = worst.2.max(dm);
        }
        println!(
            "  over 1000 more steps: max |v − u*| = {:.2e} m/s, max |Δp|/p0 = {:.2e}, momentum \
             drift {:.1e} relative",
            worst.0, worst.1, worst.2
        );
        assert!(worst.0 < 1e-10, "{n} phases: velocity {worst:?}");
        assert!(worst.1 < 1e-9, "{n} phases: pressure {worst:?}");
        assert!(worst.2 < 1e-13, "{n} phases: momentum {worst:?}");
    }
}

#[test]
fn near_empty_gas_cells_keep_the_equilibrium_with_a_finite_step() {
    // The air fills the whole box, the tungsten square too; the air's
    // points inside the square keep their state but hold 1e-6 of their
    // volume and mass: a sliver of gas (θ_air = 1e-6) on every node inside
    // the square. Exact: at rest and in a uniform motion nothing changes.
    // The closure stiffens the sliver's sound speed by √(κ_air / Σθκ) ≈
    // 800: the stable step must stay finite and positive.
    let floor = K_TUNGSTEN * f64::EPSILON;
    for (u, end) in [([0.0, 0.0], 2e-5), ([100.0, 60.0], 4e-5)] {
        let text = scene(
            20,
            true,
            end,
            "constraint = \"weak\"",
            &[TUNGSTEN, AIR],
            &[
                object("tungsten", [0.3, 0.3], [0.7, 0.7], u, ""),
                object("air", [0.0, 0.0], [1.0, 1.0], u, ""),
            ],
        );
        let mut run = build(&text);
        let dt_full = run.stable_dt();
        let (w, a) = (
            run.phase_of("tungsten").unwrap(),
            run.phase_of("air").unwrap(),
        );
        let p = &mut run.phases[a].particles;
        let mut slivers = 0;
        for i in 0..p.len() {
            let x = p.x[i];
            if (0.3..0.7).contains(&x[0]) && (0.3..0.7).contains(&x[1]) {
                p.vol[i] *= 1e-6;
                p.vol0[i] *= 1e-6;
                p.mass[i] *= 1e-6;
                slivers += 1;
            }
        }
        run.nodes(0.0).expect("nodal fields");
        let theta_min = run.phases[a]
            .theta
            .iter()
            .cloned()
            .filter(|&t| t > 0.0)
            .fold(f64::INFINITY, f64::min);
        let mut worst = vec![(0.0f64, 0.0f64); 2];
        let dt_min = run_to(&mut run, end, |r| {
            for (wk, ck) in worst.iter_mut().zip(changes(r, &[u, u])) {
                *wk = (wk.0.max(ck.0), wk.1.max(ck.1));
            }
        });
        let speed = (u[0] * u[0] + u[1] * u[1]).sqrt().max(1.0);
        println!(
            "sliver u = {u:?}: {slivers} air points at 1e-6, smallest θ_air {theta_min:.1e}; \
             Δt {dt_full:.3e} s without the sliver, {dt_min:.3e} s with it ({} steps); air max \
             |Δp|/p0 = {:.2e}, |Δv| = {:.2e}; tungsten |Δp| = {:.2} K ε, |Δv| = {:.2e}",
            run.steps,
            worst[a].0 / P0,
            worst[a].1,
            worst[w].0 / floor,
            worst[w].1
        );
        assert!(theta_min < 2e-6, "no sliver: θ_min {theta_min}");
        assert!(dt_min.is_finite() && dt_min > 0.0);
        assert!(worst[a].0 < 1e-10 * P0, "u = {u:?}: air pressure {worst:?}");
        assert!(
            worst[w].0 < 4.0 * floor,
            "u = {u:?}: tungsten pressure {worst:?}"
        );
        for (dp, dv) in &worst {
            assert!(
                *dv < 1e-10 * speed,
                "u = {u:?}: velocity change {dv:e} ({dp})"
            );
        }
    }
}

/// The message of a step's numerical failure, and its site.
fn failure(e: Error) -> (String, mpmice::error::FailureSite) {
    let msg = e.to_string();
    match e {
        Error::Numerical { site, .. } => (msg, site),
        _ => panic!("not a numerical failure: {msg}"),
    }
}

#[test]
fn failures_name_the_step_time_point_and_phase() {
    let walls = |end| {
        scene(
            20,
            false,
            end,
            "constraint = \"weak\"",
            &[TUNGSTEN, AIR],
            &[
                object("tungsten", [0.3, 0.3], [0.7, 0.7], [100.0, 0.0], ""),
                object("air", [0.0, 0.0], [1.0, 1.0], [0.0, 0.0], "except = [0]\n"),
            ],
        )
    };
    // A tungsten point pushed off the grid after 3 steps.
    let mut run = build(&walls(1e-3));
    for _ in 0..3 {
        let dt = run.stable_dt();
        run.step(dt).expect("step");
    }
    let t3 = run.t;
    let w = run.phase_of("tungsten").unwrap();
    run.phases[w].particles.x[5][0] = 1.5;
    let (msg, site) = failure(run.step(run.stable_dt()).expect_err("off the grid"));
    println!("{msg}");
    assert_eq!(
        (site.step, site.time, site.particle),
        (3, t3, Some(5)),
        "{msg}"
    );
    assert!(
        msg.contains("step 3") && msg.contains("particle 5") && msg.contains("`tungsten`"),
        "{msg}"
    );
    // A NaN in one air point's stress (as a blow-up would leave): the gas
    // pressure of its nodes is not finite; the failure names the point
    // and its phase, not only the node.
    let mut run = build(&walls(1e-3));
    let a = run.phase_of("air").unwrap();
    let stress = &mut run.phases[a].particles.stress;
    let mut s = stress.get(7);
    s[(0, 0)] = f64::NAN;
    stress.set(7, &s);
    let (msg, site) = failure(run.step(run.stable_dt()).expect_err("NaN"));
    println!("{msg}");
    assert_eq!((site.step, site.particle), (0, Some(7)), "{msg}");
    assert!(
        msg.contains("step 0") && msg.contains("particle 7") && msg.contains("`air`"),
        "{msg}"
    );
    // Through the run loop: a fixed step 260 times the stable one; the
    // run stops naming step, time, point and material.
    let tmp = tempfile::tempdir().expect("tmp");
    let mut s = parse(&walls(2e-2)).expect("scene");
    s.time.dt = Some(1e-3);
    let opts = mpmice::driver::RunOptions::quiet(tmp.path().join("run"), 1);
    let msg = mpmice::driver::run_scene(&s, &opts)
        .expect_err("blows up")
        .to_string();
    println!("{msg}");
    assert!(
        msg.contains("step ") && msg.contains("t = ") && msg.contains("particle "),
        "{msg}"
    );
    assert!(
        msg.contains("`tungsten`") || msg.contains("`air`"),
        "names the phase: {msg}"
    );
}

#[test]
fn bad_multiphase_input_is_rejected_with_its_key_and_the_allowed_values() {
    let base = tungsten_in_air(
        [100.0, 0.0],
        [0.0, 0.0],
        1e-3,
        "constraint = \"weak\"\ndrag = 1.0",
    );
    assert!(parse(&base).is_ok());
    let pair = |a: &str, b: &str, k: &str| {
        format!("drag = 1.0\npairs = [{{ materials = [\"{a}\", \"{b}\"], drag = {k} }}]")
    };
    let helium = "\n[[materials]]\nname = \"helium\"\ntype = \"fluid\"\nframe = \"particles\"\n\
                  eos = \"ideal_gas\"\ngamma = 1.66\ncv = 3116.0\n";
    // (replace, by, key path, words of the message naming what is allowed)
    let cases: Vec<(&str, String, &str, Vec<&str>)> = vec![
        // The constraint: one of three.
        (
            "constraint = \"weak\"",
            "constraint = \"tight\"".into(),
            "multiphase.constraint",
            vec!["weak", "strong", "eulerian"],
        ),
        // Negative or non-finite drag, scalar and per pair.
        (
            "drag = 1.0",
            "drag = -1.0".into(),
            "multiphase.drag",
            vec![">= 0"],
        ),
        (
            "drag = 1.0",
            "drag = nan".into(),
            "multiphase.drag",
            vec![">= 0"],
        ),
        (
            "drag = 1.0",
            "drag = inf".into(),
            "multiphase.drag",
            vec!["finite"],
        ),
        (
            "drag = 1.0",
            pair("tungsten", "air", "-5.0"),
            "multiphase.pairs[0].drag",
            vec![">= 0"],
        ),
        // Pairs naming unknown materials, one material twice, a pair twice,
        // or one material only.
        (
            "drag = 1.0",
            pair("tungsten", "water", "1.0"),
            "multiphase.pairs[0].materials[1]",
            vec!["tungsten", "air"],
        ),
        (
            "drag = 1.0",
            pair("air", "air", "1.0"),
            "multiphase.pairs[0].materials",
            vec!["two different"],
        ),
        (
            "drag = 1.0",
            "pairs = [{ materials = [\"tungsten\", \"air\"], drag = 1.0 }, { materials = \
             [\"air\", \"tungsten\"], drag = 2.0 }]"
                .into(),
            "multiphase.pairs[1].materials",
            vec!["pairs[0]"],
        ),
        (
            "drag = 1.0",
            "pairs = [{ materials = [\"tungsten\"], drag = 1.0 }]".into(),
            "multiphase.pairs[0].materials",
            vec!["2"],
        ),
        // α (the phases' share of Eq. 1) outside [0, 1].
        (
            "drag = 1.0",
            "alpha = 1.5".into(),
            "multiphase.alpha",
            vec!["[0, 1]"],
        ),
        (
            "drag = 1.0",
            "alpha = -0.1".into(),
            "multiphase.alpha",
            vec!["[0, 1]"],
        ),
        (
            "drag = 1.0",
            "alpha = nan".into(),
            "multiphase.alpha",
            vec!["[0, 1]"],
        ),
        (
            "drag = 1.0",
            "phases = [{ material = \"air\", alpha = -0.5 }]".into(),
            "multiphase.phases[0].alpha",
            vec!["[0, 1]"],
        ),
        (
            "drag = 1.0",
            "phases = [{ material = \"water\", alpha = 0.5 }]".into(),
            "multiphase.phases[0].material",
            vec!["tungsten", "air"],
        ),
        (
            "drag = 1.0",
            "phases = [{ material = \"air\", alpha = 0.5 }, { material = \"air\", alpha = 0.2 \
             }]"
            .into(),
            "multiphase.phases[1].material",
            vec!["phases[0]"],
        ),
        // Unknown keys of the table.
        (
            "drag = 1.0",
            "drag = 1.0\nk = 3.0".into(),
            "multiphase.k",
            vec!["constraint", "drag", "alpha", "pairs", "phases"],
        ),
        // Phases whose EOS does not fit: a gas point without γ or c_v, with
        // a key its EOS does not read, with keys of another EOS missing; a
        // solid with a gas key; two gases; a fluid in the cells.
        (
            "gamma = 1.4\n",
            String::new(),
            "materials[1].gamma",
            vec!["missing"],
        ),
        (
            "cv = 717.5\n",
            String::new(),
            "materials[1].cv",
            vec!["missing"],
        ),
        (
            "cv = 717.5\n",
            "cv = 717.5\np_inf = 1.0e8\n".into(),
            "materials[1].p_inf",
            vec!["gamma, cv"],
        ),
        (
            "eos = \"ideal_gas\"",
            "eos = \"stiffened_gas\"".into(),
            "materials[1].p_inf",
            vec!["missing"],
        ),
        (
            "poisson_ratio = 0.28\n",
            "poisson_ratio = 0.28\ngamma = 1.4\n".into(),
            "materials[0].gamma",
            vec!["fluid"],
        ),
        (
            "cv = 717.5\n",
            format!("cv = 717.5\n{helium}"),
            "materials[2]",
            vec!["at most one gas"],
        ),
        (
            "frame = \"particles\"",
            "frame = \"cells\"".into(),
            "materials[1]",
            vec!["frame = \"particles\""],
        ),
        // The gas's state: a density or pressure its EOS cannot take.
        (
            "density = 1.0157894736842106",
            "density = 0.0".into(),
            "objects[1].density",
            vec!["> 0"],
        ),
    ];
    let gas_pressure = base.rfind("pressure = 100000.0").expect("air pressure");
    let mut bad_gas = base.clone();
    bad_gas.replace_range(gas_pressure..gas_pressure + 19, "pressure = -1.0");
    let e = parse(&bad_gas)
        .expect_err("negative gas pressure")
        .to_string();
    assert!(
        e.contains("objects[1].pressure") && e.contains("> 0"),
        "{e}"
    );
    let solid_pressure = base.find("pressure = 100000.0").expect("prestress");
    let mut bad_solid = base.clone();
    bad_solid.replace_range(solid_pressure..solid_pressure + 19, "pressure = nan");
    let e = parse(&bad_solid).expect_err("NaN prestress").to_string();
    assert!(
        e.contains("objects[0].pressure") && e.contains("finite"),
        "{e}"
    );
    for (from, to, key, words) in cases {
        assert!(base.contains(from), "{from}");
        let text = base.replacen(from, &to, 1);
        let e = parse(&text).expect_err(&to).to_string();
        println!("{to:?} → {e}");
        assert!(e.contains(&format!("`{key}`")), "{to}: {e}");
        for w in words {
            assert!(e.contains(w), "{to}: `{w}` not in: {e}");
        }
    }
    // Volume fractions of cell-fluid regions have no place in a
    // multiphase scene (every phase is on points).
    for m in ["air", "tungsten"] {
        let text = format!(
            "{base}\n[[regions]]\npressure = 1.0e5\nstates = [{{ material = \"{m}\", \
             volume_fraction = 1.5, density = 1.0 }}]\n"
        );
        let e = parse(&text).expect_err("regions").to_string();
        println!("regions of {m} → {e}");
        assert!(e.contains("`regions"), "{e}");
    }
}

#[test]
fn tungsten_hitting_steel_in_air_conserves_momentum_at_tens_of_gigapascals() {
    // A tungsten block at 500 m/s hits a steel block at rest across one
    // cell of air, in the periodic box (no outside force: the total
    // momentum is exactly constant). The elastic impact pressure is about
    // 20 GPa, 2e5 times the air's, and the nodal pressure at metal nodes is
    // the metals'. Before the mixture's pressure force on the sampling
    // error of Σθ was made conservative, −Σ_l p_g,l G_l made or destroyed
    // momentum wherever the metals' sampled volumes met unevenly (the rod
    // case lost a tenth of its momentum by 20 µs); measured here: drift
    // 1.05e-1 relative before, 3.3e-14 after. Bound 1e-12, and the tungsten
    // must have handed the steel a good part of its momentum.
    let end = 3e-4;
    let text = scene(
        20,
        true,
        end,
        "constraint = \"weak\"\nmin_fraction = 0.2",
        &[TUNGSTEN, STEEL, AIR],
        &[
            object("tungsten", [0.2, 0.3], [0.45, 0.7], [500.0, 0.0], ""),
            object("steel", [0.5, 0.2], [0.8, 0.8], [0.0, 0.0], ""),
            object(
                "air",
                [0.0, 0.0],
                [1.0, 1.0],
                [0.0, 0.0],
                "except = [0, 1]\n",
            ),
        ],
    );
    let mut run = build(&text);
    let (w, s) = (
        run.phase_of("tungsten").unwrap(),
        run.phase_of("steel").unwrap(),
    );
    let m0 = momentum(&run);
    let (mut drift, mut p_max) = (0.0f64, 0.0f64);
    run_to(&mut run, end, |r| {
        let m = momentum(r);
        drift = drift.max((m[0] - m0[0]).abs().max(m[1].abs()));
        for ph in [w, s] {
            let p = &r.phases[ph].particles;
            for i in 0..p.len() {
                p_max = p_max.max(-p.stress.get(i).trace() / 3.0);
            }
        }
    });
    let steel = run.phases[s].particles.momentum()[0];
    println!(
        "tungsten into steel: {} steps; largest metal pressure {p_max:.3e} Pa; momentum drift \
         {:.2e} relative; steel holds {:.3} of the momentum",
        run.steps,
        drift / m0[0],
        steel / m0[0]
    );
    assert!(p_max > 1e10, "impact pressure {p_max:e}");
    assert!(drift < 1e-12 * m0[0], "momentum drift {:e}", drift / m0[0]);
    assert!(steel > 0.2 * m0[0], "steel momentum {steel:e}");
}
