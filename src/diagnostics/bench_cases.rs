//! Benchmark problems shared by `benches/` and `examples/`, so every speed
//! figure is measured on the same scene.

use nalgebra::SVector;

use crate::grid::{Boundary, Grid};
use crate::material::{ElasticConstants, SolidMaterial, SolidModel};
use crate::mpm::{ExplicitParams, Particles, UpdateScheme};
use crate::shape::ShapeKind;
use crate::stepper::{SolidRun, TimeControl};

/// A 2D neo-Hookean block (E = 1e6, ν = 0.3, ρ = 1000) of 2×2 particles per
/// cell filling [0.1, 0.9]² of a 200×200 grid with fixed walls: 102 400
/// particles, in a slow rigid rotation (0.01 rad/s) so that every kernel
/// works; fixed Δt at Courant number 0.3, USL.
pub fn rotating_block(shape: ShapeKind) -> SolidRun<2> {
    let n = 200;
    let grid = Grid::<2>::new(
        SVector::zeros(),
        SVector::repeat(1.0),
        [n, n],
        [[Boundary::Fixed; 2]; 2],
    );
    let mat = SolidMaterial {
        name: "block".into(),
        density: 1000.0,
        model: SolidModel::NeoHookean,
        elastic: ElasticConstants::from_young_poisson(1e6, 0.3),
    };
    let h = 1.0 / n as f64;
    let vol = h * h / 4.0;
    let mut p = Particles::<2>::default();
    for j in 0..320 {
        for i in 0..320 {
            let x = SVector::from([
                0.1 + (i as f64 + 0.5) * h / 2.0,
                0.1 + (j as f64 + 0.5) * h / 2.0,
            ]);
            let v = SVector::from([-(x[1] - 0.5), x[0] - 0.5]) * 0.01;
            p.push(x, v, 1000.0 * vol, vol, SVector::repeat(h / 4.0), 0);
        }
    }
    let params = ExplicitParams {
        shape,
        scheme: UpdateScheme::Usl,
        mass_floor: 1e-12,
        damping: 0.0,
    };
    let dt = 0.3 * h / mat.wave_speed(1000.0);
    let time = TimeControl {
        end: f64::INFINITY,
        cfl: 0.3,
        dt: Some(dt),
        max_steps: None,
    };
    SolidRun::new(grid, vec![mat], p, params, time)
}
