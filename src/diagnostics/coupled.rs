//! Coupled MPM-ICE reference setups: a steel block in air (at rest, or
//! translating with the air — Zhang Sec. 3), solid blocks in gas as one or
//! several solid fields, and the adiabatic piston (Guilkey Sec. 4.2,
//! Eq. 44).

use nalgebra::SVector;

use super::mms::fill_box;
use crate::coupling::{CoupledRun, CouplingParams, RigidInterface, SolidFieldSpec};
use crate::error::Result;
use crate::grid::{Boundary, Grid};
use crate::ice::{
    CellLayout, ExchangeCoefficients, IceBoundary, IceMaterial, IceParams, IceState, MaterialInit,
};
use crate::material::eos::{IdealGas, SolidEos};
use crate::material::{ElasticConstants, SolidMaterial, SolidModel};
use crate::mpm::{ExplicitParams, UpdateScheme};
use crate::shape::ShapeKind;

/// Air: `γ = 1.4`, `c_v = 717.5` J/(kg K).
pub fn air() -> IceMaterial {
    IceMaterial::new("air", IdealGas::new(1.4, 717.5).expect("valid gas"))
}

/// Steel of Guilkey Sec. 4.1: `K = 117` GPa, `G = 43.8` GPa, `ρ = 8900`.
pub fn steel() -> SolidMaterial {
    SolidMaterial {
        name: "steel".into(),
        density: 8900.0,
        model: SolidModel::NeoHookean,
        elastic: ElasticConstants::from_bulk_shear(117.0e9, 43.8e9),
    }
}

/// Aluminium: `E = 70` GPa, `ν = 0.33` (`K = 68.6` GPa, `G = 26.3` GPa),
/// `ρ = 2700`.
pub fn aluminium() -> SolidMaterial {
    SolidMaterial {
        name: "aluminium".into(),
        density: 2700.0,
        model: SolidModel::NeoHookean,
        elastic: ElasticConstants::from_bulk_shear(70.0e9 / (3.0 * 0.34), 70.0e9 / 2.66),
    }
}

/// The cell EOS of a solid material at the reference pressure `p_ref`
/// (threshold `p_ref`, Guilkey Fig. 1).
pub fn solid_eos(m: &SolidMaterial, p_ref: f64) -> SolidEos {
    SolidEos::new(m.density, m.elastic.bulk(), p_ref, p_ref, 450.0).expect("valid solid EOS")
}

/// A 2D square box `[0, 1]²` of `n × n` cells filled with air at
/// `(ρ, p) = (1.1768, 101325)` moving at `u_air`, and a steel block
/// `[lo, hi]` (2 × 2 particles per cell) moving at `u_solid` (deformable;
/// `rigid = true` prescribes that velocity). Walls: symmetry everywhere
/// when the velocities are zero, outflow / free otherwise. Exchange
/// `K = 1e15`.
///
/// # Errors
/// As [`CoupledRun::new`].
pub fn block_in_air(
    n: usize,
    lo: [f64; 2],
    hi: [f64; 2],
    u_air: [f64; 2],
    u_solid: [f64; 2],
    rigid: bool,
) -> Result<CoupledRun<2>> {
    steel_in_air(
        n,
        (lo, hi),
        u_air,
        u_solid,
        rigid,
        1.0,
        CouplingParams::default(),
    )
}

/// Steel particles at `fill` of the steel's density filling the closed box
/// `[0, 1]²` of `n × n` cells (so the steel's volume fraction is `fill` in
/// every cell) with air at rest at `(ρ, p) = (1.1768, 101325)`, about
/// 300 K; the steel starts at `t_solid` and exchanges heat with the air at
/// the coefficient `h` (Guilkey Eq. 39). Symmetry walls, `K = 1e15`.
///
/// # Errors
/// As [`CoupledRun::new`].
pub fn heated_mixture(n: usize, fill: f64, h: f64, t_solid: f64) -> Result<CoupledRun<2>> {
    let coupling = CouplingParams {
        solid_temperature: t_solid,
        heat_exchange: h,
        ..CouplingParams::default()
    };
    steel_in_air(
        n,
        ([0.0; 2], [1.0; 2]),
        [0.0; 2],
        [0.0; 2],
        false,
        fill,
        coupling,
    )
}

/// [`block_in_air`] with the particle masses scaled by `mass_scale` and
/// the coupling settings given: one steel block of [`blocks_run`], the
/// box closed only when nothing moves.
fn steel_in_air(
    n: usize,
    (lo, hi): ([f64; 2], [f64; 2]),
    u_air: [f64; 2],
    u_solid: [f64; 2],
    rigid: bool,
    mass_scale: f64,
    coupling: CouplingParams,
) -> Result<CoupledRun<2>> {
    let closed = u_air == [0.0, 0.0] && u_solid == [0.0, 0.0];
    let block = Block {
        lo,
        hi,
        velocity: u_solid,
        material: steel(),
        field: 0,
        rigid,
    };
    blocks_run(n, Gas::air(u_air), &[block], closed, mass_scale, coupling)
}

/// A coupled run of steel particles moving at `v` (prescribed if `rigid`)
/// with the linear hat, USF, `p_ref = 101325` and the coupling given.
fn steel_run<const D: usize>(
    grid: Grid<D>,
    mut particles: crate::mpm::Particles<D>,
    v: SVector<f64, D>,
    rigid: bool,
    fluid: IceState<D>,
    params: IceParams<D>,
    coupling: CouplingParams,
) -> Result<CoupledRun<D>> {
    let m = steel();
    for u in &mut particles.v {
        *u = v;
    }
    let min_mass = particles.mass.iter().copied().fold(f64::INFINITY, f64::min);
    let mpm = ExplicitParams {
        shape: ShapeKind::Linear,
        scheme: UpdateScheme::Usf,
        mass_floor: 1e-12 * min_mass,
        damping: 0.0,
        pic_fraction: 0.0,
    };
    let eos = solid_eos(&m, 101_325.0);
    CoupledRun::new(
        grid,
        vec![m],
        particles,
        mpm,
        fluid,
        params,
        "steel",
        eos,
        rigid.then_some(v),
        coupling,
        0.5,
    )
}

/// One block of [`blocks_in_air`]: the box `[lo, hi]` of `material`
/// (2 × 2 particles per cell) moving at `velocity`, in solid field `field`.
#[derive(Debug, Clone)]
pub struct Block {
    /// Lower corner.
    pub lo: [f64; 2],
    /// Upper corner.
    pub hi: [f64; 2],
    /// Initial velocity (the prescribed one of a rigid field).
    pub velocity: [f64; 2],
    /// The block's material.
    pub material: SolidMaterial,
    /// Index of the block's solid field (`0..number of fields`, every
    /// index used).
    pub field: usize,
    /// Whether the block's field is rigid (moving at `velocity`; all
    /// blocks of a rigid field share it).
    pub rigid: bool,
}

/// The gas of [`blocks_in_air`]: air (`γ = 1.4`) at density `rho` and
/// pressure `p` (also the solids' reference pressure) moving at `velocity`.
#[derive(Debug, Clone, Copy)]
pub struct Gas {
    /// Density [kg/m³].
    pub rho: f64,
    /// Pressure \[Pa\].
    pub p: f64,
    /// Velocity [m/s].
    pub velocity: [f64; 2],
}

impl Gas {
    /// Air at `(ρ, p) = (1.1768, 101325)` moving at `velocity`.
    pub fn air(velocity: [f64; 2]) -> Self {
        Self {
            rho: 1.1768,
            p: 101_325.0,
            velocity,
        }
    }
}

/// Solid blocks in `gas` in the box `[0, 1]²` of `n × n` cells, each block
/// in the solid field its `field` names (a field holds any number of
/// blocks: one field for two blocks, or one field each, are the same
/// bodies; the fields follow the fluid as ICE materials, field `i` named
/// after its first block's material, `_i` appended). Block `b`'s particles
/// have material `b` (the run's `materials` are the blocks'). Walls:
/// closed (symmetry) when the gas is at rest, free / outflow when it
/// moves; `K = 1e15`, `p_ref` the gas pressure, USF, linear hat.
///
/// # Errors
/// As [`CoupledRun::with_fields`].
pub fn blocks_in_air(n: usize, gas: Gas, blocks: &[Block]) -> Result<CoupledRun<2>> {
    let closed = gas.velocity == [0.0; 2];
    blocks_run(n, gas, blocks, closed, 1.0, CouplingParams::default())
}

/// [`blocks_in_air`] with the walls closed (symmetry / wall) or free /
/// outflow, the particle masses scaled by `mass_scale` and the coupling
/// settings given (`p_ref` set to the gas pressure).
fn blocks_run(
    n: usize,
    gas: Gas,
    blocks: &[Block],
    closed: bool,
    mass_scale: f64,
    coupling: CouplingParams,
) -> Result<CoupledRun<2>> {
    let (gbc, fbc) = if closed {
        (Boundary::Symmetry, IceBoundary::Wall)
    } else {
        (Boundary::Free, IceBoundary::Outflow)
    };
    let grid = Grid::<2>::new(
        SVector::zeros(),
        SVector::repeat(1.0),
        [n, n],
        [[gbc; 2]; 2],
    );
    let layout = CellLayout::from_grid(&grid)?;
    let ua = SVector::<f64, 2>::from(gas.velocity);
    let fluid = IceState::new(layout, vec![air()], |_| {
        vec![MaterialInit::new(1.0, gas.rho, gas.p, ua)]
    })?;
    let mut params = IceParams::new([[fbc.clone(), fbc.clone()], [fbc.clone(), fbc]]);
    params.exchange = Some(ExchangeCoefficients::uniform(1, 1e15, 0.0));
    let n_fields = blocks.iter().map(|b| b.field + 1).max().unwrap_or(0);
    let mut fields: Vec<Option<SolidFieldSpec<2>>> = vec![None; n_fields];
    for (i, b) in blocks.iter().enumerate() {
        let v = SVector::<f64, 2>::from(b.velocity);
        let mut p = fill_box(
            &grid,
            &SVector::from(b.lo),
            &SVector::from(b.hi),
            2,
            b.material.density,
            |_| true,
        );
        p.v.fill(v);
        p.material.fill(i as u16);
        for mp in &mut p.mass {
            *mp *= mass_scale;
        }
        match &mut fields[b.field] {
            Some(f) => f.particles.append(&p),
            slot => {
                *slot = Some(SolidFieldSpec {
                    name: format!("{}_{}", b.material.name, b.field),
                    particles: p,
                    eos: solid_eos(&b.material, gas.p),
                    rigid_velocity: b.rigid.then_some(v),
                })
            }
        }
    }
    let fields: Vec<SolidFieldSpec<2>> = fields.into_iter().flatten().collect();
    let min_mass = fields
        .iter()
        .flat_map(|f| f.particles.mass.iter().copied())
        .fold(f64::INFINITY, f64::min);
    let mpm = ExplicitParams {
        shape: ShapeKind::Linear,
        scheme: UpdateScheme::Usf,
        mass_floor: 1e-12 * min_mass,
        damping: 0.0,
        pic_fraction: 0.0,
    };
    let coupling = CouplingParams {
        p_ref: gas.p,
        ..coupling
    };
    CoupledRun::with_fields(
        grid,
        blocks.iter().map(|b| b.material.clone()).collect(),
        fields,
        mpm,
        fluid,
        params,
        coupling,
        0.5,
    )
}

/// The adiabatic piston of Guilkey Sec. 4.2 in 1D: air at
/// `(ρ, p) = (1.1768, 101325)` in `[0, 1.2]` (`n` cells, walls at both
/// ends), a rigid steel piston filling `[1.0, 1.1]` (2 particles per cell)
/// moving towards the closed end `x = 0` at `speed`, reached smoothly over
/// `ramp` seconds ([`CoupledRun::rigid_ramp`]); exchange `K = 1e15`. The gas
/// below the piston is compressed from length 1 to
/// `1 + run.rigid_displacement(0, t)`. `interface`: how the piston's
/// volume enters the cells ([`RigidInterface`]).
///
/// # Errors
/// As [`CoupledRun::new`].
pub fn piston(n: usize, speed: f64, ramp: f64, interface: RigidInterface) -> Result<CoupledRun<1>> {
    let grid = Grid::<1>::new(
        SVector::zeros(),
        SVector::repeat(1.2),
        [n],
        [[Boundary::Symmetry; 2]],
    );
    let layout = CellLayout::from_grid(&grid)?;
    let fluid = IceState::new(layout, vec![air()], |_| {
        vec![MaterialInit::new(1.0, 1.1768, 101_325.0, SVector::zeros())]
    })?;
    let mut params = IceParams::new([[IceBoundary::Wall, IceBoundary::Wall]]);
    params.exchange = Some(ExchangeCoefficients::uniform(1, 1e15, 0.0));
    let m = steel();
    let v = SVector::<f64, 1>::new(-speed);
    let particles = fill_box(
        &grid,
        &SVector::<f64, 1>::new(1.0),
        &SVector::<f64, 1>::new(1.1),
        2,
        m.density,
        |_| true,
    );
    let mut run = steel_run(
        grid,
        particles,
        v,
        true,
        fluid,
        params,
        CouplingParams {
            rigid_interface: interface,
            ..CouplingParams::default()
        },
    )?;
    run.rigid_ramp = ramp;
    Ok(run)
}

/// One piston sample: (compression ratio `V1/V2`, closed-end pressure,
/// `P1 (V1/V2)^γ`).
pub type PistonSample = (f64, f64, f64);

/// The piston run of [`piston`] until the compression ratio reaches
/// `ratio_end`; returns `(ratio, p_bottom, p_exact)` samples at the ratios
/// `2, 2.5, 3, …` (the cell pressure at the closed end against Guilkey
/// Eq. 44, `P₁ (V₁/V₂)^γ`) and the number of steps.
///
/// # Errors
/// As [`CoupledRun::step`].
pub fn piston_history(
    n: usize,
    speed: f64,
    ramp: f64,
    ratio_end: f64,
    interface: RigidInterface,
) -> Result<(Vec<PistonSample>, u64)> {
    let mut run = piston(n, speed, ramp, interface)?;
    let p1 = 101_325.0;
    let mut out = Vec::new();
    let mut next = 1.5;
    let ratio = |run: &CoupledRun<1>| {
        1.0 / (1.0
            + run
                .rigid_displacement(0, run.fluid.time)
                .map_or(0.0, |d| d[0]))
    };
    while ratio(&run) < ratio_end {
        run.step(f64::INFINITY)?;
        let r = ratio(&run);
        if r >= next {
            let c0 = run.fluid.layout.interior[0];
            out.push((r, run.fluid.pressure[c0], p1 * r.powf(1.4)));
            next += 0.5;
        }
    }
    Ok((out, run.steps))
}

/// What [`measure_cylinder`] reports for the pressurised cylinder of
/// Guilkey Sec. 4.1 run coupled.
#[derive(Debug, Clone)]
pub struct CylinderMeasured {
    /// Guilkey Eq. 43: mean over particles of `||σ_r + σ_θ| − 2P/3| / (2P/3)`.
    pub error43: f64,
    /// Measured inner gauge pressure `P` (mean over the cells with centre
    /// radius below `0.9 r_i`, minus `p_ref`).
    pub pressure: f64,
    /// `(r, σ_r, σ_θ)` of the particles of the row nearest the x-axis
    /// (Guilkey Fig. 3a), sorted by radius.
    pub row: Vec<(f64, f64, f64)>,
}

/// One particle's term of Guilkey Eq. 43, `||σ_r + σ_θ| − T| / T` with
/// `T = 2P/3` (in plane strain `σ_r + σ_θ = σ_xx + σ_yy`).
pub fn eq43_particle_error(stress: &nalgebra::Matrix3<f64>, target: f64) -> f64 {
    (((stress[(0, 0)] + stress[(1, 1)]).abs() - target) / target).abs()
}

/// The coupled pressurised-cylinder scene `sc` (Guilkey 4.1: the quarter
/// annulus `r_i = 0.5` on `[0, 1.2]²`, `cases/pressurized_cylinder.toml`)
/// at cell size `dx`, run to its end time: the run, its Eq. 43 measure
/// ([`measure_cylinder`] at `sc.coupling.reference_pressure`) and the
/// wall time of the stepping in seconds.
///
/// # Errors
/// The scene's build error or the run's failure.
pub fn run_cylinder_scene(
    sc: crate::scene::Scene,
    dx: f64,
) -> Result<(CoupledRun<2>, CylinderMeasured, f64)> {
    let (run, m, wall, _) = run_cylinder_history(sc, dx, f64::INFINITY)?;
    Ok((run, m, wall))
}

/// One accepted step of [`run_cylinder_history`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CylinderSample {
    /// Time at the end of the step.
    pub t: f64,
    /// Measured inner gauge pressure `P` (as [`CylinderMeasured::pressure`]).
    pub pressure: f64,
    /// Guilkey Eq. 43 against that `P`.
    pub error43: f64,
}

/// [`run_cylinder_scene`] with Eq. 43 and `P` measured after every step
/// that ends at `t ≥ from` with `P > 0` (a quasistatic solid is in
/// equilibrium with the step's load at every step, so Lamé holds at each;
/// the first steps' `P` is 0: the pressure of a step is set before the
/// step's heat is added). The wall time counts the steps only, not the
/// measurements.
///
/// # Errors
/// The scene's build error or the run's failure.
pub fn run_cylinder_history(
    mut sc: crate::scene::Scene,
    dx: f64,
    from: f64,
) -> Result<(CoupledRun<2>, CylinderMeasured, f64, Vec<CylinderSample>)> {
    let n = (1.2 / dx).round() as usize;
    sc.grid.cells = vec![n, n];
    let p_ref = sc.coupling.reference_pressure;
    let t_end = sc.time.end;
    let mut run = crate::scene::build_coupled_run::<2>(&sc)?;
    let mut wall = 0.0;
    let mut history = Vec::new();
    // As `CoupledRun::advance_to`, with a measurement between the steps.
    while run.fluid.time < t_end * (1.0 - 1e-12) {
        let start = std::time::Instant::now();
        run.step(t_end - run.fluid.time)?;
        wall += start.elapsed().as_secs_f64();
        if run.fluid.time >= from {
            let m = measure_cylinder(&run, 0.5, p_ref);
            if m.pressure > 0.0 {
                history.push(CylinderSample {
                    t: run.fluid.time,
                    pressure: m.pressure,
                    error43: m.error43,
                });
            }
        }
    }
    let m = measure_cylinder(&run, 0.5, p_ref);
    Ok((run, m, wall, history))
}

/// Guilkey Eq. 43 and the Fig. 3a row of a coupled cylinder run (inner
/// radius `r_i`, reference pressure `p_ref`).
pub fn measure_cylinder(run: &CoupledRun<2>, r_inner: f64, p_ref: f64) -> CylinderMeasured {
    let layout = &run.fluid.layout;
    let (mut sum, mut n) = (0.0, 0usize);
    for &c in &layout.interior {
        if layout.centre(c).norm() < 0.9 * r_inner {
            sum += run.fluid.pressure[c];
            n += 1;
        }
    }
    let pressure = sum / n.max(1) as f64 - p_ref;
    let target = 2.0 * pressure / 3.0;
    let p = &run.fields[0].particles;
    let mut e43 = 0.0;
    let y_min = p.x0.iter().map(|x| x[1]).fold(f64::INFINITY, f64::min);
    let mut row = Vec::new();
    for i in 0..p.len() {
        let s = &p.stress.get(i);
        e43 += eq43_particle_error(s, target);
        if p.x0[i][1] <= y_min * (1.0 + 1e-9) {
            let x = p.x[i];
            let r = x.norm();
            let (c, sn) = (x[0] / r, x[1] / r);
            let sr = c * c * s[(0, 0)] + 2.0 * c * sn * s[(0, 1)] + sn * sn * s[(1, 1)];
            let st = sn * sn * s[(0, 0)] - 2.0 * c * sn * s[(0, 1)] + c * c * s[(1, 1)];
            row.push((r, sr, st));
        }
    }
    row.sort_by(|a, b| a.0.total_cmp(&b.0));
    CylinderMeasured {
        error43: e43 / p.len().max(1) as f64,
        pressure,
        row,
    }
}

/// [`measure_wedge`] for `cases/wedge_mach3.toml` (Guilkey Sec. 4.3): the
/// tip starts at x = 0.6 and moves with the rigid field, half-angle 20°,
/// p1 = 101 325 Pa, exact p2/p1 = 3.771, the shock measured 0.05–0.15 m
/// behind the tip (0.25–0.75 wedge lengths: clear of the tip's smeared
/// cells and the base's expansion).
pub fn measure_wedge_mach3(run: &CoupledRun<2>) -> WedgeMeasured {
    let tip = 0.6
        + run
            .rigid_displacement(0, run.fluid.time)
            .map_or(0.0, |d| d[0]);
    measure_wedge(
        &run.fluid,
        tip,
        20.0,
        101_325.0,
        3.771 * 101_325.0,
        (0.05, 0.15),
    )
}

/// What [`measure_wedge`] reports for the Mach 3 wedge of Guilkey
/// Sec. 4.3.
#[derive(Debug, Clone)]
pub struct WedgeMeasured {
    /// Shock angle from a least-squares line through the shock positions.
    pub angle_deg: f64,
    /// The tip's x (the input).
    pub tip_x: f64,
    /// Height of the least-squares shock line at the tip (`d = 0`); the
    /// exact attached shock passes through the tip (0).
    pub offset: f64,
    /// Mean post-shock pressure ratio `p2/p1` between wedge and shock.
    pub pressure_ratio: f64,
    /// `(d, y_shock, p2/p1)` per cell column at distance `d` behind the tip.
    pub columns: Vec<(f64, f64, f64)>,
}

/// Shock angle and post-shock pressure of a wedge run (half plane `y ≥ 0`,
/// symmetry at `y = 0`): per column of cells at distance `d` behind the tip
/// in `[d_min, d_max]`, the shock is where the pressure first drops below
/// `(p1 + p2_exact)/2` going up from the wedge surface `y = d tan θ`, and
/// `p2` is the mean cell pressure between the surface and the shock (two
/// cells clear of each). `tip_x` is the tip's current position.
pub fn measure_wedge(
    state: &crate::ice::IceState<2>,
    tip_x: f64,
    half_angle_deg: f64,
    p1: f64,
    p2_exact: f64,
    d_range: (f64, f64),
) -> WedgeMeasured {
    let layout = &state.layout;
    let (nx, ny) = (layout.cells[0], layout.cells[1]);
    let h = layout.h;
    let ta = half_angle_deg.to_radians().tan();
    let half = 0.5 * (p1 + p2_exact);
    let mut columns = Vec::new();
    for i in 0..nx {
        let x = layout.lower[0] + (i as f64 + 0.5) * h[0];
        let d = x - tip_x;
        if d < d_range.0 || d > d_range.1 {
            continue;
        }
        let ys = d * ta;
        let p = |j: usize| state.pressure[layout.index([i as isize, j as isize])];
        let yc = |j: usize| layout.lower[1] + (j as f64 + 0.5) * h[1];
        let mut shock = None;
        for j in 0..ny.saturating_sub(1) {
            if yc(j) <= ys {
                continue;
            }
            let (pa, pb) = (p(j), p(j + 1));
            if pa >= half && pb < half {
                shock = Some(yc(j) + h[1] * (pa - half) / (pa - pb));
                break;
            }
        }
        let Some(y_sh) = shock else { continue };
        let (mut sum, mut n) = (0.0, 0usize);
        for j in 0..ny {
            let y = yc(j);
            if y > ys + 2.0 * h[1] && y < y_sh - 2.0 * h[1] {
                sum += p(j);
                n += 1;
            }
        }
        let ratio = if n > 0 { sum / n as f64 / p1 } else { f64::NAN };
        columns.push((d, y_sh, ratio));
    }
    let n = columns.len() as f64;
    let (sx, sy) = columns
        .iter()
        .fold((0.0, 0.0), |(a, b), c| (a + c.0, b + c.1));
    let (sxx, sxy) = columns
        .iter()
        .fold((0.0, 0.0), |(a, b), c| (a + c.0 * c.0, b + c.0 * c.1));
    let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    let ratios: Vec<f64> = columns
        .iter()
        .map(|c| c.2)
        .filter(|r| r.is_finite())
        .collect();
    WedgeMeasured {
        angle_deg: slope.atan().to_degrees(),
        tip_x,
        offset: (sy - slope * sx) / n,
        pressure_ratio: ratios.iter().sum::<f64>() / ratios.len().max(1) as f64,
        columns,
    }
}
