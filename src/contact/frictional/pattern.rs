//! The search for candidate face pairs, and the nodes each traction node couples in the
//! matrix pattern.

use crate::case::ContactMethod;
use crate::contact::search::{Aabb, PrimaryTree};
use crate::model::State;

use super::pass::{ContactPass, FaceData};
use super::{ContactInterfaces, PATTERN_MARGIN};

impl ContactInterfaces {
    /// Hands `couple` the nodes each traction node couples (its stencil, sorted, each node
    /// once): the pairs found at `at` with the margin [`PATTERN_MARGIN`] (module docs, "Matrix
    /// pattern"). Each node of a stencil couples to every other, so the work is the square of
    /// its length: the nodes that several faces share are handed once.
    pub(crate) fn stencils(&self, at: &State, couple: &mut dyn FnMut(&[usize])) {
        let x = at.positions();
        for pass in self.interfaces.iter().flat_map(|i| i.passes.iter()) {
            let stencils = match pass.method {
                ContactMethod::Mortar => pass.mortar_stencils(&x),
                ContactMethod::NodeOnSegment => pass.nts_stencils(&x),
            };
            for mut nodes in stencils {
                nodes.sort_unstable();
                nodes.dedup();
                couple(&nodes);
            }
        }
    }
}

impl ContactPass {
    /// Candidate primary faces (ascending) of each of `faces` (secondary indices) at positions
    /// `x`, with a search margin of `margin` box diagonals.
    pub(crate) fn candidates(
        &self,
        x: &[[f64; 3]],
        faces: &[usize],
        margin: f64,
    ) -> Vec<(usize, Vec<usize>)> {
        let coords = |f: &FaceData| -> Vec<[f64; 3]> { f.nodes.iter().map(|&n| x[n]).collect() };
        let tree = self.primary_tree(x);
        let mut found = Vec::new();
        faces
            .iter()
            .map(|&s| {
                let b = Aabb::of_points(&coords(&self.sec_faces[s]));
                tree.query(&b.inflated(margin * b.diagonal()), &mut found);
                let mut ms = found.clone();
                ms.sort_unstable();
                (s, ms)
            })
            .collect()
    }

    /// The search tree of the primary faces' boxes at positions `x`.
    pub(crate) fn primary_tree(&self, x: &[[f64; 3]]) -> PrimaryTree {
        let boxes: Vec<Aabb> = self
            .pri_faces
            .iter()
            .map(|f| Aabb::of_points(&f.nodes.iter().map(|&n| x[n]).collect::<Vec<_>>()))
            .collect();
        PrimaryTree::new(&boxes)
    }

    /// Mortar: the nodes each traction node couples (its faces and their candidate primary
    /// faces at the pattern margin), unsorted.
    pub(crate) fn mortar_stencils(&self, x: &[[f64; 3]]) -> Vec<Vec<usize>> {
        let all_faces: Vec<usize> = (0..self.sec_faces.len()).collect();
        let mut stencil: Vec<Vec<usize>> = vec![Vec::new(); self.nodes.len()];
        for (s, ms) in self.candidates(x, &all_faces, PATTERN_MARGIN) {
            let mut nodes: Vec<usize> = self.sec_faces[s].nodes.clone();
            for m in ms {
                nodes.extend(&self.pri_faces[m].nodes);
            }
            for &a in &self.carriers[s] {
                stencil[a].extend(&nodes);
            }
        }
        stencil
    }
}
