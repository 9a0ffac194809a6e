//! Meshes: nodes, elements of several types and bodies, and named node, face and element sets.
//!
//! A mesh is held whole on every rank (it is small next to the matrices: the partition decides
//! which rank assembles which element and owns which matrix rows; see `crate::dofs`). Generators
//! ([`generate`]) and the Gmsh reader (`crate::io::gmsh`) both produce this type; parts are
//! joined by [`Mesh::merge`] ([`merge`]) and validated by [`Mesh::check`] ([`check`]).

pub mod check;
pub mod generate;
pub mod merge;
pub mod partition;
#[cfg(test)]
mod test_support;

use std::collections::BTreeMap;

use crate::error::{Error, Result};
use crate::fe::{ElementType, FaceType};

/// One face of one element: `(element index, local face index)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FaceRef {
    pub element: usize,
    pub face: usize,
}

/// An unstructured mesh of solid elements.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Reference coordinates of every node.
    pub coords: Vec<[f64; 3]>,
    /// Type of every element.
    pub types: Vec<ElementType>,
    /// Body index of every element (into `bodies`).
    pub body: Vec<usize>,
    /// Flat connectivity; element `e` has nodes `conn[offsets[e]..offsets[e + 1]]` (VTK order).
    pub conn: Vec<usize>,
    /// Offsets into `conn`, length `num_elements() + 1`.
    pub offsets: Vec<usize>,
    /// Body names.
    pub bodies: Vec<String>,
    /// Named node sets (sorted, unique node indices).
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Named face sets (sorted, unique).
    pub face_sets: BTreeMap<String, Vec<FaceRef>>,
    /// Named element sets (sorted, unique element indices).
    pub element_sets: BTreeMap<String, Vec<usize>>,
}

impl Mesh {
    /// An empty mesh with `offsets = [0]`.
    pub fn new() -> Mesh {
        Mesh {
            offsets: vec![0],
            ..Default::default()
        }
    }

    /// Number of nodes.
    pub fn num_nodes(&self) -> usize {
        self.coords.len()
    }

    /// Number of elements.
    pub fn num_elements(&self) -> usize {
        self.types.len()
    }

    /// Nodes of element `e`.
    pub fn element_nodes(&self, e: usize) -> &[usize] {
        &self.conn[self.offsets[e]..self.offsets[e + 1]]
    }

    /// Appends an element and returns its index.
    pub fn push_element(&mut self, kind: ElementType, body: usize, nodes: &[usize]) -> usize {
        debug_assert_eq!(nodes.len(), kind.num_nodes());
        self.types.push(kind);
        self.body.push(body);
        self.conn.extend_from_slice(nodes);
        self.offsets.push(self.conn.len());
        self.types.len() - 1
    }

    /// Global node indices of a face, in the face type's ordering.
    pub fn face_nodes(&self, f: FaceRef) -> Vec<usize> {
        let en = self.element_nodes(f.element);
        self.types[f.element]
            .face_nodes(f.face)
            .into_iter()
            .map(|k| en[k])
            .collect()
    }

    /// Type of a face.
    pub fn face_type(&self, f: FaceRef) -> FaceType {
        self.types[f.element].face_type()
    }

    /// Reference coordinates of the nodes of element `e`.
    pub fn element_coords(&self, e: usize) -> Vec<[f64; 3]> {
        self.element_nodes(e)
            .iter()
            .map(|&n| self.coords[n])
            .collect()
    }

    /// A node set by name, or an error naming the set and what exists.
    pub fn node_set(&self, name: &str) -> Result<&[usize]> {
        named_set(&self.node_sets, "node", name)
    }

    /// A face set by name, or an error naming the set and what exists.
    pub fn face_set(&self, name: &str) -> Result<&[FaceRef]> {
        named_set(&self.face_sets, "face", name)
    }

    /// The nodes of a node set, or of a face set of that name (all nodes of its faces), sorted.
    pub fn nodes_of_set(&self, name: &str) -> Result<Vec<usize>> {
        if let Some(n) = self.node_sets.get(name) {
            return Ok(n.clone());
        }
        if let Some(fs) = self.face_sets.get(name) {
            let mut nodes: Vec<usize> = fs.iter().flat_map(|&f| self.face_nodes(f)).collect();
            nodes.sort_unstable();
            nodes.dedup();
            return Ok(nodes);
        }
        let mut have: Vec<String> = self.node_sets.keys().cloned().collect();
        have.extend(self.face_sets.keys().cloned());
        have.sort();
        have.dedup();
        Err(Error::Mesh(format!(
            "no node or face set '{name}' (have: {})",
            have.join(", ")
        )))
    }
}

/// The set `name` of `sets`, or an error naming the set, its kind (`what`: "node", "face") and
/// the sets there are.
fn named_set<'a, T>(sets: &'a BTreeMap<String, Vec<T>>, what: &str, name: &str) -> Result<&'a [T]> {
    sets.get(name).map(|v| v.as_slice()).ok_or_else(|| {
        Error::Mesh(format!(
            "no {what} set '{name}' (have: {})",
            sets.keys().cloned().collect::<Vec<_>>().join(", ")
        ))
    })
}
