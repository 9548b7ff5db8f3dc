//! Explicit MPM step throughput on `diagnostics::bench_cases::rotating_block`
//! (2D, 102 400 particles) and `rotating_block_3d` (3D, 52³ = 140 608
//! particles), per shape function and thread count (1 and 2, each on its own
//! rayon pool). Throughput is in particles per step, so criterion's "elem/s"
//! is particle-steps per second.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use mpmice::diagnostics::bench_cases::{
    rotating_block, rotating_block_3d, rotating_block_of, BlockMaterial,
};
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
    // The 3D block: the quadratic B-spline (27 nodes per particle) and GIMP
    // (up to 27 as well, with the particle's extent), 1 and 2 threads.
    let mut g = c.benchmark_group("mpm_step_3d_141k");
    g.sample_size(10);
    for (shape, name) in [
        (ShapeKind::QuadraticBspline, "bspline2"),
        (ShapeKind::Gimp, "gimp"),
    ] {
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool");
            let mut run = rotating_block_3d(shape);
            g.throughput(Throughput::Elements(run.particles.len() as u64));
            g.bench_with_input(BenchmarkId::new(name, threads), &threads, |b, _| {
                pool.install(|| b.iter(|| run.step().expect("step")))
            });
        }
    }
    g.finish();
    // The cost of the constitutive models on the same block (GIMP, one
    // thread): hypo-elastic, + Johnson–Cook plasticity (every point flows),
    // + Johnson–Cook failure, hypo-elastic with tensile failure, and Hencky
    // with multiplicative Johnson–Cook plasticity, without and with
    // Johnson–Cook failure.
    let mut g = c.benchmark_group("mpm_step_2d_100k_materials");
    g.sample_size(10);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    for (material, name) in [
        (BlockMaterial::NeoHookean, "neo_hookean"),
        (BlockMaterial::HypoElastic, "hypo_elastic"),
        (BlockMaterial::JohnsonCook, "johnson_cook"),
        (BlockMaterial::JohnsonCookFailure, "johnson_cook_failure"),
        (BlockMaterial::Tensile, "tensile_failure"),
        (BlockMaterial::HenckyJohnsonCook, "hencky_johnson_cook"),
        (
            BlockMaterial::HenckyJohnsonCookFailure,
            "hencky_johnson_cook_failure",
        ),
    ] {
        let mut run = rotating_block_of(ShapeKind::Gimp, material);
        g.throughput(Throughput::Elements(run.particles.len() as u64));
        g.bench_function(BenchmarkId::new(name, 1), |b| {
            pool.install(|| b.iter(|| run.step().expect("step")))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
