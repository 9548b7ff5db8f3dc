//! Sod L1(ρ) error and median wall time for one ICE variant:
//! `cargo run --release -p probes --bin sod_probe -- high_resolution 0.4 5 400 800 1600`
//! (variant `literal` | `high_resolution` | `hancock` | `hancock_acoustic`,
//! cfl, repetitions,
//! N...). With `REGIONS` set, the L1 error is also split by the nearest
//! wave of the exact solution (rarefaction head and tail, contact, shock);
//! with `DUMP=prefix` the final cells go to `prefix_N.csv`
//! (`x,rho,u,p,rho_exact`).
use mpmice::diagnostics::riemann::{ExactRiemann, PrimitiveState};
use mpmice::ice::{
    run_fluid, shock_tube, Advection, CellLayout, IceBoundary, IceMaterial, IceParams, IceState,
    Limiter, MaterialInit,
};
use mpmice::material::eos::IdealGas;
use nalgebra::SVector;
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
        "hancock_acoustic" => IceParams::hancock_acoustic(bcs),
        _ => IceParams::high_resolution(bcs),
    };
    p.cfl = cfl;
    // Optional overrides from the environment: ALPHA (face_dt_factor),
    // SMOOTH (face_smooth_factor), W (pressure_weight), LIM (advection and
    // face limiter: vl, mc, sb, mm), T0 (start from the exact solution at
    // t0, to see the start-up error).
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
    // WC (pressure_weight_compression), JAC (acoustic_jump), VISC
    // (face_viscosity); a negative value turns the option off.
    let opt = |x: f64| (x >= 0.0).then_some(x);
    if let Some(a) = env("WC") {
        p.pressure_weight_compression = opt(a);
    }
    if let Some(a) = env("JAC") {
        p.acoustic_jump = opt(a);
    }
    if let Some(a) = env("VISC") {
        p.face_viscosity = opt(a);
    }
    // REMAP=0/1 (lagrangian_remap).
    if let Some(a) = env("REMAP") {
        p.lagrangian_remap = a > 0.5;
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
    // CASE=123 (double rarefaction to t = 0.15) or CASE=ratio (1e4
    // pressure ratio to t = 0.012) instead of Sod.
    let case = std::env::var("CASE").unwrap_or_default();
    let ((l, r), t_end) = match case.as_str() {
        "123" => (((1.0, -2.0, 0.4), (1.0, 2.0, 0.4)), 0.15),
        "ratio" => (((1.0, 0.0, 1000.0), (1.0, 0.0, 0.1)), 0.012),
        _ => (((1.0, 0.0, 1.0), (0.125, 0.0, 0.1)), 0.2),
    };
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
            let st = match env("T0") {
                // Start from the exact solution at t0 (no start-up from
                // the discontinuity).
                Some(t0) => {
                    let h = 1.0 / n as f64;
                    let layout = CellLayout::<1>::new(
                        SVector::<f64, 1>::zeros(),
                        SVector::<f64, 1>::new(h),
                        [n],
                    )
                    .unwrap();
                    let mut st = IceState::new(layout, vec![g], |x| {
                        let w = ex.sample((x[0] - 0.5) / t0);
                        let rho = ex
                            .cell_average(x[0] - 0.5 * h, x[0] + 0.5 * h, 0.5, t0, 8)
                            .map_or(w.rho, |a| a.rho);
                        vec![MaterialInit::new(
                            1.0,
                            rho,
                            w.p,
                            SVector::<f64, 1>::new(w.u),
                        )]
                    })
                    .unwrap();
                    st.time = t0;
                    st
                }
                None => shock_tube(g, n, l, r, 0.5).unwrap(),
            };
            let run = match run_fluid(st, &p, t_end, 10_000_000) {
                Ok(run) => run,
                Err(e) => {
                    println!("N {n}: {e}");
                    break;
                }
            };
            walls.push(run.wall_s);
            out = Some(run);
        }
        walls.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let Some(run) = out else { continue };
        let err = ex.l1_density_error(&run.state, 0.5).unwrap();
        if let Ok(path) = std::env::var("DUMP") {
            dump(&ex, &run.state, &format!("{path}_{n}.csv"));
        }
        if std::env::var("REGIONS").is_ok() {
            println!("  {}", region_split(&ex, &run.state));
        }
        println!(
            "{variant} cfl {cfl} N {n:5} L1 {err:.4e} steps {:5} wall median {:.4} s (min {:.4}) {:.3e} cell-steps/s",
            run.steps,
            walls[walls.len() / 2],
            walls[0],
            n as f64 * run.steps as f64 / walls[walls.len() / 2]
        );
    }
}

/// The L1(ρ) error of `state` split by the nearest wave of the exact
/// solution: each cell's error goes to the wave (rarefaction head, tail,
/// contact, shock) whose position at `state.time` is closest to the cell
/// centre. Parts sum to the total error.
fn region_split(ex: &ExactRiemann, state: &mpmice::ice::IceState<1>) -> String {
    let t = state.time;
    let (x0, g) = (0.5, 1.4);
    let (l, r) = (ex.left(), ex.right());
    let (ps, us) = (ex.star_pressure(), ex.star_velocity());
    let (rsl, _) = ex.star_densities().unwrap_or((l.rho, r.rho));
    let cl = (g * l.p / l.rho).sqrt();
    let csl = (g * ps / rsl).sqrt();
    // Right shock speed (Toro Eq. 4.59).
    let cr = (g * r.p / r.rho).sqrt();
    let sr = r.u + cr * ((g + 1.0) / (2.0 * g) * ps / r.p + (g - 1.0) / (2.0 * g)).sqrt();
    let waves = [
        ("head", x0 + (l.u - cl) * t),
        ("tail", x0 + (us - csl) * t),
        ("contact", x0 + us * t),
        ("shock", x0 + sr * t),
    ];
    let layout = &state.layout;
    let h = layout.h[0];
    let mut parts = [0.0; 4];
    for &c in &layout.interior {
        let x = layout.centre(c)[0];
        let avg = ex
            .cell_average(x - 0.5 * h, x + 0.5 * h, x0, t, 4)
            .map(|s| s.rho)
            .unwrap_or(f64::NAN);
        let e = (state.mixture_density(c) - avg).abs();
        let k = (0..4)
            .min_by(|&a, &b| {
                (waves[a].1 - x)
                    .abs()
                    .partial_cmp(&(waves[b].1 - x).abs())
                    .unwrap_or(std::cmp::Ordering::Equal)
            })
            .unwrap_or(0);
        parts[k] += e;
    }
    let n = layout.num_interior() as f64;
    waves
        .iter()
        .zip(parts)
        .map(|((name, _), e)| format!("{name} {:.3e}", e / n))
        .collect::<Vec<_>>()
        .join("  ")
}

/// Writes the final cell values and the exact cell-averaged density.
fn dump(ex: &ExactRiemann, state: &mpmice::ice::IceState<1>, path: &str) {
    let layout = &state.layout;
    let h = layout.h[0];
    let mut out = String::from("x,rho,u,p,rho_exact\n");
    for &c in &layout.interior {
        let x = layout.centre(c)[0];
        let avg = ex
            .cell_average(x - 0.5 * h, x + 0.5 * h, 0.5, state.time, 4)
            .map(|s| s.rho)
            .unwrap_or(f64::NAN);
        out += &format!(
            "{x},{},{},{},{avg}\n",
            state.mixture_density(c),
            state.cells[0].velocity[c][0],
            state.p_eq[c]
        );
    }
    if let Err(e) = std::fs::write(path, out) {
        eprintln!("cannot write {path}: {e}");
    }
}
