//! Simple-wave probe (the `ice_simple_wave` study at chosen N):
//! `cargo run --release -p verification --example sw_probe -- VARIANT EPS T_END N...`
//! prints L1/ε and the observed order per refinement. VARIANT is one of
//! hancock, hancock_acoustic, high_resolution. Environment: `CFL=c` sets
//! the Courant number, `REMAP=0|1` the Lagrangian remap, `LIM=vl|mc|sb`
//! the limiter (advection and face states), `DIAG=1` runs the wave along
//! the diagonal of the unit square (2D, `N × N` cells).
use mpmice::ice::{Advection, IceBoundary, IceParams, Limiter};
use verification::ice_studies::{simple_wave_run, simple_wave_run_diagonal};

/// The named variant with periodic faces, `CFL` and `REMAP` applied.
fn params<const D: usize>(name: &str) -> anyhow::Result<IceParams<D>> {
    let b = std::array::from_fn(|_| [IceBoundary::<D>::Periodic, IceBoundary::<D>::Periodic]);
    let mut p = match name {
        "hancock" => IceParams::hancock(b),
        "hancock_acoustic" => IceParams::hancock_acoustic(b),
        "high_resolution" => IceParams::high_resolution(b),
        other => anyhow::bail!(
            "unknown variant {other}; allowed: hancock, hancock_acoustic, high_resolution"
        ),
    };
    if let Ok(c) = std::env::var("CFL") {
        p.cfl = c.parse()?;
    }
    if let Ok(r) = std::env::var("REMAP") {
        p.lagrangian_remap = r == "1";
    }
    if let Ok(l) = std::env::var("LIM") {
        let lim = match l.as_str() {
            "vl" => Limiter::VanLeer,
            "mc" => Limiter::MonotonizedCentral,
            "sb" => Limiter::Superbee,
            other => anyhow::bail!("unknown limiter {other}; allowed: vl, mc, sb"),
        };
        p.advection = Advection::SecondOrder(lim);
        p.face_reconstruction = Some(lim);
    }
    Ok(p)
}

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    anyhow::ensure!(a.len() >= 5, "usage: sw_probe VARIANT EPS T_END N [N ...]");
    let eps: f64 = a[2].parse()?;
    let t_end: f64 = a[3].parse()?;
    let diag = std::env::var("DIAG").is_ok();
    let mut prev: Option<(f64, f64)> = None;
    for n in a[4..].iter().map(|s| s.parse::<usize>()) {
        let n = n?;
        let (err, steps, wall) = if diag {
            simple_wave_run_diagonal(&params::<2>(&a[1])?, eps, t_end, n)?
        } else {
            simple_wave_run(&params::<1>(&a[1])?, eps, t_end, n)?
        };
        let order = prev.map(|(e0, n0)| (e0 / err).ln() / (n as f64 / n0).ln());
        println!(
            "N {n:5} L1/eps {err:.4e} steps {steps} wall {wall:.3}s order {}",
            order.map_or("-".into(), |o| format!("{o:.2}"))
        );
        prev = Some((err, n as f64));
    }
    Ok(())
}
