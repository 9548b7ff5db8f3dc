//! Lian's grid contact (Sec. 5, Eqs. 49–59) between an MPM block and a
//! body of points off the grid (standing in for membrane FE nodes: the
//! contact sees only their masses, trial velocities and normals): the
//! total momentum is conserved to round-off through contact in 2D and 3D;
//! with free slip the tangential momentum of a block sliding on a heavy
//! layer does not change; with Coulomb friction the tangential impulse is
//! μ times the normal one to round-off, and the block decelerates at μ g.

use mpmice::contact::{
    ContactDetection, ContactLaw, ContactStats, GridContact, MpmNodes, PointBody,
};
use mpmice::grid::{Boundary, Grid};
use mpmice::material::{ElasticConstants, SolidMaterial, SolidModel};
use mpmice::mpm::{
    BodyForce, CoupledMpm, ExplicitParams, GridState, Particles, StepScratch, UpdateScheme,
};
use mpmice::shape::ShapeKind;
use nalgebra::SVector;

/// A neo-Hookean block (E = 1e6, ν = 0.3, ρ = 1000) and a flat layer of
/// points with normal +e_{D−1} on the grid line under it.
struct Scene<const D: usize> {
    grid: Grid<D>,
    materials: Vec<SolidMaterial>,
    params: ExplicitParams,
    particles: Particles<D>,
    gs: GridState<D>,
    scratch: StepScratch<D>,
    grad: Vec<SVector<f64, D>>,
    contact: GridContact<D>,
    /// The layer: positions, masses, velocities, normals.
    x: Vec<SVector<f64, D>>,
    m: Vec<f64>,
    v: Vec<SVector<f64, D>>,
    n: Vec<SVector<f64, D>>,
    gravity: SVector<f64, D>,
    dt: f64,
    t: f64,
    steps: u64,
}

struct Gravity<const D: usize>(SVector<f64, D>);

impl<const D: usize> BodyForce<D> for Gravity<D> {
    fn accel(&self, _: &SVector<f64, D>, _: &SVector<f64, D>, _: f64) -> SVector<f64, D> {
        self.0
    }
}

const H: f64 = 0.05;
const RHO: f64 = 1000.0;

impl<const D: usize> Scene<D> {
    /// Block of `cells` cells (2 particles per cell and direction) with its
    /// lower face on the grid line `y0` (last coordinate) where the layer
    /// of points (spacing h/2, mass `layer_mass` each) lies, moving at `v0`;
    /// nodes with less than `floor` × a particle's mass are empty.
    fn new(
        cells: [usize; D],
        v0: SVector<f64, D>,
        layer_mass: f64,
        gravity: SVector<f64, D>,
        floor: f64,
    ) -> Self {
        let n_grid: [usize; D] = std::array::from_fn(|d| if d + 1 == D { 20 } else { 40 });
        let upper = SVector::<f64, D>::from_fn(|d, _| n_grid[d] as f64 * H);
        let grid = Grid::new(SVector::zeros(), upper, n_grid, [[Boundary::Free; 2]; D]);
        let mat = SolidMaterial {
            name: "block".into(),
            density: RHO,
            model: SolidModel::NeoHookean,
            elastic: ElasticConstants::from_young_poisson(1e6, 0.3),
        };
        let c = mat.wave_speed(RHO);
        let y0 = 10.0 * H;
        let lo = SVector::<f64, D>::from_fn(|d, _| if d + 1 == D { y0 } else { 10.0 * H });
        let hp = H / 2.0;
        let vol = hp.powi(D as i32);
        let mut particles = Particles::default();
        let counts: [usize; D] = std::array::from_fn(|d| 2 * cells[d]);
        let total: usize = counts.iter().product();
        for k in 0..total {
            let mut rem = k;
            let mut x = lo;
            for d in 0..D {
                x[d] += (0.5 + (rem % counts[d]) as f64) * hp;
                rem /= counts[d];
            }
            particles.push(x, v0, RHO * vol, vol, SVector::repeat(hp / 2.0), 0);
        }
        // The layer: a line (2D) or plane (3D) of points at y0 spanning
        // [2h, (n−2)h] in the other directions.
        let per: [usize; D] = std::array::from_fn(|d| {
            if d + 1 == D {
                1
            } else {
                2 * (n_grid[d] - 4) + 1
            }
        });
        let mut x = Vec::new();
        let num: usize = per.iter().product();
        for k in 0..num {
            let mut rem = k;
            let mut p = SVector::<f64, D>::zeros();
            for d in 0..D {
                p[d] = if d + 1 == D {
                    y0
                } else {
                    2.0 * H + (rem % per[d]) as f64 * hp
                };
                rem /= per[d];
            }
            x.push(p);
        }
        let mut normal = SVector::<f64, D>::zeros();
        normal[D - 1] = 1.0;
        let nodes = grid.num_nodes();
        Self {
            params: ExplicitParams {
                shape: ShapeKind::Gimp,
                scheme: UpdateScheme::Usl,
                mass_floor: floor * RHO * vol,
                damping: 0.0,
                pic_fraction: 0.0,
            },
            materials: vec![mat],
            particles,
            gs: GridState::new(nodes),
            scratch: StepScratch::default(),
            grad: vec![SVector::zeros(); nodes],
            contact: GridContact::new(&grid),
            m: vec![layer_mass; num],
            v: vec![SVector::zeros(); num],
            n: vec![normal; num],
            x,
            gravity,
            dt: 0.3 * H / c,
            t: 0.0,
            steps: 0,
            grid,
        }
    }

    /// One step of Lian Sec. 6: the MPM trial solution on the grid, the
    /// layer's trial velocity (no internal force), contact, G2P, the
    /// layer's corrected velocity and position.
    fn step(&mut self, law: ContactLaw) -> ContactStats {
        let body = Gravity(self.gravity);
        let mpm = CoupledMpm {
            grid: &self.grid,
            materials: &self.materials,
            params: &self.params,
            body: Some(&body),
            t: self.t,
            dt: self.dt,
            step: self.steps,
        };
        mpm.p2g(&self.particles, &mut self.gs, &mut self.scratch)
            .expect("p2g");
        mpm.mass_gradient(&self.particles, &self.scratch, &mut self.grad);
        mpm.solve(
            &mut self.particles,
            &mut self.gs,
            &mut self.scratch,
            None,
            &[],
        )
        .expect("solve");
        let points = PointBody {
            x: &self.x,
            mass: &self.m,
            v: &self.v,
            normal: &self.n,
            held: &[],
            half_thickness: &[],
        };
        self.contact
            .map_points(&self.grid, &points)
            .expect("on grid");
        let stats = self.contact.resolve(
            &mut MpmNodes {
                mass: &self.gs.mass,
                velocity: &mut self.gs.velocity_new,
                accel: &mut self.gs.accel,
                mass_gradient: &self.grad,
                mass_floor: self.params.mass_floor,
            },
            law,
            ContactDetection::Approach,
            self.dt,
        );
        self.grid.mirror_ghosts(&mut self.gs.velocity_new);
        self.grid.mirror_ghosts(&mut self.gs.accel);
        mpm.g2p(&mut self.particles, &self.gs, &mut self.scratch, &[])
            .expect("g2p");
        self.contact.correct_points(self.dt, &mut self.v);
        for (x, v) in self.x.iter_mut().zip(&self.v) {
            *x += v * self.dt;
        }
        self.t += self.dt;
        self.steps += 1;
        stats
    }

    fn block_momentum(&self) -> SVector<f64, D> {
        self.particles.momentum()
    }

    fn layer_momentum(&self) -> SVector<f64, D> {
        self.m.iter().zip(&self.v).map(|(m, v)| v * *m).sum()
    }
}

/// A block thrown at a free layer, no gravity: the sum of the two momenta
/// stays at its start value to round-off while the contact moves a large
/// share of it into the layer. The mass floor is 0 here: the scene's floor
/// (1e-12 of a particle's mass) drops the internal force of the nodes at
/// the edge of a stressed block's GIMP support, a leak of the MPM itself
/// (about 1e-11 of the momentum over these runs) that would hide the
/// contact's round-off.
fn momentum_is_conserved<const D: usize>(cells: [usize; D]) {
    let mut v0 = SVector::<f64, D>::zeros();
    v0[0] = 0.3;
    v0[D - 1] = -1.0;
    let block_mass = {
        let n: usize = cells.iter().map(|c| 2 * c).product();
        n as f64 * RHO * (H / 2.0).powi(D as i32)
    };
    // The points under the block carry half its mass.
    let under: usize = cells[..D - 1].iter().map(|c| 2 * c + 1).product();
    let mut s = Scene::<D>::new(
        cells,
        v0,
        0.5 * block_mass / under as f64,
        SVector::zeros(),
        0.0,
    );
    let p0 = s.block_momentum() + s.layer_momentum();
    let mut contacts = 0;
    for _ in 0..150 {
        contacts += s.step(ContactLaw::Stick).contact_nodes;
    }
    let p1 = s.block_momentum() + s.layer_momentum();
    let drift = (p1 - p0).norm() / p0.norm();
    let moved = s.layer_momentum().norm() / p0.norm();
    eprintln!(
        "{D}D stick: {contacts} contact node-steps, layer holds {moved:.3} of the momentum, drift {drift:.2e}"
    );
    assert!(contacts > 0);
    assert!(moved > 0.1, "the contact moved only {moved}");
    assert!(drift < 1e-14, "momentum drift {drift:e}");
}

#[test]
fn momentum_is_conserved_through_contact_in_2d() {
    momentum_is_conserved::<2>([8, 4]);
}

#[test]
fn momentum_is_conserved_through_contact_in_3d() {
    momentum_is_conserved::<3>([4, 4, 2]);
}

/// A block sliding at 1 m/s on a heavy layer (10⁹ × its particles' mass
/// per point) under gravity g = 10, with the scene's mass floor. Returns
/// the block's momentum history `(t, p_x, p_y)` and the contact impulses on
/// the layer summed over the run: x, y, normal and tangential magnitudes.
fn sliding(law: ContactLaw) -> (Scene<2>, Vec<(f64, f64, f64)>, [f64; 4]) {
    let mut s = Scene::<2>::new(
        [8, 4],
        SVector::from([1.0, 0.0]),
        1e9 * RHO * (H / 2.0).powi(2),
        SVector::from([0.0, -10.0]),
        1e-12,
    );
    let mut hist = vec![(0.0, s.block_momentum()[0], s.block_momentum()[1])];
    let mut impulse = [0.0; 4];
    while s.t < 0.2 {
        let st = s.step(law);
        if let ContactLaw::Slip { friction } = law {
            if friction > 0.0 {
                // Every contact node slips (the stick force's tangential
                // part would stop the block in one step).
                assert_eq!(st.slipping_nodes, st.contact_nodes, "at t = {}", s.t);
            }
        }
        impulse[0] += st.impulse[0];
        impulse[1] += st.impulse[1];
        impulse[2] += st.normal_impulse;
        impulse[3] += st.tangential_impulse;
        let p = s.block_momentum();
        hist.push((s.t, p[0], p[1]));
    }
    (s, hist, impulse)
}

#[test]
fn free_slip_keeps_the_tangential_momentum() {
    let (s, hist, impulse) = sliding(ContactLaw::Slip { friction: 0.0 });
    let px0 = hist[0].1;
    let worst = hist
        .iter()
        .map(|h| (h.1 - px0).abs() / px0)
        .fold(0.0, f64::max);
    let py = hist.last().expect("steps").2;
    let mass = s.particles.total_mass();
    eprintln!(
        "free slip: contact impulse {impulse:?}, tangential drift {worst:.2e}, final vertical velocity {:.3e}",
        py / mass
    );
    // The contact adds no tangential impulse at all.
    assert_eq!(impulse[0], 0.0);
    assert!(impulse[1] < 0.0, "no normal impulse");
    // The block's own drift is the mass floor's leak (see
    // `momentum_is_conserved`): measured 5.3e-11.
    assert!(worst < 1e-9, "tangential momentum drift {worst:e}");
    // The layer holds the block up: it does not fall through (free fall
    // would give −2 m/s by t = 0.2).
    assert!((py / mass).abs() < 0.01, "vertical velocity {}", py / mass);
}

#[test]
fn coulomb_friction_decelerates_at_mu_g() {
    let mu = 0.2;
    let g = 10.0;
    let (s, hist, impulse) = sliding(ContactLaw::Slip { friction: mu });
    let mass = s.particles.total_mass();
    // Every node slips, so the tangential impulse on the layer is μ times
    // the normal one node by node, to round-off (Lian Eq. 58); the net
    // tangential impulse is nearly all of it (a node or two at the block's
    // ends sees the opposite relative motion).
    let coulomb = (impulse[3] - mu * impulse[2]).abs() / impulse[3];
    let net = impulse[0] / impulse[3];
    // The block's mean deceleration over the run: the normal force
    // averages the weight once the initial elastic bounce has settled.
    let (_, px0, _) = hist[0];
    let &(t, px, _) = hist.last().expect("steps");
    let decel = (px0 - px) / mass / t;
    eprintln!(
        "Coulomb μ = {mu}: impulse {impulse:?}, Σ|J_t| − μΣ|J_n| {coulomb:.2e}, net/Σ|J_t| {net:.9}, mean deceleration {decel:.4} (μg = {})",
        mu * g
    );
    assert!(coulomb < 1e-14, "Coulomb ratio {coulomb:e}");
    assert!(net > 1.0 - 1e-6, "net tangential share {net}");
    assert!(
        (decel / (mu * g) - 1.0).abs() < 0.01,
        "deceleration {decel}"
    );
}
