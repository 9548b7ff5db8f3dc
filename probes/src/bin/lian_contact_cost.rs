//! Cost of Lian's coupled step (issue 17): particle-steps and
//! element-steps per second of a 3D case from `cases/`, on 1 and 2
//! threads, with Lian's detection and the gap check, and the step's split:
//! the MPM body's P2G, grid and G2P, the membranes' own update, the contact
//! (mass gradient, map, gaps, forces, correction) and the measure of its
//! loss.
//!
//! `cargo run --release -p probes --bin lian_contact_cost -- [CASE] [H] [STEPS] [ROUNDS]`
//!
//! `CASE` is a Lian case as in `lian_impact_probe` (default
//! `sphere_on_membrane`), `H` the cell and element size (default 1e-3),
//! `STEPS` the steps per run (default 2000, from the start: the contact
//! acts from the first step with Lian's rule, from 100 µs with the gap
//! check), `ROUNDS` the interleaved repetitions (default 3; medians).

use std::time::Instant;

use mpmice::diagnostics::lian_impact::impact_scene;
use mpmice::driver::model::{DtRequest, Model};
use mpmice::driver::models::MembraneContact;
use mpmice::scene::{self, ContactDetectionSpec};

/// One run: wall seconds and the split [p2g, grid, g2p, membrane, contact,
/// loss] in seconds, particles, elements.
fn run(
    sc: &mpmice::scene::Scene,
    steps: u64,
    threads: usize,
) -> anyhow::Result<(f64, [f64; 6], usize, usize)> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    pool.install(|| {
        let mut m = MembraneContact::from_scene(sc)?;
        let start = Instant::now();
        for _ in 0..steps {
            m.step(DtRequest {
                value: f64::INFINITY,
                exact: false,
            })?;
        }
        let wall = start.elapsed().as_secs_f64();
        let ph = m.solid.run.phase_times();
        let c = m.contact.times;
        let split = [
            ph.bin_s + ph.p2g_s,
            ph.grid_s,
            ph.g2p_s,
            c.membrane_s,
            c.contact_s,
            c.loss_s,
        ];
        let elements = m.membranes.meshes.iter().map(|e| e.num_elements()).sum();
        Ok((wall, split, m.solid.run.particles.len(), elements))
    })
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let case = a.get(1).map_or("sphere_on_membrane", String::as_str);
    let h: f64 = a.get(2).map_or(Ok(1e-3), |s| s.parse())?;
    let steps: u64 = a.get(3).map_or(Ok(2000), |s| s.parse())?;
    let rounds: usize = a.get(4).map_or(Ok(3), |s| s.parse())?;
    let base = scene::load(std::path::Path::new(&format!("cases/lian_{case}.toml")))?;
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    println!("{case}, h = {h}, {steps} steps, {rounds} rounds (medians), {cores} cores");
    println!("detection threads particle-steps/s element-steps/s | share of the step: p2g grid g2p membrane contact loss");
    for detection in [ContactDetectionSpec::Approach, ContactDetectionSpec::Gap] {
        let mut sc = impact_scene(&base, h)?;
        sc.contact.get_or_insert_with(Default::default).detection = detection;
        for threads in [1, 2] {
            let mut walls = Vec::new();
            let mut splits = vec![Vec::new(); 6];
            let (mut np, mut ne) = (0, 0);
            for _ in 0..rounds {
                let (w, s, p, e) = run(&sc, steps, threads)?;
                walls.push(w);
                for (k, x) in s.iter().enumerate() {
                    splits[k].push(x / w);
                }
                (np, ne) = (p, e);
            }
            let w = median(&mut walls);
            let shares: Vec<String> = splits
                .iter_mut()
                .map(|v| format!("{:.3}", median(v)))
                .collect();
            println!(
                "{detection:?} {threads} {:.3e} {:.3e} | {}",
                np as f64 * steps as f64 / w,
                ne as f64 * steps as f64 / w,
                shares.join(" ")
            );
        }
    }
    Ok(())
}
