//! Zhang's multiphase formulation and Guilkey's MPM-ICE side by side on the
//! same physical scenes (issue 19): the scenes are the case files
//! `cases/zhang_vs_guilkey_block_{multiphase,coupled}.toml` and
//! `cases/shock_on_steel_block_{multiphase,coupled}.toml`, built through the
//! normal scene builders, so a user runs the same thing from the CLI.
//!
//! - **Block test** (Zhang Sec. 3): a linear-elastic disk (ρ = 1000,
//!   E = 1e8, ν = 0.3, radius 0.15) moving with the air (ideal gas, 1.1768
//!   kg/m³, 101325 Pa) at (10, 10) m/s across the unit square from
//!   (0.25, 0.25) to (0.75, 0.75) (10 cell crossings at 20 cells). Exact:
//!   nothing changes. Measured: the largest relative air-pressure change
//!   and the largest velocity change over the speed, over every step. The
//!   multiphase scene is periodic (its air points would leave through free
//!   faces), the coupled one has free (outflow) faces (the coupled path
//!   offers no periodic faces for solids); both are exact for the uniform
//!   flow.
//! - **Shock on a steel block**: a Mach 1.5 air shock from a driver section
//!   hits a steel block; the air pressure at a probe in front of the block
//!   on its symmetry plane against the reflected-shock pressure `p5` of the
//!   exact 1D shock relations ([`ShockExact`]), and the block's momentum
//!   against the 1D rate `(p5 − p1) b`.
//!
//! Both report their cost: steps, the median wall time of a step (the
//! stable-step computation included) and, for MPM-ICE, the share of the
//! step spent in the pressure stages ([`CoupledRun::pressure_s`]: Guilkey
//! Sec. 3.3 steps 2–6). Zhang's formulation has no pressure solve (each
//! point's pressure is its own EOS after the closure's volume rate), so it
//! reports none.

use std::time::Instant;

use nalgebra::SVector;

use crate::coupling::CoupledRun;
use crate::error::{Error, Result, SceneError};
use crate::multiphase::MultiphaseRun;
use crate::scene::{build_coupled_run, build_multiphase_run, parse};

/// The block test, Zhang's formulation (`[multiphase]`).
pub const BLOCK_MULTIPHASE: &str =
    include_str!("../../cases/zhang_vs_guilkey_block_multiphase.toml");
/// The block test, Guilkey's MPM-ICE.
pub const BLOCK_COUPLED: &str = include_str!("../../cases/zhang_vs_guilkey_block_coupled.toml");
/// The shock on the steel block, Zhang's formulation.
pub const SHOCK_MULTIPHASE: &str = include_str!("../../cases/shock_on_steel_block_multiphase.toml");
/// The shock on the steel block, Guilkey's MPM-ICE.
pub const SHOCK_COUPLED: &str = include_str!("../../cases/shock_on_steel_block_coupled.toml");

/// Which formulation runs a scene.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Formulation {
    /// Zhang: every material on points with its own velocity field
    /// (`src/multiphase/`).
    Multiphase,
    /// Guilkey: solids on points, the air in ICE cells (`src/coupling/`).
    Coupled,
}

impl Formulation {
    /// Short name (`multiphase`, `coupled`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Multiphase => "multiphase",
            Self::Coupled => "coupled",
        }
    }
}

/// The cost of a run.
#[derive(Debug, Clone, Copy, Default)]
pub struct Cost {
    /// Steps taken.
    pub steps: u64,
    /// Wall time of the stepping \[s\].
    pub wall_s: f64,
    /// Median wall time of one step \[s\] (its stable-step computation
    /// included).
    pub median_step_s: f64,
    /// MPM-ICE: the share of the stepping's wall time spent in the
    /// pressure stages; `None` for the multiphase model (no pressure solve).
    pub pressure_share: Option<f64>,
}

/// Collects the step wall times of a run.
struct StepClock {
    times: Vec<f64>,
    start: Instant,
}

impl StepClock {
    fn new(expected_steps: usize) -> Self {
        Self {
            times: Vec::with_capacity(expected_steps.clamp(16, 1 << 22)),
            start: Instant::now(),
        }
    }

    /// Times `f`, one step.
    fn step<T>(&mut self, f: impl FnOnce() -> T) -> T {
        let s = Instant::now();
        let out = f();
        self.times.push(s.elapsed().as_secs_f64());
        out
    }

    fn finish(mut self, steps: u64, pressure_s: Option<f64>) -> Cost {
        let wall_s = self.start.elapsed().as_secs_f64();
        self.times.sort_by(f64::total_cmp);
        let n = self.times.len();
        let median_step_s = match n {
            0 => 0.0,
            _ if !n.is_multiple_of(2) => self.times[n / 2],
            _ => 0.5 * (self.times[n / 2 - 1] + self.times[n / 2]),
        };
        let stepping: f64 = self.times.iter().sum();
        Cost {
            steps,
            wall_s,
            median_step_s,
            pressure_share: pressure_s.map(|p| p / stepping.max(1e-300)),
        }
    }
}

/// `text` with the one occurrence of `from` replaced by `to`.
///
/// # Errors
/// A scene error naming `from` when it does not occur exactly once (the
/// case file changed under its user).
fn edit(text: &str, from: &str, to: &str) -> Result<String> {
    match text.matches(from).count() {
        1 => Ok(text.replacen(from, to, 1)),
        n => Err(SceneError::new(
            "<case file>",
            format!("expected `{from}` once in the case file, found it {n} times"),
        )
        .into()),
    }
}

/// Air pressure of both scenes before anything happens \[Pa\].
pub const P1: f64 = 101_325.0;

/// Velocity of disk and air in the block test [m/s].
pub const BLOCK_VELOCITY: [f64; 2] = [10.0, 10.0];

/// One block-test run: formulation, resolution, constraint, end time.
#[derive(Debug, Clone, Copy)]
pub struct BlockCase {
    /// Which formulation.
    pub formulation: Formulation,
    /// Cells per side of the unit square (the case files: 20).
    pub cells: usize,
    /// Multiphase only: `weak` (Zhang Eq. 18) or `strong` (Eq. 7).
    pub constraint: &'static str,
    /// `mpm.shape` (the case files: `gimp`; MPM-ICE's customary one is
    /// `linear`).
    pub shape: &'static str,
    /// End time (the case files: 0.05 s, the disk centre from (0.25, 0.25)
    /// to (0.75, 0.75); it must stay inside the box).
    pub end: f64,
}

impl BlockCase {
    /// The scene text: the case file with `cells`, `constraint`, `shape`
    /// and `end` set.
    ///
    /// # Errors
    /// A case file that lost one of the keys edited here.
    pub fn scene(&self) -> Result<String> {
        let n = self.cells;
        let (text, cells) = match self.formulation {
            Formulation::Multiphase => (
                edit(
                    BLOCK_MULTIPHASE,
                    "constraint = \"weak\"",
                    &format!("constraint = \"{}\"", self.constraint),
                )?,
                "cells = [20, 20]",
            ),
            Formulation::Coupled => (BLOCK_COUPLED.to_string(), "cells = [20, 20]"),
        };
        let text = edit(&text, cells, &format!("cells = [{n}, {n}]"))?;
        let text = edit(
            &text,
            "shape = \"gimp\"",
            &format!("shape = \"{}\"", self.shape),
        )?;
        edit(&text, "end = 0.05\n", &format!("end = {:?}\n", self.end))
    }
}

/// What a block-test run measured.
#[derive(Debug, Clone)]
pub struct BlockRun {
    /// Largest relative air-pressure change `|p − p1| / p1` over the run
    /// (multiphase: the air points' `−tr σ / 3`; MPM-ICE: the interior cells'
    /// pressure).
    pub pressure: f64,
    /// [`Self::pressure`] over the steps after the first cell crossing
    /// (without the start-up transient).
    pub pressure_late: f64,
    /// Largest velocity change over the speed: every point of every phase
    /// (multiphase); the air of every interior cell and every solid particle
    /// (MPM-ICE).
    pub velocity: f64,
    /// `(t, pressure change, velocity change)` after every step (the
    /// changes at that step, not the running maximum).
    pub history: Vec<(f64, f64, f64)>,
    /// Whether the run reached its end (the strong constraint fails early:
    /// the history stops at the last good step).
    pub completed: bool,
    /// Its cost.
    pub cost: Cost,
}

fn speed() -> f64 {
    BLOCK_VELOCITY.iter().map(|c| c * c).sum::<f64>().sqrt()
}

/// Block-test changes of a multiphase run at its current state.
fn multiphase_block_changes(run: &MultiphaseRun<2>) -> (f64, f64) {
    let u = SVector::<f64, 2>::from(BLOCK_VELOCITY);
    let (mut dp, mut dv) = (0.0f64, 0.0f64);
    for (k, ph) in run.phases.iter().enumerate() {
        let p = &ph.particles;
        for i in 0..p.len() {
            if Some(k) == run.gas {
                let pr = -p.stress.get(i).trace() / 3.0;
                dp = dp.max((pr - P1).abs() / P1);
            }
            dv = dv.max((p.v[i] - u).norm() / speed());
        }
    }
    (dp, dv)
}

/// Block-test changes of an MPM-ICE run at its current state.
fn coupled_block_changes(run: &CoupledRun<2>) -> (f64, f64) {
    let u = SVector::<f64, 2>::from(BLOCK_VELOCITY);
    let layout = &run.fluid.layout;
    let (mut dp, mut dv) = (0.0f64, 0.0f64);
    for &c in &layout.interior {
        dp = dp.max((run.fluid.pressure[c] - P1).abs() / P1);
        dv = dv.max((run.fluid.cells[0].velocity[c] - u).norm() / speed());
    }
    for f in &run.fields {
        for v in &f.particles.v {
            dv = dv.max((v - u).norm() / speed());
        }
    }
    (dp, dv)
}

/// Runs a block case to its end (a multiphase run with the strong
/// constraint stops at its first failed or non-finite step, keeping what it
/// measured before).
///
/// # Errors
/// A scene that does not build; a failed MPM-ICE step (it names step,
/// time and site); a failed weak-constraint multiphase step.
pub fn run_block(case: &BlockCase) -> Result<BlockRun> {
    let scene = parse(&case.scene()?)?;
    let end = case.end;
    let mut history = Vec::with_capacity(4096);
    let mut completed = true;
    let cost = match case.formulation {
        Formulation::Multiphase => {
            let mut run: MultiphaseRun<2> = build_multiphase_run(&scene)?;
            let mut clock = StepClock::new((end / run.stable_dt().max(1e-300)) as usize);
            while run.t < end * (1.0 - 1e-12) {
                let r = clock.step(|| {
                    let dt = run.stable_dt().min(end - run.t);
                    run.step(dt)
                });
                if let Err(e) = r {
                    if case.constraint == "weak" {
                        return Err(e);
                    }
                    completed = false;
                    break;
                }
                let (dp, dv) = multiphase_block_changes(&run);
                if !(dp.is_finite() && dv.is_finite()) {
                    completed = false;
                    break;
                }
                history.push((run.t, dp, dv));
            }
            clock.finish(run.steps, None)
        }
        Formulation::Coupled => {
            let mut run: CoupledRun<2> = build_coupled_run(&scene)?;
            let mut clock = StepClock::new((end / run.stable_dt().max(1e-300)) as usize);
            while run.fluid.time < end * (1.0 - 1e-12) {
                clock.step(|| run.step(end - run.fluid.time))?;
                let (dp, dv) = coupled_block_changes(&run);
                history.push((run.fluid.time, dp, dv));
            }
            clock.finish(run.steps, Some(run.pressure_s))
        }
    };
    let (pressure, velocity) = history
        .iter()
        .fold((0.0f64, 0.0f64), |a, h| (a.0.max(h.1), a.1.max(h.2)));
    let crossing = 1.0 / (case.cells as f64 * BLOCK_VELOCITY[0]);
    let pressure_late = history
        .iter()
        .filter(|h| h.0 > crossing)
        .fold(0.0f64, |a, h| a.max(h.1));
    Ok(BlockRun {
        pressure,
        pressure_late,
        velocity,
        history,
        completed,
        cost,
    })
}

/// The exact 1D shock relations of the shock case (ideal gas, γ = 1.4,
/// c_v = 717.5, both gases at 300 K, driven air at `P1`).
#[derive(Debug, Clone, Copy)]
pub struct ShockExact {
    /// Incident shock Mach number.
    pub mach: f64,
    /// Pressure behind the incident shock \[Pa\].
    pub p2: f64,
    /// Gas velocity behind it [m/s].
    pub u2: f64,
    /// Incident shock speed [m/s].
    pub shock_speed: f64,
    /// Driver pressure of the shock tube that makes this shock \[Pa\].
    pub p4: f64,
    /// Pressure behind the shock reflected from a rigid wall \[Pa\].
    pub p5: f64,
    /// Speed of the reflected shock [m/s].
    pub reflected_speed: f64,
    /// Sound speed behind the reflected shock [m/s].
    pub a5: f64,
    /// Time at which the incident shock reaches the block's front face \[s\].
    pub t_hit: f64,
}

/// Diaphragm position of the shock case \[m\].
pub const DIAPHRAGM: f64 = 0.1;
/// The block's front face \[m\].
pub const FRONT: f64 = 0.3;
/// The block's half height `b` (the symmetry plane is y = 0) \[m\].
pub const HALF_HEIGHT: f64 = 0.1;
/// The pressure probe: 2 cm in front of the face, on the symmetry plane.
pub const PROBE: [f64; 2] = [0.28, 0.0];
/// Height of the simulated half domain \[m\].
pub const HEIGHT: f64 = 0.2;
/// Until this time the walls at x = 0 and x = 0.5 see exactly `p4` and
/// `p1` (the rarefaction's head, leaving the diaphragm at `a4 = 347` m/s,
/// is still 5 cm from the wall at x = 0; nothing reaches x = 0.5 before
/// the end), so the x-momentum of everything in the box is
/// `(p4 − p1) H t` \[s\].
pub const WALL_CHECK_T: f64 = 1.5e-4;

/// The exact 1D values of the shock case: Rankine–Hugoniot for a Mach 1.5
/// shock in air at 300 K (`p2/p1 = 1 + 2γ/(γ+1)(M² − 1)`,
/// `u2 = 2 a1/(γ+1)(M − 1/M)`), the shock-tube driver pressure at equal
/// temperatures (`p4 = p2 [1 − (γ−1)/(γ+1)(M − 1/M)]^(−2γ/(γ−1))`), and the
/// reflection from a rigid wall: `p5/p2 = ((3γ−1)M² − 2(γ−1)) / ((γ−1)M² + 2)`,
/// the reflected shock's speed from mass conservation across it
/// (`W = u2 / (ρ5/ρ2 − 1)`, `ρ5/ρ2` from the Hugoniot at `p5/p2`).
pub fn shock_exact() -> ShockExact {
    let (g, cv, t1, mach) = (1.4f64, 717.5, 300.0, 1.5f64);
    let r = cv * (g - 1.0);
    let a1 = (g * r * t1).sqrt();
    let p21 = 1.0 + 2.0 * g / (g + 1.0) * (mach * mach - 1.0);
    let rho21 = (g + 1.0) * mach * mach / ((g - 1.0) * mach * mach + 2.0);
    let u2 = 2.0 * a1 / (g + 1.0) * (mach - 1.0 / mach);
    let p4 =
        P1 * p21 * (1.0 - (g - 1.0) / (g + 1.0) * (mach - 1.0 / mach)).powf(-2.0 * g / (g - 1.0));
    let p52 = ((3.0 * g - 1.0) * mach * mach - 2.0 * (g - 1.0)) / ((g - 1.0) * mach * mach + 2.0);
    let k = (g + 1.0) / (g - 1.0);
    let rho52 = (1.0 + k * p52) / (k + p52);
    let t5 = t1 * p21 / rho21 * p52 / rho52;
    let shock_speed = mach * a1;
    ShockExact {
        mach,
        p2: P1 * p21,
        u2,
        shock_speed,
        p4,
        p5: P1 * p21 * p52,
        reflected_speed: u2 / (rho52 - 1.0),
        a5: (g * r * t5).sqrt(),
        t_hit: (FRONT - DIAPHRAGM) / shock_speed,
    }
}

/// The window over which the probe pressure is averaged: from 0.1 ms after
/// the hit (the reflected shock passed the probe 0.06 ms after it, and its
/// smeared foot a few cells later) to 0.2 ms after it (before the
/// diffraction from the block's corner, 0.1 m away at `a5`, reaches the
/// probe, 0.23 ms after it).
pub fn shock_window() -> (f64, f64) {
    let e = shock_exact();
    (e.t_hit + 1.0e-4, e.t_hit + 2.0e-4)
}

/// One shock run: formulation, resolution, end time.
#[derive(Debug, Clone, Copy)]
pub struct ShockCase {
    /// Which formulation.
    pub formulation: Formulation,
    /// Cells along x (the case files: 100, h = 5 mm); y gets `2 cells / 5`.
    pub cells: usize,
    /// End time (the case files: 0.634 ms, 0.25 ms after the hit).
    pub end: f64,
}

impl ShockCase {
    /// The scene text: the case file with the cells and end set.
    ///
    /// # Errors
    /// A case file that lost one of the keys edited here, or a cell count
    /// not a multiple of 5.
    pub fn scene(&self) -> Result<String> {
        if !self.cells.is_multiple_of(5) || self.cells == 0 {
            return Err(SceneError::new(
                "cells",
                format!(
                    "a positive multiple of 5 (square cells), got {}",
                    self.cells
                ),
            )
            .into());
        }
        let text = match self.formulation {
            Formulation::Multiphase => SHOCK_MULTIPHASE,
            Formulation::Coupled => SHOCK_COUPLED,
        };
        let text = edit(
            text,
            "cells = [100, 40]",
            &format!("cells = [{}, {}]", self.cells, self.cells * 2 / 5),
        )?;
        edit(&text, "end = 6.34e-4 ", &format!("end = {:?} ", self.end))
    }
}

/// One sample of a shock run.
#[derive(Debug, Clone, Copy)]
pub struct ShockSample {
    /// Time \[s\].
    pub t: f64,
    /// Air pressure at [`PROBE`] \[Pa\] (multiphase: the nodal gas pressure
    /// `p_g` of the nearest node; MPM-ICE: the pressure of the cell holding
    /// it).
    pub probe: f64,
    /// The block's x-momentum (the half block, per metre of depth) [N s/m].
    pub momentum: f64,
    /// The x-momentum of everything (air and block) [N s/m].
    pub total_momentum: f64,
}

/// What a shock run measured.
#[derive(Debug, Clone)]
pub struct ShockRun {
    /// After every step.
    pub history: Vec<ShockSample>,
    /// Mean probe pressure over [`shock_window`] (steps ending in it) \[Pa\].
    pub front_pressure: f64,
    /// The block's momentum at the end of the window [N s/m] (linear
    /// between the samples around it).
    pub momentum: f64,
    /// Its cost.
    pub cost: Cost,
}

impl ShockRun {
    /// `|front_pressure − p5| / p5`.
    pub fn front_error(&self) -> f64 {
        let p5 = shock_exact().p5;
        (self.front_pressure - p5).abs() / p5
    }

    /// The block's momentum at the window's end over the 1D estimate
    /// `(p5 − p1) b (t − t_hit)` (the whole front face at `p5`, the back at
    /// `p1`).
    pub fn momentum_ratio(&self) -> f64 {
        let e = shock_exact();
        let t = shock_window().1;
        self.momentum / ((e.p5 - P1) * HALF_HEIGHT * (t - e.t_hit))
    }

    /// The momentum balance of the closed box until [`WALL_CHECK_T`]: the
    /// largest `|P(t) − (p4 − p1) H t|` over the samples, relative to the
    /// impulse `(p4 − p1) H WALL_CHECK_T` (the walls' net force is exactly
    /// `(p4 − p1) H` until then).
    pub fn momentum_balance_error(&self) -> f64 {
        let rate = (shock_exact().p4 - P1) * HEIGHT;
        self.history
            .iter()
            .filter(|s| s.t <= WALL_CHECK_T)
            .map(|s| (s.total_momentum - rate * s.t).abs())
            .fold(0.0, f64::max)
            / (rate * WALL_CHECK_T)
    }
}

/// The nodal gas pressure of a multiphase run at the node nearest `x`.
fn multiphase_probe(run: &MultiphaseRun<2>, x: [f64; 2]) -> f64 {
    let xi = run.grid.to_grid_units(&SVector::from(x));
    let node = run
        .grid
        .node_index([xi[0].round() as isize, xi[1].round() as isize]);
    run.gas_pressure[node]
}

/// The cell pressure of an MPM-ICE run in the cell holding `x`.
fn coupled_probe(run: &CoupledRun<2>, x: [f64; 2]) -> f64 {
    let layout = &run.fluid.layout;
    let mut ijk = [0isize; 2];
    for d in 0..2 {
        let i = ((x[d] - layout.lower[d]) / layout.h[d]).floor() as isize;
        ijk[d] = i.clamp(0, layout.cells[d] as isize - 1);
    }
    run.fluid.pressure[layout.index(ijk)]
}

/// The x-momentum of an MPM-ICE run: the fluids' cells and every solid
/// field's particles (a solid's cell state is rebuilt from them).
fn coupled_momentum_x(run: &CoupledRun<2>) -> f64 {
    let layout = &run.fluid.layout;
    let fluids: f64 = run.fluid.cells[..run.num_fluids()]
        .iter()
        .map(|m| {
            layout
                .interior
                .iter()
                .map(|&c| m.mass[c] * m.velocity[c][0])
                .sum::<f64>()
        })
        .sum();
    fluids
        + run
            .fields
            .iter()
            .map(|f| f.particles.momentum()[0])
            .sum::<f64>()
}

/// Runs a shock case to its end.
///
/// # Errors
/// A scene that does not build or a failed step.
pub fn run_shock(case: &ShockCase) -> Result<ShockRun> {
    let scene = parse(&case.scene()?)?;
    let end = case.end;
    let mut history = Vec::with_capacity(8192);
    let cost = match case.formulation {
        Formulation::Multiphase => {
            let mut run: MultiphaseRun<2> = build_multiphase_run(&scene)?;
            let block = run
                .phase_of("steel")
                .ok_or_else(|| Error::from(SceneError::new("materials", "no material `steel`")))?;
            let mut clock = StepClock::new((end / run.stable_dt().max(1e-300)) as usize);
            while run.t < end * (1.0 - 1e-12) {
                clock.step(|| {
                    let dt = run.stable_dt().min(end - run.t);
                    run.step(dt)
                })?;
                history.push(ShockSample {
                    t: run.t,
                    probe: multiphase_probe(&run, PROBE),
                    momentum: run.phases[block].particles.momentum()[0],
                    total_momentum: run.phases.iter().map(|p| p.particles.momentum()[0]).sum(),
                });
            }
            clock.finish(run.steps, None)
        }
        Formulation::Coupled => {
            let mut run: CoupledRun<2> = build_coupled_run(&scene)?;
            let mut clock = StepClock::new((end / run.stable_dt().max(1e-300)) as usize);
            while run.fluid.time < end * (1.0 - 1e-12) {
                clock.step(|| run.step(end - run.fluid.time))?;
                history.push(ShockSample {
                    t: run.fluid.time,
                    probe: coupled_probe(&run, PROBE),
                    momentum: run.fields[0].particles.momentum()[0],
                    total_momentum: coupled_momentum_x(&run),
                });
            }
            clock.finish(run.steps, Some(run.pressure_s))
        }
    };
    let (w0, w1) = shock_window();
    let in_window: Vec<f64> = history
        .iter()
        .filter(|s| s.t >= w0 && s.t <= w1)
        .map(|s| s.probe)
        .collect();
    let front_pressure = in_window.iter().sum::<f64>() / in_window.len().max(1) as f64;
    let momentum = interpolate(&history, w1);
    Ok(ShockRun {
        history,
        front_pressure: if in_window.is_empty() {
            f64::NAN
        } else {
            front_pressure
        },
        momentum,
        cost,
    })
}

/// The block momentum at `t` from the samples (linear between the two
/// around it; NaN outside them).
fn interpolate(h: &[ShockSample], t: f64) -> f64 {
    h.windows(2)
        .find(|w| w[0].t <= t && t <= w[1].t)
        .map_or(f64::NAN, |w| {
            let s = (t - w[0].t) / (w[1].t - w[0].t).max(1e-300);
            w[0].momentum + s * (w[1].momentum - w[0].momentum)
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The case headers quote these numbers.
    #[test]
    fn exact_shock_values() {
        let e = shock_exact();
        assert!((e.p2 / P1 - 2.458_333).abs() < 1e-6);
        assert!((e.p4 / P1 - 7.002_07).abs() < 1e-5);
        assert!((e.p5 / P1 - 5.425_287).abs() < 1e-6);
        assert!((e.u2 - 241.103).abs() < 1e-3);
        assert!((e.shock_speed - 520.783).abs() < 1e-3);
        assert!((e.reflected_speed - 327.900).abs() < 1e-3);
        assert!((e.t_hit - 3.8404e-4).abs() < 1e-8);
    }

    /// The scenes the diagnostics build are the case files, edited.
    #[test]
    fn scenes_edit_the_case_files() {
        for f in [Formulation::Multiphase, Formulation::Coupled] {
            let b = BlockCase {
                formulation: f,
                cells: 24,
                constraint: "weak",
                shape: "linear",
                end: 0.01,
            };
            let s = parse(&b.scene().unwrap()).unwrap();
            assert_eq!(s.grid.cells, vec![24, 24]);
            assert_eq!(s.time.end, 0.01);
            let c = ShockCase {
                formulation: f,
                cells: 50,
                end: 1e-4,
            };
            let s = parse(&c.scene().unwrap()).unwrap();
            assert_eq!(s.grid.cells, vec![50, 20]);
            assert_eq!(s.time.end, 1e-4);
        }
        let bad = ShockCase {
            formulation: Formulation::Coupled,
            cells: 51,
            end: 1e-4,
        };
        assert!(bad.scene().is_err());
    }
}
