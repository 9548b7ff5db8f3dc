//! Throughput probe on the benchmark block (`diagnostics::bench_cases`):
//! particle-steps per second and the per-phase split of a step.
//! `RAYON_NUM_THREADS=1 cargo run --release -p probes --bin mpm_throughput -- [3d] [linear|gimp|bspline2|bspline3] [steps] [solid|gas|jc|hypo|jcf|tensile|hencky|hencky_jc|hencky_jcf]`
//! (`gas`: the same block as gas points, York Sec. 3.3; `jc`: hypo-elastic
//! with Johnson–Cook plasticity; `hypo`: hypo-elastic, no plasticity;
//! `jcf`: `jc` with Johnson–Cook failure; `tensile`: hypo-elastic with a
//! spall strength; `hencky`: Hencky hyperelastic; `hencky_jc`: Hencky with
//! multiplicative Johnson–Cook plasticity; `hencky_jcf`: `hencky_jc` with
//! Johnson–Cook failure).
//! A leading `3d` (or `MPM_THROUGHPUT_3D=1` in the environment) runs the 3D
//! block instead (`rotating_block_3d_of`: 52³ = 140 608 particles on a 32³
//! grid; neo-Hookean about z is the `mpm_step_3d_141k` bench), of any of
//! the materials above, rotating about z or, with
//! `MPM_THROUGHPUT_AXIS=skew`, about (1, 1, 1) (every tensor component
//! non-zero: the Hencky models' general 3D eigen-solver); the default
//! step count is 30.
use mpmice::diagnostics::bench_cases::{rotating_block_3d_of, rotating_block_of, BlockMaterial};
use mpmice::shape::ShapeKind;
use mpmice::stepper::SolidRun;

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let three_d = if args.first().map(String::as_str) == Some("3d") {
        args.remove(0);
        true
    } else {
        std::env::var("MPM_THROUGHPUT_3D").is_ok_and(|v| !v.is_empty() && v != "0")
    };
    let shape = match args.first().map(String::as_str).unwrap_or("bspline2") {
        "linear" => ShapeKind::Linear,
        "gimp" => ShapeKind::Gimp,
        "bspline3" => ShapeKind::CubicBspline,
        _ => ShapeKind::QuadraticBspline,
    };
    let default_steps = if three_d { 30 } else { 300 };
    let steps: u64 = args
        .get(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(default_steps);
    let material = match args.get(2).map(String::as_str) {
        Some("gas") => BlockMaterial::GasPoint,
        Some("jc") => BlockMaterial::JohnsonCook,
        Some("hypo") => BlockMaterial::HypoElastic,
        Some("jcf") => BlockMaterial::JohnsonCookFailure,
        Some("tensile") => BlockMaterial::Tensile,
        Some("hencky") => BlockMaterial::Hencky,
        Some("hencky_jc") => BlockMaterial::HenckyJohnsonCook,
        Some("hencky_jcf") => BlockMaterial::HenckyJohnsonCookFailure,
        _ => BlockMaterial::NeoHookean,
    };
    if three_d {
        let skew = std::env::var("MPM_THROUGHPUT_AXIS").is_ok_and(|v| v == "skew");
        let axis = if skew {
            [1.0, 1.0, 1.0]
        } else {
            [0.0, 0.0, 1.0]
        };
        let run = rotating_block_3d_of(shape, material, axis.into());
        let dim = if skew { "3D (skew axis)" } else { "3D" };
        measure(run, dim, shape, material, steps);
    } else {
        measure(
            rotating_block_of(shape, material),
            "2D",
            shape,
            material,
            steps,
        );
    }
}

/// Runs `steps` steps of `run` and prints the throughput and phase split.
fn measure<const D: usize>(
    mut run: SolidRun<D>,
    dim: &str,
    shape: ShapeKind,
    material: BlockMaterial,
    steps: u64,
) {
    run.time.max_steps = Some(steps);
    let np = run.particles.len() as f64;
    let start = std::time::Instant::now();
    while !run.finished() {
        run.step().expect("step");
    }
    let wall = start.elapsed().as_secs_f64();
    let yielded = run
        .particles
        .plastic_strain
        .iter()
        .filter(|&&e| e > 0.0)
        .count();
    let t = run.phase_times();
    let ms = |s: f64| 1e3 * s / steps as f64;
    println!(
        "{dim} {shape:?} {material:?}: {np} particles, {steps} steps, {:.3e} particle-steps/s on {} threads; \
         per step: bin {:.2} ms, p2g {:.2} ms, grid {:.2} ms, g2p {:.2} ms",
        np * steps as f64 / wall,
        rayon::current_num_threads(),
        ms(t.bin_s),
        ms(t.p2g_s),
        ms(t.grid_s),
        ms(t.g2p_s)
    );
    if matches!(
        material,
        BlockMaterial::JohnsonCook | BlockMaterial::JohnsonCookFailure
    ) {
        println!("{yielded} of {np} points have yielded");
    }
}
