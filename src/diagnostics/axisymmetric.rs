//! Axisymmetric (r–z) explicit MPM against exact solutions: Lamé's thick
//! cylinder (plane strain, a strip in z) and thick sphere (a quarter annulus
//! in the r–z plane) under internal pressure, driven to the quasistatic state
//! by mass-proportional damping (shared by `tests/axisymmetric.rs` and the
//! `axisym_lame` study).
//!
//! Everything is per radian: a particle's volume is V_p = ∫ r dA over its
//! piece of the meridian plane and its mass ρ V_p. The inner pressure is a
//! surface load on the particles of the first layer, applied as a body force
//! (the explicit solid path has no traction facility; compare
//! `diagnostics::impm`'s band load) with the axisymmetric surface measure:
//! per radian, a cylinder particle of axial extent Δz carries P rᵢ Δz, a
//! sphere particle of polar extent [φ₀, φ₁] (φ from the z axis) carries
//! P rᵢ² ∫ (sin²φ, sinφ cosφ) dφ in (r, z) — the exact traction integral of
//! its patch of the inner surface.
//!
//! The layouts conform to the surfaces: the cylinder on a square lattice in
//! (r, z) with rᵢ and r_o on lattice lines; the sphere on a polar lattice in
//! the meridian plane (layers of equal ΔR, each split into equal Δφ of about
//! the same arc length), with exact per-radian volumes.

use std::time::Instant;

use nalgebra::{Matrix2, SVector};

use crate::error::Result;
use crate::grid::{Boundary, Grid};
use crate::material::{ElasticConstants, SolidMaterial, SolidModel};
use crate::mpm::{BodyForce, ExplicitParams, Particles, UpdateScheme};
use crate::shape::ShapeKind;
use crate::stepper::{SolidRun, TimeControl};

/// Which Lamé problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LameShape {
    /// A long thick-walled cylinder (plane strain ε_zz = 0): a strip
    /// rᵢ ≤ r ≤ r_o two cells high with symmetry faces at both ends in z.
    Cylinder,
    /// A thick-walled sphere: the quarter annulus rᵢ ≤ |(r, z)| ≤ r_o, z ≥ 0
    /// of the meridian plane (axis r = 0 and the plane z = 0 symmetry faces).
    Sphere,
}

impl LameShape {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            LameShape::Cylinder => "cylinder",
            LameShape::Sphere => "sphere",
        }
    }
}

/// An internally pressurised thick cylinder or sphere, small strain.
#[derive(Debug, Clone, Copy)]
pub struct Lame {
    /// Cylinder or sphere.
    pub shape: LameShape,
    /// Inner radius rᵢ.
    pub r_inner: f64,
    /// Outer radius r_o.
    pub r_outer: f64,
    /// Young's modulus E.
    pub young: f64,
    /// Poisson's ratio ν.
    pub poisson: f64,
    /// Density ρ.
    pub rho: f64,
    /// Internal pressure P (small against E: the comparison is with linear
    /// elasticity, whose difference from the finite-strain models is O(P/E)).
    pub pressure: f64,
    /// Constitutive model of the wall.
    pub model: SolidModel,
}

/// Exact values at one radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LameExact {
    /// Radial stress σ_r.
    pub sigma_r: f64,
    /// Hoop (circumferential) stress σ_θ.
    pub sigma_theta: f64,
    /// Radial displacement u_r.
    pub u_r: f64,
}

/// Relaxation parameters of an explicit run to the quasistatic state.
#[derive(Debug, Clone, Copy)]
pub struct Relax {
    /// Shape function.
    pub shape: ShapeKind,
    /// Stress update ordering.
    pub scheme: UpdateScheme,
    /// Courant number.
    pub cfl: f64,
    /// Mass-proportional damping α [1/s].
    pub damping: f64,
    /// The load rises as ½(1 − cos(π t/T)) over this time T.
    pub ramp: f64,
    /// End time.
    pub end: f64,
}

impl Default for Relax {
    /// GIMP, USL, CFL 0.4, α = 3, T = 3, end 20 (nondimensional E = ρ = 1,
    /// r_o = 1). Measured: the cylinder's kinetic energy is below 1e-12 of
    /// its strain energy at t = 20; the sphere's particle kinetic energy
    /// stays near 1e-5 of it (not investigated; most likely particle
    /// velocity noise that FLIP keeps and the damped grid does not carry),
    /// and running the sphere (8 cells across) to t = 40 changes its errors
    /// in the fourth digit only.
    fn default() -> Self {
        Self {
            shape: ShapeKind::Gimp,
            scheme: UpdateScheme::Usl,
            cfl: 0.4,
            damping: 3.0,
            ramp: 3.0,
            end: 20.0,
        }
    }
}

/// Errors of a quasistatic run against Lamé.
#[derive(Debug, Clone, Copy)]
pub struct LameMeasured {
    /// Cell size h.
    pub h: f64,
    /// Relative L2 error of σ_r: √(Σ V⁰ (σ_r − exact)² / Σ V⁰ exact²) over
    /// the particles (V⁰ per radian, i.e. the body's volume measure).
    pub sigma_r: f64,
    /// Relative L2 error of the hoop stress σ_θθ (`stress[(2,2)]`).
    pub sigma_theta: f64,
    /// Relative L2 error of the radial displacement.
    pub u_r: f64,
    /// Sphere: relative L2 error of the meridional stress σ_φφ (equal to σ_θ
    /// in the exact solution); cylinder: of the axial stress σ_zz against
    /// ν(σ_r + σ_θ) (plane strain).
    pub sigma_third: f64,
    /// [`Self::sigma_r`] over the particles beyond the first cell of the
    /// wall (reference radius ≥ rᵢ + h, i.e. all but the two particle layers
    /// next to the loaded surface): the load, a body force on the first
    /// layer, leaves an O(1) stress error in a layer of width O(h), which
    /// caps the whole-body L2 stress order near ½; beyond it the stress
    /// converges at first order.
    pub sigma_r_interior: f64,
    /// [`Self::sigma_theta`] beyond the first cell.
    pub sigma_theta_interior: f64,
    /// Kinetic energy per radian at the end over the strain energy (how far
    /// from quasistatic).
    pub kinetic_ratio: f64,
    /// Steps taken.
    pub steps: u64,
    /// Particles.
    pub particles: usize,
    /// Wall time of the stepping \[s\].
    pub wall_s: f64,
}

impl Lame {
    /// The nondimensional problem of the study: rᵢ = 0.5, r_o = 1, E = 1,
    /// ν = 0.3, ρ = 1, P = 10⁻⁵ (so O(P/E) finite-strain effects stay far
    /// below the discretisation error), hypo-elastic Jaumann model (York
    /// Eqs. 18–20).
    pub fn standard(shape: LameShape) -> Self {
        Self {
            shape,
            r_inner: 0.5,
            r_outer: 1.0,
            young: 1.0,
            poisson: 0.3,
            rho: 1.0,
            pressure: 1e-5,
            model: SolidModel::LinearElastic,
        }
    }

    /// Exact radial and hoop stress and radial displacement at radius `r`
    /// (cylinder: plane strain; sphere: spherical radius).
    ///
    /// Cylinder: σ_r = A − B/r², σ_θ = A + B/r², A = P rᵢ²/(r_o² − rᵢ²),
    /// B = A r_o², u_r = (1+ν)/E ((1 − 2ν) A r + B/r).
    /// Sphere: σ_r = A − 2B/r³, σ_θ = A + B/r³, A = P rᵢ³/(r_o³ − rᵢ³),
    /// B = A r_o³/2, u_r = ((1 − 2ν) A r + (1 + ν) B/r²)/E.
    pub fn exact(&self, r: f64) -> LameExact {
        let (ri, ro, p) = (self.r_inner, self.r_outer, self.pressure);
        let (e, nu) = (self.young, self.poisson);
        match self.shape {
            LameShape::Cylinder => {
                let a = p * ri * ri / (ro * ro - ri * ri);
                let b = a * ro * ro;
                LameExact {
                    sigma_r: a - b / (r * r),
                    sigma_theta: a + b / (r * r),
                    u_r: (1.0 + nu) / e * ((1.0 - 2.0 * nu) * a * r + b / r),
                }
            }
            LameShape::Sphere => {
                let a = p * ri.powi(3) / (ro.powi(3) - ri.powi(3));
                let b = 0.5 * a * ro.powi(3);
                LameExact {
                    sigma_r: a - 2.0 * b / r.powi(3),
                    sigma_theta: a + b / r.powi(3),
                    u_r: ((1.0 - 2.0 * nu) * a * r + (1.0 + nu) * b / (r * r)) / e,
                }
            }
        }
    }

    fn material(&self) -> SolidMaterial {
        SolidMaterial {
            name: "wall".into(),
            density: self.rho,
            model: self.model,
            elastic: ElasticConstants::from_young_poisson(self.young, self.poisson),
        }
    }

    /// Cell size with `n` cells across the wall.
    pub fn cell_size(&self, n: usize) -> f64 {
        (self.r_outer - self.r_inner) / n as f64
    }

    /// Number of polar cells of sphere layer `k` at particle spacing `s`.
    fn sphere_layer_count(&self, s: f64, k: usize) -> usize {
        let rc = self.r_inner + (k as f64 + 0.5) * s;
        ((0.5 * std::f64::consts::PI * rc / s).round() as usize).max(1)
    }

    /// Sphere particle (layer `k`, polar index `j`) at spacing `s`:
    /// position, volume per radian (R₁³ − R₀³)/3 (cos φ₀ − cos φ₁), meridian
    /// area (R₁² − R₀²)/2 Δφ and polar interval.
    fn sphere_cell(&self, s: f64, k: usize, j: usize) -> (SVector<f64, 2>, f64, f64, [f64; 2]) {
        let r0 = self.r_inner + k as f64 * s;
        let r1 = r0 + s;
        let rc = 0.5 * (r0 + r1);
        let dphi = 0.5 * std::f64::consts::PI / self.sphere_layer_count(s, k) as f64;
        let (p0, p1) = (j as f64 * dphi, (j + 1) as f64 * dphi);
        let pc = 0.5 * (p0 + p1);
        let vol = (r1.powi(3) - r0.powi(3)) / 3.0 * (p0.cos() - p1.cos());
        let area = 0.5 * (r1 * r1 - r0 * r0) * dphi;
        (
            SVector::from([rc * pc.sin(), rc * pc.cos()]),
            vol,
            area,
            [p0, p1],
        )
    }

    /// Grid and particles with `n` cells across the wall and 2 particles
    /// per cell per direction (sphere: the equivalent polar spacing h/2).
    pub fn setup(&self, n: usize) -> (Grid<2>, Particles<2>) {
        let h = self.cell_size(n);
        let s = 0.5 * h;
        let reach = (self.r_outer / h).round() as usize + 2;
        let mut particles = Particles::<2>::default();
        let grid = match self.shape {
            LameShape::Cylinder => {
                let mut g = Grid::<2>::new(
                    SVector::from([0.0, 0.0]),
                    SVector::from([reach as f64 * h, 2.0 * h]),
                    [reach, 2],
                    [
                        [Boundary::Symmetry, Boundary::Free],
                        [Boundary::Symmetry, Boundary::Symmetry],
                    ],
                );
                g.axisymmetric = true;
                for k in 0..2 * n {
                    let r = self.r_inner + (k as f64 + 0.5) * s;
                    for j in 0..4 {
                        let z = (j as f64 + 0.5) * s;
                        let vol = r * s * s;
                        particles.push(
                            SVector::from([r, z]),
                            SVector::zeros(),
                            self.rho * vol,
                            vol,
                            SVector::from([0.5 * s, 0.5 * s]),
                            0,
                        );
                    }
                }
                g
            }
            LameShape::Sphere => {
                let len = reach as f64 * h;
                let mut g = Grid::<2>::new(
                    SVector::from([0.0, 0.0]),
                    SVector::from([len, len]),
                    [reach, reach],
                    [
                        [Boundary::Symmetry, Boundary::Free],
                        [Boundary::Symmetry, Boundary::Free],
                    ],
                );
                g.axisymmetric = true;
                for k in 0..2 * n {
                    for j in 0..self.sphere_layer_count(s, k) {
                        let (x, vol, area, _) = self.sphere_cell(s, k, j);
                        let half = 0.5 * area.sqrt();
                        particles.push(
                            x,
                            SVector::zeros(),
                            self.rho * vol,
                            vol,
                            SVector::from([half, half]),
                            0,
                        );
                    }
                }
                g
            }
        };
        (grid, particles)
    }

    /// The explicit run with the inner-pressure load and damping of `relax`.
    pub fn build(&self, n: usize, relax: &Relax) -> SolidRun<2> {
        let (grid, particles) = self.setup(n);
        let min_mass = particles.mass.iter().cloned().fold(f64::INFINITY, f64::min);
        let params = ExplicitParams {
            shape: relax.shape,
            scheme: relax.scheme,
            mass_floor: 1e-12 * min_mass,
            damping: relax.damping,
            pic_fraction: 0.0,
        };
        let time = TimeControl {
            end: relax.end,
            cfl: relax.cfl,
            dt: None,
            max_steps: None,
        };
        let mut run = SolidRun::new(grid, vec![self.material()], particles, params, time);
        run.body = Some(Box::new(InnerPressure {
            lame: *self,
            spacing: 0.5 * self.cell_size(n),
            ramp: relax.ramp,
        }));
        run
    }

    /// Runs to `relax.end` and measures.
    ///
    /// # Errors
    /// A numerical failure of the run.
    pub fn run(&self, n: usize, relax: &Relax) -> Result<LameMeasured> {
        let mut run = self.build(n, relax);
        let start = Instant::now();
        while !run.finished() {
            run.step()?;
        }
        let wall_s = start.elapsed().as_secs_f64();
        let e = run.energies();
        let mut m = self.errors(&run.particles, self.cell_size(n));
        m.kinetic_ratio = e.kinetic / e.strain.abs().max(f64::MIN_POSITIVE);
        m.steps = run.steps;
        m.wall_s = wall_s;
        Ok(m)
    }

    /// Relative L2 errors of the wall's particles (material 0) against the
    /// exact solution at their reference radius (small strain); `h` is the
    /// cell size (the interior norms leave out the particles within h of rᵢ).
    pub fn errors(&self, p: &Particles<2>, h: f64) -> LameMeasured {
        let mut num = [0.0; 6];
        let mut den = [0.0; 6];
        for i in (0..p.len()).filter(|&i| p.material[i] == 0) {
            let x0 = p.x0[i];
            let (r0, er) = match self.shape {
                LameShape::Cylinder => (x0[0], SVector::from([1.0, 0.0])),
                LameShape::Sphere => (x0.norm(), x0 / x0.norm()),
            };
            let ex = self.exact(r0);
            let s = p.stress.get(i);
            let s2 = Matrix2::new(s[(0, 0)], s[(0, 1)], s[(1, 0)], s[(1, 1)]);
            let et = SVector::from([-er[1], er[0]]);
            let sr = er.dot(&(s2 * er));
            let third = et.dot(&(s2 * et));
            let ur = (p.x[i] - x0).dot(&er);
            let third_exact = match self.shape {
                LameShape::Cylinder => self.poisson * (ex.sigma_r + ex.sigma_theta),
                LameShape::Sphere => ex.sigma_theta,
            };
            let pairs = [
                (sr, ex.sigma_r),
                (s[(2, 2)], ex.sigma_theta),
                (ur, ex.u_r),
                (third, third_exact),
            ];
            let interior = r0 >= self.r_inner + h;
            for (k, (v, e)) in pairs.iter().enumerate() {
                num[k] += p.vol0[i] * (v - e) * (v - e);
                den[k] += p.vol0[i] * e * e;
                if interior && k < 2 {
                    num[4 + k] += p.vol0[i] * (v - e) * (v - e);
                    den[4 + k] += p.vol0[i] * e * e;
                }
            }
        }
        let rel = |k: usize| (num[k] / den[k]).sqrt();
        LameMeasured {
            h,
            sigma_r: rel(0),
            sigma_theta: rel(1),
            u_r: rel(2),
            sigma_third: rel(3),
            sigma_r_interior: rel(4),
            sigma_theta_interior: rel(5),
            kinetic_ratio: 0.0,
            steps: 0,
            particles: p.len(),
            wall_s: 0.0,
        }
    }
}

/// The same problem loaded through the grid by gas points (York Sec. 3.3)
/// filling the bore or cavity at the pressure P, as a scene: `n` cells across
/// the wall, GIMP, 2 particles per cell per direction on the scene's square
/// lattice (the sphere's surfaces are staircases), the gas an ideal gas
/// (γ = 1.4) of density 10⁻⁴ whose bulk modulus γP is so small that the
/// wall's expansion lowers P by about 3·10⁻⁵ relative; damping α = 3 to
/// t = 20. `cases/axisym_lame_cylinder.toml` and
/// `cases/axisym_lame_sphere.toml` are this scene at n = 8. The wall is
/// material 0 (what [`Lame::errors`] measures).
pub fn gas_loaded_scene(lame: &Lame, n: usize) -> String {
    let h = lame.cell_size(n);
    let cells = (lame.r_outer / h).round() as usize + 2;
    let len = cells as f64 * h;
    let (ri, ro) = (lame.r_inner, lame.r_outer);
    let (grid, wall, gas) = match lame.shape {
        LameShape::Cylinder => (
            format!(
                "upper = [{len:?}, {hz:?}]\ncells = [{cells}, 2]\nboundary = {{ x_lower = \
                 \"symmetry\", y_lower = \"symmetry\", y_upper = \"symmetry\" }}",
                hz = 2.0 * h
            ),
            format!(
                "{{ type = \"box\", lower = [{ri:?}, 0.0], upper = [{ro:?}, {hz:?}] }}",
                hz = 2.0 * h
            ),
            format!(
                "{{ type = \"box\", lower = [0.0, 0.0], upper = [{ri:?}, {hz:?}] }}",
                hz = 2.0 * h
            ),
        ),
        LameShape::Sphere => (
            format!(
                "upper = [{len:?}, {len:?}]\ncells = [{cells}, {cells}]\nboundary = {{ x_lower = \
                 \"symmetry\", y_lower = \"symmetry\" }}"
            ),
            format!(
                "{{ type = \"annulus\", center = [0.0, 0.0], inner_radius = {ri:?}, \
                 outer_radius = {ro:?} }}\nclip = true"
            ),
            format!("{{ type = \"disk\", center = [0.0, 0.0], radius = {ri:?} }}\nclip = true"),
        ),
    };
    let model = match lame.model {
        SolidModel::NeoHookean => "neo_hookean",
        _ => "linear_elastic",
    };
    format!(
        r#"[grid]
dim = 2
axisymmetric = true
lower = [0.0, 0.0]
{grid}

[time]
end = 20.0
cfl = 0.4

[mpm]
shape = "gimp"
particles_per_cell = 2
damping = 3.0

[[materials]]
name = "wall"
type = "solid"
model = "{model}"
density = {rho:?}
youngs_modulus = {e:?}
poisson_ratio = {nu:?}

[[materials]]
name = "gas"
type = "fluid"
frame = "particles"
eos = "ideal_gas"
gamma = 1.4
cv = 2.5

[[objects]]
material = "wall"
geometry = {wall}

[[objects]]
material = "gas"
geometry = {gas}
density = 1e-4
pressure = {p:?}
"#,
        rho = lame.rho,
        e = lame.young,
        nu = lame.poisson,
        p = lame.pressure,
    )
}

/// Runs [`gas_loaded_scene`] and measures the wall.
///
/// # Errors
/// A scene or numerical error.
pub fn run_gas_loaded(lame: &Lame, n: usize) -> Result<LameMeasured> {
    let scene = crate::scene::parse(&gas_loaded_scene(lame, n))?;
    let mut run = crate::scene::build_solid_run::<2>(&scene)?;
    let start = Instant::now();
    while !run.finished() {
        run.step()?;
    }
    let wall_s = start.elapsed().as_secs_f64();
    let p = &run.particles;
    let wall = || (0..p.len()).filter(|&i| p.material[i] == 0);
    let kinetic: f64 = wall()
        .map(|i| 0.5 * p.mass[i] * p.v[i].norm_squared())
        .sum();
    let strain: f64 = wall()
        .map(|i| p.vol0[i] * run.materials[0].strain_energy_density(&p.f.get(i), p.work_of(i)))
        .sum();
    let mut m = lame.errors(p, lame.cell_size(n));
    m.kinetic_ratio = kinetic / strain.abs().max(f64::MIN_POSITIVE);
    m.steps = run.steps;
    m.particles = p.len();
    m.wall_s = wall_s;
    Ok(m)
}

/// The inner pressure as a body force on the first particle layer, in
/// closed form from the reference position (see the module notes): the
/// particle's share of the surface traction, per radian, over its mass per
/// radian, ramped by ½(1 − cos(π t/T)).
#[derive(Debug, Clone, Copy)]
struct InnerPressure {
    lame: Lame,
    spacing: f64,
    ramp: f64,
}

impl BodyForce<2> for InnerPressure {
    fn accel(&self, x0: &SVector<f64, 2>, _x: &SVector<f64, 2>, t: f64) -> SVector<f64, 2> {
        let l = &self.lame;
        let (ri, s, p) = (l.r_inner, self.spacing, l.pressure);
        let f = if t < self.ramp {
            0.5 * (1.0 - (std::f64::consts::PI * t / self.ramp).cos())
        } else {
            1.0
        };
        match l.shape {
            LameShape::Cylinder => {
                if x0[0] >= ri + s {
                    return SVector::zeros();
                }
                // P rᵢ Δz over ρ r_p Δr Δz.
                SVector::from([f * p * ri / (l.rho * x0[0] * s), 0.0])
            }
            LameShape::Sphere => {
                if x0.norm() >= ri + s {
                    return SVector::zeros();
                }
                let n = l.sphere_layer_count(s, 0);
                let phi = x0[0].atan2(x0[1]);
                let dphi = 0.5 * std::f64::consts::PI / n as f64;
                let j = ((phi / dphi).floor() as usize).min(n - 1);
                let (_, vol, _, [a, b]) = l.sphere_cell(s, 0, j);
                // P rᵢ² ∫ₐᵇ (sin²φ, sinφ cosφ) dφ.
                let fr = 0.5 * (b - a) - 0.25 * ((2.0 * b).sin() - (2.0 * a).sin());
                let fz = 0.5 * (b.sin().powi(2) - a.sin().powi(2));
                SVector::from([fr, fz]) * (f * p * ri * ri / (l.rho * vol))
            }
        }
    }
}
