//! Element and face topology: node counts, parametric node positions, edges and faces.
//!
//! # Node ordering
//!
//! Every element and face uses the **VTK ordering** (what ParaView shows), so output needs no
//! permutation; Gmsh input is permuted on import (`io::gmsh`).
//!
//! Parent domains: hexahedra live on `[-1, 1]^3`, tetrahedra on the unit simplex
//! `{xi, eta, zeta >= 0, xi + eta + zeta <= 1}`; quadrilateral faces on `[-1, 1]^2`, triangular faces
//! on the unit triangle.
//!
//! - Hex8: corners 0-3 on `zeta = -1` counter-clockwise seen from `+zeta`, 4-7 above them.
//! - Hex20: corners, then mid-edge nodes 8-11 on the bottom edges (0-1, 1-2, 2-3, 3-0), 12-15 on the
//!   top edges (4-5, 5-6, 6-7, 7-4), 16-19 on the vertical edges (0-4, 1-5, 2-6, 3-7).
//! - Hex27: Hex20, then face centres 20-25 on the faces `xi = -1, xi = +1, eta = -1, eta = +1,
//!   zeta = -1, zeta = +1`, then the centre 26 (VTK_TRIQUADRATIC_HEXAHEDRON).
//! - Tet4: (0,0,0), (1,0,0), (0,1,0), (0,0,1).
//! - Tet10: corners, then mid-edge nodes on 0-1, 1-2, 2-0, 0-3, 1-3, 2-3.
//! - Quad4/Quad8/Quad9 and Tri3/Tri6: corners counter-clockwise, then mid-edge nodes on edges
//!   (c0 c1), (c1 c2), ..., then (Quad9) the centre.
//!
//! # Faces
//!
//! `ElementType::face_nodes(f)` lists the element-local nodes of face `f` in the face type's own
//! ordering, corners counter-clockwise **seen from outside**, so the right-hand rule on
//! `dx/dxi x dx/deta` gives the outward normal.

use serde::{Deserialize, Serialize};

/// A solid element type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum ElementType {
    Hex8,
    Hex20,
    Hex27,
    Tet4,
    Tet10,
}

/// A face (surface segment) type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum FaceType {
    Quad4,
    Quad8,
    Quad9,
    Tri3,
    Tri6,
}

/// Corners of the six hexahedron faces, counter-clockwise seen from outside, in the order
/// `xi = -1, xi = +1, eta = -1, eta = +1, zeta = -1, zeta = +1` (the order of the Hex27 face centres).
const HEX_FACE_CORNERS: [[usize; 4]; 6] = [
    [0, 4, 7, 3],
    [1, 2, 6, 5],
    [0, 1, 5, 4],
    [3, 7, 6, 2],
    [0, 3, 2, 1],
    [4, 5, 6, 7],
];

/// Edges of the hexahedron, in the order of the Hex20 mid-edge nodes 8..19.
const HEX_EDGES: [[usize; 2]; 12] = [
    [0, 1],
    [1, 2],
    [2, 3],
    [3, 0],
    [4, 5],
    [5, 6],
    [6, 7],
    [7, 4],
    [0, 4],
    [1, 5],
    [2, 6],
    [3, 7],
];

/// Corners of the four tetrahedron faces, counter-clockwise seen from outside:
/// `zeta = 0, eta = 0, xi = 0`, and the slanted face.
const TET_FACE_CORNERS: [[usize; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

/// Edges of the tetrahedron, in the order of the Tet10 mid-edge nodes 4..9.
const TET_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]];

/// Parametric positions of the Hex27 nodes in the VTK ordering (the first 8 are the Hex8 nodes,
/// the first 20 the Hex20 nodes): node `a` sits at `s^a` with every `s^a_i` in `{-1, 0, 1}`.
#[rustfmt::skip]
pub(crate) const HEX_NODES: [[f64; 3]; 27] = [
    // Corners: bottom (zeta = -1), then top.
    [-1.0, -1.0, -1.0], [1.0, -1.0, -1.0], [1.0, 1.0, -1.0], [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0, 1.0], [-1.0, 1.0, 1.0],
    // Mid-edge nodes: bottom edges 0-1, 1-2, 2-3, 3-0; top edges 4-5, 5-6, 6-7, 7-4; vertical
    // edges 0-4, 1-5, 2-6, 3-7.
    [0.0, -1.0, -1.0], [1.0, 0.0, -1.0], [0.0, 1.0, -1.0], [-1.0, 0.0, -1.0],
    [0.0, -1.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0], [-1.0, 0.0, 1.0],
    [-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0],
    // Face centres xi = -1, +1, eta = -1, +1, zeta = -1, +1; the centre.
    [-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 1.0, 0.0],
    [0.0, 0.0, -1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0],
];

/// Parametric positions of the Tet10 nodes (the first 4 are the Tet4 nodes).
#[rustfmt::skip]
pub(crate) const TET_NODES: [[f64; 3]; 10] = [
    // Corners.
    [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0],
    // Mid-edge nodes of 0-1, 1-2, 2-0, 0-3, 1-3, 2-3 (`TET_EDGES`).
    [0.5, 0.0, 0.0], [0.5, 0.5, 0.0], [0.0, 0.5, 0.0],
    [0.0, 0.0, 0.5], [0.5, 0.0, 0.5], [0.0, 0.5, 0.5],
];

/// Parametric positions of the Quad9 nodes (the first 4 are the Quad4 nodes, the first 8 the
/// Quad8 nodes).
#[rustfmt::skip]
pub(crate) const QUAD_NODES: [[f64; 2]; 9] = [
    // Corners; mid-edge nodes of 0-1, 1-2, 2-3, 3-0; the centre.
    [-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0],
    [0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0],
    [0.0, 0.0],
];

/// Parametric positions of the Tri6 nodes (the first 3 are the Tri3 nodes).
#[rustfmt::skip]
pub(crate) const TRI_NODES: [[f64; 2]; 6] = [
    // Corners; mid-edge nodes of 0-1, 1-2, 2-0.
    [0.0, 0.0], [1.0, 0.0], [0.0, 1.0],
    [0.5, 0.0], [0.5, 0.5], [0.0, 0.5],
];

impl ElementType {
    /// All element types, for tests and tables.
    pub const ALL: [ElementType; 5] = [
        ElementType::Hex8,
        ElementType::Hex20,
        ElementType::Hex27,
        ElementType::Tet4,
        ElementType::Tet10,
    ];

    /// Number of nodes.
    pub fn num_nodes(self) -> usize {
        match self {
            ElementType::Hex8 => 8,
            ElementType::Hex20 => 20,
            ElementType::Hex27 => 27,
            ElementType::Tet4 => 4,
            ElementType::Tet10 => 10,
        }
    }

    /// Number of corner (vertex) nodes.
    pub fn num_corners(self) -> usize {
        if self.is_hex() {
            8
        } else {
            4
        }
    }

    /// True for the hexahedra.
    pub fn is_hex(self) -> bool {
        matches!(
            self,
            ElementType::Hex8 | ElementType::Hex20 | ElementType::Hex27
        )
    }

    /// Polynomial order of the shape functions along an edge (1 or 2).
    pub fn order(self) -> usize {
        match self {
            ElementType::Hex8 | ElementType::Tet4 => 1,
            _ => 2,
        }
    }

    /// Name used in case files and messages (`"hex8"`, ...).
    pub fn name(self) -> &'static str {
        match self {
            ElementType::Hex8 => "hex8",
            ElementType::Hex20 => "hex20",
            ElementType::Hex27 => "hex27",
            ElementType::Tet4 => "tet4",
            ElementType::Tet10 => "tet10",
        }
    }

    /// Parses a case-file name (`"hex8"`, `"hex20"`, `"hex27"`, `"tet4"`, `"tet10"`).
    pub fn from_name(name: &str) -> Option<ElementType> {
        ElementType::ALL.into_iter().find(|t| t.name() == name)
    }

    /// VTK cell type number.
    pub fn vtk_cell_type(self) -> u8 {
        match self {
            ElementType::Hex8 => 12,
            ElementType::Hex20 => 25,
            ElementType::Hex27 => 29,
            ElementType::Tet4 => 10,
            ElementType::Tet10 => 24,
        }
    }

    /// The element's edges as pairs of corner nodes; for quadratic elements edge `k` carries
    /// mid-edge node `num_corners() + k`.
    pub fn edges(self) -> &'static [[usize; 2]] {
        if self.is_hex() {
            &HEX_EDGES
        } else {
            &TET_EDGES
        }
    }

    /// Number of faces.
    pub fn num_faces(self) -> usize {
        if self.is_hex() {
            6
        } else {
            4
        }
    }

    /// Type of face `f` (all faces of one element type share a type).
    pub fn face_type(self) -> FaceType {
        match self {
            ElementType::Hex8 => FaceType::Quad4,
            ElementType::Hex20 => FaceType::Quad8,
            ElementType::Hex27 => FaceType::Quad9,
            ElementType::Tet4 => FaceType::Tri3,
            ElementType::Tet10 => FaceType::Tri6,
        }
    }

    /// Element-local nodes of face `f`, in the face type's ordering, outward oriented.
    pub fn face_nodes(self, f: usize) -> Vec<usize> {
        let corners: Vec<usize> = if self.is_hex() {
            HEX_FACE_CORNERS[f].to_vec()
        } else {
            TET_FACE_CORNERS[f].to_vec()
        };
        let mut nodes = corners.clone();
        if self.order() == 2 {
            let nc = corners.len();
            for k in 0..nc {
                nodes.push(self.mid_edge_node(corners[k], corners[(k + 1) % nc]));
            }
        }
        if self == ElementType::Hex27 {
            nodes.push(20 + f);
        }
        nodes
    }

    /// The mid-edge node between corners `a` and `b` of a quadratic element.
    ///
    /// # Panics
    /// If `a`-`b` is not an edge (a programming error, never input-dependent).
    pub fn mid_edge_node(self, a: usize, b: usize) -> usize {
        let k = self
            .edges()
            .iter()
            .position(|e| (e[0] == a && e[1] == b) || (e[0] == b && e[1] == a))
            .expect("mid_edge_node: not an edge");
        self.num_corners() + k
    }

    /// Parametric coordinates of every node (a prefix of the table `HEX_NODES` or `TET_NODES`).
    pub fn node_coords(self) -> Vec<[f64; 3]> {
        let table: &[[f64; 3]] = if self.is_hex() {
            &HEX_NODES
        } else {
            &TET_NODES
        };
        table[..self.num_nodes()].to_vec()
    }
}

impl FaceType {
    /// All face types.
    pub const ALL: [FaceType; 5] = [
        FaceType::Quad4,
        FaceType::Quad8,
        FaceType::Quad9,
        FaceType::Tri3,
        FaceType::Tri6,
    ];

    /// Number of nodes.
    pub fn num_nodes(self) -> usize {
        match self {
            FaceType::Quad4 => 4,
            FaceType::Quad8 => 8,
            FaceType::Quad9 => 9,
            FaceType::Tri3 => 3,
            FaceType::Tri6 => 6,
        }
    }

    /// Number of corner nodes (3 or 4).
    pub fn num_corners(self) -> usize {
        if self.is_quad() {
            4
        } else {
            3
        }
    }

    /// True for the quadrilaterals.
    pub fn is_quad(self) -> bool {
        matches!(self, FaceType::Quad4 | FaceType::Quad8 | FaceType::Quad9)
    }

    /// Name used in messages.
    pub fn name(self) -> &'static str {
        match self {
            FaceType::Quad4 => "quad4",
            FaceType::Quad8 => "quad8",
            FaceType::Quad9 => "quad9",
            FaceType::Tri3 => "tri3",
            FaceType::Tri6 => "tri6",
        }
    }

    /// VTK cell type number.
    pub fn vtk_cell_type(self) -> u8 {
        match self {
            FaceType::Quad4 => 9,
            FaceType::Quad8 => 23,
            FaceType::Quad9 => 28,
            FaceType::Tri3 => 5,
            FaceType::Tri6 => 22,
        }
    }

    /// Parametric coordinates of every node (a prefix of the table `QUAD_NODES` or `TRI_NODES`).
    pub fn node_coords(self) -> Vec<[f64; 2]> {
        let table: &[[f64; 2]] = if self.is_quad() {
            &QUAD_NODES
        } else {
            &TRI_NODES
        };
        table[..self.num_nodes()].to_vec()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The node tables follow the topology: every mid-edge node halfway between its edge's
    /// corners, every Hex27 face centre at the mean of its face's corners, the Hex27 and Quad9
    /// centres at the middle of the parent domain.
    #[test]
    fn node_tables_follow_the_topology() {
        for et in ElementType::ALL.into_iter().filter(|t| t.order() == 2) {
            let x = et.node_coords();
            for (k, &[a, b]) in et.edges().iter().enumerate() {
                let mid: [f64; 3] = std::array::from_fn(|d| 0.5 * (x[a][d] + x[b][d]));
                assert_eq!(x[et.num_corners() + k], mid, "{et:?} edge {k}");
            }
        }
        let x = ElementType::Hex27.node_coords();
        for (f, corners) in HEX_FACE_CORNERS.iter().enumerate() {
            let centre: [f64; 3] =
                std::array::from_fn(|d| corners.iter().map(|&c| 0.25 * x[c][d]).sum());
            assert_eq!(x[20 + f], centre, "Hex27 face {f}");
        }
        assert_eq!(x[26], [0.0; 3]);
        for ft in [FaceType::Quad8, FaceType::Quad9, FaceType::Tri6] {
            let (x, nc) = (ft.node_coords(), ft.num_corners());
            for k in 0..nc {
                let (a, b) = (x[k], x[(k + 1) % nc]);
                assert_eq!(
                    x[nc + k],
                    [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])],
                    "{ft:?}"
                );
            }
        }
        assert_eq!(FaceType::Quad9.node_coords()[8], [0.0; 2]);
    }

    /// Each face's nodes, taken at their element parametric coordinates, lie on one parent face and
    /// the mid-edge nodes sit between their corners.
    #[test]
    fn face_nodes_are_consistent_with_face_node_coords() {
        for et in ElementType::ALL {
            let xe = et.node_coords();
            assert_eq!(xe.len(), et.num_nodes());
            let ft = et.face_type();
            for f in 0..et.num_faces() {
                let nodes = et.face_nodes(f);
                assert_eq!(nodes.len(), ft.num_nodes(), "{et:?} face {f}");
                let nc = ft.num_corners();
                for k in nc..nodes.len().min(2 * nc) {
                    let (a, b) = (xe[nodes[k - nc]], xe[nodes[(k - nc + 1) % nc]]);
                    for d in 0..3 {
                        assert!((xe[nodes[k]][d] - 0.5 * (a[d] + b[d])).abs() < 1e-15);
                    }
                }
            }
        }
    }

    /// The corner ordering gives an outward normal: (x1 - x0) x (x2 - x1) points away from the
    /// element centroid.
    #[test]
    fn faces_are_outward_oriented() {
        for et in ElementType::ALL {
            let xe = et.node_coords();
            let n = xe.len() as f64;
            let c: Vec<f64> = (0..3)
                .map(|d| xe.iter().map(|x| x[d]).sum::<f64>() / n)
                .collect();
            for f in 0..et.num_faces() {
                let nodes = et.face_nodes(f);
                let p = |i: usize| xe[nodes[i]];
                let a: Vec<f64> = (0..3).map(|d| p(1)[d] - p(0)[d]).collect();
                let b: Vec<f64> = (0..3).map(|d| p(2)[d] - p(1)[d]).collect();
                let nrm = [
                    a[1] * b[2] - a[2] * b[1],
                    a[2] * b[0] - a[0] * b[2],
                    a[0] * b[1] - a[1] * b[0],
                ];
                let out: f64 = (0..3).map(|d| nrm[d] * (p(0)[d] - c[d])).sum();
                assert!(out > 0.0, "{et:?} face {f} points inward");
            }
        }
    }
}
