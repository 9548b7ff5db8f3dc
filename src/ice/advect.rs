//! The advection stage of the ICE step (Guilkey Sec. 3.3 step 12): the
//! Eulerian materials' Lagrangian mass, momentum, energy (internal, or total
//! with [`super::EnergyForm::Conservative`]) and material volume advected
//! with compatible fluxes (the kernels are in [`super::advection`]), then
//! the commit of the new state ([`stage_advect`]).

use nalgebra::SVector;

use super::advection::{
    material_fluxes, net_inflow, net_inflow_vec, AdvectedFields, AdvectionFluxes,
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
    super::boundary_exchange::add_advected(layout, &ws.fluxes, conservative, &mut ws.exchange);
    let fx = &ws.fluxes;
    let (o_m, o_u, o_t, o_v) = (
        Out::new(&mut ws.new_mass[r]),
        Out::new(&mut ws.new_vel[r]),
        Out::new(&mut ws.new_temp[r]),
        Out::new(&mut ws.new_spvol[r]),
    );
    let cell = AdvectedCell {
        st: state,
        fields: &fields,
        fx,
        cv: cvr,
        r,
    };
    try_rows(layout, |row| {
        for c in row {
            let (m, u, temp, v) = cell.advect(c)?;
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
    /// Their face fluxes.
    fx: &'a AdvectionFluxes<D>,
    /// `c_v` of the material.
    cv: f64,
    /// The material.
    r: usize,
}

impl<const D: usize> AdvectedCell<'_, D> {
    /// Mass, velocity, temperature and specific volume of the material in
    /// cell `c` after advection: the Lagrangian content plus the net
    /// inflow; internal energy = advected total − kinetic with the
    /// conservative form where positive.
    ///
    /// # Errors
    /// [`IceError::NonPhysical`] for a non-positive mass, temperature or
    /// specific volume.
    fn advect(&self, c: usize) -> Result<(f64, SVector<f64, D>, f64, f64), IceError> {
        let (st, fields, fx, r) = (self.st, self.fields, self.fx, self.r);
        let layout = &st.layout;
        let m0 = fields.mass[c];
        let m = m0 + net_inflow(layout, &fx.mass, c);
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
        let mut mv = m0 * fields.sp_vol[c] + net_inflow(layout, &fx.volume, c);
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
            mv = m * fields.sp_vol[c];
        }
        let temp = me * inv_m / self.cv;
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
        Ok((m, mom * inv_m, temp, mv * inv_m))
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
