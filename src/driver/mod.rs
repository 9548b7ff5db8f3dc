//! The one run loop and the models it drives.
//!
//! [`run_scene`] builds the scene's model — explicit solid, implicit solid,
//! ICE (explicit or semi-implicit pressure), coupled MPM-ICE or membrane
//! finite elements — and hands
//! it to [`run_model`], which owns time control, retries, the watchdog,
//! snapshots, history, checkpoints, restart, a clean stop on interrupt,
//! progress and the summary. A new system implements [`Model`] (see
//! [`model`]) and is run by the same loop.

pub mod model;
pub mod models;
pub mod outputs;
pub mod run_loop;
pub mod summary;

pub use model::{DtRequest, Model, StepStats};
pub use run_loop::{run_model, scene_hash, RunOptions, MAX_RETRIES};
pub use summary::{IterationStats, Summary};

use crate::error::{Error, Result};
use crate::scene::{MaterialKind, Mode, Scene};

/// Builds the scene's model and runs it with outputs in `opts.out_dir`
/// (continuing from `opts.restart` if given).
///
/// # Errors
/// As [`run_model`]; a scene that cannot be built names its key.
pub fn run_scene(scene: &Scene, opts: &RunOptions) -> Result<Summary> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads)
        .build()
        .map_err(|e| Error::io(&opts.out_dir, std::io::Error::other(e.to_string())))?;
    let threads = pool.current_num_threads();
    if !scene.membrane_elements.is_empty() {
        return pool.install(|| {
            let fe = models::MembraneFe::from_scene(scene)?;
            if scene.grid.dim == 0 {
                let mut m = fe;
                return run_model(&mut m, scene, opts, threads);
            }
            // Lian Sec. 5–6: MPM bodies and membranes in grid contact.
            let solid = models::ExplicitSolid {
                run: crate::scene::build_solid_run::<3>(scene)?,
            };
            let law = scene.contact.clone().unwrap_or_default().law();
            let mut m = models::MembraneContact::new(solid, fe, law);
            run_model(&mut m, scene, opts, threads)
        });
    }
    pool.install(|| match scene.grid.dim {
        1 => run_dim::<1>(scene, opts, threads),
        2 => run_dim::<2>(scene, opts, threads),
        _ => run_dim::<3>(scene, opts, threads),
    })
}

fn run_dim<const D: usize>(scene: &Scene, opts: &RunOptions, threads: usize) -> Result<Summary> {
    // Gas points (fluids with frame = "particles") run with the solids in
    // the explicit MPM model (York Eq. 17: one nodal velocity field).
    let solid = scene
        .materials
        .iter()
        .any(|m| m.kind == MaterialKind::Solid);
    let fluid = scene.materials.iter().any(|m| m.in_cells());
    if scene.multiphase.is_some() {
        let mut m = models::Multiphase {
            run: crate::scene::build_multiphase_run::<D>(scene)?,
        };
        run_model(&mut m, scene, opts, threads)
    } else if solid && fluid {
        let mut m = models::Coupled {
            run: crate::scene::build_coupled_run::<D>(scene)?,
        };
        run_model(&mut m, scene, opts, threads)
    } else if fluid {
        let (mut state, params) = crate::scene::build_fluid_run::<D>(scene)?;
        crate::ice::equilibrate(&mut state, &params)?;
        let ws = crate::ice::IceWorkspace::new(&state);
        let mut m = models::Fluid { state, params, ws };
        run_model(&mut m, scene, opts, threads)
    } else if scene.time.mode == Mode::Implicit {
        let mut m = models::ImplicitSolid {
            run: crate::scene::build_implicit_run::<D>(scene)?,
            shape: models::scene_name(&scene.mpm.shape),
        };
        run_model(&mut m, scene, opts, threads)
    } else {
        let mut m = models::ExplicitSolid {
            run: crate::scene::build_solid_run::<D>(scene)?,
        };
        run_model(&mut m, scene, opts, threads)
    }
}
