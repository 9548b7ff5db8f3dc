//! Reaction mass exchange of the multifield equations (Guilkey Eqs. 6–9,
//! Sec. 3.3 steps 4 and 8, Sec. 5): a reactant solid on material points
//! burns on its surface into a product fluid in the cells.
//!
//! **Rate law** (Guilkey Sec. 5): `Γ = A K pⁿ` — the mass burnt per unit
//! time in a cell is its reactant surface area `A` times the rate constant
//! `K` [kg/(m² s Paⁿ)] times the cell pressure to the power `n`, wherever the
//! reactant is at or above the threshold temperature. With `n = 0` the
//! surface regresses at the constant speed `K/ρ_s`.
//!
//! **Surface area.** The reactant volume fraction of cell `c` is binned from
//! its particles, `θ_c = min(1, Σ_{p∈c} max(V_p, V_p⁰) / V)` (a compressed
//! particle counts with its reference volume, so that a compressed interior
//! is a full cell). A cell with reactant burns on its *exposed* faces, those
//! whose neighbour holds none (a face on the domain boundary is not
//! exposed: the walls are symmetry planes). Face `f` of direction `d`
//! contributes `a_f = |F_d| |n_d|`, with `n` the outward unit normal from
//! the gradient of `θ` on the cell's 3^D block (Youngs' weights). A
//! staircase of exposed faces along a straight interface then sums to its
//! true area (`Σ |F_x| |n_x| + Σ |F_y| |n_y| = L (n_x² + n_y²)`), instead
//! of the `|n_x| + |n_y|` (up to √2) of the bare faces; across a plane
//! normal to an axis it is exact. Where the gradient vanishes (a layer one
//! cell thin) every exposed face counts whole. The front stays sharp: a
//! partly burnt cell burns at its full area until its particles are used
//! up, and the cell behind it starts when it is exposed (the step that
//! finishes a cell burns only what is left in it).
//!
//! **Exchange** (Guilkey Sec. 3.3 step 4: "decrementing the particle mass
//! automatically decreases the momentum and internal energy of that
//! particle"): the mass `Δm_c = min(Δt Σ_f a_f K p_fⁿ, M_c)` (`M_c` the
//! mass of the cell's particles at or above the threshold; `p_f` the
//! pressure of the gas beyond face `f`) leaves those particles in
//! proportion to their masses, with their reference and current volumes
//! (the density is unchanged). The burnt mass enters the product beyond
//! the exposed faces, shared by their areas — where the gas has room: put
//! into the burning cell, which the solid fills, it would have to squeeze
//! the solid to fit. With it go the particles' momentum `Σ Δm_p v_p`
//! (Guilkey Eq. 33's `u_s Γ_s`) and energy `Σ Δm_p (c_v,s T_p + w_p + Q +
//! ½|v_p|²)` (Eq. 34's `e_s Γ_s` with the heat of reaction `Q`, the
//! chemical part of the reactant's internal energy, and `w_p` the
//! particle's stored and dissipated work per unit mass, the mechanical
//! part: a particle keeps only its unburnt part's, since its reference
//! volume shrinks with its mass, and one that burns out is removed with
//! it; left behind, the 2D confined explosion's account lost 113 J/m of
//! the 1.6e5 J/m released by 10 µs). The product's new
//! velocity is the mass-weighted one and its temperature takes the whole
//! energy, the kinetic energy lost in the inelastic mixing of the momenta
//! included, so that mass, momentum and total energy are conserved to
//! round-off by the exchange. A particle whose mass is used up is removed.
//!
//! **Volume** (Guilkey Eq. 40's `v Γ` terms, which sum to zero over the
//! materials of a cell: the product takes the volume the reactant frees).
//! Where the cells are not normalised (no solid) the equilibration fits the
//! product into the cell volume and its specific volume does not enter.
//! Where a solid fills the product cell, the equilibration normalises on
//! the cell's material volume `Σ_r M_r v_r` (Guilkey Sec. 3.3 step 2;
//! [`crate::ice::pressure::SOLID_FILL_FOR_NORMALISING`]), so the product's
//! `M v` is what gives it room. Added at its own specific volume there it
//! would make its own room and never pressurise: a reactant confined by a
//! steel wall burnt without any pressure rise. The product's added volume
//! is therefore `(1 − φ) ΔV_s + φ Δm v`, with `ΔV_s` the volume the burnt
//! particles leave, `v` the product's specific volume in the cell and `φ`
//! the fluids' share of the cell's material volume: where solid holds the
//! cell (`φ → 0`) the freed volume is all the product gets, and its
//! pressure rises as it accumulates; where gas holds most of it (`φ → 1`,
//! e.g. a burning face in open gas, whose cell a solid's interpolated
//! volume reaches) the gas there makes room as before.
//!
//! **Time step.** A burn puts its product into the few cells beside the
//! surface, whose product mass may be tiny; at a fast rate one step could
//! add many times that mass, and the next equilibration would have to find
//! a pressure for a cell whose gas grew a hundredfold (at K = 2e5 the
//! products in the burning cells reached 8000 m/s and volume fractions of 5
//! within 100 steps). The burn therefore limits the next step so
//! that no product cell receives more than [`MAX_GROWTH`] times its own mass
//! in it, at the rates of the step before (the first step's from a dry run
//! at the start); a slow burn is not limited by it (`cases/reaction_burn.toml`
//! takes the same 3487 steps with and without it). Cells where solid holds
//! most of the material volume ([`GROWTH_LIMIT_SHARE`]) are exempt: the
//! product there is a trace (against a steel wall the limit was 1e-18 s),
//! and it arrives with the volume the reactant frees, so its pressure is
//! bounded by the product's state at the reactant's density.
//!
//! **Splitting.** The exchange is applied at the end of a coupled step with
//! that step's `Δt`, pressure and positions; the next step's equilibration
//! (Guilkey Eq. 13) then finds the pressure at which the added product mass
//! fits in its room. This is the operator-split form of the `Σ v_r Γ_r`
//! term of Guilkey Eq. 29 (the linearised volume change of the reaction in
//! the pressure increment) and needs no retry logic: a step whose pressure
//! stage halves `Δt` has not burnt anything yet.

use nalgebra::SVector;

use crate::ice::CellLayout;
use crate::material::SolidMaterial;
use crate::mpm::Particles;

/// The most a product cell's mass may grow in one step, relative to
/// itself: the burn's limit on the time step (module doc).
pub const MAX_GROWTH: f64 = 1.0;

/// The fluids' share of a product cell's material volume below which the
/// cell does not limit the step ([`MAX_GROWTH`]): solid holds most of it,
/// so the product arrives with most of the reactant's volume and its
/// pressure is bounded by the product's state at the reactant's density,
/// not by how much its mass grows (module doc).
pub const GROWTH_LIMIT_SHARE: f64 = 0.5;

/// A surface burn law `Γ = A K pⁿ` (Guilkey Sec. 5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BurnLaw {
    /// Rate constant `K` [kg/(m² s Paⁿ)], `K ≥ 0`.
    pub rate_constant: f64,
    /// Pressure exponent `n ≥ 0`.
    pub pressure_exponent: f64,
    /// The reactant burns where its temperature is at least this \[K\].
    pub threshold_temperature: f64,
    /// Heat of reaction `Q ≥ 0` [J/kg] released into the product.
    pub heat_of_reaction: f64,
}

impl BurnLaw {
    /// Mass burnt per unit area and time at pressure `p`: `K pⁿ` (zero for
    /// `p ≤ 0` unless `n = 0`).
    #[inline]
    pub fn mass_flux(&self, p: f64) -> f64 {
        if self.pressure_exponent == 0.0 {
            self.rate_constant
        } else if p > 0.0 {
            self.rate_constant * p.powf(self.pressure_exponent)
        } else {
            0.0
        }
    }

    /// The first parameter out of range: its key and the allowed values.
    pub fn validate(&self) -> Result<(), (&'static str, &'static str)> {
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        if !ok(self.rate_constant) {
            return Err(("rate_constant", "finite and ≥ 0"));
        }
        if !ok(self.pressure_exponent) {
            return Err(("pressure_exponent", "finite and ≥ 0"));
        }
        if !(self.threshold_temperature.is_finite() && self.threshold_temperature > 0.0) {
            return Err(("threshold_temperature", "finite and > 0"));
        }
        if !ok(self.heat_of_reaction) {
            return Err(("heat_of_reaction", "finite and ≥ 0"));
        }
        Ok(())
    }
}

/// One reaction of a coupled run: which solid field burns into which fluid.
#[derive(Debug, Clone, PartialEq)]
pub struct Reaction {
    /// The reactant's solid field (index into the run's fields).
    pub field: usize,
    /// The product's fluid material (index among the ICE materials).
    pub product: usize,
    /// The rate law.
    pub law: BurnLaw,
    /// `c_v` of the reactant [J/(kg K)] (its internal energy `c_v T`).
    pub reactant_cv: f64,
    /// Totals since the start of the run.
    pub totals: ReactionTotals,
    /// The largest next step the burn allows ([`MAX_GROWTH`]).
    pub dt_limit: f64,
}

/// What a reaction has done since the start of the run.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ReactionTotals {
    /// Reactant mass converted into product \[kg\].
    pub mass: f64,
    /// Energy the product received with it, `Σ Δm (c_v,s T + w + Q +
    /// ½|v|²)` (`w` the reactant's stored work per unit mass)
    /// \[J\].
    pub energy: f64,
    /// Of which heat of reaction, `Σ Δm Q` \[J\].
    pub heat: f64,
}

/// Per-cell scratch of the exchange (sized on first use, reused every
/// step).
#[derive(Debug, Clone)]
pub struct BurnScratch<const D: usize> {
    /// `θ_c` of the reactant, binned from its particles.
    theta: Vec<f64>,
    /// `M_c`: mass of the cell's particles at or above the threshold.
    eligible: Vec<f64>,
    /// Fraction of `M_c` burnt this step.
    fraction: Vec<f64>,
    /// Per burning cell: the mass, momentum, energy and volume its
    /// particles gave.
    given: Vec<Transfer<D>>,
    /// Per product cell: the mass, momentum, energy and volume it receives.
    gained: Vec<Transfer<D>>,
    /// Per product cell: the mass rate it receives at the current rates.
    inflow: Vec<f64>,
    /// Per burning cell: its exposed area.
    area: Vec<f64>,
    /// Cell of each particle (`usize::MAX`: outside the interior).
    cell_of: Vec<usize>,
    /// Particles to keep (mass left).
    keep: Vec<bool>,
}

impl<const D: usize> Default for BurnScratch<D> {
    fn default() -> Self {
        Self {
            theta: Vec::new(),
            eligible: Vec::new(),
            fraction: Vec::new(),
            given: Vec::new(),
            gained: Vec::new(),
            inflow: Vec::new(),
            area: Vec::new(),
            cell_of: Vec::new(),
            keep: Vec::new(),
        }
    }
}

/// What the burn moves from a cell's particles to the product: mass,
/// momentum, energy and the volume the mass leaves.
#[derive(Debug, Clone, Copy)]
struct Transfer<const D: usize> {
    mass: f64,
    momentum: SVector<f64, D>,
    energy: f64,
    volume: f64,
}

impl<const D: usize> Default for Transfer<D> {
    fn default() -> Self {
        Self {
            mass: 0.0,
            momentum: SVector::zeros(),
            energy: 0.0,
            volume: 0.0,
        }
    }
}

/// The product's cell state the exchange updates.
pub struct ProductCells<'a, const D: usize> {
    /// Mass per cell.
    pub mass: &'a mut [f64],
    /// Velocity per cell.
    pub velocity: &'a mut [SVector<f64, D>],
    /// Temperature per cell.
    pub temperature: &'a mut [f64],
    /// Specific volume per cell.
    pub sp_vol: &'a mut [f64],
    /// Per cell: the fluids' share `φ` of the material volume where a solid
    /// fills the cell, so that the equilibration normalises on the material
    /// volume there ([`crate::ice::pressure::normalising_weight`] = 1); 1
    /// elsewhere.
    pub fluid_share: &'a [f64],
    /// `c_v` of the product.
    pub cv: f64,
}

/// The interior cell containing `x` (`None` outside the interior).
#[inline]
fn cell_containing<const D: usize>(layout: &CellLayout<D>, x: &SVector<f64, D>) -> Option<usize> {
    let mut ijk = [0isize; D];
    for d in 0..D {
        let s = ((x[d] - layout.lower[d]) / layout.h[d]).floor();
        if !(s >= 0.0 && s < layout.cells[d] as f64) {
            return None;
        }
        ijk[d] = s as isize;
    }
    Some(layout.index(ijk))
}

/// The interior face neighbour of `c` across side `side` (0 lower, 1
/// upper) of direction `d`, if any (a face on the domain boundary has none:
/// the walls are symmetry planes).
#[inline]
fn neighbour<const D: usize>(
    layout: &CellLayout<D>,
    ijk: &[isize; D],
    c: usize,
    d: usize,
    side: usize,
) -> Option<usize> {
    let s = layout.strides[d];
    if side == 1 {
        (ijk[d] + 1 < layout.cells[d] as isize).then_some(c + s)
    } else {
        (ijk[d] > 0).then(|| c - s)
    }
}

/// Outward unit normal of the reactant at cell `c` from the gradient of
/// `θ` on the 3^D block around it (Youngs' weights: 2 for the centre row
/// of each transverse direction, 1 for the others; a neighbour outside the
/// domain counts as the cell itself), or `None` where the gradient
/// vanishes (a layer one cell thin).
fn outward_normal<const D: usize>(
    layout: &CellLayout<D>,
    theta: &[f64],
    c: usize,
) -> Option<SVector<f64, D>> {
    let ijk = layout.coords(c);
    let mut g = SVector::<f64, D>::zeros();
    let n_off = 3usize.pow(D as u32);
    for k in 0..n_off {
        let mut off = [0isize; D];
        let mut rest = k;
        for o in off.iter_mut() {
            *o = (rest % 3) as isize - 1;
            rest /= 3;
        }
        let mut cell = c as isize;
        for d in 0..D {
            let j = ijk[d] + off[d];
            if j >= 0 && j < layout.cells[d] as isize {
                cell += off[d] * layout.strides[d] as isize;
            }
        }
        let t = theta[cell as usize];
        for d in 0..D {
            if off[d] != 0 {
                let w: f64 = (0..D)
                    .filter(|&e| e != d)
                    .map(|e| if off[e] == 0 { 2.0 } else { 1.0 })
                    .product();
                g[d] += w * off[d] as f64 * t / layout.h[d];
            }
        }
    }
    let norm = g.norm();
    (norm > 0.0).then(|| -g / norm)
}

/// Calls `f(neighbour, area)` for every exposed face of interior cell `c`
/// (its neighbour holds no reactant) with the face's share of the burning
/// area, `|F| |n_d|` (module doc); returns the cell's area, their sum.
fn exposed_faces<const D: usize>(
    layout: &CellLayout<D>,
    theta: &[f64],
    c: usize,
    mut f: impl FnMut(usize, f64),
) -> f64 {
    let ijk = layout.coords(c);
    let exposed =
        |d: usize, side: usize| neighbour(layout, &ijk, c, d, side).filter(|&n| theta[n] == 0.0);
    let any = (0..D).any(|d| exposed(d, 0).is_some() || exposed(d, 1).is_some());
    if !any {
        return 0.0;
    }
    let normal = outward_normal(layout, theta, c);
    let vol = layout.cell_volume();
    let mut area = 0.0;
    for d in 0..D {
        let face = vol / layout.h[d];
        let share = normal.map_or(1.0, |n| n[d].abs());
        for side in 0..2 {
            if let Some(n) = exposed(d, side) {
                let a = face * share;
                if a > 0.0 {
                    f(n, a);
                    area += a;
                }
            }
        }
    }
    area
}

/// Temperature of reactant particle `p`: `uniform_t` where the solid's
/// temperature is not tracked, else its own.
#[inline]
fn temperature<const D: usize>(particles: &Particles<D>, p: usize, uniform_t: Option<f64>) -> f64 {
    uniform_t.unwrap_or_else(|| particles.temperature_of(p))
}

/// The burn's rates at `pressure` over a step of `dt` (module doc), into
/// `s`: each cell's reactant fraction `θ`, eligible mass, the fraction of
/// it burnt, its exposed area, each product cell's inflow rate and each
/// particle's cell. Reads the particles only.
fn tally<const D: usize>(
    layout: &CellLayout<D>,
    law: &BurnLaw,
    dt: f64,
    pressure: &[f64],
    particles: &Particles<D>,
    uniform_t: Option<f64>,
    s: &mut BurnScratch<D>,
) {
    let n_cells = layout.len();
    let zero = Transfer::default();
    for v in [
        &mut s.theta,
        &mut s.eligible,
        &mut s.fraction,
        &mut s.inflow,
        &mut s.area,
    ] {
        v.clear();
        v.resize(n_cells, 0.0);
    }
    for v in [&mut s.given, &mut s.gained] {
        v.clear();
        v.resize(n_cells, zero);
    }
    s.cell_of.clear();
    let vol = layout.cell_volume();
    for p in 0..particles.len() {
        let c = cell_containing(layout, &particles.x[p]);
        s.cell_of.push(c.unwrap_or(usize::MAX));
        if let Some(c) = c {
            s.theta[c] += particles.vol[p].max(particles.vol0[p]) / vol;
            if temperature(particles, p, uniform_t) >= law.threshold_temperature {
                s.eligible[c] += particles.mass[p];
            }
        }
    }
    for t in &mut s.theta {
        *t = t.min(1.0);
    }
    for &c in &layout.interior {
        let m = s.eligible[c];
        if m > 0.0 {
            // Σ_faces a_f K p_fⁿ: each face burns at the pressure of the gas
            // beyond it.
            let mut rate = 0.0;
            let area = exposed_faces(layout, &s.theta, c, |n, a| {
                rate += a * law.mass_flux(pressure[n])
            });
            s.fraction[c] = (dt * rate).min(m) / m;
            s.area[c] = area;
            if rate > 0.0 {
                let inflow = &mut s.inflow;
                exposed_faces(layout, &s.theta, c, |n, a| inflow[n] += rate * a / area);
            }
        }
    }
}

/// The product cell that limits the next step most ([`MAX_GROWTH`] times
/// its mass over its inflow rate) and that limit; `None` where nothing
/// flows in. Cells where solid holds most of the material volume
/// (`fluid_share` below [`GROWTH_LIMIT_SHARE`]) do not limit: the product
/// brings most of its volume there (module doc).
fn growth_limit<const D: usize>(
    layout: &CellLayout<D>,
    inflow: &[f64],
    product_mass: &[f64],
    fluid_share: &[f64],
) -> Option<(usize, f64)> {
    let mut best: Option<(usize, f64)> = None;
    for &c in &layout.interior {
        if inflow[c] > 0.0 && fluid_share[c] >= GROWTH_LIMIT_SHARE {
            let dt = MAX_GROWTH * product_mass[c] / inflow[c];
            if best.is_none_or(|(_, b)| dt < b) {
                best = Some((c, dt));
            }
        }
    }
    best
}

/// Marks in `fed` the cells the burn feeds at the current state (rates at
/// `pressure`, the reactant `particles` at `uniform_t` or their own
/// temperatures) and the cells the reactant burns in (eligible, with an
/// exposed face), which become product cells as the front passes;
/// `scratch` is overwritten. Leaves the other entries. Eligible reactant
/// deeper inside is not marked: its product traces are held isothermal like
/// any other (marked, the traces at the centre of a confined PBX charge took
/// the charge's volume noise as flow work, reached 2e9 K and cut Δt 100-fold).
pub fn mark_fed<const D: usize>(
    layout: &CellLayout<D>,
    law: &BurnLaw,
    pressure: &[f64],
    particles: &Particles<D>,
    uniform_t: Option<f64>,
    scratch: &mut BurnScratch<D>,
    fed: &mut [bool],
) {
    tally(layout, law, 0.0, pressure, particles, uniform_t, scratch);
    for &c in &layout.interior {
        if scratch.inflow[c] > 0.0 || (scratch.eligible[c] > 0.0 && scratch.area[c] > 0.0) {
            fed[c] = true;
        }
    }
}

/// Where a run's burn limits the next step ([`MAX_GROWTH`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BurnLimit {
    /// The reaction (index into the run's reactions).
    pub reaction: usize,
    /// The product cell.
    pub cell: usize,
    /// The product's mass in it \[kg\].
    pub mass: f64,
    /// The rate at which the burn feeds it \[kg/s\].
    pub inflow: f64,
    /// The limit \[s\].
    pub dt: f64,
}

/// Where the burn limits the next step, at the current state (rates at
/// `pressure`, the reactant `particles` at `uniform_t` or their own
/// temperatures, the product's mass and the fluids' volume share per cell):
/// the product cell, its inflow rate \[kg/s\] and the limit \[s\]
/// ([`MAX_GROWTH`]); `None` where nothing burns. For the run loop's
/// diagnostics (it allocates).
pub fn limiting_cell<const D: usize>(
    layout: &CellLayout<D>,
    law: &BurnLaw,
    pressure: &[f64],
    particles: &Particles<D>,
    uniform_t: Option<f64>,
    product_mass: &[f64],
    fluid_share: &[f64],
) -> Option<(usize, f64, f64)> {
    let mut s = BurnScratch::default();
    tally(layout, law, 0.0, pressure, particles, uniform_t, &mut s);
    growth_limit(layout, &s.inflow, product_mass, fluid_share).map(|(c, dt)| (c, s.inflow[c], dt))
}

/// One step of the surface burn of `particles` (the reactant field; every
/// particle is reactant) into `product` (module doc): `pressure` per cell,
/// `temperature` per particle (`None`: every particle at `uniform_t`).
/// `materials` are the run's particle materials (indexed by
/// [`Particles::material`]), whose stored energy the burnt mass takes
/// along. Returns what was converted in this step and the largest step the
/// burn allows next (at the rates of this step: [`MAX_GROWTH`]), and
/// removes the particles that burnt out. With `dt = 0` it changes nothing
/// and only returns that limit.
#[allow(clippy::too_many_arguments)]
pub fn burn<const D: usize>(
    layout: &CellLayout<D>,
    law: &BurnLaw,
    reactant_cv: f64,
    materials: &[SolidMaterial],
    dt: f64,
    pressure: &[f64],
    particles: &mut Particles<D>,
    uniform_t: Option<f64>,
    product: &mut ProductCells<'_, D>,
    scratch: &mut BurnScratch<D>,
) -> (ReactionTotals, f64) {
    let s = scratch;
    tally(layout, law, dt, pressure, particles, uniform_t, s);
    // The next step's limit: no product cell may receive more than its
    // own mass in one step (module doc).
    let dt_limit = growth_limit(layout, &s.inflow, product.mass, product.fluid_share)
        .map_or(f64::INFINITY, |l| l.1);
    // The particles give mass, momentum and energy to their cell's tally.
    let mut out = ReactionTotals::default();
    let mut any_out = false;
    s.keep.clear();
    s.keep.resize(particles.len(), true);
    for p in 0..particles.len() {
        let c = s.cell_of[p];
        if c == usize::MAX {
            continue;
        }
        let f = s.fraction[c];
        if f <= 0.0 || temperature(particles, p, uniform_t) < law.threshold_temperature {
            continue;
        }
        let m = particles.mass[p];
        // The burnt share of the particle: all of it from `f = 1` on.
        let share = f.min(1.0);
        let dm = m * share;
        let v = particles.v[p];
        let e_in = reactant_cv * temperature(particles, p, uniform_t) + law.heat_of_reaction;
        // The stored (and dissipated) work of the burnt part goes with it:
        // `vol0` shrinks with the mass, so the particle keeps only its
        // own part, and the rest is internal energy of the reactant like
        // `c_v T` (module doc, "Exchange"). By the burnt share, not per
        // unit mass: a particle may have no mass left.
        let stored = share
            * particles.vol0[p]
            * materials[particles.material[p] as usize]
                .strain_energy_density(&particles.f.get(p), particles.work_of(p));
        let de = dm * (e_in + 0.5 * v.norm_squared()) + stored;
        let g = &mut s.given[c];
        g.mass += dm;
        g.momentum += v * dm;
        g.energy += de;
        // The volume the burnt mass leaves, at the particle's current
        // specific volume.
        g.volume += share * particles.vol[p];
        out.mass += dm;
        out.energy += de;
        out.heat += dm * law.heat_of_reaction;
        if f >= 1.0 {
            particles.mass[p] = 0.0;
            s.keep[p] = false;
            any_out = true;
        } else {
            let keep = 1.0 - f;
            particles.mass[p] = m - dm;
            particles.vol0[p] *= keep;
            particles.vol[p] *= keep;
        }
    }
    // Each burning cell's tally goes to the product beyond its exposed
    // faces (where the gas has room), shared by their areas.
    for &c in &layout.interior {
        let t = s.given[c];
        if t.mass > 0.0 {
            let area = s.area[c];
            let gained = &mut s.gained;
            exposed_faces(layout, &s.theta, c, |n, a| {
                let w = a / area;
                let g = &mut gained[n];
                g.mass += w * t.mass;
                g.momentum += t.momentum * w;
                g.energy += w * t.energy;
                g.volume += w * t.volume;
            });
        }
    }
    // The product's new state: mass-weighted velocity, the whole energy
    // (the kinetic energy of the inelastic mixing included) in its
    // temperature, and in a solid-filled cell its specific volume (module
    // doc).
    for &c in &layout.interior {
        let t = s.gained[c];
        if t.mass > 0.0 {
            let m0 = product.mass[c];
            let u0 = product.velocity[c];
            let e0 = m0 * (product.cv * product.temperature[c] + 0.5 * u0.norm_squared());
            let m = m0 + t.mass;
            let u = (u0 * m0 + t.momentum) / m;
            product.mass[c] = m;
            product.velocity[c] = u;
            product.temperature[c] = ((e0 + t.energy) / m - 0.5 * u.norm_squared()) / product.cv;
            let phi = product.fluid_share[c];
            if phi < 1.0 {
                let v0 = product.sp_vol[c];
                let added = (1.0 - phi) * t.volume + phi * t.mass * v0;
                product.sp_vol[c] = (m0 * v0 + added) / m;
            }
        }
    }
    if any_out {
        particles.retain(&s.keep);
    }
    (out, dt_limit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    fn law(k: f64, n: f64) -> BurnLaw {
        BurnLaw {
            rate_constant: k,
            pressure_exponent: n,
            threshold_temperature: 500.0,
            heat_of_reaction: 4.0e6,
        }
    }

    /// A 2D block of reactant particles (2×2 per cell) over cells
    /// `[x0, x1) × [0, 1)` of a 10×4 grid of h = 0.25, moving with `v`.
    fn block(x0: f64, x1: f64, v: Vector2<f64>) -> Particles<2> {
        let mut p = Particles::default();
        let h = 0.125;
        let mut x = x0 + 0.5 * h;
        while x < x1 {
            let mut y = 0.5 * h;
            while y < 1.0 {
                p.push(
                    Vector2::new(x, y),
                    v + Vector2::new(0.1 * y, -0.2 * x),
                    1800.0 * h * h,
                    h * h,
                    Vector2::repeat(0.5 * h),
                    0,
                );
                y += h;
            }
            x += h;
        }
        p.track_temperature();
        p.temperature.iter_mut().enumerate().for_each(|(i, t)| {
            *t = 600.0 + i as f64;
        });
        // Compressed and sheared differently per particle, so that each
        // holds its own stored energy.
        for i in 0..p.len() {
            let a = 0.01 * (i % 7) as f64;
            let f = nalgebra::Matrix3::new(0.97 - a, 0.02, 0.0, 0.0, 0.99, 0.0, 0.0, 0.0, 1.0);
            p.f.set(i, &f);
        }
        p
    }

    /// One [`burn`] step of the [`pbx`] reactant at its particles' own
    /// temperatures: what it converted.
    #[allow(clippy::too_many_arguments)]
    fn burn_pbx(
        layout: &CellLayout<2>,
        law: &BurnLaw,
        cv: f64,
        dt: f64,
        pressure: &[f64],
        particles: &mut Particles<2>,
        cells: &mut ProductCells<'_, 2>,
        s: &mut BurnScratch<2>,
    ) -> ReactionTotals {
        burn(
            layout,
            law,
            cv,
            &pbx(),
            dt,
            pressure,
            particles,
            None,
            cells,
            s,
        )
        .0
    }

    /// The reactant: PBX-like neo-Hookean (K = 10 GPa, G = 3 GPa).
    fn pbx() -> Vec<SolidMaterial> {
        vec![SolidMaterial {
            name: "pbx".into(),
            density: 1800.0,
            model: crate::material::SolidModel::NeoHookean,
            elastic: crate::material::ElasticConstants::from_bulk_shear(10e9, 3e9),
        }]
    }

    fn layout() -> CellLayout<2> {
        CellLayout::new(Vector2::zeros(), Vector2::repeat(0.25), [10, 4]).unwrap()
    }

    struct Product {
        mass: Vec<f64>,
        velocity: Vec<Vector2<f64>>,
        temperature: Vec<f64>,
        sp_vol: Vec<f64>,
    }

    fn product(layout: &CellLayout<2>) -> Product {
        let n = layout.len();
        let mut pr = Product {
            mass: vec![0.0; n],
            velocity: vec![Vector2::zeros(); n],
            temperature: vec![0.0; n],
            sp_vol: vec![0.0; n],
        };
        for (i, &c) in layout.interior.iter().enumerate() {
            pr.mass[c] = 1e-3 * (1.0 + (i % 3) as f64);
            pr.velocity[c] = Vector2::new(3.0 - (i % 5) as f64, 0.5 * (i % 2) as f64);
            pr.temperature[c] = 300.0 + i as f64;
            pr.sp_vol[c] = 2.0 + 0.1 * (i % 7) as f64;
        }
        pr
    }

    /// Mass, momentum, energy (the reactant's `c_v T + Q + ½|v|²`, the
    /// product's `c_v T + ½|u|²`) and material volume (the particles' and
    /// the product's `M v`) before and after.
    fn totals(
        layout: &CellLayout<2>,
        p: &Particles<2>,
        pr: &Product,
        cv_s: f64,
        cv_g: f64,
        q: f64,
    ) -> (f64, Vector2<f64>, f64, f64) {
        let mut m = 0.0;
        let mut mom = Vector2::zeros();
        let mut e = 0.0;
        let mut v = 0.0;
        for i in 0..p.len() {
            v += p.vol[i];
            m += p.mass[i];
            mom += p.v[i] * p.mass[i];
            e += p.mass[i] * (cv_s * p.temperature[i] + q + 0.5 * p.v[i].norm_squared());
        }
        e += p.strain_energy(&pbx());
        for &c in &layout.interior {
            m += pr.mass[c];
            mom += pr.velocity[c] * pr.mass[c];
            e += pr.mass[c] * (cv_g * pr.temperature[c] + 0.5 * pr.velocity[c].norm_squared());
            v += pr.mass[c] * pr.sp_vol[c];
        }
        (m, mom, e, v)
    }

    /// The exchange conserves mass, momentum, total energy and material
    /// volume (the product takes the volume the burnt reactant leaves) to
    /// round-off, also when it burns whole cells out (removing their
    /// particles).
    #[test]
    fn exchange_conserves_mass_momentum_and_energy() {
        let layout = layout();
        let (cv_s, cv_g) = (1500.0, 2000.0);
        let pressure = vec![2.0e6; layout.len()];
        for (k, dt) in [(1e-3, 1e-3), (100.0, 1e-2)] {
            let law = law(k, 0.5);
            let mut p = block(0.5, 1.75, Vector2::new(40.0, -7.0));
            let mut pr = product(&layout);
            let before = totals(&layout, &p, &pr, cv_s, cv_g, law.heat_of_reaction);
            let mut s = BurnScratch::default();
            let n0 = p.len();
            let out = {
                let mut cells = ProductCells {
                    mass: &mut pr.mass,
                    velocity: &mut pr.velocity,
                    temperature: &mut pr.temperature,
                    sp_vol: &mut pr.sp_vol,
                    fluid_share: &vec![0.0; layout.len()],
                    cv: cv_g,
                };
                burn_pbx(
                    &layout, &law, cv_s, dt, &pressure, &mut p, &mut cells, &mut s,
                )
            };
            let after = totals(&layout, &p, &pr, cv_s, cv_g, law.heat_of_reaction);
            assert!(out.mass > 0.0);
            let rel = |a: f64, b: f64, scale: f64| (a - b).abs() / scale;
            // Round-off of sums over a few hundred terms.
            assert!(
                rel(before.0, after.0, before.0) < 1e-13,
                "{before:?} {after:?}"
            );
            let pscale: f64 = before.0 * 50.0;
            assert!((before.1 - after.1).norm() / pscale < 1e-13);
            assert!(
                rel(before.2, after.2, before.2) < 1e-13,
                "{before:?} {after:?}"
            );
            assert!(
                rel(before.3, after.3, before.3) < 1e-13,
                "{before:?} {after:?}"
            );
            if k > 50.0 {
                assert!(p.len() < n0, "the fast burn removes burnt-out particles");
            }
        }
    }

    /// Across an interface normal to x the areas sum to the exact area:
    /// with n = 0 the step burns exactly `Δt K A` (A = 1 m × 1 m per unit
    /// depth here: the block's face at x = 1.75 and at x = 0.5).
    #[test]
    fn plane_interface_burns_at_the_law_rate() {
        let layout = layout();
        let pressure = vec![1e5; layout.len()];
        let law = law(2.0, 0.0);
        let mut p = block(0.5, 1.75, Vector2::zeros());
        let mut pr = product(&layout);
        let mut s = BurnScratch::default();
        let dt = 1e-3;
        let mut cells = ProductCells {
            mass: &mut pr.mass,
            velocity: &mut pr.velocity,
            temperature: &mut pr.temperature,
            sp_vol: &mut pr.sp_vol,
            fluid_share: &vec![0.0; layout.len()],
            cv: 700.0,
        };
        let out = burn_pbx(
            &layout, &law, 1500.0, dt, &pressure, &mut p, &mut cells, &mut s,
        );
        // Two faces of area 1 (the grid is 1 high).
        let exact = dt * 2.0 * 1.0 * law.rate_constant;
        assert!(
            (out.mass - exact).abs() < 1e-15 * exact.max(1.0),
            "{} vs {exact}",
            out.mass
        );
        // Below the threshold nothing burns.
        let mut cold = block(0.5, 1.75, Vector2::zeros());
        cold.temperature.iter_mut().for_each(|t| *t = 400.0);
        let out = burn_pbx(
            &layout, &law, 1500.0, dt, &pressure, &mut cold, &mut cells, &mut s,
        );
        assert_eq!(out.mass, 0.0);
    }

    /// The rate follows `K pⁿ`.
    #[test]
    fn rate_follows_the_pressure_power() {
        let l = law(1e-3, 0.8);
        assert!((l.mass_flux(1e6) - 1e-3 * 1e6f64.powf(0.8)).abs() < 1e-12);
        assert_eq!(l.mass_flux(-5.0), 0.0);
        assert_eq!(law(3.0, 0.0).mass_flux(-5.0), 3.0);
        let mut bad = l;
        bad.pressure_exponent = -1.0;
        assert_eq!(bad.validate().unwrap_err().0, "pressure_exponent");
    }
}
