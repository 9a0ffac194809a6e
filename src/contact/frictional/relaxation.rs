//! Aitken's relaxation of the tangential Uzawa updates of sticking nodes (docs/theory.md
//! section 4).
//!
//! # Why
//!
//! A sticking node's plain Uzawa update adds `r_A = eps_T dsh_A` (its elastic slip over the
//! step, times the tangential penalty) to its tangential multiplier. The next solve removes only
//! part of that slip: for one node held by a structure of stiffness `K`, each update leaves
//!
//! ```text
//! s_{k+1} = K / (K + eps_T) s_k
//! ```
//!
//! of the slip, a factor about 0.9 with the default `eps_T = E / h_A`, whose stiffness a block
//! much larger than `h_A` exceeds several times. Over a whole interface the factor is that of
//! the interface's stiffest mode of tangential motion.
//!
//! # The update
//!
//! The Uzawa loop is a fixed-point iteration `lambda <- lambda + r(lambda)` on the multipliers;
//! Aitken's delta-squared method (the dynamic relaxation of partitioned fluid-structure
//! coupling) scales each update by a factor taken from the last two:
//!
//! ```text
//! omega_k = -omega_{k-1} (r_{k-1} . (r_k - r_{k-1})) / |r_k - r_{k-1}|^2,   omega_0 = 1
//! lambda_T <- lambda_T + omega_k r_k
//! ```
//!
//! with the dot products summed over the sticking nodes of the interface (over every rank). For
//! one node (or one dominant mode) `r_k = (1 - c omega_{k-1}) r_{k-1}` with
//! `c = eps_T / (K + eps_T)`, and the formula gives `omega_k = 1 / c`: the update that removes
//! the slip in one step. `omega` is kept within `[1, MAX_RELAXATION]` (below 1 the plain update,
//! which converges, is the better one; the cap bounds the step where the two updates are nearly
//! equal).
//!
//! The formula assumes a fixed linear map from the multipliers to the slips, so the whole
//! interface takes the plain update (`omega = 1`) in its step's first augmentation and in any
//! augmentation where
//! - a pressed node of the interface slips: beside slipping nodes an over-relaxed stick moves
//!   load onto them (docs/performance.md, "Uzawa augmentations");
//! - a node started or stopped sticking since the last augmentation;
//! - in the last augmentation a node took the plain update instead of the relaxed one (below),
//!   so that the last step was not `omega r`.
//!
//! Within a relaxed augmentation a node whose relaxed carried traction `|t_old + lambda_T|`
//! would reach the Coulomb cone `mu lambda_N` of the updated pressure takes the plain update,
//! so that relaxation never turns a stick into a slip by itself. Normal multipliers are never
//! relaxed.

use std::collections::HashMap;

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::topology::SimpleCommunicator;

use crate::contact::law::{NodeHistory, CONE_TIE};
use crate::vec3::norm;

/// The largest relaxation factor.
pub(crate) const MAX_RELAXATION: f64 = 10.0;

/// One node's Uzawa update: `(pass, node)`, its violation as a multiple of its tolerance, the
/// plain update, the change it makes to the tangential multiplier, and the node's state under
/// the law (`fields::status_code`: 0 open, 1 stick, 2 slip).
#[derive(Clone, Debug)]
pub(crate) struct NodeUpdate {
    pub(crate) pass: usize,
    pub(crate) node: usize,
    pub(crate) violation: f64,
    pub(crate) history: NodeHistory,
    /// `r = history.lambda_t - lambda_t` of the multipliers the update was computed from.
    pub(crate) increment: [f64; 3],
    pub(crate) status: u8,
}

impl NodeUpdate {
    /// The update `new` of the multipliers `old` of node `node` of pass `pass`.
    pub(crate) fn plain(
        (pass, node): (usize, usize),
        violation: f64,
        old: &NodeHistory,
        new: NodeHistory,
        status: u8,
    ) -> NodeUpdate {
        NodeUpdate {
            pass,
            node,
            violation,
            increment: std::array::from_fn(|c| new.lambda_t[c] - old.lambda_t[c]),
            history: new,
            status,
        }
    }

    fn sticks(&self) -> bool {
        self.status == 1
    }

    fn slips(&self) -> bool {
        self.status == 2
    }
}

/// The relaxation of one interface over the augmentations of the step under way.
#[derive(Clone, Debug)]
pub(crate) struct Relaxation {
    /// The factor of the last augmentation of the step (1 before the first).
    pub(super) omega: f64,
    /// The plain tangential update `r` of every node of this rank that stuck in the last
    /// augmentation, by `(pass, node)`.
    pub(super) previous: HashMap<(usize, usize), [f64; 3]>,
    /// A node of this rank took the plain update instead of the relaxed one in the last
    /// augmentation.
    pub(super) fell_back: bool,
}

impl Default for Relaxation {
    fn default() -> Self {
        Relaxation {
            omega: 1.0,
            previous: HashMap::new(),
            fell_back: false,
        }
    }
}

impl Relaxation {
    /// Forgets the step's augmentations (a new step, a cut one, or grown penalties).
    pub(crate) fn reset(&mut self) {
        *self = Relaxation::default();
    }

    /// The factor of this augmentation, from the plain `updates` of the interface's nodes on
    /// this rank; the updates of the sticking nodes are kept for the next augmentation
    /// (*collective*: sums over every rank).
    pub(crate) fn next(&mut self, updates: &[NodeUpdate], world: &SimpleCommunicator) -> f64 {
        let increments: Vec<((usize, usize), [f64; 3])> = updates
            .iter()
            .filter(|u| u.sticks())
            .map(|u| ((u.pass, u.node), u.increment))
            .collect();
        // [r_{k-1} . (r_k - r_{k-1}), |r_k - r_{k-1}|^2, reasons for the plain update]
        let mut local = [0.0; 3];
        let mut both = 0;
        for (key, r) in &increments {
            if let Some(before) = self.previous.get(key) {
                both += 1;
                let d: [f64; 3] = std::array::from_fn(|c| r[c] - before[c]);
                local[0] += before[0] * d[0] + before[1] * d[1] + before[2] * d[2];
                local[1] += d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            }
        }
        let changed = (increments.len() - both) + (self.previous.len() - both);
        let slipping = updates.iter().filter(|u| u.slips()).count();
        local[2] = (changed + slipping + usize::from(self.fell_back)) as f64;
        let mut sums = [0.0; 3];
        world.all_reduce_into(&local[..], &mut sums[..], SystemOperation::sum());
        let omega = if sums[2] > 0.0 {
            1.0
        } else {
            aitken(self.omega, sums[0], sums[1])
        };
        *self = Relaxation {
            omega,
            previous: increments.into_iter().collect(),
            fell_back: false,
        };
        omega
    }

    /// The multipliers a node takes: the plain update of `old`, with the tangential change of
    /// a sticking node scaled by `omega` unless its carried traction would reach the Coulomb
    /// cone `mu lambda_N` of the updated pressure (a fallback, remembered for the next
    /// augmentation).
    pub(crate) fn relaxed(
        &mut self,
        old: &NodeHistory,
        update: &NodeUpdate,
        omega: f64,
        mu: f64,
    ) -> NodeHistory {
        let new = update.history;
        if !update.sticks() || omega == 1.0 {
            return new;
        }
        let r = update.increment;
        let lambda_t: [f64; 3] = std::array::from_fn(|c| old.lambda_t[c] + omega * r[c]);
        let carried: [f64; 3] = std::array::from_fn(|c| new.traction_t_old[c] + lambda_t[c]);
        if norm(carried) < (1.0 - CONE_TIE) * mu * new.lambda_n {
            NodeHistory { lambda_t, ..new }
        } else {
            self.fell_back = true;
            new
        }
    }
}

/// Aitken's factor from the last one and the sums `r_{k-1} . (r_k - r_{k-1})` and
/// `|r_k - r_{k-1}|^2`, within `[1, MAX_RELAXATION]`.
fn aitken(last: f64, cross: f64, square: f64) -> f64 {
    if square <= 0.0 {
        return 1.0;
    }
    let omega = -last * cross / square;
    if omega.is_finite() {
        omega.clamp(1.0, MAX_RELAXATION)
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One sticking node of stiffness `k` under a penalty `eps`: the slip the solve leaves with
    /// multiplier `lambda`, for a load that needs the multiplier `target`.
    fn slip(k: f64, eps: f64, target: f64, lambda: f64) -> f64 {
        (target - lambda) / (k + eps)
    }

    #[test]
    fn the_second_augmentation_of_one_node_lands_on_its_multiplier() {
        let (k, eps, target) = (7.0, 1.0, 3.0);
        let r0 = eps * slip(k, eps, target, 0.0);
        let lambda1 = r0;
        let r1 = eps * slip(k, eps, target, lambda1);
        let omega = aitken(1.0, r0 * (r1 - r0), (r1 - r0) * (r1 - r0));
        assert!((omega - (k + eps) / eps).abs() < 1e-12, "omega {omega}");
        let lambda2 = lambda1 + omega * r1;
        assert!((lambda2 - target).abs() < 1e-12, "lambda {lambda2}");
    }

    #[test]
    fn the_factor_stays_within_its_bounds() {
        assert_eq!(aitken(1.0, -1.0, 0.0), 1.0, "no change");
        assert_eq!(aitken(1.0, 1.0, 1.0), 1.0, "growing updates");
        assert_eq!(
            aitken(1.0, -1.0, 1e-3),
            MAX_RELAXATION,
            "nearly equal updates"
        );
        assert_eq!(aitken(1.0, f64::NAN, 1.0), 1.0, "not a number");
    }

    #[test]
    fn a_relaxed_stick_stays_inside_the_cone() {
        let old = NodeHistory {
            lambda_n: 1.0,
            lambda_t: [0.0; 3],
            normal_old: [0.0, 0.0, 1.0],
            traction_t_old: [0.1, 0.0, 0.0],
        };
        let update = |lambda_t| {
            let new = NodeHistory {
                lambda_n: 1.0,
                lambda_t,
                ..old
            };
            NodeUpdate::plain((0, 0), 2.0, &old, new, 1)
        };
        let mut relaxation = Relaxation::default();
        let inside = relaxation.relaxed(&old, &update([0.01, 0.0, 0.0]), 5.0, 0.2);
        assert!((inside.lambda_t[0] - 0.05).abs() < 1e-15);
        assert!(!relaxation.fell_back);
        let slipping = NodeUpdate {
            status: 2,
            ..update([0.01, 0.0, 0.0])
        };
        let plain = relaxation.relaxed(&old, &slipping, 5.0, 0.2);
        assert_eq!(plain.lambda_t, [0.01, 0.0, 0.0]);
        assert!(
            !relaxation.fell_back,
            "a slipping node takes the plain update"
        );
        let beyond = relaxation.relaxed(&old, &update([0.03, 0.0, 0.0]), 5.0, 0.2);
        assert_eq!(beyond.lambda_t, [0.03, 0.0, 0.0], "the plain update");
        assert!(relaxation.fell_back, "a fallback is remembered");
    }
}
