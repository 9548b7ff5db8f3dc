//! Scene overrides from the command line: `--set key.path=value` on `run`,
//! `check` and `study`, and the value lists of `study --sweep`.
//!
//! A key path is dotted TOML keys with optional array indices:
//! `grid.cells`, `time.end`, `materials[1].density`, `objects.0.velocity`.
//! An element of an array of tables may also be picked by its `name`
//! (`materials.steel.density`). A value is TOML (`[800]`, `0.4`, `"mc"`,
//! `{ type = "box", lower = [0], upper = [1] }`); a bare word that is not
//! TOML is taken as a string (`fluid.variant=literal`). Missing tables on
//! the way are created, so a key of a section the file leaves out can be
//! set. The overridden text is then parsed and validated like a scene file,
//! so an unknown key or a wrong value is named by its key path.

use crate::error::SceneError;

/// One `key.path=value` override.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    /// The key path as written.
    pub path: String,
    /// Its parsed segments.
    segments: Vec<Segment>,
    /// The value.
    pub value: toml::Value,
}

/// One step of a key path.
#[derive(Debug, Clone, PartialEq)]
enum Segment {
    /// A table key (or, in an array of tables, the element's `name`).
    Key(String),
    /// An array index.
    Index(usize),
}

impl Override {
    /// Parses `key.path=value`.
    ///
    /// # Errors
    /// A missing `=`, an empty or malformed key path, or a value that is
    /// neither TOML nor a bare word; the error's path is `--set`.
    pub fn parse(arg: &str) -> Result<Self, SceneError> {
        let (path, value) = arg.split_once('=').ok_or_else(|| {
            SceneError::new(
                "--set",
                format!("`{arg}` is not key.path=value (e.g. grid.cells=[800])"),
            )
        })?;
        Self::new(path, value)
    }

    /// An override of `path` with the value text `value`.
    ///
    /// # Errors
    /// As [`Override::parse`].
    pub fn new(path: &str, value: &str) -> Result<Self, SceneError> {
        let path = path.trim();
        let segments = segments(path)?;
        let value = parse_value(path, value.trim())?;
        Ok(Self {
            path: path.to_string(),
            segments,
            value,
        })
    }

    /// Sets the value in `table`.
    ///
    /// # Errors
    /// A path through a value that is not a table or an array, an index
    /// past the end of its array, or a name no element of the array has;
    /// the error names the path up to that point.
    pub fn apply(&self, table: &mut toml::Table) -> Result<(), SceneError> {
        let (last, rest) = self.segments.split_last().expect("a path has a segment");
        let mut at = String::new();
        let mut here = Slot::Table(table);
        for seg in rest {
            here = here.child(seg, &mut at, true)?;
        }
        let parent_path = at.clone();
        match (here, last) {
            (Slot::Table(t), Segment::Key(k)) => {
                t.insert(k.clone(), self.value.clone());
                Ok(())
            }
            (Slot::Array(a), Segment::Index(i)) => match a.get_mut(*i) {
                Some(v) => {
                    *v = self.value.clone();
                    Ok(())
                }
                None => Err(out_of_range(&parent_path, *i, a.len())),
            },
            (slot, seg) => {
                let target = slot.child(seg, &mut at, false)?;
                match target {
                    Slot::Table(t) => *t = as_table(&self.path, &self.value)?,
                    Slot::Array(a) => *a = as_array(&self.path, &self.value)?,
                    Slot::Value(v) => *v = self.value.clone(),
                }
                Ok(())
            }
        }
    }
}

/// Where a path walk stands.
enum Slot<'a> {
    Table(&'a mut toml::Table),
    Array(&'a mut Vec<toml::Value>),
    Value(&'a mut toml::Value),
}

impl<'a> Slot<'a> {
    /// The child `seg` of this slot; `at` is the path so far, extended by
    /// `seg`. With `create`, a missing table key becomes an empty table.
    fn child(self, seg: &Segment, at: &mut String, create: bool) -> Result<Slot<'a>, SceneError> {
        let parent = at.clone();
        match seg {
            Segment::Key(k) => {
                if !at.is_empty() {
                    at.push('.');
                }
                at.push_str(k);
            }
            Segment::Index(i) => at.push_str(&format!("[{i}]")),
        }
        match (self, seg) {
            (Slot::Table(t), Segment::Key(k)) => {
                if create && !t.contains_key(k) {
                    t.insert(k.clone(), toml::Value::Table(toml::Table::new()));
                }
                match t.get_mut(k) {
                    Some(v) => Ok(Slot::of(v)),
                    None => Err(SceneError::new(at.clone(), "no such key in the scene")),
                }
            }
            (Slot::Array(a), Segment::Index(i)) => {
                let n = a.len();
                a.get_mut(*i)
                    .map(Slot::of)
                    .ok_or_else(|| out_of_range(&parent, *i, n))
            }
            (Slot::Array(a), Segment::Key(name)) => {
                let names: Vec<String> = a
                    .iter()
                    .filter_map(|v| v.get("name").and_then(|n| n.as_str()).map(str::to_string))
                    .collect();
                let found = a
                    .iter_mut()
                    .find(|v| v.get("name").and_then(|n| n.as_str()) == Some(name.as_str()));
                match found {
                    Some(v) => Ok(Slot::of(v)),
                    None => Err(SceneError::new(
                        parent,
                        format!(
                            "no element named `{name}` (an index 0..{} or one of the names: {})",
                            names.len().max(1) - 1,
                            if names.is_empty() {
                                "none".to_string()
                            } else {
                                names.join(", ")
                            }
                        ),
                    )),
                }
            }
            (Slot::Table(_), Segment::Index(_)) => Err(SceneError::new(
                parent,
                "is a table, not an array: use a key, not an index",
            )),
            (Slot::Value(_), _) => Err(SceneError::new(
                parent,
                "is a value, not a table or an array: the key path goes too deep",
            )),
        }
    }

    fn of(v: &'a mut toml::Value) -> Slot<'a> {
        match v {
            toml::Value::Table(t) => Slot::Table(t),
            toml::Value::Array(a) => Slot::Array(a),
            other => Slot::Value(other),
        }
    }
}

fn out_of_range(path: &str, i: usize, n: usize) -> SceneError {
    SceneError::new(
        format!("{path}[{i}]"),
        format!(
            "index past the end: `{path}` has {n} elements (0..{})",
            n.max(1) - 1
        ),
    )
}

fn as_table(path: &str, v: &toml::Value) -> Result<toml::Table, SceneError> {
    v.as_table()
        .cloned()
        .ok_or_else(|| SceneError::new(path, "is a table: give an inline table { … }"))
}

fn as_array(path: &str, v: &toml::Value) -> Result<Vec<toml::Value>, SceneError> {
    v.as_array()
        .cloned()
        .ok_or_else(|| SceneError::new(path, "is an array: give [ … ]"))
}

/// The segments of a key path: `a.b[2].c`, `a.2.c`.
fn segments(path: &str) -> Result<Vec<Segment>, SceneError> {
    let bad = |why: &str| {
        SceneError::new(
            "--set",
            format!("key path `{path}` {why} (e.g. grid.cells, materials[0].density)"),
        )
    };
    if path.is_empty() {
        return Err(bad("is empty"));
    }
    let mut out = Vec::new();
    for part in path.split('.') {
        let (key, mut idx) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if key.is_empty() && idx.is_empty() {
            return Err(bad("has an empty key"));
        }
        if !key.is_empty() {
            if !key
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
            {
                return Err(bad("has a key with characters other than A-Z a-z 0-9 _ -"));
            }
            match key.parse::<usize>() {
                Ok(i) => out.push(Segment::Index(i)),
                Err(_) => out.push(Segment::Key(key.to_string())),
            }
        }
        while !idx.is_empty() {
            let close = idx.find(']').ok_or_else(|| bad("has an unclosed `[`"))?;
            let i = idx[1..close]
                .parse::<usize>()
                .map_err(|_| bad("has an index that is not a whole number"))?;
            out.push(Segment::Index(i));
            idx = &idx[close + 1..];
            if !idx.is_empty() && !idx.starts_with('[') {
                return Err(bad("has text after `]`"));
            }
        }
    }
    Ok(out)
}

/// A TOML value, or a bare word as a string.
fn parse_value(path: &str, text: &str) -> Result<toml::Value, SceneError> {
    if let Ok(mut t) = toml::from_str::<toml::Table>(&format!("v = {text}")) {
        if let Some(v) = t.remove("v") {
            return Ok(v);
        }
    }
    let bare = !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '/' | '+'));
    if bare {
        Ok(toml::Value::String(text.to_string()))
    } else {
        Err(SceneError::new(
            path,
            format!("`{text}` is not a TOML value (a number, [array], \"string\", true/false, {{ table }})"),
        ))
    }
}

/// Splits a `--sweep` value list `v1,v2,…` at the commas outside brackets,
/// braces and quotes: `[100],[200]` is two values.
pub fn split_values(list: &str) -> Vec<String> {
    let mut out = Vec::new();
    let (mut depth, mut quote, mut cur) = (0i32, None::<char>, String::new());
    for c in list.chars() {
        match (quote, c) {
            (Some(q), _) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '[' | '{') => depth += 1,
            (None, ']' | '}') => depth -= 1,
            (None, ',') if depth == 0 => {
                out.push(std::mem::take(&mut cur).trim().to_string());
                continue;
            }
            _ => {}
        }
        cur.push(c);
    }
    out.push(cur.trim().to_string());
    out
}

/// Parses the scene text, applies `overrides` in order and parses and
/// validates the result as [`super::parse`] does. Without overrides this is
/// [`super::parse`].
///
/// # Errors
/// As [`super::parse`] on the file's text (a syntax error is located in
/// the file), then the first override that cannot be applied, then the
/// overridden scene's errors, named by key path.
pub fn parse_with(text: &str, overrides: &[Override]) -> Result<super::Scene, SceneError> {
    if overrides.is_empty() {
        return super::parse(text);
    }
    // The file's own syntax errors first, located in the file.
    let mut table: toml::Table = toml::from_str(text).map_err(|e| super::syntax_error(text, &e))?;
    for o in overrides {
        o.apply(&mut table)?;
    }
    let text = toml::to_string(&table)
        .map_err(|e| SceneError::new("--set", format!("the overridden scene is not TOML: {e}")))?;
    super::parse(&text).map_err(|mut e| {
        let set: Vec<&str> = overrides.iter().map(|o| o.path.as_str()).collect();
        e.message = format!("{} (scene with --set {})", e.message, set.join(", "));
        e
    })
}

/// Reads the scene file and applies `overrides` ([`parse_with`]).
///
/// # Errors
/// An unreadable file, then as [`parse_with`].
pub fn load_with(
    path: &std::path::Path,
    overrides: &[Override],
) -> Result<super::Scene, SceneError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::new("<file>", format!("cannot read {}: {e}", path.display())))?;
    parse_with(&text, overrides)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = r#"
[grid]
dim = 1
lower = [0.0]
upper = [1.0]
cells = [100]
boundary = { x_lower = "free", x_upper = "free" }

[time]
end = 0.2

[[materials]]
name = "gas"
type = "fluid"
eos = "ideal_gas"
gamma = 1.4
cv = 2.5

[[regions]]
pressure = 0.1
states = [{ material = "gas", volume_fraction = 1.0, density = 0.125 }]
"#;

    fn set(args: &[&str]) -> Result<crate::scene::Scene, SceneError> {
        let o: Vec<Override> = args.iter().map(|a| Override::parse(a).unwrap()).collect();
        parse_with(SCENE, &o)
    }

    #[test]
    fn every_value_type_is_set() {
        let s = set(&[
            "grid.cells=[800]",
            "time.end=0.1",
            "time.cfl=0.25",
            "materials.gas.gamma=1.6667",
            "regions[0].states[0].density=0.5",
            "fluid.variant=literal",
            "output.formats=[\"csv\"]",
        ])
        .unwrap();
        assert_eq!(s.grid.cells, vec![800]);
        assert_eq!(s.time.end, 0.1);
        assert_eq!(s.time.cfl, 0.25);
        assert_eq!(s.regions[0].states[0].density, Some(0.5));
        let s = set(&["materials[0].gamma=1.3", "regions.0.pressure=0.2"]).unwrap();
        assert_eq!(s.regions[0].pressure, 0.2);
    }

    #[test]
    fn bad_paths_and_values_are_named() {
        let e = set(&["grid.cels=[800]"]).unwrap_err();
        assert!(
            e.path.contains("grid") && e.message.contains("cels"),
            "{e:?}"
        );
        let e = set(&["materials[3].gamma=1.3"]).unwrap_err();
        assert_eq!(e.path, "materials[3]", "{e:?}");
        assert!(e.message.contains("1 elements"), "{e:?}");
        let e = set(&["materials.steel.gamma=1.3"]).unwrap_err();
        assert!(e.message.contains("gas"), "{e:?}");
        let e = set(&["time.end=-1"]).unwrap_err();
        assert_eq!(e.path, "time.end", "{e:?}");
        let e = set(&["grid.cells=\"many\""]).unwrap_err();
        assert_eq!(e.path, "grid.cells", "{e:?}");
        let e = set(&["time.end.x=1"]).unwrap_err();
        assert_eq!(e.path, "time.end", "{e:?}");
        // The file's own syntax error is located in the file.
        let o = [Override::parse("time.end=1").unwrap()];
        let e = parse_with("[grid]\ndim = [1\n", &o).unwrap_err();
        assert!(e.path == "<toml>" && e.message.contains("line 2"), "{e:?}");
        assert!(Override::parse("grid.cells").is_err());
        assert!(Override::parse("grid..cells=1").is_err());
        assert!(Override::parse("grid.cells=[1").is_err());
    }

    #[test]
    fn sweep_lists_split_outside_brackets() {
        assert_eq!(split_values("[100],[200, 2]"), vec!["[100]", "[200, 2]"]);
        assert_eq!(split_values("0.1, 0.2"), vec!["0.1", "0.2"]);
        assert_eq!(split_values("\"a,b\",c"), vec!["\"a,b\"", "c"]);
    }
}
