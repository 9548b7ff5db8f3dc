//! Probe: the Mach 3 wedge's (Guilkey Sec. 4.3) shock angle and pressure
//! ratio over time, on the `wedge_mach3` study's long domain
//! `[−0.7, 0.8] × [0, 0.2]` at a refinement factor of the case's cells, at
//! 0.36, 0.48, 0.6, 0.72, 0.96 and 1.2 ms (exact: 37.76°, 3.771), with the
//! smeared (default) or the sharp rigid interface
//! (`coupling.rigid_interface`). At each time it also prints the shock's
//! shape along the face (its stand-off at the tip and its local angle over
//! four stretches), the slow air layer on the face and the air held in the
//! wedge's cells ([`shock_shape`]).
//!
//! `wedge_frame` runs `cases/wedge_mach3_steady.toml` instead (the wedge at
//! rest in the stream), `wedge_frame=M,θ` that scene at Mach M and
//! half-angle θ ([`mpmice::diagnostics::wedge::steady_wedge_scene`]),
//! measured against the θ–β–M relation. Further `KEY=VALUE` arguments are
//! scene overrides, as the CLI's `--set`; `END=T` stops after the sample at
//! T (beyond 1.2 ms: every 0.6 ms); `DUMP=FILE` writes
//! `i j p u_x u_y θ_wedge T_air` per cell at the end.
//! `cargo run --release -p probes --bin wedge_drift_probe -- FACTOR [sharp] [wedge_frame[=M,θ]] [KEY=VALUE…]`
use mpmice::coupling::CoupledRun;
use mpmice::coupling::RigidInterface;
use mpmice::diagnostics::coupled::{measure_wedge, WedgeMeasured};
use mpmice::diagnostics::wedge::{oblique_shock, steady_wedge_scene, ObliqueShock};

/// The wedge being run: half-angle (degrees), the exact shock, the
/// free-stream pressure and the tip's starting x.
struct Wedge {
    theta: f64,
    exact: ObliqueShock,
    p1: f64,
    tip0: f64,
}

impl Wedge {
    /// The shock over `d_range` behind the tip at `tip` ([`measure_wedge`]).
    fn measure(&self, run: &CoupledRun<2>, tip: f64, d_range: (f64, f64)) -> WedgeMeasured {
        let p2 = self.exact.pressure_ratio * self.p1;
        measure_wedge(&run.fluid, tip, self.theta, self.p1, p2, d_range)
    }
}

/// The shock's shape along the whole face and the slow layer on it: the
/// shock's height above the exact attached shock at the tip (its stand-off),
/// the local angle of the least-squares line over four stretches of the
/// face, and at mid-face (d = 0.1) the distance from the exact surface
/// (normal to it) at which the air's velocity along the face, relative to
/// the wedge, first reaches half its value at the shock.
fn shock_shape(run: &CoupledRun<2>, w: &Wedge, tip: f64) {
    let m = w.measure(run, tip, (0.0, 0.2));
    let tb = w.exact.beta_deg.to_radians().tan();
    let standoff = m.columns.first().map_or(f64::NAN, |&(d, y, _)| y - d * tb);
    let mut local = String::new();
    for k in 0..4 {
        let (lo, hi) = (0.04 * k as f64, 0.04 * (k + 1) as f64);
        let a = w.measure(run, tip, (lo, hi)).angle_deg;
        local += &format!(" [{lo:.2},{hi:.2}] {a:.2}");
    }
    // The slow layer at d = 0.1.
    let l = &run.fluid.layout;
    let h = l.h[0];
    let wall = run.rigid_velocity_at(0, run.fluid.time).unwrap_or_default();
    let (ct, st) = (w.theta.to_radians().cos(), w.theta.to_radians().sin());
    let i = ((tip + 0.1 - l.lower[0]) / h - 0.5).round() as isize;
    let xc = l.lower[0] + (i as f64 + 0.5) * h;
    let ys = (xc - tip) * w.theta.to_radians().tan();
    let y_shock = (xc - tip) * tb;
    let air = &run.fluid.cells[0];
    let prof: Vec<(f64, f64)> = (0..l.cells[1] as isize)
        .map(|j| {
            let c = l.index([i, j]);
            let u = air.velocity[c] - wall;
            (
                (l.lower[1] + (j as f64 + 0.5) * h - ys) * ct,
                u[0] * ct + u[1] * st,
            )
        })
        .collect();
    let edge = prof
        .iter()
        .filter(|p| p.0 > 0.0 && p.0 < (y_shock - ys) * ct - 2.0 * h)
        .map(|p| p.1)
        .fold(0.0, f64::max);
    let half = prof
        .iter()
        .find(|p| p.0 > 0.0 && p.1 >= 0.5 * edge)
        .map_or(f64::NAN, |p| p.0);
    // Air held in the wedge: its mass and volume (in cells) where the
    // wedge fills more than half the cell.
    let (mut m_in, mut v_in) = (0.0, 0.0);
    for &c in &l.interior {
        if run.fluid.cells[1].vol_frac[c] > 0.5 {
            m_in += air.mass[c];
            v_in += air.vol_frac[c];
        }
    }
    println!(
        "  air in cells the wedge fills beyond half: {:.3e} kg/m, {v_in:.2} cells of volume",
        m_in
    );
    println!(
        "  shock stand-off at the tip {:.1} mm ({:.1} cells); local angle{local}; at d = 0.1 the air \
         along the face reaches half its {edge:.0} m/s {:.1} mm ({:.1} cells) off the face",
        standoff * 1e3,
        standoff / h,
        half * 1e3,
        half / h
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let f: usize = args.get(1).map_or(1, |s| s.parse().unwrap());
    let root = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."));
    let sets: Vec<mpmice::scene::Override> = args
        .iter()
        .skip(2)
        .filter(|a| a.contains('=') && !a.starts_with("wedge_frame"))
        .map(|a| mpmice::scene::Override::parse(a).unwrap())
        .collect();
    let frame = args.iter().skip(2).find(|a| a.starts_with("wedge_frame"));
    let (mut sc, w) = if let Some(a) = frame {
        // The wedge at rest in the stream, at Mach M and half-angle θ.
        let (mach, theta) = a.strip_prefix("wedge_frame=").map_or((3.0, 20.0), |v| {
            let (m, t) = v.split_once(',').expect("wedge_frame=M,θ");
            (m.parse().unwrap(), t.parse().unwrap())
        });
        let base =
            mpmice::scene::load_with(&root.join("cases/wedge_mach3_steady.toml"), &sets).unwrap();
        let (sc, stream) = steady_wedge_scene(&base, mach, theta, f).unwrap();
        let exact = oblique_shock(mach, theta, stream.gamma).expect("an attached shock");
        let w = Wedge {
            theta,
            exact,
            p1: stream.p1,
            tip0: stream.tip_x,
        };
        (sc, w)
    } else {
        let mut sc = mpmice::scene::load_with(&root.join("cases/wedge_mach3.toml"), &sets).unwrap();
        let h = 0.8 / sc.grid.cells[0] as f64 / f as f64;
        sc.grid.lower[0] = -0.7;
        sc.grid.upper[1] = 0.2;
        sc.grid.cells = (0..2)
            .map(|d| ((sc.grid.upper[d] - sc.grid.lower[d]) / h).round() as usize)
            .collect();
        let w = Wedge {
            theta: 20.0,
            exact: oblique_shock(3.0, 20.0, 1.4).unwrap(),
            p1: 101_325.0,
            tip0: 0.6,
        };
        (sc, w)
    };
    if args.iter().skip(2).any(|a| a == "sharp") {
        sc.coupling.rigid_interface = RigidInterface::Sharp;
    }
    let mut run = mpmice::scene::build_coupled_run::<2>(&sc).unwrap();
    let h = run.fluid.layout.h[0];
    let end: f64 = std::env::var("END").map_or(1.2e-3, |s| s.parse().unwrap());
    // Beyond 1.2 ms (`END` larger), a sample every 0.6 ms.
    let later = (1..).map(|k| 1.2e-3 + 0.6e-3 * k as f64);
    let times = [0.36e-3, 0.48e-3, 0.6e-3, 0.72e-3, 0.96e-3, 1.2e-3]
        .into_iter()
        .chain(later);
    println!(
        "{}° wedge, exact shock {:.3}°, p2/p1 {:.3}",
        w.theta, w.exact.beta_deg, w.exact.pressure_ratio
    );
    for t in times {
        if t > end + 1e-12 {
            break;
        }
        run.advance_to(t).unwrap();
        let tip = w.tip0 + run.rigid_displacement(0, t).map_or(0.0, |d| d[0]);
        let m = w.measure(&run, tip, (0.05, 0.15));
        println!(
            "t {:.2} ms: angle {:.3} deg, p2/p1 {:.3}",
            t * 1e3,
            m.angle_deg,
            m.pressure_ratio
        );
        shock_shape(&run, &w, tip);
    }
    println!("h {h:.5}, {} steps", run.steps);
    if let Ok(path) = std::env::var("DUMP") {
        // i j p ux uy θ_wedge T_air per interior cell at the end.
        use std::io::Write;
        let mut f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
        let l = &run.fluid.layout;
        let (air, wedge) = (&run.fluid.cells[0], &run.fluid.cells[1]);
        for &c in &l.interior {
            let ij = l.coords(c);
            writeln!(
                f,
                "{} {} {:.6e} {:.3} {:.3} {:.4} {:.1}",
                ij[0],
                ij[1],
                run.fluid.pressure[c],
                air.velocity[c][0],
                air.velocity[c][1],
                wedge.vol_frac[c],
                air.temperature[c]
            )
            .unwrap();
        }
    }
}
