//! Probe: the adiabatic piston (Guilkey Sec. 4.2) against P1 (V1/V2)^γ.
use mpmice::diagnostics::coupled::piston;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(120, |s| s.parse().unwrap());
    let speed: f64 = args.get(2).map_or(10.0, |s| s.parse().unwrap());
    let mut run = piston(n, speed).unwrap();
    let p1 = 101_325.0;
    let start = std::time::Instant::now();
    let mut next = 1.5;
    loop {
        let t = run.fluid.time;
        let ratio = 1.0 / (1.0 - speed * t);
        if ratio >= 5.9 {
            break;
        }
        run.step(f64::INFINITY).unwrap();
        let ratio = 1.0 / (1.0 - speed * run.fluid.time);
        if ratio >= next {
            let c0 = run.fluid.layout.interior[0];
            let p = run.fluid.pressure[c0];
            let exact = p1 * ratio.powf(1.4);
            println!("ratio {ratio:.3} t {:.5} p {p:.6e} exact {exact:.6e} rel {:+.4e}", run.fluid.time, p / exact - 1.0);
            next += 0.5;
        }
    }
    println!("{} steps in {:.2} s", run.steps, start.elapsed().as_secs_f64());
}
