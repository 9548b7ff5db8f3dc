//! The model interface: what every system (explicit or implicit solid, ICE,
//! coupled MPM-ICE, and every later one) provides to the one run loop
//! ([`crate::driver::run_model`]).
//!
//! A model knows its physics only: its time, its stable time step, one step,
//! its snapshot fields with names and units, its conservation totals, a
//! watchdog scan for impossible values, and saving and loading its whole
//! state. Time control, retries, outputs, checkpoints, progress and the
//! summary are the loop's.

use serde::Serialize;

use crate::error::Error;
use crate::output::checkpoint::{Checkpoint, CheckpointError};
use crate::stepper::Energies;

/// The time step the loop asks a model to take.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DtRequest {
    /// Upper bound: the time left to the end or to the next snapshot, the
    /// scene's fixed step, or a retry's cut.
    pub value: f64,
    /// Take exactly `value` (a fixed time step, `time.dt`) instead of
    /// `min(stable Δt, value)`.
    pub exact: bool,
}

/// What one accepted step did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepStats {
    /// The time step taken.
    pub dt: f64,
    /// Nonlinear iterations: Newton (implicit MPM) or outer pressure
    /// iterations (semi-implicit ICE); 0 for explicit steps.
    pub nonlinear_iterations: usize,
    /// Krylov iterations behind them (0 with a direct solver).
    pub linear_iterations: usize,
    /// Attempts the model itself cut and repeated inside the step (implicit
    /// MPM's Δt control); the loop's own retries are counted apart.
    pub retries: usize,
    /// What entered the state through the domain boundary in this step,
    /// where the model accounts for it (ICE); the summary subtracts it from
    /// the change of the totals.
    pub boundary: Option<crate::ice::BoundaryExchange>,
}

/// Conservation totals of one material.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct MaterialTotals {
    /// The material's scene name.
    pub name: String,
    /// Mass [kg, per depth in 2D, per area in 1D].
    pub mass: f64,
    /// Momentum (x, y, z; zero beyond the dimension).
    pub momentum: [f64; 3],
    /// Kinetic energy Σ ½ m |v|².
    pub kinetic: f64,
    /// Stored energy: strain energy of a solid, internal energy of a fluid.
    pub internal: f64,
}

/// The conserved quantities of a model's whole state.
#[derive(Debug, Clone, Default)]
pub struct Conserved {
    /// Per material, in the scene's material order.
    pub materials: Vec<MaterialTotals>,
    /// System energies (kinetic; stored in `strain`; body-force potential).
    pub energies: Energies,
    /// Σ m |v|: the scale of the momentum drift.
    pub momentum_scale: f64,
}

impl Conserved {
    /// Total mass.
    pub fn mass(&self) -> f64 {
        self.materials.iter().map(|m| m.mass).sum()
    }

    /// Total momentum.
    pub fn momentum(&self) -> [f64; 3] {
        let mut p = [0.0; 3];
        for m in &self.materials {
            for d in 0..3 {
                p[d] += m.momentum[d];
            }
        }
        p
    }
}

/// Values of one snapshot field, one entry per point or cell.
#[derive(Clone)]
pub enum Values<'a> {
    /// One number.
    Scalar(Vec<f64>),
    /// A vector padded to 3 components.
    Vector(Vec<[f64; 3]>),
    /// A 3×3 tensor, row-major.
    Tensor(Vec<[f64; 9]>),
    /// Values computed from the model's arrays as they are written, so that
    /// a snapshot of a large run copies nothing (issue 24: a copy of every
    /// particle field took 264 bytes a particle at each snapshot).
    Computed(Computed<'a>),
}

/// Pads a `D`-vector to 3 components (the outputs' vectors are 3D).
pub fn pad3<const D: usize>(v: &nalgebra::SVector<f64, D>) -> [f64; 3] {
    std::array::from_fn(|i| if i < D { v[i] } else { 0.0 })
}

/// Writes tuple `i` of a [`Computed`] field into its output slice.
pub type TupleFn<'a> = dyn Fn(usize, &mut [f64]) + Send + Sync + 'a;

/// A field computed on demand: `n` tuples of `components` values (1, 3 or
/// 9, laid out as [`Values::Scalar`], [`Values::Vector`] or
/// [`Values::Tensor`]), tuple `i` written by `f(i, out)` into
/// `out[..components]`.
#[derive(Clone)]
pub struct Computed<'a> {
    /// Number of tuples.
    pub n: usize,
    /// Values per tuple: 1, 3 or 9.
    pub components: usize,
    /// Writes tuple `i`.
    pub f: std::sync::Arc<TupleFn<'a>>,
}

impl<'a> Values<'a> {
    /// `n` tuples of `components` values (1, 3 or 9) computed by `f`.
    pub fn computed(
        n: usize,
        components: usize,
        f: impl Fn(usize, &mut [f64]) + Send + Sync + 'a,
    ) -> Self {
        debug_assert!(matches!(components, 1 | 3 | 9));
        Values::Computed(Computed {
            n,
            components,
            f: std::sync::Arc::new(f),
        })
    }

    /// A scalar field read from `v` as it is written.
    pub fn scalars(v: &'a [f64]) -> Self {
        Self::computed(v.len(), 1, move |i, o| o[0] = v[i])
    }

    /// A vector field read from `v` (padded to 3 components) as it is
    /// written.
    pub fn vectors<const D: usize>(v: &'a [nalgebra::SVector<f64, D>]) -> Self {
        Self::computed(v.len(), 3, move |i, o| o[..3].copy_from_slice(&pad3(&v[i])))
    }

    /// A tensor field read from `m` (row-major) as it is written.
    pub fn tensors<const D: usize, const SYM: bool>(t: &'a crate::mpm::Tensors<D, SYM>) -> Self {
        Self::computed(t.len(), 9, move |i, o| {
            let m = t.get(i);
            for (k, x) in o[..9].iter_mut().enumerate() {
                *x = m[(k / 3, k % 3)];
            }
        })
    }

    /// Number of tuples.
    pub fn len(&self) -> usize {
        match self {
            Values::Scalar(v) => v.len(),
            Values::Vector(v) => v.len(),
            Values::Tensor(v) => v.len(),
            Values::Computed(c) => c.n,
        }
    }

    /// Whether there are no tuples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Values per tuple: 1, 3 or 9.
    pub fn components(&self) -> usize {
        match self {
            Values::Scalar(_) => 1,
            Values::Vector(_) => 3,
            Values::Tensor(_) => 9,
            Values::Computed(c) => c.components,
        }
    }

    /// Writes tuple `i` into `out[..self.components()]`.
    pub fn tuple(&self, i: usize, out: &mut [f64]) {
        match self {
            Values::Scalar(v) => out[0] = v[i],
            Values::Vector(v) => out[..3].copy_from_slice(&v[i]),
            Values::Tensor(v) => out[..9].copy_from_slice(&v[i]),
            Values::Computed(c) => (c.f)(i, out),
        }
    }

    /// The values stored (a computed field evaluated), independent of the
    /// model they were read from.
    pub fn into_owned(self) -> Values<'static> {
        match self {
            Values::Scalar(v) => Values::Scalar(v),
            Values::Vector(v) => Values::Vector(v),
            Values::Tensor(v) => Values::Tensor(v),
            Values::Computed(c) => {
                let mut t = [0.0; 9];
                let mut tuple = |i: usize| {
                    (c.f)(i, &mut t);
                    t
                };
                match c.components {
                    1 => Values::Scalar((0..c.n).map(|i| tuple(i)[0]).collect()),
                    3 => Values::Vector(
                        (0..c.n)
                            .map(|i| std::array::from_fn(|k| tuple(i)[k]))
                            .collect(),
                    ),
                    _ => Values::Tensor((0..c.n).map(tuple).collect()),
                }
            }
        }
    }
}

impl std::fmt::Debug for Values<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Values::Scalar(v) => f.debug_tuple("Scalar").field(v).finish(),
            Values::Vector(v) => f.debug_tuple("Vector").field(v).finish(),
            Values::Tensor(v) => f.debug_tuple("Tensor").field(v).finish(),
            Values::Computed(c) => f
                .debug_struct("Computed")
                .field("n", &c.n)
                .field("components", &c.components)
                .finish_non_exhaustive(),
        }
    }
}

/// Equal when the tuples are equal, whether stored or computed.
impl PartialEq for Values<'_> {
    fn eq(&self, other: &Self) -> bool {
        if self.len() != other.len() || self.components() != other.components() {
            return false;
        }
        let (mut a, mut b) = ([0.0; 9], [0.0; 9]);
        (0..self.len()).all(|i| {
            self.tuple(i, &mut a);
            other.tuple(i, &mut b);
            a == b
        })
    }
}

/// A named snapshot field with its unit.
#[derive(Debug, Clone, PartialEq)]
pub struct OutField<'a> {
    /// Name in the VTK file.
    pub name: String,
    /// Column base name in the CSV file (vectors add `x`, `y`, `z`, tensors
    /// the index pair, e.g. `sxy`); `None`: VTK only.
    pub csv: Option<String>,
    /// Unit, e.g. `m/s` or `kg/m` (already per depth where it applies).
    pub unit: String,
    /// The values.
    pub values: Values<'a>,
}

impl<'a> OutField<'a> {
    /// A field with the CSV name equal to the VTK name.
    pub fn new(name: &str, unit: &str, values: Values<'a>) -> Self {
        Self {
            name: name.to_string(),
            csv: Some(name.to_string()),
            unit: unit.to_string(),
            values,
        }
    }

    /// A field with its own CSV base name (`None`: not in the CSV).
    pub fn with_csv(name: &str, csv: Option<&str>, unit: &str, values: Values<'a>) -> Self {
        Self {
            name: name.to_string(),
            csv: csv.map(str::to_string),
            unit: unit.to_string(),
            values,
        }
    }
}

/// Where a field set lives.
#[derive(Debug, Clone, PartialEq)]
pub enum Geometry<'a> {
    /// Scattered points (particles): positions padded to 3D (3-component
    /// values, read from the model as they are written where it can).
    Points(Values<'a>),
    /// A structured grid; the fields are on its nodes or on its cells.
    Image {
        /// Lower corner.
        origin: [f64; 3],
        /// Cell size (1 beyond the dimension).
        spacing: [f64; 3],
        /// Cells per direction (0 beyond the dimension).
        cells: [usize; 3],
        /// Whether the fields are per cell (else per node).
        on_cells: bool,
        /// Cell centres of the CSV rows (cell fields only; empty otherwise).
        centres: Vec<[f64; 3]>,
    },
    /// A quadrilateral surface mesh (membrane elements); the fields are on
    /// its nodes or on its quads.
    Quads {
        /// Node positions.
        points: Vec<[f64; 3]>,
        /// Corner node ids of each quad.
        quads: Vec<[u32; 4]>,
        /// Whether the fields are per quad (else per node).
        on_cells: bool,
        /// Quad centres of the CSV rows (quad fields only; empty otherwise).
        centres: Vec<[f64; 3]>,
    },
}

/// One group of snapshot fields: written as `NAME_NNNN.vtu|vti` (with a
/// `NAME.pvd` series) and, if `csv`, `NAME_NNNN.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldSet<'a> {
    /// File stem: `particles`, `grid`, `cells`, ….
    pub name: &'static str,
    /// Points or grid.
    pub geometry: Geometry<'a>,
    /// The fields.
    pub fields: Vec<OutField<'a>>,
    /// Whether to write a CSV table too (when the scene asks for CSV).
    pub csv: bool,
}

impl FieldSet<'_> {
    /// The set with every computed field evaluated, independent of the
    /// model it was read from.
    pub fn into_owned(self) -> FieldSet<'static> {
        FieldSet {
            name: self.name,
            geometry: match self.geometry {
                Geometry::Points(x) => Geometry::Points(x.into_owned()),
                Geometry::Image {
                    origin,
                    spacing,
                    cells,
                    on_cells,
                    centres,
                } => Geometry::Image {
                    origin,
                    spacing,
                    cells,
                    on_cells,
                    centres,
                },
                Geometry::Quads {
                    points,
                    quads,
                    on_cells,
                    centres,
                } => Geometry::Quads {
                    points,
                    quads,
                    on_cells,
                    centres,
                },
            },
            fields: self
                .fields
                .into_iter()
                .map(|f| OutField {
                    name: f.name,
                    csv: f.csv,
                    unit: f.unit,
                    values: f.values.into_owned(),
                })
                .collect(),
            csv: self.csv,
        }
    }
}

/// Where an impossible value sits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    /// A material point.
    Particle(usize),
    /// A grid cell (flat index of the model's cell layout) with its integer
    /// coordinates.
    Cell(usize, [isize; 3]),
    /// A membrane finite element (index in its mesh).
    Element(usize),
    /// A membrane finite-element node (index in its mesh).
    Node(usize),
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Location::Particle(p) => write!(f, "particle {p}"),
            Location::Cell(c, ijk) => write!(f, "cell {c} {ijk:?}"),
            Location::Element(e) => write!(f, "element {e}"),
            Location::Node(n) => write!(f, "node {n}"),
        }
    }
}

/// A non-finite or physically impossible value found by the watchdog.
#[derive(Debug, Clone, PartialEq)]
pub struct Violation {
    /// Particle or cell.
    pub at: Location,
    /// The material's scene name.
    pub material: String,
    /// The field, e.g. `J`, `mass`, `temperature`.
    pub field: &'static str,
    /// The offending value.
    pub value: f64,
    /// What it must satisfy, e.g. `> 0 and finite`.
    pub rule: &'static str,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} of material `{}`: {} = {:e} (must be {})",
            self.at, self.material, self.field, self.value, self.rule
        )
    }
}

/// Sizes of a model for the run summary.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Counts {
    /// Material points.
    pub particles: usize,
    /// Grid cells (interior).
    pub cells: usize,
    /// Fluid materials.
    pub fluid_materials: usize,
    /// Membrane finite elements.
    pub elements: usize,
}

/// What the steps of a coupled implicit run did (since this run started:
/// a restart counts from the restart).
#[derive(Debug, Clone, Default, Serialize)]
pub struct CoupledIterations {
    /// Mean passes (pressure stage + implicit solves) per step; 1 for the
    /// staggered step.
    pub passes_mean: f64,
    /// Most passes of one step.
    pub passes_max: u64,
    /// Seconds in the pressure stages (the cells' part of the time split).
    pub cells_s: f64,
    /// Per implicit solid field.
    pub fields: Vec<FieldIterations>,
}

/// One implicit solid field's Newton solves in a coupled run.
#[derive(Debug, Clone, Default, Serialize)]
pub struct FieldIterations {
    /// The field's material (scene name).
    pub material: String,
    /// Mean Newton iterations per step (over all passes of the step).
    pub newton_mean: f64,
    /// Most Newton iterations of one solve.
    pub newton_max: u64,
    /// Mean Krylov iterations per step (0 with the direct solver).
    pub linear_mean: f64,
    /// Mean tangent factorisations per step (the Newton iterations with
    /// full Newton, fewer with `implicit.modified_newton`).
    pub factorisations_mean: f64,
}

/// How a model describes itself in the run summary.
#[derive(Debug, Clone, Default)]
pub struct Description {
    /// Shape function (empty without particles).
    pub shape: String,
    /// MPM update scheme, `newmark` or `quasistatic` (empty without
    /// particles).
    pub update: String,
    /// Whether its steps iterate (implicit MPM, semi-implicit pressure): the
    /// summary then reports iteration counts.
    pub iterative: bool,
    /// Whether the momentum of the whole state is conserved (walls and
    /// boundary pressures exchange momentum with a coupled system).
    pub momentum_conserved: bool,
    /// r–z: only the axial (second) component of the momentum is conserved
    /// (the hoop force changes the radial one), so the drift is of it.
    pub axial_momentum_only: bool,
    /// Wall time per phase of the explicit MPM step.
    pub phase_times: crate::mpm::PhaseTimes,
    /// Implicit MPM: seconds in assembly, factorisation, solves and particle
    /// updates.
    pub implicit_split: Option<[f64; 4]>,
    /// Coupled implicit MPM-ICE: passes, pressure-stage time and Newton
    /// iterations per field.
    pub coupled_iterations: Option<CoupledIterations>,
}

/// A system the run loop drives.
pub trait Model {
    /// Kind and dimension, e.g. `explicit_solid_2d`: a checkpoint of another
    /// kind is rejected.
    fn kind(&self) -> String;
    /// Current time.
    fn time(&self) -> f64;
    /// Completed steps.
    fn steps(&self) -> u64;
    /// The stable time step of the current state (CFL estimate; for an
    /// implicit model the step it will try next).
    fn stable_dt(&self) -> f64;
    /// Takes one step. On an error whose [`Error::retry_dt`] is `Some`, the
    /// state must be as before the call so that the loop can retry with a
    /// smaller step.
    fn step(&mut self, dt: DtRequest) -> Result<StepStats, Error>;
    /// The Δt below which a failed step may be retried (`None`: the
    /// failure is final, or the model already retried inside the step).
    fn retry_dt(&self, e: &Error) -> Option<f64> {
        e.retry_dt()
    }
    /// Adds what the model knows to a step's error (e.g. the scene name of
    /// the failing particle's material).
    fn annotate(&self, e: Error) -> Error {
        e
    }
    /// The snapshot fields of the current state.
    fn field_sets(&self) -> Vec<FieldSet<'_>>;
    /// Columns of `history.csv` after the time: `(quantity, unit)`, units
    /// before the per-depth suffix the loop appends.
    fn history_columns(&self) -> Vec<(&'static str, &'static str)>;
    /// Appends one history row's values (after the time) to `row`.
    fn history_row(&self, row: &mut Vec<f64>);
    /// Conservation totals.
    fn conserved(&self) -> Conserved;
    /// The first non-finite or impossible value of the state, if any.
    fn watchdog(&self) -> Option<Violation>;
    /// Writes the whole state (everything a later step reads) into `ck`.
    fn save(&self, ck: &mut Checkpoint);
    /// Restores the whole state from `ck`, after the model was built from
    /// the same scene.
    ///
    /// # Errors
    /// A missing array or one of the wrong shape.
    fn load(&mut self, ck: &mut Checkpoint) -> Result<(), CheckpointError>;
    /// Sizes for the summary.
    fn counts(&self) -> Counts;
    /// Description for the summary.
    fn describe(&self) -> Description;
    /// The particle or cell (and its material) that sets
    /// [`Self::stable_dt`], named when the run's Δt collapses or projects an
    /// absurd number of steps (`None`: the model does not say).
    fn dt_limiter(&self) -> Option<crate::driver::limiter::DtLimiter> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, SVector};

    /// A computed field equals the stored one it stands for, and
    /// `into_owned` stores exactly those values.
    #[test]
    fn computed_values_equal_their_stored_form() {
        let v = [SVector::from([1.0, -2.0]), SVector::from([0.5, 1e-300])];
        let m = crate::mpm::Tensors::<3>::try_from_matrices(&[
            Matrix3::from_fn(|i, j| (3 * i + j) as f64),
            Matrix3::identity(),
        ])
        .expect("3D tensors");
        let s = [0.25, -7.0];
        let stored_v = Values::Vector(vec![[1.0, -2.0, 0.0], [0.5, 1e-300, 0.0]]);
        let stored_m = Values::Tensor(vec![
            std::array::from_fn(|k| k as f64),
            [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        ]);
        for (lazy, stored) in [
            (Values::vectors(&v), stored_v),
            (Values::tensors(&m), stored_m),
            (Values::scalars(&s), Values::Scalar(s.to_vec())),
        ] {
            assert_eq!(lazy, stored);
            assert_eq!((lazy.len(), lazy.components()), (2, stored.components()));
            let owned = lazy.into_owned();
            assert!(!matches!(owned, Values::Computed(_)));
            assert_eq!(owned, stored);
        }
        assert_ne!(Values::scalars(&s), Values::Scalar(vec![0.25, -7.5]));
        assert_ne!(Values::scalars(&s), Values::Scalar(vec![0.25]));
    }
}
