//! Explicit MPM step throughput on `diagnostics::bench_cases::rotating_block`
//! (2D, 102 400 particles), per shape function and thread count. Throughput is
//! in particles per step, so criterion's "elem/s" is particle-steps per second.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use mpmice::diagnostics::bench_cases::rotating_block;
use mpmice::shape::ShapeKind;

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
            let mut run = rotating_block(shape);
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
