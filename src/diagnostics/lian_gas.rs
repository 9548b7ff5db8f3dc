//! Lian, Liu, Zhang Sec. 7.3 (Table 2, Figs. 14–18): a gas block expanding
//! inside a membrane of finite elements, joined by the grid contact. The
//! quarter model in 3D (plane strain between two symmetry planes z = 0 and
//! z = depth), at any element, cell and particle size; the radii at 0° and
//! 90°, the mean radius, the energy history and the count of gas points
//! outside the membrane.

use std::path::Path;
use std::time::Instant;

use crate::contact::{ContactDetection, ContactLaw};
use crate::driver::model::{DtRequest, Model};
use crate::driver::models::MembraneContact;
use crate::error::Error;
use crate::scene::parse;

/// The case's sizes (the paper: element and cell 0.1, spacing 0.025).
#[derive(Debug, Clone, Copy)]
pub struct GasExpansion {
    /// Membrane element side.
    pub element: f64,
    /// Grid cell side.
    pub cell: f64,
    /// Particles per cell and direction (cell / spacing).
    pub per_cell: usize,
    /// End time.
    pub end: f64,
    /// History interval.
    pub every: f64,
    /// The contact law between gas and membrane.
    pub law: ContactLaw,
    /// Where the contact force may act (Lian's approach rule or the gap
    /// check).
    pub detection: ContactDetection,
    /// PIC share of the gas points' velocity update (`mpm.pic_fraction`;
    /// 0: FLIP).
    pub pic_fraction: f64,
}

/// What a run gives.
#[derive(Debug, Clone, Default)]
pub struct GasExpansionRun {
    /// Sample times.
    pub t: Vec<f64>,
    /// Radius of the membrane at 0° (its node on y = 0).
    pub r0: Vec<f64>,
    /// Radius at 90° (its node on x = 0).
    pub r90: Vec<f64>,
    /// Mean distance of the membrane's nodes from the axis.
    pub r_mean: Vec<f64>,
    /// Smallest and largest distance of its nodes from the axis.
    pub r_range: Vec<(f64, f64)>,
    /// The membrane's tension T = s_tt t along its outline, the mean over
    /// its elements (plane strain through the depth: s_tt = (σ̂xx + σ̂yy) /
    /// (1 + ν)); at rest Laplace's law makes it p r.
    pub tension: Vec<f64>,
    /// The gas's median pressure over its points (−tr σ / 3; the median,
    /// not the mean, because a layer of points at the membrane ends up
    /// hotter than the rest: at h = 0.1, t = 2, β = 0.01 the bulk is at
    /// 6.31 ± 0.1 and that layer reaches 13.9).
    pub gas_pressure: Vec<f64>,
    /// Total energy (gas kinetic and internal, membrane kinetic and
    /// strain, with the hourglass losses; the contact's loss left out).
    pub energy: Vec<f64>,
    /// Energy the contact dissipated so far (the history's
    /// `contact_dissipated`): `energy + contact_loss` is the account.
    pub contact_loss: Vec<f64>,
    /// Gas kinetic energy Σ_p ½ m_p |v_p|² (of its points).
    pub gas_kinetic: Vec<f64>,
    /// The part of it the grid sees: Σ_i ½ m_i |v_i|² over the nodes after
    /// the last step (0 at the start). FLIP points can carry
    /// velocities the grid does not see (the null space of the
    /// grid-to-particle map).
    pub grid_kinetic: Vec<f64>,
    /// Gas points outside the membrane at the end.
    pub escaped: usize,
    /// Steps taken.
    pub steps: u64,
    /// Wall time \[s\].
    pub wall_s: f64,
}

/// The membrane's quarter, `(0.5, 0) → (0.5, 1) → (0, 1)`, extruded over
/// z ∈ [0, depth] with one element through the depth, in the mesh file
/// format of [`crate::membrane::quad_mesh`] (normals outward).
pub fn quarter_mesh(element: f64, depth: f64) -> String {
    let (n1, n2) = (
        (1.0 / element).round() as usize,
        (0.5 / element).round() as usize,
    );
    let mut pts: Vec<(f64, f64)> = (0..=n1).map(|i| (0.5, i as f64 / n1 as f64)).collect();
    pts.extend((1..=n2).map(|i| (0.5 - 0.5 * i as f64 / n2 as f64, 1.0)));
    let n = pts.len();
    let mut s = String::from("# Lian Sec. 7.3 quarter membrane\n");
    for (k, (x, y)) in pts.iter().enumerate() {
        s += &format!("node {k} {x} {y} 0\nnode {} {x} {y} {depth}\n", n + k);
    }
    for k in 0..n - 1 {
        s += &format!("quad {k} {k} {} {} {}\n", k + 1, n + k + 1, n + k);
    }
    s
}

impl GasExpansion {
    /// The paper's sizes, to `end`.
    pub fn paper(end: f64) -> Self {
        Self {
            element: 0.1,
            cell: 0.1,
            per_cell: 4,
            end,
            every: 0.01,
            law: ContactLaw::Stick,
            detection: ContactDetection::Approach,
            pic_fraction: 0.0,
        }
    }

    /// The scene text, with the mesh file at `mesh`.
    pub fn scene(&self, mesh: &Path) -> String {
        let depth = self.cell;
        let n = (1.6 / self.cell).round() as usize;
        let upper = n as f64 * self.cell;
        format!(
            r#"
[grid]
dim = 3
lower = [0.0, 0.0, 0.0]
upper = [{upper}, {upper}, {depth}]
cells = [{n}, {n}, 1]
boundary = {{ x_lower = "symmetry", y_lower = "symmetry", z_lower = "symmetry", z_upper = "symmetry", x_upper = "fixed", y_upper = "fixed" }}
[time]
end = {end}
cfl = 0.4
[mpm]
shape = "gimp"
update = "usl"
particles_per_cell = {ppc}
pic_fraction = {pic}
[[materials]]
name = "gas"
type = "fluid"
frame = "particles"
eos = "ideal_gas"
gamma = 1.4
cv = 1.0
viscosity = 0.1
[[objects]]
material = "gas"
geometry = {{ type = "box", lower = [0.0, 0.0, 0.0], upper = [0.45, 0.95, {depth}] }}
density = 1.0
pressure = 10.0
[[membrane_elements]]
name = "membrane"
mesh = {{ file = "{mesh}" }}
thickness = 0.1
density = 0.5
young = 1e6
poisson = 0.3
fix = [
  {{ box = {{ lower = [-1.0, -1.0, -1.0], upper = [2.0, 2.0, 2.0] }}, dofs = ["z"] }},
  {{ box = {{ lower = [0.49, -0.001, -1.0], upper = [0.51, 0.001, 1.0] }}, dofs = ["y"] }},
  {{ box = {{ lower = [-0.001, 0.99, -1.0], upper = [0.001, 1.01, 1.0] }}, dofs = ["x"] }},
]
[contact]
law = "{law}"
detection = "{detection}"
"#,
            end = self.end,
            ppc = self.per_cell,
            pic = self.pic_fraction,
            mesh = mesh.display(),
            law = match self.law {
                ContactLaw::Stick => "stick",
                ContactLaw::Slip { .. } => "slip",
            },
            detection = match self.detection {
                ContactDetection::Approach => "approach",
                ContactDetection::Gap => "gap",
            },
        )
    }

    /// Runs the case, writing its mesh file into `dir`.
    ///
    /// # Errors
    /// A scene that does not build (named), a numerical failure (named).
    pub fn run(&self, dir: &Path) -> Result<GasExpansionRun, Error> {
        let mesh = dir.join(format!("lian_gas_quarter_{}.mesh", self.element));
        std::fs::write(&mesh, quarter_mesh(self.element, self.cell))
            .map_err(|e| Error::io(&mesh, e))?;
        let scene = parse(&self.scene(&mesh))?;
        // The scene text carries `self.law` and `self.detection`.
        let mut m = MembraneContact::from_scene(&scene)?;
        let start = Instant::now();
        let mut out = GasExpansionRun::default();
        let mut row = Vec::new();
        let mut next = 0.0;
        loop {
            if m.time() >= next - 1e-12 {
                sample(&m, &mut out, &mut row);
                next += self.every;
            }
            if m.time() >= self.end * (1.0 - 1e-12) {
                break;
            }
            let stats = m.step(DtRequest {
                value: (self.end - m.time()).min(next - m.time()).max(1e-300),
                exact: false,
            });
            stats.map_err(|e| m.annotate(e))?;
        }
        out.escaped = escaped(&m);
        out.steps = m.steps();
        out.wall_s = start.elapsed().as_secs_f64();
        Ok(out)
    }
}

/// The membrane's outline: its nodes on z = 0, in order.
fn outline(m: &MembraneContact) -> Vec<(f64, f64)> {
    let sheet = &m.membranes.meshes[0];
    sheet
        .x
        .iter()
        .filter(|x| x[2].abs() < 1e-9)
        .map(|x| (x[0], x[1]))
        .collect()
}

fn sample(m: &MembraneContact, out: &mut GasExpansionRun, row: &mut Vec<f64>) {
    let line = outline(m);
    let r = |p: &(f64, f64)| p.0.hypot(p.1);
    out.t.push(m.time());
    out.r0.push(line.first().map_or(0.0, r));
    out.r90.push(line.last().map_or(0.0, r));
    out.r_mean
        .push(line.iter().map(r).sum::<f64>() / line.len().max(1) as f64);
    out.r_range.push(
        line.iter()
            .map(r)
            .fold((f64::INFINITY, 0.0), |(a, b), v| (a.min(v), b.max(v))),
    );
    let sheet = &m.membranes.meshes[0];
    let nu = sheet.material.poisson;
    out.tension.push(
        sheet
            .stress
            .iter()
            .zip(&sheet.thickness)
            .map(|(s, t)| (s[0] + s[1]) / (1.0 + nu) * t)
            .sum::<f64>()
            / sheet.stress.len().max(1) as f64,
    );
    let p = &m.solid.run.particles;
    let mut pressures: Vec<f64> = (0..p.len())
        .map(|i| -p.stress.get(i).trace() / 3.0)
        .collect();
    let mid = pressures.len() / 2;
    out.gas_pressure.push(if pressures.is_empty() {
        0.0
    } else {
        *pressures.select_nth_unstable_by(mid, f64::total_cmp).1
    });
    row.clear();
    m.history_row(row);
    // Columns: particle kinetic, strain, potential, membrane kinetic,
    // strain, external work, hourglass, damping, total (with the contact's
    // loss), contact nodes, normal impulse, contact dissipated.
    out.gas_kinetic.push(row[0]);
    out.grid_kinetic
        .push(m.solid.run.grid_state().kinetic_energy());
    out.energy.push(row[8] - row[11]);
    out.contact_loss.push(row[11]);
}

/// Gas points outside the membrane's outline (closed through the origin),
/// by the even–odd rule in the x–y plane.
fn escaped(m: &MembraneContact) -> usize {
    let mut poly = outline(m);
    poly.push((0.0, 0.0));
    let inside = |x: f64, y: f64| {
        let mut c = false;
        let n = poly.len();
        for i in 0..n {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            if (a.1 > y) != (b.1 > y) && x < a.0 + (y - a.1) / (b.1 - a.1) * (b.0 - a.0) {
                c = !c;
            }
        }
        c
    };
    m.solid
        .run
        .particles
        .x
        .iter()
        .filter(|p| !inside(p[0].max(1e-12), p[1].max(1e-12)))
        .count()
}
