//! Probe: York Sod with gas points, L1(ρ) split by wave (Sod's fan,
//! contact and shock, in ξ = (x − 0.5)/t) and the
//! density/energy range (all cases).
//! `[CASE=123|ratio] [SHAPE=q|c|l] [DUMP=1] cargo run --release -p probes --bin york_sod_probe -- G KAPPA C1 C2 CFL PPC CELLS...`
//! (G = g/Δx; York's defaults: 1.4142135623730951 0.75 1 1 0.4 3 200);
//! `END=T` ends at T instead of the case's time; `PIC=β` sets the PIC share;
//! `DENSITY=grid` gives the points the grid's density (`point_density`).
use mpmice::diagnostics::york::{riemann_exact, run_york_sod, YorkSod};

fn main() {
    let a: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().unwrap())
        .collect();
    let mut base = match std::env::var("CASE").as_deref() {
        // The 123 problem (two rarefactions, near-vacuum), the tube long
        // enough that the closed ends' shocks stay out of [0, 1].
        Ok("123") => YorkSod {
            left: (1.0, -2.0, 0.4),
            right: (1.0, 2.0, 0.4),
            tube: (-0.5, 1.5),
            end: 0.15,
            ..YorkSod::default()
        },
        // Pressure ratio 1e4.
        Ok("ratio") => YorkSod {
            left: (1.0, 0.0, 1000.0),
            right: (1.0, 0.0, 0.1),
            end: 0.012,
            ..YorkSod::default()
        },
        // Uniform gas at rest (must stay so).
        Ok("rest") => YorkSod {
            left: (1.0, 0.0, 1.0),
            right: (1.0, 0.0, 1.0),
            ..YorkSod::default()
        },
        // A gentle Sod (pressure ratio 1.1): smooth enough to see null modes.
        Ok("weak") => YorkSod {
            left: (1.0, 0.0, 1.1),
            right: (1.0, 0.0, 1.0),
            ..YorkSod::default()
        },
        _ => YorkSod::default(),
    };
    if std::env::var("DENSITY").as_deref() == Ok("grid") {
        base.point_density = mpmice::material::PointDensity::Grid;
    }
    if let Ok(b) = std::env::var("PIC") {
        base.pic_fraction = b.parse().expect("PIC: a share in [0, 1]");
    }
    if let Ok(t) = std::env::var("END") {
        base.end = t.parse().expect("END: a time");
    }
    let exact = riemann_exact(base.left, base.right).unwrap();
    for &n in &a[6..] {
        let s = YorkSod {
            cells: n as usize,
            ppc: a[5] as usize,
            q: (a[0], a[1], a[2], a[3]),
            cfl: a[4],
            shape: match std::env::var("SHAPE").as_deref() {
                Ok("q") => mpmice::shape::ShapeKind::QuadraticBspline,
                Ok("c") => mpmice::shape::ShapeKind::CubicBspline,
                Ok("l") => mpmice::shape::ShapeKind::Linear,
                _ => mpmice::shape::ShapeKind::Gimp,
            },
            ..base
        };
        let r = match run_york_sod(&s) {
            Ok(r) => r,
            Err(e) => {
                println!("N {n}: {e}");
                continue;
            }
        };
        // Region split on the bottom-row profile (1D: weight = spacing),
        // in the self-similar ξ = (x − 0.5)/t, so that it holds at any END:
        // Sod's fan (−1.4, −0.03), contact [−0.03, 1.2) (with the dip
        // behind the fan's tail), shock ≥ 1.2, and the rest.
        let t = s.end;
        let edges = [-1.4, -0.03, 1.2, f64::INFINITY];
        let mut reg = [0.0; 4];
        let pr = &r.profile;
        for i in 0..pr.len() {
            let x = pr[i][0];
            if !(0.0..=1.0).contains(&x) {
                continue;
            }
            let w = if i + 1 < pr.len() {
                pr[i + 1][0] - x
            } else {
                1.0 - x
            };
            let xi = (x - 0.5) / t;
            let e = exact.sample(xi);
            let k = if xi <= edges[0] {
                3
            } else {
                edges.iter().position(|&b| xi < b).unwrap_or(3) - 1
            };
            reg[k] += (pr[i][1] - e.rho).abs() * w;
        }
        println!(
            "N {n}: L1 {:.3e}  rho [{:.3e}, {:.3e}]  e_min {:.3e}  regions (fan, contact, shock, rest) {:?}  steps {} wall {:.2}",
            r.l1_density,
            r.density_range.0,
            r.density_range.1,
            r.energy_min,
            reg.iter().map(|v| format!("{v:.2e}")).collect::<Vec<_>>(),
            r.steps,
            r.wall_s
        );
        if std::env::var("DUMP").is_ok() {
            for p in pr {
                let e = exact.sample((p[0] - 0.5) / t);
                println!(
                    "{:.9} {:.6} {:.6} {:.6} {:.6} {:.6}",
                    p[0], p[1], e.rho, p[2], p[3], p[4]
                );
            }
        }
    }
}
