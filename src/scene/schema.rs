//! The scene schema. Every table rejects unknown keys.

use serde::{Deserialize, Serialize};

use crate::error::SceneError;
use crate::grid::Boundary;
use crate::material::eos::{EosError, FluidEos, IdealGas, Jwl, MieGruneisen, StiffenedGas};
use crate::material::{PointDensity, SolidModel};
use crate::mpm::UpdateScheme;
use crate::multiphase::MAX_PHASES;
use crate::shape::ShapeKind;

/// A whole scene.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Free-text description.
    #[serde(default)]
    pub description: String,
    /// The background grid (absent in a scene of membrane elements only).
    #[serde(default = "GridSpec::absent")]
    pub grid: GridSpec,
    /// Time integration.
    pub time: TimeSpec,
    /// MPM discretisation choices.
    #[serde(default)]
    pub mpm: MpmSpec,
    /// Materials, referred to by name.
    #[serde(default)]
    pub materials: Vec<MaterialSpec>,
    /// Bodies filled with particles.
    #[serde(default)]
    pub objects: Vec<ObjectSpec>,
    /// Fluid discretisation choices.
    #[serde(default)]
    pub fluid: FluidSpec,
    /// Implicit MPM settings (`time.mode = "implicit"`).
    #[serde(default)]
    pub implicit: ImplicitSpec,
    /// Initial fluid states by region, applied in order (a later region
    /// overrides an earlier one where both contain a cell centre).
    #[serde(default)]
    pub regions: Vec<RegionSpec>,
    /// Uniform body force per unit mass (length `dim`), e.g. `[0, -9.81]`.
    #[serde(default)]
    pub gravity: Option<Vec<f64>>,
    /// MPM-ICE coupling settings (scenes with solid and fluid materials).
    #[serde(default)]
    pub coupling: CouplingSpec,
    /// Internal-energy sources of fluid materials.
    #[serde(default)]
    pub heat_sources: Vec<HeatSourceSpec>,
    /// Reactions of coupled scenes: a solid reactant burning on its surface
    /// into a fluid product (Guilkey Sec. 5).
    #[serde(default)]
    pub reactions: Vec<ReactionSpec>,
    /// What to write.
    #[serde(default)]
    pub output: OutputSpec,
    /// Lian's membrane finite elements (Sec. 4), each a mesh with its own
    /// nodes: alone (no grid, materials or objects) or in a 3D scene with
    /// MPM bodies, joined to them by the grid contact (`[contact]`).
    #[serde(default)]
    pub membrane_elements: Vec<super::membrane_elements::MembraneElementsSpec>,
    /// Lian's grid contact between the MPM bodies and the membrane elements
    /// (Sec. 5); scenes with both.
    #[serde(default)]
    pub contact: Option<ContactSpec>,
    /// Zhang's multiphase model: every material on points is a phase with
    /// its own velocity field (the table's presence selects the model).
    #[serde(default)]
    pub multiphase: Option<super::multiphase::MultiphaseSpec>,
}

/// How membrane elements and MPM bodies touch on the grid (Lian Sec. 5);
/// the default (no `[contact]` table) is free slip.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// `stick` (Lian Eq. 55) or `slip` (Coulomb, Eq. 58).
    #[serde(default)]
    pub law: ContactLawSpec,
    /// Coulomb friction coefficient μ ≥ 0 (`slip`; 0 = free slip).
    #[serde(default)]
    pub friction: f64,
    /// Where the force may act: `gap` (Lian Eq. 52 and the bodies close
    /// their measured gap within the step, default) or `approach` (Lian
    /// Eq. 52 alone, as published).
    #[serde(default)]
    pub detection: ContactDetectionSpec,
}

/// The contact detection's name in a scene.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactDetectionSpec {
    /// Lian's rule: both bodies reach the node and approach.
    Approach,
    /// Lian's rule and a closing gap between particle surface and points.
    #[default]
    Gap,
}

/// The contact law's name in a scene.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactLawSpec {
    /// Shared velocity at contact nodes.
    Stick,
    /// Normal contact with Coulomb friction.
    #[default]
    Slip,
}

impl ContactSpec {
    /// The kernel's law.
    pub fn law(&self) -> crate::contact::ContactLaw {
        match self.law {
            ContactLawSpec::Stick => crate::contact::ContactLaw::Stick,
            ContactLawSpec::Slip => crate::contact::ContactLaw::Slip {
                friction: self.friction,
            },
        }
    }

    /// The kernel's detection rule.
    pub fn detection(&self) -> crate::contact::ContactDetection {
        match self.detection {
            ContactDetectionSpec::Approach => crate::contact::ContactDetection::Approach,
            ContactDetectionSpec::Gap => crate::contact::ContactDetection::Gap,
        }
    }
}

/// The background grid.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Spatial dimension: 1, 2 (plane strain) or 3.
    pub dim: usize,
    /// Lower corner (length `dim`).
    pub lower: Vec<f64>,
    /// Upper corner (length `dim`).
    pub upper: Vec<f64>,
    /// Cells per direction (length `dim`).
    pub cells: Vec<usize>,
    /// Boundary condition per face.
    #[serde(default)]
    pub boundary: BoundarySpec,
    /// Axisymmetric r–z geometry (explicit solids and gas points, `dim = 2`):
    /// x is the radius r ≥ 0 and y the axial coordinate z; particle volumes
    /// and masses, forces and energies are per radian. With `lower[0] = 0`
    /// the face `x_lower` is the axis and must be `symmetry`.
    #[serde(default)]
    pub axisymmetric: bool,
}

/// Boundary condition per face; faces not given are `free`.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    /// Face x = lower.
    pub x_lower: Option<Boundary>,
    /// Face x = upper.
    pub x_upper: Option<Boundary>,
    /// Face y = lower.
    pub y_lower: Option<Boundary>,
    /// Face y = upper.
    pub y_upper: Option<Boundary>,
    /// Face z = lower.
    pub z_lower: Option<Boundary>,
    /// Face z = upper.
    pub z_upper: Option<Boundary>,
}

impl BoundarySpec {
    /// The faces as `[[lower, upper]; 3]` with their key names.
    pub fn faces(&self) -> [[(Option<Boundary>, &'static str); 2]; 3] {
        [
            [(self.x_lower, "x_lower"), (self.x_upper, "x_upper")],
            [(self.y_lower, "y_lower"), (self.y_upper, "y_upper")],
            [(self.z_lower, "z_lower"), (self.z_upper, "z_upper")],
        ]
    }
}

/// Time-integration mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Explicit in every material.
    #[default]
    Explicit,
    /// Implicit pressure, explicit MPM.
    SemiImplicit,
    /// Implicit pressure and implicit MPM.
    Implicit,
}

impl Mode {
    /// Scene-file name.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Explicit => "explicit",
            Mode::SemiImplicit => "semi_implicit",
            Mode::Implicit => "implicit",
        }
    }
}

/// Where the watchdog's last good state is kept (`time.last_good`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum LastGood {
    /// In memory up to [`LAST_GOOD_MEMORY_LIMIT`] bytes of state, on disk
    /// above.
    #[default]
    Auto,
    /// Always in memory: the fastest, at the cost of a copy of the state.
    Memory,
    /// Always on disk, in the output folder's `.last_good/`.
    Disk,
}

impl LastGood {
    fn is_auto(&self) -> bool {
        *self == LastGood::Auto
    }
}

/// The size of state above which `time.last_good = "auto"` keeps the last
/// good state on disk: 64 MiB, about 350 000 2D particles.
pub const LAST_GOOD_MEMORY_LIMIT: u64 = 64 << 20;

/// Time integration.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// End time (> 0).
    pub end: f64,
    /// Courant number, 0 < cfl ≤ 1.
    #[serde(default = "default_cfl")]
    pub cfl: f64,
    /// Fixed timestep; when absent the CFL condition sets it every step.
    pub dt: Option<f64>,
    /// Integration mode.
    #[serde(default)]
    pub mode: Mode,
    /// Stop after this many steps even before `end`.
    pub max_steps: Option<u64>,
    /// Steps between watchdog scans for non-finite or impossible values
    /// (NaN, negative mass, density or internal energy, J ≤ 0); each
    /// passed scan also keeps the state as the last good one, which a
    /// failure writes as a checkpoint. 0 turns the watchdog off.
    #[serde(default = "default_watchdog_interval")]
    pub watchdog_interval: u64,
    /// Where the watchdog keeps the last good state: in memory, or written
    /// to the output folder's `.last_good/` (removed when the run ends) so
    /// that a large run does not hold a second copy of its state. Default
    /// `auto`: on disk once the state passes [`LAST_GOOD_MEMORY_LIMIT`].
    #[serde(default, skip_serializing_if = "LastGood::is_auto")]
    pub last_good: LastGood,
    /// The run stops when a step's Δt falls below this fraction of the
    /// largest Δt of the run so far (0 < fraction < 1; default 1e-6); a drop
    /// by 100× warns once.
    #[serde(
        default = "default_min_dt_fraction",
        skip_serializing_if = "is_default_min_dt_fraction"
    )]
    pub min_dt_fraction: f64,
    /// The run is refused before its first step when `(end − t) / Δt`
    /// exceeds this many steps and `max_steps` does not bound it (≥ 1;
    /// default 1e9).
    #[serde(
        default = "default_max_projected_steps",
        skip_serializing_if = "is_default_max_projected_steps"
    )]
    pub max_projected_steps: f64,
}

/// Default `time.watchdog_interval`: a scan and the copy of the state it
/// passes cost over a quarter of an explicit MPM step (66k particles: 0.25 ms
/// scan + 1.16 ms copy against a 5.1 ms step; `probes/src/bin/run_loop_cost.rs`),
/// so every 50 steps they add about 0.5 % to a run.
fn default_watchdog_interval() -> u64 {
    50
}

/// Default `time.min_dt_fraction`.
pub const DEFAULT_MIN_DT_FRACTION: f64 = 1e-6;
/// Default `time.max_projected_steps`.
pub const DEFAULT_MAX_PROJECTED_STEPS: f64 = 1e9;

fn default_min_dt_fraction() -> f64 {
    DEFAULT_MIN_DT_FRACTION
}
fn default_max_projected_steps() -> f64 {
    DEFAULT_MAX_PROJECTED_STEPS
}
// Defaults are not serialised: scene hashes of earlier checkpoints stay.
fn is_default_min_dt_fraction(v: &f64) -> bool {
    *v == DEFAULT_MIN_DT_FRACTION
}
fn is_default_max_projected_steps(v: &f64) -> bool {
    *v == DEFAULT_MAX_PROJECTED_STEPS
}

fn default_cfl() -> f64 {
    0.4
}

/// MPM discretisation choices.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MpmSpec {
    /// Shape function.
    #[serde(default = "default_shape")]
    pub shape: ShapeKind,
    /// Stress update ordering (default: `musl` in scenes with gas points,
    /// York Sec. 2.2; `usl` otherwise; see [`Scene::mpm_update`]).
    #[serde(default)]
    pub update: Option<UpdateScheme>,
    /// Default particles per cell per direction.
    #[serde(default = "default_ppc")]
    pub particles_per_cell: usize,
    /// Mass-proportional damping α ≥ 0 [1/s] (quasistatic end states).
    #[serde(default)]
    pub damping: f64,
    /// PIC share β ∈ [0, 1] of the particle velocity update (0: FLIP).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub pic_fraction: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

fn default_shape() -> ShapeKind {
    ShapeKind::QuadraticBspline
}
fn default_ppc() -> usize {
    2
}

impl Default for MpmSpec {
    fn default() -> Self {
        Self {
            shape: default_shape(),
            update: None,
            particles_per_cell: default_ppc(),
            damping: 0.0,
            pic_fraction: 0.0,
        }
    }
}

/// Kind of material.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MaterialKind {
    /// A solid on material points.
    Solid,
    /// A fluid in cell-centred multi-material ICE.
    Fluid,
    /// A membrane on one layer of ordered material points (York Sec. 3.2):
    /// `density`, `youngs_modulus`, `poisson_ratio`, `thickness`; its
    /// objects are curves (`polyline`, `circle`, `dog_bone`) with a
    /// `spacing`.
    Membrane,
}

/// Where a fluid material lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Frame {
    /// In the cells (multi-material ICE); its state comes from `[[regions]]`.
    #[default]
    Cells,
    /// On material points (York Sec. 3.3: gas points); it fills
    /// `[[objects]]` with a `density` and a `pressure` each.
    Particles,
}

/// York's artificial viscosity of gas points (York Eqs. 24–25), in the
/// table `materials[i].artificial_viscosity`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArtificialViscositySpec {
    /// Geometric length g as a multiple of the smallest cell size, > 0
    /// (York Sec. 4.1: √2).
    #[serde(default = "default_g_over_dx")]
    pub g_over_dx: f64,
    /// Artificial bulk coefficient κ̃ ≥ 0 (York: 0.75; 0 turns q off).
    #[serde(default = "default_kappa")]
    pub kappa: f64,
    /// Linear-term coefficient c₁ ≥ 0 (York: 1).
    #[serde(default = "default_c")]
    pub c1: f64,
    /// Quadratic-term coefficient c₂ ≥ 0 (York: 1).
    #[serde(default = "default_c")]
    pub c2: f64,
}

fn default_g_over_dx() -> f64 {
    crate::material::ArtificialViscosity::DEFAULT_G_OVER_DX
}
fn default_kappa() -> f64 {
    crate::material::ArtificialViscosity::DEFAULT_KAPPA
}
fn default_c() -> f64 {
    crate::material::ArtificialViscosity::DEFAULT_C1
}

impl Default for ArtificialViscositySpec {
    fn default() -> Self {
        Self {
            g_over_dx: default_g_over_dx(),
            kappa: default_kappa(),
            c1: default_c(),
            c2: crate::material::ArtificialViscosity::DEFAULT_C2,
        }
    }
}

/// The flow-stress law of a plastic solid (`materials[i].plasticity.flow`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FlowKind {
    /// σ_y = yield_stress + hardening_modulus ε̄.
    Linear,
    /// σ_y = yield_stress + hardening_coefficient ε̄^hardening_exponent.
    PowerLaw,
    /// Johnson–Cook: (a + b ε̄ⁿ)(1 + c ln ε̇*)(1 − T*ᵐ).
    JohnsonCook,
}

/// J2 plasticity of a solid (`materials[i].plasticity`): with
/// `model = "linear_elastic"` on the hypo-elastic path (explicit mode), with
/// `model = "hencky"` in the multiplicative split F = Fₑ Fₚ (explicit or
/// implicit mode; yield on the Kirchhoff stress). Keys by `flow`: `linear`
/// needs `yield_stress` (and `hardening_modulus`, default 0); `power_law`
/// needs `yield_stress`, `hardening_coefficient`, `hardening_exponent`;
/// `johnson_cook` needs `a`, `b`, `n`, `c`, `m`, `melt_temperature` and
/// `specific_heat` (`reference_rate` default 1 /s, `room_temperature`
/// default 300 K, the particles' initial temperature).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlasticitySpec {
    /// Flow-stress law.
    pub flow: FlowKind,
    /// Initial yield stress σ₀ ≥ 0 \[Pa\] (linear, power_law).
    pub yield_stress: Option<f64>,
    /// Hardening modulus H ≥ 0 \[Pa\] (linear; default 0: perfectly plastic).
    pub hardening_modulus: Option<f64>,
    /// Strength coefficient K ≥ 0 \[Pa\] (power_law).
    pub hardening_coefficient: Option<f64>,
    /// Hardening exponent in (0, 1] (power_law).
    pub hardening_exponent: Option<f64>,
    /// Johnson–Cook A \[Pa\].
    pub a: Option<f64>,
    /// Johnson–Cook B \[Pa\].
    pub b: Option<f64>,
    /// Johnson–Cook n in (0, 1].
    pub n: Option<f64>,
    /// Johnson–Cook C ≥ 0.
    pub c: Option<f64>,
    /// Johnson–Cook m > 0.
    pub m: Option<f64>,
    /// Johnson–Cook reference strain rate ε̇₀ > 0 [1/s] (default 1).
    pub reference_rate: Option<f64>,
    /// Johnson–Cook room temperature \[K\] (default 300).
    pub room_temperature: Option<f64>,
    /// Johnson–Cook melting temperature \[K\] (> room_temperature).
    pub melt_temperature: Option<f64>,
    /// Taylor–Quinney fraction β of plastic work turned into heat, in
    /// [0, 1] (default 0.9).
    pub taylor_quinney: Option<f64>,
    /// Specific heat c_p > 0 [J/(kg K)] (johnson_cook: required; it heats
    /// the point adiabatically).
    pub specific_heat: Option<f64>,
}

impl PlasticitySpec {
    /// The J2 model, or the first key that is missing or out of range
    /// (path relative to the plasticity table).
    ///
    /// # Errors
    /// A missing key or a parameter out of range, named.
    pub fn j2(&self) -> Result<crate::material::plasticity::J2, (&'static str, String)> {
        use crate::material::plasticity::{FlowStress, JohnsonCook, J2};
        let need = |v: Option<f64>, key: &'static str| {
            v.ok_or((
                key,
                format!("missing; flow = \"{}\" needs it", self.flow_name()),
            ))
        };
        let flow = match self.flow {
            FlowKind::Linear => FlowStress::Linear {
                yield_stress: need(self.yield_stress, "yield_stress")?,
                hardening: self.hardening_modulus.unwrap_or(0.0),
            },
            FlowKind::PowerLaw => FlowStress::PowerLaw {
                yield_stress: need(self.yield_stress, "yield_stress")?,
                k: need(self.hardening_coefficient, "hardening_coefficient")?,
                n: need(self.hardening_exponent, "hardening_exponent")?,
            },
            FlowKind::JohnsonCook => FlowStress::JohnsonCook(JohnsonCook {
                a: need(self.a, "a")?,
                b: need(self.b, "b")?,
                n: need(self.n, "n")?,
                c: need(self.c, "c")?,
                m: need(self.m, "m")?,
                rate0: self.reference_rate.unwrap_or(1.0),
                t_room: self.room_temperature.unwrap_or(300.0),
                t_melt: need(self.melt_temperature, "melt_temperature")?,
            }),
        };
        let specific_heat = match self.flow {
            FlowKind::JohnsonCook => need(self.specific_heat, "specific_heat")?,
            _ => self.specific_heat.unwrap_or(1.0),
        };
        let j2 = J2 {
            flow,
            taylor_quinney: self.taylor_quinney.unwrap_or(0.9),
            specific_heat,
        };
        j2.validate()
            .map_err(|b| (b.key, format!("must be {}", b.allowed)))?;
        // Keys given that the law does not read.
        let jc_keys = [
            (self.a.is_some(), "a"),
            (self.b.is_some(), "b"),
            (self.n.is_some(), "n"),
            (self.c.is_some(), "c"),
            (self.m.is_some(), "m"),
            (self.reference_rate.is_some(), "reference_rate"),
            (self.room_temperature.is_some(), "room_temperature"),
            (self.melt_temperature.is_some(), "melt_temperature"),
        ];
        let power_keys = [
            (
                self.hardening_coefficient.is_some(),
                "hardening_coefficient",
            ),
            (self.hardening_exponent.is_some(), "hardening_exponent"),
        ];
        let linear_key = [(self.hardening_modulus.is_some(), "hardening_modulus")];
        let yield_key = [(self.yield_stress.is_some(), "yield_stress")];
        let unused: Vec<(bool, &'static str)> = match self.flow {
            FlowKind::Linear => [&power_keys[..], &jc_keys[..]].concat(),
            FlowKind::PowerLaw => [&linear_key[..], &jc_keys[..]].concat(),
            FlowKind::JohnsonCook => [&yield_key[..], &linear_key[..], &power_keys[..]].concat(),
        };
        if let Some((_, k)) = unused.iter().find(|(given, _)| *given) {
            return Err((k, format!("not read by flow = \"{}\"", self.flow_name())));
        }
        Ok(j2)
    }

    fn flow_name(&self) -> &'static str {
        match self.flow {
            FlowKind::Linear => "linear",
            FlowKind::PowerLaw => "power_law",
            FlowKind::JohnsonCook => "johnson_cook",
        }
    }
}

/// The failure model of a solid (`materials[i].failure.model`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FailureKind {
    /// Johnson–Cook ductile damage D = Σ Δε̄/ε_f (needs `plasticity`).
    JohnsonCook,
    /// Brittle: fails when the largest principal stress reaches
    /// `spall_strength`.
    Tensile,
}

/// Failure of a hypo-elastic or Hencky (plastic or not) solid
/// (`materials[i].failure`; `model = "linear_elastic"` or `"hencky"`,
/// explicit mode; see
/// [`crate::material::failure`]). `johnson_cook` needs `d1`, `d2`, `d3`
/// (`d4`, `d5` default 0; `reference_rate`, `room_temperature` and
/// `melt_temperature` default to the Johnson–Cook flow stress's, else 1 /s,
/// 300 K and, when `d5 ≠ 0`, required; `nonlocal_radius` defaults to 0,
/// local damage) and a `plasticity` table; `tensile` needs
/// `spall_strength`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FailureSpec {
    /// Failure model.
    pub model: FailureKind,
    /// Johnson–Cook D₁ (d1 + d2 > 0).
    pub d1: Option<f64>,
    /// Johnson–Cook D₂ ≥ 0.
    pub d2: Option<f64>,
    /// Johnson–Cook D₃.
    pub d3: Option<f64>,
    /// Johnson–Cook D₄ ≥ 0 (default 0).
    pub d4: Option<f64>,
    /// Johnson–Cook D₅ > −1 (default 0).
    pub d5: Option<f64>,
    /// Reference strain rate ε̇₀ > 0 [1/s] of ε̇*.
    pub reference_rate: Option<f64>,
    /// Room temperature \[K\] of T*.
    pub room_temperature: Option<f64>,
    /// Melting temperature \[K\] of T*.
    pub melt_temperature: Option<f64>,
    /// Spall strength σ_s > 0 \[Pa\] (tensile).
    pub spall_strength: Option<f64>,
    /// Johnson–Cook: interaction radius R ≥ 0 \[m\] of the nonlocal damage
    /// average (default 0: local damage; [`crate::mpm::nonlocal_damage`]).
    pub nonlocal_radius: Option<f64>,
}

impl FailureSpec {
    /// The failure model, given the material's plasticity (whose
    /// Johnson–Cook constants supply the defaults), or the first key that
    /// is missing, not read or out of range (path relative to the failure
    /// table; an empty key names the table itself).
    ///
    /// # Errors
    /// A missing key, a key the model does not read, or a parameter out of
    /// range, named.
    pub fn failure(
        &self,
        plasticity: Option<&crate::material::plasticity::J2>,
    ) -> Result<crate::material::failure::Failure, (&'static str, String)> {
        use crate::material::failure::{Failure, JohnsonCookFailure};
        use crate::material::plasticity::FlowStress;
        let name = match self.model {
            FailureKind::JohnsonCook => "johnson_cook",
            FailureKind::Tensile => "tensile",
        };
        let need = |v: Option<f64>, key: &'static str| {
            v.ok_or((key, format!("missing; model = \"{name}\" needs it")))
        };
        let jc_keys = [
            (self.d1.is_some(), "d1"),
            (self.d2.is_some(), "d2"),
            (self.d3.is_some(), "d3"),
            (self.d4.is_some(), "d4"),
            (self.d5.is_some(), "d5"),
            (self.reference_rate.is_some(), "reference_rate"),
            (self.nonlocal_radius.is_some(), "nonlocal_radius"),
            (self.room_temperature.is_some(), "room_temperature"),
            (self.melt_temperature.is_some(), "melt_temperature"),
        ];
        let unused: &[(bool, &'static str)] = match self.model {
            FailureKind::JohnsonCook => &[(self.spall_strength.is_some(), "spall_strength")],
            FailureKind::Tensile => &jc_keys,
        };
        if let Some((_, k)) = unused.iter().find(|(given, _)| *given) {
            return Err((k, format!("not read by model = \"{name}\"")));
        }
        let f = match self.model {
            FailureKind::Tensile => Failure::Tensile {
                spall_strength: need(self.spall_strength, "spall_strength")?,
            },
            FailureKind::JohnsonCook => {
                let Some(j2) = plasticity else {
                    return Err((
                        "",
                        "model = \"johnson_cook\" accumulates damage from the plastic strain: \
                         the material needs a plasticity table"
                            .to_string(),
                    ));
                };
                let flow = match j2.flow {
                    FlowStress::JohnsonCook(jc) => Some(jc),
                    _ => None,
                };
                let d5 = self.d5.unwrap_or(0.0);
                let t_room = self
                    .room_temperature
                    .or(flow.map(|jc| jc.t_room))
                    .unwrap_or(300.0);
                let t_melt = match (self.melt_temperature, flow) {
                    (Some(t), _) => t,
                    (None, Some(jc)) => jc.t_melt,
                    // Unused when d5 = 0 (T* only scales D₅): any value
                    // above the room temperature.
                    (None, None) if d5 == 0.0 => t_room + 1.0,
                    (None, None) => {
                        return Err((
                            "melt_temperature",
                            "missing; d5 ≠ 0 needs it (or a johnson_cook flow stress to take \
                             it from)"
                                .to_string(),
                        ))
                    }
                };
                Failure::JohnsonCook(JohnsonCookFailure {
                    d1: need(self.d1, "d1")?,
                    d2: need(self.d2, "d2")?,
                    d3: need(self.d3, "d3")?,
                    d4: self.d4.unwrap_or(0.0),
                    d5,
                    rate0: self
                        .reference_rate
                        .or(flow.map(|jc| jc.rate0))
                        .unwrap_or(1.0),
                    t_room,
                    t_melt,
                    nonlocal_radius: self.nonlocal_radius.unwrap_or(0.0),
                })
            }
        };
        f.validate()
            .map_err(|b| (b.key, format!("must be {}", b.allowed)))?;
        Ok(f)
    }
}

/// Equation of state of a fluid material.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EosKind {
    /// p = (γ − 1) ρ c_v T.
    IdealGas,
    /// p = (γ − 1) ρ c_v T − γ p_inf (liquids).
    StiffenedGas,
    /// Mie–Grüneisen with a linear U_s–u_p Hugoniot (Lian Eq. 66; water,
    /// metals): keys `c0`, `s`, `gruneisen`, `reference_density`, `cv`,
    /// optional `reference_temperature`, `reference_pressure`.
    MieGruneisen,
    /// Jones–Wilkins–Lee detonation products: keys `a`, `b`, `r1`, `r2`,
    /// `omega`, `reference_density`, `cv`, optional `reference_temperature`.
    Jwl,
}

impl EosKind {
    /// The scene names of every EOS.
    pub const NAMES: &'static str = "ideal_gas, stiffened_gas, mie_gruneisen, jwl";

    /// The scene name of this EOS.
    pub fn name(self) -> &'static str {
        match self {
            Self::IdealGas => "ideal_gas",
            Self::StiffenedGas => "stiffened_gas",
            Self::MieGruneisen => "mie_gruneisen",
            Self::Jwl => "jwl",
        }
    }
}

/// Default `reference_temperature` of the Mie–Grüneisen and JWL EOS \[K\].
pub const DEFAULT_EOS_REFERENCE_TEMPERATURE: f64 = 300.0;
/// Default `reference_pressure` of the Mie–Grüneisen EOS \[Pa\] (one
/// atmosphere).
pub const DEFAULT_EOS_REFERENCE_PRESSURE: f64 = 101_325.0;

/// A material. Solids: `model`, `density` and elastic constants, given either
/// as `youngs_modulus` and `poisson_ratio` or as `bulk_modulus` and
/// `shear_modulus`. Fluids: `eos`, `gamma`, `cv` (and `p_inf` for a stiffened
/// gas), optional `viscosity`; their densities come from `[[regions]]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Unique name.
    pub name: String,
    /// Material kind.
    #[serde(rename = "type")]
    pub kind: MaterialKind,
    /// Constitutive model (solids).
    pub model: Option<SolidModel>,
    /// Reference density (> 0; solids).
    pub density: Option<f64>,
    /// Young's modulus E (> 0).
    pub youngs_modulus: Option<f64>,
    /// Poisson's ratio, −1 < ν < 0.5.
    pub poisson_ratio: Option<f64>,
    /// Bulk modulus K (> 0).
    pub bulk_modulus: Option<f64>,
    /// Shear modulus G (> 0).
    pub shear_modulus: Option<f64>,
    /// Equation of state (fluids).
    pub eos: Option<EosKind>,
    /// Ratio of specific heats γ > 1 (fluids).
    pub gamma: Option<f64>,
    /// Specific heat at constant volume c_v > 0 (fluids; solids in a
    /// coupled scene with `coupling.heat_exchange > 0`, where it is
    /// required).
    pub cv: Option<f64>,
    /// Stiffening pressure p_inf ≥ 0 (stiffened gas).
    pub p_inf: Option<f64>,
    /// Mie–Grüneisen: bulk sound speed c₀ > 0 of `U_s = c₀ + s u_p`.
    pub c0: Option<f64>,
    /// Mie–Grüneisen: Hugoniot slope s in [1, 4] of `U_s = c₀ + s u_p`.
    pub s: Option<f64>,
    /// Mie–Grüneisen: Grüneisen coefficient Γ₀ in [0, 2 s).
    pub gruneisen: Option<f64>,
    /// Mie–Grüneisen and JWL: reference density ρ₀ > 0.
    pub reference_density: Option<f64>,
    /// Mie–Grüneisen and JWL: reference temperature T₀ > 0 (default
    /// 300 K): MG has `p(ρ₀, T₀) = reference_pressure`; JWL must have
    /// `p(ρ₀, T₀) > 0`.
    pub reference_temperature: Option<f64>,
    /// Mie–Grüneisen: pressure at `(ρ₀, T₀)` (default 101325 Pa).
    pub reference_pressure: Option<f64>,
    /// JWL: A \[Pa\].
    pub a: Option<f64>,
    /// JWL: B \[Pa\].
    pub b: Option<f64>,
    /// JWL: R₁ > 0.
    pub r1: Option<f64>,
    /// JWL: R₂ > 0.
    pub r2: Option<f64>,
    /// JWL: ω > 0.
    pub omega: Option<f64>,
    /// Dynamic viscosity μ ≥ 0 (fluids; default 0 = inviscid).
    pub viscosity: Option<f64>,
    /// Fluids: `"cells"` (ICE, the default) or `"particles"` (gas points,
    /// York Sec. 3.3). A material lives in one frame.
    pub frame: Option<Frame>,
    /// Gas points: York's artificial viscosity (defaults: the paper's).
    pub artificial_viscosity: Option<ArtificialViscositySpec>,
    /// Gas points: pressure floor \[Pa\] (default none). Lian Eq. 66 takes a
    /// liquid's pressure as 0 in tension so that it can break up:
    /// `min_pressure = 0.0`.
    pub min_pressure: Option<f64>,
    /// Gas points: where a point's density comes from, `"continuity"`
    /// (York Eq. 16, the default) or `"grid"` (the gas's nodal density
    /// interpolated back at the start of each step; ideal gas only; see
    /// [`crate::material::PointDensity`]).
    pub point_density: Option<PointDensity>,
    /// A rigid solid (coupled scenes): its particles move with their
    /// objects' `velocity` (one for all objects of the material),
    /// prescribed; the elastic constants give its bulk EOS in the cells.
    /// Per material: in a coupled scene every solid material is a solid
    /// field of its own, rigid or deformable.
    #[serde(default)]
    pub rigid: bool,
    /// J2 plasticity (solids with `model = "linear_elastic"`, explicit
    /// mode, or `model = "hencky"`, multiplicative, explicit or implicit):
    /// see [`PlasticitySpec`].
    pub plasticity: Option<PlasticitySpec>,
    /// Failure and damage (solids with `model = "linear_elastic"`,
    /// explicit mode): see [`FailureSpec`].
    pub failure: Option<FailureSpec>,
    /// Membranes: thickness h (> 0); the areal density is ρ h.
    pub thickness: Option<f64>,
}

/// MPM-ICE coupling settings (Guilkey Sec. 3.3).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CouplingSpec {
    /// Pressure at which the solids are stress-free (> 0).
    #[serde(default = "default_p_ref")]
    pub reference_pressure: f64,
    /// Momentum exchange coefficient between every solid field and every
    /// other material, fluids and the other solid fields (≥ 0; Guilkey
    /// uses 1e15).
    #[serde(default = "default_k_solid")]
    pub momentum_exchange: f64,
    /// Initial temperature of the solids (> 0; every particle starts at
    /// it). Without a heat exchange the solids stay at it (isothermal).
    #[serde(default = "default_solid_t")]
    pub solid_temperature: f64,
    /// Heat exchange coefficient H between every solid field and every
    /// other material (Guilkey Eq. 39; ≥ 0, default 0: no heat exchange,
    /// isothermal solids). With H > 0 every solid material needs `cv`.
    #[serde(default)]
    pub heat_exchange: f64,
    /// Time over which every rigid solid's prescribed velocity rises smoothly
    /// from zero, `V (1 − cos(π t/T))/2` (≥ 0; 0: impulsive start).
    #[serde(default)]
    pub rigid_ramp: f64,
    /// A solid's cell mass below this fraction of the cell at its
    /// reference density is a trace (in [0, 1); default 1e-3): its velocity
    /// in the momentum exchange is the one it had at the start of the step.
    #[serde(default = "default_solid_trace")]
    pub solid_trace_fraction: f64,
    /// How a rigid solid's volume enters the cells: `"smeared"` (default,
    /// Guilkey's node → cell average) or `"sharp"` (the exact overlap of
    /// its particles with the cells; [`crate::coupling::RigidInterface`]).
    #[serde(default)]
    pub rigid_interface: crate::coupling::RigidInterface,
}

fn default_solid_trace() -> f64 {
    crate::coupling::SOLID_TRACE_FRACTION
}

fn default_p_ref() -> f64 {
    101_325.0
}
fn default_k_solid() -> f64 {
    1e15
}
fn default_solid_t() -> f64 {
    300.0
}

impl Default for CouplingSpec {
    fn default() -> Self {
        Self {
            reference_pressure: default_p_ref(),
            momentum_exchange: default_k_solid(),
            solid_temperature: default_solid_t(),
            heat_exchange: 0.0,
            rigid_ramp: 0.0,
            solid_trace_fraction: default_solid_trace(),
            rigid_interface: crate::coupling::RigidInterface::Smeared,
        }
    }
}

/// Internal energy added to a fluid material in a region at a constant
/// power per unit volume over a time window (Guilkey Sec. 4.1 pressurises
/// the cylinder this way).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeatSourceSpec {
    /// Name of a fluid material.
    pub material: String,
    /// Cells whose centre lies in this region are heated.
    pub geometry: Geometry,
    /// Power per unit volume [W/m³] (finite).
    pub power: f64,
    /// Start of the window (≥ 0).
    #[serde(default)]
    pub start: f64,
    /// End of the window (> start).
    pub end: f64,
}

/// A surface burn `Γ = A K pⁿ` of a solid reactant into a fluid product
/// (Guilkey Sec. 5; [`crate::coupling::reaction`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReactionSpec {
    /// Name of a deformable solid material (it needs `cv`).
    pub reactant: String,
    /// Name of a fluid material.
    pub product: String,
    /// `K` [kg/(m² s Paⁿ)], ≥ 0.
    pub rate_constant: f64,
    /// `n` ≥ 0 (default 0: a constant regression rate).
    #[serde(default)]
    pub pressure_exponent: f64,
    /// The reactant burns where its temperature is at least this \[K\] (> 0).
    pub threshold_temperature: f64,
    /// Heat of reaction `Q` [J/kg] ≥ 0 (default 0).
    #[serde(default)]
    pub heat_of_reaction: f64,
}

impl ReactionSpec {
    /// The rate law.
    pub fn law(&self) -> crate::coupling::reaction::BurnLaw {
        crate::coupling::reaction::BurnLaw {
            rate_constant: self.rate_constant,
            pressure_exponent: self.pressure_exponent,
            threshold_temperature: self.threshold_temperature,
            heat_of_reaction: self.heat_of_reaction,
        }
    }
}

/// Region filled by an object.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Geometry {
    /// Axis-aligned box.
    Box {
        /// Lower corner.
        lower: Vec<f64>,
        /// Upper corner.
        upper: Vec<f64>,
    },
    /// Disk (2D) or ball in any dimension.
    Disk {
        /// Centre.
        center: Vec<f64>,
        /// Radius.
        radius: f64,
    },
    /// Ball (3D) or disk in any dimension.
    Sphere {
        /// Centre.
        center: Vec<f64>,
        /// Radius.
        radius: f64,
    },
    /// Half space of the points x with (x − point)·normal ≥ 0.
    HalfSpace {
        /// A point on the bounding plane.
        point: Vec<f64>,
        /// Normal pointing into the region.
        normal: Vec<f64>,
    },
    /// Polygon in the x–y plane (2D; in 3D a prism along z): the points
    /// inside the closed polyline through `vertices` (even–odd rule).
    Polygon {
        /// Vertices `[[x, y], …]` (at least 3).
        vertices: Vec<[f64; 2]>,
    },
    /// A polyline in the x–y plane: a membrane's curve (York Sec. 3.2), or,
    /// when `closed`, the region inside it (like `polygon`).
    Polyline {
        /// Vertices `[[x, y], …]` in order along the curve.
        vertices: Vec<[f64; 2]>,
        /// Whether the last vertex joins the first.
        #[serde(default)]
        closed: bool,
    },
    /// A circle (2D): a membrane's closed curve, or the disk inside it.
    Circle {
        /// Centre `[x, y]`.
        center: Vec<f64>,
        /// Radius.
        radius: f64,
    },
    /// The dog-bone of York Fig. 10 (reconstructed; 2D): two circular lobes
    /// of radius `lobe_radius` centred at `center ± (lobe_offset, 0)` joined
    /// by a straight neck of half-width `neck_half_width`; a membrane's
    /// closed curve, or the region inside it.
    DogBone {
        /// Centre `[x, y]`.
        center: Vec<f64>,
        /// Lobe radius r.
        lobe_radius: f64,
        /// Distance a of each lobe centre from the centre (> r).
        lobe_offset: f64,
        /// Neck half-width w (0 < w < r).
        neck_half_width: f64,
    },
    /// Annulus (2D) or cylindrical shell along z (3D): distance from the
    /// centre (in the x–y plane) between the radii.
    Annulus {
        /// Centre (length `dim`; z ignored).
        center: Vec<f64>,
        /// Inner radius.
        inner_radius: f64,
        /// Outer radius.
        outer_radius: f64,
    },
    /// The points inside every one of `parts` (e.g. a polygon's prism or an
    /// annulus's shell cut to a length along z by a `box` or `half_space`).
    Intersection {
        /// The regions intersected (at least one; any geometry that
        /// encloses a region, intersections included).
        parts: Vec<Geometry>,
    },
}

impl Geometry {
    /// Whether point `x` lies inside the region.
    pub fn contains(&self, x: &[f64]) -> bool {
        match self {
            Geometry::Box { lower, upper } => {
                (0..x.len()).all(|d| x[d] >= lower[d] && x[d] <= upper[d])
            }
            Geometry::Disk { center, radius } | Geometry::Sphere { center, radius } => {
                dist2(x, center, x.len()) <= radius * radius
            }
            Geometry::HalfSpace { point, normal } => {
                (0..x.len())
                    .map(|d| (x[d] - point[d]) * normal[d])
                    .sum::<f64>()
                    >= 0.0
            }
            Geometry::Annulus {
                center,
                inner_radius,
                outer_radius,
            } => {
                let r2 = dist2(x, center, x.len().min(2));
                r2 >= inner_radius * inner_radius && r2 <= outer_radius * outer_radius
            }
            Geometry::Polyline { vertices, closed } => {
                *closed
                    && Geometry::Polygon {
                        vertices: vertices.clone(),
                    }
                    .contains(x)
            }
            Geometry::Circle { center, radius } => {
                x.len() >= 2 && dist2(x, center, 2) <= radius * radius
            }
            Geometry::DogBone {
                center,
                lobe_radius: r,
                lobe_offset: a,
                neck_half_width: w,
            } => {
                if x.len() < 2 {
                    return false;
                }
                let (dx, dy) = (x[0] - center[0], x[1] - center[1]);
                (dx.abs() <= *a && dy.abs() <= *w)
                    || (dx - a).powi(2) + dy * dy <= r * r
                    || (dx + a).powi(2) + dy * dy <= r * r
            }
            Geometry::Intersection { parts } => parts.iter().all(|g| g.contains(x)),
            Geometry::Polygon { vertices } => {
                if x.len() < 2 {
                    return false;
                }
                // Even–odd rule: count crossings of the ray to +x.
                let (px, py) = (x[0], x[1]);
                let n = vertices.len();
                (0..n)
                    .filter(|&i| {
                        crate::membrane::edge_crossing(vertices[i], vertices[(i + n - 1) % n], py)
                            .is_some_and(|c| px < c)
                    })
                    .count()
                    % 2
                    == 1
            }
        }
    }

    /// Axis-aligned bounding box.
    pub fn bounds(&self, dim: usize) -> (Vec<f64>, Vec<f64>) {
        match self {
            Geometry::Intersection { parts } => {
                let mut lo = vec![f64::NEG_INFINITY; dim];
                let mut hi = vec![f64::INFINITY; dim];
                for part in parts {
                    let (l, h) = part.bounds(dim);
                    for d in 0..dim {
                        lo[d] = lo[d].max(l[d]);
                        hi[d] = hi[d].min(h[d]);
                    }
                }
                (lo, hi)
            }
            Geometry::HalfSpace { .. } => (vec![f64::NEG_INFINITY; dim], vec![f64::INFINITY; dim]),
            Geometry::Polygon { vertices } | Geometry::Polyline { vertices, .. } => {
                let mut lo = vec![f64::NEG_INFINITY; dim];
                let mut hi = vec![f64::INFINITY; dim];
                for d in 0..dim.min(2) {
                    lo[d] = vertices.iter().map(|v| v[d]).fold(f64::INFINITY, f64::min);
                    hi[d] = vertices
                        .iter()
                        .map(|v| v[d])
                        .fold(f64::NEG_INFINITY, f64::max);
                }
                (lo, hi)
            }
            Geometry::Box { lower, upper } => (lower.clone(), upper.clone()),
            Geometry::Circle { center, radius } => {
                let mut lo = vec![f64::NEG_INFINITY; dim];
                let mut hi = vec![f64::INFINITY; dim];
                for d in 0..dim.min(2) {
                    lo[d] = center[d] - radius;
                    hi[d] = center[d] + radius;
                }
                (lo, hi)
            }
            Geometry::DogBone {
                center,
                lobe_radius: r,
                lobe_offset: a,
                ..
            } => {
                let mut lo = vec![f64::NEG_INFINITY; dim];
                let mut hi = vec![f64::INFINITY; dim];
                let ext = [a + r, *r];
                for d in 0..dim.min(2) {
                    lo[d] = center[d] - ext[d];
                    hi[d] = center[d] + ext[d];
                }
                (lo, hi)
            }
            Geometry::Disk { center, radius } | Geometry::Sphere { center, radius } => (
                center.iter().map(|c| c - radius).collect(),
                center.iter().map(|c| c + radius).collect(),
            ),
            Geometry::Annulus {
                center,
                outer_radius,
                ..
            } => (
                (0..dim)
                    .map(|d| {
                        if d < 2 {
                            center[d] - outer_radius
                        } else {
                            f64::NEG_INFINITY
                        }
                    })
                    .collect(),
                (0..dim)
                    .map(|d| {
                        if d < 2 {
                            center[d] + outer_radius
                        } else {
                            f64::INFINITY
                        }
                    })
                    .collect(),
            ),
        }
    }
}

fn dist2(a: &[f64], b: &[f64], n: usize) -> f64 {
    (0..n).map(|d| (a[d] - b[d]) * (a[d] - b[d])).sum()
}

/// A body of one material filled with particles.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Name of a solid material or of a fluid with `frame = "particles"`.
    pub material: String,
    /// Region to fill.
    pub geometry: Geometry,
    /// Particles per cell per direction (default: `mpm.particles_per_cell`).
    pub particles_per_cell: Option<usize>,
    /// Initial velocity (length `dim`; default zero).
    pub velocity: Option<Vec<f64>>,
    /// Pressure on the inner surface of an annulus object (implicit mode),
    /// ramped with `implicit.load_ramp`.
    pub inner_pressure: Option<f64>,
    /// Gas points: initial density (> 0).
    pub density: Option<f64>,
    /// Gas points: initial pressure (the EOS must give it a positive
    /// internal energy at `density`).
    pub pressure: Option<f64>,
    /// Keep only the part inside the grid instead of rejecting a region that
    /// extends beyond it (e.g. a quarter of an annulus on symmetry planes).
    #[serde(default)]
    pub clip: bool,
    /// Membranes: the largest distance between neighbouring points along
    /// the curve (> 0, at most the smallest cell size).
    pub spacing: Option<f64>,
    /// Membranes on an open polyline: hold the two end points in place.
    #[serde(default)]
    pub fixed_ends: bool,
    /// Membranes: initial tangential stress s₀ (a taut membrane).
    pub prestress: Option<f64>,
    /// Indices of other objects whose regions this one leaves empty (e.g.
    /// the air around a block: `except = [0]`).
    #[serde(default)]
    pub except: Vec<usize>,
}

/// Output file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Format {
    /// ParaView VTK XML (`.vtu` particles, `.vti` grid, `.pvd` series).
    Vtk,
    /// CSV snapshots of particle fields.
    Csv,
    /// NumPy arrays: one folder `NAME_NNNN_npy/` per snapshot and field set,
    /// a `.npy` file per field (and the points or mesh) and `meta.json`
    /// (time, geometry, each field's unit and shape).
    Npy,
}

/// Which ICE discretisation variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum FluidVariant {
    /// Guilkey Eqs. 28–31 as written.
    #[default]
    Literal,
    /// Limited reconstruction in Eq. 28, face velocity and pressure force
    /// time-centred (see `ice::IceParams::high_resolution`).
    HighResolution,
    /// `high_resolution` with the MUSCL–Hancock half-step predictor of the
    /// face states, second order in time up to `time.cfl = 0.8` (see
    /// `ice::IceParams::hancock`).
    Hancock,
    /// `hancock` with acoustic-Riemann shock dissipation (acoustic jump in
    /// Eq. 28, full `Δp` weight in compression, a linear face viscosity),
    /// made for `time.cfl = 0.9` (see `ice::IceParams::hancock_acoustic`).
    HancockAcoustic,
}

/// Slope limiter of the second-order reconstruction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LimiterKind {
    /// First-order donor cell (no reconstruction).
    FirstOrder,
    /// van Leer.
    VanLeer,
    /// Monotonised central.
    Mc,
    /// Superbee.
    Superbee,
    /// Minmod.
    Minmod,
}

/// Momentum and heat exchange coefficients, uniform over material pairs.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExchangeSpec {
    /// Momentum exchange coefficient K ≥ 0 (Guilkey Eq. 38).
    pub momentum: f64,
    /// Heat exchange coefficient H ≥ 0 (Guilkey Eq. 39).
    #[serde(default)]
    pub heat: f64,
}

/// Fluid discretisation choices.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluidSpec {
    /// Discretisation variant (default `literal`).
    #[serde(default)]
    pub variant: FluidVariant,
    /// Advection limiter (default: van Leer for `literal`, superbee for
    /// `high_resolution`).
    pub limiter: Option<LimiterKind>,
    /// Exchange among fluid materials (default: none).
    pub exchange: Option<ExchangeSpec>,
    /// Volume fraction below which a material of a mixed cell is held
    /// isothermal through the flow work of the Lagrangian phase (`[0, 1)`,
    /// default [`crate::ice::ISOTHERMAL_FRACTION`]; `0` turns it off; see
    /// [`crate::ice::IceParams::isothermal_fraction`]).
    pub isothermal_fraction: Option<f64>,
    /// Implicit pressure solve (used when `time.mode = "semi_implicit"`).
    #[serde(default)]
    pub pressure: PressureSolveSpec,
    /// Inflow (prescribed-state, Dirichlet) faces of the fluid,
    /// `[fluid.inflow.x_lower]` …; such a face needs
    /// `grid.boundary.<face> = "free"` (or no entry).
    #[serde(default)]
    pub inflow: InflowSpec,
}

/// Inflow faces of the fluid: the state of every fluid material beyond the
/// face (the ghost cells), given like a `[[regions]]` entry. Faces not
/// given keep their `grid.boundary` condition.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InflowSpec {
    /// Face x = lower.
    pub x_lower: Option<InflowFaceSpec>,
    /// Face x = upper.
    pub x_upper: Option<InflowFaceSpec>,
    /// Face y = lower.
    pub y_lower: Option<InflowFaceSpec>,
    /// Face y = upper.
    pub y_upper: Option<InflowFaceSpec>,
    /// Face z = lower.
    pub z_lower: Option<InflowFaceSpec>,
    /// Face z = upper.
    pub z_upper: Option<InflowFaceSpec>,
}

impl InflowSpec {
    /// The faces as `[[lower, upper]; 3]` with their key names.
    pub fn faces(&self) -> [[(Option<&InflowFaceSpec>, &'static str); 2]; 3] {
        [
            [
                (self.x_lower.as_ref(), "x_lower"),
                (self.x_upper.as_ref(), "x_upper"),
            ],
            [
                (self.y_lower.as_ref(), "y_lower"),
                (self.y_upper.as_ref(), "y_upper"),
            ],
            [
                (self.z_lower.as_ref(), "z_lower"),
                (self.z_upper.as_ref(), "z_upper"),
            ],
        ]
    }

    /// `true` when some face is an inflow.
    pub fn any(&self) -> bool {
        self.faces().iter().flatten().any(|(f, _)| f.is_some())
    }
}

/// The prescribed fluid state of an inflow face: one pressure shared by the
/// materials and a state per material (density or temperature, volume
/// fraction, velocity), as in `[[regions]]`. Materials not listed get a
/// trace volume fraction.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InflowFaceSpec {
    /// Pressure (> 0 for gases; > −p_inf for a stiffened gas).
    pub pressure: f64,
    /// States of the materials flowing in.
    pub states: Vec<FluidStateSpec>,
}

/// Linear solver of the implicit pressure equation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PressureSolverKind {
    /// Sparse Cholesky with reused symbolic factorisation.
    Direct,
    /// CG preconditioned by a geometric multigrid V-cycle.
    PcgMultigrid,
    /// CG preconditioned by the diagonal.
    PcgJacobi,
}

/// Implicit pressure solve of semi-implicit ICE.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressureSolveSpec {
    /// Linear solver (default `direct`).
    #[serde(default = "default_pressure_solver")]
    pub solver: PressureSolverKind,
    /// Relative residual of an iterative linear solve, in (0, 1).
    #[serde(default = "default_linear_tol")]
    pub linear_tolerance: f64,
    /// Outer tolerance on max |residual| / V (> 0).
    #[serde(default = "default_outer_tol")]
    pub outer_tolerance: f64,
    /// Outer iterations per step (≥ 1).
    #[serde(default = "default_max_outer")]
    pub max_outer_iterations: usize,
    /// Krylov iterations per linear solve (≥ 1).
    #[serde(default = "default_max_linear")]
    pub max_linear_iterations: usize,
    /// Factor on the sound speed in the timestep (0: advection only).
    #[serde(default)]
    pub sound_speed_factor: f64,
    /// Largest growth of the timestep from one step to the next (≥ 1); a
    /// run's first step is acoustic (`sound_speed_factor` at least 1).
    #[serde(default = "default_dt_growth")]
    pub max_dt_growth: f64,
    /// Convective predictor `β ∈ [0, 1]` of the face velocities
    /// (`mpmice::ice::SemiImplicit::convective_predictor`; default 0).
    #[serde(default)]
    pub convective_predictor: f64,
}

fn default_pressure_solver() -> PressureSolverKind {
    PressureSolverKind::Direct
}
fn default_linear_tol() -> f64 {
    1e-10
}
fn default_outer_tol() -> f64 {
    1e-9
}
fn default_max_outer() -> usize {
    20
}
fn default_max_linear() -> usize {
    500
}
fn default_dt_growth() -> f64 {
    1.2
}

impl Default for PressureSolveSpec {
    fn default() -> Self {
        Self {
            solver: default_pressure_solver(),
            linear_tolerance: default_linear_tol(),
            outer_tolerance: default_outer_tol(),
            max_outer_iterations: default_max_outer(),
            max_linear_iterations: default_max_linear(),
            sound_speed_factor: 0.0,
            max_dt_growth: default_dt_growth(),
            convective_predictor: 0.0,
        }
    }
}

/// Linear solver of the implicit MPM Newton systems.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NewtonSolverKind {
    /// Sparse Cholesky (LU when the tangent is not SPD).
    Cholesky,
    /// CG preconditioned by the diagonal.
    PcgJacobi,
}

/// Implicit MPM (used when `time.mode = "implicit"`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImplicitSpec {
    /// Newmark dynamics (true) or quasistatic load steps (false).
    #[serde(default = "default_true")]
    pub dynamic: bool,
    /// Linear solver (default `cholesky`).
    #[serde(default = "default_newton_solver")]
    pub linear_solver: NewtonSolverKind,
    /// Newton tolerance on ‖δu‖/‖u‖ (> 0).
    #[serde(default = "default_tol_disp")]
    pub tolerance_displacement: f64,
    /// Newton tolerance on the energy norm (> 0).
    #[serde(default = "default_tol_energy")]
    pub tolerance_energy: f64,
    /// Newton iterations per attempt (≥ 1).
    #[serde(default = "default_max_newton")]
    pub max_newton_iterations: usize,
    /// Modified Newton: the tangent is assembled and factorised at the
    /// first iteration of a step's attempt only (and again after an
    /// iteration that contracts the residual by less than 10×), the later
    /// iterations reuse its factorisation (default `false`: full Newton).
    #[serde(default)]
    pub modified_newton: bool,
    /// Coupled scenes with a quasistatic solid (`dynamic = false`): the
    /// pressure stage holds the solid's face velocities at its cells'
    /// velocity where it fills both cells of a face, instead of moving them
    /// by `−Δt ∇p/ρ_s` (default `false`: Guilkey's step, whose gas leaks
    /// into and through the solid at large steps).
    #[serde(default)]
    pub hold_solid_faces: bool,
    /// Loads (gravity, pressures) ramp linearly to full over this time
    /// (default: applied at once).
    pub load_ramp: Option<f64>,
    /// Largest timestep (default: `time.end`).
    pub dt_max: Option<f64>,
    /// Largest particle displacement per step in cells; a step moving a
    /// particle further is redone with a smaller Δt (default 0.5).
    pub max_cell_fraction: Option<f64>,
    /// Grips: particle sets moved by a prescribed displacement, ramped with
    /// `load_ramp` (`[[implicit.prescribed]]`).
    #[serde(default)]
    pub prescribed: Vec<PrescribedSpec>,
    /// The coupling iteration between the implicit solids and the fluid
    /// pressure of a coupled scene (`[implicit.coupling]`).
    #[serde(default)]
    pub coupling: CouplingIterationSpec,
}

/// Relaxation of the coupling iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RelaxationKind {
    /// Aitken's dynamic relaxation, starting from `omega`.
    Aitken,
    /// A constant `omega`.
    Constant,
}

/// `[implicit.coupling]`: the fixed-point iteration of a coupled implicit
/// step between the solids' implicit solve and the fluid pressure
/// ([`crate::coupling::iteration`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CouplingIterationSpec {
    /// Most passes (pressure stage + implicit solve) per step (≥ 1; 1: the
    /// staggered step without iteration). A step that does not converge
    /// in them is retried with a smaller Δt.
    #[serde(default = "default_coupling_max_iterations")]
    pub max_iterations: usize,
    /// Relative tolerance on the change of the solid cells' velocity
    /// between passes (> 0).
    #[serde(default = "default_coupling_tolerance")]
    pub tolerance: f64,
    /// `aitken` (default) or `constant`.
    #[serde(default = "default_relaxation")]
    pub relaxation: RelaxationKind,
    /// The (first) relaxation factor, in (0, 2) (default 1).
    #[serde(default = "default_omega")]
    pub omega: f64,
}

fn default_coupling_max_iterations() -> usize {
    crate::coupling::iteration::CouplingIteration::default().max_iterations
}
fn default_coupling_tolerance() -> f64 {
    crate::coupling::iteration::CouplingIteration::default().tolerance
}
fn default_relaxation() -> RelaxationKind {
    RelaxationKind::Aitken
}
fn default_omega() -> f64 {
    1.0
}

impl Default for CouplingIterationSpec {
    fn default() -> Self {
        Self {
            max_iterations: default_coupling_max_iterations(),
            tolerance: default_coupling_tolerance(),
            relaxation: default_relaxation(),
            omega: default_omega(),
        }
    }
}

/// A prescribed displacement (implicit mode): the particles of one object,
/// optionally only those whose reference position lies in `region`, are held
/// by a rigid grip that has moved by `displacement` at full load (ramped with
/// `implicit.load_ramp`). The grid nodes the gripped particles touch move
/// with the grip in the prescribed components; the force of the grip on the
/// body is reported per step.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrescribedSpec {
    /// Index into `objects`.
    pub object: usize,
    /// Displacement at full load (length `dim`).
    pub displacement: Vec<f64>,
    /// Which components are prescribed (length `dim`; default: all).
    pub components: Option<Vec<bool>>,
    /// Only the object's particles with reference position in this region
    /// (default: the whole object).
    pub region: Option<Geometry>,
}

fn default_true() -> bool {
    true
}
fn default_newton_solver() -> NewtonSolverKind {
    NewtonSolverKind::Cholesky
}
fn default_tol_disp() -> f64 {
    1e-9
}
fn default_tol_energy() -> f64 {
    1e-16
}
fn default_max_newton() -> usize {
    25
}

impl Default for ImplicitSpec {
    fn default() -> Self {
        Self {
            dynamic: true,
            linear_solver: default_newton_solver(),
            tolerance_displacement: default_tol_disp(),
            tolerance_energy: default_tol_energy(),
            max_newton_iterations: default_max_newton(),
            modified_newton: false,
            hold_solid_faces: false,
            load_ramp: None,
            dt_max: None,
            max_cell_fraction: None,
            prescribed: Vec::new(),
            coupling: CouplingIterationSpec::default(),
        }
    }
}

/// The initial state of one fluid material in a region.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluidStateSpec {
    /// Name of a fluid material.
    pub material: String,
    /// Volume fraction in [0, 1]; the fractions of a region sum to 1.
    pub volume_fraction: f64,
    /// True density (> 0); give this or `temperature`.
    pub density: Option<f64>,
    /// Temperature (> 0); give this or `density`.
    pub temperature: Option<f64>,
    /// Velocity (length `dim`; default zero).
    pub velocity: Option<Vec<f64>>,
}

/// A region of initial fluid state.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionSpec {
    /// Region (default: everywhere).
    pub geometry: Option<Geometry>,
    /// Pressure (> 0 for gases; > −p_inf for a stiffened gas), shared by all
    /// materials of the region.
    pub pressure: f64,
    /// States of the materials present; fluid materials not listed get
    /// volume fraction 0.
    pub states: Vec<FluidStateSpec>,
}

/// What to write.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Simulation time between snapshots (> 0); absent: first and last only.
    pub interval: Option<f64>,
    /// Snapshot formats.
    #[serde(default = "default_formats")]
    pub formats: Vec<Format>,
    /// Simulation time between rows of `history.csv` (default: interval / 20,
    /// or every step when there is no interval).
    pub history_interval: Option<f64>,
    /// Simulation time between checkpoints (`checkpoints/step_NNNNNNNNNN/`);
    /// absent: none (a failure or an interrupt still writes one).
    pub checkpoint_interval: Option<f64>,
    /// How many interval checkpoints to keep (the oldest are removed; 0 keeps
    /// all).
    #[serde(default = "default_checkpoint_keep")]
    pub checkpoint_keep: usize,
    /// How VTK files store their arrays: zlib-compressed (default, level 1)
    /// or raw.
    #[serde(default)]
    pub vtk_compression: VtkCompression,
    /// zlib level, 1 (fastest, the default) to 9 (smallest); only with
    /// `vtk_compression = "zlib"`.
    pub vtk_compression_level: Option<u32>,
}

/// How VTK files store their arrays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VtkCompression {
    /// Raw little-endian values.
    None,
    /// zlib blocks (`vtkZLibDataCompressor`), which ParaView, VTK and meshio
    /// read: 3–15× smaller files than raw at level 1 for up to twice the
    /// (small) output time, so the default.
    #[default]
    Zlib,
}

impl OutputSpec {
    /// The zlib level of a `vtk_compression = "zlib"` output (default 1).
    pub fn zlib_level(&self) -> Option<u32> {
        match self.vtk_compression {
            VtkCompression::None => None,
            VtkCompression::Zlib => Some(self.vtk_compression_level.unwrap_or(1)),
        }
    }
}

fn default_checkpoint_keep() -> usize {
    2
}

fn default_formats() -> Vec<Format> {
    vec![Format::Vtk, Format::Csv]
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            interval: None,
            formats: default_formats(),
            history_interval: None,
            checkpoint_interval: None,
            checkpoint_keep: default_checkpoint_keep(),
            vtk_compression: VtkCompression::default(),
            vtk_compression_level: None,
        }
    }
}

fn validate_solid(m: &MaterialSpec, p: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
    for (v, k) in [
        (m.eos.is_some(), "eos"),
        (m.gamma.is_some(), "gamma"),
        (m.p_inf.is_some(), "p_inf"),
        (m.viscosity.is_some(), "viscosity"),
        (m.frame.is_some(), "frame"),
        (m.artificial_viscosity.is_some(), "artificial_viscosity"),
        (m.min_pressure.is_some(), "min_pressure"),
        (m.point_density.is_some(), "point_density"),
    ] {
        if v {
            return Err(err(p(k), "only for fluid materials (type = \"fluid\")"));
        }
    }
    // `cv` is a solid key too (heat exchange).
    if let Some(k) = m
        .eos_parameter_keys()
        .iter()
        .find(|(given, k)| *given && *k != "cv")
    {
        return Err(err(p(k.1), "only for fluid materials (type = \"fluid\")"));
    }
    if let Some(c) = m.cv {
        positive(&p("cv"), c)?;
    }
    match m.density {
        Some(d) => positive(&p("density"), d)?,
        None => return Err(err(p("density"), "missing; solids need a density > 0")),
    }
    if m.model.is_none() {
        return Err(err(
            p("model"),
            format!("missing; solids need one of: {}", SolidModel::NAMES),
        ));
    }
    if let Some(pl) = &m.plasticity {
        if !matches!(
            m.model,
            Some(SolidModel::LinearElastic | SolidModel::Hencky)
        ) {
            return Err(err(
                p("plasticity"),
                "J2 plasticity is built for the hypo-elastic and the Hencky paths; allowed with \
                 model = \"linear_elastic\" or \"hencky\"",
            ));
        }
        if m.rigid {
            return Err(err(p("plasticity"), "a rigid solid does not deform"));
        }
        pl.j2()
            .map_err(|(k, msg)| err(p(&format!("plasticity.{k}")), msg))?;
    }
    if let Some(f) = &m.failure {
        if !matches!(
            m.model,
            Some(SolidModel::LinearElastic | SolidModel::Hencky)
        ) {
            return Err(err(
                p("failure"),
                "failure is built for the hypo-elastic and the Hencky paths; allowed with \
                 model = \"linear_elastic\" or \"hencky\"",
            ));
        }
        if m.rigid {
            return Err(err(p("failure"), "a rigid solid does not fail"));
        }
        let j2 = m.plasticity.as_ref().and_then(|pl| pl.j2().ok());
        f.failure(j2.as_ref()).map_err(|(k, msg)| {
            let path = if k.is_empty() {
                p("failure")
            } else {
                p(&format!("failure.{k}"))
            };
            err(path, msg)
        })?;
    }
    match (
        m.youngs_modulus,
        m.poisson_ratio,
        m.bulk_modulus,
        m.shear_modulus,
    ) {
        (Some(e), Some(nu), None, None) => {
            positive(&p("youngs_modulus"), e)?;
            if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
                return Err(err(
                    p("poisson_ratio"),
                    format!("must satisfy -1 < ν < 0.5 (got {nu})"),
                ));
            }
        }
        (None, None, Some(k), Some(g)) => {
            positive(&p("bulk_modulus"), k)?;
            positive(&p("shear_modulus"), g)?;
        }
        _ => {
            return Err(err(
                p("youngs_modulus"),
                "give exactly one pair: youngs_modulus + poisson_ratio, or \
                 bulk_modulus + shear_modulus",
            ))
        }
    }
    Ok(())
}

fn validate_fluid(m: &MaterialSpec, p: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
    for (v, k) in [
        (m.model.is_some(), "model"),
        (m.density.is_some(), "density"),
        (m.youngs_modulus.is_some(), "youngs_modulus"),
        (m.poisson_ratio.is_some(), "poisson_ratio"),
        (m.bulk_modulus.is_some(), "bulk_modulus"),
        (m.shear_modulus.is_some(), "shear_modulus"),
        (m.plasticity.is_some(), "plasticity"),
        (m.failure.is_some(), "failure"),
        (m.rigid, "rigid"),
    ] {
        if v {
            let extra = match k {
                "density" => " (fluid densities are set per region in [[regions]])",
                "rigid" => " (a rigid solid moving through the fluid of a coupled scene)",
                _ => "",
            };
            return Err(err(p(k), format!("only for solid materials{extra}")));
        }
    }
    let Some(eos) = m.eos else {
        return Err(err(
            p("eos"),
            format!("missing; fluids need one of: {}", EosKind::NAMES),
        ));
    };
    // The keys each EOS reads (required, optional); every other EOS key is
    // rejected.
    let (required, optional): (&[&str], &[&str]) = match eos {
        EosKind::IdealGas => (&["gamma", "cv"], &[]),
        EosKind::StiffenedGas => (&["gamma", "cv", "p_inf"], &[]),
        EosKind::MieGruneisen => (
            &["c0", "s", "gruneisen", "reference_density", "cv"],
            &["reference_temperature", "reference_pressure"],
        ),
        EosKind::Jwl => (
            &["a", "b", "r1", "r2", "omega", "reference_density", "cv"],
            &["reference_temperature"],
        ),
    };
    for (given, k) in m.eos_parameter_keys() {
        if given && !required.contains(&k) && !optional.contains(&k) {
            return Err(err(
                p(k),
                format!(
                    "not read by eos = \"{}\" (it reads {})",
                    eos.name(),
                    required
                        .iter()
                        .chain(optional)
                        .copied()
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        if !given && required.contains(&k) {
            return Err(err(
                p(k),
                format!(
                    "missing; eos = \"{}\" needs {}",
                    eos.name(),
                    required.join(", ")
                ),
            ));
        }
    }
    if let Some(g) = m.gamma {
        if !(g.is_finite() && g > 1.0) {
            return Err(err(p("gamma"), format!("must be > 1 (got {g})")));
        }
    }
    if let Some(c) = m.cv {
        positive(&p("cv"), c)?;
    }
    match (eos, m.p_inf) {
        (EosKind::IdealGas, Some(_)) => {
            return Err(err(p("p_inf"), "only for eos = \"stiffened_gas\""))
        }
        (EosKind::StiffenedGas, None) => {
            return Err(err(p("p_inf"), "missing; stiffened gas needs p_inf ≥ 0"))
        }
        (EosKind::StiffenedGas, Some(pi)) if !(pi.is_finite() && pi >= 0.0) => {
            return Err(err(p("p_inf"), format!("must be ≥ 0 (got {pi})")))
        }
        _ => {}
    }
    // The EOS's own range checks (Mie–Grüneisen, JWL), naming their key.
    m.fluid_eos().map_err(|e| eos_error(p, e))?;
    if m.is_gas_point() && m.pressure_ignores_temperature() {
        return Err(err(
            p("gruneisen"),
            "must be > 0 for gas points (frame = \"particles\"): a point's pressure follows its \
             energy",
        ));
    }
    if let Some(mu) = m.viscosity {
        if !(mu.is_finite() && mu >= 0.0) {
            return Err(err(p("viscosity"), format!("must be ≥ 0 (got {mu})")));
        }
    }
    if let Some(pm) = m.min_pressure {
        if !m.on_particles() {
            return Err(err(
                p("min_pressure"),
                "only for gas points (frame = \"particles\")",
            ));
        }
        if !pm.is_finite() {
            return Err(err(p("min_pressure"), format!("must be finite (got {pm})")));
        }
    }
    if m.point_density.is_some() && !m.on_particles() {
        return Err(err(
            p("point_density"),
            "only for gas points (frame = \"particles\")",
        ));
    }
    // An ideal gas's forces do not read its density; any other EOS's do,
    // and the grid reads a gas low next to a wall, another material or a
    // free surface (part-filled nodes): York's stiffened-gas piston column
    // had not finished after 12 min against 13 s with continuity (not
    // inspected; half the density at the piston's node is a large tension
    // for a stiffened gas at p = 0).
    if m.point_density == Some(PointDensity::Grid) && m.eos.is_some_and(|e| e != EosKind::IdealGas)
    {
        return Err(err(
            p("point_density"),
            "\"grid\" only with eos = \"ideal_gas\" (another EOS's forces read the density, \
             which the grid reads low at walls, interfaces and free surfaces); use \
             \"continuity\"",
        ));
    }
    if let Some(av) = &m.artificial_viscosity {
        if !m.on_particles() {
            return Err(err(
                p("artificial_viscosity"),
                "only for gas points (frame = \"particles\")",
            ));
        }
        if !(av.g_over_dx.is_finite() && av.g_over_dx > 0.0 && av.g_over_dx <= 10.0) {
            return Err(err(
                p("artificial_viscosity.g_over_dx"),
                format!("must satisfy 0 < g_over_dx ≤ 10 (got {})", av.g_over_dx),
            ));
        }
        for (v, k) in [(av.kappa, "kappa"), (av.c1, "c1"), (av.c2, "c2")] {
            if !(v.is_finite() && (0.0..=100.0).contains(&v)) {
                return Err(err(
                    p(&format!("artificial_viscosity.{k}")),
                    format!("must satisfy 0 ≤ {k} ≤ 100 (got {v})"),
                ));
            }
        }
    }
    Ok(())
}

/// A scene error at the key an [`EosError`] names.
fn eos_error(p: &dyn Fn(&str) -> String, e: EosError) -> SceneError {
    match e {
        EosError::Invalid {
            field,
            allowed,
            got,
        } => err(p(field), format!("must be {allowed} (got {got})")),
        other => err(p("eos"), other.to_string()),
    }
}

impl MaterialSpec {
    /// The parameter keys of the fluid equations of state beyond `gamma`,
    /// `cv` and `p_inf`, each with whether it is given.
    fn eos_parameter_keys(&self) -> [(bool, &'static str); 14] {
        [
            (self.gamma.is_some(), "gamma"),
            (self.cv.is_some(), "cv"),
            (self.p_inf.is_some(), "p_inf"),
            (self.c0.is_some(), "c0"),
            (self.s.is_some(), "s"),
            (self.gruneisen.is_some(), "gruneisen"),
            (self.reference_density.is_some(), "reference_density"),
            (
                self.reference_temperature.is_some(),
                "reference_temperature",
            ),
            (self.reference_pressure.is_some(), "reference_pressure"),
            (self.a.is_some(), "a"),
            (self.b.is_some(), "b"),
            (self.r1.is_some(), "r1"),
            (self.r2.is_some(), "r2"),
            (self.omega.is_some(), "omega"),
        ]
    }

    /// The equation of state of a fluid material from its keys (missing
    /// keys read as NaN, so the EOS rejects them by name; no `eos` reads as
    /// the ideal gas).
    ///
    /// # Errors
    /// The [`EosError`] of the EOS constructor, naming the key.
    pub fn fluid_eos(&self) -> Result<FluidEos, EosError> {
        let get = |v: Option<f64>| v.unwrap_or(f64::NAN);
        let t0 = self
            .reference_temperature
            .unwrap_or(DEFAULT_EOS_REFERENCE_TEMPERATURE);
        Ok(match self.eos {
            Some(EosKind::StiffenedGas) => {
                StiffenedGas::new(get(self.gamma), get(self.p_inf), get(self.cv))?.into()
            }
            Some(EosKind::MieGruneisen) => MieGruneisen::new(
                get(self.reference_density),
                get(self.c0),
                get(self.s),
                get(self.gruneisen),
                get(self.cv),
                t0,
                self.reference_pressure
                    .unwrap_or(DEFAULT_EOS_REFERENCE_PRESSURE),
            )?
            .into(),
            Some(EosKind::Jwl) => Jwl::new(
                get(self.a),
                get(self.b),
                get(self.r1),
                get(self.r2),
                get(self.omega),
                get(self.reference_density),
                get(self.cv),
                t0,
            )?
            .into(),
            Some(EosKind::IdealGas) | None => IdealGas::new(get(self.gamma), get(self.cv))?.into(),
        })
    }

    /// A Mie–Grüneisen fluid with `gruneisen = 0`: `p(ρ)` only, so neither
    /// a temperature from `(ρ, p)` nor a gas point's energy from its
    /// pressure exists.
    fn pressure_ignores_temperature(&self) -> bool {
        self.eos == Some(EosKind::MieGruneisen) && self.gruneisen == Some(0.0)
    }

    /// Lowest admissible pressure of a fluid material (exclusive;
    /// [`FluidEos::min_pressure`]); 0 when its EOS is invalid.
    fn min_fluid_pressure(&self) -> f64 {
        self.fluid_eos().map_or(0.0, |e| e.min_pressure())
    }

    /// Whether the material lives on particles: a solid, or a fluid with
    /// `frame = "particles"` (gas points, York Sec. 3.3).
    pub fn on_particles(&self) -> bool {
        self.kind == MaterialKind::Solid
            || self.kind == MaterialKind::Membrane
            || self.is_gas_point()
    }

    /// Whether the material is a fluid on particles (a gas point).
    pub fn is_gas_point(&self) -> bool {
        self.kind == MaterialKind::Fluid && self.frame == Some(Frame::Particles)
    }

    /// Whether the material is a fluid in the cells (ICE).
    pub fn in_cells(&self) -> bool {
        self.kind == MaterialKind::Fluid && !self.is_gas_point()
    }
}

/// Shape checks of a region's geometry (fluid regions, heat sources).
fn validate_region_shape(g: &Geometry, path: &str, dim: usize) -> Result<(), SceneError> {
    validate_geometry(g, path, dim)?;
    match g {
        Geometry::Box { lower, upper } => {
            vec_len(&format!("{path}.lower"), lower, dim)?;
            vec_len(&format!("{path}.upper"), upper, dim)?;
        }
        Geometry::Disk { center, radius } | Geometry::Sphere { center, radius } => {
            vec_len(&format!("{path}.center"), center, dim)?;
            positive(&format!("{path}.radius"), *radius)?;
        }
        Geometry::Annulus { center, .. } => vec_len(&format!("{path}.center"), center, dim)?,
        Geometry::HalfSpace { .. } | Geometry::Polygon { .. } => {}
        Geometry::Polyline { .. } | Geometry::Circle { .. } | Geometry::DogBone { .. } => {}
        Geometry::Intersection { .. } => {}
    }
    Ok(())
}

fn validate_geometry(g: &Geometry, path: &str, dim: usize) -> Result<(), SceneError> {
    if let Geometry::Intersection { parts } = g {
        if parts.is_empty() {
            return Err(err(
                format!("{path}.parts"),
                "needs at least one region (box, disk, sphere, half_space, polygon, annulus, \
                 intersection, closed polyline, circle, dog_bone)",
            ));
        }
        for (k, part) in parts.iter().enumerate() {
            let path = format!("{path}.parts[{k}]");
            validate_region_shape(part, &path, dim)?;
            match part {
                Geometry::Box { lower, upper } => {
                    if let Some(d) = (0..dim).find(|&d| upper[d] <= lower[d]) {
                        return Err(err(
                            format!("{path}.upper[{d}]"),
                            format!("must be > lower[{d}] = {}", lower[d]),
                        ));
                    }
                }
                Geometry::Annulus {
                    inner_radius,
                    outer_radius,
                    ..
                } => {
                    if dim < 2 {
                        return Err(err(format!("{path}.type"), "annulus needs dim 2 or 3"));
                    }
                    if !(inner_radius.is_finite() && *inner_radius >= 0.0) {
                        return Err(err(format!("{path}.inner_radius"), "must be ≥ 0"));
                    }
                    if !(outer_radius.is_finite() && outer_radius > inner_radius) {
                        return Err(err(
                            format!("{path}.outer_radius"),
                            format!("must be > inner_radius = {inner_radius}"),
                        ));
                    }
                }
                Geometry::Polyline { closed: false, .. } => {
                    return Err(err(
                        format!("{path}.closed"),
                        "an intersection's polyline must be closed (it encloses a region)",
                    ));
                }
                _ => {}
            }
        }
    }
    if let Geometry::Polygon { vertices } = g {
        if dim < 2 {
            return Err(err(path, "a polygon needs dim = 2 or 3"));
        }
        if vertices.len() < 3 || !vertices.iter().flatten().all(|v| v.is_finite()) {
            return Err(err(
                format!("{path}.vertices"),
                "needs at least 3 finite [x, y] vertices",
            ));
        }
    }
    match g {
        Geometry::Polyline { vertices, closed } => {
            if dim != 2 {
                return Err(err(format!("{path}.type"), "a polyline needs dim = 2"));
            }
            validate_polyline(vertices, *closed, path)?;
        }
        Geometry::Circle { center, radius } => {
            if dim != 2 {
                return Err(err(format!("{path}.type"), "a circle needs dim = 2"));
            }
            vec_len(&format!("{path}.center"), center, 2)?;
            positive(&format!("{path}.radius"), *radius)?;
        }
        Geometry::DogBone {
            center,
            lobe_radius,
            lobe_offset,
            neck_half_width,
        } => {
            if dim != 2 {
                return Err(err(format!("{path}.type"), "a dog_bone needs dim = 2"));
            }
            vec_len(&format!("{path}.center"), center, 2)?;
            positive(&format!("{path}.lobe_radius"), *lobe_radius)?;
            if !(neck_half_width.is_finite()
                && *neck_half_width > 0.0
                && neck_half_width < lobe_radius)
            {
                return Err(err(
                    format!("{path}.neck_half_width"),
                    format!("must satisfy 0 < neck_half_width < lobe_radius = {lobe_radius}"),
                ));
            }
            if !(lobe_offset.is_finite() && lobe_offset > lobe_radius) {
                return Err(err(
                    format!("{path}.lobe_offset"),
                    format!("must be > lobe_radius = {lobe_radius} (lobes apart)"),
                ));
            }
        }
        _ => {}
    }
    if let Geometry::HalfSpace { point, normal } = g {
        vec_len(&format!("{path}.point"), point, dim)?;
        vec_len(&format!("{path}.normal"), normal, dim)?;
        if normal.iter().all(|v| *v == 0.0) {
            return Err(err(format!("{path}.normal"), "must not be zero"));
        }
    }
    Ok(())
}

/// A membrane's (or a closed region's) polyline: enough finite vertices, no
/// zero-length segment, in order (no segment folds back onto the previous
/// one) and not crossing itself.
fn validate_polyline(v: &[[f64; 2]], closed: bool, path: &str) -> Result<(), SceneError> {
    let min = if closed { 3 } else { 2 };
    if v.len() < min || !v.iter().flatten().all(|x| x.is_finite()) {
        return Err(err(
            format!("{path}.vertices"),
            format!(
                "needs at least {min} finite [x, y] vertices ({} polyline)",
                if closed { "a closed" } else { "an open" }
            ),
        ));
    }
    let n = v.len();
    let nseg = if closed { n } else { n - 1 };
    let scale = v
        .iter()
        .flatten()
        .fold(0.0f64, |a, x| a.max(x.abs()))
        .max(1.0);
    for i in 0..nseg {
        let (a, b) = (v[i], v[(i + 1) % n]);
        if (b[0] - a[0]).hypot(b[1] - a[1]) <= 1e-12 * scale {
            return Err(err(
                format!("{path}.vertices[{}]", (i + 1) % n),
                format!("repeats vertex {i}: zero-length segment; vertices must be distinct"),
            ));
        }
    }
    if let Some((i, j)) = crate::membrane::self_intersection(v, closed) {
        return Err(err(
            format!("{path}.vertices"),
            format!(
                "the polyline crosses or folds onto itself (segments {i} and {j}); give the \
                 vertices in order along a simple curve"
            ),
        ));
    }
    Ok(())
}

/// A membrane material: density, Young's modulus, Poisson's ratio and
/// thickness, nothing of a solid's model or a fluid's.
fn validate_membrane(m: &MaterialSpec, p: &dyn Fn(&str) -> String) -> Result<(), SceneError> {
    for (v, k) in [
        (m.model.is_some(), "model"),
        (m.bulk_modulus.is_some(), "bulk_modulus"),
        (m.shear_modulus.is_some(), "shear_modulus"),
        (m.eos.is_some(), "eos"),
        (m.gamma.is_some(), "gamma"),
        (m.cv.is_some(), "cv"),
        (m.p_inf.is_some(), "p_inf"),
        (m.viscosity.is_some(), "viscosity"),
        (m.frame.is_some(), "frame"),
        (m.artificial_viscosity.is_some(), "artificial_viscosity"),
        (m.min_pressure.is_some(), "min_pressure"),
        (m.point_density.is_some(), "point_density"),
        (m.rigid, "rigid"),
    ] {
        if v {
            return Err(err(
                p(k),
                "not a membrane key; membranes take density, youngs_modulus, poisson_ratio, \
                 thickness",
            ));
        }
    }
    if let Some(k) = m.eos_parameter_keys().iter().find(|(given, _)| *given) {
        return Err(err(
            p(k.1),
            "not a membrane key; membranes take density, youngs_modulus, poisson_ratio, \
             thickness",
        ));
    }
    for (v, k) in [
        (m.density, "density"),
        (m.youngs_modulus, "youngs_modulus"),
        (m.thickness, "thickness"),
    ] {
        match v {
            Some(x) => positive(&p(k), x)?,
            None => return Err(err(p(k), "missing; membranes need it > 0")),
        }
    }
    match m.poisson_ratio {
        Some(nu) if nu.is_finite() && nu > -1.0 && nu < 1.0 => Ok(()),
        Some(nu) => Err(err(
            p("poisson_ratio"),
            format!("must satisfy -1 < ν < 1 (got {nu})"),
        )),
        None => Err(err(p("poisson_ratio"), "missing; -1 < ν < 1")),
    }
}

impl Scene {
    /// Checks of a scene with membranes (York Sec. 3.2): 2D, explicit
    /// mode, no fluid in the cells; membrane objects are curves with a
    /// spacing of at most a cell; other objects have no membrane keys.
    fn validate_membranes(&self) -> Result<(), SceneError> {
        let Some(mi) = self
            .materials
            .iter()
            .position(|m| m.kind == MaterialKind::Membrane)
        else {
            for (i, o) in self.objects.iter().enumerate() {
                membrane_keys_absent(o, i)?;
            }
            return Ok(());
        };
        if self.grid.dim != 2 {
            return Err(err(
                "grid.dim",
                format!(
                    "membranes (materials[{mi}]) are implemented in 2D only; allowed: 2 (got {})",
                    self.grid.dim
                ),
            ));
        }
        if self.time.mode != Mode::Explicit {
            return Err(err(
                "time.mode",
                format!(
                    "membranes (materials[{mi}]) run in explicit MPM only; allowed: explicit \
                     (got {})",
                    self.time.mode.name()
                ),
            ));
        }
        if let Some(f) = self.materials.iter().position(|m| m.in_cells()) {
            return Err(err(
                format!("materials[{f}].frame"),
                format!(
                    "membranes (materials[{mi}]) couple to gas points only, not to a fluid in \
                     the cells (ICE); allowed: frame = \"particles\""
                ),
            ));
        }
        let hmin = (0..2)
            .map(|d| (self.grid.upper[d] - self.grid.lower[d]) / self.grid.cells[d] as f64)
            .fold(f64::INFINITY, f64::min);
        for (i, o) in self.objects.iter().enumerate() {
            let p = |k: &str| format!("objects[{i}].{k}");
            let is_membrane = self
                .materials
                .iter()
                .any(|m| m.name == o.material && m.kind == MaterialKind::Membrane);
            if !is_membrane {
                membrane_keys_absent(o, i)?;
                if let Geometry::Polyline { closed: false, .. } = o.geometry {
                    return Err(err(
                        p("geometry.closed"),
                        "an open polyline encloses no region; only membranes take one",
                    ));
                }
                continue;
            }
            match &o.geometry {
                Geometry::Polyline { closed, .. } => {
                    if o.fixed_ends && *closed {
                        return Err(err(
                            p("fixed_ends"),
                            "only for open polylines (closed = false)",
                        ));
                    }
                }
                Geometry::Circle { .. } | Geometry::DogBone { .. } => {
                    if o.fixed_ends {
                        return Err(err(
                            p("fixed_ends"),
                            "only for open polylines (closed = false)",
                        ));
                    }
                }
                _ => {
                    return Err(err(
                        p("geometry.type"),
                        "a membrane is a curve; allowed: polyline, circle, dog_bone",
                    ))
                }
            }
            match o.spacing {
                None => {
                    return Err(err(
                        p("spacing"),
                        "missing; membranes need a point spacing > 0",
                    ))
                }
                Some(s) if !(s.is_finite() && s > 0.0) => {
                    return Err(err(p("spacing"), format!("must be > 0 (got {s})")))
                }
                Some(s) if s > hmin * (1.0 + 1e-12) => {
                    return Err(err(
                        p("spacing"),
                        format!(
                            "must be at most the smallest cell size {hmin} (got {s}): points \
                             farther apart than a cell let the gas through"
                        ),
                    ))
                }
                _ => {}
            }
            if let Some(s0) = o.prestress {
                if !s0.is_finite() {
                    return Err(err(p("prestress"), "must be finite"));
                }
            }
            for (v, k) in [
                (o.particles_per_cell.is_some(), "particles_per_cell"),
                (o.density.is_some(), "density"),
                (o.pressure.is_some(), "pressure"),
                (o.inner_pressure.is_some(), "inner_pressure"),
            ] {
                if v {
                    return Err(err(p(k), "not a membrane object key (use spacing)"));
                }
            }
        }
        Ok(())
    }

    /// Checks of a scene with a `[multiphase]` table (Zhang's model) beyond
    /// the table itself.
    fn validate_multiphase(&self) -> Result<(), SceneError> {
        if self.time.mode != Mode::Explicit {
            return Err(err(
                "time.mode",
                format!(
                    "the multiphase model is explicit; allowed: explicit (got {})",
                    self.time.mode.name()
                ),
            ));
        }
        if !matches!(self.mpm.update, None | Some(UpdateScheme::Usl)) {
            return Err(err(
                "mpm.update",
                "the multiphase model updates the stress last; allowed: usl",
            ));
        }
        for (i, m) in self.materials.iter().enumerate() {
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
        let gases: Vec<usize> = (0..self.materials.len())
            .filter(|&i| self.materials[i].is_gas_point())
            .collect();
        if gases.len() > 1 {
            return Err(err(
                format!("materials[{}]", gases[1]),
                "the multiphase model has one gas pressure p_g (Zhang Eq. 4): at most one gas \
                 material",
            ));
        }
        if self.materials.len() > MAX_PHASES {
            return Err(err(
                "materials",
                format!("at most {MAX_PHASES} phases (got {})", self.materials.len()),
            ));
        }
        for (axis, faces) in self.grid.boundary.faces().iter().enumerate() {
            if faces[0].0 == Some(Boundary::Periodic) && self.grid.cells[axis] < 4 {
                return Err(err(
                    format!("grid.cells[{axis}]"),
                    "a periodic axis needs at least 4 cells",
                ));
            }
        }
        Ok(())
    }

    /// Keys of objects that depend on their material: `density` and
    /// `pressure` belong to gas points, except that a hypo-elastic solid of
    /// a multiphase scene may start under a hydrostatic `pressure`; `except`
    /// names other objects.
    fn validate_object_keys(&self) -> Result<(), SceneError> {
        for (i, o) in self.objects.iter().enumerate() {
            let p = |k: &str| format!("objects[{i}].{k}");
            for (k, &e) in o.except.iter().enumerate() {
                if e >= self.objects.len() || e == i {
                    return Err(err(
                        format!("objects[{i}].except[{k}]"),
                        format!(
                            "must be the index of another object: 0 … {} except {i} (got {e})",
                            self.objects.len().saturating_sub(1)
                        ),
                    ));
                }
            }
            let Some(m) = self.materials.iter().find(|m| m.name == o.material) else {
                continue;
            };
            if m.is_gas_point() || m.kind == MaterialKind::Membrane || !m.on_particles() {
                // Gas objects are checked with the gas points; a cell fluid
                // in an object is rejected with the objects.
                continue;
            }
            if o.density.is_some() {
                return Err(err(
                    p("density"),
                    "only for objects of gas points (fluids with frame = \"particles\"); a \
                     solid's density is its material's",
                ));
            }
            if let Some(pr) = o.pressure {
                let prestress_ok = self.multiphase.is_some()
                    && m.kind == MaterialKind::Solid
                    && m.model == Some(SolidModel::LinearElastic);
                if !prestress_ok {
                    return Err(err(
                        p("pressure"),
                        "only for objects of gas points, and (as a hydrostatic initial stress) \
                         of linear_elastic solids in a [multiphase] scene",
                    ));
                }
                if !pr.is_finite() {
                    return Err(err(p("pressure"), format!("must be finite (got {pr})")));
                }
            }
        }
        Ok(())
    }

    fn validate_solvers(&self) -> Result<(), SceneError> {
        if let Some(f) = self.fluid.isothermal_fraction {
            if !(f.is_finite() && (0.0..1.0).contains(&f)) {
                return Err(err(
                    "fluid.isothermal_fraction",
                    format!("must be in [0, 1) (got {f})"),
                ));
            }
        }
        let ps = &self.fluid.pressure;
        let lt = ps.linear_tolerance;
        if !(lt.is_finite() && lt > 0.0 && lt < 1.0) {
            return Err(err(
                "fluid.pressure.linear_tolerance",
                format!("must be in (0, 1) (got {lt})"),
            ));
        }
        positive("fluid.pressure.outer_tolerance", ps.outer_tolerance)?;
        for (v, k) in [
            (ps.max_outer_iterations, "max_outer_iterations"),
            (ps.max_linear_iterations, "max_linear_iterations"),
        ] {
            if v == 0 {
                return Err(err(format!("fluid.pressure.{k}"), "must be ≥ 1 (got 0)"));
            }
        }
        if !(ps.sound_speed_factor.is_finite() && ps.sound_speed_factor >= 0.0) {
            return Err(err("fluid.pressure.sound_speed_factor", "must be ≥ 0"));
        }
        if !(ps.max_dt_growth.is_finite() && ps.max_dt_growth >= 1.0) {
            return Err(err("fluid.pressure.max_dt_growth", "must be ≥ 1"));
        }
        let b = ps.convective_predictor;
        if !(b.is_finite() && (0.0..=1.0).contains(&b)) {
            return Err(err(
                "fluid.pressure.convective_predictor",
                format!("must be in [0, 1] (got {b})"),
            ));
        }
        // Multigrid's red–black smoother needs an even number of cells along
        // a periodic axis (unless the whole grid is its directly solved
        // coarsest level, `ice::pressure_mg_options`).
        let total: usize = self.grid.cells.iter().product();
        let coarse_max = crate::ice::pressure_mg_options().coarse_max_cells;
        if ps.solver == PressureSolverKind::PcgMultigrid && total > coarse_max {
            let faces = self.grid.boundary.faces();
            for (d, (f, &n)) in faces.iter().zip(&self.grid.cells).enumerate() {
                if f[0].0 == Some(Boundary::Periodic) && n % 2 == 1 {
                    return Err(err(
                        "fluid.pressure.solver",
                        format!(
                            "pcg_multigrid needs an even number of cells along a periodic \
                             axis (grid.cells[{d}] = {n}); allowed here: direct, pcg_jacobi"
                        ),
                    ));
                }
            }
        }
        let im = &self.implicit;
        positive("implicit.tolerance_displacement", im.tolerance_displacement)?;
        positive("implicit.tolerance_energy", im.tolerance_energy)?;
        if im.max_newton_iterations == 0 {
            return Err(err("implicit.max_newton_iterations", "must be ≥ 1 (got 0)"));
        }
        if let Some(r) = im.load_ramp {
            positive("implicit.load_ramp", r)?;
        }
        if let Some(d) = im.dt_max {
            positive("implicit.dt_max", d)?;
        }
        if let Some(f) = im.max_cell_fraction {
            positive("implicit.max_cell_fraction", f)?;
        }
        let ci = &im.coupling;
        if ci.max_iterations == 0 {
            return Err(err(
                "implicit.coupling.max_iterations",
                "must be ≥ 1 (got 0; 1 is the staggered step)",
            ));
        }
        if ci.max_iterations > 1 && !im.dynamic {
            // The quasistatic solid's velocity u/Δt answers the step's
            // pressure at once: the fixed point's gain is the ratio of the
            // gas's and the solid's stiffness in the mixed cells, and on
            // the pressurised cylinder it diverged (dx 0.025, Δt 1e-4:
            // J ≤ 0 at step 119 after Δt was cut to 1.7e-12).
            return Err(err(
                "implicit.coupling.max_iterations",
                format!(
                    "the coupling iteration needs implicit.dynamic = true (got {} passes \
                     with a quasistatic solid); allowed here: 1",
                    ci.max_iterations
                ),
            ));
        }
        positive("implicit.coupling.tolerance", ci.tolerance)?;
        if !(ci.omega > 0.0 && ci.omega < 2.0) {
            return Err(err(
                "implicit.coupling.omega",
                format!("must be in (0, 2) (got {})", ci.omega),
            ));
        }
        for (i, o) in self.objects.iter().enumerate() {
            if let Some(p) = o.inner_pressure {
                if !p.is_finite() {
                    return Err(err(
                        format!("objects[{i}].inner_pressure"),
                        "must be finite",
                    ));
                }
                if !matches!(o.geometry, Geometry::Annulus { .. }) {
                    return Err(err(
                        format!("objects[{i}].inner_pressure"),
                        "only for annulus objects",
                    ));
                }
                if self.time.mode != Mode::Implicit {
                    return Err(err(
                        format!("objects[{i}].inner_pressure"),
                        "surface pressure loads are applied in implicit mode only (for now)",
                    ));
                }
                if self.materials.iter().any(|m| m.in_cells()) {
                    return Err(err(
                        format!("objects[{i}].inner_pressure"),
                        "surface pressure loads act on solid-only implicit scenes; in a \
                         coupled scene the fluid's pressure loads the solid",
                    ));
                }
            }
        }
        self.validate_prescribed()
    }

    /// `[[implicit.prescribed]]`: implicit mode, an existing object, vectors
    /// of length `dim`, at least one prescribed component, a valid region.
    fn validate_prescribed(&self) -> Result<(), SceneError> {
        let dim = self.grid.dim;
        for (k, pr) in self.implicit.prescribed.iter().enumerate() {
            let p = |s: &str| format!("implicit.prescribed[{k}].{s}");
            if self.time.mode != Mode::Implicit {
                return Err(err(
                    format!("implicit.prescribed[{k}]"),
                    "prescribed displacements are applied in implicit mode only",
                ));
            }
            if self.materials.iter().any(|m| m.in_cells()) {
                return Err(err(
                    format!("implicit.prescribed[{k}]"),
                    "prescribed displacements act on solid-only implicit scenes; a coupled \
                     scene (fluid materials in the cells) does not apply them",
                ));
            }
            if pr.object >= self.objects.len() {
                return Err(err(
                    p("object"),
                    format!(
                        "no object {} (the scene has {} objects, numbered from 0)",
                        pr.object,
                        self.objects.len()
                    ),
                ));
            }
            vec_len(&p("displacement"), &pr.displacement, dim)?;
            if let Some(c) = &pr.components {
                if c.len() != dim {
                    return Err(err(
                        p("components"),
                        format!("must have {dim} entries (grid.dim), got {}", c.len()),
                    ));
                }
                if !c.iter().any(|&b| b) {
                    return Err(err(
                        p("components"),
                        "at least one component must be prescribed",
                    ));
                }
            }
            if let Some(g) = &pr.region {
                let path = p("region");
                validate_geometry(g, &path, dim)?;
                let radius = |r: f64, key: &str| -> Result<(), SceneError> {
                    if r.is_finite() && r >= 0.0 {
                        Ok(())
                    } else {
                        Err(err(
                            format!("{path}.{key}"),
                            format!("must be ≥ 0 (got {r})"),
                        ))
                    }
                };
                match g {
                    Geometry::Box { lower, upper } => {
                        vec_len(&format!("{path}.lower"), lower, dim)?;
                        vec_len(&format!("{path}.upper"), upper, dim)?;
                        if let Some(d) = (0..dim).find(|&d| upper[d] < lower[d]) {
                            return Err(err(
                                format!("{path}.upper[{d}]"),
                                format!("must be ≥ lower[{d}] = {}", lower[d]),
                            ));
                        }
                    }
                    Geometry::Disk { center, radius: r }
                    | Geometry::Sphere { center, radius: r } => {
                        vec_len(&format!("{path}.center"), center, dim)?;
                        radius(*r, "radius")?;
                    }
                    Geometry::Annulus {
                        center,
                        inner_radius,
                        outer_radius,
                    } => {
                        vec_len(&format!("{path}.center"), center, dim)?;
                        radius(*inner_radius, "inner_radius")?;
                        radius(*outer_radius, "outer_radius")?;
                    }
                    Geometry::HalfSpace { .. }
                    | Geometry::Polygon { .. }
                    | Geometry::Polyline { .. }
                    | Geometry::Circle { .. }
                    | Geometry::DogBone { .. }
                    | Geometry::Intersection { .. } => {}
                }
            }
        }
        Ok(())
    }

    fn validate_fluid_regions(&self) -> Result<(), SceneError> {
        let dim = self.grid.dim;
        if self.regions.is_empty() {
            return Err(err("regions", "a fluid scene needs at least one region"));
        }
        if let Some(ex) = &self.fluid.exchange {
            for (v, k) in [(ex.momentum, "momentum"), (ex.heat, "heat")] {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(err(
                        format!("fluid.exchange.{k}"),
                        format!("must be a finite number ≥ 0 (got {v})"),
                    ));
                }
            }
        }
        for (i, r) in self.regions.iter().enumerate() {
            if let Some(g) = &r.geometry {
                validate_region_shape(g, &format!("regions[{i}].geometry"), dim)?;
            }
            self.validate_fluid_states(&format!("regions[{i}]"), r.pressure, &r.states)?;
        }
        self.validate_fluid_inflow()?;
        Ok(())
    }

    /// Checks of the inflow faces (`fluid.inflow.<face>`).
    fn validate_fluid_inflow(&self) -> Result<(), SceneError> {
        let dim = self.grid.dim;
        let grid_faces = self.grid.boundary.faces();
        for (axis, faces) in self.fluid.inflow.faces().iter().enumerate() {
            for (side, (spec, name)) in faces.iter().enumerate() {
                let Some(spec) = spec else { continue };
                let key = format!("fluid.inflow.{name}");
                if axis >= dim {
                    return Err(err(
                        key,
                        format!("the grid has dim {dim}; allowed faces: {}", face_names(dim)),
                    ));
                }
                if self.materials.iter().any(|m| m.kind == MaterialKind::Solid) {
                    return Err(err(key, "inflow faces are available for fluid-only scenes"));
                }
                if let Some(bc) = grid_faces[axis][side].0 {
                    if bc != Boundary::Free {
                        return Err(err(
                            key,
                            format!(
                                "an inflow face needs grid.boundary.{name} = \"free\" (or no \
                                 entry), got \"{}\"",
                                match bc {
                                    Boundary::Fixed => "fixed",
                                    Boundary::Symmetry => "symmetry",
                                    Boundary::Periodic => "periodic",
                                    Boundary::Free => "free",
                                }
                            ),
                        ));
                    }
                }
                self.validate_fluid_states(&key, spec.pressure, &spec.states)?;
            }
        }
        Ok(())
    }

    /// Checks of a pressure and a list of material states (a region or an
    /// inflow face) under the key `prefix`.
    fn validate_fluid_states(
        &self,
        prefix: &str,
        pressure: f64,
        states: &[FluidStateSpec],
    ) -> Result<(), SceneError> {
        let dim = self.grid.dim;
        let p = |k: &str| format!("{prefix}.{k}");
        if !pressure.is_finite() {
            return Err(err(p("pressure"), "must be finite"));
        }
        if states.is_empty() {
            return Err(err(p("states"), "at least one material state is required"));
        }
        let mut sum = 0.0;
        for (k, st) in states.iter().enumerate() {
            let q = |key: &str| format!("{prefix}.states[{k}].{key}");
            let Some(m) = self
                .materials
                .iter()
                .find(|m| m.name == st.material && m.kind == MaterialKind::Fluid)
            else {
                let names: Vec<&str> = self
                    .materials
                    .iter()
                    .filter(|m| m.kind == MaterialKind::Fluid)
                    .map(|m| m.name.as_str())
                    .collect();
                return Err(err(
                    q("material"),
                    format!(
                        "unknown fluid material `{}`; defined: {}",
                        st.material,
                        names.join(", ")
                    ),
                ));
            };
            if states[..k].iter().any(|o| o.material == st.material) {
                return Err(err(
                    q("material"),
                    format!("`{}` listed twice", st.material),
                ));
            }
            if !(st.volume_fraction.is_finite() && (0.0..=1.0).contains(&st.volume_fraction)) {
                return Err(err(
                    q("volume_fraction"),
                    format!("must be in [0, 1] (got {})", st.volume_fraction),
                ));
            }
            sum += st.volume_fraction;
            if st.density.is_some() && m.pressure_ignores_temperature() {
                return Err(err(
                    q("density"),
                    format!(
                        "`{}` has eos = \"mie_gruneisen\" with gruneisen = 0: its pressure does \
                         not depend on temperature, so give temperature instead",
                        m.name
                    ),
                ));
            }
            match (st.density, st.temperature) {
                (Some(d), None) => positive(&q("density"), d)?,
                (None, Some(t)) => positive(&q("temperature"), t)?,
                _ => {
                    return Err(err(
                        q("density"),
                        "give exactly one of density or temperature",
                    ))
                }
            }
            if let Some(v) = &st.velocity {
                vec_len(&q("velocity"), v, dim)?;
            }
            let p_min = m.min_fluid_pressure();
            if pressure <= p_min {
                return Err(err(
                    p("pressure"),
                    format!(
                        "must be > {p_min} for material `{}` (got {})",
                        st.material, pressure
                    ),
                ));
            }
        }
        if (sum - 1.0).abs() > 1e-9 {
            return Err(err(
                p("states"),
                format!("volume fractions must sum to 1 (got {sum})"),
            ));
        }
        Ok(())
    }
}

impl Scene {
    /// Checks of one solid material `s` of a coupled scene (one solid
    /// field): used by an object, its `cv` when heat is exchanged, one prescribed velocity for
    /// all its objects when it is rigid.
    fn validate_solid_field(&self, s: usize) -> Result<(), SceneError> {
        let c = &self.coupling;
        if !self
            .objects
            .iter()
            .any(|o| o.material == self.materials[s].name)
        {
            return Err(err(
                format!("materials[{s}]"),
                format!(
                    "solid material `{}` is used by no object; in a coupled scene each solid \
                     material is one solid field and needs particles",
                    self.materials[s].name
                ),
            ));
        }
        if c.heat_exchange > 0.0 && self.materials[s].cv.is_none() {
            return Err(err(
                format!("materials[{s}].cv"),
                "missing; the solid needs a specific heat cv > 0 when coupling.heat_exchange > 0",
            ));
        }
        if self.materials[s].rigid {
            let name = &self.materials[s].name;
            let mut vel: Option<&Option<Vec<f64>>> = None;
            for (i, o) in self.objects.iter().enumerate() {
                if &o.material == name {
                    match vel {
                        None => vel = Some(&o.velocity),
                        Some(v) if *v != o.velocity => {
                            return Err(err(
                                format!("objects[{i}].velocity"),
                                "all objects of a rigid material move with one prescribed \
                                 velocity",
                            ))
                        }
                        _ => {}
                    }
                }
            }
        }
        Ok(())
    }

    /// Checks of a scene with gas points (York Sec. 3.3): explicit mode, no
    /// fluid in the cells, every gas object with a density and a pressure
    /// that give a positive internal energy, every solid object without
    /// them, and no gas-point material in `[[regions]]` or inflow states (a
    /// material lives in one frame).
    fn validate_gas_points(&self) -> Result<(), SceneError> {
        if self.time.mode != Mode::Explicit {
            return Err(err(
                "time.mode",
                format!(
                    "gas points (frame = \"particles\") run in explicit mode only; allowed: \
                     explicit (got {})",
                    self.time.mode.name()
                ),
            ));
        }
        if let Some(i) = self.materials.iter().position(|m| m.in_cells()) {
            let gas = self.materials.iter().position(|m| m.is_gas_point());
            return Err(err(
                format!("materials[{}].frame", gas.unwrap_or(i)),
                format!(
                    "gas points cannot share a scene with a fluid in the cells (`{}`) yet; \
                     allowed: every fluid on \"particles\" or every fluid in \"cells\"",
                    self.materials[i].name
                ),
            ));
        }
        let gas_names: Vec<&str> = self
            .materials
            .iter()
            .filter(|m| m.is_gas_point())
            .map(|m| m.name.as_str())
            .collect();
        let both = |key: String, name: &str| {
            err(
                key,
                format!(
                    "`{name}` has frame = \"particles\" (its state comes from its objects); a \
                     material lives in one frame, particles or cells"
                ),
            )
        };
        for (i, r) in self.regions.iter().enumerate() {
            for (k, st) in r.states.iter().enumerate() {
                if gas_names.contains(&st.material.as_str()) {
                    return Err(both(
                        format!("regions[{i}].states[{k}].material"),
                        &st.material,
                    ));
                }
            }
        }
        for faces in self.fluid.inflow.faces().iter() {
            for (spec, name) in faces {
                let Some(spec) = spec else { continue };
                for (k, st) in spec.states.iter().enumerate() {
                    if gas_names.contains(&st.material.as_str()) {
                        return Err(both(
                            format!("fluid.inflow.{name}.states[{k}].material"),
                            &st.material,
                        ));
                    }
                }
            }
        }
        for (i, o) in self.objects.iter().enumerate() {
            let p = |k: &str| format!("objects[{i}].{k}");
            let Some(m) = self.materials.iter().find(|m| m.name == o.material) else {
                continue;
            };
            if !m.is_gas_point() {
                // Checked for every scene in `validate_objects`.
                continue;
            }
            let Some(rho) = o.density else {
                return Err(err(p("density"), "missing; gas objects need a density > 0"));
            };
            positive(&p("density"), rho)?;
            let Some(pr) = o.pressure else {
                return Err(err(
                    p("pressure"),
                    "missing; gas objects need an initial pressure",
                ));
            };
            let min = m.min_fluid_pressure();
            if !(pr.is_finite() && pr > min) {
                return Err(err(
                    p("pressure"),
                    format!("must be finite and > {min} for `{}` (got {pr})", m.name),
                ));
            }
            if o.inner_pressure.is_some() {
                return Err(err(p("inner_pressure"), "only for solid objects"));
            }
        }
        Ok(())
    }

    /// `grid.axisymmetric = true`: a 2D explicit particle scene (solids and
    /// gas points) with r = x ≥ 0 and, where the grid reaches r = 0, the
    /// axis as a `symmetry` face (mirror folding gives v_r = 0 there).
    fn validate_axisymmetric(&self, has_fluid: bool) -> Result<(), SceneError> {
        let g = &self.grid;
        if g.dim != 2 {
            return Err(err(
                "grid.axisymmetric",
                format!(
                    "only with grid.dim = 2 (coordinates (r, z)); got grid.dim = {}",
                    g.dim
                ),
            ));
        }
        if has_fluid {
            return Err(err(
                "grid.axisymmetric",
                "is available for explicit MPM scenes (solids and fluids with frame = \
                 \"particles\"); not with cell fluids (ICE) or coupled MPM-ICE",
            ));
        }
        if self.time.mode != Mode::Explicit {
            return Err(err(
                "grid.axisymmetric",
                format!(
                    "is available with time.mode = \"explicit\" only (got \"{}\"; implicit \
                     MPM has no hoop terms)",
                    self.time.mode.name()
                ),
            ));
        }
        self.validate_axisymmetric_membranes()?;
        if g.lower[0] < 0.0 {
            return Err(err(
                "grid.lower",
                format!(
                    "grid.lower[0] is the radius r and must be ≥ 0 when grid.axisymmetric = \
                     true (got {})",
                    g.lower[0]
                ),
            ));
        }
        if g.lower[0] == 0.0 && g.boundary.x_lower != Some(Boundary::Symmetry) {
            return Err(err(
                "grid.boundary.x_lower",
                "must be \"symmetry\" when grid.axisymmetric = true and grid.lower[0] = 0 \
                 (the face is the axis r = 0)",
            ));
        }
        Ok(())
    }

    /// Membranes of revolution (York Sec. 3.2 in r–z): every point of a
    /// membrane curve at r ≥ 0; a closed curve (a torus-like surface) at
    /// r > 0 everywhere, since a ring of radius 0 has no hoop rate `v_r/r`.
    /// An open polyline may end on the axis (r = 0: a surface closed at its
    /// pole).
    fn validate_axisymmetric_membranes(&self) -> Result<(), SceneError> {
        for (i, o) in self.objects.iter().enumerate() {
            let is_membrane = self
                .materials
                .iter()
                .any(|m| m.name == o.material && m.kind == MaterialKind::Membrane);
            if !is_membrane {
                continue;
            }
            let p = |k: &str| format!("objects[{i}].geometry.{k}");
            let radial = "is the radius r in an axisymmetric scene (grid.axisymmetric = true)";
            match &o.geometry {
                Geometry::Polyline { vertices, closed } => {
                    for (k, v) in vertices.iter().enumerate() {
                        if v[0] < 0.0 || (*closed && v[0] == 0.0) {
                            return Err(err(
                                p(&format!("vertices[{k}]")),
                                format!(
                                    "x = {} {radial}; allowed: x ≥ 0 on an open polyline (an \
                                     end at x = 0 closes the surface at the axis), x > 0 on a \
                                     closed one",
                                    v[0]
                                ),
                            ));
                        }
                    }
                }
                Geometry::Circle { center, radius } if center[0] - radius <= 0.0 => {
                    return Err(err(
                        p("center"),
                        format!(
                            "center[0] − radius = {} {radial}; allowed: > 0 (the ring of \
                             revolution must stay off the axis)",
                            center[0] - radius
                        ),
                    ));
                }
                Geometry::DogBone {
                    center,
                    lobe_radius,
                    lobe_offset,
                    ..
                } if center[0] - lobe_offset - lobe_radius <= 0.0 => {
                    return Err(err(
                        p("center"),
                        format!(
                            "center[0] − lobe_offset − lobe_radius = {} {radial}; allowed: > 0",
                            center[0] - lobe_offset - lobe_radius
                        ),
                    ));
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The stress-update ordering of the explicit MPM step: `mpm.update`, or
    /// by default MUSL in scenes with gas points (York Sec. 2.2, Eqs. 10–13)
    /// and USL otherwise.
    pub fn mpm_update(&self) -> UpdateScheme {
        self.mpm.update.unwrap_or_else(|| {
            // Membrane contact runs the split step (USL or USF only).
            if self.membrane_elements.is_empty() && self.materials.iter().any(|m| m.is_gas_point())
            {
                UpdateScheme::Musl
            } else {
                UpdateScheme::Usl
            }
        })
    }

    /// Checks of a scene with solid and fluid materials (MPM-ICE): one
    /// solid field per solid material.
    fn validate_coupled(&self) -> Result<(), SceneError> {
        let solids: Vec<usize> = (0..self.materials.len())
            .filter(|&i| self.materials[i].kind == MaterialKind::Solid)
            .collect();
        if solids.is_empty() {
            return Err(err(
                "materials",
                "a coupled scene needs at least one solid material (each solid material is \
                 one solid field), got none",
            ));
        }
        if self.mpm.update == Some(UpdateScheme::Musl) {
            return Err(err(
                "mpm.update",
                "musl is not offered in coupled scenes; allowed: usf, usl",
            ));
        }
        for faces in self.grid.boundary.faces().iter() {
            for (bc, name) in faces {
                if *bc == Some(Boundary::Periodic) {
                    return Err(err(
                        format!("grid.boundary.{name}"),
                        "periodic faces are not offered in coupled scenes; allowed: fixed, \
                         symmetry, free",
                    ));
                }
            }
        }
        let c = &self.coupling;
        positive("coupling.reference_pressure", c.reference_pressure)?;
        positive("coupling.solid_temperature", c.solid_temperature)?;
        if !(c.rigid_ramp.is_finite() && c.rigid_ramp >= 0.0) {
            return Err(err(
                "coupling.rigid_ramp",
                format!("must be finite and >= 0 (seconds), got {}", c.rigid_ramp),
            ));
        }
        if !(c.momentum_exchange.is_finite() && c.momentum_exchange >= 0.0) {
            return Err(err(
                "coupling.momentum_exchange",
                format!("must be finite and >= 0, got {}", c.momentum_exchange),
            ));
        }
        if !(c.heat_exchange.is_finite() && c.heat_exchange >= 0.0) {
            return Err(err(
                "coupling.heat_exchange",
                format!("must be finite and >= 0, got {}", c.heat_exchange),
            ));
        }
        if c.rigid_interface == crate::coupling::RigidInterface::Sharp
            && self.time.mode != Mode::Explicit
        {
            return Err(err(
                "coupling.rigid_interface",
                format!(
                    "\"sharp\" is offered with time.mode = explicit only (got {}; the implicit \
                     pressure's time step collapses with it); allowed here: smeared",
                    self.time.mode.name()
                ),
            ));
        }
        if !(0.0..1.0).contains(&c.solid_trace_fraction) {
            return Err(err(
                "coupling.solid_trace_fraction",
                format!("must be in [0, 1), got {}", c.solid_trace_fraction),
            ));
        }
        for &s in &solids {
            self.validate_solid_field(s)?;
        }
        self.validate_heat_sources()?;
        self.validate_reactions()
    }

    /// `[[heat_sources]]` of a scene with fluid materials: each heats a
    /// fluid of the scene, with a finite power over a window
    /// `0 ≤ start < end` and a region that overlaps the grid.
    fn validate_heat_sources(&self) -> Result<(), SceneError> {
        let (lo, hi) = (&self.grid.lower, &self.grid.upper);
        let dim = self.grid.dim;
        for (i, h) in self.heat_sources.iter().enumerate() {
            let p = |k: &str| format!("heat_sources[{i}].{k}");
            match self.materials.iter().find(|m| m.name == h.material) {
                Some(m) if m.kind == MaterialKind::Fluid => {}
                _ => {
                    return Err(err(
                        p("material"),
                        format!("`{}` is not a fluid material of this scene", h.material),
                    ))
                }
            }
            if !h.power.is_finite() {
                return Err(err(p("power"), "must be finite"));
            }
            if !(h.start.is_finite() && h.start >= 0.0) {
                return Err(err(p("start"), "must be finite and >= 0"));
            }
            if !(h.end.is_finite() && h.end > h.start) {
                return Err(err(p("end"), "must be finite and > start"));
            }
            validate_region_shape(&h.geometry, &p("geometry"), dim)?;
            let (glo, ghi) = h.geometry.bounds(dim);
            let outside = (0..dim).any(|d| ghi[d] <= lo[d] || glo[d] >= hi[d]);
            if outside {
                return Err(err(
                    p("geometry"),
                    "lies outside the domain (it must overlap the grid)",
                ));
            }
        }
        Ok(())
    }

    /// `[[reactions]]` of a coupled scene: a deformable solid reactant with
    /// `cv`, a fluid product, and the law's parameters in range.
    fn validate_reactions(&self) -> Result<(), SceneError> {
        for (i, r) in self.reactions.iter().enumerate() {
            let p = |k: &str| format!("reactions[{i}].{k}");
            match self.materials.iter().find(|m| m.name == r.reactant) {
                Some(m) if m.kind == MaterialKind::Solid && !m.rigid && !m.is_gas_point() => {
                    if m.cv.is_none() {
                        return Err(err(
                            p("reactant"),
                            format!(
                                "material `{}` needs `cv` (its internal energy goes into \
                                 the product)",
                                r.reactant
                            ),
                        ));
                    }
                }
                _ => {
                    return Err(err(
                        p("reactant"),
                        format!(
                            "`{}` is not a deformable solid material of this scene",
                            r.reactant
                        ),
                    ))
                }
            }
            match self.materials.iter().find(|m| m.name == r.product) {
                Some(m) if m.kind == MaterialKind::Fluid && !m.is_gas_point() => {}
                _ => {
                    return Err(err(
                        p("product"),
                        format!(
                            "`{}` is not a fluid material (in cells) of this scene",
                            r.product
                        ),
                    ))
                }
            }
            if self.reactions[..i].iter().any(|o| o.reactant == r.reactant) {
                return Err(err(p("reactant"), "a reactant may have one reaction only"));
            }
            r.law()
                .validate()
                .map_err(|(key, allowed)| err(p(key), format!("must be {allowed}")))?;
        }
        Ok(())
    }
}

/// The face keys of a grid of dimension `dim`, comma separated.
fn face_names(dim: usize) -> String {
    [
        "x_lower", "x_upper", "y_lower", "y_upper", "z_lower", "z_upper",
    ][..2 * dim.min(3)]
        .join(", ")
}

fn err(path: impl Into<String>, msg: impl Into<String>) -> SceneError {
    SceneError::new(path, msg)
}

fn positive(path: &str, v: f64) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(err(path, format!("must be a finite number > 0 (got {v})")))
    }
}

fn vec_len(path: &str, v: &[f64], dim: usize) -> Result<(), SceneError> {
    if v.len() != dim {
        return Err(err(
            path,
            format!("must have {dim} components (grid.dim), got {}", v.len()),
        ));
    }
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(err(format!("{path}[{i}]"), "must be finite"));
    }
    Ok(())
}

impl GridSpec {
    /// The grid of a scene without `[grid]`: dimension 0, no cells.
    pub fn absent() -> Self {
        Self {
            dim: 0,
            lower: Vec::new(),
            upper: Vec::new(),
            cells: Vec::new(),
            boundary: BoundarySpec::default(),
            axisymmetric: false,
        }
    }
}

impl Scene {
    /// The spatial dimension: the grid's, 3 for membrane elements.
    pub fn dim(&self) -> usize {
        if self.membrane_elements.is_empty() {
            self.grid.dim
        } else {
            3
        }
    }

    /// Checks a scene of membrane elements: alone (no grid, materials,
    /// objects or regions) or with MPM bodies on a 3D grid (no fluid in
    /// cells, no York membrane points), explicit time integration,
    /// 3-component gravity, each mesh, the contact settings.
    fn validate_membrane_elements(&self) -> Result<(), SceneError> {
        if self.grid.dim == 0 {
            let why = "a scene of membrane elements alone has no MPM part; for MPM bodies in \
                       contact with the membranes add a 3D [grid]";
            if !self.materials.is_empty() {
                return Err(err("materials", why));
            }
            if !self.objects.is_empty() {
                return Err(err("objects", why));
            }
            if self.contact.is_some() {
                return Err(err("contact", why));
            }
        } else {
            if self.grid.dim != 3 {
                return Err(err(
                    "grid.dim",
                    format!(
                        "membrane elements live in 3D; allowed: 3 (got {})",
                        self.grid.dim
                    ),
                ));
            }
            for (i, m) in self.materials.iter().enumerate() {
                if m.in_cells() || m.kind == MaterialKind::Membrane {
                    return Err(err(
                        format!("materials[{i}].type"),
                        "with membrane elements the MPM bodies are solids or gas points \
                         (type = \"solid\", or \"fluid\" with frame = \"particles\")",
                    ));
                }
            }
            if self.mpm.update == Some(crate::mpm::UpdateScheme::Musl) {
                return Err(err(
                    "mpm.update",
                    "membrane contact needs the split MPM step; allowed: usl, usf",
                ));
            }
        }
        if !self.regions.is_empty() {
            return Err(err(
                "regions",
                "fluid regions are not allowed with membrane elements",
            ));
        }
        if let Some(c) = &self.contact {
            if !(c.friction.is_finite() && c.friction >= 0.0) {
                return Err(err(
                    "contact.friction",
                    format!("must be a finite number ≥ 0 (got {})", c.friction),
                ));
            }
            if c.law == ContactLawSpec::Stick && c.friction != 0.0 {
                return Err(err(
                    "contact.friction",
                    "only with law = \"slip\" (stick has no friction limit)",
                ));
            }
        }
        if self.time.mode != Mode::Explicit {
            return Err(err(
                "time.mode",
                "membrane elements integrate explicitly; allowed: explicit",
            ));
        }
        if let Some(gv) = &self.gravity {
            vec_len("gravity", gv, 3)?;
        }
        for (i, m) in self.membrane_elements.iter().enumerate() {
            if self.membrane_elements[..i].iter().any(|o| o.name == m.name) {
                return Err(err(
                    format!("membrane_elements[{i}].name"),
                    format!("`{}` is used twice", m.name),
                ));
            }
            m.validate(i)?;
        }
        Ok(())
    }

    /// Checks ranges and cross-references; the error names the key path and
    /// the allowed values.
    pub fn validate(&self) -> Result<(), SceneError> {
        if !self.membrane_elements.is_empty() {
            self.validate_time()?;
            self.validate_output()?;
            self.validate_membrane_elements()?;
            if self.grid.dim == 0 {
                return Ok(());
            }
        } else if self.contact.is_some() {
            return Err(err(
                "contact",
                "only in scenes with [[membrane_elements]] (Lian's grid contact)",
            ));
        }
        let g = &self.grid;
        if g.dim == 0 {
            return Err(err(
                "grid",
                "missing; every scene but one of membrane elements only needs [grid]",
            ));
        }
        let dim = g.dim;
        if !(1..=3).contains(&dim) {
            return Err(err("grid.dim", format!("must be 1, 2 or 3 (got {dim})")));
        }
        vec_len("grid.lower", &g.lower, dim)?;
        vec_len("grid.upper", &g.upper, dim)?;
        if g.cells.len() != dim {
            return Err(err(
                "grid.cells",
                format!(
                    "must have {dim} components (grid.dim), got {}",
                    g.cells.len()
                ),
            ));
        }
        for d in 0..dim {
            if g.cells[d] == 0 {
                return Err(err(format!("grid.cells[{d}]"), "must be ≥ 1 (got 0)"));
            }
            if g.cells[d] > 1 << 20 {
                return Err(err(format!("grid.cells[{d}]"), "must be ≤ 1048576"));
            }
            if g.upper[d] <= g.lower[d] {
                return Err(err(
                    format!("grid.upper[{d}]"),
                    format!("must be > grid.lower[{d}] = {}", g.lower[d]),
                ));
            }
        }
        for (axis, faces) in g.boundary.faces().iter().enumerate() {
            for (bc, name) in faces {
                if axis >= dim && bc.is_some() {
                    return Err(err(
                        format!("grid.boundary.{name}"),
                        format!("not allowed in {dim}D (only faces of the first {dim} axes)"),
                    ));
                }
            }
        }
        self.validate_time()?;
        let t = &self.time;

        if !(1..=16).contains(&self.mpm.particles_per_cell) {
            return Err(err(
                "mpm.particles_per_cell",
                format!("must be 1 … 16 (got {})", self.mpm.particles_per_cell),
            ));
        }
        if !(self.mpm.damping.is_finite() && self.mpm.damping >= 0.0) {
            return Err(err(
                "mpm.damping",
                format!("must be a finite number ≥ 0 (got {})", self.mpm.damping),
            ));
        }
        if !(0.0..=1.0).contains(&self.mpm.pic_fraction) {
            return Err(err(
                "mpm.pic_fraction",
                format!("must be 0 (FLIP) … 1 (PIC) (got {})", self.mpm.pic_fraction),
            ));
        }
        if self.materials.is_empty() {
            return Err(err("materials", "at least one material is required"));
        }
        for (i, m) in self.materials.iter().enumerate() {
            let p = |k: &str| format!("materials[{i}].{k}");
            if m.name.trim().is_empty() {
                return Err(err(p("name"), "must not be empty"));
            }
            if m.thickness.is_some() && m.kind != MaterialKind::Membrane {
                return Err(err(
                    p("thickness"),
                    "only for membranes (type = \"membrane\")",
                ));
            }
            if self.materials[..i].iter().any(|o| o.name == m.name) {
                return Err(err(p("name"), format!("`{}` is used twice", m.name)));
            }
            match m.kind {
                MaterialKind::Solid => validate_solid(m, &p)?,
                MaterialKind::Fluid => validate_fluid(m, &p)?,
                MaterialKind::Membrane => validate_membrane(m, &p)?,
            }
        }
        self.validate_membranes()?;
        if let Some(mp) = &self.multiphase {
            let names: Vec<&str> = self.materials.iter().map(|m| m.name.as_str()).collect();
            mp.validate_table(&names)?;
            self.validate_multiphase()?;
        }
        self.validate_object_keys()?;
        let has_solid = self.materials.iter().any(|m| m.kind == MaterialKind::Solid);
        let has_fluid = self.materials.iter().any(|m| m.in_cells());
        let has_gas = self.materials.iter().any(|m| m.is_gas_point());
        if has_gas {
            self.validate_gas_points()?;
        }
        let has_membrane = self
            .materials
            .iter()
            .any(|m| m.kind == MaterialKind::Membrane);
        let has_solid = has_solid || has_gas || has_membrane;
        if has_solid && has_fluid {
            self.validate_coupled()?;
        } else {
            for (i, m) in self.materials.iter().enumerate() {
                if m.rigid {
                    return Err(err(
                        format!("materials[{i}].rigid"),
                        "rigid solids need a fluid to move through (a coupled scene)",
                    ));
                }
            }
            if has_fluid {
                self.validate_heat_sources()?;
            } else if !self.heat_sources.is_empty() {
                return Err(err(
                    "heat_sources",
                    "heat sources heat fluid materials; this scene has none",
                ));
            }
            if !self.reactions.is_empty() {
                return Err(err(
                    "reactions",
                    "reactions burn a solid into a fluid: a coupled scene (solid and \
                     fluid materials) only",
                ));
            }
        }
        if self.implicit.hold_solid_faces
            && !(has_solid && has_fluid && t.mode == Mode::Implicit && !self.implicit.dynamic)
        {
            return Err(err(
                "implicit.hold_solid_faces",
                format!(
                    "holds a quasistatic solid's faces in the pressure stage: a coupled scene \
                     (solids and fluids) with time.mode = implicit and implicit.dynamic = false \
                     only (got time.mode = {}, dynamic = {}, {}); allowed here: false",
                    t.mode.name(),
                    self.implicit.dynamic,
                    if has_solid && has_fluid {
                        "coupled"
                    } else {
                        "not coupled"
                    }
                ),
            ));
        }
        match (t.mode, has_solid) {
            (Mode::SemiImplicit, true) if !has_fluid => {
                return Err(err(
                    "time.mode",
                    "semi_implicit (implicit pressure) needs fluid materials; allowed for \
                     solids alone: explicit, implicit",
                ))
            }
            (Mode::Implicit, true) if has_fluid && !self.reactions.is_empty() => {
                return Err(err(
                    "reactions",
                    "implicit MPM needs a fixed set of particles, and a reaction burns them \
                     away; allowed with reactions: time.mode = explicit, semi_implicit",
                ))
            }
            (Mode::Implicit, false) => {
                return Err(err(
                    "time.mode",
                    "implicit (implicit MPM) is for solid scenes; allowed for fluids: explicit, \
                     semi_implicit",
                ))
            }
            (Mode::Implicit, true) if t.dt.is_none() => {
                return Err(err(
                    "time.dt",
                    "missing; implicit mode needs the first timestep (> 0)",
                ))
            }
            _ => {}
        }
        if t.mode == Mode::Implicit {
            if self.mpm.pic_fraction > 0.0 {
                return Err(err(
                    "mpm.pic_fraction",
                    "the PIC share is part of the explicit particle update; implicit MPM moves \
                     its particles by the solved displacement; allowed: time.mode = explicit, \
                     semi_implicit",
                ));
            }
            if let Some(i) = self
                .materials
                .iter()
                .position(|m| m.plasticity.is_some() && m.model != Some(SolidModel::Hencky))
            {
                return Err(err(
                    format!("materials[{i}].plasticity"),
                    "the hypo-elastic J2 plasticity runs in explicit mode only (it has no \
                     consistent tangent); allowed: time.mode = explicit, semi_implicit, or \
                     model = \"hencky\" (multiplicative plasticity with its tangent) in \
                     implicit mode",
                ));
            }
            if let Some(i) = self.materials.iter().position(|m| m.failure.is_some()) {
                return Err(err(
                    format!("materials[{i}].failure"),
                    "failure runs in explicit mode only; allowed: time.mode = explicit, \
                     semi_implicit",
                ));
            }
        }
        self.validate_solvers()?;
        if g.axisymmetric {
            self.validate_axisymmetric(has_fluid)?;
        }
        for faces in g.boundary.faces().iter().take(dim) {
            let periodic = faces.map(|(bc, _)| bc == Some(Boundary::Periodic));
            if periodic[0] != periodic[1] {
                return Err(err(
                    format!("grid.boundary.{}", faces[0].1),
                    "periodic must be set on both faces of an axis",
                ));
            }
            if periodic[0] && has_solid && self.multiphase.is_none() {
                return Err(err(
                    format!("grid.boundary.{}", faces[0].1),
                    "periodic faces are available for fluid-only scenes; allowed for solids: \
                     fixed, symmetry, free",
                ));
            }
        }
        if let Some(gv) = &self.gravity {
            vec_len("gravity", gv, dim)?;
        }
        for (i, o) in self.objects.iter().enumerate() {
            let p = |k: &str| format!("objects[{i}].{k}");
            if !self.materials.iter().any(|m| m.name == o.material) {
                let names: Vec<&str> = self.materials.iter().map(|m| m.name.as_str()).collect();
                return Err(err(
                    p("material"),
                    format!(
                        "unknown material `{}`; defined: {}",
                        o.material,
                        names.join(", ")
                    ),
                ));
            }
            if self
                .materials
                .iter()
                .any(|m| m.name == o.material && !m.on_particles())
            {
                return Err(err(
                    p("material"),
                    format!(
                        "`{}` is a fluid in the cells; objects are filled with particles of \
                         solids or of fluids with frame = \"particles\"",
                        o.material
                    ),
                ));
            }
            if let Some(ppc) = o.particles_per_cell {
                if !(1..=16).contains(&ppc) {
                    return Err(err(
                        p("particles_per_cell"),
                        format!("must be 1 … 16 (got {ppc})"),
                    ));
                }
            }
            if let Some(v) = &o.velocity {
                vec_len(&p("velocity"), v, dim)?;
            }
            match &o.geometry {
                Geometry::HalfSpace { .. } => {}
                Geometry::Polygon { .. }
                | Geometry::Polyline { .. }
                | Geometry::Circle { .. }
                | Geometry::DogBone { .. }
                | Geometry::Intersection { .. } => {
                    validate_geometry(&o.geometry, &p("geometry"), dim)?
                }
                Geometry::Box { lower, upper } => {
                    vec_len(&p("geometry.lower"), lower, dim)?;
                    vec_len(&p("geometry.upper"), upper, dim)?;
                    for d in 0..dim {
                        if upper[d] <= lower[d] {
                            return Err(err(
                                format!("objects[{i}].geometry.upper[{d}]"),
                                format!("must be > geometry.lower[{d}] = {}", lower[d]),
                            ));
                        }
                    }
                }
                Geometry::Disk { center, radius } | Geometry::Sphere { center, radius } => {
                    vec_len(&p("geometry.center"), center, dim)?;
                    positive(&p("geometry.radius"), *radius)?;
                }
                Geometry::Annulus {
                    center,
                    inner_radius,
                    outer_radius,
                } => {
                    if dim < 2 {
                        return Err(err(p("geometry.type"), "annulus needs dim 2 or 3"));
                    }
                    vec_len(&p("geometry.center"), center, dim)?;
                    if !(inner_radius.is_finite() && *inner_radius >= 0.0) {
                        return Err(err(p("geometry.inner_radius"), "must be ≥ 0"));
                    }
                    if !(outer_radius.is_finite() && outer_radius > inner_radius) {
                        return Err(err(
                            p("geometry.outer_radius"),
                            format!("must be > inner_radius = {inner_radius}"),
                        ));
                    }
                }
            }
            if !o.clip {
                let (lo, hi) = o.geometry.bounds(dim);
                for d in 0..dim {
                    let tol = 1e-12 * (g.upper[d] - g.lower[d]);
                    if lo[d] < g.lower[d] - tol || hi[d] > g.upper[d] + tol {
                        return Err(err(
                            p("geometry"),
                            format!(
                                "particles would lie outside the grid along axis {d}: region \
                                 [{}, {}] vs grid [{}, {}] (set clip = true to keep only the \
                                 part inside)",
                                lo[d], hi[d], g.lower[d], g.upper[d]
                            ),
                        ));
                    }
                }
            }
        }
        for (i, o) in self.objects.iter().enumerate() {
            validate_geometry(&o.geometry, &format!("objects[{i}].geometry"), dim)?;
        }
        if has_solid && self.objects.is_empty() {
            return Err(err(
                "objects",
                "a scene with solids needs at least one object",
            ));
        }
        if has_fluid {
            self.validate_fluid_regions()?;
        } else if !self.regions.is_empty() {
            return Err(err(
                "regions",
                "regions set fluid states; the scene has no fluid",
            ));
        } else if self.fluid.inflow.any() {
            return Err(err(
                "fluid.inflow",
                "inflow faces set fluid states; the scene has no fluid",
            ));
        }
        self.validate_output()
    }

    fn validate_time(&self) -> Result<(), SceneError> {
        let t = &self.time;
        positive("time.end", t.end)?;
        if !(t.cfl.is_finite() && t.cfl > 0.0 && t.cfl <= 1.0) {
            return Err(err(
                "time.cfl",
                format!("must satisfy 0 < cfl ≤ 1 (got {})", t.cfl),
            ));
        }
        if let Some(dt) = t.dt {
            positive("time.dt", dt)?;
        }
        if t.max_steps == Some(0) {
            return Err(err("time.max_steps", "must be ≥ 1 (got 0)"));
        }
        if !(t.min_dt_fraction > 0.0 && t.min_dt_fraction < 1.0) {
            return Err(err(
                "time.min_dt_fraction",
                format!("must satisfy 0 < fraction < 1 (got {})", t.min_dt_fraction),
            ));
        }
        if t.max_projected_steps.is_nan() || t.max_projected_steps < 1.0 {
            return Err(err(
                "time.max_projected_steps",
                format!("must be ≥ 1 (got {})", t.max_projected_steps),
            ));
        }
        Ok(())
    }

    fn validate_output(&self) -> Result<(), SceneError> {
        let out = &self.output;
        if let Some(iv) = out.interval {
            positive("output.interval", iv)?;
        }
        if let Some(iv) = out.history_interval {
            positive("output.history_interval", iv)?;
        }
        if let Some(iv) = out.checkpoint_interval {
            positive("output.checkpoint_interval", iv)?;
        }
        if let Some(level) = out.vtk_compression_level {
            if out.vtk_compression != VtkCompression::Zlib {
                return Err(err(
                    "output.vtk_compression_level",
                    "only with output.vtk_compression = \"zlib\"",
                ));
            }
            if !(1..=9).contains(&level) {
                return Err(err(
                    "output.vtk_compression_level",
                    format!("must be 1 (fastest) to 9 (smallest) (got {level})"),
                ));
            }
        }
        Ok(())
    }
}

/// Membrane-only object keys must be absent on other objects.
fn membrane_keys_absent(o: &ObjectSpec, i: usize) -> Result<(), SceneError> {
    for (v, k) in [
        (o.spacing.is_some(), "spacing"),
        (o.fixed_ends, "fixed_ends"),
        (o.prestress.is_some(), "prestress"),
    ] {
        if v {
            return Err(err(
                format!("objects[{i}].{k}"),
                "only for membrane objects (materials with type = \"membrane\")",
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::Geometry;

    /// A quarter annulus's prism cut to 0 ≤ z ≤ 1 by a box: inside where
    /// every part is, with the box's z bounds and the annulus's x–y bounds.
    #[test]
    fn an_intersection_is_inside_every_part_and_bounded_by_the_tightest() {
        let g = Geometry::Intersection {
            parts: vec![
                Geometry::Annulus {
                    center: vec![0.0, 0.0, 0.0],
                    inner_radius: 1.0,
                    outer_radius: 2.0,
                },
                Geometry::Box {
                    lower: vec![0.0, 0.0, 0.0],
                    upper: vec![5.0, 5.0, 1.0],
                },
            ],
        };
        assert!(g.contains(&[1.5, 0.1, 0.5]));
        assert!(!g.contains(&[1.5, 0.1, 1.5])); // above the box
        assert!(!g.contains(&[-1.5, 0.1, 0.5])); // outside the box in x
        assert!(!g.contains(&[0.5, 0.1, 0.5])); // in the annulus's hole
        let (lo, hi) = g.bounds(3);
        assert_eq!(lo, vec![0.0, 0.0, 0.0]);
        assert_eq!(hi, vec![2.0, 2.0, 1.0]);
        // A polygon's prism cut by a half space keeps the prism's x–y
        // bounds and the half space's open z.
        let prism = Geometry::Intersection {
            parts: vec![
                Geometry::Polygon {
                    vertices: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
                },
                Geometry::HalfSpace {
                    point: vec![0.0, 0.0, 2.0],
                    normal: vec![0.0, 0.0, -1.0],
                },
            ],
        };
        assert!(prism.contains(&[0.2, 0.2, -7.0]));
        assert!(!prism.contains(&[0.2, 0.2, 2.5]));
        assert!(!prism.contains(&[0.8, 0.8, 0.0]));
        let (lo, hi) = prism.bounds(3);
        assert_eq!((lo[0], hi[1]), (0.0, 1.0));
        assert_eq!((lo[2], hi[2]), (f64::NEG_INFINITY, f64::INFINITY));
    }
}
