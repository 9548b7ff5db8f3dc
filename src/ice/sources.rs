//! Momentum and energy sources of the Lagrangian phase, per cell (Guilkey
//! Sec. 3.3 step 8): the pressure force, gravity and the viscous force of
//! Guilkey Eq. 33, the flow work of Eq. 34 (as written, or in the
//! total-energy-conservative form of [`super::EnergyForm::Conservative`]),
//! the viscous heating, and the internal-energy sources
//! ([`super::HeatSource`]). The values they produce per material of a cell
//! (`LagrangianCell`) go on to the exchange and the specific-volume
//! evolution ([`super::lagrangian`]).

use nalgebra::SVector;

use super::params::IceParams;
use super::state::{CellLayout, IceState};
use super::MAX_MATERIALS;
use crate::material::eos::{EquationOfState, FluidEos};

/// What the Lagrangian phase reads in every cell: the state, the
/// parameters, the pressure stage's results (volume fluxes, pressures) and
/// per-material constants.
///
/// `N` is the number of materials when it is fixed at compile time (1 or
/// 2: the loops over the materials of a cell unroll; Sod in 1D went from
/// 79.5 to 75.9 ns per cell-step), 0 for the scene's number read at run
/// time ([`Self::nm`]).
pub(super) struct LagrangianInputs<'a, const D: usize, const N: usize> {
    /// The state at the start of the step (equilibrated).
    pub(super) st: &'a IceState<D>,
    /// The step's parameters.
    pub(super) params: &'a IceParams<D>,
    /// `κ_r` per material and cell (Guilkey Eq. 29).
    pub(super) kappa: &'a [Vec<f64>],
    /// `Σ_r ∇·(θu*)_r` per cell.
    pub(super) div_sum: &'a [f64],
    /// `Σ_r θ_r κ_r` per cell.
    pub(super) stk: &'a [f64],
    /// The pressure of the sources, `p_eq + w Δp` (Guilkey Eq. 30).
    pub(super) press: &'a [f64],
    /// Face pressures per direction (Guilkey Eq. 31).
    pub(super) pstar: &'a [Vec<f64>; D],
    /// Mixture volume fluxes per direction (`Δt A/V Σ_s θ_s,f u*_s,f`).
    pub(super) mix_vflux: &'a [Vec<f64>; D],
    /// Lagrangian cell velocities of the particle-borne materials.
    pub(super) particle_velocity: &'a [Vec<SVector<f64, D>>],
    /// Dynamic viscosity per material, `None` when all are zero.
    pub(super) mu: Option<&'a [f64]>,
    /// `c_v` per material.
    pub(super) cv: [f64; MAX_MATERIALS],
    /// `true` per particle-borne material (with particle velocities).
    pub(super) lagr: [bool; MAX_MATERIALS],
    /// `true` per rigid material (velocity held in the exchange).
    pub(super) fixed: [bool; MAX_MATERIALS],
    /// `true` when any material is rigid.
    pub(super) any_fixed: bool,
    /// `true` when exactly one material is Eulerian (not particle-borne):
    /// its shares of the cell's flow work and dissipation are 1.
    pub(super) one_eulerian: bool,
    /// Number of materials (read through [`Self::nm`]).
    pub(super) n_dyn: usize,
    /// Time step.
    pub(super) dt: f64,
    /// Cell volume.
    pub(super) vol: f64,
    /// Reciprocal cell sizes `1/h_d`.
    pub(super) inv_h: SVector<f64, D>,
    /// Start and end of the step (heat source windows).
    pub(super) t0: f64,
    /// End of the step.
    pub(super) t1: f64,
}

impl<const D: usize, const N: usize> LagrangianInputs<'_, D, N> {
    /// Number of materials: `N`, or the scene's when `N = 0`.
    #[inline(always)]
    pub(super) fn nm(&self) -> usize {
        if N == 0 {
            self.n_dyn
        } else {
            N
        }
    }
}

/// Per material of one cell: the values the Lagrangian phase builds up
/// (stack arrays of [`MAX_MATERIALS`], first `nm` entries used).
pub(super) struct LagrangianCell<const D: usize> {
    /// Volume fraction `θ_r`.
    pub(super) theta: [f64; MAX_MATERIALS],
    /// Specific volume `v_r` (Guilkey Eq. 13).
    pub(super) v: [f64; MAX_MATERIALS],
    /// Mass `M_r`.
    pub(super) mass: [f64; MAX_MATERIALS],
    /// Lagrangian velocity (Eqs. 35, 38).
    pub(super) u: [SVector<f64, D>; MAX_MATERIALS],
    /// Lagrangian temperature (Eqs. 37, 39).
    pub(super) t: [f64; MAX_MATERIALS],
    /// Temperature before the heat exchange.
    pub(super) t_before: [f64; MAX_MATERIALS],
    /// Thermal expansivity `β_r` at `t_before` (with heat exchange).
    pub(super) beta: [f64; MAX_MATERIALS],
    /// Viscous heating `Δt V θ τ:∇u`.
    pub(super) heat: [f64; MAX_MATERIALS],
    /// `1/M_r` (Eulerian materials).
    pub(super) inv_m: [f64; MAX_MATERIALS],
    /// The work a material held at its prescribed velocity `U` does on the
    /// others in the exchange, `U · (the momentum they gain)`.
    pub(super) fixed_work: f64,
}

impl<const D: usize> LagrangianCell<D> {
    /// All zero.
    pub(super) fn new() -> Self {
        Self {
            theta: [0.0; MAX_MATERIALS],
            v: [0.0; MAX_MATERIALS],
            mass: [0.0; MAX_MATERIALS],
            u: [SVector::<f64, D>::zeros(); MAX_MATERIALS],
            t: [0.0; MAX_MATERIALS],
            t_before: [0.0; MAX_MATERIALS],
            beta: [0.0; MAX_MATERIALS],
            heat: [0.0; MAX_MATERIALS],
            inv_m: [0.0; MAX_MATERIALS],
            fixed_work: 0.0,
        }
    }
}

/// The face pressure gradient `∇p*` of cell `c` (Guilkey Eq. 33), `inv_h`
/// the reciprocal cell sizes.
#[inline]
fn pressure_gradient<const D: usize>(
    layout: &CellLayout<D>,
    inv_h: &SVector<f64, D>,
    pstar: &[Vec<f64>; D],
    c: usize,
) -> SVector<f64, D> {
    let mut grad = SVector::<f64, D>::zeros();
    for d in 0..D {
        grad[d] = (pstar[d][c + layout.strides[d]] - pstar[d][c]) * inv_h[d];
    }
    grad
}

/// The sources of every material in cell `c` (Guilkey Eqs. 33–34): fills
/// `θ`, `v`, `M`, the Lagrangian velocity and temperature (Eq. 34 as
/// written unless `cons`; with `cons` the flow work is added later by
/// [`conservative_energy`]) and the viscous heating. A particle-borne
/// material takes its Lagrangian velocity from the nodes, where its
/// sources were applied (Guilkey Sec. 3.3 step 8). Returns the kinetic
/// energy change of the pressure force, `Σ_r [½ M_r (|u_p|² − |u|²) − Δt
/// M_r g·(u + u_p)/2]`: the whole change less gravity's work along the
/// step's mean velocity. Gravity's work goes to the total energy, not out
/// of the internal energy (before, a uniform gas falling freely in a
/// periodic box cooled by `g²t²/(2c_v)`: T 1 → 0.8 at g = 10, t = 0.1).
// Called once per cell from one place: the body of the loop it came
// from before the stage split, kept inlined there.
#[inline(always)]
pub(super) fn cell_sources<const D: usize, const N: usize>(
    inp: &LagrangianInputs<'_, D, N>,
    c: usize,
    cons: bool,
    cell: &mut LagrangianCell<D>,
) -> f64 {
    let st = inp.st;
    let layout = &st.layout;
    let (dt, vol) = (inp.dt, inp.vol);
    let grad = pressure_gradient(layout, &inp.inv_h, inp.pstar, c);
    let gravity = inp.params.gravity.iter().any(|&g| g != 0.0);
    let mut dke_src = 0.0;
    for r in 0..inp.nm() {
        let mc = &st.cells[r];
        cell.theta[r] = mc.vol_frac[c];
        cell.v[r] = mc.sp_vol[c];
        let m = mc.mass[c];
        cell.mass[r] = m;
        if inp.lagr[r] {
            // Particle-borne: the sources were applied on the
            // nodes (Guilkey Sec. 3.3 step 8).
            cell.u[r] = inp.particle_velocity[r][c];
            cell.t[r] = mc.temperature[c];
            cell.heat[r] = 0.0;
            continue;
        }
        // Guilkey Eq. 33: Δ(mu) = −Δt V θ ∇p* + Δt M g
        // (+ Δt V ∇·(θ τ) with viscosity).
        let mut mom =
            mc.velocity[c] * m - grad * (dt * vol * cell.theta[r]) + inp.params.gravity * (dt * m);
        // One division per material and cell: divisions are much of the
        // step's cost (taking 13 of them out of each cell's step took
        // Sod, 3 200 cells, one thread, from 62.7 to 58.2 ns per cell-step).
        let inv_m = 1.0 / m;
        cell.inv_m[r] = inv_m;
        let u_p = mom * inv_m;
        // Gravity's work m g·ū Δt (ū the step's mean velocity) is the
        // part of the kinetic energy change that the body force pays for.
        let u0 = mc.velocity[c];
        dke_src += 0.5 * m * (u_p.norm_squared() - u0.norm_squared());
        if gravity {
            dke_src -= 0.5 * dt * m * inp.params.gravity.dot(&(u0 + u_p));
        }
        cell.heat[r] = 0.0;
        if let Some(mu) = inp.mu {
            if mu[r] > 0.0 {
                let (force, q) = viscous_source(layout, st, r, mu[r], c);
                mom += force * (dt * vol);
                cell.heat[r] = q * dt * vol;
            }
        }
        cell.u[r] = mom * inv_m;
        let cv = inp.cv[r];
        let me = m * cv * mc.temperature[c];
        cell.t[r] = if cons {
            // `M c_v T/(M c_v)`: the flow work comes later.
            mc.temperature[c]
        } else if isothermal_in(inp, cell, r, c) {
            (me + cell.heat[r]) / (m * cv)
        } else {
            // Guilkey Eq. 34: Δ(me) = −Δt V f^θ p Σ_s ∇·(θu*)_s.
            let f_theta = share(cell.theta[r] * inp.kappa[r][c], inp.stk[c], inp.nm() == 1);
            (me - dt * vol * f_theta * inp.press[c] * inp.div_sum[c] + cell.heat[r]) / (m * cv)
        };
        add_heat_sources(inp, c, r, cell);
    }
    dke_src
}

/// Whether material `r` of cell `c` is a minor material of a mixed cell,
/// volume fraction below [`IceParams::isothermal_fraction`]: its flow work
/// is left out of the Lagrangian phase, so that its temperature changes
/// only by exchange, heating and advection (the rest of the cell's energy
/// balance goes to the other materials by mass in the total-energy form).
///
/// The equilibration (Guilkey Eq. 13) re-partitions a cell's volume at
/// fixed temperatures, i.e. without work. A minor gas in a cell full of a
/// stiffer material (air at θ = 1e-15…1e-3 inside a steel block, or in
/// water) takes that material's volume noise — node-mass noise of a
/// moving block, stress waves — in proportion to its compressibility:
/// order-one compressions and expansions every step (`Δv/v ≈ (K/γp) ∇·u
/// Δt`). The Lagrangian phase charged them `−p Δv` and the equilibration
/// undid them without work, a ratchet: the air inside a block moving at
/// 100 m/s reached 1.4e5 K in 0.08 ms, its sound speed cut Δt 60-fold and
/// an expansion then drove it below 0 K; the air trace in the water of the
/// ratio-1e4 water–air tube reached 1e5 K and took 1404 steps where the
/// water needs about 530. Holding such a material isothermal makes both
/// halves of its volume change alike (no work). Its heat capacity is a
/// negligible part of the cell's, so the cell's energy is unchanged to
/// that order. Single-material cells (θ = 1) are never affected.
#[inline]
pub(super) fn isothermal_in<const D: usize, const N: usize>(
    inp: &LagrangianInputs<'_, D, N>,
    cell: &LagrangianCell<D>,
    r: usize,
    c: usize,
) -> bool {
    let params = inp.params;
    let exempt = params.isothermal_exempt.get(r) == Some(&true)
        && params.isothermal_exempt_cells.get(c) == Some(&true);
    inp.nm() > 1 && cell.theta[r] < params.isothermal_fraction && !exempt
}

/// Heat sources: internal energy added to material `r` of cell `c` at a
/// rate per unit volume over a time window (the part of the step inside
/// it).
#[inline]
fn add_heat_sources<const D: usize, const N: usize>(
    inp: &LagrangianInputs<'_, D, N>,
    c: usize,
    r: usize,
    cell: &mut LagrangianCell<D>,
) {
    let (m, cv) = (cell.mass[r], inp.cv[r]);
    for src in inp.params.heat_sources.iter().filter(|s| s.material == r) {
        let overlap = (inp.t1.min(src.end) - inp.t0.max(src.start)).max(0.0);
        if overlap > 0.0 {
            // Per unit volume of the material (θ_r V), so a
            // cell the material barely fills is not
            // overheated.
            cell.t[r] += src.power[c] * cell.theta[r] * inp.vol * overlap / (m * cv);
        }
    }
}

/// `Σ_r θ_r κ_r` over the materials that receive the flux work and the
/// exchange heat (the Eulerian ones) in cell `c`: the denominator of their
/// `f_θ`.
#[inline]
pub(super) fn eulerian_theta_kappa<const D: usize, const N: usize>(
    inp: &LagrangianInputs<'_, D, N>,
    c: usize,
    cell: &LagrangianCell<D>,
) -> f64 {
    let mut stk_e = 0.0;
    for r in 0..inp.nm() {
        if !inp.lagr[r] {
            stk_e += cell.theta[r] * inp.kappa[r][c];
        }
    }
    stk_e
}

/// Conservative Guilkey Eq. 34 in cell `c`: `Δ(mE) = −Δt Σ_f A p*_f Σ_s
/// θ_s,f u*_s,f`, whose internal part `Δ(mE) − dke_src` (plus the viscous
/// heating) goes to the Eulerian materials in two pieces:
///
/// * each material's flow work `W_r` of its own volume change, the share
///   `f_θ = θ κ/stk_e` of the cell's (Guilkey Eq. 40), along the
///   material's own path ([`flow_work`]; Eq. 34's `−p Δ(θ_r V)` to first
///   order); and
/// * the rest, `Δ(mE) − dke_src − Σ_r W_r` (the dissipation of the
///   discrete kinetic energy: shock heating, and of either sign where the
///   face work and the cell-centred kinetic energy disagree), shared by
///   mass ([`dissipation_share`]).
///
/// With one material the sum is the cell's `Δ(mE) − dke_src`: the
/// total-energy form is unchanged. Sharing the rest by `f_θ` as well
/// treated it as compression work: a gas trace in a liquid cell has `κ v`
/// about 1300 times the liquid's (air at 1e7 Pa in water), so it took 1300
/// times the liquid's specific share of any kinetic-energy residual, and a
/// residual of −560 J/kg in the water (0.06 % of its energy) drove the air
/// trace to −680 K (water–air shock tube, step 10).
#[inline]
pub(super) fn conservative_energy<const D: usize, const N: usize>(
    inp: &LagrangianInputs<'_, D, N>,
    c: usize,
    stk_e: f64,
    dke_src: f64,
    cell: &mut LagrangianCell<D>,
) {
    let layout = &inp.st.layout;
    // The stored fluxes carry Δt A / V.
    let mut de = 0.0;
    for d in 0..D {
        let f_hi = c + layout.strides[d];
        de += inp.pstar[d][c] * inp.mix_vflux[d][c] - inp.pstar[d][f_hi] * inp.mix_vflux[d][f_hi];
    }
    de *= inp.vol;
    // The cell's volume change (Guilkey Eq. 29's Δt V Σ ∇·(θu*)).
    let dvol = inp.dt * inp.vol * inp.div_sum[c];
    let mut dt_work = [0.0; MAX_MATERIALS];
    let mut rest = de - dke_src;
    // With one Eulerian material its flow work and the rest both go to it:
    // its temperature change is `(Δ(mE) − dke_src + heat)/(M c_v)` however
    // the two are split (the split shares the energy between materials), so
    // the flow work is not computed. (It changes the result by round-off:
    // `w + (rest − M c_v w)/(M c_v)` against `rest/(M c_v)`.) It was three
    // divisions and two EOS calls on the dependency chain of every cell.
    let n_split = if inp.one_eulerian { 0 } else { inp.nm() };
    for r in 0..n_split {
        if inp.lagr[r] {
            continue;
        }
        if isothermal_in(inp, cell, r, c) {
            continue;
        }
        let f_theta = cell.theta[r] * inp.kappa[r][c] / stk_e;
        let (m, cv) = (cell.mass[r], inp.cv[r]);
        dt_work[r] = flow_work(
            &inp.st.materials[r].eos,
            cell.v[r],
            f_theta * dvol / m,
            cell.t[r],
            inp.press[c],
            cv,
        );
        rest -= m * cv * dt_work[r];
    }
    for r in 0..inp.nm() {
        if inp.lagr[r] {
            continue;
        }
        let f_mass = dissipation_share(inp, &cell.mass, r);
        cell.t[r] += dt_work[r] + (f_mass * rest + cell.heat[r]) / (cell.mass[r] * inp.cv[r]);
    }
}

/// The temperature change of a material's flow work over the step: its
/// specific volume goes from `v0` to `v0 + dv` (Guilkey Eq. 40's share)
/// from temperature `t0` (`c_v` = `cv`); `p` is the cell pressure of
/// Guilkey Eq. 30.
///
/// The work along the material's own path, by the trapezoidal rule with
/// the material's pressure `p_r` at both ends,
///
/// ```text
/// c_v (T1 − t0) = −½ (p_r(v0, t0) + p_r(v1, T1)) dv,
/// T1 − t0 = −dv (p_r(v0, t0) + p_r(v1, t0)) / (2 c_v + dv (∂p/∂T)_ρ(v1, t0)),
/// ```
///
/// (`p_r` linear in `T` at fixed `ρ`: exact for every fluid EOS here).
/// Eq. 34's `−p dv` with the cell pressure is its linearisation for small
/// `dv/v0`. Two things need the material's own path: a gas trace in a
/// liquid cell takes the liquid's volume change in proportion to its
/// compressibility (`f_θ`), so it can be driven to the gas's lowest
/// pressure and grow by orders of magnitude in one step (water expanding
/// below 0 Pa in a rarefaction while `p_∞ = 6e8` makes its pressure 1e-4 of
/// its stiffness), where `−p dv` took more energy than it had (air trace
/// at −312 K, water–air shock tube at ratio 10, step 98); and a trace
/// compressed and expanded by the liquid's pressure noise should come
/// back to its temperature (with backward Euler in expansion and `−p dv`
/// in compression the air trace in the water of the ratio-1e4 tube reached
/// 2.4e5 K and 1887 steps; with the trapezoid 1e5 K and 1404 steps; what
/// heats it to that is not found yet).
///
/// Where the trapezoid cannot hold the temperature positive (an ideal gas
/// expanding by more than `2/(γ − 1)` times its volume in one step, or
/// compressed to less than `1/(1 + 2/(γ − 1))` of it), the one-sided rule
/// that can: backward Euler `c_v ΔT = −p_r(v1, T1) dv` in expansion (an
/// ideal gas ends at `t0/(1 + (γ − 1) dv/v1) > 0`), forward `−p dv` in
/// compression (heating).
///
/// The cell's total energy does not depend on it ([`conservative_energy`]
/// books the difference to the cell's flow work as dissipation).
#[inline]
pub(super) fn flow_work(eos: &FluidEos, v0: f64, dv: f64, t0: f64, p: f64, cv: f64) -> f64 {
    let rho1 = 1.0 / (v0 + dv);
    let (p0, p1) = (eos.pressure(1.0 / v0, t0), eos.pressure(rho1, t0));
    let dpdt = eos.dp_dt(rho1, t0);
    let den = 2.0 * cv + dv * dpdt;
    let trapezoid = -dv * (p0 + p1) / den;
    if den > 0.0 && trapezoid.is_finite() && t0 + trapezoid > 0.0 {
        return trapezoid;
    }
    if dv > 0.0 {
        let backward = -dv * p1 / (cv + dv * dpdt);
        if backward.is_finite() {
            return backward;
        }
    }
    -p * dv / cv
}

/// `part / total`, a material's share of a sum over the cell's materials;
/// `whole` says that the sum has this one term (`total == part`), and then
/// the share is exactly 1 for a positive finite `part` (as the division
/// gives) without the division, which sat on the Lagrangian phase's
/// dependency chain in every single-fluid cell.
#[inline]
pub(super) fn share(part: f64, total: f64, whole: bool) -> f64 {
    if whole && part > 0.0 && part.is_finite() {
        1.0
    } else {
        part / total
    }
}

/// The share of Eulerian material `r` (masses `mass`) of a cell's dissipated energy
/// (the kinetic-energy residual of [`conservative_energy`], the kinetic
/// energy the momentum exchange removes): its mass over the Eulerian
/// materials' mass, so that each kilogram is heated alike. (A share by
/// `f_θ = θ κ/Σ θ κ` heats a gas trace in a liquid per kilogram about
/// `(κ v)_gas/(κ v)_liquid` times as much as the liquid, see
/// [`conservative_energy`].)
#[inline]
pub(super) fn dissipation_share<const D: usize, const N: usize>(
    inp: &LagrangianInputs<'_, D, N>,
    mass: &[f64; MAX_MATERIALS],
    r: usize,
) -> f64 {
    if inp.one_eulerian {
        // `m/m`, without the division (`total > 0` below is `m > 0`).
        return if mass[r] > 0.0 { 1.0 } else { 0.0 };
    }
    let mut total = 0.0;
    for s in 0..inp.nm() {
        if !inp.lagr[s] {
            total += mass[s];
        }
    }
    if total > 0.0 {
        mass[r] / total
    } else {
        0.0
    }
}

/// Viscous momentum source `∇·(θ τ)` per unit volume of material `r` in
/// cell `c` and the viscous heating `θ τ:∇u` per unit volume, for the
/// Newtonian stress `τ = μ (∇u + ∇uᵀ − ⅔ (∇·u) I)` (the deviatoric stress
/// of Guilkey Eq. 33's `σ_r − σ` term and Eq. 9's heating). The traction
/// on a face normal to `d` uses the compact normal derivative `(u_R −
/// u_L)/h_d` and the mean of the two cells' central tangential derivatives,
/// `θ_f = (θ_L + θ_R)/2`; the divergence is the difference of the face
/// tractions. Needs the velocity ghosts including corners.
#[inline]
fn viscous_source<const D: usize>(
    layout: &CellLayout<D>,
    st: &IceState<D>,
    r: usize,
    mu: f64,
    c: usize,
) -> (SVector<f64, D>, f64) {
    let mc = &st.cells[r];
    let u = &mc.velocity;
    // Central gradient G[(i, e)] = ∂u_i/∂x_e at a cell.
    let grad = |k: usize| {
        nalgebra::SMatrix::<f64, D, D>::from_fn(|i, e| {
            let s = layout.strides[e];
            (u[k + s][i] - u[k - s][i]) / (2.0 * layout.h[e])
        })
    };
    let traction = |l: usize, rr: usize, d: usize| {
        let (gl, gr) = (grad(l), grad(rr));
        let mut g = (gl + gr) * 0.5;
        for i in 0..D {
            g[(i, d)] = (u[rr][i] - u[l][i]) / layout.h[d];
        }
        let div = g.trace();
        let theta_f = 0.5 * (mc.vol_frac[l] + mc.vol_frac[rr]);
        // Row d of τ (τ is symmetric): τ_{d i} = μ (∂u_d/∂x_i + ∂u_i/∂x_d) − ⅔ μ div δ_di.
        SVector::<f64, D>::from_fn(|i, _| {
            let mut t = mu * (g[(d, i)] + g[(i, d)]);
            if i == d {
                t -= 2.0 / 3.0 * mu * div;
            }
            theta_f * t
        })
    };
    let mut force = SVector::<f64, D>::zeros();
    for d in 0..D {
        let s = layout.strides[d];
        force += (traction(c, c + s, d) - traction(c - s, c, d)) / layout.h[d];
    }
    let g = grad(c);
    let sym = g + g.transpose();
    let div = g.trace();
    let heat = mc.vol_frac[c] * mu * (0.5 * sym.norm_squared() - 2.0 / 3.0 * div * div);
    (force, heat.max(0.0))
}
