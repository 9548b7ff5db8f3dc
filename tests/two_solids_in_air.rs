//! Two solids meeting inside a fluid (issue 22): two steel blocks in air
//! approach, collide and fly apart (explicit MPM-ICE,
//! `cases/two_blocks_in_air.toml`, coarsened). The air squeezed between
//! them and the air left in the blocks' cells must stay physical and must
//! not collapse the time step. In the mirror-symmetric case the total
//! energy (the blocks' kinetic and strain energy and the air's internal and
//! kinetic energy) is conserved up to the scheme's collision error, and the
//! x-momentum (zero) to round-off. Unequal blocks (set-ups the case file
//! does not hold) keep the air physical too; their energy is not conserved
//! (see [`a_small_block_hitting_a_taller_one_in_air_keeps_the_air_physical`]).

use mpmice::driver::models::Coupled;
use mpmice::driver::Model;
use mpmice::scene::{self, Scene};

const CASE: &str = include_str!("../cases/two_blocks_in_air.toml");

/// What one run measured.
#[derive(Debug)]
struct Outcome {
    steps: u64,
    dt_min: f64,
    dt_max: f64,
    /// Lowest and highest air temperature and lowest air true density over
    /// all cells holding air above the mass floor and all steps.
    t_min: f64,
    t_max: f64,
    rho_min: f64,
    /// Highest air speed over the same cells and steps.
    u_max: f64,
    /// `|E(end) − E(0)|` over the blocks' initial kinetic energy.
    energy_error: f64,
    /// `|Σ p_x(end) − Σ p_x(0)|` over `Σ m |v|` of the blocks at the start.
    momentum_error: f64,
}

/// Two steel blocks on `y = 0` (a symmetry plane): `[x0, x1] × [0, height]`
/// each, at x-velocity `v`.
#[derive(Debug, Clone, Copy)]
struct Block {
    x: [f64; 2],
    height: f64,
    v: f64,
}

/// A block `[x0, x1] × [0, height]` at x-velocity `v`.
fn block(x0: f64, x1: f64, height: f64, v: f64) -> Block {
    Block {
        x: [x0, x1],
        height,
        v,
    }
}

/// The case's blocks at ±`v` m/s.
fn mirrored(v: f64) -> [Block; 2] {
    [block(0.04, 0.08, 0.025, v), block(0.12, 0.16, 0.025, -v)]
}

/// Runs the case on `cells` with `blocks` to `end`.
fn run(cells: [usize; 2], blocks: [Block; 2], end: f64) -> Outcome {
    let mut s: Scene = scene::parse(CASE).expect("case");
    s.grid.cells = cells.to_vec();
    s.time.end = end;
    for (o, b) in s.objects.iter_mut().zip(&blocks) {
        o.velocity = Some(vec![b.v, 0.0]);
        o.geometry = scene::Geometry::Box {
            lower: vec![b.x[0], 0.0],
            upper: vec![b.x[1], b.height],
        };
    }
    let mut model = Coupled {
        run: scene::build_coupled_run::<2>(&s).expect("build"),
    };
    let start = model.conserved();
    let e0 = start.energies.total();
    let ke0 = start
        .materials
        .iter()
        .find(|m| m.name == "steel")
        .expect("steel")
        .kinetic;
    let px = |c: &mpmice::driver::model::Conserved| -> f64 {
        c.materials.iter().map(|m| m.momentum[0]).sum()
    };
    let p0 = px(&start);
    let scale = start.momentum_scale;
    let mut o = Outcome {
        steps: 0,
        dt_min: f64::INFINITY,
        dt_max: 0.0,
        t_min: f64::INFINITY,
        t_max: 0.0,
        rho_min: f64::INFINITY,
        u_max: 0.0,
        energy_error: 0.0,
        momentum_error: 0.0,
    };
    while model.time() < end * (1.0 - 1e-12) {
        let st = model
            .step(mpmice::driver::DtRequest {
                value: end - model.time(),
                exact: false,
            })
            .unwrap_or_else(|e| panic!("step {}: {e}", model.steps()));
        if model.time() < end * (1.0 - 1e-9) {
            o.dt_min = o.dt_min.min(st.dt);
        }
        o.dt_max = o.dt_max.max(st.dt);
        let f = &model.run.fluid;
        let air = &f.cells[0];
        let floor = 1e-12 * f.layout.cell_volume();
        for &c in &f.layout.interior {
            if air.mass[c] > floor {
                o.t_min = o.t_min.min(air.temperature[c]);
                o.t_max = o.t_max.max(air.temperature[c]);
                o.rho_min = o.rho_min.min(1.0 / air.sp_vol[c]);
                o.u_max = o.u_max.max(air.velocity[c].norm());
            }
        }
    }
    o.steps = model.steps();
    let end_state = model.conserved();
    o.energy_error = (end_state.energies.total() - e0).abs() / ke0;
    o.momentum_error = (px(&end_state) - p0).abs() / scale;
    eprintln!("{cells:?}, {blocks:?}: {o:?}");
    o
}

/// The bounds every set-up shares: no Δt collapse, the air above 100 K
/// and below `t_max` (adiabatic compression of air from 1e5 Pa to the
/// blocks' collision stress `ρ c Δv/2` ≈ 5 GPa at ±100 m/s gives 300
/// (5e4)^(2/7) ≈ 6600 K; a shock heats more), and positive density.
fn check_common(o: &Outcome, t_max: f64) {
    assert!(
        o.dt_min > 0.5 * o.dt_max,
        "Δt collapsed: {:.3e} of at most {:.3e} ({o:?})",
        o.dt_min,
        o.dt_max
    );
    assert!(o.t_min > 100.0 && o.t_max < t_max, "air temperature {o:?}");
    assert!(o.rho_min > 0.0, "air density {o:?}");
}

/// The case's mesh at ±100 m/s through the collision and the bounce (0.5
/// ms). Before the air left in the blocks' cells was held isothermal
/// (`fluid.isothermal_fraction = 0`): 37 704 steps, Δt down to 0.016 of its
/// largest, air at 1.3e8 K, energy error 8.3e-3. Held isothermal: 3788
/// steps, Δt ≥ 0.88 of its largest, air 112–7657 K, energy error 2.3e-3.
/// With the steel traces beside the blocks at their start-of-step velocity
/// in the exchange (`coupling.solid_trace_fraction`): 3747 steps, Δt ≥
/// 0.92 of its largest, air 152–7034 K, energy error 5.7e-4.
#[test]
fn steel_blocks_meeting_at_200_m_per_s_in_air_keep_the_air_physical() {
    let o = run([80, 20], mirrored(100.0), 5e-4);
    check_common(&o, 1e4);
    assert!(o.momentum_error < 1e-12, "momentum {o:?}");
    assert!(o.energy_error < 2e-3, "energy {o:?}");
}

/// A coarser mesh at ±10 m/s (the collision at 2 ms, the bounce by 3 ms):
/// measured Δt ≥ 0.98 of its largest, air 264–496 K (779 K without the
/// isothermal minor air), energy error 4.4e-3 of the blocks' kinetic
/// energy (1.2e-2 with the steel traces' node velocities in the exchange).
#[test]
fn steel_blocks_meeting_at_20_m_per_s_in_air_keep_the_air_physical() {
    let o = run([40, 10], mirrored(10.0), 3e-3);
    check_common(&o, 1e4);
    assert!(o.momentum_error < 1e-12, "momentum {o:?}");
    assert!(o.energy_error < 1e-2, "energy {o:?}");
}

/// Unequal blocks: 4 cm at +100 m/s against 2 cm at −50 m/s, 1 ms (they
/// meet near 0.27 ms). With the steel traces' node-to-cell velocities in
/// the exchange the run failed at step 1113 (0.297 ms) with the air at
/// −2 K in a wake cell above the blocks: the trace's velocity had dragged
/// the air of the cell below it to 1000 m/s. Now: 3752 steps, Δt ≥ 0.94
/// of its largest, air 208–985 K, at most 1031 m/s (the jet squeezed out
/// of the closing gap). The energy error, 1.7e-2 here, is 8.9e-2 on 80 ×
/// 20 cells: not asserted (see the next test).
#[test]
fn unequal_blocks_meeting_in_air_keep_the_air_physical() {
    let blocks = [
        block(0.04, 0.08, 0.025, 100.0),
        block(0.12, 0.14, 0.025, -50.0),
    ];
    let o = run([40, 10], blocks, 1e-3);
    check_common(&o, 1e4);
}

/// A 1 × 2.5 cm block at −100 m/s hitting a 4 × 4 cm one at +50 m/s,
/// 1 ms: the pair then leaves the cells behind it. Before the trace fix
/// the run failed at step 2650 (0.350 ms, air at −5.8 K). Now: 7522 steps,
/// Δt ≥ 0.92 of its largest, air 150–12 900 K (the collision stress `ρ c
/// Δv/2` ≈ 4 GPa compresses air adiabatically to 6200 K; the trapped air
/// is shocked), density down to 4e-10 kg/m³ in the cells the blocks leave.
///
/// Open (issue 22): on this mesh the total energy falls by 43 % of the
/// blocks' kinetic energy, within the 15 µs of the collision, where the
/// same blocks without air keep it to 1.2 %. It is not a steady error of
/// the scheme: on 40 × 10 cells the energy error is +1.6 %, on 160 × 40
/// −0.44 % (`mpmice run` of this set-up, `energy` drift). Measured at 0.26 ms (after the
/// collision): −38 %; with the cell-pressure force on the steel switched
/// off, −20 %; with the steel's exchange increment off as well, +1.4 %
/// (the steel alone conserves; the air, pushed without pushing back,
/// gains). The steel's dual representation (its own stress on
/// the particles, the cell pressure of its EOS in the cells, Guilkey Eq.
/// 33's `θ∇p* + ∇·θ(σ_s − σ)`) does work that neither stores.
#[test]
fn a_small_block_hitting_a_taller_one_in_air_keeps_the_air_physical() {
    let blocks = [
        block(0.04, 0.08, 0.04, 50.0),
        block(0.12, 0.13, 0.025, -100.0),
    ];
    let o = run([80, 20], blocks, 1e-3);
    check_common(&o, 2e4);
}
