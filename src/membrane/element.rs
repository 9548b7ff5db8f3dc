//! Lian's membrane finite elements (Lian, Liu, Zhang Sec. 4): four-node
//! Belytschko–Tsay membrane quadrilaterals with a co-rotational frame per
//! element, one-point quadrature at the centre and Flanagan–Belytschko
//! viscous hourglass control, integrated by central differences.
//!
//! A [`MembraneMesh`] is a struct of arrays: nodes (positions, velocities at
//! n−½, lumped masses, fixed directions, forces) and elements (corner ids,
//! thickness, the in-plane stress in the element's own frame). The step is
//! split so that a grid contact (Lian Sec. 6, steps 3 and 4(d)) can sit
//! between its parts:
//!
//! 1. [`MembraneMesh::compute_forces`]: internal forces from the stress
//!    (Lian Eqs. 42–45), hourglass forces, the follower pressure and gravity
//!    (Eq. 31), assembled to the nodes in a fixed order;
//! 2. [`MembraneMesh::trial_velocities`]: v^{n+½} = v^{n−½} + Δt f/m
//!    (Eq. 46), fixed directions held at rest;
//! 3. (a contact may correct `v` here);
//! 4. [`MembraneMesh::update_positions`]: x^{n+1} = x^n + Δt v^{n+½}
//!    (Eq. 47);
//! 5. [`MembraneMesh::update_stress`]: the strain rate of v^{n+½} (Eqs.
//!    40–41) on the mid-step geometry x^{n+½} = ½(x^n + x^{n+1}), the
//!    hypo-elastic plane-stress update in the co-rotational frame, the
//!    thickness, the stored energy, and the failure checks on x^{n+1}.
//!
//! Lian evaluates the strain rate at the start of the next step on the
//! geometry x^n (step 3(a)–(c)); the increment is the same, but taking the
//! frame and the B matrix at x^{n+½} makes the strain increment of a rigid
//! rotation exactly zero (the mid-point rule of Hughes and Winget), so a
//! spinning element stays unstressed to round-off.
//!
//! Every element loop runs in parallel writing per-element results; the
//! nodes gather their elements' contributions in a fixed order, so results
//! are bit-identical for any number of threads.

use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

/// A 3-vector of `f64`.
pub type V3 = Vector3<f64>;

/// The hourglass pattern of a four-node quadrilateral (Flanagan and
/// Belytschko 1981): +1, −1, +1, −1 around the element.
const HOURGLASS: [f64; 4] = [1.0, -1.0, 1.0, -1.0];

/// Plane-stress isotropic elastic membrane material, with the element
/// settings that go with it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MembraneMaterial {
    /// Density ρ [kg/m³].
    pub density: f64,
    /// Young's modulus E \[Pa\].
    pub young: f64,
    /// Poisson's ratio ν.
    pub poisson: f64,
    /// Flanagan–Belytschko viscous hourglass coefficient κ (dimensionless,
    /// typically 0.05–0.15).
    pub hourglass: f64,
    /// Mass-proportional damping α [1/s]: the nodes feel −α m v (dynamic
    /// relaxation to a static state; 0 for dynamics).
    pub damping: f64,
}

impl MembraneMaterial {
    /// The plane-stress wave speed c = √(E / (ρ (1 − ν²))) (Lian Eq. 48).
    pub fn wave_speed(&self) -> f64 {
        (self.young / (self.density * (1.0 - self.poisson * self.poisson))).sqrt()
    }

    /// The plane-stress stress rate C : D for a strain rate
    /// `d = [Dxx, Dyy, Dxy]` (tensor shear component); returns
    /// `[σ̇xx, σ̇yy, σ̇xy]`.
    #[inline]
    pub fn stress_rate(&self, d: [f64; 3]) -> [f64; 3] {
        let nu = self.poisson;
        let c = self.young / (1.0 - nu * nu);
        [
            c * (d[0] + nu * d[1]),
            c * (d[1] + nu * d[0]),
            c * (1.0 - nu) * d[2],
        ]
    }
}

/// The co-rotational frame of one element (Lian Eqs. 32–39).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Columns ê₁, ê₂, ê₃ (Lian Eq. 39: local → global is `q · v̂`).
    pub q: Matrix3<f64>,
    /// The element centre (mean of the corners).
    pub centre: V3,
}

/// The in-plane geometry of one element in its frame: local corner
/// coordinates, the one-point B matrix at ξ = η = 0 and the area.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalGeometry {
    /// Local coordinates (x̂, ŷ) of the four corners.
    pub xy: [[f64; 2]; 4],
    /// `b[0][k] = ∂N_k/∂x̂`, `b[1][k] = ∂N_k/∂ŷ` at the centre.
    pub b: [[f64; 4]; 2],
    /// Area of the projected quadrilateral (negative when inverted).
    pub area: f64,
}

/// The co-rotational frame of the quadrilateral with corners `p` (Lian Eqs.
/// 32–38); `None` when the corners are degenerate (χ × ψ or χ + ψ vanish).
pub fn frame(p: &[V3; 4]) -> Option<Frame> {
    // Lian Eqs. 32–33: χ = r21 + r34, ψ = r31 + r42.
    let chi = (p[1] - p[0]) + (p[2] - p[3]);
    let psi = (p[2] - p[0]) + (p[3] - p[1]);
    // Lian Eq. 34.
    let n = chi.cross(&psi);
    let nn = n.norm();
    // Lian Eq. 35.
    let s = chi + psi;
    let sn = s.norm();
    if !(nn > 0.0 && sn > 0.0 && nn.is_finite()) {
        return None;
    }
    let e3 = n / nn;
    let alpha = s / sn;
    // Lian Eq. 36 (α ⊥ ê₃, so |ê₃ × α| = 1 up to round-off).
    let beta = e3.cross(&alpha).normalize();
    // Lian Eqs. 37–38.
    let r = std::f64::consts::FRAC_1_SQRT_2;
    let e1 = (alpha - beta) * r;
    let e2 = (alpha + beta) * r;
    let centre = (p[0] + p[1] + p[2] + p[3]) * 0.25;
    Some(Frame {
        q: Matrix3::from_columns(&[e1, e2, e3]),
        centre,
    })
}

/// Local coordinates, B matrix and area of the corners `p` in frame `fr`
/// (the standard one-point bilinear quadrilateral, Belytschko et al.).
pub fn local_geometry(p: &[V3; 4], fr: &Frame) -> LocalGeometry {
    let e1 = fr.q.column(0);
    let e2 = fr.q.column(1);
    let xy: [[f64; 2]; 4] = std::array::from_fn(|k| {
        let r = p[k] - fr.centre;
        [e1.dot(&r), e2.dot(&r)]
    });
    let (x, y) = (
        [xy[0][0], xy[1][0], xy[2][0], xy[3][0]],
        [xy[0][1], xy[1][1], xy[2][1], xy[3][1]],
    );
    let area = 0.5 * ((x[2] - x[0]) * (y[3] - y[1]) + (x[1] - x[3]) * (y[2] - y[0]));
    let s = 0.5 / area;
    let b = [
        [
            s * (y[1] - y[3]),
            s * (y[2] - y[0]),
            s * (y[3] - y[1]),
            s * (y[0] - y[2]),
        ],
        [
            s * (x[3] - x[1]),
            s * (x[0] - x[2]),
            s * (x[1] - x[3]),
            s * (x[2] - x[0]),
        ],
    ];
    LocalGeometry { xy, b, area }
}

/// The Flanagan–Belytschko hourglass shape vector γ (Flanagan and
/// Belytschko 1981): γ = ¼ [h − (h·x̂) b₁ − (h·ŷ) b₂], which
/// is orthogonal to every linear field on the element.
pub fn hourglass_vector(g: &LocalGeometry) -> [f64; 4] {
    let hx: f64 = (0..4).map(|k| HOURGLASS[k] * g.xy[k][0]).sum();
    let hy: f64 = (0..4).map(|k| HOURGLASS[k] * g.xy[k][1]).sum();
    std::array::from_fn(|k| 0.25 * (HOURGLASS[k] - hx * g.b[0][k] - hy * g.b[1][k]))
}

/// The in-plane strain rate `[D̂xx, D̂yy, D̂xy]` at the centre from local
/// node velocities (Lian Eq. 40).
#[inline]
pub fn strain_rate(g: &LocalGeometry, vhat: &[V3; 4]) -> [f64; 3] {
    let mut d = [0.0; 3];
    for k in 0..4 {
        d[0] += g.b[0][k] * vhat[k][0];
        d[1] += g.b[1][k] * vhat[k][1];
        d[2] += 0.5 * (g.b[1][k] * vhat[k][0] + g.b[0][k] * vhat[k][1]);
    }
    d
}

/// What went wrong with an element.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ElementFailure {
    /// Area ≤ 0 in its own frame, or a degenerate frame.
    Collapsed,
    /// The normal turned by more than 90° in one step (the element folded
    /// through itself).
    Inverted,
    /// A non-finite position, velocity, stress or thickness.
    NotFinite,
}

impl std::fmt::Display for ElementFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ElementFailure::Collapsed => "area ≤ 0 (collapsed element)",
            ElementFailure::Inverted => "normal flipped in one step (inverted element)",
            ElementFailure::NotFinite => "non-finite position, velocity, stress or thickness",
        })
    }
}

/// A membrane element failed during a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("membrane element {element} at step {step}: {failure}")]
pub struct MembraneError {
    /// Element index (0-based, in mesh order).
    pub element: usize,
    /// The step that produced the state (completed steps before it).
    pub step: u64,
    /// What happened.
    pub failure: ElementFailure,
}

/// A membrane of Belytschko–Tsay quadrilaterals (struct of arrays).
#[derive(Debug, Clone)]
pub struct MembraneMesh {
    /// Material and element settings.
    pub material: MembraneMaterial,
    /// Uniform pressure on every element \[Pa\], along its current normal
    /// ê₃ (a follower load; ê₃ follows the corner order by the right-hand
    /// rule).
    pub pressure: f64,
    /// Body force per unit mass [m/s²].
    pub gravity: V3,
    /// Reference (initial) node positions.
    pub x0: Vec<V3>,
    /// Node positions x^n.
    pub x: Vec<V3>,
    /// Node velocities v^{n−½} (v^{n+½} after the trial update).
    pub v: Vec<V3>,
    /// Lumped node masses (¼ ρ t A of every element at a corner).
    pub mass: Vec<f64>,
    /// Fixed directions per node (x, y, z): held at zero velocity.
    pub fixed: Vec<[bool; 3]>,
    /// Applied node forces \[N\] (point loads; a contact may add its forces
    /// here before [`Self::trial_velocities`]).
    pub f_applied: Vec<V3>,
    /// Internal (stress + hourglass) node forces of the last
    /// [`Self::compute_forces`].
    pub f_int: Vec<V3>,
    /// External (pressure + gravity + applied) node forces of the last
    /// [`Self::compute_forces`].
    pub f_ext: Vec<V3>,
    /// Corner node ids, counter-clockwise about the normal.
    pub quads: Vec<[u32; 4]>,
    /// Current thickness t.
    pub thickness: Vec<f64>,
    /// Stress `[σ̂xx, σ̂yy, σ̂xy]` in the element's co-rotational frame.
    pub stress: Vec<[f64; 3]>,
    /// Element normal at x^n (failure check: it must not flip).
    pub normal: Vec<V3>,
    /// Stored (strain) energy of each element, accumulated ∫ V σ : D dt.
    pub strain_energy: Vec<f64>,
    /// Energy dissipated by each element's hourglass forces.
    pub hourglass_work: Vec<f64>,
    /// Work of the external forces on each node.
    pub external_work: Vec<f64>,
    /// Energy removed at each node by the mass-proportional damping.
    pub damping_work: Vec<f64>,
    /// Element-to-node gather lists: node `n`'s entries are
    /// `node_elems[node_start[n]..node_start[n + 1]]`, each `4 e + corner`.
    node_start: Vec<usize>,
    node_elems: Vec<u32>,
    /// Per-element corner forces (internal, external) of the last force
    /// computation (scratch).
    elem_force: Vec<[V3; 4]>,
    elem_ext: Vec<V3>,
    /// Velocities v^{n−½} kept by the trial update for the energy sums.
    v_old: Vec<V3>,
}

impl MembraneMesh {
    /// A mesh of nodes `x0` (at rest) and quads `quads` (node ids < `x0.len()`,
    /// every quad with positive area) of thickness `thickness`, with the
    /// uniform in-plane initial stress `prestress` = `[σxx, σyy, σxy]` in each
    /// element's frame (`[σ0, σ0, 0]` is an isotropic pretension).
    ///
    /// # Errors
    /// The first element with zero or negative area or a degenerate frame.
    pub fn new(
        x0: Vec<V3>,
        quads: Vec<[u32; 4]>,
        thickness: f64,
        material: MembraneMaterial,
        prestress: [f64; 3],
    ) -> Result<Self, MembraneError> {
        let nn = x0.len();
        let ne = quads.len();
        let mut mass = vec![0.0; nn];
        let mut normal = Vec::with_capacity(ne);
        for (e, q) in quads.iter().enumerate() {
            let p = corners(&x0, q);
            let fail = |failure| MembraneError {
                element: e,
                step: 0,
                failure,
            };
            let fr = frame(&p).ok_or(fail(ElementFailure::Collapsed))?;
            let g = local_geometry(&p, &fr);
            if g.area.is_nan() || g.area <= 0.0 {
                return Err(fail(ElementFailure::Collapsed));
            }
            // Lumped mass: a quarter of the element's mass to each corner.
            let m = 0.25 * material.density * thickness * g.area;
            for &n in q {
                mass[n as usize] += m;
            }
            normal.push(fr.q.column(2).into_owned());
        }
        let mut count = vec![0usize; nn + 1];
        for q in &quads {
            for &n in q {
                count[n as usize + 1] += 1;
            }
        }
        for i in 0..nn {
            count[i + 1] += count[i];
        }
        let node_start = count.clone();
        let mut node_elems = vec![0u32; node_start[nn]];
        let mut fill = count;
        for (e, q) in quads.iter().enumerate() {
            for (c, &n) in q.iter().enumerate() {
                node_elems[fill[n as usize]] = (4 * e + c) as u32;
                fill[n as usize] += 1;
            }
        }
        Ok(Self {
            material,
            pressure: 0.0,
            gravity: V3::zeros(),
            x: x0.clone(),
            v: vec![V3::zeros(); nn],
            mass,
            fixed: vec![[false; 3]; nn],
            f_applied: vec![V3::zeros(); nn],
            f_int: vec![V3::zeros(); nn],
            f_ext: vec![V3::zeros(); nn],
            thickness: vec![thickness; ne],
            stress: vec![prestress; ne],
            normal,
            strain_energy: vec![0.0; ne],
            hourglass_work: vec![0.0; ne],
            external_work: vec![0.0; nn],
            damping_work: vec![0.0; nn],
            node_start,
            node_elems,
            elem_force: vec![[V3::zeros(); 4]; ne],
            elem_ext: vec![V3::zeros(); ne],
            v_old: vec![V3::zeros(); nn],
            quads,
            x0,
        })
    }

    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.x.len()
    }

    /// Number of elements.
    pub fn num_elements(&self) -> usize {
        self.quads.len()
    }

    /// Sets the velocity of fixed directions to zero (after changing
    /// `fixed` or `v`).
    pub fn apply_fixed(&mut self) {
        for (v, f) in self.v.iter_mut().zip(&self.fixed) {
            for d in 0..3 {
                if f[d] {
                    v[d] = 0.0;
                }
            }
        }
    }

    /// The stable time step min L_e / c (Lian Eq. 48) with the plane-stress
    /// wave speed c and L_e = area / longest side (LS-DYNA's shell length
    /// with the default option), on the current geometry.
    pub fn stable_dt(&self) -> f64 {
        let le = self
            .quads
            .par_iter()
            .map(|q| self.characteristic_length(q))
            .reduce(|| f64::INFINITY, f64::min);
        le / self.material.wave_speed()
    }

    /// The element with the smallest limit of [`Self::stable_dt`] and that
    /// limit (`None` without elements); a serial pass, for the progress
    /// guard's message.
    pub fn limiting_element(&self) -> Option<(usize, f64)> {
        let c = self.material.wave_speed();
        let mut best: Option<(usize, f64)> = None;
        for (e, q) in self.quads.iter().enumerate() {
            let dt = self.characteristic_length(q) / c;
            // A NaN limit (a non-finite position) is the cause: first.
            if dt.is_nan() {
                return Some((e, dt));
            }
            if best.is_none_or(|(_, b)| dt < b) {
                best = Some((e, dt));
            }
        }
        best
    }

    /// Lian Eq. 48's length of quad `q`: its area over its longest side
    /// (infinite for a degenerate quad).
    fn characteristic_length(&self, q: &[u32; 4]) -> f64 {
        let p = corners(&self.x, q);
        let area = frame(&p)
            .map(|fr| local_geometry(&p, &fr).area)
            .unwrap_or(0.0);
        let longest = (0..4)
            .map(|k| (p[(k + 1) % 4] - p[k]).norm())
            .fold(0.0, f64::max);
        if area > 0.0 && longest > 0.0 {
            area / longest
        } else {
            f64::INFINITY
        }
    }

    /// Node forces at x^n: internal forces of the stored stress (Lian Eqs.
    /// 42–45), Flanagan–Belytschko viscous hourglass forces from v^{n−½},
    /// the follower pressure (¼ p A ê₃ per corner), gravity m g and the
    /// applied forces; written to `f_int` and `f_ext`. Also accumulates the
    /// hourglass dissipation over the step `dt` about to be taken.
    pub fn compute_forces(&mut self, dt: f64) {
        let mat = self.material;
        let c = mat.wave_speed();
        let pressure = self.pressure;
        let (x, v) = (&self.x, &self.v);
        self.elem_force
            .par_iter_mut()
            .zip(self.elem_ext.par_iter_mut())
            .zip(self.hourglass_work.par_iter_mut())
            .enumerate()
            .for_each(|(e, ((fe, fx), hw))| {
                let q = &self.quads[e];
                let p = corners(x, q);
                let Some(fr) = frame(&p) else {
                    *fe = [V3::zeros(); 4];
                    *fx = V3::zeros();
                    return;
                };
                let g = local_geometry(&p, &fr);
                let t = self.thickness[e];
                let vol = g.area * t;
                let s = self.stress[e];
                // Lian Eqs. 42–43: local internal forces.
                let mut fl = [V3::zeros(); 4];
                for k in 0..4 {
                    fl[k][0] = vol * (g.b[0][k] * s[0] + g.b[1][k] * s[2]);
                    fl[k][1] = vol * (g.b[1][k] * s[1] + g.b[0][k] * s[2]);
                }
                // Flanagan–Belytschko viscous hourglass control on all three
                // local directions (the out-of-plane checkerboard is a zero-
                // energy mode of a membrane too): q̇ᵢ = Σ γ_k v̂ᵢₖ,
                // f̂ᵢₖ = Qᵢ γ_k q̇ᵢ (resisting), Qᵢ = κ ρ cᵢ t √A with the
                // in-plane wave speed c for x̂, ŷ and the transverse one
                // c_T = √(max(½(σ̂xx + σ̂yy), 0)/ρ) for ẑ, which is what
                // resists out-of-plane motion in a membrane.
                if mat.hourglass > 0.0 {
                    let gam = hourglass_vector(&g);
                    let mut qdot = V3::zeros();
                    for k in 0..4 {
                        qdot += fr.q.tr_mul(&v[q[k] as usize]) * gam[k];
                    }
                    let base = mat.hourglass * mat.density * t * g.area.max(0.0).sqrt();
                    let ct = (0.5 * (s[0] + s[1])).max(0.0) / mat.density;
                    let qc = V3::new(base * c, base * c, base * ct.sqrt());
                    let fq = qc.component_mul(&qdot);
                    for k in 0..4 {
                        fl[k] += fq * gam[k];
                    }
                    *hw += dt * fq.dot(&qdot);
                }
                // Lian Eqs. 44–45: to global, internal force = −q f̂.
                for k in 0..4 {
                    fe[k] = -(fr.q * fl[k]);
                }
                // Follower pressure, split equally to the corners.
                *fx = fr.q.column(2) * (0.25 * pressure * g.area);
            });
        let (fe, fx) = (&self.elem_force, &self.elem_ext);
        let (starts, list) = (&self.node_start, &self.node_elems);
        let (mass, fa, grav) = (&self.mass, &self.f_applied, self.gravity);
        self.f_int
            .par_iter_mut()
            .zip(self.f_ext.par_iter_mut())
            .enumerate()
            .for_each(|(n, (fi, fo))| {
                let mut a = V3::zeros();
                let mut b = fa[n] + grav * mass[n];
                for &ec in &list[starts[n]..starts[n + 1]] {
                    let (e, c) = (ec as usize / 4, ec as usize % 4);
                    a += fe[e][c];
                    b += fx[e];
                }
                *fi = a;
                *fo = b;
            });
    }

    /// The trial velocities v^{n+½} = v^{n−½} + Δt (f_int + f_ext)/m (Lian
    /// Eq. 46), with mass-proportional damping α taken semi-implicitly
    /// (v^{n+½} = [(1 − αΔt/2) v^{n−½} + Δt f/m] / (1 + αΔt/2)) and fixed
    /// directions held at zero (Lian Sec. 6, step 3(d)).
    pub fn trial_velocities(&mut self, dt: f64) {
        let alpha = self.material.damping;
        let (a, b) = (1.0 - 0.5 * alpha * dt, 1.0 / (1.0 + 0.5 * alpha * dt));
        let (fi, fo, m, fixed) = (&self.f_int, &self.f_ext, &self.mass, &self.fixed);
        self.v
            .par_iter_mut()
            .zip(self.v_old.par_iter_mut())
            .enumerate()
            .for_each(|(n, (v, vo))| {
                *vo = *v;
                let mut w = (*v * a + (fi[n] + fo[n]) * (dt / m[n])) * b;
                for d in 0..3 {
                    if fixed[n][d] {
                        w[d] = 0.0;
                    }
                }
                *v = w;
            });
    }

    /// x^{n+1} = x^n + Δt v^{n+½} (Lian Eq. 47), and the work of the
    /// external forces and of the damping over the step (with the
    /// mid-step velocity ½(v^{n−½} + v^{n+½}), which a contact correction
    /// of `v` is part of).
    pub fn update_positions(&mut self, dt: f64) {
        let alpha = self.material.damping;
        let (fo, m, vo) = (&self.f_ext, &self.mass, &self.v_old);
        self.x
            .par_iter_mut()
            .zip(self.v.par_iter())
            .zip(self.external_work.par_iter_mut())
            .zip(self.damping_work.par_iter_mut())
            .enumerate()
            .for_each(|(n, (((x, v), we), wd))| {
                let vm = (vo[n] + v) * 0.5;
                *we += dt * fo[n].dot(&vm);
                *wd += dt * alpha * m[n] * vm.norm_squared();
                *x += v * dt;
            });
    }

    /// The stress update of the step just taken: the strain rate of
    /// v^{n+½} (Lian Eqs. 40–41) on the mid-step geometry
    /// x^{n+½} = x^{n+1} − ½Δt v^{n+½}, σ̂ += C : D̂ Δt in the co-rotational
    /// frame (plane stress), thickness t ← t exp(ε̇zz Δt) with
    /// ε̇zz = −ν/(1−ν)(D̂xx + D̂yy), and the stored energy
    /// ΔU = V ½(σ̂ⁿ + σ̂ⁿ⁺¹) : D̂ Δt. Then the checks on x^{n+1}: area > 0,
    /// the normal not flipped, everything finite.
    ///
    /// # Errors
    /// The lowest-numbered failing element, with `step`.
    pub fn update_stress(&mut self, dt: f64, step: u64) -> Result<(), MembraneError> {
        let mat = self.material;
        let nu = mat.poisson;
        let (x, v) = (&self.x, &self.v);
        let failure = self
            .stress
            .par_iter_mut()
            .zip(self.thickness.par_iter_mut())
            .zip(self.normal.par_iter_mut())
            .zip(self.strain_energy.par_iter_mut())
            .enumerate()
            .map(|(e, (((s, t), nrm), u))| {
                let q = &self.quads[e];
                let p1 = corners(x, q);
                let vq: [V3; 4] = std::array::from_fn(|k| v[q[k] as usize]);
                let finite = |a: &[V3; 4]| a.iter().all(|c| c.iter().all(|x| x.is_finite()));
                if !(finite(&p1) && finite(&vq)) {
                    return Some(ElementFailure::NotFinite);
                }
                let pm: [V3; 4] = std::array::from_fn(|k| p1[k] - vq[k] * (0.5 * dt));
                let Some(fm) = frame(&pm) else {
                    return Some(ElementFailure::Collapsed);
                };
                let gm = local_geometry(&pm, &fm);
                // Lian Eq. 41: local velocities.
                let vhat: [V3; 4] = std::array::from_fn(|k| fm.q.tr_mul(&vq[k]));
                let d = strain_rate(&gm, &vhat);
                let rate = mat.stress_rate(d);
                let s_new = [
                    s[0] + rate[0] * dt,
                    s[1] + rate[1] * dt,
                    s[2] + rate[2] * dt,
                ];
                let t_mid = *t;
                *t *= (-nu / (1.0 - nu) * (d[0] + d[1]) * dt).exp();
                let vol = gm.area * 0.5 * (t_mid + *t);
                *u += vol
                    * dt
                    * (0.5 * (s[0] + s_new[0]) * d[0]
                        + 0.5 * (s[1] + s_new[1]) * d[1]
                        + (s[2] + s_new[2]) * d[2]);
                *s = s_new;
                if !(s.iter().all(|c| c.is_finite()) && t.is_finite()) {
                    return Some(ElementFailure::NotFinite);
                }
                let Some(f1) = frame(&p1) else {
                    return Some(ElementFailure::Collapsed);
                };
                let a1 = local_geometry(&p1, &f1).area;
                if a1.is_nan() || a1 <= 0.0 {
                    return Some(ElementFailure::Collapsed);
                }
                let n1 = f1.q.column(2).into_owned();
                if n1.dot(nrm) <= 0.0 {
                    return Some(ElementFailure::Inverted);
                }
                *nrm = n1;
                None
            })
            .enumerate()
            .find_first(|(_, f)| f.is_some());
        match failure {
            Some((element, Some(failure))) => Err(MembraneError {
                element,
                step,
                failure,
            }),
            _ => Ok(()),
        }
    }

    /// One whole explicit step of a membrane on its own: forces, trial
    /// velocities, positions, stress.
    ///
    /// # Errors
    /// As [`Self::update_stress`].
    pub fn step(&mut self, dt: f64, step: u64) -> Result<(), MembraneError> {
        self.compute_forces(dt);
        self.trial_velocities(dt);
        self.update_positions(dt);
        self.update_stress(dt, step)
    }

    /// Σ ½ m |v|² (with v at the half step).
    pub fn kinetic_energy(&self) -> f64 {
        crate::mpm::particles::kinetic_energy(&self.mass, &self.v)
    }

    /// The work a correction of this step's velocities did on the nodes,
    /// from the trial velocities `trial` (Lian Eq. 46) to the present ones:
    /// `Σ m (v − v̄)·(v^{n−½} + v)/2`, with the mid-step velocity the
    /// external work and the positions use ([`Self::update_positions`]),
    /// so that it closes the membrane's own energy account.
    pub fn correction_work(&self, trial: &[V3]) -> f64 {
        (0..self.v.len())
            .map(|n| self.mass[n] * (self.v[n] - trial[n]).dot(&(self.v_old[n] + self.v[n])) * 0.5)
            .sum()
    }

    /// Stored (strain) energy Σ_e U_e, measured from the initial state.
    pub fn strain_energy_total(&self) -> f64 {
        self.strain_energy.iter().sum()
    }

    /// Energy dissipated by the hourglass forces so far.
    pub fn hourglass_energy(&self) -> f64 {
        self.hourglass_work.iter().sum()
    }

    /// Work of the external forces so far.
    pub fn external_work_total(&self) -> f64 {
        self.external_work.iter().sum()
    }

    /// Energy removed by mass-proportional damping so far.
    pub fn damping_energy(&self) -> f64 {
        self.damping_work.iter().sum()
    }

    /// Σ m v.
    pub fn momentum(&self) -> V3 {
        self.mass
            .iter()
            .zip(&self.v)
            .fold(V3::zeros(), |p, (m, v)| p + v * *m)
    }

    /// Total mass.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// The element stress as a global 3×3 tensor q σ̂ qᵀ (σ̂ in the current
    /// frame, zero through the thickness).
    pub fn stress_global(&self, e: usize) -> Matrix3<f64> {
        let p = corners(&self.x, &self.quads[e]);
        let s = self.stress[e];
        let sl = Matrix3::new(s[0], s[2], 0.0, s[2], s[1], 0.0, 0.0, 0.0, 0.0);
        match frame(&p) {
            Some(fr) => fr.q * sl * fr.q.transpose(),
            None => Matrix3::from_element(f64::NAN),
        }
    }

    /// The element's in-plane Green–Lagrange strain E = ½(F̂ᵀF̂ − I) at the
    /// centre, with F̂ = ∂x̂/∂X̂ the one-point gradient from the reference
    /// local geometry (frame of `x0`) to the current one (frame of `x`),
    /// returned as a global 3×3 tensor in the reference frame's axes.
    pub fn green_strain(&self, e: usize) -> Matrix3<f64> {
        let q = &self.quads[e];
        let (p0, p1) = (corners(&self.x0, q), corners(&self.x, q));
        let (Some(f0), Some(f1)) = (frame(&p0), frame(&p1)) else {
            return Matrix3::from_element(f64::NAN);
        };
        let (g0, g1) = (local_geometry(&p0, &f0), local_geometry(&p1, &f1));
        let mut f = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                f[i][j] = (0..4).map(|k| g1.xy[k][i] * g0.b[j][k]).sum();
            }
        }
        let c = |a: usize, b: usize| f[0][a] * f[0][b] + f[1][a] * f[1][b];
        let el = Matrix3::new(
            0.5 * (c(0, 0) - 1.0),
            0.5 * c(0, 1),
            0.0,
            0.5 * c(1, 0),
            0.5 * (c(1, 1) - 1.0),
            0.0,
            0.0,
            0.0,
            0.0,
        );
        f0.q * el * f0.q.transpose()
    }
}

/// The four corner positions of quad `q`.
#[inline]
pub fn corners(x: &[V3], q: &[u32; 4]) -> [V3; 4] {
    std::array::from_fn(|k| x[q[k] as usize])
}
