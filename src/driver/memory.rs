//! The memory a scene needs, estimated from the scene alone before anything
//! is allocated: grid nodes × particle fields × node fields, particles ×
//! particle fields, cells × fluid materials × cell fields, and the solver
//! workspace. `check` and `run` print it and refuse a scene that needs more
//! than the machine has (unless told to go on), naming the keys that drive
//! it, so that no scene reaches the OOM killer or an allocation abort.

use crate::error::SceneError;
use crate::scene::{Geometry, LastGood, MaterialKind, Mode, Scene, LAST_GOOD_MEMORY_LIMIT};

/// Bytes of one f64.
const F64: f64 = 8.0;

/// A scene's estimated memory, by part.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MemoryEstimate {
    /// Grid cells (`Π grid.cells`).
    pub cells: f64,
    /// Particles, estimated per object from its bounding box and
    /// `particles_per_cell` (an upper bound for a filled body).
    pub particles: f64,
    /// Particles of each object (`objects[i]`).
    pub object_particles: Vec<f64>,
    /// Bytes of the MPM grid (node fields of every particle field).
    pub grid_bytes: f64,
    /// Bytes of the particles and their per-step scratch.
    pub particle_bytes: f64,
    /// Bytes of the cell-centred fluid state, its step workspace and the
    /// pressure solver (semi-implicit).
    pub cell_bytes: f64,
    /// Membrane finite elements of each mesh (`membrane_elements[i]`).
    pub mesh_elements: Vec<f64>,
    /// Bytes of the membrane element meshes (nodes, elements, their
    /// frames and forces).
    pub element_bytes: f64,
    /// Bytes the run keeps besides: the last good state (a copy of the
    /// particle and cell state), the snapshot fields and, in implicit mode,
    /// the Newton matrix and its factor.
    pub run_bytes: f64,
}

impl MemoryEstimate {
    /// Total bytes.
    pub fn total(&self) -> f64 {
        self.grid_bytes
            + self.particle_bytes
            + self.cell_bytes
            + self.element_bytes
            + self.run_bytes
    }

    /// The estimate of `scene` (validated; a scene of membrane elements
    /// only has no grid and counts nothing here).
    pub fn of(scene: &Scene) -> Self {
        // A quad element and its node: coordinates, velocities, forces,
        // frames, stresses and the snapshot and last good copies.
        let mesh_elements: Vec<f64> = scene
            .membrane_elements
            .iter()
            .map(|m| m.elements())
            .collect();
        let element_bytes = mesh_elements.iter().fold(0.0, |a, n| a + n * F64 * 120.0);
        let g = &scene.grid;
        let dim = g.dim;
        if dim == 0 || g.cells.len() != dim {
            return Self {
                mesh_elements,
                element_bytes,
                ..Self::default()
            };
        }
        let dimf = dim as f64;
        let cells: f64 = g.cells.iter().map(|&n| n as f64).product();
        // Ghost layers and the node lattice: one more per direction, two
        // ghosts per side for the fluid.
        let nodes: f64 = g.cells.iter().map(|&n| n as f64 + 1.0).product();
        let padded: f64 = g.cells.iter().map(|&n| n as f64 + 4.0).product();
        let on_particles = |k: MaterialKind| {
            scene
                .materials
                .iter()
                .filter(|m| m.kind == k && m.on_particles())
                .count()
        };
        let fluids = scene.materials.iter().filter(|m| m.in_cells()).count() as f64;
        let solids = on_particles(MaterialKind::Solid) as f64;
        let particle_fields = if fluids > 0.0 { solids.max(1.0) } else { 1.0 };
        let has_particles = scene.materials.iter().any(|m| m.on_particles());
        let mut object_particles = Vec::with_capacity(scene.objects.len());
        for o in &scene.objects {
            object_particles.push(object_particles_of(scene, o));
        }
        let particles = object_particles.iter().fold(0.0, |a, b| a + b);
        // Node fields: mass, momentum, velocity, new velocity, the force
        // that the grid solve turns into the acceleration (one array),
        // normals and scratch; gas points reading the grid's
        // density add their nodal mass, density and the nodes' volumes.
        let grid_density = scene
            .materials
            .iter()
            .any(|m| m.point_density == Some(crate::material::PointDensity::Grid));
        let density_fields = if grid_density { 3.0 } else { 0.0 };
        let grid_bytes = if has_particles {
            particle_fields * nodes * F64 * (4.0 + 5.0 * dimf + density_fields)
        } else {
            0.0
        };
        // One particle's arrays: F (3, 5 or 9 stored entries in 1D, 2D,
        // 3D) and the symmetric σ (3, 4 or 6), 3 vectors, 6 scalars (work,
        // temperature and plastic strain counted whether a run tracks them
        // or not; the id is stored only once particles are removed or
        // split, not counted), a 4-byte half-size index and a 2-byte
        // material index.
        let tensors = match dim {
            1 => 6.0,
            2 => 9.0,
            _ => 15.0,
        };
        let state = tensors + 3.0 * dimf + 6.75;
        // The arrays and the step's scratch (offsets and half-widths: two
        // vectors; the bins: a 4-byte index); in implicit mode also the weights,
        // gradients, node indices and signs of the 3^dim support nodes and
        // the Newton step's per-particle F increment, stress and J.
        let mut per_particle = state + 2.0 * dimf + 0.5;
        if scene.time.mode == Mode::Implicit {
            per_particle += 3f64.powi(dim as i32) * (2.0 + 2.0 * dimf) + 2.0 * 9.0 + 1.0;
        }
        let particle_bytes = particles * F64 * per_particle;
        // Per material: mass, velocity, temperature, specific volume,
        // volume fraction, their Lagrangian and advected copies and face
        // values; per cell: pressures, the exchange and pressure-solver
        // rows (a stencil of 2D + 1 and Krylov/multigrid vectors).
        let materials_in_cells = if fluids > 0.0 { fluids + solids } else { 0.0 };
        let mut per_cell = materials_in_cells * F64 * (24.0 + 8.0 * dimf);
        if materials_in_cells > 0.0 {
            per_cell += F64 * 24.0;
            if scene.time.mode == Mode::SemiImplicit {
                per_cell += F64 * (4.0 * (2.0 * dimf + 1.0) + 16.0);
            }
        }
        let cell_bytes = padded * per_cell;
        // The last good state: the particle arrays (the material index as a
        // u64) and per material and cell its state. The snapshot reads the
        // particle fields in place; a run of several solid fields or phases
        // joins them into one copy first (the arrays and about 36 field
        // values); cells: about 12 values a material and cell.
        // The copy is on disk, and not counted, without the watchdog, with
        // `time.last_good = "disk"`, and with `"auto"` above
        // [`LAST_GOOD_MEMORY_LIMIT`].
        let joined = scene.multiphase.is_some() || (fluids > 0.0 && solids > 1.0);
        let snapshot = if joined { state + 36.0 } else { 0.0 };
        let last_good = particles * F64 * (state + 0.75)
            + padded * materials_in_cells * F64 * (6.0 + dimf + 12.0);
        let in_memory = scene.time.watchdog_interval > 0
            && match scene.time.last_good {
                LastGood::Memory => true,
                LastGood::Disk => false,
                LastGood::Auto => last_good <= LAST_GOOD_MEMORY_LIMIT as f64,
            };
        let mut run_bytes = particles * F64 * snapshot + if in_memory { last_good } else { 0.0 };
        if scene.time.mode == Mode::Implicit {
            // Rows of the Newton matrix: dim DOFs a node, coupled to the 5^dim
            // nodes of two overlapping quadratic supports; matrix, triplets,
            // factor fill-in and solver vectors (measured: about 4 KiB a DOF
            // for the 2D cylinder of Guilkey 4.1).
            let nnz_row = 5f64.powi(dim as i32) * dimf;
            run_bytes += nodes * dimf * nnz_row * 16.0 * 5.0;
        }
        Self {
            cells,
            particles,
            object_particles,
            grid_bytes,
            particle_bytes,
            cell_bytes,
            mesh_elements,
            element_bytes,
            run_bytes,
        }
    }

    /// The object with the most particles, `objects[i] (N particles)`.
    fn largest_object(&self) -> Option<String> {
        self.object_particles
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(i, n)| format!("objects[{i}] ({n:.3e} particles)"))
    }

    /// One line: the total and its parts, e.g. for `check`.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:.3e} cells: grid {}, fluid cells {}; {:.3e} particles: {}; {:.3e} \
             membrane elements: {}; last good state, snapshot and solver: {})",
            bytes(self.total()),
            self.cells,
            bytes(self.grid_bytes),
            bytes(self.cell_bytes),
            self.particles,
            bytes(self.particle_bytes),
            self.mesh_elements.iter().fold(0.0, |a, b| a + b),
            bytes(self.element_bytes),
            bytes(self.run_bytes)
        )
    }
}

/// Particles of object `o`: its bounding box (clipped to the grid) in
/// cells times `particles_per_cell^dim`; a membrane's points along its
/// polyline at its spacing.
fn object_particles_of(scene: &Scene, o: &crate::scene::ObjectSpec) -> f64 {
    let g = &scene.grid;
    let dim = g.dim;
    let membrane = scene
        .materials
        .iter()
        .any(|m| m.name == o.material && m.kind == MaterialKind::Membrane);
    let h: Vec<f64> = (0..dim)
        .map(|d| (g.upper[d] - g.lower[d]) / g.cells[d] as f64)
        .collect();
    if membrane {
        let spacing = o
            .spacing
            .unwrap_or_else(|| h.iter().cloned().fold(f64::INFINITY, f64::min));
        let length = match &o.geometry {
            Geometry::Polyline { vertices, .. } | Geometry::Polygon { vertices } => vertices
                .windows(2)
                .map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt())
                .sum::<f64>(),
            Geometry::Circle { radius, .. } => std::f64::consts::TAU * radius,
            _ => 0.0,
        };
        return (length / spacing).ceil() + 2.0;
    }
    let ppc = o.particles_per_cell.unwrap_or(scene.mpm.particles_per_cell) as f64;
    let (lo, hi) = o.geometry.bounds(dim);
    let mut n = 1.0;
    for d in 0..dim {
        let a = lo[d].max(g.lower[d]);
        let b = hi[d].min(g.upper[d]);
        let span = if b > a {
            ((b - a) / h[d]).ceil() + 1.0
        } else {
            0.0
        };
        n *= span.min(g.cells[d] as f64) * ppc;
    }
    n
}

/// `1.23 GiB`.
pub fn bytes(b: f64) -> String {
    const UNITS: [&str; 7] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut v = b;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    format!("{v:.3} {}", UNITS[u])
}

/// The memory this process may still use: the smaller of the system's
/// available memory (`MemAvailable`) and the room left under a cgroup
/// limit; `None` where neither is known.
pub fn available_memory() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|s| {
        s.lines()
            .find(|l| l.starts_with("MemAvailable:"))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|kb| kb.parse::<u64>().ok())
            .map(|kb| kb.saturating_mul(1024))
    });
    let read = |p: &str| {
        std::fs::read_to_string(p)
            .ok()
            .and_then(|s| s.trim().parse::<u64>().ok())
    };
    let cgroup = match (
        read("/sys/fs/cgroup/memory.max"),
        read("/sys/fs/cgroup/memory.current"),
    ) {
        (Some(max), Some(cur)) => Some(max.saturating_sub(cur)),
        (Some(max), None) => Some(max),
        _ => None,
    };
    match (meminfo, cgroup) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// The process's peak resident memory so far \[bytes\] (`VmHWM` of
/// `/proc/self/status`); `None` where the system does not report it.
pub fn peak_resident_bytes() -> Option<u64> {
    std::fs::read_to_string("/proc/self/status")
        .ok()?
        .lines()
        .find(|l| l.starts_with("VmHWM:"))?
        .split_whitespace()
        .nth(1)?
        .parse::<u64>()
        .ok()
        .map(|kb| kb.saturating_mul(1024))
}

/// The share of the memory limit a scene's estimate may take: the
/// estimate leaves out the program, its threads and the allocator's slack
/// (the peak resident memory of 20-step runs, `summary.json`'s
/// `peak_memory_bytes`, less the program's own 9.6 MiB, was 0.74–0.98 of
/// the estimate: bench/block_1m 419.5 MiB for 485.9, two_disks at 256²
/// 32.4 for 43.9, pressurized_cylinder_impm 17.9 for 22.2,
/// shock_helium_bubble 19.9 for 23.3, taylor_anvil at 160 × 320 33.5 for
/// 34.2).
pub const MEMORY_SHARE: f64 = 0.6;

/// Refuses `scene` when its estimate exceeds [`MEMORY_SHARE`] of `limit`
/// bytes (default: the available memory), naming the key that drives it
/// and the estimate.
///
/// # Errors
/// A [`SceneError`] at `grid.cells` (naming the largest object) or at
/// the largest `membrane_elements[i].mesh`.
pub fn check_memory(est: &MemoryEstimate, limit: Option<u64>) -> Result<(), SceneError> {
    let Some(limit) = limit.or_else(available_memory) else {
        return Ok(());
    };
    if est.total() <= MEMORY_SHARE * limit as f64 {
        return Ok(());
    }
    let largest = est
        .largest_object()
        .map_or(String::new(), |o| format!("; the largest object is {o}"));
    // The cell count drives the grid, the fluid cells and, through the
    // particles per cell, the particles; else the largest mesh.
    let key = match est
        .mesh_elements
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
    {
        Some((i, _)) if est.element_bytes > 0.5 * est.total() => {
            format!("membrane_elements[{i}].mesh")
        }
        _ => "grid.cells".to_string(),
    };
    Err(SceneError::new(
        key,
        format!(
            "the scene needs about {} but {} is available (a scene may take {:.0}% of \
             it){largest}: reduce grid.cells or \
             the particle counts (the objects, mpm.particles_per_cell), or pass \
             --ignore-memory-limit to try anyway",
            est.describe(),
            bytes(limit as f64),
            100.0 * MEMORY_SHARE
        ),
    ))
}
