//! One explicit ICE step for a fluid-only scene (Guilkey Sec. 3.3 steps 2,
//! 3, 5, 6, 8–12), the time step estimate, and a small driver.

use std::time::Instant;

use nalgebra::SVector;

use super::advection::{
    material_fluxes, net_inflow, net_inflow_vec, scalar_fluxes, AdvectedFields, Advection,
    AdvectionFluxes, Limiter,
};
use super::boundary::{fill_scalar, fill_vector, zero_wall_faces, Boundaries, IceBoundary};
use super::equilibration::{equilibrate_cell, min_pressure, EquilibrationSettings};
use super::exchange::{exchange_heat, exchange_momentum, ExchangeCoefficients};
use super::faces::{face_exchange, face_pressure, face_velocities};
use super::state::IceState;
use super::{invalid, IceError, Site, MAX_MATERIALS};
use crate::material::eos::EquationOfState;

/// All knobs of the explicit ICE step.
#[derive(Debug, Clone, PartialEq)]
pub struct IceParams<const D: usize> {
    /// Courant number on `Σ_d (|u_d| + c)/h_d` (`0 < cfl ≤ 1`).
    pub cfl: f64,
    /// Advection scheme.
    pub advection: Advection,
    /// Gravitational acceleration.
    pub gravity: SVector<f64, D>,
    /// Momentum and heat exchange among materials; `None` turns both off.
    pub exchange: Option<ExchangeCoefficients>,
    /// Equilibration pressure iteration settings.
    pub equilibration: EquilibrationSettings,
    /// Boundary conditions per direction, `[lower, upper]`.
    pub boundaries: Boundaries<D>,
    /// Form of the energy update.
    pub energy: EnergyForm,
    /// Time integration of the whole step.
    pub time: TimeIntegration,
    /// Factor `α` on the `Δt` of the pressure-gradient term of the face
    /// velocity (Guilkey Eq. 28 has `α = 1`); `α = 1/2` time-centres the
    /// face velocity and halves the `Δt`-proportional pressure dissipation
    /// (Sod L1 error −18 % at N = 400), `0 < α ≤ 1`.
    pub face_dt_factor: f64,
}

/// Time integration of the step sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeIntegration {
    /// One pass of the sequence (Guilkey Sec. 3.3 as written): first order
    /// in time.
    ForwardEuler,
    /// Heun / SSP-RK2: two passes with the same `Δt`, then the average of
    /// the conserved quantities, `U^{n+1} = (U^n + S(S(U^n)))/2`. Twice the
    /// cost per step. Measured: no gain, because the dominant error is the
    /// `Δt`-proportional pressure dissipation of Guilkey Eq. 28, which both
    /// stages apply (acoustic wave error at N equals forward Euler's at N/2).
    Heun,
}

/// Form of the internal-energy update of the Lagrangian phase and the
/// advection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EnergyForm {
    /// Guilkey Eq. 34 literally: `Δ(me)_r = −Δt V f_r^θ p Σ_s ∇·(θu*)_s`,
    /// internal energy advected. Not conservative in total energy, so shocks
    /// converge to slightly wrong states (Sod: post-shock density +2 %).
    FlowWork,
    /// Total-energy-conservative form of Eq. 34: per cell
    /// `Δ(mE) = −Δt Σ_f A p*_f Σ_s θ_s,f u*_s,f` (the face pressure of
    /// Eq. 31 times the mixture volume flux of Eq. 29); the internal-energy
    /// part `Δ(mE) − ΔKE` (the kinetic energy change of Eq. 33 and of the
    /// exchange, Eq. 38) is shared among the materials by `f_r^θ` as in
    /// Eq. 34; total energy `e + |u|²/2` is advected. Consistent with Eq. 34
    /// for smooth flow (`∇·(p u) − u·∇p = p ∇·u`); a cell whose advected
    /// total energy would leave `e ≤ 0` falls back to advecting `e`.
    Conservative,
}

impl<const D: usize> IceParams<D> {
    /// Defaults: `cfl = 0.5`, second order with van Leer, no gravity, no
    /// exchange, conservative energy, forward Euler, `face_dt_factor = 1`
    /// (Guilkey Eq. 28 as written), the given boundaries.
    pub fn new(boundaries: Boundaries<D>) -> Self {
        Self {
            cfl: 0.5,
            advection: Advection::SecondOrder(Limiter::VanLeer),
            gravity: SVector::zeros(),
            exchange: None,
            equilibration: EquilibrationSettings::default(),
            boundaries,
            energy: EnergyForm::Conservative,
            time: TimeIntegration::ForwardEuler,
            face_dt_factor: 1.0,
        }
    }

    /// Checks the parameters against a state.
    ///
    /// # Errors
    /// [`IceError::InvalidInput`] naming the offending parameter.
    pub fn validate(&self, state: &IceState<D>) -> Result<(), IceError> {
        if !(self.cfl.is_finite() && self.cfl > 0.0 && self.cfl <= 1.0) {
            return Err(invalid(
                "cfl",
                format!("must be in (0, 1], got {}", self.cfl),
            ));
        }
        if !(self.face_dt_factor.is_finite()
            && self.face_dt_factor > 0.0
            && self.face_dt_factor <= 1.0)
        {
            return Err(invalid(
                "face_dt_factor",
                format!("must be in (0, 1], got {}", self.face_dt_factor),
            ));
        }
        if !self.gravity.iter().all(|g| g.is_finite()) {
            return Err(invalid("gravity", "must be finite"));
        }
        let s = &self.equilibration;
        if !(s.tolerance.is_finite() && s.tolerance > 0.0) || s.max_iterations == 0 {
            return Err(invalid(
                "equilibration",
                "tolerance must be > 0 and max_iterations >= 1",
            ));
        }
        let nm = state.num_materials();
        if let Some(ex) = &self.exchange {
            ex.validate(nm)?;
        }
        for d in 0..D {
            let [lo, hi] = &self.boundaries[d];
            if (*lo == IceBoundary::Periodic) != (*hi == IceBoundary::Periodic) {
                return Err(invalid(
                    format!("boundaries[{d}]"),
                    "periodic must be set on both sides",
                ));
            }
            for (side, bc) in [lo, hi].into_iter().enumerate() {
                if let IceBoundary::Inflow(states) = bc {
                    if states.len() != nm {
                        return Err(invalid(
                            format!("boundaries[{d}][{side}]"),
                            format!("inflow needs {nm} material states, got {}", states.len()),
                        ));
                    }
                    let sum: f64 = states.iter().map(|s| s.vol_frac).sum();
                    if (sum - 1.0).abs() > 1e-12
                        || states
                            .iter()
                            .any(|s| !(s.density > 0.0 && s.temperature > 0.0 && s.vol_frac > 0.0))
                    {
                        return Err(invalid(
                            format!("boundaries[{d}][{side}]"),
                            "inflow needs vol_frac > 0 summing to 1, density > 0, temperature > 0",
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// Scratch memory of the step, allocated once per layout and material count.
#[derive(Debug, Clone)]
pub struct IceWorkspace<const D: usize> {
    ustar: Vec<[Vec<f64>; D]>,
    div: Vec<Vec<f64>>,
    kappa: Vec<Vec<f64>>,
    div_sum: Vec<f64>,
    sum_theta_kappa: Vec<f64>,
    mix_mass: Vec<f64>,
    press: Vec<f64>,
    pstar: [Vec<f64>; D],
    theta_flux: [Vec<f64>; D],
    mix_vflux: [Vec<f64>; D],
    ke: Vec<Vec<f64>>,
    vel_l: Vec<Vec<SVector<f64, D>>>,
    temp_l: Vec<Vec<f64>>,
    e_l: Vec<Vec<f64>>,
    v_l: Vec<Vec<f64>>,
    fluxes: AdvectionFluxes<D>,
    new_mass: Vec<Vec<f64>>,
    new_vel: Vec<Vec<SVector<f64, D>>>,
    new_temp: Vec<Vec<f64>>,
    new_spvol: Vec<Vec<f64>>,
    saved: Vec<super::state::MaterialCells<D>>,
}

impl<const D: usize> IceWorkspace<D> {
    /// Workspace for a state's layout and materials.
    pub fn new(state: &IceState<D>) -> Self {
        let n = state.layout.len();
        let nm = state.num_materials();
        let s = || vec![0.0; n];
        let sv = || vec![SVector::<f64, D>::zeros(); n];
        Self {
            ustar: (0..nm).map(|_| std::array::from_fn(|_| s())).collect(),
            div: (0..nm).map(|_| s()).collect(),
            kappa: (0..nm).map(|_| s()).collect(),
            div_sum: s(),
            sum_theta_kappa: s(),
            mix_mass: s(),
            press: s(),
            pstar: std::array::from_fn(|_| s()),
            theta_flux: std::array::from_fn(|_| s()),
            mix_vflux: std::array::from_fn(|_| s()),
            ke: (0..nm).map(|_| s()).collect(),
            vel_l: (0..nm).map(|_| sv()).collect(),
            temp_l: (0..nm).map(|_| s()).collect(),
            e_l: (0..nm).map(|_| s()).collect(),
            v_l: (0..nm).map(|_| s()).collect(),
            fluxes: AdvectionFluxes::new(n),
            new_mass: (0..nm).map(|_| s()).collect(),
            new_vel: (0..nm).map(|_| sv()).collect(),
            new_temp: (0..nm).map(|_| s()).collect(),
            new_spvol: (0..nm).map(|_| s()).collect(),
            saved: state.cells.clone(),
        }
    }
}

/// What a step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepInfo {
    /// The time step taken.
    pub dt: f64,
    /// Largest number of equilibration iterations in a cell.
    pub max_equilibration_iterations: usize,
}

fn site<const D: usize>(state: &IceState<D>, c: usize, material: Option<usize>) -> Site {
    Site {
        step: state.steps,
        time: state.time,
        cell: state.layout.coords(c).to_vec(),
        material,
    }
}

/// Fills the ghosts of mass, velocity and temperature of every material.
fn fill_primary_ghosts<const D: usize>(state: &mut IceState<D>, bcs: &Boundaries<D>) {
    let vol = state.layout.cell_volume();
    let layout = &state.layout;
    for (r, mc) in state.cells.iter_mut().enumerate() {
        fill_scalar(layout, bcs, &mut mc.mass, |s| {
            s[r].vol_frac * s[r].density * vol
        });
        fill_vector(layout, bcs, &mut mc.velocity, |s| s[r].velocity);
        fill_scalar(layout, bcs, &mut mc.temperature, |s| s[r].temperature);
    }
}

/// Equilibration pressure in every interior cell (Guilkey Eq. 13, step 2):
/// updates `p_eq`, `sp_vol` and `vol_frac` (interior and ghosts; the mass,
/// velocity and temperature ghosts are filled too). Returns the largest
/// iteration count.
///
/// # Errors
/// [`IceError::Equilibration`] naming the first failing cell.
pub fn equilibrate<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
) -> Result<usize, IceError> {
    let bcs = &params.boundaries;
    fill_primary_ghosts(state, bcs);
    let nm = state.num_materials();
    let vol = state.layout.cell_volume();
    let mut eos = [state.materials[0].eos; MAX_MATERIALS];
    for r in 0..nm {
        eos[r] = state.materials[r].eos;
    }
    let mut max_it = 0;
    let mut rb = [0.0; MAX_MATERIALS];
    let mut t = [0.0; MAX_MATERIALS];
    let mut v = [0.0; MAX_MATERIALS];
    let mut th = [0.0; MAX_MATERIALS];
    for k in 0..state.layout.interior.len() {
        let c = state.layout.interior[k];
        for r in 0..nm {
            rb[r] = state.cells[r].mass[c] / vol;
            t[r] = state.cells[r].temperature[c];
        }
        match equilibrate_cell(
            &eos[..nm],
            &rb[..nm],
            &t[..nm],
            state.p_eq[c],
            &params.equilibration,
            &mut v[..nm],
            &mut th[..nm],
        ) {
            Ok((p, it)) => {
                state.p_eq[c] = p;
                max_it = max_it.max(it);
                for r in 0..nm {
                    state.cells[r].sp_vol[c] = v[r];
                    state.cells[r].vol_frac[c] = th[r];
                }
            }
            Err(e) => {
                return Err(IceError::Equilibration {
                    site: site(state, c, None),
                    residual: e.residual,
                    iterations: e.iterations,
                    pressure: e.pressure,
                })
            }
        }
    }
    let layout = &state.layout;
    let eos0 = state.materials[0].eos;
    fill_scalar(layout, bcs, &mut state.p_eq, |s| {
        eos0.pressure(s[0].density, s[0].temperature)
    });
    for (r, mc) in state.cells.iter_mut().enumerate() {
        fill_scalar(layout, bcs, &mut mc.sp_vol, |s| 1.0 / s[r].density);
        fill_scalar(layout, bcs, &mut mc.vol_frac, |s| s[r].vol_frac);
    }
    Ok(max_it)
}

/// Stable time step `cfl / max_c Σ_d max_r (|u_r,d| + c̃_r)/h_d` from the
/// current (equilibrated, ghosts filled) state, with the sound speed
/// `c̃ = c √(max_f v_f / v)` seen through the face specific volumes of
/// Guilkey Eq. 28.
pub fn timestep<const D: usize>(state: &IceState<D>, cfl: f64) -> f64 {
    let mut rate: f64 = 0.0;
    for &c in &state.layout.interior {
        let mut sum = 0.0;
        for d in 0..D {
            let mut w: f64 = 0.0;
            let s = state.layout.strides[d];
            for (mat, mc) in state.materials.iter().zip(&state.cells) {
                let v = mc.sp_vol[c];
                // The face velocity (Guilkey Eq. 28) couples the cell to its
                // neighbours through v_f = 2 v_c v_n/(v_c + v_n) (< 2 v_n):
                // the effective sound speed is c √(max v_f / v_c).
                let hm = |vn: f64| 2.0 * v * vn / (v + vn);
                let vf = hm(mc.sp_vol[c - s]).max(hm(mc.sp_vol[c + s])).max(v);
                let cs = mat.eos.sound_speed(1.0 / v, mc.temperature[c]) * (vf / v).sqrt();
                w = w.max(mc.velocity[c][d].abs() + cs);
            }
            sum += w / state.layout.h[d];
        }
        rate = rate.max(sum);
    }
    if rate > 0.0 {
        cfl / rate
    } else {
        f64::INFINITY
    }
}

/// One explicit ICE step with `Δt = min(dt_max, cfl-limited Δt)`.
///
/// Sequence (Guilkey Sec. 3.3): ghosts; equilibration pressure (Eq. 13);
/// face velocities (Eq. 28) and face exchange; `Δp` (Eq. 29) and `p`
/// (Eq. 30); face pressure (Eq. 31); sources (Eqs. 33–34); Lagrangian
/// values (Eqs. 35–37); exchange (Eqs. 38–39); specific volume (Eqs. 40–41);
/// advection (step 12).
///
/// On error the primary state (mass, velocity, temperature, time) is
/// unchanged; [`IceError::TimestepTooLarge`] asks for a retry with a smaller
/// `dt_max`.
///
/// # Errors
/// [`IceError::Equilibration`], [`IceError::TimestepTooLarge`],
/// [`IceError::NonPhysical`], naming step, time, cell and material.
pub fn step<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt_max: f64,
) -> Result<StepInfo, IceError> {
    advance(state, params, ws, dt_max, false)
}

/// [`step`] with exactly the time step `dt` (no CFL limit), for a stepper
/// that chooses `Δt` itself (e.g. from the solid's sound speed); a `dt`
/// that empties a cell returns [`IceError::TimestepTooLarge`].
///
/// # Errors
/// As [`step`].
pub fn step_with_dt<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt: f64,
) -> Result<StepInfo, IceError> {
    advance(state, params, ws, dt, true)
}

fn advance<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt_max: f64,
    fixed: bool,
) -> Result<StepInfo, IceError> {
    match params.time {
        TimeIntegration::ForwardEuler => stage(state, params, ws, dt_max, fixed),
        TimeIntegration::Heun => {
            let (t0, n0) = (state.time, state.steps);
            for (saved, mc) in ws.saved.iter_mut().zip(&state.cells) {
                saved.mass.copy_from_slice(&mc.mass);
                saved.velocity.copy_from_slice(&mc.velocity);
                saved.temperature.copy_from_slice(&mc.temperature);
                saved.sp_vol.copy_from_slice(&mc.sp_vol);
            }
            let first = stage(state, params, ws, dt_max, fixed)?;
            let second = stage(state, params, ws, first.dt, true);
            let restore = |state: &mut IceState<D>, ws: &IceWorkspace<D>| {
                for (saved, mc) in ws.saved.iter().zip(state.cells.iter_mut()) {
                    mc.mass.copy_from_slice(&saved.mass);
                    mc.velocity.copy_from_slice(&saved.velocity);
                    mc.temperature.copy_from_slice(&saved.temperature);
                    mc.sp_vol.copy_from_slice(&saved.sp_vol);
                }
                state.time = t0;
                state.steps = n0;
            };
            let second = match second {
                Ok(s) => s,
                Err(e) => {
                    restore(state, ws);
                    return Err(e);
                }
            };
            // U^{n+1} = (U^n + S(S(U^n)))/2 on the conserved quantities
            // (mass, momentum, energy, material volume).
            let conservative = params.energy == EnergyForm::Conservative;
            for (r, (saved, mc)) in ws.saved.iter().zip(state.cells.iter_mut()).enumerate() {
                let cv = state.materials[r].eos.specific_heat_cv();
                for &c in &state.layout.interior {
                    let (m0, m2) = (saved.mass[c], mc.mass[c]);
                    let m = 0.5 * (m0 + m2);
                    let (u0, u2) = (saved.velocity[c], mc.velocity[c]);
                    let u = (u0 * m0 + u2 * m2) * (0.5 / m);
                    let mut me = 0.5 * cv * (m0 * saved.temperature[c] + m2 * mc.temperature[c]);
                    if conservative {
                        let ke = 0.25 * (m0 * u0.norm_squared() + m2 * u2.norm_squared())
                            - 0.5 * m * u.norm_squared();
                        if me + ke > 0.0 {
                            me += ke;
                        }
                    }
                    mc.sp_vol[c] = 0.5 * (m0 * saved.sp_vol[c] + m2 * mc.sp_vol[c]) / m;
                    mc.mass[c] = m;
                    mc.velocity[c] = u;
                    mc.temperature[c] = me / (m * cv);
                }
            }
            state.time = t0 + first.dt;
            state.steps = n0 + 1;
            Ok(StepInfo {
                dt: first.dt,
                max_equilibration_iterations: first
                    .max_equilibration_iterations
                    .max(second.max_equilibration_iterations),
            })
        }
    }
}

/// One forward-Euler pass of the step sequence; `fixed` uses exactly
/// `dt_max` instead of the CFL limit.
fn stage<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt_max: f64,
    fixed: bool,
) -> Result<StepInfo, IceError> {
    let nm = state.num_materials();
    let bcs = &params.boundaries;
    let scheme = params.advection;
    // Step 2: equilibration pressure (Guilkey Eq. 13).
    let max_it = equilibrate(state, params)?;
    let dt = if fixed {
        dt_max
    } else {
        timestep(state, params.cfl).min(dt_max)
    };
    if !(dt.is_finite() && dt > 0.0) {
        return Err(invalid(
            "dt",
            format!("time step must be finite and > 0, got {dt}"),
        ));
    }
    let layout = &state.layout;
    let vol = layout.cell_volume();
    let exchange = params.exchange.as_ref().filter(|_| nm > 1);
    let k_on = exchange.filter(|e| e.momentum.iter().any(|&k| k > 0.0));
    let h_on = exchange.filter(|e| !e.heat_off());

    // Step 3: face velocities (Guilkey Eq. 28), then the face exchange.
    for r in 0..nm {
        let mc = &state.cells[r];
        for d in 0..D {
            let out = &mut ws.ustar[r][d];
            let fdt = params.face_dt_factor * dt;
            face_velocities(
                layout,
                d,
                &mc.mass,
                &mc.velocity,
                &mc.sp_vol,
                &state.p_eq,
                fdt,
                params.gravity[d] * dt / fdt,
                out,
            );
            zero_wall_faces(layout, bcs, d, out);
        }
    }
    if let Some(ex) = k_on {
        for d in 0..D {
            face_exchange(layout, d, &ex.momentum, dt, &state.cells, &mut ws.ustar);
        }
    }
    // Outflux larger than a cell's content: ask for a smaller step.
    for r in 0..nm {
        for &c in &layout.interior {
            let mut courant = 0.0;
            for d in 0..D {
                let s = layout.strides[d];
                let (lo, hi) = (ws.ustar[r][d][c], ws.ustar[r][d][c + s]);
                courant += (hi.max(0.0) - lo.min(0.0)) * dt / layout.h[d];
            }
            if courant > 1.0 {
                return Err(IceError::TimestepTooLarge {
                    site: site(state, c, Some(r)),
                    courant,
                    dt,
                });
            }
        }
    }

    // Step 5: Δp (Guilkey Eq. 29) and p = p_eq + Δp (Eq. 30).
    ws.div_sum.iter_mut().for_each(|x| *x = 0.0);
    ws.sum_theta_kappa.iter_mut().for_each(|x| *x = 0.0);
    for r in 0..nm {
        let mc = &state.cells[r];
        let eos = &state.materials[r].eos;
        for d in 0..D {
            scalar_fluxes(
                layout,
                d,
                &ws.ustar[r][d],
                &mc.vol_frac,
                dt,
                scheme,
                &mut ws.theta_flux[d],
            );
            let acc = &mut ws.mix_vflux[d];
            if r == 0 {
                for &f in &layout.faces[d] {
                    acc[f] = ws.theta_flux[d][f];
                }
            } else {
                for &f in &layout.faces[d] {
                    acc[f] += ws.theta_flux[d][f];
                }
            }
        }
        let div = &mut ws.div[r];
        let kappa = &mut ws.kappa[r];
        for &c in &layout.interior {
            // ∇·(θ u*)_r; the fluxes carry Δt/h.
            let dv = -net_inflow(layout, &ws.theta_flux, c) / dt;
            div[c] = dv;
            ws.div_sum[c] += dv;
            let k = eos.compressibility(1.0 / mc.sp_vol[c], mc.temperature[c]);
            kappa[c] = k;
            ws.sum_theta_kappa[c] += mc.vol_frac[c] * k;
        }
    }
    let p_min = state
        .materials
        .iter()
        .map(|m| min_pressure(&m.eos))
        .fold(f64::NEG_INFINITY, f64::max);
    for &c in &layout.interior {
        let p = state.p_eq[c] - dt * ws.div_sum[c] / ws.sum_theta_kappa[c];
        if !(p.is_finite() && p > p_min) {
            return Err(IceError::NonPhysical {
                site: site(state, c, None),
                quantity: "pressure",
                value: p,
            });
        }
        ws.press[c] = p;
    }
    let eos0 = state.materials[0].eos;
    fill_scalar(layout, bcs, &mut ws.press, |s| {
        eos0.pressure(s[0].density, s[0].temperature)
    });

    // Step 6: face pressure (Guilkey Eq. 31).
    ws.mix_mass.iter_mut().for_each(|x| *x = 0.0);
    for mc in &state.cells {
        for (m, &mr) in ws.mix_mass.iter_mut().zip(&mc.mass) {
            *m += mr;
        }
    }
    for d in 0..D {
        face_pressure(layout, d, &ws.press, &ws.mix_mass, &mut ws.pstar[d]);
    }

    // Steps 8–9: sources (Guilkey Eqs. 33–34) and Lagrangian values
    // (Eqs. 35–37), as specific quantities u^{L−}, T^{L−}.
    for r in 0..nm {
        let mc = &state.cells[r];
        let cv = state.materials[r].eos.specific_heat_cv();
        for &c in &layout.interior {
            let m = mc.mass[c];
            let theta = mc.vol_frac[c];
            let mut grad = SVector::<f64, D>::zeros();
            for d in 0..D {
                grad[d] = (ws.pstar[d][c + layout.strides[d]] - ws.pstar[d][c]) / layout.h[d];
            }
            // Guilkey Eq. 33: Δ(mu) = −Δt V θ ∇p* + Δt M g.
            let mom = mc.velocity[c] * m - grad * (dt * vol * theta) + params.gravity * (dt * m);
            ws.vel_l[r][c] = mom / m;
            if params.energy == EnergyForm::FlowWork {
                // Guilkey Eq. 34: Δ(me) = −Δt V f^θ p Σ_s ∇·(θu*)_s.
                let f_theta = theta * ws.kappa[r][c] / ws.sum_theta_kappa[c];
                let me =
                    m * cv * mc.temperature[c] - dt * vol * f_theta * ws.press[c] * ws.div_sum[c];
                ws.temp_l[r][c] = me / (m * cv);
            }
        }
    }
    let conservative = params.energy == EnergyForm::Conservative;

    // Steps 10–11: exchange (Guilkey Eqs. 38–39) and specific volume
    // (Eqs. 40–41, Appendix Eq. 53).
    let mut theta = [0.0; MAX_MATERIALS];
    let mut v = [0.0; MAX_MATERIALS];
    let mut mass = [0.0; MAX_MATERIALS];
    let mut cv = [0.0; MAX_MATERIALS];
    let mut u = [SVector::<f64, D>::zeros(); MAX_MATERIALS];
    let mut t = [0.0; MAX_MATERIALS];
    let mut t_before = [0.0; MAX_MATERIALS];
    let mut beta = [0.0; MAX_MATERIALS];
    for r in 0..nm {
        cv[r] = state.materials[r].eos.specific_heat_cv();
    }
    for &c in &layout.interior {
        for r in 0..nm {
            let mc = &state.cells[r];
            theta[r] = mc.vol_frac[c];
            v[r] = mc.sp_vol[c];
            mass[r] = mc.mass[c];
            u[r] = ws.vel_l[r][c];
        }
        if conservative {
            // Conservative Eq. 34: Δ(mE) = −Δt Σ_f A p*_f Σ_s θ_s,f u*_s,f
            // (the stored fluxes carry Δt A / V).
            let mut de = 0.0;
            for d in 0..D {
                let f_hi = c + layout.strides[d];
                de +=
                    ws.pstar[d][c] * ws.mix_vflux[d][c] - ws.pstar[d][f_hi] * ws.mix_vflux[d][f_hi];
            }
            de *= vol;
            let mut dke = 0.0;
            for r in 0..nm {
                let u0 = state.cells[r].velocity[c];
                dke += 0.5 * mass[r] * (u[r].norm_squared() - u0.norm_squared());
            }
            let de_int = de - dke;
            for r in 0..nm {
                let f_theta = theta[r] * ws.kappa[r][c] / ws.sum_theta_kappa[c];
                let me = mass[r] * cv[r] * state.cells[r].temperature[c] + f_theta * de_int;
                ws.temp_l[r][c] = me / (mass[r] * cv[r]);
            }
        }
        for r in 0..nm {
            t[r] = ws.temp_l[r][c];
        }
        if let Some(ex) = k_on {
            let ke0: f64 = (0..nm).map(|r| 0.5 * mass[r] * u[r].norm_squared()).sum();
            exchange_momentum(
                &ex.momentum,
                dt,
                &theta[..nm],
                &v[..nm],
                &mass[..nm],
                &mut u[..nm],
            );
            if conservative {
                // The kinetic energy dissipated by the exchange becomes heat.
                let ke1: f64 = (0..nm).map(|r| 0.5 * mass[r] * u[r].norm_squared()).sum();
                for r in 0..nm {
                    let f_theta = theta[r] * ws.kappa[r][c] / ws.sum_theta_kappa[c];
                    t[r] += f_theta * (ke0 - ke1) / (mass[r] * cv[r]);
                }
            }
        }
        t_before[..nm].copy_from_slice(&t[..nm]);
        let mut sum_tb = 0.0;
        if let Some(ex) = h_on {
            exchange_heat(
                &ex.heat,
                dt,
                &theta[..nm],
                &v[..nm],
                &cv[..nm],
                &mass[..nm],
                &mut t[..nm],
            );
            for r in 0..nm {
                let eos = &state.materials[r].eos;
                beta[r] = eos.thermal_expansivity(1.0 / v[r], t_before[r]);
                sum_tb += theta[r] * beta[r] * (t[r] - t_before[r]) / dt;
            }
        }
        for r in 0..nm {
            if !(t[r].is_finite() && t[r] > 0.0) {
                return Err(IceError::NonPhysical {
                    site: site(state, c, Some(r)),
                    quantity: "temperature",
                    value: t[r],
                });
            }
            ws.vel_l[r][c] = u[r];
            ws.temp_l[r][c] = t[r];
            ws.e_l[r][c] = cv[r] * t[r];
            ws.ke[r][c] = 0.5 * u[r].norm_squared();
            // Guilkey Eq. 40 with the isentropic κ of Eq. 29: the
            // adiabatic heating is inside κ, so Ṫ is the exchange part only.
            let f_theta = theta[r] * ws.kappa[r][c] / ws.sum_theta_kappa[c];
            let mut dmv = f_theta * ws.div_sum[c];
            if h_on.is_some() {
                dmv += theta[r] * beta[r] * (t[r] - t_before[r]) / dt - f_theta * sum_tb;
            }
            // Guilkey Eq. 41.
            let mv = mass[r] * v[r] + dt * vol * dmv;
            if !(mv.is_finite() && mv > 0.0) {
                return Err(IceError::NonPhysical {
                    site: site(state, c, Some(r)),
                    quantity: "specific volume",
                    value: mv / mass[r],
                });
            }
            ws.v_l[r][c] = mv / mass[r];
        }
    }

    // Step 12: advection with compatible fluxes.
    for r in 0..nm {
        let inflow_v = |s: &[super::InflowState<D>]| s[r].velocity;
        fill_vector(layout, bcs, &mut ws.vel_l[r], inflow_v);
        let cvr = cv[r];
        fill_scalar(layout, bcs, &mut ws.e_l[r], |s| cvr * s[r].temperature);
        fill_scalar(layout, bcs, &mut ws.v_l[r], |s| 1.0 / s[r].density);
        if conservative {
            fill_scalar(layout, bcs, &mut ws.ke[r], |s| {
                0.5 * s[r].velocity.norm_squared()
            });
        }
        let mc = &state.cells[r];
        let fields = AdvectedFields {
            mass: &mc.mass,
            velocity: &ws.vel_l[r],
            energy: &ws.e_l[r],
            sp_vol: &ws.v_l[r],
            kinetic: if conservative { Some(&ws.ke[r]) } else { None },
        };
        material_fluxes(layout, &ws.ustar[r], &fields, dt, scheme, &mut ws.fluxes);
        let fx = &ws.fluxes;
        for &c in &layout.interior {
            let m0 = mc.mass[c];
            let m = m0 + net_inflow(layout, &fx.mass, c);
            if !(m.is_finite() && m > 0.0) {
                return Err(IceError::NonPhysical {
                    site: site(state, c, Some(r)),
                    quantity: "mass",
                    value: m,
                });
            }
            let mom = ws.vel_l[r][c] * m0 + net_inflow_vec(layout, &fx.momentum, c);
            let mut me = m0 * ws.e_l[r][c] + net_inflow(layout, &fx.energy, c);
            if conservative {
                // Total energy advected; internal = total − kinetic.
                let me_tot = me + m0 * ws.ke[r][c] + net_inflow(layout, &fx.kinetic, c);
                let me_cons = me_tot - 0.5 * mom.norm_squared() / m;
                if me_cons > 0.0 {
                    me = me_cons;
                }
            }
            let mv = m0 * ws.v_l[r][c] + net_inflow(layout, &fx.volume, c);
            let temp = me / (m * cvr);
            if !(temp.is_finite() && temp > 0.0) {
                return Err(IceError::NonPhysical {
                    site: site(state, c, Some(r)),
                    quantity: "temperature",
                    value: temp,
                });
            }
            if !(mv.is_finite() && mv > 0.0) {
                return Err(IceError::NonPhysical {
                    site: site(state, c, Some(r)),
                    quantity: "specific volume",
                    value: mv / m,
                });
            }
            ws.new_mass[r][c] = m;
            ws.new_vel[r][c] = mom / m;
            ws.new_temp[r][c] = temp;
            ws.new_spvol[r][c] = mv / m;
        }
    }
    // Commit.
    for r in 0..nm {
        let mc = &mut state.cells[r];
        std::mem::swap(&mut mc.mass, &mut ws.new_mass[r]);
        std::mem::swap(&mut mc.velocity, &mut ws.new_vel[r]);
        std::mem::swap(&mut mc.temperature, &mut ws.new_temp[r]);
        std::mem::swap(&mut mc.sp_vol, &mut ws.new_spvol[r]);
    }
    std::mem::swap(&mut state.pressure, &mut ws.press);
    // Keep the old p_eq as the next equilibration's guess (already there).
    state.time += dt;
    state.steps += 1;
    Ok(StepInfo {
        dt,
        max_equilibration_iterations: max_it,
    })
}

/// Result of [`run_fluid`].
#[derive(Debug, Clone)]
pub struct FluidRun<const D: usize> {
    /// Final state (equilibrated: `p_eq`, `sp_vol`, `vol_frac` are
    /// consistent with the final masses and temperatures).
    pub state: IceState<D>,
    /// Steps taken.
    pub steps: u64,
    /// Steps retried with a smaller time step.
    pub retries: u64,
    /// Wall-clock time of the time loop in seconds.
    pub wall_s: f64,
}

/// Runs a fluid-only scene from `state` to `t_end` (at most `max_steps`
/// steps), retrying a step with half the time step when it reports
/// [`IceError::TimestepTooLarge`] (up to 20 times in a row).
///
/// # Errors
/// [`IceError::InvalidInput`] for invalid parameters, a non-finite `t_end`
/// or exceeding `max_steps`; any error of [`step`].
pub fn run_fluid<const D: usize>(
    mut state: IceState<D>,
    params: &IceParams<D>,
    t_end: f64,
    max_steps: u64,
) -> Result<FluidRun<D>, IceError> {
    params.validate(&state)?;
    if !(t_end.is_finite() && t_end >= state.time) {
        return Err(invalid(
            "t_end",
            format!(
                "must be finite and >= the current time {}, got {t_end}",
                state.time
            ),
        ));
    }
    let mut ws = IceWorkspace::new(&state);
    let start = Instant::now();
    let mut steps = 0u64;
    let mut retries = 0u64;
    // Stop within a relative round-off of t_end.
    while state.time < t_end * (1.0 - 1e-14) {
        if steps >= max_steps {
            return Err(invalid(
                "max_steps",
                format!(
                    "{max_steps} steps reached at t = {} < t_end = {t_end}",
                    state.time
                ),
            ));
        }
        let mut dt_max = t_end - state.time;
        let mut tries = 0;
        loop {
            match step(&mut state, params, &mut ws, dt_max) {
                Ok(_) => break,
                Err(IceError::TimestepTooLarge { dt, .. }) if tries < 20 => {
                    dt_max = 0.5 * dt;
                    tries += 1;
                    retries += 1;
                }
                Err(e) => return Err(e),
            }
        }
        steps += 1;
    }
    let wall_s = start.elapsed().as_secs_f64();
    equilibrate(&mut state, params)?;
    Ok(FluidRun {
        state,
        steps,
        retries,
        wall_s,
    })
}
