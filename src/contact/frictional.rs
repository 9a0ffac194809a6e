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
//! ([`coverage_scale`]). The node's force is `a_A t_A`, so without the scale a node covered by a
//! fraction `c` of its support resists its penetration (and its slip) with `c` times the
//! stiffness of a covered node, and its Uzawa update moves its force by `c` times as much:
//! measured on the paper's case 4 (sliding blocks, Hex8), the slowest nodes, 19-25 % covered
//! along the upper cube's edge, lost 30-40 % of their violation per augmentation, and 13 of 50
//! steps needed more than 5 augmentations. With the scale every node's penalty force per unit
//! normalized gap is that of a covered node. Covered nodes (the patch tests) are unchanged,
//! and the Uzawa solution of the nodes held to the tolerances is the same (the scale changes
//! the regularization, not the constraint). `s_A` depends on the geometry:
//! `d s / s = d a_full / a_full - d a / a` enters the tangent below.
//!
//! **Nodes sliding off.** A node below [`MIN_COVERAGE`] (0.1 %) carries no traction
//! (docs/theory.md section 10: as a node slides off the edge of the primary surface `a_A -> 0`,
//! and `1 / a_A` in `gh_A` and its derivative would be unbounded). Between 0.1 % and
//! [`FADE_COVERAGE`] (5 %) the node's traction is multiplied by a smooth step from 0 to 1
//! ([`coverage_fade`]), so that its force vanishes smoothly, with its derivative, as it slides
//! off (and appears as it slides on); such a node takes no Uzawa update (it keeps its
//! multipliers) and is not held to the tolerances. Slivers cannot be enforced in a few
//! augmentations: on case 4 a node 0.3 % covered held 50 times the mean pressure after 10
//! augmentations with the scale capped at 100, while its mean gap fell by 5-10 % per
//! augmentation (the edge of the primary body must be bent to close it). A sliver's
//! penetration is held by its covered neighbours. Measured on case 4: a plain threshold at 5 %
//! instead of the fade also met 5 augmentations per step, but the jump of a node's force as it
//! crossed it made a coarse slide cut steps on one rank count and not on the other; a fade
//! from 5 % to 10 % let the slivers' mean penetration reach 5e-4 h on case 3 (1.4e-7 h with
//! this one).
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
//! difference of positions of order 1 that a penalty leaves at 1e-7 or less: measured on the
//! scaling scene, a node on the Coulomb cone at the start of a step (its trial 1e-16 from it in the
//! residual) sat 1.25e-10 inside it in the tangent's kinematics, beyond the cone's tie band
//! ([`crate::contact::law::CONE_TIE`]), and took the stick tangent while its residual slipped;
//! which of the two happened followed round-off, so 1 and 2 ranks took 53 and 68 Newton iterations;
//! with the residual's inputs both took 53 in three runs.
//!
//! A tangent linearizes only the pairs whose secondary face carries a node the law presses
//! (`ContactPass::pressed_faces`, from the residual's weights as above): an open node has no
//! tangent block, so the derivatives of a face without a pressed node would go unused. The
//! tangent is unchanged, bit for bit; where the contact zone is smaller than the surfaces the
//! search pairs, the linearized kernel (the costliest part of the contact work) shrinks with it
//! (measured on `cases/hertz`: the mortar integration 3.0 s -> 0.95 s, the run 9.6 s -> 7.4 s,
//! every output the same). The derivatives of the other faces are neither computed nor
//! checked: a non-finite one no longer stops the evaluation (it would have gone unused).
//!
//! # Uzawa
//!
//! After a converged Newton solve, each node's multipliers are updated (law::uzawa_update);
//! the violation of a node, relative to `h_A`, is the size of the normal update in gap units,
//! `|d lambda_N| / eps_N` (the penetration of a pressed node, the multiplier an open node still
//! holds), and the slip `|dsh_A|` of a sticking node (docs/theory.md section 4; a slipping node has
//! no tangential constraint to meet). A node without traction (no overlap, or coverage below
//! [`MIN_COVERAGE`]) has its multipliers released without counting a violation (they exert
//! no force whatever their value); a fading node keeps them and counts none. Solves repeat
//! while a penetration is above `uzawa_tol`
//! or a slip above `uzawa_slip_tol` (both relative to `h_A`; the slip tolerance is looser
//! because with the soft default tangential penalty each update removes only part of a
//! sticking node's slip), at most `uzawa_max` times per step. With
//! `penalty_growth > 1`, an augmentation that did not bring the violation below a quarter of the
//! previous one multiplies both penalties by that factor, up to `penalty_growth_cap`.
//!
//! # Stick predictor
//!
//! With [`ContactInterfaces::set_stick_all`] every pressed node sticks whatever its cone (the
//! law is called with `mu = infinity`): a smooth problem whose solution is a good start for the
//! Coulomb law, because the nodes that truly stick are already in place and those that slip
//! start from the direction of the tangential traction that sticking would need. The solver uses
//! it when `steps.stick_predictor` is set.
//!
//! # Parallel layout
//!
//! The mesh is replicated and every rank gathers the displacements of every contact surface
//! node. The contact work is dealt out by traction node, independently of the element
//! partition: METIS balances elements, and a partition whose cut does not cross the interface
//! leaves the whole surface to one rank. The passes of an interface are dealt to blocks of
//! ranks (`pass_ranks`: on two ranks each pass of a two-pass interface goes whole to one rank),
//! and each pass's nodes are cut into strips of equal counts along the longest side of the
//! secondary surface, one strip per rank of its block (`deal_in_strips`).
//!
//! The rank holding a traction node computes everything of that node and keeps its Uzawa
//! multipliers and history: it integrates every face pair whose secondary face carries a node
//! it holds (faces next to a strip cut are thus integrated by both neighbours; their pair
//! statistics are counted by the holder of the face's first traction node), sums them in a
//! canonical order (by secondary face, then primary face), and adds the node's forces and
//! tangent block into the distributed vector and matrix, whatever ranks own the rows (the
//! blocks summed first into node rows, [`BlockSum`]). The results are therefore independent of
//! the partition up to round-off: the order of PETSc's assembly, and which node blocks a rank
//! sums before it.
//!
//! # Matrix pattern
//!
//! The pattern of a node's block is every node of the faces carrying it and of the primary faces
//! their search finds. At the start of each step, [`ContactInterfaces::add_sparsity`] adds the
//! blocks of the pairs found with a search margin of [`PATTERN_MARGIN`] face sizes, twice the
//! margin the evaluations use ([`EVAL_MARGIN`]); the solver rebuilds the matrix when the pattern
//! grows. A pair that still falls outside the pattern inside a step costs PETSc a reallocation,
//! not an error.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::rc::Rc;

use mpi::collective::{CommunicatorCollectives, SystemOperation};
use mpi::topology::SimpleCommunicator;

use crate::case::{ContactMethod, Interface, InterfaceKind, Scene};
use crate::contact::block_sum::BlockSum;
use crate::contact::law::{
    carries_friction, friction_traction, normal_pressure_touching, touching_friction, uzawa_update,
    FrictionResult, LawParams, NodeHistory, Status,
};
use crate::contact::mortar::{
    integrate_pair, integrate_pair_linearized, sub_segments, traction_node_count, traction_nodes,
    traction_shape_on, FaceGeom, IntegrationOptions, LinearizedWeights, PalletSplit, RejectStats,
    TractionScheme,
};
use crate::contact::node_on_segment::{self as nts, NodeGeometry, NodeLaw, Segment};
use crate::contact::normals::{NodalNormals, SurfaceFace};
use crate::contact::search::{Aabb, PrimaryTree};
use crate::contact::tying::Augmented;
use crate::dofs::DofMap;
use crate::error::Result;
use crate::fe::shape::{normal_from_tangents, tangents_from_grad};
use crate::fe::FaceType;
use crate::mesh::FaceRef;
use crate::petsc::log::Section;
use crate::petsc::{Matrix, PetscInt, Sparsity, Vector};
use crate::vec3::{cross, dot, norm, tangential};

/// A node carries traction only if its overlap integral `a_A` is at least this fraction of its
/// full integral `a_full_A` (its coverage). It also bounds the coverage scaling of the
/// penalties ([`coverage_scale`]) at `1 / MIN_COVERAGE`.
pub const MIN_COVERAGE: f64 = 1e-3;

/// Between [`MIN_COVERAGE`] and this coverage a node's traction fades out
/// ([`coverage_fade`]); such a node takes no Uzawa update and is not held to the tolerances.
pub const FADE_COVERAGE: f64 = 0.05;

/// The factor `r` on the traction of a node of coverage `c`, with `dr/dc`: 0 below
/// [`MIN_COVERAGE`], 1 from [`FADE_COVERAGE`] on, and the smooth step `u^2 (3 - 2 u)`,
/// `u = (c - MIN_COVERAGE) / (FADE_COVERAGE - MIN_COVERAGE)`, between (continuous with its
/// first derivative, so that a node's force vanishes smoothly as it slides off).
pub fn coverage_fade(coverage: f64) -> (f64, f64) {
    let width = FADE_COVERAGE - MIN_COVERAGE;
    let u = ((coverage - MIN_COVERAGE) / width).clamp(0.0, 1.0);
    (u * u * (3.0 - 2.0 * u), 6.0 * u * (1.0 - u) / width)
}

/// A node whose overlap integral is within this fraction of its full integral counts as
/// covered: the pallets' quadrature and the full integral's differ in the last digits (and
/// more on curved faces), and without the margin covered nodes would hover about the kink of
/// the scale at coverage 1 (measured on `ci/extremes`: 96 Newton iterations instead of 76 for
/// the base slide, whose secondary surface is covered whole).
pub const COVERED_TOL: f64 = 1e-6;

/// The factor `s_A = (1 - COVERED_TOL) a_full_A / a_A` (continuous at the margin) by which the
/// penalties of a partly covered node are multiplied (`a_full_A` over the current faces
/// carrying A), `None` for a covered node (`a_A >= (1 - COVERED_TOL) a_full_A`: factor 1).
/// With it, the penalty *force* of a node per unit normalized gap, `a_A s_A eps`, is that of a
/// fully covered node whatever its coverage (module docs, "Coverage scale"). Called for nodes
/// with `a_A >= MIN_COVERAGE a_full_A`, so `s_A <= 1 / MIN_COVERAGE`.
pub fn coverage_scale(area: f64, a_full: f64) -> Option<f64> {
    let covered = (1.0 - COVERED_TOL) * a_full;
    (area > 0.0 && area < covered).then(|| covered / area)
}

/// Number of figures of [`ContactInterfaces::force_sums`] per interface.
pub const FORCE_SUMS: usize = 9;

/// Gaps within this fraction of `h_A` of closing count as touching: zero pressure, closed
/// tangent ([`normal_pressure_touching`]), so that surfaces that start in contact without load
/// hold each other from the first iteration.
pub const TOUCH_TOLERANCE: f64 = 1e-10;

/// Search margin of the evaluations, in secondary-face box diagonals.
pub const EVAL_MARGIN: f64 = 0.5;

/// Search margin of the matrix pattern made at the start of a step, in face box diagonals.
pub const PATTERN_MARGIN: f64 = 1.0;

/// Node-on-segment: primary faces whose boxes come within this many `h_A` of the node are
/// candidates for its closest face.
pub const NTS_MARGIN: f64 = 0.5;

/// Node-on-segment: the search margin of the matrix pattern, in `h_A`.
pub const NTS_PATTERN_MARGIN: f64 = 1.0;

/// The state of one traction node that persists between Newton solves.
#[derive(Clone, Debug, Default)]
pub struct NodeState {
    /// Uzawa multipliers and the converged tangential traction of the last step.
    pub history: NodeHistory,
    /// Initial penalties `alpha E / h_A` and `alpha_T E / h_A`.
    pub eps_n: f64,
    pub eps_t: f64,
    /// `h_A`: the mean size (square root of the area) of the secondary faces around A.
    pub h: f64,
    /// Integral of the node's traction function over the whole secondary surface (reference).
    pub a_full: f64,
    /// Weighted gap vector at the last converged step, if the node had an overlap then.
    pub gap_old: Option<[f64; 3]>,
    /// Node-on-segment: the primary face and closest point of the last converged step.
    pub segment_old: Option<(usize, [f64; 2])>,
}

/// What a node looks like at one state: the fields written to the interface output.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NodeFields {
    /// `a_A` (0 without overlap).
    pub area: f64,
    /// The full integral of A's traction function over the current secondary faces around
    /// it (mortar nodes with traction; the reference one for node-on-segment; 0 otherwise).
    pub full_area: f64,
    /// Normalized gap `gh_A` (positive in penetration; 0 without overlap).
    pub gap: f64,
    /// Contact pressure `p_A >= 0`.
    pub pressure: f64,
    /// Normalized slip increment of the step `dsh_A`, tangential part.
    pub slip: [f64; 3],
    /// Tangential traction `t_T` (as applied: times the fade of a fading node).
    pub traction_t: [f64; 3],
    /// The return map's `t_T` before the fade: the history of the next step (not in
    /// `pass_fields`).
    pub law_traction_t: [f64; 3],
    /// Unit nodal normal.
    pub normal: [f64; 3],
    /// 0 open (no overlap, open, or inside the touching band), 1 stick, 2 slip.
    pub status: u8,
    /// The weighted gap vector `g_A` (zero without overlap; not in `pass_fields`).
    pub weighted_gap: [f64; 3],
    /// Node-on-segment: the primary face and closest point (not in `pass_fields`).
    pub segment: Option<(usize, [f64; 2])>,
}

/// One pass: which side carries the tractions, and its nodes' state.
#[derive(Clone, Debug)]
pub struct ContactPass {
    /// Faces carrying the tractions.
    pub secondary: Vec<FaceRef>,
    sec_faces: Vec<FaceData>,
    pri_faces: Vec<FaceData>,
    /// Traction nodes (global ids), ascending.
    pub nodes: Vec<usize>,
    /// Per secondary face: the index into `nodes` of its k-th traction node.
    carriers: Vec<Vec<usize>>,
    /// Per traction node: the secondary faces carrying it, with its index `k` in each.
    node_faces: Vec<Vec<(usize, usize)>>,
    /// Per traction node. The multipliers and history (`history`, `gap_old`, `segment_old`)
    /// are kept only by the rank holding the node; elsewhere they stay as they started. (The
    /// node-on-segment pattern reads `segment_old` on every rank: a row owned by another rank
    /// may then miss the old face's columns, which costs PETSc a reallocation, not an error.)
    pub state: Vec<NodeState>,
    /// Secondary faces that carry a node this rank holds (the faces it integrates).
    local_faces: Vec<usize>,
    /// The traction nodes this rank holds: it does their contact work and keeps their
    /// multipliers and history (indices into `nodes`; see "Parallel layout").
    held: Vec<usize>,
    /// Per secondary face: this rank reports the face's pair statistics (it holds the face's
    /// first traction node), so that a face integrated on two ranks counts once.
    tallied: Vec<bool>,
    /// Symmetry constraints `(node, axis)` of the secondary surface (for the normals).
    symmetry: Vec<(usize, usize)>,
    /// Mortar or node-on-segment.
    method: ContactMethod,
    /// Every node of the pass's faces, ascending: their positions key `last_values`.
    surface_nodes: Vec<usize>,
    /// The last values-only integration ([`ContactPass::values_at`]).
    last_values: RefCell<Option<ValuesAt>>,
}

/// The values-only pairs of a pass at one set of positions, with their statistics.
#[derive(Clone, Debug)]
struct ValuesAt {
    /// Positions of the pass's `surface_nodes`, as bits (so that `-0.0` and NaN compare as
    /// what they are).
    positions: Vec<[u64; 3]>,
    pairs: Rc<Vec<PairData>>,
    stats: RejectStats,
}

/// A face's type and global nodes.
#[derive(Clone, Debug)]
struct FaceData {
    kind: FaceType,
    nodes: Vec<usize>,
}

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
    pub uzawa_max: usize,
    penalty_growth: f64,
    penalty_growth_cap: f64,
    /// Current multiple of the initial penalties.
    pub penalty_scale: f64,
    /// Violation after the previous augmentation of this step (for the penalty growth).
    last_violation: f64,
    quadrature_degree: Option<usize>,
    pallets: PalletSplit,
    pub passes: Vec<ContactPass>,
    /// Rejected and integrated segment pairs of this rank's last evaluation.
    pub stats: std::cell::RefCell<RejectStats>,
}

/// Every contact interface of a scene, as this rank sees it.
#[derive(Clone, Debug, Default)]
pub struct ContactInterfaces {
    pub interfaces: Vec<ContactInterface>,
    rank: usize,
    /// Positions of every node at the last converged step.
    x_old: Vec<[f64; 3]>,
    /// Every pressed node sticks (the stick predictor), whatever its Coulomb cone.
    stick_all: std::cell::Cell<bool>,
    /// Where the time of the residual and tangent evaluations goes.
    pub timings: ContactTimings,
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

/// A state saved before a step, to restore when the step is cut.
#[derive(Clone, Debug)]
pub struct Saved {
    states: Vec<Vec<Vec<NodeState>>>,
    scales: Vec<f64>,
}

/// The weights of one face pair of one evaluation.
#[derive(Clone, Debug)]
struct PairData {
    /// Index of the secondary face in the pass.
    s: usize,
    /// Index of the primary face.
    m: usize,
    /// Values, and derivatives when the tangent is wanted.
    w: LinearizedWeights,
}

/// Traction nodes (indices into a pass's nodes) with their pairs and their traction index in
/// each pair's secondary face ([`ContactPass::pairs_by_node`]).
type ByNode<'p> = BTreeMap<usize, Vec<(&'p PairData, usize)>>;

/// The secondary faces whose pairs a tangent evaluation linearizes.
#[derive(Clone, Copy)]
enum Linearize {
    /// The faces carrying a node the law presses ([`ContactPass::pressed_faces`]): the others'
    /// derivatives would go unused.
    PressedFaces,
    /// Every face of a held node (tests: the reference for [`Linearize::PressedFaces`]).
    #[cfg_attr(not(test), allow(dead_code))]
    EveryFace,
}

/// The forces and (optionally) tangent block of one node, in local slot numbering.
struct NodeBlock {
    /// Global nodes of the slots.
    slots: Vec<usize>,
    /// Force on each slot dof (`3 slot + c`).
    force: Vec<f64>,
    /// Tangent, row-major `3m x 3m` (empty when not wanted).
    tangent: Vec<f64>,
}

impl ContactInterface {
    /// What an evaluation of this interface needs at positions `x` (old positions `x_old`).
    fn context<'a>(
        &self,
        stick_all: bool,
        x: &'a [[f64; 3]],
        x_old: &'a [[f64; 3]],
    ) -> EvalContext<'a> {
        EvalContext {
            iface_mu: self.mu,
            stick_all,
            scheme: self.scheme,
            degree: self.quadrature_degree,
            pallets: self.pallets,
            scale: self.penalty_scale,
            x,
            x_old,
            face_integrals: RefCell::new(BTreeMap::new()),
        }
    }
}

impl ContactInterfaces {
    /// Sets up every contact interface: faces, traction nodes, their full integrals and
    /// penalties, and which faces this rank integrates.
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
                let (sec, pri) = if pass == 0 {
                    (&iface.secondary, &iface.primary)
                } else {
                    (&iface.primary, &iface.secondary)
                };
                let workers = pass_ranks(pass, iface.passes, dofs.ranks);
                passes.push(ContactPass::new(
                    scene, dofs, iface, sec, pri, &young, workers,
                )?);
            }
            interfaces.push(ContactInterface {
                name: iface.name.clone(),
                scheme: iface.scheme,
                mu: iface.friction,
                uzawa_tol: iface.uzawa_tol,
                uzawa_slip_tol: iface.uzawa_slip_tol,
                uzawa_max: iface.uzawa_max,
                penalty_growth: iface.penalty_growth,
                penalty_growth_cap: iface.penalty_growth_cap,
                penalty_scale: 1.0,
                last_violation: f64::INFINITY,
                quadrature_degree: iface.quadrature_degree,
                pallets: iface.pallets,
                passes,
                stats: Default::default(),
            });
        }
        Ok(ContactInterfaces {
            interfaces,
            rank: dofs.rank,
            x_old: scene.mesh.coords.clone(),
            stick_all: Default::default(),
            timings: ContactTimings::default(),
        })
    }

    /// True when a contact interface has friction.
    pub fn has_friction(&self) -> bool {
        self.interfaces.iter().any(|i| i.mu > 0.0)
    }

    /// Switches the stick predictor on or off (module docs, "Stick predictor").
    pub fn set_stick_all(&self, on: bool) {
        self.stick_all.set(on);
    }

    /// True when the scene has no contact interface.
    pub fn is_empty(&self) -> bool {
        self.interfaces.is_empty()
    }

    /// Every node of every contact surface (whose displacements every rank gathers).
    pub fn nodes(&self) -> Vec<usize> {
        let mut n: Vec<usize> = self
            .interfaces
            .iter()
            .flat_map(|i| i.passes.iter())
            .flat_map(|p| p.surface_nodes.iter().copied())
            .collect();
        n.sort_unstable();
        n.dedup();
        n
    }

    /// Adds the contact forces of the nodes this rank holds to `f` (not assembled). Returns a
    /// description of a failure that must cut the step (a degenerate normal), if any.
    pub fn add_residual(
        &self,
        scene: &Scene,
        dofs: &DofMap,
        u: &[f64],
        f: &mut Vector,
    ) -> Result<Option<String>> {
        self.assemble(scene, u, false, |block| {
            let idx = global_dofs(dofs, &block.slots);
            f.set_values(&idx, &block.force, true)
        })
    }

    /// Adds the contact tangent of the nodes this rank holds to `jac` (not assembled), their
    /// blocks summed first into sparse node rows ([`BlockSum`]).
    pub fn add_jacobian(
        &self,
        scene: &Scene,
        dofs: &DofMap,
        u: &[f64],
        jac: &mut Matrix,
    ) -> Result<Option<String>> {
        let mut sum = BlockSum::default();
        let failure = self.assemble(scene, u, true, |block| {
            sum.add(&block.slots, &block.tangent);
            Ok(())
        })?;
        self.timings.assembly.time(|| sum.add_to(dofs, jac))?;
        Ok(failure)
    }

    /// Adds the contact forces of the held nodes at every dof (constrained ones included)
    /// into `out` (dof-indexed), for reactions.
    pub fn add_nodal_forces(&self, scene: &Scene, u: &[f64], out: &mut [f64]) {
        let _ = self.assemble(scene, u, false, |block| {
            for (s, &n) in block.slots.iter().enumerate() {
                for c in 0..3 {
                    out[3 * n + c] += block.force[3 * s + c];
                }
            }
            Ok(())
        });
    }

    /// Evaluates every pass and hands each held node's block to `sink`.
    fn assemble(
        &self,
        scene: &Scene,
        u: &[f64],
        tangent: bool,
        sink: impl FnMut(&NodeBlock) -> Result<()>,
    ) -> Result<Option<String>> {
        self.assemble_linearizing(scene, u, tangent, Linearize::PressedFaces, sink)
    }

    /// [`Self::assemble`], with a tangent that linearizes the pairs of the faces `linearize`
    /// says.
    fn assemble_linearizing(
        &self,
        scene: &Scene,
        u: &[f64],
        tangent: bool,
        linearize: Linearize,
        mut sink: impl FnMut(&NodeBlock) -> Result<()>,
    ) -> Result<Option<String>> {
        let x = current_positions(scene, u);
        let timed = &self.timings;
        for iface in &self.interfaces {
            let mut stats = RejectStats::default();
            // A pass this rank holds no node of costs it nothing (not even its normals).
            for pass in iface.passes.iter().filter(|p| !p.held.is_empty()) {
                let ctx = iface.context(self.stick_all.get(), &x, &self.x_old);
                if pass.method == ContactMethod::NodeOnSegment {
                    let tree = timed.search.time(|| pass.primary_tree(&x));
                    let failed = timed.assembly.time(|| -> Result<bool> {
                        for &a in &pass.held {
                            let (block, _) = pass.nts_node(&ctx, &tree, a, tangent);
                            if let Some(block) = block {
                                if block.force.iter().any(|v| !v.is_finite()) {
                                    return Ok(true);
                                }
                                sink(&block)?;
                            }
                        }
                        Ok(false)
                    })?;
                    if failed {
                        return Ok(Some(format!(
                            "interface '{}': non-finite node-on-segment force",
                            iface.name
                        )));
                    }
                    continue;
                }
                let normals = match timed.integration.time(|| pass.normals(&x)) {
                    Ok(n) => n,
                    Err(e) => return Ok(Some(format!("interface '{}': {e}", iface.name))),
                };
                let values = pass.values_at(&ctx, Some(timed), &mut stats);
                if stats.non_finite > 0 {
                    return Ok(Some(non_finite(&iface.name)));
                }
                let (measured, kinematics) = timed.assembly.time(|| pass.measured(&ctx, &values));
                // The tangent's weights with their derivatives, of the faces of pressed nodes
                // only; the law's inputs (area, gap, slip) still come from the residual's
                // weights, so that every branch of the law (open or pressed, stick or slip,
                // which the cone's tie band decides to 1e-10) is the one the residual took.
                // The two kernels' weights agree to round-off only, and a gap of a penalty's
                // penetration, a difference of positions of order 1, magnifies that to 1e-10
                // relative and more.
                let linearized = if tangent {
                    let faces = match linearize {
                        Linearize::PressedFaces => timed
                            .assembly
                            .time(|| pass.pressed_faces(&ctx, &normals, &kinematics)),
                        Linearize::EveryFace => pass.local_faces.clone(),
                    };
                    // (No pressed node: no search either.)
                    let candidates = if faces.is_empty() {
                        Vec::new()
                    } else {
                        timed
                            .search
                            .time(|| pass.candidates(&x, &faces, EVAL_MARGIN))
                    };
                    let mut own = RejectStats::default();
                    let integrate = || pass.integrate(&ctx, candidates, true, &mut own);
                    let pairs = timed.integration.time(integrate);
                    // The pairs are counted by the residual's weights; only derivatives (of
                    // the linearized faces: the others' are neither computed nor checked) that
                    // are not finite where the values are stop the evaluation.
                    if own.non_finite > 0 {
                        return Ok(Some(non_finite(&iface.name)));
                    }
                    Some(pairs)
                } else {
                    None
                };
                timed.assembly.time(|| -> Result<()> {
                    let differentiated = linearized
                        .as_ref()
                        .map(|pairs| pass.pairs_by_node(pairs, &pass.held));
                    let by_node = differentiated.as_ref().unwrap_or(&measured);
                    for (&a, terms) in by_node {
                        // A node without residual weights has no force to linearize.
                        let Some(kin) = kinematics.get(&a) else {
                            continue;
                        };
                        let (block, _) = pass.node_block(&ctx, &normals, a, kin, terms, tangent);
                        if let Some(block) = block {
                            sink(&block)?;
                        }
                    }
                    Ok(())
                })?;
            }
            *iface.stats.borrow_mut() = stats;
        }
        Ok(None)
    }

    /// Fields of every traction node of one pass at displacements `u`, on every rank (holders
    /// compute, all sum).
    pub fn pass_fields(
        &self,
        scene: &Scene,
        interface: usize,
        pass: usize,
        u: &[f64],
        world: &SimpleCommunicator,
    ) -> Vec<NodeFields> {
        let local = self.local_fields(scene, interface, pass, u);
        let pass_ref = &self.interfaces[interface].passes[pass];
        let mut flat = vec![0.0; 15 * pass_ref.nodes.len()];
        for (i, f) in local {
            let v = &mut flat[15 * i..15 * i + 15];
            v[0] = f.area;
            v[1] = f.gap;
            v[2] = f.pressure;
            v[3..6].copy_from_slice(&f.slip);
            v[6..9].copy_from_slice(&f.traction_t);
            v[9..12].copy_from_slice(&f.normal);
            v[12] = f.status as f64;
            v[13] = f.full_area;
        }
        let mut all = vec![0.0; flat.len()];
        world.all_reduce_into(&flat[..], &mut all[..], SystemOperation::sum());
        all.chunks(15)
            .map(|v| NodeFields {
                area: v[0],
                gap: v[1],
                pressure: v[2],
                slip: [v[3], v[4], v[5]],
                traction_t: [v[6], v[7], v[8]],
                normal: [v[9], v[10], v[11]],
                status: v[12] as u8,
                full_area: v[13],
                law_traction_t: [0.0; 3],
                weighted_gap: [0.0; 3],
                segment: None,
            })
            .collect()
    }

    /// Fields of the held traction nodes of one pass, `(index into nodes, fields)`.
    fn local_fields(
        &self,
        scene: &Scene,
        interface: usize,
        pass: usize,
        u: &[f64],
    ) -> Vec<(usize, NodeFields)> {
        let iface = &self.interfaces[interface];
        let p = &iface.passes[pass];
        if p.held.is_empty() {
            return Vec::new();
        }
        let x = current_positions(scene, u);
        let ctx = iface.context(self.stick_all.get(), &x, &self.x_old);
        if p.method == ContactMethod::NodeOnSegment {
            let tree = p.primary_tree(&x);
            return p
                .held
                .iter()
                .map(|&a| (a, p.nts_node(&ctx, &tree, a, false).1))
                .collect();
        }
        let Ok(normals) = p.normals(&x) else {
            return Vec::new();
        };
        let pairs = p.values_at(&ctx, None, &mut RejectStats::default());
        let by_node = p.pairs_by_node(&pairs, &p.held);
        p.held
            .iter()
            .map(|&a| {
                let fields = match by_node.get(&a) {
                    Some(terms) => {
                        let kin = p.kinematics(&ctx, terms);
                        p.node_block(&ctx, &normals, a, &kin, terms, false).1
                    }
                    None => NodeFields {
                        normal: normals.normal(p.nodes[a]).unwrap_or_default(),
                        ..Default::default()
                    },
                };
                (a, fields)
            })
            .collect()
    }

    /// Total contact force per interface, summed over passes and ranks:
    /// `[normal, tangential, fx, fy, fz, stick, slip, dissipation, max_slip]`, with
    /// `normal = sum_A a_A p_A`,
    /// `tangential = |sum_A a_A t_T,A|`, `f = sum_A a_A t_A` (the force on the primary side of
    /// the first pass; the second pass's terms enter with the opposite sign, its sides being
    /// swapped), the numbers of sticking and slipping nodes, and the frictional work of the
    /// step `sum_A a_A t_T,A . dsh_A` (non-negative: friction dissipates), and the largest
    /// step slip `|dsh_A|` of a pressed node.
    pub fn force_sums(
        &self,
        scene: &Scene,
        u: &[f64],
        world: &SimpleCommunicator,
    ) -> Vec<[f64; FORCE_SUMS]> {
        let mut local = Vec::new();
        let mut local_max = Vec::new();
        for i in 0..self.interfaces.len() {
            let mut v = [0.0; 10];
            let mut max_slip = 0.0f64;
            for p in 0..self.interfaces[i].passes.len() {
                // Forces on the primary side of the first pass: the second pass's primary is
                // the first pass's secondary.
                let sign = if p == 0 { 1.0 } else { -1.0 };
                for (_, nf) in self.local_fields(scene, i, p, u) {
                    v[0] += nf.area * nf.pressure;
                    for c in 0..3 {
                        v[1 + c] += sign * nf.area * nf.traction_t[c];
                        v[4 + c] +=
                            sign * nf.area * (nf.pressure * nf.normal[c] + nf.traction_t[c]);
                    }
                    match nf.status {
                        1 => v[7] += 1.0,
                        2 => v[8] += 1.0,
                        _ => {}
                    }
                    v[9] += nf.area * dot(nf.traction_t, nf.slip);
                    if nf.pressure > 0.0 {
                        max_slip = max_slip.max(norm(nf.slip));
                    }
                }
            }
            local.extend(v);
            local_max.push(max_slip);
        }
        let mut all = vec![0.0; local.len()];
        world.all_reduce_into(&local[..], &mut all[..], SystemOperation::sum());
        let mut all_max = vec![0.0; local_max.len()];
        world.all_reduce_into(&local_max[..], &mut all_max[..], SystemOperation::max());
        all.chunks(10)
            .zip(all_max)
            .map(|(v, m)| {
                [
                    v[0],
                    norm([v[1], v[2], v[3]]),
                    v[4],
                    v[5],
                    v[6],
                    v[7],
                    v[8],
                    v[9],
                    m,
                ]
            })
            .collect()
    }

    /// Adds the contact blocks of every node to the pattern of the rows this rank owns: the
    /// pairs found at displacements `u` with the margin [`PATTERN_MARGIN`]. Returns true if the
    /// pattern grew.
    pub fn add_sparsity(
        &self,
        scene: &Scene,
        dofs: &DofMap,
        u: &[f64],
        sparsity: &mut Sparsity,
    ) -> bool {
        let x = current_positions(scene, u);
        let owned = dofs.owned_start..dofs.owned_start + dofs.owned_count;
        let owns = |g: PetscInt| g >= 0 && owned.contains(&(g as usize));
        // The nodes each node with an owned dof couples to, gathered per node: the three dofs
        // of a node share their columns, and a node lies in many stencils.
        let mut coupled: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
        for pass in self.interfaces.iter().flat_map(|i| i.passes.iter()) {
            let mut stencil = match pass.method {
                ContactMethod::Mortar => pass.mortar_stencils(&x),
                ContactMethod::NodeOnSegment => pass.nts_stencils(&x),
            };
            for nodes in &mut stencil {
                nodes.sort_unstable();
                nodes.dedup();
                for &n in nodes.iter() {
                    if dofs.global[3 * n..3 * n + 3].iter().any(|&g| owns(g)) {
                        coupled.entry(n).or_default().extend_from_slice(nodes);
                    }
                }
            }
        }
        let mut grew = false;
        for (n, mut nodes) in coupled {
            nodes.sort_unstable();
            nodes.dedup();
            let cols: Vec<PetscInt> = global_dofs(dofs, &nodes)
                .into_iter()
                .filter(|&g| g >= 0)
                .collect();
            for &g in dofs.global[3 * n..3 * n + 3].iter().filter(|&&g| owns(g)) {
                let row = &mut sparsity.rows[g as usize - dofs.owned_start];
                let before = row.len();
                row.extend_from_slice(&cols);
                row.sort_unstable();
                row.dedup();
                grew |= row.len() != before;
            }
        }
        grew
    }

    /// One Uzawa step (collective): every interface whose largest violation exceeds its
    /// tolerances and that has augmentations left (`done < uzawa_max`) updates the
    /// multipliers of its held nodes. Returns what happened and the largest violation, as a
    /// multiple of its tolerance (at most 1 when met).
    pub fn augment(
        &mut self,
        scene: &Scene,
        u: &[f64],
        done: usize,
        world: &SimpleCommunicator,
    ) -> (Augmented, f64) {
        let mut result = Augmented::Converged;
        let mut worst = 0.0f64;
        for i in 0..self.interfaces.len() {
            let updates = self.uzawa_updates(scene, i, u);
            let local = updates.iter().map(|u| u.2).fold(0.0, f64::max);
            let mut violation = 0.0;
            world.all_reduce_into(&local, &mut violation, SystemOperation::max());
            worst = worst.max(violation);
            let iface = &mut self.interfaces[i];
            if violation <= 1.0 || iface.uzawa_max == 0 {
                continue;
            }
            if done >= iface.uzawa_max {
                if result == Augmented::Converged {
                    result = Augmented::CapReached;
                }
                continue;
            }
            for (p, a, _, h) in updates {
                iface.passes[p].state[a].history = h;
            }
            if violation > 0.25 * iface.last_violation && iface.penalty_growth > 1.0 {
                iface.penalty_scale =
                    (iface.penalty_scale * iface.penalty_growth).min(iface.penalty_growth_cap);
            }
            iface.last_violation = violation;
            result = Augmented::Updated;
        }
        (result, worst)
    }

    /// The Uzawa update of every held node of interface `i`: `(pass, node, violation as a
    /// multiple of its tolerance, new history)`.
    fn uzawa_updates(
        &self,
        scene: &Scene,
        i: usize,
        u: &[f64],
    ) -> Vec<(usize, usize, f64, NodeHistory)> {
        let iface = &self.interfaces[i];
        let mut out = Vec::new();
        for (p, pass) in iface.passes.iter().enumerate() {
            for (a, f) in self.local_fields(scene, i, p, u) {
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
                    norm(f.slip)
                } else {
                    0.0
                };
                let violation = (dn / iface.uzawa_tol).max(dt / iface.uzawa_slip_tol) / st.h;
                out.push((p, a, violation, new));
            }
        }
        out
    }

    /// Closes a converged step: the tangential tractions, normals and weighted gaps of the
    /// held nodes become the history of the next step; `u` becomes the old displacement.
    pub fn commit(&mut self, scene: &Scene, u: &[f64]) {
        for i in 0..self.interfaces.len() {
            let mu = self.interfaces[i].mu;
            for p in 0..self.interfaces[i].passes.len() {
                let fields = self.local_fields(scene, i, p, u);
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
        }
        self.x_old = current_positions(scene, u);
    }

    /// The state to restore if the coming step is cut.
    pub fn save(&self) -> Saved {
        Saved {
            states: self
                .interfaces
                .iter()
                .map(|i| i.passes.iter().map(|p| p.state.clone()).collect())
                .collect(),
            scales: self.interfaces.iter().map(|i| i.penalty_scale).collect(),
        }
    }

    /// Restores a state saved by [`ContactInterfaces::save`].
    pub fn restore(&mut self, saved: &Saved) {
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
        }
    }

    /// This rank.
    pub fn rank(&self) -> usize {
        self.rank
    }
}

/// What one evaluation of a pass needs besides the pass.
struct EvalContext<'a> {
    iface_mu: f64,
    /// The stick predictor is on: pressed nodes stick whatever their cone.
    stick_all: bool,
    scheme: TractionScheme,
    degree: Option<usize>,
    pallets: PalletSplit,
    scale: f64,
    /// Current and last converged positions of every node.
    x: &'a [[f64; 3]],
    x_old: &'a [[f64; 3]],
    /// The traction integrals of the secondary faces at `x`, computed once per face for the
    /// nodes they carry (with the gradient if it was asked for).
    face_integrals: RefCell<BTreeMap<usize, Rc<TractionIntegrals>>>,
}

/// Sums of one node's weights.
struct Kinematics {
    area: f64,
    gap: [f64; 3],
    /// The current weights applied to the old positions (friction only).
    gap_at_old: [f64; 3],
}

impl ContactPass {
    fn new(
        scene: &Scene,
        dofs: &DofMap,
        iface: &Interface,
        sec: &[FaceRef],
        pri: &[FaceRef],
        young: &[f64],
        workers: std::ops::Range<usize>,
    ) -> Result<ContactPass> {
        let mesh = &scene.mesh;
        let data = |faces: &[FaceRef]| -> Vec<FaceData> {
            faces
                .iter()
                .map(|&f| FaceData {
                    kind: mesh.face_type(f),
                    nodes: mesh.face_nodes(f),
                })
                .collect()
        };
        let sec_faces = data(sec);
        let pri_faces = data(pri);
        let carrier_scheme = iface.method.carrier_scheme(iface.scheme);
        let mut nodes: Vec<usize> = Vec::new();
        let mut local_carriers: Vec<Vec<usize>> = Vec::new();
        for f in &sec_faces {
            let ks = traction_nodes(f.kind, carrier_scheme).map_err(crate::Error::Mesh)?;
            let global: Vec<usize> = ks.iter().map(|&k| f.nodes[k]).collect();
            nodes.extend(&global);
            local_carriers.push(global);
        }
        nodes.sort_unstable();
        nodes.dedup();
        let index: BTreeMap<usize, usize> =
            nodes.iter().enumerate().map(|(i, &n)| (n, i)).collect();
        let carriers: Vec<Vec<usize>> = local_carriers
            .iter()
            .map(|g| g.iter().map(|n| index[n]).collect())
            .collect();
        let (a_full, sizes) =
            full_integrals(scene, carrier_scheme, &sec_faces, &carriers, nodes.len());
        let mut node_faces = vec![Vec::new(); nodes.len()];
        for (f, car) in carriers.iter().enumerate() {
            for (k, &a) in car.iter().enumerate() {
                node_faces[a].push((f, k));
            }
        }
        let state = nodes
            .iter()
            .zip(a_full.iter().zip(&sizes))
            .map(|(&n, (&a, &h))| NodeState {
                eps_n: iface.penalty * young[n] / h,
                eps_t: iface.tangential_penalty * young[n] / h,
                h,
                a_full: a,
                ..Default::default()
            })
            .collect();
        let points: Vec<[f64; 3]> = nodes.iter().map(|&n| mesh.coords[n]).collect();
        let holder: Vec<usize> = deal_in_strips(&points, workers.len())
            .into_iter()
            .map(|strip| workers.start + strip)
            .collect();
        let held: Vec<usize> = (0..nodes.len())
            .filter(|&a| holder[a] == dofs.rank)
            .collect();
        let local_faces: Vec<usize> = (0..sec_faces.len())
            .filter(|&s| carriers[s].iter().any(|&a| holder[a] == dofs.rank))
            .collect();
        let tallied = carriers
            .iter()
            .map(|c| c.first().is_some_and(|&a| holder[a] == dofs.rank))
            .collect();
        let surface: std::collections::BTreeSet<usize> = sec_faces
            .iter()
            .flat_map(|f| f.nodes.iter().copied())
            .collect();
        let symmetry = scene
            .symmetry
            .iter()
            .filter(|(n, _)| surface.contains(n))
            .copied()
            .collect();
        let mut surface_nodes: Vec<usize> = sec_faces
            .iter()
            .chain(&pri_faces)
            .flat_map(|f| f.nodes.iter().copied())
            .collect();
        surface_nodes.sort_unstable();
        surface_nodes.dedup();
        Ok(ContactPass {
            secondary: sec.to_vec(),
            sec_faces,
            pri_faces,
            nodes,
            carriers,
            node_faces,
            state,
            local_faces,
            held,
            tallied,
            symmetry,
            method: iface.method,
            surface_nodes,
            last_values: RefCell::new(None),
        })
    }

    /// The law's parameters at a node: its penalties times the interface's growth factor
    /// `scale` and the node's [`coverage_scale`] `coverage` (1 for a covered node).
    fn law_params(&self, st: &NodeState, mu: f64, scale: f64, coverage: f64) -> LawParams {
        let scale = scale * coverage;
        LawParams {
            eps_n: st.eps_n * scale,
            eps_t: st.eps_t * scale,
            mu,
        }
    }

    /// The full integral of traction node `a`'s function over the secondary faces carrying
    /// it at positions `x` ([`traction_integrals`]), with its gradient if asked.
    fn full_integral(&self, ctx: &EvalContext, a: usize, gradient: bool) -> FullIntegral {
        let mut full = FullIntegral {
            value: 0.0,
            gradient: Vec::new(),
        };
        for &(f, k) in &self.node_faces[a] {
            let face = &self.sec_faces[f];
            let n = face.nodes.len();
            let cached = ctx.face_integrals.borrow().get(&f).cloned();
            let integrals = match cached {
                Some(i) if !gradient || !i.gradient.is_empty() => i,
                _ => {
                    let xf: Vec<[f64; 3]> = face.nodes.iter().map(|&m| ctx.x[m]).collect();
                    let scheme = self.method.carrier_scheme(ctx.scheme);
                    let i = Rc::new(traction_integrals(
                        face.kind,
                        scheme,
                        &xf,
                        gradient,
                        |_, _| {},
                    ));
                    ctx.face_integrals.borrow_mut().insert(f, Rc::clone(&i));
                    i
                }
            };
            full.value += integrals.value[k];
            if gradient {
                let per_node = &integrals.gradient[k * n..(k + 1) * n];
                full.gradient
                    .extend(face.nodes.iter().copied().zip(per_node.iter().copied()));
            }
        }
        full
    }

    /// Nodal normals of the secondary surface at positions `x`.
    fn normals(&self, x: &[[f64; 3]]) -> std::result::Result<NodalNormals, String> {
        let faces: Vec<SurfaceFace> = self
            .sec_faces
            .iter()
            .map(|f| SurfaceFace {
                kind: f.kind,
                nodes: &f.nodes,
            })
            .collect();
        NodalNormals::compute(&faces, x, &self.symmetry)
    }

    /// Candidate primary faces (ascending) of each of `faces` (secondary indices) at positions
    /// `x`, with a search margin of `margin` box diagonals.
    fn candidates(&self, x: &[[f64; 3]], faces: &[usize], margin: f64) -> Vec<(usize, Vec<usize>)> {
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
    fn primary_tree(&self, x: &[[f64; 3]]) -> PrimaryTree {
        let boxes: Vec<Aabb> = self
            .pri_faces
            .iter()
            .map(|f| Aabb::of_points(&f.nodes.iter().map(|&n| x[n]).collect::<Vec<_>>()))
            .collect();
        PrimaryTree::new(&boxes)
    }

    /// Mortar: the nodes each traction node couples (its faces and their candidate primary
    /// faces at the pattern margin), unsorted.
    fn mortar_stencils(&self, x: &[[f64; 3]]) -> Vec<Vec<usize>> {
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

    /// Node-on-segment: the nodes each node couples (itself, the primary faces within the
    /// pattern margin, and its old face), unsorted.
    fn nts_stencils(&self, x: &[[f64; 3]]) -> Vec<Vec<usize>> {
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

    /// Node-on-segment forces (and tangent) of node `a` on its closest primary face, and its
    /// fields. `None` when no primary face lies under the node (its projection on every face
    /// within [`NTS_MARGIN`] `h_A` falls outside the face) or the node is open.
    fn nts_node(
        &self,
        ctx: &EvalContext,
        tree: &PrimaryTree,
        a: usize,
        tangent: bool,
    ) -> (Option<NodeBlock>, NodeFields) {
        let st = &self.state[a];
        let node = self.nodes[a];
        let p = ctx.x[node];
        let coords = |m: usize| -> Vec<[f64; 3]> {
            self.pri_faces[m].nodes.iter().map(|&n| ctx.x[n]).collect()
        };
        let mut found = Vec::new();
        tree.query(
            &Aabb::of_points(&[p]).inflated(NTS_MARGIN * st.h),
            &mut found,
        );
        let faces: Vec<(usize, Vec<[f64; 3]>)> = found.iter().map(|&m| (m, coords(m))).collect();
        let closest = nts::closest(
            faces.iter().map(|(m, xs)| {
                (
                    *m,
                    Segment {
                        kind: self.pri_faces[*m].kind,
                        x: xs,
                    },
                )
            }),
            p,
        );
        let Some((m, projection)) = closest.filter(|(_, pr)| pr.inside) else {
            return (None, NodeFields::default());
        };
        let xs = &faces.iter().find(|(k, _)| *k == m).expect("found face").1;
        let old_x = st
            .segment_old
            .filter(|_| ctx.iface_mu > 0.0)
            .map(|(mo, xi)| (mo, coords(mo), xi));
        let geo = NodeGeometry {
            x_node: p,
            segment: Segment {
                kind: self.pri_faces[m].kind,
                x: xs,
            },
            projection,
            old: old_x.as_ref().map(|(mo, xo, xi)| {
                (
                    Segment {
                        kind: self.pri_faces[*mo].kind,
                        x: xo,
                    },
                    *xi,
                )
            }),
        };
        let law = NodeLaw {
            history: &st.history,
            params: self.law_params(st, ctx.iface_mu, ctx.scale, 1.0),
            touch: TOUCH_TOLERANCE * st.h,
            area: st.a_full,
            stick_all: ctx.stick_all,
        };
        let Some(c) = nts::node_contribution(&geo, &law, tangent) else {
            return (None, NodeFields::default());
        };
        let fields = NodeFields {
            area: st.a_full,
            full_area: st.a_full,
            gap: c.gh,
            pressure: c.pressure,
            slip: c.slip,
            traction_t: c.friction.traction,
            law_traction_t: c.friction.traction,
            normal: c.nu,
            status: match c.friction.status {
                Status::Open => 0,
                Status::Stick => 1,
                Status::Slip => 2,
            },
            weighted_gap: [0.0; 3],
            segment: Some((m, projection.xi)),
        };
        if c.dp_dgh == 0.0 {
            return (None, fields);
        }
        let mut slots = vec![node];
        slots.extend(&self.pri_faces[m].nodes);
        if let Some((mo, _, _)) = &old_x {
            slots.extend(&self.pri_faces[*mo].nodes);
        }
        let block = NodeBlock {
            slots,
            force: c.force,
            tangent: c.tangent,
        };
        (Some(block), fields)
    }

    /// The candidate pairs of this rank's faces integrated at positions `ctx.x`, values only,
    /// with their statistics added to `stats`; the search and the integration are timed in
    /// `timed` when given.
    ///
    /// The weights are a function of the positions alone, and a state is evaluated several
    /// times: by a residual and the tangent that follows it at the same point (the law's
    /// inputs; module docs, "Consistent tangent"), and at a converged state by the Uzawa
    /// update, the reactions, the output and the commit of the step. So the last result is
    /// kept and returned again while the pass's nodes sit at the same positions, bit for bit.
    fn values_at(
        &self,
        ctx: &EvalContext,
        timed: Option<&ContactTimings>,
        stats: &mut RejectStats,
    ) -> Rc<Vec<PairData>> {
        let positions: Vec<[u64; 3]> = self
            .surface_nodes
            .iter()
            .map(|&n| ctx.x[n].map(f64::to_bits))
            .collect();
        if let Some(last) = self.last_values.borrow().as_ref() {
            if last.positions == positions {
                stats.add(&last.stats);
                return Rc::clone(&last.pairs);
            }
        }
        let search = || self.candidates(ctx.x, &self.local_faces, EVAL_MARGIN);
        let candidates = match timed {
            Some(t) => t.search.time(search),
            None => search(),
        };
        let mut own = RejectStats::default();
        let integrate = || self.integrate(ctx, candidates, false, &mut own);
        let pairs = Rc::new(match timed {
            Some(t) => t.integration.time(integrate),
            None => integrate(),
        });
        stats.add(&own);
        *self.last_values.borrow_mut() = Some(ValuesAt {
            positions,
            pairs: Rc::clone(&pairs),
            stats: own,
        });
        pairs
    }

    /// Integrates every candidate pair (secondary face, its candidate primary faces; see
    /// [`ContactPass::candidates`]), in canonical order; the pair statistics of the faces this
    /// rank tallies go to `stats` (non-finite values from every face).
    fn integrate(
        &self,
        ctx: &EvalContext,
        candidates: Vec<(usize, Vec<usize>)>,
        tangent: bool,
        stats: &mut RejectStats,
    ) -> Vec<PairData> {
        let mut out = Vec::new();
        for (s, ms) in candidates {
            let sf = &self.sec_faces[s];
            let sx: Vec<[f64; 3]> = sf.nodes.iter().map(|&n| ctx.x[n]).collect();
            for m in ms {
                let pf = &self.pri_faces[m];
                let px: Vec<[f64; 3]> = pf.nodes.iter().map(|&n| ctx.x[n]).collect();
                let mut opts = IntegrationOptions::for_faces(ctx.scheme, sf.kind, pf.kind);
                if let Some(d) = ctx.degree {
                    opts.degree = d;
                }
                opts.pallets = ctx.pallets;
                let (sg, pg) = (
                    FaceGeom {
                        kind: sf.kind,
                        x: &sx,
                    },
                    FaceGeom {
                        kind: pf.kind,
                        x: &px,
                    },
                );
                let mut face_stats = RejectStats::default();
                let w = if tangent {
                    integrate_pair_linearized(&sg, &pg, &opts, &mut face_stats)
                } else {
                    let values = integrate_pair(&sg, &pg, &opts, &mut face_stats);
                    dense_values(&values, sf, pf, ctx.scheme)
                };
                if self.tallied[s] {
                    stats.add(&face_stats);
                } else {
                    // Counted by the rank that tallies the face; a failure still counts here.
                    stats.non_finite += face_stats.non_finite;
                }
                if w.area > 0.0 {
                    out.push(PairData { s, m, w });
                }
            }
        }
        out
    }

    /// The pairs carrying each of `nodes` (indices into `self.nodes`), with the traction index
    /// `k` of the node in the pair's secondary face.
    fn pairs_by_node<'p>(&self, pairs: &'p [PairData], nodes: &[usize]) -> ByNode<'p> {
        let wanted: std::collections::BTreeSet<usize> = nodes.iter().copied().collect();
        let mut out: BTreeMap<usize, Vec<(&PairData, usize)>> = BTreeMap::new();
        for pair in pairs {
            for (k, &a) in self.carriers[pair.s].iter().enumerate() {
                if wanted.contains(&a) {
                    out.entry(a).or_default().push((pair, k));
                }
            }
        }
        out
    }

    /// The held nodes' pairs in the residual's weights `values` ([`Self::pairs_by_node`]) and
    /// their [`Self::kinematics`]: the law's inputs of a residual and of a tangent.
    fn measured<'p>(
        &self,
        ctx: &EvalContext,
        values: &'p [PairData],
    ) -> (ByNode<'p>, BTreeMap<usize, Kinematics>) {
        let measured = self.pairs_by_node(values, &self.held);
        let kinematics = measured
            .iter()
            .map(|(&a, terms)| (a, self.kinematics(ctx, terms)))
            .collect();
        (measured, kinematics)
    }

    /// `a_A`, `g_A` and (friction) the current weights on the old positions.
    fn kinematics(&self, ctx: &EvalContext, terms: &[(&PairData, usize)]) -> Kinematics {
        let mut k = Kinematics {
            area: 0.0,
            gap: [0.0; 3],
            gap_at_old: [0.0; 3],
        };
        let friction = ctx.iface_mu > 0.0;
        for &(pair, t) in terms {
            let w = &pair.w;
            let (sf, pf) = (&self.sec_faces[pair.s], &self.pri_faces[pair.m]);
            for (b, &n) in sf.nodes.iter().enumerate() {
                let v = w.n1[t * w.sec_nodes + b];
                k.area += v;
                for c in 0..3 {
                    k.gap[c] += v * ctx.x[n][c];
                    if friction {
                        k.gap_at_old[c] += v * ctx.x_old[n][c];
                    }
                }
            }
            for (cn, &n) in pf.nodes.iter().enumerate() {
                let v = w.n2[t * w.pri_nodes + cn];
                for c in 0..3 {
                    k.gap[c] -= v * ctx.x[n][c];
                    if friction {
                        k.gap_at_old[c] -= v * ctx.x_old[n][c];
                    }
                }
            }
        }
        k
    }

    /// The normal part of the law at traction node `a` (normal `nu`) from its kinematics
    /// `kin`: `None` when the node is covered less than [`MIN_COVERAGE`] and carries no
    /// traction. Shared by [`Self::node_block`] and [`Self::pressed_faces`], so that both
    /// decide alike which nodes are pressed.
    fn normal_law(
        &self,
        ctx: &EvalContext,
        a: usize,
        nu: [f64; 3],
        kin: &Kinematics,
    ) -> Option<NormalLaw> {
        let st = &self.state[a];
        let full = self.full_integral(ctx, a, false);
        if kin.area < MIN_COVERAGE * full.value {
            return None;
        }
        let gh = dot(nu, kin.gap) / kin.area;
        let coverage = coverage_scale(kin.area, full.value);
        let prm = self.law_params(st, ctx.iface_mu, ctx.scale, coverage.unwrap_or(1.0));
        let (p, dp_dgh) =
            normal_pressure_touching(st.history.lambda_n, prm.eps_n, gh, TOUCH_TOLERANCE * st.h);
        Some(NormalLaw {
            full,
            gh,
            coverage,
            prm,
            p,
            dp_dgh,
        })
    }

    /// The secondary faces (ascending) carrying a node of `kinematics` (held nodes and their
    /// [`Self::kinematics`]) that the law presses (`dp/dgh != 0`: in contact or within the
    /// touching band). Only these faces' pairs are linearized: an open node has no tangent
    /// ([`Self::node_block`] returns none), so the derivatives of a pair whose secondary face
    /// carries no pressed node would go unused. Where the contact zone is smaller than the
    /// surfaces the search pairs (a Hertz contact), this skips most of the linearized kernel.
    fn pressed_faces(
        &self,
        ctx: &EvalContext,
        normals: &NodalNormals,
        kinematics: &BTreeMap<usize, Kinematics>,
    ) -> Vec<usize> {
        let mut faces = std::collections::BTreeSet::new();
        for (&a, kin) in kinematics {
            let nu = normals.normal(self.nodes[a]).unwrap_or_default();
            let pressed = self
                .normal_law(ctx, a, nu, kin)
                .is_some_and(|law| law.dp_dgh != 0.0);
            if pressed {
                faces.extend(self.node_faces[a].iter().map(|&(f, _)| f));
            }
        }
        faces.into_iter().collect()
    }

    /// Forces (and tangent) of traction node `a` from its pairs `terms`, and its fields.
    /// `None` when the node carries no traction. `kin` is the node's [`Self::kinematics`]:
    /// of `terms` for a residual, of the residual's weights for a tangent (see
    /// [`ContactInterfaces::assemble_linearizing`]).
    fn node_block(
        &self,
        ctx: &EvalContext,
        normals: &NodalNormals,
        a: usize,
        kin: &Kinematics,
        terms: &[(&PairData, usize)],
        tangent: bool,
    ) -> (Option<NodeBlock>, NodeFields) {
        let st = &self.state[a];
        let node = self.nodes[a];
        let nu = normals.normal(node).unwrap_or_default();
        let mut fields = NodeFields {
            normal: nu,
            ..Default::default()
        };
        let Some(NormalLaw {
            mut full,
            gh,
            coverage,
            prm,
            p,
            dp_dgh,
        }) = self.normal_law(ctx, a, nu, kin)
        else {
            return (None, fields);
        };
        let area = kin.area;
        let (fade, dfade) = coverage_fade(area / full.value);
        if coverage.is_some() && tangent {
            full = self.full_integral(ctx, a, true);
        }
        let slip_history = ctx.iface_mu > 0.0 && st.gap_old.is_some();
        let dsh = match st.gap_old {
            Some(g_old) if slip_history => {
                std::array::from_fn(|c| (g_old[c] - kin.gap_at_old[c]) / area)
            }
            _ => [0.0; 3],
        };
        let touching = dp_dgh > 0.0 && !carries_friction(p, prm.eps_n, TOUCH_TOLERANCE * st.h);
        let fr = if ctx.iface_mu > 0.0 && touching {
            touching_friction(nu, &prm)
        } else if ctx.iface_mu > 0.0 && p > 0.0 {
            let law = if ctx.stick_all {
                LawParams {
                    mu: f64::INFINITY,
                    ..prm
                }
            } else {
                prm
            };
            friction_traction(&st.history, &law, nu, p, dsh)
        } else {
            FrictionResult::frictionless(p)
        };
        let t: [f64; 3] = std::array::from_fn(|c| p * nu[c] + fr.traction[c]);
        fields = NodeFields {
            area,
            full_area: full.value,
            gap: gh,
            pressure: fade * p,
            slip: tangential(dsh, nu),
            traction_t: fr.traction.map(|v| fade * v),
            law_traction_t: fr.traction,
            normal: nu,
            status: match fr.status {
                Status::Open => 0,
                Status::Stick => 1,
                Status::Slip => 2,
            },
            weighted_gap: kin.gap,
            segment: None,
        };
        if dp_dgh == 0.0 {
            return (None, fields);
        }
        let mut block = Slots::new(self, normals, node, terms);
        if coverage.is_some() && tangent {
            block.include(full.gradient.iter().map(|g| g.0));
        }
        let applied = t.map(|v| fade * v);
        block.add_forces(self, terms, applied);
        if tangent {
            let lin = Linearization {
                nu,
                gap: kin.gap,
                area,
                gh,
                p,
                dp_dgh,
                coverage: coverage.is_some().then_some(&full),
                fade: (fade < 1.0).then_some((fade, dfade, t)),
                dsh,
                friction: (ctx.iface_mu > 0.0).then_some(&fr),
                slip_history,
            };
            block.add_tangent(self, ctx, normals, node, terms, &lin, applied);
        }
        (Some(block.into_block()), fields)
    }
}

/// The normal part of the law at one node ([`ContactPass::normal_law`]).
struct NormalLaw {
    /// The node's full integral (its value; no gradient).
    full: FullIntegral,
    /// The mean normal gap `nu . g / a`.
    gh: f64,
    /// The node's [`coverage_scale`], when it is partly covered.
    coverage: Option<f64>,
    /// The law's parameters, coverage scale included.
    prm: LawParams,
    /// The normal pressure and its derivative with respect to `gh`.
    p: f64,
    dp_dgh: f64,
}

/// Values at one node that the tangent needs.
struct Linearization<'a> {
    nu: [f64; 3],
    gap: [f64; 3],
    area: f64,
    gh: f64,
    p: f64,
    dp_dgh: f64,
    /// The full integral when the penalties carry the coverage scale `s = a_full / a`, whose
    /// derivative `ds / s = d a_full / a_full - da / a` enters `d (eps gh)` and `d (eps_t dsh)`.
    coverage: Option<&'a FullIntegral>,
    /// A fading node ([`coverage_fade`]): `r`, `dr/dc` and the traction before the factor,
    /// `t`; the force is `r t`, and `d (r t) = r dt + t dr`, `dc = -c ds / s`.
    fade: Option<(f64, f64, [f64; 3])>,
    dsh: [f64; 3],
    /// The return map's result and derivatives (friction only).
    friction: Option<&'a FrictionResult>,
    /// The slip is measured (the node had an overlap at the last converged step); otherwise
    /// it is the constant zero.
    slip_history: bool,
}

/// Local numbering of the nodes one traction node couples, with its force and tangent.
struct Slots {
    nodes: Vec<usize>,
    force: Vec<f64>,
    tangent: Vec<f64>,
}

impl Slots {
    /// Slots for every node of the pairs of the node and of its normal's stencil.
    fn new(
        pass: &ContactPass,
        normals: &NodalNormals,
        node: usize,
        terms: &[(&PairData, usize)],
    ) -> Slots {
        let mut nodes: Vec<usize> = normals.derivative(node).iter().map(|d| d.0).collect();
        for &(pair, _) in terms {
            nodes.extend(&pass.sec_faces[pair.s].nodes);
            nodes.extend(&pass.pri_faces[pair.m].nodes);
        }
        nodes.sort_unstable();
        nodes.dedup();
        let n = 3 * nodes.len();
        Slots {
            nodes,
            force: vec![0.0; n],
            tangent: Vec::new(),
        }
    }

    /// Adds slots for `nodes` (before any force or tangent is added).
    fn include(&mut self, nodes: impl Iterator<Item = usize>) {
        self.nodes.extend(nodes);
        self.nodes.sort_unstable();
        self.nodes.dedup();
        self.force = vec![0.0; 3 * self.nodes.len()];
    }

    fn slot(&self, node: usize) -> usize {
        self.nodes
            .binary_search(&node)
            .expect("contact: node outside its own stencil")
    }

    /// Column of each pair-local input dof (secondary face nodes, then primary).
    fn pair_columns(&self, pass: &ContactPass, pair: &PairData) -> Vec<usize> {
        pass.sec_faces[pair.s]
            .nodes
            .iter()
            .chain(&pass.pri_faces[pair.m].nodes)
            .flat_map(|&n| {
                let s = self.slot(n);
                (0..3).map(move |c| 3 * s + c)
            })
            .collect()
    }

    /// Residual terms: `F_B += n1_AB t`, `F_C -= n2_AC t` (the residual is internal minus
    /// external force, and the secondary node receives `-n1_AB t`).
    fn add_forces(&mut self, pass: &ContactPass, terms: &[(&PairData, usize)], t: [f64; 3]) {
        for &(pair, k) in terms {
            let w = &pair.w;
            for (b, &n) in pass.sec_faces[pair.s].nodes.iter().enumerate() {
                let v = w.n1[k * w.sec_nodes + b];
                let s = self.slot(n);
                for (f, tc) in self.force[3 * s..3 * s + 3].iter_mut().zip(t) {
                    *f += v * tc;
                }
            }
            for (cn, &n) in pass.pri_faces[pair.m].nodes.iter().enumerate() {
                let v = w.n2[k * w.pri_nodes + cn];
                let s = self.slot(n);
                for (f, tc) in self.force[3 * s..3 * s + 3].iter_mut().zip(t) {
                    *f -= v * tc;
                }
            }
        }
    }

    /// The tangent block (module docs, "Consistent tangent").
    #[allow(clippy::too_many_arguments)]
    fn add_tangent(
        &mut self,
        pass: &ContactPass,
        ctx: &EvalContext,
        normals: &NodalNormals,
        node: usize,
        terms: &[(&PairData, usize)],
        lin: &Linearization,
        t: [f64; 3],
    ) {
        let n = 3 * self.nodes.len();
        let friction = lin.friction.is_some();
        // Differentials (rows of length n): d a, d g, d gt, d nu.
        let mut da = vec![0.0; n];
        let mut dg = vec![vec![0.0; n]; 3];
        let mut dgt = vec![vec![0.0; n]; 3];
        let mut dnu = vec![vec![0.0; n]; 3];
        for &(b, m) in normals.derivative(node) {
            let s = self.slot(b);
            for i in 0..3 {
                for j in 0..3 {
                    dnu[i][3 * s + j] += m[i][j];
                }
            }
        }
        let mut columns = Vec::with_capacity(terms.len());
        for &(pair, k) in terms {
            let w = &pair.w;
            let cols = self.pair_columns(pass, pair);
            let nd = w.ndof();
            let sec = &pass.sec_faces[pair.s].nodes;
            let pri = &pass.pri_faces[pair.m].nodes;
            for (b, &nb) in sec.iter().enumerate() {
                let r = k * w.sec_nodes + b;
                let (v, dv) = (w.n1[r], &w.dn1[r * nd..(r + 1) * nd]);
                let s = self.slot(nb);
                for (j, &col) in cols.iter().enumerate() {
                    da[col] += dv[j];
                    for i in 0..3 {
                        dg[i][col] += dv[j] * ctx.x[nb][i];
                        if friction {
                            dgt[i][col] += dv[j] * ctx.x_old[nb][i];
                        }
                    }
                }
                for i in 0..3 {
                    dg[i][3 * s + i] += v;
                }
            }
            for (cn, &nc) in pri.iter().enumerate() {
                let r = k * w.pri_nodes + cn;
                let (v, dv) = (w.n2[r], &w.dn2[r * nd..(r + 1) * nd]);
                let s = self.slot(nc);
                for (j, &col) in cols.iter().enumerate() {
                    for i in 0..3 {
                        dg[i][col] -= dv[j] * ctx.x[nc][i];
                        if friction {
                            dgt[i][col] -= dv[j] * ctx.x_old[nc][i];
                        }
                    }
                }
                for i in 0..3 {
                    dg[i][3 * s + i] -= v;
                }
            }
            columns.push(cols);
        }
        // The coverage scale's `ds / s` (zero without it): the law's inputs are in effect
        // `s gh` and `s dsh`, and `dp_dgh`, `dt_T/d dsh` already hold `s`.
        let mut ds_over_s = vec![0.0; n];
        if let Some(full) = lin.coverage {
            for &(b, g) in &full.gradient {
                let s = self.slot(b);
                for c in 0..3 {
                    ds_over_s[3 * s + c] += g[c] / full.value;
                }
            }
            for (d, a) in ds_over_s.iter_mut().zip(&da) {
                *d -= a / lin.area;
            }
        }
        // d gh and d p.
        let dp: Vec<f64> = (0..n)
            .map(|col| {
                let dgh = ((0..3)
                    .map(|i| lin.nu[i] * dg[i][col] + lin.gap[i] * dnu[i][col])
                    .sum::<f64>()
                    - lin.gh * da[col])
                    / lin.area;
                lin.dp_dgh * (dgh + lin.gh * ds_over_s[col])
            })
            .collect();
        // d t = nu d p + p d nu + d t_T.
        let mut dt: Vec<Vec<f64>> = (0..3)
            .map(|i| {
                (0..n)
                    .map(|col| lin.nu[i] * dp[col] + lin.p * dnu[i][col])
                    .collect()
            })
            .collect();
        if let Some(fr) = lin.friction {
            for col in 0..n {
                let ddsh: [f64; 3] = if lin.slip_history {
                    std::array::from_fn(|i| {
                        -(dgt[i][col] + lin.dsh[i] * da[col]) / lin.area
                            + lin.dsh[i] * ds_over_s[col]
                    })
                } else {
                    [0.0; 3]
                };
                for (i, row) in dt.iter_mut().enumerate() {
                    let mut v = fr.d_p[i] * dp[col];
                    for j in 0..3 {
                        v += fr.d_dsh[i][j] * ddsh[j] + fr.d_nu[i][j] * dnu[j][col];
                    }
                    row[col] += v;
                }
            }
        }
        // A fading node: d (r t) = r dt + t (dr/dc) dc, with dc / c = -ds / s.
        if let Some((r, dr_dc, t_full)) = lin.fade {
            let c = lin.coverage.map_or(1.0, |full| lin.area / full.value);
            for (row, ti) in dt.iter_mut().zip(t_full) {
                for (v, dlog_s) in row.iter_mut().zip(&ds_over_s) {
                    *v = r * *v - ti * dr_dc * c * dlog_s;
                }
            }
        }
        // d F_B = d n1_AB t + n1_AB d t, d F_C = -(d n2_AC t + n2_AC d t).
        self.tangent = vec![0.0; n * n];
        for (&(pair, k), cols) in terms.iter().zip(&columns) {
            let w = &pair.w;
            let nd = w.ndof();
            let sides = [
                (
                    &pass.sec_faces[pair.s].nodes,
                    &w.n1,
                    &w.dn1,
                    w.sec_nodes,
                    1.0,
                ),
                (
                    &pass.pri_faces[pair.m].nodes,
                    &w.n2,
                    &w.dn2,
                    w.pri_nodes,
                    -1.0,
                ),
            ];
            for (nodes, vals, ders, count, sign) in sides {
                for (b, &nb) in nodes.iter().enumerate() {
                    let r = k * count + b;
                    let (v, dv) = (vals[r], &ders[r * nd..(r + 1) * nd]);
                    let s = self.slot(nb);
                    for i in 0..3 {
                        let row = &mut self.tangent[(3 * s + i) * n..(3 * s + i + 1) * n];
                        for (j, &col) in cols.iter().enumerate() {
                            row[col] += sign * dv[j] * t[i];
                        }
                        for (x, d) in row.iter_mut().zip(&dt[i]) {
                            *x += sign * v * d;
                        }
                    }
                }
            }
        }
    }

    fn into_block(self) -> NodeBlock {
        NodeBlock {
            slots: self.nodes,
            force: self.force,
            tangent: self.tangent,
        }
    }
}

/// Dense values of a pair's weights in the layout of [`LinearizedWeights`] (no derivatives).
fn dense_values(
    w: &crate::contact::mortar::PairWeights,
    sf: &FaceData,
    pf: &FaceData,
    scheme: TractionScheme,
) -> LinearizedWeights {
    let nt = traction_node_count(sf.kind, scheme);
    let (ns, np) = (sf.kind.num_nodes(), pf.kind.num_nodes());
    let mut out = LinearizedWeights {
        traction_nodes: nt,
        sec_nodes: ns,
        pri_nodes: np,
        n1: vec![0.0; nt * ns],
        n2: vec![0.0; nt * np],
        area: w.area,
        ..Default::default()
    };
    for &(k, b, v) in &w.n1 {
        out.n1[k * ns + b] += v;
    }
    for &(k, c, v) in &w.n2 {
        out.n2[k * np + c] += v;
    }
    out
}

/// `a_full` of every traction node (the integral of its traction function over every
/// secondary face, reference configuration) and `h_A` (the mean square root of the areas of
/// the faces around it).
fn full_integrals(
    scene: &Scene,
    scheme: TractionScheme,
    faces: &[FaceData],
    carriers: &[Vec<usize>],
    count: usize,
) -> (Vec<f64>, Vec<f64>) {
    let mut a = vec![0.0; count];
    let (mut size_sum, mut size_count) = (vec![0.0; count], vec![0.0; count]);
    for (f, car) in faces.iter().zip(carriers) {
        let x: Vec<[f64; 3]> = f.nodes.iter().map(|&n| scene.mesh.coords[n]).collect();
        // Summed point by point into `a` (the node-on-segment baseline, whose path is
        // sensitive to round-off, normalizes its gaps by these values).
        let integrals = traction_integrals(f.kind, scheme, &x, false, |k, v| a[car[k]] += v);
        for &node in car {
            size_sum[node] += integrals.area.sqrt();
            size_count[node] += 1.0;
        }
    }
    let h = size_sum
        .iter()
        .zip(&size_count)
        .map(|(s, c)| s / c)
        .collect();
    (a, h)
}

/// The full integral of one traction node over the current faces carrying it.
struct FullIntegral {
    value: f64,
    /// `(node, d value / d x_node)`, one entry per node of each face (a node shared by faces
    /// appears once per face).
    gradient: Vec<(usize, [f64; 3])>,
}

/// The integrals of a face's traction functions over the whole face at node positions `x`.
struct TractionIntegrals {
    /// The face's area.
    area: f64,
    /// `int Phi_k dA` for the face's k-th traction node.
    value: Vec<f64>,
    /// With the gradient: `d value[k] / d x_b` at `k * x.len() + b` (empty without).
    gradient: Vec<[f64; 3]>,
}

/// [`TractionIntegrals`] of a face: per sub-segment, so that scheme 3's piecewise functions
/// are integrated exactly, with a degree-6 rule. With `gradient`, also the derivatives with
/// respect to the face's node coordinates: `J = |x_,xi x x_,eta|` varies as
/// `dJ = (x_,eta x n) . dx_,xi + (n x x_,xi) . dx_,eta`, `dx_,i = sum_b N_b,i dx_b`.
/// `add(k, v)` also receives every quadrature point's term `v` of `value[k]`.
fn traction_integrals(
    kind: FaceType,
    scheme: TractionScheme,
    x: &[[f64; 3]],
    gradient: bool,
    mut add: impl FnMut(usize, f64),
) -> TractionIntegrals {
    let mut out = TractionIntegrals {
        area: 0.0,
        value: Vec::new(),
        gradient: Vec::new(),
    };
    let mut phi = Vec::new();
    let mut dn = vec![[0.0; 2]; x.len()];
    for seg in sub_segments(kind) {
        let rule = seg.linear_kind().quadrature(6);
        let jac = seg.parent_jacobian();
        for (q, w) in rule.points.iter().zip(&rule.weights) {
            let xi = seg.to_parent(*q);
            kind.shape_grad(xi, &mut dn);
            let (t1, t2) = tangents_from_grad(x, &dn);
            let (n, j_face) = normal_from_tangents(t1, t2);
            traction_shape_on(kind, scheme, &seg, xi, &mut phi);
            if out.value.is_empty() {
                out.value = vec![0.0; phi.len()];
                if gradient {
                    out.gradient = vec![[0.0; 3]; phi.len() * x.len()];
                }
            }
            out.area += w * jac * j_face;
            for (k, &phi_k) in phi.iter().enumerate() {
                let v = w * jac * j_face * phi_k;
                out.value[k] += v;
                add(k, v);
            }
            if gradient {
                let (a1, a2) = (cross(t2, n), cross(n, t1));
                for (b, g) in dn.iter().enumerate() {
                    let dj: [f64; 3] = std::array::from_fn(|c| g[0] * a1[c] + g[1] * a2[c]);
                    for (k, &phi_k) in phi.iter().enumerate() {
                        let slot = &mut out.gradient[k * x.len() + b];
                        for c in 0..3 {
                            slot[c] += w * jac * phi_k * dj[c];
                        }
                    }
                }
            }
        }
    }
    out
}

/// The ranks that share the contact work of pass `pass` of `passes`: the passes of an
/// interface are dealt out first, so that on two ranks the two passes of a two-pass interface
/// go one to each rank whole (no face is integrated twice); with more ranks than passes, each
/// pass gets its own block of ranks, which [`deal_in_strips`] then shares out.
fn pass_ranks(pass: usize, passes: usize, ranks: usize) -> std::ops::Range<usize> {
    if ranks >= passes {
        pass * ranks / passes..(pass + 1) * ranks / passes
    } else {
        let rank = pass * ranks / passes;
        rank..rank + 1
    }
}

/// The strip (of `strips`) that does the contact work of each traction node: the nodes, sorted
/// along the longest side of their bounding box (reference positions; ties by index), cut into
/// `strips` strips of equal counts. The faces next to each cut (one row of faces, or two when
/// the cut falls inside a row of nodes) are integrated by both neighbours. Equal counts are
/// equal work when the whole surface is in contact; a contact zone smaller than the surface
/// may fall in one strip.
fn deal_in_strips(points: &[[f64; 3]], strips: usize) -> Vec<usize> {
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
    let mut strip = vec![0; points.len()];
    for (position, &a) in order.iter().enumerate() {
        strip[a] = position * strips / points.len();
    }
    strip
}

/// The message of an evaluation stopped by non-finite mortar weights or derivatives.
fn non_finite(interface: &str) -> String {
    format!("interface '{interface}': non-finite values in the mortar integration")
}

/// Current positions `X + u` of every node.
fn current_positions(scene: &Scene, u: &[f64]) -> Vec<[f64; 3]> {
    scene
        .mesh
        .coords
        .iter()
        .enumerate()
        .map(|(n, x)| [x[0] + u[3 * n], x[1] + u[3 * n + 1], x[2] + u[3 * n + 2]])
        .collect()
}

/// Global dof indices of `nodes` (`3 slot + c` order; -1 where constrained).
fn global_dofs(dofs: &DofMap, nodes: &[usize]) -> Vec<PetscInt> {
    nodes
        .iter()
        .flat_map(|&n| dofs.global[3 * n..3 * n + 3].iter().copied())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{
        coverage_fade, current_positions, deal_in_strips, pass_ranks, traction_integrals,
        ContactInterfaces, Linearize, FADE_COVERAGE, MIN_COVERAGE,
    };
    use crate::case::Scene;
    use crate::contact::mortar::RejectStats;
    use crate::contact::mortar::TractionScheme;
    use crate::dofs::DofMap;
    use crate::fe::FaceType;
    use std::collections::BTreeSet;

    /// Two Hex8 blocks: the top of the lower one (4 x 4 faces, nodes every 0.25, the secondary
    /// side) covered by the upper one from x = 0.45 and y = 0.245 on, 0.01 deep. With bilinear
    /// traction functions a node's coverage is the product of its coverages along x and y:
    /// along x, the column at 0 has no overlap, the column at 0.25 is 2 % covered, the one at
    /// 0.5 68 %, the others wholly; along y, the row at 0 is 0.04 % covered (below
    /// [`MIN_COVERAGE`]), the row at 0.25 52 %, the others wholly.
    fn partly_covered_blocks() -> Scene {
        scene_of(PARTLY_COVERED)
    }

    /// The case text of [`partly_covered_blocks`].
    const PARTLY_COVERED: &str = r#"
name = "partly_covered"
[[mesh]]
body = "low"
generator = "box"
element = "hex8"
divisions = [4, 4, 1]
lo = [0.0, 0.0, 0.0]
hi = [1.0, 1.0, 0.5]
[[mesh]]
body = "up"
generator = "box"
element = "hex8"
divisions = [2, 2, 1]
lo = [0.45, 0.245, 0.49]
hi = [1.45, 1.245, 1.0]
[[material]]
body = "low"
model = "neo_hookean"
young = 1000.0
poisson = 0.3
[[material]]
body = "up"
model = "neo_hookean"
young = 1000.0
poisson = 0.3
[[symmetry]]
set = "low.zmin"
normal = "z"
[[dirichlet]]
set = "up.zmax"
components = ["x", "y", "z"]
value = [0.0, 0.0, 0.0]
[[interface]]
name = "blocks"
kind = "contact"
secondary = "low.zmax"
primary = "up.zmin"
scheme = 2
friction = 0.3
"#;

    /// The scene of a case text.
    fn scene_of(case: &str) -> Scene {
        // One folder per call: the tests run in parallel threads.
        static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("mortar-covered-{}-{call}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("case.toml");
        std::fs::write(&path, case).unwrap();
        let scene = Scene::load(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        scene
    }

    /// The Uzawa bookkeeping of partly covered nodes ([`partly_covered_blocks`]), every node
    /// starting with multipliers. One Uzawa update
    /// - releases the multipliers of the nodes without traction (no overlap, or below
    ///   [`MIN_COVERAGE`]), without a violation: they exert no force whatever their multipliers;
    /// - leaves the fading nodes out (below [`FADE_COVERAGE`]: no constraint to meet, the
    ///   multipliers kept);
    /// - updates every other node, partly covered or not, and counts its penetration as a
    ///   violation.
    ///
    /// Closing the step (`commit`, without applying the update) then releases the normal
    /// multiplier of the nodes without traction and keeps those of the others.
    #[test]
    fn uzawa_skips_fading_nodes_and_releases_nodes_without_traction() {
        let scene = partly_covered_blocks();
        let elements = vec![0; scene.mesh.num_elements()];
        let dofs = DofMap::new(&scene.mesh, elements, 0, 1, &scene.constrained_mask());
        let mut contact = ContactInterfaces::new(&scene, &dofs).unwrap();
        const LAMBDA_N: f64 = 5.0;
        for st in &mut contact.interfaces[0].passes[0].state {
            st.history.lambda_n = LAMBDA_N;
            st.history.lambda_t = [0.5, 0.0, 0.0];
        }
        let u = vec![0.0; 3 * scene.mesh.num_nodes()];

        let fields = contact.local_fields(&scene, 0, 0, &u);
        let updates = contact.uzawa_updates(&scene, 0, &u);
        // Nodes without traction, fading, partly covered, wholly covered.
        let mut counts = [0; 4];
        for (a, f) in &fields {
            let update = updates.iter().find(|(p, b, ..)| *p == 0 && b == a);
            let coverage = f.area / f.full_area;
            if f.area == 0.0 {
                counts[0] += 1;
                let (_, _, violation, new) = update.expect("a node without traction is released");
                assert_eq!(*violation, 0.0, "node {a}: a release is no violation");
                assert_eq!((new.lambda_n, new.lambda_t), (0.0, [0.0; 3]), "node {a}");
                continue;
            }
            if coverage < FADE_COVERAGE {
                counts[1] += 1;
                assert!(
                    update.is_none(),
                    "fading node {a} (coverage {coverage}) updated"
                );
                continue;
            }
            counts[if coverage < 1.0 - 1e-9 { 2 } else { 3 }] += 1;
            let (_, _, violation, new) = update.expect("a covered node is updated");
            assert!(f.gap > 0.0, "node {a}: gap {}", f.gap);
            assert!(*violation > 1.0, "node {a}: violation {violation}");
            assert!(
                new.lambda_n > LAMBDA_N,
                "node {a}: lambda_n {}",
                new.lambda_n
            );
        }
        // Without traction: the column at x = 0 and the rest of the row at y = 0; fading: the
        // rest of the column at x = 0.25; partly covered: the rest of the column at x = 0.5 and
        // of the row at y = 0.25.
        assert_eq!(counts, [9, 4, 6, 6]);

        contact.commit(&scene, &u);
        let pass = &contact.interfaces[0].passes[0];
        for (a, f) in &fields {
            let history = &pass.state[*a].history;
            if f.area == 0.0 {
                assert_eq!(history.lambda_n, 0.0, "node {a} without traction");
                assert_eq!(
                    history.traction_t_old, [0.0; 3],
                    "node {a} without traction"
                );
            } else {
                assert_eq!(history.lambda_n, LAMBDA_N, "node {a}");
            }
        }
    }

    /// A tangent linearizes only the pairs of the faces that carry a pressed node
    /// ([`Linearize::PressedFaces`]), and its blocks are bit for bit those of a tangent that
    /// linearizes every face, on each rank of 1 and of 2 (strips of held nodes, faces whose
    /// nodes two ranks hold): [`partly_covered_blocks`]
    /// - tilted: the upper block lifted by `0.06 (x - 0.45)` about y, so that it presses the
    ///   lower surface's nodes at x = 0.5 and the fading ones at x = 0.25 (1-2 % covered), and
    ///   stands over those at x = 0.75 and 1 (mean weighted gaps -0.008 and -0.018): the faces
    ///   between x = 0.75 and 1 overlap the upper block and carry no pressed node, and on one
    ///   rank those four are exactly the faces skipped;
    /// - flush: the upper block lifted by 0.01, onto the lower surface, so that the covered
    ///   nodes sit in the touching band (no pressure, a tangent: `dp/dgh > 0`).
    ///
    /// Checked to fail with every overlapping face linearized, with one face per pressed node,
    /// with "pressed" read as `p > 0` (the touching band left out), and with the fading nodes
    /// left out.
    #[test]
    fn tangent_linearizes_only_the_faces_of_pressed_nodes() {
        let scene = partly_covered_blocks();
        let mesh = &scene.mesh;
        let up = mesh.bodies.iter().position(|b| b == "up").unwrap();
        let lifted = |lift: &dyn Fn(f64) -> f64| {
            let mut u = vec![0.0; 3 * mesh.num_nodes()];
            for e in (0..mesh.num_elements()).filter(|&e| mesh.body[e] == up) {
                for &n in mesh.element_nodes(e) {
                    u[3 * n + 2] = lift(mesh.coords[n][0]);
                }
            }
            u
        };
        let tilted = lifted(&|x| 0.06 * (x - 0.45));
        let flush = lifted(&|_| 0.01);
        for (name, u) in [("tilted", &tilted), ("flush", &flush)] {
            for (rank, ranks) in [(0, 1), (0, 2), (1, 2)] {
                let elements = vec![0; mesh.num_elements()];
                let dofs = DofMap::new(mesh, elements, rank, ranks, &scene.constrained_mask());
                let contact = ContactInterfaces::new(&scene, &dofs).unwrap();
                let blocks = |linearize| {
                    let mut out: Vec<(Vec<usize>, Vec<u64>, Vec<u64>)> = Vec::new();
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect();
                    let failure = contact
                        .assemble_linearizing(&scene, u, true, linearize, |b| {
                            out.push((b.slots.clone(), bits(&b.force), bits(&b.tangent)));
                            Ok(())
                        })
                        .unwrap();
                    assert_eq!(failure, None, "{name}, rank {rank} of {ranks}");
                    out
                };
                let pressed = blocks(Linearize::PressedFaces);
                let every = blocks(Linearize::EveryFace);
                let at = format!("{name}, rank {rank} of {ranks}");
                assert!(pressed.iter().all(|b| !b.2.is_empty()), "{at}");
                assert_eq!(pressed.len(), every.len(), "{at}: blocks");
                if let Some(k) = (0..pressed.len()).find(|&k| pressed[k] != every[k]) {
                    panic!("{at}: the block of slots {:?} differs", pressed[k].0);
                }
                if ranks == 1 {
                    assert!(!pressed.is_empty(), "{at}: nothing pressed");
                }
            }
        }

        // Tilted, one rank: the faces with an overlap but no pressed node are the four of the
        // column between x = 0.75 and 1.
        let elements = vec![0; mesh.num_elements()];
        let dofs = DofMap::new(mesh, elements, 0, 1, &scene.constrained_mask());
        let contact = ContactInterfaces::new(&scene, &dofs).unwrap();
        let x = current_positions(&scene, &tilted);
        let iface = &contact.interfaces[0];
        let pass = &iface.passes[0];
        let ctx = iface.context(false, &x, &contact.x_old);
        let normals = pass.normals(&x).unwrap();
        let values = pass.values_at(&ctx, None, &mut RejectStats::default());
        let (_, kinematics) = pass.measured(&ctx, &values);
        let linearized: BTreeSet<usize> = pass
            .pressed_faces(&ctx, &normals, &kinematics)
            .into_iter()
            .collect();
        let skipped: BTreeSet<usize> = values
            .iter()
            .map(|p| p.s)
            .filter(|s| !linearized.contains(s))
            .collect();
        let column = |s: &usize| {
            let xs = pass.sec_faces[*s].nodes.iter().map(|&n| mesh.coords[n][0]);
            xs.fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(v), h.max(v)))
        };
        assert_eq!(skipped.len(), 4, "skipped faces {skipped:?}");
        assert!(skipped.iter().all(|s| column(s) == (0.75, 1.0)));
    }

    /// The fade is 0 up to MIN_COVERAGE, 1 from FADE_COVERAGE on, increasing between, with a
    /// continuous derivative that matches central differences (and is 0 at both ends).
    #[test]
    fn coverage_fade_is_a_smooth_step() {
        assert_eq!(coverage_fade(0.0), (0.0, 0.0));
        assert_eq!(coverage_fade(MIN_COVERAGE), (0.0, 0.0));
        assert_eq!(coverage_fade(FADE_COVERAGE), (1.0, 0.0));
        assert_eq!(coverage_fade(0.7), (1.0, 0.0));
        let mut last = 0.0;
        for i in 1..100 {
            let c = MIN_COVERAGE + (FADE_COVERAGE - MIN_COVERAGE) * i as f64 / 100.0;
            let (r, dr) = coverage_fade(c);
            assert!(r > last && r < 1.0, "not increasing at {c}");
            last = r;
            let h = 1e-7;
            let fd = (coverage_fade(c + h).0 - coverage_fade(c - h).0) / (2.0 * h);
            assert!(
                (dr - fd).abs() <= 1e-6 * dr.abs().max(1.0),
                "{c}: {dr} vs {fd}"
            );
        }
    }

    /// The traction integrals of a face: on a flat square the corner functions integrate to a
    /// quarter of the area each; on a curved, distorted Quad9 face the corner functions sum to
    /// the area, and the gradient matches central differences of the integrals.
    #[test]
    fn traction_integrals_and_their_gradient() {
        let square = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 2.0, 0.0],
            [0.0, 2.0, 0.0],
        ];
        let flat = traction_integrals(
            FaceType::Quad4,
            TractionScheme::Corners,
            &square,
            false,
            |_, _| {},
        );
        assert!((flat.area - 4.0).abs() < 1e-14);
        for v in &flat.value {
            assert!((v - 1.0).abs() < 1e-14, "{v}");
        }
        let parent = FaceType::Quad9.node_coords();
        let x: Vec<[f64; 3]> = parent
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let w = 0.05 * (i as f64 * 1.7).sin();
                [p[0] + w, p[1] - 0.5 * w, 0.2 * p[0] * p[0] + 0.1 * p[1] + w]
            })
            .collect();
        for scheme in [TractionScheme::Corners, TractionScheme::PiecewiseLinear] {
            let f = traction_integrals(FaceType::Quad9, scheme, &x, true, |_, _| {});
            if scheme == TractionScheme::Corners {
                let sum: f64 = f.value.iter().sum();
                assert!((sum - f.area).abs() < 1e-13 * f.area, "{sum} vs {}", f.area);
            }
            let h = 1e-6;
            for b in 0..x.len() {
                for c in 0..3 {
                    let mut xp = x.clone();
                    let mut xm = x.clone();
                    xp[b][c] += h;
                    xm[b][c] -= h;
                    let fp = traction_integrals(FaceType::Quad9, scheme, &xp, false, |_, _| {});
                    let fm = traction_integrals(FaceType::Quad9, scheme, &xm, false, |_, _| {});
                    for k in 0..f.value.len() {
                        let fd = (fp.value[k] - fm.value[k]) / (2.0 * h);
                        let g = f.gradient[k * x.len() + b][c];
                        assert!(
                            (g - fd).abs() < 1e-7,
                            "{scheme:?} k {k} node {b}.{c}: {g} vs {fd}"
                        );
                    }
                }
            }
        }
    }

    /// The contact pattern of [`ContactInterfaces::add_sparsity`] is the dof-by-dof one: every
    /// free dof of a stencil couples to every free dof of it, in the rows this rank owns,
    /// added to the bulk pattern; on each rank of a two-rank layout. A second call at the same
    /// state adds nothing.
    #[test]
    fn contact_pattern_couples_every_dof_of_a_stencil() {
        // As shipped, then with constrained dofs on both contact faces (their columns and rows
        // left out), then node-on-segment.
        let constrained = PARTLY_COVERED.replace(
            "[[dirichlet]]",
            "[[symmetry]]\nset = \"low.xmin\"\nnormal = \"x\"\n[[symmetry]]\nset = \"up.ymin\"\nnormal = \"y\"\n[[dirichlet]]",
        );
        let node_on_segment = PARTLY_COVERED.replace("scheme = 2", "method = \"node_on_segment\"");
        assert_eq!(check_contact_pattern(&scene_of(PARTLY_COVERED)), 0);
        assert!(check_contact_pattern(&scene_of(&constrained)) > 0);
        check_contact_pattern(&scene_of(&node_on_segment));
    }

    /// [`contact_pattern_couples_every_dof_of_a_stencil`] for one scene; returns how many
    /// constrained dofs the stencils held.
    fn check_contact_pattern(scene: &Scene) -> usize {
        let u = vec![0.0; 3 * scene.mesh.num_nodes()];
        let x = super::current_positions(scene, &u);
        let mut constrained = 0;
        let half = scene.mesh.num_elements() / 2;
        for rank in 0..2 {
            let elements = (0..scene.mesh.num_elements())
                .map(|e| usize::from(e >= half))
                .collect();
            let dofs = DofMap::new(&scene.mesh, elements, rank, 2, &scene.constrained_mask());
            let contact = ContactInterfaces::new(scene, &dofs).unwrap();
            let owned = dofs.owned_start..dofs.owned_start + dofs.owned_count;
            let mut expected = dofs.bulk_sparsity(&scene.mesh);
            let mut added = 0;
            for pass in contact.interfaces.iter().flat_map(|i| &i.passes) {
                let stencils = match pass.method {
                    super::ContactMethod::Mortar => pass.mortar_stencils(&x),
                    super::ContactMethod::NodeOnSegment => pass.nts_stencils(&x),
                };
                for nodes in stencils {
                    let all = super::global_dofs(&dofs, &nodes);
                    constrained += all.iter().filter(|&&g| g < 0).count();
                    let cols: Vec<_> = all.into_iter().filter(|&g| g >= 0).collect();
                    for &g in cols.iter().filter(|&&g| owned.contains(&(g as usize))) {
                        expected.rows[g as usize - dofs.owned_start].extend(&cols);
                        added += 1;
                    }
                }
            }
            assert!(added > 0, "rank {rank}: no contact rows owned");
            for row in &mut expected.rows {
                row.sort_unstable();
                row.dedup();
            }
            let mut sparsity = dofs.bulk_sparsity(&scene.mesh);
            assert!(contact.add_sparsity(scene, &dofs, &u, &mut sparsity));
            assert_eq!(sparsity.rows, expected.rows, "rank {rank}");
            assert!(!contact.add_sparsity(scene, &dofs, &u, &mut sparsity));
        }
        constrained
    }

    #[test]
    fn passes_are_dealt_before_strips() {
        // Two passes on two ranks: one each, whole.
        assert_eq!(pass_ranks(0, 2, 2), 0..1);
        assert_eq!(pass_ranks(1, 2, 2), 1..2);
        // One pass: every rank shares it.
        assert_eq!(pass_ranks(0, 1, 2), 0..2);
        // Two passes on one rank, or on four ranks.
        assert_eq!(pass_ranks(1, 2, 1), 0..1);
        assert_eq!(pass_ranks(1, 2, 4), 2..4);
        // Two passes on three ranks: blocks of 1 and 2.
        assert_eq!(pass_ranks(0, 2, 3), 0..1);
        assert_eq!(pass_ranks(1, 2, 3), 1..3);
    }

    #[test]
    fn every_node_is_held_by_exactly_one_rank() {
        let points: Vec<[f64; 3]> = (0..23)
            .map(|i| [(i % 5) as f64 * 0.3, (i / 5) as f64, 0.5 * (i % 2) as f64])
            .collect();
        for ranks in 1..=5 {
            for passes in 1..=2 {
                let mut held_by_pass = vec![0usize; passes];
                for (pass, held) in held_by_pass.iter_mut().enumerate() {
                    let workers = pass_ranks(pass, passes, ranks);
                    assert!(!workers.is_empty() && workers.end <= ranks);
                    let strips = deal_in_strips(&points, workers.len());
                    let mut counts = vec![0usize; workers.len()];
                    for &s in &strips {
                        counts[s] += 1;
                    }
                    let (lo, hi) = (counts.iter().min(), counts.iter().max());
                    assert!(hi.unwrap() - lo.unwrap() <= 1, "{ranks} ranks: {counts:?}");
                    *held += counts.iter().sum::<usize>();
                }
                assert!(held_by_pass.iter().all(|&n| n == points.len()));
                // Every rank gets a share of some pass.
                let used: std::collections::BTreeSet<usize> = (0..passes)
                    .flat_map(|p| pass_ranks(p, passes, ranks))
                    .collect();
                assert_eq!(used.len(), ranks);
            }
        }
        assert!(deal_in_strips(&[], 3).is_empty());
    }

    #[test]
    fn strips_split_along_the_longest_side_in_equal_counts() {
        // A 5 x 3 grid of points, longer along y: two ranks take the lower and upper rows.
        let points: Vec<[f64; 3]> = (0..15)
            .map(|i| [(i % 3) as f64, (i / 3) as f64, 1.0])
            .collect();
        let owner = deal_in_strips(&points, 2);
        let counts = [0, 1].map(|r| owner.iter().filter(|&&o| o == r).count());
        assert_eq!(counts, [8, 7]);
        for (p, &o) in points.iter().zip(&owner) {
            match p[1] {
                y if y < 2.0 => assert_eq!(o, 0),
                y if y > 2.0 => assert_eq!(o, 1),
                _ => {}
            }
        }
        // One rank holds everything; more ranks than points leave some empty.
        assert!(deal_in_strips(&points, 1).iter().all(|&o| o == 0));
        let many = deal_in_strips(&points[..2], 4);
        assert_eq!(many, vec![0, 2]);
    }
}
