//! Probe: the adiabatic piston (Guilkey Sec. 4.2) against P1 (V1/V2)^γ.
//! `cargo run --release -p probes --bin piston_probe -- N SPEED RAMP [sharp]`
//! (`sharp`: `coupling.rigid_interface = "sharp"`).
use mpmice::coupling::RigidInterface;
use mpmice::diagnostics::coupled::piston_history;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(120, |s| s.parse().unwrap());
    let speed: f64 = args.get(2).map_or(10.0, |s| s.parse().unwrap());
    let ramp: f64 = args.get(3).map_or(0.02, |s| s.parse().unwrap());
    let interface = if args.get(4).map(String::as_str) == Some("sharp") {
        RigidInterface::Sharp
    } else {
        RigidInterface::Smeared
    };
    let start = std::time::Instant::now();
    let (h, steps) = piston_history(n, speed, ramp, 5.9, interface).unwrap();
    for (r, p, e) in h {
        println!(
            "ratio {r:.3} p {p:.6e} exact {e:.6e} rel {:+.4e}",
            p / e - 1.0
        );
    }
    println!("{steps} steps in {:.2} s", start.elapsed().as_secs_f64());
}
