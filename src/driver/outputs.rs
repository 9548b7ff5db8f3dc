//! The run loop's files: snapshots of a model's field sets (VTK + `.pvd`
//! series, CSV tables) and `history.csv`.
//!
//! Every file is written whole under a temporary name and renamed
//! ([`crate::output::atomic_write`]): the history is kept in memory and the
//! file rewritten at each snapshot, checkpoint and at the end, so a run
//! killed at any moment leaves only complete files.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::driver::model::{FieldSet, Geometry, Values};
use crate::error::{Error, Result};
use crate::output::csv::write_rows;
use crate::output::vtk::{
    write_vti, write_vtu_point_data, write_vtu_quads, Compression, Field, FieldData, PvdSeries,
};
use crate::scene::{Format, OutputSpec};

/// Unit of a quantity per unit of the dimensions a run does not resolve
/// (2D plane strain is per metre of depth, 1D per square metre of section).
pub fn per_depth(dim: usize) -> &'static str {
    match dim {
        1 => "/m^2",
        2 => "/m",
        _ => "",
    }
}

/// The snapshot series and the history of one run.
pub(crate) struct Outputs {
    dir: PathBuf,
    formats: Vec<Format>,
    compression: Compression,
    dim: usize,
    /// One `.pvd` series per field set, by set name.
    series: Vec<(&'static str, PvdSeries)>,
    /// Times of the snapshots written so far (snapshot `k` at `times[k]`).
    pub times: Vec<f64>,
    header: Vec<String>,
    /// History rows, flattened (`header.len()` values a row).
    pub history: Vec<f64>,
    row: Vec<f64>,
    /// Seconds spent writing.
    pub output_s: f64,
}

impl Outputs {
    /// Creates `dir` for the snapshots `spec` asks for; the history has a
    /// time column and one column per `(quantity, unit)`, units made per
    /// depth in 2D and per area in 1D.
    pub fn new(
        dir: &Path,
        spec: &OutputSpec,
        dim: usize,
        columns: &[(&str, &str)],
    ) -> Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let u = per_depth(dim);
        let mut header = vec!["time [s]".to_string()];
        header.extend(columns.iter().map(|(q, unit)| format!("{q} [{unit}{u}]")));
        Ok(Self {
            dir: dir.to_path_buf(),
            formats: spec.formats.clone(),
            compression: match spec.zlib_level() {
                Some(level) => Compression::Zlib { level },
                None => Compression::None,
            },
            dim,
            series: Vec::new(),
            times: Vec::new(),
            header,
            history: Vec::new(),
            row: Vec::new(),
            output_s: 0.0,
        })
    }

    /// Number of snapshots written.
    pub fn snapshots(&self) -> usize {
        self.times.len()
    }

    /// Columns of a history row, the time included.
    pub fn history_width(&self) -> usize {
        self.header.len()
    }

    /// Appends a history row: the time, then `fill`'s values.
    pub fn history_row(&mut self, t: f64, fill: impl FnOnce(&mut Vec<f64>)) {
        self.row.clear();
        self.row.push(t);
        fill(&mut self.row);
        debug_assert_eq!(self.row.len(), self.header.len());
        self.history.extend_from_slice(&self.row);
    }

    /// Time of the last history row.
    pub fn last_history_time(&self) -> Option<f64> {
        let w = self.header.len();
        (self.history.len() >= w).then(|| self.history[self.history.len() - w])
    }

    /// Rewrites `history.csv` atomically with every row so far.
    pub fn flush_history(&mut self) -> Result<()> {
        let start = Instant::now();
        let w = self.header.len();
        let rows = self.history.len() / w;
        let h: Vec<&str> = self.header.iter().map(String::as_str).collect();
        let path = self.dir.join("history.csv");
        let history = &self.history;
        write_rows(&path, &h, rows, |i, row| {
            row.extend_from_slice(&history[i * w..(i + 1) * w])
        })
        .map_err(|e| Error::io(&path, e))?;
        self.output_s += start.elapsed().as_secs_f64();
        Ok(())
    }

    /// Writes snapshot number [`Self::snapshots`] of `sets` at time `t`.
    pub fn snapshot(&mut self, t: f64, sets: &[FieldSet<'_>]) -> Result<()> {
        let start = Instant::now();
        let k = self.times.len();
        for set in sets {
            if self.formats.contains(&Format::Vtk) {
                let ext = match set.geometry {
                    Geometry::Points(_) | Geometry::Quads { .. } => "vtu",
                    Geometry::Image { .. } => "vti",
                };
                let name = format!("{}_{k:04}.{ext}", set.name);
                let path = self.dir.join(&name);
                write_vtk(&path, set, self.compression).map_err(|e| Error::io(&path, e))?;
                let series = self.series_of(set.name);
                series
                    .push(t, &name)
                    .map_err(|e| Error::io(series.path().to_path_buf(), e))?;
            }
            if self.formats.contains(&Format::Csv) && set.csv {
                let path = self.dir.join(format!("{}_{k:04}.csv", set.name));
                write_csv(&path, set, self.dim).map_err(|e| Error::io(&path, e))?;
            }
            if self.formats.contains(&Format::Npy) {
                let path = self.dir.join(format!("{}_{k:04}_npy", set.name));
                write_npy(&path, set, t, self.dim).map_err(|e| Error::io(&path, e))?;
            }
        }
        self.times.push(t);
        self.output_s += start.elapsed().as_secs_f64();
        Ok(())
    }

    fn series_of(&mut self, name: &'static str) -> &mut PvdSeries {
        let i = match self.series.iter().position(|(n, _)| *n == name) {
            Some(i) => i,
            None => {
                let pvd = PvdSeries::new(self.dir.join(format!("{name}.pvd")));
                self.series.push((name, pvd));
                self.series.len() - 1
            }
        };
        &mut self.series[i].1
    }

    /// Restores the state of a restarted run: the snapshot times (the
    /// `.pvd` series of `sets` are rewritten to list them) and the history
    /// rows.
    pub fn restore(
        &mut self,
        times: Vec<f64>,
        history: Vec<f64>,
        sets: &[FieldSet<'_>],
    ) -> Result<()> {
        if self.formats.contains(&Format::Vtk) {
            for set in sets {
                let ext = match set.geometry {
                    Geometry::Points(_) | Geometry::Quads { .. } => "vtu",
                    Geometry::Image { .. } => "vti",
                };
                let mut pvd = PvdSeries::new(self.dir.join(format!("{}.pvd", set.name)));
                for (k, &t) in times.iter().enumerate() {
                    pvd.push(t, &format!("{}_{k:04}.{ext}", set.name))
                        .map_err(|e| Error::io(pvd.path().to_path_buf(), e))?;
                }
                self.series.push((set.name, pvd));
            }
        }
        self.times = times;
        self.history = history;
        self.flush_history()
    }
}

/// The VTK writer's view of `v`.
fn field_data<'s>(v: &'s Values<'_>) -> FieldData<'s> {
    match v {
        Values::Scalar(v) => FieldData::Scalar(v),
        Values::Vector(v) => FieldData::Vector(v),
        Values::Tensor(v) => FieldData::Tensor(v),
        Values::Computed(c) => FieldData::Computed {
            n: c.n,
            components: c.components,
            f: &*c.f,
        },
    }
}

fn vtk_fields<'s>(set: &'s FieldSet<'_>) -> Vec<Field<'s>> {
    set.fields
        .iter()
        .map(|f| Field {
            name: &f.name,
            data: field_data(&f.values),
        })
        .collect()
}

fn write_vtk(path: &Path, set: &FieldSet<'_>, z: Compression) -> std::io::Result<()> {
    let fields = vtk_fields(set);
    match &set.geometry {
        Geometry::Points(x) => write_vtu_point_data(path, field_data(x), &fields, z),
        Geometry::Quads {
            points,
            quads,
            on_cells,
            ..
        } => {
            if *on_cells {
                write_vtu_quads(path, points, quads, &[], &fields, z)
            } else {
                write_vtu_quads(path, points, quads, &fields, &[], z)
            }
        }
        Geometry::Image {
            origin,
            spacing,
            cells,
            on_cells,
            ..
        } => {
            if *on_cells {
                write_vti(path, *origin, *spacing, *cells, &[], &fields, z)
            } else {
                write_vti(path, *origin, *spacing, *cells, &fields, &[], z)
            }
        }
    }
}

/// Values per tuple of `v` (1, 3 or 9) and their number.
fn tuples(v: &Values<'_>) -> (usize, usize) {
    match v {
        Values::Scalar(x) => (1, x.len()),
        Values::Vector(x) => (3, x.len()),
        Values::Tensor(x) => (9, x.len()),
        Values::Computed(c) => (c.components, c.n),
    }
}

/// Writes `v` as `folder/file` (`.npy`, `<f8`) of shape `lead` followed by
/// `()`, `(3,)` or `(3, 3)` for scalars, vectors and tensors; returns the
/// shape.
fn write_npy_values(
    folder: &Path,
    file: &str,
    lead: &[usize],
    v: &Values<'_>,
) -> std::io::Result<Vec<usize>> {
    let (c, _) = tuples(v);
    let mut shape = lead.to_vec();
    match c {
        3 => shape.push(3),
        9 => shape.extend([3, 3]),
        _ => {}
    }
    crate::output::atomic_write(&folder.join(file), |w| {
        let mut a = crate::output::npy::begin::<f64, _>(w, "<f8", &shape)?;
        match v {
            Values::Scalar(x) => a.extend(x.iter().copied())?,
            Values::Vector(x) => a.extend(x.iter().flatten().copied())?,
            Values::Tensor(x) => a.extend(x.iter().flatten().copied())?,
            Values::Computed(f) => {
                let mut buf = [0.0; 9];
                for i in 0..f.n {
                    (f.f)(i, &mut buf[..f.components]);
                    a.extend(buf[..f.components].iter().copied())?;
                }
            }
        }
        a.finish()
    })?;
    Ok(shape)
}

/// A field's file name: its name with anything but letters, digits, `-`
/// and `_` replaced by `_`, and `.npy`.
fn npy_file(name: &str) -> String {
    let stem: String = name
        .chars()
        .map(|ch| {
            if ch.is_ascii_alphanumeric() || ch == '-' || ch == '_' {
                ch
            } else {
                '_'
            }
        })
        .collect();
    format!("{stem}.npy")
}

/// Writes `set` at time `t` as the folder `folder`: one `.npy` per field,
/// the geometry (`points.npy` of particles, `points.npy` and `quads.npy`
/// of a mesh; a grid's origin, spacing and cells in the metadata, its
/// fields shaped `(n_z, n_y, n_x, …)` over the run's `dim` axes) and
/// `meta.json`.
fn write_npy(folder: &Path, set: &FieldSet<'_>, t: f64, dim: usize) -> std::io::Result<()> {
    std::fs::create_dir_all(folder)?;
    let mut meta = serde_json::Map::new();
    meta.insert("set".into(), set.name.into());
    meta.insert("time".into(), t.into());
    let lead: Vec<usize> = match &set.geometry {
        Geometry::Points(x) => {
            let (_, n) = tuples(x);
            write_npy_values(folder, "points.npy", &[n], x)?;
            meta.insert("geometry".into(), "points".into());
            vec![n]
        }
        Geometry::Quads {
            points,
            quads,
            on_cells,
            ..
        } => {
            let xyz = Values::computed(points.len(), 3, |i, o| o.copy_from_slice(&points[i]));
            write_npy_values(folder, "points.npy", &[points.len()], &xyz)?;
            crate::output::atomic_write(&folder.join("quads.npy"), |w| {
                let mut a = crate::output::npy::begin::<u64, _>(w, "<u8", &[quads.len(), 4])?;
                a.extend(quads.iter().flatten().map(|&q| u64::from(q)))?;
                a.finish()
            })?;
            meta.insert("geometry".into(), "quads".into());
            meta.insert("on_cells".into(), (*on_cells).into());
            vec![if *on_cells { quads.len() } else { points.len() }]
        }
        Geometry::Image {
            origin,
            spacing,
            cells,
            on_cells,
            ..
        } => {
            meta.insert("geometry".into(), "image".into());
            meta.insert("origin".into(), serde_json::json!(&origin[..dim]));
            meta.insert("spacing".into(), serde_json::json!(&spacing[..dim]));
            meta.insert("cells".into(), serde_json::json!(&cells[..dim]));
            meta.insert("on_cells".into(), (*on_cells).into());
            let n = |d: usize| cells[d] + usize::from(!*on_cells);
            (0..dim).rev().map(n).collect()
        }
    };
    let mut fields = Vec::new();
    for f in &set.fields {
        let file = npy_file(&f.name);
        let shape = write_npy_values(folder, &file, &lead, &f.values)?;
        fields.push(serde_json::json!({
            "name": f.name,
            "unit": f.unit,
            "file": file,
            "shape": shape,
        }));
    }
    meta.insert("fields".into(), fields.into());
    crate::output::atomic_write(&folder.join("meta.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &meta).map_err(std::io::Error::other)?;
        writeln!(w)
    })
}

/// Components of a symmetric tensor written to CSV in `dim` dimensions.
fn tensor_components(dim: usize) -> &'static [(usize, usize)] {
    match dim {
        1 => &[(0, 0), (1, 1), (2, 2)],
        2 => &[(0, 0), (1, 1), (2, 2), (0, 1)],
        _ => &[(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)],
    }
}

/// Writes `set` as a CSV table row by row (coordinates, then each CSV
/// field's components), computing no column ahead.
fn write_csv(path: &Path, set: &FieldSet<'_>, dim: usize) -> std::io::Result<()> {
    const AXES: [&str; 3] = ["x", "y", "z"];
    // The row coordinates: stored, or the points' values.
    let (stored, points): (&[[f64; 3]], Option<&Values<'_>>) = match &set.geometry {
        Geometry::Points(x) => (&[], Some(x)),
        Geometry::Quads {
            points,
            on_cells,
            centres,
            ..
        } => {
            if *on_cells {
                (centres, None)
            } else {
                (points, None)
            }
        }
        Geometry::Image { centres, .. } => (centres, None),
    };
    let rows = points.map_or(stored.len(), Values::len);
    let mut header: Vec<String> = (0..dim).map(|d| format!("{} [m]", AXES[d])).collect();
    // Per CSV field: its values and the tuple entries that are columns.
    let mut columns: Vec<(&Values<'_>, Vec<usize>)> = Vec::new();
    for f in &set.fields {
        let Some(base) = &f.csv else { continue };
        let unit = &f.unit;
        let picks: Vec<usize> = match f.values.components() {
            1 => {
                header.push(format!("{base} [{unit}]"));
                vec![0]
            }
            3 => {
                for axis in &AXES[..dim] {
                    header.push(format!("{base}{axis} [{unit}]"));
                }
                (0..dim).collect()
            }
            _ => tensor_components(dim)
                .iter()
                .map(|&(a, b)| {
                    header.push(format!("{base}{}{} [{unit}]", AXES[a], AXES[b]));
                    3 * a + b
                })
                .collect(),
        };
        if f.values.len() != rows {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!(
                    "field \"{}\" has {} values for {} rows",
                    f.name,
                    f.values.len(),
                    rows
                ),
            ));
        }
        columns.push((&f.values, picks));
    }
    let h: Vec<&str> = header.iter().map(String::as_str).collect();
    write_rows(path, &h, rows, |i, row| {
        let mut t = [0.0; 9];
        match points {
            Some(x) => {
                x.tuple(i, &mut t);
                row.extend_from_slice(&t[..dim]);
            }
            None => row.extend_from_slice(&stored[i][..dim]),
        }
        for (v, picks) in &columns {
            v.tuple(i, &mut t);
            row.extend(picks.iter().map(|&k| t[k]));
        }
    })
}
