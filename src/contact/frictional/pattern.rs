//! The search for candidate face pairs, and the nodes each traction node couples in the
//! matrix pattern.

use std::borrow::Cow;

use crate::case::ContactMethod;
use crate::contact::search::{Aabb, PrimaryTree};
use crate::model::{merge_ascending, State};

use super::pass::{ContactPass, FaceData};
use super::{ContactInterfaces, EVAL_MARGIN};

impl ContactInterfaces {
    /// Hands `couple` the nodes each traction node couples (its stencil, sorted, each node
    /// once): the pairs an evaluation at `at` finds (module docs, "Matrix pattern"), which a
    /// mortar pass records as held by the pattern. Each node of a stencil couples to every
    /// other, so the work is the square of its length: the nodes that several faces share are
    /// handed once.
    pub(crate) fn stencils(&self, at: &State, couple: &mut dyn FnMut(&[usize])) {
        let x = at.positions();
        for pass in self.passes() {
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

    /// The matrix pattern is being made anew: no pair is held any more.
    pub(crate) fn forget_held_pairs(&self) {
        for pass in self.passes() {
            pass.held_pairs.borrow_mut().clear();
        }
    }

    /// Whether the pairs recorded as held by the matrix pattern include every pair this rank's
    /// evaluations at `at` find (node-on-segment passes: not tracked, true); every rank's
    /// answer together covers every face.
    pub(crate) fn holds_pairs_of(&self, at: &State) -> bool {
        let x = at.positions();
        self.passes()
            .filter(|pass| pass.method == ContactMethod::Mortar)
            .all(|pass| pass.holds_pairs_at(&x))
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
    /// faces, as an evaluation finds them), unsorted; the pairs are recorded as held.
    pub(crate) fn mortar_stencils(&self, x: &[[f64; 3]]) -> Vec<Vec<usize>> {
        let candidates = self.every_face_candidates(x);
        self.hold_pairs(&candidates);
        let mut stencil: Vec<Vec<usize>> = vec![Vec::new(); self.nodes.len()];
        for (s, ms) in candidates {
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

    /// Records `candidates` (per secondary face, its primary faces, ascending) as held by the
    /// matrix pattern.
    fn hold_pairs(&self, candidates: &[(usize, Vec<usize>)]) {
        let mut held = self.held_pairs.borrow_mut();
        held.resize(self.sec_faces.len(), Vec::new());
        for (s, ms) in candidates {
            merge_ascending(&mut held[*s], ms);
        }
    }

    /// The candidate primary faces of every secondary face at positions `x`, as the
    /// evaluations search ([`EVAL_MARGIN`]).
    pub(crate) fn every_face_candidates(&self, x: &[[f64; 3]]) -> Vec<(usize, Vec<usize>)> {
        let all_faces: Vec<usize> = (0..self.sec_faces.len()).collect();
        self.candidates(x, &all_faces, EVAL_MARGIN)
    }

    /// Whether every pair this rank's evaluations at positions `x` find (those of the faces it
    /// integrates) is recorded as held. Before a tangent the residual has searched at the same
    /// positions, and its candidates are taken from `last_values` instead of searching again.
    fn holds_pairs_at(&self, x: &[[f64; 3]]) -> bool {
        let last = self.last_values.borrow();
        let searched = match last.as_ref() {
            Some(v) if v.positions == self.surface_positions(x) => Cow::Borrowed(&v.candidates),
            _ => Cow::Owned(self.candidates(x, &self.local_faces, EVAL_MARGIN)),
        };
        let held = self.held_pairs.borrow();
        searched.iter().all(|(s, ms)| {
            let row = held.get(*s).map_or(&[][..], Vec::as_slice);
            ms.iter().all(|m| row.binary_search(m).is_ok())
        })
    }
}
