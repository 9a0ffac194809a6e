//! How far one Newton update may push the surfaces into each other: the reach of the search.
//!
//! The evaluations pair a secondary face only with the primary faces within [`EVAL_MARGIN`]
//! of its box diagonals ([`ContactPass::values_at`]). A traction node that one Newton update
//! pushes deeper than that has no pair at the next iterate: it carries no pressure, nothing
//! pushes it back, and Newton converges to bodies that pass through each other. This happens
//! when a full Newton step opens every node of a sliding interface (the linearized gaps of
//! a step that slides across several faces are off by more than the penalty's penetration
//! `p / eps_n`): the next update, without contact, moves the bodies by the whole load.
//!
//! So every Newton update is shortened, as a whole, to the fraction that keeps each held
//! node's penetration within [`PENETRATION_REACH`] `h_A` (`r_A`), with the increment of its
//! normal gap taken from the current weights (those of the residual at the iterate):
//!
//! ```text
//! dgh_A = nu_A . (sum_B n1_AB du_B - sum_C n2_AC du_C) / a_A
//! fraction = min over A of max(r_A - gh_A, LEAST_DEEPENING r_A) / dgh_A
//!            where gh_A < r_A < gh_A + dgh_A
//! ```
//!
//! A node may always go [`LEAST_DEEPENING`] `r_A` deeper, so that one just short of the
//! reach does not shrink the update to nothing (a vanishing update would pass PETSc's test
//! on the step length as converged); a node already deeper than the reach is left alone: its
//! pairs hold it. Nodes covered less than the coverage that carries traction, and increments
//! that are not finite, are not looked at (a non-finite update fails in the residual).
//! Node-on-segment passes are not limited. The limit holds for the line searches that take
//! at most the full update (`basic`, `bt`); `l2` may extrapolate beyond it, and the trust
//! region method has no line search.

use crate::case::ContactMethod;
use crate::contact::mortar::RejectStats;
use crate::model::State;
use crate::vec3::dot;

use super::evaluate::EvalContext;
use super::pass::ContactPass;
#[cfg(doc)]
use super::EVAL_MARGIN;
use super::{ContactInterfaces, PENETRATION_REACH};

/// The least deepening an update may bring a node below the reach, in units of the reach.
const LEAST_DEEPENING: f64 = 0.25;

impl ContactInterfaces {
    /// The fraction of the Newton update `du` (indexed as `at.u`) from `at` that keeps every
    /// node this rank holds within the search's reach (module docs).
    pub(crate) fn reach_fraction(&self, at: &State, du: &[f64]) -> f64 {
        let x = at.positions();
        let dx: Vec<[f64; 3]> = du.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let mut fraction = 1.0f64;
        for iface in &self.interfaces {
            let mortar = iface
                .passes
                .iter()
                .filter(|p| !p.held.is_empty() && p.method == ContactMethod::Mortar);
            for pass in mortar {
                let ctx = iface.context(self.modes.get(), &x, &self.x_old);
                fraction = fraction.min(pass.reach_fraction(&ctx, &dx));
            }
        }
        fraction
    }
}

impl ContactPass {
    /// [`ContactInterfaces::reach_fraction`] of this pass's held nodes, at the positions of
    /// `ctx`, for the position increments `dx`.
    fn reach_fraction(&self, ctx: &EvalContext, dx: &[[f64; 3]]) -> f64 {
        let Ok(normals) = self.normals(ctx.x) else {
            return 1.0;
        };
        let values = self.values_at(ctx, None, &mut RejectStats::default());
        let mut fraction = 1.0f64;
        for (a, terms) in self.pairs_by_node(&values, &self.held) {
            let nu = normals.normal(self.nodes[a]).unwrap_or_default();
            let kin = self.kinematics(ctx, &terms);
            let Some(law) = self.normal_law(ctx, a, nu, &kin) else {
                continue;
            };
            let (_, increment) = self.weighted_gap(&terms, dx);
            let dgh = dot(nu, increment) / kin.area;
            if !dgh.is_finite() {
                continue;
            }
            let reach = PENETRATION_REACH * self.state[a].h;
            if law.gh < reach && law.gh + dgh > reach {
                let deepening = (reach - law.gh).max(LEAST_DEEPENING * reach);
                fraction = fraction.min(deepening / dgh);
            }
        }
        fraction
    }
}
