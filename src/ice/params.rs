//! All knobs of the ICE step ([`IceParams`]) and the choices they hold: the
//! frame of each material ([`Frame`]), heat sources ([`HeatSource`]), the
//! time integration ([`TimeIntegration`]) and the form of the energy update
//! ([`EnergyForm`]); the switched `Δp` weight of the sources (Guilkey
//! Eq. 30, [`IceParams::source_weight`]) with its pressure shock sensor
//! ([`cell_shock_sensor`]) and scales.

use nalgebra::SVector;

use super::advection::{Advection, Limiter};
use super::boundary::{Boundaries, IceBoundary};
use super::equilibration::EquilibrationSettings;
use super::exchange::ExchangeCoefficients;
use super::implicit_params::{pressure_mg_options, LinearSolver, SemiImplicit};
use super::state::{CellLayout, IceState};
use super::{invalid, IceError, MAX_MATERIALS};

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
    /// The face exchange (Guilkey Eq. 38 at the faces) gives a rigid
    /// material ([`Frame::Rigid`]) the smaller of its two cells' volume
    /// fractions at a face instead of their mean: a face between a cell
    /// the body has reached and one it has not lets the other materials
    /// through at their own velocity
    /// ([`crate::coupling::RigidInterface::Sharp`]).
    pub rigid_faces_sharp: bool,
    /// Solid materials (by index; shorter than the material list means
    /// `false`) whose face velocity the pressure stage holds at the average
    /// of their cells' velocities, without the pressure gradient's
    /// acceleration, at every face where both cells hold at least
    /// [`HELD_FACE_FILL`] of them: a quasistatic implicit solid, whose
    /// velocity its stress sets, not `−Δt ∇p/ρ` (see [`HeldFaces`]).
    pub held_solids: Vec<bool>,
    /// Volume fraction below which a material of a mixed cell keeps its
    /// temperature through the flow work of the Lagrangian phase
    /// (isothermal, like the equilibration; `0` turns it off). See
    /// [`super::sources`]: a gas trace in a cell full of a much stiffer
    /// material takes that material's volume noise as order-one
    /// compressions and expansions, which the equilibration undoes
    /// without work, a ratchet that heated air traces to 1e5–1e6 K.
    pub isothermal_fraction: f64,
    /// Materials never held isothermal (by index; shorter than the
    /// material list means `false`): a reaction's product, whose traces
    /// ahead of the burn receive the burn's mass and energy (held
    /// isothermal, the very fast burn of `tests/reaction.rs` balanced its
    /// energy to −4.09e-2 instead of −6.41e-3).
    pub isothermal_exempt: Vec<bool>,
    /// Where the materials of [`Self::isothermal_exempt`] are exempt, per
    /// cell: the cells a burn feeds or burns in (set with the flags).
    /// Elsewhere a product trace is held isothermal like any other (inside
    /// a steel wall beside a confined burn its exempt trace took the work
    /// of the wall's volume noise, reached a sound speed of 4.5e5 m/s and
    /// cut Δt 100-fold).
    pub isothermal_exempt_cells: Vec<bool>,
}

/// Default of [`IceParams::isothermal_fraction`].
pub const ISOTHERMAL_FRACTION: f64 = 1e-3;

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

/// The volume fraction of a [`IceParams::held_solids`] material that both
/// cells of a face must hold for the pressure stage to hold its velocity
/// there. Without the hold, the pressure stage gave the quasistatic steel of
/// the pressurised cylinder faces moving at `−Δt ∇p/ρ_s` (about 0.4 m/s
/// across the wall at Δt 1e-4 s) and the gas locked to them was advected
/// into and through the wall: P fell 4.4 % from 3.2 to 8 ms (dx 0.05).
/// Held at faces with both cells at ≥ 1 % steel, P stays at 1.9286e7 Pa;
/// at ≥ 20 % / 50 % it still fell 1.5 % / 3.1 % from 3.1 to 8 ms (the
/// threshold made a variable in a temporary build); held at every face
/// (the traces' too) the run went unstable at 2.6 ms, starting at the
/// steel's outer surface, where outside air was trapped and compressed in
/// its surface cells.
pub const HELD_FACE_FILL: f64 = 0.01;

/// Per material, whether the pressure stage holds its face velocity:
/// always for a rigid material, and for a [`IceParams::held_solids`] one
/// where both cells of the face hold at least [`HELD_FACE_FILL`] of it
/// ([`IceParams::held_faces`]).
#[derive(Debug, Clone, Copy)]
pub struct HeldFaces {
    rigid: [bool; MAX_MATERIALS],
    solid: [bool; MAX_MATERIALS],
}

impl HeldFaces {
    /// Whether any material may be held.
    pub fn any(&self) -> bool {
        self.rigid.contains(&true) || self.solid.contains(&true)
    }

    /// Whether material `r` (volume fractions `theta`) is held at the face
    /// between cells `l` and `f`.
    #[inline]
    pub fn at(&self, r: usize, theta: &[f64], l: usize, f: usize) -> bool {
        self.rigid[r] || (self.solid[r] && theta[l].min(theta[f]) >= HELD_FACE_FILL)
    }
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
            rigid_faces_sharp: false,
            held_solids: Vec::new(),
            isothermal_fraction: ISOTHERMAL_FRACTION,
            isothermal_exempt: Vec::new(),
            isothermal_exempt_cells: Vec::new(),
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

    /// Which materials the pressure stage holds at a face
    /// ([`HeldFaces::at`]), per material once, for the face loops.
    pub fn held_faces(&self) -> HeldFaces {
        let mut solid = [false; MAX_MATERIALS];
        for (r, &h) in self.held_solids.iter().enumerate().take(MAX_MATERIALS) {
            solid[r] = h;
        }
        HeldFaces {
            rigid: self.rigid_mask(),
            solid,
        }
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
        self.validate_cfl(state)?;
        self.validate_factors()?;
        let nm = state.num_materials();
        self.validate_frames(nm)?;
        self.validate_heat_sources(state)?;
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
        self.validate_boundaries(nm)
    }

    /// The Courant number (explicit: `(0, 1]`; semi-implicit: `(0, 1e4]`)
    /// and the semi-implicit settings, including multigrid's even cell
    /// count along periodic directions.
    fn validate_cfl(&self, state: &IceState<D>) -> Result<(), IceError> {
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
        Ok(())
    }

    /// The factors and weights of the face velocity, the sources and the
    /// face viscosity, gravity and the equilibration settings.
    fn validate_factors(&self) -> Result<(), IceError> {
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
        Ok(())
    }

    /// One frame per material (or none), particle-borne materials after the
    /// Eulerian ones, and forward Euler when any is particle-borne.
    fn validate_frames(&self, nm: usize) -> Result<(), IceError> {
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
        Ok(())
    }

    /// Each heat source heats a fluid material with a finite power per cell
    /// over a window `start <= end`.
    fn validate_heat_sources(&self, state: &IceState<D>) -> Result<(), IceError> {
        let nm = state.num_materials();
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
        Ok(())
    }

    /// Periodic on both sides or neither; an inflow state per material with
    /// volume fractions summing to 1.
    fn validate_boundaries(&self, nm: usize) -> Result<(), IceError> {
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
