//! Sub-segments of faces and traction shape functions.
//!
//! # Sub-segments (the paper's Figure 1)
//!
//! Quadratic faces are integrated piece by piece: each face is split, in its parent coordinates,
//! into linear sub-segments (triangles or quadrilaterals) whose vertices are face nodes. The mortar
//! integrator projects and clips these straight-edged pieces, and maps every quadrature point back
//! into the face's parent coordinates, where the full (possibly quadratic) shape functions of the
//! face are evaluated. With `c0..c3` the corners, `m0..m3` the mid-edge nodes on the edges
//! `(c0 c1), (c1 c2), ...` and `ctr` the Quad9 centre (VTK order, [`crate::fe::element`]):
//!
//! | face  | sub-segments |
//! |-------|--------------|
//! | Quad4 | itself |
//! | Quad9 | 4 Quad4: `(c0 m0 ctr m3)`, `(m0 c1 m1 ctr)`, `(ctr m1 c2 m2)`, `(m3 ctr m2 c3)` |
//! | Quad8 | 4 corner triangles `(c0 m0 m3)`, `(m0 c1 m1)`, `(m1 c2 m2)`, `(m2 c3 m3)` and the quad `(m0 m1 m2 m3)` |
//! | Tri3  | itself |
//! | Tri6  | 4 triangles `(c0 m0 m2)`, `(m0 c1 m1)`, `(m2 m1 c2)`, `(m0 m1 m2)` |
//!
//! The paper's figure draws three triangles for the six-node patch; that split is not
//! symmetric in the corners, so this code uses the usual four-triangle split (three corner
//! triangles and the middle one), which treats all nodes alike and tiles the parent triangle.
//!
//! Every sub-segment is counter-clockwise in the parent domain, like its face, so its own normal
//! (right-hand rule) points out of the body as the face's does. In the parent domain every
//! sub-segment is a triangle or a parallelogram (the Quad9 quarters are squares, the Quad8 middle
//! quad is a square turned by 45 degrees), so the map from a sub-segment's own coordinates to the
//! face's parent coordinates is affine and inverted in closed form ([`SubSegment::to_local`]).
//! Sub-segment local coordinates are those of Tri3 (unit triangle) and Quad4 (`[-1, 1]^2`).
//!
//! # Traction interpolation (docs/theory.md section 5)
//!
//! The pressure and tangential traction of the secondary face are interpolated with functions
//! `Phi_A` of its traction nodes `A`:
//!
//! 1. [`TractionScheme::FaceShape`]: `Phi_A = N_A`, the face's own shape functions, all nodes.
//! 2. [`TractionScheme::Corners`]: bilinear (quad) or linear (triangle) functions of the corner
//!    nodes only, evaluated at the parent coordinates `xi`: `Phi_A = N^Quad4_A(xi)` or
//!    `N^Tri3_A(xi)`.
//! 3. [`TractionScheme::PiecewiseLinear`]: on each sub-segment, its own linear/bilinear functions
//!    of its vertices (continuous across sub-segments, all face nodes carry unknowns).
//!
//! Traction nodes are always a prefix of the face's nodes (all nodes, or the corners, which come
//! first in VTK order), so the index `k` of [`traction_nodes`] equals the face-local node number.
//!
//! Scheme 1 is refused on Quad8 and Tri6 ([`traction_nodes`] returns an error): there the integral
//! of a corner shape function over the face is negative (Quad8, `-1/12` of the face area on a
//! parallelogram) or zero (Tri6), so the corner weights `a_A = int Phi_A` in the nodal
//! Kuhn-Tucker conditions and the normalized gap `g_A / a_A` are meaningless. On Quad9 all the
//! integrals are positive (`1/36`, `1/9`, `4/9` of the area for corner, mid-edge and centre nodes).

use crate::fe::shape::Scalar;
use crate::fe::FaceType;

/// How the interface traction is interpolated on a secondary face (the paper's three schemes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TractionScheme {
    /// Scheme 1: the secondary face's own shape functions.
    FaceShape,
    /// Scheme 2: linear/bilinear functions of the corner nodes.
    Corners,
    /// Scheme 3: piecewise linear/bilinear over the sub-segments.
    PiecewiseLinear,
}

impl TractionScheme {
    /// The scheme with the paper's number (1, 2 or 3).
    pub fn from_number(n: u8) -> Option<Self> {
        match n {
            1 => Some(TractionScheme::FaceShape),
            2 => Some(TractionScheme::Corners),
            3 => Some(TractionScheme::PiecewiseLinear),
            _ => None,
        }
    }

    /// The paper's number of the scheme (1, 2 or 3).
    pub fn number(self) -> u8 {
        match self {
            TractionScheme::FaceShape => 1,
            TractionScheme::Corners => 2,
            TractionScheme::PiecewiseLinear => 3,
        }
    }
}

/// A linear sub-segment of a face: a triangle or a quadrilateral (parallelogram) in the face's
/// parent coordinates whose vertices are face nodes, counter-clockwise.
#[derive(Clone, Debug, PartialEq)]
pub struct SubSegment {
    /// Face-local node at each vertex.
    pub local_nodes: Vec<usize>,
    /// Parent coordinates of each vertex on the face.
    pub vertices: Vec<[f64; 2]>,
}

impl SubSegment {
    fn from_nodes(kind: FaceType, local_nodes: &[usize]) -> SubSegment {
        let coords = kind.node_coords();
        SubSegment {
            local_nodes: local_nodes.to_vec(),
            vertices: local_nodes.iter().map(|&a| coords[a]).collect(),
        }
    }

    /// The linear face type of the sub-segment: Quad4 (4 vertices) or Tri3 (3 vertices).
    pub fn linear_kind(&self) -> FaceType {
        if self.vertices.len() == 4 {
            FaceType::Quad4
        } else {
            FaceType::Tri3
        }
    }

    /// Values of the sub-segment's own linear (Tri3) or bilinear (Quad4) functions of its vertices
    /// at its local coordinates `local`.
    pub fn linear_shape(&self, local: [f64; 2]) -> [f64; 4] {
        self.linear_shape_at(local)
    }

    /// [`SubSegment::linear_shape`] for any [`Scalar`] (unused entries are zero).
    pub fn linear_shape_at<T: Scalar>(&self, local: [T; 2]) -> [T; 4] {
        let mut n = [T::from(0.0); 4];
        let kind = self.linear_kind();
        kind.shape_at(local, &mut n[..kind.num_nodes()]);
        n
    }

    /// Parent coordinates on the face of the point with sub-segment local coordinates `local`.
    pub fn to_parent(&self, local: [f64; 2]) -> [f64; 2] {
        self.to_parent_at(local)
    }

    /// [`SubSegment::to_parent`] for any [`Scalar`], by the affine map of the sub-segment (exact:
    /// see [`SubSegment::parent_jacobian`]).
    pub fn to_parent_at<T: Scalar>(&self, local: [T; 2]) -> [T; 2] {
        let (origin, j) = self.affine_map();
        [
            local[0] * j[0][0] + local[1] * j[0][1] + origin[0],
            local[0] * j[1][0] + local[1] * j[1][1] + origin[1],
        ]
    }

    /// The affine map `xi = origin + J local` of the sub-segment into the parent domain (exact:
    /// triangles, and quadrilaterals that are parallelograms in the parent domain, which all
    /// sub-segments of [`sub_segments`] are). Returns `(origin, J)` with
    /// `J[i][j] = dxi_i/dlocal_j`.
    pub fn affine_map(&self) -> ([f64; 2], [[f64; 2]; 2]) {
        let v = &self.vertices;
        if v.len() == 3 {
            let j = [
                [v[1][0] - v[0][0], v[2][0] - v[0][0]],
                [v[1][1] - v[0][1], v[2][1] - v[0][1]],
            ];
            return (v[0], j);
        }
        let centre = [
            0.25 * (v[0][0] + v[1][0] + v[2][0] + v[3][0]),
            0.25 * (v[0][1] + v[1][1] + v[2][1] + v[3][1]),
        ];
        let d_s = |i: usize| 0.25 * (-v[0][i] + v[1][i] + v[2][i] - v[3][i]);
        let d_t = |i: usize| 0.25 * (-v[0][i] - v[1][i] + v[2][i] + v[3][i]);
        (centre, [[d_s(0), d_t(0)], [d_s(1), d_t(1)]])
    }

    /// Determinant of `dxi/dlocal` (constant, positive): the parent-domain area of the sub-segment
    /// divided by that of its local domain (1/2 or 4).
    pub fn parent_jacobian(&self) -> f64 {
        let (_, j) = self.affine_map();
        j[0][0] * j[1][1] - j[0][1] * j[1][0]
    }

    /// Local coordinates of the point with face parent coordinates `xi` (inverse of
    /// [`SubSegment::to_parent`]; also defined outside the sub-segment).
    pub fn to_local(&self, xi: [f64; 2]) -> [f64; 2] {
        self.to_local_at(xi)
    }

    /// [`SubSegment::to_local`] for any [`Scalar`].
    pub fn to_local_at<T: Scalar>(&self, xi: [T; 2]) -> [T; 2] {
        let (origin, j) = self.affine_map();
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        let d = [xi[0] - origin[0], xi[1] - origin[1]];
        [
            (d[0] * j[1][1] - d[1] * j[0][1]) / det,
            (d[1] * j[0][0] - d[0] * j[1][0]) / det,
        ]
    }

    /// Parent coordinates of the sub-segment's centre (the image of the local centroid: the
    /// vertex mean, which for triangles and parallelograms is also the area centroid).
    pub fn centre(&self) -> [f64; 2] {
        let n = self.vertices.len() as f64;
        let sum = self
            .vertices
            .iter()
            .fold([0.0; 2], |acc, v| [acc[0] + v[0], acc[1] + v[1]]);
        [sum[0] / n, sum[1] / n]
    }
}

/// Linear sub-segments of a face in its parent coordinates (see the module docs for the table).
pub fn sub_segments(kind: FaceType) -> Vec<SubSegment> {
    let lists: &[&[usize]] = match kind {
        FaceType::Quad4 => &[&[0, 1, 2, 3]],
        FaceType::Quad9 => &[&[0, 4, 8, 7], &[4, 1, 5, 8], &[8, 5, 2, 6], &[7, 8, 6, 3]],
        FaceType::Quad8 => &[
            &[0, 4, 7],
            &[4, 1, 5],
            &[5, 2, 6],
            &[6, 3, 7],
            &[4, 5, 6, 7],
        ],
        FaceType::Tri3 => &[&[0, 1, 2]],
        FaceType::Tri6 => &[&[0, 3, 5], &[3, 1, 4], &[5, 4, 2], &[3, 4, 5]],
    };
    lists
        .iter()
        .map(|nodes| SubSegment::from_nodes(kind, nodes))
        .collect()
}

/// Number of traction nodes of a face under a scheme, without the well-posedness check of
/// [`traction_nodes`] (scheme 1 counts all nodes also on Quad8 and Tri6).
pub fn traction_node_count(kind: FaceType, scheme: TractionScheme) -> usize {
    match scheme {
        TractionScheme::Corners => kind.num_corners(),
        TractionScheme::FaceShape | TractionScheme::PiecewiseLinear => kind.num_nodes(),
    }
}

/// Face-local nodes that carry traction unknowns: FaceShape -> all nodes; Corners -> corners only;
/// PiecewiseLinear -> all nodes (the sub-segment vertices). Always `0..count`, so the index of a
/// traction node is its face-local node number.
///
/// # Errors
/// FaceShape on Quad8 and Tri6: the integrals of the corner shape functions are negative (Quad8)
/// or zero (Tri6), which makes nodal Kuhn-Tucker conditions ill-posed.
pub fn traction_nodes(kind: FaceType, scheme: TractionScheme) -> Result<Vec<usize>, String> {
    if scheme == TractionScheme::FaceShape {
        let why = match kind {
            FaceType::Quad8 => Some("negative"),
            FaceType::Tri6 => Some("zero"),
            _ => None,
        };
        if let Some(why) = why {
            return Err(format!(
                "traction scheme 1 (the face's own shape functions) is ill-posed on {} faces: the \
                 integral of a corner shape function over the face is {why}, so the nodal \
                 Kuhn-Tucker conditions (and the normalized gap g_A / a_A) cannot be enforced \
                 there; use scheme 2 (corner nodes) or 3 (piecewise linear over sub-segments)",
                kind.name()
            ));
        }
    }
    Ok((0..traction_node_count(kind, scheme)).collect())
}

/// Values of the traction shape functions Phi at a point given by its sub-segment index `sub`
/// (into [`sub_segments`]) and its parent coordinates `xi` on the face: `out[k]` is Phi of
/// `traction_nodes(kind, scheme)[k]`; `out` is resized to [`traction_node_count`].
///
/// FaceShape: the face's own N (also evaluated on Quad8 and Tri6, where [`traction_nodes`]
/// refuses the scheme). Corners: bilinear (quad) / linear (tri) in the corner nodes, at `xi`.
/// PiecewiseLinear: the sub-segment's own linear/bilinear functions of `xi` mapped into the
/// sub-segment's local coordinates; zero for nodes not on that sub-segment. `sub` is only used by
/// PiecewiseLinear.
///
/// # Panics
/// PiecewiseLinear with `sub >= sub_segments(kind).len()`.
pub fn traction_shape(
    kind: FaceType,
    scheme: TractionScheme,
    sub: usize,
    xi: [f64; 2],
    out: &mut Vec<f64>,
) {
    let index = if scheme == TractionScheme::PiecewiseLinear {
        sub
    } else {
        0
    };
    traction_shape_on(kind, scheme, &sub_segments(kind)[index], xi, out);
}

/// [`traction_shape`] with the sub-segment given directly (no table look-up or allocation of
/// the sub-segments): `segment` must be one of `sub_segments(kind)`.
pub fn traction_shape_on(
    kind: FaceType,
    scheme: TractionScheme,
    segment: &SubSegment,
    xi: [f64; 2],
    out: &mut Vec<f64>,
) {
    traction_shape_on_at(kind, scheme, segment, xi, out);
}

/// [`traction_shape_on`] for any [`Scalar`] (with a dual `xi`, `Phi` carries its derivatives).
pub fn traction_shape_on_at<T: Scalar>(
    kind: FaceType,
    scheme: TractionScheme,
    segment: &SubSegment,
    xi: [T; 2],
    out: &mut Vec<T>,
) {
    out.clear();
    out.resize(traction_node_count(kind, scheme), T::from(0.0));
    match scheme {
        TractionScheme::FaceShape => kind.shape_at(xi, out),
        TractionScheme::Corners => {
            let linear = if kind.is_quad() {
                FaceType::Quad4
            } else {
                FaceType::Tri3
            };
            linear.shape_at(xi, out);
        }
        TractionScheme::PiecewiseLinear => {
            let n = segment.linear_shape_at(segment.to_local_at(xi));
            for (&a, na) in segment.local_nodes.iter().zip(n) {
                out[a] = na;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::mortar::test_support::SCHEMES;

    fn shoelace(p: &[[f64; 2]]) -> f64 {
        0.5 * (0..p.len())
            .map(|i| {
                let (a, b) = (p[i], p[(i + 1) % p.len()]);
                a[0] * b[1] - a[1] * b[0]
            })
            .sum::<f64>()
    }

    fn parent_area(kind: FaceType) -> f64 {
        if kind.is_quad() {
            4.0
        } else {
            0.5
        }
    }

    /// `(parent point, weight)` pairs integrating exactly (degree 6) over each sub-segment.
    fn sub_segment_points(kind: FaceType) -> Vec<(usize, [f64; 2], f64)> {
        let mut pts = Vec::new();
        for (s, seg) in sub_segments(kind).iter().enumerate() {
            let rule = seg.linear_kind().quadrature(6);
            for (p, w) in rule.points.iter().zip(&rule.weights) {
                pts.push((s, seg.to_parent(*p), w * seg.parent_jacobian()));
            }
        }
        pts
    }

    #[test]
    fn scheme_numbers_round_trip() {
        for s in SCHEMES {
            assert_eq!(TractionScheme::from_number(s.number()), Some(s));
        }
        assert_eq!(TractionScheme::from_number(0), None);
        assert_eq!(TractionScheme::from_number(4), None);
    }

    /// Sub-segments are counter-clockwise, their vertices are their nodes' parent coordinates,
    /// and they tile the parent domain (areas sum to 4 or 1/2, every node is used).
    #[test]
    fn sub_segments_tile_the_parent_domain() {
        for kind in FaceType::ALL {
            let coords = kind.node_coords();
            let segments = sub_segments(kind);
            let mut total = 0.0;
            let mut used = vec![false; kind.num_nodes()];
            for seg in &segments {
                for (&a, v) in seg.local_nodes.iter().zip(&seg.vertices) {
                    assert_eq!(coords[a], *v, "{kind:?}");
                    used[a] = true;
                }
                let area = shoelace(&seg.vertices);
                assert!(area > 0.0, "{kind:?}: clockwise sub-segment");
                let local_area = if seg.vertices.len() == 4 { 4.0 } else { 0.5 };
                assert!((seg.parent_jacobian() * local_area - area).abs() < 1e-15);
                total += area;
            }
            assert!(
                (total - parent_area(kind)).abs() < 1e-15,
                "{kind:?}: {total}"
            );
            // Quad8 has no centre node; every other node is a sub-segment vertex.
            assert!(used.iter().all(|&u| u), "{kind:?}: unused node");
        }
        let counts: Vec<usize> = FaceType::ALL
            .iter()
            .map(|&k| sub_segments(k).len())
            .collect();
        assert_eq!(counts, vec![1, 5, 4, 1, 4]);
    }

    /// The local/parent maps of every sub-segment invert each other and send the local vertices
    /// to the vertices.
    #[test]
    fn sub_segment_maps_invert_each_other() {
        for kind in FaceType::ALL {
            for seg in sub_segments(kind) {
                let local_vertices = seg.linear_kind().node_coords();
                for (lv, v) in local_vertices.iter().zip(&seg.vertices) {
                    let p = seg.to_parent(*lv);
                    assert!((p[0] - v[0]).abs() < 1e-15 && (p[1] - v[1]).abs() < 1e-15);
                    let back = seg.to_local(*v);
                    assert!((back[0] - lv[0]).abs() < 1e-15 && (back[1] - lv[1]).abs() < 1e-15);
                }
                let q = seg.to_local([0.123, -0.0456]);
                let p = seg.to_parent(q);
                assert!((p[0] - 0.123).abs() < 1e-15 && (p[1] + 0.0456).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn traction_nodes_per_scheme() {
        for kind in FaceType::ALL {
            let all: Vec<usize> = (0..kind.num_nodes()).collect();
            let corners: Vec<usize> = (0..kind.num_corners()).collect();
            assert_eq!(
                traction_nodes(kind, TractionScheme::Corners).unwrap(),
                corners
            );
            assert_eq!(
                traction_nodes(kind, TractionScheme::PiecewiseLinear).unwrap(),
                all
            );
            match kind {
                FaceType::Quad8 | FaceType::Tri6 => {
                    let err = traction_nodes(kind, TractionScheme::FaceShape).unwrap_err();
                    assert!(err.contains("ill-posed"), "{err}");
                    assert!(err.contains(kind.name()), "{err}");
                }
                _ => assert_eq!(
                    traction_nodes(kind, TractionScheme::FaceShape).unwrap(),
                    all
                ),
            }
        }
    }

    /// Phi is a partition of unity at points spread over every sub-segment, for every scheme and
    /// face type (including scheme 1 on Quad8/Tri6, which is refused for another reason), and
    /// is non-negative for schemes 2 and 3.
    #[test]
    fn traction_shapes_sum_to_one() {
        let mut phi = Vec::new();
        for kind in FaceType::ALL {
            for scheme in SCHEMES {
                for (s, xi, _) in sub_segment_points(kind) {
                    traction_shape(kind, scheme, s, xi, &mut phi);
                    assert_eq!(phi.len(), traction_node_count(kind, scheme));
                    let sum: f64 = phi.iter().sum();
                    assert!((sum - 1.0).abs() < 1e-14, "{kind:?} {scheme:?}: {sum}");
                    if scheme != TractionScheme::FaceShape {
                        assert!(phi.iter().all(|&p| p >= -1e-15), "{kind:?} {scheme:?}");
                    }
                }
            }
        }
    }

    /// Scheme 3 is continuous across sub-segments: at every vertex of every sub-segment, Phi is the
    /// Kronecker delta of that node whatever sub-segment it is evaluated on.
    #[test]
    fn piecewise_linear_is_nodal() {
        let mut phi = Vec::new();
        for kind in FaceType::ALL {
            for (s, seg) in sub_segments(kind).iter().enumerate() {
                for (&a, v) in seg.local_nodes.iter().zip(&seg.vertices) {
                    traction_shape(kind, TractionScheme::PiecewiseLinear, s, *v, &mut phi);
                    for (b, p) in phi.iter().enumerate() {
                        let expected = if a == b { 1.0 } else { 0.0 };
                        assert!((p - expected).abs() < 1e-15, "{kind:?} sub {s} node {a}");
                    }
                }
            }
        }
    }

    /// `int Phi_A` over the parent domain taken as a flat face.
    fn traction_integrals(kind: FaceType, scheme: TractionScheme) -> Vec<f64> {
        let mut phi = Vec::new();
        let mut sums = vec![0.0; traction_node_count(kind, scheme)];
        for (s, xi, w) in sub_segment_points(kind) {
            traction_shape(kind, scheme, s, xi, &mut phi);
            for (sum, p) in sums.iter_mut().zip(&phi) {
                *sum += w * p;
            }
        }
        sums
    }

    /// Exact integrals of the traction functions over the flat parent face, per scheme, node
    /// class (corner, mid-edge, centre). They also show why scheme 1 is refused on Quad8 (corner
    /// integral -1/3 of 4, i.e. negative) and Tri6 (corner integral 0).
    #[test]
    fn exact_traction_integrals_on_a_flat_face() {
        use FaceType::*;
        use TractionScheme::*;
        // (kind, scheme, [corner, mid-edge, centre]) integrals.
        let table: [(FaceType, TractionScheme, [f64; 3]); 15] = [
            (Quad4, FaceShape, [1.0, 0.0, 0.0]),
            (Quad4, Corners, [1.0, 0.0, 0.0]),
            (Quad4, PiecewiseLinear, [1.0, 0.0, 0.0]),
            (Quad8, FaceShape, [-1.0 / 3.0, 4.0 / 3.0, 0.0]),
            (Quad8, Corners, [1.0, 0.0, 0.0]),
            (Quad8, PiecewiseLinear, [1.0 / 6.0, 5.0 / 6.0, 0.0]),
            (Quad9, FaceShape, [1.0 / 9.0, 4.0 / 9.0, 16.0 / 9.0]),
            (Quad9, Corners, [1.0, 0.0, 0.0]),
            (Quad9, PiecewiseLinear, [0.25, 0.5, 1.0]),
            (Tri3, FaceShape, [1.0 / 6.0, 0.0, 0.0]),
            (Tri3, Corners, [1.0 / 6.0, 0.0, 0.0]),
            (Tri3, PiecewiseLinear, [1.0 / 6.0, 0.0, 0.0]),
            (Tri6, FaceShape, [0.0, 1.0 / 6.0, 0.0]),
            (Tri6, Corners, [1.0 / 6.0, 0.0, 0.0]),
            (Tri6, PiecewiseLinear, [1.0 / 24.0, 1.0 / 8.0, 0.0]),
        ];
        for (kind, scheme, expected) in table {
            let integrals = traction_integrals(kind, scheme);
            let nc = kind.num_corners();
            for (a, value) in integrals.iter().enumerate() {
                let class = if a < nc {
                    0
                } else if a < 2 * nc {
                    1
                } else {
                    2
                };
                assert!(
                    (value - expected[class]).abs() < 1e-14,
                    "{kind:?} {scheme:?} node {a}: {value} != {}",
                    expected[class]
                );
            }
            let total: f64 = integrals.iter().sum();
            assert!((total - parent_area(kind)).abs() < 1e-14);
            // Exactly the refused combinations have a non-positive integral.
            let ill_posed = integrals.iter().any(|&v| v <= 1e-14);
            assert_eq!(
                ill_posed,
                traction_nodes(kind, scheme).is_err(),
                "{kind:?} {scheme:?}: {integrals:?}"
            );
        }
    }
}
