//! Plain CSV output: whole tables written atomically ([`write_columns`],
//! [`write_rows`]) and
//! append-as-you-go history files ([`CsvAppender`]).
//!
//! Numbers are written in Rust's shortest round-trip form (plain notation
//! such as `0.25` for moderate magnitudes, scientific such as `1.5e-7` for
//! tiny or huge ones; `NaN`, `inf`, `-inf` for non-finite values), so
//! parsing them with `str::parse::<f64>` gives back exactly the written
//! bits. Header names are written as given (they carry units, e.g.
//! `x [m]`); a name containing a comma, quote or line break is quoted as in
//! RFC 4180. Lines end with `\n`.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::{atomic_write, push_f64};

/// Rows formatted by one task of [`write_rows`].
const ROW_CHUNK: usize = 256;

/// Chunks formatted in parallel before they are written: 4096 rows, a few
/// MiB of text held at a time.
const CHUNK_BATCH: usize = 16;

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// Quotes a header cell if it contains a separator, quote or line break.
fn header_cell(name: &str) -> String {
    if name.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", name.replace('"', "\"\""))
    } else {
        name.to_string()
    }
}

fn header_line(header: &[&str]) -> String {
    let mut line = header
        .iter()
        .map(|h| header_cell(h))
        .collect::<Vec<_>>()
        .join(",");
    line.push('\n');
    line
}

/// Appends one CSV row of `values` (with the trailing newline) to `line`.
fn push_row(line: &mut String, values: impl Iterator<Item = f64>) {
    for (i, v) in values.enumerate() {
        if i > 0 {
            line.push(',');
        }
        push_f64(line, v);
    }
    line.push('\n');
}

/// Writes a table atomically: a header line, then one row per index of the
/// columns (`columns[j][i]` is row `i`, column `j`).
///
/// # Errors
/// [`io::ErrorKind::InvalidInput`] when `header` and `columns` differ in
/// count or the columns differ in length (nothing is written then);
/// otherwise any I/O error of the write.
pub fn write_columns(path: &Path, header: &[&str], columns: &[&[f64]]) -> io::Result<()> {
    if header.len() != columns.len() {
        return Err(invalid(format!(
            "{} header names for {} columns",
            header.len(),
            columns.len()
        )));
    }
    let rows = columns.first().map_or(0, |c| c.len());
    if let Some((j, c)) = columns.iter().enumerate().find(|(_, c)| c.len() != rows) {
        return Err(invalid(format!(
            "column \"{}\" has {} values, expected {rows} (as column \"{}\")",
            header[j],
            c.len(),
            header[0]
        )));
    }
    write_rows(path, header, rows, |i, row| {
        row.extend(columns.iter().map(|c| c[i]))
    })
}

/// Writes a table atomically, row by row, without holding it: a header
/// line, then `rows` rows, row `i` being the values `fill(i, row)` appends
/// to the (cleared) `row`. Rows are formatted in parallel, 256 to a task
/// and 16 tasks at a time, and written in order, so the
/// file is the same for any thread count.
///
/// # Errors
/// [`io::ErrorKind::InvalidInput`] when a row has another number of values
/// than the header (the first such row is named; the file is left as it
/// was); otherwise any I/O error of the write.
pub fn write_rows(
    path: &Path,
    header: &[&str],
    rows: usize,
    fill: impl Fn(usize, &mut Vec<f64>) + Sync,
) -> io::Result<()> {
    let width = header.len();
    // One task's rows: its text, and the first row of a wrong width.
    let format = |first: usize, text: &mut String, row: &mut Vec<f64>| -> Result<(), usize> {
        text.clear();
        for i in first..(first + ROW_CHUNK).min(rows) {
            row.clear();
            fill(i, row);
            if row.len() != width {
                return Err(i);
            }
            push_row(text, row.iter().copied());
        }
        Ok(())
    };
    atomic_write(path, |w| {
        w.write_all(header_line(header).as_bytes())?;
        let mut tasks = vec![(String::new(), Vec::with_capacity(width)); CHUNK_BATCH];
        for start in (0..rows).step_by(ROW_CHUNK * CHUNK_BATCH) {
            let n = (rows - start).div_ceil(ROW_CHUNK).min(CHUNK_BATCH);
            let done: Vec<Result<(), usize>> = tasks[..n]
                .par_iter_mut()
                .enumerate()
                .map(|(c, (text, row))| format(start + c * ROW_CHUNK, text, row))
                .collect();
            if let Some(&Err(i)) = done.iter().find(|r| r.is_err()) {
                let mut row = Vec::new();
                fill(i, &mut row);
                return Err(invalid(format!(
                    "row {i} has {} values for {width} header names",
                    row.len()
                )));
            }
            for (text, _) in &tasks[..n] {
                w.write_all(text.as_bytes())?;
            }
        }
        Ok(())
    })
}

/// An append-as-you-go CSV history file (e.g. energy vs. time).
///
/// Each [`row`](Self::row) is written with a single `write` and flushed to
/// the operating system immediately, so every row already written survives
/// a crash or kill of the process. [`flush`](Self::flush) additionally
/// syncs the file to disk (survives a power loss).
#[derive(Debug)]
pub struct CsvAppender {
    path: PathBuf,
    writer: BufWriter<File>,
    columns: usize,
    rows: u64,
}

impl CsvAppender {
    /// Creates (or truncates) `path` and writes the header line.
    ///
    /// # Errors
    /// [`io::ErrorKind::InvalidInput`] for an empty header; any I/O error of
    /// creating or writing the file.
    pub fn create(path: &Path, header: &[&str]) -> io::Result<Self> {
        if header.is_empty() {
            return Err(invalid(format!(
                "empty CSV header for `{}`",
                path.display()
            )));
        }
        let mut writer = BufWriter::new(File::create(path)?);
        writer.write_all(header_line(header).as_bytes())?;
        writer.flush()?;
        Ok(CsvAppender {
            path: path.to_path_buf(),
            writer,
            columns: header.len(),
            rows: 0,
        })
    }

    /// Appends one row and flushes it to the operating system.
    ///
    /// # Errors
    /// [`io::ErrorKind::InvalidInput`] when `values.len()` differs from the
    /// header's column count (nothing is written then); any I/O error.
    pub fn row(&mut self, values: &[f64]) -> io::Result<()> {
        if values.len() != self.columns {
            return Err(invalid(format!(
                "row of {} values for {} columns in `{}`",
                values.len(),
                self.columns,
                self.path.display()
            )));
        }
        let mut line = String::with_capacity(24 * values.len());
        push_row(&mut line, values.iter().copied());
        self.writer.write_all(line.as_bytes())?;
        self.writer.flush()?;
        self.rows += 1;
        Ok(())
    }

    /// Flushes buffered data and syncs the file's content to disk.
    ///
    /// # Errors
    /// Any I/O error of the flush or sync.
    pub fn flush(&mut self) -> io::Result<()> {
        self.writer.flush()?;
        self.writer.get_ref().sync_data()
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Number of rows written so far (header excluded).
    pub fn rows(&self) -> u64 {
        self.rows
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_dir;
    use super::*;
    use std::fs;

    /// Parses a numeric CSV (simple header without quoted commas).
    fn read(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
        let text = fs::read_to_string(path).expect("read csv");
        let mut lines = text.lines();
        let header = lines
            .next()
            .expect("header")
            .split(',')
            .map(str::to_string)
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(|v| v.parse().expect("f64")).collect())
            .collect();
        (header, rows)
    }

    fn same_bits(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    #[test]
    fn columns_round_trip_bit_exactly() {
        let dir = test_dir("csv");
        let path = dir.join("profile.csv");
        let x: Vec<f64> = (0..50).map(|i| i as f64 / 49.0).collect();
        let mut y: Vec<f64> = x.iter().map(|v| (v * 7.3).sin() * 1e-12).collect();
        y[0] = -0.0;
        y[1] = f64::MAX;
        y[2] = 5e-324;
        y[3] = f64::INFINITY;
        y[4] = f64::NAN;
        y[5] = 0.1 + 0.2;
        y[6] = -123456789.125;
        write_columns(&path, &["x [m]", "p [Pa]"], &[&x, &y]).expect("write");
        let (header, rows) = read(&path);
        assert_eq!(header, vec!["x [m]", "p [Pa]"]);
        assert_eq!(rows.len(), 50);
        for (i, r) in rows.iter().enumerate() {
            assert!(same_bits(r[0], x[i]), "x[{i}]");
            assert!(same_bits(r[1], y[i]), "y[{i}]: {} vs {}", r[1], y[i]);
        }
        assert_eq!(fs::read_dir(&dir).expect("dir").count(), 1, "tmp left");
        fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn header_with_comma_is_quoted() {
        let dir = test_dir("csv-q");
        let path = dir.join("q.csv");
        write_columns(&path, &["a,b", "say \"hi\""], &[&[1.0], &[2.0]]).expect("write");
        let text = fs::read_to_string(&path).expect("read");
        assert_eq!(text, "\"a,b\",\"say \"\"hi\"\"\"\n1,2\n");
        fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn rows_are_written_as_columns_are_and_a_short_row_writes_nothing() {
        let dir = test_dir("csv-rows");
        let (a, b) = (dir.join("a.csv"), dir.join("b.csv"));
        let x = [0.1, 1.0 / 3.0, -2.5e-7];
        let y = [7.0, f64::MAX, 0.0];
        write_columns(&a, &["x [m]", "y [m]"], &[&x, &y]).expect("columns");
        write_rows(&b, &["x [m]", "y [m]"], 3, |i, r| r.extend([x[i], y[i]])).expect("rows");
        assert_eq!(fs::read(&a).expect("a"), fs::read(&b).expect("b"));
        let c = dir.join("c.csv");
        let err = write_rows(&c, &["x [m]", "y [m]"], 3, |i, r| {
            r.push(x[i]);
            if i < 2 {
                r.push(y[i]);
            }
        })
        .expect_err("short row");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert!(err.to_string().contains("row 2"), "{err}");
        assert!(!c.exists());
        fs::remove_dir_all(&dir).expect("cleanup");
    }

    /// A table of many batches is the same file for 1 and 2 threads and
    /// the same as one formatted row by row; a bad row in a later batch is
    /// the one named, the lowest of several.
    #[test]
    fn parallel_rows_match_serial_text_and_name_the_first_bad_row() {
        let dir = test_dir("csv-par");
        let rows = 3 * ROW_CHUNK * CHUNK_BATCH + 17;
        let fill = |i: usize, r: &mut Vec<f64>| {
            let x = i as f64;
            r.extend([x, (x * 0.37).sin() * 1e-9, 1.0 / (x + 1.0), x * 1e17]);
        };
        let h = ["i", "a [m]", "b", "c [Pa]"];
        let mut expect = header_line(&h);
        let mut row = Vec::new();
        for i in 0..rows {
            row.clear();
            fill(i, &mut row);
            push_row(&mut expect, row.iter().copied());
        }
        for threads in [1, 2] {
            let path = dir.join(format!("t{threads}.csv"));
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            pool.install(|| write_rows(&path, &h, rows, fill))
                .expect("rows");
            assert!(
                fs::read_to_string(&path).expect("read") == expect,
                "{threads} threads"
            );
        }
        let bad = |i: usize, r: &mut Vec<f64>| {
            fill(i, r);
            if i == 2 * ROW_CHUNK * CHUNK_BATCH + 5 || i == rows - 1 {
                r.pop();
            }
        };
        let c = dir.join("c.csv");
        let err = write_rows(&c, &h, rows, bad).expect_err("short row");
        let first = 2 * ROW_CHUNK * CHUNK_BATCH + 5;
        assert!(
            err.to_string()
                .contains(&format!("row {first} has 3 values")),
            "{err}"
        );
        assert!(!c.exists());
        fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn unequal_columns_are_invalid_input() {
        let dir = test_dir("csv-bad");
        let path = dir.join("bad.csv");
        let err =
            write_columns(&path, &["t [s]", "E [J]"], &[&[0.0, 1.0], &[2.0]]).expect_err("unequal");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert!(err.to_string().contains("E [J]"), "{err}");
        let err = write_columns(&path, &["t [s]"], &[&[0.0], &[1.0]]).expect_err("count");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert_eq!(fs::read_dir(&dir).expect("dir").count(), 0);
        fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn appender_flushes_every_row() {
        let dir = test_dir("csv-app");
        let path = dir.join("history.csv");
        let mut app = CsvAppender::create(&path, &["t [s]", "E [J]"]).expect("create");
        let data = [[0.0, 1.0], [1e-3, 0.999_999_7], [2e-3, f64::MIN_POSITIVE]];
        for (k, r) in data.iter().enumerate() {
            app.row(r).expect("row");
            // Readable from another handle while the appender is still open.
            let (header, rows) = read(&path);
            assert_eq!(header, vec!["t [s]", "E [J]"]);
            assert_eq!(rows.len(), k + 1);
            assert!(same_bits(rows[k][1], r[1]));
        }
        let err = app.row(&[1.0]).expect_err("short row");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        app.flush().expect("flush");
        assert_eq!(app.rows(), 3);
        let (_, rows) = read(&path);
        assert_eq!(rows.len(), 3);
        fs::remove_dir_all(&dir).expect("cleanup");
    }
}
