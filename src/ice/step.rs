//! One explicit ICE step for a fluid-only scene (Guilkey Sec. 3.3 steps 2,
//! 3, 5, 6, 8–12), the time step estimate, and a small driver.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use nalgebra::SVector;
use rayon::prelude::*;

use super::advection::{
    material_fluxes, net_inflow, net_inflow_vec, scalar_fluxes, AdvectedFields, Advection,
    AdvectionFluxes, Limiter,
};
use super::boundary::{fill_scalar, fill_vector, zero_wall_faces, Boundaries, IceBoundary};
use super::equilibration::{equilibrate_cell, min_pressure, EquilibrationSettings};
use super::exchange::{exchange_heat, exchange_momentum_fixed, ExchangeCoefficients};
use super::faces::{face_exchange, face_pressure, face_velocities, face_viscosity, FacePredictor};
use super::implicit::{pressure_mg_options, LinearSolver, SemiImplicit};
use super::par::{max_rows, par_face_rows, par_rows, try_rows, Out};
use super::state::{CellLayout, IceState};
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
    /// Limited linear (MUSCL) reconstruction of the normal velocity and the
    /// equilibration pressure to the two sides of a face in Guilkey Eq. 28
    /// (see [`super::faces::face_velocities`]); `None` is Eq. 28 as written
    /// (cell values).
    pub face_reconstruction: Option<Limiter>,
    /// Dynamic viscosity `μ_r` per material (Newtonian stress in the
    /// momentum source of Guilkey Eq. 33, heating `θ τ:∇u` in the energy);
    /// `None` (or all zero) skips the viscous kernel entirely.
    pub viscosity: Option<Vec<f64>>,
    /// Factor `γ` on the `Δt` of the resolved (reconstructed-slope) part of
    /// the pressure difference in Guilkey Eq. 28 when
    /// `face_reconstruction` is on: `γ = 1/2` time-centres the face
    /// velocity at `t + Δt/2` (MUSCL–Hancock-like), `0` drops the term.
    pub face_smooth_factor: f64,
    /// MUSCL–Hancock half-step predictor of the reconstructed face states
    /// of Guilkey Eq. 28 (needs `face_reconstruction`; see
    /// [`super::faces::face_velocities`]): the face velocity sees the
    /// velocity and pressure at `t + Δt/2` on either side of the face,
    /// including the convective term; `face_smooth_factor` is then not used.
    pub face_predictor: bool,
    /// Advection as the remap of the Lagrangian cells (second order in
    /// time on smooth flow of finite amplitude). The Lagrangian phase
    /// (Guilkey Eqs. 33–41) leaves each cell's material in a cell whose
    /// faces have moved by `u* Δt`, of volume `V^L_r = M_r v^L_r`; the
    /// material that crossed a fixed face during the step is then the part
    /// of the donor's Lagrangian cell beyond it: its mass is the swept mass
    /// of the fixed cell times `V_r/V^L_r = v_r/v^L_r` (`v` the specific
    /// volume of Eq. 13, `v^L` of Eq. 41), and the face predictor gives
    /// the Lagrangian face velocity (no convective term, see
    /// [`super::faces::FacePredictor`]). With the fixed-cell swept mass
    /// (`false`, Guilkey Sec. 3.3 step 12 as written) the Lagrangian
    /// quantities are remapped as if the cell had not changed volume: an
    /// error `Δt² ∇·u` per step in the swept mass, which on a simple wave
    /// of amplitude `ε` is `O(ε² Δt)` globally (first order; measured
    /// order 1.08 at `ε = 0.1`, `N = 1024`, L1/ε 1.04e-4, against 1.96
    /// and 1.30e-5 with the remap, Hancock variant). The rescaled mass is
    /// taken from the region of width `(V/V^L) u* Δt` at the face (the
    /// donor's Courant number is scaled too), and the strain
    /// `V^L/V − 1` is limited across the face ([`super::advection::remap_strain`])
    /// so that a velocity jump inside one cell is not spread over its
    /// material. In 2D and 3D `V^L` is the full Lagrangian volume (all
    /// directions), which is exact to second order for a plane wave in
    /// any direction (measured: the ε = 0.1 wave along the diagonal,
    /// order 1.93 at 64², 1.75 at 256² with superbee, whose compression of
    /// the steepening wave costs the order there, and 2.00 at 256² with
    /// the MC limiter; 1.12 without the remap).
    pub lagrangian_remap: bool,
    /// Weight `w` of `Δp` in the pressure of the momentum and energy
    /// sources, `p = p_eq + w Δp` (Guilkey Eq. 30 has `w = 1`); `w = 1/2`
    /// centres the pressure force at `t + Δt/2`. `0 ≤ w ≤ 1`. With
    /// `pressure_weight_compression` set this is the weight of cells where
    /// `Δp ≤ 0` (expansion) only.
    pub pressure_weight: f64,
    /// Weight of `Δp` in cells where `Δp > 0` (compression), `0 ≤ w_c ≤ 1`;
    /// `None` uses `pressure_weight` everywhere. With `Some(w_c)` both
    /// weights are switched ([`Self::source_weight`]): `w_c` in compression
    /// and `pressure_weight` in expansion where the step changes the
    /// pressure by `|Δp|/p_eq ≥ 1e-3` (shocks, start-up discontinuities),
    /// tending linearly to the time-centred `1/2` as `|Δp|/p_eq → 0`, so
    /// that smooth flow stays second order. `Some(1.0)` is Guilkey Eq. 30
    /// as written in a shock, so that the full `Δp = −Δt K ∇·u*` acts as
    /// its bulk viscosity.
    pub pressure_weight_compression: Option<f64>,
    /// Acoustic dissipation of Guilkey Eq. 28: `Some(λ)` takes the jump
    /// (dissipation) part of the face velocity over the time
    /// `τ_f = λ h_d/(c_L + c_R)` per face instead of `face_dt_factor · Δt`,
    /// with `c² = K/ρ` the mixture sound speed of the cell (`K = 1/Σ θ κ`
    /// as in Eq. 29, `ρ = Σ M/V`). For one material and equal states the
    /// term is then `λ [p]/(2ρc)`: `λ = 1` is the acoustic Riemann (Godunov)
    /// value at every face, whatever the local Courant number (with
    /// `face_dt_factor` it holds only where `c Δt/h` is largest).
    /// `λ < 1` applies where the reconstructed pressures of the face differ
    /// by `≳ 1e-2` of the pressure; below that it tends to 1 (see
    /// [`super::faces::face_velocities`]), so that acoustic waves are not
    /// under-damped. `0 < λ ≤ 1`.
    pub acoustic_jump: Option<f64>,
    /// Linear artificial viscosity in the face pressure of Guilkey Eq. 31
    /// at compressive faces: `Some(μ)` adds
    /// `μ Z_L Z_R/(Z_L + Z_R) max(0, u_L − u_R)` to `p*`, with `Z = ρc`
    /// (the mixture impedance, see `acoustic_jump`) and `u_L`, `u_R` the
    /// mixture normal velocities of the two cells: the pressure term of the
    /// acoustic Riemann solver (`μ = 1/2`), kept in compression only, so
    /// expansions and contacts are untouched, and scaled by a pressure
    /// shock sensor (Jameson, Schmidt & Turkel 1981; see
    /// [`super::faces::face_viscosity`]) that is `O(h²)` on smooth flow, so
    /// that a smooth compression sees an `O(h³)` viscosity. The energy
    /// stays conservative (the same `p*` does the work). `0 ≤ μ ≤ 1`.
    pub face_viscosity: Option<f64>,
    /// Semi-implicit (implicit-pressure) ICE: `Some` replaces the explicit
    /// `Δp` of Guilkey Eq. 29 by the pressure equation solved with an outer
    /// iteration ([`super::implicit`]); the sound speed then no longer
    /// limits the time step. `None` is the explicit step.
    pub implicit: Option<SemiImplicit>,
    /// Frame of each material (empty: all Eulerian, a fluid-only scene).
    /// Materials carried by particles take part in the cell equations
    /// (equilibration, face velocities, Eq. 29, exchange) but are not
    /// advected, and their Lagrangian velocities come from the nodes
    /// (Guilkey Sec. 3.3).
    pub frames: Vec<Frame>,
    /// Internal-energy sources of fluid materials.
    pub heat_sources: Vec<HeatSource>,
    /// Equilibrate on the total material volume `Σ_r M_r v_r` of a cell
    /// instead of the cell volume (Guilkey Sec. 3.3 step 2: "the volume
    /// fraction θ_r is then computed as the volume of r-material per total
    /// material volume"), with `v_r` the evolved specific volume of a fluid
    /// (Eqs. 40–41) and the solid EOS value at the previous pressure for a
    /// particle material. Needed when solid mass reaches the cells by
    /// interpolation; `false` for fluid-only scenes.
    pub normalise_volume: bool,
}

/// How a material moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Frame {
    /// A fluid in the cells: advected (Guilkey Sec. 3.3 step 12).
    Eulerian,
    /// A deformable solid on material points (step 13).
    Particles,
    /// A rigid solid on material points with a prescribed velocity: it
    /// takes part in the exchange with that velocity held fixed.
    Rigid,
}

/// An internal-energy source: `power` W per m³ of the material (flat cell
/// index, zero outside the region; a cell receives `power θ_r V`) added to
/// material `material` while
/// `start ≤ t < end` (the part of a step inside the window counts).
#[derive(Debug, Clone, PartialEq)]
pub struct HeatSource {
    /// Index of the fluid material heated.
    pub material: usize,
    /// Power per unit volume in every cell (length: the layout's cells).
    pub power: Vec<f64>,
    /// Start of the window.
    pub start: f64,
    /// End of the window.
    pub end: f64,
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

/// Relative pressure change `|Δp|/p_eq` of a step (Eq. 29) at which the
/// switched `Δp` weight of [`IceParams::source_weight`] reaches its
/// shock values; below it the weight tends linearly to the time-centred
/// `1/2`. (`1e-3` before the compression weight was shock-sensed: the
/// simple wave `ε = 0.1` then ran at `w_c`/`w` at every `N ≤ 512`; `3e-3`
/// measured best on the simple wave for Sod within 1 %.)
pub const WEIGHT_SWITCH_SCALE: f64 = 3.0e-3;

/// Value of the cell pressure shock sensor ([`cell_shock_sensor`]) at
/// which the compression weight of [`IceParams::source_weight`] is fully
/// on (below it, it is scaled by `ψ/ψ_c`).
pub const COMPRESSION_SENSOR_SCALE: f64 = 3.0e-4;

/// Value of the cell pressure shock sensor ([`cell_shock_sensor`]) at
/// which the expansion weight of [`IceParams::source_weight`] is fully on.
/// Ten times below the compression's: a rarefaction is smooth after its
/// first steps, and the weight must stay on there (Sod: L1(ρ) 4.601e-4 at
/// N = 800 with it, 4.613e-4 at `3e-5`, 5.02e-4 at `3e-4`), while on a
/// smooth wave (`ψ = O(h²)`) it lets the weight tend to 1/2 (simple wave
/// `ε = 0.1`, acoustic Hancock at N = 1024: L1/ε 1.61e-5 against 5.10e-5
/// with the amplitude switch alone).
pub const EXPANSION_SENSOR_SCALE: f64 = 1.0e-5;

/// Pressure shock sensor of cell `c` (Jameson, Schmidt & Turkel 1981):
/// the largest, over the directions and the cells `c − s, c, c + s`, of
/// `|p_{i+s} − 2 p_i + p_{i−s}|/(p_{i+s} + 2 p_i + p_{i−s})`: `O(h²)`
/// where `p` is smooth, `O(1)` within a cell or two of a shock (taking the
/// neighbours' values catches the middle of a shock spread over three
/// cells, where the second difference vanishes). Needs two ghost layers
/// of `p` filled; a non-positive denominator counts as a shock.
#[inline]
pub fn cell_shock_sensor<const D: usize>(layout: &CellLayout<D>, p: &[f64], c: usize) -> f64 {
    let sens = |i: usize, s: usize| {
        let den = p[i + s] + 2.0 * p[i] + p[i - s];
        if den > 0.0 {
            (p[i + s] - 2.0 * p[i] + p[i - s]).abs() / den
        } else {
            1.0
        }
    };
    let mut psi: f64 = 0.0;
    for d in 0..D {
        let s = layout.strides[d];
        psi = psi.max(sens(c - s, s)).max(sens(c, s)).max(sens(c + s, s));
    }
    psi
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
            face_reconstruction: None,
            viscosity: None,
            face_smooth_factor: 0.0,
            face_predictor: false,
            lagrangian_remap: false,
            pressure_weight: 1.0,
            pressure_weight_compression: None,
            acoustic_jump: None,
            face_viscosity: None,
            implicit: None,
            frames: Vec::new(),
            heat_sources: Vec::new(),
            normalise_volume: false,
        }
    }

    /// The frame of material `r` (Eulerian unless set in `frames`).
    #[inline]
    pub fn frame(&self, r: usize) -> Frame {
        self.frames.get(r).copied().unwrap_or(Frame::Eulerian)
    }

    /// `true` per material with a prescribed (rigid) velocity.
    pub fn rigid_mask(&self) -> [bool; MAX_MATERIALS] {
        let mut m = [false; MAX_MATERIALS];
        for (r, f) in self.frames.iter().enumerate().take(MAX_MATERIALS) {
            m[r] = *f == Frame::Rigid;
        }
        m
    }

    /// The high-resolution variant of the same ICE step (an improvement of
    /// the discretisation, the method unchanged): MUSCL reconstruction of
    /// velocity and pressure in Guilkey Eq. 28 with superbee
    /// (`face_reconstruction`), the resolved part of the face pressure
    /// difference at `Δt/2` (`face_smooth_factor = 1/2`), the pressure force
    /// of Eqs. 33–34 at `p_eq + Δp/2` (`pressure_weight = 1/2`), superbee
    /// advection, the Lagrangian remap (`lagrangian_remap`) and
    /// `cfl = 0.4`. Sod L1(ρ) at N = 400: 1.33e-3 (1.47e-3 without the
    /// remap; literal: 3.73e-3).
    pub fn high_resolution(boundaries: Boundaries<D>) -> Self {
        Self {
            cfl: 0.4,
            advection: Advection::SecondOrder(Limiter::Superbee),
            face_reconstruction: Some(Limiter::Superbee),
            face_smooth_factor: 0.5,
            pressure_weight: 0.5,
            lagrangian_remap: true,
            ..Self::new(boundaries)
        }
    }

    /// [`Self::high_resolution`] with the MUSCL–Hancock predictor of the
    /// face states of Guilkey Eq. 28 (`face_predictor`; the resolved
    /// pressure gradient at `t + Δt/2`, the Lagrangian face velocity), which
    /// keeps the scheme second order in time up to `cfl = 0.8`: the same
    /// ICE step (Eqs. 28–41) with time-centred face states. The jump
    /// (dissipation) part of Eq. 28 is taken with `face_dt_factor = 0.625`,
    /// so that `α ν = 1/2` at the largest acoustic Courant number `ν = 0.8`
    /// (for a pressure jump `[p]` the term is `α ν [p]/(ρ c)`, and `[p]/(2ρc)`
    /// is the acoustic Riemann (Godunov) value). Sod L1(ρ): 7.22e-4 at
    /// N = 800 in 481 steps (high resolution: 6.43e-4 in 925 steps; before
    /// the Lagrangian remap 7.96e-4 and 7.42e-4).
    pub fn hancock(boundaries: Boundaries<D>) -> Self {
        Self {
            cfl: 0.8,
            face_dt_factor: 0.625,
            face_predictor: true,
            ..Self::high_resolution(boundaries)
        }
    }

    /// [`Self::hancock`] with shock-capturing dissipation from the acoustic
    /// Riemann problem, tuned on Sod (the MUSCL–Hancock ICE step, Guilkey
    /// Eqs. 28–41, with three changes to its numerical dissipation):
    /// the jump part of Eq. 28 at half the acoustic (Godunov) value
    /// (`acoustic_jump = 0.5`, replacing `face_dt_factor`) at faces whose
    /// reconstructed pressures jump by `≳ 1e-2 p`, tending to the Godunov
    /// value below (see [`super::faces::face_velocities`]); `Δp` of
    /// Eq. 30 at full weight where a cell is compressed and at `0.4` where
    /// it expands weakly (`pressure_weight_compression = 1`,
    /// `pressure_weight = 0.4`), both only where the step changes the
    /// pressure by `|Δp|/p_eq ≳ 1e-3` and tending to the time-centred `1/2`
    /// below (see [`Self::source_weight`]), which damps the post-shock
    /// oscillations and reduces the start-up error of the rarefaction, the
    /// largest part of the Sod error; a linear face viscosity `μ = 0.25` at
    /// compressive faces (`face_viscosity`), scaled by a pressure shock
    /// sensor (Jameson, Schmidt & Turkel 1981); and `cfl = 0.9`. The
    /// switches are `O(h)`-small perturbations on smooth flow (the weight,
    /// `σ ∝ Δp ∝ Δt`; the jump factor, `∝ |p_R − p_L| = O(h²)`) or vanish
    /// as `O(h²)` (the viscosity), so that the step is second order there:
    /// linear acoustic wave order 1.96 at N = 512, error 8.1e-5 (Hancock:
    /// 8.7e-5; the unswitched rules: order 0.81, 1.14e-2). Sod L1(ρ)
    /// 4.60e-4 at N = 800 in 403 steps (Hancock: 7.22e-4 in 481 steps),
    /// 2.63e-4 at N = 1600 in 804 steps, 1.57e-4 at N = 3200; before the
    /// Lagrangian remap 5.42e-4, 2.99e-4 and 1.65e-4 (then unswitched:
    /// 5.40e-4, 2.99e-4; compression weight not shock-sensed: 5.42e-4,
    /// 2.97e-4, 1.57e-4). The switches were tuned before the remap.
    /// Expansion weights below 0.4 were more accurate at N ≤ 1600 but
    /// stalled the convergence at N = 6400; switching the weight, or the
    /// jump factor, with the pressure shock sensor *instead of* the
    /// amplitude switch cost 18–27 % on Sod (the rarefaction then runs at
    /// the smooth values); both weights now take the product of the two
    /// (see [`Self::source_weight`]).
    pub fn hancock_acoustic(boundaries: Boundaries<D>) -> Self {
        Self {
            cfl: 0.9,
            pressure_weight: 0.4,
            pressure_weight_compression: Some(1.0),
            acoustic_jump: Some(0.5),
            face_viscosity: Some(0.25),
            ..Self::hancock(boundaries)
        }
    }

    /// The weight of `Δp` in the pressure of the sources (Guilkey Eq. 30,
    /// `p = p_eq + w Δp`): `pressure_weight` without
    /// `pressure_weight_compression`. With it, the weight is switched by
    /// the relative pressure change of the step,
    /// `σ = min(1, |Δp|/(s p_eq))` with `s = ` [`WEIGHT_SWITCH_SCALE`]
    /// (`3e-3`): `1/2 + σ φ (w_c − 1/2)` where `Δp > 0` (compression),
    /// `φ = min(1, ψ/ψ_c)` the value of `shock()` — the cell pressure shock
    /// sensor [`cell_shock_sensor`] — over `ψ_c = `
    /// [`COMPRESSION_SENSOR_SCALE`] (`3e-4`), and,
    /// where `Δp < 0`, `w_b + (1 − w_b) x²` with `w_b = 1/2 + σ φ_e (w −
    /// 1/2)`, `φ_e = min(1, ψ/ψ_e)` over `ψ_e = `
    /// [`EXPANSION_SENSOR_SCALE`] (`1e-5`), and the relative expansion
    /// `x = min(1, −Δp/p_eq)`. A shock or a
    /// start-up discontinuity (`σ = 1`) gets `w_c` in compression and `w`
    /// in weak expansion; a strong expansion (towards vacuum) is weighted
    /// towards the end-of-step pressure, so that the flow work `p ΔV` it
    /// does stays within the internal energy of the cell (the "123"
    /// problem). On smooth flow `Δp = O(Δt)`, so `σ = O(Δt)` (and
    /// `x² = O(Δt²)`): the weight is the time-centred `1/2 + O(Δt)`, a
    /// pressure error `O(Δt²)` per step, and the step stays second order;
    /// for acoustic amplitudes (`|Δp|/p_eq ≪ 3e-3`) the switch is off.
    /// The amplitude switch alone (`s = 1e-3`, no `φ`) saturated on a
    /// smooth wave of finite amplitude (the simple wave of the
    /// `ice_simple_wave` study, `ε = 0.1`: `|Δp|/p_eq ≈ 0.8 h`), which then
    /// ran at `w_c` and `w`, first order and 14× Hancock's error at
    /// `N = 1024`; sensing the compression weight and `s = 3e-3` give
    /// 1.3× Hancock's error there. The expansion weight was an amplitude
    /// switch only until the Lagrangian remap: with the remap, acoustic
    /// Hancock on that wave was 3.9× Hancock's error at `N = 1024` (L1/ε
    /// 5.10e-5), and sensing the expansion weight too (at a ten times
    /// smaller scale, so that the Sod rarefaction keeps it) gives 1.61e-5
    /// (Hancock 1.30e-5), Sod within 1.4 %. (The former rule switched on the sign of `Δp` alone, `w_c` for any
    /// compression, and was first order on smooth compressions: acoustic
    /// wave order 0.81.) Cells with `p_eq ≤ 0` keep the switch on.
    #[inline]
    pub fn source_weight(&self, dp: f64, p_eq: f64, shock: impl FnOnce() -> f64) -> f64 {
        let w = self.pressure_weight;
        let Some(wc) = self.pressure_weight_compression else {
            return w;
        };
        if p_eq <= 0.0 || p_eq.is_nan() {
            return if dp > 0.0 { wc } else { w };
        }
        // The switch σ = min(1, |Δp|/(s p_eq)), s = WEIGHT_SWITCH_SCALE.
        let sigma = (dp.abs() / (WEIGHT_SWITCH_SCALE * p_eq)).min(1.0);
        // The pressure shock sensor over a scale (a NaN counts as a shock).
        let psi = shock();
        let sensed = |scale: f64| {
            if psi.is_nan() {
                1.0
            } else {
                (psi / scale).min(1.0)
            }
        };
        if dp > 0.0 {
            // Compression: only at a shock.
            0.5 + sigma * sensed(COMPRESSION_SENSOR_SCALE) * (wc - 0.5)
        } else {
            // Expansion: where the pressure is not smooth on the grid
            // scale (a shock, a rarefaction's start or its edges).
            let wb = 0.5 + sigma * sensed(EXPANSION_SENSOR_SCALE) * (w - 0.5);
            let x = (-dp / p_eq).min(1.0);
            wb + (1.0 - wb) * x * x
        }
    }

    /// Checks the parameters against a state.
    ///
    /// # Errors
    /// [`IceError::InvalidInput`] naming the offending parameter.
    pub fn validate(&self, state: &IceState<D>) -> Result<(), IceError> {
        if let Some(sp) = &self.implicit {
            // The Courant number is on `|u| + sound_speed_factor c`: above 1
            // it is an acoustic Courant number; the advective limit is
            // checked per step (`TimestepTooLarge`).
            if !(self.cfl.is_finite() && self.cfl > 0.0 && self.cfl <= 1.0e4) {
                return Err(invalid(
                    "cfl",
                    format!("must be in (0, 1e4] (semi-implicit), got {}", self.cfl),
                ));
            }
            sp.validate()?;
            // Multigrid's red–black smoother needs an even number of cells
            // along a periodic direction, unless the whole grid is its
            // directly solved coarsest level.
            let coarse_max = pressure_mg_options().coarse_max_cells;
            let cells = state.layout.cells;
            if sp.linear_solver == LinearSolver::PcgMultigrid
                && cells.iter().product::<usize>() > coarse_max
            {
                for (d, b) in self.boundaries.iter().enumerate() {
                    if b[0] == IceBoundary::Periodic && cells[d] % 2 == 1 {
                        return Err(invalid(
                            "implicit.linear_solver",
                            format!(
                                "pcg_multigrid needs an even number of cells along periodic direction {d} (got {}); use direct or pcg_jacobi",
                                cells[d]
                            ),
                        ));
                    }
                }
            }
        } else if !(self.cfl.is_finite() && self.cfl > 0.0 && self.cfl <= 1.0) {
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
        if self.face_predictor && self.face_reconstruction.is_none() {
            return Err(invalid(
                "face_predictor",
                "needs face_reconstruction (a limiter for the face states)",
            ));
        }
        for (name, x) in [
            ("face_smooth_factor", self.face_smooth_factor),
            ("pressure_weight", self.pressure_weight),
            (
                "pressure_weight_compression",
                self.pressure_weight_compression.unwrap_or(0.0),
            ),
            ("face_viscosity", self.face_viscosity.unwrap_or(0.0)),
        ] {
            if !(x.is_finite() && (0.0..=1.0).contains(&x)) {
                return Err(invalid(name, format!("must be in [0, 1], got {x}")));
            }
        }
        if let Some(l) = self.acoustic_jump {
            if !(l.is_finite() && l > 0.0 && l <= 1.0) {
                return Err(invalid(
                    "acoustic_jump",
                    format!("must be in (0, 1], got {l}"),
                ));
            }
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
        if !self.frames.is_empty() && self.frames.len() != nm {
            return Err(invalid(
                "frames",
                format!("needs {nm} entries, got {}", self.frames.len()),
            ));
        }
        let coupled = self.frames.iter().any(|f| *f != Frame::Eulerian);
        if let Some(first) = self.frames.iter().position(|f| *f != Frame::Eulerian) {
            if self.frames[first..].contains(&Frame::Eulerian) {
                return Err(invalid(
                    "frames",
                    "particle-borne materials must come after the Eulerian ones",
                ));
            }
        }
        if coupled && self.time != TimeIntegration::ForwardEuler {
            return Err(invalid(
                "time",
                "particle-borne materials need forward_euler time integration",
            ));
        }
        for (i, h) in self.heat_sources.iter().enumerate() {
            if h.material >= nm || self.frame(h.material) != Frame::Eulerian {
                return Err(invalid(
                    format!("heat_sources[{i}].material"),
                    "must be a fluid material",
                ));
            }
            if h.power.len() != state.layout.len()
                || !h.power.iter().all(|q| q.is_finite())
                || !(h.start.is_finite() && h.end.is_finite() && h.end >= h.start)
            {
                return Err(invalid(
                    format!("heat_sources[{i}]"),
                    "needs a finite power per cell and a window start <= end",
                ));
            }
        }
        if let Some(mu) = &self.viscosity {
            if mu.len() != nm || !mu.iter().all(|m| m.is_finite() && *m >= 0.0) {
                return Err(invalid(
                    "viscosity",
                    format!("needs {nm} finite values >= 0, got {mu:?}"),
                ));
            }
        }
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
    pub(super) ustar: Vec<[Vec<f64>; D]>,
    pub(super) div: Vec<Vec<f64>>,
    pub(super) kappa: Vec<Vec<f64>>,
    pub(super) div_sum: Vec<f64>,
    pub(super) sum_theta_kappa: Vec<f64>,
    pub(super) mix_mass: Vec<f64>,
    pub(super) press: Vec<f64>,
    pub(super) pstar: [Vec<f64>; D],
    pub(super) theta_flux: [Vec<f64>; D],
    pub(super) mix_vflux: [Vec<f64>; D],
    pub(super) ke: Vec<Vec<f64>>,
    pub(super) vel_l: Vec<Vec<SVector<f64, D>>>,
    pub(super) temp_l: Vec<Vec<f64>>,
    pub(super) e_l: Vec<Vec<f64>>,
    pub(super) v_l: Vec<Vec<f64>>,
    pub(super) fluxes: AdvectionFluxes<D>,
    pub(super) new_mass: Vec<Vec<f64>>,
    pub(super) new_vel: Vec<Vec<SVector<f64, D>>>,
    pub(super) new_temp: Vec<Vec<f64>>,
    pub(super) new_spvol: Vec<Vec<f64>>,
    pub(super) saved: Vec<super::state::MaterialCells<D>>,
    pub(super) implicit: super::implicit::ImplicitSlot<D>,
    pub(super) last_dt: Option<f64>,
    pub(super) accel: Vec<Vec<SVector<f64, D>>>,

    pub(super) vel_pred: Vec<Vec<SVector<f64, D>>>,
    /// Mixture bulk modulus `1/Σ θ κ` per cell, ghosts included (face
    /// predictor, acoustic jump and face viscosity only).
    pub(super) bulk: Vec<f64>,
    /// Mixture sound speed `√(K V/Σ M)` per cell, ghosts included (with
    /// `bulk`).
    pub(super) sound: Vec<f64>,
    /// `V/V^L` per cell of the material being advected, ghosts included
    /// (`IceParams::lagrangian_remap` only).
    pub(super) remap: Vec<f64>,
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
            implicit: Default::default(),
            last_dt: None,
            accel: Vec::new(),

            vel_pred: Vec::new(),
            bulk: Vec::new(),
            sound: Vec::new(),
            remap: s(),
        }
    }
}

impl<const D: usize> IceWorkspace<D> {
    /// The pressure of the current step (`p_eq + w Δp`, Guilkey Eq. 30),
    /// ghosts filled, after [`stage_pressure`].
    pub fn pressure(&self) -> &[f64] {
        &self.press
    }

    /// The face pressures normal to each direction (Guilkey Eq. 31), after
    /// [`stage_pressure`].
    pub fn face_pressure(&self) -> &[Vec<f64>; D] {
        &self.pstar
    }

    /// The Lagrangian velocities after the exchange (Guilkey Eq. 38) of
    /// material `r`, after [`stage_lagrangian`].
    pub fn lagrangian_velocity(&self, r: usize) -> &[SVector<f64, D>] {
        &self.vel_l[r]
    }

    /// Per cell, material `r`'s Lagrangian temperature after the exchange
    /// (Guilkey Eqs. 37 and 39), after [`stage_lagrangian`].
    pub fn lagrangian_temperature(&self, r: usize) -> &[f64] {
        &self.temp_l[r]
    }

    /// Per material and direction, the face velocities `u*` after the face
    /// exchange (Guilkey Eq. 28), after [`stage_pressure`].
    pub fn face_velocities(&self) -> &[[Vec<f64>; D]] {
        &self.ustar
    }
}

/// What a step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepInfo {
    /// The time step taken.
    pub dt: f64,
    /// Largest number of equilibration iterations in a cell.
    pub max_equilibration_iterations: usize,
    /// Semi-implicit pressure: outer iterations (linear solves) of the step
    /// (0 for the explicit pressure).
    pub outer_iterations: usize,
    /// Semi-implicit pressure: Krylov iterations summed over the outer
    /// iterations (0 for the direct solver and the explicit pressure).
    pub linear_iterations: usize,
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
    // Split the borrows: inputs (mass, temperature) read, outputs written.
    let IceState {
        layout,
        cells,
        p_eq,
        steps,
        time,
        ..
    } = state;
    let mut sv_out = [Out::empty(); MAX_MATERIALS];
    let mut th_out = [Out::empty(); MAX_MATERIALS];
    let mut mass_in: [&[f64]; MAX_MATERIALS] = [&[]; MAX_MATERIALS];
    let mut temp_in: [&[f64]; MAX_MATERIALS] = [&[]; MAX_MATERIALS];
    for (r, mc) in cells.iter_mut().enumerate() {
        sv_out[r] = Out::new(&mut mc.sp_vol);
        th_out[r] = Out::new(&mut mc.vol_frac);
        mass_in[r] = &mc.mass;
        temp_in[r] = &mc.temperature;
    }
    let p_out = Out::new(p_eq);
    let (step_no, t_now) = (*steps, *time);
    // Ideal gas only: p(ρ, T) has no cancellation there (a stiffened gas
    // with a large p_∞ keeps the iteration on the density balance).
    let single = nm == 1
        && !params.normalise_volume
        && matches!(eos[0], crate::material::eos::FluidEos::IdealGas(_));
    let p_min0 = min_pressure(&eos[0]);
    let mut particle = [false; MAX_MATERIALS];
    for (r, p) in particle.iter_mut().enumerate().take(nm) {
        *p = params.frame(r) != Frame::Eulerian;
    }
    let lay: &CellLayout<D> = layout;
    try_rows(lay, |row| {
        let mut rb = [0.0; MAX_MATERIALS];
        let mut t = [0.0; MAX_MATERIALS];
        let mut v = [0.0; MAX_MATERIALS];
        let mut th = [0.0; MAX_MATERIALS];
        let mut local_max = 0;
        for c in row {
            // Guilkey Sec. 3.3 step 2: θ_r per total material volume where
            // a particle material fills the cell, blended to the cell
            // volume where it does not (see `SOLID_FILL_FOR_NORMALISING`).
            let mut vt = vol;
            if params.normalise_volume {
                let (mut sum, mut solid) = (0.0, 0.0);
                for r in 0..nm {
                    // SAFETY: cell c is read and written by this task only.
                    let mv = mass_in[r][c] * unsafe { sv_out[r].get(c) };
                    sum += mv;
                    if particle[r] {
                        solid += mv;
                    }
                }
                if sum.is_finite() && sum > 0.0 {
                    let w = (solid / (SOLID_FILL_FOR_NORMALISING * vol)).min(1.0);
                    let r = FLUID_NORMALISING_RANGE;
                    let bounded = sum.clamp(vol / r, vol * r);
                    vt = bounded + w * (sum - bounded);
                }
            }
            for r in 0..nm {
                rb[r] = mass_in[r][c] / vt;
                t[r] = temp_in[r][c];
            }
            if single {
                // One ideal gas: Eq. 13 is θ = ρ̂ v = 1, so v = 1/ρ̂ and
                // p = p(ρ̂, T) directly (no iteration).
                let p = eos[0].pressure(rb[0], t[0]);
                if p.is_finite() && p > p_min0 && rb[0] > 0.0 {
                    local_max = local_max.max(1);
                    // SAFETY: cell c is written by this task only.
                    unsafe {
                        p_out.set(c, p);
                        sv_out[0].set(c, 1.0 / rb[0]);
                        th_out[0].set(c, 1.0);
                    }
                    continue;
                }
            }
            // SAFETY: cell c is read and written by this task only.
            let guess = unsafe { p_out.get(c) };
            match equilibrate_cell(
                &eos[..nm],
                &rb[..nm],
                &t[..nm],
                guess,
                &params.equilibration,
                &mut v[..nm],
                &mut th[..nm],
            ) {
                Ok((p, it)) => {
                    local_max = local_max.max(it);
                    // SAFETY: as above.
                    unsafe {
                        p_out.set(c, p);
                        for r in 0..nm {
                            sv_out[r].set(c, v[r]);
                            th_out[r].set(c, th[r]);
                        }
                    }
                }
                Err(e) => {
                    return Err(IceError::Equilibration {
                        site: Site {
                            step: step_no,
                            time: t_now,
                            cell: lay.coords(c).to_vec(),
                            material: None,
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
    let layout = &state.layout;
    let eos0 = state.materials[0].eos;
    fill_scalar(layout, bcs, &mut state.p_eq, |s| {
        eos0.pressure(s[0].density, s[0].temperature)
    });
    for (r, mc) in state.cells.iter_mut().enumerate() {
        fill_scalar(layout, bcs, &mut mc.sp_vol, |s| 1.0 / s[r].density);
        fill_scalar(layout, bcs, &mut mc.vol_frac, |s| s[r].vol_frac);
    }
    Ok(max_it.into_inner())
}

/// Stable time step `cfl / max_c Σ_d max_r (|u_r,d| + c̃_r)/h_d` from the
/// current (equilibrated, ghosts filled) state, with the sound speed
/// `c̃ = c √(max_f v_f / v)` seen through the face specific volumes of
/// Guilkey Eq. 28.
pub fn timestep<const D: usize>(state: &IceState<D>, cfl: f64) -> f64 {
    timestep_with(state, cfl, 1.0, &[])
}

/// [`timestep`] with the sound speed scaled by `sound_factor`
/// (`cfl / max_c Σ_d max_r (|u_r,d| + sound_factor c̃_r)/h_d`): `0` is the
/// advective limit of the semi-implicit pressure. Materials with
/// `rigid[r]` (a prescribed velocity, [`Frame::Rigid`]) add their velocity
/// but not their sound speed: their face velocities do not respond to the
/// pressure (Eq. 28 is replaced by the prescribed value and the exchange
/// locks the fluid to it where they are present), so no acoustic wave
/// travels through them.
pub fn timestep_with<const D: usize>(
    state: &IceState<D>,
    cfl: f64,
    sound_factor: f64,
    rigid: &[bool],
) -> f64 {
    let layout = &state.layout;
    let rate = max_rows(layout, |row| {
        let mut rate: f64 = 0.0;
        // c² v⁻¹ per material of the cell (the sound speed is the same in
        // every direction).
        let mut c2_v = [0.0; MAX_MATERIALS];
        for c in row {
            for (r, (mat, mc)) in state.materials.iter().zip(&state.cells).enumerate() {
                c2_v[r] = if sound_factor > 0.0 && !rigid.get(r).copied().unwrap_or(false) {
                    let v = mc.sp_vol[c];
                    mat.eos.sound_speed_sq(1.0 / v, mc.temperature[c]) / v
                } else {
                    0.0
                };
            }
            let mut sum = 0.0;
            for d in 0..D {
                let mut w: f64 = 0.0;
                let s = layout.strides[d];
                for (r, mc) in state.cells.iter().enumerate() {
                    let v = mc.sp_vol[c];
                    // The face velocity (Guilkey Eq. 28) couples the cell to
                    // its neighbours through v_f = 2 v_c v_n/(v_c + v_n)
                    // (< 2 v_n, increasing in v_n): the effective sound speed
                    // is c √(max v_f/v_c).
                    let vn = mc.sp_vol[c - s].max(mc.sp_vol[c + s]);
                    let vf = (2.0 * v * vn / (v + vn)).max(v);
                    let cs = if c2_v[r] > 0.0 {
                        sound_factor * (c2_v[r] * vf).sqrt()
                    } else {
                        0.0
                    };
                    w = w.max(mc.velocity[c][d].abs() + cs);
                }
                sum += w / layout.h[d];
            }
            rate = rate.max(sum);
        }
        rate
    });
    if rate > 0.0 {
        cfl / rate
    } else {
        f64::INFINITY
    }
}

/// Largest explicit viscous rate `2 Σ_d max_r μ_r v_r / h_d²` (the time
/// step of the viscous term must stay below `1/rate`); zero without
/// viscosity.
fn viscous_rate<const D: usize>(state: &IceState<D>, mu: &[f64]) -> f64 {
    let layout = &state.layout;
    let inv_h2: f64 = (0..D).map(|d| 1.0 / (layout.h[d] * layout.h[d])).sum();
    max_rows(layout, |row| {
        let mut rate: f64 = 0.0;
        for c in row {
            for (r, mc) in state.cells.iter().enumerate() {
                rate = rate.max(2.0 * mu[r] * mc.sp_vol[c] * inv_h2);
            }
        }
        rate
    })
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
    let info = advance_inner(state, params, ws, dt_max, fixed)?;
    ws.last_dt = Some(info.dt);
    Ok(info)
}

fn advance_inner<const D: usize>(
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
                outer_iterations: first.outer_iterations + second.outer_iterations,
                linear_iterations: first.linear_iterations + second.linear_iterations,
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
    let info = stage_pressure(state, params, ws, dt_max, fixed)?;
    stage_lagrangian(state, params, ws, info.dt, &[])?;
    stage_advect(state, params, ws, info)
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
/// As [`step`].
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
    let mu = params
        .viscosity
        .as_deref()
        .filter(|m| m.iter().any(|&x| x > 0.0));
    let implicit = params.implicit.as_ref();
    let dt = if fixed {
        dt_max
    } else {
        // Semi-implicit: the sound speed no longer limits the step (only
        // through `sound_speed_factor`, default 0), and the step grows by at
        // most `max_dt_growth` per step.
        let factor = implicit.map_or(1.0, |sp| sp.sound_speed_factor);
        let mut dt = timestep_with(state, params.cfl, factor, &params.rigid_mask());
        if let Some(mu) = mu {
            let rate = viscous_rate(state, mu);
            if rate > 0.0 {
                dt = dt.min(params.cfl.min(1.0) / rate);
            }
        }
        if let (Some(sp), Some(last)) = (implicit, ws.last_dt) {
            dt = dt.min(sp.max_dt_growth * last);
        }
        dt.min(dt_max)
    };
    if !(dt.is_finite() && dt > 0.0) {
        return Err(invalid(
            "dt",
            format!("time step must be finite and > 0, got {dt}"),
        ));
    }
    let layout = &state.layout;
    let exchange = params.exchange.as_ref().filter(|_| nm > 1);
    let k_on = exchange.filter(|e| e.momentum.iter().any(|&k| k > 0.0));

    // Step 3: face velocities (Guilkey Eq. 28), then the face exchange.
    let fdt = params.face_dt_factor * dt;
    // Semi-implicit convective predictor: the cell velocities seen by
    // Eq. 28 are advanced by the previous step's advective acceleration.
    let predictor = implicit.map_or(0.0, |sp| sp.convective_predictor);
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
    let predictor_on = params.face_predictor && params.face_reconstruction.is_some();
    let viscosity = params.face_viscosity.filter(|&mu| mu > 0.0);
    // Mixture mass per cell, ghosts included (Guilkey Eq. 31 and the
    // mixture sound speed).
    {
        let cells = &state.cells;
        let mix = |(i, m): (usize, &mut f64)| {
            let mut sum = 0.0;
            for mc in cells {
                sum += mc.mass[i];
            }
            *m = sum;
        };
        if layout.rows.len() == 1 {
            ws.mix_mass.iter_mut().enumerate().for_each(mix);
        } else {
            ws.mix_mass.par_iter_mut().enumerate().for_each(mix);
        }
    }
    if predictor_on || params.acoustic_jump.is_some() || viscosity.is_some() {
        // K = 1/Σ_s θ_s κ_s and c = √(K V/M) per cell, ghosts included
        // (the face kernels read the cells on both sides of each face).
        ws.bulk.resize(layout.len(), 0.0);
        ws.sound.resize(layout.len(), 0.0);
        let cells = &state.cells;
        let mats = &state.materials;
        let mix_mass = &ws.mix_mass;
        let vol = layout.cell_volume();
        let bulk = |(c, (k, cs)): (usize, (&mut f64, &mut f64))| {
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
            ws.bulk
                .iter_mut()
                .zip(ws.sound.iter_mut())
                .enumerate()
                .for_each(bulk);
        } else {
            ws.bulk
                .par_iter_mut()
                .zip(ws.sound.par_iter_mut())
                .enumerate()
                .for_each(bulk);
        }
    }
    for r in 0..nm {
        let mc = &state.cells[r];
        let vel_in = if use_pred {
            &ws.vel_pred[r]
        } else {
            &mc.velocity
        };
        // A rigid material's face velocity is the average of its prescribed
        // cell velocities (no pressure acceleration).
        let rigid = params.frame(r) == Frame::Rigid;
        for d in 0..D {
            let out = &mut ws.ustar[r][d];
            face_velocities(
                layout,
                d,
                &mc.mass,
                vel_in,
                &mc.sp_vol,
                &state.p_eq,
                if rigid { 0.0 } else { fdt },
                if rigid {
                    0.0
                } else {
                    params.gravity[d] * dt / fdt
                },
                params.face_reconstruction,
                if rigid || predictor_on {
                    0.0
                } else {
                    params.face_smooth_factor * dt
                },
                if predictor_on && !rigid {
                    Some(FacePredictor {
                        tau: 0.5 * dt,
                        bulk: &ws.bulk[..],
                        velocity_convection: !params.lagrangian_remap,
                    })
                } else {
                    None
                },
                match params.acoustic_jump {
                    Some(lambda) if !rigid => Some((lambda, &ws.sound[..])),
                    _ => None,
                },
                out,
            );
            zero_wall_faces(layout, bcs, d, out);
        }
    }
    if let Some(sp) = implicit {
        // The implicit correction starts from the pre-exchange values.
        super::implicit::save_pre_exchange(state, params, sp, ws)?;
    }
    if let Some(ex) = k_on {
        for d in 0..D {
            face_exchange(
                layout,
                d,
                &ex.momentum,
                dt,
                &state.cells,
                &params.rigid_mask(),
                &mut ws.ustar,
            );
        }
    }
    let (outer_iterations, linear_iterations) = if let Some(sp) = implicit {
        // Semi-implicit: the pressure equation solved by the outer
        // iteration of `implicit` (fills `ws.press`, the volume fluxes and
        // the face velocities consistent with the new pressure).
        let its = super::implicit::implicit_pressure(state, params, sp, ws, dt, fdt)?;
        courant_check(state, &ws.ustar, dt)?;
        its
    } else {
        courant_check(state, &ws.ustar, dt)?;
        // Step 5: Δp (Guilkey Eq. 29) and p = p_eq + Δp (Eq. 30).
        volume_fluxes(state, params, ws, dt);
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
                let w =
                    params.source_weight(dp, st.p_eq[c], || cell_shock_sensor(layout, &st.p_eq, c));
                // SAFETY: cell c is written by this task only.
                unsafe { press.set(c, st.p_eq[c] + w * dp) };
            }
            Ok(())
        })?;
        (0, 0)
    };
    let eos0 = state.materials[0].eos;
    fill_scalar(layout, bcs, &mut ws.press, |s| {
        eos0.pressure(s[0].density, s[0].temperature)
    });

    // Step 6: face pressure (Guilkey Eq. 31), with the face viscosity.
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
    Ok(StepInfo {
        dt,
        max_equilibration_iterations: max_it,
        outer_iterations,
        linear_iterations,
    })
}

/// Steps 8–11 (Guilkey Sec. 3.3): momentum and energy sources (Eqs. 33–34),
/// heat sources, Lagrangian values (Eqs. 35–37), the pointwise-implicit
/// exchange (Eqs. 38–39) and the specific-volume evolution (Eqs. 40–41),
/// after [`stage_pressure`]. The Lagrangian values are left in the
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
/// Volume fraction above which a particle-borne material makes a cell (and
/// its face neighbours) use Guilkey Eq. 34's flow work instead of the
/// total-energy form.
const SOLID_FRACTION_FOR_FLOW_WORK: f64 = 1e-9;

pub fn stage_lagrangian<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt: f64,
    particle_velocity: &[Vec<SVector<f64, D>>],
) -> Result<(), IceError> {
    let nm = state.num_materials();
    let layout = &state.layout;
    let vol = layout.cell_volume();
    let mu = params
        .viscosity
        .as_deref()
        .filter(|m| m.iter().any(|&x| x > 0.0));
    let exchange = params.exchange.as_ref().filter(|_| nm > 1);
    let k_on = exchange.filter(|e| e.momentum.iter().any(|&k| k > 0.0));
    let h_on = exchange.filter(|e| !e.heat_off());
    let conservative = params.energy == EnergyForm::Conservative;
    let mut cv = [0.0; MAX_MATERIALS];
    let mut lagr = [false; MAX_MATERIALS];
    let mut fixed = [false; MAX_MATERIALS];
    for r in 0..nm {
        cv[r] = state.materials[r].eos.specific_heat_cv();
        lagr[r] = params.frame(r) != Frame::Eulerian && !particle_velocity.is_empty();
        fixed[r] = params.frame(r) == Frame::Rigid;
    }
    let any_fixed = fixed[..nm].iter().any(|&f| f);
    let (t0, t1) = (state.time, state.time + dt);
    let sources = &params.heat_sources;

    // Steps 8–11: sources (Guilkey Eqs. 33–34), Lagrangian values
    // (Eqs. 35–37), exchange (Eqs. 38–39) and specific volume (Eqs. 40–41,
    // Appendix Eq. 53), per cell and all materials at once.
    {
        let st: &IceState<D> = state;
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
            ..
        } = ws;
        let (kappa, div_sum, stk, press, pstar, mix_vflux) = (
            &*kappa,
            &*div_sum,
            &*sum_theta_kappa,
            &*press,
            &*pstar,
            &*mix_vflux,
        );
        let mut o_vel = [Out::empty(); MAX_MATERIALS];
        let mut o_temp = [Out::empty(); MAX_MATERIALS];
        let mut o_e = [Out::empty(); MAX_MATERIALS];
        let mut o_ke = [Out::empty(); MAX_MATERIALS];
        let mut o_v = [Out::empty(); MAX_MATERIALS];
        for (o, a) in o_vel.iter_mut().zip(vel_l.iter_mut()) {
            *o = Out::new(a);
        }
        for (o, a) in o_temp.iter_mut().zip(temp_l.iter_mut()) {
            *o = Out::new(a);
        }
        for (o, a) in o_e.iter_mut().zip(e_l.iter_mut()) {
            *o = Out::new(a);
        }
        for (o, a) in o_ke.iter_mut().zip(ke.iter_mut()) {
            *o = Out::new(a);
        }
        for (o, a) in o_v.iter_mut().zip(v_l.iter_mut()) {
            *o = Out::new(a);
        }
        let any_lagr = lagr[..nm].iter().any(|&l| l);
        let solid_in = |k: usize| {
            (0..nm).any(|r| lagr[r] && st.cells[r].vol_frac[k] > SOLID_FRACTION_FOR_FLOW_WORK)
        };
        let solid_near = |c: usize| {
            solid_in(c)
                || (0..D)
                    .any(|d| solid_in(c - layout.strides[d]) || solid_in(c + layout.strides[d]))
        };
        try_rows(layout, |row| {
            let mut theta = [0.0; MAX_MATERIALS];
            let mut v = [0.0; MAX_MATERIALS];
            let mut mass = [0.0; MAX_MATERIALS];
            let mut u = [SVector::<f64, D>::zeros(); MAX_MATERIALS];
            let mut t = [0.0; MAX_MATERIALS];
            let mut t_before = [0.0; MAX_MATERIALS];
            let mut beta = [0.0; MAX_MATERIALS];
            let mut heat = [0.0; MAX_MATERIALS];
            for c in row {
                let mut grad = SVector::<f64, D>::zeros();
                for d in 0..D {
                    grad[d] = (pstar[d][c + layout.strides[d]] - pstar[d][c]) / layout.h[d];
                }
                let mut dke_src = 0.0;
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
                // compression, `p κ_r θ_r Δp`.
                let cons = conservative && !(any_lagr && solid_near(c));
                for r in 0..nm {
                    let mc = &st.cells[r];
                    theta[r] = mc.vol_frac[c];
                    v[r] = mc.sp_vol[c];
                    let m = mc.mass[c];
                    mass[r] = m;
                    if lagr[r] {
                        // Particle-borne: the sources were applied on the
                        // nodes (Guilkey Sec. 3.3 step 8).
                        u[r] = particle_velocity[r][c];
                        t[r] = mc.temperature[c];
                        heat[r] = 0.0;
                        continue;
                    }
                    // Guilkey Eq. 33: Δ(mu) = −Δt V θ ∇p* + Δt M g
                    // (+ Δt V ∇·(θ τ) with viscosity).
                    let mut mom = mc.velocity[c] * m - grad * (dt * vol * theta[r])
                        + params.gravity * (dt * m);
                    let u_p = mom / m;
                    dke_src += 0.5 * m * (u_p.norm_squared() - mc.velocity[c].norm_squared());
                    heat[r] = 0.0;
                    if let Some(mu) = mu {
                        if mu[r] > 0.0 {
                            let (force, q) = viscous_source(layout, st, r, mu[r], c);
                            mom += force * (dt * vol);
                            heat[r] = q * dt * vol;
                        }
                    }
                    u[r] = mom / m;
                    let me = m * cv[r] * mc.temperature[c];
                    t[r] = if !cons {
                        // Guilkey Eq. 34: Δ(me) = −Δt V f^θ p Σ_s ∇·(θu*)_s.
                        let f_theta = theta[r] * kappa[r][c] / stk[c];
                        (me - dt * vol * f_theta * press[c] * div_sum[c] + heat[r]) / (m * cv[r])
                    } else {
                        me / (m * cv[r])
                    };
                    // Heat sources: internal energy added at a rate per unit
                    // volume over a time window.
                    for src in sources.iter().filter(|s| s.material == r) {
                        let overlap = (t1.min(src.end) - t0.max(src.start)).max(0.0);
                        if overlap > 0.0 {
                            // Per unit volume of the material (θ_r V), so a
                            // cell the material barely fills is not
                            // overheated.
                            t[r] += src.power[c] * theta[r] * vol * overlap / (m * cv[r]);
                        }
                    }
                }
                // f_θ among the materials that receive the flux work and the
                // exchange heat (the Eulerian ones).
                let mut stk_e = 0.0;
                for r in 0..nm {
                    if !lagr[r] {
                        stk_e += theta[r] * kappa[r][c];
                    }
                }
                if cons {
                    // Conservative Eq. 34: Δ(mE) = −Δt Σ_f A p*_f Σ_s θ_s,f u*_s,f
                    // (the stored fluxes carry Δt A / V).
                    let mut de = 0.0;
                    for d in 0..D {
                        let f_hi = c + layout.strides[d];
                        de += pstar[d][c] * mix_vflux[d][c] - pstar[d][f_hi] * mix_vflux[d][f_hi];
                    }
                    de *= vol;
                    let de_int = de - dke_src;
                    for r in 0..nm {
                        if lagr[r] {
                            continue;
                        }
                        let f_theta = theta[r] * kappa[r][c] / stk_e;
                        t[r] += (f_theta * de_int + heat[r]) / (mass[r] * cv[r]);
                    }
                }
                if let Some(ex) = k_on {
                    let ke0: f64 = (0..nm).map(|r| 0.5 * mass[r] * u[r].norm_squared()).sum();
                    let u0 = u;
                    exchange_momentum_fixed(
                        &ex.momentum,
                        dt,
                        &theta[..nm],
                        &v[..nm],
                        &mass[..nm],
                        if any_fixed { &fixed[..nm] } else { &[] },
                        &mut u[..nm],
                    );
                    if cons {
                        // The kinetic energy dissipated by the exchange
                        // becomes heat.
                        let ke1: f64 = (0..nm).map(|r| 0.5 * mass[r] * u[r].norm_squared()).sum();
                        // A material held at a prescribed velocity U does
                        // work U · (the momentum the others gain) on the
                        // cell: the dissipation is ke0 − ke1 + that work
                        // (½ m (U − u0)² ≥ 0 for one fluid locked to it).
                        let mut work = 0.0;
                        if any_fixed {
                            if let Some(s) = (0..nm).find(|&s| fixed[s]) {
                                let gained: SVector<f64, D> = (0..nm)
                                    .filter(|&r| !fixed[r])
                                    .map(|r| (u[r] - u0[r]) * mass[r])
                                    .sum();
                                work = u[s].dot(&gained);
                            }
                        }
                        for r in 0..nm {
                            if lagr[r] {
                                continue;
                            }
                            let f_theta = theta[r] * kappa[r][c] / stk_e;
                            t[r] += f_theta * (ke0 - ke1 + work) / (mass[r] * cv[r]);
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
                        let eos = &st.materials[r].eos;
                        beta[r] = eos.thermal_expansivity(1.0 / v[r], t_before[r]);
                        sum_tb += theta[r] * beta[r] * (t[r] - t_before[r]) / dt;
                    }
                }
                for r in 0..nm {
                    if lagr[r] {
                        // The cell values of a particle-borne material are
                        // rebuilt from the particles next step.
                        // SAFETY: cell c is written by this task only.
                        unsafe {
                            o_vel[r].set(c, u[r]);
                            o_temp[r].set(c, t[r]);
                            o_e[r].set(c, cv[r] * t[r]);
                            o_ke[r].set(c, 0.5 * u[r].norm_squared());
                            o_v[r].set(c, v[r]);
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
                    // Guilkey Eq. 40 with the isentropic κ of Eq. 29: the
                    // adiabatic heating is inside κ, so Ṫ is the exchange
                    // part only.
                    let f_theta = theta[r] * kappa[r][c] / stk[c];
                    let mut dmv = f_theta * div_sum[c];
                    if h_on.is_some() {
                        dmv += theta[r] * beta[r] * (t[r] - t_before[r]) / dt - f_theta * sum_tb;
                    }
                    // Guilkey Eq. 41.
                    let mut mv = mass[r] * v[r] + dt * vol * dmv;
                    if !(mv.is_finite() && mv > 0.0) {
                        // A material with a small share of the cell (a
                        // fluid trace in a solid's cell) cannot absorb its
                        // linearised share of the compression: take its EOS
                        // volume at the new pressure instead.
                        if let Ok(rho) = st.materials[r].eos.density(press[c], t[r]) {
                            mv = mass[r] / rho;
                        }
                    }

                    if !(mv.is_finite() && mv > 0.0) {
                        return Err(IceError::NonPhysical {
                            site: site(st, c, Some(r)),
                            quantity: "specific volume",
                            value: mv / mass[r],
                        });
                    }
                    // SAFETY: cell c is written by this task only.
                    unsafe {
                        o_vel[r].set(c, u[r]);
                        o_temp[r].set(c, t[r]);
                        o_e[r].set(c, cv[r] * t[r]);
                        o_ke[r].set(c, 0.5 * u[r].norm_squared());
                        o_v[r].set(c, mv / mass[r]);
                    }
                }
            }
            Ok(())
        })?;
    }
    Ok(())
}

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
    let bcs = &params.boundaries;
    let scheme = params.advection;
    let layout = &state.layout;
    let dt = info.dt;
    let conservative = params.energy == EnergyForm::Conservative;
    let predictor = params
        .implicit
        .as_ref()
        .map_or(0.0, |sp| sp.convective_predictor);
    let mut cv = [0.0; MAX_MATERIALS];
    for r in 0..nm {
        cv[r] = state.materials[r].eos.specific_heat_cv();
    }
    // Step 12: advection with compatible fluxes.
    for r in 0..nm {
        if params.frame(r) != Frame::Eulerian {
            continue;
        }
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
        if params.lagrangian_remap {
            // The Lagrangian strain V^L/V − 1 = v^L/v − 1 (Eq. 13's v,
            // Eq. 41's v^L); 0 where it is not usable.
            for &c in &layout.interior {
                let e = ws.v_l[r][c] / mc.sp_vol[c] - 1.0;
                ws.remap[c] = if e.is_finite() && e > -1.0 { e } else { 0.0 };
            }
            fill_scalar(layout, bcs, &mut ws.remap, |_| 0.0);
        }
        let fields = AdvectedFields {
            remap: params.lagrangian_remap.then_some(&ws.remap[..]),
            mass: &mc.mass,
            velocity: &ws.vel_l[r],
            energy: &ws.e_l[r],
            sp_vol: &ws.v_l[r],
            kinetic: if conservative { Some(&ws.ke[r]) } else { None },
        };
        material_fluxes(layout, &ws.ustar[r], &fields, dt, scheme, &mut ws.fluxes);
        let fx = &ws.fluxes;
        let (o_m, o_u, o_t, o_v) = (
            Out::new(&mut ws.new_mass[r]),
            Out::new(&mut ws.new_vel[r]),
            Out::new(&mut ws.new_temp[r]),
            Out::new(&mut ws.new_spvol[r]),
        );
        let st: &IceState<D> = state;
        try_rows(layout, |row| {
            for c in row {
                let m0 = mc.mass[c];
                let m = m0 + net_inflow(layout, &fx.mass, c);
                if !(m.is_finite() && m > 0.0) {
                    return Err(IceError::NonPhysical {
                        site: site(st, c, Some(r)),
                        quantity: "mass",
                        value: m,
                    });
                }
                let mom = fields.velocity[c] * m0 + net_inflow_vec(layout, &fx.momentum, c);
                let mut me = m0 * fields.energy[c] + net_inflow(layout, &fx.energy, c);
                if let Some(k) = fields.kinetic {
                    // Total energy advected; internal = total − kinetic.
                    let me_tot = me + m0 * k[c] + net_inflow(layout, &fx.kinetic, c);
                    let me_cons = me_tot - 0.5 * mom.norm_squared() / m;
                    if me_cons > 0.0 {
                        me = me_cons;
                    }
                }
                let mut mv = m0 * fields.sp_vol[c] + net_inflow(layout, &fx.volume, c);
                if !(mv.is_finite() && mv > 0.0) {
                    // A trace material next to cells where its specific
                    // volume is orders of magnitude larger (a fluid floor
                    // inside a solid in tension) can be given more volume
                    // flux than it holds: keep its own specific volume.
                    // In a coupled scene (where the solid field makes such
                    // contrasts at every surface) this applies to any
                    // fluid.
                    let m_cell: f64 = st.cells.iter().map(|mc| mc.mass[c]).sum();
                    if m0 < 1e-6 * m_cell || params.normalise_volume {
                        mv = m * fields.sp_vol[c];
                    }
                }
                let temp = me / (m * cvr);
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
                // SAFETY: cell c is written by this task only.
                unsafe {
                    o_m.set(c, m);
                    o_u.set(c, mom / m);
                    o_t.set(c, temp);
                    o_v.set(c, mv / m);
                }
            }
            Ok(())
        })?;
    }
    // Commit.
    for r in 0..nm {
        if params.frame(r) != Frame::Eulerian {
            continue;
        }
        let mc = &mut state.cells[r];
        std::mem::swap(&mut mc.mass, &mut ws.new_mass[r]);
        std::mem::swap(&mut mc.velocity, &mut ws.new_vel[r]);
        std::mem::swap(&mut mc.temperature, &mut ws.new_temp[r]);
        std::mem::swap(&mut mc.sp_vol, &mut ws.new_spvol[r]);
    }
    if predictor > 0.0 {
        if ws.accel.len() != nm {
            // Allocated once, on the first semi-implicit step.
            let n = layout.len();
            ws.accel = (0..nm).map(|_| vec![SVector::zeros(); n]).collect();
            ws.vel_pred = (0..nm).map(|_| vec![SVector::zeros(); n]).collect();
        }
        // Advective acceleration of this step (advected minus Lagrangian
        // velocity, per unit time); zero for materials that are not
        // advected here (carried by particles or rigid).
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
    std::mem::swap(&mut state.pressure, &mut ws.press);
    // Keep the old p_eq as the next equilibration's guess (already there).
    state.time += dt;
    state.steps += 1;
    Ok(info)
}

/// Viscous momentum source `∇·(θ τ)` per unit volume of material `r` in
/// cell `c` and the viscous heating `θ τ:∇u` per unit volume, for the
/// Newtonian stress `τ = μ (∇u + ∇uᵀ − ⅔ (∇·u) I)` (the deviatoric stress
/// of Guilkey Eq. 33's `σ_r − σ` term and Eq. 9's heating). The traction
/// on a face normal to `d` uses the compact normal derivative `(u_R −
/// u_L)/h_d` and the mean of the two cells' central tangential derivatives,
/// `θ_f = (θ_L + θ_R)/2`; the divergence is the difference of the face
/// tractions. Needs the velocity ghosts including corners.
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
    /// Semi-implicit pressure: outer iterations summed over the steps.
    pub outer_iterations: u64,
    /// Semi-implicit pressure: Krylov iterations summed over the steps.
    pub linear_iterations: u64,
    /// Semi-implicit pressure: largest outer iteration count of a step.
    pub max_outer_iterations: usize,
    /// Semi-implicit pressure: largest Krylov iteration count of a step.
    pub max_linear_iterations: usize,
}

impl<const D: usize> FluidRun<D> {
    /// One line for a run summary: steps, retries, wall time and (for the
    /// semi-implicit pressure) the outer and linear iterations per step.
    pub fn summary(&self) -> String {
        let per = |x: u64| x as f64 / self.steps.max(1) as f64;
        format!(
            "{} steps ({} retried) in {:.3} s; pressure solve: {:.2} outer (max {}) and {:.1} linear (max {}) iterations per step",
            self.steps,
            self.retries,
            self.wall_s,
            per(self.outer_iterations),
            self.max_outer_iterations,
            per(self.linear_iterations),
            self.max_linear_iterations
        )
    }
}

/// Runs a fluid-only scene from `state` to `t_end` (at most `max_steps`
/// steps), retrying a step with half the time step when it reports a
/// retryable error ([`IceError::TimestepTooLarge`], or a failed semi-implicit
/// pressure solve, [`IceError::PressureSolve`]; up to 20 times in a row).
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
    let (mut outer, mut linear, mut max_outer, mut max_linear) = (0u64, 0u64, 0usize, 0usize);
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
                Ok(info) => {
                    outer += info.outer_iterations as u64;
                    linear += info.linear_iterations as u64;
                    max_outer = max_outer.max(info.outer_iterations);
                    max_linear = max_linear.max(info.linear_iterations);
                    break;
                }
                Err(e) if tries < 20 && e.retry_dt().is_some() => {
                    dt_max = 0.5 * e.retry_dt().unwrap_or(dt_max);
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
        outer_iterations: outer,
        linear_iterations: linear,
        max_outer_iterations: max_outer,
        max_linear_iterations: max_linear,
    })
}

/// The pressure `p ∈ (p_min, p_eq)` at which the materials of cell `c`,
/// each following its EOS at its own temperature, fill the relative volume
/// change `dv = Δt Σ ∇·(θu*)` (> 0: net volume outflow, an expansion):
/// `Σ_r θ_r (v_r(p)/v_r(p_eq) − 1) = dv`, the balance that Guilkey Eq. 29
/// linearises. Bisection in `ln(p − p_min)`; `None` when no admissible
/// pressure satisfies it.
fn expanded_pressure<const D: usize>(
    st: &IceState<D>,
    c: usize,
    dv: f64,
    p_min: f64,
) -> Option<f64> {
    let p_eq = st.p_eq[c];
    if !(dv > 0.0 && p_eq > p_min) {
        return None;
    }
    let excess = |p: f64| -> Option<f64> {
        let mut sum = 0.0;
        for (mat, mc) in st.materials.iter().zip(&st.cells) {
            let t = mc.temperature[c];
            let v0 = mc.sp_vol[c];
            let v = 1.0 / mat.eos.density(p, t).ok()?;
            sum += mc.vol_frac[c] * (v / v0 - 1.0);
        }
        Some(sum - dv)
    };
    // excess decreases with p; at p_eq it is −dv < 0.
    let (mut lo, mut hi) = ((1e-300f64).ln(), (p_eq - p_min).ln());
    let at = |s: f64| p_min + s.exp();
    if excess(at(lo)).is_none_or(|e| e < 0.0) {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        match excess(at(mid)) {
            Some(e) if e > 0.0 => lo = mid,
            Some(_) => hi = mid,
            None => lo = mid,
        }
        if hi - lo < 1e-12 {
            break;
        }
    }
    let p = at(hi);
    (p > p_min).then_some(p)
}

/// Largest of the materials' lowest admissible pressures.
pub(super) fn min_pressure_all<const D: usize>(state: &IceState<D>) -> f64 {
    state
        .materials
        .iter()
        .map(|m| min_pressure(&m.eos))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Returns [`IceError::TimestepTooLarge`] when the face velocities would
/// take more than a cell's content out of a cell in `Δt`.
pub(super) fn courant_check<const D: usize>(
    state: &IceState<D>,
    ustar: &[[Vec<f64>; D]],
    dt: f64,
) -> Result<(), IceError> {
    let layout = &state.layout;
    let nm = state.num_materials();
    try_rows(layout, |row| {
        for c in row {
            for r in 0..nm {
                let mut courant = 0.0;
                for d in 0..D {
                    let s = layout.strides[d];
                    let (lo, hi) = (ustar[r][d][c], ustar[r][d][c + s]);
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
        Ok(())
    })
}

/// The volume fluxes of Guilkey Eq. 29 from the current face velocities
/// `ws.ustar`: per face the `θ` fluxes (`Δt A/V θ_f u*_f`, advected with
/// the step's scheme) summed over the materials (`ws.mix_vflux`), per cell
/// `∇·(θu*)_r` (`ws.div`), their sum (`ws.div_sum`), `κ_r` (`ws.kappa`) and
/// `Σ_r θ_r κ_r` (`ws.sum_theta_kappa`).
pub(super) fn volume_fluxes<const D: usize>(
    state: &IceState<D>,
    params: &IceParams<D>,
    ws: &mut IceWorkspace<D>,
    dt: f64,
) {
    let scheme = params.advection;
    let layout = &state.layout;
    let nm = state.num_materials();

    for r in 0..nm {
        let mc = &state.cells[r];
        let eos = &state.materials[r].eos;
        for d in 0..D {
            scalar_fluxes(
                layout,
                d,
                &ws.ustar[r][d],
                &mc.vol_frac,
                &mc.velocity,
                dt,
                scheme,
                &mut ws.theta_flux[d],
            );
            let tf = &ws.theta_flux[d];
            let acc = Out::new(&mut ws.mix_vflux[d]);
            par_face_rows(layout, d, |row| {
                for f in row {
                    // SAFETY: face f is read and written by this task only.
                    unsafe {
                        let prev = if r == 0 { 0.0 } else { acc.get(f) };
                        acc.set(f, prev + tf[f]);
                    }
                }
            });
        }
        let tf = &ws.theta_flux;
        let (div, kappa) = (Out::new(&mut ws.div[r]), Out::new(&mut ws.kappa[r]));
        let (div_sum, stk) = (Out::new(&mut ws.div_sum), Out::new(&mut ws.sum_theta_kappa));
        par_rows(layout, |row| {
            for c in row {
                // ∇·(θ u*)_r; the fluxes carry Δt/h.
                let dv = -net_inflow(layout, tf, c) / dt;
                let k = eos.compressibility(1.0 / mc.sp_vol[c], mc.temperature[c]);
                // SAFETY: cell c is read and written by this task only.
                unsafe {
                    div.set(c, dv);
                    kappa.set(c, k);
                    let (ds, sk) = if r == 0 {
                        (0.0, 0.0)
                    } else {
                        (div_sum.get(c), stk.get(c))
                    };
                    div_sum.set(c, ds + dv);
                    stk.set(c, sk + mc.vol_frac[c] * k);
                }
            }
        });
    }
}
