//! The command line as a user drives a study (issue 23): `--set` on `run`,
//! `check` and `study`, the refusal of a non-empty `--out` without
//! `--force`, and `study` writing the built-in studies' files.

use std::path::{Path, PathBuf};
use std::process::Command;

fn sod() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/sod.toml")
}

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cli-overrides-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// `mpmice ARGS`: (success, stdout, stderr).
fn mpmice(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_mpmice"))
        .args(args)
        .output()
        .expect("spawn");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `mpmice run cases/sod.toml --out DIR --quiet EXTRA…`.
fn run_sod(dir: &Path, extra: &[&str]) -> (bool, String, String) {
    let s = sod();
    let mut args = vec![
        "run",
        s.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
    ];
    args.extend(extra);
    mpmice(&args)
}

/// Every value type reaches the scene: an array, a float, a bare word, a
/// quoted string and an element picked by name; `check` reports the
/// overridden cell count.
#[test]
fn set_overrides_reach_the_scene() {
    let s = sod();
    let s = s.to_str().unwrap();
    let (ok, out, err) = mpmice(&[
        "check",
        s,
        "--set",
        "grid.cells=[800]",
        "--set",
        "time.cfl=0.25",
        "--set",
        "fluid.variant=literal",
        "--set",
        "output.formats=[\"csv\"]",
        "--set",
        "materials.gas.gamma=1.3",
        "--set",
        "regions[1].pressure=2.0",
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("800 cells"), "{out}");
    // The overridden Δt: CFL 0.25 on 800 cells against 0.4 on 400.
    let dt = |o: &str| -> f64 {
        let i = o.find("first Δt ").unwrap() + "first Δt ".len();
        o[i..].split_whitespace().next().unwrap().parse().unwrap()
    };
    let (_, base, _) = mpmice(&["check", s]);
    let ratio = dt(&out) / dt(&base);
    // Half the cells, 0.25/0.4 of the Courant number, and the left state's
    // sound speed sqrt(1.3 * 2 / 1) against sqrt(1.4 * 1 / 1).
    let expect = 0.5 * 0.25 / 0.4 * (1.4f64 / 2.6).sqrt();
    assert!((ratio / expect - 1.0).abs() < 0.05, "{ratio} vs {expect}");
}

/// A bad path and a bad value are named by their key path, by every verb.
#[test]
fn bad_overrides_are_named() {
    let s = sod();
    let s = s.to_str().unwrap();
    let dir = tmp("bad");
    let d = dir.to_str().unwrap();
    for (set, key) in [
        ("grid.cels=[800]", "cels"),
        ("materials[2].gamma=1.3", "materials[2]"),
        ("materials.air.gamma=1.3", "gas"),
        ("time.end=-1", "time.end"),
        ("grid.cells=\"many\"", "grid.cells"),
        ("time.end.x=1", "time.end"),
        ("fluid.variant=nonsense", "fluid.variant"),
    ] {
        for verb in [
            vec!["check", s],
            vec!["run", s, "--out", d, "--quiet"],
            vec!["study", s, "--out", d],
        ] {
            let mut args = verb.clone();
            args.extend(["--set", set]);
            let (ok, _, err) = mpmice(&args);
            assert!(!ok, "{args:?} accepted");
            assert!(err.contains(key), "{args:?}: {err}");
            assert!(!err.contains("panicked"), "{err}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A non-empty output folder is refused without `--force`; with it the
/// previous run's snapshots go, so a shorter rerun leaves no stale file
/// beside its `.pvd`. Other files in the folder stay.
#[test]
fn non_empty_out_is_refused_unless_forced() {
    let s = sod();
    let s = s.to_str().unwrap();
    let dir = tmp("out");
    let d = dir.to_str().unwrap();
    let base = ["run", s, "--out", d, "--quiet", "--set", "grid.cells=[50]"];
    let (ok, _, err) = mpmice(&base);
    assert!(ok, "{err}");
    let snapshots = |d: &Path| {
        std::fs::read_dir(d)
            .unwrap()
            .filter(|e| {
                let n = e.as_ref().unwrap().file_name();
                n.to_string_lossy().ends_with(".vti")
            })
            .count()
    };
    assert_eq!(snapshots(&dir), 5);
    std::fs::write(dir.join("notes.txt"), "mine").unwrap();
    let (ok, _, err) = mpmice(&base);
    assert!(!ok && err.contains("--force") && err.contains(d), "{err}");
    let mut shorter = base.to_vec();
    shorter.extend(["--set", "time.end=0.05", "--force"]);
    let (ok, _, err) = mpmice(&shorter);
    assert!(ok, "{err}");
    assert_eq!(snapshots(&dir), 2, "stale snapshots left");
    assert!(dir.join("notes.txt").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `study` writes the JSON, CSV and PNG of the built-in studies and each
/// run's outputs; its Sod errors fall at first order against the exact
/// solution.
#[test]
fn study_writes_the_built_in_files() {
    let s = sod();
    let dir = tmp("study");
    let (ok, out, err) = mpmice(&[
        "study",
        s.to_str().unwrap(),
        "--refine",
        "2",
        "--set",
        "grid.cells=[100]",
        "--reference",
        "riemann",
        "--quantity",
        "kinetic",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    for ext in ["json", "csv", "png"] {
        assert!(dir.join(format!("study_sod.{ext}")).is_file(), "{ext}");
    }
    assert!(dir.join("series_0/level_2/summary.json").is_file());
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("study_sod.json")).unwrap()).unwrap();
    let order = json["series"][0]["observed_order"].as_f64().unwrap();
    assert!((0.9..1.1).contains(&order), "{order} {out}");
    assert_eq!(json["h_axis"], "cell size Δx [m]");
    let error_axis = json["error_axis"].as_str().unwrap();
    assert!(
        error_axis.contains("cells.mixture_density") && error_axis.contains("kinetic"),
        "{error_axis}"
    );
    assert!(out.contains("Richardson"), "{out}");
    let (ok, _, err) = mpmice(&["study", s.to_str().unwrap(), "--reference", "exact"]);
    assert!(!ok && err.contains("finest, riemann"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Snapshots are taken at the times asked for (`output.interval` 0.05 on
/// Sod: 0, 0.05, …, 0.2 to round-off; before, the first step past each,
/// e.g. 0.10040), and the last history row is not repeated.
#[test]
fn snapshots_fall_on_the_requested_times() {
    let dir = tmp("times");
    let (ok, _, err) = run_sod(&dir, &["--set", "grid.cells=[100]"]);
    assert!(ok, "{err}");
    let pvd = std::fs::read_to_string(dir.join("cells.pvd")).unwrap();
    let times: Vec<f64> = pvd
        .split("timestep=\"")
        .skip(1)
        .map(|r| r.split('"').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(times.len(), 5, "{pvd}");
    for (k, t) in times.iter().enumerate() {
        assert!((t - 0.05 * k as f64).abs() < 1e-14, "{times:?}");
    }
    let hist = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    let rows: Vec<&str> = hist.lines().skip(1).collect();
    let t_of = |r: &str| r.split(',').next().unwrap().to_string();
    assert_ne!(t_of(rows[rows.len() - 1]), t_of(rows[rows.len() - 2]));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `summary.json` says where its numbers come from: the program, its
/// version and commit, the date, the command line, the threads and the
/// scene as run (with the `--set` overrides resolved).
#[test]
fn the_summary_carries_its_provenance() {
    let dir = tmp("provenance");
    let (ok, _, err) = run_sod(&dir, &["--threads", "1", "--set", "grid.cells=[50]"]);
    assert!(ok, "{err}");
    let sum: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    let p = &sum["provenance"];
    assert_eq!(p["program"], "mpmice");
    assert_eq!(p["version"], env!("CARGO_PKG_VERSION"));
    let git = p["git"].as_str().unwrap();
    assert!(
        git == "unknown" || (git.len() == 40 && git.chars().all(|c| c.is_ascii_hexdigit())),
        "{git}"
    );
    let date = p["date_utc"].as_str().unwrap();
    assert!(
        date.len() == 20 && date.ends_with('Z') && date.starts_with("20"),
        "{date}"
    );
    let cl: Vec<&str> = p["command_line"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(cl.contains(&"grid.cells=[50]"), "{cl:?}");
    assert_eq!(p["threads"], 1);
    assert_eq!(p["scene"]["grid"]["cells"], serde_json::json!([50]));
    assert_eq!(p["scene"]["materials"][0]["gamma"], 1.4);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `output.vtk_compression = "zlib"` (the default) writes zlib VTK files
/// (smaller than `"none"`'s raw ones, the compressor named) at any level,
/// and a bad value or level is refused naming the key and the allowed
/// values.
#[test]
fn vtk_compression_keys_reach_the_writer() {
    let size = |dir: &Path, f: &str| std::fs::metadata(dir.join(f)).unwrap().len();
    let raw = tmp("vtk-raw");
    let (ok, _, err) = run_sod(
        &raw,
        &[
            "--set",
            "grid.cells=[400]",
            "--set",
            "output.vtk_compression=none",
        ],
    );
    assert!(ok, "{err}");
    let default = tmp("vtk-default");
    let (ok, _, err) = run_sod(&default, &["--set", "grid.cells=[400]"]);
    assert!(ok, "{err}");
    let f = "cells_0004.vti";
    let text = String::from_utf8_lossy(&std::fs::read(default.join(f)).unwrap()).into_owned();
    assert!(text.contains("compressor=\"vtkZLibDataCompressor\""));
    assert!(size(&default, f) < size(&raw, f));
    let _ = std::fs::remove_dir_all(&default);
    for level in ["1", "9"] {
        let z = tmp(&format!("vtk-zlib{level}"));
        let set = format!("output.vtk_compression_level={level}");
        let (ok, _, err) = run_sod(
            &z,
            &[
                "--set",
                "grid.cells=[400]",
                "--set",
                "output.vtk_compression=zlib",
                "--set",
                &set,
            ],
        );
        assert!(ok, "{err}");
        let f = "cells_0004.vti";
        let text = String::from_utf8_lossy(&std::fs::read(z.join(f)).unwrap()).into_owned();
        assert!(text.contains("compressor=\"vtkZLibDataCompressor\""));
        assert!(size(&z, f) < size(&raw, f), "level {level}");
        let _ = std::fs::remove_dir_all(&z);
    }
    let _ = std::fs::remove_dir_all(&raw);
    let s = sod();
    let s = s.to_str().unwrap();
    for (set, says) in [
        (
            vec!["output.vtk_compression=gzip"],
            "`output.vtk_compression`: unknown variant `gzip`, expected `none` or `zlib`",
        ),
        (
            vec![
                "output.vtk_compression=none",
                "output.vtk_compression_level=3",
            ],
            "`output.vtk_compression_level`: only with output.vtk_compression = \"zlib\"",
        ),
        (
            vec![
                "output.vtk_compression=zlib",
                "output.vtk_compression_level=10",
            ],
            "`output.vtk_compression_level`: must be 1 (fastest) to 9 (smallest) (got 10)",
        ),
    ] {
        let mut args = vec!["check", s];
        for kv in &set {
            args.extend(["--set", kv]);
        }
        let (ok, _, err) = mpmice(&args);
        assert!(!ok && err.contains(says), "{set:?}: {err}");
    }
}
