//! `verification bench_report`: collects criterion's medians from
//! `$CARGO_TARGET_DIR/criterion` (or `$CRITERION_HOME`, or
//! `<workspace>/target/criterion`) into `bench/RESULTS.md`: a header with
//! the date (UTC), git revision, machine and load, then one table per
//! benchmark group (median with its confidence interval, throughput, and
//! the 2-thread speed-up where a group pairs 1- and 2-thread rows).
//!
//! Criterion writes each benchmark's latest run into
//! `<group>/<function>/<value>/new/` (`benchmark.json`: the id and
//! throughput; `estimates.json`: the statistics in ns). A `new` folder
//! lacking either file is skipped with a note; a file that does not parse
//! is an error naming it. `bench/run` regenerates the whole file.

use std::cmp::Ordering;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use anyhow::{bail, Context};
use clap::Parser;
use serde_json::Value;

/// The command that regenerates `bench/RESULTS.md` from scratch.
pub const REGENERATE: &str = "bench/run";
/// The command that rebuilds `bench/RESULTS.md` from criterion's stored
/// results only.
pub const REPORT_ONLY: &str = "cargo run --release -p verification -- bench_report";

/// Command line of `verification bench_report`.
#[derive(Parser, Debug, Default)]
#[command(
    name = "bench_report",
    about = "Write bench/RESULTS.md from criterion's stored results"
)]
pub struct BenchReportArgs {
    /// Criterion's output folder (default: $CRITERION_HOME, else
    /// $CARGO_TARGET_DIR/criterion, else target/criterion in the workspace).
    #[arg(long)]
    pub criterion_dir: Option<PathBuf>,
    /// The file to write (default: bench/RESULTS.md in the workspace).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Leave out results measured before this time (Unix seconds; the
    /// modification time of `new/estimates.json`): `bench/run` passes its
    /// start time, so that stale rows of benchmarks since renamed or
    /// removed stay out.
    #[arg(long)]
    pub since: Option<u64>,
    /// The machine's load before the benchmarks ran (`bench/run` passes
    /// the output of `uptime`), recorded in the header.
    #[arg(long)]
    pub load_before: Option<String>,
}

/// What one benchmark measured per iteration, from `benchmark.json`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Throughput {
    /// Elements (particles, cells, ...) per iteration.
    Elements(u64),
    /// Bytes per iteration (binary prefixes).
    Bytes(u64),
    /// Bytes per iteration (decimal prefixes).
    BytesDecimal(u64),
    /// Bits per iteration.
    Bits(u64),
}

impl Throughput {
    /// The rate at `median_ns` nanoseconds per iteration, formatted with
    /// its unit (e.g. `3.42 M elem/s`).
    pub fn rate(&self, median_ns: f64) -> String {
        let per_s = |n: u64| n as f64 / (median_ns * 1e-9);
        match *self {
            Throughput::Elements(n) => format!("{} elem/s", si(per_s(n))),
            Throughput::Bytes(n) => format!("{}B/s", binary(per_s(n))),
            Throughput::BytesDecimal(n) => format!("{}B/s", si(per_s(n))),
            Throughput::Bits(n) => format!("{}bit/s", si(per_s(n))),
        }
    }
}

/// One benchmark's latest result.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchRecord {
    /// Criterion group (`mpm_step_2d_100k`).
    pub group: String,
    /// Function within the group (`bspline2`), if any.
    pub function: Option<String>,
    /// Parameter (`2`), if any; in our benches the thread count.
    pub value: Option<String>,
    /// Median time per iteration, ns.
    pub median_ns: f64,
    /// The median's confidence interval, ns.
    pub ci_ns: (f64, f64),
    /// The interval's level (0.95 by default).
    pub confidence_level: f64,
    /// Work per iteration, when the bench declared it.
    pub throughput: Option<Throughput>,
    /// The benchmark's folder, relative to the criterion folder.
    pub dir: PathBuf,
}

/// The results found under a criterion folder.
#[derive(Debug, Default)]
pub struct Scan {
    /// Every complete result, in no particular order.
    pub records: Vec<BenchRecord>,
    /// Skipped folders and why.
    pub notes: Vec<String>,
}

/// Where the report's header comes from.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// `YYYY-MM-DD HH:MM UTC`.
    pub date_utc: String,
    /// `git rev-parse --short HEAD` (+ `-dirty`), or `unknown`.
    pub git_rev: String,
    /// CPU model from /proc/cpuinfo, or `unknown`.
    pub cpu: String,
    /// `std::thread::available_parallelism`.
    pub cores: usize,
    /// /proc/loadavg's 1, 5 and 15 minute averages at report time.
    pub load_at_report: String,
    /// The load before the run, if given.
    pub load_before: Option<String>,
    /// The criterion folder read, as shown.
    pub source: String,
}

/// Reads every benchmark under `dir` (module notes). Results whose
/// `new/estimates.json` is older than `since` (Unix seconds) are left
/// out with one note counting them.
///
/// # Errors
/// A folder that cannot be read, or a `benchmark.json`/`estimates.json`
/// that is not valid JSON or lacks a field (the error names the file).
pub fn scan(dir: &Path, since: Option<u64>) -> anyhow::Result<Scan> {
    let mut out = Scan::default();
    let mut stale = 0usize;
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let mut entries: Vec<_> = std::fs::read_dir(&d)
            .with_context(|| format!("reading {}", d.display()))?
            .collect::<Result<_, _>>()
            .with_context(|| format!("reading {}", d.display()))?;
        entries.sort_by_key(|e| e.file_name());
        for e in entries {
            let ft = e.file_type()?;
            if !ft.is_dir() {
                continue;
            }
            let p = e.path();
            if e.file_name() == "new" && has_files(&p)? {
                let bench_dir = p.parent().unwrap_or(dir);
                let rel = bench_dir.strip_prefix(dir).unwrap_or(bench_dir);
                let (bj, ej) = (p.join("benchmark.json"), p.join("estimates.json"));
                let missing: Vec<&str> = [("benchmark.json", &bj), ("estimates.json", &ej)]
                    .into_iter()
                    .filter(|(_, f)| !f.is_file())
                    .map(|(n, _)| n)
                    .collect();
                if !missing.is_empty() {
                    out.notes.push(format!(
                        "skipped `{}`: no new/{}",
                        rel.display(),
                        missing.join(" or new/")
                    ));
                    continue;
                }
                if let Some(since) = since {
                    let t = std::fs::metadata(&ej)
                        .and_then(|m| m.modified())
                        .with_context(|| format!("reading the time of {}", ej.display()))?;
                    let secs = t.duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs());
                    if secs < since {
                        stale += 1;
                        continue;
                    }
                }
                let mut rec = read_record(&bj, &ej)?;
                rec.dir = rel.to_path_buf();
                out.records.push(rec);
            } else {
                stack.push(p);
            }
        }
    }
    if stale > 0 {
        out.notes.push(format!(
            "left out {stale} result(s) measured before this run (--since)"
        ));
    }
    out.notes.sort();
    Ok(out)
}

/// Whether `dir` holds any plain file (criterion's result folders do; a
/// benchmark function named `new` is a folder of folders).
fn has_files(dir: &Path) -> anyhow::Result<bool> {
    for e in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        if e?.file_type()?.is_file() {
            return Ok(true);
        }
    }
    Ok(false)
}

fn read_json(path: &Path) -> anyhow::Result<Value> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: malformed JSON", path.display()))
}

/// One result from its `benchmark.json` and `estimates.json`.
///
/// # Errors
/// Either file unreadable, not JSON, or lacking a field (naming the file).
pub fn read_record(benchmark_json: &Path, estimates_json: &Path) -> anyhow::Result<BenchRecord> {
    let b = read_json(benchmark_json)?;
    let name = |v: &Value, key: &str| -> anyhow::Result<Option<String>> {
        match v.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::String(s)) => Ok(Some(s.clone())),
            Some(other) => bail!(
                "{}: `{key}` is {other}, not a string",
                benchmark_json.display()
            ),
        }
    };
    let group = name(&b, "group_id")?
        .with_context(|| format!("{}: no `group_id`", benchmark_json.display()))?;
    let throughput =
        match b.get("throughput") {
            None | Some(Value::Null) => None,
            Some(t) => Some(parse_throughput(t).with_context(|| {
                format!("{}: unknown `throughput` {t}", benchmark_json.display())
            })?),
        };
    let e = read_json(estimates_json)?;
    let num = |ptr: &str| -> anyhow::Result<f64> {
        e.pointer(ptr)
            .and_then(Value::as_f64)
            .with_context(|| format!("{}: no number at `{ptr}`", estimates_json.display()))
    };
    Ok(BenchRecord {
        function: name(&b, "function_id")?,
        value: name(&b, "value_str")?,
        group,
        median_ns: num("/median/point_estimate")?,
        ci_ns: (
            num("/median/confidence_interval/lower_bound")?,
            num("/median/confidence_interval/upper_bound")?,
        ),
        confidence_level: num("/median/confidence_interval/confidence_level").unwrap_or(0.95),
        throughput,
        dir: PathBuf::new(),
    })
}

fn parse_throughput(t: &Value) -> Option<Throughput> {
    let obj = t.as_object()?;
    let (kind, v) = obj.iter().next()?;
    let n = v.as_u64();
    match kind.as_str() {
        "Elements" => n.map(Throughput::Elements),
        "Bytes" => n.map(Throughput::Bytes),
        "BytesDecimal" => n.map(Throughput::BytesDecimal),
        "Bits" => n.map(Throughput::Bits),
        "ElementsAndBytes" => v
            .get("elements")
            .and_then(Value::as_u64)
            .map(Throughput::Elements),
        _ => None,
    }
}

/// Orders strings with their digit runs compared as numbers
/// (`cells_3200` before `cells_204800`), then bytewise.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut x, mut y) = (a.as_bytes(), b.as_bytes());
    loop {
        match (x.first(), y.first()) {
            (None, None) => return a.cmp(b),
            (None, _) => return Ordering::Less,
            (_, None) => return Ordering::Greater,
            (Some(c), Some(d)) if c.is_ascii_digit() && d.is_ascii_digit() => {
                let run = |s: &[u8]| s.iter().take_while(|c| c.is_ascii_digit()).count();
                let (m, n) = (run(x), run(y));
                let (p, q) = (trim_zeros(&x[..m]), trim_zeros(&y[..n]));
                let o = p.len().cmp(&q.len()).then_with(|| p.cmp(q));
                if o != Ordering::Equal {
                    return o;
                }
                x = &x[m..];
                y = &y[n..];
            }
            (Some(c), Some(d)) => {
                if c != d {
                    return c.cmp(d);
                }
                x = &x[1..];
                y = &y[1..];
            }
        }
    }
}

fn trim_zeros(s: &[u8]) -> &[u8] {
    let k = s.iter().take_while(|&&c| c == b'0').count();
    &s[k.min(s.len().saturating_sub(1))..]
}

/// A value with an SI prefix and three significant digits (`3.42 M`).
fn si(x: f64) -> String {
    let prefixes = [(1e12, "T"), (1e9, "G"), (1e6, "M"), (1e3, "k")];
    for (scale, p) in prefixes {
        if x.abs() >= scale {
            return format!("{} {p}", sig3(x / scale));
        }
    }
    format!("{} ", sig3(x))
}

/// A value with a binary prefix (`1.20 Gi`).
fn binary(x: f64) -> String {
    let prefixes = [
        (1u64 << 40, "Ti"),
        (1 << 30, "Gi"),
        (1 << 20, "Mi"),
        (1 << 10, "Ki"),
    ];
    for (scale, p) in prefixes {
        if x.abs() >= scale as f64 {
            return format!("{} {p}", sig3(x / scale as f64));
        }
    }
    format!("{} ", sig3(x))
}

/// `x` rounded to three significant digits.
fn round3(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(2 - x.abs().log10().floor() as i32);
    (x * scale).round() / scale
}

/// Three significant digits, without exponent for 0.001 ≤ |x| < 1000.
fn sig3(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    // Round first, so that 99.97 prints as 100, not 100.0.
    let x = round3(x);
    let a = x.abs();
    if a >= 100.0 {
        format!("{x:.0}")
    } else if a >= 10.0 {
        format!("{x:.1}")
    } else if a >= 1.0 {
        format!("{x:.2}")
    } else if a >= 1e-3 {
        let decimals = (2 - a.log10().floor() as i32) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.2e}")
    }
}

/// A time in ns with the unit chosen by the median (`12.3 ms`), so that
/// a median and its interval share a unit.
fn time_unit(ns: f64) -> (f64, &'static str) {
    let a = ns.abs();
    if a >= 1e9 {
        (1e9, "s")
    } else if a >= 1e6 {
        (1e6, "ms")
    } else if a >= 1e3 {
        (1e3, "µs")
    } else {
        (1.0, "ns")
    }
}

/// `12.3 ms [12.1, 12.6]`.
fn median_cell(r: &BenchRecord) -> String {
    // The unit of the rounded median: 999.96 µs shows as 1.00 ms.
    let (scale, unit) = time_unit(round3(r.median_ns));
    format!(
        "{} {unit} [{}, {}]",
        sig3(r.median_ns / scale),
        sig3(r.ci_ns.0 / scale),
        sig3(r.ci_ns.1 / scale)
    )
}

fn escape(s: &str) -> String {
    s.replace('|', "\\|").replace('`', "'")
}

/// One row of a group's table.
struct Row<'a> {
    name: String,
    threads: Option<usize>,
    rec: &'a BenchRecord,
}

/// The markdown tables of `records`, one per group (sorted by group
/// name, then benchmark name, then thread count).
pub fn tables(records: &[BenchRecord]) -> String {
    let mut groups: BTreeMap<&str, Vec<&BenchRecord>> = BTreeMap::new();
    for r in records {
        groups.entry(r.group.as_str()).or_default().push(r);
    }
    let mut out = String::new();
    for (group, recs) in groups {
        // A group pairs threads when some function has rows with the
        // parameters 1 and 2: its parameter is then the thread count.
        let mut values: BTreeMap<Option<&str>, BTreeSet<&str>> = BTreeMap::new();
        for r in &recs {
            if let Some(v) = r.value.as_deref() {
                values.entry(r.function.as_deref()).or_default().insert(v);
            }
        }
        let pairs = values
            .values()
            .any(|vs| vs.contains("1") && vs.contains("2"));
        let mut rows: Vec<Row> = recs
            .iter()
            .map(|&rec| {
                let threads = if pairs {
                    rec.value.as_deref().and_then(|v| v.parse().ok())
                } else {
                    None
                };
                let name = match (&rec.function, &rec.value, threads) {
                    (Some(f), _, Some(_)) => f.clone(),
                    (None, _, Some(_)) => String::new(),
                    (Some(f), Some(v), None) => format!("{f}/{v}"),
                    (Some(f), None, None) => f.clone(),
                    (None, Some(v), None) => v.clone(),
                    (None, None, None) => rec.group.clone(),
                };
                Row { name, threads, rec }
            })
            .collect();
        rows.sort_by(|a, b| {
            natural_cmp(&a.name, &b.name)
                .then_with(|| a.threads.cmp(&b.threads))
                .then_with(|| a.rec.dir.cmp(&b.rec.dir))
        });
        let level = recs.first().map_or(0.95, |r| r.confidence_level);
        let any_tp = rows.iter().any(|r| r.rec.throughput.is_some());
        let _ = writeln!(out, "### `{}`\n", escape(group));
        let mut head = vec!["benchmark".to_string()];
        let mut rule = vec!["---".to_string()];
        if pairs {
            head.push("threads".into());
            rule.push("---:".into());
        }
        head.push(format!("median [{:.0} % CI]", 100.0 * level));
        rule.push("---:".into());
        if any_tp {
            head.push("throughput".into());
            rule.push("---:".into());
        }
        if pairs {
            head.push("2-thread speed-up".into());
            rule.push("---:".into());
        }
        let _ = writeln!(out, "| {} |", head.join(" | "));
        let _ = writeln!(out, "|{}|", rule.join("|"));
        for row in &rows {
            let mut cells = vec![if row.name.is_empty() {
                String::new()
            } else {
                format!("`{}`", escape(&row.name))
            }];
            if pairs {
                cells.push(row.threads.map_or(String::new(), |t| t.to_string()));
            }
            cells.push(median_cell(row.rec));
            if any_tp {
                cells.push(
                    row.rec
                        .throughput
                        .map_or(String::new(), |t| t.rate(row.rec.median_ns)),
                );
            }
            if pairs {
                let one = (row.threads == Some(2))
                    .then(|| {
                        rows.iter()
                            .find(|o| o.name == row.name && o.threads == Some(1))
                    })
                    .flatten();
                cells.push(one.map_or(String::new(), |o| {
                    format!("{:.2}×", o.rec.median_ns / row.rec.median_ns)
                }));
            }
            let _ = writeln!(out, "| {} |", cells.join(" | "));
        }
        out.push('\n');
    }
    out
}

/// The whole `bench/RESULTS.md`.
pub fn render(header: &Header, scan: &Scan) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Benchmark results\n");
    let _ = writeln!(
        s,
        "Generated by `{REPORT_ONLY}` from criterion's results; regenerate everything \
         (benchmarks and this file) with `{REGENERATE}` (see `bench/README.md`). The \
         figures depend on the machine's load: compare rows of one file only.\n"
    );
    let _ = writeln!(s, "- date: {}", header.date_utc);
    let _ = writeln!(s, "- git revision: `{}`", header.git_rev);
    let _ = writeln!(
        s,
        "- machine: {}, {} cores available",
        header.cpu, header.cores
    );
    if let Some(l) = &header.load_before {
        let _ = writeln!(s, "- load before the run (`uptime`): {}", l.trim());
    }
    let _ = writeln!(
        s,
        "- load average at report time (1, 5, 15 min): {}",
        header.load_at_report
    );
    let _ = writeln!(s, "- source: `{}`", header.source);
    let _ = writeln!(
        s,
        "\nMedians are criterion's, per iteration (one step or one solve); \
         throughput is the bench's declared elements (particles, cells, …) per \
         second at the median; the 2-thread speed-up is median(1 thread) / \
         median(2 threads).\n"
    );
    if scan.records.is_empty() {
        let _ = writeln!(s, "No benchmark results were found.\n");
    }
    s.push_str(&tables(&scan.records));
    if !scan.notes.is_empty() {
        let _ = writeln!(s, "## Notes\n");
        for n in &scan.notes {
            let _ = writeln!(s, "- {n}");
        }
    }
    s
}

/// The UTC calendar time of `secs` since the epoch, `YYYY-MM-DD HH:MM UTC`
/// (the date of `summary.json`'s provenance, to the minute).
pub fn utc_string(secs: u64) -> String {
    let iso = mpmice::driver::summary::utc_of(secs);
    format!("{} {} UTC", &iso[..10], &iso[11..16])
}

fn git_rev(root: &Path) -> String {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .arg("-C")
            .arg(root)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match git(&["rev-parse", "--short", "HEAD"]) {
        Some(rev) if !rev.is_empty() => {
            let dirty = git(&["status", "--porcelain", "--untracked-files=no"])
                .is_some_and(|s| !s.is_empty());
            if dirty {
                format!("{rev}-dirty")
            } else {
                rev
            }
        }
        _ => "unknown".into(),
    }
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(", "))
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

/// Criterion's folder: `$CRITERION_HOME`, else `$CARGO_TARGET_DIR/criterion`,
/// else `<root>/target/criterion` (criterion's own order).
pub fn default_criterion_dir(root: &Path) -> PathBuf {
    if let Some(h) = std::env::var_os("CRITERION_HOME").filter(|v| !v.is_empty()) {
        return PathBuf::from(h);
    }
    match std::env::var_os("CARGO_TARGET_DIR").filter(|v| !v.is_empty()) {
        // Relative to the working directory, as cargo reads it.
        Some(t) => PathBuf::from(t).join("criterion"),
        None => root.join("target/criterion"),
    }
}

/// Runs `bench_report` for the workspace at `root`: scans, renders and
/// writes the report, printing the notes to stderr. Returns the path
/// written.
///
/// # Errors
/// No criterion folder, a malformed result file, or the report not
/// writable.
pub fn run(args: &BenchReportArgs, root: &Path) -> anyhow::Result<PathBuf> {
    let dir = args
        .criterion_dir
        .clone()
        .unwrap_or_else(|| default_criterion_dir(root));
    if !dir.is_dir() {
        bail!(
            "no criterion results at {} (run `{REGENERATE}` or `cargo bench` first)",
            dir.display()
        );
    }
    let scan = scan(&dir, args.since)?;
    for n in &scan.notes {
        eprintln!("note: {n}");
    }
    let now = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let header = Header {
        date_utc: utc_string(now),
        git_rev: git_rev(root),
        cpu: cpu_model(),
        cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
        load_at_report: load_average(),
        load_before: args.load_before.clone(),
        source: dir.strip_prefix(root).unwrap_or(&dir).display().to_string(),
    };
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| root.join("bench/RESULTS.md"));
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("creating {}", parent.display()))?;
    }
    // Written under a temporary name and renamed: never half a file.
    let text = render(&header, &scan);
    mpmice::output::atomic_write(&out, |w| {
        use std::io::Write as _;
        w.write_all(text.as_bytes())
    })
    .with_context(|| format!("writing {}", out.display()))?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
