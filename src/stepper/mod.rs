//! Time stepping: one step per mode, built from the kernels in the order of
//! the papers, with timestep control.
//!
//! Here: the explicit solid (MPM-only) run. The coupled MPM-ICE step of
//! Guilkey Sec. 3.3 is [`crate::coupling::CoupledRun`]; it reuses the same
//! MPM kernels, split into phases ([`crate::mpm::CoupledMpm`]), and the ICE
//! stages ([`crate::ice::stage_pressure`], [`crate::ice::stage_lagrangian`],
//! [`crate::ice::stage_advect`]).

use nalgebra::SVector;

use crate::error::{Error, FailureSite, Result};
use crate::grid::Grid;
use crate::material::SolidMaterial;
use crate::membrane::Membranes;
use crate::mpm::{
    explicit_step, stable_dt, BodyForce, ExplicitParams, GridState, Particles, StepScratch,
};

/// Timestep control.
#[derive(Debug, Clone, Copy)]
pub struct TimeControl {
    /// End time.
    pub end: f64,
    /// Courant number.
    pub cfl: f64,
    /// Fixed timestep (overrides the CFL estimate).
    pub dt: Option<f64>,
    /// Step limit.
    pub max_steps: Option<u64>,
}

/// Energies of the particle system.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct Energies {
    /// Σ ½ m v².
    pub kinetic: f64,
    /// Σ V⁰ W(F).
    pub strain: f64,
    /// Potential of the uniform body force.
    pub potential: f64,
}

impl Energies {
    /// Kinetic + strain + potential.
    pub fn total(&self) -> f64 {
        self.kinetic + self.strain + self.potential
    }
}

/// A solid-only explicit MPM run: the state and the reusable buffers.
pub struct SolidRun<const D: usize> {
    /// Background grid.
    pub grid: Grid<D>,
    /// Solid materials, indexed by `Particles::material`.
    pub materials: Vec<SolidMaterial>,
    /// Particles.
    pub particles: Particles<D>,
    /// Discretisation choices.
    pub params: ExplicitParams,
    /// Body force per unit mass (gravity, or a manufactured one).
    pub body: Option<Box<dyn BodyForce<D> + Send + Sync>>,
    /// Uniform gravity used for the potential energy (zero if none).
    pub gravity: SVector<f64, D>,
    /// Timestep control.
    pub time: TimeControl,
    /// Current time.
    pub t: f64,
    /// Completed steps.
    pub steps: u64,
    /// Membranes (York Sec. 3.2) among the particles: chains and frames.
    pub membranes: Membranes<D>,
    /// Grid node fields (the split step of [`crate::contact`] uses them).
    pub(crate) grid_state: GridState<D>,
    /// Reusable step buffers.
    pub(crate) scratch: StepScratch<D>,
    /// The impulse the fixed walls, symmetry planes and fixed membrane ends
    /// gave the particles in the last step ([`GridState::wall_impulse`]).
    pub wall_impulse: SVector<f64, D>,
    /// The impulse of the body force in the last step, `Δt Σ_p m_p b_p`.
    pub body_impulse: SVector<f64, D>,
    /// The work of the grid's damping in the last step
    /// ([`GridState::damping_work`]; ≤ 0, 0 without damping).
    pub damping_work: f64,
    /// Partial sums of the body impulse, one per fixed block of particles
    /// (a sum independent of the thread count).
    body_partial: Vec<SVector<f64, D>>,
}

/// Particles per partial sum of [`SolidRun::body_impulse`].
const BODY_BLOCK: usize = 4096;

impl<const D: usize> SolidRun<D> {
    /// A run at t = 0.
    pub fn new(
        grid: Grid<D>,
        materials: Vec<SolidMaterial>,
        particles: Particles<D>,
        params: ExplicitParams,
        time: TimeControl,
    ) -> Self {
        let n = grid.num_nodes();
        Self {
            grid,
            materials,
            particles,
            params,
            body: None,
            gravity: SVector::zeros(),
            time,
            t: 0.0,
            steps: 0,
            membranes: Membranes::default(),
            grid_state: GridState::new(n),
            scratch: StepScratch::default(),
            wall_impulse: SVector::zeros(),
            body_impulse: SVector::zeros(),
            damping_work: 0.0,
            body_partial: Vec::new(),
        }
    }

    /// Whether the end time or step limit is reached.
    pub fn finished(&self) -> bool {
        self.t >= self.time.end * (1.0 - 1e-12)
            || self.time.max_steps.is_some_and(|m| self.steps >= m)
    }

    /// The next timestep: fixed or CFL-limited, shortened to land on the end time.
    pub fn next_dt(&self) -> f64 {
        let dt = self.time.dt.unwrap_or_else(|| {
            stable_dt(&self.grid, &self.materials, &self.particles, self.time.cfl)
        });
        dt.min(self.time.end - self.t)
    }

    /// Takes one step; returns the timestep used.
    pub fn step(&mut self) -> Result<f64> {
        self.step_dt(self.next_dt())
    }

    /// Takes one step of exactly `dt`; returns it.
    pub fn step_dt(&mut self, dt: f64) -> Result<f64> {
        if !self.membranes.is_empty() {
            // York Sec. 3.2: the local frames from the neighbours' positions.
            let p = &mut self.particles;
            if let Err(q) = self.membranes.update_frames(&p.x, &mut p.stress) {
                return Err(Error::Numerical {
                    site: FailureSite {
                        step: self.steps,
                        time: self.t,
                        particle: Some(q),
                        cell: None,
                    },
                    what: "membrane point coincides with a neighbour (no tangent)".into(),
                });
            }
        }
        self.body_impulse = match self.body.as_deref() {
            Some(b) => body_impulse(b, &self.particles, self.t, dt, &mut self.body_partial),
            None => SVector::zeros(),
        };
        explicit_step(
            &self.grid,
            &self.materials,
            &self.params,
            self.body.as_deref().map(|b| b as &dyn BodyForce<D>),
            &self.membranes.tangent,
            &mut self.particles,
            &mut self.grid_state,
            &mut self.scratch,
            self.t,
            dt,
            self.steps,
        )?;
        self.wall_impulse = self.grid_state.wall_impulse(dt, self.params.pic_fraction);
        self.damping_work = self.grid_state.damping_work();
        if !self.membranes.is_empty() {
            let p = &mut self.particles;
            self.wall_impulse += self.membranes.fix_ends(&mut p.x, &p.x0, &mut p.v, &p.mass);
        }
        self.t += dt;
        self.steps += 1;
        Ok(dt)
    }

    /// Current energies.
    pub fn energies(&self) -> Energies {
        Energies {
            kinetic: self.particles.kinetic_energy(),
            strain: self.particles.strain_energy(&self.materials),
            potential: self.particles.potential_energy(&self.gravity),
        }
    }

    /// Wall time per phase of the explicit step, accumulated over the run.
    pub fn phase_times(&self) -> crate::mpm::PhaseTimes {
        self.scratch.times
    }

    /// The grid node fields of the last step.
    pub fn grid_state(&self) -> &GridState<D> {
        &self.grid_state
    }
}

/// `Δt Σ_p m_p b(x⁰_p, x_p, t)`, summed in fixed blocks of particles and
/// then in block order, so that every thread count gives the same bits.
fn body_impulse<const D: usize>(
    body: &(dyn BodyForce<D> + Send + Sync),
    p: &Particles<D>,
    t: f64,
    dt: f64,
    partial: &mut Vec<SVector<f64, D>>,
) -> SVector<f64, D> {
    use rayon::prelude::*;
    partial.resize(p.len().div_ceil(BODY_BLOCK), SVector::zeros());
    let uniform = body.uniform();
    partial.par_iter_mut().enumerate().for_each(|(b, out)| {
        let range = b * BODY_BLOCK..((b + 1) * BODY_BLOCK).min(p.len());
        *out = match uniform {
            // Gravity: g Σ m, from the masses alone.
            Some(g) => g * p.mass[range].iter().sum::<f64>(),
            None => range.fold(SVector::zeros(), |acc, i| {
                acc + body.accel(&p.x0[i], &p.x[i], t) * p.mass[i]
            }),
        };
    });
    partial.iter().sum::<SVector<f64, D>>() * dt
}
