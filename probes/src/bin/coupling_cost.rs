//! Cost of the coupled MPM-ICE step against the bare MPM and ICE steps on
//! the same particles and cells (the pressurised cylinder, Guilkey 4.1):
//! `cargo run --release -p probes --bin coupling_cost -- [CELLS] [STEPS] [REPEATS]`.
//! Prints the median wall time per step of each and the ratio
//! coupled / (MPM-only + ICE-only). `HEAT=H` turns on the solid–fluid heat
//! exchange with coefficient `H` (the steel's `c_v` 450 J/(kg K)), to
//! measure what the temperature transfer costs.
use std::time::Instant;

use mpmice::ice::{step_with_dt, IceWorkspace};
use mpmice::scene;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(48, |s| s.parse().unwrap());
    let steps: usize = args.get(2).map_or(200, |s| s.parse().unwrap());
    let repeats: usize = args.get(3).map_or(5, |s| s.parse().unwrap());
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .join("cases/pressurized_cylinder.toml");
    let mut sc = scene::load(&path)?;
    sc.grid.cells = vec![n, n];
    if let Ok(h) = std::env::var("HEAT") {
        sc.coupling.heat_exchange = h.parse()?;
        for m in &mut sc.materials {
            if m.kind == scene::MaterialKind::Solid {
                m.cv = Some(450.0);
            }
        }
    }
    let (mut tc, mut tm, mut tf) = (Vec::new(), Vec::new(), Vec::new());
    let mut dt = 0.0;
    for _ in 0..repeats {
        // Coupled.
        let mut run = scene::build_coupled_run::<2>(&sc)?;
        let start = Instant::now();
        for _ in 0..steps {
            dt = run.step(f64::INFINITY)?.dt;
        }
        tc.push(start.elapsed().as_secs_f64() / steps as f64);
        // MPM only: the same particles and grid, same dt.
        let mut solid = scene::build_solid_run::<2>(&sc)?;
        solid.time.dt = Some(dt);
        solid.time.end = f64::INFINITY;
        let start = Instant::now();
        for _ in 0..steps {
            solid.step()?;
        }
        tm.push(start.elapsed().as_secs_f64() / steps as f64);
        // ICE only: the same cells and fluid, same dt.
        let (mut state, params) = scene::build_fluid_run::<2>(&sc)?;
        mpmice::ice::equilibrate(&mut state, &params)?;
        let mut ws = IceWorkspace::new(&state);
        let start = Instant::now();
        for _ in 0..steps {
            step_with_dt(&mut state, &params, &mut ws, dt)?;
        }
        tf.push(start.elapsed().as_secs_f64() / steps as f64);
    }
    let (c, m, f) = (median(tc), median(tm), median(tf));
    println!(
        "{n}x{n} cells, {steps} steps x {repeats}, {} threads: coupled {:.3} ms/step, MPM-only {:.3}, ICE-only {:.3} (one fluid material), ratio coupled/(MPM+ICE) = {:.2}",
        rayon::current_num_threads(),
        c * 1e3,
        m * 1e3,
        f * 1e3,
        c / (m + f)
    );
    Ok(())
}
