//! The memory a particle costs in a run as a user makes it (issue 24): the
//! memory bench `bench/block_1m.toml` (2D, quadratic B-spline, 2 × 2
//! particles per cell, snapshots in VTK and CSV, the watchdog keeping the
//! last good state) run by the `mpmice` binary at two sizes, each in its own
//! process, so that `summary.json`'s peak resident memory is the run's
//! alone.

use std::path::Path;
use std::process::Command;

/// `(particles, peak resident bytes)` of `bench/block_1m.toml` on a
/// `cells`² grid, the watchdog's last good state kept as `last_good` says
/// (`time.last_good`).
fn peak(cells: usize, last_good: &str) -> (f64, f64) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir =
        std::env::temp_dir().join(format!("memory-{cells}-{last_good}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let set = format!("grid.cells=[{cells},{cells}]");
    let keep = format!("time.last_good=\"{last_good}\"");
    let out = Command::new(env!("CARGO_BIN_EXE_mpmice"))
        .args([
            "run",
            "bench/block_1m.toml",
            "--quiet",
            "--set",
            &set,
            "--set",
            &keep,
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
/// its arrays (F in 5 entries, the symmetric σ in 4, 3 vectors, 3 scalars,
/// a 4-byte half-size index and a 2-byte material: 150 B; an elastic neo-Hookean run
/// keeps no stress work, temperature, plastic strain or damage), the step's
/// scratch (offsets and half-widths, 32 B, and the bins' 4-byte order) and
/// its share of the grid (72 B a node, the force and the acceleration
/// sharing one array; 0.39 nodes a particle: 28 B): 214 B; with the last
/// good state in memory another 168 B (its arrays as a checkpoint stores
/// them: the half-sizes as vectors, the material as a u64): 382 B. A snapshot reads every particle
/// and grid field in place. Before issue 24's changes (the snapshot reading
/// the fields in place, the tensors stored in the plane, the stress's upper
/// triangle, the optional arrays, the last good state on disk) the 1M-particle bench took 995 B a
/// particle.
#[test]
fn a_particle_costs_what_its_arrays_and_the_last_good_state_take() {
    if !Path::new("/proc/self/status").exists() {
        return; // the peak is read from /proc
    }
    for (last_good, design) in [("memory", 382.0), ("disk", 214.0)] {
        let (n0, b0) = peak(40, last_good);
        let (n1, b1) = peak(320, last_good);
        let marginal = (b1 - b0) / (n1 - n0);
        println!("last good state in {last_good}: {n0} particles: {b0} B; {n1}: {b1} B; {marginal:.1} B a particle");
        assert!(
            marginal < design * 1.05,
            "{last_good}: {marginal} B a particle"
        );
        // The scene's estimate (`check`) bounds what the run took beyond
        // the small run (the program).
        let est = {
            let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("bench/block_1m.toml");
            let mut s = mpmice::scene::load(&path).expect("scene");
            s.grid.cells = vec![320, 320];
            s.time.last_good = match last_good {
                "memory" => mpmice::scene::LastGood::Memory,
                _ => mpmice::scene::LastGood::Disk,
            };
            mpmice::driver::MemoryEstimate::of(&s).total()
        };
        assert!(
            b1 - b0 < est,
            "{last_good}: {} B beyond the program, estimate {est}",
            b1 - b0
        );
    }
}
