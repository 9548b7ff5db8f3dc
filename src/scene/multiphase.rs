//! Scene keys of Zhang's multiphase model (`[multiphase]`), their
//! validation (key paths named) and building the run.

use serde::{Deserialize, Serialize};

use crate::error::SceneError;
use crate::grid::Boundary;
use crate::mpm::explicit::Uniform;
use crate::mpm::{ExplicitParams, UpdateScheme};
use crate::multiphase::{Constraint, MultiphaseParams, MultiphaseRun, Phase, MAX_PHASES};
use crate::stepper::TimeControl;

use super::schema::{MaterialKind, Mode, Scene};

/// Zhang's multi-velocity, multi-pressure phases (Zhang Secs. 2–3): every
/// material on points (solids and gas points, `frame = "particles"`) is a
/// phase with its own velocity field. The table's presence selects the
/// model.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MultiphaseSpec {
    /// `weak` (Eq. 18, default), `strong` (Eq. 7 through Eq. 15) or
    /// `eulerian` (Eq. 2 as printed).
    #[serde(default)]
    pub constraint: Constraint,
    /// Drag coefficient K ≥ 0 [kg/(m³ s)] of Eq. 5 between every pair of
    /// phases (default 0); `pairs` overrides it pair by pair.
    #[serde(default)]
    pub drag: f64,
    /// α of Eq. 1 for every phase, in [0, 1] (default 1: the phase's volume
    /// follows its own velocity divergence, as a continuous phase; 0: all
    /// of it through the compressibility share B, as dispersed grains).
    #[serde(default = "one")]
    pub alpha: f64,
    /// Per-pair drag coefficients.
    #[serde(default)]
    pub pairs: Vec<PairSpec>,
    /// Per-phase α.
    #[serde(default)]
    pub phases: Vec<PhaseSpec>,
}

fn one() -> f64 {
    1.0
}

/// The drag coefficient of one pair of phases.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairSpec {
    /// The two materials' names.
    pub materials: [String; 2],
    /// K ≥ 0 [kg/(m³ s)].
    pub drag: f64,
}

/// α of one phase.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseSpec {
    /// The material's name.
    pub material: String,
    /// α in [0, 1].
    pub alpha: f64,
}

fn err(path: impl Into<String>, msg: impl Into<String>) -> SceneError {
    SceneError::new(path, msg)
}

impl MultiphaseSpec {
    /// Checks the table against the scene's materials.
    pub(super) fn validate(&self, scene: &Scene) -> Result<(), SceneError> {
        if !(self.drag.is_finite() && self.drag >= 0.0) {
            return Err(err(
                "multiphase.drag",
                format!("must be finite and >= 0 [kg/(m^3 s)] (got {})", self.drag),
            ));
        }
        if !(0.0..=1.0).contains(&self.alpha) {
            return Err(err(
                "multiphase.alpha",
                format!("must be in [0, 1] (got {})", self.alpha),
            ));
        }
        let names: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
        let known = |path: String, n: &str| -> Result<(), SceneError> {
            if names.contains(&n) {
                Ok(())
            } else {
                Err(err(
                    path,
                    format!("unknown material `{n}`; defined: {}", names.join(", ")),
                ))
            }
        };
        for (k, pr) in self.pairs.iter().enumerate() {
            let p = |s: &str| format!("multiphase.pairs[{k}].{s}");
            known(p("materials[0]"), &pr.materials[0])?;
            known(p("materials[1]"), &pr.materials[1])?;
            if pr.materials[0] == pr.materials[1] {
                return Err(err(p("materials"), "must name two different materials"));
            }
            if !(pr.drag.is_finite() && pr.drag >= 0.0) {
                return Err(err(
                    p("drag"),
                    format!("must be finite and >= 0 [kg/(m^3 s)] (got {})", pr.drag),
                ));
            }
        }
        for (k, ph) in self.phases.iter().enumerate() {
            let p = |s: &str| format!("multiphase.phases[{k}].{s}");
            known(p("material"), &ph.material)?;
            if !(0.0..=1.0).contains(&ph.alpha) {
                return Err(err(
                    p("alpha"),
                    format!("must be in [0, 1] (got {})", ph.alpha),
                ));
            }
        }
        if scene.time.mode != Mode::Explicit {
            return Err(err(
                "time.mode",
                format!(
                    "the multiphase model is explicit; allowed: explicit (got {})",
                    scene.time.mode.name()
                ),
            ));
        }
        if scene.grid.axisymmetric {
            return Err(err(
                "grid.axisymmetric",
                "the multiphase model runs in plane 2D and 3D; allowed: false",
            ));
        }
        if !matches!(scene.mpm.update, None | Some(UpdateScheme::Usl)) {
            return Err(err(
                "mpm.update",
                "the multiphase model updates the stress last; allowed: usl",
            ));
        }
        for (i, m) in scene.materials.iter().enumerate() {
            if !(m.kind == MaterialKind::Solid || m.is_gas_point()) {
                return Err(err(
                    format!("materials[{i}]"),
                    format!(
                        "`{}`: every phase of the multiphase model lives on points; allowed: \
                         type = \"solid\", or a fluid with frame = \"particles\"",
                        m.name
                    ),
                ));
            }
            if m.rigid {
                return Err(err(
                    format!("materials[{i}].rigid"),
                    "not offered in the multiphase model (rigid solids ride MPM-ICE)",
                ));
            }
        }
        let gases: Vec<usize> = (0..scene.materials.len())
            .filter(|&i| scene.materials[i].is_gas_point())
            .collect();
        if gases.len() > 1 {
            return Err(err(
                format!("materials[{}]", gases[1]),
                "the multiphase model has one gas pressure p_g (Zhang Eq. 4): at most one gas \
                 material",
            ));
        }
        if scene.materials.len() > MAX_PHASES {
            return Err(err(
                "materials",
                format!(
                    "at most {MAX_PHASES} phases (got {})",
                    scene.materials.len()
                ),
            ));
        }
        for (axis, faces) in scene.grid.boundary.faces().iter().enumerate() {
            if faces[0].0 == Some(Boundary::Periodic) && scene.grid.cells[axis] < 4 {
                return Err(err(
                    format!("grid.cells[{axis}]"),
                    "a periodic axis needs at least 4 cells",
                ));
            }
        }
        Ok(())
    }

    /// The model parameters for the scene's materials in scene order.
    fn params(&self, scene: &Scene) -> MultiphaseParams {
        let names: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
        let n = names.len();
        let at = |s: &str| names.iter().position(|&x| x == s).unwrap_or(0);
        let mut drag = vec![self.drag; n * n];
        for i in 0..n {
            drag[i * n + i] = 0.0;
        }
        for pr in &self.pairs {
            let (a, b) = (at(&pr.materials[0]), at(&pr.materials[1]));
            drag[a * n + b] = pr.drag;
            drag[b * n + a] = pr.drag;
        }
        let mut alpha = vec![self.alpha; n];
        for ph in &self.phases {
            alpha[at(&ph.material)] = ph.alpha;
        }
        MultiphaseParams {
            constraint: self.constraint,
            drag,
            alpha,
        }
    }
}

/// Builds the multiphase run of a validated scene with a `[multiphase]`
/// table and `D == dim`: one phase per material, in scene order.
pub fn build_multiphase_run<const D: usize>(scene: &Scene) -> Result<MultiphaseRun<D>, SceneError> {
    let spec = scene
        .multiphase
        .as_ref()
        .ok_or_else(|| err("multiphase", "missing"))?;
    let grid = super::grid_of::<D>(scene);
    let materials = super::build::particle_materials(scene, &grid)?;
    let particles = super::fill_particles(scene, &grid, &materials)?;
    let nodes = grid.num_nodes();
    let phases: Vec<Phase<D>> = (0..materials.len())
        .map(|k| {
            let p = particles.select(|i| particles.material[i] as usize == k);
            Phase::new(k, p, nodes)
        })
        .collect();
    if let Some(k) = phases.iter().position(|ph| ph.particles.is_empty()) {
        return Err(err(
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
        spec.params(scene),
        time,
    );
    run.nodes(0.0)
        .map_err(|e| err("objects", format!("initial state: {e}")))?;
    if let Some(g) = &scene.gravity {
        let g = nalgebra::SVector::<f64, D>::from_fn(|d, _| g[d]);
        if g.norm() > 0.0 {
            run.gravity = g;
            run.body = Some(Box::new(Uniform(g)));
        }
    }
    Ok(run)
}
