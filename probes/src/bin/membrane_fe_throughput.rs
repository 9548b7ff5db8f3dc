//! Throughput of Lian's membrane elements: element-steps per second of a
//! pre-tensioned square membrane of N × N Belytschko–Tsay quads (default
//! 200 × 200), with a time split of the four step kernels, and a check
//! that 1 and 2 threads give bit-identical states.
//! `cargo run --release -p probes --bin membrane_fe_throughput -- [N] [steps]`
use std::time::Instant;

use mpmice::diagnostics::membrane_fe::SquareVibration;
use mpmice::membrane::element::MembraneMesh;

/// Runs `steps` steps on `threads` threads; returns the mesh, the wall
/// seconds and the split (forces, trial velocities, positions, stress).
fn run(n: usize, steps: u64, threads: usize) -> (MembraneMesh, f64, [f64; 4]) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let cfg = SquareVibration {
            amplitude: 1e-3,
            ..Default::default()
        };
        let mut m = cfg.mesh(n).expect("mesh");
        let dt = cfg.cfl * m.stable_dt();
        let mut split = [0.0; 4];
        let start = Instant::now();
        for k in 0..steps {
            let t0 = Instant::now();
            m.compute_forces(dt);
            let t1 = Instant::now();
            m.trial_velocities(dt);
            let t2 = Instant::now();
            m.update_positions(dt);
            let t3 = Instant::now();
            m.update_stress(dt, k).expect("step");
            let t4 = Instant::now();
            for (s, (a, b)) in split
                .iter_mut()
                .zip([(t0, t1), (t1, t2), (t2, t3), (t3, t4)])
            {
                *s += (b - a).as_secs_f64();
            }
        }
        (m, start.elapsed().as_secs_f64(), split)
    })
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(200);
    let steps: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(200);
    let mut states = Vec::new();
    for threads in [1, 2] {
        let (m, wall, split) = run(n, steps, threads);
        let ne = m.num_elements() as f64;
        let ms = |s: f64| 1e3 * s / steps as f64;
        println!(
            "{n} x {n} ({ne} elements), {steps} steps on {threads} thread(s): {:.3e} element-steps/s; \
             per step: forces {:.2} ms, trial v {:.2} ms, positions {:.2} ms, stress {:.2} ms",
            ne * steps as f64 / wall,
            ms(split[0]),
            ms(split[1]),
            ms(split[2]),
            ms(split[3])
        );
        states.push((m.x.clone(), m.stress.clone()));
    }
    println!("1 and 2 threads bit-identical: {}", states[0] == states[1]);
}
