//! Probe of York Sec. 4.3's dog-bone (`diagnostics::york_membrane::DogBone`):
//! `cargo run --release -p probes --bin york_dogbone_probe -- H END MARGIN SHAPE PIC`
//! (defaults 0.2, 0.3, 0, the case's `quadratic_bspline`, 0; `DENSITY=continuity` for York Eq. 16's
//! density instead of the case's grid density, `CFL=c` for the Courant number, default the case's) prints the final measures (radii, hoop
//! stress against p r / t, gas points out, energy, kinetic energy of the
//! points and of the grid; `HIST=1` adds the history CSV). With `TRACE=1`
//! it prints instead, for each gas point the first time it is outside the
//! membrane, the step, time, its position, velocity and J, its distance to
//! the membrane polygon then and at the start, and (`DETAIL=1`) the
//! neighbouring membrane points before and after that step.
use mpmice::diagnostics::york_membrane::{gas_outside, DogBone};
use mpmice::membrane::inside_polygon;
use mpmice::scene::{build_solid_run, parse};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let h: f64 = args.get(1).map_or(Ok(0.2), |s| s.parse())?;
    let end: f64 = args.get(2).map_or(Ok(0.3), |s| s.parse())?;
    let margin: f64 = args.get(3).map_or(Ok(0.0), |s| s.parse())?;
    let shape: &'static str = match args.get(4).map(String::as_str) {
        Some("linear") => "linear",
        Some("gimp") => "gimp",
        Some("cubic_bspline") => "cubic_bspline",
        _ => DogBone::default().shape,
    };
    let s = DogBone {
        h,
        end,
        gas_margin_over_h: margin,
        shape,
        pic_fraction: args.get(5).map_or(Ok(0.0), |s| s.parse())?,
        point_density: match std::env::var("DENSITY").as_deref() {
            Ok("continuity") => mpmice::material::PointDensity::Continuity,
            _ => DogBone::default().point_density,
        },
        cfl: std::env::var("CFL").map_or(Ok(DogBone::default().cfl), |s| s.parse())?,
        ..DogBone::default()
    };
    if std::env::var("TRACE").is_err() {
        let r = mpmice::diagnostics::york_membrane::run_dog_bone(&s)?;
        let m = r.last;
        let laplace = m.area_pressure * m.mean_radius / DogBone::THICKNESS;
        println!(
            "h {h} {shape}: mean r {:.4}, r0 {:.4}, r90 {:.4} ({:+.2} %), hoop {:.1} vs p r/t {:.1} ({:+.2} %), p point-mean {:.2} area {:.2}, out end {} max {}, steps {}, {:.1} s",
            m.mean_radius, m.radius_0, m.radius_90, 100.0 * (m.radius_0 - m.radius_90) / m.mean_radius,
            m.mean_stress, laplace, 100.0 * (m.mean_stress / laplace - 1.0), m.mean_pressure, m.area_pressure,
            r.outside_end, r.outside_max, r.steps, r.wall_s
        );
        let e = |x: &mpmice::diagnostics::york_membrane::DogBoneSample| {
            x.kinetic + x.internal + x.strain
        };
        if let (Some(a), Some(b)) = (r.history.first(), r.history.last()) {
            println!(
                "   energy {:.3} -> {:.3} ({:+.3} %), final kinetic {:.3e} (grid {:.3e})",
                e(a),
                e(b),
                100.0 * (e(b) / e(a) - 1.0),
                b.kinetic,
                b.grid_kinetic
            );
            if std::env::var("HIST").is_ok() {
                print!("{}", r.history_csv());
            }
        }
        return Ok(());
    }
    let text = s.scene();
    let scene = parse(&text).map_err(|e| format!("{e:?}"))?;
    let mut run = build_solid_run::<2>(&scene)?;
    let c = run.membranes.chains[0];
    let n = run.particles.len();
    let gas: Vec<usize> = (0..n)
        .filter(|&i| {
            run.materials[run.particles.material[i] as usize]
                .gas()
                .is_some()
        })
        .collect();
    let mut reported = vec![false; n];
    // Distance from the initial membrane polygon for every gas point.
    let dist = |run: &mpmice::stepper::SolidRun<2>, i: usize| -> (f64, usize) {
        let x = run.particles.x[i];
        let mut best = (f64::INFINITY, 0);
        for k in 0..c.count {
            let a = run.particles.x[c.first + k];
            let b = run.particles.x[c.first + (k + 1) % c.count];
            let ab = b - a;
            let t = ((x - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
            let d = (x - (a + ab * t)).norm();
            if d < best.0 {
                best = (d, k);
            }
        }
        best
    };
    let d0: Vec<f64> = (0..n)
        .map(|i| {
            if gas.contains(&i) {
                dist(&run, i).0
            } else {
                0.0
            }
        })
        .collect();
    let mut prev = run.particles.x.clone();
    while !run.finished() {
        let dt = run.next_dt();
        prev.clone_from(&run.particles.x);
        run.step_dt(dt)?;
        let mem = &run.particles.x[c.first..c.first + c.count];
        for &i in &gas {
            if reported[i] || inside_polygon(&run.particles.x[i], mem) {
                continue;
            }
            reported[i] = true;
            let (d, k) = dist(&run, i);
            let p = &run.particles;
            let m = c.first + k;
            println!(
                "step {} t {:.5} dt {:.2e}: gas {} at ({:.4}, {:.4}) v ({:.3}, {:.3}) J {:.3} started {:.4} from the membrane; now {:.4} beyond segment {} (membrane point at ({:.4}, {:.4}) v ({:.3}, {:.3}), next point {:.4} away)",
                run.steps, run.t, dt, i, p.x[i][0], p.x[i][1], p.v[i][0], p.v[i][1],
                p.vol[i] / p.vol0[i], d0[i], d, k, p.x[m][0], p.x[m][1], p.v[m][0], p.v[m][1],
                (p.x[c.first + (k + 1) % c.count] - p.x[m]).norm()
            );
            if std::env::var("DETAIL").is_ok() {
                println!(
                    "   gas before ({:.5}, {:.5}) after ({:.5}, {:.5})",
                    prev[i][0], prev[i][1], p.x[i][0], p.x[i][1]
                );
                for j in 0..11 {
                    let q = c.first + (k + c.count + j - 5) % c.count;
                    println!("   mem {:4} before ({:.5}, {:.5}) after ({:.5}, {:.5}) v ({:.3}, {:.3}) s {:.2}", q - c.first, prev[q][0], prev[q][1], p.x[q][0], p.x[q][1], p.v[q][0], p.v[q][1], p.stress.get(q).trace());
                }
            }
        }
    }
    println!(
        "end: t {:.4}, steps {}, outside {}",
        run.t,
        run.steps,
        gas_outside(&run)
    );
    Ok(())
}
