//! Throughput probe: a 2D neo-Hookean block of ~100k particles (as in the
//! criterion bench) stepped N times; prints particle-steps/s and the phase split.
//! `cargo run --release --example mpm_throughput -- [shape] [steps]`
use mpmice::grid::{Boundary, Grid};
use mpmice::material::{ElasticConstants, SolidMaterial, SolidModel};
use mpmice::mpm::{ExplicitParams, Particles, UpdateScheme};
use mpmice::shape::ShapeKind;
use mpmice::stepper::{SolidRun, TimeControl};
use nalgebra::SVector;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let shape = match args.get(1).map(String::as_str).unwrap_or("bspline2") {
        "linear" => ShapeKind::Linear,
        "gimp" => ShapeKind::Gimp,
        "bspline3" => ShapeKind::CubicBspline,
        _ => ShapeKind::QuadraticBspline,
    };
    let steps: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(200);
    let n = 200;
    let grid = Grid::<2>::new(
        SVector::zeros(),
        SVector::repeat(1.0),
        [n, n],
        [[Boundary::Fixed; 2]; 2],
    );
    let mat = SolidMaterial {
        name: "b".into(),
        density: 1000.0,
        model: SolidModel::NeoHookean,
        elastic: ElasticConstants::from_young_poisson(1e6, 0.3),
    };
    let mut p = Particles::<2>::default();
    let h = 1.0 / n as f64;
    let vol = h * h / 4.0;
    for j in 0..320 {
        for i in 0..320 {
            let x = SVector::from([
                0.1 + (i as f64 + 0.5) * h / 2.0,
                0.1 + (j as f64 + 0.5) * h / 2.0,
            ]);
            let v = SVector::from([-(x[1] - 0.5), x[0] - 0.5]) * 0.01;
            p.push(x, v, 1000.0 * vol, vol, SVector::repeat(h / 4.0), 0);
        }
    }
    let params = ExplicitParams {
        shape,
        scheme: UpdateScheme::Usl,
        mass_floor: 1e-12,
        damping: 0.0,
    };
    let c = mat.wave_speed(1000.0);
    let time = TimeControl {
        end: f64::INFINITY,
        cfl: 0.3,
        dt: Some(0.3 * h / c),
        max_steps: Some(steps),
    };
    let mut run = SolidRun::new(grid, vec![mat], p, params, time);
    let np = run.particles.len() as f64;
    let start = std::time::Instant::now();
    while !run.finished() {
        run.step().expect("step");
    }
    let wall = start.elapsed().as_secs_f64();
    let t = run.phase_times();
    println!(
        "{shape:?}: {np} particles, {steps} steps, {:.3e} particle-steps/s on {} threads; per step: bin {:.2} ms, p2g {:.2} ms, grid {:.2} ms, g2p {:.2} ms",
        np * steps as f64 / wall,
        rayon::current_num_threads(),
        1e3 * t.bin_s / steps as f64,
        1e3 * t.p2g_s / steps as f64,
        1e3 * t.grid_s / steps as f64,
        1e3 * t.g2p_s / steps as f64
    );
}
