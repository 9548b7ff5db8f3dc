//! The block-in-air test of Zhang Sec. 3: a solid (disk, sphere or box)
//! translating through air at the air's velocity across a periodic box.
//! Nothing may change: the scene builder and the measure of how much did
//! (for the multiphase model, its tests and the `zhang_block` study).

use crate::error::Error;
use crate::multiphase::MultiphaseRun;
use crate::scene::{build_multiphase_run, parse};

/// One block-in-air set-up.
#[derive(Debug, Clone)]
pub struct BlockCase {
    /// Dimension, 2 or 3.
    pub dim: usize,
    /// Cells per side of the unit box.
    pub cells: usize,
    /// `weak`, `strong` or `eulerian`.
    pub constraint: &'static str,
    /// Velocity of solid and air (first `dim` components).
    pub velocity: [f64; 3],
    /// End time.
    pub end: f64,
    /// Courant number.
    pub cfl: f64,
    /// `sphere` (a disk in 2D; radius 0.2) or `box` (side 0.4), centred.
    pub solid: &'static str,
    /// Points per cell per direction of the solid (the air has 2).
    pub solid_ppc: usize,
}

/// The block test's solid (a `[[materials]]` table): `block`, linear
/// elastic (ρ = 1000, E = 1e8, ν = 0.3); the objects give its 1e5 Pa
/// prestress.
pub const BLOCK_SOLID: &str = r#"
[[materials]]
name = "block"
type = "solid"
model = "linear_elastic"
density = 1000.0
youngs_modulus = 1.0e8
poisson_ratio = 0.3
"#;

/// Air as gas points (a `[[materials]]` table): `air`, an ideal gas with
/// γ = 1.4, c_v = 717.5 J/(kg K); the objects give its density and state.
pub const AIR_POINTS: &str = r#"
[[materials]]
name = "air"
type = "fluid"
frame = "particles"
eos = "ideal_gas"
gamma = 1.4
cv = 717.5
"#;

impl BlockCase {
    /// The scene: a linear-elastic solid (ρ = 1000, E = 1e8, ν = 0.3)
    /// prestressed to the air's 1e5 Pa, ideal-gas air at 1.2 kg/m³,
    /// GIMP, periodic on every axis.
    pub fn scene(&self) -> String {
        let dim = self.dim;
        let v = |x: [f64; 3]| {
            x[..dim]
                .iter()
                .map(|c| format!("{c:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let axes = ["x", "y", "z"];
        let bcs: Vec<String> = axes[..dim]
            .iter()
            .flat_map(|a| {
                [
                    format!("{a}_lower = \"periodic\""),
                    format!("{a}_upper = \"periodic\""),
                ]
            })
            .collect();
        let geometry = match self.solid {
            "box" => format!(
                "{{ type = \"box\", lower = [{}], upper = [{}] }}",
                v([0.3; 3]),
                v([0.7; 3])
            ),
            _ => format!(
                "{{ type = \"sphere\", center = [{}], radius = 0.2 }}",
                v([0.5; 3])
            ),
        };
        format!(
            r#"
[grid]
dim = {dim}
lower = [{lo}]
upper = [{hi}]
cells = [{cells}]
boundary = {{ {bcs} }}

[time]
end = {end:?}
cfl = {cfl:?}

[mpm]
shape = "gimp"

[multiphase]
constraint = "{constraint}"

{BLOCK_SOLID}{AIR_POINTS}
[[objects]]
material = "block"
geometry = {geometry}
particles_per_cell = {ppc}
velocity = [{u}]
pressure = 1.0e5

[[objects]]
material = "air"
geometry = {{ type = "box", lower = [{lo}], upper = [{hi}] }}
except = [0]
particles_per_cell = 2
velocity = [{u}]
density = 1.2
pressure = 1.0e5
"#,
            lo = v([0.0; 3]),
            hi = v([1.0; 3]),
            cells = vec![self.cells.to_string(); dim].join(", "),
            bcs = bcs.join(", "),
            end = self.end,
            cfl = self.cfl,
            constraint = self.constraint,
            ppc = self.solid_ppc,
            u = v(self.velocity),
        )
    }
}

/// What changed over a block run.
#[derive(Debug, Clone, Copy)]
pub struct BlockOutcome {
    /// Largest relative pressure change of any point, |p − 1e5| / 1e5.
    pub pressure: f64,
    /// Largest velocity change of any point over the speed.
    pub velocity: f64,
    /// Steps taken.
    pub steps: u64,
    /// Points.
    pub points: usize,
    /// Whether the run reached its end (the strong constraint may fail).
    pub completed: bool,
}

/// The changes of a run's points from the uniform state.
pub fn block_changes<const D: usize>(run: &MultiphaseRun<D>, u: &[f64; 3]) -> (f64, f64) {
    let speed = u[..D].iter().map(|c| c * c).sum::<f64>().sqrt();
    let (mut dp, mut dv) = (0.0f64, 0.0f64);
    for ph in &run.phases {
        let p = &ph.particles;
        for i in 0..p.len() {
            let pr = -p.stress.get(i).trace() / 3.0;
            dp = dp.max((pr - 1e5).abs() / 1e5);
            let e = (0..D)
                .map(|d| (p.v[i][d] - u[d]).powi(2))
                .sum::<f64>()
                .sqrt();
            dv = dv.max(e / speed);
        }
    }
    (dp, dv)
}

/// Runs a case to its end (or to its first failure, keeping the state
/// before it) and measures the changes.
///
/// # Errors
/// A scene that does not build.
pub fn run_block<const D: usize>(case: &BlockCase) -> Result<BlockOutcome, Error> {
    let scene = parse(&case.scene())?;
    let mut run: MultiphaseRun<D> = build_multiphase_run(&scene)?;
    let end = case.end;
    let mut completed = true;
    let mut worst = (0.0f64, 0.0f64);
    while run.t < end * (1.0 - 1e-12) {
        let dt = run.stable_dt().min(end - run.t);
        if run.step(dt).is_err() {
            completed = false;
            break;
        }
        let (dp, dv) = block_changes(&run, &case.velocity);
        if !(dp.is_finite() && dv.is_finite()) {
            completed = false;
            break;
        }
        worst = (worst.0.max(dp), worst.1.max(dv));
    }
    Ok(BlockOutcome {
        pressure: worst.0,
        velocity: worst.1,
        steps: run.steps,
        points: run.phases.iter().map(|p| p.particles.len()).sum(),
        completed,
    })
}
