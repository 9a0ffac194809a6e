//! Mapped blocks and the boxes built on them.
//!
//! # Mapped blocks
//!
//! Every generator is built on [`mapped_block`]: a structured block over the unit parameter cube
//! `u = (u0, u1, u2) in [0, 1]^3` with `div = [n0, n1, n2]` cells, mapped to space by a
//! user-supplied `map: u -> x`. The nodes are the points of a lattice with `p n_d + 1` points
//! along direction `d`, where `p` is the element order (1 for Hex8/Tet4, 2 for the quadratic
//! types): lattice point `(i, j, k)` sits at `u = (i / (p n0), j / (p n1), k / (p n2))` and at
//! `x = map(u)`. **Every** node, mid-edge, face and centre nodes included, is mapped, so quadratic
//! elements reproduce a curved geometry (to interpolation accuracy) rather than being straight
//! sided. Only lattice points used by some element become mesh nodes (Hex20 uses no face or cell
//! centre points), numbered compactly in lattice order (`i` fastest, then `j`, then `k`).
//!
//! Cell `(a, b, c)` spans lattice points `p (a, b, c) .. p (a + 1, b + 1, c + 1)`.
//!
//! - **Hexahedra**: one element per cell with parametric axes `xi, eta, zeta` along `u0, u1, u2`;
//!   element node `k` with parametric coordinates `xi_k in {-1, 0, 1}^3` is lattice point
//!   `p (a, b, c) + p (xi_k + 1) / 2`.
//! - **Tetrahedra**: each cell is split into six tetrahedra along its main diagonal
//!   (Kuhn/Freudenthal split): for every permutation `s` of the three axes the tetrahedron
//!   `v0 = 0, v1 = e_s0, v2 = e_s0 + e_s1, v3 = (1, 1, 1)` (cell-local unit coordinates), with
//!   `v1, v2` swapped for odd permutations so that `det[v1 - v0, v2 - v0, v3 - v0] = +1`. The
//!   split is translation invariant, hence conforming across cells. A node with simplex
//!   coordinates `(xi, eta, zeta)` is the lattice point `p (a, b, c) + p (v0 + xi (v1 - v0) +
//!   eta (v2 - v0) + zeta (v3 - v0))`; the edges of the split are the seven directions `e_S`
//!   (`S` a non-empty subset of the axes), so Tet10 uses every point of the `2 n + 1` lattice.
//!
//! All elements have positive Jacobian determinant as long as `map` preserves orientation
//! (`det(dx/du) > 0`).
//!
//! Named sets: face sets and node sets `"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"` are the
//! sides `u0 = 0, u0 = 1, u1 = 0, ...` of the **parameter** cube (for [`box_mesh`] these are the
//! planes `x = lo[0]`, `x = hi[0]`, ...). A face belongs to a side when all its corners do.
//!
//! # Graded boxes
//!
//! [`zoned_box_mesh`] puts the cell corners along each axis at
//! `x = lo + (hi - lo) expm1(beta u) / expm1(beta)` ([`exp_grading`](super::exp_grading)), so the cells grow in a
//! constant ratio from `lo` to `hi` and the last is `grading` times the first
//! (`beta = ln(grading) n / (n - 1)` for `n` cells; OpenFOAM's expansion ratio), or keeps the
//! cells uniform over a zone at the fine end first ([`ZoneGrading`]). Inside a cell the map is linear: the elements are straight-sided boxes,
//! with the mid-nodes of quadratic elements halfway along their edges.

use std::collections::BTreeMap;

use super::grading::ZoneGrading;
use crate::fe::ElementType;
use crate::mesh::{FaceRef, Mesh};

/// Names of the six parameter-cube sides, in the order `(axis, min/max)`.
const SIDE_NAMES: [[&str; 2]; 3] = [["xmin", "xmax"], ["ymin", "ymax"], ["zmin", "zmax"]];

/// The six tetrahedra of the Kuhn split of a cell: the permutation `s` of the axes, and whether
/// it is odd.
const KUHN_PERMUTATIONS: [([usize; 3], bool); 6] = [
    ([0, 1, 2], false),
    ([1, 2, 0], false),
    ([2, 0, 1], false),
    ([0, 2, 1], true),
    ([2, 1, 0], true),
    ([1, 0, 2], true),
];

/// The lattice point nearest to `x` (in lattice steps).
fn to_lattice(x: [f64; 3]) -> [usize; 3] {
    let mut o = [0usize; 3];
    for d in 0..3 {
        o[d] = x[d].round() as usize;
    }
    o
}

/// Element-local lattice offsets of every sub-element of one cell, in units of lattice steps.
fn cell_offsets(kind: ElementType) -> Vec<Vec<[usize; 3]>> {
    let p = kind.order() as f64;
    let ref_coords = kind.node_coords();
    if kind.is_hex() {
        let to_cell = |xi: &[f64; 3]| {
            to_lattice([
                p * (xi[0] + 1.0) / 2.0,
                p * (xi[1] + 1.0) / 2.0,
                p * (xi[2] + 1.0) / 2.0,
            ])
        };
        return vec![ref_coords.iter().map(to_cell).collect()];
    }
    KUHN_PERMUTATIONS
        .iter()
        .map(|&(s, odd)| {
            let mut v = [[0.0f64; 3]; 4];
            v[1][s[0]] = 1.0;
            v[2][s[0]] = 1.0;
            v[2][s[1]] = 1.0;
            v[3] = [1.0; 3];
            if odd {
                v.swap(1, 2);
            }
            ref_coords
                .iter()
                .map(|xi| {
                    let mut x = [0.0; 3];
                    for d in 0..3 {
                        x[d] = p
                            * (v[0][d]
                                + xi[0] * (v[1][d] - v[0][d])
                                + xi[1] * (v[2][d] - v[0][d])
                                + xi[2] * (v[3][d] - v[0][d]));
                    }
                    to_lattice(x)
                })
                .collect()
        })
        .collect()
}

/// The node lattice of a block: `m[d] = p div[d] + 1` points along axis `d`.
struct Lattice {
    m: [usize; 3],
}

impl Lattice {
    /// Linear index of lattice point `l` (`l[0]` fastest).
    fn index(&self, l: [usize; 3]) -> usize {
        l[0] + self.m[0] * (l[1] + self.m[1] * l[2])
    }

    /// Every element of the block as its lattice points, cell by cell (`a` fastest).
    fn elements(kind: ElementType, div: [usize; 3]) -> Vec<Vec<[usize; 3]>> {
        let p = kind.order();
        let offsets = cell_offsets(kind);
        let mut elems = Vec::new();
        for c in 0..div[2] {
            for b in 0..div[1] {
                for a in 0..div[0] {
                    let base = [p * a, p * b, p * c];
                    for sub in &offsets {
                        elems.push(
                            sub.iter()
                                .map(|o| [base[0] + o[0], base[1] + o[1], base[2] + o[2]])
                                .collect(),
                        );
                    }
                }
            }
        }
        elems
    }

    /// Numbers the lattice points used by `elems` compactly in lattice order, appending their
    /// mapped positions to `mesh.coords` and returning the node of each lattice point
    /// (`usize::MAX` where unused) with the node sets of the parameter-cube sides.
    fn number_nodes(
        &self,
        elems: &[Vec<[usize; 3]>],
        map: impl Fn([f64; 3]) -> [f64; 3],
        mesh: &mut Mesh,
    ) -> (Vec<usize>, BTreeMap<String, Vec<usize>>) {
        let m = self.m;
        let mut id = vec![usize::MAX; m[0] * m[1] * m[2]];
        for e in elems {
            for &l in e {
                id[self.index(l)] = 0;
            }
        }
        let mut node_sets: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        let mut count = 0;
        for k in 0..m[2] {
            for j in 0..m[1] {
                for i in 0..m[0] {
                    let l = [i, j, k];
                    let li = self.index(l);
                    if id[li] == usize::MAX {
                        continue;
                    }
                    id[li] = count;
                    let u = [
                        i as f64 / (m[0] - 1) as f64,
                        j as f64 / (m[1] - 1) as f64,
                        k as f64 / (m[2] - 1) as f64,
                    ];
                    mesh.coords.push(map(u));
                    for (d, names) in SIDE_NAMES.iter().enumerate() {
                        for (side, end) in [(0, 0), (1, m[d] - 1)] {
                            if l[d] == end {
                                node_sets.entry(names[side].into()).or_default().push(count);
                            }
                        }
                    }
                    count += 1;
                }
            }
        }
        (id, node_sets)
    }

    /// Pushes the elements onto `mesh` (body 0, nodes from `id`) and returns the face sets of
    /// the parameter-cube sides.
    fn push_elements(
        &self,
        kind: ElementType,
        elems: &[Vec<[usize; 3]>],
        id: &[usize],
        mesh: &mut Mesh,
    ) -> BTreeMap<String, Vec<FaceRef>> {
        let mut face_sets: BTreeMap<String, Vec<FaceRef>> = BTreeMap::new();
        let nc_face = kind.face_type().num_corners();
        let mut nodes = Vec::with_capacity(kind.num_nodes());
        for e in elems {
            nodes.clear();
            nodes.extend(e.iter().map(|&l| id[self.index(l)]));
            let element = mesh.push_element(kind, 0, &nodes);
            for face in 0..kind.num_faces() {
                let corners = &kind.face_nodes(face)[..nc_face];
                for (d, names) in SIDE_NAMES.iter().enumerate() {
                    for (side, target) in [(0, 0), (1, self.m[d] - 1)] {
                        if corners.iter().all(|&c| e[c][d] == target) {
                            face_sets
                                .entry(names[side].into())
                                .or_default()
                                .push(FaceRef { element, face });
                        }
                    }
                }
            }
        }
        for v in face_sets.values_mut() {
            v.sort_unstable();
        }
        face_sets
    }
}

/// A structured block of `kind` elements over the unit parameter cube, mapped by `map`.
///
/// `div` is the number of cells per parameter direction; see the module documentation for the
/// lattice, the tetrahedral split and the named sets. All elements belong to body `body`.
///
/// # Panics
/// If a division is zero (validate user input before calling).
pub fn mapped_block(
    kind: ElementType,
    div: [usize; 3],
    map: impl Fn([f64; 3]) -> [f64; 3],
    body: &str,
) -> Mesh {
    assert!(
        div.iter().all(|&n| n > 0),
        "mapped_block: every division must be positive, got {div:?}"
    );
    let p = kind.order();
    let lattice = Lattice {
        m: [p * div[0] + 1, p * div[1] + 1, p * div[2] + 1],
    };
    let elems = Lattice::elements(kind, div);
    let mut mesh = Mesh::new();
    mesh.bodies.push(body.to_string());
    let (id, node_sets) = lattice.number_nodes(&elems, map, &mut mesh);
    mesh.face_sets = lattice.push_elements(kind, &elems, &id, &mut mesh);
    mesh.node_sets = node_sets;
    mesh
}

/// A box `[lo, hi]` of `kind` elements with `div` cells per axis (affine [`mapped_block`]); the
/// sets `"xmin"`, ... are the planes `x = lo[0]`, ....
pub fn box_mesh(
    kind: ElementType,
    div: [usize; 3],
    lo: [f64; 3],
    hi: [f64; 3],
    body: &str,
) -> Mesh {
    zoned_box_mesh(kind, div, lo, hi, [1.0; 3], [0.0; 3], body)
}

/// A box `[lo, hi]` whose cells grow geometrically along each axis: along axis `d` the last
/// cell (at `hi[d]`) is `grading[d]` times as long as the first (at `lo[d]`), consecutive cells
/// in the constant ratio `grading[d]^(1 / (div[d] - 1))` (OpenFOAM's expansion ratio; 1 is
/// uniform, below 1 refines toward `hi`): the cell corners per axis are at
/// `x = lo + (hi - lo) expm1(beta u) / expm1(beta)` with `beta = ln(grading) n / (n - 1)`.
/// Sets as [`box_mesh`].
///
/// With a non-zero `zone[d]`, the first `zone[d]` of the length along axis `d`, counted from
/// the fine end (`lo` for a grading above 1, `hi` below 1), has uniform cells, then the cells
/// grow ([`ZoneGrading`]); the grading is then the spacing at the coarse end over the zone's
/// (the ratio of the continuous profile, near that of the end cells). The cell corners follow
/// the map and every cell is straight (mid-nodes halfway along the edges).
///
/// # Panics
/// If a division is zero, a grading is not finite and positive, or a zone is not in
/// `[0, hi - lo)` (validate user input first).
pub fn zoned_box_mesh(
    kind: ElementType,
    div: [usize; 3],
    lo: [f64; 3],
    hi: [f64; 3],
    grading: [f64; 3],
    zone: [f64; 3],
    body: &str,
) -> Mesh {
    assert!(
        grading.iter().all(|g| g.is_finite() && *g > 0.0),
        "graded box: grading must be finite and positive, got {grading:?}"
    );
    let shares: [f64; 3] = std::array::from_fn(|d| zone[d] / (hi[d] - lo[d]));
    // The cell corners along each axis; inside a cell the map is linear, so the elements are
    // straight-sided and the mid-nodes of quadratic elements sit at the middle of their edges
    // (the smooth map would push them toward the coarse end, by a lot in a steeply growing
    // cell).
    let corners: [Vec<f64>; 3] =
        std::array::from_fn(|d| graded_corners(div[d], grading[d], shares[d]));
    let along = |d: usize, u: f64| -> f64 {
        let c = &corners[d];
        let t = u * div[d] as f64;
        let i = (t.floor() as usize).min(div[d] - 1);
        c[i] + (t - i as f64) * (c[i + 1] - c[i])
    };
    mapped_block(
        kind,
        div,
        |u| {
            [
                lo[0] + along(0, u[0]) * (hi[0] - lo[0]),
                lo[1] + along(1, u[1]) * (hi[1] - lo[1]),
                lo[2] + along(2, u[2]) * (hi[2] - lo[2]),
            ]
        },
        body,
    )
}

/// The `n + 1` cell corners in `[0, 1]` along one axis of a box: growing by `grading` (refining
/// toward 0 for a grading above 1, toward 1 below), uniform over the fine `share` of the axis
/// first (none: the exact cell ratio).
///
/// # Panics
/// If `share` is not in `[0, 1)`.
fn graded_corners(n: usize, grading: f64, share: f64) -> Vec<f64> {
    // The map refines toward u = 0; a grading below 1 flips it.
    let (ratio, flip) = if grading >= 1.0 {
        (grading, false)
    } else {
        (1.0 / grading, true)
    };
    assert!(
        (0.0..1.0).contains(&share),
        "graded box: zone share {share} outside the axis length"
    );
    let g = if share == 0.0 {
        ZoneGrading::exact_cell_ratio(ratio, n)
    } else {
        ZoneGrading::new(ratio, share)
    };
    (0..=n)
        .map(|i| {
            let u = i as f64 / n as f64;
            if flip {
                1.0 - g.map(1.0 - u)
            } else {
                g.map(u)
            }
        })
        .collect()
}

/// A beam along the x axis: the box `[0, length] x [-width/2, width/2] x [-height/2, height/2]`
/// (the beam axis is the x axis, the cross-section centred on it).
pub fn beam(
    kind: ElementType,
    div: [usize; 3],
    length: f64,
    width: f64,
    height: f64,
    body: &str,
) -> Mesh {
    box_mesh(
        kind,
        div,
        [0.0, -0.5 * width, -0.5 * height],
        [length, 0.5 * width, 0.5 * height],
        body,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::test_support::{expected_nodes, set_coordinates, volume};

    const ALL: [ElementType; 5] = ElementType::ALL;

    #[test]
    fn boxes_of_every_type() {
        let div = [3, 2, 4];
        let (lo, hi) = ([-1.0, 0.5, 2.0], [2.0, 1.5, 2.5]);
        for kind in ALL {
            let m = box_mesh(kind, div, lo, hi, "b");
            m.check().unwrap();
            let per_cell = if kind.is_hex() { 1 } else { 6 };
            assert_eq!(m.num_elements(), 24 * per_cell);
            assert_eq!(m.num_nodes(), expected_nodes(kind, div), "{kind:?}");
            // Every node is used.
            let mut used = vec![false; m.num_nodes()];
            for &n in &m.conn {
                used[n] = true;
            }
            assert!(used.iter().all(|&u| u), "{kind:?}");
            assert!((volume(&m) - 3.0 * 1.0 * 0.5).abs() < 1e-12, "{kind:?}");
            let faces_per_cell = if kind.is_hex() { 1 } else { 2 };
            for (d, names) in SIDE_NAMES.iter().enumerate() {
                let ncells = div[(d + 1) % 3] * div[(d + 2) % 3];
                for (side, name) in names.iter().enumerate() {
                    let plane = if side == 0 { lo[d] } else { hi[d] };
                    let fs = m.face_set(name).unwrap();
                    assert_eq!(fs.len(), ncells * faces_per_cell, "{kind:?} {name}");
                    for &f in fs {
                        for n in m.face_nodes(f) {
                            assert!((m.coords[n][d] - plane).abs() < 1e-14);
                        }
                    }
                    let ns = m.node_set(name).unwrap();
                    let on_plane = (0..m.num_nodes())
                        .filter(|&n| (m.coords[n][d] - plane).abs() < 1e-14)
                        .count();
                    assert_eq!(ns.len(), on_plane, "{kind:?} {name}");
                    assert_eq!(m.nodes_of_set(name).unwrap().len(), on_plane);
                }
            }
        }
    }

    #[test]
    fn beam_is_centred_on_the_x_axis() {
        let m = beam(ElementType::Hex20, [4, 1, 2], 10.0, 1.0, 2.0, "beam");
        m.check().unwrap();
        assert!((volume(&m) - 20.0).abs() < 1e-11);
        for &n in m.node_set("xmin").unwrap() {
            assert_eq!(m.coords[n][0], 0.0);
        }
        for &n in m.node_set("zmax").unwrap() {
            assert_eq!(m.coords[n][2], 1.0);
        }
    }

    #[test]
    fn graded_box_cells_grow_geometrically() {
        for kind in [ElementType::Hex8, ElementType::Hex27, ElementType::Tet10] {
            let (lo, hi) = ([0.0, -1.0, -2.0], [1.0, 1.0, 0.0]);
            let m = zoned_box_mesh(kind, [4, 3, 5], lo, hi, [8.0, 1.0, 0.1], [0.0; 3], "b");
            m.check().unwrap();
            assert!((volume(&m) - 4.0).abs() < 1e-12, "{kind:?}");
            // The corner (vertex) coordinates along each axis.
            let p = kind.order();
            let xs = set_coordinates(&m, "ymin", 0);
            assert_eq!(xs.len(), 4 * p + 1);
            let cells: Vec<f64> = (0..4).map(|i| xs[p * (i + 1)] - xs[p * i]).collect();
            let q = 8f64.powf(1.0 / 3.0);
            for w in cells.windows(2) {
                assert!((w[1] / w[0] - q).abs() < 1e-12, "{cells:?}");
            }
            assert!((cells[3] / cells[0] - 8.0).abs() < 1e-11);
            let zs = set_coordinates(&m, "xmin", 2);
            let first = zs[p] - zs[0];
            let last = zs[5 * p] - zs[5 * p - p];
            assert!((last / first - 0.1).abs() < 1e-12);
            assert_eq!(zs[0], -2.0);
            assert_eq!(zs[5 * p], 0.0);
            // Uniform along y.
            let ys = set_coordinates(&m, "xmin", 1);
            for (i, y) in ys.iter().enumerate() {
                assert!((y - (-1.0 + 2.0 * i as f64 / (3 * p) as f64)).abs() < 1e-14);
            }
        }
        // Grading 1 is the plain box, bit for bit.
        let a = box_mesh(
            ElementType::Hex20,
            [2, 3, 4],
            [0.0; 3],
            [1.0, 2.0, 3.0],
            "b",
        );
        let b = zoned_box_mesh(
            ElementType::Hex20,
            [2, 3, 4],
            [0.0; 3],
            [1.0, 2.0, 3.0],
            [1.0; 3],
            [0.0; 3],
            "b",
        );
        assert_eq!(a.coords, b.coords);
    }

    #[test]
    fn zoned_box_keeps_uniform_cells_near_its_fine_end() {
        let m = zoned_box_mesh(
            ElementType::Hex8,
            [10, 2, 10],
            [0.0, 0.0, -1.0],
            [1.0, 1.0, 0.0],
            [10.0, 1.0, 0.1],
            [0.3, 0.0, 0.3],
            "b",
        );
        m.check().unwrap();
        assert!((volume(&m) - 1.0).abs() < 1e-12);
        // x from 0: equal cells up to 0.3, growing after.
        let xs = set_coordinates(&m, "ymin", 0);
        let cells: Vec<f64> = xs.windows(2).map(|w| w[1] - w[0]).collect();
        let k = xs.iter().filter(|&&x| x <= 0.3 + 1e-12).count() - 1;
        assert!(k >= 2);
        for c in &cells[..k - 1] {
            assert!((c - cells[0]).abs() < 1e-12, "{cells:?}");
        }
        assert!(
            cells[k + 1] > 1.05 * cells[0] && cells[9] > 3.0 * cells[0],
            "{cells:?}"
        );
        // z from the top (grading below 1): the same, mirrored.
        let zs = set_coordinates(&m, "xmin", 2);
        let cz: Vec<f64> = zs.windows(2).map(|w| w[1] - w[0]).rev().collect();
        for (a, b) in cz.iter().zip(&cells) {
            assert!((a - b).abs() < 1e-12, "{cz:?} {cells:?}");
        }
    }

    #[test]
    fn curved_block_mid_nodes_are_mapped() {
        // A quarter annulus: mid-edge nodes of the arcs lie on the circles.
        let map = |u: [f64; 3]| {
            let r = 1.0 + u[0];
            let t = std::f64::consts::FRAC_PI_2 * u[1];
            [r * t.cos(), r * t.sin(), u[2]]
        };
        for kind in ALL {
            let m = mapped_block(kind, [2, 4, 1], map, "ring");
            m.check().unwrap();
            for &n in m.node_set("xmin").unwrap() {
                let x = m.coords[n];
                assert!(((x[0] * x[0] + x[1] * x[1]).sqrt() - 1.0).abs() < 1e-14);
            }
            let exact = std::f64::consts::PI / 4.0 * 3.0;
            let tol = if kind.order() == 1 { 0.03 } else { 1e-3 };
            assert!((volume(&m) - exact).abs() / exact < tol, "{kind:?}");
        }
    }
}
