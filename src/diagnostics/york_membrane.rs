//! York Sec. 4.3's membrane measures (dog-bone expansion, York Tables
//! III–IV, Figs. 11–13) and the runner of the dog-bone case at a given
//! element size.
//!
//! York Table II's Young's modulus lost its exponent ("1 × 10^?"). York
//! Table IV gives a final mean hoop stress of 433 at mean radius 1.36
//! (simulation 4). The reconstructed dog-bone ([`DogBone::default`]) has the
//! unstretched perimeter `L₀ = 4r(π − θ) + 4(a − r cos θ)`, θ = asin(w/r),
//! = 8.213, so the final circle of radius 1.36 is stretched by
//! `ε = 2π·1.36/L₀ − 1 = 4.0 %` and `E/(1 − ν²) = 433/ε = 1.07e4`,
//! `E = 0.98e4`: the exponent is 4 ([`DogBone::recovered_young`]). (With
//! 1e3 the final stretch would be 40 %, with 1e5 0.4 %; neither fits this
//! perimeter.) The dog-bone's area 1.923 is chosen so the initial internal
//! energy 250·A₀ = 481 matches York Table III's final p V/(γ − 1) =
//! 31.7·π·1.36²/0.4 = 460 plus the membrane's strain energy (7) within the
//! 1–3 % that York reports lost.

use std::time::Instant;

use crate::error::{Error, Result};
use crate::material::PointDensity;
use crate::membrane::inside_polygon;
use crate::scene::{build_solid_run, parse};
use crate::stepper::SolidRun;

/// Averages over a run's membrane and gas points about a centre.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct MembraneMeasures {
    /// Mean distance of the membrane points from the centre.
    pub mean_radius: f64,
    /// Distance from the centre to the membrane along +x (York Fig. 13's
    /// 0°): the farthest crossing of the membrane polygon.
    pub radius_0: f64,
    /// The same along +y (90°).
    pub radius_90: f64,
    /// Mean tangential (hoop) stress of the membrane points.
    pub mean_stress: f64,
    /// Smallest membrane point stress.
    pub min_stress: f64,
    /// Largest membrane point stress.
    pub max_stress: f64,
    /// Mean thermodynamic pressure of the gas points (EOS, q excluded;
    /// York Table III's "averaging values at material points").
    pub mean_pressure: f64,
    /// The gas's pressure as the grid feels it: `Σ p_p V_p / A` with `A`
    /// the area inside the membrane (an ideal gas's `p V = (γ − 1) m e` is
    /// its internal energy, whatever the points' own volumes).
    pub area_pressure: f64,
    /// Area inside the (closed) membrane polygon.
    pub area: f64,
    /// Σ V_p of the gas points (their volumes from continuity, York Eq.
    /// 16); the area inside the membrane if they tiled it.
    pub gas_volume: f64,
    /// Length of the membrane polygon.
    pub perimeter: f64,
}

/// The membrane points (first chain) and gas-point measures of `run`
/// about `center`.
pub fn membrane_measures(run: &SolidRun<2>, center: [f64; 2]) -> MembraneMeasures {
    let p = &run.particles;
    let Some(c) = run.membranes.chains.first() else {
        return MembraneMeasures::default();
    };
    let pts = &p.x[c.first..c.first + c.count];
    let n = pts.len() as f64;
    let rel = |x: &nalgebra::Vector2<f64>| [x[0] - center[0], x[1] - center[1]];
    let mean_radius = pts.iter().map(|x| rel(x)[0].hypot(rel(x)[1])).sum::<f64>() / n;
    let stress: Vec<f64> = (c.first..c.first + c.count)
        .map(|i| p.stress.get(i)[(0, 0)] + p.stress.get(i)[(1, 1)])
        .collect();
    // Farthest crossing of the ray from the centre along axis `a`.
    let ray = |a: usize| {
        let b = 1 - a;
        let mut best: f64 = 0.0;
        let m = pts.len();
        let last = if c.closed { m } else { m - 1 };
        for k in 0..last {
            let (u, v) = (rel(&pts[k]), rel(&pts[(k + 1) % m]));
            if (u[b] > 0.0) != (v[b] > 0.0) {
                let f = u[b] / (u[b] - v[b]);
                let r = u[a] + f * (v[a] - u[a]);
                if r > 0.0 {
                    best = best.max(r);
                }
            }
        }
        best
    };
    let mut perimeter = 0.0;
    let m = pts.len();
    let last = if c.closed { m } else { m - 1 };
    for k in 0..last {
        perimeter += (pts[(k + 1) % m] - pts[k]).norm();
    }
    let mut area = 0.0;
    if c.closed {
        for k in 0..m {
            let (u, v) = (pts[k], pts[(k + 1) % m]);
            area += 0.5 * (u[0] * v[1] - v[0] * u[1]);
        }
        area = area.abs();
    }
    let (mut psum, mut pn, mut pv, mut gas_volume) = (0.0, 0usize, 0.0, 0.0);
    for i in 0..p.len() {
        if let Some(g) = run.materials[p.material[i] as usize].gas() {
            let rho = p.mass[i] / p.vol[i];
            let e = p.work_of(i) * p.vol0[i] / p.mass[i];
            let pi = g.pressure(rho, e);
            psum += pi;
            pv += pi * p.vol[i];
            gas_volume += p.vol[i];
            pn += 1;
        }
    }
    MembraneMeasures {
        mean_radius,
        radius_0: ray(0),
        radius_90: ray(1),
        mean_stress: stress.iter().sum::<f64>() / n,
        min_stress: stress.iter().cloned().fold(f64::INFINITY, f64::min),
        max_stress: stress.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        mean_pressure: if pn > 0 { psum / pn as f64 } else { 0.0 },
        area_pressure: if area > 0.0 { pv / area } else { 0.0 },
        area,
        gas_volume,
        perimeter,
    }
}

/// Number of gas points outside every closed membrane (York Sec. 4.3's
/// first check: the gas must not escape).
pub fn gas_outside(run: &SolidRun<2>) -> usize {
    let p = &run.particles;
    let closed: Vec<_> = run.membranes.chains.iter().filter(|c| c.closed).collect();
    if closed.is_empty() {
        return 0;
    }
    (0..p.len())
        .filter(|&i| run.materials[p.material[i] as usize].gas().is_some())
        .filter(|&i| {
            !closed
                .iter()
                .any(|c| inside_polygon(&p.x[i], &p.x[c.first..c.first + c.count]))
        })
        .count()
}

/// The dog-bone expansion (York Sec. 4.3, Table II) at one element size.
#[derive(Debug, Clone)]
pub struct DogBone {
    /// Square element size (York: 0.4, 0.2, 0.1, 0.05).
    pub h: f64,
    /// Membrane point spacing as a fraction of `h`.
    pub spacing_over_h: f64,
    /// End time (York Fig. 12: 4).
    pub end: f64,
    /// Interval of the recorded history.
    pub history_interval: f64,
    /// Times of the recorded membrane snapshots (York Figs. 11–12).
    pub snapshot_times: Vec<f64>,
    /// Young's modulus of the membrane.
    pub young: f64,
    /// The gas fills the dog-bone shrunk by this fraction of `h` (lobe
    /// radius and neck half-width less the margin; York: 0, the default).
    /// With GIMP, gas points that start within a quarter cell of the
    /// membrane crossed it during the expansion (6 of 515 points at
    /// h = 0.2, 10 of 1430 at h = 0.1), and a quarter-cell margin kept them
    /// in at h = 0.2 but not at 0.1 (still 10 out), and removed gas; with
    /// the quadratic B-spline (the default [`Self::shape`]) none crosses
    /// without a margin.
    pub gas_margin_over_h: f64,
    /// The MPM shape function (`mpm.shape`; default the quadratic
    /// B-spline). With GIMP, gas points that start a few hundredths of a
    /// cell inside the membrane drift onto it and through it (6 of 515
    /// points out at h = 0.2, 10 of 1430 at h = 0.1); with the B-spline
    /// none leaves at h = 0.4 … 0.05.
    pub shape: &'static str,
    /// The PIC share of the particle velocity update (`mpm.pic_fraction`).
    pub pic_fraction: f64,
    /// Where the gas points' density comes from (`point_density`; the
    /// case's grid density; York Eq. 16 is continuity, whose points'
    /// volumes outgrow the membrane's area, see
    /// [`crate::material::PointDensity`]).
    pub point_density: PointDensity,
    /// Courant number (`time.cfl`; the case's 0.2: with the grid density at
    /// 0.3 and 0.4 the membrane creeps outwards at h = 0.1, mean radius
    /// 1.375 and 1.683 at t = 4 against 1.346 at 0.2 and 1.347 at 0.1;
    /// with continuity the inflated points' viscous limit keeps Δt far
    /// below either).
    pub cfl: f64,
}

impl Default for DogBone {
    fn default() -> Self {
        Self {
            h: 0.1,
            spacing_over_h: 0.125,
            end: 4.0,
            history_interval: 0.02,
            snapshot_times: vec![0.0, 0.1, 0.2, 0.4, 0.8, 4.0],
            young: 1.0e4,
            gas_margin_over_h: 0.0,
            shape: "quadratic_bspline",
            pic_fraction: 0.0,
            point_density: PointDensity::Grid,
            cfl: 0.2,
        }
    }
}

/// York Table II–IV numbers and the reconstructed geometry.
impl DogBone {
    /// Lobe radius r.
    pub const LOBE_RADIUS: f64 = 0.45;
    /// Lobe-centre offset a.
    pub const LOBE_OFFSET: f64 = 1.25;
    /// Neck half-width w.
    pub const NECK: f64 = 0.2;
    /// Membrane thickness (York Table IV).
    pub const THICKNESS: f64 = 0.1;
    /// Poisson's ratio (York Table II).
    pub const POISSON: f64 = 0.3;
    /// Half-width of the square domain (a multiple of every element size).
    pub const HALF_WIDTH: f64 = 2.4;

    /// The unstretched perimeter `4r(π − θ) + 4(a − r cos θ)`.
    pub fn perimeter() -> f64 {
        let (r, a, w) = (Self::LOBE_RADIUS, Self::LOBE_OFFSET, Self::NECK);
        let th = (w / r).asin();
        4.0 * r * (std::f64::consts::PI - th) + 4.0 * (a - r * th.cos())
    }

    /// Young's modulus recovered from York Table IV (hoop stress 433 at
    /// radius 1.36) with this perimeter and the plane-2D membrane modulus
    /// E/(1 − ν²): `E = 433 (1 − ν²) / (2π·1.36/L₀ − 1)`.
    pub fn recovered_young() -> f64 {
        let strain = std::f64::consts::TAU * 1.36 / Self::perimeter() - 1.0;
        433.0 * (1.0 - Self::POISSON * Self::POISSON) / strain
    }

    /// The scene (as `cases/york_dogbone.toml`, at element size `h`).
    pub fn scene(&self) -> String {
        let cells = (2.0 * Self::HALF_WIDTH / self.h).round() as usize;
        let l = Self::HALF_WIDTH;
        let shape = |margin: f64| {
            format!(
                "{{ type = \"dog_bone\", center = [0.0, 0.0], lobe_radius = {}, lobe_offset = {}, \
                 neck_half_width = {} }}",
                Self::LOBE_RADIUS - margin,
                Self::LOBE_OFFSET,
                Self::NECK - margin
            )
        };
        let (membrane, gas) = (shape(0.0), shape(self.gas_margin_over_h * self.h));
        format!(
            r#"
[grid]
dim = 2
lower = [-{l}, -{l}]
upper = [{l}, {l}]
cells = [{cells}, {cells}]
boundary = {{ x_lower = "fixed", x_upper = "fixed", y_lower = "fixed", y_upper = "fixed" }}
[time]
end = {end:e}
cfl = {cfl:e}
[mpm]
shape = "{shape}"
update = "musl"
particles_per_cell = 2
pic_fraction = {pic:e}
[[materials]]
name = "gas"
type = "fluid"
frame = "particles"
eos = "ideal_gas"
gamma = 1.4
cv = 1.0
viscosity = 0.2
artificial_viscosity = {{ g_over_dx = 1.4142135623730951, kappa = 0.75, c1 = 1.0, c2 = 1.0 }}
point_density = "{density}"
[[materials]]
name = "membrane"
type = "membrane"
density = 0.5
youngs_modulus = {e:e}
poisson_ratio = {nu}
thickness = {t}
[[objects]]
material = "membrane"
geometry = {membrane}
spacing = {s:e}
[[objects]]
material = "gas"
geometry = {gas}
density = 1.0
pressure = 100.0
"#,
            end = self.end,
            e = self.young,
            nu = Self::POISSON,
            t = Self::THICKNESS,
            s = self.spacing_over_h * self.h,
            shape = self.shape,
            pic = self.pic_fraction,
            cfl = self.cfl,
            density = self.point_density.name(),
        )
    }
}

/// One recorded time of a dog-bone run.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct DogBoneSample {
    /// Time.
    pub t: f64,
    /// Radius at 0°.
    pub radius_0: f64,
    /// Radius at 90°.
    pub radius_90: f64,
    /// Mean radius.
    pub mean_radius: f64,
    /// Kinetic energy (gas and membrane) of the points.
    pub kinetic: f64,
    /// Kinetic energy on the grid's nodes after the last step (0 at the
    /// start; [`crate::mpm::GridState::kinetic_energy`]).
    pub grid_kinetic: f64,
    /// Gas internal energy.
    pub internal: f64,
    /// Membrane strain energy.
    pub strain: f64,
    /// Area inside the membrane.
    pub area: f64,
    /// Σ V_p of the gas points ([`MembraneMeasures::gas_volume`]).
    pub gas_volume: f64,
}

/// A dog-bone run's results.
#[derive(Debug, Clone)]
pub struct DogBoneRun {
    /// Final measures.
    pub last: MembraneMeasures,
    /// Gas points outside the membrane at the end.
    pub outside_end: usize,
    /// Largest number of gas points outside at any recorded time.
    pub outside_max: usize,
    /// History.
    pub history: Vec<DogBoneSample>,
    /// Membrane point positions at the snapshot times: `(t, [[x, y]…])`.
    pub snapshots: Vec<(f64, Vec<[f64; 2]>)>,
    /// Gas point positions at the snapshot times.
    pub gas_snapshots: Vec<(f64, Vec<[f64; 2]>)>,
    /// Steps.
    pub steps: u64,
    /// Particles.
    pub particles: usize,
    /// Wall time of the stepping \[s\].
    pub wall_s: f64,
}

impl DogBoneRun {
    /// The history as CSV: `t, radius_0, radius_90, mean_radius, kinetic,
    /// grid_kinetic, internal, strain, total` (York Figs. 12–13's curves),
    /// then `area, gas_volume` (the enclosed area and the gas points'
    /// summed volume).
    pub fn history_csv(&self) -> String {
        let mut csv = String::from(
            "t,radius_0,radius_90,mean_radius,kinetic,grid_kinetic,internal,strain,total,area,gas_volume\n",
        );
        for x in &self.history {
            csv.push_str(&format!(
                "{},{},{},{},{},{},{},{},{},{},{}\n",
                x.t,
                x.radius_0,
                x.radius_90,
                x.mean_radius,
                x.kinetic,
                x.grid_kinetic,
                x.internal,
                x.strain,
                x.kinetic + x.internal + x.strain,
                x.area,
                x.gas_volume
            ));
        }
        csv
    }
}

/// Kinetic, gas internal and membrane strain energy of a run.
fn energy_split(run: &SolidRun<2>) -> (f64, f64, f64) {
    let p = &run.particles;
    let (mut internal, mut strain) = (0.0, 0.0);
    for i in 0..p.len() {
        let m = &run.materials[p.material[i] as usize];
        if m.gas().is_some() {
            internal += p.vol0[i] * p.work_of(i);
        } else {
            strain += p.vol0[i] * p.work_of(i);
        }
    }
    (p.kinetic_energy(), internal, strain)
}

/// Runs the dog-bone at `s.h`, recording the history every
/// `s.history_interval` and the snapshots.
///
/// # Errors
/// A scene or numerical error.
pub fn run_dog_bone(s: &DogBone) -> Result<DogBoneRun> {
    let scene = parse(&s.scene()).map_err(Error::Scene)?;
    let mut run = build_solid_run::<2>(&scene)?;
    let pos = |run: &SolidRun<2>, gas: bool| -> Vec<[f64; 2]> {
        (0..run.particles.len())
            .filter(|&i| {
                run.materials[run.particles.material[i] as usize]
                    .gas()
                    .is_some()
                    == gas
            })
            .map(|i| [run.particles.x[i][0], run.particles.x[i][1]])
            .collect()
    };
    let mut history = Vec::new();
    let mut snapshots = Vec::new();
    let mut gas_snapshots = Vec::new();
    let mut next_snap = 0;
    let mut next_hist = 0.0;
    let mut outside_max = 0;
    let start = Instant::now();
    loop {
        if run.t >= next_hist - 1e-12 || run.finished() {
            let m = membrane_measures(&run, [0.0, 0.0]);
            let (kinetic, internal, strain) = energy_split(&run);
            let grid_kinetic = run.grid_state().kinetic_energy();
            history.push(DogBoneSample {
                t: run.t,
                radius_0: m.radius_0,
                radius_90: m.radius_90,
                mean_radius: m.mean_radius,
                kinetic,
                grid_kinetic,
                internal,
                strain,
                area: m.area,
                gas_volume: m.gas_volume,
            });
            outside_max = outside_max.max(gas_outside(&run));
            next_hist += s.history_interval;
        }
        while next_snap < s.snapshot_times.len()
            && run.t >= s.snapshot_times[next_snap] * (1.0 - 1e-12) - 1e-12
        {
            snapshots.push((run.t, pos(&run, false)));
            gas_snapshots.push((run.t, pos(&run, true)));
            next_snap += 1;
        }
        if run.finished() {
            break;
        }
        let dt = run.next_dt();
        // Land on the history times.
        let dt = dt.min((next_hist - run.t).max(1e-12 * s.end));
        run.step_dt(dt)?;
    }
    let wall_s = start.elapsed().as_secs_f64();
    Ok(DogBoneRun {
        last: membrane_measures(&run, [0.0, 0.0]),
        outside_end: gas_outside(&run),
        outside_max,
        history,
        snapshots,
        gas_snapshots,
        steps: run.steps,
        particles: run.particles.len(),
        wall_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_recovered_exponent_is_four() {
        let e = DogBone::recovered_young();
        assert!((e.log10() - 4.0).abs() < 0.05, "E = {e}");
        assert!((DogBone::perimeter() - 8.213).abs() < 1e-3);
    }
}
