//! Multi-material ICE (explicit or semi-implicit pressure) as a model of the
//! run loop.

use crate::driver::model::{
    Conserved, Counts, Description, DtRequest, FieldSet, Model, StepStats, Violation,
};
use crate::driver::models::arrays::{
    cell_energies, cell_fields, cell_material_totals, cell_watchdog, load_cells, save_cells,
};
use crate::error::Error;
use crate::ice::{self, IceParams, IceState, IceWorkspace};
use crate::output::checkpoint::{Checkpoint, CheckpointError};

/// A fluid-only ICE run: the state, its parameters and its workspace.
pub struct Fluid<const D: usize> {
    /// Cell state (equilibrated at build).
    pub state: IceState<D>,
    /// Scheme parameters.
    pub params: IceParams<D>,
    /// Step buffers and the carried Δt / predictor accelerations.
    pub ws: IceWorkspace<D>,
}

/// Fluid energies and mass as history columns.
pub(crate) const FLUID_HISTORY: [(&str, &str); 4] = [
    ("mass", "kg"),
    ("kinetic", "J"),
    ("internal", "J"),
    ("total", "J"),
];

/// A history row of an ICE state: mass, kinetic, internal and total energy.
pub(crate) fn fluid_history_row<const D: usize>(s: &IceState<D>, row: &mut Vec<f64>) {
    let e = cell_energies(s);
    let (mass, _, _) = s.totals();
    row.extend([mass, e.kinetic, e.strain, e.kinetic + e.strain]);
}

/// `Σ m |u|` over the interior cells of ICE materials `materials`.
pub(crate) fn cell_momentum_scale<const D: usize>(
    s: &IceState<D>,
    materials: std::ops::Range<usize>,
) -> f64 {
    s.cells[materials]
        .iter()
        .map(|mc| {
            s.layout
                .interior
                .iter()
                .map(|&c| mc.mass[c] * mc.velocity[c].norm())
                .sum::<f64>()
        })
        .sum()
}

/// Saves the workspace's carried part under `prefix`.
pub(crate) fn save_carried<const D: usize>(
    ck: &mut Checkpoint,
    prefix: &str,
    ws: &IceWorkspace<D>,
) {
    let last = ws.last_dt();
    ck.put_f64(
        &format!("{prefix}.last_dt"),
        vec![1],
        vec![last.unwrap_or(0.0)],
    );
    ck.put_u64(
        &format!("{prefix}.has_last_dt"),
        vec![1],
        vec![last.is_some() as u64],
    );
    let acc = ws.accelerations();
    ck.put_u64(
        &format!("{prefix}.accel_count"),
        vec![1],
        vec![acc.len() as u64],
    );
    for (r, a) in acc.iter().enumerate() {
        crate::driver::models::arrays::put_vectors(ck, &format!("{prefix}.accel.m{r}"), a);
    }
}

/// Restores what [`save_carried`] saved.
pub(crate) fn load_carried<const D: usize>(
    ck: &mut Checkpoint,
    prefix: &str,
    ws: &mut IceWorkspace<D>,
    cells: usize,
) -> Result<(), CheckpointError> {
    let last = ck.take_f64(&format!("{prefix}.last_dt"), Some(&[1]))?[0];
    let has = ck.take_u64(&format!("{prefix}.has_last_dt"), Some(&[1]))?[0] != 0;
    let count = ck.take_u64(&format!("{prefix}.accel_count"), Some(&[1]))?[0] as usize;
    let mut accel = Vec::with_capacity(count);
    for r in 0..count {
        accel.push(crate::driver::models::arrays::take_vectors(
            ck,
            &format!("{prefix}.accel.m{r}"),
            cells,
        )?);
    }
    ws.restore_carried(has.then_some(last), accel);
    Ok(())
}

impl<const D: usize> Model for Fluid<D> {
    fn kind(&self) -> String {
        format!("ice_{D}d")
    }

    fn time(&self) -> f64 {
        self.state.time
    }

    fn steps(&self) -> u64 {
        self.state.steps
    }

    fn stable_dt(&self) -> f64 {
        ice::timestep(&self.state, self.params.cfl)
    }

    fn step(&mut self, dt: DtRequest) -> Result<StepStats, Error> {
        let info = if dt.exact {
            ice::step_with_dt(&mut self.state, &self.params, &mut self.ws, dt.value)?
        } else {
            ice::step(&mut self.state, &self.params, &mut self.ws, dt.value)?
        };
        Ok(StepStats {
            dt: info.dt,
            nonlinear_iterations: info.outer_iterations,
            linear_iterations: info.linear_iterations,
            retries: 0,
            boundary: Some(self.ws.boundary_exchange()),
        })
    }

    fn field_sets(&self) -> Vec<FieldSet<'_>> {
        vec![cell_fields(&self.state)]
    }

    fn history_columns(&self) -> Vec<(&'static str, &'static str)> {
        FLUID_HISTORY.to_vec()
    }

    fn history_row(&self, row: &mut Vec<f64>) {
        fluid_history_row(&self.state, row);
    }

    fn conserved(&self) -> Conserved {
        let s = &self.state;
        Conserved {
            materials: (0..s.num_materials())
                .map(|r| cell_material_totals(s, r))
                .collect(),
            energies: cell_energies(s),
            momentum_scale: cell_momentum_scale(s, 0..s.num_materials()),
        }
    }

    fn watchdog(&self) -> Option<Violation> {
        cell_watchdog(&self.state)
    }

    fn save(&self, ck: &mut Checkpoint) {
        save_cells(ck, "cells", &self.state);
        save_carried(ck, "workspace", &self.ws);
    }

    fn load(&mut self, ck: &mut Checkpoint) -> Result<(), CheckpointError> {
        load_cells(ck, "cells", &mut self.state)?;
        load_carried(ck, "workspace", &mut self.ws, self.state.layout.len())
    }

    fn counts(&self) -> Counts {
        Counts {
            particles: 0,
            cells: self.state.layout.num_interior(),
            fluid_materials: self.state.num_materials(),
            elements: 0,
        }
    }

    fn dt_limiter(&self) -> Option<crate::driver::limiter::DtLimiter> {
        crate::driver::limiter::cell_limiter(&self.state, 0..self.state.materials.len())
    }

    fn describe(&self) -> Description {
        Description {
            iterative: self.params.implicit.is_some(),
            momentum_conserved: true,
            ..Default::default()
        }
    }
}
