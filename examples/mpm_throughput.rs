//! Throughput probe on the benchmark block (`diagnostics::bench_cases`):
//! particle-steps per second and the per-phase split of a step.
//! `RAYON_NUM_THREADS=1 cargo run --release --example mpm_throughput -- [linear|gimp|bspline2|bspline3] [steps] [solid|gas|jc|hypo|jcf|tensile]`
//! (`gas`: the same block as gas points, York Sec. 3.3; `jc`: hypo-elastic
//! with Johnson–Cook plasticity; `hypo`: hypo-elastic, no plasticity;
//! `jcf`: `jc` with Johnson–Cook failure; `tensile`: hypo-elastic with a
//! spall strength).
use mpmice::diagnostics::bench_cases::{rotating_block_of, BlockMaterial};
use mpmice::shape::ShapeKind;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let shape = match args.get(1).map(String::as_str).unwrap_or("bspline2") {
        "linear" => ShapeKind::Linear,
        "gimp" => ShapeKind::Gimp,
        "bspline3" => ShapeKind::CubicBspline,
        _ => ShapeKind::QuadraticBspline,
    };
    let steps: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(300);
    let material = match args.get(3).map(String::as_str) {
        Some("gas") => BlockMaterial::GasPoint,
        Some("jc") => BlockMaterial::JohnsonCook,
        Some("hypo") => BlockMaterial::HypoElastic,
        Some("jcf") => BlockMaterial::JohnsonCookFailure,
        Some("tensile") => BlockMaterial::Tensile,
        _ => BlockMaterial::NeoHookean,
    };
    let mut run = rotating_block_of(shape, material);
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
        "{shape:?} {material:?}: {np} particles, {steps} steps, {:.3e} particle-steps/s on {} threads; \
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
