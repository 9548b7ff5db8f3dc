//! Lian Sec. 7.1's membrane–sphere impacts (issue 17) at one cell size and
//! contact detection: the contact's onset, the clearance, the peak
//! deflection, the rebound and the energy account, and with `CURVES=1` the
//! sampled curves (CSV).
//!
//! `cargo run --release -p probes --bin lian_impact_probe -- CASE H END [gap|approach] [EVERY]`
//!
//! `CASE` is `sphere_on_membrane` or `membrane_on_sphere`
//! (`cases/lian_CASE.toml`), `H` the cell and element size [m], `END` the
//! end time [s], `EVERY` the sampling interval [s] (default 1e-5).

use mpmice::diagnostics::lian_impact::{impact_scene, run_impact};
use mpmice::scene::{self, ContactDetectionSpec, ContactSpec};

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let case = a.get(1).map_or("sphere_on_membrane", String::as_str);
    let h: f64 = a.get(2).map_or(Ok(2e-3), |s| s.parse())?;
    let end: f64 = a.get(3).map_or(Ok(1.2e-3), |s| s.parse())?;
    let detection = match a.get(4).map_or("gap", String::as_str) {
        "approach" => ContactDetectionSpec::Approach,
        _ => ContactDetectionSpec::Gap,
    };
    let every: f64 = a.get(5).map_or(Ok(1e-5), |s| s.parse())?;
    let base = scene::load(std::path::Path::new(&format!("cases/lian_{case}.toml")))?;
    let mut sc = impact_scene(&base, h)?;
    sc.time.end = end;
    let spec = sc.contact.get_or_insert_with(ContactSpec::default);
    spec.detection = detection;
    let r = run_impact(&sc, every)?;
    if std::env::var_os("CURVES").is_some() {
        print!("{}", r.curves_csv());
    }
    let lowest =
        r.membrane_centre_z
            .iter()
            .copied()
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |a, (k, z)| if z < a.1 { (k, z) } else { a },
            );
    println!(
        "{case} h = {} mm, {detection:?}: first contact {:.2} us, smallest clearance {:.3} mm (along the normals {:.3} mm), \
         centre lowest {:.5} mm at {:.3} ms, centre at end {:.5} mm, sphere v_z at end {:.4} m/s, \
         contact loss {:.4e} J, account's largest departure {:.3} %, {} steps, {:.1} s",
        h * 1e3,
        r.first_contact.unwrap_or(f64::NAN) * 1e6,
        r.min_clearance * 1e3,
        r.min_normal_clearance * 1e3,
        lowest.1 * 1e3,
        r.t.get(lowest.0).copied().unwrap_or(f64::NAN) * 1e3,
        r.membrane_centre_z.last().copied().unwrap_or(f64::NAN) * 1e3,
        r.sphere_vz.last().copied().unwrap_or(f64::NAN),
        r.contact.last().copied().unwrap_or(0.0),
        100.0 * r.energy_residual(),
        r.steps,
        r.wall_s
    );
    Ok(())
}
