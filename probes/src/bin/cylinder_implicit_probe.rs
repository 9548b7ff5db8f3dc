//! The coupled pressurised cylinder (Guilkey 4.1) explicit against
//! implicit at one cell size: Eq. 43 error, measured inner pressure,
//! steps and wall time of each.
//!
//! `cargo run --release -p probes --bin cylinder_implicit_probe -- DX [DT]`
//! (DT: the implicit step, default the case's `time.dt`). `PASSES=N` sets
//! `implicit.coupling.max_iterations` (the coupling iteration), `RELAX=constant`
//! and `OMEGA=w` its relaxation, `TOL=t` its tolerance; `DYNAMIC=1` makes the
//! steel Newmark instead of quasistatic; `MODIFIED=1` / `MODIFIED=0` sets
//! `implicit.modified_newton`; `HOLD=1` sets `implicit.hold_solid_faces`;
//! `END=t` sets `time.end`; `HISTORY=1` prints
//! P and Eq. 43 after every step.

use mpmice::diagnostics::coupled::run_cylinder_history;
use mpmice::scene;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let dx: f64 = args.get(1).map_or(Ok(0.05), |s| s.parse())?;
    let dt: Option<f64> = args.get(2).map(|s| s.parse()).transpose()?;
    let explicit = std::env::var("SKIP_EXPLICIT").is_err();
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let implicit_case =
        std::env::var("CASE").unwrap_or("cases/pressurized_cylinder_implicit.toml".into());
    let mut cases = vec![("implicit", implicit_case.as_str())];
    if explicit {
        cases.push(("explicit", "cases/pressurized_cylinder.toml"));
    }
    for (name, path) in cases {
        let mut sc = scene::load(&std::path::Path::new(root).join(path))?;
        if name == "implicit" {
            if let Some(dt) = dt {
                sc.time.dt = Some(dt);
            }
            if std::env::var("DYNAMIC").is_ok() {
                sc.implicit.dynamic = true;
            }
            if let Ok(e) = std::env::var("END") {
                sc.time.end = e.parse()?;
            }
            if std::env::var("HOLD").is_ok_and(|h| h == "1") {
                sc.implicit.hold_solid_faces = true;
            }
            if let Ok(m) = std::env::var("MODIFIED") {
                sc.implicit.modified_newton = m == "1";
            }
            let ci = &mut sc.implicit.coupling;
            if let Ok(n) = std::env::var("PASSES") {
                ci.max_iterations = n.parse()?;
            }
            if let Ok(t) = std::env::var("TOL") {
                ci.tolerance = t.parse()?;
            }
            if let Ok(w) = std::env::var("OMEGA") {
                ci.omega = w.parse()?;
            }
            if std::env::var("RELAX").is_ok_and(|r| r == "constant") {
                ci.relaxation = scene::RelaxationKind::Constant;
            }
        }
        let trace = std::env::var("HISTORY").is_ok();
        let from = if trace { 0.0 } else { f64::INFINITY };
        let (run, m, wall, history) = run_cylinder_history(sc, dx, from)?;
        if trace {
            for h in &history {
                println!(
                    "{name:8} t {:.4e}  P {:.4e} Pa  Eq.43 {:.4e}",
                    h.t, h.pressure, h.error43
                );
            }
        }
        let it = run.implicit_totals;
        println!(
            "{name:8} dx {dx}: Eq.43 {:.4e}  P {:.4e} Pa  steps {}  wall {:.3} s  \
             newton {} (max {}, {} factorisations) passes {} (max {}) retries {}; s: pressure {:.2} \
             assembly {:.2} factor {:.2} solve {:.2} particles {:.2}",
            m.error43,
            m.pressure,
            run.steps,
            wall,
            it.newton_iterations,
            it.max_newton_iterations,
            it.factorisations,
            it.coupling_iterations,
            it.max_coupling_iterations,
            it.step_retries,
            run.pressure_s,
            it.assembly_s,
            it.factor_s,
            it.solve_s,
            it.particles_s
        );
    }
    Ok(())
}
