use mpmice::grid::{Boundary, Grid};
use mpmice::material::{ElasticConstants, SolidMaterial, SolidModel};
use mpmice::mpm::{ExplicitParams, Particles, UpdateScheme};
use mpmice::shape::ShapeKind;
use mpmice::stepper::{SolidRun, TimeControl};
use nalgebra::SVector;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args[1].parse().unwrap();
    let w: f64 = args[2].parse().unwrap();
    let shape = match args[3].as_str() {
        "linear" => ShapeKind::Linear,
        "gimp" => ShapeKind::Gimp,
        _ => ShapeKind::QuadraticBspline,
    };
    let grid = Grid::<2>::new(
        SVector::zeros(),
        SVector::repeat(1.0),
        [n, n],
        [[Boundary::Fixed; 2]; 2],
    );
    let mat = SolidMaterial {
        name: "b".into(),
        density: 1000.0,
        model: SolidModel::NeoHookean,
        elastic: ElasticConstants::from_young_poisson(1e6, 0.3),
    };
    let mut p = Particles::<2>::default();
    let h = 1.0 / n as f64;
    let vol = h * h / 4.0;
    let m = (0.8 / h * 2.0).round() as usize;
    for j in 0..m {
        for i in 0..m {
            let x = SVector::from([
                0.1 + (i as f64 + 0.5) * h / 2.0,
                0.1 + (j as f64 + 0.5) * h / 2.0,
            ]);
            let v = SVector::from([-(x[1] - 0.5), x[0] - 0.5]) * w;
            p.push(x, v, 1000.0 * vol, vol, SVector::repeat(h / 4.0), 0);
        }
    }
    let params = ExplicitParams {
        shape,
        scheme: UpdateScheme::Usl,
        mass_floor: 1e-12,
    };
    let c = mat.wave_speed(1000.0);
    let time = TimeControl {
        end: f64::INFINITY,
        cfl: 0.3,
        dt: Some(0.3 * h / c),
        max_steps: Some(400),
    };
    let mut run = SolidRun::new(grid, vec![mat], p, params, time);
    let e0 = run.energies();
    for s in 0..400 {
        if let Err(e) = run.step() {
            println!("{e}");
            break;
        }
        if s % 200 == 0 {
            let e = run.energies();
            println!(
                "step {s} t {:.4e} K {:.6e} S {:.6e} J0 {:.4}",
                run.t,
                e.kinetic,
                e.strain,
                run.particles.f[0].determinant()
            );
        }
    }
    println!("E0 {:?}", e0);
}
