//! Per-material cell state (struct of arrays), the cell layout with ghost
//! layers, and the construction of an initial state.

use nalgebra::SVector;

use super::{invalid, IceError, IceMaterial, MAX_MATERIALS};
use crate::grid::Grid;
use crate::material::eos::EquationOfState;

/// Ghost cell layers on each side of the domain: the second-order
/// reconstruction of a donor ghost cell needs one more layer beyond it.
pub const NGHOST: usize = 2;

/// Cell indexing of the ICE fields: `cells + 2 NGHOST` cells per direction,
/// flat index x fastest. Interior coordinates run `0..cells[d]`; ghosts have
/// negative or `≥ cells[d]` coordinates.
///
/// Faces normal to direction `d` are stored at the flat index of the cell on
/// their upper side: the lower face of cell `c` is `c`, its upper face
/// `c + strides[d]`.
#[derive(Debug, Clone)]
pub struct CellLayout<const D: usize> {
    /// Interior cells per direction.
    pub cells: [usize; D],
    /// Cells per direction including ghosts.
    pub dims: [usize; D],
    /// Flat-index stride per direction.
    pub strides: [usize; D],
    /// Lower corner of the domain.
    pub lower: SVector<f64, D>,
    /// Cell size per direction.
    pub h: SVector<f64, D>,
    /// Flat indices of the interior cells, in order.
    pub interior: Vec<usize>,
    /// Per direction: flat indices of the faces bounding interior cells.
    pub faces: [Vec<usize>; D],
    /// Per direction and side (`0` lower, `1` upper): the interior cells
    /// adjacent to that domain face.
    pub boundary_cells: [[Vec<usize>; 2]; D],
    /// Per direction and side: the cells whose ghost neighbours in `d` the
    /// boundary fill sets, i.e. the cells next to that domain face that are
    /// interior in the directions after `d` and interior or ghost in the
    /// directions before `d` (filling the directions in order then fills the
    /// corner ghosts as well, consistently with both boundaries).
    pub fill_cells: [[Vec<usize>; 2]; D],
    /// Flat index of the first cell of every interior x-row (a row is
    /// `cells[0]` consecutive flat indices); the unit of parallel work.
    pub rows: Vec<usize>,
    /// Per direction `d`: flat index of the first face of every x-row of the
    /// faces normal to `d` (`cells[0] + 1` faces per row for `d = 0`,
    /// `cells[0]` otherwise).
    pub face_rows: [Vec<usize>; D],
}

impl<const D: usize> CellLayout<D> {
    /// Builds the layout of a box `[lower, lower + cells h]`.
    ///
    /// # Errors
    /// [`IceError::InvalidInput`] for zero cells or a non-positive or
    /// non-finite cell size, or `D` not in `1..=3`.
    pub fn new(
        lower: SVector<f64, D>,
        h: SVector<f64, D>,
        cells: [usize; D],
    ) -> Result<Self, IceError> {
        if !(1..=3).contains(&D) {
            return Err(invalid("dim", format!("must be 1, 2 or 3, got {D}")));
        }
        for d in 0..D {
            if cells[d] == 0 {
                return Err(invalid(format!("cells[{d}]"), "must be >= 1"));
            }
            if !(h[d].is_finite() && h[d] > 0.0) {
                return Err(invalid(
                    format!("h[{d}]"),
                    format!("must be finite and > 0, got {}", h[d]),
                ));
            }
            if !lower[d].is_finite() {
                return Err(invalid(format!("lower[{d}]"), "must be finite"));
            }
        }
        let dims: [usize; D] = std::array::from_fn(|d| cells[d] + 2 * NGHOST);
        let mut strides = [1usize; D];
        for d in 1..D {
            strides[d] = strides[d - 1] * dims[d - 1];
        }
        let total: usize = dims.iter().product();
        let mut interior = Vec::with_capacity(cells.iter().product());
        let mut faces: [Vec<usize>; D] = std::array::from_fn(|_| Vec::new());
        let mut boundary_cells: [[Vec<usize>; 2]; D] =
            std::array::from_fn(|_| [Vec::new(), Vec::new()]);
        let mut fill_cells: [[Vec<usize>; 2]; D] =
            std::array::from_fn(|_| [Vec::new(), Vec::new()]);
        let mut rows = Vec::new();
        let mut face_rows: [Vec<usize>; D] = std::array::from_fn(|_| Vec::new());
        let within = |i: isize, n: usize| i >= 0 && i < n as isize;
        for c in 0..total {
            let ijk = coords_of(c, &dims);
            let inside = (0..D).all(|d| within(ijk[d], cells[d]));
            if inside {
                interior.push(c);
                if ijk[0] == 0 {
                    rows.push(c);
                }
            }
            for d in 0..D {
                // Faces normal to d: ijk[d] in 0..=cells[d], others interior.
                let others = (0..D).filter(|&e| e != d).all(|e| within(ijk[e], cells[e]));
                if others && ijk[0] == 0 && ijk[d] >= 0 && ijk[d] <= cells[d] as isize {
                    face_rows[d].push(c);
                }
                let fill = (0..D).all(|e| e <= d || within(ijk[e], cells[e]));
                if fill {
                    if ijk[d] == 0 {
                        fill_cells[d][0].push(c);
                    }
                    if ijk[d] == cells[d] as isize - 1 {
                        fill_cells[d][1].push(c);
                    }
                }
            }
            for d in 0..D {
                let others = (0..D)
                    .filter(|&e| e != d)
                    .all(|e| ijk[e] >= 0 && ijk[e] < cells[e] as isize);
                if others && ijk[d] >= 0 && ijk[d] <= cells[d] as isize {
                    faces[d].push(c);
                }
                if inside && ijk[d] == 0 {
                    boundary_cells[d][0].push(c);
                }
                if inside && ijk[d] == cells[d] as isize - 1 {
                    boundary_cells[d][1].push(c);
                }
            }
        }
        Ok(Self {
            cells,
            dims,
            strides,
            lower,
            h,
            interior,
            faces,
            boundary_cells,
            fill_cells,
            rows,
            face_rows,
        })
    }

    /// The layout of a [`Grid`]'s cells (geometry only: lower corner, cell
    /// size, cell counts).
    ///
    /// # Errors
    /// As [`CellLayout::new`].
    pub fn from_grid(grid: &Grid<D>) -> Result<Self, IceError> {
        Self::new(grid.lower, grid.h, grid.cells)
    }

    /// Number of cells including ghosts (length of every field array).
    pub fn len(&self) -> usize {
        self.dims.iter().product()
    }

    /// `true` when the layout has no cells (never, by construction).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of interior cells.
    pub fn num_interior(&self) -> usize {
        self.interior.len()
    }

    /// Flat index of the cell with coordinates `ijk` (ghosts allowed).
    #[inline]
    pub fn index(&self, ijk: [isize; D]) -> usize {
        let mut c = 0usize;
        for d in 0..D {
            c += (ijk[d] + NGHOST as isize) as usize * self.strides[d];
        }
        c
    }

    /// Coordinates of a flat index (inverse of [`CellLayout::index`]).
    pub fn coords(&self, c: usize) -> [isize; D] {
        coords_of(c, &self.dims)
    }

    /// Centre of a cell.
    pub fn centre(&self, c: usize) -> SVector<f64, D> {
        let ijk = self.coords(c);
        SVector::<f64, D>::from_fn(|d, _| self.lower[d] + (ijk[d] as f64 + 0.5) * self.h[d])
    }

    /// Volume of one cell.
    pub fn cell_volume(&self) -> f64 {
        self.h.iter().product()
    }
}

fn coords_of<const D: usize>(mut c: usize, dims: &[usize; D]) -> [isize; D] {
    let mut ijk = [0isize; D];
    for d in 0..D {
        ijk[d] = (c % dims[d]) as isize - NGHOST as isize;
        c /= dims[d];
    }
    ijk
}

/// The cell fields of one fluid material (struct of arrays, ghosts
/// included, length [`CellLayout::len`]).
#[derive(Debug, Clone)]
pub struct MaterialCells<const D: usize> {
    /// Mass `M_r` in the cell.
    pub mass: Vec<f64>,
    /// Velocity `u_r` (momentum is `M_r u_r`).
    pub velocity: Vec<SVector<f64, D>>,
    /// Temperature `T_r`; the specific internal energy is `e_r = c_v T_r`
    /// (Guilkey Eq. 10).
    pub temperature: Vec<f64>,
    /// Specific volume `v_r = 1/ρ_r` (true density), Guilkey Eq. 11.
    pub sp_vol: Vec<f64>,
    /// Volume fraction `θ_r = ρ̂_r v_r` (Guilkey Eq. 12).
    pub vol_frac: Vec<f64>,
}

impl<const D: usize> MaterialCells<D> {
    fn zeros(n: usize) -> Self {
        Self {
            mass: vec![0.0; n],
            velocity: vec![SVector::zeros(); n],
            temperature: vec![0.0; n],
            sp_vol: vec![0.0; n],
            vol_frac: vec![0.0; n],
        }
    }
}

/// Initial state of one material at a point: volume fraction, true density,
/// pressure and velocity (the temperature follows from the EOS).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialInit<const D: usize> {
    /// Volume fraction `θ_r` (the fractions of a cell must sum to 1).
    pub vol_frac: f64,
    /// True (material) density `ρ_r = 1/v_r`.
    pub density: f64,
    /// Pressure (all materials of a cell must be at the same pressure).
    pub pressure: f64,
    /// Velocity.
    pub velocity: SVector<f64, D>,
}

impl<const D: usize> MaterialInit<D> {
    /// A material state.
    pub fn new(vol_frac: f64, density: f64, pressure: f64, velocity: SVector<f64, D>) -> Self {
        Self {
            vol_frac,
            density,
            pressure,
            velocity,
        }
    }
}

/// Temperature with `p(ρ, T) = p` for an EOS linear in `T` at fixed `ρ`
/// (every [`crate::material::eos::FluidEos`] variant is), checked.
pub(crate) fn temperature_from_rho_p(eos: &impl EquationOfState, rho: f64, p: f64) -> f64 {
    let t0 = 1.0;
    let t = t0 + (p - eos.pressure(rho, t0)) / eos.dp_dt(rho, t0);
    // One Newton correction removes round-off of the linear extrapolation.
    t + (p - eos.pressure(rho, t)) / eos.dp_dt(rho, t)
}

/// The complete ICE fluid state.
#[derive(Debug, Clone)]
pub struct IceState<const D: usize> {
    /// Cell indexing.
    pub layout: CellLayout<D>,
    /// The fluid materials.
    pub materials: Vec<IceMaterial>,
    /// Per-material cell fields.
    pub cells: Vec<MaterialCells<D>>,
    /// Equilibration pressure `p_eq` (Guilkey Eq. 13) of the last step.
    pub p_eq: Vec<f64>,
    /// Time-advanced pressure `p = p_eq + Δp` (Guilkey Eq. 30) of the last
    /// step.
    pub pressure: Vec<f64>,
    /// Current time.
    pub time: f64,
    /// Steps taken.
    pub steps: u64,
}

impl<const D: usize> IceState<D> {
    /// Builds a state by sampling `init(x)` at every cell centre; `init`
    /// returns one [`MaterialInit`] per material.
    ///
    /// # Errors
    /// [`IceError::InvalidInput`] for no or too many materials, a wrong
    /// number of entries returned by `init`, non-positive density, a
    /// negative or non-finite volume fraction, fractions not summing to 1
    /// (to 1e-12), unequal pressures in a cell, or a non-positive
    /// temperature.
    pub fn new(
        layout: CellLayout<D>,
        materials: Vec<IceMaterial>,
        init: impl Fn(&SVector<f64, D>) -> Vec<MaterialInit<D>>,
    ) -> Result<Self, IceError> {
        let nm = materials.len();
        if nm == 0 || nm > MAX_MATERIALS {
            return Err(invalid(
                "materials",
                format!("need 1..={MAX_MATERIALS} materials, got {nm}"),
            ));
        }
        let n = layout.len();
        let vol = layout.cell_volume();
        let mut cells: Vec<MaterialCells<D>> = (0..nm).map(|_| MaterialCells::zeros(n)).collect();
        let mut p_eq = vec![0.0; n];
        for &c in &layout.interior {
            let x = layout.centre(c);
            let states = init(&x);
            let at = || format!("initial state at cell {:?}", layout.coords(c));
            if states.len() != nm {
                return Err(invalid(
                    at(),
                    format!("expected {nm} material states, got {}", states.len()),
                ));
            }
            let sum: f64 = states.iter().map(|s| s.vol_frac).sum();
            if (sum - 1.0).abs() > 1e-12 {
                return Err(invalid(
                    at(),
                    format!("volume fractions sum to {sum}, not 1"),
                ));
            }
            let p0 = states[0].pressure;
            for (r, s) in states.iter().enumerate() {
                if !(s.vol_frac.is_finite() && s.vol_frac > 0.0) {
                    return Err(invalid(
                        at(),
                        format!(
                            "material `{}`: vol_frac must be finite and > 0, got {}",
                            materials[r].name, s.vol_frac
                        ),
                    ));
                }
                if !(s.density.is_finite() && s.density > 0.0) {
                    return Err(invalid(
                        at(),
                        format!(
                            "material `{}`: density must be finite and > 0, got {}",
                            materials[r].name, s.density
                        ),
                    ));
                }
                if !s.pressure.is_finite() || (s.pressure - p0).abs() > 1e-12 * p0.abs().max(1.0) {
                    return Err(invalid(
                        at(),
                        format!(
                            "material `{}`: pressure {} differs from {p0}",
                            materials[r].name, s.pressure
                        ),
                    ));
                }
                if !s.velocity.iter().all(|v| v.is_finite()) {
                    return Err(invalid(
                        at(),
                        format!("material `{}`: velocity must be finite", materials[r].name),
                    ));
                }
                let eos = &materials[r].eos;
                let t = temperature_from_rho_p(eos, s.density, s.pressure);
                if !(t.is_finite() && t > 0.0) {
                    return Err(invalid(
                        at(),
                        format!(
                            "material `{}`: temperature from (rho, p) is {t}, must be > 0",
                            materials[r].name
                        ),
                    ));
                }
                let mc = &mut cells[r];
                mc.mass[c] = s.vol_frac * s.density * vol;
                mc.velocity[c] = s.velocity;
                mc.temperature[c] = t;
                mc.sp_vol[c] = 1.0 / s.density;
                mc.vol_frac[c] = s.vol_frac;
            }
            p_eq[c] = p0;
        }
        Ok(Self {
            layout,
            materials,
            cells,
            pressure: p_eq.clone(),
            p_eq,
            time: 0.0,
            steps: 0,
        })
    }

    /// Appends a material with empty cells (zero mass, velocity,
    /// temperature, specific volume and volume fraction) for a caller that
    /// fills them itself (the solid field of a coupled scene).
    pub fn push_material(&mut self, material: IceMaterial) {
        self.materials.push(material);
        self.cells.push(MaterialCells::zeros(self.layout.len()));
    }

    /// Number of materials.
    pub fn num_materials(&self) -> usize {
        self.materials.len()
    }

    /// Mixture bulk density `Σ_r M_r / V` of a cell.
    pub fn mixture_density(&self, c: usize) -> f64 {
        let v = self.layout.cell_volume();
        self.cells.iter().map(|m| m.mass[c]).sum::<f64>() / v
    }

    /// Totals over the interior cells: mass, momentum and total energy
    /// `Σ M (e + |u|²/2)`, summed in cell order (deterministic).
    pub fn totals(&self) -> (f64, SVector<f64, D>, f64) {
        let mut mass = 0.0;
        let mut mom = SVector::<f64, D>::zeros();
        let mut energy = 0.0;
        for (mat, mc) in self.materials.iter().zip(&self.cells) {
            let cv = mat.eos.specific_heat_cv();
            for &c in &self.layout.interior {
                let m = mc.mass[c];
                mass += m;
                mom += mc.velocity[c] * m;
                energy += m * (cv * mc.temperature[c] + 0.5 * mc.velocity[c].norm_squared());
            }
        }
        (mass, mom, energy)
    }
}
