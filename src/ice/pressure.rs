//! The pressure stage of the ICE step (Guilkey Sec. 3.3 steps 2–6):
//! equilibration pressure in every cell (Eq. 13, [`equilibrate`]; the
//! per-cell Newton is in [`super::equilibration`]), the time step, face
//! velocities (Eq. 28) and their exchange, `Δp` (Eq. 29, explicit here or
//! semi-implicit in [`super::implicit`]) and `p = p_eq + w Δp` (Eq. 30),
//! and the face pressure (Eq. 31) ([`stage_pressure`]).

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use super::boundary::{fill_scalar, fill_vector, zero_wall_faces, Boundaries};
use super::equilibration::{
    equilibrate_cell, expanded_pressure, min_pressure, min_pressure_all, EquilibrationFailure,
    EquilibrationSettings,
};
use super::faces::{face_exchange, face_pressure, face_velocities, face_viscosity, FacePredictor};
use super::implicit::{implicit_pressure, save_pre_exchange};
use super::par::{try_rows, Out};
use super::params::{cell_shock_sensor, Frame, IceParams};
use super::state::{CellLayout, IceState};
use super::timestep::step_dt;
use super::volume_flux::volume_fluxes;
use super::workspace::{IceWorkspace, StepInfo};
use super::{site, IceError, Site, MAX_MATERIALS};
use crate::material::eos::{EquationOfState, FluidEos};

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

/// Fraction of a cell's volume a particle material must fill for the
/// equilibration to normalise freely on the total material volume
/// ([`IceParams::normalise_volume`]); below it the reference volume blends
/// linearly to a bounded one, `V_t = V_b + w (Σ_r M_r v_r − V_b)` with
/// `w = min(1, V_solid / (f V))` and `V_b` the total material volume
/// clamped to `[V / R, R V]` (`R` = [`FLUID_NORMALISING_RANGE`]).
///
/// The normalisation absorbs the error of a solid's interpolated volume.
/// In cells without solid it leaves the fluid's evolved specific volume
/// (Guilkey Eqs. 40–41) without the restoring force of `Σ θ = 1` on the
/// cell; near a moving rigid surface the fluid's `M v` departs from `V` by
/// up to a factor 2 and tracks its compression (the piston's closed-end
/// pressure depends on it), but in the near-vacuum wake behind the Mach 3
/// wedge it drifted to 3 % of the cell at 16 times its neighbours'
/// pressure before the temperature went negative (h = 0.00125).
pub const SOLID_FILL_FOR_NORMALISING: f64 = 1.0e-2;

/// The weight `w = min(1, V_solid / (f V))` of the free normalisation in a
/// cell whose particle materials fill `solid_volume` of `cell_volume`
/// ([`SOLID_FILL_FOR_NORMALISING`]); at 1 the cell's reference volume is
/// its total material volume.
#[inline]
pub fn normalising_weight(solid_volume: f64, cell_volume: f64) -> f64 {
    (solid_volume / (SOLID_FILL_FOR_NORMALISING * cell_volume)).min(1.0)
}

/// How far (as a factor) the total material volume of a cell without solid
/// may depart from the cell volume in the normalised equilibration (see
/// [`SOLID_FILL_FOR_NORMALISING`]).
pub const FLUID_NORMALISING_RANGE: f64 = 2.0;

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
    let max_it = AtomicUsize::new(0);
    // A failure names the material where the cells hold only one.
    let only: Option<Box<str>> = (nm == 1).then(|| format!("`{}`", state.materials[0].name).into());
    // Split the borrows: inputs (mass, temperature) read, outputs written.
    let IceState {
        layout,
        cells,
        p_eq,
        steps,
        time,
        ..
    } = state;
    let mut out = CellEquilibrium {
        p: Out::new(p_eq),
        sp_vol: [Out::empty(); MAX_MATERIALS],
        vol_frac: [Out::empty(); MAX_MATERIALS],
    };
    let mut mass: [&[f64]; MAX_MATERIALS] = [&[]; MAX_MATERIALS];
    let mut temp: [&[f64]; MAX_MATERIALS] = [&[]; MAX_MATERIALS];
    for (r, mc) in cells.iter_mut().enumerate() {
        out.sp_vol[r] = Out::new(&mut mc.sp_vol);
        out.vol_frac[r] = Out::new(&mut mc.vol_frac);
        mass[r] = &mc.mass;
        temp[r] = &mc.temperature;
    }
    let (step_no, t_now) = (*steps, *time);
    let mut particle = [false; MAX_MATERIALS];
    for (r, p) in particle.iter_mut().enumerate().take(nm) {
        *p = params.frame(r) != Frame::Eulerian;
    }
    let inputs = CellInputs {
        eos: &eos[..nm],
        mass,
        temp,
        particle,
        vol,
        normalise: params.normalise_volume,
        // Ideal gas only: p(ρ, T) has no cancellation there (a stiffened gas
        // with a large p_∞ keeps the iteration on the density balance).
        single: nm == 1 && !params.normalise_volume && matches!(eos[0], FluidEos::IdealGas(_)),
        p_min0: min_pressure(&eos[0]),
        settings: &params.equilibration,
    };
    let lay: &CellLayout<D> = layout;
    try_rows(lay, |row| {
        let mut local_max = 0;
        for c in row {
            match equilibrate_one(&inputs, &out, c) {
                Ok(it) => local_max = local_max.max(it),
                Err(e) => {
                    return Err(IceError::Equilibration {
                        site: Site {
                            step: step_no,
                            time: t_now,
                            cell: lay.coords(c).to_vec(),
                            material: only.as_ref().map(|_| 0),
                            material_name: only.clone(),
                        },
                        residual: e.residual,
                        iterations: e.iterations,
                        pressure: e.pressure,
                    })
                }
            }
        }
        max_it.fetch_max(local_max, Ordering::Relaxed);
        Ok(())
    })?;
    fill_equilibrium_ghosts(state, bcs);
    Ok(max_it.into_inner())
}

/// What the equilibration of one cell reads: the materials' equations of
/// state (`nm` entries), masses and temperatures per cell, which materials
/// are particle-borne, the cell volume and the settings.
struct CellInputs<'a> {
    eos: &'a [FluidEos],
    mass: [&'a [f64]; MAX_MATERIALS],
    temp: [&'a [f64]; MAX_MATERIALS],
    particle: [bool; MAX_MATERIALS],
    vol: f64,
    /// [`IceParams::normalise_volume`].
    normalise: bool,
    /// One ideal gas: `p = p(ρ̂, T)` without iteration.
    single: bool,
    /// Lowest admissible pressure of the first material.
    p_min0: f64,
    settings: &'a EquilibrationSettings,
}

/// Where the equilibration of one cell writes `p_eq` (read first as the
/// Newton guess) and each material's `sp_vol` (read first by the
/// normalised reference volume) and `vol_frac`.
struct CellEquilibrium<'a> {
    p: Out<'a, f64>,
    sp_vol: [Out<'a, f64>; MAX_MATERIALS],
    vol_frac: [Out<'a, f64>; MAX_MATERIALS],
}

/// Guilkey Eq. 13 in cell `c`: `p_eq`, `v_r` and `θ_r` with `Σ_r θ_r = 1`
/// on the reference volume of the cell. Returns the iteration count.
///
/// Each cell `c` must be read and written by one task only.
// Called once per cell from one place: the body of the loop it came
// from before the stage split, kept inlined there.
#[inline(always)]
fn equilibrate_one(
    inp: &CellInputs<'_>,
    out: &CellEquilibrium<'_>,
    c: usize,
) -> Result<usize, EquilibrationFailure> {
    let nm = inp.eos.len();
    let vt = if inp.normalise {
        reference_volume(inp, out, c)
    } else {
        inp.vol
    };
    let mut rb = [0.0; MAX_MATERIALS];
    let mut t = [0.0; MAX_MATERIALS];
    for r in 0..nm {
        rb[r] = inp.mass[r][c] / vt;
        t[r] = inp.temp[r][c];
    }
    if inp.single {
        // One ideal gas: Eq. 13 is θ = ρ̂ v = 1, so v = 1/ρ̂ and
        // p = p(ρ̂, T) directly (no iteration).
        let p = inp.eos[0].pressure(rb[0], t[0]);
        if p.is_finite() && p > inp.p_min0 && rb[0] > 0.0 {
            // SAFETY: cell c is written by this task only.
            unsafe {
                out.p.set(c, p);
                out.sp_vol[0].set(c, 1.0 / rb[0]);
                out.vol_frac[0].set(c, 1.0);
            }
            return Ok(1);
        }
    }
    // SAFETY: cell c is read and written by this task only.
    let guess = unsafe { out.p.get(c) };
    let mut v = [0.0; MAX_MATERIALS];
    let mut th = [0.0; MAX_MATERIALS];
    let (p, it) = equilibrate_cell(
        inp.eos,
        &rb[..nm],
        &t[..nm],
        guess,
        inp.settings,
        &mut v[..nm],
        &mut th[..nm],
    )?;
    // SAFETY: as above.
    unsafe {
        out.p.set(c, p);
        for r in 0..nm {
            out.sp_vol[r].set(c, v[r]);
            out.vol_frac[r].set(c, th[r]);
        }
    }
    Ok(it)
}

/// The reference volume `V_t` of cell `c` in the normalised equilibration
/// (Guilkey Sec. 3.3 step 2): `θ_r` per total material volume
/// `Σ_r M_r v_r` where a particle material fills the cell, blended to the
/// cell volume where it does not (see [`SOLID_FILL_FOR_NORMALISING`]);
/// the cell volume when the total is not positive.
// Called once per cell from one place: the body of the loop it came
// from before the stage split, kept inlined there.
#[inline(always)]
fn reference_volume(inp: &CellInputs<'_>, out: &CellEquilibrium<'_>, c: usize) -> f64 {
    let (mut sum, mut solid) = (0.0, 0.0);
    for r in 0..inp.eos.len() {
        // SAFETY: cell c is read and written by this task only.
        let mv = inp.mass[r][c] * unsafe { out.sp_vol[r].get(c) };
        sum += mv;
        if inp.particle[r] {
            solid += mv;
        }
    }
    if sum.is_finite() && sum > 0.0 {
        let w = normalising_weight(solid, inp.vol);
        let r = FLUID_NORMALISING_RANGE;
        let bounded = sum.clamp(inp.vol / r, inp.vol * r);
        bounded + w * (sum - bounded)
    } else {
        inp.vol
    }
}

/// Fills the ghosts of `p_eq` and of every material's `sp_vol` and
/// `vol_frac` from the boundary conditions.
fn fill_equilibrium_ghosts<const D: usize>(state: &mut IceState<D>, bcs: &Boundaries<D>) {
    let layout = &state.layout;
    let eos0 = state.materials[0].eos;
    fill_scalar(layout, bcs, &mut state.p_eq, |s| {
        eos0.pressure(s[0].density, s[0].temperature)
    });
    for (r, mc) in state.cells.iter_mut().enumerate() {
        fill_scalar(layout, bcs, &mut mc.sp_vol, |s| 1.0 / s[r].density);
        fill_scalar(layout, bcs, &mut mc.vol_frac, |s| s[r].vol_frac);
    }
}

/// Steps 2–6 of the sequence (Guilkey Sec. 3.3): equilibration pressure
/// (Eq. 13), the time step, face velocities (Eq. 28) and their exchange,
/// the pressure `p = p_eq + Δp` (Eqs. 29–30, explicit or semi-implicit) and
/// the face pressure (Eq. 31). Leaves the pressure in
/// [`IceWorkspace::pressure`] and the face pressures in
/// [`IceWorkspace::face_pressure`]; the state is not changed except for the
/// equilibrated `p_eq`, `sp_vol` and `vol_frac`.
///
/// # Errors
/// As [`super::step()`].
pub fn stage_pressure<const D: usize>(
    state: &mut IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt_max: f64,
    fixed: bool,
) -> Result<StepInfo, IceError> {
    let nm = state.num_materials();
    let bcs = &params.boundaries;
    // Step 2: equilibration pressure (Guilkey Eq. 13).
    let max_it = equilibrate(state, params)?;
    let implicit = params.implicit.as_ref();
    let dt = step_dt(state, params, ws.last_dt, dt_max, fixed)?;
    let state: &IceState<D> = state;
    let layout = &state.layout;
    let exchange = params.exchange.as_ref().filter(|_| nm > 1);
    let k_on = exchange.filter(|e| e.momentum.iter().any(|&k| k > 0.0));

    // Step 3: face velocities (Guilkey Eq. 28), then the face exchange.
    let fdt = params.face_dt_factor * dt;
    let use_pred = predict_velocities(state, params, ws, dt);
    let predictor_on = params.face_predictor && params.face_reconstruction.is_some();
    let viscosity = params.face_viscosity.filter(|&mu| mu > 0.0);
    // Mixture mass per cell, ghosts included (Guilkey Eq. 31 and the
    // mixture sound speed).
    mixture_mass(state, &mut ws.mix_mass);
    if predictor_on || params.acoustic_jump.is_some() || viscosity.is_some() {
        mixture_sound_speed(state, &ws.mix_mass, &mut ws.bulk, &mut ws.sound);
    }
    material_face_velocities(state, params, ws, dt, fdt, use_pred);
    if let Some(sp) = implicit {
        // The implicit correction starts from the pre-exchange values.
        save_pre_exchange(state, params, sp, ws)?;
    }
    if let Some(ex) = k_on {
        for d in 0..D {
            face_exchange(
                layout,
                d,
                &ex.momentum,
                dt,
                &state.cells,
                params,
                &mut ws.ustar,
            );
        }
    }
    let (outer_iterations, linear_iterations) = if let Some(sp) = implicit {
        // Semi-implicit: the pressure equation solved by the outer
        // iteration of `implicit` (fills `ws.press`, the volume fluxes and
        // the face velocities consistent with the new pressure).
        let its = implicit_pressure(state, params, sp, ws, dt, fdt)?;
        courant_check(state, &ws.ustar, dt)?;
        its
    } else {
        courant_check(state, &ws.ustar, dt)?;
        // Step 5: Δp (Guilkey Eq. 29) and p = p_eq + Δp (Eq. 30).
        volume_fluxes(state, params, ws, dt);
        explicit_pressure(state, params, ws, dt)?;
        (0, 0)
    };
    let eos0 = state.materials[0].eos;
    fill_scalar(layout, bcs, &mut ws.press, |s| {
        eos0.pressure(s[0].density, s[0].temperature)
    });

    // Step 6: face pressure (Guilkey Eq. 31), with the face viscosity.
    face_pressures(state, ws, viscosity);
    Ok(StepInfo {
        dt,
        max_equilibration_iterations: max_it,
        outer_iterations,
        linear_iterations,
    })
}

/// Semi-implicit convective predictor: the cell velocities seen by Guilkey
/// Eq. 28 advanced by the previous step's advective acceleration,
/// `u + a Δt · convective_predictor`, into `ws.vel_pred` (ghosts filled).
/// Returns whether the predictor is on (it needs the accelerations of a
/// previous step).
fn predict_velocities<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt: f64,
) -> bool {
    let nm = state.num_materials();
    let layout = &state.layout;
    let bcs = &params.boundaries;
    let predictor = params
        .implicit
        .as_ref()
        .map_or(0.0, |sp| sp.convective_predictor);
    let use_pred = predictor > 0.0 && ws.accel.len() == nm;
    if use_pred {
        for r in 0..nm {
            let (vp, acc, u) = (&mut ws.vel_pred[r], &ws.accel[r], &state.cells[r].velocity);
            for &c in &layout.interior {
                vp[c] = u[c] + acc[c] * (predictor * dt);
            }
            fill_vector(layout, bcs, vp, |s| s[r].velocity);
        }
    }
    use_pred
}

/// Mixture mass `Σ_r M_r` per cell, ghosts included, into `mix_mass`.
fn mixture_mass<const D: usize>(state: &IceState<D>, mix_mass: &mut [f64]) {
    let cells = &state.cells;
    let mix = |(i, m): (usize, &mut f64)| {
        let mut sum = 0.0;
        for mc in cells {
            sum += mc.mass[i];
        }
        *m = sum;
    };
    if state.layout.rows.len() == 1 {
        mix_mass.iter_mut().enumerate().for_each(mix);
    } else {
        mix_mass.par_iter_mut().enumerate().for_each(mix);
    }
}

/// Mixture bulk modulus `K = 1/Σ_s θ_s κ_s` (as in Guilkey Eq. 29) and
/// sound speed `c = √(K V/M)` per cell, ghosts included (the face kernels
/// read the cells on both sides of each face), into `bulk` and `sound`
/// (sized to the layout on first use).
fn mixture_sound_speed<const D: usize>(
    state: &IceState<D>,
    mix_mass: &[f64],
    bulk: &mut Vec<f64>,
    sound: &mut Vec<f64>,
) {
    let layout = &state.layout;
    bulk.resize(layout.len(), 0.0);
    sound.resize(layout.len(), 0.0);
    let cells = &state.cells;
    let mats = &state.materials;
    let vol = layout.cell_volume();
    let kernel = |(c, (k, cs)): (usize, (&mut f64, &mut f64))| {
        let mut stk = 0.0;
        for (mat, mc) in mats.iter().zip(cells) {
            let v = mc.sp_vol[c];
            if v > 0.0 && mc.vol_frac[c] > 0.0 {
                stk += mc.vol_frac[c] * mat.eos.compressibility(1.0 / v, mc.temperature[c]);
            }
        }
        *k = if stk > 0.0 { 1.0 / stk } else { 0.0 };
        let m = mix_mass[c];
        *cs = if m > 0.0 { (*k * vol / m).sqrt() } else { 0.0 };
    };
    if layout.rows.len() == 1 {
        bulk.iter_mut()
            .zip(sound.iter_mut())
            .enumerate()
            .for_each(kernel);
    } else {
        bulk.par_iter_mut()
            .zip(sound.par_iter_mut())
            .enumerate()
            .for_each(kernel);
    }
}

/// Step 3: the face velocities `u*` of every material and direction
/// (Guilkey Eq. 28, [`face_velocities`]) into `ws.ustar`, zero at walls,
/// from the cell velocities (or the predicted ones with `use_pred`). A
/// rigid material's face velocity is the average of its prescribed cell
/// velocities (no pressure acceleration), and so is a held solid's
/// ([`IceParams::held_solids`]) at the faces it fills on both sides.
fn material_face_velocities<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt: f64,
    fdt: f64,
    use_pred: bool,
) {
    let layout = &state.layout;
    let bcs = &params.boundaries;
    let predictor_on = params.face_predictor && params.face_reconstruction.is_some();
    let hold = params.held_faces();
    for r in 0..state.num_materials() {
        let mc = &state.cells[r];
        let vel_in = if use_pred {
            &ws.vel_pred[r]
        } else {
            &mc.velocity
        };
        let rigid = params.frame(r) == Frame::Rigid;
        let held_solid = params.held_solids.get(r) == Some(&true);
        for d in 0..D {
            // `held`: the average of the cell velocities, no pressure
            // acceleration (a rigid material's, a held solid's).
            let pass = |held: bool, out: &mut [f64]| {
                face_velocities(
                    layout,
                    d,
                    &mc.mass,
                    vel_in,
                    &mc.sp_vol,
                    &state.p_eq,
                    if held { 0.0 } else { fdt },
                    if held {
                        0.0
                    } else {
                        params.gravity[d] * dt / fdt
                    },
                    params.face_reconstruction,
                    if held || predictor_on {
                        0.0
                    } else {
                        params.face_smooth_factor * dt
                    },
                    if predictor_on && !held {
                        Some(FacePredictor {
                            tau: 0.5 * dt,
                            bulk: &ws.bulk[..],
                            velocity_convection: !params.lagrangian_remap,
                        })
                    } else {
                        None
                    },
                    match params.acoustic_jump {
                        Some(lambda) if !held => Some((lambda, &ws.sound[..])),
                        _ => None,
                    },
                    out,
                );
                zero_wall_faces(layout, bcs, d, out);
            };
            pass(rigid, &mut ws.ustar[r][d]);
            if held_solid {
                // Held where it fills both cells: computed into the θ flux
                // buffer, which `volume_fluxes` fills afterwards.
                pass(true, &mut ws.theta_flux[d]);
                let (out, held) = (&mut ws.ustar[r][d], &ws.theta_flux[d]);
                let s = layout.strides[d];
                for f in s..out.len() {
                    if hold.at(r, &mc.vol_frac, f - s, f) {
                        out[f] = held[f];
                    }
                }
            }
        }
    }
}

/// Step 5, explicit: `Δp = −Δt Σ_r ∇·(θu*)_r / Σ_r θ_r κ_r` (Guilkey
/// Eq. 29; the exact volume balance where the linearisation falls below
/// the admissible pressure, [`expanded_pressure`]) and the pressure of the
/// sources `p = p_eq + w Δp` (Eq. 30 with the weight of
/// [`IceParams::source_weight`]) into `ws.press` (interior), from the
/// volume fluxes of [`volume_fluxes`].
///
/// # Errors
/// [`IceError::NonPhysical`] for a non-finite or inadmissible pressure.
fn explicit_pressure<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt: f64,
) -> Result<(), IceError> {
    let layout = &state.layout;
    let p_min = min_pressure_all(state);
    let (div_sum, stk) = (&ws.div_sum, &ws.sum_theta_kappa);
    let press = Out::new(&mut ws.press);
    let st: &IceState<D> = state;
    try_rows(layout, |row| {
        for c in row {
            // Guilkey Eq. 29.
            let mut dp = -dt * div_sum[c] / stk[c];
            let mut p = st.p_eq[c] + dp;
            if p <= p_min && dp.is_finite() {
                // The linearised Eq. 29 overshoots below the admissible
                // range (a strong expansion, or a solid in tension on
                // its threshold EOS, Guilkey Fig. 1, whose κ grows as p
                // falls): solve the volume balance it linearises
                // exactly instead.
                if let Some(q) = expanded_pressure(st, c, dt * div_sum[c], p_min) {
                    p = q;
                    dp = q - st.p_eq[c];
                }
            }
            if !(p.is_finite() && p > p_min) {
                return Err(IceError::NonPhysical {
                    site: site(st, c, None),
                    quantity: "pressure",
                    value: p,
                });
            }
            let w = params.source_weight(dp, st.p_eq[c], || cell_shock_sensor(layout, &st.p_eq, c));
            // SAFETY: cell c is written by this task only.
            unsafe { press.set(c, st.p_eq[c] + w * dp) };
        }
        Ok(())
    })
}

/// Step 6: the face pressure `p*` normal to each direction (Guilkey
/// Eq. 31) into `ws.pstar`, plus the linear face viscosity `μ` at
/// compressive faces when on ([`face_viscosity`]).
fn face_pressures<const D: usize>(
    state: &IceState<D>,
    ws: &mut IceWorkspace<D>,
    viscosity: Option<f64>,
) {
    let layout = &state.layout;
    for d in 0..D {
        face_pressure(layout, d, &ws.press, &ws.mix_mass, &mut ws.pstar[d]);
        if let Some(mu) = viscosity {
            face_viscosity(
                layout,
                d,
                &state.cells,
                &ws.mix_mass,
                &ws.bulk,
                &state.p_eq,
                mu,
                &mut ws.pstar[d],
            );
        }
    }
}

/// Returns [`IceError::TimestepTooLarge`] when the face velocities would
/// take more than a cell's content out of a cell in `Δt`.
fn courant_check<const D: usize>(
    state: &IceState<D>,
    ustar: &[[Vec<f64>; D]],
    dt: f64,
) -> Result<(), IceError> {
    let layout = &state.layout;
    let nm = state.num_materials();
    let dt_h = layout.h.map(|h| dt / h);
    try_rows(layout, |row| {
        for c in row {
            for r in 0..nm {
                let mut courant = 0.0;
                for d in 0..D {
                    let s = layout.strides[d];
                    let (lo, hi) = (ustar[r][d][c], ustar[r][d][c + s]);
                    courant += (hi.max(0.0) - lo.min(0.0)) * dt_h[d];
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
        Ok(())
    })
}
