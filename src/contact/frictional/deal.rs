//! Which rank does the contact work of which traction node (module docs, "Parallel layout").

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::topology::SimpleCommunicator;

use super::carried::{node_values, set_node_values, NODE_VALUES, NO_SEGMENT};
use super::pass::ContactPass;
use super::{ContactInterface, ContactInterfaces};

/// The work of a traction node none of whose faces has a candidate pair, in pairs: enough
/// that a surface out of contact is dealt in equal counts, too little to matter beside a
/// node in contact.
pub(crate) const IDLE_NODE_WORK: f64 = 1e-3;

/// The ranks that share the contact work of pass `pass` of `passes`: the passes of an
/// interface are dealt out first, so that on two ranks the two passes of a two-pass interface
/// go one to each rank whole (no face is integrated twice); with more ranks than passes, each
/// pass gets its own block of ranks, which [`deal_in_strips`] then shares out.
pub(crate) fn pass_ranks(pass: usize, passes: usize, ranks: usize) -> std::ops::Range<usize> {
    if ranks >= passes {
        pass * ranks / passes..(pass + 1) * ranks / passes
    } else {
        let rank = pass * ranks / passes;
        rank..rank + 1
    }
}

/// The strip (of `strips`) that does the contact work of each traction node: the nodes, sorted
/// along the longest side of their bounding box (reference positions; ties by index), cut into
/// `strips` strips of equal work, each node's work given by `work`: a node goes to the strip in
/// which the work of the nodes before it ends. The faces next to each cut (one row of faces,
/// or two when the cut falls inside a row of nodes) are integrated by both neighbours.
pub(crate) fn deal_in_strips(points: &[[f64; 3]], work: &[f64], strips: usize) -> Vec<usize> {
    let extent: [f64; 3] = std::array::from_fn(|c| {
        let (lo, hi) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |b, p| {
                (b.0.min(p[c]), b.1.max(p[c]))
            });
        hi - lo
    });
    // The longest side; the first axis of equally long ones.
    let axis = (0..3)
        .max_by(|&i, &j| extent[i].total_cmp(&extent[j]).then(j.cmp(&i)))
        .unwrap_or(0);
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| points[a][axis].total_cmp(&points[b][axis]).then(a.cmp(&b)));
    debug_assert_eq!(work.len(), points.len());
    let strips = strips.max(1);
    // (No work to share, or a work that is not a number: equal counts.)
    let by_work = work.iter().sum::<f64>() > 0.0;
    let weight = |a: usize| if by_work { work[a] } else { 1.0 };
    let total: f64 = (0..points.len()).map(weight).sum();
    let mut strip = vec![0; points.len()];
    let mut before = 0.0;
    for &a in &order {
        strip[a] = ((strips as f64 * before / total) as usize).min(strips - 1);
        before += weight(a);
    }
    strip
}

/// The work of each of `nodes` traction nodes: every secondary face's candidate pairs
/// (`pairs`, per face) shared equally among its traction nodes (`carriers`), plus
/// [`IDLE_NODE_WORK`].
pub(crate) fn node_work(carriers: &[Vec<usize>], pairs: &[usize], nodes: usize) -> Vec<f64> {
    let mut work = vec![IDLE_NODE_WORK; nodes];
    for (carried, &count) in carriers.iter().zip(pairs) {
        for &a in carried {
            work[a] += count as f64 / carried.len() as f64;
        }
    }
    work
}

impl ContactPass {
    /// The work of each traction node at positions `x`: [`node_work`] of the candidate pairs
    /// the evaluations' search finds there.
    pub(crate) fn node_work_at(&self, x: &[[f64; 3]]) -> Vec<f64> {
        let pairs: Vec<usize> = self
            .every_face_candidates(x)
            .iter()
            .map(|(_, ms)| ms.len())
            .collect();
        node_work(&self.carriers, &pairs, self.nodes.len())
    }

    /// Deals the pass's traction nodes to its ranks by their work at positions `x`
    /// ([`ContactPass::node_work_at`], in strips by [`deal_in_strips`]): what this rank holds,
    /// integrates and tallies. (A pass one rank does needs no search: it holds every node.)
    pub(crate) fn deal(&mut self, x: &[[f64; 3]]) {
        let work = if self.is_shared() {
            self.node_work_at(x)
        } else {
            vec![IDLE_NODE_WORK; self.nodes.len()]
        };
        let holder: Vec<usize> = deal_in_strips(&self.reference, &work, self.workers.len())
            .into_iter()
            .map(|strip| self.workers.start + strip)
            .collect();
        let rank = self.rank;
        self.held = (0..self.nodes.len())
            .filter(|&a| holder[a] == rank)
            .collect();
        self.local_faces = (0..self.carriers.len())
            .filter(|&s| self.carriers[s].iter().any(|&a| holder[a] == rank))
            .collect();
        self.tallied = self
            .carriers
            .iter()
            .map(|c| c.first().is_some_and(|&a| holder[a] == rank))
            .collect();
        self.last_values.replace(None);
        self.state_log.borrow_mut().dealt(&self.held);
    }

    /// Whether more than one rank shares the pass (and a new deal may move its nodes).
    pub(crate) fn is_shared(&self) -> bool {
        self.workers.len() > 1
    }

    /// Hands every rank the state of every traction node (*collective*): each node's
    /// multipliers and history, and its law state at the last tangent evaluation, as the rank
    /// holding it keeps them. Before a new deal, which may move a node to another rank.
    pub(crate) fn share_held_state(&mut self, world: &SimpleCommunicator) {
        let n = self.nodes.len();
        let mut values = vec![0.0; NODE_VALUES * n];
        let mut codes = vec![0u64; 2 * n];
        let log = self.state_log.borrow();
        for &a in &self.held {
            let st = &self.state[a];
            values[NODE_VALUES * a..NODE_VALUES * (a + 1)].copy_from_slice(&node_values(st));
            // (Zero stands for "not held here" in the sum; a face is sent as its index + 1.)
            codes[a] = st.segment_old.map_or(0, |(f, _)| f as u64 + 1);
            codes[n + a] = log.state(a);
        }
        drop(log);
        let mut all_values = vec![0.0; values.len()];
        let mut all_codes = vec![0u64; codes.len()];
        world.all_reduce_into(&values[..], &mut all_values[..], SystemOperation::sum());
        world.all_reduce_into(&codes[..], &mut all_codes[..], SystemOperation::sum());
        for (a, st) in self.state.iter_mut().enumerate() {
            let face = all_codes[a].checked_sub(1).unwrap_or(NO_SEGMENT);
            set_node_values(
                st,
                &all_values[NODE_VALUES * a..NODE_VALUES * (a + 1)],
                face,
            );
        }
        self.state_log.borrow_mut().set_states(&all_codes[n..]);
    }
}

impl ContactInterfaces {
    /// Deals the traction nodes of every shared pass anew by their work at the last converged
    /// positions (*collective*), each rank first handed the state of every node.
    pub(crate) fn redeal(&mut self, world: &SimpleCommunicator) {
        for pass in self.interfaces.iter_mut().flat_map(|i| &mut i.passes) {
            if pass.is_shared() {
                pass.share_held_state(world);
            }
        }
        let (interfaces, x_old) = (&mut self.interfaces, &self.x_old);
        self.timings
            .search
            .time(|| deal_shared_passes(interfaces, x_old));
    }

    /// The deal [`ContactInterfaces::redeal`] made after the last converged step, again (a
    /// restart, whose checkpoint holds the state of every node).
    pub(crate) fn deal_as_committed(&mut self) {
        deal_shared_passes(&mut self.interfaces, &self.x_old);
    }
}

/// Deals the traction nodes of every pass of `interfaces` that ranks share by their work at
/// positions `x`.
fn deal_shared_passes(interfaces: &mut [ContactInterface], x: &[[f64; 3]]) {
    for pass in interfaces.iter_mut().flat_map(|i| &mut i.passes) {
        if pass.is_shared() {
            pass.deal(x);
        }
    }
}
