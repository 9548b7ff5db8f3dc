//! Solid constitutive models for MPM particles.
//!
//! Stress and deformation gradient are always 3×3: 2D runs are plane strain
//! (F₃₃ = 1, σ₃₃ kept) and 1D runs are uniaxial strain.

use nalgebra::Matrix3;

use super::failure::{Failure, Fracturing};
use super::gas_point::{GasPoint, GasStep};
use super::membrane::MembraneLaw;
use super::plasticity::{PlasticState, J2};

/// Isotropic elastic constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElasticConstants {
    /// Lamé's first parameter λ.
    pub lambda: f64,
    /// Shear modulus μ = G.
    pub mu: f64,
}

impl ElasticConstants {
    /// From Young's modulus and Poisson's ratio.
    pub fn from_young_poisson(e: f64, nu: f64) -> Self {
        Self {
            lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            mu: e / (2.0 * (1.0 + nu)),
        }
    }

    /// From bulk and shear moduli.
    pub fn from_bulk_shear(k: f64, g: f64) -> Self {
        Self {
            lambda: k - 2.0 * g / 3.0,
            mu: g,
        }
    }

    /// Bulk modulus K = λ + 2μ/3.
    pub fn bulk(&self) -> f64 {
        self.lambda + 2.0 * self.mu / 3.0
    }

    /// P-wave (constrained) modulus λ + 2μ = K + 4G/3.
    pub fn p_wave(&self) -> f64 {
        self.lambda + 2.0 * self.mu
    }
}

/// Which constitutive model a particle material uses: a solid's, or the
/// fluid stress of a gas point (York Sec. 3.3; set by the scene for a fluid
/// material with `frame = "particles"`, never named in a scene's `model`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SolidModel {
    /// Hypo-elastic, Jaumann rate (York Eqs. 18–20):
    /// σⁿ⁺¹ = σⁿ + Δt (W σⁿ − σⁿ W) + Δt (λ tr(D) I + 2μ D).
    LinearElastic,
    /// Compressible neo-Hookean (as in Wallstedt & Guilkey 2008):
    /// σ = (λ ln J / J) I + (μ / J)(F Fᵀ − I),
    /// W = λ/2 (ln J)² − μ ln J + μ/2 (tr FᵀF − 3).
    NeoHookean,
    /// A compressible viscous gas on material points (York Eqs. 21–25):
    /// σ = 2μ ε̇′ − (p + q) I. The particle's `work` holds its internal
    /// energy per unit reference volume, ρ_ref e (ρ_ref = m / V⁰).
    #[serde(skip)]
    GasPoint(GasPoint),
    /// Hypo-elastic (Jaumann rate, as [`SolidModel::LinearElastic`]) with
    /// J2 plasticity by radial return ([`J2`]); set by the scene for
    /// `model = "linear_elastic"` with a `plasticity` table. The particle's
    /// `work` holds the total stress work (stored and dissipated) per unit
    /// reference volume; its equivalent plastic strain and temperature are
    /// [`PlasticState`].
    #[serde(skip)]
    ElasticPlastic(J2),
    /// Hypo-elastic, optionally J2-plastic, with a failure model
    /// ([`Fracturing`]: Johnson–Cook damage or a spall strength); set by
    /// the scene for `model = "linear_elastic"` with a `failure` table. The
    /// point's damage (1: failed) travels in [`PlasticState::damage`]; a
    /// failed point keeps only a compressive pressure.
    #[serde(skip)]
    Fracturing(Fracturing),
    /// A membrane material point (York Sec. 3.2, [`MembraneLaw`]): its
    /// stress is updated by the explicit MPM step in the membrane's local
    /// frame (it needs the tangent from its neighbours); the particle's
    /// `work` holds its strain energy per unit reference volume.
    #[serde(skip)]
    Membrane(MembraneLaw),
    /// Hencky hyperelastic ([`crate::material::hencky`]):
    /// τ = J σ = λ tr(ε) I + 2μ ε with ε = ½ ln(F Fᵀ). The particle's `work`
    /// holds its stored energy per unit reference volume.
    Hencky,
    /// Hencky hyperelastic with J2 plasticity in the multiplicative split
    /// F = Fₑ Fₚ (exponential-map return on the Kirchhoff stress,
    /// [`crate::material::hencky`]); set by the scene for `model = "hencky"`
    /// with a `plasticity` table. Explicit and implicit (with its consistent
    /// tangent). The particle's `work` holds the stored energy plus the
    /// plastic work dissipated, per unit reference volume.
    #[serde(skip)]
    HenckyPlastic(J2),
    /// Hencky, optionally J2-plastic as [`SolidModel::HenckyPlastic`], with
    /// a failure model ([`Fracturing`]); set by the scene for
    /// `model = "hencky"` with a `failure` table. Explicit only. A failed
    /// point keeps only a compressive Kirchhoff pressure
    /// ([`crate::material::failure`]).
    #[serde(skip)]
    HenckyFracturing(Fracturing),
}

impl SolidModel {
    /// Names accepted in scene files.
    pub const NAMES: &'static str = "linear_elastic, neo_hookean, hencky";
}

/// A particle material as the MPM kernels see it: a solid, or a gas on
/// material points ([`SolidModel::GasPoint`], whose elastic constants are
/// unused).
#[derive(Debug, Clone, PartialEq)]
pub struct SolidMaterial {
    /// Name from the scene.
    pub name: String,
    /// Reference density ρ₀.
    pub density: f64,
    /// Constitutive model.
    pub model: SolidModel,
    /// Elastic constants.
    pub elastic: ElasticConstants,
}

impl SolidMaterial {
    /// Dilatational wave speed √((λ + 2μ)/ρ) at density `rho` (solids; a gas
    /// point's sound speed needs its energy: [`GasPoint::sound_speed`]).
    pub fn wave_speed(&self, rho: f64) -> f64 {
        (self.elastic.p_wave() / rho).sqrt()
    }

    /// The plasticity of this material, if it has one.
    #[inline]
    pub fn plasticity(&self) -> Option<&J2> {
        match &self.model {
            SolidModel::ElasticPlastic(j2) => Some(j2),
            SolidModel::Fracturing(f) | SolidModel::HenckyFracturing(f) => f.plasticity.as_ref(),
            SolidModel::HenckyPlastic(j2) => Some(j2),
            _ => None,
        }
    }

    /// The failure model of this material, if it has one.
    #[inline]
    pub fn failure(&self) -> Option<&Failure> {
        match &self.model {
            SolidModel::Fracturing(f) | SolidModel::HenckyFracturing(f) => Some(&f.failure),
            _ => None,
        }
    }

    /// The gas-point model of this material, if it is one.
    #[inline]
    pub fn gas(&self) -> Option<&GasPoint> {
        match &self.model {
            SolidModel::GasPoint(g) => Some(g),
            _ => None,
        }
    }

    /// Whether this is a gas whose points read their density from the grid
    /// ([`crate::material::PointDensity::Grid`]).
    #[inline]
    pub fn reads_grid_density(&self) -> bool {
        self.gas()
            .is_some_and(|g| g.density == super::gas_point::PointDensity::Grid)
    }

    /// The membrane law of this material, if it is a membrane.
    #[inline]
    pub fn membrane(&self) -> Option<&MembraneLaw> {
        match &self.model {
            SolidModel::Membrane(m) => Some(m),
            _ => None,
        }
    }

    /// Largest stable explicit step of one particle in a grid of smallest
    /// cell size `h`: `h / (c + |v|)` for a solid, [`GasPoint::dt_limit`]
    /// for a gas point. `p` gives the particle's state.
    #[inline(always)]
    pub fn dt_limit(&self, h: f64, p: &PointState, c_max: f64) -> f64 {
        let rho = p.mass / p.vol;
        match &self.model {
            SolidModel::GasPoint(g) => {
                g.dt_limit(h, rho, p.work * p.vol0 / p.mass, p.stress, p.speed, c_max)
            }
            SolidModel::Membrane(m) => h / (m.wave_speed() + p.speed),
            _ => h / (self.wave_speed(rho) + p.speed),
        }
    }

    /// Advances the particle stress over one step.
    ///
    /// `l` is the velocity gradient ∇v (Guilkey Eq. 23) over the step, `f_new`
    /// the updated deformation gradient and `j` its determinant, `stress` the
    /// Cauchy stress (updated in place) and `work` the accumulated stress work
    /// per unit reference volume (updated for rate models, whose strain energy
    /// is that work; for a gas point, its internal energy ρ_ref e). `gas`
    /// gives a gas point its reference density ρ_ref = m/V⁰, its Jacobian at
    /// the start of the step and the largest gas sound speed (York Eq. 24);
    /// solids ignore it. `plastic` is the point's plastic state (read and
    /// updated by the plastic models: [`SolidModel::ElasticPlastic`] heats
    /// at the current density `gas.rho_ref / j`, [`SolidModel::HenckyPlastic`]
    /// at the reference density `gas.rho_ref`, its plastic work being per
    /// unit reference volume). Returns `false` where the
    /// update cannot be made (a Hencky model's inverted step).
    #[inline]
    #[must_use]
    #[allow(clippy::too_many_arguments)]
    pub fn update_stress(
        &self,
        l: &Matrix3<f64>,
        f_new: &Matrix3<f64>,
        j: f64,
        dt: f64,
        gas: &GasInput,
        stress: &mut Matrix3<f64>,
        work: &mut f64,
        plastic: &mut PlasticState,
    ) -> bool {
        let ElasticConstants { lambda, mu } = self.elastic;
        match self.model {
            SolidModel::GasPoint(g) => {
                let step = GasStep {
                    // York Eq. 16: ρ = m/V with V = J V⁰.
                    rho_old: gas.rho_ref / gas.j_old,
                    rho_new: gas.rho_ref / j,
                    dt,
                    c_max: gas.c_max,
                };
                let (sigma, e_new, _) = g.update(l, *work / gas.rho_ref, &step);
                *stress = sigma;
                *work = gas.rho_ref * e_new;
            }
            SolidModel::LinearElastic => {
                let d = 0.5 * (l + l.transpose());
                let w = 0.5 * (l - l.transpose());
                let old = *stress;
                // York Eq. 19 (Jaumann rate; York's W is the negative of ours).
                *stress = old
                    + dt * (w * old - old * w)
                    + dt * (lambda * d.trace() * Matrix3::identity() + 2.0 * mu * d);
                // Stress power per unit current volume, midpoint in time,
                // converted to per unit reference volume with J.
                *work += dt * j * 0.5 * (old + *stress).component_mul(&d).sum();
            }
            SolidModel::NeoHookean => {
                *stress = neo_hookean_stress_j(lambda, mu, f_new, j);
            }
            SolidModel::ElasticPlastic(j2) => {
                let old = *stress;
                j2.update(l, dt, lambda, mu, gas.rho_ref / j, stress, plastic);
                let d = 0.5 * (l + l.transpose());
                // Total stress power (stored + dissipated), as for the
                // hypo-elastic model.
                *work += dt * j * 0.5 * (old + *stress).component_mul(&d).sum();
            }
            SolidModel::Fracturing(fr) => {
                let old = *stress;
                fr.update(l, dt, lambda, mu, gas.rho_ref / j, stress, plastic);
                let d = 0.5 * (l + l.transpose());
                // Total stress power, as above: at failure the elastic
                // energy the point stored becomes dissipated (the fracture
                // energy) and stays in the work.
                *work += dt * j * 0.5 * (old + *stress).component_mul(&d).sum();
            }
            SolidModel::Hencky | SolidModel::HenckyPlastic(_) | SolidModel::HenckyFracturing(_) => {
                // The explicit step's relative deformation: F ← (I + Δt L) F.
                let f_rel = Matrix3::identity() + l * dt;
                return self
                    .hencky_update(
                        &f_rel,
                        f_new,
                        j,
                        gas.j_old,
                        dt,
                        gas.rho_ref,
                        stress,
                        work,
                        plastic,
                        None,
                    )
                    .is_some();
            }
            // The explicit step updates a membrane point in its local frame
            // (`mpm::explicit`, York Sec. 3.2); without a frame the stress
            // is kept.
            SolidModel::Membrane(_) => {}
        }
        true
    }

    /// Stress at the end of an implicit step from the incremental deformation
    /// gradient `df` (ΔF = ∂x/∂xⁿ over the step), the new total `f_new` with
    /// determinant `j`, and the stress `stress_old` at the start of the step.
    ///
    /// Neo-Hookean: the hyperelastic stress of `f_new`. Hypo-elastic: the
    /// update of [`Self::update_stress`] with `Δt L = ΔF − I`, i.e.
    /// σ = σⁿ + (ΔW σⁿ − σⁿ ΔW) + λ tr(Δε) I + 2μ Δε.
    pub fn implicit_stress(
        &self,
        df: &Matrix3<f64>,
        f_new: &Matrix3<f64>,
        j: f64,
        stress_old: &Matrix3<f64>,
    ) -> Matrix3<f64> {
        let ElasticConstants { lambda, mu } = self.elastic;
        match self.model {
            // Plastic solids are explicit only (the scene rejects them in
            // implicit mode, and `spatial_tangent` gives none): the elastic
            // predictor stands in.
            SolidModel::LinearElastic
            | SolidModel::ElasticPlastic(_)
            | SolidModel::Fracturing(_) => {
                let g = df - Matrix3::identity();
                let d = 0.5 * (g + g.transpose());
                let w = 0.5 * (g - g.transpose());
                stress_old
                    + (w * stress_old - stress_old * w)
                    + lambda * d.trace() * Matrix3::identity()
                    + 2.0 * mu * d
            }
            SolidModel::NeoHookean => neo_hookean_stress_j(lambda, mu, f_new, j),
            // Gas points are explicit only (the scene rejects them in implicit
            // mode, and `spatial_tangent` gives none): the stress is kept.
            // The implicit step updates the Hencky models through
            // `hencky_update` (they need the plastic state and
            // give their own tangent).
            SolidModel::GasPoint(_)
            | SolidModel::Membrane(_)
            | SolidModel::Hencky
            | SolidModel::HenckyPlastic(_)
            | SolidModel::HenckyFracturing(_) => *stress_old,
        }
    }

    /// The spatial elasticity tensor used by the implicit tangent, which for
    /// both models is isotropic, c_abcd = λ' δ_ab δ_cd + μ' (δ_ac δ_bd +
    /// δ_ad δ_bc); returns `(λ', μ')` at total Jacobian `j`, or `None` for a
    /// model without a tangent.
    ///
    /// Neo-Hookean (Bonet & Wood, *Nonlinear continuum mechanics for finite
    /// element analysis*, Eq. 5.53 with their σ of Eq. 5.52, the same as
    /// [`neo_hookean_stress`]): λ' = λ/J, μ' = (μ − λ ln J)/J (exact
    /// linearisation of the Truesdell rate). Hypo-elastic: the small-strain
    /// moduli λ' = λ, μ' = μ (the Jaumann spin terms are left out of the
    /// tangent, so Newton converges linearly when rotations are large).
    pub fn spatial_tangent(&self, j: f64) -> Option<(f64, f64)> {
        let ElasticConstants { lambda, mu } = self.elastic;
        match self.model {
            SolidModel::LinearElastic => Some((lambda, mu)),
            SolidModel::NeoHookean => Some((lambda / j, (mu - lambda * j.ln()) / j)),
            SolidModel::GasPoint(_)
            | SolidModel::ElasticPlastic(_)
            | SolidModel::Fracturing(_)
            | SolidModel::Membrane(_)
            | SolidModel::Hencky
            | SolidModel::HenckyPlastic(_)
            | SolidModel::HenckyFracturing(_) => None,
        }
    }

    /// Whether the implicit mode can run this material: an isotropic
    /// [`Self::spatial_tangent`], or the Hencky models' general one
    /// ([`crate::material::hencky::Tangent`]).
    pub fn has_implicit_tangent(&self) -> bool {
        self.spatial_tangent(1.0).is_some() || self.is_hencky()
    }

    /// Whether this is a Hencky model ([`SolidModel::Hencky`],
    /// [`SolidModel::HenckyPlastic`] or [`SolidModel::HenckyFracturing`]),
    /// updated by [`Self::hencky_update`].
    #[inline]
    pub fn is_hencky(&self) -> bool {
        matches!(
            self.model,
            SolidModel::Hencky | SolidModel::HenckyPlastic(_) | SolidModel::HenckyFracturing(_)
        )
    }

    /// One step of a Hencky model ([`crate::material::hencky::step`]) from
    /// the relative deformation gradient `f_rel`, the new total `f_new`
    /// (determinant `j`; `j_old` at the start of the step): updates the
    /// Cauchy `stress`, the `work` (stored energy plus plastic work, per
    /// unit reference volume) and the plastic `state` (with a failure
    /// model its damage too; a failed point keeps only a compressive
    /// Kirchhoff pressure, [`crate::material::failure`]), writes the tangent
    /// ∂τ/∂h into `tangent` when given, and returns the plastic work of the
    /// step, or `None` for a model that is not Hencky or an inverted step.
    #[allow(clippy::too_many_arguments)]
    pub fn hencky_update(
        &self,
        f_rel: &Matrix3<f64>,
        f_new: &Matrix3<f64>,
        j: f64,
        j_old: f64,
        dt: f64,
        rho0: f64,
        stress: &mut Matrix3<f64>,
        work: &mut f64,
        plastic: &mut PlasticState,
        tangent: Option<&mut crate::material::hencky::Tangent>,
    ) -> Option<f64> {
        let (j2, failure) = match &self.model {
            SolidModel::Hencky => (None, None),
            SolidModel::HenckyPlastic(j2) => (Some(j2), None),
            SolidModel::HenckyFracturing(f) => (f.plasticity.as_ref(), Some(&f.failure)),
            _ => return None,
        };
        let ElasticConstants { lambda, mu } = self.elastic;
        let stored = |tau: &Matrix3<f64>| crate::material::hencky::stored_energy(tau, lambda, mu);
        let tau_old = *stress * j_old;
        if failure.is_some() && plastic.damage >= 1.0 {
            // A failed point (module `failure`): the Kirchhoff mean stress
            // follows Hencky's volumetric response K ln J from where it
            // was, with no tension; its work is the change of the energy it
            // stores, (tr τ)²/(18K).
            if j <= 0.0 || j_old <= 0.0 {
                return None;
            }
            let bulk = lambda + 2.0 * mu / 3.0;
            let mean = (tau_old.trace() / 3.0 + bulk * (j / j_old).ln()).min(0.0);
            let tau = Matrix3::identity() * mean;
            *work += stored(&tau) - stored(&tau_old);
            *stress = tau / j;
            return Some(0.0);
        }
        let s = crate::material::hencky::step(
            lambda, mu, j2, f_rel, f_new, &tau_old, dt, rho0, plastic, tangent,
        )?;
        let w_new = stored(&s.tau);
        let mut tau = s.tau;
        if j2.is_some() || failure.is_some() {
            // Stored energy plus plastic work; at failure the energy the
            // point stored becomes dissipated (the fracture energy) and
            // stays in the work.
            *work += w_new - stored(&tau_old) + s.ret.plastic_work;
        } else {
            // Hyperelastic: the work is the stored energy of F.
            *work = w_new;
        }
        if let Some(failure) = failure {
            failure.accumulate(&(tau / j), s.ret.dplastic, dt, plastic);
            if plastic.damage >= 1.0 {
                tau = crate::material::failure::failed_stress(&tau);
            }
        }
        *stress = tau / j;
        Some(s.ret.plastic_work)
    }

    /// Whether a particle of this material keeps its stress work
    /// ([`crate::mpm::Particles::work`]): every model but neo-Hookean, whose
    /// energy is a function of F and whose update leaves the work alone.
    pub fn reads_work(&self) -> bool {
        !matches!(self.model, SolidModel::NeoHookean)
    }

    /// Strain energy per unit reference volume: the accumulated `work` for
    /// the models that keep it ([`SolidMaterial::reads_work`]), the
    /// neo-Hookean energy of `f` otherwise.
    #[inline]
    pub fn strain_energy_density(&self, f: &Matrix3<f64>, work: f64) -> f64 {
        match self.model {
            // Rate models: the accumulated work; a gas point: ρ_ref e.
            SolidModel::LinearElastic
            | SolidModel::GasPoint(_)
            | SolidModel::ElasticPlastic(_)
            | SolidModel::Fracturing(_)
            | SolidModel::Membrane(_)
            | SolidModel::Hencky
            | SolidModel::HenckyPlastic(_)
            | SolidModel::HenckyFracturing(_) => work,
            SolidModel::NeoHookean => {
                let ElasticConstants { lambda, mu } = self.elastic;
                let j = f.determinant();
                let lnj = j.ln();
                0.5 * lambda * lnj * lnj - mu * lnj + 0.5 * mu * ((f.transpose() * f).trace() - 3.0)
            }
        }
    }
}

/// What a gas point's stress update needs beyond the kinematics (ignored by
/// solids).
#[derive(Debug, Clone, Copy)]
pub struct GasInput {
    /// Reference density ρ_ref = m / V⁰.
    pub rho_ref: f64,
    /// Jacobian J at the start of the step.
    pub j_old: f64,
    /// Largest sound speed among the gas points (York Eq. 24).
    pub c_max: f64,
}

impl GasInput {
    /// The input of a solid (unused values).
    pub const SOLID: Self = Self {
        rho_ref: 1.0,
        j_old: 1.0,
        c_max: 0.0,
    };
}

/// One particle's state, as [`SolidMaterial::dt_limit`] reads it.
#[derive(Debug, Clone, Copy)]
pub struct PointState<'a> {
    /// Mass m_p.
    pub mass: f64,
    /// Current volume V_p.
    pub vol: f64,
    /// Reference volume V_p⁰.
    pub vol0: f64,
    /// Work (a gas point: ρ_ref e).
    pub work: f64,
    /// Cauchy stress.
    pub stress: &'a Matrix3<f64>,
    /// Speed |v_p|.
    pub speed: f64,
}

/// Compressible neo-Hookean Cauchy stress σ = (λ ln J/J) I + (μ/J)(F Fᵀ − I).
#[inline]
pub fn neo_hookean_stress(lambda: f64, mu: f64, f: &Matrix3<f64>) -> Matrix3<f64> {
    neo_hookean_stress_j(lambda, mu, f, f.determinant())
}

/// [`neo_hookean_stress`] with J = det F given; forms only the six
/// independent entries of B = F Fᵀ.
#[inline]
pub fn neo_hookean_stress_j(lambda: f64, mu: f64, f: &Matrix3<f64>, j: f64) -> Matrix3<f64> {
    let inv_j = 1.0 / j;
    let iso = (lambda * j.ln() - mu) * inv_j;
    let m = mu * inv_j;
    let r0 = f.row(0);
    let r1 = f.row(1);
    let r2 = f.row(2);
    let (b00, b11, b22) = (r0.dot(&r0), r1.dot(&r1), r2.dot(&r2));
    let (b01, b02, b12) = (r0.dot(&r1), r0.dot(&r2), r1.dot(&r2));
    Matrix3::new(
        m * b00 + iso,
        m * b01,
        m * b02,
        m * b01,
        m * b11 + iso,
        m * b12,
        m * b02,
        m * b12,
        m * b22 + iso,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moduli_conversions_agree() {
        let a = ElasticConstants::from_young_poisson(200e9, 0.3);
        let b = ElasticConstants::from_bulk_shear(a.bulk(), a.mu);
        assert!((a.lambda - b.lambda).abs() < 1e-3);
        assert!((a.mu - b.mu).abs() < 1e-3);
    }

    #[test]
    fn neo_hookean_small_strain_matches_linear_elasticity() {
        let c = ElasticConstants::from_young_poisson(1e4, 0.3);
        let eps = 1e-7;
        let grad = Matrix3::new(1.0, 0.3, 0.0, 0.2, -0.5, 0.1, 0.0, 0.4, 0.7) * eps;
        let f = Matrix3::identity() + grad;
        let s = neo_hookean_stress(c.lambda, c.mu, &f);
        let e = 0.5 * (grad + grad.transpose());
        let lin = c.lambda * e.trace() * Matrix3::identity() + 2.0 * c.mu * e;
        assert!((s - lin).norm() < 1e-6 * lin.norm());
    }

    #[test]
    fn neo_hookean_energy_derivative_is_first_piola() {
        // P = ∂W/∂F = J σ F⁻ᵀ: check by central differences.
        let m = SolidMaterial {
            name: "t".into(),
            density: 1.0,
            model: SolidModel::NeoHookean,
            elastic: ElasticConstants::from_young_poisson(1e4, 0.3),
        };
        let f = Matrix3::new(1.1, 0.05, 0.0, -0.02, 0.93, 0.03, 0.01, 0.0, 1.04);
        let j = f.determinant();
        let p = j
            * neo_hookean_stress(m.elastic.lambda, m.elastic.mu, &f)
            * f.try_inverse().unwrap().transpose();
        let h = 1e-6;
        for a in 0..3 {
            for b in 0..3 {
                let mut fp = f;
                let mut fm = f;
                fp[(a, b)] += h;
                fm[(a, b)] -= h;
                let d = (m.strain_energy_density(&fp, 0.0) - m.strain_energy_density(&fm, 0.0))
                    / (2.0 * h);
                assert!(
                    (d - p[(a, b)]).abs() < 1e-4,
                    "P[{a}{b}]: {d} vs {}",
                    p[(a, b)]
                );
            }
        }
    }

    #[test]
    fn jaumann_rate_rotation_keeps_stress_invariants() {
        // A pure spin rotates the stress without changing its invariants (to O(dt²)).
        let m = SolidMaterial {
            name: "t".into(),
            density: 1.0,
            model: SolidModel::LinearElastic,
            elastic: ElasticConstants::from_young_poisson(1.0, 0.25),
        };
        let mut s = Matrix3::new(2.0, 0.5, 0.0, 0.5, -1.0, 0.0, 0.0, 0.0, 0.3);
        let tr0 = s.trace();
        let n0 = s.norm();
        let l = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        let steps = 1000;
        let dt = 1.0 / steps as f64;
        let mut work = 0.0;
        for _ in 0..steps {
            let ok = m.update_stress(
                &l,
                &Matrix3::identity(),
                1.0,
                dt,
                &GasInput::SOLID,
                &mut s,
                &mut work,
                &mut PlasticState::default(),
            );
            assert!(ok);
        }
        assert!((s.trace() - tr0).abs() < 1e-12);
        assert!((s.norm() - n0).abs() < 5e-3 * n0);
        assert!(work.abs() < 1e-12);
    }
}
