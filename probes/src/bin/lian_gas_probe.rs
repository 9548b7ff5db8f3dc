//! The Lian Sec. 7.3 gas expansion over time (issue 17): the membrane's
//! radii at 0° and 90°, its roundness (the spread of its nodes' radii), its
//! tension over Laplace's p r, the total energy, the contact's loss and the account
//! with it, the gas's kinetic energy carried by its points and the part of it the grid sees,
//! at every `EVERY` of time.
//!
//! `cargo run --release -p probes --bin lian_gas_probe -- H END [stick|slip] [EVERY] [PIC] [gap|approach]`
//!
//! `H` is the element and cell size (4 particles per cell and direction),
//! `END` the end time, `PIC` the PIC share of the gas points' velocity
//! update (`mpm.pic_fraction`, default 0: FLIP), the last argument the
//! contact's detection (`contact.detection`: `gap`, the default, or Lian's `approach`).

use mpmice::contact::{ContactDetection, ContactLaw};
use mpmice::diagnostics::lian_gas::GasExpansion;

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().collect();
    let h: f64 = a.get(1).map_or(Ok(0.2), |s| s.parse())?;
    let end: f64 = a.get(2).map_or(Ok(3.0), |s| s.parse())?;
    let law = match a.get(3).map_or("stick", String::as_str) {
        "slip" => ContactLaw::Slip { friction: 0.0 },
        _ => ContactLaw::Stick,
    };
    let every: f64 = a.get(4).map_or(Ok(0.25), |s| s.parse())?;
    let pic_fraction: f64 = a.get(5).map_or(Ok(0.0), |s| s.parse())?;
    let detection = match a.get(6).map_or("gap", String::as_str) {
        "approach" => ContactDetection::Approach,
        _ => ContactDetection::Gap,
    };
    let dir = std::env::temp_dir().join(format!("lian_gas_probe_{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let case = GasExpansion {
        element: h,
        cell: h,
        per_cell: 4,
        end,
        every,
        law,
        detection,
        pic_fraction,
    };
    let r = case.run(&dir)?;
    println!(
        "t r0 r90 r_mean (r0-r90)/r_mean (r_max-r_min)/r_mean T/(p r_mean) E/E0-1 contact_loss/E0 account/E0-1 gas_KE_points gas_KE_grid"
    );
    for i in 0..r.t.len() {
        println!(
            "{:.3} {:.5} {:.5} {:.5} {:+.3e} {:.3e} {:.4} {:+.4e} {:.4e} {:+.3e} {:.4e} {:.4e}",
            r.t[i],
            r.r0[i],
            r.r90[i],
            r.r_mean[i],
            (r.r0[i] - r.r90[i]) / r.r_mean[i],
            (r.r_range[i].1 - r.r_range[i].0) / r.r_mean[i],
            r.tension[i] / (r.gas_pressure[i] * r.r_mean[i]),
            r.energy[i] / r.energy[0] - 1.0,
            r.contact_loss[i] / r.energy[0],
            (r.energy[i] + r.contact_loss[i]) / r.energy[0] - 1.0,
            r.gas_kinetic[i],
            r.grid_kinetic[i]
        );
    }
    println!(
        "{} steps, {:.1} s, {} gas points escaped",
        r.steps, r.wall_s, r.escaped
    );
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
