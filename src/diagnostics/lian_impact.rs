//! Lian, Liu, Zhang Sec. 7.1 (Figs. 5–11): membrane–sphere impacts through
//! the grid contact: `cases/lian_membrane_on_sphere.toml` (a membrane falls
//! on a sphere whose bottom is held; the whole model) and
//! `cases/lian_sphere_on_membrane.toml` (a sphere falls on a clamped
//! membrane; a quarter model); also Sec. 7.2's water drop
//! (`cases/lian_water_sphere.toml`, gas points with Lian's Mie–Grüneisen
//! EOS on the same membrane layout). [`impact_scene`] refines a case (cell
//! size `h`, element size the nearest that divides the membrane, particles
//! per cell and direction fixed); [`run_impact`] records the paper's curves
//! — the z of the membrane's centre and corner (Figs. 6, 11) and of the
//! sphere's top point (Fig. 9) — with the energy account, the first contact
//! and the smallest clearance between the bodies.
//!
//! No reference solution exists for these impacts (the paper compares with
//! LS-DYNA, not available here); the measures are convergence under
//! refinement, the contact's onset against the exact free-flight time, and
//! the energy account.

use std::collections::HashMap;
use std::time::Instant;

use crate::contact::node_normals;
use crate::driver::model::{DtRequest, Model};
use crate::driver::models::MembraneContact;
use crate::error::{Error, SceneError};
use crate::membrane::element::V3;
use crate::scene::{Geometry, MeshSpec, Scene};

/// A case refined to the cell size `h`: the grid's cells set to
/// `extent / h` (which must come out whole within 1e-6), the first
/// membrane's rectangle elements to the nearest whole number of `h` (the
/// 25 mm half-side takes 13 elements at h = 2 mm; a membrane centred on
/// the axis the nearest even number, 26 across 50 mm), particles per cell
/// and direction unchanged.
///
/// # Errors
/// A scene not laid out as the cases (one sphere object, one rectangle
/// membrane), or an `h` that does not divide the grid or the membrane.
pub fn impact_scene(base: &Scene, h: f64) -> Result<Scene, Error> {
    let mut sc = base.clone();
    let whole = |len: f64, key: &str| -> Result<usize, Error> {
        let n = len / h;
        if !(n.is_finite() && n >= 1.0 && (n - n.round()).abs() < 1e-6) {
            return Err(
                SceneError::new(key, format!("a whole number of cells of {h} (got {n})")).into(),
            );
        }
        Ok(n.round() as usize)
    };
    for d in 0..sc.grid.cells.len() {
        sc.grid.cells[d] = whole(sc.grid.upper[d] - sc.grid.lower[d], "grid.cells")?;
    }
    let layout = "a rectangle, laid out as cases/lian_*_sphere*.toml";
    let Some(MeshSpec::Rectangle {
        corner,
        edge_a,
        edge_b,
        cells,
    }) = sc.membrane_elements.first_mut().map(|m| &mut m.mesh)
    else {
        return Err(SceneError::new("membrane_elements[0].mesh", layout).into());
    };
    // A membrane centred on the axis (the whole model) keeps a node there:
    // an even count.
    let step = if corner[0] < 0.0 { 2.0 } else { 1.0 };
    let n = |e: &[f64; 3]| {
        let len = e.iter().map(|c| c * c).sum::<f64>().sqrt();
        (((len / (step * h)).round() * step) as usize).max(step as usize)
    };
    *cells = [n(edge_a), n(edge_b)];
    sphere(&sc)?;
    Ok(sc)
}

/// The sphere's centre and radius (the first object).
fn sphere(sc: &Scene) -> Result<([f64; 3], f64), Error> {
    match sc.objects.first().map(|o| &o.geometry) {
        Some(Geometry::Sphere { center, radius }) if center.len() == 3 => {
            Ok(([center[0], center[1], center[2]], *radius))
        }
        _ => Err(SceneError::new("objects[0].geometry", "a sphere in 3D").into()),
    }
}

/// What a run gives: the paper's curves and the account, sampled every
/// `every` (the steps land on the sample times).
#[derive(Debug, Clone, Default)]
pub struct ImpactRun {
    /// Cell (and element) size.
    pub h: f64,
    /// Sample times \[s\].
    pub t: Vec<f64>,
    /// z of the membrane's node on the axis (the paper's centre (0, 0)).
    pub membrane_centre_z: Vec<f64>,
    /// z of its node farthest from the axis (the paper's corner
    /// (−25, −25) mm, by symmetry).
    pub membrane_corner_z: Vec<f64>,
    /// z of the sphere's particle that starts nearest its top on the axis.
    pub sphere_top_z: Vec<f64>,
    /// The sphere's mass (its particles').
    pub sphere_mass: Vec<f64>,
    /// The sphere's mass-weighted mean z velocity.
    pub sphere_vz: Vec<f64>,
    /// Kinetic energy of both bodies.
    pub kinetic: Vec<f64>,
    /// Kinetic and stored energy of both bodies (less the membranes'
    /// external work).
    pub mechanical: Vec<f64>,
    /// Energy the membrane's hourglass control and damping dissipated.
    pub hourglass: Vec<f64>,
    /// Energy the contact took from both bodies (minus its work,
    /// [`crate::contact::ContactStats`]).
    pub contact: Vec<f64>,
    /// The account, `mechanical + hourglass + contact` (the history's
    /// total): the initial energy up to the scheme's own error.
    pub total: Vec<f64>,
    /// Time of the first step with a contact force.
    pub first_contact: Option<f64>,
    /// Smallest clearance over the samples: a sphere particle's distance from
    /// the membrane, along z, on the membrane's side it started on, taken
    /// at the membrane's node nearest the particle in plan (negative: the
    /// particle passed through).
    pub min_clearance: f64,
    /// Smallest clearance along the membrane's normal: a particle's
    /// distance from the membrane node nearest to it (in space, now), along
    /// that node's unit normal, on the side the sphere started on. Unlike
    /// [`Self::min_clearance`] it follows a membrane that moves in plan or
    /// slopes (the water drop's bowl, many cells deep).
    pub min_normal_clearance: f64,
    /// Steps taken.
    pub steps: u64,
    /// Wall time \[s\].
    pub wall_s: f64,
}

impl ImpactRun {
    /// The sampled curves as CSV with a header: time, the membrane's centre
    /// and corner z, the sphere's top z and mean v_z, the mechanical
    /// energy, the hourglass and contact losses and the account.
    pub fn curves_csv(&self) -> String {
        let mut csv = String::from(
            "t [s],membrane_centre_z [m],membrane_corner_z [m],sphere_top_z [m],sphere_vz [m/s],\
             mechanical [J],hourglass [J],contact [J],total [J]\n",
        );
        for k in 0..self.t.len() {
            let row = [
                self.t[k],
                self.membrane_centre_z[k],
                self.membrane_corner_z[k],
                self.sphere_top_z[k],
                self.sphere_vz[k],
                self.mechanical[k],
                self.hourglass[k],
                self.contact[k],
                self.total[k],
            ];
            let row: Vec<String> = row.iter().map(f64::to_string).collect();
            csv.push_str(&row.join(","));
            csv.push('\n');
        }
        csv
    }

    /// The largest difference of a curve between this run and `other`
    /// over their common samples (same `every`).
    pub fn max_difference(&self, other: &Self, curve: fn(&Self) -> &[f64]) -> f64 {
        curve(self)
            .iter()
            .zip(curve(other))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    }

    /// The account's largest departure from its initial value over the
    /// samples, relative to the initial kinetic energy (all of the energy
    /// in the two impacts; a water drop also carries its internal energy,
    /// `e = c_v T`, which would make the departure look small): what the
    /// losses it books do not explain.
    pub fn energy_residual(&self) -> f64 {
        self.largest_change(&self.total, f64::abs)
    }

    /// The mechanical energy's largest rise above its initial value,
    /// relative to the initial kinetic energy (nothing does work on the
    /// system; only the staggered kinetic energy of the membranes'
    /// half-step velocities can raise it).
    pub fn largest_gain(&self) -> f64 {
        self.largest_change(&self.mechanical, |d| d)
    }

    /// `max over samples of f(e − e(0)) / kinetic(0)`, at least 0.
    fn largest_change(&self, series: &[f64], f: fn(f64) -> f64) -> f64 {
        let e0 = series.first().copied().unwrap_or(0.0);
        let k0 = self.kinetic.first().copied().unwrap_or(0.0);
        series
            .iter()
            .map(|e| f(e - e0) / k0.max(f64::MIN_POSITIVE))
            .fold(0.0, f64::max)
    }
}

/// Runs a case (from [`impact_scene`] or as loaded) to its `time.end`,
/// sampling every `every`.
///
/// # Errors
/// A scene that does not build, a numerical failure (both named).
pub fn run_impact(sc: &Scene, every: f64) -> Result<ImpactRun, Error> {
    let (centre, radius) = sphere(sc)?;
    let mut m = MembraneContact::from_scene(sc)?;
    let h = (sc.grid.upper[0] - sc.grid.lower[0]) / sc.grid.cells[0] as f64;
    let sheet = &m.membranes.meshes[0];
    let node = |key: &dyn Fn(&[f64]) -> f64| {
        (0..sheet.num_nodes())
            .min_by(|&a, &b| key(sheet.x[a].as_slice()).total_cmp(&key(sheet.x[b].as_slice())))
            .unwrap_or(0)
    };
    let centre_node = node(&|x| x[0].hypot(x[1]));
    let corner_node = node(&|x| -(x[0] + x[1]));
    // The membrane's nodes by their place in plan (the rectangle's lattice).
    let he = match &sc.membrane_elements[0].mesh {
        MeshSpec::Rectangle { edge_a, cells, .. } => edge_a[0].hypot(edge_a[1]) / cells[0] as f64,
        _ => h,
    };
    let lattice = |x: f64, y: f64| ((x / he).round() as i64, (y / he).round() as i64);
    let plan: HashMap<(i64, i64), usize> = (0..sheet.num_nodes())
        .map(|k| (lattice(sheet.x[k][0], sheet.x[k][1]), k))
        .collect();
    let p = &m.solid.run.particles;
    let top = [centre[0], centre[1], centre[2] + radius];
    let top_particle = (0..p.len())
        .min_by(|&a, &b| {
            let d = |q: usize| (0..3).map(|k| (p.x[q][k] - top[k]).powi(2)).sum::<f64>();
            d(a).total_cmp(&d(b))
        })
        .unwrap_or(0);
    // Which side of the membrane the sphere starts on.
    let side = (sheet.x[centre_node][2] - centre[2]).signum();
    let mut normals = vec![V3::zeros(); sheet.num_nodes()];
    node_normals(sheet, &mut normals, None);
    let to_sphere = V3::new(centre[0], centre[1], centre[2]) - sheet.x[centre_node];
    let normal_side = to_sphere.dot(&normals[centre_node]).signum();
    let start = Instant::now();
    let mut out = ImpactRun {
        h,
        min_clearance: f64::INFINITY,
        min_normal_clearance: f64::INFINITY,
        ..Default::default()
    };
    let mut row = Vec::new();
    let mut next = 0.0;
    let end = sc.time.end;
    loop {
        if m.time() >= next - 1e-12 * end {
            sample(
                &m,
                &mut out,
                &mut row,
                [centre_node, corner_node, top_particle],
            );
            clearance(&m, &plan, &lattice, side, &mut out.min_clearance);
            node_normals(&m.membranes.meshes[0], &mut normals, None);
            normal_clearance(&m, &normals, normal_side, &mut out.min_normal_clearance);
            next += every;
        }
        if m.time() >= end * (1.0 - 1e-12) {
            break;
        }
        m.step(DtRequest {
            value: (end - m.time()).min(next - m.time()).max(1e-300),
            exact: false,
        })
        .map_err(|e| m.annotate(e))?;
        if out.first_contact.is_none() && m.contact.last.contact_nodes > 0 {
            out.first_contact = Some(m.time());
        }
    }
    out.steps = m.steps();
    out.wall_s = start.elapsed().as_secs_f64();
    Ok(out)
}

fn sample(m: &MembraneContact, out: &mut ImpactRun, row: &mut Vec<f64>, at: [usize; 3]) {
    let sheet = &m.membranes.meshes[0];
    let p = &m.solid.run.particles;
    out.t.push(m.time());
    out.membrane_centre_z.push(sheet.x[at[0]][2]);
    out.membrane_corner_z.push(sheet.x[at[1]][2]);
    out.sphere_top_z.push(p.x[at[2]][2]);
    let mass = p.total_mass();
    out.sphere_mass.push(mass);
    out.sphere_vz
        .push(p.momentum()[2] / mass.max(f64::MIN_POSITIVE));
    row.clear();
    m.history_row(row);
    // Columns (membrane_contact's HISTORY): particle kinetic, strain,
    // potential, membrane kinetic, strain, external work, hourglass,
    // damping, total, contact nodes, normal impulse, contact dissipated.
    out.kinetic.push(row[0] + row[3]);
    out.mechanical
        .push(row[0] + row[1] + row[2] + row[3] + row[4] - row[5]);
    out.hourglass.push(row[6] + row[7]);
    out.contact.push(row[11]);
    out.total.push(row[8]);
}

/// [`ImpactRun::min_normal_clearance`] now: `min_p side (x_p − x_k)·n̂_k`, `k`
/// the node nearest to particle `p`.
fn normal_clearance(m: &MembraneContact, normals: &[V3], side: f64, min: &mut f64) {
    let sheet = &m.membranes.meshes[0];
    for x in &m.solid.run.particles.x {
        let nearest = (0..sheet.num_nodes()).min_by(|&a, &b| {
            (sheet.x[a] - x)
                .norm_squared()
                .total_cmp(&(sheet.x[b] - x).norm_squared())
        });
        if let Some(k) = nearest {
            let n = normals[k].normalize();
            *min = min.min(side * (x - sheet.x[k]).dot(&n));
        }
    }
}

/// Updates `min` with the smallest clearance of the sphere's particles
/// from the membrane node nearest each in plan.
fn clearance(
    m: &MembraneContact,
    plan: &HashMap<(i64, i64), usize>,
    lattice: &dyn Fn(f64, f64) -> (i64, i64),
    side: f64,
    min: &mut f64,
) {
    let sheet = &m.membranes.meshes[0];
    for x in &m.solid.run.particles.x {
        if let Some(&k) = plan.get(&lattice(x[0], x[1])) {
            *min = min.min(side * (sheet.x[k][2] - x[2]));
        }
    }
}
