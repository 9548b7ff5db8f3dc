//! Coupled MPM-ICE (Guilkey Sec. 3.3): conservation-law and exact-solution
//! checks of the explicit step.

use mpmice::diagnostics::coupled::block_in_air;

/// Largest deviation from the velocity `u` of the first fluid's cells and
/// of the particles of every solid field.
fn velocity_deviations(run: &mpmice::coupling::CoupledRun<2>, u: [f64; 2]) -> (f64, f64) {
    let u = nalgebra::SVector::<f64, 2>::from(u);
    let air = &run.fluid.cells[0];
    let uf = run
        .fluid
        .layout
        .interior
        .iter()
        .map(|&c| (air.velocity[c] - u).norm())
        .fold(0.0, f64::max);
    let up = run
        .fields
        .iter()
        .flat_map(|f| f.particles.v.iter())
        .map(|v| (v - u).norm())
        .fold(0.0, f64::max);
    (uf, up)
}

/// Largest relative deviation of the cell pressure from `p0`.
fn pressure_dev(run: &mpmice::coupling::CoupledRun<2>, p0: f64) -> f64 {
    run.fluid
        .layout
        .interior
        .iter()
        .map(|&c| ((run.fluid.pressure[c] - p0) / p0).abs())
        .fold(0.0, f64::max)
}

#[test]
fn solid_at_rest_in_still_gas_stays_at_rest() {
    let mut run = block_in_air(20, [0.3, 0.3], [0.7, 0.65], [0.0; 2], [0.0; 2], false).unwrap();
    for _ in 0..200 {
        run.step(f64::INFINITY).unwrap();
    }
    let (uf, up) = velocity_deviations(&run, [0.0; 2]);
    let dp = pressure_dev(&run, 101_325.0);
    eprintln!(
        "t = {:e}, fluid {uf:e}, particles {up:e}, dp {dp:e}",
        run.fluid.time
    );
    assert!(
        uf < 1e-9 && up < 1e-9,
        "spurious currents: fluid {uf:e}, particles {up:e}"
    );
    assert!(dp < 1e-12, "pressure changed by {dp:e}");
}

/// Zhang Sec. 3: a solid block translating through air at the air's
/// velocity produces no pressure change, over ten cell crossings.
fn translating_block(rigid: bool) {
    let u = [100.0, 0.0];
    let mut run = block_in_air(20, [0.1, 0.4], [0.3, 0.6], u, u, rigid).unwrap();
    let x0 = run.fields[0].particles.x[0][0];
    while run.fluid.time < 5e-3 {
        run.step(5e-3 - run.fluid.time).unwrap();
    }
    let moved = (run.fields[0].particles.x[0][0] - x0) / 0.05;
    let dp = pressure_dev(&run, 101_325.0);
    let (du, _) = velocity_deviations(&run, u);
    eprintln!(
        "rigid {rigid}: {} steps, moved {moved} cells, dp {dp:e}, du {du:e}",
        run.steps
    );
    assert!(moved > 9.99, "moved {moved} cells");
    assert!(dp < 1e-10, "relative pressure change {dp:e}");
    assert!(du < 1e-8 * 100.0, "velocity change {du:e}");
}

#[test]
fn block_translating_with_the_air_keeps_the_pressure_deformable() {
    translating_block(false);
}

#[test]
fn block_translating_with_the_air_keeps_the_pressure_rigid() {
    translating_block(true);
}

/// The semi-implicit pressure (implicit ICE + explicit MPM) keeps Zhang's
/// translating block at constant pressure too.
#[test]
fn translating_block_semi_implicit() {
    use mpmice::ice::SemiImplicit;
    let u = [100.0, 0.0];
    let mut run = block_in_air(20, [0.1, 0.4], [0.3, 0.6], u, u, false).unwrap();
    run.ice.implicit = Some(SemiImplicit::default());
    run.ice.cfl = 0.5;
    while run.fluid.time < 1e-3 {
        run.step(1e-3 - run.fluid.time).unwrap();
    }
    let dp = pressure_dev(&run, 101_325.0);
    eprintln!("semi-implicit: {} steps, dp {dp:e}", run.steps);
    assert!(dp < 1e-10, "relative pressure change {dp:e}");
}

/// Hard case: a steel block expanding (in tension, below the threshold of
/// the solid EOS, Guilkey Fig. 1) next to air: the equilibration keeps a
/// positive pressure and nothing becomes NaN; the steel/air density ratio is
/// ~7600:1 with K = 1e15 and near-empty cells at the surface.
#[test]
fn solid_in_tension_next_to_gas_runs_without_nan() {
    let mut run = block_in_air(20, [0.3, 0.3], [0.7, 0.7], [0.0; 2], [0.0; 2], false).unwrap();
    let p = &mut run.fields[0].particles;
    for (x, v) in p.x.iter().zip(p.v.iter_mut()) {
        *v = (x - nalgebra::SVector::<f64, 2>::repeat(0.5)) * 20.0;
    }
    let (mut tension, mut p_min) = (f64::NEG_INFINITY, f64::INFINITY);
    for _ in 0..300 {
        run.step(f64::INFINITY).unwrap();
        for s in run.fields[0].particles.stress.iter() {
            tension = tension.max(s[(0, 0)] + s[(1, 1)]);
        }
        for &c in &run.fluid.layout.interior {
            p_min = p_min.min(run.fluid.pressure[c]);
        }
    }
    let finite = run.fields[0]
        .particles
        .stress
        .iter()
        .all(|s| s.iter().all(|v| v.is_finite()))
        && run.fluid.cells.iter().all(|mc| {
            mc.velocity.iter().all(|u| u.iter().all(|v| v.is_finite()))
                && mc.temperature.iter().all(|t| t.is_finite())
        });
    eprintln!("max tr σ = {tension:e}, min p = {p_min:e}");
    assert!(finite);
    assert!(tension > 1e7, "the block should be in tension: {tension:e}");
    assert!(p_min > 0.0, "pressure {p_min:e}");
}

/// Guilkey Sec. 4.2: the adiabatic piston converges at first order to
/// P1 (V1/V2)^γ (Eq. 44): closed-end pressure at compression ratio 3.
#[test]
fn piston_converges_to_the_adiabatic_law() {
    use mpmice::coupling::RigidInterface;
    use mpmice::diagnostics::coupled::piston_history;
    let err = |n: usize| {
        let (h, _) = piston_history(n, 10.0, 0.02, 3.01, RigidInterface::Smeared).unwrap();
        let &(r, p, e) = h.iter().find(|s| (s.0 - 3.0).abs() < 0.01).unwrap();
        eprintln!(
            "N = {n}: ratio {r:.3}, p/p_exact − 1 = {:+.4e}",
            p / e - 1.0
        );
        (p / e - 1.0).abs()
    };
    let (e1, e2) = (err(60), err(120));
    assert!(e2 < 0.035, "error {e2:e} at N = 120");
    assert!(e1 / e2 > 1.6, "not converging: {e1:e} -> {e2:e}");
}

/// `cases/piston.toml` is the piston of `diagnostics::coupled::piston`: at
/// N = 120 and compression ratio 3 (t = 0.01 + (1 − 1/3)/10 s) its
/// closed-end pressure is the diagnostic run's, with either rigid
/// interface (`coupling.rigid_interface`), and within the first-order
/// bound of Eq. 44 (smeared) or 1 % (sharp). The two runs differ in the
/// last bits from the start (1e-15 in Δt by step 611); the smeared
/// interface keeps that at round-off (1e-12), the sharp one amplifies it
/// in the gas left in the cells the piston covers (`rigid_volume`'s
/// notes) to about 5e-5, hence its looser agreement bound.
#[test]
fn piston_case_file_matches_the_adiabatic_law() {
    use mpmice::coupling::RigidInterface;
    use mpmice::diagnostics::coupled::piston;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/piston.toml");
    for (interface, same, bound) in [
        (RigidInterface::Smeared, 1e-9, 0.035),
        (RigidInterface::Sharp, 1e-3, 0.01),
    ] {
        let mut sc = mpmice::scene::load(&path).unwrap();
        sc.grid.cells = vec![120];
        sc.coupling.rigid_interface = interface;
        let t_end = 0.01 + (1.0 - 1.0 / 3.0) / 10.0;
        let mut run = mpmice::scene::build_coupled_run::<1>(&sc).unwrap();
        let mut reference = piston(120, 10.0, 0.02, interface).unwrap();
        for r in [&mut run, &mut reference] {
            while r.fluid.time < t_end * (1.0 - 1e-12) {
                r.step(t_end - r.fluid.time).unwrap();
            }
        }
        let c0 = run.fluid.layout.interior[0];
        let (p, p_ref) = (run.fluid.pressure[c0], reference.fluid.pressure[c0]);
        let exact = 101_325.0 * 3.0f64.powf(1.4);
        eprintln!("{interface:?}: scene p = {p:e}, diagnostic p = {p_ref:e}, exact {exact:e}");
        assert!(
            (p / p_ref - 1.0).abs() < same,
            "{interface:?}: scene {p:e} vs diagnostic {p_ref:e}"
        );
        assert!(
            (p / exact - 1.0).abs() < bound,
            "{interface:?}: p/exact − 1 = {:e}",
            p / exact - 1.0
        );
    }
}

/// Issue 21: with the sharp rigid interface the piston's closed-end
/// pressure follows P1 (V1/V2)^γ (Guilkey Eq. 44) within 1 % at every
/// compression ratio from 1.5 to 5.5, at N = 120 and 240 (the smeared
/// interface is 7.2 % and 3.4 % off at ratio 5, `piston_adiabatic`). This
/// is the coarse regime the sharp interface is for: it does not converge
/// (−0.8 % at N = 480, −1.2 % at 960; `rigid_volume`'s notes).
#[test]
fn sharp_rigid_piston_follows_the_adiabat_at_every_ratio() {
    use mpmice::coupling::RigidInterface;
    use mpmice::diagnostics::coupled::piston_history;
    for n in [120, 240] {
        let (h, _) = piston_history(n, 10.0, 0.02, 5.6, RigidInterface::Sharp).unwrap();
        assert_eq!(h.len(), 9, "samples at ratios 1.5 … 5.5");
        for (r, p, e) in h {
            eprintln!(
                "N = {n}: ratio {r:.3}, p/p_exact − 1 = {:+.4e}",
                p / e - 1.0
            );
            assert!(
                (p / e - 1.0).abs() < 0.01,
                "N = {n}, ratio {r:.3}: {:+e}",
                p / e - 1.0
            );
        }
    }
}

/// Guilkey Sec. 4.1 through the scene file: Eq. 43 error below 0.13 at
/// dx = 0.05 and converging at about first order from dx = 0.1.
#[test]
fn pressurized_cylinder_eq43_converges() {
    use mpmice::diagnostics::coupled::run_cylinder_scene;
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/pressurized_cylinder.toml");
    let err = |n: usize| {
        let sc = mpmice::scene::load(&path).unwrap();
        let (_, m, _) = run_cylinder_scene(sc, 1.2 / n as f64).unwrap();
        eprintln!("n = {n}: P = {:e}, Eq. 43 = {:e}", m.pressure, m.error43);
        assert!(
            (m.pressure - 19.3e6).abs() < 0.02 * 19.3e6,
            "P = {:e}",
            m.pressure
        );
        m.error43
    };
    let (e1, e2) = (err(12), err(24));
    assert!(e2 < 0.13, "Eq. 43 error {e2:e} at dx = 0.05");
    assert!((e1 / e2).log2() > 0.9, "order {}", (e1 / e2).log2());
}

/// Guilkey Sec. 4.3 through the scene file at its own resolution
/// (h = 0.005) on the study's cropped domain [0, 0.8] × [0, 0.2]: at the
/// case's end (0.48 ms) the attached shock is within 2.15° of the exact
/// 37.76° and p2/p1 within 2.5 % of 3.771 (measured 36.03°, 3.701; the
/// `wedge_mach3` study refines to 0.25° and 0.63 % at h = 0.00125).
#[test]
fn wedge_mach3_case_gives_the_oblique_shock() {
    use mpmice::diagnostics::coupled::measure_wedge_mach3;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/wedge_mach3.toml");
    let mut sc = mpmice::scene::load(&path).unwrap();
    sc.grid.upper[1] = 0.2;
    sc.grid.cells[1] = 40;
    let mut run = mpmice::scene::build_coupled_run::<2>(&sc).unwrap();
    run.advance_to(sc.time.end).unwrap();
    let m = measure_wedge_mach3(&run);
    eprintln!("angle {:.3}, p2/p1 {:.4}", m.angle_deg, m.pressure_ratio);
    assert!((m.angle_deg - 37.76).abs() < 2.15, "angle {}", m.angle_deg);
    assert!(
        (m.pressure_ratio / 3.771 - 1.0).abs() < 0.025,
        "p2/p1 {}",
        m.pressure_ratio
    );
}

/// The wedge of Guilkey Sec. 4.3 seen from itself
/// (`cases/wedge_mach3_steady.toml`, h = 5 mm): at rest in the Mach 3
/// stream the flow settles (two samples 0.3 ms apart from 2.4 ms agree
/// within 0.02° by 3.0 ms), and its steady shock angle is within 3° of the
/// θ–β–M value, 37.76° (measured 40.602° at 2.4 ms, 40.604° at 2.7 ms;
/// the `wedge_steady` study refines it to 0.92° at h = 1.25 mm and adds a
/// 15° wedge at Mach 2 and a 25° wedge at Mach 4).
#[test]
fn the_wedge_at_rest_in_a_mach_3_stream_reaches_a_steady_oblique_shock() {
    use mpmice::diagnostics::wedge::{run_steady_wedge, steady_wedge_scene};
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/wedge_mach3_steady.toml");
    let base = mpmice::scene::load(&path).unwrap();
    let (sc, stream) = steady_wedge_scene(&base, 3.0, 20.0, 1).unwrap();
    // The scene rebuilt at 20° and Mach 3 is the case itself.
    let u = sc.regions[0].states[0].velocity.as_ref().unwrap()[0];
    let b = &base.regions[0].states[0].velocity.as_ref().unwrap()[0];
    assert!((u - b).abs() < 0.5, "{u} against {b}");
    let r = run_steady_wedge(&sc, &stream, 20.0, 0.3e-3, 0.02, 3.0e-3).unwrap();
    eprintln!(
        "angle {:.3} at {:.2} ms after {:.3} (exact {:.3}), p2/p1 {:.3} (exact {:.3})",
        r.angle_deg,
        r.time * 1e3,
        r.angle_before_deg,
        r.exact.beta_deg,
        r.pressure_ratio,
        r.exact.pressure_ratio
    );
    assert!((r.exact.beta_deg - 37.76).abs() < 0.01);
    assert!(r.settled, "not steady by 3 ms");
    assert!(
        (r.angle_deg - r.exact.beta_deg).abs() < 3.0,
        "{}",
        r.angle_deg
    );
}

/// Steel at half its density filling a closed 8 × 8 box (θ_s = 1/2 in
/// every cell) with air at 300 K; the steel at 400 K and exchanging heat
/// with the air at the coefficient `h`.
fn heated_mixture(h: f64) -> mpmice::coupling::CoupledRun<2> {
    mpmice::diagnostics::coupled::heated_mixture(8, 0.5, h, 400.0).unwrap()
}

/// (thermal energy, mean temperature) of the air and (thermal energy,
/// lowest, highest particle temperature) of the steel.
fn thermal(run: &mpmice::coupling::CoupledRun<2>) -> ((f64, f64), (f64, f64, f64)) {
    use mpmice::material::eos::EquationOfState;
    let (c_g, c_s) = (717.5, run.fields[0].eos.specific_heat_cv());
    let cells = &run.fluid.cells[0];
    let int = &run.fluid.layout.interior;
    let e_g: f64 = int
        .iter()
        .map(|&c| cells.mass[c] * c_g * cells.temperature[c])
        .sum();
    let t_g = int.iter().map(|&c| cells.temperature[c]).sum::<f64>() / int.len() as f64;
    let p = &run.fields[0].particles;
    let e_s: f64 = (0..p.len())
        .map(|i| p.mass[i] * c_s * p.temperature[i])
        .sum();
    let (lo, hi) = p
        .temperature
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| {
            (a.min(t), b.max(t))
        });
    ((e_g, t_g), (e_s, lo, hi))
}

/// Solid–fluid heat exchange (Guilkey Eq. 39, Sec. 3.3 step 10) in the
/// uniform mixture of [`heated_mixture`]. Nothing moves, so the exchange is
/// all that happens. Exact: the thermal energy `Σ_p m_p c_s T_p + Σ_c M_g
/// c_g T_g` is conserved, every particle keeps one temperature (the cell →
/// node → particle transfer at the walls included), and the difference
/// `T_g − T_s` falls by the backward-Euler factor
/// `1/(1 + Δt H (θ_s v_g/c_g + θ_g v_s/c_s))` per step. Explicit and
/// semi-implicit pressure (the exchange is the same stage in both).
#[test]
fn uniform_mixture_relaxes_at_the_discrete_heat_exchange_rate() {
    relax_uniform_mixture(false);
    relax_uniform_mixture(true);
}

fn relax_uniform_mixture(semi_implicit: bool) {
    use mpmice::material::eos::EquationOfState;
    let h = 1e7;
    let mut run = heated_mixture(h);
    if semi_implicit {
        run.ice.implicit = Some(mpmice::ice::SemiImplicit::default());
    }
    let (c_g, c_s) = (717.5, run.fields[0].eos.specific_heat_cv());
    let c0 = run.fluid.layout.interior[0];
    // The exchange rate of the current cell state (θ and v change by
    // O(Δp/K) as the heated gas squeezes the steel).
    let rate = |run: &mpmice::coupling::CoupledRun<2>| {
        let (g, s) = (&run.fluid.cells[0], &run.fluid.cells[1]);
        h * (s.vol_frac[c0] * g.sp_vol[c0] / c_g + g.vol_frac[c0] * s.sp_vol[c0] / c_s)
    };
    let theta_s = run.fluid.cells[1].vol_frac[c0];
    let ((e_g0, t_g0), (e_s0, t_s0, _)) = thermal(&run);
    let e0 = e_g0 + e_s0;
    let mut factor = 1.0;
    let mut worst_rate: f64 = 0.0;
    let mut worst_energy: f64 = 0.0;
    let mut worst_spread: f64 = 0.0;
    for step in 0..150 {
        let r = rate(&run);
        let info = run.step(f64::INFINITY).unwrap();
        factor /= 1.0 + info.dt * r;
        let ((e_g, t_g), (e_s, lo, hi)) = thermal(&run);
        let t_s = 0.5 * (lo + hi);
        let diff = (t_g - t_s) / (t_g0 - t_s0);
        worst_rate = worst_rate.max((diff / factor - 1.0).abs());
        worst_energy = worst_energy.max(((e_g + e_s) / e0 - 1.0).abs());
        worst_spread = worst_spread.max(hi - lo);
        if step == 149 {
            eprintln!(
                "semi-implicit {semi_implicit}: θ_s {theta_s:.6}, Δt·rate {:.3e}, T_g {t_g:.4}, T_s {t_s:.6}, \
                 diff/exact − 1 ≤ {worst_rate:.2e}, energy ≤ {worst_energy:.2e}, \
                 particle spread ≤ {worst_spread:.2e} K, remaining {factor:.3e}",
                info.dt * r
            );
        }
    }
    let (uf, up) = velocity_deviations(&run, [0.0; 2]);
    assert!((theta_s - 0.5).abs() < 1e-3, "θ_s = {theta_s}");
    assert!(factor < 1e-2, "the test must relax: {factor:e} left");
    assert!(
        worst_rate < 1e-7,
        "relaxation off the exact rate by {worst_rate:e}"
    );
    assert!(
        worst_energy < 1e-13,
        "thermal energy drift {worst_energy:e}"
    );
    assert!(
        worst_spread < 1e-9,
        "particle temperatures spread by {worst_spread:e} K"
    );
    assert!(
        uf < 1e-9 && up < 1e-9,
        "spurious motion: fluid {uf:e}, particles {up:e}"
    );
}

/// The exchange is implicit: at `H = 1e15` (`Δt · rate ≈ 5e6`) one step
/// brings air and steel to the heat-capacity-weighted mean temperature, up
/// to the backward-Euler remainder `(T_g − T_s)/(1 + Δt · rate)`, and
/// conserves the energy.
#[test]
fn stiff_heat_exchange_equalises_in_one_step() {
    use mpmice::material::eos::EquationOfState;
    let h = 1e15;
    let mut run = heated_mixture(h);
    let ((e_g0, t_g0), (e_s0, t_s0, _)) = thermal(&run);
    let cap_s =
        run.fields[0].particles.mass.iter().sum::<f64>() * run.fields[0].eos.specific_heat_cv();
    let mean = (e_g0 + e_s0) / (e_g0 / t_g0 + cap_s);
    let c0 = run.fluid.layout.interior[0];
    let (g, s) = (&run.fluid.cells[0], &run.fluid.cells[1]);
    let rate = h
        * (s.vol_frac[c0] * g.sp_vol[c0] / 717.5
            + g.vol_frac[c0] * s.sp_vol[c0] / run.fields[0].eos.specific_heat_cv());
    let dt = run.step(f64::INFINITY).unwrap().dt;
    let ((e_g, t_g), (e_s, lo, hi)) = thermal(&run);
    let remainder = (t_g0 - t_s0) / (1.0 + dt * rate);
    eprintln!(
        "mean {mean:.9}, air {t_g:.9}, steel {lo:.9}…{hi:.9}, Δt·rate {:.3e}, \
         T_g − T_s {:.6e} (backward Euler {remainder:.6e})",
        dt * rate,
        t_g - lo
    );
    assert!(dt * rate > 1e6);
    assert!(((e_g + e_s) / (e_g0 + e_s0) - 1.0).abs() < 1e-13);
    assert!(((t_g - lo) / remainder - 1.0).abs() < 1e-6);
    for t in [t_g, lo, hi] {
        assert!((t - mean).abs() < 1e-4, "{t} vs the mean {mean}");
    }
}

/// The pressurised cylinder held past the case's end (12 ms instead of 8)
/// at dx = 0.05: the air outside the steel stays at its 300 K (Eq. 34's
/// flow work beside the solid; the total-energy form there took the work
/// of the solid's face volume fluxes as heat, which heated that air to
/// 326 K by 8 ms and 396 K by 12 ms, and blew up at 15 ms).
#[test]
fn held_cylinder_keeps_the_outer_air_cool() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/pressurized_cylinder.toml");
    let mut sc = mpmice::scene::load(&path).unwrap();
    sc.grid.cells = vec![24, 24];
    sc.time.end = 0.012;
    let mut run = mpmice::scene::build_coupled_run::<2>(&sc).unwrap();
    let mut hottest: f64 = 0.0;
    while run.fluid.time < sc.time.end * (1.0 - 1e-12) {
        run.step(sc.time.end - run.fluid.time).unwrap();
        let (air, steel) = (&run.fluid.cells[0], &run.fluid.cells[1]);
        for &c in &run.fluid.layout.interior {
            if run.fluid.layout.centre(c).norm() > 1.0 && steel.vol_frac[c] < 1e-3 {
                hottest = hottest.max(air.temperature[c]);
            }
        }
    }
    eprintln!("{} steps, hottest outer air {hottest:.3} K", run.steps);
    assert!(hottest < 302.0, "outer air reached {hottest} K");
}

/// Several solid fields (Guilkey Sec. 2: one velocity field per material,
/// the fields meeting only in the cell exchange, Eqs. 38–39).
mod solid_fields {
    use mpmice::coupling::CoupledRun;
    use mpmice::diagnostics::coupled::{aluminium, blocks_in_air, steel, Block, Gas};
    use mpmice::material::SolidMaterial;
    use nalgebra::SVector;

    fn block(
        lo: [f64; 2],
        hi: [f64; 2],
        velocity: [f64; 2],
        material: SolidMaterial,
        field: usize,
        rigid: bool,
    ) -> Block {
        Block {
            lo,
            hi,
            velocity,
            material,
            field,
            rigid,
        }
    }

    /// All particles' positions and velocities, field after field.
    fn particle_state(run: &CoupledRun<2>) -> (Vec<SVector<f64, 2>>, Vec<SVector<f64, 2>>) {
        let p = run.all_particles();
        (p.x, p.v)
    }

    /// Two steel bodies five cells apart in still air, one moving at 60 m/s
    /// along x, the other at 40 m/s along −y, run as ONE solid field and as
    /// TWO fields of the same material: the same bodies, so the same
    /// particle motion and cell pressure, up to the second field's floor
    /// (`θ = 1e-15` in every cell, moving with the other materials there).
    /// Both runs take the same steps (3 µs, below both stable limits):
    /// the adaptive step is not split-invariant, since the ICE limit
    /// counts every solid material's sound speed with its velocity in
    /// every cell, and a floor moving with the air beside the other body
    /// can raise it (by 0.27 % at one step of this run, after which the
    /// runs differ at O(Δt) level: pressure 3.6e-5). Measured with equal
    /// steps, worst over 300 steps: positions 1.35e-14 cells, velocities
    /// 1.44e-13 of the largest speed, pressure 5.86e-10 relative (in the
    /// steel's cells, where `ρc²` magnifies the volume round-off).
    #[test]
    fn two_bodies_as_one_field_or_two_give_the_same_motion() {
        let blocks = |fb: usize| {
            vec![
                block([0.1, 0.1], [0.3, 0.3], [60.0, 0.0], steel(), 0, false),
                block([0.6, 0.55], [0.8, 0.75], [0.0, -40.0], steel(), fb, false),
            ]
        };
        let gas = Gas::air([0.0; 2]);
        let mut one = blocks_in_air(20, gas, &blocks(0)).unwrap();
        let mut two = blocks_in_air(20, gas, &blocks(1)).unwrap();
        assert_eq!((one.fields.len(), two.fields.len()), (1, 2));
        let h = 0.05;
        let int = one.fluid.layout.interior.clone();
        let (mut dx, mut dv, mut dp, mut p_range) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let dt = 3e-6;
        for _ in 0..300 {
            assert_eq!(one.step(dt).unwrap().dt, dt);
            assert_eq!(two.step(dt).unwrap().dt, dt);
            let ((x1, v1), (x2, v2)) = (particle_state(&one), particle_state(&two));
            assert_eq!(x1.len(), x2.len());
            let v_scale = v1.iter().map(|v| v.norm()).fold(0.0, f64::max);
            for p in 0..x1.len() {
                dx = dx.max((x1[p] - x2[p]).norm() / h);
                dv = dv.max((v1[p] - v2[p]).norm() / v_scale);
            }
            for &c in &int {
                let (p1, p2) = (one.fluid.pressure[c], two.fluid.pressure[c]);
                dp = dp.max((p1 / p2 - 1.0).abs());
                p_range = p_range.max((p1 / 101_325.0 - 1.0).abs());
            }
        }
        eprintln!(
            "{} steps: positions {dx:.2e} cells, velocities {dv:.2e}, pressure {dp:.2e} (the \
             pressure itself varies by {p_range:.2e})",
            one.steps
        );
        // The run is not trivial: the bodies move and push the air.
        assert!(p_range > 1e-2, "pressure disturbance {p_range:e}");
        assert!(dx < 1e-12, "positions differ by {dx:e} cells");
        assert!(dv < 1e-11, "velocities differ by {dv:e}");
        assert!(dp < 4e-9, "pressures differ by {dp:e}");
    }

    /// Zhang Sec. 3 with two solid fields of different densities (steel
    /// 8900, aluminium 2700): both translating through the air at the
    /// air's velocity over ten cell crossings, the pressure changes by
    /// less than `bound` (relative) and the air keeps its velocity.
    fn translating_pair(rigid_steel: bool, rigid_aluminium: bool, (bound, du_bound): (f64, f64)) {
        let u = [100.0, 0.0];
        let blocks = [
            block([0.1, 0.15], [0.3, 0.35], u, steel(), 0, rigid_steel),
            block([0.1, 0.6], [0.3, 0.8], u, aluminium(), 1, rigid_aluminium),
        ];
        let mut run = blocks_in_air(20, Gas::air(u), &blocks).unwrap();
        let x0: Vec<f64> = run.fields.iter().map(|f| f.particles.x[0][0]).collect();
        run.advance_to(5e-3).unwrap();
        let moved: Vec<f64> = run
            .fields
            .iter()
            .zip(&x0)
            .map(|(f, x)| (f.particles.x[0][0] - x) / 0.05)
            .collect();
        let dp = super::pressure_dev(&run, 101_325.0);
        let (du, dup) = super::velocity_deviations(&run, u);
        eprintln!(
            "rigid steel {rigid_steel}, aluminium {rigid_aluminium}: {} steps, moved {moved:?} \
             cells, dp {dp:e}, du air {du:e}, particles {dup:e}",
            run.steps
        );
        assert!(moved.iter().all(|&m| m > 9.99), "moved {moved:?} cells");
        assert!(dp < bound, "relative pressure change {dp:e}");
        assert!(du < du_bound, "air velocity change {du:e}");
        assert!(dup < du_bound, "particle velocity change {dup:e}");
    }

    /// Both deformable and both rigid: the one-field test's bounds
    /// (pressure 1e-10, velocities 1e-8 of the speed); measured pressure
    /// 1.4e-16 in both, air velocity 4.9e-12 and 1.9e-12 m/s.
    #[test]
    fn two_solid_fields_translating_with_the_air_keep_the_pressure() {
        translating_pair(false, false, (1e-10, 1e-8 * 100.0));
        translating_pair(true, true, (1e-10, 1e-8 * 100.0));
    }

    /// A rigid steel field and a deformable aluminium one: measured
    /// pressure 4.2e-9, air velocity 1.2e-6 m/s. Likely cause (not
    /// verified): where the rigid field is absent its floor still has a
    /// prescribed velocity, and the exchange with a prescribed velocity
    /// skips the momentum-conserving projection of the implicit solve
    /// (`ice::exchange::exchange_momentum_fixed`), so in the aluminium's
    /// cells the round-off of the stiff (`K = 1e15`) solve is not removed.
    #[test]
    fn rigid_and_deformable_fields_translating_with_the_air_keep_the_pressure() {
        translating_pair(true, false, (1e-8, 1e-7 * 100.0));
    }

    /// Total momentum: all particles plus the fluid's cells (the solid
    /// fields' cells are copies of the particles).
    fn momentum(run: &CoupledRun<2>) -> (SVector<f64, 2>, f64) {
        let mut p = SVector::zeros();
        let mut scale = 0.0;
        for f in &run.fields {
            p += f.particles.momentum();
            scale += f.particles.momentum_scale();
        }
        for mc in &run.fluid.cells[..run.num_fluids()] {
            for &c in &run.fluid.layout.interior {
                p += mc.velocity[c] * mc.mass[c];
                scale += mc.mass[c] * mc.velocity[c].norm();
            }
        }
        (p, scale)
    }

    /// A steel block (field 0, +50 m/s) and an aluminium block (field 1,
    /// −50 m/s), 2.8 cells apart in still air in a closed box, collide
    /// through the cells they share (pressure and momentum exchange, the
    /// only link between fields): nothing becomes NaN, the steel is
    /// slowed and the aluminium thrown back (nearly inelastic: the pair's
    /// centre-of-mass velocity is 9300/348 = 26.7 m/s), and the bodies do
    /// not interpenetrate: they
    /// stop about two cells apart, where each field's cells (one beyond
    /// its particles) overlap. Momentum of particles and gas is conserved
    /// to 2e-8 of Σ m|v| over the run (measured 1.97e-8 over 1935 steps;
    /// closest gap 2.14 cells, final mean velocities 25.3 and 31.4 m/s).
    /// Before step 8 shared a cell's pressure force among its corner nodes
    /// by mass, each corner got an equal share and a massless node's share
    /// was dropped: drift 3.8e-6 (one steel block at 80 m/s alone, one
    /// field, drifted 4.6e-6 in 100 steps, each step's drift equal to the
    /// dropped impulse). The remaining 2e-8 is not round-off and was not
    /// traced (candidates: nodes below the MPM mass floor, the closed
    /// box's walls).
    #[test]
    fn two_solid_fields_collide_through_the_cells() {
        let n = 40;
        let h = 1.0 / n as f64;
        let v = 50.0;
        let blocks = [
            block([0.3, 0.4], [0.45, 0.6], [v, 0.0], steel(), 0, false),
            block([0.525, 0.4], [0.675, 0.6], [-v, 0.0], aluminium(), 1, false),
        ];
        let mut run = blocks_in_air(n, Gas::air([0.0; 2]), &blocks).unwrap();
        let (p0, scale) = momentum(&run);
        let mut drift: f64 = 0.0;
        let mut gap_min = f64::INFINITY;
        // Gap between the blocks' material: outermost particles ± h/4.
        let gap = |run: &CoupledRun<2>| {
            let right = run.fields[0]
                .particles
                .x
                .iter()
                .map(|x| x[0])
                .fold(f64::NEG_INFINITY, f64::max);
            let left = run.fields[1]
                .particles
                .x
                .iter()
                .map(|x| x[0])
                .fold(f64::INFINITY, f64::min);
            (left - 0.25 * h - (right + 0.25 * h)) / h
        };
        while run.fluid.time < 4e-4 {
            run.step(4e-4 - run.fluid.time).unwrap();
            let (p, _) = momentum(&run);
            drift = drift.max((p - p0).norm() / scale);
            gap_min = gap_min.min(gap(&run));
        }
        let finite = run.fields.iter().all(|f| {
            f.particles
                .x
                .iter()
                .chain(&f.particles.v)
                .all(|v| v.iter().all(|c| c.is_finite()))
        }) && run.fluid.cells.iter().all(|mc| {
            mc.velocity.iter().all(|u| u.iter().all(|v| v.is_finite()))
                && mc.temperature.iter().all(|t| t.is_finite())
        });
        let mean_v = |f: &mpmice::coupling::SolidField<2>| {
            f.particles.momentum()[0] / f.particles.total_mass()
        };
        let (v_steel, v_al) = (mean_v(&run.fields[0]), mean_v(&run.fields[1]));
        eprintln!(
            "{} steps: momentum drift {drift:.2e} of Σ m|v| = {scale:.4e}, closest gap \
             {gap_min:.3} cells (now {:.3}), mean x-velocities steel {v_steel:.3}, aluminium \
             {v_al:.3} m/s",
            run.steps,
            gap(&run)
        );
        assert!(finite, "NaN or inf in the state");
        assert!(drift < 1e-7, "momentum drift {drift:e}");
        assert!(gap_min > -1.0, "interpenetration {:.3} cells", -gap_min);
        assert!(v_steel < 0.7 * v, "the steel was not slowed: {v_steel} m/s");
        assert!(v_al > 0.0, "the aluminium was not thrown back: {v_al} m/s");
    }
}
