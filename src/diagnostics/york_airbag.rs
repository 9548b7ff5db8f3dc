//! Membranes of revolution (York Sec. 3.2 in r–z, Sec. 4.4): measures of a
//! gas-filled axisymmetric membrane — the volume it encloses with the axis,
//! its mean meridional and hoop stresses, the gas pressure by point mean
//! and by `Σ p V / V_enclosed` — and the runner of York's airbag impact
//! (Tables V–VI, Figs. 14–17).

use crate::membrane::inside_polygon;
use crate::stepper::SolidRun;
use nalgebra::Vector2;

/// Averages over one membrane of revolution and the gas points (all
/// volumes and masses per radian).
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct RevolutionMeasures {
    /// Volume per radian `∫ r dA` inside the membrane curve closed by the
    /// axis (the chain's ends joined to their projections on r = 0).
    pub volume: f64,
    /// Mass-weighted mean distance of the membrane points from `center`.
    pub mean_radius: f64,
    /// Mass-weighted mean meridional (tangential) stress `s_tt`.
    pub meridional: f64,
    /// Mass-weighted mean hoop stress `s_θθ`.
    pub hoop: f64,
    /// Number of gas points.
    pub gas_points: usize,
    /// Mean thermodynamic pressure of the gas points (EOS, q excluded).
    pub mean_pressure: f64,
    /// Sum of the gas points' volumes (per radian).
    pub gas_volume: f64,
    /// `Σ p_p V_p / volume`: the pressure an ideal gas of that internal
    /// energy (`p V = (γ − 1) m e`) has in the enclosed volume.
    pub volume_pressure: f64,
    /// Gas internal energy `Σ m e` (per radian).
    pub gas_internal: f64,
    /// Membrane strain energy `Σ V⁰ w` (per radian).
    pub membrane_strain: f64,
    /// Gas points outside the enclosed region.
    pub outside: usize,
}

/// The closed polygon of chain `chain` of `run` with the axis: its points,
/// with each open end's projection on r = 0 added when that end is off the
/// axis.
pub fn revolution_polygon(run: &SolidRun<2>, chain: usize) -> Vec<Vector2<f64>> {
    let c = run.membranes.chains[chain];
    let pts = &run.particles.x[c.first..c.first + c.count];
    let mut poly = Vec::with_capacity(pts.len() + 2);
    if !c.closed {
        poly.push(Vector2::new(0.0, pts[0][1]));
    }
    poly.extend_from_slice(pts);
    if !c.closed {
        poly.push(Vector2::new(0.0, pts[pts.len() - 1][1]));
    }
    poly
}

/// Volume per radian `∫∫ r dr dz` of the closed polygon `v` in the r–z
/// plane (Green's theorem: `(1/6) Σ (r_i z_{i+1} − r_{i+1} z_i)(r_i + r_{i+1})`),
/// positive.
pub fn volume_of_revolution(v: &[Vector2<f64>]) -> f64 {
    let n = v.len();
    let mut s = 0.0;
    for i in 0..n {
        let (a, b) = (v[i], v[(i + 1) % n]);
        s += (a[0] * b[1] - b[0] * a[1]) * (a[0] + b[0]);
    }
    (s / 6.0).abs()
}

/// [`RevolutionMeasures`] of chain `chain` of an axisymmetric run about
/// `center` (on the axis).
pub fn revolution_measures(
    run: &SolidRun<2>,
    chain: usize,
    center: [f64; 2],
) -> RevolutionMeasures {
    let p = &run.particles;
    let c = run.membranes.chains[chain];
    let poly = revolution_polygon(run, chain);
    let (mut m_sum, mut r_sum, mut s_sum, mut h_sum, mut strain) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for i in c.first..c.first + c.count {
        let m = p.mass[i];
        let d = p.x[i] - Vector2::new(center[0], center[1]);
        m_sum += m;
        r_sum += m * d.norm();
        s_sum += m * (p.stress[i][(0, 0)] + p.stress[i][(1, 1)]);
        h_sum += m * p.stress[i][(2, 2)];
        strain += p.vol0[i] * p.work[i];
    }
    let volume = volume_of_revolution(&poly);
    let mut out = RevolutionMeasures {
        volume,
        mean_radius: r_sum / m_sum,
        meridional: s_sum / m_sum,
        hoop: h_sum / m_sum,
        membrane_strain: strain,
        ..Default::default()
    };
    let (mut psum, mut pv) = (0.0, 0.0);
    for i in 0..p.len() {
        if let Some(g) = run.materials[p.material[i] as usize].gas() {
            let rho = p.mass[i] / p.vol[i];
            let e = p.work[i] * p.vol0[i] / p.mass[i];
            let pi = g.pressure(rho, e);
            psum += pi;
            pv += pi * p.vol[i];
            out.gas_points += 1;
            out.gas_volume += p.vol[i];
            out.gas_internal += p.work[i] * p.vol0[i];
            if !inside_polygon(&p.x[i], &poly) {
                out.outside += 1;
            }
        }
    }
    if out.gas_points > 0 {
        out.mean_pressure = psum / out.gas_points as f64;
        out.volume_pressure = pv / volume;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volume_of_a_revolved_square_and_half_disc() {
        // The square [1, 2] × [0, 1] revolved: ∫ r dA = 1.5 per radian.
        let sq = [[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]].map(Vector2::from);
        assert!((volume_of_revolution(&sq) - 1.5).abs() < 1e-14);
        // A half disc of radius R on the axis: the sphere, 2R³/3 per radian.
        let n = 4000;
        let v: Vec<_> = (0..=n)
            .map(|k| {
                let a = std::f64::consts::PI * k as f64 / n as f64;
                Vector2::new(a.sin(), a.cos())
            })
            .collect();
        assert!((volume_of_revolution(&v) - 2.0 / 3.0).abs() < 1e-6);
    }
}
