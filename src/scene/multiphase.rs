//! Scene keys of Zhang's multiphase model (`[multiphase]`), their
//! validation (key paths named) and building the run.

use serde::{Deserialize, Serialize};

use crate::error::SceneError;
use crate::multiphase::{Constraint, MultiphaseParams};

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
    /// Vanishing phases, in [0, 1) (default 0: Zhang's closure exactly):
    /// a point takes the volume mismatch in proportion to κ_p/Σθκ, about
    /// 1/θ for a gas point where the gas has fraction θ; with `f > 0` at
    /// most 1/f times its share (and its sound speed is raised by at most
    /// 1/√f for the stable step). Gas caught in thin pockets between
    /// colliding solids (the rod case) otherwise takes the solids' whole
    /// mismatch and is crushed and heated without bound, collapsing the
    /// step. Where it acts, Σθ is not held (the pocket is below the grid's
    /// resolution).
    #[serde(default)]
    pub min_fraction: f64,
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
    /// Checks the table's values and names against the scene's material
    /// names.
    pub(super) fn validate_table(&self, names: &[&str]) -> Result<(), SceneError> {
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
        if !(0.0..1.0).contains(&self.min_fraction) {
            return Err(err(
                "multiphase.min_fraction",
                format!("must be in [0, 1) (got {})", self.min_fraction),
            ));
        }
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
            let same = |q: &PairSpec| {
                let (a, b) = (&q.materials[0], &q.materials[1]);
                (a, b) == (&pr.materials[0], &pr.materials[1])
                    || (b, a) == (&pr.materials[0], &pr.materials[1])
            };
            if let Some(j) = self.pairs[..k].iter().position(same) {
                return Err(err(
                    p("materials"),
                    format!(
                        "the pair `{}`–`{}` is already given in multiphase.pairs[{j}]; one drag \
                         coefficient per pair",
                        pr.materials[0], pr.materials[1]
                    ),
                ));
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
            if let Some(j) = self.phases[..k]
                .iter()
                .position(|q| q.material == ph.material)
            {
                return Err(err(
                    p("material"),
                    format!(
                        "`{}` is already given in multiphase.phases[{j}]; one α per phase",
                        ph.material
                    ),
                ));
            }
            if !(0.0..=1.0).contains(&ph.alpha) {
                return Err(err(
                    p("alpha"),
                    format!("must be in [0, 1] (got {})", ph.alpha),
                ));
            }
        }
        Ok(())
    }

    /// The model parameters for the scene's materials in scene order.
    pub(super) fn params(&self, names: &[&str]) -> MultiphaseParams {
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
            max_share: if self.min_fraction > 0.0 {
                1.0 / self.min_fraction
            } else {
                f64::INFINITY
            },
        }
    }
}
