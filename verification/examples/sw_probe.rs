//! Simple-wave probe: `sw_probe VARIANT EPS T_END N...` prints L1/ε and
//! the observed orders (variants: hancock, hancock_acoustic, high_resolution).
use mpmice::ice::{IceBoundary, IceParams};
use verification::ice_studies::{simple_wave_run, simple_wave_run_diagonal};

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let b = [[IceBoundary::<1>::Periodic, IceBoundary::<1>::Periodic]];
    let mut params = match a[1].as_str() {
        "hancock" => IceParams::hancock(b),
        "hancock_acoustic" => IceParams::hancock_acoustic(b),
        _ => IceParams::high_resolution(b),
    };
    if let Ok(c) = std::env::var("CFL") {
        params.cfl = c.parse()?;
    }
    if let Ok(r) = std::env::var("REMAP") {
        params.lagrangian_remap = r == "1";
    }
    let eps: f64 = a[2].parse()?;
    let t_end: f64 = a[3].parse()?;
    let mut prev: Option<(f64, f64)> = None;
    for n in a[4..].iter().map(|s| s.parse::<usize>()) {
        let n = n?;
        let (err, steps, wall) = if std::env::var("DIAG").is_ok() {
            let b2 =
                std::array::from_fn(|_| [IceBoundary::<2>::Periodic, IceBoundary::<2>::Periodic]);
            let mut p2 = match a[1].as_str() {
                "hancock" => IceParams::hancock(b2),
                "hancock_acoustic" => IceParams::hancock_acoustic(b2),
                _ => IceParams::high_resolution(b2),
            };
            p2.cfl = params.cfl;
            p2.lagrangian_remap = params.lagrangian_remap;
            simple_wave_run_diagonal(&p2, eps, t_end, n)?
        } else {
            simple_wave_run(&params, eps, t_end, n)?
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
