//! Zhang's multiphase MPM (Zhang Secs. 2–3): the block-in-air test — a
//! solid moving with the air must change nothing — under the weak
//! volume-fraction constraint (Eq. 18) and the strong one (Eq. 7), which
//! the paper shows to fail; the phase interaction (Eq. 5); bad input.

use mpmice::diagnostics::zhang_block::{self, BlockCase};
use mpmice::multiphase::MultiphaseRun;
use mpmice::scene::{build_multiphase_run, parse};

fn case(dim: usize, cells: usize, constraint: &'static str, u: [f64; 3], end: f64) -> BlockCase {
    BlockCase {
        dim,
        cells,
        constraint,
        velocity: u,
        end,
        cfl: 0.4,
        solid: "sphere",
        solid_ppc: 3,
    }
}

fn run_block<const D: usize>(c: &BlockCase) -> (f64, f64) {
    let o = zhang_block::run_block::<D>(c).expect("scene");
    assert!(o.completed || c.constraint != "weak", "weak run stopped");
    (o.pressure, o.velocity)
}

fn block_scene(dim: usize, n: usize, constraint: &'static str, u: [f64; 3], end: f64) -> String {
    case(dim, n, constraint, u, end).scene()
}

#[test]
fn weak_constraint_keeps_a_disk_moving_diagonally_with_the_air_unchanged() {
    // 20 × 20 cells of 0.05: 3 cell crossings along each axis (every
    // point crosses a cell face; the changes allowed are round-off's).
    let u = [10.0, 10.0, 0.0];
    let (dp, dv) = run_block::<2>(&case(2, 20, "weak", u, 0.015));
    assert!(dp < 1e-10 && dv < 1e-10, "dp = {dp:e}, dv = {dv:e}");
    // Along a grid axis too.
    let u = [10.0, 0.0, 0.0];
    let (dp, dv) = run_block::<2>(&case(2, 20, "weak", u, 0.015));
    assert!(dp < 1e-10 && dv < 1e-10, "axis: dp = {dp:e}, dv = {dv:e}");
}

#[test]
fn weak_constraint_keeps_a_sphere_moving_diagonally_with_the_air_unchanged() {
    // 3D, 8³ cells of 0.125: two cell crossings along each axis.
    let u = [10.0, 5.0, -7.5];
    let (dp, dv) = run_block::<3>(&case(3, 8, "weak", u, 0.025));
    assert!(dp < 1e-10 && dv < 1e-10, "dp = {dp:e}, dv = {dv:e}");
}

#[test]
fn strong_constraint_turns_the_volume_fraction_error_into_pressure() {
    // Zhang Sec. 3: with Eq. 7 enforced every step the sampled Σθ ≠ 1
    // at the disk's edge drives the pressure at once (Eq. 17's
    // O((Δx)^d / Δt)): after one cell crossing it is off by percents.
    let u = [10.0, 10.0, 0.0];
    let (dp, _) = run_block::<2>(&case(2, 10, "strong", u, 0.01));
    assert!(dp > 1e-2, "dp = {dp:e}");
}

#[test]
fn drag_relaxes_two_phases_to_their_common_velocity_conserving_momentum() {
    // A solid slab moving at 10 m/s through air at rest along x (periodic,
    // 1D-like 2D strip), with drag K: the relative velocity decays and the
    // total momentum stays.
    let text = r#"
[grid]
dim = 2
lower = [0.0, 0.0]
upper = [1.0, 0.1]
cells = [10, 1]
boundary = { x_lower = "periodic", x_upper = "periodic", y_lower = "symmetry", y_upper = "symmetry" }

[time]
end = 0.002

[mpm]
shape = "gimp"

[multiphase]
drag = 1.0e4

[[materials]]
name = "slab"
type = "solid"
model = "linear_elastic"
density = 1000.0
youngs_modulus = 1.0e8
poisson_ratio = 0.3

[[materials]]
name = "air"
type = "fluid"
frame = "particles"
eos = "ideal_gas"
gamma = 1.4
cv = 717.5

[[objects]]
material = "slab"
geometry = { type = "box", lower = [0.4, 0.0], upper = [0.6, 0.1] }
velocity = [10.0, 0.0]
pressure = 1.0e5

[[objects]]
material = "air"
geometry = { type = "box", lower = [0.0, 0.0], upper = [1.0, 0.1] }
except = [0]
density = 1.2
pressure = 1.0e5
"#;
    let scene = parse(text).expect("scene");
    let mut run: MultiphaseRun<2> = build_multiphase_run(&scene).expect("build");
    let momentum = |r: &MultiphaseRun<2>| -> f64 {
        r.phases.iter().map(|ph| ph.particles.momentum()[0]).sum()
    };
    let p0 = momentum(&run);
    let air = run.phase_of("air").unwrap();
    while run.t < 0.002 * (1.0 - 1e-12) {
        let dt = run.stable_dt().min(0.002 - run.t);
        run.step(dt).expect("step");
    }
    // The pressure forces of the phases cancel where the points' volumes
    // tile the space; once the slab has pushed into the air they no longer
    // do exactly (Σθ ≠ 1 by the sampling error of Zhang Eq. 14, times the
    // nodal pressure), so the momentum is conserved to that error only.
    // Measured: 3.1e-6 relative with p_g the gas points' mean pressure,
    // 1.19e-5 with the compressibility-weighted p_g that makes the
    // interface's pressure work balance (which removed the growing mode of
    // the block test); the bound is that measurement's order, 3e-5.
    let p1 = momentum(&run);
    assert!((p1 - p0).abs() < 3e-5 * p0.abs(), "{p0} → {p1}");
    // The air touching the slab was set moving (with no drag it stays at
    // rest: the slab meets it only through the pressure).
    let vmax = run.phases[air]
        .particles
        .v
        .iter()
        .map(|v| v[0])
        .fold(0.0f64, f64::max);
    assert!(vmax > 0.1, "air velocity {vmax}");
}

#[test]
fn bad_multiphase_keys_are_rejected_with_their_path() {
    let base = block_scene(2, 10, "weak", [1.0, 0.0, 0.0], 0.01);
    let cases = [
        (
            "constraint = \"weak\"",
            "constraint = \"tight\"",
            "multiphase.constraint",
        ),
        (
            "constraint = \"weak\"",
            "constraint = \"weak\"\ndrag = -1.0",
            "multiphase.drag",
        ),
        (
            "constraint = \"weak\"",
            "constraint = \"weak\"\nalpha = 1.5",
            "multiphase.alpha",
        ),
        (
            "constraint = \"weak\"",
            "constraint = \"weak\"\npairs = [{ materials = [\"block\", \"water\"], drag = 1.0 }]",
            "multiphase.pairs[0].materials[1]",
        ),
        ("except = [0]", "except = [1]", "objects[1].except[0]"),
        ("except = [0]", "except = [7]", "objects[1].except[0]"),
        (
            "[time]",
            "[time]\nmode = \"implicit\"\ndt = 1e-5",
            "time.mode",
        ),
        (
            "shape = \"gimp\"",
            "shape = \"gimp\"\nupdate = \"usf\"",
            "mpm.update",
        ),
    ];
    for (from, to, key) in cases {
        let text = base.replacen(from, to, 1);
        let e = parse(&text).expect_err(to);
        assert!(e.to_string().contains(key), "{to}: {e}");
    }
    // A solid's `pressure` outside a multiphase scene is rejected.
    let text = base.replace("[multiphase]\nconstraint = \"weak\"\n", "");
    let text = text.replace("periodic", "symmetry");
    let e = parse(&text).expect_err("pressure on a solid");
    assert!(e.to_string().contains("objects[0].pressure"), "{e}");
}

#[test]
fn plate_spall_time_and_plane_match_the_elastic_wave_analysis() {
    // Zhang Sec. 4 (Fig. 2; the paper: 1.12 us computed against 1.18 us,
    // 5 %): the first failure within 5 % of 3 d / c, converging, on the
    // target's middle plane. Measured (`cargo run --release -p verification -- zhang_spall`): time
    // +4.5 % / +2.8 % / +1.7 % and plane 0.28 / 0.17 / 0.12 mm behind it at
    // h = 0.1 / 0.05 / 0.025 mm (about 3 cells: the smeared fronts reach
    // the strength first on the rear side).
    use mpmice::diagnostics::zhang_spall::{analytic, run_spall};
    let (t, x) = analytic();
    let coarse = run_spall(161).expect("run");
    let fine = run_spall(322).expect("run");
    for s in [&coarse, &fine] {
        let err = (s.time - t) / t;
        assert!(err.abs() < 0.05, "{} vs {t} ({err:+.3})", s.time);
    }
    assert!((fine.time - t).abs() < (coarse.time - t).abs());
    assert!((fine.plane - x).abs() < (coarse.plane - x).abs());
    // Within 4 % of the target's thickness (2d = 4.6 mm) at 0.05 mm.
    assert!(
        (fine.plane - x).abs() < 0.04 * 0.0046,
        "plane {} vs {x}",
        fine.plane
    );
}
