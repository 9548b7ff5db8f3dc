//! Median wall and CPU time and RMS velocity error of the `ice_low_mach`
//! vortex (A = 0.5, γ = 1.4, c = 100, t = 1) for one mode:
//! `cargo run --release -p probes --bin low_mach_probe -- MODE CFL REPS N...`
//! with MODE `explicit` | `direct` | `pcg_multigrid` | `pcg_jacobi`
//! (semi-implicit modes use the convective predictor β = 1 unless
//! `BETA=0`; `T_END` overrides the end time). Prints one line per N:
//! `N error median_wall median_cpu steps linear_per_step walls...`.
//!
//! Measured 2026-11-21 on the shared 2-core machine (load 7.8–8.5; three
//! interleaved rounds of one run each, medians; 256² at load ~5–8, the
//! explicit 256² run once), speed-up = explicit time interpolated log-log
//! at the same RMS velocity error / semi-implicit time:
//!
//! | mode (β = 1) | N | error | wall [s] | CPU [s] | speed-up wall / CPU |
//! |---|---:|---:|---:|---:|---:|
//! | explicit CFL 1 | 64 | 1.436e-3 | 4.22 | 2.83 | — |
//! | explicit CFL 1 | 128 | 4.317e-4 | 31.9 | 20.9 | — |
//! | explicit CFL 1 | 256 | 1.283e-4 | 158 | 154 | — |
//! | pcg_multigrid CFL 50 | 64 | 1.886e-3 | 0.145 | 0.140 | 18.3x / 13.7x |
//! | pcg_multigrid CFL 50 | 128 | 8.532e-4 | 1.35 | 0.96 | 7.5x / 7.0x |
//! | pcg_multigrid CFL 50 | 256 | 4.111e-4 | 14.9 | 7.65 | 2.3x / 3.0x |
//! | pcg_multigrid CFL 20 | 128 | 5.066e-4 | 3.92 | 2.22 | 6.2x / 7.2x |
//! | pcg_multigrid CFL 20 | 256 | 1.989e-4 | 21.8 | 18.9 | 4.1x / 4.0x |
//! | direct CFL 50 | 128 | 8.532e-4 | 3.52 | 1.92 | 2.9x / 3.5x |
use mpmice::ice::{
    periodic_vortex, periodic_vortex_exact, run_fluid, IceBoundary, IceMaterial, IceParams,
    LinearSolver, SemiImplicit,
};
use mpmice::material::eos::IdealGas;

/// CPU seconds (user + system, all threads) of this process.
fn cpu_s() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<f64> = rest
        .split_whitespace()
        .map(|x| x.parse().unwrap_or(f64::NAN))
        .collect();
    match (f.get(11), f.get(12)) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => f64::NAN,
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let mode = a.get(1).cloned().unwrap_or_else(|| "pcg_multigrid".into());
    let cfl: f64 = a.get(2).and_then(|s| s.parse().ok()).unwrap_or(50.0);
    let reps: usize = a.get(3).and_then(|s| s.parse().ok()).unwrap_or(3);
    let ns: Vec<usize> = a[4.min(a.len())..]
        .iter()
        .filter_map(|s| s.parse().ok())
        .collect();
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
    let beta = env("BETA").unwrap_or(1.0);
    let t_end = env("T_END").unwrap_or(1.0);
    let (amp, gamma, c0) = (0.5, 1.4, 100.0);
    let bcs = [
        [IceBoundary::Periodic, IceBoundary::Periodic],
        [IceBoundary::Periodic, IceBoundary::Periodic],
    ];
    let mut p = IceParams::new(bcs);
    p.cfl = cfl;
    let solver = match mode.as_str() {
        "explicit" => None,
        "direct" => Some(LinearSolver::Direct),
        "pcg_jacobi" => Some(LinearSolver::PcgJacobi),
        _ => Some(LinearSolver::PcgMultigrid),
    };
    if let Some(s) = solver {
        p.implicit = Some(SemiImplicit {
            sound_speed_factor: 1.0,
            convective_predictor: beta,
            ..SemiImplicit::with_solver(s)
        });
    }
    for n in ns {
        let (mut walls, mut cpus) = (Vec::new(), Vec::new());
        let mut last = None;
        for _ in 0..reps {
            let g = IceMaterial::new("gas", IdealGas::new(gamma, 1.0 / (gamma - 1.0)).unwrap());
            let st = periodic_vortex(g, n, amp, c0 * c0 / gamma).unwrap();
            let c = cpu_s();
            let run = run_fluid(st, &p, t_end, 10_000_000).unwrap();
            cpus.push(cpu_s() - c);
            walls.push(run.wall_s);
            last = Some(run);
        }
        let run = last.expect("reps >= 1");
        let s = &run.state;
        let mut eu = 0.0;
        for &c in &s.layout.interior {
            let (u, v, _) = periodic_vortex_exact(&s.layout.centre(c), s.time, amp, 0.0);
            let w = s.cells[0].velocity[c];
            eu += (w[0] - u).powi(2) + (w[1] - v).powi(2);
        }
        let eu = (eu / (n * n) as f64).sqrt();
        println!(
            "{mode} cfl {cfl} N {n}: error {eu:.4e} wall {:.4} cpu {:.3} steps {} linear/step {:.1} walls {:?}",
            median(walls.clone()),
            median(cpus),
            run.steps,
            run.linear_iterations as f64 / run.steps.max(1) as f64,
            walls.iter().map(|w| (w * 1e4).round() / 1e4).collect::<Vec<_>>()
        );
    }
}
