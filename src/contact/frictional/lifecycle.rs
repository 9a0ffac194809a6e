//! The life of the contact interfaces over a run: the Uzawa step after a converged solve, the
//! commit of a converged step, and the state a cut step returns to (module docs, "Uzawa").

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::topology::SimpleCommunicator;

use crate::case::UzawaRelaxation;
use crate::contact::law::{uzawa_update, NodeHistory};
use crate::model::{Augmented, State};
use crate::vec3::norm;

use super::coverage::{coverage_scale, FADE_COVERAGE};
use super::pass::NodeState;
use super::relaxation::NodeUpdate;
use super::ContactInterfaces;

/// A state saved before a step, to restore when the step is cut.
#[derive(Clone, Debug)]
pub(crate) struct Saved {
    pub(crate) states: Vec<Vec<Vec<NodeState>>>,
    pub(crate) scales: Vec<f64>,
}

impl ContactInterfaces {
    /// One Uzawa step at `at` (*collective*): every interface whose largest violation
    /// exceeds its tolerances and that has augmentations left (`done < uzawa_max`) updates the
    /// multipliers of its held nodes. Returns what happened and the largest violation, as a
    /// multiple of its tolerance (at most 1 when met).
    pub(crate) fn uzawa_step(
        &mut self,
        at: &State,
        done: usize,
        world: &SimpleCommunicator,
    ) -> (Augmented, f64) {
        let mut result = Augmented::Converged;
        let mut worst = 0.0f64;
        for i in 0..self.interfaces.len() {
            // (Only a sticking node's slip is measured against the motion.)
            let mut motion = 0.0;
            if self.interfaces[i].mu > 0.0 {
                let mine = self.interface_motion(at, i);
                world.all_reduce_into(&mine, &mut motion, SystemOperation::max());
            }
            let updates = self.uzawa_updates(at, i, motion);
            let local = updates.iter().map(|u| u.violation).fold(0.0, f64::max);
            let mut violation = 0.0;
            world.all_reduce_into(&local, &mut violation, SystemOperation::max());
            worst = worst.max(violation);
            let iface = &mut self.interfaces[i];
            if violation <= 1.0 || iface.uzawa_max == 0 {
                continue;
            }
            if done >= iface.uzawa_max {
                result = result.and(Augmented::CapReached);
                continue;
            }
            // (A frictionless interface has no sticking node to relax.)
            let mut omega = 1.0;
            if iface.mu > 0.0 && iface.uzawa_relaxation == UzawaRelaxation::Aitken {
                omega = iface.relaxation.next(&updates, world);
            }
            for u in &updates {
                let st = &mut iface.passes[u.pass].state[u.node];
                st.history = iface.relaxation.relaxed(&st.history, u, omega, iface.mu);
            }
            if violation > 0.25 * iface.last_violation && iface.penalty_growth > 1.0 {
                iface.penalty_scale =
                    (iface.penalty_scale * iface.penalty_growth).min(iface.penalty_growth_cap);
                // (Aitken's factor compares updates of one penalty.)
                iface.relaxation.reset();
            }
            iface.last_violation = violation;
            result = Augmented::Updated;
        }
        (result, worst)
    }

    /// The plain Uzawa update of every held node of interface `i` (module `relaxation`: what
    /// the sticking nodes take). A sticking node's slip is measured against the larger of
    /// `uzawa_slip_tol h_A` and `uzawa_slip_motion` times `motion`, the interface's
    /// tangential motion over the step ([`ContactInterfaces::interface_motion`],
    /// over every rank).
    pub(crate) fn uzawa_updates(&self, at: &State, i: usize, motion: f64) -> Vec<NodeUpdate> {
        let iface = &self.interfaces[i];
        let mut out = Vec::new();
        for (p, pass) in iface.passes.iter().enumerate() {
            for (a, f) in self.local_fields(at, i, p) {
                let st = &pass.state[a];
                if f.area <= 0.0 && st.history.lambda_n == 0.0 {
                    continue;
                }
                if f.area > 0.0 && f.area < FADE_COVERAGE * f.full_area {
                    // Fading out (or in): no constraint to meet, the multipliers are kept.
                    continue;
                }
                let coverage = coverage_scale(f.area, f.full_area).unwrap_or(1.0);
                let prm = pass.law_params(st, iface.mu, iface.penalty_scale, coverage);
                let dsh = if iface.mu > 0.0 { f.slip } else { [0.0; 3] };
                let new = if f.area > 0.0 {
                    uzawa_update(&st.history, &prm, f.normal, f.gap, dsh)
                } else {
                    // No overlap, or below MIN_COVERAGE: nothing to enforce and no traction
                    // whatever the multipliers, which are released.
                    NodeHistory {
                        lambda_n: 0.0,
                        lambda_t: [0.0; 3],
                        ..st.history
                    }
                };
                // Normal: the size of the multiplier update in gap units (the penetration of a
                // pressed node, the released multiplier of an open one; 0 for a node without
                // traction). Tangential: the slip of a sticking node (a slipping node has no
                // slip constraint).
                let dn = if f.area > 0.0 {
                    (new.lambda_n - st.history.lambda_n).abs() / prm.eps_n
                } else {
                    0.0
                };
                let dt = if iface.mu > 0.0 && f.status == 1 {
                    let allowed =
                        (iface.uzawa_slip_tol * st.h).max(iface.uzawa_slip_motion * motion);
                    norm(f.slip) / allowed
                } else {
                    0.0
                };
                let violation = (dn / iface.uzawa_tol / st.h).max(dt);
                out.push(NodeUpdate::plain(
                    (p, a),
                    violation,
                    &st.history,
                    new,
                    f.status,
                ));
            }
        }
        out
    }

    /// How far interface `i` moved along itself over the step, on this rank: the largest
    /// tangential displacement since the last converged step of a traction node it holds
    /// that has an overlap. (Not each node's own: a node held on a symmetry plane does not
    /// move while the other side's material passes over it.)
    pub(crate) fn interface_motion(&self, at: &State, i: usize) -> f64 {
        let iface = &self.interfaces[i];
        let mut largest = 0.0f64;
        for (p, pass) in iface.passes.iter().enumerate() {
            for (a, f) in self.local_fields(at, i, p) {
                if f.area > 0.0 {
                    largest = largest.max(self.tangential_motion(at, pass.nodes[a], f.normal));
                }
            }
        }
        largest
    }

    /// The length of the tangential part (to `normal`) of node `node`'s displacement since the
    /// last converged step.
    fn tangential_motion(&self, at: &State, node: usize, normal: [f64; 3]) -> f64 {
        let x = at.scene.mesh.coords[node];
        let d: [f64; 3] = std::array::from_fn(|c| x[c] + at.u[3 * node + c] - self.x_old[node][c]);
        let dn = d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2];
        norm(std::array::from_fn(|c| d[c] - dn * normal[c]))
    }

    /// Closes a converged step at `at`: the tangential tractions, normals and weighted gaps
    /// of the held nodes become the history of the next step; its positions the old ones.
    pub(crate) fn close_step(&mut self, at: &State) {
        for i in 0..self.interfaces.len() {
            let mu = self.interfaces[i].mu;
            for p in 0..self.interfaces[i].passes.len() {
                let fields = self.local_fields(at, i, p);
                let pass = &mut self.interfaces[i].passes[p];
                for (a, f) in fields {
                    let st = &mut pass.state[a];
                    st.gap_old = (f.area > 0.0).then_some(f.weighted_gap);
                    st.segment_old = f.segment;
                    if f.area == 0.0 {
                        // No traction: the multiplier is released (the Uzawa updates release
                        // it only when an interface augments).
                        st.history.lambda_n = 0.0;
                    }
                    if mu > 0.0 && f.normal != [0.0; 3] {
                        st.history = NodeHistory {
                            lambda_n: st.history.lambda_n,
                            lambda_t: [0.0; 3],
                            normal_old: f.normal,
                            traction_t_old: f.law_traction_t,
                        };
                    } else if f.area == 0.0 {
                        // No contact (node-on-segment: no face under the node): no tangential
                        // traction to carry into the next contact.
                        st.history.lambda_t = [0.0; 3];
                        st.history.traction_t_old = [0.0; 3];
                    }
                }
            }
            self.interfaces[i].last_violation = f64::INFINITY;
            self.interfaces[i].relaxation.reset();
        }
        self.x_old = at.positions();
    }

    /// The state to restore if the coming step is cut.
    pub(crate) fn snapshot(&self) -> Saved {
        Saved {
            states: self
                .interfaces
                .iter()
                .map(|i| i.passes.iter().map(|p| p.state.clone()).collect())
                .collect(),
            scales: self.interfaces.iter().map(|i| i.penalty_scale).collect(),
        }
    }

    /// Restores a state saved by [`ContactInterfaces::snapshot`].
    pub(crate) fn restore_snapshot(&mut self, saved: &Saved) {
        for ((iface, states), &scale) in self
            .interfaces
            .iter_mut()
            .zip(&saved.states)
            .zip(&saved.scales)
        {
            for (pass, st) in iface.passes.iter_mut().zip(states) {
                pass.state.clone_from(st);
            }
            iface.penalty_scale = scale;
            iface.last_violation = f64::INFINITY;
            iface.relaxation.reset();
        }
    }
}
