//! The coupled pressurised cylinder (Guilkey 4.1) at chosen cell sizes and
//! shape functions, with Guilkey Eq. 43's error split by where the
//! particles sit (first-cell layers at the inner and outer surfaces, and
//! the rest): what limits the order.
//! Also the hoop force across the cut y = 0 against P r_i, and σ_r and σ_θ
//! of the first particle rows at the inner surface against Lamé (mean per
//! row of reference radius).
//! `cargo run --release -p probes --bin cylinder_probe -- SHAPE DX [DX ...]`,
//! SHAPE a scene shape name (`ShapeKind::NAMES`); `PPC=K`
//! sets K × K particles per cell (the case has 2), `END=T` the end time
//! (the case: 8 ms), `DAMPING=A` the solid's damping (the case: 3000 1/s).

use mpmice::diagnostics::coupled::{eq43_particle_error, run_cylinder_scene};
use mpmice::scene;
use mpmice::shape::ShapeKind;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("gimp", String::as_str);
    let Some(shape) = ShapeKind::ALL.into_iter().find(|k| k.name() == name) else {
        anyhow::bail!("unknown shape {name}; one of {}", ShapeKind::NAMES);
    };
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .join("cases/pressurized_cylinder.toml");
    for dx in args.iter().skip(2).map(|s| s.parse::<f64>()) {
        let dx = dx?;
        let mut sc = scene::load(&path)?;
        sc.mpm.shape = shape;
        if let Ok(k) = std::env::var("PPC") {
            sc.mpm.particles_per_cell = k.parse()?;
        }
        let ppc = sc.mpm.particles_per_cell;
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
            let e = eq43_particle_error(&p.stress.get(i), target);
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
        // The hoop force across the cut y = 0: Σ σ_θ over the row nearest
        // the x-axis times its spacing; Lamé (and the quarter's balance)
        // make it P r_i.
        let hoop: f64 = m.row.iter().map(|s| s.2).sum::<f64>() * dx / ppc as f64;
        println!(
            "  hoop force across the cut {hoop:.5e} = {:.4} P r_i",
            hoop / (m.pressure * 0.5)
        );
        // Rows of particles by reference radius from the inner surface.
        let rows = 3 * ppc;
        let mut acc = vec![(0.0, 0.0, 0.0, 0usize); rows];
        for i in 0..p.len() {
            let k = ((p.x0[i].norm() - 0.5) / dx * ppc as f64) as usize;
            if k < rows {
                let x = p.x[i];
                let (c, s) = (x[0] / x.norm(), x[1] / x.norm());
                let st = &p.stress.get(i);
                acc[k].0 += c * c * st[(0, 0)] + 2.0 * c * s * st[(0, 1)] + s * s * st[(1, 1)];
                acc[k].1 += s * s * st[(0, 0)] - 2.0 * c * s * st[(0, 1)] + c * c * st[(1, 1)];
                acc[k].2 += eq43_particle_error(st, target);
                acc[k].3 += 1;
            }
        }
        let cc = m.pressure * 0.25 / 0.75;
        for (k, a) in acc.iter().enumerate() {
            let r = 0.5 + (k as f64 + 0.5) * dx / ppc as f64;
            let n = a.3.max(1) as f64;
            println!(
                "  row {k} (r {r:.4}): sigma_r {:.3e} (Lame {:.3e}), sigma_theta {:.3e} (Lame {:.3e}), Eq.43 {:.3e}",
                a.0 / n,
                cc * (1.0 - 1.0 / (r * r)),
                a.1 / n,
                cc * (1.0 + 1.0 / (r * r)),
                a.2 / n
            );
        }
    }
    Ok(())
}
