//! Probe: the Mach 3 wedge (Guilkey Sec. 4.3) at a refinement factor, on
//! the case's domain or a cropped one (the study's crop: `0.0 0.2`; the tip
//! reaches x = 0.1 at the case's end, so X_LO must stay below about 0.05).
//! `cargo run --release -p probes --bin wedge_probe -- FACTOR [X_LO Y_HI]`
//! (`WEDGE_CASE=other.toml` runs a copy of the case, e.g. with another end).
use mpmice::diagnostics::coupled::measure_wedge_mach3;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let f: usize = args.get(1).map_or(1, |s| s.parse().unwrap());
    let path = std::env::var("WEDGE_CASE").map_or_else(
        |_| {
            std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
                .join("cases/wedge_mach3.toml")
        },
        std::path::PathBuf::from,
    );
    let mut sc = mpmice::scene::load(&path).unwrap();
    let h = 0.8 / sc.grid.cells[0] as f64 / f as f64;
    if let (Some(xl), Some(yh)) = (args.get(2), args.get(3)) {
        sc.grid.lower[0] = xl.parse().unwrap();
        sc.grid.upper[1] = yh.parse().unwrap();
    }
    sc.grid.cells = (0..2)
        .map(|d| ((sc.grid.upper[d] - sc.grid.lower[d]) / h).round() as usize)
        .collect();
    let mut run = mpmice::scene::build_coupled_run::<2>(&sc).unwrap();
    let start = std::time::Instant::now();
    run.advance_to(sc.time.end).unwrap();
    let wall = start.elapsed().as_secs_f64();
    let m = measure_wedge_mach3(&run);
    println!(
        "h {h:.5} cells {:?} angle {:.3} ratio {:.4} steps {} wall {:.1} s",
        sc.grid.cells, m.angle_deg, m.pressure_ratio, run.steps, wall
    );
}
