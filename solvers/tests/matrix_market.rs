//! Matrix Market output round trip.

use solvers::{write_matrix_market, Assembler};

/// Minimal reader for `coordinate real general` files (test only).
fn read_mm(text: &str) -> (usize, usize, Vec<(usize, usize, f64)>) {
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    assert_eq!(header, "%%MatrixMarket matrix coordinate real general");
    let mut lines = lines.filter(|l| !l.starts_with('%'));
    let dims: Vec<usize> = lines
        .next()
        .unwrap()
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    let entries: Vec<(usize, usize, f64)> = lines
        .map(|l| {
            let t: Vec<&str> = l.split_whitespace().collect();
            (
                t[0].parse::<usize>().unwrap() - 1,
                t[1].parse::<usize>().unwrap() - 1,
                t[2].parse().unwrap(),
            )
        })
        .collect();
    assert_eq!(entries.len(), dims[2]);
    (dims[0], dims[1], entries)
}

/// A small rectangular matrix with awkward values survives the round trip
/// bit for bit, and no temporary file is left behind.
#[test]
fn matrix_market_round_trip() {
    let rows = [0, 2, 1, 3, 0, 2];
    let cols = [0, 0, 1, 2, 3, 3];
    let vals = [1.5, -2.0e-300, std::f64::consts::PI, 1e300, -0.1, 7.0];
    let a = Assembler::from_triplets(4, 5, &rows, &cols, &vals)
        .unwrap()
        .into_matrix();
    let dir = std::env::temp_dir().join(format!("solvers_mm_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("a.mtx");
    write_matrix_market(&path, &a).unwrap();
    assert!(!dir.join("a.mtx.tmp").exists());
    let (m, n, entries) = read_mm(&std::fs::read_to_string(&path).unwrap());
    assert_eq!((m, n), (4, 5));
    let mut expect: Vec<(usize, usize, f64)> = rows
        .iter()
        .zip(&cols)
        .zip(&vals)
        .map(|((&r, &c), &v)| (r, c, v))
        .collect();
    expect.sort_by_key(|e| (e.1, e.0));
    assert_eq!(entries, expect);
    // Writing into a missing directory is an I/O error, not a panic.
    let bad = dir.join("missing").join("b.mtx");
    assert!(matches!(
        write_matrix_market(&bad, &a),
        Err(solvers::SolverError::Io(_))
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}
