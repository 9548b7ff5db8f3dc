//! Membranes of revolution (York Sec. 3.2 in r–z, Sec. 4.4): measures of a
//! gas-filled axisymmetric membrane — the volume it encloses with the axis,
//! its mean meridional and hoop stresses, the gas pressure by point mean
//! and by `Σ p V / V_enclosed` — and the runner of York's airbag impact
//! (Tables V–VI, Figs. 14–17).

use crate::material::PointDensity;
use crate::membrane::inside_polygon;
use crate::stepper::SolidRun;
use nalgebra::Vector2;

/// Averages over one membrane of revolution and the gas points (all
/// volumes and masses per radian).
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct RevolutionMeasures {
    /// Volume per radian `∫ r dA` inside the membrane curve closed by the
    /// axis (the chain's ends joined to their projections on r = 0).
    pub volume: f64,
    /// Mass-weighted mean distance of the membrane points from `center`.
    pub mean_radius: f64,
    /// Mass-weighted mean meridional (tangential) stress `s_tt`.
    pub meridional: f64,
    /// Mass-weighted mean hoop stress `s_θθ`.
    pub hoop: f64,
    /// Number of gas points.
    pub gas_points: usize,
    /// Mean thermodynamic pressure of the gas points (EOS, q excluded).
    pub mean_pressure: f64,
    /// Sum of the gas points' volumes (per radian).
    pub gas_volume: f64,
    /// Sum of the volumes of the gas points inside the membrane.
    pub gas_volume_inside: f64,
    /// `Σ p_p V_p / volume`: the pressure an ideal gas of that internal
    /// energy (`p V = (γ − 1) m e`) has in the enclosed volume.
    pub volume_pressure: f64,
    /// Gas internal energy `Σ m e` (per radian).
    pub gas_internal: f64,
    /// Membrane strain energy `Σ V⁰ w` (per radian).
    pub membrane_strain: f64,
    /// Gas points outside the enclosed region.
    pub outside: usize,
}

/// The closed polygon of chain `chain` of `run` with the axis: its points,
/// with each open end's projection on r = 0 added when that end is off the
/// axis.
pub fn revolution_polygon(run: &SolidRun<2>, chain: usize) -> Vec<Vector2<f64>> {
    let c = run.membranes.chains[chain];
    let pts = &run.particles.x[c.first..c.first + c.count];
    let mut poly = Vec::with_capacity(pts.len() + 2);
    if !c.closed {
        poly.push(Vector2::new(0.0, pts[0][1]));
    }
    poly.extend_from_slice(pts);
    if !c.closed {
        poly.push(Vector2::new(0.0, pts[pts.len() - 1][1]));
    }
    poly
}

/// Volume per radian `∫∫ r dr dz` of the closed polygon `v` in the r–z
/// plane (Green's theorem: `(1/6) Σ (r_i z_{i+1} − r_{i+1} z_i)(r_i + r_{i+1})`),
/// positive.
pub fn volume_of_revolution(v: &[Vector2<f64>]) -> f64 {
    let n = v.len();
    let mut s = 0.0;
    for i in 0..n {
        let (a, b) = (v[i], v[(i + 1) % n]);
        s += (a[0] * b[1] - b[0] * a[1]) * (a[0] + b[0]);
    }
    (s / 6.0).abs()
}

/// [`RevolutionMeasures`] of chain `chain` of an axisymmetric run about
/// `center` (on the axis).
pub fn revolution_measures(
    run: &SolidRun<2>,
    chain: usize,
    center: [f64; 2],
) -> RevolutionMeasures {
    let p = &run.particles;
    let c = run.membranes.chains[chain];
    let poly = revolution_polygon(run, chain);
    let (mut m_sum, mut r_sum, mut s_sum, mut h_sum, mut strain) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for i in c.first..c.first + c.count {
        let m = p.mass[i];
        let d = p.x[i] - Vector2::new(center[0], center[1]);
        m_sum += m;
        r_sum += m * d.norm();
        let s = p.stress.get(i);
        s_sum += m * (s[(0, 0)] + s[(1, 1)]);
        h_sum += m * s[(2, 2)];
        strain += p.vol0[i] * p.work_of(i);
    }
    let volume = volume_of_revolution(&poly);
    let mut out = RevolutionMeasures {
        volume,
        mean_radius: r_sum / m_sum,
        meridional: s_sum / m_sum,
        hoop: h_sum / m_sum,
        membrane_strain: strain,
        ..Default::default()
    };
    let (mut psum, mut pv) = (0.0, 0.0);
    for i in 0..p.len() {
        if let Some(g) = run.materials[p.material[i] as usize].gas() {
            let rho = p.mass[i] / p.vol[i];
            let e = p.work_of(i) * p.vol0[i] / p.mass[i];
            let pi = g.pressure(rho, e);
            psum += pi;
            pv += pi * p.vol[i];
            out.gas_points += 1;
            out.gas_volume += p.vol[i];
            out.gas_internal += p.work_of(i) * p.vol0[i];
            if inside_polygon(&p.x[i], &poly) {
                out.gas_volume_inside += p.vol[i];
            } else {
                out.outside += 1;
            }
        }
    }
    if out.gas_points > 0 {
        out.mean_pressure = psum / out.gas_points as f64;
        out.volume_pressure = pv / volume;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volume_of_a_revolved_square_and_half_disc() {
        // The square [1, 2] × [0, 1] revolved: ∫ r dA = 1.5 per radian.
        let sq = [[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]].map(Vector2::from);
        assert!((volume_of_revolution(&sq) - 1.5).abs() < 1e-14);
        // A half disc of radius R on the axis: the sphere, 2R³/3 per radian.
        let n = 4000;
        let v: Vec<_> = (0..=n)
            .map(|k| {
                let a = std::f64::consts::PI * k as f64 / n as f64;
                Vector2::new(a.sin(), a.cos())
            })
            .collect();
        assert!((volume_of_revolution(&v) - 2.0 / 3.0).abs() < 1e-6);
    }
}

/// York Sec. 4.4 (Tables V–VI, Figs. 14–17): a cylindrical probe (diameter
/// 200 mm, 6.03 kg, 3.90 m/s) hits an inflated airbag, axisymmetric about
/// the probe's axis (r = x, z = y; the probe moves towards −z).
///
/// What the text does not give, and the choices made here:
/// * **Bag shape** (York Fig. 14 is not in the text): an oblate spheroid
///   of radius `a` = 357.5 mm and half-depth `c = a/2`, whose surface
///   (1.108 m²) at York's areal density 662 kg/m³ · 0.5 mm gives York's
///   total bag mass 367.2 g. Its back pole sits [`Airbag::FLOOR_GAP`] above
///   a rigid no-slip floor (the grid's lower z face: the mounting plate).
///   York reached the initial shape by a preliminary inflation with an
///   internal tether; here the unstressed spheroid with the gas at its
///   initial state is inflated with mass damping (no tether) for
///   [`Airbag::inflate_time`] and that state starts the impact.
/// * **Fabric Young's modulus** (Table VI: "6 × 10^? N/m", exponent
///   lost): 6 × 10⁸ Pa, a woven nylon 6.6 airbag fabric's in-plane modulus
///   (order 0.1–1 GPa; the fibre itself is a few GPa).
/// * **Gas pressure**: York's 4000 N/m² is `(γ − 1) ρ e₀ = 0.4 · 1.2156 ·
///   8226` — the EOS pressure of the gas points, with no air outside the
///   bag, so it acts as the gauge pressure on the fabric.
/// * **Probe**: an elastic cylinder of radius 100 mm and length 100 mm,
///   density 6.03 kg / its volume; York chose its modulus "5 × 10^?"
///   arbitrarily: 5 × 10⁸ Pa here (its wave speed stays below the
///   fabric's, so it does not shorten the step; its elastic strain under
///   the peak load is ~10⁻⁴).
#[derive(Debug, Clone)]
pub struct Airbag {
    /// Cell size \[m\].
    pub h: f64,
    /// Membrane point spacing as a fraction of `h`.
    pub spacing_over_h: f64,
    /// Fabric Young's modulus \[Pa\].
    pub young: f64,
    /// Duration of the damped preliminary inflation \[s\] (0: none).
    pub inflate_time: f64,
    /// Mass-proportional damping during the inflation [1/s].
    pub inflate_damping: f64,
    /// Duration of the impact \[s\].
    pub impact_time: f64,
    /// Interval of the recorded history \[s\].
    pub history_interval: f64,
    /// The gas fills the spheroid shrunk by this fraction of `h` (both
    /// semi-axes), at the density that keeps York's gas mass `ρ₀ V_bag`
    /// and at `e₀`. Gas points that start within a quarter cell of the
    /// membrane cross it at once (with no margin at h = 20 mm: 2 of 1005
    /// points, which then expand freely outside, one to 220 times its
    /// volume; the same happens in the dog-bone).
    pub gas_margin_over_h: f64,
    /// Shear viscosity of the air [Pa s]. York Table VI lists none; York's
    /// dog-bone (Sec. 4.3) uses μ = 0.2, the default here. Inviscid, the
    /// gas points' disordered motion grows during the impact (gas kinetic
    /// energy 0.46 J at release, 7.7 J at 80 ms with 20 mm cells and 46 J
    /// with 10 mm cells, taken from the gas's internal energy; the total
    /// stays within 1 %); μ = 0.02 slows that growth, μ = 0.2 stops it.
    /// The viscous stress this adds, μ v/ℓ ≈ 0.2 · 4 / 0.05 = 16 Pa at the
    /// probe, is 0.4 % of the bag pressure.
    pub gas_viscosity: f64,
    /// PIC share of the particle velocity update (`mpm.pic_fraction`; 0:
    /// FLIP, York's update). It damps the gas points' disordered motion
    /// that the inviscid gas grows (see `gas_viscosity`).
    pub pic_fraction: f64,
    /// Where the air points' density comes from (`point_density`; York Eq.
    /// 16's continuity, the default, or the grid's).
    pub point_density: PointDensity,
}

impl Default for Airbag {
    fn default() -> Self {
        Self {
            h: 0.01,
            spacing_over_h: 0.125,
            young: 6.0e8,
            inflate_time: 0.04,
            inflate_damping: 200.0,
            impact_time: 0.12,
            history_interval: 2.0e-4,
            gas_margin_over_h: 0.25,
            gas_viscosity: 0.2,
            pic_fraction: 0.0,
            point_density: PointDensity::Continuity,
        }
    }
}

impl Airbag {
    /// Bag radius a \[m\].
    pub const BAG_RADIUS: f64 = 0.3575;
    /// Bag half-depth c \[m\].
    pub const BAG_HALF_DEPTH: f64 = 0.17875;
    /// Gap between the floor and the bag's back pole \[m\].
    pub const FLOOR_GAP: f64 = 0.01;
    /// Fabric thickness \[m\] (York Table VI).
    pub const THICKNESS: f64 = 5.0e-4;
    /// Fabric density [kg/m³] (York Table VI).
    pub const FABRIC_DENSITY: f64 = 662.0;
    /// Fabric Poisson's ratio (York Table VI).
    pub const POISSON: f64 = 0.4;
    /// Air: γ, ρ₀ [kg/m³], e₀ [J/kg] (York Table VI).
    pub const GAMMA: f64 = 1.4;
    /// Initial air density [kg/m³].
    pub const AIR_DENSITY: f64 = 1.2156;
    /// Initial specific internal energy [J/kg].
    pub const AIR_ENERGY: f64 = 8226.0;
    /// Probe radius \[m\] (York Table V: diameter 200 mm).
    pub const PROBE_RADIUS: f64 = 0.1;
    /// Probe length \[m\] (not given; chosen).
    pub const PROBE_LENGTH: f64 = 0.1;
    /// Probe mass \[kg\] (York Table V).
    pub const PROBE_MASS: f64 = 6.03;
    /// Probe speed [m/s] (York Table V).
    pub const PROBE_SPEED: f64 = 3.90;
    /// Probe Young's modulus \[Pa\] (chosen, see above).
    pub const PROBE_YOUNG: f64 = 5.0e8;
    /// Grid extent: r ∈ [0, R_MAX], z ∈ [0, Z_MAX] \[m\].
    pub const R_MAX: f64 = 0.6;
    /// See [`Self::R_MAX`].
    pub const Z_MAX: f64 = 0.8;
    /// Where the probe waits during the inflation: its lower face \[m\].
    pub const PROBE_PARK: f64 = 0.65;

    /// Initial air pressure `(γ − 1) ρ₀ e₀` \[Pa\] (York: 4000).
    pub fn pressure0() -> f64 {
        (Self::GAMMA - 1.0) * Self::AIR_DENSITY * Self::AIR_ENERGY
    }

    /// The bag's meridian shrunk by `margin`, from the front pole on the
    /// axis to the back pole on the axis, as `n + 1` vertices.
    pub fn meridian(n: usize, margin: f64) -> Vec<[f64; 2]> {
        let zc = Self::FLOOR_GAP + Self::BAG_HALF_DEPTH;
        let (a, c) = (Self::BAG_RADIUS - margin, Self::BAG_HALF_DEPTH - margin);
        (0..=n)
            .map(|k| {
                let th = std::f64::consts::PI * k as f64 / n as f64;
                let r = if k == 0 || k == n { 0.0 } else { a * th.sin() };
                [r, zc + c * th.cos()]
            })
            .collect()
    }

    /// The scene (as `cases/york_airbag.toml` at h = 10 mm): the probe at
    /// `probe_bottom` moving at 3.9 m/s towards the bag.
    pub fn scene(&self, probe_bottom: f64) -> String {
        let cells = [
            (Self::R_MAX / self.h).round() as usize,
            (Self::Z_MAX / self.h).round() as usize,
        ];
        let list = |v: &[[f64; 2]]| {
            let s: Vec<String> = v
                .iter()
                .map(|p| format!("[{:.9}, {:.9}]", p[0], p[1]))
                .collect();
            format!("[{}]", s.join(", "))
        };
        let meridian = Self::meridian(180, 0.0);
        let margin = self.gas_margin_over_h * self.h;
        let region = Self::meridian(180, margin);
        // York's gas mass ρ₀ V_bag in the shrunk region, at e₀.
        let (a, c) = (Self::BAG_RADIUS, Self::BAG_HALF_DEPTH);
        let rho_fill = Self::AIR_DENSITY * a * a * c / ((a - margin).powi(2) * (c - margin));
        let p_fill = (Self::GAMMA - 1.0) * rho_fill * Self::AIR_ENERGY;
        let probe_volume = std::f64::consts::PI * Self::PROBE_RADIUS.powi(2) * Self::PROBE_LENGTH;
        format!(
            r#"description = "York Sec. 4.4 airbag impact (axisymmetric), cell size {h} m"

[grid]
dim = 2
axisymmetric = true
lower = [0.0, 0.0]
upper = [{rmax}, {zmax}]
cells = [{nr}, {nz}]
boundary = {{ x_lower = "symmetry", x_upper = "fixed", y_lower = "fixed", y_upper = "fixed" }}

[time]
end = {end}
cfl = 0.4
mode = "explicit"

[mpm]
shape = "gimp"
update = "musl"
particles_per_cell = 2
pic_fraction = {pic}

[[materials]]
name = "air"
type = "fluid"
frame = "particles"
eos = "ideal_gas"
gamma = {gamma}
cv = 718.0
viscosity = {mu:e}
artificial_viscosity = {{ g_over_dx = 1.4142135623730951, kappa = 0.75, c1 = 1.0, c2 = 1.0 }}
point_density = "{density}"

[[materials]]
name = "fabric"
type = "membrane"
density = {rho_f}
youngs_modulus = {young:e}
poisson_ratio = {nu}
thickness = {t:e}

[[materials]]
name = "probe"
type = "solid"
model = "linear_elastic"
density = {rho_p}
youngs_modulus = {e_p:e}
poisson_ratio = 0.3

[[objects]]
material = "fabric"
geometry = {{ type = "polyline", vertices = {meridian} }}
spacing = {spacing:e}

[[objects]]
material = "air"
geometry = {{ type = "polyline", closed = true, vertices = {region} }}
density = {rho_a}
pressure = {p0}

[[objects]]
material = "probe"
geometry = {{ type = "box", lower = [0.0, {pz0}], upper = [{pr}, {pz1}] }}
velocity = [0.0, -{v}]

[output]
interval = 0.005
formats = ["csv"]
"#,
            h = self.h,
            rmax = Self::R_MAX,
            zmax = Self::Z_MAX,
            nr = cells[0],
            nz = cells[1],
            end = self.impact_time,
            gamma = Self::GAMMA,
            mu = self.gas_viscosity,
            pic = self.pic_fraction,
            density = self.point_density.name(),
            rho_f = Self::FABRIC_DENSITY,
            young = self.young,
            nu = Self::POISSON,
            t = Self::THICKNESS,
            rho_p = Self::PROBE_MASS / probe_volume,
            e_p = Self::PROBE_YOUNG,
            meridian = list(&meridian),
            spacing = self.spacing_over_h * self.h,
            region = list(&region),
            rho_a = rho_fill,
            p0 = p_fill,
            pz0 = probe_bottom,
            pr = Self::PROBE_RADIUS,
            pz1 = probe_bottom + Self::PROBE_LENGTH,
            v = Self::PROBE_SPEED,
        )
    }
}

/// One recorded time of the airbag impact (energies of the whole body, J;
/// volumes m³: the per-radian values times 2π).
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct AirbagSample {
    /// Time since the probe's release \[s\].
    pub t: f64,
    /// Probe displacement into the bag (mean z at release − mean z) \[m\].
    pub penetration: f64,
    /// Probe velocity along z (mass-weighted mean; < 0 towards the bag).
    pub probe_velocity: f64,
    /// Mean gas point pressure \[Pa\].
    pub mean_pressure: f64,
    /// `Σ p V / V_enclosed` \[Pa\].
    pub volume_pressure: f64,
    /// Enclosed volume \[m³\].
    pub volume: f64,
    /// Sum of the gas points' volumes \[m³\].
    pub gas_volume: f64,
    /// Sum of the volumes of the gas points inside the bag \[m³\].
    pub gas_volume_inside: f64,
    /// `p V^γ` with the point-mean pressure, relative to its value at
    /// release.
    pub adiabat_mean: f64,
    /// `p V^γ` with the `p V` pressure, relative to its value at release.
    pub adiabat_volume: f64,
    /// Probe kinetic energy.
    pub probe_kinetic: f64,
    /// Probe strain energy.
    pub probe_strain: f64,
    /// Gas kinetic energy.
    pub gas_kinetic: f64,
    /// Gas internal energy.
    pub gas_internal: f64,
    /// Membrane kinetic energy.
    pub membrane_kinetic: f64,
    /// Membrane strain energy.
    pub membrane_strain: f64,
    /// Total energy.
    pub total: f64,
    /// Gas points outside the bag.
    pub outside: usize,
}

/// An airbag run's results.
#[derive(Debug, Clone)]
pub struct AirbagRun {
    /// State at the end of the inflation (t = 0 of the impact).
    pub inflated: AirbagSample,
    /// Impact history.
    pub history: Vec<AirbagSample>,
    /// Largest penetration \[m\] and its time \[s\].
    pub peak_penetration: (f64, f64),
    /// Largest probe velocity away from the bag after the peak [m/s]
    /// (the rebound velocity once the probe has left the bag).
    pub rebound_velocity: f64,
    /// Probe velocity at the end [m/s].
    pub end_velocity: f64,
    /// Largest mean gas point pressure \[Pa\] and largest `p V` pressure.
    pub peak_pressure: (f64, f64),
    /// Largest |p V^γ / (p V^γ)₀ − 1| (point-mean, p V pressures).
    pub adiabat_drift: (f64, f64),
    /// Largest |E(t) − E(0)| / (the probe's initial kinetic energy).
    pub energy_error: f64,
    /// Membrane mass \[kg\] (whole bag).
    pub bag_mass: f64,
    /// Probe mass \[kg\].
    pub probe_mass: f64,
    /// Membrane points at release, at the peak and at the end: `(t,
    /// [[r, z]…])`.
    pub shapes: Vec<(f64, Vec<[f64; 2]>)>,
    /// The probe's lower face at release \[m\] (at time t it is this less
    /// the penetration).
    pub probe_bottom0: f64,
    /// Particles.
    pub particles: usize,
    /// Steps (inflation and impact).
    pub steps: u64,
    /// Wall time \[s\].
    pub wall_s: f64,
}

impl AirbagRun {
    /// The history as CSV (one header line).
    pub fn history_csv(&self) -> String {
        let mut s = String::from(
            "t,penetration,probe_velocity,mean_pressure,volume_pressure,volume,gas_volume,\
             gas_volume_inside,adiabat_mean,adiabat_volume,probe_kinetic,probe_strain,gas_kinetic,gas_internal,\
             membrane_kinetic,membrane_strain,total,outside\n",
        );
        for r in &self.history {
            s.push_str(&format!(
                "{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.8e},{:.8e},{:.6e},{:.6e},\
                 {:.6e},{:.6e},{:.6e},{:.6e},{:.8e},{}\n",
                r.t,
                r.penetration,
                r.probe_velocity,
                r.mean_pressure,
                r.volume_pressure,
                r.volume,
                r.gas_volume,
                r.gas_volume_inside,
                r.adiabat_mean,
                r.adiabat_volume,
                r.probe_kinetic,
                r.probe_strain,
                r.gas_kinetic,
                r.gas_internal,
                r.membrane_kinetic,
                r.membrane_strain,
                r.total,
                r.outside
            ));
        }
        s
    }
}

/// Kinetic and strain energy (per radian) of the particles of material
/// `m`, and its mass-weighted mean velocity and position along z.
fn material_totals(run: &SolidRun<2>, m: usize) -> (f64, f64, f64, f64, f64) {
    let p = &run.particles;
    let (mut ke, mut se, mut mass, mut mv, mut mz) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for i in (0..p.len()).filter(|&i| p.material[i] as usize == m) {
        ke += 0.5 * p.mass[i] * p.v[i].norm_squared();
        se += p.vol0[i] * run.materials[m].strain_energy_density(&p.f.get(i), p.work_of(i));
        mass += p.mass[i];
        mv += p.mass[i] * p.v[i][1];
        mz += p.mass[i] * p.x[i][1];
    }
    (
        ke,
        se,
        mass,
        mv / mass.max(f64::MIN_POSITIVE),
        mz / mass.max(f64::MIN_POSITIVE),
    )
}

/// Runs the airbag case: the damped inflation with the probe parked above
/// the bag, then the probe moved to one cell above the bag's front and
/// released at 3.9 m/s.
///
/// # Errors
/// A scene or numerical error.
pub fn run_airbag(cfg: &Airbag) -> crate::error::Result<AirbagRun> {
    use crate::error::Error;
    let start = std::time::Instant::now();
    let tau = std::f64::consts::TAU;
    let scene = crate::scene::parse(&cfg.scene(Airbag::PROBE_PARK))?;
    let mut run = crate::scene::build_solid_run::<2>(&scene)?;
    let mat = |name: &str| {
        run.materials
            .iter()
            .position(|m| m.name == name)
            .unwrap_or(0)
    };
    let (air, fabric, probe) = (mat("air"), mat("fabric"), mat("probe"));
    let probe_pts: Vec<usize> = (0..run.particles.len())
        .filter(|&i| run.particles.material[i] as usize == probe)
        .collect();
    let v0: Vec<_> = probe_pts.iter().map(|&i| run.particles.v[i]).collect();
    // Inflation: the probe parked at rest, mass damping on.
    for &i in &probe_pts {
        run.particles.v[i] = Vector2::zeros();
    }
    run.params.damping = cfg.inflate_damping;
    run.time.end = cfg.inflate_time;
    // A numerical failure names the particle's material too.
    let named = |run: &SolidRun<2>, e| {
        crate::driver::models::arrays::name_particle_material(e, &run.particles, &run.materials)
    };
    while !run.finished() {
        run.step().map_err(|e| named(&run, e))?;
    }
    let steps_inflate = run.steps;
    // Release: the probe one cell above the bag's front.
    let c = run.membranes.chains[0];
    let front = (c.first..c.first + c.count)
        .map(|i| run.particles.x[i][1])
        .fold(f64::NEG_INFINITY, f64::max);
    let bottom = probe_pts
        .iter()
        .map(|&i| run.particles.x[i][1])
        .fold(f64::INFINITY, f64::min)
        - 0.25 * cfg.h;
    let shift = front + cfg.h - bottom;
    for (k, &i) in probe_pts.iter().enumerate() {
        run.particles.x[i][1] += shift;
        run.particles.x0[i][1] += shift;
        run.particles.v[i] = v0[k];
    }
    run.params.damping = 0.0;
    let t0 = run.t;
    run.time.end = t0 + cfg.impact_time;
    let sample = |run: &SolidRun<2>, z0: f64, ref_mean: f64, ref_vol: f64| {
        let m = revolution_measures(run, 0, [0.0, 0.0]);
        let (pk, ps, _, pv, pz) = material_totals(run, probe);
        let (gk, gi, ..) = material_totals(run, air);
        let (mk, ms, ..) = material_totals(run, fabric);
        let vol = tau * m.volume;
        let g = Airbag::GAMMA;
        AirbagSample {
            t: run.t - t0,
            penetration: z0 - pz,
            probe_velocity: pv,
            mean_pressure: m.mean_pressure,
            volume_pressure: m.volume_pressure,
            volume: vol,
            gas_volume: tau * m.gas_volume,
            gas_volume_inside: tau * m.gas_volume_inside,
            adiabat_mean: m.mean_pressure * vol.powf(g) / ref_mean,
            adiabat_volume: m.volume_pressure * vol.powf(g) / ref_vol,
            probe_kinetic: tau * pk,
            probe_strain: tau * ps,
            gas_kinetic: tau * gk,
            gas_internal: tau * gi,
            membrane_kinetic: tau * mk,
            membrane_strain: tau * ms,
            total: tau * (pk + ps + gk + gi + mk + ms),
            outside: m.outside,
        }
    };
    let z0 = material_totals(&run, probe).4;
    let first = sample(&run, z0, 1.0, 1.0);
    let (ref_mean, ref_vol) = (
        first.mean_pressure * first.volume.powf(Airbag::GAMMA),
        first.volume_pressure * first.volume.powf(Airbag::GAMMA),
    );
    let inflated = sample(&run, z0, ref_mean, ref_vol);
    let membrane_xy = |run: &SolidRun<2>| -> Vec<[f64; 2]> {
        (c.first..c.first + c.count)
            .map(|i| [run.particles.x[i][0], run.particles.x[i][1]])
            .collect()
    };
    let mut shapes = vec![(0.0, membrane_xy(&run))];
    let mut history = vec![inflated];
    let mut next = cfg.history_interval;
    let mut peak_shape = (0.0, Vec::new());
    let mut peak = f64::NEG_INFINITY;
    while !run.finished() {
        run.step().map_err(|e| named(&run, e))?;
        if run.t - t0 >= next * (1.0 - 1e-9) || run.finished() {
            let s = sample(&run, z0, ref_mean, ref_vol);
            if s.penetration > peak {
                peak = s.penetration;
                peak_shape = (s.t, membrane_xy(&run));
            }
            history.push(s);
            next += cfg.history_interval;
        }
    }
    shapes.push(peak_shape);
    shapes.push((run.t - t0, membrane_xy(&run)));
    let e0 = inflated.total;
    let ke0 = inflated.probe_kinetic;
    let mut out = AirbagRun {
        inflated,
        peak_penetration: (0.0, 0.0),
        rebound_velocity: 0.0,
        end_velocity: history.last().map_or(0.0, |s| s.probe_velocity),
        peak_pressure: (0.0, 0.0),
        adiabat_drift: (0.0, 0.0),
        energy_error: 0.0,
        bag_mass: tau * material_totals(&run, fabric).2,
        probe_mass: tau * material_totals(&run, probe).2,
        shapes,
        probe_bottom0: front + cfg.h,
        particles: run.particles.len(),
        steps: run.steps,
        wall_s: 0.0,
        history,
    };
    for s in &out.history {
        if s.penetration > out.peak_penetration.0 {
            out.peak_penetration = (s.penetration, s.t);
        }
        out.rebound_velocity = out.rebound_velocity.max(s.probe_velocity);
        out.peak_pressure.0 = out.peak_pressure.0.max(s.mean_pressure);
        out.peak_pressure.1 = out.peak_pressure.1.max(s.volume_pressure);
        out.adiabat_drift.0 = out.adiabat_drift.0.max((s.adiabat_mean - 1.0).abs());
        out.adiabat_drift.1 = out.adiabat_drift.1.max((s.adiabat_volume - 1.0).abs());
        out.energy_error = out.energy_error.max((s.total - e0).abs() / ke0);
    }
    if !out.history.iter().all(|s| s.total.is_finite()) {
        return Err(Error::Watchdog {
            step: run.steps,
            time: run.t,
            what: format!(
                "airbag run at h = {}: non-finite energy (inflation took {steps_inflate} steps)",
                cfg.h
            ),
        });
    }
    out.wall_s = start.elapsed().as_secs_f64();
    Ok(out)
}
