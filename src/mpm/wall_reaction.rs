//! The impulse that fixed walls and symmetry planes give the particles in
//! an explicit step: the momentum term of the run's conservation account.
//!
//! The grid imposes a `Fixed` or `Symmetry` face by standing the mirror
//! image of the particles beyond it ([`crate::grid::Grid::fold_ghosts`]).
//! What the images push on the real particles is the wall's reaction. With
//! `m_i^r`, `p_i^r`, `f_i^r` the mass, momentum and force the real particles
//! put on node `i` before the fold (ghost nodes included), and `a_i`, `vᴸ_i`
//! the grid's acceleration and updated velocity (mirrored onto the ghosts),
//! the G2P update with PIC share β (Guilkey Eq. 26 blended) changes the
//! particles' momentum by
//!
//! ```text
//! ΔP = Σ_i [(1 − β) Δt m_i^r a_i + β (m_i^r vᴸ_i − p_i^r)].
//! ```
//!
//! The applied forces give `Δt Σ_i f_i^r` (the internal forces sum to zero
//! over a particle's stencil; body forces `Δt Σ_p m_p b_p`). At a node the
//! fold leaves alone, `m = m^r`, `p = p^r`, `f = f^r`, `a = f/m` and
//! `vᴸ = (p + Δt f)/m` (no damping), so the node's share of `ΔP` is exactly
//! `Δt f_i^r`: only the mirrored nodes add anything else, and that is the
//! reaction
//!
//! ```text
//! J = Σ_{i mirrored} [(1 − β) Δt (m_i^r a_i − f_i^r) + β (m_i^r vᴸ_i − p_i^r − Δt f_i^r)].
//! ```
//!
//! It is computed from the grid alone; the run summary checks it against
//! the particles' momentum change, and what is left (forces dropped on
//! nodes below the mass floor, damping) is the numerical drift.

use nalgebra::SVector;

use crate::grid::Grid;

/// The unfolded mass, momentum and force on the nodes the wall fold
/// touches, recorded by P2G before it folds. Empty (and free) on a grid
/// without `Fixed` or `Symmetry` faces.
#[derive(Debug, Clone, Default)]
pub struct WallRecord<const D: usize> {
    /// Whether `nodes` was built for the grid (built once, at the first P2G).
    built: bool,
    /// The mirrored nodes ([`Grid::mirrored_nodes`]).
    nodes: Vec<usize>,
    mass: Vec<f64>,
    momentum: Vec<SVector<f64, D>>,
    force: Vec<SVector<f64, D>>,
}

impl<const D: usize> WallRecord<D> {
    /// Builds the node list and buffers on the first call for `grid`.
    fn ensure(&mut self, grid: &Grid<D>) {
        if !self.built {
            self.nodes = grid.mirrored_nodes();
            let n = self.nodes.len();
            self.mass = vec![0.0; n];
            self.momentum = vec![SVector::zeros(); n];
            self.force = vec![SVector::zeros(); n];
            self.built = true;
        }
    }

    /// Records the particles' own nodal mass and momentum (`mass`:
    /// the first mapping of the step) and force, before the fold.
    pub(crate) fn record(
        &mut self,
        grid: &Grid<D>,
        mass: Option<(&[f64], &[SVector<f64, D>])>,
        force: Option<&[SVector<f64, D>]>,
    ) {
        self.ensure(grid);
        if let Some((m, p)) = mass {
            for (k, &i) in self.nodes.iter().enumerate() {
                self.mass[k] = m[i];
                self.momentum[k] = p[i];
            }
        }
        if let Some(f) = force {
            for (k, &i) in self.nodes.iter().enumerate() {
                self.force[k] = f[i];
            }
        }
    }

    /// `Σ_i q(m_i^r, p_i^r, i)` over every node, ghosts included, for a
    /// nodal quantity `q` of a node's mass and momentum (zero at zero
    /// mass and momentum), with the particles' own (unfolded) mass and
    /// momentum where the fold changed them (recorded) and the folded
    /// `mass` and `momentum` elsewhere: the real particles' part of a
    /// folded grid's `Σ q` (a node on a symmetry plane holds twice its
    /// real mass). Summed in node order, so independent of the thread
    /// count.
    fn real_sum<T>(
        &self,
        mass: &[f64],
        momentum: &[SVector<f64, D>],
        zero: T,
        q: impl Fn(f64, &SVector<f64, D>, usize) -> T,
    ) -> T
    where
        T: Copy + std::ops::Add<Output = T> + std::ops::Sub<Output = T>,
    {
        let mut sum = zero;
        for (i, (&m, p)) in mass.iter().zip(momentum).enumerate() {
            if m > 0.0 {
                sum = sum + q(m, p, i);
            }
        }
        if self.built {
            for (k, &i) in self.nodes.iter().enumerate() {
                sum = sum + q(self.mass[k], &self.momentum[k], i) - q(mass[i], &momentum[i], i);
            }
        }
        sum
    }

    /// `Σ_i m_i^r |v(i)|²` ([`Self::real_sum`]) for a nodal velocity `v(i)`
    /// with the ghosts mirrored.
    pub(crate) fn real_mass_weighted(
        &self,
        mass: &[f64],
        momentum: &[SVector<f64, D>],
        v: impl Fn(usize) -> SVector<f64, D>,
    ) -> f64 {
        self.real_sum(mass, momentum, 0.0, |m, _, i| m * v(i).norm_squared())
    }

    /// The momentum change the G2P update with PIC share `pic` gives the
    /// particles, from the grid: `Σ_i [(1 − β) Δt m_i^r a_i + β (m_i^r vᴸ_i
    /// − p_i^r)]` ([`Self::real_sum`]; module docs).
    pub(crate) fn particle_momentum_change(
        &self,
        mass: &[f64],
        momentum: &[SVector<f64, D>],
        accel: &[SVector<f64, D>],
        velocity_new: &[SVector<f64, D>],
        dt: f64,
        pic: f64,
    ) -> SVector<f64, D> {
        self.real_sum(mass, momentum, SVector::zeros(), |m, p, i| {
            accel[i] * ((1.0 - pic) * dt * m) + (velocity_new[i] * m - p) * pic
        })
    }

    /// The reaction `J` of the walls over a step of `dt` with PIC share
    /// `pic` (module docs), from the recorded fields and the grid's
    /// acceleration `accel` and updated velocity `velocity_new`.
    pub fn impulse(
        &self,
        accel: &[SVector<f64, D>],
        velocity_new: &[SVector<f64, D>],
        dt: f64,
        pic: f64,
    ) -> SVector<f64, D> {
        let mut j = SVector::<f64, D>::zeros();
        for (k, &i) in self.nodes.iter().enumerate() {
            let (m, p, f) = (self.mass[k], self.momentum[k], self.force[k]);
            let flip = (accel[i] * m - f) * dt;
            j += if pic > 0.0 {
                flip * (1.0 - pic) + (velocity_new[i] * m - p - f * dt) * pic
            } else {
                flip
            };
        }
        j
    }
}
