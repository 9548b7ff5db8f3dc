//! Boundary conditions on the faces of the domain, imposed through ghost
//! cells ([`super::NGHOST`] layers per side).

use nalgebra::SVector;

use super::state::{CellLayout, NGHOST};

/// Prescribed state of one material at an inflow face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InflowState<const D: usize> {
    /// Volume fraction.
    pub vol_frac: f64,
    /// True density.
    pub density: f64,
    /// Temperature.
    pub temperature: f64,
    /// Velocity.
    pub velocity: SVector<f64, D>,
}

/// Boundary condition on one face of the domain.
#[derive(Debug, Clone, PartialEq)]
pub enum IceBoundary<const D: usize> {
    /// Reflective wall: zero normal velocity on the face (face velocities
    /// are set to zero), mirrored scalars and tangential velocity, negated
    /// normal velocity in the ghosts.
    Wall,
    /// Zero-gradient outflow: ghosts copy the adjacent interior cell.
    Outflow,
    /// Prescribed inflow state, one entry per material.
    Inflow(Vec<InflowState<D>>),
    /// Periodic: ghosts copy the opposite side (both sides of the direction
    /// must be periodic).
    Periodic,
}

/// Boundary conditions per direction, `[lower, upper]`.
pub type Boundaries<const D: usize> = [[IceBoundary<D>; 2]; D];

/// Calls `f(d, side, ghost, Some(source))` for every ghost layer of every
/// boundary cell, or `f(d, side, ghost, None)` for an inflow ghost (the
/// caller supplies the value).
#[inline]
fn for_each_ghost<const D: usize>(
    layout: &CellLayout<D>,
    bcs: &Boundaries<D>,
    mut f: impl FnMut(usize, usize, usize, Option<usize>),
) {
    for d in 0..D {
        let s = layout.strides[d];
        let n = layout.cells[d];
        for side in 0..2 {
            let bc = &bcs[d][side];
            for &b in &layout.fill_cells[d][side] {
                for g in 1..=NGHOST {
                    let (ghost, src) = if side == 0 {
                        let ghost = b - g * s;
                        let src = match bc {
                            IceBoundary::Wall => Some(b + (g - 1).min(n - 1) * s),
                            IceBoundary::Outflow => Some(b),
                            IceBoundary::Periodic => Some(b + (n - 1 - (g - 1) % n) * s),
                            IceBoundary::Inflow(_) => None,
                        };
                        (ghost, src)
                    } else {
                        let ghost = b + g * s;
                        let src = match bc {
                            IceBoundary::Wall => Some(b - (g - 1).min(n - 1) * s),
                            IceBoundary::Outflow => Some(b),
                            IceBoundary::Periodic => Some(b - (n - 1) * s + ((g - 1) % n) * s),
                            IceBoundary::Inflow(_) => None,
                        };
                        (ghost, src)
                    };
                    f(d, side, ghost, src);
                }
            }
        }
    }
}

/// Fills the ghosts of a scalar field: walls and outflow mirror/copy,
/// periodic copies the opposite side, inflow takes `inflow(states)`.
pub fn fill_scalar<const D: usize>(
    layout: &CellLayout<D>,
    bcs: &Boundaries<D>,
    field: &mut [f64],
    inflow: impl Fn(&[InflowState<D>]) -> f64,
) {
    for_each_ghost(layout, bcs, |d, side, ghost, src| {
        field[ghost] = match src {
            Some(s) => field[s],
            None => match &bcs[d][side] {
                IceBoundary::Inflow(states) => inflow(states),
                _ => unreachable!("only inflow ghosts have no source"),
            },
        };
    });
}

/// Fills the ghosts of a velocity field: the normal component is negated at
/// walls; inflow takes `inflow(states)`.
pub fn fill_vector<const D: usize>(
    layout: &CellLayout<D>,
    bcs: &Boundaries<D>,
    field: &mut [SVector<f64, D>],
    inflow: impl Fn(&[InflowState<D>]) -> SVector<f64, D>,
) {
    for_each_ghost(layout, bcs, |d, side, ghost, src| {
        field[ghost] = match src {
            Some(s) => {
                let mut v = field[s];
                if bcs[d][side] == IceBoundary::Wall {
                    v[d] = -v[d];
                }
                v
            }
            None => match &bcs[d][side] {
                IceBoundary::Inflow(states) => inflow(states),
                _ => unreachable!("only inflow ghosts have no source"),
            },
        };
    });
}

/// Sets the face values on wall faces to zero (zero normal velocity).
pub fn zero_wall_faces<const D: usize>(
    layout: &CellLayout<D>,
    bcs: &Boundaries<D>,
    d: usize,
    faces: &mut [f64],
) {
    let s = layout.strides[d];
    if bcs[d][0] == IceBoundary::Wall {
        for &b in &layout.boundary_cells[d][0] {
            faces[b] = 0.0;
        }
    }
    if bcs[d][1] == IceBoundary::Wall {
        for &b in &layout.boundary_cells[d][1] {
            faces[b + s] = 0.0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ghosts_follow_the_boundary_kind() {
        let layout =
            CellLayout::<1>::new(SVector::<f64, 1>::zeros(), SVector::<f64, 1>::new(1.0), [4])
                .unwrap();
        let vals = [1.0, 2.0, 3.0, 4.0];
        let mut f = vec![0.0; layout.len()];
        for (k, v) in vals.iter().enumerate() {
            f[layout.index([k as isize])] = *v;
        }
        let bcs = [[IceBoundary::Wall, IceBoundary::Periodic]];
        fill_scalar(&layout, &bcs, &mut f, |_| 0.0);
        assert_eq!(f[layout.index([-1])], 1.0);
        assert_eq!(f[layout.index([-2])], 2.0);
        assert_eq!(f[layout.index([4])], 1.0);
        assert_eq!(f[layout.index([5])], 2.0);
        let bcs = [[IceBoundary::Periodic, IceBoundary::Outflow]];
        fill_scalar(&layout, &bcs, &mut f, |_| 0.0);
        assert_eq!(f[layout.index([-1])], 4.0);
        assert_eq!(f[layout.index([-2])], 3.0);
        assert_eq!(f[layout.index([5])], 4.0);
        let mut v = vec![SVector::<f64, 1>::zeros(); layout.len()];
        v[layout.index([0])] = SVector::<f64, 1>::new(2.0);
        let bcs = [[IceBoundary::Wall, IceBoundary::Wall]];
        fill_vector(&layout, &bcs, &mut v, |_| SVector::zeros());
        assert_eq!(v[layout.index([-1])][0], -2.0);
    }
}
