//! The volume fluxes of Guilkey Eq. 29 (`Δp = −Δt Σ_r ∇·(θu*)_r / Σ_r θ_r
//! κ_r`) from the face velocities: per face the mixture volume flux, per
//! cell each material's divergence `∇·(θu*)_r`, its compressibility `κ_r`
//! and the sums over the materials. Shared by the explicit pressure
//! ([`super::pressure`]) and the semi-implicit one ([`super::implicit`]).

use super::advection::{net_inflow, scalar_fluxes};
use super::par::{par_face_rows, par_rows, Out};
use super::params::IceParams;
use super::state::IceState;
use super::workspace::IceWorkspace;
use crate::material::eos::EquationOfState;

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
    let inv_dt = 1.0 / dt;

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
                let dv = -net_inflow(layout, tf, c) * inv_dt;
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
