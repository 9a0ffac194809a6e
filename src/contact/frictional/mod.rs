//! Frictional mortar contact: the Kuhn-Tucker conditions on the normalized weighted gap and
//! Coulomb's law on the mortar slip, by penalty plus Uzawa augmented Lagrangian, with the
//! consistent tangent (docs/theory.md sections 1, 2, 4, 6 and 7; the paper's eqs. 5-8).
//!
//! # Per traction node A (one pass of one interface)
//!
//! With the mortar weights `n1_AB`, `n2_AC` of the **current** configuration (summed over every
//! face pair whose secondary face carries A, [`crate::contact::mortar`]):
//!
//! ```text
//! a_A   = sum_B n1_AB                                   (traction integral of the overlap)
//! g_A   = sum_B n1_AB x_B - sum_C n2_AC x_C             (weighted gap vector)
//! gh_A  = nu_A . g_A / a_A                              (normalized gap, > 0 in penetration)
//! p_A   = max(0, lambda_A + eps_N gh_A)                 (law::normal_pressure_touching)
//! dsh_A = (g_A^n - gt_A) / a_A,  gt_A = sum_B n1_AB x_B^n - sum_C n2_AC x_C^n
//! t_T   = return map of the trial (contact::law::friction_traction)
//! t_A   = p_A nu_A + t_T
//! ```
//!
//! `x^n` are the positions and `g_A^n` the weighted gap at the last converged step, so
//! `dsh_A` is the paper's eq. 7 (docs/theory.md section 6): the current weights applied to the old
//! positions, minus the old weights applied to the old positions. A node without overlap at the
//! last converged step has no slip history yet: `dsh_A = 0` in its first step of contact. The
//! reference configuration counts as the first converged state (`commit` at `u = 0`).
//!
//! A gap within [`TOUCH_TOLERANCE`] `h_A` of closing counts as touching: zero pressure but the
//! closed derivative `eps_N`, so that bodies that start in contact without load (a block resting
//! on another) hold each other in the first Newton iteration.
//! `nu_A` is the averaged nodal normal of the secondary surface (contact::normals), with the
//! components of symmetry planes removed. The secondary node B receives the force
//! `-sum_A n1_AB t_A` and the primary node C `+sum_A n2_AC t_A`; in the residual (internal
//! minus external forces) these enter as `F_B += n1_AB t_A`, `F_C -= n2_AC t_A`.
//!
//! Penalties: `eps_N = s_A alpha E / h_A` and `eps_T = s_A alpha_T E / h_A`, with `E` the
//! Young's modulus of the secondary body at A and `h_A` the mean of `sqrt(area)` of the secondary
//! faces around A (reference configuration); both are multiplied by the interface's penalty
//! growth factor (1 unless `penalty_growth` is set). `h_A` is a face size, not the node's share
//! of the surface (`sqrt(a_full_A)`, which is half as large at an edge and a quarter at a
//! corner): a penalty that varies from node to node on a uniform mesh turns a uniform
//! penetration into a non-uniform pressure and fails the penalty patch test.
//!
//! **Coverage.** `a_full_A` is the integral of A's traction function over the secondary faces
//! carrying A in the current configuration (`traction_integrals`, with its derivative), and
//! `c_A = a_A / a_full_A` the node's coverage: 1 for a node whose faces the primary surface
//! covers whole (up to the quadrature of the pallets, whatever the strain of the surface), less
//! at the edge of the primary surface.
//!
//! **Coverage scale** `s_A = 1 / c_A` for a partly covered node, 1 otherwise
//! ([`coverage::coverage_scale`]). The node's force is `a_A t_A`, so without the scale a node
//! covered by a fraction `c` of its support resists its penetration (and its slip) with `c` times
//! the stiffness of a covered node, and its Uzawa update moves its force by `c` times as much (the
//! slow augmentations this caused: docs/performance.md, "Uzawa augmentations"). With the scale
//! every node's penalty force per unit normalized gap is that of a covered node. Covered nodes (the
//! patch tests) are unchanged, and the Uzawa solution of the nodes held to the tolerances is the
//! same (the scale changes the regularization, not the constraint). `s_A` depends on the geometry:
//! `d s / s = d a_full / a_full - d a / a` enters the tangent below.
//!
//! **Nodes sliding off.** A node below [`coverage::MIN_COVERAGE`] (0.1 %) carries no traction
//! (docs/theory.md section 10: as a node slides off the edge of the primary surface `a_A -> 0`, and
//! `1 / a_A` in `gh_A` and its derivative would be unbounded). Between 0.1 % and
//! [`coverage::FADE_COVERAGE`] (5 %) the node's traction is multiplied by a smooth step from 0 to 1
//! ([`coverage::coverage_fade`]), so that its force vanishes smoothly, with its derivative, as it
//! slides off (and appears as it slides on); such a node takes no Uzawa update (it keeps its
//! multipliers) and is not held to the tolerances. Slivers cannot be enforced in a few
//! augmentations (the edge of the primary body must be bent to close them); a sliver's penetration
//! is held by its covered neighbours. Why a smooth fade and not a plain threshold, and why these
//! bounds: docs/performance.md, "Uzawa augmentations".
//!
//! # Consistent tangent
//!
//! Differentiating the residual actually computed (every term, including the weights):
//!
//! ```text
//! d a    = sum_B d n1_AB
//! d g    = sum_B (d n1_AB x_B + n1_AB d x_B) - sum_C (d n2_AC x_C + n2_AC d x_C)
//! d gh   = (nu . d g + g . d nu) / a - gh d a / a
//! d p    = (dp/dgh) (d gh + gh d s / s)
//! d dsh  = -(d gt + dsh d a) / a,   d gt = sum_B d n1_AB x_B^n - sum_C d n2_AC x_C^n
//! d t_T  = (dt_T/d dsh) (d dsh + dsh d s / s) + (dt_T/dp) d p + (dt_T/d nu) d nu
//! d t    = nu d p + p d nu + d t_T
//! d F_B  = sum_A (d n1_AB r t_A + n1_AB d (r t_A)),   d F_C likewise with -n2_AC
//! d (r t) = r d t - t (dr/dc) c d s / s
//! ```
//!
//! with `d s / s = d a_full / a_full - d a / a` for a coverage-scaled node and 0 otherwise (the
//! law depends on `eps_N gh` and `eps_T dsh`, and `d eps / eps = d s / s`), `r` the fade
//! factor (1 for most nodes), `d n1`, `d n2` from
//! [`crate::contact::mortar::integrate_pair_linearized`] (forward-mode
//! automatic differentiation of the pair kernel), `d nu` from the nodal normals' exact
//! derivative, and the law's derivatives from `contact::law`. Friction makes it nonsymmetric.
//! With `mu = 0` nothing of friction is computed (no old positions, no slip, no return map).
//!
//! The law's inputs in a tangent (`a`, `g`, `gt`, so `gh`, `p`, `dsh` and every branch: open or
//! pressed, stick or slip) come from the residual's weights (`ContactPass::values_at`: the same
//! positions, so its cached result, with no new integration in the usual flow), and the weights
//! with their derivatives in `d F` (`n1`, `n2`, `d n1`, `d n2`) from the linearized kernel, whose
//! weights agree with the residual's to round-off only. That round-off is magnified by the gap, a
//! difference of positions of order 1 that a penalty leaves at 1e-7 or less: with the
//! linearized kernel's own weights as the law's inputs, a node on the Coulomb cone could take
//! the stick tangent while its residual slipped (beyond the cone's tie band,
//! [`crate::contact::law::CONE_TIE`]), and rank counts took different Newton paths
//! (docs/performance.md, "Newton on frictional contact").
//!
//! A tangent linearizes only the pairs whose secondary face carries a node the law presses
//! (`ContactPass::pressed_faces`, from the residual's weights as above): an open node has no
//! tangent block, so the derivatives of a face without a pressed node would go unused. The
//! tangent is unchanged, bit for bit; where the contact zone is smaller than the surfaces the
//! search pairs, the linearized kernel (the costliest part of the contact work) shrinks with it.
//! The derivatives of the other faces are neither computed nor
//! checked: a non-finite one no longer stops the evaluation (it would have gone unused).
//!
//! # Uzawa
//!
//! After a converged Newton solve, each node's multipliers are updated (law::uzawa_update); the
//! violation of a node, relative to `h_A`, is the size of the normal update in gap units,
//! `|d lambda_N| / eps_N` (the penetration of a pressed node, the multiplier an open node still
//! holds), and the slip `|dsh_A|` of a sticking node (docs/theory.md section 4; a slipping node has
//! no tangential constraint to meet). A node without traction (no overlap, or coverage below
//! [`coverage::MIN_COVERAGE`]) has its multipliers released without counting a violation (they
//! exert no force whatever their value); a fading node keeps them and counts none. Solves repeat
//! while a penetration is above `uzawa_tol` (relative to `h_A`) or a slip above the larger of
//! `uzawa_slip_motion` times the interface's tangential motion over the step
//! ([`ContactInterfaces::interface_motion`]) and `uzawa_slip_tol h_A` (docs/theory.md section
//! 4), at most `uzawa_max` times per step. The tangential updates of sticking nodes are scaled
//! by Aitken's factor while the interface sticks whole (module `relaxation`, the case key
//! `uzawa_relaxation`). With `penalty_growth > 1`, an augmentation that did not bring the
//! violation below a quarter of the previous one multiplies both penalties by that factor, up
//! to `penalty_growth_cap`.
//!
//! # Stick predictor
//!
//! With the stick predictor on (`Contribution::set_stick_all`) every pressed node sticks
//! whatever its cone (the law is called with `mu = infinity`): a smooth problem whose
//! solution is a good start for the Coulomb law, because the nodes that truly stick are
//! already in place and those that slip start from the direction of the tangential traction
//! that sticking would need. The solver uses it when `steps.stick_predictor` is set.
//!
//! # Bilateral iteration
//!
//! With the bilateral mode on (`Contribution::set_bilateral`), every mortar node with a normal
//! multiplier (`lambda_A > 0`: pressed at the last converged step) takes `p_A = lambda_A +
//! eps_N gh_A` whatever its sign, with `dp/dgh = eps_N` (law::bilateral_pressure): a node that
//! an iterate opened is pulled back by a tension instead of being released. Friction is the
//! law's on the resulting pressure: a node in tension takes the touching band's friction, no
//! traction and the stick tangent, which is not the derivative of its residual (deliberately:
//! docs/theory.md section 6). Nor does its tangent carry its tension's geometric terms: in
//! the tangent above a node in tension has no pressure (`p d nu`, `d n1 t`, `d n2 t` and a
//! fading node's `t dr` with `p = 0`; its friction is zero in tension), only the penalty's
//! `dp = eps_N d gh` that pulls it back (why: docs/performance.md, "The tension's geometric
//! terms"). Otherwise the tangent above differentiates whichever normal law the node took.
//! The solver uses it for one Newton iteration at the start of a step, two when the first
//! raised the law's residual (`steps.bilateral_iteration`): in a slide, the predictor's
//! linearized gaps miss by more than the multiplier's reach `lambda_A / eps_N`, every pressed
//! node opens, and from there the penalty law gives Newton no contact stiffness to close them
//! with (docs/theory.md section 6).
//!
//! # Nodes a Newton update closes
//!
//! `closing` finds the nodes that the law leaves open at a Newton iterate and that the Newton
//! update carries deeper than `CLOSING_DEPTH` `h_A` into the other surface, and holds them on
//! the bilateral law above while the solver solves for the update again
//! (`newton.hold_closing`): the second update's linear model knows they press once closed
//! (docs/theory.md section 6).
//!
//! # Parallel layout
//!
//! The mesh is replicated and every rank gathers the displacements of every contact surface
//! node. The contact work is dealt out by traction node, independently of the element
//! partition: METIS balances elements, and a partition whose cut does not cross the interface
//! leaves the whole surface to one rank. The passes of an interface are dealt to blocks of
//! ranks (`pass_ranks`: on two ranks each pass of a two-pass interface goes whole to one rank),
//! and each pass's nodes are cut into strips of equal work along the longest side of the
//! secondary surface, one strip per rank of its block (`deal_in_strips`). A node's work is
//! its share of the candidate pairs of the faces carrying it (`node_work`: a face's pairs split
//! equally among its traction nodes), found by the evaluations' search; a node without pairs
//! weighs little, so that the ranks share the part of the surface in contact, not the surface.
//! The nodes are dealt at the reference configuration and again after every converged step, at
//! its positions: the contact zone moves with the load. Before a new deal, every rank is handed
//! the multipliers, history and last law state of every node (`share_held_state`), so a node
//! that changes rank carries them along; a checkpoint of a rank sharing a pass thus holds every
//! node's state, and a restart deals as the run did from the positions it read back.
//!
//! The rank holding a traction node computes everything of that node and keeps its Uzawa
//! multipliers and history: it integrates every face pair whose secondary face carries a node it
//! holds (faces next to a strip cut are thus integrated by both neighbours; their pair statistics
//! are counted by the holder of the face's first traction node), sums them in a canonical order (by
//! secondary face, then primary face), and adds the node's forces and tangent block into the
//! distributed vector and matrix, whatever ranks own the rows (the blocks summed first into node
//! rows, [`crate::contact::block_sum::BlockSum`]). The results are therefore independent of the
//! partition up to round-off: the order of PETSc's assembly, and which node blocks a rank sums
//! before it.
//!
//! # Matrix pattern
//!
//! The pattern of a node's block is every node of the faces carrying it and of the primary
//! faces their search finds. At the start of each step and at its predicted end (the load-step
//! predictor's iterate, with `steps.predictor`), the contact contribution hands the solver the
//! blocks of the pairs an evaluation there finds (the evaluations' search margin,
//! [`EVAL_MARGIN`]); the solver keeps the pattern to those two states' pairs and the couplings
//! that do not move, and makes a new matrix when it changes (`solver::pattern_update`). A
//! mortar pass records the pairs it handed out, and before each Newton tangent the solver asks
//! whether they hold the pairs an evaluation at the iterate finds (those the residual at the
//! iterate found, kept with its values, or a search of its own where the last residual was
//! elsewhere; no stencils); where an iterate strayed from the two states, its stencils are
//! added and the matrix preallocated anew, so that no contact entry falls outside the pattern
//! (PETSc would reallocate the rows for each). No wider margin is needed, and none is taken:
//! its pairs would be stored zeros, which an exact solve of the contact rows factorizes as
//! entries. Node-on-segment passes keep a margin of their own and are not checked: an entry of
//! theirs outside the pattern costs a reallocation, not an error.
//!
//! # Modules
//!
//! - `pass`: one pass of an interface: its faces, traction nodes and their state.
//! - `coverage`: the full integrals of the traction functions, the coverage scale and fade.
//! - `evaluate`: one evaluation: the pairs' weights, each node's kinematics, law and block.
//! - `tangent`: a node's tangent block (the consistent linearization above).
//! - `pattern`: the search for candidate pairs and the nodes each traction node couples.
//! - `lifecycle`: Uzawa, the commit of a converged step, save and restore for a cut step.
//! - `fields`: the nodal fields of the output, the force sums, the summary's metrics.
//! - `deal`: which rank does the work of which traction node.
//!
//! The node-on-segment driver of a pass lives with its geometry in
//! [`crate::contact::node_on_segment`].

mod carried;
mod changes;
mod closing;
mod coverage;
mod deal;
mod evaluate;
mod fields;
mod lifecycle;
mod metrics;
mod pass;
mod pattern;
mod reach;
mod relaxation;
mod tangent;
#[cfg(test)]
pub(crate) mod tests;

use std::cell::{Cell, RefCell};

use mpi::topology::SimpleCommunicator;

use crate::case::{ContactMethod, InterfaceKind, Scene, UzawaRelaxation};
use crate::contact::block_sum::BlockSum;
use crate::contact::mortar::{PalletSplit, RejectStats, TractionScheme};
use crate::dofs::DofMap;
use crate::error::Result;
use crate::model::{
    Augmentation, Closing, Contribution, DomainIssue, ForceSink, Output, State, StateSink,
    StateSource, TangentSink,
};
use crate::petsc::log::Section;

pub use changes::StateChanges;
pub use coverage::{coverage_fade, coverage_scale, COVERED_TOL, FADE_COVERAGE, MIN_COVERAGE};
pub(crate) use evaluate::{EvalContext, Evaluation, LawModes};
pub(crate) use fields::status_code;
pub use fields::NodeFields;
pub(crate) use pass::ContactPass;
pub(crate) use tangent::NodeBlock;

use deal::pass_ranks;
use lifecycle::Saved;
use relaxation::Relaxation;

/// Number of figures of [`ContactInterfaces::force_sums`] per interface.
pub const FORCE_SUMS: usize = 9;

/// The names of the force sums in the history columns (`contact_<interface>_<name>`).
const FORCE_SUM_NAMES: [&str; FORCE_SUMS] = [
    "normal",
    "tangential",
    "fx",
    "fy",
    "fz",
    "stick",
    "slip",
    "dissipation",
    "max_slip",
];

/// Gaps within this fraction of `h_A` of closing count as touching: zero pressure, closed tangent
/// ([`crate::contact::law::normal_pressure_touching`]), so that surfaces that start in contact
/// without load hold each other from the first iteration.
pub const TOUCH_TOLERANCE: f64 = 1e-10;

/// Search margin of the evaluations, in secondary-face box diagonals.
pub const EVAL_MARGIN: f64 = 0.5;

/// The deepest penetration, in `h_A`, a Newton update may take a traction node to
/// ([`ContactInterfaces::reach_fraction`]): within what the evaluations' search still pairs
/// ([`EVAL_MARGIN`] box diagonals: `0.71 h_A` on square faces, `h_A` on right triangles).
pub const PENETRATION_REACH: f64 = 0.5;

/// One contact interface.
#[derive(Clone, Debug)]
pub struct ContactInterface {
    pub name: String,
    pub scheme: TractionScheme,
    /// Coulomb coefficient.
    pub mu: f64,
    pub uzawa_tol: f64,
    /// Uzawa tolerance on the slip of sticking nodes (fraction of h_A).
    pub uzawa_slip_tol: f64,
    /// Uzawa tolerance on the slip of sticking nodes (fraction of the node's tangential motion
    /// over the step).
    pub uzawa_slip_motion: f64,
    /// How the tangential updates of sticking nodes are relaxed.
    pub uzawa_relaxation: UzawaRelaxation,
    pub uzawa_max: usize,
    penalty_growth: f64,
    penalty_growth_cap: f64,
    /// Current multiple of the initial penalties.
    pub penalty_scale: f64,
    /// Violation after the previous augmentation of this step (for the penalty growth).
    last_violation: f64,
    /// The relaxation of the tangential updates over this step's augmentations.
    relaxation: Relaxation,
    quadrature_degree: Option<usize>,
    pallets: PalletSplit,
    pub passes: Vec<ContactPass>,
    /// Rejected and integrated segment pairs of this rank's last evaluation.
    pub stats: RefCell<RejectStats>,
}

/// Every contact interface of a scene, as this rank sees it.
#[derive(Clone, Debug, Default)]
pub struct ContactInterfaces {
    pub interfaces: Vec<ContactInterface>,
    /// Positions of every node at the last converged step.
    x_old: Vec<[f64; 3]>,
    /// The stick predictor's and the bilateral iteration's departures from the law.
    modes: Cell<LawModes>,
    /// Where the time of the residual and tangent evaluations goes.
    pub timings: ContactTimings,
    /// The state a cut step returns to ([`Contribution::save`]).
    saved: Option<Saved>,
    /// The force sums of every committed step ([`ContactInterfaces::force_sums`]).
    history: Vec<Vec<[f64; FORCE_SUMS]>>,
    /// Per interface: the law state changes of the last committed step, over every rank
    /// ([`changes`]).
    step_changes: Vec<u64>,
}

/// The contact work of the residual and tangent evaluations, each a PETSc log stage and a
/// wall-clock total. The reactions of the output go through the same evaluation, so the log
/// stages count them too; the solver takes the totals' increase over each Newton solve for
/// `summary.json`. (The output's and Uzawa's field evaluations are not timed.)
#[derive(Clone, Debug)]
pub struct ContactTimings {
    /// The search: the primary faces' tree and the candidate pairs.
    pub search: Section,
    /// The mortar integration of the candidate pairs, with the nodal normals.
    pub integration: Section,
    /// The nodal laws, their tangents and the insertion into PETSc's vector or matrix
    /// (node-on-segment: the projections too).
    pub assembly: Section,
}

impl Default for ContactTimings {
    fn default() -> Self {
        ContactTimings {
            search: Section::new("Contact search"),
            integration: Section::new("Mortar integration"),
            assembly: Section::new("Contact assembly"),
        }
    }
}

impl ContactInterfaces {
    /// Sets up every contact interface: faces, traction nodes, their full integrals and
    /// penalties, and which faces this rank integrates; the reference configuration is
    /// committed as the first converged state.
    pub fn new(scene: &Scene, dofs: &DofMap) -> Result<ContactInterfaces> {
        let young = crate::contact::tying::young_by_node(scene);
        let mut interfaces = Vec::new();
        for iface in scene
            .interfaces
            .iter()
            .filter(|i| i.kind == InterfaceKind::Contact)
        {
            let mut passes = Vec::new();
            for pass in 0..iface.passes {
                let workers = pass_ranks(pass, iface.passes, dofs.ranks);
                passes.push(ContactPass::new(
                    scene,
                    dofs,
                    iface,
                    crate::contact::pass_sides(iface, pass),
                    &young,
                    workers,
                )?);
            }
            interfaces.push(ContactInterface {
                name: iface.name.clone(),
                scheme: iface.scheme,
                mu: iface.friction,
                uzawa_tol: iface.uzawa_tol,
                uzawa_slip_tol: iface.uzawa_slip_tol,
                uzawa_slip_motion: iface.uzawa_slip_motion,
                uzawa_relaxation: iface.uzawa_relaxation,
                uzawa_max: iface.uzawa_max,
                penalty_growth: iface.penalty_growth,
                penalty_growth_cap: iface.penalty_growth_cap,
                penalty_scale: 1.0,
                last_violation: f64::INFINITY,
                relaxation: Relaxation::default(),
                quadrature_degree: iface.quadrature_degree,
                pallets: iface.pallets,
                passes,
                stats: Default::default(),
            });
        }
        let mut contact = ContactInterfaces {
            interfaces,
            x_old: scene.mesh.coords.clone(),
            modes: Default::default(),
            timings: ContactTimings::default(),
            saved: None,
            history: Vec::new(),
            step_changes: Vec::new(),
        };
        // The reference configuration is the first converged state: slip is measured from it.
        let zero = vec![0.0; 3 * scene.mesh.num_nodes()];
        contact.close_step(&State {
            scene,
            u: &zero,
            t: 0.0,
        });
        Ok(contact)
    }

    /// True when a contact interface has friction.
    pub fn has_friction(&self) -> bool {
        self.interfaces.iter().any(|i| i.mu > 0.0)
    }

    /// True when the scene has no contact interface.
    pub fn is_empty(&self) -> bool {
        self.interfaces.is_empty()
    }

    /// The contact tangent of the nodes this rank holds, their blocks summed into node rows
    /// first ([`BlockSum`]) and handed to `out` one node row at a time.
    fn tangent(&self, at: &State, out: &mut dyn TangentSink) -> Result<Option<String>> {
        let mut sum = BlockSum::default();
        let failure = self.assemble(at, true, |block| {
            sum.add(&block.slots, &block.tangent);
            Ok(())
        })?;
        self.timings.assembly.time(|| sum.hand_out(out))?;
        Ok(failure)
    }

    /// Every pass of every interface, in order.
    pub(crate) fn passes(&self) -> impl Iterator<Item = &ContactPass> {
        self.interfaces.iter().flat_map(|i| &i.passes)
    }

    /// Every node of every contact surface (whose displacements every rank gathers).
    pub fn nodes(&self) -> Vec<usize> {
        let mut n: Vec<usize> = self
            .passes()
            .flat_map(|p| p.surface_nodes.iter().copied())
            .collect();
        n.sort_unstable();
        n.dedup();
        n
    }
}

impl Contribution for ContactInterfaces {
    fn coupled_nodes(&self) -> Vec<usize> {
        self.nodes()
    }

    fn pattern_moves(&self) -> bool {
        true
    }

    fn couplings(&self, at: &State, couple: &mut dyn FnMut(&[usize])) {
        self.stencils(at, couple)
    }

    fn forget_couplings(&self) {
        self.forget_held_pairs()
    }

    fn holds_couplings_of(&self, at: &State) -> bool {
        self.holds_pairs_of(at)
    }

    fn residual(&self, at: &State, out: &mut dyn ForceSink) -> Result<Option<DomainIssue>> {
        let failure = self.assemble(at, false, |block| {
            out.add_forces(&block.slots, &block.force)
        })?;
        Ok(failure.map(DomainIssue::Contact))
    }

    fn jacobian(&self, at: &State, out: &mut dyn TangentSink) -> Result<Option<DomainIssue>> {
        Ok(self.tangent(at, out)?.map(DomainIssue::Contact))
    }

    fn step_fraction(&self, at: &State, du: &[f64]) -> f64 {
        self.reach_fraction(at, du)
    }

    fn is_augmented(&self) -> bool {
        true
    }

    fn takes_uzawa_updates(&self) -> bool {
        self.interfaces.iter().any(|i| i.uzawa_max > 0)
    }

    fn augment(&mut self, at: &State, done: usize, world: &SimpleCommunicator) -> Augmentation {
        let (outcome, violation) = self.uzawa_step(at, done, world);
        Augmentation {
            outcome,
            violation: format!("contact: {violation:.3e} times the tolerance"),
        }
    }

    fn save(&mut self) {
        self.saved = Some(self.snapshot());
        self.for_each_log(|log| log.start_step());
    }

    fn restore(&mut self) {
        if let Some(saved) = self.saved.take() {
            self.restore_snapshot(&saved);
            self.saved = Some(saved);
        }
    }

    fn commit(&mut self, at: &State, world: &SimpleCommunicator) {
        let sums = self.force_sums(at, world);
        self.history.push(sums);
        self.step_changes = self
            .state_changes(world, |log| log.step)
            .iter()
            .map(|(changes, _)| changes.total())
            .collect();
        self.close_step(at);
        self.redeal(world);
    }

    fn write_state(&self, out: &mut dyn StateSink) {
        self.write_carried(out)
    }

    fn read_state(&mut self, from: &mut dyn StateSource) -> Result<()> {
        self.read_carried(from)?;
        self.deal_as_committed();
        Ok(())
    }

    fn is_frictional(&self) -> bool {
        self.has_friction()
    }

    fn set_stick_all(&self, on: bool) {
        self.modes.set(LawModes {
            stick_all: on,
            ..self.modes.get()
        });
    }

    fn set_bilateral(&self, on: bool) {
        self.modes.set(LawModes {
            bilateral: on,
            ..self.modes.get()
        });
    }

    fn hold_closing(&self, at: &State, to: &State) -> Closing {
        ContactInterfaces::hold_closing(self, at, to)
    }

    fn release_closing(&self) {
        ContactInterfaces::release_closing(self)
    }

    fn has_bilateral_nodes(&self) -> bool {
        self.passes().any(|pass| {
            pass.method == ContactMethod::Mortar
                && pass
                    .held
                    .iter()
                    .any(|&a| pass.state[a].history.lambda_n > 0.0)
        })
    }

    fn iteration_report(&self, world: &SimpleCommunicator) -> Vec<String> {
        let changes = self.state_changes(world, |log| log.last);
        self.interfaces
            .iter()
            .zip(changes)
            .map(|(iface, (c, [stick, slip]))| {
                format!(
                    "    contact {}: {stick} stick, {slip} slip; changed {}: {} closed, {} opened, \
                     {} stick->slip, {} slip->stick",
                    iface.name,
                    c.total(),
                    c.closed,
                    c.opened,
                    c.slipped,
                    c.stuck
                )
            })
            .collect()
    }

    fn history_columns(&self) -> Vec<String> {
        self.interfaces
            .iter()
            .flat_map(|i| {
                let sums = FORCE_SUM_NAMES.map(|c| format!("contact_{}_{c}", i.name));
                sums.into_iter()
                    .chain([format!("contact_{}_state_changes", i.name)])
            })
            .collect()
    }

    fn history(&self) -> Vec<f64> {
        let Some(sums) = self.history.last() else {
            return Vec::new();
        };
        sums.iter()
            .zip(&self.step_changes)
            .flat_map(|(s, &changes)| s.iter().copied().chain([changes as f64]))
            .collect()
    }

    fn output(&self, at: &State, world: &SimpleCommunicator) -> Vec<Output> {
        self.surface_output(at, world)
    }

    fn metrics(&self, at: &State, world: &SimpleCommunicator) -> Vec<(String, f64)> {
        let mut out = self.state_metrics(at, world);
        out.extend(self.run_metrics(world));
        out
    }

    fn phase_seconds(&self) -> Vec<(&'static str, f64)> {
        let t = &self.timings;
        vec![
            ("contact_search", t.search.seconds()),
            ("contact_integration", t.integration.seconds()),
            ("contact_assembly", t.assembly.seconds()),
        ]
    }
}
