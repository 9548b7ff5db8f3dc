//! The Lagrangian phase of the ICE step (Guilkey Sec. 3.3 steps 8–11),
//! per cell and all materials at once: momentum and energy sources
//! (Eqs. 33–34, [`super::sources`]), Lagrangian values (Eqs. 35–37), the
//! pointwise-implicit momentum and heat exchange (Eqs. 38–39,
//! [`super::exchange`]) and the specific-volume evolution (Eqs. 40–41,
//! [`super::specific_volume`]) ([`stage_lagrangian`]).

use nalgebra::SVector;

use super::exchange::{exchange_heat, exchange_momentum_fixed};
use super::par::{try_rows, Out};
use super::params::{EnergyForm, Frame, IceParams};
use super::sources::{
    cell_sources, conservative_energy, dissipation_share, eulerian_theta_kappa, share,
    LagrangianCell, LagrangianInputs,
};
use super::specific_volume::{lagrangian_volume, CellShare, MaterialShare};
use super::state::{CellLayout, IceState};
use super::workspace::IceWorkspace;
use super::{site, IceError, MAX_MATERIALS};
use crate::material::eos::EquationOfState;

/// Volume fraction above which a particle-borne material makes a cell (and
/// its face neighbours) use Guilkey Eq. 34's flow work instead of the
/// total-energy form.
const SOLID_FRACTION_FOR_FLOW_WORK: f64 = 1e-9;

/// Steps 8–11 (Guilkey Sec. 3.3): momentum and energy sources (Eqs. 33–34),
/// heat sources, Lagrangian values (Eqs. 35–37), the pointwise-implicit
/// exchange (Eqs. 38–39) and the specific-volume evolution (Eqs. 40–41),
/// after [`super::stage_pressure`]. The Lagrangian values are left in the
/// workspace ([`IceWorkspace::lagrangian_velocity`]).
///
/// `particle_velocity[r]`, for a material carried by particles
/// ([`Frame::Particles`] or [`Frame::Rigid`]), is its Lagrangian cell
/// velocity computed on the nodes (Guilkey Sec. 3.3: "the time advanced
/// solid material momentum is then aggregated at the cell centers for
/// momentum exchange"); its momentum source is not recomputed here. Empty
/// for fluid-only scenes.
///
/// # Errors
/// [`IceError::NonPhysical`] naming the cell.
pub fn stage_lagrangian<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt: f64,
    particle_velocity: &[Vec<SVector<f64, D>>],
) -> Result<(), IceError> {
    // The loops over a cell's materials unrolled for one and two
    // materials (Sod, 3 200 cells, one thread: the step from 79.5 to 75.9 ns
    // per cell), the scene's count otherwise.
    match state.num_materials() {
        1 => lagrangian_cells::<D, 1>(state, params, ws, dt, particle_velocity),
        2 => lagrangian_cells::<D, 2>(state, params, ws, dt, particle_velocity),
        _ => lagrangian_cells::<D, 0>(state, params, ws, dt, particle_velocity),
    }
}

/// [`stage_lagrangian`] with `N` materials (0: the scene's number).
fn lagrangian_cells<const D: usize, const N: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt: f64,
    particle_velocity: &[Vec<SVector<f64, D>>],
) -> Result<(), IceError> {
    let nm = state.num_materials();
    let layout = &state.layout;
    let exchange = params.exchange.as_ref().filter(|_| nm > 1);
    let k_on = exchange.filter(|e| e.momentum.iter().any(|&k| k > 0.0));
    let h_on = exchange.filter(|e| !e.heat_off());
    let conservative = params.energy == EnergyForm::Conservative;
    let (inp, out) = split_workspace::<D, N>(state, params, ws, dt, particle_velocity);
    let any_lagr = inp.lagr[..nm].iter().any(|&l| l);
    // Steps 8–11: sources (Guilkey Eqs. 33–34), Lagrangian values
    // (Eqs. 35–37), exchange (Eqs. 38–39) and specific volume (Eqs. 40–41,
    // Appendix Eq. 53), per cell and all materials at once.
    try_rows(layout, |row| {
        let mut cell = LagrangianCell::<D>::new();
        for c in row {
            // Cells a solid occupies, and their face neighbours, use
            // Guilkey Eq. 34 as written. In the total-energy form the
            // face work `p* θ_s u*_s` of the solid's volume flux goes
            // into the fluid's energy, but the solid does not pay for
            // it (its force is `−θ_s ∇p` on the nodes): in the solid's
            // own cells the fluid floor cannot absorb it, and in a
            // fluid cell beside the solid it is a steady source (the
            // held pressurised cylinder heated the air beside its
            // outer surface from 300 to 326 K by 8 ms and blew up at
            // 15 ms). Eq. 34 gives each material the work of its own
            // compression, `p κ_r θ_r Δp`. A burn's open product cell
            // ([`burn_cell_open`]) keeps the total-energy form.
            let cons =
                conservative && !(any_lagr && solid_near(&inp, c) && !burn_cell_open(&inp, c));
            let dke_src = cell_sources(&inp, c, cons, &mut cell);
            let stk_e = eulerian_theta_kappa(&inp, c, &cell);
            if cons {
                conservative_energy(&inp, c, stk_e, dke_src, &mut cell);
            }
            cell.fixed_work = 0.0;
            if let Some(ex) = k_on {
                momentum_exchange(&inp, &ex.momentum, cons, c, &mut cell);
            }
            let sum_tb = heat_exchange(&inp, h_on.map(|ex| &ex.heat[..]), &mut cell);
            store_cell(&inp, &out, c, h_on.map(|_| sum_tb), &cell)?;
        }
        Ok(())
    })
}

/// The inputs of the Lagrangian phase (the state, the parameters, the
/// pressure stage's results in the workspace and per-material constants)
/// and its outputs (the workspace's Lagrangian values).
fn split_workspace<'a, const D: usize, const N: usize>(
    state: &'a IceState<D>,
    params: &'a IceParams<D>,
    ws: &'a mut IceWorkspace<D>,
    dt: f64,
    particle_velocity: &'a [Vec<SVector<f64, D>>],
) -> (LagrangianInputs<'a, D, N>, LagrangianOut<'a, D>) {
    let nm = state.num_materials();
    let mu = params
        .viscosity
        .as_deref()
        .filter(|m| m.iter().any(|&x| x > 0.0));
    let mut cv = [0.0; MAX_MATERIALS];
    let mut lagr = [false; MAX_MATERIALS];
    let mut fixed = [false; MAX_MATERIALS];
    for r in 0..nm {
        cv[r] = state.materials[r].eos.specific_heat_cv();
        lagr[r] = params.frame(r) != Frame::Eulerian && !particle_velocity.is_empty();
        fixed[r] = params.frame(r) == Frame::Rigid;
    }
    let IceWorkspace {
        kappa,
        div_sum,
        sum_theta_kappa,
        press,
        pstar,
        mix_vflux,
        ke,
        vel_l,
        temp_l,
        e_l,
        v_l,
        fixed_work,
        ..
    } = ws;
    let any_fixed = fixed[..nm].iter().any(|&f| f);
    if any_fixed {
        // Sized once: a scene's rigid materials do not change.
        fixed_work.resize(state.layout.len(), 0.0);
    }
    let inp = LagrangianInputs {
        st: state,
        params,
        kappa,
        div_sum,
        stk: sum_theta_kappa,
        press,
        pstar,
        mix_vflux,
        particle_velocity,
        mu,
        cv,
        lagr,
        fixed,
        any_fixed,
        one_eulerian: lagr[..nm].iter().filter(|&&l| !l).count() == 1,
        n_dyn: nm,
        dt,
        vol: state.layout.cell_volume(),
        inv_h: state.layout.h.map(|h| 1.0 / h),
        t0: state.time,
        t1: state.time + dt,
    };
    let mut out = LagrangianOut::new(vel_l, temp_l, e_l, ke, v_l);
    if any_fixed {
        out.fixed_work = Out::new(fixed_work);
    }
    (inp, out)
}

/// Where the Lagrangian phase writes, per material: velocity, temperature,
/// internal energy `c_v T`, kinetic energy `|u|²/2` and specific volume.
struct LagrangianOut<'a, const D: usize> {
    vel: [Out<'a, SVector<f64, D>>; MAX_MATERIALS],
    temp: [Out<'a, f64>; MAX_MATERIALS],
    e: [Out<'a, f64>; MAX_MATERIALS],
    ke: [Out<'a, f64>; MAX_MATERIALS],
    v: [Out<'a, f64>; MAX_MATERIALS],
    /// Per cell, the exchange's work of a material held at its prescribed
    /// velocity (empty without one).
    fixed_work: Out<'a, f64>,
}

impl<'a, const D: usize> LagrangianOut<'a, D> {
    /// Writes into the workspace's per-material buffers.
    fn new(
        vel: &'a mut [Vec<SVector<f64, D>>],
        temp: &'a mut [Vec<f64>],
        e: &'a mut [Vec<f64>],
        ke: &'a mut [Vec<f64>],
        v: &'a mut [Vec<f64>],
    ) -> Self {
        let mut out = Self {
            vel: [Out::empty(); MAX_MATERIALS],
            temp: [Out::empty(); MAX_MATERIALS],
            e: [Out::empty(); MAX_MATERIALS],
            ke: [Out::empty(); MAX_MATERIALS],
            v: [Out::empty(); MAX_MATERIALS],
            fixed_work: Out::empty(),
        };
        for (o, a) in out.vel.iter_mut().zip(vel.iter_mut()) {
            *o = Out::new(a);
        }
        for (o, a) in out.temp.iter_mut().zip(temp.iter_mut()) {
            *o = Out::new(a);
        }
        for (o, a) in out.e.iter_mut().zip(e.iter_mut()) {
            *o = Out::new(a);
        }
        for (o, a) in out.ke.iter_mut().zip(ke.iter_mut()) {
            *o = Out::new(a);
        }
        for (o, a) in out.v.iter_mut().zip(v.iter_mut()) {
            *o = Out::new(a);
        }
        out
    }
}

/// Particle-borne volume fraction up to which a cell a burn feeds keeps the
/// total-energy form ([`burn_cell_open`]).
const SOLID_FRACTION_OF_OPEN_BURN_CELL: f64 = 0.5;

/// `true` in a cell a burn feeds or burns in
/// ([`IceParams::isothermal_exempt_cells`]), or a face neighbour of one,
/// that particle-borne materials
/// fill to at most [`SOLID_FRACTION_OF_OPEN_BURN_CELL`]: the product gas
/// beside a burning face. Its product arrives with the volume it takes
/// (`Δm v`) and pushes its neighbours; booked by Guilkey Eq. 34 at the cell
/// pressure against the neighbours' face work, that expansion lost 2–6 % of
/// the energy each step released where the product had to fit in its cell,
/// and at each cell's burn-out where it did not (`tests/reaction.rs`: the
/// very fast burn's balance −4.25e-2 with only the burning cells exempt
/// from the trace hold, −9.4e-4 with these cells in the total-energy form).
#[inline]
fn burn_cell_open<const D: usize, const N: usize>(
    inp: &LagrangianInputs<'_, D, N>,
    c: usize,
) -> bool {
    let fed = |k: usize| inp.params.isothermal_exempt_cells.get(k) == Some(&true);
    in_or_beside(&inp.st.layout, c, fed) && !solid_above(inp, c, SOLID_FRACTION_OF_OPEN_BURN_CELL)
}

/// `true` when `pred` holds in cell `c` or in one of its face neighbours.
#[inline]
fn in_or_beside<const D: usize>(
    layout: &CellLayout<D>,
    c: usize,
    pred: impl Fn(usize) -> bool,
) -> bool {
    pred(c) || (0..D).any(|d| pred(c - layout.strides[d]) || pred(c + layout.strides[d]))
}

/// `true` when a particle-borne material fills more than `fraction` of
/// cell `k`.
#[inline]
fn solid_above<const D: usize, const N: usize>(
    inp: &LagrangianInputs<'_, D, N>,
    k: usize,
    fraction: f64,
) -> bool {
    (0..inp.nm()).any(|r| inp.lagr[r] && inp.st.cells[r].vol_frac[k] > fraction)
}

/// `true` when a particle-borne material fills more than
/// [`SOLID_FRACTION_FOR_FLOW_WORK`] of cell `c` or of a face neighbour.
#[inline]
fn solid_near<const D: usize, const N: usize>(inp: &LagrangianInputs<'_, D, N>, c: usize) -> bool {
    in_or_beside(&inp.st.layout, c, |k| {
        solid_above(inp, k, SOLID_FRACTION_FOR_FLOW_WORK)
    })
}

/// The pointwise-implicit momentum exchange of cell `c` (Guilkey Eq. 38,
/// rigid materials held at their velocity); with `cons`, the kinetic
/// energy it dissipates (plus the work of a rigid material) becomes heat
/// of the Eulerian materials, shared by mass ([`dissipation_share`]).
// Called once per cell from one place: the body of the loop it came
// from before the stage split, kept inlined there.
#[inline(always)]
fn momentum_exchange<const D: usize, const N: usize>(
    inp: &LagrangianInputs<'_, D, N>,
    k: &[f64],
    cons: bool,
    _c: usize,
    cell: &mut LagrangianCell<D>,
) {
    let nm = inp.nm();
    let LagrangianCell {
        theta,
        v,
        mass,
        u,
        t,
        fixed_work,
        ..
    } = cell;
    let ke0: f64 = (0..nm).map(|r| 0.5 * mass[r] * u[r].norm_squared()).sum();
    let u0 = *u;
    exchange_momentum_fixed(
        k,
        inp.dt,
        &theta[..nm],
        &v[..nm],
        &mass[..nm],
        if inp.any_fixed { &inp.fixed[..nm] } else { &[] },
        &mut u[..nm],
    );
    // A material held at a prescribed velocity U does work U · (the
    // momentum the others gain) on the cell (the run's account books it
    // as put in from outside).
    if inp.any_fixed {
        if let Some(s) = (0..nm).find(|&s| inp.fixed[s]) {
            let gained: SVector<f64, D> = (0..nm)
                .filter(|&r| !inp.fixed[r])
                .map(|r| (u[r] - u0[r]) * mass[r])
                .sum();
            *fixed_work = u[s].dot(&gained);
        }
    }
    if cons {
        // The kinetic energy dissipated by the exchange
        // becomes heat: ke0 − ke1 plus the work of a held
        // material (½ m (U − u0)² ≥ 0 for one fluid locked to it).
        let ke1: f64 = (0..nm).map(|r| 0.5 * mass[r] * u[r].norm_squared()).sum();
        // Shared by mass (`dissipation_share`), like the dissipation
        // of the total-energy form.
        let heat = ke0 - ke1 + *fixed_work;
        for r in 0..nm {
            if inp.lagr[r] {
                continue;
            }
            t[r] += dissipation_share(inp, mass, r) * heat / (mass[r] * inp.cv[r]);
        }
    }
}

/// The pointwise-implicit heat exchange of the cell (Guilkey Eq. 39) with
/// coefficients `h` (`None`: off). Keeps the temperatures before it and
/// the thermal expansivities `β` there (with the exchange only), and returns `Σ_s θ_s β_s Ṫ_s`
/// (Eq. 40; 0 without heat exchange).
// Called once per cell from one place: the body of the loop it came
// from before the stage split, kept inlined there.
#[inline(always)]
fn heat_exchange<const D: usize, const N: usize>(
    inp: &LagrangianInputs<'_, D, N>,
    h: Option<&[f64]>,
    cell: &mut LagrangianCell<D>,
) -> f64 {
    let nm = inp.nm();
    let dt = inp.dt;
    let mut sum_tb = 0.0;
    if let Some(h) = h {
        // Only here: the temperatures before the exchange are read only with
        // it (`MaterialShare::temp_before` with `sum_tb`). Copied without it,
        // the wide loads of `t` just after its scalar stores stall on store
        // forwarding: 19 % of this stage in a 1D Sod step (perf annotate).
        cell.t_before = cell.t;
        exchange_heat(
            h,
            dt,
            &cell.theta[..nm],
            &cell.v[..nm],
            &inp.cv[..nm],
            &cell.mass[..nm],
            &mut cell.t[..nm],
        );
        for r in 0..nm {
            let eos = &inp.st.materials[r].eos;
            cell.beta[r] = eos.thermal_expansivity(1.0 / cell.v[r], cell.t_before[r]);
            sum_tb += cell.theta[r] * cell.beta[r] * (cell.t[r] - cell.t_before[r]) / dt;
        }
    }
    sum_tb
}

/// Writes the Lagrangian values of cell `c` (Guilkey Eqs. 35–41): velocity,
/// temperature, energies and, for the Eulerian materials, the evolved
/// specific volume (`sum_tb`: the heat exchange's `Σ θ β Ṫ`, `None` without
/// it). The cell values of a particle-borne material are rebuilt from the
/// particles next step; its specific volume is kept.
///
/// # Errors
/// [`IceError::NonPhysical`] for a non-positive temperature or specific
/// volume of an Eulerian material.
// Called once per cell from one place: the body of the loop it came
// from before the stage split, kept inlined there.
#[inline(always)]
fn store_cell<const D: usize, const N: usize>(
    inp: &LagrangianInputs<'_, D, N>,
    out: &LagrangianOut<'_, D>,
    c: usize,
    sum_tb: Option<f64>,
    cell: &LagrangianCell<D>,
) -> Result<(), IceError> {
    let st = inp.st;
    let LagrangianCell { u, t, v, .. } = cell;
    if inp.any_fixed {
        // SAFETY: cell c is written by this task only.
        unsafe { out.fixed_work.set(c, cell.fixed_work) };
    }
    for r in 0..inp.nm() {
        let cv = inp.cv[r];
        if inp.lagr[r] {
            // The cell values of a particle-borne material are
            // rebuilt from the particles next step.
            // SAFETY: cell c is written by this task only.
            unsafe {
                out.vel[r].set(c, u[r]);
                out.temp[r].set(c, t[r]);
                out.e[r].set(c, cv * t[r]);
                out.ke[r].set(c, 0.5 * u[r].norm_squared());
                out.v[r].set(c, v[r]);
            }
            continue;
        }
        if !(t[r].is_finite() && t[r] > 0.0) {
            return Err(IceError::NonPhysical {
                site: site(st, c, Some(r)),
                quantity: "Lagrangian temperature",
                value: t[r],
            });
        }
        let share = MaterialShare {
            mass: cell.mass[r],
            sp_vol: v[r],
            theta: cell.theta[r],
            f_theta: share(cell.theta[r] * inp.kappa[r][c], inp.stk[c], inp.nm() == 1),
            temp: t[r],
            temp_before: cell.t_before[r],
            beta: cell.beta[r],
        };
        let totals = CellShare {
            div_sum: inp.div_sum[c],
            sum_tb,
            press: inp.press[c],
            dt: inp.dt,
            vol: inp.vol,
        };
        let mv = lagrangian_volume(&st.materials[r].eos, &share, &totals);
        if !(mv.is_finite() && mv > 0.0) {
            return Err(IceError::NonPhysical {
                site: site(st, c, Some(r)),
                quantity: "specific volume",
                value: mv / cell.mass[r],
            });
        }
        // SAFETY: cell c is written by this task only.
        unsafe {
            out.vel[r].set(c, u[r]);
            out.temp[r].set(c, t[r]);
            out.e[r].set(c, cv * t[r]);
            out.ke[r].set(c, 0.5 * u[r].norm_squared());
            out.v[r].set(c, mv * cell.inv_m[r]);
        }
    }
    Ok(())
}
