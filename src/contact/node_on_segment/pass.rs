//! The node-on-segment driver of a contact pass: each held secondary node against its closest
//! primary face, through the geometry and forces of the parent module, with the laws and the
//! bookkeeping (history, fields, blocks) of mortar contact's passes.

use crate::contact::frictional::{status_code, ContactPass, NodeFields};
use crate::contact::frictional::{EvalContext, Evaluation, NodeBlock, TOUCH_TOLERANCE};
use crate::contact::search::{Aabb, PrimaryTree};
use crate::error::Result;

use super::Segment;
use super::{closest, node_contribution, NodeContribution, NodeGeometry, NodeLaw, Projection};

/// Primary faces whose boxes come within this many `h_A` of the node are candidates for its
/// closest face.
pub const NTS_MARGIN: f64 = 0.5;

/// The search margin of the matrix pattern, in `h_A`.
pub const NTS_PATTERN_MARGIN: f64 = 1.0;

/// A node's closest primary face: its index, its current node positions and the projection.
struct Closest {
    face: usize,
    x: Vec<[f64; 3]>,
    projection: Projection,
}

impl ContactPass {
    /// The blocks of the held nodes of a node-on-segment pass; why the state cannot be
    /// evaluated (a non-finite force), if so.
    pub(crate) fn node_on_segment_blocks(
        &self,
        ctx: &EvalContext,
        evaluation: &Evaluation,
        sink: &mut dyn FnMut(&NodeBlock) -> Result<()>,
    ) -> Result<Option<String>> {
        let timed = evaluation.timed;
        let tree = timed.search.time(|| self.primary_tree(ctx.x));
        let failed = timed.assembly.time(|| -> Result<bool> {
            let mut states = Vec::new();
            for &a in &self.held {
                let (block, fields) = self.nts_node(ctx, &tree, a, evaluation.tangent);
                if evaluation.tangent {
                    states.push((a, fields.status));
                }
                if let Some(block) = block {
                    if block.force.iter().any(|v| !v.is_finite()) {
                        return Ok(true);
                    }
                    sink(&block)?;
                }
            }
            if evaluation.tangent {
                self.record_states(states);
            }
            Ok(false)
        })?;
        Ok(failed.then(|| "non-finite node-on-segment force".to_string()))
    }

    /// The nodes each node couples (itself, the primary faces within the pattern margin, and
    /// its old face), unsorted.
    pub(crate) fn nts_stencils(&self, x: &[[f64; 3]]) -> Vec<Vec<usize>> {
        let tree = self.primary_tree(x);
        let mut found = Vec::new();
        (0..self.nodes.len())
            .map(|a| {
                let node = self.nodes[a];
                let st = &self.state[a];
                tree.query(
                    &Aabb::of_points(&[x[node]]).inflated(NTS_PATTERN_MARGIN * st.h),
                    &mut found,
                );
                let mut nodes = vec![node];
                for &m in found.iter().chain(st.segment_old.iter().map(|(m, _)| m)) {
                    nodes.extend(&self.pri_faces[m].nodes);
                }
                nodes
            })
            .collect()
    }

    /// Forces (and tangent) of node `a` on its closest primary face, and its fields. `None`
    /// when no primary face lies under the node (its projection on every face within
    /// [`NTS_MARGIN`] `h_A` falls outside the face) or the node is open.
    pub(crate) fn nts_node(
        &self,
        ctx: &EvalContext,
        tree: &PrimaryTree,
        a: usize,
        tangent: bool,
    ) -> (Option<NodeBlock>, NodeFields) {
        let st = &self.state[a];
        let node = self.nodes[a];
        let Some(now) = self.closest_face(ctx, tree, a) else {
            return (None, NodeFields::default());
        };
        let old = st
            .segment_old
            .filter(|_| ctx.iface_mu > 0.0)
            .map(|(face, xi)| (face, self.face_positions(ctx, face), xi));
        let geo = NodeGeometry {
            x_node: ctx.x[node],
            segment: self.segment(now.face, &now.x),
            projection: now.projection,
            old: old
                .as_ref()
                .map(|(face, x, xi)| (self.segment(*face, x), *xi)),
        };
        let law = NodeLaw {
            history: &st.history,
            params: self.law_params(st, ctx.iface_mu, ctx.scale, 1.0),
            touch: TOUCH_TOLERANCE * st.h,
            area: st.a_full,
            stick_all: ctx.modes.stick_all,
        };
        let Some(c) = node_contribution(&geo, &law, tangent) else {
            return (None, NodeFields::default());
        };
        let fields = node_fields(&c, st.a_full, (now.face, now.projection.xi));
        if c.dp_dgh == 0.0 {
            return (None, fields);
        }
        let mut slots = vec![node];
        slots.extend(&self.pri_faces[now.face].nodes);
        if let Some((face, _, _)) = &old {
            slots.extend(&self.pri_faces[*face].nodes);
        }
        let block = NodeBlock {
            slots,
            force: c.force,
            tangent: c.tangent,
        };
        (Some(block), fields)
    }

    /// The closest primary face under traction node `a`, among the faces whose boxes come
    /// within [`NTS_MARGIN`] `h_A` of it.
    fn closest_face(&self, ctx: &EvalContext, tree: &PrimaryTree, a: usize) -> Option<Closest> {
        let p = ctx.x[self.nodes[a]];
        let mut found = Vec::new();
        tree.query(
            &Aabb::of_points(&[p]).inflated(NTS_MARGIN * self.state[a].h),
            &mut found,
        );
        let faces: Vec<(usize, Vec<[f64; 3]>)> = found
            .iter()
            .map(|&m| (m, self.face_positions(ctx, m)))
            .collect();
        let segments = faces.iter().map(|(m, xs)| (*m, self.segment(*m, xs)));
        let (face, projection) = closest(segments, p).filter(|(_, pr)| pr.inside)?;
        let x = faces.into_iter().find(|(k, _)| *k == face)?.1;
        Some(Closest {
            face,
            x,
            projection,
        })
    }

    /// The current positions of primary face `m`'s nodes.
    fn face_positions(&self, ctx: &EvalContext, m: usize) -> Vec<[f64; 3]> {
        self.pri_faces[m].nodes.iter().map(|&n| ctx.x[n]).collect()
    }

    /// Primary face `m` at the positions `x` of its nodes.
    fn segment<'a>(&self, m: usize, x: &'a [[f64; 3]]) -> Segment<'a> {
        Segment {
            kind: self.pri_faces[m].kind,
            x,
        }
    }
}

/// The fields of a node with node share `area` on the face and point `segment`.
fn node_fields(c: &NodeContribution, area: f64, segment: (usize, [f64; 2])) -> NodeFields {
    NodeFields {
        area,
        full_area: area,
        gap: c.gh,
        pressure: c.pressure,
        slip: c.slip,
        traction_t: c.friction.traction,
        law_traction_t: c.friction.traction,
        normal: c.nu,
        status: status_code(c.friction.status),
        weighted_gap: [0.0; 3],
        segment: Some(segment),
    }
}
