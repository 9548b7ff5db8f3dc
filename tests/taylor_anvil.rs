//! The Taylor anvil (`cases/taylor_anvil.toml`, issue 18): a Johnson–Cook
//! OFHC copper rod on a rigid frictionless wall in axisymmetric MPM, at
//! R₀/6 (the full study: `cargo run --release -p verification --
//! taylor_anvil`).

use std::path::Path;

use mpmice::diagnostics::taylor::{run, TaylorMeasured, MEASURED};

fn base() -> mpmice::scene::Scene {
    let path = format!("{}/cases/taylor_anvil.toml", env!("CARGO_MANIFEST_DIR"));
    mpmice::scene::load(Path::new(&path)).expect("case parses")
}

fn show(m: &TaylorMeasured) {
    println!(
        "h = R0/{:.0}, v = {} m/s: gap {:.2e} m, L/L0 {:.4}, D/D0 {:.4} (footprint {:.4}), K0 {:.3} J/rad, K \
         {:.3}, W {:.3}, elastic {:.4}, plastic (heat) {:.3}; energy error {:.2e}, plastic \
         account {:.2e}; max eps {:.3}; {} particles, {} steps, {:.2} s",
        3.81e-3 / m.h,
        m.speed,
        m.gap,
        m.length_ratio(),
        m.diameter_ratio(),
        m.footprint / 7.62e-3,
        m.kinetic0,
        m.kinetic,
        m.work,
        m.elastic,
        m.plastic,
        m.energy_error(),
        m.plastic_account_error(),
        m.max_plastic_strain,
        m.particles,
        m.steps,
        m.wall_s
    );
}

/// At R₀/6 and 190 m/s: the final length and impact-face diameter within
/// 8 % of the measured rod (L_f/L₀ 0.638, D_f/D₀ 1.78; the study shows the
/// gap at finer grids); the energy account closes: the kinetic energy lost
/// equals the stress work to 2e-3 of K₀ (the scheme's energy error: MUSL
/// with GIMP dissipates a little), and the plastic work from the heat
/// equals the kinetic energy lost minus the elastic energy left to 2e-3 of
/// K₀ (that error plus the difference between the midpoint stress power
/// and the end-of-step σ_y Δε̄). At 130, 146 and 190 m/s (R₀/3) the final
/// length falls and the diameter grows monotonically with the speed, as
/// measured.
#[test]
fn copper_rod_at_190_m_per_s_matches_the_measured_shape() {
    let b = base();
    let m = run(&b, 6, 190.0, 80e-6).expect("runs");
    show(&m);
    let (_, l_ref, d_ref) = MEASURED[2];
    assert!((m.length_ratio() / l_ref - 1.0).abs() < 0.08, "L/L0");
    assert!((m.footprint / 7.62e-3 / d_ref - 1.0).abs() < 0.08, "D/D0");
    assert!(m.energy_error() < 2e-3, "energy error");
    assert!(m.plastic_account_error() < 2e-3, "plastic work account");
    let mut last: Option<TaylorMeasured> = None;
    for (v, _, _) in MEASURED {
        let m = run(&b, 3, v, 80e-6).expect("runs");
        show(&m);
        if let Some(prev) = last {
            assert!(m.length < prev.length && m.footprint > prev.footprint);
        }
        assert!(m.energy_error() < 2e-3 && m.plastic_account_error() < 1e-2);
        last = Some(m);
    }
}

/// The same rod with the multiplicative plasticity (`model = "hencky"`,
/// `material::hencky`) instead of the hypo-elastic radial return, at R₀/6
/// and 190 m/s (plastic strains to about 2): the two formulations differ
/// only by terms of the order of the elastic strains (σ_y/E ≈ 1e-3), so
/// the final length and footprint agree to a few 1e-3, and the energy
/// account closes as tightly.
#[test]
fn hencky_plasticity_gives_the_hypo_elastic_rod() {
    let b = base();
    let hypo = run(&b, 6, 190.0, 80e-6).expect("runs");
    let mut h = b.clone();
    h.materials[0].model = Some(mpmice::material::SolidModel::Hencky);
    let henc = run(&h, 6, 190.0, 80e-6).expect("runs");
    show(&hypo);
    show(&henc);
    let dl = (henc.length_ratio() / hypo.length_ratio() - 1.0).abs();
    let dd = (henc.footprint / hypo.footprint - 1.0).abs();
    println!("Hencky against hypo-elastic: length {dl:.2e}, footprint {dd:.2e}");
    assert!(dl < 3e-3 && dd < 3e-3, "{dl:e} {dd:e}");
    assert!(henc.max_plastic_strain > 1.5);
    assert!(henc.energy_error() < 2e-3, "energy error");
}
