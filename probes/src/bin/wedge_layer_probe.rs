//! Probe: the Mach 3 wedge (Guilkey Sec. 4.3) over a long run on the case's
//! domain extended upstream to [−0.8, 0.8] × [0, 0.4]: per 0.16 ms, the
//! shock angle, its offset above the tip and p2/p1
//! (`measure_wedge_mach3`), and the mean thickness in cells of the gas
//! layer above the face (0.05–0.15 m behind the tip) that moves within
//! 10 % of the wedge's velocity.
//! `cargo run --release -p probes --bin wedge_layer_probe -- FACTOR [END]`
//! (`WEDGE_K=1e6` overrides `coupling.momentum_exchange`).
use mpmice::diagnostics::coupled::measure_wedge_mach3;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let f: usize = args.get(1).map_or(1, |s| s.parse().unwrap());
    let end: f64 = args.get(2).map_or(1.2e-3, |s| s.parse().unwrap());
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .join("cases/wedge_mach3.toml");
    let text = std::fs::read_to_string(path)
        .unwrap()
        .replace("lower = [0.0, 0.0]", "lower = [-0.8, 0.0]");
    let mut sc = mpmice::scene::parse(&text).unwrap();
    let h = 0.005 / f as f64;
    if let Ok(k) = std::env::var("WEDGE_K") {
        sc.coupling.momentum_exchange = k.parse().unwrap();
    }
    sc.grid.cells = (0..2)
        .map(|d| ((sc.grid.upper[d] - sc.grid.lower[d]) / h).round() as usize)
        .collect();
    let mut run = mpmice::scene::build_coupled_run::<2>(&sc).unwrap();
    let (u_w, ta) = (-1041.3, 20f64.to_radians().tan());
    let mut t_next: f64 = 0.16e-3;
    while run.fluid.time < end * (1.0 - 1e-9) {
        run.advance_to(t_next.min(end)).unwrap();
        let m = measure_wedge_mach3(&run);
        let tip = m.tip_x;
        let lay = &run.fluid.layout;
        let (mut thick, mut cols) = (0.0, 0usize);
        for i in 0..lay.cells[0] {
            let d = lay.lower[0] + (i as f64 + 0.5) * h - tip;
            if !(0.05..=0.15).contains(&d) {
                continue;
            }
            let ys = d * ta;
            let mut top = ys;
            for j in 0..lay.cells[1] {
                let y = lay.lower[1] + (j as f64 + 0.5) * h;
                if y <= ys {
                    continue;
                }
                let c = lay.index([i as isize, j as isize]);
                if (run.fluid.cells[0].velocity[c][0] - u_w).abs() >= 0.1 * u_w.abs() {
                    break;
                }
                top = y + 0.5 * h;
            }
            thick += top - ys;
            cols += 1;
        }
        println!(
            "t {:.3e}: angle {:.3}, offset {:.4} m, p2/p1 {:.4}, layer {:.2} cells",
            run.fluid.time,
            m.angle_deg,
            m.offset,
            m.pressure_ratio,
            thick / cols.max(1) as f64 / h
        );
        t_next += 0.16e-3;
    }
}
