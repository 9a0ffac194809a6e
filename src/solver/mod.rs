//! Load stepping with Newton (PETSc SNES), step cutting, and per-step output.
//!
//! The load factor t goes from 0 to 1 in `steps.count` equal increments. Each increment is one
//! SNES solve of `F(u; t) = 0` from the previous converged state, `F` the sum of the model's
//! contributions ([`crate::model`]). A solve that does not converge (diverged Newton, line-search
//! failure, an inverted element reported as a domain error, NaN) is **cut** (`cut`): the state
//! is restored and the increment halved, at most `steps.max_cuts` times in a row and never below
//! `1 / (steps.count 2^max_cuts)`; after a converged cut increment the step size doubles back
//! toward the nominal one. Every cut is reported on rank 0 and counted in the history and
//! summary. When a run fails, every output describes the last converged step.
//!
//! With frictional contact, a solve gets `FULL_STEP_ITERATIONS` full Newton steps first; if
//! they do not converge, or they cycle (`FULL_STEP_CYCLE_PROGRESS`: a node's open, stick or
//! slip state flipping back and forth), the solve is redone from
//! the same start with the `FALLBACK_LINE_SEARCH` before the step is cut. The step's Newton
//! count includes the failed attempt; the redone solves are counted in the summary
//! (`line_search_fallbacks`) and named in the progress line. When a step's first solve needed
//! the fallback, the next step's first solve starts with it (`started with bt` in the progress
//! line) and does so until it takes full steps throughout: a steady slide's steps fail their
//! full steps alike.
//!
//! Each step's Newton starts from the load-step predictor (`predictor`, `steps.predictor`),
//! which halves the Newton iterations of displacement-driven steps and removes the cuts that a
//! large prescribed increment otherwise causes. With contact multipliers, the step's first
//! Newton iteration is the bilateral iteration (`steps.bilateral_iteration`; module docs of
//! `contact::frictional`), two iterations when the first raised the residual, kept when it
//! lowers the residual. A Newton update that carries contact nodes open at the iterate through
//! the other surface is solved again with them held pressed (`newton.hold_closing`; a
//! pre-check of SNES's line search, `petsc::UpdateCheck`), and taken where its full step leaves
//! the smaller residual. After a converged solve, the augmented
//! contributions take an Uzawa step, and the step is solved again until they meet their
//! tolerances (`step`). Those solves stop at `newton.augmented_rtol`; once the tolerances are
//! met, a last solve meets `newton.rtol` and they are checked again (docs/theory.md section
//! 4, "Loose solves between augmentations").
//!
//! After each converged step: reactions on the constrained sets (summed over ranks), one VTU
//! file per rank, the PVTU and PVD written by rank 0 once all pieces exist, and a history row
//! (`results`). `summary.json` is rewritten after every step, so a killed run leaves a valid
//! summary of what finished (with `"converged": false`). A run stopped by SIGINT or SIGTERM
//! ([`crate::interrupt`]: polled, collectively, before every step and every Jacobian) ends
//! there: its summary keeps the finished steps and says `interrupted by ...` in `message`.
//! With `output.checkpoint_every`, finished steps leave checkpoints that `--restart` goes on
//! from, to the same answer bit for bit (`checkpoint`).
//!
//! # Modules
//!
//! - `setup`: the partition, the dofs, the model, the PETSc objects.
//! - `state`: the mutable state of a run (load, step size, cuts, counters).
//! - `step`: one load step: predictor, attempts, Uzawa, cutting, the step's outputs.
//! - `predictor`, `cut`: the load-step predictor and the cutting rules.
//! - `pattern_update`: the matrix pattern through the steps, and new matrices.
//! - `evaluation`, `assembly`: the model evaluated at a Newton iterate and put into PETSc.
//! - `summary`: the run's metrics, progress notes and last line.
//! - `results`: the files a run writes.
//! - `checkpoint`: checkpoints, and runs restarted from them.
//! - `collective`: agreement between ranks.

mod assembly;
mod checkpoint;
mod collective;
mod cut;
mod evaluation;
mod linear;
mod pattern_update;
mod predictor;
mod results;
mod rigid_motion;
mod setup;
mod state;
mod step;
mod summary;

use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;
use std::time::Instant;

use mpi::topology::{Communicator, SimpleCommunicator};

use crate::case::Scene;
use crate::dofs::DofMap;
use crate::error::{print_error, Error, Result};
use crate::interrupt;
use crate::io::output::Summary;
use crate::model::Model;
use crate::petsc::log::Phases;
use crate::petsc::{Matrix, Petsc, Snes, Vector};

pub(crate) use collective::agree_on;
pub use collective::lowest_rank_with;
pub use linear::{
    COARSE_CORRECTION_FROM, COARSE_CORRECTION_FROM_SECOND_ORDER, DIRECT_BELOW,
    DIRECT_BELOW_SECOND_ORDER, LINEAR_DIRECT_BELOW,
};

use assembly::Pattern;
use evaluation::Evaluator;
use predictor::Tangent;
use results::Results;
use state::RunState;
use step::StepEnd;

/// At most this many Newton iterations for the stick predictor of a frictional step (it is
/// only a starting point: when it does not converge, the step starts from the load predictor).
const STICK_PREDICTOR_ITERATIONS: usize = 6;

/// Frictional contact: a solve with full Newton steps gets at most this many iterations; when it
/// does not converge (a node's stick, slip or open state cycling), the solve is redone from the
/// same start with [`FALLBACK_LINE_SEARCH`] before the step is cut.
const FULL_STEP_ITERATIONS: usize = 10;

/// Frictional contact: a solve with full Newton steps also ends, and is redone with
/// [`FALLBACK_LINE_SEARCH`], when its residual norm rises to above this fraction of its value
/// two iterations before: the iterates cycle between two sets of node states (open and
/// closed, stick and slip), where converging full steps, even those that rise once or twice on
/// the way, gain more than this over two iterations (docs/performance.md, "Newton on
/// frictional contact").
const FULL_STEP_CYCLE_PROGRESS: f64 = 0.5;

/// The line search of the second attempt, and of a step's first one after a step that needed
/// it (`Run::attempt`): PETSc's `bt` (backtracking: the Newton step shortened
/// until ||F||^2 decreases enough, by cubic interpolation); why this one: docs/performance.md,
/// "Newton on frictional contact".
const FALLBACK_LINE_SEARCH: &str = "bt";

/// The phases of a run, each a PETSc log stage (`-log_view`) and a total in `summary.json`'s
/// `timings`.
const PHASES: [&str; 5] = [
    "setup",
    "assembly",
    "solve",
    pattern_update::PATTERN_PHASE,
    "output",
];

/// The parts of `assembly` timed apart in `timings`: the contributions' own timed phases (the
/// contact search, the mortar integration, the contact assembly) and `bulk_assembly`, the rest
/// (the bulk elements, tied interfaces and PETSc's vector and matrix assembly).
const TIMED_PARTS: [&str; 4] = [
    "contact_search",
    "contact_integration",
    "contact_assembly",
    "bulk_assembly",
];

/// How a run is carried out.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Folder for every result file.
    pub out_dir: PathBuf,
    /// No progress lines on rank 0.
    pub quiet: bool,
    /// Go on from the last checkpoint in `out_dir` (`checkpoint`).
    pub restart: bool,
}

impl RunOptions {
    /// A run from the start into `out_dir`.
    pub fn new(out_dir: PathBuf, quiet: bool) -> RunOptions {
        RunOptions {
            out_dir,
            quiet,
            restart: false,
        }
    }
}

/// What a run works with and keeps from its set-up to its end.
struct Context<'a> {
    scene: &'a Scene,
    opts: &'a RunOptions,
    rank: usize,
    ranks: usize,
    world: Rc<SimpleCommunicator>,
    dofs: DofMap,
    /// The state being evaluated (its displacements gathered for the contributions).
    evaluator: RefCell<Evaluator>,
}

/// Everything a run works with: the context, and what changes as it goes.
struct Run<'a> {
    cx: Context<'a>,
    model: Model,
    linear: Linear,
    results: Results,
    phases: Phases,
    state: RunState,
    summary: Summary,
    /// The line search of a second attempt, or of a led first one (frictional scenes with full
    /// Newton steps).
    fallback_line_search: Option<&'static str>,
    /// Print the contact state of every Newton iterate ([`CONTACT_MONITOR`]).
    contact_monitor: bool,
    /// The step of the last checkpoint written or restarted from.
    checkpointed: Option<usize>,
    /// What ties this run's checkpoints to it (the mesh's digest is made once).
    identity: std::cell::OnceCell<checkpoint::Identity>,
    started: Instant,
}

/// The option that prints, after each Newton iteration's residual norm, how many nodes of
/// each contact interface stick and slip and how many changed their state since the previous
/// iterate (`contact::frictional`, "changes").
pub const CONTACT_MONITOR: &str = "-contact_monitor";

/// The PETSc objects of a run and the matrix pattern.
struct Linear {
    /// The matrix's pattern (`pattern_update`).
    pattern: Pattern,
    /// The couplings of the contributions that do not move, made at set-up: what each renewal
    /// of `pattern` starts from.
    fixed_pattern: Pattern,
    /// The near null space of every matrix made.
    rigid_modes: Vec<Vec<f64>>,
    jac: Matrix,
    /// The Newton iterate.
    x: Vector,
    /// The last converged state (restored when a step is cut).
    x_prev: Vector,
    /// The start of the stick predictor (the step restarts there when it does not converge).
    x_guess: Vector,
    /// The start of a first attempt (the fallback line search restarts there).
    x_attempt: Vector,
    snes: Snes,
    tangent: Tangent,
    /// The linear solver of the Newton steps, and why.
    choice: linear::LinearChoice,
    /// The force scale of Newton's absolute tolerance (the residual at rest under the full
    /// load).
    force_scale: f64,
}

/// Runs a scene; returns the summary (also written to `summary.json`).
pub fn run(scene: &Scene, petsc: &Petsc, opts: &RunOptions) -> Result<Summary> {
    let mut run = Run::set_up(scene, petsc, opts)?;
    run.say(format!(
        "mortar: {} on {} rank(s): {} nodes, {} elements, {} free dofs, {} steps",
        scene.name,
        run.cx.ranks,
        scene.mesh.num_nodes(),
        scene.mesh.num_elements(),
        run.cx.dofs.total_free,
        scene.steps
    ));
    run.say(format!("  linear solver: {}", run.linear.choice.why));
    if opts.restart {
        run.say(format!(
            "  restarted from the checkpoint of step {} (load {}) in {}",
            run.state.step,
            summary::Load(run.state.t),
            opts.out_dir.display()
        ));
    }
    // Everything from here may fail on one rank only (I/O, say) while the others wait in a
    // collective call; such an error aborts the job *here*, while the PETSc objects are alive:
    // destroying them (MUMPS in particular) is itself collective and would hang.
    match run.steps().and_then(|()| run.finish()) {
        Ok(()) => Ok(run.summary),
        Err(e) if run.cx.ranks > 1 && !e.is_collective() => {
            print_error(crate::error::abort_line(run.cx.rank as i32, &e));
            run.cx.world.abort(1)
        }
        Err(e) => {
            run.record_error(&e);
            Err(e)
        }
    }
}

impl Run<'_> {
    /// A progress line on rank 0, unless quiet. A closed stdout ends the run with SIGPIPE
    /// (`petsc::init`); should the signal be ignored after all, a failed write is no reason to
    /// stop it either.
    fn say(&self, msg: String) {
        if self.cx.rank == 0 && !self.cx.opts.quiet {
            use std::io::Write;
            let _ = writeln!(std::io::stdout(), "{msg}");
        }
    }

    /// Steps until the load path is complete, a step fails for good, or a signal stops it;
    /// checkpoints every `output.checkpoint_every` steps and at the last finished step.
    fn steps(&mut self) -> Result<()> {
        while !self.state.finished() {
            match self.step()? {
                StepEnd::Finished if self.checkpoint_due() => self.write_checkpoint()?,
                StepEnd::Finished | StepEnd::Cut => {}
                StepEnd::Stopped | StepEnd::GaveUp => break,
            }
        }
        self.write_checkpoint()
    }

    /// An error that ended the run before its summary said so (a singular tangent, a failed
    /// write, an option PETSc reads at the first factorization): the summary says it, with the
    /// steps finished (best effort: the error may be a full disk).
    fn record_error(&mut self, e: &Error) {
        if self.summary.message.is_some() {
            return;
        }
        // (The error may come after a complete load path: the run still failed.)
        self.summary.converged = false;
        self.summary.message = Some(e.to_string());
        self.summary.timings = self.phases.timings();
        if self.cx.rank == 0 {
            self.results.write_summary(&self.summary);
        }
    }

    /// The signal the ranks agreed to stop on, if any, asked of them all now (*collective*).
    fn stop_requested(&self) -> Option<i32> {
        let signal = interrupt::agreed(&self.cx.world)?;
        self.state.stop.set(Some(signal));
        Some(signal)
    }
}
