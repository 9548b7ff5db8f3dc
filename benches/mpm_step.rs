//! Explicit MPM step throughput: a 2D neo-Hookean block of ~100k particles
//! (160×160 cells filled with 2×2 particles, 200×200 grid), per shape function
//! and thread count. Throughput is reported in particles per step, so
//! criterion's "elem/s" is particle-steps per second.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use mpmice::grid::{Boundary, Grid};
use mpmice::material::{ElasticConstants, SolidMaterial, SolidModel};
use mpmice::mpm::{ExplicitParams, Particles, UpdateScheme};
use mpmice::shape::ShapeKind;
use mpmice::stepper::{SolidRun, TimeControl};
use nalgebra::SVector;

fn block(shape: ShapeKind) -> SolidRun<2> {
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
            // A slow rigid rotation plus a shear keeps every kernel busy.
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
        max_steps: None,
    };
    SolidRun::new(grid, vec![mat], p, params, time)
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("mpm_step_2d_100k");
    g.sample_size(20);
    for (shape, name) in [
        (ShapeKind::Linear, "linear"),
        (ShapeKind::QuadraticBspline, "bspline2"),
        (ShapeKind::Gimp, "gimp"),
        (ShapeKind::CubicBspline, "bspline3"),
    ] {
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool");
            let mut run = block(shape);
            g.throughput(Throughput::Elements(run.particles.len() as u64));
            g.bench_with_input(BenchmarkId::new(name, threads), &threads, |b, _| {
                pool.install(|| b.iter(|| run.step().expect("step")))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
