//! Output writers: ParaView VTK XML files ([`vtk`]), plain CSV tables and
//! histories ([`csv`]), checkpoint folders ([`checkpoint`]: a manifest and
//! `.npy` arrays), NumPy arrays ([`npy`], also a snapshot format), and the
//! [`atomic_write`] helper they share.
//!
//! Every whole-file output is written through [`atomic_write`], so a crash or
//! an interrupted run never leaves a half-written file behind: readers see
//! either the previous complete version or the new complete version.
//!
//! This module depends on `std` and crates only (the checkpoint format on
//! `serde_json` and `npyz`), never on the solver's other modules.

pub mod checkpoint;
pub mod csv;
pub mod npy;
pub mod vtk;

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Counter making temporary names unique between concurrent writers of one
/// process (the process id separates processes).
static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Writes a file atomically.
///
/// `f` writes the content into a buffered writer on a temporary sibling of
/// `path` (named `.<name>.<pid>.<n>.tmp` in the same directory, so the final
/// rename stays on one file system). The buffer is then flushed and the
/// temporary file is renamed over `path`. On any error (including an error returned by `f`) the temporary file is removed
/// and `path` is left untouched.
///
/// # Errors
/// Returns [`io::ErrorKind::InvalidInput`] when `path` has no file name, and
/// any I/O error from creating, writing, syncing or renaming the file.
pub fn atomic_write<F>(path: &Path, f: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let tmp = tmp_sibling(path, "")?;
    let result = write_and_rename(path, &tmp, f);
    if result.is_err() {
        // Best effort: the temporary file may not exist (e.g. create failed).
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Temporary sibling name of `path`: `.<name>.<pid>.<n>.tmp<suffix>` in
/// the same directory (a suffix keeps an extension that a writer reads the
/// format from, e.g. `.png`).
pub(crate) fn tmp_sibling(path: &Path, suffix: &str) -> io::Result<PathBuf> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("output path `{}` has no file name", path.display()),
        )
    })?;
    let n = TMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.{n}.tmp{suffix}", std::process::id()));
    Ok(path.with_file_name(tmp_name))
}

fn write_and_rename<F>(path: &Path, tmp: &Path, f: F) -> io::Result<()>
where
    F: FnOnce(&mut BufWriter<File>) -> io::Result<()>,
{
    let mut writer = BufWriter::new(File::create(tmp)?);
    f(&mut writer)?;
    writer.flush()?;
    // No fsync: the rename alone guarantees that a crashed or killed run
    // leaves either the old or the new complete file (durability against
    // power loss is not worth one disk flush per snapshot).
    drop(writer.into_inner().map_err(|e| e.into_error())?);
    fs::rename(tmp, path)?;
    Ok(())
}

/// Formats an `f64` so that parsing the text gives back exactly the same
/// bits (Rust's shortest round-trip representation).
///
/// Plain notation (`0.25`, `-3`, `1234.5`) is used for magnitudes in
/// `[1e-5, 1e16)` and for zero; scientific notation (`1.5e-7`) otherwise, so
/// tiny or huge values stay short. Non-finite values print as `NaN`, `inf`
/// and `-inf`, which `str::parse::<f64>` accepts.
pub(crate) fn fmt_f64(x: f64) -> String {
    let mut s = String::new();
    push_f64(&mut s, x);
    s
}

/// Appends [`fmt_f64`]'s text of `x` to `out` (no allocation once `out`
/// has grown).
pub(crate) fn push_f64(out: &mut String, x: f64) {
    use std::fmt::Write as _;
    let a = x.abs();
    // Writing to a String cannot fail.
    let _ = if x == 0.0 || !x.is_finite() || (1e-5..1e16).contains(&a) {
        write!(out, "{x}")
    } else {
        write!(out, "{x:e}")
    };
}

/// A unique, empty scratch directory for unit tests (removed by the caller).
#[cfg(test)]
pub(crate) fn test_dir(tag: &str) -> PathBuf {
    static N: AtomicU64 = AtomicU64::new(0);
    let n = N.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!(
        "mpmice-output-test-{tag}-{}-{n}",
        std::process::id()
    ));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).expect("create test dir");
    dir
}

/// The sorted names in a test folder.
#[cfg(test)]
pub(crate) fn test_entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .expect("read dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use test_entries as entries;

    #[test]
    fn atomic_write_replaces_and_leaves_no_tmp() {
        let dir = test_dir("atomic");
        let path = dir.join("out.txt");
        atomic_write(&path, |w| w.write_all(b"first")).expect("write 1");
        atomic_write(&path, |w| w.write_all(b"second")).expect("write 2");
        assert_eq!(fs::read(&path).expect("read"), b"second");
        assert_eq!(entries(&dir), vec!["out.txt".to_string()]);
        fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn atomic_write_error_keeps_old_file_and_removes_tmp() {
        let dir = test_dir("atomic-err");
        let path = dir.join("out.txt");
        atomic_write(&path, |w| w.write_all(b"good")).expect("write");
        let err = atomic_write(&path, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("simulated failure"))
        })
        .expect_err("must fail");
        assert_eq!(err.to_string(), "simulated failure");
        assert_eq!(fs::read(&path).expect("read"), b"good");
        assert_eq!(entries(&dir), vec!["out.txt".to_string()]);
        fs::remove_dir_all(&dir).expect("cleanup");
    }

    #[test]
    fn atomic_write_rejects_path_without_file_name() {
        let err = atomic_write(Path::new("/"), |_| Ok(())).expect_err("no name");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
    }

    #[test]
    fn fmt_f64_round_trips() {
        let values = [
            0.0,
            -0.0,
            1.0,
            -2.5,
            0.1,
            1.0 / 3.0,
            1e-300,
            -7.25e-6,
            6.02214076e23,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            123456.789,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for v in values {
            let s = fmt_f64(v);
            let back: f64 = s.parse().expect("parse");
            assert_eq!(back.to_bits(), v.to_bits(), "{v} -> {s}");
        }
        assert!(fmt_f64(f64::NAN).parse::<f64>().expect("nan").is_nan());
        assert_eq!(fmt_f64(1e-300), "1e-300");
        assert_eq!(fmt_f64(0.5), "0.5");
    }
}
