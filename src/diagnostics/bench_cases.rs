//! Benchmark problems shared by `benches/` and the probes (`probes/`), so
//! every speed figure is measured on the same scene.

use nalgebra::SVector;

use crate::grid::{Boundary, Grid};
use crate::material::eos::{FluidEos, IdealGas};
use crate::material::{
    ArtificialViscosity, ElasticConstants, GasPoint, PointDensity, SolidMaterial, SolidModel,
};
use crate::mpm::{ExplicitParams, Particles, UpdateScheme};
use crate::shape::ShapeKind;
use crate::stepper::{SolidRun, TimeControl};

/// What the benchmark block is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlockMaterial {
    /// Neo-Hookean solid (E = 1e6, ν = 0.3, ρ = 1000).
    NeoHookean,
    /// Gas points (York Sec. 3.3): ideal gas γ = 1.4, c_v = 717.5, ρ = 1.2,
    /// p = 1e5, μ = 1.8e-5, York's artificial viscosity (g = √2 Δx).
    GasPoint,
    /// Hypo-elastic with Johnson–Cook J2 plasticity (the neo-Hookean's
    /// E, ν, ρ; A = 0, so that every point with any stress flows: the worst
    /// case,
    /// the cost of the radial return with its Newton iteration.
    JohnsonCook,
    /// Hypo-elastic (Jaumann) without plasticity: the baseline of the
    /// plastic and failing blocks.
    HypoElastic,
    /// [`BlockMaterial::JohnsonCook`] with Johnson–Cook failure (Johnson &
    /// Cook 1985 OFHC copper D₁..D₅): the damage update on every flowing
    /// point (the block's strains stay far below failure).
    JohnsonCookFailure,
    /// Hypo-elastic with brittle tensile failure (a spall strength far
    /// above the block's stresses): the largest principal stress of every
    /// point each step.
    Tensile,
    /// Hencky hyperelastic (the neo-Hookean's E, ν, ρ).
    Hencky,
    /// Hencky with multiplicative J2 plasticity and the
    /// [`BlockMaterial::JohnsonCook`] flow stress (A = 0: every stressed
    /// point flows).
    HenckyJohnsonCook,
    /// [`BlockMaterial::HenckyJohnsonCook`] with the Johnson–Cook failure
    /// of [`BlockMaterial::JohnsonCookFailure`]: the damage update on the
    /// Hencky path.
    HenckyJohnsonCookFailure,
}

/// A 2D neo-Hookean block (E = 1e6, ν = 0.3, ρ = 1000) of 2×2 particles per
/// cell filling [0.1, 0.9]² of a 200×200 grid with fixed walls: 102 400
/// particles, in a slow rigid rotation (0.01 rad/s) so that every kernel
/// works; fixed Δt at Courant number 0.3, USL.
pub fn rotating_block(shape: ShapeKind) -> SolidRun<2> {
    rotating_block_of(shape, BlockMaterial::NeoHookean)
}

/// [`rotating_block`] made of `material`: the same particles, grid, shape
/// function and update, Δt at Courant number 0.3 of the material's wave
/// speed — so a gas point's cost is measured against a solid point's on
/// identical work.
pub fn rotating_block_of(shape: ShapeKind, material: BlockMaterial) -> SolidRun<2> {
    let n = 200;
    let grid = Grid::<2>::new(
        SVector::zeros(),
        SVector::repeat(1.0),
        [n, n],
        [[Boundary::Fixed; 2]; 2],
    );
    let h = 1.0 / n as f64;
    let (mat, rho, speed) = block_material(material, h);
    let vol = h * h / 4.0;
    let mut p = Particles::<2>::default();
    for j in 0..320 {
        for i in 0..320 {
            let x = SVector::from([
                0.1 + (i as f64 + 0.5) * h / 2.0,
                0.1 + (j as f64 + 0.5) * h / 2.0,
            ]);
            let v = SVector::from([-(x[1] - 0.5), x[0] - 0.5]) * 0.01;
            p.push(x, v, rho * vol, vol, SVector::repeat(h / 4.0), 0);
            if material == BlockMaterial::GasPoint {
                gas_point_at_rest(&mut p);
            }
        }
    }
    block_run(grid, mat, p, shape, 0.3 * h / speed)
}

/// The block's run: USL with `shape`, no damping, a fixed `dt`.
fn block_run<const D: usize>(
    grid: Grid<D>,
    mat: SolidMaterial,
    p: Particles<D>,
    shape: ShapeKind,
    dt: f64,
) -> SolidRun<D> {
    let params = ExplicitParams {
        shape,
        scheme: UpdateScheme::Usl,
        mass_floor: 1e-12,
        damping: 0.0,
        pic_fraction: 0.0,
    };
    let time = TimeControl {
        end: f64::INFINITY,
        cfl: 0.3,
        dt: Some(dt),
        max_steps: None,
    };
    SolidRun::new(grid, vec![mat], p, params, time)
}

/// Pressure p₀ and γ of the [`BlockMaterial::GasPoint`] block.
const GAS_P0: f64 = 1e5;
const GAS_GAMMA: f64 = 1.4;

/// The last particle pushed onto `p` as a gas point at p₀ (York Eq. 22:
/// ρ_ref e = p/(γ − 1) per unit reference volume).
fn gas_point_at_rest<const D: usize>(p: &mut Particles<D>) {
    let k = p.len() - 1;
    p.track_work();
    p.work[k] = GAS_P0 / (GAS_GAMMA - 1.0);
    p.stress.set(k, &(nalgebra::Matrix3::identity() * -GAS_P0));
}

/// The block's material on a grid of cell size `h`, its density and wave
/// speed (for Δt).
fn block_material(material: BlockMaterial, h: f64) -> (SolidMaterial, f64, f64) {
    let (gamma, p0) = (GAS_GAMMA, GAS_P0);
    match material {
        BlockMaterial::NeoHookean => {
            let mat = SolidMaterial {
                name: "block".into(),
                density: 1000.0,
                model: SolidModel::NeoHookean,
                elastic: ElasticConstants::from_young_poisson(1e6, 0.3),
            };
            let c = mat.wave_speed(1000.0);
            (mat, 1000.0, c)
        }
        BlockMaterial::JohnsonCook
        | BlockMaterial::HypoElastic
        | BlockMaterial::JohnsonCookFailure
        | BlockMaterial::Tensile
        | BlockMaterial::Hencky
        | BlockMaterial::HenckyJohnsonCook
        | BlockMaterial::HenckyJohnsonCookFailure => {
            use crate::material::failure::{Failure, Fracturing, JohnsonCookFailure};
            use crate::material::plasticity::{FlowStress, JohnsonCook, J2};
            let j2 = J2 {
                flow: FlowStress::JohnsonCook(JohnsonCook {
                    a: 0.0,
                    b: 1e4,
                    n: 0.26,
                    c: 0.014,
                    m: 1.03,
                    rate0: 1.0,
                    t_room: 300.0,
                    t_melt: 1800.0,
                }),
                taylor_quinney: 0.9,
                specific_heat: 477.0,
            };
            let jc_failure = Fracturing {
                plasticity: Some(j2),
                failure: Failure::JohnsonCook(JohnsonCookFailure {
                    d1: 0.54,
                    d2: 4.89,
                    d3: -3.03,
                    d4: 0.014,
                    d5: 1.12,
                    rate0: 1.0,
                    t_room: 300.0,
                    t_melt: 1800.0,
                    nonlocal_radius: 0.0,
                }),
            };
            let model = match material {
                BlockMaterial::HypoElastic => SolidModel::LinearElastic,
                BlockMaterial::Hencky => SolidModel::Hencky,
                BlockMaterial::HenckyJohnsonCook => SolidModel::HenckyPlastic(j2),
                BlockMaterial::HenckyJohnsonCookFailure => SolidModel::HenckyFracturing(jc_failure),
                BlockMaterial::JohnsonCookFailure => SolidModel::Fracturing(jc_failure),
                BlockMaterial::Tensile => SolidModel::Fracturing(Fracturing {
                    plasticity: None,
                    failure: Failure::Tensile {
                        spall_strength: 1e9,
                    },
                }),
                _ => SolidModel::ElasticPlastic(j2),
            };
            let mat = SolidMaterial {
                name: "block".into(),
                density: 1000.0,
                model,
                elastic: ElasticConstants::from_young_poisson(1e6, 0.3),
            };
            let c = mat.wave_speed(1000.0);
            (mat, 1000.0, c)
        }
        BlockMaterial::GasPoint => {
            let ideal = IdealGas::new(gamma, 717.5).expect("valid ideal gas");
            let mat = SolidMaterial {
                name: "gas".into(),
                density: 0.0,
                model: SolidModel::GasPoint(GasPoint {
                    eos: FluidEos::IdealGas(ideal),
                    viscosity: 1.8e-5,
                    q: ArtificialViscosity {
                        g: ArtificialViscosity::DEFAULT_G_OVER_DX * h,
                        kappa: ArtificialViscosity::DEFAULT_KAPPA,
                        c1: ArtificialViscosity::DEFAULT_C1,
                        c2: ArtificialViscosity::DEFAULT_C2,
                    },
                    min_pressure: f64::NEG_INFINITY,
                    density: PointDensity::Continuity,
                }),
                elastic: ElasticConstants {
                    lambda: 0.0,
                    mu: 0.0,
                },
            };
            (mat, 1.2, (gamma * p0 / 1.2f64).sqrt())
        }
    }
}

/// Cells per side of the [`rotating_block_3d`] grid (the unit cube).
pub const BLOCK_3D_GRID_CELLS: usize = 32;
/// Cells per side of the [`rotating_block_3d`] block (2 particles per cell
/// and axis, so 52³ = 140 608 particles).
pub const BLOCK_3D_CELLS: usize = 26;

/// The 3D analogue of [`rotating_block`]: a neo-Hookean block (E = 1e6,
/// ν = 0.3, ρ = 1000) of 2×2×2 particles per cell on the unit cube cut in
/// 32³ cells (h = 1/32) with fixed walls. The block spans cells 3..29 on
/// every axis, i.e. [3/32, 29/32]³ = [0.09375, 0.90625]³ (26 cells, 0.8125
/// wide, three empty cells to each wall): 52³ = 140 608 particles, each
/// h/2 wide (GIMP half-width h/4), in a slow rigid rotation about the
/// z axis through the cube's centre (0.01 rad/s) so that every kernel
/// works; fixed Δt at Courant number 0.3 of the dilatational wave speed,
/// USL.
pub fn rotating_block_3d(shape: ShapeKind) -> SolidRun<3> {
    rotating_block_3d_of(
        shape,
        BlockMaterial::NeoHookean,
        SVector::from([0.0, 0.0, 1.0]),
    )
}

/// [`rotating_block_3d`] made of `material` (as [`rotating_block_of`]) and
/// rotating about the unit `axis` through the cube's centre. About z the
/// deformation keeps the plane-strain structure (no (1,3), (2,3)
/// coupling); about a skew axis every component is non-zero, so that a
/// Hencky model's 3D eigen-solver does the work.
pub fn rotating_block_3d_of(
    shape: ShapeKind,
    material: BlockMaterial,
    axis: SVector<f64, 3>,
) -> SolidRun<3> {
    let n = BLOCK_3D_GRID_CELLS;
    let grid = Grid::<3>::new(
        SVector::zeros(),
        SVector::repeat(1.0),
        [n; 3],
        [[Boundary::Fixed; 2]; 3],
    );
    let h = 1.0 / n as f64;
    let (mat, rho, speed) = block_material(material, h);
    let omega = axis.normalize() * 0.01;
    let centre = SVector::<f64, 3>::repeat(0.5);
    let lower = ((n - BLOCK_3D_CELLS) / 2) as f64 * h;
    let per_side = 2 * BLOCK_3D_CELLS;
    let vol = h * h * h / 8.0;
    let mut p = Particles::<3>::default();
    for k in 0..per_side {
        for j in 0..per_side {
            for i in 0..per_side {
                let at = |m: usize| lower + (m as f64 + 0.5) * h / 2.0;
                let x = SVector::from([at(i), at(j), at(k)]);
                let v = omega.cross(&(x - centre));
                p.push(x, v, rho * vol, vol, SVector::repeat(h / 4.0), 0);
                if material == BlockMaterial::GasPoint {
                    gas_point_at_rest(&mut p);
                }
            }
        }
    }
    block_run(grid, mat, p, shape, 0.3 * h / speed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotating_block_3d_fills_its_cells() {
        let run = rotating_block_3d(ShapeKind::Gimp);
        assert_eq!(run.particles.len(), 52 * 52 * 52);
        let (lo, hi) = (3.0 / 32.0, 29.0 / 32.0);
        for x in &run.particles.x {
            assert!(x.iter().all(|&c| c > lo && c < hi), "{x:?}");
        }
        let vol: f64 = run.particles.vol.iter().sum();
        assert!((vol - 0.8125f64.powi(3)).abs() < 1e-12, "{vol}");
    }
}
