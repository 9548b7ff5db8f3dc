//! Scene fuzzing (issue 22): seeded mutations of the scenes in `cases/` —
//! lines deleted or duplicated, values and keys altered, text truncated,
//! characters swapped or inserted — each checked through the library
//! (`scene::parse`, then `driver::check_scene`, everything `run` checks
//! before its first step), and every scene `check` accepts is run for at
//! most three steps (`driver::run_scene`, outputs in a temporary
//! folder). None may panic or hang; every TOML syntax error names its line
//! and column.

use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Marsaglia's xorshift64 (no dependency, same sequence everywhere).
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Values that stress ranges, types and sizes.
const VALUES: [&str; 22] = [
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-308",
    "nan",
    "inf",
    "-inf",
    "1e9",
    "3",
    "1.5",
    "100000",
    "18446744073709551615",
    "-0.0",
    "\"x\"",
    "true",
    "[]",
    "[1e308, 1e308]",
    "{}",
    "0.5",
    "[0, 0, 0]",
    "65536",
];

/// The byte offset of char boundary at or before `i`.
fn floor(text: &str, mut i: usize) -> usize {
    i = i.min(text.len());
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// One seeded mutation of `text`; returns the mutated text and what was
/// done.
fn mutate(text: &str, rng: &mut XorShift) -> (String, String) {
    let lines: Vec<&str> = text.lines().collect();
    if lines.is_empty() || text.len() < 2 {
        return (text.to_string(), "none".into());
    }
    let k = rng.below(lines.len());
    match rng.below(8) {
        0 => {
            let mut l = lines.clone();
            l.remove(k);
            (l.join("\n"), format!("delete line {}", k + 1))
        }
        1 => {
            let mut l = lines.clone();
            l.insert(k, lines[k]);
            (l.join("\n"), format!("duplicate line {}", k + 1))
        }
        2 | 3 => {
            // A value: the text after the `=` of a key line.
            let keyed: Vec<usize> = (0..lines.len())
                .filter(|&i| lines[i].contains('=') && !lines[i].trim_start().starts_with('#'))
                .collect();
            if keyed.is_empty() {
                return (text.to_string(), "none".into());
            }
            let i = keyed[rng.below(keyed.len())];
            let v = VALUES[rng.below(VALUES.len())];
            let (key, old) = lines[i].split_once('=').unwrap_or((lines[i], ""));
            // Inside an inline table or array, replace one number only.
            let new_line = match old.find(|c: char| c.is_ascii_digit()) {
                Some(d) if old.contains('{') || old.contains('[') => {
                    let end = old[d..]
                        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-'))
                        .map_or(old.len(), |e| d + e);
                    format!("{key}={}{v}{}", &old[..d], &old[end..])
                }
                _ => format!("{key}= {v}"),
            };
            let mut l = lines.clone();
            l[i] = &new_line;
            (l.join("\n"), format!("line {}: `{new_line}`", i + 1))
        }
        4 => {
            // A key: one character dropped or doubled.
            let line = lines[k];
            let Some((key, rest)) = line.split_once('=') else {
                return (text.to_string(), "none".into());
            };
            let key = key.trim_end();
            if key.is_empty() {
                return (text.to_string(), "none".into());
            }
            let j = floor(key, rng.below(key.len()));
            let new_key = if rng.below(2) == 0 {
                format!("{}{}", &key[..j], &key[floor(key, j + 1)..])
            } else {
                format!("{}{}", &key[..floor(key, j + 1)], &key[j..])
            };
            let new_line = format!("{new_key} ={rest}");
            let mut l = lines.clone();
            l[k] = &new_line;
            (l.join("\n"), format!("line {}: `{new_line}`", k + 1))
        }
        5 => {
            let at = floor(text, rng.below(text.len()));
            (text[..at].to_string(), format!("truncate at byte {at}"))
        }
        6 => {
            // Swap two adjacent ASCII characters.
            let b = text.as_bytes();
            let at = rng.below(text.len().saturating_sub(1));
            if !(b[at].is_ascii() && b[at + 1].is_ascii()) {
                return (text.to_string(), "none".into());
            }
            let mut v = b.to_vec();
            v.swap(at, at + 1);
            (
                String::from_utf8(v).expect("ascii swap"),
                format!("swap bytes {at}, {}", at + 1),
            )
        }
        _ => {
            let at = floor(text, rng.below(text.len()));
            let c = ["[", "]", "=", "\"", "{", "}", ",", "\n", "#", "[[", "'''"][rng.below(11)];
            (
                format!("{}{c}{}", &text[..at], &text[at..]),
                format!("insert `{c}` at byte {at}"),
            )
        }
    }
}

/// What became of one mutated scene.
enum Verdict {
    /// A TOML syntax error, with its message.
    Syntax(String),
    /// Rejected by the parser or validation, naming a key path.
    Rejected,
    /// Parsed; `check` refused it.
    Refused,
    /// Accepted by `check` and run for at most three steps: it ran to its
    /// step limit or end (`true`) or stopped with an error.
    Ran(bool),
}

/// The verdict on one mutated scene: `Err` for a panic. A scene `check`
/// accepts is also run for at most three steps, its outputs in `dir`
/// (removed after).
fn verdict(text: &str, dir: std::path::PathBuf) -> Result<Verdict, String> {
    let text = text.to_string();
    std::panic::catch_unwind(move || {
        let s = match mpmice::scene::parse(&text) {
            Ok(s) => s,
            Err(e) if e.path == "<toml>" => return Verdict::Syntax(e.message),
            Err(_) => return Verdict::Rejected,
        };
        let opts = mpmice::driver::RunOptions {
            threads: 1,
            memory_limit: Some(256 << 20),
            ..Default::default()
        };
        if mpmice::driver::check_scene(&s, &opts).is_err() {
            return Verdict::Refused;
        }
        let mut s = s;
        s.time.max_steps = Some(3);
        let opts = mpmice::driver::RunOptions {
            out_dir: dir.clone(),
            ..opts
        };
        let ran = mpmice::driver::run_scene(&s, &opts).is_ok();
        let _ = std::fs::remove_dir_all(&dir);
        Verdict::Ran(ran)
    })
    .map_err(|p| {
        p.downcast_ref::<String>()
            .cloned()
            .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default()
    })
}

#[test]
fn mutated_scenes_never_panic_or_hang_and_syntax_errors_have_a_location() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/cases");
    let mut cases: Vec<(String, String)> = std::fs::read_dir(dir)
        .expect("cases")
        .filter_map(|e| {
            let p = e.ok()?.path();
            (p.extension()? == "toml").then(|| {
                (
                    p.file_name().unwrap().to_string_lossy().into_owned(),
                    std::fs::read_to_string(&p).expect("case"),
                )
            })
        })
        .collect();
    cases.sort();
    assert!(cases.len() >= 20);
    // Quiet panics of the checking threads: each is reported below with
    // its mutation.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if std::thread::current().name() != Some("check") {
            default_hook(info);
        }
    }));
    let mut rng = XorShift(0x2545_F491_4F6C_DD1D);
    let (mut syntax, mut located, mut rejected) = (0, 0, 0);
    let (mut accepted, mut refused, mut ran, mut stopped) = (0, 0, 0, 0);
    let scratch = std::env::temp_dir().join(format!("mpmice_fuzz_{}", std::process::id()));
    let mut failures = Vec::new();
    let start = Instant::now();
    const MUTATIONS: usize = 2000;
    for n in 0..MUTATIONS {
        let (name, text) = &cases[rng.below(cases.len())];
        // One to three mutations in a row.
        let (mut mutated, mut what) = mutate(text, &mut rng);
        for _ in 0..rng.below(3) {
            let (m, w) = mutate(&mutated, &mut rng);
            (mutated, what) = (m, format!("{what}; {w}"));
        }
        let (tx, rx) = mpsc::channel();
        let t = mutated.clone();
        let dir = scratch.join(n.to_string());
        std::thread::Builder::new()
            .name("check".into())
            .spawn(move || {
                let _ = tx.send(verdict(&t, dir));
            })
            .expect("thread");
        match rx.recv_timeout(Duration::from_secs(20)) {
            Ok(Ok(Verdict::Syntax(message))) => {
                syntax += 1;
                if message.contains("line ") && message.contains("column ") {
                    located += 1;
                } else {
                    failures.push(format!("{name} ({what}): no location: {message}"));
                }
            }
            Ok(Ok(Verdict::Rejected)) => rejected += 1,
            Ok(Ok(Verdict::Refused)) => refused += 1,
            Ok(Ok(Verdict::Ran(ok))) => {
                accepted += 1;
                if ok {
                    ran += 1;
                } else {
                    stopped += 1;
                }
            }
            Ok(Err(panic)) => failures.push(format!("{name} ({what}): panicked: {panic}")),
            Err(_) => {
                failures.push(format!("{name} ({what}): no answer in 20 s (hang)"));
                break;
            }
        }
        if n % 50 == 49 {
            eprintln!(
                "{} mutations, {:.1} s",
                n + 1,
                start.elapsed().as_secs_f64()
            );
        }
    }
    let _ = std::panic::take_hook();
    let _ = std::fs::remove_dir_all(&scratch);
    eprintln!(
        "{MUTATIONS} mutations in {:.1} s: {syntax} TOML syntax errors ({located} with line and \
         column), {rejected} rejected by the parser or validation, {accepted} accepted and \
         {refused} refused by check; of the accepted, {ran} ran three steps and {stopped} \
         stopped with an error",
        start.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert_eq!(located, syntax);
    assert!(
        syntax > 30 && rejected > 30 && accepted > 30 && ran > 30,
        "{syntax} {rejected} {accepted} {ran}"
    );
}
