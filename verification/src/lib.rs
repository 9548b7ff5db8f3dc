//! Verification studies of mpmice: the harness (result format, order fits,
//! plots) and the studies themselves.

pub mod axisym_studies;
pub mod bench_report;
pub mod coupled_studies;
pub mod eos_studies;
pub mod formulation_studies;
/// The study harness lives in `mpmice::study::harness` (the `mpmice study`
/// command writes its results with the same code).
pub use mpmice::study::harness;
pub mod ice_studies;
pub mod implicit_coupled_studies;
pub mod impm_studies;
pub mod lian_studies;
pub mod mpm_studies;
pub mod multiphase_rod;
pub mod multiphase_spall;
pub mod multiphase_studies;
pub mod plasticity_studies;
pub mod reaction_studies;
pub mod taylor_studies;
pub mod york_studies;

/// The folder the binary's `--out` names (set once by `main`; absent:
/// `verification/results`).
static RESULTS_ROOT: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();

/// Sends the studies' extra plots to `dir` (`verification --out DIR`), as
/// their JSON, CSV and PNG go; the first call wins.
pub fn set_results_root(dir: std::path::PathBuf) {
    let _ = RESULTS_ROOT.set(dir);
}

/// Where a study's extra plots go: beside the harness output, in the
/// results folder (`--out`, or `verification/results`), `quick/` under it
/// for a quick run, so quick plots never overwrite the full ones.
pub(crate) fn plot_dir(quick: bool) -> std::path::PathBuf {
    let root = RESULTS_ROOT
        .get()
        .cloned()
        .unwrap_or_else(|| std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("results"));
    if quick {
        root.join("quick")
    } else {
        root
    }
}

/// A study: name, one-line description, runner (`quick` = coarse resolutions).
pub type Study = (
    &'static str,
    &'static str,
    fn(bool) -> anyhow::Result<harness::StudyResult>,
);

/// Every study the binary knows.
pub const STUDIES: &[Study] = &[
    (
        "zhang_block",
        "Zhang Sec. 3 block-in-air: a disk/sphere moving with the air, weak (Eq. 18) vs strong (Eq. 7) constraint, 2D axis/diagonal and 3D",
        multiphase_studies::zhang_block,
    ),
    (
        "zhang_vs_guilkey",
        "Zhang multiphase beside Guilkey MPM-ICE on the same scenes: block test (disk diagonal with the air) pressure change and a Mach 1.5 shock on a steel block vs p5; cost per step, pressure-solve share",
        formulation_studies::zhang_vs_guilkey,
    ),
    (
        "zhang_spall",
        "Zhang Sec. 4 plate spall (multiphase, air around): first-failure time vs 3d/c and plane vs h",
        multiphase_spall::zhang_spall,
    ),
    (
        "zhang_rod",
        "Zhang Figs. 3-4 tungsten rod into steel (tungsten/steel/air phases, r-z): penetration and residual length vs time at R/2, R/3, R/4, Alekseevskii-Tate band",
        multiphase_rod::zhang_rod,
    ),
    (
        "reaction_burn",
        "Guilkey 5 surface burn: burning area of a disk and turned squares vs h; slab burnt mass vs K A t",
        reaction_studies::reaction_burn,
    ),
    (
        "confined_explosion_onset",
        "Guilkey 5 confined explosion 2D: first failed steel point vs h, local and nonlocal (R = 2 mm) Johnson-Cook damage",
        reaction_studies::confined_explosion_onset,
    ),
    (
        "cylinder_order",
        "Guilkey 4.1 pressurised cylinder, MPM-ICE, Eq. 43 vs dx and Fig. 3a",
        coupled_studies::cylinder_order,
    ),
    (
        "cylinder_implicit",
        "Guilkey 4.1 pressurised cylinder, implicit MPM-ICE at large steps: Eq. 43 and wall time vs dx beside explicit, and vs dt",
        implicit_coupled_studies::cylinder_implicit,
    ),
    (
        "piston_implicit",
        "Guilkey 4.2 adiabatic piston, implicit pressure at steps set by the piston's motion: closed-end pressure at ratio 5 vs dt and h, beside explicit",
        implicit_coupled_studies::piston_implicit,
    ),
    (
        "slab_temporal_order",
        "Steel slab on two air springs, implicit MPM-ICE: temporal order at fixed h, staggered and with the coupling iteration",
        implicit_coupled_studies::slab_temporal_order,
    ),
    (
        "piston_adiabatic",
        "Guilkey 4.2 adiabatic piston, MPM-ICE, closed-end pressure vs P1 (V1/V2)^gamma",
        coupled_studies::piston_adiabatic,
    ),
    (
        "wedge_mach3",
        "Guilkey 4.3 rigid wedge at Mach 3, MPM-ICE, shock angle and p2/p1 vs exact",
        coupled_studies::wedge_mach3,
    ),
    (
        "wedge_steady",
        "Guilkey 4.3 seen from the wedge: steady shock angle vs theta-beta-M for 20 deg at Mach 3, 15 deg at Mach 2, 25 deg at Mach 4",
        coupled_studies::wedge_steady,
    ),
    (
        "mpm_bar_1d",
        "1D elastic bar, fixed-free, mode 1 vs exact; energy drift",
        mpm_studies::mpm_bar_1d,
    ),
    (
        "mpm_mms_axis_aligned",
        "Wallstedt-Guilkey axis-aligned MMS, 1D/2D, all shape functions, A = 1e-4 and 0.05",
        mpm_studies::mpm_mms_axis_aligned,
    ),
    (
        "impm_column",
        "implicit quasistatic self-weight column, stress error vs h, linear hat and GIMP",
        impm_studies::impm_column,
    ),
    (
        "impm_cylinder",
        "Guilkey 4.1 pressurised cylinder, implicit quasistatic, Eq. 43 and Lame u_r error vs dx",
        impm_studies::impm_cylinder,
    ),
    (
        "impm_vs_explicit",
        "error vs wall time: implicit vs damped explicit cylinder, dynamic bar across dt",
        impm_studies::impm_vs_explicit,
    ),
    (
        "impm_mms",
        "axis-aligned MMS run implicitly (Newmark): order vs explicit, stability at large dt",
        impm_studies::impm_mms,
    ),
    (
        "york_sod",
        "York 4.1 Sod with gas material points, L1(rho) vs exact Riemann beside ICE at equal dx",
        york_studies::york_sod,
    ),
    (
        "york_piston_container",
        "York 4.2 piston-container: period vs Eq. 27 for m = 0.1 and 1.0 vs h",
        york_studies::york_piston_container,
    ),
    (
        "axisym_lame",
        "axisymmetric r-z explicit MPM: Lame thick cylinder and sphere under internal pressure, sigma_r, sigma_theta, u_r vs h",
        axisym_studies::axisym_lame,
    ),
    (
        "hencky_simple_shear",
        "multiplicative (Hencky) J2 plasticity: simple shear of one point to gamma = 1, tau_xy error vs the shear step, three flow laws",
        plasticity_studies::hencky_simple_shear,
    ),
    (
        "taylor_anvil",
        "Taylor anvil: Johnson-Cook copper rod on a rigid wall (axisymmetric MPM), final length and impact-face diameter vs the measured rods at 190/146/130 m/s, energy account, vs h",
        taylor_studies::taylor_anvil,
    ),
    (
        "york_dogbone",
        "York 4.3 dog-bone membrane expansion: radius, pressure, hoop vs p r / t, gas kept, vs h",
        york_studies::york_dogbone,
    ),
    (
        "york_airbag",
        "York 4.4 airbag impact (axisymmetric membrane points): penetration, pressure, p V^gamma, energy vs h",
        york_studies::york_airbag,
    ),
    (
        "lian_membrane",
        "Lian 4 Belytschko-Tsay membrane quads: pre-tensioned square period vs c/(sqrt2 L), Hencky disc w0, point-load hourglass share",
        lian_studies::lian_membrane,
    ),
    (
        "lian_gas_expansion",
        "Lian 7.3 gas expanding in a membrane of elements (grid contact, 3D quarter): final radius vs the inextensible circle, radii at 0/90 deg, energy, vs h",
        lian_studies::lian_gas_expansion,
    ),
    (
        "lian_impact",
        "Lian 7.1 membrane-sphere impacts (quarter models): membrane centre/corner and sphere top z(t) vs h, contact onset, energy account with contact and hourglass losses",
        lian_studies::lian_impact,
    ),
    (
        "lian_water",
        "Lian 7.2 water drop (gas points, Mie-Grueneisen, p >= 0) on a soft clamped membrane: centre and drop top z(t) vs h, both contact detections, energy account, mass",
        lian_studies::lian_water,
    ),
    (
        "ice_sod",
        "Sod shock tube, explicit ICE, L1(rho) vs exact Riemann, 1st/2nd order advection",
        ice_studies::ice_sod,
    ),
    (
        "ice_entropy_wave",
        "advected smooth density wave (exact translation), periodic",
        ice_studies::ice_entropy_wave,
    ),
    (
        "ice_diagonal_wave",
        "2D density wave advected diagonally: corner transport vs dimension by dimension, error vs N and Courant number",
        ice_studies::ice_diagonal_wave,
    ),
    (
        "ice_acoustic",
        "small-amplitude acoustic wave vs linear acoustics",
        ice_studies::ice_acoustic,
    ),
    (
        "ice_simple_wave",
        "finite-amplitude isentropic simple wave (eps 1e-2 and 0.1) vs characteristics: Hancock, acoustic Hancock, high resolution",
        ice_studies::ice_simple_wave,
    ),
    (
        "ice_sod_semi_implicit",
        "Sod shock tube, explicit vs semi-implicit (implicit pressure) ICE, both vs exact Riemann",
        ice_studies::ice_sod_semi_implicit,
    ),
    (
        "ice_low_mach",
        "low-Mach periodic vortex, explicit vs semi-implicit ICE at acoustic CFL 1/10/50 (and 10/20/50 with the convective predictor): order, Mach floor, work-precision, speed-up at equal error",
        ice_studies::ice_low_mach,
    ),
    (
        "mie_gruneisen_shock",
        "Mie-Gruneisen water and copper driven into a wall at u_p = 100/500/1000/3000 m/s, explicit ICE and (water) gas points: U_s vs c0 + s u_p, p1 vs p0 + rho0 U_s u_p, vs h",
        eos_studies::mie_gruneisen_shock,
    ),
    (
        "water_air_shock_tube",
        "water | air shock tube at pressure ratios 10, 100, 1e4: L1(rho) and interface position vs the exact stiffened-gas Riemann solution",
        eos_studies::water_air_shock_tube,
    ),
];
