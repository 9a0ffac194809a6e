//! Newton updates solved again with the nodes they close held pressed
//! (`newton.hold_closing`).
//!
//! At a Newton iterate a traction node that the law leaves open has no normal stiffness in the
//! tangent (`dp/dgh = 0`), so the Newton update may carry it deep into the other body: the
//! linear model does not know that the node would press there. Where an update does so,
//! [`ContactInterfaces::hold_closing`] holds those nodes on the law's pressed branch at the
//! iterate, `p = lambda_n + eps_N gh` whatever its sign (`law::bilateral_pressure`, as the
//! bilateral iteration holds its nodes), and the solver solves for the update again: the
//! linear model of a held node is that of the pressed side of the law's kink, so the second
//! update closes it onto the other surface instead of through it. The solver keeps the second
//! update only where its full step leaves the smaller residual of the solve (the held law is a
//! direction's model, never a residual Newton converges to).
//!
//! A node counts as carried through when the law presses it at the update's end deeper than
//! [`CLOSING_DEPTH`] `h_A` past the gap at which it closes, `p / (eps_N h_A) > CLOSING_DEPTH`:
//! updates that close nodes by less, which are common in steps that converge quadratically
//! (the overshoot is what closes them), keep their one solve.

use std::collections::BTreeSet;

use crate::case::ContactMethod;
use crate::contact::mortar::RejectStats;
use crate::model::{Closing, State};

use super::evaluate::NormalLaw;
use super::pass::ContactPass;
use super::{ContactInterface, ContactInterfaces};

/// How far past closing (in units of the node's face size `h_A`) an update must carry an open
/// node for [`ContactInterfaces::hold_closing`] to hold it (docs/performance.md, "Newton
/// updates that close nodes, solved again": the creeping steps' updates carry nodes 1e-2 to
/// 4e-2 `h_A` deep, most others' less than 1e-3).
pub(crate) const CLOSING_DEPTH: f64 = 1e-3;

impl ContactInterfaces {
    /// Holds pressed every mortar traction node of this rank that the law leaves open at `at`
    /// (no normal stiffness: neither pressed nor touching; not held already, as the bilateral
    /// iteration's nodes are) and presses at `to`, where the Newton update leads, deeper than
    /// [`CLOSING_DEPTH`]; held until [`Self::release_closing`].
    pub(crate) fn hold_closing(&self, at: &State, to: &State) -> Closing {
        let (x_at, x_to) = (at.positions(), to.positions());
        let mut closing = Closing::default();
        for iface in &self.interfaces {
            let worked = iface.passes.iter().filter(|p| !p.held.is_empty());
            for pass in worked.filter(|p| p.method == ContactMethod::Mortar) {
                let modes = self.modes.get();
                let open: BTreeSet<usize> = self
                    .laws(iface, pass, &x_at)
                    .into_iter()
                    .filter(|(a, law)| law.dp_dgh == 0.0 && !pass.held_pressed(modes, *a))
                    .map(|(a, _)| a)
                    .collect();
                if open.is_empty() {
                    continue;
                }
                let mut carried = Vec::new();
                for (a, law) in self.laws(iface, pass, &x_to) {
                    let depth = law.p / (law.prm.eps_n * pass.state[a].h);
                    if open.contains(&a) && depth > CLOSING_DEPTH {
                        carried.push(a);
                        closing.deepest = closing.deepest.max(depth);
                    }
                }
                closing.held += carried.len();
                pass.closing_held.borrow_mut().extend(carried);
            }
        }
        closing
    }

    /// Lets go of the nodes [`Self::hold_closing`] held.
    pub(crate) fn release_closing(&self) {
        for pass in self.passes() {
            pass.closing_held.borrow_mut().clear();
        }
    }

    /// The normal law at positions `x` of every held traction node of `pass` that has one (the
    /// pass's values there kept for the evaluation that follows); none where the normals cannot
    /// be computed.
    fn laws(
        &self,
        iface: &ContactInterface,
        pass: &ContactPass,
        x: &[[f64; 3]],
    ) -> Vec<(usize, NormalLaw)> {
        let ctx = iface.context(self.modes.get(), x, &self.x_old);
        let Ok(normals) = pass.normals(ctx.x) else {
            return Vec::new();
        };
        let mut stats = RejectStats::default();
        let values = pass.values_at(&ctx, Some(&self.timings), &mut stats);
        let (_, kinematics) = pass.measured(&ctx, &values);
        kinematics
            .iter()
            .filter_map(|(&a, kin)| {
                let nu = normals.normal(pass.nodes[a]).unwrap_or_default();
                pass.normal_law(&ctx, a, nu, kin).map(|law| (a, law))
            })
            .collect()
    }
}
