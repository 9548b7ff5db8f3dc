//! The steady oblique shock of a rigid wedge at rest in a supersonic stream
//! (Guilkey Sec. 4.3 seen from the wedge, `cases/wedge_mach3_steady.toml`):
//! the exact θ–β–M relation, the scene of any half-angle and Mach number,
//! and a run continued until its shock angle stops changing, so that a
//! steady state is shown rather than assumed.
//!
//! Why the wedge's frame: `cases/wedge_mach3.toml` moves the wedge through
//! still air, and its angle was still rising when the wedge reached the
//! end of the domain (36.0° at 0.48 ms, 40.0° at 1.2 ms at h = 5 mm). At
//! rest, with the body running on as a plate through the outflow face (no
//! base, no wake), the same flow settles: 40.606° from 3.0 to 4.8 ms to the
//! last printed digit at h = 5 mm
//! (`cargo run --release -p probes --bin wedge_drift_probe`, notes of
//! issue 21).

use std::time::Instant;

use crate::diagnostics::coupled::measure_wedge;
use crate::error::{Result, SceneError};
use crate::scene::{Geometry, Scene};

/// The weak attached oblique shock of a wedge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObliqueShock {
    /// Shock angle β to the stream (degrees).
    pub beta_deg: f64,
    /// Static pressure ratio across it, `p2/p1`.
    pub pressure_ratio: f64,
}

/// The flow deflection `θ(β)` (radians) of an oblique shock of angle `β`
/// (radians) at upstream Mach number `m` and ratio of specific heats
/// `gamma` (the θ–β–M relation; Anderson, *Modern Compressible Flow*,
/// Eq. 4.17):
///
/// ```text
/// tan θ = 2 cot β (M² sin²β − 1) / (M² (γ + cos 2β) + 2)
/// ```
pub fn deflection(m: f64, beta: f64, gamma: f64) -> f64 {
    let m2 = m * m;
    let s2 = beta.sin().powi(2);
    (2.0 / beta.tan() * (m2 * s2 - 1.0) / (m2 * (gamma + (2.0 * beta).cos()) + 2.0)).atan()
}

/// The weak attached oblique shock for upstream Mach number `m`, wedge
/// half-angle `theta_deg` and ratio of specific heats `gamma`: `β` solves
/// the θ–β–M relation ([`deflection`]) between the Mach angle
/// `asin(1/M)` and the angle of maximum deflection, and
/// `p2/p1 = 1 + 2γ/(γ + 1) (M² sin²β − 1)` (the normal shock of
/// `M sin β`). `None` for `m ≤ 1`, `θ ≤ 0`, or a wedge beyond the maximum
/// deflection (a detached shock).
pub fn oblique_shock(m: f64, theta_deg: f64, gamma: f64) -> Option<ObliqueShock> {
    if !(m > 1.0 && theta_deg > 0.0 && theta_deg < 90.0 && gamma > 1.0) {
        return None;
    }
    let theta = theta_deg.to_radians();
    let mu = (1.0 / m).asin();
    let half_pi = std::f64::consts::FRAC_PI_2;
    // θ(β) rises from 0 at the Mach angle to its maximum and falls to 0
    // at 90°: the maximum by golden-section search.
    let (mut a, mut b) = (mu, half_pi);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..200 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if deflection(m, c, gamma) < deflection(m, d, gamma) {
            a = c;
        } else {
            b = d;
        }
    }
    let beta_max = 0.5 * (a + b);
    if deflection(m, beta_max, gamma) < theta {
        return None;
    }
    // The weak branch: θ increases on [μ, β_max]; bisection.
    let (mut lo, mut hi) = (mu, beta_max);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if deflection(m, mid, gamma) < theta {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let beta = 0.5 * (lo + hi);
    let mn2 = (m * beta.sin()).powi(2);
    Some(ObliqueShock {
        beta_deg: beta.to_degrees(),
        pressure_ratio: 1.0 + 2.0 * gamma / (gamma + 1.0) * (mn2 - 1.0),
    })
}

/// The stream of a steady wedge scene: its Mach number, the air's `γ`, the
/// free-stream pressure and the tip's `x`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WedgeStream {
    /// Upstream Mach number.
    pub mach: f64,
    /// Ratio of specific heats of the air.
    pub gamma: f64,
    /// Free-stream pressure `p1`.
    pub p1: f64,
    /// The tip's `x` (the polygon's first vertex).
    pub tip_x: f64,
    /// The wedge's length, tip to shoulder along `x`.
    pub length: f64,
}

/// `base` (`cases/wedge_mach3_steady.toml` or a scene laid out as it is)
/// with a wedge of half-angle `half_angle_deg` in a stream of Mach number
/// `mach`, its cells multiplied by `factor`: the shoulder's height becomes
/// `L tan θ` (L the tip-to-shoulder length) and the stream's velocity
/// `M c₁` with `c₁ = √(γ p/ρ)` of the region's air. Also returns the
/// stream.
///
/// # Errors
/// A [`SceneError`] naming the key when `base` is not laid out as the case
/// (a polygon of four vertices as the first object, one region whose first
/// state gives the air's density and velocity, an air material with
/// `gamma`).
pub fn steady_wedge_scene(
    base: &Scene,
    mach: f64,
    half_angle_deg: f64,
    factor: usize,
) -> Result<(Scene, WedgeStream)> {
    let mut sc = base.clone();
    let layout = "laid out as cases/wedge_mach3_steady.toml";
    let Some(Geometry::Polygon { vertices }) = sc.objects.first_mut().map(|o| &mut o.geometry)
    else {
        return Err(SceneError::new("objects[0].geometry", format!("a polygon, {layout}")).into());
    };
    if vertices.len() != 4 {
        return Err(SceneError::new("objects[0].geometry.vertices", "four vertices").into());
    }
    let tip_x = vertices[0][0];
    let length = vertices[1][0] - tip_x;
    let height = length * half_angle_deg.to_radians().tan();
    vertices[1][1] = height;
    vertices[2][1] = height;
    let region = sc
        .regions
        .first_mut()
        .ok_or_else(|| SceneError::new("regions", format!("one region, {layout}")))?;
    let p1 = region.pressure;
    let state = region
        .states
        .first_mut()
        .ok_or_else(|| SceneError::new("regions[0].states", "the air's state"))?;
    let rho = state
        .density
        .ok_or_else(|| SceneError::new("regions[0].states[0].density", "needed"))?;
    let gamma = base
        .materials
        .iter()
        .find(|m| m.name == state.material)
        .and_then(|m| m.gamma)
        .ok_or_else(|| SceneError::new("materials", "the air's gamma"))?;
    state.velocity = Some(vec![mach * (gamma * p1 / rho).sqrt(), 0.0]);
    for n in sc.grid.cells.iter_mut() {
        *n *= factor;
    }
    Ok((
        sc,
        WedgeStream {
            mach,
            gamma,
            p1,
            tip_x,
            length,
        },
    ))
}

/// A steady wedge run measured against [`oblique_shock`].
#[derive(Debug, Clone)]
pub struct SteadyWedge {
    /// The exact weak shock.
    pub exact: ObliqueShock,
    /// Cell size.
    pub h: f64,
    /// The shock angle at the sample before the last (degrees; NaN when
    /// `max_end` left room for one sample only).
    pub angle_before_deg: f64,
    /// The shock angle at the last sample (degrees).
    pub angle_deg: f64,
    /// `p2/p1` at the last sample.
    pub pressure_ratio: f64,
    /// Time of the last sample.
    pub time: f64,
    /// Whether the last two samples agreed within the tolerance (`false`:
    /// the run reached its time limit first).
    pub settled: bool,
    /// Steps taken.
    pub steps: u64,
    /// Wall time of the run (s).
    pub wall_s: f64,
}

/// Runs a steady wedge scene ([`steady_wedge_scene`]) until its shock
/// angle is steady: measured at the scene's end and then every `interval`
/// until two samples agree within `tolerance` degrees or the time passes
/// `max_end`; the shock is measured 0.25–0.75 wedge lengths behind the tip
/// ([`measure_wedge`]).
///
/// # Errors
/// A scene error (including a detached shock), or the run's failure.
pub fn run_steady_wedge(
    sc: &Scene,
    stream: &WedgeStream,
    half_angle_deg: f64,
    interval: f64,
    tolerance: f64,
    max_end: f64,
) -> Result<SteadyWedge> {
    let exact = oblique_shock(stream.mach, half_angle_deg, stream.gamma).ok_or_else(|| {
        SceneError::new(
            "objects[0].geometry",
            format!(
                "a {half_angle_deg}° wedge detaches the shock at Mach {}",
                stream.mach
            ),
        )
    })?;
    if !(interval > 0.0 && tolerance > 0.0) {
        return Err(SceneError::new(
            "interval, tolerance",
            format!("must be > 0 (got {interval}, {tolerance})"),
        )
        .into());
    }
    let start = Instant::now();
    let mut run = crate::scene::build_coupled_run::<2>(sc)?;
    let length = stream.length;
    let measure = |run: &crate::coupling::CoupledRun<2>| {
        measure_wedge(
            &run.fluid,
            stream.tip_x,
            half_angle_deg,
            stream.p1,
            exact.pressure_ratio * stream.p1,
            (0.25 * length, 0.75 * length),
        )
    };
    let mut t = sc.time.end;
    run.advance_to(t)?;
    let mut last = measure(&run);
    let mut before = f64::NAN;
    let mut settled = false;
    while t + interval <= max_end * (1.0 + 1e-12) {
        t += interval;
        run.advance_to(t)?;
        before = last.angle_deg;
        last = measure(&run);
        if (last.angle_deg - before).abs() < tolerance {
            settled = true;
            break;
        }
    }
    Ok(SteadyWedge {
        exact,
        h: run.fluid.layout.h[0],
        angle_before_deg: before,
        angle_deg: last.angle_deg,
        pressure_ratio: last.pressure_ratio,
        time: t,
        settled,
        steps: run.steps,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case() -> Scene {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/wedge_mach3_steady.toml");
        crate::scene::load(&path).unwrap()
    }

    #[test]
    fn a_wedge_scene_of_another_angle_and_mach_number_and_its_bad_input() {
        let (sc, stream) = steady_wedge_scene(&case(), 2.0, 15.0, 2).unwrap();
        let Geometry::Polygon { vertices } = &sc.objects[0].geometry else {
            panic!("polygon")
        };
        assert!((vertices[1][1] - 0.2 * 15f64.to_radians().tan()).abs() < 1e-12);
        assert_eq!(vertices[1][1], vertices[2][1]);
        assert_eq!(sc.grid.cells, vec![320, 80]);
        let u = sc.regions[0].states[0].velocity.as_ref().unwrap()[0];
        assert!((u - 2.0 * (1.4f64 * 101_325.0 / 1.1768).sqrt()).abs() < 1e-9);
        assert_eq!(stream.tip_x, 0.6);
        assert!((stream.length - 0.2).abs() < 1e-12);
        // A 30° wedge at Mach 2 detaches its shock: refused, naming the
        // wedge, before anything runs.
        let (sc, stream) = steady_wedge_scene(&case(), 2.0, 30.0, 1).unwrap();
        let e = run_steady_wedge(&sc, &stream, 30.0, 1e-4, 0.02, 1e-3).unwrap_err();
        assert!(e.to_string().contains("objects[0].geometry"), "{e}");
        let e = run_steady_wedge(&sc, &stream, 20.0, 0.0, 0.02, 1e-3).unwrap_err();
        assert!(e.to_string().contains("interval"), "{e}");
        // A scene not laid out as the case.
        let mut other = case();
        other.objects[0].geometry = Geometry::Box {
            lower: vec![0.6, 0.0],
            upper: vec![0.8, 0.05],
        };
        let e = steady_wedge_scene(&other, 3.0, 20.0, 1).unwrap_err();
        assert!(e.to_string().contains("objects[0].geometry"), "{e}");
    }

    #[test]
    fn the_oblique_shock_matches_the_tables() {
        // Guilkey Sec. 4.3's wedge: 37.76°, 3.771.
        let s = oblique_shock(3.0, 20.0, 1.4).unwrap();
        assert!((s.beta_deg - 37.76).abs() < 0.01, "{}", s.beta_deg);
        assert!(
            (s.pressure_ratio - 3.771).abs() < 2e-3,
            "{}",
            s.pressure_ratio
        );
        // The θ–β–M chart: β = 53.4° at M = 2, θ = 20°.
        let s = oblique_shock(2.0, 20.0, 1.4).unwrap();
        assert!((s.beta_deg - 53.4).abs() < 0.1, "{}", s.beta_deg);
        // The deflection of the returned angle is the wedge's, and a
        // normal-shock limit: θ_max(M = 2) = 22.97°, so 23° detaches.
        for (m, th) in [(1.5, 5.0), (3.0, 10.0), (4.0, 25.0), (8.0, 40.0)] {
            let s = oblique_shock(m, th, 1.4).unwrap();
            let back = deflection(m, s.beta_deg.to_radians(), 1.4).to_degrees();
            assert!((back - th).abs() < 1e-9, "M {m}, θ {th}: {back}");
            assert!(s.beta_deg > (1.0 / m).asin().to_degrees());
        }
        assert!(oblique_shock(2.0, 22.9, 1.4).is_some());
        assert!(oblique_shock(2.0, 23.1, 1.4).is_none());
        assert!(oblique_shock(0.9, 5.0, 1.4).is_none());
    }
}
