//! `output.formats = ["npy"]` (issue 23): every snapshot of every field set
//! is a folder of NumPy arrays and a `meta.json`. The arrays must be the
//! values the CSV snapshot holds, bit for bit, in the documented shapes.

use std::path::Path;

use mpmice::driver::{run_scene, RunOptions};
use mpmice::scene::{self, Override};

/// Runs `case` with `set` and NumPy and CSV snapshots into a temporary
/// folder; returns it, snapshot folder `snap`'s path and its metadata.
fn run(
    case: &str,
    set: &[&str],
    snap: &str,
) -> (tempfile::TempDir, std::path::PathBuf, serde_json::Value) {
    let text =
        std::fs::read_to_string(format!("{}/cases/{case}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let mut o: Vec<Override> = set.iter().map(|a| Override::parse(a).unwrap()).collect();
    o.push(Override::parse(r#"output.formats=["npy", "csv"]"#).unwrap());
    let s = scene::parse_with(&text, &o).unwrap();
    let dir = tempfile::tempdir().unwrap();
    run_scene(&s, &RunOptions::quiet(dir.path(), 1)).unwrap();
    let snap = dir.path().join(snap);
    let meta =
        serde_json::from_str(&std::fs::read_to_string(snap.join("meta.json")).unwrap()).unwrap();
    (dir, snap, meta)
}

/// A `.npy` file's shape and values (read with `npyz`, as NumPy would).
fn load(path: &Path) -> (Vec<u64>, Vec<f64>) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    assert_eq!(npy.order(), npyz::Order::C);
    match npy.dtype() {
        npyz::DType::Plain(t) => assert_eq!(t.to_string(), "<f8"),
        other => panic!("dtype {other:?}"),
    }
    let shape = npy.shape().to_vec();
    (shape, npy.into_vec::<f64>().unwrap())
}

/// A CSV snapshot's header and rows.
fn csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

fn column(header: &[String], rows: &[Vec<f64>], name: &str) -> Vec<f64> {
    let c = header
        .iter()
        .position(|h| h.split(' ').next() == Some(name))
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"));
    rows.iter().map(|r| r[c]).collect()
}

/// Particles (2D, two elastic disks): positions, velocities (padded to 3
/// components), stress tensors and masses equal the CSV's columns; the
/// grid's node fields are shaped (n_y, n_x).
#[test]
fn particle_arrays_are_the_csv_values() {
    let (dir, snap, meta) = run(
        "two_disks.toml",
        &[
            "grid.cells=[16, 16]",
            "time.end=0.5",
            "output.interval=0.25",
        ],
        "particles_0001_npy",
    );
    assert_eq!(meta["geometry"], "points");
    assert!(
        (meta["time"].as_f64().unwrap() - 0.25).abs() < 1e-12,
        "{meta}"
    );
    let (header, rows) = csv(&dir.path().join("particles_0001.csv"));
    let n = rows.len() as u64;
    let (shape, x) = load(&snap.join("points.npy"));
    assert_eq!(shape, [n, 3]);
    let (shape, v) = load(&snap.join("velocity.npy"));
    assert_eq!(shape, [n, 3]);
    let (shape, s) = load(&snap.join("stress.npy"));
    assert_eq!(shape, [n, 3, 3]);
    let (shape, m) = load(&snap.join("mass.npy"));
    assert_eq!(shape, [n]);
    for (a, name) in [(0, "x"), (1, "y")] {
        let col = column(&header, &rows, name);
        assert!(col.iter().enumerate().all(|(i, &c)| x[3 * i + a] == c));
        let col = column(&header, &rows, &format!("v{name}"));
        assert!(col.iter().enumerate().all(|(i, &c)| v[3 * i + a] == c));
    }
    let sxy = column(&header, &rows, "sxy");
    assert!(sxy.iter().enumerate().all(|(i, &c)| s[9 * i + 1] == c));
    assert!(column(&header, &rows, "mass")
        .iter()
        .zip(&m)
        .all(|(c, a)| c == a));
    // Every field of the set has its file and its shape in the metadata.
    for f in meta["fields"].as_array().unwrap() {
        let (shape, _) = load(&snap.join(f["file"].as_str().unwrap()));
        assert_eq!(serde_json::json!(shape), f["shape"], "{f}");
    }
    let grid = dir.path().join("grid_0001_npy");
    let (shape, _) = load(&grid.join("mass.npy"));
    assert_eq!(shape, [17, 17]);
}

/// Cells (1D Sod): the fields are shaped (n_x,) and equal the CSV's
/// columns; the metadata gives the grid.
#[test]
fn cell_arrays_are_the_csv_values() {
    let (dir, snap, meta) = run(
        "sod.toml",
        &["grid.cells=[100]", "output.interval=0.1"],
        "cells_0002_npy",
    );
    assert_eq!(meta["geometry"], "image");
    assert_eq!(meta["cells"], serde_json::json!([100]));
    assert_eq!(meta["on_cells"], true);
    let (header, rows) = csv(&dir.path().join("cells_0002.csv"));
    let file = meta["fields"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["name"] == "mixture_density")
        .expect("mixture_density")["file"]
        .as_str()
        .unwrap()
        .to_string();
    let (shape, rho) = load(&snap.join(file));
    assert_eq!(shape, [100]);
    let col = column(&header, &rows, "mixture_density");
    assert_eq!(col, rho);
}
