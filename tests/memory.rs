//! The memory a particle costs in a run as a user makes it (issue 24): the
//! memory bench `bench/block_1m.toml` (2D, quadratic B-spline, 2 × 2
//! particles per cell, snapshots in VTK and CSV, the watchdog keeping the
//! last good state) run by the `mpmice` binary at two sizes, each in its own
//! process, so that `summary.json`'s peak resident memory is the run's
//! alone.

use std::path::Path;
use std::process::Command;

/// `(particles, peak resident bytes)` of `bench/block_1m.toml` on a
/// `cells`² grid.
fn peak(cells: usize) -> (f64, f64) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("memory-{cells}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let set = format!("grid.cells=[{cells},{cells}]");
    let out = Command::new(env!("CARGO_BIN_EXE_mpmice"))
        .args([
            "run",
            "bench/block_1m.toml",
            "--quiet",
            "--set",
            &set,
            "--out",
        ])
        .arg(&dir)
        .current_dir(root)
        .output()
        .expect("spawn");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary");
    let v: serde_json::Value = serde_json::from_str(&text).expect("json");
    let _ = std::fs::remove_dir_all(&dir);
    let n = v["n_particles"].as_f64().expect("n_particles");
    let Some(b) = v["peak_memory_bytes"].as_f64() else {
        panic!("no peak memory on this system: {text}")
    };
    (n, b)
}

/// The memory one more particle costs, measured between a 40² and a 320²
/// run (4 096 and 262 144 particles), stays within what the design keeps:
/// its arrays (F and σ in 5 entries each, 4 vectors, 5 scalars and a u16
/// material: 186 B; an elastic run tracks no temperature, plastic strain or
/// damage), the step's scratch (40 B), its share of the grid (88 B a node,
/// 0.39 nodes a particle: 35 B) and the last good state (192 B): 453 B (a
/// snapshot reads every particle field, positions included, in place).
/// Before issue 24's changes (the snapshot reading the fields in place, the
/// tensors stored in the plane, the optional arrays) the 1M-particle bench
/// took 995 B a particle.
#[test]
fn a_particle_costs_what_its_arrays_and_the_last_good_state_take() {
    if !Path::new("/proc/self/status").exists() {
        return; // the peak is read from /proc
    }
    let (n0, b0) = peak(40);
    let (n1, b1) = peak(320);
    let marginal = (b1 - b0) / (n1 - n0);
    println!("{n0} particles: {b0} B; {n1}: {b1} B; {marginal:.1} B a particle");
    // Measured 436.9 B a particle.
    assert!(marginal < 453.0 * 1.05, "{marginal} B a particle");
    // The scene's estimate (`check`) bounds what the run took beyond the
    // small run (the program).
    let est = {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("bench/block_1m.toml");
        let mut s = mpmice::scene::load(&path).expect("scene");
        s.grid.cells = vec![320, 320];
        mpmice::driver::MemoryEstimate::of(&s).total()
    };
    assert!(
        b1 - b0 < est,
        "{} B beyond the program, estimate {est}",
        b1 - b0
    );
}
