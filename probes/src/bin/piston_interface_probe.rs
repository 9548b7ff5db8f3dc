//! Probe: the adiabatic piston's (Guilkey Sec. 4.2) gas volume and mass
//! balance at a compression ratio: the cells near the piston's face (volume
//! fractions, fill Σ M v / V, air state), the air mass ahead of, inside and
//! behind the piston, and the closed-end pressure and temperature against
//! the adiabat.
//! `cargo run --release -p probes --bin piston_interface_probe -- N RATIO [off|sharp]`
//! (`off`: equilibrate on the cell volume, `ice.normalise_volume = false`;
//! `sharp`: `coupling.rigid_interface = "sharp"`).
use mpmice::coupling::{CoupledRun, RigidInterface};
use mpmice::diagnostics::coupled::piston;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let n: usize = a.get(1).map_or(120, |s| s.parse().unwrap());
    let target: f64 = a.get(2).map_or(5.0, |s| s.parse().unwrap());
    let interface = if a.get(3).map(String::as_str) == Some("sharp") {
        RigidInterface::Sharp
    } else {
        RigidInterface::Smeared
    };
    let mut run = piston(n, 10.0, 0.02, interface).unwrap();
    if a.get(3).map(String::as_str) == Some("off") {
        run.ice.normalise_volume = false;
    }
    let ratio = |run: &CoupledRun<1>| {
        1.0 / (1.0
            + run
                .rigid_displacement(0, run.fluid.time)
                .map_or(0.0, |d| d[0]))
    };
    let lay = run.fluid.layout.clone();
    let t0 = run.fluid.cells[0].temperature[lay.interior[0]];
    while ratio(&run) < target {
        run.step(f64::INFINITY).unwrap();
    }
    let r = ratio(&run);
    let face = 1.0 + run.rigid_displacement(0, run.fluid.time).unwrap()[0];
    let h = 1.2 / n as f64;
    let steel = run.fields[0].ice_material;
    let (air, st) = (&run.fluid.cells[0], &run.fluid.cells[steel]);
    println!("ratio {r:.4}, face at {face:.5} (cell {:.2})", face / h);
    let (mut ahead, mut inside, mut behind, mut steel_ahead) = (0.0, 0.0, 0.0, 0.0);
    for (k, &c) in lay.interior.iter().enumerate() {
        let xc = (k as f64 + 0.5) * h;
        if (xc - face).abs() < 4.5 * h {
            println!(
                "cell {k:4} x {xc:.4}: theta air {:.4} steel {:.4}, fill {:.4} (steel {:.4}), \
                 air mass {:.4e}, rho {:.4}, T {:.2}, p {:.5e}, u {:.3}",
                air.vol_frac[c],
                st.vol_frac[c],
                (air.mass[c] * air.sp_vol[c] + st.mass[c] * st.sp_vol[c]) / h,
                st.mass[c] * st.sp_vol[c] / h,
                air.mass[c],
                1.0 / air.sp_vol[c],
                air.temperature[c],
                run.fluid.pressure[c],
                air.velocity[c][0],
            );
        }
        if xc < face {
            ahead += air.mass[c];
            steel_ahead += st.vol_frac[c] * h;
        } else if xc < face + 0.1 {
            inside += air.mass[c];
        } else {
            behind += air.mass[c];
        }
    }
    let c0 = lay.interior[0];
    let (p0, rho0) = (run.fluid.pressure[c0], 1.0 / air.sp_vol[c0]);
    let p_exact = 101_325.0 * r.powf(1.4);
    let t_exact = t0 * r.powf(0.4);
    println!(
        "air mass ahead of the face {ahead:.5} ({:+.3} % of 1.1768), inside the piston's span \
         {inside:.5}, behind it {behind:.5} (initially 0.11768); steel ahead of the face \
         {:.2} cells",
        (ahead / 1.1768 - 1.0) * 100.0,
        steel_ahead / h
    );
    println!(
        "closed end: p {p0:.5e} ({:+.3} % of P1 r^1.4), T {:.3} ({:+.3} % of adiabatic), \
         p/rho^1.4 {:.1} (initially {:.1})",
        (p0 / p_exact - 1.0) * 100.0,
        air.temperature[c0],
        (air.temperature[c0] / t_exact - 1.0) * 100.0,
        p0 / rho0.powf(1.4),
        101_325.0 / 1.1768f64.powf(1.4)
    );
}
