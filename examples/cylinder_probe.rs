//! The coupled pressurised cylinder (Guilkey 4.1) at chosen cell sizes and
//! shape functions, with Guilkey Eq. 43's error split by where the
//! particles sit (first-cell layers at the inner and outer surfaces, and
//! the rest): what limits the order.
//! `cargo run --release --example cylinder_probe -- SHAPE DX [DX ...]`,
//! SHAPE one of linear, gimp, quadratic_bspline, cubic_bspline; `PPC=K`
//! sets K × K particles per cell (the case has 2), `END=T` the end time
//! (the case: 8 ms), `DAMPING=A` the solid's damping (the case: 3000 1/s).

use mpmice::diagnostics::coupled::{eq43_particle_error, run_cylinder_scene};
use mpmice::scene;
use mpmice::shape::ShapeKind;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let shape = match args.get(1).map(String::as_str) {
        Some("linear") => ShapeKind::Linear,
        Some("gimp") | None => ShapeKind::Gimp,
        Some("quadratic_bspline") => ShapeKind::QuadraticBspline,
        Some("cubic_bspline") => ShapeKind::CubicBspline,
        Some(s) => anyhow::bail!("unknown shape {s}"),
    };
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/pressurized_cylinder.toml");
    for dx in args.iter().skip(2).map(|s| s.parse::<f64>()) {
        let dx = dx?;
        let mut sc = scene::load(&path)?;
        sc.mpm.shape = shape;
        if let Ok(k) = std::env::var("PPC") {
            sc.mpm.particles_per_cell = k.parse()?;
        }
        if let Ok(t) = std::env::var("END") {
            sc.time.end = t.parse()?;
        }
        if let Ok(a) = std::env::var("DAMPING") {
            sc.mpm.damping = a.parse()?;
        }
        let (run, m, wall) = run_cylinder_scene(sc, dx)?;
        // Eq. 43 per particle, split by the reference radius.
        let target = 2.0 * m.pressure / 3.0;
        let p = &run.fields[0].particles;
        let mut bands = [(0.0, 0usize); 3];
        for i in 0..p.len() {
            let e = eq43_particle_error(&p.stress[i], target);
            let r0 = p.x0[i].norm();
            let b = if r0 < 0.5 + dx {
                0
            } else if r0 > 1.0 - dx {
                2
            } else {
                1
            };
            bands[b].0 += e;
            bands[b].1 += 1;
        }
        let np = p.len() as f64;
        println!(
            "{shape:?} dx {dx}: Eq.43 {:.5e}, P {:.5e}, {} steps, {:.1} s; share of Eq.43 (sum/N): inner layer {:.3e} ({} p), middle {:.3e} ({} p), outer layer {:.3e} ({} p)",
            m.error43,
            m.pressure,
            run.steps,
            wall,
            bands[0].0 / np,
            bands[0].1,
            bands[1].0 / np,
            bands[1].1,
            bands[2].0 / np,
            bands[2].1
        );
    }
    Ok(())
}
