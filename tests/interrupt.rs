//! Ctrl-C on `mpmice run`: the process stops at the end of the current
//! step, exits non-zero with a one-line message naming the checkpoint,
//! leaves only whole output files, and `--restart` from that checkpoint
//! finishes with outputs identical to an uninterrupted run.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_mpmice");

/// The shock–helium-bubble case at 100 × 50 cells (about 2 s a run).
fn scene(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/shock_helium_bubble.toml"
    ))
    .expect("case");
    assert_eq!(text.matches("cells = [200, 100]").count(), 1);
    let path = dir.join("bubble.toml");
    std::fs::write(
        &path,
        text.replace("cells = [200, 100]", "cells = [100, 50]"),
    )
    .expect("write");
    path
}

fn run(args: &[&str]) -> std::process::Output {
    Command::new(BIN).args(args).output().expect("mpmice runs")
}

/// Checks that every file in `dir` is whole: XML files close their root,
/// CSV rows have the header's width and parse as numbers, JSON parses; no
/// temporary file is left.
fn assert_all_whole(dir: &Path) {
    for e in std::fs::read_dir(dir).expect("dir") {
        let path = e.expect("entry").path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            !name.ends_with(".tmp") && !name.starts_with('.'),
            "left over: {name}"
        );
        if path.is_dir() {
            continue;
        }
        let bytes = std::fs::read(&path).expect("read");
        if name.ends_with(".vti") || name.ends_with(".vtu") {
            assert!(
                bytes.starts_with(b"<?xml") && bytes.ends_with(b"</VTKFile>\n"),
                "{name}"
            );
        } else if name.ends_with(".pvd") {
            let text = String::from_utf8(bytes).expect("utf8");
            assert!(text.trim_end().ends_with("</VTKFile>"), "{name}");
        } else if name.ends_with(".csv") {
            let text = String::from_utf8(bytes).expect("utf8");
            let mut lines = text.lines();
            let width = lines.next().expect("header").split(',').count();
            for l in lines {
                let cells: Vec<&str> = l.split(',').collect();
                assert_eq!(cells.len(), width, "{name}: {l}");
                for c in cells {
                    c.parse::<f64>().unwrap_or_else(|_| panic!("{name}: `{c}`"));
                }
            }
        } else if name.ends_with(".json") {
            serde_json::from_slice::<serde_json::Value>(&bytes).expect(&name);
        }
    }
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.is_file() && !p.ends_with("summary.json"))
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).expect("read"),
            )
        })
        .collect();
    v.sort();
    v
}

#[test]
fn ctrl_c_stops_cleanly_and_the_restart_matches_an_uninterrupted_run() {
    let tmp = tempfile::tempdir().expect("tmp");
    let scene = scene(tmp.path());
    let scene = scene.to_str().expect("utf8 path");
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    let b_str = b.to_str().expect("utf8");

    // Interrupt once the second snapshot (t = 0.1 of 0.6) is on disk.
    let mut child = Command::new(BIN)
        .args(["run", scene, "--out", b_str, "--quiet", "--threads", "2"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let start = Instant::now();
    while !b.join("cells_0001.vti").exists() {
        assert!(
            child.try_wait().expect("wait").is_none(),
            "the run ended before it could be interrupted"
        );
        assert!(start.elapsed() < Duration::from_secs(300), "no progress");
        std::thread::sleep(Duration::from_millis(20));
    }
    let status = Command::new("sh")
        .args(["-c", &format!("kill -INT {}", child.id())])
        .status()
        .expect("kill");
    assert!(status.success());
    let out = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("{stderr}");
    assert!(!out.status.success(), "an interrupted run exits non-zero");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "one line: {stderr}");
    assert!(
        lines[0].starts_with("error: interrupted after step") && lines[0].contains("saved in "),
        "{stderr}"
    );
    let ck = lines[0].rsplit("saved in ").next().expect("path").trim();
    assert!(Path::new(ck).join("manifest.json").is_file(), "{ck}");
    assert_all_whole(&b);
    assert!(!b.join("cells_0006.vti").exists(), "stopped before the end");

    let rest = run(&["run", scene, "--out", b_str, "--quiet", "--restart", ck]);
    assert!(
        rest.status.success(),
        "{}",
        String::from_utf8_lossy(&rest.stderr)
    );
    let full = run(&["run", scene, "--out", a.to_str().unwrap(), "--quiet"]);
    assert!(
        full.status.success(),
        "{}",
        String::from_utf8_lossy(&full.stderr)
    );
    assert_all_whole(&b);
    let (fa, fb) = (files(&a), files(&b));
    assert_eq!(
        fa.iter().map(|f| &f.0).collect::<Vec<_>>(),
        fb.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    for ((name, x), (_, y)) in fa.iter().zip(&fb) {
        assert!(x == y, "{name} differs after the interrupt and restart");
    }
    println!("{} files identical", fa.len());
}
