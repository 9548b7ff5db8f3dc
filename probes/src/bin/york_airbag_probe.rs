//! Probe of York Sec. 4.4's airbag (`diagnostics::york_airbag::Airbag`):
//! `cargo run --release -p probes --bin york_airbag_probe -- H MU PIC`
//! (defaults 0.02 m, the study's 0.2 Pa s, 0; `DENSITY=grid` for the air
//! points' grid density) prints what the `york_airbag` study notes per run.
use mpmice::diagnostics::york_airbag::{run_airbag, Airbag};
use mpmice::material::PointDensity;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: f64| args.get(i).map_or(Ok(d), |s| s.parse::<f64>());
    let a = Airbag {
        h: arg(1, 0.02)?,
        gas_viscosity: arg(2, Airbag::default().gas_viscosity)?,
        pic_fraction: arg(3, 0.0)?,
        point_density: match std::env::var("DENSITY").as_deref() {
            Ok("grid") => PointDensity::Grid,
            _ => PointDensity::Continuity,
        },
        ..Airbag::default()
    };
    let r = run_airbag(&a)?;
    let i = r.inflated;
    let gas_ke = r.history.last().map_or(0.0, |s| s.gas_kinetic);
    println!(
        "h {} mu {} pic {} {}: after inflation p {:.1} (pV {:.1}) Pa, volume {:.5} m^3 (gas point volumes {:.5}); gas KE {:.2} J at release, {gas_ke:.2} J at the end; peak penetration {:.4} m at {:.4} s, rebound {:+.3} m/s (end {:+.3}), peak pressure {:.1} (pV {:.1}) Pa, p V^gamma drift {:.2e} (pV {:.2e}), energy error {:.2e}, out max {}, {} steps, {:.1} s",
        a.h, a.gas_viscosity, a.pic_fraction, a.point_density.name(),
        i.mean_pressure, i.volume_pressure, i.volume, i.gas_volume, i.gas_kinetic,
        r.peak_penetration.0, r.peak_penetration.1, r.rebound_velocity, r.end_velocity,
        r.peak_pressure.0, r.peak_pressure.1, r.adiabat_drift.0, r.adiabat_drift.1, r.energy_error,
        r.history.iter().map(|s| s.outside).max().unwrap_or(0), r.steps, r.wall_s
    );
    Ok(())
}
