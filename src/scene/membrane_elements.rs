//! Scene keys of Lian's membrane finite elements (`[[membrane_elements]]`),
//! their validation (key paths named) and building the meshes.

use serde::{Deserialize, Serialize};

use crate::error::SceneError;
use crate::membrane::element::{MembraneMaterial, MembraneMesh, V3};
use crate::membrane::quad_mesh::{self, boundary_nodes, QuadMesh};

/// One membrane of Belytschko–Tsay quadrilaterals (Lian Sec. 4): its mesh,
/// material, loads, initial state and fixed nodes.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MembraneElementsSpec {
    /// Name in outputs and error messages.
    pub name: String,
    /// The mesh.
    pub mesh: MeshSpec,
    /// Thickness t > 0 \[m\].
    pub thickness: f64,
    /// Density ρ > 0 [kg/m³].
    pub density: f64,
    /// Young's modulus E > 0 \[Pa\].
    pub young: f64,
    /// Poisson's ratio, 0 ≤ ν < 0.5.
    pub poisson: f64,
    /// Flanagan–Belytschko viscous hourglass coefficient κ ≥ 0.
    #[serde(default = "default_hourglass")]
    pub hourglass: f64,
    /// Mass-proportional damping α ≥ 0 [1/s] (dynamic relaxation).
    #[serde(default)]
    pub damping: f64,
    /// Uniform pressure \[Pa\] along each element's normal (follower load).
    #[serde(default)]
    pub pressure: f64,
    /// Initial in-plane stress `[σxx, σyy, σxy]` \[Pa\] in each element's
    /// frame (`[σ0, σ0, 0]`: isotropic pretension σ0).
    #[serde(default)]
    pub prestress: [f64; 3],
    /// Uniform initial velocity [m/s].
    #[serde(default)]
    pub velocity: [f64; 3],
    /// An initial velocity sin(m π ξ) sin(n π η) along `direction`
    /// (rectangle meshes, ξ, η the edge parameters), added to `velocity`.
    #[serde(default)]
    pub velocity_mode: Option<VelocityModeSpec>,
    /// Fixed node directions.
    #[serde(default)]
    pub fix: Vec<FixSpec>,
    /// Point loads: a total force shared equally by the selected nodes.
    #[serde(default)]
    pub loads: Vec<LoadSpec>,
}

fn default_hourglass() -> f64 {
    0.1
}

/// Where the mesh comes from (exactly one key).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum MeshSpec {
    /// A structured rectangle: nodes at corner + (i/na) edge_a + (j/nb)
    /// edge_b, normal edge_a × edge_b.
    Rectangle {
        /// A corner \[m\].
        corner: [f64; 3],
        /// First edge vector \[m\].
        edge_a: [f64; 3],
        /// Second edge vector \[m\].
        edge_b: [f64; 3],
        /// Elements along edge_a and edge_b.
        cells: [usize; 2],
    },
    /// A disc in the plane z = centre.z (normal +z), `cells × cells`
    /// elements (even), butterfly layout.
    Disc {
        /// Centre \[m\].
        centre: [f64; 3],
        /// Radius \[m\].
        radius: f64,
        /// Elements across the diameter (even, ≥ 2).
        cells: usize,
    },
    /// A mesh file (`node ID X Y Z`, `quad ID N1 N2 N3 N4`), the path as
    /// given (relative to the working directory).
    File(String),
}

/// An initial velocity mode on a rectangle mesh.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VelocityModeSpec {
    /// Peak speed [m/s].
    pub amplitude: f64,
    /// Half-waves (m, n) along edge_a and edge_b (≥ 1).
    pub modes: [u32; 2],
    /// Direction (normalised), default the normal edge_a × edge_b.
    #[serde(default)]
    pub direction: Option<[f64; 3]>,
}

/// Selected nodes: exactly one of `boundary = true` (nodes on edges used
/// by one element only) or `box`.
#[derive(Debug, Clone, Copy)]
struct NodeSelector<'a> {
    boundary: bool,
    bounds: Option<&'a BoxSelector>,
}

impl FixSpec {
    fn nodes(&self) -> NodeSelector<'_> {
        NodeSelector {
            boundary: self.boundary,
            bounds: self.bounds.as_ref(),
        }
    }
}

impl LoadSpec {
    fn nodes(&self) -> NodeSelector<'_> {
        NodeSelector {
            boundary: self.boundary,
            bounds: self.bounds.as_ref(),
        }
    }
}

/// An axis-aligned box.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSelector {
    /// Lower corner \[m\].
    pub lower: [f64; 3],
    /// Upper corner \[m\].
    pub upper: [f64; 3],
}

/// Fixed directions of selected nodes (`boundary = true` or `box`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FixSpec {
    /// The mesh's free boundary.
    #[serde(default)]
    pub boundary: bool,
    /// Nodes inside an axis-aligned box (bounds included).
    #[serde(default, rename = "box")]
    pub bounds: Option<BoxSelector>,
    /// Directions held, any of "x", "y", "z" (default all three).
    #[serde(default = "all_dofs")]
    pub dofs: Vec<String>,
}

fn all_dofs() -> Vec<String> {
    vec!["x".into(), "y".into(), "z".into()]
}

/// A point load on selected nodes (`boundary = true` or `box`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// The mesh's free boundary.
    #[serde(default)]
    pub boundary: bool,
    /// Nodes inside an axis-aligned box (bounds included).
    #[serde(default, rename = "box")]
    pub bounds: Option<BoxSelector>,
    /// Total force \[N\], shared equally.
    pub force: [f64; 3],
}

/// Meshes of up to this many elements are built while validating (their
/// node selections checked at parse time); larger ones when the run is
/// built, after the memory guard.
const VALIDATE_MESH_ELEMENTS: f64 = 1e6;

fn err(path: impl Into<String>, msg: impl Into<String>) -> SceneError {
    SceneError::new(path, msg)
}

fn positive(path: &str, v: f64) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(err(path, format!("must be a finite number > 0 (got {v})")))
    }
}

fn finite3(path: &str, v: &[f64; 3]) -> Result<(), SceneError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(err(format!("{path}[{i}]"), "must be finite")),
        None => Ok(()),
    }
}

fn non_negative(path: &str, v: f64) -> Result<(), SceneError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(err(path, format!("must be a finite number ≥ 0 (got {v})")))
    }
}

impl NodeSelector<'_> {
    fn validate(&self, path: &str) -> Result<(), SceneError> {
        match (self.bounds, self.boundary) {
            (Some(b), false) => {
                finite3(&format!("{path}.box.lower"), &b.lower)?;
                finite3(&format!("{path}.box.upper"), &b.upper)?;
                for d in 0..3 {
                    if b.upper[d] < b.lower[d] {
                        return Err(err(
                            format!("{path}.box.upper[{d}]"),
                            format!("must be ≥ box.lower[{d}] = {}", b.lower[d]),
                        ));
                    }
                }
                Ok(())
            }
            (None, true) => Ok(()),
            _ => Err(err(
                path,
                "select nodes by exactly one of: boundary = true, box = { lower, upper }",
            )),
        }
    }

    /// The selected nodes of `mesh`.
    fn select(&self, mesh: &QuadMesh, edge: &[bool]) -> Vec<usize> {
        (0..mesh.nodes.len())
            .filter(|&n| match self.bounds {
                Some(b) => (0..3).all(|d| {
                    let x = mesh.nodes[n][d];
                    x >= b.lower[d] && x <= b.upper[d]
                }),
                None => edge[n],
            })
            .collect()
    }
}

impl MembraneElementsSpec {
    /// Checks the keys of `membrane_elements[i]` (reading a mesh file).
    ///
    /// # Errors
    /// The key path and the allowed values.
    pub fn validate(&self, i: usize) -> Result<(), SceneError> {
        let p = |k: &str| format!("membrane_elements[{i}].{k}");
        if self.name.trim().is_empty() {
            return Err(err(p("name"), "must not be empty"));
        }
        positive(&p("thickness"), self.thickness)?;
        positive(&p("density"), self.density)?;
        positive(&p("young"), self.young)?;
        if !(self.poisson.is_finite() && (0.0..0.5).contains(&self.poisson)) {
            return Err(err(
                p("poisson"),
                format!("must satisfy 0 ≤ ν < 0.5 (got {})", self.poisson),
            ));
        }
        non_negative(&p("hourglass"), self.hourglass)?;
        non_negative(&p("damping"), self.damping)?;
        if !self.pressure.is_finite() {
            return Err(err(p("pressure"), "must be finite"));
        }
        finite3(&p("prestress"), &self.prestress)?;
        finite3(&p("velocity"), &self.velocity)?;
        for (k, f) in self.fix.iter().enumerate() {
            let fp = p(&format!("fix[{k}]"));
            f.nodes().validate(&fp)?;
            if f.dofs.is_empty() {
                return Err(err(
                    format!("{fp}.dofs"),
                    "must name at least one of: x, y, z",
                ));
            }
            for (j, d) in f.dofs.iter().enumerate() {
                if !["x", "y", "z"].contains(&d.as_str()) {
                    return Err(err(
                        format!("{fp}.dofs[{j}]"),
                        format!("`{d}` is not a direction; allowed: x, y, z"),
                    ));
                }
            }
        }
        for (k, l) in self.loads.iter().enumerate() {
            let lp = p(&format!("loads[{k}]"));
            l.nodes().validate(&lp)?;
            finite3(&format!("{lp}.force"), &l.force)?;
        }
        // A mesh too large to build while parsing (before the memory
        // guard) has its node selections checked when it is built.
        let small = self.elements() <= VALIDATE_MESH_ELEMENTS;
        let mesh = self.mesh_geometry(i, small)?;
        if let Some(vm) = &self.velocity_mode {
            let vp = p("velocity_mode");
            if !matches!(self.mesh, MeshSpec::Rectangle { .. }) {
                return Err(err(vp, "only for mesh = { rectangle = … }"));
            }
            if !vm.amplitude.is_finite() {
                return Err(err(format!("{vp}.amplitude"), "must be finite"));
            }
            if vm.modes.contains(&0) {
                return Err(err(format!("{vp}.modes"), "must be ≥ 1 each"));
            }
            if let Some(d) = vm.direction {
                finite3(&format!("{vp}.direction"), &d)?;
                if V3::from(d).norm() == 0.0 {
                    return Err(err(format!("{vp}.direction"), "must not be zero"));
                }
            }
        }
        if let Some(mesh) = mesh {
            let edge = boundary_nodes(mesh.nodes.len(), &mesh.quads);
            self.check_selections(i, &mesh, &edge)?;
        }
        Ok(())
    }

    /// Every `fix` and `loads` entry selects a node of the mesh.
    fn check_selections(&self, i: usize, mesh: &QuadMesh, edge: &[bool]) -> Result<(), SceneError> {
        let p = |k: &str| format!("membrane_elements[{i}].{k}");
        for (k, f) in self.fix.iter().enumerate() {
            if f.nodes().select(mesh, edge).is_empty() {
                return Err(err(p(&format!("fix[{k}]")), "selects no node of the mesh"));
            }
        }
        for (k, l) in self.loads.iter().enumerate() {
            if l.nodes().select(mesh, edge).is_empty() {
                return Err(err(
                    p(&format!("loads[{k}]")),
                    "selects no node of the mesh",
                ));
            }
        }
        Ok(())
    }

    /// Elements of the mesh: from its parameters, or for a mesh file an
    /// upper bound from its size (a quad line takes at least 16 bytes).
    pub fn elements(&self) -> f64 {
        match &self.mesh {
            MeshSpec::Rectangle { cells, .. } => cells[0] as f64 * cells[1] as f64,
            MeshSpec::Disc { cells, .. } => *cells as f64 * *cells as f64,
            MeshSpec::File(path) => std::fs::metadata(path).map_or(0.0, |m| m.len() as f64 / 16.0),
        }
    }

    /// The mesh's nodes and quads (validated); without `build` only its
    /// parameters are checked (`None`; a mesh file is read either way).
    fn mesh_geometry(&self, i: usize, build: bool) -> Result<Option<QuadMesh>, SceneError> {
        let p = |k: &str| format!("membrane_elements[{i}].mesh.{k}");
        let mesh = match &self.mesh {
            MeshSpec::Rectangle {
                corner,
                edge_a,
                edge_b,
                cells,
            } => {
                finite3(&p("rectangle.corner"), corner)?;
                finite3(&p("rectangle.edge_a"), edge_a)?;
                finite3(&p("rectangle.edge_b"), edge_b)?;
                for (d, &c) in cells.iter().enumerate() {
                    if !(1..=1 << 14).contains(&c) {
                        return Err(err(
                            p(&format!("rectangle.cells[{d}]")),
                            format!("must be 1 … 16384 (got {c})"),
                        ));
                    }
                }
                let (a, b) = (V3::from(*edge_a), V3::from(*edge_b));
                if a.cross(&b).norm() <= 1e-12 * a.norm() * b.norm() {
                    return Err(err(
                        p("rectangle.edge_b"),
                        "must not be zero or parallel to edge_a",
                    ));
                }
                if !build {
                    return Ok(None);
                }
                quad_mesh::rectangle(V3::from(*corner), a, b, cells[0], cells[1])
            }
            MeshSpec::Disc {
                centre,
                radius,
                cells,
            } => {
                finite3(&p("disc.centre"), centre)?;
                positive(&p("disc.radius"), *radius)?;
                if *cells < 2 || cells % 2 != 0 || *cells > 1 << 14 {
                    return Err(err(
                        p("disc.cells"),
                        format!("must be even, 2 … 16384 (got {cells})"),
                    ));
                }
                if !build {
                    return Ok(None);
                }
                quad_mesh::disc(V3::from(*centre), *radius, *cells)
            }
            MeshSpec::File(path) => {
                let text = std::fs::read_to_string(path)
                    .map_err(|e| err(p("file"), format!("cannot read `{path}`: {e}")))?;
                quad_mesh::parse_mesh_file(&text)
                    .map_err(|e| err(p("file"), format!("`{path}` {e}")))?
            }
        };
        if let Some((e, msg)) = quad_mesh::check_quads(&mesh) {
            return Err(err(
                format!("membrane_elements[{i}].mesh"),
                format!("element {e}: {msg}"),
            ));
        }
        Ok(Some(mesh))
    }

    /// Builds the mesh with its material, loads, initial state and fixed
    /// nodes; `gravity` per unit mass.
    ///
    /// # Errors
    /// As [`Self::validate`].
    pub fn build(&self, i: usize, gravity: V3) -> Result<MembraneMesh, SceneError> {
        let Some(mesh) = self.mesh_geometry(i, true)? else {
            return Err(err(format!("membrane_elements[{i}].mesh"), "not built"));
        };
        let edge = boundary_nodes(mesh.nodes.len(), &mesh.quads);
        self.check_selections(i, &mesh, &edge)?;
        let material = MembraneMaterial {
            density: self.density,
            young: self.young,
            poisson: self.poisson,
            hourglass: self.hourglass,
            damping: self.damping,
        };
        let mut m = MembraneMesh::new(
            mesh.nodes.clone(),
            mesh.quads.clone(),
            self.thickness,
            material,
            self.prestress,
        )
        .map_err(|e| {
            err(
                format!("membrane_elements[{i}].mesh"),
                format!("element {}: {}", e.element, e.failure),
            )
        })?;
        m.pressure = self.pressure;
        m.gravity = gravity;
        let v0 = V3::from(self.velocity);
        for v in m.v.iter_mut() {
            *v = v0;
        }
        if let (Some(vm), MeshSpec::Rectangle { edge_a, edge_b, .. }) =
            (&self.velocity_mode, &self.mesh)
        {
            let dir = match vm.direction {
                Some(d) => V3::from(d).normalize(),
                None => V3::from(*edge_a).cross(&V3::from(*edge_b)).normalize(),
            };
            let pi = std::f64::consts::PI;
            for (v, s) in m.v.iter_mut().zip(&mesh.params) {
                let shape =
                    (pi * vm.modes[0] as f64 * s[0]).sin() * (pi * vm.modes[1] as f64 * s[1]).sin();
                *v += dir * (vm.amplitude * shape);
            }
        }
        for f in &self.fix {
            let dofs: [bool; 3] =
                std::array::from_fn(|d| f.dofs.iter().any(|s| s == ["x", "y", "z"][d]));
            for n in f.nodes().select(&mesh, &edge) {
                for d in 0..3 {
                    m.fixed[n][d] |= dofs[d];
                }
            }
        }
        for l in &self.loads {
            let nodes = l.nodes().select(&mesh, &edge);
            let share = V3::from(l.force) / nodes.len() as f64;
            for n in nodes {
                m.f_applied[n] += share;
            }
        }
        m.apply_fixed();
        Ok(m)
    }
}
