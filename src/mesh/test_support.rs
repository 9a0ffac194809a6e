//! Helpers of the mesh tests: measures of a generated mesh.

use crate::fe::ElementType;
use crate::mesh::check::jacobian_determinant;
use crate::mesh::Mesh;

/// Volume of the mesh by quadrature of det J (degree 6).
pub(crate) fn volume(m: &Mesh) -> f64 {
    let mut v = 0.0;
    for e in 0..m.num_elements() {
        let kind = m.types[e];
        let rule = kind.quadrature(6);
        let x = m.element_coords(e);
        let mut dn = vec![[0.0; 3]; kind.num_nodes()];
        for (p, w) in rule.points.iter().zip(&rule.weights) {
            kind.shape_grad(*p, &mut dn);
            v += w * jacobian_determinant(|a| x[a], &dn);
        }
    }
    v
}

/// Number of nodes of a structured block of `n` cells per axis.
pub(crate) fn expected_nodes(kind: ElementType, n: [usize; 3]) -> usize {
    let q = |d: usize| 2 * n[d] + 1;
    let l = |d: usize| n[d] + 1;
    match kind {
        ElementType::Hex8 | ElementType::Tet4 => l(0) * l(1) * l(2),
        ElementType::Hex27 | ElementType::Tet10 => q(0) * q(1) * q(2),
        ElementType::Hex20 => {
            l(0) * l(1) * l(2) + n[0] * l(1) * l(2) + l(0) * n[1] * l(2) + l(0) * l(1) * n[2]
        }
    }
}

/// The distinct coordinates along axis `d` of the nodes of node set `set`, increasing.
pub(crate) fn set_coordinates(m: &Mesh, set: &str, d: usize) -> Vec<f64> {
    let mut v: Vec<f64> = m
        .node_set(set)
        .unwrap()
        .iter()
        .map(|&n| m.coords[n][d])
        .collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}

/// Number of element faces on the boundary (faces of no other element), for a mesh of one
/// element type.
pub(crate) fn boundary_faces(m: &Mesh) -> usize {
    let (xadj, _) = crate::mesh::partition::dual_graph(m);
    let nf = m.types[0].num_faces();
    m.num_elements() * nf - xadj[m.num_elements()]
}

/// The boundary of `m` is exactly the face sets `sets`: every face is shared by at most two
/// elements, and the parts left no internal seams.
pub(crate) fn assert_boundary_is(m: &Mesh, sets: &[&str], what: &str) {
    let named: usize = sets.iter().map(|s| m.face_sets[*s].len()).sum();
    assert_eq!(boundary_faces(m), named, "{what}");
}
