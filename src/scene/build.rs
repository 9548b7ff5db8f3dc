//! Building a run from a validated scene.

use nalgebra::SVector;

use super::schema::{
    FluidVariant, Geometry, LimiterKind, MaterialKind, MaterialSpec, Mode, NewtonSolverKind,
    ObjectSpec, PressureSolverKind, RelaxationKind, Scene,
};
use crate::coupling::iteration::{CouplingIteration, Relaxation};
use crate::error::SceneError;
use crate::grid::{Boundary, Grid};
use crate::ice::implicit::{LinearSolver as PressureSolver, SemiImplicit};
use crate::ice::state::temperature_from_rho_p;
use crate::ice::{
    Advection, CellLayout, ExchangeCoefficients, IceBoundary, IceMaterial, IceParams, IceState,
    InflowState, Limiter, MaterialInit,
};
use crate::material::eos::{EosError, EquationOfState, FluidEos};
use crate::material::failure::Fracturing;
use crate::material::{
    ArtificialViscosity, ElasticConstants, GasPoint, MembraneLaw, SolidMaterial, SolidModel,
};
use crate::membrane::{self, MembraneChain, Membranes};
use crate::mpm::explicit::Uniform;
use crate::mpm::implicit::{
    ImplicitParams, ImplicitRun, LinearSolver as ImplicitLinear, PrescribedDisplacement,
    SurfaceLoad,
};
use crate::mpm::{ExplicitParams, Particles, UpdateScheme};
use crate::multiphase::{MultiphaseRun, Phase};
use crate::stepper::{SolidRun, TimeControl};

fn to_vec<const D: usize>(v: &[f64]) -> SVector<f64, D> {
    SVector::from_fn(|i, _| v[i])
}

fn solid_material(m: &MaterialSpec) -> SolidMaterial {
    let elastic = match (m.youngs_modulus, m.poisson_ratio) {
        (Some(e), Some(nu)) => ElasticConstants::from_young_poisson(e, nu),
        _ => ElasticConstants::from_bulk_shear(
            m.bulk_modulus.unwrap_or_default(),
            m.shear_modulus.unwrap_or_default(),
        ),
    };
    // Validation has checked the plasticity and failure tables (and that
    // they go with the hypo-elastic or the Hencky model).
    let j2 = m.plasticity.as_ref().and_then(|pl| pl.j2().ok());
    let failure = m.failure.as_ref().and_then(|f| f.failure(j2.as_ref()).ok());
    let model = match (j2, failure) {
        (plasticity, Some(failure)) => {
            let f = Fracturing {
                plasticity,
                failure,
            };
            if m.model == Some(SolidModel::Hencky) {
                SolidModel::HenckyFracturing(f)
            } else {
                SolidModel::Fracturing(f)
            }
        }
        (Some(j2), None) if m.model == Some(SolidModel::Hencky) => SolidModel::HenckyPlastic(j2),
        (Some(j2), None) => SolidModel::ElasticPlastic(j2),
        _ => m.model.unwrap_or(SolidModel::NeoHookean),
    };
    SolidMaterial {
        name: m.name.clone(),
        density: m.density.unwrap_or_default(),
        model,
        elastic,
    }
}

/// The particle material of a gas-point fluid (York Sec. 3.3) on a grid of
/// smallest cell size `h` (York's `g` is a multiple of it).
fn gas_point_material(m: &MaterialSpec, i: usize, h: f64) -> Result<SolidMaterial, SceneError> {
    let av = m.artificial_viscosity.unwrap_or_default();
    Ok(SolidMaterial {
        name: m.name.clone(),
        density: 0.0,
        model: SolidModel::GasPoint(GasPoint {
            eos: fluid_eos(m, i)?,
            viscosity: m.viscosity.unwrap_or(0.0),
            q: ArtificialViscosity {
                g: av.g_over_dx * h,
                kappa: av.kappa,
                c1: av.c1,
                c2: av.c2,
            },
            min_pressure: m.min_pressure.unwrap_or(f64::NEG_INFINITY),
            density: m.point_density.unwrap_or_default(),
        }),
        elastic: ElasticConstants {
            lambda: 0.0,
            mu: 0.0,
        },
    })
}

/// The particle material of a membrane (York Sec. 3.2).
fn membrane_material(m: &MaterialSpec) -> SolidMaterial {
    let law = MembraneLaw {
        young: m.youngs_modulus.unwrap_or_default(),
        poisson: m.poisson_ratio.unwrap_or_default(),
        thickness: m.thickness.unwrap_or_default(),
        density: m.density.unwrap_or_default(),
    };
    SolidMaterial {
        name: m.name.clone(),
        density: law.density,
        model: SolidModel::Membrane(law),
        elastic: ElasticConstants {
            lambda: 0.0,
            mu: 0.0,
        },
    }
}

/// The ordered points of a membrane object's curve (York Sec. 3.2) at most
/// `spacing` apart, whether the curve is closed, and the arc length Δ
/// between neighbours.
///
/// Axisymmetric (`axis`): an open polyline's end on the axis (r = 0) gets
/// no point (a ring of radius 0 has no volume and no hoop rate); the points
/// start half an interval from it and the end point's segment reaches the
/// axis ([`membrane::resample_offset`]). Returns, per point, the share of
/// Δ its segment covers (½ at an end that has a point, 1 elsewhere).
fn membrane_curve(g: &Geometry, spacing: f64, axis: bool) -> (Vec<[f64; 2]>, bool, f64, [f64; 2]) {
    match g {
        Geometry::Polyline { vertices, closed } => {
            let on_axis = |v: &[f64; 2]| axis && !*closed && v[0] == 0.0;
            let bare = [
                on_axis(&vertices[0]),
                on_axis(&vertices[vertices.len() - 1]),
            ];
            let (p, d) = membrane::resample_offset(vertices, *closed, spacing, bare);
            let share = bare.map(|b| if b { 1.0 } else { 0.5 });
            (p, *closed, d, share)
        }
        Geometry::Circle { center, radius } => {
            let (p, d) = membrane::circle_points([center[0], center[1]], *radius, spacing);
            (p, true, d, [1.0; 2])
        }
        Geometry::DogBone {
            center,
            lobe_radius,
            lobe_offset,
            neck_half_width,
        } => {
            let outline = membrane::dog_bone_outline(
                [center[0], center[1]],
                *lobe_radius,
                *lobe_offset,
                *neck_half_width,
                spacing / 64.0,
            );
            let (p, d) = membrane::resample(&outline, true, spacing);
            (p, true, d, [1.0; 2])
        }
        // Validation admits only the curves above.
        _ => (Vec::new(), true, spacing, [1.0; 2]),
    }
}

/// The particle materials of a scene in scene order (solids and gas points),
/// as indexed by `Particles::material`.
pub(super) fn particle_materials<const D: usize>(
    scene: &Scene,
    grid: &Grid<D>,
) -> Result<Vec<SolidMaterial>, SceneError> {
    scene
        .materials
        .iter()
        .enumerate()
        .filter(|(_, m)| m.on_particles())
        .map(|(i, m)| {
            if m.is_gas_point() {
                gas_point_material(m, i, grid.h.min())
            } else if m.kind == MaterialKind::Membrane {
                Ok(membrane_material(m))
            } else {
                Ok(solid_material(m))
            }
        })
        .collect()
}

/// The grid a scene describes (the scene must be validated and `D == dim`).
pub fn grid_of<const D: usize>(scene: &Scene) -> Grid<D> {
    let g = &scene.grid;
    let faces = g.boundary.faces();
    let bc: [[Boundary; 2]; D] = std::array::from_fn(|d| {
        [
            faces[d][0].0.unwrap_or(Boundary::Free),
            faces[d][1].0.unwrap_or(Boundary::Free),
        ]
    });
    let mut grid = Grid::new(
        to_vec::<D>(&g.lower),
        to_vec::<D>(&g.upper),
        std::array::from_fn(|d| g.cells[d]),
        bc,
    );
    grid.axisymmetric = g.axisymmetric;
    grid
}

/// Fills every object with particles: `ppc` per cell per direction at the
/// centres of a regular sub-lattice of each grid cell, kept where the point is
/// inside the object's region. Volume = cell volume / ppc^D, mass = ρ₀ V;
/// axisymmetric grids: volume per radian V = r_p A_p (exact ∫ r dA over the
/// particle's square, r being linear), mass ρ₀ V per radian.
pub fn fill_particles<const D: usize>(
    scene: &Scene,
    grid: &Grid<D>,
    materials: &[SolidMaterial],
) -> Result<Particles<D>, SceneError> {
    fill_objects(scene, grid, materials).map(|(p, _)| p)
}

/// [`fill_particles`] plus the range of particle indices of each object.
fn fill_objects<const D: usize>(
    scene: &Scene,
    grid: &Grid<D>,
    materials: &[SolidMaterial],
) -> Result<(Particles<D>, Vec<std::ops::Range<usize>>), SceneError> {
    let mut ranges = Vec::with_capacity(scene.objects.len());
    let mut particles = Particles::<D>::default();
    // Arrays of the exact size: grown by doubling they would keep up to
    // twice the particles' memory for the whole run (issue 24).
    let mut count = 0;
    for obj in &scene.objects {
        let membrane = materials
            .iter()
            .any(|m| m.name == obj.material && m.membrane().is_some());
        if !membrane {
            let ppc = obj
                .particles_per_cell
                .unwrap_or(scene.mpm.particles_per_cell);
            object_positions(scene, grid, obj, ppc, |_| count += 1);
        }
    }
    particles.reserve_exact(count);
    for (oi, obj) in scene.objects.iter().enumerate() {
        let mat_index = materials
            .iter()
            .position(|m| m.name == obj.material)
            .ok_or_else(|| {
                SceneError::new(format!("objects[{oi}].material"), "unknown material")
            })?;
        // A gas object carries its own density and pressure (York Sec. 3.3):
        // stress −p I and internal energy ρ e per unit reference volume.
        let gas = materials[mat_index].gas();
        let rho = match (gas, obj.density) {
            (Some(_), Some(r)) => r,
            _ => materials[mat_index].density,
        };
        let (gas_work, gas_stress) = match (gas, obj.pressure) {
            // A hypo-elastic solid of a multiphase scene under a hydrostatic
            // pressure p: σ = −p I, stored energy p²/(2K) per unit volume.
            (None, Some(p)) => (
                p * p / (2.0 * materials[mat_index].elastic.bulk()),
                -p * nalgebra::Matrix3::identity(),
            ),
            (Some(g), Some(p)) => {
                let e = g.energy_of(rho, p);
                if !(e.is_finite() && e > 0.0) {
                    return Err(SceneError::new(
                        format!("objects[{oi}].pressure"),
                        format!(
                            "gives internal energy {e} at density {rho}; must give a positive \
                             one (raise the pressure)"
                        ),
                    ));
                }
                (rho * e, -p * nalgebra::Matrix3::identity())
            }
            _ => (0.0, nalgebra::Matrix3::zeros()),
        };
        let vel0 = obj
            .velocity
            .as_deref()
            .map(to_vec::<D>)
            .unwrap_or_else(SVector::zeros);
        if let Some(law) = materials[mat_index].membrane() {
            // York Sec. 3: mass from the areal density ρ h and the spacing
            // (per unit depth in 2D, per radian in r–z: V = r h Δ); an open
            // chain's ends carry half unless they sit next to the axis.
            let spacing = obj.spacing.unwrap_or(grid.h.min());
            let axi = grid.axisymmetric;
            let (pts, closed, delta, ends) = membrane_curve(&obj.geometry, spacing, axi);
            let before = particles.len();
            let s0 = obj.prestress.unwrap_or(0.0);
            // Plane 2D: s₃₃ = ν s₀ (ε₃₃ = 0); r–z: an equal biaxial
            // prestress (meridian and hoop, as in a sphere).
            let s0_3 = if axi { s0 } else { law.out_of_plane(s0) };
            for (k, xy) in pts.iter().enumerate() {
                let share = match (closed, k) {
                    (false, 0) => ends[0],
                    (false, k) if k + 1 == pts.len() => ends[1],
                    _ => 1.0,
                };
                let r = if axi { xy[0] } else { 1.0 };
                let vol = law.thickness * delta * share * r;
                let x = SVector::<f64, D>::from_fn(|d, _| if d < 2 { xy[d] } else { 0.0 });
                particles.push(
                    x,
                    vel0,
                    law.density * vol,
                    vol,
                    SVector::repeat(0.5 * delta),
                    mat_index as u16,
                );
                let p = particles.len() - 1;
                // The prestress as an in-plane trace; the first frame update
                // turns it along the tangent.
                let mut s = nalgebra::Matrix3::zeros();
                s[(0, 0)] = s0;
                s[(2, 2)] = s0_3;
                particles.stress.set(p, &s);
                particles.track_work();
                particles.work[p] = law.energy_of([s0, s0_3]);
            }
            if let Some(q) = (before..particles.len()).find(|&q| {
                (0..D).any(|d| {
                    let x = particles.x[q][d];
                    x < grid.lower[d] || x > grid.upper[d]
                })
            }) {
                return Err(SceneError::new(
                    format!("objects[{oi}].geometry"),
                    format!("membrane point {} lies outside the grid", q - before),
                ));
            }
            ranges.push(before..particles.len());
            continue;
        }
        let ppc = obj
            .particles_per_cell
            .unwrap_or(scene.mpm.particles_per_cell);
        let vel = obj
            .velocity
            .as_deref()
            .map(to_vec::<D>)
            .unwrap_or_else(SVector::zeros);
        let vol = grid.cell_volume() / (ppc as f64).powi(D as i32);
        let half = grid.h / (2.0 * ppc as f64);
        let before = particles.len();
        object_positions(scene, grid, obj, ppc, |x| {
            let vol = if grid.axisymmetric { vol * x[0] } else { vol };
            particles.push(
                SVector::from(x),
                vel,
                rho * vol,
                vol,
                half,
                mat_index as u16,
            );
            if gas.is_some() || obj.pressure.is_some() {
                let p = particles.len() - 1;
                particles.track_work();
                particles.work[p] = gas_work;
                particles.stress.set(p, &gas_stress);
            }
        });
        if particles.len() == before {
            return Err(SceneError::new(
                format!("objects[{oi}].geometry"),
                "the region contains no particle position inside the grid (make it larger \
                 than a particle spacing, or refine the grid)",
            ));
        }
        ranges.push(before..particles.len());
    }
    // Membrane points were not counted ahead.
    particles.shrink_to_fit();
    Ok((particles, ranges))
}

/// The polygon of a closed membrane drawn on the same curve as `obj`'s
/// region, if the scene has one: an object filling a membrane fills the
/// polygon of the membrane's points. The points lie on the curve and their
/// chords inside it, so a filling point within a chord's sagitta of the
/// curve would start outside the membrane: at element size 0.2 the
/// dog-bone's lobe tops y = ±0.45 fall on the gas's lattice, 2e-4 beyond
/// the chords, and those two gas points were outside from the first step.
fn enclosing_membrane<const D: usize>(
    scene: &Scene,
    grid: &Grid<D>,
    obj: &ObjectSpec,
) -> Option<RowCrossings> {
    let is_membrane = |name: &str| {
        scene
            .materials
            .iter()
            .any(|m| m.name == name && m.kind == MaterialKind::Membrane)
    };
    if D != 2 || is_membrane(&obj.material) {
        return None;
    }
    scene
        .objects
        .iter()
        .filter(|m| is_membrane(&m.material) && m.geometry == obj.geometry)
        .find_map(|m| {
            let spacing = m.spacing.unwrap_or(grid.h.min());
            let (vertices, closed, ..) = membrane_curve(&m.geometry, spacing, grid.axisymmetric);
            closed.then(|| RowCrossings {
                vertices,
                rows: std::collections::HashMap::new(),
            })
        })
}

/// The even–odd inside test of a polygon (the crossings of
/// [`membrane::edge_crossing`], as [`Geometry::Polygon`]'s `contains`
/// counts them) for the many points of a
/// lattice that share few rows: each row's edge crossings are found once
/// and sorted, and a point counts the crossings beyond it by bisection. A
/// membrane of 10⁴ points around 10⁶ lattice points would otherwise cost
/// 10¹⁰ edge tests.
struct RowCrossings {
    vertices: Vec<[f64; 2]>,
    /// Sorted crossings per row, keyed by the row's y bits.
    rows: std::collections::HashMap<u64, Vec<f64>>,
}

impl RowCrossings {
    fn contains(&mut self, x: &[f64]) -> bool {
        let (px, py) = (x[0], x[1]);
        let v = &self.vertices;
        let row = self.rows.entry(py.to_bits()).or_insert_with(|| {
            let n = v.len();
            let mut c: Vec<f64> = (0..n)
                .filter_map(|i| membrane::edge_crossing(v[i], v[(i + n - 1) % n], py))
                .collect();
            c.sort_by(f64::total_cmp);
            c
        });
        // Crossings with px < x_c.
        (row.len() - row.partition_point(|&c| c <= px)) % 2 == 1
    }
}

/// Calls `f` with each particle position of the filled object `obj`, in
/// creation order: `ppc` points per cell and axis at the centres of the
/// cell's sub-cells, kept where `obj.geometry` contains them, and the
/// polygon of a closed membrane on the same curve if there is one
/// ([`enclosing_membrane`]), and no object of `obj.except` does (not for
/// membranes, whose points follow their polyline).
fn object_positions<const D: usize>(
    scene: &Scene,
    grid: &Grid<D>,
    obj: &ObjectSpec,
    ppc: usize,
    mut f: impl FnMut([f64; D]),
) {
    let per_cell = ppc.pow(D as u32);
    let mut enclosing = enclosing_membrane(scene, grid, obj);
    for cell in 0..grid.num_cells() {
        let mut rem = cell;
        let c: [usize; D] = std::array::from_fn(|d| {
            let v = rem % grid.cells[d];
            rem /= grid.cells[d];
            v
        });
        for k in 0..per_cell {
            let mut r = k;
            let mut x = [0.0; D];
            for d in 0..D {
                let s = r % ppc;
                r /= ppc;
                x[d] = grid.lower[d] + grid.h[d] * (c[d] as f64 + (s as f64 + 0.5) / ppc as f64);
            }
            if obj.geometry.contains(&x)
                && enclosing.as_mut().is_none_or(|poly| poly.contains(&x))
                && !obj
                    .except
                    .iter()
                    .any(|&e| scene.objects[e].geometry.contains(&x))
            {
                f(x);
            }
        }
    }
}

/// Builds the implicit (Newmark + Newton, or quasistatic) solid run of a
/// validated scene with `D == dim` and `time.mode = "implicit"`.
pub fn build_implicit_run<const D: usize>(
    scene: &Scene,
) -> Result<ImplicitRun<D>, crate::error::Error> {
    let grid = grid_of::<D>(scene);
    let materials: Vec<SolidMaterial> = scene
        .materials
        .iter()
        .filter(|m| m.kind == MaterialKind::Solid)
        .map(solid_material)
        .collect();
    let (particles, ranges) = fill_objects(scene, &grid, &materials)?;
    let min_mass = particles.mass.iter().cloned().fold(f64::INFINITY, f64::min);
    let params = implicit_params(scene, min_mass);
    let dt = scene.time.dt.unwrap_or(scene.time.end);
    let mut run = ImplicitRun::new(grid, materials, particles, params, scene.time.end, dt)?;
    run.load_ramp = scene.implicit.load_ramp;
    if let Some(g) = &scene.gravity {
        let g = to_vec::<D>(g);
        if g.norm() > 0.0 {
            run.body = Some(Box::new(Uniform(g)));
        }
    }
    // Inner-surface pressure of annulus objects: the particles whose centres
    // lie within one particle spacing s of the inner radius carry it, pushed
    // radially out, with the total force P·A exact: A is the part of the
    // inner surface inside the grid (the circle sampled at 2^16 angles; times
    // the z extent in 3D), so a clipped annulus (a quarter cylinder on
    // symmetry planes) gets its exact total load. In 2D the shares follow the
    // particles' angular spacing, in 3D their volumes.
    let mut loaded = Vec::new();
    let mut forces = Vec::new();
    for (oi, obj) in scene.objects.iter().enumerate() {
        let (
            Some(pressure),
            Geometry::Annulus {
                center,
                inner_radius,
                ..
            },
        ) = (obj.inner_pressure, &obj.geometry)
        else {
            continue;
        };
        let ppc = obj
            .particles_per_cell
            .unwrap_or(scene.mpm.particles_per_cell);
        let s = run.grid.h[0] / ppc as f64;
        let ri = *inner_radius;
        let samples = 1 << 16;
        let inside = (0..samples)
            .filter(|k| {
                let a = std::f64::consts::TAU * (*k as f64 + 0.5) / samples as f64;
                let xy = [center[0] + ri * a.cos(), center[1] + ri * a.sin()];
                (0..2).all(|d| xy[d] >= run.grid.lower[d] && xy[d] <= run.grid.upper[d])
            })
            .count();
        let mut area = std::f64::consts::TAU * ri * inside as f64 / samples as f64;
        if D == 3 {
            area *= run.grid.upper[2] - run.grid.lower[2];
        }
        let band: Vec<usize> = ranges[oi]
            .clone()
            .filter(|&p| {
                let x0 = run.particles.x0[p];
                let r = ((x0[0] - center[0]).powi(2) + (x0[1] - center[1]).powi(2)).sqrt();
                r < ri + s
            })
            .collect();
        let radial = |p: usize| {
            let x0 = run.particles.x0[p];
            let mut r = SVector::<f64, D>::zeros();
            for d in 0..2 {
                r[d] = x0[d] - center[d];
            }
            r.normalize()
        };
        let shares: Vec<f64> = if D == 2 {
            // Each particle carries rᵢ times the part inside the grid of its
            // angular interval between the midpoints to its angular
            // neighbours: the load per unit arc stays uniform where the
            // particle lattice meets the circle unevenly (a volume-share
            // split does not converge in the displacement).
            let angle = |p: usize| {
                let x0 = run.particles.x0[p];
                (x0[1] - center[1]).atan2(x0[0] - center[0])
            };
            let inside = |a: f64| {
                let xy = [center[0] + ri * a.cos(), center[1] + ri * a.sin()];
                (0..2).all(|d| xy[d] >= run.grid.lower[d] && xy[d] <= run.grid.upper[d])
            };
            let mut order: Vec<usize> = (0..band.len()).collect();
            order.sort_by(|&a, &b| angle(band[a]).total_cmp(&angle(band[b])).then(a.cmp(&b)));
            let n = order.len();
            let tau = std::f64::consts::TAU;
            let mut share = vec![0.0; n];
            for (k, &i) in order.iter().enumerate() {
                let a = angle(band[i]);
                let prev = angle(band[order[(k + n - 1) % n]]) - if k == 0 { tau } else { 0.0 };
                let next = angle(band[order[(k + 1) % n]]) + if k + 1 == n { tau } else { 0.0 };
                let (lo, hi) = if n == 1 {
                    (a - 0.5 * tau, a + 0.5 * tau)
                } else {
                    (0.5 * (prev + a), 0.5 * (a + next))
                };
                let m = 256;
                let frac = (0..m)
                    .filter(|j| inside(lo + (hi - lo) * (*j as f64 + 0.5) / m as f64))
                    .count() as f64
                    / m as f64;
                share[i] = ri * (hi - lo) * frac;
            }
            // Normalise to the measured inside arc (sampling round-off).
            let total: f64 = share.iter().sum();
            share
                .iter()
                .map(|v| v * area / total.max(f64::MIN_POSITIVE))
                .collect()
        } else {
            let band_volume: f64 = band.iter().map(|&p| run.particles.vol0[p]).sum();
            band.iter()
                .map(|&p| area * run.particles.vol0[p] / band_volume)
                .collect()
        };
        for (k, &p) in band.iter().enumerate() {
            loaded.push(p);
            forces.push(radial(p) * (pressure * shares[k]));
        }
    }
    run.surface = SurfaceLoad {
        particle: loaded,
        force: forces,
    };
    // Grips: the object's particles whose reference position lies in the
    // region (all of them without one).
    for (k, pr) in scene.implicit.prescribed.iter().enumerate() {
        let particle: Vec<usize> = ranges[pr.object]
            .clone()
            .filter(|&p| {
                let x0 = run.particles.x0[p];
                pr.region.as_ref().is_none_or(|g| g.contains(x0.as_slice()))
            })
            .collect();
        if particle.is_empty() {
            let key = if pr.region.is_some() {
                "region"
            } else {
                "object"
            };
            return Err(SceneError::new(
                format!("implicit.prescribed[{k}].{key}"),
                format!("selects no particles of objects[{}]", pr.object),
            )
            .into());
        }
        let mut components = [true; D];
        if let Some(c) = &pr.components {
            components.copy_from_slice(&c[..D]);
        }
        run.prescribed.push(PrescribedDisplacement {
            particle,
            displacement: to_vec::<D>(&pr.displacement),
            components,
        });
    }
    Ok(run)
}

/// The implicit MPM parameters of `[implicit]` (`min_mass`: the lightest
/// particle, which sets the node mass floor).
fn implicit_params(scene: &Scene, min_mass: f64) -> ImplicitParams {
    let im = &scene.implicit;
    let mut params = ImplicitParams::new(scene.mpm.shape, im.dynamic, 1e-12 * min_mass);
    params.tol_displacement = im.tolerance_displacement;
    params.tol_energy = im.tolerance_energy;
    params.max_newton = im.max_newton_iterations;
    params.modified_newton = im.modified_newton;
    params.linear = match im.linear_solver {
        NewtonSolverKind::Cholesky => ImplicitLinear::Cholesky,
        NewtonSolverKind::PcgJacobi => ImplicitLinear::PcgJacobi {
            rel_tol: 1e-12,
            max_iter: 10_000,
        },
    };
    if let Some(d) = im.dt_max {
        params.dt_max = d;
    }
    if let Some(f) = im.max_cell_fraction {
        params.max_cell_fraction = f;
    }
    params
}

/// Builds the solid-only explicit run of a validated scene with `D == dim`.
pub fn build_solid_run<const D: usize>(scene: &Scene) -> Result<SolidRun<D>, SceneError> {
    if scene.grid.dim != D {
        return Err(SceneError::new(
            "grid.dim",
            format!("internal: built for {D}D, scene has {}", scene.grid.dim),
        ));
    }
    let grid = grid_of::<D>(scene);
    let materials = particle_materials(scene, &grid)?;
    let (mut particles, ranges) = fill_objects(scene, &grid, &materials)?;
    let chains: Vec<MembraneChain> = scene
        .objects
        .iter()
        .zip(&ranges)
        .filter(|(o, _)| {
            scene
                .materials
                .iter()
                .any(|m| m.name == o.material && m.kind == MaterialKind::Membrane)
        })
        .map(|(o, r)| MembraneChain {
            first: r.start,
            count: r.len(),
            closed: !matches!(o.geometry, Geometry::Polyline { closed: false, .. }),
            fixed_ends: o.fixed_ends,
        })
        .collect();
    let mut membranes = Membranes::new(chains, &particles.x);
    if !membranes.is_empty() {
        let p = &mut particles;
        if let Err(q) = membranes.update_frames(&p.x, &mut p.stress) {
            return Err(SceneError::new(
                "objects",
                format!("membrane point {q} coincides with a neighbour"),
            ));
        }
    }
    let min_mass = particles.mass.iter().cloned().fold(f64::INFINITY, f64::min);
    let params = ExplicitParams {
        shape: scene.mpm.shape,
        scheme: scene.mpm_update(),
        mass_floor: 1e-12 * min_mass,
        damping: scene.mpm.damping,
        pic_fraction: scene.mpm.pic_fraction,
    };
    let time = TimeControl {
        end: scene.time.end,
        cfl: scene.time.cfl,
        dt: scene.time.dt,
        max_steps: scene.time.max_steps,
    };
    let mut run = SolidRun::new(grid, materials, particles, params, time);
    run.membranes = membranes;
    if let Some(g) = &scene.gravity {
        let g = to_vec::<D>(g);
        if g.norm() > 0.0 {
            run.gravity = g;
            run.body = Some(Box::new(Uniform(g)));
        }
    }
    Ok(run)
}

fn fluid_eos(m: &MaterialSpec, i: usize) -> Result<FluidEos, SceneError> {
    m.fluid_eos().map_err(|e| {
        let key = match e {
            EosError::Invalid { field, .. } => format!("materials[{i}].{field}"),
            _ => format!("materials[{i}]"),
        };
        SceneError::new(key, e.to_string())
    })
}

/// Volume fraction given to a fluid material absent from a region.
pub const TRACE_VOLUME_FRACTION: f64 = 1e-10;

/// Temperature at which `eos` gives pressure `p` at density `rho` (every
/// fluid EOS is linear in T at fixed ρ).
fn temperature_of(eos: &FluidEos, rho: f64, p: f64) -> f64 {
    let t0 = 1.0;
    t0 + (p - eos.pressure(rho, t0)) / eos.dp_dt(rho, t0)
}

/// One [`MaterialInit`] per fluid material (in `materials` order) from a
/// scene's pressure and listed states (a region or an inflow face, `key`):
/// density from the EOS where a temperature is given, absent materials at a
/// trace volume fraction, fractions renormalised to sum to 1.
fn material_states<const D: usize>(
    materials: &[IceMaterial],
    key: &str,
    pressure: f64,
    states_in: &[super::schema::FluidStateSpec],
) -> Result<Vec<MaterialInit<D>>, SceneError> {
    let mut states = Vec::with_capacity(materials.len());
    // Reference temperature for the absent materials: the first listed.
    let first = &states_in[0];
    let first_eos = &materials[materials
        .iter()
        .position(|m| m.name == first.material)
        .unwrap_or(0)]
    .eos;
    let t_ref = match (first.temperature, first.density) {
        (Some(t), _) => t,
        (None, Some(rho)) => temperature_of(first_eos, rho, pressure),
        _ => 300.0,
    };
    for mat in materials {
        let listed = states_in.iter().find(|s| s.material == mat.name);
        let (theta, rho, vel) = match listed {
            Some(s) => {
                let rho = match s.density {
                    Some(rho) => rho,
                    // Validation guarantees a temperature here; the EOS
                    // rejects a missing (NaN) one anyway.
                    None => mat
                        .eos
                        .density(pressure, s.temperature.unwrap_or(f64::NAN))
                        .map_err(|e| SceneError::new(format!("{key}.states"), e.to_string()))?,
                };
                let v = s
                    .velocity
                    .as_deref()
                    .map(to_vec::<D>)
                    .unwrap_or_else(SVector::zeros);
                (s.volume_fraction, rho, v)
            }
            None => {
                let rho = mat
                    .eos
                    .density(pressure, t_ref)
                    .map_err(|e| SceneError::new(format!("{key}.pressure"), e.to_string()))?;
                (0.0, rho, SVector::zeros())
            }
        };
        states.push(MaterialInit::new(theta, rho, pressure, vel));
    }
    // Multi-material ICE needs every material present in every cell:
    // raise absent ones to a trace fraction and renormalise to Σθ = 1.
    for st in states.iter_mut() {
        st.vol_frac = st.vol_frac.max(TRACE_VOLUME_FRACTION);
    }
    let sum: f64 = states.iter().map(|st| st.vol_frac).sum();
    for st in states.iter_mut() {
        st.vol_frac /= sum;
    }
    Ok(states)
}

/// Builds the fluid-only ICE run of a validated scene with `D == dim`: the
/// initial state sampled at cell centres from `[[regions]]` (the last region
/// containing a centre wins) and the parameters from `[fluid]`.
pub fn build_fluid_run<const D: usize>(
    scene: &Scene,
) -> Result<(IceState<D>, IceParams<D>), SceneError> {
    let grid = grid_of::<D>(scene);
    let layout =
        CellLayout::from_grid(&grid).map_err(|e| SceneError::new("grid", e.to_string()))?;
    let fluids: Vec<(usize, &MaterialSpec)> = scene
        .materials
        .iter()
        .enumerate()
        .filter(|(_, m)| m.kind == MaterialKind::Fluid)
        .collect();
    let mut materials = Vec::with_capacity(fluids.len());
    for (i, m) in &fluids {
        materials.push(IceMaterial::new(m.name.clone(), fluid_eos(m, *i)?));
    }
    // Every cell centre must lie in some region.
    for &c in &layout.interior {
        let x = layout.centre(c);
        let xs: Vec<f64> = x.iter().copied().collect();
        if !scene
            .regions
            .iter()
            .any(|r| r.geometry.as_ref().is_none_or(|g| g.contains(&xs)))
        {
            return Err(SceneError::new(
                "regions",
                format!(
                    "the cell centred at {xs:?} lies in no region (start with a region without \
                     geometry, which covers everything)"
                ),
            ));
        }
    }
    // Per region: one MaterialInit per fluid material, computed once.
    let mut inits: Vec<Vec<MaterialInit<D>>> = Vec::with_capacity(scene.regions.len());
    for (ri, r) in scene.regions.iter().enumerate() {
        inits.push(material_states::<D>(
            &materials,
            &format!("regions[{ri}]"),
            r.pressure,
            &r.states,
        )?);
    }
    let regions = &scene.regions;
    let state = IceState::new(layout, materials, |x| {
        let xs: Vec<f64> = x.iter().copied().collect();
        let k = regions
            .iter()
            .rposition(|r| r.geometry.as_ref().is_none_or(|g| g.contains(&xs)))
            .unwrap_or(0);
        inits[k].clone()
    })
    .map_err(|e| SceneError::new("regions", e.to_string()))?;
    let mut bcs: [[IceBoundary<D>; 2]; D] = std::array::from_fn(|d| {
        std::array::from_fn(|side| match grid.bc[d][side] {
            Boundary::Fixed | Boundary::Symmetry => IceBoundary::Wall,
            Boundary::Free => IceBoundary::Outflow,
            Boundary::Periodic => IceBoundary::Periodic,
        })
    });
    // Inflow faces: the prescribed state of every material in the ghosts.
    for (d, faces) in scene.fluid.inflow.faces().iter().enumerate().take(D) {
        for (side, (spec, name)) in faces.iter().enumerate() {
            let Some(spec) = spec else { continue };
            let key = format!("fluid.inflow.{name}");
            let inits = material_states::<D>(&state.materials, &key, spec.pressure, &spec.states)?;
            let states = inits
                .iter()
                .zip(&state.materials)
                .map(|(m, mat)| InflowState {
                    vol_frac: m.vol_frac,
                    density: m.density,
                    temperature: temperature_from_rho_p(&mat.eos, m.density, m.pressure),
                    velocity: m.velocity,
                })
                .collect();
            bcs[d][side] = IceBoundary::Inflow(states);
        }
    }
    let mut params = match scene.fluid.variant {
        FluidVariant::Literal => IceParams::new(bcs),
        FluidVariant::HighResolution => IceParams::high_resolution(bcs),
        FluidVariant::Hancock => IceParams::hancock(bcs),
        FluidVariant::HancockAcoustic => IceParams::hancock_acoustic(bcs),
    };
    params.cfl = scene.time.cfl;
    if let Some(f) = scene.fluid.isothermal_fraction {
        params.isothermal_fraction = f;
    }
    if let Some(l) = scene.fluid.limiter {
        params.advection = match l {
            LimiterKind::FirstOrder => Advection::FirstOrder,
            LimiterKind::VanLeer => Advection::SecondOrder(Limiter::VanLeer),
            LimiterKind::Mc => Advection::SecondOrder(Limiter::MonotonizedCentral),
            LimiterKind::Superbee => Advection::SecondOrder(Limiter::Superbee),
            LimiterKind::Minmod => Advection::SecondOrder(Limiter::Minmod),
        };
    }
    let n = fluids.len();
    if let Some(ex) = scene.fluid.exchange {
        params.exchange = Some(ExchangeCoefficients::uniform(n, ex.momentum, ex.heat));
    }
    let mu: Vec<f64> = fluids
        .iter()
        .map(|(_, m)| m.viscosity.unwrap_or(0.0))
        .collect();
    if mu.iter().any(|&v| v > 0.0) {
        params.viscosity = Some(mu);
    }
    if let Some(g) = &scene.gravity {
        params.gravity = to_vec::<D>(g);
    }
    // The implicit pressure: semi-implicit ICE, and the fluid half of a
    // coupled implicit scene (implicit MPM with the implicit pressure).
    if matches!(scene.time.mode, Mode::SemiImplicit | Mode::Implicit) {
        let ps = &scene.fluid.pressure;
        params.implicit = Some(SemiImplicit {
            linear_solver: match ps.solver {
                PressureSolverKind::Direct => PressureSolver::Direct,
                PressureSolverKind::PcgMultigrid => PressureSolver::PcgMultigrid,
                PressureSolverKind::PcgJacobi => PressureSolver::PcgJacobi,
            },
            linear_tolerance: ps.linear_tolerance,
            outer_tolerance: ps.outer_tolerance,
            max_outer_iterations: ps.max_outer_iterations,
            max_linear_iterations: ps.max_linear_iterations,
            sound_speed_factor: ps.sound_speed_factor,
            max_dt_growth: ps.max_dt_growth,
            convective_predictor: ps.convective_predictor,
        });
    }
    // Heat sources: the power on the cells whose centre lies in the region.
    for (i, h) in scene.heat_sources.iter().enumerate() {
        let material = fluids
            .iter()
            .position(|(_, m)| m.name == h.material)
            .ok_or_else(|| {
                SceneError::new(
                    format!("heat_sources[{i}].material"),
                    "not a fluid material",
                )
            })?;
        let layout = &state.layout;
        let mut power = vec![0.0; layout.len()];
        for &c in &layout.interior {
            let x: Vec<f64> = layout.centre(c).iter().copied().collect();
            if h.geometry.contains(&x) {
                power[c] = h.power;
            }
        }
        params.heat_sources.push(crate::ice::HeatSource {
            material,
            power,
            start: h.start,
            end: h.end,
        });
    }
    params
        .validate(&state)
        .map_err(|e| SceneError::new("fluid", e.to_string()))?;
    Ok((state, params))
}

/// Builds the coupled MPM-ICE run of a validated scene with solid and fluid
/// materials (`D == dim`): one solid field per solid material (in
/// `materials` order, with the particles of the objects of that material,
/// rigid with the objects' velocity if the material is `rigid`), the fluid
/// state from `[[regions]]`, the heat sources and `[coupling]`.
pub fn build_coupled_run<const D: usize>(
    scene: &Scene,
) -> Result<crate::coupling::CoupledRun<D>, SceneError> {
    let solid_run = build_solid_run::<D>(scene)?;
    let (state, params) = build_fluid_run::<D>(scene)?;
    let cs = &scene.coupling;
    let mut specs = Vec::new();
    // `k`: the material's index among the solid materials (the particles'
    // `material`).
    let solid_specs = scene
        .materials
        .iter()
        .enumerate()
        .filter(|(_, m)| m.kind == MaterialKind::Solid);
    for (k, (spec_index, spec)) in solid_specs.enumerate() {
        let solid = solid_material(spec);
        let eos = crate::material::eos::SolidEos::new(
            solid.density,
            solid.elastic.bulk(),
            cs.reference_pressure,
            cs.reference_pressure,
            // c_v only enters the heat exchange, which requires it;
            // otherwise steel's value stands in.
            spec.cv.unwrap_or(450.0),
        )
        .map_err(|e| SceneError::new(format!("materials[{spec_index}]"), e.to_string()))?;
        let rigid_velocity = if spec.rigid {
            let v = scene
                .objects
                .iter()
                .find(|o| o.material == spec.name)
                .and_then(|o| o.velocity.as_deref())
                .map(to_vec::<D>)
                .unwrap_or_else(SVector::zeros);
            Some(v)
        } else {
            None
        };
        specs.push(crate::coupling::SolidFieldSpec {
            name: spec.name.clone(),
            particles: solid_run
                .particles
                .select(|p| solid_run.particles.material[p] as usize == k),
            eos,
            rigid_velocity,
        });
    }
    if specs.is_empty() {
        return Err(SceneError::new(
            "materials",
            "a coupled scene needs at least one solid material",
        ));
    }
    let coupling = crate::coupling::CouplingParams {
        p_ref: cs.reference_pressure,
        solid_temperature: cs.solid_temperature,
        momentum_exchange: cs.momentum_exchange,
        heat_exchange: cs.heat_exchange,
        trace_fraction: cs.solid_trace_fraction,
        rigid_interface: cs.rigid_interface,
        ..Default::default()
    };
    let SolidRun {
        grid,
        materials,
        params: mpm,
        body,
        ..
    } = solid_run;
    let mut run = crate::coupling::CoupledRun::with_fields(
        grid,
        materials,
        specs,
        mpm,
        state,
        params,
        coupling,
        scene.time.cfl.min(0.9),
    )
    .map_err(|e| SceneError::new("materials", e.to_string()))?;
    run.body = body;
    run.rigid_ramp = cs.rigid_ramp;
    if scene.time.mode == Mode::Implicit {
        // Implicit MPM for every deformable field with the implicit
        // pressure (time.dt: the step, cut on a failed solve).
        let min_mass = run
            .fields
            .iter()
            .flat_map(|f| f.particles.mass.iter().copied())
            .fold(f64::INFINITY, f64::min);
        let mut params = implicit_params(scene, min_mass);
        let dt = scene.time.dt.unwrap_or(scene.time.end);
        params.dt_max = params.dt_max.min(dt);
        run.make_implicit(params, dt)
            .map_err(|e| SceneError::new("implicit", e.to_string()))?;
        if scene.implicit.hold_solid_faces {
            run.hold_solid_faces();
        }
        let ci = &scene.implicit.coupling;
        run.iteration = CouplingIteration {
            max_iterations: ci.max_iterations,
            tolerance: ci.tolerance,
            relaxation: match ci.relaxation {
                RelaxationKind::Aitken => Relaxation::Aitken(ci.omega),
                RelaxationKind::Constant => Relaxation::Constant(ci.omega),
            },
        };
        if let Some(g) = scene.gravity.as_deref().map(to_vec::<D>) {
            for imp in run.fields.iter_mut().filter_map(|f| f.implicit.as_mut()) {
                if g.norm() > 0.0 {
                    imp.body = Some(Box::new(Uniform(g)));
                }
            }
        }
    }
    // Reactions: the reactant's field is its solid material's (one field
    // per solid material, in order), the product its fluid index.
    let solid_names: Vec<&MaterialSpec> = scene
        .materials
        .iter()
        .filter(|m| m.kind == MaterialKind::Solid)
        .collect();
    for r in &scene.reactions {
        let field = solid_names
            .iter()
            .position(|m| m.name == r.reactant)
            .expect("validated: the reactant is a solid material");
        let product = run
            .fluid
            .materials
            .iter()
            .position(|m| m.name == r.product)
            .expect("validated: the product is a fluid material");
        run.reactions.push(crate::coupling::reaction::Reaction {
            field,
            product,
            law: r.law(),
            reactant_cv: solid_names[field]
                .cv
                .expect("validated: the reactant has cv"),
            totals: Default::default(),
            dt_limit: f64::INFINITY,
        });
    }
    run.init_reactions();
    Ok(run)
}

/// Builds the multiphase run of a validated scene with a `[multiphase]`
/// table and `D == dim`: one phase per material, in scene order.
pub fn build_multiphase_run<const D: usize>(scene: &Scene) -> Result<MultiphaseRun<D>, SceneError> {
    let spec = scene
        .multiphase
        .as_ref()
        .ok_or_else(|| SceneError::new("multiphase", "missing"))?;
    let grid = grid_of::<D>(scene);
    let materials = particle_materials(scene, &grid)?;
    let particles = fill_particles(scene, &grid, &materials)?;
    let nodes = grid.num_nodes();
    let phases: Vec<Phase<D>> = (0..materials.len())
        .map(|k| {
            let p = particles.select(|i| particles.material[i] as usize == k);
            Phase::new(k, p, nodes)
        })
        .collect();
    if let Some(k) = phases.iter().position(|ph| ph.particles.is_empty()) {
        return Err(SceneError::new(
            "objects",
            format!(
                "material `{}` has no object: every phase needs points",
                materials[k].name
            ),
        ));
    }
    let gas = materials.iter().position(|m| m.gas().is_some());
    let min_mass = particles.mass.iter().cloned().fold(f64::INFINITY, f64::min);
    let params = ExplicitParams {
        shape: scene.mpm.shape,
        scheme: UpdateScheme::Usl,
        mass_floor: 1e-12 * min_mass,
        damping: scene.mpm.damping,
        pic_fraction: scene.mpm.pic_fraction,
    };
    let time = TimeControl {
        end: scene.time.end,
        cfl: scene.time.cfl,
        dt: scene.time.dt,
        max_steps: scene.time.max_steps,
    };
    let mut run = MultiphaseRun::new(
        grid,
        materials,
        phases,
        gas,
        params,
        spec.params(
            &scene
                .materials
                .iter()
                .map(|m| m.name.as_str())
                .collect::<Vec<_>>(),
        ),
        time,
    );
    run.nodes(0.0)
        .map_err(|e| SceneError::new("objects", format!("initial state: {e}")))?;
    if let Some(g) = &scene.gravity {
        let g = nalgebra::SVector::<f64, D>::from_fn(|d, _| g[d]);
        if g.norm() > 0.0 {
            run.gravity = g;
            run.body = Some(Box::new(Uniform(g)));
        }
    }
    Ok(run)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`RowCrossings`] classifies every point as
    /// [`Geometry::Polygon`]'s `contains` does: a dog-bone's membrane
    /// polygon against a lattice (including points on its vertices' rows)
    /// and points on a vertex.
    #[test]
    fn row_crossings_agree_with_the_polygon_rule() {
        let g = Geometry::DogBone {
            center: vec![0.1, -0.05],
            lobe_radius: 0.45,
            lobe_offset: 1.25,
            neck_half_width: 0.2,
        };
        let (vertices, closed, ..) = membrane_curve(&g, 0.025, false);
        assert!(closed);
        let poly = Geometry::Polygon {
            vertices: vertices.clone(),
        };
        let mut rows = RowCrossings {
            vertices: vertices.clone(),
            rows: std::collections::HashMap::new(),
        };
        let mut inside = 0;
        let mut points: Vec<[f64; 2]> = (0..200)
            .flat_map(|i| (0..60).map(move |j| [-1.9 + 0.019 * i as f64, -0.6 + 0.02 * j as f64]))
            .collect();
        points.extend(vertices.iter().copied());
        points.extend(vertices.iter().map(|v| [v[0] + 1e-3, v[1]]));
        for x in &points {
            let a = poly.contains(x);
            assert_eq!(rows.contains(x), a, "at {x:?}");
            inside += usize::from(a);
        }
        assert!(inside > 1000 && inside < points.len() - 1000, "{inside}");
    }
}
