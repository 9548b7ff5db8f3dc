//! `verification bench-report` (`verification::bench_report`): a fake
//! criterion tree is scanned, tabulated and written. (Outside the library,
//! so that `cargo test` does not compile the whole study library a second
//! time as a unit-test harness for these six tests.)

use std::cmp::Ordering;
use std::path::Path;
use std::time::{SystemTime, UNIX_EPOCH};

use verification::bench_report::*;

/// Writes a criterion result folder `<root>/<rel>/new/`.
fn fake(
    root: &Path,
    rel: &str,
    group: &str,
    function: Option<&str>,
    value: Option<&str>,
    throughput: &str,
    median: f64,
) {
    let d = root.join(rel).join("new");
    std::fs::create_dir_all(&d).unwrap();
    let js = |o: Option<&str>| o.map_or("null".to_string(), |s| format!("\"{s}\""));
    std::fs::write(
        d.join("benchmark.json"),
        format!(
            r#"{{"group_id":"{group}","function_id":{},"value_str":{},"throughput":{throughput},"full_id":"x","directory_name":"{rel}","title":"x"}}"#,
            js(function),
            js(value)
        ),
    )
    .unwrap();
    let est = |m: f64| {
        format!(
            r#"{{"confidence_interval":{{"confidence_level":0.95,"lower_bound":{},"upper_bound":{}}},"point_estimate":{m},"standard_error":1.0}}"#,
            0.9 * m,
            1.1 * m
        )
    };
    std::fs::write(
        d.join("estimates.json"),
        format!(
            r#"{{"mean":{},"median":{},"median_abs_dev":{},"slope":null,"std_dev":{}}}"#,
            est(median * 1.01),
            est(median),
            est(1.0),
            est(2.0)
        ),
    )
    .unwrap();
    // Criterion writes these too; the scan must ignore them.
    std::fs::write(d.join("sample.json"), "{}").unwrap();
}

fn tree() -> tempfile::TempDir {
    let t = tempfile::tempdir().unwrap();
    let r = t.path();
    let el = r#"{"Elements":1000}"#;
    fake(
        r,
        "grp/bspline2/1",
        "grp",
        Some("bspline2"),
        Some("1"),
        el,
        2e6,
    );
    fake(
        r,
        "grp/bspline2/2",
        "grp",
        Some("bspline2"),
        Some("2"),
        el,
        1e6,
    );
    fake(
        r,
        "grp/cells_204800/1",
        "grp",
        Some("cells_204800"),
        Some("1"),
        el,
        4e6,
    );
    fake(
        r,
        "grp/cells_3200/1",
        "grp",
        Some("cells_3200"),
        Some("1"),
        el,
        5e3,
    );
    // A stale base run beside the new one: not a result.
    std::fs::create_dir_all(r.join("grp/bspline2/1/base")).unwrap();
    fake(
        r,
        "pcg/solve_256_2/2",
        "pcg",
        Some("solve/256^2"),
        Some("2"),
        "null",
        3e8,
    );
    fake(
        r,
        "pcg/solve_256_2/1",
        "pcg",
        Some("solve/256^2"),
        Some("1"),
        "null",
        4.5e8,
    );
    fake(r, "solo/fn", "solo", Some("fn"), None, "null", 750.0);
    fake(r, "mat/neo/1", "mat", Some("neo"), Some("1"), el, 1e7);
    // Incomplete: estimates.json missing.
    let inc = r.join("grp/broken/1/new");
    std::fs::create_dir_all(&inc).unwrap();
    std::fs::write(inc.join("benchmark.json"), "{}").unwrap();
    t
}

#[test]
fn bench_report_parses_a_fake_criterion_tree() {
    let t = tree();
    let s = scan(t.path(), None).unwrap();
    assert_eq!(s.records.len(), 8, "{:?}", s.records);
    assert_eq!(s.notes.len(), 1, "{:?}", s.notes);
    assert!(s.notes[0].contains("grp/broken/1") && s.notes[0].contains("estimates.json"));
    let r = s
        .records
        .iter()
        .find(|r| r.group == "pcg" && r.value.as_deref() == Some("1"))
        .unwrap();
    assert_eq!(r.function.as_deref(), Some("solve/256^2"));
    assert_eq!(r.median_ns, 4.5e8);
    assert_eq!(r.ci_ns, (0.9 * 4.5e8, 1.1 * 4.5e8));
    assert_eq!(r.throughput, None);
    let r = s.records.iter().find(|r| r.group == "solo").unwrap();
    assert_eq!(
        (r.function.as_deref(), r.value.as_deref()),
        (Some("fn"), None)
    );
    let r = s
        .records
        .iter()
        .find(|r| r.function.as_deref() == Some("bspline2") && r.value.as_deref() == Some("2"))
        .unwrap();
    assert_eq!(r.throughput, Some(Throughput::Elements(1000)));
}

#[test]
fn bench_report_tables_pair_threads_and_sort() {
    let t = tree();
    let s = scan(t.path(), None).unwrap();
    let md = tables(&s.records);
    // Groups sorted by name.
    let pos = |needle: &str| md.find(needle).unwrap_or_else(|| panic!("{needle}\n{md}"));
    assert!(pos("### `grp`") < pos("### `mat`"));
    assert!(pos("### `mat`") < pos("### `pcg`"));
    assert!(pos("### `pcg`") < pos("### `solo`"));
    // Thread pairs: 2 ms / 1 ms = 2.00x on the 2-thread row; 1000
    // elements in 1 ms = 1 M elem/s.
    assert!(
        md.contains("| `bspline2` | 2 | 1.00 ms [0.900, 1.10] | 1.00 M elem/s | 2.00× |"),
        "{md}"
    );
    assert!(md.contains("| `bspline2` | 1 | 2.00 ms [1.80, 2.20] | 500 k elem/s |  |"));
    // Natural order: 3200 before 204800.
    assert!(pos("`cells_3200`") < pos("`cells_204800`"));
    assert!(
        md.contains("| `solve/256^2` | 2 | 300 ms [270, 330] | 1.50× |"),
        "{md}"
    );
    // No pair: the parameter stays in the name, no threads column.
    assert!(
        md.contains("| `neo/1` | 10.0 ms [9.00, 11.0] | 100 k elem/s |"),
        "{md}"
    );
    assert!(md.contains("| `fn` | 750 ns [675, 825] |"), "{md}");
    // Deterministic.
    let mut shuffled = s.records.clone();
    shuffled.reverse();
    assert_eq!(tables(&shuffled), md);
}

#[test]
fn bench_report_malformed_json_names_the_file() {
    let t = tree();
    let bad = t.path().join("grp/bspline2/2/new/estimates.json");
    std::fs::write(&bad, "{ not json").unwrap();
    let err = format!("{:#}", scan(t.path(), None).unwrap_err());
    assert!(err.contains("grp/bspline2/2/new/estimates.json"), "{err}");
    std::fs::write(&bad, r#"{"median": {}}"#).unwrap();
    let err = format!("{:#}", scan(t.path(), None).unwrap_err());
    assert!(
        err.contains("estimates.json") && err.contains("point_estimate"),
        "{err}"
    );
}

#[test]
fn bench_report_since_leaves_out_old_results() {
    let t = tree();
    let future = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_secs()
        + 3600;
    let s = scan(t.path(), Some(future)).unwrap();
    assert!(s.records.is_empty());
    assert!(
        s.notes.iter().any(|n| n.contains("left out 8")),
        "{:?}",
        s.notes
    );
}

#[test]
fn bench_report_writes_the_file() {
    let t = tree();
    let out = t.path().join("out/RESULTS.md");
    let args = BenchReportArgs {
        criterion_dir: Some(t.path().to_path_buf()),
        out: Some(out.clone()),
        since: None,
        load_before: Some(" 07:33:37 up 11:15,  load average: 0.51, 1.33, 1.71\n".into()),
    };
    run(&args, t.path()).unwrap();
    let md = std::fs::read_to_string(out).unwrap();
    assert!(md.starts_with("# Benchmark results"));
    for needle in [
        "- date: ",
        "- git revision: ",
        "- machine: ",
        "load average",
        "## Notes",
        "bench/run",
    ] {
        assert!(md.contains(needle), "{needle}\n{md}");
    }
    // A missing criterion folder is an error, not a panic.
    let args = BenchReportArgs {
        criterion_dir: Some(t.path().join("nowhere")),
        ..BenchReportArgs::default()
    };
    assert!(run(&args, t.path()).is_err());
}

#[test]
fn bench_report_helpers() {
    assert_eq!(utc_string(0), "1970-01-01 00:00 UTC");
    assert_eq!(utc_string(951_782_400 + 3_661), "2000-02-29 01:01 UTC");
    assert_eq!(natural_cmp("a10", "a9"), Ordering::Greater);
    assert_eq!(natural_cmp("a09", "a9"), Ordering::Less);
    assert_eq!(sig3(0.0123), "0.0123");
    assert_eq!(si(3.42e6), "3.42 M");
    assert_eq!(sig3(99.97), "100");
    assert_eq!(sig3(9.996), "10.0");
    assert_eq!(sig3(0.9996), "1.00");
    assert_eq!(sig3(1234.5), "1230");
}
