//! Conversions between the solver's arrays (vectors of `SVector`, 3×3
//! matrices, material indices) and checkpoint arrays (`[n, D]`, `[n, 3, 3]`,
//! u64), and the shared particle and ICE-cell parts of the models: their
//! snapshot fields, their save/load and their watchdog scans.

use nalgebra::{Matrix3, SVector};
use rayon::prelude::*;

use crate::driver::model::pad3;
use crate::driver::model::{Conserved, FieldSet, Geometry, Location, OutField, Values, Violation};
use crate::driver::outputs::per_depth;
use crate::ice::{IceState, MaterialCells};
use crate::material::eos::EquationOfState;
use crate::material::SolidMaterial;
use crate::mpm::{HalfSizes, Particles, Stresses, Tensors};
use crate::output::checkpoint::{Checkpoint, CheckpointError};

/// Stores `D`-vectors as an `[n, D]` array.
pub fn put_vectors<const D: usize>(ck: &mut Checkpoint, name: &str, v: &[SVector<f64, D>]) {
    ck.put_f64_with(name, vec![v.len(), D], |buf| {
        for x in v {
            buf.extend_from_slice(x.as_slice());
        }
    });
}

/// Reads an `[n, D]` array back into `D`-vectors.
pub fn take_vectors<const D: usize>(
    ck: &mut Checkpoint,
    name: &str,
    n: usize,
) -> Result<Vec<SVector<f64, D>>, CheckpointError> {
    let data = ck.take_f64(name, Some(&[n, D]))?;
    Ok(data
        .chunks_exact(D)
        .map(SVector::<f64, D>::from_column_slice)
        .collect())
}

/// Stores particle tensors as an `[n, k]` array of their stored entries,
/// `k` = [`Tensors::STRIDE`] in the order of [`Tensors::ENTRIES`] (1D: xx,
/// yy, zz; 2D: xx, xy, yx, yy, zz; 3D: all nine, row-major).
pub fn put_tensors<const D: usize, const SYM: bool>(
    ck: &mut Checkpoint,
    name: &str,
    t: &Tensors<D, SYM>,
) {
    ck.put_f64_with(name, vec![t.len(), Tensors::<D, SYM>::STRIDE], |buf| {
        buf.extend_from_slice(t.values())
    });
}

/// Reads `n` tensors saved by [`put_tensors`], or saved as full `[n, 3, 3]`
/// row-major matrices (checkpoints before the packed layout), whose entries
/// the dimension does not keep must then be zero. Symmetric tensors (the
/// stress) also load from the general packed layout (checkpoints before
/// the stress kept only its upper triangle), as their symmetric parts.
pub fn take_tensors<const D: usize, const SYM: bool>(
    ck: &mut Checkpoint,
    name: &str,
    n: usize,
) -> Result<Tensors<D, SYM>, CheckpointError> {
    let malformed = |reason: String| CheckpointError::Malformed {
        what: name.to_string(),
        reason,
    };
    if ck.shape(name) == Some(&[n, 3, 3][..]) {
        let m = take_matrices(ck, name, n)?;
        return Tensors::try_from_matrices(&m).map_err(|p| {
            malformed(format!(
                "particle {p} has a non-zero entry that a {D}D run keeps zero"
            ))
        });
    }
    if SYM && ck.shape(name) == Some(&[n, Tensors::<D>::STRIDE][..]) {
        let general = take_tensors::<D, false>(ck, name, n)?;
        let m: Vec<_> = general.iter().collect();
        return Tensors::try_from_matrices(&m)
            .map_err(|p| malformed(format!("particle {p}: not a {D}D tensor")));
    }
    let data = ck.take_f64(name, Some(&[n, Tensors::<D, SYM>::STRIDE]))?;
    Tensors::from_values(data).ok_or_else(|| malformed("not whole tensors".to_string()))
}

/// Reads an `[n, 3, 3]` array back into matrices.
pub fn take_matrices(
    ck: &mut Checkpoint,
    name: &str,
    n: usize,
) -> Result<Vec<Matrix3<f64>>, CheckpointError> {
    let data = ck.take_f64(name, Some(&[n, 3, 3]))?;
    Ok(data.chunks_exact(9).map(Matrix3::from_row_slice).collect())
}

/// Stores a scalar array as `[n]`.
pub fn put_scalars(ck: &mut Checkpoint, name: &str, v: &[f64]) {
    ck.put_f64_with(name, vec![v.len()], |buf| buf.extend_from_slice(v));
}

/// Reads an `[n]` array.
pub fn take_scalars(
    ck: &mut Checkpoint,
    name: &str,
    n: usize,
) -> Result<Vec<f64>, CheckpointError> {
    ck.take_f64(name, Some(&[n]))
}

/// The length of array `name` (its first axis).
pub fn length_of(ck: &Checkpoint, name: &str) -> Result<usize, CheckpointError> {
    ck.shape(name)
        .and_then(|s| s.first().copied())
        .ok_or_else(|| CheckpointError::Missing {
            what: format!("array `{name}`"),
        })
}

/// Saves every particle array under `prefix` (`prefix.x`, `prefix.v`, …).
pub fn save_particles<const D: usize>(ck: &mut Checkpoint, prefix: &str, p: &Particles<D>) {
    let n = |s: &str| format!("{prefix}.{s}");
    put_vectors(ck, &n("x"), &p.x);
    put_vectors(ck, &n("x0"), &p.x0);
    put_vectors(ck, &n("v"), &p.v);
    put_scalars(ck, &n("mass"), &p.mass);
    put_scalars(ck, &n("vol0"), &p.vol0);
    put_scalars(ck, &n("vol"), &p.vol);
    ck.put_f64_with(&n("half_size"), vec![p.len(), D], |buf| {
        for h in p.half_size.iter() {
            buf.extend_from_slice(h.as_slice());
        }
    });
    put_tensors(ck, &n("f"), &p.f);
    put_tensors(ck, &n("stress"), &p.stress);
    ck.put_u64_with(&n("material"), vec![p.len()], |buf| {
        buf.extend(p.material.iter().map(|&m| m as u64));
    });
    // The optional arrays, where a run tracks them.
    for (name, v) in [
        ("work", &p.work),
        ("temperature", &p.temperature),
        ("plastic_strain", &p.plastic_strain),
        ("damage", &p.damage),
    ] {
        if !v.is_empty() {
            put_scalars(ck, &n(name), v);
        }
    }
    // Ids only once they are not the indices ([`Particles::id`]).
    if !p.id.is_empty() {
        ck.put_u64_with(&n("id"), vec![p.len()], |buf| buf.extend(&p.id));
    }
}

/// Loads the particle arrays saved by [`save_particles`]; the material
/// indices must name one of `n_materials` materials.
pub fn load_particles<const D: usize>(
    ck: &mut Checkpoint,
    prefix: &str,
    n_materials: usize,
) -> Result<Particles<D>, CheckpointError> {
    let n = |s: &str| format!("{prefix}.{s}");
    let len = length_of(ck, &n("x"))?;
    let material = ck.take_u64(&n("material"), Some(&[len]))?;
    if let Some(&m) = material.iter().find(|&&m| m as usize >= n_materials) {
        return Err(CheckpointError::Malformed {
            what: n("material"),
            reason: format!("material index {m}, the scene has {n_materials} solid materials"),
        });
    }
    let optional = |ck: &mut Checkpoint, name: &str| {
        if ck.shape(&n(name)).is_some() {
            take_scalars(ck, &n(name), len)
        } else {
            Ok(Vec::new())
        }
    };
    Ok(Particles {
        x: take_vectors(ck, &n("x"), len)?,
        x0: take_vectors(ck, &n("x0"), len)?,
        v: take_vectors(ck, &n("v"), len)?,
        mass: take_scalars(ck, &n("mass"), len)?,
        vol0: take_scalars(ck, &n("vol0"), len)?,
        vol: take_scalars(ck, &n("vol"), len)?,
        half_size: HalfSizes::from_values(take_vectors(ck, &n("half_size"), len)?),
        f: take_tensors(ck, &n("f"), len)?,
        stress: take_tensors(ck, &n("stress"), len)?,
        // Stored by every checkpoint before the work became optional.
        work: optional(ck, "work")?,
        material: material.into_iter().map(|m| m as u16).collect(),
        // Each present when the run had started to track it.
        temperature: optional(ck, "temperature")?,
        plastic_strain: optional(ck, "plastic_strain")?,
        damage: optional(ck, "damage")?,
        // Absent: each particle's id is its index. Stored ids that are the
        // indices (an older checkpoint) become implicit again.
        id: match ck.shape(&n("id")) {
            Some(_) => {
                let id = ck.take_u64(&n("id"), Some(&[len]))?;
                let identity = id.iter().enumerate().all(|(i, &v)| v == i as u64);
                if identity {
                    Vec::new()
                } else {
                    id
                }
            }
            None => Vec::new(),
        },
    })
}

/// The particle snapshot: velocity, displacement, stress, deformation
/// gradient, mass, volume, J, material and temperature.
pub fn particle_fields<const D: usize>(p: &Particles<D>) -> FieldSet<'_> {
    let u = per_depth(D);
    let n = p.len();
    FieldSet {
        name: "particles",
        geometry: Geometry::Points(Values::vectors(&p.x)),
        fields: vec![
            OutField::with_csv("velocity", Some("v"), "m/s", Values::vectors(&p.v)),
            OutField::with_csv(
                "displacement",
                Some("u"),
                "m",
                Values::computed(n, 3, |i, o| {
                    o[..3].copy_from_slice(&pad3(&(p.x[i] - p.x0[i])))
                }),
            ),
            OutField::with_csv("stress", Some("s"), "Pa", Values::tensors(&p.stress)),
            OutField::with_csv("deformation_gradient", None, "-", Values::tensors(&p.f)),
            OutField::new("mass", &format!("kg{u}"), Values::scalars(&p.mass)),
            OutField::new("volume", &format!("m^3{u}"), Values::scalars(&p.vol)),
            OutField::new(
                "J",
                "-",
                Values::computed(n, 1, |i, o| o[0] = p.f.get(i).determinant()),
            ),
            OutField::new(
                "id",
                "-",
                Values::computed(n, 1, |i, o| o[0] = p.id_of(i) as f64),
            ),
            OutField::new(
                "material",
                "-",
                Values::computed(n, 1, |i, o| o[0] = f64::from(p.material[i])),
            ),
            OutField::new(
                "temperature",
                "K",
                Values::computed(n, 1, |i, o| o[0] = p.temperature_of(i)),
            ),
        ],
        csv: true,
    }
}

/// The plastic snapshot field `plastic_strain` (equivalent plastic strain
/// ε̄, 0 for elastic materials); empty when no material is plastic.
pub fn plastic_fields<'a, const D: usize>(
    p: &'a Particles<D>,
    materials: &[SolidMaterial],
) -> Vec<OutField<'a>> {
    if materials.iter().all(|m| m.plasticity().is_none()) {
        return Vec::new();
    }
    vec![OutField::new(
        "plastic_strain",
        "-",
        Values::computed(p.len(), 1, |i, o| o[0] = p.plastic_strain_of(i)),
    )]
}

/// The failure snapshot fields `damage` (D ∈ [0, 1]) and `failed` (1 when
/// D = 1, else 0); empty when no material has a failure model.
pub fn failure_fields<'a, const D: usize>(
    p: &'a Particles<D>,
    materials: &[SolidMaterial],
) -> Vec<OutField<'a>> {
    if materials.iter().all(|m| m.failure().is_none()) {
        return Vec::new();
    }
    vec![
        OutField::new(
            "damage",
            "-",
            Values::computed(p.len(), 1, |i, o| o[0] = p.damage_of(i)),
        ),
        OutField::new(
            "failed",
            "-",
            Values::computed(p.len(), 1, |i, o| {
                o[0] = if p.failed(i) { 1.0 } else { 0.0 }
            }),
        ),
    ]
}

/// The gas-point snapshot fields (York Sec. 3.3), one value per particle:
/// `pressure` (the EOS pressure p of a gas point, −tr σ/3 of a solid),
/// `density` (m/V, York Eq. 16), `internal_energy` (specific e of a gas
/// point, York Eq. 23; the stored work per unit mass of a solid) and `q`
/// (York Eq. 24; 0 for solids). Empty when no material is a gas point.
pub fn gas_point_fields<'a, const D: usize>(
    p: &'a Particles<D>,
    materials: &'a [SolidMaterial],
) -> Vec<OutField<'a>> {
    if materials.iter().all(|m| m.gas().is_none()) {
        return Vec::new();
    }
    let n = p.len();
    let rho = move |i: usize| p.mass[i] / p.vol[i];
    let e = move |i: usize| p.work_of(i) * p.vol0[i] / p.mass[i];
    // (p, q) of particle i.
    let pq = move |i: usize| {
        let s = p.stress.get(i);
        let mean = -s.trace() / 3.0;
        match materials[p.material[i] as usize].gas() {
            Some(g) => {
                let qi = g.q_of(&s, rho(i), e(i));
                (mean - qi, qi)
            }
            None => (mean, 0.0),
        }
    };
    vec![
        OutField::new(
            "pressure",
            "Pa",
            Values::computed(n, 1, move |i, o| o[0] = pq(i).0),
        ),
        OutField::new(
            "density",
            "kg/m^3",
            Values::computed(n, 1, move |i, o| o[0] = rho(i)),
        ),
        OutField::new(
            "internal_energy",
            "J/kg",
            Values::computed(n, 1, move |i, o| o[0] = e(i)),
        ),
        OutField::new(
            "q",
            "Pa",
            Values::computed(n, 1, move |i, o| o[0] = pq(i).1),
        ),
    ]
}

/// Whether particle `i` holds only finite, physically possible values.
fn particle_ok<const D: usize>(p: &Particles<D>, i: usize, materials: &[SolidMaterial]) -> bool {
    particle_violation(p, i, materials).is_none()
}

/// The first impossible value of particle `i`: `(field, value, rule)`.
fn particle_violation<const D: usize>(
    p: &Particles<D>,
    i: usize,
    materials: &[SolidMaterial],
) -> Option<(&'static str, f64, &'static str)> {
    const POS: &str = "finite and > 0";
    const FIN: &str = "finite";
    let bad_vec = |v: &SVector<f64, D>| v.iter().copied().find(|x| !x.is_finite());
    if let Some(x) = bad_vec(&p.x[i]) {
        return Some(("position", x, FIN));
    }
    if let Some(x) = bad_vec(&p.v[i]) {
        return Some(("velocity", x, FIN));
    }
    for (field, x) in [("mass", p.mass[i]), ("volume", p.vol[i])] {
        if !(x.is_finite() && x > 0.0) {
            return Some((field, x, POS));
        }
    }
    let j = p.f.get(i).determinant();
    if !(j.is_finite() && j > 0.0) {
        return Some(("J", j, POS));
    }
    if let Some(&x) = p.stress.get(i).iter().find(|x| !x.is_finite()) {
        return Some(("stress", x, FIN));
    }
    let t = p.temperature_of(i);
    if !(t.is_finite() && t > 0.0) {
        return Some(("temperature", t, POS));
    }
    let ep = p.plastic_strain_of(i);
    if !(ep.is_finite() && ep >= 0.0) {
        return Some(("plastic_strain", ep, "finite and ≥ 0"));
    }
    if let Some(&d) = p.damage.get(i) {
        if !(d.is_finite() && (0.0..=1.0).contains(&d)) {
            return Some(("damage", d, "in [0, 1]"));
        }
    }
    // A gas point needs a positive internal energy (York Eq. 23; its work
    // holds ρ_ref e).
    if materials
        .get(p.material[i] as usize)
        .is_some_and(|m| m.gas().is_some())
        && !(p.work_of(i).is_finite() && p.work_of(i) > 0.0)
    {
        return Some(("internal_energy", p.work_of(i) * p.vol0[i] / p.mass[i], POS));
    }
    None
}

/// Whether every particle passes [`particle_violation`]: the watchdog's
/// fast pass, branch-free sweeps per field over chunks of particles (as
/// [`cells_pass`]); only a failing state pays for the search that names the
/// particle.
fn particles_pass<const D: usize>(p: &Particles<D>, materials: &[SolidMaterial]) -> bool {
    const CHUNK: usize = 4096;
    let any_gas = materials.iter().any(|m| m.gas().is_some());
    (0..p.len().div_ceil(CHUNK)).into_par_iter().all(|c| {
        let r = c * CHUNK..((c + 1) * CHUNK).min(p.len());
        let j_ok = r.clone().fold(true, |ok, i| {
            let j = p.f.get(i).determinant();
            ok & (j > 0.0) & (j <= f64::MAX)
        });
        // The entries a dimension keeps zero are not stored.
        let k = Stresses::<D>::STRIDE;
        let stress_ok = p.stress.values()[k * r.start..k * r.end]
            .iter()
            .fold(true, |o, &x| o & (x.abs() <= f64::MAX));
        let damage_ok = p
            .damage
            .get(r.clone())
            .is_none_or(|d| d.iter().fold(true, |ok, &x| ok & (0.0..=1.0).contains(&x)));
        all_finite_vectors(&p.x[r.clone()])
            && all_finite_vectors(&p.v[r.clone()])
            && all_positive(&p.mass[r.clone()])
            && all_positive(&p.vol[r.clone()])
            && j_ok
            && stress_ok
            && p.temperature.get(r.clone()).is_none_or(all_positive)
            && p.plastic_strain.get(r.clone()).is_none_or(all_nonnegative)
            && damage_ok
            && (!any_gas
                || r.into_iter()
                    .all(|i| particle_violation(p, i, materials).is_none()))
    })
}

/// The first particle (lowest index) with an impossible value.
pub fn particle_watchdog<const D: usize>(
    p: &Particles<D>,
    materials: &[SolidMaterial],
) -> Option<Violation> {
    if particles_pass(p, materials) {
        return None;
    }
    let i = (0..p.len())
        .into_par_iter()
        .find_first(|&i| !particle_ok(p, i, materials))?;
    let (field, value, rule) = particle_violation(p, i, materials)?;
    Some(Violation {
        at: Location::Particle(i),
        material: materials
            .get(p.material[i] as usize)
            .map_or_else(|| format!("#{}", p.material[i]), |m| m.name.clone()),
        field,
        value,
        rule,
    })
}

/// Saves the cell fields of every ICE material (ghosts included), the
/// pressures, the time and the step count under `prefix`.
pub fn save_cells<const D: usize>(ck: &mut Checkpoint, prefix: &str, s: &IceState<D>) {
    for (r, mc) in s.cells.iter().enumerate() {
        let n = |f: &str| format!("{prefix}.m{r}.{f}");
        put_scalars(ck, &n("mass"), &mc.mass);
        put_vectors(ck, &n("velocity"), &mc.velocity);
        put_scalars(ck, &n("temperature"), &mc.temperature);
        put_scalars(ck, &n("sp_vol"), &mc.sp_vol);
        put_scalars(ck, &n("vol_frac"), &mc.vol_frac);
    }
    put_scalars(ck, &format!("{prefix}.p_eq"), &s.p_eq);
    put_scalars(ck, &format!("{prefix}.pressure"), &s.pressure);
    ck.put_f64(&format!("{prefix}.time"), vec![1], vec![s.time]);
    ck.put_u64(&format!("{prefix}.steps"), vec![1], vec![s.steps]);
}

/// Loads what [`save_cells`] saved into `s` (built from the same scene, so
/// of the same layout and materials).
pub fn load_cells<const D: usize>(
    ck: &mut Checkpoint,
    prefix: &str,
    s: &mut IceState<D>,
) -> Result<(), CheckpointError> {
    let len = s.layout.len();
    for (r, mc) in s.cells.iter_mut().enumerate() {
        let n = |f: &str| format!("{prefix}.m{r}.{f}");
        *mc = MaterialCells {
            mass: take_scalars(ck, &n("mass"), len)?,
            velocity: take_vectors(ck, &n("velocity"), len)?,
            temperature: take_scalars(ck, &n("temperature"), len)?,
            sp_vol: take_scalars(ck, &n("sp_vol"), len)?,
            vol_frac: take_scalars(ck, &n("vol_frac"), len)?,
        };
    }
    s.p_eq = take_scalars(ck, &format!("{prefix}.p_eq"), len)?;
    s.pressure = take_scalars(ck, &format!("{prefix}.pressure"), len)?;
    s.time = ck.take_f64(&format!("{prefix}.time"), Some(&[1]))?[0];
    s.steps = ck.take_u64(&format!("{prefix}.steps"), Some(&[1]))?[0];
    Ok(())
}

/// The first impossible value of cell `c` for material `r`.
fn cell_violation<const D: usize>(
    mc: &MaterialCells<D>,
    c: usize,
) -> Option<(&'static str, f64, &'static str)> {
    let m = mc.mass[c];
    if !(m.is_finite() && m >= 0.0) {
        return Some(("mass", m, "finite and >= 0"));
    }
    if let Some(&u) = mc.velocity[c].iter().find(|u| !u.is_finite()) {
        return Some(("velocity", u, "finite"));
    }
    let t = mc.temperature[c];
    if !(t.is_finite() && t > 0.0) {
        return Some(("temperature (internal energy)", t, "finite and > 0"));
    }
    let v = mc.sp_vol[c];
    if !(v.is_finite() && v > 0.0) {
        return Some(("specific volume (1/density)", v, "finite and > 0"));
    }
    let th = mc.vol_frac[c];
    if !(th.is_finite() && th >= 0.0) {
        return Some(("volume fraction", th, "finite and >= 0"));
    }
    None
}

/// Whether every value is finite and ≥ 0 (`x ∈ [0, MAX]` fails on NaN and
/// ±∞). Non-short-circuit `&` over a contiguous slice: no branch per
/// value, so the compiler vectorises it.
fn all_nonnegative(v: &[f64]) -> bool {
    v.iter()
        .fold(true, |ok, &x| ok & (0.0..=f64::MAX).contains(&x))
}

/// Whether every value is finite and > 0 (as [`all_nonnegative`]).
fn all_positive(v: &[f64]) -> bool {
    v.iter()
        .fold(true, |ok, &x| ok & (x > 0.0) & (x <= f64::MAX))
}

/// Whether every value is finite (as [`all_nonnegative`]).
fn all_finite(v: &[f64]) -> bool {
    v.iter().fold(true, |ok, &x| ok & (x.abs() <= f64::MAX))
}

/// Whether every component of every vector is finite.
fn all_finite_vectors<const D: usize>(v: &[SVector<f64, D>]) -> bool {
    v.iter().fold(true, |ok, x| {
        ok & x.iter().fold(true, |o, &c| o & (c.abs() <= f64::MAX))
    })
}

/// Whether every interior cell passes [`cell_violation`] for every material
/// and has a finite pressure: the watchdog's fast pass, one branch-free
/// sweep per field over each contiguous interior x-row (1D Sod, 6400
/// cells: 8 µs, where the per-cell [`cell_violation`] test with its early
/// exits took 67 µs; `probes/src/bin/run_loop_cost.rs`). Only a failing state
/// pays for the search of [`cell_watchdog`] that names the site.
fn cells_pass<const D: usize>(s: &IceState<D>) -> bool {
    let n = s.layout.cells[0];
    s.layout.rows.par_iter().all(|&r0| {
        let r = r0..r0 + n;
        all_finite(&s.pressure[r.clone()])
            && s.cells.iter().all(|mc| {
                all_nonnegative(&mc.mass[r.clone()])
                    && all_finite_vectors(&mc.velocity[r.clone()])
                    && all_positive(&mc.temperature[r.clone()])
                    && all_positive(&mc.sp_vol[r.clone()])
                    && all_nonnegative(&mc.vol_frac[r.clone()])
            })
    })
}

/// The first interior cell (in layout order, then material order) with an
/// impossible value; `names[r]` names ICE material `r`; the pressure must be
/// finite.
pub fn cell_watchdog<const D: usize>(s: &IceState<D>) -> Option<Violation> {
    if cells_pass(s) {
        return None;
    }
    let interior = &s.layout.interior;
    let bad = |c: usize| {
        !s.pressure[c].is_finite() || s.cells.iter().any(|mc| cell_violation(mc, c).is_some())
    };
    let k = (0..interior.len())
        .into_par_iter()
        .find_first(|&k| bad(interior[k]))?;
    let c = interior[k];
    let ijk = s.layout.coords(c);
    let at = Location::Cell(c, std::array::from_fn(|d| if d < D { ijk[d] } else { 0 }));
    for (r, mc) in s.cells.iter().enumerate() {
        if let Some((field, value, rule)) = cell_violation(mc, c) {
            return Some(Violation {
                at,
                material: s.materials[r].name.clone(),
                field,
                value,
                rule,
            });
        }
    }
    Some(Violation {
        at,
        material: "(mixture)".into(),
        field: "pressure",
        value: s.pressure[c],
        rule: "finite",
    })
}

/// The cell snapshot: pressure, equilibration pressure and mixture density,
/// then per material its density, true density, volume fraction,
/// temperature and velocity (names prefixed by the material's name).
pub fn cell_fields<const D: usize>(s: &IceState<D>) -> FieldSet<'static> {
    let l = &s.layout;
    let interior = &l.interior;
    let vol = l.cell_volume();
    let pick = |v: &[f64]| interior.iter().map(|&c| v[c]).collect::<Vec<f64>>();
    let mut fields = vec![
        OutField::new("pressure", "Pa", Values::Scalar(pick(&s.pressure))),
        OutField::new("p_eq", "Pa", Values::Scalar(pick(&s.p_eq))),
        OutField::new(
            "mixture_density",
            "kg/m^3",
            Values::Scalar(interior.iter().map(|&c| s.mixture_density(c)).collect()),
        ),
    ];
    for (m, mc) in s.materials.iter().zip(&s.cells) {
        let n = &m.name;
        fields.push(OutField::new(
            &format!("{n}_density"),
            "kg/m^3",
            Values::Scalar(interior.iter().map(|&c| mc.mass[c] / vol).collect()),
        ));
        fields.push(OutField::new(
            &format!("{n}_true_density"),
            "kg/m^3",
            Values::Scalar(interior.iter().map(|&c| 1.0 / mc.sp_vol[c]).collect()),
        ));
        fields.push(OutField::new(
            &format!("{n}_volume_fraction"),
            "-",
            Values::Scalar(pick(&mc.vol_frac)),
        ));
        fields.push(OutField::new(
            &format!("{n}_temperature"),
            "K",
            Values::Scalar(pick(&mc.temperature)),
        ));
        fields.push(OutField::with_csv(
            &format!("{n}_velocity"),
            Some(&format!("{n}_u")),
            "m/s",
            Values::Vector(interior.iter().map(|&c| pad3(&mc.velocity[c])).collect()),
        ));
    }
    FieldSet {
        name: "cells",
        geometry: Geometry::Image {
            origin: pad3(&l.lower),
            spacing: std::array::from_fn(|d| if d < D { l.h[d] } else { 1.0 }),
            cells: std::array::from_fn(|d| if d < D { l.cells[d] } else { 0 }),
            on_cells: true,
            centres: interior.iter().map(|&c| pad3(&l.centre(c))).collect(),
        },
        fields,
        csv: D <= 2,
    }
}

/// Kinetic and internal energy of the fluid cells (internal in `strain`).
pub fn cell_energies<const D: usize>(state: &IceState<D>) -> crate::stepper::Energies {
    let (mut kinetic, mut internal) = (0.0, 0.0);
    for (mat, mc) in state.materials.iter().zip(&state.cells) {
        let cv = mat.eos.specific_heat_cv();
        for &c in &state.layout.interior {
            kinetic += 0.5 * mc.mass[c] * mc.velocity[c].norm_squared();
            internal += mc.mass[c] * cv * mc.temperature[c];
        }
    }
    crate::stepper::Energies {
        kinetic,
        strain: internal,
        potential: 0.0,
    }
}

/// Per-material totals of ICE material `r` over the interior cells.
pub fn cell_material_totals<const D: usize>(
    s: &IceState<D>,
    r: usize,
) -> crate::driver::model::MaterialTotals {
    let (mat, mc) = (&s.materials[r], &s.cells[r]);
    let cv = mat.eos.specific_heat_cv();
    let mut t = crate::driver::model::MaterialTotals {
        name: mat.name.clone(),
        ..Default::default()
    };
    let mut p = SVector::<f64, D>::zeros();
    for &c in &s.layout.interior {
        let m = mc.mass[c];
        t.mass += m;
        p += mc.velocity[c] * m;
        t.kinetic += 0.5 * m * mc.velocity[c].norm_squared();
        t.internal += m * cv * mc.temperature[c];
    }
    t.momentum = pad3(&p);
    t
}

/// Per-material totals of the particles of solid material `k`.
pub fn particle_material_totals<const D: usize>(
    p: &Particles<D>,
    materials: &[SolidMaterial],
    k: usize,
) -> crate::driver::model::MaterialTotals {
    let mut t = crate::driver::model::MaterialTotals {
        name: materials[k].name.clone(),
        ..Default::default()
    };
    let mut mom = SVector::<f64, D>::zeros();
    for i in (0..p.len()).filter(|&i| p.material[i] as usize == k) {
        t.mass += p.mass[i];
        mom += p.v[i] * p.mass[i];
        t.kinetic += 0.5 * p.mass[i] * p.v[i].norm_squared();
        t.internal += p.vol0[i] * materials[k].strain_energy_density(&p.f.get(i), p.work_of(i));
    }
    t.momentum = pad3(&mom);
    t
}

/// Names the material of the particle a numerical failure names (`what`
/// gains `, material `NAME``).
pub fn name_particle_material<const D: usize>(
    e: crate::error::Error,
    p: &Particles<D>,
    materials: &[SolidMaterial],
) -> crate::error::Error {
    match e {
        crate::error::Error::Numerical { site, what } => {
            let name = site
                .particle
                .and_then(|i| p.material.get(i))
                .and_then(|&m| materials.get(m as usize));
            let what = match name {
                Some(m) => format!("{what} (material `{}`)", m.name),
                None => what,
            };
            crate::error::Error::Numerical { site, what }
        }
        e => e,
    }
}

/// The conservation totals of a particle model: per material, and the
/// model's energies.
pub fn particle_conserved<const D: usize>(
    p: &Particles<D>,
    materials: &[SolidMaterial],
    energies: crate::stepper::Energies,
) -> Conserved {
    Conserved {
        materials: (0..materials.len())
            .map(|k| particle_material_totals(p, materials, k))
            .collect(),
        energies,
        momentum_scale: p.momentum_scale(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Particle tensors round-trip through a checkpoint in the packed
    /// layout, and the full `[n, 3, 3]` layout of older checkpoints still
    /// loads unless it holds an entry the dimension keeps zero.
    #[test]
    fn tensors_load_from_the_packed_and_the_full_layout() {
        let plane = Matrix3::new(1.1, 0.2, 0.0, -0.3, 0.9, 0.0, 0.0, 0.0, 1.05);
        let t = Tensors::<2>::try_from_matrices(&[Matrix3::identity(), plane]).expect("2D");
        let mut ck = Checkpoint::new("test", "", 0, 0.0);
        put_tensors(&mut ck, "f", &t);
        assert_eq!(ck.shape("f"), Some(&[2, 5][..]));
        assert_eq!(
            take_tensors::<2, false>(&mut ck, "f", 2).expect("packed"),
            t
        );
        let full = |m: &[Matrix3<f64>], ck: &mut Checkpoint| {
            ck.put_f64_with("f", vec![m.len(), 3, 3], |buf| {
                for a in m {
                    buf.extend_from_slice(a.transpose().as_slice());
                }
            })
        };
        full(&[Matrix3::identity(), plane], &mut ck);
        assert_eq!(take_tensors::<2, false>(&mut ck, "f", 2).expect("full"), t);
        let mut bent = plane;
        bent[(0, 2)] = 1e-3;
        full(&[plane, bent], &mut ck);
        let err = take_tensors::<2, false>(&mut ck, "f", 2).expect_err("out of plane");
        assert!(err.to_string().contains("particle 1"), "{err}");
        // A stress saved in the general packed layout (before the stress
        // kept its upper triangle) loads as its symmetric part: to the bit
        // when it was symmetric.
        let sigma = Matrix3::new(2.0, -0.5, 0.0, -0.5, 1.0, 0.0, 0.0, 0.0, 0.25);
        let mut skew = sigma;
        skew[(1, 0)] = -0.25;
        let general = Tensors::<2>::try_from_matrices(&[sigma, skew]).expect("2D");
        put_tensors(&mut ck, "stress", &general);
        let s = take_tensors::<2, true>(&mut ck, "stress", 2).expect("general layout");
        assert_eq!(s.get(0), sigma);
        assert_eq!((s.get(1)[(0, 1)], s.get(1)[(1, 0)]), (-0.375, -0.375));
        put_tensors(&mut ck, "stress", &s);
        assert_eq!(ck.shape("stress"), Some(&[2, 4][..]));
        assert_eq!(
            take_tensors::<2, true>(&mut ck, "stress", 2).expect("upper"),
            s
        );
    }

    /// Ids in creation order are neither stored nor checkpointed; ids
    /// after a removal are, and both come back; an older checkpoint's
    /// stored identity ids load as implicit ones.
    #[test]
    fn particle_ids_round_trip_implicit_or_stored() {
        let mut p = Particles::<2>::default();
        for i in 0..4 {
            let x = SVector::<f64, 2>::new(i as f64, 0.0);
            p.push(x, x, 1.0, 1.0, x, 0);
        }
        let ids = |p: &Particles<2>| (0..p.len()).map(|i| p.id_of(i)).collect::<Vec<_>>();
        let mut ck = Checkpoint::new("test", "", 0, 0.0);
        save_particles(&mut ck, "particles", &p);
        assert!(ck.shape("particles.id").is_none());
        let back = load_particles::<2>(&mut ck, "particles", 1).expect("implicit");
        assert!(back.id.is_empty() && ids(&back) == [0, 1, 2, 3]);

        p.retain(&[true, false, true, true]);
        let mut ck = Checkpoint::new("test", "", 0, 0.0);
        save_particles(&mut ck, "particles", &p);
        assert_eq!(ck.shape("particles.id"), Some(&[3][..]));
        let back = load_particles::<2>(&mut ck, "particles", 1).expect("stored");
        assert_eq!(ids(&back), [0, 2, 3]);

        let mut ck = Checkpoint::new("test", "", 0, 0.0);
        save_particles(&mut ck, "particles", &p);
        ck.put_u64("particles.id", vec![3], vec![0, 1, 2]);
        let back = load_particles::<2>(&mut ck, "particles", 1).expect("old");
        assert!(back.id.is_empty() && ids(&back) == [0, 1, 2]);
    }
}
