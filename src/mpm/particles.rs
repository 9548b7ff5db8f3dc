//! Particle state as a struct of arrays.

use nalgebra::{Matrix3, SVector};

use super::tensors::{Stresses, Tensors};
use crate::material::SolidMaterial;

/// Material points of every solid material in a scene.
#[derive(Debug, Clone, Default)]
pub struct Particles<const D: usize> {
    /// Current position x_p.
    pub x: Vec<SVector<f64, D>>,
    /// Reference (initial) position X_p.
    pub x0: Vec<SVector<f64, D>>,
    /// Velocity v_p.
    pub v: Vec<SVector<f64, D>>,
    /// Mass m_p.
    pub mass: Vec<f64>,
    /// Reference volume V_p⁰.
    pub vol0: Vec<f64>,
    /// Current volume V_p = J V_p⁰.
    pub vol: Vec<f64>,
    /// Initial half-size per direction (physical units): the particle
    /// domain of GIMP and CPDI-like kernels, contact and the rigid volume.
    pub half_size: HalfSizes<D>,
    /// Deformation gradient F (3×3; plane strain / uniaxial strain in 2D/1D,
    /// stored without the entries those keep zero).
    pub f: Tensors<D>,
    /// Cauchy stress σ (3×3, symmetric: stored as [`Particles::f`] without
    /// the lower triangle).
    pub stress: Stresses<D>,
    /// Accumulated stress work per unit reference volume (rate models,
    /// Hencky, membranes; a gas point's ρ_ref e): empty unless a run's
    /// materials read it ([`SolidMaterial::reads_work`]; every model but
    /// neo-Hookean, whose energy is a function of F), then one per particle
    /// ([`Particles::track_work`]; read it with [`Particles::work_of`]).
    /// An elastic neo-Hookean run saves 8 bytes a particle (issue 24).
    pub work: Vec<f64>,
    /// Index into the scene's solid materials.
    pub material: Vec<u16>,
    /// Temperature T_p \[K\]: empty unless a run changes it, then one per
    /// particle ([`Particles::track_temperature`]; read it with
    /// [`Particles::temperature_of`]). The solid–fluid heat exchange of a
    /// coupled run (Guilkey Sec. 3.3 step 10: the exchange's change goes
    /// from the cells to the nodes and then to the particles) and plastic
    /// heating change it; elsewhere every particle is at
    /// [`Particles::INITIAL_TEMPERATURE`], and storing that would cost 8
    /// bytes a particle for nothing (issue 24).
    pub temperature: Vec<f64>,
    /// Equivalent plastic strain ε̄: empty unless a material is plastic,
    /// then one per particle (0 for elastic materials; the explicit step
    /// sizes it at its first step).
    pub plastic_strain: Vec<f64>,
    /// Damage D ∈ [0, 1] (1: failed; [`crate::material::failure`]): empty
    /// unless a material has a failure model, then one per particle (the
    /// explicit step sizes it at its first step; 0 for materials without
    /// failure).
    pub damage: Vec<f64>,
    /// A particle's identity: its index in the order the scene created the
    /// particles, kept when particles are removed (burnt out) or split into
    /// solid fields, so that outputs of different times can be matched.
    /// Empty while every particle's id is its index (nothing removed or
    /// reordered yet): storing those would cost 8 bytes a particle, twice
    /// with the watchdog's copy (issue 24). Read it with
    /// [`Particles::id_of`].
    pub id: Vec<u64>,
}

impl<const D: usize> Particles<D> {
    /// Temperature a particle gets from [`Particles::push`] \[K\].
    pub const INITIAL_TEMPERATURE: f64 = 300.0;

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Appends one particle at rest in its reference configuration.
    #[allow(clippy::too_many_arguments)]
    pub fn push(
        &mut self,
        x: SVector<f64, D>,
        v: SVector<f64, D>,
        mass: f64,
        vol: f64,
        half_size: SVector<f64, D>,
        material: u16,
    ) {
        self.x.push(x);
        self.x0.push(x);
        self.v.push(v);
        self.mass.push(mass);
        self.vol0.push(vol);
        self.vol.push(vol);
        self.half_size.push(half_size);
        self.f.push(&Matrix3::identity());
        self.stress.push(&Matrix3::zeros());
        self.material.push(material);
        for (v, value) in [
            (&mut self.work, 0.0),
            (&mut self.temperature, Self::INITIAL_TEMPERATURE),
            (&mut self.plastic_strain, 0.0),
            (&mut self.damage, 0.0),
        ] {
            if !v.is_empty() {
                v.push(value);
            }
        }
        // Implicit ids stay implicit: the new particle's id is its index.
        if let Some(&last) = self.id.last() {
            self.id.push(last + 1);
        }
    }

    /// Id of particle `p` ([`Particles::id`]).
    #[inline]
    pub fn id_of(&self, p: usize) -> u64 {
        self.id.get(p).copied().unwrap_or(p as u64)
    }

    /// Stores the implicit ids (each particle's index) of the first `n`
    /// particles, before an operation that breaks index = id.
    fn store_ids(&mut self, n: usize) {
        if self.id.is_empty() {
            self.id.extend(0..n as u64);
        }
    }

    /// Makes room for exactly `n` more particles in every array (no
    /// doubling slack).
    pub fn reserve_exact(&mut self, n: usize) {
        self.for_each_array(|v| v.reserve_exact(n));
    }

    /// Drops every array's unused capacity.
    pub fn shrink_to_fit(&mut self) {
        self.for_each_array(|v| v.shrink_to_fit());
    }

    /// Applies `op` to every per-particle array (temperature, plastic strain
    /// and damage only where tracked).
    fn for_each_array(&mut self, mut op: impl FnMut(&mut dyn ParticleArray)) {
        op(&mut self.x);
        op(&mut self.x0);
        op(&mut self.v);
        op(&mut self.mass);
        op(&mut self.vol0);
        op(&mut self.vol);
        op(&mut self.half_size);
        op(&mut self.f);
        op(&mut self.stress);
        op(&mut self.material);
        for v in [
            &mut self.work,
            &mut self.temperature,
            &mut self.plastic_strain,
            &mut self.damage,
        ] {
            if !v.is_empty() {
                op(v);
            }
        }
        if !self.id.is_empty() {
            op(&mut self.id);
        }
    }

    /// Sizes [`Particles::temperature`] to one entry per particle (new
    /// entries at [`Particles::INITIAL_TEMPERATURE`]); a no-op when it is
    /// sized already.
    pub fn track_temperature(&mut self) {
        if self.temperature.len() != self.len() {
            self.temperature
                .resize(self.len(), Self::INITIAL_TEMPERATURE);
        }
    }

    /// Sizes [`Particles::work`] to one entry per particle (new entries 0);
    /// a no-op when it is sized already.
    pub fn track_work(&mut self) {
        if self.work.len() != self.len() {
            self.work.resize(self.len(), 0.0);
        }
    }

    /// Sizes [`Particles::work`] where one of `materials` reads it.
    pub fn track_work_for(&mut self, materials: &[SolidMaterial]) {
        if materials.iter().any(SolidMaterial::reads_work) {
            self.track_work();
        }
    }

    /// Stress work of particle `p` (tracked or not: 0 where not).
    #[inline]
    pub fn work_of(&self, p: usize) -> f64 {
        self.work.get(p).copied().unwrap_or(0.0)
    }

    /// Sizes [`Particles::plastic_strain`] to one entry per particle (new
    /// entries 0); a no-op when it is sized already.
    pub fn track_plastic_strain(&mut self) {
        if self.plastic_strain.len() != self.len() {
            self.plastic_strain.resize(self.len(), 0.0);
        }
    }

    /// Temperature of particle `p` (tracked or not).
    #[inline]
    pub fn temperature_of(&self, p: usize) -> f64 {
        self.temperature
            .get(p)
            .copied()
            .unwrap_or(Self::INITIAL_TEMPERATURE)
    }

    /// Equivalent plastic strain of particle `p` (tracked or not).
    #[inline]
    pub fn plastic_strain_of(&self, p: usize) -> f64 {
        self.plastic_strain.get(p).copied().unwrap_or(0.0)
    }

    /// Sizes [`Particles::damage`] to one entry per particle (new entries
    /// undamaged); a no-op when it is sized already.
    pub fn track_damage(&mut self) {
        if self.damage.len() != self.len() {
            self.damage.resize(self.len(), 0.0);
        }
    }

    /// Damage of particle `p` (tracked or not).
    #[inline]
    pub fn damage_of(&self, p: usize) -> f64 {
        self.damage.get(p).copied().unwrap_or(0.0)
    }

    /// Whether particle `p` has failed (damage 1).
    #[inline]
    pub fn failed(&self, p: usize) -> bool {
        self.damage_of(p) >= 1.0
    }

    /// The particles `p` with `keep(p)`, in order (a new set).
    pub fn select(&self, keep: impl Fn(usize) -> bool) -> Self {
        let mut out = Self::default();
        for p in (0..self.len()).filter(|&p| keep(p)) {
            out.push_copy(self, p);
        }
        out
    }

    /// Keeps the particles `p` with `keep[p]`, in order, in place (no
    /// allocation).
    pub fn retain(&mut self, keep: &[bool]) {
        if keep.iter().any(|&k| !k) {
            self.store_ids(self.len());
        }
        self.for_each_array(|v| v.retain_by(keep));
    }

    /// Appends copies of all of `other`'s particles.
    pub fn append(&mut self, other: &Self) {
        for p in 0..other.len() {
            self.push_copy(other, p);
        }
    }

    /// Appends a copy of particle `p` of `other` (every field).
    fn push_copy(&mut self, other: &Self, p: usize) {
        self.x.push(other.x[p]);
        self.x0.push(other.x0[p]);
        self.v.push(other.v[p]);
        self.mass.push(other.mass[p]);
        self.vol0.push(other.vol0[p]);
        self.vol.push(other.vol[p]);
        self.half_size.push(other.half_size.get(p));
        self.f.push(&other.f.get(p));
        self.stress.push(&other.stress.get(p));
        self.material.push(other.material[p]);
        let before = self.len() - 1;
        for (v, src, untracked) in [
            (
                &mut self.temperature,
                &other.temperature,
                Self::INITIAL_TEMPERATURE,
            ),
            (&mut self.plastic_strain, &other.plastic_strain, 0.0),
            (&mut self.work, &other.work, 0.0),
            (&mut self.damage, &other.damage, 0.0),
        ] {
            // Keep each optional array empty or full: size it before the
            // first tracked copy.
            if !src.is_empty() {
                v.resize(before, untracked);
                v.push(src[p]);
            } else if !v.is_empty() {
                v.push(untracked);
            }
        }
        let id = other.id_of(p);
        if id != before as u64 || !self.id.is_empty() {
            self.store_ids(before);
            self.id.push(id);
        }
    }

    /// Total mass.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// `Σ m_p |v_p|`: the scale of a momentum drift.
    pub fn momentum_scale(&self) -> f64 {
        self.mass
            .iter()
            .zip(&self.v)
            .map(|(m, v)| m * v.norm())
            .sum()
    }

    /// Total linear momentum Σ m_p v_p.
    pub fn momentum(&self) -> SVector<f64, D> {
        self.mass
            .iter()
            .zip(&self.v)
            .fold(SVector::zeros(), |acc, (m, v)| acc + *m * v)
    }

    /// Kinetic energy Σ ½ m_p |v_p|².
    pub fn kinetic_energy(&self) -> f64 {
        kinetic_energy(&self.mass, &self.v)
    }

    /// Strain energy Σ V_p⁰ W(F_p).
    pub fn strain_energy(&self, materials: &[SolidMaterial]) -> f64 {
        (0..self.len())
            .map(|p| {
                self.vol0[p]
                    * materials[self.material[p] as usize]
                        .strain_energy_density(&self.f.get(p), self.work_of(p))
            })
            .sum()
    }

    /// Potential energy of a uniform body force g: −Σ m_p g·x_p.
    pub fn potential_energy(&self, g: &SVector<f64, D>) -> f64 {
        -self
            .mass
            .iter()
            .zip(&self.x)
            .map(|(m, x)| m * g.dot(x))
            .sum::<f64>()
    }
}

/// The operations [`Particles`] applies to all its arrays alike.
pub(crate) trait ParticleArray {
    fn reserve_exact(&mut self, n: usize);
    fn shrink_to_fit(&mut self);
    /// Keeps entry `i` where `keep[i]`, in order.
    fn retain_by(&mut self, keep: &[bool]);
}

impl<T> ParticleArray for Vec<T> {
    fn retain_by(&mut self, keep: &[bool]) {
        let mut i = 0;
        self.retain(|_| {
            i += 1;
            keep[i - 1]
        });
    }
    fn reserve_exact(&mut self, n: usize) {
        Vec::reserve_exact(self, n);
    }
    fn shrink_to_fit(&mut self) {
        Vec::shrink_to_fit(self);
    }
}

impl<const D: usize, const SYM: bool> ParticleArray for Tensors<D, SYM> {
    fn reserve_exact(&mut self, n: usize) {
        self.values_mut().reserve_exact(n * Self::STRIDE);
    }
    fn shrink_to_fit(&mut self) {
        self.values_mut().shrink_to_fit();
    }
    fn retain_by(&mut self, keep: &[bool]) {
        let s = Self::STRIDE;
        let v = self.values_mut();
        let mut kept = 0;
        for (i, _) in keep.iter().enumerate().filter(|(_, &k)| k) {
            v.copy_within(i * s..(i + 1) * s, kept * s);
            kept += 1;
        }
        v.truncate(kept * s);
    }
}

/// Σ ½ m |v|² of lumped masses and their velocities (particles, grid nodes,
/// membrane nodes), summed in order.
pub fn kinetic_energy<const D: usize>(mass: &[f64], v: &[SVector<f64, D>]) -> f64 {
    mass.iter()
        .zip(v)
        .map(|(m, v)| 0.5 * m * v.norm_squared())
        .sum()
}

#[cfg(test)]
mod tests {
    use super::Particles;
    use nalgebra::SVector;

    /// Ids follow a particle through removal, splitting and joining.
    #[test]
    fn ids_follow_the_particles() {
        let mut p = Particles::<1>::default();
        for i in 0..6 {
            let x = SVector::<f64, 1>::new(i as f64);
            p.push(x, x, 1.0, 1.0, x, (i % 2) as u16);
        }
        let ids = |p: &Particles<1>| (0..p.len()).map(|i| p.id_of(i)).collect::<Vec<_>>();
        assert_eq!(ids(&p), [0, 1, 2, 3, 4, 5]);
        assert!(p.id.is_empty(), "ids in creation order are not stored");
        p.retain(&[true, false, true, true, false, true]);
        assert_eq!(ids(&p), [0, 2, 3, 5]);
        let odd = p.select(|i| p.material[i] == 1);
        let even = p.select(|i| p.material[i] == 0);
        assert_eq!((ids(&odd), ids(&even)), (vec![3, 5], vec![0, 2]));
        let mut all = even.clone();
        all.append(&odd);
        assert_eq!(ids(&all), [0, 2, 3, 5]);
        // A particle added later gets a new id.
        all.push(
            SVector::zeros(),
            SVector::zeros(),
            1.0,
            1.0,
            SVector::zeros(),
            0,
        );
        assert_eq!(all.id_of(4), 6);
        for (id, x) in ids(&all).into_iter().zip(&all.x).take(4) {
            assert_eq!(id as f64, x[0]);
        }
        // Keeping every particle, or copying all in order, keeps them
        // implicit.
        let mut q = Particles::<1>::default();
        for i in 0..3 {
            let x = SVector::<f64, 1>::new(i as f64);
            q.push(x, x, 1.0, 1.0, x, 0);
        }
        q.retain(&[true; 3]);
        let copy = q.select(|_| true);
        assert!(q.id.is_empty() && copy.id.is_empty());
        assert_eq!(ids(&copy), [0, 1, 2]);
    }
}

/// The particles' initial half-sizes, stored as a short table of the
/// distinct values and a 4-byte index per particle: a scene seeds each
/// object at one spacing, so a run has a handful of distinct sizes, and
/// the table saves 12 bytes a particle in 2D, 20 in 3D (issue 24). Read
/// with [`HalfSizes::get`]; the values are kept bit for bit.
#[derive(Debug, Clone, Default)]
pub struct HalfSizes<const D: usize> {
    /// The distinct values, in the order first pushed.
    table: Vec<SVector<f64, D>>,
    /// Each particle's entry of `table`.
    index: Vec<u32>,
}

impl<const D: usize> HalfSizes<D> {
    /// How many table entries [`HalfSizes::push`] searches for an equal
    /// value before adding one: a scene with sizes that vary particle by
    /// particle pays a growing table, never a quadratic search.
    const SEARCH: usize = 64;

    /// The half-sizes of `values`, in order.
    pub fn from_values(values: impl IntoIterator<Item = SVector<f64, D>>) -> Self {
        let mut h = Self::default();
        for v in values {
            h.push(v);
        }
        h
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    /// Half-size of particle `p`.
    #[inline]
    pub fn get(&self, p: usize) -> SVector<f64, D> {
        self.table[self.index[p] as usize]
    }

    /// Appends a particle's half-size.
    pub fn push(&mut self, v: SVector<f64, D>) {
        let same = |t: &SVector<f64, D>| {
            t.iter()
                .zip(v.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits())
        };
        let last = self.index.last().map(|&i| i as usize);
        let found = match last {
            Some(i) if same(&self.table[i]) => Some(i),
            _ => self
                .table
                .iter()
                .rev()
                .take(Self::SEARCH)
                .position(same)
                .map(|k| self.table.len() - 1 - k),
        };
        let i = found.unwrap_or_else(|| {
            self.table.push(v);
            self.table.len() - 1
        });
        self.index.push(i as u32);
    }

    /// Every particle's half-size, in order.
    pub fn iter(&self) -> impl Iterator<Item = SVector<f64, D>> + '_ {
        self.index.iter().map(|&i| self.table[i as usize])
    }
}

impl<const D: usize> ParticleArray for HalfSizes<D> {
    fn reserve_exact(&mut self, n: usize) {
        self.index.reserve_exact(n);
    }
    fn shrink_to_fit(&mut self) {
        self.index.shrink_to_fit();
    }
    fn retain_by(&mut self, keep: &[bool]) {
        self.index.retain_by(keep);
    }
}
