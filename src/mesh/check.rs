//! Mesh validation.
//!
//! [`Mesh::check`] verifies array lengths, indices and element node counts, that elements
//! sharing an edge or face share its nodes, and that
//! `det J = det(sum_a x_a (dN_a/dxi)^T)` is positive at every node of every element and at its
//! centre (`xi = 0` for hexahedra, `(1/4, 1/4, 1/4)` for tetrahedra).

use std::collections::HashMap;

use crate::error::{Error, Result};
use crate::fe::ElementType;
use crate::mesh::Mesh;

/// `det(sum_a x_a (dN_a/dxi)^T)` of the nodes `x` (by index) with shape-function gradients `dn`.
pub(crate) fn jacobian_determinant(x: impl Fn(usize) -> [f64; 3], dn: &[[f64; 3]]) -> f64 {
    let mut j = [[0.0; 3]; 3];
    for (a, g) in dn.iter().enumerate() {
        let xa = x(a);
        for r in 0..3 {
            for c in 0..3 {
                j[r][c] += xa[r] * g[c];
            }
        }
    }
    j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
        - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
        + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0])
}

impl Mesh {
    /// Validates the mesh: array lengths, connectivity indices, element node counts, body and
    /// set indices, finite coordinates, conforming elements (shared edges and faces share
    /// their nodes), and a positive Jacobian determinant at every node and the centre of every
    /// element. Element indices in messages are 0-based.
    pub fn check(&self) -> Result<()> {
        self.check_labelled(&|e| format!("element {e}"))
    }

    /// [`Mesh::check`] with elements named by `label(e)` (e.g. with their Gmsh tags).
    pub(crate) fn check_labelled(&self, label: &dyn Fn(usize) -> String) -> Result<()> {
        self.check_arrays()?;
        self.check_coordinates()?;
        self.check_elements(label)?;
        self.check_sets(label)?;
        self.check_conforming(label)?;
        self.check_jacobians(label)
    }

    /// Describes element `e` for messages: `element 17 (hex8, body 'top')`.
    fn describe_element(&self, e: usize, label: &dyn Fn(usize) -> String) -> String {
        let body = self
            .body
            .get(e)
            .and_then(|&b| self.bodies.get(b))
            .map(|s| s.as_str())
            .unwrap_or("?");
        format!("{} ({}, body '{body}')", label(e), self.types[e].name())
    }

    /// The element arrays agree in length and the offsets span the connectivity.
    fn check_arrays(&self) -> Result<()> {
        let ne = self.num_elements();
        if self.offsets.len() != ne + 1 || self.body.len() != ne {
            return Err(Error::Mesh(format!(
                "inconsistent arrays: {ne} element types, {} bodies of elements, {} offsets",
                self.body.len(),
                self.offsets.len()
            )));
        }
        if self.offsets[0] != 0 || *self.offsets.last().unwrap_or(&0) != self.conn.len() {
            return Err(Error::Mesh(format!(
                "offsets must run from 0 to the connectivity length {}",
                self.conn.len()
            )));
        }
        Ok(())
    }

    /// Every coordinate is finite and within the accepted magnitude.
    fn check_coordinates(&self) -> Result<()> {
        for (i, x) in self.coords.iter().enumerate() {
            if !x.iter().all(|&v| crate::within_bounds(v)) {
                return Err(Error::Mesh(format!(
                    "node {i} has coordinates {x:?}: not finite or beyond +-{:e}",
                    crate::MAX_MAGNITUDE
                )));
            }
        }
        Ok(())
    }

    /// Every element has sound offsets, a body, its type's node count and existing nodes.
    fn check_elements(&self, label: &dyn Fn(usize) -> String) -> Result<()> {
        let nn = self.num_nodes();
        for e in 0..self.num_elements() {
            let (a, b) = (self.offsets[e], self.offsets[e + 1]);
            if b < a || b > self.conn.len() {
                return Err(Error::Mesh(format!(
                    "element {e}: bad connectivity offsets {a}..{b}"
                )));
            }
            if self.body[e] >= self.bodies.len() {
                return Err(Error::Mesh(format!(
                    "{} ({}) has body index {} but there are {} bodies",
                    label(e),
                    self.types[e].name(),
                    self.body[e],
                    self.bodies.len()
                )));
            }
            let kind = self.types[e];
            if b - a != kind.num_nodes() {
                return Err(Error::Mesh(format!(
                    "{} has {} nodes, expected {}",
                    self.describe_element(e, label),
                    b - a,
                    kind.num_nodes()
                )));
            }
            for (k, &n) in self.element_nodes(e).iter().enumerate() {
                if n >= nn {
                    return Err(Error::Mesh(format!(
                        "{}: its node {k} is node {n}, but the mesh has {nn} nodes",
                        self.describe_element(e, label)
                    )));
                }
            }
        }
        Ok(())
    }

    /// Every node, element and face set refers to existing nodes, elements and faces.
    fn check_sets(&self, label: &dyn Fn(usize) -> String) -> Result<()> {
        let (nn, ne) = (self.num_nodes(), self.num_elements());
        for (name, v) in &self.node_sets {
            if let Some(&n) = v.iter().find(|&&n| n >= nn) {
                return Err(Error::Mesh(format!(
                    "node set '{name}' contains node {n}, but the mesh has {nn} nodes"
                )));
            }
        }
        for (name, v) in &self.element_sets {
            if let Some(&e) = v.iter().find(|&&e| e >= ne) {
                return Err(Error::Mesh(format!(
                    "element set '{name}' contains element {e}, but the mesh has {ne} elements"
                )));
            }
        }
        for (name, v) in &self.face_sets {
            for f in v {
                if f.element >= ne {
                    return Err(Error::Mesh(format!(
                        "face set '{name}' refers to element {}, but the mesh has {ne} elements",
                        f.element
                    )));
                }
                if f.face >= self.types[f.element].num_faces() {
                    return Err(Error::Mesh(format!(
                        "face set '{name}' refers to face {} of {}, which has {} faces",
                        f.face,
                        self.describe_element(f.element, label),
                        self.types[f.element].num_faces()
                    )));
                }
            }
        }
        Ok(())
    }

    /// A positive Jacobian determinant at every node and the centre of every element.
    fn check_jacobians(&self, label: &dyn Fn(usize) -> String) -> Result<()> {
        let mut dn = vec![[0.0; 3]; 27];
        let mut points: HashMap<ElementType, Vec<[f64; 3]>> = HashMap::new();
        for e in 0..self.num_elements() {
            let kind = self.types[e];
            let pts = points.entry(kind).or_insert_with(|| {
                let mut p = kind.node_coords();
                p.push(if kind.is_hex() { [0.0; 3] } else { [0.25; 3] });
                p
            });
            let en = self.element_nodes(e);
            let dn = &mut dn[..kind.num_nodes()];
            for (k, &xi) in pts.iter().enumerate() {
                kind.shape_grad(xi, dn);
                let det = jacobian_determinant(|a| self.coords[en[a]], dn);
                if det.is_nan() || det <= 0.0 {
                    let at = if k < kind.num_nodes() {
                        format!("its node {k} (mesh node {})", en[k])
                    } else {
                        "its centre".to_string()
                    };
                    return Err(Error::Mesh(format!(
                        "{} is inverted: det J = {det:e} at {at}",
                        self.describe_element(e, label)
                    )));
                }
            }
        }
        Ok(())
    }

    /// Elements that share an edge (its two corner nodes) share its nodes, the same mid-edge
    /// node or none, and quadrilateral faces that share their corners share their centre node
    /// or have none: a linear element against a quadratic one (Hex8 against Hex20, Tet4 against
    /// Tet10), a Hex20 face against a Hex27 one, or quadratic elements whose mid-edge nodes were
    /// not merged would leave a crack in the body. (A ring of quadratic elements only two
    /// around, whose two edges join the same corners, would be refused too.) Only meshes with
    /// quadratic elements are checked (linear ones have nothing to disagree on), and faces
    /// only with Hex27 among them.
    fn check_conforming(&self, label: &dyn Fn(usize) -> String) -> Result<()> {
        if self.types.iter().all(|t| t.order() == 1) {
            return Ok(());
        }
        let with_centres = self.types.contains(&ElementType::Hex27);
        let mismatch = |e: usize, other: usize, what: String| {
            Error::Mesh(format!(
                "{} and {} share {what} but not its nodes (mixed element orders or unmerged \
                 nodes: the mesh would crack there)",
                self.describe_element(other, label),
                self.describe_element(e, label)
            ))
        };
        let mut edges: HashMap<(usize, usize), (usize, Option<usize>)> = HashMap::new();
        let mut faces: HashMap<[usize; 4], (usize, Option<usize>)> = HashMap::new();
        for e in 0..self.num_elements() {
            let kind = self.types[e];
            let en = self.element_nodes(e);
            for (k, &[a, b]) in kind.edges().iter().enumerate() {
                let key = (en[a].min(en[b]), en[a].max(en[b]));
                let mid = (kind.order() == 2).then(|| en[kind.num_corners() + k]);
                let (other, theirs) = *edges.entry(key).or_insert((e, mid));
                if theirs != mid {
                    let what = format!("the edge between nodes {} and {}", key.0, key.1);
                    return Err(mismatch(e, other, what));
                }
            }
            if with_centres && kind.is_hex() {
                for f in 0..kind.num_faces() {
                    let nodes = kind.face_nodes(f);
                    let mut key = [en[nodes[0]], en[nodes[1]], en[nodes[2]], en[nodes[3]]];
                    key.sort_unstable();
                    let centre = (kind == ElementType::Hex27).then(|| en[20 + f]);
                    let (other, theirs) = *faces.entry(key).or_insert((e, centre));
                    if theirs != centre {
                        let what = format!("the face with corner nodes {key:?}");
                        return Err(mismatch(e, other, what));
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::box_mesh;
    use crate::mesh::FaceRef;

    /// Two elements of a `kind` box sharing a face, the first cut down to its first `keep`
    /// nodes and made a `first` (Hex27 -> Hex20 -> Hex8 keep the leading nodes, VTK's order).
    fn two_with_first_as(kind: ElementType, first: ElementType) -> Mesh {
        let mut m = box_mesh(kind, [2, 1, 1], [0.0; 3], [2.0, 1.0, 1.0], "b");
        let keep = first.num_nodes();
        let mut conn = m.element_nodes(0)[..keep].to_vec();
        conn.extend_from_slice(m.element_nodes(1));
        m.types[0] = first;
        m.offsets = vec![0, keep, conn.len()];
        m.conn = conn;
        m
    }

    /// The message of the check of `m`, which fails.
    fn check_error(m: Mesh) -> String {
        m.check().unwrap_err().to_string()
    }

    #[test]
    fn elements_of_mixed_orders_sharing_nodes_are_refused() {
        let e = check_error(two_with_first_as(ElementType::Hex20, ElementType::Hex8));
        assert!(
            e.contains("element 0 (hex8") && e.contains("element 1 (hex20") && e.contains("edge"),
            "{e}"
        );
        // The same edges, but a face with a centre node on one side only.
        let e = check_error(two_with_first_as(ElementType::Hex27, ElementType::Hex20));
        assert!(
            e.contains("hex20") && e.contains("hex27") && e.contains("face"),
            "{e}"
        );
        // The control: both kept whole.
        two_with_first_as(ElementType::Hex27, ElementType::Hex27)
            .check()
            .unwrap();
    }

    #[test]
    fn check_reports_inverted_elements_and_bad_indices() {
        let mut m = box_mesh(ElementType::Hex8, [2, 1, 1], [0.0; 3], [1.0; 3], "top");
        let (a, b) = (m.offsets[1], m.offsets[1] + 4);
        // Swap bottom and top faces of element 1: inverted.
        for k in 0..4 {
            m.conn.swap(a + k, b + k);
        }
        let e = check_error(m);
        assert!(
            e.contains("element 1 (hex8, body 'top') is inverted"),
            "{e}"
        );
        assert!(e.contains("at its node 0"), "{e}");
        let mut m = box_mesh(ElementType::Tet10, [1, 1, 1], [0.0; 3], [1.0; 3], "b");
        m.conn[3] = 999;
        assert!(check_error(m).contains("element 0 (tet10"));
        let mut m = box_mesh(ElementType::Tet4, [1, 1, 1], [0.0; 3], [1.0; 3], "b");
        m.node_sets.get_mut("xmin").unwrap().push(100);
        assert!(check_error(m).contains("node set 'xmin'"));
        let mut m = box_mesh(ElementType::Tet4, [1, 1, 1], [0.0; 3], [1.0; 3], "b");
        m.face_sets.get_mut("zmax").unwrap().push(FaceRef {
            element: 0,
            face: 4,
        });
        assert!(check_error(m).contains("face set 'zmax'"));
    }
}
