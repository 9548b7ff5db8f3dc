//! Quadrilateral membrane meshes for [`super::element::MembraneMesh`]: a
//! structured rectangle in any plane, a "butterfly" disc, and a plain text
//! mesh file, all checked the same way (ids, connectivity, warp, area).
//!
//! The mesh file format, one item a line, `#` starts a comment:
//!
//! ```text
//! node ID X Y Z
//! quad ID N1 N2 N3 N4
//! ```
//!
//! Node and quad ids are any distinct non-negative integers; a quad's nodes
//! go counter-clockwise about its normal (the direction a positive pressure
//! pushes). Nodes are numbered internally in the order they appear.

use std::collections::HashMap;

use super::element::{frame, local_geometry, V3};

/// Largest allowed warp of a quad: the corners' distance from the
/// element's mean plane over √area.
pub const MAX_WARP: f64 = 0.05;

/// A quadrilateral mesh: node positions and corner ids.
#[derive(Debug, Clone, PartialEq)]
pub struct QuadMesh {
    /// Node positions.
    pub nodes: Vec<V3>,
    /// Corner node indices (into `nodes`) of each quad.
    pub quads: Vec<[u32; 4]>,
    /// Parameter coordinates (ξ, η) ∈ [0, 1]² of each node for meshes made
    /// by [`rectangle`] (empty otherwise).
    pub params: Vec<[f64; 2]>,
}

/// A structured rectangle of `na × nb` quads: nodes at
/// `corner + (i/na) a + (j/nb) b`, `i = 0..=na`, `j = 0..=nb` (node
/// `i + (na+1) j`); the normal is a × b.
pub fn rectangle(corner: V3, a: V3, b: V3, na: usize, nb: usize) -> QuadMesh {
    let mut nodes = Vec::with_capacity((na + 1) * (nb + 1));
    let mut params = Vec::with_capacity(nodes.capacity());
    for j in 0..=nb {
        for i in 0..=na {
            let (s, t) = (i as f64 / na as f64, j as f64 / nb as f64);
            nodes.push(corner + a * s + b * t);
            params.push([s, t]);
        }
    }
    QuadMesh {
        nodes,
        quads: structured_quads(na, nb),
        params,
    }
}

fn structured_quads(na: usize, nb: usize) -> Vec<[u32; 4]> {
    let id = |i: usize, j: usize| (i + (na + 1) * j) as u32;
    let mut quads = Vec::with_capacity(na * nb);
    for j in 0..nb {
        for i in 0..na {
            quads.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    quads
}

/// A disc of radius `radius` about `centre` in the plane z = centre.z
/// (normal +z), meshed by `cells × cells` quads (`cells` even): a
/// structured grid on the square [−1, 1]² whose inner half (|u|,|v| ≤ ½)
/// is a square of half-width `radius/2` and whose outer ring is blended
/// linearly, along rays, from that square to the circle (a "butterfly"
/// mesh without degenerate corners). The nodes of the outer ring lie on
/// the circle.
pub fn disc(centre: V3, radius: f64, cells: usize) -> QuadMesh {
    let inner = 0.5;
    let mut nodes = Vec::with_capacity((cells + 1) * (cells + 1));
    for j in 0..=cells {
        for i in 0..=cells {
            let u = 2.0 * i as f64 / cells as f64 - 1.0;
            let v = 2.0 * j as f64 / cells as f64 - 1.0;
            let r = u.abs().max(v.abs());
            let p = if r <= 0.5 {
                [inner * u / 0.5, inner * v / 0.5]
            } else {
                // Point on the unit square's boundary along this ray, and
                // the circle point on the same ray.
                let (su, sv) = (u / r, v / r);
                let norm = su.hypot(sv);
                let t = (r - 0.5) / 0.5;
                [
                    (1.0 - t) * inner * su + t * su / norm,
                    (1.0 - t) * inner * sv + t * sv / norm,
                ]
            };
            nodes.push(centre + V3::new(radius * p[0], radius * p[1], 0.0));
        }
    }
    QuadMesh {
        nodes,
        quads: structured_quads(cells, cells),
        params: Vec::new(),
    }
}

/// A mesh file that cannot be used: the 1-based line and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct MeshFileError {
    /// 1-based line number (0: the file as a whole).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

fn line_err(line: usize, message: impl Into<String>) -> MeshFileError {
    MeshFileError {
        line,
        message: message.into(),
    }
}

/// Parses and checks a mesh file (format in the module docs).
///
/// # Errors
/// The first bad line: an unknown keyword, a wrong number of fields, a
/// value that is not a number, a duplicate node or quad id, a quad naming
/// a missing node or the same node twice, a quad that is warped beyond
/// [`MAX_WARP`], has zero area or is not convex (folded, a bow-tie), a
/// quad ordered against its neighbour ([`check_orientation`]), or a node
/// no quad uses.
pub fn parse_mesh_file(text: &str) -> Result<QuadMesh, MeshFileError> {
    let mut nodes = Vec::new();
    let mut node_line = Vec::new();
    let mut node_ids: HashMap<u64, u32> = HashMap::new();
    let mut quads = Vec::new();
    let mut quad_lines = Vec::new();
    let mut quad_ids: HashMap<u64, usize> = HashMap::new();
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let body = raw.split('#').next().unwrap_or("");
        let f: Vec<&str> = body.split_whitespace().collect();
        if f.is_empty() {
            continue;
        }
        let id = |s: &str| -> Result<u64, MeshFileError> {
            s.parse::<u64>()
                .map_err(|_| line_err(line, format!("`{s}` is not an id (an integer ≥ 0)")))
        };
        match f[0] {
            "node" => {
                if f.len() != 5 {
                    return Err(line_err(
                        line,
                        format!("`node` takes 4 fields (ID X Y Z), got {}", f.len() - 1),
                    ));
                }
                let nid = id(f[1])?;
                let mut c = [0.0; 3];
                for d in 0..3 {
                    c[d] = f[2 + d]
                        .parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| {
                            line_err(line, format!("`{}` is not a finite number", f[2 + d]))
                        })?;
                }
                if let Some(&prev) = node_ids.get(&nid) {
                    return Err(line_err(
                        line,
                        format!(
                            "duplicate node id {nid} (first on line {})",
                            node_line[prev as usize]
                        ),
                    ));
                }
                node_ids.insert(nid, nodes.len() as u32);
                nodes.push(V3::new(c[0], c[1], c[2]));
                node_line.push(line);
            }
            "quad" => {
                if f.len() != 6 {
                    return Err(line_err(
                        line,
                        format!(
                            "`quad` takes 5 fields (ID N1 N2 N3 N4), got {}",
                            f.len() - 1
                        ),
                    ));
                }
                let qid = id(f[1])?;
                if let Some(&prev) = quad_ids.get(&qid) {
                    return Err(line_err(
                        line,
                        format!(
                            "duplicate quad id {qid} (first on line {})",
                            quad_lines[prev]
                        ),
                    ));
                }
                let mut q = [0u32; 4];
                for c in 0..4 {
                    let nid = id(f[2 + c])?;
                    q[c] = *node_ids.get(&nid).ok_or_else(|| {
                        line_err(
                            line,
                            format!(
                                "quad {qid} names node {nid}, which is not defined above \
                                 (nodes come before the quads using them)"
                            ),
                        )
                    })?;
                }
                for a in 0..4 {
                    for b in a + 1..4 {
                        if q[a] == q[b] {
                            return Err(line_err(
                                line,
                                format!("quad {qid} names node {} twice", f[2 + a]),
                            ));
                        }
                    }
                }
                quad_ids.insert(qid, quads.len());
                quads.push(q);
                quad_lines.push(line);
            }
            other => {
                return Err(line_err(
                    line,
                    format!("unknown keyword `{other}`; allowed: node, quad"),
                ))
            }
        }
    }
    if quads.is_empty() {
        return Err(line_err(0, "no quads; the file needs `quad` lines"));
    }
    let mesh = QuadMesh {
        nodes,
        quads,
        params: Vec::new(),
    };
    if let Some((e, msg)) = check_quads(&mesh).or_else(|| check_orientation(&mesh.quads)) {
        return Err(line_err(quad_lines[e], msg));
    }
    let mut used = vec![false; mesh.nodes.len()];
    for q in &mesh.quads {
        for &n in q {
            used[n as usize] = true;
        }
    }
    if let Some(n) = used.iter().position(|u| !u) {
        return Err(line_err(
            node_line[n],
            "node is used by no quad (it would have no mass)",
        ));
    }
    Ok(mesh)
}

/// The first quad that is warped beyond [`MAX_WARP`] or has zero or
/// negative area, with the reason.
pub fn check_quads(mesh: &QuadMesh) -> Option<(usize, String)> {
    for (e, q) in mesh.quads.iter().enumerate() {
        let p: [V3; 4] = std::array::from_fn(|k| mesh.nodes[q[k] as usize]);
        let Some(fr) = frame(&p) else {
            return Some((
                e,
                "degenerate quad: zero area, or a bow-tie whose diagonals do not cross".into(),
            ));
        };
        let g = local_geometry(&p, &fr);
        let scale = (0..4)
            .map(|k| (p[(k + 1) % 4] - p[k]).norm())
            .fold(0.0, f64::max);
        if g.area.is_nan() || g.area <= 1e-12 * scale * scale {
            return Some((
                e,
                format!(
                    "area {:e} ≤ 0: the quad is degenerate, folded or clockwise about its \
                     normal",
                    g.area
                ),
            ));
        }
        // The area is measured on the projection; a bow-tie shows as a
        // corner whose two edges turn the wrong way.
        for k in 0..4 {
            let a = g.xy[k];
            let b = g.xy[(k + 1) % 4];
            let c = g.xy[(k + 2) % 4];
            let cross = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]);
            if cross <= 0.0 {
                return Some((
                    e,
                    format!(
                        "not convex at its corner {}: the quad is folded, a bow-tie or has \
                         a straight angle",
                        k + 2
                    ),
                ));
            }
        }
        let e3 = fr.q.column(2);
        let warp = p
            .iter()
            .map(|x| e3.dot(&(x - fr.centre)).abs())
            .fold(0.0, f64::max)
            / g.area.sqrt();
        if warp > MAX_WARP {
            return Some((
                e,
                format!(
                    "warped: its corners lie {warp:.3} √area off its mean plane (allowed ≤ \
                     {MAX_WARP})"
                ),
            ));
        }
    }
    None
}

/// The first quad whose corner order disagrees with an earlier
/// neighbour's (a shared edge run the same way by both, so their normals
/// point to opposite sides), or that shares an edge with two earlier quads.
pub fn check_orientation(quads: &[[u32; 4]]) -> Option<(usize, String)> {
    let mut seen: HashMap<(u32, u32), usize> = HashMap::new();
    let mut shared: HashMap<(u32, u32), u32> = HashMap::new();
    for (e, q) in quads.iter().enumerate() {
        for k in 0..4 {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            if let Some(&other) = seen.get(&(a, b)) {
                return Some((
                    e,
                    format!(
                        "its corners run the other way round from quad number {} (in file \
                         order) across their shared edge, so their normals point to \
                         opposite sides; list the corners of both counter-clockwise about \
                         the same side",
                        other + 1
                    ),
                ));
            }
            let c = shared.entry((a.min(b), a.max(b))).or_insert(0);
            *c += 1;
            if *c > 2 {
                return Some((e, "an edge shared by more than two quads".into()));
            }
            seen.insert((a, b), e);
        }
    }
    None
}

/// Nodes on the mesh boundary: those of edges that belong to one quad only.
pub fn boundary_nodes(n_nodes: usize, quads: &[[u32; 4]]) -> Vec<bool> {
    let mut count: HashMap<(u32, u32), u32> = HashMap::new();
    for q in quads {
        for k in 0..4 {
            let (a, b) = (q[k], q[(k + 1) % 4]);
            *count.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut on = vec![false; n_nodes];
    for ((a, b), c) in count {
        if c == 1 {
            on[a as usize] = true;
            on[b as usize] = true;
        }
    }
    on
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rectangle_and_disc_pass_the_checks() {
        let r = rectangle(
            V3::zeros(),
            V3::new(2.0, 0.0, 0.0),
            V3::new(0.0, 0.0, 1.0),
            4,
            3,
        );
        assert_eq!(r.nodes.len(), 20);
        assert_eq!(check_quads(&r), None);
        let d = disc(V3::zeros(), 1.0, 8);
        assert_eq!(check_quads(&d), None);
        let b = boundary_nodes(d.nodes.len(), &d.quads);
        for (x, on) in d.nodes.iter().zip(&b) {
            if *on {
                assert!((x.norm() - 1.0).abs() < 1e-14);
            } else {
                assert!(x.norm() < 1.0 - 1e-3);
            }
        }
    }
}
