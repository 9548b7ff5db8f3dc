//! Criterion bench of the coupled MPM-ICE step against the bare MPM and ICE
//! steps on the same particles and cells (the pressurised cylinder of
//! Guilkey 4.1, `cases/pressurized_cylinder.toml` on a 96 × 96 grid): a
//! scene with only solids or only fluids runs the bare path, and the
//! coupled step should cost about their sum (the coupling's own work is
//! the node ↔ cell transfers and the solid's cell state). Each runs on
//! explicit rayon pools of 1 and 2 threads (ids `coupled/1`, `coupled/2`,
//! ...), every one from a fresh copy of the scene (the ICE-only row
//! starts again from it every 1000 steps).
//! `cargo bench --bench coupled_step`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use mpmice::ice::{step_with_dt, IceWorkspace};
use mpmice::scene;

const N: usize = 96;
/// Steps of the ICE-only row after which its state starts again.
const ICE_RESTART: usize = 1000;

fn bench(c: &mut Criterion) {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/pressurized_cylinder.toml");
    let mut sc = scene::load(&path).expect("case");
    sc.grid.cells = vec![N, N];
    let mut g = c.benchmark_group("cylinder_96x96");
    g.sample_size(20);
    // The coupled step's Δt (the ICE limit) on the initial state, used by
    // every row, the bare steps included.
    let dt = scene::build_coupled_run::<2>(&sc)
        .expect("coupled")
        .step(f64::INFINITY)
        .expect("step")
        .dt;
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        let mut run = scene::build_coupled_run::<2>(&sc).expect("coupled");
        // One step before timing, as the single-thread bench always did.
        pool.install(|| run.step(dt).expect("first coupled step"));
        g.bench_with_input(BenchmarkId::new("coupled", threads), &threads, |b, _| {
            pool.install(|| b.iter(|| run.step(dt).expect("coupled step")))
        });
        let mut solid = scene::build_solid_run::<2>(&sc).expect("solid");
        solid.time.dt = Some(dt);
        solid.time.end = f64::INFINITY;
        g.bench_with_input(BenchmarkId::new("mpm_only", threads), &threads, |b, _| {
            pool.install(|| b.iter(|| solid.step().expect("MPM step")))
        });
        let (mut state, params) = scene::build_fluid_run::<2>(&sc).expect("fluid");
        mpmice::ice::equilibrate(&mut state, &params).expect("equilibrate");
        let mut ws = IceWorkspace::new(&state);
        // The fixed Δt outgrows the heated gas's own limit after about 1800
        // steps (Courant 1.04 at step 1785), which a fast enough step
        // reaches within criterion's measurement: the state goes back to
        // its start every `ICE_RESTART` steps (one copy per 1000 steps).
        let start = state.clone();
        let mut steps = 0usize;
        g.bench_with_input(BenchmarkId::new("ice_only", threads), &threads, |b, _| {
            pool.install(|| {
                b.iter(|| {
                    steps += 1;
                    if steps.is_multiple_of(ICE_RESTART) {
                        state.clone_from(&start);
                    }
                    step_with_dt(&mut state, &params, &mut ws, dt).expect("ICE step")
                })
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
