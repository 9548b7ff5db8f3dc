//! Explicit ICE step throughput: a 2D 500×500 grid with two materials
//! (air with a helium bubble and a Mach 1.2 shock), per thread count.
//! Throughput is reported in cells × materials per step, so criterion's
//! "elem/s" is cell-steps per second per material.
//!
//! `ice_step_1d_sod`: Sod's shock tube (`cases/sod.toml`, one material,
//! high-resolution variant, CFL 0.4) at 3 200 cells on one thread and at
//! 204 800 cells on 1 and 2 threads; throughput in cells, so "elem/s" is
//! cell-steps per second. The state keeps evolving over the iterations
//! (past the case's end time, the waves leaving through the free ends):
//! the cost of a step hardly depends on where the waves are.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use mpmice::ice::{step, Advection, CellLayout, Limiter};
use mpmice::ice::{
    ExchangeCoefficients, IceBoundary, IceMaterial, IceParams, IceState, IceWorkspace, MaterialInit,
};
use mpmice::material::eos::IdealGas;
use mpmice::scene;
use nalgebra::SVector;

const N: usize = 500;

fn scene() -> IceState<2> {
    let h = 1.0 / N as f64;
    let layout = CellLayout::<2>::new(
        SVector::<f64, 2>::zeros(),
        SVector::<f64, 2>::new(h, h),
        [N, N],
    )
    .expect("layout");
    let air = IceMaterial::new("air", IdealGas::new(1.4, 717.5).expect("air"));
    let he = IceMaterial::new("helium", IdealGas::new(1.66, 3115.6).expect("helium"));
    IceState::new(layout, vec![air, he], |x| {
        let inside = (x[0] - 0.5).powi(2) + (x[1] - 0.5).powi(2) < 0.2f64.powi(2);
        let th = if inside { 1.0 - 1e-6 } else { 1e-6 };
        // Mach 1.2 post-shock state left of x = 0.2.
        let (rho, p, u) = if x[0] < 0.2 {
            (1.61, 1.513e5, SVector::<f64, 2>::new(104.4, 0.0))
        } else {
            (1.2, 1e5, SVector::<f64, 2>::zeros())
        };
        vec![
            MaterialInit::new(1.0 - th, rho, p, u),
            MaterialInit::new(th, 0.17 * p / 1e5, p, u),
        ]
    })
    .expect("state")
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("ice_step_2d_500x500_2mat");
    g.sample_size(10);
    g.throughput(Throughput::Elements((N * N * 2) as u64));
    let bcs = [
        [IceBoundary::Outflow, IceBoundary::Outflow],
        [IceBoundary::Wall, IceBoundary::Wall],
    ];
    // `literal_dbd`: the literal step with the dimension-by-dimension
    // advection instead of corner transport (the cost of the CTU terms);
    // `hancock_no_remap`: Hancock without the Lagrangian remap.
    let mut dbd = IceParams::new(bcs.clone());
    dbd.advection = Advection::DimensionByDimension(Limiter::VanLeer);
    for (name, mut params) in [
        ("literal", IceParams::new(bcs.clone())),
        ("literal_dbd", dbd),
        ("high_resolution", IceParams::high_resolution(bcs.clone())),
        ("hancock", IceParams::hancock(bcs.clone())),
        // The cost of the Lagrangian remap (`lagrangian_remap`).
        (
            "hancock_no_remap",
            IceParams {
                lagrangian_remap: false,
                ..IceParams::hancock(bcs.clone())
            },
        ),
        ("hancock_acoustic", IceParams::hancock_acoustic(bcs.clone())),
    ] {
        params.exchange = Some(ExchangeCoefficients::uniform(2, 1e15, 0.0));
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            let mut state = scene();
            let mut ws = IceWorkspace::new(&state);
            g.bench_with_input(BenchmarkId::new(name, threads), &threads, |b, _| {
                pool.install(|| {
                    b.iter(|| step(&mut state, &params, &mut ws, f64::INFINITY).expect("step"))
                })
            });
        }
    }
    g.finish();
    sod_1d(c);
}

/// The 1D Sod bench (module notes).
fn sod_1d(c: &mut Criterion) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/sod.toml");
    let mut sc = scene::load(&path).expect("case");
    let mut g = c.benchmark_group("ice_step_1d_sod");
    g.sample_size(10);
    for (cells, threads) in [(3200usize, 1usize), (204_800, 1), (204_800, 2)] {
        sc.grid.cells = vec![cells];
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let (mut state, params) = scene::build_fluid_run::<1>(&sc).expect("fluid");
        mpmice::ice::equilibrate(&mut state, &params).expect("equilibrate");
        let mut ws = IceWorkspace::new(&state);
        g.throughput(Throughput::Elements(cells as u64));
        g.bench_with_input(
            BenchmarkId::new(format!("cells_{cells}"), threads),
            &threads,
            |b, _| {
                pool.install(|| {
                    b.iter(|| step(&mut state, &params, &mut ws, f64::INFINITY).expect("step"))
                })
            },
        );
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
