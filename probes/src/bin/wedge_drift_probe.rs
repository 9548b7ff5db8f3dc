//! Probe: the Mach 3 wedge's (Guilkey Sec. 4.3) shock angle and pressure
//! ratio over time, on the `wedge_mach3` study's long domain
//! `[−0.7, 0.8] × [0, 0.2]` at a refinement factor of the case's cells, at
//! 0.36, 0.48, 0.6, 0.72, 0.96 and 1.2 ms (exact: 37.76°, 3.771), with the
//! smeared (default) or the sharp rigid interface
//! (`coupling.rigid_interface`).
//! `cargo run --release -p probes --bin wedge_drift_probe -- FACTOR [sharp]`
use mpmice::coupling::RigidInterface;
use mpmice::diagnostics::coupled::measure_wedge_mach3;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let f: usize = args.get(1).map_or(1, |s| s.parse().unwrap());
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .join("cases/wedge_mach3.toml");
    let mut sc = mpmice::scene::load(&path).unwrap();
    if args.get(2).map(String::as_str) == Some("sharp") {
        sc.coupling.rigid_interface = RigidInterface::Sharp;
    }
    let h = 0.8 / sc.grid.cells[0] as f64 / f as f64;
    sc.grid.lower[0] = -0.7;
    sc.grid.upper[1] = 0.2;
    sc.grid.cells = (0..2)
        .map(|d| ((sc.grid.upper[d] - sc.grid.lower[d]) / h).round() as usize)
        .collect();
    let mut run = mpmice::scene::build_coupled_run::<2>(&sc).unwrap();
    for t in [0.36e-3, 0.48e-3, 0.6e-3, 0.72e-3, 0.96e-3, 1.2e-3] {
        run.advance_to(t).unwrap();
        let m = measure_wedge_mach3(&run);
        println!(
            "t {:.2} ms: angle {:.3} deg, p2/p1 {:.3}",
            t * 1e3,
            m.angle_deg,
            m.pressure_ratio
        );
    }
    println!("h {h:.5}, {} steps", run.steps);
}
