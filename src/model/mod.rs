//! The discrete model a Newton iteration sees, as a list of contributions.
//!
//! `F(u; t) = f_int(u) - f_ext(u, t) + f_tie(u) + f_contact(u)`: the bulk of the solids
//! ([`crate::solid::Bulk`]), the tied interfaces ([`crate::contact::tying::TiedInterfaces`]) and
//! the contact interfaces ([`crate::contact::frictional::ContactInterfaces`]) each add their
//! terms. Every one of them implements [`Contribution`], one vocabulary for their life in a run:
//!
//! | stage | method | when |
//! |---|---|---|
//! | matrix pattern | [`Contribution::couplings`] | at set-up; at every step for a moving pattern |
//! | residual | [`Contribution::residual`] | every Newton iterate, the predictor, the reactions |
//! | tangent | [`Contribution::jacobian`] | every Newton iteration (and the predictor's) |
//! | augmentation (Uzawa) | [`Contribution::augment`] | after a converged Newton solve |
//! | a cut step | [`Contribution::save`], [`Contribution::restore`] | at a step's start, at a cut |
//! | a converged step | [`Contribution::commit`] | after the step's VTU files, before its history row |
//! | output | [`Contribution::output`], [`Contribution::history`] | per step written |
//! | checkpoint, restart | [`Contribution::write_state`], [`Contribution::read_state`] | after a commit; at a restart's set-up |
//! | summary | [`Contribution::metrics`] | at the end of a run |
//!
//! A contribution never touches PETSc: it hands out **blocks** over mesh nodes (three dofs per
//! node, `3 a + c` order) to a [`ForceSink`] or a [`TangentSink`], the way the element kernels
//! of [`crate::solid`] do, and the solver puts them into its distributed vector or matrix
//! (`solver::assembly`). The same residual blocks summed into a dof-indexed array give the
//! nodal forces of the reactions.
//!
//! Only what a scene requires is in its model: a scene without tied interfaces has no tying
//! contribution, and one without contact no contact contribution (no search, no Uzawa loop).

use mpi::topology::SimpleCommunicator;

use crate::case::Scene;
use crate::contact::mortar::TractionScheme;
use crate::error::Result;
use crate::mesh::FaceRef;

/// The state a contribution is evaluated at.
#[derive(Clone, Copy)]
pub struct State<'a> {
    pub scene: &'a Scene,
    /// Displacement of every dof this rank touches (`3 * node + c`); others are zero.
    pub u: &'a [f64],
    /// The load factor.
    pub t: f64,
}

impl State<'_> {
    /// Current positions `X + u` of every node.
    pub fn positions(&self) -> Vec<[f64; 3]> {
        self.scene
            .mesh
            .coords
            .iter()
            .enumerate()
            .map(|(n, x)| std::array::from_fn(|c| x[c] + self.u[3 * n + c]))
            .collect()
    }
}

/// Where residual blocks go.
pub trait ForceSink {
    /// Adds `forces` (three per node of `nodes`, `3 a + c`) to the residual.
    fn add_forces(&mut self, nodes: &[usize], forces: &[f64]) -> Result<()>;
}

/// Where tangent blocks go.
pub trait TangentSink {
    /// Adds the dense block `values` (row-major, `3 rows.len() x 3 cols.len()`, dofs `3 a + c`)
    /// of the rows of the nodes `rows` and the columns of the nodes `cols`. A node listed twice
    /// gets both its rows (columns) added.
    fn add_block(&mut self, rows: &[usize], cols: &[usize], values: &[f64]) -> Result<()>;
}

/// Nodal forces summed into a dof-indexed array (`3 * node + c`), constrained dofs included:
/// the internal forces of the reactions.
pub struct NodalForces<'a>(pub &'a mut [f64]);

impl ForceSink for NodalForces<'_> {
    fn add_forces(&mut self, nodes: &[usize], forces: &[f64]) -> Result<()> {
        for (a, &n) in nodes.iter().enumerate() {
            for c in 0..3 {
                self.0[3 * n + c] += forces[3 * a + c];
            }
        }
        Ok(())
    }
}

/// Where a contribution writes the state a restarted run needs ([`Contribution::write_state`]):
/// named arrays, kept bit for bit (`io::checkpoint`).
pub trait StateSink {
    fn f64s(&mut self, name: &str, values: &[f64]);
    fn u64s(&mut self, name: &str, values: &[u64]);
}

/// Where a restarted contribution reads its state back, in the order it was written: an
/// array of another name is an error naming both.
pub trait StateSource {
    fn f64s(&mut self, name: &str) -> Result<Vec<f64>>;
    fn u64s(&mut self, name: &str) -> Result<Vec<u64>>;
}

/// Where a residual or tangent evaluation found an inverted element.
#[derive(Clone, Debug)]
pub struct Inverted {
    pub element: usize,
    pub det: f64,
}

/// Why a state cannot be evaluated: the step must be cut.
#[derive(Clone, Debug)]
pub enum DomainIssue {
    /// An element with a non-positive Jacobian determinant.
    Inverted(Inverted),
    /// A contact evaluation failed (a degenerate normal, a non-finite value).
    Contact(String),
}

/// What one Uzawa step of a contribution did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Augmented {
    /// Every interface meets its tolerance (or is plain penalty): nothing changed.
    Converged,
    /// Some multipliers were updated: solve again.
    Updated,
    /// An interface is above its tolerance with no augmentations left.
    CapReached,
}

impl Augmented {
    /// The outcome of two contributions' Uzawa steps together: updated if either was, else
    /// capped if either was.
    pub fn and(self, other: Augmented) -> Augmented {
        use Augmented::*;
        match (self, other) {
            (Updated, _) | (_, Updated) => Updated,
            (CapReached, _) | (_, CapReached) => CapReached,
            _ => Converged,
        }
    }
}

/// An [`Augmented`] outcome with the violation left, in words for a warning (`tied relative
/// gap 1.2e-5`).
#[derive(Clone, Debug)]
pub struct Augmentation {
    pub outcome: Augmented,
    pub violation: String,
}

/// The nodes a Newton update carries through the other surface, held for its second solve
/// ([`Contribution::hold_closing`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Closing {
    /// How many are held.
    pub held: usize,
    /// How deep the update carries the deepest of them past closing, over its face size.
    pub deepest: f64,
}

impl Closing {
    /// Both together.
    pub fn and(self, other: Closing) -> Closing {
        Closing {
            held: self.held + other.held,
            deepest: self.deepest.max(other.deepest),
        }
    }
}

/// A point field of an interface piece, given at its traction nodes (one value set per row).
#[derive(Clone, Debug)]
pub struct RowField {
    pub name: &'static str,
    pub components: usize,
    /// `components` values per row.
    pub values: Vec<f64>,
    /// At nodes without a traction unknown (mid-nodes under scheme 2), the field interpolated
    /// by the scheme's traction functions; otherwise [`RowField::absent`] there.
    pub interpolate: bool,
    pub absent: f64,
}

impl RowField {
    /// A field of `components` values per row; zero where a node has no traction unknown,
    /// or interpolated there (`interpolate`).
    pub fn new(
        name: &'static str,
        components: usize,
        values: Vec<f64>,
        interpolate: bool,
    ) -> RowField {
        RowField {
            name,
            components,
            values,
            interpolate,
            absent: 0.0,
        }
    }

    /// The value written at nodes without a traction unknown, when not interpolated.
    pub fn absent_as(self, absent: f64) -> Self {
        RowField { absent, ..self }
    }
}

/// The output of one interface pass at one step: the faces that carried its tractions, with
/// fields at its traction nodes.
#[derive(Clone, Debug)]
pub struct SurfaceOutput {
    /// `<interface>_pass<p>` (the file stem after the case name).
    pub name: String,
    pub scheme: TractionScheme,
    pub faces: Vec<FaceRef>,
    /// The traction nodes, in field order.
    pub rows: Vec<usize>,
    pub fields: Vec<RowField>,
}

/// A cell field of the volume output: `components` values per element.
#[derive(Clone, Debug)]
pub struct CellField {
    pub name: &'static str,
    pub components: usize,
    pub values: Vec<f64>,
}

impl CellField {
    /// The field `name` of `components` values per element.
    pub fn new(name: &'static str, components: usize, values: Vec<f64>) -> CellField {
        CellField {
            name,
            components,
            values,
        }
    }
}

/// What a contribution writes at a step.
#[derive(Clone, Debug)]
pub enum Output {
    /// This rank's elements (ascending), with cell fields.
    Volume {
        elements: Vec<usize>,
        fields: Vec<CellField>,
    },
    /// One interface pass (rank 0 writes it; the fields are gathered on every rank).
    Surface(SurfaceOutput),
}

/// Merges the ascending, distinct `new` into the ascending, distinct `into`; whether `into`
/// gained an element (the coupled nodes of a pattern row, the primary faces of a held pair).
pub fn merge_ascending(into: &mut Vec<usize>, new: &[usize]) -> bool {
    if new.iter().all(|n| into.binary_search(n).is_ok()) {
        return false;
    }
    into.extend_from_slice(new);
    into.sort_unstable();
    into.dedup();
    true
}

/// One part of the discrete model (module docs).
///
/// Methods marked *collective* are called on every rank together.
pub trait Contribution {
    /// Nodes whose displacements this rank needs beyond those of its own elements (the
    /// nodes of an interface, whose terms couple elements of other ranks).
    fn coupled_nodes(&self) -> Vec<usize> {
        Vec::new()
    }

    /// Whether [`Contribution::couplings`] depend on the displacements (asked again at the
    /// start of every step and at its predicted end) or only on the mesh (asked once).
    fn pattern_moves(&self) -> bool {
        false
    }

    /// Hands `couple` every set of nodes whose dofs this contribution couples (each set a dense
    /// block of the matrix pattern), at the state `at`: at least every set that has a node whose
    /// rows this rank owns, on every rank (a rank's pattern is of the rows it owns). Called only
    /// to build the solver's pattern: a contribution may record what it handed out (see
    /// [`Contribution::holds_couplings_of`]).
    fn couplings(&self, at: &State, couple: &mut dyn FnMut(&[usize]));

    /// The matrix pattern is being made anew: the couplings handed out so far are no longer
    /// all in it (for [`Contribution::holds_couplings_of`]).
    fn forget_couplings(&self) {}

    /// Whether the couplings handed out since the last [`Contribution::forget_couplings`]
    /// include every block an evaluation at `at` adds; true where the contribution does not
    /// keep track (moving couplings: checked before each Newton tangent).
    fn holds_couplings_of(&self, _at: &State) -> bool {
        true
    }

    /// Adds this rank's terms of `F(u; t)` to `out`. Returns the issue that makes the state
    /// unusable, if any (the evaluation still completes).
    fn residual(&self, at: &State, out: &mut dyn ForceSink) -> Result<Option<DomainIssue>>;

    /// Adds this rank's terms of the tangent `dF/du` to `out`.
    fn jacobian(&self, at: &State, out: &mut dyn TangentSink) -> Result<Option<DomainIssue>>;

    /// The largest fraction of the Newton update `du` (indexed as `at.u`) from `at` this
    /// contribution accepts (at most 1, above 0 for a finite update): contact keeps what its
    /// search sees within its reach.
    fn step_fraction(&self, _at: &State, _du: &[f64]) -> f64 {
        1.0
    }

    /// Whether this contribution is enforced by penalty plus Uzawa augmentations.
    fn is_augmented(&self) -> bool {
        false
    }

    /// Whether an Uzawa step can update this contribution's multipliers (`uzawa_max > 0`
    /// somewhere; plain penalty cannot).
    fn takes_uzawa_updates(&self) -> bool {
        false
    }

    /// One Uzawa step after a converged Newton solve at `at`, the `done`-th of the step
    /// (*collective*).
    fn augment(&mut self, _at: &State, _done: usize, _world: &SimpleCommunicator) -> Augmentation {
        Augmentation {
            outcome: Augmented::Converged,
            violation: String::new(),
        }
    }

    /// Keeps the state a cut step returns to (at a step's start).
    fn save(&mut self) {}

    /// Returns to the state of the last [`Contribution::save`] (the step is cut).
    fn restore(&mut self) {}

    /// Closes a converged step at `at`: its state becomes the history of the next step
    /// (*collective*).
    fn commit(&mut self, _at: &State, _world: &SimpleCommunicator) {}

    /// Writes what the next step needs of this contribution after a [`Contribution::commit`]
    /// (a checkpoint): everything of it that carries over from one step to the next.
    fn write_state(&self, _out: &mut dyn StateSink) {}

    /// Reads back what [`Contribution::write_state`] wrote, into a contribution made afresh
    /// for the same case on the same rank (a restart).
    fn read_state(&mut self, _from: &mut dyn StateSource) -> Result<()> {
        Ok(())
    }

    /// Whether a Coulomb law is part of this contribution.
    fn is_frictional(&self) -> bool {
        false
    }

    /// The stick predictor: every pressed node sticks whatever its Coulomb cone while on.
    fn set_stick_all(&self, _on: bool) {}

    /// The bilateral iteration: every node this contribution can hold bilaterally (a mortar
    /// contact node with a normal multiplier) is so held while on.
    fn set_bilateral(&self, _on: bool) {}

    /// Whether this rank's part of the contribution has a node the bilateral iteration binds.
    fn has_bilateral_nodes(&self) -> bool {
        false
    }

    /// Holds on the law's pressed branch the nodes of this rank that are open at `at` and that
    /// the Newton update from `at` to `to` carries through the other surface (mortar contact,
    /// `newton.hold_closing`), for the update to be solved again; until
    /// [`Contribution::release_closing`].
    fn hold_closing(&self, _at: &State, _to: &State) -> Closing {
        Closing::default()
    }

    /// Lets go of what [`Contribution::hold_closing`] held.
    fn release_closing(&self) {}

    /// Lines on the last Newton iteration's state of this contribution, for the
    /// `-contact_monitor` option (*collective*; only rank 0's are printed).
    fn iteration_report(&self, _world: &SimpleCommunicator) -> Vec<String> {
        Vec::new()
    }

    /// The names of this contribution's history columns (`history.csv`).
    fn history_columns(&self) -> Vec<String> {
        Vec::new()
    }

    /// The values of the history columns of the last committed step.
    fn history(&self) -> Vec<f64> {
        Vec::new()
    }

    /// What is written of this contribution at a step (*collective*).
    fn output(&self, _at: &State, _world: &SimpleCommunicator) -> Vec<Output> {
        Vec::new()
    }

    /// Summary metrics at the final state `at` (*collective*).
    fn metrics(&self, _at: &State, _world: &SimpleCommunicator) -> Vec<(String, f64)> {
        Vec::new()
    }

    /// Seconds spent so far in the named phases this contribution times itself (the phases
    /// of `summary.json`'s timings).
    fn phase_seconds(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }
}

/// The contributions of a scene, in the order their terms are summed (the bulk first).
pub struct Model {
    parts: Vec<Box<dyn Contribution>>,
}

impl Model {
    pub fn new(parts: Vec<Box<dyn Contribution>>) -> Model {
        Model { parts }
    }

    pub fn parts(&self) -> &[Box<dyn Contribution>] {
        &self.parts
    }

    /// Nodes whose displacements this rank gathers for the contributions (beyond its own
    /// elements'), ascending.
    pub fn coupled_nodes(&self) -> Vec<usize> {
        let mut nodes: Vec<usize> = self.parts.iter().flat_map(|c| c.coupled_nodes()).collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }

    /// Whether some contribution's matrix pattern moves with the displacements (contact).
    pub fn pattern_moves(&self) -> bool {
        self.parts.iter().any(|c| c.pattern_moves())
    }

    /// The smallest [`Contribution::step_fraction`] of this rank's contributions.
    pub fn step_fraction(&self, at: &State, du: &[f64]) -> f64 {
        self.parts
            .iter()
            .map(|c| c.step_fraction(at, du))
            .fold(1.0, f64::min)
    }

    /// Whether some contribution is enforced by penalty plus Uzawa augmentations.
    pub fn is_augmented(&self) -> bool {
        self.parts.iter().any(|c| c.is_augmented())
    }

    /// Whether some contribution can take Uzawa updates.
    pub fn takes_uzawa_updates(&self) -> bool {
        self.parts.iter().any(|c| c.takes_uzawa_updates())
    }

    /// Whether some contribution has a Coulomb law.
    pub fn is_frictional(&self) -> bool {
        self.parts.iter().any(|c| c.is_frictional())
    }

    /// The stick predictor on or off for every contribution.
    pub fn set_stick_all(&self, on: bool) {
        self.parts.iter().for_each(|c| c.set_stick_all(on));
    }

    /// The bilateral iteration's law on or off for every contribution.
    pub fn set_bilateral(&self, on: bool) {
        self.parts.iter().for_each(|c| c.set_bilateral(on));
    }

    /// Whether some contribution has a node the bilateral iteration binds on this rank.
    pub fn has_bilateral_nodes(&self) -> bool {
        self.parts.iter().any(|c| c.has_bilateral_nodes())
    }

    /// [`Contribution::hold_closing`] of every contribution, on this rank.
    pub fn hold_closing(&self, at: &State, to: &State) -> Closing {
        self.parts
            .iter()
            .map(|c| c.hold_closing(at, to))
            .fold(Closing::default(), Closing::and)
    }

    /// [`Contribution::release_closing`] of every contribution.
    pub fn release_closing(&self) {
        self.parts.iter().for_each(|c| c.release_closing());
    }

    /// One Uzawa step of every contribution (*collective*): updated if any updated, else
    /// capped if any is above its tolerance with no augmentations left; the violations left,
    /// in words, of the augmented contributions.
    pub fn augment(&mut self, at: &State, done: usize, world: &SimpleCommunicator) -> Augmentation {
        let mut outcome = Augmented::Converged;
        let mut violations = Vec::new();
        for c in self.parts.iter_mut().filter(|c| c.is_augmented()) {
            let step = c.augment(at, done, world);
            outcome = outcome.and(step.outcome);
            violations.push(step.violation);
        }
        Augmentation {
            outcome,
            violation: violations.join("; "),
        }
    }

    /// [`Contribution::save`] of every part.
    pub fn save(&mut self) {
        self.parts.iter_mut().for_each(|c| c.save());
    }

    /// [`Contribution::restore`] of every part.
    pub fn restore(&mut self) {
        self.parts.iter_mut().for_each(|c| c.restore());
    }

    /// [`Contribution::commit`] of every part (*collective*).
    pub fn commit(&mut self, at: &State, world: &SimpleCommunicator) {
        self.parts.iter_mut().for_each(|c| c.commit(at, world));
    }

    /// [`Contribution::write_state`] of every part.
    pub fn write_state(&self, out: &mut dyn StateSink) {
        self.parts.iter().for_each(|c| c.write_state(out));
    }

    /// [`Contribution::read_state`] of every part.
    pub fn read_state(&mut self, from: &mut dyn StateSource) -> Result<()> {
        self.parts.iter_mut().try_for_each(|c| c.read_state(from))
    }

    /// [`Contribution::iteration_report`] of every part (*collective*).
    pub fn iteration_report(&self, world: &SimpleCommunicator) -> Vec<String> {
        self.parts
            .iter()
            .flat_map(|c| c.iteration_report(world))
            .collect()
    }

    /// The history columns of every part, in order.
    pub fn history_columns(&self) -> Vec<String> {
        self.parts
            .iter()
            .flat_map(|c| c.history_columns())
            .collect()
    }

    /// The history values of the last committed step, in the order of the columns.
    pub fn history(&self) -> Vec<f64> {
        self.parts.iter().flat_map(|c| c.history()).collect()
    }

    /// Every part's output at a step (*collective*).
    pub fn output(&self, at: &State, world: &SimpleCommunicator) -> Vec<Output> {
        self.parts
            .iter()
            .flat_map(|c| c.output(at, world))
            .collect()
    }

    /// Every part's summary metrics (*collective*).
    pub fn metrics(&self, at: &State, world: &SimpleCommunicator) -> Vec<(String, f64)> {
        self.parts
            .iter()
            .flat_map(|c| c.metrics(at, world))
            .collect()
    }

    /// The seconds of every timed phase, summed over the parts that time it.
    pub fn phase_seconds(&self) -> std::collections::BTreeMap<&'static str, f64> {
        let mut out = std::collections::BTreeMap::new();
        for (name, s) in self.parts.iter().flat_map(|c| c.phase_seconds()) {
            *out.entry(name).or_insert(0.0) += s;
        }
        out
    }
}
