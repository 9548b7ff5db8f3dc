//! Semi-implicit (implicit-pressure) ICE: the pressure of Guilkey Eq. 29
//! solved implicitly, so that the sound speed no longer limits the time step
//! (the paper's conclusion asks for it; DESIGN.md "The implicit pressure").
//!
//! Unknown: the pressure increment `δp` per interior cell in an outer
//! iteration. With the total increment `Δp = Σ δp` the face velocities are
//!
//! ```text
//! u*_r,f(Δp) = E[ u*_r,f,pre − Δt_f v_r,f (Δp_R − Δp_L)/Δx ]
//! ```
//!
//! (`u*_pre` from Guilkey Eq. 28 before the face exchange, `v_r,f` its face
//! specific volume ([`super::faces::face_specific_volume`]), `Δt_f = face_dt_factor Δt`, `E`
//! the pointwise-implicit face momentum exchange), and the pressure
//! equation is Guilkey Eq. 29 multiplied by `V`,
//!
//! ```text
//! R_c(Δp) = V (Σ_r θ_r κ_r Δp_c + Δt Σ_r ∇·(θ u*)_r) = 0,   κ = v/c².
//! ```
//!
//! Its linearisation is the 5-/7-point matrix
//!
//! ```text
//! (M δp)_c = V Σ_r θ_r κ_r δp_c + Σ_f c_f (δp_c − δp_nb),
//! c_f = Δt Δt_f A/Δx Σ_r θ̂_r,f v̂_r,f,
//! ```
//!
//! with `θ̂` the upwind face volume fraction and `v̂ = E v` the face specific
//! volume after the face exchange (so stiff exchange gives the mixture
//! response instead of a plain harmonic mean). Walls, outflow (zero
//! gradient) and symmetry faces contribute nothing (Neumann); inflow faces
//! hold the ghost pressure (Dirichlet, `δp = 0` in the ghost); periodic
//! faces link the two sides. Each outer iteration: `M δp = −R`, `Δp += δp`,
//! face velocities corrected from their pre-exchange values, the face
//! exchange redone, `R` recomputed; converged when `max |R|/V` is below
//! [`SemiImplicit::outer_tolerance`]. The matrix is symmetric positive
//! definite; it is solved by sparse Cholesky with a reused symbolic
//! factorisation, multigrid-preconditioned CG or Jacobi-preconditioned CG
//! ([`LinearSolver`]).

use nalgebra::SVector;
use solvers::{KrylovOptions, SolverError};

use super::boundary::{fill_scalar, zero_wall_faces};
use super::equilibration::min_pressure_all;
use super::exchange::exchange_momentum_fixed;
use super::faces::{face_exchange, face_specific_volume};
use super::par::{max_rows, nan_max, par_face_rows, Out};
use super::params::{cell_shock_sensor, IceParams};
use super::pressure_system::{ImplicitWorkspace, PressureSystem};
use super::state::{CellLayout, IceState};
use super::volume_flux::volume_fluxes;
use super::workspace::IceWorkspace;
use super::{invalid, IceError, Site, MAX_MATERIALS};

pub use super::implicit_params::{pressure_mg_options, LinearSolver, SemiImplicit};
pub use super::pressure_system::ImplicitSlot;

/// Creates the semi-implicit buffers on first use and stores the
/// pre-exchange face velocities (`ws.ustar` right after Guilkey Eq. 28).
///
/// # Errors
/// [`IceError::InvalidInput`] when the pressure system cannot be built.
pub(super) fn save_pre_exchange<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    sp: &SemiImplicit,
    ws: &mut IceWorkspace<D>,
) -> Result<(), IceError> {
    let rebuild = match &ws.implicit.0 {
        Some(w) => w.solver != sp.linear_solver || w.dp.len() != state.layout.len(),
        None => true,
    };
    if rebuild {
        let n = state.layout.len();
        ws.implicit.0 = Some(Box::new(ImplicitWorkspace {
            solver: sp.linear_solver,
            system: PressureSystem::new(&state.layout, &params.boundaries, sp.linear_solver)?,
            ustar_pre: (0..state.num_materials())
                .map(|_| std::array::from_fn(|_| vec![0.0; n]))
                .collect(),
            dp: vec![0.0; n],
        }));
    }
    let iw = ws
        .implicit
        .0
        .as_mut()
        .ok_or_else(|| invalid("implicit", "workspace missing"))?;
    for (pre, cur) in iw.ustar_pre.iter_mut().zip(&ws.ustar) {
        for d in 0..D {
            pre[d].copy_from_slice(&cur[d]);
        }
    }
    Ok(())
}

/// The semi-implicit pressure (replaces Guilkey Eq. 29's explicit `Δp`):
/// outer iteration on `M δp = −R` (see the module documentation). On
/// return `ws.ustar` holds the corrected, exchanged face velocities, the
/// volume fluxes (`ws.mix_vflux`, `ws.div_sum`, `ws.kappa`,
/// `ws.sum_theta_kappa`) match them, and `ws.press = p_eq + w Δp`
/// (interior; Guilkey Eq. 30 with the pressure weight `w`). Returns
/// `(outer iterations, linear iterations)`.
///
/// # Errors
/// [`IceError::PressureSolve`]: singular matrix (not retryable); failed
/// linear solve, too many outer iterations, growing residual, non-physical
/// pressure (retryable with a smaller `Δt`).
pub(super) fn implicit_pressure<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    sp: &SemiImplicit,
    ws: &mut IceWorkspace<D>,
    dt: f64,
    fdt: f64,
) -> Result<(usize, usize), IceError> {
    let layout = &state.layout;
    let nm = state.num_materials();
    let k_on = params
        .exchange
        .as_ref()
        .filter(|e| nm > 1 && e.momentum.iter().any(|&k| k > 0.0));
    let mut iw = ws
        .implicit
        .0
        .take()
        .ok_or_else(|| invalid("implicit", "workspace missing"))?;
    let res = outer_iteration(
        state,
        params,
        sp,
        ws,
        &mut iw,
        dt,
        fdt,
        k_on.map(|e| &e.momentum[..]),
    );
    ws.implicit.0 = Some(iw);
    let (outer, linear, res_max) = res?;
    // Guilkey Eq. 30: p = p_eq + Δp (the sources use p_eq + w Δp).
    let p_min = min_pressure_all(state);
    let mut iw = ws
        .implicit
        .0
        .take()
        .ok_or_else(|| invalid("implicit", "workspace missing"))?;
    let mut finish = || -> Result<(), IceError> {
        for &c in &layout.interior {
            let mut p = state.p_eq[c] + iw.dp[c];
            if p <= p_min && p.is_finite() {
                // The linearised balance (κ at p_eq) overshoots below the
                // admissible range: a strong expansion, or a solid pulled into
                // tension on its threshold EOS (Guilkey Fig. 1), whose κ grows
                // without bound as p falls to 0 (two halves of a steel bar
                // separating at 2 m/s in air asked for −1.6 MPa at Δt = 1e-4 s
                // and halved Δt 166 times in 2 ms). As the explicit Eq. 29
                // does, the cell's volume balance is solved exactly instead.
                if let Some(q) =
                    super::equilibration::expanded_pressure(state, c, dt * ws.div_sum[c], p_min)
                {
                    p = q;
                    iw.dp[c] = q - state.p_eq[c];
                }
            }
            if !(p.is_finite() && p > p_min) {
                return Err(IceError::PressureSolve {
                    site: site_at(state, c),
                    reason: format!("non-physical pressure p = {p:e}"),
                    outer,
                    residual: res_max,
                    dt,
                    retryable: true,
                });
            }
            let w = params.source_weight(iw.dp[c], state.p_eq[c], || {
                cell_shock_sensor(layout, &state.p_eq, c)
            });
            ws.press[c] = state.p_eq[c] + w * iw.dp[c];
        }
        Ok(())
    };
    let r = finish();
    ws.implicit.0 = Some(iw);
    r?;
    Ok((outer, linear))
}

fn site_at<const D: usize>(state: &IceState<D>, c: usize) -> Site {
    super::site(state, c, None)
}

/// Largest `|R_c|/V = |Σθκ Δp_c + Δt Σ∇·(θu*)|` over the interior (exact
/// maximum, thread-count independent).
fn residual_max<const D: usize>(
    layout: &CellLayout<D>,
    ws: &IceWorkspace<D>,
    dp: &[f64],
    dt: f64,
) -> f64 {
    let (stk, div) = (&ws.sum_theta_kappa, &ws.div_sum);
    max_rows(layout, |row| {
        let mut m: f64 = 0.0;
        for c in row {
            // NaN propagates as the maximum (through `max_rows` too).
            m = nan_max(m, (stk[c] * dp[c] + dt * div[c]).abs());
        }
        m
    })
}

/// The cell of the largest residual (for error messages).
fn residual_argmax<const D: usize>(
    layout: &CellLayout<D>,
    ws: &IceWorkspace<D>,
    dp: &[f64],
    dt: f64,
) -> usize {
    let mut best = (layout.interior[0], -1.0);
    for &c in &layout.interior {
        let r = (ws.sum_theta_kappa[c] * dp[c] + dt * ws.div_sum[c]).abs();
        if r.is_nan() {
            return c;
        }
        if r > best.1 {
            best = (c, r);
        }
    }
    best.0
}

#[allow(clippy::too_many_arguments)]
fn outer_iteration<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    sp: &SemiImplicit,
    ws: &mut IceWorkspace<D>,
    iw: &mut ImplicitWorkspace<D>,
    dt: f64,
    fdt: f64,
    k_mom: Option<&[f64]>,
) -> Result<(usize, usize, f64), IceError> {
    let layout = &state.layout;
    let bcs = &params.boundaries;
    let vol = layout.cell_volume();
    let opts = KrylovOptions {
        rel_tol: sp.linear_tolerance,
        max_iter: sp.max_linear_iterations,
    };
    iw.dp.fill(0.0);
    let mut linear = 0usize;
    let mut prev = f64::INFINITY;
    let fail = |ws: &IceWorkspace<D>,
                dp: &[f64],
                outer: usize,
                res: f64,
                reason: String,
                retryable: bool| {
        IceError::PressureSolve {
            site: site_at(state, residual_argmax(layout, ws, dp, dt)),
            reason,
            outer,
            residual: res,
            dt,
            retryable,
        }
    };
    for outer in 0..=sp.max_outer_iterations {
        // Guilkey Eq. 29 residual with the current face velocities.
        volume_fluxes(state, params, ws, dt);
        let res = residual_max(layout, ws, &iw.dp, dt);
        if res <= sp.outer_tolerance {
            return Ok((outer, linear, res));
        }
        if let Some(reason) = outer_failure(sp, outer, res, prev) {
            return Err(fail(ws, &iw.dp, outer, res, reason, true));
        }
        prev = res;
        if outer == 0 {
            // The matrix, once per step.
            let r = assemble_matrix(state, ws, &mut iw.system, dt, fdt, k_mom, params);
            if let Err(e) = r {
                let retryable = !matches!(e, SolverError::Singular { .. });
                return Err(fail(
                    ws,
                    &iw.dp,
                    outer,
                    res,
                    format!("pressure matrix: {e}"),
                    retryable,
                ));
            }
        }
        // M δp = −R.
        for (b, &c) in iw.system.rhs.iter_mut().zip(&layout.interior) {
            *b = -vol * (ws.sum_theta_kappa[c] * iw.dp[c] + dt * ws.div_sum[c]);
        }
        match iw.system.solve(&opts) {
            Ok(rep) => linear += rep.iterations,
            Err(e) => {
                let retryable = !matches!(e, SolverError::Singular { .. });
                return Err(fail(
                    ws,
                    &iw.dp,
                    outer,
                    res,
                    format!("linear solve ({}): {e}", sp.linear_solver.name()),
                    retryable,
                ));
            }
        }
        for (&x, &c) in iw.system.x.iter().zip(&layout.interior) {
            iw.dp[c] += x;
        }
        // Ghosts of Δp: zero gradient at walls and outflow, periodic copy,
        // zero (Dirichlet) at inflow.
        fill_scalar(layout, bcs, &mut iw.dp, |_| 0.0);
        correct_face_velocities(state, params, ws, iw, dt, fdt, k_mom);
    }
    // The loop returns at `outer == max_outer_iterations` at the latest.
    Err(invalid(
        "implicit.max_outer_iterations",
        "outer iteration ended without a result",
    ))
}

/// Why the outer iteration must stop at iteration `outer` with residual
/// `res` (not converged; `prev` the previous residual): a non-finite
/// residual, the iteration cap, or a residual that grows from the third
/// iteration on. All are retryable with a smaller `Δt`.
fn outer_failure(sp: &SemiImplicit, outer: usize, res: f64, prev: f64) -> Option<String> {
    if !res.is_finite() {
        return Some("non-finite residual".into());
    }
    if outer == sp.max_outer_iterations {
        return Some(format!(
            "not converged in {} outer iterations",
            sp.max_outer_iterations
        ));
    }
    if outer >= 2 && res > prev {
        return Some(format!(
            "outer iteration diverges (residual {prev:e} → {res:e})"
        ));
    }
    None
}

/// Assembles the pressure matrix of the step (see the module
/// documentation): face coefficients `Δt Δt_f A/Δx Σ_r θ̂_r,f v̂_r,f` with
/// the upwind `θ̂` from the exchanged face velocities and `v̂ = E v` (the
/// face exchange with coefficients `k_mom` applied to the face specific
/// volumes), `V Σθκ` on the diagonal. A material held at a face
/// ([`super::params::HeldFaces`]: rigid, or a held solid it fills on both
/// sides) does not answer Δp there (`v = 0`) and the exchange holds it, as in
/// [`correct_face_velocities`] and `face_exchange`: the matrix is then the
/// Jacobian of the residual that the outer iteration reduces. (It was
/// not: with a cap of 20 outer iterations and free Δt growth, the
/// semi-implicit piston with its rigid steel halved its step 863 times in
/// 655 steps; now the outer iteration converges in one and 3 halvings
/// remain, outflow Courant numbers above 1 in the first two steps.)
fn assemble_matrix<const D: usize>(
    state: &IceState<D>,
    ws: &IceWorkspace<D>,
    system: &mut PressureSystem,
    dt: f64,
    fdt: f64,
    k_mom: Option<&[f64]>,
    params: &IceParams<D>,
) -> Result<(), SolverError> {
    let layout = &state.layout;
    let nm = state.num_materials();
    let vol = layout.cell_volume();
    let cells = &state.cells;
    let ustar = &ws.ustar;
    let stk = &ws.sum_theta_kappa;
    let interior = &layout.interior;
    let scale: [f64; D] = std::array::from_fn(|d| dt * fdt * vol / (layout.h[d] * layout.h[d]));
    let hold = params.held_faces();
    let any_held = hold.any();
    system.assemble(
        |f, d| {
            let l = f - layout.strides[d];
            let mut theta = [0.0; MAX_MATERIALS];
            let mut v = [0.0; MAX_MATERIALS];
            let mut w = [0.0; MAX_MATERIALS];
            let mut vv = [SVector::<f64, 1>::zeros(); MAX_MATERIALS];
            let mut held = [false; MAX_MATERIALS];
            for m in 0..nm {
                let mc = &cells[m];
                theta[m] = 0.5 * (mc.vol_frac[l] + mc.vol_frac[f]);
                v[m] = face_specific_volume(mc.mass[l], mc.sp_vol[l], mc.mass[f], mc.sp_vol[f]);
                w[m] = theta[m] / v[m];
                // A held material's face velocity does not answer Δp.
                held[m] = any_held && hold.at(m, &mc.vol_frac, l, f);
                vv[m][0] = if held[m] { 0.0 } else { v[m] };
            }
            // The exchange's held materials (none: the plain exchange).
            let fixed: &[bool] = if held[..nm].contains(&true) {
                &held[..nm]
            } else {
                &[]
            };
            if let Some(k) = k_mom {
                // ... and the exchange holds it (as `face_exchange` does).
                exchange_momentum_fixed(
                    k,
                    dt,
                    &theta[..nm],
                    &v[..nm],
                    &w[..nm],
                    fixed,
                    &mut vv[..nm],
                );
            }
            let mut sum = 0.0;
            for m in 0..nm {
                let mc = &cells[m];
                let u = ustar[m][d][f];
                let th = if u > 0.0 {
                    mc.vol_frac[l]
                } else if u < 0.0 {
                    mc.vol_frac[f]
                } else {
                    theta[m]
                };
                // A held material's pull leaves another `v − v β/(1 + β)`,
                // which rounds to −1 ulp once β passes 1e16 (a gas trace of
                // specific volume 1e5 m³/kg in a held solid's cell): not a
                // negative mobility.
                sum += th * vv[m][0].max(0.0);
            }
            scale[d] * sum
        },
        |k| vol * stk[interior[k]],
    )
}

/// Face velocities from their pre-exchange values with the accumulated
/// pressure increment, `u* = u*_pre − Δt_f v_f ∇Δp` (zero at walls; a
/// material held at a face, [`super::params::HeldFaces`], keeps its `u*_pre`
/// there), then the face exchange with coefficients `k_mom` again (held
/// materials held).
fn correct_face_velocities<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    iw: &ImplicitWorkspace<D>,
    dt: f64,
    fdt: f64,
    k_mom: Option<&[f64]>,
) {
    let layout = &state.layout;
    let bcs = &params.boundaries;
    let nm = state.num_materials();
    // A rigid material keeps its prescribed face velocity, a held solid its
    // held one where it fills both cells.
    let hold = params.held_faces();
    for r in 0..nm {
        let mc = &state.cells[r];
        for d in 0..D {
            let s = layout.strides[d];
            let inv_h = 1.0 / layout.h[d];
            let pre = &iw.ustar_pre[r][d];
            let dp = &iw.dp;
            let (sv, ms, th) = (&mc.sp_vol, &mc.mass, &mc.vol_frac);
            let out = Out::new(&mut ws.ustar[r][d]);
            par_face_rows(layout, d, |row| {
                for f in row {
                    let fdt = if hold.at(r, th, f - s, f) { 0.0 } else { fdt };
                    let vf = face_specific_volume(ms[f - s], sv[f - s], ms[f], sv[f]);
                    let u = pre[f] - fdt * vf * (dp[f] - dp[f - s]) * inv_h;
                    // SAFETY: each face is written by one task only.
                    unsafe { out.set(f, u) };
                }
            });
            zero_wall_faces(layout, bcs, d, &mut ws.ustar[r][d]);
        }
    }
    if let Some(k) = k_mom {
        for d in 0..D {
            face_exchange(layout, d, k, dt, &state.cells, params, &mut ws.ustar);
        }
    }
}
