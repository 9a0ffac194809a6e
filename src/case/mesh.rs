//! The scene's mesh: its `[[mesh]]` parts checked ([`super::parts`]), generated or read,
//! translated, their generated sets prefixed with the body name, optionally distorted, and
//! merged in order.

use std::collections::BTreeMap;
use std::path::Path;

use crate::error::{Error, Result};
use crate::fe::ElementType;
use crate::io::case_file::MeshPart;
use crate::mesh::Mesh;

use super::parts::{check_part, PartSource};

/// The mesh of all parts, merged in order (`err` makes a case-file error of a message).
pub(super) fn build_mesh(
    parts: &[MeshPart],
    dir: &Path,
    err: &dyn Fn(String) -> Error,
) -> Result<Mesh> {
    if parts.is_empty() {
        return Err(err("mesh: at least one [[mesh]] part is required".into()));
    }
    let mut mesh = Mesh::new();
    for (i, part) in parts.iter().enumerate() {
        let mut m = build_part(part, i, dir, err)?;
        if let Some(t) = part.translate {
            for x in m.coords.iter_mut() {
                for d in 0..3 {
                    x[d] += t[d];
                }
            }
        }
        if mesh.num_elements() == 0 && mesh.coords.is_empty() {
            mesh = m;
        } else {
            mesh.merge(m);
        }
    }
    Ok(mesh)
}

/// Part `i`: checked, then generated (sets renamed `<body>.<set>`, distorted if asked) or read
/// from its Gmsh file.
fn build_part(p: &MeshPart, i: usize, dir: &Path, err: &dyn Fn(String) -> Error) -> Result<Mesh> {
    let source = check_part(p, &format!("mesh[{i}]")).map_err(err)?;
    let body = p.body.clone().unwrap_or_else(|| "body".into());
    let mut mesh = match source {
        PartSource::Gmsh(file) => return crate::io::gmsh::read_msh(&dir.join(file)),
        PartSource::Generator(generate) => generate(&body),
    };
    prefix_sets(&mut mesh, &body);
    if p.distort != 0.0 {
        distort_interior(&mut mesh, p.distort);
    }
    Ok(mesh)
}

/// Renames generated sets `s` to `<body>.s`.
fn prefix_sets(mesh: &mut Mesh, body: &str) {
    fn prefixed<T>(sets: &mut BTreeMap<String, Vec<T>>, body: &str) {
        *sets = std::mem::take(sets)
            .into_iter()
            .map(|(k, v)| (format!("{body}.{k}"), v))
            .collect();
    }
    prefixed(&mut mesh.node_sets, body);
    prefixed(&mut mesh.face_sets, body);
    prefixed(&mut mesh.element_sets, body);
}

/// Distorts a generated part: every corner (vertex) node that lies in no node set (the interior)
/// moves by a deterministic pseudo-random vector of length up to `amount` times the shortest
/// element edge; every other interior node (mid-edge, face and centre nodes of quadratic
/// elements) moves by the motion of its element's corners interpolated at its parametric
/// position, plus a quarter of that random amount. Moving higher-order nodes with their corners
/// keeps elements valid and neighbours consistent (an edge node follows only its edge's corners).
fn distort_interior(mesh: &mut Mesh, amount: f64) {
    let n = mesh.num_nodes();
    let mut on_set = vec![false; n];
    for nodes in mesh.node_sets.values() {
        for &v in nodes {
            on_set[v] = true;
        }
    }
    let h = mesh.min_edge_length();
    let mut rng = XorShift(0x9E37_79B9_7F4A_7C15);
    let noise: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            let d = [rng.next(), rng.next(), rng.next()];
            d.map(|c| amount * h * c / 3f64.sqrt())
        })
        .collect();
    // Vertex motion first.
    let mut is_vertex = vec![false; n];
    for e in 0..mesh.num_elements() {
        let k = mesh.types[e].num_corners();
        for &v in &mesh.element_nodes(e)[..k] {
            is_vertex[v] = true;
        }
    }
    let motion: Vec<[f64; 3]> = (0..n)
        .map(|v| {
            if is_vertex[v] && !on_set[v] {
                noise[v]
            } else {
                [0.0; 3]
            }
        })
        .collect();
    let shift = follow_corners(mesh, &motion, &noise, &on_set);
    for (x, d) in mesh.coords.iter_mut().zip(&shift) {
        for k in 0..3 {
            x[k] += d[k];
        }
    }
}

/// The shift of every node: `motion` for the corners; for the other nodes in no set, the
/// motion of their element's corners interpolated at their parametric position (the linear
/// element's shape functions), plus a quarter of their `noise`.
fn follow_corners(
    mesh: &Mesh,
    motion: &[[f64; 3]],
    noise: &[[f64; 3]],
    on_set: &[bool],
) -> Vec<[f64; 3]> {
    let mut placed = vec![false; mesh.num_nodes()];
    let mut shift = motion.to_vec();
    for e in 0..mesh.num_elements() {
        let kind = mesh.types[e];
        let linear = if kind.is_hex() {
            ElementType::Hex8
        } else {
            ElementType::Tet4
        };
        let params = kind.node_coords();
        let nodes = mesh.element_nodes(e);
        let corners = &nodes[..kind.num_corners()];
        let mut nl = vec![0.0; linear.num_nodes()];
        for (a, &v) in nodes.iter().enumerate().skip(kind.num_corners()) {
            if on_set[v] || placed[v] {
                continue;
            }
            placed[v] = true;
            linear.shape(params[a], &mut nl);
            for d in 0..3 {
                let follow: f64 = corners
                    .iter()
                    .zip(&nl)
                    .map(|(&c, w)| w * motion[c][d])
                    .sum();
                shift[v][d] = follow + 0.25 * noise[v][d];
            }
        }
    }
    shift
}

/// xorshift64*: the same sequence on every rank and platform.
struct XorShift(u64);

impl XorShift {
    /// A number in [-1, 1).
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}
