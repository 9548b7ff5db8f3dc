//! Specific-volume evolution of the Lagrangian phase (Guilkey Sec. 3.3
//! step 11, Eqs. 40–41, Appendix Eq. 53): each material's share of the
//! cell's volume change, `Δ(M v)_r = Δt V (f_r^θ Σ_s ∇·(θu*)_s + θ_r β_r
//! Ṫ_r − f_r^θ Σ_s θ_s β_s Ṫ_s)`, with the isentropic `κ` of Eq. 29 (the
//! adiabatic heating is inside `κ`, so `Ṫ` is the exchange part only).

use crate::material::eos::{EquationOfState, FluidEos};

/// One material's values in a cell for Guilkey Eqs. 40–41.
pub(super) struct MaterialShare {
    /// Mass `M_r`.
    pub(super) mass: f64,
    /// Specific volume `v_r` of Guilkey Eq. 13.
    pub(super) sp_vol: f64,
    /// Volume fraction `θ_r`.
    pub(super) theta: f64,
    /// `f_r^θ = θ_r κ_r / Σ_s θ_s κ_s`.
    pub(super) f_theta: f64,
    /// Lagrangian temperature after the exchange (Eq. 39).
    pub(super) temp: f64,
    /// Temperature before the heat exchange.
    pub(super) temp_before: f64,
    /// Thermal expansivity `β_r` at `temp_before`.
    pub(super) beta: f64,
}

/// The cell's values for Guilkey Eqs. 40–41.
pub(super) struct CellShare {
    /// `Σ_s ∇·(θu*)_s`.
    pub(super) div_sum: f64,
    /// With heat exchange, `Σ_s θ_s β_s Ṫ_s`; `None` without.
    pub(super) sum_tb: Option<f64>,
    /// The pressure of the sources (Eq. 30).
    pub(super) press: f64,
    /// Time step.
    pub(super) dt: f64,
    /// Cell volume.
    pub(super) vol: f64,
}

/// `M v^L` of one material after the Lagrangian phase (Guilkey Eq. 41 with
/// the rate of Eq. 40). A material with a small share of the cell (a fluid
/// trace in a solid's cell) that cannot absorb its linearised share of the
/// compression takes its EOS volume at the new pressure instead. The
/// result may still be non-physical; the caller checks it.
#[inline]
pub(super) fn lagrangian_volume(eos: &FluidEos, m: &MaterialShare, cell: &CellShare) -> f64 {
    // Guilkey Eq. 40 with the isentropic κ of Eq. 29: the
    // adiabatic heating is inside κ, so Ṫ is the exchange
    // part only.
    let mut dmv = m.f_theta * cell.div_sum;
    if let Some(sum_tb) = cell.sum_tb {
        dmv += m.theta * m.beta * (m.temp - m.temp_before) / cell.dt - m.f_theta * sum_tb;
    }
    // Guilkey Eq. 41.
    let mut mv = m.mass * m.sp_vol + cell.dt * cell.vol * dmv;
    if !(mv.is_finite() && mv > 0.0) {
        // A material with a small share of the cell (a
        // fluid trace in a solid's cell) cannot absorb its
        // linearised share of the compression: take its EOS
        // volume at the new pressure instead.
        if let Ok(rho) = eos.density(cell.press, m.temp) {
            mv = m.mass / rho;
        }
    }
    mv
}
