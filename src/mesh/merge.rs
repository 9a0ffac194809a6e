//! Merging meshes: appending one mesh to another, and merging the coincident nodes of parts that
//! touch.

use std::collections::HashMap;

use crate::mesh::{FaceRef, Mesh};

/// Sorts and removes duplicates.
fn sort_dedup<T: Ord>(v: &mut Vec<T>) {
    v.sort_unstable();
    v.dedup();
}

/// The distance between two points.
fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// A spatial hash of points with cells of size `h`: points closer than `h` are in the same or
/// neighbouring cells.
struct PointGrid {
    h: f64,
    cells: HashMap<[i64; 3], Vec<usize>>,
}

impl PointGrid {
    /// The cell of `x`.
    fn cell(&self, x: [f64; 3]) -> [i64; 3] {
        [
            (x[0] / self.h).floor() as i64,
            (x[1] / self.h).floor() as i64,
            (x[2] / self.h).floor() as i64,
        ]
    }

    /// The first point of `points` (in the cells' order, neighbours `x` fastest) within `h` of
    /// `x`, whose cell is `c`.
    fn find_close(&self, points: &[[f64; 3]], x: [f64; 3], c: [i64; 3]) -> Option<usize> {
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let Some(list) = self.cells.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    for &k in list {
                        let y = points[k];
                        let d2 =
                            (x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2);
                        if d2 <= self.h * self.h {
                            return Some(k);
                        }
                    }
                }
            }
        }
        None
    }
}

impl Mesh {
    /// Appends `other`: its nodes and elements follow this mesh's, bodies are matched by name
    /// (new names appended), and named sets of the same name are united. Nodes are not shared;
    /// see [`Mesh::merge_coincident_nodes`].
    pub fn merge(&mut self, other: Mesh) {
        let n0 = self.num_nodes();
        let e0 = self.num_elements();
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        let body_map: Vec<usize> = other
            .bodies
            .iter()
            .map(|name| match self.bodies.iter().position(|b| b == name) {
                Some(i) => i,
                None => {
                    self.bodies.push(name.clone());
                    self.bodies.len() - 1
                }
            })
            .collect();
        self.coords.extend_from_slice(&other.coords);
        for e in 0..other.num_elements() {
            let nodes: Vec<usize> = other.element_nodes(e).iter().map(|&n| n + n0).collect();
            self.push_element(other.types[e], body_map[other.body[e]], &nodes);
        }
        for (name, nodes) in other.node_sets {
            let v = self.node_sets.entry(name).or_default();
            v.extend(nodes.into_iter().map(|n| n + n0));
            sort_dedup(v);
        }
        for (name, faces) in other.face_sets {
            let v = self.face_sets.entry(name).or_default();
            v.extend(faces.into_iter().map(|f| FaceRef {
                element: f.element + e0,
                face: f.face,
            }));
            sort_dedup(v);
        }
        for (name, elems) in other.element_sets {
            let v = self.element_sets.entry(name).or_default();
            v.extend(elems.into_iter().map(|e| e + e0));
            sort_dedup(v);
        }
    }

    /// Shortest corner-to-corner element edge, or the bounding-box diagonal if there are no
    /// elements (0 for an empty mesh).
    pub(crate) fn min_edge_length(&self) -> f64 {
        let mut h = f64::INFINITY;
        for e in 0..self.num_elements() {
            let en = self.element_nodes(e);
            for ed in self.types[e].edges() {
                h = h.min(distance(self.coords[en[ed[0]]], self.coords[en[ed[1]]]));
            }
        }
        if h.is_finite() {
            return h;
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for x in &self.coords {
            for d in 0..3 {
                lo[d] = lo[d].min(x[d]);
                hi[d] = hi[d].max(x[d]);
            }
        }
        if self.coords.is_empty() {
            0.0
        } else {
            distance(lo, hi)
        }
    }

    /// Merges nodes closer than `tol * h`, `h` the shortest element edge (so `tol < 0.5` never
    /// merges two nodes of one element), keeping the first node of each cluster. Nodes are
    /// renumbered compactly in their original order; connectivity and node sets follow.
    pub fn merge_coincident_nodes(&mut self, tol: f64) {
        let abs_tol = tol * self.min_edge_length();
        if self.coords.is_empty() || abs_tol <= 0.0 || !abs_tol.is_finite() {
            return;
        }
        let mut grid = PointGrid {
            h: abs_tol,
            cells: HashMap::new(),
        };
        let n = self.num_nodes();
        let mut new_id = vec![0usize; n];
        let mut kept: Vec<[f64; 3]> = Vec::with_capacity(n);
        for (i, &x) in self.coords.iter().enumerate() {
            let c = grid.cell(x);
            new_id[i] = match grid.find_close(&kept, x, c) {
                Some(k) => k,
                None => {
                    kept.push(x);
                    grid.cells.entry(c).or_default().push(kept.len() - 1);
                    kept.len() - 1
                }
            };
        }
        self.coords = kept;
        for c in &mut self.conn {
            *c = new_id[*c];
        }
        for v in self.node_sets.values_mut() {
            for c in v.iter_mut() {
                *c = new_id[*c];
            }
            sort_dedup(v);
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::fe::ElementType;
    use crate::mesh::generate::box_mesh;
    use crate::mesh::test_support::{boundary_faces, volume};

    const ALL: [ElementType; 5] = ElementType::ALL;

    #[test]
    fn merging_touching_boxes_shares_the_interface() {
        for kind in ALL {
            let mut a = box_mesh(kind, [2, 2, 2], [0.0; 3], [1.0; 3], "a");
            let b = box_mesh(kind, [2, 2, 2], [1.0, 0.0, 0.0], [2.0, 1.0, 1.0], "b");
            let (na, nb) = (a.num_nodes(), b.num_nodes());
            let iface = b.node_set("xmin").unwrap().len();
            a.merge(b);
            assert_eq!(a.num_nodes(), na + nb);
            assert_eq!(a.bodies, vec!["a".to_string(), "b".to_string()]);
            // Sets of the same name are united: "xmin" holds x = 0 and the interface x = 1.
            let fpc = if kind.is_hex() { 1 } else { 2 };
            assert_eq!(a.face_set("xmin").unwrap().len(), 2 * 4 * fpc);
            a.merge_coincident_nodes(1e-6);
            a.check().unwrap();
            assert_eq!(a.num_nodes(), na + nb - iface, "{kind:?}");
            assert!((volume(&a) - 2.0).abs() < 1e-12);
            assert_eq!(boundary_faces(&a), 2 * (4 + 8 + 8) * fpc, "{kind:?}");
            // Node sets are renumbered: the interface x = 1 is in both "xmin" (of b) and "xmax".
            for &n in a.node_set("xmax").unwrap() {
                let x = a.coords[n][0];
                assert!(x == 1.0 || x == 2.0);
            }
        }
    }
}
