//! What sets a model's stable time step: the particle or cell, its material
//! and the wave speed behind the CFL limit, or, for an implicit model, the
//! failed solve that last cut Δt. The progress guard of the run
//! loop names it when a run's Δt collapses or would take an absurd number
//! of steps ([`crate::driver::Model::dt_limiter`]).

use crate::grid::Grid;
use crate::ice::IceState;
use crate::material::eos::EquationOfState;
use crate::material::SolidMaterial;
use crate::membrane::element::MembraneMesh;
use crate::mpm::explicit::{gas_sound_speed_max, particle_dt_limit};
use crate::mpm::Particles;

/// The site that sets a stable time step.
#[derive(Debug, Clone, PartialEq)]
pub struct DtLimiter {
    /// `particle 17` or `cell [3, 4]`.
    pub site: String,
    /// The material's scene name (several, joined by `` `, ` ``, when the
    /// site is not one particle or cell).
    pub material: String,
    /// What limits Δt there.
    pub cause: LimitCause,
    /// The limit at that site before the Courant number, or the Δt that
    /// failed \[s\].
    pub dt: f64,
}

/// Why a site limits Δt.
#[derive(Debug, Clone, PartialEq)]
pub enum LimitCause {
    /// An explicit model's CFL limit: the signal speed `h / Δt_limit`
    /// (wave speed plus |v|) \[m/s\].
    Wave {
        /// The signal speed \[m/s\].
        speed: f64,
    },
    /// A step control's cut: a step at Δt `dt` failed there (an implicit
    /// solid's Newton did not converge, a particle inverted, a coupled
    /// pressure stage failed retryably, ...), and Δt was cut.
    FailedSolve {
        /// The solver's reason.
        what: String,
    },
    /// A surface burn's step limit (`crate::coupling::reaction::MAX_GROWTH`):
    /// the product cell would receive more than that many times its own
    /// mass in one step.
    Burn {
        /// The reactant's scene name.
        reactant: String,
        /// The product's mass in the cell \[kg\].
        mass: f64,
        /// The rate at which the burn feeds the cell \[kg/s\].
        inflow: f64,
    },
}

impl std::fmt::Display for DtLimiter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.cause {
            LimitCause::Wave { speed } => write!(
                f,
                "{} of material `{}`: signal speed {:.3e} m/s (wave speed plus |v|), Δt limit {:.3e} s",
                self.site, self.material, speed, self.dt
            ),
            LimitCause::FailedSolve { what } => write!(
                f,
                "{} of material `{}`: the last Δt cut, after the step at Δt {:.3e} s failed ({what})",
                self.site, self.material, self.dt
            ),
            LimitCause::Burn { reactant, mass, inflow } => write!(
                f,
                "{} of material `{}`: the burn of `{reactant}` feeds it {inflow:.3e} kg/s and \
                 its mass there is {mass:.3e} kg (a product cell may grow by at most {} \
                 times its mass in a step), Δt limit {:.3e} s",
                self.site,
                self.material,
                crate::coupling::reaction::MAX_GROWTH,
                self.dt
            ),
        }
    }
}

/// The particle with the smallest explicit limit `h / (c + |v|)`
/// ([`particle_dt_limit`], with the multiphase drag's `stiffening` where
/// given); `None` without particles. A serial pass: called only when the
/// guard stops a run.
pub fn particle_limiter<const D: usize>(
    grid: &Grid<D>,
    materials: &[SolidMaterial],
    p: &Particles<D>,
    stiffening: &[f64],
) -> Option<DtLimiter> {
    let h = grid.h.min();
    let c_max = gas_sound_speed_max(materials, p);
    let mut best: Option<(usize, f64)> = None;
    for i in 0..p.len() {
        let dt = particle_dt_limit(materials, p, stiffening, h, c_max, i);
        // NaN limits first: they are the cause.
        if best.is_none_or(|(_, b)| dt.is_nan() || dt < b) {
            best = Some((i, dt));
            if dt.is_nan() {
                break;
            }
        }
    }
    let (i, dt) = best?;
    Some(DtLimiter {
        site: format!("particle {i}"),
        material: materials[p.material[i] as usize].name.clone(),
        cause: LimitCause::Wave { speed: h / dt },
        dt,
    })
}

/// The interior cell and material with the largest rate
/// `Σ_d (|u_d| + c)/h_d` of ICE materials `materials` (the sound speed
/// from the EOS at the cell's density and temperature); `None` without
/// cells.
pub fn cell_limiter<const D: usize>(
    s: &IceState<D>,
    materials: std::ops::Range<usize>,
) -> Option<DtLimiter> {
    let mut best: Option<(usize, usize, f64)> = None;
    for r in materials {
        let (mat, mc) = (s.materials.get(r)?, s.cells.get(r)?);
        for &c in &s.layout.interior {
            let v = mc.sp_vol[c];
            let cs = mat.eos.sound_speed_sq(1.0 / v, mc.temperature[c]).sqrt();
            let rate: f64 = (0..D)
                .map(|d| (mc.velocity[c][d].abs() + cs) / s.layout.h[d])
                .sum();
            if best.is_none_or(|(_, _, b)| rate.is_nan() || rate > b) {
                best = Some((r, c, rate));
                if rate.is_nan() {
                    break;
                }
            }
        }
    }
    let (r, c, rate) = best?;
    let h = s.layout.h.min();
    Some(DtLimiter {
        site: format!("cell {:?}", s.layout.coords(c)),
        material: s.materials[r].name.clone(),
        cause: LimitCause::Wave { speed: rate * h },
        dt: 1.0 / rate,
    })
}

/// The membrane element with the smallest limit of Lian Eq. 48 over
/// `meshes` (scene names `names`); `None` without elements.
pub fn element_limiter(meshes: &[MembraneMesh], names: &[String]) -> Option<DtLimiter> {
    let mut best: Option<DtLimiter> = None;
    for (m, name) in meshes.iter().zip(names) {
        let Some((e, dt)) = m.limiting_element() else {
            continue;
        };
        let site = DtLimiter {
            site: format!("element {e}"),
            material: name.clone(),
            cause: LimitCause::Wave {
                speed: m.material.wave_speed(),
            },
            dt,
        };
        best = tighter(best, Some(site));
    }
    best
}

/// The more limiting of two sites (the smaller Δt limit; NaN first).
pub fn tighter(a: Option<DtLimiter>, b: Option<DtLimiter>) -> Option<DtLimiter> {
    match (a, b) {
        (Some(a), Some(b)) => Some(if b.dt.is_nan() || b.dt < a.dt { b } else { a }),
        (a, b) => a.or(b),
    }
}
