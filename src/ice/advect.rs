//! The advection stage of the ICE step (Guilkey Sec. 3.3 step 12): the
//! Eulerian materials' Lagrangian mass, momentum, energy (internal, or total
//! with [`super::EnergyForm::Conservative`]) and material volume advected
//! with compatible fluxes (the kernels are in [`super::advection`]), then
//! the commit of the new state ([`stage_advect`]).

use nalgebra::SVector;

use super::advection::{
    limit_outflow, material_fluxes, net_inflow, net_inflow_vec, AdvectedFields, AdvectionFluxes,
};
use super::boundary::{fill_scalar, fill_vector};
use super::par::{try_rows, Out};
use super::params::{EnergyForm, Frame, IceParams};
use super::state::IceState;
use super::workspace::{IceWorkspace, StepInfo};
use super::{site, IceError, InflowState};
use crate::material::eos::EquationOfState;

/// Step 12 (Guilkey Sec. 3.3): advection of the Eulerian materials with
/// compatible fluxes, then the commit of the new state (time and step
/// count advance by `info.dt`). Materials carried by particles are not
/// advected (their cell values are rebuilt from the particles).
///
/// # Errors
/// [`IceError::NonPhysical`] naming the cell.
pub fn stage_advect<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    info: StepInfo,
) -> Result<StepInfo, IceError> {
    let nm = state.num_materials();
    let dt = info.dt;
    let predictor = params
        .implicit
        .as_ref()
        .map_or(0.0, |sp| sp.convective_predictor);
    // What crosses the boundary: the face pressures' impulse and work,
    // then each material's advected fluxes.
    ws.exchange = super::BoundaryExchange::default();
    super::boundary_exchange::add_pressure(
        &state.layout,
        &ws.pstar,
        &ws.mix_vflux,
        dt,
        &mut ws.exchange,
    );
    super::boundary_exchange::add_gravity(state, params, &ws.vel_l, dt, &mut ws.exchange);
    super::boundary_exchange::add_heat_sources(state, params, dt, &mut ws.exchange);
    if !ws.fixed_work.is_empty() {
        ws.exchange.prescribed_work += state
            .layout
            .interior
            .iter()
            .map(|&c| ws.fixed_work[c])
            .sum::<f64>();
    }
    // Step 12: advection with compatible fluxes.
    for r in 0..nm {
        if params.frame(r) != Frame::Eulerian {
            continue;
        }
        advect_material(state, params, ws, r, dt)?;
    }
    commit(state, params, ws);
    if predictor > 0.0 {
        advective_acceleration(state, params, ws, dt);
    }
    std::mem::swap(&mut state.pressure, &mut ws.press);
    // Keep the old p_eq as the next equilibration's guess (already there).
    state.time += dt;
    state.steps += 1;
    Ok(info)
}

/// Advects Eulerian material `r`: ghosts of its Lagrangian values, the
/// Lagrangian strain for the remap, the fluxes of every advected quantity
/// and the new cell values into `ws.new_*`.
///
/// # Errors
/// [`IceError::NonPhysical`] naming the cell.
fn advect_material<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    r: usize,
    dt: f64,
) -> Result<(), IceError> {
    let layout = &state.layout;
    let conservative = params.energy == EnergyForm::Conservative;
    let cvr = state.materials[r].eos.specific_heat_cv();
    fill_lagrangian_ghosts(state, params, ws, r, cvr);
    let mc = &state.cells[r];
    if params.lagrangian_remap {
        remap_strain(state, params, ws, r);
    }
    let fields = AdvectedFields {
        remap: params.lagrangian_remap.then_some(&ws.remap[..]),
        mass: &mc.mass,
        velocity: &ws.vel_l[r],
        energy: &ws.e_l[r],
        sp_vol: &ws.v_l[r],
        kinetic: if conservative { Some(&ws.ke[r]) } else { None },
    };
    material_fluxes(
        layout,
        &ws.ustar[r],
        &fields,
        dt,
        params.advection,
        &mut ws.fluxes,
    );
    let outs = (
        Out::new(&mut ws.new_mass[r]),
        Out::new(&mut ws.new_vel[r]),
        Out::new(&mut ws.new_temp[r]),
        Out::new(&mut ws.new_spvol[r]),
    );
    let cell = AdvectedCell {
        st: state,
        fields: &fields,
        cv: cvr,
        r,
        trace_fraction: params.isothermal_fraction,
        vol: layout.cell_volume(),
    };
    let mut result = advect_cells(&cell, &ws.fluxes, outs);
    if result.is_err() {
        // Only where the fluxes as computed fail (a trace sending out more
        // than it has): every run that passed without it is unchanged, at
        // no cost.
        limit_outflow(layout, &mc.mass, &mut ws.fluxes);
        result = advect_cells(&cell, &ws.fluxes, outs);
    }
    super::boundary_exchange::add_advected(layout, &ws.fluxes, conservative, &mut ws.exchange);
    result
}

/// The new mass, velocity, temperature and specific volume of every
/// interior cell ([`AdvectedCell::advect`]) into `outs`.
///
/// # Errors
/// The first [`IceError::NonPhysical`] in index order.
fn advect_cells<const D: usize>(
    cell: &AdvectedCell<'_, D>,
    fx: &AdvectionFluxes<D>,
    outs: (
        Out<'_, f64>,
        Out<'_, SVector<f64, D>>,
        Out<'_, f64>,
        Out<'_, f64>,
    ),
) -> Result<(), IceError> {
    let (o_m, o_u, o_t, o_v) = outs;
    try_rows(&cell.st.layout, |row| {
        for c in row {
            let (m, u, temp, v) = cell.advect(c, fx)?;
            // SAFETY: cell c is written by this task only.
            unsafe {
                o_m.set(c, m);
                o_u.set(c, u);
                o_t.set(c, temp);
                o_v.set(c, v);
            }
        }
        Ok(())
    })
}

/// Fills the ghosts of material `r`'s Lagrangian velocity, internal energy
/// `c_v T`, specific volume and (conservative energy) kinetic energy from
/// the boundary conditions.
fn fill_lagrangian_ghosts<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    r: usize,
    cvr: f64,
) {
    let layout = &state.layout;
    let bcs = &params.boundaries;
    let inflow_v = |s: &[InflowState<D>]| s[r].velocity;
    fill_vector(layout, bcs, &mut ws.vel_l[r], inflow_v);
    fill_scalar(layout, bcs, &mut ws.e_l[r], |s| cvr * s[r].temperature);
    fill_scalar(layout, bcs, &mut ws.v_l[r], |s| 1.0 / s[r].density);
    if params.energy == EnergyForm::Conservative {
        fill_scalar(layout, bcs, &mut ws.ke[r], |s| {
            0.5 * s[r].velocity.norm_squared()
        });
    }
}

/// The Lagrangian strain `V^L/V − 1 = v^L/v − 1` of material `r` (Eq. 13's
/// `v`, Eq. 41's `v^L`) per cell into `ws.remap`; 0 where it is not usable
/// and in the ghosts ([`IceParams::lagrangian_remap`]).
#[inline]
fn remap_strain<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    r: usize,
) {
    let layout = &state.layout;
    let mc = &state.cells[r];
    for &c in &layout.interior {
        let e = ws.v_l[r][c] / mc.sp_vol[c] - 1.0;
        ws.remap[c] = if e.is_finite() && e > -1.0 { e } else { 0.0 };
    }
    fill_scalar(layout, &params.boundaries, &mut ws.remap, |_| 0.0);
}

/// What the advection of one material reads in every cell.
struct AdvectedCell<'a, const D: usize> {
    st: &'a IceState<D>,
    /// The advected quantities (Lagrangian values).
    fields: &'a AdvectedFields<'a, D>,
    /// `c_v` of the material.
    cv: f64,
    /// The material.
    r: usize,
    /// Volume fraction (at the start of the step) below which a material
    /// that advection empties or leaves at a non-positive temperature is
    /// repaired ([`TraceRepair`], [`TRACE_MASS_FLOOR`]) instead of stopping
    /// the run ([`IceParams::isothermal_fraction`]).
    trace_fraction: f64,
    /// Cell volume.
    vol: f64,
}

/// Volume fraction of the mass an emptied trace keeps after advection
/// (its mass times its specific volume over the cell volume): ten orders
/// below the trace a scene starts with
/// (1e-10, the scenes' `TRACE_VOLUME_FRACTION`): the mass it adds is 1e-20 of
/// a cell full of the material at its own density.
pub const TRACE_MASS_FLOOR: f64 = 1e-20;

/// A trace's specific internal energy and velocity where advection left it
/// with no mass or a non-positive temperature: the mass-weighted mean of
/// what the cell kept and what flowed in, `(M₀ φ₀ + Σ_in F_M φ_f) / (M₀ +
/// Σ_in F_M)`, a convex combination of values that are all physical.
///
/// The compatible fluxes bound each face's `φ_f` by the neighbours' range
/// and [`limit_outflow`] a cell's outflow by its mass, but with
/// second-order face values a trace's `M₀ e₀ − Σ_out F_M e_f` can still go
/// below zero when the faces' `e_f` exceed `e₀`, and the sum is divided by
/// a mass orders of magnitude below its neighbours' (an air trace at
/// θ = 1e-10 in a steel wall loaded by a confined burn went to −1.36 K at
/// t = 4.4 μs). The energy and momentum this sets differ from the
/// conservative ones by at most the trace's, below
/// [`IceParams::isothermal_fraction`] of its cell's volume. The
/// temperature is repaired only where the conservative update failed; the
/// mass floor also applies where a trace merely decayed below it (a run
/// that passed before changes only there).
struct TraceRepair<const D: usize> {
    /// Convex mean of `e`.
    e: f64,
    /// Convex mean of `u`.
    u: SVector<f64, D>,
}

impl<const D: usize> TraceRepair<D> {
    fn new(
        layout: &super::state::CellLayout<D>,
        fx: &AdvectionFluxes<D>,
        fields: &AdvectedFields<'_, D>,
        c: usize,
    ) -> Self {
        let m0 = fields.mass[c];
        let (mut m, mut me, mut mu) = (m0, m0 * fields.energy[c], fields.velocity[c] * m0);
        for d in 0..D {
            // Inflow through the lower face is a positive flux, through the
            // upper face a negative one.
            for (f, sign) in [(c, 1.0), (c + layout.strides[d], -1.0)] {
                if sign * fx.mass[d][f] > 0.0 {
                    m += sign * fx.mass[d][f];
                    me += sign * fx.energy[d][f];
                    mu += fx.momentum[d][f] * sign;
                }
            }
        }
        Self {
            e: me / m,
            u: mu / m,
        }
    }
}

impl<const D: usize> AdvectedCell<'_, D> {
    /// Mass, velocity, temperature and specific volume of the material in
    /// cell `c` after advection with the face fluxes `fx`: the Lagrangian
    /// content plus the net inflow; internal energy = advected total −
    /// kinetic with the conservative form where positive.
    ///
    /// # Errors
    /// [`IceError::NonPhysical`] for a non-positive mass, temperature or
    /// specific volume.
    fn advect(
        &self,
        c: usize,
        fx: &AdvectionFluxes<D>,
    ) -> Result<(f64, SVector<f64, D>, f64, f64), IceError> {
        let (st, fields, r) = (self.st, self.fields, self.r);
        let layout = &st.layout;
        let m0 = fields.mass[c];
        let m = m0 + net_inflow(layout, &fx.mass, c);
        let trace = || st.cells[r].vol_frac[c] < self.trace_fraction;
        let v0 = fields.sp_vol[c];
        let floor_mv = TRACE_MASS_FLOOR * self.vol;
        if (m.is_nan() || m * v0 <= floor_mv) && v0 > 0.0 && trace() {
            // A trace emptied ([`limit_outflow`] lets a cell give away all
            // it has) or nearly: a floor of volume fraction
            // [`TRACE_MASS_FLOOR`] at its own specific volume, with the
            // mean state of what it kept and what flowed in. (Air traces
            // in a steel wall decayed to 3e-38 kg, where `M e` and the
            // fluxes overflowed to NaN.)
            let rep = TraceRepair::new(layout, fx, fields, c);
            let m_floor = floor_mv / v0;
            if m_floor > 0.0
                && m_floor.is_finite()
                && rep.e > 0.0
                && rep.e.is_finite()
                && rep.u.iter().all(|x| x.is_finite())
            {
                return Ok((m_floor, rep.u, rep.e / self.cv, v0));
            }
        }
        if !(m.is_finite() && m > 0.0) {
            return Err(IceError::NonPhysical {
                site: site(st, c, Some(r)),
                quantity: "mass",
                value: m,
            });
        }
        // Two divisions, not four (see `sources::cell_sources`).
        let inv_m = 1.0 / m;
        let mom = fields.velocity[c] * m0 + net_inflow_vec(layout, &fx.momentum, c);
        let mut me = m0 * fields.energy[c] + net_inflow(layout, &fx.energy, c);
        if let Some(k) = fields.kinetic {
            // Total energy advected; internal = total − kinetic.
            let me_tot = me + m0 * k[c] + net_inflow(layout, &fx.kinetic, c);
            let me_cons = me_tot - 0.5 * mom.norm_squared() * inv_m;
            if me_cons > 0.0 {
                me = me_cons;
            }
        }
        let mut mv = m0 * v0 + net_inflow(layout, &fx.volume, c);
        if !(mv.is_finite() && mv > 0.0) {
            // The compatible volume flux `F_M v_f` is not bounded by
            // the donor's volume where the material's specific volume
            // varies by orders of magnitude across a few cells (a
            // fluid floor inside a solid in tension; air compressed
            // against a water column, 2D CTU transverse terms
            // included): keep the material's own specific volume. In a
            // fluid-only scene the next equilibration replaces the
            // advected volume anyway (Guilkey Eq. 13 gives v_r(p, T_r)
            // from mass and temperature); a coupled scene uses it only
            // as the reference volume of its normalised equilibration.
            // (This was for traces and coupled scenes only; the
            // shocked water column at 0.5 mm cells stopped on a
            // negative air volume at t = 2.4e-5 s.)
            mv = m * v0;
        }
        let mut temp = me * inv_m / self.cv;
        let mut u = mom * inv_m;
        if !(temp.is_finite() && temp > 0.0) && trace() {
            let rep = TraceRepair::new(layout, fx, fields, c);
            temp = rep.e / self.cv;
            u = rep.u;
        }
        if !(temp.is_finite() && temp > 0.0) {
            return Err(IceError::NonPhysical {
                site: site(st, c, Some(r)),
                quantity: "temperature after advection",
                value: temp,
            });
        }
        if !(mv.is_finite() && mv > 0.0) {
            return Err(IceError::NonPhysical {
                site: site(st, c, Some(r)),
                quantity: "specific volume",
                value: mv / m,
            });
        }
        Ok((m, u, temp, mv * inv_m))
    }
}

/// Commit: the advected values of the Eulerian materials become the state
/// (buffers swapped, no copy).
#[inline]
fn commit<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
) {
    for r in 0..state.num_materials() {
        if params.frame(r) != Frame::Eulerian {
            continue;
        }
        let mc = &mut state.cells[r];
        std::mem::swap(&mut mc.mass, &mut ws.new_mass[r]);
        std::mem::swap(&mut mc.velocity, &mut ws.new_vel[r]);
        std::mem::swap(&mut mc.temperature, &mut ws.new_temp[r]);
        std::mem::swap(&mut mc.sp_vol, &mut ws.new_spvol[r]);
    }
}

/// The advective acceleration of this step (advected minus Lagrangian
/// velocity, per unit time) into `ws.accel`, for the semi-implicit
/// convective predictor of the next step; zero for materials that are not
/// advected here (carried by particles or rigid). The buffers are
/// allocated once, on the first semi-implicit step.
#[inline]
fn advective_acceleration<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt: f64,
) {
    let nm = state.num_materials();
    let layout = &state.layout;
    if ws.accel.len() != nm {
        // Allocated once, on the first semi-implicit step.
        let n = layout.len();
        ws.accel = (0..nm).map(|_| vec![SVector::zeros(); n]).collect();
        ws.vel_pred = (0..nm).map(|_| vec![SVector::zeros(); n]).collect();
    }
    for r in 0..nm {
        let (acc, u, ul) = (&mut ws.accel[r], &state.cells[r].velocity, &ws.vel_l[r]);
        if params.frame(r) != Frame::Eulerian {
            acc.fill(SVector::zeros());
            continue;
        }
        for &c in &layout.interior {
            acc[c] = (u[c] - ul[c]) / dt;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::state::CellLayout;
    use super::*;

    /// A trace that sends out more energy than it keeps: its conservative
    /// temperature is negative, the repair is the mass-weighted mean of
    /// its own state and the inflow only (positive, between them).
    #[test]
    fn trace_repair_is_the_mean_of_what_stayed_and_what_came_in() {
        let layout =
            CellLayout::<1>::new(SVector::zeros(), SVector::<f64, 1>::new(1.0), [3]).unwrap();
        let len = layout.len();
        let c = layout.interior[1];
        let (m0, e0, u0) = (1e-12, 300.0, SVector::<f64, 1>::new(2.0));
        let mut mass = vec![1.0; len];
        mass[c] = m0;
        let energy = vec![e0; len];
        let vel = vec![u0; len];
        let fields = AdvectedFields {
            remap: None,
            mass: &mass,
            velocity: &vel,
            energy: &energy,
            sp_vol: &energy,
            kinetic: None,
        };
        let mut fx = AdvectionFluxes::<1>::new(len);
        // In through the lower face: 2e-13 kg at e = 100, u = 5; out through
        // the upper face: the whole trace at e = 500 (a second-order face
        // value above its own).
        let (m_in, e_in, u_in) = (2e-13, 100.0, 5.0);
        fx.mass[0][c] = m_in;
        fx.energy[0][c] = m_in * e_in;
        fx.momentum[0][c] = SVector::<f64, 1>::new(m_in * u_in);
        fx.mass[0][c + 1] = m0;
        fx.energy[0][c + 1] = m0 * 500.0;
        fx.momentum[0][c + 1] = u0 * m0;
        let conservative = m0 * e0 + net_inflow(&layout, &fx.energy, c);
        assert!(conservative < 0.0);
        let rep = TraceRepair::new(&layout, &fx, &fields, c);
        let e = (m0 * e0 + m_in * e_in) / (m0 + m_in);
        let u = (m0 * u0[0] + m_in * u_in) / (m0 + m_in);
        assert!((rep.e - e).abs() <= 1e-13 * e, "{} {e}", rep.e);
        assert!((rep.u[0] - u).abs() <= 1e-13 * u, "{} {u}", rep.u[0]);
        assert!(rep.e > e_in && rep.e < e0);
    }
}
