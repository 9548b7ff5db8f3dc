//! What an [`IceWorkspace`] carries from one step to the next (the rest of
//! it is scratch): the last step's Δt, which bounds the next semi-implicit
//! step's growth, and the per-material accelerations of the face velocity
//! predictor. A checkpoint saves them so that a restarted run continues
//! bit-identically.

use nalgebra::SVector;

use super::IceWorkspace;

impl<const D: usize> IceWorkspace<D> {
    /// The last accepted step's Δt (`None` before the first step).
    pub fn last_dt(&self) -> Option<f64> {
        self.last_dt
    }

    /// Per-material cell accelerations of the last step (empty unless the
    /// face velocity predictor is on).
    pub fn accelerations(&self) -> &[Vec<SVector<f64, D>>] {
        &self.accel
    }

    /// Records an accepted step's Δt (a coupled step, which runs the ICE
    /// stages itself), so that the next semi-implicit step grows from it.
    pub fn set_last_dt(&mut self, dt: f64) {
        self.last_dt = Some(dt);
    }

    /// Restores what [`Self::last_dt`] and [`Self::accelerations`] returned.
    pub fn restore_carried(&mut self, last_dt: Option<f64>, accel: Vec<Vec<SVector<f64, D>>>) {
        self.last_dt = last_dt;
        self.accel = accel;
    }
}
