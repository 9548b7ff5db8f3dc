//! Sod L1(ρ) error and median wall time for one ICE variant:
//! `cargo run --release --example sod_probe -- high_resolution 0.4 5 400 800 1600`
//! (variant `literal` | `high_resolution` | `hancock`, cfl, repetitions,
//! N...).
use mpmice::diagnostics::riemann::{ExactRiemann, PrimitiveState};
use mpmice::ice::{run_fluid, shock_tube, Advection, IceBoundary, IceMaterial, IceParams, Limiter};
use mpmice::material::eos::IdealGas;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let variant = a
        .get(1)
        .cloned()
        .unwrap_or_else(|| "high_resolution".into());
    let cfl: f64 = a.get(2).and_then(|s| s.parse().ok()).unwrap_or(0.4);
    let reps: usize = a.get(3).and_then(|s| s.parse().ok()).unwrap_or(3);
    let ns: Vec<usize> = a[4.min(a.len())..]
        .iter()
        .filter_map(|s| s.parse().ok())
        .collect();
    let bcs = [[IceBoundary::Outflow, IceBoundary::Outflow]];
    let mut p = match variant.as_str() {
        "literal" => IceParams::new(bcs),
        "hancock" => IceParams::hancock(bcs),
        _ => IceParams::high_resolution(bcs),
    };
    p.cfl = cfl;
    // Optional overrides from the environment: ALPHA (face_dt_factor),
    // SMOOTH (face_smooth_factor), W (pressure_weight), LIM (advection and
    // face limiter: vl, mc, sb, mm).
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
    if let Some(a) = env("ALPHA") {
        p.face_dt_factor = a;
    }
    if let Some(a) = env("SMOOTH") {
        p.face_smooth_factor = a;
    }
    if let Some(a) = env("W") {
        p.pressure_weight = a;
    }
    if std::env::var("PRED").is_ok() {
        p.face_predictor = true;
    }
    if let Ok(l) = std::env::var("LIM") {
        let lim = match l.as_str() {
            "vl" => Limiter::VanLeer,
            "mc" => Limiter::MonotonizedCentral,
            "mm" => Limiter::Minmod,
            _ => Limiter::Superbee,
        };
        p.advection = Advection::SecondOrder(lim);
        if p.face_reconstruction.is_some() {
            p.face_reconstruction = Some(lim);
        }
    }
    if let Ok(l) = std::env::var("FLIM") {
        p.face_reconstruction = match l.as_str() {
            "vl" => Some(Limiter::VanLeer),
            "mc" => Some(Limiter::MonotonizedCentral),
            "mm" => Some(Limiter::Minmod),
            "none" => None,
            _ => Some(Limiter::Superbee),
        };
    }
    let (l, r) = ((1.0, 0.0, 1.0), (0.125, 0.0, 0.1));
    let ex = ExactRiemann::solve(
        PrimitiveState::new(l.0, l.1, l.2),
        PrimitiveState::new(r.0, r.1, r.2),
        1.4,
    )
    .unwrap();
    for n in ns {
        let mut walls = Vec::new();
        let mut out = None;
        for _ in 0..reps {
            let g = IceMaterial::new("gas", IdealGas::new(1.4, 2.5).unwrap());
            let st = shock_tube(g, n, l, r, 0.5).unwrap();
            let run = run_fluid(st, &p, 0.2, 10_000_000).unwrap();
            walls.push(run.wall_s);
            out = Some(run);
        }
        walls.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let run = out.unwrap();
        let err = ex.l1_density_error(&run.state, 0.5).unwrap();
        println!(
            "{variant} cfl {cfl} N {n:5} L1 {err:.4e} steps {:5} wall median {:.4} s (min {:.4}) {:.3e} cell-steps/s",
            run.steps,
            walls[walls.len() / 2],
            walls[0],
            n as f64 * run.steps as f64 / walls[walls.len() / 2]
        );
    }
}
