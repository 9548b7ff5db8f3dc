//! Probe: Zhang's rod at one mesh, with the energy of each phase over time
//! (kinetic; stored: stress work, gas internal energy) and the drag heat
//! (taken from the points; beside it the nodal dissipation of Eq. 5),
//! so that the run's energy error can be placed in time and in a phase.
//! `cargo run --release -p probes --bin zhang_rod_probe -- N [END_US] [EVERY_US]`
//! (N cells per rod radius; defaults 50 and 2 µs); `DRAG=f` scales the
//! drag coefficients.
use mpmice::diagnostics::zhang_rod::{run_observed, scene};
use mpmice::multiphase::MultiphaseRun;
use mpmice::scene::build_multiphase_run;

fn main() -> anyhow::Result<()> {
    let a: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("a number"))
        .collect();
    let n = a.first().copied().unwrap_or(2.0) as usize;
    let end = a.get(1).copied().unwrap_or(50.0) * 1e-6;
    let every = a.get(2).copied().unwrap_or(2.0) * 1e-6;
    let mut run: MultiphaseRun<2> = build_multiphase_run(&scene(n, end)?)?;
    if let Ok(f) = std::env::var("DRAG") {
        let f: f64 = f.parse().expect("DRAG: a factor on the drag coefficients");
        run.model.drag.iter_mut().for_each(|k| *k *= f);
    }
    let k0 = run.energies().kinetic;
    let names: Vec<String> = run
        .phases
        .iter()
        .map(|ph| run.materials[ph.material].name.clone())
        .collect();
    println!(
        "R/{n}: {} points; columns t_us P_mm L_mm total/K0-1 then per phase (K, W)/K0 ({}) and drag heat/K0 (the points' loss; the nodes')",
        run.phases.iter().map(|q| q.particles.len()).sum::<usize>(),
        names.join(", ")
    );
    let r = run_observed(run, every, |run, s| {
        let e = run.energies();
        let mut line = format!(
            "{:6.2} {:7.3} {:7.3} {:+.4e}",
            s.t * 1e6,
            s.penetration * 1e3,
            s.length * 1e3,
            (e.kinetic + e.strain) / k0 - 1.0
        );
        for ph in &run.phases {
            line += &format!(
                "  {:.4e} {:.4e}",
                ph.particles.kinetic_energy() / k0,
                ph.particles.strain_energy(&run.materials) / k0
            );
        }
        line += &format!(
            "  {:.4e} ({:.4e} on the nodes) dt {:.2e}",
            run.drag_heat / k0,
            run.drag_dissipation / k0,
            run.stable_dt()
        );
        println!("{line}");
    })?;
    println!(
        "{} steps, {:.1} s, stopped early at {:?}",
        r.steps, r.wall_s, r.stopped_at
    );
    Ok(())
}
