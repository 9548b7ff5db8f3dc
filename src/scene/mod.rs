//! Scene files (TOML): schema, validation with key-path errors, and building
//! a run from them.
//!
//! Parsing goes through `serde_path_to_error`, so unknown keys, missing keys and
//! wrong types name their key path; [`Scene::validate`] then checks ranges and
//! cross-references and names the offending key with its allowed range.

mod build;
mod ignored;
mod membrane_elements;
mod multiphase;
mod names;
mod overrides;
mod schema;

pub use build::{
    build_coupled_run, build_fluid_run, build_implicit_run, build_multiphase_run, build_solid_run,
    fill_particles, grid_of,
};
pub use membrane_elements::*;
pub use multiphase::*;
pub use overrides::{load_with, parse_with, split_values, Override};
pub use schema::*;

use crate::error::SceneError;

/// Parses and validates a scene from TOML text.
///
/// A TOML syntax error names its line and column and quotes the offending
/// text; a value of the wrong type or range names its key path (and its
/// line where the parser knows it).
pub fn parse(text: &str) -> Result<Scene, SceneError> {
    let de = toml::Deserializer::parse(text).map_err(|e| syntax_error(text, &e))?;
    let scene: Scene = serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        let message = match inner.span() {
            Some(span) => format!("{} ({})", inner.message(), location(text, Some(span))),
            None => inner.message().to_string(),
        };
        SceneError::new(
            if path == "." {
                "<root>".to_string()
            } else {
                path
            },
            message,
        )
    })?;
    scene.validate()?;
    // The text parsed above, so it parses as a table too.
    if let Ok(raw) = toml::from_str::<toml::Table>(text) {
        scene.reject_ignored(&raw)?;
    }
    Ok(scene)
}

/// A TOML syntax error of `text`, with its line, column and text.
fn syntax_error(text: &str, e: &toml::de::Error) -> SceneError {
    SceneError::new(
        "<toml>",
        format!(
            "not valid TOML: {} ({})",
            e.message(),
            location(text, e.span())
        ),
    )
}

/// `line L, column C: `text`` of a byte span of `text`. Without a span (a
/// few syntax errors carry none) it is the first line after the longest
/// prefix of whole lines that still parses: where the text stops being
/// TOML.
fn location(text: &str, span: Option<std::ops::Range<usize>>) -> String {
    let start = span
        .as_ref()
        .map(|s| s.start)
        .unwrap_or_else(|| first_bad_line(text));
    let start = floor_char_boundary(text, start.min(text.len()));
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line = text[..start].matches('\n').count() + 1;
    let column = text[line_start..start].chars().count() + 1;
    let line_end = text[start..].find('\n').map_or(text.len(), |i| start + i);
    // The span's own text where it has some, else the rest of the line,
    // else the whole line (an error at its end).
    let end = span.map_or(start, |s| floor_char_boundary(text, s.end.min(line_end)));
    let quoted = [&text[start..end.max(start)], &text[start..line_end]]
        .into_iter()
        .find(|s| !s.trim().is_empty())
        .unwrap_or(&text[line_start..line_end])
        .trim_end_matches('\r');
    let quoted: String = quoted.chars().take(60).collect();
    if quoted.trim().is_empty() {
        format!("line {line}, column {column}: end of input")
    } else {
        format!("line {line}, column {column}: `{quoted}`")
    }
}

/// The byte offset of the first line after the longest prefix of whole
/// lines that parses as TOML (the start of the text if none does). Up to
/// [`LINEAR_SEARCH_LINES`] lines every prefix is tried; a longer text is
/// bisected (a few dozen parses), so that a large file cannot make the
/// error slow.
fn first_bad_line(text: &str) -> usize {
    let ends: Vec<usize> = text
        .split_inclusive('\n')
        .scan(0, |at, line| {
            *at += line.len();
            Some(*at)
        })
        .collect();
    let parses = |end: usize| toml::Deserializer::parse(&text[..end]).is_ok();
    let good = if ends.len() <= LINEAR_SEARCH_LINES {
        ends.iter()
            .copied()
            .filter(|&e| parses(e))
            .max()
            .unwrap_or(0)
    } else {
        // The largest k whose prefix parses, assuming prefixes stop
        // parsing at the error and stay broken after it.
        let (mut lo, mut hi) = (0, ends.len());
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if parses(ends[mid - 1]) {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        if lo == 0 {
            0
        } else {
            ends[lo - 1]
        }
    };
    // Skip blank and comment lines after it: the error is on the next
    // line with content.
    let mut at = good;
    for line in text[good..].split_inclusive('\n') {
        let t = line.trim();
        if !(t.is_empty() || t.starts_with('#')) {
            break;
        }
        at += line.len();
    }
    at.min(text.len())
}

/// Texts of up to this many lines are searched prefix by prefix.
const LINEAR_SEARCH_LINES: usize = 2000;

/// The largest char boundary of `text` at or before `i`.
fn floor_char_boundary(text: &str, mut i: usize) -> usize {
    while i > 0 && !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// Reads, parses and validates a scene file.
pub fn load(path: &std::path::Path) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::new("<file>", format!("cannot read {}: {e}", path.display())))?;
    parse(&text)
}

#[cfg(test)]
mod tests {
    use super::{first_bad_line, location};

    /// A text of `n` lines `kI = I` with line `bad` (1-based) broken.
    fn lines(n: usize, bad: usize) -> String {
        (1..=n)
            .map(|i| {
                if i == bad {
                    format!("k{i} = [{i}\n")
                } else {
                    format!("k{i} = {i}\n")
                }
            })
            .collect()
    }

    #[test]
    fn the_first_bad_line_is_found_by_prefix_and_by_bisection() {
        for (n, bad) in [(10, 1), (10, 7), (10, 10), (5000, 3000), (5000, 1)] {
            let text = lines(n, bad);
            let at = first_bad_line(&text);
            let line = text[..at].matches('\n').count() + 1;
            assert_eq!(line, bad, "{n} lines");
            let loc = location(&text, None);
            assert!(
                loc.starts_with(&format!("line {bad}, column 1: `k{bad} = [{bad}`")),
                "{loc}"
            );
        }
    }

    #[test]
    fn a_span_gives_line_column_and_text() {
        let text = "a = 1\nbé = [1, 2\n";
        // The span of `[1, 2` on line 2 (after a two-byte character).
        let start = text.find('[').unwrap();
        assert_eq!(
            location(text, Some(start..start + 5)),
            "line 2, column 6: `[1, 2`"
        );
        assert_eq!(
            location(text, Some(text.len()..text.len())),
            "line 3, column 1: end of input"
        );
    }
}
