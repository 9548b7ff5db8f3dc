//! Building a run from a validated scene.

use nalgebra::SVector;

use super::schema::{MaterialSpec, Scene};
use crate::error::SceneError;
use crate::grid::{Boundary, Grid};
use crate::material::{ElasticConstants, SolidMaterial, SolidModel};
use crate::mpm::explicit::Uniform;
use crate::mpm::{ExplicitParams, Particles};
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
    SolidMaterial {
        name: m.name.clone(),
        density: m.density,
        model: m.model.unwrap_or(SolidModel::NeoHookean),
        elastic,
    }
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
    Grid::new(
        to_vec::<D>(&g.lower),
        to_vec::<D>(&g.upper),
        std::array::from_fn(|d| g.cells[d]),
        bc,
    )
}

/// Fills every object with particles: `ppc` per cell per direction at the
/// centres of a regular sub-lattice of each grid cell, kept where the point is
/// inside the object's region. Volume = cell volume / ppc^D, mass = ρ₀ V.
pub fn fill_particles<const D: usize>(
    scene: &Scene,
    grid: &Grid<D>,
    materials: &[SolidMaterial],
) -> Result<Particles<D>, SceneError> {
    let mut particles = Particles::<D>::default();
    for (oi, obj) in scene.objects.iter().enumerate() {
        let mat_index = materials
            .iter()
            .position(|m| m.name == obj.material)
            .ok_or_else(|| {
                SceneError::new(format!("objects[{oi}].material"), "unknown material")
            })?;
        let rho = materials[mat_index].density;
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
        let per_cell = ppc.pow(D as u32);
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
                    x[d] =
                        grid.lower[d] + grid.h[d] * (c[d] as f64 + (s as f64 + 0.5) / ppc as f64);
                }
                if obj.geometry.contains(&x) {
                    particles.push(
                        SVector::from(x),
                        vel,
                        rho * vol,
                        vol,
                        half,
                        mat_index as u16,
                    );
                }
            }
        }
        if particles.len() == before {
            return Err(SceneError::new(
                format!("objects[{oi}].geometry"),
                "the region contains no particle position inside the grid (make it larger \
                 than a particle spacing, or refine the grid)",
            ));
        }
    }
    Ok(particles)
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
    let materials: Vec<SolidMaterial> = scene.materials.iter().map(solid_material).collect();
    let particles = fill_particles(scene, &grid, &materials)?;
    let min_mass = particles.mass.iter().cloned().fold(f64::INFINITY, f64::min);
    let params = ExplicitParams {
        shape: scene.mpm.shape,
        scheme: scene.mpm.update,
        mass_floor: 1e-12 * min_mass,
        damping: scene.mpm.damping,
    };
    let time = TimeControl {
        end: scene.time.end,
        cfl: scene.time.cfl,
        dt: scene.time.dt,
        max_steps: scene.time.max_steps,
    };
    let mut run = SolidRun::new(grid, materials, particles, params, time);
    if let Some(g) = &scene.gravity {
        let g = to_vec::<D>(g);
        if g.norm() > 0.0 {
            run.gravity = g;
            run.body = Some(Box::new(Uniform(g)));
        }
    }
    Ok(run)
}
