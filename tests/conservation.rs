//! Conservation laws of the explicit step: mass exactly, linear momentum to
//! round-off on a free grid (Σ_i ∇S_ip = 0 and Σ_i S_ip = 1), and the energy
//! exchange of the colliding disks.

use mpmice::driver::{run_scene, RunOptions};
use mpmice::grid::{Boundary, Grid};
use mpmice::material::{ElasticConstants, SolidMaterial, SolidModel};
use mpmice::mpm::{ExplicitParams, Particles, UpdateScheme};
use mpmice::shape::ShapeKind;
use mpmice::stepper::{SolidRun, TimeControl};
use nalgebra::SVector;

/// A spinning, shearing elastic block on a free grid, 400 steps, with PIC
/// share `pic` in the particle velocity update.
fn free_block(
    shape: ShapeKind,
    scheme: UpdateScheme,
    pic: f64,
) -> mpmice::error::Result<(SVector<f64, 2>, SVector<f64, 2>, f64)> {
    let grid = Grid::<2>::new(
        SVector::zeros(),
        SVector::repeat(1.0),
        [32, 32],
        [[Boundary::Free; 2]; 2],
    );
    let mat = SolidMaterial {
        name: "b".into(),
        density: 1000.0,
        model: SolidModel::NeoHookean,
        elastic: ElasticConstants::from_young_poisson(1e5, 0.3),
    };
    let h = 1.0 / 32.0;
    let mut p = Particles::<2>::default();
    for j in 0..24 {
        for i in 0..24 {
            let x = SVector::from([
                0.3 + (i as f64 + 0.5) * h / 2.0,
                0.3 + (j as f64 + 0.5) * h / 2.0,
            ]);
            let v = SVector::from([0.3 - (x[1] - 0.5), 0.1 + 0.5 * (x[0] - 0.5) + x[1] * x[1]]);
            p.push(
                x,
                v,
                1000.0 * h * h / 4.0,
                h * h / 4.0,
                SVector::repeat(h / 4.0),
                0,
            );
        }
    }
    let scale: f64 = p.mass.iter().zip(&p.v).map(|(m, v)| m * v.norm()).sum();
    // Floor 0: only exactly empty nodes (which carry exactly zero force) are
    // skipped, so the algebra conserves momentum to round-off. (A positive
    // floor drops the tiny force on GIMP's tail nodes: ~1e-12 relative drift.)
    let params = ExplicitParams {
        shape,
        scheme,
        mass_floor: 0.0,
        damping: 0.0,
        pic_fraction: pic,
    };
    let time = TimeControl {
        end: f64::INFINITY,
        cfl: 0.3,
        dt: None,
        max_steps: Some(400),
    };
    let mut run = SolidRun::new(grid, vec![mat], p, params, time);
    let p0 = run.particles.momentum();
    while !run.finished() {
        run.step()?;
    }
    Ok((p0, run.particles.momentum(), scale))
}

#[test]
fn momentum_is_conserved_to_round_off_on_a_free_grid() {
    for shape in [
        ShapeKind::Linear,
        ShapeKind::Gimp,
        ShapeKind::QuadraticBspline,
        ShapeKind::CubicBspline,
        ShapeKind::QuadraticBsplineGimp,
    ] {
        for scheme in [UpdateScheme::Usf, UpdateScheme::Usl, UpdateScheme::Musl] {
            if shape == ShapeKind::Linear && scheme == UpdateScheme::Usl {
                continue; // unstable here, see the next test
            }
            // The PIC share moves momentum between particles through the
            // grid (Σ_p m_p Σ_i S_ip v_i = Σ_i m_i v_i), so it conserves
            // it as FLIP does.
            for pic in [0.0, 0.3] {
                let (p0, p1, scale) = free_block(shape, scheme, pic)
                    .unwrap_or_else(|e| panic!("{shape:?} {scheme:?} pic {pic}: {e}"));
                let drift = (p1 - p0).norm() / scale;
                assert!(
                    drift < 1e-13,
                    "{shape:?} {scheme:?} pic {pic}: momentum drift {drift}"
                );
            }
        }
    }
}

/// The linear hat under USL is unstable when a particle enters a cell at a
/// free surface: the new node's mass is w·m_p but its stress force does not
/// scale with w, so vᴸ there is huge and the velocity gradient explodes. The
/// run must stop with an error naming the step and the particle, not a NaN.
#[test]
fn linear_hat_usl_small_mass_instability_is_reported_cleanly() {
    let err = free_block(ShapeKind::Linear, UpdateScheme::Usl, 0.0).expect_err("known to fail");
    let msg = err.to_string();
    assert!(msg.contains("step") && msg.contains("particle"), "{msg}");
}

#[test]
fn colliding_disks_conserve_mass_and_momentum_and_bounce() {
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/cases/two_disks.toml"))
            .expect("default scene");
    let mut s = mpmice::scene::parse(&text).expect("valid");
    s.output.interval = None;
    let dir = tempfile::tempdir().expect("tmp");
    let sum = run_scene(&s, &RunOptions::quiet(dir.path(), 1)).expect("run");
    assert_eq!(sum.mass_drift, 0.0);
    // Zero total momentum, kept to round-off relative to Σ m|v|.
    assert!(
        sum.momentum_drift < 1e-13,
        "momentum drift {}",
        sum.momentum_drift
    );
    // Elastic bounce: after the collision most energy is kinetic again and the
    // total is kept within a few per cent (scheme dissipation at the contact;
    // measured −3.4 % on the default 64² grid).
    assert!(
        sum.energy_drift.abs() < 0.04,
        "energy drift {}",
        sum.energy_drift
    );
    assert!(sum.final_energy.kinetic > 0.8 * sum.initial_energy.kinetic);
    // The history shows the exchange: strain energy peaks mid-collision.
    let hist = std::fs::read_to_string(dir.path().join("history.csv")).expect("history");
    let peak = hist
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .nth(2)
                .expect("strain column")
                .parse::<f64>()
                .expect("number")
        })
        .fold(0.0f64, f64::max);
    assert!(
        peak > 0.5 * sum.initial_energy.kinetic,
        "strain peak {peak}"
    );
}
