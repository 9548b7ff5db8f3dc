//! Convergence studies of a user's own scene (`mpmice study`): refine the
//! grid, sweep a key, measure a field's error against a reference and the
//! observed order, and write the same JSON, CSV and log-log PNG as the
//! built-in studies ([`harness`]).
//!
//! A study runs the scene (with its `--set` overrides) at `grid.cells`
//! times 1, 2, …, 2^N — particles per cell fixed, Δt by the scene's CFL (a
//! fixed `time.dt` is halved with the cells, `time.max_steps` doubled) —
//! once per value of a swept key. The error of one field of the final
//! state (a cell field, or a particle field) is measured against
//!
//! - [`Reference::Finest`]: the finest run. Every field is compared as
//!   averages over the cells of the coarser grid (cell centres or particle
//!   positions binned into its cells; for nested grids this is the
//!   restriction of the finer cells): `e_k = Σ_c |f̄_k − f̄_N| / n` over the
//!   cells both runs reach (vector fields by the Euclidean norm of the
//!   difference).
//! - [`Reference::Riemann`]: the exact Riemann solution of a 1D fluid scene
//!   whose initial state is two constant states (ideal or stiffened gases,
//!   [`crate::diagnostics::riemann`]): `Σ_c |f_c − f̄_c| / n` with exact
//!   cell averages, the norm of the built-in Sod studies.
//!
//! With `quantity` (a history column, e.g. `kinetic_energy`) the final
//! values `Q_k` of the three finest runs give Richardson's estimate of the
//! order `p = log2((Q_{N−2} − Q_{N−1}) / (Q_{N−1} − Q_N))`, the converged
//! value `Q_∞ = Q_N + (Q_N − Q_{N−1}) / (2^p − 1)` and its uncertainty, the
//! grid-convergence index `GCI = 1.25 |Q_N − Q_{N−1}| / (2^p − 1)`
//! (Roache's safety factor for three grids).
//!
//! The result's axes ([`StudyResult::h_axis`], [`StudyResult::error_axis`])
//! name `h`, the cell size along x in metres, and the error: its norm, its
//! reference and the field's unit as the runs' output names it.

pub mod harness;

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::diagnostics::riemann::{ExactRiemann, GasLaw, PrimitiveState};
use crate::driver::model::{FieldSet, Geometry};
use crate::driver::{run_scene_keep, KeptRun, RunOptions};
use crate::scene::{parse_with, EosKind, Override, Scene};
use harness::{Point, Series, StudyResult};

/// What a study's errors are measured against.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reference {
    /// The finest run of the series.
    Finest,
    /// The exact Riemann solution of a 1D two-state fluid scene.
    Riemann,
}

impl Reference {
    /// The allowed names.
    pub const NAMES: &'static str = "finest, riemann";

    /// By name (`finest`, `riemann`).
    ///
    /// # Errors
    /// Another name; the message lists the allowed ones.
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "finest" => Ok(Self::Finest),
            "riemann" => Ok(Self::Riemann),
            _ => bail!("--reference: `{name}` is not one of {}", Self::NAMES),
        }
    }
}

/// What to study.
#[derive(Debug, Clone)]
pub struct StudySpec {
    /// Study name (file stem of the results).
    pub name: String,
    /// Halvings of the cell size: `refine + 1` runs per series.
    pub refine: usize,
    /// `SET.FIELD` (e.g. `cells.mixture_density`, `particles.velocity`);
    /// `None`: `cells.mixture_density` where there are cells, else
    /// `particles.velocity`.
    pub field: Option<String>,
    /// The reference of the errors.
    pub reference: Reference,
    /// A history column whose final value gets a Richardson estimate.
    pub quantity: Option<String>,
    /// A swept key and its values (one series each).
    pub sweep: Option<(String, Vec<String>)>,
}

/// One series' runs as measured.
struct Level {
    h: f64,
    cells: Vec<usize>,
    kept: KeptRun,
}

/// Runs the study on the scene `text` with the overrides `set`, each run's
/// outputs under `out_dir/SERIES/level_K`; `log` gets a line per run.
///
/// # Errors
/// A scene or override error (named by key path), a run's failure, a field
/// or quantity the runs do not have (the message lists those they have),
/// or a reference the scene does not admit.
pub fn run_study(
    text: &str,
    set: &[Override],
    spec: &StudySpec,
    out_dir: &Path,
    threads: usize,
    log: &mut dyn FnMut(&str),
) -> Result<StudyResult> {
    if spec.refine == 0 {
        bail!("--refine: at least 1 (two resolutions)");
    }
    let variants: Vec<(String, Vec<Override>)> = match &spec.sweep {
        None => vec![("scene".to_string(), set.to_vec())],
        Some((key, values)) => values
            .iter()
            .map(|v| {
                let mut o = set.to_vec();
                o.push(Override::new(key, v)?);
                Ok((format!("{key}={v}"), o))
            })
            .collect::<std::result::Result<_, crate::error::SceneError>>()
            .map_err(|e| anyhow::anyhow!("--sweep {}: {}", e.path, e.message))?,
    };
    let mut result = StudyResult {
        study: spec.name.clone(),
        series: Vec::new(),
        notes: Vec::new(),
        // h is the x extent of the grid over its cells (`Level::h`), in the
        // scene's length unit.
        h_axis: "cell size Δx [m]".to_string(),
        error_axis: String::new(),
    };
    // The error axis of each series' field (one per variant).
    let mut error_axes: Vec<String> = Vec::new();
    for (vi, (label, ovs)) in variants.iter().enumerate() {
        let base = parse_with(text, ovs).map_err(scene_err)?;
        refinable(&base)?;
        let mut levels = Vec::new();
        for k in 0..=spec.refine {
            let scene = refined(text, ovs, &base, k)?;
            let dir = out_dir
                .join(format!("series_{vi}"))
                .join(format!("level_{k}"));
            let opts = RunOptions::quiet(dir.clone(), threads);
            let kept = run_scene_keep(&scene, &opts)
                .with_context(|| format!("{label}, cells {:?}", scene.grid.cells))?;
            let h = (scene.grid.upper[0] - scene.grid.lower[0]) / scene.grid.cells[0] as f64;
            log(&format!(
                "{label}: cells {:?}, {} steps in {:.2} s ({})",
                scene.grid.cells,
                kept.summary.steps,
                kept.summary.wall_s,
                dir.display()
            ));
            levels.push(Level {
                h,
                cells: scene.grid.cells.clone(),
                kept,
            });
        }
        let field = match &spec.field {
            Some(f) => f.clone(),
            None => default_field(&levels[0].kept.last)?,
        };
        let mut series = measure(&base, &levels, &field, spec.reference)?;
        let axis = field_error_axis(&levels[0].kept.last, &field, spec.reference);
        if !error_axes.contains(&axis) {
            error_axes.push(axis);
        }
        series.label = if variants.len() > 1 {
            format!("{field}, {label}")
        } else {
            field.clone()
        };
        result.series.push(series);
        if let Some(q) = &spec.quantity {
            let (series, note) = richardson(&levels, q, label)?;
            result.series.push(series);
            result.notes.push(note);
        }
    }
    let mut error_axis = match error_axes.as_slice() {
        [one] => one.clone(),
        _ => format!(
            "L1 cell-mean error vs {} (field in the legend, in its unit)",
            reference_name(spec.reference)
        ),
    };
    if let Some(q) = &spec.quantity {
        error_axis.push_str(&format!("; |Q − Q∞| of {q} (history column's unit)"));
    }
    result.error_axis = error_axis;
    result.notes.push(format!(
        "{} refinements of grid.cells by 2, particles per cell fixed; reference: {}",
        spec.refine,
        match spec.reference {
            Reference::Finest => "the finest run (fields averaged over the coarser cells)",
            Reference::Riemann => "the exact Riemann solution (exact cell averages)",
        }
    ));
    Ok(result)
}

fn scene_err(e: crate::error::SceneError) -> anyhow::Error {
    anyhow::anyhow!("scene: {}: {}", e.path, e.message)
}

/// Whether refining `grid.cells` refines the scene.
fn refinable(s: &Scene) -> Result<()> {
    if !s.membrane_elements.is_empty() {
        bail!(
            "study refines grid.cells; a scene with membrane element meshes \
             (membrane_elements) is not refined by it"
        );
    }
    Ok(())
}

/// The scene at refinement `k`: cells × 2^k, a fixed Δt / 2^k, max steps
/// × 2^k.
fn refined(text: &str, ovs: &[Override], base: &Scene, k: usize) -> Result<Scene> {
    let f = 1usize << k;
    let mut o = ovs.to_vec();
    let cells: Vec<String> = base
        .grid
        .cells
        .iter()
        .map(|c| (c * f).to_string())
        .collect();
    let mut add = |path: &str, v: String| -> Result<()> {
        o.push(Override::new(path, &v).map_err(scene_err)?);
        Ok(())
    };
    add("grid.cells", format!("[{}]", cells.join(", ")))?;
    if let Some(dt) = base.time.dt {
        add("time.dt", format!("{:e}", dt / f as f64))?;
    }
    if let Some(m) = base.time.max_steps {
        add("time.max_steps", (m * f as u64).to_string())?;
    }
    parse_with(text, &o).map_err(scene_err)
}

/// The reference as the error axis names it.
fn reference_name(reference: Reference) -> &'static str {
    match reference {
        Reference::Finest => "finest run",
        Reference::Riemann => "exact Riemann",
    }
}

/// The error axis of `field`'s series ([`measure`]): its norm, reference and
/// the field's unit as the runs' output names it.
fn field_error_axis(sets: &[FieldSet<'_>], field: &str, reference: Reference) -> String {
    let unit = field
        .split_once('.')
        .and_then(|(set, name)| find(sets, set, name))
        .map(|(s, i)| s.fields[i].unit.as_str());
    let reference = reference_name(reference);
    match unit {
        Some("1") => format!("L1 cell-mean error of {field} vs {reference} [-]"),
        Some(u) if !u.is_empty() => format!("L1 cell-mean error of {field} vs {reference} [{u}]"),
        _ => format!("L1 cell-mean error of {field} vs {reference} (in the field's unit)"),
    }
}

/// `cells.mixture_density` where the runs have cells, else
/// `particles.velocity`.
fn default_field(sets: &[FieldSet<'_>]) -> Result<String> {
    for (set, field) in [("cells", "mixture_density"), ("particles", "velocity")] {
        if find(sets, set, field).is_some() {
            return Ok(format!("{set}.{field}"));
        }
    }
    bail!(
        "--field: no default field in this scene; one of {}",
        available(sets)
    )
}

fn find<'a, 'm>(
    sets: &'a [FieldSet<'m>],
    set: &str,
    field: &str,
) -> Option<(&'a FieldSet<'m>, usize)> {
    let s = sets.iter().find(|s| s.name == set)?;
    let i = s.fields.iter().position(|f| f.name == field)?;
    Some((s, i))
}

fn available(sets: &[FieldSet<'_>]) -> String {
    sets.iter()
        .filter(|s| {
            matches!(s.geometry, Geometry::Points(_))
                || matches!(s.geometry, Geometry::Image { on_cells: true, .. })
        })
        .flat_map(|s| {
            s.fields
                .iter()
                .map(move |f| format!("{}.{}", s.name, f.name))
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// A field as positions and values (`ncomp` numbers per entry).
struct Sampled {
    pos: Vec<[f64; 3]>,
    vals: Vec<f64>,
    ncomp: usize,
}

fn sample(sets: &[FieldSet<'_>], field: &str) -> Result<Sampled> {
    let (set, name) = field.split_once('.').with_context(|| {
        format!(
            "--field `{field}` is not SET.FIELD; one of {}",
            available(sets)
        )
    })?;
    let Some((s, i)) = find(sets, set, name) else {
        bail!(
            "--field `{field}`: no such field; one of {}",
            available(sets)
        );
    };
    let pos = match &s.geometry {
        Geometry::Points(p) => {
            let mut t = [0.0; 9];
            (0..p.len())
                .map(|i| {
                    p.tuple(i, &mut t);
                    [t[0], t[1], t[2]]
                })
                .collect()
        }
        Geometry::Image {
            on_cells: true,
            centres,
            ..
        } => centres.clone(),
        _ => bail!(
            "--field `{field}`: node and mesh fields are not compared; one of {}",
            available(sets)
        ),
    };
    let v = &s.fields[i].values;
    let ncomp = v.components();
    let mut vals = Vec::with_capacity(v.len() * ncomp);
    let mut t = [0.0; 9];
    for k in 0..v.len() {
        v.tuple(k, &mut t);
        vals.extend_from_slice(&t[..ncomp]);
    }
    Ok(Sampled { pos, vals, ncomp })
}

/// Averages of a sampled field over the cells of the grid `lower`, `cells`,
/// `h`: per cell the component sums over the entries inside and their
/// count.
fn bin(s: &Sampled, lower: &[f64], cells: &[usize], h: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let n: usize = cells.iter().product();
    let mut sum = vec![0.0; n * s.ncomp];
    let mut count = vec![0usize; n];
    for (e, p) in s.pos.iter().enumerate() {
        let mut idx = 0;
        let mut stride = 1;
        let mut inside = true;
        for d in 0..cells.len() {
            let x = ((p[d] - lower[d]) / h[d]).floor();
            if !(x >= 0.0 && (x as usize) < cells[d]) {
                inside = false;
                break;
            }
            idx += x as usize * stride;
            stride *= cells[d];
        }
        if inside {
            count[idx] += 1;
            for c in 0..s.ncomp {
                sum[idx * s.ncomp + c] += s.vals[e * s.ncomp + c];
            }
        }
    }
    (sum, count)
}

/// `Σ |ā − b̄| / n` over the cells of level `coarse` that both reach.
fn binned_difference(scene: &Scene, coarse: &Level, a: &Sampled, b: &Sampled) -> f64 {
    let lower = &scene.grid.lower;
    let h: Vec<f64> = (0..coarse.cells.len())
        .map(|d| (scene.grid.upper[d] - lower[d]) / coarse.cells[d] as f64)
        .collect();
    let (sa, ca) = bin(a, lower, &coarse.cells, &h);
    let (sb, cb) = bin(b, lower, &coarse.cells, &h);
    let nc = a.ncomp;
    let (mut err, mut n) = (0.0, 0usize);
    for c in 0..ca.len() {
        if ca[c] == 0 || cb[c] == 0 {
            continue;
        }
        let d2: f64 = (0..nc)
            .map(|k| {
                let d = sa[c * nc + k] / ca[c] as f64 - sb[c * nc + k] / cb[c] as f64;
                d * d
            })
            .sum();
        err += d2.sqrt();
        n += 1;
    }
    if n == 0 {
        f64::NAN
    } else {
        err / n as f64
    }
}

/// The error series of `field` over the levels.
fn measure(scene: &Scene, levels: &[Level], field: &str, reference: Reference) -> Result<Series> {
    let sampled: Vec<Sampled> = levels
        .iter()
        .map(|l| sample(&l.kept.last, field))
        .collect::<Result<_>>()?;
    let exact = match reference {
        Reference::Riemann => Some(riemann_reference(scene, &levels[0].kept, field)?),
        Reference::Finest => None,
    };
    let n = levels.len();
    let mut points = Vec::new();
    for (k, l) in levels.iter().enumerate() {
        let error = match &exact {
            Some(ex) => ex.error(&sampled[k], l.kept.summary.final_time)?,
            None if k + 1 == n => continue,
            None => binned_difference(scene, l, &sampled[k], &sampled[n - 1]),
        };
        let sum = &l.kept.summary;
        let rate = if sum.n_particles > 0 {
            sum.particle_steps_per_s
        } else {
            sum.cell_steps_per_s
        };
        let mut p = Point::new(l.h, error, sum.wall_s, rate)
            .with_extra("steps", sum.steps as f64)
            .with_extra("cells", l.cells.iter().product::<usize>() as f64);
        if k + 1 < n {
            p = p.with_extra(
                "difference_to_next",
                binned_difference(scene, l, &sampled[k], &sampled[k + 1]),
            );
        }
        points.push(p);
    }
    let norm = match reference {
        Reference::Finest => "L1 cell mean vs finest",
        Reference::Riemann => "L1 cell mean vs exact Riemann",
    };
    Ok(Series::new(field, norm, points))
}

/// The exact Riemann solution of a 1D two-state fluid scene, and which
/// primitive a field is.
struct RiemannRef {
    exact: ExactRiemann,
    x0: f64,
    /// Length of the domain.
    len: f64,
    /// The field's primitive.
    q: fn(&PrimitiveState) -> f64,
    /// Components per cell of the field (3 for a velocity, else 1).
    ncomp: usize,
}

impl RiemannRef {
    fn error(&self, s: &Sampled, t: f64) -> Result<f64> {
        if s.ncomp != self.ncomp {
            bail!(
                "--reference riemann: the field has {} components per cell, not {}",
                s.ncomp,
                self.ncomp
            );
        }
        // Each level's own cell size; the x component of a velocity.
        let h = self.len / s.pos.len() as f64;
        let cells = s
            .pos
            .iter()
            .zip(s.vals.iter().step_by(s.ncomp))
            .map(|(p, &v)| (p[0], v));
        self.exact
            .l1_cell_error(cells, h, self.x0, t, self.q)
            .map_err(|e| anyhow::anyhow!("exact Riemann solution: {e}"))
    }
}

/// Reads the two initial states of a 1D fluid scene from its first run.
fn riemann_reference(scene: &Scene, first: &KeptRun, field: &str) -> Result<RiemannRef> {
    let need =
        "--reference riemann needs a 1D fluid scene whose initial state is two constant states";
    if scene.grid.dim != 1 {
        bail!("{need} (grid.dim is {})", scene.grid.dim);
    }
    let (q, ncomp): (fn(&PrimitiveState) -> f64, usize) = match field.strip_prefix("cells.") {
        Some("mixture_density") => (|w| w.rho, 1),
        Some("pressure") => (|w| w.p, 1),
        Some(f) if f.ends_with("_velocity") => (|w| w.u, 3),
        _ => bail!(
            "--reference riemann compares cells.mixture_density, cells.pressure or \
             cells.MATERIAL_velocity, not `{field}`"
        ),
    };
    let sets = &first.initial;
    let get = |name: &str| -> Result<Vec<f64>> {
        match find(sets, "cells", name) {
            Some((s, i)) => {
                let v = &s.fields[i].values;
                if v.components() == 9 {
                    bail!("cells.{name} is a tensor");
                }
                let mut t = [0.0; 9];
                Ok((0..v.len())
                    .map(|k| {
                        v.tuple(k, &mut t);
                        t[0]
                    })
                    .collect())
            }
            None => bail!("{need} (no cells.{name})"),
        }
    };
    let rho = get("mixture_density")?;
    let p = get("pressure")?;
    let n = rho.len();
    if n < 2 {
        bail!("{need} (fewer than 2 cells)");
    }
    // The fluid present on each side and its velocity.
    let fluids: Vec<_> = scene.materials.iter().filter(|m| m.in_cells()).collect();
    let side = |c: usize| -> Result<(GasLaw, f64)> {
        for m in &fluids {
            let theta = get(&format!("{}_volume_fraction", m.name))?;
            if theta[c] > 0.5 {
                let law = match m.eos {
                    Some(EosKind::IdealGas) => GasLaw::ideal(m.gamma.unwrap_or(1.4)),
                    Some(EosKind::StiffenedGas) => {
                        GasLaw::stiffened(m.gamma.unwrap_or(1.4), m.p_inf.unwrap_or(0.0))
                    }
                    _ => bail!(
                        "{need} of ideal or stiffened gases (materials `{}`: eos {:?})",
                        m.name,
                        m.eos
                    ),
                };
                let u = get(&format!("{}_velocity", m.name))?;
                return Ok((law, u[c]));
            }
        }
        bail!("{need} (no fluid fills cell {c})")
    };
    let (law_l, u_l) = side(0)?;
    let (law_r, u_r) = side(n - 1)?;
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
    let jump = (1..n)
        .find(|&c| !(same(rho[c], rho[c - 1]) && same(p[c], p[c - 1])))
        .with_context(|| format!("{need} (the initial state is uniform)"))?;
    if (jump..n).any(|c| !(same(rho[c], rho[n - 1]) && same(p[c], p[n - 1]))) {
        bail!("{need} (the initial state has more than one jump)");
    }
    let len = scene.grid.upper[0] - scene.grid.lower[0];
    let x0 = scene.grid.lower[0] + jump as f64 * len / n as f64;
    let exact = ExactRiemann::solve_stiffened(
        PrimitiveState::new(rho[0], u_l, p[0]),
        PrimitiveState::new(rho[n - 1], u_r, p[n - 1]),
        law_l,
        law_r,
    )
    .map_err(|e| anyhow::anyhow!("exact Riemann solution: {e}"))?;
    Ok(RiemannRef {
        exact,
        x0,
        len,
        q,
        ncomp,
    })
}

/// Richardson's estimate on the final value of the history column `q`
/// over the three finest levels; a series of `|Q_k − Q_∞|`.
fn richardson(levels: &[Level], q: &str, label: &str) -> Result<(Series, String)> {
    let values: Vec<f64> = levels
        .iter()
        .map(|l| {
            l.kept
                .history
                .iter()
                .find(|(name, _)| name == q)
                .map(|(_, v)| *v)
                .with_context(|| {
                    let names: Vec<&str> = l.kept.history.iter().map(|(n, _)| n.as_str()).collect();
                    format!(
                        "--quantity `{q}`: no such history column; one of {}",
                        names.join(", ")
                    )
                })
        })
        .collect::<Result<_>>()?;
    let n = values.len();
    let est = (n >= 3).then(|| richardson_estimate([values[n - 3], values[n - 2], values[n - 1]]));
    let (order, limit, gci) = est.unwrap_or((f64::NAN, f64::NAN, f64::NAN));
    let points = levels
        .iter()
        .zip(&values)
        .map(|(l, &v)| {
            Point::new(l.h, (v - limit).abs(), l.kept.summary.wall_s, f64::NAN)
                .with_extra("value", v)
        })
        .collect();
    let series = Series::new(
        format!("{q} (history), {label}"),
        "|Q - Q_inf| (Richardson)",
        points,
    );
    let note = format!(
        "{label}: {q} at the end = {}; Richardson over the three finest: order {order:.3}, \
         converged value {limit:.6e} ± {gci:.2e} (GCI, safety factor 1.25)",
        values
            .iter()
            .map(|v| format!("{v:.6e}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok((series, note))
}

/// Richardson's order, converged value and grid-convergence index from the
/// values on grids `h`, `h/2`, `h/4` (NaN where the differences do not
/// shrink monotonically).
pub fn richardson_estimate(q: [f64; 3]) -> (f64, f64, f64) {
    let (d1, d2) = (q[0] - q[1], q[1] - q[2]);
    let ratio = d1 / d2;
    if !(ratio.is_finite() && ratio > 1.0) {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let p = ratio.log2();
    let denom = 2f64.powf(p) - 1.0;
    (p, q[2] - d2 / denom, 1.25 * d2.abs() / denom)
}

/// The default output folder of a study of `scene`: `out/study_<stem>`.
pub fn default_out(scene: &Path) -> PathBuf {
    PathBuf::from("out").join(format!(
        "study_{}",
        scene.file_stem().unwrap_or_default().to_string_lossy()
    ))
}

#[cfg(test)]
mod tests {
    use super::richardson_estimate;

    #[test]
    fn richardson_recovers_a_known_expansion() {
        // Q(h) = 2 + 3 h^1.5 at h = 1, 1/2, 1/4.
        let q = |h: f64| 2.0 + 3.0 * h.powf(1.5);
        let (p, limit, gci) = richardson_estimate([q(1.0), q(0.5), q(0.25)]);
        assert!((p - 1.5).abs() < 1e-12, "{p}");
        assert!((limit - 2.0).abs() < 1e-12, "{limit}");
        // The GCI bounds the fine grid's true error with its safety factor.
        assert!(gci >= (q(0.25) - 2.0).abs() && gci <= 1.3 * (q(0.25) - 2.0).abs());
        // Not converging monotonically: no estimate.
        assert!(richardson_estimate([1.0, 2.0, 1.5]).0.is_nan());
    }
}
