//! What crosses the domain boundary in one ICE step: the mass, momentum and
//! energy the advection carries through the boundary faces, the impulse of
//! the face pressures there and their work. The run summary subtracts it
//! from the change of the totals, so that what is left is the scheme's
//! numerical drift (Sod's momentum change `(p_L − p_R) t` is a boundary
//! impulse, not a drift).
//!
//! Momentum: the pressure force on the materials of a cell, `−Δt V θ_r
//! ∇p*` (Guilkey Eq. 33), summed over the materials (`Σ θ_r = 1` after the
//! equilibration) and the cells telescopes to the boundary faces, `Δt A
//! (p*_lower − p*_upper)` per row; the exchange sums to zero. Energy: the
//! face work `p*_f (Σ θ u*)_f A Δt` of the conservative form
//! ([`super::EnergyForm::Conservative`]) at the boundary faces and the
//! advected internal and kinetic energy; in the non-conservative form the
//! kinetic energy through a face is `|F_mu|² / (2 F_M)` from the mass and
//! momentum fluxes. Gravity's impulse and work are added apart
//! (`add_gravity`); viscous boundary stresses are not in it.

use nalgebra::SVector;

use super::advection::AdvectionFluxes;
use super::state::CellLayout;

/// Mass, momentum (padded to 3D) and energy that entered the system through
/// the domain boundary (for ICE, through the boundary faces; for MPM, the
/// reaction of fixed walls, symmetry planes and fixed membrane ends,
/// [`crate::mpm::wall_reaction`]), the momentum the body force added, and
/// the energy put in by heat sources, reactions, prescribed motion and
/// damping.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct BoundaryExchange {
    /// Mass in \[kg\] (per depth in 1D/2D).
    pub mass: f64,
    /// Momentum in through the boundary.
    pub momentum: [f64; 3],
    /// Energy in (internal + kinetic + pressure work).
    pub energy: f64,
    /// Momentum added by the body force (gravity), `∫ Σ m b dt`.
    pub body_momentum: [f64; 3],
    /// Energy the body force added where the model keeps no potential
    /// energy (ICE: gravity's work `Δt M g·ū`, ū the Lagrangian step's mean
    /// velocity); 0 where its work is in the potential energy (MPM).
    pub body_work: f64,
    /// Energy the scene's heat sources put into the fluids, `Σ power θ_r V
    /// Δt` over the cells and the part of each step inside a source's
    /// window.
    pub source_energy: f64,
    /// Work of prescribed motion and loads. In a coupled run, of materials
    /// held at a prescribed velocity (rigid solids): `U · J` per step, `J`
    /// the impulse that holding them at `U` takes from them (the cells'
    /// pressure force on their nodes and the exchange's momentum transfer),
    /// plus their own kinetic energy change. In an implicit solid run, of
    /// its grips, surface loads and ramped body force
    /// ([`crate::mpm::StepStats::external_work`]).
    pub prescribed_work: f64,
    /// Chemical energy the reactions of a coupled run released into their
    /// products ([`crate::coupling::reaction`]).
    pub reaction_energy: f64,
    /// Work of the grid's mass-proportional damping (`mpm.damping`) on the
    /// solids' nodes, `−Σ α m |v̄|² Δt` with `v̄` the step's time-centred
    /// nodal velocity: energy the damping takes out (≤ 0).
    pub damping_work: f64,
}

impl BoundaryExchange {
    /// Adds `o`.
    pub fn add(&mut self, o: &Self) {
        self.mass += o.mass;
        for d in 0..3 {
            self.momentum[d] += o.momentum[d];
            self.body_momentum[d] += o.body_momentum[d];
        }
        self.energy += o.energy;
        self.body_work += o.body_work;
        self.source_energy += o.source_energy;
        self.prescribed_work += o.prescribed_work;
        self.damping_work += o.damping_work;
        self.reaction_energy += o.reaction_energy;
    }

    /// Every energy that entered the system from outside it: through the
    /// boundary, by the body force outside the potential energy, by heat
    /// sources and reactions, by prescribed motion and by damping
    /// (negative).
    pub fn energy_in(&self) -> f64 {
        self.energy
            + self.body_work
            + self.source_energy
            + self.reaction_energy
            + self.prescribed_work
            + self.damping_work
    }
}

/// Every boundary face: direction, flat face index and `+1` at a lower
/// face (a positive flux enters), `−1` at an upper one.
fn boundary_faces<const D: usize>(
    layout: &CellLayout<D>,
) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
    (0..D).flat_map(move |d| {
        let lower = layout.boundary_cells[d][0]
            .iter()
            .map(move |&c| (d, c, 1.0));
        let upper = layout.boundary_cells[d][1]
            .iter()
            .map(move |&c| (d, c + layout.strides[d], -1.0));
        lower.chain(upper)
    })
}

/// Adds what one material's advection `fx` carried in through the boundary
/// faces; `kinetic`: `fx.kinetic` holds the kinetic energy fluxes.
pub(super) fn add_advected<const D: usize>(
    layout: &CellLayout<D>,
    fx: &AdvectionFluxes<D>,
    kinetic: bool,
    acc: &mut BoundaryExchange,
) {
    for (d, f, s) in boundary_faces(layout) {
        let fm = fx.mass[d][f];
        let fu: SVector<f64, D> = fx.momentum[d][f];
        acc.mass += s * fm;
        for k in 0..D {
            acc.momentum[k] += s * fu[k];
        }
        let ke = if kinetic {
            fx.kinetic[d][f]
        } else if fm != 0.0 {
            fu.norm_squared() / (2.0 * fm)
        } else {
            0.0
        };
        acc.energy += s * (fx.energy[d][f] + ke);
    }
}

/// Adds the impulse `Δt A p*_f n` and the work `p*_f V (mixture volume
/// flux)` of the face pressures at the boundary faces (`mix_vflux` holds
/// `Δt A/V Σ θ u*`).
pub(super) fn add_pressure<const D: usize>(
    layout: &CellLayout<D>,
    pstar: &[Vec<f64>; D],
    mix_vflux: &[Vec<f64>; D],
    dt: f64,
    acc: &mut BoundaryExchange,
) {
    let vol = layout.cell_volume();
    for (d, f, s) in boundary_faces(layout) {
        let area = vol / layout.h[d];
        acc.momentum[d] += s * pstar[d][f] * area * dt;
        acc.energy += s * pstar[d][f] * mix_vflux[d][f] * vol;
    }
}

/// Adds gravity's impulse `Δt Σ M g` and work `Δt Σ M g·(u + u_L)/2` on
/// the Eulerian materials (Guilkey Eq. 33's `Δt M g`), from the cells'
/// masses and velocities at the step's start and their Lagrangian
/// velocities `vel_l` (the exchange conserves each cell's momentum, so the
/// sum over materials is the one before it); particle-borne materials take
/// gravity on the nodes.
pub(super) fn add_gravity<const D: usize>(
    state: &super::IceState<D>,
    params: &super::IceParams<D>,
    vel_l: &[Vec<SVector<f64, D>>],
    dt: f64,
    acc: &mut BoundaryExchange,
) {
    let g = params.gravity;
    if g.iter().all(|&x| x == 0.0) {
        return;
    }
    let (mut mass, mut mom) = (0.0, SVector::<f64, D>::zeros());
    for (r, mc) in state.cells.iter().enumerate() {
        if params.frame(r) != super::Frame::Eulerian {
            continue;
        }
        for &c in &state.layout.interior {
            mass += mc.mass[c];
            mom += (mc.velocity[c] + vel_l[r][c]) * (0.5 * mc.mass[c]);
        }
    }
    for d in 0..D {
        acc.body_momentum[d] += g[d] * mass * dt;
    }
    acc.body_work += g.dot(&mom) * dt;
}

/// Adds the energy the heat sources put into the Eulerian materials over
/// the step from `state.time` to `state.time + dt`: `power θ_r V` per cell
/// over the part of the step inside each source's window, with the volume
/// fractions the Lagrangian phase used (Guilkey Sec. 3.3's sources,
/// `super::sources`' `add_heat_sources`).
pub(super) fn add_heat_sources<const D: usize>(
    state: &super::IceState<D>,
    params: &super::IceParams<D>,
    dt: f64,
    acc: &mut BoundaryExchange,
) {
    let (t0, t1) = (state.time, state.time + dt);
    let vol = state.layout.cell_volume();
    for src in &params.heat_sources {
        let overlap = (t1.min(src.end) - t0.max(src.start)).max(0.0);
        if overlap <= 0.0 {
            continue;
        }
        let theta = &state.cells[src.material].vol_frac;
        let sum: f64 = state
            .layout
            .interior
            .iter()
            .map(|&c| src.power[c] * theta[c])
            .sum();
        acc.source_energy += sum * vol * overlap;
    }
}
